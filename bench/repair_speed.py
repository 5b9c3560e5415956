"""Speed of sorpia.repair on a large mesh, side by side with validation alone.

Clean: sorpia.shapes.irregular(--vertices) as it is; sorpia.repair against
the validation every sorpia function already pays (the topology build of
sorpia.limit_points and sorpia.interpolate: converting the faces and
sorpia::Topology), and the core alone (_core.repair against _core.Topology).
Defects: the same mesh with a few hundred defects injected at random faces
(reversed faces, exact and reversed duplicates, degenerate faces, bowties made
by a triangle hung on one vertex, non-manifold edges made by a third face on an
edge), repaired, and again without the degenerate faces; each repaired mesh is
checked to pass sorpia's validation.

Quads: sorpia.shapes.quad_irregular(--vertices), clean and with the same
kinds of defects made of quads (a degenerate quad repeats a corner
consecutively, so repair keeps it as a triangle), repaired by the polygon path
(sorpia::repair on counts and indices) against the polygon validation.

Runs alternate between the sides; medians of --repeat runs. Prints Markdown
tables and writes them into docs/benchmarks/repair-speed.md (unless
--no-page); --json writes the figures.

    python bench/repair_speed.py [--vertices 1000000] [--defects 100] [--repeat 5] [--json out.json] [--no-page]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time

import numpy as np

import sorpia
from sorpia import _core
from sorpia.limit import topology

sys.path.insert(0, os.path.dirname(__file__))
from _report import commit, write_page  # noqa: E402


def inject_defects(v, f, k, seed=0, degenerate=True):
    """k of each kind of defect (k duplicates, half of them reversed), at random faces; without
    `degenerate`, no degenerate faces."""
    rng = np.random.default_rng(seed)
    n = len(v)
    at = rng.choice(len(f), 5 * k, replace=False)
    bad = f.copy()
    flipped, dup, nm, hang, degenerate_at = np.split(at, 5)
    bad[flipped] = bad[flipped][:, [0, 2, 1]]
    dups = np.vstack([f[dup[: k // 2]], f[dup[k // 2:]][:, [0, 2, 1]]])
    extra = np.arange(n, n + 3 * k).reshape(k, 3)  # new vertices: a third face on an edge, a triangle on a vertex
    third_faces = np.column_stack([f[nm, 0], f[nm, 1], extra[:, 0]])
    hung = np.column_stack([f[hang, 0], extra[:, 1], extra[:, 2]])
    degenerate_faces = np.column_stack([f[degenerate_at, 0], f[degenerate_at, 0], f[degenerate_at, 1]])
    faces = np.vstack([bad, dups, third_faces, hung] + ([degenerate_faces] if degenerate else [])).astype(np.int32)
    vertices = np.vstack([v, rng.normal(size=(3 * k, 3))])
    return vertices, faces


def inject_quad_defects(v, f, k, seed=0):
    """inject_defects for an (m, 4) quad array: reversed quads, duplicates (half reversed), a third quad on an
    edge, a quad hung on a vertex, and quads repeating a corner; (vertices, faces as an (m', 4) array)."""
    rng = np.random.default_rng(seed)
    n = len(v)
    flipped, dup, nm, hang, degenerate_at = np.split(rng.choice(len(f), 5 * k, replace=False), 5)
    bad = f.copy()
    bad[flipped] = bad[flipped][:, [0, 3, 2, 1]]
    dups = np.vstack([f[dup[: k // 2]], f[dup[k // 2:]][:, [0, 3, 2, 1]]])
    extra = np.arange(n, n + 5 * k).reshape(k, 5)  # new vertices: 2 for a third quad on an edge, 3 for a hung quad
    third_faces = np.column_stack([f[nm, 0], f[nm, 1], extra[:, 0], extra[:, 1]])
    hung = np.column_stack([f[hang, 0], extra[:, 2], extra[:, 3], extra[:, 4]])
    degenerate = np.column_stack([f[degenerate_at, 0], f[degenerate_at, 0], f[degenerate_at, 1], extra[:, 2]])
    faces = np.vstack([bad, dups, third_faces, hung, degenerate]).astype(np.int32)
    return np.vstack([v, rng.normal(size=(5 * k, 3))]), faces


def alternate(fns, repeat):
    """Median seconds of each function, run in turn `repeat` times."""
    times = {name: [] for name in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {name: statistics.median(ts) for name, ts in times.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--defects", type=int, default=100, help="defects of each of the five kinds")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/benchmarks/repair-speed.md")
    args = ap.parse_args()

    v, f = sorpia.shapes.irregular(args.vertices, 1)
    v, f = np.ascontiguousarray(v), np.ascontiguousarray(f, np.int32)
    clean = alternate({
        "validation (sorpia's topology build)": lambda: topology(f, len(v), warn=False),
        "sorpia.repair": lambda: sorpia.repair(v, f),
        "core: sorpia::Topology": lambda: _core.Topology(f, len(v)),
        "core: sorpia::repair": lambda: _core.repair(f, len(v)),
    }, args.repeat)
    assert sorpia.repair(v, f).faces is f

    # A degenerate face ends the first validity check at once; without one it runs to its end.
    variants = {"5 kinds": inject_defects(v, f, args.defects),
                "no degenerate faces": inject_defects(v, f, args.defects, degenerate=False)}
    defects, counts = {}, {}
    for label, (dv, df) in variants.items():
        defects[f"sorpia.repair, {label}"] = lambda dv=dv, df=df: sorpia.repair(dv, df)
        defects[f"core: sorpia::repair, {label}"] = lambda dv=dv, df=df: _core.repair(df, len(dv))
        result = sorpia.repair(dv, df)
        _core.Topology(result.faces, len(result.vertices))  # the repaired mesh passes validation
        counts[label] = result.changes["counts"]
    defects = alternate(defects, args.repeat)

    qv, qf = sorpia.shapes.quad_irregular(args.vertices, 1)
    qv, qf = np.ascontiguousarray(qv), np.ascontiguousarray(qf, np.int32)
    q_counts, q_indices = np.full(len(qf), 4, np.int32), qf.ravel()
    dqv, dqf = inject_quad_defects(qv, qf, args.defects)
    dq_counts, dq_indices = np.full(len(dqf), 4, np.int32), dqf.ravel()
    quads = alternate({
        "core: sorpia::Topology, clean quads": lambda: _core.Topology(q_counts, q_indices, len(qv)),
        "core: sorpia::repair, clean quads": lambda: _core.repair_polygons(q_counts, q_indices, len(qv)),
        "sorpia.repair, quads with 5 kinds": lambda: sorpia.repair(dqv, dqf),
        "core: sorpia::repair, quads with 5 kinds": lambda: _core.repair_polygons(dq_counts, dq_indices, len(dqv)),
    }, args.repeat)
    assert sorpia.repair(qv, qf).faces is qf
    result = sorpia.repair(dqv, dqf)
    topology(result.faces, len(result.vertices), scheme="catmull-clark", warn=False)  # passes validation
    counts["quads with 5 kinds"] = result.changes["counts"]

    machine = f"{platform.machine()}, {platform.processor() or platform.system()}"
    lines = [f"sorpia.repair at {len(v):,} vertices, {len(f):,} faces (sorpia.shapes.irregular); median of "
             f"{args.repeat}, alternated; load average {os.getloadavg()[0]:.1f} at the end.", "",
             "| clean mesh | seconds | vs validation |", "|---|---:|---:|"]
    base = clean["validation (sorpia's topology build)"]
    core_base = clean["core: sorpia::Topology"]
    for name, t in clean.items():
        ref = core_base if name.startswith("core") else base
        lines.append(f"| {name} | {t:.3f} | {t / ref:.2f}x |")
    for label, c in counts.items():
        lines += ["", f"{label}: " + ", ".join(f"{k} {n}" for k, n in c.items() if n)]
    lines += ["", "| mesh with defects | seconds |", "|---|---:|"]
    lines += [f"| {name} | {t:.3f} |" for name, t in defects.items()]
    lines += ["", f"Quads: sorpia.shapes.quad_irregular, {len(qv):,} vertices, {len(qf):,} quads; {len(dqf) - len(qf)} "
              "defect quads added.", "", "| quads | seconds |", "|---|---:|"]
    lines += [f"| {name} | {t:.3f} |" for name, t in quads.items()]
    print("\n".join(lines))
    if not args.no_page:
        write_page("repair-speed", "Speed of `sorpia.repair`", "\n".join(lines), settings=(ap, args))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"vertices": len(v), "faces": len(f), "repeat": args.repeat, "commit": commit(),
                       "load_average": os.getloadavg()[0],
                       "machine": machine, "clean_seconds": clean, "defect_seconds": defects, "quad_seconds": quads,
                       "counts": counts},
                      fh, indent=1)


if __name__ == "__main__":
    main()
