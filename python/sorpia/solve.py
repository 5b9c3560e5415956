"""Subdivision surface interpolation: solve B V = V0 with SOR-PIA and the PIA family.

B is the limit matrix of the Loop or Catmull-Clark surface (paper eq. 7, as
OpenSubdiv evaluates it; ``scheme=``), V0 the
(n, 3) mesh vertices, V the control vertices whose limit surface passes through
V0. Every method starts from V = V0 and stops by the paper's rule (section 5):
E_k = max_i ||v_i^0 - (B V^(k))_i||, stop when E_k / E_0 < tol or at max_iter.

Methods (the iteration itself runs in the C++ core):

- ``"pia"``: V += V0 - B V (paper eq. 9).
- ``"wpia"``: V += sigma (V0 - B V), sigma = 2 / (lambda_min + lambda_max) by
  default. lambda_max(B) = 1 exactly (B's rows are non-negative and sum to 1,
  and its spectrum is real); lambda_min is estimated by Lanczos on B in the
  Gamma^-1 inner product, where B = Gamma Upsilon is self-adjoint (with a
  boundary, on B without its one-way entries, which has B's eigenvalues), at
  most 300 scalar products with B; the estimate is at or above the true value.
  Catmull-Clark rows of quad rings have such a Gamma (Gamma_ii proportional to
  1 / (n_i (n_i + 5))), and so do the rows refined around non-quad faces on
  every mesh tried (sorpia::symmetriser finds it or says there is none);
  without one, lambda_min comes from the power method on I - B.
- ``"gs"``: Gauss-Seidel, the SOR-PIA sweep with omega = 1.
- ``"sor"``: SOR-PIA (paper eq. 18), vertices in input order:
  d_i = (v_i^0 - v_i^inf) / alpha_i with the neighbours already updated in
  this sweep, then v_i += omega d_i (alpha_i = B_ii). E_k is computed inside
  the sweep (one pass over the mesh per iteration, the same values as a
  separate residual pass, or by such a pass where most residuals would wait
  for the end of the sweep); ``threads=N`` sweeps N index ranges (or, where
  ranges would share many vertices, N slabs across the mesh) in parallel,
  the vertices they share last. A mesh whose vertex order is very poor
  (shuffled) is swept in a breadth-first order and returned in its own order.
- ``"cg"``: on closed meshes B = Gamma Upsilon (paper section 3.2) with
  Gamma = diag((1 - alpha_i)/n_i) and Upsilon symmetric positive definite:
  conjugate gradients on Upsilon V = Gamma^-1 V0, one product per iteration.
  Catmull-Clark on a closed quad mesh: Gamma = diag(1 / (n_i (n_i + 5))),
  Upsilon with n_i^2 on the diagonal, 4 on edges and 1 across quads (closed
  meshes with other polygons: the Gamma sorpia::symmetriser finds). On
  meshes with boundary, rows of boundary vertices ignore interior neighbours
  that do see them, so Upsilon is not symmetric (nor where no diagonal Gamma
  symmetrises the rows): "cg" then runs BiCGSTAB (van der Vorst 1992) on
  Gamma^-1 B V = Gamma^-1 V0 (two products per iteration); ``result.variant``
  says which ran.
- ``"hss"``: Bai, Golub and Ng (2003) on B V = V0, H = (B + B^T)/2,
  S = (B - B^T)/2::

      (alpha I + H) U       = (alpha I - S) V^(k) + V0
      (alpha I + S) V^(k+1) = (alpha I - H) U     + V0

  alpha = sqrt(lambda_min(H) lambda_max(H)) (both by one Lanczos run on H). The
  first system is solved by CG; the second by CG on
  (alpha^2 I - S^2) V = (alpha I - S) c, which is SPD because S^T = -S. Inner
  solves are warm-started and stop at a residual of 1e-3 E_k.
- ``"whss"``: the HSS step relaxed, V^(k+1) <- V^(k) + w (HSS(V^(k)) - V^(k)),
  w = 2 / (2 - mu_min - mu_max) by default, mu = (alpha - l) / (alpha + l) at
  l = lambda_max(H) and lambda_min(H): for S = 0 the HSS iteration matrix is
  (alpha I - H)(alpha I + H)^-1 with eigenvalues in [mu_min, mu_max], and this
  w centres them on 0. At the default alpha they are centred already, so w = 1
  and "whss" equals "hss" unless alpha or weight is given.

omega for "sor": a float in (0, 2); ``"young"``, the paper's Remark 1,
omega = 2 / (1 + sqrt(1 - rho^2)) with rho = rho(I - D^-1 B) by the power
method (a lower bound of the true rho); rho >= 0.9999 (rho >= 1 is the usual
case on real meshes, where the formula has no real value) warns with
OmegaWarning and uses rho = 0.9999, omega = 1.9720; ``"auto"`` (default):
omega = 1 (sorpia::sor_auto_omega): bench/omega_study.py finds the fastest
fixed omega close to 1 on every mesh it runs, and only omega = 1 never needs
more sweeps than Gauss-Seidel (figures on the omega study's page of the docs).
"""

from __future__ import annotations

import math
import numbers
import time
import warnings
from typing import Callable, Optional

import numpy as np

from . import _core
from ._validate import DEFAULT_BOUNDARY, DEFAULT_SCHEME, as_boundary, as_scheme, as_vertices
from .errors import ParameterError
from .limit import TAGS_DOC as _TAGS_DOC
from .limit import tags as _tags
from .limit import topology as _topology

METHODS = tuple(_core.method_names())  # the core's one list, in its order
OMEGA_RULES = ("auto", "young")
THREADED_METHODS = ("sor", "gs")  # the methods that sweep on threads > 1
YOUNG_RHO_CLAMP = float(_core.YOUNG_RHO_CLAMP)
MAX_THREADS = int(_core.MAX_THREADS)
_INT64_MAX = 2**63 - 1


class ConvergenceWarning(UserWarning):
    """A solve stopped at max_iter or diverged before reaching tol."""


class OmegaWarning(UserWarning):
    """omega="young" met rho(I - D^-1 B) >= 0.9999: Young's formula has no real value (rho >= 1) or none of use."""


# The one result type, defined in the core's binding (its docstring lists the fields).
InterpolationResult = _core.InterpolationResult


def _real(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name} must be a real number, got {value!r}")
    return float(value)


def _integer(value, name: str, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ParameterError(f"{name} = {value!r} must be {what}")
    return min(int(value), _INT64_MAX)  # beyond any limit: the core names it as too large


def check_options(method: str = "sor", omega="auto", tol: float = 1e-10, max_iter: int = 1000,
                  callback: Optional[Callable[[int, float], object]] = None, *, sigma=None, alpha=None,
                  weight=None, threads: int = 1) -> _core.SolveOptions:
    """The solver options, checked: what `interpolate` and `Interpolator.solve`
    accept, with the same messages (sorpia.ParameterError), before any work.

    Python types are converted here (a bool, a string or None where a number
    belongs is refused); every range and which options apply to which method
    are checked once, by the core (sorpia::check_options), for Python, the
    command line and C++ alike.
    """
    if not isinstance(method, str):
        raise ParameterError(f"method must be a string, got {method!r}")
    method_value = _core.parse_method(method)
    if isinstance(omega, str):
        rule, omega_value = _core.parse_omega(omega)
    else:
        rule, omega_value = _core.OmegaRule.given, _real(omega, "omega")
    if callback is not None and not callable(callback):
        raise ParameterError(f"callback = {callback!r} must be callable (k, error) or None")
    return _core.SolveOptions(
        method=method_value, omega_rule=rule, omega=omega_value,
        sigma=None if sigma is None else _real(sigma, "sigma"),
        alpha=None if alpha is None else _real(alpha, "alpha"),
        weight=None if weight is None else _real(weight, "weight"),
        tol=_real(tol, "tol"), max_iter=_integer(max_iter, "max_iter", "an integer >= 1"),
        threads=min(_integer(threads, "threads", "an integer >= 1"), 2**31 - 1))


class Interpolator:
    """Build once, solve many: the topology and the limit operator B of one mesh.

    Parameters
    ----------
    faces : array_like (m, k) int, list of polygons or sorpia.Polygons
        Faces, consistently oriented, manifold: triangles for Loop, any
        polygons for Catmull-Clark.
    n_vertices : int
        Number of vertices, an int or numpy integer >= 0 checked as
        `sorpia.limit_matrix` checks it (a float, even 12.0, or a bool raises
        TypeError; a count below the largest face index + 1, MeshError).
        Vertices no face references pass through unchanged, with an
        UnreferencedVerticesWarning.
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule, see sorpia.limit_points.
    scheme : {"loop", "catmull-clark"}
        The subdivision scheme whose limit surface interpolates, see sorpia.limit_points.
    {tags}

    The spectral estimates a method needs (lambda_min for "wpia", rho for
    omega="young", H's extremes for "hss"/"whss", ...) are computed on first
    use and kept, so that running every method on one mesh pays for them once.
    """

    def __init__(self, faces, n_vertices: int, boundary: str = DEFAULT_BOUNDARY, *, scheme: str = DEFAULT_SCHEME,
                 creases=None, corners=None, holes=None):
        self._build(faces, n_vertices, boundary, scheme, "n_vertices", (creases, corners, holes))

    @classmethod
    def _for_vertices(cls, faces, n_vertices: int, boundary: str, scheme: str, tags: tuple) -> Interpolator:
        """As Interpolator(faces, n_vertices, boundary, scheme=, creases=, corners=,
        holes=), for interpolate(): its messages call the count len(vertices),
        the rows of the caller's array."""
        self = cls.__new__(cls)
        self._build(faces, n_vertices, boundary, scheme, "len(vertices)", tags)
        return self

    def _build(self, faces, n_vertices, boundary, scheme, count_name: str, tags: tuple) -> None:
        t0 = time.perf_counter()
        self._boundary = as_boundary(boundary)
        self.boundary = _core.boundary_name(self._boundary)
        self._scheme = as_scheme(scheme)
        self.scheme = _core.scheme_name(self._scheme)
        # validates n_vertices as limit_matrix does (as_vertex_count: no float, bool or negative count)
        self.topology = _topology(faces, n_vertices, scheme=self.scheme, count_name=count_name)
        self.n_vertices = self.topology.n_vertices
        self.tags = _tags(self.topology, *tags)
        t1 = time.perf_counter()
        self._operator = _core.LimitOperator(self.topology, self._boundary, self.tags, self._scheme)
        t2 = time.perf_counter()
        self.build_timings = {"topology": t1 - t0, "operator": t2 - t1}

    @property
    def closed(self) -> bool:
        """True when B = Gamma Upsilon with Upsilon symmetric ("cg" runs CG, not BiCGSTAB)."""
        return bool(self._operator.symmetrisable)

    def limit_matrix(self) -> scipy.sparse.csr_matrix:
        """B as a scipy CSR matrix: the operator the solvers use, as `sorpia.limit_matrix` gives it."""
        import scipy.sparse  # here, not at import: sorpia's commands need no scipy

        n = self.n_vertices
        return scipy.sparse.csr_matrix(self._operator.limit_matrix(), shape=(n, n))

    def solve(self, vertices, method: str = "sor", omega="auto", tol: float = 1e-10, max_iter: int = 1000,
              callback: Optional[Callable[[int, float], object]] = None, *, sigma=None, alpha=None, weight=None,
              threads: int = 1) -> InterpolationResult:
        """Solve B V = V0 for the control vertices V.

        Parameters
        ----------
        vertices : array_like, (n, 3) float
            V0, finite; n must equal the n_vertices given at construction.
        method : {"sor", "gs", "pia", "wpia", "cg", "hss", "whss"}
        omega : float in (0, 2), "auto" or "young"
            SOR relaxation ("sor" only; other methods accept only the default).
        tol : float > 0
            Stop when E_k / E_0 < tol.
        max_iter : int >= 1
        callback : callable(k, error) or None
            Called with k = 0, 1, ... and error = E_k / E_0 as each E_k is
            known; a true return value stops the run (stop_reason "callback",
            no warning). None costs nothing per iteration.
        sigma : float in (0, 2), "wpia" only
            Step; default 2 / (lambda_min(B) + 1).
        alpha : float > 0, "hss"/"whss" only
            Shift; default sqrt(lambda_min(H) lambda_max(H)).
        weight : float in (0, 2), "whss" only
            Relaxation weight; default 2 / (2 - mu_min - mu_max) (module docstring).
        threads : int >= 1, "sor"/"gs" only
            Threads sweeping at once. The vertices are split into one
            contiguous index range per thread (renumbered into slabs across
            the mesh first when more than 1/16 of them would have a
            neighbour in another range), swept in parallel in vertex
            order, then the vertices with a neighbour in another range:
            Gauss-Seidel in a slightly different vertex order, so the
            iterates differ from threads=1 by that ordering (the solution
            agrees to the tolerance, iteration counts within a few percent)
            and do not depend on timing. 1 (default) on one core; more than
            the cores free only slows down. control_vertices are always in
            the input order.

        Returns
        -------
        InterpolationResult
            Warns with ConvergenceWarning when tol was not reached (max_iter,
            divergence) and with OmegaWarning when omega="young" met rho >= 0.9999.
        """
        t0 = time.perf_counter()
        options = check_options(method, omega, tol, max_iter, callback, sigma=sigma, alpha=alpha, weight=weight,
                                threads=threads)
        return self._solve(as_vertices(vertices), method, options, callback, t0)

    def _solve(self, v0: np.ndarray, method: str, options: _core.SolveOptions, callback,
               t0: float) -> InterpolationResult:
        """solve() on input already validated: `v0` from as_vertices, `options`
        from check_options (interpolate validates both before building B and
        calls this). Warnings point at the caller of solve() or interpolate()."""
        tol_value, max_iter = options.tol, options.max_iter
        if v0.shape[0] != self.n_vertices:
            raise ParameterError(f"vertices has {v0.shape[0]} rows but the mesh has {self.n_vertices} vertices")
        r = self._operator.solve(v0, options, callback)
        seconds = time.perf_counter() - t0
        if r.omega_clamped:
            warnings.warn(
                f"omega='young': rho(I - D^-1 B) = {r.rho:.6f} >= {YOUNG_RHO_CLAMP}, where Young's formula "
                f"(paper Remark 1) has no real value (rho >= 1) or none of use; rho clamped to {YOUNG_RHO_CLAMP}, "
                f"omega = {r.omega:.4f} (slow: omega='auto' is the measured choice)",
                OmegaWarning, stacklevel=3)
        reason = r.stop_reason
        if reason in ("max_iter", "diverged"):
            what = (f"reached max_iter = {max_iter}" if reason == "max_iter"
                    else "diverged (E_k grew past 1e6 E_0 or was not finite)")
            warnings.warn(f"method={method!r} {what} with E_k/E_0 = {r.errors[-1]:.3g} > tol = {tol_value:g}",
                          ConvergenceWarning, stacklevel=3)
        r._record_build(time.perf_counter() - t0, 0.0, 0.0)
        return r


Interpolator.__doc__ = Interpolator.__doc__.replace("{tags}", _TAGS_DOC)


def interpolate(vertices, faces, method: str = "sor", omega="auto", tol: float = 1e-10, max_iter: int = 1000,
                boundary: str = DEFAULT_BOUNDARY, callback: Optional[Callable[[int, float], object]] = None, *,
                sigma=None, alpha=None, weight=None, threads: int = 1, scheme: str = DEFAULT_SCHEME,
                creases=None, corners=None, holes=None) -> InterpolationResult:
    """Control vertices whose limit surface (Loop, or Catmull-Clark with
    ``scheme="catmull-clark"``) interpolates ``vertices``.

    One call of ``Interpolator(faces, len(vertices), boundary, scheme=,
    creases=, corners=, holes=).solve(...)``; see `Interpolator` for the
    scheme and the tags, `Interpolator.solve` for the other parameters and the
    module docstring for
    the methods and their formulas. `seconds` and `timings` include building
    the topology and B.

    Examples
    --------
    >>> V, F = sorpia.shapes.icosphere(3)
    >>> res = sorpia.interpolate(V, F)                   # SOR-PIA, omega="auto"
    >>> np.allclose(sorpia.limit_points(res.control_vertices, F), V, atol=1e-9)
    True
    """
    t0 = time.perf_counter()
    # Options are checked before the (costly) operator is built.
    options = check_options(method, omega, tol, max_iter, callback, sigma=sigma, alpha=alpha, weight=weight,
                            threads=threads)
    v0 = as_vertices(vertices)
    interp = Interpolator._for_vertices(faces, v0.shape[0], boundary, scheme, (creases, corners, holes))
    res = interp._solve(v0, method, options, callback, t0)
    res._record_build(time.perf_counter() - t0, interp.build_timings["topology"], interp.build_timings["operator"])
    return res
