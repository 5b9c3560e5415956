"""Time and memory against mesh size: is every phase linear?

    python bench/scaling.py                       # irregular meshes, 10k .. 4M vertices
    python bench/scaling.py --sizes 10000,100000 --kind torus --no-page --plot /tmp/s.png

Runs sorpia-bench (C++, one process per size so that each peak memory is its
own) on generated meshes of growing size, prints a Markdown table of seconds
per phase, iterations, peak memory and bytes per vertex above the input
arrays, draws a log-log plot (matplotlib, Agg) with a dashed line of slope 1
through the smallest size, and writes both into the documentation page
docs/benchmarks/scaling.md (unless --no-page). Nothing here runs under pytest.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import sysconfig

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _report import PAGES, print_json_plot, write_page, write_readme_excerpt  # noqa: E402


def bench_exe():
    """The sorpia-bench installed into this Python's scripts folder (where CMake puts it, as pip does the
    `sorpia` script; not always next to sys.executable), else the one on PATH, else None."""
    exe = os.path.join(sysconfig.get_path("scripts"), "sorpia-bench")
    return exe if os.path.exists(exe) else shutil.which("sorpia-bench")


def spec(kind: str, n: int) -> str:
    if kind == "torus":  # nu x nv with nu = 2.5 nv, as irregular() does
        nv = max(3, round(math.sqrt(n / 2.5)))
        return f"torus:{max(3, n // nv)}x{nv}"
    if kind == "icosphere":  # the level nearest n
        return f"icosphere:{max(0, round(math.log(max(n, 12) / 10, 4)))}"
    return f"irregular:{n}"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="10000,100000,1000000,4000000")
    p.add_argument("--kind", choices=["irregular", "torus", "icosphere"], default="irregular")
    p.add_argument("--method", default="sor")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--plot", default=None, help="where to draw the plot (default: beside the page, "
                   "docs/benchmarks/scaling.png; with --no-page, no plot unless given)")
    p.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    p.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/scaling.md")
    p.add_argument("--readme", action="store_true", help="also put the table into README.md (its 'scaling table')")
    p.add_argument("--from-json", metavar="PATH", help="table and plot from an earlier --json, without running")
    a = p.parse_args(argv)
    exe = bench_exe()
    if exe is None and not a.from_json:
        sys.exit("sorpia-bench not found: pip install the package first")

    rows = []
    if a.from_json:
        with open(a.from_json) as fh:
            rows = json.load(fh)
    for n in [] if a.from_json else (int(s) for s in a.sizes.split(",")):
        out = subprocess.run([exe, spec(a.kind, n), "--method", a.method, "--repeat", str(a.repeat), "--json"],
                             capture_output=True, text=True)
        if out.returncode != 0:
            print(f"{spec(a.kind, n)}: sorpia-bench failed: {out.stderr.strip()}", file=sys.stderr)
            break
        m = json.loads(out.stdout)["meshes"][0]
        r = m["methods"][0]
        rows.append({"mesh": m["mesh"], "n": m["n_vertices"], "topology": m["topology"], "operator": m["operator"],
                     "solve": r["solve"], "estimate": r["estimate"], "iterations": r["iterations"],
                     "end_to_end": r["end_to_end"], "floor": m["floor"], "sweep_over_floor": r["sweep_over_floor"],
                     "peak_mb": m["peak_rss_bytes"] / 2**20, "bytes_per_vertex": m["bytes_per_vertex"]})

    table = ["| vertices | topology s | operator s | solve s | iterations | end to end s | peak MB "
             "| bytes/vertex above input |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    table += [f"| {r['n']:,} | {r['topology']:.3f} | {r['operator']:.4f} | {r['solve']:.3f} | {r['iterations']} "
              f"| {r['end_to_end']:.3f} | {r['peak_mb']:.0f} | {r['bytes_per_vertex']:.0f} |" for r in rows]
    table = [f"`sorpia-bench`, `{a.kind}` meshes, method `{a.method}` to 1e-10, one thread, medians of {a.repeat} "
             "(C++ core: arrays in, control vertices out):", ""] + table
    lines = [f"`{a.kind}` meshes, method `{a.method}`, one thread, medians of {a.repeat} runs of `sorpia-bench` "
             "(seconds).", "",
             "| mesh | vertices | topology s | operator s | solve s | iterations | end to end s | µs/vertex "
             "| sweep/floor | peak MB | bytes/vertex above input |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| `{r['mesh']}` | {r['n']:,} | {r['topology']:.3f} | {r['operator']:.4f} | {r['solve']:.3f} "
                     f"| {r['iterations']} | {r['end_to_end']:.3f} | {1e6 * r['end_to_end'] / r['n']:.2f} "
                     f"| {r['sweep_over_floor']:.2f} | {r['peak_mb']:.0f} | {r['bytes_per_vertex']:.0f} |")
    lines += ["", "sweep/floor: solve seconds per iteration over the streaming floor (one plain pass over the "
              "arrays a sweep touches, measured by `sorpia-bench`)."]
    lines = print_json_plot(lines, rows, json_path=a.json, plot=a.plot, no_page=a.no_page,
                            default_plot=PAGES / "scaling.png", draw=lambda r, path: draw(r, a.kind, a.method, path),
                            caption="time and memory against size")
    if not a.no_page:
        write_page("scaling", "Growth with size", "\n".join(lines), settings=(p, a))
    if a.readme:
        write_readme_excerpt("scaling table", "scaling", "\n".join(table))


def draw(rows, kind, method, path):
    """Log-log plot of the phases' seconds and of the peak memory against the vertex count."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = [r["n"] for r in rows]
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(10, 4))
    for key in ("topology", "operator", "solve", "end_to_end"):
        ax_t.loglog(n, [r[key] for r in rows], "o-", label=key.replace("_", " "))
    ax_t.loglog(n, [rows[0]["end_to_end"] * x / n[0] for x in n], "k--", lw=0.8, label="slope 1")
    ax_t.set(xlabel="vertices", ylabel="seconds", title=f"time ({kind}, {method})")
    ax_t.legend(fontsize=8)
    above = [r["bytes_per_vertex"] * r["n"] / 2**20 for r in rows]
    ax_m.loglog(n, [r["peak_mb"] for r in rows], "o-", label="peak resident MB")
    ax_m.loglog(n, above, "s-", label="peak above the input arrays, MB")
    ax_m.loglog(n, [above[-1] * x / n[-1] for x in n], "k--", lw=0.8, label="slope 1")
    ax_m.set(xlabel="vertices", ylabel="MB", title="peak memory (topology, operator, solve)")
    ax_m.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"plot: {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
