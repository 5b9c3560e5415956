"""``nonmanifold="sharp"``: OpenSubdiv's own rules for non-manifold topology.

OpenSubdiv takes a non-manifold mesh as it is (Far's TopologyRefinerFactory):
an edge of three or more faces, or whose two faces run it the same way, is
made infinitely sharp; a vertex on such an edge, or whose faces form several
fans, becomes an infinitely sharp corner, except on an interior non-manifold
crease (two non-manifold edges, no boundary edge, more faces than edges),
where it gets the crease rule along those two edges. OpenSubdiv's
documentation calls the result of non-manifold topology undefined for now:
`NonmanifoldWarning` says so whenever a mesh is non-manifold.

sorpia computes exactly those rows through a manifold split
(sorpia::split_nonmanifold): the faces cut apart at the non-manifold edges and
vertices, one vertex per fan (copies of the input vertices), with an
infinitely sharp corner on every copy of each corner vertex; the copies of a
crease vertex lie on boundaries of the split whose boundary rule is the
crease rule (where such a copy has one face, which "edge-and-corner" would
make a corner, the split is solved under "edge-only" with that rule's
corners as tags). Where two faces of a non-manifold edge meet again in the
split (a pillow, two faces with the same vertices in the opposite order,
beside a third face on one of its edges: the pillow's faces stay joined at
both ends of that edge), that edge of the split gets an infinitely sharp
crease, as OpenSubdiv makes it. The limit rows of the split, their columns mapped back through
the vertex map, are OpenSubdiv's rows of the input mesh (to rounding, tested
against Far's Limit() on the whole mesh). Faces that repeat a vertex, to
which OpenSubdiv gives degenerate edges, are refused: `sorpia.repair` drops
the repeat.
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

from . import _core, _scipy
from ._meshdata import merge_sharpness
from ._remap import core_faces, faces_as_given, mapped_tags
from ._validate import DEFAULT_BOUNDARY, as_boundary, as_tags
from .errors import MeshError, NonmanifoldWarning


# Appended to the messages that refuse non-manifold topology.
REPAIR_HINT = "sorpia.repair (command line: --repair) makes the mesh manifold by splitting it"
NONMANIFOLD_HINT = (REPAIR_HINT + ", or nonmanifold=\"sharp\" (--nonmanifold sharp) keeps it with OpenSubdiv's "
                    "rules for it (non-manifold edges infinitely sharp, non-manifold vertices corners)")


# The refusals of sorpia::Topology that OpenSubdiv takes as non-manifold topology.
NONMANIFOLD_KINDS = ("non-manifold edge", "non-manifold vertex", "inconsistent orientation", "duplicate faces")


def refusal_hint(message: str) -> str | None:
    """The ways out to append to a refusal of sorpia::Topology (`message`),
    or None where it is not about topology repair or OpenSubdiv's
    non-manifold rules change. (Two faces with the same vertices in the
    opposite order are refused only beside a third face on one of their
    edges, which is non-manifold; alone they are a valid closed 'pillow'.)"""
    return NONMANIFOLD_HINT if any(kind in message for kind in NONMANIFOLD_KINDS) else None


def manifold_only(exc: MeshError, what: str) -> MeshError:
    """`exc` for a caller that has no nonmanifold="sharp" (`what`, e.g. "fair
    interpolation"): the refusal's hint offers the repair alone."""
    return MeshError(str(exc).replace(NONMANIFOLD_HINT, f"{REPAIR_HINT}; {what} takes manifold meshes only"))


class Split(NamedTuple):
    """A non-manifold mesh as its manifold split (see the module docstring)."""

    faces: object  # as the faces were given: (m, k) array or sorpia.Polygons
    vertex_map: np.ndarray  # for every vertex of the split, the input vertex it copies
    tags: dict  # the split's tags: the caller's, carried over, the corners and the creases of sharp_edges
    report: dict  # nonmanifold_edges, nonmanifold_vertices, corners, single_face_sheets (input indices); sharp_edges
    # (the split's indices: its edges whose two faces border a non-manifold edge, infinitely sharp creases in tags)
    boundary: str = DEFAULT_BOUNDARY  # the boundary rule the split is solved under (see split)


def split(faces, n_vertices: int, boundary: str = DEFAULT_BOUNDARY, *, creases=None, corners=None,
          holes=None, stacklevel: int = 4) -> Split | None:
    """The manifold split of `faces` with OpenSubdiv's rules as tags, or None
    for a manifold mesh (nothing to split). Warns NonmanifoldWarning
    otherwise.

    The split is solved under `boundary`, except where a crease vertex has a
    copy in a sheet of one face and the rule is "edge-and-corner", which
    would make that copy a corner: there it is solved under "edge-only" with
    the corners "edge-and-corner" makes (every other vertex of one face) as
    infinitely sharp corner tags, the same rows (OpenSubdiv sharpens such
    vertices whatever their tags). `Split.boundary` is the rule to solve it
    under.

    Raises MeshError for what the split cannot reproduce: a face that repeats
    a vertex; a crease vertex whose fans do not all lie between its two
    non-manifold edges; a caller's crease at a crease vertex (OpenSubdiv
    counts it with the creases of every sheet).
    """
    rows, triangles, polygons = core_faces(faces, n_vertices)
    if triangles is not None:
        found = _core.split_nonmanifold(triangles, n_vertices)
        if found is None:
            return None
        split_faces, vertex_map, report = found
        split_indices = split_faces.ravel()
    else:
        found = _core.split_nonmanifold_polygons(*polygons, n_vertices)
        if found is None:
            return None
        counts, split_indices, vertex_map, report = found
        split_faces = faces_as_given(rows, counts, split_indices)
    warnings.warn(f"nonmanifold=\"sharp\": {len(report['nonmanifold_edges'])} non-manifold edges and "
                  f"{len(report['nonmanifold_vertices'])} non-manifold vertices kept with OpenSubdiv's rules, "
                  "whose result OpenSubdiv's documentation calls undefined for now", NonmanifoldWarning,
                  stacklevel=stacklevel)
    crease_vertices = sorted(set(report["nonmanifold_vertices"]) - set(report["corners"]))
    corner_vertices = report["corners"]
    if report["single_face_sheets"] and as_boundary(boundary) == _core.Boundary.edge_and_corner:
        boundary = "edge-only"
        one_face = np.bincount(split_indices, minlength=len(vertex_map)) == 1
        corner_vertices = np.union1d(corner_vertices, vertex_map[one_face & ~np.isin(vertex_map, crease_vertices)])

    n_faces = len(polygons[0]) if triangles is None else len(triangles)
    given = {kind for kind, value in (("creases", creases), ("corners", corners), ("holes", holes))
             if value is not None}
    tags = {}
    if given:
        checked = as_tags(creases, corners, holes, n_vertices=n_vertices, n_faces=n_faces)
        at_crease = np.isin(checked.crease_vertices, crease_vertices).any(axis=1)
        if at_crease.any():
            a, b = checked.crease_vertices[np.flatnonzero(at_crease)[0]]
            raise MeshError(f"creases: edge ({a}, {b}) ends at a vertex on an interior non-manifold crease, whose "
                            "rule OpenSubdiv takes from the creases of all its sheets at once: nonmanifold=\"sharp\" "
                            "cannot reproduce it; repair the mesh or leave that crease out")
        tags = mapped_tags(checked, split_faces, vertex_map, np.arange(n_faces, dtype=np.int32), n_vertices, given)
    copies = np.flatnonzero(np.isin(vertex_map, corner_vertices)).astype(np.int32)
    # ours last: a corner or edge given twice counts with its last sharpness (OpenSubdiv's rule, merge_sharpness)
    tags["corners"] = merge_sharpness(tags.get("corners"), (copies, _core.INFINITE_SHARPNESS), width=1)
    sharp = np.asarray(report["sharp_edges"], dtype=np.int32).reshape(-1, 2)
    if len(sharp):  # faces of a non-manifold edge joined again in the split (a pillow beside a third face)
        tags["creases"] = merge_sharpness(tags.get("creases"), (sharp, _core.INFINITE_SHARPNESS))
    return Split(split_faces, vertex_map, tags, report, boundary)


def _columns_to_input(vertex_map: np.ndarray, n: int):
    """The (len(vertex_map), n) 0/1 matrix that adds each copy's column to its input vertex's."""
    sparse = _scipy.sparse("the limit matrix of a non-manifold mesh")
    k = len(vertex_map)
    return sparse.csr_matrix((np.ones(k), (np.arange(k), vertex_map)), shape=(k, n))


def folded(b, vertex_map: np.ndarray, n: int):
    """The split's B as the input mesh's: the rows of the input vertices,
    each copy's column added to its input vertex's."""
    return (b[:n] @ _columns_to_input(vertex_map, n)).tocsr()
