"""Speed of sorpia's mesh files and limit surface, each phase timed on its own.

Files: write and read of a generated mesh (default sorpia.shapes.irregular
with 1M vertices, 2M faces) in every format sorpia writes; median of
--repeat runs; files go to --dir (default: a temporary folder on the same
disk as this repository's build/, so page-cache effects are those of a real
disk, and fsync is included in the write times).

Surface, for each scheme: LimitSurface build, limit_surface at levels
1..--max-level (first call builds the refined topology, second call reuses
it, as after set_vertices), and evaluate_limit at 1M random points with
derivatives, on sorpia.shapes.irregular (Loop) and sorpia.shapes.quad_irregular
(Catmull-Clark) of --surface-vertices vertices (default 100k).

Prints Markdown tables and writes them into docs/benchmarks/io-speed.md
(unless --no-page); --json writes the figures.

Reads side by side (--baseline DIR): the same files read by this sorpia and
by another build of it (DIR holds an installed ``sorpia`` package, e.g. a copy
of site-packages/sorpia taken before a change), each read in a fresh process,
the two alternated --repeat times, medians and their ratio; written into
docs/benchmarks/io-read-compare.md.

    python bench/io_speed.py [--vertices 1000000] [--surface-vertices 100000] [--repeat 3] [--json out.json]
    python bench/io_speed.py --baseline /tmp/sorpia-before [--vertices 1000000] [--repeat 7]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import tempfile
import sys
import time

import numpy as np

import sorpia

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _report import write_page  # noqa: E402

FORMATS = [("ply", True), ("ply", False), ("obj", False), ("off", False), ("stl", True), ("stl", False)]


def timed(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def reset_peak_rss():
    """Linux: writing 5 to /proc/self/clear_refs resets the peak RSS (VmHWM)."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
    except OSError:
        pass


def _status_mb(field: str):
    """A kB field of /proc/self/status (Linux) in MB; None where it cannot be read."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return None


def peak_rss_mb():
    peak = _status_mb("VmHWM")
    return peak if peak is not None else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def current_rss_mb():
    return _status_mb("VmRSS") or 0.0


def bench_files(n_vertices, repeat, folder):
    v, f = sorpia.shapes.irregular(n_vertices)
    rows = []
    for ext, binary in FORMATS:
        path = os.path.join(folder, f"bench.{ext}")
        t_write, _ = timed(lambda: sorpia.write_mesh(path, v, f, binary=binary), repeat)
        t_read, (v2, f2) = timed(lambda: sorpia.read_mesh(path), repeat)
        exact = bool(v2.tobytes() == v.tobytes()) if ext != "stl" else None
        rows.append({"format": ext, "binary": binary, "vertices": len(v), "faces": len(f),
                     "bytes": os.path.getsize(path), "write_s": t_write, "read_s": t_read, "bit_exact": exact})
        os.remove(path)
    return rows


# The surface benchmark's mesh for each scheme: most vertices extraordinary.
SURFACE_MESHES = {"loop": ("irregular triangle mesh", sorpia.shapes.irregular),
                  "catmull-clark": ("irregular quad mesh", sorpia.shapes.quad_irregular)}


def bench_surface(scheme, n_vertices, max_level, repeat):
    v, f = SURFACE_MESHES[scheme][1](n_vertices)
    out = {"scheme": scheme, "vertices": len(v), "faces": len(f)}
    t0 = time.perf_counter()
    s = sorpia.LimitSurface(v, f, scheme=scheme)
    out["build_s"] = time.perf_counter() - t0
    out["levels"] = []
    core_scheme = sorpia._core.parse_scheme(scheme)
    for level in range(1, max_level + 1):
        before = current_rss_mb()
        reset_peak_rss()
        t0 = time.perf_counter()
        vs, fs = s.tessellate(level)
        first = time.perf_counter() - t0
        t_again, _ = timed(lambda: s.tessellate(level), repeat)
        estimate = sorpia._core.tessellation_bytes(len(v), len(f), level, core_scheme, f.size)
        out["levels"].append({"level": level, "out_vertices": len(vs), "out_faces": len(fs), "first_s": first,
                              "again_s": t_again, "peak_rss_mb": peak_rss_mb() - before,
                              "estimate_mb": estimate / 1e6})
        del vs, fs
    rng = np.random.default_rng(1)
    k = 1_000_000
    face_ids = rng.integers(0, len(f), k)
    uv = rng.dirichlet([1, 1, 1], k)[:, :2] if scheme == "loop" else rng.uniform(0, 1, (k, 2))
    out["evaluate_points"] = k
    out["evaluate_s"], _ = timed(lambda: s.evaluate(face_ids, uv), repeat)
    out["evaluate_derivatives_s"], _ = timed(lambda: s.evaluate(face_ids, uv, derivatives=True), repeat)
    return out


# One timed read in a child process: the sorpia found first on sys.path (PYTHONPATH chooses the build).
_READ_CHILD = """
import sys, time
import sorpia
t0 = time.perf_counter()
v, f = sorpia.read_mesh(sys.argv[1])
print(time.perf_counter() - t0, len(v), len(f))
"""


def _read_in_child(path, package_dir):
    env = dict(os.environ)
    if package_dir:
        env["PYTHONPATH"] = package_dir + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", _READ_CHILD, path], env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    return float(out[0]), int(out[1]), int(out[2])


def compare_reads(args, lines):
    """Read time of this build against --baseline, alternated in fresh processes; table onto lines."""
    v, f = sorpia.shapes.irregular(args.vertices)
    base = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build")
    os.makedirs(base, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory(dir=args.dir or base) as folder:
        for ext, binary in (("ply", True), ("ply", False), ("obj", False), ("off", False)):
            path = os.path.join(folder, f"bench.{ext}")
            sorpia.write_mesh(path, v, f, binary=binary)
            _read_in_child(path, None)  # the page cache warm for both
            times = {"baseline": [], "this": []}
            for _ in range(args.repeat):
                for who, package in (("baseline", args.baseline), ("this", None)):
                    t, nv, nf = _read_in_child(path, package)
                    assert (nv, nf) == (len(v), len(f))
                    times[who].append(t)
            b, t = statistics.median(times["baseline"]), statistics.median(times["this"])
            rows.append({"format": ext, "binary": binary, "baseline_s": b, "this_s": t, "ratio": t / b,
                         "all_baseline_s": times["baseline"], "all_this_s": times["this"]})
    lines += [f"## Reads side by side: irregular mesh, {len(v):,} vertices, {len(f):,} triangles",
              "", f"Baseline: {args.baseline_label or 'the sorpia package in ' + args.baseline}. Each read in a "
              f"fresh process, baseline and this build alternated, median of {args.repeat}.", "",
              "| format | baseline read s | this read s | this / baseline |", "|---|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['format']} {'binary' if r['binary'] else 'ascii'} | {r['baseline_s']:.3f} "
                     f"| {r['this_s']:.3f} | {r['ratio']:.3f} |")
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--surface-vertices", type=int, default=100_000)
    ap.add_argument("--max-level", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dir", default=None, help="folder for the files (default: a temporary folder under build/)")
    ap.add_argument("--only", choices=["files", "surface"], default=None)
    ap.add_argument("--json", default=None)
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/io-speed.md")
    ap.add_argument("--baseline", default=None, metavar="DIR",
                    help="only compare read times with the sorpia package in DIR (see above)")
    ap.add_argument("--baseline-label", default=None, metavar="TEXT",
                    help="what the baseline is, for the page (e.g. the commit it was built from)")
    args = ap.parse_args()

    if args.baseline:
        lines = []
        rows = compare_reads(args, lines)
        print("\n".join(lines))
        if not args.no_page:
            write_page("io-read-compare", "Mesh file reads against a baseline build", "\n".join(lines),
                       settings=(ap, args))
        if args.json:
            with open(args.json, "w") as fh:
                json.dump(rows, fh, indent=2)
        return

    result, lines = {}, []
    if args.only != "surface":
        result["files"] = files_table(args, lines)
    if args.only != "files":
        result["surface"] = surface_table(args, lines)
    print("\n".join(lines))
    if not args.no_page:
        write_page("io-speed", "Mesh files and the limit surface", "\n".join(lines), settings=(ap, args))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)


def files_table(args, lines):
    """Time the file formats; their Markdown table goes onto lines."""
    base = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build")
    os.makedirs(base, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=args.dir or base) as folder:
        files = bench_files(args.vertices, args.repeat, folder)
    lines += [f"## Files: irregular mesh, {files[0]['vertices']:,} vertices, {files[0]['faces']:,} faces "
              f"(median of {args.repeat}; writes include fsync)", "",
              "| format | MB | write s | read s | float64 bit-exact |", "|---|---:|---:|---:|---|"]
    for r in files:
        name = f"{r['format']} {'binary' if r['binary'] else 'ascii'}"
        exact = "float32 by definition" if r["bit_exact"] is None else ("yes" if r["bit_exact"] else "NO")
        lines.append(f"| {name} | {r['bytes'] / 1e6:.1f} | {r['write_s']:.2f} | {r['read_s']:.2f} | {exact} |")
    return files


def surface_table(args, lines):
    """Time the limit surface under each scheme; the Markdown tables go onto lines."""
    result = {}
    for scheme, (what, _) in SURFACE_MESHES.items():
        surface = result[scheme] = bench_surface(scheme, args.surface_vertices, args.max_level, args.repeat)
        lines += ["", f"## Limit surface, {scheme}: {what}, {surface['vertices']:,} vertices, "
                  f"{surface['faces']:,} faces", "",
                  f"`LimitSurface` build: {surface['build_s']:.2f} s. \"first\": the first `tessellate(level)`, "
                  f"which builds the refined topology; \"again\": median of {args.repeat} more on the same topology.",
                  "", "| level | output vertices | output faces | first s | again s | peak RSS growth MB | estimate MB |",
                  "|---:|---:|---:|---:|---:|---:|---:|"]
        for r in surface["levels"]:
            lines.append(f"| {r['level']} | {r['out_vertices']:,} | {r['out_faces']:,} | {r['first_s']:.2f} "
                         f"| {r['again_s']:.2f} | {r['peak_rss_mb']:.0f} | {r['estimate_mb']:.0f} |")
        lines += ["", f"`evaluate` at {surface['evaluate_points']:,} random points: {surface['evaluate_s']:.2f} s, "
                  f"with derivatives {surface['evaluate_derivatives_s']:.2f} s"]
    return result


if __name__ == "__main__":
    main()
