"""The Blender extension's operators against the library on the same arrays.

Installs the extension zip (``make blender-extension``) into a temporary
Blender user folder and, in Blender's Python (.venv-blender, or
SORPIA_BLENDER_PYTHON), times each operator as the menu runs it (one undo
step) against the sorpia call it makes, on the arrays Blender holds:

- Fit Subdivision Through Vertices against sorpia.interpolate on a quad mesh
  of --vertices vertices (sorpia.shapes.quad_irregular: extraordinary
  vertices of valence 3 to 6), with a ring of creases;
- Fair Fit against sorpia.fair_interpolate (fit --fair's tol and max_iter) on
  the same mesh;
- Fit Cage to Target against sorpia.approximate: the scan the same mesh's
  --vertices vertices, the cage that mesh decimated by OpenMesh to
  --cage-vertices vertices (sorpia.decimate, quads).

Each the median of --repeat runs (the mesh rebuilt between runs, untimed), the operators also without
Blender's undo step.
The operator's time includes reading and writing Blender's mesh, the checks,
the miss of the float32 cage it reports and Blender's undo step; not the
redraw, where Blender evaluates the modifier. Writes
docs/benchmarks/blender-operators.md unless --no-page.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _report import ROOT, write_page  # noqa: E402

# Runs in Blender's Python: argv ZIP OUT.json VERTICES CAGE_VERTICES REPEAT
INNER = r'''
import json, statistics, sys, time
import bpy
import numpy as np
sys.path.insert(0, BLENDER_DIR)
from headless import install
install(sys.argv[-5])
import sorpia
from sorpia.blender import EDGE_CREASE, blender_rules, crease_weights_of
from bl_ext.user_default.sorpia_blender import read_mesh

out_path, n, n_cage, repeat = sys.argv[-4], int(sys.argv[-3]), int(sys.argv[-2]), int(sys.argv[-1])
V, F = sorpia.shapes.quad_irregular(n, seed=1)
V = V + 0.01 * np.sin(7 * V[:, [1, 2, 0]])


def make(name, V, F, crease=True):
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    for m in list(bpy.data.meshes):
        bpy.data.meshes.remove(m)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(V))
    mesh.vertices.foreach_set("co", np.asarray(V, np.float32).ravel())
    F = np.asarray(F)
    mesh.loops.add(F.size)
    mesh.loops.foreach_set("vertex_index", F.astype(np.int32).ravel())
    mesh.polygons.add(len(F))
    mesh.polygons.foreach_set("loop_start", np.arange(0, F.size, F.shape[1], dtype=np.int32))
    mesh.update(calc_edges=True)
    if crease:  # semi-sharp creases (2.5) on the first edge of each of the first 100 faces
        edges = np.empty(2 * len(mesh.edges), np.int32)
        mesh.edges.foreach_get("vertices", edges)
        w, _ = crease_weights_of(edges.reshape(-1, 2), len(V), (F[:100, :2], 2.5))
        mesh.attributes.new(EDGE_CREASE, "FLOAT", "EDGE").data.foreach_set("value", w)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.modifiers.new("Subdivision", "SUBSURF")
    return obj


def arrays(obj):
    return read_mesh(obj.data)  # the operators' own reading of Blender's mesh


def select(*objs):
    for o in bpy.context.scene.objects:
        o.select_set(o in objs)
    bpy.context.view_layer.objects.active = objs[0]


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


results = {}
cage = sorpia.decimate(V, np.vstack([F[:, [0, 1, 2]], F[:, [0, 2, 3]]]), n_cage, scheme="catmull-clark")
cases = {
    "fit": (lambda: make("fit", V, F), "sorpia_fit",
            lambda m: sorpia.interpolate(m.vertices, m.faces, scheme="catmull-clark", **blender_rules(m))),
    "fair": (lambda: make("fair", V, F), "sorpia_fair_fit",
             lambda m: sorpia.fair_interpolate(m.vertices, m.faces, scheme="catmull-clark", tol=1e-10,
                                               max_iter=1000, **blender_rules(m))),
}
for name, (build, op, library) in cases.items():
    ops, bare, libs = [], [], []
    for _ in range(repeat):
        obj = build()
        m = arrays(obj)
        libs.append(timed(lambda: library(m)))
        for undo, times in ((True, ops), (False, bare)):
            obj = build()
            select(obj)
            times.append(timed(lambda: getattr(bpy.ops.object, op)("EXEC_DEFAULT", undo)))
    results[name] = {"operator": statistics.median(ops), "no_undo": statistics.median(bare),
                     "library": statistics.median(libs), "vertices": len(V), "faces": len(F)}



def make_scan():
    mesh = bpy.data.meshes.new("scan")  # a point cloud: vertices only
    mesh.vertices.add(len(V))
    mesh.vertices.foreach_set("co", np.asarray(V, np.float32).ravel())
    scan = bpy.data.objects.new("scan", mesh)
    bpy.context.scene.collection.objects.link(scan)
    return scan


ops, bare, libs = [], [], []
points = V.astype(np.float32).astype(float)
for _ in range(repeat):
    m = arrays(make("cage", cage.vertices, cage.faces, crease=False))
    libs.append(timed(lambda: sorpia.approximate(points, m.vertices, m.faces, scheme="catmull-clark",
                                                 **blender_rules(m))))
    for undo, times in ((True, ops), (False, bare)):
        cage_obj = make("cage", cage.vertices, cage.faces, crease=False)
        select(cage_obj, make_scan())
        times.append(timed(lambda: bpy.ops.object.sorpia_fit_cage("EXEC_DEFAULT", undo)))
results["cage"] = {"operator": statistics.median(ops), "no_undo": statistics.median(bare),
                   "library": statistics.median(libs), "vertices": len(cage.vertices), "points": len(V)}
results["blender"] = bpy.app.version_string
results["numpy"] = np.__version__
json.dump(results, open(out_path, "w"))
'''

LABELS = {"fit": ("Fit Subdivision Through Vertices", "sorpia.interpolate"),
          "fair": ("Fair Fit", "sorpia.fair_interpolate"),
          "cage": ("Fit Cage to Target", "sorpia.approximate")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vertices", type=int, default=100_000)
    parser.add_argument("--cage-vertices", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--zip", default=None, help="the extension zip (default dist/sorpia_blender-VERSION.zip)")
    parser.add_argument("--no-page", action="store_true")
    args = parser.parse_args()
    import sorpia

    python = os.environ.get("SORPIA_BLENDER_PYTHON") or str(ROOT / ".venv-blender" / "bin" / "python")
    zip_path = args.zip or str(ROOT / "dist" / f"sorpia_blender-{sorpia.__version__}.zip")
    with tempfile.TemporaryDirectory() as folder:
        inner, out = Path(folder) / "inner.py", Path(folder) / "out.json"
        inner.write_text(INNER.replace("BLENDER_DIR", repr(str(ROOT / "blender"))))
        env = {**os.environ, "BLENDER_USER_RESOURCES": str(Path(folder) / "user")}
        subprocess.run([python, str(inner), zip_path, str(out), str(args.vertices), str(args.cage_vertices),
                        str(args.repeat)], check=True, env=env)
        results = json.loads(out.read_text())
    lines = ["| operator | sorpia call | mesh | operator s | without the undo step s | library s | ratio |",
             "|---|---|---|---:|---:|---:|---:|"]
    for key, (op, call) in LABELS.items():
        r = results[key]
        mesh = (f"{r['vertices']:,} vertices" if key != "cage"
                else f"cage of {r['vertices']:,} vertices, {r['points']:,} points")
        lines.append(f"| {op} | `{call}` | {mesh} | {r['operator']:.3f} | {r['no_undo']:.3f} | {r['library']:.3f} | "
                     f"{r['operator'] / r['library']:.2f} |")
    body = (f"Blender {results['blender']} (the bpy module, numpy {results['numpy']}), medians of {args.repeat} runs; "
            "the operator as the menu runs it (with Blender's undo step) and without the undo step; the library's "
            "time on the arrays the operator reads from Blender, in the same process; the ratio is the operator's "
            "(with the undo step) over the library's.\n\n"
            + "\n".join(lines))
    print(body)
    if not args.no_page:
        write_page("blender-operators", "The Blender extension's operators against the library", body,
                   settings=(parser, args))


if __name__ == "__main__":
    main()
