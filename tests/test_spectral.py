"""The spectral estimates behind the solver parameters (W-PIA's lambda_min(B),
HSS's extremes of H = (B + B^T)/2) against dense eigenvalues, on closed meshes
and on meshes with boundary (where B is not symmetrisable), valences 3 to 12."""

from __future__ import annotations

import functools

import numpy as np
import pytest

import sorpia
from sorpia import _core

# The meshes with a hole keep the vertex whose fan was removed, unreferenced.
pytestmark = pytest.mark.filterwarnings("ignore::sorpia.UnreferencedVerticesWarning")


def fan_removed(vertices, faces, vertex):
    """The mesh without the faces round `vertex`: a hole whose rim is boundary,
    and `vertex` left unreferenced (a row of B without neighbours)."""
    f = np.asarray(faces)
    return vertices, f[~np.any(f == vertex, axis=1)]


MESHES = {
    "icosphere-1": (lambda: sorpia.shapes.icosphere(1), "edge-and-corner"),
    "torus": (lambda: sorpia.shapes.torus(12, 9), "edge-and-corner"),
    "irregular-200": (lambda: sorpia.shapes.irregular(200, seed=7), "edge-and-corner"),
    "irregular-150": (lambda: sorpia.shapes.irregular(150, seed=3), "edge-and-corner"),
    "grid-corners": (lambda: sorpia.shapes.grid(7, 6), "edge-and-corner"),
    "grid-edge-only": (lambda: sorpia.shapes.grid(9, 7), "edge-only"),
    "pole-12": (lambda: sorpia.shapes.pole(12), "edge-and-corner"),
    "irregular-hole": (lambda: fan_removed(*sorpia.shapes.irregular(200, seed=7), 0), "edge-and-corner"),
    "irregular-hole-edge-only": (lambda: fan_removed(*sorpia.shapes.irregular(200, seed=2), 5), "edge-only"),
}

# The estimates stop when the extreme Ritz values change by at most 1e-5 of
# their size per product (after 40 products); on these meshes that leaves
# them within these distances of the dense eigenvalues.
LAMBDA_TOL = 1e-4
HERMITIAN_TOL = 1e-3


@functools.lru_cache(maxsize=None)
def case(name):
    """Mesh, boundary rule, the core's operator, and the dense eigenvalues of
    B and of H (numpy, independent of the core's estimates)."""
    make, boundary = MESHES[name]
    v, f = make()
    f = np.ascontiguousarray(f, dtype=np.int32)
    b = sorpia.limit_matrix(f, len(v), boundary=boundary).toarray()
    op = _core.Interpolator(f, len(v), _core.Rules(boundary=_core.parse_boundary(boundary)))
    return v, f, boundary, op, np.linalg.eigvals(b), np.linalg.eigvalsh((b + b.T) / 2)


def test_the_meshes_cover_valence_3_to_12_and_both_kinds():
    valences, closed = set(), set()
    for name in MESHES:
        op = case(name)[3]
        valences |= set(np.diff(np.asarray(op.offsets)).tolist())
        closed.add(bool(op.symmetrisable))
    assert set(range(3, 13)) <= valences and closed == {True, False}


@pytest.mark.parametrize("name", sorted(MESHES))
def test_lambda_min_against_dense_eigenvalues(name):
    _, _, _, op, lam, _ = case(name)
    # With boundary B is not symmetric in any weighting, yet block triangular
    # with self-adjoint blocks: its spectrum is real, which the estimate relies on.
    assert np.abs(lam.imag).max() < 1e-9
    true_min = lam.real.min()
    est = op.lambda_min()
    # Ritz values lie inside the spectrum: the estimate is never below the true value.
    assert true_min - 1e-12 <= est <= true_min + LAMBDA_TOL


@pytest.mark.parametrize("name", sorted(MESHES))
def test_hermitian_extremes_against_dense_eigenvalues(name):
    _, _, _, op, _, h = case(name)
    lo, hi = op.hermitian_extremes()
    assert h[0] - 1e-12 <= lo <= h[0] + HERMITIAN_TOL
    assert h[-1] - HERMITIAN_TOL <= hi <= h[-1] + 1e-12


@pytest.mark.parametrize("name", sorted(MESHES))
def test_wpia_iterations_as_with_the_exact_sigma(name):
    # The estimate is good to the digits that matter: W-PIA with the estimated
    # sigma takes as many iterations as with sigma from the dense lambda_min.
    v, f, boundary, _, lam, _ = case(name)
    true_min = lam.real.min()
    solver = sorpia.Interpolator(f, len(v), boundary=boundary)
    estimated = solver.solve(v, method="wpia")
    exact = solver.solve(v, method="wpia", sigma=2.0 / (true_min + 1.0))
    assert estimated.converged and exact.converged
    assert estimated.iterations == exact.iterations
