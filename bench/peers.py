"""sorpia against the peers a user would reach for, side by side on one mesh.

    python bench/peers.py irregular:1000000 --repeat 3
    python bench/peers.py icosphere:7 --methods sor,gs,cg --json peers.json

One run, one machine, one mesh, every entry timed `--repeat` times (medians):

- peer 1, "splu": B from sorpia.limit_matrix (OpenSubdiv), then
  scipy.sparse.linalg.splu(B) and one solve: the direct solve.
- peer 2, "numpy-wpia": B from sorpia.limit_matrix, then the weighted PIA
  V += sigma (V0 - B V) with scipy's sparse product, sigma = 2 / (lmin + lmax),
  lmax = 1 (rows of B are non-negative and sum to 1) and lmin from 100 power
  iterations on I - B, stopped by the paper's rule E_k / E_0 < tol.
- sorpia's methods, each through sorpia.interpolate (arrays in, control
  vertices out), and the same through the C++ sorpia-bench, which also
  measures the streaming floor (one plain pass over the arrays a sweep touches)
  and reports each sweep as a multiple of it.

Every peer includes the time to build B, as sorpia's end-to-end time includes
its own topology and operator. "solve" is the iteration alone (peer 2: without
its eigenvalue estimate, reported as "estimate"); ratios are peer time over
sorpia's "sor" time. The tables also go into docs/benchmarks/peers.md (unless
--no-page). Nothing here runs under pytest.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
import warnings

import numpy as np
import scipy
import scipy.sparse.linalg

import sorpia

sys.path.insert(0, os.path.dirname(__file__))
from _report import write_page  # noqa: E402
from scaling import bench_exe  # noqa: E402


def load(spec: str):
    """(vertices, faces) from a mesh file or a generated mesh spec (same syntax as sorpia-bench)."""
    if ":" in spec and "." not in spec:
        kind, _, args = spec.partition(":")
        make = getattr(sorpia.shapes, kind, None)
        if make is None:
            raise SystemExit(f"unknown mesh {spec!r}")
        nums = [int(x) for x in args.replace("x", ":").split(":")]
        return make(*nums)
    return sorpia.read_mesh(spec)


def relative_error(B, V0, V, E0):
    """E_k / E_0 with E = max_i ||v0_i - (B V)_i|| (paper section 5)."""
    return float(np.sqrt(((V0 - B @ V) ** 2).sum(axis=1)).max() / E0)


def peer_splu(V0, F, tol):
    t0 = time.perf_counter()
    B = sorpia.limit_matrix(F, len(V0))
    t1 = time.perf_counter()
    lu = scipy.sparse.linalg.splu(B.tocsc())
    V = lu.solve(V0)
    t2 = time.perf_counter()
    E0 = np.sqrt(((V0 - B @ V0) ** 2).sum(axis=1)).max()
    return {"operator": t1 - t0, "solve": t2 - t1, "estimate": 0.0, "total": t2 - t0, "iterations": 1,
            "final_error": relative_error(B, V0, V, E0)}


def peer_numpy_wpia(V0, F, tol, max_iter=10000):
    t0 = time.perf_counter()
    B = sorpia.limit_matrix(F, len(V0))
    t1 = time.perf_counter()
    # lmin(B) = 1 - lmax(I - B): power iterations on I - B from a fixed start.
    x = np.random.default_rng(0).standard_normal(len(V0))
    mu = 0.0
    for _ in range(100):
        y = x - B @ x
        mu = np.linalg.norm(y) / np.linalg.norm(x)
        x = y / np.linalg.norm(y)
    sigma = 2.0 / ((1.0 - mu) + 1.0)
    t2 = time.perf_counter()
    V = V0.copy()
    R = V0 - B @ V
    E0 = np.sqrt((R ** 2).sum(axis=1)).max()
    k = 0
    err = 1.0
    while err >= tol and k < max_iter:
        V += sigma * R
        R = V0 - B @ V
        err = np.sqrt((R ** 2).sum(axis=1)).max() / E0
        k += 1
    t3 = time.perf_counter()
    return {"operator": t1 - t0, "estimate": t2 - t1, "solve": t3 - t2, "total": t3 - t0, "iterations": k,
            "final_error": err}


def sorpia_method(V0, F, tol, method):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = sorpia.interpolate(V0, F, method=method, tol=tol)
    total = time.perf_counter() - t0
    t = r.timings
    return {"topology": t.get("topology", 0.0), "operator": t.get("operator", 0.0), "estimate": t.get("estimate", 0.0),
            "solve": t.get("solve", 0.0), "total": total, "iterations": r.iterations,
            "final_error": float(r.history[-1])}


def sorpia_bench(spec, methods, tol, repeat):
    """The C++ figures (phases, floor, sweep/floor) from sorpia-bench --json, or None."""
    exe = bench_exe()
    if exe is None:
        return None
    out = subprocess.run([exe, spec, "--method", ",".join(methods), "--tol", str(tol), "--repeat", str(repeat),
                          "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)["meshes"][0]


def median_of(runs):
    keys = runs[0].keys()
    return {k: statistics.median(r[k] for r in runs) for k in keys}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("mesh", help="mesh file or generated mesh, e.g. irregular:1000000, icosphere:8, torus:1000x1000")
    p.add_argument("--methods", default="sor,gs,cg,pia,wpia", help="sorpia methods, comma-separated")
    p.add_argument("--tol", type=float, default=1e-10)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--splu-max", type=int, default=600_000,
                   help="skip splu above this many vertices (its fill-in needs several GB)")
    p.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    p.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/peers.md")
    a = p.parse_args(argv)

    V0, F = load(a.mesh)
    n = len(V0)
    methods = [m for m in a.methods.split(",") if m]
    entries = {}
    for m in methods:
        entries[f"sorpia {m}"] = median_of([sorpia_method(V0, F, a.tol, m) for _ in range(a.repeat)])
    entries["numpy-wpia (peer 2)"] = median_of([peer_numpy_wpia(V0, F, a.tol) for _ in range(a.repeat)])
    if n <= a.splu_max:
        entries["splu (peer 1)"] = median_of([peer_splu(V0, F, a.tol) for _ in range(a.repeat)])
    cpp = sorpia_bench(a.mesh, methods, a.tol, a.repeat)

    ref = entries.get("sorpia sor") or next(iter(entries.values()))
    lines = [f"`{a.mesh}`: {n:,} vertices, {len(F):,} faces; tol {a.tol:g}; medians of {a.repeat}; "
             f"numpy {np.__version__}, scipy {scipy.__version__}. Every entry includes building B (peers: "
             "`sorpia.limit_matrix`; sorpia: topology + operator, the \"operator\" column); ratios are over "
             "sorpia `sor`.", "",
             "| entry | total s | operator s | estimate s | solve s | iterations | E_k/E_0 | total / sor "
             "| solve / sor |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, e in entries.items():
        op = e.get("topology", 0.0) + e["operator"]
        lines.append(f"| {name} | {e['total']:.3f} | {op:.3f} | {e['estimate']:.3f} | {e['solve']:.3f} "
                     f"| {int(e['iterations'])} | {e['final_error']:.2e} | {e['total'] / ref['total']:.2f} "
                     f"| {e['solve'] / ref['solve']:.2f} |")
    if cpp:
        lines += ["", f"C++ `sorpia-bench` on the same mesh: topology {cpp['topology']:.3f} s, operator "
                  f"{cpp['operator']:.3f} s, streaming floor {cpp['floor'] * 1e3:.2f} ms, peak "
                  f"{cpp['peak_rss_bytes'] / 2**20:.0f} MB ({cpp['bytes_per_vertex']:.0f} B/vertex above the input).",
                  "", "| method | solve s | estimate s | iterations | sweep ms | sweep / floor | end to end s "
                  "| peers, end to end / this |", "|---|---:|---:|---:|---:|---:|---:|---|"]
        peers = {k: e for k, e in entries.items() if "peer" in k}
        for m in cpp["methods"]:
            vs = ", ".join(f"{k.split()[0]} {e['total'] / m['end_to_end']:.1f}x" for k, e in peers.items())
            lines.append(f"| `{m['method']}` | {m['solve']:.3f} | {m['estimate']:.3f} | {m['iterations']} "
                         f"| {m['sweep'] * 1e3:.2f} | {m['sweep_over_floor']:.2f} | {m['end_to_end']:.3f} | {vs} |")
    print("\n".join(lines))
    if not a.no_page:
        slug = "peers-" + "".join(c if c.isalnum() else "-" for c in os.path.basename(a.mesh).lower())
        write_page(slug, f"Peers on {a.mesh}", "\n".join(lines), settings=(p, a))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"mesh": a.mesh, "n_vertices": n, "n_faces": len(F), "tol": a.tol, "repeat": a.repeat,
                       "entries": entries, "sorpia_bench": cpp}, fh, indent=1)


if __name__ == "__main__":
    main()
