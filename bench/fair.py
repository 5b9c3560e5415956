"""Fair interpolation (sorpia.fair_interpolate) against plain interpolation
(sorpia.interpolate): how much less the surface bends, how far it strays
from the input mesh, and what it costs.

Like with like: plain interpolation's control mesh refined `levels` times by
the same refinement (R V_plain, the same surface) lies on the same fine mesh
as the fair control mesh, so both surfaces are measured on the same faces
with the same rules:

- the thin-plate energy tr(V^T K V) (K = sorpia.fairness_matrix of the fine
  mesh as fair interpolation takes it, what it minimises: semi-sharp creases
  taken as infinitely sharp, depth 0);
- the integral of the squared mean curvature, int H^2 dA, by Gauss points in
  every fine face (3 x 3 on quads, Dunavant's 6 points on triangles) from the
  limit surface's first and second derivatives (LimitSurface.rows); also
  without each surface's 1% of faces of largest int H^2 (the integral of a
  surface through noisy points is dominated by a few faces where it nearly
  folds, |S_u x S_v| small and H large), and the median of H^2 over the
  points;
- the largest distance from a point of the surface (the fine mesh tessellated
  twice, every vertex at its limit position) to the input mesh's faces
  (polygons split into fans), over the bounding-box diagonal.

Each mesh also with metric="reference" (a face metric from the input's own
limit surface, docs/fair.md) against the default.

Meshes: the demo mesh (`sorpia demo`'s sample, both schemes), the shared
meshes in ../shared/meshes when present (manifold ones up to --max-shared
vertices, with their tags), and generated noisy meshes; where a mesh has
semi-sharp tags, also fair interpolation with semi_sharp="as-tagged" and
depth=4 (the energy of the thin layers where semi-sharp creases turn
counted, integrated down to them: the behaviour before both options). Then
what more freedom buys on the small meshes: two and three levels finer, a
membrane term, every other vertex a target; and the bound on the gain for a
regular Catmull-Clark grid (spectral, see `regular_grid_bound`). Then the
time of fair against plain interpolation of generated noisy meshes of --sizes
vertices (both schemes, one thread each), with fair's phases. Writes
docs/benchmarks/fair.md and docs/benchmarks/fair.png (plain and fair side by
side, `sorpia render --fair`'s figure) unless --no-page.

    python bench/fair.py [--shared ../shared/meshes] [--sizes 10000,100000] [--no-page]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.spatial

import sorpia
from sorpia.cli.demo import sample_mesh

sys.path.insert(0, os.path.dirname(__file__))
from _report import PAGES, write_page  # noqa: E402

# Dunavant's degree-4 rule on the triangle u, v >= 0, u + v <= 1 (weights sum to 1/2).
_A, _B = 0.445948490915965, 0.091576213509771
_WA, _WB = 0.223381589678011 / 2, 0.109951743655322 / 2
TRI_POINTS = np.array([[_A, _A], [1 - 2 * _A, _A], [_A, 1 - 2 * _A], [_B, _B], [1 - 2 * _B, _B], [_B, 1 - 2 * _B]])
TRI_WEIGHTS = np.array([_WA] * 3 + [_WB] * 3)
_G = np.array([0.5 - np.sqrt(0.15), 0.5, 0.5 + np.sqrt(0.15)])
_GW = np.array([5, 8, 5]) / 18
QUAD_POINTS = np.array([[u, v] for u in _G for v in _G])
QUAD_WEIGHTS = np.array([a * b for a in _GW for b in _GW])


def diagonal(v) -> float:
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))


def mean_curvature_integral(res, vertices_list):
    """(int H^2 dA, the same without the 1% of faces of largest int H^2, the
    median of H^2 over the points) of the limit surface
    of each (n_fine, 3) control mesh in `vertices_list` on the fine mesh of
    `res`, by the Gauss points of every face that is not a hole (the rows
    computed once for all). The integral is dominated by a few points where
    a surface through noisy points nearly folds (|S_u x S_v| small, H large):
    the median says how the bulk of the surface bends."""
    faces = np.asarray(res.faces)
    tri = faces.shape[1] == 3
    pts, wts = (TRI_POINTS, TRI_WEIGHTS) if tri else (QUAD_POINTS, QUAD_WEIGHTS)
    keep = np.setdiff1d(np.arange(len(faces)), res.holes if res.holes is not None else [])
    face_ids = np.repeat(keep, len(pts)).astype(np.int32)
    uv = np.tile(pts, (len(keep), 1))
    w = np.tile(wts, len(keep))
    surface = sorpia.LimitSurface(vertices_list[0], res.faces, scheme=res.scheme, boundary=res.boundary, **res.tags)
    rows = surface.rows(face_ids, uv, derivatives=2)
    out = []
    for v in vertices_list:
        _, su, sv, suu, suv, svv = (r @ v for r in rows)
        n = np.cross(su, sv)
        area = np.linalg.norm(n, axis=1)
        n = n / np.maximum(area, 1e-300)[:, None]
        e, f, g = (su * su).sum(1), (su * sv).sum(1), (sv * sv).sum(1)
        l, m, nn = (suu * n).sum(1), (suv * n).sum(1), (svv * n).sum(1)
        det = np.maximum(e * g - f * f, 1e-300)
        h = (e * nn - 2 * f * m + g * l) / (2 * det)
        per_face = np.sort(np.bincount(face_ids, weights=w * h * h * area))
        trimmed = float(per_face[:len(per_face) - max(1, len(keep) // 100)].sum())
        out.append((float(np.sum(w * h * h * area)), trimmed, float(np.median(h * h))))
    return out


def _closest_on_triangles(p, a, b, c):
    """Closest points to p on triangles (a, b, c), all (k, 3) (Ericson, Real-Time Collision Detection 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp = p - b
    d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    cp = p - c
    d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = va + vb + vc
    denom = np.where(denom == 0, 1.0, denom)
    v, w = vb / denom, vc / denom
    out = a + ab * v[:, None] + ac * w[:, None]  # inside the face
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ab = np.clip(d1 / (d1 - d3), 0, 1)
        t_ac = np.clip(d2 / (d2 - d6), 0, 1)
        t_bc = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
    cases = [
        (vc <= 0) & (d1 >= 0) & (d3 <= 0), a + ab * np.nan_to_num(t_ab)[:, None],
        (vb <= 0) & (d2 >= 0) & (d6 <= 0), a + ac * np.nan_to_num(t_ac)[:, None],
        (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), b + (c - b) * np.nan_to_num(t_bc)[:, None],
    ]
    for mask, point in zip(cases[::2], cases[1::2]):
        out = np.where(mask[:, None], point, out)
    for mask, point in (((d1 <= 0) & (d2 <= 0), a), ((d3 >= 0) & (d4 <= d3), b), ((d6 >= 0) & (d5 <= d6), c)):
        out = np.where(mask[:, None], point, out)
    return out


def distance_to_faces(points, vertices, faces, k=12):
    """The distance from each point to the nearest of the faces (fans of
    triangles), among the k triangles whose centroids are nearest."""
    rows = [list(f) for f in (faces.tolist() if isinstance(faces, np.ndarray) else faces)] \
        if not isinstance(faces, sorpia.Polygons) else np.split(faces.face_vertex_indices,
                                                                np.cumsum(faces.face_vertex_counts)[:-1])
    tris = np.array([[f[0], f[j], f[j + 1]] for f in rows for j in range(1, len(f) - 1)])
    a, b, c = vertices[tris[:, 0]], vertices[tris[:, 1]], vertices[tris[:, 2]]
    tree = scipy.spatial.cKDTree((a + b + c) / 3)
    _, near = tree.query(points, k=min(k, len(tris)))
    best = np.full(len(points), np.inf)
    for j in range(near.shape[1]):
        t = near[:, j]
        q = _closest_on_triangles(points, a[t], b[t], c[t])
        best = np.minimum(best, np.linalg.norm(points - q, axis=1))
    return best


def has_semi_sharp(tags) -> bool:
    """Whether the tags hold a sharpness in (0, INFINITE_SHARPNESS)."""
    return any(t is not None and np.any((np.asarray(t[1]) > 0) & (np.asarray(t[1]) < sorpia._core.INFINITE_SHARPNESS))
               for t in (tags.get("creases"), tags.get("corners")))


def measure(name, v, f, scheme, tags, two_levels: bool):
    """One mesh: the figures of plain and fair interpolation, side by side
    (the energy ratio two levels finer where `two_levels`; fair with
    semi_sharp="as-tagged" where the mesh has semi-sharp tags)."""
    v = np.asarray(v, float)
    res = sorpia.fair_interpolate(v, f, scheme=scheme, **tags)
    ratio2 = None
    if two_levels:
        res2 = sorpia.fair_interpolate(v, f, scheme=scheme, levels=2, **tags)
        ratio2 = res2.energy / res2.plain_energy
    plain_fine = res.refinement @ np.asarray(res.plain.control_vertices)
    controls = [plain_fine, res.control_vertices]
    metric = sorpia.fair_interpolate(v, f, scheme=scheme, metric="reference", **tags)
    controls.append(metric.control_vertices)
    tagged = sorpia.fair_interpolate(v, f, scheme=scheme, semi_sharp="as-tagged", depth=4, **tags) \
        if has_semi_sharp(tags) else None
    if tagged is not None:
        controls.append(tagged.control_vertices)
    curvature = mean_curvature_integral(res, controls)
    k_param = sorpia.fairness_matrix(res.faces, len(plain_fine), scheme=res.scheme, boundary=res.boundary, depth=0,
                                     **res.tags)  # fair_interpolate's default K
    surface = sorpia.LimitSurface(plain_fine, res.faces, scheme=res.scheme, boundary=res.boundary, **res.tags)
    dist = []
    for ctrl in controls:
        surface.set_vertices(ctrl)
        points, _ = surface.tessellate(2)
        dist.append(float(distance_to_faces(points, v, f).max()) / diagonal(v))
    (h_plain, t_plain, m_plain), (h_fair, t_fair, m_fair) = curvature[:2]
    row = {"mesh": name, "scheme": scheme, "vertices": len(v), "fine_faces": len(res.faces),
           "plain_energy": res.plain_energy, "fair_energy": res.energy, "energy_ratio": res.energy / res.plain_energy,
           "plain_h2": h_plain, "fair_h2": h_fair, "h2_ratio": h_fair / h_plain,
           "trimmed_h2_ratio": t_fair / t_plain, "median_h2_ratio": m_fair / m_plain,
           "energy_ratio_2": ratio2,
           "plain_distance": dist[0], "fair_distance": dist[1], "iterations": res.iterations,
           "max_error_relative": res.max_error_relative, "seconds": res.seconds, "tagged": None}
    for key, result, i in (("metric", metric, 2), ("tagged", tagged, 3)):
        if result is not None:
            h, t, m = curvature[i]
            row[key] = {"energy_ratio": result.energy / result.plain_energy, "h2_ratio": h / h_plain,
                        "trimmed_h2_ratio": t / t_plain, "median_h2_ratio": m / m_plain, "distance": dist[i],
                        "parametric_ratio": float(np.sum(result.control_vertices * (k_param @ result.control_vertices))
                                                  / res.plain_energy)}
    return row


def freedom(name, v, f, scheme, tags, three_levels: bool):
    """What more freedom buys: the thin-plate energy ratio fair / plain (K of
    each fine mesh with its defaults, thin plate alone) one, two and three
    (where `three_levels`) levels finer; one level finer with a membrane term
    of weight 0.1 (its thin-plate energy: the membrane only adds a
    different term); and with every other vertex a target (the others free;
    plain still interpolates them all), with the largest distance of a
    vertex left free from the fair surface over the diagonal."""
    v = np.asarray(v, float)
    out = {"mesh": name}
    for levels in (1, 2, 3) if three_levels else (1, 2):
        res = sorpia.fair_interpolate(v, f, scheme=scheme, levels=levels, **tags)
        out[f"levels_{levels}"] = res.energy / res.plain_energy
    res = sorpia.fair_interpolate(v, f, scheme=scheme, membrane=0.1, **tags)
    k = sorpia.fairness_matrix(res.faces, len(res.control_vertices), scheme=res.scheme, boundary=res.boundary,
                               depth=0, **res.tags)  # fair_interpolate's K: its default depth
    plain_fine = res.refinement @ np.asarray(res.plain.control_vertices)
    out["membrane"] = float(np.sum(res.control_vertices * (k @ res.control_vertices)) /
                            np.sum(plain_fine * (k @ plain_fine)))
    targets = np.arange(0, len(v), 2)
    res = sorpia.fair_interpolate(v, f, scheme=scheme, targets=targets, **tags)
    out["half"] = res.energy / res.plain_energy
    free = np.setdiff1d(np.arange(len(v)), targets)
    surface = sorpia.LimitSurface(res.control_vertices, res.faces, scheme=res.scheme, boundary=res.boundary,
                                  **res.tags)
    points, _ = surface.tessellate(2)
    gap = scipy.spatial.cKDTree(points).query(v[free])[0]
    out["half_free_distance"] = float(gap.max()) / diagonal(v)
    return out


def _bspline_hat(w):
    """Fourier transform of the uniform cubic B-spline of unit knot spacing."""
    x = np.asarray(w, float) / 2
    safe = np.where(x == 0, 1.0, x)
    return np.where(x == 0, 1.0, np.sin(safe) / safe) ** 4


def regular_grid_bound(levels, spectrum, n_modes=24, aliases=40):
    """The thin-plate energy ratio fair / plain for interpolation at every
    vertex of an infinite (periodic) regular Catmull-Clark grid, data with
    the given power spectrum(xi, eta) over the modes of the grid, summed over
    n_modes^2 modes. Levels = None: the infimum over all functions, what any
    number of levels approaches. Per mode (xi, eta) the data sampled at the
    integers is met by the bicubic splines of spacing 2^-levels through
    frequencies xi + 2 pi m; the energy is diagonal over the 4^levels classes
    of aliases, so the least energy of an interpolant is 1 / sum_r (b_r^2 /
    A_r), b_r the sum of the B-spline transforms in class r, A_r that of their
    squares times |omega|^4 (plain: levels 0, one class)."""
    xs = -np.pi + (np.arange(n_modes) + 0.5) * 2 * np.pi / n_modes

    def least(xi, eta, lv):
        if lv is None:  # any function: sum over aliases of |omega|^-4
            m = np.arange(-400, 401) * 2 * np.pi
            w1, w2 = np.meshgrid(xi + m, eta + m, indexing="ij")
            return 1.0 / np.sum(1.0 / (w1 ** 2 + w2 ** 2) ** 2)
        n = 2 ** lv
        m = np.arange(-aliases * n, aliases * n)
        w1, w2 = xi + 2 * np.pi * m, eta + 2 * np.pi * m
        b = np.outer(_bspline_hat(w1 / n), _bspline_hat(w2 / n))
        cls = ((m % n)[:, None] * n + (m % n)[None, :]).ravel()
        wsq = (w1[:, None] ** 2 + w2[None, :] ** 2) ** 2
        bs = np.bincount(cls, b.ravel(), n * n)
        a = np.bincount(cls, (b * b * wsq).ravel(), n * n)
        return 1.0 / np.sum(bs ** 2 / a)

    plain = fair = 0.0
    for xi in xs:
        for eta in xs:
            p = spectrum(xi, eta)
            plain += p * least(xi, eta, 0)
            fair += p * least(xi, eta, levels)
    return fair / plain


def meshes(shared: Path | None, max_shared: int):
    """(name, vertices, faces, scheme, tags) of every mesh measured."""
    rng = np.random.default_rng(2026)
    for scheme in ("loop", "catmull-clark"):
        v, f = sample_mesh(scheme)
        yield f"demo ({scheme})", v, f, scheme, {}
    if shared is not None and shared.is_dir():
        for path in sorted(shared.glob("*.obj")) + sorted(shared.glob("*.off")):
            if "nonman" in path.name:
                continue
            try:
                v, f, tags = sorpia.read_mesh(path, tags=True)
            except ValueError:
                continue
            if len(v) > max_shared or len(v) < 20:
                continue
            scheme = "catmull-clark" if "catmark" in path.name or "quads" in path.name else "loop"
            tags = {k: t for k, t in tags.items() if k in ("creases", "corners", "holes", "boundary")}
            try:
                sorpia.limit_points(v, f, scheme=scheme, **tags)  # a mesh the library refuses is left out
            except (ValueError, sorpia.MeshError):
                continue
            yield path.name, v, f, scheme, tags
    for noise in (0.01, 0.03):
        v, f = sorpia.shapes.icosphere(3)
        yield f"icosphere(3), noise {noise}", v + noise * rng.standard_normal(v.shape), f, "loop", {}
        v, f = sorpia.shapes.irregular(2000, seed=4)
        v = np.asarray(v, float)
        yield f"irregular(2000), noise {noise}", v + noise * rng.standard_normal(v.shape), f, "loop", {}
        v, f = sorpia.shapes.quad_torus(32, 16)
        v = np.asarray(v, float)
        yield f"quad_torus(32, 16), noise {noise}", v + noise * rng.standard_normal(v.shape), f, "catmull-clark", {}
        v, f = sorpia.shapes.quad_irregular(2000, seed=4)
        v = np.asarray(v, float)
        yield f"quad_irregular(2000), noise {noise}", v + noise * rng.standard_normal(v.shape), f, "catmull-clark", {}


def timing(n, scheme, threads, repeats=3):
    """Seconds of plain interpolation (median of 2 * `repeats` runs) and of
    fair interpolation (median of `repeats` runs, each phase its own median)
    of a noisy generated mesh of about n vertices, plain and fair on the same
    `threads`. One thread: the process also pinned to one processor for the
    measurement (`threads` caps the solves, K's assembly and Bfr's
    evaluation; the pin keeps anything else on one processor too)."""
    rng = np.random.default_rng(n)
    v, f = (sorpia.shapes.irregular if scheme == "loop" else sorpia.shapes.quad_irregular)(n, seed=1)
    v = np.asarray(v, float)
    v = v + 0.2 * np.mean(np.linalg.norm(v[np.asarray(f)[:, 0]] - v[np.asarray(f)[:, 1]], axis=1)) * \
        rng.standard_normal(v.shape)
    processors = os.sched_getaffinity(0)
    if threads == 1:
        os.sched_setaffinity(0, {min(processors)})
    try:
        plain, fair = [], []
        for _ in range(repeats):
            for _ in range(2):
                t = time.perf_counter()
                sorpia.interpolate(v, f, scheme=scheme, threads=threads)
                plain.append(time.perf_counter() - t)
            res = sorpia.fair_interpolate(v, f, scheme=scheme, threads=threads)
            fair.append({"fair_seconds": res.seconds, **res.timings})
    finally:
        os.sched_setaffinity(0, processors)
    phases = {k: float(np.median([r[k] for r in fair])) for k in fair[0]}
    phases["rest"] = phases["fair_seconds"] - sum(phases[k] for k in ("refine", "plain", "energy", "setup", "solve"))
    return {"scheme": scheme, "vertices": len(v), "fine_faces": len(res.faces), "threads": threads,
            "plain_seconds": float(np.median(plain)), "ratio": phases["fair_seconds"] / float(np.median(plain)),
            "iterations": res.iterations, **phases}


def figure(path: Path):
    """Plain and fair interpolation of the demo mesh side by side (`sorpia render --fair`'s panels)."""
    from sorpia._plotting import interpolation_figure

    v, f = sample_mesh("loop")
    res = sorpia.fair_interpolate(v, f)
    plain = np.asarray(res.plain.control_vertices)
    surface = sorpia.LimitSurface(v, f)
    given = surface.tessellate(3)
    surface.set_vertices(plain)
    fitted = surface.tessellate(3)
    fine = sorpia.LimitSurface(res.control_vertices, res.faces, **res.tags).tessellate(2)
    fig = interpolation_figure(v, f, given, plain, fitted, size=(1200, 1000), title="sorpia demo mesh: plain "
                               "against fair interpolation (Loop)", iterations=int(res.plain.iterations), level=3,
                               fair=(res.control_vertices, res.faces, fine, 1))
    fig.savefig(path, dpi=100)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shared", type=Path,
                        default=Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes")
    parser.add_argument("--max-shared", type=int, default=4000, help="largest shared mesh measured (vertices)")
    parser.add_argument("--max-two-levels", type=int, default=1000,
                        help="largest mesh also measured two levels finer (vertices)")
    parser.add_argument("--max-three-levels", type=int, default=400,
                        help="largest mesh also measured three levels finer (vertices)")
    parser.add_argument("--sizes", default="10000,100000", help="vertex counts of the timed meshes")
    parser.add_argument("--threads", default="1,2", help="thread counts of the timed runs")
    parser.add_argument("--repeats", type=int, default=3, help="fair runs per timed mesh (plain: twice as many)")
    parser.add_argument("--no-page", action="store_true")
    args = parser.parse_args(argv)

    rows, free = [], []
    for name, v, f, scheme, tags in meshes(args.shared, args.max_shared):
        r = measure(name, v, f, scheme, tags, two_levels=len(v) <= args.max_two_levels)
        rows.append(r)
        print(f"{name}: energy {r['energy_ratio']:.3f}, H^2 {r['h2_ratio']:.3f}, distance {r['plain_distance']:.2e} "
              f"-> {r['fair_distance']:.2e}, {r['seconds']:.2f} s", file=sys.stderr, flush=True)
        if len(v) <= args.max_two_levels:
            free.append(freedom(name, v, f, scheme, tags, three_levels=len(v) <= args.max_three_levels))
    bounds = {label: [regular_grid_bound(levels, spectrum) for levels in (1, 2, 3, None)]
              for label, spectrum in (("white noise", lambda a, b: 1.0),
                                      ("smooth (power falling as k^-4)", lambda a, b: 1.0 / (a * a + b * b) ** 2))}
    times = []
    for n in (int(s) for s in args.sizes.split(",") if s):
        for scheme in ("loop", "catmull-clark"):
            for threads in (int(s) for s in args.threads.split(",") if s):
                t = timing(n, scheme, threads, args.repeats)
                times.append(t)
                print(f"time {scheme} {n}, {threads} thread(s): plain {t['plain_seconds']:.3f} s, fair "
                      f"{t['fair_seconds']:.2f} s ({t['ratio']:.0f}x)", file=sys.stderr, flush=True)

    energy = np.array([r["energy_ratio"] for r in rows])
    h2 = np.array([r["h2_ratio"] for r in rows])
    th2 = np.array([r["trimmed_h2_ratio"] for r in rows])
    mh2 = np.array([r["median_h2_ratio"] for r in rows])
    dist = np.array([r["fair_distance"] / r["plain_distance"] for r in rows])
    two = np.array([r["energy_ratio_2"] for r in rows if r["energy_ratio_2"] is not None])
    tagged = [r for r in rows if r["tagged"] is not None]
    lines = [
        "Fair interpolation (`sorpia.fair_interpolate`, one level finer, thin plate alone, every vertex a target, "
        "its defaults) against plain interpolation (`sorpia.interpolate`), both on the same fine mesh: plain's "
        "control mesh refined once by the same refinement (the same surface). Energy: the thin-plate energy "
        "tr(V^T K V) with K from `sorpia.fairness_matrix` of the fine mesh as fair interpolation takes it "
        "(semi-sharp creases and corners taken as infinitely sharp, depth 0), what fair interpolation minimises; "
        "H^2: the integral of the squared mean curvature by Gauss points in every fine face, also without each "
        "surface's 1% of faces of largest int H^2 (near-folds of surfaces through noisy points dominate the whole "
        "integral), and the ratio of the medians of H^2 over the points; distance: the largest distance of the "
        "surface (the fine mesh tessellated twice) from the input mesh's faces, over the bounding-box diagonal. "
        "Ratios are fair / plain.",
        "",
        f"**Median energy ratio {np.median(energy):.3f}** (goal: at most 0.5), largest {energy.max():.3f} "
        f"(goal: below 1 on every mesh); two levels finer (meshes up to {args.max_two_levels} vertices) median "
        f"{np.median(two) if len(two) else float('nan'):.3f}. int H^2 dA ratio: median {np.median(h2):.3f}, "
        f"largest {h2.max():.3f}; without each surface's 1% worst faces: median {np.median(th2):.3f}, largest "
        f"{th2.max():.3f}; the ratio of the pointwise medians of H^2: median {np.median(mh2):.3f}, largest "
        f"{mh2.max():.3f}. Distance ratio: median {np.median(dist):.3f}, largest {dist.max():.3f}. "
        f"The targets are met to {max(r['max_error_relative'] for r in rows):.1e} of the diagonal at most.",
        "",
        "| mesh | scheme | vertices | fine faces | energy plain | energy fair | ratio | ratio, 2 levels | "
        "int H^2 plain | int H^2 fair | ratio | ratio, 99% of faces | median H^2 ratio | distance plain | "
        "distance fair | iterations | seconds |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        two_text = "" if r["energy_ratio_2"] is None else f"{r['energy_ratio_2']:.3f}"
        lines.append(f"| {r['mesh']} | {r['scheme']} | {r['vertices']} | {r['fine_faces']} | {r['plain_energy']:.4g} "
                     f"| {r['fair_energy']:.4g} | {r['energy_ratio']:.3f} | {two_text} | {r['plain_h2']:.4g} | "
                     f"{r['fair_h2']:.4g} | {r['h2_ratio']:.3f} | {r['trimmed_h2_ratio']:.3f} | "
                     f"{r['median_h2_ratio']:.3f} | {r['plain_distance']:.2e} | {r['fair_distance']:.2e} | "
                     f"{r['iterations']} | {r['seconds']:.2f} |")
    lines += [
        "",
        "## Semi-sharp creases",
        "",
        "The meshes with semi-sharp tags, fair interpolation with `semi_sharp=\"as-tagged\", depth=4` (the energy "
        "of the surface as tagged, the thin layer where a crease of sharpness s turns, about 2^-s of a face wide, "
        "included and integrated down to level 4: the behaviour before both options) against the defaults "
        "(`\"sharp\"`: the bending on each side of the crease; depth 0). With depth 0 alone the Gauss rule "
        "hardly sees a layer of sharpness above 3 or so; `\"sharp\"` makes the measure independent of the "
        "rule, and matters where the layer is wide (Loop cubes_semisharp). Ratios against plain interpolation; "
        "each energy ratio by its own K.",
        "",
        "| mesh | energy ratio before | now | int H^2 ratio before | now | 99% of faces before | now "
        "| median H^2 ratio before | now | distance before | now | plain |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in tagged:
        t = r["tagged"]
        lines.append(f"| {r['mesh']} | {t['energy_ratio']:.3f} | {r['energy_ratio']:.3f} | {t['h2_ratio']:.3f} | "
                     f"{r['h2_ratio']:.3f} | {t['trimmed_h2_ratio']:.3f} | {r['trimmed_h2_ratio']:.3f} | "
                     f"{t['median_h2_ratio']:.3f} | {r['median_h2_ratio']:.3f} | {t['distance']:.2e} | "
                     f"{r['fair_distance']:.2e} | {r['plain_distance']:.2e} |")
    lines += [
        "",
        "## A metric per face",
        "",
        "Fair interpolation with `metric=\"reference\"` (each face measured in the first fundamental form of the "
        "input mesh's own limit surface at its centre; the parametric shape scaled to that area at faces with an "
        "extraordinary corner; see docs/fair.md) against the default `\"parameter\"`, ratios against plain "
        "interpolation: its own energy (by its K), the parametric energy (by the default K), int H^2, the same "
        "without each surface's 1% worst faces, the median of H^2, the distance from the input's faces.",
        "",
        "| mesh | own energy | parametric energy | default | int H^2 | default | 99% of faces | default | "
        "median H^2 | default | distance | default |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        m = r["metric"]
        lines.append(f"| {r['mesh']} | {m['energy_ratio']:.3f} | {m['parametric_ratio']:.3f} | "
                     f"{r['energy_ratio']:.3f} | {m['h2_ratio']:.3f} | {r['h2_ratio']:.3f} | "
                     f"{m['trimmed_h2_ratio']:.3f} | {r['trimmed_h2_ratio']:.3f} | {m['median_h2_ratio']:.3f} | "
                     f"{r['median_h2_ratio']:.3f} | {m['distance'] / r['plain_distance']:.3f} | "
                     f"{r['fair_distance'] / r['plain_distance']:.3f} |")
    stats = {k: np.array([r["metric"][k] for r in rows]) for k in ("energy_ratio", "parametric_ratio", "h2_ratio",
                                                                     "trimmed_h2_ratio", "median_h2_ratio")}
    mdist = np.array([r["metric"]["distance"] / r["plain_distance"] for r in rows])
    for label, fn in (("median", np.median), ("largest", np.max)):
        lines.append(f"| {label} | {fn(stats['energy_ratio']):.3f} | {fn(stats['parametric_ratio']):.3f} | "
                     f"{fn(energy):.3f} | {fn(stats['h2_ratio']):.3f} | {fn(h2):.3f} | "
                     f"{fn(stats['trimmed_h2_ratio']):.3f} | {fn(th2):.3f} | {fn(stats['median_h2_ratio']):.3f} | "
                     f"{fn(mh2):.3f} | {fn(mdist):.3f} | {fn(dist):.3f} |")
    cols = [("levels_1", "1 level"), ("levels_2", "2 levels"), ("levels_3", "3 levels"),
            ("membrane", "membrane 0.1"), ("half", "half the targets")]
    lines += [
        "",
        "## What more freedom buys",
        "",
        f"Thin-plate energy ratio fair / plain on the meshes up to {args.max_two_levels} vertices (three levels: up "
        f"to {args.max_three_levels}): more levels; a membrane term of weight 0.1 (its thin-plate energy: the "
        "membrane trades bending for area); every other vertex a target (the others free, so the surface need not "
        "pass through them: the last column is the largest distance of a freed vertex from the fair surface over "
        "the diagonal).",
        "",
        "| mesh | " + " | ".join(c[1] for c in cols) + " | freed vertex distance |",
        "|---|" + "---|" * (len(cols) + 1),
    ]
    for r in free:
        lines.append(f"| {r['mesh']} | " + " | ".join(f"{r[c]:.3f}" if c in r else "" for c, _ in cols) +
                     f" | {r['half_free_distance']:.2e} |")
    med = {c: np.median([r[c] for r in free if c in r]) for c, _ in cols}
    lines.append("| median | " + " | ".join(f"{med[c]:.3f}" for c, _ in cols) + " | |")
    lines += [
        "",
        "The bound on a regular grid: on an infinite regular Catmull-Clark grid (periodic), every vertex a target, "
        "the least thin-plate energy of a bicubic spline of spacing 2^-L through the data, per Fourier mode of the "
        "data, against plain interpolation (L = 0), summed over the modes (`regular_grid_bound`); infinity: the "
        "least energy of any function through the data, which no number of levels beats. In one dimension the "
        "ratio is exactly 1 at every level: the cubic spline with knots at the data (plain interpolation of a "
        "uniform cubic B-spline curve) already has the least int f''^2 of all interpolants.",
        "",
        "| data | 1 level | 2 levels | 3 levels | any function |",
        "|---|---|---|---|---|",
    ]
    for label, b in bounds.items():
        lines.append(f"| {label} | " + " | ".join(f"{x:.3f}" for x in b) + " |")
    lines += [
        "",
        "## Time",
        "",
        "Noisy generated meshes (`shapes.irregular` for Loop, `shapes.quad_irregular` for Catmull-Clark, each "
        "vertex moved by 0.2 of the mean edge length), plain and fair on the same threads; one thread: the process "
        "also pinned to one processor (`threads` caps fair interpolation's solve, its fairness matrix's assembly "
        "and Bfr's evaluation; the pin keeps anything else on one processor too). Plain: `sorpia.interpolate`, "
        "median of "
        f"{2 * args.repeats} runs. Fair: `sorpia.fair_interpolate` (goal: at most 10 times plain at 100k targets), "
        f"median of {args.repeats} runs, and the median of each phase: refine (Far's refinement and the start R "
        "V_plain by Far's PrimvarRefiner; R itself is built only when `FairResult.refinement` is read), plain (the "
        "plain solve it starts from), energy (K of the fine mesh), setup (the fine mesh's B, the elimination, the "
        "preconditioner), solve (the conjugate gradients), rest (the fine mesh's topology, checks).",
        "",
        "| scheme | vertices | fine faces | threads | plain s | fair s | fair / plain | refine | plain | energy | "
        "setup | solve | rest | iterations |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for t in times:
        lines.append(f"| {t['scheme']} | {t['vertices']} | {t['fine_faces']} | {t['threads']} | "
                     f"{t['plain_seconds']:.3f} | {t['fair_seconds']:.2f} | {t['ratio']:.0f} | {t['refine']:.2f} | "
                     f"{t['plain']:.2f} | {t['energy']:.2f} | {t['setup']:.2f} | {t['solve']:.2f} | "
                     f"{t['rest']:.2f} | {t['iterations']} |")
    lines += ["", "![plain and fair interpolation of the demo mesh](fair.png)"]
    if not args.no_page:
        figure(PAGES / "fair.png")
        write_page("fair", "Fair interpolation against plain", "\n".join(lines), settings=(parser, args))
    else:
        print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
