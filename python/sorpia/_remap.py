"""Faces and tags carried from a mesh to one made from it by copying
vertices and faces: what `sorpia.repair` and the non-manifold split
(`sorpia._nonmanifold`) share."""

from __future__ import annotations

import numpy as np

from . import _core
from ._validate import Polygons, _face_rows, as_faces, as_polygons


def core_faces(faces, n_vertices: int):
    """`faces` validated for the core: ``(rows, triangles, polygons)`` where
    rows is the (m, k) array the faces were given as (None for Polygons and
    ragged lists), triangles the (m, 3) int32 array when k == 3 (else None)
    and polygons otherwise the int32 (counts, indices)."""
    rows = None if isinstance(faces, Polygons) else _face_rows(
        faces, "faces", "(m, k)", "an (m, k) array of integer vertex indices, a list of polygons or sorpia.Polygons")
    if rows is not None and rows.shape[1] == 3:  # triangles: the (m, 3) path, as sorpia's Loop functions take them
        return rows, as_faces(rows, n_vertices, count_name="len(vertices)"), None
    return rows, None, as_polygons(faces if rows is None else rows, n_vertices, count_name="len(vertices)")


def faces_as_given(rows, counts, indices):
    """Output polygons in the form the input came in (see `repair`)."""
    if rows is not None and (counts == rows.shape[1]).all():
        return indices.reshape(-1, rows.shape[1])
    return Polygons(counts, indices)


def mapped_tags(tags: _core.Tags, faces, vertex_map: np.ndarray, face_map: np.ndarray, n_vertices: int,
                kinds) -> dict:
    """The tags (a checked _core.Tags of the input mesh, of `n_vertices`
    vertices) on a mesh made from it by copying vertices and faces (a repair,
    a non-manifold split): `faces`, each vertex copying ``vertex_map[i]`` and
    each face ``face_map[f]`` of the input; the `kinds` given."""
    out = {}
    if "creases" in kinds:
        counts, indices = as_polygons(faces, len(vertex_map))
        last = np.cumsum(counts) - 1
        nxt = np.arange(1, len(indices) + 1)
        nxt[last] = last - counts + 1  # a face's last corner is followed by its first
        a, b = indices, indices[nxt]
        edges = np.unique(np.column_stack([np.minimum(a, b), np.maximum(a, b)]), axis=0)  # the output edges
        ends = np.sort(vertex_map[edges], axis=1).astype(np.int64)  # their input vertices
        key = ends[:, 0] * n_vertices + ends[:, 1]
        order = np.argsort(key, kind="stable")
        wanted = np.sort(tags.crease_vertices, axis=1).astype(np.int64)
        wanted_key = wanted[:, 0] * n_vertices + wanted[:, 1]
        lo = np.searchsorted(key[order], wanted_key, side="left")
        hi = np.searchsorted(key[order], wanted_key, side="right")
        which = np.concatenate([order[i:j] for i, j in zip(lo, hi)] + [np.zeros(0, np.int64)])
        out["creases"] = (edges[which].astype(np.int32), np.repeat(tags.crease_sharpness, hi - lo))
    if "corners" in kinds:
        sharpness = np.full(n_vertices, np.nan)
        sharpness[tags.corner_vertices] = tags.corner_sharpness  # a corner given twice: the last, as OpenSubdiv
        copies = np.flatnonzero(~np.isnan(sharpness[vertex_map]))
        out["corners"] = (copies.astype(np.int32), sharpness[vertex_map[copies]])
    if "holes" in kinds:
        out["holes"] = np.flatnonzero(np.isin(face_map, tags.holes)).astype(np.int32)
    return out
