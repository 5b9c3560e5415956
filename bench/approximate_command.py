"""The whole command on a million real points: `sorpia approximate scan.ply -o cage.obj --vertices 20000` (issue 32,
item 1), timed from outside and phase by phase.

    python bench/approximate_command.py                         # make the scan (cached under /tmp), time, write JSON
    python bench/approximate_command.py --runs 5 --json bench/approximate_command.json

The scan: a real mesh of ../shared/meshes (--mesh, default the Stanford bunny) decimated to --base vertices
(`sorpia.decimate`), then Loop's limit surface at level 3 (`sorpia.limit_surface`: 64 triangles per base face,
every vertex on the limit surface): about 1M vertices of a clean surface with the bunny's holes, written as binary
PLY (the input of the command), ASCII PLY and OBJ (for the read times). Each is made once and kept under --dir.

Timed: the command in a fresh process, --runs times, its wall seconds from this process (start to exit, Python's
start-up included) and its peak resident memory; its phases from its own --report (read, cage, approximate and
approximate's inner phases, write); `sorpia.read_mesh` of each file in this process, median of --runs. The JSON
row (--json) is what bench/approximate_scaling.py's page shows as its end-to-end row. Nothing here runs under
pytest.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
# ../shared/meshes beside the repository (or beside the folder of worktrees that holds it).
MESHES = next((p for p in (ROOT.parent / "shared" / "meshes", ROOT.parent.parent / "shared" / "meshes") if p.is_dir()),
              ROOT.parent / "shared" / "meshes")
DEFAULT_JSON = ROOT / "bench" / "approximate_command.json"


def make_scan(mesh: str, base: int, folder: pathlib.Path) -> dict:
    """The scan's three files (made once: reused when present); their paths and sizes."""
    import sorpia

    stem = folder / f"sorpia-scan-{pathlib.Path(mesh).stem}-{base}"
    files = {"ply": stem.with_suffix(".ply"), "ply_ascii": pathlib.Path(f"{stem}-ascii.ply"),
             "obj": stem.with_suffix(".obj")}
    if not all(p.exists() for p in files.values()):
        v, f = sorpia.read_mesh(MESHES / mesh)
        cage = sorpia.decimate(v, f, base, strict=False)
        sv, sf = sorpia.limit_surface(cage.vertices, cage.faces, level=3)
        sorpia.write_mesh(files["ply"], sv, sf, binary=True)
        sorpia.write_mesh(files["ply_ascii"], sv, sf)
        sorpia.write_mesh(files["obj"], sv, sf)
    v, f = sorpia.read_mesh(files["ply"])
    return {"mesh": mesh, "base": base, "vertices": int(len(v)), "faces": int(len(f)),
            "files": {k: str(p) for k, p in files.items()},
            "mb": {k: round(p.stat().st_size / 2 ** 20, 1) for k, p in files.items()}}


def time_command(scan: str, n_cage: int, runs: int, extra: list[str]) -> dict:
    """The command run `runs` times in fresh processes: median wall seconds, peak MB, the phases of the median run."""
    walls, peaks, reports = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(runs):
            out, rep = os.path.join(tmp, "cage.obj"), os.path.join(tmp, "report.json")
            cmd = [sys.executable, "-m", "sorpia", "approximate", scan, "-o", out, "--vertices", str(n_cage),
                   "--report", rep, "--force", "--quiet", *extra]
            before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
            t0 = time.perf_counter()
            done = subprocess.run(cmd, capture_output=True, text=True)
            walls.append(time.perf_counter() - t0)
            if done.returncode != 0:
                raise SystemExit(f"the command failed ({done.returncode}): {done.stderr.strip()[-2000:]}")
            # RUSAGE_CHILDREN's maxrss is the largest child so far: exact for the first run, a floor after.
            peaks.append(max(before, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024)
            with open(rep) as fh:
                reports.append(json.load(fh))
    median_run = sorted(range(runs), key=lambda i: walls[i])[runs // 2]
    rep = reports[median_run]
    return {"wall_s": statistics.median(walls), "wall_min_s": min(walls), "wall_max_s": max(walls),
            "peak_mb": max(peaks), "phases": rep["timings"], "iterations": rep["iterations"],
            "stop_reason": rep["stop_reason"], "cage_vertices": rep["cage"]["vertices"],
            "rms_relative": rep["final"]["rms_relative"], "max_relative": rep["final"]["max_relative"]}


def time_reads(files: dict, runs: int) -> dict:
    """sorpia.read_mesh of each file: median seconds."""
    import sorpia

    out = {}
    for kind, path in files.items():
        times = []
        for _ in range(runs):
            t0 = time.perf_counter()
            sorpia.read_mesh(path)
            times.append(time.perf_counter() - t0)
        out[kind] = statistics.median(times)
    return out


def page_lines(path=DEFAULT_JSON) -> list[str]:
    """The row of `path` (written by --json) as Markdown for bench/approximate_scaling.py's page; none when absent."""
    if not os.path.exists(path):
        return []
    with open(path) as fh:
        row = json.load(fh)
    c, scan, t = row["command"], row["scan"], row["command"]["phases"]
    inner = ", ".join(f"{k.split('.', 1)[1]} {v:.2f}" for k, v in t.items()
                      if k.startswith("approximate.") and k != "approximate.total")
    return ["", f"## The whole command at {scan['vertices']:,} points (bench/approximate_command.py)", "",
            f"`sorpia approximate scan.ply -o cage.obj --vertices {row['cage_asked']}` on a real scan: "
            f"{scan['mesh']} decimated to {scan['base']:,} vertices and refined by Loop's limit surface at level 3 "
            f"({scan['vertices']:,} vertices, binary PLY of {scan['mb']['ply']} MB), default settings, in a fresh "
            f"process (start-up included); 1-minute load average {row.get('load_start', float('nan')):.1f} before, "
            f"{row.get('load_end', float('nan')):.1f} after, on 2 cores.", "",
            "| wall s (median) | read s | cage s | approximate s | write s | iterations | RMS / diagonal | peak MB |",
            "|---:|---:|---:|---:|---:|---:|---:|---:|",
            f"| {c['wall_s']:.2f} | {t['read']:.2f} | {t['cage']:.2f} | {t['approximate']:.2f} | {t['write']:.2f} "
            f"| {c['iterations']} ({c['stop_reason']}) | {c['rms_relative']:.3g} | {c['peak_mb']:.0f} |", "",
            f"approximate's phases (s): {inner}."]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--mesh", default="stanford-bunny.obj", help="a triangle mesh of ../shared/meshes")
    p.add_argument("--base", type=int, default=16000, help="vertices of the mesh before level 3 (about 1M after)")
    p.add_argument("--vertices", type=int, default=20000, help="the cage's vertices (--vertices of the command)")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--dir", default=tempfile.gettempdir(), help="where the scan's files are made and kept")
    p.add_argument("--json", metavar="PATH", help=f"write the row (e.g. {DEFAULT_JSON.relative_to(ROOT)})")
    p.add_argument("--no-reads", action="store_true", help="time only the command")
    p.add_argument("extra", nargs="*", help="more options for the command (after --)")
    a = p.parse_args(argv)
    scan = make_scan(a.mesh, a.base, pathlib.Path(a.dir))
    print(f"scan: {scan['vertices']:,} vertices, {scan['faces']:,} faces ({scan['mb']})", file=sys.stderr)
    row = {"scan": scan, "cage_asked": a.vertices, "options": a.extra, "load_start": os.getloadavg()[0]}
    if not a.no_reads:
        row["read_s"] = time_reads(scan["files"], a.runs)
        print("read_mesh s: " + ", ".join(f"{k} {v:.3f}" for k, v in row["read_s"].items()), file=sys.stderr)
    row["command"] = time_command(scan["files"]["ply"], a.vertices, a.runs, a.extra)
    c = row["command"]
    row["load_end"] = os.getloadavg()[0]
    print(f"command: {c['wall_s']:.2f} s median of {a.runs} (min {c['wall_min_s']:.2f}, max {c['wall_max_s']:.2f}), "
          f"peak {c['peak_mb']:.0f} MB, {c['iterations']} iterations ({c['stop_reason']}), cage {c['cage_vertices']}, "
          f"RMS {c['rms_relative']:.3g}, max {c['max_relative']:.3g} of the diagonal", file=sys.stderr)
    print("phases: " + ", ".join(f"{k} {v:.2f}" for k, v in c["phases"].items()), file=sys.stderr)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(row, fh, indent=1)
            fh.write("\n")
    print(json.dumps(row))


if __name__ == "__main__":
    main()
