"""sorpia.repair: each kind of defect built in code, and hypothesis properties
over random corruptions of valid meshes. Validity of a repaired mesh is
checked independently of sorpia by test_fuzz.mesh_problems (plain Python
dictionaries); the fit by limit positions of the interpolated control mesh."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import sorpia
from sorpia._repair import REPORT_KINDS
from test_fuzz import BASE_MESHES, CORRUPTIONS, FUZZ, corrupt, mesh_problems


def tetrahedron(offset=0):
    return np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]) + offset


def moebius(n):
    """A band of n quads (two triangles each) closed with a half twist: not orientable (2 n vertices)."""
    f = []
    for i in range(n):
        a0, a1 = 2 * i, 2 * i + 1
        b0, b1 = (2 * i + 2, 2 * i + 3) if i + 1 < n else (1, 0)
        f += [[a0, b0, b1], [a0, b1, a1]]
    return np.array(f)


def points(n, seed=0):
    return np.random.default_rng(seed).normal(size=(n, 3))


def check_repaired(v, f, result):
    """What every repair holds, checked without sorpia's validation."""
    v = np.asarray(v, float)
    assert mesh_problems(result.faces, len(result.vertices)) == set()
    n = len(v)
    assert np.array_equal(result.vertex_map[:n], np.arange(n))
    # every output vertex is its input vertex, bit for bit
    assert np.array_equal(result.vertices.view(np.uint64), v[result.vertex_map].view(np.uint64))
    # every output face is its input face renumbered (reversed if flipped)
    flipped = set(result.changes["flipped_faces"])
    for j, src in enumerate(result.face_map):
        mapped = list(result.vertex_map[result.faces[j]])
        want = list(np.asarray(f)[src])
        if src in flipped:
            want = want[::-1]
        assert any(mapped == want[k:] + want[:k] for k in range(3)), (j, src)
    # every vertex a kept face used is still used (by itself or a copy)
    kept_used = set(np.asarray(f)[result.face_map].ravel())
    assert kept_used <= set(result.vertex_map[np.unique(result.faces)])
    json.dumps(result.changes)  # JSON-able
    # idempotent: the output is valid, and comes back as it is
    again = sorpia.repair(result.vertices, result.faces)
    assert again.vertices is result.vertices and again.faces is result.faces
    assert not any(again.changes["counts"].values())


def test_valid_mesh_comes_back_unchanged_without_a_copy():
    v, f = sorpia.shapes.icosphere(2)
    v, f = np.ascontiguousarray(v, float), np.ascontiguousarray(f, np.int32)
    r = sorpia.repair(v, f)
    assert r.vertices is v and r.faces is f
    assert np.array_equal(r.vertex_map, np.arange(len(v))) and np.array_equal(r.face_map, np.arange(len(f)))
    assert r.changes["counts"] == {k: 0 for k in REPORT_KINDS}


def test_open_bowtie():
    f = np.array([[0, 1, 2], [0, 3, 4]])
    r = sorpia.repair(points(5), f)
    assert r.changes["bowtie_vertices"] == [0] and r.changes["bowtie_copies"] == [1]
    assert r.faces.tolist() == [[0, 1, 2], [5, 3, 4]] and r.vertex_map.tolist() == [0, 1, 2, 3, 4, 0]
    check_repaired(points(5), f, r)


def test_closed_bowtie_of_two_cones():
    f = np.vstack([tetrahedron(), tetrahedron(4)])
    f[f == 7] = 0  # two closed tetrahedra, (0, 1, 2, 3) and (4, 5, 6, 0), touching at vertex 0
    r = sorpia.repair(points(7), f)
    assert r.changes["bowtie_vertices"] == [0] and r.changes["counts"]["bowtie_copies"] == 1
    assert r.changes["counts"]["flipped_faces"] == 0
    check_repaired(points(7), f, r)


@pytest.mark.parametrize("n_sheets", [3, 4])
def test_sheets_on_one_edge(n_sheets):
    # n_sheets triangles on edge (0, 1), alternating in direction: paired into sheets of two in face
    # order, a third one left alone; each sheet after the first gets its own copies of 0 and 1
    f = [[0, 1, 2 + k] if k % 2 == 0 else [1, 0, 2 + k] for k in range(n_sheets)]
    r = sorpia.repair(points(2 + n_sheets), f)
    assert r.changes["nonmanifold_edges"] == [[0, 1]]
    assert r.changes["sheet_vertices"] == [0, 1]
    assert r.changes["sheet_copies"] == [(n_sheets - 1) // 2] * 2
    check_repaired(points(2 + n_sheets), f, r)


def test_duplicate_reversed_duplicate_and_degenerate_faces():
    v, f = sorpia.shapes.icosphere(1)
    bad = np.vstack([f, f[[5]][:, [1, 2, 0]], f[[9]][:, ::-1], [[3, 3, 7]]])
    r = sorpia.repair(v, bad)
    n = len(f)
    assert (r.changes["duplicate_faces"], r.changes["reversed_duplicate_faces"]) == ([n], [n + 1])
    assert r.changes["degenerate_faces"] == [n + 2]
    assert np.array_equal(r.faces, f) and np.array_equal(r.face_map, np.arange(n))
    check_repaired(v, bad, r)


def test_mixed_orientation_flips_the_fewer_faces():
    v, f = sorpia.shapes.icosphere(2)
    bad = np.array(f)
    bad[[4, 70, 71]] = bad[[4, 70, 71]][:, [0, 2, 1]]  # reversed as repair reverses: the second and third corners swapped
    r = sorpia.repair(v, bad)
    assert r.changes["flipped_faces"] == [4, 70, 71]
    assert np.array_equal(r.faces, f)
    check_repaired(v, bad, r)


def test_moebius_strip_is_cut_along_one_edge():
    # every vertex of a band one quad wide is on its boundary: one edge across it, its two ends split, makes
    # a strip that can be oriented
    v, f = points(16), moebius(8)
    r = sorpia.repair(v, f)
    assert len(r.changes["cut_edges"]) == 1
    assert r.changes["cut_vertices"] == r.changes["cut_edges"][0] and r.changes["cut_copies"] == [1, 1]
    assert len(r.vertices) == 18 and r.changes["counts"]["nonmanifold_edges"] == 0
    check_repaired(v, f, r)
    fit_passes_through_inputs(v, r)


def test_out_of_range_is_refused_as_everywhere():
    with pytest.raises(sorpia.MeshError, match="out of range"):
        sorpia.repair(points(3), [[0, 1, 3]])


def fit_passes_through_inputs(v, result):
    """The limit surface of the interpolated repaired mesh passes through every
    referenced input vertex, at each of its copies."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        fit = sorpia.interpolate(result.vertices, result.faces)
        assert fit.converged
        limit = sorpia.limit_points(fit.control_vertices, result.faces)
    used = np.unique(result.faces)
    scale = max(1.0, np.abs(v).max())
    assert np.abs(limit[used] - np.asarray(v, float)[result.vertex_map[used]]).max() <= 1e-8 * scale


def defect_mesh():
    """A closed irregular mesh with every kind of defect added: 3 exact and 1
    reversed duplicate face, a degenerate face, a third face on an edge, two
    triangles hung on a vertex (bowties), 3 faces reversed. (vertices, faces)."""
    v, f = sorpia.shapes.irregular(400, seed=3)
    v, f = np.asarray(v), np.asarray(f)
    n = len(v)
    v = np.vstack([v, points(6, 1)])
    bad = np.vstack([f, f[:3], f[5:6, ::-1], [[f[6, 0], f[6, 0], f[6, 1]]], [[f[10, 0], f[10, 1], n]],
                     [[f[20, 0], n + 1, n + 2]], [[f[30, 0], n + 3, n + 4]]])
    bad[40:43] = bad[40:43][:, ::-1]
    return v, bad


def test_fit_of_repaired_defects_passes_through_the_inputs():
    v, bad = defect_mesh()
    r = sorpia.repair(v, bad)
    assert sum(r.changes["counts"].values()) > 0
    check_repaired(v, bad, r)
    fit_passes_through_inputs(v, r)


IN_RANGE = CORRUPTIONS.filter(lambda e: e[0] != "set")


def repair_corrupted(name, edits):
    """(input vertices, corrupted faces, repair result or None where repair refused them). The
    refusal for faces in range: nothing left."""
    v, f = BASE_MESHES[name]
    bad = corrupt(v, f, edits)
    assume(len(bad) > 0)
    try:
        return v, bad, sorpia.repair(v, bad)
    except sorpia.MeshError as e:
        assert all(len(set(t)) < 3 for t in bad.tolist()) and "no face is left" in str(e)
        return v, bad, None


@settings(FUZZ, max_examples=FUZZ.max_examples // 2)
@given(name=st.sampled_from(sorted(BASE_MESHES)), edits=st.lists(IN_RANGE, min_size=0, max_size=4))
def test_repair_of_corrupted_meshes(name, edits):
    v, bad, r = repair_corrupted(name, edits)
    if r is None:
        return
    check_repaired(v, bad, r)
    if not mesh_problems(bad, len(v)):  # a valid mesh comes back as it is
        assert not any(r.changes["counts"].values()) and r.vertices is v


@settings(FUZZ, max_examples=min(FUZZ.max_examples, 40))
@given(name=st.sampled_from(sorted(BASE_MESHES)), edits=st.lists(IN_RANGE, min_size=1, max_size=3))
def test_fit_of_repaired_corrupted_meshes_passes_through_the_inputs(name, edits):
    v, _, r = repair_corrupted(name, edits)
    assume(r is not None)
    fit_passes_through_inputs(v, r)
