"""Runs in Blender's Python (the bpy module), for tests/test_blender_extension.py:

    python blender_extension_runner.py ZIP OUTDIR SHARED_MESHES

Installs the extension zip through Blender's extension API into the user
folder BLENDER_USER_RESOURCES names (the caller makes it a temporary one),
then runs each scenario on meshes it builds (and on the shared meshes where
SHARED_MESHES is a folder), and writes OUTDIR/NAME.npz per scenario: the
targets, Blender's own evaluated limit positions (the Subdivision Surface
modifier at level 1 with the limit surface on: the first vertices of the
evaluated mesh are the control vertices' limit positions, in order) and what
the scenario checks. A scenario that raises writes OUTDIR/NAME.error with the
traceback. Nothing here asserts: the tests do, on what it wrote.
"""

from __future__ import annotations

import os
import sys
import traceback
from pathlib import Path

import bpy
import numpy as np

ZIP, OUT, SHARED = sys.argv[-3], Path(sys.argv[-2]), Path(sys.argv[-1])
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "blender"))
from headless import install  # noqa: E402

MODULE = install(ZIP)
import sorpia  # noqa: E402  (from the wheel the extension installed, not from the repository)
from sorpia.blender import EDGE_CREASE, VERTEX_CREASE, crease_weights_of  # noqa: E402


def fresh_scene() -> None:
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)


def add_mesh(name, V, F, creases=None, corners=None, subsurf=None, location=(0.0, 0.0, 0.0)):
    """A mesh object from vertices and faces (lists or sorpia.Polygons), with Blender's crease attributes for
    sorpia's tags and, where `subsurf` is a dict of settings, a Subdivision Surface modifier."""
    if isinstance(F, sorpia.Polygons):
        starts = np.concatenate([[0], np.cumsum(F.face_vertex_counts)])
        F = [F.face_vertex_indices[a:b].tolist() for a, b in zip(starts[:-1], starts[1:])]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(np.asarray(V).tolist(), [], [list(map(int, f)) for f in F])
    mesh.update()
    edges = np.array([e.vertices[:] for e in mesh.edges], dtype=np.int64).reshape(-1, 2)
    edge_w, vert_w = crease_weights_of(edges, len(V), creases, corners)
    if edge_w.any():
        mesh.attributes.new(EDGE_CREASE, "FLOAT", "EDGE").data.foreach_set("value", edge_w)
    if vert_w.any():
        mesh.attributes.new(VERTEX_CREASE, "FLOAT", "POINT").data.foreach_set("value", vert_w)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    if subsurf is not None:
        modifier = obj.modifiers.new("Subdivision", "SUBSURF")
        for key, value in subsurf.items():
            setattr(modifier, key, value)
    return obj


def select(*objects, active=None) -> None:
    for o in bpy.context.scene.objects:
        o.select_set(False)
    for o in objects:
        o.select_set(True)
    bpy.context.view_layer.objects.active = active if active is not None else objects[0]


def coordinates(obj) -> np.ndarray:
    co = np.empty(3 * len(obj.data.vertices), np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def blender_limit(obj) -> np.ndarray:
    """Blender's limit positions of the object's control vertices: its own Subdivision Surface modifier (as the
    operator left it) evaluated at level 1, whose first vertices are those positions."""
    (modifier,) = [m for m in obj.modifiers if m.type == "SUBSURF"]
    modifier.levels = 1
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    return co.reshape(-1, 3)[:len(obj.data.vertices)].astype(np.float64)


def snapshot(obj) -> dict:
    """What the operators must leave as it was, or change only as they say: the mesh and its modifiers."""
    mesh = obj.data

    def get(collection, attribute, width, dtype):
        out = np.empty(len(collection) * width, dtype)
        collection.foreach_get(attribute, out)
        return out

    out = {"co": coordinates(obj), "edges": get(mesh.edges, "vertices", 2, np.int32),
           "corner_verts": get(mesh.loops, "vertex_index", 1, np.int32),
           "face_sizes": get(mesh.polygons, "loop_total", 1, np.int32),
           "material_index": get(mesh.polygons, "material_index", 1, np.int32),
           "modifiers": np.array([f"{m.type}:{m.name}" for m in obj.modifiers] or [""])}
    for layer in mesh.uv_layers:
        out[f"uv:{layer.name}"] = get(layer.uv, "vector", 2, np.float32)
    for group in obj.vertex_groups:
        out[f"group:{group.name}"] = np.array([group.weight(i) if any(g.group == group.index for g in v.groups)
                                               else -1.0 for i, v in enumerate(mesh.vertices)])
    for layer in mesh.attributes:
        if layer.name in (EDGE_CREASE, VERTEX_CREASE):
            out[f"attribute:{layer.name}"] = get(layer.data, "value", 1, np.float32)
    return out


def run_op(name: str, **options) -> str:
    """Run the operator as the menu does (with an undo step); '' when it finished, else its error report."""
    try:
        result = getattr(bpy.ops.object, name)("EXEC_DEFAULT", True, **options)
    except RuntimeError as e:  # an ERROR report raises
        return str(e)
    return "" if result == {"FINISHED"} else f"returned {sorted(result)}"


def wavy(V) -> np.ndarray:
    return V + 0.05 * np.sin(3 * V[:, [1, 2, 0]])  # no symmetry for a wrong rule to hide behind


def ring(nu: int, nv: int, i: int) -> np.ndarray:
    v = np.arange(nv)
    return np.stack([i * nv + v, i * nv + (v + 1) % nv], axis=1)


def creased_torus():
    V, F = sorpia.shapes.quad_torus(12, 8)
    return wavy(V), F, {"creases": (np.vstack([ring(12, 8, 0), ring(12, 8, 6)]), np.r_[np.full(8, 10.0),
                                                                                       np.full(8, 2.5)]),
                        "corners": (np.array([3 * 8 + 4]), np.array([1.5]))}


def decorate(obj) -> None:
    """A UV map, two materials and a vertex group: what a fit that keeps the topology keeps."""
    mesh = obj.data
    layer = mesh.uv_layers.new(name="UVMap")
    uv = np.random.default_rng(0).random(2 * len(mesh.loops)).astype(np.float32)
    layer.uv.foreach_set("vector", uv)
    for name in ("a", "b"):
        mesh.materials.append(bpy.data.materials.new(name))
    mesh.polygons.foreach_set("material_index", np.arange(len(mesh.polygons), dtype=np.int32) % 2)
    group = obj.vertex_groups.new(name="half")
    group.add(list(range(0, len(mesh.vertices), 2)), 0.25, "REPLACE")
    mesh.update()


def fit_scenario(obj, method="auto", tolerance=1e-10) -> dict:
    """Fit Subdivision Through Vertices on one object: its targets, Blender's limit after, what stayed. The
    options are given each time: Blender remembers an operator's last options for its next run."""
    select(obj)
    before = snapshot(obj)
    error = run_op("sorpia_fit", method=method, tolerance=tolerance)
    after = snapshot(obj)
    out = {"error": error, "targets": before["co"], "moved": after["co"]}
    out.update({f"before/{k}": v for k, v in before.items()})
    out.update({f"after/{k}": v for k, v in after.items()})
    if not error:
        modifier = [m for m in obj.modifiers if m.type == "SUBSURF"][0]
        out.update(limit=blender_limit(obj), quality=modifier.quality, use_limit_surface=modifier.use_limit_surface,
                   boundary_smooth=modifier.boundary_smooth)
    return out


# ---- scenarios: each returns the arrays its test reads -----------------------------------------------------------

def scenario_fit_creased_torus():
    fresh_scene()
    V, F, tags = creased_torus()
    obj = add_mesh("torus", V, F, **tags, subsurf={"levels": 2, "quality": 3, "use_limit_surface": False})
    decorate(obj)
    return fit_scenario(obj)


def scenario_fit_grid_no_modifier():
    """An open grid with a crease across it and no modifier: the operator adds one (boundary 'ALL', edge-only)."""
    fresh_scene()
    V, F = sorpia.shapes.quad_grid(7, 6)
    obj = add_mesh("grid", wavy(V), F, creases=(np.array([[8, 9], [9, 10], [10, 11]]), 4.0))
    return fit_scenario(obj)


def scenario_fit_grid_preserve_corners():
    fresh_scene()
    V, F = sorpia.shapes.quad_grid(7, 6)
    obj = add_mesh("grid", wavy(V), F, subsurf={"boundary_smooth": "PRESERVE_CORNERS"})
    return fit_scenario(obj, method="gmres", tolerance=1e-12)  # the redo panel's options


def scenario_fit_ngons():
    fresh_scene()
    V, F = sorpia.shapes.polygon_torus(10, 8, seed=4)
    obj = add_mesh("ngons", wavy(V), F, subsurf={})
    return fit_scenario(obj)


def scenario_fit_suzanne():
    """A real model, made by Blender: Suzanne subdivided once and relaxed, quads with poles, triangles and
    open boundaries (her eyes are separate parts)."""
    fresh_scene()
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.object
    modifier = obj.modifiers.new("refine", "SUBSURF")
    modifier.levels = 1
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    obj.modifiers.new("Subdivision", "SUBSURF")
    return fit_scenario(obj)


def scenario_fit_shared():
    """The shared meshes' quad models with their OBJ tags, where the folder SHARED is present."""
    out = {}
    names = ["osd_catmark_car", "osd_catmark_helmet", "osd_catmark_bishop", "osd_catmark_cube_creases1"]
    for name in names:
        path = SHARED / f"{name}.obj"
        if not path.exists():
            continue
        fresh_scene()
        V, F, tags = sorpia.read_mesh(path, tags=True)
        boundary = tags.pop("boundary", "edge-only")
        if "holes" in tags:
            continue
        obj = add_mesh(name, V, F, **tags, subsurf={"boundary_smooth": sorpia.blender.BOUNDARY_SMOOTH[boundary]})
        result = fit_scenario(obj)
        out.update({f"{name}/{k}": v for k, v in result.items() if k in ("error", "targets", "limit")})
    out["names"] = np.array([n for n in names if f"{n}/error" in out] or [""])
    return out


def scenario_fit_two_face_vertex():
    """A grid with one quad split by an interior vertex of two faces: fitted, with the warning."""
    fresh_scene()
    V, F = sorpia.shapes.quad_grid(6, 6)
    V, F = wavy(V), [list(f) for f in F]
    a, b, c, d = F[12]  # an interior quad, split along its diagonal a-c through a new vertex of two faces
    V = np.vstack([V, 0.5 * (V[a] + V[c]) + [0.0, 0.0, 0.03]])
    F[12:13] = [[a, b, c, len(V) - 1], [c, d, a, len(V) - 1]]
    obj = add_mesh("split", V, F, subsurf={})
    return fit_scenario(obj)


def scenario_fair():
    fresh_scene()
    V, F, tags = creased_torus()
    obj = add_mesh("fair", V, F, **tags, subsurf={"levels": 2})
    decorate(obj)
    select(obj)
    before = snapshot(obj)
    error = run_op("sorpia_fair_fit")
    out = {"error": error, "targets": V, "coarse_faces": np.asarray(F), "coarse_material": before["material_index"],
           "crease_edges": tags["creases"][0], "crease_sharpness": tags["creases"][1],
           "corner_vertices": tags["corners"][0], "corner_sharpness": tags["corners"][1]}
    if not error:
        after = snapshot(obj)
        out.update({f"after/{k}": v for k, v in after.items()})
        out["limit"] = blender_limit(obj)
        # sorpia's own limit of the fine cage as it now is in Blender, with the crease weights it carries
        mesh = obj.data
        edges = after["edges"].reshape(-1, 2)
        edge_w = after.get(f"attribute:{EDGE_CREASE}", np.zeros(len(edges), np.float32))
        vert_w = after.get(f"attribute:{VERTEX_CREASE}", np.zeros(len(mesh.vertices), np.float32))
        out.update(fine_edges=edges, edge_weights=edge_w, vertex_weights=vert_w)
    return out


def scan_and_cage():
    """A scan: the limit surface of a wavy torus cage, densely tessellated and moved by noise; the cage: the
    torus unfitted (shrunk), to be fitted to it."""
    V, F = sorpia.shapes.quad_torus(12, 8)
    V = wavy(V)
    points, faces = sorpia.limit_surface(V, F, level=3, scheme="catmull-clark")
    points = points + 1e-4 * np.random.default_rng(1).standard_normal(points.shape)
    return V * 0.9, F, points, faces


def cage_scenario(with_faces: bool):
    fresh_scene()
    cage_v, cage_f, points, faces = scan_and_cage()
    cage = add_mesh("cage", cage_v, cage_f, subsurf={"levels": 2})
    # The scan is another object with its own transform: its points in world space are those above.
    scale, shift = 2.0, np.array([0.3, -0.2, 0.5])
    scan = add_mesh("scan", (points - shift) / scale, faces.tolist() if with_faces else [], location=shift)
    scan.scale = (scale, scale, scale)
    bpy.context.view_layer.update()
    select(cage, scan, active=cage)
    before = snapshot(cage)
    error = run_op("sorpia_fit_cage")
    out = {"error": error, "points": points, "faces": np.asarray(cage_f), "before": before["co"]}
    if not error:
        out.update(fitted=coordinates(cage), limit=blender_limit(cage))
    return out


def scenario_cage_mesh():
    return cage_scenario(True)


def scenario_cage_points():
    return cage_scenario(False)


def bad(name: str, build, op: str = "sorpia_fit"):
    """Run `op` on the object `build` makes; the error and the object's state before and after."""
    fresh_scene()
    obj = build()
    select(obj)
    before = snapshot(obj)
    error = run_op(op)
    after = snapshot(obj)
    out = {f"{name}/error": error}
    for key in before:
        out[f"{name}/before/{key}"], out[f"{name}/after/{key}"] = before[key], after.get(key)
    return out


def grid_with(extra_vertices=(), extra_edges=(), flip=False, faces_extra=()):
    V, F = sorpia.shapes.quad_grid(5, 5)
    V = np.vstack([wavy(V)] + [np.atleast_2d(v) for v in extra_vertices])
    F = [list(f) for f in F] + list(faces_extra)
    if flip:
        F[7] = F[7][::-1]
    mesh = bpy.data.meshes.new("bad")
    mesh.from_pydata(V.tolist(), list(extra_edges), F)
    mesh.update()
    obj = bpy.data.objects.new("bad", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def with_modifiers(*kinds):
    def build():
        obj = grid_with()
        for kind in kinds:
            obj.modifiers.new(kind.lower(), kind)
        return obj
    return build


def with_shape_keys():
    obj = grid_with()
    obj.shape_key_add(name="Basis")
    obj.shape_key_add(name="Key 1")
    return obj


def simple_subdivision():
    obj = grid_with()
    obj.modifiers.new("Subdivision", "SUBSURF").subdivision_type = "SIMPLE"
    return obj


def empty_mesh():
    obj = bpy.data.objects.new("bad", bpy.data.meshes.new("bad"))
    bpy.context.scene.collection.objects.link(obj)
    return obj


BAD = {
    "loose_vertex": lambda: grid_with(extra_vertices=[(0.5, 0.5, 1.0)]),
    "loose_edge": lambda: grid_with(extra_vertices=[(0.5, 0.5, 1.0)], extra_edges=[(0, 25)]),
    "nonmanifold": lambda: grid_with(extra_vertices=[(0.1, 0.1, 1.0)], faces_extra=[[6, 7, 25]]),
    "flipped": lambda: grid_with(flip=True),
    "empty": empty_mesh,
    "multires": with_modifiers("MULTIRES"),
    "modifier_before": with_modifiers("ARRAY", "SUBSURF"),
    "two_subsurf": with_modifiers("SUBSURF", "SUBSURF"),
    "simple": simple_subdivision,
    "shape_keys": with_shape_keys,
}


def scenario_bad_input():
    out = {}
    for name, build in BAD.items():
        for op in ("sorpia_fit", "sorpia_fair_fit"):
            out.update(bad(f"{op}/{name}", build, op))
    out["names"] = np.array(list(BAD))
    return out


def scenario_undo():
    """Each operator run as the menu runs it (one undo step), then Edit > Undo: the mesh as it was."""
    out = {}
    for op in ("sorpia_fit", "sorpia_fair_fit", "sorpia_fit_cage"):
        fresh_scene()
        if op == "sorpia_fit_cage":
            cage_v, cage_f, points, faces = scan_and_cage()
            obj = add_mesh("cage", cage_v, cage_f)
            scan = add_mesh("scan", points, faces.tolist())
            select(obj, scan, active=obj)
        else:
            V, F, tags = creased_torus()
            obj = add_mesh("subject", V, F, **tags)
            select(obj)
        bpy.ops.ed.undo_push(message="before")
        before = snapshot(obj)
        error = run_op(op)
        changed = snapshot(bpy.data.objects[obj.name])
        bpy.ops.ed.undo()
        after = snapshot(bpy.data.objects["cage" if op == "sorpia_fit_cage" else "subject"])
        out[f"{op}/error"] = error
        for key in before:
            out[f"{op}/before/{key}"], out[f"{op}/changed/{key}"] = before[key], changed.get(key)
            out[f"{op}/after/{key}"] = after.get(key)
    return out


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    wanted = os.environ.get("SORPIA_SCENARIOS")
    for name, fn in list(globals().items()):
        if not name.startswith("scenario_") or (wanted and name[9:] not in wanted.split(",")):
            continue
        try:
            result = fn()
            np.savez(OUT / f"{name[9:]}.npz", **{k: np.asarray(v) for k, v in result.items()})
        except Exception:
            (OUT / f"{name[9:]}.error").write_text(traceback.format_exc())
    # after every operator ran: whether anything imported scipy, which Blender does not ship
    np.savez(OUT / "install.npz", sorpia_file=np.array(sorpia.__file__), version=np.array(sorpia.__version__),
             scipy_loaded=np.array("scipy" in sys.modules), blender=np.array(bpy.app.version_string))


main()
