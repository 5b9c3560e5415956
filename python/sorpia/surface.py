"""The Loop limit surface of a control mesh: evaluation at any (face, u, v) and
uniform tessellation, through OpenSubdiv (Bfr and Far).

Parameterisation of a face ``(a, b, c)`` (OpenSubdiv Bfr's triangle
parameterisation): ``(u, v) = (0, 0)`` is vertex ``a``, ``(1, 0)`` is ``b``,
``(0, 1)`` is ``c``; the face's limit patch is ``u >= 0, v >= 0, u + v <= 1``
(values a rounding error, 1e-12, outside are pulled onto it, others refused).
"""

from __future__ import annotations

import numpy as np

from . import _core
from ._validate import DEFAULT_BOUNDARY, as_boundary, as_vertices
from .errors import ParameterError
from .limit import topology


def _as_level(level) -> int:
    if isinstance(level, (bool, np.bool_)) or not isinstance(level, (int, np.integer)):
        raise ParameterError(f"level must be an integer in 0..15, got {level!r}")
    level = int(level)
    if not 0 <= level <= 15:
        raise ParameterError(f"level must be in 0..15, got {level}")
    return level


class LoopSurface:
    """The Loop limit surface of a triangle mesh: build once, query many.

    Keeps the validated topology and OpenSubdiv's structures (a Far topology
    refiner, the Bfr surface factory and its cache of irregular patches, and
    the refined topology of the last tessellation level), so that repeated
    evaluation, and new control vertices on the same faces (`set_vertices`, as
    in the PIA loop), cost no rebuild.

    Parameters
    ----------
    vertices : array_like, (n, 3) float
        Control vertices.
    faces : array_like, (m, 3) int
        Triangles, consistently oriented, manifold.
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule, as in `sorpia.limit_points`.

    Notes
    -----
    Parameterisation of face ``(a, b, c)``: ``(0, 0)`` is ``a``, ``(1, 0)`` is
    ``b``, ``(0, 1)`` is ``c``; ``u >= 0, v >= 0, u + v <= 1``.
    """

    def __init__(self, vertices, faces, boundary: str = DEFAULT_BOUNDARY):
        vertices = as_vertices(vertices)
        self._boundary = as_boundary(boundary)
        self._topology = topology(faces, vertices.shape[0], count_name="len(vertices)")
        self._surface = _core.LoopSurface(self._topology, vertices, self._boundary)

    @property
    def n_vertices(self) -> int:
        """Number of control vertices, n."""
        return self._surface.n_vertices

    @property
    def n_faces(self) -> int:
        """Number of control faces, m."""
        return self._surface.n_faces

    @property
    def boundary(self) -> str:
        """The boundary rule, "edge-and-corner" or "edge-only"."""
        return _core.boundary_name(self._boundary)

    @property
    def vertices(self) -> np.ndarray:
        """A copy of the control vertices, (n, 3) float64."""
        return self._surface.get_vertices()

    def set_vertices(self, vertices) -> None:
        """Replace the control vertices, (n, 3) float, on the same faces."""
        self._surface.set_vertices(as_vertices(vertices))

    def evaluate(self, face_ids, uv, derivatives: bool = False):
        """Limit positions at k points (face_ids[i], uv[i]), by OpenSubdiv's
        ``Bfr::Surface<double>::Evaluate``.

        Parameters
        ----------
        face_ids : array_like, (k,) int
            Face of each point, in [0, m).
        uv : array_like, (k, 2) float
            Parameters in the face: (0, 0) is its first vertex, (1, 0) its
            second, (0, 1) its third; u >= 0, v >= 0, u + v <= 1.
        derivatives : bool
            Also return the tangents and the unit normal.

        Returns
        -------
        positions : (k, 3) float64
            P(u, v). At a face corner this is the limit position B V of the
            corner vertex (paper eq. 6), under both boundary rules; on regular
            patches (box splines) it is the exact limit surface.
        du, dv : (k, 3) float64, only with ``derivatives=True``
            dP/du and dP/dv.
        normals : (k, 3) float64, only with ``derivatives=True``
            ``(dP/du x dP/dv) / |dP/du x dP/dv|``: outward for faces oriented
            counter-clockwise seen from outside; zero where the cross product
            vanishes.

        Notes
        -----
        Accuracy near extraordinary vertices: Bfr represents the surface in
        the corner triangle of side 1/16 (in u, v) at a vertex of valence
        other than 6 (4 on the boundary) by a Gregory triangle, after 4 local
        refinements. There positions approximate the limit surface (exactly
        at the corners of the refined triangles) and OpenSubdiv's derivatives
        approximate the derivatives of those positions (it drops the
        derivative of the rational Gregory weights): tangents within a few
        percent, normals within a few hundredths of a radian of finite
        differences (the tests hold them to 0.05 rad).
        Elsewhere tangents and normals agree with finite differences of the
        positions to 1e-9.
        """
        uv = np.asarray(uv)
        if uv.ndim != 2 or uv.shape[1] != 2:
            raise ParameterError(f"uv must have shape (k, 2), got {uv.shape}")
        if not np.issubdtype(uv.dtype, np.number) or np.iscomplexobj(uv):
            raise TypeError(f"uv must be an array of real numbers, got dtype {uv.dtype}")
        uv = np.ascontiguousarray(uv, dtype=np.float64)
        if not np.isfinite(uv).all():
            i = int(np.flatnonzero(~np.isfinite(uv).all(axis=1))[0])
            raise ParameterError(f"uv[{i}] = {uv[i].tolist()} is not finite")
        face_ids = np.asarray(face_ids)
        if face_ids.ndim != 1 or face_ids.shape[0] != uv.shape[0]:
            raise ParameterError(f"face_ids must have shape ({uv.shape[0]},) to match uv, got {face_ids.shape}")
        if face_ids.size and not np.issubdtype(face_ids.dtype, np.integer):
            raise TypeError(f"face_ids must be integers, got dtype {face_ids.dtype}")
        bad = (face_ids < 0) | (face_ids >= self.n_faces)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ParameterError(f"face_ids[{i}] = {int(face_ids[i])} is out of range [0, {self.n_faces})")
        face_ids = np.ascontiguousarray(face_ids, dtype=np.int32)
        return self._surface.evaluate(face_ids, uv, bool(derivatives))

    def tessellate(self, level: int = 3):
        """The limit surface as a triangle mesh; see `limit_surface`.

        The refined topology of the last level asked for is kept, so a second
        call at the same level (e.g. after `set_vertices`) only recomputes
        positions.
        """
        return self._surface.tessellate(_as_level(level))


def limit_surface(vertices, faces, level: int = 3, boundary: str = DEFAULT_BOUNDARY):
    """The Loop limit surface as a triangle mesh: uniform refinement to `level`
    with every output vertex at its exact limit position.

    Computed by OpenSubdiv's ``Far::PrimvarRefinerReal<double>``: positions
    interpolated level by level (the Loop masks, paper eq. 2-4), then each
    vertex of the last level moved to its limit position (paper eq. 5-6).

    Parameters
    ----------
    vertices : array_like, (n, 3) float
        Control vertices.
    faces : array_like, (m, 3) int
        Triangles, consistently oriented, manifold.
    level : int, 0..15
        Refinement level. Size grows as 4**level: the output has m * 4**level
        triangles and about n + m * (4**level - 1) / 2 vertices. Memory at the
        peak is about 270 bytes per output triangle (OpenSubdiv's refined
        topology of every level plus the output arrays), e.g. level 2 of a
        100k-vertex closed mesh (200k faces): 3.2M triangles, under 1 GB;
        level 3: 12.8M triangles, about 3.4 GB. A level whose estimate
        exceeds the memory left to the process now (free memory, ulimit -v,
        the cgroup's memory limit) raises ParameterError.
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule, as in `sorpia.limit_points`.

    Returns
    -------
    vertices : (n_s, 3) float64
        Limit positions. Rows 0..n-1 descend from the control vertices and
        equal ``limit_points(vertices, faces)`` (B V) exactly; unreferenced
        control vertices stay where they are.
    faces : (m * 4**level, 3) int32
        Triangles; rows ``f * 4**level .. (f + 1) * 4**level - 1`` cover
        control face f, with its orientation.
    """
    return LoopSurface(vertices, faces, boundary).tessellate(level)


def evaluate_limit(vertices, faces, face_ids, uv, derivatives: bool = False, boundary: str = DEFAULT_BOUNDARY):
    """Limit surface positions (and with ``derivatives=True`` the tangents and
    the unit normal) at points (face_ids[i], uv[i]); one-call form of
    ``LoopSurface(vertices, faces, boundary).evaluate(face_ids, uv, derivatives)``.

    Parameterisation of face ``(a, b, c)``: ``(0, 0)`` is ``a``, ``(1, 0)`` is
    ``b``, ``(0, 1)`` is ``c``; u >= 0, v >= 0, u + v <= 1. Evaluated with
    OpenSubdiv's Bfr, which is exact at face corners (equal to `limit_points`)
    under both boundary rules.

    Returns
    -------
    positions : (k, 3) float64, or the tuple (positions, du, dv, normals) of
    (k, 3) float64 arrays with ``derivatives=True``; see `LoopSurface.evaluate`.
    """
    return LoopSurface(vertices, faces, boundary).evaluate(face_ids, uv, derivatives)
