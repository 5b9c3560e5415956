"""Validation and conversion of user input, done once at the API's edge.

Vertices become C-contiguous float64 (n, 3) arrays and faces C-contiguous
int32 (m, 3) arrays (copies only when the input is not already so); the
compiled core refuses anything else. Messages name the argument, what was
expected, what was given, and the index of the first bad row.
"""

from __future__ import annotations

import numpy as np

from .errors import MeshError, ParameterError

BOUNDARY_RULES = ("edge-and-corner", "edge-only")
DEFAULT_BOUNDARY = "edge-and-corner"


def as_vertices(vertices, name: str = "vertices") -> np.ndarray:
    """Return `vertices` as a C-contiguous float64 (n, 3) array, finite."""
    try:
        arr = np.asarray(vertices)
    except Exception as exc:  # ragged lists and the like
        raise TypeError(f"{name} must be an (n, 3) array of floats: {exc}") from None
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise TypeError(f"{name} must be an (n, 3) array of real numbers, got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {arr.shape}")
    if arr.shape[0] == 0:
        raise MeshError(f"{name} is empty: a mesh needs at least one triangle")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    finite = np.isfinite(arr).all(axis=1)
    if not finite.all():
        i = int(np.flatnonzero(~finite)[0])
        raise MeshError(f"{name}[{i}] = {arr[i].tolist()} is not finite (NaN or inf); "
                        f"{int((~finite).sum())} vertices in all")
    return arr


def as_faces(faces, n_vertices: int, name: str = "faces") -> np.ndarray:
    """Return `faces` as a C-contiguous int32 (m, 3) array of indices in range."""
    try:
        arr = np.asarray(faces)
    except Exception as exc:
        raise TypeError(f"{name} must be an (m, 3) array of vertex indices: {exc}") from None
    if arr.dtype == object or arr.dtype == bool or not (
        np.issubdtype(arr.dtype, np.integer) or (np.issubdtype(arr.dtype, np.floating) and arr.size == 0)
    ):
        raise TypeError(f"{name} must be an (m, 3) array of integer vertex indices, got dtype {arr.dtype}")
    if arr.ndim != 2:
        raise ValueError(f"{name} must have shape (m, 3), got {arr.shape}")
    if arr.shape[1] != 3:
        raise MeshError(
            f"{name} has {arr.shape[1]} vertices per face: Loop subdivision needs triangles "
            "(split each polygon into triangles first, e.g. sorpia.read_mesh(path, triangulate=True))")
    if arr.shape[0] == 0:
        raise MeshError(f"{name} is empty: a mesh needs at least one triangle")
    bad = (arr < 0) | (arr >= n_vertices)
    if bad.any():
        f = int(np.flatnonzero(bad.any(axis=1))[0])
        raise MeshError(f"{name}[{f}] = {arr[f].tolist()} has a vertex index out of range [0, {n_vertices})")
    return np.ascontiguousarray(arr, dtype=np.int32)


def as_boundary(boundary: str) -> str:
    if boundary not in BOUNDARY_RULES:
        raise ParameterError(f"unknown boundary {boundary!r}: use one of {', '.join(map(repr, BOUNDARY_RULES))}")
    return boundary
