"""sorpia.decimate: cages made by OpenMesh's quadric decimation, its triangles paired into quads for Catmull-Clark,
with the sharp edges of the cage as creases. Checked against properties computed here in numpy and scipy: counts, edge
incidences, Euler characteristic, distances to the sphere, the quads against the Loop cage's triangles, dihedral
angles, fits of both schemes."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest
from scipy.spatial import cKDTree

import sorpia


def edge_counts(faces):
    """{directed edge (a, b): how many faces have it}, over the faces' consecutive corners."""
    faces = np.asarray(faces)
    a, b = faces.ravel(), np.roll(faces, -1, axis=1).ravel()
    keys, counts = np.unique(np.stack([a, b], axis=1), axis=0, return_counts=True)
    return {tuple(k): c for k, c in zip(keys.tolist(), counts.tolist())}


def check_oriented_manifold(vertices, faces, closed):
    """Every directed edge in one face (consistent orientation), every edge in at most two faces, and on a closed
    mesh in exactly two (its opposite present); every vertex used."""
    directed = edge_counts(faces)
    assert max(directed.values()) == 1
    unpaired = [e for e in directed if (e[1], e[0]) not in directed]
    assert (not unpaired) if closed else bool(unpaired)
    assert np.array_equal(np.unique(faces), np.arange(len(vertices)))
    return unpaired


def euler_characteristic(vertices, faces):
    edges = {tuple(sorted(e)) for e in edge_counts(faces)}
    return len(vertices) - len(edges) + len(faces)


def boundary_loops(unpaired):
    """The boundary's directed edges chained into loops; the number of loops."""
    succ = dict(unpaired)
    seen, loops = set(), 0
    for start in succ:
        if start in seen:
            continue
        loops += 1
        v = start
        while v not in seen:
            seen.add(v)
            v = succ[v]
    return loops


def surface_samples(vertices, faces, n=8):
    """Points on every face: a barycentric grid of n + 1 points a side (triangles) or a bilinear n x n grid
    (quads)."""
    t = np.linspace(0, 1, n + 1)
    corners = vertices[np.asarray(faces)]
    if corners.shape[1] == 3:
        u, v = np.meshgrid(t, t)
        keep = u + v <= 1 + 1e-12
        u, v = u[keep], v[keep]
        w = np.stack([1 - u - v, u, v], axis=1)
    else:
        u, v = (x.ravel() for x in np.meshgrid(t, t))
        w = np.stack([(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v], axis=1)
    return np.einsum("pk,fkd->fpd", w, corners).reshape(-1, 3)


def flat_split(vertices, faces, n):
    """Each triangle split into n * n flat triangles (points of a barycentric grid, shared along the edges): the
    same polyhedron, densely meshed."""
    points, tris = [], []
    for a, b, c in np.asarray(vertices)[np.asarray(faces)]:
        index = {}
        for i in range(n + 1):
            for j in range(n + 1 - i):
                index[i, j] = len(points)
                points.append(a + (b - a) * i / n + (c - a) * j / n)
        for i in range(n):
            for j in range(n - i):
                tris.append([index[i, j], index[i + 1, j], index[i, j + 1]])
                if i + j + 1 < n:
                    tris.append([index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]])
    points = np.array(points)
    _, first, inverse = np.unique(np.round(points, 12), axis=0, return_index=True, return_inverse=True)
    return points[first], inverse.ravel()[np.array(tris)].astype(np.int32)


def test_loop_cage_has_the_count_and_stays_on_the_sphere():
    v, f = sorpia.shapes.icosphere(4)  # 2562 vertices on the unit sphere
    cage = sorpia.decimate(v, f, 300)
    assert cage.vertices.shape == (300, 3) and cage.faces.shape[1] == 3 and cage.creases is None
    check_oriented_manifold(cage.vertices, cage.faces, closed=True)
    assert euler_characteristic(cage.vertices, cage.faces) == 2
    # A collapse moves a vertex onto a neighbour: the cage's vertices are input vertices.
    assert cKDTree(v).query(cage.vertices)[0].max() < 1e-15
    # Hausdorff-like, both ways. Cage to sphere: a face inscribed in the unit sphere lies in a plane at distance
    # sqrt(1 - R^2) from the centre (R its circumradius), so it is within 1 - sqrt(1 - R^2) of the sphere; the
    # quadric keeps the faces even (a uniform 300-vertex triangulation has R about 0.15), none above 0.3, so within
    # 0.05. Sphere to cage: every input vertex near the cage, by the nearest of 45 samples per face (an upper
    # bound, the samples 1/8 of an edge apart).
    t = cage.vertices[cage.faces]
    a, b, c = (np.linalg.norm(t[:, i] - t[:, j], axis=1) for i, j in ((1, 2), (2, 0), (0, 1)))
    area = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1) / 2
    circumradius = a * b * c / (4 * area)
    assert circumradius.max() < 0.3
    samples = surface_samples(cage.vertices, cage.faces)
    assert np.abs(np.linalg.norm(samples, axis=1) - 1).max() <= 1 - np.sqrt(1 - circumradius.max() ** 2) + 1e-12
    assert cKDTree(samples).query(v)[0].max() < 0.05


def face_lists(faces):
    """The faces as lists of corners: an (m, k) array or sorpia.Polygons."""
    if isinstance(faces, sorpia.Polygons):
        return np.split(np.asarray(faces.face_vertex_indices), np.cumsum(faces.face_vertex_counts)[:-1])
    return list(np.asarray(faces))


def bumpy_sphere(level=5, noise=0.0):
    """Points of the bumpy sphere r = 1 + 0.25 sin 6x sin 6y sin 6z (an icosphere's vertices moved out to it),
    with its triangles; `noise` (of the radius) along the normal of the sphere, seed 3."""
    V, F = sorpia.shapes.icosphere(level)
    r = 1 + 0.25 * np.sin(6 * V[:, 0]) * np.sin(6 * V[:, 1]) * np.sin(6 * V[:, 2])
    r = r + noise * np.random.default_rng(3).standard_normal(len(V))
    return np.ascontiguousarray(V * r[:, None]), F


def test_catmull_clark_cage_is_the_loop_cages_triangles_paired_into_quads():
    v, f = bumpy_sphere(4)
    loop = sorpia.decimate(v, f, 300)
    cage = sorpia.decimate(v, f, 300, scheme="catmull-clark")
    # The same decimation: the count asked exactly, the Loop cage's vertices.
    np.testing.assert_array_equal(cage.vertices, loop.vertices)
    faces = face_lists(cage.faces)
    sizes = np.array([len(x) for x in faces])
    assert set(sizes.tolist()) <= {3, 4}
    # Each quad is two of the Loop cage's triangles across one diagonal ((a, d, b, c) = (a, b, c) + (b, a, d)),
    # each triangle is in one face: the faces are the Loop cage's triangles, grouped.
    triangles = []
    for x in faces:
        triangles += [tuple(x)] if len(x) == 3 else [(x[0], x[2], x[3]), (x[2], x[0], x[1])]
    canon = lambda t: min((t[i], t[(i + 1) % 3], t[(i + 2) % 3]) for i in range(3))  # noqa: E731
    assert sorted(map(canon, triangles)) == sorted(canon(tuple(t)) for t in loop.faces.tolist())
    # Most are paired (measured: 97% of 596 triangles, 20 left; 90% stated), and a pairing never leaves a
    # vertex with two edges (Catmull-Clark's rules want none inside).
    assert 2 * (sizes == 4).sum() >= 0.9 * len(loop.faces)
    directed = {}
    for x in faces:
        for a, b in zip(x, np.roll(x, -1)):
            directed[a, b] = directed.get((a, b), 0) + 1
    assert max(directed.values()) == 1 and all((b, a) in directed for a, b in directed)
    edges = {tuple(sorted(e)) for e in directed}
    assert len(cage.vertices) - len(edges) + len(faces) == 2
    valence = np.bincount(np.array(list(edges)).ravel(), minlength=len(cage.vertices))
    assert valence.min() >= 3
    # Quads well shaped: every corner convex and between 30 and 150 degrees would be too much to promise of a
    # decimation; none is reflex (the pairing refuses a quad whose triangles fold over their diagonal).
    for x in faces:
        if len(x) == 4:
            p = cage.vertices[x]
            n = np.cross(p[2] - p[0], p[3] - p[1])
            for i in range(4):
                assert np.cross(p[(i + 1) % 4] - p[i], p[i - 1] - p[i]) @ n > 0
    # And OpenSubdiv takes it (a mixed cage: the triangles are Catmull-Clark's n-gons).
    tv, _ = sorpia.limit_surface(cage.vertices, cage.faces, 2, scheme="catmull-clark")
    assert np.isfinite(tv).all()


def test_catmull_clark_cage_fits_as_well_as_loops_and_every_face_gets_points():
    # Issue 32, item 4: the cages split into three quads per triangle of a 6x coarser decimation fitted 1.4-6x
    # worse than Loop's and left quads without a point. A noisy bumpy sphere of 10,242 points, a 200-vertex cage.
    P, F = bumpy_sphere(5, noise=1e-3)
    fits = {}
    for scheme in ("loop", "catmull-clark"):
        cage = sorpia.decimate(P, F, 200, scheme=scheme)
        assert len(cage.vertices) == 200
        fits[scheme] = sorpia.approximate(P, cage.vertices, cage.faces, scheme=scheme, iterations=5)
        # Every face gets points: each point goes to the face of its nearest sample of the cage's faces (a
        # 9 x 9 grid on a quad, 45 points on a triangle), and every face has one.
        samples, owner = [], []
        for i, x in enumerate(face_lists(cage.faces)):
            s = surface_samples(cage.vertices, [x])
            samples.append(s)
            owner += [i] * len(s)
        nearest = np.asarray(owner)[cKDTree(np.vstack(samples)).query(P)[1]]
        assert len(np.unique(nearest)) == len(face_lists(cage.faces))
    # Measured: Loop 3.36e-3, Catmull-Clark 3.74e-3 (1.12x; the 3-quad split of before: 9.06e-3, 2.7x).
    assert fits["catmull-clark"].rms <= 1.3 * fits["loop"].rms


def test_boundary_keeps_its_corners_and_outline():
    v, f = sorpia.shapes.grid(30, 30)  # [0, 1]^2, wavy in z; corners (0,0) (1,0) (0,1) (1,1)
    cage = sorpia.decimate(v, f, 150)
    assert len(cage.vertices) == 150
    unpaired = check_oriented_manifold(cage.vertices, cage.faces, closed=False)
    assert boundary_loops(unpaired) == 1
    for corner in ([0, 0], [1, 0], [0, 1], [1, 1]):
        assert np.min(np.abs(cage.vertices[:, :2] - corner).sum(axis=1)) == 0
    # Every boundary edge runs along one side of the square: none cuts a corner.
    for a, b in unpaired:
        pa, pb = cage.vertices[a, :2], cage.vertices[b, :2]
        assert any(pa[k] == pb[k] and pa[k] in (0.0, 1.0) for k in (0, 1))
    # max_boundary_angle=0 keeps every boundary vertex where the boundary turns: the 2 * 30 of the wavy sides
    # y = 0 and y = 1 (z = 0.1 sin(2 pi x)); the straight sides x = 0 and x = 1 may lose theirs.
    kept = sorpia.decimate(v, f, 300, max_boundary_angle=0)
    wavy = v[np.isin(v[:, 1], (0.0, 1.0))]
    assert len(wavy) == 60 and cKDTree(kept.vertices).query(wavy)[0].max() == 0


def test_sharp_angle_creases_are_the_edges_whose_faces_meet_at_more_than_it():
    tetra = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    v, f = flat_split(tetra, [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]], 12)
    for scheme in ("loop", "catmull-clark"):
        cage = sorpia.decimate(v, f, 40, scheme=scheme, sharp_angle=30)
        edges, sharpness = cage.creases
        assert len(edges) and np.all(sharpness >= 10)  # OpenSubdiv's infinitely sharp
        # The dihedral angle of every interior edge, here in numpy: a crease exactly where it exceeds 30 degrees.
        # Newell's normal of each face (a Catmull-Clark cage has quads and the triangles its pairing left).
        faces = [x.tolist() for x in face_lists(cage.faces)]
        normals = np.array([sum(np.cross(cage.vertices[a], cage.vertices[b]) for a, b in zip(x, x[1:] + x[:1]))
                            for x in faces])
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        face_of = {}
        for i, face in enumerate(faces):
            for a, b in zip(face, face[1:] + face[:1]):
                face_of[a, b] = i
        creases = {tuple(e) for e in edges.tolist()}
        for (a, b), i in face_of.items():
            if a < b:
                cos = np.clip(normals[i] @ normals[face_of[b, a]], -1, 1)
                assert ((a, b) in creases) == (np.degrees(np.arccos(cos)) > 30)
        # They lie along the tetrahedron's six edges, the points (+-1, t, +-t) and their permutations: the
        # midpoint of each crease has a coordinate of magnitude 1 and two of equal magnitude.
        mid = np.sort(np.abs(cage.vertices[edges].mean(axis=1)), axis=1)
        assert np.allclose(mid[:, 2], 1, atol=1e-9) and np.allclose(mid[:, 0], mid[:, 1], atol=1e-9)


def test_unreferenced_vertices_are_left_out():
    v, f = sorpia.shapes.icosphere(2)  # 162 vertices
    extra = np.vstack([v, [[5.0, 5.0, 5.0]]])
    cage = sorpia.decimate(extra, f, 100)
    assert len(cage.vertices) == 100 and np.linalg.norm(cage.vertices, axis=1).max() < 1 + 1e-12
    with pytest.raises(sorpia.MeshError, match="163 vertices asked but the mesh has 162 vertices in its faces"):
        sorpia.decimate(extra, f, 163)


def test_bad_input_is_named():
    v, f = sorpia.shapes.icosphere(2)
    with pytest.raises(sorpia.MeshError, match="200 vertices asked but the mesh has 162 vertices"):
        sorpia.decimate(v, f, 200)
    with pytest.raises(sorpia.ParameterError, match="at least 4 vertices, got 3"):
        sorpia.decimate(v, f, 3)
    with pytest.raises(sorpia.MeshError, match="Catmull-Clark|triangulate"):
        sorpia.decimate(*sorpia.shapes.quad_torus(8, 6), 20)
    with pytest.raises(sorpia.ParameterError, match="sharp angle"):
        sorpia.decimate(v, f, 100, sharp_angle=200)
    with pytest.raises(sorpia.ParameterError, match="max_aspect_ratio"):
        sorpia.decimate(v, f, 100, max_aspect_ratio=0.5)
    with pytest.raises(sorpia.ParameterError, match="unknown|scheme"):
        sorpia.decimate(v, f, 100, scheme="butterfly")
    # An edge of three faces: named.
    fan = np.vstack([f, [[f[0, 0], f[0, 1], next(x for x in range(len(v)) if x not in f[0])]]])
    with pytest.raises(sorpia.MeshError, match=f"face {len(f)} cannot join OpenMesh's half-edge mesh"):
        sorpia.decimate(v, fan, 100)
    # A face oriented against its neighbours: the edge and the faces named, as Topology names them.
    twisted = f.copy()
    twisted[3] = twisted[3][::-1]
    with pytest.raises(sorpia.MeshError, match=r"cannot join OpenMesh's half-edge mesh: inconsistent orientation at "
                       r"edge \(\d+, \d+\)"):
        sorpia.decimate(v, twisted, 100)
    # Decimation the guards stop: the 60 vertices of the wavy sides kept cannot reach 50.
    gv, gf = sorpia.shapes.grid(30, 30)
    with pytest.raises(sorpia.MeshError, match=r"decimate stopped at \d+ vertices of the 50 asked \(from 900\)"):
        sorpia.decimate(gv, gf, 50, max_boundary_angle=0)
    # Under Catmull-Clark the count is the same: the triangles' vertices (their pairing into quads keeps them).
    with pytest.raises(sorpia.MeshError, match="163 vertices asked but the mesh has 162 vertices"):
        sorpia.decimate(v, f, 163, scheme="catmull-clark")


def holed_plate(m=12):
    """A flat m x m plate of unit squares (two triangles each) with the cells (i, j), i % 3 == j % 3 == 1, cut
    out: 16 square holes for m = 12. Returns (vertices, triangles, the 4 + 4 * holes corners where the boundary
    turns by 90 degrees)."""
    index = lambda i, j: i * (m + 1) + j  # noqa: E731
    vertices = np.array([[i, j, 0.0] for i in range(m + 1) for j in range(m + 1)])
    holes = [(i, j) for i in range(m) for j in range(m) if i % 3 == 1 and j % 3 == 1]
    tris = []
    for i in range(m):
        for j in range(m):
            if (i, j) not in holes:
                a, b, c, d = index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)
                tris += [[a, b, c], [a, c, d]]
    corners = [[0, 0], [m, 0], [0, m], [m, m]] + [[i + di, j + dj] for i, j in holes for di in (0, 1) for dj in (0, 1)]
    return vertices, np.array(tris, dtype=np.int32), np.array(corners, dtype=float)


def test_not_strict_returns_the_cage_the_guards_stopped_at():
    """strict=False: where the guards stop decimation above the count asked, the cage reached comes back with a
    DecimationWarning (the MeshError's words) instead of the error. Why it stopped is checked here: the boundary
    turns by 90 degrees at the plate's 68 corners (more than max_boundary_angle, 30), so every one of them stays."""
    v, f, corners = holed_plate()
    with pytest.raises(sorpia.MeshError, match=r"decimate stopped at (\d+) vertices of the 20 asked") as raised:
        sorpia.decimate(v, f, 20)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cage = sorpia.decimate(v, f, 20, strict=False)
    assert [w.category for w in caught] == [sorpia.DecimationWarning]
    assert str(caught[0].message) == str(raised.value)
    assert f"stopped at {len(cage.vertices)} vertices of the 20 asked (from 169)" in str(raised.value)
    assert len(cage.vertices) >= len(corners) == 68
    assert cKDTree(cage.vertices[:, :2]).query(corners)[0].max() == 0
    check_oriented_manifold(cage.vertices, cage.faces, closed=False)
    # Reached counts give no warning and the cage asked.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(sorpia.decimate(v, f, 120, strict=False).vertices) == 120


def test_command_fits_the_cage_the_guards_stopped_at_and_says_so(tmp_path):
    """`sorpia approximate --vertices N` where decimation stops above N: the cage reached is fitted and written,
    a warning on stderr says how far decimation got and why, the report records it ("stopped"), exit 0."""
    v, f, corners = holed_plate()
    sorpia.write_mesh(tmp_path / "plate.ply", v, f)
    r = subprocess.run([sys.executable, "-m", "sorpia", "approximate", "plate.ply", "-o", "cage.obj", "--vertices",
                        "20", "--iterations", "2", "--report", "r.json"], cwd=tmp_path, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    report = json.loads((tmp_path / "r.json").read_text())
    cage_v, _ = sorpia.read_mesh(tmp_path / "cage.obj")
    n = report["cage"]["vertices"]
    assert n == len(cage_v) >= 68 and report["cage"]["vertices_asked"] == 20
    assert report["cage"]["stopped"].startswith(f"decimate stopped at {n} vertices of the 20 asked (from 169)")
    assert f"sorpia: warning: decimate stopped at {n} vertices of the 20 asked" in r.stderr
    assert f"fitting the cage of {n} vertices it reached" in r.stderr
    assert "20 asked: the guards stopped decimation" in r.stdout
    # The plate is flat: its fitted limit surface lies in z = 0 (the data there), to rounding.
    assert np.abs(cage_v[:, 2]).max() < 1e-9
    # A count reached records no stop.
    r = subprocess.run([sys.executable, "-m", "sorpia", "approximate", "plate.ply", "-o", "cage2.obj", "--vertices",
                        "120", "--iterations", "1", "--report", "r2.json", "--quiet"], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    assert json.loads((tmp_path / "r2.json").read_text())["cage"]["stopped"] is None


@pytest.mark.parametrize("scale", [1e20, 1e155, 1e-155])
def test_decimation_does_not_depend_on_the_scale(scale):
    """A cage at any scale: OpenMesh works on coordinates scaled by a power of two, so the cage of 20 vertices
    is reached as at scale 1 (which vertices survive may differ where priorities tie on this flat grid) and its
    vertices are input vertices, unmoved (a half-edge collapse keeps them)."""
    v, f = sorpia.shapes.grid(8, 8)
    v = np.asarray(v, float)
    big = sorpia.decimate(v * scale, f, 20)
    assert len(big.vertices) == len(sorpia.decimate(v, f, 20).vertices) == 20
    kept = {tuple(p) for p in (v * scale).tolist()}
    assert all(tuple(p) in kept for p in big.vertices.tolist())


@pytest.mark.parametrize("offset", [1e3, 1e6, -3e8])
def test_decimation_does_not_depend_on_where_the_mesh_lies(offset):
    """The same noisy sphere moved away from the origin gives the same cage (issue 33, item 9): OpenMesh's quadric
    errors are differences of terms of order |p|^2, which far from the origin rounding decides (before the
    decimation ran in centred coordinates, at 1e6 the cage's faces strayed 1.5 times as far from the sphere)."""
    v, f = sorpia.shapes.icosphere(4)
    v = v * (1 + 0.002 * np.random.default_rng(0).standard_normal((len(v), 1)))
    shift = offset * np.array([1.0, -0.5, 0.25])
    here, there = sorpia.decimate(v, f, 200), sorpia.decimate(v + shift, f, 200)
    assert np.array_equal(np.asarray(here.faces), np.asarray(there.faces))
    # The cage's vertices are the input's: exactly the moved ones.
    assert np.array_equal(there.vertices, (v + shift)[[np.flatnonzero((v == p).all(axis=1))[0] for p in here.vertices]])


def test_catmull_clark_cage_of_an_open_mesh_keeps_its_boundary_and_orientation():
    # A wavy 30 x 30 grid: the paired cage has the Loop cage's vertices and boundary, every directed edge once,
    # and no vertex with fewer than two edges (a corner) on the boundary or three inside.
    v, f = sorpia.shapes.grid(30, 30)
    loop = sorpia.decimate(v, f, 150)
    cage = sorpia.decimate(v, f, 150, scheme="catmull-clark")
    np.testing.assert_array_equal(cage.vertices, loop.vertices)
    faces = face_lists(cage.faces)
    directed = [(a, b) for x in faces for a, b in zip(x.tolist(), np.roll(x, -1).tolist())]
    assert len(set(directed)) == len(directed)
    boundary = {(a, b) for a, b in directed if (b, a) not in set(directed)}
    assert boundary == set(check_oriented_manifold(loop.vertices, loop.faces, closed=False))
    edges = {tuple(sorted(e)) for e in directed}
    valence = np.bincount(np.array(sorted(edges)).ravel(), minlength=len(cage.vertices))
    on_boundary = np.zeros(len(cage.vertices), bool)
    on_boundary[np.array(sorted(boundary)).ravel()] = True
    assert valence[on_boundary].min() >= 2 and valence[~on_boundary].min() >= 3
    assert 2 * sum(len(x) == 4 for x in faces) >= 0.85 * len(loop.faces)  # measured: 93% of 269


def test_a_cage_held_up_by_holes_says_so():
    """Issue 33, item 11: a patch with 49 single-triangle holes asked for a 150-vertex Catmull-Clark cage stops
    above it (measured: 168 and 171 vertices, 163 of them on the boundary; each hole keeps its three corners: no
    collapse closes a hole, whatever max_boundary_angle allows); the warning says how many of the cage's vertices
    lie on how many boundary loops, and what to do."""
    v, f = sorpia.shapes.grid(40, 40)
    f = np.asarray(f)
    centres = np.asarray(v)[f].mean(axis=1)[:, :2]
    lo, hi = centres.min(axis=0), centres.max(axis=0)
    holes = {int(np.argmin(np.linalg.norm(centres - (lo + (hi - lo) * (np.array([i, j]) + 1) / 8), axis=1)))
             for i in range(7) for j in range(7)}
    assert len(holes) == 49
    f = np.delete(f, sorted(holes), axis=0)
    for angle in (30, 180):
        with pytest.warns(sorpia.DecimationWarning) as caught:
            cage = sorpia.decimate(v, f, 150, scheme="catmull-clark", strict=False, max_boundary_angle=angle)
        # Held up: 49 holes of at least 3 vertices each and the outer loop's 4 corners.
        assert len(cage.vertices) >= 49 * 3 + 4
        message = str(caught[0].message)
        assert f"decimate stopped at {len(cage.vertices)} vertices of the 150 asked" in message
        assert f"of the cage's {len(cage.vertices)} vertices lie on its 50 boundary loops" in message
        assert "lie on its 50 boundary loops: each loop keeps at least 3 (no collapse closes a hole)" in message
        assert f"max_boundary_angle ({angle} degrees)" in message and "fill small holes first" in message


def corner_plate(m=17):
    """A plate of m x m unit cells (m odd) with a square hole at every cell (i, j) of odd i and j ((m//2)^2 holes), its
    outline zigzagging (every other outline vertex pushed out by 2): every vertex is a corner of a hole or of the
    outline, where the boundary turns by 90 degrees (holes) or at least 36.9 (acos 0.8, at a corner of the plate
    between two pushed vertices)."""
    xy = np.array([[i, j] for j in range(m + 1) for i in range(m + 1)], float)
    on_side = (xy == 0) | (xy == m)
    odd = (xy.sum(axis=1) % 2 == 1)
    for axis in (0, 1):  # pushed out across the side it lies on
        push = on_side[:, axis] & ~on_side[:, 1 - axis] & odd
        xy[push, axis] += np.where(xy[push, axis] == 0, -2.0, 2.0)
    idx = lambda i, j: j * (m + 1) + i  # noqa: E731
    faces = []
    for j in range(m):
        for i in range(m):
            if i % 2 == 1 and j % 2 == 1:
                continue
            faces += [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]]
    v = np.column_stack([xy, np.zeros(len(xy))])
    return v, np.array(faces, np.int32), (m // 2) ** 2


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
def test_a_cage_that_keeps_every_vertex_is_refused(scheme):
    """Issue 33, item 11: where no collapse is allowed (every vertex a corner of one of 64 holes or of the outline)
    the cage would have as many control vertices as the mesh has points: refused, strict or not, with the reason
    and the way out; the counts in the message are the mesh's own (numpy)."""
    v, f, n_holes = corner_plate()
    assert n_holes == 64
    turn = np.degrees(np.arccos(0.8))
    assert turn > 30  # the outline's corners: above the default max_boundary_angle
    for strict in (True, False):
        with pytest.raises(sorpia.MeshError) as caught:
            sorpia.decimate(v, f, 150, scheme=scheme, strict=strict)
        message = str(caught.value)
        n = len(np.unique(f))
        assert f"decimate stopped at {n} vertices of the 150 asked (from {n})" in message
        assert f"lie on its {n_holes + 1} boundary loops" in message
        assert f"the cage would keep all {n} vertices, as many control vertices as the mesh has points" in message
        assert "no fit is determined" in message and "give a cage of your own" in message
    # One hole filled (its two triangles back): a few collapses become legal and the cage is returned, with the
    # warning, lighter than the mesh.
    idx = lambda i, j: j * 18 + i  # noqa: E731
    filled = np.vstack([f, [[idx(7, 7), idx(8, 7), idx(8, 8)], [idx(7, 7), idx(8, 8), idx(7, 8)]]])
    with pytest.warns(sorpia.DecimationWarning):
        cage = sorpia.decimate(v, filled, 150, scheme=scheme, strict=False)
    assert 150 < len(cage.vertices) < len(np.unique(filled))


def test_the_command_refuses_a_cage_that_keeps_every_vertex(tmp_path, command):
    v, f, _ = corner_plate()
    sorpia.write_mesh(tmp_path / "plate.ply", v, f)
    code, out, err = command("approximate", tmp_path / "plate.ply", "-o", tmp_path / "cage.obj", "--vertices", 150)
    assert code == 2 and out == "", err
    assert "no light cage" in err and "no fit is determined" in err and "--cage CAGE" in err
    assert "repair" not in err  # the mesh is valid: no repair helps
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plate.ply"]


@pytest.mark.parametrize("count", [2000, 30000])
def test_a_large_mesh_clustered_or_decimated_in_rounds_fits_as_the_heap_alone(count):
    """From 200,000 vertices decimate lays the mesh out in Morton order and goes down to 4 times the count first:
    by vertex clustering where the mesh has more than 8 times the count (2000 here), else in rounds (30000), then
    the heap takes the rest (docs/cages.md); below 200,000 vertices, the heap alone. Two tori of the same shape on
    either side of that size, each to `count` vertices: both cages closed, oriented, of genus 1, made of input
    vertices, and their faces as close to the torus (distance from the torus's own equation, radii 1 and 0.4):
    the large mesh's RMS within 10% of the heap's, its max (one sample's, which moves by a quarter either way
    from one count to the next on either path) within 30%."""
    def torus_distance(p):
        return np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - 1.0, p[:, 2]) - 0.4)

    distances = {}
    for nu, nv in ((700, 300), (680, 290)):  # 210,000 vertices (clustered or rounds) and 197,200 (the heap alone)
        v, f = sorpia.shapes.torus(nu, nv)
        cage = sorpia.decimate(v, f, count)
        assert cage.vertices.shape == (count, 3)
        check_oriented_manifold(cage.vertices, cage.faces, closed=True)
        assert euler_characteristic(cage.vertices, cage.faces) == 0
        assert cKDTree(v).query(cage.vertices)[0].max() < 1e-15
        d = torus_distance(surface_samples(cage.vertices, cage.faces, n=8 if count < 10000 else 4))
        distances[len(v) >= 200000] = (np.sqrt(np.mean(d ** 2)), d.max())
    large, heap = distances[True], distances[False]
    assert large[0] <= 1.1 * heap[0] and large[1] <= 1.3 * heap[1], distances


def test_clustering_a_mesh_noisier_than_its_spacing_fits_as_the_heap_alone():
    """A torus whose vertices are moved along its normals by Gaussian noise of one vertex spacing (a scan denser
    than its noise), decimated to 2000 vertices: at 210,000 vertices its clusters fold in and out of the grid's
    cells until the grid is laid over smoothed positions (docs/cages.md); at 197,200 (the same shape and noise)
    the heap alone decimates it. Both cages closed, oriented, of genus 1, made of input vertices; the clustered
    one's faces as close to the noiseless torus (its equation, radii 1 and 0.4) as the heap's: RMS within 10%,
    max within 30%."""
    def torus_distance(p):
        return np.abs(np.hypot(np.hypot(p[:, 0], p[:, 1]) - 1.0, p[:, 2]) - 0.4)

    distances = {}
    for nu, nv in ((700, 300), (680, 290)):
        v, f = sorpia.shapes.torus(nu, nv)
        ring = np.hypot(v[:, 0], v[:, 1])
        normal = (v - np.stack([v[:, 0] / ring, v[:, 1] / ring, 0.0 * ring], axis=1)) / 0.4
        spacing = 2 * np.pi * 0.4 / nv
        v = v + normal * (spacing * np.random.default_rng(1).standard_normal(len(v)))[:, None]
        cage = sorpia.decimate(v, f, 2000)
        assert cage.vertices.shape == (2000, 3)
        check_oriented_manifold(cage.vertices, cage.faces, closed=True)
        assert euler_characteristic(cage.vertices, cage.faces) == 0
        assert cKDTree(v).query(cage.vertices)[0].max() < 1e-15
        d = torus_distance(surface_samples(cage.vertices, cage.faces, n=8))
        distances[len(v) >= 200000] = (np.sqrt(np.mean(d ** 2)), d.max())
    large, heap = distances[True], distances[False]
    assert large[0] <= 1.1 * heap[0] and large[1] <= 1.3 * heap[1], distances


def test_clustering_keeps_the_holes_and_their_boundary_vertices():
    """A large open mesh with holes (the wavy patch of 250,000 vertices, four round holes cut) clustered before
    its decimation: its boundary vertices (and their neighbours) are never clustered, so the cage has the input's
    boundary loops and Euler characteristic, its boundary vertices are input boundary vertices, and it is an
    oriented manifold."""
    v, f = sorpia.shapes.grid(500, 500)
    centroid = v[f].mean(axis=1)
    holes = np.array([[0.3, 0.3], [0.7, 0.35], [0.5, 0.7], [0.25, 0.75]])
    f = f[np.all(np.linalg.norm(centroid[:, None, :2] - holes[None], axis=2) > 0.06, axis=1)]
    used = np.unique(f)
    v, f = v[used], np.searchsorted(used, f).astype(np.int32)
    # The input's boundary: its directed edges whose opposite no face has (the patch is oriented consistently).
    a, b = f.ravel().astype(np.int64), np.roll(f, -1, axis=1).ravel().astype(np.int64)
    on_boundary = ~np.isin(a * len(v) + b, b * len(v) + a)
    boundary = list(zip(a[on_boundary].tolist(), b[on_boundary].tolist()))
    euler = len(v) - (3 * len(f) + len(boundary)) // 2 + len(f)
    assert len(v) > 200000 and boundary_loops(boundary) == 5 and euler == 1 - 4
    cage = sorpia.decimate(v, f, 2000)
    assert cage.vertices.shape == (2000, 3)
    cage_boundary = check_oriented_manifold(cage.vertices, cage.faces, closed=False)
    assert boundary_loops(cage_boundary) == 5
    assert euler_characteristic(cage.vertices, cage.faces) == euler
    distance, nearest = cKDTree(v).query(cage.vertices[np.unique(np.array(cage_boundary))])
    assert distance.max() < 1e-15
    assert set(nearest.tolist()) <= set(a[on_boundary].tolist())


def test_clustering_two_sheets_closer_than_a_cell_leaves_a_manifold():
    """A sphere flattened to a thousandth of its width (655,362 vertices): the grid's cells hold both of its
    sheets, joined only round the rim, where clusters must not make the mesh non-manifold (a cell's corner cut
    off between two clusters is joined to one, any other fold split back). The cage: the count, closed,
    oriented, of genus 0, made of input vertices."""
    v, f = sorpia.shapes.icosphere(8)
    v = v * [1.0, 1.0, 0.001]
    cage = sorpia.decimate(v, f, 2000)
    assert cage.vertices.shape == (2000, 3)
    check_oriented_manifold(cage.vertices, cage.faces, closed=True)
    assert euler_characteristic(cage.vertices, cage.faces) == 2
    assert cKDTree(v).query(cage.vertices)[0].max() < 1e-15
