"""The "sor" solve phase on 1, 2, ... threads, side by side (medians).

    python bench/sweep_threads.py irregular:1000000 torus:1000x1000 irregular:500000 --threads 1,2 --repeat 5

Each mesh's operator is built once (sorpia.Interpolator); then the runs
alternate between the thread counts (1, 2, 1, 2, ...) so that a change in the
machine's load hits every column alike. Reported: the C++ solve seconds
(result.timings["solve"]: the sweep engine's set-up, E_0 and the sweeps),
median and min over the repeats, iterations, final E_k/E_0, and each thread
count's speed-up over the first. Meshes: irregular:N[:SEED], torus:NUxNV,
icosphere:L, grid:NUxNV, pole:N (sorpia.shapes) or a mesh file (peers.load).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys

import sorpia

sys.path.insert(0, os.path.dirname(__file__))
from peers import load as mesh  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--threads", default="1,2", help="comma-separated thread counts (default 1,2)")
    ap.add_argument("--method", default="sor", choices=("sor", "gs"))
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", action="store_true", help="print JSON instead of a table")
    a = ap.parse_args(argv)
    counts = [int(t) for t in a.threads.split(",")]
    rows = []
    for spec in a.meshes:
        v, f = mesh(spec)
        solver = sorpia.Interpolator(f, len(v))
        runs = {t: [] for t in counts}
        last = {}
        for _ in range(a.repeat):
            for t in counts:
                r = solver.solve(v, method=a.method, tol=a.tol, threads=t)
                runs[t].append(r.timings["solve"])
                last[t] = r
        base = statistics.median(runs[counts[0]])
        for t in counts:
            med = statistics.median(runs[t])
            rows.append({"mesh": spec, "vertices": len(v), "threads": t, "solve_median": med, "solve_min": min(runs[t]),
                         "iterations": last[t].iterations, "final_error": float(last[t].errors[-1]),
                         "speedup": base / med})
    if a.json:
        print(json.dumps({"cpus": os.cpu_count(), "method": a.method, "tol": a.tol, "repeat": a.repeat, "rows": rows},
                         indent=1))
        return 0
    print(f"{a.method} to {a.tol:g}, {os.cpu_count()} CPUs, medians of {a.repeat} (solve phase, seconds)")
    print(f"{'mesh':22} {'vertices':>9} {'threads':>7} {'median':>8} {'min':>8} {'iters':>6} {'E_k/E_0':>9} {'speed-up':>8}")
    for r in rows:
        print(f"{r['mesh']:22} {r['vertices']:9d} {r['threads']:7d} {r['solve_median']:8.3f} {r['solve_min']:8.3f} "
              f"{r['iterations']:6d} {r['final_error']:9.2e} {r['speedup']:8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
