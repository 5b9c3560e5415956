"""Cost of sharpness tags: the same mesh solved without tags and with a share
of its edges tagged as creases, side by side.

Mesh: sorpia.shapes.irregular(--vertices). Sides: no tags; --share of the
edges (a fixed random draw) infinitely sharp; the same edges with sharpness
--semi (semi-sharp: their vertices' rows come from OpenSubdiv's refinement).
For each side: building B (sorpia.Interpolator, topology excluded), the solve
of each --methods, its iterations, and the solve time per vertex and
iteration. Runs alternate between the sides; medians of --repeat runs.
Prints Markdown tables and writes them into docs/benchmarks/creases-speed.md
(unless --no-page).

    python bench/creases_speed.py [--vertices 1000000] [--share 0.01] [--semi 2.5] [--methods sor,pia]
                                  [--repeat 3] [--no-page]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import warnings

import numpy as np

import sorpia

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402


def edges_of(faces):
    f = np.asarray(faces)
    return np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1), axis=0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--share", type=float, default=0.01, help="share of the edges tagged")
    ap.add_argument("--semi", type=float, default=2.5, help="sharpness of the semi-sharp side")
    ap.add_argument("--methods", default="sor,pia")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/creases-speed.md")
    args = ap.parse_args()

    v, f = sorpia.shapes.irregular(args.vertices, 1)
    e = edges_of(f)
    picked = e[np.random.default_rng(1).random(len(e)) < args.share]
    sides = {"no tags": {}, f"{len(picked):,} edges infinitely sharp": {"creases": (picked, np.inf)},
             f"{len(picked):,} edges sharpness {args.semi:g}": {"creases": (picked, args.semi)}}
    methods = args.methods.split(",")
    build = {s: [] for s in sides}
    solve = {(s, m): [] for s in sides for m in methods}
    iters, uniform = {}, {}
    for _ in range(args.repeat):
        for side, tags in sides.items():
            interp = sorpia.Interpolator(f, len(v), **tags)
            build[side].append(interp.build_timings["operator"])
            uniform[side] = interp._impl.uniform
            for m in methods:
                with warnings.catch_warnings():
                    warnings.simplefilter("error")  # a run that does not converge is no measurement
                    t0 = time.perf_counter()
                    r = interp.solve(v, method=m)
                    solve[side, m].append(time.perf_counter() - t0)
                iters[side, m] = r.iterations
            del interp

    n = len(v)
    lines = [f"sorpia.shapes.irregular({args.vertices}): {n:,} vertices, {len(e):,} edges; tagged: "
             f"{len(picked):,} edges ({100 * len(picked) / len(e):.2f}%); medians of {args.repeat}, the sides "
             f"alternated; load average {os.getloadavg()[0]:.1f} at the end.", "",
             "| tags | B built (s) | uniform rows | method | iterations | solve (s) | ns per vertex and iteration "
             "| vs no tags |", "|---|---:|:---:|---|---:|---:|---:|---:|"]
    for side in sides:
        for m in methods:
            t = statistics.median(solve[side, m])
            per = 1e9 * t / (n * iters[side, m])
            base = 1e9 * statistics.median(solve["no tags", m]) / (n * iters["no tags", m])
            lines.append(f"| {side} | {statistics.median(build[side]):.3f} | {'yes' if uniform[side] else 'no'} | {m} "
                         f"| {iters[side, m]} | {t:.3f} | {per:.1f} | {per / base:.2f}x |")
    print("\n".join(lines))
    if not args.no_page:
        write_page("creases-speed", "Speed with sharpness tags", "\n".join(lines), settings=(ap, args))


if __name__ == "__main__":
    main()
