"""``sorpia info``: mesh statistics (the paper's Table 2) and whether Loop PIA can run."""

from __future__ import annotations

import json
import sys

from .._validate import DEFAULT_BOUNDARY
from .common import EXIT_OK, read_input
from .output import jsonable

MAX_LISTED = 16  # extraordinary vertices listed in the text output (--json lists all)


def run_info(input_path, *, as_json=False, boundary=DEFAULT_BOUNDARY, triangulate=False,
             out=None) -> tuple[int, dict]:
    """`sorpia info`: mesh statistics and whether Loop PIA can run (exit 0 either way).

    A file with polygons is described as its fan triangulation, with the
    verdict that Loop PIA cannot run on it as it is (--triangulate)."""
    from ..meshinfo import format_info, mesh_info

    out = out if out is not None else sys.stdout
    # One read, polygons split whether or not --triangulate was given (the
    # statistics are of the fan triangulation either way); the count says
    # whether the verdict must send the user to --triangulate.
    V0, F, _, n_polygons = read_input(input_path, triangulate=True)
    polygons = n_polygons > 0 and not triangulate
    info = mesh_info(V0, F, boundary=boundary, list_extraordinary=True if as_json else MAX_LISTED)
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
