"""Mesh files that keep every digit: OBJ, OFF, PLY and STL; and USD.

sorpia reads and writes OBJ, OFF, PLY and STL itself (C++, std::to_chars /
std::from_chars) rather than through OpenMesh, whose readers and writers go
through float32. USD files (.usd, .usda, .usdc) go through usd-core
(``pip install sorpia[usd]``, see ``sorpia._usd``).
"""

from __future__ import annotations

import os
import warnings
from typing import NamedTuple, Optional

import numpy as np

from . import _core
from ._mesh import FaceVarying, SubdivisionMesh, mesh_arguments, tags_dict
from ._usd import _mesh as _usd_mesh
from ._usd import _open as _usd_open
from ._usd import is_usd, read_usd, write_usd
from ._validate import (AUTO_SCHEME, DEFAULT_BOUNDARY, Polygons, as_boundary, as_polygons, as_tags,
                        as_vertices, resolve_scheme)
from .errors import AttributeWarning, FormatWarning, MeshFileError, ParameterError, UnknownTagWarning


def read_mesh(path, triangulate: bool = False, tags: bool = False, attributes: bool = False, *, prim=None):
    """Read a mesh from an .obj, .off, .ply, .stl, .usd, .usda or .usdc file
    as arrays: ``V, F = read_mesh(path)``, with ``tags`` and ``attributes``
    a third and fourth value.

    `sorpia.read` reads the same file into one `sorpia.SubdivisionMesh`
    (tags, scheme and attributes included), the form every function takes;
    this array form stays for the callers written for it.

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
        see Tags below) or a USD mesh (see USD below) and return them as a
        third value. Other formats have no tags (an empty dict).

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
    attributes : dict
        Only with ``attributes=True`` (returned after the tags when both are
        asked for): ``uvs`` (texture coordinates) and ``normals``, each a
        `FaceVarying` (values, one index per face corner), for those the file
        has: OBJ ``vt`` (2 or 3 numbers) and ``vn`` lines with the faces'
        ``a/b/c`` indices; PLY per-vertex ``u v`` (or ``s t``, ``texture_u
        texture_v``, ``texture_s texture_t``) and ``nx ny nz``. With
        ``triangulate`` each triangle corner keeps the value of its polygon's
        corner. OBJ values named by only some corners are dropped with an
        `AttributeWarning`. ``write_mesh(path, v, f, **attributes)`` writes
        them back.

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
    ``a/b/c`` and negative (relative) indices; texture coordinates and
    normals only with ``attributes``; groups, materials and every other
    statement are ignored.
    OFF: OFF/COFF/NOFF/STOFF headers (extra per-vertex numbers and face colours
    ignored), ``#`` comments, records running over several lines. PLY: ascii, binary little- and big-endian; x, y, z
    of any numeric type and the ``vertex_indices`` list of the ``face`` element;
    other properties and elements are skipped. STL: ascii or binary (told apart
    by the binary size rule); coordinates are float32 by definition (ascii
    numbers are read as float32), and since STL stores each triangle's corners
    separately, corners with exactly equal coordinates (no tolerance) are
    merged into one vertex, numbered in order of first appearance.

    **USD** (needs usd-core: ``pip install sorpia[usd]``). The mesh prim's
    ``points`` (float32 in USD: read exactly into float64) at the default time
    (time-sampled points without a default value: the first sample, with a
    `UsdWarning`), ``faceVertexCounts`` and ``faceVertexIndices`` (checked by
    UsdGeom.Mesh.ValidateTopology). With ``tags`` the dict also holds
    ``scheme`` (``subdivisionScheme`` catmullClark: "catmull-clark", loop:
    "loop"; bilinear and none are refused), always ``boundary``
    (``interpolateBoundary``, USD's fallback edgeAndCorner when not authored;
    none is refused), ``creases`` from ``creaseIndices``/``creaseLengths``/
    ``creaseSharpnesses`` (each chain of L vertices gives its L - 1 edges, a
    sharpness per crease or per edge), ``corners`` from ``cornerIndices``/
    ``cornerSharpnesses`` and ``holes`` from ``holeIndices``;
    ``triangleSubdivisionRule`` smooth is refused. With ``attributes``,
    ``uvs`` from the ``st`` primvar and ``normals`` from the ``normals``
    primvar or attribute, face-varying (indexed or not) or per vertex; a
    constant or uniform one is left out with a `UsdWarning`. ``triangulate``
    is refused for USD.

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
    contents = read_mesh_file(path, triangulate, tags, attributes, prim)
    out = (contents.vertices, contents.faces)
    return out + ((contents.tags,) if tags else ()) + ((contents.attributes,) if attributes else ())


def read(path: str | os.PathLike[str] | bytes, *, triangulate: bool = False,
         prim: Optional[str] = None) -> SubdivisionMesh:
    """Read a mesh file as one `SubdivisionMesh`: vertices, faces, the file's
    scheme, boundary rule and sharpness tags, and its texture coordinates and
    normals, whatever the file holds.

    The one shape of a mesh read: ``read_mesh(path)`` returns the arrays
    ``(vertices, faces)`` and, by its flags, the tags and attributes as a
    third and fourth value; this function reads them all into the mesh
    (``mesh.tags``, ``mesh.attributes``), which every function of sorpia
    takes: ``sorpia.interpolate(sorpia.read("part.obj"))``.

    The scheme is the file's own where it has one (a USD mesh's
    ``subdivisionScheme``), else "auto" resolved on the faces: Loop for
    triangles, Catmull-Clark otherwise (`resolve_scheme`). Formats, tags,
    attributes, `triangulate`, `prim` and the errors are `read_mesh`'s.
    """
    contents = read_mesh_file(path, triangulate, True, True, prim)
    tags = contents.tags or {}
    attributes = contents.attributes or {}
    return SubdivisionMesh(contents.vertices, contents.faces, scheme=tags.get("scheme") or AUTO_SCHEME,
                           boundary=tags.get("boundary", DEFAULT_BOUNDARY), creases=tags.get("creases"),
                           corners=tags.get("corners"), holes=tags.get("holes"), uvs=attributes.get("uvs"),
                           normals=attributes.get("normals"))


class MeshFileContents(NamedTuple):
    """What `read_mesh_file` returns: read_mesh's values and how many polygons were split."""

    vertices: np.ndarray
    faces: object  # (m, k) int32 array or Polygons
    tags: dict | None  # None unless asked for
    polygons_split: int
    attributes: dict | None = None  # None unless asked for
    scheme: str | None = None  # a USD mesh's subdivisionScheme (sorpia's name: "loop", "catmull-clark"; else USD's)


def read_mesh_file(path, triangulate: bool = False, tags: bool = False, attributes: bool = False, prim=None,
                   points: bool = False) -> MeshFileContents:
    """`read_mesh` with the count of polygons it split (0 without
    `triangulate`); warns (UnknownTagWarning) of tags it skipped and
    (AttributeWarning) of attributes it drops. `points`: a file without
    faces (a point cloud) is read, with faces of shape (0, 3)."""
    if is_usd(path):
        return _read_usd_file(path, triangulate, tags, attributes, prim)
    vertices, faces, counts, split, file_tags, file_attributes = _core.read_mesh(
        os.fsencode(path), bool(triangulate), bool(tags), bool(attributes), bool(points))
    if len(faces) == 0:
        faces = np.zeros((0, 3), dtype=np.int32)
    elif counts is not None:
        faces = Polygons(counts, faces)
    attribute_dict = None
    if attributes:
        attribute_dict = {}
        for name, channel in zip(ATTRIBUTE_WORDS, file_attributes):  # the core's order: uvs, normals
            if channel is None:
                continue
            label = ATTRIBUTE_WORDS[name]
            missing = np.flatnonzero(channel[1] < 0)
            if len(missing):
                warnings.warn(f"{os.fsdecode(path)}: {label} dropped: {len(missing)} of {len(channel[1])} face "
                              f"corners name none (the first is corner {missing[0]}), and a face-varying channel "
                              "needs one at every corner", AttributeWarning, stacklevel=3)
                continue
            attribute_dict[name] = FaceVarying(*channel)
    tag_dict = None
    if tags:
        core_tags, boundary, unknown = file_tags
        tag_dict = tags_dict(core_tags, boundary)
        for text in unknown:
            warnings.warn(f"{os.fsdecode(path)}: skipped tag {text}: sorpia does not know it (OpenSubdiv skips it "
                          "too)", UnknownTagWarning, stacklevel=3)
    return MeshFileContents(vertices, faces, tag_dict, int(split), attribute_dict)


def _read_usd_file(path, triangulate: bool, tags: bool, attributes: bool, prim) -> MeshFileContents:
    if triangulate:
        raise MeshFileError(f"{os.fsdecode(path)}: triangulate is not available for USD files (sorpia splits "
                            "polygons while reading OBJ, OFF and PLY): fit the polygons with Catmull-Clark")
    vertices, faces, tag_dict, channels, scheme = read_usd(path, prim=prim, tags=tags, attributes=attributes)
    attribute_dict = None if channels is None else {k: FaceVarying(*v) for k, v in channels.items()}
    return MeshFileContents(vertices, faces, tag_dict, 0, attribute_dict, scheme)


def write_mesh(path, vertices, faces=None, binary: bool = False, *, creases=None, corners=None, holes=None,
               boundary=None, uvs=None, normals=None, scheme=None, prim=None, template=None) -> None:
    """Write a mesh to an .obj, .off, .ply, .stl, .usd, .usda or .usdc file, atomically.

    The file is written to a temporary file in the same folder, flushed to disk
    and renamed over `path`: a failure (full disk, no permission, bad input)
    leaves no partial file, and an existing file is replaced whole or not at
    all.

    Parameters
    ----------
    path : str or os.PathLike
        The extension (any case) names the format.
    vertices : array_like, (n, 3) float, or sorpia.SubdivisionMesh
        Finite coordinates; or a mesh, written with its rules and attributes
        (``write_mesh(path, mesh)``, ``write_mesh(path, mesh, True)`` for
        binary): its tags, a boundary rule other than the default and its
        uvs and normals as the keywords below write them, its scheme in USD.
        A format that cannot hold what the mesh carries is a ParameterError
        (as for the keywords), as is OBJ, OFF, PLY or STL for a mesh whose
        scheme is not the one its faces imply ("auto": Loop for triangles):
        ``mesh.replace(...)`` drops what is not to be written.
    faces : (m, k) int array, list of index lists, or sorpia.Polygons
        Faces of 3 or more vertices (any mix in OBJ, OFF and PLY; STL stores
        triangles only: anything else is a ParameterError).
    binary : bool
        Binary PLY (little-endian) or binary STL; OBJ and OFF are text only
        (ParameterError).
    creases, corners, holes, boundary
        Sharpness tags, as `read_mesh` returns them (``write_mesh(path, v, f,
        **tags)`` writes back what ``read_mesh(path, tags=True)`` read):
        written to OBJ as OpenSubdiv's ``t`` lines, one tag a line, and to
        USD as the mesh's attributes (see Notes); another format is a
        ParameterError. Sharpness is written as given (inf as ``inf``),
        exactly in OBJ, rounded to float32 in USD (its type there).
    uvs, normals : FaceVarying or (values (k, width), indices (c,)), optional
        Texture coordinates (width 1 to 3) and normals (width 3), one index per
        face corner, as `read_mesh` returns them (``attributes=True``): OBJ
        ``vt``/``vn`` lines and ``f a/b/c`` corners; PLY per-vertex ``u v`` and
        ``nx ny nz`` (width 2 and 3), where every corner of a vertex must have
        the same value (a seam is a ParameterError: OBJ holds it); OFF and STL
        hold neither (ParameterError). USD: ``uvs`` the ``st`` primvar and
        ``normals`` the ``normals`` primvar, face-varying and indexed.
    scheme : "loop" or "catmull-clark", optional
        USD only (other formats do not hold it: ParameterError): the
        ``subdivisionScheme`` written (USD's fallback, catmullClark, when not
        given), as ``read_mesh(path, tags=True)`` returns it.
    prim : str, optional
        USD only: the mesh prim's path (default ``/Mesh``; with `template`,
        the template's mesh, chosen as `read_mesh` chooses it).
    template : str or os.PathLike, optional
        USD only: a USD file whose stage is written with this mesh put into
        its mesh prim (points, faces, scheme, tags, uvs); every other prim,
        transform and attribute stays as it was. Time samples of the points
        are cleared (the mesh written is one shape); when the faces differ
        from the template's, the mesh's per-point, per-face and per-corner
        primvars no longer fit and are blocked, with a `UsdWarning`. The
        template's root layer is what is written: its sublayers and
        references stay as authored.

    Notes
    -----
    OBJ, OFF and PLY keep float64 exactly: text numbers are the shortest
    decimal that reads back to the same double (std::to_chars), binary PLY
    stores ``double`` x, y, z and ``list uchar int vertex_indices`` (``list
    int int`` when a face has more than 255 vertices). STL stores float32 by
    definition: coordinates are rounded to float32, and vertices no face uses
    are not stored. USD stores ``points`` as float32 (point3f, the schema's
    type): coordinates are rounded to float32, and read back as written. Each
    crease edge is written as a crease of its own (``creaseLengths`` 2).
    """
    if isinstance(vertices, SubdivisionMesh):
        mesh = vertices
        if faces is not None:  # write_mesh(path, mesh, binary)
            if binary is not False or not isinstance(faces, bool):
                raise TypeError("write_mesh(path, mesh, binary): the faces come from the SubdivisionMesh")
            binary = faces
        given = [k for k, v in (("creases", creases), ("corners", corners), ("holes", holes), ("boundary", boundary),
                                ("uvs", uvs), ("normals", normals), ("scheme", scheme)) if v is not None]
        if given:
            raise ParameterError(f"write_mesh: {', '.join(given)} given beside a SubdivisionMesh, which carries its "
                                 "own: use mesh.replace(...)")
        vertices, faces = mesh.vertices, mesh.faces
        creases, corners, holes, uvs, normals = mesh.creases, mesh.corners, mesh.holes, mesh.uvs, mesh.normals
        boundary = None if mesh.boundary == DEFAULT_BOUNDARY else mesh.boundary
        if is_usd(path):
            scheme = mesh.scheme
        elif mesh.scheme != resolve_scheme(AUTO_SCHEME, mesh.faces):
            raise ParameterError(f"{os.fsdecode(path)}: the mesh's scheme {mesh.scheme!r} is not the one its faces "
                                 "imply, and OBJ, OFF, PLY and STL do not hold a scheme: write USD, or "
                                 "mesh.replace(scheme=\"auto\")")
    usd = is_usd(path)
    if not usd and (scheme is not None or prim is not None or template is not None):
        given = [k for k, v in (("scheme", scheme), ("prim", prim), ("template", template)) if v is not None]
        raise ParameterError(f"{os.fsdecode(path)}: {', '.join(given)} apply to USD files only (.usd, .usda, "
                             ".usdc); OBJ, OFF, PLY and STL do not hold them")
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
    channels = [_as_face_varying(channel, name, len(indices), width)
                for channel, name, width in ((uvs, "uvs", (1, 3)), (normals, "normals", (3, 3)))]
    if usd:
        if scheme is not None and scheme not in ("loop", "catmull-clark"):
            raise ParameterError(f"scheme must be 'loop' or 'catmull-clark', got {scheme!r}")
        if counts is None:
            counts = np.full(len(indices) // size, size, dtype=np.int32)
        tag_dict = {} if core_tags is None else tags_dict(core_tags)
        if boundary is not None:
            tag_dict["boundary"] = _core.boundary_name(boundary_rule)
        uv, normal = ((None if c[0] is None else c) for c in (channels[0], channels[1]))
        write_usd(path, vertices, counts, indices, scheme=scheme, tags=tag_dict, uvs=uv, normals=normal, prim=prim,
                  template=template)
        return
    _core.write_mesh(os.fsencode(path), vertices, indices, counts, size, bool(binary), core_tags, boundary_rule,
                     *channels[0], *channels[1])


# The rules each format holds: OBJ OpenSubdiv's 't' tags (boundary, creases, corners, holes), USD those and the
# scheme (UsdGeomMesh's attributes); OFF, PLY and STL none.
TAG_KINDS = ("creases", "corners", "holes")
OBJ_RULES = ("boundary",) + TAG_KINDS
USD_RULES = ("scheme",) + OBJ_RULES


def rules_held(path) -> tuple:
    """The rules (scheme, boundary, creases, corners, holes) a mesh file of `path`'s format holds."""
    suffix = os.fsdecode(path).lower().rsplit(".", 1)[-1]
    return USD_RULES if is_usd(path) else OBJ_RULES if suffix == "obj" else ()


class WrittenMesh(NamedTuple):
    """What `write_mesh_file` wrote."""

    vertices: np.ndarray  # as the file holds them, read back (float32 in USD and STL)
    written: tuple  # the rules written: among scheme, boundary, creases, corners, holes
    dropped: tuple  # the rules the format could not hold and a reader would miss (each named in a FormatWarning)


def write_mesh_file(path, vertices, faces=None, *, scheme=None, boundary=None, creases=None, corners=None,
                    holes=None, uvs=None, normals=None, binary: bool = False, prim=None,
                    template=None) -> WrittenMesh:
    """Write a subdivision mesh with every rule the format holds, warn of those
    it cannot hold, and read back what was written: the one path by which the
    command line writes a control mesh.

    `write_mesh` with all of a mesh's rules given, whatever the format: the
    scheme, the boundary rule and the sharpness tags are written where the
    format holds them (`rules_held`: USD all of them, OBJ all but the scheme,
    OFF, PLY and STL none) and left out otherwise, with a `FormatWarning` for
    each one a reader would miss: tags that are not empty, a boundary rule
    other than the default ("edge-and-corner"), a scheme other than the one a
    reader's "auto" picks for the faces (Loop for triangles, Catmull-Clark
    otherwise). Empty tags are not written.

    A `SubdivisionMesh` in the place of `vertices` is written with all of
    its rules and attributes (``write_mesh_file(path, mesh)``; a rule given
    beside it as well must agree, as everywhere).

    Returns a `WrittenMesh`: the vertices as the file holds them, read back
    from it (USD rounds them to float32; STL too, and since an STL file
    merges its corners, its vertices are the float32 rounding of those given,
    in their order), and the rules written and dropped. Raises what
    `write_mesh` raises, before anything is written (coordinates beyond
    float32 for USD and STL, a seam for PLY).
    """
    rules = {"scheme": scheme, "boundary": boundary, "creases": creases, "corners": corners, "holes": holes}
    if isinstance(vertices, SubdivisionMesh):
        mesh = vertices
        vertices, faces, _ = mesh_arguments(mesh, faces, {k: v for k, v in rules.items() if v is not None},
                                                     "write_mesh_file")
        rules = {k: v for k, v in mesh.rules.items() if k in rules}
        uvs = mesh.uvs if uvs is None else uvs
        normals = mesh.normals if normals is None else normals
    given = {k: v for k, v in rules.items() if v is not None and not (k in TAG_KINDS and _empty_tag(k, v))}
    held = rules_held(path)
    name, fmt = os.fsdecode(path), _format_label(path)
    dropped = []
    lost_tags = sorted(k for k in given if k in TAG_KINDS and k not in held)
    if lost_tags:
        dropped += lost_tags
        warnings.warn(f"{name}: the sharpness tags ({', '.join(lost_tags)}) are not written: only .obj and USD "
                      "files hold them; refitting this file would solve without them", FormatWarning, stacklevel=2)
    if "boundary" in given and "boundary" not in held and as_boundary(given["boundary"]) != as_boundary(
            DEFAULT_BOUNDARY):
        dropped.append("boundary")
        warnings.warn(f"{name}: the boundary rule {given['boundary']} is not written: {fmt} holds none, and a "
                      f"reader takes {DEFAULT_BOUNDARY}; .obj and USD files hold it", FormatWarning, stacklevel=2)
    if "scheme" in given and "scheme" not in held:
        auto = resolve_scheme(AUTO_SCHEME, faces)  # what a reader of the file takes
        if given["scheme"] != auto:
            dropped.append("scheme")
            warnings.warn(f"{name}: the scheme {given['scheme']} is not written: {fmt} holds no subdivision "
                          f"scheme, and a reader's auto takes {auto} for these faces; USD files hold it",
                          FormatWarning, stacklevel=2)
    kept = {k: v for k, v in given.items() if k in held}
    write_mesh(path, vertices, faces, binary=binary, uvs=uvs, normals=normals, prim=prim, template=template, **kept)
    if fmt == "STL":
        back = np.asarray(vertices, dtype=np.float64).astype(np.float32).astype(np.float64)
    else:
        back = read_mesh_file(path, prim=prim if template is None else _template_prim(template, prim)).vertices
    return WrittenMesh(back, tuple(sorted(kept)), tuple(dropped))


ATTRIBUTE_WORDS = {"uvs": "texture coordinates", "normals": "normals"}


def attribute_refusal(path, name: str, channel, faces, n_vertices: int) -> str | None:
    """Why a mesh file of `path`'s format cannot hold the face-varying
    attribute `name` ("uvs" or "normals", a FaceVarying of `faces`), or None
    where it can: OFF and STL hold none; PLY one value of 2 (uvs) or 3
    (normals) numbers per vertex, so not a seam (a vertex with different
    values in different faces). The check `write_mesh` makes, the core's
    PLY writer's own (sorpia::check_ply_per_vertex, with its words), made
    before the work."""
    suffix = os.fsdecode(path).lower().rsplit(".", 1)[-1]
    if suffix in ("off", "stl"):
        return f"{suffix.upper()} has no per-vertex or per-corner values"
    if suffix != "ply":
        return None
    values = np.ascontiguousarray(channel[0], dtype=np.float64)
    indices = np.ascontiguousarray(channel[1], dtype=np.int32)
    counts, corners = as_polygons(faces, n_vertices)
    uniform = bool((counts == counts[0]).all()) if len(counts) else True
    try:
        _core.check_ply_per_vertex(corners, None if uniform else counts, int(counts[0]) if len(counts) else 3,
                                   int(n_vertices), values, indices, ATTRIBUTE_WORDS[name])
    except ParameterError as exc:
        return str(exc)
    return None


def _empty_tag(kind: str, value) -> bool:
    if kind == "holes":
        return len(np.asarray(value).reshape(-1)) == 0
    return len(np.asarray(value[0]).reshape(-1)) == 0


def _format_label(path) -> str:
    suffix = os.fsdecode(path).lower().rsplit(".", 1)[-1]
    return "USD" if is_usd(path) else suffix.upper()


def _template_prim(template, prim):
    """The prim write_mesh wrote into with a template: `prim`, else the template's only mesh."""
    if prim is not None:
        return prim
    return str(_usd_mesh(_usd_open(template), template, None).GetPath())


def _as_face_varying(channel, name: str, n_corners: int, widths: tuple[int, int]):
    """write_mesh's `uvs` or `normals` as (values (k, width) float64, indices (c,) int32), or (None, None)."""
    if channel is None:
        return None, None
    try:
        values, indices = channel
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be (values (k, width), indices (corners,)), e.g. a FaceVarying") from None
    values = np.ascontiguousarray(values, dtype=np.float64)
    indices = np.asarray(indices)
    if values.ndim != 2 or not widths[0] <= values.shape[1] <= widths[1]:
        raise ParameterError(f"{name} values must be (k, {widths[0]}..{widths[1]}), got shape {values.shape}")
    if indices.ndim != 1 or len(indices) != n_corners or not np.issubdtype(indices.dtype, np.integer):
        raise ParameterError(f"{name} indices must be {n_corners} integers, one per face corner, got shape "
                             f"{indices.shape} of {indices.dtype}")
    return values, np.ascontiguousarray(indices, dtype=np.int32)


__all__ = ["read", "read_mesh", "write_mesh", "write_mesh_file", "attribute_refusal", "WrittenMesh", "FaceVarying",
           "AttributeWarning", "UnknownTagWarning", "FormatWarning"]
