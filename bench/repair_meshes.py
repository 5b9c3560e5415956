"""`sorpia fit --repair` on a folder of mesh files: what each needed, and whether the repaired mesh fits.

The acceptance check of `sorpia repair`, run through the command's own functions in this process: for each
file, ``sorpia info`` (its verdict, and for a refused mesh what --repair would change), then ``sorpia fit
--repair`` (with --triangulate where the file has polygons) into a temporary folder, with its report: the
repair's counts, the sweeps, and the check of the written control mesh (max |B V - V0| over the bounding-box
diagonal, B V evaluated by OpenSubdiv's masks, V0 the input vertex each output vertex copies). "info explains"
says that info's would-fix counts are the counts of the repair fit made. Prints a Markdown table and writes it
into docs/benchmarks/repair-meshes.md (unless --no-page); --json writes the rows.

    python bench/repair_meshes.py DIR [--tol 1e-10] [--json out.json] [--no-page]
"""

from __future__ import annotations

import argparse
import io
import json
import os
import sys
import tempfile
from pathlib import Path

from sorpia.cli import common
from sorpia.cli.fit import run_fit
from sorpia.cli.info import run_info

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402


def one(path: Path, tol: float, tmp: str) -> dict:
    row = {"mesh": path.name}
    try:
        polygons = common.read_input(path, triangulate=True).polygons > 0
        _, info = run_info(path, triangulate=polygons, out=io.StringIO())
    except (ValueError, common.UserError) as e:
        return {**row, "status": f"unread: {e}"}
    verdict = info["loop_pia"]
    row.update(vertices=info["vertices"], faces=info["faces"], triangulated=polygons,
               refusal="" if verdict["can_run"] else verdict["reason"].split(":")[0],
               info_says=info.get("repair", {}).get("changes", []))
    try:
        code, fit = run_fit(path, os.path.join(tmp, "ctrl.ply"), tol=tol, repair=True, triangulate=polygons,
                            quiet=True, binary=True)
    except (ValueError, common.UserError) as e:
        return {**row, "status": f"refused: {e}"}
    counts = fit["repair"]["report"]["counts"]
    row.update(changes={k: n for k, n in counts.items() if n}, sweeps=fit["iterations"],
               converged=fit["converged"], max_residual_relative=fit["max_residual_relative"],
               repair_seconds=fit["timings"]["repair"],
               info_explains=verdict["can_run"] or info.get("repair", {}).get("counts") == counts)
    row["status"] = "fits" if fit["converged"] and row["max_residual_relative"] <= 1e-8 else "does not fit"
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--tol", type=float, default=1e-10, help="fit's --tol")
    ap.add_argument("--json")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/repair-meshes.md")
    args = ap.parse_args()
    paths = sorted(p for p in Path(args.folder).iterdir() if p.suffix.lower() in common.MESH_SUFFIXES)
    with tempfile.TemporaryDirectory() as tmp:
        rows = [one(p, args.tol, tmp) for p in paths]
    fits = sum(r["status"] == "fits" for r in rows)
    lines = [f"{len(rows)} mesh files; {fits} fit with `sorpia fit --repair` (`--triangulate` where a file has "
             "polygons, marked *); \"refused as\" is `sorpia info`'s verdict before repair; \"residual\" is max "
             "\\|B V - V0\\| of the written control mesh over the bounding-box diagonal.", "",
             "| mesh | vertices | faces | refused as | repaired | info explains | sweeps | residual | repair (s) "
             "| status |",
             "|---|---:|---:|---|---|---|---:|---:|---:|---|"]
    for r in rows:
        changes = ", ".join(f"{k} {n}" for k, n in r.get("changes", {}).items())
        residual = f"{r['max_residual_relative']:.1e}" if "max_residual_relative" in r else ""
        seconds = f"{r['repair_seconds']:.3f}" if "repair_seconds" in r else ""
        explains = {True: "yes", False: "no"}.get(r.get("info_explains"), "") if r.get("refusal") else ""
        lines.append(f"| {r['mesh']}{' *' if r.get('triangulated') else ''} | {r.get('vertices', '')} | "
                     f"{r.get('faces', '')} | {r.get('refusal', '')} | {changes} | {explains} | {r.get('sweeps', '')} "
                     f"| {residual} | {seconds} | {r['status']} |")
    table = "\n".join(lines)
    print(table)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    if not args.no_page:
        write_page("repair-meshes", "`sorpia fit --repair` on real meshes", table, settings=(ap, args))


if __name__ == "__main__":
    main()
