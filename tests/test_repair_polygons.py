"""sorpia.repair on quad and polygon meshes: each kind of defect built in code,
hypothesis properties over random corruptions of valid polygon meshes, and the
polygon meshes of ../shared/meshes (skipped when absent). Validity of a
repaired mesh is checked independently of sorpia by test_fuzz.mesh_problems
(plain Python dictionaries)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import sorpia
from sorpia.limit import topology
from sorpia._repair import REPORT_KINDS
from test_fuzz import CORRUPTIONS, FUZZ, corrupt, cycle, face_lists, mesh_problems
from test_io import SHARED_MESHES as SHARED


def without_repeats(face) -> list[int]:
    """A face without its consecutive repeats (cyclically)."""
    return [v for i, v in enumerate(face) if v != face[i - 1]]


def check_repaired(v, faces, result):
    """What every repair holds, checked without sorpia's validation."""
    v = np.asarray(v, float)
    out = face_lists(result.faces)
    assert mesh_problems(out, len(result.vertices)) == set()
    topology(result.faces, len(result.vertices), scheme="catmull-clark", warn=False)  # and sorpia's validation
    n = len(v)
    assert np.array_equal(result.vertex_map[:n], np.arange(n))
    assert np.array_equal(result.vertices.view(np.uint64), v[result.vertex_map].view(np.uint64))  # bit for bit
    given_faces = face_lists(faces)
    flipped = set(result.changes["flipped_faces"])
    for j, src in enumerate(result.face_map):
        mapped = [int(result.vertex_map[x]) for x in out[j]]
        assert cycle(mapped) == cycle(without_repeats(given_faces[src]), src in flipped), (j, src)
    kept_used = {x for src in result.face_map for x in given_faces[src]}
    assert kept_used <= set(result.vertex_map[[x for f in out for x in f]].tolist())
    json.dumps(result.changes)
    again = sorpia.repair(result.vertices, result.faces)  # idempotent: valid, and back as it is
    assert again.vertices is result.vertices and again.faces is result.faces
    assert not any(again.changes["counts"].values())


# ---- meshes built in code -------------------------------------------------

def quad_grid(nx, ny):
    """(vertices, (ny nx, 4) quads), counter-clockwise seen from +z."""
    x, y = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0))
    v = np.column_stack([x.ravel(), y.ravel(), np.sin(x.ravel()) * np.cos(y.ravel())])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    a = (j * (nx + 1) + i).ravel()
    return v, np.column_stack([a, a + 1, a + nx + 2, a + nx + 1])


def quad_torus(n, m):
    """A closed torus of n m quads."""
    u, w = np.meshgrid(np.arange(n) * 2 * np.pi / n, np.arange(m) * 2 * np.pi / m, indexing="ij")
    v = np.column_stack([((2 + np.cos(w)) * np.cos(u)).ravel(), ((2 + np.cos(w)) * np.sin(u)).ravel(),
                         np.sin(w).ravel()])
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    q = lambda a, b: ((a % n) * m + b % m).ravel()  # noqa: E731
    return v, np.column_stack([q(i, j), q(i + 1, j), q(i + 1, j + 1), q(i, j + 1)])


CUBE = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])


def cube(offset=0):
    corners = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float)[[0, 1, 3, 2, 4, 5, 7, 6]]
    return corners + offset, CUBE + 8 * offset


def mixed():
    """A 3 x 2 quad grid with a pentagon and a triangle on top: faces of 3, 4 and 5 vertices."""
    v, f = quad_grid(3, 2)
    v = np.vstack([v, [[1.5, 3.0, 0.0], [0.0, 3.5, 0.0]]])
    return v, [list(q) for q in f] + [[8, 9, 10, 11, 12], [8, 12, 13]]


def quad_moebius(n):
    """A band of n quads glued with a half twist: not orientable (2 n vertices)."""
    f = []
    for i in range(n):
        b0, b1 = (2 * i + 2, 2 * i + 3) if i + 1 < n else (1, 0)
        f.append([2 * i, b0, b1, 2 * i + 1])
    return np.random.default_rng(0).normal(size=(2 * n, 3)), np.array(f)


def points(n, seed=0):
    return np.random.default_rng(seed).normal(size=(n, 3))


# ---- each defect ----------------------------------------------------------

@pytest.mark.parametrize("form", ["array", "polygons", "lists"])
def test_valid_polygon_meshes_come_back_unchanged(form):
    for v, f in (quad_grid(4, 3), quad_torus(6, 4), cube(), mixed()):
        if form == "array" and isinstance(f, list):
            continue
        faces = {"array": lambda: np.ascontiguousarray(f, np.int32),
                 "polygons": lambda: sorpia.Polygons(np.array([len(x) for x in f], np.int32),
                                                     np.concatenate([np.asarray(x) for x in f]).astype(np.int32)),
                 "lists": lambda: [list(x) for x in f]}[form]()
        v = np.ascontiguousarray(v, float)
        r = sorpia.repair(v, faces)
        assert r.vertices is v and not any(r.changes["counts"].values())
        assert np.array_equal(r.face_map, np.arange(len(f)))
        if form == "lists":  # equal lengths are an (m, k) array, ragged lists Polygons
            assert isinstance(r.faces, sorpia.Polygons if isinstance(f, list) else np.ndarray)
            assert face_lists(r.faces) == face_lists(f)
        else:
            assert r.faces is faces  # the caller's own array or Polygons


def test_open_bowtie_of_quads_keeps_the_array_form():
    f = np.array([[0, 1, 2, 3], [0, 4, 5, 6]])
    r = sorpia.repair(points(7), f)
    assert r.changes["bowtie_vertices"] == [0] and r.changes["bowtie_copies"] == [1]
    assert r.faces.dtype == np.int32 and r.faces.tolist() == [[0, 1, 2, 3], [7, 4, 5, 6]]
    check_repaired(points(7), f, r)


def test_closed_bowtie_of_two_cubes():
    (v0, f0), (v1, f1) = cube(), cube(1)
    f = np.vstack([f0, f1])
    f[f == 8] = 6  # the second cube's first corner welded onto the first's 6
    v = np.vstack([v0, v1])
    r = sorpia.repair(v, f)
    assert r.changes["bowtie_vertices"] == [6] and r.changes["counts"]["bowtie_copies"] == 1
    assert r.changes["counts"]["flipped_faces"] == 0
    check_repaired(v, f, r)


@pytest.mark.parametrize("n_sheets", [3, 4])
def test_quad_sheets_on_one_edge(n_sheets):
    # n_sheets quads on edge (0, 1), alternating in direction: paired into sheets in face order
    f = [[0, 1, 2 + 2 * k, 3 + 2 * k] if k % 2 == 0 else [1, 0, 2 + 2 * k, 3 + 2 * k] for k in range(n_sheets)]
    v = points(2 + 2 * n_sheets)
    r = sorpia.repair(v, f)
    assert r.changes["nonmanifold_edges"] == [[0, 1]]
    assert r.changes["sheet_vertices"] == [0, 1]
    assert r.changes["sheet_copies"] == [(n_sheets - 1) // 2] * 2
    assert r.faces.shape == (n_sheets, 4)
    check_repaired(v, f, r)


def test_four_quad_sheets_from_two_cubes_sharing_an_edge():
    (v0, f0), (v1, f1) = cube(), cube(1)
    f = np.vstack([f0, f1])
    f[f == 8], f[f == 9] = 2, 3  # the second cube's edge (8, 9) welded onto (2, 3)
    v = np.vstack([v0, v1])
    r = sorpia.repair(v, f)
    assert r.changes["sheet_vertices"] == [2, 3] and r.changes["sheet_copies"] == [1, 1]
    edges = {tuple(sorted((a, b))) for q in r.faces.tolist() for a, b in zip(q, q[1:] + q[:1])}
    assert len(edges) == 24  # two closed cubes again
    check_repaired(v, f, r)


def test_duplicate_and_reversed_duplicate_quads_keep_the_first():
    v, f = quad_grid(3, 3)
    bad = np.vstack([f, f[[1]][:, [2, 3, 0, 1]], f[[4]][:, ::-1], f[[7]][:, [1, 0, 3, 2]]])
    r = sorpia.repair(v, bad)
    assert r.changes["duplicate_faces"] == [9] and r.changes["reversed_duplicate_faces"] == [10, 11]
    assert np.array_equal(r.faces, f)
    check_repaired(v, bad, r)


def test_mixed_orientation_flips_the_fewer_faces():
    v, f = mixed()
    bad = [list(x) for x in f]
    for i in (1, 6, 7):
        bad[i] = [bad[i][0]] + bad[i][:0:-1]  # reversed as repair reverses: the first corner kept
    r = sorpia.repair(v, bad)
    assert r.changes["flipped_faces"] == [1, 6, 7]
    assert isinstance(r.faces, sorpia.Polygons) and face_lists(r.faces) == face_lists(f)
    check_repaired(v, bad, r)


def test_repeated_corners_collapse_to_a_smaller_polygon_or_remove_the_face():
    # a triangle stored in a quad array as (a, b, c, c): the array comes back as Polygons
    v, f = quad_grid(2, 1)
    v = np.vstack([v, points(3)])
    bad = np.vstack([f, [[2, 6, 5, 5], [6, 2, 7, 6], [7, 8, 7, 2]]])
    r = sorpia.repair(v, bad)
    assert r.changes["collapsed_faces"] == [2, 3] and r.changes["degenerate_faces"] == [4]
    assert isinstance(r.faces, sorpia.Polygons)
    assert r.faces.face_vertex_counts.tolist() == [4, 4, 3, 3]
    assert face_lists(r.faces)[2:] == [[2, 6, 5], [2, 7, 6]]
    check_repaired(v, bad, r)
    assert any("repeated corner" in line for line in sorpia._repair.describe_changes(r.changes))


def test_degenerate_quad_removed_keeps_the_array_form():
    v, f = quad_grid(2, 2)
    bad = np.vstack([f, [[0, 1, 0, 3]]])
    r = sorpia.repair(v, bad)
    assert r.changes["degenerate_faces"] == [4] and r.faces.shape == (4, 4)
    check_repaired(v, bad, r)


def test_quad_moebius_strip_is_cut_along_one_edge():
    v, f = quad_moebius(7)
    r = sorpia.repair(v, f)
    assert len(r.changes["cut_edges"]) == 1 and r.changes["cut_copies"] == [1, 1]
    assert r.changes["cut_vertices"] == r.changes["cut_edges"][0]
    check_repaired(v, f, r)


def test_what_repair_does_not_change_is_refused():
    with pytest.raises(sorpia.MeshError, match="out of range"):
        sorpia.repair(points(4), [[0, 1, 2, 3], [0, 3, 9]])
    with pytest.raises(sorpia.MeshError, match="at least 3"):
        sorpia.repair(points(4), [[0, 1, 2, 3], [0, 1]])
    with pytest.raises(sorpia.MeshError, match="no face is left"):
        sorpia.repair(points(4), [[0, 1, 1], [2, 2, 2, 2]])


# ---- hypothesis properties -------------------------------------------------

BASES = {"grid-3x3": quad_grid(3, 3), "torus-4x3": quad_torus(4, 3), "cube": cube(), "mixed": mixed()}
IN_RANGE = CORRUPTIONS.filter(lambda e: e[0] != "set")


def as_form(faces, form):
    if form == "polygons":
        return sorpia.Polygons(np.array([len(x) for x in faces]), np.array([x for f in faces for x in f]))
    if form == "array" and len({len(x) for x in faces}) == 1:
        return np.array(faces)
    return faces


@settings(FUZZ, max_examples=FUZZ.max_examples // 2)
@given(name=st.sampled_from(sorted(BASES)), edits=st.lists(IN_RANGE, min_size=0, max_size=4),
       form=st.sampled_from(["array", "polygons", "lists"]))
def test_repair_of_corrupted_polygon_meshes(name, edits, form):
    v, f = BASES[name]
    bad = corrupt(v, f, edits, polygons=True)
    assume(len(bad) > 0)
    faces = as_form(bad, form)
    try:
        r = sorpia.repair(v, faces)
    except sorpia.MeshError as e:  # the refusal for faces in range: nothing left
        assert all(len(without_repeats(t)) < 3 or len(set(without_repeats(t))) < len(without_repeats(t))
                   for t in bad)
        assert "no face is left" in str(e)
        return
    check_repaired(v, bad, r)
    if isinstance(faces, sorpia.Polygons) or len({len(t) for t in bad}) > 1:
        assert isinstance(r.faces, sorpia.Polygons)
    else:  # an (m, k) array, or lists of k, stays an array unless a face got shorter
        assert isinstance(r.faces, np.ndarray) != bool(r.changes["collapsed_faces"])
    if not mesh_problems(bad, len(v)):  # a valid mesh comes back as it is
        assert not any(r.changes["counts"].values()) and r.vertices is v


# ---- real polygon meshes ----------------------------------------------------

POLYGON_FILES = sorted(SHARED.glob("osd_catmark_*.obj")) + sorted(SHARED.glob("igl_*")) if SHARED.is_dir() else []


@pytest.mark.skipif(not POLYGON_FILES, reason="../shared/meshes absent")
@pytest.mark.parametrize("path", POLYGON_FILES, ids=lambda p: p.name)
def test_real_polygon_meshes_repair_to_valid_meshes(path):
    v, f = sorpia.read_mesh(path)
    r = sorpia.repair(v, f)
    check_repaired(v, f, r)
    assert set(r.changes) == set(REPORT_KINDS) | {"counts"}


# ---- sharpness tags ---------------------------------------------------------

def test_tags_follow_the_repair():
    """Two cubes welded along an edge (four sheets) with a crease on that edge, a corner at one of its
    ends and a hole: on the repaired mesh the crease is on every output edge whose ends copy the
    crease's vertices, the corner on the vertex and its copy, the hole on the output face of its face."""
    (v0, f0), (v1, f1) = cube(), cube(1)
    f = np.vstack([f0, f1])
    f[f == 8], f[f == 9] = 2, 3
    v = np.vstack([v0, v1])
    f = np.vstack([f[:1], f[:1], f[1:]])  # face 0 twice: the duplicate (input face 1) is removed
    r = sorpia.repair(v, f, creases=([[3, 2], [0, 1]], [10.0, 2.5]), corners=([2], 4.0), holes=[1, 5])
    assert set(r.tags) == {"creases", "corners", "holes"}
    out = face_lists(r.faces)
    output_edges = {tuple(sorted((a, b))) for q in out for a, b in zip(q, q[1:] + q[:1])}
    edges, sharpness = r.tags["creases"]
    for wanted, s in (((2, 3), 10.0), ((0, 1), 2.5)):  # brute force over the output edges
        copies = {e for e in output_edges if tuple(sorted(r.vertex_map[list(e)])) == wanted}
        got = {tuple(sorted(e)) for e, t in zip(edges.tolist(), sharpness) if t == s}
        assert got == copies and copies
    assert len(edges) == 3  # (2, 3) twice (one copy per cube), (0, 1) once
    corners, corner_sharpness = r.tags["corners"]
    assert sorted(r.vertex_map[corners].tolist()) == [2, 2] and set(corner_sharpness) == {4.0}
    assert r.changes["duplicate_faces"] == [1]
    assert r.tags["holes"].tolist() == [j for j, src in enumerate(r.face_map) if src == 5]
    assert sorpia.repair(v, f).tags == {}


def test_catmull_clark_fit_of_repaired_quads_passes_through_the_inputs():
    """Every defect at once on a quad torus; the Catmull-Clark limit surface of the interpolated repaired mesh
    passes through every referenced input vertex, at each of its copies."""
    v, f = quad_torus(8, 6)
    n = len(v)
    v = np.vstack([v, points(6, 3)])
    bad = np.vstack([f, f[:2], f[5:6, ::-1], [[f[6, 0], f[6, 0], f[6, 1], n]], [[f[10, 0], f[10, 1], n + 1, n + 2]],
                     [[f[20, 0], n + 3, n + 4, n + 5]]])
    bad[30:32] = bad[30:32][:, ::-1]
    r = sorpia.repair(v, bad)
    assert sum(r.changes["counts"].values()) > 0
    check_repaired(v, bad, r)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        fit = sorpia.interpolate(r.vertices, r.faces, scheme="catmull-clark")
        assert fit.converged
        limit = sorpia.limit_points(fit.control_vertices, r.faces, scheme="catmull-clark")
    used = np.unique(np.concatenate(face_lists(r.faces)))
    assert np.abs(limit[used] - v[r.vertex_map[used]]).max() <= 1e-8 * max(1.0, np.abs(v).max())
