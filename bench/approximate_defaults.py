"""The study behind approximate()'s default objective (docs/approximation.md, "The default"): the tangent-distance
blend `tangential` against the fairness weight, both ways.

    python bench/approximate_defaults.py                       # the four shared scans and a noisy torus, Loop
    python bench/approximate_defaults.py --scheme catmull-clark --meshes mountain.obj,airplane.obj

On each mesh (as bench/approximate_peers.py loads it) the cage is `sorpia.decimate` to --fraction of the
vertices (the quad cage of as many vertices for Catmull-Clark; where the guards stop it, the cage where they
stopped). Each (tangential, fairness) pair runs `sorpia.approximate` for 4 and 10 iterations and prints one JSON
line: the RMS and largest distance data -> surface (`measure`) and surface -> dense mesh (`measure_back`), over
the diagonal, the call's seconds and why it stopped. Prints only; nothing here runs under pytest.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

import sorpia

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from approximate_peers import load, measure, measure_back  # noqa: E402

PAIRS = ((1.0, 0.0), (1.0, 1e-4), (0.2, 0.0), (0.2, 1e-4), (0.2, 3e-4),
         (0.1, 0.0), (0.1, 3e-5), (0.1, 1e-4), (0.1, 3e-4), (0.1, 1e-3))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--meshes", default="mountain.obj,stanford-bunny.obj,igl_bumpy-cube.obj,airplane.obj,"
                    "noisy-torus:100000")
    ap.add_argument("--scheme", choices=("loop", "catmull-clark"), default="loop")
    ap.add_argument("--fraction", type=float, default=0.02)
    args = ap.parse_args()
    for spec in args.meshes.split(","):
        name, v, f = load(spec)
        diag = float(np.linalg.norm(v.max(0) - v.min(0)))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sorpia.DecimationWarning)
            cage = sorpia.decimate(v, f, max(4, round(args.fraction * len(v))), scheme=args.scheme, strict=False)
        for t, fairness in PAIRS:
            for iterations in (4, 10):
                t0 = time.perf_counter()
                r = sorpia.approximate(v, cage.vertices, cage.faces, scheme=args.scheme, tangential=t,
                                       fairness=fairness, iterations=iterations)
                seconds = time.perf_counter() - t0
                rms, mx = measure(v, r.control_vertices, cage.faces, diag, args.scheme)
                srms, smax = measure_back(v, f, r.control_vertices, cage.faces, diag, args.scheme)
                print(json.dumps({"mesh": name, "scheme": args.scheme, "cage_vertices": len(cage.vertices),
                                  "tangential": t, "fairness": fairness, "iterations": iterations,
                                  "stop_reason": r.stop_reason, "rms": rms, "max": mx, "surface_rms": srms,
                                  "surface_max": smax, "seconds": seconds, "load_average": os.getloadavg()}),
                      flush=True)


if __name__ == "__main__":
    main()
