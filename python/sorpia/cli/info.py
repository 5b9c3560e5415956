"""``sorpia info``: mesh statistics (the paper's Table 2) and whether Loop PIA can run."""

from __future__ import annotations

import json
import sys

from .._validate import DEFAULT_BOUNDARY
from .common import EXIT_OK, read_input, repair_lines
from .output import jsonable

MAX_LISTED = 16  # extraordinary vertices listed in the text output (--json lists all)


def run_info(input_path, *, as_json=False, boundary=DEFAULT_BOUNDARY, triangulate=False,
             repair=False, out=None) -> tuple[int, dict]:
    """`sorpia info`: mesh statistics and whether Loop PIA can run (exit 0 either way).

    A file with polygons is described as its fan triangulation, with the
    verdict that Loop PIA cannot run on it as it is (--triangulate). With
    `repair`, everything is of the repaired mesh and info["repair"] says what
    changed; without it, a mesh Loop PIA cannot run on is repaired in memory
    and info["repair"] says what --repair would change (or why it cannot)."""
    from ..meshinfo import format_info, mesh_info

    out = out if out is not None else sys.stdout
    # One read, polygons split whether or not --triangulate was given (the
    # statistics are of the fan triangulation either way); the count says
    # whether the verdict must send the user to --triangulate.
    mesh = read_input(input_path, triangulate=True, repair=repair)
    polygons = mesh.polygons > 0 and not triangulate
    info = mesh_info(mesh.vertices, mesh.faces, boundary=boundary,
                     list_extraordinary=True if as_json else MAX_LISTED)
    if repair:
        info["repair"] = {"applied": True, "changes": repair_lines(mesh.repair),
                          "counts": mesh.repair.report["counts"]}
    elif not info["loop_pia"]["can_run"]:
        info["repair"] = _what_repair_would_do(mesh.vertices, mesh.faces)
    info["triangulated"] = bool(triangulate or polygons)
    if polygons and info["loop_pia"]["can_run"]:
        info["loop_pia"] = {"can_run": False, "notes": [],
                            "reason": "the file has faces of more than 3 vertices (the counts are of their fan "
                            "triangulation); pass --triangulate to fit, compare or render to split them"}
    if as_json:
        print(json.dumps(jsonable({"input": str(input_path), **info}), indent=2), file=out)
    else:
        print(format_info(info, str(input_path), max_listed=MAX_LISTED), file=out)
    return EXIT_OK, info


def _what_repair_would_do(vertices, faces) -> dict:
    """sorpia.repair run in memory on a mesh Loop PIA refuses: the changes it
    would make, one line per kind, or the reason it refuses the mesh too."""
    from .. import MeshError
    from .. import repair as repair_mesh
    from ..mesh_repair import describe_changes

    try:
        result = repair_mesh(vertices, faces)
    except (MeshError, ValueError, TypeError) as exc:
        return {"applied": False, "refused": str(exc)}
    return {"applied": False, "changes": describe_changes(result.report), "counts": result.report["counts"]}
