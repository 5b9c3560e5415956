"""``sorpia fit``: a control mesh whose limit surface (Loop or Catmull-Clark) interpolates a mesh file."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .. import __version__
from .._usd import is_usd
from .._validate import as_boundary
from ..solve import stopped_short_message
from .common import (EXIT_NOT_CONVERGED, EXIT_OK, OMEGA_METHODS, SCHEME_LABELS, UserError, check_mesh_suffix, check_paths,
                     check_solver_options, cpu_clock, face_counts, face_size_histogram, fit_once, fmt_seconds,
                     is_triangles, mesh_line, method_label, read_solve_input, repair_json, repair_lines, result_fields,
                     scheme_kwargs, split_json, split_lines, tags_lines, tags_summary, usd_template, warn_once)
from .output import write_json
from .progress import Progress


def run_fit(input_path, output, *, method="auto", omega="auto", tol=1e-10, max_iter=1000,
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
        from .fair import run_fair

        return run_fair(input_path, output, levels=1 if levels is None else levels,
                        membrane=0.0 if membrane is None else membrane, targets=targets, tol=tol,
                        max_iter=max_iter, boundary=boundary, surface=surface, level=level, report=report,
                        quiet=quiet, force=force, triangulate=triangulate, binary=binary, threads=threads,
                        repair=repair, scheme=scheme, ignore_tags=ignore_tags, sharp_angle=sharp_angle, out=out,
                        prim=prim, blender=blender)
    from .. import _core, write_mesh
    from .._meshinfo import topology_info

    out = out if out is not None else sys.stdout
    check_fit_paths([input_path], output, surface, report, blender, binary, force)
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
        _check_outputs_hold(output, surface, F, scheme, level)
        if blender is not None:
            _check_blender(blender, scheme, tags)
        attributes, attribute_notes = _attributes_to_write(output, mesh.attributes, F, len(V0))
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

        written_tags = _tags_to_write(output, tags, boundary, mesh, scheme)

        if keep:
            progress.status(f"writing {output}")
            t0 = time.perf_counter()
            # The control mesh keeps the tags it was fitted with (OBJ), so that it can be refitted.
            write_mesh(output, ctrl, F, binary=_binary_for(output, binary), **written_tags, **attributes,
                       **usd_template(input_path, output, prim))
            if blender is not None:
                from ..blender import write_blender_script

                write_blender_script(blender, ctrl, F, boundary=boundary, **tags)
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
        # USD stores float32 points: the check is of the cage as written.
        written = ctrl.astype(np.float32).astype(np.float64) if is_usd(output) else ctrl
        max_residual = _max_residual(interp, written, V0, F, boundary, scheme, tags)
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
                 "written_to_output": sorted(written_tags)},
        "attributes": attribute_notes,
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


def _tags_to_write(output, tags: dict, boundary: str, mesh, scheme=None) -> dict:
    """The tags the control mesh is written with: those it was fitted with,
    and always the boundary rule (a reader without the tag takes its own
    default: OpenSubdiv's regression reader, far_utils.h, edge-only); OBJ and
    USD only (another format cannot hold them: a warning says the sharpness
    tags are left out); USD also the scheme."""
    out = {**tags, "boundary": boundary}
    if Path(output).suffix.lower() == ".obj":
        return out
    if is_usd(output):
        return {**out, **({"scheme": scheme} if scheme is not None else {})}
    if tags:
        warn_once(f"-o {output}: the sharpness tags ({', '.join(sorted(tags))}) are not written: only .obj and "
                  "USD files hold them; refitting this file would solve without them")
    return {}


def check_fit_paths(inputs: list, output, surface, report, blender, binary: bool, force: bool) -> None:
    """The checks of fit's (and fit --fair's) paths before any work: mesh
    suffixes of -o and --surface, inputs readable and outputs writable
    (check_paths), --blender a .py script, --binary only with a PLY or STL
    output."""
    check_mesh_suffix("-o", output)
    check_mesh_suffix("--surface", surface)
    check_paths(inputs, {"-o": output, "--surface": surface, "--report": report, "--blender": blender}, force)
    if blender is not None and Path(blender).suffix.lower() != ".py":
        raise UserError(f"--blender {blender}: the script is Python, give a file name ending in .py")
    if binary and not any(Path(p).suffix.lower() in (".ply", ".stl") for p in (output, surface) if p):
        raise UserError("--binary applies to .ply and .stl outputs only (OBJ and OFF are text formats)")


ATTRIBUTE_LABELS = {"uvs": "texture coordinates", "normals": "normals"}


def _attributes_to_write(output, attributes: dict, faces, n_vertices: int, keep_normals: bool = False
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
    vertex has several, a seam) leaves them out with a warning, before the
    solve."""
    written, notes = {}, {}
    for name, channel in attributes.items():
        if name == "normals" and not keep_normals:
            notes[name] = "not written: they are the input surface's; the limit surface has its own"
            continue
        reason = _unwritable(output, channel, faces, n_vertices, 3 if name == "normals" else 2)
        if reason is None:
            written[name], notes[name] = channel, "written"
            continue
        label = ATTRIBUTE_LABELS[name]
        warn_once(f"-o {output}: the input's {label} are not written: {reason}; write .obj to keep them")
        notes[name] = f"not written: {reason}; .obj holds them per face corner"
    return written, notes


def _unwritable(output, channel, faces, n_vertices: int, width: int) -> str | None:
    """Why `output`'s format cannot hold the face-varying `channel`, or None:
    OFF and STL hold none, PLY one value of `width` numbers per vertex (the
    check write_mesh makes, sorpia::detail::io::per_vertex_values, made here
    before the solve)."""
    suffix = Path(output).suffix.lower()
    if suffix in (".off", ".stl"):
        return f"{suffix[1:].upper()} has no per-vertex or per-corner values"
    if suffix != ".ply":
        return None
    if channel.values.shape[1] != width:
        return f"PLY stores {width} numbers per vertex, these have {channel.values.shape[1]}"
    corners = np.asarray(faces).reshape(-1) if isinstance(faces, np.ndarray) else np.asarray(
        faces.face_vertex_indices)
    values = channel.values[channel.indices]
    first = np.zeros((n_vertices, width))
    used, first_corner = np.unique(corners, return_index=True)
    first[used] = values[first_corner]  # the value of each vertex's first corner
    seams = np.flatnonzero((first[corners] != values).any(axis=1))
    if len(seams):
        return (f"PLY stores them per vertex, and vertex {int(corners[seams[0]])} has several (a seam; "
                f"{len(np.unique(corners[seams]))} such vertices)")
    return None


def _check_blender(path, scheme: str, tags: dict) -> None:
    """Refuse --blender before the solve where Blender cannot draw the surface (sorpia.blender.blender_refusal)."""
    from ..blender import blender_refusal

    reason = blender_refusal(scheme, tags)
    if reason is not None:
        raise UserError(f"--blender {path}: {reason}")


def _check_outputs_hold(output, surface, faces, scheme: str, level: int) -> None:
    """Refuse, before the solve, an output whose format cannot hold its faces:
    STL stores triangles only, and the control mesh has the input's faces, a
    Catmull-Clark limit surface quads (its control polygons at level 0)."""
    from .common import face_sizes_text

    if output is not None and Path(output).suffix.lower() == ".stl" and not is_triangles(faces):
        raise UserError(f"-o {output}: STL holds triangles only, and the control mesh has the input's faces (of "
                        f"{face_sizes_text(faces)} vertices): write .obj, .off or .ply, or pass --triangulate to "
                        "fit a triangulation with Loop")
    surface_triangles = scheme == "loop" or (level == 0 and is_triangles(faces))
    if surface is not None and Path(surface).suffix.lower() == ".stl" and not surface_triangles:
        raise UserError(f"--surface {surface}: STL holds triangles only, and the Catmull-Clark limit surface is "
                        f"{'the control polygons' if level == 0 else 'a quad mesh'}: write .obj, .off or .ply")


def _max_residual(interp, ctrl, V0, faces, boundary, scheme, tags) -> float:
    """max_i ||(B V)_i - v0_i|| (the Euclidean norm of a row, as E_k is) of the
    control mesh written, independent of the solver: Loop without tags from
    OpenSubdiv's masks over the topology's one-ring (limit_residual);
    otherwise from the library's limit points of the scheme and tags."""
    from .. import _core

    if not scheme_kwargs(scheme, tags):
        return float(_core.limit_residual(interp.topology, ctrl, V0, as_boundary(boundary))[0])
    from .. import limit_points

    miss = limit_points(ctrl, faces, boundary=boundary, **scheme_kwargs(scheme, tags)) - V0
    return float(np.linalg.norm(miss, axis=1).max()) if len(miss) else 0.0


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


def summary_text(lines: list, surface) -> str:
    """A fit's summary lines, the written surface's line (`surface`: the report's "surface" entry, or None)
    before the last ("wrote"), as one text: what fit and fit --fair print."""
    if surface:
        lines.insert(-1, f"  surface     level {surface['level']}: {surface['vertices']} vertices, "
                         f"{surface['faces']} faces")
    return "\n".join(lines)


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
        *(f"  {'attributes' if j == 0 else '':<12}{ATTRIBUTE_LABELS[name]} {note}"
          for j, (name, note) in enumerate(d.get("attributes", {}).items())),
        f"  method      {label}",
        f"  result      {state}",
        f"  check       max |B V - V0| = {d['max_residual']:.3g} "
        f"({d['max_residual_relative']:.3g} of the bounding-box diagonal)"
        + (", of the cage as written (USD stores float32)" if is_usd(d["output"]) else ""),
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written) or 'nothing'}",
    ]
    return summary_text(lines, d["surface"])
