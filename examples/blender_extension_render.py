"""Render the before/after picture of docs/blender.md with the extension, headless.

Installs the extension zip (``make blender-extension``) into a temporary
Blender user folder, in Blender's Python (SORPIA_BLENDER_PYTHON, else
../.venv-blender), and draws Suzanne twice with a Subdivision Surface
modifier: on the left as she is (the limit surface shrinks inside her
vertices, the red points), on the right after Object > sorpia > Fit
Subdivision Through Vertices (it passes through them). Workbench, to the PNG
named on the command line.

    python examples/blender_extension_render.py docs/images/blender-extension.png
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SCENE = r"""
import sys
import bpy
import numpy as np
sys.path.insert(0, {blender_dir!r})
from headless import install
install({zip!r})
bpy.ops.wm.read_homefile(use_empty=True)
scene = bpy.context.scene

def suzanne(x):
    bpy.ops.mesh.primitive_monkey_add(location=(x, 0.0, 0.0), rotation=(0.0, 0.0, 0.3 if x < 0 else -0.3))
    obj = bpy.context.object
    modifier = obj.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = 3
    for polygon in obj.data.polygons:
        polygon.use_smooth = True
    obj.color = (0.75, 0.78, 0.85, 1.0)
    return obj

def points(obj):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.018, segments=10, ring_count=6)
    template = bpy.context.object
    dot = template.data
    bpy.data.objects.remove(template)
    world = np.array(obj.matrix_world)
    for v in obj.data.vertices:
        p = world @ np.r_[v.co[:], 1.0]
        o = bpy.data.objects.new("dot", dot)
        o.location = p[:3]
        o.color = (0.9, 0.1, 0.1, 1.0)
        scene.collection.objects.link(o)

before, after = suzanne(-1.45), suzanne(1.45)
points(before)
points(after)
for o in scene.objects:
    o.select_set(o is after)
bpy.context.view_layer.objects.active = after
bpy.ops.object.sorpia_fit()
bpy.ops.object.camera_add(location=(0.0, -8.0, 0.9), rotation=(1.46, 0.0, 0.0))
scene.camera = bpy.context.object
scene.camera.data.lens = 48
scene.render.engine = "BLENDER_WORKBENCH"
scene.display.shading.color_type = "OBJECT"
scene.display.shading.show_cavity = True
scene.render.resolution_x, scene.render.resolution_y = 840, 380
scene.render.image_settings.color_mode = "RGB"
scene.render.image_settings.compression = 100
scene.render.filepath = {output!r}
bpy.ops.render.render(write_still=True)
"""


def main(output: str) -> None:
    import sorpia

    python = os.environ.get("SORPIA_BLENDER_PYTHON") or str(ROOT / ".venv-blender" / "bin" / "python")
    zip_path = ROOT / "dist" / f"sorpia_blender-{sorpia.__version__}.zip"
    with tempfile.TemporaryDirectory() as folder:
        script = Path(folder) / "scene.py"
        script.write_text(SCENE.format(blender_dir=str(ROOT / "blender"), zip=str(zip_path),
                                       output=str(Path(output).resolve())))
        env = {**os.environ, "BLENDER_USER_RESOURCES": str(Path(folder) / "user")}
        subprocess.run([python, str(script)], check=True, env=env)


if __name__ == "__main__":
    main(sys.argv[1])
