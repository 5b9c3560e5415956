"""Catmull-Clark interpolation measured: the spectrum of B, the fastest omega, the paper's Table 1 layout, and
the cost of a sweep against Loop's at 1M vertices. Writes docs/benchmarks/catmull-clark.md (unless --no-page).

Meshes: OpenSubdiv's osd_catmark_* shapes from --meshes (their crease tags ignored; shapes sorpia refuses, such
as non-manifold ones, are listed with the reason) and generated ones (sorpia.shapes.quad_irregular,
quad_grid, polygon_torus). Spectrum: every eigenvalue of the dense B up to --dense vertices, else the core's
estimate (Lanczos in the Gamma^-1 inner product, or the power method without one). Fastest omega: SOR sweeps
to E_k/E_0 < 1e-10 over a grid of fixed omegas. Table: iterations each method needs to reach 1e-1 .. 1e-10.

Cost at 1M: sorpia-bench runs "gs" on quads:1000000 and quadtorus:1000x1000 (Catmull-Clark) and on
irregular:1000000 and torus:1000x1000 (Loop), rounds alternated; with --baseline PATH (a sorpia-bench built
from an earlier commit) Loop also runs on that binary in each round, side by side. Seconds per vertex per
sweep are the median over rounds of (solve seconds / iterations / vertices), each run's solve seconds the
median of its --repeat.

    python bench/catmull_clark.py [--meshes DIR] [--rounds 5] [--repeat 3] [--baseline PATH] [--no-page]
                                  [--skip-1m]
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import shutil
import statistics
import subprocess
import sys
import warnings

import numpy as np

import sorpia
from sorpia.cli.compare import TABLE_TOLERANCES, iterations_to_reach

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402
from omega_study import DEFAULT_MESH_DIR  # noqa: E402

CC = "catmull-clark"
GENERATED = {
    "quad_irregular(3000)": lambda: sorpia.shapes.quad_irregular(3000, seed=1),
    "quad_grid(40,30)": lambda: sorpia.shapes.quad_grid(40, 30),
    "polygon_torus(40,30)": lambda: sorpia.shapes.polygon_torus(40, 30, seed=1),
}
OMEGAS = [round(w, 2) for w in np.arange(0.70, 1.501, 0.05)]
METHODS = [("PIA", dict(method="pia", max_iter=5000)), ("W-PIA", dict(method="wpia")), ("HSS", dict(method="hss")),
           ("WHSS", dict(method="whss")), ("SOR auto", dict(method="sor")), ("CG", dict(method="cg"))]
BENCH_MESHES = [("catmull-clark", "quads:1000000"), ("catmull-clark", "quadtorus:1000x1000"),
                ("loop", "irregular:1000000"), ("loop", "torus:1000x1000")]


def load(mesh_dir):
    """([(name, vertices, faces)], [(name, reason)]): the osd_catmark_* shapes sorpia accepts, then the generated ones."""
    meshes, skipped = [], []
    for path in sorted(glob.glob(os.path.join(mesh_dir, "osd_catmark_*.obj"))):
        name = os.path.basename(path)[:-4]
        try:
            v, f = sorpia.read_mesh(path)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
                sorpia.Interpolator(f, len(v), scheme=CC)
        except (sorpia.MeshFileError, sorpia.MeshError) as e:
            skipped.append((name, str(e).splitlines()[0]))
            continue
        meshes.append((name, v, f))
    meshes += [(name, *make()) for name, make in GENERATED.items()]
    return meshes, skipped


def interpolator(v, f):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        return sorpia.Interpolator(f, len(v), scheme=CC)


def solve(interp, v, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.ConvergenceWarning)
        return interp.solve(v, **kw)


def spectrum(interp, dense_limit):
    """(lambda_min, lambda_max, max |imaginary part|, how)."""
    if interp.n_vertices <= dense_limit:
        ev = np.linalg.eigvals(interp.limit_matrix().toarray())
        return ev.real.min(), ev.real.max(), np.abs(ev.imag).max(), "dense"
    return interp._impl.lambda_min(), 1.0, float("nan"), "estimate"


def mesh_rows(name, v, f, dense_limit):
    interp = interpolator(v, f)
    lo, hi, imag, how = spectrum(interp, dense_limit)
    sweeps = {w: solve(interp, v, method="sor", omega=w, max_iter=2000) for w in OMEGAS}
    converged = {w: r.iterations for w, r in sweeps.items() if r.converged}
    best = min(converged, key=lambda w: (converged[w], abs(w - 1.0))) if converged else None
    table = []
    for label, kw in METHODS:
        try:
            r = solve(interpolator(v, f), v, **kw)
        except ValueError as e:  # e.g. W-PIA on a singular B
            table.append(dict(label=label, levels=[None] * 10, iterations=0, converged=False, variant="",
                              refused=str(e).split(":")[0] + ": " + str(e).split("(")[0].split(":", 1)[-1].strip()))
            continue
        table.append(dict(label=label, levels=iterations_to_reach(r.history, TABLE_TOLERANCES),
                          iterations=r.iterations, converged=r.converged, variant=r.variant, refused=None))
    return dict(mesh=name, n=len(v), lambda_min=lo, lambda_max=hi, imag=imag, how=how,
                closed=interp.closed, gs=converged.get(1.0), best_omega=best,
                best_sweeps=converged.get(best), table=table)


def bench_binary():
    here = os.path.join(os.path.dirname(__file__), "..", "build", "python", "sorpia-bench")
    return here if os.path.exists(here) else shutil.which("sorpia-bench")


def run_bench(binary, scheme, mesh, repeat):
    # Loop without --scheme: a baseline binary from before the option runs the same command.
    args = [binary, "--method", "gs", "--json", "--repeat", str(repeat), mesh] + (
        ["--scheme", scheme] if scheme != "loop" else [])
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    m = json.loads(out)["meshes"][0]
    r = m["methods"][0]
    return dict(n=m["n_vertices"], iterations=r["iterations"], seconds=r["solve"],
                per_vertex=r["solve"] / r["iterations"] / m["n_vertices"])


def cost_rows(rounds, baseline, repeat):
    binary = bench_binary()
    runs = [(label, scheme, mesh, path) for scheme, mesh in BENCH_MESHES
            for label, path in [("this build", binary)] + ([("baseline", baseline)] if baseline and scheme == "loop"
                                                           else [])]
    got = {key[:3]: [] for key in runs}
    info = {}
    for _ in range(rounds):
        for label, scheme, mesh, path in runs:
            r = run_bench(path, scheme, mesh, repeat)
            got[(label, scheme, mesh)].append(r["per_vertex"])
            info[(label, scheme, mesh)] = r
    return [dict(build=label, scheme=scheme, mesh=mesh, n=info[(label, scheme, mesh)]["n"],
                 iterations=info[(label, scheme, mesh)]["iterations"],
                 ns=1e9 * statistics.median(got[(label, scheme, mesh)]),
                 all_ns=[round(1e9 * x, 1) for x in got[(label, scheme, mesh)]])
            for label, scheme, mesh, _ in runs]


def page(rows, skipped, costs):
    lines = ["B for Catmull-Clark is OpenSubdiv's CATMARK limit masks (docs: Catmull-Clark): interior vertex of "
             "valence n in a quad ring (n^2 v + 4 sum e_j + sum f_j) / (n (n + 5)), boundary (v_prev + 4 v + "
             "v_next) / 6, vertices of non-quad faces refined once. Crease tags of the shapes ignored.", "",
             "## Spectrum of B and the fastest omega", "",
             "lambda: all eigenvalues of the dense B (dense) or the core's estimate of lambda_min (estimate; "
             "lambda_max is 1). Sweeps: SOR-PIA to E_k/E_0 < 1e-10; omega = 1 is Gauss-Seidel, the fastest is "
             "the smallest count over omega in 0.70 .. 1.50 (step 0.05), ties to the omega nearest 1. closed: "
             "B = Gamma Upsilon with Upsilon symmetric (CG runs CG, else BiCGSTAB).", "",
             "| mesh | vertices | lambda_min | lambda_max | max imag | how | closed | sweeps omega=1 | fastest omega "
             "| its sweeps |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        imag = "-" if np.isnan(r["imag"]) else f"{r['imag']:.1e}"
        lines.append(f"| {r['mesh']} | {r['n']} | {r['lambda_min']:.4f} | {r['lambda_max']:.4f} | {imag} | "
                     f"{r['how']} | {'yes' if r['closed'] else 'no'} | {r['gs']} | {r['best_omega']} | "
                     f"{r['best_sweeps']} |")
    if skipped:
        lines += ["", "Not run (sorpia refuses them): " + "; ".join(f"{n}: {why}" for n, why in skipped)]
    lines += ["", "## Iterations to E_k/E_0 < 1e-j (the paper's Table 1 layout)", "",
              "| mesh | method | " + " | ".join(f"1e-{j}" for j in range(1, 11)) + " | note |",
              "|---|---|" + "---|" * 10 + "---|"]
    for r in rows:
        for t in r["table"]:
            cells = ["-" if x is None else str(x) for x in t["levels"]]
            note = t["refused"] or (t["variant"] if t["label"] == "CG" else ("" if t["converged"] else "not converged"))
            lines.append(f"| {r['mesh']} | {t['label']} | " + " | ".join(cells) + f" | {note} |")
    if costs:
        lines += ["", "## Cost of a sweep at 1M vertices", "",
                  "sorpia-bench --method gs --repeat R, one thread; ns per vertex per sweep = solve seconds (the "
                  "median of R) / sweeps / vertices, then the median over the rounds (each round runs every line "
                  "once, in this order; the rounds column lists each round's figure).", "",
                  "| build | scheme | mesh | vertices | sweeps | ns / vertex / sweep | rounds |",
                  "|---|---|---|---|---|---|---|"]
        for c in costs:
            lines.append(f"| {c['build']} | {c['scheme']} | {c['mesh']} | {c['n']} | {c['iterations']} | "
                         f"{c['ns']:.1f} | {', '.join(map(str, c['all_ns']))} |")
        ref = {(c["build"], c["mesh"]): c["ns"] for c in costs}
        loop = ref.get(("this build", "irregular:1000000"))
        if loop:
            lines += ["", "Ratios: " + ", ".join(
                f"{m} / irregular:1000000 (Loop) = {ref[('this build', m)] / loop:.2f}"
                for m in ("quads:1000000", "quadtorus:1000x1000") if ("this build", m) in ref)]
        for m in ("irregular:1000000", "torus:1000x1000"):
            if ("baseline", m) in ref:
                lines.append(f"Loop {m}: this build / baseline = {ref[('this build', m)] / ref[('baseline', m)]:.3f}")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default=DEFAULT_MESH_DIR, help="folder with OpenSubdiv's osd_catmark_*.obj")
    ap.add_argument("--dense", type=int, default=4000, help="dense eigenvalues up to this many vertices")
    ap.add_argument("--rounds", type=int, default=5, help="alternated rounds of the 1M runs")
    ap.add_argument("--repeat", type=int, default=3, help="sorpia-bench --repeat in each 1M run (its median)")
    ap.add_argument("--baseline", help="a sorpia-bench of an earlier commit: Loop side by side")
    ap.add_argument("--skip-1m", action="store_true", help="no 1M-vertex runs")
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--no-page", action="store_true", help="print only")
    args = ap.parse_args(argv)
    meshes, skipped = load(args.meshes)
    rows = [mesh_rows(name, v, f, args.dense) for name, v, f in meshes]
    costs = [] if args.skip_1m else cost_rows(args.rounds, args.baseline, args.repeat)
    body = page(rows, skipped, costs)
    print(body)
    if args.json:
        with open(args.json, "w") as out:
            json.dump(dict(rows=rows, skipped=skipped, costs=costs), out, indent=1, default=float)
    if not args.no_page:
        write_page("catmull-clark", "Catmull-Clark: spectrum, omega, iterations, cost per sweep", body,
                   settings=(ap, args))


if __name__ == "__main__":
    main()
