"""Shared test meshes, grouped by what they stress, and the closed-form Loop
limit masks written independently of sorpia (from the paper, eq. 5)."""

from __future__ import annotations

import os
import sysconfig
from pathlib import Path

# One BLAS thread: the dense eigenvalue references are small, and a threaded
# BLAS on a loaded machine takes seconds for what one thread does in 0.05 s.
# Set before numpy loads its BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import signal  # noqa: E402

# A shell runs background jobs with SIGINT ignored, and children inherit that:
# the tests that send SIGINT (to this process or to a child Python, which then
# installs no KeyboardInterrupt handler) would see it dropped. Run them as from
# a terminal whatever started the suite.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

import numpy as np  # noqa: E402
import pytest
import scipy.sparse
import scipy.sparse.linalg
import scipy.spatial

import sorpia
from sorpia import cli
from sorpia.cli import common

from cli_support import CLI_MESHES, write_obj


def installed_script(name: str) -> Path | None:
    """The program `name` installed into this Python's scripts folder (where pip
    puts the `sorpia` script and CMake the sorpia-bench executable), or None."""
    path = Path(sysconfig.get_path("scripts")) / (f"{name}.exe" if os.name == "nt" else name)
    return path if path.exists() else None


def sphere_hull(n_points: int, seed: int):
    """Convex hull of random points on the unit sphere, faces oriented outward:
    a closed mesh with valences from about 3 to 12."""
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n_points, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    faces = scipy.spatial.ConvexHull(p).simplices.astype(np.int64)
    a, b, c = p[faces[:, 0]], p[faces[:, 1]], p[faces[:, 2]]
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), a) < 0
    faces[inward] = faces[inward][:, ::-1]
    return p, faces


def zigzag_strip(n: int):
    """A zig-zag strip of n triangles, consistently oriented: every vertex is on the boundary."""
    v = np.array([[i // 2, i % 2, 0.1 * i] for i in range(n + 2)], float)
    return v, np.array([[i, i + 1, i + 2] if i % 2 == 0 else [i + 1, i, i + 2] for i in range(n)])


def level_dependent(faces, n_vertices: int, scheme: str = "loop", creases=None, corners=None, **_) -> np.ndarray:
    """Which vertices' OpenSubdiv Limit() changes with the level, from the faces and tags alone: darts (below)
    and, under Catmull-Clark, interior vertices of two faces with no infinitely sharp tag (Sdc gives them the
    corner mask). Their rows of B are the limit of refinement; tests/cpp/test_darts.cpp checks them."""
    out = darts(faces, n_vertices, creases=creases, corners=corners)
    if scheme != "catmull-clark":
        return out
    face_list = _face_list(faces)
    count = np.zeros(n_vertices, int)
    for face in face_list:
        count[face] += 1
    interior = _used(face_list, n_vertices) & ~_on_boundary(face_list, n_vertices)
    return out | (interior & (count == 2) & (_sharp(n_vertices, creases, corners) == 0))


def _face_list(faces):
    if isinstance(faces, sorpia.Polygons):
        ends = np.cumsum(faces.face_vertex_counts)
        return [faces.face_vertex_indices[e - c:e].tolist() for c, e in zip(faces.face_vertex_counts, ends)]
    return np.asarray(faces).tolist()


def _edge_faces(face_list):
    edge_faces = {}
    for face in face_list:
        for a, b in zip(face, face[1:] + face[:1]):
            key = (min(a, b), max(a, b))
            edge_faces[key] = edge_faces.get(key, 0) + 1
    return edge_faces


def _used(face_list, n_vertices):
    used = np.zeros(n_vertices, bool)
    for face in face_list:
        used[face] = True
    return used


def _on_boundary(face_list, n_vertices):
    on_boundary = np.zeros(n_vertices, bool)
    for (a, b), count in _edge_faces(face_list).items():
        if count == 1:
            on_boundary[[a, b]] = True
    return on_boundary


def _sharp(n_vertices, creases, corners):
    """Per vertex: its infinitely sharp crease edges, 99 at an infinitely sharp corner."""
    sharp = np.zeros(n_vertices, int)
    if creases is not None:
        e = np.asarray(creases[0]).reshape(-1, 2)
        s = np.broadcast_to(np.asarray(creases[1], float), (len(e),))
        np.add.at(sharp, e[s >= 10].ravel(), 1)
    if corners is not None:
        c = np.atleast_1d(np.asarray(corners[0]))
        s = np.broadcast_to(np.asarray(corners[1], float), (len(c),))
        sharp[c[s >= 10]] = 99
    return sharp


def darts(faces, n_vertices: int, creases=None, corners=None, **_) -> np.ndarray:
    """Which vertices are darts, from the faces and tags alone: interior vertices with exactly one infinitely sharp
    crease edge (sharpness 10 or more, each edge given once) and no infinitely sharp corner. Their rows of B are
    the limit of refinement, which OpenSubdiv's Limit() after any finite number of levels (the whole-mesh
    reference, reference_limit_matrix) is not: comparisons with that reference skip them, and
    tests/cpp/test_darts.cpp checks them. Other tags (holes) are taken and ignored."""
    face_list = _face_list(faces)
    used, on_boundary = _used(face_list, n_vertices), _on_boundary(face_list, n_vertices)
    sharp = _sharp(n_vertices, creases, corners)
    return used & ~on_boundary & (sharp == 1)


def loop_alpha(n):
    """alpha_n = 3 / (3 + 8 n beta_n), n beta_n = 5/8 - (3/8 + cos(2 pi/n)/4)^2."""
    n = np.asarray(n, dtype=float)
    c = 3.0 / 8.0 + np.cos(2.0 * np.pi / n) / 4.0
    return 3.0 / (3.0 + 8.0 * (5.0 / 8.0 - c * c))


def closed_form_limit_matrix(faces, n_vertices: int, boundary: str = "edge-and-corner"):
    """Loop limit matrix from the closed-form masks: interior alpha_n and
    (1 - alpha_n)/n; boundary 2/3 and 1/6 for the two boundary neighbours; a
    one-face corner under "edge-and-corner" stays put (weight 1)."""
    faces = np.asarray(faces)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    und = np.sort(edges, axis=1)
    uniq, counts = np.unique(und, axis=0, return_counts=True)
    adj = scipy.sparse.coo_matrix((np.ones(len(uniq)), (uniq[:, 0], uniq[:, 1])), shape=(n_vertices,) * 2)
    adj = (adj + adj.T).tocsr()
    valence = np.diff(adj.indptr)
    bnd = uniq[counts == 1]
    on_boundary = np.zeros(n_vertices, bool)
    on_boundary[bnd.ravel()] = True
    faces_at = np.bincount(faces.ravel(), minlength=n_vertices)
    rows, cols, vals = [], [], []
    for i in range(n_vertices):
        if valence[i] == 0:
            rows.append(i); cols.append(i); vals.append(1.0)
        elif not on_boundary[i]:
            a = loop_alpha(valence[i])
            nb = adj.indices[adj.indptr[i]:adj.indptr[i + 1]]
            rows += [i] * (len(nb) + 1); cols += [i, *nb]; vals += [a] + [(1 - a) / len(nb)] * len(nb)
        elif faces_at[i] == 1 and boundary == "edge-and-corner":
            rows.append(i); cols.append(i); vals.append(1.0)
        else:
            nb = np.concatenate([bnd[bnd[:, 0] == i, 1], bnd[bnd[:, 1] == i, 0]])
            assert len(nb) == 2, f"vertex {i} is not a manifold boundary vertex"
            rows += [i] * 3; cols += [i, *nb]; vals += [2 / 3, 1 / 6, 1 / 6]
    return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(n_vertices, n_vertices))


def direct_solve(faces, vertices, boundary: str = "edge-and-corner"):
    """B^-1 V0 by scipy's sparse LU of sorpia.limit_matrix: the reference the
    iterative solvers are checked against."""
    b = sorpia.limit_matrix(faces, len(vertices), boundary=boundary).tocsc()
    return scipy.sparse.linalg.splu(b).solve(vertices)


# Meshes by what they stress: closed with valences 3..12, boundary, a high-valence pole.
MESHES = {
    "sphere-hull": lambda: sphere_hull(300, seed=4),
    "icosphere": lambda: sorpia.shapes.icosphere(2),
    "irregular-torus": lambda: sorpia.shapes.irregular(500, seed=2),
    "grid-boundary": lambda: sorpia.shapes.grid(9, 7),
    "pole-48": lambda: sorpia.shapes.pole(48),
}


@pytest.fixture(params=sorted(MESHES))
def mesh(request):
    """(name, vertices, faces) for each test mesh."""
    v, f = MESHES[request.param]()
    return request.param, np.asarray(v, dtype=float), np.asarray(f)


@pytest.fixture
def closed_form():
    return closed_form_limit_matrix


# ---- the sorpia command ----------------------------------------------------

@pytest.fixture
def command(capsys):
    """run(*args): `sorpia ARGS` in this process, as the script runs it; returns
    (exit code, stdout, stderr)."""

    def run(*args) -> tuple[int, str, str]:
        common._warned.clear()  # each command prints its warnings once, as a process of its own would
        capsys.readouterr()
        try:
            code = cli.main([str(a) for a in args])
        except SystemExit as exc:  # argparse: --help, --version, a bad option
            code = exc.code
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


@pytest.fixture(params=sorted(CLI_MESHES))
def mesh_file(request, tmp_path, monkeypatch):
    """(name, path, V, F): each of CLI_MESHES as an OBJ file in tmp_path, the working directory."""
    monkeypatch.chdir(tmp_path)
    V, F = CLI_MESHES[request.param]()
    return request.param, write_obj(tmp_path / f"{request.param}.obj", V, F), np.asarray(V), np.asarray(F)


@pytest.fixture
def torus_file(tmp_path, monkeypatch):
    """(path, V, F): the irregular torus of CLI_MESHES as tmp_path/torus.obj; tmp_path is the working directory."""
    monkeypatch.chdir(tmp_path)
    V, F = CLI_MESHES["irregular-torus"]()
    return write_obj(tmp_path / "torus.obj", V, F), np.asarray(V), np.asarray(F)


def _reference_module():
    """sorpia._reference, the test-only module of the references; where it was not built (SORPIA_BUILD_TESTS off),
    the calling test is skipped, saying so, or fails under SORPIA_REQUIRE_REFERENCE=1, which `make test` sets: its
    build turns SORPIA_BUILD_TESTS on, so a missing module there is a broken build, not a choice."""
    reason = "sorpia was built without SORPIA_BUILD_TESTS: no reference builds (tests/reference)"
    if os.environ.get("SORPIA_REQUIRE_REFERENCE") == "1":
        try:
            import sorpia._reference as reference
        except ImportError as exc:
            pytest.fail(f"SORPIA_REQUIRE_REFERENCE=1 but sorpia._reference does not import ({exc}): {reason}",
                        pytrace=False)
        return reference
    return pytest.importorskip("sorpia._reference", reason=reason)


def reference_limit_matrix(topology, rules):
    """B from OpenSubdiv's Far::Limit() after refinement of the whole mesh (sorpia._reference, the test-only module
    built with SORPIA_BUILD_TESTS, as `make test` builds it) as CSR arrays; the calling test is skipped where the
    module was not built."""
    return _reference_module().reference_limit_matrix(topology, rules)


def reference_one_ring(face_vertex_counts, face_vertex_indices, n_vertices):
    """The one-ring of the faces from OpenMesh's half-edge mesh (sorpia._reference, the test-only module), a dict
    named after _core.Topology's properties; the calling test is skipped where the module was not built."""
    return _reference_module().reference_one_ring(np.ascontiguousarray(face_vertex_counts, dtype=np.int32),
                                        np.ascontiguousarray(face_vertex_indices, dtype=np.int32), n_vertices)
