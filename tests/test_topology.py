"""The one-ring sorpia::Topology builds, checked against the face list alone and
against OpenMesh's half-edge mesh (the test-only reference)."""

from __future__ import annotations

import numpy as np
import pytest

import sorpia
from sorpia import _core
from sorpia._validate import as_rules

from conftest import MESHES, reference_one_ring


def scrambled(vertices, faces, seed):
    """Faces shuffled and each rotated at random: the same surface."""
    rng = np.random.default_rng(seed)
    f = np.asarray(faces)[rng.permutation(len(faces))]
    shift = rng.integers(0, 3, len(f))
    return vertices, np.stack([np.roll(row, s) for row, s in zip(f, shift)])


CASES = {**MESHES, "grid-scrambled": lambda: scrambled(*sorpia.shapes.grid(7, 6), seed=1),
         "irregular-scrambled": lambda: scrambled(*sorpia.shapes.irregular(400, seed=3), seed=2)}


@pytest.mark.parametrize("name", sorted(CASES))
def test_ring_is_the_clockwise_fan_of_each_vertex(name):
    V, F = CASES[name]()
    F = np.asarray(F, dtype=np.int32)
    topo = _core.Topology(np.ascontiguousarray(F), len(V))
    offsets, ring, on_boundary = topo.ring_offsets, topo.ring_neighbors, topo.is_boundary
    # Independent: each face (a, b, c) gives vertex a the clockwise step c -> b.
    steps = {}
    edge_use = {}
    for a, b, c in F.tolist():
        for v, nxt, prv in ((a, b, c), (b, c, a), (c, a, b)):
            steps.setdefault(v, set()).add((prv, nxt))
            key = (min(v, nxt), max(v, nxt))
            edge_use[key] = edge_use.get(key, 0) + 1
    boundary_nbrs = {}
    for (u, w), k in edge_use.items():
        if k == 1:
            boundary_nbrs.setdefault(u, set()).add(w)
            boundary_nbrs.setdefault(w, set()).add(u)
    for v in range(len(V)):
        r = ring[offsets[v]:offsets[v + 1]].tolist()
        assert bool(on_boundary[v]) == (v in boundary_nbrs), f"vertex {v}"
        if on_boundary[v]:
            assert {r[0], r[-1]} == boundary_nbrs[v], f"vertex {v}: ring {r} must run boundary to boundary"
            pairs = set(zip(r[:-1], r[1:]))
        else:
            pairs = set(zip(r, r[1:] + r[:1]))
        assert pairs == steps[v], f"vertex {v}: ring {r} is not the clockwise fan"


POLYGON_CASES = {"quad-torus": lambda: sorpia.shapes.quad_torus(6, 5),
                 "quad-grid": lambda: sorpia.shapes.quad_grid(5, 4),
                 "polygon-torus": lambda: sorpia.shapes.polygon_torus(10, 8, seed=2)}


@pytest.mark.parametrize("name", sorted(CASES) + sorted(POLYGON_CASES))
def test_one_ring_is_openmeshs(name):
    """Every array of the one-ring equals the one from OpenMesh's half-edge mesh and its circulators (an
    independent build: add_face per face), exactly: they are integer arrays in the same documented order."""
    V, F = (CASES if name in CASES else POLYGON_CASES)[name]()
    arrays, n, _ = as_rules(F, len(V), scheme="catmull-clark" if name in POLYGON_CASES else "loop",
                            boundary="edge-and-corner")
    counts, indices = (np.full(len(arrays[0]), 3, np.int32), arrays[0].ravel()) if len(arrays) == 1 else arrays
    topo = _core.Topology(*arrays, n)
    ref = reference_one_ring(counts, indices, n)
    for key in ("ring_offsets", "ring_neighbors", "is_boundary", "vertex_face_offsets", "vertex_faces",
                "face_ring_offsets", "face_ring_neighbors"):
        assert np.array_equal(np.asarray(getattr(topo, key)), ref[key]), key
    assert (topo.n_edges, topo.n_boundary_edges, topo.n_unreferenced) == (
        ref["n_edges"], ref["n_boundary_edges"], ref["n_unreferenced"])
