"""Light cages for dense meshes: OpenMesh's quadric decimation down to a
given number of vertices, its triangles paired into quads for Catmull-Clark, with the sharp
edges found on the cage as creases. The control mesh that
approximation (issue 23) fits to a scan's points."""

from __future__ import annotations

import warnings
from typing import NamedTuple, Optional

import numpy as np

from . import _core
from ._sharp import sharp_edges
from .errors import DecimationWarning
from ._mesh import SubdivisionMesh
from ._validate import AUTO_SCHEME, DEFAULT_SCHEME, Polygons, as_faces, as_scheme, as_vertex_count, as_vertices, resolve_scheme


class Cage(NamedTuple):
    """A control mesh made by `decimate`.

    Attributes
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int32 triangles (Loop); under Catmull-Clark (m, 4) int32
        quads, or `sorpia.Polygons` of quads and the triangles their pairing
        left
    creases : ``(edges (k, 2) int32, sharpness (k,) float64)`` or None
        The cage's edges sharper than `sharp_angle`, infinitely sharp: ready
        for ``creases=`` of `sorpia.interpolate`, `sorpia.limit_surface` and
        the rest. None without a `sharp_angle`.

    ``mesh`` is the cage as a `sorpia.SubdivisionMesh` (its scheme from its
    faces: triangles Loop, quads Catmull-Clark; its creases), ready for
    ``sorpia.approximate(points, cage.mesh)``; ``report()`` its report, as
    every sorpia result gives it: a JSON-ready dict.
    """

    vertices: np.ndarray
    faces: np.ndarray
    creases: Optional[tuple]

    @property
    def mesh(self) -> SubdivisionMesh:
        """The cage with its scheme and creases."""
        return SubdivisionMesh(self.vertices, self.faces, creases=self.creases)

    def report(self) -> dict:
        """The cage's sizes, scheme and creases as a JSON-ready dict."""
        return {"n_vertices": int(len(self.vertices)), "n_faces": int(len(self.faces)),
                "scheme": resolve_scheme(AUTO_SCHEME, self.faces),
                "n_creases": 0 if self.creases is None else int(len(self.creases[0]))}


def decimate(vertices, faces=None, n_vertices: Optional[int] = None, *, scheme: str = DEFAULT_SCHEME,
             sharp_angle: Optional[float] = None,
             max_normal_deviation: float = 60.0, max_aspect_ratio: float = 10.0,
             max_boundary_angle: float = 30.0, strict: bool = True) -> Cage:
    """A cage of ``n_vertices`` vertices for a dense triangle mesh.

    OpenMesh's Decimater framework collapses edges in the order of Garland
    and Heckbert's quadric error (``ModQuadricT``; a collapse moves a vertex
    onto a neighbour, so the cage's vertices are vertices of the mesh),
    refusing any collapse that turns a face's normal by more than
    `max_normal_deviation` degrees (``ModNormalFlippingT``), that leaves a
    face with an aspect ratio above `max_aspect_ratio` unless it improves the
    worst one around (``ModAspectRatioT``), or that removes a boundary vertex
    where the boundary turns by more than `max_boundary_angle` degrees (so
    that the outline and corners of an open mesh stay; 0 removes them only
    where the boundary runs straight, 180 leaves them to the quadric).
    A mesh of 200,000 vertices or more and over 8 times ``n_vertices`` is
    first clustered on a grid to about 4 times ``n_vertices`` (Lindstrom's
    vertex clustering: each cluster becomes its vertex of least summed
    quadric; boundary vertices and their neighbours are kept) and
    decimated from there, in a fraction of the time (docs/cages.md).

    Under Catmull-Clark the same decimation's triangles (``n_vertices``
    vertices, as Loop's) are paired into quads across their edges, the
    best-shaped quads first (corners nearest right angles, the two triangles
    nearest flat; no reflex corner, no vertex left with two edges), then
    along augmenting paths that pair two left-over triangles more. Triangles that find no
    partner stay triangles (Catmull-Clark takes them as n-gons): the faces
    are then `sorpia.Polygons`, an (m, 4) array when every triangle paired.

    Parameters
    ----------
    vertices : (n, 3) float, or sorpia.SubdivisionMesh
        The mesh's vertices; or a triangle mesh (``decimate(mesh, 500)``:
        the vertex count then comes second).
    faces : (m, 3) int
        Triangles, manifold and consistently oriented (`sorpia.repair` makes
        a mesh so). Vertices no face uses are left out.
    n_vertices : int
        The cage's vertices: at least 4, at most the mesh's.
    scheme : {"auto", "loop", "catmull-clark"}
        The cage's: Loop gives a triangle cage, Catmull-Clark a cage of
        quads (and a few triangles; above); "auto" (the default) is a mesh's
        own scheme, and Loop for arrays
        (resolved on the input's triangles).
    sharp_angle : float, optional
        Degrees in [0, 180]: the cage's edges whose faces meet at more than
        this (`sorpia.sharp_edges` on the cage) become infinitely sharp
        creases.
    max_normal_deviation, max_aspect_ratio, max_boundary_angle : float
        The decimation's guards, above.
    strict : bool
        True: a decimation the guards stop before ``n_vertices`` raises
        `MeshError`. False: it returns the cage it reached (more vertices than
        asked) with a `DecimationWarning` saying how far it got, unless no
        collapse at all was allowed (every vertex a corner of a hole or of
        the outline): that cage, every vertex of the mesh, is no lighter than
        the data and raises `MeshError` either way.

    Returns
    -------
    Cage
        ``(vertices, faces, creases)``.

    Raises
    ------
    MeshError
        A face that is not a triangle, a mesh OpenMesh's half-edge mesh
        cannot take (the face named), ``n_vertices`` above the mesh's, or
        (`strict`) a decimation the guards stop before ``n_vertices`` (the
        message says how far it got), or one that can remove no vertex.
    ParameterError
        ``n_vertices`` below 4, an unknown scheme, an angle or ratio out of range.
    """
    if isinstance(vertices, SubdivisionMesh):  # decimate(mesh, n_vertices)
        if faces is not None:  # decimate(mesh, n)
            if n_vertices is not None:
                raise TypeError("decimate(mesh, n_vertices): the faces come from the SubdivisionMesh")
            n_vertices = faces
        if scheme == DEFAULT_SCHEME:  # the mesh's scheme (a triangle mesh marked Catmull-Clark: a quad cage)
            scheme = vertices.scheme
        vertices, faces = vertices.vertices, vertices.faces
    vertices = as_vertices(vertices)
    triangles = as_faces(faces, len(vertices), count_name="len(vertices)")
    n = as_vertex_count(n_vertices, "n_vertices")
    scheme_value = as_scheme(scheme, triangles)
    if sharp_angle is not None:  # the angle's one check (sorpia::sharp_edges), before the decimation's long work
        _core.sharp_edges(np.zeros((0, 3)), np.zeros(0, np.int32), np.zeros(0, np.int32), float(sharp_angle))
    mesh, stopped = _core.decimate(vertices, triangles, n, scheme_value, float(max_normal_deviation),
                                   float(max_aspect_ratio), float(max_boundary_angle), bool(strict))
    if stopped is not None:
        warnings.warn(stopped, DecimationWarning, stacklevel=2)
    if scheme_value == _core.Scheme.loop:
        cage_vertices, cage_faces = mesh
    else:
        cage_vertices, counts, indices = mesh
        # All quads as an (m, 4) array; quads and the triangles the pairing left as Polygons.
        cage_faces = indices.reshape(len(counts), 4) if (counts == 4).all() else Polygons(counts, indices)
    creases = None
    if sharp_angle is not None:
        edges = sharp_edges(cage_vertices, cage_faces, sharp_angle)
        creases = (edges, np.full(len(edges), _core.INFINITE_SHARPNESS))
    return Cage(cage_vertices, cage_faces, creases)


__all__ = ["Cage", "decimate"]
