"""sorpia.repair on a folder of mesh files: what each needed, and whether the repaired mesh fits.

Each file is read with sorpia.read_mesh(path, triangulate=True); a mesh sorpia
refuses is repaired; every mesh (repaired or not) is interpolated and the
limit positions of the control mesh compared with the input vertex each output
vertex copies. Prints a Markdown table; --json writes the rows.

    python bench/repair_meshes.py DIR [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

import sorpia
from sorpia.limit import topology


def one(path: Path) -> dict:
    row = {"mesh": path.name}
    try:
        v, f = sorpia.read_mesh(str(path), triangulate=True)
    except ValueError as e:
        return {**row, "status": f"unread: {e}"}
    row.update(vertices=len(v), faces=len(f))
    try:
        topology(f, len(v), warn=False)
        row["refusal"] = ""
    except sorpia.MeshError as e:
        row["refusal"] = str(e).split(":")[0]
    t0 = time.perf_counter()
    try:
        r = sorpia.repair(v, f)
    except sorpia.MeshError as e:
        return {**row, "status": f"repair refused: {e}"}
    row["repair_seconds"] = time.perf_counter() - t0
    row["changes"] = {k: n for k, n in r.report["counts"].items() if n}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        fit = sorpia.interpolate(r.vertices, r.faces)
        limit = sorpia.limit_points(fit.control_vertices, r.faces)
    used = np.unique(r.faces)
    scale = max(1.0, float(np.abs(v).max()))
    row.update(converged=bool(fit.converged), sweeps=int(fit.iterations),
               max_error=float(np.abs(limit[used] - np.asarray(v)[r.vertex_map[used]]).max() / scale))
    row["status"] = "fits" if fit.converged and row["max_error"] <= 1e-8 else "does not fit"
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--json")
    args = ap.parse_args()
    paths = sorted(p for p in Path(args.folder).iterdir() if p.suffix.lower() in {".obj", ".off", ".ply", ".stl"})
    rows = [one(p) for p in paths]
    print("| mesh | vertices | refused as | repairs | sweeps | max error / scale | status |")
    print("|---|---:|---|---|---:|---:|---|")
    for r in rows:
        changes = ", ".join(f"{k} {n}" for k, n in r.get("changes", {}).items())
        err = f"{r['max_error']:.1e}" if "max_error" in r else ""
        print(f"| {r['mesh']} | {r.get('vertices', '')} | {r.get('refusal', '')} | {changes} | "
              f"{r.get('sweeps', '')} | {err} | {r['status']} |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
