"""What a mesh carries besides its vertices and faces, kept when its faces
change: sharpness tags merged by one rule, and face-varying attributes
(texture coordinates, normals) carried onto new faces.

The rule for a tag given twice is OpenSubdiv's: an edge (either order) or a
vertex tagged more than once counts with the last sharpness given. Every
merge of tags in sorpia goes through `merge_sharpness` (the command line's
--sharp-angle creases after a file's, the non-manifold split's corners and
creases after the caller's).
"""

from __future__ import annotations

import numpy as np

from ._validate import as_polygons
from ._mesh import FaceVarying


def merge_sharpness(*tags, width: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Creases (`width` 2: edges (k, 2), sharpness (k,)) or corners (`width`
    1: vertices (k,), sharpness (k,)) given as several (indices, sharpness)
    pairs (None skipped; a single sharpness applies to all of its indices),
    as one pair with one row per edge or vertex: the last sharpness given
    for it (OpenSubdiv's rule), in the order of first appearance. Edges come
    back with their vertices as first given."""
    rows, values = [], []
    for tag in tags:
        if tag is None:
            continue
        indices = np.asarray(tag[0], dtype=np.int64).reshape(-1, width) if width > 1 else np.asarray(
            tag[0], dtype=np.int64).reshape(-1)
        sharpness = np.broadcast_to(np.asarray(tag[1], dtype=np.float64), (len(indices),))
        rows.append(indices)
        values.append(sharpness)
    if not rows:
        return (np.zeros((0, width) if width > 1 else 0, np.int32), np.zeros(0))
    indices, sharpness = np.concatenate(rows), np.concatenate(values)
    keys = np.sort(indices, axis=1) if width > 1 else indices[:, None]
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    last = np.zeros(len(first), dtype=np.int64)
    last[inverse] = np.arange(len(indices))  # a later row of the same key overwrites: the last one given
    order = np.argsort(first, kind="stable")
    return (np.ascontiguousarray(indices[first[order]], dtype=np.int32),
            np.ascontiguousarray(sharpness[last[order]], dtype=np.float64))


def merge_tags(*tag_dicts) -> dict:
    """Several dicts of creases, corners and holes as one (merge_sharpness for
    creases and corners, holes united); other keys (a boundary rule, a
    scheme) as the last dict that has them gives them."""
    out: dict = {}
    for d in tag_dicts:
        out.update({k: v for k, v in d.items() if k not in ("creases", "corners", "holes")})
    for kind, width in (("creases", 2), ("corners", 1)):
        given = [d[kind] for d in tag_dicts if d.get(kind) is not None]
        if given:
            out[kind] = merge_sharpness(*given, width=width)
    holes = [np.asarray(d["holes"], dtype=np.int64).reshape(-1) for d in tag_dicts if d.get("holes") is not None]
    if holes:
        out["holes"] = np.unique(np.concatenate(holes)).astype(np.int32)
    return out


def carry_attributes(attributes: dict, faces, n_vertices: int, new_faces, vertex_map, face_map) -> dict:
    """Face-varying attributes (FaceVarying per name) of `faces` onto
    `new_faces`, whose face f is input face face_map[f] (None: the same face)
    with vertex v a copy of input vertex vertex_map[v], its corners in any
    order: each corner takes the value of its input face's corner at the same
    input vertex (what repair and the non-manifold split change: faces
    dropped, vertices copied, orientation reversed)."""
    if not attributes:
        return {}
    vertex_map = np.asarray(vertex_map, dtype=np.int64)
    counts, indices = as_polygons(faces, n_vertices)
    new_counts, new_indices = as_polygons(new_faces, len(vertex_map))
    face_map = np.arange(len(new_counts)) if face_map is None else np.asarray(face_map, dtype=np.int64)
    keys = np.repeat(np.arange(len(counts), dtype=np.int64), counts) * n_vertices + indices
    order = np.argsort(keys, kind="stable")
    new_keys = np.repeat(face_map, new_counts) * n_vertices + vertex_map[new_indices]
    corner = order[np.minimum(np.searchsorted(keys[order], new_keys), len(keys) - 1)]
    if not np.array_equal(keys[corner], new_keys):  # a contract of repair and split, checked
        raise AssertionError("carry_attributes: a new corner has no input corner at its vertex")
    return {name: FaceVarying(channel.values, np.ascontiguousarray(channel.indices[corner]))
            for name, channel in attributes.items()}
