"""Local updates and warm starts against full re-solves, side by side (medians).

    python bench/update_speed.py irregular:1000000 --repeat 7 --frames 100

On one mesh (sorpia.shapes spec or a mesh file, as bench/peers.py loads it),
with one sorpia.Interpolator:

1. One target moved by 1% of the bounding-box diagonal (a different random
   vertex each repeat): `Interpolator.update(..., in_place=True)` from the last
   update's result, the same with a copy of the vertices (the default), and a
   full cold re-solve of the same targets; the runs alternate. Reported: the
   seconds (wall time of the Python call, medians), relaxations, and the
   accuracy of both, E / E_0 and E itself (max-norm residual, recomputed by
   sorpia.limit_points, independent of the kept residuals), so that an update
   that had nothing to do would show.
2. A patch of targets (a breadth-first ring neighbourhood of p% of the
   vertices) moved rigidly by 1% of the diagonal: cost against patch size.
3. A generated deformation of `--frames` frames (a travelling wave across the
   mesh, one period over the frames, amplitude 2% of the diagonal), every frame solved cold, warm from the
   previous frame's control vertices, and warm from those moved by the
   targets' displacement, in turn: sweeps and seconds per frame, medians and
   totals.

The tolerance: E_0 is that of the new targets over the whole mesh, so a move
that changes little may already meet tol * E_0; a 1% move makes a residual of
about 1% of the diagonal at the moved vertex, far above tol * E_0 = 1e-10
E_0, and the columns E / E_0 and E show what each run reached. The page goes
to docs/benchmarks/update-speed.md (unless --no-page).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

import sorpia

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402
from peers import load as mesh  # noqa: E402


def max_residual(F, targets, control) -> float:
    """E = max_i ||v_i^0 - (B V)_i||, from sorpia.limit_points."""
    return float(np.linalg.norm(targets - sorpia.limit_points(control, F), axis=1).max())


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def patch(interp, seed_vertex: int, size: int) -> np.ndarray:
    """`size` vertices breadth-first around seed_vertex (rings of the one-ring)."""
    off, nb = interp.topology.ring_offsets, interp.topology.ring_neighbors
    seen = np.zeros(interp.n_vertices, bool)
    order, head = [seed_vertex], 0
    seen[seed_vertex] = True
    while head < len(order) and len(order) < size:
        i = order[head]
        head += 1
        for j in nb[off[i]:off[i + 1]]:
            if not seen[j]:
                seen[j] = True
                order.append(int(j))
    return np.array(order[:size])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh", nargs="?", default="irregular:1000000")
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--patches", default="0.1,1", help="patch sizes in percent of the vertices (default 0.1,1)")
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--no-page", action="store_true", help="do not write docs/benchmarks/update-speed.md")
    a = ap.parse_args(argv)
    V, F = mesh(a.mesh)
    n = len(V)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    rng = np.random.default_rng(1)
    interp = sorpia.Interpolator(F, n)
    first, res = timed(lambda: interp.solve(V, tol=a.tol))
    targets = V.copy()
    direction = np.array([0.3, 0.4, np.sqrt(1 - 0.25)])

    # The first update builds B's transpose and the targets' residuals: O(n), once.
    i = int(rng.integers(n))
    targets[i] += 0.01 * diag * direction
    setup, res = timed(lambda: interp.update(res, [i], targets[i], tol=a.tol, in_place=True))

    # 1. One target.
    runs = {"in_place": [], "copy": [], "full": []}
    rel = {"in_place": [], "copy": [], "full": []}
    acc = {"update": [], "full": []}
    for _ in range(a.repeat):
        for kind in ("in_place", "copy"):
            i = int(rng.integers(n))
            targets[i] += 0.01 * diag * direction
            dt, res = timed(lambda: interp.update(res, [i], targets[i], tol=a.tol, in_place=kind == "in_place"))
            runs[kind].append(dt)
            rel[kind].append(res.relaxations)
        acc["update"].append((res.history[-1], max_residual(F, targets, res.control_vertices), res.initial_error))
        full_solver = sorpia.Interpolator(F, n)  # a second one: a solve would reset `interp`'s kept targets
        dt, full = timed(lambda: full_solver.solve(targets, tol=a.tol))
        runs["full"].append(dt)
        rel["full"].append(full.relaxations)
        acc["full"].append((full.history[-1], max_residual(F, targets, full.control_vertices), full.initial_error))
        # Same final accuracy: both within tol of the same solution.
        acc.setdefault("diff", []).append(float(np.abs(full.control_vertices - res.control_vertices).max()))
    med = {k: statistics.median(v) for k, v in runs.items()}
    lines = [f"Mesh `{a.mesh}`: {n:,} vertices; tol = {a.tol:g}; bounding-box diagonal {diag:.4g}. "
             f"Seconds are wall times of the Python call, medians of {a.repeat} runs alternating between the "
             f"columns; E is max_i ||v_i^0 - (B V)_i||, recomputed by `sorpia.limit_points`.", "",
             "## One target moved by 1% of the diagonal", "",
             f"First solve {first:.3f} s; the first update {setup * 1e3:.1f} ms (builds B's transpose and the "
             "targets' residuals, once per Interpolator; later updates start from the last one's kept residual).",
             "",
             "| run | median ms | min ms | relaxations (median) | vs full re-solve |",
             "|---|---:|---:|---:|---:|"]
    for kind, label in (("in_place", "`update(..., in_place=True)`"), ("copy", "`update(...)` (copies V)"),
                        ("full", "full re-solve (cold)")):
        r = statistics.median(rel[kind])
        lines.append(f"| {label} | {med[kind] * 1e3:.3f} | {min(runs[kind]) * 1e3:.3f} | {r:,.0f} "
                     f"| {med['full'] / med[kind]:.0f}x |")
    lines += ["", "| result | E / E_0 (median) | E (median) | E_0 (median) |", "|---|---:|---:|---:|"]
    for kind in ("update", "full"):
        e_rel, e_abs, e0 = (statistics.median(x) for x in zip(*acc[kind]))
        lines.append(f"| {kind} | {e_rel:.3g} | {e_abs:.3g} | {e0:.3g} |")
    lines += ["", f"Largest difference between the updated and the re-solved control vertices: "
                  f"{max(acc['diff']):.3g} (median {statistics.median(acc['diff']):.3g})."]

    # 2. Patches.
    lines += ["", "## A patch of targets moved by 1% of the diagonal", "",
              "| patch | vertices | median ms | relaxations (median) | relaxations per moved target | "
              "ms per 1000 moved targets | E / E_0 |", "|---|---:|---:|---:|---:|---:|---:|"]
    for pct in (float(p) for p in a.patches.split(",")):
        size = max(1, int(round(n * pct / 100)))
        times, relax, errs = [], [], []
        for _ in range(a.repeat):
            idx = patch(interp, int(rng.integers(n)), size)
            targets[idx] += 0.01 * diag * direction
            dt, res = timed(lambda: interp.update(res, idx, targets[idx], tol=a.tol, in_place=True))
            times.append(dt)
            relax.append(res.relaxations)
            errs.append(max_residual(F, targets, res.control_vertices) / res.initial_error)
        m, r = statistics.median(times), statistics.median(relax)
        lines.append(f"| {pct:g}% | {len(idx):,} | {m * 1e3:.2f} | {r:,.0f} | {r / len(idx):.1f} "
                     f"| {m * 1e3 / len(idx) * 1000:.2f} | {max(errs):.3g} |")

    # 3. Frames.
    lo = V.min(axis=0)
    phase = 6 * np.pi * (V[:, 0] - lo[0]) / diag
    normal = np.array([0.0, 0.0, 1.0])
    kinds = ("cold", "previous", "moved")
    runs = {kind: {"sweeps": [], "seconds": [], "start": []} for kind in kinds}
    previous = interp.solve(V, tol=a.tol).control_vertices
    previous_v = V
    for frame in range(a.frames):
        frame_v = V + (0.02 * diag * np.sin(phase - 2 * np.pi * frame / a.frames))[:, None] * normal
        starts = {"cold": None, "previous": previous, "moved": previous + (frame_v - previous_v)}
        for kind in kinds[frame % 3:] + kinds[:frame % 3]:  # each first in turn
            dt, r = timed(lambda: interp.solve(frame_v, tol=a.tol, initial=starts[kind]))
            runs[kind]["sweeps"].append(r.iterations)
            runs[kind]["seconds"].append(dt)
            runs[kind]["start"].append(r.history[0])
            if kind == "moved":
                frame_result = r
        previous, previous_v = frame_result.control_vertices, frame_v
    lines += ["", f"## {a.frames} frames of a travelling wave (one period, amplitude 2% of the diagonal)", "",
              "Each frame solved cold (from V0), from the previous frame's control vertices, and from those moved "
              "by the targets' displacement (`previous + (V0 - previous V0)`), the three in turn first; all to the "
              "same E_k/E_0 < tol, E_0 of the frame's cold start.", "",
              "| start | E(start)/E_0 (median) | sweeps per frame (median) | sweeps in all | seconds per frame "
              "(median) | seconds in all |", "|---|---:|---:|---:|---:|---:|"]
    for kind, label in zip(kinds, ("cold", "`initial=previous`", "`initial=previous + displacement`")):
        d = runs[kind]
        lines.append(f"| {label} | {statistics.median(d['start']):.3g} | {statistics.median(d['sweeps']):.0f} "
                     f"| {sum(d['sweeps']):,} | {statistics.median(d['seconds']):.3f} | {sum(d['seconds']):.1f} |")
    text = "\n".join(lines)
    print(text)
    if not a.no_page:
        write_page("update-speed", "Local updates and warm starts", text, settings=(ap, a))
    return 0


if __name__ == "__main__":
    sys.exit(main())
