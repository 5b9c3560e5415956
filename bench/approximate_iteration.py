"""One iteration of approximation on all points, phase by phase (issue 32): the footpoints re-projected from the
previous ones (ApproximationChunk.refine), the rows of the limit surface at them (LimitSurface.rows, in face order
as the normal sums make them) and the robust normal sums with the rows inside (ApproximationChunk.robust_normal_sums,
tangential 0.1, Tukey at a scale of 1e-4 of the diagonal, the defaults' floor).

    python bench/approximate_iteration.py                        # 1M points onto a 20k-vertex cage
    python bench/approximate_iteration.py --points 100000 --cage 2000 --repeat 5

The data: approximate_speed.py's (the limit surface of `sorpia.shapes.irregular(--cage)` sampled at --points, with
noise; the cage moved by noise). The two cages the phases alternate between are `sorpia.approximate`'s iterates 1
and 2 from it (each refine then moves the footpoints as far as one update does), one chunk of all points. Prints,
as JSON, per phase the medians over its 2 x --repeat runs of the wall seconds, the process's CPU seconds (all threads)
and the calling thread's CPU seconds (the work no other thread shares, plus its share of the parallel work).

Nothing here runs under pytest. Timings depend on the machine's load: the JSON holds the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def main() -> None:
    import sorpia
    from sorpia import _core

    from approximate_speed import data

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--cage", type=int, default=20_000)
    ap.add_argument("--repeat", type=int, default=3, help="pairs of iterations timed")
    args = ap.parse_args()
    P, V0, F = data(args.points, args.cage)
    iterates = [sorpia.approximate(P, V0, F, iterations=i, coarse_iterations=0, tol=0).control_vertices
                for i in (1, 2)]
    surface = sorpia.LimitSurface(iterates[0], F)._surface
    chunk = _core.ApproximationChunk(np.ascontiguousarray(P))
    grid, steps = 4, 10
    chunk.search(_core.FootpointSearch(surface, grid, steps))
    robust = _core.robust_options("tukey")
    scale = 1e-4 * float(np.linalg.norm(P.max(0) - P.min(0)))
    times: dict[str, list] = {"refine": [], "rows": [], "normal_sums": []}

    def timed(name, fn):
        w, c, t = time.perf_counter(), time.process_time(), time.thread_time()
        out = fn()
        times[name].append((time.perf_counter() - w, time.process_time() - c, time.thread_time() - t))
        return out

    out = {"points": len(P), "cage_vertices": len(V0), "load_average": os.getloadavg()}
    for _ in range(args.repeat):
        for V in (iterates[1], iterates[0]):
            surface.set_vertices(V)
            timed("refine", lambda: chunk.refine(surface, grid, steps))
            chunk.keep_best()
            fid, uv, _ = chunk.best_footpoints()
            order = np.argsort(fid, kind="stable")
            fo, uo = np.ascontiguousarray(fid[order]), np.ascontiguousarray(uv[order])
            timed("rows", lambda: surface.rows(fo, uo, 0))
            timed("normal_sums", lambda: chunk.robust_normal_sums(surface, 0.1, robust, scale))
    for name, t in times.items():
        t = np.array(t)
        out[name] = {"wall": float(np.median(t[:, 0])), "cpu": float(np.median(t[:, 1])),
                     "calling_thread_cpu": float(np.median(t[:, 2]))}
    out["load_average_after"] = os.getloadavg()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
