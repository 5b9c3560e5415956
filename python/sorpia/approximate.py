"""Approximation of dense data by a light cage: control vertices whose limit
surface (Loop or Catmull-Clark, with OpenSubdiv's tags) lies close to many
points, in the least-squares sense.

The data points P (a scan, a point cloud, a dense mesh's vertices) are fitted
by the limit surface S(V) of a cage with control vertices V and fixed faces:

- **footpoints**: for each point p_i the closest point of S(V) as (face, u, v)
  in OpenSubdiv Bfr's parameterisation (`sorpia.surface`): the nearest of a
  grid of limit points (a k-d tree), then Gauss-Newton steps on (u, v) with
  Bfr's derivatives in a trust region, crossing into the neighbouring face
  where a step leaves the face (the core's ``sorpia::closest_points``);
- **rows**: the limit basis at the footpoints, A (one row per point, one
  column per control vertex; ``LimitSurface.rows``), so that A V are the
  footpoints' positions;
- **the update**: V minimising ``sum_i (A_i V - p_i)^T W_i (A_i V - p_i) +
  fairness m V^T K V + mu |V - V_prev|^2`` (W_i below; K the thin-plate
  energy, `sorpia.fairness_matrix` at depth 0; m the mean diagonal of the
  data term's normal matrix A^T W A), the normal equations ``(A^T W A +
  fairness m K + mu I) V = A^T W P + mu V_prev`` formed and solved in the core (``sorpia::NormalEquations``:
  the fitting layer's preconditioned conjugate gradients, Jacobi for the
  three coordinates; block Jacobi on the 3x3 blocks with ``tangential`` < 1,
  below), or by LSPIA (Deng and Lin 2014: each control vertex moves by the
  sum of its points' residuals weighted by the basis, divided by the sum of
  those weights). mu is 1e-6 of the mean diagonal of A^T W A: a
  proximal pull towards the previous control vertices which leaves the
  least-squares solution unchanged (it vanishes at a fixed point) and keeps a
  vertex no point influences where it is;
- W_i = I fits the points' full distances (point distance, ``tangential`` =
  1); below 1 the distance along the surface counts less (the default 0.1:
  ``W_i = tangential I + (1 - tangential) n_i n_i^T`` per point, n_i the
  normal at the footpoint: the tangent-distance fit of Marinov and Kobbelt
  and of Cheng, Wang et al., blended with the point distance);
- **parameter correction**: the footpoints re-projected onto the new surface
  (from their previous (face, u, v)), and again, until the lowest RMS
  distance falls by less than ``tol`` of itself per iteration over three
  iterations and a fresh search of every footpoint finds none closer
  enough to go on, or ``iterations``;
- with ``faces`` (a dense mesh's), the data is its surface: the points are
  samples of it weighted by area (`surface_samples`), so that the fit
  minimises a quadrature of the squared distance over the surface.

The whole run (footpoints, updates, stopping rule, records) is the C++
core's ``sorpia::approximate``; this module checks the arguments, samples a
dense mesh's surface and builds the result.

Distances are reported at every iteration from the data to the surface (the
footpoint distances), and for the returned iterate (at every iteration with
``report_each``) from the surface to the data (from the vertices of a
uniform tessellation of the limit surface, exact limit points, to the nearest
data point), as RMS and max, in model units and as fractions of the diagonal
of the data's bounding box.

The points are worked on in chunks (``chunk_points``, docs/approximation.md,
"Large data"), and may be streamed from a file given by its path.
"""

from __future__ import annotations

import os
import tempfile
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from . import _core, _dask
from ._mesh import SubdivisionMesh, mesh_arguments
from ._scipy import CSRMatrix
from ._validate import DEFAULT_BOUNDARY, DEFAULT_SCHEME, as_integer, as_polygons, as_real, as_vertices, resolve_scheme
from .errors import MeshError, ParameterError, SorpiaWarning
from .surface import LimitSurface

UPDATE_METHODS = ("cg", "lspia")
SAMPLINGS = ("area", "midpoints")
DEFAULT_UPDATE = "cg"
# The defaults of the fit's objective (docs/approximation.md, "The default", has the measurements): the
# tangent-distance blend, which removes most of point distance's slow footpoint slide, held by a small thin-plate
# term where few points hold the cage (without it the blend, and on cages with faces that no point reaches point
# distance too, let the surface stray or fly off between the points).
DEFAULT_TANGENTIAL = 0.1
DEFAULT_FAIRNESS = 3e-4
# The stopping rule's default: the blend goes on lowering the RMS distance by a few parts in a thousand per
# iteration on noisy data long after the surface has settled (fitting the noise); the scans' fits fall faster.
DEFAULT_TOL = 3e-3
# The robust fit (docs/approximation.md, "Robustness"): the losses, and the default one from the core, which also
# holds each loss's scale quantile and tuning constant c (sorpia::robust_options; _core.robust_options(loss)).
ROBUST_LOSSES = ("none", "cauchy", "tukey")
DEFAULT_ROBUST = _core.DEFAULT_ROBUST
# A fitted surface whose farthest point lies farther than this (in diagonals) from the data is warned about: it
# strays between points that do not hold the cage (e.g. fairness 0 with a cage as fine as the data).
_STRAY = 1.0
# Points per chunk (the core's ApproximationOptions::chunk_points): up to this many run as one array.
DEFAULT_CHUNK_POINTS = 1 << 20
# Points of a streamed file's fixed sample for the surface-to-data distances (a k-d tree of 4M points: ~200 MB).
DEFAULT_SAMPLE_POINTS = 1 << 22
# The coarse iterations (the core's ApproximationOptions::coarse_iterations, coarse_points, coarse_tol): at most
# coarse_iterations updates on a fixed sample of coarse_points per control vertex before those on all points, fewer
# where one lowers the sample's criterion by at most coarse_tol of it.
DEFAULT_COARSE_ITERATIONS = _core.DEFAULT_COARSE_ITERATIONS
DEFAULT_COARSE_POINTS = _core.DEFAULT_COARSE_POINTS
DEFAULT_COARSE_TOL = _core.DEFAULT_COARSE_TOL
# The stopping rule's window (the core's ApproximationOptions::window), for `_levelled`.
_WINDOW = 3


@dataclass
class ApproximationResult:
    """What `approximate` returns: the fitted cage, the footpoints of the data
    on its limit surface, and the distances per iteration.

    Attributes
    ----------
    control_vertices : (n, 3) float64
        The cage's new control vertices (faces and tags unchanged).
    face_ids : (k,) int32, uv : (k, 2) float64
        Footpoint of each data point on the final limit surface, as
        (face, u, v) in Bfr's parameterisation (`sorpia.surface`).
    distances : (k,) float64
        Distance of each data point to its footpoint.
    points : (k, 3) float64 or str
        The data points these belong to: `points` as given or, with
        ``faces``, the samples of the dense surface (`surface_samples`); for
        points streamed from a file, its path (and `face_ids`, `uv`,
        `distances` are empty: they are not kept).
    weights : (k,) float64 or None
        The points' weights in the fit and in the RMS distances, scaled to
        mean 1 (None: all equal).
    iterations : int
        Updates made (each followed by a re-projection of the footpoints),
        the coarse ones included.
    coarse_iterations : int
        Of them, the updates from the footpoints of the coarse sample only
        (``coarse_iterations`` of `approximate`; 0 where none ran).
    converged : bool
        True when the run stopped before ``iterations`` ran out
        (``stop_reason`` other than "max_iter").
    stop_reason : str
        Why the run stopped: "converged" (the lowest RMS distance fell by
        less than ``tol`` of itself per iteration over the last three, and
        a fresh search of every footpoint found none closer enough to go
        on), "exact" (the RMS distance is at rounding level, 1e-13 of the
        diagonal), or "max_iter" (``iterations`` ran out; "iterations"
        until this release), the names every sorpia result uses.
    best_iteration : int
        The iteration whose control vertices and footpoints are returned:
        that of the lowest RMS distance (an update that raised it is not
        returned); `rms`, `max_error` and the report's ``final`` are its
        record's, measured after a fresh search of every footpoint on its
        surface (the closer kept: `distances`, `face_ids` and `uv` are those).
    method : str
        The update that ran, "cg" or "lspia".
    fairness : float
        The weight of the fairness term.
    tangential : float
        The weight of the distance along the surface that ran (the default
        resolved: 0.1 for CG, 1 for LSPIA).
    diagonal : float
        The diagonal of the data points' bounding box, the unit of the
        relative distances.
    history : list of dict
        One record per iteration, from 0 (the cage as given): ``iteration``,
        ``points`` (the points its distances are of: all, or the coarse
        sample's before the last coarse update), ``rms``, ``max`` (data to
        surface), ``surface_rms``, ``surface_max``
        (surface to data: in the returned iterate's record, and in the
        others only with ``report_each``, else None), each also
        ``_relative`` (divided by ``diagonal``),
        ``move_max_relative`` and ``move_rms_relative`` (how far the update
        before it moved the control vertices, largest and RMS, over the
        diagonal; 0 at iteration 0), ``solver_iterations`` (of the update
        before it; 0 at iteration 0) and ``seconds`` (since the start).
    timings : dict
        Seconds spent in each phase: ``footpoints``, ``rows`` (the rows of
        the surface at the footpoints, a face's points at a time, each
        face's share of A^T A and A^T P added in as it is made),
        ``normal`` (the rest of forming A^T A and A^T P: the whole matrix
        from its upper triangle, the chunks' sums added), ``solve``,
        ``report`` (surface to data),
        ``total`` (`seconds`); and ``cpu``: the process's CPU seconds of
        each (all threads). With ``client``, also ``cluster``: ``workers``,
        ``chunks``, ``chunk_points``, ``worker_seconds`` and
        ``worker_cpu_seconds`` (the workers' wall and CPU seconds per call
        of the driver, summed over the chunks: ``search``, ``refine``,
        ``normal_sums``, ...), ``bytes_to_workers`` (of the arrays sent: the
        points once, the control vertices each iteration) and
        ``bytes_from_workers`` (per call: the chunks' sums back).
    mesh : sorpia.SubdivisionMesh or None
        The fitted cage: the control vertices on the cage's faces, with its
        scheme, boundary rule and tags.
    robust : str
        The robust loss that ran ("none": least squares).
    robust_scale : float
        The scale s of the returned iterate's distances (0 with "none"); the
        records' ``robust_scale`` the scale of each iteration's.
    robust_outliers : int
        The points (of weight > 0) farther than c s from the returned
        surface (with "tukey": the points that did not pull on it): its
        record's ``robust_cut``. The records also give the loss's RMS
        (``robust_loss``) and the RMS distance of the points within c s
        (``inlier_rms``), in model units and ``_relative`` to the diagonal.

    `rms` and `max_error` (the largest distance of a data point to the
    returned surface; ``max_distance`` until this release, a deprecated
    alias now), `seconds` (timings["total"]) and ``report()`` as every
    sorpia result names them.
    """

    control_vertices: np.ndarray
    face_ids: np.ndarray
    uv: np.ndarray
    distances: np.ndarray
    points: np.ndarray
    weights: Optional[np.ndarray]
    iterations: int
    stop_reason: str
    best_iteration: int
    method: str
    fairness: float
    tangential: float
    diagonal: float
    history: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    mesh: Optional[SubdivisionMesh] = None
    n_points: int = 0
    robust: str = "none"
    robust_scale: float = 0.0
    robust_outliers: int = 0
    coarse_iterations: int = 0

    @property
    def converged(self) -> bool:
        """True when the run stopped before ``iterations`` ran out."""
        return self.stop_reason != "max_iter"

    @property
    def seconds(self) -> float:
        """Wall time of the whole call, timings["total"]."""
        return self.timings["total"]

    @property
    def rms(self) -> float:
        """RMS distance of the data points to the returned limit surface."""
        return self.history[self.best_iteration]["rms"]

    @property
    def max_error(self) -> float:
        """Largest distance of a data point to the returned limit surface."""
        return self.history[self.best_iteration]["max"]

    @property
    def max_distance(self) -> float:
        """Deprecated name of ``max_error`` (DeprecationWarning), for one release."""
        warnings.warn("ApproximationResult.max_distance is deprecated: use max_error (the same value; the name "
                      "every sorpia result uses)", DeprecationWarning, stacklevel=2)
        return self.max_error

    def report(self) -> dict:
        """The result as a JSON-ready dict (what ``sorpia approximate --report``
        writes): the history, the timings and the final figures, without the
        per-point arrays."""
        last = self.history[self.best_iteration]
        return {"iterations": self.iterations, "coarse_iterations": self.coarse_iterations,
                "converged": self.converged, "stop_reason": self.stop_reason,
                "rms": self.rms, "max_error": self.max_error, "seconds": self.seconds,
                "best_iteration": self.best_iteration, "method": self.method,
                "fairness": self.fairness, "tangential": self.tangential, "diagonal": self.diagonal,
                "robust": self.robust, "robust_scale": self.robust_scale, "robust_outliers": self.robust_outliers,
                "n_points": int(self.n_points),
                "n_control_vertices": int(self.control_vertices.shape[0]),
                "final": {k: v for k, v in last.items() if k not in ("iteration", "seconds")},
                "history": self.history, "timings": self.timings}


def _count(value, name: str, what: str) -> int:
    """An integer option as the core takes it (int): the type converted, clamped to int32 (the core names a value
    out of its range, once)."""
    return min(max(as_integer(value, name, what), -2**31), 2**31 - 1)


def _levelled(bests, tol: float) -> bool:
    """The stopping test on the lowest RMS distance after each iteration so
    far (non-increasing): True when over the last _WINDOW iterations it fell
    by at most tol of itself per iteration on average (with tol = 0: not at
    all). One small step between large ones does not stop a run. The core's
    rule (sorpia::rms_levelled), which approximate runs."""
    return _core.rms_levelled([float(b) for b in bests], float(tol), _WINDOW)


def _weights(weights, k: int) -> Optional[np.ndarray]:
    """The points' weights as float64 scaled to mean 1, or None for equal
    weights (ParameterError for a wrong shape, a negative or non-finite
    entry, or none positive)."""
    if weights is None:
        return None
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (k,):
        raise ParameterError(f"weights has shape {w.shape}: one weight per point, ({k},), is needed")
    bad = np.flatnonzero(~np.isfinite(w) | (w < 0))
    if len(bad):
        raise ParameterError(f"weights[{bad[0]}] = {w[bad[0]]!r} must be a finite number >= 0")
    total = float(w.sum())
    if not total > 0:
        raise ParameterError("weights are all 0: no point would count")
    return w * (k / total)


def surface_samples(vertices, faces, sampling: str = "area") -> tuple[np.ndarray, np.ndarray]:
    """Points and weights whose weighted sum of squared distances is a
    quadrature of the squared distance over a mesh's surface: ``sum_i w_i
    g(p_i)`` ~ the integral of g over the faces (polygons fanned into
    triangles from their first vertex).

    sampling "area": the vertices, each weighted by a third of the area of
    its triangles (exact for g linear on each triangle; a vertex no face
    uses weighs 0). "midpoints": the midpoints of the edges, each weighted by
    a third of the area of its triangles (exact for g quadratic on each
    triangle; about three times as many points as vertices).

    Parameters
    ----------
    vertices : array_like, (k, 3) float
        The mesh's vertices; finite.
    faces : array_like
        Its faces: an (m, 3) or (m, k) integer array, a list of polygons or
        `sorpia.Polygons`.
    sampling : {"area", "midpoints"}

    Returns
    -------
    points : (p, 3) float64, weights : (p,) float64
        The samples and their weights (the weights sum to the area).

    Raises
    ------
    sorpia.ParameterError
        Non-finite vertices, an unknown `sampling`.
    sorpia.MeshError
        A face with fewer than 3 vertices or an index out of range.
    """
    if sampling not in SAMPLINGS:
        raise ParameterError(f"sampling = {sampling!r} must be one of {', '.join(SAMPLINGS)}")
    vertices = as_points(vertices)
    counts, indices = as_polygons(faces, len(vertices), "faces", "len(points)")
    starts = np.concatenate([[0], np.cumsum(counts[:-1], dtype=np.int64)])
    # the fan of each polygon: (first, j, j + 1) for j = 1 .. count - 2
    fan = np.repeat(np.arange(len(counts)), counts - 2)
    j = np.arange(len(fan)) - np.repeat(np.cumsum(counts - 2) - (counts - 2), counts - 2) + 1
    tri = np.stack([indices[starts[fan]], indices[starts[fan] + j], indices[starts[fan] + j + 1]], axis=1)
    third = np.linalg.norm(np.cross(vertices[tri[:, 1]] - vertices[tri[:, 0]],
                                    vertices[tri[:, 2]] - vertices[tri[:, 0]]), axis=1) / 6.0
    if sampling == "area":
        weights = np.bincount(tri.ravel(), np.repeat(third, 3), minlength=len(vertices))
        return vertices, weights
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    weights = np.bincount(inverse.ravel(), np.tile(third, 3), minlength=len(unique))
    return np.ascontiguousarray(0.5 * (vertices[unique[:, 0]] + vertices[unique[:, 1]])), weights


def as_points(points) -> np.ndarray:
    """`points` as a C-contiguous (k, 3) float64 array of finite values, k >= 1
    (sorpia.MeshError naming the first bad row otherwise, as for vertices)."""
    arr = np.asarray(points) if not isinstance(points, np.ndarray) else points
    if arr.ndim == 2 and arr.shape[0] == 0:
        raise MeshError("points is empty: there is nothing to approximate")
    return as_vertices(arr, "points")


def _core_csr(K: CSRMatrix) -> tuple:
    """(data, indices, indptr) of a CSR matrix as the core's NormalEquations
    takes it (float64, int32, int32, contiguous)."""
    return (np.ascontiguousarray(K.data, dtype=np.float64), np.ascontiguousarray(K.indices, dtype=np.int32),
            np.ascontiguousarray(K.indptr, dtype=np.int32))


def approximate(points, cage_vertices, cage_faces=None, *, scheme: str = DEFAULT_SCHEME,
                boundary: str = DEFAULT_BOUNDARY,
                creases=None, corners=None, holes=None, iterations: int = 10, tol: float = DEFAULT_TOL,
                fairness: float = DEFAULT_FAIRNESS, tangential: Optional[float] = None,
                method: str = DEFAULT_UPDATE, solver_tol: float = 1e-3,
                solver_max_iter: int = 2000, grid: int = 4, newton_steps: int = 10, report_level: int = 2,
                report_each: bool = False,
                callback: Optional[Callable[[dict], object]] = None, weights=None, faces=None,
                sampling: Optional[str] = None, chunk_points: int = DEFAULT_CHUNK_POINTS,
                spill_directory=None, sample_points: int = DEFAULT_SAMPLE_POINTS,
                robust: str = DEFAULT_ROBUST, coarse_iterations: int = DEFAULT_COARSE_ITERATIONS,
                coarse_points: float = DEFAULT_COARSE_POINTS, coarse_tol: float = DEFAULT_COARSE_TOL,
                client=None) -> ApproximationResult:
    """Control vertices of a cage whose limit surface approximates `points`
    in the least-squares sense (the module docstring describes the method).

    Parameters
    ----------
    points : array_like, (k, 3) float, or str or os.PathLike
        The data: a point cloud or a dense mesh's vertices; finite, k >= 1.
        Or the path of a file whose points are streamed a chunk at a time,
        never all in memory (out of core; docs/approximation.md, "Large
        data"): a binary little-endian PLY (the vertex element's x, y, z as
        float or double, its other properties skipped, faces ignored) or a
        .npy array (k, 3) of float32 or float64 in C order; equally
        weighted (not with `weights` or `faces`).
    cage_vertices : array_like, (n, 3) float, or sorpia.SubdivisionMesh
        The cage's control vertices at the start (e.g. a decimated mesh);
        or the cage as a mesh, with its rules (``approximate(points,
        cage.mesh)``).
    cage_faces : array_like
        The cage's faces: triangles for Loop, any polygons for Catmull-Clark.
    scheme : {"auto", "loop", "catmull-clark"}
        "auto": Loop when every face is a triangle, else Catmull-Clark.
    boundary, creases, corners, holes
        The rules of the cage's limit surface, as in `sorpia.LimitSurface`.
    iterations : int >= 1
        Updates at most, each followed by a re-projection of the footpoints
        (parameter correction); the coarse ones included.
    tol : float >= 0
        Stop when the lowest RMS distance so far fell by less than this
        fraction of it per iteration over the last three iterations, and a
        fresh search of every footpoint (not only from where it was) does
        not lower it by more than this fraction either (it goes on from the
        closer footpoints when it does). With 0: when the lowest RMS did not
        fall at all over three iterations. The default, 3e-3, stops fits of
        noisy data where the blend goes on fitting the noise by a few parts
        in a thousand per iteration; the shared scans' fits fall faster and
        run their 10 iterations.
    fairness : float >= 0
        Weight of the thin-plate fairness term V^T K V (the energy shared with
        fair interpolation, `sorpia.fairness_matrix` with depth 0), relative
        to the mean diagonal of A^T W A; 0 for none. The default, 3e-4, holds
        the surface where few points hold the cage (a cage face that no point
        reaches, thin parts, boundaries) and moves the fit little elsewhere;
        with 0 the fit of points sampled on a cage's own limit surface
        returns that cage exactly, with 3e-4 within about the fairness term's
        pull.
    tangential : float in [0, 1], optional
        Weight of the distance along the surface: 1 fits each point's full
        distance to its footpoint (point distance, three independent
        coordinates, converging slowly: the footpoints must slide along the
        surface between updates); 0 its distance to the tangent plane there
        (tangent distance, one (3n, 3n) system of 3x3 blocks, converging much
        faster on clean data but ill-posed alone on scans); between, a blend.
        None (the default): 0.1, or 1 with method="lspia". Below 1 the
        surface between loosely held points strays farther unless the
        fairness term holds it; docs/approximation.md has the measurements.
    method : {"cg", "lspia"}
        The update: conjugate gradients on the normal equations (default:
        the faster, bench/approximate_speed.py), or LSPIA's iteration (with
        tangential=1 only).
    solver_tol, solver_max_iter
        Each update stops when the normal equations' residual is below
        solver_tol times its value at the start of the update, or after
        solver_max_iter iterations. Each update starts from the previous
        control vertices and the footpoints move after it, so a loose
        solve loses nothing: 1e-3 leaves the RMS distances of 1e-6 to 4
        digits at half the CG iterations (docs/approximation.md).
    grid : int 1..64
        Samples per side of each face's domain whose nearest one starts a
        point's footpoint search.
    newton_steps : int >= 1
        Levenberg-Marquardt steps on each footpoint at most, per projection.
    report_level : int 0..15
        Tessellation level of the limit surface whose vertices measure the
        distance from the surface to the data.
    report_each : bool
        Measure the surface-to-data distances at every iteration (a
        tessellation and a k-d tree query each time: about a tenth of a
        run), not only for the returned iterate at the end (the default).
    callback : callable(record) or None
        Called with each iteration's record (see `ApproximationResult.history`)
        as soon as it is known.
    weights : array_like, (k,) float >= 0, or None
        Each point's weight in the least-squares fit and in the RMS
        distances (weighted RMS); None: equal.
    faces : array_like or None
        The faces of the dense mesh whose vertices are `points`: the data
        becomes its surface, sampled by `surface_samples` with `sampling`
        (the fit then minimises a quadrature of the integral of the squared
        distance over the surface, and the RMS distances are per area). Not
        with `weights`.
    sampling : {"area", "midpoints"}, optional
        With `faces` (None means "area"): "area", the vertices weighted by
        their share of the area; "midpoints", the edges' midpoints likewise.
        Refused without `faces`.
    chunk_points : int >= 1
        Points per chunk, the unit of the footpoint search and of the
        normal equations' sums (added in the chunks' order;
        docs/approximation.md, "Large data"). The result does not depend on
        it beyond rounding (1e-10 relative); at most this many points run
        exactly as one array.
    robust : {"tukey", "cauchy", "none"}
        Iteratively reweighted least squares against outliers: before each
        update every point's weight is multiplied by a factor of its
        distance d to the surface, w(d / (c s)), s the 90th percentile of
        the distances (by weight) and c a constant: "tukey" (the default,
        c = 30), Tukey's biweight (1 - r^2)^2, 0 for d beyond c s: such a
        point does not pull at all; "cauchy" (c = 12), 1 / (1 + r^2): the
        pull of a far point falls as 1 / d; "none": least squares. The
        iterate returned and the stop rule then go by the loss's RMS
        (``sqrt(sum_i w_i rho(d_i) / k)``), not the RMS distance of all the
        points (the records still give that). On clean data the default
        fits as least squares does (docs/approximation.md, "Robustness").
    coarse_iterations : int >= 0
        At most this many updates made first from the footpoints of a fixed
        sample of the points only (each point's choice its own, the same
        however the points are chunked or streamed), each a fraction of a
        full iteration's cost; fewer where one of them lowers the sample's
        lowest RMS (with a robust loss: its criterion) by at most
        `coarse_tol` of it, as on noisy data near its noise floor. Then the
        footpoints of all points are searched afresh and the rest of
        ``iterations`` (four at least: the first takes back what the
        sample's fit made of its own points, the stop rule needs three
        more) run on all of them, with the stop rule. None where the sample
        would hold more than half the points; 0: none.
        docs/approximation.md, "Coarse iterations".
    coarse_points : float > 0
        The sample's size: this many points per control vertex.
    coarse_tol : float >= 0
        The coarse updates end after one that lowered the sample's lowest
        RMS by at most this fraction of it (0: only after one that did not
        lower it).
    client : dask.distributed.Client or None
        Run the chunks on the workers of this Dask cluster (needs
        ``pip install 'sorpia[dask]'``; docs/distributed.md): each worker
        holds its chunks between iterations, the client adds their sums in
        chunk order and solves, so the result is the one without `client`
        and the same `chunk_points`. Points given as a path are read by
        the workers themselves (a filesystem that the client and every
        worker see at that path). The client is left open.

    Returns
    -------
    ApproximationResult

    Raises
    ------
    sorpia.ParameterError
        Empty or non-finite points, an option out of range; a `client`
        that is not a running Client of a cluster with workers, or
        dask.distributed not installed.
    sorpia.MeshError
        A cage with no faces, or one the scheme cannot take.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    cage_vertices, cage_faces, rules = mesh_arguments(cage_vertices, cage_faces, dict(
        scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes), "approximate")
    scheme, boundary, creases, corners, holes = rules.values()
    path = os.fspath(points) if isinstance(points, (str, os.PathLike)) else None
    if path is not None:
        if weights is not None or faces is not None:
            raise ParameterError(f"points = {path!r} is a file, streamed with equal weights: weights= and faces= "
                                 "take the points as an array")
    else:
        points = as_points(points)
    # Types converted here; every range (and method, and lspia's tangential) is the core's to check, once.
    iterations = _count(iterations, "iterations", "an integer >= 1")
    tol = as_real(tol, "tol")
    fairness = as_real(fairness, "fairness")
    if tangential is None:  # the blend for CG; LSPIA moves each coordinate on its own
        tangential = 1.0 if method == "lspia" else DEFAULT_TANGENTIAL
    tangential = as_real(tangential, "tangential")
    solver_tol = as_real(solver_tol, "solver_tol")
    solver_max_iter = as_integer(solver_max_iter, "solver_max_iter", "an integer >= 1")
    grid = _count(grid, "grid", "an integer in 1..64")
    newton_steps = _count(newton_steps, "newton_steps", "an integer >= 1")
    report_level = _count(report_level, "report_level", "an integer in 0..15")
    coarse_iterations = _count(coarse_iterations, "coarse_iterations", "an integer >= 0")
    coarse_points = as_real(coarse_points, "coarse_points")
    coarse_tol = as_real(coarse_tol, "coarse_tol")
    if not isinstance(robust, str):
        raise ParameterError(f"robust = {robust!r} must be one of {', '.join(ROBUST_LOSSES)}")
    if not isinstance(method, str):
        raise ParameterError(f"method = {method!r} must be one of {', '.join(UPDATE_METHODS)}")
    if callback is not None and not callable(callback):
        raise ParameterError(f"callback = {callback!r} must be callable (record) or None")
    workers = None if client is None else _dask.check_client(client)
    if faces is None and sampling is not None:
        raise ParameterError(f"sampling = {sampling!r} samples a dense mesh's faces: give faces= too")
    if faces is not None and weights is not None:
        raise ParameterError("weights and faces: give one (with faces the weights are the faces' areas)")
    cage_vertices = as_vertices(cage_vertices, "cage_vertices")
    if len(cage_faces) == 0:
        raise MeshError("cage_faces is empty: the cage needs at least one face")
    # The pipeline runs in the core (sorpia::approximate: footpoints, updates, the stop rule, the records, the exact
    # scaling of data beyond 2^+-200). A dense mesh's surface is sampled here, on the data as the core scales it
    # (areas square the coordinates), and the samples handed over in the caller's units.
    chunk_points = as_integer(chunk_points, "chunk_points", "an integer >= 1")
    sample_points = as_integer(sample_points, "sample_points", "an integer >= 1")
    for value, name in ((chunk_points, "chunk_points"), (sample_points, "sample_points")):
        if value < 1:
            raise ParameterError(f"{name} = {value} must be an integer >= 1")
    if faces is not None:
        e = _core.scale_exponent(points, cage_vertices)
        samples, weights = surface_samples(np.ldexp(points, -e), faces, sampling or "area")
        points = np.ldexp(samples, e)
    weights = _weights(weights, len(points)) if path is None else None
    scheme = resolve_scheme(scheme, cage_faces)
    surface = LimitSurface(cage_vertices, cage_faces, boundary=boundary, scheme=scheme, creases=creases,
                           corners=corners, holes=holes)
    if client is not None:  # the workers build the same surface from the cage's arrays and rules
        chunks = _dask.DaskChunks(client, workers, dict(vertices=cage_vertices, faces=cage_faces, boundary=boundary,
                                                        scheme=scheme, creases=creases, corners=corners, holes=holes),
                                  points if path is None else path, weights, chunk_points, sample_points)
    elif path is None:
        chunks = _core.InMemoryChunks(surface._surface, points, weights, chunk_points)
    else:
        chunks = _core.FileChunks(surface._surface, path, chunk_points,
                                  os.fspath(spill_directory if spill_directory is not None else tempfile.gettempdir()),
                                  sample_points)
    try:
        out = _core.approximate(surface._surface, chunks, iterations, tol, fairness, tangential, method,
                                solver_tol, solver_max_iter, grid, newton_steps, report_level, callback,
                                time.perf_counter() - t0, bool(report_each), robust,
                                coarse_iterations=coarse_iterations, coarse_points=coarse_points,
                                coarse_tol=coarse_tol)
    finally:
        if client is not None:
            chunks.close()
    if client is not None:
        out["timings"]["cluster"] = chunks.stats
    out["timings"]["total"] = time.perf_counter() - t0
    out["timings"]["cpu"]["total"] = time.process_time() - c0
    V = out["control_vertices"]
    final = out["history"][out["best_iteration"]]
    if final["surface_max_relative"] > _STRAY:
        warnings.warn(f"the fitted surface strays from the data: its farthest point lies "
                      f"{final['surface_max_relative']:.3g} of the diagonal from the nearest data point (the "
                      f"data -> surface RMS is {final['rms_relative']:.3g} of the diagonal); where points do not hold "
                      f"the cage, raise fairness (now {fairness:g}) or give a lighter cage", SorpiaWarning,
                      stacklevel=2)
    return ApproximationResult(control_vertices=V, face_ids=out["face_ids"], uv=out["uv"],
                               distances=out["distances"], points=points if path is None else path,
                               weights=weights,
                               iterations=out["iterations"], stop_reason=out["stop_reason"],
                               best_iteration=out["best_iteration"], method=method, fairness=fairness,
                               tangential=tangential, diagonal=out["diagonal"], history=out["history"],
                               robust=robust, robust_scale=out["robust_scale"],
                               robust_outliers=out["robust_outliers"],
                               coarse_iterations=out["coarse_iterations"],
                               timings=out["timings"],
                               mesh=SubdivisionMesh(V, cage_faces, scheme=scheme, boundary=boundary,
                                                    creases=creases, corners=corners, holes=holes),
                               n_points=chunks.size())
