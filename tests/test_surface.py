"""The Loop limit surface (LimitSurface, limit_surface, evaluate_limit) against
limit_points, a direct sparse solve and finite differences."""

from __future__ import annotations

import numpy as np
import pytest

import sorpia
from conftest import direct_solve

BOUNDARIES = ["edge-and-corner", "edge-only"]
CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])


def diagonal(v):
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))


def fit(v0, f, boundary, how):
    """Control vertices V with B V = V0 (paper eq. 7): by sorpia.interpolate
    (SOR-PIA, stopping at E_k <= 1e-12 E_0), or by a direct sparse solve
    independent of sorpia's solvers (B's spectrum lies in about [0.2, 1], so
    it is accurate to ~1e-15)."""
    if how == "interpolate":
        res = sorpia.interpolate(v0, f, tol=1e-12, boundary=boundary)
        assert res.converged
        return res.control_vertices
    return direct_solve(f, v0, boundary)


@pytest.mark.parametrize("how", ["interpolate", "direct"])
@pytest.mark.parametrize("boundary", BOUNDARIES)
def test_limit_surface_of_a_fitted_mesh_passes_through_the_data(mesh, boundary, how):
    # 1e-9 of the bounding-box diagonal: the requirement, far above
    # both fits' accuracy.
    _, v0, f = mesh
    v = fit(v0, f, boundary, how)
    vs, fs = sorpia.limit_surface(v, f, level=2, boundary=boundary)
    assert vs.dtype == np.float64 and fs.dtype == np.int32
    assert fs.shape == (16 * len(f), 3)
    assert np.abs(vs[: len(v0)] - v0).max() <= 1e-9 * diagonal(v0)


@pytest.mark.parametrize("boundary", BOUNDARIES)
def test_tessellation_vertices_of_control_vertices_are_limit_points_exactly(mesh, boundary):
    # Same computation (OpenSubdiv's Limit on the unrefined mesh): bit-identical.
    _, v, f = mesh
    vs, fs = sorpia.limit_surface(v, f, level=1, boundary=boundary)
    assert np.array_equal(vs[: len(v)], sorpia.limit_points(v, f, boundary=boundary))
    # Every vertex is used and every index is in range.
    assert np.array_equal(np.unique(fs), np.arange(len(vs)))


def test_children_of_a_face_are_contiguous_and_keep_its_corners():
    # Rows f*4^L .. (f+1)*4^L - 1 cover face f: its three corner vertices (the
    # only indices < n among them) are exactly face f's vertices.
    v, f = sorpia.shapes.irregular(300, seed=3)
    vs, fs = sorpia.limit_surface(v, f, level=2)
    children = fs.reshape(len(f), 16, 3)
    for k in range(len(f)):
        ids = children[k][children[k] < len(v)]
        assert sorted(set(ids.tolist())) == sorted(f[k].tolist())


@pytest.mark.parametrize("boundary", BOUNDARIES)
def test_edge_midpoints_of_the_tessellation_lie_on_the_limit_surface(mesh, boundary):
    # Level 1: the child (a, e_ab, e_ca) of face (a, b, c) keeps the face's
    # orientation, so the vertex after a is the midpoint vertex of edge ab,
    # which is the limit point at (u, v) = (1/2, 0) (Bfr). Two independent
    # OpenSubdiv paths (Far uniform refinement + Limit, Bfr patches); 1e-12 of
    # the diagonal allows for their different rounding.
    _, v, f = mesh
    vs, fs = sorpia.limit_surface(v, f, level=1, boundary=boundary)
    children = fs.reshape(len(f), 4, 3)
    mid = np.empty(len(f), dtype=np.int64)
    for k in range(len(f)):
        a = f[k, 0]
        for child in children[k]:
            where = np.flatnonzero(child == a)
            if where.size:
                mid[k] = child[(where[0] + 1) % 3]
    p = sorpia.evaluate_limit(v, f, np.arange(len(f)), np.tile([[0.5, 0.0]], (len(f), 1)), boundary=boundary)
    assert np.abs(vs[mid] - p).max() <= 1e-12 * diagonal(v)


@pytest.mark.parametrize("boundary", BOUNDARIES)
def test_evaluate_limit_at_the_corners_equals_limit_points(mesh, boundary):
    # (0,0), (1,0), (0,1) are the face's first, second and third vertex. Bfr
    # and Far's Limit evaluate the same mask with different arithmetic: 1e-14
    # of the diagonal (measured: 2e-16).
    _, v, f = mesh
    face_ids = np.repeat(np.arange(len(f)), 3)
    uv = np.tile(CORNERS, (len(f), 1))
    p = sorpia.evaluate_limit(v, f, face_ids, uv, boundary=boundary)
    expected = sorpia.limit_points(v, f, boundary=boundary)[f.ravel()]
    assert p.shape == (3 * len(f), 3)
    assert np.abs(p - expected).max() <= 1e-14 * diagonal(v)


def finite_difference_check(s, face_ids, uv, h):
    """Largest differences between Bfr's tangents (relative to their size) and
    normals and central differences of Bfr's positions."""
    p, du, dv, n = s.evaluate(face_ids, uv, derivatives=True)
    assert np.array_equal(p, s.evaluate(face_ids, uv))
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-14)
    fd_u = (s.evaluate(face_ids, uv + [h, 0]) - s.evaluate(face_ids, uv - [h, 0])) / (2 * h)
    fd_v = (s.evaluate(face_ids, uv + [0, h]) - s.evaluate(face_ids, uv - [0, h])) / (2 * h)
    fd_n = np.cross(fd_u, fd_v)
    fd_n /= np.linalg.norm(fd_n, axis=1, keepdims=True)
    scale = max(np.abs(du).max(), np.abs(dv).max())
    return max(np.abs(fd_u - du).max(), np.abs(fd_v - dv).max()) / scale, np.abs(fd_n - n).max()


@pytest.mark.parametrize("boundary", BOUNDARIES)
def test_tangents_and_normals_agree_with_finite_differences(mesh, boundary):
    # Away from the Gregory corner triangles (side 1/16 at extraordinary
    # vertices; every barycentric coordinate <= 0.9 < 15/16 here) the patches
    # are polynomial. Central differences with h = 1e-6: truncation
    # ~h^2 |P'''| plus rounding ~eps/h, ~1e-10 for these unit-sized meshes;
    # 1e-7 leaves a margin.
    _, v, f = mesh
    rng = np.random.default_rng(7)
    k = 300
    face_ids = rng.integers(0, len(f), size=k)
    uv = rng.dirichlet([1, 1, 1], size=k)[:, :2] * 0.85 + 0.05
    s = sorpia.LimitSurface(v, f, boundary=boundary)
    tangent_err, normal_err = finite_difference_check(s, face_ids, uv, 1e-6)
    assert tangent_err <= 1e-7 and normal_err <= 1e-7


def test_near_extraordinary_vertices_normals_stay_within_the_documented_bound():
    # In the Gregory corner triangles OpenSubdiv approximates the derivatives
    # (it drops the derivative of the rational weights): about 0.02 rad for
    # normals, documented; a regular torus has no Gregory patches, so there
    # points next to the corners are as exact as the rest.
    rng = np.random.default_rng(3)
    for (v, f), bound in [(sorpia.shapes.irregular(500, seed=2), 0.05), (sorpia.shapes.torus(12, 8), 1e-7)]:
        k = 300
        face_ids = rng.integers(0, len(f), size=k)
        uv = rng.uniform(0.002, 0.04, size=(k, 2))
        _, normal_err = finite_difference_check(sorpia.LimitSurface(v, f), face_ids, uv, 1e-7)
        assert normal_err <= bound


def test_normals_point_outward_on_a_sphere():
    # Faces counter-clockwise seen from outside: du x dv points away from the centre.
    v, f = sorpia.shapes.icosphere(2)
    rng = np.random.default_rng(1)
    uv = rng.dirichlet([1, 1, 1], size=len(f))[:, :2]
    p, _, _, n = sorpia.evaluate_limit(v, f, np.arange(len(f)), uv, derivatives=True)
    assert (np.einsum("ij,ij->i", p, n) > 0.9 * np.linalg.norm(p, axis=1)).all()


def test_set_vertices_gives_the_surface_of_the_new_control_mesh():
    # Same topology, new positions: bit-identical to a surface built afresh,
    # for evaluation and for a tessellation at the level kept from before.
    v, f = sorpia.shapes.irregular(400, seed=5)
    v2 = v * 1.5 + np.sin(v)
    s = sorpia.LimitSurface(v, f)
    s.tessellate(2)
    s.set_vertices(v2)
    fresh = sorpia.LimitSurface(v2, f)
    rng = np.random.default_rng(2)
    face_ids, uv = rng.integers(0, len(f), 50), rng.dirichlet([1, 1, 1], 50)[:, :2]
    assert np.array_equal(s.vertices, v2)
    assert np.array_equal(s.evaluate(face_ids, uv), fresh.evaluate(face_ids, uv))
    for a, b in zip(s.tessellate(2), fresh.tessellate(2)):
        assert np.array_equal(a, b)


def test_changing_the_tessellation_level_gives_the_fresh_surfaces_tessellation():
    # The refined topology is rebuilt on the kept base level whenever the
    # level changes (down, to 0 and back up): bit-identical to a new surface's,
    # and evaluation on the same object is unaffected (same Bfr factory).
    v, f = sorpia.shapes.grid(6, 5)
    s = sorpia.LimitSurface(v, f, boundary="edge-only")
    rng = np.random.default_rng(3)
    face_ids, uv = rng.integers(0, len(f), 20), rng.dirichlet([1, 1, 1], 20)[:, :2]
    before = s.evaluate(face_ids, uv)
    for level in (2, 1, 0, 2):
        for a, b in zip(s.tessellate(level), sorpia.limit_surface(v, f, level, boundary="edge-only")):
            assert np.array_equal(a, b)
    assert np.array_equal(s.evaluate(face_ids, uv), before)


def test_level_zero_is_the_limit_points_on_the_control_faces():
    v, f = sorpia.shapes.grid(5, 4)
    vs, fs = sorpia.limit_surface(v, f, level=0)
    assert np.array_equal(fs, f) and np.array_equal(vs, sorpia.limit_points(v, f))


def test_unreferenced_vertex_stays_where_it_is():
    v, f = sorpia.shapes.icosphere(1)
    v = np.vstack([v, [[3.0, 4.0, 5.0]]])
    with pytest.warns(sorpia.UnreferencedVerticesWarning):
        vs, fs = sorpia.limit_surface(v, f, level=1)
    assert np.array_equal(vs[len(v) - 1], [3.0, 4.0, 5.0])
    assert (fs != len(v) - 1).all()


def test_a_level_that_does_not_fit_in_memory_is_refused():
    # icosphere(3) at level 10: 1.3e9 triangles, hundreds of GB.
    v, f = sorpia.shapes.icosphere(3)
    with pytest.raises(sorpia.ParameterError, match=r"4\^level per face\) and needs about .* GB"):
        sorpia.limit_surface(v, f, level=10)


@pytest.mark.parametrize("level", [-1, 16, 2.5, True])
def test_bad_levels_are_refused(level):
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(sorpia.ParameterError, match="level"):
        sorpia.limit_surface(v, f, level=level)


def test_bad_evaluation_points_are_refused():
    v, f = sorpia.shapes.icosphere(0)
    s = sorpia.LimitSurface(v, f)
    with pytest.raises(sorpia.ParameterError, match=r"face_ids\[1\] = 20 is out of range"):
        s.evaluate([0, 20], [[0.1, 0.1], [0.1, 0.1]])
    with pytest.raises(sorpia.ParameterError, match=r"uv\[0\] = \(0\.8.*outside the triangle"):
        s.evaluate([0], [[0.8, 0.3]])
    with pytest.raises(sorpia.ParameterError, match="shape"):
        s.evaluate([0, 1], [[0.1, 0.1]])
    with pytest.raises(sorpia.ParameterError, match="not finite"):
        s.evaluate([0], [[np.nan, 0.1]])


def test_parameters_a_rounding_error_outside_are_accepted():
    # u + v = 1 + 1e-16 from floating-point arithmetic is on the edge, not an error.
    v, f = sorpia.shapes.icosphere(0)
    p = sorpia.evaluate_limit(v, f, [0], [[1 / 3 + 1e-16, 2 / 3]])
    assert np.isfinite(p).all()


def test_wrong_vertex_count_for_set_vertices_is_refused():
    v, f = sorpia.shapes.grid(4, 4)
    s = sorpia.LimitSurface(v, f)
    with pytest.raises(sorpia.ParameterError, match="rows"):
        s.set_vertices(np.asarray(v)[:-1])


@pytest.mark.parametrize("scale", [1e-300, 1e-100, 1e80, 1e154, 1e155, 1e300])
def test_normals_do_not_depend_on_the_scale_of_the_coordinates(scale):
    """Scaling a mesh by s > 0 scales du and dv by s and leaves the unit
    normals as they are; the squared cross product (of order s^4) must neither
    underflow to zero nor overflow to inf/NaN. 1e-14: a few ulps of unit
    vectors after the (inexact) scaling of the positions."""
    v, f = sorpia.shapes.icosphere(2)
    fid = np.arange(len(f))
    uv = np.full((len(f), 2), 1 / 3)
    _, _, _, n0 = sorpia.evaluate_limit(v, f, fid, uv, derivatives=True)
    _, _, _, n = sorpia.evaluate_limit(v * scale, f, fid, uv, derivatives=True)
    assert np.allclose(np.linalg.norm(n0, axis=1), 1.0, atol=1e-14)
    assert np.abs(n - n0).max() < 1e-14
