"""The limit surface of a control mesh under Loop or Catmull-Clark
subdivision, with OpenSubdiv's sharpness tags: evaluation at any
(face, u, v) and uniform tessellation, through OpenSubdiv (Bfr and Far).

Parameterisation of a face (OpenSubdiv Bfr's, chosen by the scheme and the
face's size k; values a rounding error, 1e-12, outside the domain are pulled
onto it, others refused):

- Loop, a triangle ``(a, b, c)``: ``(u, v) = (0, 0)`` is ``a``, ``(1, 0)`` is
  ``b``, ``(0, 1)`` is ``c``; the face is ``u >= 0, v >= 0, u + v <= 1``.
- Catmull-Clark, a quad ``(a, b, c, d)``: the unit square, ``(0, 0)`` is
  ``a``, ``(1, 0)`` is ``b``, ``(1, 1)`` is ``c``, ``(0, 1)`` is ``d``.
- Catmull-Clark, any other k-gon (a triangle included): the face's limit
  surface is k quad sub-faces, one at each corner (the quads of its first
  subdivision). Sub-face j is the square ``[x_j, x_j + 1/2] x [y_j, y_j +
  1/2]`` with ``(x_j, y_j) = (j % w, j // w)``, where w = 2 for k < 5, 3 for
  k = 5..9 and ``1 + isqrt(k - 1)`` from k = 10 (`subface_columns`).
  ``(x_j, y_j)`` is corner j, ``(x_j + 1/2, y_j)`` the midpoint of edge j
  (corner j to j + 1), ``(x_j, y_j + 1/2)`` the midpoint of edge j - 1 and
  ``(x_j + 1/2, y_j + 1/2)`` the centre of the face. Doubling the offset
  within a sub-face gives Ptex's coordinates of that sub-face.
"""

from __future__ import annotations

import numpy as np

from . import _core, _scipy
from ._mesh import SubdivisionMesh, mesh_arguments
from ._nonmanifold import split
from ._validate import (DEFAULT_BOUNDARY, DEFAULT_NONMANIFOLD, DEFAULT_SCHEME, Polygons, as_nonmanifold, as_rules,
                        as_vertices)
from .errors import ParameterError
from .limit import built, warn_unreferenced


def _as_level(level) -> int:
    if isinstance(level, (bool, np.bool_)) or not isinstance(level, (int, np.integer)):
        raise ParameterError(f"level must be an integer in 0..15, got {level!r}")
    level = int(level)
    if not 0 <= level <= 15:
        raise ParameterError(f"level must be in 0..15, got {level}")
    return level


def subface_columns(face_size: int) -> int:
    """Columns w of the grid of sub-faces of a k-gon under Catmull-Clark
    (k != 4): corner j of the face is at ``(u, v) = (j % w, j // w)``; the
    core's one definition (``sorpia/subface_grid.hpp``)."""
    return _core.subface_columns(int(face_size))


def corner_uv(scheme: str, face_size: int, corner: int) -> tuple[float, float]:
    """(u, v) of corner `corner` of a face of `face_size` vertices in Bfr's
    parameterisation under `scheme` (see the module docstring)."""
    k, j = int(face_size), int(corner)
    if scheme == "loop":
        return [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)][j]
    if k == 4:
        return [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)][j]
    w = subface_columns(k)
    return float(j % w), float(j // w)


def edge_uv(scheme: str, face_size: int, edge: int, t) -> np.ndarray:
    """(len(t), 2) parameters of the points at t in [0, 1] along edge `edge`
    (corner `edge` to corner `edge + 1`) of a face, in Bfr's
    parameterisation (Bfr::Parameterization::GetEdgeCoord): straight from
    corner to corner in a triangle or a quad; in a k-gon's sub-faces the
    first half runs in sub-face `edge` and the second in sub-face `edge + 1`."""
    t = np.asarray(t, dtype=float)[:, None]
    a = np.array(corner_uv(scheme, face_size, edge))
    b = np.array(corner_uv(scheme, face_size, (edge + 1) % face_size))
    if scheme == "loop" or face_size == 4:
        return a + t * (b - a)
    return np.where(t < 0.5, a + t * [1.0, 0.0], b + (1.0 - t) * [0.0, 1.0])


def _faces_out(faces, counts):
    """A tessellation's faces as the core returns them: an (m, k) array, or
    sorpia.Polygons when the sizes differ."""
    return faces if counts is None else Polygons(counts, faces)


class LimitSurface:
    """The limit surface of a control mesh under Loop or Catmull-Clark
    subdivision, with sharpness tags: build once, query many.

    Keeps the validated topology and OpenSubdiv's structures (a Far topology
    refiner carrying the tags, the Bfr surface factory and its cache of
    irregular patches, and the refined topology of the last tessellation
    level), so that repeated evaluation, and new control vertices on the same
    faces (`set_vertices`, as in the PIA loop), cost no rebuild.

    Parameters
    ----------
    vertices : array_like, (n, 3) float, or sorpia.SubdivisionMesh
        Control vertices; or a mesh (``LimitSurface(mesh)``: its vertices,
        faces and rules).
    faces : array_like or sorpia.SubdivisionMesh
        Faces, consistently oriented, manifold: an (m, 3) array for Loop; for
        Catmull-Clark any polygons; or a mesh whose faces and rules take
        `vertices` (``LimitSurface(control_vertices, mesh)``).
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule, as in `sorpia.limit_points`.
    scheme : {"auto", "loop", "catmull-clark"}
        Subdivision scheme (OpenSubdiv's SCHEME_LOOP or SCHEME_CATMARK);
        "auto": Loop for triangles, else Catmull-Clark.
    creases : (edges, sharpness), optional
        Sharp edges: an (k, 2) int array of vertex pairs and a sharpness per
        edge (or one for all); ``inf`` (or 10 and more) is infinitely sharp,
        smaller values are semi-sharp.
    corners : (vertex indices, sharpness), optional
        Sharp vertices, as for creases.
    holes : array_like of int, optional
        Faces that are holes: they have no limit surface.
    nonmanifold : {"error", "sharp"}
        "sharp": a non-manifold mesh is taken with OpenSubdiv's rules for it
        (edges of three or more faces infinitely sharp, non-manifold vertices
        corners), as `sorpia.limit_points` takes it: the surface is that of
        its manifold split (`sorpia._nonmanifold.split`), whose faces are the
        input's, in order, so face ids and (u, v) mean what they mean on the
        input. `vertices`, `set_vertices` and the rows of `tessellate` are
        the split's (the input's vertices, then the copies).

    Notes
    -----
    The parameterisation of each kind of face is described in the module
    docstring (`sorpia.surface`).
    """

    def __init__(self, vertices, faces=None, *, boundary: str = DEFAULT_BOUNDARY, scheme: str = DEFAULT_SCHEME,
                 creases=None, corners=None, holes=None, nonmanifold: str = DEFAULT_NONMANIFOLD):
        vertices, faces, rules = mesh_arguments(vertices, faces, dict(
            scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes, nonmanifold=nonmanifold),
            "LimitSurface")
        scheme, boundary, creases, corners, holes, nonmanifold = rules.values()
        vertices = as_vertices(vertices)
        self._vertex_map, self._n_input = None, vertices.shape[0]
        if as_nonmanifold(nonmanifold) == "sharp":
            s = split(faces, vertices.shape[0], boundary, creases=creases, corners=corners, holes=holes, stacklevel=3)
            if s is not None:
                self._vertex_map = s.vertex_map
                vertices, faces, boundary = vertices[s.vertex_map], s.faces, s.boundary
                creases, corners, holes = (s.tags.get(name) for name in ("creases", "corners", "holes"))
        # The faces and rules checked once (as_rules), as every entry point checks them.
        arrays, n, checked = as_rules(faces, vertices.shape[0], scheme=scheme, boundary=boundary, creases=creases,
                                      corners=corners, holes=holes, count_name="len(vertices)")
        self._topology = built(lambda: _core.Topology(*arrays, n))
        warn_unreferenced(self._topology, stacklevel=3)
        self._scheme, self._boundary = checked.scheme, checked.boundary
        self._surface = _core.LimitSurface(self._topology, vertices, checked.scheme, checked.boundary, checked.tags)

    @property
    def n_vertices(self) -> int:
        """Number of control vertices, n."""
        return self._surface.n_vertices

    @property
    def n_faces(self) -> int:
        """Number of control faces, m."""
        return self._surface.n_faces

    @property
    def scheme(self) -> str:
        """The subdivision scheme, "loop" or "catmull-clark"."""
        return _core.scheme_name(self._scheme)

    @property
    def boundary(self) -> str:
        """The boundary rule, "edge-and-corner" or "edge-only"."""
        return _core.boundary_name(self._boundary)

    @property
    def vertices(self) -> np.ndarray:
        """A copy of the control vertices, (n, 3) float64."""
        return self._surface.get_vertices()

    def set_vertices(self, vertices) -> None:
        """Replace the control vertices, (n, 3) float, on the same faces (with
        nonmanifold="sharp", those of the input mesh or of its split)."""
        vertices = as_vertices(vertices)
        if self._vertex_map is not None and vertices.shape[0] == self._n_input:
            vertices = vertices[self._vertex_map]
        self._surface.set_vertices(vertices)

    def evaluate(self, face_ids, uv, derivatives: bool = False):
        """Limit positions at k points (face_ids[i], uv[i]), by OpenSubdiv's
        ``Bfr::Surface<double>::Evaluate``.

        Parameters
        ----------
        face_ids : array_like, (k,) int
            Face of each point, in [0, m); not a hole.
        uv : array_like, (k, 2) float
            Parameters in the face (see the module docstring): for a Loop
            triangle (0, 0) is its first vertex, (1, 0) its second, (0, 1)
            its third; for a Catmull-Clark quad the unit square, (0, 0) its
            first vertex, (1, 0), (1, 1), (0, 1) the next ones; for another
            k-gon corner j is at ``(j % w, j // w)`` with ``w =
            subface_columns(k)``, and the points of sub-face j are within 1/2
            of it in u and v.
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
        the corner region of side 1/16 (in u, v) at an extraordinary vertex
        (valence other than 6 for Loop, 4 for Catmull-Clark; 4 and 3 on the
        boundary) by a Gregory patch, after 4 local refinements (10 on a mesh
        with darts, so that the points next to a dart's corner meet it). There
        positions approximate the limit surface (exactly at the corners of the
        refined faces) and OpenSubdiv's derivatives approximate the
        derivatives of those positions (it drops the derivative of the
        rational Gregory weights): tangents within a few percent, normals
        within a few hundredths of a radian of finite differences (the tests
        hold them to 0.05 rad). Semi-sharp creases and corners are resolved
        by Bfr's local refinement until their sharpness has decayed. At a
        dart (an interior vertex with one infinitely sharp edge) Bfr's own
        corner is OpenSubdiv's ``Limit()`` after those 4 refinements, not the
        limit of refinement: the corner itself is taken from B (exact), and
        points next to it start from Bfr's point (the Creases page says more).
        Elsewhere tangents and normals agree with finite differences of the
        positions to 1e-9.
        """
        face_ids, uv = self._points(face_ids, uv)
        return self._surface.evaluate(face_ids, uv, bool(derivatives))

    def _points(self, face_ids, uv):
        """(face_ids, uv) as the core takes them: int32 (k,), float64 (k, 2), checked."""
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
        return face_ids, uv

    def rows(self, face_ids, uv, derivatives: int = 0):
        """Rows of the limit surface at k points: the weights of the control
        vertices in each point and its derivatives, so that
        ``rows[0] @ vertices`` is `evaluate`'s positions (to rounding) and
        ``rows[1] @ vertices`` its ``du``, and so on.

        These are what fitting composes into its linear systems (the limit
        matrix B holds the same rows at the vertices). They come from
        OpenSubdiv's ``Bfr::Surface::EvaluateStencil`` over each face's control
        points, and do not depend on the control vertices.

        Parameters
        ----------
        face_ids, uv : array_like
            The points, as in `evaluate`.
        derivatives : {0, 1, 2}
            0: positions; 1: also dP/du, dP/dv; 2: also the second
            derivatives d2P/du2, d2P/dudv, d2P/dv2.

        Returns
        -------
        tuple of scipy.sparse.csr_matrix, each (k, n)
            ``(position,)``, ``(position, du, dv)`` or ``(position, du, dv,
            duu, duv, dvv)``; n is the number of control vertices (with
            nonmanifold="sharp", of the input's vertices: the weights of a
            vertex's copies add up). At a dart's corner, and at an interior
            vertex of two faces under Catmull-Clark, the position row is the
            vertex's row of B (as `evaluate` takes it); near extraordinary
            vertices the derivative rows are those of Bfr's Gregory patches
            (see `evaluate`'s notes).
        """
        sparse = _scipy.sparse("LimitSurface.rows")

        if isinstance(derivatives, bool) or derivatives not in (0, 1, 2):
            raise ParameterError(f"derivatives = {derivatives!r} must be 0, 1 or 2")
        face_ids, uv = self._points(face_ids, uv)
        n = self.n_vertices
        mats = [sparse.csr_matrix(t, shape=(len(face_ids), n))
                for t in self._surface.rows(face_ids, uv, int(derivatives))]
        if self._vertex_map is not None:
            # V_split = V[vertex_map]: compose with the selection matrix.
            select = sparse.csr_matrix((np.ones(n), (np.arange(n), self._vertex_map)),
                                       shape=(n, self._n_input))
            mats = [(m @ select).tocsr() for m in mats]
            for m in mats:
                m.sort_indices()
        return tuple(mats)

    def tessellate(self, level: int = 3):
        """The limit surface as a mesh; see `limit_surface`.

        The refined topology of the last level asked for is kept, so a second
        call at the same level (e.g. after `set_vertices`) only recomputes
        positions.
        """
        vertices, faces, counts = self._surface.tessellate(_as_level(level))
        return vertices, _faces_out(faces, counts)


def limit_surface(vertices, faces=None, level: int = 3, *, boundary: str = DEFAULT_BOUNDARY,
                  scheme: str = DEFAULT_SCHEME, creases=None, corners=None, holes=None,
                  nonmanifold: str = DEFAULT_NONMANIFOLD):
    """The limit surface as a mesh: uniform refinement to `level` with every
    output vertex at its exact limit position.

    Computed by OpenSubdiv's ``Far::PrimvarRefinerReal<double>``: positions
    interpolated level by level (the scheme's refinement masks, paper eq.
    2-4 for Loop), then each vertex of the last level moved to its limit
    position (paper eq. 5-6). With semi-sharp tags the refinement goes on
    until every sharpness has decayed (level ``ceil`` of the largest one),
    where OpenSubdiv's limit masks are exact, and each output vertex takes
    the limit position of its descendant there.

    Parameters
    ----------
    vertices : array_like, (n, 3) float, or sorpia.SubdivisionMesh
        Control vertices, or a mesh (``limit_surface(mesh, level)``: the
        level then comes second).
    faces : array_like or sorpia.SubdivisionMesh
        Faces, consistently oriented, manifold; see `LimitSurface`.
    level : int, 0..15
        Refinement level. Loop: the output has m * 4**level triangles and
        about n + m * (4**level - 1) / 2 vertices. Catmull-Clark: level 0 is
        the control polygons; from level 1 a k-sided face gives
        k * 4**(level - 1) quads, and the output has about as many vertices as
        quads. Memory at the peak is about 270 bytes per output triangle and
        380 per output quad (OpenSubdiv's refined topology of every level
        plus the output arrays), e.g. Loop level 2 of a 100k-vertex closed
        mesh (200k faces): 3.2M triangles, under 1 GB; level 3: 12.8M
        triangles, about 3.4 GB. A level whose estimate exceeds the memory
        left to the process now (free memory, ulimit -v, the cgroup's memory
        limit) raises ParameterError.
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule, as in `sorpia.limit_points`.
    scheme, creases, corners, holes, nonmanifold
        As in `LimitSurface`.

    Returns
    -------
    vertices : (n_s, 3) float64
        Limit positions. Rows 0..n-1 descend from the control vertices and
        equal ``limit_points(vertices, faces)`` (B V); unreferenced control
        vertices stay where they are. The vertices of a level are the first
        rows of every higher level's, in the same order.
    faces : (m_s, 3) or (m_s, 4) int32, or sorpia.Polygons
        Triangles (Loop) or quads (Catmull-Clark); the control polygons at
        Catmull-Clark's level 0 (sorpia.Polygons when their sizes differ).
        The faces refined from control face f are one block of rows, after
        those of the faces before it, with f's orientation
        (``f * 4**level .. (f + 1) * 4**level - 1`` for Loop). Faces of holes
        are left out.
    """
    if isinstance(vertices, SubdivisionMesh) and faces is not None:  # limit_surface(mesh, level)
        faces, level = None, faces
    return LimitSurface(vertices, faces, boundary=boundary, scheme=scheme, creases=creases, corners=corners,
                        holes=holes, nonmanifold=nonmanifold).tessellate(level)


def evaluate_limit(vertices, faces, face_ids=None, uv=None, derivatives: bool = False, *,
                   boundary: str = DEFAULT_BOUNDARY, scheme: str = DEFAULT_SCHEME, creases=None, corners=None,
                   holes=None, nonmanifold: str = DEFAULT_NONMANIFOLD):
    """Limit surface positions (and with ``derivatives=True`` the tangents and
    the unit normal) at points (face_ids[i], uv[i]); one-call form of
    ``LimitSurface(vertices, faces, boundary=..., scheme=..., ...).evaluate(face_ids,
    uv, derivatives)``; the rule options (boundary, scheme, creases, corners,
    holes, nonmanifold) as in `LimitSurface`. With a `sorpia.SubdivisionMesh`:
    ``evaluate_limit(mesh, face_ids, uv)`` or ``evaluate_limit(
    control_vertices, mesh, face_ids, uv)``.

    The parameterisation of each kind of face is in `LimitSurface.evaluate`
    and the module docstring; for a Loop triangle ``(a, b, c)``, ``(0, 0)`` is
    ``a``, ``(1, 0)`` is ``b``, ``(0, 1)`` is ``c``. Evaluated with
    OpenSubdiv's Bfr, which is exact at face corners (equal to `limit_points`)
    under both boundary rules.

    Returns
    -------
    positions : (k, 3) float64, or the tuple (positions, du, dv, normals) of
    (k, 3) float64 arrays with ``derivatives=True``; see `LimitSurface.evaluate`.
    """
    if isinstance(vertices, SubdivisionMesh):  # evaluate_limit(mesh, face_ids, uv[, derivatives])
        if uv is not None and not isinstance(uv, bool):
            raise TypeError("evaluate_limit(mesh, face_ids, uv, derivatives): too many positional arguments")
        faces, face_ids, uv, derivatives = None, faces, face_ids, derivatives if uv is None else uv
    if face_ids is None or uv is None:
        raise TypeError("evaluate_limit needs face_ids and uv")
    return LimitSurface(vertices, faces, boundary=boundary, scheme=scheme, creases=creases, corners=corners,
                        holes=holes, nonmanifold=nonmanifold).evaluate(face_ids, uv, derivatives)
