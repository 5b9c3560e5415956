"""``sorpia fit``: a control mesh whose limit surface (Loop or Catmull-Clark) interpolates a mesh file."""

from __future__ import annotations

import sys
import time

import numpy as np

from .. import __version__, limit_surface
from .._checks import interpolation_miss
from .._meshinfo import topology_info
from .._usd import is_usd
from ..blender import write_blender_script
from ..solve import stopped_short_message
from .common import (EXIT_NOT_CONVERGED, EXIT_OK, FAIR_DEFAULTS, FIT_DEFAULTS, OMEGA_METHODS, SCHEME_LABELS,
                     UserError, check_solver_options, cpu_clock, face_counts, face_size_histogram, fit_once,
                     fmt_seconds, mesh_line, method_label, read_solve_input, repair_json, repair_lines, result_fields,
                     scheme_kwargs, split_json, split_lines, tags_lines, tags_summary, usd_template)
from .fair import run_fair
from .output import (attribute_lines, attributes_to_write, check_blender, check_faces_fit, check_float32_outputs,
                     check_outputs, check_surface_fits, summary_text, write_control_mesh, write_json, write_surface)
from .progress import Progress


def run_fit(input_path, output, *, method="auto", omega="auto", tol=None, max_iter=None,
            boundary=None, surface=None, level=3, report=None, quiet=False, force=False,
            triangulate=False, binary=False, threads=1, repair=False, scheme="auto", ignore_tags=False,
            sharp_angle=None, nonmanifold="error", keep_unconverged=False, out=None, prim=None, blender=None,
            fair=False, levels=None, membrane=None, targets=None) -> tuple[int, dict]:
    """`sorpia fit`: returns (exit code, report dict). `boundary` None: the
    file's interpolateboundary tag, else the default rule. A solve that did
    not reach tol writes no control mesh or surface (only the report) unless
    `keep_unconverged`, or unless it is the least-squares answer on a
    singular B (stop_reason "singular"), which is written with its warning.
    A USD output of a USD input is the input's stage with the fitted mesh in
    its prim (`prim`); `blender` a bpy script (sorpia.blender) for the control
    mesh. `fair`: fair interpolation instead (cli.fair.run_fair), with
    `levels`, `membrane` and `targets` (a file of vertex indices)."""
    if not fair:
        for opt, value in (("--levels", levels), ("--membrane", membrane), ("--targets", targets)):
            if value is not None:
                raise UserError(f"{opt} applies to fair interpolation only: add --fair")
    else:
        refused = [opt for opt, given in (("--method", method != "auto"), ("--omega", omega != "auto"),
                                          ("--keep-unconverged", keep_unconverged),
                                          ("--nonmanifold sharp", nonmanifold != "error")) if given]
        if refused:
            raise UserError(f"{', '.join(refused)} cannot go with --fair: fair interpolation starts from the default "
                            "plain solve (auto), always writes its control mesh (the targets are met whatever the "
                            "iteration stops at) and takes manifold meshes only")
        return run_fair(input_path, output, levels=FAIR_DEFAULTS["levels"] if levels is None else levels,
                        membrane=FAIR_DEFAULTS["membrane"] if membrane is None else membrane, targets=targets, tol=tol,
                        max_iter=max_iter, boundary=boundary, surface=surface, level=level, report=report,
                        quiet=quiet, force=force, triangulate=triangulate, binary=binary, threads=threads,
                        repair=repair, scheme=scheme, ignore_tags=ignore_tags, sharp_angle=sharp_angle, out=out,
                        prim=prim, blender=blender)
    out = out if out is not None else sys.stdout
    tol = FIT_DEFAULTS["tol"] if tol is None else tol
    max_iter = FIT_DEFAULTS["max_iter"] if max_iter is None else max_iter
    check_outputs([input_path], output, surface, report, blender, binary, force)
    given = f"--method {method}" + (f" --omega {omega}" if omega != "auto" else "") + (
        f" --threads {threads}" if threads != 1 else "")
    check_solver_options(given, method=method, omega=omega, tol=tol, max_iter=max_iter, threads=threads)
    uses_omega = method in OMEGA_METHODS

    timings: dict[str, float] = {}
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        mesh, scheme, boundary, tags = read_solve_input(
            input_path, triangulate=triangulate, repair=repair, ignore_tags=ignore_tags, nonmanifold=nonmanifold,
            scheme=scheme, boundary=boundary, sharp_angle=sharp_angle, attributes=True, prim=prim)
        V0, F = mesh.vertices, mesh.faces
        timings.update(mesh.timings)
        check_faces_fit(output, surface, F, scheme, level)
        check_float32_outputs(V0, {"-o": output, "--surface": surface})
        check_blender(blender, scheme, tags)
        attributes, attribute_notes = attributes_to_write(output, mesh.attributes, F, len(V0))
        if surface is not None:
            check_surface_fits(len(V0), face_counts(F), level, scheme)
        timings["statistics"] = 0.0  # reported before the fit, measured after the topology is built
        interp, res, timings["fit"], cpu = fit_once(
            V0, F, method=method, omega=omega if uses_omega else None, tol=tol, max_iter=max_iter,
            boundary=boundary, threads=threads, progress=progress, source=input_path, scheme=scheme, tags=tags)
        progress.status("mesh statistics")
        t0 = time.perf_counter()
        stats = topology_info(V0, interp.topology, scheme=scheme)
        timings["statistics"] = time.perf_counter() - t0
        ctrl = np.asarray(res.control_vertices)
        # What a solve that stopped short left is no answer (a diverged
        # iterate, or one of --max-iter): written only when asked for. The
        # least-squares answer on a singular B is the best there is: written.
        keep = res.converged or res.stop_reason == "singular" or keep_unconverged

        written = None
        if keep:
            progress.status(f"writing {output}")
            t0 = time.perf_counter()
            # The control mesh keeps the scheme, boundary rule and tags it was fitted with where the format holds
            # them, so that it can be refitted; the file is read back for the check below.
            written = write_control_mesh(output, ctrl, F, scheme=scheme, boundary=boundary, tags=tags,
                                         binary=binary, attributes=attributes,
                                         template=usd_template(input_path, output, prim))
            if blender is not None:
                write_blender_script(blender, ctrl, F, boundary=boundary, **tags)
            timings["write"] = time.perf_counter() - t0
        surface_stats = None
        if surface is not None and keep:
            progress.status(f"limit surface, level {level}")
            t0 = time.perf_counter()
            Vs, Fs = limit_surface(ctrl, F, level=level, boundary=boundary, **scheme_kwargs(scheme, tags))
            write_surface(surface, Vs, Fs, binary)
            timings["surface"] = time.perf_counter() - t0
            surface_stats = {"path": str(surface), "level": level, "vertices": len(Vs), "faces": len(Fs)}
        # A check of what was written, independent of the solver: the limit
        # positions of the control mesh as read back from the file (USD
        # stores float32) from OpenSubdiv's masks, against the given vertices.
        progress.status("checking B V = V0")
        t0 = time.perf_counter()
        max_residual = interpolation_miss(ctrl if written is None else written.vertices, V0, F,
                                          boundary=boundary, scheme=scheme, tags=tags, topology=interp.topology)
        timings["check"] = time.perf_counter() - t0

    fields = result_fields(res)
    # The solver's own phases (topology, operator, estimate, solve), inside "fit".
    fit_phases = {f"fit.{k}": float(v) for k, v in res.timings.items()}
    errors = np.asarray(res.history, dtype=float)
    diag = stats.get("diagonal") or 1.0
    data = {
        "sorpia_version": __version__,
        "command": "fit",
        "input": str(input_path),
        "triangulated": triangulate,
        "scheme": scheme,
        "face_sizes": face_size_histogram(F),
        "tags": {"from_file": not ignore_tags, "sharp_angle": sharp_angle, **tags_summary(tags),
                 "written_to_output": [] if written is None else list(written.written)},
        "attributes": attribute_notes,
        "repair": repair_json(mesh.repair) if repair else None,
        "nonmanifold": split_json(mesh.split) if mesh.split is not None else None,
        "output": str(output),
        "written": bool(keep),
        "not_written": [] if keep else [str(p) for p in (output, surface) if p is not None],
        "surface": surface_stats,
        "blender": None if blender is None or not keep else str(blender),
        "report": None if report is None else str(report),
        "mesh": stats,
        "method": method,
        "variant": res.variant,
        "stop_reason": res.stop_reason,
        "attempts": res.attempts,
        "recommended": res.recommended,
        "stopped_short": stopped_short_message(res, method, tol, max_iter),
        "omega_rule": omega if uses_omega else None,
        "omega": res.omega,
        "tol": tol,
        "max_iter": max_iter,
        "boundary": boundary,
        "threads": threads,
        "iterations": int(res.iterations),
        "converged": bool(res.converged),
        "final_error": float(errors[-1]),
        "history": errors,
        "max_residual": float(max_residual),
        "max_residual_relative": float(max_residual / diag),
        "cpu_seconds": cpu,
        "cpu_clock": cpu_clock(threads),
        "timings": {**timings, **fit_phases},
        "result": {k: v for k, v in fields.items() if k not in ("history", "timings")},
    }
    if report is not None:
        write_json(report, data)
    if not quiet:
        print(fit_summary(data, repair_lines(mesh.repair) if repair else (),
                          split_lines(mesh.split) if mesh.split is not None else ()), file=out)
    return (EXIT_OK if res.converged else EXIT_NOT_CONVERGED), data


def fit_summary(d: dict, repaired=(), kept=()) -> str:
    """The summary printed by fit; `repaired`: a line per kind of change --repair made; `kept`: what
    --nonmanifold sharp kept."""
    label = method_label(d["method"])
    omega = d["omega"]
    if d["method"] == "auto":
        label += ": " + ", then ".join(f"{method_label(a['method'])} ({a['stop_reason']}, {a['iterations']} "
                                      "iterations)" for a in d["attempts"])
    elif d["method"] == "sor" and omega is not None:
        label += f", omega {omega:.4f} ({d['omega_rule']})"
    elif d["method"] == "gs":
        label += ", omega 1"
    if d["threads"] > 1:
        label += f", {d['threads']} threads"
    state = (f"converged in {d['iterations']} iterations: E_k/E_0 = {d['final_error']:.3g} " + (
             f"< tol {d['tol']:g}" if d["final_error"] < d["tol"] else
             f"(tol {d['tol']:g} is below what float64 reaches: E_k stopped at rounding level)")
             if d["converged"] else
             f"NOT converged ({d['stop_reason']}): {d['stopped_short']}; " + (
                 "outputs written, exit code 1" if not d["not_written"] else
                 f"{', '.join(d['not_written'])} NOT written (--keep-unconverged writes them), exit code 1"))
    t = d["timings"]
    inner = ", ".join(f"{k[4:]} {fmt_seconds(v)}" for k, v in t.items() if k.startswith("fit."))
    phases = ", ".join(f"{k} {fmt_seconds(v)}" + (f" ({inner})" if k == "fit" and inner else "")
                       for k, v in t.items() if not k.startswith("fit."))
    written = ([d["output"]] if d["written"] else []) + ([d["surface"]["path"]] if d["surface"] else []) + (
        [d["blender"]] if d.get("blender") else []) + ([d["report"]] if d["report"] else [])
    lines = [
        f"sorpia fit: {d['input']} -> {d['output']}",
        *(f"  {'repaired' if j == 0 else '':<12}{line}" for j, line in enumerate(repaired)),
        *(f"  {'nonmanifold' if j == 0 else '':<12}{line}" for j, line in enumerate(kept)),
        f"  mesh        {mesh_line(d['mesh'])}",
        f"  scheme      {SCHEME_LABELS[d['scheme']]}" + (f", boundary {d['boundary']}"),
        *(f"  {'tags' if j == 0 else '':<12}{line}" for j, line in enumerate(tags_lines(d["tags"]))),
        *attribute_lines(d.get("attributes", {})),
        f"  method      {label}",
        f"  result      {state}",
        f"  check       max |B V - V0| = {d['max_residual']:.3g} model units "
        f"({d['max_residual_relative']:.3g} of the bounding-box diagonal), " + (
            "of the control mesh as written (read back" + (": USD stores float32)" if is_usd(d["output"]) else ")")
            if d["written"] else "of the solve's control vertices (not written)"),
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written) or 'nothing'}",
    ]
    return summary_text(lines, d["surface"])
