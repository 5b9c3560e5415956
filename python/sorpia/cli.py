"""The ``sorpia`` command (also ``python -m sorpia``).

Subcommands: ``fit`` (control mesh whose Loop limit surface interpolates a
mesh file), ``compare`` (the paper's Table 1 and Figure 7 for one mesh),
``render`` (the paper's Figure 3), ``info`` (mesh statistics, the paper's
Table 2) and ``demo`` (all of it on a generated sample mesh).

Exit codes: 0 success; 1 a solve stopped at --max-iter before reaching --tol
(every output is still written); 2 bad input (a one-line message on stderr, no
traceback); 130 interrupted. The input file is only read. Every output is
written atomically: a temporary file in the same folder, then os.replace.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import math
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from . import __version__
from ._validate import BOUNDARY_RULES, DEFAULT_BOUNDARY
from .plotting import FACE_BUDGET  # plotting imports matplotlib only when drawing
from .solve import THREADED_METHODS  # the methods that sweep on --threads N
from .solve import ConvergenceWarning  # not printed: the summary and the exit code say it

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130

# The paper's names (Table 1) for the methods it compares, and ours for the rest.
METHOD_LABELS = {"pia": "PIA", "wpia": "W-PIA", "hss": "HSS-PIA", "whss": "WHSS-PIA", "gs": "Gauss-Seidel",
                 "sor": "SOR-PIA", "cg": "CG"}
METHODS = tuple(METHOD_LABELS)  # --method choices, and compare's rows in this order
# The columns of the paper's Table 1: iterations to reach E_k/E_0 < 10^-j.
TABLE_TOLERANCES = tuple(10.0 ** -j for j in range(1, 11))
MESH_SUFFIXES = (".obj", ".off", ".ply", ".stl")


class UserError(Exception):
    """Bad input from the command line: reported as one line, exit code 2."""


class PolygonError(UserError):
    """The input file has faces of more than 3 vertices and --triangulate was not given."""


# --------------------------------------------------------------------------- output files

@contextlib.contextmanager
def atomic_output(path):
    """Yield a temporary path in the folder of `path`; on success it replaces
    `path` (os.replace, atomic on one file system), on failure it is removed
    and `path` is left as it was."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent if str(path.parent) else ".")
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path, text: str) -> None:
    with atomic_output(path) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)


def _jsonable(obj):
    """numpy scalars and arrays to Python, NaN and inf to None (JSON has neither)."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(path, data) -> None:
    write_text(path, json.dumps(_jsonable(data), indent=2) + "\n")


def save_figure(fig, path) -> None:
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format="png")


# --------------------------------------------------------------------------- progress

class Progress:
    """Progress of a command: the phase it is in (`status`) and the solve,
    fed by interpolate's callback(k, error).

    On a terminal: one live line on stderr (the phase, then iteration and
    E_k/E_0 redrawn at most 10 times a second), erased at the end. In a pipe
    or a file: a plain line every two seconds of iterating (short runs print
    none), no phases. Disabled: nothing at all. A context manager: the live
    line is erased however the block ends (before an error message).
    """

    def __init__(self, label: str = "", enabled: bool = True, stream=None):
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.tty = enabled and _isatty(self.stream)
        self.interval = 0.1 if self.tty else 2.0
        self.width = 0
        self.restart(label)

    def restart(self, label: str) -> None:
        """A new solve: its label, its clock."""
        self.label = label
        self.start = self.last = time.perf_counter()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _draw(self, text: str) -> None:
        global _live_line
        self.stream.write("\r" + text.ljust(self.width))
        self.width = len(text)
        self.stream.flush()
        _live_line = self

    def status(self, text: str) -> None:
        """Show the phase the command is in (terminal only)."""
        if self.tty:
            self._draw(f"{text} ...")

    def __call__(self, k: int, error: float) -> bool:
        if self.enabled:
            now = time.perf_counter()
            if now - self.last >= self.interval:
                self.last = now
                text = f"{self.label}: iteration {k}, E_k/E_0 = {error:.3e}, {now - self.start:.1f} s"
                if self.tty:
                    self._draw(text)
                else:
                    self.stream.write(text + "\n")
                    self.stream.flush()
        return False  # never ask the solver to stop

    def close(self) -> None:
        """Erase the live line (it is drawn again by the next update)."""
        global _live_line
        if self.tty and self.width:
            self.stream.write("\r" + " " * self.width + "\r")
            self.stream.flush()
            self.width = 0
        if _live_line is self:
            _live_line = None


_live_line: Progress | None = None  # the Progress whose line is on the terminal now


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


# --------------------------------------------------------------------------- checks and helpers

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
    for two outputs, and an output whose folder does not exist; before any
    work is done, so a long fit never ends in 'cannot write'."""
    named = [(opt, p) for opt, p in outputs.items() if p is not None]
    for opt, p in named:
        for src in inputs:
            if _same_file(p, src) and not force:
                raise UserError(f"{opt} {p} is the input file: refusing to overwrite it (pass --force to do so)")
        folder = Path(p).parent
        if not folder.is_dir():
            raise UserError(f"{opt} {p}: folder {folder} does not exist")
        if Path(p).is_dir():
            raise UserError(f"{opt} {p} is a folder, not a file")
    for i, (opt_a, a) in enumerate(named):
        for opt_b, b in named[i + 1:]:
            if _same_file(a, b):
                raise UserError(f"{opt_a} and {opt_b} name the same file {a}")


def check_mesh_suffix(opt: str, path) -> None:
    if path is not None and Path(path).suffix.lower() not in MESH_SUFFIXES:
        raise UserError(f"{opt} {path}: unknown mesh format {Path(path).suffix or '(no suffix)'!r}; "
                        f"use one of {', '.join(MESH_SUFFIXES)}")


def read_input(path, triangulate: bool = False):
    """Read the input mesh; returns (vertices, faces, seconds, polygons split).
    A polygon in the file without --triangulate is a UserError that says to
    pass it."""
    from . import MeshFileError
    from .io import read_mesh_counting

    if not Path(path).exists():
        raise UserError(f"{path}: no such file")
    if Path(path).is_dir():
        raise UserError(f"{path} is a folder, not a mesh file")
    t0 = time.perf_counter()
    try:
        vertices, faces, polygons = read_mesh_counting(path, triangulate=triangulate)
    except MeshFileError as exc:
        if triangulate or not _is_polygon_error(exc):
            raise
        raise PolygonError(f"{_polygon_message(exc)}; pass --triangulate to split each polygon into a fan of "
                        "triangles from its first vertex") from None
    return vertices, faces, time.perf_counter() - t0, polygons


def _is_polygon_error(exc) -> bool:
    # sorpia.read_mesh refuses a face of more than 3 vertices and names the
    # Python remedy (triangulate=True); the command line has --triangulate.
    return "triangulate" in str(exc)


def _polygon_message(exc) -> str:
    return str(exc).split(": sorpia works on triangles")[0].split("; read the file with")[0]


def _omega_arg(text: str):
    """--omega: 'auto', 'young' or a number (its range is checked by interpolate)."""
    low = text.strip().lower()
    if low in ("auto", "young"):
        return low
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected auto, young or a number, got {text!r}") from None


def _methods_arg(text: str):
    names = [m.strip().lower() for m in text.split(",") if m.strip()]
    bad = [m for m in names if m not in METHODS]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"unknown method {', '.join(bad) or '(none)'}: use a comma-separated "
                                         f"list of {','.join(METHODS)}")
    return list(dict.fromkeys(names))


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def _int_arg(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None


def _positive_int(text: str) -> int:
    value = _int_arg(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1, got {text!r}")
    return value


def _level_arg(text: str) -> int:
    value = _int_arg(text)
    if not 0 <= value <= 8:
        raise argparse.ArgumentTypeError(f"expected a level from 0 to 8, got {text!r}")
    return value


def _size_arg(text: str):
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels, e.g. 1200x1000, got {text!r}") from None
    if not (100 <= w <= 10000 and 100 <= h <= 10000):
        raise argparse.ArgumentTypeError(f"width and height must be 100 to 10000 pixels, got {text!r}")
    return w, h


def _result_fields(res) -> dict:
    """Every field of an InterpolationResult except the control vertices
    (method, omega, iterations, converged, errors, seconds and the per-phase
    timings, spectral estimates...), in the order of InterpolationResult._fields."""
    return {name: getattr(res, name) for name in res._fields if name != "control_vertices"}


def cpu_clock(threads: int) -> str:
    """The clock of the CPU seconds reported for a solve on `threads` threads (_Clock)."""
    return "thread" if threads == 1 else "process"


class _Clock:
    """Wall (perf_counter) and CPU seconds of a block.

    The CPU clock depends on who does the work. threads == 1: every solve and
    build runs on the calling thread, so time.thread_time() (that thread
    only). time.process_time() would also count threads that merely spin:
    libgomp's workers busy-wait some tens of ms after a parallel region ends
    (limit_surface's, in fit --surface or demo), which showed as PIA at CPU
    0.0044 s against wall 0.0004 s in the demo: about 4 ms of a spinning
    worker, accounted to the process in scheduler-tick steps. threads > 1: the sweep's workers do part of the work, so
    time.process_time() (every thread, their busy-waiting between sweeps
    included: CPU the run occupies). cpu_clock(threads) names the one used."""

    def __init__(self, threads: int = 1):
        self._cpu = time.thread_time if cpu_clock(threads) == "thread" else time.process_time

    def __enter__(self):
        self.cpu0, self.t0 = self._cpu(), time.perf_counter()
        return self

    def __exit__(self, *exc) -> None:
        self.wall = time.perf_counter() - self.t0
        self.cpu = self._cpu() - self.cpu0


def _timed(call, *, threads: int, source):
    """call() with its wall and CPU seconds (_Clock(threads)); the warnings it
    raised are printed (_report_warnings). Returns (value, clock). A mesh the
    library refuses is a UserError naming the file `source`."""
    from . import MeshError

    try:
        with warnings.catch_warnings(record=True) as caught, _Clock(threads) as clock:
            warnings.simplefilter("always")
            value = call()
    except MeshError as exc:
        raise UserError(f"{source}: Loop PIA cannot run on this mesh: {exc}") from None
    _report_warnings(caught)
    return value, clock


def _run_solver(solve, vertices, *, phase, method, omega, tol, max_iter, threads, progress: Progress, source):
    """solve(vertices, **options) with a progress line labelled by the method,
    its phase shown as `phase`; returns (result, wall seconds, CPU seconds).

    fit and render pass sorpia.interpolate with the faces bound (one solve, so
    no Interpolator kept; interpolate checks the options before building B),
    compare passes the shared Interpolator's solve."""
    progress.restart(METHOD_LABELS[method])
    kwargs = dict(method=method, tol=tol, max_iter=max_iter, callback=progress, threads=threads)
    if omega is not None:
        kwargs["omega"] = omega
    progress.status(f"{progress.label}: {phase}")
    res, clock = _timed(lambda: solve(vertices, **kwargs), threads=threads, source=source)
    return res, clock.wall, clock.cpu


def _fit_once(vertices, faces, *, boundary, **options):
    """sorpia.interpolate through _run_solver (fit, render)."""
    from . import interpolate

    return _run_solver(lambda v, **kw: interpolate(v, faces, boundary=boundary, **kw), vertices,
                       phase="setting up (topology, limit operator)", **options)


def _build_interpolator(vertices, faces, *, boundary, progress: Progress, source):
    """sorpia.Interpolator for the mesh (compare: topology and limit operator
    B built once for every method); prints its warnings; returns
    (interpolator, {"wall": s, "cpu": s})."""
    from . import Interpolator

    progress.status("setting up (topology, limit operator)")
    interp, clock = _timed(lambda: Interpolator(faces, len(vertices), boundary=boundary), threads=1, source=source)
    return interp, {"wall": clock.wall, "cpu": clock.cpu}


def check_threads(threads: int, method: str | None = None) -> None:
    """--threads: 1..sorpia's MAX_THREADS, more than 1 for sor/gs only
    (`method` None: compare, which applies it to sor/gs and runs the rest on
    one thread). Checked before any work; the solver checks again."""
    from .solve import MAX_THREADS

    if not 1 <= threads <= MAX_THREADS:
        raise UserError(f"--threads {threads}: expected a whole number from 1 to {MAX_THREADS}")
    if threads > 1 and method is not None and method not in THREADED_METHODS:
        raise UserError(f"--threads applies to --method sor or gs only (got --method {method}); "
                        "the other methods run on one thread")


_warned: set = set()  # texts already printed in this process


def warn_once(text: str) -> None:
    """Print 'sorpia: warning: TEXT' on stderr unless it was printed already
    (several steps of one command meet the same unreferenced vertices)."""
    if text not in _warned:
        _warned.add(text)
        if _live_line is not None:
            _live_line.close()  # a warning on a line of its own
        print(f"sorpia: warning: {text}", file=sys.stderr)


def _report_warnings(caught) -> None:
    """Print the warnings of a solve; the solver's own 'did not converge' is
    left out: the summary says it, and the exit code."""
    for w in caught:
        if not issubclass(w.category, ConvergenceWarning):
            warn_once(str(w.message))


def _fmt_seconds(s: float) -> str:
    return f"{s:.2g}" if s < 0.1 else f"{s:.2f}"


def _omega_text(omega) -> str:
    """A result's omega (None, or a finite float: solve maps NaN to None) as printed."""
    return "-" if omega is None else f"{omega:.4f}"


# --------------------------------------------------------------------------- fit

def run_fit(input_path, output, *, method="sor", omega="auto", tol=1e-10, max_iter=1000,
            boundary=DEFAULT_BOUNDARY, surface=None, level=3, report=None, quiet=False, force=False,
            triangulate=False, binary=False, threads=1, out=None) -> tuple[int, dict]:
    """`sorpia fit`: returns (exit code, report dict)."""
    from . import limit_points, write_mesh
    from .meshinfo import mesh_info

    out = out if out is not None else sys.stdout
    check_mesh_suffix("-o", output)
    check_mesh_suffix("--surface", surface)
    check_paths([input_path], {"-o": output, "--surface": surface, "--report": report}, force)
    if omega != "auto" and method != "sor":
        raise UserError(f"--omega applies to --method sor only (got --method {method})")
    check_threads(threads, method)
    if binary and not any(Path(p).suffix.lower() in (".ply", ".stl") for p in (output, surface) if p):
        raise UserError("--binary applies to .ply and .stl outputs only (OBJ and OFF are text formats)")

    timings: dict[str, float] = {}
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        V0, F, timings["read"], _ = read_input(input_path, triangulate)
        if surface is not None:
            _check_surface_fits(len(V0), len(F), level)
        progress.status("mesh statistics")
        t0 = time.perf_counter()
        # interpolate validates the mesh (MeshError: exit code 2) right after this.
        stats = mesh_info(V0, F, boundary=boundary, list_extraordinary=False, verdict=False)
        timings["statistics"] = time.perf_counter() - t0

        res, timings["fit"], cpu = _fit_once(
            V0, F, method=method, omega=omega if method == "sor" else None, tol=tol, max_iter=max_iter,
            boundary=boundary, threads=threads, progress=progress, source=input_path)
        ctrl = np.asarray(res.control_vertices)

        progress.status(f"writing {output}")
        t0 = time.perf_counter()
        write_mesh(output, ctrl, F, binary=_binary_for(output, binary))
        timings["write"] = time.perf_counter() - t0
        surface_stats, limit = None, None
        if surface is not None:
            from . import limit_surface

            progress.status(f"limit surface, level {level}")
            t0 = time.perf_counter()
            Vs, Fs = limit_surface(ctrl, F, level=level, boundary=boundary)
            write_mesh(surface, Vs, Fs, binary=_binary_for(surface, binary))
            timings["surface"] = time.perf_counter() - t0
            surface_stats = {"path": str(surface), "level": level, "vertices": len(Vs), "faces": len(Fs)}
            limit = Vs[: len(V0)]  # the surface's first n vertices are B V exactly (limit_surface's contract)
        # An independent check of what was written: the limit positions of the
        # control mesh against the given vertices (OpenSubdiv, not the solver).
        progress.status("checking B V = V0")
        t0 = time.perf_counter()
        if limit is None:
            limit = limit_points(ctrl, F, boundary=boundary)
        residual = np.linalg.norm(limit - V0, axis=1)
        timings["check"] = time.perf_counter() - t0

    fields = _result_fields(res)
    # The solver's own phases (topology, operator, estimate, solve), inside "fit".
    fit_phases = {f"fit.{k}": float(v) for k, v in res.timings.items()}
    errors = np.asarray(res.errors, dtype=float)
    diag = stats.get("diagonal") or 1.0
    data = {
        "sorpia_version": __version__,
        "command": "fit",
        "input": str(input_path),
        "triangulated": triangulate,
        "output": str(output),
        "surface": surface_stats,
        "report": None if report is None else str(report),
        "mesh": stats,
        "method": method,
        "omega_rule": omega if method == "sor" else None,
        "omega": res.omega,
        "tol": tol,
        "max_iter": max_iter,
        "boundary": boundary,
        "threads": threads,
        "iterations": int(res.iterations),
        "converged": bool(res.converged),
        "final_error": float(errors[-1]),
        "errors": errors,
        "max_residual": float(residual.max()),
        "max_residual_relative": float(residual.max() / diag),
        "cpu_seconds": cpu,
        "cpu_clock": cpu_clock(threads),
        "timings": {**timings, **fit_phases},
        "result": {k: v for k, v in fields.items() if k not in ("errors", "timings")},
    }
    if report is not None:
        write_json(report, data)
    if not quiet:
        print(_fit_summary(data), file=out)
    return (EXIT_OK if res.converged else EXIT_NOT_CONVERGED), data


def _check_surface_fits(n_vertices: int, n_faces: int, level: int) -> None:
    """Refuse --level before the solve when the tessellation would not fit in
    memory (limit_surface would refuse it only after the solve)."""
    from . import _core

    need, avail = _core.tessellation_bytes(n_vertices, n_faces, level), _core.available_memory_bytes()
    if avail and need > avail:  # 0: not known here; limit_surface decides
        raise UserError(f"--surface at --level {level} needs about {need / 2**30:.1f} GiB "
                        f"({n_faces * 4 ** level} triangles) but {avail / 2**30:.1f} GiB of memory is available: "
                        "use a lower --level")


def _binary_for(path, binary: bool) -> bool:
    """--binary for the formats that have a binary form (PLY, STL)."""
    return binary and Path(path).suffix.lower() in (".ply", ".stl")


def _mesh_line(stats: dict) -> str:
    parts = [f"{stats['vertices']} vertices", f"{stats['faces']} faces"]
    if "boundary_loops" in stats:
        loops = stats["boundary_loops"]
        parts.append("closed" if loops == 0 else f"{loops} boundary loop{'s' if loops > 1 else ''}")
        if stats.get("genus") is not None:
            parts.append(f"genus {stats['genus']}")
        parts.append(f"{stats['extraordinary_vertices']} extraordinary vertices "
                     f"(valence {stats['valence_min']} to {stats['valence_max']})")
    return ", ".join(parts)


def _fit_summary(d: dict) -> str:
    label = METHOD_LABELS[d["method"]]
    omega = d["omega"]
    if d["method"] == "sor" and omega is not None:
        label += f", omega {omega:.4f} ({d['omega_rule']})"
    elif d["method"] == "gs":
        label += ", omega 1"
    if d["threads"] > 1:
        label += f", {d['threads']} threads"
    state = (f"converged in {d['iterations']} iterations: E_k/E_0 = {d['final_error']:.3g} " + (
             f"< tol {d['tol']:g}" if d["final_error"] < d["tol"] else
             f"(tol {d['tol']:g} is below what float64 reaches: E_k stopped at rounding level)")
             if d["converged"] else
             f"NOT converged: stopped after {d['iterations']} iterations at E_k/E_0 = {d['final_error']:.3g} "
             f"(tol {d['tol']:g}); outputs written anyway, exit code 1")
    t = d["timings"]
    inner = ", ".join(f"{k[4:]} {_fmt_seconds(v)}" for k, v in t.items() if k.startswith("fit."))
    phases = ", ".join(f"{k} {_fmt_seconds(v)}" + (f" ({inner})" if k == "fit" and inner else "")
                       for k, v in t.items() if not k.startswith("fit."))
    written = [d["output"]] + ([d["surface"]["path"]] if d["surface"] else []) + (
        [d["report"]] if d["report"] else [])
    lines = [
        f"sorpia fit: {d['input']} -> {d['output']}",
        f"  mesh        {_mesh_line(d['mesh'])}",
        f"  method      {label}",
        f"  result      {state}",
        f"  check       max |B V - V0| = {d['max_residual']:.3g} "
        f"({d['max_residual_relative']:.3g} of the bounding-box diagonal)",
        f"  seconds     {phases}",
        f"  wrote       {', '.join(written)}",
    ]
    if d["surface"]:
        s = d["surface"]
        lines.insert(-1, f"  surface     level {s['level']}: {s['vertices']} vertices, {s['faces']} faces")
    return "\n".join(lines)


# --------------------------------------------------------------------------- compare

def iterations_to_reach(errors, tolerances=TABLE_TOLERANCES) -> list:
    """For each tol: the first k with errors[k] < tol (None if never)."""
    errors = np.asarray(errors, dtype=float)
    out = []
    for tol in tolerances:
        hit = np.flatnonzero(errors < tol)
        out.append(int(hit[0]) if len(hit) else None)
    return out


def run_compare(input_path, *, methods=METHODS, tol=1e-10, max_iter=1000, boundary=DEFAULT_BOUNDARY,
                table=None, csv_path=None, plot=None, json_path=None, quiet=False, force=False,
                triangulate=False, threads=1, out=None) -> tuple[int, dict]:
    """`sorpia compare`: every method to the same tolerance, on one
    sorpia.Interpolator (topology, limit operator and spectral estimates built
    once and shared); returns (exit code, data). `threads` applies to sor/gs."""
    from .meshinfo import mesh_info

    out = out if out is not None else sys.stdout
    check_threads(threads)
    check_paths([input_path], {"--table": table, "--csv": csv_path, "--plot": plot, "--json": json_path}, force)
    if plot is not None:
        _require_plotting()
    rows = []
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        V0, F, read_seconds, _ = read_input(input_path, triangulate)
        progress.status("mesh statistics")
        stats = mesh_info(V0, F, boundary=boundary, list_extraordinary=False, verdict=False)  # Interpolator validates
        interp, build = _build_interpolator(V0, F, boundary=boundary, progress=progress, source=input_path)
        for method in methods:
            n_threads = threads if method in THREADED_METHODS else 1
            res, wall, cpu = _run_solver(interp.solve, V0, phase="solving", method=method, omega=None, tol=tol,
                                         max_iter=max_iter, threads=n_threads, progress=progress, source=input_path)
            fields = _result_fields(res)
            rows.append({
                "method": method,
                "label": METHOD_LABELS[method],
                "omega": res.omega,  # None but for sor and gs
                "iterations": int(res.iterations),
                "converged": bool(res.converged),
                "reached": iterations_to_reach(res.errors),
                "threads": n_threads,
                "cpu_seconds": cpu,
                "cpu_clock": cpu_clock(n_threads),
                "wall_seconds": wall,
                "errors": np.asarray(res.errors, dtype=float),
                "result": {k: v for k, v in fields.items() if k != "errors"},
            })
    data = {
        "sorpia_version": __version__,
        "command": "compare",
        "input": str(input_path),
        "mesh": stats,
        "tol": tol,
        "max_iter": max_iter,
        "boundary": boundary,
        "tolerances": TABLE_TOLERANCES,
        "threads": threads,
        "read_seconds": read_seconds,
        # Topology and limit operator B, built once and shared by every method;
        # not in any row's seconds.
        "setup": {"wall_seconds": build["wall"], "cpu_seconds": build["cpu"], **interp.build_timings},
        "methods": rows,
    }
    markdown = compare_markdown(data, Path(input_path).name)
    if table is not None:
        write_text(table, markdown + "\n")
    if csv_path is not None:
        write_text(csv_path, compare_csv(data))
    if json_path is not None:
        write_json(json_path, data)
    if plot is not None:
        from .plotting import convergence_figure

        curves = [(_curve_label(r), r["errors"]) for r in rows]
        save_figure(convergence_figure(curves, tol=tol, title=f"Convergence on {Path(input_path).name} "
                                       f"(paper Figure 7)"), plot)
    if not quiet:
        print(f"sorpia compare: {input_path}: {_mesh_line(stats)}", file=out)
        print(markdown, file=out)
        print(_setup_line(data), file=out)
        failed = [r["label"] for r in rows if not r["converged"]]
        if failed:
            print(f"NOT converged to tol {tol:g} within {max_iter} iterations: {', '.join(failed)} (exit code 1)",
                  file=out)
        written = [p for p in (table, csv_path, plot, json_path) if p is not None]
        if written:
            print(f"wrote {', '.join(map(str, written))}", file=out)
    ok = all(r["converged"] for r in rows)
    return (EXIT_OK if ok else EXIT_NOT_CONVERGED), data


def _curve_label(row) -> str:
    return row["label"] + (f" (omega {row['omega']:.4f})" if row["method"] == "sor" and row["omega"] else "")


def _tol_header(tol: float) -> str:
    return f"1e-{round(-math.log10(tol))}"


SOLVE_SECONDS_NOTE = (
    "solve seconds: each method's own Interpolator.solve call, to --tol: the spectral estimates it is the first "
    "to need (kept and shared: WHSS-PIA reuses HSS-PIA's) and its iterations; CPU of the calling thread "
    "(of the whole process for sor/gs with --threads above 1). Not included: reading the file and the "
    "topology and limit operator, built once for every method")


def _setup_line(data: dict) -> str:
    s = data["setup"]
    return (f"{SOLVE_SECONDS_NOTE}: {s['wall_seconds']:.4f} s wall, {s['cpu_seconds']:.4f} s CPU "
            f"(topology {s['topology']:.4f} s, operator {s['operator']:.4f} s).")


def compare_markdown(data: dict, name: str) -> str:
    """The paper's Table 1 layout for one mesh: method, omega, iterations to
    reach E_k/E_0 < 1e-1 ... 1e-10 ('-' = not reached), CPU and wall seconds
    of the method's own solve (SOLVE_SECONDS_NOTE)."""
    head = ["mesh", "method", "omega"] + [_tol_header(t) for t in data["tolerances"]] + ["solve CPU (s)",
                                                                                        "solve wall (s)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join(["---"] * 3 + ["---:"] * (len(head) - 3)) + "|"]
    for j, r in enumerate(data["methods"]):
        cells = [name if j == 0 else "", r["label"], _omega_text(r["omega"])]
        cells += ["-" if k is None else str(k) for k in r["reached"]]
        cells += [f"{r['cpu_seconds']:.4f}", f"{r['wall_seconds']:.4f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def compare_csv(data: dict) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["method", "omega", "iterations", "converged"]
                    + [f"iterations_to_{_tol_header(t)}" for t in data["tolerances"]]
                    + ["cpu_seconds", "wall_seconds"])
    for r in data["methods"]:
        writer.writerow([r["method"], "" if r["omega"] is None else repr(float(r["omega"])), r["iterations"],
                         r["converged"]] + ["" if k is None else k for k in r["reached"]]
                        + [f"{r['cpu_seconds']:.6f}", f"{r['wall_seconds']:.6f}"])
    return buf.getvalue()


# --------------------------------------------------------------------------- render

def _require_plotting() -> None:
    from .plotting import require_matplotlib

    try:
        require_matplotlib()
    except ImportError as exc:
        raise UserError(str(exc)) from None


def run_render(input_path, output, *, level=3, tol=1e-10, max_iter=1000, boundary=DEFAULT_BOUNDARY,
               size=(1200, 1000), elev=30.0, azim=-60.0, face_budget=FACE_BUDGET, quiet=False, force=False,
               triangulate=False, up="z", threads=1, out=None) -> tuple[int, dict]:
    """`sorpia render`: the paper's Figure 3 for a mesh file."""
    from . import LoopSurface
    from .plotting import interpolation_figure, level_for_budget

    out = out if out is not None else sys.stdout
    if Path(output).suffix.lower() != ".png":
        raise UserError(f"-o {output}: render writes a PNG image, give a file name ending in .png")
    check_paths([input_path], {"-o": output}, force)
    check_threads(threads, "sor")
    _require_plotting()
    budget = face_budget
    timings = {}
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        V0, F, timings["read"], _ = read_input(input_path, triangulate)
        res, timings["fit"], _ = _fit_once(V0, F, method="sor", omega="auto", tol=tol, max_iter=max_iter,
                                           boundary=boundary, threads=threads, progress=progress, source=input_path)
        ctrl = np.asarray(res.control_vertices)
        drawn_level = level_for_budget(len(F), level, budget)
        progress.status(f"limit surfaces, level {drawn_level}")
        t0 = time.perf_counter()
        # One LoopSurface for both: the topology is built once, only positions change.
        surface = LoopSurface(V0, F, boundary=boundary)
        given = surface.tessellate(drawn_level)
        surface.set_vertices(ctrl)
        fitted = surface.tessellate(drawn_level)
        timings["surface"] = time.perf_counter() - t0
        progress.status(f"drawing {output}")
        t0 = time.perf_counter()
        fig = interpolation_figure(V0, F, given, ctrl, fitted, size=size, elev=elev, azim=azim, face_budget=budget,
                                   title=f"{Path(input_path).name}: Loop limit surface and SOR-PIA (paper Figure 3)",
                                   iterations=int(res.iterations), level=drawn_level, up=up)
        save_figure(fig, output)
        timings["draw"] = time.perf_counter() - t0
    data = {"output": str(output), "level": drawn_level, "threads": threads, "iterations": int(res.iterations),
            "converged": bool(res.converged), "omega": res.omega, "timings": timings}
    if not quiet:
        lvl = f"level {drawn_level}" + (f" (asked {level}; face budget {budget})" if drawn_level < level else "")
        state = "" if res.converged else f"; NOT converged to tol {tol:g} (exit code 1)"
        print(f"sorpia render: {input_path} -> {output} ({size[0]}x{size[1]} px, limit surfaces at {lvl}; "
              f"SOR-PIA omega {_omega_text(res.omega)}, {res.iterations} iterations{state})", file=out)
        print("  seconds     " + ", ".join(f"{k} {_fmt_seconds(v)}" for k, v in timings.items()), file=out)
    return (EXIT_OK if res.converged else EXIT_NOT_CONVERGED), data


# --------------------------------------------------------------------------- info

def run_info(input_path, *, as_json=False, boundary=DEFAULT_BOUNDARY, triangulate=False,
             out=None) -> tuple[int, dict]:
    """`sorpia info`: mesh statistics and whether Loop PIA can run (exit 0 either way).

    A file with polygons is described as its fan triangulation, with the
    verdict that Loop PIA cannot run on it as it is (--triangulate)."""
    from .meshinfo import format_info, mesh_info

    out = out if out is not None else sys.stdout
    # One read, polygons split whether or not --triangulate was given (the
    # statistics are of the fan triangulation either way); the count says
    # whether the verdict must send the user to --triangulate.
    V0, F, _, n_polygons = read_input(input_path, triangulate=True)
    polygons = n_polygons > 0 and not triangulate
    info = mesh_info(V0, F, boundary=boundary)
    info["triangulated"] = bool(triangulate or polygons)
    if polygons and info["loop_pia"]["can_run"]:
        info["loop_pia"] = {"can_run": False, "notes": [],
                            "reason": "the file has faces of more than 3 vertices (the counts are of their fan "
                            "triangulation); pass --triangulate to fit, compare or render to split them"}
    if as_json:
        print(json.dumps(_jsonable({"input": str(input_path), **info}), indent=2), file=out)
    else:
        print(format_info(info, str(input_path)), file=out)
    return EXIT_OK, info


# --------------------------------------------------------------------------- demo

def sample_mesh():
    """The demo's mesh: a closed genus-1 mesh of 400 vertices with random edge
    flips (sorpia.shapes.irregular: valences 3 to 12, most vertices
    extraordinary), its tube made wavy so that the Loop surface visibly shrinks
    away from the vertices. Returns (vertices (n, 3) float64, faces (m, 3) int32)."""
    from . import shapes

    V, F = shapes.irregular(400, seed=3)
    V = np.array(V, dtype=float)
    # A bump in the tube radius, 5 waves around the ring: the Loop surface
    # shrinks most at the crests, where the curvature is largest.
    angle = np.arctan2(V[:, 1], V[:, 0])
    ring = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(len(V))])
    offset = V - ring  # from the tube's centre circle (major radius 1)
    V = ring + offset * (1.0 + 0.45 * np.sin(5 * angle))[:, None]
    return V, F


def _new_demo_folder() -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    for k in range(100):
        folder = Path(f"sorpia-demo-{stamp}" + (f"-{k}" if k else ""))  # relative: short paths in the summary
        try:
            folder.mkdir()
            return folder
        except FileExistsError:
            continue
    raise UserError("could not create a new sorpia-demo-* folder in the working directory")


def run_demo(out_dir=None, *, quiet=False, out=None) -> int:
    """`sorpia demo`: fit, compare and render on the built-in sample mesh."""
    from . import write_mesh

    out = out if out is not None else sys.stdout
    t_start = time.perf_counter()
    if out_dir is None:
        folder = _new_demo_folder()
    else:
        folder = Path(out_dir)
        if folder.exists() and not folder.is_dir():
            raise UserError(f"--out {folder} is a file, not a folder")
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UserError(f"--out {folder}: cannot create the folder: {exc.strerror}") from None
    try:
        plots = True
        _require_plotting()
    except UserError as exc:
        plots = False
        print(f"sorpia demo: no figures: {exc}", file=out)
    paths = {
        "sample mesh": folder / "sample.obj",
        "control mesh": folder / "control.obj",
        "limit surface of the control mesh": folder / "surface.obj",
        "fit report": folder / "fit-report.json",
        "Table 1 (Markdown)": folder / "table.md",
        "Table 1 (CSV)": folder / "table.csv",
        "comparison (JSON)": folder / "compare.json",
    }
    if plots:
        paths["Figure 7 (convergence)"] = folder / "convergence.png"
        paths["Figure 3 (interpolation)"] = folder / "figure3.png"
    V, F = sample_mesh()
    write_mesh(paths["sample mesh"], V, F)
    sample = paths["sample mesh"]
    say = (lambda *a: None) if quiet else (lambda *a: print(*a, file=out))
    say(f"sorpia {__version__} demo: sample mesh {sample} (a wavy torus with random edge flips)\n")
    codes = []
    code, _ = run_fit(sample, paths["control mesh"], surface=paths["limit surface of the control mesh"],
                      level=3, report=paths["fit report"], quiet=quiet, out=out)
    codes.append(code)
    say("")
    code, _ = run_compare(sample, table=paths["Table 1 (Markdown)"], csv_path=paths["Table 1 (CSV)"],
                          json_path=paths["comparison (JSON)"], plot=paths.get("Figure 7 (convergence)"),
                          quiet=quiet, out=out)
    codes.append(code)
    if plots:
        say("")
        code, _ = run_render(sample, paths["Figure 3 (interpolation)"], quiet=quiet, out=out)
        codes.append(code)
    width = max(len(k) for k in paths)
    say(f"\nsorpia demo: done in {time.perf_counter() - t_start:.1f} s; files in {folder}:")
    for what, p in paths.items():
        say(f"  {what:<{width}}  {p}")
    say(f"next: sorpia info {sample}   |   sorpia fit --help")
    return max(codes)


# --------------------------------------------------------------------------- parser

class _Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """The default shown after every option that has one (not after flags
    and optional outputs, whose default is simply 'off')."""

    def _get_help_string(self, action):
        if action.default is None or action.default is False:
            return action.help
        return super()._get_help_string(action)


EXIT_HELP = ("exit codes: 0 done; 1 a solve stopped at --max-iter before reaching --tol (all outputs still "
             "written); 2 bad input or options (one line on stderr); 130 interrupted.")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sorpia",
        description="Interpolating Loop subdivision surfaces: move the control vertices of a triangle mesh so "
        "that its Loop limit surface passes through the given vertices (SOR-PIA and the PIA family).",
        epilog=EXIT_HELP + " Run 'sorpia COMMAND --help' for the options of a command.",
        formatter_class=_Formatter,
    )
    parser.add_argument("--version", action="version", version=f"sorpia {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def command(name, help_text, description, input_arg=True):
        p = sub.add_parser(name, help=help_text, description=description, epilog=EXIT_HELP,
                           formatter_class=_Formatter)
        if input_arg:
            p.add_argument("input", metavar="IN", help="input triangle mesh (.obj, .off, .ply, .stl); only read")
        return p

    def triangulate_flag(p):
        p.add_argument("--triangulate", action="store_true",
                       help="split faces of more than 3 vertices into fans of triangles from their first vertex "
                       "(without it such a file is refused)")

    def quiet_flag(p):
        p.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors and warnings")

    def output_flags(p):
        quiet_flag(p)
        p.add_argument("--force", action="store_true", help="allow an output to overwrite the input file")

    def solver_options(p, with_method=True):
        if with_method:
            p.add_argument("--method", choices=METHODS, default="sor",
                           help="iteration: sor = SOR-PIA (paper eq. 18), gs = Gauss-Seidel, pia = PIA (eq. 9), "
                           "wpia = weighted PIA, hss/whss = (weighted) Hermitian/skew-Hermitian splitting, "
                           "cg = conjugate gradients")
        p.add_argument("--tol", type=_positive_float, default=1e-10,
                       help="stop when E_k/E_0 < TOL, E_k = max_i |v_i^0 - (B V_k)_i| (paper section 5)")
        p.add_argument("--max-iter", type=_positive_int, default=1000, metavar="N",
                       help="stop after N iterations (exit code 1 if TOL was not reached)")
        p.add_argument("--boundary", choices=BOUNDARY_RULES, default=DEFAULT_BOUNDARY,
                       help="boundary rule of the limit surface (OpenSubdiv VTX_BOUNDARY_EDGE_AND_CORNER keeps "
                       "one-face corners; EDGE_ONLY smooths them)")

    def threads_option(p, which):
        p.add_argument("--threads", type=_int_arg, default=1, metavar="N",
                       help=f"threads sweeping at once, {which}: vertex index ranges in parallel, then the "
                       "vertices they share (iterations may differ by a few percent from one thread); more "
                       "than the free cores only slows down")

    fit = command("fit", "fit a control mesh whose Loop limit surface interpolates a mesh",
                  "Read a triangle mesh, solve B V = V0 for control vertices V whose Loop limit surface passes "
                  "through the given vertices V0, write the control mesh (same faces, same vertex order) and, if "
                  "asked, the tessellated limit surface and a JSON report. Prints a short summary; long runs "
                  "show progress on stderr.")
    fit.add_argument("-o", "--output", metavar="OUT", required=True,
                     help="control mesh to write (.obj, .off, .ply or .stl; .stl stores float32 only)")
    solver_options(fit)
    fit.add_argument("--omega", type=_omega_arg, default="auto",
                     help="relaxation of --method sor: auto (sorpia's measured rule), young (paper Remark 1, "
                     "from the spectral radius of the Jacobi matrix) or a number in (0, 2)")
    fit.add_argument("--surface", metavar="SURF",
                     help="also write the limit surface of the control mesh, refined --level times (a triangle "
                     "mesh with every vertex at its exact limit position)")
    fit.add_argument("--level", type=_level_arg, default=3, metavar="L",
                     help="refinement level of --surface: 4^L triangles per input triangle")
    fit.add_argument("--report", metavar="REPORT.json",
                     help="write a JSON report: mesh statistics, method, omega, E_k/E_0 per iteration, seconds "
                     "per phase (read, statistics, fit, write, check, surface)")
    threads_option(fit, "--method sor or gs only (refused with other methods, which run on one thread)")
    fit.add_argument("--binary", action="store_true", help="write .ply and .stl outputs in binary (faster, "
                     "smaller; PLY keeps float64 either way)")
    triangulate_flag(fit)
    output_flags(fit)
    fit.set_defaults(func=lambda a: run_fit(
        a.input, a.output, method=a.method, omega=a.omega, tol=a.tol, max_iter=a.max_iter, boundary=a.boundary,
        surface=a.surface, level=a.level, report=a.report, quiet=a.quiet, force=a.force, triangulate=a.triangulate,
        binary=a.binary, threads=a.threads)[0])

    comp = command("compare", "run several methods to one tolerance: the paper's Table 1 and Figure 7",
                   "Run each method on the mesh to the same tolerance and print the paper's Table 1 layout for "
                   "it: omega, iterations to reach E_k/E_0 < 1e-1 ... 1e-10 ('-' = not reached), CPU and wall "
                   "seconds of each method's own solve (the topology and limit operator are built once for all "
                   "methods, their seconds printed below the table). Optionally write the table (Markdown, CSV), every figure (JSON) and "
                   "the convergence plot (Figure 7: log10(E_k/E_0) against k, one line per method).")
    comp.add_argument("--methods", type=_methods_arg, default=",".join(METHODS), metavar="LIST",
                      help=f"comma-separated methods, from {','.join(METHODS)} (sor with omega auto)")
    solver_options(comp, with_method=False)
    comp.add_argument("--table", metavar="T.md", help="write the table as Markdown")
    comp.add_argument("--csv", metavar="T.csv", help="write the table as CSV")
    comp.add_argument("--plot", metavar="P.png", help="write the convergence plot (paper Figure 7) as PNG")
    comp.add_argument("--json", metavar="J.json", help="write every figure (E_k/E_0 per iteration, timings) as JSON")
    threads_option(comp, "applied to sor and gs only (the other methods always run on one thread)")
    triangulate_flag(comp)
    output_flags(comp)
    comp.set_defaults(func=lambda a: run_compare(
        a.input, methods=a.methods, tol=a.tol, max_iter=a.max_iter, boundary=a.boundary, table=a.table,
        csv_path=a.csv, plot=a.plot, json_path=a.json, quiet=a.quiet, force=a.force, triangulate=a.triangulate,
        threads=a.threads)[0])

    ren = command("render", "draw the paper's Figure 3 for a mesh (PNG)",
                  "Fit the mesh with SOR-PIA and draw four shaded panels, the same camera in each: (a) the given "
                  "mesh, (b) its Loop limit surface (it shrinks away from the given vertices, red), (c) the "
                  "control mesh found by SOR-PIA, given vertices red and control vertices blue, (d) the limit "
                  "surface of the control mesh through the red points. Big meshes are drawn at a lower level "
                  "or with part of their faces (--face-budget) so that drawing takes seconds.")
    ren.add_argument("-o", "--output", metavar="FIG.png", required=True, help="PNG image to write")
    ren.add_argument("--level", type=_level_arg, default=3, metavar="L",
                     help="refinement level of the limit surfaces drawn (lowered to fit --face-budget)")
    solver_options(ren, with_method=False)
    ren.add_argument("--size", type=_size_arg, default="1200x1000", metavar="WxH", help="image size in pixels")
    ren.add_argument("--elev", type=float, default=30.0, help="camera elevation in degrees")
    ren.add_argument("--azim", type=float, default=-60.0, help="camera azimuth in degrees")
    ren.add_argument("--up", choices=("x", "y", "z"), default="z",
                     help="the axis drawn vertical (many mesh files, e.g. the Stanford bunny, have y up)")
    ren.add_argument("--face-budget", type=_positive_int, default=FACE_BUDGET, metavar="N",
                     help="most triangles drawn per panel")
    threads_option(ren, "in the SOR-PIA fit")
    triangulate_flag(ren)
    output_flags(ren)
    ren.set_defaults(func=lambda a: run_render(
        a.input, a.output, level=a.level, tol=a.tol, max_iter=a.max_iter, boundary=a.boundary, size=a.size,
        elev=a.elev, azim=a.azim, face_budget=a.face_budget, quiet=a.quiet, force=a.force,
        triangulate=a.triangulate, up=a.up, threads=a.threads)[0])

    inf = command("info", "mesh statistics (the paper's Table 2) and whether Loop PIA can run on it",
                  "Print vertices, faces, edges, boundary loops, Euler characteristic, genus, components, "
                  "unreferenced vertices, the valence histogram and the extraordinary vertices (valence other "
                  "than 6 inside, 4 on the boundary; the paper's Table 2), and whether Loop PIA can run on the "
                  "mesh and if not why. Exit code 0 whenever the file can be read.")
    inf.add_argument("--json", action="store_true", help="print JSON (every extraordinary vertex listed) instead")
    inf.add_argument("--boundary", choices=BOUNDARY_RULES, default=DEFAULT_BOUNDARY,
                     help="boundary rule the verdict refers to")
    triangulate_flag(inf)
    inf.set_defaults(func=lambda a: run_info(a.input, as_json=a.json, boundary=a.boundary,
                                             triangulate=a.triangulate)[0])

    demo = command("demo", "fit, compare and render on a built-in sample mesh",
                   "Generate a small sample mesh (a wavy torus with random edge flips: valences 3 to 12, visible "
                   "shrinkage), then run fit (control mesh, limit surface, report), compare (Table 1 as Markdown "
                   "and CSV, Figure 7) and render (Figure 3) on it, writing every file into one folder, and "
                   "print where they are. Takes a few seconds.", input_arg=False)
    demo.add_argument("--out", metavar="DIR", default=None,
                      help="folder for the files (created if needed; default: a new folder "
                      "sorpia-demo-YYYYMMDD-HHMMSS in the working directory)")
    quiet_flag(demo)
    demo.set_defaults(func=lambda a: run_demo(a.out, quiet=a.quiet))
    return parser


def _error_text(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.filename}: {exc.strerror}" if exc.filename else exc.strerror
    return str(exc) or type(exc).__name__


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `sorpia` script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)  # exits 2 with a usage line on a bad option
    if args.command is None:
        parser.print_help()
        return EXIT_OK

    def show(message, category, filename, lineno, file=None, line=None):
        warn_once(str(message))

    old_show = warnings.showwarning
    warnings.showwarning = show
    try:
        return args.func(args)
    except UserError as exc:
        print(f"sorpia: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        # `sorpia info mesh.obj | head`: the reader left; not an error of ours.
        with contextlib.suppress(OSError):
            sys.stdout = open(os.devnull, "w")
        return EXIT_OK
    except (ValueError, TypeError, OSError, ImportError) as exc:
        # sorpia.MeshError, ParameterError and MeshFileError are ValueErrors.
        print(f"sorpia: error: {_error_text(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("sorpia: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        warnings.showwarning = old_show


if __name__ == "__main__":
    sys.exit(main())
