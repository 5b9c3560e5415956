"""Approximation against the number of points: the cost of each phase, 10k to 4M points (issue 23, item 6).

    python bench/approximate_scaling.py                              # 10k .. 4M points, cages of 2%
    python bench/approximate_scaling.py --sizes 10000,100000 --no-page --plot /tmp/a.png
    python bench/approximate_scaling.py --sizes "" --from-json bench/approximate_scaling.json --dask 1000000

For each size N, in a process of its own (so that each peak memory is its own): a noisy torus of about N
vertices (`sorpia.shapes.torus`, each vertex moved along the normal by Gaussian noise of 1e-3 of the bounding-box
diagonal, seed 1) whose vertices are the data points; its cage, `sorpia.decimate` to --fraction of N vertices
(Loop); then `sorpia.approximate` of the points with that cage, its own phases timed by itself
(ApproximationResult.timings: footpoints, rows, normal equations, solve, report). The table gives seconds per
phase, the iterations, the final RMS and max distance over the diagonal, and the peak resident memory; the plot
(log-log, with a dashed line of slope 1) the phases and the memory against N. Writes
docs/benchmarks/approximate-scaling.md and its plot (unless --no-page). Nothing here runs under pytest.

Out of core (--out-of-core N1,N2,..., rows of their own, --ooc-json): N points streamed from a binary PLY
(float32 x, y, z) that is never in memory whole. The data: samples of a known limit surface (a torus cage of
--ooc-cage vertices, moved along its normals by a smooth wave of 2% of its tube radius) at uniform random (face,
u, v), plus Gaussian noise of 1e-3 of the diagonal, written a million points at a time into --ooc-dir (deleted
after the run unless --keep); the fit starts from the torus cage without the wave, `sorpia.approximate(path,
...)` with its defaults and --chunk-points points per chunk, in a process of its own (its peak resident memory is
that of the fit alone, the file's writing done in another).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _report import PAGES, print_json_plot, write_page  # noqa: E402

PHASES = ("decimate", "footpoints", "rows", "normal", "solve", "report")
# The backend's calls of an iteration's normal-equation sums: the plain fit's, and the robust fit's (the default).
SUMS_CALLS = ("normal_sums", "robust_normal_sums")


def torus(n: int):
    """A torus of about n vertices (nu = 2.5 nv; major radius 1), its faces, its vertices' unit normals (from the
    ring through the tube's centre) and their distance from that ring."""
    import sorpia

    nv = max(3, round(np.sqrt(n / 2.5)))
    v, f = sorpia.shapes.torus(max(3, n // nv), nv)
    ring = v.copy()
    ring[:, 2] = 0
    ring /= np.linalg.norm(ring, axis=1, keepdims=True)
    normal = v - ring
    tube = np.linalg.norm(normal, axis=1, keepdims=True)
    return v, f, normal / tube, tube


def noisy_torus(n: int):
    """A torus of about n vertices, displaced along its normals by noise of 1e-3 of the diagonal."""
    v, f, normal, _ = torus(n)
    diag = np.linalg.norm(v.max(0) - v.min(0))
    return v + normal * np.random.default_rng(1).normal(scale=1e-3 * diag, size=(len(v), 1)), f


def one(n: int, fraction: float) -> dict:
    """Every phase at one size, in this process."""
    import sorpia

    points, faces = noisy_torus(n)
    n_cage = max(4, int(round(fraction * len(points))))
    t0 = time.perf_counter()
    cage = sorpia.decimate(points, faces, n_cage)
    decimate = time.perf_counter() - t0
    t0 = time.perf_counter()
    result = sorpia.approximate(points, cage.vertices, cage.faces)
    total = time.perf_counter() - t0
    timings = dict(result.timings)
    last = result.history[-1]
    return {"points": len(points), "cage": n_cage, "decimate": decimate,
            **{k: float(timings.get(k, 0.0)) for k in PHASES[1:]}, "approximate": total,
            "iterations": result.iterations, "rms": last["rms_relative"], "max": last["max_relative"],
            "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def wave_torus(n_cage: int):
    """The out-of-core benchmark's cages: a torus cage of about n_cage vertices (Loop), and the known one whose
    limit surface the data samples, moved along the torus's normals by a smooth wave of 2% of the tube radius."""
    v, f, normal, tube = torus(n_cage)
    tube = tube.mean()
    theta = np.arctan2(v[:, 1], v[:, 0])
    phi = np.arctan2(v[:, 2], np.linalg.norm(v[:, :2], axis=1) - 1.0)  # the torus of major radius 1
    known = v + normal * (0.02 * tube * np.sin(5 * theta) * np.cos(3 * phi))[:, None]
    return v, known, f


def write_samples(path: str, n: int, n_cage: int, block: int = 1 << 20) -> float:
    """n noisy samples of wave_torus's known limit surface as a binary little-endian PLY of float32 x, y, z,
    written a block at a time (never n points in memory). Returns the seconds taken."""
    from sorpia.surface import LimitSurface

    t0 = time.perf_counter()
    _, known, f = wave_torus(n_cage)
    surface = LimitSurface(known, f, scheme="loop")
    diag = np.linalg.norm(known.max(0) - known.min(0))
    rng = np.random.default_rng(7)
    with open(path, "wb") as fh:
        fh.write(("ply\nformat binary_little_endian 1.0\n"
                  f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\nend_header\n").encode())
        for start in range(0, n, block):
            m = min(block, n - start)
            fid = rng.integers(0, surface.n_faces, m).astype(np.int32)
            uv = rng.random((m, 2))
            flip = uv.sum(axis=1) > 1
            uv[flip] = 1 - uv[flip]
            p = surface.evaluate(fid, uv) + rng.normal(scale=1e-3 * diag / np.sqrt(3), size=(m, 3))
            fh.write(p.astype("<f4").tobytes())
    return time.perf_counter() - t0


def one_out_of_core(path: str, n_cage: int, chunk_points: int, iterations: int) -> dict:
    """The streamed fit of the points of `path`, in this process."""
    import sorpia

    v, _, f = wave_torus(n_cage)
    t0 = time.perf_counter()
    result = sorpia.approximate(path, v, f, chunk_points=chunk_points, iterations=iterations)
    total = time.perf_counter() - t0
    best = result.history[result.best_iteration]
    return {"points": result.n_points, "cage": len(v), "chunk_points": chunk_points, "max_iterations": iterations,
            **{k: float(result.timings.get(k, 0.0)) for k in PHASES[1:]}, "approximate": total,
            "iterations": result.iterations, "stop_reason": result.stop_reason, "rms": best["rms_relative"],
            "max": best["max_relative"], "surface_rms": best["surface_rms_relative"],
            "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "file_mb": os.path.getsize(path) / 2**20}


def out_of_core_rows(sizes, n_cage: int, chunk_points: int, directory: str, keep: bool, iterations: int) -> list:
    rows = []
    for n in sizes:
        path = os.path.join(directory, f"sorpia-ooc-{n}.ply")
        if not os.path.exists(path):
            print(f"writing {n:,} points to {path}", file=sys.stderr)
            made = subprocess.run([sys.executable, __file__, "--write-samples", path, "--ooc-cage", str(n_cage),
                                   "--points", str(n)], capture_output=True, text=True)
            if made.returncode != 0:
                print(f"{n} points: writing failed: {made.stderr.strip()[-2000:]}", file=sys.stderr)
                break
        out = subprocess.run([sys.executable, __file__, "--one-ooc", path, "--ooc-cage", str(n_cage),
                              "--chunk-points", str(chunk_points), "--iterations", str(iterations)],
                             capture_output=True, text=True)
        if not keep:
            os.remove(path)
        if out.returncode != 0:
            print(f"{n} points out of core: failed: {out.stderr.strip()[-2000:]}", file=sys.stderr)
            break
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
        print(rows[-1], file=sys.stderr)
    return rows


def dask_rows(n: int, fraction: float, workers: tuple, chunk_points: int) -> list:
    """The data and cage of one(n), fitted with chunks of `chunk_points` in this process (2 threads) and on a
    LocalCluster of each of `workers` worker processes of one thread (the same chunks): each run's seconds and
    the Dask runs' largest relative difference from the in-process one, the workers' seconds per million points
    per call (footpoints: search and refine; sums: normal_sums, or robust_normal_sums under the default robust
    fit) and the bytes of arrays sent each way per
    iteration (the points' first sending apart)."""
    import sorpia
    from dask.distributed import Client, LocalCluster

    points, faces = noisy_torus(n)
    cage = sorpia.decimate(points, faces, max(4, int(round(fraction * len(points)))))
    t0 = time.perf_counter()
    local = sorpia.approximate(points, cage.vertices, cage.faces, chunk_points=chunk_points)
    rows = [{"points": len(points), "cage": len(cage.vertices), "workers": 0, "chunk_points": chunk_points,
             "seconds": time.perf_counter() - t0, "iterations": local.iterations, "rms": local.rms / local.diagonal,
             "relative": 0.0}]
    for w in workers:
        with LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
                Client(cluster) as client:
            t0 = time.perf_counter()
            res = sorpia.approximate(points, cage.vertices, cage.faces, chunk_points=chunk_points, client=client)
            seconds = time.perf_counter() - t0
        c = res.timings["cluster"]
        rounds = res.iterations + 1  # searches and re-projections: the first, one per iteration
        per_m = 1e6 / len(points)
        sent_points = len(points) * 24
        rows.append({**rows[0], "workers": w, "seconds": seconds, "iterations": res.iterations,
                     "rms": res.rms / res.diagonal,
                     "relative": float(np.abs(res.control_vertices - local.control_vertices).max()
                                       / np.abs(local.control_vertices).max()),
                     **{f"{what}_per_m{suffix}": per_m * sum(c[key].get(call, 0.0) for call in calls) / n_calls
                        for key, suffix in (("worker_seconds", ""), ("worker_cpu_seconds", "_cpu"))
                        for what, calls, n_calls in (("footpoints", ("search", "refine"), rounds),
                                                     ("sums", SUMS_CALLS, max(res.iterations, 1)))},
                     "mb_out_per_iteration": (c["bytes_to_workers"] - sent_points) / rounds / 1e6,
                     "mb_in_per_iteration": sum(c["bytes_from_workers"].get(call, 0) for call in SUMS_CALLS)
                     / max(res.iterations, 1) / 1e6
                     + sum(c["bytes_from_workers"].get(call, 0) for call in ("search", "refine")) / rounds / 1e6,
                     "chunks": c["chunks"]})
        print(rows[-1], file=sys.stderr)
    return rows


def dask_lines(rows) -> list:
    """The Dask table of the page."""
    lines = ["", "## On a Dask cluster", "",
             "The same data and cage at one size, cut into chunks (--dask-chunk points each), fitted in one process "
             "(workers 0: `sorpia.approximate` on the machine's threads) and on a `LocalCluster` of 1 and 2 worker "
             "processes of one thread each (`client=`; the same chunks, their sums added in chunk order): seconds "
             "of the whole call, the largest difference of the control vertices from the in-process run's "
             "(relative), and what the workers did: their wall seconds (and their processes' CPU seconds, the "
             "core's threads) per million points for one round of footpoints (search or re-projection) and for "
             "one iteration's normal-equation sums, and the megabytes "
             "of arrays sent to the workers and back per iteration (besides the points, sent once). "
             "Each worker's core runs on all the machine's cores: where two workers share the machine, the rows "
             "show the same result from either, not a speed-up. docs/distributed.md projects a billion points "
             "from these.", "",
             "| points | cage | chunks | workers | seconds | iterations | RMS / diagonal | relative difference "
             "| footpoints s (CPU) per 1M | sums s (CPU) per 1M | MB out per iteration | MB back per iteration |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        dask = r["workers"] > 0
        lines.append(f"| {r['points']:,} | {r['cage']:,} | {r.get('chunks', '')} | {r['workers']} "
                     f"| {r['seconds']:.3g} | {r['iterations']} | {r['rms']:.3g} | {r['relative']:.2g} | "
                     + (f"{r['footpoints_per_m']:.3g} ({r['footpoints_per_m_cpu']:.3g}) | {r['sums_per_m']:.3g} "
                        f"({r['sums_per_m_cpu']:.3g}) | {r['mb_out_per_iteration']:.3g} "
                        f"| {r['mb_in_per_iteration']:.3g} |" if dask else " | | | |"))
    return lines


OOC_JSON = os.path.join(os.path.dirname(os.path.abspath(__file__)), "approximate_scaling_ooc.json")


def ooc_lines(rows) -> list:
    """The out-of-core table of the page (the rows of --out-of-core runs, kept in --ooc-json)."""
    lines = ["", "## Out of core", "",
             "Points streamed from a binary PLY (float32) a chunk at a time, never in memory whole (module "
             "docstring: samples of a known limit surface plus noise), onto a fixed cage; each row from its own "
             "run of --out-of-core, in a process of its own. Peak MB is the fit's process alone. Seconds are "
             "wall seconds; each row's note says on what code and at what load it ran (a loaded machine inflates "
             "them). The peak memory is set by the chunk and the cage, not the points.", "",
             "| points | cage | chunk | iterations | footpoints s | rows s | normal s | solve s | report s "
             "| approximate s | RMS / diagonal | max / diagonal | peak MB | file MB |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['points']:,} | {r['cage']:,} | {r['chunk_points']:,} | {r['iterations']} | "
                     + " | ".join(f"{r[k]:.3g}" for k in PHASES[1:])
                     + f" | {r['approximate']:.3g} | {r['rms']:.3g} | {r['max']:.3g} | {r['peak_mb']:.0f} "
                     f"| {r['file_mb']:.0f} |")
    notes = [f"{r['points']:,} points: {r['note']}" for r in rows if r.get("note")]
    if notes:
        lines += ["", "How each row was measured:", ""] + [f"- {n}." for n in notes]
    return lines


def draw(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = [r["points"] for r in rows]
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(10, 4))
    for key in PHASES + ("approximate",):
        if any(r[key] > 0 for r in rows):
            ax_t.loglog(n, [max(r[key], 1e-4) for r in rows], "o-", label=key)
    ax_t.loglog(n, [rows[0]["approximate"] * x / n[0] for x in n], "k--", lw=0.8, label="slope 1")
    ax_t.set(xlabel="data points", ylabel="seconds", title="time per phase (cage: 2% of the points)")
    ax_t.legend(fontsize=8)
    ax_m.loglog(n, [r["peak_mb"] for r in rows], "o-", label="peak resident MB")
    ax_m.loglog(n, [rows[-1]["peak_mb"] * x / n[-1] for x in n], "k--", lw=0.8, label="slope 1")
    ax_m.set(xlabel="data points", ylabel="MB", title="peak memory (whole process)")
    ax_m.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"plot: {path}", file=sys.stderr)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="10000,100000,1000000,4000000")
    p.add_argument("--fraction", type=float, default=0.02, help="cage vertices per data point")
    p.add_argument("--plot", help="where to draw the plot (default: beside the page; with --no-page, none)")
    p.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    p.add_argument("--no-page", action="store_true", help="print only; do not write the page")
    p.add_argument("--from-json", metavar="PATH", help="rows measured earlier (a --json file), before the new ones")
    p.add_argument("--dask", type=int, metavar="N",
                   help="also fit N points on a Dask LocalCluster of 1 and 2 workers (needs dask.distributed)")
    p.add_argument("--dask-chunk", type=int, default=250_000, help="points per chunk of the --dask runs")
    p.add_argument("--dask-json", metavar="PATH",
                   help="the Dask rows' JSON: written when --dask measures them, read (rows measured earlier) when not")
    p.add_argument("--one", type=int, help=argparse.SUPPRESS)  # a child: one size, JSON on stdout
    p.add_argument("--out-of-core", metavar="N1,N2", help="streamed rows instead: points per PLY (module docstring)")
    p.add_argument("--ooc-cage", type=int, default=50000, help="cage vertices of the out-of-core rows")
    p.add_argument("--chunk-points", type=int, default=1 << 20, help="points per chunk of the out-of-core rows")
    p.add_argument("--ooc-dir", default="/tmp", help="where the out-of-core rows' PLY files are written")
    p.add_argument("--ooc-json", metavar="PATH", help="append the out-of-core rows to this JSON list")
    p.add_argument("--keep", action="store_true", help="keep the out-of-core PLY files")
    p.add_argument("--iterations", type=int, default=10, help="iterations at most of the out-of-core rows' fits")
    p.add_argument("--write-samples", metavar="PATH", help=argparse.SUPPRESS)  # a child: write one PLY
    p.add_argument("--points", type=int, help=argparse.SUPPRESS)
    p.add_argument("--one-ooc", metavar="PATH", help=argparse.SUPPRESS)  # a child: one streamed fit
    p.add_argument("--dask-one", type=int, help=argparse.SUPPRESS)  # a child: the Dask rows of one size
    a = p.parse_args(argv)
    if a.write_samples:
        print(json.dumps({"seconds": write_samples(a.write_samples, a.points, a.ooc_cage)}))
        return
    if a.one_ooc:
        print(json.dumps(one_out_of_core(a.one_ooc, a.ooc_cage, a.chunk_points, a.iterations)))
        return
    if a.out_of_core:
        rows = out_of_core_rows([int(x) for x in a.out_of_core.split(",") if x], a.ooc_cage, a.chunk_points,
                                a.ooc_dir, a.keep, a.iterations)
        if a.ooc_json:
            old = []
            if os.path.exists(a.ooc_json):
                with open(a.ooc_json) as fh:
                    old = json.load(fh)
            with open(a.ooc_json, "w") as fh:
                json.dump(old + rows, fh, indent=1)
        print(json.dumps(rows, indent=1))
        return
    if a.one:
        print(json.dumps(one(a.one, a.fraction)))
        return
    if a.dask_one:
        print(json.dumps(dask_rows(a.dask_one, a.fraction, (1, 2), a.dask_chunk)))
        return
    rows = []
    if a.from_json:
        with open(a.from_json) as fh:
            rows = json.load(fh)
    for n in (int(s) for s in a.sizes.split(",") if s):
        out = subprocess.run([sys.executable, __file__, "--one", str(n), "--fraction", str(a.fraction)],
                             capture_output=True, text=True)
        if out.returncode != 0:
            print(f"{n} points: failed: {out.stderr.strip()[-2000:]}", file=sys.stderr)
            break
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
        print(rows[-1], file=sys.stderr)
    dask = []
    if a.dask_json and not a.dask:
        with open(a.dask_json) as fh:
            dask = json.load(fh)
    if a.dask:
        out = subprocess.run([sys.executable, __file__, "--dask-one", str(a.dask), "--fraction", str(a.fraction),
                              "--dask-chunk", str(a.dask_chunk)], capture_output=True, text=True)
        if out.returncode != 0:
            print(f"Dask, {a.dask} points: failed: {out.stderr.strip()[-2000:]}", file=sys.stderr)
        else:
            dask = json.loads(out.stdout.strip().splitlines()[-1])
    lines = ["| points | cage | decimate s | footpoints s | rows s | normal s | solve s | report s | approximate s "
             "| iterations | RMS / diagonal | max / diagonal | peak MB |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['points']:,} | {r['cage']:,} | " + " | ".join(f"{r[k]:.3g}" for k in PHASES)
                     + f" | {r['approximate']:.3g} | {r['iterations']} | {r['rms']:.3g} | {r['max']:.3g} "
                     f"| {r['peak_mb']:.0f} |")
    lines += ["", "approximate s: the whole call of `sorpia.approximate` (its phases and the rest: validation, "
              "the limit surface's set-up); decimate s: `sorpia.decimate`, before it."]
    from approximate_command import page_lines as command_lines  # the whole command at 1M, when measured
    lines += command_lines()
    lines = print_json_plot(lines, rows, json_path=a.json, plot=a.plot, no_page=a.no_page,
                            default_plot=PAGES / "approximate-scaling.png", draw=draw,
                            caption="time and memory against the number of points")
    if dask:
        lines += dask_lines(dask)
        print("\n".join(dask_lines(dask)))
    ooc_path = a.ooc_json or OOC_JSON
    if os.path.exists(ooc_path):
        with open(ooc_path) as fh:
            lines += ooc_lines(json.load(fh))
    if not a.no_page:
        intro = __doc__.split("\n\n", 2)[2].split(" Writes\ndocs/")[0]
        write_page("approximate-scaling", "Approximation: cost of each phase against the number of points",
                   intro + "\n\n" + "\n".join(lines), settings=(p, a))
    if a.dask and dask and a.dask_json:  # after the page, whose stamp would call the tree dirty for it
        with open(a.dask_json, "w") as fh:
            json.dump(dask, fh, indent=1)


if __name__ == "__main__":
    main()
