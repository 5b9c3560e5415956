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
   lambda > 1/2.
3. Assembly time against mesh size (medians of --repeat runs), both schemes,
   the default rule: irregular meshes, the same refined once (the fine mesh of
   fair interpolation), and a regular quad torus.
Writes docs/benchmarks/energy.md (unless --no-page).

    python bench/energy.py [--sizes 2000,10000] [--repeat 3] [--no-page]
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


def ring_table():
    lines = ["| valence | 4 lambda^2 | ring 2 | ring 3 | ring 4 | ratio 4/3 |", "|---|---|---|---|---|---|"]
    for n in (3, 5, 6, 8):
        c = np.cos(2 * np.pi / n)
        lam = (5 + c + np.cos(np.pi / n) * np.sqrt(2 * (9 + c))) / 16  # Catmull-Clark's subdominant eigenvalue
        e = ring_energies(n)
        lines.append(f"| {n} | {4 * lam * lam:.3f} | {e[0]:.4g} | {e[1]:.4g} | {e[2]:.4g} | {e[2] / e[1]:.3f} |")
        print(lines[-1], flush=True)
    return "\n".join(lines) + "\n"


def assembly_times(sizes, repeat):
    """Generated irregular meshes of each size (most vertices extraordinary), and the same refined once by their
    scheme (extraordinary vertices only at the original vertices: the fine mesh fair interpolation builds K on)."""
    lines = ["| mesh | vertices | faces | nnz(K) | seconds (median) | microseconds per face |",
             "|---|---|---|---|---|---|"]
    for n in sizes:
        for name, (v, f), scheme in [("quad_irregular", sorpia.shapes.quad_irregular(n, 1), "catmull-clark"),
                                     ("irregular", sorpia.shapes.irregular(n, 1), "loop")]:
            fine = sorpia.LimitSurface(v, f, scheme=scheme).tessellate(1)
            for label, (mv, mf) in [(name, (v, f)), (f"{name} refined once", fine)]:
                times = []
                for _ in range(repeat):
                    t = time.perf_counter()
                    k = sorpia.fairness_matrix(mf, len(mv), scheme=scheme)
                    times.append(time.perf_counter() - t)
                s = float(np.median(times))
                lines.append(f"| {label} ({scheme}) | {len(mv)} | {len(mf)} | {k.nnz} | {s:.2f} | "
                             f"{1e6 * s / len(mf):.0f} |")
                print(lines[-1], flush=True)
    (v, f) = sorpia.shapes.quad_torus(200, 200)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        k = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark")
        times.append(time.perf_counter() - t)
    s = float(np.median(times))
    lines.append(f"| quad_torus 200x200, regular (catmull-clark) | {len(v)} | {len(f)} | {k.nnz} | {s:.2f} | "
                 f"{1e6 * s / len(f):.0f} |")
    print(lines[-1], flush=True)
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="2000,10000")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-page", action="store_true")
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",") if s]
    errors = quadrature_errors()
    rings = ring_table()
    times = assembly_times(sizes, args.repeat)
    body = (f"## Quadrature error\n\n{errors}\n"
            f"## Rings at an extraordinary vertex (Catmull-Clark)\n\nThin-plate energy of Bfr's polynomial rings "
            f"at the centre of `shapes.pole(n)` refined once by Catmull-Clark, ring l the three squares of side 2^-l next to the corner piece:\n\n{rings}\n"
            f"## Assembly time\n\nThe default rule (4 x 4 points, depth 4), `sorpia.fairness_matrix` from faces to "
            f"scipy matrix:\n\n{times}")
    if not args.no_page:
        write_page("energy", "Fairness matrix: quadrature error and assembly time", body, settings=(parser, args))


if __name__ == "__main__":
    main()
