"""A user's script, typed as a project under `mypy --strict` types it (tests/test_typing.py runs mypy on it;
it is not run). The assert_type lines fail under mypy if sorpia's types degrade to Any."""

from __future__ import annotations

from pathlib import Path
from typing import assert_type

import numpy as np
import numpy.typing as npt

import sorpia


def fit(vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.int32]) -> tuple[npt.NDArray[np.float64], float]:
    """Control vertices whose Loop limit surface passes through `vertices`, and the largest miss."""
    res = sorpia.interpolate(vertices, faces, method="sor", tol=1e-12)
    assert_type(res, sorpia.InterpolationResult)
    assert_type(res.converged, bool)
    assert_type(res.iterations, int)
    control: npt.NDArray[np.float64] = res.control_vertices
    miss = float(np.abs(sorpia.limit_points(control, faces) - vertices).max())
    return control, miss


def many(faces: npt.NDArray[np.int32], frames: list[npt.NDArray[np.float64]]) -> list[sorpia.InterpolationResult]:
    """One topology, many solves: build once."""
    solver = sorpia.Interpolator(faces, len(frames[0]))
    return [solver.solve(frame, tol=1e-10) for frame in frames]


def main(out: Path) -> None:
    V, F = sorpia.shapes.icosphere(2)
    assert_type(V, npt.NDArray[np.float64])
    assert_type(F, npt.NDArray[np.int32])
    control, miss = fit(V, F)
    print(f"largest miss {miss:.2e}")
    results = many(F, [V, 1.5 * V])
    print([r.iterations for r in results])
    sorpia.write_mesh(out / "control.obj", control, F)
    fair = sorpia.fair_interpolate(V, F, thin_plate=1.0)
    assert_type(fair, sorpia.FairResult)
    assert_type(fair.control_vertices, np.ndarray)
    Vq, Fq = sorpia.shapes.quad_torus(16, 8)
    try:
        sorpia.interpolate(Vq, Fq, scheme="loop")
    except sorpia.MeshError as exc:
        print(f"refused: {exc}")


if __name__ == "__main__":
    main(Path("."))
