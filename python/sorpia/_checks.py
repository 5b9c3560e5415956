"""Checks of a result against its targets, independent of the solver that
made it: what the command line reports as "check" after writing a control
mesh (its vertices as read back from the file)."""

from __future__ import annotations

import numpy as np

from . import _core
from ._validate import as_boundary
from .limit import limit_points

# e such that arrays times 2^-e lie within 2^+-200 (0 where they do already): the core's exact scaling
# (sorpia/detail/scaling.hpp), which keeps squares inside double's range; the solvers scale their data by it.
scale_exponent = _core.scale_exponent


def interpolation_miss(control_vertices, targets, faces, *, boundary, scheme: str = "loop", tags=None,
                       topology=None, rows=None) -> float:
    """max_i ||(B V)_i - t_i||: the largest distance of the limit positions of
    `control_vertices` (B: the scheme's limit stencils with `boundary` and
    the sharpness `tags`) from their `targets`, over `rows` (the vertex
    indices targets[j] belongs to; None: every vertex, targets (n, 3)).

    Loop without tags and with `topology` given (a _core.Topology of the
    faces): OpenSubdiv's masks over the one-ring (the core's limit_residual);
    otherwise the library's limit points. Coordinates beyond 2^+-200 in
    magnitude are checked scaled by a power of two and the result scaled
    back (exact), so that the norm's squares do not overflow (1e200 gives a
    finite miss, not inf) or underflow."""
    ctrl = np.asarray(control_vertices, dtype=np.float64)
    targets = np.asarray(targets, dtype=np.float64)
    e = scale_exponent(ctrl, targets)
    ctrl, targets = np.ldexp(ctrl, -e), np.ldexp(targets, -e)
    tags = tags or {}
    if rows is None and topology is not None and scheme == "loop" and not tags:
        miss = float(_core.limit_residual(topology, np.ascontiguousarray(ctrl), np.ascontiguousarray(targets),
                                          as_boundary(boundary))[0])
    else:
        kwargs = {} if scheme == "loop" else {"scheme": scheme}
        hit = limit_points(ctrl, faces, boundary=boundary, **kwargs, **tags)
        if rows is not None:
            hit = hit[np.asarray(rows)]
        miss = float(np.linalg.norm(hit - targets, axis=1).max()) if len(hit) else 0.0
    return float(np.ldexp(miss, e))
