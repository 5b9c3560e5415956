"""Sharp features found from the geometry: the edges where faces meet at a
large angle, to be kept as infinitely sharp creases (``--sharp-angle``)."""

from __future__ import annotations

from typing import Optional

import numpy as np

from . import _core
from ._mesh import SubdivisionMesh
from ._validate import as_polygons, as_vertices


def sharp_edges(vertices, faces=None, angle_degrees: Optional[float] = None) -> np.ndarray:
    """The edges whose two faces' normals are more than `angle_degrees` apart.

    Computed on OpenMesh's half-edge mesh (a PolyMesh with double points,
    sorpia::sharp_edges): a face's normal is OpenMesh's ``calc_face_normal``
    (Newell's method; for a triangle the normalised cross product), the angle
    between two unit normals ``atan2(|n0 x n1|, n0 . n1)``: 0 between coplanar
    faces, 90 across a cube's edge. Boundary edges and edges beside a face of
    zero area are never sharp.

    Parameters
    ----------
    vertices : (n, 3) float, or sorpia.SubdivisionMesh
        The vertices, or a mesh (``sharp_edges(mesh, angle_degrees)``).
    faces : (m, k) int array, list of index lists, or sorpia.Polygons
    angle_degrees : float
        In [0, 180]; an edge is sharp when its angle exceeds it.

    Returns
    -------
    (k, 2) int32
        Each edge's two vertices, smaller first, rows sorted: ready for
        ``creases=(edges, numpy.inf)``.

    Raises
    ------
    ParameterError
        An angle outside [0, 180].
    MeshError
        A face OpenMesh's half-edge mesh cannot take (an edge of three faces,
        a bowtie vertex, inconsistent orientation), named.
    """
    if isinstance(vertices, SubdivisionMesh):
        if faces is not None:  # sharp_edges(mesh, angle)
            if angle_degrees is not None:
                raise TypeError("sharp_edges(mesh, angle_degrees): the faces come from the SubdivisionMesh")
            angle_degrees = faces
        vertices, faces = vertices.vertices, vertices.faces
    if angle_degrees is None:
        raise TypeError("sharp_edges needs angle_degrees")
    vertices = as_vertices(vertices)
    counts, indices = as_polygons(faces, len(vertices), count_name="len(vertices)")
    return _core.sharp_edges(vertices, counts, indices, float(angle_degrees))


__all__ = ["sharp_edges"]
