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


def fine_grid(s: LimitSurface, faces, m: int = 12):
    """(face_ids, uv, points): m x m cell-centred parameters in each face's domain (each chart of a Catmull-Clark
    k-gon), and their limit points."""
    t = (np.arange(m) + 0.5) / m
    a, b = (x.ravel() for x in np.meshgrid(t, t))
    sizes = np.asarray(faces.face_vertex_counts) if hasattr(faces, "face_vertex_counts") else \
        np.full(s.n_faces, np.asarray(faces).shape[1])
    fids, uvs = [], []
    for f in range(s.n_faces):
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


def brute_force(s: LimitSurface, faces, P, starts: int = 48):
    fid, uv, X = fine_grid(s, faces)
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
    # (certify=False, the exhaustive rule) or than the brute force (on every tenth point) by more than 1e-9 of the
    # diagonal. On a clean fit it certifies more than 90% of the points (Catmull-Clark: quads and the charts of
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
    assert np.all(certified_d <= every + 1e-9 * diagonal), np.max(certified_d - every) / diagonal
    assert np.all(certified_d <= before)
    least = brute_force(s, faces, P[::10])
    assert np.all(certified_d[::10] <= least + 1e-9 * diagonal), np.max(certified_d[::10] - least) / diagonal


def test_closer_certificate_refused_near_creases():
    # A torus cage whose inner equator is an infinitely sharp crease (concave seen from inside the tube) and points
    # on both sides of the surface, up to 0.05 off it: no point whose footpoint's face has a crease vertex in its star
    # (the faces sharing a vertex with it) is certified, some points away from the crease are, and no point ends
    # farther than with every start (certify=False) by more than 1e-9 of the diagonal. (Both miss the brute force's
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
    assert np.all(d <= every + 1e-9 * diagonal), np.max(d - every) / diagonal
    np.testing.assert_array_equal(d[crease_side], d_near)
    np.testing.assert_array_equal(d[crease_side], every[crease_side])
