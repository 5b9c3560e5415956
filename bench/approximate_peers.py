"""Approximation of dense meshes side by side with Subdivfit (issue 23, item 7).

    python bench/approximate_peers.py                      # the shared scans and two generated meshes
    python bench/approximate_peers.py --meshes noisy-sphere:40962 --fraction 0.02 --no-page
    SUBDIVFIT=/path/to/Subdivfit python bench/approximate_peers.py
    python bench/approximate_peers.py --subdivfit-only    # fill the cache of Subdivfit's rows; no page

On each mesh the data points are its vertices (those its faces use), and the
cage is `sorpia.decimate(vertices, faces, N)` with N = --fraction of them
(Loop, OpenMesh's quadric decimation). Every row fits that cage to those
points, and every row is measured the same way: the distance from each data
point to the row's limit surface (sorpia's Loop limit of the row's cage,
tessellated at level 4), exact point-to-triangle distance, as RMS and max,
divided by the bounding-box diagonal of the points. Rows:

- Subdivfit -gfit 10 and -gfit 30: Hugues Hoppe's program (Hoppe et al.,
  "Piecewise smooth surface reconstruction", SIGGRAPH 1994), built from
  hhoppe/Mesh-processing-library at commit b79dd12 (`make CC=gcc -C libHh`,
  `-C Subdivfit`: g++ 12, -std=c++14 -O3 -march=corei7 -ffast-math -fopenmp;
  about 4 minutes on 2 cores); its output cage is read back and evaluated by sorpia's
  Loop limit surface. Time: the process (its own reading of the text files
  included), wall clock and CPU (the child's user + system time, all its
  threads, from getrusage(RUSAGE_CHILDREN)).
- interpolation: `sorpia.interpolate` of the cage: the limit surface through
  the decimated cage's vertices.
- decimated cage: the cage's own limit surface, unchanged.
- sorpia.approximate: with its defaults, with point distance and no fairness (the default before),
  and the blend without fairness stopped at 4 iterations (Loop).

Every row records its wall and CPU seconds (sorpia's: the process's CPU time
around the call, all its threads) and the 1-minute load average before and
after it. The summary gives sorpia's time over -gfit 10's in both: CPU seconds
are the work done, which other jobs on a shared machine inflate little; wall
seconds grow with the load, unevenly from row to row and from run to run.

Subdivfit's rows depend on the cage, the points, the options and the
executable, not on sorpia's fitting code, and they are most of a run's time: they
are kept in a cache (--cache, bench/approximate_peers_subdivfit.json), keyed by
the mesh spec, the hashes of the cage's and the points' arrays, the Subdivfit
options, the level measured to and the executable's path and hash, with the date,
commit and loads of the run that measured them. A later run measures sorpia's
rows and takes Subdivfit's from the cache where the key matches (--remeasure to
run Subdivfit again); the page says of each row when it was measured and at what
load, and which runs its rows came from. The distances of a cached row were
measured by that run's sorpia (its Loop limit surface, OpenSubdiv's).

The check that Subdivfit's Loop rules are OpenSubdiv's on smooth parts
(--check-rules, on by default): its own subdivided surface (`-outn`, two
levels, vertices sent to their limit positions) against sorpia's level-2
tessellation of the same closed cage, the largest distance from each of its
vertices to the nearest of sorpia's, over the diagonal.

Subdivfit's input converters (.m: ``Vertex i x y z`` / ``Face j a b c``,
1-based; points: ``p x y z``) live here, not in the product. Nothing here runs
under pytest.
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import os
import pathlib
import re
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.spatial import cKDTree

import sorpia

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _report import ROOT, commit, write_page  # noqa: E402

SHARED = ROOT.parent / "shared" / "meshes"
DEFAULT_MESHES = ("mountain.obj", "stanford-bunny.obj", "igl_bumpy-cube.obj", "airplane.obj",
                  "noisy-sphere:163842", "noisy-torus:100000")
DEFAULT_SUBDIVFIT = pathlib.Path("/work/peers/mpl/bin/unix/Subdivfit")
LEVEL = 4  # the tessellation the distances are measured to
CACHE = pathlib.Path(__file__).resolve().with_name("approximate_peers_subdivfit.json")


# ---- meshes ----------------------------------------------------------------------------------------------------

def load(spec: str):
    """(name, vertices, triangles): a file (relative names under ../shared/meshes) or a generated noisy mesh
    ``noisy-sphere:N`` / ``noisy-torus:N`` (about N vertices, displaced along the normal by Gaussian noise of
    1e-3 of the bounding-box diagonal, seed 1). The vertices no face uses are left out (they are no data)."""
    rng = np.random.default_rng(1)
    if ":" in spec and not spec.endswith((".obj", ".ply", ".off", ".stl")):
        kind, _, n = spec.partition(":")
        n = int(n)
        if kind == "noisy-sphere":
            level = int(round(np.log((n - 2) / 10) / np.log(4)))
            v, f = sorpia.shapes.icosphere(level)
            normals = v / np.linalg.norm(v, axis=1, keepdims=True)
        elif kind == "noisy-torus":
            nv = max(3, round(np.sqrt(n / 2.5)))
            v, f = sorpia.shapes.torus(max(3, n // nv), nv)
            ring = v.copy()
            ring[:, 2] = 0
            ring *= 1.0 / np.linalg.norm(ring, axis=1, keepdims=True)
            normals = v - ring
            normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        else:
            raise SystemExit(f"unknown mesh {spec!r}")
        diag = np.linalg.norm(v.max(0) - v.min(0))
        v = v + normals * rng.normal(scale=1e-3 * diag, size=(len(v), 1))
        return f"{kind} ({len(v)})", v, f
    path = pathlib.Path(spec)
    if not path.is_absolute() and not path.exists():
        path = SHARED / spec
    v, f = sorpia.read_mesh(str(path))
    f = np.asarray(f)
    used = np.unique(f)
    if len(used) < len(v):
        renumber = np.full(len(v), -1, np.int64)
        renumber[used] = np.arange(len(used))
        v, f = v[used], renumber[f]
    return path.name, np.asarray(v, dtype=float), np.asarray(f, dtype=np.int32)


# ---- exact point-to-triangle distance ----------------------------------------------------------------------------

def point_triangle_distance(p, a, b, c):
    """Distance from each p[i] to the triangle (a[i], b[i], c[i]), exact: the closest point by the Voronoi
    regions of the triangle's vertices, edges and face (Ericson, Real-Time Collision Detection, 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
        closest = a + ab * v[:, None] + ac * w[:, None]  # inside the face
        # edge ab
        t = d1 / (d1 - d3)
        sel = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        closest[sel] = a[sel] + t[sel, None] * ab[sel]
        # edge ac
        t = d2 / (d2 - d6)
        sel = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        closest[sel] = a[sel] + t[sel, None] * ac[sel]
        # edge bc
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        sel = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        closest[sel] = b[sel] + t[sel, None] * (c[sel] - b[sel])
    for sel, q in (((d1 <= 0) & (d2 <= 0), a), ((d3 >= 0) & (d4 <= d3), b), ((d6 >= 0) & (d5 <= d6), c)):
        closest[sel] = q[sel]  # vertex regions last: they take precedence, as in Ericson's order of tests
    return np.linalg.norm(p - closest, axis=1)


def distances_to_mesh(points, vertices, triangles, chunk=100_000):
    """Exact distance from every point to the triangle mesh. The triangles are grouped by their radius (largest
    centroid-to-corner distance; the radii of a group within a factor 2 of its largest, r). In each group a
    point's candidates are the k triangles of nearest centroids: any other is at least (k-th centroid distance
    - r) away, so where that exceeds the best distance found so far the group cannot improve it; elsewhere the
    group is asked again with 4k candidates, up to all of its triangles."""
    tri = vertices[triangles]
    centroids = tri.mean(axis=1)
    r = np.linalg.norm(tri - centroids[:, None, :], axis=2).max(axis=1)
    group = np.floor(np.log2(np.maximum(r / r.max(), 2.0 ** -20)))
    labels, sizes = np.unique(group, return_counts=True)
    best = np.full(len(points), np.inf)
    for label in labels[np.argsort(-sizes)]:  # the most triangles first: the best drops early
        members = np.flatnonzero(group == label)
        tree, radius, k = cKDTree(centroids[members]), float(r[members].max()), 16
        todo = np.arange(len(points))
        while len(todo):
            k = min(k, len(members))
            step = max(1, chunk * 16 // k)
            for s in range(0, len(todo), step):
                rows = todo[s:s + step]
                dist, idx = tree.query(points[rows], k=k)
                dist, idx = dist.reshape(len(rows), k), members[idx.reshape(len(rows), k)]
                t = tri[idx.ravel()]
                d = point_triangle_distance(np.repeat(points[rows], k, axis=0), t[:, 0], t[:, 1], t[:, 2])
                best[rows] = np.minimum(best[rows], d.reshape(len(rows), k).min(axis=1))
                done = (best[rows] <= dist[:, -1] - radius) | (k == len(members))
                todo[s:s + len(rows)] = np.where(done, -1, rows)
            todo = todo[todo >= 0]
            k *= 4
    return best


def measure(points, cage_vertices, cage_faces, diag, scheme="loop"):
    """(RMS, max) distance from the points to the cage's limit surface (level-4 tessellation; under
    Catmull-Clark its quads split into two triangles each along a diagonal), / diag."""
    tv, tf = sorpia.limit_surface(cage_vertices, cage_faces, LEVEL, scheme=scheme)
    tf = np.asarray(tf)
    if tf.shape[1] == 4:  # a level >= 1 Catmull-Clark tessellation is all quads
        tf = np.vstack([tf[:, [0, 1, 2]], tf[:, [0, 2, 3]]])
    d = distances_to_mesh(points, tv, tf) / diag
    return float(np.sqrt(np.mean(d ** 2))), float(d.max())


def measure_back(vertices, triangles, cage_vertices, cage_faces, diag, scheme="loop"):
    """(RMS, max) distance from the row's limit surface to the dense mesh, / diag: from each vertex of the
    level-4 tessellation (an exact limit point) to the nearest of the dense mesh's triangles, exact. A surface
    that strays between loosely held points, or flies off where a cage face holds none, shows here."""
    tv, _ = sorpia.limit_surface(cage_vertices, cage_faces, LEVEL, scheme=scheme)
    d = distances_to_mesh(np.asarray(tv), vertices, np.asarray(triangles)) / diag
    return float(np.sqrt(np.mean(d ** 2))), float(d.max())


# ---- Subdivfit -------------------------------------------------------------------------------------------------

def write_m(path, vertices, triangles):
    """Hoppe's .m mesh: ``Vertex i x y z`` and ``Face j a b c``, both 1-based."""
    with open(path, "w") as fh:
        fh.writelines(f"Vertex {i + 1} {x:.17g} {y:.17g} {z:.17g}\n" for i, (x, y, z) in enumerate(vertices))
        fh.writelines(f"Face {j + 1} {a + 1} {b + 1} {c + 1}\n" for j, (a, b, c) in enumerate(triangles))


def write_points(path, points):
    """Hoppe's point file: one ``p x y z`` line per point."""
    with open(path, "w") as fh:
        fh.writelines(f"p {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in points)


def read_m(text):
    """(vertices, triangles) of a .m mesh, renumbered 0-based in the order of its Vertex lines; lines other
    than Vertex and Face (comments, Edge attributes) are skipped."""
    number, vertices, faces = {}, [], []
    for line in text.splitlines():
        tok = line.split()
        if not tok:
            continue
        if tok[0] == "Vertex":
            number[int(tok[1])] = len(vertices)
            vertices.append([float(x) for x in tok[2:5]])
        elif tok[0] == "Face":
            faces.append([int(x) for x in tok[2:5]])
    faces = np.array([[number[i] for i in f] for f in faces], dtype=np.int32)
    return np.array(vertices, dtype=float), faces


def timed(call, children=False):
    """(call(), timing): timing is {"seconds": wall, "cpu_seconds": CPU, "load": [1-minute load average before,
    after], "date": UTC start}. CPU: the user + system time of the children reaped during the call (children=True,
    for a subprocess: all its threads), else of this process (all its threads)."""
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    c0, t0 = time.process_time(), time.perf_counter()
    result = call()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    if children:
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return result, {"seconds": wall, "cpu_seconds": cpu, "load": [load, os.getloadavg()[0]], "date": date}


def subdivfit(exe, workdir, options):
    """Run Subdivfit on cage.m and points.pts in workdir: (output mesh text, timing as `timed` gives it)."""
    run, timing = timed(lambda: subprocess.run([str(exe), "-mf", "cage.m", "-fi", "points.pts", *options],
                                               cwd=workdir, capture_output=True, text=True), children=True)
    if run.returncode != 0:
        raise RuntimeError(f"Subdivfit {' '.join(options)} failed: {run.stderr[-2000:]}")
    return run.stdout, timing


# ---- the cache of Subdivfit's rows -------------------------------------------------------------------------------

def array_hash(*arrays) -> str:
    """sha256 of the arrays' dtypes, shapes and bytes (C order)."""
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def file_hash(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


class SubdivfitCache:
    """Subdivfit's measured rows in a JSON file, keyed by what determines them (see the module's docstring):
    {"entries": {sha256 of the key: {"key": {...}, "value": {...}}}}. path None: nothing is kept."""

    def __init__(self, path, remeasure=False):
        self.path, self.remeasure, self.entries = path, remeasure, {}
        if path is not None and pathlib.Path(path).exists():
            self.entries = json.loads(pathlib.Path(path).read_text())["entries"]

    @staticmethod
    def key(spec, cage, points, options, exe, exe_hash):
        key = {"mesh": spec, "cage": array_hash(cage.vertices, cage.faces), "points": array_hash(points),
               "options": list(options), "level": LEVEL, "executable": str(exe), "executable_sha256": exe_hash}
        return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest(), key

    def get(self, key):
        entry = None if self.remeasure else self.entries.get(key[0])
        return None if entry is None else entry["value"]

    def put(self, key, value):
        self.entries[key[0]] = {"key": key[1], "value": value}
        if self.path is not None:
            pathlib.Path(self.path).write_text(json.dumps({"entries": self.entries}, indent=1, sort_keys=True) + "\n")


def subdivfit_surface(exe, workdir, vertices, triangles, level):
    """Subdivfit's own surface of a cage: its subdivided mesh at `level` (-outn), vertices sent to their limit
    positions, as (vertices, triangles)."""
    write_m(pathlib.Path(workdir) / "surface.m", vertices, triangles)
    run = subprocess.run([str(exe), "-mf", "surface.m", "-nsubdiv", str(level), "-outn"], cwd=workdir,
                         capture_output=True, text=True, check=True)
    return read_m(run.stdout)


def check_rules(exe, workdir, vertices, triangles, diag):
    """Subdivfit's Loop rules against OpenSubdiv's on a cage: the distance from each vertex of Subdivfit's
    two-level surface (sent to the limit) to the nearest vertex of sorpia's level-2 limit tessellation, / diag:
    (largest, how many above 1e-5, how many)."""
    theirs, _ = subdivfit_surface(exe, workdir, vertices, triangles, 2)
    ours, _ = sorpia.limit_surface(vertices, triangles, 2)
    gap = cKDTree(ours).query(theirs)[0] / diag
    return float(gap.max()), int((gap > 1e-5).sum()), len(gap)


PAGE_INTRO = """
On each mesh the data points are its vertices (those its faces use); the cage is `sorpia.decimate` of the mesh to
the stated number of vertices (Loop; OpenMesh's quadric decimation), and for the Catmull-Clark rows the quad cage of
as many vertices (`sorpia.decimate(..., scheme="catmull-clark")`). Every row fits its cage to those points and is
measured the same way: the distance from each data point to the row's limit surface (sorpia's limit surface of the
row's cage, tessellated at level 4), exact point-to-triangle distance, as RMS and max over the bounding-box
diagonal of the points. Subdivfit (Hoppe et al., "Piecewise smooth surface reconstruction", SIGGRAPH 1994; Loop
only) is built from hhoppe/Mesh-processing-library at commit b79dd12; its time is the process's (its reading of the
text files included), its output cage is evaluated by sorpia's Loop limit surface. Its Loop rules
are OpenSubdiv's inside the mesh but not along a boundary (the check under each table), so its rows are also
measured to its own surface (its subdivision of its cage to level 4 with the vertices at their limit positions,
`Subdivfit -nsubdiv 4 -outn`), the one it fits. "interpolation" is `sorpia.interpolate` of the cage (the limit
surface through the decimated cage's vertices); "decimated cage as it is" the cage's own limit surface.
"sorpia.approximate" is the call with its defaults (the tangent-distance blend W_i = 0.1 I + 0.9 n_i n_i^T with the
fairness term 3e-4, Tukey's biweight against outliers, at most 10 iterations, tol 3e-3; its time is the call's, the
first in the process; its
iterations and why it stopped in brackets: "the limit" of 10, "converged" by tol); "tangential=1, fairness=0"
point distance without fairness (the default before); "fairness=0, 4 iterations" the blend alone, stopped at 4.
The last column measures the other way, from the surface to the dense mesh (its level-4 tessellation's
vertices to the nearest dense triangle, exact): where the cage has faces that few points hold, a fit can stray
between the points, or fly off, without the data -> surface distance showing it. Every timed row gives its wall
and CPU seconds (user + system, all threads: Subdivfit's child process, sorpia's process around the call) and when
it was measured, with the 1-minute load average before and after it. Subdivfit's rows do not depend on sorpia's
fitting code: they are kept in bench/approximate_peers_subdivfit.json, keyed by the mesh, the cage's and the
points' hashes, the options and the executable's hash, and a later run takes them from there (the list below the
summary says which rows came from which run).

"""


# ---- the table -----------------------------------------------------------------------------------------------

def run_mesh(spec, args, gfit, exe, cache, here):
    """The rows of one mesh: Subdivfit's (exe: (path, sha256), or None), from the cache where it has them, then
    sorpia's unless args.subdivfit_only; `here` is the commit the rows measured now are labelled with."""
    name, v, f = load(spec)
    diag = float(np.linalg.norm(v.max(0) - v.min(0)))
    n_cage = max(4, int(round(args.fraction * len(v))))
    t0 = time.perf_counter()
    note = ""
    try:
        cage = sorpia.decimate(v, f, n_cage)
    except sorpia.MeshError as exc:  # the guards stopped it: take the cage where it stopped, and say so
        stopped = re.search(r"stopped at (\d+) vertices", str(exc))
        if stopped is None:
            raise
        note = f"decimation to {n_cage:,} vertices stopped at {stopped.group(1)}: the cage has that many"
        n_cage = int(stopped.group(1))
        cage = sorpia.decimate(v, f, n_cage)
    t_decimate = time.perf_counter() - t0
    rows = []
    out = {"mesh": name, "points": len(v), "cage_vertices": n_cage, "decimate_seconds": t_decimate, "rows": rows,
           "note": note}
    print(f"{name}: {len(v)} points, cage {n_cage} vertices ({t_decimate:.2f} s)", file=sys.stderr)

    def row(label, vertices, timing, faces=cage.faces, scheme="loop", **extra):
        """A row: the distances of the cage `vertices` (its faces `faces`) both ways, its timing (None: none)."""
        rms, mx = measure(v, vertices, faces, diag, scheme)
        extra["surface"] = measure_back(v, f, vertices, faces, diag, scheme)
        if "own" in extra:  # the distances to Subdivfit's own level-4 surface of the same cage
            d = distances_to_mesh(v, *extra["own"]) / diag
            extra["own"] = (float(np.sqrt(np.mean(d ** 2))), float(d.max()))
        timing = timing or {"seconds": 0.0, "cpu_seconds": 0.0}
        return {"row": label, "scheme": scheme, "rms": rms, "max": mx, **timing, **extra}

    def add(r):
        rows.append(r)
        print(f"  {r['row']} ({r['scheme']}): rms {r['rms']:.3g} max {r['max']:.3g} ({r['seconds']:.2f} s wall, "
              f"{r['cpu_seconds']:.2f} s CPU{', cached' if r.get('cached') else ''})", file=sys.stderr)

    if exe is not None:
        keys = {k: cache.key(spec, cage, v, ["-gfit", str(k)], *exe) for k in gfit}
        rules_key = cache.key(spec, cage, v, ["-nsubdiv", "2", "-outn"], *exe)
        with tempfile.TemporaryDirectory() as work:
            write_m(pathlib.Path(work) / "cage.m", cage.vertices, cage.faces)
            write_points(pathlib.Path(work) / "points.pts", v)
            for k in gfit:
                value = cache.get(keys[k])
                if value is not None:
                    add({**value, "cached": True})
                    continue
                text, timing = subdivfit(exe[0], work, ["-gfit", str(k)])
                fitted, faces = read_m(text)
                if not np.array_equal(faces, cage.faces):
                    raise RuntimeError(f"Subdivfit -gfit {k} changed the cage's faces")
                value = {**row(f"Subdivfit -gfit {k}", fitted, timing,
                               own=subdivfit_surface(exe[0], work, fitted, faces, LEVEL)), "commit": here}
                cache.put(keys[k], value)
                add(value)
            if args.check_rules:
                value = cache.get(rules_key)
                if value is None:
                    value = {"rules_check": check_rules(exe[0], work, cage.vertices, cage.faces, diag)}
                    cache.put(rules_key, value)
                out["rules_check"] = value["rules_check"]
    if args.subdivfit_only:
        return out
    # The same rows of sorpia's on the Loop cage, then on the quad cage of as many vertices (Catmull-Clark).
    cages = [("loop", cage)]
    try:
        cages.append(("catmull-clark", sorpia.decimate(v, f, n_cage, scheme="catmull-clark")))
        out["quad_cage_vertices"] = len(cages[-1][1].vertices)
    except sorpia.MeshError as exc:  # the guards stopped it: no Catmull-Clark rows, and the page says why
        out["quad_cage_vertices"] = 0
        out["note"] = "; ".join(x for x in (out["note"], f"no quad cage: {exc}") if x)
    for scheme, c in cages:
        interp, timing = timed(lambda: sorpia.interpolate(c.vertices, c.faces, scheme=scheme))
        add({**row("interpolation of the cage's vertices", interp.control_vertices, timing, c.faces, scheme),
             "commit": here})
        add({**row("decimated cage as it is", c.vertices, None, c.faces, scheme), "commit": here})
        runs = (("sorpia.approximate", {}),
                ("sorpia.approximate tangential=1, fairness=0 (point distance)", {"tangential": 1.0, "fairness": 0.0}),
                ("sorpia.approximate fairness=0, 4 iterations", {"fairness": 0.0, "iterations": 4}))
        for label, options in runs[:3 if scheme == "loop" else 2]:
            result, timing = timed(lambda: sorpia.approximate(v, c.vertices, c.faces, scheme=scheme, **options))
            add({**row(label, result.control_vertices, timing, c.faces, scheme, iterations=result.iterations,
                       stop_reason=getattr(result, "stop_reason", None)), "commit": here})
    return out


def ratio_range(values, digits=2):
    return "-" if not values else (f"{min(values):.{digits}f} to {max(values):.{digits}f}" if len(values) > 1
                                   else f"{values[0]:.{digits}f}")


def summary(results):
    """The comparisons the docs quote, from the rows below: per mesh, sorpia.approximate (defaults) against
    Subdivfit -gfit 30 (RMS, max, surface -> dense), its time against -gfit 10's (CPU and wall), and the
    Catmull-Clark fit's RMS over the Loop fit's; their ranges; then every figure where sorpia's default is worse
    than -gfit 30."""
    lines = ["## Summary\n", "sorpia.approximate with its defaults against Subdivfit on the same cage (Loop), and its "
             "Catmull-Clark fit against its Loop fit, from the tables below. Time is given twice: in CPU seconds "
             "(user + system, all threads: sorpia's process around the call, Subdivfit's child process), the work "
             "done, which other jobs on a shared machine inflate little; and in wall seconds, which grow with the "
             "load, unevenly from row to row and from run to run (Subdivfit's rows may come from another run, at "
             "another load: the tables say when each row was measured). The CPU ratio is the one to compare.\n",
             "| mesh | RMS: sorpia / -gfit 30 | max: sorpia / -gfit 30 | surface -> dense RMS, max: sorpia / -gfit 30 "
             "| CPU time: sorpia / -gfit 10 | wall time: sorpia / -gfit 10 | RMS: Catmull-Clark / Loop |",
             "|---|---|---|---|---|---|---|"]
    worse, ranges = [], {"rms": [], "cpu": [], "wall": [], "cc": []}
    for r in results:
        rows = {(row["row"], row["scheme"]): row for row in r["rows"]}
        ours, g30, g10 = (rows.get((label, "loop")) for label in
                          ("sorpia.approximate", "Subdivfit -gfit 30", "Subdivfit -gfit 10"))
        cc = rows.get(("sorpia.approximate", "catmull-clark"))
        if ours is None:
            continue
        cells = ["-"] * 6
        if g30 is not None:
            cells[0] = f"{ours['rms'] / g30['rms']:.3f}"
            ranges["rms"].append(ours["rms"] / g30["rms"])
            cells[1] = f"{ours['max'] / g30['max']:.3f}"
            cells[2] = f"{ours['surface'][0] / g30['surface'][0]:.3f}, {ours['surface'][1] / g30['surface'][1]:.3f}"
            for what, a, b in (("RMS", ours["rms"], g30["rms"]), ("max", ours["max"], g30["max"]),
                               ("surface -> dense RMS", ours["surface"][0], g30["surface"][0]),
                               ("surface -> dense max", ours["surface"][1], g30["surface"][1])):
                if a > b:
                    worse.append(f"{r['mesh']}: {what} {a:.3g} against {b:.3g}")
        if g10 is not None and g10.get("cpu_seconds") and "cpu_seconds" in ours:
            cells[3] = f"{ours['cpu_seconds'] / g10['cpu_seconds']:.2f}"
            ranges["cpu"].append(ours["cpu_seconds"] / g10["cpu_seconds"])
        if g10 is not None and g10["seconds"]:
            cells[4] = f"{ours['seconds'] / g10['seconds']:.2f}"
            ranges["wall"].append(ours["seconds"] / g10["seconds"])
        if cc is not None:
            cells[5] = f"{cc['rms'] / ours['rms']:.2f}"
            ranges["cc"].append(cc["rms"] / ours["rms"])
        lines.append(f"| {r['mesh']} | " + " | ".join(cells) + " |")
    lines.append("")
    lines.append(f"Over these meshes: RMS {ratio_range(ranges['rms'], 3)} of -gfit 30's, in "
                 f"{ratio_range(ranges['cpu'])} of -gfit 10's CPU time ({ratio_range(ranges['wall'])} of its wall "
                 f"time); Catmull-Clark RMS {ratio_range(ranges['cc'])} of Loop's.\n")
    if worse:
        lines.append("Where sorpia's default is worse than Subdivfit -gfit 30: " + "; ".join(worse) + ".\n")
    return "\n".join(lines)


def sources(results):
    """Which run each group of rows came from: Subdivfit's from the cache or this run, sorpia's from this run,
    with their dates, commits and loads."""
    groups = {}
    for r in results:
        for row in r["rows"]:
            if "date" not in row:
                continue
            who = "Subdivfit" if row["row"].startswith("Subdivfit") else "sorpia"
            where = "the cache (bench/approximate_peers_subdivfit.json)" if row.get("cached") else "this run"
            groups.setdefault((who, where), []).append(row)
    lines = []
    for (who, where), rows in sorted(groups.items()):
        dates = sorted(row["date"] for row in rows)
        loads = [x for row in rows for x in row.get("load", ())]
        commits = ", ".join(f"`{c}`" for c in sorted({row.get("commit", "?") for row in rows}))
        when = dates[0] if dates[0] == dates[-1] else f"{dates[0]} to {dates[-1]}"
        lines.append(f"- {who}'s {len(rows)} timed rows: from {where}, measured {when} at commit {commits}, "
                     f"1-minute load {min(loads):.1f} to {max(loads):.1f} around the rows")
    return ("The rows' runs:\n\n" + "\n".join(lines) + "\n") if lines else ""


def table(results, have_subdivfit):
    lines = [summary(results)] if have_subdivfit else []
    lines.append(sources(results))
    for r in results:
        lines.append(f"## {r['mesh']}: {r['points']:,} points, cage of {r['cage_vertices']:,} vertices "
                     f"(decimated in {r['decimate_seconds']:.2f} s; the quad cage: "
                     f"{r.get('quad_cage_vertices') or 'none'}{' vertices' if r.get('quad_cage_vertices') else ''})\n")
        if r["note"]:
            lines.append(f"({r['note']}.)\n")
        lines.append("| fit | scheme | RMS / diagonal | max / diagonal | wall seconds | CPU seconds "
                     "| on Subdivfit's own surface: RMS, max | surface -> dense: RMS, max "
                     "| measured (load before, after) |")
        lines.append("|---|---|---|---|---|---|---|---|---|")
        for row in r["rows"]:
            seconds = f"{row['seconds']:.3g}" if row["seconds"] else "-"
            cpu = f"{row['cpu_seconds']:.3g}" if row.get("cpu_seconds") else "-"
            if row.get("iterations"):
                why = {"max_iter": ", the limit", None: ""}.get(row.get("stop_reason"), f", {row.get('stop_reason')}")
                seconds += f" ({row['iterations']} iterations{why})"
            own = f"{row['own'][0]:.3g}, {row['own'][1]:.3g}" if "own" in row else ""
            back = f"{row['surface'][0]:.3g}, {row['surface'][1]:.3g}" if "surface" in row else ""
            when = (f"{row['date']}{', cache' if row.get('cached') else ''} ({row['load'][0]:.1f}, "
                    f"{row['load'][1]:.1f})" if "date" in row else "")
            lines.append(f"| {row['row']} | {row['scheme']} | {row['rms']:.3g} | {row['max']:.3g} | {seconds} | {cpu} "
                         f"| {own} | {back} | {when} |")
        if "rules_check" in r:
            gap, n_apart, n = r["rules_check"]
            where = ("all within float32 rounding" if n_apart == 0 else
                     f"{n_apart:,} of them (along the boundary) farther than 1e-5 of the diagonal")
            lines.append(f"\nSubdivfit's Loop rules against OpenSubdiv's on the decimated cage: its two-level "
                         f"surface's {n:,} limit vertices lie within {gap:.2g} of the diagonal of sorpia's "
                         f"level-2 limit tessellation, {where}.")
        lines.append("")
    if not have_subdivfit:
        lines.append("Subdivfit was not found (set SUBDIVFIT): its rows are missing.")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--meshes", default=",".join(DEFAULT_MESHES),
                        help="comma-separated files (names under ../shared/meshes) or noisy-sphere:N, noisy-torus:N")
    parser.add_argument("--fraction", type=float, default=0.02, help="cage vertices per data point")
    parser.add_argument("--gfit", default="10,30", help="Subdivfit -gfit iteration counts, comma-separated")
    parser.add_argument("--no-check-rules", dest="check_rules", action="store_false",
                        help="skip the check of Subdivfit's Loop rules against OpenSubdiv's")
    parser.add_argument("--json", help="also write the results here")
    parser.add_argument("--no-page", action="store_true", help="do not write docs/benchmarks/approximate.md")
    parser.add_argument("--from-json", metavar="PATH", help="the tables from an earlier --json, without running")
    parser.add_argument("--cache", default=os.path.relpath(CACHE, ROOT),
                        help="the JSON cache of Subdivfit's rows (relative to the repository; '' for none)")
    parser.add_argument("--remeasure", action="store_true",
                        help="run Subdivfit again where the cache has its rows (and replace them there)")
    parser.add_argument("--subdivfit-only", action="store_true",
                        help="Subdivfit's rows only (filling the cache), without sorpia's rows or the page")
    args = parser.parse_args(argv)
    gfit = [int(k) for k in args.gfit.split(",") if k]
    exe = pathlib.Path(os.environ.get("SUBDIVFIT", DEFAULT_SUBDIVFIT))
    exe = (exe.resolve(), file_hash(exe)) if exe.exists() else None
    cache = SubdivfitCache(ROOT / args.cache if args.cache else None, args.remeasure)
    here = commit()  # before the run writes the cache (a tracked file)
    results = []
    if args.from_json:
        results = json.loads(pathlib.Path(args.from_json).read_text())
    for spec in [] if args.from_json else args.meshes.split(","):
        if not spec.startswith("noisy-") and not (SHARED / spec).exists() and not pathlib.Path(spec).exists():
            print(f"{spec}: not found, skipped", file=sys.stderr)
            continue
        results.append(run_mesh(spec, args, gfit, exe, cache, here))
    if args.subdivfit_only:
        return
    have_subdivfit = exe is not None or any(row["row"].startswith("Subdivfit") for r in results for row in r["rows"])
    body = table(results, have_subdivfit)
    print(body)
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(results, indent=1))
    if not args.no_page:
        write_page("approximate", "Approximation of dense meshes, side by side with Subdivfit", PAGE_INTRO + body,
                   settings=(parser, args))


if __name__ == "__main__":
    main()
