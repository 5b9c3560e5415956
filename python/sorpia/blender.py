"""Blender's subdivision rules as sorpia's, both ways: the one mapping that
the bpy script ``sorpia fit ... --blender cage.py`` writes with and that the
Blender extension (blender/sorpia_blender) reads meshes with.

Blender subdivides with OpenSubdiv. Its edge and vertex crease weights c
(attributes ``crease_edge`` and ``crease_vert``) are OpenSubdiv sharpness
10 c^2, computed in float32 (blenkernel's crease_to_sharpness), so a sharpness
s is the weight sqrt(s / 10), 1 for infinitely sharp (s >= 10); its
Subdivision Surface modifier's ``boundary_smooth`` 'ALL' is the boundary rule
edge-only and 'PRESERVE_CORNERS' edge-and-corner; ``use_creases`` off drops
every crease; ``use_limit_surface`` puts vertices at their limit positions,
with ``quality`` OpenSubdiv's isolation level. Blender has no Loop scheme and
no holes (deleting a hole's face would make its edges a boundary, another
surface): those cages are refused.

`BlenderMesh` holds a mesh as Blender stores it (vertices, edges, face sizes,
corner vertices and edges, the crease weights): `blender_rules` gives the
keyword arguments sorpia's functions take for it, `mesh_refusal` what Blender
would draw differently from sorpia's surface, `two_face_vertices` where
Blender 5.0 and older draw the surface wrong.
"""

from __future__ import annotations

import os
from typing import NamedTuple, Optional

import numpy as np

from . import _core
from ._mesh import mesh_arguments
from ._meshinfo import bounding_box_diagonal
from ._validate import DEFAULT_BOUNDARY, DEFAULT_SCHEME, Polygons, as_boundary, as_polygons, as_tags, as_vertices
from .errors import ParameterError
from .solve import Interpolator

# Blender's default isolation; QUALITY_EXACT where features need the deepest isolation (darts, semi-sharp
# creases and corners, one-face corners under edge-only): the limit positions there are then exact to float32.
QUALITY_DEFAULT, QUALITY_EXACT = 3, 10
BOUNDARY_SMOOTH = {"edge-only": "ALL", "edge-and-corner": "PRESERVE_CORNERS"}
BOUNDARY_RULE = {smooth: rule for rule, smooth in BOUNDARY_SMOOTH.items()}
# The mesh attributes Blender (4.0 and later) keeps crease weights in.
EDGE_CREASE, VERTEX_CREASE = "crease_edge", "crease_vert"


def crease_weight(sharpness) -> np.ndarray:
    """Blender's crease weight for OpenSubdiv sharpness: sqrt(s / 10), clipped to [0, 1]."""
    s = np.asarray(sharpness, dtype=np.float64)
    return np.sqrt(np.clip(s, 0.0, 10.0) / 10.0)


def crease_sharpness(weight) -> np.ndarray:
    """OpenSubdiv sharpness of Blender crease weights, as Blender computes it:
    c * c * 10 in float32 (blenkernel's crease_to_sharpness), as float64.
    Weight 1 is 10, OpenSubdiv's infinitely sharp."""
    c = np.asarray(weight, dtype=np.float32)
    return (c * c * np.float32(10.0)).astype(np.float64)


def blender_refusal(scheme: str, tags: dict) -> str | None:
    """Why Blender cannot draw the limit surface of this cage, or None."""
    if scheme != "catmull-clark":
        return "Blender subdivides with Catmull-Clark only (it has no Loop scheme): fit with --scheme catmull-clark"
    if len(tags.get("holes", ())):
        return ("Blender has no holes (deleting a hole's face makes its edges a boundary, another surface): fit "
                "without hole tags")
    return None


def blender_quality(faces, n_vertices: int, boundary: str, creases=None, corners=None) -> int:
    """The modifier's quality (OpenSubdiv's isolation level): QUALITY_EXACT when
    the cage has creases or corners of sharpness above 0, or, under edge-only,
    a vertex of one face; Blender's default otherwise (regular and
    extraordinary smooth vertices need no more)."""
    tagged = any(c is not None and np.any(np.asarray(c[1]) > 0) for c in (creases, corners))
    counts, indices = as_polygons(faces, n_vertices)
    one_face = boundary == "edge-only" and bool((np.bincount(indices, minlength=n_vertices) == 1).any())
    return QUALITY_EXACT if tagged or one_face else QUALITY_DEFAULT


def modifier_settings(faces, n_vertices: int, boundary: str, creases=None, corners=None) -> dict:
    """The Subdivision Surface modifier's settings under which Blender draws
    the limit surface sorpia computes for these rules: attribute name to
    value, as ``setattr(modifier, name, value)`` takes them."""
    as_boundary(boundary)
    return {"subdivision_type": "CATMULL_CLARK",
            "use_limit_surface": True,  # vertices at their limit positions: the fitted surface
            "quality": blender_quality(faces, n_vertices, boundary, creases, corners),  # the isolation level
            "boundary_smooth": BOUNDARY_SMOOTH[boundary],
            "use_creases": True}


class BlenderMesh(NamedTuple):
    """A mesh as Blender stores it (``Mesh.vertices``, ``edges``,
    ``polygons``, the ``corner_vert`` and ``corner_edge`` attributes), the
    arrays ``foreach_get`` fills. Crease weights None where the mesh has no
    such attribute."""

    vertices: np.ndarray  # (n, 3) float
    edges: np.ndarray  # (e, 2) int
    face_sizes: np.ndarray  # (m,) int: Polygon.loop_total, faces in order, corners consecutive
    corner_verts: np.ndarray  # (k,) int: each corner's vertex
    corner_edges: np.ndarray  # (k,) int: the edge from each corner to the next of its face
    edge_creases: Optional[np.ndarray] = None  # (e,) float
    vertex_creases: Optional[np.ndarray] = None  # (n,) float

    @property
    def faces(self) -> Polygons:
        return Polygons(np.asarray(self.face_sizes, dtype=np.int32), np.asarray(self.corner_verts, dtype=np.int32))


def blender_rules(mesh: BlenderMesh, boundary_smooth: str = "ALL", use_creases: bool = True) -> dict:
    """sorpia's rule options for `mesh` under a Subdivision Surface modifier
    with these settings (Blender's defaults: 'ALL', creases on):
    ``boundary=``, and ``creases=``, ``corners=`` for the edges and vertices
    of weight whose sharpness is above 0."""
    if boundary_smooth not in BOUNDARY_RULE:
        raise ParameterError(f"boundary_smooth must be one of {', '.join(map(repr, BOUNDARY_RULE))}, "
                             f"got {boundary_smooth!r}")
    rules: dict = {"boundary": BOUNDARY_RULE[boundary_smooth]}
    if not use_creases:
        return rules
    for kind, weights, ids in (("creases", mesh.edge_creases, np.asarray(mesh.edges).reshape(-1, 2)),
                               ("corners", mesh.vertex_creases, None)):
        if weights is None:
            continue
        s = crease_sharpness(weights)
        tagged = np.flatnonzero(s > 0)
        if len(tagged):
            rules[kind] = (ids[tagged] if ids is not None else tagged, s[tagged])
    return rules


def _count(n: int, what: str, plural: str = "") -> str:
    return f"{n} {what if n == 1 else plural or what + 's'}"


def mesh_refusal(mesh: BlenderMesh) -> str | None:
    """Why Blender's modifier would draw another surface than the one sorpia
    fits for this mesh (or sorpia cannot fit it), or None: no faces; loose
    vertices or edges (Blender makes the ends of loose edges corners);
    edges of three or more faces; faces of a vertex repeated; neighbouring
    faces of opposite orientation (OpenSubdiv then takes the edge as
    non-manifold). Non-manifold vertices are left to sorpia's own check."""
    n, edges = len(mesh.vertices), np.asarray(mesh.edges).reshape(-1, 2)
    corner_verts, corner_edges = np.asarray(mesh.corner_verts), np.asarray(mesh.corner_edges)
    if len(mesh.face_sizes) == 0:
        return "the mesh has no faces: there is no surface to fit"
    loose_vertices = np.count_nonzero(np.bincount(corner_verts, minlength=n) == 0)
    uses = np.bincount(corner_edges, minlength=len(edges))
    loose_edges = np.count_nonzero(uses == 0)
    if loose_vertices or loose_edges:
        loose = " and ".join(_count(k, *what) for k, what in ((loose_edges, ("loose edge",)),
                                                              (loose_vertices, ("loose vertex", "loose vertices"))) if k)
        return (f"the mesh has {loose} (of no face): Blender's modifier makes the "
                "ends of loose edges sharp corners; delete them (Select > Select All by Trait > Loose Geometry)")
    many = np.count_nonzero(uses > 2)
    if many:
        return (f"the mesh has {_count(many, 'edge')} of three or more faces (non-manifold): "
                "Select > Select All by Trait > Non Manifold finds them")
    ends = np.cumsum(mesh.face_sizes)
    nxt = np.arange(1, len(corner_verts) + 1)  # each corner's next in its face
    nxt[ends - 1] = ends - mesh.face_sizes
    if np.any(corner_verts == corner_verts[nxt]) or np.any(corner_edges == corner_edges[nxt]):
        return "the mesh has a face with a vertex or an edge twice: Mesh > Clean Up > Degenerate Dissolve"
    # An edge of two faces must be run one way by one and the other way by the other.
    forward = corner_verts == edges[corner_edges, 0]
    ways = np.bincount(corner_edges, weights=forward, minlength=len(edges))
    flipped = np.count_nonzero((uses == 2) & (ways != 1))
    if flipped:
        return (f"the mesh has {_count(flipped, 'edge')} between faces of opposite orientation: "
                "Mesh > Normals > Recalculate Outside")
    return None


def two_face_vertices(mesh: BlenderMesh) -> np.ndarray:
    """The interior vertices of exactly two faces (indices): Blender 5.0 and
    older (OpenSubdiv 3.6.0's Bfr, fixed in 3.6.1 by PR 1353) draw the
    surface around them wrong."""
    n, edges = len(mesh.vertices), np.asarray(mesh.edges).reshape(-1, 2)
    boundary = np.zeros(n, dtype=bool)
    boundary[edges[np.bincount(mesh.corner_edges, minlength=len(edges)) == 1].ravel()] = True
    return np.flatnonzero((np.bincount(mesh.corner_verts, minlength=n) == 2) & ~boundary)


def interpolate_float32(vertices, faces, rules: dict, **options):
    """`sorpia.interpolate` (Catmull-Clark, the rule options `rules`, the
    solve's `options`) for a program that keeps float32 coordinates, as
    Blender does: returns the result, its control vertices rounded to
    float32, and the largest distance from `vertices` to the limit positions
    of that rounded cage over the diagonal of their bounding box (what
    Blender's surface misses by, but for its own float32 evaluation). The
    miss is B times the rounded cage by the solve's own operator B, which
    `sorpia.limit_points` would build again."""
    vertices = as_vertices(vertices)
    interp = Interpolator(faces, len(vertices), scheme="catmull-clark", **rules)
    res = interp.solve(vertices, **options)
    cage = res.control_vertices.astype(np.float32)
    limit = interp._impl.apply(cage.astype(np.float64))
    diagonal = bounding_box_diagonal(vertices) or 1.0
    return res, cage, float(np.linalg.norm(limit - vertices, axis=1).max()) / diagonal


def two_face_note(mesh: BlenderMesh) -> str | None:
    """The warning for a mesh with `two_face_vertices`, None without."""
    two = two_face_vertices(mesh)
    if not len(two):
        return None
    return (f"{_count(len(two), 'interior vertex', 'interior vertices')} of two faces (the first: {two[0]}): Blender "
            "5.0 and older draw the surface around them wrong (OpenSubdiv 3.6.0's Bfr, fixed in 3.6.1); sorpia's "
            "fit is right there")


def crease_weights_of(edges, n_vertices: int, creases=None, corners=None) -> tuple[np.ndarray, np.ndarray]:
    """Blender's crease attributes, (e,) edge weights and (n,) vertex weights
    in float32, for sorpia's tags on a mesh whose edges are `edges` (e, 2);
    every tagged edge must be one of them."""
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    edge_w, vert_w = np.zeros(len(edges), np.float32), np.zeros(n_vertices, np.float32)
    if creases is not None and len(np.asarray(creases[0])):
        pairs = np.sort(np.asarray(creases[0], dtype=np.int64).reshape(-1, 2), axis=1)
        keys = np.sort(edges, axis=1) @ np.array([n_vertices, 1], dtype=np.int64)
        order = np.argsort(keys)
        found = order[np.searchsorted(keys, pairs @ np.array([n_vertices, 1]), sorter=order).clip(0, len(keys) - 1)]
        if not np.array_equal(np.sort(edges[found], axis=1), pairs):
            raise ValueError("a crease edge is not an edge of the mesh")
        edge_w[found] = crease_weight(np.broadcast_to(np.asarray(creases[1], dtype=float), (len(pairs),)))
    if corners is not None and len(np.asarray(corners[0])):
        ids = np.asarray(corners[0], dtype=np.int64).reshape(-1)
        vert_w[ids] = crease_weight(np.broadcast_to(np.asarray(corners[1], dtype=float), (len(ids),)))
    return edge_w, vert_w


def blender_script(vertices, faces=None, *, boundary: str = DEFAULT_BOUNDARY, creases=None, corners=None,
                   holes=None, name: str = "sorpia_cage", levels: int = 3) -> str:
    """A bpy script that adds the Catmull-Clark cage `vertices`, `faces` to the
    scene as object `name`: edge creases (``crease_edge``) and vertex creases
    (``crease_vert``) from the sharpness tags (`crease_weight`), and a
    Subdivision Surface modifier with `modifier_settings` and `levels`
    subdivisions in the viewport and render. The coordinates are written as
    Python's shortest repr (Blender keeps float32). Holes are refused
    (`blender_refusal`). ``blender_script(mesh)`` takes a Catmull-Clark
    `sorpia.SubdivisionMesh` (another scheme is refused)."""
    vertices, faces, rules = mesh_arguments(vertices, faces, dict(
        scheme=DEFAULT_SCHEME, boundary=boundary, creases=creases, corners=corners, holes=holes), "blender_script")
    boundary, creases, corners, holes = rules["boundary"], rules["creases"], rules["corners"], rules["holes"]
    # a mesh's scheme, else the script's own: its modifier is Catmull-Clark's
    scheme = "catmull-clark" if rules["scheme"] == DEFAULT_SCHEME else rules["scheme"]
    vertices = as_vertices(vertices)
    counts, indices = as_polygons(faces, len(vertices))
    as_tags(creases, corners, holes, n_vertices=len(vertices), n_faces=len(counts))  # checked as a solve checks
    reason = blender_refusal(scheme, {"holes": holes} if holes is not None else {})
    if reason is not None:
        raise ParameterError(reason)
    settings = modifier_settings(faces, len(vertices), boundary, creases, corners)
    starts = np.concatenate([[0], np.cumsum(counts)])
    face_lists = [indices[starts[f]:starts[f + 1]].tolist() for f in range(len(counts))]
    edges, edge_w = ([], []) if creases is None else (
        np.asarray(creases[0]).reshape(-1, 2).tolist(), crease_weight(np.broadcast_to(
            np.asarray(creases[1], dtype=float), (len(np.asarray(creases[0]).reshape(-1, 2)),))).tolist())
    verts, vert_w = ([], []) if corners is None else (
        np.asarray(corners[0]).reshape(-1).tolist(), crease_weight(np.broadcast_to(
            np.asarray(corners[1], dtype=float), (len(np.asarray(corners[0]).reshape(-1)),))).tolist())
    modifier_lines = "".join(f"modifier.{key} = {value!r}\n" for key, value in settings.items())
    return f'''# Written by sorpia: a fitted Catmull-Clark cage whose limit surface passes through the
# given points. Run in Blender (Text Editor > Run Script, or blender --python THIS.py).
import bpy

vertices = {vertices.tolist()!r}
faces = {face_lists!r}
crease_edges = {edges!r}  # OpenSubdiv sharpness s as Blender's weight sqrt(s / 10)
crease_edge_weights = {edge_w!r}
crease_vertices = {verts!r}
crease_vertex_weights = {vert_w!r}

mesh = bpy.data.meshes.new({name!r})
mesh.from_pydata(vertices, [], faces)
mesh.update()
if crease_edges:
    index = {{tuple(sorted(e.vertices)): e.index for e in mesh.edges}}
    layer = mesh.attributes.new({EDGE_CREASE!r}, "FLOAT", "EDGE")
    for (a, b), w in zip(crease_edges, crease_edge_weights):
        layer.data[index[(min(a, b), max(a, b))]].value = w
if crease_vertices:
    layer = mesh.attributes.new({VERTEX_CREASE!r}, "FLOAT", "POINT")
    for v, w in zip(crease_vertices, crease_vertex_weights):
        layer.data[v].value = w
obj = bpy.data.objects.new({name!r}, mesh)
bpy.context.scene.collection.objects.link(obj)
modifier = obj.modifiers.new("Subdivision", "SUBSURF")
# sorpia's rules ({boundary}) as Blender's (sorpia.blender.modifier_settings)
{modifier_lines}modifier.levels = modifier.render_levels = {int(levels)}
'''


def write_blender_script(path, vertices, faces=None, **options) -> None:
    """`blender_script` written to `path` atomically."""
    _core.write_file_atomic(os.fsencode(path), blender_script(vertices, faces, **options).encode("utf-8"))


__all__ = ["blender_script", "write_blender_script", "blender_refusal", "blender_quality", "crease_weight",
           "crease_sharpness", "modifier_settings", "BlenderMesh", "blender_rules", "mesh_refusal",
           "two_face_vertices", "two_face_note", "crease_weights_of", "interpolate_float32"]
