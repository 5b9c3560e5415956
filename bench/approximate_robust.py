"""The robust fit of sorpia.approximate on clean data and on data with outliers (issue 33, item 15).

    python bench/approximate_robust.py                 # writes docs/benchmarks/approximate_robust.md
    python bench/approximate_robust.py --no-page --losses none,cauchy

Clean data: the shared scans (their vertices, the cage `sorpia.decimate` to 2% of them) and a noisy torus.
Outliers: the same data with 1% of the points moved off the surface, each along a random direction by a distance
drawn uniformly from 0.1 to 2 diagonals (seed 1); and, on a sphere of 642 points (icosphere level 3, radius 1,
the cage its level-1 icosphere), 5 points at 50 radii. Duplicates: 2% of the points all copies of one point 0.2
diagonals off the surface. Every row fits the same cage with the defaults but `robust`, and is measured on the
points that are not outliers (the inliers): data -> surface RMS and max over the diagonal of the inliers
(footpoints searched afresh on the returned surface, sorpia's own measure), the largest distance from the surface
(its level-2 tessellation's vertices) to the nearest inlier, how far the surface lies from the least-squares fit
of the clean data (the largest distance between their level-2 tessellations' corresponding vertices: the same
cage's faces), and the extent of the cage (its bounding-box diagonal over the inliers'). Nothing here runs under
pytest.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from scipy.spatial import cKDTree

import sorpia

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _report import ROOT, write_page  # noqa: E402

SHARED = ROOT.parent / "shared" / "meshes"
CLEAN = ("stanford-bunny.obj", "mountain.obj", "airplane.obj", "noisy-torus")


def diagonal(p):
    return float(np.linalg.norm(p.max(0) - p.min(0)))


def clean(name):
    """(points, cage vertices, cage faces) of a scan (its vertices; the cage decimated to 2%) or the noisy torus."""
    if name == "noisy-torus":
        v, f = sorpia.shapes.torus(200, 200)
        ring = v.copy()
        ring[:, 2] = 0
        ring /= np.linalg.norm(ring, axis=1, keepdims=True)
        n = (v - ring) / np.linalg.norm(v - ring, axis=1, keepdims=True)
        v = v + n * np.random.default_rng(1).normal(scale=1e-3 * diagonal(v), size=(len(v), 1))
    else:
        v, f = sorpia.read_mesh(str(SHARED / name))
        f = np.asarray(f)
        used = np.unique(f)
        remap = np.full(len(v), -1)
        remap[used] = np.arange(len(used))
        v, f = np.asarray(v, float)[used], remap[f]
    n_cage = max(4, round(0.02 * len(v)))
    try:
        cage = sorpia.decimate(v, f, n_cage)
    except sorpia.MeshError:
        cage = sorpia.decimate(v, f, n_cage, strict=False)
    return v, cage.vertices, cage.faces


def with_outliers(points, fraction, rng):
    """The points with `fraction` of them moved 0.1..2 diagonals along random directions; (points, inlier mask)."""
    p = points.copy()
    k = max(1, round(fraction * len(p)))
    idx = rng.choice(len(p), k, replace=False)
    direction = rng.normal(size=(k, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    p[idx] += direction * rng.uniform(0.1, 2.0, size=(k, 1)) * diagonal(points)
    inlier = np.ones(len(p), bool)
    inlier[idx] = False
    return p, inlier


def with_duplicates(points, fraction, rng):
    """The points and `fraction` of their count more, all copies of one point 0.2 diagonals off the data."""
    k = max(1, round(fraction * len(points)))
    centre = points.mean(0)
    i = int(rng.integers(len(points)))
    out = points[i] + 0.2 * diagonal(points) * (points[i] - centre) / np.linalg.norm(points[i] - centre)
    p = np.vstack([points, np.repeat(out[None], k, axis=0)])
    return p, np.r_[np.ones(len(points), bool), np.zeros(k, bool)]


def sphere_case():
    v, _ = sorpia.shapes.icosphere(3)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    cv, cf = sorpia.shapes.icosphere(1)
    rng = np.random.default_rng(1)
    p = v.copy()
    idx = rng.choice(len(p), 5, replace=False)
    p[idx] *= 50.0
    inlier = np.ones(len(p), bool)
    inlier[idx] = False
    return v, p, inlier, cv, cf


def measure(result, faces, points, inlier, reference):
    """(inlier RMS / diag, inlier max / diag, surface -> inliers max / diag, largest distance from the reference
    tessellation / diag, cage extent / inliers' extent)."""
    d_in = diagonal(points[inlier])
    d = result.distances[inlier] / d_in
    tv, _ = sorpia.limit_surface(result.control_vertices, faces, 2)
    back = cKDTree(points[inlier]).query(tv)[0] / d_in
    gap = float(np.linalg.norm(tv - reference, axis=1).max()) / d_in
    return (float(np.sqrt(np.mean(d ** 2))), float(d.max()), float(back.max()), gap,
            diagonal(result.control_vertices) / d_in)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--losses", default="none,cauchy,tukey")
    parser.add_argument("--meshes", default=",".join(CLEAN))
    parser.add_argument("--no-page", action="store_true")
    args = parser.parse_args(argv)
    losses = args.losses.split(",")
    rows = []

    def run(label, points, inlier, cv, cf, reference):
        for loss in losses:
            t0 = time.perf_counter()
            r = sorpia.approximate(points, cv, cf, robust=loss)
            seconds = time.perf_counter() - t0
            m = measure(r, cf, points, inlier, reference)
            rows.append((label, loss, *m, seconds, r.iterations, r.robust_outliers))
            print(f"{label:40s} {loss:7s} rms {m[0]:.4g} max {m[1]:.4g} surf->in {m[2]:.4g} from clean {m[3]:.3g} "
                  f"extent {m[4]:.4g} {seconds:.2f} s ({r.iterations} it, {r.robust_outliers} beyond c s)",
                  file=sys.stderr)

    def least_squares(points, cv, cf):  # the reference surface: the clean data's least-squares fit
        return sorpia.limit_surface(sorpia.approximate(points, cv, cf, robust="none").control_vertices, cf, 2)[0]

    for name in args.meshes.split(","):
        if name != "noisy-torus" and not (SHARED / name).exists():
            print(f"{name}: not found, skipped", file=sys.stderr)
            continue
        v, cv, cf = clean(name)
        reference = least_squares(v, cv, cf)
        everything = np.ones(len(v), bool)
        run(f"{name}: clean ({len(v):,} points)", v, everything, cv, cf, reference)
        p, inlier = with_outliers(v, 0.01, np.random.default_rng(1))
        run(f"{name}: 1% outliers", p, inlier, cv, cf, least_squares(v[inlier], cv, cf))
        p, inlier = with_duplicates(v, 0.02, np.random.default_rng(1))
        run(f"{name}: 2% duplicates of one point", p, inlier, cv, cf, reference)
    v, p, inlier, cv, cf = sphere_case()
    run("sphere (642 points): clean", v, np.ones(len(v), bool), cv, cf, least_squares(v, cv, cf))
    run("sphere: 5 points at 50 radii", p, inlier, cv, cf, least_squares(v[inlier], cv, cf))
    lines = ["| data | robust | inlier RMS / diagonal | inlier max / diagonal | surface -> inliers: max | "
             "surface from the clean least-squares fit: max | cage extent / inliers' | seconds (iterations) "
             "| points beyond c s |", "|---|---|---|---|---|---|---|---|---|"]
    for label, loss, rms, mx, back, gap, extent, seconds, its, beyond in rows:
        lines.append(f"| {label} | {loss} | {rms:.4g} | {mx:.4g} | {back:.4g} | {gap:.3g} | {extent:.4g} "
                     f"| {seconds:.3g} ({its}) | {beyond} |")
    body = "\n".join(lines)
    print(body)
    if not args.no_page:
        write_page("approximate_robust", "Robust approximation: clean data and outliers",
                   __doc__.split("\n\n", 2)[2] + "\n" + body + "\n", settings=(parser, args))


if __name__ == "__main__":
    main()
