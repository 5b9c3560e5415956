"""``sorpia fit``: a control mesh whose Loop limit surface interpolates a mesh file."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .. import __version__
from .._validate import as_boundary
from ..solve import stopped_short_message
from .common import (EXIT_NOT_CONVERGED, EXIT_OK, OMEGA_METHODS, SCHEME_LABELS, UserError, check_mesh_suffix, check_paths,
                     check_solver_options, cpu_clock, face_counts, face_size_histogram, fit_once, fmt_seconds,
                     mesh_line, method_label, read_solve_input, repair_json, repair_lines, result_fields,
                     scheme_kwargs, split_json, split_lines, tags_lines, tags_summary, warn_once)
from .output import write_json
from .progress import Progress


def run_fit(input_path, output, *, method="auto", omega="auto", tol=1e-10, max_iter=1000,
            boundary=None, surface=None, level=3, report=None, quiet=False, force=False,
            triangulate=False, binary=False, threads=1, repair=False, scheme="auto", ignore_tags=False,
            sharp_angle=None, nonmanifold="error", keep_unconverged=False, out=None) -> tuple[int, dict]:
    """`sorpia fit`: returns (exit code, report dict). `boundary` None: the
    file's interpolateboundary tag, else the default rule. A solve that did
    not reach tol writes no control mesh or surface (only the report) unless
    `keep_unconverged`, or unless it is the least-squares answer on a
    singular B (stop_reason "singular"), which is written with its warning."""
    from .. import _core, write_mesh
    from ..meshinfo import topology_info

    out = out if out is not None else sys.stdout
    check_mesh_suffix("-o", output)
    check_mesh_suffix("--surface", surface)
    check_paths([input_path], {"-o": output, "--surface": surface, "--report": report}, force)
    given = f"--method {method}" + (f" --omega {omega}" if omega != "auto" else "") + (
        f" --threads {threads}" if threads != 1 else "")
    check_solver_options(given, method=method, omega=omega, tol=tol, max_iter=max_iter, threads=threads)
    uses_omega = method in OMEGA_METHODS
    if binary and not any(Path(p).suffix.lower() in (".ply", ".stl") for p in (output, surface) if p):
        raise UserError("--binary applies to .ply and .stl outputs only (OBJ and OFF are text formats)")

    timings: dict[str, float] = {}
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        mesh, scheme, boundary, tags = read_solve_input(
            input_path, triangulate=triangulate, repair=repair, ignore_tags=ignore_tags, nonmanifold=nonmanifold,
            scheme=scheme, boundary=boundary, sharp_angle=sharp_angle)
        V0, F = mesh.vertices, mesh.faces
        timings.update(mesh.timings)
        if surface is not None:
            _check_surface_fits(len(V0), face_counts(F), level, scheme)
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

        written_tags = _tags_to_write(output, tags, boundary, mesh)
        if keep:
            progress.status(f"writing {output}")
            t0 = time.perf_counter()
            # The control mesh keeps the tags it was fitted with (OBJ), so that it can be refitted.
            write_mesh(output, ctrl, F, binary=_binary_for(output, binary), **written_tags)
            timings["write"] = time.perf_counter() - t0
        surface_stats = None
        if surface is not None and keep:
            from .. import limit_surface

            progress.status(f"limit surface, level {level}")
            t0 = time.perf_counter()
            Vs, Fs = limit_surface(ctrl, F, level=level, boundary=boundary, **scheme_kwargs(scheme, tags))
            write_mesh(surface, Vs, Fs, binary=_binary_for(surface, binary))
            timings["surface"] = time.perf_counter() - t0
            surface_stats = {"path": str(surface), "level": level, "vertices": len(Vs), "faces": len(Fs)}
        # A check of what was written, independent of the solver: the limit
        # positions of the control mesh from OpenSubdiv's masks over the
        # topology's one-ring, against the given vertices.
        progress.status("checking B V = V0")
        t0 = time.perf_counter()
        max_residual = _max_residual(interp, ctrl, V0, F, boundary, scheme, tags)
        timings["check"] = time.perf_counter() - t0

    fields = result_fields(res)
    # The solver's own phases (topology, operator, estimate, solve), inside "fit".
    fit_phases = {f"fit.{k}": float(v) for k, v in res.timings.items()}
    errors = np.asarray(res.errors, dtype=float)
    diag = stats.get("diagonal") or 1.0
    data = {
        "sorpia_version": __version__,
        "command": "fit",
        "input": str(input_path),
        "triangulated": triangulate,
        "scheme": scheme,
        "face_sizes": face_size_histogram(F),
        "tags": {"from_file": not ignore_tags, "sharp_angle": sharp_angle, **tags_summary(tags),
                 "written_to_output": sorted(written_tags)},
        "repair": repair_json(mesh.repair) if repair else None,
        "nonmanifold": split_json(mesh.split) if mesh.split is not None else None,
        "output": str(output),
        "written": bool(keep),
        "not_written": [] if keep else [str(p) for p in (output, surface) if p is not None],
        "surface": surface_stats,
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
        "errors": errors,
        "max_residual": float(max_residual),
        "max_residual_relative": float(max_residual / diag),
        "cpu_seconds": cpu,
        "cpu_clock": cpu_clock(threads),
        "timings": {**timings, **fit_phases},
        "result": {k: v for k, v in fields.items() if k not in ("errors", "timings")},
    }
    if report is not None:
        write_json(report, data)
    if not quiet:
        print(fit_summary(data, repair_lines(mesh.repair) if repair else (),
                          split_lines(mesh.split) if mesh.split is not None else ()), file=out)
    return (EXIT_OK if res.converged else EXIT_NOT_CONVERGED), data


def _tags_to_write(output, tags: dict, boundary: str, mesh) -> dict:
    """The tags the control mesh is written with: those it was fitted with,
    and the boundary rule when it is not the default or the file named it;
    OBJ only (another format cannot hold them: a warning says they are left out)."""
    from .._validate import DEFAULT_BOUNDARY

    out = dict(tags)
    if boundary != DEFAULT_BOUNDARY or "boundary" in mesh.tags:
        out["boundary"] = boundary
    if Path(output).suffix.lower() == ".obj":
        return out
    if tags:
        warn_once(f"-o {output}: the sharpness tags ({', '.join(sorted(tags))}) are not written: only .obj files "
                  "hold them; refitting this file would solve without them")
    return {}


def _max_residual(interp, ctrl, V0, faces, boundary, scheme, tags) -> float:
    """max |B V - V0| of the control mesh written, independent of the
    solver: Loop without tags from OpenSubdiv's masks over the topology's
    one-ring (limit_residual); otherwise from the library's limit points of
    the scheme and tags."""
    from .. import _core

    if not scheme_kwargs(scheme, tags):
        return float(_core.limit_residual(interp.topology, ctrl, V0, as_boundary(boundary))[0])
    from .. import limit_points

    return float(np.abs(limit_points(ctrl, faces, boundary=boundary, **scheme_kwargs(scheme, tags))
                        - V0).max())


def _check_surface_fits(n_vertices: int, counts: np.ndarray, level: int, scheme: str) -> None:
    """Refuse --level before the solve when the tessellation would not fit in
    the memory left to the process (sorpia::available_memory_bytes: free
    memory, rlimits, cgroup limits), by the estimate limit_surface checks
    (sorpia::tessellation_bytes for the scheme); limit_surface would refuse it
    only after the solve."""
    from .. import _core
    from .._validate import as_scheme

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


def _binary_for(path, binary: bool) -> bool:
    """--binary for the formats that have a binary form (PLY, STL)."""
    return binary and Path(path).suffix.lower() in (".ply", ".stl")


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
        [d["report"]] if d["report"] else [])
    lines = [
        f"sorpia fit: {d['input']} -> {d['output']}",
        *(f"  {'repaired' if j == 0 else '':<12}{line}" for j, line in enumerate(repaired)),
        *(f"  {'nonmanifold' if j == 0 else '':<12}{line}" for j, line in enumerate(kept)),
        f"  mesh        {mesh_line(d['mesh'])}",
        f"  scheme      {SCHEME_LABELS[d['scheme']]}" + (f", boundary {d['boundary']}"),
        *(f"  {'tags' if j == 0 else '':<12}{line}" for j, line in enumerate(tags_lines(d["tags"]))),
        f"  method      {label}",
        f"  result      {state}",
        f"  check       max |B V - V0| = {d['max_residual']:.3g} "
        f"({d['max_residual_relative']:.3g} of the bounding-box diagonal)",
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written) or 'nothing'}",
    ]
    if d["surface"]:
        s = d["surface"]
        lines.insert(-1, f"  surface     level {s['level']}: {s['vertices']} vertices, {s['faces']} faces")
    return "\n".join(lines)
