"""How many SOR-PIA sweeps each omega needs, on real and generated meshes:
the evidence behind omega="auto" (docs: convergence against the paper).

For every mesh: sweeps to E_k/E_0 < tol for omega on a grid (0.80 .. 1.60 by
0.05, and 0.96 .. 1.12 by 0.01), Gauss-Seidel, omega="young" (paper Remark 1,
with rho(I - D^-1 B) by the power method) and omega="auto"; times are medians
of --repeat runs of estimate + solve (the operator is built once per mesh and
not counted). Prints Markdown; --json writes everything. --whss adds the same
study for the relaxation weight of "whss" (outer iterations for w = 0.8 .. 1.2
at the default alpha). --arpack checks rho(I - D^-1 B) with scipy's ARPACK
(eigs, tol 1e-10), independent of sorpia's power method. The tables also go
into docs/benchmarks/omega-study.md (unless --no-page).

    python bench/omega_study.py [--meshes DIR] [--tol 1e-10] [--whss] [--arpack] [--json out.json] [--no-page]
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import statistics
import sys
import warnings

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

import sorpia

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _report import write_page  # noqa: E402

DEFAULT_MESH_DIR = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "meshes")

GENERATED = {
    "icosphere(3)": lambda: sorpia.shapes.icosphere(3),
    "torus(40,30)": lambda: sorpia.shapes.torus(40, 30),
    "grid(30,20)": lambda: sorpia.shapes.grid(30, 20),
    "pole(48)": lambda: sorpia.shapes.pole(48),
    "irregular(2000)": lambda: sorpia.shapes.irregular(2000, seed=1),
}


def load_meshes(mesh_dir: str, generated: bool = True, skipped: list | None = None):
    """[(name, vertices, faces)]: the .obj files of mesh_dir (sorted) that sorpia accepts as triangle meshes,
    then the generated meshes. Files it refuses (polygons, non-manifold topology) go onto `skipped` as
    (name, reason) when a list is given."""
    out = []
    for path in sorted(glob.glob(os.path.join(mesh_dir, "*.obj"))):
        name = os.path.basename(path)[:-4]
        try:
            v, f = sorpia.read_mesh(path)
            make_interpolator(v, f)
        except (sorpia.MeshFileError, sorpia.MeshError) as e:
            if skipped is not None:  # the reason in a few words: the message up to its first colon
                msg = str(e).replace(path + ", ", "")
                skipped.append((name, "polygons" if "works on triangles" in msg else msg.split(":")[0]))
            continue
        out.append((name, v, f))
    if generated:
        out += [(name, *make()) for name, make in GENERATED.items()]
    return out


def skipped_note(skipped) -> str:
    """A Markdown paragraph naming the mesh files left out and why ("" when none were)."""
    if not skipped:
        return ""
    return "\nLeft out (sorpia refuses them as Loop input): " + "; ".join(f"{n} ({why})" for n, why in skipped)


def make_interpolator(v, f):
    """An Interpolator, silencing UnreferencedVerticesWarning (expected: the bunny has 1113)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        return sorpia.Interpolator(f, len(v))


WEIGHTS = (0.8, 0.9, 1.0, 1.1, 1.2)
OMEGAS = sorted(set(np.round(np.arange(0.80, 1.601, 0.05), 2)) | set(np.round(np.arange(0.96, 1.121, 0.01), 2)))


def arpack_rho(v, f) -> float:
    """Spectral radius of I - D^-1 B by ARPACK (largest magnitude eigenvalues)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        b = sorpia.limit_matrix(f, len(v))
    jac = scipy.sparse.identity(len(v)) - scipy.sparse.diags(1.0 / b.diagonal()) @ b
    ev = scipy.sparse.linalg.eigs(jac, k=4, which="LM", return_eigenvectors=False, tol=1e-10, maxiter=50000)
    return float(np.abs(ev).max())


def timed(solver, v, repeat, **kw):
    """(result, median seconds of estimate + solve over `repeat` runs)."""
    times, res = [], None
    for _ in range(repeat):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sorpia.OmegaWarning)
            warnings.simplefilter("ignore", sorpia.ConvergenceWarning)
            res = solver.solve(v, **kw)
        times.append(res.timings["estimate"] + res.timings["solve"])
    return res, statistics.median(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default=DEFAULT_MESH_DIR, help="folder of .obj meshes (skipped if missing)")
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--whss", action="store_true", help="also scan the whss relaxation weight")
    ap.add_argument("--arpack", action="store_true", help="also rho(I - D^-1 B) by scipy's ARPACK")
    ap.add_argument("--json", help="write the measurements here")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/omega-study.md")
    args = ap.parse_args(argv)

    rows, skipped = [], []
    for name, v, f in load_meshes(args.meshes, skipped=skipped):
        # A fresh Interpolator for young so that rho's estimate is paid and timed.
        young, t_young = timed(make_interpolator(v, f), v, 1, omega="young", max_iter=5000, tol=args.tol)
        solver = make_interpolator(v, f)
        gs, t_gs = timed(solver, v, args.repeat, method="gs", tol=args.tol)
        auto, t_auto = timed(solver, v, args.repeat, omega="auto", tol=args.tol)
        scan = {}
        for om in OMEGAS:
            r = solver.solve(v, omega=float(om), tol=args.tol)
            scan[float(om)] = r.iterations
        best_it = min(scan.values())
        best = [om for om, it in scan.items() if it == best_it]
        best_res, t_best = timed(solver, v, args.repeat, omega=best[0], tol=args.tol)
        whss = {}
        if args.whss:
            for w in WEIGHTS:
                whss[w] = solver.solve(v, method="whss", weight=w, tol=args.tol).iterations
        rho_arpack = arpack_rho(v, f) if args.arpack else float("nan")
        rows.append(dict(mesh=name, n=len(v), whss=whss, rho_arpack=rho_arpack, gs=gs.iterations, t_gs=t_gs,
                         auto=auto.iterations, auto_omega=auto.omega, t_auto=t_auto, rho=young.rho,
                         young_omega=young.omega, young=young.iterations,
                         young_converged=young.converged, t_young=t_young, best_omegas=best, best=best_it,
                         t_best=t_best, scan=scan))
        print(f"# {name}: gs {gs.iterations}, best {best_it} at omega {best[0]}..{best[-1]}", file=sys.stderr)

    lines = []

    def out(text=""):
        lines.extend(text.split("\n"))

    out(f"Sweeps to E_k/E_0 < {args.tol:g} (time: median of {args.repeat}, estimate + solve)\n")
    out("| mesh | n | rho(I-D^-1B) | rho ARPACK | young omega | young sweeps | GS sweeps | auto omega | auto sweeps "
        "| fastest omega | its sweeps | t GS ms | t auto ms | t young ms |")
    out("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        b = r["best_omegas"]
        br = f"{b[0]:.2f}" if len(b) == 1 else f"{b[0]:.2f}-{b[-1]:.2f}"
        yi = str(r["young"]) + ("" if r["young_converged"] else " (not converged)")
        out(f"| {r['mesh']} | {r['n']} | {r['rho']:.5f} | {r['rho_arpack']:.5f} | {r['young_omega']:.4f} | {yi} "
            f"| {r['gs']} | {r['auto_omega']:.2f} | {r['auto']} | {br} | {r['best']} | {1e3 * r['t_gs']:.2f} "
            f"| {1e3 * r['t_auto']:.2f} | {1e3 * r['t_young']:.2f} |")

    out("\nSweeps per omega (columns) and mesh (rows):\n")
    out("| mesh | " + " | ".join(f"{om:.2f}" for om in OMEGAS) + " |")
    out("|---|" + "---|" * len(OMEGAS))
    for r in rows:
        out(f"| {r['mesh']} | " + " | ".join(str(r["scan"][float(om)]) for om in OMEGAS) + " |")

    # The largest fixed omega that never needs more sweeps than GS on any mesh.
    safe = [om for om in OMEGAS if all(r["scan"][float(om)] <= r["gs"] for r in rows)]
    out(f"\n- Fixed omegas never worse than GS on all {len(rows)} meshes: {', '.join(f'{o:.2f}' for o in safe)}")
    gains = {float(om): sum(r["gs"] - r["scan"][float(om)] for r in rows) for om in safe}
    out("- Sweeps saved against GS, summed over the meshes: " + ", ".join(f"{o:.2f}: {g}" for o, g in gains.items()))
    out(f"- auto never worse than GS: {all(r['auto'] <= r['gs'] for r in rows)}")
    if args.whss:
        out("\nwhss outer iterations per relaxation weight (default alpha):\n")
        out("| mesh | " + " | ".join(f"w={w}" for w in WEIGHTS) + " |")
        out("|---|" + "---|" * len(WEIGHTS))
        for r in rows:
            out(f"| {r['mesh']} | " + " | ".join(str(r["whss"][w]) for w in WEIGHTS) + " |")
    out(skipped_note(skipped))
    print("\n".join(lines))
    if not args.no_page:
        write_page("omega-study", "SOR-PIA sweeps against omega", "\n".join(lines), settings=(ap, args))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
