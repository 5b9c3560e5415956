"""Where the Blender tests find Blender: a Python that imports bpy (the bpy
module, about 400 MB, pins its own numpy, so it lives in a venv of its own,
.venv-blender, which ``make blender-venv`` builds; SORPIA_BLENDER_PYTHON
names another), and the extension zip ``make blender-extension`` writes."""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import pytest

import sorpia

REPO = Path(__file__).resolve().parent.parent


def blender_python() -> str | None:
    """A Python that imports bpy: $SORPIA_BLENDER_PYTHON, the repository's .venv-blender, or this one."""
    given = os.environ.get("SORPIA_BLENDER_PYTHON")
    if given:
        return given
    venv = REPO / ".venv-blender" / "bin" / "python"
    if venv.exists():
        return str(venv)
    return sys.executable if importlib.util.find_spec("bpy") is not None else None


def extension_zip() -> Path | None:
    """The extension zip for this sorpia: $SORPIA_BLENDER_EXTENSION, or dist/sorpia_blender-VERSION.zip."""
    given = os.environ.get("SORPIA_BLENDER_EXTENSION")
    path = Path(given) if given else REPO / "dist" / f"sorpia_blender-{sorpia.__version__}.zip"
    return path if path.exists() else None


BLENDER = blender_python()
needs_bpy = pytest.mark.skipif(BLENDER is None, reason="bpy is not installed: `make blender-venv` builds "
                               ".venv-blender with bpy 5.0.1 (about 400 MB), or set SORPIA_BLENDER_PYTHON")
EXTENSION = extension_zip()
needs_extension = pytest.mark.skipif(EXTENSION is None, reason="no extension zip: `make blender-extension` writes "
                                     f"dist/sorpia_blender-{sorpia.__version__}.zip (or set SORPIA_BLENDER_EXTENSION)")
