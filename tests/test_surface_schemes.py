"""LimitSurface under Catmull-Clark and with sharpness tags: Bfr's evaluation
(at the parameters its documented parameterisation gives) against Far's
uniform refinement + Limit() (the tessellation), and sharp creases against
the closed form of their limit curve (a uniform cubic B-spline)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import sorpia
from sorpia.surface import corner_uv, edge_uv  # checked here: Bfr at these parameters is the corner

SCHEMES = ["loop", "catmull-clark"]


def diagonal(v):
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))


def face_list(faces):
    """Faces as a list of int lists, whatever their form."""
    if isinstance(faces, sorpia.Polygons):
        ends = np.cumsum(faces.face_vertex_counts)
        return [faces.face_vertex_indices[e - c:e].tolist() for c, e in zip(faces.face_vertex_counts, ends)]
    return np.asarray(faces).tolist()


def level_one_children(scheme, faces, tess_faces):
    """[(control face, [(u, v) of each corner])] for the quads of a level-1
    Catmull-Clark tessellation, from the documented layout alone: the quads
    of control face f come in one block after those of the faces before it,
    the quad at corner j holds f[j] and, in f's orientation, the edge point of
    edge j, the face point and the edge point of edge j - 1."""
    quads = np.asarray(tess_faces).tolist()
    out = [None] * len(quads)
    row = 0
    for fi, f in enumerate(faces):
        k = len(f)
        for j in range(k):
            r = next(r for r in range(row, row + k) if f[j] in quads[r])
            p = quads[r].index(f[j])
            c = corner_uv(scheme, k, j)
            if k == 4:
                c1, cp = corner_uv(scheme, 4, (j + 1) % 4), corner_uv(scheme, 4, (j + 3) % 4)
                edge = ((c[0] + c1[0]) / 2, (c[1] + c1[1]) / 2)
                prev = ((c[0] + cp[0]) / 2, (c[1] + cp[1]) / 2)
                centre = (0.5, 0.5)
            else:
                edge, centre, prev = (c[0] + 0.5, c[1]), (c[0] + 0.5, c[1] + 0.5), (c[0], c[1] + 0.5)
            uv = [None] * 4
            for step, point in enumerate((c, edge, centre, prev)):
                uv[(p + step) % 4] = point
            out[r] = (fi, uv)
        row += k
    assert row == len(quads)
    return out


def next_level_children(children, parent_faces, child_faces):
    """The same for the next level of an all-quad tessellation: the children
    of quad r are rows 4r..4r+3 (one block per parent, whose vertices keep
    their indices); the child at the parent's corner j holds it and the points
    of the parent's edge j, centre and edge j - 1, at the midpoints and the
    centre of the parent's corner parameters."""
    parents, quads = np.asarray(parent_faces).tolist(), np.asarray(child_faces).tolist()
    out = [None] * len(quads)
    for r, (fi, uv) in enumerate(children):
        P = [np.array(x) for x in uv]
        for j in range(4):
            rr = next(rr for rr in range(4 * r, 4 * r + 4) if parents[r][j] in quads[rr])
            p = quads[rr].index(parents[r][j])
            points = (P[j], (P[j] + P[(j + 1) % 4]) / 2, sum(P) / 4, (P[j] + P[(j + 3) % 4]) / 2)
            corner = [None] * 4
            for step, point in enumerate(points):
                corner[(p + step) % 4] = tuple(point)
            out[rr] = (fi, corner)
    return out


def vertex_parameters(children, tess_faces):
    """{vertex: (control face, u, v)} from per-quad corner parameters."""
    params = {}
    for (fi, uv), quad in zip(children, np.asarray(tess_faces).tolist()):
        for x, point in zip(quad, uv):
            params.setdefault(x, (fi, *point))
    return params


def fan_mesh(k):
    """A closed mesh with k-gons: a k-sided prism (two k-gon caps, k quads), as triangles-free polygons."""
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    ring = np.column_stack([np.cos(t), np.sin(t), np.zeros(k)])
    v = np.vstack([ring + [0, 0, -0.6], ring * 0.8 + [0, 0, 0.6]])
    faces = [list(range(k))[::-1], list(range(k, 2 * k))]
    faces += [[j, (j + 1) % k, k + (j + 1) % k, k + j] for j in range(k)]
    return v, faces


def triangle_meshes():
    return {"icosphere": sorpia.shapes.icosphere(1), "grid": sorpia.shapes.grid(5, 4),
            "irregular": sorpia.shapes.irregular(200, seed=4)}


def polygon_meshes():
    """Meshes for Catmull-Clark: triangles, quads (closed, open, irregular) and mixed polygons."""
    return {**triangle_meshes(), "quad-torus": sorpia.shapes.quad_torus(8, 6),
            "quad-grid": sorpia.shapes.quad_grid(6, 5), "quad-irregular": sorpia.shapes.quad_irregular(300, seed=2),
            "polygon-torus": sorpia.shapes.polygon_torus(10, 6, seed=3)}


@pytest.fixture(params=sorted(triangle_meshes()))
def tri_mesh(request):
    v, f = triangle_meshes()[request.param]
    return np.asarray(v, dtype=float), np.asarray(f)


@pytest.fixture(params=sorted(polygon_meshes()))
def cc_mesh(request):
    """(vertices, faces as lists) of each mesh for Catmull-Clark."""
    v, f = polygon_meshes()[request.param]
    return np.asarray(v, dtype=float), face_list(f)


# ---- Catmull-Clark ----------------------------------------------------------

@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
def test_catmull_clark_corners_are_the_limit_points_of_the_tessellation(cc_mesh, boundary):
    # Bfr at corner j of every face (the documented parameterisation) against
    # Far's Limit() on the descendants of the control vertices at levels 1 and
    # 2: two OpenSubdiv paths; 1e-12 of the diagonal allows for their rounding.
    v, f = cc_mesh
    s = sorpia.LimitSurface(v, f, boundary=boundary, scheme="catmull-clark")
    ids = np.concatenate([[i] * len(face) for i, face in enumerate(f)])
    uv = np.array([corner_uv("catmull-clark", len(face), j) for face in f for j in range(len(face))])
    corners = np.concatenate(f)
    p = s.evaluate(ids, uv)
    for level in (1, 2):
        vs, _ = s.tessellate(level)
        assert np.abs(p - vs[corners]).max() <= 1e-12 * diagonal(v)
    # Level 0: the control faces, and the same points (on a quad mesh Far's
    # Limit() there, elsewhere Bfr for the vertices of non-quads).
    vs0, fs0 = s.tessellate(0)
    assert face_list(fs0) == f
    assert np.abs(vs0 - s.tessellate(1)[0][:len(v)]).max() <= 1e-12 * diagonal(v)


def test_catmull_clark_level_one_and_two_vertices_are_bfr_at_their_parameters(cc_mesh):
    # Every vertex of the level-1 and level-2 tessellations (vertex, edge and
    # face points) against Bfr at the parameter the documented layout gives
    # it: Far's refinement + Limit() against Bfr's patches.
    v, f = cc_mesh
    s = sorpia.LimitSurface(v, f, scheme="catmull-clark")
    v1, f1 = s.tessellate(1)
    v2, f2 = s.tessellate(2)
    assert f1.shape == (sum(map(len, f)), 4) and f2.shape == (4 * len(f1), 4)
    children = level_one_children("catmull-clark", f, f1)
    for vs, fs in ((v1, f1), (v2, f2)):
        params = vertex_parameters(children, fs)
        assert sorted(params) == list(range(len(vs)))
        ids = np.array([params[i][0] for i in range(len(vs))])
        uv = np.array([params[i][1:] for i in range(len(vs))])
        assert np.abs(s.evaluate(ids, uv) - vs).max() <= 1e-12 * diagonal(v)
        if fs is f1:
            children = next_level_children(children, f1, f2)


@pytest.mark.parametrize("k", [3, 5, 6, 9, 10, 13])
def test_n_gons_give_k_quads_and_bfr_matches_at_their_parameters(k):
    # A prism with two k-gon caps: corner j of each face (the documented
    # sub-face layout) against the tessellation's control vertices, and every
    # level-1 vertex against Bfr at its parameter.
    v, f = fan_mesh(k)
    s = sorpia.LimitSurface(v, f, scheme="catmull-clark")
    vs, fs = s.tessellate(1)
    assert fs.shape == (2 * k + 4 * k, 4)
    ids = np.concatenate([[i] * len(face) for i, face in enumerate(f)])
    uv = np.array([corner_uv("catmull-clark", len(face), j) for face in f for j in range(len(face))])
    corners = np.concatenate(f)
    assert np.abs(s.evaluate(ids, uv) - vs[corners]).max() <= 1e-12 * diagonal(v)
    params = vertex_parameters(level_one_children("catmull-clark", f, fs), fs)
    assert sorted(params) == list(range(len(vs)))
    p = s.evaluate([params[i][0] for i in range(len(vs))], [params[i][1:] for i in range(len(vs))])
    assert np.abs(p - vs).max() <= 1e-12 * diagonal(v)
    # Level 0 is the control polygons, as sorpia.Polygons (sizes k and 4).
    v0, f0 = s.tessellate(0)
    assert isinstance(f0, sorpia.Polygons) and face_list(f0) == f
    assert np.abs(v0 - vs[:len(v)]).max() <= 1e-12 * diagonal(v)


@pytest.mark.parametrize("level", [1, 2, 3])
@pytest.mark.parametrize("shape, euler", [("icosphere", 2), ("quad-torus", 0), ("polygon-torus", 0)])
def test_catmull_clark_tessellation_counts_and_blocks(level, shape, euler):
    # k 4^(level-1) quads per k-gon, one block per control face holding its
    # corners; a closed quad mesh has V - E + F = V - F = Euler characteristic.
    v, f = polygon_meshes()[shape]
    f = face_list(f)
    vs, fs = sorpia.limit_surface(v, f, level, scheme="catmull-clark")
    assert fs.dtype == np.int32 and fs.shape == (sum(len(face) for face in f) * 4 ** (level - 1), 4)
    assert np.array_equal(np.unique(fs), np.arange(len(vs)))
    assert len(vs) - len(fs) == euler
    row = 0
    for face in f:
        block = fs[row:row + len(face) * 4 ** (level - 1)]
        row += len(block)
        assert sorted(set(block[block < len(v)].tolist())) == sorted(face)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_the_vertices_of_a_level_are_the_first_of_the_next(scheme):
    # Same points from Limit() on different levels: equal up to rounding.
    v, f = sorpia.shapes.irregular(150, seed=2)
    s = sorpia.LimitSurface(v, f, scheme=scheme)
    v1, _ = s.tessellate(1)
    v2, _ = s.tessellate(2)
    assert np.abs(v2[:len(v1)] - v1).max() <= 1e-12 * diagonal(v)


def test_sub_face_parameters_outside_every_sub_face_are_refused():
    v, f = sorpia.shapes.icosphere(0)
    s = sorpia.LimitSurface(v, f, scheme="catmull-clark")
    for bad in ([0.7, 0.2], [1.2, 1.2], [-0.1, 0.2], [2.0, 0.0]):
        with pytest.raises(sorpia.ParameterError, match=r"in none of the 3 sub-faces .* \(j mod 2, j div 2\)"):
            s.evaluate([0], [bad])
    # On the closed squares, and a rounding error outside them, all is well.
    ok = [[0.5, 0.5], [1.5, 0.0], [0.0, 1.5], [1.5 - 1e-13, 0.25], [-1e-13, 1.0]]
    assert np.isfinite(s.evaluate([0] * len(ok), ok)).all()


def test_limit_surface_names_its_scheme_and_the_loop_alias_is_gone():
    assert not hasattr(sorpia, "LoopSurface")
    v, f = sorpia.shapes.icosphere(0)
    assert sorpia.LimitSurface(v, f).scheme == "loop"
    assert sorpia.LimitSurface(v, f, scheme="catmull-clark").scheme == "catmull-clark"
    with pytest.raises(sorpia.ParameterError, match="scheme"):
        sorpia.LimitSurface(v, f, scheme="butterfly")


# ---- sharpness tags -----------------------------------------------------------

def folded_grid(n=9):
    """An n x n grid of triangles folded along its middle column of vertices,
    and that column as a crease polyline (its vertices bottom to top)."""
    v, f = sorpia.shapes.grid(n, n)
    v = np.asarray(v, dtype=float).copy()
    xs = np.unique(np.round(v[:, 0], 12))
    mid = xs[len(xs) // 2]
    line = np.flatnonzero(np.isclose(v[:, 0], mid))
    line = line[np.argsort(v[line, 1])]
    v[:, 2] = 0.6 * np.abs(v[:, 0] - mid)
    return v, np.asarray(f), line


@pytest.mark.parametrize("scheme", SCHEMES)
def test_an_infinitely_sharp_crease_is_the_cubic_b_spline_of_its_vertices(scheme):
    # Along a crease both schemes use the boundary curve rule: the limit curve
    # is the uniform cubic B-spline of the crease polygon. Vertex i of it lies
    # at (p[i-1] + 4 p[i] + p[i+1]) / 6 and the midpoint of the edge (i, i+1),
    # the level-1 edge point, at (p[i-1] + 23 p[i] + 23 p[i+1] + p[i+2]) / 48.
    v, f, line = folded_grid()
    edges = np.column_stack([line[:-1], line[1:]])
    s = sorpia.LimitSurface(v, f, scheme=scheme, creases=(edges, np.inf))
    vs, fs = s.tessellate(1)
    p = v[line]
    for i in range(1, len(line) - 2):
        at_vertex = (p[i - 1] + 4 * p[i] + p[i + 1]) / 6
        at_middle = (p[i - 1] + 23 * p[i] + 23 * p[i + 1] + p[i + 2]) / 48
        assert np.abs(vs[line[i]] - at_vertex).max() <= 1e-14
        # The level-1 vertex on edge (i, i+1): the one both ends share a face with, nearest their midpoint.
        tess_edges = {tuple(sorted((a, b))) for face in fs.tolist() for a, b in zip(face, face[1:] + face[:1])}
        mids = [w for w in range(len(v), len(vs))
                if tuple(sorted((line[i], w))) in tess_edges and tuple(sorted((line[i + 1], w))) in tess_edges]
        best = min(mids, key=lambda w: np.linalg.norm(vs[w] - (p[i] + p[i + 1]) / 2))
        assert np.abs(vs[best] - at_middle).max() <= 1e-14


@pytest.mark.parametrize("scheme", SCHEMES)
def test_the_normal_jumps_across_a_sharp_crease_and_not_across_a_smooth_one(scheme):
    # The two faces on either side of a crease edge, evaluated at the edge's
    # midpoint (sorpia.surface.edge_uv, from either side): the same point, with normals as far apart as the fold (about
    # 60 degrees) when the edge is sharp, equal when it is not.
    v, f, line = folded_grid()
    edges = np.column_stack([line[:-1], line[1:]])
    a, b = line[3], line[4]
    sides = [k for k in range(len(f)) if a in f[k] and b in f[k]]
    assert len(sides) == 2
    ids, uv = sides, []
    for k in sides:
        face = f[k].tolist()
        j = next(j for j in range(3) if {face[j], face[(j + 1) % 3]} == {a, b})
        uv.append(edge_uv(scheme, 3, j, [0.5])[0])  # the midpoint of edge j, on this face's side
    for sharp, check in [(np.inf, lambda angle: angle > 0.5), (0.0, lambda angle: angle < 1e-9)]:
        s = sorpia.LimitSurface(v, f, scheme=scheme, creases=(edges, sharp))
        p, _, _, n = s.evaluate(ids, np.array(uv), derivatives=True)
        assert np.abs(p[0] - p[1]).max() <= 1e-13
        assert check(math.acos(min(1.0, abs(float(n[0] @ n[1])))))


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("sharpness", [0.5, 1.0, 2.5])
def test_semi_sharp_limit_points_equal_far_on_the_level_where_the_sharpness_has_decayed(scheme, sharpness):
    # Below level ceil(s) the tessellation takes the semi-sharp vertices from
    # Bfr; on level ceil(s) every sharpness has decayed and Far's Limit() is
    # exact: the control vertices' descendants there are an independent value.
    # The semi-sharp limit lies strictly between the smooth and the sharp one.
    v, f, line = folded_grid()
    edges = np.column_stack([line[:-1], line[1:]])
    deep = math.ceil(sharpness)
    s = sorpia.LimitSurface(v, f, scheme=scheme, creases=(edges, sharpness), corners=([line[0]], sharpness / 2))
    far = s.tessellate(deep)[0][:len(v)]
    for level in range(deep):
        assert np.abs(s.tessellate(level)[0][:len(v)] - far).max() <= 1e-12 * diagonal(v)
    smooth = sorpia.LimitSurface(v, f, scheme=scheme).tessellate(1)[0][:len(v)]
    sharp = sorpia.LimitSurface(v, f, scheme=scheme, creases=(edges, np.inf)).tessellate(1)[0][:len(v)]
    z, z_smooth, z_sharp = far[line[4], 2], smooth[line[4], 2], sharp[line[4], 2]
    assert z_sharp + 1e-6 < z < z_smooth - 1e-6


@pytest.mark.parametrize("scheme", SCHEMES)
def test_holes_have_no_surface_and_no_tessellated_faces(scheme):
    v, f = sorpia.shapes.icosphere(1)
    holes = [0, 7, 30]
    s = sorpia.LimitSurface(v, f, scheme=scheme, holes=holes)
    per_face = 4 if scheme == "loop" else 3
    vs, fs = s.tessellate(1)
    assert len(fs) == per_face * (len(f) - len(holes))
    full = sorpia.LimitSurface(v, f, scheme=scheme).tessellate(1)[1]
    kept = np.ones(len(f), bool)
    kept[holes] = False
    assert np.array_equal(fs, full.reshape(len(f), per_face, -1)[kept].reshape(-1, fs.shape[1]))
    with pytest.raises(sorpia.ParameterError, match=r"face_ids\[1\] = 7 is a hole"):
        s.evaluate([1, 7], [[0.1, 0.1], [0.1, 0.1]])


def test_tagged_loop_tessellation_starts_with_limit_points():
    # The control vertices' rows are B V as sorpia.limit_points computes it
    # with the same tags (one operator, bit for bit), infinite and semi-sharp.
    v, f, line = folded_grid()
    edges = np.column_stack([line[:-1], line[1:]])
    sharpness = np.where(np.arange(len(edges)) % 2, np.inf, 1.5)
    tags = dict(creases=(edges, sharpness), corners=([line[0]], 2.0))
    for level in (0, 2):
        vs, _ = sorpia.limit_surface(v, f, level, **tags)
        assert np.array_equal(vs[:len(v)], sorpia.limit_points(v, f, **tags))


@pytest.mark.parametrize("scheme", SCHEMES)
def test_at_a_dart_evaluate_and_tessellate_give_the_limit_of_refinement(scheme):
    # An interior vertex with one infinitely sharp edge (a dart; both ends of
    # the one crease here): Sdc gives it the smooth limit mask, which is not
    # the limit of its refinement, and Bfr's own corner there is Far's Limit()
    # after its 4 local refinements. B's row is the limit (checked against Far
    # in tests/cpp/test_darts.cpp); evaluate() at every corner, the darts'
    # included, and the tessellation's control vertices at every level are
    # B V. A point just off a dart's corner is Bfr's, which starts from its
    # level-4 point: within 1% of the edge length of the limit, not at it.
    v, f = sorpia.shapes.grid(7, 7)
    v = np.asarray(v, dtype=float)
    v[:, 2] += 0.1 * np.random.default_rng(0).standard_normal(49)  # a bumpy height field
    f = np.asarray(f)
    dart = 24
    other = int(next(x for face in f if dart in face for x in face if x != dart))
    creases = ([[dart, other]], np.inf)
    s = sorpia.LimitSurface(v, f, scheme=scheme, creases=creases)
    ids = np.repeat(np.arange(len(f)), 3)
    uv = np.array([corner_uv(scheme, 3, j) for j in range(3)] * len(f))
    limit = sorpia.limit_points(v, f, scheme=scheme, creases=creases)
    assert np.abs(s.evaluate(ids, uv) - limit[f.ravel()]).max() <= 1e-14
    for level in (0, 1, 2, 3):
        assert np.abs(s.tessellate(level)[0][:len(v)] - limit).max() <= 1e-14
    at_dart = np.flatnonzero(f.ravel() == dart)
    # into the face: the triangle's corner, or the corner's quad sub-face of side 1/2
    near = uv[at_dart] + 1e-9 * ((1.0 - 3 * uv[at_dart]) if scheme == "loop" else 1.0)
    off = np.abs(s.evaluate(ids[at_dart], near) - limit[dart])
    assert 1e-7 <= off.max() <= 0.01 / 6


# ---- OpenSubdiv's shapes ----------------------------------------------------

SHARED_MESHES = Path(__file__).resolve().parents[2] / "shared" / "meshes"
# Not the non-manifold shapes (refused; the fan has edges of three faces), nor the car: it holds a
# separate cube, whose Catmull-Clark B is singular (the checkerboard vector), so no fit exists.
OSD_SHAPES = (sorted(p.name for p in SHARED_MESHES.glob("osd_*.obj")
                    if "nonman" not in p.name and p.name not in ("osd_catmark_car.obj", "osd_catmark_fan.obj"))
              if SHARED_MESHES.exists() else [])


@pytest.mark.skipif(not OSD_SHAPES, reason="../shared/meshes is not present")
@pytest.mark.parametrize("name", OSD_SHAPES or ["absent"])
def test_opensubdiv_shapes_fitted_surfaces_pass_through_their_vertices(name):
    # Fit with the file's tags and scheme, then evaluate the limit surface of
    # the control mesh by Bfr (OpenSubdiv's own evaluation, not sorpia's B) at
    # every corner of every face that is not a hole: the given vertices, to
    # 1e-9 of the diagonal (at darts too: evaluate takes their corners from B,
    # the limit of refinement there).
    v, f, tags = sorpia.read_mesh(SHARED_MESHES / name, tags=True)
    scheme = "loop" if name.startswith("osd_loop") else "catmull-clark"
    boundary = tags.pop("boundary", "edge-and-corner")
    res = sorpia.interpolate(v, f, boundary=boundary, scheme=scheme, tol=1e-14, max_iter=5000, **tags)
    assert res.converged
    s = sorpia.LimitSurface(res.control_vertices, f, boundary=boundary, scheme=scheme, **tags)
    faces = face_list(f)
    holes = set(np.asarray(tags.get("holes", [])).tolist())
    keep = [i for i in range(len(faces)) if i not in holes]
    ids = np.concatenate([[i] * len(faces[i]) for i in keep])
    uv = np.array([corner_uv(scheme, len(faces[i]), j) for i in keep for j in range(len(faces[i]))])
    corners = np.concatenate([faces[i] for i in keep])
    p = s.evaluate(ids, uv)
    assert np.abs(p - v[corners]).max() <= 1e-9 * diagonal(v)


def test_evaluation_on_threads_and_from_threads_gives_the_points_of_one_thread():
    # Each point is computed alone: a large query (split over the core's
    # threads, 64 faces a chunk), small queries of at most 64 faces (on the
    # calling thread) and four Python threads querying one surface at once
    # (the GIL released) give the same bits. Catmull-Clark with semi-sharp and
    # infinitely sharp creases, so that Bfr's cache is shared by irregular
    # patches.
    import threading

    v, f = sorpia.shapes.quad_irregular(3000, seed=5)
    f = np.asarray(f)
    edges = np.unique(np.sort(f[::7, :2], axis=1), axis=0)
    sharpness = np.where(np.arange(len(edges)) % 2, np.inf, 2.5)
    s = sorpia.LimitSurface(v, f, scheme="catmull-clark", creases=(edges, sharpness))
    rng = np.random.default_rng(4)
    ids = rng.integers(0, len(f), 20000)
    uv = rng.uniform(0, 1, (20000, 2))
    whole = s.evaluate(ids, uv, derivatives=True)
    order = np.argsort(ids, kind="stable")
    pieces = np.empty_like(whole[0])
    for chunk in np.array_split(order, 400):  # about 50 points, at most 50 faces each
        pieces[chunk] = s.evaluate(ids[chunk], uv[chunk])
    assert np.array_equal(pieces, whole[0])
    results = [None] * 4

    def query(k):
        results[k] = s.evaluate(ids, uv, derivatives=True)

    workers = [threading.Thread(target=query, args=(k,)) for k in range(4)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    for r in results:
        assert all(np.array_equal(a, b) for a, b in zip(r, whole))
