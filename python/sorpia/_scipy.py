"""scipy where a function needs it: imported on first use, not by ``import sorpia``.

``import sorpia`` needs numpy alone: Blender ships numpy but no scipy, and scipy.sparse is about half of
sorpia's import time, which every command pays. Interpolation, fair interpolation, approximation, the limit
points and surface, and mesh files need no scipy; what builds or takes a scipy sparse matrix
(`sorpia.limit_matrix`, `sorpia.fairness_matrix`, `LimitSurface.rows`, `Interpolator.limit_matrix`,
`FairResult.refinement`) gets it from `sparse`, which names the function and the package when scipy is missing.
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from scipy.sparse import csr_matrix as CSRMatrix
else:
    # At run time the annotations' name for a scipy CSR matrix must resolve without importing scipy
    # (typing.get_type_hints evaluates them in the module's namespace). scipy ships no type information, so
    # a type checker without scipy-stubs sees Any there too.
    CSRMatrix = Any

INSTALL_HINT = "pip install scipy"


def sparse(needed_by: str) -> ModuleType:
    """scipy.sparse, imported now; `needed_by` (e.g. "sorpia.limit_matrix") names the caller in the
    ImportError raised when scipy is not installed."""
    try:
        return importlib.import_module("scipy.sparse")
    except ImportError as exc:
        raise ImportError(f"{needed_by} needs scipy, which is not installed here: {INSTALL_HINT} "
                          "(interpolation, fair interpolation, approximation, limit surfaces and mesh files "
                          "work without it)",
                          name="scipy") from exc
