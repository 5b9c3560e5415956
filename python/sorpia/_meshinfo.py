"""Mesh statistics for ``sorpia info`` and the fit report (the paper's Table 2).

The counting is the core's (sorpia::mesh_statistics): from the topology a
solve builds anyway, or, for a mesh sorpia's validation refuses, from the
raw face list; this module only lays the counts out. Whether Loop PIA can
run is decided by that same validation (`sorpia.limit.topology`, the check
`interpolate` makes), never by a second implementation of the rules.
"""

from __future__ import annotations

import numpy as np

from . import _core
from ._mesh import SubdivisionMesh
from ._validate import DEFAULT_SCHEME, Polygons, as_boundary, as_scheme, as_vertices
from .errors import MeshError
from .limit import topology as _topology


def topology_info(vertices, topology, list_extraordinary: bool | int = False, scheme: str = "loop") -> dict:
    """Statistics of a mesh from its validated topology (`Interpolator.topology`).

    Parameters
    ----------
    vertices : (n, 3) float64
        For the bounding box.
    topology : sorpia._core.Topology
    list_extraordinary : bool or int
        Include the index, valence and side of every extraordinary vertex
        (True), of the first N (an int), or of none (False).
    scheme : {"loop", "catmull-clark"}
        Whose regular valence the extraordinary vertices are counted against.

    Returns
    -------
    dict
        ``vertices, faces, edges, boundary_edges, boundary_loops,
        euler_characteristic`` (chi = V - E + F over the referenced vertices),
        ``genus`` (per component (2 - chi_c - b_c)/2 summed; None when the mesh
        is not a valid oriented manifold), ``components``,
        ``unreferenced_vertices``, ``valence_min``, ``valence_max``,
        ``valence_histogram`` ({"interior": {valence: count}, "boundary": ...}),
        ``extraordinary_vertices`` (count: a valence other than the scheme's
        regular one, ``regular_valence`` [inside, on the boundary]: Loop 6 and
        4, Catmull-Clark 4 and 3), ``extraordinary_share`` (of the referenced vertices),
        ``extraordinary`` (list of [index, valence, "interior"|"boundary"],
        if asked), ``bounding_box`` ([min xyz, max xyz]), ``diagonal``.
    """
    info = _layout(vertices, topology.n_faces, _core.mesh_statistics(topology, as_scheme(scheme)), list_extraordinary)
    return _with_regular(info, scheme)


def _with_regular(info: dict, scheme: str) -> dict:
    """info with "regular_valence": [inside, on the boundary], the valences the
    scheme calls regular (Loop 6 and 4, Catmull-Clark 4 and 3)."""
    info["regular_valence"] = list(_core.regular_valence(as_scheme(scheme)))
    return info


def mesh_info(vertices, faces, boundary: str = "edge-and-corner", list_extraordinary: bool | int = True,
              scheme: str = "loop") -> dict:
    """Statistics of a mesh (`topology_info`'s dict) and whether PIA of the
    scheme can run on it: ``loop_pia``: {"can_run": bool, "reason": str | None,
    "notes": [str]} (the faces' validation for `scheme`: triangles for Loop,
    any polygons for "catmull-clark").

    The mesh goes through sorpia's validation (`boundary` is the rule the
    verdict refers to); a mesh it refuses is still counted from its face
    list, with genus None. Faces that are not (m, 3) indices into `vertices`
    get vertex and face counts only.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    n_faces = len(faces.face_vertex_counts) if isinstance(faces, Polygons) else None
    if n_faces is None:
        faces = np.asarray(faces)
        n_faces = len(faces) if faces.ndim else 0
    notes: list[str] = []
    topo, reason = None, None
    try:
        as_boundary(boundary)
        as_vertices(vertices)
        topo = _topology(faces, len(vertices), scheme=scheme, warn=False, count_name="len(vertices)")  # validates
    except (MeshError, ValueError, TypeError) as exc:
        reason = str(exc)
    if topo is not None:
        stats = _core.mesh_statistics(topo, as_scheme(scheme))
    else:
        stats = None if isinstance(faces, Polygons) else _face_list_statistics(faces, len(vertices))
    info = _with_regular(_layout(vertices, n_faces, stats, list_extraordinary), scheme)
    if reason is None:
        notes.append(f"boundary rule {boundary!r}")
        if topo.n_unreferenced:
            notes.append(f"{topo.n_unreferenced} vertices belong to no face: they pass through unchanged (their "
                         "limit is themselves)")
    info["loop_pia"] = {"can_run": reason is None, "reason": reason, "notes": notes}
    return info


def mesh_statistics(vertices, faces=None, *, scheme: str = DEFAULT_SCHEME,
                    list_extraordinary: bool | int = False) -> dict:
    """Statistics of a mesh, as ``sorpia info`` prints them (the paper's Table 2).

    Parameters
    ----------
    vertices : array_like (n, 3) float, or sorpia.SubdivisionMesh
        For the counts and the bounding box; or a mesh (its faces and scheme).
    faces : array_like (m, k) int, list of polygons or sorpia.Polygons
    scheme : {"auto", "loop", "catmull-clark"}
        Whose regular valence the extraordinary vertices are counted against
        (Loop 6 inside and 4 on the boundary, Catmull-Clark 4 and 3); "auto":
        a mesh's own scheme, else Loop when every face is a triangle.
    list_extraordinary : bool or int
        Include the index, valence and side of every extraordinary vertex
        (True), of the first N (an int), or of none (False).

    Returns
    -------
    dict
        ``vertices, faces, edges, boundary_edges, boundary_loops,
        euler_characteristic, genus, components, unreferenced_vertices,
        valence_min, valence_max, valence_histogram, extraordinary_vertices,
        extraordinary_share, regular_valence, bounding_box, diagonal`` (see
        `topology_info`). A mesh sorpia's validation refuses (non-manifold,
        inconsistently oriented) is counted from its face list where it can
        be, with ``genus`` None; ``refused`` then holds the reason.

    Examples
    --------
    >>> V, F = sorpia.shapes.icosphere(1)
    >>> s = sorpia.mesh_statistics(V, F)
    >>> s["vertices"], s["edges"], s["faces"], s["genus"]
    (42, 120, 80, 0)
    """
    if isinstance(vertices, SubdivisionMesh):
        if faces is not None:
            raise TypeError("mesh_statistics(mesh): the faces come from the SubdivisionMesh")
        if scheme == DEFAULT_SCHEME:
            scheme = vertices.scheme
        vertices, faces = vertices.vertices, vertices.faces
    name = _core.scheme_name(as_scheme(scheme, faces))
    info = mesh_info(vertices, faces, list_extraordinary=list_extraordinary, scheme=name)
    verdict = info.pop("loop_pia")
    if not verdict["can_run"]:
        info["refused"] = verdict["reason"]
    return info


def _face_list_statistics(faces: np.ndarray, n: int):
    """The core's counts of a raw face list; None where there is none to count."""
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0 or n == 0 or faces.dtype.kind not in "iu":
        return None
    if faces.min() < 0 or faces.max() >= n:
        return None
    return _core.face_list_statistics(np.ascontiguousarray(faces, dtype=np.int32), n)


def boundary_share(faces, n_vertices: int) -> float:
    """Boundary edges / edges of a triangle list (0 for a closed mesh), valid or not."""
    stats = _face_list_statistics(np.asarray(faces), n_vertices)
    return stats["boundary_edges"] / stats["edges"] if stats and stats["edges"] else 0.0


def extent_length(extent: np.ndarray) -> float:
    """The length of a bounding box's extent (its diagonal), scaled before
    squaring: the squares of coordinates beyond 1e154 overflow (the diagonal
    would read inf and every figure relative to it 0)."""
    scale = float(np.abs(extent).max())
    return scale * float(np.linalg.norm(extent / scale)) if scale > 0 else 0.0


def bounding_box_diagonal(points: np.ndarray) -> float:
    """Length of the diagonal of the points' bounding box, finite for any
    finite coordinates (extent_length)."""
    return extent_length(points.max(axis=0) - points.min(axis=0)) if len(points) else 0.0


def _layout(vertices, n_faces: int, stats, list_extraordinary) -> dict:
    vertices = np.asarray(vertices, dtype=np.float64)
    info: dict = {"vertices": len(vertices), "faces": n_faces}
    if len(vertices):
        # Column by column: numpy's reduction along axis 0 of an (n, 3) array is several times slower.
        lo = np.array([vertices[:, k].min() for k in range(3)])
        hi = np.array([vertices[:, k].max() for k in range(3)])
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
            finite = np.isfinite(vertices).all(axis=1)
            lo, hi = (vertices[finite].min(axis=0), vertices[finite].max(axis=0)) if finite.any() else (None, None)
        if lo is not None:
            info["bounding_box"] = [lo.tolist(), hi.tolist()]
            info["diagonal"] = extent_length(hi - lo)
    if stats is None:
        return info
    for key in ("edges", "boundary_edges", "boundary_loops", "euler_characteristic", "genus", "components",
                "unreferenced_vertices", "valence_min", "valence_max"):
        info[key] = stats[key]
    info["valence_histogram"] = {"interior": _histogram(stats["interior_valences"]),
                                 "boundary": _histogram(stats["boundary_valences"])}
    index, valence, on_boundary = stats["extraordinary"]
    n_ref = stats["vertices"] - stats["unreferenced_vertices"]
    info["extraordinary_vertices"] = int(len(index))
    info["extraordinary_share"] = float(len(index) / n_ref) if n_ref else 0.0
    if list_extraordinary is not False:
        k = len(index) if list_extraordinary is True else int(list_extraordinary)
        sides = np.where(on_boundary[:k], "boundary", "interior").tolist()
        info["extraordinary"] = [list(row) for row in zip(index[:k].tolist(), valence[:k].tolist(), sides)]
    return info


def _repair_rows(repair: dict | None) -> list[tuple[str, str]]:
    """The rows of `format_info` for info["repair"] (``sorpia info``): what
    --repair changed, would change, or why it cannot repair the mesh."""
    if repair is None:
        return []
    if "refused" in repair:
        return [("--repair", f"cannot make it valid either: {repair['refused']}")]
    if not repair["changes"]:
        return [("--repair", "would change nothing")]
    label = "repaired" if repair["applied"] else "--repair would fix"
    return [(label if j == 0 else "", line) for j, line in enumerate(repair["changes"])]


def _histogram(counts) -> dict:
    return {v: int(c) for v, c in enumerate(counts) if c}


def format_info(info: dict, name: str | None = None, max_listed: int = 16, extra_rows=()) -> str:
    """Human-readable text of `mesh_info`'s dict; the extraordinary vertices
    laid out as the paper's Table 2 (vertex / valence rows), the first
    `max_listed` of them; `extra_rows` (label, text) after the statistics."""
    rows: list[tuple[str, str]] = []
    if name:
        rows.append(("mesh", name))
    rows.append(("vertices", f"{info['vertices']}"))
    rows.append(("faces", f"{info['faces']}"))
    if "edges" in info:
        rows += [
            ("edges", f"{info['edges']} ({info['boundary_edges']} on the boundary)"),
            ("boundary loops", f"{info['boundary_loops']}" + (" (closed)" if info["boundary_loops"] == 0 else "")),
            ("Euler characteristic", f"{info['euler_characteristic']}"),
            ("genus", "undetermined (not a valid oriented manifold)" if info["genus"] is None
             else f"{info['genus']}"),
            ("components", f"{info['components']}"),
            ("unreferenced vertices", f"{info['unreferenced_vertices']}"),
            ("valence", f"{info['valence_min']} to {info['valence_max']}"),
        ]
        for kind in ("interior", "boundary"):
            hist = info["valence_histogram"][kind]
            if hist:
                rows.append((f"  {kind} valences", "  ".join(f"{v}:{c}" for v, c in hist.items())))
        rows.append(("extraordinary vertices",
                     f"{info['extraordinary_vertices']} ({100 * info['extraordinary_share']:.1f}% of the "
                     f"referenced vertices; regular: valence {info['regular_valence'][0]} inside, "
                     f"{info['regular_valence'][1]} on the boundary)"))
    if "diagonal" in info:
        rows.append(("bounding-box diagonal", f"{info['diagonal']:.6g}"))
    verdict = info["loop_pia"]
    if verdict["can_run"]:
        rows.append(("Loop PIA", "can run" + (f" ({'; '.join(verdict['notes'])})" if verdict["notes"] else "")))
    else:
        rows.append(("Loop PIA", f"cannot run: {verdict['reason']}"))
    rows += _repair_rows(info.get("repair"))
    rows += list(extra_rows)
    width = max(len(k) for k, _ in rows)
    lines = [f"{k:<{width}}  {v}" for k, v in rows]
    shown = (info.get("extraordinary") or [])[:max_listed]
    if shown:
        cells = [(str(i), str(v)) for i, v, _ in shown]
        w = [max(len(a), len(b)) for a, b in cells]
        rest = info["extraordinary_vertices"] - len(shown)
        more = f"  ... ({rest} more)" if rest > 0 else ""
        lines.append("extraordinary vertices (as the paper's Table 2):")
        lines.append("  vertex   " + " ".join(f"{a:>{k}}" for (a, _), k in zip(cells, w)) + more)
        lines.append("  valence  " + " ".join(f"{b:>{k}}" for (_, b), k in zip(cells, w)))
    return "\n".join(lines)
