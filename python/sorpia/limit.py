"""The Loop limit operator: limit positions and the limit matrix B."""

from __future__ import annotations

import warnings

import numpy as np

from . import _core
from ._validate import DEFAULT_BOUNDARY, DEFAULT_SCHEME, as_boundary, as_faces, as_polygons, as_scheme, as_vertex_count, as_vertices


class UnreferencedVerticesWarning(UserWarning):
    """Some vertices belong to no face; their limit is themselves."""


def topology(faces, n_vertices: int, *, scheme: str = DEFAULT_SCHEME, warn: bool = True,
             count_name: str = "n_vertices") -> _core.Topology:
    """Validate `n_vertices` and `faces` and build the mesh connectivity (sorpia::Topology).

    Loop (``scheme="loop"``) takes triangles only (`as_faces`); Catmull-Clark
    any polygons (`as_polygons`: (m, k) arrays, lists of polygons,
    `sorpia.Polygons`). `count_name` names the vertex count in messages:
    "n_vertices" where the caller passed the count, "len(vertices)" where it is
    the rows of an array. Warns with UnreferencedVerticesWarning when some
    vertices belong to no face.
    """
    n_vertices = as_vertex_count(n_vertices, count_name)
    if as_scheme(scheme) == _core.Scheme.loop:
        topo = _core.Topology(as_faces(faces, n_vertices, count_name=count_name), n_vertices)
    else:
        counts, indices = as_polygons(faces, n_vertices, count_name=count_name)
        topo = _core.Topology(counts, indices, n_vertices)
    if warn and topo.n_unreferenced:
        warnings.warn(
            f"{topo.n_unreferenced} of {n_vertices} vertices belong to no face; "
            "they pass through unchanged (their limit is themselves)",
            UnreferencedVerticesWarning,
            stacklevel=3,
        )
    return topo


def limit_points(vertices, faces, boundary: str = DEFAULT_BOUNDARY) -> np.ndarray:
    """Loop limit positions of the vertices of a triangle mesh (paper eq. 5-6).

    Parameters
    ----------
    vertices : array_like, (n, 3) float
        Control vertices.
    faces : array_like, (m, 3) int
        Triangles, indices into `vertices`, consistently oriented.
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule (OpenSubdiv's VTX_BOUNDARY_EDGE_AND_CORNER or
        VTX_BOUNDARY_EDGE_ONLY). With "edge-and-corner" (the default) a
        boundary vertex with a single face stays where it is; with "edge-only"
        it gets the boundary mask (1/6, 2/3, 1/6).

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        B V, from OpenSubdiv's Loop limit masks (``Sdc::Scheme::ComputeVertexLimitMask``,
        what ``Far::PrimvarRefinerReal<double>::Limit`` applies; equal to it to 1e-15).
        Interior vertex of valence n: alpha_n v + (1 - alpha_n)/n sum of its
        neighbours, alpha_n = 3 / (8 - 8 (3/8 + cos(2 pi/n)/4)^2) (paper eq. 5);
        boundary vertex: 2/3 v + 1/6 (its two boundary neighbours). Vertices no
        face references are returned unchanged (with a warning).
    """
    vertices = as_vertices(vertices)
    topo = topology(faces, vertices.shape[0], count_name="len(vertices)")
    return _core.limit_points(topo, vertices, as_boundary(boundary))


def limit_matrix(faces, n_vertices: int, boundary: str = DEFAULT_BOUNDARY) -> scipy.sparse.csr_matrix:
    """The Loop limit matrix B (paper eq. 7) as a scipy CSR matrix, (n, n) float64.

    Row i holds the limit mask of vertex i as OpenSubdiv evaluates it, so that
    ``limit_matrix(F, len(V)) @ V == limit_points(V, F)``. Unreferenced vertices
    get an identity row. See `limit_points` for `boundary`.
    """
    import scipy.sparse  # here, not at import: sorpia's commands need no scipy

    topo = topology(faces, n_vertices)  # validates n_vertices (as_vertex_count) and the faces
    n = topo.n_vertices
    data, indices, indptr = _core.limit_matrix(topo, as_boundary(boundary))
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=(n, n))
