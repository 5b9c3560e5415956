"""What `sorpia fit` costs against the library it runs, file in -> file out.

Writes a binary PLY of sorpia.shapes.irregular(--vertices, 1), then runs,
each as a process of its own (interpreter start included), alternated,
--repeat times:

- command: ``sorpia fit big.ply -o out.ply --binary --quiet``;
- library: the same work through the Python API in a script: read_mesh, an
  Interpolator, the statistics of its topology, the solve, write_mesh and the
  check of the written control vertices;
- library, fit only: read_mesh, interpolate, write_mesh (no statistics, no check);
- info: ``sorpia info big.ply``.

Reports the median wall seconds and the median peak resident memory of each
(/usr/bin/time's maximum resident set size), and the command's ratios to the library.
Prints a Markdown table, writes bench/cli_cost.json and the docs page
docs/benchmarks/cli-cost.md.

    python bench/cli_cost.py [--vertices 1000000] [--repeat 3] [--dir DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

import sorpia

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402

LIBRARY = """
import sys
import sorpia
from sorpia import _core
from sorpia._meshinfo import topology_info
V0, F = sorpia.read_mesh(sys.argv[1])
interp = sorpia.Interpolator(F, len(V0))
stats = topology_info(V0, interp.topology)
res = interp.solve(V0)
sorpia.write_mesh(sys.argv[2], res.control_vertices, F, binary=True)
worst, _, _ = _core.limit_residual(interp.topology, res.control_vertices, V0, "edge-and-corner")
assert res.converged and worst < 1e-6 * stats["diagonal"]
"""

LIBRARY_FIT_ONLY = """
import sys
import sorpia
V0, F = sorpia.read_mesh(sys.argv[1])
res = sorpia.interpolate(V0, F)
sorpia.write_mesh(sys.argv[2], res.control_vertices, F, binary=True)
"""


def run(argv, scratch: Path) -> tuple[float, float]:
    """(wall seconds, peak RSS in MB) of one child process. The peak is
    /usr/bin/time's (%M): the RSS a process forked from this one reports
    (ru_maxrss) starts at this process's own."""
    report = scratch / "time.txt"
    t0 = time.perf_counter()
    proc = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", report, *argv], stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, argv))} exited {proc.returncode}: {proc.stderr}")
    return wall, int(report.read_text().split()[-1]) / 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dir", default=None, help="folder for the files (default: a temporary folder)")
    args = ap.parse_args()
    load = os.getloadavg()[0]  # other work on the machine inflates every wall time alike; the ratios hold better

    with tempfile.TemporaryDirectory(dir=args.dir) as tmp:
        tmp = Path(tmp)
        big = tmp / "big.ply"
        V, F = sorpia.shapes.irregular(args.vertices, 1)
        sorpia.write_mesh(big, V, F, binary=True)
        del V, F
        (tmp / "library.py").write_text(LIBRARY)
        (tmp / "library_fit_only.py").write_text(LIBRARY_FIT_ONLY)
        script = Path(sysconfig.get_path("scripts")) / "sorpia"
        cases = {
            "command (sorpia fit)": [script, "fit", big, "-o", tmp / "a.ply", "--binary", "--quiet"],
            "library (read, statistics, fit, write, check)": [sys.executable, tmp / "library.py", big,
                                                              tmp / "b.ply"],
            "library, fit only (read, interpolate, write)": [sys.executable, tmp / "library_fit_only.py", big,
                                                             tmp / "c.ply"],
            "sorpia info": [script, "info", big],
        }
        samples = {name: [] for name in cases}
        for _ in range(args.repeat):
            for name, argv in cases.items():  # alternated: each round runs every case once
                samples[name].append(run(argv, tmp))

    median = {name: (statistics.median(w for w, _ in s), statistics.median(m for _, m in s))
              for name, s in samples.items()}
    command, library = median["command (sorpia fit)"], median["library (read, statistics, fit, write, check)"]
    lines = [f"{args.vertices} vertices (sorpia.shapes.irregular(n, 1), binary PLY); median of {args.repeat} "
             f"runs, alternated; each a process of its own, interpreter start included; load average "
             f"{load:.1f} at the start.", "",
             "| run | wall (s) | peak RSS (MB) | wall / library | peak / library |", "|---|---:|---:|---:|---:|"]
    for name, (wall, peak) in median.items():
        lines.append(f"| {name} | {wall:.3f} | {peak:.0f} | {wall / library[0]:.2f} | {peak / library[1]:.2f} |")
    table = "\n".join(lines)
    print(table)
    out = {"vertices": args.vertices, "repeat": args.repeat, "load_average": load,
           "runs": {name: {"wall_seconds": [w for w, _ in s], "peak_rss_mb": [m for _, m in s],
                           "median_wall_seconds": median[name][0], "median_peak_rss_mb": median[name][1]}
                    for name, s in samples.items()},
           "command_over_library": {"wall": command[0] / library[0], "peak": command[1] / library[1]}}
    Path(__file__).with_name("cli_cost.json").write_text(json.dumps(out, indent=2) + "\n")
    write_page("cli-cost", "What `sorpia fit` costs against the library", table)


if __name__ == "__main__":
    main()
