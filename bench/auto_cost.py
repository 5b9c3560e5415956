"""Cost of method="auto" (the default): against "sor" where SOR converges, and
against "cg" and "gmres" on meshes with interior valence-2 vertices, where SOR
diverges.

Part 1, ordinary meshes (sorpia.shapes.irregular, Loop, and
sorpia.shapes.quad_irregular, Catmull-Clark, of --vertices each): "auto" and
"sor" on one Interpolator, alternated, medians of --repeat solves; auto's
result must be SOR's, bit for bit, and nothing else may run.
Part 2, valence-2 meshes: sorpia.shapes.quad_torus(--torus) with a share
(--split) of its edges split at their midpoints (pentagons on both sides, an
interior vertex of valence 2 as at OpenSubdiv's gregory_test8: B indefinite),
or of its quads split in two through a new vertex joined to two opposite
corners (valence 2, B definite): every method with its outcome, iterations,
products of B and solve seconds (medians of --repeat), and the singular prism
of --prism sides (Catmull-Clark, targets jiggled), where "auto" ends with the
least-squares answer.
Prints Markdown tables and writes them into docs/benchmarks/auto-cost.md
(unless --no-page).

    python bench/auto_cost.py [--vertices 1000000] [--torus 400x200] [--split 0.01] [--prism 100]
                              [--repeat 5] [--no-page]
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


def split_quads(v, f, share: float, seed: int = 1):
    """Quads (a, b, c, d) of `f` picked at random with probability `share`,
    each replaced by (a, b, c, x) and (a, x, c, d), x a new vertex near the
    quad's centre: x is interior and of valence 2 (B stays definite here)."""
    f = np.asarray(f)
    pick = np.random.default_rng(seed).random(len(f)) < share
    quads = f[pick]
    x = len(v) + np.arange(len(quads))
    centre = v[quads].mean(axis=1)
    new_v = np.vstack([v, centre + 0.1 * (v[quads[:, 1]] - centre)])
    halves = np.vstack([np.c_[quads[:, 0], quads[:, 1], quads[:, 2], x], np.c_[quads[:, 0], x, quads[:, 2], quads[:, 3]]])
    return new_v, [list(q) for q in np.vstack([f[~pick], halves])], len(quads)


def split_edges(v, f, share: float, seed: int = 1):
    """Edges of the quad mesh `f` picked at random with probability `share`
    (no two on one face), each split at its midpoint by a new vertex inserted
    into both its faces, which become pentagons: as at OpenSubdiv's
    gregory_test8, the new vertex is interior of valence 2 and B gets negative
    eigenvalues."""
    faces = [list(q) for q in np.asarray(f)]
    faces_of = {}
    for i, face in enumerate(faces):
        for a, b in zip(face, face[1:] + face[:1]):
            faces_of.setdefault((min(a, b), max(a, b)), []).append(i)
    edges = sorted(faces_of)
    used, new_v = set(), [np.asarray(v, float)]
    picked = np.random.default_rng(seed).random(len(edges)) < share
    for (a, b), take in zip(edges, picked):
        if not take or not used.isdisjoint(faces_of[a, b]):
            continue
        used.update(faces_of[a, b])
        x = len(v) + len(new_v) - 1
        new_v.append(((v[a] + v[b]) / 2)[None])
        for i in faces_of[a, b]:
            face = faces[i]
            j = next(j for j in range(len(face)) if {face[j], face[(j + 1) % len(face)]} == {a, b})
            face.insert(j + 1, x)
    return np.vstack(new_v), faces, len(new_v) - 1


def prism(m: int):
    t = 2 * np.pi * np.arange(m) / m
    v = np.vstack([np.c_[np.cos(t), np.sin(t), -np.ones(m)], np.c_[np.cos(t), np.sin(t), np.ones(m)]])
    f = [list(range(m))[::-1], list(range(m, 2 * m))] + [[i, (i + 1) % m, m + (i + 1) % m, m + i] for i in range(m)]
    return v + 0.05 * np.random.default_rng(1).standard_normal(v.shape), f


def timed_solve(interp, v, method):
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        r = interp.solve(v, method=method)
        return r, time.perf_counter() - t0


def outcome(r) -> str:
    return ", then ".join(f"{a['method']} {a['stop_reason']} ({a['iterations']})" for a in r.attempts)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=1_000_000, help="vertices of the ordinary meshes")
    ap.add_argument("--torus", default="400x200", help="NUxNV quads of the valence-2 torus")
    ap.add_argument("--split", type=float, default=0.01, help="share of the torus's quads split (valence 2)")
    ap.add_argument("--prism", type=int, default=100, help="sides of the singular prism")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/auto-cost.md")
    args = ap.parse_args()

    lines = [f"## Where SOR converges: auto against sor", "",
             f"One Interpolator per mesh; auto and sor alternated, medians of {args.repeat} solves.", "",
             "| mesh | vertices | sor iterations | sor (s) | auto (s) | auto / sor | auto ran | same result |",
             "|---|---:|---:|---:|---:|---:|---|:---:|"]
    for name, (v, f), scheme in (
            (f"irregular({args.vertices})", sorpia.shapes.irregular(args.vertices, 1), "loop"),
            (f"quad_irregular({args.vertices})", sorpia.shapes.quad_irregular(args.vertices, 1), "catmull-clark")):
        interp = sorpia.Interpolator(f, len(v), scheme=scheme)
        times = {"sor": [], "auto": []}
        results = {}
        for _ in range(args.repeat):
            for m in ("sor", "auto"):
                results[m], t = timed_solve(interp, v, m)
                times[m].append(t)
        sor, auto = results["sor"], results["auto"]
        same = np.array_equal(sor.control_vertices, auto.control_vertices) and np.array_equal(sor.history, auto.history)
        ts, ta = statistics.median(times["sor"]), statistics.median(times["auto"])
        lines.append(f"| {name} ({scheme}) | {len(v):,} | {sor.iterations} | {ts:.3f} | {ta:.3f} | {ta / ts:.3f} "
                     f"| {outcome(auto)} | {'yes' if same else 'NO'} |")
        del interp

    nu, nv = (int(x) for x in args.torus.lower().split("x"))
    torus = sorpia.shapes.quad_torus(nu, nv)
    ev, ef, n_edges = split_edges(*torus, args.split)
    qv, qf, n_quads = split_quads(*torus, args.split)
    lines += ["", "## Interior vertices of valence 2: auto against cg and gmres", "",
              f"sorpia.shapes.quad_torus({nu}, {nv}) with {n_edges:,} edges split at their midpoints (valence-2 "
              f"vertices between pentagons, B indefinite), or {n_quads:,} quads split through a valence-2 vertex "
              f"(B definite), and a prism of {args.prism} sides (B singular, targets jiggled); Catmull-Clark; "
              f"medians of {args.repeat} solves.", "",
              "| mesh | method | outcome (iterations) | E_k/E_0 | products of B | solve (s) |",
              "|---|---|---|---:|---:|---:|"]
    methods = ("sor", "pia", "cg", "gmres", "auto")
    for name, (mv, mf) in ((f"torus, {n_edges:,} edges split", (ev, ef)), (f"torus, {n_quads:,} quads split", (qv, qf)),
                           (f"prism {args.prism}", prism(args.prism))):
        interp = sorpia.Interpolator(mf, len(mv), scheme="catmull-clark")
        times = {m: [] for m in methods}
        results = {}
        for _ in range(args.repeat):
            for m in methods:
                results[m], t = timed_solve(interp, mv, m)
                times[m].append(t)
        for m in methods:
            r = results[m]
            lines.append(f"| {name} | {m} | {outcome(r)} | {r.history[-1]:.2e} | {r.products} "
                         f"| {statistics.median(times[m]):.3f} |")
        del interp
    lines += ["", f"Load average {os.getloadavg()[0]:.1f} at the end."]
    print("\n".join(lines))
    if not args.no_page:
        write_page("auto-cost", "The default method: auto against sor, cg and gmres", "\n".join(lines),
                   settings=(ap, args))


if __name__ == "__main__":
    main()
