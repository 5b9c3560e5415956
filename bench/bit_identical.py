"""Fingerprints of sorpia's outputs on a folder of meshes, to show that a
refactoring changes no bit of them.

For every mesh file in the folder (read with its OpenSubdiv tags; Loop for an
all-triangle mesh, Catmull-Clark otherwise) and every method, it runs
`sorpia.interpolate` and records the SHA-256 of the control vertices' bytes and
of the errors' bytes, the iterations and the stop reason; also a warm start,
"sor" on two threads, a local update (`Interpolator.update`) and
`limit_points`. A mesh or a case the library refuses is recorded with the
reason. Only keyword arguments are used, so the script runs against the API
before and after a change of positional parameters.

    python bench/bit_identical.py ../shared/meshes --out before.json
    python bench/bit_identical.py ../shared/meshes --out after.json --compare before.json

--compare prints every case whose fingerprint differs and how many were
compared, and exits 1 when any differs.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import warnings

import numpy as np

import sorpia

METHODS = ("pia", "wpia", "gs", "sor", "cg", "hss", "whss")


def _digest(arr) -> str:
    return hashlib.sha256(np.ascontiguousarray(arr, dtype=np.float64).tobytes()).hexdigest()


def _fingerprint(res) -> dict:
    return {"control_vertices": _digest(res.control_vertices), "errors": _digest(res.history),
            "iterations": int(res.iterations), "stop_reason": str(res.stop_reason)}


def _case(out: dict, name: str, run) -> None:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out[name] = run()
    except Exception as exc:  # a refusal is part of the behaviour compared
        out[name] = {"refused": f"{type(exc).__name__}: {exc}"}


def mesh_cases(path: str, max_iter: int) -> dict:
    out: dict = {}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            V, F, tags = sorpia.read_mesh(path, tags=True)
    except Exception as exc:
        return {"read": {"refused": f"{type(exc).__name__}: {exc}"}}
    all_triangles = isinstance(F, np.ndarray) and F.shape[1] == 3
    rules = dict(tags, scheme="loop" if all_triangles else "catmull-clark")
    nonmanifold = "sharp" if "nonman" in os.path.basename(path) else "error"
    for method in METHODS:
        _case(out, method, lambda: _fingerprint(sorpia.interpolate(V, F, method=method, max_iter=max_iter,
                                                                   nonmanifold=nonmanifold, **rules)))
    _case(out, "sor-threads-2", lambda: _fingerprint(sorpia.interpolate(V, F, threads=2, max_iter=max_iter,
                                                                        nonmanifold=nonmanifold, **rules)))
    _case(out, "warm-start", lambda: _fingerprint(sorpia.interpolate(V, F, initial=V * 1.01, max_iter=max_iter,
                                                                     nonmanifold=nonmanifold, **rules)))
    _case(out, "limit_points", lambda: {"limit_points": _digest(sorpia.limit_points(V, F, nonmanifold=nonmanifold,
                                                                                    **rules))})

    def update():
        interp = sorpia.Interpolator(F, len(V), **rules)
        first = interp.solve(V, max_iter=max_iter)
        moved = [0, len(V) // 2, len(V) - 1]
        res = interp.update(first, moved, V[moved] + 0.01, max_iter=max_iter)
        again = interp.update(res, moved[:1], V[moved[:1]] - 0.02, max_iter=max_iter)
        return {"solve": _fingerprint(first), "update": _fingerprint(res), "update-2": _fingerprint(again),
                "relaxations": [int(res.relaxations), int(again.relaxations)]}

    _case(out, "update", update)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder")
    parser.add_argument("--out", required=True, help="JSON file of the fingerprints")
    parser.add_argument("--compare", help="a JSON file of an earlier run to compare with")
    parser.add_argument("--max-iter", type=int, default=1000)
    args = parser.parse_args(argv)
    files = sorted(f for f in os.listdir(args.folder) if f.rsplit(".", 1)[-1].lower() in ("obj", "off", "ply", "stl"))
    result = {}
    for name in files:
        result[name] = mesh_cases(os.path.join(args.folder, name), args.max_iter)
        refused = [k for k, v in result[name].items() if "refused" in v]
        print(f"{name}: {len(result[name]) - len(refused)} cases, refused: {refused or 'none'}", flush=True)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1, sort_keys=True)
    if not args.compare:
        return 0
    with open(args.compare) as f:
        before = json.load(f)
    compared = differ = 0
    for mesh in sorted(set(before) | set(result)):
        for case in sorted(set(before.get(mesh, {})) | set(result.get(mesh, {}))):
            a, b = before.get(mesh, {}).get(case), result.get(mesh, {}).get(case)
            compared += 1
            if a != b:
                differ += 1
                print(f"DIFFERS {mesh} {case}:\n  before {a}\n  after  {b}")
    print(f"{compared} cases compared, {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
