"""The fairness energy of a limit surface: thin plate and membrane, as a
sparse symmetric quadratic form in the control vertices (Halstead, Kass &
DeRose 1993), the energy fair interpolation minimises and approximation's
fairness term adds.

``E(V) = sum over columns c of V[:, c] @ K @ V[:, c]`` with

``K = thin_plate * integral (|S_xx|^2 + 2 |S_xy|^2 + |S_yy|^2) + membrane * integral (|S_x|^2 + |S_y|^2)``

over the faces' parameter domains (holes left out), S the limit surface as a
function of its control values.

The measure (x, y): Catmull-Clark integrates in Bfr's parameters (x, y) = (u,
v) (`sorpia.surface`): a quad is the unit square (area 1), each of a k-gon's k
sub-faces a square of side 1/2 (area 1/4, as a quarter of a quad), so a k-gon
counts as k/4 quads, as it does after one subdivision step. Loop maps each
triangle onto the equilateral triangle of side 1 (x = u + v/2, y = v
sqrt(3)/2, area sqrt(3)/4), so that K does not depend on which corner a face
lists first and a flat regular triangle grid has a membrane energy of twice
its area.

The quadrature: OpenSubdiv's stencils (`LimitSurface.rows`, first and second
derivatives). Each face's domain is split ``depth`` times towards its
irregular corners (extraordinary, boundary and tagged vertices, a k-gon's
centre) and tagged edges, following the rings of polynomial pieces of Bfr's
surface there. A Catmull-Clark piece away from them is a bicubic B-spline
piece, integrated in closed form from the derivatives at 2 x 2 points; the
others (all Loop pieces, and the pieces at the marks) by Gauss-Legendre, n x n
on squares and the collapsed n x n rule on triangles (``gauss_points`` = n =
4 is exact on polynomial pieces: bicubic B-splines, Loop's quartic box
splines). Only the last corner piece (Bfr's Gregory patch, within 2^-4 of an
extraordinary corner) is integrated approximately: ``bench/energy.py``
measures the error against much finer rules (about 1e-4 relative under
Catmull-Clark and 5e-3 under Loop on irregular meshes, at the defaults).
A face's energy, as a quadratic form over its control points, depends only on
its local topology: faces that agree in it (size, valences and boundary
places of the corners) share one element matrix, computed once, so a once
refined mesh (a few extraordinary vertices among regular ones) costs little
more than gathering the matrix; faces near tags, holes or n-gons are
integrated on their own.

Near an extraordinary vertex whose subdominant eigenvalue lambda exceeds 1/2
(Catmull-Clark valence 5 and more, Loop 7 and more) the parametric thin-plate
energy of the exact limit surface grows by 4 lambda^2 from one ring of
polynomial pieces to the next, so its integral diverges: K measures Bfr's
surface, whose corner patch is a Gregory patch after 4 local refinements (10
on meshes with darts). Constant control values have zero energy; affine
functions of the parameters have zero energy where every face is regular (a
flat regular grid), not near extraordinary vertices, where the
parameterisation is not affine.

Semi-sharp creases and corners (``semi_sharp``): a crease of sharpness s
turns the surface within a layer about 2^-s of a face wide, and the bending
in that layer, of order 2^s times the square of the crease's turn per unit
of its length, dominates the parametric thin-plate energy of a surface with
sharp features (OpenSubdiv's shapes carry sharpness 6 to 8). Minimising it
undoes the crease: the surface turns less there and bends more everywhere
else. ``semi_sharp="sharp"`` (the default) measures the energy of the surface
with every semi-sharp tag made infinitely sharp, which agrees with the
surface away from the layers and measures the bending on each side of a
crease, leaving the crease's own turn free, as an infinitely sharp crease
is; ``"as-tagged"`` integrates the surface as tagged, layers included.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from . import _core, _scipy
from ._mesh import mesh_arguments, mesh_count
from ._validate import DEFAULT_BOUNDARY, DEFAULT_SCHEME, as_integer, as_real, as_rules, as_vertices
from .limit import built, warn_unreferenced
from .errors import ParameterError

__all__ = ["fairness_matrix", "thin_plate_energy"]

SEMI_SHARP = ("sharp", "as-tagged")


def fairness_matrix(faces, n_vertices: Optional[int] = None, *, scheme: str = DEFAULT_SCHEME,
                    boundary: str = DEFAULT_BOUNDARY,
                    creases=None, corners=None, holes=None, thin_plate: float = 1.0, membrane: float = 0.0,
                    gauss_points: int = 4, depth: int = 4, semi_sharp: str = "sharp", reference=None):
    """The fairness matrix K of a mesh's limit surface, (n, n) scipy CSR,
    symmetric positive semidefinite: ``V[:, c] @ K @ V[:, c]`` summed over the
    columns is the energy of control vertices V (see the module docstring
    for the energy, its measure and its quadrature).

    Parameters
    ----------
    faces, n_vertices, scheme, boundary, creases, corners, holes
        The mesh and its rules, as for `sorpia.limit_matrix` (a
        `sorpia.SubdivisionMesh` for all of them: ``fairness_matrix(mesh)``).
        K depends on them alone, not on the vertices' positions.
    thin_plate, membrane : float
        Weights of the two terms, finite and >= 0, not both 0.
    gauss_points : int
        Gauss-Legendre points per direction on each piece, 1..16 (4: exact on
        regular patches).
    depth : int
        Splits of a face's domain towards its irregular corners and tagged
        edges, 0..12 (4: Bfr's own refinement there).
    semi_sharp : {"sharp", "as-tagged"}
        How semi-sharp creases and corners enter the energy (module
        docstring): "sharp" measures the surface with them infinitely sharp,
        the bending on each side of a crease; "as-tagged" the surface as
        tagged, the thin layer where a crease turns included.
    reference : (n, 3) array_like float, optional (n the vertex count)
        None: the parametric measure (module docstring). Given: each face is
        measured in a fixed first fundamental form G, that of the limit
        surface of these control vertices at the face's centre (a reference
        shape: fair interpolation passes the input mesh refined), so that a
        face's energy is the integral of tr(G^-1 H G^-1 H) sqrt(det G) per
        coordinate (membrane: tr(G^-1 J^T J) sqrt(det G)), H the Hessian and
        J the Jacobian in Bfr's (u, v); at faces with an extraordinary
        corner the parametric shape scaled to the area sqrt(det G), since
        Bfr's parameterisation there is far from affine within the face.
        Invariant (thin plate) under rotations and uniform scalings of
        the coordinates; every face integrated on its own (slower); needs
        a mesh of triangles (Loop) or quads (Catmull-Clark) only.

    Returns
    -------
    scipy.sparse.csr_matrix
        (n, n) float64, columns sorted within each row; unreferenced vertices
        have empty rows.

    Raises
    ------
    sorpia.ParameterError
        A weight negative, not finite or both zero; gauss_points, depth or
        semi_sharp out of range (the message names the option).
    """
    sparse = _scipy.sparse("sorpia.fairness_matrix")

    semi_sharp = check_semi_sharp(semi_sharp)
    faces, n_vertices, given = mesh_count(faces, n_vertices, dict(
        scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes), "fairness_matrix")
    arrays, n, rules = as_rules(faces, n_vertices, **given)
    topo = built(lambda: _core.Topology(*arrays, n))
    warn_unreferenced(topo, stacklevel=3)
    if reference is not None:
        reference = as_vertices(reference)
    data, indices, indptr = matrix_arrays(topo, rules, thin_plate, membrane, gauss_points, depth, semi_sharp,
                                          reference)
    return sparse.csr_matrix((data, indices, indptr), shape=(n, n))


def thin_plate_energy(vertices, faces=None, *, scheme: str = DEFAULT_SCHEME, boundary: str = DEFAULT_BOUNDARY,
                      creases=None, corners=None, holes=None, thin_plate: float = 1.0, membrane: float = 0.0,
                      gauss_points: int = 4, depth: int = 4, semi_sharp: str = "sharp") -> float:
    """The fairness energy of the limit surface of control vertices
    `vertices` (n, 3): ``sum(V * (K @ V))`` with K = `fairness_matrix` of the
    same faces, rules and options (by default the thin-plate term alone).
    ``thin_plate_energy(mesh)`` and ``thin_plate_energy(V, mesh)`` take a
    `sorpia.SubdivisionMesh`."""
    vertices, faces, rules = mesh_arguments(vertices, faces, dict(
        scheme=scheme, boundary=boundary, creases=creases, corners=corners, holes=holes), "thin_plate_energy")
    vertices = as_vertices(vertices)
    k = fairness_matrix(faces, vertices.shape[0], **rules, thin_plate=thin_plate, membrane=membrane,
                        gauss_points=gauss_points,
                        depth=depth, semi_sharp=semi_sharp)
    return float(np.sum(vertices * (k @ vertices)))


def _options(thin_plate, membrane, gauss_points, depth) -> tuple:
    """The options as the core takes them; the core checks their ranges once."""
    return (as_real(thin_plate, "thin_plate"), as_real(membrane, "membrane"),
            min(as_integer(gauss_points, "gauss_points", "an integer in 1..16"), 2**31 - 1),
            min(as_integer(depth, "depth", "an integer in 0..12"), 2**31 - 1))


def check_semi_sharp(semi_sharp) -> str:
    """The semi_sharp option, checked (ParameterError naming it)."""
    if not isinstance(semi_sharp, str) or semi_sharp not in SEMI_SHARP:
        raise ParameterError(f"semi_sharp must be one of {', '.join(map(repr, SEMI_SHARP))}, got {semi_sharp!r}")
    return semi_sharp


def energy_tags(tags: _core.Tags, n_vertices: int, n_faces: int, semi_sharp: str = "sharp") -> _core.Tags:
    """The tags K integrates: `tags` as given ("as-tagged"), or with every
    positive sharpness made infinite (INFINITE_SHARPNESS, "sharp"; sharpness 0 stays
    smooth)."""
    if semi_sharp == "as-tagged" or tags.max_semi_sharpness() <= 0:
        return tags

    def sharp(s):
        s = np.asarray(s, dtype=np.float64)
        return np.ascontiguousarray(np.where(s > 0, _core.INFINITE_SHARPNESS, s))

    return _core.Tags(np.asarray(tags.crease_vertices, dtype=np.int32), sharp(tags.crease_sharpness),
                      np.asarray(tags.corner_vertices, dtype=np.int32), sharp(tags.corner_sharpness),
                      np.asarray(tags.holes, dtype=np.int32), n_vertices, n_faces)


def matrix_arrays(topology: _core.Topology, rules: _core.Rules, thin_plate=1.0, membrane=0.0, gauss_points=4,
                  depth=4, semi_sharp="sharp", reference=None) -> tuple:
    """K of a topology already built, under `rules`, as CSR arrays (data,
    indices, indptr): what `fairness_matrix` returns. The surface's vertices
    are zero: K does not use them (the reference, when given, sets each
    face's metric). Fair interpolation builds its K in the core, next to the
    solve that uses it, with the same tags (`energy_tags`). `semi_sharp`
    as check_semi_sharp returns it."""
    tags = energy_tags(rules.tags, topology.n_vertices, topology.n_faces, semi_sharp)  # checked by the caller
    return _core.fairness_matrix(topology, _core.Rules(scheme=rules.scheme, boundary=rules.boundary, tags=tags),
                                 *_options(thin_plate, membrane, gauss_points, depth),
                                 reference=None if reference is None else np.ascontiguousarray(reference, np.float64))
