"""The fairness matrix K (sorpia.fairness_matrix): its quadrature error and its
assembly time.

1. Quadrature error: the thin-plate energy V^T K V of each mesh's own
   vertices at depth 0..6 (splits towards irregular corners) and 2..6 Gauss
   points, against a much finer rule (depth 9, 8 x 8 points), relative.
2. The rings at an extraordinary vertex: the thin-plate energy of the
   polynomial pieces of Bfr's surface in the L-shaped ring at distance 2^-l
   from a corner of valence n (Catmull-Clark) for l = 2..4, from
   LimitSurface.rows with 8 x 8 Gauss points per piece: the ratio between
   rings tends to 4 lambda^2 (lambda the subdominant eigenvalue), so that
   the integral over all rings of the exact limit surface diverges where
   lambda > 1/2. The same under Loop.
3. Assembly time against mesh size (medians of --repeat runs), both schemes,
   the default rule: irregular meshes, the same refined once (the fine mesh of
   fair interpolation), and a regular quad torus; element matrices shared
   between faces of one local topology against every face on its own.
Writes docs/benchmarks/energy.md (unless --no-page).

    python bench/energy.py [--sizes 2000,10000] [--repeat 3] [--alone-up-to N] [--times-only] [--no-page]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

import sorpia

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402


def cube():
    v = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], dtype=float)
    f = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]])
    return v, f


def error_meshes():
    return [("cube (CC, valence 3)", *cube(), "catmull-clark"),
            ("quad_irregular 300 (CC)", *sorpia.shapes.quad_irregular(300, 2), "catmull-clark"),
            ("polygon_torus 8x6 (CC, n-gons)", *sorpia.shapes.polygon_torus(8, 6), "catmull-clark"),
            ("icosphere 1 (Loop, valence 5)", *sorpia.shapes.icosphere(1), "loop"),
            ("irregular 300 (Loop)", *sorpia.shapes.irregular(300, 2), "loop")]


def quadrature_errors():
    depths, points = [0, 1, 2, 3, 4, 5, 6], [2, 3, 4, 5, 6]
    rows = []
    for name, v, f, scheme in error_meshes():
        fine = sorpia.thin_plate_energy(v, f, scheme=scheme, depth=9, gauss_points=8)
        by_depth = [abs(sorpia.thin_plate_energy(v, f, scheme=scheme, depth=d) / fine - 1) for d in depths]
        by_points = [abs(sorpia.thin_plate_energy(v, f, scheme=scheme, gauss_points=g) / fine - 1) for g in points]
        rows.append((name, fine, by_depth, by_points))
        print(name, f"{fine:.6g}", " ".join(f"{e:.1e}" for e in by_depth), "|",
              " ".join(f"{e:.1e}" for e in by_points), flush=True)
    head = "| mesh | energy (fine) | " + " | ".join(f"depth {d}" for d in depths) + " |\n"
    head += "|---" * (len(depths) + 2) + "|\n"
    body = "".join(f"| {n} | {e:.6g} | " + " | ".join(f"{x:.1e}" for x in d) + " |\n" for n, e, d, _ in rows)
    head2 = "| mesh | " + " | ".join(f"{g} points" for g in points) + " |\n" + "|---" * (len(points) + 1) + "|\n"
    body2 = "".join(f"| {n} | " + " | ".join(f"{x:.1e}" for x in p) + " |\n" for n, _, _, p in rows)
    return (f"Relative error of the thin-plate energy of each mesh's own vertices against depth 9 with 8 x 8 "
            f"points; by depth (4 x 4 points):\n\n{head}{body}\nby Gauss points (depth 4):\n\n{head2}{body2}")


def ring_energies(valence: int, levels=(2, 3, 4)):
    """Thin-plate energy of the L-shaped rings at a valence-`valence` corner, summed over the faces at that corner:
    each ring's three squares of side 2^-l integrated with 8 x 8 points. The mesh: `shapes.pole(valence)` refined
    once by Catmull-Clark (quads; its centre keeps valence n), so that from level 2 on the corner's quadrant sees
    no other extraordinary vertex and its rings are polynomial pieces of Bfr's surface (levels 1..4)."""
    tv, tf = sorpia.shapes.pole(valence)
    centre = int(np.argmax(np.bincount(np.asarray(tf).ravel())))
    v, quads = sorpia.LimitSurface(tv, tf, scheme="catmull-clark").tessellate(1)
    quads = np.asarray(quads)
    surface = sorpia.LimitSurface(v, quads, scheme="catmull-clark")
    x, w = np.polynomial.legendre.leggauss(8)
    x, w = (x + 1) / 2, w / 2
    gu, gv = (g.ravel() for g in np.meshgrid(x, x, indexing="ij"))
    gw = np.outer(w, w).ravel()
    corner_uv = {0: (0, 0), 1: (1, 0), 2: (1, 1), 3: (0, 1)}
    faces = [i for i in range(len(quads)) if centre in quads[i]]
    out = []
    for level in levels:
        h = 0.5 ** level
        e = 0.0
        for fi in faces:
            cu, cv = corner_uv[list(quads[fi]).index(centre)]
            for du, dv in [(1, 0), (1, 1), (0, 1)]:  # the ring's three squares, offsets from the corner
                uv = np.column_stack([np.abs(cu - h * (du + gu)), np.abs(cv - h * (dv + gv))])
                rows = surface.rows(np.full(len(uv), fi), uv, derivatives=2)
                duu, duv, dvv = (r @ v for r in rows[3:])
                dens = (duu ** 2).sum(1) + 2 * (duv ** 2).sum(1) + (dvv ** 2).sum(1)
                e += h * h * float(gw @ dens)
        out.append(e)
    return out


def loop_ring_energies(valence: int, levels=(2, 3, 4)):
    """The same under Loop at the centre of `shapes.pole(valence)`: ring l the three triangles of the corner
    triangle of level l - 1 other than its own corner triangle, 8 x 8 collapsed Gauss points each, in the
    equilateral measure of sorpia.energy."""
    v, f = sorpia.shapes.pole(valence)
    f = np.asarray(f)
    centre = int(np.argmax(np.bincount(f.ravel())))
    surface = sorpia.LimitSurface(v, f, scheme="loop")
    x, w = np.polynomial.legendre.leggauss(8)
    x, w = (x + 1) / 2, w / 2
    s, t = np.meshgrid(x, x, indexing="ij")
    weights = (np.outer(w, w) * (1 - s)).ravel()
    s, t = s.ravel(), t.ravel() * (1 - s.ravel())
    corners = [np.array(c, float) for c in ((0, 0), (1, 0), (0, 1))]
    out = []
    for level in levels:
        e = 0.0
        for fi in range(len(f)):
            if centre not in f[fi]:
                continue
            j = list(f[fi]).index(centre)
            a, b, c = corners[j], corners[(j + 1) % 3], corners[(j + 2) % 3]
            h = 0.5 ** (level - 1)
            b, c = a + h * (b - a), a + h * (c - a)
            ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
            for p, q, r in [(ab, b, bc), (ca, bc, c), (bc, ca, ab)]:
                uv = p + s[:, None] * (q - p) + t[:, None] * (r - p)
                area2 = abs((q - p)[0] * (r - p)[1] - (q - p)[1] * (r - p)[0])
                rows = surface.rows(np.full(len(uv), fi), uv, derivatives=2)
                uu, uvd, vv = (m @ v for m in rows[3:])
                xx, xy, yy = uu, (2 * uvd - uu) / np.sqrt(3), (uu - 4 * uvd + 4 * vv) / 3
                dens = (xx ** 2).sum(1) + 2 * (xy ** 2).sum(1) + (yy ** 2).sum(1)
                e += float(weights @ dens) * area2 * np.sqrt(3) / 2
        out.append(e)
    return out


def loop_ring_table():
    lines = ["| valence | 4 lambda^2 | ring 2 | ring 3 | ring 4 | ratio 4/3 |", "|---|---|---|---|---|---|"]
    for n in (4, 5, 7, 8, 10):
        lam = 3 / 8 + np.cos(2 * np.pi / n) / 4  # Loop's subdominant eigenvalue
        e = loop_ring_energies(n)
        lines.append(f"| {n} | {4 * lam * lam:.3f} | {e[0]:.4g} | {e[1]:.4g} | {e[2]:.4g} | {e[2] / e[1]:.3f} |")
        print(lines[-1], flush=True)
    return "\n".join(lines) + "\n"


def ring_table():
    lines = ["| valence | 4 lambda^2 | ring 2 | ring 3 | ring 4 | ratio 4/3 |", "|---|---|---|---|---|---|"]
    for n in (3, 5, 6, 8):
        c = np.cos(2 * np.pi / n)
        lam = (5 + c + np.cos(np.pi / n) * np.sqrt(2 * (9 + c))) / 16  # Catmull-Clark's subdominant eigenvalue
        e = ring_energies(n)
        lines.append(f"| {n} | {4 * lam * lam:.3f} | {e[0]:.4g} | {e[1]:.4g} | {e[2]:.4g} | {e[2] / e[1]:.3f} |")
        print(lines[-1], flush=True)
    return "\n".join(lines) + "\n"


def _median_seconds(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times)), out


def _matrix_seconds(faces, n, scheme, repeat, reuse):
    """Median seconds of the default rule from faces to CSR arrays, with element matrices shared between faces of
    one local topology (reuse, the default) or every face integrated on its own; and K's entry count."""
    from sorpia.energy import _core, as_rules

    def build():
        arrays, count, rules = as_rules(faces, n, scheme=scheme, boundary="edge-and-corner")
        return _core.fairness_matrix(_core.Topology(*arrays, count), rules, 1.0, 0.0, 4, 4, reuse=reuse)
    s, (data, _, _) = _median_seconds(build, repeat)
    return s, len(data)


def assembly_times(sizes, repeat, alone_up_to):
    """Generated irregular meshes of each size (most vertices extraordinary), and the same refined once by their
    scheme (extraordinary vertices only at the original vertices: the fine mesh fair interpolation builds K on),
    and a regular quad torus: shared element matrices against every face on its own (the latter only up to
    `alone_up_to` vertices, once)."""
    lines = ["| mesh | vertices | faces | nnz(K) | seconds, shared (median) | seconds, face by face | speed-up | "
             "microseconds per face, shared |", "|---|---|---|---|---|---|---|---|"]
    meshes = []
    for n in sizes:
        for name, (v, f), scheme in [("quad_irregular", sorpia.shapes.quad_irregular(n, 1), "catmull-clark"),
                                     ("irregular", sorpia.shapes.irregular(n, 1), "loop")]:
            fine = sorpia.LimitSurface(v, f, scheme=scheme).tessellate(1)
            meshes += [(f"{name} {n} ({scheme})", v, f, scheme),
                       (f"{name} {n} refined once ({scheme})", *fine, scheme)]
    meshes.append(("quad_torus 200x200, regular (catmull-clark)", *sorpia.shapes.quad_torus(200, 200),
                   "catmull-clark"))
    for label, v, f, scheme in meshes:
        shared, nnz = _matrix_seconds(f, len(v), scheme, repeat, True)
        alone = _matrix_seconds(f, len(v), scheme, 1, False)[0] if len(v) <= alone_up_to else None
        lines.append(f"| {label} | {len(v)} | {len(f)} | {nnz} | {shared:.3f} | "
                     + (f"{alone:.2f} | {alone / shared:.0f} | " if alone is not None else "- | - | ")
                     + f"{1e6 * shared / len(f):.1f} |")
        print(lines[-1], flush=True)
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="2000,10000")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--alone-up-to", type=int, default=200000,
                        help="time the face-by-face assembly (once) on meshes of at most this many vertices")
    parser.add_argument("--times-only", action="store_true", help="only the assembly times (implies --no-page)")
    parser.add_argument("--no-page", action="store_true")
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",") if s]
    if args.times_only:
        assembly_times(sizes, args.repeat, args.alone_up_to)
        return
    errors = quadrature_errors()
    rings = ring_table()
    loop_rings = loop_ring_table()
    times = assembly_times(sizes, args.repeat, args.alone_up_to)
    body = (f"## Quadrature error\n\n{errors}\n"
            f"## Rings at an extraordinary vertex (Catmull-Clark)\n\nThin-plate energy of Bfr's polynomial rings "
            f"at the centre of `shapes.pole(n)` refined once by Catmull-Clark, ring l the three squares of side 2^-l next to the corner piece:\n\n{rings}\n"
            f"## Rings at an extraordinary vertex (Loop)\n\nThe same at the centre of `shapes.pole(n)` under Loop, ring l "
            f"the three triangles of the corner triangle of level l - 1 other than its corner:\n\n{loop_rings}\n"
            f"## Assembly time\n\nThe default rule (4 x 4 points, depth 4), thin plate, from faces to CSR arrays; "
            f"element matrices shared between faces of one local topology (the default) against every face "
            f"integrated on its own (FairnessQuadrature::reuse = false):\n\n{times}")
    if not args.no_page:
        write_page("energy", "Fairness matrix: quadrature error and assembly time", body, settings=(parser, args))


if __name__ == "__main__":
    main()
