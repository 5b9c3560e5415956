"""Speed and quality of sorpia.decimate's cages, side by side with a baseline build.

Each case is a triangle mesh (noisy tori of --sizes vertices, made here, and the meshes of --meshes DIR found
there) decimated to --fraction of its vertices under each of --schemes, by this build and, with --baseline DIR
(a folder holding an installed ``sorpia`` package, e.g. a copy of site-packages/sorpia from before a change), by
that one: each decimation in a fresh process, the two builds alternated --repeats times, medians. Quality of each
cage: the distance of the input's vertices to the cage's triangles (exact, approximate_peers.distances_to_mesh:
RMS and max, relative to the bounding-box diagonal), and with --fit the same of the limit surface that
`sorpia.approximate` (this build, defaults) fits to those vertices on that cage. A decimation the guards stop
before the count asked is shown as "stopped at" the count reached (this build's decimate(strict=False)); the
baseline's error says the same count. Writes docs/benchmarks/decimate-speed.md unless --no-page.

    python bench/decimate_speed.py --baseline /tmp/sorpia-before --baseline-label "main 8a10afa"
    python bench/decimate_speed.py --sizes 10000 100000 --meshes ../shared/meshes --fit --repeats 3
    python bench/decimate_speed.py --sizes --files /tmp/sorpia-scan-stanford-bunny-16000.ply --fit --fit-max 2000000
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile

import numpy as np

import sorpia

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from _report import load_average, write_page  # noqa: E402
from approximate_peers import distances_to_mesh  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESHES = ["mountain", "stanford-bunny", "igl_bumpy-cube", "airplane", "spot", "teddy", "costa_surface"]

# One timed decimation in a child process: the sorpia found first on sys.path (PYTHONPATH chooses the build).
# argv: mesh.npz, n_vertices, scheme, cage.npz; prints the seconds and the count reached (or the error).
_CHILD = """
import inspect, json, sys, time, warnings
import numpy as np
import sorpia
data = np.load(sys.argv[1])
kwargs = {"strict": False} if "strict" in inspect.signature(sorpia.decimate).parameters else {}
warnings.simplefilter("ignore")
t0 = time.perf_counter()
try:
    cage = sorpia.decimate(data["v"], data["f"], int(sys.argv[2]), scheme=sys.argv[3], **kwargs)
except sorpia.MeshError as e:
    print(json.dumps({"seconds": time.perf_counter() - t0, "error": str(e)}))
    sys.exit(0)
seconds = time.perf_counter() - t0
faces = cage.faces
if hasattr(faces, "face_vertex_counts"):  # quads and triangles: counts and indices
    np.savez(sys.argv[4], v=cage.vertices, fc=faces.face_vertex_counts, fi=faces.face_vertex_indices)
else:
    np.savez(sys.argv[4], v=cage.vertices, f=faces)
print(json.dumps({"seconds": seconds, "vertices": len(cage.vertices)}))
"""


def noisy_torus(n, noise, seed=0):
    nv = int(round(np.sqrt(n / 2.5)))
    nu = int(round(n / nv))
    mesh = sorpia.shapes.torus(nu, nv)
    v = np.asarray(mesh[0], dtype=float)
    v = v + np.random.default_rng(seed).normal(scale=noise, size=v.shape)
    return v, np.asarray(mesh[1])


def faces_of(cage):
    """The faces of a cage written by _CHILD: an array, or sorpia.Polygons for quads and triangles mixed."""
    return sorpia.Polygons(cage["fc"], cage["fi"]) if "fc" in cage else cage["f"]


def triangles_of(faces):
    """Triangles of faces (an array of triangles or quads, or sorpia.Polygons of both): each quad split into two."""
    if isinstance(faces, sorpia.Polygons):
        counts, indices = np.asarray(faces.face_vertex_counts), np.asarray(faces.face_vertex_indices)
        start = np.concatenate([[0], np.cumsum(counts)[:-1]])
        tri, quad = start[counts == 3], start[counts == 4]
        return np.concatenate([indices[tri[:, None] + [0, 1, 2]], indices[quad[:, None] + [0, 1, 2]],
                               indices[quad[:, None] + [0, 2, 3]]])
    faces = np.asarray(faces)
    if faces.shape[1] == 3:
        return faces
    return np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])


def decimate_in_child(mesh_path, n, scheme, cage_path, package_dir):
    env = dict(os.environ)
    if package_dir:
        env["PYTHONPATH"] = package_dir + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", _CHILD, mesh_path, str(n), scheme, cage_path], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def shape(vertices, triangles):
    """The triangles' smallest angles (degrees: 5th percentile, median) and aspect ratios (longest edge over the
    height onto it: 95th percentile, max)."""
    p = np.asarray(vertices, float)[triangles]
    e = np.stack([p[:, 2] - p[:, 1], p[:, 0] - p[:, 2], p[:, 1] - p[:, 0]], axis=1)  # edge k opposite corner k
    length = np.linalg.norm(e, axis=2)
    twice_area = np.linalg.norm(np.cross(e[:, 0], e[:, 1]), axis=1)
    cos = np.stack([-(e[:, (k + 1) % 3] * e[:, (k + 2) % 3]).sum(1) / (length[:, (k + 1) % 3] * length[:, (k + 2) % 3])
                    for k in range(3)], axis=1)
    min_angle = np.degrees(np.arccos(np.clip(cos, -1, 1))).min(1)
    longest = length.max(1)
    aspect = np.where(twice_area > 0, longest ** 2 / np.maximum(twice_area, 1e-300), np.inf)
    return {"min_angle_p5": float(np.percentile(min_angle, 5)), "min_angle_median": float(np.median(min_angle)),
            "aspect_p95": float(np.percentile(aspect, 95)), "aspect_max": float(aspect.max())}


def quality(points, cage_path, scheme, diag, fit):
    """Distances of the points to the cage's triangles, the triangles' shape (shape(); a Catmull-Clark cage's quads
    split into two), and (fit) the distances to the limit surface approximate fits."""
    cage = np.load(cage_path)
    faces = faces_of(cage)
    d = distances_to_mesh(points, cage["v"], triangles_of(faces))
    q = {"cage_rms": float(np.sqrt(np.mean(d ** 2)) / diag), "cage_max": float(d.max() / diag)}
    q.update(shape(cage["v"], triangles_of(faces)))
    if fit:
        res = sorpia.approximate(points, cage["v"], faces, scheme=scheme)
        q.update(fit_rms=res.rms / diag, fit_max=res.max_error / diag)
    return q


def cases(args):
    """(name, vertices, triangles) of every case."""
    for n in args.sizes:
        yield f"noisy torus {n:,}", *noisy_torus(n, args.noise)
    if args.meshes and os.path.isdir(args.meshes):
        for name in MESHES:
            path = os.path.join(args.meshes, name + ".obj")
            if os.path.exists(path):
                v, f = sorpia.read_mesh(path)[:2]
                yield name, np.asarray(v, float), np.asarray(f)
    elif args.meshes:
        print(f"--meshes {args.meshes}: no such folder; its meshes are left out", file=sys.stderr)
    for path in args.files:
        v, f = sorpia.read_mesh(path)[:2]
        yield pathlib.Path(path).name, np.asarray(v, float), np.asarray(f)


def measure(args, folder):
    builds = ([("baseline", args.baseline)] if args.baseline else []) + [("this", None)]
    rows = []
    for name, v, f in cases(args):
        used = np.unique(f)
        points = v[used]
        diag = float(np.linalg.norm(points.max(0) - points.min(0)))
        target = max(4, int(round(args.fraction * len(used))))
        mesh_path = os.path.join(folder, "mesh.npz")
        np.savez(mesh_path, v=v, f=np.asarray(f, np.int32))
        for scheme in args.schemes:
            row = {"mesh": name, "points": len(used), "scheme": scheme, "asked": target, "load": os.getloadavg()[0]}
            baseline_here = args.baseline and len(used) <= args.baseline_max
            times = {who: [] for who, _ in builds}
            for _ in range(args.repeats):
                for who, package in builds:
                    if who == "baseline" and not baseline_here:
                        continue
                    out = decimate_in_child(mesh_path, target, scheme, os.path.join(folder, f"{who}.npz"), package)
                    times[who].append(out["seconds"])
                    if "error" in out:
                        m = re.search(r"stopped at (\d+)", out["error"])
                        row[f"{who}_vertices"] = int(m.group(1)) if m else None
                        row[f"{who}_error"] = out["error"]
                    else:
                        row[f"{who}_vertices"] = out["vertices"]
            for who, _ in builds:
                if not times[who]:
                    continue
                row[f"{who}_s"] = statistics.median(times[who])
                row[f"{who}_times"] = times[who]
                if f"{who}_error" not in row:
                    q = quality(points, os.path.join(folder, f"{who}.npz"), scheme, diag,
                                args.fit and len(used) <= args.fit_max)
                    row.update({f"{who}_{k}": x for k, x in q.items()})
            print(json.dumps(row), flush=True)
            rows.append(row)
    return rows


def fmt(x, spec):
    return "" if x is None else format(x, spec)


def table(rows, args):
    both = bool(args.baseline)
    who = ["baseline", "this"] if both else ["this"]
    pair = lambda r, k, spec: " / ".join(fmt(r.get(f"{w}_{k}"), spec) for w in who)  # noqa: E731
    head = "| mesh | vertices | scheme | asked | cage vertices | seconds" + (" | speed-up" if both else "") + \
        " | cage RMS / diag | cage max / diag | fit RMS / diag | fit max / diag" \
        " | min angle p5 / median (deg) | aspect p95 / max | load |"
    lines = [head, "|" + "---|" * 3 + "---:|" * (head.count("|") - 4)]
    for r in rows:
        counts = " / ".join(("stopped at " if (r.get(f"{w}_error") or r.get(f"{w}_vertices", 0) > r["asked"])
                             else "") + fmt(r.get(f"{w}_vertices"), "d") for w in who)
        speed = ""
        if both:
            speed = f" | {r['baseline_s'] / r['this_s']:.1f}x" if r.get("baseline_s") else " | "
        lines.append(f"| {r['mesh']} | {r['points']:,} | {r['scheme']} | {r['asked']:,} | {counts} | "
                     f"{pair(r, 's', '.3g')}{speed} | {pair(r, 'cage_rms', '.3e')} | {pair(r, 'cage_max', '.3e')} | "
                     f"{pair(r, 'fit_rms', '.3e')} | {pair(r, 'fit_max', '.3e')} | "
                     f"{pair(r, 'min_angle_p5', '.1f')}; {pair(r, 'min_angle_median', '.1f')} | "
                     f"{pair(r, 'aspect_p95', '.2f')}; {pair(r, 'aspect_max', '.3g')} | {r['load']:.1f} |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[10_000, 100_000, 1_000_000],
                    help="noisy tori of these many vertices")
    ap.add_argument("--meshes", default=None, metavar="DIR",
                    help=f"also the meshes {', '.join(MESHES)} found in DIR (OBJ)")
    ap.add_argument("--files", nargs="*", default=[], metavar="PATH",
                    help="also these triangle mesh files (e.g. bench/approximate_command.py's 1M scan)")
    ap.add_argument("--fraction", type=float, default=0.02, help="cage vertices per input vertex")
    ap.add_argument("--noise", type=float, default=1e-3, help="the tori's Gaussian noise (the tube radius is 0.25)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--schemes", nargs="+", default=["loop", "catmull-clark"])
    ap.add_argument("--fit", action="store_true", help="also fit approximate's limit surface on each cage")
    ap.add_argument("--fit-max", type=int, default=200_000, help="fit only meshes of at most this many vertices")
    ap.add_argument("--baseline", default=None, metavar="DIR", help="a folder holding another build's sorpia")
    ap.add_argument("--baseline-label", default=None, metavar="TEXT", help="what the baseline is, for the page")
    ap.add_argument("--baseline-max", type=int, default=10**9,
                    help="run the baseline only on meshes of at most this many vertices")
    ap.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write the page")
    args = ap.parse_args(argv)
    load_start = load_average()
    with tempfile.TemporaryDirectory() as folder:
        rows = measure(args, folder)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    lines = table(rows, args)
    print("\n".join(lines))
    if args.no_page:
        return
    base = (f"baseline: {args.baseline_label or 'the sorpia package in ' + args.baseline}, then this build"
            if args.baseline else "this build")
    intro = [__doc__.split("\n\n")[1].split(" Writes\ndocs/")[0], "",
             f"Pairs a / b are {base}. Seconds: the median of {args.repeats} `sorpia.decimate` calls, each in a "
             f"fresh process, the builds alternated. Load average (1 min) at each case's start in the last column; "
             f"{load_start} (1 / 5 / 15 min) when the run began.", ""]
    write_page("decimate-speed", "Decimation: time and quality of the cages", "\n".join(intro + lines),
               settings=(ap, args))


if __name__ == "__main__":
    main()
