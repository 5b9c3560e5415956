"""sorpia: subdivision surfaces through given points.

Moves the control vertices of a mesh so that its limit surface (Loop for
triangle meshes, Catmull-Clark for quad and polygon meshes, with OpenSubdiv's
creases, corners and holes, as OpenSubdiv defines them) passes through the
given vertices: solves B V = V0 with SOR-PIA and the rest of the PIA family.
"""

from ._core import __version__
from .errors import (AttributeWarning, ConvergenceWarning, DecimationWarning, FormatWarning, MeshError, MeshFileError,
                     NonmanifoldWarning, OmegaWarning, ParameterError, SingularMatrixWarning, SorpiaWarning,
                     UnknownTagWarning, UnreferencedVerticesWarning, UsdWarning)
from ._mesh import FaceVarying, SubdivisionMesh
from ._validate import resolve_scheme
from .limit import limit_matrix, limit_points
from .solve import InterpolationResult, Interpolator, interpolate
from .io import read, read_mesh, write_mesh
from ._sharp import sharp_edges
from ._validate import Polygons
from ._repair import RepairResult, repair
from ._meshinfo import mesh_statistics
from .surface import LimitSurface, evaluate_limit, limit_surface
from .cage import Cage, decimate
from .energy import fairness_matrix, thin_plate_energy
from .fair import FairResult, fair_interpolate
from .approximate import ApproximationResult, approximate, surface_samples
from . import shapes

__all__ = [
    "__version__",
    "SubdivisionMesh", "read", "resolve_scheme",
    "MeshError",
    "MeshFileError",
    "ParameterError",
    "SorpiaWarning",
    "FormatWarning",
    "UnreferencedVerticesWarning",
    "ConvergenceWarning", "InterpolationResult", "Interpolator", "OmegaWarning", "SingularMatrixWarning",
    "interpolate",
    "limit_matrix",
    "Polygons",
    "limit_points",
    "shapes",
    "LimitSurface", "evaluate_limit", "limit_surface", "read_mesh", "write_mesh",
    "UnknownTagWarning", "AttributeWarning", "FaceVarying", "sharp_edges",
    "RepairResult", "repair",
    "mesh_statistics",
    "fairness_matrix", "thin_plate_energy",
    "FairResult", "fair_interpolate",
    "NonmanifoldWarning", "UsdWarning", "DecimationWarning",
    "Cage", "decimate",
    "ApproximationResult", "approximate", "surface_samples",
]
