"""Exceptions and warnings raised by sorpia.

The exceptions are subclasses of ValueError, so ``except ValueError`` catches
bad input of every kind; each message names the problem and where it is
(vertex, face or edge index, or line number in a file).

The warnings are subclasses of `SorpiaWarning`, so one filter
(``warnings.simplefilter("error", sorpia.SorpiaWarning)``) turns every one of
them into an error, or silences them all.
"""

from ._core import MeshError, MeshFileError, ParameterError

# The classes are made by the binding (pybind11's register_exception), which
# gives them no docstring; the documentation is here, with the Python API.
MeshError.__doc__ = """The faces or coordinates cannot be used: an index out of range, a repeated
vertex, duplicate faces, an edge of three or more faces, inconsistent
orientation, a bowtie vertex, a non-finite coordinate. The message names the
face, edge or vertex."""
ParameterError.__doc__ = """An option is out of range or does not apply: a method, omega, tol,
max_iter, boundary, level or thread count. The message names the parameter
and the value given."""
MeshFileError.__doc__ = """A mesh file cannot be read or written: missing, a directory, truncated,
malformed, of an unknown format, or holding polygons without
``triangulate=True``. The message names the file and the line (text) or
element (binary)."""



class SorpiaWarning(UserWarning):
    """The base class of every warning sorpia issues."""


class ConvergenceWarning(SorpiaWarning):
    """A solve stopped at max_iter or diverged before reaching tol; the message
    names the method that would work (result.recommended)."""


class SingularMatrixWarning(SorpiaWarning):
    """B is singular and the targets have a part outside its range: the result
    is the least-squares control mesh of least norm (stop_reason "singular"),
    and the message says how far the targets are missed and where
    (result.worst_vertices); or a solve stopped short on a mesh whose B is
    singular on a part known in closed form (`sorpia.limit.singular_cubes`)."""


class OmegaWarning(SorpiaWarning):
    """omega="young" met rho(I - D^-1 B) >= 0.9999: Young's formula has no real value (rho >= 1) or none of use."""


class UnreferencedVerticesWarning(SorpiaWarning):
    """Some vertices belong to no face; their limit is themselves."""


class UnknownTagWarning(SorpiaWarning):
    """An OBJ file has `t` tags sorpia does not know; they are skipped, as
    OpenSubdiv's own shape parser skips them."""


class AttributeWarning(SorpiaWarning):
    """A file's texture coordinates or normals that cannot be kept: given on
    some face corners and not others (OpenSubdiv's face-varying channels need
    a value at every corner)."""


class UsdWarning(SorpiaWarning):
    """What a USD stage holds that sorpia reads or writes otherwise than as it
    is: time-sampled points (one time is read, and the fitted cage written
    without samples), a primvar sorpia cannot carry, primvars that no longer
    fit the faces written."""


class FormatWarning(SorpiaWarning):
    """A file format cannot hold a rule a mesh is written with (the scheme,
    a boundary rule other than the default, sharpness tags): the file is
    written without it, and the message names what is left out and the
    formats that hold it (`sorpia.io.write_mesh_file`)."""


class DecimationWarning(SorpiaWarning):
    """`sorpia.decimate` with ``strict=False``: the guards refused every
    further collapse before the count asked; the cage returned has the
    vertices decimation reached, and the message says how many of how many."""


class NonmanifoldWarning(SorpiaWarning):
    """nonmanifold="sharp" on a non-manifold mesh: OpenSubdiv's documentation
    calls the surface of non-manifold topology undefined for now."""


__all__ = ["MeshError", "MeshFileError", "ParameterError", "SorpiaWarning", "ConvergenceWarning",
           "SingularMatrixWarning", "OmegaWarning", "UnreferencedVerticesWarning", "UnknownTagWarning",
           "AttributeWarning", "UsdWarning", "FormatWarning", "NonmanifoldWarning", "DecimationWarning"]
