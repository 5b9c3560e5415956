"""The footpoint search's re-search (sorpia::FootpointSearch::closer, `_core.closer_footpoints`) against a brute-force
closest point: refinement from the 48 nearest of a fine grid of limit points (12 x 12 per face, evaluated by
LimitSurface.evaluate, searched by scipy's k-d tree), 200 steps at most, the least distance kept. The cases are
those where the grid's nearest sample starts some points in a local minimum of their distance (issue 33, item 6)."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import sorpia
from sorpia import _core
from sorpia.surface import LimitSurface, subface_columns


def fine_grid(s: LimitSurface, faces, m: int = 12, holes=()):
    """(face_ids, uv, points): m x m cell-centred parameters in each face's domain (each chart of a Catmull-Clark
    k-gon) but the holes', and their limit points."""
    t = (np.arange(m) + 0.5) / m
    a, b = (x.ravel() for x in np.meshgrid(t, t))
    sizes = np.asarray(faces.face_vertex_counts) if hasattr(faces, "face_vertex_counts") else \
        np.full(s.n_faces, np.asarray(faces).shape[1])
    fids, uvs = [], []
    for f in np.setdiff1d(np.arange(s.n_faces), holes):
        if s.scheme == "loop":
            keep = a + b < 1
            charts = [np.c_[a[keep], b[keep]]]
        elif sizes[f] == 4:
            charts = [np.c_[a, b]]
        else:
            w = subface_columns(sizes[f])
            charts = [np.c_[j % w + 0.5 * a, j // w + 0.5 * b] for j in range(sizes[f])]
        for uv in charts:
            fids.append(np.full(len(uv), f, np.int32))
            uvs.append(uv)
    fid, uv = np.concatenate(fids), np.concatenate(uvs)
    return fid, uv, s.evaluate(fid, uv)


def brute_force(s: LimitSurface, faces, P, starts: int = 48, holes=()):
    fid, uv, X = fine_grid(s, faces, holes=holes)
    _, idx = cKDTree(X).query(P, k=starts)
    out = _core.refine_footpoints(s._surface, s._topology, np.repeat(P, starts, axis=0), fid[idx.ravel()],
                                  uv[idx.ravel()], 200)
    return out[3].reshape(len(P), starts).min(axis=1)


def bumpy_sphere():
    V, F = sorpia.shapes.icosphere(4)
    r = 1 + 0.25 * np.sin(6 * V[:, 0]) * np.sin(6 * V[:, 1]) * np.sin(6 * V[:, 2])
    return np.ascontiguousarray(V * r[:, None]), F


def fitted(case):
    """A fitted surface and its data: the cases of issue 33 item 6 on a bumpy sphere (2562 points)."""
    P, F = bumpy_sphere()
    if case == "catmull-clark-100":  # test_approximate's test_reported_distances_are_true_distances
        cage = sorpia.decimate(P, F, 100, scheme="catmull-clark", strict=False)
        res = sorpia.approximate(P, cage.vertices, cage.faces, scheme="catmull-clark", iterations=3)
        return LimitSurface(res.control_vertices, cage.faces, scheme="catmull-clark"), cage.faces, P
    # A Loop cage of 300 vertices started collapsed to a point (1e-3 of its size) and fitted for 10 iterations.
    cage = sorpia.decimate(P, F, 300, scheme="loop", strict=False)
    centre = cage.vertices.mean(axis=0)
    res = sorpia.approximate(P, centre + 1e-3 * (cage.vertices - centre), cage.faces, scheme="loop", iterations=10)
    return LimitSurface(res.control_vertices, cage.faces, scheme="loop"), cage.faces, P


@pytest.mark.parametrize("case, stuck", [("catmull-clark-100", 3), ("collapsed-loop-300", 100)])
def test_closer_footpoints_are_the_brute_force_closest_points(case, stuck):
    # The grid's nearest sample (closest_points, as approximate searches) leaves points in local minima, at least
    # `stuck` of them by more than 1e-9 of the diagonal; after the re-search with the default FootpointOptions no
    # point is farther than the brute-force minimum by more than 1e-9 of the diagonal (the collapsed start's folds
    # included, and the corners of irregular faces, where Bfr's derivatives are approximate), none farther than
    # before, and the footpoints are their (face, u, v)'s limit points.
    s, faces, P = fitted(case)
    diagonal = np.linalg.norm(P.max(axis=0) - P.min(axis=0))
    fid, uv, _, before, _ = _core.closest_points(s._surface, s._topology, P, 4, 10)
    (fid2, uv2, pos, after, nrm), moved, certified = _core.closer_footpoints(s._surface, s._topology, P, fid, uv, 4, 10, 8)
    least = brute_force(s, faces, P)
    assert np.sum(before > least + 1e-9 * diagonal) >= stuck
    assert np.all(after <= before)
    assert np.all(after <= least + 1e-9 * diagonal), np.max(after - least) / diagonal
    assert moved >= np.sum(before > least + 1e-9 * diagonal)
    assert certified < len(P)  # (the collapsed start's folds and the coarse cage refuse most points)
    np.testing.assert_allclose(s.evaluate(fid2, uv2), pos, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(P - pos, axis=1), after, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(nrm, axis=1), 1.0, atol=1e-12)
    # near = 0.1 re-searches only the points farther than a tenth of their nearest sample's reach: never farther
    # than before or than the exhaustive search's result by more than rounding.
    (_, _, _, cheap, _), _, _ = _core.closer_footpoints(s._surface, s._topology, P, fid, uv, 4, 10, 8, near=0.1)
    assert np.all(cheap <= before) and np.all(cheap >= after - 1e-12 * diagonal)


def test_closer_footpoints_keep_closest_points_and_refuse_bad_faces():
    # Points on the surface are their own closest points: the re-search leaves them there (distance below 1e-9).
    V, F = sorpia.shapes.icosphere(2)
    s = LimitSurface(V * (1 + 0.2 * np.sin(5 * V[:, :1])), F)
    rng = np.random.default_rng(3)
    fid = rng.integers(0, s.n_faces, 500).astype(np.int32)
    uv = rng.random((500, 2)) * 0.5
    P = s.evaluate(fid, uv)
    (_, _, _, d, _), _, _ = _core.closer_footpoints(s._surface, s._topology, P, fid, uv, 4, 10, 8)
    assert d.max() < 1e-9
    bad = fid.copy()
    bad[7] = s.n_faces
    with pytest.raises(sorpia.ParameterError, match=f"face_ids\\[7\\] = {s.n_faces} is out of range"):
        _core.closer_footpoints(s._surface, s._topology, P, bad, uv, 4, 10, 8)


def noisy_torus():
    """20000 points of a torus with Gaussian noise of 2e-3 of the diagonal, fitted by a 40 x 20 Loop cage with little
    fairness, so that the surface follows the noise (folds finer than a face, its curvature varying across a face)."""
    V, F = sorpia.shapes.torus(200, 100)
    P = np.asarray(V, float)
    diagonal = np.linalg.norm(P.max(axis=0) - P.min(axis=0))
    P = P + np.random.default_rng(1).normal(0.0, 2e-3 * diagonal, P.shape)
    CV, CF = sorpia.shapes.torus(40, 20)
    res = sorpia.approximate(P, CV, CF, scheme="loop", iterations=5, fairness=1e-5)
    return LimitSurface(res.control_vertices, CF, scheme="loop"), CF, P


def smooth_fit(scheme):
    """A clean fit: 40962 points of a smooth bumpy sphere and a cage of 2000 vertices decimated from them."""
    V, F = sorpia.shapes.icosphere(6)
    P = np.ascontiguousarray(V * (1 + 0.1 * np.sin(3 * V[:, 0]) * np.sin(3 * V[:, 1]))[:, None])
    cage = sorpia.decimate(P, F, 2000, scheme=scheme, strict=False)
    res = sorpia.approximate(P, cage.vertices, cage.faces, scheme=scheme, iterations=5)
    return LimitSurface(res.control_vertices, cage.faces, scheme=scheme), cage.faces, P


@pytest.mark.parametrize("case", ["clean-loop", "clean-catmull-clark", "noisy-torus"])
def test_closer_certificate_leaves_no_point_farther_than_every_start(case):
    # The certificate (FootpointOptions.certify, on by default) leaves out the starts in the star of a footpoint's
    # face where it shows that none can hold a closer point: no point ends farther than with every start
    # (certify=False, the exhaustive rule) by more than 1e-12 of the diagonal, or than the brute force (on every
    # tenth point) by more than 1e-9 of it. On a clean fit it certifies more than 90% of the points (Catmull-Clark: quads and the charts of
    # n-gons); on the noisy fit, whose surface follows the noise, between 20% and 95% (mixed: it refuses where the
    # curvature bound times the distance or the cone of normals is too large).
    s, faces, P = noisy_torus() if case == "noisy-torus" else smooth_fit(case.removeprefix("clean-"))
    diagonal = np.linalg.norm(P.max(axis=0) - P.min(axis=0))
    fid, uv, _, before, _ = _core.closest_points(s._surface, s._topology, P, 4, 10)
    (_, _, _, certified_d, _), _, certified = _core.closer_footpoints(s._surface, s._topology, P, fid, uv, 4, 10, 8)
    (_, _, _, every, _), _, none = _core.closer_footpoints(s._surface, s._topology, P, fid, uv, 4, 10, 8,
                                                           certify=False)
    assert none == 0
    low, high = (0.2, 0.95) if case == "noisy-torus" else (0.9, 1.0)
    assert low * len(P) < certified <= high * len(P), certified / len(P)
    assert np.all(certified_d <= every + 1e-12 * diagonal), np.max(certified_d - every) / diagonal
    assert np.all(certified_d <= before)
    least = brute_force(s, faces, P[::10])
    assert np.all(certified_d[::10] <= least + 1e-9 * diagonal), np.max(certified_d[::10] - least) / diagonal


def test_closer_certificate_refused_near_creases():
    # A torus cage whose inner equator is an infinitely sharp crease (concave seen from inside the tube) and points
    # on both sides of the surface, up to 0.05 off it: no point whose footpoint's face has a crease vertex in its star
    # (the faces sharing a vertex with it) is certified, some points away from the crease are, and no point ends
    # farther than with every start (certify=False) by more than 1e-12 of the diagonal. (Both miss the brute force's
    # closest point by up to 3e-6 of the diagonal at the crease, where the distance has a kink.)
    V, F = sorpia.shapes.torus(24, 12)
    V, F = np.asarray(V, float), np.asarray(F)
    radial = np.hypot(V[:, 0], V[:, 1])
    inner = np.flatnonzero(radial < radial.min() + 1e-9)
    ring = {tuple(sorted((a, b))) for f in F for a, b in zip(f, np.roll(f, -1)) if a in inner and b in inner}
    edges = np.array(sorted(ring), np.int32)
    s = LimitSurface(V, F, scheme="loop", creases=(edges, np.full(len(edges), 10.0)))
    rng = np.random.default_rng(5)
    fid = rng.integers(0, s.n_faces, 6000).astype(np.int32)
    uv = rng.random((6000, 2))
    uv[uv.sum(axis=1) > 1] = 1 - uv[uv.sum(axis=1) > 1]
    X = s.evaluate(fid, uv)
    n = np.cross(X - np.roll(X, 1, axis=0), X - np.roll(X, 2, axis=0))  # any direction, both sides
    P = np.ascontiguousarray(X + 0.05 * rng.uniform(-1, 1, (6000, 1)) * n / np.linalg.norm(n, axis=1)[:, None])
    diagonal = np.linalg.norm(P.max(axis=0) - P.min(axis=0))
    f0, uv0, _, _, _ = _core.closest_points(s._surface, s._topology, P, 4, 10)
    # The faces whose star touches a crease vertex.
    at_crease = np.isin(F, inner).any(axis=1)
    near = np.isin(F, np.unique(F[at_crease])).any(axis=1)
    crease_side = near[f0]
    assert 0 < crease_side.sum() < len(P)
    (_, _, _, d_near, _), _, certified_near = _core.closer_footpoints(
        s._surface, s._topology, np.ascontiguousarray(P[crease_side]), f0[crease_side], uv0[crease_side], 4, 10, 8)
    assert certified_near == 0
    (_, _, _, d, _), _, certified = _core.closer_footpoints(s._surface, s._topology, P, f0, uv0, 4, 10, 8)
    assert certified > 0
    (_, _, _, every, _), _, _ = _core.closer_footpoints(s._surface, s._topology, P, f0, uv0, 4, 10, 8, certify=False)
    assert np.all(d <= every + 1e-12 * diagonal), np.max(d - every) / diagonal
    np.testing.assert_array_equal(d[crease_side], d_near)
    np.testing.assert_array_equal(d[crease_side], every[crease_side])


def stars_touching(F, vertices):
    """Per face of F: whether its star (the faces sharing a vertex with it) has a vertex among `vertices`."""
    at = np.isin(F, vertices).any(axis=1)
    return np.isin(F, np.unique(F[at])).any(axis=1)


def off_surface(s: LimitSurface, faces, n: int, offset: float, seed: int):
    """n points at random (face, u, v) of the faces given, moved along the normal by up to `offset` either way and
    by Gaussian noise of a third of it."""
    rng = np.random.default_rng(seed)
    fid = rng.choice(np.asarray(faces), n).astype(np.int32)
    uv = rng.random((n, 2))
    uv[uv.sum(axis=1) > 1] = 1 - uv[uv.sum(axis=1) > 1]
    X, _, _, N = s.evaluate(fid, uv, derivatives=True)
    return np.ascontiguousarray(X + offset * rng.uniform(-1, 1, (n, 1)) * N + offset / 3 * rng.normal(size=(n, 3)))


@pytest.mark.parametrize("case", ["grid-edge-and-corner", "grid-edge-only", "holes"])
def test_closer_certificate_at_boundaries_and_holes(case):
    # Where the surface ends (the boundary of an open Loop patch, with its one-face corners: valence-2 vertices, kept
    # sharp by "edge-and-corner"; the edges of hole faces of a closed one) the certificate still holds where those
    # curves lie farther than 4 d from the footpoint: some points whose star touches them are certified, and no
    # point ends farther than with every start (certify=False) by more than 1e-12 of the diagonal, or than the
    # brute force by more than 1e-9 of it where the exhaustive search's footpoint is inside the surface (x - p along
    # the normal; both stop short of the brute force on the boundary curve itself, up to 4e-3 of the diagonal).
    if case == "holes":
        V, F = sorpia.shapes.icosphere(2)
        V = np.asarray(V, float) * (1 + 0.1 * np.sin(4 * np.asarray(V, float)[:, :1]))
        holes = np.arange(0, len(F), 17, dtype=np.int32)
        s = LimitSurface(V, F, scheme="loop", holes=holes)
        ends = np.unique(np.asarray(F)[holes])
    else:
        V, F = sorpia.shapes.grid(12, 12)
        V, holes = np.asarray(V, float), np.zeros(0, np.int32)
        s = LimitSurface(V, F, scheme="loop", boundary=case.removeprefix("grid-"))
        edges = np.sort(np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
        unique, count = np.unique(edges, axis=0, return_counts=True)
        ends = np.unique(unique[count == 1])
    F = np.asarray(F)
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    P = off_surface(s, np.setdiff1d(np.arange(len(F)), holes), 4000, 0.03 * diagonal, 2)
    fid, uv, _, before, _ = _core.closest_points(s._surface, s._topology, P, 4, 10)
    (_, _, _, certified_d, _), _, certified = _core.closer_footpoints(s._surface, s._topology, P, fid, uv, 4, 10, 8)
    (_, _, pos, every, nrm), _, _ = _core.closer_footpoints(s._surface, s._topology, P, fid, uv, 4, 10, 8,
                                                            certify=False)
    assert np.all(certified_d <= every + 1e-12 * diagonal), np.max(certified_d - every) / diagonal
    assert np.all(certified_d <= before)
    touching = stars_touching(F, ends)[fid]
    assert 0 < touching.sum() < len(P)
    (_, _, _, touching_d, _), _, certified_touching = _core.closer_footpoints(
        s._surface, s._topology, np.ascontiguousarray(P[touching]), fid[touching], uv[touching], 4, 10, 8)
    assert certified_touching > 0.05 * touching.sum(), certified_touching / touching.sum()
    np.testing.assert_array_equal(touching_d, certified_d[touching])
    inside = np.abs(np.sum((P - pos) * nrm, axis=1)) > (1 - 1e-9) * every
    least = brute_force(s, F, P, holes=holes)
    assert inside.sum() > 0.9 * len(P)
    assert np.all(certified_d[inside] <= least[inside] + 1e-9 * diagonal), \
        np.max(certified_d[inside] - least[inside]) / diagonal


def test_closer_certificate_on_strongly_curved_stars():
    # A Loop cage of 42 vertices on a bumpy sphere: the normals of each face's star span more than 90 degrees; the
    # certificate tests only the faces of the star within 4 d of the footpoint (joined to its face across their
    # edges) and certifies most points within 2% of the radius of the surface. None ends farther than with every start by more than 1e-12 of the diagonal or
    # than the brute force by more than 1e-9 of it.
    V, F = sorpia.shapes.icosphere(1)
    V, F = np.asarray(V, float), np.asarray(F)
    s = LimitSurface(V * (1 + 0.15 * np.sin(3 * V[:, :1])), F, scheme="loop")
    rng = np.random.default_rng(4)
    fid = rng.integers(0, s.n_faces, 4000).astype(np.int32)
    uv = rng.random((4000, 2))
    uv[uv.sum(axis=1) > 1] = 1 - uv[uv.sum(axis=1) > 1]
    X, _, _, N = s.evaluate(fid, uv, derivatives=True)
    # Each star's spread: the largest angle between its faces' limit normals at 15 points of each.
    t = np.array([(a, b) for a in np.linspace(0, 1, 5) for b in np.linspace(0, 1, 5) if a + b <= 1])
    _, _, _, normals = s.evaluate(np.repeat(np.arange(len(F), dtype=np.int32), len(t)), np.tile(t, (len(F), 1)),
                                  derivatives=True)
    normals = normals.reshape(len(F), len(t), 3)
    stars = [normals[np.isin(F, F[f]).any(axis=1)].reshape(-1, 3) for f in range(len(F))]
    assert min(np.degrees(np.arccos(np.clip(n @ n.T, -1, 1).min())) for n in stars) > 90
    P = np.ascontiguousarray(X * (1 + 0.02 * rng.uniform(-1, 1, (4000, 1))))
    diagonal = np.linalg.norm(P.max(axis=0) - P.min(axis=0))
    f0, uv0, _, before, _ = _core.closest_points(s._surface, s._topology, P, 4, 10)
    (_, _, _, d, _), _, certified = _core.closer_footpoints(s._surface, s._topology, P, f0, uv0, 4, 10, 8)
    (_, _, _, every, _), _, _ = _core.closer_footpoints(s._surface, s._topology, P, f0, uv0, 4, 10, 8, certify=False)
    assert certified > 0.5 * len(P), certified / len(P)
    assert np.all(d <= every + 1e-12 * diagonal), np.max(d - every) / diagonal
    assert np.all(d <= before)
    least = brute_force(s, F, P)
    assert np.all(d <= least + 1e-9 * diagonal), np.max(d - least) / diagonal
