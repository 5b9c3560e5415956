"""sorpia: interpolating subdivision surfaces.

Moves the control vertices of a mesh so that its limit surface (Loop for
triangles, Catmull-Clark for quads and polygons, with OpenSubdiv's creases,
corners and holes, as OpenSubdiv defines them) passes through the given
vertices: solves B V = V0 with SOR-PIA and the rest of the PIA family.
"""

from ._core import __version__
from .errors import MeshError, MeshFileError, ParameterError
from .limit import UnreferencedVerticesWarning, limit_matrix, limit_points
from .solve import (ConvergenceWarning, InterpolationResult, Interpolator, OmegaWarning, SingularMatrixWarning,
                    interpolate)
from .io import AttributeWarning, FaceVarying, UnknownTagWarning, read_mesh, write_mesh
from .sharp import sharp_edges
from ._validate import Polygons
from .mesh_repair import RepairResult, repair
from .nonmanifold import NonmanifoldWarning
from .surface import LimitSurface, LoopSurface, evaluate_limit, limit_surface
from . import shapes

__all__ = [
    "__version__",
    "MeshError",
    "MeshFileError",
    "ParameterError",
    "UnreferencedVerticesWarning",
    "ConvergenceWarning", "InterpolationResult", "Interpolator", "OmegaWarning", "SingularMatrixWarning",
    "interpolate",
    "limit_matrix",
    "Polygons",
    "limit_points",
    "shapes",
    "LimitSurface", "LoopSurface", "evaluate_limit", "limit_surface", "read_mesh", "write_mesh",
    "UnknownTagWarning", "AttributeWarning", "FaceVarying", "sharp_edges",
    "RepairResult", "repair",
    "NonmanifoldWarning",
]
