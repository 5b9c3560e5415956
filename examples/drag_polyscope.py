"""Drag a target vertex with a slider and watch the interpolating limit surface follow (needs polyscope).

    pip install polyscope
    python examples/drag_polyscope.py

polyscope is an optional dependency of this example only. Each frame the
slider's height moves one target; `Interpolator.update` re-solves locally
from the previous control vertices and the limit surface (sorpia.limit_surface,
two refinement levels) is redrawn. This example needs a display and is not
run by the tests.
"""

from __future__ import annotations

import numpy as np
import polyscope as ps
import polyscope.imgui as psim

import sorpia

V, F = sorpia.shapes.icosphere(3)
interp = sorpia.Interpolator(F, len(V))
result = interp.solve(V)
targets = V.copy()
picked, height, status = 0, 0.0, "move the slider"

ps.init()
ps.register_point_cloud("targets", targets, radius=0.004)
surface = sorpia.limit_surface(result.control_vertices, F, level=2)
ps.register_surface_mesh("limit surface", surface[0], surface[1])


def frame():
    global result, height, status
    changed, height = psim.SliderFloat("height of vertex 0", height, -0.5, 0.5)
    psim.TextUnformatted(status)
    if not changed:
        return
    targets[picked] = V[picked] * (1.0 + height)
    result = interp.update(result, [picked], targets[picked], in_place=True)
    status = f"update: {result.seconds * 1e3:.2f} ms, {result.relaxations} relaxations"
    ps.get_point_cloud("targets").update_point_positions(targets)
    verts, _ = sorpia.limit_surface(result.control_vertices, F, level=2)
    ps.get_surface_mesh("limit surface").update_vertex_positions(verts)


ps.set_user_callback(frame)
ps.show()
