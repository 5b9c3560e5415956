"""The robust fit of sorpia.approximate (issue 33, item 15): outliers and
duplicates do not move the cage far from where the rest of the data puts it,
and on clean data the robust fit is the plain one. Every comparison is with
the fit of the same cage to the clean points alone, measured on the limit
surfaces themselves (their level-2 tessellations, vertex by vertex: the same
cage's faces give the same tessellation), over the clean points' diagonal;
the plain least-squares fit (robust="none") of the same data must fail the
bound that the robust fit meets, so each test can fail."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest

import sorpia
from sorpia import shapes
from sorpia.approximate import approximate


def diagonal(p):
    return float(np.linalg.norm(p.max(0) - p.min(0)))


def noisy_torus(seed: int = 1):
    """Points of a torus (radii 1, 0.4; 48 x 24 vertices) displaced along the normal by Gaussian noise of 1e-3
    of the diagonal, and a torus cage of a quarter as many vertices (24 x 12) to fit them with, as decimation gives."""
    v, _ = shapes.torus(48, 24)
    ring = v.copy()
    ring[:, 2] = 0
    ring /= np.linalg.norm(ring, axis=1, keepdims=True)
    n = (v - ring) / np.linalg.norm(v - ring, axis=1, keepdims=True)
    rng = np.random.default_rng(seed)
    p = v + n * rng.normal(scale=1e-3 * diagonal(v), size=(len(v), 1))
    cv, cf = shapes.torus(24, 12)
    return p, cv, np.asarray(cf)


def gap(a, b, faces, diag):
    """The largest distance between two fits' limit surfaces of the same cage faces, / diag."""
    ta, _ = sorpia.limit_surface(a.control_vertices, faces, 2)
    tb, _ = sorpia.limit_surface(b.control_vertices, faces, 2)
    return float(np.linalg.norm(ta - tb, axis=1).max()) / diag


def with_outliers(p, fraction, seed):
    """`fraction` of the points moved 0.1 to 2 diagonals along random directions; (points, inlier mask)."""
    rng = np.random.default_rng(seed)
    k = max(1, round(fraction * len(p)))
    idx = rng.choice(len(p), k, replace=False)
    u = rng.normal(size=(k, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    q = p.copy()
    q[idx] += u * rng.uniform(0.1, 2.0, size=(k, 1)) * diagonal(p)
    inlier = np.ones(len(p), bool)
    inlier[idx] = False
    return q, inlier


def test_on_clean_data_the_robust_fit_is_the_plain_one():
    # Tukey's factors of points within a few times the 90th percentile of the distances are 1 to within
    # 2 (d / (c s))^2, c = 30: the robust fit of clean data moves its surface by less than 1e-4 of the diagonal
    # from the plain fit's (the noise is 1e-3) and its RMS distance is the plain one's within 0.1%.
    p, cv, cf = noisy_torus()
    diag = diagonal(p)
    plain = approximate(p, cv, cf, robust="none")
    robust = approximate(p, cv, cf)
    assert robust.robust == "tukey" and plain.robust == "none"
    assert gap(robust, plain, cf, diag) < 1e-4
    assert abs(robust.rms / plain.rms - 1) < 1e-3
    assert robust.robust_outliers == 0  # no clean point lies beyond c s
    assert plain.robust_scale == 0 and robust.robust_scale > 0


@pytest.mark.parametrize("loss", ["cauchy", "tukey"])
def test_far_outliers_do_not_move_the_surface(loss):
    # 1% of the points moved 0.1 to 2 diagonals away: the plain fit's surface goes out to them (more than 0.1 of
    # the diagonal from the fit of the other points alone), the robust fit's stays within 5e-3 of the diagonal of
    # it (the noise is 1e-3; the outliers nearest the surface pull in the first updates, while the scale of the
    # distances to the cage as given puts them within c s), its RMS distance of the inliers within 1% of that fit's, and it counts the outliers
    # beyond c s.
    p, cv, cf = noisy_torus()
    diag = diagonal(p)
    q, inlier = with_outliers(p, 0.01, 2)
    clean = approximate(p[inlier], cv, cf, robust=loss)
    plain = approximate(q, cv, cf, robust="none")
    robust = approximate(q, cv, cf, robust=loss)
    assert gap(plain, clean, cf, diag) > 0.1
    assert gap(robust, clean, cf, diag) < 5e-3
    inlier_rms = np.sqrt(np.mean(robust.distances[inlier] ** 2))
    assert inlier_rms < 1.01 * clean.rms
    assert robust.robust_outliers >= (~inlier).sum()


def test_five_points_at_fifty_radii_among_642():
    # The case: a sphere's 642 points, 5 of them moved to 50 times the radius. The plain fit's cage
    # reaches out (its extent grows tenfold and more); the robust fit's surface stays within 1e-3 of the
    # diagonal of the fit without them.
    v, _ = shapes.icosphere(3)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    cv, cf = shapes.icosphere(1)
    cf = np.asarray(cf)
    q = v.copy()
    far = np.random.default_rng(3).choice(len(v), 5, replace=False)
    q[far] *= 50.0
    keep = np.setdiff1d(np.arange(len(v)), far)
    clean = approximate(v[keep], cv, cf)
    plain = approximate(q, cv, cf, robust="none")
    robust = approximate(q, cv, cf)
    assert diagonal(plain.control_vertices) > 10 * diagonal(v)
    assert gap(robust, clean, cf, 2.0) < 1e-3
    assert robust.robust_outliers == 5


def test_duplicates_of_one_point_do_not_pull_the_surface():
    # 2% more points, all copies of one point 0.2 diagonals off the torus: least squares bulges the surface
    # towards them (more than 0.15 of the diagonal); the robust fit's surface stays within 0.02 of the diagonal of
    # the clean fit. Not closer: the first update weighs the points by the distances to the cage as given, whose
    # scale (and so cut, c s) lets the copies pull until the surface has come closer to the other points.
    p, cv, cf = noisy_torus()
    diag = diagonal(p)
    clean = approximate(p, cv, cf)
    i = 100
    off = p[i] + 0.2 * diag * (p[i] - p.mean(0)) / np.linalg.norm(p[i] - p.mean(0))
    q = np.vstack([p, np.repeat(off[None], round(0.02 * len(p)), axis=0)])
    plain = approximate(q, cv, cf, robust="none")
    robust = approximate(q, cv, cf)
    assert gap(plain, clean, cf, diag) > 0.15
    assert gap(robust, clean, cf, diag) < 0.02


def test_robust_is_checked():
    p, cv, cf = noisy_torus()
    with pytest.raises(sorpia.ParameterError, match=r"robust = 'huber' must be one of none, cauchy, tukey"):
        approximate(p, cv, cf, robust="huber")
    with pytest.raises(sorpia.ParameterError, match="robust = 1 must be one of"):
        approximate(p, cv, cf, robust=1)


def test_a_surface_that_strays_from_the_data_is_warned_about():
    # Points on a cap of a sphere (a fifth of it), a cage of the whole sphere, no fairness and the tangent
    # distance alone: nothing holds the cage away from the cap, and its surface flies off more than the
    # diagonal of the data, which a SorpiaWarning names; with the default fairness it stays, and no warning. (The
    # cage of 42 vertices: with 162, the fresh searches' re-search finds the footpoints that strayed parts of the
    # surface bring near the data, the RMS rises from there on, and the iterate returned is the start.)
    v, _ = shapes.icosphere(3)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    p = v[v[:, 2] > 0.6]
    cv, cf = shapes.icosphere(1)
    with pytest.warns(sorpia.SorpiaWarning, match=r"strays from the data: its farthest point lies [\d.]+ of the "
                                                  r"diagonal .* raise fairness \(now 0\)"):
        r = approximate(p, cv, cf, fairness=0.0, tangential=0.0, robust="none")
    assert r.history[r.best_iteration]["surface_max_relative"] > 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("error", sorpia.SorpiaWarning)
        r = approximate(p, cv, cf)
    assert r.history[r.best_iteration]["surface_max_relative"] <= 1.0


def test_the_robust_fit_over_chunks_is_the_fit_of_one_array():
    # The scale is a histogram of all the chunks' distances merged (the same counts however the points are cut)
    # and the loss's sums are added in the chunks' order: cut into chunks of 100 points, the robust fit of data
    # with outliers returns the same cage as the one-array fit to 1e-10 of the diagonal, and the same outliers.
    p, cv, cf = noisy_torus()
    q, _ = with_outliers(p, 0.01, 2)
    one = approximate(q, cv, cf)
    cut = approximate(q, cv, cf, chunk_points=100)
    assert cut.iterations == one.iterations and cut.best_iteration == one.best_iteration
    assert np.abs(cut.control_vertices - one.control_vertices).max() <= 1e-10 * diagonal(q)
    assert cut.robust_outliers == one.robust_outliers > 0
    assert abs(cut.robust_scale - one.robust_scale) <= 1e-10 * one.robust_scale


def test_command_fits_robustly_by_default_and_says_how_many_points_it_cut(tmp_path):
    # A point cloud with 1% far outliers and a cage given: `sorpia approximate` fits robustly unless --robust none,
    # its summary counts the points beyond the cut, its report says the loss, and its cage's surface stays with
    # the other points (the library's robust fit, the same cage to 1e-12 of the diagonal).
    p, cv, cf = noisy_torus()
    q, inlier = with_outliers(p, 0.01, 2)
    (tmp_path / "cloud.obj").write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in q.tolist()))
    sorpia.write_mesh(tmp_path / "start.obj", cv, cf)
    runs = {}
    for robust in ("tukey", "none"):
        args = ["cloud.obj", "-o", f"{robust}.obj", "--cage", "start.obj", "--report", f"{robust}.json"]
        args += [] if robust == "tukey" else ["--robust", robust]
        r = subprocess.run([sys.executable, "-m", "sorpia", "approximate", *args], cwd=tmp_path, capture_output=True,
                           text=True)
        assert r.returncode == 0, r.stderr
        runs[robust] = (r.stdout, json.loads((tmp_path / f"{robust}.json").read_text()))
    out, report = runs["tukey"]
    assert report["robust"] == "tukey" and report["robust_outliers"] >= (~inlier).sum()
    assert f"within the cut, {report['robust_outliers']} points beyond it" in out.split("kept")[1]
    assert runs["none"][1]["robust"] == "none" and "robust" not in runs["none"][0].split("update")[1].split("\n")[0]
    fitted = sorpia.read_mesh(tmp_path / "tukey.obj")[0]
    np.testing.assert_allclose(fitted, approximate(q, cv, cf).control_vertices, atol=1e-12 * diagonal(q))


def test_data_the_surface_reaches_is_fitted_as_least_squares_fits_it():
    # A mesh's own vertices fitted with that mesh as the cage, no fairness: least squares drives the distances to
    # rounding; the robust fit too (its scale, at least 1e-4 of the diagonal, cuts no point converging last).
    v, f = shapes.torus(24, 12)
    v = v + 0.01 * np.random.default_rng(4).standard_normal(v.shape)
    plain = approximate(v, v, f, fairness=0.0, robust="none")
    robust = approximate(v, v, f, fairness=0.0)
    assert plain.rms < 1e-9 * plain.diagonal
    assert robust.rms < 1e-9 * robust.diagonal and robust.robust_outliers == 0


def test_the_robust_defaults_seen_from_python_are_the_cores():
    # One place for the defaults (sorpia::robust_options, ApproximationOptions::robust): sorpia.approximate, the
    # binding and the command line default to the core's loss, and a loss named without its settings fits with
    # the core's: the same bits as the binding given the core's (quantile, c) explicitly.
    import inspect

    from sorpia import _core
    from sorpia.cli.parser import build_parser

    assert inspect.signature(approximate).parameters["robust"].default == _core.DEFAULT_ROBUST == "tukey"
    assert "robust: str = 'tukey'" in _core.approximate.__doc__
    args = build_parser().parse_args(["approximate", "in.ply", "-o", "out.obj", "--vertices", "50"])
    assert args.robust == _core.DEFAULT_ROBUST
    assert _core.robust_options("tukey") == ("tukey", 0.9, 30.0)  # docs/approximation.md, "Robustness"
    assert _core.robust_options("cauchy") == ("cauchy", 0.9, 12.0)
    p, cv, cf = noisy_torus()
    q, _ = with_outliers(p, 0.01, 2)
    for loss in ("tukey", "cauchy"):
        _, quantile, c = _core.robust_options(loss)
        r = approximate(q, cv, cf, robust=loss, iterations=3)
        surface = sorpia.LimitSurface(cv, cf)
        o = dict(iterations=3, tol=3e-3, fairness=3e-4, tangential=0.1, method="cg", solver_tol=1e-3,
                 solver_max_iter=2000, grid=4, newton_steps=10, report_level=2, callback=None)
        out = _core.approximate(surface._surface, _core.InMemoryChunks(surface._surface, q, None, 1 << 20),
                                *o.values(), robust=loss, robust_quantile=quantile, robust_c=c)
        np.testing.assert_array_equal(r.control_vertices, out["control_vertices"])
        other = _core.approximate(sorpia.LimitSurface(cv, cf)._surface,
                                  _core.InMemoryChunks(sorpia.LimitSurface(cv, cf)._surface, q, None, 1 << 20),
                                  *o.values(), robust=loss, robust_quantile=quantile, robust_c=2 * c)
        assert not np.array_equal(other["control_vertices"], out["control_vertices"])  # c reaches the fit


def sphere_with_far_points(count=20, factor=40.0, seed=3):
    """The level-3 icosphere's 642 points with `count` of them moved `factor` times as far out; (points, far)."""
    v, _ = shapes.icosphere(3)
    p = np.asarray(v, float)
    far = np.random.default_rng(seed).choice(len(p), count, replace=False)
    p[far] *= factor
    return p, far


@pytest.mark.parametrize("robust", ["tukey", "cauchy", "none"])
@pytest.mark.parametrize("case", ["zero on the far points", "nonzero only on the far points"])
def test_points_of_weight_zero_are_no_data(robust, case):
    # A point of weight 0 counts nowhere: the fit, and every figure of it (RMS, the largest distance, the
    # diagonal, surface -> data, the points cut), are those of the points of weight > 0 given alone (the same
    # cage to 1e-9 of the diagonal, the figures to 1e-9 relative; solved tightly, so that rounding in the sums'
    # order does not change the iterates). With every nonzero weight on the far points, those are the data: the
    # robust fit cuts none of them.
    p, far = sphere_with_far_points()
    cv, cf = shapes.icosphere(1)
    w = np.ones(len(p))
    if case == "zero on the far points":
        w[far] = 0.0
        w[np.random.default_rng(4).choice(len(p), 100, replace=False)] = 0.0
    else:
        w[:] = 0.0
        w[far] = 1.0
    kw = dict(robust=robust, solver_tol=1e-13, solver_max_iter=100000)
    got = approximate(p, cv, cf, weights=w, **kw)
    alone = approximate(p[w > 0], cv, cf, **kw)
    assert got.diagonal == pytest.approx(alone.diagonal, rel=1e-12)
    assert np.abs(got.control_vertices - alone.control_vertices).max() <= 1e-9 * alone.diagonal
    a, b = got.history[got.best_iteration], alone.history[alone.best_iteration]
    for key in ("rms", "max", "surface_rms", "surface_max", "inlier_rms"):
        assert a[key] == pytest.approx(b[key], rel=1e-9, abs=1e-12 * alone.diagonal), key
    assert got.robust_outliers == alone.robust_outliers
    if robust != "none" and case != "zero on the far points":
        assert got.robust_outliers == 0


@pytest.mark.parametrize("source", ["array", "streamed"])
@pytest.mark.parametrize("exponent", [200, 201, -210])
def test_outliers_near_2_to_the_200_are_cut_as_at_unit_scale(tmp_path, source, exponent):
    # Data beyond 2^+-200 is fitted scaled by a power of two (exact): with 20 far points among them the robust fit
    # is the unit-scale fit times 2^e, bit for bit, in memory and streamed from a file, and so are its robust
    # figures (scale, cut count, the kept points' RMS).
    p, _ = sphere_with_far_points()
    cv, cf = shapes.icosphere(1)
    cv = np.asarray(cv, float)
    unit = approximate(p, cv, cf, iterations=4)
    big = np.ldexp(p, exponent)
    if source == "streamed":
        np.save(tmp_path / "big.npy", big)
        big = str(tmp_path / "big.npy")
    got = approximate(big, np.ldexp(cv, exponent), cf, iterations=4)
    np.testing.assert_array_equal(np.ldexp(got.control_vertices, -exponent), unit.control_vertices)
    assert got.robust_outliers == unit.robust_outliers == 20
    assert np.ldexp(got.robust_scale, -exponent) == unit.robust_scale
    a, b = got.history[got.best_iteration], unit.history[unit.best_iteration]
    assert np.ldexp(a["inlier_rms"], -exponent) == b["inlier_rms"] and a["inlier_rms_relative"] == b["inlier_rms_relative"]
    assert np.isfinite([a["rms"], a["max"], a["surface_rms"], a["robust_loss"]]).all()
