"""Repair of triangle and polygon meshes that sorpia refuses (duplicate and
degenerate faces, bowtie vertices, edges of three or more faces, mixed
orientation)."""

from __future__ import annotations

import warnings
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from . import _core
from ._mesh import SubdivisionMesh, mesh_arguments
from ._remap import core_faces, faces_as_given, mapped_tags
from ._validate import Polygons, as_tags, as_vertices

# The report's keys, in the order the repair applies its rules (see `repair`).
REPORT_KINDS = ("degenerate_faces", "collapsed_faces", "duplicate_faces", "reversed_duplicate_faces", "nonmanifold_edges",
                "sheet_vertices", "sheet_copies", "bowtie_vertices", "bowtie_copies", "cut_nonmanifold_edges",
                "cut_edges", "cut_vertices", "cut_copies", "flipped_faces")


def _counts(report: dict) -> dict:
    """Per kind, the number of faces, edges or vertices; for the "_copies" kinds, the copies made."""
    return {kind: (sum if kind.endswith("_copies") else len)(report[kind]) for kind in REPORT_KINDS}


def _listed(noun: str, items, max_listed: int) -> str:
    """"(faces 3, 7, ... 12 in all)": the first `max_listed` items of a report
    list; `noun` is (singular, plural)."""
    names = [f"({x[0]}, {x[1]})" if isinstance(x, (list, tuple)) else str(x) for x in items[:max_listed]]
    more = f", ... {len(items)} in all" if len(items) > max_listed else ""
    return f"({noun[len(items) > 1]} {', '.join(names)}{more})"


def _copies(per_vertex) -> str:
    n = sum(per_vertex)
    return f"{n} {'copy' if n == 1 else 'copies'} added"


_FACES, _EDGES, _VERTICES = ("face", "faces"), ("edge", "edges"), ("vertex", "vertices")


def describe_changes(report: dict, max_listed: int = 5) -> list[str]:
    """One line per kind of change in a `repair` report (none for a valid
    mesh), naming the first `max_listed` input faces, edges or vertices of
    each; for ``sorpia repair``, ``--repair`` and ``sorpia info``."""
    r, lines = report, []
    for kind, what, done in (("degenerate_faces", "degenerate faces (a repeated vertex)", "removed"),
                             ("collapsed_faces", "polygons with a repeated corner", "kept without the repeats"),
                             ("duplicate_faces", "duplicate faces", "removed"),
                             ("reversed_duplicate_faces", "reversed duplicate faces", "removed")):
        if r[kind]:
            lines.append(f"{what}: {len(r[kind])} {done} {_listed(_FACES, r[kind], max_listed)}")
    if r["nonmanifold_edges"]:
        lines.append(f"non-manifold edges (3 or more faces): {len(r['nonmanifold_edges'])} separated into "
                     f"sheets {_listed(_EDGES, r['nonmanifold_edges'], max_listed)}, their "
                     f"{len(r['sheet_vertices'])} end vertices split with {_copies(r['sheet_copies'])}")
    if r["bowtie_vertices"]:
        lines.append(f"bowtie vertices (fans meeting at one vertex): {len(r['bowtie_vertices'])} split into one "
                     f"vertex per fan, {_copies(r['bowtie_copies'])} "
                     f"{_listed(_VERTICES, r['bowtie_vertices'], max_listed)}")
    if r["cut_nonmanifold_edges"]:
        lines.append(f"sheets that no orientation fits: at {len(r['cut_nonmanifold_edges'])} of the non-manifold "
                     "edges some faces left unpaired, each bordering the edge alone "
                     f"{_listed(_EDGES, r['cut_nonmanifold_edges'], max_listed)}")
    if r["cut_edges"]:
        n = len(r["cut_edges"])
        lines.append(f"not orientable (a twist, like a Moebius strip): cut along {n} {_EDGES[n > 1]} "
                     f"{_listed(_EDGES, r['cut_edges'], max_listed)}, their {len(r['cut_vertices'])} end vertices "
                     f"split with {_copies(r['cut_copies'])}")
    if r["flipped_faces"]:
        lines.append(f"inconsistent orientation: {len(r['flipped_faces'])} faces reversed "
                     f"{_listed(_FACES, r['flipped_faces'], max_listed)}")
    return lines


class _DeprecatedReport(dict):
    """RepairResult.report for one release: the changes dict of old
    (``r.report["counts"]``, with a DeprecationWarning: use ``r.changes``),
    callable as every result's ``report()`` is."""

    def __init__(self, changes: dict, report: dict) -> None:
        super().__init__(changes)
        self._report = report

    def __call__(self) -> dict:
        return self._report

    def _warn(self) -> None:
        warnings.warn("RepairResult.report as a dict is deprecated: use RepairResult.changes (the same dict); "
                      "report() is the result's report, as on every sorpia result", DeprecationWarning, stacklevel=3)


def _warning(name: str):
    def method(self, *args, **kwargs):
        self._warn()
        return getattr(dict, name)(self, *args, **kwargs)
    method.__name__ = name
    return method


# Every way of reading the old dict warns (json.dumps reads it without a warning, as it reads dicts in C).
for _name in ("__getitem__", "__contains__", "__iter__", "__len__", "get", "keys", "values", "items"):
    setattr(_DeprecatedReport, _name, _warning(_name))


class RepairResult(NamedTuple):
    """What `repair` returns.

    Attributes
    ----------
    vertices : numpy.ndarray, (n + k, 3) float64
        The input vertices, then k copies: ``vertices[i]`` equals
        ``input_vertices[vertex_map[i]]`` bit for bit.
    faces : numpy.ndarray, (m', k) int32, or sorpia.Polygons
        The repaired faces, a valid mesh for every sorpia function, in the
        form they were given (see `repair`).
    vertex_map : numpy.ndarray, (n + k,) int32
        For every output vertex, the input vertex it copies
        (``vertex_map[i] == i`` for i < n).
    face_map : numpy.ndarray, (m',) int32
        For every output face, the input face it comes from.
    changes : dict
        Every change, JSON-able (lists of ints): see `repair`. (Called
        ``report`` until this release: ``result.report[...]`` still reads it, with a
        DeprecationWarning, for one release.)
    tags : dict
        The sharpness tags given to `repair`, on the repaired mesh: the keys
        among ``creases``, ``corners`` and ``holes`` that were given, ready
        for ``interpolate(vertices, faces, **tags)`` (see `repair`).
    rules : dict
        The scheme, boundary rule and nonmanifold option of the mesh given
        (a `sorpia.SubdivisionMesh`'s; the defaults for arrays), which
        `mesh` carries over.

    ``mesh`` is the repaired mesh as a `sorpia.SubdivisionMesh` with the
    tags and rules; ``report()`` the result's report, as every sorpia
    result gives it: a JSON-ready dict.
    """

    vertices: np.ndarray
    faces: np.ndarray | Polygons
    vertex_map: np.ndarray
    face_map: np.ndarray
    changes: dict
    tags: dict = MappingProxyType({})  # read-only: no tags given
    rules: dict = MappingProxyType({})  # read-only: the defaults

    @property
    def mesh(self) -> SubdivisionMesh:
        """The repaired mesh with its tags and the input's rules."""
        return SubdivisionMesh(self.vertices, self.faces, **{**self.rules, **self.tags})

    @property
    def report(self) -> _DeprecatedReport:  # type: ignore[override]
        """``report()``: the result's report (a JSON-ready dict: ``changes``
        and the sizes of the input and output meshes). Read as a dict, the
        deprecated name of `changes`."""
        return _DeprecatedReport(self.changes, {"changes": self.changes, "n_vertices": int(len(self.vertices)),
                                                "n_faces": int(len(self.face_map))})


def repair(vertices, faces=None, *, creases=None, corners=None, holes=None) -> RepairResult:
    """Make a triangle or polygon mesh valid for subdivision without moving a vertex.

    The rules, applied in this order:

    1. a face with a repeated vertex loses its consecutive repeats (cyclically:
       ``(a, b, b, c)`` and ``(a, b, c, a)`` become the triangle ``(a, b, c)``)
       when what is left is a polygon of three or more distinct vertices
       ("collapsed_faces"); otherwise (every triangle with a repeated vertex, a
       polygon crossing itself at a vertex such as ``(a, b, a, c)``) it is
       removed ("degenerate_faces");
    2. of faces with the same vertices in the same cyclic sequence the first is
       kept; later ones in the same direction ("duplicate_faces") or the
       opposite one ("reversed_duplicate_faces") are removed, except a pair in
       the opposite order with no other face on their edges (a closed
       "pillow" of two faces, valid), which is kept;
    3. at an edge of three or more faces ("nonmanifold_edges"), the faces are
       paired into sheets in face order: the lowest-numbered unpaired face with
       the next unpaired face running the edge the other way (else the next
       unpaired face); a face left over borders the edge alone;
    4. where no orientation of the faces fits, the joins that disagree are
       cut, each face then bordering the edge alone: first, per part joined
       by edges of two faces, a twist (a Moebius strip) is cut across where
       the fronts of a breadth-first search from the face farthest from the
       part's boundary meet ("cut_edges": a short path of edges from
       boundary to boundary, or a closed one); then the pairs of rule 3, in face order, join the parts
       they connect, and a pair that would join two faces already oriented
       against it is left unpaired ("cut_nonmanifold_edges"). Nothing is cut
       where every part orients with its pairs;
    5. a vertex whose faces form several fans (joined across the edges of
       rules 3 and 4) gets one vertex per fan: the ends of a non-manifold edge
       ("sheet_vertices"), the ends of a cut edge ("cut_vertices") and the
       'bowtie' vertices where fans meet at a point ("bowtie_vertices"), with
       the number of copies each got in "sheet_copies", "cut_copies" and
       "bowtie_copies". The fan holding the vertex's first corner in face
       order keeps the input vertex; every other fan gets a copy appended
       after the input vertices, in the order of its first corner;
    6. each connected part is oriented consistently by reversing the smaller of
       its two classes of faces (on a tie, those disagreeing with its
       lowest-numbered face) ("flipped_faces"); a reversed face keeps its
       first corner: ``(a, b, c, d)`` becomes ``(a, d, c, b)``.

    No vertex is moved or dropped: vertices used only by removed faces and
    unreferenced vertices stay (unreferenced). Repair is idempotent.

    Parameters
    ----------
    vertices : array_like, (n, 3) float, or sorpia.SubdivisionMesh
        Vertex positions (validated as everywhere in sorpia); or a mesh,
        whose tags are carried over and whose rules ``result.mesh`` keeps.
    faces : array_like, (m, k) int, list of lists, or sorpia.Polygons
        Triangles, quads or polygons of any sizes (at least 3 vertices each),
        indices into ``vertices``; they may fail sorpia's topology checks, which
        is what this function is for.
    creases, corners, holes : optional
        OpenSubdiv's sharpness tags of the input mesh, as `interpolate` takes
        them. They come back in ``RepairResult.tags`` on the repaired mesh: a
        crease on every output edge whose two ends copy its two vertices (an
        edge of removed faces only is dropped), a corner on its vertex and
        every copy, a hole on the output faces of its face (a removed face's
        hole is dropped).

    Returns
    -------
    RepairResult
        ``(vertices, faces, vertex_map, face_map, report, tags)``. The faces come
        back in the form they were given: an (m, k) array (or a list of
        faces of k vertices each) as an (m', k) int32 array, unless rule 1
        shortened a face, and then, like a ragged list or a
        `sorpia.Polygons`, as a `sorpia.Polygons` of int32 arrays.
        ``report`` has one key per kind above, holding the input face
        indices, the input edges ``[a, b]`` (a < b) or the input vertex
        indices concerned, and "counts", the number of each kind (for
        the "_copies" kinds, the number of vertices added). For
        a valid mesh every count is 0 and the validated input arrays come back
        themselves (no copy; they are the caller's arrays, or the caller's
        `sorpia.Polygons`, when these are already float64 and int32,
        C-contiguous), with identity maps.

    Raises
    ------
    sorpia.MeshError
        Faces that all repeat a vertex, or a problem repair does not change (index out of range, a face of
        fewer than 3 vertices, no faces, a vertex of more edges than
        OpenSubdiv takes).
    """
    rules = {}
    if isinstance(vertices, SubdivisionMesh):
        given = vertices.rules
        rules = {k: given[k] for k in ("scheme", "boundary", "nonmanifold")}
        vertices, faces, tags = mesh_arguments(vertices, faces, dict(creases=creases, corners=corners, holes=holes),
                                               "repair")
        creases, corners, holes = tags["creases"], tags["corners"], tags["holes"]
    vertices = as_vertices(vertices)
    result = _repair_faces(vertices, faces)
    if rules:
        result = result._replace(rules=rules)
    if creases is None and corners is None and holes is None:
        return result
    r = result.changes  # every input face is kept or removed by one rule
    n_faces = len(result.face_map) + sum(len(r[k]) for k in ("degenerate_faces", "duplicate_faces",
                                                              "reversed_duplicate_faces"))
    tags = as_tags(creases, corners, holes, n_vertices=len(vertices), n_faces=n_faces)
    given = {kind for kind, value in (("creases", creases), ("corners", corners), ("holes", holes))
             if value is not None}
    return result._replace(tags=mapped_tags(tags, result.faces, result.vertex_map, result.face_map, len(vertices),
                                            given))


def _repair_faces(vertices, faces) -> RepairResult:
    """`repair` without tags, of validated vertices."""
    n = vertices.shape[0]
    rows, triangles, polygons = core_faces(faces, n)
    if triangles is not None:
        changed = _core.repair(triangles, n)
        if changed is None:
            return _unchanged(vertices, triangles, len(triangles))
        new_faces, vertex_map, face_map, report = changed
        report["counts"] = _counts(report)
        return RepairResult(vertices[vertex_map], new_faces, vertex_map, face_map, report)

    counts, indices = polygons
    changed = _core.repair_polygons(counts, indices, n)
    if changed is None:
        if rows is not None:  # validated: the cast cannot wrap; no copy of an int32 C-contiguous array
            return _unchanged(vertices, np.ascontiguousarray(rows, dtype=np.int32), len(rows))
        same = (isinstance(faces, Polygons) and faces.face_vertex_counts is counts
                and faces.face_vertex_indices is indices)
        return _unchanged(vertices, faces if same else Polygons(counts, indices), len(counts))
    new_counts, new_indices, vertex_map, face_map, report = changed
    report["counts"] = _counts(report)
    return RepairResult(vertices[vertex_map], faces_as_given(rows, new_counts, new_indices), vertex_map, face_map,
                        report)


def _unchanged(vertices, faces, n_faces) -> RepairResult:
    """The result for a valid mesh: its arrays, identity maps, an empty report."""
    report = {kind: [] for kind in REPORT_KINDS}
    report["counts"] = _counts(report)
    return RepairResult(vertices, faces, np.arange(len(vertices), dtype=np.int32),
                        np.arange(n_faces, dtype=np.int32), report)
