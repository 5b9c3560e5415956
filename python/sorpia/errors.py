"""Exceptions raised by sorpia.

All are subclasses of ValueError, so ``except ValueError`` catches bad input of
every kind; each message names the problem and where it is (vertex, face or
edge index, or line number in a file).
"""

from ._core import MeshError, MeshFileError, ParameterError

__all__ = ["MeshError", "MeshFileError", "ParameterError"]
