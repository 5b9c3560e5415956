"""``sorpia repair``: a mesh file made valid for subdivision (sorpia.repair), written to another file."""

from __future__ import annotations

import sys

from .. import __version__
from .._validate import DEFAULT_BOUNDARY
from .common import (EXIT_OK, check_mesh_suffix, check_paths, face_counts, read_input, repair_json, repair_lines,
                     sharpness_tags, usd_template)
from .output import attributes_to_write, check_float32_outputs, write_control_mesh, write_json


def run_repair(input_path, output, *, report=None, triangulate=False, quiet=False, force=False,
               out=None, prim=None) -> tuple[int, dict]:
    """`sorpia repair`: returns (exit code, report dict). A valid mesh is
    written unchanged; one repair refuses (no face left) is a UserError."""
    out = out if out is not None else sys.stdout
    check_mesh_suffix("-o", output)
    check_paths([input_path], {"-o": output, "--report": report}, force)
    mesh = read_input(input_path, triangulate, repair=True, attributes=True, prim=prim)
    check_float32_outputs(mesh.vertices, {"-o": output})
    # the file's scheme, boundary rule, tags, texture coordinates and normals, carried onto the repaired mesh
    # (the same surface)
    attributes, _ = attributes_to_write(output, mesh.attributes, mesh.faces, len(mesh.vertices), keep_normals=True)
    write_control_mesh(output, mesh.vertices, mesh.faces, scheme=mesh.tags.get("scheme"),
                       boundary=mesh.tags.get("boundary", DEFAULT_BOUNDARY), tags=sharpness_tags(mesh.tags),
                       attributes=attributes, template=usd_template(input_path, output, prim))
    n_faces = len(face_counts(mesh.faces))
    data = {"sorpia_version": __version__, "command": "repair", "input": str(input_path),
            "triangulated": triangulate, "output": str(output), "vertices": len(mesh.vertices),
            "faces": n_faces, **repair_json(mesh.repair)}
    if report is not None:
        write_json(report, data)
    if not quiet:
        changed = any(mesh.repair.changes["counts"].values())
        print(f"sorpia repair: {input_path} -> {output} ({len(mesh.vertices)} vertices, {n_faces} faces"
              + ("" if changed else "; the mesh is valid: written unchanged") + ")", file=out)
        for line in repair_lines(mesh.repair) if changed else []:
            print(f"  {line}", file=out)
    return EXIT_OK, data
