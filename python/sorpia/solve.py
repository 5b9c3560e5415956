"""Subdivision surface interpolation: solve B V = V0 with SOR-PIA and the PIA family.

B is the limit matrix of the Loop or Catmull-Clark surface (paper eq. 7, as
OpenSubdiv evaluates it; ``scheme=``), V0 the
(n, 3) mesh vertices, V the control vertices whose limit surface passes through
V0. Every method starts from V = V0 (or a warm start, ``initial=``) and stops
by the paper's rule (section 5): E_k = max_i ||v_i^0 - (B V^(k))_i||, stop when
E_k / E_0 < tol or at max_iter, E_0 always that of the cold start V = V0.

Any per-vertex data can be interpolated on the limit surface: V0 may be
(n, k) for any k >= 1 (colours, texture coordinates, a scalar field as
(n, 1)); E_k is then the Euclidean norm over the k components.
`Interpolator.update` re-solves locally after a few targets move.

Methods (the iteration itself runs in the C++ core):

- ``"auto"`` (default): ``"sor"`` watched over its sweeps; at the first sign
  of divergence (E_k not below E_{k-5}) or of a rate too slow to reach tol
  within max_iter (the contraction of the last 5 sweeps, from sweep 10 on),
  ``"gmres"``, which converges on any invertible B; where that stalls (B
  singular), ``"cgls"``: the least-squares control mesh of least norm, with
  a `SingularMatrixWarning` naming where the targets are missed.
  ``result.variant`` says which method made the result, ``result.attempts``
  what was tried. Where "sor" converges it costs nothing more than "sor".

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
- ``"gmres"``: GMRES(m) (Saad and Schultz 1986) on D^-1 B V = D^-1 V0
  (Jacobi preconditioning, D = diag(B)), restart length 30, doubled after a
  cycle that leaves the residual above 0.9 of its start (up to the longest basis that fits
  in 512 MiB, or n: full GMRES, exact on any invertible B); E_k of the
  current iterate at every Arnoldi step (one product each). A cycle that
  leaves the residual where it was (ratio above 0.999) stops as "stalled":
  B is singular, or (rarely) a restarted GMRES stagnates.
- ``"cgls"``: CG on the normal equations B^T B V = B^T V0 (LSQR's iterates),
  two products per iteration: the least-squares solution nearest the start
  for any B; from ``initial=np.zeros_like(V0)`` (where "auto" starts it) the
  least-squares solution of least norm. Where the normal
  equations are solved and E_k / E_0 is still above tol it stops as
  "singular".
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
import time
import warnings
import weakref
from typing import Callable, Optional

import numpy as np

from . import _core, _scipy
from ._mesh import mesh_arguments, mesh_count
from ._nonmanifold import folded, split
from ._scipy import CSRMatrix
from ._validate import (DEFAULT_BOUNDARY, DEFAULT_NONMANIFOLD, DEFAULT_SCHEME, as_boundary, as_integer,
                        as_nonmanifold, as_real, as_rules, as_vertex_count, as_vertices)
from .errors import ConvergenceWarning, OmegaWarning, ParameterError, SingularMatrixWarning
from .limit import NONMANIFOLD_DOC as _NONMANIFOLD_DOC
from .limit import TAGS_DOC as _TAGS_DOC
from .limit import singular_cubes
from .limit import built, warn_unreferenced

METHODS = tuple(_core.method_names())  # the core's one list, in its order
OMEGA_RULES = ("auto", "young")
THREADED_METHODS = ("sor", "gs", "auto")  # the methods that sweep on threads > 1 (auto: its sor run)
YOUNG_RHO_CLAMP = float(_core.YOUNG_RHO_CLAMP)
MAX_THREADS = int(_core.MAX_THREADS)


# The one result type, defined in the core's binding (its docstring lists the fields).
InterpolationResult = _core.InterpolationResult


def check_options(method: str = "auto", omega="auto", tol: float = 1e-10, max_iter: int = 1000,
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
        rule, omega_value = _core.OmegaRule.given, as_real(omega, "omega")
    if callback is not None and not callable(callback):
        raise ParameterError(f"callback = {callback!r} must be callable (k, error) or None")
    return _core.SolveOptions(
        method=method_value, omega_rule=rule, omega=omega_value,
        sigma=None if sigma is None else as_real(sigma, "sigma"),
        alpha=None if alpha is None else as_real(alpha, "alpha"),
        weight=None if weight is None else as_real(weight, "weight"),
        tol=as_real(tol, "tol"), max_iter=as_integer(max_iter, "max_iter", "an integer >= 1"),
        threads=min(as_integer(threads, "threads", "an integer >= 1"), 2**31 - 1))


class Interpolator:
    """Build once, solve many: the topology and the limit operator B of one mesh
    (the core's sorpia::Interpolator).

    Parameters
    ----------
    faces : array_like (m, k) int, list of polygons, sorpia.Polygons or sorpia.SubdivisionMesh
        Faces, consistently oriented, manifold: triangles for Loop, any
        polygons for Catmull-Clark; or a mesh (``Interpolator(mesh)``: its
        faces, vertex count and rules).
    n_vertices : int
        Number of vertices (not needed with a mesh), an int or numpy integer >= 0 checked as
        `sorpia.limit_matrix` checks it (a float, even 12.0, or a bool raises
        TypeError; a count below the largest face index + 1, MeshError).
        Vertices no face references pass through unchanged, with an
        UnreferencedVerticesWarning.
    scheme : {"auto", "loop", "catmull-clark"}
        The subdivision scheme whose limit surface interpolates, see
        sorpia.limit_points ("auto", the default: Loop when every face is a
        triangle, else Catmull-Clark).
    boundary : {"edge-and-corner", "edge-only"}
        Boundary rule, see sorpia.limit_points.
    {tags}
    {nonmanifold}
        With "sharp", solves and updates take and return the rows of the
        caller's vertices (the split's copies follow their vertex).

    The spectral estimates a method needs (lambda_min for "wpia", rho for
    omega="young", H's extremes for "hss"/"whss", ...) are computed on first
    use and kept, so that running every method on one mesh pays for them once.

    The Interpolator also keeps the targets of its last `solve` (a copy), which
    `update` moves: see `targets` and `update`.
    """

    def __init__(self, faces, n_vertices: Optional[int] = None, *, scheme: str = DEFAULT_SCHEME,
                 boundary: str = DEFAULT_BOUNDARY, creases=None, corners=None, holes=None,
                 nonmanifold: str = DEFAULT_NONMANIFOLD):
        faces, n_vertices, rules = mesh_count(faces, n_vertices, dict(
            scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes, nonmanifold=nonmanifold),
            "Interpolator")
        nonmanifold = rules.pop("nonmanifold")
        self._build(faces, n_vertices, "n_vertices", rules, nonmanifold)

    @classmethod
    def _for_vertices(cls, faces, n_vertices: int, rule_options: dict, nonmanifold: str) -> Interpolator:
        """As Interpolator(faces, n_vertices, nonmanifold=, **rule_options),
        for interpolate(): its messages call the count len(vertices), the rows
        of the caller's array."""
        self = cls.__new__(cls)
        self._build(faces, n_vertices, "len(vertices)", rule_options, nonmanifold)
        return self

    def _build(self, faces, n_vertices, count_name: str, rule_options: dict, nonmanifold: str) -> None:
        # nonmanifold="sharp": the core solves the manifold split, with the
        # caller's vertices in and out (sorpia::Interpolator's vertex_map).
        self._split = None
        boundary = rule_options["boundary"]
        if as_nonmanifold(nonmanifold) == "sharp":
            tags = {kind: rule_options[kind] for kind in ("creases", "corners", "holes")}
            self._split = split(faces, as_vertex_count(n_vertices, count_name),
                                                  rule_options["boundary"], **tags)
        vertex_map = None
        if self._split is not None:
            faces, n_vertices, vertex_map = self._split.faces, len(self._split.vertex_map), self._split.vertex_map
            rule_options = {**rule_options, "boundary": self._split.boundary, "creases": None, "corners": None,
                            "holes": None, **self._split.tags}
        arrays, n, rules = as_rules(faces, n_vertices, count_name=count_name, **rule_options)
        self._impl = built(lambda: _core.Interpolator(*arrays, n, rules, vertex_map=vertex_map))
        self.topology = self._impl.topology
        warn_unreferenced(self.topology, stacklevel=5)
        self.n_vertices = self._impl.n_vertices
        self.scheme = _core.scheme_name(rules.scheme)
        # the caller's rule (a split may be solved under another that gives the same rows: nonmanifold.split)
        self.boundary = _core.boundary_name(as_boundary(boundary))
        self.tags = rules.tags
        # the rules the core solves under (a split's with nonmanifold="sharp")
        self._rules = rules
        self.build_timings = self._impl.build_timings
        self._last_update = None  # weak reference to the result the last update returned
        self._solved_method = None  # the method of the last solve keeping its targets

    @property
    def targets(self) -> Optional[np.ndarray]:
        """A copy of the targets `update` moves: those of the last `solve`, moved
        by every `update` since; None before the first solve."""
        return self._impl.targets

    @property
    def closed(self) -> bool:
        """True when B = Gamma Upsilon with Upsilon symmetric ("cg" runs CG, not BiCGSTAB)."""
        return bool(self._impl.symmetrisable)

    def limit_matrix(self) -> CSRMatrix:
        """B as a scipy CSR matrix: the operator the solvers use, as `sorpia.limit_matrix` gives it."""
        sparse = _scipy.sparse("Interpolator.limit_matrix")

        data, indices, indptr = self._impl.limit_matrix()
        b = sparse.csr_matrix((data, indices, indptr), shape=(len(indptr) - 1, len(indptr) - 1))
        if self._split is not None:  # the split's rows of the caller's vertices, copies' columns added
            return folded(b, self._split.vertex_map, self.n_vertices)
        return b

    def solve(self, vertices, method: str = "auto", omega="auto", tol: float = 1e-10, max_iter: int = 1000,
              callback: Optional[Callable[[int, float], object]] = None, *, sigma=None, alpha=None, weight=None,
              threads: int = 1, initial=None) -> InterpolationResult:
        """Solve B V = V0 for the control vertices V.

        Parameters
        ----------
        vertices : array_like, (n, 3) or (n, k) float
            V0, finite; n must equal the n_vertices given at construction.
            Any k >= 1 columns: every column is interpolated on the limit
            surface, E_k is the largest Euclidean norm of a row of the
            residual over all k. The Interpolator keeps a copy, the targets
            of later `update` calls.
        method : {"auto", "sor", "gs", "pia", "wpia", "cg", "hss", "whss", "gmres", "cgls"}
            "auto" (default) runs "sor" and falls back to "gmres" (then
            "cgls" where B is singular) at the first sign that "sor" will
            not reach tol: see the module docstring.
        omega : float in (0, 2), "auto" or "young"
            SOR relaxation ("sor", and "auto"'s "sor" run; other methods accept only the default).
        tol : float > 0
            Stop when E_k / E_0 < tol.
        max_iter : int >= 1
        callback : callable(k, error) or None
            Called with k = 0, 1, ... and error = E_k / E_0 as each E_k is
            known; a true return value stops the run (stop_reason "callback",
            no warning). None costs nothing per iteration. Under "auto", k
            counts on across its runs (a fallback's E_k follow "sor"'s).
        sigma : float in (0, 2), "wpia" only
            Step; default 2 / (lambda_min(B) + 1).
        alpha : float > 0, "hss"/"whss" only
            Shift; default sqrt(lambda_min(H) lambda_max(H)).
        weight : float in (0, 2), "whss" only
            Relaxation weight; default 2 / (2 - mu_min - mu_max) (module docstring).
        threads : int >= 1, "sor"/"gs"/"auto" only (the fallbacks of "auto" run on one thread)
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
            the input order. With more than 3 columns of data, 1 only.
        initial : array_like, same shape as ``vertices``, or None
            A warm start V^(0) (e.g. the previous frame's control_vertices),
            for every method; finite and at most 1e150 times the targets'
            scale (1, or about the largest magnitude in V0 for targets
            beyond 2^+-200, which the solvers scale exactly), so that no
            squared norm overflows. The stopping rule is unchanged: E_0 is
            the error of the cold start V = V0, so the result meets the same
            E_k / E_0 < tol; history[0] = E(initial) / E_0 and iterations
            count from the warm start (0 when it already meets tol); a start
            far off iterates (divergence is measured against the larger of
            E_0 and the start's error).

        Returns
        -------
        InterpolationResult
            Warns with ConvergenceWarning when tol was not reached (max_iter,
            divergence: the result is then the iterate of the lowest E_k, and
            the message names the method that would work), with
            SingularMatrixWarning when B is singular (the least-squares
            solution, stop_reason "singular") and with OmegaWarning when
            omega="young" met rho >= 0.9999.
        """
        t0 = time.perf_counter()
        options = check_options(method, omega, tol, max_iter, callback, sigma=sigma, alpha=alpha, weight=weight,
                                threads=threads)
        v0 = as_vertices(vertices, columns=None)
        return self._solve(v0, method, options, callback, t0, _as_initial(initial, v0), keep_targets=True)

    def update(self, previous: InterpolationResult, indices, positions, tol: float = 1e-10, max_iter: int = 1000,
               *, in_place: bool = False) -> InterpolationResult:
        """Move the targets at `indices` to `positions` and re-solve locally.

        Starts from ``previous.control_vertices`` and relaxes only the vertices
        whose residual is at least tol * E_0 (a work-list Gauss-Seidel:
        a vertex enters the list when its residual reaches the threshold,
        and leaves it relaxed), so the work stays near the moved targets: the
        change of the solution decays geometrically with the distance in rings.

        The targets are the Interpolator's: those of its last `solve`, moved by
        every update since (`targets`); this call moves them for good, so
        successive updates compose. The result meets the guarantee of a full
        solve of the new targets: E / E_0 < tol over the whole mesh, with E the
        largest residual row max_i ||v_i^0 - (B V)_i|| and E_0 that of the cold
        start V = V0, both for the new targets, or E at the rounding floor
        (64 eps max_i ||v_i^0||) as in a solve. With E_0 taken over the whole
        mesh, a small move may need no relaxation at all (its residual already
        below tol * E_0): the result is then previous's vertices.

        Parameters
        ----------
        previous : InterpolationResult
            The start: any result with the targets' shape, usually this
            Interpolator's last solve or update. Starting from the result the
            last update returned, whose residual the Interpolator keeps, costs
            O(work) only; any other start first computes its residual, O(n).
        indices : array_like of int, (m,)
            Vertices whose targets move; a repeated index takes its last position.
        positions : array_like, (m, k) float
            Their new targets (k the columns of the solved data).
        tol : float > 0
            As in `solve`.
        max_iter : int >= 1
            At most max_iter * n single-vertex relaxations (max_iter sweeps'
            worth); stop_reason "max_iter" with a ConvergenceWarning beyond.
        in_place : bool
            False (default): a new result, with a copy of previous's vertices
            (O(n) memory traffic). True: `previous` itself is updated and
            returned (its arrays show the new vertices; arrays taken from it
            before must not be written into, as the kept residual relies on
            them): for interactive loops on large meshes.

        Returns
        -------
        InterpolationResult
            method "gs", variant "local"; history = [E(previous) / E_0,
            E(result) / E_0] (only the first when nothing needed relaxing);
            iterations 1 when any vertex was relaxed, else 0; relaxations the
            single-vertex relaxations done; initial_error E_0 of the new targets.
            Where the local relaxation diverges (B indefinite, e.g. interior
            vertices of valence 2 next to faces of more than four sides), the new targets are solved in full by the
            last solve's method from previous, and the result is that solve's.
            An update that cannot meet tol (max_iter, or divergence of both)
            changes nothing — targets, kept residual, previous's vertices —
            and warns with ConvergenceWarning; its result holds previous's
            vertices and says why (stop_reason).

        Raises
        ------
        ParameterError
            Before anything changes: positions beyond 1e150 in magnitude
            (their squared norms would overflow; non-finite ones raise
            MeshError as vertices do), targets of the last solve beyond 1e150
            (the local relaxation does not rescale), an index that is not a
            vertex, previous of another shape.
        """
        t0 = time.perf_counter()
        if not isinstance(previous, InterpolationResult):
            raise ParameterError(f"previous must be an InterpolationResult, got {type(previous).__name__}")
        options = check_options(tol=tol, max_iter=max_iter)
        idx = np.asarray(indices)
        if idx.ndim == 0:
            idx = idx.reshape(1)
        if idx.ndim != 1 or not (np.issubdtype(idx.dtype, np.integer) or idx.size == 0):
            raise ParameterError(f"indices must be a 1-D array of vertex indices, got {idx.dtype} {idx.shape}")
        if idx.size and (idx.min() < np.iinfo(np.int32).min or idx.max() > np.iinfo(np.int32).max):
            bad = int(np.flatnonzero((idx < 0) | (idx >= self.n_vertices))[0])
            raise ParameterError(f"indices[{bad}] = {int(idx[bad])} is not a vertex (0..{self.n_vertices - 1})")
        idx = np.ascontiguousarray(idx, dtype=np.int32)
        targets_k = self._impl.targets_columns
        pos = np.asarray(positions)
        if pos.ndim == 1 and idx.size == 1:  # one vertex: its position alone
            pos = pos.reshape(1, -1)
        if targets_k == 0:  # no targets yet: the core says so
            pos = np.zeros((len(idx), 1))
        elif idx.size:
            pos = as_vertices(pos, "positions", columns=targets_k)
        else:
            pos = np.zeros((0, targets_k))
        if len(pos) != len(idx):
            raise ParameterError(f"positions has {len(pos)} rows but indices has {len(idx)}")
        last = self._last_update() if self._last_update is not None else None
        r, moved = self._impl.update(previous, last is previous, idx, pos, options.tol, options.max_iter,
                                     bool(in_place))
        if moved:
            self._last_update = weakref.ref(r)
        else:
            if r.variant == "local":
                what = f"reached max_iter = {options.max_iter} sweeps' worth of relaxations"
            else:  # the local relaxation diverged, and the full solve that followed stopped short
                what = (f"diverged, and method={self._solved_method!r} on the whole mesh stopped short "
                        f"({r.stop_reason})")
            warnings.warn(f"update {what} with E/E_0 = {r.history[-1]:.3g} > tol = {options.tol:g}: the targets "
                          "are left as they were, and the result holds previous's vertices", ConvergenceWarning,
                          stacklevel=2)
        r._record_build(time.perf_counter() - t0, 0.0, 0.0)
        return r

    def _solve(self, v0: np.ndarray, method: str, options: _core.SolveOptions, callback, t0: float,
               initial: Optional[np.ndarray] = None, keep_targets: bool = False,
               result: Optional[InterpolationResult] = None) -> InterpolationResult:
        """solve() on input already validated: `v0` from as_vertices, `options`
        from check_options, `initial` from _as_initial (interpolate validates
        them before building B and calls this). keep_targets: `update` moves
        these targets from now on. Warnings point at the caller of solve() or
        interpolate(). `result`: the core already ran this solve (fair
        interpolation's pipeline, sorpia::fair_interpolate): only what follows
        it here (state, warnings, wall time)."""
        r = self._impl.solve(v0, options, callback, initial, keep_targets) if result is None else result
        tol_value, max_iter = options.tol, options.max_iter
        if keep_targets:
            self._last_update = None
            self._solved_method = method
        seconds = time.perf_counter() - t0
        if r.omega_clamped:
            warnings.warn(
                f"omega='young': rho(I - D^-1 B) = {r.rho:.6f} >= {YOUNG_RHO_CLAMP}, where Young's formula "
                f"(paper Remark 1) has no real value (rho >= 1) or none of use; rho clamped to {YOUNG_RHO_CLAMP}, "
                f"omega = {r.omega:.4f} (slow: omega='auto' is the measured choice)",
                OmegaWarning, stacklevel=3)
        why = None
        if r.stop_reason in ("max_iter", "diverged", "stalled", "singular") and self.scheme == "catmull-clark":
            why = self._singular_cubes_message()
        _warn_stopped_short(r, method, tol_value, max_iter, why)
        r._record_build(time.perf_counter() - t0, 0.0, 0.0)
        return r


    def _singular_cubes_message(self) -> Optional[str]:
        """After a solve that stopped short: where B is singular in closed
        form (limit.singular_cubes), which no method can fit unless the
        targets lack the null vector's component; None when nowhere."""
        cubes = singular_cubes(self.topology, self.tags)
        if not cubes:
            return None
        return (f"B is singular on {len(cubes)} closed cube{'s' if len(cubes) > 1 else ''} of valence-3 vertices "
                f"(the first: vertices {cubes[0].tolist()}): under Catmull-Clark the alternating +1/-1 vector "
                "over a cube's corners is a null vector of B (3/8 - 3/6 + 3/24 = 0), so targets with a component "
                "along it cannot be interpolated there (docs: Catmull-Clark)")


Interpolator.__doc__ = Interpolator.__doc__.replace("{tags}", _TAGS_DOC).replace("{nonmanifold}", _NONMANIFOLD_DOC)


def _where(r: InterpolationResult) -> str:
    """'vertex 7 (|r| = 0.12), vertex 3 (0.05), ...': where the targets are missed most."""
    pairs = list(zip(r.worst_vertices.tolist(), r.worst_residuals.tolist()))[:5]
    return ", ".join(f"vertex {v} ({e:.3g})" for v, e in pairs)


def stopped_short_message(r: InterpolationResult, method: str, tol: float, max_iter: int) -> Optional[str]:
    """What a result that did not reach tol says to its user (the warning of
    `Interpolator.solve` and the command line's summary), or None."""
    reason = r.stop_reason
    if reason in ("converged", "callback"):
        return None
    final = f"E_k/E_0 = {r.history[-1]:.3g} > tol = {tol:g}"
    if reason == "singular":
        return (f"B is singular and the targets have a part outside its range: method={method!r} returns the "
                f"least-squares control mesh of least norm ({r.variant}), {final}; the targets are missed most at "
                f"{_where(r)} (result.worst_vertices)")
    tried = "" if len(r.attempts) < 2 else " (tried: " + ", ".join(
        f"{a['method']} {a['stop_reason']} after {a['iterations']}" for a in r.attempts) + ")"
    if reason == "diverged":
        final = (f"E_k/E_0 = {r.history[r.returned_iteration]:.3g} > tol = {tol:g} at iteration "
                 f"{r.returned_iteration}, the iterate returned (the lowest E_k; the run stopped at "
                 f"{r.history[-1]:.3g})")
    what = {"max_iter": f"reached max_iter = {max_iter}",
            "diverged": "diverged (E_k rose above a multiple of its lowest value, or was not finite)",
            "stalled": "stalled (no progress over a whole GMRES cycle: B is singular, or numerically so)"}[reason]
    advice = f"; use method={r.recommended!r}, which works here" if r.recommended else ""
    if r.recommended == "gmres" and method != "auto":
        advice += " (or the default 'auto', which falls back to it)"
    return f"method={method!r} {what}{tried} with {final}{advice}"


def _warn_stopped_short(r: InterpolationResult, method: str, tol: float, max_iter: int,
                        singular_where: Optional[str] = None) -> None:
    """The warnings of a result that did not reach tol: SingularMatrixWarning
    for the least-squares answer, ConvergenceWarning otherwise; and
    `singular_where` (where B is singular, when known) as a
    SingularMatrixWarning, in the same warning as the least-squares answer's."""
    text = stopped_short_message(r, method, tol, max_iter)
    if text is None:
        return
    if r.stop_reason == "singular":
        warnings.warn(text if singular_where is None else f"{text}. {singular_where}", SingularMatrixWarning,
                      stacklevel=4)
        return
    warnings.warn(text, ConvergenceWarning, stacklevel=4)
    if singular_where is not None:
        warnings.warn(singular_where, SingularMatrixWarning, stacklevel=4)


def _as_initial(initial, v0: np.ndarray) -> Optional[np.ndarray]:
    """A warm start checked against V0: None, or a finite float64 array of V0's shape."""
    if initial is None:
        return None
    arr = as_vertices(initial, "initial", columns=v0.shape[1])
    if arr.shape != v0.shape:
        raise ParameterError(f"initial has shape {arr.shape} but vertices has {v0.shape}")
    return arr


def interpolate(vertices, faces=None, method: str = "auto", omega="auto", tol: float = 1e-10, max_iter: int = 1000,
                callback: Optional[Callable[[int, float], object]] = None, *, scheme: str = DEFAULT_SCHEME,
                boundary: str = DEFAULT_BOUNDARY, creases=None, corners=None, holes=None,
                nonmanifold: str = DEFAULT_NONMANIFOLD,
                sigma=None, alpha=None, weight=None, threads: int = 1, initial=None) -> InterpolationResult:
    """Control vertices whose limit surface (``scheme="auto"``, the default:
    Loop when every face is a triangle, else Catmull-Clark) interpolates
    ``vertices``.

    ``interpolate(mesh)`` takes a `sorpia.SubdivisionMesh` (its vertices,
    faces and rules), ``interpolate(data, mesh)`` other per-vertex data on
    its faces; the other arguments then by keyword.

    ``vertices`` may be (n, k) data for any k >= 1 (every column interpolated);
    `initial` is a warm start, see `Interpolator.solve`. With
    ``nonmanifold="sharp"`` (see `limit_points`) a non-manifold mesh is solved
    with OpenSubdiv's rules for it, and the result's control_vertices are those
    of the input vertices.

    One call of ``Interpolator(faces, len(vertices), scheme=, boundary=,
    creases=, corners=, holes=).solve(...)``; see `Interpolator` for the
    rules and the tags, `Interpolator.solve` for the other parameters and the
    module docstring for the methods and their formulas. `seconds` and
    `timings` include building the topology and B.

    Examples
    --------
    >>> V, F = sorpia.shapes.icosphere(3)
    >>> res = sorpia.interpolate(V, F)                   # method="auto": SOR-PIA here
    >>> res.variant
    'sor'
    >>> np.allclose(sorpia.limit_points(res.control_vertices, F), V, atol=1e-9)
    True
    """
    vertices, faces, rule_options = mesh_arguments(vertices, faces, dict(
        scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes, nonmanifold=nonmanifold),
        "interpolate")
    nonmanifold = as_nonmanifold(rule_options.pop("nonmanifold"))
    t0 = time.perf_counter()
    # Options are checked before the (costly) operator is built.
    options = check_options(method, omega, tol, max_iter, callback, sigma=sigma, alpha=alpha, weight=weight,
                            threads=threads)
    v0 = as_vertices(vertices, columns=None)
    start = _as_initial(initial, v0)
    interp = Interpolator._for_vertices(faces, v0.shape[0], rule_options, nonmanifold)
    res = interp._solve(v0, method, options, callback, t0, start)
    res._record_build(time.perf_counter() - t0, interp.build_timings["topology"], interp.build_timings["operator"])
    return res
