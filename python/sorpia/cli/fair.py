"""``sorpia fit --fair``: a control mesh `--levels` subdivision steps finer
than the input whose limit surface passes through the input's vertices (or
those of ``--targets``) and bends least (sorpia.fair_interpolate)."""

from __future__ import annotations

import math
import re
import sys
import time
from pathlib import Path

import numpy as np

from .. import ParameterError, __version__, fair_interpolate, limit_surface
from .._checks import interpolation_miss
from .._meshinfo import topology_info
from .._usd import is_usd
from ..blender import write_blender_script
from ..limit import topology as build_topology
from .common import (EXIT_NOT_CONVERGED, EXIT_OK, FAIR_DEFAULTS, SCHEME_LABELS, UserError, face_counts,
                     face_size_histogram, fmt_seconds, read_solve_input, repair_json, repair_lines, scheme_kwargs,
                     tags_lines, tags_summary, usd_template, warn_once)
from .output import (ATTRIBUTE_LABELS, check_blender, check_float32_outputs, check_outputs, check_surface_fits,
                     summary_text, write_control_mesh, write_json, write_surface)
from .progress import Progress

# A vertex index in a --targets file: ASCII digits only (Python's int() also takes '1_0' and other scripts' digits).
_INDEX = re.compile(r"[+-]?[0-9]+")


def read_targets(path) -> tuple[np.ndarray, list[int]]:
    """The vertex indices of a --targets file, and the line of each: whole
    numbers separated by spaces, commas or newlines, '#' to the end of a line
    a comment (a UserError names the line of a word that is not one). Their
    values (at least one, each a vertex, none twice) are the library's to
    check; `on_line` puts the lines into its message."""
    out, line_of = [], []
    try:
        with open(path, encoding="utf-8") as fh:
            lines = fh.read().splitlines()
    except UnicodeDecodeError as exc:
        raise UserError(f"--targets {path}: the file is not UTF-8 text (byte {exc.start}: "
                        f"{exc.object[exc.start:exc.start + 1]!r}); it holds vertex indices as ASCII digits") from None
    for line_no, line in enumerate(lines, 1):
        for word in line.split("#", 1)[0].replace(",", " ").split():
            if not _INDEX.fullmatch(word):
                raise UserError(f"--targets {path}, line {line_no}: {word!r} is not a vertex index (a whole "
                                "number in ASCII digits)")
            out.append(min(max(int(word), _INT64_MIN), _INT64_MAX))  # beyond int64: out of range all the same
            line_of.append(line_no)
    return np.array(out, dtype=np.int64), line_of


def on_line(message: str, line_of: list[int]) -> str:
    """The library's message about targets[i] with the file's line of each
    entry it names ("targets[2] (line 3) = 5 repeats targets[0] (line 1)")."""
    def named(m: re.Match) -> str:
        i = int(m.group(1))
        return f"{m.group(0)} (line {line_of[i]})" if i < len(line_of) else m.group(0)
    return re.sub(r"targets\[(\d+)\]", named, message)


_INT64_MIN, _INT64_MAX = int(np.iinfo(np.int64).min), int(np.iinfo(np.int64).max)


def run_fair(input_path, output, *, levels=1, membrane=0.0, targets=None, tol=None, max_iter=None,
             boundary=None, surface=None, level=3, report=None, quiet=False, force=False, triangulate=False,
             binary=False, threads=1, repair=False, scheme="auto", ignore_tags=False, sharp_angle=None, out=None,
             prim=None, blender=None) -> tuple[int, dict]:
    """`sorpia fit --fair`: returns (exit code, report dict). The targets are
    met to rounding whatever the iteration stops at, so the control mesh is
    always written; exit code 1 when the iteration reached --max-iter before
    the energy settled to --tol. `tol` and `max_iter` None: fair_interpolate's
    defaults (FAIR_DEFAULTS)."""
    out = out if out is not None else sys.stdout
    tol = FAIR_DEFAULTS["tol"] if tol is None else tol
    max_iter = FAIR_DEFAULTS["max_iter"] if max_iter is None else max_iter
    check_outputs([input_path] + ([targets] if targets is not None else []), output, surface, report, blender,
                  binary, force)

    timings: dict[str, float] = {}
    with Progress("fit --fair", enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        mesh, scheme, boundary, tags = read_solve_input(
            input_path, triangulate=triangulate, repair=repair, ignore_tags=ignore_tags, nonmanifold="error",
            scheme=scheme, boundary=boundary, sharp_angle=sharp_angle, attributes=True, prim=prim)
        if "uvs" in mesh.attributes:  # read to say so: the fine cage has other faces, and nothing refines them
            warn_once(f"-o {output}: the input's {ATTRIBUTE_LABELS['uvs']} are not written: the fair control mesh "
                      f"has the faces of {levels} refinement{'s' if levels > 1 else ''}, and fit --fair does not refine "
                      "face-varying data; fit without --fair keeps them")
        V0, F = mesh.vertices, mesh.faces
        timings.update(mesh.timings)
        fine_kind = "triangles" if scheme == "loop" else "quads"
        if Path(output).suffix.lower() == ".stl" and scheme != "loop":
            raise UserError(f"-o {output}: STL holds triangles only, and the fair control mesh of Catmull-Clark is "
                            "made of quads: write .obj, .off or .ply")
        if surface is not None and Path(surface).suffix.lower() == ".stl" and scheme != "loop":
            raise UserError(f"--surface {surface}: STL holds triangles only, and the Catmull-Clark limit surface is "
                            "a quad mesh: write .obj, .off or .ply")
        check_float32_outputs(V0, {"-o": output, "--surface": surface})
        check_blender(blender, scheme, tags)
        target_ids, target_lines = (None, []) if targets is None else read_targets(targets)
        if surface is not None:  # the fine mesh's faces, tessellated --level more times
            n_fine_faces = (len(F) * 4 if scheme == "loop" else int(np.sum(face_counts(F)))) * 4 ** (levels - 1)
            check_surface_fits(len(V0) * 4 ** levels, np.full(n_fine_faces, 3 if scheme == "loop" else 4), level,
                                scheme)
        progress.status(f"fair interpolation, {levels} level{'s' if levels > 1 else ''} finer")
        t0 = time.perf_counter()
        try:
            res = fair_interpolate(V0, F, levels=levels, membrane=membrane, targets=target_ids,
                                   boundary=boundary, tol=tol, max_iter=max_iter, threads=threads,
                                   **scheme_kwargs(scheme, tags))
        except ParameterError as exc:  # the library's check of the targets, named with the file they came from
            if targets is not None and str(exc).startswith("targets"):
                raise UserError(f"--targets {targets}: {on_line(str(exc), target_lines)}") from None
            raise
        timings["fit"] = time.perf_counter() - t0
        stats = topology_info(V0, build_topology(F, len(V0), scheme=scheme, warn=False), scheme=scheme)
        ctrl = np.asarray(res.control_vertices)

        progress.status(f"writing {output}")
        t0 = time.perf_counter()
        # The fine cage with its scheme, boundary rule and refined tags where the format holds them; read back
        # for the check below.
        written = write_control_mesh(output, ctrl, res.faces, scheme=scheme, boundary=boundary, tags=res.tags,
                                     binary=binary, template=usd_template(input_path, output, prim))
        if blender is not None:
            write_blender_script(blender, ctrl, res.faces, boundary=boundary, **res.tags)
        timings["write"] = time.perf_counter() - t0
        surface_stats = None
        if surface is not None:
            progress.status(f"limit surface, level {level}")
            t0 = time.perf_counter()
            Vs, Fs = limit_surface(ctrl, res.faces, level=level, boundary=boundary, **scheme_kwargs(scheme, res.tags))
            write_surface(surface, Vs, Fs, binary)
            timings["surface"] = time.perf_counter() - t0
            surface_stats = {"path": str(surface), "level": level, "vertices": len(Vs), "faces": len(Fs)}
        # A check of what was written, independent of the solver's elimination: the limit positions of the fine
        # cage as read back from the file (USD stores float32) at the targets.
        progress.status("checking the targets")
        t0 = time.perf_counter()
        max_residual = interpolation_miss(written.vertices, V0[res.targets], res.faces, boundary=boundary,
                                          scheme=scheme, tags=res.tags, rows=res.targets)
        timings["check"] = time.perf_counter() - t0

    diag = stats.get("diagonal") or 1.0
    fair_report = res.report()
    data = {
        "sorpia_version": __version__,
        "command": "fit",
        "fair": True,
        "input": str(input_path),
        "triangulated": triangulate,
        "scheme": scheme,
        "face_sizes": face_size_histogram(F),
        "tags": {"from_file": not ignore_tags, "sharp_angle": sharp_angle, **tags_summary(tags),
                 "written_to_output": list(written.written)},
        "fine_tags": tags_summary(res.tags),
        "repair": repair_json(mesh.repair) if repair else None,
        "output": str(output),
        "written": True,
        "surface": surface_stats,
        "blender": None if blender is None else str(blender),
        "report": None if report is None else str(report),
        "mesh": stats,
        "boundary": boundary,
        "levels": levels,
        "thin_plate": 1.0,
        "membrane": membrane,
        "targets": {"file": None if targets is None else str(targets), "count": int(len(res.targets))},
        "fine_mesh": {"vertices": int(len(ctrl)), "faces": int(len(res.faces)), "face_kind": fine_kind},
        # energies in model units (inf where beyond double), and exactly in units of 2^energy_exponent
        **{key: fair_report[key] for key in ("energy", "plain_energy", "energy_ratio", "energy_exponent",
                                             "energy_scaled", "plain_energy_scaled", "history")},
        "tol": tol,
        "max_iter": max_iter,
        "threads": threads,
        "iterations": int(res.iterations),
        "stop_reason": res.stop_reason,
        "converged": bool(res.converged),
        "plain": {"variant": res.plain.variant, "iterations": int(res.plain.iterations),
                  "stop_reason": res.plain.stop_reason},
        "max_residual": max_residual,
        "max_residual_relative": max_residual / diag,
        "timings": {**timings, **{f"fit.{k}": float(v) for k, v in res.timings.items()}},
    }
    if report is not None:
        write_json(report, data)
    if not quiet:
        print(fair_summary(data, repair_lines(mesh.repair) if repair else ()), file=out)
    return (EXIT_OK if res.converged else EXIT_NOT_CONVERGED), data


def energy(d: dict, key: str) -> str:
    """An energy of the report as printed: in model units squared, or where that leaves double's range (data
    beyond 2^+-200: inf, or below the normal range) as the scaled value times its power of two."""
    value, scaled = d[key], d.get(key + "_scaled", d[key])
    if not d.get("energy_exponent") or scaled == 0 or (math.isfinite(value) and abs(value) >= sys.float_info.min):
        return f"{value:.6g}"
    return f"{scaled:.6g} x 2^{d['energy_exponent']}"


def fair_summary(d: dict, repaired=()) -> str:
    """The summary `sorpia fit --fair` prints."""
    ratio = d["energy_ratio"]
    state = (f"{d['iterations']} iterations ({d['stop_reason']}: the energy fell by less than {d['tol']:g} of "
             "itself over the last iterations)" if d["converged"] else
             f"stopped at --max-iter {d['max_iter']} before the energy settled (exit code 1; the targets are met "
             "all the same)")
    t = d["timings"]
    inner = ", ".join(f"{k[4:]} {fmt_seconds(v)}" for k, v in t.items() if k.startswith("fit."))
    phases = ", ".join(f"{k} {fmt_seconds(v)}" + (f" ({inner})" if k == "fit" and inner else "")
                       for k, v in t.items() if not k.startswith("fit."))
    written = [d["output"]] + ([d["surface"]["path"]] if d["surface"] else []) + (
        [d["blender"]] if d.get("blender") else []) + ([d["report"]] if d["report"] else [])
    fine = d["fine_mesh"]
    lines = [
        f"sorpia fit --fair: {d['input']} -> {d['output']}",
        *(f"  {'repaired' if j == 0 else '':<12}{line}" for j, line in enumerate(repaired)),
        f"  mesh        {d['mesh']['vertices']} vertices, {d['mesh']['faces']} faces",
        f"  scheme      {SCHEME_LABELS[d['scheme']]}, boundary {d['boundary']}",
        *(f"  {'tags' if j == 0 else '':<12}{line}" for j, line in enumerate(tags_lines(d["tags"]))),
        f"  fine mesh   {d['levels']} level{'s' if d['levels'] > 1 else ''} finer: {fine['vertices']} vertices, "
        f"{fine['faces']} {fine['face_kind']}; {d['targets']['count']} targets",
        f"  energy      thin plate" + (f" + {d['membrane']:g} membrane" if d["membrane"] else "") +
        f": {energy(d, 'energy')}, plain interpolation {energy(d, 'plain_energy')}" +
        (f" (ratio {ratio:.3f})" if ratio is not None else ""),
        f"  result      {state}",
        f"  check       max |B V - V0| over the targets = {d['max_residual']:.3g} model units "
        f"({d['max_residual_relative']:.3g} of the bounding-box diagonal), of the control mesh as written "
        "(read back" + (": USD stores float32)" if is_usd(d["output"]) else ")"),
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written)}",
    ]
    return summary_text(lines, d["surface"])
