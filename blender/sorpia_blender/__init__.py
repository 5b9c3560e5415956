"""sorpia in Blender: subdivision surfaces that pass through the mesh's vertices.

Three operators in Object mode (Object menu > sorpia, and the sidebar's sorpia tab):

- Fit Subdivision Through Vertices (``object.sorpia_fit``): moves each selected mesh's vertices so that the limit
  surface of its Subdivision Surface modifier passes through where they were (sorpia.interpolate).
- Fair Fit (``object.sorpia_fair_fit``): replaces each selected mesh with the one-level-finer cage whose limit
  surface passes through its vertices and bends least (sorpia.fair_interpolate), creases carried.
- Fit Cage to Target (``object.sorpia_fit_cage``): moves the active mesh's vertices so that its limit surface fits
  the vertices of the other selected mesh, a scan or a point cloud (sorpia.approximate).

Blender's rules are read by sorpia.blender (crease weights, the modifier's boundary_smooth and use_creases), the
one mapping that ``sorpia fit --blender`` writes with. Every check runs and every fit is solved before any mesh
changes: a refusal or a failed solve leaves every mesh as it was.
"""

from __future__ import annotations

import time
import warnings

import bpy
import numpy as np
from bpy.props import EnumProperty, FloatProperty

import sorpia
from sorpia.blender import (EDGE_CREASE, VERTEX_CREASE, BlenderMesh, blender_rules, crease_weights_of,
                            interpolate_float32, mesh_refusal, modifier_settings, two_face_note)
from sorpia.solve import METHODS

SCHEME = "catmull-clark"  # Blender's Subdivision Surface modifier: Catmull-Clark (its "Simple" is refused)


class Refused(Exception):
    """A mesh the operators leave alone, with the reason for the user."""


def _get(collection, attribute: str, count: int, dtype) -> np.ndarray:
    out = np.empty(count, dtype)
    collection.foreach_get(attribute, out)
    return out


def _attribute(mesh, name: str, domain: str, data_type: str, value: str, count: int, dtype):
    """An attribute's values by name, domain and type (or None): Blender's own arrays (position, .edge_verts,
    .corner_vert, .corner_edge) are attributes too, and foreach_get copies them in one pass, where the same
    values through MeshEdge.vertices or MeshLoop.vertex_index take a call per element."""
    layer = mesh.attributes.get(name)
    if layer is None or layer.domain != domain or layer.data_type != data_type:
        return None
    return _get(layer.data, value, count, dtype)


def read_mesh(mesh) -> BlenderMesh:
    """The mesh's arrays by foreach_get (no Python loop over its elements). Blender keeps each face's corners
    consecutive and in face order, so the corner arrays are the faces' vertex lists concatenated."""
    n, e, m, k = len(mesh.vertices), len(mesh.edges), len(mesh.polygons), len(mesh.loops)

    def arrays(name, domain, data_type, value, width, collection, attribute, count, dtype=np.int32):
        out = _attribute(mesh, name, domain, data_type, value, width * count, dtype)
        return _get(collection, attribute, width * count, dtype) if out is None else out  # (an empty mesh)

    starts = np.append(_get(mesh.polygons, "loop_start", m, np.int32), k)
    return BlenderMesh(
        vertices=arrays("position", "POINT", "FLOAT_VECTOR", "vector", 3, mesh.vertices, "co", n,
                        np.float32).reshape(n, 3).astype(np.float64),
        edges=arrays(".edge_verts", "EDGE", "INT32_2D", "value", 2, mesh.edges, "vertices", e).reshape(e, 2),
        face_sizes=np.diff(starts).astype(np.int32),
        corner_verts=arrays(".corner_vert", "CORNER", "INT", "value", 1, mesh.loops, "vertex_index", k),
        corner_edges=arrays(".corner_edge", "CORNER", "INT", "value", 1, mesh.loops, "edge_index", k),
        edge_creases=_attribute(mesh, EDGE_CREASE, "EDGE", "FLOAT", "value", e, np.float32),
        vertex_creases=_attribute(mesh, VERTEX_CREASE, "POINT", "FLOAT", "value", n, np.float32))


def _names(modifiers) -> str:
    return ", ".join(f"'{m.name}'" for m in modifiers)


def subdivision_modifier(obj):
    """The object's Subdivision Surface modifier (None where it has none and one is to be added), and the
    modifiers after it; Refused where the stack would draw another surface than the fitted one."""
    modifiers = list(obj.modifiers)
    multires = [m for m in modifiers if m.type == "MULTIRES"]
    if multires:
        raise Refused(f"it has a Multires modifier ({_names(multires)}): its sculpted levels are not the "
                      "subdivision surface of the mesh; apply or remove it first")
    subsurf = [i for i, m in enumerate(modifiers) if m.type == "SUBSURF"]
    if len(subsurf) > 1:
        raise Refused(f"it has {len(subsurf)} Subdivision Surface modifiers ({_names(modifiers[i] for i in subsurf)})"
                      ": the second subdivides the first's result; keep one")
    first = subsurf[0] if subsurf else len(modifiers)
    if first > 0:
        which = "its Subdivision Surface modifier" if subsurf else "the Subdivision Surface modifier it would get"
        raise Refused(f"modifiers come before {which} ({_names(modifiers[:first])}): it would subdivide their "
                      "result, not the mesh; apply or remove them, or move the Subdivision Surface modifier first")
    if not subsurf:
        return None, []
    modifier = modifiers[first]
    if modifier.subdivision_type != "CATMULL_CLARK":
        raise Refused(f"its Subdivision Surface modifier '{modifier.name}' is set to Simple, which has no smooth "
                      "limit surface: set it to Catmull-Clark")
    return modifier, modifiers[first + 1:]


class Subject:
    """One mesh object as the operators read it, checked: its arrays, sorpia's rules for it, its modifier."""

    def __init__(self, obj):
        self.obj = obj
        if obj.type != "MESH":
            raise Refused("it is not a mesh")
        mesh = obj.data
        if mesh.library is not None or not getattr(mesh, "is_editable", True):
            raise Refused("its mesh is linked from a library and cannot be changed")
        if mesh.shape_keys is not None:
            raise Refused("it has shape keys: Blender draws their mix, which moving the mesh's vertices does not "
                          "change; apply or remove them first")
        self.modifier, self.after = subdivision_modifier(obj)
        self.mesh = read_mesh(mesh)
        reason = mesh_refusal(self.mesh)
        if reason is not None:
            raise Refused(reason)
        boundary_smooth = "ALL" if self.modifier is None else self.modifier.boundary_smooth
        use_creases = True if self.modifier is None else self.modifier.use_creases
        self.rules = blender_rules(self.mesh, boundary_smooth, use_creases)
        self.faces = self.mesh.faces

    def miss(self, cage: np.ndarray, faces, rules, targets) -> float:
        """The largest distance from the mesh's vertices to the limit positions of `targets` (indices) of `cage`
        (faces, rules) as Blender holds it (float32), over the bounding box's diagonal; sorpia's limit."""
        limit = sorpia.limit_points(np.asarray(cage, np.float32).astype(np.float64), faces, scheme=SCHEME, **rules)
        return float(np.linalg.norm(limit[targets] - self.mesh.vertices, axis=1).max()) / _diagonal(self.mesh.vertices)

    def notes(self) -> list:
        """What the user should know about this object's result: where Blender draws the surface wrong, what
        the modifiers after the Subdivision Surface one do."""
        notes = []
        two = two_face_note(self.mesh)
        if two is not None:
            notes.append(f"{self.obj.name}: {two}")
        if self.after:
            notes.append(f"{self.obj.name}: the modifiers after its Subdivision Surface ({_names(self.after)}) "
                         "still change what is drawn")
        return notes

    def set_modifier(self, faces=None, n_vertices=None, rules=None) -> None:
        """Add the Subdivision Surface modifier where there is none (with every setting of
        sorpia.blender.modifier_settings); on an existing one, turn the limit surface on and raise its quality
        to what the features need (the settings that were read, boundary and creases, stay)."""
        faces = self.faces if faces is None else faces
        n_vertices = len(self.mesh.vertices) if n_vertices is None else n_vertices
        rules = self.rules if rules is None else rules
        settings = modifier_settings(faces, n_vertices, **rules)
        if self.modifier is None:
            self.modifier = self.obj.modifiers.new("Subdivision", "SUBSURF")
            for key, value in settings.items():
                setattr(self.modifier, key, value)
        else:
            self.modifier.use_limit_surface = True
            self.modifier.quality = max(self.modifier.quality, settings["quality"])


def _subjects(objects) -> list:
    """Subjects for the objects, each mesh once (objects sharing a mesh share its fit); Refused, naming the
    object, at the first that cannot be fitted."""
    seen, subjects = set(), []
    for obj in objects:
        if obj.type != "MESH" or obj.data.name_full in seen:
            continue
        seen.add(obj.data.name_full)
        try:
            subjects.append(Subject(obj))
        except Refused as e:
            raise Refused(f"{obj.name}: {e}") from None
    return subjects


def _set_vertices(obj, vertices: np.ndarray) -> None:
    """The mesh's positions set in one pass (the position attribute: MeshVertex.co takes a call per vertex)."""
    obj.data.attributes["position"].data.foreach_set("vector", np.ascontiguousarray(vertices, np.float32).ravel())
    obj.data.update()


def _diagonal(vertices: np.ndarray) -> float:
    return float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0))) or 1.0


class _Run:
    """An operator's run: the progress indicator, sorpia's warnings and errors as the operator's reports."""

    def __init__(self, operator, context, steps: int):
        self.operator, self.wm, self.steps = operator, context.window_manager, steps
        self.notes = []

    def __enter__(self):
        self.wm.progress_begin(0, self.steps)
        self._warnings = warnings.catch_warnings(record=True)
        self.caught = self._warnings.__enter__()
        warnings.simplefilter("always", sorpia.SorpiaWarning)
        return self

    def __exit__(self, kind, value, traceback):
        self._warnings.__exit__(kind, value, traceback)
        self.wm.progress_end()
        if isinstance(value, Refused) or isinstance(value, ValueError):  # sorpia's MeshError, ParameterError
            self.operator.report({"ERROR"}, f"sorpia: {value}; nothing was changed")
            return True
        return False

    def progress(self, value: float) -> None:
        self.wm.progress_update(min(value, self.steps))

    def finish(self, text: str) -> None:
        """One report: the result, then the notes and sorpia's warnings (a warning when there are any)."""
        notes = self.notes + [str(w.message) for w in self.caught]
        self.operator.report({"WARNING"} if notes else {"INFO"}, "; ".join([text] + notes))


def _selected_meshes(context) -> list:
    return [o for o in context.selected_objects if o.type == "MESH"]


def _plural(n: int) -> str:
    return f"{n} mesh{'es' if n != 1 else ''}"


class _EachSelectedMesh:
    """An operator on each selected mesh (each mesh once): `solve` for every one first, then `apply` to every
    one, so that a refusal or a failed solve leaves them all as they were; then one report, `summary`."""

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT" and bool(_selected_meshes(context))

    def execute(self, context):
        t0 = time.perf_counter()
        meshes = _selected_meshes(context)
        with _Run(self, context, len(meshes)) as run:
            fits = []
            for i, s in enumerate(_subjects(meshes)):
                fits.append(self.solve(s, run, i))
                run.notes += s.notes()
            for fit in fits:  # every fit solved: now the meshes change
                self.apply(*fit)
            run.finish(self.summary(fits, time.perf_counter() - t0))
            return {"FINISHED"}
        return {"CANCELLED"}


class SORPIA_OT_fit(_EachSelectedMesh, bpy.types.Operator):
    """Move the vertices of each selected mesh so that the limit surface of its Subdivision Surface modifier passes
    through where they were"""

    bl_idname = "object.sorpia_fit"
    bl_label = "Fit Subdivision Through Vertices"
    bl_options = {"REGISTER", "UNDO"}

    method: EnumProperty(name="Method", description="sorpia's solver (auto: SOR-PIA, with fallbacks where it "
                         "would not converge)", items=[(m, m, "") for m in METHODS], default="auto")
    tolerance: FloatProperty(name="Tolerance", description="stop when the largest miss has fallen below this "
                             "fraction of the first", default=1e-10, min=1e-15, max=0.1, precision=12)

    def solve(self, s: Subject, run: _Run, i: int) -> tuple:
        res, cage, miss = interpolate_float32(s.mesh.vertices, s.faces, s.rules, method=self.method,
                                              tol=self.tolerance,
                                              callback=lambda k, error: run.progress(i + min(k, 99) / 100))
        # As sorpia fit: where B is singular the least-squares cage is the best there is (its
        # SingularMatrixWarning names where the targets are missed); any other stop is no answer.
        if not (res.converged or res.stop_reason == "singular"):
            raise Refused(f"{s.obj.name}: the solve stopped short ({res.stop_reason}, {res.iterations} "
                          f"iterations, E_k/E_0 {res.history[-1]:.2g}); try another method")
        return s, cage, miss, res

    def apply(self, s: Subject, cage, miss, res) -> None:
        _set_vertices(s.obj, cage)
        s.set_modifier()

    def summary(self, fits, seconds: float) -> str:
        s, _, miss, res = max(fits, key=lambda f: f[2])
        return (f"sorpia: fitted {_plural(len(fits))} in {seconds:.2f} s; largest miss {miss:.2g} of the diagonal "
                f"({s.obj.name}, {res.iterations} iterations of {res.variant})")


def _replace_geometry(mesh, vertices: np.ndarray, faces: np.ndarray, parents: np.ndarray, creases, corners) -> None:
    """The mesh's geometry replaced by the quads `faces` on `vertices`: each face's material and smooth shading
    those of its parent face, Blender's crease attributes from the tags; other attributes do not carry."""
    material = _get(mesh.polygons, "material_index", len(mesh.polygons), np.int32)[parents]
    smooth = _get(mesh.polygons, "use_smooth", len(mesh.polygons), bool)[parents]
    counts = np.full(len(faces), faces.shape[1], np.int32)
    mesh.clear_geometry()
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(vertices, dtype=np.float32).ravel())
    mesh.loops.add(int(counts.sum()))
    mesh.loops.foreach_set("vertex_index", np.ascontiguousarray(faces, dtype=np.int32).ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.cumsum(counts) - counts)
    mesh.polygons.foreach_set("material_index", material)
    mesh.polygons.foreach_set("use_smooth", smooth)
    mesh.update(calc_edges=True)
    edges = _get(mesh.edges, "vertices", 2 * len(mesh.edges), np.int32).reshape(-1, 2)
    edge_w, vert_w = crease_weights_of(edges, len(vertices), creases, corners)
    for name, domain, weights in ((EDGE_CREASE, "EDGE", edge_w), (VERTEX_CREASE, "POINT", vert_w)):
        if weights.any():
            mesh.attributes.new(name, "FLOAT", domain).data.foreach_set("value", weights)
    mesh.update()


class SORPIA_OT_fair_fit(_EachSelectedMesh, bpy.types.Operator):
    """Replace each selected mesh with the one-level-finer cage whose limit surface passes through its vertices
    and bends least (creases carried; UV maps and vertex weights are not)"""

    bl_idname = "object.sorpia_fair_fit"
    bl_label = "Fair Fit"
    bl_options = {"REGISTER", "UNDO"}

    def solve(self, s: Subject, run: _Run, i: int) -> tuple:
        # The library's defaults, as `sorpia fit --fair` takes them, so that Fair Fit gives what the command gives.
        res = sorpia.fair_interpolate(s.mesh.vertices, s.faces, scheme=SCHEME, **s.rules)
        run.progress(i + 1)
        tags = {k: v for k, v in (("creases", res.creases), ("corners", res.corners)) if v is not None}
        rules = {"boundary": s.rules["boundary"], **tags}
        return s, res, rules, s.miss(res.control_vertices, res.faces, rules, res.targets)

    def apply(self, s: Subject, res, rules, miss) -> None:
        # Far's refinement lists each face's children together, in the order of the faces.
        parents = np.repeat(np.arange(len(s.mesh.face_sizes)), s.mesh.face_sizes)
        _replace_geometry(s.obj.data, res.control_vertices, res.faces, parents, res.creases, res.corners)
        s.set_modifier(res.faces, len(res.control_vertices), rules)

    def summary(self, fits, seconds: float) -> str:
        return (f"sorpia: fair fit of {_plural(len(fits))} in {seconds:.2f} s, one level finer; largest miss "
                f"{max(f[-1] for f in fits):.2g} of the diagonal")


class SORPIA_OT_fit_cage(bpy.types.Operator):
    """Move the active mesh's vertices (a cage) so that its limit surface fits the vertices of the other selected
    mesh (a scan or a point cloud)"""

    bl_idname = "object.sorpia_fit_cage"
    bl_label = "Fit Cage to Target"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        cage = context.active_object
        return (context.mode == "OBJECT" and cage is not None and cage.type == "MESH" and cage.select_get()
                and any(o is not cage for o in _selected_meshes(context)))

    def execute(self, context):
        t0 = time.perf_counter()
        cage = context.active_object
        with _Run(self, context, 1) as run:
            targets = [o for o in _selected_meshes(context) if o is not cage]
            if len(targets) != 1:
                raise Refused(f"select one target mesh besides the active cage '{cage.name}', not {len(targets)}")
            (target,) = targets
            (s,) = _subjects([cage])
            evaluated = target.evaluated_get(context.evaluated_depsgraph_get())
            data = evaluated.to_mesh()
            try:
                points = _get(data.vertices, "co", 3 * len(data.vertices), np.float32).reshape(-1, 3)
            finally:
                evaluated.to_mesh_clear()
            if len(points) == 0:
                raise Refused(f"the target '{target.name}' has no vertices")
            # The target's points in the cage's object space, where its modifier subdivides.
            m = np.array(cage.matrix_world.inverted() @ target.matrix_world, dtype=np.float64)
            points = points.astype(np.float64) @ m[:3, :3].T + m[:3, 3]
            res = sorpia.approximate(points, s.mesh.vertices, s.faces, scheme=SCHEME, **s.rules,
                                     callback=lambda record: run.progress(record["iteration"] / 10))
            run.notes += s.notes()
            _set_vertices(cage, res.control_vertices)
            s.set_modifier()
            run.finish(f"sorpia: fitted '{cage.name}' to the {len(points)} points of '{target.name}' in "
                       f"{time.perf_counter() - t0:.2f} s: RMS distance {res.rms:.3g} "
                       f"({res.rms / res.diagonal:.2g} of the points' diagonal), {res.iterations} iterations")
            return {"FINISHED"}
        return {"CANCELLED"}


OPERATORS = (SORPIA_OT_fit, SORPIA_OT_fair_fit, SORPIA_OT_fit_cage)


class VIEW3D_MT_sorpia(bpy.types.Menu):
    bl_label = "sorpia"
    bl_idname = "VIEW3D_MT_sorpia"

    def draw(self, context):
        for op in OPERATORS:
            self.layout.operator(op.bl_idname)


class VIEW3D_PT_sorpia(bpy.types.Panel):
    bl_label = "sorpia"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "sorpia"
    bl_context = "objectmode"

    def draw(self, context):
        column = self.layout.column(align=True)
        for op in OPERATORS:
            column.operator(op.bl_idname)


def _object_menu(self, context):
    self.layout.separator()
    self.layout.menu(VIEW3D_MT_sorpia.bl_idname)


CLASSES = OPERATORS + (VIEW3D_MT_sorpia, VIEW3D_PT_sorpia)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_object.append(_object_menu)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(_object_menu)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
