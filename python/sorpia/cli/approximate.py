"""``sorpia approximate``: a light cage whose limit surface fits the points of a scan (sorpia.approximate)."""

from __future__ import annotations

import contextlib
import sys
import time
import warnings

import numpy as np

from .. import DecimationWarning, MeshError, MeshFileError, __version__, _core, approximate, decimate, limit_surface
from .._dask import connect, worker_addresses  # imports dask.distributed only when called
from .._nonmanifold import NONMANIFOLD_HINT, REPAIR_HINT
from .._validate import DEFAULT_BOUNDARY, Polygons, resolve_scheme
from ..approximate import DEFAULT_COARSE_ITERATIONS, DEFAULT_FAIRNESS, DEFAULT_ROBUST, DEFAULT_TOL
from .common import (EXIT_OK, SCHEME_LABELS, UserError, check_mesh_suffix, choose_scheme, fmt_seconds, is_triangles,
                     read_input, report_warnings, solve_tags, tags_lines, tags_summary, warn_once)
from .output import (attribute_lines, attributes_to_write, check_float32_outputs, check_outputs,
                     write_control_mesh, write_json, write_surface)
from .progress import Progress

# The data of an input mesh with faces when --sampling is not given (measured in docs/approximation.md).
DEFAULT_SAMPLING = "vertices"
# An input of more points than this is streamed (--stream auto): in memory a fit holds about 1 KB per point, so 2^24
# points would take some 16 GB (docs/approximation.md, "Large data").
STREAM_POINTS = 1 << 24


def _streamed(input_path, stream) -> bool:
    """Whether the input's points are streamed from the file (sorpia.approximate(path)): --stream yes, or auto and
    a binary little-endian PLY or .npy of more than STREAM_POINTS points (its header says how many)."""
    if stream == "no":
        return False
    try:
        count = _core.point_file_points(str(input_path))
    except MeshFileError as exc:
        if stream == "yes":
            raise UserError(f"--stream yes: {exc}") from None
        return False
    return stream == "yes" or count > STREAM_POINTS


def _cage(input_mesh, vertices, cage, scheme, sharp_angle, source, progress):
    """The cage to fit: (vertices, faces, tags, scheme, boundary rule of its file or None, how it was made, its
    attributes). --cage: read (its tags, scheme, texture coordinates and normals kept, with --sharp-angle's creases
    added: the fit moves only its vertices, so what hangs on its faces stays valid); --vertices N: the input mesh
    decimated (sorpia.decimate). Where the guards stop decimation above N, the cage it reached is fitted: a
    warning says so, and how it was made records why ("stopped")."""
    if cage is not None:
        progress.status(f"reading {cage}")
        mesh = read_input(cage, attributes=True)
        if len(mesh.faces) == 0:
            raise UserError(f"--cage {cage} has no faces: a cage is a mesh of triangles, quads or polygons")
        scheme = choose_scheme(scheme, mesh.faces, cage, mesh.tags.get("scheme"))
        tags = solve_tags(mesh, sharp_angle, cage)
        return (mesh.vertices, mesh.faces, tags, scheme, mesh.tags.get("boundary"),
                {"from": "file", "path": str(cage)}, mesh.attributes)
    if len(input_mesh.faces) == 0:
        raise UserError(f"{source} is a point cloud (no faces): --vertices decimates a mesh's faces; give the "
                        "cage with --cage CAGE")
    if not is_triangles(input_mesh.faces):
        raise UserError(f"{source}: --vertices decimates triangle meshes and this one has other faces: pass "
                        "--triangulate to split them (the data points stay the mesh's vertices), or give the cage "
                        "with --cage CAGE")
    # The vertices the faces use, counted in O(n) (np.unique would sort all 3m corners: seconds at 1M vertices).
    n_referenced = int(np.bincount(np.asarray(input_mesh.faces).reshape(-1), minlength=1).astype(bool).sum())
    scheme = resolve_scheme(scheme, input_mesh.faces)  # triangles: auto is Loop
    progress.status(f"decimating to {vertices} vertices")
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            made = decimate(input_mesh.vertices, input_mesh.faces, vertices, scheme=scheme,
                            sharp_angle=sharp_angle, strict=False)
        except MeshError as exc:
            text = _without_hints(str(exc))
            if text.startswith("decimate stopped at"):  # a valid mesh the guards hold up: no repair helps
                raise UserError(f"{source}: no light cage: {text} (--cage CAGE)") from None
            raise UserError(f"{source}: cannot decimate this mesh: {text}; repair it first "
                            f"(sorpia repair {source} -o repaired.obj)") from None
    stopped = next((str(w.message) for w in caught if issubclass(w.category, DecimationWarning)), None)
    if stopped is not None:
        caught = [w for w in caught if not issubclass(w.category, DecimationWarning)]
        warn_once(f"{stopped}; fitting the cage of {len(made.vertices)} vertices it reached")
    report_warnings(caught)
    tags = {"creases": made.creases} if made.creases is not None and len(made.creases[0]) else {}
    return made.vertices, made.faces, tags, scheme, None, {
        "from": "decimation", "vertices_asked": vertices, "mesh_vertices": n_referenced, "stopped": stopped,
        "seconds": time.perf_counter() - t0}, {}


def _without_hints(message: str) -> str:
    """A library refusal without its ways out that name options of other commands (--repair, --nonmanifold)."""
    for hint in (NONMANIFOLD_HINT, REPAIR_HINT):
        message = message.replace("; " + hint, "").replace(": " + hint, "").replace(hint, "")
    return message.rstrip(" ;:,")


def _cage_refusal(exc: MeshError, origin: dict, source) -> UserError:
    """A cage the library refuses, named as approximate's user knows it: the --cage file, or the cage decimated
    from the input (whose indices are the cage's, not the input's), with approximate's own way out."""
    text = _without_hints(str(exc))
    if origin["from"] == "file":
        path = origin["path"]
        return UserError(f"--cage {path}: the cage cannot be fitted: {text}; sorpia repair {path} -o repaired.obj "
                         "makes a cage valid without moving a vertex")
    return UserError(f"the cage decimated from {source} ({origin.get('vertices_asked')} vertices asked; indices "
                     f"are the cage's) cannot be fitted: {text}; give a cage with --cage CAGE, or another "
                     "--vertices")


def _n_faces(faces) -> int:
    """The faces of an (m, k) array or of Polygons (whose len() is its two fields)."""
    return int(len(faces.face_vertex_counts)) if isinstance(faces, Polygons) else int(len(faces))


def run_approximate(input_path, output, *, vertices=None, cage=None, scheme="auto", sharp_angle=None, report=None,
                    surface=None, level=3, iterations=10, tol=DEFAULT_TOL, fairness=DEFAULT_FAIRNESS, tangential=None,
                    method="cg", boundary=None, sampling=None, quiet=False, force=False, out=None, prim=None,
                    triangulate=False, stream="auto", robust=DEFAULT_ROBUST, scheduler=None,
                    coarse_iterations=DEFAULT_COARSE_ITERATIONS) -> tuple[int, dict]:
    """`sorpia approximate`: returns (exit code, report dict). Every output
    is checked before the work and written atomically after it; an error
    leaves none of them. The cage is written with its scheme, boundary rule
    and tags where the format holds them (a warning where it does not).
    `prim`: the USD input's mesh prim; `triangulate`: the input's polygons
    split into triangles (for --vertices); `stream`: "auto", "yes" or "no"
    (_streamed: the points read a chunk at a time, never all in memory);
    `scheduler`: the address of a Dask scheduler whose workers run the fit's
    chunks (dialled before the input is read; its client closed at the end;
    a streamed file is read by the workers themselves)."""
    out = out if out is not None else sys.stdout
    if (vertices is None) == (cage is None):
        raise UserError("give the cage: --vertices N (decimate the input) or --cage CAGE (a mesh file), one of them")
    check_mesh_suffix("--cage", cage)
    check_outputs([p for p in (input_path, cage) if p is not None], output, surface, report, force=force)
    timings = {}
    with _client(scheduler) if scheduler is not None else contextlib.nullcontext() as client:
        return _run(input_path, output, client, scheduler, timings, vertices=vertices, cage=cage, scheme=scheme,
                    sharp_angle=sharp_angle, report=report, surface=surface, level=level, iterations=iterations,
                    tol=tol, fairness=fairness, tangential=tangential, method=method, boundary=boundary,
                    sampling=sampling, quiet=quiet, out=out, prim=prim, triangulate=triangulate, stream=stream,
                    robust=robust, coarse_iterations=coarse_iterations)


@contextlib.contextmanager
def _client(address):
    """A Client of the Dask scheduler at `address`, closed on leaving; a UserError naming the address when
    dask.distributed is not installed or no scheduler answers there."""
    try:
        client = connect(address)
    except (ImportError, OSError) as exc:
        raise UserError(str(exc)) from None
    try:
        yield client
    finally:
        client.close()


def _run(input_path, output, client, scheduler, timings, *, vertices, cage, scheme, sharp_angle, report, surface,
         level, iterations, tol, fairness, tangential, method, boundary, sampling, quiet, out, prim, triangulate,
         stream, robust, coarse_iterations):
    """run_approximate's work, with its client (or None)."""
    with Progress("approximate", enabled=not quiet) as progress:
        t0 = time.perf_counter()
        streamed = _streamed(input_path, stream)
        if streamed:
            if cage is None:
                raise UserError(f"{input_path} is streamed (--stream): --vertices decimates a mesh, which must be in "
                                "memory; give the cage with --cage CAGE (e.g. decimate a subsample of the points)")
            if sampling not in (None, "vertices"):
                raise UserError(f"--sampling {sampling} samples a mesh's faces and {input_path} is streamed: its "
                                "points are the data as they are (--stream no reads the mesh)")
            mesh = None
            points = str(input_path)
            n_input = _core.point_file_points(points)
        else:
            progress.status(f"reading {input_path}")
            mesh = read_input(input_path, triangulate=triangulate, tags=False, points=True, prim=prim)
            points = mesh.vertices
            n_input = len(points)
        timings["read"] = time.perf_counter() - t0
        if not streamed and sampling not in (None, "vertices") and len(mesh.faces) == 0:
            raise UserError(f"--sampling {sampling} samples a mesh's faces and {input_path} is a point cloud: "
                            "its points are the data as they are")
        sampling = sampling or (DEFAULT_SAMPLING if not streamed and len(mesh.faces) else "vertices")
        surface_data = {} if sampling == "vertices" else {"faces": mesh.faces, "sampling": sampling}
        if not streamed:
            check_float32_outputs(points, {"-o": output, "--surface": surface})
        t0 = time.perf_counter()
        cage_v, cage_f, tags, scheme, file_rule, origin, cage_attributes = _cage(mesh, vertices, cage, scheme, sharp_angle,
                                                                input_path, progress)
        timings["cage"] = time.perf_counter() - t0
        check_float32_outputs(cage_v, {"-o": output, "--surface": surface})
        attributes, attribute_notes = attributes_to_write(output, cage_attributes, cage_f, len(cage_v))
        rule = boundary if boundary is not None else file_rule if file_rule is not None else DEFAULT_BOUNDARY

        def on_iteration(rec):
            progress.note(f"approximate: iteration {rec['iteration']}, RMS {rec['rms_relative']:.3g} of the "
                          f"diagonal, max {rec['max_relative']:.3g}, {rec['seconds']:.1f} s")

        progress.status("footpoints")
        t0 = time.perf_counter()
        try:
            with warnings.catch_warnings(record=True) as caught:  # a surface that strays: said once, as the others
                warnings.simplefilter("always")
                res = approximate(points, cage_v, cage_f, scheme=scheme, boundary=rule, iterations=iterations,
                                  tol=tol, fairness=fairness, tangential=tangential, method=method,
                                  callback=on_iteration, robust=robust, client=client,
                                  coarse_iterations=coarse_iterations, **surface_data,
                                  **tags)
        except MeshError as exc:  # the data were read and checked: what is refused is the cage
            raise _cage_refusal(exc, origin, input_path) from None
        report_warnings(caught)
        timings["approximate"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        surface_stats = None
        if surface is not None:  # made before anything is written: a failure leaves no output
            progress.status(f"limit surface, level {level}")
            Vs, Fs = limit_surface(res.control_vertices, cage_f, level=level, boundary=rule, scheme=scheme, **tags)
            surface_stats = {"path": str(surface), "level": level, "vertices": len(Vs), "faces": len(Fs)}
        progress.status(f"writing {output}")
        # The cage keeps its scheme, boundary rule and tags where the format holds them, so that it can be refitted.
        written = write_control_mesh(output, res.control_vertices, cage_f, scheme=scheme, boundary=rule, tags=tags,
                                     attributes=attributes)
        if surface is not None:
            write_surface(surface, Vs, Fs)
        timings["write"] = time.perf_counter() - t0
    data = {"sorpia_version": __version__, "command": "approximate", "input": str(input_path),
            "input_points": int(n_input), "sampling": sampling, "streamed": streamed, "output": str(output),
            "cage": {**origin, "vertices": int(len(cage_v)), "faces": _n_faces(cage_f)},
            "scheme": scheme, "boundary": rule,
            "tags": {"sharp_angle": sharp_angle, **tags_summary(tags), "written_to_output": list(written.written)},
            "attributes": attribute_notes, "surface": surface_stats,
            "scheduler": None if client is None else {"address": scheduler, "workers": len(worker_addresses(client))},
            "report": None if report is None else str(report), **res.report(),
            # the cage as read back from the file against the fitted one (USD stores float32): 0 for OBJ, OFF, PLY
            "written_max_change": float(np.abs(written.vertices - res.control_vertices).max(initial=0.0)),
            "timings": {**timings, **{f"approximate.{k}": v for k, v in res.timings.items() if k not in ("cpu", "cluster")}},
            "cpu_seconds": res.timings["cpu"]}
    if report is not None:
        write_json(report, data)
    if not quiet:
        print(approximate_summary(data), file=out)
    return EXIT_OK, data


def _distances(rec: dict, prefix: str = "") -> str:
    """'RMS a, max b of the diagonal (RMS c, max d model units)' for a history record's distances."""
    r, m = rec[f"{prefix}rms"], rec[f"{prefix}max"]
    return (f"RMS {rec[f'{prefix}rms_relative']:.3g}, max {rec[f'{prefix}max_relative']:.3g} of the diagonal "
            f"(RMS {r:.4g}, max {m:.4g} model units)")


def _kept(rec: dict) -> str:
    """'RMS a of the diagonal (RMS b model units) within the cut, n cut' for a robust fit's record: the points the
    loss keeps (within c s) and the count of those it cuts."""
    return (f"RMS {rec['inlier_rms_relative']:.3g} of the diagonal (RMS {rec['inlier_rms']:.4g} model units) within "
            f"the cut, {rec['robust_cut']} points beyond it")


def approximate_summary(d: dict) -> str:
    """The summary `sorpia approximate` prints: every distance in model units and as a fraction of the data's
    bounding-box diagonal; the cage as given beside it, or "unchanged" when no update lowered its criterion (the
    RMS distance, or the robust loss: the cage written is the one given). With a robust loss, a line for the
    points within its cut (the data the fit keeps) beside the count of those beyond it, for both."""
    f, first = d["final"], d["history"][0]
    robust = d.get("robust", "none") != "none"
    criterion = f"the robust loss ({d['robust']})" if robust else "the RMS distance"
    made = (f"read from {d['cage']['path']}" if d["cage"]["from"] == "file" else
            f"decimated from {d['cage']['mesh_vertices']} vertices" +
            (f" ({d['cage']['vertices_asked']} asked: the guards stopped decimation)" if d["cage"]["stopped"] else ""))
    t = d["timings"]
    inner = ", ".join(f"{k.split('.', 1)[1]} {fmt_seconds(v)}" for k, v in t.items()
                      if k.startswith("approximate.") and k != "approximate.total")
    phases = ", ".join(f"{k} {fmt_seconds(v)}" + (f" ({inner})" if k == "approximate" else "")
                       for k, v in t.items() if "." not in k)
    written = [d["output"]] + ([d["surface"]["path"]] if d["surface"] else []) + ([d["report"]] if d["report"] else [])
    state = {"converged": f"stopped: {criterion} no longer fell by --tol", "exact": "stopped: the data lie on "
             "the surface to rounding", "max_iter": "stopped at --iterations"}[d["stop_reason"]]
    unchanged = d["best_iteration"] == 0
    given = (f"unchanged: no update lowered {criterion} of the cage as given (best iteration 0), which is "
             "written" if unchanged else
             f"the cage as given: RMS {first['rms_relative']:.3g}, max {first['max_relative']:.3g} of the diagonal")
    tag_lines = tags_lines(d["tags"])
    return "\n".join([
        f"sorpia approximate: {d['input']} -> {d['output']}",
        f"  data        {d['input_points']} points, bounding-box diagonal {d['diagonal']:.4g} model units; " + (
            "the points, equally weighted" if d["sampling"] == "vertices" else
            f"the surface: {d['n_points']} samples ({d['sampling']}), RMS distances per area"),
        f"  cage        {d['cage']['vertices']} vertices, {d['cage']['faces']} faces, {made}",
        f"  scheme      {SCHEME_LABELS[d['scheme']]}, boundary {d['boundary']}",
        *(f"  {'tags' if j == 0 else '':<12}{line}" for j, line in enumerate(tag_lines)),
        *attribute_lines(d.get("attributes", {})),
        *([f"  cluster     Dask scheduler {d['scheduler']['address']}, {d['scheduler']['workers']} workers"]
          if d.get("scheduler") else []),
        f"  update      {d['method']}, {d['iterations']} iterations ({state})" + (
            f"; robust {d['robust']}" if robust else ""),
        f"  data->surf  {_distances(f)}" + (" over all the points" if robust else "") + f"; {given}",
        *([f"  kept        {_kept(f)}" + ("" if unchanged else f"; the cage as given: {_kept(first)}")]
          if robust else []),
        f"  surf->data  {_distances(f, 'surface_')}",
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written)}" + (
            f" (the cage as written, read back, moved by at most {d['written_max_change']:.3g} model units, "
            f"{d['written_max_change'] / (d['diagonal'] or 1.0):.3g} of the diagonal: USD stores float32)"
            if d["written_max_change"] else ""),
    ])
