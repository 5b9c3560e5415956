"""The files a command writes besides meshes: text, JSON and PNG figures.

Every one goes through the core's atomic writer, as meshes do
(sorpia::write_file_atomic: a temporary file in the same folder, fsync,
rename), so a failure leaves the old file or none.
"""

from __future__ import annotations

import io
import json
import math
import os

import numpy as np

from .. import _core


def write_bytes(path, data: bytes) -> None:
    _core.write_file_atomic(os.fsencode(path), data)  # bytes: any file name the OS takes


def write_text(path, text: str) -> None:
    write_bytes(path, text.encode("utf-8"))


def jsonable(obj):
    """numpy scalars and arrays to Python, NaN and inf to None (JSON has neither)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(path, data) -> None:
    write_text(path, json.dumps(jsonable(data), indent=2) + "\n")


def save_figure(fig, path) -> None:
    """A matplotlib figure as PNG; drawn in memory first, so a failure to draw writes nothing."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    write_bytes(path, buf.getvalue())
