"""The limit operator of Loop and Catmull-Clark surfaces: limit positions and the limit matrix B."""

from __future__ import annotations

import warnings
from typing import Optional

import numpy as np

from . import _core, _scipy
from ._mesh import mesh_arguments, mesh_count
from ._nonmanifold import folded, refusal_hint, split
from ._scipy import CSRMatrix
from ._validate import (DEFAULT_BOUNDARY, DEFAULT_NONMANIFOLD, DEFAULT_SCHEME, as_nonmanifold, as_rules, as_tags,
                        as_vertex_count, as_vertices)
from .errors import MeshError, UnreferencedVerticesWarning


def topology(faces, n_vertices: int, *, scheme: str = DEFAULT_SCHEME, warn: bool = True,
             count_name: str = "n_vertices") -> _core.Topology:
    """Validate `n_vertices` and `faces` and build the mesh connectivity (sorpia::Topology).

    Loop (``scheme="loop"``) takes triangles only (`as_faces`); Catmull-Clark
    any polygons (`as_polygons`: (m, k) arrays, lists of polygons,
    `sorpia.Polygons`); "auto" picks Loop when every face is a triangle.
    `count_name` names the vertex count in messages: "n_vertices" where the
    caller passed the count, "len(vertices)" where it is the rows of an array.
    Warns with UnreferencedVerticesWarning when some vertices belong to no face.
    """
    arrays, n_vertices, _ = as_rules(faces, n_vertices, scheme=scheme, boundary=DEFAULT_BOUNDARY,
                                     count_name=count_name)
    topo = built(lambda: _core.Topology(*arrays, n_vertices))
    if warn:
        warn_unreferenced(topo, stacklevel=4)
    return topo


def built(build):
    """build() (a core object made from faces), its refusal of non-manifold
    topology (MeshError) completed with the ways to keep or repair it."""
    try:
        return build()
    except MeshError as exc:
        hint = refusal_hint(str(exc))
        if hint is None:
            raise
        raise MeshError(f"{exc}; {hint}") from None


def warn_unreferenced(topo: _core.Topology, stacklevel: int) -> None:
    """UnreferencedVerticesWarning when some vertices of `topo` belong to no face."""
    if topo.n_unreferenced:
        warnings.warn(f"{topo.n_unreferenced} of {topo.n_vertices} vertices belong to no face; "
                      "they pass through unchanged (their limit is themselves)", UnreferencedVerticesWarning,
                      stacklevel=stacklevel)




def singular_cubes(topo: _core.Topology, tag_set: _core.Tags) -> list:
    """The parts of a Catmull-Clark mesh on which B is singular for a reason
    known in closed form: closed cubes (connected parts of 8 vertices, each
    interior, of valence 3, on quads) that no crease or corner touches. The
    alternating +1/-1 vector over a cube's corners (its two colours) is a null
    vector of their CATMARK limit masks, 3/8 - 3 (1/6) + 3 (1/24) = 0, so
    only targets without a component along it can be interpolated there.
    Returns the vertices of each such cube (sorted arrays)."""
    offsets, neighbours = np.asarray(topo.ring_offsets), np.asarray(topo.ring_neighbors)
    n = topo.n_vertices
    closed = (np.diff(offsets) == 3) & ~np.asarray(topo.is_boundary)
    closed[np.asarray(tag_set.crease_vertices, dtype=np.intp).ravel()] = False
    closed[np.asarray(tag_set.corner_vertices, dtype=np.intp)] = False
    # A cube's corners are closed: untagged interior vertices of valence 3
    # whose neighbours are closed too (peeled until that holds). Labels (the
    # smallest vertex index reachable) spread over a cube in 3 steps, its
    # diameter; a group of 8 sharing one label whose neighbours all carry it
    # is a whole connected part, a cube.
    ring = np.zeros((n, 3), dtype=np.int64)
    ring[closed] = neighbours[offsets[:-1][closed, None] + np.arange(3)]
    while True:
        keep = closed & closed[ring].all(axis=1)
        if (keep == closed).all():
            break
        closed = keep
    if closed.sum() < 8 or topo.all_triangles:
        return []
    label = np.arange(n)
    for _ in range(3):
        label = np.where(closed, np.minimum(label, label[ring].min(axis=1)), label)
    groups, size = np.unique(label[closed], return_counts=True)
    found = [g for g in groups[size == 8] if (label[ring[(label == g) & closed]] == g).all()]
    cubes = []
    counts, face_offsets, faces = (np.asarray(a) for a in (topo.face_counts, topo.vertex_face_offsets,
                                                            topo.vertex_faces))
    for g in found:
        vertices = np.flatnonzero((label == g) & closed)
        around = np.concatenate([faces[face_offsets[v]:face_offsets[v + 1]] for v in vertices])
        if np.all(counts[around] == 4):
            cubes.append(vertices)
    return cubes


def tags(topo: _core.Topology, creases=None, corners=None, holes=None) -> _core.Tags:
    """The sharpness tags of a mesh, checked against its counts (`_validate.as_tags`);
    whether each crease is an edge of the mesh is checked where B is built."""
    return as_tags(creases, corners, holes, n_vertices=topo.n_vertices, n_faces=topo.n_faces)


TAGS_DOC = """creases : (edges (k, 2) int, sharpness (k,) float or one float), optional
        OpenSubdiv's crease tags: each edge must be an edge of the mesh (a
        MeshError names the first that is not). Sharpness 0 is smooth, inf
        (or 10 and above) infinitely sharp, anything between semi-sharp (it
        decays by one per subdivision level). A crease given twice counts
        with its last sharpness, as in OpenSubdiv.
    corners : (vertex indices (c,) int, sharpness), optional
        OpenSubdiv's corner tags (vertex sharpness).
    holes : (h,) int, optional
        Faces cut out of the surface. They change no row of B: OpenSubdiv
        refines and limits the vertices around a hole as if the face were
        there."""


def limit_points(vertices, faces=None, *, scheme: str = DEFAULT_SCHEME, boundary: str = DEFAULT_BOUNDARY,
                 creases=None, corners=None, holes=None, nonmanifold: str = DEFAULT_NONMANIFOLD) -> np.ndarray:
    """Limit positions of the vertices of a mesh (paper eq. 5-6), B V.

    Parameters
    ----------
    vertices : array_like, (n, 3) or (n, k) float, or sorpia.SubdivisionMesh
        Control vertices, or any per-vertex data (k >= 1 columns, each
        mapped by B alike); or a mesh (its vertices, faces and rules:
        ``limit_points(mesh)``).
    faces : array_like (m, k) int, list of polygons, sorpia.Polygons or sorpia.SubdivisionMesh
        Faces, indices into ``vertices``, consistently oriented; triangles for
        Loop, any polygons for Catmull-Clark; or a mesh whose faces and rules
        take `vertices` (``limit_points(control_vertices, mesh)``).
    scheme : {"auto", "loop", "catmull-clark"}
        The subdivision scheme (OpenSubdiv's SCHEME_LOOP or SCHEME_CATMARK);
        "auto" (the default everywhere) is Loop when every face is a
        triangle, else Catmull-Clark (`sorpia.resolve_scheme`).
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule (OpenSubdiv's VTX_BOUNDARY_EDGE_AND_CORNER or
        VTX_BOUNDARY_EDGE_ONLY). With "edge-and-corner" (the default) a
        boundary vertex with a single face stays where it is; with "edge-only"
        it gets the boundary mask (1/6, 2/3, 1/6).
    {tags}
    {nonmanifold}

    Returns
    -------
    numpy.ndarray, (n, 3) or (n, k) float64
        B V, from OpenSubdiv's limit masks (``Sdc::Scheme::ComputeVertexLimitMask``,
        what ``Far::PrimvarRefinerReal<double>::Limit`` applies; equal to it to 1e-15).
        Loop, interior vertex of valence n: alpha_n v + (1 - alpha_n)/n sum of
        its neighbours, alpha_n = 3 / (8 - 8 (3/8 + cos(2 pi/n)/4)^2) (paper
        eq. 5). Catmull-Clark, interior vertex of valence n whose faces are
        quads: (n^2 v + 4 sum e_j + sum f_j) / (n (n + 5)), e_j its edge
        neighbours, f_j the opposite corners of its quads; an interior vertex
        of a non-quad face: its limit after one uniform refinement (OpenSubdiv
        evaluates limits on quads only), composed back onto its faces'
        vertices. Boundary vertex, both schemes: 2/3 v + 1/6 (its two boundary
        neighbours). Vertices no face references are returned unchanged (with
        a warning).
        With tags: infinitely sharp features keep this form (a vertex with
        two sharp edges gets 2/3 and 1/6 on their ends, with three or more
        or an infinitely sharp corner it keeps itself, with one it stays
        smooth); with semi-sharp tags B is OpenSubdiv's ``Limit()`` after
        refining until every sharpness has decayed, composed back to the
        control vertices (docs: "Creases, corners and holes").
    """
    vertices, faces, rules = mesh_arguments(vertices, faces, dict(
        scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes, nonmanifold=nonmanifold),
        "limit_points")
    scheme, boundary, creases, corners, holes = (rules[k] for k in ("scheme", "boundary", "creases", "corners",
                                                                    "holes"))
    vertices = as_vertices(vertices, columns=None)
    if as_nonmanifold(rules["nonmanifold"]) == "sharp":
        s = split(faces, len(vertices), boundary, creases=creases, corners=corners, holes=holes, stacklevel=3)
        if s is not None:  # the split's rows of the input vertices
            return limit_points(vertices[s.vertex_map], s.faces, boundary=s.boundary, scheme=scheme,
                                **s.tags)[: len(vertices)]
    arrays, n, rules = as_rules(faces, vertices.shape[0], scheme=scheme, boundary=boundary, creases=creases,
                                corners=corners, holes=holes, count_name="len(vertices)")
    topo = built(lambda: _core.Topology(*arrays, n))
    warn_unreferenced(topo, stacklevel=3)
    return _core.limit_points(topo, vertices, rules)


NONMANIFOLD_DOC = """nonmanifold : {"error", "sharp"}
        What non-manifold topology (edges of three or more faces, or run the
        same way by their two faces, and 'bowtie' vertices) gets: "error" (the
        default) refuses it, naming the first problem; "sharp" keeps it with
        OpenSubdiv's own rules for it, non-manifold edges infinitely sharp and
        non-manifold vertices corners (a vertex on an interior non-manifold
        crease gets the crease rule), with a `NonmanifoldWarning`: OpenSubdiv's
        documentation calls that result undefined (`sorpia._nonmanifold`)."""


limit_points.__doc__ = limit_points.__doc__.replace("{tags}", TAGS_DOC).replace("{nonmanifold}", NONMANIFOLD_DOC)


def limit_matrix(faces, n_vertices: Optional[int] = None, *, scheme: str = DEFAULT_SCHEME,
                 boundary: str = DEFAULT_BOUNDARY, creases=None, corners=None, holes=None,
                 nonmanifold: str = DEFAULT_NONMANIFOLD) -> CSRMatrix:
    """The limit matrix B (paper eq. 7) as a scipy CSR matrix, (n, n) float64.

    Row i holds the limit mask of vertex i as OpenSubdiv evaluates it, so that
    ``limit_matrix(F, len(V)) @ V == limit_points(V, F)``. Unreferenced vertices
    get an identity row. See `limit_points` for `scheme`, `boundary`, the
    tags (`creases`, `corners`, `holes`) and `nonmanifold`. ``limit_matrix(mesh)``
    takes a `sorpia.SubdivisionMesh`'s faces, vertex count and rules.
    """
    sparse = _scipy.sparse("sorpia.limit_matrix")

    faces, n_vertices, rules = mesh_count(faces, n_vertices, dict(
        scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes, nonmanifold=nonmanifold),
        "limit_matrix")
    scheme, boundary, creases, corners, holes = (rules[k] for k in ("scheme", "boundary", "creases", "corners",
                                                                    "holes"))
    if as_nonmanifold(rules["nonmanifold"]) == "sharp":
        s = split(faces, as_vertex_count(n_vertices), boundary, creases=creases, corners=corners, holes=holes,
                  stacklevel=3)
        if s is not None:  # the split's rows of the input vertices, each copy's column added to its vertex's
            return folded(limit_matrix(s.faces, len(s.vertex_map), boundary=s.boundary, scheme=scheme, **s.tags),
                          s.vertex_map, as_vertex_count(n_vertices))
    arrays, n, rules = as_rules(faces, n_vertices, scheme=scheme, boundary=boundary, creases=creases,
                                corners=corners, holes=holes)
    topo = built(lambda: _core.Topology(*arrays, n))
    warn_unreferenced(topo, stacklevel=3)
    data, indices, indptr = _core.limit_matrix(topo, rules)
    return sparse.csr_matrix((data, indices, indptr), shape=(n, n))
