"""Repair of triangle meshes that sorpia refuses (duplicate and degenerate
faces, bowtie vertices, edges of three or more faces, mixed orientation)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import _core
from ._validate import as_faces, as_vertices

# The report's keys, in the order the repair applies its rules (see `repair`).
REPORT_KINDS = ("degenerate_faces", "duplicate_faces", "reversed_duplicate_faces", "nonmanifold_edges",
                "sheet_vertices", "sheet_copies", "bowtie_vertices", "bowtie_copies", "flipped_faces")


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
    for kind, what in (("degenerate_faces", "degenerate faces (a repeated vertex)"),
                       ("duplicate_faces", "duplicate faces"),
                       ("reversed_duplicate_faces", "reversed duplicate faces")):
        if r[kind]:
            lines.append(f"{what}: {len(r[kind])} removed {_listed(_FACES, r[kind], max_listed)}")
    if r["nonmanifold_edges"]:
        lines.append(f"non-manifold edges (3 or more faces): {len(r['nonmanifold_edges'])} separated into "
                     f"sheets {_listed(_EDGES, r['nonmanifold_edges'], max_listed)}, their "
                     f"{len(r['sheet_vertices'])} end vertices split with {_copies(r['sheet_copies'])}")
    if r["bowtie_vertices"]:
        lines.append(f"bowtie vertices (fans meeting at one vertex): {len(r['bowtie_vertices'])} split into one "
                     f"vertex per fan, {_copies(r['bowtie_copies'])} "
                     f"{_listed(_VERTICES, r['bowtie_vertices'], max_listed)}")
    if r["flipped_faces"]:
        lines.append(f"inconsistent orientation: {len(r['flipped_faces'])} faces reversed "
                     f"{_listed(_FACES, r['flipped_faces'], max_listed)}")
    return lines


class RepairResult(NamedTuple):
    """What `repair` returns.

    Attributes
    ----------
    vertices : numpy.ndarray, (n + k, 3) float64
        The input vertices, then k copies: ``vertices[i]`` equals
        ``input_vertices[vertex_map[i]]`` bit for bit.
    faces : numpy.ndarray, (m', 3) int32
        The repaired triangles, a valid mesh for every sorpia function.
    vertex_map : numpy.ndarray, (n + k,) int32
        For every output vertex, the input vertex it copies
        (``vertex_map[i] == i`` for i < n).
    face_map : numpy.ndarray, (m',) int32
        For every output face, the input face it comes from.
    report : dict
        Every change, JSON-able (lists of ints): see `repair`.
    """

    vertices: np.ndarray
    faces: np.ndarray
    vertex_map: np.ndarray
    face_map: np.ndarray
    report: dict


def repair(vertices, faces) -> RepairResult:
    """Make a triangle mesh valid for Loop interpolation without moving a vertex.

    The rules, applied in this order:

    1. faces with a repeated vertex are removed ("degenerate_faces");
    2. of faces with the same three vertices the first is kept; later ones in
       the same cyclic order ("duplicate_faces") or the opposite one
       ("reversed_duplicate_faces") are removed;
    3. at an edge of three or more faces ("nonmanifold_edges"), the faces are
       paired into sheets in face order: the lowest-numbered unpaired face with
       the next unpaired face running the edge the other way (else the next
       unpaired face); a face left over borders the edge alone;
    4. a vertex whose faces form several fans (joined across the edges of
       rule 3) gets one vertex per fan: the ends of a non-manifold edge
       ("sheet_vertices") and the 'bowtie' vertices where fans meet at a point
       ("bowtie_vertices"), with the number of copies each got in
       "sheet_copies" and "bowtie_copies". The fan holding the vertex's first
       corner in face order keeps the input vertex; every other fan gets a copy
       appended after the input vertices, in the order of its first corner;
    5. each connected part is oriented consistently by reversing the smaller of
       its two classes of faces (on a tie, those disagreeing with its
       lowest-numbered face) ("flipped_faces").

    No vertex is moved or dropped: vertices used only by removed faces and
    unreferenced vertices stay (unreferenced). Repair is idempotent.

    Parameters
    ----------
    vertices : array_like, (n, 3) float
        Vertex positions (validated as everywhere in sorpia).
    faces : array_like, (m, 3) int
        Triangles, indices into `vertices`; they may fail sorpia's topology
        checks, which is what this function is for.

    Returns
    -------
    RepairResult
        ``(vertices, faces, vertex_map, face_map, report)``. ``report`` has one
        key per kind above, holding the input face indices, the input edges
        ``[a, b]`` (a < b) or the input vertex indices concerned, and "counts",
        the number of each kind (for "sheet_copies" and "bowtie_copies", the
        number of vertices added). For a
        valid mesh every count is 0 and the validated input arrays come back
        themselves (no copy; they are the caller's arrays when these are
        already float64 and int32, C-contiguous), with identity maps.

    Raises
    ------
    sorpia.MeshError
        A connected part with no consistent orientation (a Moebius strip),
        named by its lowest face and its size; faces that all repeat a vertex;
        or a problem repair does not change (index
        out of range, no faces, a vertex of more edges than OpenSubdiv takes).
    """
    vertices = as_vertices(vertices)
    n = vertices.shape[0]
    faces = as_faces(faces, n, count_name="len(vertices)")
    changed = _core.repair(faces, n)
    if changed is None:
        report = {kind: [] for kind in REPORT_KINDS}
        report["counts"] = _counts(report)
        return RepairResult(vertices, faces, np.arange(n, dtype=np.int32), np.arange(len(faces), dtype=np.int32),
                            report)
    new_faces, vertex_map, face_map, report = changed
    report["counts"] = _counts(report)
    return RepairResult(vertices[vertex_map], new_faces, vertex_map, face_map, report)
