"""``sorpia approximate``: a light cage whose limit surface fits the points of a scan (sorpia.approximate)."""

from __future__ import annotations

import sys
import time
import warnings

import numpy as np

from .. import __version__
from .common import (EXIT_OK, SCHEME_LABELS, UserError, check_mesh_suffix, check_paths, fmt_seconds, is_triangles,
                     read_input, report_warnings, solve_tags, tags_summary, warn_once)
from .output import write_json
from ..approximate import DEFAULT_FAIRNESS, DEFAULT_TOL
from .._validate import resolve_scheme
from .progress import Progress

# The data of an input mesh with faces when --sampling is not given (measured in docs/approximation.md).
DEFAULT_SAMPLING = "vertices"


def _cage(input_mesh, vertices, cage, scheme, sharp_angle, source, progress):
    """The cage to fit: (vertices, faces, tags, scheme, how it was made). --cage: read (its tags kept, with
    --sharp-angle's creases added); --vertices N: the input mesh decimated (sorpia.decimate). Where the guards stop
    decimation above N, the cage it reached is fitted: a warning says so, and how it was made records why
    ("stopped")."""
    if cage is not None:
        progress.status(f"reading {cage}")
        mesh = read_input(cage)
        if len(mesh.faces) == 0:
            raise UserError(f"--cage {cage} has no faces: a cage is a mesh of triangles, quads or polygons")
        tags = solve_tags(mesh, sharp_angle, cage)
        scheme = resolve_scheme(scheme, mesh.faces, mesh.tags.get("scheme"))  # a USD cage's own scheme first
        return mesh.vertices, mesh.faces, tags, scheme, {"from": "file", "path": str(cage)}
    from .. import DecimationWarning, decimate

    if len(input_mesh.faces) == 0:
        raise UserError(f"{source} is a point cloud (no faces): --vertices decimates a mesh's faces; give the "
                        "cage with --cage CAGE")
    if not is_triangles(input_mesh.faces):
        raise UserError(f"{source}: --vertices decimates triangle meshes and this one has other faces; "
                        "give the cage with --cage CAGE")
    n_referenced = len(np.unique(np.asarray(input_mesh.faces).reshape(-1)))
    scheme = resolve_scheme(scheme, input_mesh.faces)  # triangles: auto is Loop
    progress.status(f"decimating to {vertices} vertices")
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        made = decimate(input_mesh.vertices, input_mesh.faces, vertices, scheme=scheme, sharp_angle=sharp_angle,
                        strict=False)
    stopped = next((str(w.message) for w in caught if issubclass(w.category, DecimationWarning)), None)
    if stopped is not None:
        caught = [w for w in caught if not issubclass(w.category, DecimationWarning)]
        warn_once(f"{stopped}; fitting the cage of {len(made.vertices)} vertices it reached")
    report_warnings(caught)
    tags = {"creases": made.creases} if made.creases is not None and len(made.creases[0]) else {}
    return made.vertices, made.faces, tags, scheme, {"from": "decimation", "vertices_asked": vertices,
                                                     "mesh_vertices": n_referenced, "stopped": stopped,
                                                     "seconds": time.perf_counter() - t0}


def run_approximate(input_path, output, *, vertices=None, cage=None, scheme="auto", sharp_angle=None, report=None,
                    surface=None, level=3, iterations=10, tol=DEFAULT_TOL, fairness=DEFAULT_FAIRNESS, tangential=None,
                    method="cg", boundary=None, sampling=None, quiet=False, force=False, out=None) -> tuple[int, dict]:
    """`sorpia approximate`: returns (exit code, report dict). Every output
    is checked before the work and written atomically after it; an error
    leaves none of them."""
    from .. import approximate, limit_surface, write_mesh
    from .._validate import DEFAULT_BOUNDARY

    out = out if out is not None else sys.stdout
    if (vertices is None) == (cage is None):
        raise UserError("give the cage: --vertices N (decimate the input) or --cage CAGE (a mesh file), one of them")
    check_mesh_suffix("-o", output)
    check_mesh_suffix("--surface", surface)
    check_mesh_suffix("--cage", cage)
    check_paths([p for p in (input_path, cage) if p is not None],
                {"-o": output, "--surface": surface, "--report": report}, force)
    timings = {}
    with Progress("approximate", enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        t0 = time.perf_counter()
        mesh = read_input(input_path, tags=False, points=True)
        timings["read"] = time.perf_counter() - t0
        points = mesh.vertices
        if sampling not in (None, "vertices") and len(mesh.faces) == 0:
            raise UserError(f"--sampling {sampling} samples a mesh's faces and {input_path} is a point cloud: "
                            "its points are the data as they are")
        sampling = sampling or (DEFAULT_SAMPLING if len(mesh.faces) else "vertices")
        surface_data = {} if sampling == "vertices" else {"faces": mesh.faces, "sampling": sampling}
        t0 = time.perf_counter()
        cage_v, cage_f, tags, scheme, origin = _cage(mesh, vertices, cage, scheme, sharp_angle, input_path, progress)
        timings["cage"] = time.perf_counter() - t0
        rule = boundary if boundary is not None else DEFAULT_BOUNDARY

        def on_iteration(rec):
            if quiet:
                return
            text = (f"approximate: iteration {rec['iteration']}, RMS {rec['rms']:.3g} ({rec['rms_relative']:.3g} of "
                    f"the diagonal), max {rec['max']:.3g}, {rec['seconds']:.1f} s")
            progress.status(text)

        progress.status("footpoints")
        t0 = time.perf_counter()
        res = approximate(points, cage_v, cage_f, scheme=scheme, boundary=rule, iterations=iterations, tol=tol,
                          fairness=fairness, tangential=tangential, method=method, callback=on_iteration,
                          **surface_data, **tags)
        timings["approximate"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        surface_stats = None
        if surface is not None:  # made before anything is written: a failure leaves no output
            progress.status(f"limit surface, level {level}")
            Vs, Fs = limit_surface(res.control_vertices, cage_f, level=level, boundary=rule, scheme=scheme, **tags)
            surface_stats = {"path": str(surface), "level": level, "vertices": len(Vs), "faces": len(Fs)}
        progress.status(f"writing {output}")
        # OBJ keeps the tags and the boundary rule the cage was fitted with, so that it can be refitted.
        obj = str(output).lower().endswith(".obj")
        write_mesh(output, res.control_vertices, cage_f, **(dict(tags, boundary=rule) if obj else {}))
        if surface is not None:
            write_mesh(surface, Vs, Fs)
        timings["write"] = time.perf_counter() - t0
    data = {"sorpia_version": __version__, "command": "approximate", "input": str(input_path),
            "input_points": int(len(points)), "sampling": sampling, "output": str(output),
            "cage": {**origin, "vertices": int(len(cage_v)), "faces": int(len(cage_f))},
            "scheme": scheme, "boundary": rule, "tags": {"sharp_angle": sharp_angle, **tags_summary(tags)},
            "surface": surface_stats, "report": None if report is None else str(report), **res.report(),
            "timings": {**timings, **{f"approximate.{k}": v for k, v in res.timings.items() if k != "cpu"}},
            "cpu_seconds": res.timings["cpu"]}
    if report is not None:
        write_json(report, data)
    if not quiet:
        print(approximate_summary(data), file=out)
    return EXIT_OK, data


def approximate_summary(d: dict) -> str:
    """The summary `sorpia approximate` prints."""
    f, first = d["final"], d["history"][0]
    made = (f"read from {d['cage']['path']}" if d["cage"]["from"] == "file" else
            f"decimated from {d['cage']['mesh_vertices']} vertices" +
            (f" ({d['cage']['vertices_asked']} asked: the guards stopped decimation)" if d["cage"]["stopped"] else ""))
    t = d["timings"]
    inner = ", ".join(f"{k.split('.', 1)[1]} {fmt_seconds(v)}" for k, v in t.items()
                      if k.startswith("approximate.") and k != "approximate.total")
    phases = ", ".join(f"{k} {fmt_seconds(v)}" + (f" ({inner})" if k == "approximate" else "")
                       for k, v in t.items() if "." not in k)
    written = [d["output"]] + ([d["surface"]["path"]] if d["surface"] else []) + ([d["report"]] if d["report"] else [])
    state = {"converged": "stopped: the RMS distance no longer fell by --tol", "exact": "stopped: the data lie on "
             "the surface to rounding", "max_iter": "stopped at --iterations"}[d["stop_reason"]]
    return "\n".join([
        f"sorpia approximate: {d['input']} -> {d['output']}",
        f"  data        {d['input_points']} points, bounding-box diagonal {d['diagonal']:.4g}; " + (
            "the points, equally weighted" if d["sampling"] == "vertices" else
            f"the surface: {d['n_points']} samples ({d['sampling']}), RMS distances per area"),
        f"  cage        {d['cage']['vertices']} vertices, {d['cage']['faces']} faces, {made}",
        f"  scheme      {SCHEME_LABELS[d['scheme']]}, boundary {d['boundary']}",
        f"  update      {d['method']}, {d['iterations']} iterations ({state})",
        f"  data->surf  RMS {f['rms']:.4g} ({f['rms_relative']:.3g} of the diagonal), max {f['max']:.4g} "
        f"({f['max_relative']:.3g}); the cage as given: RMS {first['rms_relative']:.3g}, max "
        f"{first['max_relative']:.3g}",
        f"  surf->data  RMS {f['surface_rms']:.4g} ({f['surface_rms_relative']:.3g}), max {f['surface_max']:.4g} "
        f"({f['surface_max_relative']:.3g})",
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written)}",
    ])
