"""Property-based tests (hypothesis) over random small meshes and random
corruptions of them (issue 7). Bounded: every test has a fixed number of
examples and a deadline, so the whole file runs in well under 30 s.

A 5 s per-example deadline catches a reader that crawls without failing on a
loaded machine. Each property is checked against an independent computation:
the closed-form Loop masks of conftest.py for valid meshes, and
`mesh_problems` below (plain Python dictionaries, no sorpia code) for what
makes a face list invalid.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from collections import defaultdict

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import sorpia
from conftest import zigzag_strip

# The `closed_form` fixture is a stateless function: sharing it between examples is safe.
# database=None: nothing is written into the source tree. derandomize: the normal run is
# reproducible; SORPIA_FUZZ_EXAMPLES=5000 explores with that many random examples instead.
_EXPLORE = int(os.environ.get("SORPIA_FUZZ_EXAMPLES", "0"))
FUZZ = settings(max_examples=_EXPLORE or 300, derandomize=not _EXPLORE, deadline=5000, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])


BASES = {
    "tetrahedron": lambda: (np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float),
                            np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]])),
    "icosahedron": lambda: sorpia.shapes.icosphere(0),
    "icosphere-1": lambda: sorpia.shapes.icosphere(1),
    "torus-4x3": lambda: sorpia.shapes.torus(4, 3),
    "grid-3x4": lambda: sorpia.shapes.grid(3, 4),
    "pole-7": lambda: sorpia.shapes.pole(7),
    "irregular": lambda: sorpia.shapes.irregular(60, seed=5),
    "strip": lambda: zigzag_strip(5),
}
BASE_MESHES = {k: tuple(np.asarray(a) for a in make()) for k, make in BASES.items()}


def face_lists(faces) -> list[list[int]]:
    """Faces in any accepted form as a list of lists of ints."""
    if isinstance(faces, sorpia.Polygons):
        ends = np.cumsum(faces.face_vertex_counts)
        return [list(map(int, f)) for f in np.split(np.asarray(faces.face_vertex_indices), ends[:-1])]
    return [list(map(int, f)) for f in faces]


def cycle(face, reverse=False) -> tuple:
    """A face as a cycle starting at its smallest vertex, reversed first when `reverse`."""
    f = list(face)[::-1] if reverse else list(face)
    k = f.index(min(f))
    return tuple(f[k:] + f[:k])


def mesh_problems(faces, n_vertices: int) -> set[str]:
    """What is wrong with a face list (triangles or polygons, in any accepted form),
    found independently of sorpia: the set of message fragments sorpia may report
    ("out of range", "vertices: a face needs at least 3", "repeats vertex",
    "duplicate faces", "non-manifold edge", "inconsistent orientation",
    "non-manifold vertex"). Empty for a valid mesh."""
    faces = face_lists(faces)
    if any(not 0 <= x < n_vertices for f in faces for x in f):
        return {"out of range"}
    if any(len(f) < 3 for f in faces):
        return {"vertices: a face needs at least 3"}
    if any(len(set(f)) < len(f) for f in faces):
        return {"repeats vertex"}
    problems = set()
    # The same cycle twice is a duplicate; the same vertices in the opposite order only where one of their
    # edges has a third face (alone, the two are a closed 'pillow', valid).
    if len({cycle(f) for f in faces}) < len(faces):
        problems.add("duplicate faces")
    cycles = {cycle(g) for g in faces}
    reversed_pairs = [f for f in faces if cycle(f, True) in cycles]
    directed = defaultdict(int)
    for f in faces:
        for i, a in enumerate(f):
            directed[a, f[(i + 1) % len(f)]] += 1
    undirected = defaultdict(int)
    for (a, b), k in directed.items():
        undirected[min(a, b), max(a, b)] += k
        if k > 1:
            problems.add("inconsistent orientation")
    if any(k > 2 for k in undirected.values()):
        problems.add("non-manifold edge")
        if any(undirected[min(a, b), max(a, b)] > 2 for f in reversed_pairs for a, b in zip(f, f[1:] + f[:1])):
            problems.add("duplicate faces")
    if problems:
        return problems
    # Fans: the faces at v joined when they share an edge (v, w) of both.
    at = defaultdict(list)
    for i, f in enumerate(faces):
        for j, x in enumerate(f):
            at[x].append((i, {f[j - 1], f[(j + 1) % len(f)]}))
    for v, corners in at.items():
        seen, stack = {0}, [0]
        while stack:
            c = stack.pop()
            for d, (_, ends) in enumerate(corners):
                if d not in seen and ends & corners[c][1]:
                    seen.add(d)
                    stack.append(d)
        if len(seen) < len(corners):
            problems.add("non-manifold vertex")
    return problems


def limit_quietly(v, f, boundary="edge-and-corner"):
    """limit_points with unreferenced vertices allowed (they may follow from a corruption)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        return sorpia.limit_points(v, f, boundary=boundary)


@st.composite
def relabeled_meshes(draw):
    """A base mesh with its vertices permuted, its faces shuffled and each face's
    corners rotated (orientation kept): the same surface, numbered differently."""
    name = draw(st.sampled_from(sorted(BASE_MESHES)))
    v, f = BASE_MESHES[name]
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    perm = rng.permutation(len(v))  # new index of old vertex i is perm[i]
    v2 = np.empty_like(v)
    v2[perm] = v
    f2 = perm[f][rng.permutation(len(f))]
    shift = rng.integers(0, 3, size=len(f2))
    f2 = np.array([np.roll(t, s) for t, s in zip(f2, shift)])
    return name, v, f, perm, v2, f2


@FUZZ
@given(case=relabeled_meshes(), boundary=st.sampled_from(["edge-and-corner", "edge-only"]))
def test_limit_points_equal_closed_form_and_follow_relabeling(case, boundary, closed_form):
    _, v, f, perm, v2, f2 = case
    out = sorpia.limit_points(v2, f2, boundary=boundary)
    # 1e-14: the same closed-form masks in double precision (coordinates within [-2, 2]^3 or the grid's size).
    assert np.abs(out - closed_form(f2, len(v2), boundary) @ v2).max() <= 1e-14
    # Equivariance: renumbering vertices and faces renumbers the limit points, nothing else;
    # only the summation order may change (1e-14).
    assert np.abs(out[perm] - sorpia.limit_points(v, f, boundary=boundary)).max() <= 1e-14


@FUZZ
@given(relabeled_meshes())
def test_limit_matrix_is_relabeled_with_the_vertices(case):
    _, v, f, perm, v2, f2 = case
    b = sorpia.limit_matrix(f, len(v)).toarray()
    b2 = sorpia.limit_matrix(f2, len(v2)).toarray()
    # B2[perm[i], perm[j]] = B[i, j]; exact: the same weights are computed for the same vertex.
    assert np.array_equal(b2[np.ix_(perm, perm)], b)


CORRUPTIONS = st.one_of(
    st.tuples(st.just("set"), st.integers(0, 10**6), st.integers(0, 2), st.integers(-2, 10**6)),
    st.tuples(st.just("flip"), st.integers(0, 10**6)),
    st.tuples(st.just("duplicate"), st.integers(0, 10**6)),
    st.tuples(st.just("delete"), st.integers(0, 10**6)),
    st.tuples(st.just("add"), st.integers(0, 10**6), st.integers(0, 10**6), st.integers(0, 10**6)),
    st.tuples(st.just("weld"), st.integers(0, 10**6), st.integers(0, 10**6)),
)


def corrupt(v, f, edits, polygons=False):
    """Apply edits to a face list; vertex indices wrap modulo n (+2, so a few are out of range). An (m, 3)
    array; with `polygons`, a list of lists, "add" appending a quad (its fourth vertex from the other three)."""
    faces = [list(t) for t in f]
    n = len(v)
    for e in edits:
        if not faces:
            break
        i = e[1] % len(faces)
        if e[0] == "set":
            faces[i][e[2]] = e[3] % (n + 2) if e[3] >= 0 else e[3]
        elif e[0] == "flip":
            faces[i] = faces[i][::-1]
        elif e[0] == "duplicate":
            faces.append(list(faces[i]))
        elif e[0] == "delete":
            del faces[i]
        elif e[0] == "add":
            faces.append([e[1] % n, e[2] % n, e[3] % n] + ([(e[1] + e[2] + e[3]) % n] if polygons else []))
        elif e[0] == "weld":  # merge two vertices: makes non-manifold edges and vertices
            a, b = e[1] % n, e[2] % n
            faces = [[a if x == b else x for x in t] for t in faces]
    return faces if polygons else np.array(faces, dtype=np.int64).reshape(-1, 3)


@FUZZ
@given(name=st.sampled_from(sorted(BASE_MESHES)), edits=st.lists(CORRUPTIONS, min_size=1, max_size=4))
def test_corrupted_faces_are_refused_exactly_when_invalid(name, edits, closed_form):
    v, f = BASE_MESHES[name]
    bad = corrupt(v, f, edits)
    assume(len(bad) > 0)
    problems = mesh_problems(bad, len(v))
    if not problems:
        out = limit_quietly(v, bad)
        assert np.abs(out - closed_form(bad, len(v)) @ v).max() <= 1e-14
        return
    with pytest.raises(sorpia.MeshError) as info:
        limit_quietly(v, bad)
    # The reported problem is one that is really there.
    assert any(p in str(info.value) for p in problems), (str(info.value), problems)


@FUZZ
@given(st.sampled_from(sorted(BASE_MESHES)), st.integers(0, 10**6), st.integers(0, 2),
       st.sampled_from([np.nan, np.inf, -np.inf]))
def test_non_finite_vertex_is_named(name, i, k, value):
    v, f = BASE_MESHES[name]
    v = v.copy()
    i %= len(v)
    v[i, k] = value
    with pytest.raises(sorpia.MeshError, match=rf"vertices\[{i}\] = .* is not finite"):
        sorpia.limit_points(v, f)


# ------------------------------------------------------- corrupted files --

def _valid_files():
    """Bytes of small valid files in every format sorpia reads, written by sorpia itself
    (plus a quad OBJ with texture coordinates and normals, and an OBJ of polygons with tags)."""
    meshes = {"tetra": BASE_MESHES["tetrahedron"], "grid": BASE_MESHES["grid-3x4"], "strip": BASE_MESHES["strip"]}
    out = {}
    with tempfile.TemporaryDirectory() as d:
        for name, (v, f) in meshes.items():
            for ext, binary in (("obj", False), ("off", False), ("ply", False), ("ply", True), ("stl", False),
                                ("stl", True)):
                path = os.path.join(d, f"{name}.{ext}")
                sorpia.write_mesh(path, v, f, binary=binary)
                with open(path, "rb") as fh:
                    out[f"{name}{'-binary' if binary else ''}.{ext}"] = fh.read()
    out["quad.obj"] = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\n"
    out["uv.obj"] = (b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nvt 0 0\nvt 1 0\nvt 1 1 0.5\nvn 0 0 1\n"
                     b"f 1/1/1 2/2/1 3/3/1 4/1/1\nf 2/-1/-1 5/2/1 3/-2/1\n")
    out["uv.ply"] = (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                     b"property float u\nproperty float v\nproperty float nx\nproperty float ny\nproperty float nz\n"
                     b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 0 0 1\n"
                     b"1 0 0 1 0 0 0 1\n1 1 0 1 1 0 0 1\n0 1 0 0 1 0 0 1\n4 0 1 2 3\n")
    out["tags.obj"] = (b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3 4\nf 2 5 3\nf 5 6 3\n"
                       b"t crease 2/1/0 0 1 2.5\nt crease 4/2/0 1 2 4 5 10 0.5\nt corner 1/1/0 4 0.7\nt hole 1/0/0 1\n"
                       b"t interpolateboundary 1/0/0 2\nt creasemethod 0/0/1 normal\n")
    return out


VALID_FILES = _valid_files()

EDITS = st.one_of(
    st.tuples(st.just("flip"), st.integers(0, 10**6), st.integers(1, 255)),  # xor one byte
    st.tuples(st.just("truncate"), st.integers(0, 10**6)),
    st.tuples(st.just("delete"), st.integers(0, 10**6), st.integers(1, 40)),
    st.tuples(st.just("insert"), st.integers(0, 10**6), st.binary(min_size=1, max_size=12)),
    st.tuples(st.just("insert-digits"), st.integers(0, 10**6), st.text("0123456789-+.e", min_size=1, max_size=12)),
    st.tuples(st.just("shuffle-lines"), st.randoms(use_true_random=False)),
    st.tuples(st.just("repeat-line"), st.integers(0, 10**6)),
)


def corrupt_bytes(data: bytes, edits) -> bytes:
    b = bytearray(data)
    for e in edits:
        kind, n = e[0], max(len(b), 1)
        if kind == "flip" and b:
            b[e[1] % n] ^= e[2]
        elif kind == "truncate":
            del b[e[1] % n:]
        elif kind == "delete":
            del b[e[1] % n:e[1] % n + e[2]]
        elif kind in ("insert", "insert-digits"):
            chunk = e[2] if isinstance(e[2], bytes) else e[2].encode()
            b[e[1] % n:e[1] % n] = chunk
        elif kind == "shuffle-lines":
            lines = bytes(b).split(b"\n")
            e[1].shuffle(lines)
            b = bytearray(b"\n".join(lines))
        elif kind == "repeat-line":
            lines = bytes(b).split(b"\n")
            i = e[1] % len(lines)
            b = bytearray(b"\n".join(lines[:i + 1] + lines[i:]))
    return bytes(b)


@FUZZ
@given(name=st.sampled_from(sorted(VALID_FILES)), edits=st.lists(EDITS, min_size=1, max_size=3),
       triangulate=st.booleans())
def test_corrupted_files_read_or_fail_cleanly(name, edits, triangulate):
    data = corrupt_bytes(VALID_FILES[name], edits)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, name)
        with open(path, "wb") as fh:
            fh.write(data)
        try:
            with warnings.catch_warnings():  # a corrupted tag name is an unknown tag: skipped with a warning
                warnings.simplefilter("ignore", sorpia.UnknownTagWarning)
                warnings.simplefilter("ignore", sorpia.AttributeWarning)  # a corrupted corner loses its vt
                v, f, tags, attributes = sorpia.read_mesh(path, triangulate=triangulate, tags=True, attributes=True)
        except sorpia.MeshFileError as e:
            # The message names the file and is printable (it goes to a terminal or a log).
            assert str(e).startswith(path) and str(e).isprintable(), str(e)
            return
        with open(path, "rb") as fh:
            assert fh.read() == data  # reading never modifies the file
    # What a reader accepts is well formed: polygons of 3 or more vertices (triangles with triangulate) ...
    assert v.dtype == np.float64 and v.ndim == 2 and v.shape[1] == 3 and np.isfinite(v).all()
    if isinstance(f, sorpia.Polygons):
        counts, corners = f
        assert not triangulate and counts.dtype == np.int32 and counts.min() >= 3
        assert corners.dtype == np.int32 and counts.sum() == len(corners)
    else:
        assert f.dtype == np.int32 and f.ndim == 2 and f.shape[1] >= 3 and len(f) > 0
        assert f.shape[1] == 3 or not triangulate
        corners = f.ravel()
    assert corners.min() >= 0 and corners.max() < len(v)
    n_faces = len(f) if isinstance(f, np.ndarray) else len(f.face_vertex_counts)
    for kind, (indices, sharpness) in ((k, tags[k]) for k in ("creases", "corners") if k in tags):
        assert indices.min() >= 0 and indices.max() < len(v) and (sharpness >= 0).all(), kind
    assert "holes" not in tags or (tags["holes"].min() >= 0 and tags["holes"].max() < n_faces)
    for name, (values, indices) in attributes.items():  # a value for every corner, finite, in range
        assert values.ndim == 2 and np.isfinite(values).all() and len(indices) == len(corners), name
        assert indices.min() >= 0 and indices.max() < len(values), name
    if not (isinstance(f, np.ndarray) and f.shape[1] == 3):
        return  # the topology checks below are Loop's
    # ... and a triangle mesh is then either a valid mesh or refused by the topology checks, never anything else.
    problems = mesh_problems(f, len(v))
    if problems:
        with pytest.raises(sorpia.MeshError):
            limit_quietly(v, f)
    else:
        assert np.isfinite(limit_quietly(v, f)).all()
