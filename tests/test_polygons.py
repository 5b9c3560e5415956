"""Polygon faces: the one validation (_validate.as_polygons) for every form
faces come in, the polygon topology against the face list, and Loop's
refusal of non-triangles."""

from __future__ import annotations

import numpy as np
import pytest

import sorpia
from sorpia import _validate
from sorpia.limit import topology


def forms(faces):
    """The same polygons as an (m, k) array (when uniform), a ragged list and sorpia.Polygons."""
    rows = [list(map(int, r)) for r in faces]
    counts = np.array([len(r) for r in rows])
    out = {"list": rows, "polygons": sorpia.Polygons(counts, np.concatenate(rows))}
    if len(set(counts.tolist())) == 1:
        out["array"] = np.array(rows, dtype=np.int64)
    return out


def rows_of(polygons):
    counts, indices = polygons
    offsets = np.concatenate([[0], np.cumsum(counts)])
    return [indices[offsets[f]:offsets[f + 1]].tolist() for f in range(len(counts))]


@pytest.mark.parametrize("shape", ["quad_torus", "quad_grid", "polygon_torus"])
def test_every_form_gives_the_same_counts_and_indices(shape):
    V, F = getattr(sorpia.shapes, shape)(6, 5)
    rows = rows_of(F) if isinstance(F, sorpia.Polygons) else F.tolist()
    for name, faces in forms(rows).items():
        counts, indices = _validate.as_polygons(faces, len(V))
        assert counts.dtype == np.int32 and indices.dtype == np.int32, name
        assert rows_of((counts, indices)) == rows, name


BAD = [
    ("two-vertices", [[0, 1, 2, 3], [0, 1]], r"faces\[1\] has 2 vertices: a face needs at least 3"),
    ("array-two-columns", np.zeros((4, 2), int), r"faces has 2 vertices per face, shape \(4, 2\)"),
    ("out-of-range", [[0, 1, 2, 3], [3, 2, 4, 9]], r"faces\[1\] = \[3, 2, 4, 9\] has vertex index 9 out of range"),
    ("polygons-out-of-range", sorpia.Polygons([3, 4], [0, 1, 2, 2, 1, 7, 3]),
     r"faces\[1\] = \[2, 1, 7, 3\] has vertex index 7 out of range \[0, 5\)"),
    ("polygons-sum", sorpia.Polygons([3, 4], [0, 1, 2, 3]), r"face_vertex_counts sum to 7 but .* has 4 entries"),
    ("polygons-short", sorpia.Polygons([3, 2], [0, 1, 2, 3, 4]), r"faces\[1\] has 2 vertices"),
    ("empty", np.zeros((0, 4), int), r"faces is empty"),
]


@pytest.mark.parametrize("faces, match", [c[1:] for c in BAD], ids=[c[0] for c in BAD])
def test_bad_polygons_are_named(faces, match):
    with pytest.raises(sorpia.MeshError, match=match):
        _validate.as_polygons(faces, 5)


def test_float_polygons_are_a_type_error():
    with pytest.raises(TypeError, match="integer"):
        _validate.as_polygons(np.zeros((3, 4)), 5)
    with pytest.raises(TypeError, match="face_vertex_indices"):
        _validate.as_polygons(sorpia.Polygons([4], [0.0, 1.0, 2.0, 3.0]), 5)


@pytest.mark.parametrize("form", ["array", "list", "polygons"])
def test_loop_names_the_first_non_triangle_and_the_way_out(form):
    V, F = sorpia.shapes.quad_grid(4, 4)
    faces = forms(F.tolist())[form]
    with pytest.raises(sorpia.MeshError, match=r"faces.*4 vertices.*Loop subdivision needs triangles.*"
                                               r'scheme="catmull-clark"'):
        topology(faces, len(V), scheme="loop")


def test_repeated_vertex_in_a_polygon_is_named_by_the_core():
    with pytest.raises(sorpia.MeshError, match=r"face 1 \(2, 1, 4, 1\) repeats vertex 1"):
        topology([[0, 1, 2, 3], [2, 1, 4, 1]], 5, scheme="catmull-clark")


def test_face_ring_against_the_face_list():
    """Face j of vertex v lies between ring neighbours j and j + 1; its face
    neighbours are its other vertices in order."""
    V, F = sorpia.shapes.polygon_torus(9, 8, seed=4)
    topo = topology(F, len(V), scheme="catmull-clark")
    rows = rows_of(F)
    assert sorted(set(map(len, rows))) == [3, 4, 5, 6]
    ro, rn = topo.ring_offsets, topo.ring_neighbors
    vo, vf = topo.vertex_face_offsets, topo.vertex_faces
    fo, fn = topo.face_ring_offsets, topo.face_ring_neighbors
    for v in range(len(V)):
        ring = rn[ro[v]:ro[v + 1]].tolist()
        faces = vf[vo[v]:vo[v + 1]].tolist()
        assert sorted(faces) == sorted(f for f, r in enumerate(rows) if v in r)
        expected = []
        for j, f in enumerate(faces):
            r = rows[f]
            p = r.index(v)
            n = len(r)
            assert r[(p - 1) % n] == ring[j] and r[(p + 1) % n] == ring[(j + 1) % len(ring)]
            expected += [r[(p + s) % n] for s in range(2, n - 1)]
        assert fn[fo[v]:fo[v + 1]].tolist() == expected


def test_quad_irregular_has_the_advertised_valences():
    V, F = sorpia.shapes.quad_irregular(3000, seed=2)
    assert F.shape[1] == 4
    topo = topology(F, len(V), scheme="catmull-clark")
    valence = np.diff(topo.ring_offsets)
    assert topo.n_boundary_edges == 0 and topo.all_quads
    assert set(np.unique(valence)) <= set(range(3, 13)) and (valence == 3).any() and (valence >= 5).any()
    assert abs(len(V) - 3000) < 300


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_polygon_torus_has_no_vertex_of_valence_two(seed):
    """Interior vertices of valence 2 make Catmull-Clark's B indefinite; the generator never makes one."""
    V, F = sorpia.shapes.polygon_torus(40, 30, seed=seed)
    valence = np.diff(topology(F, len(V), scheme="catmull-clark").ring_offsets)
    assert valence.min() >= 3
    assert sorted(set(np.asarray(F.face_vertex_counts).tolist())) == [3, 4, 5, 6]

