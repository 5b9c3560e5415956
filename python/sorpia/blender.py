"""A fitted Catmull-Clark cage for Blender: a bpy script (``sorpia fit ...
--blender cage.py``) that builds the control mesh with its tags as Blender's
crease weights and a Subdivision Surface modifier that draws its limit surface.

Blender subdivides with OpenSubdiv. Its edge and vertex crease weights c in
[0, 1] are OpenSubdiv sharpness 10 c^2 (blenkernel's crease_to_sharpness), so
a sharpness s is the weight sqrt(s / 10), 1 for infinitely sharp (s >= 10);
its modifier's ``boundary_smooth`` 'ALL' is the boundary rule edge-only and
'PRESERVE_CORNERS' edge-and-corner; ``use_limit_surface`` puts vertices at
their limit positions, with ``quality`` OpenSubdiv's isolation level. Blender
has no Loop scheme and no holes (deleting a hole's face would make its edges a
boundary, another surface): those cages are refused.
"""

from __future__ import annotations

import os

import numpy as np

from . import _core
from ._mesh import mesh_arguments
from ._validate import DEFAULT_BOUNDARY, DEFAULT_SCHEME, as_boundary, as_polygons, as_tags, as_vertices
from .errors import ParameterError

# Blender's default isolation; QUALITY_EXACT where features need the deepest isolation (darts, semi-sharp
# creases and corners, one-face corners under edge-only): the limit positions there are then exact to float32.
QUALITY_DEFAULT, QUALITY_EXACT = 3, 10
BOUNDARY_SMOOTH = {"edge-only": "ALL", "edge-and-corner": "PRESERVE_CORNERS"}


def crease_weight(sharpness) -> np.ndarray:
    """Blender's crease weight for OpenSubdiv sharpness: sqrt(s / 10), clipped to [0, 1]."""
    s = np.asarray(sharpness, dtype=np.float64)
    return np.sqrt(np.clip(s, 0.0, 10.0) / 10.0)


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


def blender_script(vertices, faces=None, *, boundary: str = DEFAULT_BOUNDARY, creases=None, corners=None,
                   holes=None, name: str = "sorpia_cage", levels: int = 3) -> str:
    """A bpy script that adds the Catmull-Clark cage `vertices`, `faces` to the
    scene as object `name`: edge creases (``crease_edge``) and vertex creases
    (``crease_vert``) from the sharpness tags (`crease_weight`), and a
    Subdivision Surface modifier with ``use_limit_surface``, `blender_quality`,
    the boundary rule, and `levels` subdivisions in the viewport and render.
    The coordinates are written as Python's shortest repr (Blender keeps
    float32). Holes are refused (`blender_refusal`). ``blender_script(mesh)``
    takes a Catmull-Clark `sorpia.SubdivisionMesh` (another scheme is refused)."""
    vertices, faces, rules = mesh_arguments(vertices, faces, dict(
        scheme=DEFAULT_SCHEME, boundary=boundary, creases=creases, corners=corners, holes=holes), "blender_script")
    boundary, creases, corners, holes = rules["boundary"], rules["creases"], rules["corners"], rules["holes"]
    if rules["scheme"] != DEFAULT_SCHEME:  # a mesh's scheme: the script's modifier is Catmull-Clark's
        reason = blender_refusal(rules["scheme"], {})
        if reason is not None:
            raise ParameterError(reason)
    vertices = as_vertices(vertices)
    counts, indices = as_polygons(faces, len(vertices))
    as_tags(creases, corners, holes, n_vertices=len(vertices), n_faces=len(counts))  # checked as a solve checks
    reason = blender_refusal("catmull-clark", {"holes": holes} if holes is not None else {})
    if reason is not None:
        raise ParameterError(reason)
    as_boundary(boundary)
    starts = np.concatenate([[0], np.cumsum(counts)])
    face_lists = [indices[starts[f]:starts[f + 1]].tolist() for f in range(len(counts))]
    edges, edge_w = ([], []) if creases is None else (
        np.asarray(creases[0]).reshape(-1, 2).tolist(), crease_weight(np.broadcast_to(
            np.asarray(creases[1], dtype=float), (len(np.asarray(creases[0]).reshape(-1, 2)),))).tolist())
    verts, vert_w = ([], []) if corners is None else (
        np.asarray(corners[0]).reshape(-1).tolist(), crease_weight(np.broadcast_to(
            np.asarray(corners[1], dtype=float), (len(np.asarray(corners[0]).reshape(-1)),))).tolist())
    quality = blender_quality(faces, len(vertices), boundary, creases, corners)
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
    layer = mesh.attributes.new("crease_edge", "FLOAT", "EDGE")
    for (a, b), w in zip(crease_edges, crease_edge_weights):
        layer.data[index[(min(a, b), max(a, b))]].value = w
if crease_vertices:
    layer = mesh.attributes.new("crease_vert", "FLOAT", "POINT")
    for v, w in zip(crease_vertices, crease_vertex_weights):
        layer.data[v].value = w
obj = bpy.data.objects.new({name!r}, mesh)
bpy.context.scene.collection.objects.link(obj)
modifier = obj.modifiers.new("Subdivision", "SUBSURF")
modifier.subdivision_type = "CATMULL_CLARK"
modifier.use_limit_surface = True  # vertices at their limit positions: the fitted surface
modifier.quality = {quality}  # OpenSubdiv's isolation level
modifier.boundary_smooth = {BOUNDARY_SMOOTH[boundary]!r}  # sorpia's boundary rule {boundary}
modifier.use_creases = True
modifier.levels = modifier.render_levels = {int(levels)}
'''


def write_blender_script(path, vertices, faces=None, **options) -> None:
    """`blender_script` written to `path` atomically."""
    _core.write_file_atomic(os.fsencode(path), blender_script(vertices, faces, **options).encode("utf-8"))


__all__ = ["blender_script", "write_blender_script", "blender_refusal", "blender_quality", "crease_weight"]
