"""Fingerprints of sorpia's outputs on a folder of meshes, to show that a
refactoring changes no bit of them.

For every mesh file in the folder (read with its OpenSubdiv tags; Loop for an
all-triangle mesh, Catmull-Clark otherwise) and every method, it runs
`sorpia.interpolate` and records the SHA-256 of the control vertices' bytes and
of the errors' bytes, the iterations and the stop reason; also a warm start,
"sor" on two threads, a local update (`Interpolator.update`) and
`limit_points`. With --tasks fair: `sorpia.fair_interpolate` (every vertex;
every other vertex with a membrane and two levels; the reference metric on
meshes below 5,000 vertices), its fine control vertices, energies, faces and
the plain solve. With --tasks approximate: `sorpia.approximate` of the mesh's
vertices by its decimated cage (Loop and Catmull-Clark; LSPIA; weights; the
mesh's own surface sampled by area) and of the mesh's own limit surface,
perturbed, from the mesh itself with its tags (CG and LSPIA): the control
vertices, the footpoints, the history's figures (not its seconds). A mesh or
a case the library refuses is recorded with the reason. Only keyword
arguments are used, so the script runs against the API before and after a
change of positional parameters.

    python bench/bit_identical.py ../shared/meshes --out before.json
    python bench/bit_identical.py ../shared/meshes --out after.json --compare before.json
    python bench/bit_identical.py ../shared/meshes --tasks fair,approximate --out after.json --compare before.json

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


def _series(res, old: str):
    """A result's per-iteration array: `history` since the one result vocabulary, `old` (errors, energies)
    before it, so that the script runs against both."""
    value = getattr(res, old, None)
    return res.history if value is None else value


def _fingerprint(res) -> dict:
    return {"control_vertices": _digest(res.control_vertices), "errors": _digest(_series(res, "errors")),
            "iterations": int(res.iterations), "stop_reason": str(res.stop_reason)}


def _case(out: dict, name: str, run) -> None:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out[name] = run()
    except Exception as exc:  # a refusal is part of the behaviour compared
        out[name] = {"refused": f"{type(exc).__name__}: {exc}"}


def _read(path: str):
    """(V, F, tags, all_triangles), or the refusal's record."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            V, F, tags = sorpia.read_mesh(path, tags=True)
    except Exception as exc:
        return {"read": {"refused": f"{type(exc).__name__}: {exc}"}}
    return V, F, tags, isinstance(F, np.ndarray) and F.shape[1] == 3


def mesh_cases(path: str, mesh, max_iter: int) -> dict:
    out: dict = {}
    V, F, tags, all_triangles = mesh
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


def _fair_fingerprint(res) -> dict:
    return {"control_vertices": _digest(res.control_vertices), "energies": _digest(_series(res, "energies")),
            "faces": hashlib.sha256(np.ascontiguousarray(res.faces, dtype=np.int64).tobytes()).hexdigest(),
            "energy": float(res.energy), "plain_energy": float(res.plain_energy), "max_error": float(res.max_error),
            "iterations": int(res.iterations), "stop_reason": str(res.stop_reason),
            "plain": _fingerprint(res.plain)}


def fair_cases(mesh) -> dict:
    out: dict = {}
    V, F, tags, all_triangles = mesh
    rules = dict(tags, scheme="loop" if all_triangles else "catmull-clark")
    _case(out, "fair", lambda: _fair_fingerprint(sorpia.fair_interpolate(V, F, **rules)))
    _case(out, "fair-half-membrane-2", lambda: _fair_fingerprint(sorpia.fair_interpolate(
        V, F, levels=2, membrane=0.1, targets=np.arange(0, len(V), 2), **rules)) if len(V) < 10000 else
        {"skipped": "large"})
    if len(V) < 5000:
        _case(out, "fair-reference", lambda: _fair_fingerprint(sorpia.fair_interpolate(
            V, F, metric="reference", max_iter=300, **rules)))
    return out


def _approximation_fingerprint(res) -> dict:
    history = [{k: v for k, v in rec.items() if k != "seconds"} for rec in res.history]
    return {"control_vertices": _digest(res.control_vertices), "face_ids": _digest(res.face_ids.astype(np.float64)),
            "uv": _digest(res.uv), "distances": _digest(res.distances), "points": _digest(res.points),
            "iterations": int(res.iterations), "stop_reason": str(res.stop_reason),
            "best_iteration": int(res.best_iteration), "diagonal": float(res.diagonal), "history": history}


def approximate_cases(mesh) -> dict:
    out: dict = {}
    V, F, tags, all_triangles = mesh
    scheme = "loop" if all_triangles else "catmull-clark"
    weights = 1.0 + 0.5 * np.sin(np.arange(len(V)))  # deterministic, uneven
    if all_triangles:
        n_cage = max(50, len(V) // 50)
        for cage_scheme in ("loop", "catmull-clark"):
            def cage(cage_scheme=cage_scheme):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    return sorpia.decimate(V, F, min(n_cage, len(V) - 1), scheme=cage_scheme, strict=False)

            def fit(cage_scheme=cage_scheme, **options):
                c = cage(cage_scheme)
                return _approximation_fingerprint(sorpia.approximate(V, c.vertices, c.faces, scheme=cage_scheme,
                                                                     **options))

            _case(out, f"approximate-{cage_scheme}", lambda fit=fit: fit())
            _case(out, f"approximate-{cage_scheme}-lspia", lambda fit=fit: fit(method="lspia", iterations=4))
            _case(out, f"approximate-{cage_scheme}-weights", lambda fit=fit: fit(weights=weights, iterations=4))
            _case(out, f"approximate-{cage_scheme}-area", lambda fit=fit: fit(faces=F, sampling="area",
                                                                              iterations=4))

    # The mesh's own limit surface (level 1 of its tessellation), moved off by a fixed wave, fitted from the mesh
    # itself with its tags: any faces, creases, corners and holes.
    def own(**options):
        surface_vertices, _ = sorpia.limit_surface(V, F, level=1, scheme=scheme, **tags)
        size = float(np.ptp(V, axis=0).max()) or 1.0
        points = surface_vertices + 0.01 * size * np.sin(np.arange(surface_vertices.size)).reshape(-1, 3)
        return _approximation_fingerprint(sorpia.approximate(points, V, F, scheme=scheme, iterations=3, **tags,
                                                             **options))

    _case(out, "approximate-own", lambda: own())
    _case(out, "approximate-own-lspia", lambda: own(method="lspia"))
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder")
    parser.add_argument("--out", required=True, help="JSON file of the fingerprints")
    parser.add_argument("--compare", help="a JSON file of an earlier run to compare with")
    parser.add_argument("--max-iter", type=int, default=1000)
    parser.add_argument("--tasks", default="interpolate",
                        help="comma-separated: interpolate (default), fair, approximate")
    args = parser.parse_args(argv)
    tasks = args.tasks.split(",")
    unknown = set(tasks) - {"interpolate", "fair", "approximate"}
    if unknown:
        parser.error(f"--tasks: unknown {sorted(unknown)}")
    files = sorted(f for f in os.listdir(args.folder) if f.rsplit(".", 1)[-1].lower() in ("obj", "off", "ply", "stl"))
    result = {}
    for name in files:
        path = os.path.join(args.folder, name)
        mesh = _read(path)  # once for every task; a refusal is recorded under each task's "read"
        result[name] = {}
        if "interpolate" in tasks:
            result[name].update(mesh if isinstance(mesh, dict) else mesh_cases(path, mesh, args.max_iter))
        if "fair" in tasks:
            cases = mesh if isinstance(mesh, dict) else fair_cases(mesh)
            result[name].update({f"fair:{k}": v for k, v in cases.items()})
        if "approximate" in tasks:
            cases = mesh if isinstance(mesh, dict) else approximate_cases(mesh)
            result[name].update({f"approximate:{k}": v for k, v in cases.items()})
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
