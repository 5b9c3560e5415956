"""Render a fitted cage in Blender, headless: the picture of docs/blender.md.

Run with a Python that has both sorpia and bpy, or in two steps as here: this
script (with sorpia) fits a creased quad torus and writes the bpy script with
sorpia's --blender writer, then runs Blender's Python (SORPIA_BLENDER_PYTHON,
else ../.venv-blender) on it with a camera, a light and the targets as small
red spheres, rendering with Workbench to the PNG named on the command line.

    python examples/blender_render.py docs/images/blender-cage.png
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import sorpia
from sorpia.blender import blender_script

SCENE = """
import bpy
targets = {targets!r}
for p in targets:
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.035, location=p, segments=12, ring_count=8)
    bpy.context.object.color = (0.9, 0.1, 0.1, 1.0)
cage = bpy.data.objects["sorpia_cage"]
cage.color = (0.75, 0.78, 0.85, 1.0)
for polygon in cage.data.polygons:
    polygon.use_smooth = True
bpy.ops.object.camera_add(location=(4.0, -3.2, 3.6))
camera = bpy.context.object
aim = camera.constraints.new("TRACK_TO")  # at the origin, the torus's centre
aim.target = bpy.data.objects.new("centre", None)
aim.track_axis, aim.up_axis = "TRACK_NEGATIVE_Z", "UP_Y"
scene = bpy.context.scene
scene.collection.objects.link(aim.target)
scene.camera = camera
scene.render.engine = "BLENDER_WORKBENCH"
scene.display.shading.color_type = "OBJECT"
scene.display.shading.show_cavity = True
scene.render.resolution_x, scene.render.resolution_y = 900, 560
scene.render.filepath = {output!r}
bpy.ops.render.render(write_still=True)
"""


def main(output: str) -> None:
    nu, nv = 16, 8
    V, F = sorpia.shapes.quad_torus(nu, nv)
    V = V + 0.08 * np.sin(3 * V[:, [1, 2, 0]])
    v = np.arange(nv)
    ring = np.stack([v, (v + 1) % nv], axis=1).astype(np.int32)  # the tube's ring at u = 0: a closed crease
    tags = {"creases": (np.vstack([ring, ring + 8 * nv]), np.r_[np.full(nv, np.inf), np.full(nv, 2.0)])}
    res = sorpia.interpolate(V, F, scheme="catmull-clark", **tags)
    python = os.environ.get("SORPIA_BLENDER_PYTHON") or str(Path(__file__).resolve().parents[1] / ".venv-blender"
                                                             / "bin" / "python")
    with tempfile.TemporaryDirectory() as folder:
        script = Path(folder) / "scene.py"
        text = blender_script(res.control_vertices, F, **tags)
        text = "import bpy\nbpy.ops.wm.read_factory_settings(use_empty=True)\n" + text
        script.write_text(text + SCENE.format(targets=V.tolist(), output=str(Path(output).resolve())))
        subprocess.run([python, str(script)], check=True)


if __name__ == "__main__":
    main(sys.argv[1])
