"""Move one target vertex and re-solve locally: the time of an update against a full solve.

    python examples/move_vertex.py                 # a 1M-vertex mesh
    python examples/move_vertex.py --vertices 50000

The Interpolator keeps the targets of its last solve; `update` moves some of
them and relaxes only where the residual reaches tol * E_0, starting from the
previous control vertices. The result meets the same E / E_0 < tol as a full
solve of the new targets, checked here with `sorpia.limit_points`.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import sorpia


def main(n_vertices: int = 1_000_000, moves: int = 5, tol: float = 1e-10):
    V, F = sorpia.shapes.irregular(n_vertices, seed=1)
    interp = sorpia.Interpolator(F, len(V))
    t = time.perf_counter()
    result = interp.solve(V, tol=tol)
    print(f"{len(V):,} vertices: full solve {time.perf_counter() - t:.3f} s, {result.iterations} sweeps")

    targets = V.copy()
    step = 0.01 * np.linalg.norm(V.max(axis=0) - V.min(axis=0))  # 1% of the bounding-box diagonal
    rng = np.random.default_rng(0)
    for move in range(moves):
        i = int(rng.integers(len(V)))
        targets[i] += step * np.array([0.0, 0.0, 1.0])
        t = time.perf_counter()
        # in_place: the result's arrays are updated, no copy of the whole mesh
        result = interp.update(result, [i], targets[i], tol=tol, in_place=True)
        seconds = time.perf_counter() - t
        e = np.linalg.norm(targets - sorpia.limit_points(result.control_vertices, F), axis=1).max()
        print(f"move vertex {i}: update {seconds * 1e3:.2f} ms, {result.relaxations:,} relaxations, "
              f"E/E_0 = {e / result.initial_error:.2e}"
              + (" (the first update also builds B's transpose)" if move == 0 else ""))
    return targets, F, result


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--moves", type=int, default=5)
    a = ap.parse_args()
    main(a.vertices, a.moves)
