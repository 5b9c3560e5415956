"""The fitted surface in a real program: sorpia's --blender script run in
Blender (the bpy module), its Subdivision Surface modifier evaluated, and
Blender's own limit positions (OpenSubdiv in Blender, float32) compared with
the points the cage was fitted through.

Blender is found as tests/blender_support.py says (``make blender-venv``,
or SORPIA_BLENDER_PYTHON); without it the tests skip, saying so."""

from __future__ import annotations

import subprocess
import textwrap

import numpy as np
import pytest

import sorpia
from sorpia.blender import QUALITY_DEFAULT, QUALITY_EXACT, blender_quality, crease_weight, write_blender_script
from sorpia.errors import ParameterError

from blender_support import BLENDER, needs_bpy

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


def blender_arrays(V, faces, edge_sharpness=None, vertex_sharpness=None, extra_edges=()):
    """A BlenderMesh built here, as Blender stores a mesh: each edge once (first seen first), each corner's
    vertex and the edge to the next corner of its face; crease weights from sharpness by sqrt(s / 10)."""
    from sorpia.blender import BlenderMesh

    faces = [list(f) for f in faces]
    index: dict = {}
    corner_verts, corner_edges = [], []
    for f in faces:
        for a, b in zip(f, f[1:] + f[:1]):
            corner_verts.append(a)
            corner_edges.append(index.setdefault((min(a, b), max(a, b)), len(index)))
    for a, b in extra_edges:
        index.setdefault((min(a, b), max(a, b)), len(index))
    edges = np.array(list(index), dtype=np.int32).reshape(-1, 2)
    weights = None
    if edge_sharpness is not None:
        weights = np.array([np.sqrt(min(edge_sharpness.get(e, 0.0), 10) / 10) for e in index], np.float32)
    vweights = None if vertex_sharpness is None else np.sqrt(np.asarray(vertex_sharpness) / 10).astype(np.float32)
    return BlenderMesh(np.asarray(V, float), edges, np.array([len(f) for f in faces], np.int32),
                       np.array(corner_verts, np.int32), np.array(corner_edges, np.int32), weights, vweights)


def test_blender_rules_invert_the_script_mapping():
    """What the script writes (sharpness as weights, the boundary rule as boundary_smooth) reads back as the
    same rules: sharpness to float32 rounding, boundary exactly; creases off drops every tag."""
    from sorpia.blender import BOUNDARY_RULE, BOUNDARY_SMOOTH, blender_rules, crease_sharpness

    s = np.array([0.1, 0.5, 2.5, 9.99, 10.0])
    assert np.allclose(crease_sharpness(crease_weight(s)), s, rtol=1e-6, atol=0)
    assert crease_sharpness(1.0) == 10.0 and crease_sharpness(0.5) == 2.5
    assert {BOUNDARY_SMOOTH[BOUNDARY_RULE[k]] for k in BOUNDARY_RULE} == set(BOUNDARY_RULE)
    V, F = sorpia.shapes.quad_grid(5, 5)
    mesh = blender_arrays(V, F, {(5, 6): 2.5, (6, 7): 10.0}, np.r_[0.0, 0.0, 0.0, 1.5, np.zeros(21)])
    rules = blender_rules(mesh, "PRESERVE_CORNERS")
    assert rules["boundary"] == "edge-and-corner"
    edges, sharp = rules["creases"]
    assert sorted(map(tuple, np.sort(edges, axis=1).tolist())) == [(5, 6), (6, 7)]
    assert np.allclose(sorted(sharp), [2.5, 10.0], rtol=1e-6)
    assert rules["corners"][0].tolist() == [3] and np.isclose(rules["corners"][1][0], 1.5, rtol=1e-6)
    assert blender_rules(mesh, "ALL", use_creases=False) == {"boundary": "edge-only"}
    with pytest.raises(ParameterError, match="boundary_smooth"):
        blender_rules(mesh, "NONE")


def test_crease_weights_of_the_fair_tags():
    """Tags on a mesh's own edges as Blender's attributes, read back by blender_rules."""
    from sorpia.blender import blender_rules, crease_weights_of

    V, F = sorpia.shapes.quad_grid(5, 5)
    mesh = blender_arrays(V, F)
    edge_w, vert_w = crease_weights_of(mesh.edges, len(V), (np.array([[6, 5], [11, 12]]), [2.5, np.inf]),
                                       (np.array([7]), 0.4))
    assert edge_w.dtype == np.float32 and np.count_nonzero(edge_w) == 2 and np.count_nonzero(vert_w) == 1
    rules = blender_rules(mesh._replace(edge_creases=edge_w, vertex_creases=vert_w))
    got = dict(zip(map(tuple, np.sort(rules["creases"][0], axis=1).tolist()), rules["creases"][1]))
    assert got.keys() == {(5, 6), (11, 12)} and np.isclose(got[(5, 6)], 2.5, rtol=1e-6) and got[(11, 12)] == 10.0
    with pytest.raises(ValueError, match="not an edge"):
        crease_weights_of(mesh.edges, len(V), (np.array([[0, 6]]), 1.0))


def test_mesh_refusals():
    """Each kind of mesh Blender's modifier draws otherwise than sorpia fits it is named; a good one passes."""
    from sorpia.blender import mesh_refusal

    V, F = sorpia.shapes.quad_grid(5, 5)
    F = F.tolist()
    up = np.vstack([V, [[0.5, 0.5, 1.0]]])
    assert mesh_refusal(blender_arrays(V, F)) is None
    assert "no faces" in mesh_refusal(blender_arrays(V, []))
    assert "1 loose vertex" in mesh_refusal(blender_arrays(up, F))
    assert "1 loose edge" in mesh_refusal(blender_arrays(up, F, extra_edges=[(0, 25)]))
    assert "three or more faces" in mesh_refusal(blender_arrays(up, F + [[6, 7, 25]]))
    assert "opposite orientation" in mesh_refusal(blender_arrays(V, F[:7] + [F[7][::-1]] + F[8:]))
    assert "twice" in mesh_refusal(blender_arrays(V, F + [[0, 1, 1, 5]]))


def test_two_face_vertices():
    """Interior vertices of two faces are found; boundary vertices of two faces are not."""
    from sorpia.blender import two_face_vertices

    V, F = sorpia.shapes.quad_grid(5, 5)
    F = F.tolist()
    a, b, c, d = F[5]
    V = np.vstack([V, 0.5 * (V[a] + V[c])])
    F[5:6] = [[a, b, c, 25], [c, d, a, 25]]
    assert two_face_vertices(blender_arrays(V, F)).tolist() == [25]
    assert two_face_vertices(blender_arrays(*sorpia.shapes.quad_grid(5, 5))).size == 0


def test_script_and_extension_share_the_modifier_settings(tmp_path):
    """The script sets every setting modifier_settings gives, as the extension sets them on a new modifier."""
    from sorpia.blender import blender_script, modifier_settings

    V, F = sorpia.shapes.quad_grid(5, 5)
    text = blender_script(V, F, boundary="edge-only", creases=(np.array([[5, 6]]), 2.5))
    settings = modifier_settings(F, len(V), "edge-only", creases=(np.array([[5, 6]]), 2.5))
    assert settings == {"subdivision_type": "CATMULL_CLARK", "use_limit_surface": True, "quality": QUALITY_EXACT,
                        "boundary_smooth": "ALL", "use_creases": True}
    for key, value in settings.items():
        assert f"modifier.{key} = {value!r}\n" in text


def test_interpolate_float32_measures_the_rounded_cage():
    """The miss interpolate_float32 reports is that of the float32 cage, as sorpia.limit_points measures it."""
    from sorpia.blender import interpolate_float32

    V, F, tags = CASES["creases and a corner"]()
    V = V + 0.05 * np.sin(3 * V[:, [1, 2, 0]])
    res, cage, miss = interpolate_float32(V, F, {"boundary": "edge-only", **tags}, tol=1e-12)
    assert res.converged and cage.dtype == np.float32
    assert np.array_equal(cage, res.control_vertices.astype(np.float32))
    limit = sorpia.limit_points(cage.astype(np.float64), F, scheme="catmull-clark", boundary="edge-only", **tags)
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    assert miss == pytest.approx(np.linalg.norm(limit - V, axis=1).max() / diagonal, rel=1e-9)
    assert 1e-10 < miss < 1e-6  # float32's rounding, not the solve's 1e-12


def test_extension_zip_layout(tmp_path):
    """blender/build_extension.py: the manifest Blender reads (schema 1.0.0, Blender 4.2 and later, no
    permissions, the wheels' paths and the platforms they share) and every file it names inside the zip."""
    import importlib.util
    import tomllib
    import zipfile
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "blender" / "build_extension.py"
    spec = importlib.util.spec_from_file_location("build_extension", path)
    build_extension = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build_extension)
    assert build_extension.wheel_tags(Path("sorpia-1.2.3-cp311-cp311-manylinux_2_35_x86_64.whl")) == (
        "1.2.3", ["linux-x64"])
    assert build_extension.wheel_tags(Path("x-1-cp311-cp311-macosx_11_0_arm64.whl"))[1] == ["macos-arm64"]
    assert build_extension.wheel_tags(Path("x-1-cp311-cp311-win_amd64.whl"))[1] == ["windows-x64"]
    with pytest.raises(SystemExit, match="none Blender installs on"):
        build_extension.wheel_tags(Path("x-1-cp311-cp311-linux_riscv64.whl"))
    wheels = []
    for name in ("sorpia-0.9.1-cp311-cp311-manylinux_2_35_x86_64.whl",
                 "scipy-1.13.1-cp311-cp311-manylinux_2_17_x86_64.manylinux2014_x86_64.whl"):
        with zipfile.ZipFile(tmp_path / name, "w") as z:
            z.writestr("x.txt", "a stand-in wheel")
        wheels.append(tmp_path / name)
    out = build_extension.build(wheels[0], tmp_path / "dist", (wheels[1],))
    assert out.name == "sorpia_blender-0.9.1.zip"
    with zipfile.ZipFile(out) as z:
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        names = set(z.namelist())
    assert manifest["schema_version"] == "1.0.0" and manifest["id"] == "sorpia_blender"
    assert manifest["version"] == "0.9.1" and manifest["blender_version_min"] == "4.2.0"
    assert manifest["type"] == "add-on" and "permissions" not in manifest
    assert manifest["platforms"] == ["linux-x64"]
    assert {w.removeprefix("./") for w in manifest["wheels"]} == {f"wheels/{w.name}" for w in wheels} <= names
    assert "__init__.py" in names


@needs_bpy
def test_blender_imports_a_streamed_fits_usd_cage_with_its_tags(command, tmp_path, monkeypatch):
    # `sorpia approximate --stream yes` of a binary PLY with a creased, cornered Catmull-Clark cage, written to
    # .usda: Blender's own USD import draws the limit surface sorpia evaluates for the cage as written, tags
    # included (float32: 1e-6 of the cage's size), and not the surface without the tags.
    monkeypatch.chdir(tmp_path)
    sorpia.write_mesh(tmp_path / "scan.ply", *sorpia.shapes.icosphere(3), binary=True)
    V = np.array([[x, y, z] for z in (-0.6, 0.6) for y in (-0.6, 0.6) for x in (-0.6, 0.6)])
    F = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [1, 3, 7, 5], [3, 2, 6, 7], [2, 0, 4, 6]], np.int32)
    tags = {"creases": (np.array([[4, 5], [5, 7], [7, 6], [6, 4]], np.int32), np.full(4, 2.0)),
            "corners": (np.array([0], np.int32), np.array([10.0]))}
    sorpia.write_mesh(tmp_path / "cube.obj", V, F, **tags)
    code, _, err = command("approximate", "scan.ply", "--cage", "cube.obj", "-o", "cage.usda", "--stream", "yes")
    assert code == 0, err
    cage = sorpia.read_mesh(tmp_path / "cage.usda", tags=True)
    (tmp_path / "runner.py").write_text(RUNNER)
    done = subprocess.run([BLENDER, str(tmp_path / "runner.py"), "usd", str(tmp_path / "cage.usda"),
                           str(tmp_path / "limit.npy"), str(len(cage[0]))], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    limit = np.load(tmp_path / "limit.npy")
    want, _ = sorpia.limit_surface(cage[0], cage[1], level=0, scheme="catmull-clark", creases=cage[2]["creases"],
                                   corners=cage[2]["corners"])
    size = np.abs(cage[0]).max()
    assert np.abs(limit - want[:len(cage[0])]).max() < 1e-6 * size
    untagged, _ = sorpia.limit_surface(cage[0], cage[1], level=0, scheme="catmull-clark")
    assert np.abs(limit - untagged[:len(cage[0])]).max() > 1e-2 * size
