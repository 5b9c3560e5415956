"""Sharpness tags (creases, corners, holes) in B and in the solvers: rows
against closed forms and against OpenSubdiv's refinement of the whole mesh
(reference_limit_matrix, sorpia._reference), fits through the input vertices with every
method, and the OpenSubdiv shapes in ../shared/meshes when present."""

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

import sorpia
from sorpia import _core
from sorpia._validate import as_boundary, as_scheme
from sorpia.limit import tags as make_tags
from sorpia.limit import topology as make_topology
from sorpia.solve import METHODS

from conftest import reference_limit_matrix, darts, direct_solve, loop_alpha

SHARED_MESHES = Path(__file__).resolve().parents[2] / "shared" / "meshes"


def edges_of(faces):
    f = np.asarray(faces)
    return np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1), axis=0)


def reference_b(faces, n, boundary="edge-and-corner", **tags):
    """B from OpenSubdiv's whole-mesh refinement and Limit() (the test reference)."""
    topo = make_topology(faces, n, warn=False)
    data, indices, indptr = reference_limit_matrix(
        topo, _core.Rules(scheme=_core.Scheme.loop, boundary=as_boundary(boundary), tags=make_tags(topo, **tags)))
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=(n, n))


def ring_path(faces, v):
    """The neighbours of interior vertex v, in ring order."""
    f = np.asarray(faces)
    nxt = {}
    for a, b, c in f:
        for x, y, z in ((a, b, c), (b, c, a), (c, a, b)):
            if x == v:
                nxt[y] = z
    start = next(iter(nxt))
    out = [start]
    while nxt[out[-1]] != start:
        out.append(nxt[out[-1]])
    return out


@pytest.fixture
def sphere():
    return sorpia.shapes.icosphere(2)


def test_crease_rows_have_the_crease_rule(sphere):
    """Two infinitely sharp edges at an interior vertex: 2/3 on it, 1/6 on their ends (Sdc's crease rule)."""
    v, f = sphere
    v0 = 20
    ring = ring_path(f, v0)
    a, b = ring[0], ring[len(ring) // 2]
    B = sorpia.limit_matrix(f, len(v), creases=([[v0, a], [b, v0]], math.inf))
    row = B.getrow(v0).toarray().ravel()
    expected = np.zeros(len(v))
    expected[[v0, a, b]] = [2 / 3, 1 / 6, 1 / 6]
    np.testing.assert_allclose(row, expected, atol=1e-15)


def test_a_dart_is_not_the_smooth_rule_and_three_sharp_edges_make_a_corner(sphere):
    # A dart (one infinitely sharp edge) gets the limit of its refinement, not Sdc's smooth mask (Far's Limit() at
    # level 0): a row over the same one-ring, summing to 1, with its own weights (against Far refined around the
    # dart in tests/cpp/test_darts.cpp).
    v, f = sphere
    v0 = 20
    ring = ring_path(f, v0)
    smooth = sorpia.limit_matrix(f, len(v)).getrow(v0).toarray().ravel()
    assert smooth[v0] == pytest.approx(loop_alpha(len(ring)), abs=1e-15)
    dart = sorpia.limit_matrix(f, len(v), creases=([[v0, ring[0]]], math.inf)).getrow(v0).toarray().ravel()
    np.testing.assert_array_equal(np.flatnonzero(dart), np.flatnonzero(smooth))
    assert dart.sum() == pytest.approx(1.0, abs=1e-15)
    assert np.abs(dart - smooth).max() > 1e-3
    three = [[v0, ring[0]], [v0, ring[1]], [v0, ring[3]]]
    corner = sorpia.limit_matrix(f, len(v), creases=(three, 10.0)).getrow(v0).toarray().ravel()
    np.testing.assert_array_equal(corner, np.eye(len(v))[v0])
    tagged = sorpia.limit_matrix(f, len(v), corners=([v0], math.inf)).getrow(v0).toarray().ravel()
    np.testing.assert_array_equal(tagged, np.eye(len(v))[v0])


def test_infinitely_sharp_tags_keep_the_uniform_kernel_without_darts(sphere):
    # A closed loop of sharp edges (the ring around vertex 20) and a corner: no dart, one weight per row. A dart's
    # row has several weights.
    v, f = sphere
    ring = ring_path(f, 20)
    loop = np.column_stack([ring, np.roll(ring, -1)])
    interp = sorpia.Interpolator(f, len(v), creases=(loop, math.inf), corners=([3], math.inf))
    assert interp._impl.uniform
    assert not sorpia.Interpolator(f, len(v), creases=(loop[:3], math.inf))._impl.uniform
    semi = sorpia.Interpolator(f, len(v), creases=(edges_of(f)[::7], 1.5))
    assert not semi._impl.uniform


@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
@pytest.mark.parametrize("name", ["icosphere", "grid", "irregular"])
def test_rows_equal_opensubdivs_whole_mesh_refinement(name, boundary):
    """Every row against OpenSubdiv's refinement of the whole mesh until the
    sharpness has decayed and Limit() on the last level, to 1e-14."""
    v, f = {"icosphere": lambda: sorpia.shapes.icosphere(2), "grid": lambda: sorpia.shapes.grid(8, 6),
            "irregular": lambda: sorpia.shapes.irregular(300, seed=5)}[name]()
    rng = np.random.default_rng(7)
    e = edges_of(f)
    pick = rng.random(len(e)) < 0.15
    sharp = rng.choice([0.25, 1.0, 1.75, 2.5, math.inf], pick.sum())
    corners = rng.choice(len(v), 4, replace=False)
    tags = dict(creases=(e[pick], sharp), corners=(corners, [0.5, 2.0, math.inf, 1.25]), holes=[0, 5])
    B = sorpia.limit_matrix(f, len(v), boundary=boundary, **tags)
    ref = reference_b(f, len(v), boundary, **tags)
    rows = np.flatnonzero(~darts(f, len(v), **tags))
    assert abs(B - ref)[rows].max() < 1e-14
    # Rows of semi-sharp vertices and darts are wider than a ring mask or have several weights, and sum to 1.
    np.testing.assert_allclose(np.asarray(B.sum(axis=1)).ravel(), 1.0, atol=1e-14)


@pytest.mark.parametrize("method", METHODS)
def test_every_method_fits_through_the_vertices_with_tags(method):
    v, f = sorpia.shapes.irregular(400, seed=3)
    rng = np.random.default_rng(1)
    e = edges_of(f)
    pick = rng.random(len(e)) < 0.2
    tags = dict(creases=(e[pick], rng.choice([0.5, 2.0, math.inf], pick.sum())), corners=([0], 3.0))
    res = sorpia.interpolate(v, f, method=method, max_iter=2000, **tags)
    assert res.converged
    # Checked with OpenSubdiv's own B (whole-mesh refinement + Limit()), not sorpia's operator, away from darts
    # (whose rows that reference does not give).
    ref = reference_b(f, len(v), **tags)
    rows = ~darts(f, len(v), **tags)
    assert np.linalg.norm(ref @ res.control_vertices - v, axis=1)[rows].max() <= 1e-9 * np.abs(v).max()
    # and against scipy's direct solve of sorpia's B
    B = sorpia.limit_matrix(f, len(v), **tags).tocsc()
    np.testing.assert_allclose(res.control_vertices, scipy.sparse.linalg.splu(B).solve(v), atol=1e-8)


def test_limit_points_with_tags_is_b_times_v(sphere):
    v, f = sphere
    e = edges_of(f)[::5]
    tags = dict(creases=(e, 1.5), corners=([1, 2], [math.inf, 0.5]))
    np.testing.assert_allclose(sorpia.limit_points(v, f, **tags), sorpia.limit_matrix(f, len(v), **tags) @ v,
                               atol=1e-15)


def test_holes_change_no_row(sphere):
    v, f = sphere
    holes = np.arange(0, len(f), 4)
    np.testing.assert_array_equal(sorpia.limit_matrix(f, len(v), holes=holes).toarray(),
                                  sorpia.limit_matrix(f, len(v)).toarray())
    assert abs(reference_b(f, len(v), holes=holes) - sorpia.limit_matrix(f, len(v))).max() < 1e-15


def test_a_crease_that_is_not_an_edge_is_named(sphere):
    v, f = sphere
    e = edges_of(f)
    far = next(j for j in range(len(v)) if not np.any((e == [0, j]).all(axis=1)) and j != 0)
    with pytest.raises(sorpia.MeshError, match=rf"creases\[1\] = \[0, {far}\] is not an edge of the mesh"):
        sorpia.interpolate(v, f, creases=([e[0], [0, far]], 1.0))
    with pytest.raises(sorpia.MeshError, match=r"creases\[0\] = \[3, 3\]"):
        sorpia.limit_points(v, f, creases=([[3, 3]], 1.0))


def test_untagged_calls_are_unchanged(sphere):
    v, f = sphere
    np.testing.assert_array_equal(sorpia.limit_matrix(f, len(v), creases=(np.zeros((0, 2), int), [])).toarray(),
                                  sorpia.limit_matrix(f, len(v)).toarray())
    np.testing.assert_allclose(sorpia.interpolate(v, f).control_vertices, direct_solve(f, v), atol=1e-8)


# OpenSubdiv's Loop shapes with their tags (`t` lines of the OBJ files).
def read_osd_shape(path: Path):
    v, f, tags = sorpia.read_mesh(path, tags=True)
    boundary = tags.pop("boundary", "edge-and-corner")
    return v, f, tags, boundary


OSD_LOOP_TAGGED = ["osd_loop_cube_creases0.obj", "osd_loop_cubes_semisharp.obj", "osd_loop_icos_infsharp.obj"]


@pytest.mark.skipif(not SHARED_MESHES.exists(), reason="../shared/meshes is not present")
@pytest.mark.parametrize("name", OSD_LOOP_TAGGED)
def test_opensubdiv_shapes_rows_and_fits(name):
    v, f, tags, boundary = read_osd_shape(SHARED_MESHES / name)
    assert tags
    ref = reference_b(f, len(v), boundary, **tags)
    B = sorpia.limit_matrix(f, len(v), boundary=boundary, **tags)
    rows = ~darts(f, len(v), **tags)  # their rows: tests/cpp/test_darts.cpp
    assert abs(B - ref)[np.flatnonzero(rows)].max() < 1e-14
    for method in METHODS:
        res = sorpia.interpolate(v, f, method=method, boundary=boundary, max_iter=3000, **tags)
        assert res.converged, method
        miss = np.linalg.norm(ref @ res.control_vertices - v, axis=1)[rows]
        assert miss.max() <= 1e-9 * np.abs(v).max(), method


def reference_b_scheme(faces, n, boundary, scheme, **tags):
    topo = make_topology(faces, n, scheme=scheme, warn=False)
    data, indices, indptr = reference_limit_matrix(
        topo, _core.Rules(scheme=as_scheme(scheme), boundary=as_boundary(boundary), tags=make_tags(topo, **tags)))
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=(n, n))


@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
def test_catmull_clark_rows_with_tags_equal_opensubdivs(boundary):
    """Quads and other polygons (polygon_torus has interior vertices of two faces, whose rows OpenSubdiv's
    Limit() changes with the level): every row against the whole mesh refined by OpenSubdiv, to 1e-14."""
    for v, f in [sorpia.shapes.quad_grid(7, 5), sorpia.shapes.polygon_torus(9, 7, 2)]:
        e = edges_of_polygons(f)
        rng = np.random.default_rng(3)
        pick = rng.random(len(e)) < 0.15
        tags = dict(creases=(e[pick], rng.choice([0.5, 1.5, 2.5, math.inf], pick.sum())), corners=([2], 1.5))
        B = sorpia.limit_matrix(f, len(v), boundary=boundary, scheme="catmull-clark", **tags)
        rows = np.flatnonzero(~darts(f, len(v), **tags))  # darts: tests/cpp/test_darts.cpp
        assert abs(B - reference_b_scheme(f, len(v), boundary, "catmull-clark", **tags))[rows].max() < 1e-14


def edges_of_polygons(faces):
    if isinstance(faces, sorpia.Polygons):
        counts, idx = np.asarray(faces.face_vertex_counts), np.asarray(faces.face_vertex_indices)
    else:
        f = np.asarray(faces)
        counts, idx = np.full(len(f), f.shape[1]), f.ravel()
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    pos = np.arange(len(idx)) - np.repeat(start, counts)
    nxt = np.repeat(start, counts) + (pos + 1) % np.repeat(counts, counts)
    return np.unique(np.sort(np.column_stack([idx, idx[nxt]]), axis=1), axis=0)


OSD_CATMARK_TAGGED = ["osd_catmark_cube_corner0.obj", "osd_catmark_cube_creases0.obj", "osd_catmark_cube_creases1.obj",
                      "osd_catmark_cubes_semisharp.obj", "osd_catmark_torus_creases0.obj", "osd_catmark_helmet.obj"]


@pytest.mark.skipif(not SHARED_MESHES.exists(), reason="../shared/meshes is not present")
@pytest.mark.parametrize("name", OSD_CATMARK_TAGGED)
def test_opensubdiv_catmull_clark_shapes_rows_and_fits(name):
    """Every row against OpenSubdiv's whole-mesh refinement (7 levels for the helmet), then every method's fit
    checked with that B."""
    v, f, tags, boundary = read_osd_shape(SHARED_MESHES / name)
    ref = reference_b_scheme(f, len(v), boundary, "catmull-clark", **tags)
    rows = ~darts(f, len(v), **tags)  # their rows: tests/cpp/test_darts.cpp
    B = sorpia.limit_matrix(f, len(v), boundary=boundary, scheme="catmull-clark", **tags)
    assert abs(B - ref)[np.flatnonzero(rows)].max() < 1e-14
    for method in METHODS:
        res = sorpia.interpolate(v, f, method=method, boundary=boundary, scheme="catmull-clark", max_iter=3000, **tags)
        assert res.converged, method
        miss = np.linalg.norm(ref @ res.control_vertices - v, axis=1)[rows]
        assert miss.max() <= 1e-9 * np.abs(v).max(), method


@pytest.mark.skipif(not SHARED_MESHES.exists(), reason="../shared/meshes is not present")
@pytest.mark.parametrize("name", ["osd_catmark_pawn.obj", "osd_catmark_bishop.obj", "osd_catmark_rook.obj",
                                  "osd_catmark_car.obj"])
def test_large_opensubdiv_shapes_rows_on_whole_neighbourhoods(name):
    """The chess pieces and the car need 6 to 8 levels, past a whole-mesh refinement here: the rows of tagged
    vertices are checked against OpenSubdiv's refinement of the whole two-ring around them (faces beyond the
    one-ring that sorpia's rows are computed from), with their tags."""
    v, f, tags, boundary = read_osd_shape(SHARED_MESHES / name)
    B = sorpia.limit_matrix(f, len(v), boundary=boundary, scheme="catmull-clark", **tags).tocsr()
    faces = [np.asarray(x) for x in (f if not isinstance(f, sorpia.Polygons) else np.split(
        np.asarray(f.face_vertex_indices), np.cumsum(f.face_vertex_counts)[:-1]))]
    edges, sharp = tags["creases"]
    dart = darts(f, len(v), **tags)  # their rows: tests/cpp/test_darts.cpp
    rng = np.random.default_rng(0)
    for seed in rng.choice(np.unique(edges), 1):
        ring = {int(seed)}
        for _ in range(2):
            ring |= {int(u) for face in faces if ring & set(face.tolist()) for u in face}
        near = [face for face in faces if set(face.tolist()) & ring]
        used = np.unique(np.concatenate(near))
        index = {int(u): k for k, u in enumerate(used)}
        sub = sorpia.Polygons(np.array([len(x) for x in near]), np.array([index[int(u)] for x in near for u in x]))
        keep = np.array([a in index and b in index for a, b in edges])
        sub_tags = {"creases": (np.array([[index[int(a)], index[int(b)]] for a, b in edges[keep]]).reshape(-1, 2),
                                sharp[keep])}
        # only edges of the sub-mesh (an edge between two kept vertices may belong to faces left out)
        sub_edges = {tuple(e) for e in edges_of_polygons(sub)}
        ok = np.array([tuple(sorted(e)) in sub_edges for e in sub_tags["creases"][0]], bool)
        sub_tags["creases"] = (sub_tags["creases"][0][ok], sub_tags["creases"][1][ok])
        ref = reference_b_scheme(sub, len(used), boundary, "catmull-clark", **sub_tags)
        one_ring = {int(u) for face in faces if int(seed) in face.tolist() for u in face}
        for u in one_ring - set(np.flatnonzero(dart).tolist()):  # every vertex whose faces lie in the sub-mesh
            row = B.getrow(u).toarray().ravel()[used]
            np.testing.assert_allclose(ref.getrow(index[u]).toarray().ravel(), row, atol=1e-14, err_msg=f"{name} {u}")
