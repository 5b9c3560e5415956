"""Speed of sorpia.repair on a large mesh, side by side with validation alone.

Clean: sorpia.shapes.irregular(--vertices) as it is; sorpia.repair against
the validation every sorpia function already pays (the topology build of
sorpia.limit_points and sorpia.interpolate: converting the faces and
sorpia::Topology), and the core alone (_core.repair against _core.Topology).
Defects: the same mesh with a few hundred defects injected at random faces
(reversed faces, exact and reversed duplicates, degenerate faces, bowties made
by a triangle hung on one vertex, non-manifold edges made by a third face on an
edge), repaired; the repaired mesh is checked to pass sorpia's validation.

Runs alternate between the sides; medians of --repeat runs. Prints a Markdown
table; --json writes the figures.

    python bench/repair_speed.py [--vertices 1000000] [--defects 100] [--repeat 5] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import time

import numpy as np

import sorpia
from sorpia import _core
from sorpia.limit import topology


def inject_defects(v, f, k, seed=0):
    """k of each kind of defect (2k duplicates, half of them reversed), at random faces."""
    rng = np.random.default_rng(seed)
    n = len(v)
    at = rng.choice(len(f), 5 * k, replace=False)
    bad = f.copy()
    flipped, dup, nm, hang, degenerate = np.split(at, 5)
    bad[flipped] = bad[flipped][:, [0, 2, 1]]
    dups = np.vstack([f[dup[: k // 2]], f[dup[k // 2:]][:, [0, 2, 1]]])
    extra = np.arange(n, n + 3 * k).reshape(k, 3)  # new vertices: a third face on an edge, a triangle on a vertex
    third_faces = np.column_stack([f[nm, 0], f[nm, 1], extra[:, 0]])
    hung = np.column_stack([f[hang, 0], extra[:, 1], extra[:, 2]])
    degenerate_faces = np.column_stack([f[degenerate, 0], f[degenerate, 0], f[degenerate, 1]])
    faces = np.vstack([bad, dups, third_faces, hung, degenerate_faces]).astype(np.int32)
    vertices = np.vstack([v, rng.normal(size=(3 * k, 3))])
    return vertices, faces


def alternate(fns, repeat):
    """Median seconds of each function, run in turn `repeat` times."""
    times = {name: [] for name in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {name: statistics.median(ts) for name, ts in times.items()}


def commit():
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--defects", type=int, default=100, help="defects of each of the five kinds")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json")
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

    dv, df = inject_defects(v, f, args.defects)
    defects = alternate({"sorpia.repair": lambda: sorpia.repair(dv, df),
                         "core: sorpia::repair": lambda: _core.repair(df, len(dv))}, args.repeat)
    result = sorpia.repair(dv, df)
    _core.Topology(result.faces, len(result.vertices))  # the repaired mesh passes validation
    counts = result.report["counts"]

    machine = f"{platform.machine()}, {platform.processor() or platform.system()}"
    print(f"sorpia.repair at {len(v):,} vertices, {len(f):,} faces; commit {commit()}; {machine}; "
          f"median of {args.repeat}, alternated\n")
    print("| clean mesh | seconds | vs validation |")
    print("|---|---:|---:|")
    base = clean["validation (sorpia's topology build)"]
    core_base = clean["core: sorpia::Topology"]
    for name, t in clean.items():
        ref = core_base if name.startswith("core") else base
        print(f"| {name} | {t:.3f} | {t / ref:.2f}x |")
    print(f"\n| {sum(counts.values())} changes ({', '.join(f'{k} {n}' for k, n in counts.items() if n)}) "
          "| seconds |")
    print("|---|---:|")
    for name, t in defects.items():
        print(f"| {name} | {t:.3f} |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"vertices": len(v), "faces": len(f), "repeat": args.repeat, "commit": commit(),
                       "machine": machine, "clean_seconds": clean, "defect_seconds": defects, "counts": counts},
                      fh, indent=1)


if __name__ == "__main__":
    main()
