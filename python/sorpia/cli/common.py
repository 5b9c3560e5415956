"""What the subcommands share: exit codes, the user error, input paths and
files, solver options, the timed solve and the printed warnings."""

from __future__ import annotations

import inspect
import os
import sys
import time
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .. import (Interpolator, MeshError, MeshFileError, ParameterError, _core, fair_interpolate, interpolate,
                sharp_edges)
from .. import repair as repair_mesh
from .._meshdata import carry_attributes, merge_sharpness
from .._nonmanifold import split
from .._plotting import require_matplotlib
from .._repair import describe_changes
from .._usd import is_usd
from .._validate import AUTO_SCHEME, DEFAULT_BOUNDARY, SCHEMES, resolve_scheme
from ..io import read_mesh_file
from ..solve import METHODS, THREADED_METHODS, ConvergenceWarning  # ConvergenceWarning: the summary says it
from ..solve import check_options
from . import progress as _progress

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143


def _defaults(function, names) -> dict:
    return {name: p.default for name, p in inspect.signature(function).parameters.items() if name in names}


# The library's own defaults, which the commands use where an option is not given (--tol and --max-iter of
# fit, compare and render: sorpia.interpolate's; with --fair: sorpia.fair_interpolate's).
FIT_DEFAULTS = _defaults(interpolate, ("tol", "max_iter"))
FAIR_DEFAULTS = _defaults(fair_interpolate, ("tol", "max_iter", "levels", "membrane"))

# The paper's names (Table 1) for the methods it compares, and ours for the
# rest; compare's rows and the help list the methods in this order.
METHOD_LABELS = {"auto": "auto", "pia": "PIA", "wpia": "W-PIA", "hss": "HSS-PIA", "whss": "WHSS-PIA",
                 "gs": "Gauss-Seidel", "sor": "SOR-PIA", "cg": "CG", "gmres": "GMRES", "cgls": "CGLS"}
# The methods that take --omega: sor, and auto for its sor run.
OMEGA_METHODS = ("sor", "auto")
DISPLAY_ORDER = tuple(sorted(METHODS, key=lambda m: list(METHOD_LABELS).index(m) if m in METHOD_LABELS
                             else len(METHOD_LABELS)))
MESH_SUFFIXES = (".obj", ".off", ".ply", ".stl", ".usd", ".usda", ".usdc")
# --scheme: the library's schemes, and "auto" (Loop for an all-triangle mesh, Catmull-Clark otherwise).
CLI_SCHEMES = (AUTO_SCHEME,) + SCHEMES  # the library's names (_validate.as_scheme)
SCHEME_LABELS = {"loop": "Loop", "catmull-clark": "Catmull-Clark"}


def method_label(method: str) -> str:
    return METHOD_LABELS.get(method, method)


class UserError(Exception):
    """Bad input from the command line: reported as one line, exit code 2."""


class PolygonError(UserError):
    """Loop was asked for (--scheme loop) on a file with faces of more than 3 vertices."""


# --------------------------------------------------------------------------- paths and files


def _same_file(a, b) -> bool:
    a, b = Path(a), Path(b)
    if a.resolve() == b.resolve():
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_paths(inputs, outputs: dict, force: bool = False) -> None:
    """Refuse an output that is an input (unless `force`), the same file given
    for two outputs, an output whose folder does not exist, and one the
    atomic writer could not start on (a folder not writable, a name too long
    for its folder: sorpia::check_writable); before any work is done, so a
    long fit never ends in 'cannot write'."""
    named = [(opt, p) for opt, p in outputs.items() if p is not None]
    for opt, p in named:
        folder = Path(p).parent
        if not folder.is_dir():
            raise UserError(f"{opt} {p}: folder {folder} does not exist")
        try:
            # First: a name too long for its folder fails every other look-up.
            _core.check_writable(os.fsencode(p))
        except MeshFileError as exc:
            raise UserError(f"{opt} {exc}") from None
        for src in inputs:
            if _same_file(p, src) and not force:
                raise UserError(f"{opt} {p} is the input file: refusing to overwrite it (pass --force to do so)")
    for i, (opt_a, a) in enumerate(named):
        for opt_b, b in named[i + 1:]:
            if _same_file(a, b):
                raise UserError(f"{opt_a} and {opt_b} name the same file {a}")


def usd_template(input_path, output, prim) -> dict:
    """write_mesh's keywords for a USD output of a USD input: the input's stage
    as the template, the mesh written into its prim (`prim`, --prim); {}
    otherwise."""
    return {"template": input_path, "prim": prim} if is_usd(output) and is_usd(input_path) else {}


def check_mesh_suffix(opt: str, path) -> None:
    if path is not None and Path(path).suffix.lower() not in MESH_SUFFIXES:
        raise UserError(f"{opt} {path}: unknown mesh format {Path(path).suffix or '(no suffix)'!r}; "
                        f"use one of {', '.join(MESH_SUFFIXES)}")


class InputMesh(NamedTuple):
    """The input mesh of a command, as read_input returns it."""

    vertices: np.ndarray
    faces: object  # (m, k) int32 array, or sorpia.Polygons for mixed sizes
    seconds: float  # reading (and triangulating)
    polygons: int  # polygons split by --triangulate
    repair: object = None  # sorpia.RepairResult with --repair: vertices and faces are its output
    repair_seconds: float = 0.0
    tags: dict = {}  # the file's tags as read_mesh(tags=True) returns them ({} with --ignore-tags)
    split: object = None  # sorpia._nonmanifold.Split with --nonmanifold sharp: vertices and faces are the split's
    attributes: dict = {}  # texture coordinates and normals (read_mesh(attributes=True)), on the faces above

    @property
    def timings(self) -> dict:
        """The seconds of a command's input phases: "read", and "repair" with --repair."""
        return {"read": self.seconds, **({"repair": self.repair_seconds} if self.repair is not None else {})}


def read_input(path, triangulate: bool = False, repair: bool = False, tags: bool = True,
               nonmanifold: str = "error", boundary=None, attributes: bool = False, prim=None,
               points: bool = False) -> InputMesh:
    """Read the input mesh of every subcommand: polygons kept (or split with
    `triangulate`), the OBJ file's sharpness tags read unless `tags` is
    False (--ignore-tags), the mesh repaired with `repair` (repair_input),
    its tags carried onto the repaired mesh; with `nonmanifold` "sharp", a
    non-manifold mesh replaced by its manifold split (split_input) under the
    boundary rule the command solves with (`boundary`: --boundary, None for
    the file's, see boundary_rule); with `attributes`, the file's texture
    coordinates and normals, carried onto the repaired or split faces
    (carry_attributes); `prim`: a USD file's mesh prim (--prim); `points`: a
    file without faces (a point cloud) is read too. A USD mesh's
    subdivisionScheme is in `tags` as "scheme" (choose_scheme)."""
    if not Path(path).exists():
        raise UserError(f"{path}: no such file")
    if Path(path).is_dir():
        raise UserError(f"{path} is a folder, not a mesh file")
    t0 = time.perf_counter()
    has_tags = Path(path).suffix.lower() == ".obj" or is_usd(path)
    contents = read_mesh_file(path, triangulate=triangulate, tags=tags and has_tags, attributes=attributes,
                              prim=prim, points=points)
    seconds = time.perf_counter() - t0
    vertices, faces, file_tags = contents.vertices, contents.faces, contents.tags or {}
    file_attributes = contents.attributes or {}
    if not repair:
        mesh = InputMesh(vertices, faces, seconds, contents.polygons_split, tags=file_tags, attributes=file_attributes)
    else:
        t0 = time.perf_counter()
        result = repair_input(vertices, faces, path, sharpness_tags(file_tags))
        mesh = InputMesh(result.vertices, result.faces, seconds, contents.polygons_split, result,
                         time.perf_counter() - t0, {**file_tags, **result.tags},
                         attributes=carry_attributes(file_attributes, faces, len(vertices), result.faces,
                                                     result.vertex_map, result.face_map))
    return split_input(mesh, path, boundary_rule(boundary, mesh)) if nonmanifold == "sharp" else mesh


def sharpness_tags(tags: dict) -> dict:
    """The creases, corners and holes of a file's tags (without its boundary rule)."""
    return {k: v for k, v in tags.items() if k in ("creases", "corners", "holes")}


def split_input(mesh: InputMesh, source, boundary: str) -> InputMesh:
    """--nonmanifold sharp: a non-manifold mesh replaced by its manifold split
    with OpenSubdiv's rules as corner and crease tags (sorpia._nonmanifold.split under the
    `boundary` rule; its NonmanifoldWarning is printed); what the split
    cannot reproduce is a UserError naming the file `source`."""
    try:
        s = split(mesh.faces, len(mesh.vertices), boundary, **sharpness_tags(mesh.tags))
    except MeshError as exc:
        raise UserError(f"{source}: --nonmanifold sharp: {exc}") from None
    if s is None:
        return mesh
    return mesh._replace(vertices=mesh.vertices[s.vertex_map], faces=s.faces, tags={**mesh.tags, **s.tags}, split=s,
                         attributes=carry_attributes(mesh.attributes, mesh.faces, len(mesh.vertices), s.faces,
                                                     s.vertex_map, None))


def split_json(split) -> dict:
    """What a command's JSON report holds of --nonmanifold sharp: the
    non-manifold edges and vertices (input indices), the corners among them,
    the edges of the split made infinitely sharp creases (sharp_edges, the
    split's indices) and the vertex map of the split (for every vertex of the
    split, the input vertex it copies)."""
    return {**split.report, "vertex_map": split.vertex_map}


def split_lines(split) -> list[str]:
    """One line saying what --nonmanifold sharp kept."""
    r = split.report
    return [f"non-manifold topology kept (OpenSubdiv's rules): {len(r['nonmanifold_edges'])} edges infinitely "
            f"sharp, {len(r['corners'])} corner vertices, "
            f"{len(r['nonmanifold_vertices']) - len(r['corners'])} crease vertices; "
            f"{len(split.vertex_map) - int(split.vertex_map.max()) - 1} vertex copies in the split"]


def is_triangles(faces) -> bool:
    """Whether faces as read_mesh returns them are all triangles."""
    return isinstance(faces, np.ndarray) and faces.ndim == 2 and faces.shape[1] == 3


def face_counts(faces) -> np.ndarray:
    """The number of vertices of each face, for faces as read_mesh returns them."""
    if isinstance(faces, np.ndarray):
        return np.full(len(faces), faces.shape[1] if faces.ndim == 2 else 0, dtype=np.int64)
    return np.asarray(faces.face_vertex_counts, dtype=np.int64)


def face_sizes_text(faces) -> str:
    """'3, 4 and 5': the face sizes a mesh has."""
    sizes = [str(k) for k in np.unique(face_counts(faces))]
    return sizes[0] if len(sizes) == 1 else ", ".join(sizes[:-1]) + " and " + sizes[-1]


def face_size_histogram(faces) -> dict:
    """{vertices per face: faces}, e.g. {3: 132, 4: 836}."""
    sizes, counts = np.unique(face_counts(faces), return_counts=True)
    return {int(k): int(c) for k, c in zip(sizes, counts)}


def choose_scheme(scheme: str, faces, source, file_scheme=None) -> str:
    """--scheme resolved for the mesh: auto is the file's scheme (a USD
    mesh's subdivisionScheme, `file_scheme`) when it has one, else Loop for
    an all-triangle mesh and Catmull-Clark otherwise; Loop on polygons is a
    PolygonError naming the first face that is not a triangle and the two
    ways out."""
    scheme_asked = scheme
    scheme = resolve_scheme(scheme, faces, file_scheme)  # the library's one rule
    if scheme == "loop" and not is_triangles(faces):
        counts = face_counts(faces)
        f = int(np.flatnonzero(counts != 3)[0])
        given = "the file's subdivisionScheme is loop" if file_scheme == "loop" and scheme_asked == AUTO_SCHEME else ""
        ways = ("pass --scheme catmull-clark to keep them (a USD file cannot be triangulated while read)"
                if is_usd(source) else "pass --triangulate to split the polygons, or --scheme catmull-clark (or "
                "auto) to keep them")
        raise PolygonError(f"{source}: face {f} has {counts[f]} vertices and Loop subdivision needs triangles"
                           f"{' (' + given + ')' if given else ''}; {ways}")
    return scheme


def solve_tags(mesh: InputMesh, sharp_angle, source) -> dict:
    """The creases, corners and holes a command solves with: the file's tags,
    and with --sharp-angle every edge sharper than it as an infinitely sharp
    crease (sorpia.sharp_edges; an edge the file already tags is infinitely
    sharp too: the last sharpness given counts, OpenSubdiv's rule)."""
    tags = {k: v for k, v in mesh.tags.items() if k in ("creases", "corners", "holes")}
    if sharp_angle is None:
        return tags
    try:
        edges = sharp_edges(mesh.vertices, mesh.faces, sharp_angle)
    except MeshError as exc:
        raise UserError(f"{source}: --sharp-angle: {exc}") from None
    # After the file's creases: an edge both tag counts with the infinite sharpness (the library's one rule,
    # sorpia._meshdata.merge_sharpness: the last one given).
    tags["creases"] = merge_sharpness(tags.get("creases"), (edges, _core.INFINITE_SHARPNESS))
    return tags


def read_solve_input(path, *, triangulate: bool, repair: bool, ignore_tags: bool, nonmanifold: str, scheme: str,
                     boundary, sharp_angle, attributes: bool = False, prim=None) -> tuple[InputMesh, str, str, dict]:
    """read_input for the commands that solve (fit, compare, render), then
    what they solve with: (mesh, scheme (choose_scheme), boundary rule
    (boundary_rule; with --nonmanifold sharp, the rule its split is solved
    under), creases/corners/holes (solve_tags))."""
    mesh = read_input(path, triangulate, repair, tags=not ignore_tags, nonmanifold=nonmanifold, boundary=boundary,
                      attributes=attributes, prim=prim)
    rule = mesh.split.boundary if mesh.split is not None else boundary_rule(boundary, mesh)
    return mesh, choose_scheme(scheme, mesh.faces, path, mesh.tags.get("scheme")), rule, solve_tags(
        mesh, sharp_angle, path)


def boundary_rule(boundary, mesh: InputMesh) -> str:
    """--boundary when given, else the file's interpolateboundary tag, else the default rule."""
    return boundary if boundary is not None else mesh.tags.get("boundary", DEFAULT_BOUNDARY)


def tags_summary(tags: dict) -> dict:
    """What a command reports of the tags it solved with: per kind the count,
    and for creases and corners how many are infinitely sharp, semi-sharp
    and smooth (0), with the histogram {sharpness: count}."""
    out: dict = {}
    for kind in ("creases", "corners"):
        if kind not in tags:
            continue
        sharpness = np.asarray(tags[kind][1], dtype=float)
        infinite = sharpness >= _core.INFINITE_SHARPNESS
        values, counts = np.unique(sharpness, return_counts=True)
        out[kind] = {"count": len(sharpness), "infinitely_sharp": int(infinite.sum()),
                     "semi_sharp": int(((sharpness > 0) & ~infinite).sum()), "smooth": int((sharpness == 0).sum()),
                     "sharpness_histogram": {repr(float(v)): int(c) for v, c in zip(values, counts)}}
    if "holes" in tags:
        out["holes"] = {"count": len(tags["holes"])}
    return out


def tags_lines(summary: dict) -> list[str]:
    """One line per kind of tag, e.g. 'creases  314: 280 infinitely sharp, 34 semi-sharp (sharpness 6.0 x 20, ...)'."""
    lines = []
    for kind in ("creases", "corners"):
        if kind not in summary:
            continue
        s = summary[kind]
        parts = [f"{s[k]} {label}" for k, label in (("infinitely_sharp", "infinitely sharp"),
                                                    ("semi_sharp", "semi-sharp"), ("smooth", "smooth (0)")) if s[k]]
        histogram = ", ".join(f"{float(v):g} x {c}" for v, c in s["sharpness_histogram"].items())
        lines.append(f"{kind} {s['count']}: {', '.join(parts)} (sharpness {histogram})")
    if "holes" in summary:
        lines.append(f"holes {summary['holes']['count']}")
    return lines


def scheme_kwargs(scheme: str, tags: dict) -> dict:
    """The keyword arguments a solve takes for the scheme and tags: none for
    Loop (the library's default scheme), `scheme` otherwise, and the tags.
    A library without the argument asked for is a UserError saying so."""
    kwargs = {**({} if scheme == "loop" else {"scheme": scheme}), **tags}
    missing = [k for k in ("scheme", "creases") if (k == "scheme" and "scheme" in kwargs or k == "creases" and tags)
               and k not in inspect.signature(Interpolator).parameters]
    if missing:
        raise UserError(f"this build of sorpia cannot solve {SCHEME_LABELS[scheme]}"
                        f"{' with sharpness tags' if tags else ''}: its Interpolator takes no "
                        f"{' or '.join(m + '=' for m in missing)}; pass --triangulate and --ignore-tags")
    return kwargs


def repair_input(vertices, faces, source, tags=None):
    """sorpia.repair of a command's input, with its sharpness `tags` (a dict
    of creases, corners, holes); a mesh it refuses (no face left, an index
    out of range) is a UserError naming the file `source`."""
    try:
        return repair_mesh(vertices, faces, **(tags or {}))
    except MeshError as exc:
        raise UserError(f"{source}: cannot repair this mesh: {exc}") from None


def repair_json(result) -> dict:
    """What a command's JSON report holds of a repair: the report (every
    change, with input indices), the vertex map (for every output vertex, the
    input vertex it copies) and the face map (for every output face, the input
    face it comes from; with --triangulate, a face of the triangulation)."""
    return {"report": result.changes, "vertex_map": result.vertex_map, "face_map": result.face_map}


def repair_lines(result) -> list[str]:
    """The repair's summary: one line per kind of change, or one saying there was none."""
    return describe_changes(result.changes) or ["nothing to repair: the mesh is valid"]


def require_plotting() -> None:
    try:
        require_matplotlib()
    except ImportError as exc:
        raise UserError(str(exc)) from None


# --------------------------------------------------------------------------- solver options


def check_solver_options(given: str, **options) -> None:
    """The library's own check of the solver options (sorpia.solve.check_options),
    before the file is read; its message follows the options as given
    on the command line (`given`, e.g. "--method pia --threads 2")."""
    try:
        check_options(**options)
    except ParameterError as exc:
        raise UserError(f"{given}: {exc}") from None


def threads_for(method: str, threads: int) -> int:
    """--threads applies to the methods that sweep on threads (compare runs the others on one)."""
    return threads if method in THREADED_METHODS else 1


# --------------------------------------------------------------------------- timed solves


def result_fields(res) -> dict:
    """Every field of an InterpolationResult except the control vertices
    (method, omega, iterations, converged, errors, seconds and the per-phase
    timings, spectral estimates...), in the order of InterpolationResult._fields."""
    return {name: getattr(res, name) for name in res._fields if name != "control_vertices"}


def cpu_clock(threads: int) -> str:
    """The clock of the CPU seconds reported for a solve on `threads` threads (Clock)."""
    return "thread" if threads == 1 else "process"


class Clock:
    """Wall (perf_counter) and CPU seconds of a block.

    The CPU clock depends on who does the work. threads == 1: every solve and
    build runs on the calling thread, so time.thread_time() (that thread
    only): time.process_time() would also count other threads of the process
    (a BLAS's, or the core's pool busy with a surface evaluation).
    threads > 1: the sweep's workers do part of the work, so
    time.process_time() (every thread: CPU the run occupies). cpu_clock(threads)
    names the one used."""

    def __init__(self, threads: int = 1):
        self._cpu = time.thread_time if cpu_clock(threads) == "thread" else time.process_time

    def __enter__(self):
        self.cpu0, self.t0 = self._cpu(), time.perf_counter()
        return self

    def __exit__(self, *exc) -> None:
        self.wall = time.perf_counter() - self.t0
        self.cpu = self._cpu() - self.cpu0


def timed(call, *, threads: int, source, scheme: str = "loop"):
    """call() with its wall and CPU seconds (Clock(threads)); the warnings it
    raised are printed (report_warnings). Returns (value, clock). A mesh the
    library refuses is a UserError naming the file `source` and the scheme."""
    try:
        with warnings.catch_warnings(record=True) as caught, Clock(threads) as clock:
            warnings.simplefilter("always")
            value = call()
    except MeshError as exc:
        raise UserError(f"{source}: {SCHEME_LABELS[scheme]} PIA cannot run on this mesh: {exc}") from None
    report_warnings(caught)
    return value, clock


def build_interpolator(vertices, faces, *, boundary, progress, source, scheme="loop", tags=None):
    """sorpia.Interpolator for the mesh, the scheme and the tags: the topology
    and limit operator B, built once for every solve, check and statistic of
    a command; prints its warnings; returns (interpolator, {"wall": s, "cpu": s})."""
    kwargs = scheme_kwargs(scheme, tags or {})
    progress.status("setting up (topology, limit operator)")
    interp, clock = timed(lambda: Interpolator(faces, len(vertices), boundary=boundary, **kwargs), threads=1,
                          source=source, scheme=scheme)
    return interp, {"wall": clock.wall, "cpu": clock.cpu}


def run_solver(interp, vertices, *, phase, method, omega, tol, max_iter, threads, progress, source, scheme="loop"):
    """interp.solve(vertices, **options) with a progress line labelled by the
    method, its phase shown as `phase`; returns (result, wall seconds, CPU seconds)."""
    progress.restart(method_label(method))
    kwargs = dict(method=method, tol=tol, max_iter=max_iter, callback=progress, threads=threads)
    if omega is not None:
        kwargs["omega"] = omega
    progress.status(f"{progress.label}: {phase}")
    res, clock = timed(lambda: interp.solve(vertices, **kwargs), threads=threads, source=source, scheme=scheme)
    return res, clock.wall, clock.cpu


def fit_once(vertices, faces, *, boundary, progress, source, scheme="loop", tags=None, **options):
    """One solve on a fresh Interpolator (fit, render), reported as
    sorpia.interpolate reports it: `seconds` and `timings` include the build.
    Returns (interpolator, result, wall seconds, CPU seconds)."""
    interp, build = build_interpolator(vertices, faces, boundary=boundary, progress=progress, source=source,
                                       scheme=scheme, tags=tags)
    res, wall, cpu = run_solver(interp, vertices, phase="solving", progress=progress, source=source, scheme=scheme,
                                **options)
    res._record_build(res.seconds + build["wall"], interp.build_timings["topology"],
                      interp.build_timings["operator"])
    return interp, res, wall + build["wall"], cpu + build["cpu"]


# --------------------------------------------------------------------------- printing

_warned: set = set()  # texts already printed in this process


def warn_once(text: str) -> None:
    """Print 'sorpia: warning: TEXT' on stderr unless it was printed already
    (several steps of one command meet the same unreferenced vertices)."""
    if text not in _warned:
        _warned.add(text)
        _progress.erase_live_line()  # a warning on a line of its own
        print(f"sorpia: warning: {text}", file=sys.stderr)


def report_warnings(caught) -> None:
    """Print the warnings of a solve; the solver's own 'did not converge' is
    left out: the summary says it, and the exit code."""
    for w in caught:
        if not issubclass(w.category, ConvergenceWarning):
            warn_once(str(w.message))


def fmt_seconds(s: float) -> str:
    return f"{s:.2g}" if s < 0.1 else f"{s:.2f}"


def omega_text(omega) -> str:
    """A result's omega (None, or a finite float: solve maps NaN to None) as printed."""
    return "-" if omega is None else f"{omega:.4f}"


def mesh_line(stats: dict) -> str:
    parts = [f"{stats['vertices']} vertices", f"{stats['faces']} faces"]
    if "boundary_loops" in stats:
        loops = stats["boundary_loops"]
        parts.append("closed" if loops == 0 else f"{loops} boundary loop{'s' if loops > 1 else ''}")
        if stats.get("genus") is not None:
            parts.append(f"genus {stats['genus']}")
        parts.append(f"{stats['extraordinary_vertices']} extraordinary vertices "
                     f"(valence {stats['valence_min']} to {stats['valence_max']})")
    return ", ".join(parts)
