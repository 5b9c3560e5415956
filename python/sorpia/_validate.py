"""Validation and conversion of user input, done once at the API's edge.

Vertices become C-contiguous float64 (n, 3) arrays and faces C-contiguous
int32 (m, 3) arrays for Loop, or (counts, indices) int32 pairs for polygons
(copies only when the input is not already so; the input
is never modified, read-only and non-contiguous arrays are accepted); the
compiled core refuses anything else. Messages name the argument, what was
expected, what was given, and the index of the first bad row.

What is checked where:

- here (Python): kind and dtype (TypeError), shape, emptiness, finite
  coordinates, face indices in range (before the cast to int32, so that an
  int64 index of 2**32 + 1 is refused rather than wrapped to 1), faces of
  fewer than 3 vertices, and for Loop polygons that are not triangles (with
  the recipe to triangulate them, or to use scheme="catmull-clark");
- in the C++ core (sorpia::Topology, validate_faces in cpp/mesh/src/topology.cpp),
  for every caller including sorpia-bench: indices again, a vertex repeated
  in a face, duplicate faces, edges of three or more faces, inconsistent
  orientation (with the faces to flip, or "not orientable" for a Moebius
  strip) and non-manifold ("bowtie") vertices, raised as sorpia.MeshError.

sorpia.repair changes the faces the core refuses (all but indices out of
range) into a valid mesh without moving a vertex.

Faces given as floats are refused with TypeError even when they hold whole
numbers, as numpy refuses float indices: a float face array is more often a
mistake (vertices and faces swapped) than a convenience.
"""

from __future__ import annotations

import numbers
import operator
from typing import NamedTuple, Optional

import numpy as np

from . import _core
from .errors import MeshError, ParameterError

BOUNDARY_RULES = tuple(_core.boundary_name(b) for b in _core.Boundary.__members__.values())
DEFAULT_BOUNDARY = "edge-and-corner"

# How to make triangles of polygons, quoted in the messages.
TRIANGULATE_HINT = (
    "split each polygon (a, b, c, d, ...) into the fan (a, b, c), (a, c, d), ...; for an (m, 4) quad array "
    "F: numpy.vstack([F[:, [0, 1, 2]], F[:, [0, 2, 3]]]); sorpia.read_mesh(path, triangulate=True) does this "
    "for files")


def _asarray(value, name: str, expected: str) -> np.ndarray:
    try:
        return np.asarray(value)
    except (ValueError, TypeError) as exc:  # ragged nested lists and the like
        raise TypeError(f"{name} must be {expected}: {exc}") from None


def as_vertices(vertices, name: str = "vertices", columns: Optional[int] = 3) -> np.ndarray:
    """Return `vertices` as a C-contiguous float64 (n, 3) array of finite values.

    `columns=None` accepts (n, k) data for any k >= 1 (colours, texture
    coordinates, scalar fields as (n, 1)), checked alike.

    Any real dtype (float16..longdouble, integers) is converted; bool, complex,
    object and string arrays raise TypeError. Raises ValueError for a wrong
    shape and sorpia.MeshError for an empty or non-finite array.
    """
    shape = "(n, 3)" if columns == 3 else "(n, k)" if columns is None else f"(n, {columns})"
    arr = _asarray(vertices, name, f"an {shape} array of floats")
    if arr.dtype == bool or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise TypeError(f"{name} must be an {shape} array of real numbers, got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] < 1 or (columns is not None and arr.shape[1] != columns):
        hint = " (a scalar per vertex: values[:, None])" if arr.ndim == 1 and columns is None else ""
        raise MeshError(f"{name} must have shape {shape}{', k >= 1' if columns is None else ''}, "
                         f"got {arr.shape}{hint}")
    if arr.shape[0] == 0:
        raise MeshError(f"{name} is empty: a mesh needs at least one triangle")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if not np.isfinite(arr).all():  # the rows only when one is bad: a per-row reduction is much slower
        finite = np.isfinite(arr).all(axis=1)
        i = int(np.flatnonzero(~finite)[0])
        raise MeshError(f"{name}[{i}] = {arr[i].tolist()} is not finite (NaN or inf); "
                        f"{int((~finite).sum())} of {len(arr)} vertices are not")
    return arr


def as_vertex_count(n_vertices, name: str = "n_vertices") -> int:
    """Return `n_vertices` as an int >= 0; floats (even 12.0) and bools raise TypeError."""
    if isinstance(n_vertices, (bool, np.bool_)):
        raise TypeError(f"{name} must be an integer, got {n_vertices!r}")
    try:
        n = operator.index(n_vertices)
    except TypeError:
        raise TypeError(f"{name} must be an integer, got {n_vertices!r}") from None
    if n < 0:
        raise ParameterError(f"{name} = {n} must be >= 0")
    return n


_INT64_MAX = 2**63 - 1


def as_real(value, name: str) -> float:
    """An option that is a real number as a float: the one type check of scalar options (a bool, a string or None
    where a number belongs is a ParameterError); its range is the core's to check, once."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name} must be a real number, got {value!r}")
    return float(value)


def as_integer(value, name: str, what: str) -> int:
    """An option that is an integer as an int (`what` says which integers the option takes, for the message);
    beyond int64 it is clamped there, where the core names it as too large."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ParameterError(f"{name} = {value!r} must be {what}")
    return min(int(value), _INT64_MAX)


def _first_polygon(faces) -> tuple[int, int] | None:
    """(index, length) of the first row of a list of faces that is not a triple."""
    try:
        for i, row in enumerate(faces):
            if len(row) != 3:
                return i, len(row)
    except TypeError:  # rows without a length: not a list of polygons at all
        return None
    return None


def _not_triangles(what: str) -> str:
    return (f"{what}: Loop subdivision needs triangles; {TRIANGULATE_HINT}; or pass scheme=\"catmull-clark\" "
            "for the Catmull-Clark surface of the polygons as they are")


def _index_dtype(arr: np.ndarray, name: str, expected: str) -> None:
    """TypeError unless `arr` holds integers."""
    if arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer):
        if np.issubdtype(arr.dtype, np.floating):
            raise TypeError(f"{name} must hold integer vertex indices, got dtype {arr.dtype} (float indices are "
                            f"refused, as numpy refuses them; if they are whole numbers pass {name}.astype(int))")
        raise TypeError(f"{name} must be {expected}, got dtype {arr.dtype}")


def _check_range(indices: np.ndarray, offsets, n_vertices: int, name: str, count_name: str) -> None:
    """MeshError naming the first face (row f of `indices` when `offsets` is
    None, else indices[offsets[f]:offsets[f+1]]) with an index outside [0, n_vertices)."""
    if indices.min() >= 0 and indices.max() < n_vertices:  # two reductions; the rest only to name the face
        return
    flat = indices.ravel()
    h = int(np.flatnonzero((flat < 0) | (flat >= n_vertices))[0])
    if offsets is None:
        f = h // indices.shape[1]
        row = indices[f]
    else:
        f = int(np.searchsorted(offsets, h, side="right")) - 1
        row = flat[offsets[f]:offsets[f + 1]]
    message = f"{name}[{f}] = {row.tolist()} has vertex index {flat[h]} out of range [0, {n_vertices})"
    if flat[h] >= n_vertices:  # the count may be the mistake rather than the faces
        message += f": {count_name} = {n_vertices} is too small for {name}, whose largest vertex index is {flat.max()}"
    raise MeshError(message)


def _face_rows(faces, name: str, shape: str, expected: str):
    """`faces` as a 2-D integer array, or None for a ragged list of rows."""
    try:
        arr = np.asarray(faces)
    except (ValueError, TypeError) as exc:
        arr = None
        error = exc
    if arr is None or (arr.dtype == object and arr.ndim == 1):
        if _first_polygon(faces) is not None:
            return None
        if arr is None:
            raise TypeError(f"{name} must be {expected}: {error}") from None
    _index_dtype(arr, name, expected)
    if arr.ndim != 2:
        raise MeshError(f"{name} must have shape {shape}, got {arr.shape}")
    if arr.shape[0] == 0:
        raise MeshError(f"{name} is empty: a mesh needs at least one face")
    return arr


def as_faces(faces, n_vertices: int, name: str = "faces", count_name: str = "n_vertices") -> np.ndarray:
    """Return `faces` as a C-contiguous int32 (m, 3) array of indices in [0, n_vertices).

    Any integer dtype is accepted (signed or unsigned, any byte order);
    float, bool, complex and object arrays raise TypeError. Polygons with
    other than 3 vertices raise sorpia.MeshError saying how to triangulate
    them or to use the Catmull-Clark scheme (see `as_polygons`).
    `count_name` is what the caller calls the vertex count ("n_vertices",
    "len(vertices)"), named with its value when an index is too large for it.
    """
    n_vertices = as_vertex_count(n_vertices, count_name)
    if isinstance(faces, Polygons):
        counts, indices = as_polygons(faces, n_vertices, name, count_name)
        bad = np.flatnonzero(counts != 3)
        if len(bad):
            raise MeshError(_not_triangles(f"{name}[{bad[0]}] has {counts[bad[0]]} vertices"))
        return indices.reshape(-1, 3)
    arr = _face_rows(faces, name, "(m, 3)", "an (m, 3) array of integer vertex indices")
    if arr is None:
        i, k = _first_polygon(faces)
        if k < 3:
            raise MeshError(f"{name}[{i}] has {k} vertices: a face needs at least 3")
        raise MeshError(_not_triangles(f"{name}[{i}] has {k} vertices"))
    if arr.shape[1] != 3:
        raise MeshError(_not_triangles(f"{name} has {arr.shape[1]} vertices per face, shape {arr.shape}"))
    _check_range(arr, None, n_vertices, name, count_name)
    return np.ascontiguousarray(arr, dtype=np.int32)


def as_polygons(faces, n_vertices: int, name: str = "faces",
                count_name: str = "n_vertices") -> tuple[np.ndarray, np.ndarray]:
    """Return `faces` as ``(face_vertex_counts, face_vertex_indices)``, two
    C-contiguous int32 arrays (the form of OpenSubdiv's TopologyDescriptor).

    `faces` may be an (m, k) integer array (every face with k >= 3 vertices),
    a list of lists of any lengths, or a `sorpia.Polygons`. Every face needs at
    least 3 vertices and every index must lie in [0, n_vertices); dtypes as in
    `as_faces`. Repeated vertices, edges of three faces and the like are the
    core's checks (sorpia::Topology).
    """
    n_vertices = as_vertex_count(n_vertices, count_name)
    if isinstance(faces, Polygons):
        counts = _asarray(faces.face_vertex_counts, f"{name}.face_vertex_counts", "a 1-D array of integers")
        indices = _asarray(faces.face_vertex_indices, f"{name}.face_vertex_indices", "a 1-D array of integers")
        for arr, what in ((counts, "face_vertex_counts"), (indices, "face_vertex_indices")):
            _index_dtype(arr, f"{name}.{what}", "a 1-D array of integers")
            if arr.ndim != 1:
                raise MeshError(f"{name}.{what} must be one-dimensional, got shape {arr.shape}")
        if len(counts) == 0:
            raise MeshError(f"{name} is empty: a mesh needs at least one face")
        if counts.min() < 3:
            f = int(np.flatnonzero(counts < 3)[0])
            raise MeshError(f"{name}[{f}] has {counts[f]} vertices: a face needs at least 3")
        total = int(counts.sum(dtype=np.int64))
        if total != len(indices):
            raise MeshError(f"{name}.face_vertex_counts sum to {total} but {name}.face_vertex_indices has "
                            f"{len(indices)} entries")
        if total > np.iinfo(np.int32).max:
            raise MeshError(f"{name} has {total} face vertices: at most 2^31 - 1")
        offsets = np.concatenate([[0], np.cumsum(counts, dtype=np.int64)])
        _check_range(indices, offsets, n_vertices, name, count_name)
        return np.ascontiguousarray(counts, dtype=np.int32), np.ascontiguousarray(indices, dtype=np.int32)
    arr = _face_rows(faces, name, "(m, k)",
                     "an (m, k) array of integer vertex indices, a list of polygons or sorpia.Polygons")
    if arr is None:  # a ragged list: one row at a time
        rows = [np.asarray(row) for row in faces]
        counts = np.array([len(row) for row in rows], dtype=np.int64)
        short = np.flatnonzero(counts < 3)
        if len(short):
            raise MeshError(f"{name}[{short[0]}] has {counts[short[0]]} vertices: a face needs at least 3")
        for i, row in enumerate(rows):
            _index_dtype(row, f"{name}[{i}]", "a list of integer vertex indices")
        return as_polygons(Polygons(counts, np.concatenate(rows)), n_vertices, name, count_name)
    if arr.shape[1] < 3:
        raise MeshError(f"{name} has {arr.shape[1]} vertices per face, shape {arr.shape}: a face needs at least 3")
    _check_range(arr, None, n_vertices, name, count_name)
    return (np.full(arr.shape[0], arr.shape[1], dtype=np.int32),
            np.ascontiguousarray(arr, dtype=np.int32).ravel())


def as_boundary(boundary: str) -> _core.Boundary:
    """The core's Boundary for a rule's name; the names and the message of an
    unknown one come from the core (sorpia::parse_boundary)."""
    if not isinstance(boundary, str):
        raise ParameterError(f"boundary must be a string, got {boundary!r}")
    return _core.parse_boundary(boundary)


SCHEMES = tuple(_core.scheme_name(s) for s in _core.Scheme.__members__.values())
# The one default scheme of every entry point (library and command line): "auto", resolved by resolve_scheme.
AUTO_SCHEME = "auto"
DEFAULT_SCHEME = AUTO_SCHEME


def all_triangles(faces) -> bool:
    """Whether every face of `faces` (any form faces are accepted in) has 3
    vertices; what is not faces at all counts as triangles (as_faces names
    its problem)."""
    if isinstance(faces, Polygons):
        counts = np.asarray(faces.face_vertex_counts)
        return bool(counts.size and np.all(counts == 3))
    try:
        arr = np.asarray(faces)
    except (ValueError, TypeError):  # ragged nested lists
        arr = None
    if arr is not None and arr.ndim == 2 and arr.dtype != object:
        return arr.shape[1] == 3
    return _first_polygon(faces) is None


def resolve_scheme(scheme: str, faces: object = None, file_scheme: Optional[str] = None) -> str:
    """The subdivision scheme's name ("loop" or "catmull-clark") for a
    scheme option: the one place where "auto" is resolved, for the library
    and the command line alike.

    "auto" is the file's own scheme where it has one (`file_scheme`, a USD
    mesh's subdivisionScheme as `sorpia.read` gives it), else Loop when every
    face of `faces` is a triangle (`all_triangles`) and Catmull-Clark
    otherwise. A scheme named explicitly is returned as it is, checked.
    ParameterError for anything else (the names come from the core,
    sorpia::parse_scheme), and for "auto" without faces or a file's scheme.
    """
    if not isinstance(scheme, str):
        raise ParameterError(f"scheme must be a string, got {scheme!r}")
    if scheme == AUTO_SCHEME:
        if file_scheme is not None:
            return resolve_scheme(file_scheme)
        if faces is None:
            raise ParameterError('scheme="auto" needs the faces to choose from')
        return "loop" if all_triangles(faces) else "catmull-clark"
    try:
        return _core.scheme_name(_core.parse_scheme(scheme))
    except ParameterError as exc:
        raise ParameterError(f"{exc}, or 'auto' (Loop for triangles, else Catmull-Clark)") from None


def as_scheme(scheme: str, faces=None) -> _core.Scheme:
    """The core's Scheme for a scheme option (`resolve_scheme`)."""
    return _core.parse_scheme(resolve_scheme(scheme, faces))


NONMANIFOLD_MODES = ("error", "sharp")
DEFAULT_NONMANIFOLD = "error"


def as_nonmanifold(value) -> str:
    """"error" or "sharp" (what non-manifold topology gets), checked."""
    if value not in NONMANIFOLD_MODES:
        raise ParameterError(f"nonmanifold must be one of {', '.join(map(repr, NONMANIFOLD_MODES))}, got {value!r}")
    return value


def as_rules(faces, n_vertices, *, scheme, boundary, creases=None, corners=None, holes=None,
             count_name: str = "n_vertices") -> tuple[tuple, int, _core.Rules]:
    """The one check of a mesh's faces and its rule options (scheme, boundary,
    creases, corners, holes) for the core: returns (face arrays, n_vertices,
    rules), the face arrays ``(triangles,)`` (int32 (m, 3)) under Loop and
    ``(face_vertex_counts, face_vertex_indices)`` under Catmull-Clark, as
    _core.Topology and _core.Interpolator take them."""
    n_vertices = as_vertex_count(n_vertices, count_name)
    boundary_value = as_boundary(boundary)
    scheme_value = as_scheme(scheme, faces)
    if scheme_value == _core.Scheme.loop:
        arrays = (as_faces(faces, n_vertices, count_name=count_name),)
    else:
        arrays = as_polygons(faces, n_vertices, count_name=count_name)
    tags = as_tags(creases, corners, holes, n_vertices=n_vertices, n_faces=len(arrays[0]))
    return arrays, n_vertices, _core.Rules(scheme=scheme_value, boundary=boundary_value, tags=tags)


class Polygons(NamedTuple):
    """Faces of any sizes in the counts + indices form of OpenSubdiv's
    Far::TopologyDescriptor and USD: face f has ``face_vertex_counts[f]``
    vertices, listed in ``face_vertex_indices`` after those of faces 0..f-1.
    Accepted wherever faces are."""

    face_vertex_counts: np.ndarray
    face_vertex_indices: np.ndarray


def _tag_indices(value, name: str, width: int) -> np.ndarray:
    arr = _asarray(value, name, "an array of integer indices")
    if arr.size == 0:
        return np.zeros((0, width) if width > 1 else 0, dtype=np.int32)
    if arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{name} must hold integer indices, got dtype {arr.dtype}")
    if width > 1 and (arr.ndim != 2 or arr.shape[1] != width):
        raise MeshError(f"{name} must have shape (k, {width}), got {arr.shape}")
    if width == 1 and arr.ndim != 1:
        raise MeshError(f"{name} must have shape (k,), got {arr.shape}")
    if arr.min() < np.iinfo(np.int32).min or arr.max() > np.iinfo(np.int32).max:
        raise MeshError(f"{name} holds an index that does not fit in 32 bits")
    return np.ascontiguousarray(arr, dtype=np.int32)


def _tag_sharpness(value, name: str, k: int) -> np.ndarray:
    arr = _asarray(value, name, "a number or an array of numbers")
    if arr.dtype == bool or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise TypeError(f"{name} must be real numbers, got dtype {arr.dtype}")
    if arr.ndim == 0:
        arr = np.full(k, float(arr))
    if arr.shape != (k,):
        raise MeshError(f"{name} must be a number or have shape ({k},), got {arr.shape}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    return np.where(np.isposinf(arr), _core.INFINITE_SHARPNESS, arr)


def _pair(value, name: str):
    if isinstance(value, tuple) and len(value) == 2:
        return value
    raise TypeError(f"{name} must be a pair (indices, sharpness), got {type(value).__name__}")


def as_tags(creases=None, corners=None, holes=None, *, n_vertices: int, n_faces: int) -> _core.Tags:
    """OpenSubdiv's sharpness tags as the core's Tags, checked (sorpia::check_tags).

    ``creases = (edges (k, 2) ints, sharpness)``, ``corners = (vertices (c,),
    sharpness)``, ``holes = faces (h,)``; a sharpness is a number for all or
    one per tag; inf (or anything >= 10, OpenSubdiv's Sdc::Crease::
    SHARPNESS_INFINITE) is infinitely sharp. None means no tag of that kind.
    """
    empty_i, empty_d = np.zeros(0, np.int32), np.zeros(0, np.float64)
    edges, edge_s, verts, vert_s, hole_faces = np.zeros((0, 2), np.int32), empty_d, empty_i, empty_d, empty_i
    if creases is not None:
        e, s = _pair(creases, "creases")
        edges = _tag_indices(e, "creases[0] (the edges)", 2)
        edge_s = _tag_sharpness(s, "creases[1] (the sharpness)", len(edges))
    if corners is not None:
        v, s = _pair(corners, "corners")
        verts = _tag_indices(v, "corners[0] (the vertices)", 1)
        vert_s = _tag_sharpness(s, "corners[1] (the sharpness)", len(verts))
    if holes is not None:
        hole_faces = _tag_indices(holes, "holes", 1)
    return _core.Tags(edges, edge_s, verts, vert_s, hole_faces, n_vertices, n_faces)
