"""The fairness matrix K (sorpia.fairness_matrix): thin-plate and membrane
energies of the limit surface against closed forms computed here in numpy
(the uniform bicubic B-spline, a quartic fitted to Bfr's positions on Loop's
regular patches), its null space, symmetry and definiteness, convergence of
the quadrature near extraordinary vertices, and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.polynomial import polynomial as P

import sorpia

SQ3 = math.sqrt(3.0)


# ---- meshes -----------------------------------------------------------------

def periodic_quads(n: int):
    """An n x n grid of quads on a torus (every vertex of valence 4): every
    patch a uniform bicubic B-spline. Vertex (i, j) is i + n j; face (i, j) is
    ((i, j), (i+1, j), (i+1, j+1), (i, j+1)), u along i, v along j."""
    idx = lambda i, j: (i % n) + n * (j % n)  # noqa: E731
    return np.array([[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]
                     for j in range(n) for i in range(n)], dtype=np.int32)


def periodic_triangles(n: int):
    """An n x n grid on a torus, each square cut along its (i+1, j)-(i, j+1)
    diagonal: every vertex of valence 6, every patch a quartic box spline."""
    idx = lambda i, j: (i % n) + n * (j % n)  # noqa: E731
    faces = []
    for j in range(n):
        for i in range(n):
            faces.append([idx(i, j), idx(i + 1, j), idx(i, j + 1)])
            faces.append([idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)])
    return np.array(faces, dtype=np.int32)


def flat_quad_grid(n: int, a: float = 1.0, b: float = 1.0):
    """A flat (n - 1) x (n - 1) quad grid of spacing a by b, with boundary."""
    x, y = np.meshgrid(np.arange(n) * a, np.arange(n) * b, indexing="xy")
    v = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])
    f = [[i + n * j, i + 1 + n * j, i + 1 + n * (j + 1), i + n * (j + 1)] for j in range(n - 1) for i in range(n - 1)]
    return v, np.array(f, dtype=np.int32)


def cube():
    v = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], dtype=float)
    f = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]], dtype=np.int32)
    return v, f


# ---- the closed form of the uniform bicubic B-spline ---------------------------

# The four cubic B-spline pieces on [0, 1], power basis (lowest degree first).
BSPLINE = [np.array(c) / 6.0 for c in ([1, -3, 3, -1], [4, 0, -6, 3], [1, 3, 3, -3], [0, 0, 0, 1])]


def gram(k: int) -> np.ndarray:
    """G[a, c] = integral over [0, 1] of B_a^(k) B_c^(k), exactly (polynomial
    antiderivative)."""
    d = [P.polyder(b, k) if k else b for b in BSPLINE]
    g = np.empty((4, 4))
    for a in range(4):
        for c in range(4):
            anti = P.polyint(P.polymul(d[a], d[c]))
            g[a, c] = P.polyval(1.0, anti) - P.polyval(0.0, anti)
    return g


def bspline_reference(n: int, thin_plate: float, membrane: float) -> np.ndarray:
    """K of the periodic quad grid, dense, from the bicubic B-spline element:
    point (u, v) of face (i, j) is sum B_a(u) B_b(v) P[i - 1 + a, j - 1 + b]."""
    g0, g1, g2 = gram(0), gram(1), gram(2)
    # element[(a, b), (c, d)], index a + 4 b as the patch points below
    elem = thin_plate * (np.kron(g0, g2) + 2.0 * np.kron(g1, g1) + np.kron(g2, g0)) + \
        membrane * (np.kron(g0, g1) + np.kron(g1, g0))
    k = np.zeros((n * n, n * n))
    for j in range(n):
        for i in range(n):
            pts = [((i - 1 + a) % n) + n * ((j - 1 + b) % n) for b in range(4) for a in range(4)]
            k[np.ix_(pts, pts)] += elem
    return k


# ---- the regular Loop patch as a polynomial fitted to Bfr's positions ----------

MONOMIALS = [(a, d - a) for d in range(5) for a in range(d + 1)]  # u^a v^b, total degree <= 4


def triangle_moment(a: int, b: int) -> float:
    """Integral of u^a v^b over the triangle u, v >= 0, u + v <= 1."""
    return math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)


def quartic_energy(coef: np.ndarray, thin_plate: float, membrane: float) -> float:
    """The energy of the polynomial sum c_(a,b) u^a v^b (one column) over the
    triangle, in the equilateral measure of sorpia.energy, exactly:
    d/dx = d/du, d/dy = (2 d/dv - d/du) / sqrt(3), dx dy = sqrt(3)/2 du dv."""
    def deriv(poly, du, dv):
        out = {}
        for (a, b), c in poly.items():
            if a < du or b < dv:
                continue
            f = math.perm(a, du) * math.perm(b, dv)
            out[(a - du, b - dv)] = out.get((a - du, b - dv), 0.0) + c * f
        return out

    def comb(*parts):
        out = {}
        for s, p in parts:
            for m, c in p.items():
                out[m] = out.get(m, 0.0) + s * c
        return out

    def square_integral(p):
        return sum(c1 * c2 * triangle_moment(m1[0] + m2[0], m1[1] + m2[1])
                   for m1, c1 in p.items() for m2, c2 in p.items())

    poly = {m: c for m, c in zip(MONOMIALS, coef)}
    pu, pv = deriv(poly, 1, 0), deriv(poly, 0, 1)
    puu, puv, pvv = deriv(poly, 2, 0), deriv(poly, 1, 1), deriv(poly, 0, 2)
    xx = puu
    xy = comb((-1 / SQ3, puu), (2 / SQ3, puv))
    yy = comb((1 / 3, puu), (-4 / 3, puv), (4 / 3, pvv))
    x, y = pu, comb((-1 / SQ3, pu), (2 / SQ3, pv))
    e = thin_plate * (square_integral(xx) + 2 * square_integral(xy) + square_integral(yy)) + \
        membrane * (square_integral(x) + square_integral(y))
    return e * SQ3 / 2


def loop_reference_energy(vertices, faces, thin_plate, membrane):
    """The energy of a regular Loop surface face by face: positions from
    LimitSurface.evaluate at 40 points fitted by a quartic (the residual
    shows the patch is one), integrated exactly."""
    surface = sorpia.LimitSurface(vertices, faces, scheme="loop")
    rng = np.random.default_rng(5)
    s = rng.random((40, 2))
    uv = np.where(s.sum(axis=1, keepdims=True) > 1, 1 - s[:, ::-1], s)
    basis = np.column_stack([uv[:, 0] ** a * uv[:, 1] ** b for a, b in MONOMIALS])
    total = 0.0
    for f in range(len(faces)):
        pos = surface.evaluate(np.full(len(uv), f), uv)
        coef, *_ = np.linalg.lstsq(basis, pos, rcond=None)
        # The patch is a quartic: the fit is exact to rounding.
        assert np.abs(basis @ coef - pos).max() < 1e-12 * max(1.0, np.abs(pos).max())
        total += sum(quartic_energy(coef[:, c], thin_plate, membrane) for c in range(3))
    return total


def energy(k, v) -> float:
    return float(np.sum(v * (k @ v)))


# ---- tests ----------------------------------------------------------------------

@pytest.mark.parametrize("thin_plate, membrane", [(1.0, 0.0), (0.0, 1.0), (2.0, 0.5)])
def test_regular_quad_grid_is_the_bicubic_bspline_closed_form(thin_plate, membrane):
    n = 6
    faces = periodic_quads(n)
    k = sorpia.fairness_matrix(faces, n * n, scheme="catmull-clark", thin_plate=thin_plate, membrane=membrane)
    ref = bspline_reference(n, thin_plate, membrane)
    # Gauss 4 x 4 integrates the bicubic patch's squared derivatives (degree 6
    # in each variable) exactly: equal to rounding.
    assert np.abs(k.toarray() - ref).max() < 1e-12 * np.abs(ref).max()


def test_hole_removes_its_element():
    n = 6
    faces = periodic_quads(n)
    k = sorpia.fairness_matrix(faces, n * n, scheme="catmull-clark", holes=[7]).toarray()
    ref = bspline_reference(n, 1.0, 0.0)
    # The hole's own element, from a one-face comparison: the reference of
    # the whole grid less that of the grid with face 7 dropped, built alike.
    g0, g1, g2 = gram(0), gram(1), gram(2)
    elem = np.kron(g0, g2) + 2.0 * np.kron(g1, g1) + np.kron(g2, g0)
    i, j = 7 % n, 7 // n
    pts = [((i - 1 + a) % n) + n * ((j - 1 + b) % n) for b in range(4) for a in range(4)]
    ref[np.ix_(pts, pts)] -= elem
    assert np.abs(k - ref).max() < 1e-12 * np.abs(ref).max()


@pytest.mark.parametrize("thin_plate, membrane", [(1.0, 0.0), (0.0, 1.0)])
def test_regular_loop_grid_is_the_quartic_patch(thin_plate, membrane):
    n = 5
    faces = periodic_triangles(n)
    rng = np.random.default_rng(3)
    v = rng.normal(size=(n * n, 3))
    k = sorpia.fairness_matrix(faces, n * n, scheme="loop", thin_plate=thin_plate, membrane=membrane)
    ref = loop_reference_energy(v, faces, thin_plate, membrane)
    # The collapsed 4 x 4 Gauss rule is exact for total degree 6 (the membrane
    # term's); both sides are exact integrals of the same quartics.
    assert energy(k, v) == pytest.approx(ref, rel=1e-11)


def test_loop_matrix_does_not_depend_on_the_first_corner():
    v, f = sorpia.shapes.icosphere(1)
    k = sorpia.fairness_matrix(f, len(v), scheme="loop", membrane=0.3)
    k2 = sorpia.fairness_matrix(np.roll(f, 1, axis=1), len(v), scheme="loop", membrane=0.3)
    # The equilateral measure is symmetric under the corners' rotation; the
    # quadrature points move, so the two agree to the quadrature error near
    # the valence-5 corners, and exactly elsewhere.
    assert abs(k - k2).max() < 1e-3 * abs(k).max()


def test_constants_are_in_the_null_space_and_k_is_symmetric_psd():
    cases = [(*sorpia.shapes.icosphere(1), "loop", {}),
             (*cube(), "catmull-clark", dict(creases=(np.array([[0, 1]]), 2.0), corners=([7], np.inf))),
             (*sorpia.shapes.grid(5, 4), "loop", dict(boundary="edge-only")),
             (*sorpia.shapes.polygon_torus(6, 5), "catmull-clark", dict(holes=[2]))]
    for v, f, scheme, tags in cases:
        k = sorpia.fairness_matrix(f, len(v), scheme=scheme, membrane=0.5, **tags).toarray()
        scale = np.abs(k).max()
        assert np.abs(k - k.T).max() <= 1e-14 * scale  # assembled as symmetric pairs: exactly symmetric
        # partition of unity: the rows of every derivative sum to zero
        assert np.abs(k @ np.ones(len(v))).max() < 1e-12 * scale
        assert np.linalg.eigvalsh(k).min() > -1e-12 * scale


def test_flat_regular_quad_grid():
    v, f = flat_quad_grid(7, a=0.5, b=2.0)
    k = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark")
    # The B-splines (with the boundary's phantom points) reproduce linear
    # functions: the limit surface of a flat regular grid is the affine map
    # (u, v) -> (a (i + u), b (j + v), 0), whose second derivatives vanish.
    assert np.abs(k @ v).max() < 1e-12 * abs(k).max()
    m = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", thin_plate=0.0, membrane=1.0)
    # Membrane of that map: (a^2 + b^2) per unit square.
    assert energy(m, v) == pytest.approx(len(f) * (0.5 ** 2 + 2.0 ** 2), rel=1e-12)


def test_quadrature_converges_on_a_closed_mesh():
    """On the cube (eight valence-3 corners) and the icosahedron (valence 5),
    the energy as the domain is split further towards the corners converges
    to that of a far finer rule."""
    for (v, f), scheme in [(cube(), "catmull-clark"), (sorpia.shapes.icosphere(0), "loop")]:
        fine = sorpia.thin_plate_energy(v, f, scheme=scheme, depth=8, gauss_points=8)
        errors = [abs(sorpia.thin_plate_energy(v, f, scheme=scheme, depth=d) - fine) / fine for d in (0, 2, 4, 6)]
        assert all(b < a for a, b in zip(errors, errors[1:])), errors
        assert errors[2] < 1e-2, errors  # the default: Bfr's polynomial rings exact, its corner patch approximated


def test_semi_sharp_creases_are_measured_on_each_side():
    """A roof: a flat 8 x 8 quad grid folded along its middle column, the fold
    tagged as a crease. Each side's surface, with the crease infinitely
    sharp, is the affine map of that side (the crease and boundary rules
    reproduce linear functions), so semi_sharp="sharp" measures zero bending
    whatever the tagged sharpness. As tagged, a crease of sharpness s turns
    the surface within a layer 2^-s of a face wide, the same shape scaled in
    the parameter (subdivision is self-similar): its bending, (d / w)^2 over
    width w for a turn d, doubles with each unit of sharpness."""
    n = 9
    v, f = flat_quad_grid(n)
    v[:, 2] = 0.5 * np.abs(v[:, 0] - 4)
    edges = np.array([[4 + n * j, 4 + n * (j + 1)] for j in range(n - 1)])
    tagged = []
    for s in (1.0, 2.0, 3.0, 4.0):
        creases = (edges, np.full(len(edges), s))
        k = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", creases=creases)
        # zero to rounding: the entries of K are of order 1, the vertices of order 10
        assert abs(energy(k, v)) < 1e-9 * abs(k).max() * np.abs(v).max() ** 2
        tagged.append(energy(sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", creases=creases,
                                                    semi_sharp="as-tagged"), v))
    assert tagged[0] > 1.0
    # exact doubling to rounding: the layers are polynomial pieces integrated exactly at every s here
    assert np.allclose(np.array(tagged[1:]) / tagged[:-1], 2.0, rtol=1e-9), tagged
    # an infinitely sharp crease is the same under both
    infinite = (edges, np.full(len(edges), sorpia._core.INFINITE_SHARPNESS))
    a = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", creases=infinite)
    b = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", creases=infinite, semi_sharp="as-tagged")
    assert abs(a - b).max() == 0.0


def rotation(seed: int) -> np.ndarray:
    q, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    return q


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_reference_metric_is_invariant_under_rotation_and_scaling(scheme):
    # A bumpy closed mesh with regular and extraordinary vertices (the
    # hybrid's two kinds of faces): K measured in the reference surface's
    # metric depends on it through inner products only, and the thin plate,
    # |H|^2 / |G| times area, is of degree 0 in the coordinates.
    v, f = (sorpia.shapes.quad_torus(8, 6) if scheme == "catmull-clark" else sorpia.shapes.icosphere(1))
    v = np.asarray(v, float)
    v = v + 0.05 * np.random.default_rng(3).standard_normal(v.shape)
    if scheme == "catmull-clark":  # the torus is regular: the cube's corners are all extraordinary
        cv, cf = cube()
        for vv, ff in ((v, f), (cv + 0.1 * np.random.default_rng(4).standard_normal(cv.shape), cf)):
            check_invariance(vv, ff, scheme)
    else:
        check_invariance(v, f, scheme)


def check_invariance(v, f, scheme):
    k = sorpia.fairness_matrix(f, len(v), scheme=scheme, reference=v)
    scale = 3.7
    moved = scale * v @ rotation(5).T + np.array([1.0, -2.0, 0.5])
    k2 = sorpia.fairness_matrix(f, len(v), scheme=scheme, reference=moved)
    # G scales by s^2, so K by s^-2: the energy of the moved surface, sum over
    # columns of (s Q V)^T K2 (s Q V), is that of V (to rounding)
    assert abs(scale ** 2 * k2 - k).max() < 1e-10 * abs(k).max()
    assert np.sum(moved * (k2 @ moved)) == pytest.approx(np.sum(v * (k @ v)), rel=1e-10)
    # symmetric, constants in its null space
    assert abs(k - k.T).max() < 1e-12 * abs(k).max()
    assert np.abs(k @ np.ones(len(v))).max() < 1e-10 * abs(k).max()
    # it is not the parametric energy
    p = sorpia.fairness_matrix(f, len(v), scheme=scheme)
    assert abs(k - p).max() > 1e-3 * abs(p).max()


def test_reference_metric_on_a_stretched_grid_is_the_geometric_thin_plate():
    # A flat grid of spacing a by b as its own reference: on the faces whose 16
    # control points are all inside the grid the surface is the uniform
    # bicubic B-spline, which reproduces quadratics, and G = diag(a^2, b^2),
    # so the energy of a height z is the geometric thin plate, int z_xx^2 + 2
    # z_xy^2 + z_yy^2 dx dy: 4 per unit area for x^2 and y^2, 2 for x y; the
    # other faces are holes. The parametric energy differs: (2 a^2)^2 per face
    # for x^2.
    n, a, b = 9, 0.5, 2.0
    v, f = flat_quad_grid(n, a, b)
    inner = [i + (n - 1) * j for j in range(1, n - 2) for i in range(1, n - 2)]
    holes = np.setdiff1d(np.arange(len(f)), inner)
    k = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", holes=holes, reference=v)
    x, y = v[:, 0], v[:, 1]
    area = len(inner) * a * b
    # rel 1e-6: G carries a floor of 1e-9 of its trace against degenerate reference faces, here
    # (b/a)^2 = 16 times that relative to the small axis
    for z, density in ((x * x, 4.0), (x * y, 2.0), (y * y, 4.0)):
        assert float(z @ k @ z) == pytest.approx(density * area, rel=1e-6)
    p = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", holes=holes)
    assert float((x * x) @ p @ (x * x)) == pytest.approx(len(inner) * (2 * a * a) ** 2, rel=1e-12)
    # a plane: the limit surface of the grid itself, affine everywhere (boundary rules too), has zero energy
    full = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", reference=v)
    assert np.abs(full @ v).max() < 1e-9 * abs(full).max() * np.abs(v).max()


def test_reference_metric_refuses_what_it_cannot_measure():
    v, f = cube()
    with pytest.raises(sorpia.ParameterError, match="reference has 7 rows"):
        sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", reference=v[:7])
    with pytest.raises(sorpia.ParameterError, match="degenerate at face"):
        sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", reference=np.zeros_like(v))
    # a quad and a pentagon side by side (test_cli_fit's mesh)
    pv = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2.5, 0.5, 0], [2, 1, 0]], dtype=float)
    pf = sorpia.Polygons(np.array([4, 5]), np.array([0, 1, 4, 3, 1, 2, 5, 6, 4]))
    with pytest.raises(sorpia.ParameterError, match="face 1 has 5 corners"):
        sorpia.fairness_matrix(pf, len(pv), scheme="catmull-clark", reference=pv)


@pytest.mark.parametrize("options, words", [
    (dict(thin_plate=-1.0), "thin_plate must be a finite number >= 0"),
    (dict(membrane=float("nan")), "membrane must be a finite number >= 0"),
    (dict(thin_plate=float("inf")), "thin_plate must be a finite number >= 0"),
    (dict(thin_plate=0.0, membrane=0.0), "thin_plate and membrane are both 0"),
    (dict(gauss_points=0), "gauss_points must be in 1..16"),
    (dict(gauss_points=17), "gauss_points must be in 1..16"),
    (dict(depth=-1), "depth must be in 0..12"),
    (dict(depth=13), "depth must be in 0..12"),
    (dict(thin_plate="1"), "thin_plate must be a real number"),
    (dict(depth=True), "depth = True must be an integer"),
    (dict(gauss_points=2.5), "gauss_points = 2.5 must be an integer"),
    (dict(semi_sharp="smooth"), "semi_sharp must be one of 'sharp', 'as-tagged'"),
])
def test_bad_options(options, words):
    v, f = cube()
    with pytest.raises(sorpia.ParameterError, match=words):
        sorpia.fairness_matrix(f, len(v), scheme="catmull-clark", **options)


def test_bad_mesh_is_refused_by_the_one_check():
    with pytest.raises(sorpia.MeshError, match="faces"):
        sorpia.fairness_matrix(np.array([[0, 1, 5]]), 3, scheme="loop")
    with pytest.raises(sorpia.MeshError, match="holes"):
        sorpia.fairness_matrix(cube()[1], 8, scheme="catmull-clark", holes=[6])


def test_polygon_sub_faces_are_measured_in_bfr_parameters():
    """Catmull-Clark k-gons: each of the k sub-faces is the square of side 1/2
    at (j % w, j // w) in Bfr's (u, v), measured by du dv. An independent
    quadrature here (every sub-face cut into 8 x 8 squares, 6 x 6 Gauss points
    each, LimitSurface.rows' second derivatives) agrees with K to the error
    both make at the extraordinary corners (Bfr's Gregory patch), far below
    the factor 4 a sub-face measured as a unit square would give."""
    v, f = sorpia.shapes.polygon_torus(6, 5)
    counts = np.asarray(f.face_vertex_counts)
    assert (counts != 4).any()
    surface = sorpia.LimitSurface(v, f, scheme="catmull-clark")
    x, w = np.polynomial.legendre.leggauss(6)
    x, w = (x + 1) / 2, w / 2
    cells = 8
    s, t = (g.ravel() for g in np.meshgrid((np.arange(cells)[:, None] + x).ravel() / cells,
                                           (np.arange(cells)[:, None] + x).ravel() / cells, indexing="ij"))
    ws = np.outer(np.tile(w, cells), np.tile(w, cells)).ravel() / cells ** 2
    total = 0.0
    for face, k in enumerate(counts):
        cols = sorpia.surface.subface_columns(k) if k != 4 else 1
        corners = [(0.0, 0.0)] if k == 4 else [(j % cols, j // cols) for j in range(k)]
        side = 1.0 if k == 4 else 0.5
        for cu, cv in corners:
            uv = np.column_stack([cu + side * s, cv + side * t])
            rows = surface.rows(np.full(len(uv), face), uv, derivatives=2)
            duu, duv, dvv = (r @ v for r in rows[3:])
            dens = (duu ** 2).sum(1) + 2 * (duv ** 2).sum(1) + (dvv ** 2).sum(1)
            total += side * side * float(ws @ dens)
    k = sorpia.fairness_matrix(f, len(v), scheme="catmull-clark")
    assert energy(k, v) == pytest.approx(total, rel=2e-3)
