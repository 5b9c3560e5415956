"""The footpoint search's speed at approximation's size (issue 32): the phases of one iteration's footpoints, two
builds side by side.

    python bench/footpoints_speed.py --before /tmp/base           # 1M points, 20k-vertex cage, 5 rounds
    python bench/footpoints_speed.py --points 100000 --cage 2000 --rounds 3
    python bench/footpoints_speed.py --callgrind refine            # instruction counts of one phase (small case)

The data (as bench/approximate_speed.py's): the limit surface of `sorpia.shapes.irregular(--cage)` (Loop) sampled at
--points random (face, u, v) with Gaussian noise of 1e-4 of the diagonal; the start cage: the mesh's vertices moved
by 2e-3 of the diagonal; the next cage: one `sorpia.approximate` iteration from it (the surface moves as in the
fit's loop). The memory a surface holds: the growth of the worker's resident set from making the next cage's
surface to having evaluated each face once, per face (``surface_bytes_per_face``). Phases, each timed in a worker process per build and round (the builds alternate, so that the shared
machine's load falls on both alike), medians over the rounds:

- ``find``: `_core.closest_points` on the start cage (the grid, its k-d tree, the nearest sample, Gauss-Newton);
- ``refine``: `_core.refine_footpoints` on the next cage from find's footpoints (the loop's warm start);
- ``closer``: `_core.closer_footpoints` on the next cage from refine's footpoints (the re-search before stopping
  and before reporting; FootpointOptions' defaults: 8 starts, the build's near unless --near), where the build has
  it;
- ``rows``: `LimitSurface.rows` (positions only) at refine's footpoints, in face order (the normal equations' rows,
  as approximation builds them).

The results are compared between the builds (largest difference of the distances over the diagonal). --before DIR
names a directory holding a `sorpia` package (a copy of an installed one) for the other build; without it only the
installed build runs. --callgrind PHASE runs that phase of the installed build once under valgrind's callgrind and
prints the functions' instruction counts (on one processor, `taskset -c 0`, so that every
thread's instructions are counted). Prints JSON. Nothing here runs under pytest.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def make_data(n_points: int, n_cage: int, path: str) -> None:
    import sorpia
    from approximate_speed import data

    P, V0, F = data(n_points, n_cage)
    diag = float(np.linalg.norm(P.max(0) - P.min(0)))
    V1 = sorpia.approximate(P, V0, F, iterations=1, tol=0).control_vertices
    np.savez(path, P=P, V0=V0, V1=V1, F=F, diag=diag)


def resident_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def worker(data: str, phase: str | None, out: str, near: float | None) -> None:
    """Times the phases (or runs one, for callgrind) with the sorpia on sys.path; writes timings and distances."""
    from sorpia import _core
    from sorpia.surface import LimitSurface

    d = np.load(data)
    P, F = d["P"], d["F"]
    res, times = {}, {}
    if phase is None:
        # The resident memory a surface holds per face once every face is evaluated (its Bfr surfaces, patch trees
        # and, where the build keeps them, prepared patch points), before anything else is allocated.
        rss = resident_bytes()
        s = LimitSurface(d["V1"], F)
        s.evaluate(np.arange(s.n_faces, dtype=np.int32), np.full((s.n_faces, 2), 0.25))
        times["surface_bytes_per_face"] = (resident_bytes() - rss) / s.n_faces
        del s
    s0, s1 = LimitSurface(d["V0"], F), LimitSurface(d["V1"], F)
    # Bfr's patch trees built (its factory caches them), as in a fit's loop after its first iteration; then the
    # control vertices set again, so that each phase prepares the faces' patch points at them itself, as after a
    # fit's update.
    for s in (s0, s1):
        s.evaluate(np.arange(s.n_faces, dtype=np.int32), np.full((s.n_faces, 2), 0.25))
        s.set_vertices(s.vertices)
    if phase in (None, "find"):
        t = time.perf_counter()
        found = _core.closest_points(s0._surface, s0._topology, P, 4, 10)
        times["find"] = time.perf_counter() - t
        res["find"] = found[3]
    else:
        found = _core.closest_points(s0._surface, s0._topology, P, 4, 10)
    if phase in (None, "refine", "closer"):
        t = time.perf_counter()
        refined = _core.refine_footpoints(s1._surface, s1._topology, P, found[0], found[1], 10)
        times["refine"] = time.perf_counter() - t
        res["refine"] = refined[3]
    if phase in (None, "closer") and hasattr(_core, "closer_footpoints"):
        t = time.perf_counter()
        kw = {} if near is None else {"near": near}
        closer = _core.closer_footpoints(s1._surface, s1._topology, P, refined[0], refined[1], 4, 10, 8, **kw)
        times["closer"] = time.perf_counter() - t
        dist = closer[0][3]
        if len(closer) > 2:  # the points certified (builds from the closer certificate on)
            times["closer_certified"] = closer[2] / len(P)
        res["closer"] = dist
        times["closer_moved"] = closer[1]
    if phase in (None, "rows"):
        if phase == "rows":
            refined = _core.refine_footpoints(s1._surface, s1._topology, P, found[0], found[1], 10)
        order = np.argsort(refined[0], kind="stable")
        fid, uv = refined[0][order], refined[1][order]
        t = time.perf_counter()
        A = s1._surface.rows(fid, uv, 0)[0]
        times["rows"] = time.perf_counter() - t
        from scipy.sparse import csr_matrix
        A = csr_matrix(A, shape=(len(fid), len(d["V1"])))
        res["rows"] = np.linalg.norm(A @ d["V1"] - refined[2][order], axis=1)  # against refine's positions
    np.savez(out, **res)
    with open(out + ".json", "w") as f:
        json.dump(times, f)


def run(build: str | None, data: str, tmp: str, phase: str | None = None, prefix: list[str] | None = None,
        near: float | None = None):
    env = dict(os.environ)
    if build:
        env["PYTHONPATH"] = build + os.pathsep + env.get("PYTHONPATH", "")
    out = os.path.join(tmp, "out")
    cmd = (prefix or []) + [sys.executable, __file__, "--worker", data, "--out", out] + \
        (["--phase", phase] if phase else []) + (["--near", str(near)] if near is not None else [])
    subprocess.run(cmd, env=env, check=True, capture_output=prefix is not None)
    with open(out + ".json") as f:
        times = json.load(f)
    return times, dict(np.load(out + ".npz"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--cage", type=int, default=20_000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--before", help="a directory holding the other build's sorpia package")
    ap.add_argument("--callgrind", choices=["find", "refine", "closer", "rows"])
    ap.add_argument("--near", type=float, help="closer's FootpointOptions::near (default: the build's)")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    ap.add_argument("--phase", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        worker(a.worker, a.phase, a.out, a.near)
        return
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "data.npz")
        make_data(a.points, a.cage, data)
        diag = float(np.load(data)["diag"])
        if a.callgrind:
            log = os.path.join(tmp, "callgrind.out")
            entry = {"find": "sorpia::closest_points*", "refine": "sorpia::refine_footpoints*",
                     "closer": "sorpia::FootpointSearch::closer*", "rows": "sorpia::LimitSurface::rows*"}[a.callgrind]
            run(None, data, tmp, a.callgrind,
                ["taskset", "-c", "0", "valgrind", "--tool=callgrind", f"--callgrind-out-file={log}",
                 f"--toggle-collect={entry}"],
                a.near)
            ann = subprocess.run(["callgrind_annotate", "--inclusive=no", log], capture_output=True, text=True).stdout
            print(json.dumps({"points": a.points, "cage": a.cage, "phase": a.callgrind,
                              "annotate": ann.splitlines()[:40]}, indent=1))
            return
        builds = {"after": None} if not a.before else {"before": a.before, "after": None}
        times = {b: [] for b in builds}
        results = {}
        for _ in range(a.rounds):
            for name, path in builds.items():
                t, r = run(path, data, tmp, near=a.near)
                times[name].append(t)
                results[name] = r
        report = {"points": a.points, "cage": a.cage, "rounds": a.rounds, "load": os.getloadavg()}
        for name in builds:
            report[name] = {k: statistics.median(t[k] for t in times[name]) for k in times[name][0]}
        if a.before:
            report["speedup"] = {k: report["before"][k] / report["after"][k] for k in report["after"]
                                 if k in report["before"] and k not in ("closer_moved", "closer_certified", "surface_bytes_per_face")}
            report["largest_difference_over_diagonal"] = {
                k: float(np.abs(results["before"][k] - results["after"][k]).max() / diag)
                for k in results["after"] if k in results["before"]}
        print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
