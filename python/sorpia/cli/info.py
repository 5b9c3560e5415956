"""``sorpia info``: mesh statistics (the paper's Table 2), the scheme and the
sharpness tags, and whether PIA can run."""

from __future__ import annotations

import json
import sys
import warnings

import numpy as np

from .. import Interpolator, MeshError, MeshFileError, ParameterError
from .. import repair as repair_mesh
from .._meshinfo import format_info, mesh_info
from .._repair import describe_changes
from .._usd import is_usd
from .common import (EXIT_OK, SCHEME_LABELS, UserError, boundary_rule, choose_scheme, face_size_histogram,
                     is_triangles, read_input, repair_lines, scheme_kwargs, solve_tags, tags_lines, tags_summary)
from .output import jsonable

MAX_LISTED = 16  # extraordinary vertices listed in the text output (--json lists all)


def run_info(input_path, *, as_json=False, boundary=None, triangulate=False, repair=False, scheme="auto",
             ignore_tags=False, sharp_angle=None, nonmanifold="error", out=None, prim=None) -> tuple[int, dict]:
    """`sorpia info`: mesh statistics, the scheme, the tags, and whether PIA
    can run (exit 0 either way).

    The statistics are of the mesh as the scheme sees it: a file with
    polygons as it is under Catmull-Clark, as its triangulation (the read with
    --triangulate) when Loop was asked for; its faces by size either way. The verdict is the library's own: the solve's
    validation of the faces, scheme and tags. Tags the reader refuses (a
    crease method sorpia does not have, a malformed tag) are reported, and
    the mesh described without them, and the verdict is fit's: it cannot
    run (fit refuses the file). With `repair`, everything is of the
    repaired mesh and info["repair"] says what changed; without it, a mesh
    Loop PIA cannot run on is repaired in memory and info["repair"] says what
    --repair would change (or why it cannot)."""
    out = out if out is not None else sys.stdout
    tags_refused = None
    try:
        mesh = read_input(input_path, triangulate=triangulate, repair=repair, tags=not ignore_tags,
                          nonmanifold=nonmanifold, prim=prim)
    except MeshFileError as exc:
        if ignore_tags:
            raise
        # A file that reads without its tags was refused for them (a rule sorpia has not, a malformed tag, a
        # token USD does not define): described without them, the verdict fit's.
        try:
            mesh = read_input(input_path, triangulate=triangulate, repair=repair, tags=False,
                              nonmanifold=nonmanifold, prim=prim)
        except MeshFileError:
            raise exc from None
        tags_refused = str(exc)
    polygons = not is_triangles(mesh.faces)
    try:
        chosen = choose_scheme(scheme, mesh.faces, input_path, mesh.tags.get("scheme"))
        refusal = None
    except UserError as exc:  # --scheme loop on polygons
        chosen, refusal = scheme, str(exc)
    # The statistics are of the mesh under its scheme (polygons as they are for Catmull-Clark); with Loop
    # refused on polygons, of their triangulation (a USD file's as they are: sorpia triangulates while reading
    # the other formats only).
    counted = (read_input(input_path, triangulate=True, repair=repair, tags=False, prim=prim)
               if polygons and refusal and not is_usd(input_path) else mesh)
    info = mesh_info(counted.vertices, counted.faces, boundary=boundary_rule(boundary, mesh),
                     list_extraordinary=True if as_json else MAX_LISTED, scheme="loop" if refusal else chosen)
    info["face_sizes"] = face_size_histogram(mesh.faces)
    info["triangulated"] = bool(triangulate or (polygons and refusal))
    info["scheme"] = chosen
    info["boundary"] = boundary_rule(boundary, mesh)
    tags = solve_tags(mesh, sharp_angle, input_path)
    info["tags"] = {"from_file": not ignore_tags, "sharp_angle": sharp_angle, **tags_summary(tags),
                    **({"refused": tags_refused} if tags_refused else {})}
    if repair:
        info["repair"] = {"applied": True, "changes": repair_lines(mesh.repair),
                          "counts": mesh.repair.changes["counts"]}
    elif not info["loop_pia"]["can_run"]:  # what --repair would do: to the faces as read (polygons kept)
        info["repair"] = _what_repair_would_do(mesh.vertices, mesh.faces)
    if polygons and (info["loop_pia"]["can_run"] or is_usd(input_path)):
        if is_usd(input_path):  # read as it is: sorpia triangulates while reading OBJ, OFF and PLY only
            reason = ("the file has faces of more than 3 vertices: Loop needs triangles, and a USD file is fitted "
                      "with its faces as they are (Catmull-Clark: --scheme auto or catmull-clark)")
        elif refusal:
            reason = ("the file has faces of more than 3 vertices (the counts are of their triangulation); pass "
                      "--triangulate to split them, or --scheme catmull-clark")
        else:
            reason = "the file has faces of more than 3 vertices: Loop needs triangles (--triangulate splits them)"
        info["loop_pia"] = {"can_run": False, "notes": [], "reason": reason}
    if tags_refused:  # fit refuses the file: so does the verdict
        reason = f"fit refuses the file's tags: {tags_refused} (--ignore-tags fits without them)"
        if info["loop_pia"]["can_run"]:
            info["loop_pia"] = {"can_run": False, "notes": info["loop_pia"].get("notes", []), "reason": reason}
        refusal = refusal or reason
    info["pia"] = _verdict(chosen, refusal, mesh, tags, info)
    if as_json:
        print(json.dumps(jsonable({"input": str(input_path), **info}), indent=2), file=out)
    else:
        print(format_info(info, str(input_path), max_listed=MAX_LISTED, extra_rows=_scheme_rows(info)), file=out)
    return EXIT_OK, info


def _verdict(scheme: str, refusal, mesh, tags: dict, info: dict) -> dict:
    """Whether PIA can run with the scheme and the tags, and if not why: the
    Interpolator's own validation, or Loop's verdict for Loop without tags."""
    if refusal is not None:
        return {"scheme": scheme, "can_run": False, "reason": refusal}
    if scheme == "loop" and not tags:
        return {"scheme": scheme, **{k: info["loop_pia"][k] for k in ("can_run", "reason")}}
    try:
        kwargs = scheme_kwargs(scheme, tags)
        with warnings.catch_warnings():  # unreferenced vertices: the statistics' notes say it
            warnings.simplefilter("ignore")
            interp = Interpolator(mesh.faces, len(mesh.vertices), boundary=info["boundary"], **kwargs)
    except (UserError, MeshError, ParameterError, TypeError) as exc:
        return {"scheme": scheme, "can_run": False, "reason": str(exc)}
    return {"scheme": scheme, "can_run": True, "reason": None, **_valence_two(interp.topology)}


def _valence_two(topo) -> dict:
    """Interior vertices of valence 2, which can make B indefinite (next to
    faces of more than four sides: with exact rows, quads split by them keep
    B positive): the stationary methods (pia, wpia, gs, sor, hss, whss) may
    diverge there, and the default method auto then falls back to gmres."""
    valence = np.diff(np.asarray(topo.ring_offsets))
    found = np.flatnonzero((valence == 2) & ~np.asarray(topo.is_boundary))
    if len(found) == 0:
        return {}
    return {"valence_two": found[:MAX_LISTED].tolist(), "note": (
        f"{len(found)} interior vert{'ex' if len(found) == 1 else 'ices'} of valence 2 (the first: "
        f"{found[:4].tolist()}): next to faces of more than four sides they can make B indefinite, where pia, wpia, "
        "gs, sor, hss and whss may diverge; the default method auto then falls back to gmres")}


def _scheme_rows(info: dict) -> list[tuple[str, str]]:
    """The rows of the scheme, the faces by size, the tags and the verdict."""
    names = {3: "triangles", 4: "quads"}
    rows = [("faces by size", ", ".join(f"{c} {names.get(k, f'{k}-gons')}" for k, c in info["face_sizes"].items())),
            ("scheme", f"{SCHEME_LABELS.get(info['scheme'], info['scheme'])}, boundary {info['boundary']}")]
    tags = info["tags"]
    lines = tags_lines(tags)
    if tags.get("refused"):
        rows.append(("tags", f"refused, the mesh described without them: {tags['refused']}"))
    elif not lines:
        rows.append(("tags", "none" if tags["from_file"] else "none (--ignore-tags)"))
    rows += [("tags" if j == 0 else "", line) for j, line in enumerate(lines)]
    if tags.get("sharp_angle") is not None:
        rows.append(("", f"(with the creases of --sharp-angle {tags['sharp_angle']:g})"))
    v = info["pia"]
    label = f"{SCHEME_LABELS.get(v['scheme'], v['scheme'])} PIA"
    if v["scheme"] != "loop" or lines:  # Loop without tags: the Loop PIA row above says it
        rows.append((label, "can run" if v["can_run"] else f"cannot run: {v['reason']}"))
    if v.get("note"):
        rows.append(("", v["note"]))
    return rows


def _what_repair_would_do(vertices, faces) -> dict:
    """sorpia.repair run in memory on a mesh PIA refuses (triangles or
    polygons, as --repair takes them): the changes it would make, one line
    per kind, or the reason it refuses the mesh too."""
    try:
        result = repair_mesh(vertices, faces)
    except (MeshError, ValueError, TypeError) as exc:
        return {"applied": False, "refused": str(exc)}
    return {"applied": False, "changes": describe_changes(result.changes), "counts": result.changes["counts"]}
