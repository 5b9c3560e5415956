"""LimitSurface.rows (the rows of the limit surface at (face, u, v) that fitting
composes): rows @ V against Bfr's own evaluation of the same points
(LimitSurface.evaluate, which prepares patch points from V rather than
stencils), second derivatives against central differences of the first, and
the rows at corners against the limit matrix B."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse

import sorpia
from sorpia.surface import corner_uv, subface_columns

# EvaluateStencil and Evaluate sum the same products in a different order:
# rounding, relative to the coordinates' magnitude.
ROUNDING = 1e-12


def random_points(surface, faces, count, rng):
    """`count` random (face, u, v) inside the faces' domains (both schemes, any
    face size), including every face's corners."""
    sizes = [len(f) for f in faces]
    face_ids, uv = [], []
    for f, k in enumerate(sizes):
        for j in range(k):
            face_ids.append(f)
            uv.append(corner_uv(surface.scheme, k, j))
    for _ in range(count):
        f = int(rng.integers(len(sizes)))
        k = sizes[f]
        a, b = rng.random(2)
        if surface.scheme == "loop":
            if a + b > 1:
                a, b = 1 - a, 1 - b
            uv.append((a, b))
        elif k == 4:
            uv.append((a, b))
        else:
            w = subface_columns(k)
            j = int(rng.integers(k))
            uv.append((j % w + a / 2, j // w + b / 2))
        face_ids.append(f)
    return np.array(face_ids), np.array(uv, dtype=float)


def cases():
    yield "loop", sorpia.shapes.icosphere(2), {}
    v, f = sorpia.shapes.grid(6, 5)
    yield "loop-creases", (v, f), dict(creases=(np.array([[7, 8], [8, 9]]), [2.5, np.inf]), corners=([0], [np.inf]))
    yield "catmull-clark", sorpia.shapes.quad_irregular(300), {}
    yield "polygons", sorpia.shapes.polygon_torus(8, 6), {}
    v, f = sorpia.shapes.quad_torus(8, 6)
    # a dart: one infinitely sharp edge at an interior vertex
    yield "dart", (v, f), dict(creases=(np.array([[0, 1]]), [np.inf]))


@pytest.mark.parametrize("name,mesh,tags", list(cases()), ids=[c[0] for c in cases()])
def test_rows_reproduce_evaluate(name, mesh, tags):
    vertices, faces = mesh
    scheme = "loop" if name.startswith("loop") else "catmull-clark"
    surface = sorpia.LimitSurface(vertices, faces, scheme=scheme, **tags)
    flist = faces.tolist() if isinstance(faces, np.ndarray) else [
        list(x) for x in np.split(faces.face_vertex_indices, np.cumsum(faces.face_vertex_counts)[:-1])]
    face_ids, uv = random_points(surface, flist, 200, np.random.default_rng(3))
    p, du, dv, _ = surface.evaluate(face_ids, uv, derivatives=True)
    rows = surface.rows(face_ids, uv, derivatives=2)
    assert len(rows) == 6
    scale = np.abs(vertices).max()
    for m in rows:
        assert isinstance(m, scipy.sparse.csr_matrix) and m.shape == (len(face_ids), len(vertices))
        assert m.has_sorted_indices
    np.testing.assert_allclose(rows[0] @ vertices, p, rtol=0, atol=ROUNDING * scale)
    np.testing.assert_allclose(rows[1] @ vertices, du, rtol=0, atol=ROUNDING * scale)
    np.testing.assert_allclose(rows[2] @ vertices, dv, rtol=0, atol=ROUNDING * scale)
    # Affine invariance: position weights sum to 1, derivative weights to 0.
    np.testing.assert_allclose(np.asarray(rows[0].sum(axis=1)).ravel(), 1.0, atol=1e-12)
    # First derivatives to rounding; second derivatives at the corners of
    # semi-sharp and dart vertices carry the rounding of Bfr's local
    # refinement 10 levels deep (weights of 4^level magnitude inside it).
    for d, m in enumerate(rows[1:], 1):
        bound = (1e-11 if d < 3 else 1e-8) * np.maximum(1.0, np.asarray(abs(m).sum(axis=1)).ravel())
        assert (np.abs(np.asarray(m.sum(axis=1)).ravel()) <= bound).all()
    assert len(surface.rows(face_ids, uv)) == 1 and len(surface.rows(face_ids, uv, derivatives=1)) == 3


def test_corner_rows_are_limit_matrix_rows():
    """At a face's corner the position row is the vertex's row of B (Far's
    limit masks; the exact row at a dart)."""
    v, f = sorpia.shapes.quad_torus(8, 6)
    creases = (np.array([[0, 1]]), [np.inf])
    surface = sorpia.LimitSurface(v, f, scheme="catmull-clark", creases=creases)
    b = sorpia.limit_matrix(f, len(v), scheme="catmull-clark", creases=creases)
    face_ids = np.repeat(np.arange(len(f)), 4)
    uv = np.array([corner_uv("catmull-clark", 4, j) for j in range(4)] * len(f), dtype=float)
    (rows,) = surface.rows(face_ids, uv)
    expected = b[f.ravel()]
    assert abs(rows - expected).max() < 1e-12


def test_second_derivatives_match_differences_of_first():
    """duu, duv, dvv rows against central differences of the du, dv rows
    (step h, error O(h^2) on the polynomial patches of a regular grid's
    interior)."""
    v, f = sorpia.shapes.quad_grid(8, 8)
    rng = np.random.default_rng(5)
    v = v + 0.05 * rng.standard_normal(v.shape)
    surface = sorpia.LimitSurface(v, f, scheme="catmull-clark")
    interior = [i for i, face in enumerate(f) if all(0 < x % 9 < 8 and 0 < x // 9 < 8 for x in face)]
    face_ids = np.array(interior[:10])
    uv = rng.uniform(0.2, 0.8, (len(face_ids), 2))
    h = 1e-4
    _, du, dv, duu, duv, dvv = (m @ v for m in surface.rows(face_ids, uv, derivatives=2))
    e_u, e_v = np.array([h, 0.0]), np.array([0.0, h])
    d = lambda shift, which: surface.rows(face_ids, uv + shift, derivatives=1)[which] @ v
    np.testing.assert_allclose(duu, (d(e_u, 1) - d(-e_u, 1)) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(duv, (d(e_v, 1) - d(-e_v, 1)) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(dvv, (d(e_v, 2) - d(-e_v, 2)) / (2 * h), atol=1e-6)


def test_nonmanifold_rows_are_over_input_vertices():
    """With nonmanifold="sharp" the rows are over the input's vertices (the
    copies' weights added): rows @ V equals evaluate at the same points."""
    # two tetrahedra sharing one vertex: a non-manifold vertex
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1],
                  [-1, 0, 0], [0, -1, 0], [0, 0, -1]], dtype=float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3],
                  [0, 4, 5], [0, 6, 4], [0, 5, 6], [4, 6, 5]])
    with pytest.warns(sorpia.NonmanifoldWarning):
        surface = sorpia.LimitSurface(v, f, nonmanifold="sharp")
    face_ids, uv = random_points(surface, f.tolist(), 40, np.random.default_rng(1))
    (rows,) = surface.rows(face_ids, uv)
    assert rows.shape == (len(face_ids), 7)
    np.testing.assert_allclose(rows @ v, surface.evaluate(face_ids, uv), atol=ROUNDING)


def test_rows_bad_input():
    v, f = sorpia.shapes.icosphere(1)
    surface = sorpia.LimitSurface(v, f)
    with pytest.raises(sorpia.ParameterError, match="derivatives"):
        surface.rows([0], [[0.1, 0.1]], derivatives=3)
    with pytest.raises(sorpia.ParameterError, match="outside the triangle"):
        surface.rows([0], [[0.9, 0.9]])
    with pytest.raises(sorpia.ParameterError, match="out of range"):
        surface.rows([len(f)], [[0.1, 0.1]])
