"""One value for a subdivision mesh: `SubdivisionMesh` (vertices, faces, the
rules of its limit surface and the attributes read with it), and the one way
every entry point takes it beside plain arrays (`mesh_arguments`).

Conventions of the entry points, which all follow from this type:

- a function of a mesh's coordinates takes ``(vertices, faces, **rules)``
  and also ``(mesh)`` (the mesh's own vertices) or ``(vertices, mesh)``
  (other per-vertex data on the mesh's faces and rules: control vertices,
  colours): ``interpolate(mesh)``, ``limit_surface(result.control_vertices,
  mesh)``;
- a function of the connectivity alone takes ``(faces, n_vertices,
  **rules)`` and also ``(mesh)``: ``Interpolator(mesh)``,
  ``limit_matrix(mesh)``, ``fairness_matrix(mesh)``;
- data that is not per vertex comes first: ``approximate(points, cage)``,
  ``write_mesh(path, mesh)``;
- after a mesh, further arguments are best given by keyword; the positional
  slot of `faces` is read as the next parameter where a function documents
  it (``limit_surface(mesh, 3)``, ``decimate(mesh, 500)``);
- a rule keyword given beside a mesh that carries another value is an error
  (`ParameterError` naming both): ``mesh.replace(scheme=...)`` makes the mesh
  with the other rule.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, NamedTuple, Optional, Union

import numpy as np
import numpy.typing as npt

from . import _core
from ._validate import (DEFAULT_BOUNDARY, DEFAULT_NONMANIFOLD, DEFAULT_SCHEME, Polygons, as_boundary,
                        as_faces, as_nonmanifold, as_polygons, as_tags, as_vertices, resolve_scheme)
from .errors import ParameterError

Faces = Union[npt.NDArray[np.integer[Any]], Polygons]
"""Faces as sorpia returns them: an (m, k) int32 array or `sorpia.Polygons`."""


class FaceVarying(NamedTuple):
    """Values given per face corner, as OpenSubdiv's face-varying channels
    (Far::TopologyDescriptor::FVarChannel) hold them: texture coordinates or
    normals.

    ``values`` (k, width) float64; ``indices`` (c,) int32, one per face corner
    in the faces' order (row by row of an (m, k) face array, or
    ``Polygons.face_vertex_indices``' order): corner j's value is
    ``values[indices[j]]``. A per-vertex attribute (PLY) has one value per
    vertex and the faces' vertex indices as ``indices``."""

    values: np.ndarray
    indices: np.ndarray


def tags_dict(core_tags: _core.Tags, boundary: Optional[_core.Boundary] = None) -> dict[str, Any]:
    """A _core.Tags (and Boundary or None) as read_mesh's keyword dict: only the kinds present."""
    out: dict[str, Any] = {}
    if len(core_tags.crease_sharpness):
        out["creases"] = (core_tags.crease_vertices, core_tags.crease_sharpness)
    if len(core_tags.corner_sharpness):
        out["corners"] = (core_tags.corner_vertices, core_tags.corner_sharpness)
    if len(core_tags.holes):
        out["holes"] = core_tags.holes
    if boundary is not None:
        out["boundary"] = _core.boundary_name(boundary)
    return out


def _read_only(arr: np.ndarray) -> np.ndarray:
    """`arr` if it is read-only already (a mesh's own, passed on by ``replace``), else a read-only view of it (the
    caller's array keeps its own flags)."""
    if not arr.flags.writeable:
        return arr
    view = arr.view()
    view.flags.writeable = False
    return view


# The rule keywords every entry point takes, with their one default each.
RULE_DEFAULTS: dict[str, Any] = {"scheme": DEFAULT_SCHEME, "boundary": DEFAULT_BOUNDARY, "creases": None,
                                 "corners": None, "holes": None, "nonmanifold": DEFAULT_NONMANIFOLD}


@dataclass(frozen=True, eq=False)
class SubdivisionMesh:
    """A subdivision mesh: control vertices, faces, the rules of its limit
    surface (scheme, boundary rule, OpenSubdiv's sharpness tags, what
    non-manifold topology gets) and the attributes read with it.

    Every function that takes ``(vertices, faces, scheme=, boundary=,
    creases=, corners=, holes=, nonmanifold=)`` also takes a mesh in their
    place (``sorpia.interpolate(mesh)``, ``sorpia.limit_surface(
    res.control_vertices, mesh)``; the conventions are in `sorpia._mesh`);
    `sorpia.read` returns one, and the results of `repair`, `decimate`,
    `fair_interpolate` and `approximate` carry one (``result.mesh``).

    The arrays are converted once, when the mesh is made (vertices to
    float64, faces to int32, tags to int32 indices and float64 sharpness;
    no copy where they are so already), and are read-only views: the mesh
    is a value, and ``replace`` or ``with_vertices`` make another one. The
    checks here are those of types, shapes and index ranges (`TypeError`,
    `ValueError`, `sorpia.MeshError`); the topology (manifold, oriented) is
    checked by the functions that build on it, where ``nonmanifold`` and
    `sorpia.repair` apply.

    Attributes
    ----------
    vertices : (n, 3) float64
    faces : (m, k) int32 or sorpia.Polygons
        An (m, k) array when every face has k vertices, else
        ``Polygons(face_vertex_counts, face_vertex_indices)``.
    scheme : {"loop", "catmull-clark"}
        Always resolved: "auto" (the default) is Loop when every face is a
        triangle, else Catmull-Clark (`sorpia.resolve_scheme`).
    boundary : {"edge-and-corner", "edge-only"}
    creases : (edges (k, 2) int32, sharpness (k,) float64) or None
    corners : (vertices (c,) int32, sharpness (c,) float64) or None
    holes : (h,) int32 or None
        As `sorpia.limit_points` takes them (a sharpness given as one number
        is stored as one per tag; inf stays inf).
    nonmanifold : {"error", "sharp"}
        What non-manifold topology gets (`sorpia.limit_points`).
    uvs, normals : FaceVarying or None
        Texture coordinates and normals, one index per face corner (as
        `sorpia.read_mesh` reads them with ``attributes=True``).

    Examples
    --------
    >>> V, F = sorpia.shapes.quad_torus(16, 8)
    >>> mesh = sorpia.SubdivisionMesh(V, F)
    >>> mesh.scheme
    'catmull-clark'
    >>> res = sorpia.interpolate(mesh)
    >>> np.abs(sorpia.limit_points(res.control_vertices, mesh) - V).max() < 1e-8
    True
    """

    vertices: np.ndarray
    faces: Faces
    scheme: str = DEFAULT_SCHEME
    boundary: str = DEFAULT_BOUNDARY
    creases: Optional[tuple[np.ndarray, np.ndarray]] = None
    corners: Optional[tuple[np.ndarray, np.ndarray]] = None
    holes: Optional[np.ndarray] = None
    nonmanifold: str = DEFAULT_NONMANIFOLD
    uvs: Optional[FaceVarying] = None
    normals: Optional[FaceVarying] = None

    def __post_init__(self) -> None:
        put = object.__setattr__  # frozen: the converted values are set once, here
        vertices = as_vertices(self.vertices)
        n = vertices.shape[0]
        scheme = resolve_scheme(self.scheme, self.faces)
        if scheme == "loop":
            faces: Faces = as_faces(self.faces, n, count_name="len(vertices)")
            n_faces = len(faces)
        else:
            counts, indices = as_polygons(self.faces, n, count_name="len(vertices)")
            n_faces = len(counts)
            given = self.faces
            if isinstance(given, np.ndarray) and given.dtype == np.int32 and given.ndim == 2 and \
                    given.flags.c_contiguous:  # checked above; kept (no copy, the same object for a mesh's own)
                faces = given
            elif (counts == counts[0]).all():
                faces = indices.reshape(n_faces, int(counts[0]))
            else:
                faces = Polygons(_read_only(counts), _read_only(indices))
        put(self, "vertices", _read_only(vertices))
        put(self, "faces", _read_only(faces) if isinstance(faces, np.ndarray) else faces)
        put(self, "scheme", scheme)
        put(self, "boundary", _core.boundary_name(as_boundary(self.boundary)))
        put(self, "nonmanifold", as_nonmanifold(self.nonmanifold))
        as_tags(self.creases, self.corners, self.holes, n_vertices=n, n_faces=n_faces)  # the tags' one check
        if self.creases is not None:
            edges = np.asarray(self.creases[0], dtype=np.int32).reshape(-1, 2)
            put(self, "creases", (_read_only(edges), _read_only(np.broadcast_to(
                np.asarray(self.creases[1], dtype=np.float64), (len(edges),)).copy())))
        if self.corners is not None:
            corners = np.asarray(self.corners[0], dtype=np.int32).reshape(-1)
            put(self, "corners", (_read_only(corners), _read_only(np.broadcast_to(
                np.asarray(self.corners[1], dtype=np.float64), (len(corners),)).copy())))
        if self.holes is not None:
            put(self, "holes", _read_only(np.asarray(self.holes, dtype=np.int32).reshape(-1)))
        for name in ("uvs", "normals"):
            channel = getattr(self, name)
            if channel is not None:
                try:
                    values, corner_indices = channel
                except (TypeError, ValueError):
                    raise ParameterError(f"{name} must be (values (k, width), indices (corners,)), e.g. a "
                                         "FaceVarying") from None
                put(self, name, FaceVarying(_read_only(np.asarray(values, dtype=np.float64)),
                                            _read_only(np.asarray(corner_indices, dtype=np.int32))))

    @property
    def n_vertices(self) -> int:
        """Number of vertices, n."""
        return int(self.vertices.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of faces, m."""
        if isinstance(self.faces, Polygons):
            return len(self.faces.face_vertex_counts)
        return int(self.faces.shape[0])

    @property
    def rules(self) -> dict[str, Any]:
        """The rule keywords, all six: ``f(vertices, faces, **mesh.rules)``
        equals ``f(mesh)``."""
        return {"scheme": self.scheme, "boundary": self.boundary, "creases": self.creases, "corners": self.corners,
                "holes": self.holes, "nonmanifold": self.nonmanifold}

    @property
    def tags(self) -> dict[str, Any]:
        """The sharpness tags and boundary rule as `sorpia.read_mesh` returns
        them with ``tags=True``: ``boundary`` and the kinds present among
        ``creases``, ``corners`` and ``holes``."""
        out: dict[str, Any] = {k: v for k, v in (("creases", self.creases), ("corners", self.corners),
                                                 ("holes", self.holes)) if v is not None}
        out["boundary"] = self.boundary
        return out

    @property
    def attributes(self) -> dict[str, FaceVarying]:
        """``uvs`` and ``normals``, those present, as `sorpia.read_mesh`
        returns them with ``attributes=True``."""
        return {k: v for k, v in (("uvs", self.uvs), ("normals", self.normals)) if v is not None}

    def with_vertices(self, vertices: npt.ArrayLike) -> SubdivisionMesh:
        """The same faces, rules and attributes with other vertices (a
        result's control vertices): ``mesh.with_vertices(res.control_vertices)``."""
        arr = as_vertices(vertices)
        if arr.shape[0] != self.n_vertices:
            raise ParameterError(f"vertices has {arr.shape[0]} rows but the mesh has {self.n_vertices} vertices")
        return dataclasses.replace(self, vertices=arr)

    def replace(self, **changes: Any) -> SubdivisionMesh:
        """A copy with some fields changed, checked as a new mesh is
        (``mesh.replace(scheme="catmull-clark", creases=None)``)."""
        return dataclasses.replace(self, **changes)

    def __reduce__(self) -> tuple[type, tuple[Any, ...]]:
        """Pickled as its fields and made again by the constructor (unpickled arrays would be writeable)."""
        return (SubdivisionMesh, tuple(getattr(self, f.name) for f in dataclasses.fields(self)))

    def __repr__(self) -> str:
        parts = [f"n_vertices={self.n_vertices}", f"n_faces={self.n_faces}", f"scheme={self.scheme!r}",
                 f"boundary={self.boundary!r}"]
        for name in ("creases", "corners"):
            value = getattr(self, name)
            if value is not None:
                parts.append(f"{name}={len(value[0])}")
        if self.holes is not None:
            parts.append(f"holes={len(self.holes)}")
        if self.nonmanifold != DEFAULT_NONMANIFOLD:
            parts.append(f"nonmanifold={self.nonmanifold!r}")
        parts += [f"{name}=<{len(getattr(self, name).values)} values>" for name in ("uvs", "normals")
                  if getattr(self, name) is not None]
        return "SubdivisionMesh(" + ", ".join(parts) + ")"


def _given(name: str, value: Any) -> bool:
    """Whether a rule keyword was given a value other than its default."""
    default = RULE_DEFAULTS[name]
    return value is not None if default is None else value != default


def mesh_arguments(vertices: Any, faces: Any, rules: dict[str, Any],
                   where: str = "this function") -> tuple[Any, Any, dict[str, Any]]:
    """``(vertices, faces, rules)`` for an entry point called with a
    `SubdivisionMesh` in the place of its vertices (``f(mesh)``) or of its
    faces (``f(vertices, mesh)``), else the arguments as they were given.

    `rules` holds the rule keywords the function was called with (any of the
    six). Beside a mesh, one given a value other than its default and other
    than the mesh's is a ParameterError: the mesh carries its rules."""
    if isinstance(vertices, SubdivisionMesh):
        if faces is not None:
            raise TypeError(f"{where}: faces come from the SubdivisionMesh given as vertices; pass the other "
                            f"arguments by keyword (got {type(faces).__name__} where faces would be)")
        mesh, vertices = vertices, vertices.vertices
    elif isinstance(faces, SubdivisionMesh):
        mesh = faces
    else:
        return vertices, faces, rules
    merged = mesh.rules
    for name, value in rules.items():
        if not _given(name, value):
            continue
        same = isinstance(value, str) and value == merged[name]
        if not same:
            shown = repr(value) if isinstance(value, str) else type(value).__name__
            raise ParameterError(f"{where}: {name}={shown} given beside a SubdivisionMesh whose {name} is "
                                 f"{merged[name]!r}: the mesh carries its rules; use mesh.replace({name}=...)")
    return vertices, mesh.faces, {name: merged[name] for name in rules}


def mesh_count(faces: Any, n_vertices: Optional[int], rules: dict[str, Any],
               where: str = "this function") -> tuple[Any, Any, dict[str, Any]]:
    """``(faces, n_vertices, rules)`` for an entry point of the connectivity
    alone (``f(faces, n_vertices, **rules)``) called as ``f(mesh)``; plain
    arguments pass through (`mesh_arguments` for the rules)."""
    if not isinstance(faces, SubdivisionMesh):
        return faces, n_vertices, rules
    if n_vertices is not None and n_vertices != faces.n_vertices:
        raise ParameterError(f"{where}: n_vertices = {n_vertices!r} given beside a SubdivisionMesh of "
                             f"{faces.n_vertices} vertices")
    _, mesh_faces, merged = mesh_arguments(faces, None, rules, where)
    return mesh_faces, faces.n_vertices, merged


__all__ = ["SubdivisionMesh", "FaceVarying", "Faces", "mesh_arguments", "mesh_count", "tags_dict"]
