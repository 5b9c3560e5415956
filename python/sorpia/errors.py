"""Exceptions raised by sorpia.

All are subclasses of ValueError, so ``except ValueError`` catches bad input of
every kind; each message names the problem and where it is (vertex, face or
edge index, or line number in a file).
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

__all__ = ["MeshError", "MeshFileError", "ParameterError"]
