"""The paper's Table 1 for our meshes: iterations each method needs to reach
E_k/E_0 < 1e-1 ... 1e-10 (paper section 5.3), with its parameter and time.

For each .obj in --meshes (skipped when the folder is missing) and, with
--generated, the generated meshes: every method of sorpia.interpolate, SOR-PIA
both with omega="young" (paper Remark 1) and omega="auto". Time: median of
--repeat runs of estimate + solve, each run on a fresh Interpolator so that the
spectral estimates (W-PIA's lambda_min, Young's rho, HSS's alpha) are paid
every time; building B is not included (it is the same for every method).
The paper's own Table 1 (Ninja-Turtle, Pumpkin, Kangaroo) is printed first.
Both tables also go into docs/benchmarks/paper-table.md (unless --no-page).

    python bench/paper_table.py [--meshes DIR] [--generated] [--json out.json] [--no-page]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys

from sorpia.cli.compare import TABLE_TOLERANCES, iterations_to_reach

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402
from omega_study import DEFAULT_MESH_DIR, load_meshes, make_interpolator, skipped_note, timed  # noqa: E402

LEVELS = range(1, 11)  # column j: E_k/E_0 < 10^-j, TABLE_TOLERANCES

# Hamza & Hamza 2026, Table 1, copied from the paper's text: omega, then per
# method iterations to 1e-1 .. 1e-10 ("-" as printed) and CPU seconds.
PAPER = {
    "Ninja-Turtle": (1.9778, {
        "PIA": ([1, 5, 12, 19, 27, 35, 43, 51, 60, 68], 1.8479),
        "W-PIA": ([1, 4, 8, 12, 17, 22, 26, 31, 36, 41], 1.1929),
        "HSS-PIA": ([1, 3, 7, 11, 16, 20, 25, 29, 34, 39], 1.7789),
        "WHSS-PIA": ([1, 2, 4, 7, 9, 11, 14, 16, 18, 21], 0.8774),
        "SOR-PIA": (["-", "-", 1, 3, 4, 6, 7, 9, 11, 13], 0.6265),
    }),
    "Pumpkin": (1.9453, {
        "PIA": ([1, 6, 13, 20, 28, 36, 43, 51, 59, 67], 3.0395),
        "W-PIA": ([1, 4, 8, 12, 16, 21, 26, 30, 35, 40], 1.8481),
        "HSS-PIA": ([1, 4, 8, 12, 16, 20, 25, 29, 34, 38], 2.6126),
        "WHSS-PIA": ([1, 2, 4, 6, 8, 10, 12, 14, 17, 19], 1.4453),
        "SOR-PIA": (["-", "-", 1, 3, 5, 7, 9, 11, 13, 15], 1.2002),
    }),
    "Kangaroo": (1.9778, {
        "PIA": ([1, 6, 16, 26, 37, 48, 60, 71, 83, 95], 2.7521),
        "W-PIA": ([1, 3, 7, 12, 17, 22, 27, 32, 37, 43], 1.5205),
        "HSS-PIA": ([1, 4, 9, 15, 21, 26, 33, 40, 46, 52], 2.2476),
        "WHSS-PIA": ([1, 2, 5, 8, 10, 13, 16, 18, 21, 24], 1.0606),
        "SOR-PIA": (["-", 1, 2, 4, 6, 7, 9, 11, 13, 24], 0.8122),
    }),
}

# (row label, interpolate keywords)
RUNS = [
    ("PIA", dict(method="pia")),
    ("W-PIA", dict(method="wpia")),
    ("HSS", dict(method="hss")),
    ("WHSS", dict(method="whss")),
    ("SOR young", dict(method="sor", omega="young", max_iter=5000)),
    ("SOR auto", dict(method="sor", omega="auto")),
    ("CG", dict(method="cg")),
]


def parameter(r) -> str:
    """The table's parameter column: omega (and rho), sigma, alpha (and w) or the CG variant."""
    if r.method in ("sor", "gs"):
        return f"omega={r.omega:.4f}" + (f", rho={r.rho:.4f}" if r.rho is not None else "")
    if r.method == "wpia":
        return f"sigma={r.sigma:.3f}"
    if r.method in ("hss", "whss"):
        return f"alpha={r.alpha:.3f}" + (f", w={r.weight:.3f}" if r.method == "whss" else "")
    if r.method == "cg":
        return r.variant
    return ""


def run(name, v, f, repeat):
    rows = []
    for label, kw in RUNS:
        # A fresh Interpolator per run: the spectral estimates are paid every time.
        runs = [timed(make_interpolator(v, f), v, 1, **kw) for _ in range(repeat)]
        res, times = runs[-1][0], [t for _, t in runs]
        rows.append(dict(mesh=name, n=len(v), label=label, parameter=parameter(res),
                         levels=iterations_to_reach(res.history, TABLE_TOLERANCES), iterations=res.iterations,
                         converged=res.converged, products=res.products, seconds=statistics.median(times),
                         estimate_seconds=res.timings["estimate"]))
    return rows


def paper_lines():
    """The paper's Table 1 as Markdown lines."""
    lines = ["## The paper's Table 1", "", "Hamza & Hamza 2026, iterations to E_k/E_0 < 1e-j, as printed:", "",
             "| model | omega | method | " + " | ".join(f"1e-{j}" for j in LEVELS) + " | CPU s |",
             "|---|---|---|" + "---|" * len(LEVELS) + "---|"]
    for model, (omega, methods) in PAPER.items():
        for m, (its, t) in methods.items():
            lines.append(f"| {model} | {omega} | {m} | " + " | ".join(map(str, its)) + f" | {t} |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default=DEFAULT_MESH_DIR, help="folder of .obj meshes (skipped if missing)")
    ap.add_argument("--generated", action="store_true", help="also the generated meshes")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/paper-table.md")
    args = ap.parse_args(argv)

    rows, skipped = [], []
    for name, v, f in load_meshes(args.meshes, generated=args.generated, skipped=skipped):
        rows += run(name, v, f, args.repeat)
    lines = paper_lines() + [
        "", "## sorpia on our meshes", "",
        "Iterations to E_k/E_0 < 1e-j; products: applications of B (or B^T), inner solves included; "
        f"ms: median of {args.repeat} runs of estimate + solve, each on a fresh `Interpolator` so that the spectral "
        "estimates are paid every time. \"SOR auto\" is omega = 1, i.e. Gauss-Seidel.", "",
        "| mesh | n | method | parameter | " + " | ".join(f"1e-{j}" for j in LEVELS) + " | products | ms |",
        "|---|---|---|---|" + "---|" * len(LEVELS) + "---|---|"]
    for r in rows:
        lv = " | ".join("-" if x is None else str(x) for x in r["levels"])
        lines.append(f"| {r['mesh']} | {r['n']} | {r['label']} | {r['parameter']} | {lv} | {r['products']} "
                     f"| {1e3 * r['seconds']:.2f} |")
    if not rows:
        lines += ["", f"(no meshes: {args.meshes} is missing and --generated was not given)"]
    lines += skipped_note(skipped).split("\n")
    print("\n".join(lines))
    if not args.no_page:
        write_page("paper-table", "Iterations against the paper's Table 1", "\n".join(lines), settings=(ap, args))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
