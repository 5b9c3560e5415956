"""``sorpia render``: the paper's Figure 3 for a mesh file (PNG)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .. import LimitSurface, approximate, fair_interpolate, limit_surface
# _plotting imports matplotlib only when drawing
from .._plotting import FACE_BUDGET, crease_curves, interpolation_figure, level_for_budget
from .._validate import DEFAULT_BOUNDARY
from ..solve import stopped_short_message
from .common import (EXIT_NOT_CONVERGED, EXIT_OK, FAIR_DEFAULTS, FIT_DEFAULTS, OMEGA_METHODS, SCHEME_LABELS,
                     UserError, check_paths, check_solver_options, choose_scheme, face_counts, fit_once, fmt_seconds,
                     method_label, omega_text, read_input, read_solve_input, repair_lines, require_plotting,
                     scheme_kwargs, solve_tags)
from .output import save_figure
from .progress import Progress


def run_render(input_path, output, *, level=3, method="auto", omega="auto", tol=None, max_iter=None, boundary=None,
               size=(1200, 1000), elev=30.0, azim=-60.0, face_budget=FACE_BUDGET, quiet=False, force=False,
               triangulate=False, up="z", threads=1, repair=False, scheme="auto", ignore_tags=False,
               sharp_angle=None, nonmanifold="error", out=None, prim=None, fair=False, levels=None,
               membrane=None, cage=None, iterations=10) -> tuple[int, dict]:
    """`sorpia render`: the paper's Figure 3 for a mesh file; with `fair`,
    plain and fair interpolation (sorpia.fair_interpolate, `levels` finer,
    `membrane`) side by side; with `cage`, the same four panels for
    approximation (render_approximation)."""
    out = out if out is not None else sys.stdout
    tol = (FAIR_DEFAULTS if fair else FIT_DEFAULTS)["tol"] if tol is None else tol
    max_iter = (FAIR_DEFAULTS if fair else FIT_DEFAULTS)["max_iter"] if max_iter is None else max_iter
    if Path(output).suffix.lower() != ".png":
        raise UserError(f"-o {output}: render writes a PNG image, give a file name ending in .png")
    check_paths([input_path] + ([cage] if cage is not None else []), {"-o": output}, force)
    if cage is not None and fair:
        raise UserError("--cage (approximation) and --fair (fair interpolation) draw different figures: give one")
    if cage is not None:
        return render_approximation(input_path, cage, output, level=level, boundary=boundary, size=size, elev=elev,
                                    azim=azim, face_budget=face_budget, quiet=quiet, up=up, scheme=scheme,
                                    sharp_angle=sharp_angle, iterations=iterations, out=out)
    uses_omega = method in OMEGA_METHODS
    check_solver_options(f"--method {method}" + (f" --omega {omega}" if omega != "auto" else "")
                         + (f" --threads {threads}" if threads != 1 else ""), method=method,
                         **({"omega": omega} if uses_omega else {}), tol=tol, max_iter=max_iter, threads=threads)
    if not fair and (levels is not None or membrane is not None):
        raise UserError(f"{'--levels' if levels is not None else '--membrane'} applies to --fair only: add --fair")
    if fair and (method != "auto" or omega != "auto" or nonmanifold != "error"):
        raise UserError("--method, --omega and --nonmanifold sharp cannot go with --fair: fair interpolation starts "
                        "from the default plain solve and takes manifold meshes only")
    levels = FAIR_DEFAULTS["levels"] if levels is None else levels
    require_plotting()
    budget = face_budget
    timings = {}
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        mesh, scheme, boundary, tags = read_solve_input(
            input_path, triangulate=triangulate, repair=repair, ignore_tags=ignore_tags, nonmanifold=nonmanifold,
            scheme=scheme, boundary=boundary, sharp_angle=sharp_angle, prim=prim)
        V0, F = mesh.vertices, mesh.faces
        timings.update(mesh.timings)
        fair_res = None
        if fair:
            progress.status(f"fair interpolation, {levels} level{'s' if levels > 1 else ''} finer")
            t0 = time.perf_counter()
            fair_res = fair_interpolate(V0, F, levels=levels,
                                        membrane=FAIR_DEFAULTS["membrane"] if membrane is None else membrane,
                                        tol=tol, max_iter=max_iter, boundary=boundary, threads=threads,
                                        **scheme_kwargs(scheme, tags))
            res = fair_res.plain
            timings["fit"] = time.perf_counter() - t0
        else:
            _, res, timings["fit"], _ = fit_once(V0, F, method=method, omega=omega if uses_omega else None,
                                                 tol=tol, max_iter=max_iter, boundary=boundary, threads=threads,
                                                 progress=progress, source=input_path, scheme=scheme, tags=tags)
        ctrl = np.asarray(res.control_vertices)
        counts = face_counts(F)
        drawn_level = level_for_budget(len(counts), level, budget,
                                       first_level_faces=None if scheme == "loop" else int(counts.sum()))
        progress.status(f"limit surfaces, level {drawn_level}")
        t0 = time.perf_counter()
        # One LimitSurface for both: the topology is built once, only positions change.
        surface = LimitSurface(V0, F, boundary=boundary, **scheme_kwargs(scheme, tags))
        # The creases drawn orange, with their limit curves: every crease that is not smooth.
        creases = None
        if "creases" in tags:
            edges, sharpness = tags["creases"]
            creases = np.asarray(edges)[np.asarray(sharpness) > 0]
        given = surface.tessellate(drawn_level)
        holes = tags.get("holes")
        given_curves = (crease_curves(surface, F, creases, holes=holes) if creases is not None and len(creases)
                        else None)
        surface.set_vertices(ctrl)
        fitted = surface.tessellate(drawn_level)
        curves = None if given_curves is None else (given_curves, crease_curves(surface, F, creases, holes=holes))
        fair_panels = None
        if fair_res is not None:  # the fine mesh tessellated to about the plain surface's resolution
            fine_surface = LimitSurface(fair_res.control_vertices, fair_res.faces,
                                        boundary=boundary, **scheme_kwargs(scheme, fair_res.tags))
            fair_panels = (fair_res.control_vertices, fair_res.faces,
                           fine_surface.tessellate(max(drawn_level - levels, 0)), levels)
        timings["surface"] = time.perf_counter() - t0
        progress.status(f"drawing {output}")
        t0 = time.perf_counter()
        fig = interpolation_figure(V0, F, given, ctrl, fitted, size=size, elev=elev, azim=azim, face_budget=budget,
                                   title=f"{Path(input_path).name}: {SCHEME_LABELS[scheme]} limit surface and "
                                   + (f"{method_label(res.variant)} (paper Figure 3)" if fair_res is None else
                                      "plain against fair interpolation"),
                                   iterations=int(res.iterations), level=drawn_level, up=up, scheme=scheme,
                                   creases=creases, crease_curves=curves, fair=fair_panels)
        save_figure(fig, output)
        timings["draw"] = time.perf_counter() - t0
    data = {"output": str(output), "scheme": scheme, "level": drawn_level, "threads": threads, "method": method,
            "variant": res.variant, "stop_reason": res.stop_reason, "attempts": res.attempts,
            "iterations": int(res.iterations), "converged": bool(res.converged), "omega": res.omega, "timings": timings}
    if fair_res is not None:
        data["fair"] = {"levels": levels, "energy": fair_res.energy, "plain_energy": fair_res.plain_energy,
                        "iterations": fair_res.iterations, "stop_reason": fair_res.stop_reason}
    if not quiet:
        lvl = f"level {drawn_level}" + (f" (asked {level}; face budget {budget})" if drawn_level < level else "")
        state = "" if res.converged else (f"; NOT converged ({res.stop_reason}): "
                                          f"{stopped_short_message(res, method, tol, max_iter)} (exit code 1)")
        print(f"sorpia render: {input_path} -> {output} ({size[0]}x{size[1]} px, limit surfaces at {lvl}; "
              f"{method_label(method)}" + (f" ({method_label(res.variant)})" if res.variant != method else "")
              + f", omega {omega_text(res.omega)}, {res.iterations} iterations{state})", file=out)
        for line in repair_lines(mesh.repair) if repair else ():
            print(f"  repaired    {line}", file=out)
        if fair_res is not None:
            print(f"  fair        {levels} level{'s' if levels > 1 else ''} finer, {fair_res.iterations} iterations: "
                  f"thin-plate energy {fair_res.energy:.6g}, plain {fair_res.plain_energy:.6g}", file=out)
        print("  seconds     " + ", ".join(f"{k} {fmt_seconds(v)}" for k, v in timings.items()), file=out)
    return (EXIT_OK if res.converged else EXIT_NOT_CONVERGED), data


def render_approximation(input_path, cage_path, output, *, level, boundary, size, elev, azim, face_budget, quiet, up,
                         scheme, sharp_angle, iterations, out) -> tuple[int, dict]:
    """`sorpia render IN --cage CAGE`: the input's vertices are data points; the cage is fitted to them
    (sorpia.approximate) and drawn as in Figure 3: (a) the cage as given, (b) its limit surface with the data,
    (c) the fitted cage, (d) its limit surface with the data."""
    require_plotting()
    timings = {}
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        points = read_input(input_path, tags=False, points=True).vertices
        mesh = read_input(cage_path)
        tags = solve_tags(mesh, sharp_angle, cage_path)
        scheme = choose_scheme(scheme, mesh.faces, cage_path, mesh.tags.get("scheme"))
        rule = boundary if boundary is not None else mesh.tags.get("boundary", DEFAULT_BOUNDARY)
        progress.status("approximate")
        t0 = time.perf_counter()
        res = approximate(points, mesh.vertices, mesh.faces, scheme=scheme, boundary=rule, iterations=iterations,
                          **tags)
        timings["approximate"] = time.perf_counter() - t0
        counts = face_counts(mesh.faces)
        drawn = level_for_budget(len(counts), level, face_budget,
                                 first_level_faces=None if scheme == "loop" else int(counts.sum()))
        progress.status(f"limit surfaces, level {drawn}")
        t0 = time.perf_counter()
        kw = dict(level=drawn, boundary=rule, scheme=scheme, **tags)
        given, fitted = limit_surface(mesh.vertices, mesh.faces, **kw), limit_surface(res.control_vertices,
                                                                                       mesh.faces, **kw)
        timings["surface"] = time.perf_counter() - t0
        progress.status(f"drawing {output}")
        t0 = time.perf_counter()
        f = res.history[-1]
        fig = interpolation_figure(mesh.vertices, mesh.faces, given, res.control_vertices, fitted, size=size,
                                   elev=elev, azim=azim, face_budget=face_budget, up=up, scheme=scheme,
                                   level=drawn, data_points=points,
                                   title=f"{Path(input_path).name}: {len(points)} points (red), "
                                   f"{SCHEME_LABELS[scheme]} cage of {len(mesh.vertices)} vertices, "
                                   f"RMS {f['rms_relative']:.3g} of the diagonal",
                                   labels=["(a) cage as given", "(b) its limit surface and the data",
                                           f"(c) cage fitted, {res.iterations} iterations",
                                           "(d) fitted limit surface and the data"])
        save_figure(fig, output)
        timings["draw"] = time.perf_counter() - t0
    data = {"output": str(output), "scheme": scheme, "level": drawn, "iterations": res.iterations,
            "rms_relative": f["rms_relative"], "timings": timings}
    if not quiet:
        print(f"sorpia render: {input_path} and {cage_path} -> {output} ({size[0]}x{size[1]} px, approximation: "
              f"{res.iterations} iterations, RMS {f['rms_relative']:.3g} of the diagonal)", file=out)
        print("  seconds     " + ", ".join(f"{k} {fmt_seconds(v)}" for k, v in timings.items()), file=out)
    return EXIT_OK, data
