"""Mesh files that keep every digit: OBJ, OFF, PLY and STL.

sorpia reads and writes these itself (C++, std::to_chars / std::from_chars)
rather than through OpenMesh, whose readers and writers go through float32.
"""

from __future__ import annotations

import os

from . import _core
from ._validate import as_faces, as_vertices


def read_mesh(path, triangulate: bool = False):
    """Read a triangle mesh from an .obj, .off, .ply or .stl file.

    Parameters
    ----------
    path : str or os.PathLike
        The file; its extension (any case) names the format.
    triangulate : bool
        Split polygons (faces of more than 3 vertices) into triangles, each
        polygon's triangles in its place in the face order. The split keeps the
        mesh manifold where it can: a quad is cut along its shorter diagonal
        unless that diagonal is already an edge of the mesh (then along the
        other); a larger polygon is fanned from its first corner whose
        diagonals are all new edges (else, and beyond 32 corners, from its first
        corner; fans are right for convex polygons). A new diagonal never repeats a face or gives an
        edge a third face. When False (the default) a polygon raises
        MeshFileError naming its line.

    Returns
    -------
    vertices : (n, 3) float64
        In file order, nothing merged or dropped (unreferenced vertices are
        kept). Text numbers are parsed with correct rounding, so a file written
        by `write_mesh` reads back bit for bit.
    faces : (m, 3) int32
        0-based vertex indices, in file order.

    Formats
    -------
    OBJ: ``v`` and ``f`` lines; ``f`` accepts ``a``, ``a/b``, ``a//c``,
    ``a/b/c`` and negative (relative) indices; texture coordinates, normals,
    groups, materials and every other statement are ignored.
    OFF: OFF/COFF/NOFF/STOFF headers (extra per-vertex numbers and face colours
    ignored), ``#`` comments. PLY: ascii, binary little- and big-endian; x, y, z
    of any numeric type and the ``vertex_indices`` list of the ``face`` element;
    other properties and elements are skipped. STL: ascii or binary (told apart
    by the binary size rule); coordinates are float32 by definition (ascii
    numbers are read as float32), and since STL stores each triangle's corners
    separately, corners with exactly equal coordinates (no tolerance) are
    merged into one vertex, numbered in order of first appearance.

    Raises
    ------
    MeshFileError
        (a ValueError) naming the file and the line (or element): missing
        file, directory, empty, truncated, not of the format, bad or
        out-of-range index, non-finite coordinate, a polygon without
        ``triangulate``, counts in the header the file cannot hold, no faces.
    """
    vertices, faces, _ = read_mesh_counting(path, triangulate)
    return vertices, faces


def read_mesh_counting(path, triangulate: bool = False):
    """`read_mesh`, and how many polygons it split: (vertices, faces,
    polygons); polygons is 0 without `triangulate` (a polygon is an error)."""
    return _core.read_mesh(os.fsencode(path), bool(triangulate))  # bytes: any file name the OS takes


def write_mesh(path, vertices, faces, binary: bool = False) -> None:
    """Write a triangle mesh to an .obj, .off, .ply or .stl file, atomically.

    The file is written to a temporary file in the same folder, flushed to disk
    and renamed over `path`: a failure (full disk, no permission, bad input)
    leaves no partial file, and an existing file is replaced whole or not at
    all.

    Parameters
    ----------
    path : str or os.PathLike
        The extension (any case) names the format.
    vertices : array_like, (n, 3) float
        Finite coordinates.
    faces : array_like, (m, 3) int
        Triangles, indices into `vertices`.
    binary : bool
        Binary PLY (little-endian) or binary STL; OBJ and OFF are text only
        (ParameterError).

    Notes
    -----
    OBJ, OFF and PLY keep float64 exactly: text numbers are the shortest
    decimal that reads back to the same double (std::to_chars), binary PLY
    stores ``double`` x, y, z and ``list uchar int vertex_indices``. STL
    stores float32 by definition: coordinates are rounded to float32, and
    vertices no face uses are not stored.
    """
    vertices = as_vertices(vertices)
    faces = as_faces(faces, vertices.shape[0], count_name="len(vertices)")
    _core.write_mesh(os.fsencode(path), vertices, faces, bool(binary))


__all__ = ["read_mesh", "write_mesh"]
