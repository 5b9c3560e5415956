"""Catmull-Clark's B is singular on a closed cube of valence-3 vertices: the
alternating +1/-1 vector over its corners is a null vector. A solve that stops
short names such cubes (SingularMatrixWarning); checked against the dense B
of limit_matrix and an explicit two-colouring of the cube's corners."""

from __future__ import annotations

import warnings

import numpy as np
import sorpia
from sorpia.limit import singular_cubes, tags, topology

# The unit cube: vertex x + 2 y + 4 z at (x, y, z), quads oriented outwards.
CUBE_V = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
CUBE_F = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]])
CHECKERBOARD = np.where(CUBE_V.sum(axis=1) % 2 == 0, 1.0, -1.0)  # neighbours differ in one coordinate


def _with_torus(cube_v):
    """The cube beside a quad torus (valence 4 everywhere: B regular there)."""
    tv, tf = sorpia.shapes.quad_torus(12, 8)
    v = np.vstack([tv, cube_v + [5.0, 0.0, 0.0]])
    f = np.vstack([tf, CUBE_F + len(tv)])
    return v, f, np.arange(len(tv), len(tv) + 8)


def test_the_checkerboard_is_a_null_vector_of_the_cube_s_b():
    B = sorpia.limit_matrix(CUBE_F, 8, scheme="catmull-clark").toarray()
    assert np.abs(B @ CHECKERBOARD).max() < 1e-15
    assert np.abs(np.linalg.eigvals(B)).min() < 1e-14  # singular, by a dense eigensolver
    found = singular_cubes(topology(CUBE_F, 8, scheme="catmull-clark"),
                           tags(topology(CUBE_F, 8, scheme="catmull-clark")))
    assert [c.tolist() for c in found] == [list(range(8))]


def test_a_cube_beside_a_torus_is_found_and_the_torus_is_not():
    v, f, cube = _with_torus(CUBE_V)
    topo = topology(f, len(v), scheme="catmull-clark")
    found = singular_cubes(topo, tags(topo))
    assert [c.tolist() for c in found] == [cube.tolist()]
    # Tags change the cube's rows: a tagged cube is not claimed singular.
    assert singular_cubes(topo, tags(topo, corners=([cube[0]], np.inf))) == []


def test_a_stopped_solve_names_the_cube_and_a_symmetric_cube_converges():
    v, f, cube = _with_torus(CUBE_V)
    # The symmetric cube's corners have no checkerboard component (each
    # coordinate sums to zero against it): B V = V0 has a solution.
    assert abs(CHECKERBOARD @ CUBE_V).max() == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = sorpia.interpolate(v, f, scheme="catmull-clark", max_iter=200)
    assert res.converged
    # Moving one corner gives the targets a checkerboard component: no V fits.
    v[cube[0]] += [0.1, 0.0, 0.0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sorpia.interpolate(v, f, scheme="catmull-clark", method="sor", max_iter=200)
    assert not res.converged
    assert [w.category for w in caught] == [sorpia.ConvergenceWarning, sorpia.SingularMatrixWarning]
    assert f"vertices {cube.tolist()}" in str(caught[1].message)
    # The default ("auto") ends with the least-squares answer, missing the targets on the cube only.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sorpia.interpolate(v, f, scheme="catmull-clark", max_iter=200)
    assert res.stop_reason == "singular" and res.variant == "cgls"
    # One warning: the least-squares answer, and where B is singular.
    assert [w.category for w in caught] == [sorpia.SingularMatrixWarning]
    assert "least-squares" in str(caught[0].message) and f"vertices {cube.tolist()}" in str(caught[0].message)
    assert set(res.worst_vertices[:8].tolist()) == set(cube.tolist())


def test_the_command_line_prints_the_singular_warning(tmp_path, command):
    v, f, cube = _with_torus(CUBE_V)
    v[cube[0]] += [0.1, 0.0, 0.0]
    src = tmp_path / "cube.obj"
    sorpia.write_mesh(src, v, f)
    out = tmp_path / "c.obj"
    code, stdout, err = command("fit", src, "-o", out, "--max-iter", 200)
    assert code == 1
    assert "B is singular on 1 closed cube" in err
    # The least-squares answer is written (no --keep-unconverged needed), and the summary says what it misses.
    assert out.exists() and "NOT converged (singular)" in stdout and "least-squares" in stdout
