"""The fitted surface in a real program: sorpia's --blender script run in
Blender (the bpy module), its Subdivision Surface modifier evaluated, and
Blender's own limit positions (OpenSubdiv in Blender, float32) compared with
the points the cage was fitted through.

bpy is large (about 400 MB) and pins its own numpy, so it lives in a venv of
its own, .venv-blender, which ``make blender-venv`` builds (``make test``
builds it where bpy installs); SORPIA_BLENDER_PYTHON names another Python
with bpy. Without one the tests skip, saying so."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import sorpia
from sorpia.blender import QUALITY_DEFAULT, QUALITY_EXACT, blender_quality, crease_weight, write_blender_script
from sorpia.errors import ParameterError

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


BLENDER = blender_python()
needs_bpy = pytest.mark.skipif(BLENDER is None, reason="bpy is not installed: `make blender-venv` builds "
                               ".venv-blender with bpy 5.0.1 (about 400 MB), or set SORPIA_BLENDER_PYTHON")

# Runs in Blender's Python: the script sorpia wrote, or Blender's own USD import of the file sorpia wrote (its
# Subdivision Surface modifier made from subdivisionScheme, quality raised as docs/blender.md says), then the
# modifier at level 1 with the limit surface on, whose first vertices are the control vertices' limit positions,
# in order.
RUNNER = textwrap.dedent("""
    import runpy, sys
    import bpy
    import numpy as np
    how, path, out, n = sys.argv[-4], sys.argv[-3], sys.argv[-2], int(sys.argv[-1])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if how == "script":
        runpy.run_path(path)
        obj = bpy.data.objects["sorpia_cage"]
    else:
        bpy.ops.wm.usd_import(filepath=path, import_subdivision=True)
        (obj,) = [o for o in bpy.data.objects if o.type == "MESH"]
        (modifier,) = obj.modifiers
        assert modifier.type == "SUBSURF" and modifier.use_limit_surface, modifier
        modifier.quality = 10
    obj.modifiers[0].levels = 1
    mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).to_mesh()
    co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    np.save(out, co.reshape(-1, 3)[:n])
""")


def blender_limit(tmp_path, ctrl, faces, how: str = "script", **options) -> np.ndarray:
    """The limit positions Blender draws for the cage (n, 3) float32, loaded through sorpia's bpy script
    (`how` "script") or Blender's USD import of the cage sorpia wrote ("usd")."""
    out, runner = tmp_path / "limit.npy", tmp_path / "runner.py"
    if how == "script":
        path = tmp_path / "cage.py"
        write_blender_script(path, ctrl, faces, **options)
    else:
        path = tmp_path / "cage.usda"
        sorpia.write_mesh(path, ctrl, faces, scheme="catmull-clark", **options)
    runner.write_text(RUNNER)
    done = subprocess.run([BLENDER, str(runner), how, str(path), str(out), str(len(ctrl))], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return np.load(out)


def ring(nu: int, nv: int, i: int) -> np.ndarray:
    """The edges of quad_torus(nu, nv) around its tube at u index i: a closed loop (no crease ends)."""
    v = np.arange(nv)
    return np.stack([i * nv + v, i * nv + (v + 1) % nv], axis=1).astype(np.int32)


CASES = {
    "quads, extraordinary vertices": lambda: (*sorpia.shapes.quad_irregular(300, seed=2), {}),
    "n-gons": lambda: (*sorpia.shapes.polygon_torus(10, 8, seed=4), {}),
    "boundary edge-only": lambda: (*sorpia.shapes.quad_grid(7, 6), {"boundary": "edge-only"}),
    "boundary edge-and-corner": lambda: (*sorpia.shapes.quad_grid(7, 6), {"boundary": "edge-and-corner"}),
    "creases and a corner": lambda: (*sorpia.shapes.quad_torus(12, 8), {
        "creases": (np.vstack([ring(12, 8, 0), ring(12, 8, 6)]), np.r_[np.full(8, np.inf), np.full(8, 2.5)]),
        "corners": (np.array([3 * 8 + 4], np.int32), np.array([1.5]))}),
}


@needs_bpy
@pytest.mark.parametrize("how", ["script", "usd"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_blender_draws_the_fitted_surface(tmp_path, case, how):
    V, F, tags = CASES[case]()
    V = V + 0.05 * np.sin(3 * V[:, [1, 2, 0]])  # no symmetry for a wrong rule to hide behind
    res = sorpia.interpolate(V, F, scheme="catmull-clark", tol=1e-12, **tags)
    assert res.converged
    limit = blender_limit(tmp_path, res.control_vertices, F, how, **tags)
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    # Blender evaluates in float32: the cage is rounded to float32 and the patches summed in float32, a few
    # ulps of the coordinates (float32's epsilon is 6e-8 of the diagonal).
    assert np.abs(limit - V).max() < 1e-6 * diagonal
    # Without the fit, Blender's surface misses the points by far more: the comparison sees the fit.
    assert np.abs(blender_limit(tmp_path, V, F, how, **tags) - V).max() > 1e-3 * diagonal


def test_crease_weights_are_blenders_mapping():
    """Blender's sharpness of weight c is 10 c^2 (blenkernel crease_to_sharpness): the weights invert it."""
    s = np.array([0.0, 0.5, 2.5, 9.99, 10.0, 40.0, np.inf])
    c = crease_weight(s)
    assert np.allclose(10 * c**2, np.minimum(s, 10), rtol=1e-15, atol=0)
    assert c[-3:].tolist() == [1.0, 1.0, 1.0]


def test_quality_and_refusals(tmp_path):
    V, F = sorpia.shapes.quad_grid(4, 4)
    assert blender_quality(F, len(V), "edge-and-corner") == QUALITY_DEFAULT
    assert blender_quality(F, len(V), "edge-only") == QUALITY_EXACT  # one-face corners under edge-only
    assert blender_quality(F, len(V), "edge-and-corner", creases=(np.array([[0, 1]]), 0.5)) == QUALITY_EXACT
    with pytest.raises(ParameterError, match="Blender has no holes"):
        write_blender_script(tmp_path / "x.py", V, F, holes=np.array([0]))
    assert not (tmp_path / "x.py").exists()


def test_fit_blender_option(command, tmp_path):
    V, F = sorpia.shapes.quad_grid(5, 5)
    sorpia.write_mesh(tmp_path / "grid.obj", V, F, creases=(np.array([[6, 7]]), 3.0), boundary="edge-only")
    code, out, err = command("fit", str(tmp_path / "grid.obj"), "-o", str(tmp_path / "out.obj"), "-q",
                             "--blender", str(tmp_path / "cage.py"))
    assert code == 0, err
    text = (tmp_path / "cage.py").read_text()
    assert "boundary_smooth = 'ALL'" in text and f"quality = {QUALITY_EXACT}" in text
    assert repr(float(crease_weight(3.0))) in text
    compile(text, "cage.py", "exec")  # valid Python
    V3, F3 = sorpia.shapes.icosphere(1)
    sorpia.write_mesh(tmp_path / "tri.obj", V3, F3)
    code, out, err = command("fit", str(tmp_path / "tri.obj"), "-o", str(tmp_path / "o.obj"),
                             "--blender", str(tmp_path / "c.py"))
    assert code == 2 and "has no Loop scheme" in err and not (tmp_path / "c.py").exists()


@needs_bpy
@pytest.mark.parametrize("how", ["script", "usd"])
def test_blender_draws_the_fair_surface(tmp_path, how):
    """Fair interpolation's fine cage with the tags Far's refinement decayed (2.5 -> 1.5, a semi-sharp corner,
    infinitely sharp loops) as Blender draws it: through the input vertices (the fine mesh's first vertices are
    their children) and, at every fine vertex, at sorpia's own limit point of the fine cage."""
    V, F, tags = CASES["creases and a corner"]()
    V = V + 0.05 * np.sin(3 * V[:, [1, 2, 0]])
    res = sorpia.fair_interpolate(V, F, scheme="catmull-clark", **tags)
    limit = blender_limit(tmp_path, res.control_vertices, res.faces, how, creases=res.creases,
                          corners=res.corners)
    ours = sorpia.limit_points(res.control_vertices, res.faces, scheme="catmull-clark", creases=res.creases,
                               corners=res.corners)
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    # float32 in Blender, as above.
    assert np.abs(limit[:len(V)] - V).max() < 1e-6 * diagonal
    assert np.abs(limit - ours).max() < 1e-6 * diagonal
    # Tags dropped, the surface misses the points: the comparison sees the tags.
    assert np.abs(blender_limit(tmp_path, res.control_vertices, res.faces, how)[:len(V)] - V).max() > 1e-3 * diagonal


@needs_bpy
def test_blender_draws_the_approximated_cage(tmp_path):
    """A quad cage made by decimation with --sharp-angle creases and fitted to points by approximate, as
    Blender draws it: at sorpia's limit points of that cage, every vertex."""
    V, F = sorpia.shapes.quad_torus(24, 12)
    V = V * np.where(V[:, 2:3] > 0, 1.0, 0.7)  # a flattened bottom half: an edge the sharp angle finds
    F = np.vstack([F[:, [0, 1, 2]], F[:, [0, 2, 3]]])  # decimation takes triangles
    cage = sorpia.decimate(V, F, 120, scheme="catmull-clark", sharp_angle=30)
    res = sorpia.approximate(V, cage.vertices, cage.faces, scheme="catmull-clark", creases=cage.creases,
                             iterations=3)
    limit = blender_limit(tmp_path, res.control_vertices, cage.faces, "script", creases=cage.creases)
    ours = sorpia.limit_points(res.control_vertices, cage.faces, scheme="catmull-clark", creases=cage.creases)
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    assert len(cage.creases[0]) > 0
    # Where a crease ends inside the surface (a dart: one crease edge at the vertex) Blender's patches, isolated
    # to its highest quality and summed in float32, sit a few 1e-6 of the diagonal off the limit point, which
    # OpenSubdiv's Bfr in double puts where Far's limit mask does (1e-16): looser there, float32's bound elsewhere.
    darts = np.bincount(np.asarray(cage.creases[0]).ravel(), minlength=len(ours)) == 1
    error = np.abs(limit - ours).max(axis=1)
    assert error[~darts].max() < 1e-6 * diagonal
    assert error.max() < 1e-5 * diagonal
    # Creases dropped, Blender's surface is another one: the comparison sees them.
    assert np.abs(blender_limit(tmp_path, res.control_vertices, cage.faces) - ours).max() > 1e-3 * diagonal
