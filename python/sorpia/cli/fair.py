"""``sorpia fit --fair``: a control mesh `--levels` subdivision steps finer
than the input whose limit surface passes through the input's vertices (or
those of ``--targets``) and bends least (sorpia.fair_interpolate)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .. import __version__
from .common import (EXIT_NOT_CONVERGED, EXIT_OK, SCHEME_LABELS, UserError, face_counts, face_size_histogram,
                     fmt_seconds, read_solve_input, repair_json, repair_lines, scheme_kwargs, tags_lines, tags_summary,
                     usd_template, warn_once)
from .fit import summary_text
from .output import write_json
from .progress import Progress


def read_targets(path, n_vertices: int) -> np.ndarray:
    """The vertex indices of a --targets file: whole numbers separated by
    spaces, commas or newlines, '#' to the end of a line a comment; each in
    [0, n_vertices) and none twice (a UserError names the line)."""
    seen: dict[int, int] = {}
    out = []
    with open(path, encoding="utf-8") as fh:
        for line_no, line in enumerate(fh, 1):
            for word in line.split("#", 1)[0].replace(",", " ").split():
                try:
                    index = int(word)
                except ValueError:
                    raise UserError(f"--targets {path}, line {line_no}: {word!r} is not a vertex index (a whole "
                                    "number)") from None
                if not 0 <= index < n_vertices:
                    raise UserError(f"--targets {path}, line {line_no}: vertex {index} is out of range [0, "
                                    f"{n_vertices}) (the input has {n_vertices} vertices)")
                if index in seen:
                    raise UserError(f"--targets {path}, line {line_no}: vertex {index} is repeated (first on line "
                                    f"{seen[index]})")
                seen[index] = line_no
                out.append(index)
    if not out:
        raise UserError(f"--targets {path}: no vertex index in the file")
    return np.array(out, dtype=np.int64)


def run_fair(input_path, output, *, levels=1, membrane=0.0, targets=None, tol=1e-10, max_iter=1000,
             boundary=None, surface=None, level=3, report=None, quiet=False, force=False, triangulate=False,
             binary=False, threads=1, repair=False, scheme="auto", ignore_tags=False, sharp_angle=None, out=None,
             prim=None, blender=None) -> tuple[int, dict]:
    """`sorpia fit --fair`: returns (exit code, report dict). The targets are
    met to rounding whatever the iteration stops at, so the control mesh is
    always written; exit code 1 when the iteration reached --max-iter before
    the energy settled to --tol."""
    from .. import fair_interpolate, limit_points, write_mesh
    from .._meshinfo import topology_info
    from ..limit import topology as build_topology
    from .fit import (ATTRIBUTE_LABELS, _binary_for, _check_blender, _check_surface_fits, _tags_to_write,
                  check_fit_paths)

    out = out if out is not None else sys.stdout
    check_fit_paths([input_path] + ([targets] if targets is not None else []), output, surface, report, blender,
                    binary, force)

    timings: dict[str, float] = {}
    with Progress(enabled=not quiet) as progress:
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
        if blender is not None:
            _check_blender(blender, scheme, tags)
        target_ids = None if targets is None else read_targets(targets, len(V0))
        if surface is not None:  # the fine mesh's faces, tessellated --level more times
            n_fine_faces = (len(F) * 4 if scheme == "loop" else int(np.sum(face_counts(F)))) * 4 ** (levels - 1)
            _check_surface_fits(len(V0) * 4 ** levels, np.full(n_fine_faces, 3 if scheme == "loop" else 4), level,
                                scheme)
        progress.status(f"fair interpolation, {levels} level{'s' if levels > 1 else ''} finer")
        t0 = time.perf_counter()
        res = fair_interpolate(V0, F, levels=levels, membrane=membrane, targets=target_ids, boundary=boundary,
                               tol=tol, max_iter=max_iter, threads=threads, **scheme_kwargs(scheme, tags))
        timings["fit"] = time.perf_counter() - t0
        stats = topology_info(V0, build_topology(F, len(V0), scheme=scheme, warn=False), scheme=scheme)
        ctrl = np.asarray(res.control_vertices)
        written_tags = _tags_to_write(output, res.tags, boundary, mesh, scheme)

        progress.status(f"writing {output}")
        t0 = time.perf_counter()
        write_mesh(output, ctrl, res.faces, binary=_binary_for(output, binary), **written_tags,
                   **usd_template(input_path, output, prim))
        if blender is not None:
            from ..blender import write_blender_script

            write_blender_script(blender, ctrl, res.faces, boundary=boundary, **res.tags)
        timings["write"] = time.perf_counter() - t0
        surface_stats = None
        if surface is not None:
            from .. import limit_surface

            progress.status(f"limit surface, level {level}")
            t0 = time.perf_counter()
            Vs, Fs = limit_surface(ctrl, res.faces, level=level, boundary=boundary, **scheme_kwargs(scheme, res.tags))
            write_mesh(surface, Vs, Fs, binary=_binary_for(surface, binary))
            timings["surface"] = time.perf_counter() - t0
            surface_stats = {"path": str(surface), "level": level, "vertices": len(Vs), "faces": len(Fs)}
        # A check of what was written, independent of the solver's elimination:
        # the fine mesh's limit positions (sorpia.limit_points) at the targets.
        progress.status("checking the targets")
        t0 = time.perf_counter()
        miss = limit_points(ctrl, res.faces, boundary=boundary, **scheme_kwargs(scheme, res.tags))[res.targets] - \
            V0[res.targets]
        max_residual = float(np.linalg.norm(miss, axis=1).max())
        timings["check"] = time.perf_counter() - t0

    diag = stats.get("diagonal") or 1.0
    data = {
        "sorpia_version": __version__,
        "command": "fit",
        "fair": True,
        "input": str(input_path),
        "triangulated": triangulate,
        "scheme": scheme,
        "face_sizes": face_size_histogram(F),
        "tags": {"from_file": not ignore_tags, "sharp_angle": sharp_angle, **tags_summary(tags),
                 "written_to_output": sorted(written_tags)},
        "fine_tags": tags_summary(res.tags),
        "repair": repair_json(mesh.repair) if repair else None,
        "output": str(output),
        "written": True,
        "surface": surface_stats,
        "report": None if report is None else str(report),
        "mesh": stats,
        "boundary": boundary,
        "levels": levels,
        "thin_plate": 1.0,
        "membrane": membrane,
        "targets": {"file": None if targets is None else str(targets), "count": int(len(res.targets))},
        "fine_mesh": {"vertices": int(len(ctrl)), "faces": int(len(res.faces)), "face_kind": fine_kind},
        "plain_energy": res.plain_energy,
        "energy": res.energy,
        "energy_ratio": res.energy / res.plain_energy if res.plain_energy > 0 else None,
        "history": np.asarray(res.history),
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
        [d["report"]] if d["report"] else [])
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
        f": {d['energy']:.6g}, plain interpolation {d['plain_energy']:.6g}" +
        (f" (ratio {ratio:.3f})" if ratio is not None else ""),
        f"  result      {state}",
        f"  check       max |B V - V0| over the targets = {d['max_residual']:.3g} "
        f"({d['max_residual_relative']:.3g} of the bounding-box diagonal)",
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written)}",
    ]
    return summary_text(lines, d["surface"])
