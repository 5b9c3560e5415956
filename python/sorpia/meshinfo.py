"""Mesh statistics for ``sorpia info`` and the fit report (the paper's Table 2).

Counts are computed with numpy from the face array alone, so they exist even
for a mesh Loop PIA cannot run on; whether it can run is decided by sorpia's
own validation (`sorpia.limit.topology`, the same check `interpolate` makes),
never by a second implementation of the rules.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph

from .errors import MeshError
from .limit import topology

# A vertex is regular for Loop subdivision with 6 edges inside the mesh and 4 on
# its boundary; any other valence makes it extraordinary (paper section 2).
REGULAR_INTERIOR_VALENCE = 6
REGULAR_BOUNDARY_VALENCE = 4


def _components(n: int, a: np.ndarray, b: np.ndarray) -> tuple[int, np.ndarray]:
    """Connected components of the graph on n nodes with edges (a[k], b[k])."""
    graph = scipy.sparse.coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(n, n)).tocsr()
    return scipy.sparse.csgraph.connected_components(graph, directed=False)


def edge_counts(faces: np.ndarray, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """The undirected edges of (m, 3) int64 `faces` as sorted keys
    min(a, b) * n_vertices + max(a, b), and the number of faces at each (1: a
    boundary edge)."""
    half = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(half.min(axis=1) * n_vertices + half.max(axis=1), return_counts=True)


def mesh_info(vertices, faces, boundary: str = "edge-and-corner", list_extraordinary: bool = True,
              verdict: bool = True) -> dict:
    """Statistics of a triangle mesh and whether Loop PIA can run on it.

    Parameters
    ----------
    vertices : array_like, (n, 3) float
    faces : array_like, (m, 3) int
    boundary : str
        Boundary rule the verdict refers to (see `sorpia.limit_points`).
    list_extraordinary : bool
        Include the index and valence of every extraordinary vertex (one entry
        per vertex; leave out for compact reports of big meshes).
    verdict : bool
        Run sorpia's validation for ``loop_pia``. False leaves ``loop_pia``
        out and takes the mesh as valid (for a caller about to run
        `interpolate`, which validates it anyway: building the topology twice
        costs seconds on a million vertices).

    Returns
    -------
    dict
        ``vertices, faces, edges, boundary_edges, boundary_loops,
        euler_characteristic`` (chi = V - E + F over the referenced vertices),
        ``genus`` (per component (2 - chi_c - b_c)/2 summed; None when the mesh
        is not a valid oriented manifold), ``components``,
        ``unreferenced_vertices``, ``valence_min``, ``valence_max``,
        ``valence_histogram`` ({"interior": {valence: count}, "boundary": ...}),
        ``extraordinary_vertices`` (count: interior valence != 6 or boundary
        valence != 4), ``extraordinary_share`` (of the referenced vertices),
        ``extraordinary`` (list of [index, valence, "interior"|"boundary"],
        if asked), ``bounding_box`` ([min xyz, max xyz]), ``diagonal``, and
        (with `verdict`) ``loop_pia``: {"can_run": bool, "reason": str | None,
        "notes": [str]}.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    n, m = len(vertices), len(faces)
    info: dict = {"vertices": n, "faces": m}
    finite = np.isfinite(vertices).all(axis=1) if n else np.ones(0, bool)
    if n and finite.any():
        lo, hi = vertices[finite].min(axis=0), vertices[finite].max(axis=0)
        info["bounding_box"] = [lo.tolist(), hi.tolist()]
        info["diagonal"] = float(np.linalg.norm(hi - lo))
    checked = _loop_pia_verdict(vertices, faces, boundary) if verdict else None
    # The counts below need triangles with indices in range; anything else is
    # reported by the verdict.
    if faces.ndim != 2 or faces.shape[1] != 3 or m == 0 or n == 0 or faces.min() < 0 or faces.max() >= n:
        if checked:
            info["loop_pia"] = checked
        return info

    faces = faces.astype(np.int64)
    keys, counts = edge_counts(faces, n)
    ea, eb = keys // n, keys % n
    boundary_edge = counts == 1
    referenced = np.zeros(n, bool)
    referenced[faces.ravel()] = True
    n_ref = int(referenced.sum())
    valence = np.bincount(ea, minlength=n) + np.bincount(eb, minlength=n)
    on_boundary = np.zeros(n, bool)
    on_boundary[ea[boundary_edge]] = True
    on_boundary[eb[boundary_edge]] = True

    _, labels = _components(n, ea, eb)
    comp_of_face = labels[faces[:, 0]]
    comp_ids, comp_index = np.unique(labels[referenced], return_inverse=True)
    n_comp = len(comp_ids)
    remap = np.full(labels.max() + 1, -1)
    remap[comp_ids] = np.arange(n_comp)

    # Boundary loops: components of the graph of boundary edges.
    bverts = np.flatnonzero(on_boundary)
    n_loops, loop_labels = 0, np.zeros(0, int)
    if len(bverts):
        local = np.full(n, -1)
        local[bverts] = np.arange(len(bverts))
        n_loops, loop_labels = _components(len(bverts), local[ea[boundary_edge]], local[eb[boundary_edge]])

    chi = n_ref - len(keys) + m
    info.update(
        edges=int(len(keys)),
        boundary_edges=int(boundary_edge.sum()),
        boundary_loops=int(n_loops),
        euler_characteristic=int(chi),
        genus=None,
        components=int(n_comp),
        unreferenced_vertices=int(n - n_ref),
    )
    if checked is None or checked["can_run"]:
        # chi_c = 2 - 2 g_c - b_c on each connected orientable surface.
        v_c = np.bincount(comp_index, minlength=n_comp)
        e_c = np.bincount(remap[labels[ea]], minlength=n_comp)
        f_c = np.bincount(remap[comp_of_face], minlength=n_comp)
        b_c = np.zeros(n_comp, int)
        if n_loops:
            first_vertex_of_loop = np.zeros(n_loops, int)
            first_vertex_of_loop[loop_labels] = bverts
            b_c = np.bincount(remap[labels[first_vertex_of_loop]], minlength=n_comp)
        info["genus"] = int(((2 - (v_c - e_c + f_c) - b_c) // 2).sum())

    ref = np.flatnonzero(referenced)
    interior = ref[~on_boundary[ref]]
    bnd = ref[on_boundary[ref]]
    info["valence_min"] = int(valence[ref].min())
    info["valence_max"] = int(valence[ref].max())
    info["valence_histogram"] = {
        "interior": _histogram(valence[interior]),
        "boundary": _histogram(valence[bnd]),
    }
    extra = np.zeros(n, bool)
    extra[interior] = valence[interior] != REGULAR_INTERIOR_VALENCE
    extra[bnd] = valence[bnd] != REGULAR_BOUNDARY_VALENCE
    idx = np.flatnonzero(extra)
    info["extraordinary_vertices"] = int(len(idx))
    info["extraordinary_share"] = float(len(idx) / n_ref) if n_ref else 0.0
    if list_extraordinary:
        info["extraordinary"] = [
            [int(i), int(valence[i]), "boundary" if on_boundary[i] else "interior"] for i in idx
        ]
    if checked:
        if n - n_ref and checked["can_run"]:
            checked["notes"].append(
                f"{n - n_ref} vertices belong to no face: they pass through unchanged (their limit is themselves)")
        info["loop_pia"] = checked
    return info


def _histogram(values: np.ndarray) -> dict:
    vals, counts = np.unique(values, return_counts=True)
    return {int(v): int(c) for v, c in zip(vals, counts)}


def _loop_pia_verdict(vertices: np.ndarray, faces: np.ndarray, boundary: str) -> dict:
    """Run sorpia's own validation and turn its verdict into a dict."""
    from ._validate import as_boundary, as_vertices

    notes: list[str] = []
    try:
        as_boundary(boundary)
        as_vertices(vertices)
        topology(faces, len(vertices), warn=False, count_name="len(vertices)")  # validates the faces, then builds
    except (MeshError, ValueError, TypeError) as exc:
        return {"can_run": False, "reason": str(exc), "notes": notes}
    notes.append(f"boundary rule {boundary!r}")
    return {"can_run": True, "reason": None, "notes": notes}


def format_info(info: dict, name: str | None = None, max_listed: int = 16) -> str:
    """Human-readable text of `mesh_info`'s dict; the extraordinary vertices
    laid out as the paper's Table 2 (vertex / valence rows), the first
    `max_listed` of them."""
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
                     f"referenced vertices; regular: valence 6 inside, 4 on the boundary)"))
    if "diagonal" in info:
        rows.append(("bounding-box diagonal", f"{info['diagonal']:.6g}"))
    verdict = info["loop_pia"]
    if verdict["can_run"]:
        rows.append(("Loop PIA", "can run" + (f" ({'; '.join(verdict['notes'])})" if verdict["notes"] else "")))
    else:
        rows.append(("Loop PIA", f"cannot run: {verdict['reason']}"))
    width = max(len(k) for k, _ in rows)
    lines = [f"{k:<{width}}  {v}" for k, v in rows]
    listed = info.get("extraordinary") or []
    if listed:
        shown = listed[:max_listed]
        cells = [(str(i), str(v)) for i, v, _ in shown]
        w = [max(len(a), len(b)) for a, b in cells]
        more = f"  ... ({len(listed) - len(shown)} more)" if len(listed) > len(shown) else ""
        lines.append("extraordinary vertices (as the paper's Table 2):")
        lines.append("  vertex   " + " ".join(f"{a:>{k}}" for (a, _), k in zip(cells, w)) + more)
        lines.append("  valence  " + " ".join(f"{b:>{k}}" for (_, b), k in zip(cells, w)))
    return "\n".join(lines)
