"""Fits through darts and Catmull-Clark's vertices of two faces (the vertices
whose OpenSubdiv Limit() changes with the level): how far the fitted surface
misses its targets there with OpenSubdiv's Limit() rows (what B had before)
and with the limit of refinement (B now), and what those rows cost.

For each shape (OpenSubdiv's tagged shapes in ../shared/meshes when present,
and generated ones): the cage fitted by a direct solve (scipy's splu) with
OpenSubdiv's B (sorpia._reference.reference_limit_matrix: Far's Limit() after the levels
the semi-sharp tags need, 0 with infinitely sharp tags alone, which gives a
dart Sdc's smooth mask) and with sorpia's B; each cage's limit surface
evaluated at every face corner (sorpia.LimitSurface: Bfr, and the limit of
refinement at such vertices' corners); the largest miss |P - V| over the
diagonal, at those vertices and elsewhere. Then the cost: B built with k darts
against the same vertices made infinitely sharp corners (uniform rows), per
dart; and B of a quad mesh with k quads split by a vertex of two faces against
the same mesh unsplit, per such vertex. Last, quad meshes with many quads split
(OpenSubdiv before 3.6.1 gets Bfr's patches wrong there through its topology
cache, pull request 1353; sorpia builds those faces without it): the surface
against Far's refinement (sorpia.limit_surface, level 2) at every corner of
every refined quad, and what evaluation costs with and without such faces.
Writes docs/benchmarks/darts.md (unless --no-page).

    python bench/darts.py [--shared ../shared/meshes] [--names a.obj,b.obj] [--no-page]
"""

from __future__ import annotations

import argparse
import ctypes
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

import sorpia
from sorpia import _core
from sorpia import _reference  # the test-only module: a `make test` build (SORPIA_BUILD_TESTS)
from sorpia._validate import as_boundary, as_scheme
from sorpia.limit import tags as make_tags
from sorpia.limit import topology as make_topology
from sorpia.surface import corner_uv

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
from _report import write_page  # noqa: E402
from conftest import level_dependent  # noqa: E402  (the tests' own: from the faces and tags alone)
from test_catmull_clark import refined_corner_uv  # noqa: E402
from test_robust_default import gregory_test8  # noqa: E402


def darts(f, n, scheme="loop", **tags):
    """Darts, and under Catmull-Clark the vertices of two faces too."""
    return np.flatnonzero(level_dependent(f, n, scheme, **tags))


def split_quads(v, f, faces, lift):
    """Each quad in `faces` split along its diagonal (corners 0 and 2) by a new vertex at its centre raised by
    `lift` in z (an interior vertex of two faces)."""
    v, f = np.asarray(v, float).tolist(), np.asarray(f).tolist()
    for i in faces:
        a, b, c, d = f[i]
        centre = np.mean([v[a], v[b], v[c], v[d]], axis=0) + [0.0, 0.0, lift]
        v.append(centre.tolist())
        f[i] = [a, b, c, len(v) - 1]
        f.append([len(v) - 1, c, d, a])
    return np.array(v), np.array(f)

SHARED = Path(__file__).resolve().parents[2] / "shared" / "meshes"
OSD = ["osd_loop_icos_infsharp.obj", "osd_loop_cube_creases0.obj", "osd_catmark_cube_creases1.obj",
       "osd_catmark_torus_creases0.obj", "osd_catmark_helmet.obj"]


def face_list(f):
    if isinstance(f, sorpia.Polygons):
        ends = np.cumsum(f.face_vertex_counts)
        return [f.face_vertex_indices[e - c:e].tolist() for c, e in zip(f.face_vertex_counts, ends)]
    return np.asarray(f).tolist()


def corner_misses(x, v, f, boundary, scheme, tags, at):
    """Largest |P - V| / diagonal at the face corners of the vertices in `at` and at the others."""
    s = sorpia.LimitSurface(x, f, boundary=boundary, scheme=scheme, **tags)
    holes = set(np.asarray(tags.get("holes", []), int).tolist())
    faces = face_list(f)
    ids, uv, corner, inward = [], [], [], []
    for i, face in enumerate(faces):
        if i in holes:
            continue
        for j, u in enumerate(face):
            ids.append(i)
            corner.append(u)
            uv.append(corner_uv(scheme, len(face), j))
            # towards the face's centre (Loop, quads) or the corner's sub-face's (other polygons: side 1/2)
            centre = [1 / 3, 1 / 3] if scheme == "loop" else [0.5, 0.5] if len(face) == 4 else np.add(uv[-1], 0.25)
            inward.append(np.subtract(centre, uv[-1]))
    ids, uv = np.array(ids), np.array(uv, float)
    p = s.evaluate(ids, uv)
    diagonal = np.linalg.norm(np.ptp(v, axis=0))
    miss = np.linalg.norm(p - v[np.array(corner)], axis=1) / diagonal
    mask = np.isin(corner, at)
    # The jump next to those corners: the point 1e-9 of the way inward against the corner's.
    jump = 0.0
    if mask.any():
        near = s.evaluate(ids[mask], uv[mask] + 1e-9 * np.array(inward)[mask])
        jump = np.linalg.norm(near - p[mask], axis=1).max() / diagonal
    return (miss[mask].max() if mask.any() else 0.0), (miss[~mask].max() if (~mask).any() else 0.0), jump


def generated():
    """A bumpy quad grid and its triangulation with a sharp path ending inside; an irregular torus with paths."""
    out = []
    v, f = sorpia.shapes.quad_grid(12, 12)
    v = np.asarray(v, float)
    v[:, 2] += 0.05 * np.sin(9.0 * v[:, 0]) * np.cos(7.0 * v[:, 1])
    path = [12 * i + 6 for i in range(0, 6)]  # from the boundary to the middle
    creases = (np.column_stack([path[:-1], path[1:]]), np.inf)
    out.append(("quad grid 12x12, path ending inside", v, f, "catmull-clark", "edge-and-corner", {"creases": creases}))
    t = sorpia.shapes.grid(12, 12)[1]
    out.append(("triangle grid 12x12, same path", v, t, "loop", "edge-and-corner", {"creases": creases}))
    v, f = sorpia.shapes.irregular(400, seed=2)
    e = np.unique(np.sort(np.asarray(f)[::37, :2], axis=1), axis=0)
    out.append(("irregular(400), isolated sharp edges", np.asarray(v), f, "loop", "edge-and-corner",
                {"creases": (e, np.inf)}))
    v, f = sorpia.shapes.quad_irregular(1200, seed=2)
    f = np.asarray(f)
    e = np.unique(np.sort(f[::41, :2], axis=1), axis=0)
    out.append(("quad_irregular(1200), sharp 2.5 and inf edges", np.asarray(v), f, "catmull-clark", "edge-only",
                {"creases": (e, np.where(np.arange(len(e)) % 3, np.inf, 2.5))}))
    v, f = sorpia.shapes.quad_grid(12, 12)
    v = np.asarray(v, float)
    v[:, 2] += 0.05 * np.sin(9.0 * v[:, 0]) * np.cos(7.0 * v[:, 1])
    v, f = split_quads(v, f, [13, 40, 66, 100], 0.1)
    out.append(("quad grid 12x12, 4 quads split", v, f, "catmull-clark", "edge-and-corner", {}))
    v, f = gregory_test8()
    f = sorpia.Polygons(np.array([len(x) for x in f]), np.concatenate(f))
    out.append(("gregory_test8 (topology)", v, f, "catmull-clark", "edge-and-corner", {}))
    v, f = sorpia.shapes.quad_irregular(1200, seed=2)
    v, f = split_quads(v, f, range(0, 1000, 50), 0.02)
    out.append(("quad_irregular(1200), 20 quads split", v, f, "catmull-clark", "edge-only", {}))
    v, f = sorpia.shapes.quad_irregular(1200, seed=2)
    v, f = split_quads(v, f, np.random.default_rng(2).choice(len(f), len(f) // 4, replace=False), 0.02)
    out.append(("quad_irregular(1200), a quarter of its quads split", v, f, "catmull-clark", "edge-only", {}))
    return out


def split_cases():
    """Quad meshes with many quads split by a vertex of two faces, and one with none."""
    out = []
    v, f = sorpia.shapes.quad_irregular(12_000, seed=1)
    out.append(("quad_irregular(12000), none split", np.asarray(v), np.asarray(f)))
    for share in (0.01, 0.1):
        which = np.random.default_rng(1).choice(len(f), int(share * len(f)), replace=False)
        out.append((f"quad_irregular(12000), {share:.0%} of its quads split", *split_quads(v, f, which, 0.01)))
    v, f = sorpia.shapes.quad_irregular(1200, seed=3)
    out.append(("quad_irregular(1200), every quad split", *split_quads(v, f, range(len(f)), 0.02)))
    return out


class _Mallinfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks",
                                                      "fsmblks", "uordblks", "fordblks", "keepcost")]


def heap_mb():
    """Bytes malloc has handed out and not had back (glibc's mallinfo2), in MB."""
    libc = ctypes.CDLL("libc.so.6")
    libc.mallinfo2.restype = _Mallinfo2
    info = libc.mallinfo2()
    return (info.uordblks + info.hblkhd) / 2**20


def split_table():
    """Per mesh: |LimitSurface.evaluate - Far| / diagonal at every corner of every quad of the level-2
    refinement, the first evaluation (16 points a face: it builds the patches), the next ones (median of 5, with
    derivatives) and the heap the surface holds after the first."""
    lines = ["| mesh | faces | faces at a vertex of two faces | max miss against Far | first evaluation (s) | "
             "next evaluations (s) | heap held after the first (MB) |", "|---|---:|---:|---:|---:|---:|---:|"]
    rng = np.random.default_rng(5)
    for name, v, f in split_cases():
        diagonal = np.linalg.norm(np.ptp(v, axis=0))
        vs, fs = sorpia.limit_surface(v, f, level=2, scheme="catmull-clark")
        face, uv = refined_corner_uv(len(f), 2)
        miss = np.linalg.norm(sorpia.LimitSurface(v, f, scheme="catmull-clark").evaluate(face, uv)
                              - vs[fs.reshape(-1)], axis=1).max() / diagonal
        counts = np.bincount(f.reshape(-1), minlength=len(v))
        at_two = int(np.isin(f, np.flatnonzero(counts == 2)).any(axis=1).sum())
        ids = np.repeat(np.arange(len(f), dtype=np.int32), 16)
        uv = rng.random((len(ids), 2))
        before = heap_mb()
        s = sorpia.LimitSurface(v, f, scheme="catmull-clark")
        t0 = time.perf_counter()
        s.evaluate(ids, uv)
        first = time.perf_counter() - t0
        grown = heap_mb() - before
        nexts = []
        for _ in range(5):
            t0 = time.perf_counter()
            s.evaluate(ids, uv, derivatives=True)
            nexts.append(time.perf_counter() - t0)
        line = (f"| {name} | {len(f)} | {at_two} | {miss:.1e} | {first:.3f} | {np.median(nexts):.3f} | "
                f"{grown:.1f} |")
        print(line, flush=True)
        lines.append(line)
    return lines


def shapes(shared: Path, names):
    out = []
    for name in names if shared.exists() else []:
        v, f, tags = sorpia.read_mesh(shared / name, tags=True)
        boundary = tags.pop("boundary", "edge-and-corner")
        out.append((name, v, f, "loop" if name.startswith("osd_loop") else "catmull-clark", boundary, tags))
    return out + generated()


def fit(B, v):
    return scipy.sparse.linalg.splu(B.tocsc()).solve(v)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=SHARED, help="the folder of OpenSubdiv's shapes (skipped if absent)")
    ap.add_argument("--names", default=",".join(OSD), help="comma-separated files in --shared")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write the page")
    args = ap.parse_args()
    lines = ["| shape | scheme | vertices | darts and two-face vertices | miss there, Far's Limit() rows "
             "| miss there, limit rows | miss elsewhere (both) | jump next to them |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, v, f, scheme, boundary, tags in shapes(args.shared, args.names.split(",")):
        n = len(v)
        at = darts(f, n, scheme, **tags)
        B = sorpia.limit_matrix(f, n, boundary=boundary, scheme=scheme, **tags)
        topo = make_topology(f, n, scheme=scheme, warn=False)
        data, indices, indptr = _reference.reference_limit_matrix(
            topo, _core.Rules(scheme=as_scheme(scheme), boundary=as_boundary(boundary), tags=make_tags(topo, **tags)))
        far = scipy.sparse.csr_matrix((data, indices, indptr), shape=(n, n))
        before, other_before, _ = corner_misses(fit(far, v), v, f, boundary, scheme, tags, at)
        after, other_after, jump = corner_misses(fit(B, v), v, f, boundary, scheme, tags, at)
        line = (f"| {name} | {scheme} | {n} | {len(at)} | {before:.1e} | {after:.1e} | "
                f"{max(other_before, other_after):.1e} | {jump:.1e} |")
        print(line, flush=True)
        lines.append(line)

    # Cost: k isolated infinitely sharp edges (2k darts) against the same 2k vertices as infinitely sharp corners.
    cost = ["", "| mesh | scheme | darts | B with darts (s) | B with corners there (s) | per dart (us) |",
            "|---|---|---:|---:|---:|---:|"]
    for scheme, (v, f) in [("loop", sorpia.shapes.irregular(100_000, seed=1)),
                           ("catmull-clark", sorpia.shapes.quad_irregular(100_000, seed=1))]:
        f = np.asarray(f) if not isinstance(f, sorpia.Polygons) else f
        fl = np.asarray(f)
        e = np.unique(np.sort(fl[::50, :2], axis=1), axis=0)
        ends = np.unique(e)
        at = darts(f, len(v), creases=(e, np.inf))
        times = {}
        for kind, tags in (("darts", {"creases": (e, np.inf)}),
                           ("corners", {"creases": (e, np.inf), "corners": (ends, np.inf)})):
            best = np.inf
            for _ in range(3):
                t0 = time.perf_counter()
                sorpia.limit_matrix(f, len(v), scheme=scheme, **tags)
                best = min(best, time.perf_counter() - t0)
            times[kind] = best
        per = (times["darts"] - times["corners"]) / max(len(at), 1) * 1e6
        line = (f"| {'irregular' if scheme == 'loop' else 'quad_irregular'}({len(v)}) | {scheme} | {len(at)} | "
                f"{times['darts']:.3f} | {times['corners']:.3f} | {per:.1f} |")
        print(line, flush=True)
        cost.append(line)
    # Cost: k quads split by a vertex of two faces against the same mesh unsplit.
    cost += ["", "| mesh | vertices of two faces | B split (s) | B unsplit (s) | per vertex of two faces (us) |",
             "|---|---:|---:|---:|---:|"]
    v, f = sorpia.shapes.quad_irregular(100_000, seed=1)
    split = split_quads(v, f, range(0, len(np.asarray(f)), 50), 0.01)
    times = {}
    for kind, (vv, ff) in (("split", split), ("plain", (np.asarray(v), np.asarray(f)))):
        best = np.inf
        for _ in range(3):
            t0 = time.perf_counter()
            sorpia.limit_matrix(ff, len(vv), scheme="catmull-clark")
            best = min(best, time.perf_counter() - t0)
        times[kind] = best
    k = len(split[0]) - len(v)
    line = (f"| quad_irregular({len(v)}) | {k} | {times['split']:.3f} | {times['plain']:.3f} | "
            f"{(times['split'] - times['plain']) / k * 1e6:.1f} |")
    print(line, flush=True)
    cost.append(line)
    split = split_table()
    if not args.no_page:
        body = ("Misses are the largest |P - V| over the diagonal at the face corners (the limit surface of the "
                "fitted cage, evaluated by sorpia.LimitSurface), at darts and Catmull-Clark's vertices of two faces, "
                "and elsewhere; the jump is the distance from such a corner's point to the surface's point 1e-9 of "
                "the way to the face's (or the corner's sub-face's) centre (Bfr's corner there is its own, Far's Limit() after its smooth level: "
                "10 on a mesh with darts).\n\n" + "\n".join(lines + cost) +
                "\n\nBfr before OpenSubdiv 3.6.1 (pull request 1353) builds the patch of a face with a corner at an "
                "interior vertex of two faces from that face's vertex indices but shares it, through its topology "
                "cache, with faces of the same topology whose indices repeat differently, where it is wrong (2e-2 "
                "of the diagonal on quad_irregular(1200) with a quarter of its quads split). sorpia builds those "
                "faces with a factory without the cache, each once, when first evaluated, and keeps them. Below, the "
                "misses of sorpia.LimitSurface against Far's refinement (sorpia.limit_surface at level 2: Far's "
                "Limit() on the last level, B V at the control vertices) at every corner of every refined quad, "
                "and the cost, the control vertices as cage (16 random points a face; 'first' builds the patches, "
                "'next' evaluates with derivatives).\n\n" + "\n".join(split))
        write_page("darts", "Fits through darts", body, settings=(ap, args))


if __name__ == "__main__":
    main()
