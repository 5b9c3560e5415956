"""Speed and accuracy of sorpia.decimate's cages: Catmull-Clark (and Loop) cages of a fraction of a noisy torus's
vertices; time (median of the repeats) and the RMS distance of the input vertices to the cage's triangles
(bench/approximate_peers.py's exact distances_to_mesh), relative to the bounding-box diagonal.

    python bench/decimate_speed.py --sizes 100000 500000 --fraction 0.02 --repeats 3 --scheme catmull-clark
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time

import numpy as np

import sorpia

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from approximate_peers import distances_to_mesh  # noqa: E402


def noisy_torus(n, noise, seed=0):
    nv = int(round(np.sqrt(n / 2.5)))
    nu = int(round(n / nv))
    mesh = sorpia.shapes.torus(nu, nv)
    v = np.asarray(mesh[0], dtype=float)
    v = v + np.random.default_rng(seed).normal(scale=noise, size=v.shape)
    return v, np.asarray(mesh[1])


def triangles_of(faces):
    faces = np.asarray(faces)
    if faces.shape[1] == 3:
        return faces
    return np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[100_000, 500_000])
    ap.add_argument("--fraction", type=float, default=0.02)
    ap.add_argument("--noise", type=float, default=1e-3)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--scheme", default="catmull-clark")
    args = ap.parse_args()
    rows = []
    for n in args.sizes:
        v, f = noisy_torus(n, args.noise)
        target = int(round(args.fraction * len(v)))
        times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            cage = sorpia.decimate(v, f, target, scheme=args.scheme)
            times.append(time.perf_counter() - t0)
        cv = np.asarray(cage[0])
        d = distances_to_mesh(v, cv, triangles_of(cage[1]))
        diag = float(np.linalg.norm(v.max(0) - v.min(0)))
        row = dict(n=len(v), target=target, cage=len(cv), seconds=float(np.median(times)), times=times,
                   rms_rel=float(np.sqrt(np.mean(d ** 2)) / diag), load=os.getloadavg()[0])
        print(json.dumps(row), flush=True)
        rows.append(row)


if __name__ == "__main__":
    main()
