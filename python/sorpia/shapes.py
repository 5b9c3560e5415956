"""Generated triangle meshes, for tests, benchmarks and the demo.

Each function returns ``(vertices, faces)``: float64 (n, 3) and int32 (m, 3),
faces oriented counter-clockwise seen from outside. Built by the C++ core, so
``sorpia-bench`` uses the very same meshes.
"""

from __future__ import annotations

from . import _core
from ._validate import as_vertex_count


def icosphere(level: int = 3):
    """Unit sphere from the icosahedron split `level` times: 10*4**level + 2
    vertices, 12 of valence 5, the rest of valence 6."""
    return _core.icosphere(level)


def torus(nu: int = 32, nv: int = 16):
    """Torus (radii 1 and 0.4) on an nu x nv vertex grid; every vertex has valence 6."""
    return _core.torus(nu, nv)


def grid(nu: int = 10, nv: int = 10):
    """Open wavy square patch on an nu x nv vertex grid: a mesh with boundary,
    two one-face corners."""
    return _core.grid(nu, nv)


def pole(n: int = 48):
    """Disk with one interior vertex of valence `n` and two rings around it."""
    return _core.pole(n)


def irregular(n_vertices: int = 2000, seed: int = 1):
    """Closed genus-1 mesh of about `n_vertices` vertices with random edge flips:
    valences 3 to 12, most vertices extraordinary."""
    return _core.irregular(as_vertex_count(n_vertices), seed)


__all__ = ["icosphere", "torus", "grid", "pole", "irregular"]
