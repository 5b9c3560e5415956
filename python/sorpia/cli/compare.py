"""``sorpia compare``: several methods to one tolerance, the paper's Table 1 and Figure 7."""

from __future__ import annotations

import csv
import io
import math
import sys
from pathlib import Path

import numpy as np

from .. import __version__
from .._meshinfo import topology_info
from .._plotting import convergence_figure
from .common import (DISPLAY_ORDER, EXIT_NOT_CONVERGED, EXIT_OK, FIT_DEFAULTS, OMEGA_METHODS, SCHEME_LABELS, UserError,
                     build_interpolator, check_paths,
                     check_solver_options, cpu_clock, mesh_line, method_label, omega_text, read_solve_input,
                     repair_json, repair_lines, require_plotting, result_fields, run_solver, tags_lines, tags_summary,
                     threads_for)
from .output import save_figure, write_json, write_text
from .progress import Progress

# The columns of the paper's Table 1: iterations to reach E_k/E_0 < 10^-j.
TABLE_TOLERANCES = tuple(10.0 ** -j for j in range(1, 11))

SOLVE_SECONDS_NOTE = (
    "solve seconds: each method's own Interpolator.solve call, to --tol: the spectral estimates it is the first "
    "to need (kept and shared: WHSS-PIA reuses HSS-PIA's) and its iterations; CPU of the calling thread "
    "(of the whole process for sor/gs with --threads above 1). Not included: reading the file and the "
    "topology and limit operator, built once for every method")


def iterations_to_reach(errors, tolerances=TABLE_TOLERANCES) -> list:
    """For each tol: the first k with errors[k] < tol (None if never)."""
    errors = np.asarray(errors, dtype=float)
    out = []
    for tol in tolerances:
        hit = np.flatnonzero(errors < tol)
        out.append(int(hit[0]) if len(hit) else None)
    return out


def run_compare(input_path, *, methods=DISPLAY_ORDER, omega="auto", tol=None, max_iter=None, boundary=None,
                table=None, csv_path=None, plot=None, json_path=None, quiet=False, force=False,
                triangulate=False, threads=1, repair=False, scheme="auto", ignore_tags=False, sharp_angle=None,
                nonmanifold="error", out=None, prim=None) -> tuple[int, dict]:
    """`sorpia compare`: every method to the same tolerance, on one
    sorpia.Interpolator (topology, limit operator and spectral estimates built
    once and shared); returns (exit code, data). `threads` applies to sor/gs
    (and auto's sor run), `omega` to sor and auto. A method that refuses the
    mesh (wpia where B has an eigenvalue at or below 0) gets a row marked
    "refused" with its reason, and the others run."""
    out = out if out is not None else sys.stdout
    tol = FIT_DEFAULTS["tol"] if tol is None else tol
    max_iter = FIT_DEFAULTS["max_iter"] if max_iter is None else max_iter
    given = f"--methods {','.join(methods)}" + (f" --threads {threads}" if threads != 1 else "")
    for method in methods:
        check_solver_options(given, method=method, tol=tol, max_iter=max_iter, threads=threads_for(method, threads),
                             **({"omega": omega} if method in OMEGA_METHODS else {}))
    check_solver_options(given, method="sor", threads=threads)  # --threads as sor takes it, whichever methods run
    check_paths([input_path], {"--table": table, "--csv": csv_path, "--plot": plot, "--json": json_path}, force)
    if plot is not None:
        require_plotting()
    rows = []
    with Progress(enabled=not quiet) as progress:
        progress.status(f"reading {input_path}")
        mesh, scheme, boundary, tags = read_solve_input(
            input_path, triangulate=triangulate, repair=repair, ignore_tags=ignore_tags, nonmanifold=nonmanifold,
            scheme=scheme, boundary=boundary, sharp_angle=sharp_angle, prim=prim)
        V0, F, read_seconds = mesh.vertices, mesh.faces, mesh.seconds
        interp, build = build_interpolator(V0, F, boundary=boundary, progress=progress, source=input_path,
                                           scheme=scheme, tags=tags)
        progress.status("mesh statistics")
        stats = topology_info(V0, interp.topology, scheme=scheme)
        for method in methods:
            n_threads = threads_for(method, threads)
            try:
                res, wall, cpu = run_solver(interp, V0, phase="solving", method=method,
                                            omega=omega if method in OMEGA_METHODS else None, tol=tol,
                                            max_iter=max_iter, threads=n_threads, progress=progress,
                                            source=input_path, scheme=scheme)
            except UserError as exc:  # this method refuses the mesh: say so in its row, run the others
                rows.append(_refused_row(method, n_threads, str(exc)))
                continue
            fields = result_fields(res)
            rows.append({
                "method": method,
                "label": method_label(method),
                "omega": res.omega,  # None but for sor and gs
                "iterations": int(res.iterations),
                "converged": bool(res.converged),
                "stop_reason": res.stop_reason,
                "variant": res.variant,
                "refused": None,
                "reached": iterations_to_reach(res.history),
                "threads": n_threads,
                "cpu_seconds": cpu,
                "cpu_clock": cpu_clock(n_threads),
                "wall_seconds": wall,
                "history": np.asarray(res.history, dtype=float),
                "result": {k: v for k, v in fields.items() if k != "history"},
            })
    data = {
        "sorpia_version": __version__,
        "command": "compare",
        "input": str(input_path),
        "repair": repair_json(mesh.repair) if repair else None,
        "mesh": stats,
        "scheme": scheme,
        "tags": {"from_file": not ignore_tags, "sharp_angle": sharp_angle, **tags_summary(tags)},
        "tol": tol,
        "max_iter": max_iter,
        "boundary": boundary,
        "tolerances": TABLE_TOLERANCES,
        "threads": threads,
        "read_seconds": read_seconds,
        # Topology and limit operator B, built once and shared by every method;
        # not in any row's seconds.
        "setup": {"wall_seconds": build["wall"], "cpu_seconds": build["cpu"], **interp.build_timings},
        "methods": rows,
    }
    markdown = compare_markdown(data, Path(input_path).name)
    if table is not None:
        write_text(table, markdown + "\n")
    if csv_path is not None:
        write_text(csv_path, compare_csv(data))
    if json_path is not None:
        write_json(json_path, data)
    if plot is not None:

        curves = [(_curve_label(r), r["history"]) for r in rows if r["refused"] is None]
        save_figure(convergence_figure(curves, tol=tol, title=f"Convergence on {Path(input_path).name} "
                                       f"(paper Figure 7)"), plot)
    if not quiet:
        print(f"sorpia compare: {input_path}: {mesh_line(stats)}; {SCHEME_LABELS[scheme]}"
              + "".join(f"; {line}" for line in tags_lines(data["tags"])), file=out)
        for line in repair_lines(mesh.repair) if repair else ():
            print(f"  repaired: {line}", file=out)
        print(markdown, file=out)
        print(_setup_line(data), file=out)
        for r in rows:
            if r["refused"] is not None:
                print(f"{r['label']} refused: {r['refused']}", file=out)
        failed = [f"{r['label']} ({r['stop_reason']})" for r in rows if not r["converged"] and r["refused"] is None]
        if failed:
            print(f"NOT converged to tol {tol:g} within {max_iter} iterations: {', '.join(failed)} (exit code 1)",
                  file=out)
        written = [p for p in (table, csv_path, plot, json_path) if p is not None]
        if written:
            print(f"wrote {', '.join(map(str, written))}", file=out)
    ok = all(r["converged"] for r in rows)
    return (EXIT_OK if ok else EXIT_NOT_CONVERGED), data


def _refused_row(method: str, threads: int, reason: str) -> dict:
    """The row of a method that refused the mesh: no iterations, the reason."""
    return {"method": method, "label": method_label(method), "omega": None, "iterations": 0, "converged": False,
            "stop_reason": "refused", "variant": None, "refused": reason, "reached": [None] * len(TABLE_TOLERANCES),
            "threads": threads, "cpu_seconds": 0.0, "cpu_clock": cpu_clock(threads), "wall_seconds": 0.0,
            "history": np.zeros(0), "result": None}


def _curve_label(row) -> str:
    return row["label"] + (f" (omega {row['omega']:.4f})" if row["method"] == "sor" and row["omega"] else "")


def _tol_header(tol: float) -> str:
    return f"1e-{round(-math.log10(tol))}"


def _setup_line(data: dict) -> str:
    s = data["setup"]
    return (f"{SOLVE_SECONDS_NOTE}: {s['wall_seconds']:.4f} s wall, {s['cpu_seconds']:.4f} s CPU "
            f"(topology {s['topology']:.4f} s, operator {s['operator']:.4f} s).")


def compare_markdown(data: dict, name: str) -> str:
    """The paper's Table 1 layout for one mesh: method, omega, iterations to
    reach E_k/E_0 < 1e-1 ... 1e-10 ('-' = not reached), CPU and wall seconds
    of the method's own solve (SOLVE_SECONDS_NOTE)."""
    head = ["mesh", "method", "omega"] + [_tol_header(t) for t in data["tolerances"]] + ["solve CPU (s)",
                                                                                        "solve wall (s)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join(["---"] * 3 + ["---:"] * (len(head) - 3)) + "|"]
    for j, r in enumerate(data["methods"]):
        cells = [name if j == 0 else "", r["label"], omega_text(r["omega"])]
        if r["refused"] is not None:
            cells += ["refused"] + [""] * (len(r["reached"]) - 1) + ["-", "-"]
        else:
            cells += ["-" if k is None else str(k) for k in r["reached"]]
            cells += [f"{r['cpu_seconds']:.4f}", f"{r['wall_seconds']:.4f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def compare_csv(data: dict) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["method", "omega", "iterations", "converged", "stop_reason"]
                    + [f"iterations_to_{_tol_header(t)}" for t in data["tolerances"]]
                    + ["cpu_seconds", "wall_seconds"])
    for r in data["methods"]:
        writer.writerow([r["method"], "" if r["omega"] is None else repr(float(r["omega"])), r["iterations"],
                         r["converged"], r["stop_reason"]] + ["" if k is None else k for k in r["reached"]]
                        + [f"{r['cpu_seconds']:.6f}", f"{r['wall_seconds']:.6f}"])
    return buf.getvalue()
