"""
sorpia's compiled core (mesh topology, OpenSubdiv Loop and Catmull-Clark limits, PIA solvers)
"""
from __future__ import annotations
import collections.abc
import numpy
import numpy.typing
import typing
__all__: list[str] = ['ApproximationChunk', 'Boundary', 'DEFAULT_COARSE_ITERATIONS', 'DEFAULT_COARSE_POINTS', 'DEFAULT_COARSE_TOL', 'DEFAULT_ROBUST', 'FileChunks', 'FootpointSearch', 'INFINITE_SHARPNESS', 'InMemoryChunks', 'InterpolationResult', 'Interpolator', 'LimitSurface', 'MAX_REFINEMENT_LEVELS', 'MAX_THREADS', 'MeshError', 'MeshFileError', 'Method', 'NormalEquations', 'OmegaRule', 'ParameterError', 'PointChunks', 'PointIndex', 'Rules', 'Scheme', 'SolveOptions', 'Tags', 'Topology', 'YOUNG_RHO_CLAMP', 'approximate', 'available_memory_bytes', 'blend_weights', 'boundary_name', 'check_ply_per_vertex', 'check_refinement', 'check_writable', 'closer_footpoints', 'closest_points', 'decimate', 'face_list_statistics', 'fair_interpolate', 'fairness_matrix', 'grid', 'icosphere', 'irregular', 'limit_matrix', 'limit_points', 'limit_residual', 'mesh_statistics', 'method_names', 'normal_matrix', 'parse_boundary', 'parse_method', 'parse_omega', 'parse_scheme', 'point_file_points', 'point_sample_mask', 'pole', 'polygon_torus', 'quad_grid', 'quad_irregular', 'quad_torus', 'read_mesh', 'read_point_file', 'refine_footpoints', 'refine_uniform', 'refinement_bytes', 'regular_valence', 'repair', 'repair_polygons', 'rms_levelled', 'robust_options', 'scale_exponent', 'scheme_name', 'sharp_edges', 'split_nonmanifold', 'split_nonmanifold_polygons', 'subface_columns', 'tessellation_bytes', 'torus', 'write_file_atomic', 'write_mesh']
class MeshError(ValueError):
    """
    The faces or coordinates cannot be used: an index out of range, a repeated
    vertex, duplicate faces, an edge of three or more faces, inconsistent
    orientation, a bowtie vertex, a non-finite coordinate. The message names the
    face, edge or vertex.
    """
class ParameterError(ValueError):
    """
    An option is out of range or does not apply: a method, omega, tol,
    max_iter, boundary, level or thread count. The message names the parameter
    and the value given.
    """
class MeshFileError(ValueError):
    """
    A mesh file cannot be read or written: missing, a directory, truncated,
    malformed, of an unknown format, or holding polygons without
    ``triangulate=True``. The message names the file and the line (text) or
    element (binary).
    """
class Boundary:
    """
    Boundary interpolation rule (sorpia::Boundary).
    
    Members:
    
      edge_and_corner
    
      edge_only
    """
    __members__: typing.ClassVar[dict[str, Boundary]]
    edge_and_corner: typing.ClassVar[Boundary]
    edge_only: typing.ClassVar[Boundary]
    @typing.overload
    def __eq__(self, other: Boundary) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: Boundary) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class Scheme:
    """
    Subdivision scheme (sorpia::Scheme).
    
    Members:
    
      loop
    
      catmull_clark
    """
    __members__: typing.ClassVar[dict[str, Scheme]]
    catmull_clark: typing.ClassVar[Scheme]
    loop: typing.ClassVar[Scheme]
    @typing.overload
    def __eq__(self, other: Scheme) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: Scheme) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class Tags:
    """
    OpenSubdiv's sharpness tags (sorpia::Tags).
    """
    @typing.overload
    def __init__(self, crease_vertices: numpy.typing.NDArray[numpy.int32], crease_sharpness: numpy.typing.NDArray[numpy.float64], corner_vertices: numpy.typing.NDArray[numpy.int32], corner_sharpness: numpy.typing.NDArray[numpy.float64], holes: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex, n_faces: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @typing.overload
    def __init__(self) -> None:
        ...
    def empty(self) -> bool:
        ...
    def max_semi_sharpness(self) -> float:
        ...
    @property
    def corner_sharpness(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @property
    def corner_vertices(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def crease_sharpness(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @property
    def crease_vertices(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def holes(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
class Rules:
    """
    Scheme, boundary rule and sharpness tags (sorpia::Rules).
    """
    def __init__(self, *, scheme: Scheme = Scheme.loop, boundary: Boundary = Boundary.edge_and_corner, tags: Tags = ...) -> None:
        ...
    @property
    def boundary(self) -> Boundary:
        ...
    @property
    def scheme(self) -> Scheme:
        ...
    @property
    def tags(self) -> Tags:
        ...
class Topology:
    @typing.overload
    def __init__(self, faces: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @typing.overload
    def __init__(self, face_vertex_counts: numpy.typing.NDArray[numpy.int32], face_vertex_indices: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def all_quads(self) -> bool:
        ...
    @property
    def all_triangles(self) -> bool:
        ...
    @property
    def face_counts(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def face_indices(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def face_offsets(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def face_ring_neighbors(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def face_ring_offsets(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def is_boundary(self) -> numpy.typing.NDArray[numpy.bool]:
        ...
    @property
    def n_boundary_edges(self) -> int:
        ...
    @property
    def n_edges(self) -> int:
        ...
    @property
    def n_faces(self) -> int:
        ...
    @property
    def n_unreferenced(self) -> int:
        ...
    @property
    def n_vertices(self) -> int:
        ...
    @property
    def ring_neighbors(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def ring_offsets(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def vertex_face_offsets(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def vertex_faces(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
class InterpolationResult:
    """
    What a solve returns (sorpia.interpolate, Interpolator.solve).
    
    ``report()`` gives every attribute but control_vertices as a JSON-ready dict
    (arrays as lists), as every sorpia result's report() does. ``errors`` is the
    deprecated name of ``history`` (DeprecationWarning), for one release.
    
    Attributes
    ----------
    control_vertices : (n, k) float64
        V, in the input vertex order; B V = V0 to the tolerance reached. k = 3
        for vertices, the data's columns otherwise. Read-only in the result of
        an update (Interpolator.update), whose residual the Interpolator keeps
        for the next update.
    iterations : int
        Iterations done (sweeps for "gs"/"sor", outer steps for "hss"/"whss"),
        counted from the start: 0 when a warm start already met tol. An update
        (Interpolator.update): 1 when it relaxed any vertex, else 0.
    converged : bool
        history[-1] < tol, or E_k at the rounding floor (E_k <= 64 eps max_i ||v_i^0||),
        below which no method can go: a tol of 1e-300 ends there, converged.
    history : (iterations + 1,) float64
        history[k] = E_k / E_0, E_0 = max_i ||v_i^0 - (B V0)_i|| the error of the
        cold start V = V0 whatever the start, so history[0] = 1 from a cold start
        and E(start) / E_0 from a warm one (`initial`, an update); a single 0.0
        when E_0 = 0: V0 already interpolates and is the result. An update:
        [E(previous) / E_0, E(result) / E_0] with E_0 of the new targets, E over
        the whole mesh.
    method : str
    omega : float or None
        "sor"/"gs": the omega used (1.0 for "gs"); None for other methods.
    seconds : float
        Wall time of the whole call, every phase in `timings` included
        (timings["total"]).
    stop_reason : {"converged", "max_iter", "diverged", "callback", "singular", "stalled", "slow"}
        "diverged": E_k rose above 10 times (the Krylov methods: 1e4 times) its
        lowest value before, or was not finite; control_vertices are then the
        iterate of the lowest E_k (`returned_iteration`). "singular": "cgls"
        ("auto"'s last resort) solved the least-squares problem, E_k / E_0 still
        above tol: B is singular and the targets have a part outside its range,
        control_vertices are the least-squares solution of least norm, and
        `worst_vertices` says where the targets are missed. "stalled": "gmres"
        made no progress over a whole cycle (B singular, or numerically so). "slow" (in `attempts` only): "auto"
        stopped "sor", whose rate would not reach tol by max_iter.
    initial_error : float
        E_0, absolute.
    variant : str
        The algorithm that made control_vertices: the method's name, "bicgstab"
        for "cg" on a mesh with boundary, and for "auto" the method it ended
        with ("sor", "gmres" or "cgls").
    attempts : list of dict
        Every method run, in order, each {"method", "variant", "iterations",
        "stop_reason", "final_error" (its last E_k / E_0), "products",
        "seconds"}: one for an explicit method; for "auto" its "sor" run and,
        where that stopped short, "gmres" and "cgls". errors and iterations are
        those of the last.
    returned_iteration : int
        The iteration whose iterate control_vertices holds: `iterations`, or
        after a divergence the one of the lowest E_k.
    recommended : str or None
        Not converged: the method that would work here ("gmres" after a method
        that diverged or stopped at max_iter, "cgls" after "gmres" stalled);
        None otherwise.
    worst_vertices : (m,) int64
        Not converged: the (at most 10) vertices where ||v_i^0 - (B V)_i|| is
        largest, largest first; empty when converged.
    worst_residuals : (m,) float64
        Their residual norms ||v_i^0 - (B V)_i||, absolute.
    max_error : float
        The largest miss of the returned control vertices, max_i ||v_i^0 -
        (B V)_i||, absolute: history[returned_iteration] * initial_error.
    rho : float or None
        omega="young": the estimated spectral radius of I - D^-1 B.
    sigma : float or None
        "pia"/"wpia": the step.
    lambda_min : float or None
        "wpia": the estimated smallest eigenvalue of B.
    alpha : float or None
        "hss"/"whss": the shift.
    weight : float or None
        "hss"/"whss": the relaxation weight.
    products : int
        Applications of B (or B^T) in the iteration, inner solves included: a
        measure of work comparable across methods (0 for an update).
    relaxations : int
        Single-vertex relaxations (eq. 18 at one vertex): iterations * n for
        "sor"/"gs", those of the work list for an update, 0 for other methods.
    timings : dict
        Seconds per phase: "topology" (faces validated, one-ring), "operator"
        (B from OpenSubdiv's limit masks), "estimate" (spectral estimates for the
        parameters: 0 when an Interpolator already holds them), "solve", and
        "total", equal to `seconds`.
    """
    _fields: typing.ClassVar[tuple] = ('control_vertices', 'iterations', 'converged', 'history', 'method', 'omega', 'seconds', 'stop_reason', 'initial_error', 'variant', 'attempts', 'returned_iteration', 'recommended', 'worst_vertices', 'worst_residuals', 'max_error', 'rho', 'sigma', 'lambda_min', 'alpha', 'weight', 'products', 'relaxations', 'timings')
    def __getstate__(self) -> tuple[list[float], list[float], float, int, int, int, str, float, bool, float, bool, float, float, float, float, int, float, float, float, float, float, int, int, list, int, int, list[int], list[float]]:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, arg0: tuple) -> None:
        ...
    def _record_build(self, seconds: typing.SupportsFloat | typing.SupportsIndex, topology_seconds: typing.SupportsFloat | typing.SupportsIndex, operator_seconds: typing.SupportsFloat | typing.SupportsIndex) -> None:
        """
        For sorpia's Python layer: the whole call's wall time and the build phases it timed.
        """
    def report(self) -> dict:
        """
        Every attribute but control_vertices, JSON-ready (arrays as lists), as every sorpia result's report().
        """
    @property
    def alpha(self) -> typing.Any:
        ...
    @property
    def attempts(self) -> list:
        ...
    @property
    def control_vertices(self) -> numpy.ndarray:
        ...
    @property
    def converged(self) -> bool:
        ...
    @property
    def errors(self) -> numpy.ndarray:
        ...
    @property
    def history(self) -> numpy.ndarray:
        ...
    @property
    def initial_error(self) -> float:
        ...
    @property
    def iterations(self) -> int:
        ...
    @property
    def lambda_min(self) -> typing.Any:
        ...
    @property
    def max_error(self) -> float:
        ...
    @property
    def method(self) -> str:
        ...
    @property
    def omega(self) -> typing.Any:
        ...
    @property
    def omega_clamped(self) -> bool:
        """
        omega='young' met rho >= YOUNG_RHO_CLAMP.
        """
    @property
    def products(self) -> int:
        ...
    @property
    def recommended(self) -> typing.Any:
        ...
    @property
    def relaxations(self) -> int:
        ...
    @property
    def returned_iteration(self) -> int:
        ...
    @property
    def rho(self) -> typing.Any:
        ...
    @property
    def seconds(self) -> float:
        ...
    @property
    def sigma(self) -> typing.Any:
        ...
    @property
    def stop_reason(self) -> str:
        ...
    @property
    def timings(self) -> dict:
        ...
    @property
    def variant(self) -> str:
        ...
    @property
    def weight(self) -> typing.Any:
        ...
    @property
    def worst_residuals(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @property
    def worst_vertices(self) -> numpy.typing.NDArray[numpy.int64]:
        ...
class Method:
    """
    The PIA-family methods (sorpia::Method).
    
    Members:
    
      auto
    
      pia
    
      wpia
    
      gs
    
      sor
    
      cg
    
      hss
    
      whss
    
      gmres
    
      cgls
    """
    __members__: typing.ClassVar[dict[str, Method]]
    auto: typing.ClassVar[Method]
    cg: typing.ClassVar[Method]
    cgls: typing.ClassVar[Method]
    gmres: typing.ClassVar[Method]
    gs: typing.ClassVar[Method]
    hss: typing.ClassVar[Method]
    pia: typing.ClassVar[Method]
    sor: typing.ClassVar[Method]
    whss: typing.ClassVar[Method]
    wpia: typing.ClassVar[Method]
    @typing.overload
    def __eq__(self, other: Method) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: Method) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class OmegaRule:
    """
    How 'sor' chooses omega (sorpia::OmegaRule).
    
    Members:
    
      given
    
      young
    
      auto
    """
    __members__: typing.ClassVar[dict[str, OmegaRule]]
    auto: typing.ClassVar[OmegaRule]
    given: typing.ClassVar[OmegaRule]
    young: typing.ClassVar[OmegaRule]
    @typing.overload
    def __eq__(self, other: OmegaRule) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: OmegaRule) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class SolveOptions:
    def __init__(self, *, method: Method, omega_rule: OmegaRule, omega: typing.SupportsFloat | typing.SupportsIndex, sigma: typing.SupportsFloat | typing.SupportsIndex | None, alpha: typing.SupportsFloat | typing.SupportsIndex | None, weight: typing.SupportsFloat | typing.SupportsIndex | None, tol: typing.SupportsFloat | typing.SupportsIndex, max_iter: typing.SupportsInt | typing.SupportsIndex, threads: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def max_iter(self) -> int:
        ...
    @property
    def method(self) -> Method:
        ...
    @property
    def omega_rule(self) -> OmegaRule:
        ...
    @property
    def threads(self) -> int:
        ...
    @property
    def tol(self) -> float:
        ...
class Interpolator:
    """
    One mesh, its rules and B (sorpia::Interpolator).
    """
    @typing.overload
    def __init__(self, faces: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex, rules: Rules, *, vertex_map: numpy.typing.NDArray[numpy.int32] | None = None) -> None:
        """
        Triangles, (m, 3); vertex_map: a non-manifold mesh's split (sorpia::Interpolator).
        """
    @typing.overload
    def __init__(self, face_vertex_counts: numpy.typing.NDArray[numpy.int32], face_vertex_indices: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex, rules: Rules, *, vertex_map: numpy.typing.NDArray[numpy.int32] | None = None) -> None:
        """
        Polygons as counts and indices.
        """
    def apply(self, x: numpy.typing.NDArray[numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        B x for (n, 3) x.
        """
    def hermitian_extremes(self) -> tuple[float, float]:
        ...
    def jacobi_rho(self) -> float:
        ...
    def lambda_min(self) -> float:
        ...
    def limit_matrix(self) -> tuple:
        """
        B as CSR arrays (data, indices, indptr).
        """
    def solve(self, vertices: numpy.typing.NDArray[numpy.float64], options: SolveOptions, callback: typing.Any, initial: numpy.typing.NDArray[numpy.float64] | None = None, keep_targets: bool = False) -> InterpolationResult:
        """
        sorpia::Interpolator::solve on (n, k) data with checked options, from `initial` when given. Returns an InterpolationResult.
        """
    def update(self, previous: typing.Any, previous_is_last: bool, indices: numpy.typing.NDArray[numpy.int32], positions: numpy.typing.NDArray[numpy.float64], tol: typing.SupportsFloat | typing.SupportsIndex, max_iter: typing.SupportsInt | typing.SupportsIndex, in_place: bool) -> tuple[typing.Any, bool]:
        """
        sorpia::Interpolator::update from previous.control_vertices (in place, or on a copy). previous_is_last: previous is the last update's result, unchanged. Returns (result, whether the targets moved).
        """
    @property
    def build_timings(self) -> dict:
        ...
    @property
    def diag(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @property
    def n_vertices(self) -> int:
        ...
    @property
    def neighbors(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def offsets(self) -> numpy.typing.NDArray[numpy.int32]:
        ...
    @property
    def rules(self) -> Rules:
        ...
    @property
    def symmetrisable(self) -> bool:
        ...
    @property
    def symmetriser(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        Gamma^-1 with Gamma^-1 B symmetric on its two-way entries (sorpia::symmetriser), or empty.
        """
    @property
    def targets(self) -> typing.Any:
        """
        A copy of the targets later updates move (None before a solve that kept them).
        """
    @property
    def targets_columns(self) -> int:
        """
        k of the kept (n, k) targets; 0 before a solve that kept them.
        """
    @property
    def topology(self) -> Topology:
        ...
    @property
    def uniform(self) -> bool:
        ...
    @property
    def weight(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
class LimitSurface:
    def __init__(self, topology: Topology, vertices: numpy.typing.NDArray[numpy.float64], scheme: Scheme, boundary: Boundary, tags: Tags) -> None:
        ...
    def evaluate(self, face_ids: numpy.typing.NDArray[numpy.int32], uv: numpy.typing.NDArray[numpy.float64], derivatives: bool) -> typing.Any:
        ...
    def get_vertices(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def rows(self, face_ids: numpy.typing.NDArray[numpy.int32], uv: numpy.typing.NDArray[numpy.float64], derivatives: typing.SupportsInt | typing.SupportsIndex) -> list:
        ...
    def set_vertices(self, vertices: numpy.typing.NDArray[numpy.float64]) -> None:
        ...
    def tessellate(self, level: typing.SupportsInt | typing.SupportsIndex) -> tuple:
        ...
    @property
    def boundary(self) -> Boundary:
        ...
    @property
    def n_faces(self) -> int:
        ...
    @property
    def n_vertices(self) -> int:
        ...
    @property
    def scheme(self) -> Scheme:
        ...
class PointIndex:
    def __init__(self, points: numpy.typing.NDArray[numpy.float64]) -> None:
        ...
    def nearest(self, queries: numpy.typing.NDArray[numpy.float64]) -> tuple[numpy.typing.NDArray[numpy.int64], numpy.typing.NDArray[numpy.float64]]:
        ...
    @property
    def size(self) -> int:
        ...
class NormalEquations:
    def __init__(self, indptr: numpy.typing.NDArray[numpy.int32], indices: numpy.typing.NDArray[numpy.int32], data: numpy.typing.NDArray[numpy.float64], n_cols: typing.SupportsInt | typing.SupportsIndex, weights: typing.Any, fairness_matrix: typing.Any, fairness: typing.SupportsFloat | typing.SupportsIndex, proximal: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    def apply(self, x: numpy.typing.NDArray[numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def solve(self, rhs: numpy.typing.NDArray[numpy.float64], start: numpy.typing.NDArray[numpy.float64], rtol: typing.SupportsFloat | typing.SupportsIndex, max_iter: typing.SupportsInt | typing.SupportsIndex, threads: typing.SupportsInt | typing.SupportsIndex = 0) -> tuple[numpy.typing.NDArray[numpy.float64], int, str]:
        """
        (N + mu I + c K) X = rhs by the fitting layer's PCG from `start` (sorpia::NormalEquations::solve):
        (X, iterations, stop_reason).
        """
    @property
    def mean_diagonal(self) -> float:
        ...
    @property
    def mu(self) -> float:
        ...
class FootpointSearch:
    """
    closest_points' search start on one state of a surface, built once and queried per chunk (sorpia::FootpointSearch); keep the surface unchanged while it is used.
    """
    def __init__(self, surface: LimitSurface, grid: typing.SupportsInt | typing.SupportsIndex, max_steps: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class ApproximationChunk:
    """
    One chunk of approximation's points: its footpoints and its share of the normal equations (sorpia::ApproximationChunk, sorpia/point_chunks.hpp).
    """
    def __init__(self, points: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], weights: typing.Any = None, first: typing.SupportsInt | typing.SupportsIndex = 0) -> None:
        ...
    def best_footpoints(self) -> tuple[numpy.typing.NDArray[numpy.int32], numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
        ...
    def distance_histogram(self, unit: typing.SupportsFloat | typing.SupportsIndex) -> tuple:
        """
        the current distances' weighted histogram (sorpia/robust.hpp) as (unit, total, mass)
        """
    def extent(self) -> tuple:
        ...
    def keep_best(self) -> None:
        ...
    def keep_fresh(self, closer: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    def keep_fresh_in_best(self) -> tuple:
        ...
    def line_offset(self, mean: typing.Any, axis: typing.Any, diagonal: typing.SupportsFloat | typing.SupportsIndex) -> float:
        ...
    def moments(self, center: typing.Any, diagonal: typing.SupportsFloat | typing.SupportsIndex) -> tuple:
        ...
    def normal_sums(self, surface: LimitSurface, tangential: typing.SupportsFloat | typing.SupportsIndex) -> tuple:
        ...
    def refine(self, surface: LimitSurface, grid: typing.SupportsInt | typing.SupportsIndex, max_steps: typing.SupportsInt | typing.SupportsIndex) -> tuple:
        ...
    def refine_fresh(self, search: FootpointSearch) -> tuple:
        ...
    def robust_normal_sums(self, surface: LimitSurface, tangential: typing.SupportsFloat | typing.SupportsIndex, robust: tuple, scale: typing.SupportsFloat | typing.SupportsIndex) -> tuple:
        """
        normal_sums with each weight times the robust factor of its distance at `scale`
        """
    def robust_sums(self, robust: tuple, scale: typing.SupportsFloat | typing.SupportsIndex) -> tuple:
        """
        the current distances' robust sums (sorpia/robust.hpp) as (sum w rho(d), sum w d^2 and sum w within the cut c s, the points beyond it); robust = (loss, quantile, c)
        """
    def sampled(self, k: typing.SupportsInt | typing.SupportsIndex, sample_points: typing.SupportsInt | typing.SupportsIndex) -> ApproximationChunk:
        """
        a chunk of this one's points in the fixed sample of about sample_points of all k (the coarse iterations' chunk)
        """
    def scale(self, e: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def search(self, search: FootpointSearch) -> tuple:
        ...
    def search_fresh(self, search: FootpointSearch, closer: typing.SupportsFloat | typing.SupportsIndex) -> tuple:
        ...
    @property
    def first(self) -> int:
        ...
    @property
    def points(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @property
    def size(self) -> int:
        ...
class PointChunks:
    """
    approximation's points as chunks (sorpia::PointChunks), the backend its driver calls: subclass it in Python and implement every method (their calls and order: sorpia/point_chunks.hpp); sums may be returned per chunk, as a list, added in its order.
    """
    def __init__(self) -> None:
        ...
    def size(self) -> int:
        """
        the number of points
        """
class InMemoryChunks(PointChunks):
    def __init__(self, surface: LimitSurface, points: numpy.typing.NDArray[numpy.float64], weights: typing.Any, chunk_points: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class FileChunks(PointChunks):
    """
    Points streamed from a binary little-endian PLY or .npy file a chunk at a time, footpoint states spilled to a temporary file in spill_directory (sorpia::FileChunks).
    """
    def __init__(self, surface: LimitSurface, path: str, chunk_points: typing.SupportsInt | typing.SupportsIndex, spill_directory: str, sample_points: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
def approximate(surface: LimitSurface, chunks: PointChunks, iterations: typing.SupportsInt | typing.SupportsIndex, tol: typing.SupportsFloat | typing.SupportsIndex, fairness: typing.SupportsFloat | typing.SupportsIndex, tangential: typing.SupportsFloat | typing.SupportsIndex, method: str, solver_tol: typing.SupportsFloat | typing.SupportsIndex, solver_max_iter: typing.SupportsInt | typing.SupportsIndex, grid: typing.SupportsInt | typing.SupportsIndex, newton_steps: typing.SupportsInt | typing.SupportsIndex, report_level: typing.SupportsInt | typing.SupportsIndex, callback: typing.Any, seconds_before: typing.SupportsFloat | typing.SupportsIndex = 0.0, report_each: bool = False, robust: str = 'tukey', robust_quantile: typing.SupportsFloat | typing.SupportsIndex | None = None, robust_c: typing.SupportsFloat | typing.SupportsIndex | None = None, coarse_iterations: typing.SupportsInt | typing.SupportsIndex = 6, coarse_points: typing.SupportsFloat | typing.SupportsIndex = 16.0, coarse_tol: typing.SupportsFloat | typing.SupportsIndex = 0.01) -> dict:
    """
    Approximation's pipeline (sorpia::approximate) from the surface's control vertices, over the points of
    `chunks` (InMemoryChunks, FileChunks or a Python PointChunks): a dict with control_vertices, face_ids, uv,
    distances, iterations, stop_reason, best_iteration, diagonal, robust_scale, robust_outliers, history
    (records as dicts, seconds counted from seconds_before) and timings; callback(record) after each record.
    The surface-to-data figures in every record with report_each, else only in the returned iterate's (None
    in the others). robust: the loss of the robust fit (none, cauchy, tukey; the core's default unless
    given) at the robust_quantile of the distances times robust_c (sorpia/robust.hpp; None: the loss's
    defaults, robust_options): a Python backend fits robustly only where it defines distance_histogram,
    robust_sums and robust_normal_sums (sorpia/point_chunks.hpp); robust = 'none' runs without them. coarse_iterations: updates on a fixed sample of
    coarse_points per control vertex first, at most that many, fewer where one lowers the sample's criterion by
    at most coarse_tol of it (ApproximationOptions), where the backend defines set_sample.
    """
def available_memory_bytes() -> int:
    ...
def blend_weights(points: numpy.typing.NDArray[numpy.float64], normals: numpy.typing.NDArray[numpy.float64], tangential: typing.SupportsFloat | typing.SupportsIndex, weights: typing.Any = None) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
    """
    (W (k, 6), W p (k, 3)) of the tangent-distance blend (sorpia::blend_weights).
    """
def boundary_name(boundary: Boundary) -> str:
    ...
def check_ply_per_vertex(face_vertex_indices: numpy.typing.NDArray[numpy.int32], face_vertex_counts: numpy.typing.NDArray[numpy.int32] | None, face_size: typing.SupportsInt | typing.SupportsIndex, n_vertices: typing.SupportsInt | typing.SupportsIndex, values: numpy.typing.NDArray[numpy.float64], indices: numpy.typing.NDArray[numpy.int32], what: str) -> None:
    """
    Raise ParameterError where PLY cannot hold the channel per vertex (write_mesh's check: the width, a seam).
    """
def check_refinement(topology: Topology, rules: Rules, levels: typing.SupportsInt | typing.SupportsIndex) -> None:
    """
    refine_uniform's checks before any work (sorpia::check_refinement): raises for levels it refuses.
    """
def check_writable(path: str) -> None:
    """
    Raise MeshFileError naming path when write_file_atomic(path, ...) could not start.
    """
def closer_footpoints(surface: LimitSurface, topology: Topology, points: numpy.typing.NDArray[numpy.float64], face_ids: numpy.typing.NDArray[numpy.int32], uv: numpy.typing.NDArray[numpy.float64], grid: typing.SupportsInt | typing.SupportsIndex, max_steps: typing.SupportsInt | typing.SupportsIndex, starts: typing.SupportsInt | typing.SupportsIndex, near: typing.SupportsFloat | typing.SupportsIndex = 0.0, certify: bool = True) -> tuple[tuple, int, int]:
    """
    ((face_ids, uv, positions, distances, normals), moved, certified): the footpoints given, evaluated at their
    (face, uv), re-searched from the grid samples within their distance (sorpia::FootpointSearch::closer);
    certified: how many points its certificate let leave out their star's samples (certify=False: none).
    """
def closest_points(surface: LimitSurface, topology: Topology, points: numpy.typing.NDArray[numpy.float64], grid: typing.SupportsInt | typing.SupportsIndex, max_steps: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def decimate(vertices: numpy.typing.NDArray[numpy.float64], triangles: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex, scheme: Scheme, max_normal_deviation: typing.SupportsFloat | typing.SupportsIndex, max_aspect_ratio: typing.SupportsFloat | typing.SupportsIndex, max_boundary_angle: typing.SupportsFloat | typing.SupportsIndex, strict: bool) -> tuple[tuple, typing.Any]:
    """
    The cage of a triangle mesh (sorpia::decimate) and, unless strict, why the guards stopped it short (None when the count was reached): ((vertices, triangles) under Loop, (vertices, face_vertex_counts, face_vertex_indices) under Catmull-Clark; message).
    """
def face_list_statistics(faces: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex) -> typing.Any:
    """
    Statistics of a raw triangle list that may fail validation (genus None); None without faces or with an index out of range.
    """
def fair_interpolate(interpolator: Interpolator, vertices: numpy.typing.NDArray[numpy.float64], targets: numpy.typing.NDArray[numpy.int32], plain: SolveOptions, levels: typing.SupportsInt | typing.SupportsIndex, thin_plate: typing.SupportsFloat | typing.SupportsIndex, membrane: typing.SupportsFloat | typing.SupportsIndex, tol: typing.SupportsFloat | typing.SupportsIndex, window: typing.SupportsInt | typing.SupportsIndex, max_iter: typing.SupportsInt | typing.SupportsIndex, threads: typing.SupportsInt | typing.SupportsIndex, semi_sharp: str, depth: typing.SupportsInt | typing.SupportsIndex, reference: bool) -> dict:
    """
    Fair interpolation's pipeline (sorpia::fair_interpolate): the plain solve on the Interpolator's mesh, the
    refinement, K and the fair solve. A dict: plain (InterpolationResult), faces, n_vertices, tags (the fine
    mesh's), refinement (R as CSR arrays, only where the reference metric built it), vertices, energies,
    energy, start_energy, energy_exponent (the energies are in units of 2^energy_exponent), iterations,
    stop_reason, max_error and seconds per phase.
    """
def fairness_matrix(topology: Topology, rules: Rules, thin_plate: typing.SupportsFloat | typing.SupportsIndex, membrane: typing.SupportsFloat | typing.SupportsIndex, gauss_points: typing.SupportsInt | typing.SupportsIndex, depth: typing.SupportsInt | typing.SupportsIndex, reuse: bool = True, reference: numpy.typing.NDArray[numpy.float64] | None = None) -> tuple:
    """
    Fairness matrix K (thin-plate and membrane energy) as CSR arrays (data, indices, indptr); reuse=False
    integrates every face on its own (FairnessQuadrature::reuse); reference: (n, 3) control vertices whose
    limit surface gives each face its metric (sorpia::fairness_matrix).
    """
def grid(nu: typing.SupportsInt | typing.SupportsIndex, nv: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def icosphere(level: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def irregular(n_vertices: typing.SupportsInt | typing.SupportsIndex, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> tuple:
    ...
def limit_matrix(topology: Topology, rules: Rules) -> tuple:
    """
    Limit matrix B as CSR arrays (data, indices, indptr).
    """
def limit_points(topology: Topology, vertices: numpy.typing.NDArray[numpy.float64], rules: Rules) -> numpy.typing.NDArray[numpy.float64]:
    """
    Limit positions B V of (n, k) data, (n, k).
    """
def limit_residual(topology: Topology, control: numpy.typing.NDArray[numpy.float64], target: numpy.typing.NDArray[numpy.float64], boundary: Boundary) -> tuple[float, int, numpy.typing.NDArray[numpy.float64]]:
    """
    (max, argmax, norms): r_i = |(B V)_i - V0_i| from OpenSubdiv's limit masks over the one-ring.
    """
def mesh_statistics(topology: Topology, scheme: Scheme = Scheme.loop) -> dict:
    """
    Statistics of a validated mesh (a dict), from its one-ring; extraordinary vertices as the scheme has them.
    """
def method_names() -> list[str]:
    ...
def normal_matrix(indptr: numpy.typing.NDArray[numpy.int32], indices: numpy.typing.NDArray[numpy.int32], data: numpy.typing.NDArray[numpy.float64], n_cols: typing.SupportsInt | typing.SupportsIndex, weights: typing.Any) -> tuple[numpy.typing.NDArray[numpy.int64], numpy.typing.NDArray[numpy.int32], numpy.typing.NDArray[numpy.float64]]:
    ...
def parse_boundary(name: str) -> Boundary:
    ...
def parse_method(name: str) -> Method:
    ...
def parse_omega(text: str) -> tuple[OmegaRule, float]:
    """
    (OmegaRule, omega) from 'auto', 'young' or a number.
    """
def parse_scheme(name: str) -> Scheme:
    ...
def point_file_points(path: str) -> int:
    """
    The number of points of a file FileChunks streams (a binary little-endian PLY's vertices, a .npy (k, 3)
    array), from its header; FileError (sorpia.MeshFileError) for any other file.
    """
def point_sample_mask(first: typing.SupportsInt | typing.SupportsIndex, count: typing.SupportsInt | typing.SupportsIndex, k: typing.SupportsInt | typing.SupportsIndex, sample_points: typing.SupportsInt | typing.SupportsIndex) -> numpy.typing.NDArray[numpy.bool]:
    """
    Which of points first .. first + count of k are in FileChunks' fixed sample of about sample_points.
    """
def pole(n: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def polygon_torus(nu: typing.SupportsInt | typing.SupportsIndex, nv: typing.SupportsInt | typing.SupportsIndex, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> tuple:
    ...
def quad_grid(nu: typing.SupportsInt | typing.SupportsIndex, nv: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def quad_irregular(n_vertices: typing.SupportsInt | typing.SupportsIndex, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> tuple:
    ...
def quad_torus(nu: typing.SupportsInt | typing.SupportsIndex, nv: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def read_mesh(path: str, triangulate: bool, tags: bool, attributes: bool, points: bool = False) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.int32], typing.Any, int, typing.Any, typing.Any]:
    ...
def read_point_file(path: str, first: typing.SupportsInt | typing.SupportsIndex, count: typing.SupportsInt | typing.SupportsIndex) -> numpy.typing.NDArray[numpy.float64]:
    """
    Points first .. first + count of a file FileChunks streams, (count, 3) float64 (a chunk read where it is
    used: a Dask worker).
    """
def refine_footpoints(surface: LimitSurface, topology: Topology, points: numpy.typing.NDArray[numpy.float64], face_ids: numpy.typing.NDArray[numpy.int32], uv: numpy.typing.NDArray[numpy.float64], max_steps: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def refine_uniform(topology: Topology, rules: Rules, levels: typing.SupportsInt | typing.SupportsIndex, vertices: numpy.typing.NDArray[numpy.float64] | None = None, refinement: bool = True) -> dict:
    """
    The mesh refined `levels` times by OpenSubdiv's Far (sorpia::refine_uniform): a dict with faces, n_vertices, tags, refinement (R as CSR arrays (data, indices, indptr); left out with refinement=False), vertices (R V, with vertices= V) and coarse_face.
    """
def refinement_bytes(n_vertices: typing.SupportsInt | typing.SupportsIndex, n_faces: typing.SupportsInt | typing.SupportsIndex, levels: typing.SupportsInt | typing.SupportsIndex, scheme: Scheme, n_face_vertices: typing.SupportsInt | typing.SupportsIndex = 0) -> int:
    ...
def regular_valence(scheme: Scheme) -> tuple[int, int]:
    """
    (inside, on the boundary): the valences of a regular vertex (sorpia::regular_valence).
    """
def repair(faces: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex) -> typing.Any:
    """
    sorpia::repair: None for a valid mesh, else (faces, vertex_map, face_map, report dict).
    """
def repair_polygons(face_vertex_counts: numpy.typing.NDArray[numpy.int32], face_vertex_indices: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex) -> typing.Any:
    """
    sorpia::repair of polygons: None for a valid mesh, else (face_vertex_counts, face_vertex_indices, vertex_map, face_map, report dict).
    """
def rms_levelled(bests: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex], tol: typing.SupportsFloat | typing.SupportsIndex, window: typing.SupportsInt | typing.SupportsIndex) -> bool:
    """
    approximation's stop test on the lowest RMS after each iteration (sorpia::rms_levelled).
    """
def robust_options(loss: str) -> tuple:
    """
    The default settings of a robust loss (sorpia::robust_options) as (loss, quantile, c).
    """
def scale_exponent(*args) -> int:
    """
    The exponent e of the core's exact scaling (sorpia/detail/scaling.hpp) for data whose largest magnitude
    is that of the arrays given: 0 within 2^+-200.
    """
def scheme_name(scheme: Scheme) -> str:
    ...
def sharp_edges(vertices: numpy.typing.NDArray[numpy.float64], face_vertex_counts: numpy.typing.NDArray[numpy.int32], face_vertex_indices: numpy.typing.NDArray[numpy.int32], angle_degrees: typing.SupportsFloat | typing.SupportsIndex) -> numpy.typing.NDArray[numpy.int32]:
    """
    (k, 2) edges whose faces meet at more than angle_degrees (sorpia::sharp_edges).
    """
def split_nonmanifold(faces: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex) -> typing.Any:
    """
    sorpia::split_nonmanifold: None for a manifold mesh, else (faces, vertex_map, report dict).
    """
def split_nonmanifold_polygons(face_vertex_counts: numpy.typing.NDArray[numpy.int32], face_vertex_indices: numpy.typing.NDArray[numpy.int32], n_vertices: typing.SupportsInt | typing.SupportsIndex) -> typing.Any:
    """
    sorpia::split_nonmanifold of polygons: None for a manifold mesh, else (face_vertex_counts, face_vertex_indices, vertex_map, report dict).
    """
def subface_columns(face_size: typing.SupportsInt | typing.SupportsIndex) -> int:
    ...
def tessellation_bytes(n_vertices: typing.SupportsInt | typing.SupportsIndex, n_faces: typing.SupportsInt | typing.SupportsIndex, level: typing.SupportsInt | typing.SupportsIndex, scheme: Scheme = Scheme.loop, n_face_vertices: typing.SupportsInt | typing.SupportsIndex = 0) -> int:
    ...
def torus(nu: typing.SupportsInt | typing.SupportsIndex, nv: typing.SupportsInt | typing.SupportsIndex) -> tuple:
    ...
def write_file_atomic(path: str, data: bytes) -> None:
    """
    Write bytes to path atomically (temporary file, fsync, rename).
    """
def write_mesh(path: str, vertices: numpy.typing.NDArray[numpy.float64], face_vertex_indices: numpy.typing.NDArray[numpy.int32], face_vertex_counts: numpy.typing.NDArray[numpy.int32] | None, face_size: typing.SupportsInt | typing.SupportsIndex, binary: bool, tags: Tags | None, boundary: Boundary | None, uv_values: numpy.typing.NDArray[numpy.float64] | None = None, uv_indices: numpy.typing.NDArray[numpy.int32] | None = None, normal_values: numpy.typing.NDArray[numpy.float64] | None = None, normal_indices: numpy.typing.NDArray[numpy.int32] | None = None) -> None:
    ...
DEFAULT_COARSE_ITERATIONS: int = 6
DEFAULT_COARSE_POINTS: float = 16.0
DEFAULT_COARSE_TOL: float = 0.01
DEFAULT_ROBUST: str = 'tukey'
INFINITE_SHARPNESS: float = 10.0
MAX_REFINEMENT_LEVELS: int = 10
MAX_THREADS: int = 1024
YOUNG_RHO_CLAMP: float = 0.9999
__version__: str = '0.1.0'
