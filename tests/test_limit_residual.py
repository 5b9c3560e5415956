"""The check after a fit (sorpia::limit_residual): |(B V)_i - v0_i| from
OpenSubdiv's limit masks over the one-ring, against the closed-form limit
matrix; and it catches a control mesh solved with a wrong operator, returned
in a wrong order or left by a wrong sweep."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg

import sorpia
from sorpia import _core
from sorpia.limit import topology

from conftest import direct_solve


def residual(V, F, V0, boundary="edge-and-corner"):
    """(max, argmax, norms) of the core's check."""
    topo = topology(F, len(V0), warn=False)
    return _core.limit_residual(topo, np.ascontiguousarray(V, dtype=float), np.ascontiguousarray(V0, dtype=float),
                                _core.parse_boundary(boundary))


@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
def test_residual_is_the_closed_form_limit_minus_the_target(mesh, closed_form, boundary):
    _, V0, F = mesh
    V = V0 + np.random.default_rng(3).normal(scale=0.1, size=V0.shape)  # any control vertices
    expected = np.linalg.norm(closed_form(F, len(V0), boundary) @ V - V0, axis=1)
    top, at, norms = residual(V, F, V0, boundary)
    np.testing.assert_allclose(norms, expected, rtol=1e-13, atol=1e-15)
    assert top == norms.max() and at == int(np.argmax(norms))


@pytest.fixture
def solved():
    """(V0, F, V): a closed irregular mesh and its control vertices by scipy's direct solve."""
    V0, F = sorpia.shapes.irregular(400, seed=4)
    V0, F = np.asarray(V0), np.asarray(F)
    return V0, F, direct_solve(F, V0)


def test_the_check_passes_a_right_solve(solved):
    V0, F, V = solved
    assert residual(V, F, V0)[0] < 1e-12
    fitted = sorpia.interpolate(V0, F).control_vertices
    assert residual(fitted, F, V0)[0] < 1e-9


def test_the_check_catches_a_wrong_operator(solved):
    # B with one weight of row 17 changed by 1%, solved exactly: the solution of the wrong system.
    V0, F, _ = solved
    B = sorpia.limit_matrix(F, len(V0)).tolil()
    j = B.rows[17][-1]
    B[17, j] *= 1.01
    V = scipy.sparse.linalg.splu(B.tocsc()).solve(V0)
    top, at, _ = residual(V, F, V0)
    assert top > 1e-5 and at == 17


def test_the_check_catches_a_wrong_reordering(solved):
    # The right control vertices with two of them swapped, as a reordering bug would return them.
    V0, F, V = solved
    V = V.copy()
    V[[5, 200]] = V[[200, 5]]
    assert residual(V, F, V0)[0] > 1e-2


def test_the_check_catches_a_wrong_sweep(solved):
    # Gauss-Seidel sweeps (paper eq. 18 with omega 1) that never update vertex 9: they converge
    # on every other row, and the check names vertex 9's neighbourhood.
    V0, F, _ = solved
    B = sorpia.limit_matrix(F, len(V0)).tocsr()
    diag = B.diagonal()
    V = V0.copy()
    for _ in range(60):
        for i in range(len(V0)):
            if i == 9:
                continue
            lo, hi = B.indptr[i], B.indptr[i + 1]
            V[i] += (V0[i] - B.data[lo:hi] @ V[B.indices[lo:hi]]) / diag[i]
    top, at, _ = residual(V, F, V0)
    assert top > 1e-3 and at == 9
