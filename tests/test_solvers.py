"""sorpia.interpolate and sorpia.Interpolator: every method against an
independent scipy direct solve of the same B, the stopping rule, the omega
rules, callbacks, warnings and parameter checks."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sorpia
from conftest import direct_solve
from sorpia.solve import METHODS, YOUNG_RHO_CLAMP

TOL = 1e-10


@pytest.mark.parametrize("method", METHODS)
def test_every_method_equals_direct_solve(mesh, method):
    name, v, f = mesh
    res = sorpia.interpolate(v, f, method=method, tol=TOL)
    assert res.converged and res.stop_reason == "converged", (name, res.stop_reason, res.history[-5:])
    assert res.method == method
    assert res.control_vertices.shape == v.shape and res.control_vertices.dtype == np.float64
    # errors[k] = E_k / E_0: starts at 1, ends below tol, one entry per iteration.
    assert len(res.history) == res.iterations + 1
    assert res.history[0] == 1.0 and res.history[-1] < TOL
    assert np.all(np.isfinite(res.history)) and np.all(res.history[:-1] >= TOL)
    ref = direct_solve(f, v)
    # E_k/E_0 < 1e-10 and cond(B) <= about 5 (spectrum in [0.2, 1]) bound the
    # relative error of V by about 5e-10 E_0/|V|, well inside 1e-8.
    rel = np.abs(res.control_vertices - ref).max() / np.abs(ref).max()
    assert rel < 1e-8, (name, method, rel)


@pytest.mark.parametrize("method", ["sor", "cg", "hss"])
def test_edge_only_boundary_rule(method):
    v, f = sorpia.shapes.grid(8, 6)
    res = sorpia.interpolate(v, f, method=method, boundary="edge-only")
    ref = direct_solve(f, v, "edge-only")
    assert res.converged
    assert np.abs(res.control_vertices - ref).max() / np.abs(ref).max() < 1e-8


def test_result_interpolates_through_opensubdiv():
    # Independent of scipy: OpenSubdiv's own limit of the control vertices.
    v, f = sorpia.shapes.irregular(400, seed=5)
    res = sorpia.interpolate(v, f)
    limit = sorpia.limit_points(res.control_vertices, f)
    e0 = res.initial_error
    assert np.linalg.norm(limit - v, axis=1).max() < TOL * e0 * 1.0000001


def test_errors_are_the_papers_relative_errors():
    # errors[k] recomputed from scratch: run k iterations and measure E_k / E_0.
    v, f = sorpia.shapes.icosphere(2)
    full = sorpia.interpolate(v, f, method="pia")
    e0 = np.linalg.norm(v - sorpia.limit_points(v, f), axis=1).max()
    assert full.initial_error == pytest.approx(e0, rel=1e-12)
    for k in (1, 5, 20):
        with pytest.warns(sorpia.ConvergenceWarning):
            part = sorpia.interpolate(v, f, method="pia", max_iter=k)
        ek = np.linalg.norm(v - sorpia.limit_points(part.control_vertices, f), axis=1).max()
        # the same arithmetic up to OpenSubdiv's order of summation
        assert ek / e0 == pytest.approx(full.history[k], rel=1e-9)


def test_callback_watches_and_stops():
    v, f = sorpia.shapes.icosphere(2)
    seen = []

    def watch(k, error):
        seen.append((k, error))
        return k == 3

    res = sorpia.interpolate(v, f, method="pia", callback=watch)
    assert res.iterations == 3 and not res.converged and res.stop_reason == "callback"
    assert [k for k, _ in seen] == [0, 1, 2, 3]
    np.testing.assert_array_equal([e for _, e in seen], res.history)


def test_callback_errors_propagate():
    v, f = sorpia.shapes.icosphere(1)

    def boom(k, error):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        sorpia.interpolate(v, f, callback=boom)


def test_max_iter_warns_and_keeps_finite_result():
    v, f = sorpia.shapes.icosphere(2)
    with pytest.warns(sorpia.ConvergenceWarning, match="max_iter = 2"):
        res = sorpia.interpolate(v, f, method="pia", max_iter=2)
    assert not res.converged and res.stop_reason == "max_iter" and res.iterations == 2
    assert np.all(np.isfinite(res.control_vertices))


def test_young_warns_and_clamps_when_rho_at_least_one():
    # The icosphere has valence-5 vertices (alpha_5 < 1/2), so D^-1 B has an
    # eigenvalue above 2 and rho(I - D^-1 B) > 1.
    v, f = sorpia.shapes.icosphere(2)
    with pytest.warns(sorpia.OmegaWarning, match="rho"):
        res = sorpia.interpolate(v, f, method="sor", omega="young", max_iter=3000)
    assert res.rho >= 1.0
    assert res.omega == pytest.approx(2.0 / (1.0 + math.sqrt(1.0 - YOUNG_RHO_CLAMP**2)), rel=1e-12)
    # The clamped omega (1.972) is slow, but it converges and stays finite.
    assert res.converged and np.all(np.isfinite(res.control_vertices))
    assert res.iterations > 10 * sorpia.interpolate(v, f, method="gs").iterations


def test_young_rho_against_dense_eigenvalues():
    # On the regular grid with boundary rho < 1: no warning, Young's formula as written.
    v, f = sorpia.shapes.grid(7, 6)
    b = sorpia.limit_matrix(f, len(v)).toarray()
    jac = np.eye(len(v)) - b / np.diag(b)[:, None]
    rho = np.abs(np.linalg.eigvals(jac)).max()
    res = sorpia.interpolate(v, f, omega="young")
    # The power method approaches rho from below; 1e-3 is what its stopping rule guarantees here.
    assert res.rho == pytest.approx(rho, abs=1e-3) and res.rho < 1.0
    assert res.omega == pytest.approx(2.0 / (1.0 + math.sqrt(1.0 - res.rho**2)), rel=1e-12)


def test_wpia_sigma_from_dense_lambda_min():
    v, f = sorpia.shapes.irregular(200, seed=3)
    b = sorpia.limit_matrix(f, len(v)).toarray()
    lam = np.linalg.eigvals(b).real
    assert lam.max() == pytest.approx(1.0, abs=1e-12)  # rows of B sum to 1
    res = sorpia.interpolate(v, f, method="wpia")
    assert res.lambda_min == pytest.approx(lam.min(), abs=2e-3)
    assert res.sigma == pytest.approx(2.0 / (res.lambda_min + 1.0), rel=1e-12)


def test_hss_alpha_from_dense_hermitian_part():
    v, f = sorpia.shapes.grid(7, 6)
    b = sorpia.limit_matrix(f, len(v)).toarray()
    h = np.linalg.eigvalsh((b + b.T) / 2)
    res = sorpia.interpolate(v, f, method="hss")
    assert res.alpha == pytest.approx(math.sqrt(h.min() * h.max()), rel=5e-3)


def test_cg_variant_by_symmetry():
    v, f = sorpia.shapes.icosphere(1)
    assert sorpia.interpolate(v, f, method="cg").variant == "cg"
    v, f = sorpia.shapes.grid(5, 5)
    assert sorpia.interpolate(v, f, method="cg").variant == "bicgstab"


GENERATED = {
    "icosphere-1": lambda: sorpia.shapes.icosphere(1),
    "icosphere-3": lambda: sorpia.shapes.icosphere(3),
    "torus": lambda: sorpia.shapes.torus(12, 9),
    "grid": lambda: sorpia.shapes.grid(12, 10),
    "pole-5": lambda: sorpia.shapes.pole(5),
    "pole-64": lambda: sorpia.shapes.pole(64),
    "irregular-1": lambda: sorpia.shapes.irregular(600, seed=1),
    "irregular-7": lambda: sorpia.shapes.irregular(300, seed=7),
}


@pytest.mark.parametrize("name", sorted(GENERATED))
def test_auto_omega_never_worse_than_gauss_seidel(name):
    v, f = GENERATED[name]()
    solver = sorpia.Interpolator(f, len(v))
    auto = solver.solve(v)
    gs = solver.solve(v, method="gs")
    assert auto.converged and auto.iterations <= gs.iterations


def test_interpolator_reuses_estimates():
    v, f = sorpia.shapes.icosphere(3)
    solver = sorpia.Interpolator(f, len(v))
    first = solver.solve(v, method="wpia")
    second = solver.solve(v * 2.0, method="wpia")
    assert first.timings["estimate"] > 0.0 and second.timings["estimate"] == 0.0
    # B is linear: twice the data, twice the control vertices.
    np.testing.assert_allclose(second.control_vertices, 2.0 * first.control_vertices, rtol=0, atol=1e-12)
    b = sorpia.limit_matrix(f, len(v))
    assert abs(solver.limit_matrix() - b).max() == 0.0


def test_result_arrays_outlive_the_solver_and_are_plain_numpy():
    # The core hands its result vectors to numpy without a copy (a capsule
    # owns them): they must stay valid and writable after the Interpolator
    # and the result are gone, and hold the solution (checked by B V = V0).
    import gc

    v, f = sorpia.shapes.icosphere(3)
    solver = sorpia.Interpolator(f, len(v))
    res = solver.solve(v)
    cv, errors = res.control_vertices, res.history
    del solver, res
    gc.collect()
    assert cv.shape == v.shape and cv.dtype == np.float64 and cv.flags.c_contiguous and cv.flags.writeable
    assert errors.ndim == 1 and errors[0] == 1.0
    b = sorpia.limit_matrix(f, len(v))
    assert np.abs(b @ cv - v).max() < 1e-9 * np.abs(v).max()
    cv += 1.0  # writable storage of its own
    np.testing.assert_allclose(b @ (cv - 1.0), v, rtol=0, atol=1e-9)


def test_unreferenced_vertex_passes_through():
    v, f = sorpia.shapes.icosphere(1)
    v = np.vstack([v, [[5.0, 6.0, 7.0]]])
    with pytest.warns(sorpia.UnreferencedVerticesWarning):
        res = sorpia.interpolate(v, f)
    np.testing.assert_array_equal(res.control_vertices[-1], [5.0, 6.0, 7.0])


def test_nothing_to_do_when_the_mesh_is_its_own_limit():
    # One triangle under "edge-and-corner": three one-face corners, B = I, E_0 = 0.
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]])
    res = sorpia.interpolate(v, [[0, 1, 2]], method="cg")
    assert res.converged and res.iterations == 0 and res.initial_error == 0.0
    np.testing.assert_array_equal(res.history, [0.0])
    np.testing.assert_array_equal(res.control_vertices, v)


def test_timings_and_products():
    v, f = sorpia.shapes.icosphere(2)
    res = sorpia.interpolate(v, f, method="hss")
    assert set(res.timings) == {"topology", "operator", "estimate", "solve", "total"}
    assert res.timings["total"] == res.seconds >= sum(v for k, v in res.timings.items() if k != "total") * 0.99
    assert res.products > res.iterations  # inner solves count


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"method": "jacobi"}, "unknown method 'jacobi'"),
        ({"omega": 2.0}, r"omega = 2.0 is outside \(0, 2\)"),
        ({"omega": 0.0}, r"omega = 0.0 is outside"),
        ({"omega": float("nan")}, "omega = nan"),
        ({"omega": "fast"}, "omega = 'fast'"),
        ({"omega": True}, "omega must be a real number"),
        ({"method": "pia", "omega": 1.5}, "applies to method='sor' or 'auto' only"),
        ({"tol": 0.0}, "tol = 0.0 must be"),
        ({"tol": float("nan")}, "tol = nan"),
        ({"tol": -1e-3}, "tol = -0.001"),
        ({"max_iter": 0}, "max_iter = 0"),
        ({"max_iter": 2.5}, "max_iter = 2.5"),
        ({"callback": 3}, "callback = 3"),
        ({"method": "gs", "sigma": 1.2}, "sigma = 1.2 applies to method='wpia'"),
        ({"method": "wpia", "sigma": 2.5}, r"sigma = 2.5 is outside \(0, 2\)"),
        ({"method": "hss", "alpha": -1.0}, "alpha = -1.0 must be"),
        ({"method": "hss", "weight": 1.1}, "weight = 1.1 applies to method='whss'"),
        ({"boundary": "none"}, "unknown boundary 'none'"),
        # the remaining edges: infinities, numpy scalars, strings, None, wrong case, too large
        ({"omega": float("inf")}, r"omega = inf is outside \(0, 2\)"),
        ({"omega": -0.5}, r"omega = -0.5 is outside \(0, 2\)"),
        ({"omega": np.float64(2.0)}, r"omega = .*2\.0.* is outside \(0, 2\)"),
        ({"tol": float("inf")}, r"tol = inf must be a positive finite number"),
        ({"tol": "1e-10"}, r"tol must be a real number, got '1e-10'"),
        ({"max_iter": np.int64(0)}, r"max_iter = (np\.int64\()?0\)? must be an integer >= 1"),
        ({"max_iter": -5}, r"max_iter = -5 must be an integer >= 1"),
        ({"max_iter": 10**12}, r"max_iter = 1000000000000 is too large"),
        ({"method": "SOR"}, r"unknown method 'SOR': use one of 'auto', 'pia'"),
        ({"method": None}, r"method must be a string, got None"),
        ({"boundary": "Edge-Only"}, r"unknown boundary 'Edge-Only': use one of 'edge-and-corner', 'edge-only'"),
        ({"boundary": None}, r"boundary must be a string, got None"),
    ],
)
def test_bad_parameters(kwargs, match):
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(sorpia.ParameterError, match=match):
        sorpia.interpolate(v, f, **kwargs)


def test_wrong_vertex_count_for_interpolator():
    v, f = sorpia.shapes.icosphere(1)
    solver = sorpia.Interpolator(f, len(v))
    with pytest.raises(sorpia.ParameterError, match="vertices has 41 rows but the mesh has 42"):
        solver.solve(v[:-1])


@pytest.mark.parametrize("method", ["sor", "gs", "cg", "hss"])
@pytest.mark.parametrize("exponent", [700, -700])
def test_huge_and_tiny_coordinates_scale_exactly(method, exponent):
    # B is linear and the core solves for V0 / 2^e (2^e ~ max |V0|), which is
    # exact: scaling the input by a power of two scales the answer exactly and
    # leaves the error history alone (squared norms of 1e210 would overflow).
    # Found by test_validation.py: E_0 overflowed to inf (|v| > 1e154) or
    # underflowed to 0 (|v| < 1e-154, and V0 came back as if it interpolated);
    # fixed by solving for V0 / 2**e (9ac2c8d).
    v, f = sorpia.shapes.irregular(300, seed=2)
    res = sorpia.interpolate(v, f, method=method)
    big = sorpia.interpolate(np.ldexp(v, exponent), f, method=method)
    assert big.converged and big.iterations == res.iterations
    np.testing.assert_array_equal(big.history, res.history)
    np.testing.assert_array_equal(big.control_vertices, np.ldexp(res.control_vertices, exponent))


def test_result_round_trips_through_pickle_and_is_read_only():
    """The one result type (bound from the core) pickles for multiprocessing
    with every field equal, and its fields cannot be reassigned."""
    import pickle

    v, f = sorpia.shapes.icosphere(2)
    res = sorpia.interpolate(v, f, method="wpia")
    back = pickle.loads(pickle.dumps(res))
    for name in sorpia.InterpolationResult._fields:
        a, b = getattr(res, name), getattr(back, name)
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(a, b)
        else:
            assert a == b, name
    assert "control_vertices=<array (162, 3)>" in repr(res)
    with pytest.raises(AttributeError):
        res.iterations = 3


@pytest.mark.parametrize("method", ["sor", "cg", "pia"])
@pytest.mark.parametrize("scale", [1e-300, 1e-318, 5e-324])
def test_subnormal_input_is_reported_consistently(method, scale):
    """Tiny input is solved on V0 scaled by a power of two, and E_0 reported at
    V0's own scale. Where that E_0 underflows to 0 (the smallest subnormals),
    V0 interpolates as far as doubles can tell: errors == [0.0], no iterations,
    V0 returned, as the docs promise for E_0 = 0; otherwise E_0 > 0 and the
    solve reaches tol."""
    v, f = sorpia.shapes.icosphere(2)
    res = sorpia.interpolate(v * scale, f, method=method)
    assert res.converged
    if res.initial_error == 0.0:
        assert list(res.history) == [0.0] and res.iterations == 0
        assert np.array_equal(res.control_vertices, v * scale)
    else:
        assert res.iterations > 0 and res.history[-1] < 1e-10
