"""Approximation's speed at one size, phase by phase, and the update's two methods side by side (issue 23, items
4 and 6).

    python bench/approximate_speed.py                       # 1M points onto a 20k-vertex cage
    python bench/approximate_speed.py --points 200000 --cage 5000 --iterations 3
    python bench/approximate_speed.py --no-update-comparison --tangential 0.1   # the blend's cost at 1M points

The data: the limit surface of `sorpia.shapes.irregular(--cage)` (Loop, valences 3 to 12) sampled at --points
random (face, u, v), moved by Gaussian noise of 1e-4 of the bounding-box diagonal; the cage: the same mesh with
its vertices moved by noise of 2e-3 of the diagonal. Prints, as JSON:

- ``update``: on the footpoints of the starting cage, the same normal equations (A^T A + mu I) V = A^T P + mu V0
  solved by the core's conjugate gradients (Jacobi preconditioner) and by LSPIA (Deng and Lin 2014) to residuals of
  1e-2 ... 1e-8 of the start (one iteration of `sorpia.approximate` each): iterations and seconds of each, and the
  RMS distance after the update (its footpoints re-projected);
- ``phases``: `sorpia.approximate` with the default update for --iterations, its own timings (footpoints, rows,
  normal equations, solve, report) and history, with the process's CPU seconds and peak resident memory.

Nothing here runs under pytest. Timings depend on the machine's load: the JSON holds the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time

import numpy as np


def data(n_points: int, n_cage: int):
    import sorpia

    V, F = sorpia.shapes.irregular(n_cage)
    s = sorpia.LimitSurface(V, F)
    rng = np.random.default_rng(1)
    fid = rng.integers(0, s.n_faces, n_points).astype(np.int32)
    uv = rng.random((n_points, 2))
    flip = uv.sum(axis=1) > 1
    uv[flip] = 1 - uv[flip]
    P = s.evaluate(fid, uv)
    diag = float(np.linalg.norm(P.max(0) - P.min(0)))
    P += 1e-4 * diag * rng.standard_normal(P.shape)
    return P, V + 2e-3 * diag * rng.standard_normal(V.shape), F


def compare_updates(P, V0, F) -> dict:
    """One update of `sorpia.approximate` from the starting cage (point distance, no fairness term) by each method
    to each residual: its iterations and seconds (the core's pipeline times its solve) and the RMS distance after
    the update's re-projection of the footpoints."""
    import sorpia

    out = {}
    for name in ("cg", "lspia"):
        rows = []
        for rtol in (1e-2, 1e-4, 1e-6, 1e-8):
            r = sorpia.approximate(P, V0, F, iterations=1, tol=0, fairness=0.0, tangential=1.0, method=name,
                                   solver_tol=rtol, solver_max_iter=100000)
            rows.append({"rtol": rtol, "iterations": r.history[1]["solver_iterations"],
                         "seconds": r.timings["solve"], "rms": r.history[1]["rms"]})
        out[name] = rows
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--cage", type=int, default=20_000)
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--no-update-comparison", action="store_true")
    ap.add_argument("--tangential", type=float, default=None,
                    help="approximate()'s tangential (default: approximate()'s own default)")
    args = ap.parse_args()
    import sorpia

    P, V0, F = data(args.points, args.cage)
    out = {"points": len(P), "cage_vertices": len(V0), "load_average": os.getloadavg()}
    if not args.no_update_comparison:
        out["update"] = compare_updates(P, V0, F)
    cpu0 = time.process_time()
    t0 = time.perf_counter()
    blend = {} if args.tangential is None else {"tangential": args.tangential}
    r = sorpia.approximate(P, V0, F, iterations=args.iterations, tol=0, **blend)
    out["phases"] = {"wall_seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - cpu0,
                     "timings": r.timings, "history": r.history,
                     "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
    out["tangential"] = args.tangential
    out["load_average_after"] = os.getloadavg()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
