"""sorpia where scipy is not installed (Blender ships numpy but no scipy): ``import sorpia`` imports no scipy,
interpolation, fair interpolation, approximation, limit points and surfaces, mesh files and `sorpia fit` work,
and what needs scipy says so.

Standalone (no conftest): tools/clean_root_test.sh runs this file in a venv that has no scipy at all; here, where
scipy is installed, the fixture hides it as a missing module does (None in sys.modules makes the import fail).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import sorpia


@pytest.fixture
def no_scipy(monkeypatch):
    for name in [m for m in sys.modules if m == "scipy" or m.startswith("scipy.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "scipy", None)


def diagonal(V: np.ndarray) -> float:
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


def test_import_sorpia_imports_no_scipy():
    # A fresh interpreter: this one may have scipy loaded by other tests.
    code = ("import sys; sys.modules['scipy'] = None; import sorpia, sorpia.cli; "
            "print(sorted(m for m, v in sys.modules.items() if m.startswith('scipy') and v is not None))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_interpolation_and_limit_surfaces_need_no_scipy(no_scipy):
    # Loop and Catmull-Clark: the limit points of the control vertices are the given vertices, to the solve's
    # tolerance (1e-10 relative residual; 1e-9 of the diagonal leaves room for the rounding of B V).
    for scheme, (V, F) in (("loop", sorpia.shapes.icosphere(2)), ("catmull-clark", sorpia.shapes.quad_torus(12, 8))):
        V = np.asarray(V, float)
        res = sorpia.interpolate(V, F, scheme=scheme)
        assert res.converged
        assert np.abs(sorpia.limit_points(res.control_vertices, F, scheme=scheme) - V).max() < 1e-9 * diagonal(V)
        # The surface evaluated at the corners of faces is the limit point of the corner vertex.
        surface = sorpia.LimitSurface(res.control_vertices, F, scheme=scheme)
        corner = np.zeros((len(F), 2))
        points = surface.evaluate(np.arange(len(F)), corner)
        first = np.asarray(F)[:, 0]
        assert np.abs(points - V[first]).max() < 1e-9 * diagonal(V)
        Vs, Fs = sorpia.limit_surface(res.control_vertices, F, level=2, scheme=scheme)
        assert len(Fs) > 0 and np.isfinite(Vs).all()


def test_fair_interpolation_needs_no_scipy(no_scipy):
    V, F = sorpia.shapes.icosphere(1)
    V = np.asarray(V, float)
    res = sorpia.fair_interpolate(V, F)
    # Its limit surface passes through the targets to its reported error (the solve's tolerance); the limit
    # points are computed here independently of that report.
    fine = sorpia.limit_points(res.control_vertices, res.faces)[res.targets]
    assert np.abs(fine - V).max() <= 1e-6 * diagonal(V)
    with pytest.raises(ImportError, match=r"FairResult\.refinement needs scipy.*pip install scipy"):
        res.refinement


def test_mesh_files_need_no_scipy(no_scipy, tmp_path):
    V, F = sorpia.shapes.quad_torus(6, 4)
    path = tmp_path / "torus.obj"
    sorpia.write_mesh(path, V, F)
    V2, F2 = sorpia.read_mesh(path)
    # OBJ writes 17 significant digits: the coordinates come back to the last bit or two.
    assert np.abs(V2 - V).max() < 1e-15 * diagonal(np.asarray(V, float)) + 1e-300
    assert np.array_equal(F2, F)


def test_the_fit_command_needs_no_scipy(no_scipy, tmp_path, capsys):
    from sorpia.cli import main

    V, F = sorpia.shapes.quad_torus(8, 6)
    sorpia.write_mesh(tmp_path / "torus.obj", V, F)
    assert main(["fit", str(tmp_path / "torus.obj"), "-o", str(tmp_path / "control.obj"), "-q"]) == 0
    control, _ = sorpia.read_mesh(tmp_path / "control.obj")
    # The cage as written (OBJ, 17 digits): its limit points are the input vertices, to the solve's tolerance.
    assert np.abs(sorpia.limit_points(control, F) - V).max() < 1e-9 * diagonal(np.asarray(V, float))


def test_approximation_needs_no_scipy(no_scipy):
    # Points on a quad torus's limit surface (a tessellation's vertices are exact limit points), fitted from the
    # cage grown by 2%: the fitted surface comes closer than the start by far. The distance is recomputed here
    # from the returned footpoints, independently of the fit's own record.
    V, F = sorpia.shapes.quad_torus(12, 8)
    points, _ = sorpia.limit_surface(V, F, level=2)
    start = V.mean(axis=0) + 1.02 * (V - V.mean(axis=0))
    res = sorpia.approximate(points, start, F, fairness=0.0)
    fitted = sorpia.LimitSurface(res.control_vertices, F).evaluate(res.face_ids, res.uv)
    rms = float(np.sqrt(np.mean(np.sum((points - fitted) ** 2, axis=1))))
    assert rms == pytest.approx(res.rms, rel=1e-9)
    assert rms < 0.1 * res.history[0]["rms"]


def test_what_needs_scipy_names_itself_and_the_package(no_scipy):
    V, F = sorpia.shapes.icosphere(1)
    with pytest.raises(ImportError, match=r"sorpia\.limit_matrix needs scipy.*pip install scipy"):
        sorpia.limit_matrix(F, len(V))
    with pytest.raises(ImportError, match=r"sorpia\.fairness_matrix needs scipy.*pip install scipy"):
        sorpia.fairness_matrix(F, len(V))
