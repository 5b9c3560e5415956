"""Warm starts, (n, k) data and local updates (Interpolator.update), against a
scipy direct solve and the residual of sorpia.limit_matrix (independent of the
solvers' operator code paths: a scipy CSR product)."""

import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg

import sorpia
from sorpia.errors import MeshError, ParameterError
from sorpia.solve import METHODS, ConvergenceWarning
from test_robust_default import folded_octagon

SHARED_MESHES = Path(__file__).resolve().parents[2] / "shared" / "meshes"


def meshes():
    closed = sorpia.shapes.irregular(400, seed=4)
    grid = sorpia.shapes.grid(14, 11)  # boundary and one-face corners
    return {"irregular": closed, "grid": grid}


def residual(B, targets, v):
    """max_i ||t_i - (B v)_i||, the paper's E, from a scipy product."""
    return float(np.linalg.norm(targets - B @ v, axis=1).max())


def data(n, k, seed=0):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, k))


@pytest.mark.parametrize("name", ["irregular", "grid"])
@pytest.mark.parametrize("k", [1, 2, 3, 5])
@pytest.mark.parametrize("method", METHODS)
def test_k_columns_every_method_matches_direct_solve(name, k, method):
    V, F = meshes()[name]
    values = data(len(V), k, seed=k)
    B = sorpia.limit_matrix(F, len(V))
    ref = scipy.sparse.linalg.spsolve(B.tocsc(), values)
    ref = ref.reshape(len(V), k)
    res = sorpia.interpolate(values, F, method=method, tol=1e-12, max_iter=20000)
    assert res.converged
    assert res.control_vertices.shape == (len(V), k)
    e0 = residual(B, values, values)
    assert res.initial_error == pytest.approx(e0, rel=1e-12)
    # E_k / E_0 < 1e-12, E over the k columns' Euclidean norm; B^-1 bounded
    # (spectrum in about [0.2, 1]): the solution to a few 1e-12 E_0.
    assert residual(B, values, res.control_vertices) < 1.01e-12 * e0
    np.testing.assert_allclose(res.control_vertices, ref, atol=1e-9 * np.abs(ref).max())


def test_k_columns_are_the_columns_solved_together():
    """Columns iterate independently; only the stopping rule joins them. With a
    tight tol, (n, 5) equals its (n, 3) and (n, 2) parts solved apart."""
    V, F = meshes()["irregular"]
    values = data(len(V), 5)
    interp = sorpia.Interpolator(F, len(V))
    whole = interp.solve(values, tol=1e-13).control_vertices
    first = interp.solve(values[:, :3], tol=1e-13).control_vertices
    rest = interp.solve(values[:, 3:], tol=1e-13).control_vertices
    np.testing.assert_allclose(whole, np.hstack([first, rest]), atol=1e-10)


def test_k_columns_threads():
    V, F = meshes()["irregular"]
    two = data(len(V), 2)
    one = sorpia.interpolate(two, F, threads=1, tol=1e-12).control_vertices
    both = sorpia.interpolate(two, F, threads=2, tol=1e-12).control_vertices
    np.testing.assert_allclose(one, both, atol=1e-9)
    with pytest.raises(ParameterError, match="threads = 2 .* 5 columns"):
        sorpia.interpolate(data(len(V), 5), F, threads=2)


@pytest.mark.parametrize("k", [1, 2, 4, 7])
def test_limit_points_k_columns(k):
    V, F = meshes()["grid"]
    values = data(len(V), k)
    B = sorpia.limit_matrix(F, len(V))
    np.testing.assert_allclose(sorpia.limit_points(values, F), B @ values, atol=1e-14)


def test_bad_data_shapes():
    V, F = meshes()["irregular"]
    with pytest.raises(ValueError, match=r"values\[:, None\]"):
        sorpia.interpolate(V[:, 0], F)
    with pytest.raises(ValueError, match=r"\(n, k\), k >= 1"):
        sorpia.interpolate(np.zeros((len(V), 0)), F)
    with pytest.raises(ParameterError, match="initial has shape"):
        sorpia.interpolate(V, F, initial=V[:-1])
    with pytest.raises(ValueError, match=r"initial must have shape \(n, 3\)"):
        sorpia.interpolate(V, F, initial=V[:, :2])


@pytest.mark.parametrize("name", ["irregular", "grid"])
@pytest.mark.parametrize("method", METHODS)
def test_warm_start_same_guarantee(name, method):
    V, F = meshes()[name]
    B = sorpia.limit_matrix(F, len(V))
    interp = sorpia.Interpolator(F, len(V))
    first = interp.solve(V, tol=1e-12)
    moved = V + 1e-3 * np.sin(np.arange(V.size)).reshape(V.shape)
    warm = interp.solve(moved, method=method, tol=1e-10, max_iter=5000, initial=first.control_vertices)
    e0 = residual(B, moved, moved)
    assert warm.converged
    assert warm.initial_error == pytest.approx(e0, rel=1e-12)  # E_0 of the cold start
    assert warm.history[0] == pytest.approx(residual(B, moved, first.control_vertices) / e0, rel=1e-6)
    assert warm.history[0] < 1
    assert residual(B, moved, warm.control_vertices) < 1.0001e-10 * e0
    assert len(warm.history) == warm.iterations + 1


def test_warm_start_already_solved_does_nothing():
    V, F = meshes()["irregular"]
    exact = sorpia.interpolate(V, F, tol=1e-13)
    again = sorpia.interpolate(V, F, tol=1e-8, initial=exact.control_vertices)
    assert again.iterations == 0 and again.converged
    np.testing.assert_array_equal(again.control_vertices, exact.control_vertices)


def diagonal(V):
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


@pytest.mark.parametrize("name", ["irregular", "grid"])
@pytest.mark.parametrize("in_place", [False, True])
def test_update_meets_full_solve_guarantee_and_composes(name, in_place):
    V, F = meshes()[name]
    B = sorpia.limit_matrix(F, len(V))
    interp = sorpia.Interpolator(F, len(V))
    res = interp.solve(V, tol=1e-10)
    targets = V.copy()
    step = 0.01 * diagonal(V)
    for idx in ([len(V) // 2], [5, 6, 7, 8], [len(V) // 3]):
        targets[idx] += step * np.array([0.3, -0.2, 1.0])
        before = res.control_vertices.copy()
        new = interp.update(res, idx, targets[idx], tol=1e-10, in_place=in_place)
        assert (new is res) == in_place
        if not in_place:
            np.testing.assert_array_equal(res.control_vertices, before)  # previous left alone
        res = new
        np.testing.assert_array_equal(interp.targets, targets)
        e0 = residual(B, targets, targets)
        assert res.converged and res.variant == "local" and res.method == "gs"
        assert res.initial_error == pytest.approx(e0, rel=1e-12)
        assert residual(B, targets, res.control_vertices) < 1.0001e-10 * e0
        assert res.history[-1] < 1e-10 < res.history[0]
        assert res.iterations == 1 and 0 < res.relaxations
        full = interp.solve(targets, tol=1e-13)  # a solve resets the kept targets to these: the same
        np.testing.assert_allclose(res.control_vertices, full.control_vertices, atol=100 * 1e-10 * e0)


@pytest.mark.parametrize("sharpness", [np.inf, 1.5])
def test_update_with_creases(sharpness):
    """Crease rows: one-way entries (infinitely sharp) or per-entry weights
    (semi-sharp, B composed through refinement levels); the update's guarantee
    against the residual of limit_matrix with the same tags."""
    V, F = sorpia.shapes.grid(16, 12)
    nv = 12  # vertex (i, j) of the grid is i * nv + j
    row = 6
    # boundary to boundary: no dart, so infinitely sharp rows keep one weight each
    edges = np.array([[row * nv + j, row * nv + j + 1] for j in range(nv - 1)])
    tags = {"creases": (edges, sharpness), "corners": ([0], np.inf)}
    B = sorpia.limit_matrix(F, len(V), **tags)
    interp = sorpia.Interpolator(F, len(V), **tags)
    assert interp._impl.uniform == (sharpness == np.inf)
    res = interp.solve(V)
    targets = V.copy()
    for i in (row * nv + 5, 5, len(V) - 1):
        targets[i] += [0.0, 0.0, 0.3]
        res = interp.update(res, [i], targets[i])
        e0 = residual(B, targets, targets)
        assert res.converged and residual(B, targets, res.control_vertices) < 1.0001e-10 * e0


def quad_grid(nu, nv):
    """A bumpy open grid of nu x nv quads: vertex (i, j) is i * (nv + 1) + j."""
    i, j = np.meshgrid(np.arange(nu + 1), np.arange(nv + 1), indexing="ij")
    V = np.stack([i.ravel() / nu, j.ravel() / nv, 0.1 * np.sin(3 * i.ravel()) * np.cos(2 * j.ravel())], axis=1)
    a = (i[:-1, :-1] * (nv + 1) + j[:-1, :-1]).ravel()
    F = np.stack([a, a + nv + 1, a + nv + 2, a + 1], axis=1)
    return V, F


@pytest.mark.parametrize("k", [3, 2])
def test_update_catmull_clark(k):
    """Catmull-Clark rows (per-entry weights: edge and face neighbours): the
    update's guarantee against limit_matrix(scheme="catmull-clark")."""
    V, F = quad_grid(12, 9)
    data = V[:, :k].copy()
    B = sorpia.limit_matrix(F, len(V), scheme="catmull-clark")
    interp = sorpia.Interpolator(F, len(V), scheme="catmull-clark")
    assert not interp._impl.uniform
    res = interp.solve(data)
    for i in (50, 3, len(V) - 1):
        data[i] += 0.2
        res = interp.update(res, [i], data[i])
        assert res.converged and residual(B, data, res.control_vertices) < 1.0001e-10 * residual(B, data, data)
    warm = interp.solve(data + 0.01, initial=res.control_vertices, method="cg")
    assert residual(B, data + 0.01, warm.control_vertices) < 1.0001e-10 * residual(B, data + 0.01, data + 0.01)


def test_update_one_vertex_is_local():
    V, F = sorpia.shapes.irregular(20000, seed=2)
    interp = sorpia.Interpolator(F, len(V))
    res = interp.solve(V)
    p = V[100] + 0.01 * diagonal(V)
    res = interp.update(res, [100], p)
    assert res.converged and 0 < res.relaxations < len(V) / 4


def test_update_k_columns_and_start_from_any_result():
    V, F = meshes()["grid"]
    B = sorpia.limit_matrix(F, len(V))
    values = data(len(V), 1)
    interp = sorpia.Interpolator(F, len(V))
    cold = interp.solve(values)
    values[3] = 5.0
    up = interp.update(cold, 3, [5.0])
    assert up.control_vertices.shape == (len(V), 1)
    assert residual(B, values, up.control_vertices) < 1.0001e-10 * residual(B, values, values)
    # From another start than the last update (its residual computed in full): the same guarantee.
    values[7] = -2.0
    up2 = interp.update(cold, [7], [[-2.0]])
    assert residual(B, values, up2.control_vertices) < 1.0001e-10 * residual(B, values, values)


def test_results_pickle_with_their_columns():
    import pickle

    V, F = meshes()["irregular"]
    interp = sorpia.Interpolator(F, len(V))
    res = interp.solve(V[:, :2])
    up = interp.update(res, [4], [1.0, 2.0])
    for r in (res, up):
        back = pickle.loads(pickle.dumps(r))
        np.testing.assert_array_equal(back.control_vertices, r.control_vertices)
        assert back.control_vertices.shape == (len(V), 2)
        assert back.relaxations == r.relaxations and back.variant == r.variant
    assert not pickle.loads(pickle.dumps(up)).control_vertices.flags.writeable


def test_update_nothing_to_do():
    V, F = meshes()["irregular"]
    interp = sorpia.Interpolator(F, len(V))
    res = interp.solve(V)
    same = interp.update(res, [3], V[3])
    assert same.iterations == 0 and same.relaxations == 0 and list(same.history) == [res.history[-1]]
    np.testing.assert_array_equal(same.control_vertices, res.control_vertices)


def test_update_bad_input():
    V, F = meshes()["irregular"]
    interp = sorpia.Interpolator(F, len(V))
    with pytest.raises(ParameterError, match="needs the targets of a solve"):
        interp.update(sorpia.interpolate(V, F), [0], V[0])
    res = interp.solve(V)
    with pytest.raises(ParameterError, match="is not a vertex"):
        interp.update(res, [len(V)], V[0])
    with pytest.raises(ParameterError, match="positions has 1 rows but indices has 2"):
        interp.update(res, [0, 1], [V[0]])
    with pytest.raises(ValueError, match=r"positions must have shape \(n, 3\)"):
        interp.update(res, [0], [[1.0, 2.0]])
    with pytest.raises(MeshError, match="not finite"):
        interp.update(res, [0], [np.nan, 0, 0])
    with pytest.raises(ParameterError, match="previous must be an InterpolationResult"):
        interp.update(V, [0], V[0])
    with pytest.raises(ParameterError, match="previous has shape"):
        interp.update(sorpia.interpolate(V[:, :2], F), [0], V[0])
    with pytest.raises(ParameterError, match="tol"):
        interp.update(res, [0], V[0], tol=0)
    up = interp.update(res, [0], V[0] + 1.0)
    with pytest.raises(ValueError, match="read-only"):  # the next update relies on its kept residual
        up.control_vertices[0] = 0.0
    res.control_vertices[0] = 0.0  # a solve's result stays writable


def test_update_max_iter_warns():
    V, F = meshes()["irregular"]
    interp = sorpia.Interpolator(F, len(V))
    res = interp.solve(V)
    with pytest.warns(ConvergenceWarning, match="max_iter"):
        r = interp.update(res, [0], V[0] + 1.0, tol=1e-300, max_iter=1)
    assert r.stop_reason == "max_iter"


def shared_loop_meshes():
    if not SHARED_MESHES.exists():
        return []
    return sorted(p.name for p in SHARED_MESHES.iterdir() if p.suffix in (".obj", ".off", ".ply", ".stl"))


@pytest.mark.skipif(not SHARED_MESHES.exists(), reason="../shared/meshes is not present")
@pytest.mark.parametrize("name", shared_loop_meshes() or ["none"])
@pytest.mark.filterwarnings("ignore::sorpia.limit.UnreferencedVerticesWarning")
def test_update_on_shared_meshes(name):
    """On every shared mesh the interpolator accepts, with the file's tags and
    the command line's scheme (Loop for all-triangle meshes, Catmull-Clark
    otherwise): one target moved, the update meets the guarantee of a full solve."""
    V, F, tags = sorpia.read_mesh(SHARED_MESHES / name, tags=True)
    triangles = isinstance(F, np.ndarray) and F.shape[1] == 3
    tags["scheme"] = "loop" if triangles else "catmull-clark"
    try:
        interp = sorpia.Interpolator(F, len(V), **tags)
    except (MeshError, ValueError) as exc:
        pytest.skip(f"refused: {exc}")
    B = sorpia.limit_matrix(F, len(V), **tags)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        warnings.simplefilter("ignore", sorpia.SingularMatrixWarning)  # the car's cubes (test_singular_cubes)
        res = interp.solve(V, max_iter=5000)
    if not res.converged:  # a full solve is the reference: without one there is nothing to match
        pytest.skip(f"the full solve stops at E/E_0 = {res.history[-1]:.3g} (docs: Creases, corners and holes)")
    targets = V.copy()
    i = len(V) // 2
    targets[i] += 0.01 * diagonal(V)
    up = interp.update(res, [i], targets[i])
    e0 = residual(B, targets, targets)
    assert up.converged
    assert residual(B, targets, up.control_vertices) < 1.0001e-10 * e0


def test_move_vertex_example_meets_the_guarantee():
    """examples/move_vertex.py (shown in the docs) on a small mesh: its last update interpolates."""
    import runpy

    example = runpy.run_path(str(Path(__file__).resolve().parents[1] / "examples" / "move_vertex.py"))
    targets, F, result = example["main"](3000, moves=3)
    e = np.linalg.norm(targets - sorpia.limit_points(result.control_vertices, F), axis=1).max()
    assert result.converged and e < 1.0001e-10 * result.initial_error


def test_folded_octagon_is_indefinite():
    V, F = folded_octagon()
    eigenvalues = np.linalg.eigvals(sorpia.limit_matrix(F, len(V), scheme="catmull-clark").toarray())
    assert eigenvalues.real.min() < -0.07  # what makes Gauss-Seidel diverge


@pytest.mark.parametrize("in_place", [False, True])
def test_update_after_cg_on_valence_2_shape_matches_direct_solve(in_place):
    """Issue 20: after a converged cg solve, update returned inf/NaN (its
    local Gauss-Seidel diverged). Now the divergence is caught and the new
    targets are solved in full by the last solve's method: the result equals
    scipy's direct solve of the limit matrix to 1e-8 (tol 1e-10 on E/E_0,
    B's condition number about 25)."""
    V, F = folded_octagon()
    B = sorpia.limit_matrix(F, len(V), scheme="catmull-clark").tocsc()
    interp = sorpia.Interpolator(F, len(V), scheme="catmull-clark")
    res = interp.solve(V, method="cg")
    assert res.converged
    targets = V.copy()
    for step, (i, move) in enumerate([(1, 0.5), (4, -0.3)]):
        targets[i] = targets[i] + move
        res = interp.update(res, [i], targets[i], in_place=in_place)
        assert res.converged and np.isfinite(res.control_vertices).all(), step
        direct = scipy.sparse.linalg.spsolve(B, targets)
        assert np.abs(res.control_vertices - direct).max() < 1e-8 * np.abs(direct).max()
        np.testing.assert_array_equal(interp.targets, targets)


@pytest.mark.filterwarnings("ignore::sorpia.solve.ConvergenceWarning")
def test_update_that_diverges_leaves_the_interpolator_as_it_was():
    """The last solve's method (sor) diverges on the folded octagon too: the
    update says so, and the targets, the vertices and later updates are as if
    it had not been called."""
    V, F = folded_octagon()
    interp = sorpia.Interpolator(F, len(V), scheme="catmull-clark")
    res = interp.solve(V, method="cg")
    interp.solve(V, method="sor")  # the last solve keeping its targets: its method is the fallback's
    start = res.control_vertices.copy()
    with pytest.warns(ConvergenceWarning, match="diverged.*targets are left as they were"):
        failed = interp.update(res, [1], V[1] + 0.5, in_place=True)
    assert failed.stop_reason == "diverged"
    np.testing.assert_array_equal(res.control_vertices, start)
    np.testing.assert_array_equal(interp.targets, V)


def test_update_at_max_iter_leaves_the_interpolator_as_it_was():
    """An update that cannot meet tol (max_iter) changes nothing: the next
    update from the last good result gives what it gives without the failed
    one, and agrees with scipy's direct solve."""
    V, F = meshes()["irregular"]
    B = sorpia.limit_matrix(F, len(V)).tocsc()
    interp, fresh = sorpia.Interpolator(F, len(V)), sorpia.Interpolator(F, len(V))
    good = interp.update(interp.solve(V), [0], V[0] + 0.1)
    same = fresh.update(fresh.solve(V), [0], V[0] + 0.1)
    kept = good.control_vertices.copy()
    with pytest.warns(ConvergenceWarning, match="max_iter.*targets are left as they were"):
        failed = interp.update(good, [5], V[5] + 1.0, tol=1e-300, max_iter=1, in_place=True)
    assert failed.stop_reason == "max_iter"
    np.testing.assert_array_equal(good.control_vertices, kept)
    np.testing.assert_array_equal(interp.targets, fresh.targets)
    after = interp.update(good, [7], V[7] - 0.1)
    expected = fresh.update(same, [7], V[7] - 0.1)
    np.testing.assert_array_equal(after.control_vertices, expected.control_vertices)
    targets = interp.targets
    assert np.abs(after.control_vertices - scipy.sparse.linalg.spsolve(B, targets)).max() < 1e-8


@pytest.mark.parametrize("value", [np.inf, np.nan, 1e155, -1e200])
def test_overflowing_or_non_finite_data_refused_before_any_change(value):
    """Issue 20: an update to 1e155 reported converged with errors [nan, 0],
    and a warm start of 1e200 "diverged after 0 iterations". Values whose
    squares overflow (beyond 1e150, sorpia::max_coordinate, for update
    positions; 1e150 times the targets' scale for a warm start) or that are
    not finite are refused naming the argument, row and column, before
    anything changes."""
    V, F = meshes()["irregular"]
    interp = sorpia.Interpolator(F, len(V))
    res = interp.solve(V)
    bad = V.copy()
    bad[9, 1] = value
    kind = (MeshError, ParameterError)  # non-finite: the Python edge's check (MeshError), large: the core's
    with pytest.raises(kind, match=r"positions\[0(, 1)?\]"):
        interp.update(res, [9], bad[9])
    np.testing.assert_array_equal(interp.targets, V)
    with pytest.raises(kind, match=r"initial\[9(, 1)?\]"):
        interp.solve(V, initial=bad)
    np.testing.assert_array_equal(interp.targets, V)
    up = interp.update(res, [9], V[9] + 0.1)  # the kept state still serves
    assert up.converged and up.control_vertices.shape == V.shape
    if np.isfinite(value):  # huge targets are solved (scaled exactly), but not updated locally
        huge = interp.solve(bad)
        assert huge.converged
        with pytest.raises(ParameterError, match="update needs targets within 1e.150"):
            interp.update(huge, [0], V[0])
    else:
        with pytest.raises(kind, match=r"vertices\[9(, 1)?\]"):
            interp.solve(bad)


def test_far_warm_start_iterates():
    """A warm start far off (1e100 times the targets, within the bound) iterates
    to the answer instead of stopping as diverged after 0 iterations: divergence
    is measured against the larger of E_0 and the start's error."""
    V, F = meshes()["irregular"]
    res = sorpia.interpolate(V, F, initial=V * 1e100, max_iter=5000)
    assert res.converged and res.iterations > 0 and res.history[0] > 1e99
    B = sorpia.limit_matrix(F, len(V))
    assert residual(B, V, res.control_vertices) < 1e-10 * residual(B, V, V)
