"""The "sor" solve phase on 1, 2, ... threads, side by side (medians).

    python bench/sweep_threads.py irregular:1000000 torus:1000x1000 irregular:500000 --threads 1,2 --repeat 5

Each mesh's operator is built once (sorpia.Interpolator); then the runs
alternate between the thread counts (1, 2, 1, 2, ...) so that a change in the
machine's load hits every column alike. Reported: the C++ solve seconds
(result.timings["solve"]: the sweep engine's set-up, E_0 and the sweeps),
median and min over the repeats, iterations, final E_k/E_0, and each thread
count's speed-up over the first. Meshes: irregular:N[:SEED], torus:NUxNV,
icosphere:L, grid:NUxNV, pole:N (sorpia.shapes) or a mesh file (peers.load).
The table also goes into docs/benchmarks/sweep-threads.md (unless --no-page).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys

import sorpia

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402
from peers import load as mesh  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--threads", default="1,2", help="comma-separated thread counts (default 1,2)")
    ap.add_argument("--method", default="sor", choices=("sor", "gs"))
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", action="store_true", help="print JSON instead of a table")
    ap.add_argument("--no-page", action="store_true", help="do not write docs/benchmarks/sweep-threads.md")
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
                         "iterations": last[t].iterations, "final_error": float(last[t].history[-1]),
                         "speedup": base / med})
    if a.json:
        print(json.dumps({"cpus": os.cpu_count(), "method": a.method, "tol": a.tol, "repeat": a.repeat, "rows": rows},
                         indent=1))
    lines = [f"`{a.method}` to {a.tol:g}, {os.cpu_count()} CPUs; the solve phase (`result.timings[\"solve\"]`), "
             f"seconds, medians of {a.repeat} runs alternating between the thread counts.", "",
             "| mesh | vertices | threads | median s | min s | iterations | E_k/E_0 | speed-up |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| `{r['mesh']}` | {r['vertices']:,} | {r['threads']} | {r['solve_median']:.3f} "
                     f"| {r['solve_min']:.3f} | {r['iterations']} | {r['final_error']:.2e} | {r['speedup']:.2f} |")
    if not a.json:
        print("\n".join(lines))
    if not a.no_page:
        write_page("sweep-threads", "Threads", "\n".join(lines), settings=(ap, a))
    return 0


if __name__ == "__main__":
    sys.exit(main())
