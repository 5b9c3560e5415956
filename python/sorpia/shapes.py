"""Generated triangle and polygon meshes, for tests, benchmarks and the demo.

Each function returns ``(vertices, faces)``: float64 (n, 3) and int32 (m, 3)
for triangles, int32 (m, 4) for quads, or a `sorpia.Polygons` for mixed
polygons (the form `sorpia.read_mesh` returns), faces oriented
counter-clockwise seen from outside. Built by the C++ core, so
``sorpia-bench`` uses the very same meshes.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from . import _core
from ._validate import Polygons, as_vertex_count

# What the functions return: vertices (n, 3) float64 and faces (m, 3) or (m, 4) int32.
Mesh = tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]


def icosphere(level: int = 3) -> Mesh:
    """Unit sphere from the icosahedron split `level` times: 10*4**level + 2
    vertices, 12 of valence 5, the rest of valence 6."""
    return _core.icosphere(level)


def torus(nu: int = 32, nv: int = 16) -> Mesh:
    """Torus (radii 1 and 0.4) on an nu x nv vertex grid; every vertex has valence 6."""
    return _core.torus(nu, nv)


def grid(nu: int = 10, nv: int = 10) -> Mesh:
    """Open wavy square patch on an nu x nv vertex grid: a mesh with boundary,
    two one-face corners."""
    return _core.grid(nu, nv)


def pole(n: int = 48) -> Mesh:
    """Disk with one interior vertex of valence `n` and two rings around it."""
    return _core.pole(n)


def irregular(n_vertices: int = 2000, seed: int = 1) -> Mesh:
    """Closed genus-1 mesh of about ``n_vertices`` vertices with random edge flips:
    valences 3 to 12, most vertices extraordinary."""
    return _core.irregular(as_vertex_count(n_vertices), seed)


def _quads(mesh) -> Mesh:
    vertices, counts, indices = mesh
    return vertices, indices.reshape(len(counts), 4)


def quad_torus(nu: int = 32, nv: int = 16) -> Mesh:
    """The torus of `torus` as nu x nv quads, (m, 4): every vertex of valence 4."""
    return _quads(_core.quad_torus(nu, nv))


def quad_grid(nu: int = 10, nv: int = 10) -> Mesh:
    """The patch of `grid` as (nu - 1) x (nv - 1) quads, (m, 4): boundary vertices
    of valence 3 and four one-face corners."""
    return _quads(_core.quad_grid(nu, nv))


def quad_irregular(n_vertices: int = 12000, seed: int = 1) -> Mesh:
    """A closed all-quad mesh of about ``n_vertices`` vertices with irregular
    vertices: `irregular` (n_vertices / 6) with each triangle split into three
    quads at its centroid and edge midpoints; valences 3 (the centroids), 4 (the
    midpoints) and 3..12 (the triangle mesh's vertices). Faces (m, 4)."""
    return _quads(_core.quad_irregular(as_vertex_count(n_vertices), seed))


def polygon_torus(nu: int = 32, nv: int = 16, seed: int = 1) -> tuple[npt.NDArray[np.float64], Polygons]:
    """`quad_torus` with quads split into triangles and joined into pentagons and
    hexagons at random: mixed polygons as a `sorpia.Polygons`."""
    vertices, counts, indices = _core.polygon_torus(nu, nv, seed)
    return vertices, Polygons(counts, indices)


__all__ = ["icosphere", "torus", "grid", "pole", "irregular", "quad_torus", "quad_grid", "quad_irregular",
           "polygon_torus"]
