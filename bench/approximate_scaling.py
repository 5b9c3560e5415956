"""Approximation against the number of points: the cost of each phase, 10k to 4M points (issue 23, item 6).

    python bench/approximate_scaling.py                              # 10k .. 4M points, cages of 2%
    python bench/approximate_scaling.py --sizes 10000,100000 --no-page --plot /tmp/a.png

For each size N, in a process of its own (so that each peak memory is its own): a noisy torus of about N
vertices (`sorpia.shapes.torus`, each vertex moved along the normal by Gaussian noise of 1e-3 of the bounding-box
diagonal, seed 1) whose vertices are the data points; its cage, `sorpia.decimate` to --fraction of N vertices
(Loop); then `sorpia.approximate` of the points with that cage, its own phases timed by itself
(ApproximationResult.timings: footpoints, rows, normal equations, solve, report). The table gives seconds per
phase, the iterations, the final RMS and max distance over the diagonal, and the peak resident memory; the plot
(log-log, with a dashed line of slope 1) the phases and the memory against N. Writes
docs/benchmarks/approximate-scaling.md and its plot (unless --no-page). Nothing here runs under pytest.
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


def noisy_torus(n: int):
    """A torus of about n vertices (nu = 2.5 nv), displaced along its normals by noise of 1e-3 of the diagonal."""
    import sorpia

    nv = max(3, round(np.sqrt(n / 2.5)))
    v, f = sorpia.shapes.torus(max(3, n // nv), nv)
    ring = v.copy()
    ring[:, 2] = 0
    ring /= np.linalg.norm(ring, axis=1, keepdims=True)
    normal = v - ring
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
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
    p.add_argument("--one", type=int, help=argparse.SUPPRESS)  # a child: one size, JSON on stdout
    a = p.parse_args(argv)
    if a.one:
        print(json.dumps(one(a.one, a.fraction)))
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
    if not a.no_page:
        intro = __doc__.split("\n\n", 2)[2].split(" Writes\ndocs/")[0]
        write_page("approximate-scaling", "Approximation: cost of each phase against the number of points",
                   intro + "\n\n" + "\n".join(lines), settings=(p, a))


if __name__ == "__main__":
    main()
