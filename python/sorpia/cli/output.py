"""What the commands write, and the checks of their outputs before the work.

Meshes go through one path, sorpia.io.write_mesh_file (the scheme, the
boundary rule and the tags written where the format holds them, a warning
where it does not, the file read back for the command's check); text, JSON
and PNG figures through the core's atomic writer, as meshes do
(sorpia::write_file_atomic: a temporary file in the same folder, fsync,
rename), so a failure leaves the old file or none. The checks here run
before a command reads its input or solves: an output that cannot hold
the result is refused before the work.
"""

from __future__ import annotations

import io
import json
import math
import os
from pathlib import Path

import numpy as np

from .. import SubdivisionMesh, _core
from .._usd import is_usd
from ..blender import blender_refusal
from .._validate import as_scheme
from ..io import ATTRIBUTE_WORDS, attribute_refusal, write_mesh_file
from .common import UserError, check_mesh_suffix, check_paths, face_sizes_text, is_triangles, warn_once

ATTRIBUTE_LABELS = ATTRIBUTE_WORDS  # the writer's words for the attributes (sorpia.io)
FLOAT32_MAX = float(np.finfo(np.float32).max)  # a Python float: compared with float64s, never cast down
FLOAT32_FORMATS = {".stl": "STL"}  # and USD: the formats that store float32 coordinates


def write_bytes(path, data: bytes) -> None:
    _core.write_file_atomic(os.fsencode(path), data)  # bytes: any file name the OS takes


def write_text(path, text: str) -> None:
    write_bytes(path, text.encode("utf-8"))


def jsonable(obj):
    """numpy scalars and arrays to Python, NaN and inf to None (JSON has neither)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(path, data) -> None:
    write_text(path, json.dumps(jsonable(data), indent=2) + "\n")


def save_figure(fig, path) -> None:
    """A matplotlib figure as PNG; drawn in memory first, so a failure to draw writes nothing."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    write_bytes(path, buf.getvalue())


# --------------------------------------------------------------------------- meshes


def check_outputs(inputs: list, output, surface, report, blender=None, binary: bool = False,
                  force: bool = False) -> None:
    """The checks of a command's paths before any work: mesh suffixes of -o
    and --surface, inputs readable and outputs writable (check_paths),
    --blender a .py script, --binary only with a PLY or STL output."""
    check_mesh_suffix("-o", output)
    check_mesh_suffix("--surface", surface)
    check_paths(inputs, {"-o": output, "--surface": surface, "--report": report, "--blender": blender}, force)
    if blender is not None and Path(blender).suffix.lower() != ".py":
        raise UserError(f"--blender {blender}: the script is Python, give a file name ending in .py")
    if binary and not any(Path(p).suffix.lower() in (".ply", ".stl") for p in (output, surface) if p):
        raise UserError("--binary applies to .ply and .stl outputs only (OBJ and OFF are text formats)")


def float32_format(path) -> str | None:
    """'USD' or 'STL' for an output that stores float32 coordinates, else None."""
    if path is None:
        return None
    return "USD" if is_usd(path) else FLOAT32_FORMATS.get(Path(path).suffix.lower())


def check_float32_outputs(vertices, outputs: dict) -> None:
    """Refuse, before the work, a USD or STL output (float32 coordinates) for
    data beyond float32's range (3.4e38): the result lies near the data, so
    the file could not hold it; the writer refuses it the same way
    (sorpia._usd.check_float32, the core's STL writer). `outputs`:
    {option: path or None}."""
    largest = float(np.abs(np.asarray(vertices, dtype=np.float64)).max(initial=0.0))
    if largest <= FLOAT32_MAX:
        return
    for opt, path in outputs.items():
        fmt = float32_format(path)
        if fmt is not None:
            raise UserError(f"{opt} {path}: the data reach {largest:.3g}, beyond float32, which {fmt} stores: "
                            "write .obj, .off or .ply (float64)")


def check_faces_fit(output, surface, faces, scheme: str, level: int) -> None:
    """Refuse, before the solve, an output whose format cannot hold its faces:
    STL stores triangles only, and the control mesh has the input's faces, a
    Catmull-Clark limit surface quads (its control polygons at level 0)."""
    if output is not None and Path(output).suffix.lower() == ".stl" and not is_triangles(faces):
        raise UserError(f"-o {output}: STL holds triangles only, and the control mesh has the input's faces (of "
                        f"{face_sizes_text(faces)} vertices): write .obj, .off or .ply, or pass --triangulate to "
                        "fit a triangulation with Loop")
    surface_triangles = scheme == "loop" or (level == 0 and is_triangles(faces))
    if surface is not None and Path(surface).suffix.lower() == ".stl" and not surface_triangles:
        raise UserError(f"--surface {surface}: STL holds triangles only, and the Catmull-Clark limit surface is "
                        f"{'the control polygons' if level == 0 else 'a quad mesh'}: write .obj, .off or .ply")


def check_blender(path, scheme: str, tags: dict) -> None:
    """Refuse --blender before the solve where Blender cannot draw the surface (sorpia.blender.blender_refusal)."""
    if path is None:
        return
    reason = blender_refusal(scheme, tags)
    if reason is not None:
        raise UserError(f"--blender {path}: {reason}")


def check_surface_fits(n_vertices: int, counts: np.ndarray, level: int, scheme: str) -> None:
    """Refuse --level before the solve when the tessellation would not fit in
    the memory left to the process (sorpia::available_memory_bytes: free
    memory, rlimits, cgroup limits), by the estimate limit_surface checks
    (sorpia::tessellation_bytes for the scheme); limit_surface would refuse it
    only after the solve."""
    n_corners = int(counts.sum())
    need = _core.tessellation_bytes(n_vertices, len(counts), level, as_scheme(scheme), n_corners)
    avail = _core.available_memory_bytes()
    if avail and need > avail:  # 0: not known here; limit_surface decides
        if scheme == "loop":
            output = f"{len(counts) * 4 ** level} triangles"
        else:  # a k-gon gives k quads at level 1, each 4 more per level
            output = f"{n_corners * 4 ** (level - 1) if level else len(counts)} faces"
        raise UserError(f"--surface at --level {level} needs about {need / 2**30:.1f} GiB ({output}) but "
                        f"{avail / 2**30:.1f} GiB is left to this process (free memory, ulimit -v, the cgroup's "
                        "memory limit): use a lower --level")


def binary_for(path, binary: bool) -> bool:
    """--binary for the formats that have a binary form (PLY, STL)."""
    return binary and Path(path).suffix.lower() in (".ply", ".stl")


def attributes_to_write(output, attributes: dict, faces, n_vertices: int, keep_normals: bool = False
                        ) -> tuple[dict, dict]:
    """The input's texture coordinates and normals an output is written with,
    and a note on each: {name: "written" or why not}.

    Texture coordinates are carried: the control mesh has the input's faces,
    and OpenSubdiv interpolates face-varying data over the control mesh's faces
    (as the input's were meant to be). Normals only with `keep_normals` (a
    repaired mesh, the same surface): a control mesh's are not written, since
    they describe the input surface, the control mesh is no surface to shade
    (a subdivision renderer takes the limit surface's normals from its
    derivatives), and the limit surface through the targets has its own
    normals there. A format that cannot hold them (OFF, STL; PLY where a
    vertex has several, a seam: sorpia.io.attribute_refusal, the writer's own
    check) leaves them out with a warning, before the solve."""
    written, notes = {}, {}
    for name, channel in attributes.items():
        if name == "normals" and not keep_normals:
            notes[name] = "not written: they are the input surface's; the limit surface has its own"
            continue
        reason = attribute_refusal(output, name, channel, faces, n_vertices)
        if reason is None:
            written[name], notes[name] = channel, "written"
            continue
        label = ATTRIBUTE_LABELS[name]
        way = "" if ".obj" in reason else "; write .obj to keep them"
        warn_once(f"-o {output}: the input's {label} are not written: {reason}{way}")
        notes[name] = f"not written: {reason}{way}"
    return written, notes


def attribute_lines(notes: dict) -> list[str]:
    """A summary's lines for attributes_to_write's notes ({name: "written" or why not})."""
    return [f"  {'attributes' if j == 0 else '':<12}{ATTRIBUTE_LABELS[name]} {note}"
            for j, (name, note) in enumerate(notes.items())]


def write_control_mesh(output, vertices, faces, *, scheme, boundary, tags: dict, binary: bool = False,
                       attributes=None, template=None):
    """A command's control mesh (cage), as one sorpia.SubdivisionMesh (its
    scheme, boundary rule, tags and attributes), through the library's one
    writer path (sorpia.io.write_mesh_file): the rules written where the
    format holds them, a warning for each that it cannot; returns its
    WrittenMesh (the vertices read back from the file, the rules written).
    `scheme` None (a mesh file without one, `repair`): not written, nor
    warned of."""
    if scheme is None:
        return write_mesh_file(output, vertices, faces, boundary=boundary, binary=binary_for(output, binary),
                               **tags, **(attributes or {}), **(template or {}))
    mesh = SubdivisionMesh(vertices, faces, scheme=scheme, boundary=boundary, **tags, **(attributes or {}))
    return write_mesh_file(output, mesh, binary=binary_for(output, binary), **(template or {}))


def write_surface(path, vertices, faces, binary: bool = False) -> None:
    """A tessellated limit surface: a plain mesh, no rules."""
    write_mesh_file(path, vertices, faces, binary=binary_for(path, binary))


def summary_text(lines: list, surface) -> str:
    """A fit's summary lines, the written surface's line (`surface`: the report's "surface" entry, or None)
    before the last ("wrote"), as one text: what fit and fit --fair print."""
    if surface:
        lines.insert(-1, f"  surface     level {surface['level']}: {surface['vertices']} vertices, "
                         f"{surface['faces']} faces")
    return "\n".join(lines)
