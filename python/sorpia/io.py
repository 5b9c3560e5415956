"""Mesh files that keep every digit: OBJ, OFF, PLY and STL.

sorpia reads and writes these itself (C++, std::to_chars / std::from_chars)
rather than through OpenMesh, whose readers and writers go through float32.
"""

from __future__ import annotations

import os
import warnings
from typing import NamedTuple

import numpy as np

from . import _core
from ._validate import Polygons, as_boundary, as_polygons, as_tags, as_vertices
from .errors import UnknownTagWarning


def read_mesh(path, triangulate: bool = False, tags: bool = False):
    """Read a mesh from an .obj, .off, .ply or .stl file.

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
        edge a third face. When False (the default) polygons are returned as
        they are.
    tags : bool
        Also read OpenSubdiv's sharpness tags from an OBJ file (``t`` lines,
        see Tags below) and return them as a third value. Other formats have
        no tags (an empty dict).

    Returns
    -------
    vertices : (n, 3) float64
        In file order, nothing merged or dropped (unreferenced vertices are
        kept). Text numbers are parsed with correct rounding, so a file written
        by `write_mesh` reads back bit for bit.
    faces : (m, k) int32 or sorpia.Polygons
        0-based vertex indices, in file order: an (m, k) array when every face
        has k vertices (an (m, 3) triangle array, an (m, 4) quad array, and
        always (m, 3) with ``triangulate``), else ``sorpia.Polygons(
        face_vertex_counts, face_vertex_indices)`` (int32 arrays: face f has
        ``face_vertex_counts[f]`` vertices, listed in ``face_vertex_indices``
        after those of the faces before it), the form of OpenSubdiv's
        Far::TopologyDescriptor and USD. Either form is accepted wherever
        faces are.
    tags : dict
        Only with ``tags=True``: the keys among ``creases``, ``corners``,
        ``holes`` and ``boundary`` that the file sets, ready for
        ``interpolate(vertices, faces, **tags)`` and ``write_mesh(path,
        vertices, faces, **tags)``: ``creases = (edges (k, 2) int32,
        sharpness (k,) float64)``, ``corners = (vertices (c,) int32,
        sharpness (c,) float64)``, ``holes = faces (h,) int32``, ``boundary =
        "edge-and-corner" | "edge-only"``. Indices are 0-based, as in the
        tags; with ``triangulate`` a hole is every triangle of its face.
        Sharpness is as written (10 and above, or inf, is infinitely sharp;
        a negative one reads as 0, as OpenSubdiv reads it).

    Notes
    -----
    **Tags.** The ``t`` lines of OpenSubdiv's shapes, read as its shape parser reads
    them (``t NAME I/F/S`` then I integers, F numbers, S words):
    ``t crease 2/1/0 A B S`` (an edge; 2k integers are k edges, pairs not a
    chain, with one sharpness for all or one each), ``t corner 1/1/0 V S``,
    ``t hole K/0/0 F...``, ``t interpolateboundary 1/0/0 MODE`` (1:
    edge-and-corner, 2: edge-only; 0, OpenSubdiv's "none", is refused),
    ``t creasemethod 0/0/1 normal`` (``chaikin`` is refused: sorpia's
    semi-sharp creases decay uniformly) and
    ``t smoothtriangles 0/0/1 catmark`` (``smooth`` is refused). The face-varying tags are skipped
    (they do not move vertices); any other name is skipped with an
    `UnknownTagWarning`.

    **Formats.** OBJ: ``v``, ``f`` and (with ``tags``) ``t`` lines; ``f`` accepts ``a``, ``a/b``, ``a//c``,
    ``a/b/c`` and negative (relative) indices; texture coordinates, normals,
    groups, materials and every other statement are ignored.
    OFF: OFF/COFF/NOFF/STOFF headers (extra per-vertex numbers and face colours
    ignored), ``#`` comments, records running over several lines. PLY: ascii, binary little- and big-endian; x, y, z
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
        out-of-range index, a face of fewer than 3 vertices, non-finite
        coordinate, counts in the header the file cannot hold, no faces; with
        ``tags``, a malformed tag, an index out of range, or a rule sorpia
        does not have (above).
    """
    contents = read_mesh_file(path, triangulate, tags)
    if not tags:
        return contents.vertices, contents.faces
    return contents.vertices, contents.faces, contents.tags


class MeshFileContents(NamedTuple):
    """What `read_mesh_file` returns: read_mesh's values and how many polygons were split."""

    vertices: np.ndarray
    faces: object  # (m, k) int32 array or Polygons
    tags: dict | None  # None unless asked for
    polygons_split: int


def read_mesh_file(path, triangulate: bool = False, tags: bool = False) -> MeshFileContents:
    """`read_mesh` with the count of polygons it split (0 without
    `triangulate`); warns (UnknownTagWarning) of tags it skipped."""
    vertices, faces, counts, split, file_tags = _core.read_mesh(os.fsencode(path), bool(triangulate), bool(tags))
    if counts is not None:
        faces = Polygons(counts, faces)
    tag_dict = None
    if tags:
        core_tags, boundary, unknown = file_tags
        tag_dict = tags_dict(core_tags, boundary)
        for text in unknown:
            warnings.warn(f"{os.fsdecode(path)}: skipped tag {text}: sorpia does not know it (OpenSubdiv skips it "
                          "too)", UnknownTagWarning, stacklevel=3)
    return MeshFileContents(vertices, faces, tag_dict, int(split))


def tags_dict(core_tags, boundary=None) -> dict:
    """A _core.Tags (and Boundary or None) as read_mesh's keyword dict: only the kinds present."""
    out: dict = {}
    if len(core_tags.crease_sharpness):
        out["creases"] = (core_tags.crease_vertices, core_tags.crease_sharpness)
    if len(core_tags.corner_sharpness):
        out["corners"] = (core_tags.corner_vertices, core_tags.corner_sharpness)
    if len(core_tags.holes):
        out["holes"] = core_tags.holes
    if boundary is not None:
        out["boundary"] = _core.boundary_name(boundary)
    return out


def write_mesh(path, vertices, faces, binary: bool = False, *, creases=None, corners=None, holes=None,
               boundary=None) -> None:
    """Write a mesh to an .obj, .off, .ply or .stl file, atomically.

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
    faces : (m, k) int array, list of index lists, or sorpia.Polygons
        Faces of 3 or more vertices (any mix in OBJ, OFF and PLY; STL stores
        triangles only: anything else is a ParameterError).
    binary : bool
        Binary PLY (little-endian) or binary STL; OBJ and OFF are text only
        (ParameterError).
    creases, corners, holes, boundary
        Sharpness tags, as `read_mesh` returns them (``write_mesh(path, v, f,
        **tags)`` writes back what ``read_mesh(path, tags=True)`` read):
        written to OBJ as OpenSubdiv's ``t`` lines, one tag a line; another
        format is a ParameterError. Sharpness is written as given (inf as
        ``inf``), exactly.

    Notes
    -----
    OBJ, OFF and PLY keep float64 exactly: text numbers are the shortest
    decimal that reads back to the same double (std::to_chars), binary PLY
    stores ``double`` x, y, z and ``list uchar int vertex_indices`` (``list
    int int`` when a face has more than 255 vertices). STL stores float32 by
    definition: coordinates are rounded to float32, and vertices no face uses
    are not stored.
    """
    vertices = as_vertices(vertices)
    n = vertices.shape[0]
    arr = faces if isinstance(faces, np.ndarray) else None
    if (arr is not None and arr.ndim == 2 and arr.dtype == np.int32 and arr.flags.c_contiguous
            and arr.shape[1] >= 3 and arr.size and arr.min() >= 0 and arr.max() < n):
        indices, counts, size = arr.reshape(-1), None, arr.shape[1]  # an (m, k) array: no copy, no counts
    else:
        counts, indices = as_polygons(faces, n, count_name="len(vertices)")
        size = int(counts[0])
        if (counts == size).all():
            counts = None
    core_tags = None
    if creases is not None or corners is not None or holes is not None:
        n_faces = len(indices) // size if counts is None else len(counts)
        core_tags = as_tags(creases, corners, holes, n_vertices=n, n_faces=n_faces)
    boundary_rule = None if boundary is None else as_boundary(boundary)
    _core.write_mesh(os.fsencode(path), vertices, indices, counts, size, bool(binary), core_tags, boundary_rule)


__all__ = ["read_mesh", "write_mesh", "UnknownTagWarning"]
