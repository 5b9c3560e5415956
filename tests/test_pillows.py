"""Two faces with the same vertices in the opposite cyclic order whose edges no
other face uses (a 'pillow': a closed, consistently oriented surface of two
faces, which OpenSubdiv takes; issue 20, item 1) are a valid mesh on every
path: B's rows against OpenSubdiv's Far Limit() on the whole mesh, the default
fit against a dense numpy solve of the same B, repair leaves them alone, and
OpenSubdiv's regression shapes catmark_val2_back2back and loop_val2_interior
(their face lists written here) fit through the command line. A pair with a
third face on one of its edges is non-manifold and still refused."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.sparse

import sorpia

from conftest import reference_limit_matrix
from sorpia import _core
from sorpia._validate import as_boundary, as_scheme
from sorpia.limit import topology as make_topology

from test_fuzz import mesh_problems


def with_pillow(v, f, pillow):
    """Mesh (v, f) with a separate pillow of one face `pillow` (indices 0..k-1) and its reverse, on k new
    vertices off to the side."""
    k = len(pillow)
    t = 2 * np.pi * np.arange(k) / k
    pv = np.c_[3 + np.cos(t), np.sin(t), 0.3 * np.cos(2 * t) + 0.1 * np.arange(k)]
    n = len(v)
    faces = [list(map(int, x)) for x in f] + [[n + i for i in pillow], [n + i for i in pillow[::-1]]]
    return np.vstack([v, pv]) if n else pv, faces


EMPTY = (np.zeros((0, 3)), [])
CASES = {
    "triangle-pillow-loop": ("loop", lambda: with_pillow(*EMPTY, [0, 1, 2])),
    "triangle-pillow-catmull-clark": ("catmull-clark", lambda: with_pillow(*EMPTY, [0, 1, 2])),
    "quad-pillow": ("catmull-clark", lambda: with_pillow(*EMPTY, [0, 1, 2, 3])),
    "icosphere-and-triangle-pillow": ("loop", lambda: with_pillow(*sorpia.shapes.icosphere(1), [0, 1, 2])),
    "quad-torus-and-quad-pillow": ("catmull-clark", lambda: with_pillow(*sorpia.shapes.quad_torus(6, 4),
                                                                           [0, 1, 2, 3])),
    "quad-torus-and-triangle-pillow": ("catmull-clark", lambda: with_pillow(*sorpia.shapes.quad_torus(6, 4),
                                                                               [0, 1, 2])),
    # four pillows, one a quad: B singular (see test_val2_back2back_fits_through_the_command)
    "val2-back2back": ("catmull-clark", lambda: (np.array(VAL2_BACK2BACK[0]), VAL2_BACK2BACK[1])),
}


def reference_b(faces, n, scheme):
    """B from OpenSubdiv's whole-mesh refinement and Far's Limit() (the test reference)."""
    topo = make_topology(faces, n, scheme=scheme, warn=False)
    data, indices, indptr = reference_limit_matrix(
        topo, _core.Rules(scheme=as_scheme(scheme), boundary=as_boundary("edge-and-corner")))
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=(n, n))


def dense_answer(b, v0):
    """The dense numpy answer: the solve where B is invertible, else the least-squares minimum-norm one."""
    if np.linalg.matrix_rank(b) == len(b):
        return np.linalg.solve(b, v0)
    return np.linalg.lstsq(b, v0, rcond=None)[0]


@pytest.mark.parametrize("name", sorted(CASES))
def test_pillows_are_valid_and_fit_as_a_dense_solve(name):
    scheme, make = CASES[name]
    v, f = make()
    assert mesh_problems(f, len(v)) == set()  # the independent checker's verdict: valid
    b = sorpia.limit_matrix(f, len(v), scheme=scheme)
    # OpenSubdiv's own rows to rounding, every row but Catmull-Clark's at interior vertices of two faces (every
    # vertex of a pillow): there B takes the limit of refinement, which Far's Limit() at a finite level is not
    # (docs/creases.md); Loop's mask at valence 2 is that limit already.
    rows = np.arange(len(v))
    if scheme == "catmull-clark":
        topo = make_topology(f, len(v), scheme=scheme, warn=False)
        two_faces = (np.diff(np.asarray(topo.ring_offsets)) == 2) & ~np.asarray(topo.is_boundary)
        rows = rows[~two_faces]
    assert np.abs((b - reference_b(f, len(v), scheme)).toarray()[rows]).max(initial=0.0) <= 1e-14
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a singular B warns; the answer is checked below
        res = sorpia.interpolate(v, f, scheme=scheme)
    expected = dense_answer(b.toarray(), v)
    # B is well conditioned on these meshes: the Krylov or direct answer agrees with numpy to far below 1e-9
    assert np.abs(res.control_vertices - expected).max() <= 1e-9 * np.abs(v).max()
    r = sorpia.repair(v, f)  # a valid mesh comes out of repair unchanged
    assert not any(r.changes["counts"].values())
    assert np.array_equal(r.face_map, np.arange(len(f))) and len(r.vertices) == len(v)


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
def test_repair_keeps_a_pillow_beside_what_it_fixes(scheme):
    """A pillow in a mesh repair must change elsewhere (a same-order duplicate face) is kept; a reversed
    duplicate with a third face on an edge is removed."""
    v, f = with_pillow(*sorpia.shapes.icosphere(1), [0, 1, 2])
    n_faces = len(f)
    bad = f + [f[0], f[1][::-1]]  # a duplicate of face 0, and face 1 reversed (a third face on its edges)
    r = sorpia.repair(v, bad)
    assert r.changes["duplicate_faces"] == [n_faces] and r.changes["reversed_duplicate_faces"] == [n_faces + 1]
    assert r.face_map.tolist() == list(range(n_faces))
    assert mesh_problems(np.asarray(r.faces).tolist(), len(r.vertices)) == set()


ATTACHED = {
    "triangles-and-a-quad-on-an-edge": [[0, 1, 2], [0, 2, 1], [1, 3, 4, 2]],
    "triangles-and-a-triangle-on-an-edge": [[0, 1, 2], [0, 2, 1], [1, 3, 2]],
    "quads-and-a-quad-on-an-edge": [[0, 1, 2, 3], [0, 3, 2, 1], [1, 4, 5, 2]],
}


@pytest.mark.parametrize("faces", ATTACHED.values(), ids=ATTACHED.keys())
def test_a_reversed_pair_beside_a_third_face_is_refused_and_repaired(faces):
    assert "non-manifold edge" in mesh_problems(faces, 8)  # the independent checker's verdict
    v = np.random.default_rng(0).normal(size=(8, 3))
    with pytest.raises(sorpia.MeshError, match=r"duplicate faces: face 0 .* opposite|non-manifold edge"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
            sorpia.interpolate(v, faces, scheme="catmull-clark")
    r = sorpia.repair(v, faces)
    assert r.changes["reversed_duplicate_faces"] == [1] and r.face_map.tolist() == [0, 2]


# OpenSubdiv's regression shapes (regression/shapes/*.h), faces 0-based, vertices as there.
VAL2_BACK2BACK = (
    [[-.9, 0, .1], [-.1, 0, .1], [-.5, 0, .9], [.1, 0, .1], [.9, 0, .1], [.9, 0, .9], [.1, 0, .9],
     [-.7, 0, -.9], [-.3, 0, -.9], [-.1, 0, -.5], [-.5, 0, -.1], [-.9, 0, -.5],
     [.3, 0, -.9], [.7, 0, -.9], [.9, 0, -.5], [.7, 0, -.1], [.3, 0, -.1], [.1, 0, -.5]],
    [[0, 1, 2], [2, 1, 0], [3, 4, 5, 6], [6, 5, 4, 3], [7, 8, 9, 10, 11], [11, 10, 9, 8, 7],
     [12, 13, 14, 15, 16, 17], [17, 16, 15, 14, 13, 12]])
LOOP_VAL2_INTERIOR = (
    [[-1.75, 0, 0], [-.75, 0, 0], [-1.25, 0, .866], [-1.75, -.75, .866], [-.75, -.75, .866], [-1.75, .75, .866],
     [-.75, .75, .866], [-.5, 0, 0], [.5, 0, 0], [0, 0, .866], [.75, 0, 0], [1.75, 0, 0], [1.25, 0, .866],
     [1.25, -.75, 0], [1.25, .75, 0]],
    [[0, 1, 2], [1, 0, 2], [2, 3, 4], [2, 6, 5], [7, 8, 9], [8, 7, 9], [10, 11, 12], [11, 10, 12], [13, 11, 10],
     [14, 10, 11]])


def write_polygon_obj(path, vertices, faces):
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices] + ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_val2_back2back_fits_through_the_command(tmp_path, command):
    """Four pillows (a triangle, a quad, a pentagon, a hexagon): valid. The non-quads make OpenSubdiv take the
    valence-2 rows after one refinement (as Far's Limit() does), where the quad pillow's rows weight opposite
    corners alike: B is singular, so the command answers the least-squares cage (exit 1, "singular"),
    which equals numpy's lstsq of the same B, and the written cage is that answer."""
    v, f = VAL2_BACK2BACK
    code, out, err = command("fit", write_polygon_obj(tmp_path / "b2b.obj", v, f), "-o", tmp_path / "out.obj")
    b = sorpia.limit_matrix(f, len(v), scheme="catmull-clark").toarray()
    assert np.linalg.matrix_rank(b) < len(v)  # singular (rank 14 of 18 with the limit rows at two-face vertices)
    assert code == 1 and "singular" in out, (code, out, err)
    cage = np.asarray(sorpia.read_mesh(tmp_path / "out.obj")[0])
    # written with 17 significant digits; CGLS to tol 1e-10 on a B of condition 9 on its range
    assert np.abs(cage - np.linalg.lstsq(b, np.asarray(v), rcond=None)[0]).max() <= 1e-8


@pytest.mark.filterwarnings("default::sorpia.NonmanifoldWarning")  # shown as the command shows warnings
def test_loop_val2_interior_fits_through_the_command(tmp_path, command):
    """Two triangle pillows, one touching two triangles at a vertex (a bowtie), one with two more triangles on an
    edge (four faces there), and one alone: non-manifold, refused by default (exit 2) and fitted with
    --nonmanifold sharp (exit 0). The lone pillow's rows are Far's Limit() rows of that pillow alone, the
    vertices of the non-manifold edge and the bowtie are OpenSubdiv's infinitely sharp corners (identity rows),
    and the written cage interpolates: B V = V0."""
    v, f = LOOP_VAL2_INTERIOR
    path = write_polygon_obj(tmp_path / "lv2.obj", v, f)
    code, out, err = command("fit", path, "-o", tmp_path / "out.obj")
    assert code == 2 and "face 6 (10, 11, 12) and face 7 (11, 10, 12)" in err and "--nonmanifold sharp" in err, err
    code, out, err = command("fit", path, "-o", tmp_path / "out.obj", "--nonmanifold", "sharp")
    assert code == 0, (code, out, err)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.NonmanifoldWarning)
        b = sorpia.limit_matrix(f, len(v), scheme="loop", nonmanifold="sharp").toarray()
    alone = reference_b([[0, 1, 2], [1, 0, 2]], 3, "loop").toarray()
    assert np.abs(b[7:10, 7:10] - alone).max() <= 1e-14 and not b[7:10, :7].any() and not b[7:10, 10:].any()
    for corner in (2, 10, 11):
        assert np.array_equal(b[corner], np.eye(len(v))[corner])
    # the written cage is the split's: the input's 15 vertices first, then the copies of the split vertices
    cage = np.asarray(sorpia.read_mesh(tmp_path / "out.obj")[0])
    assert np.abs(b @ cage[:len(v)] - np.asarray(v)).max() <= 1e-8  # tol 1e-10 relative; 17 digits written
