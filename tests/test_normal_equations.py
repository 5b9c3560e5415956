"""Approximation's normal equations in the core: the normal matrix A^T W A
(sorpia::normal_matrix) and their solve by the fitting layer's PCG
(sorpia::NormalEquations), against scipy's products and direct solve on small
systems: three independent columns (point distance) and 3x3 blocks (the
tangent-distance blend), with and without a fairness term."""

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

from sorpia import _core
from sorpia.approximate import _core_csr
from sorpia.errors import ParameterError

PAIRS = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))  # the six stored entries of a symmetric 3x3 weight


def random_rows(k=240, n=30, per_row=5, seed=0):
    """A (k, n) CSR with per_row sorted columns in each row, rows in runs of equal columns (as points of one
    face are), nonnegative entries as a limit basis has."""
    rng = np.random.default_rng(seed)
    cols = []
    while len(cols) < k:
        c = np.sort(rng.choice(n, per_row, replace=False))
        cols.extend([c] * int(rng.integers(1, 6)))
    cols = np.concatenate(cols[:k]).astype(np.int32)
    indptr = np.arange(0, per_row * k + 1, per_row, dtype=np.int32)
    return scipy.sparse.csr_matrix((rng.random(per_row * k), cols, indptr), shape=(k, n))


def spd_weights(k, seed):
    """Per-row symmetric positive definite 3x3 weights t I + (1 - t) n n^T (stored xx, xy, xz, yy, yz, zz)."""
    rng = np.random.default_rng(seed)
    nrm = rng.standard_normal((k, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    w = rng.random(k) + 0.5
    return np.stack([w * (0.1 * (a == b) + 0.9 * nrm[:, a] * nrm[:, b]) for a, b in PAIRS], axis=1)


def fairness(n, seed):
    """A symmetric positive semidefinite (n, n) K with sorted int32 indices (a graph Laplacian)."""
    rng = np.random.default_rng(seed)
    i, j = rng.integers(0, n, 3 * n), rng.integers(0, n, 3 * n)
    keep = i != j
    adj = scipy.sparse.coo_matrix((np.ones(keep.sum()), (i[keep], j[keep])), shape=(n, n)).tocsr()
    adj = ((adj + adj.T) > 0).astype(float)
    K = (scipy.sparse.diags(np.asarray(adj.sum(axis=1)).ravel()) - adj).tocsr()
    K.sort_indices()
    return K


def k_arrays(K):
    return None if K is None else _core_csr(K)


def scipy_matrix(A, weights, K, c, mu):
    """The whole system matrix, assembled by scipy: (n, n) for 0/1 weights, (3n, 3n) interleaved for 6."""
    n = A.shape[1]
    if weights is None or weights.shape[1] == 1:
        w = np.ones(A.shape[0]) if weights is None else weights[:, 0]
        M = A.T @ scipy.sparse.diags(w) @ A + mu * scipy.sparse.identity(n)
        return (M + c * K if K is not None else M).tocsc()
    blocks = [[None] * 3 for _ in range(3)]
    for col, (a, b) in enumerate(PAIRS):
        blocks[a][b] = A.T @ scipy.sparse.diags(weights[:, col]) @ A
        blocks[b][a] = blocks[a][b]
    # unknowns interleaved x0, y0, z0, x1, ...: entry (3i + a, 3j + b) = block (a, b) at (i, j)
    M = sum(scipy.sparse.kron(blocks[a][b], scipy.sparse.coo_matrix(([1.0], ([a], [b])), shape=(3, 3)))
            for a in range(3) for b in range(3))
    M = M + mu * scipy.sparse.identity(3 * n)
    if K is not None:
        M = M + scipy.sparse.kron(c * K, scipy.sparse.identity(3))
    return M.tocsc()


@pytest.mark.parametrize("count", [0, 1, 6])
def test_normal_matrix_is_scipys_product(count):
    # Every stored block (i, j) of A^T W A equals scipy's A^T diag(W[:, c]) A, to rounding of sums of five
    # products of numbers below 2 (1e-13).
    A = random_rows()
    rng = np.random.default_rng(1)
    w = None if count == 0 else (rng.random((A.shape[0], 1)) if count == 1 else spd_weights(A.shape[0], 2))
    ip, ix, val = _core.normal_matrix(A.indptr, A.indices, A.data, A.shape[1], w)
    assert np.all(np.diff(ip) >= 0) and all(np.all(np.diff(ix[ip[i]:ip[i + 1]]) > 0) for i in range(A.shape[1]))
    for c in range(val.shape[1]):
        weight = np.ones(A.shape[0]) if w is None else w[:, c]
        want = (A.T @ scipy.sparse.diags(weight) @ A).toarray()
        got = scipy.sparse.csr_matrix((val[:, c], ix, ip), shape=(A.shape[1],) * 2).toarray()
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13)
    # the pattern is that of A^T A: nothing more, nothing less
    pattern = (A.T @ A).tocsr()
    pattern.sort_indices()
    np.testing.assert_array_equal(ip, pattern.indptr)
    np.testing.assert_array_equal(ix, pattern.indices)


@pytest.mark.parametrize("with_k", [False, True])
@pytest.mark.parametrize("count", [0, 1, 6])
def test_pcg_solves_as_scipys_direct_solve(count, with_k):
    # The core's PCG to rtol 1e-13 against spsolve on the assembled matrix: three independent columns (count 0,
    # 1: Jacobi) or one system of 3x3 blocks (count 6: block Jacobi), each with mu I and c K. The systems' condition
    # numbers are below 1e4, so the solutions agree to 1e-8 of their size.
    A = random_rows(seed=3)
    n = A.shape[1]
    rng = np.random.default_rng(4)
    w = None if count == 0 else (rng.random((A.shape[0], 1)) + 0.5 if count == 1 else spd_weights(A.shape[0], 5))
    K = fairness(n, 6) if with_k else None
    eq = _core.NormalEquations(A.indptr, A.indices, A.data, n, w, k_arrays(K), 0.05, 1e-3)
    M = scipy_matrix(A, w, K, 0.05 * eq.mean_diagonal, eq.mu)
    diag = M.diagonal()
    assert eq.mean_diagonal == pytest.approx(np.mean(diag) - eq.mu - (0.05 * eq.mean_diagonal * np.mean(K.diagonal())
                                                                      if with_k else 0.0), rel=1e-12)
    assert eq.mu == pytest.approx(1e-3 * eq.mean_diagonal, rel=1e-15)
    rhs, x0 = rng.standard_normal((n, 3)), rng.standard_normal((n, 3))
    # the product is the assembled matrix's
    np.testing.assert_allclose(eq.apply(x0).ravel() if count == 6 else eq.apply(x0),
                               M @ x0.ravel() if count == 6 else M @ x0, rtol=0, atol=1e-12)
    x, iterations, reason = eq.solve(rhs, x0, 1e-13, 10000)
    want = scipy.sparse.linalg.spsolve(M, rhs.ravel() if count == 6 else rhs).reshape(n, 3)
    assert reason == "converged" and 0 < iterations < 10000
    np.testing.assert_allclose(x, want, rtol=0, atol=1e-8 * np.abs(want).max())


@pytest.mark.parametrize("count", [1, 6])
def test_pcg_stops_at_its_relative_residual(count):
    # The stop rule: each system's residual (per column for count 1, over all 3n unknowns for 6) at most rtol
    # times its start's, measured by scipy on the assembled matrix (to 1e-9 of the start: the iteration's
    # recursive residual and the true one differ by rounding), and not many iterations past it.
    A = random_rows(seed=7)
    n = A.shape[1]
    rng = np.random.default_rng(8)
    w = rng.random((A.shape[0], 1)) + 0.5 if count == 1 else spd_weights(A.shape[0], 9)
    eq = _core.NormalEquations(A.indptr, A.indices, A.data, n, w, None, 0.0, 1e-6)
    M = scipy_matrix(A, w, None, 0.0, eq.mu)
    rhs, x0 = rng.standard_normal((n, 3)), rng.standard_normal((n, 3))

    def residual(x):
        r = rhs - (M @ x.ravel()).reshape(n, 3) if count == 6 else rhs - M @ x
        return np.array([np.linalg.norm(r)]) if count == 6 else np.linalg.norm(r, axis=0)

    start = residual(x0)
    x, iterations, reason = eq.solve(rhs, x0, 1e-3, 10000)
    assert reason == "converged"
    assert np.all(residual(x) <= (1e-3 + 1e-9) * start)
    x_short, _, reason_short = eq.solve(rhs, x0, 1e-3, iterations - 1)
    assert reason_short == "max_iter" and np.any(residual(x_short) > 1e-3 * start * (1 - 1e-9))


def test_bad_rows_are_refused():
    A = random_rows(k=6, n=8, per_row=3)
    bad = A.indices.copy()
    bad[[0, 1]] = bad[[1, 0]]
    with pytest.raises(ParameterError, match="row 0 are not sorted"):
        _core.normal_matrix(A.indptr, bad, A.data, 8, None)
    with pytest.raises(ParameterError, match="out of range"):
        _core.normal_matrix(A.indptr, A.indices, A.data, 2, None)
    with pytest.raises(ParameterError, match="weight_count"):
        _core.NormalEquations(A.indptr, A.indices, A.data, 8, np.ones((6, 2)), None, 0.0, 1e-6)
    with pytest.raises(ParameterError, match="fairness matrix"):
        _core.NormalEquations(A.indptr, A.indices, A.data, 8, None, k_arrays(fairness(5, 1)), 1.0, 1e-6)
    data, indices, indptr = k_arrays(fairness(8, 1))
    r = int(np.argmax(np.diff(indptr)))  # a row of several entries
    unordered = indices.copy()
    unordered[indptr[r]:indptr[r + 1]] = unordered[indptr[r]:indptr[r + 1]][::-1]
    for broken in (np.where(indices == indices.max(), 8, indices).astype(np.int32), unordered):
        with pytest.raises(ParameterError, match="row .* out of range or out of order"):
            _core.NormalEquations(A.indptr, A.indices, A.data, 8, None, (data, broken, indptr), 1.0, 1e-6)


@pytest.mark.parametrize("with_weights", [False, True])
def test_blend_weights_are_the_blended_matrices(with_weights):
    # W_i = w_i (t I + (1 - t) n_i n_i^T), a zero (or NaN) normal giving w_i I, against the 3x3 matrices formed
    # by numpy, and W_i p_i against their products (sums of three products: 1e-15).
    rng = np.random.default_rng(11)
    k, t = 50, 0.3
    normals = rng.standard_normal((k, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    normals[3] = 0.0
    normals[7] = np.nan
    points = rng.standard_normal((k, 3))
    w = rng.random(k) + 0.1 if with_weights else None
    W, Wp = _core.blend_weights(points, normals, t, w)
    for i in range(k):
        scale = 1.0 if w is None else w[i]
        n = normals[i] if np.all(np.isfinite(normals[i])) and normals[i].any() else None
        full = scale * (np.eye(3) if n is None else t * np.eye(3) + (1 - t) * np.outer(n, n))
        np.testing.assert_allclose(W[i], [full[a, b] for a, b in PAIRS], rtol=0, atol=1e-15)
        np.testing.assert_allclose(Wp[i], full @ points[i], rtol=0, atol=1e-15)


def test_pcg_result_does_not_depend_on_the_threads():
    # Above 100k rows the vector updates and products run on several threads; the sums are formed over fixed
    # chunks of rows in order, so one thread and two give the same bits (a tridiagonal-like system of 120k
    # unknowns from rows with two columns each).
    n = 120_000
    rng = np.random.default_rng(13)
    cols = np.stack([np.arange(n), (np.arange(n) + 1) % n], axis=1)
    cols.sort(axis=1)
    A = scipy.sparse.csr_matrix((rng.random(2 * n) + 0.1, cols.ravel().astype(np.int32),
                                 np.arange(0, 2 * n + 1, 2, dtype=np.int32)), shape=(n, n))
    eq = _core.NormalEquations(A.indptr, A.indices, A.data, n, spd_weights(n, 14), None, 0.0, 1e-6)
    rhs, x0 = rng.standard_normal((n, 3)), np.zeros((n, 3))
    one = eq.solve(rhs, x0, 1e-12, 15, 1)
    two = eq.solve(rhs, x0, 1e-12, 15, 2)
    assert one[1] == two[1] == 15
    np.testing.assert_array_equal(one[0], two[0])
