"""sorpia.SubdivisionMesh: one value for a mesh and its rules, taken wherever
(vertices, faces, **rules) are, with results bit for bit those of the arrays;
the one scheme default ("auto") and its one resolver; the file round trip."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
import scipy.sparse

import sorpia
from sorpia import MeshError, ParameterError, SubdivisionMesh


@pytest.fixture(scope="module")
def creased_quads():
    """A quad torus with a crease, a corner and a hole: every rule set."""
    V, F = sorpia.shapes.quad_torus(12, 8)
    creases = (np.array([[0, 1], [1, 2]]), np.array([2.0, np.inf]))
    corners = (np.array([30]), np.array([3.0]))
    holes = np.array([40])
    rules = dict(scheme="catmull-clark", boundary="edge-only", creases=creases, corners=corners, holes=holes)
    return V, F, rules, SubdivisionMesh(V, F, **rules)


def test_the_mesh_converts_once_and_is_read_only():
    V, F = sorpia.shapes.icosphere(1)
    mesh = SubdivisionMesh(V.tolist(), F.astype(np.int64))
    assert mesh.vertices.dtype == np.float64 and mesh.faces.dtype == np.int32
    np.testing.assert_array_equal(mesh.vertices, V)
    np.testing.assert_array_equal(mesh.faces, F)
    with pytest.raises(ValueError, match="read-only"):
        mesh.vertices[0, 0] = 1.0
    assert V.flags.writeable  # the caller's array keeps its flags
    with pytest.raises(AttributeError):
        mesh.scheme = "catmull-clark"  # frozen
    assert (mesh.n_vertices, mesh.n_faces, mesh.scheme, mesh.boundary) == (42, 80, "loop", "edge-and-corner")


@pytest.mark.parametrize("shape, expected", [("icosphere", "loop"), ("quad_torus", "catmull-clark"),
                                             ("polygon_torus", "catmull-clark")])
def test_auto_is_resolved_once_on_the_faces(shape, expected):
    V, F = getattr(sorpia.shapes, shape)()
    assert SubdivisionMesh(V, F).scheme == expected == sorpia.resolve_scheme("auto", F)
    assert sorpia.resolve_scheme("auto", F, file_scheme="loop") == "loop"  # a file's own scheme first
    assert sorpia.resolve_scheme("catmull-clark", F) == "catmull-clark"


def test_resolve_scheme_refuses_what_it_cannot_resolve():
    with pytest.raises(ParameterError, match="needs the faces"):
        sorpia.resolve_scheme("auto")
    with pytest.raises(ParameterError, match="'auto'"):
        sorpia.resolve_scheme("butterfly", np.zeros((1, 3), int))
    with pytest.raises(ParameterError, match="string"):
        sorpia.resolve_scheme(None)


def test_bad_meshes_are_refused_when_made():
    V, F = sorpia.shapes.quad_torus(6, 4)
    with pytest.raises(MeshError, match="Loop subdivision needs triangles"):
        SubdivisionMesh(V, F, scheme="loop")
    with pytest.raises(ParameterError, match="unknown boundary"):
        SubdivisionMesh(V, F, boundary="none")
    with pytest.raises(MeshError, match="out of range"):
        SubdivisionMesh(V[:5], F)
    with pytest.raises(ParameterError, match="nonmanifold"):
        SubdivisionMesh(V, F, nonmanifold="ignore")


def test_interpolate_takes_quads_by_default():
    """The one default, "auto": interpolate(V, quads) is Catmull-Clark, as approximate's always was."""
    V, F = sorpia.shapes.quad_torus(10, 6)
    auto = sorpia.interpolate(V, F)
    cc = sorpia.interpolate(V, F, scheme="catmull-clark")
    np.testing.assert_array_equal(auto.control_vertices, cc.control_vertices)
    B = sorpia.limit_matrix(F, len(V), scheme="catmull-clark")
    assert np.abs(B @ auto.control_vertices - V).max() < 1e-8 * np.abs(V).max()


def test_every_entry_point_gives_the_arrays_result_bit_for_bit(creased_quads):
    V, F, rules, mesh = creased_quads
    a, b = sorpia.interpolate(V, F, **rules), sorpia.interpolate(mesh)
    np.testing.assert_array_equal(a.control_vertices, b.control_vertices)
    cv = a.control_vertices
    np.testing.assert_array_equal(sorpia.limit_points(cv, F, **rules), sorpia.limit_points(cv, mesh))
    np.testing.assert_array_equal(sorpia.limit_points(V, F, **rules), sorpia.limit_points(mesh))
    assert (sorpia.limit_matrix(F, len(V), **rules) != sorpia.limit_matrix(mesh)).nnz == 0
    s1, s2 = sorpia.limit_surface(cv, F, 2, **rules), sorpia.limit_surface(cv, mesh, level=2)
    np.testing.assert_array_equal(s1[0], s2[0])
    np.testing.assert_array_equal(sorpia.limit_surface(mesh, 2)[0], sorpia.limit_surface(V, F, 2, **rules)[0])
    fids, uv = np.array([0, 5, 17]), np.array([[0.2, 0.3], [0.5, 0.5], [0.9, 0.1]])
    np.testing.assert_array_equal(sorpia.evaluate_limit(V, F, fids, uv, **rules), sorpia.evaluate_limit(mesh, fids, uv))
    np.testing.assert_array_equal(sorpia.evaluate_limit(cv, F, fids, uv, True, **rules)[3],
                                  sorpia.evaluate_limit(cv, mesh, fids, uv, True)[3])
    np.testing.assert_array_equal(sorpia.LimitSurface(V, F, **rules).tessellate(1)[0],
                                  sorpia.LimitSurface(mesh).tessellate(1)[0])
    i1, i2 = sorpia.Interpolator(F, len(V), **rules), sorpia.Interpolator(mesh)
    np.testing.assert_array_equal(i1.solve(V).control_vertices, i2.solve(V).control_vertices)
    k1, k2 = sorpia.fairness_matrix(F, len(V), **rules), sorpia.fairness_matrix(mesh)
    assert (k1 != k2).nnz == 0
    assert sorpia.thin_plate_energy(V, F, **rules) == sorpia.thin_plate_energy(mesh)
    f1, f2 = sorpia.fair_interpolate(V, F, **rules), sorpia.fair_interpolate(mesh)
    np.testing.assert_array_equal(f1.control_vertices, f2.control_vertices)
    stats = sorpia.mesh_statistics(V, F, scheme="catmull-clark")
    assert sorpia.mesh_statistics(mesh) == stats
    np.testing.assert_array_equal(sorpia.sharp_edges(V, F, 20.0), sorpia.sharp_edges(mesh, 20.0))
    np.testing.assert_array_equal(sorpia.sharp_edges(V, F, 20.0), sorpia.sharp_edges(mesh, angle_degrees=20.0))


def test_approximate_takes_the_cage_as_a_mesh(creased_quads):
    V, F, rules, mesh = creased_quads
    points = sorpia.limit_surface(V, F, 2, **rules)[0]
    r1 = sorpia.approximate(points, V, F, iterations=2, **rules)
    r2 = sorpia.approximate(points, mesh, iterations=2)
    np.testing.assert_array_equal(r1.control_vertices, r2.control_vertices)
    assert r1.history[-1]["rms"] == r2.history[-1]["rms"]
    fitted = r2.mesh  # the cage's faces and rules with the fitted vertices
    assert (fitted.scheme, fitted.boundary) == ("catmull-clark", "edge-only")
    np.testing.assert_array_equal(fitted.vertices, r2.control_vertices)
    np.testing.assert_array_equal(fitted.creases[0], mesh.creases[0])


def test_repair_and_decimate_carry_the_mesh():
    V, F = sorpia.shapes.icosphere(3)
    bowtie = np.vstack([F, F[:1] + 0])  # a duplicate face: repair removes it
    mesh = SubdivisionMesh(V, bowtie, boundary="edge-only", corners=(np.array([3]), 2.0))
    r = sorpia.repair(mesh)
    assert r.changes["counts"]["duplicate_faces"] == 1
    assert (r.mesh.boundary, r.mesh.scheme) == ("edge-only", "loop")
    np.testing.assert_array_equal(r.mesh.corners[0], [3])
    np.testing.assert_array_equal(r.faces, sorpia.repair(V, bowtie).faces)
    cage = sorpia.decimate(SubdivisionMesh(V, F), 60)
    same = sorpia.decimate(V, F, 60)
    np.testing.assert_array_equal(cage.vertices, same.vertices)
    assert cage.mesh.scheme == "loop"
    quad = sorpia.decimate(SubdivisionMesh(V, F, scheme="catmull-clark"), n_vertices=200)  # the mesh's scheme
    assert len(quad.vertices) == 200 and quad.mesh.scheme == "catmull-clark"


def test_a_rule_given_twice_is_refused(creased_quads):
    V, F, rules, mesh = creased_quads
    with pytest.raises(ParameterError, match=r"scheme='loop' given beside a SubdivisionMesh whose scheme is "
                                             r"'catmull-clark'"):
        sorpia.interpolate(mesh, scheme="loop")
    with pytest.raises(ParameterError, match="creases=tuple given beside"):
        sorpia.limit_points(mesh, creases=rules["creases"])
    sorpia.limit_points(mesh, boundary="edge-only")  # the mesh's own value: no conflict
    with pytest.raises(TypeError, match="by keyword"):
        sorpia.interpolate(mesh, "sor")
    with pytest.raises(ParameterError, match="n_vertices = 3"):
        sorpia.limit_matrix(mesh, 3)


def test_with_vertices_and_replace():
    V, F = sorpia.shapes.quad_grid(4, 4)
    mesh = SubdivisionMesh(V, F, creases=([[0, 1]], 1.0))
    moved = mesh.with_vertices(V + 1.0)
    np.testing.assert_array_equal(moved.vertices, V + 1.0)
    assert moved.faces is mesh.faces  # no copy of the faces
    np.testing.assert_array_equal(moved.creases[0], mesh.creases[0])
    np.testing.assert_array_equal(mesh.creases[1], [1.0])  # one number, one per tag
    with pytest.raises(ParameterError, match="rows"):
        mesh.with_vertices(V[:3])
    assert mesh.replace(boundary="edge-only").boundary == "edge-only"
    assert "creases=1" in repr(mesh)
    again = pickle.loads(pickle.dumps(mesh))  # made again by the constructor: read-only, equal
    assert not again.vertices.flags.writeable and not again.creases[0].flags.writeable
    np.testing.assert_array_equal(again.vertices, mesh.vertices)
    np.testing.assert_array_equal(again.faces, mesh.faces)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".off"])
def test_file_round_trip(tmp_path, suffix, creased_quads):
    V, F, rules, mesh = creased_quads
    if suffix != ".obj":  # only OBJ holds tags; PLY and OFF take the bare mesh
        mesh = SubdivisionMesh(V, F)
    path = tmp_path / f"m{suffix}"
    sorpia.write_mesh(path, mesh)
    back = sorpia.read(path)
    np.testing.assert_array_equal(back.vertices, mesh.vertices)
    np.testing.assert_array_equal(back.faces, mesh.faces)
    assert back.rules.keys() == mesh.rules.keys()
    for name in ("scheme", "boundary", "nonmanifold"):
        assert getattr(back, name) == getattr(mesh, name)
    for name in ("creases", "corners"):
        if getattr(mesh, name) is not None:
            (got_i, got_s), (want_i, want_s) = getattr(back, name), getattr(mesh, name)
            np.testing.assert_array_equal(got_i, want_i)
            # inf is read back as OpenSubdiv's infinite sharpness, 10: the same rule (10 and above is infinite)
            np.testing.assert_array_equal(np.minimum(got_s, 10.0), np.minimum(want_s, 10.0))
    if mesh.holes is not None:
        np.testing.assert_array_equal(back.holes, mesh.holes)
    # the arrays form reads the same values
    V2, F2 = sorpia.read_mesh(path)
    np.testing.assert_array_equal(V2, back.vertices)


def test_write_refuses_what_the_format_cannot_hold(tmp_path):
    V, F = sorpia.shapes.icosphere(1)
    with pytest.raises(ParameterError, match="do not hold a scheme"):
        sorpia.write_mesh(tmp_path / "m.obj", SubdivisionMesh(V, F, scheme="catmull-clark"))
    with pytest.raises(ParameterError, match="creases"):
        sorpia.write_mesh(tmp_path / "m.ply", SubdivisionMesh(V, F, creases=([[0, 1]], 2.0)))
    with pytest.raises(ParameterError, match="carries its own"):
        sorpia.write_mesh(tmp_path / "m.obj", SubdivisionMesh(V, F), boundary="edge-only")


def test_usd_round_trip_keeps_the_scheme(tmp_path):
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    V, F = sorpia.shapes.icosphere(1)
    mesh = SubdivisionMesh(V.astype(np.float32).astype(np.float64), F, scheme="catmull-clark")
    sorpia.write_mesh(tmp_path / "m.usda", mesh)
    back = sorpia.read(tmp_path / "m.usda")
    assert back.scheme == "catmull-clark"  # the file's own scheme, though the faces are triangles
    np.testing.assert_array_equal(back.vertices, mesh.vertices)


# ---------------------------------------------------------------- the result vocabulary

def _results():
    V, F = sorpia.shapes.quad_torus(8, 6)
    mesh = SubdivisionMesh(V, F)
    points = sorpia.limit_surface(mesh, 2)[0]
    return {"interpolate": sorpia.interpolate(mesh), "fair": sorpia.fair_interpolate(mesh),
            "approximate": sorpia.approximate(points, mesh, iterations=2), "repair": sorpia.repair(mesh),
            "cage": sorpia.decimate(*sorpia.shapes.icosphere(2), 30)}


STOP_REASONS = {"converged", "exact", "max_iter", "diverged", "stalled", "singular", "callback"}


def test_every_result_reports_the_same_way():
    for name, res in _results().items():
        report = res.report()
        assert isinstance(report, dict) and json.loads(json.dumps(report)) == report, name
        if name in ("interpolate", "fair", "approximate"):
            assert res.seconds == res.timings["total"] == report["seconds"], name
            assert res.stop_reason in STOP_REASONS and report["stop_reason"] == res.stop_reason, name
            assert len(res.history) == res.iterations + 1, name
            assert report["max_error"] == res.max_error >= 0, name


def test_max_error_is_the_largest_miss_measured_independently():
    V, F = sorpia.shapes.quad_torus(8, 6)
    res = sorpia.interpolate(V, F, tol=1e-6)
    B = sorpia.limit_matrix(F, len(V))
    miss = np.linalg.norm(V - B @ res.control_vertices, axis=1).max()
    assert res.max_error == pytest.approx(miss, rel=1e-9)
    fair = sorpia.fair_interpolate(V, F)
    fine = scipy.sparse.csr_matrix(sorpia.limit_matrix(fair.faces, len(fair.control_vertices), **fair.mesh.rules))
    assert fair.max_error == pytest.approx(np.linalg.norm(V - (fine @ fair.control_vertices)[:len(V)],
                                                          axis=1).max(), rel=1e-6, abs=1e-15)


def test_old_names_are_deprecated_aliases():
    results = _results()
    with pytest.warns(DeprecationWarning, match="history"):
        errors = results["interpolate"].errors
    np.testing.assert_array_equal(errors, results["interpolate"].history)
    with pytest.warns(DeprecationWarning, match="history"):
        np.testing.assert_array_equal(results["fair"].energies, results["fair"].history)
    with pytest.warns(DeprecationWarning, match="max_error"):
        assert results["approximate"].max_distance == results["approximate"].max_error
    with pytest.warns(DeprecationWarning, match="changes"):
        assert results["repair"].report["counts"] == results["repair"].changes["counts"]
    assert results["repair"].report()["changes"] is results["repair"].changes


def test_the_blender_script_takes_a_catmull_clark_mesh():
    from sorpia.blender import blender_script

    V, F = sorpia.shapes.quad_torus(6, 4)
    creases = (F[:3, :2], 2.0)
    assert blender_script(SubdivisionMesh(V, F, creases=creases)) == blender_script(V, F, creases=creases)
    with pytest.raises(ParameterError, match="Catmull-Clark only"):
        blender_script(SubdivisionMesh(*sorpia.shapes.icosphere(1)))


def test_a_mesh_carries_nonmanifold_sharp():
    """Two fans meeting at vertex 0 (a bowtie): nonmanifold="sharp" travels with the mesh."""
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0.5], [0, -1, 0.5]])
    F = np.array([[0, 1, 2], [0, 3, 4]])
    mesh = SubdivisionMesh(V, F, nonmanifold="sharp")
    with pytest.warns(sorpia.NonmanifoldWarning):
        arrays = sorpia.limit_points(V, F, nonmanifold="sharp")
    with pytest.warns(sorpia.NonmanifoldWarning):
        np.testing.assert_array_equal(sorpia.limit_points(mesh), arrays)
    with pytest.warns(sorpia.NonmanifoldWarning):
        np.testing.assert_array_equal(sorpia.interpolate(mesh).control_vertices,
                                      sorpia.interpolate(V, F, nonmanifold="sharp").control_vertices)
    with pytest.raises(MeshError, match="non-manifold vertex 0"):
        sorpia.limit_points(mesh.replace(nonmanifold="error"))
