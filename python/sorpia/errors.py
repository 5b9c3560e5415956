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
    """A solve stopped at max_iter or diverged before reaching tol."""


class SingularMatrixWarning(SorpiaWarning):
    """The limit matrix B is singular (or numerically so) on the mesh solved:
    targets with a component along its null space cannot be interpolated."""


class OmegaWarning(SorpiaWarning):
    """omega="young" met rho(I - D^-1 B) >= 0.9999: Young's formula has no real value (rho >= 1) or none of use."""


class UnreferencedVerticesWarning(SorpiaWarning):
    """Some vertices belong to no face; their limit is themselves."""


class UnknownTagWarning(SorpiaWarning):
    """An OBJ file has `t` tags sorpia does not know; they are skipped, as
    OpenSubdiv's own shape parser skips them."""


class NonmanifoldWarning(SorpiaWarning):
    """nonmanifold="sharp" on a non-manifold mesh: OpenSubdiv's documentation
    calls the surface of non-manifold topology undefined for now."""


__all__ = ["MeshError", "MeshFileError", "ParameterError", "SorpiaWarning", "ConvergenceWarning",
           "SingularMatrixWarning", "OmegaWarning", "UnreferencedVerticesWarning", "UnknownTagWarning",
           "NonmanifoldWarning"]
