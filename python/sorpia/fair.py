"""Fair interpolation: a finer control mesh whose limit surface passes through
the given vertices and bends least (Halstead, Kass and DeRose, "Efficient,
fair interpolation using Catmull-Clark surfaces", SIGGRAPH 1993), under Loop
or Catmull-Clark, with OpenSubdiv's creases, corners and holes.

Plain interpolation (`sorpia.interpolate`) has as many control vertices as
targets, so its surface has no freedom left and undulates between uneven
targets. Here the control mesh is first refined ``levels`` times uniformly by
OpenSubdiv's Far (its faces and tags as Far's refinement carries them: edge
and vertex sharpness decayed by one per level, holes from their parent faces;
the refinement matrix R from Far's stencils, so that R V on the fine mesh has
the coarse mesh's limit surface). Vertex i of the fine mesh is the child of
input vertex i; the limit positions of the targets' children are required to
equal the targets, and the rest of the freedom minimises the fairness energy

    E(V) = thin_plate * integral(|S_uu|^2 + 2 |S_uv|^2 + |S_vv|^2)
         + membrane   * integral(|S_u|^2 + |S_v|^2)

of the fine mesh's limit surface S, a quadratic form tr(V^T K V) in the fine
control vertices (K: `sorpia.fairness_matrix` of the fine mesh; by default
with its semi-sharp creases and corners taken as infinitely sharp, so that
the bending is measured on each side of a crease and the fairing does not
flatten the creases: see `sorpia.energy`).

The pipeline (plain solve, refinement, K, solve) is the C++ core's
sorpia::fair_interpolate; its solve (sorpia::fair_solve): the constraint rows, the fine
mesh's limit matrix B at the targets' children, touch no other target's child
(a vertex child's limit mask covers the faces around it, whose other corners
are edge and face children), so each constraint gives its vertex from the
others, V_t = (T_t - sum_j B_tj V_j) / B_tt, exactly; what is left is an
unconstrained quadratic in the free vertices, minimised by conjugate gradients
with Jacobi preconditioning, started from the plain interpolation refined
(R V_plain: the plain surface, which meets the constraints). The targets are
met to rounding whatever the iteration stops at; the iteration stops when the
energy fell by at most ``tol`` times itself over the last d iterations, d the
iterations so far over 5, at least 2 and at most 10 (`ENERGY_WINDOW`): the
fall over the last d iterations estimates how far the energy was above its
minimum d iterations ago, closely where it falls fast (every vertex a
target), and a slow iteration is judged over more of them.

Where the reduced energy has a null space (thin plate alone with few targets:
a flat regular grid's affine functions), the conjugate gradients on the
consistent semidefinite system keep the start's component along it: the
result is a minimiser, the one nearest the plain interpolation in that sense.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from . import _core, _scipy
from ._mesh import SubdivisionMesh, mesh_arguments
from ._meshinfo import bounding_box_diagonal
from ._nonmanifold import manifold_only
from ._validate import DEFAULT_BOUNDARY, DEFAULT_SCHEME, as_integer, as_real, as_vertices
from .errors import MeshError, ParameterError
from .limit import TAGS_DOC as _TAGS_DOC
from .energy import check_semi_sharp
from .solve import InterpolationResult, Interpolator, check_options

METRICS = ("parameter", "reference")
# The iteration's largest window: the energy change is measured over the iterations so far over 5, at least 2
# and at most this many.
ENERGY_WINDOW = 10
MAX_LEVELS = int(_core.MAX_REFINEMENT_LEVELS)


@dataclass(frozen=True, eq=False)
class FairResult:
    """What `fair_interpolate` returns: a control mesh ``levels`` subdivision
    steps finer than the input, with its faces and tags (pass them on as
    they are: ``sorpia.LimitSurface(r.control_vertices, r.faces,
    scheme=r.scheme, boundary=r.boundary, creases=r.creases,
    corners=r.corners, holes=r.holes)`` is the fair surface).

    Attributes
    ----------
    control_vertices : (n_fine, 3) float64
        V on the fine mesh; row i < len(vertices) is the child of input vertex i.
    faces : (m_fine, 3) or (m_fine, 4) int32
        The fine mesh's faces (triangles under Loop, quads under
        Catmull-Clark), Far's level ``levels`` in its order, holes included.
    creases, corners : (indices, sharpness) or None
        The fine mesh's tags, as `sorpia.limit_points` takes them.
    holes : (h,) int32 or None
        The fine faces whose input face is a hole.
    scheme, boundary : str
    levels : int
    targets : (k,) int64
        The interpolated vertices (input indices, which are also their
        children's indices in the fine mesh).
    energy : float
        tr(V^T K V) of the result, in model units squared (inf or 0 where
        that leaves double's range: ``energy_exponent``).
    plain_energy : float
        tr(V^T K V) of the plain interpolation's control mesh refined
        (R V_plain: the same surface as plain interpolation's, on the same
        fine mesh), which the iteration starts from.
    history : (iterations + 1,) float64
        The energy after each iteration (history[0]: the start's, after its
        target vertices were recomputed from the others), in the units of
        ``energy``. ``energies``: its deprecated name (DeprecationWarning),
        for one release.
    energy_exponent : int
        0, except for data beyond 2^+-200 in magnitude, which is solved
        scaled by a power of two: there the energies (squares of the
        coordinates) are exactly ``energy_scaled * 2**energy_exponent``,
        which can overflow or underflow a double. ``energy_scaled`` and
        ``plain_energy_scaled`` hold the scaled values; ``energy_ratio`` is
        taken from them.
    max_error : float
        max over the targets of ||(B_fine V)_t - v_t||, absolute.
    max_error_relative : float
        max_error over the bounding-box diagonal of the input vertices.
    iterations : int
    stop_reason : {"converged", "max_iter", "exact"}
        "converged": the energy fell by at most tol times itself over the
        last d iterations (d: the iterations over 5, 2..10); "exact": the
        gradient vanished in every column.
    converged : bool
        stop_reason is "converged" or "exact".
    seconds : float
        Wall time of the whole call (timings["total"]).
    timings : dict
        Seconds per phase: "refine" (Far's refinement and the start R
        V_plain; R itself is built when `refinement` is read), "plain" (the
        plain interpolation, topology and B included), "energy" (K),
        "setup" (the fine mesh's B, the elimination, the preconditioner),
        "solve" (the iteration), and "total", equal to `seconds`.
    plain : InterpolationResult
        The plain interpolation of every input vertex on the input mesh
        (`sorpia.interpolate`), whose refined control mesh starts the
        iteration.
    refinement : scipy.sparse.csr_matrix (n_fine, n)
        R: ``R @ plain.control_vertices`` is the plain surface's control
        mesh on the fine faces. Built by Far when first read (a property),
        then kept.

    ``mesh`` is the fine control mesh as a `sorpia.SubdivisionMesh` (its
    faces, scheme, boundary rule and tags); ``report()`` the result as a
    JSON-ready dict, as every sorpia result gives it.
    """

    control_vertices: np.ndarray
    faces: np.ndarray
    creases: Optional[tuple]
    corners: Optional[tuple]
    holes: Optional[np.ndarray]
    scheme: str
    boundary: str
    levels: int
    targets: np.ndarray
    energy: float
    plain_energy: float
    history: np.ndarray
    energy_exponent: int
    energy_scaled: float
    plain_energy_scaled: float
    max_error: float
    max_error_relative: float
    iterations: int
    stop_reason: str
    seconds: float
    timings: dict = field(repr=False)
    plain: InterpolationResult = field(repr=False)
    _refinement: "_Refinement" = field(repr=False)

    @property
    def refinement(self):
        """R, (n_fine, n) scipy.sparse.csr_matrix (class docstring), built
        on first access (Far's stencil tables) and kept."""
        return self._refinement()

    @property
    def converged(self) -> bool:
        return self.stop_reason in ("converged", "exact")

    @property
    def energy_ratio(self) -> Optional[float]:
        """energy / plain_energy (at most 1: the fair surface bends no more than
        the plain one), from the scaled energies, so finite where the energies
        in model units are not; None where the plain energy is 0."""
        return self.energy_scaled / self.plain_energy_scaled if self.plain_energy_scaled > 0 else None

    @property
    def tags(self) -> dict:
        """The fine mesh's tags as keyword arguments (creases=, corners=, holes=; absent kinds left out)."""
        return {k: v for k, v in (("creases", self.creases), ("corners", self.corners), ("holes", self.holes))
                if v is not None}

    @property
    def mesh(self) -> SubdivisionMesh:
        """The fine control mesh with its faces, scheme, boundary rule and tags."""
        return SubdivisionMesh(self.control_vertices, self.faces, scheme=self.scheme, boundary=self.boundary,
                               **self.tags)

    @property
    def energies(self) -> np.ndarray:
        """Deprecated name of ``history`` (DeprecationWarning), for one release."""
        warnings.warn("FairResult.energies is deprecated: use history (the same array; the name every sorpia "
                      "result uses)", DeprecationWarning, stacklevel=2)
        return self.history

    def report(self) -> dict:
        """The result as a JSON-ready dict: every scalar field, the history and
        the timings (no per-vertex arrays), and the plain solve's figures."""
        return {"scheme": self.scheme, "boundary": self.boundary, "levels": self.levels,
                "n_control_vertices": int(len(self.control_vertices)), "n_targets": int(len(self.targets)),
                "energy": self.energy, "plain_energy": self.plain_energy, "energy_ratio": self.energy_ratio,
                "energy_exponent": self.energy_exponent, "energy_scaled": self.energy_scaled,
                "plain_energy_scaled": self.plain_energy_scaled, "max_error": self.max_error,
                "max_error_relative": self.max_error_relative, "iterations": self.iterations,
                "converged": self.converged, "stop_reason": self.stop_reason, "seconds": self.seconds,
                "history": np.asarray(self.history).tolist(), "timings": dict(self.timings),
                "plain": {"variant": self.plain.variant, "iterations": int(self.plain.iterations),
                          "stop_reason": self.plain.stop_reason}}


def check_fair_options(levels, thin_plate, membrane, tol) -> tuple[int, int, float, float, float]:
    """levels, thin_plate, membrane and tol converted to the core's types (ParameterError for a value of the wrong
    type); their ranges are the core's (sorpia::fair_interpolate) to check, once, before any work."""
    return (_as_int32(levels, "levels", f"an integer in 1..{MAX_LEVELS}"), as_real(thin_plate, "thin_plate"),
            as_real(membrane, "membrane"), as_real(tol, "tol"))


_INT32_MIN, _INT32_MAX = int(np.iinfo(np.int32).min), int(np.iinfo(np.int32).max)


def _as_int32(value, name: str, what: str) -> int:
    """An integer option the core takes as int: beyond int32 it is clamped there, where the core names it as out of
    range."""
    return min(max(as_integer(value, name, what), _INT32_MIN), _INT32_MAX)


def as_targets(targets, n_vertices: int) -> np.ndarray:
    """The target vertex indices as the core takes them (int32): None is every vertex; a non-integer array is a
    TypeError. Their values (at least one, each in [0, n_vertices), none twice) are the core's to check; an index
    beyond int32 is clamped there, where the core names it as out of range."""
    if targets is None:
        return np.arange(n_vertices, dtype=np.int32)
    arr = np.asarray(targets)
    if arr.size == 0:  # before the dtype: an empty list is float64 to numpy
        return np.zeros(arr.shape, dtype=np.int32)
    if arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"targets must be integer vertex indices, got dtype {arr.dtype}")
    return np.ascontiguousarray(np.clip(arr, _INT32_MIN, _INT32_MAX), dtype=np.int32)


class _Refinement:
    """R of a refinement, built by Far on the first call and kept: fair
    interpolation needs only R V_plain (Far's PrimvarRefiner), so R is built
    when FairResult.refinement is read (or a reference metric needs it)."""

    def __init__(self, topology, rules, levels: int, built=None):
        self._args, self._matrix = (topology, rules, levels), None
        if built is not None:  # the core built R for the reference metric: (data, indices, indptr)
            import scipy.sparse

            self._matrix = scipy.sparse.csr_matrix(built, shape=(len(built[2]) - 1, topology.n_vertices))
            self._args = None

    def __call__(self):
        if self._matrix is None:
            sparse = _scipy.sparse("FairResult.refinement")

            topology, rules, levels = self._args
            fine = _core.refine_uniform(topology, rules, levels)
            self._matrix = sparse.csr_matrix(fine["refinement"],
                                             shape=(int(fine["n_vertices"]), topology.n_vertices))
            self._args = None
        return self._matrix


def _fine_tags(tags: _core.Tags) -> tuple:
    creases = corners = holes = None
    if len(tags.crease_sharpness):
        creases = (np.asarray(tags.crease_vertices), np.asarray(tags.crease_sharpness))
    if len(tags.corner_sharpness):
        corners = (np.asarray(tags.corner_vertices), np.asarray(tags.corner_sharpness))
    if len(tags.holes):
        holes = np.asarray(tags.holes)
    return creases, corners, holes


def fair_interpolate(vertices, faces=None, *, scheme: str = DEFAULT_SCHEME, levels: int = 1, thin_plate: float = 1.0,
                     membrane: float = 0.0, targets=None, boundary: str = DEFAULT_BOUNDARY, creases=None,
                     corners=None, holes=None, tol: float = 1e-6, max_iter: int = 2000,
                     threads: int = 1, semi_sharp: str = "sharp", depth: int = 0,
                     metric: str = "parameter") -> FairResult:
    """A control mesh `levels` subdivision steps finer than (`vertices`,
    `faces`) whose limit surface passes through the targets and whose
    fairness energy is least (module docstring).

    Parameters
    ----------
    vertices : (n, 3) array_like float, or sorpia.SubdivisionMesh
        The points to interpolate (and the input control mesh's vertices);
        or a mesh (``fair_interpolate(mesh)``: its vertices, faces and rules).
    faces : faces as `sorpia.interpolate` takes them
    scheme : {"auto", "loop", "catmull-clark"}
    levels : int
        Uniform refinement steps, 1..10 (each multiplies the faces by 4).
        Refused before any work when the fine mesh and its solve would not
        fit in the memory left (sorpia::refinement_bytes).
    thin_plate, membrane : float
        The energy's weights, >= 0, not both 0.
    targets : (k,) int, optional
        The vertices to interpolate (distinct indices); the others are free
        (partial interpolation). None: every vertex.
    boundary : {"edge-and-corner", "edge-only"}
    {tags}
    tol : float
        Stop when the energy fell by at most tol times itself over the last
        d iterations (d: the iterations so far over 5, at least 2, at most
        10), in (0, 1).
    max_iter : int
        At most this many iterations.
    threads : int
        Threads for the fairness matrix (its assembly and Bfr's evaluation
        in it) and the products with it: at most this many.
    semi_sharp : {"sharp", "as-tagged"}
        How the energy takes semi-sharp creases and corners
        (`sorpia.fairness_matrix`): "sharp" measures the bending on each side
        of a crease and keeps the crease; "as-tagged" also counts the thin
        layer where a semi-sharp crease turns, which the minimiser then
        flattens at the cost of bending elsewhere.
    depth : int
        The energy's quadrature (`sorpia.fairness_matrix`'s depth), 0..12.
        0 (the default) integrates the faces at extraordinary vertices by
        the Gauss rule over the whole face, like every other face: the
        parametric thin-plate energy there grows by 4 lambda^2 per ring of
        Bfr's pieces and diverges on the exact surface, so a rule that looks
        closer (4: Bfr's own isolation level) weighs the few vertices of
        high valence more, and the minimiser flattens their neighbourhoods
        at the cost of bending elsewhere (docs/fair.md).
    metric : {"parameter", "reference"}
        How the energy measures a face (`sorpia.fairness_matrix`):
        "parameter", in Bfr's parameters, every face a unit domain; "reference",
        in the first fundamental form of the input mesh's own limit surface
        (the input refined) at the face's centre, so that bending across a
        face that is long and thin in space is not cheap (docs/fair.md).
        Bends less where faces differ in shape, but slower: K face by face
        and many more iterations (raise max_iter on large meshes).

    Returns
    -------
    FairResult
    """
    t0 = time.perf_counter()
    vertices, faces, rules = mesh_arguments(vertices, faces, dict(
        scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes), "fair_interpolate")
    scheme, boundary, creases, corners, holes = rules.values()
    levels, thin_plate, membrane, tol = check_fair_options(levels, thin_plate, membrane, tol)
    semi_sharp = check_semi_sharp(semi_sharp)
    depth = _as_int32(depth, "depth", "an integer in 0..12")
    if metric not in METRICS:
        raise ParameterError(f"metric must be one of {', '.join(map(repr, METRICS))}, got {metric!r}")
    max_iter = as_integer(max_iter, "max_iter", "an integer >= 1")
    threads = _as_int32(threads, "threads", "an integer >= 1")
    v0 = as_vertices(vertices)
    n = v0.shape[0]

    # The Interpolator's topology and B serve the plain solve and the refinement; the pipeline runs in the core
    # (sorpia::fair_interpolate: plain solve, refinement, K, the fair solve, the exact scaling). Building it is the
    # one check of the faces and rules (as_rules).
    t = time.perf_counter()
    rule_options = dict(scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes)
    try:
        interp = Interpolator._for_vertices(faces, n, rule_options, "error")
    except MeshError as exc:
        raise manifold_only(exc, "fair interpolation") from None
    build = time.perf_counter() - t
    rules = interp._rules
    target_ids = as_targets(targets, n)
    t_plain = time.perf_counter()
    plain_options = check_options()
    out = _core.fair_interpolate(interp._impl, v0, target_ids, plain_options, levels, thin_plate, membrane, tol,
                                 ENERGY_WINDOW, max_iter, threads, semi_sharp, depth, metric == "reference")
    seconds = out["seconds"]
    plain = interp._solve(v0, "auto", plain_options, None, t_plain, keep_targets=True, result=out["plain"])
    timings = {"plain": build + seconds["plain"], "refine": seconds["refine"], "energy": seconds["energy"],
               "setup": seconds["setup"], "solve": seconds["solve"]}
    refinement = _Refinement(interp.topology, rules, levels, out.get("refinement"))
    fine_faces = out["faces"]
    diagonal = bounding_box_diagonal(v0)
    max_error = float(out["max_error"])
    exponent = int(out["energy_exponent"])
    with np.errstate(over="ignore", under="ignore"):  # beyond double in model units: inf or 0 (energy_exponent)
        energy, plain_energy, history = (np.ldexp(out[key], exponent) for key in ("energy", "start_energy", "energies"))
    fine_creases, fine_corners, fine_holes = _fine_tags(out["tags"])
    timings["total"] = time.perf_counter() - t0
    return FairResult(
        control_vertices=out["vertices"], faces=fine_faces, creases=fine_creases, corners=fine_corners,
        holes=fine_holes, scheme=_core.scheme_name(rules.scheme), boundary=_core.boundary_name(rules.boundary),
        levels=levels, targets=target_ids.astype(np.int64), energy=float(energy),
        plain_energy=float(plain_energy), history=history, energy_exponent=exponent,
        energy_scaled=float(out["energy"]), plain_energy_scaled=float(out["start_energy"]), max_error=max_error,
        max_error_relative=max_error / diagonal if diagonal > 0 else max_error,
        iterations=int(out["iterations"]), stop_reason=out["stop_reason"], seconds=timings["total"],
        timings=timings, plain=plain, _refinement=refinement)


fair_interpolate.__doc__ = fair_interpolate.__doc__.replace("{tags}", _TAGS_DOC)
