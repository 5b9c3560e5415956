"""Shared by the tests of the `sorpia` command: mesh files written by hand,
the meshes they hold, what a refused input looks like (the fixtures that run
the command and make the files are in conftest.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import sorpia


def write_obj(path: Path, vertices, faces) -> Path:
    """An OBJ file written by hand, every float with 17 significant digits
    (repr), so the file holds exactly the float64 vertices the test compares."""
    lines = ["# written by the tests of the sorpia command"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=float).tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(faces).tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path


def assert_user_error(code: int, err: str) -> None:
    """Exit code 2, a message on stderr naming the problem, no traceback."""
    assert code == 2, (code, err)
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert last.startswith("sorpia") and "error:" in last, err


# Two inputs: closed with valences 3 to 12 (most vertices extraordinary), and
# open with a boundary and two one-face corners.
CLI_MESHES = {
    "irregular-torus": lambda: sorpia.shapes.irregular(300, seed=5),
    "grid-boundary": lambda: sorpia.shapes.grid(8, 7),
}
