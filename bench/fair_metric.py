"""A prototype measured, not the library's energy: fair interpolation whose
thin-plate energy carries a fixed metric per face, against the library's
parametric energy (docs/fair.md, "Faces of very different shape").

The library's K (sorpia.fairness_matrix) integrates the second derivatives
in each face's own parameters, every face a unit domain, so bending across a
face that is long and thin in space is cheap. Here each fine face f gets a
fixed 2 x 2 first fundamental form G_f and the energy

    sum over faces of int tr(G_f^-1 H G_f^-1 H) sqrt(det G_f) du dv

per coordinate (H the 2 x 2 Hessian of the coordinate in (u, v)): still a
quadratic form in the control vertices, invariant under rotations and
uniform scalings of the coordinates. G_f: the input mesh's own limit surface
(R V0 on the fine mesh, free of the near-folds a surface through noisy
points can have) at the face's centre. "metric": that G_f on every face;
"hybrid": at faces with an extraordinary corner, where Bfr's
parameterisation is far from affine within the face and a constant G_f
charges it, the parametric shape scaled to the same area instead.

The quadrature: Bfr's rows (LimitSurface.rows) at 3 x 3 Gauss points (6
Dunavant points on triangles) of each face split once into four: exact on
regular Catmull-Clark faces, approximate near extraordinary vertices, where
the parametric energy diverges and any rule stops somewhere
(sorpia.energy). The minimiser: the
library's own solve (sorpia._core.fair_solve, as sorpia.fair_interpolate
calls it) with the prototype's K. Measures as bench/fair.py's, fair / plain,
for the library's fair interpolation and the two prototypes: the energy by
the library's K (as fair_interpolate takes it), int H^2, the same without each surface's 1%
worst faces, the median of H^2, the distance from the input's faces.

    python bench/fair_metric.py [--shared ../shared/meshes] [--max-shared 4000]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np
import scipy.sparse

import sorpia
from sorpia import _core
from sorpia.fair import ENERGY_WINDOW

sys.path.insert(0, os.path.dirname(__file__))
from fair import (QUAD_POINTS, QUAD_WEIGHTS, TRI_POINTS, TRI_WEIGHTS, diagonal,  # noqa: E402
                  distance_to_faces, mean_curvature_integral, meshes)

VARIANTS = ("library", "metric", "hybrid")


def split_rule(triangles: bool):
    """Points and weights of the bench's rule on each quarter of the unit
    square (or of the unit right triangle, split at its edge midpoints)."""
    if not triangles:
        pts = [(np.array([i, j]) + QUAD_POINTS) / 2 for j in (0, 1) for i in (0, 1)]
        return np.concatenate(pts), np.tile(QUAD_WEIGHTS / 4, 4)
    a, b, c = np.array([0.0, 0.0]), np.array([1.0, 0.0]), np.array([0.0, 1.0])
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    pts = []
    for p, q, r in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (bc, ca, ab)):
        pts.append(p + TRI_POINTS[:, :1] * (q - p) + TRI_POINTS[:, 1:] * (r - p))
    return np.concatenate(pts), np.tile(TRI_WEIGHTS / 4, 4)  # each quarter: |det| = 1/4


def face_metrics(surface, faces, keep, control, triangles, topology, hybrid):
    """(len(keep), 2, 2) G per face: control's limit surface at the face centre."""
    centre = np.array([1 / 3, 1 / 3]) if triangles else np.array([0.5, 0.5])
    _, du, dv = surface.rows(keep.astype(np.int32), np.tile(centre, (len(keep), 1)), derivatives=1)
    su, sv = du @ control, dv @ control
    g = np.empty((len(keep), 2, 2))
    g[:, 0, 0], g[:, 1, 1] = (su * su).sum(1), (sv * sv).sum(1)
    g[:, 0, 1] = g[:, 1, 0] = (su * sv).sum(1)
    # parametric shape of a face: the unit square, or the equilateral triangle the library measures Loop in
    shape = np.eye(2) if not triangles else np.array([[1.0, 0.5], [0.5, 1.0]]) / np.sqrt(0.75)
    if hybrid:
        valence = np.diff(np.asarray(topology.ring_offsets))
        boundary = np.asarray(topology.is_boundary).astype(bool)
        corners = faces[keep]
        extraordinary = ((valence[corners] != (6 if triangles else 4)) & ~boundary[corners]).any(axis=1)
        g[extraordinary] = np.sqrt(np.linalg.det(g[extraordinary]))[:, None, None] * shape
    return g


def metric_energy(res, v0, hybrid: bool, chunk: int = 100000):
    """(K of the per-face metric energy on `res`'s fine mesh (thin plate),
    the fine topology, its rules); v0 the input vertices."""
    faces = np.asarray(res.faces)
    triangles = faces.shape[1] == 3
    n = len(res.control_vertices)
    holes = res.holes if res.holes is not None else []
    keep = np.setdiff1d(np.arange(len(faces)), holes)
    control = res.refinement @ np.asarray(res.plain.control_vertices)
    surface = sorpia.LimitSurface(control, res.faces, scheme=res.scheme, boundary=res.boundary, **res.tags)
    arrays, count, rules = sorpia._validate.as_rules(res.faces, n, scheme=res.scheme, boundary=res.boundary,
                                                     **res.tags)
    topology = _core.Topology(*arrays, count)
    g = face_metrics(surface, faces, keep, res.refinement @ v0, triangles, topology, hybrid)
    lower = np.linalg.cholesky(np.linalg.inv(g))  # G^-1 = L L^T: tr(G^-1 H G^-1 H) = |L^T H L|_F^2
    scale = np.sqrt(np.linalg.det(g))
    pts, wts = split_rule(triangles)
    k = scipy.sparse.csr_matrix((n, n))
    per_chunk = max(1, chunk // len(pts))
    for s in range(0, len(keep), per_chunk):
        f = np.arange(s, min(s + per_chunk, len(keep)))
        fid = np.repeat(keep[f], len(pts)).astype(np.int32)
        _, _, _, duu, duv, dvv = surface.rows(fid, np.tile(pts, (len(f), 1)), derivatives=2)
        l11, l21, l22 = (np.repeat(lower[f, i, j], len(pts)) for i, j in ((0, 0), (1, 0), (1, 1)))
        w = np.repeat(scale[f], len(pts)) * np.tile(wts, len(f))
        d = scipy.sparse.diags
        for m, c in ((d(l11 ** 2) @ duu + d(2 * l11 * l21) @ duv + d(l21 ** 2) @ dvv, 1.0),
                     (d(l22 * l11) @ duv + d(l22 * l21) @ dvv, 2.0), (d(l22 ** 2) @ dvv, 1.0)):
            k = k + m.T @ d(c * w) @ m
    return scipy.sparse.csr_matrix(k), topology, rules


def solve(res, v0, k, topology, rules):
    """The library's fair solve with K = k: control vertices meeting every target."""
    k.sort_indices()
    start = np.ascontiguousarray(res.refinement @ np.asarray(res.plain.control_vertices))
    sol = _core.fair_solve(topology, rules, np.ascontiguousarray(k.data), k.indices.astype(np.int32),
                           k.indptr.astype(np.int32), res.targets.astype(np.int32),
                           np.ascontiguousarray(v0[res.targets]), start, 1e-6, ENERGY_WINDOW, 5000, 1)
    return np.asarray(sol["vertices"])


def measure(name, v, f, scheme, tags):
    v = np.asarray(v, float)
    res = sorpia.fair_interpolate(v, f, scheme=scheme, **tags)
    plain = res.refinement @ np.asarray(res.plain.control_vertices)
    controls = {"plain": plain, "library": res.control_vertices}
    for variant in VARIANTS[1:]:
        k, topology, rules = metric_energy(res, v, hybrid=variant == "hybrid")
        controls[variant] = solve(res, v, k, topology, rules)
    library_k = sorpia.fairness_matrix(res.faces, len(plain), scheme=res.scheme, boundary=res.boundary, depth=0,
                                       **res.tags)
    curvature = mean_curvature_integral(res, list(controls.values()))
    surface = sorpia.LimitSurface(plain, res.faces, scheme=res.scheme, boundary=res.boundary, **res.tags)
    out = {}
    for (label, ctrl), h in zip(controls.items(), curvature):
        surface.set_vertices(ctrl)
        points, _ = surface.tessellate(2)
        out[label] = (float(np.sum(ctrl * (library_k @ ctrl))), *h,
                      float(distance_to_faces(points, v, f).max()) / diagonal(v))
    return {label: np.array(x) / np.array(out["plain"]) for label, x in out.items() if label != "plain"}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shared", type=Path,
                        default=Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes")
    parser.add_argument("--max-shared", type=int, default=4000)
    args = parser.parse_args(argv)
    head = "energy  int H^2  99% faces  median H^2  distance"
    print(f"{'mesh':36s}" + "".join(f" | {v:^{len(head)}s}" for v in VARIANTS))
    print(f"{'':36s}" + f" | {head}" * len(VARIANTS))
    table = {v: [] for v in VARIANTS}
    for name, v, f, scheme, tags in meshes(args.shared, args.max_shared):
        r = measure(name, v, f, scheme, tags)
        for variant in VARIANTS:
            table[variant].append(r[variant])
        print(f"{name[:36]:36s}" + "".join(" | {:6.3f} {:8.3g} {:10.3g} {:11.3g} {:9.3g}".format(*r[x])
                                           for x in VARIANTS), flush=True)
    for label, fn in (("median", np.median), ("largest", np.max)):
        print(f"{label:36s}" + "".join(" | {:6.3f} {:8.3g} {:10.3g} {:11.3g} {:9.3g}".format(
            *fn(np.array(table[x]), axis=0)) for x in VARIANTS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
