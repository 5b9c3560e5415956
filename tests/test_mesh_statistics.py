"""sorpia's mesh statistics (the core's counting, for `sorpia info` and the
fit report) against counts made here with numpy and scipy from the face
array alone; the raw-face-list counts equal the topology's on valid meshes."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.csgraph

import sorpia
from sorpia import _core
from sorpia.limit import topology

from conftest import MESHES


def two_pieces():
    """An icosphere and a grid side by side, and two vertices no face uses."""
    V1, F1 = sorpia.shapes.icosphere(1)
    V2, F2 = sorpia.shapes.grid(5, 4)
    V = np.vstack([V1, np.asarray(V2) + 3.0, [[9.0, 9, 9], [8.0, 8, 8]]])
    return V, np.vstack([F1, np.asarray(F2) + len(V1)])


def grid_with_holes():
    """A grid with two square holes (the faces with all corners in a box of 3 x 3
    vertices): three boundary loops, genus 0."""
    V, F = sorpia.shapes.grid(12, 10)
    V, F = np.asarray(V), np.asarray(F)
    xs, ys = np.unique(V[:, 0]), np.unique(V[:, 1])

    def in_box(i, j):
        return ((V[:, 0] >= xs[i]) & (V[:, 0] <= xs[i + 2]) & (V[:, 1] >= ys[j]) & (V[:, 1] <= ys[j + 2]))[F].all(axis=1)

    hole = in_box(2, 3) | in_box(7, 4)
    used = np.unique(F[~hole])
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    return np.asarray(V)[used], remap[F[~hole]]


CASES = {**MESHES, "two-pieces": two_pieces, "grid-with-holes": grid_with_holes}
GENUS = {"sphere-hull": 0, "icosphere": 0, "irregular-torus": 1, "grid-boundary": 0, "pole-48": 0, "two-pieces": 0,
         "grid-with-holes": 0}


def independent(F, n):
    """Counts from the face array with numpy and scipy."""
    F = np.asarray(F, dtype=np.int64)
    half = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    edges, counts = np.unique(np.sort(half, axis=1), axis=0, return_counts=True)
    valence = np.bincount(edges.ravel(), minlength=n)
    referenced = np.bincount(F.ravel(), minlength=n) > 0
    on_boundary = np.zeros(n, bool)
    bnd = edges[counts == 1]
    on_boundary[bnd.ravel()] = True

    def pieces(pairs, nodes):
        graph = scipy.sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
        _, labels = scipy.sparse.csgraph.connected_components(graph, directed=False)
        return len(np.unique(labels[nodes]))

    extraordinary = referenced & np.where(on_boundary, valence != 4, valence != 6)
    return {
        "edges": len(edges), "boundary_edges": int((counts == 1).sum()),
        "components": pieces(edges, referenced),
        "boundary_loops": pieces(bnd, on_boundary) if len(bnd) else 0,  # one loop per piece on a manifold
        "unreferenced_vertices": int(n - referenced.sum()),
        "euler_characteristic": int(referenced.sum() - len(edges) + len(F)),
        "valence_min": int(valence[referenced].min()), "valence_max": int(valence[referenced].max()),
        "extraordinary": np.flatnonzero(extraordinary), "valence": valence, "on_boundary": on_boundary,
        "interior": np.bincount(valence[referenced & ~on_boundary]),
        "boundary": np.bincount(valence[referenced & on_boundary]),
    }


@pytest.mark.parametrize("name", sorted(CASES))
def test_statistics_match_counts_from_the_faces(name):
    V, F = CASES[name]()
    n = len(V)
    topo = topology(F, n, warn=False)
    stats = _core.mesh_statistics(topo)
    ref = independent(F, n)
    for key in ("edges", "boundary_edges", "components", "boundary_loops", "unreferenced_vertices",
                "euler_characteristic", "valence_min", "valence_max"):
        assert stats[key] == ref[key], key
    np.testing.assert_array_equal(np.trim_zeros(np.asarray(stats["interior_valences"]), "b"),
                                  np.trim_zeros(ref["interior"], "b"))
    np.testing.assert_array_equal(np.trim_zeros(np.asarray(stats["boundary_valences"]), "b"),
                                  np.trim_zeros(ref["boundary"], "b"))
    index, valence, on_boundary = stats["extraordinary"]
    np.testing.assert_array_equal(index, ref["extraordinary"])
    np.testing.assert_array_equal(valence, ref["valence"][index])
    np.testing.assert_array_equal(on_boundary, ref["on_boundary"][index])
    assert stats["genus"] == GENUS[name]
    # The raw face list, counted without the topology, gives the same numbers (and no genus).
    raw = _core.face_list_statistics(np.ascontiguousarray(F, dtype=np.int32), n)
    assert raw.pop("genus") is None
    stats.pop("genus")
    for key, value in stats.items():
        if key == "extraordinary":
            for a, b in zip(value, raw[key]):
                np.testing.assert_array_equal(a, b)
        else:
            assert raw[key] == value, key


@pytest.mark.parametrize("faces, loops", [
    # An edge (0, 1) of three faces: no fan to follow there, so the boundary is counted in pieces.
    ([[0, 1, 2], [1, 0, 3], [0, 1, 4]], 1),
    # Two triangles sharing vertex 0 only: two loops touching there.
    ([[0, 1, 2], [0, 3, 4]], 2),
    # A face with a repeated vertex makes no edge of its own: the edges of (0, 1, 2) only.
    ([[0, 1, 2], [0, 0, 1]], 1),
], ids=["edge-of-three-faces", "bowtie", "repeated-vertex"])
def test_raw_face_lists_that_fail_validation_are_still_counted(faces, loops):
    F = np.asarray(faces, dtype=np.int32)
    n = int(F.max()) + 1
    stats = _core.face_list_statistics(F, n)
    proper = F[[len(set(f)) == 3 for f in faces]]
    ref = independent(proper, n)
    assert (stats["edges"], stats["boundary_edges"]) == (ref["edges"], ref["boundary_edges"])
    assert stats["boundary_loops"] == loops and stats["genus"] is None


def test_no_counts_without_faces_or_with_an_index_out_of_range():
    assert _core.face_list_statistics(np.zeros((0, 3), np.int32), 4) is None
    assert _core.face_list_statistics(np.array([[0, 1, 5]], np.int32), 4) is None


def _numpy_counts(V, faces):
    """Vertices, edges, faces and the Euler characteristic of a closed polygon mesh from its face list alone."""
    edges = {tuple(sorted((f[j], f[(j + 1) % len(f)]))) for f in faces for j in range(len(f))}
    return len(V), len(edges), len(faces), len(V) - len(edges) + len(faces)


@pytest.mark.parametrize("shape", ["icosphere", "quad_torus"])
def test_public_mesh_statistics_count_as_numpy_does(shape):
    # sorpia.mesh_statistics (the Python API of `sorpia info`'s counts) against counts from the face list, and the
    # scheme "auto" picks the regular valences of the scheme the faces call for (Loop for triangles, else
    # Catmull-Clark).
    V, F = sorpia.shapes.icosphere(2) if shape == "icosphere" else sorpia.shapes.quad_torus()
    faces = [list(map(int, f)) for f in np.asarray(F)]
    n, e, f, chi = _numpy_counts(np.asarray(V), faces)
    s = sorpia.mesh_statistics(V, F)
    assert (s["vertices"], s["edges"], s["faces"], s["euler_characteristic"]) == (n, e, f, chi)
    assert s["genus"] == (2 - chi) // 2 and "refused" not in s
    assert s["regular_valence"] == ([6, 4] if shape == "icosphere" else [4, 3])
    valences = np.bincount(np.array([v for fc in faces for v in fc]), minlength=n)  # faces per vertex = valence
    assert (s["valence_min"], s["valence_max"]) == (valences.min(), valences.max())


def test_public_mesh_statistics_of_a_refused_mesh_say_why():
    # A bowtie (two triangles sharing one vertex only) is refused by validation: counted from its face list, genus
    # unknown, and the reason given.
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]], float)
    F = np.array([[0, 1, 2], [0, 3, 4]])
    s = sorpia.mesh_statistics(V, F)
    assert s["faces"] == 2 and s["genus"] is None
    assert "refused" in s and "vertex 0" in s["refused"]


def test_the_diagonal_of_huge_coordinates_is_finite():
    # Coordinates of 1e155 square past the largest double; the diagonal (and fit's figures relative to it) must
    # still be the bounding box's: sqrt(3) * 2e155 for the cube [-1e155, 1e155]^3 of an icosphere's extremes,
    # compared with the same mesh at scale 1 (relative 1e-15: rounding of a scaled norm).
    V, F = sorpia.shapes.icosphere(1)
    small = sorpia.mesh_statistics(V, F)["diagonal"]
    huge = sorpia.mesh_statistics(np.asarray(V) * 1e155, F)["diagonal"]
    assert np.isfinite(huge) and huge == pytest.approx(small * 1e155, rel=1e-15)
