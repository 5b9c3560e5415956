"""Bad input gets a clear error naming the problem and where (issue 7): arrays,
topology, parameters. Each refusal asserts the exception type and a message
that names the index; each acceptance asserts the result against an
independent computation (the closed-form limit masks of conftest.py)."""

from __future__ import annotations

import hashlib
import os
import warnings

import numpy as np
import pytest

import sorpia
from sorpia._validate import as_faces, as_vertex_count, as_vertices

from conftest import zigzag_strip

V1, F1 = sorpia.shapes.icosphere(1)  # 42 vertices, 80 faces


def two_triangles_sharing_a_vertex():
    """The smallest bowtie: faces (0, 1, 2) and (0, 3, 4) meet at vertex 0 only."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]], float)
    return v, np.array([[0, 1, 2], [0, 3, 4]])


def double_cone():
    """Two closed tetrahedra glued at one vertex: a bowtie with no boundary edge."""
    rng = np.random.default_rng(0)
    f = [[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2], [0, 4, 5], [0, 5, 6], [0, 6, 4], [4, 6, 5]]
    return rng.normal(size=(7, 3)), np.array(f)


def moebius(n: int = 8):
    """A Moebius strip: a band of n quads, two triangles each, glued with a half twist."""
    t = 2 * np.pi * np.arange(n) / n
    v = []
    for a in t:
        for w in (-0.3, 0.3):
            v.append([(1 + w * np.cos(a / 2)) * np.cos(a), (1 + w * np.cos(a / 2)) * np.sin(a), w * np.sin(a / 2)])
    f = []
    for i in range(n):
        a0, a1 = 2 * i, 2 * i + 1
        b0, b1 = (2 * i + 2, 2 * i + 3) if i + 1 < n else (1, 0)  # the twist
        f += [[a0, b0, b1], [a0, b1, a1]]
    return np.array(v), np.array(f)


def with_faces_flipped(faces, ids):
    f = np.array(faces, copy=True)
    f[ids] = f[ids][:, ::-1]
    return f


def digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
        h.update(str((a.dtype, a.shape, a.strides)).encode())
    return h.hexdigest()


# ---------------------------------------------------------------- arrays --

def nan_at(i, value=np.nan):
    v = V1.copy()
    v[i, 1] = value
    return v


def face_set(f, i, row):
    f = np.array(f, copy=True)
    f[i] = row
    return f


# (id, vertices, faces, exception, message pattern)
BAD_ARRAYS = [
    # limit_points maps (n, k) data for any k >= 1 (tests/test_update.py)
    ("vertices-0-columns", V1[:, :0], F1, ValueError, r"vertices must have shape \(n, k\), k >= 1, got \(42, 0\)"),
    ("vertices-1d", V1.ravel(), F1, ValueError,
     r"vertices must have shape \(n, k\), k >= 1, got \(126,\) \(a scalar per vertex: values\[:, None\]\)"),
    ("vertices-3d", V1[None], F1, ValueError, r"vertices must have shape \(n, k\), k >= 1, got \(1, 42, 3\)"),
    ("vertices-bool", V1 > 0, F1, TypeError, r"vertices must be .* real numbers, got dtype bool"),
    ("vertices-complex", V1 + 0j, F1, TypeError, r"vertices .* got dtype complex128"),
    ("vertices-object", V1.astype(object), F1, TypeError, r"vertices .* got dtype object"),
    ("vertices-strings", V1.astype(str), F1, TypeError, r"vertices .* got dtype <U"),
    ("vertices-none", None, F1, TypeError, r"vertices .* got dtype object"),
    ("vertices-ragged", [[0, 0, 0], [1, 0]], F1, TypeError, r"vertices must be an \(n, k\) array"),
    ("vertices-empty", np.zeros((0, 3)), F1, sorpia.MeshError, r"vertices is empty"),
    ("vertex-nan", nan_at(17), F1, sorpia.MeshError, r"vertices\[17\] = \[.*nan.*\] is not finite"),
    ("vertex-inf", nan_at(5, np.inf), F1, sorpia.MeshError, r"vertices\[5\] = \[.*inf.*\] is not finite"),
    ("vertex-minus-inf", nan_at(41, -np.inf), F1, sorpia.MeshError, r"vertices\[41\] .* not finite"),
    ("faces-1d", V1, F1.ravel(), ValueError, r"faces must have shape \(m, 3\), got \(240,\)"),
    ("faces-float", V1, F1.astype(float), TypeError, r"faces must hold integer .* got dtype float64.*astype\(int\)"),
    ("faces-float32", V1, F1.astype(np.float32), TypeError, r"got dtype float32"),
    ("faces-bool", V1, F1 > 0, TypeError, r"faces must be .* integer vertex indices, got dtype bool"),
    ("faces-complex", V1, F1 + 0j, TypeError, r"faces .* got dtype complex128"),
    ("faces-object", V1, F1.astype(object), TypeError, r"faces .* got dtype object"),
    ("faces-empty", V1, np.zeros((0, 3), int), sorpia.MeshError, r"faces is empty"),
    ("faces-quads", V1, np.zeros((5, 4), int), sorpia.MeshError,
     r"faces has 4 vertices per face, shape \(5, 4\): Loop subdivision needs triangles; split each polygon"),
    ("faces-mixed-polygons", V1, [[0, 1, 2], [0, 2, 3], [3, 4, 5, 6]], sorpia.MeshError,
     r"faces\[2\] has 4 vertices: Loop subdivision needs triangles; .*numpy.vstack"),
    ("faces-edge", V1, [[0, 1, 2], [0, 2]], sorpia.MeshError, r"faces\[1\] has 2 vertices"),
    ("index-negative", V1, face_set(F1, 9, [3, -1, 4]), sorpia.MeshError,
     r"faces\[9\] = \[3, -1, 4\] has vertex index -1 out of range \[0, 42\)"),
    ("index-too-large", V1, face_set(F1, 0, [0, 42, 5]), sorpia.MeshError,
     r"faces\[0\] = \[0, 42, 5\] has vertex index 42 out of range \[0, 42\)"),
    # 2**32 + 1 would become 1 in a careless cast to int32
    ("index-wraps-int32", V1, face_set(F1.astype(np.int64), 3, [0, 2**32 + 1, 5]), sorpia.MeshError,
     r"faces\[3\] .* vertex index 4294967297 out of range"),
    ("index-uint64-huge", V1, face_set(F1.astype(np.uint64), 3, [0, 2**63, 5]), sorpia.MeshError,
     r"faces\[3\] .* vertex index 9223372036854775808 out of range"),
    ("repeated-vertex", V1, face_set(F1, 11, [7, 8, 7]), sorpia.MeshError,
     r"face 11 \(7, 8, 7\) repeats vertex 7 \(a degenerate triangle\)"),
    ("duplicate-face", V1, np.vstack([F1, F1[[30]]]), sorpia.MeshError,
     r"duplicate faces: face 30 \(.*\) and face 80 \(.*\) have the same three vertices"),
    ("duplicate-face-reversed", V1, np.vstack([F1, F1[[30], ::-1]]), sorpia.MeshError,
     r"duplicate faces: face 30 .* and face 80"),
]


@pytest.mark.parametrize("vertices, faces, exc, match", [c[1:] for c in BAD_ARRAYS], ids=[c[0] for c in BAD_ARRAYS])
def test_bad_arrays_are_refused_with_the_index(vertices, faces, exc, match):
    # Loop named: "auto", the default, would take the quads of "faces-quads" as Catmull-Clark's
    with pytest.raises(exc, match=match):
        sorpia.limit_points(vertices, faces, scheme="loop")


# Two faces with the same vertices in the opposite order (issue 20, item 1) whose edges no other face uses are a
# closed 'pillow' of two faces, valid (test_pillows.py); with a third face on one of their edges they are
# non-manifold: refused naming the pair (triangles) or the edge (polygons), with both ways out; repair removes
# the second, nonmanifold="sharp" takes them.
ATTACHED = {
    "triangles-and-a-quad-on-an-edge": ([[0, 1, 2], [0, 2, 1], [1, 3, 4, 2]],  # the polygon path
                                        r"non-manifold edge \(1, 2\): shared by 3 faces \(faces 0, 1, 2\)"),
    "triangles-and-a-triangle-on-an-edge": ([[0, 1, 2], [0, 2, 1], [1, 3, 2]], r"duplicate faces: face 0 \(0, 1, 2\) "
                                            r"and face 1 \(0, 2, 1\) have the same three vertices, in the opposite"),
    "quads-and-a-quad-on-an-edge": ([[0, 1, 2, 3], [0, 3, 2, 1], [1, 4, 5, 2]],
                                    r"non-manifold edge \(1, 2\): shared by 3 faces \(faces 0, 1, 2\)"),
}


@pytest.mark.parametrize("faces, match", ATTACHED.values(), ids=ATTACHED.keys())
def test_reversed_duplicates_beside_a_third_face_are_refused(faces, match):
    from test_fuzz import mesh_problems

    assert "non-manifold edge" in mesh_problems(faces, 8)  # the independent checker's verdict
    v = np.random.default_rng(0).normal(size=(8, 3))
    with pytest.raises(sorpia.MeshError, match=match + r".*sorpia.repair .*nonmanifold=\"sharp\""):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
            sorpia.interpolate(v, faces, scheme="catmull-clark")
    r = sorpia.repair(v, faces)
    assert r.changes["reversed_duplicate_faces"] == [1] and r.face_map.tolist() == [0, 2]


def test_every_refusal_is_a_value_or_type_error():
    # The sorpia exceptions are ValueError subclasses: `except ValueError` catches bad input of every kind.
    assert issubclass(sorpia.MeshError, ValueError)
    assert issubclass(sorpia.ParameterError, ValueError)
    assert issubclass(sorpia.MeshFileError, ValueError)


def test_limit_matrix_refuses_bad_faces_and_counts():
    with pytest.raises(sorpia.MeshError, match=r"faces\[0\] = \[0, 12, 14\] has vertex index 12 out of range \[0, 10\)"):
        sorpia.limit_matrix(F1, 10)
    with pytest.raises(TypeError, match=r"n_vertices must be an integer, got 42.5"):
        as_faces(F1, 42.5)
    with pytest.raises(sorpia.ParameterError, match=r"n_vertices = -1 must be >= 0"):
        sorpia.limit_matrix(F1, -1)


def test_vertex_count_accepts_numpy_integers_only():
    assert as_vertex_count(np.int64(42)) == 42
    with pytest.raises(TypeError, match="n_vertices must be an integer, got True"):
        as_vertex_count(True)


# Every public entry taking a vertex count validates it with the one helper
# (as_vertex_count, through sorpia.limit.topology): same type, same message.
COUNT_ENTRIES = {
    "limit_matrix": lambda n: sorpia.limit_matrix(F1, n),
    "limit_matrix-keyword": lambda n: sorpia.limit_matrix(F1, n_vertices=n),
    "Interpolator": lambda n: sorpia.Interpolator(F1, n),
    "Interpolator-keyword": lambda n: sorpia.Interpolator(F1, n_vertices=n),
}

# (id, count, exception, message pattern naming the parameter and the value)
BAD_COUNTS = [
    ("float", 42.0, TypeError, r"^n_vertices must be an integer, got 42\.0$"),
    ("numpy-float", np.float64(42), TypeError, r"^n_vertices must be an integer, got (np\.float64\()?42\.0\)?$"),
    ("bool", True, TypeError, r"^n_vertices must be an integer, got True$"),
    ("numpy-bool", np.bool_(True), TypeError, r"^n_vertices must be an integer, got (np\.)?True_?$"),
    ("string", "42", TypeError, r"^n_vertices must be an integer, got '42'$"),
    ("negative", -1, sorpia.ParameterError, r"^n_vertices = -1 must be >= 0$"),
    ("too-small-for-faces", 10, sorpia.MeshError,
     r"^faces\[0\] = \[0, 12, 14\] has vertex index 12 out of range \[0, 10\): n_vertices = 10 is too small for "
     r"faces, whose largest vertex index is 41$"),
]


@pytest.mark.parametrize("entry", sorted(COUNT_ENTRIES))
@pytest.mark.parametrize("count, exc, match", [c[1:] for c in BAD_COUNTS], ids=[c[0] for c in BAD_COUNTS])
def test_every_vertex_count_entry_refuses_the_same_way(entry, count, exc, match):
    with pytest.raises(exc, match=match):
        COUNT_ENTRIES[entry](count)


@pytest.mark.parametrize("count", [np.int64(42), np.int32(42), np.uint8(42), np.uint64(42)],
                         ids=lambda c: type(c).__name__)
def test_vertex_count_entries_accept_numpy_integers(count, closed_form):
    # The same B as the closed-form masks for the plain int count: 1e-15, one rounding of the same formulas.
    exact = closed_form(F1, 42)
    assert abs(sorpia.limit_matrix(F1, count) - exact).max() <= 1e-15
    interp = sorpia.Interpolator(F1, count)
    assert type(interp.n_vertices) is int and interp.n_vertices == 42
    assert abs(interp.limit_matrix() - exact).max() <= 1e-15


@pytest.mark.parametrize("call", [
    lambda: sorpia.limit_points(V1[:10], F1),
    lambda: sorpia.interpolate(V1[:10], F1),
    lambda: sorpia.LimitSurface(V1[:10], F1),
    lambda: sorpia.limit_surface(V1[:10], F1, level=1),
], ids=["limit_points", "interpolate", "LimitSurface", "limit_surface"])
def test_too_few_vertices_for_the_faces_names_len_vertices(call):
    # Where the count is the rows of `vertices`, the message names it so (there is no n_vertices argument).
    with pytest.raises(sorpia.MeshError, match=r"out of range \[0, 10\): len\(vertices\) = 10 is too small for faces, "
                                               r"whose largest vertex index is 41$"):
        call()


@pytest.mark.parametrize("count, exc, match", [
    (400.0, TypeError, r"^n_vertices must be an integer, got 400\.0$"),
    (True, TypeError, r"^n_vertices must be an integer, got True$"),
    (-5, sorpia.ParameterError, r"^n_vertices = -5 must be >= 0$"),
], ids=["float", "bool", "negative"])
def test_irregular_validates_its_vertex_count(count, exc, match):
    with pytest.raises(exc, match=match):
        sorpia.shapes.irregular(count)


def test_irregular_accepts_a_numpy_integer_count():
    # Same mesh for the numpy and the plain int count (the generator is deterministic for a seed).
    v, f = sorpia.shapes.irregular(np.int64(300), seed=2)
    v2, f2 = sorpia.shapes.irregular(300, seed=2)
    assert np.array_equal(v, v2) and np.array_equal(f, f2)


def strided(a):
    """A non-contiguous view of `a` (every other column of a wider array)."""
    wide = np.zeros((a.shape[0], 2 * a.shape[1]), a.dtype)
    wide[:, ::2] = a
    return wide[:, ::2]


def read_only(a):
    a = np.array(a, copy=True)
    a.flags.writeable = False
    return a


CONVERTED = {
    "non-contiguous": lambda v, f: (strided(v), strided(f)),
    "fortran-order": lambda v, f: (np.asfortranarray(v), np.asfortranarray(f)),
    "read-only": lambda v, f: (read_only(v), read_only(f)),
    "big-endian": lambda v, f: (v.astype(">f8"), f.astype(">i8")),
    "uint16-and-int-vertices": lambda v, f: ((v * 1000).astype(np.int64), f.astype(np.uint16)),
    "float32-and-int8": lambda v, f: (v.astype(np.float32), f.astype(np.int8)),
    "lists": lambda v, f: (v.tolist(), f.tolist()),
}


@pytest.mark.parametrize("kind", sorted(CONVERTED))
def test_unusual_arrays_are_converted_and_never_modified(kind, closed_form):
    v, f = CONVERTED[kind](V1, F1)
    arrays = [a for a in (v, f) if isinstance(a, np.ndarray)]
    before = digest(*arrays)
    flags = [(a.flags.writeable, a.flags.c_contiguous) for a in arrays]
    out = sorpia.limit_points(v, f)
    # Same answer as the closed-form masks applied to the same (converted) numbers:
    # 1e-14 relative to the coordinates (the int vertices are scaled by 1000).
    exact = closed_form(F1, len(V1)) @ np.asarray(v, dtype=np.float64)
    assert np.abs(out - exact).max() <= 1e-14 * max(1.0, np.abs(exact).max())
    assert out.dtype == np.float64 and out.flags.c_contiguous and out.flags.writeable
    assert digest(*arrays) == before  # the input is untouched
    assert [(a.flags.writeable, a.flags.c_contiguous) for a in arrays] == flags


def test_validated_arrays_are_not_copied_when_already_right():
    # No hidden copy of a large input that is already float64/int32 C-contiguous.
    f32 = F1.astype(np.int32)
    assert as_vertices(V1) is V1
    assert as_faces(f32, len(V1)) is f32


# -------------------------------------------------------------- topology --

BAD_TOPOLOGY = [
    ("non-manifold-edge", lambda: (np.eye(5, 3), np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])),
     r"non-manifold edge \(0, 1\): shared by 3 faces \(faces 0, 1, 2\)"),
    ("non-manifold-edge-in-a-sphere", lambda: (np.vstack([V1, [[2, 2, 2]]]), np.vstack([F1, [[F1[0, 0], F1[0, 1], 42]]])),
     r"non-manifold edge \(\d+, \d+\): shared by 3 faces \(faces 0, .*80\)"),
    ("bowtie", two_triangles_sharing_a_vertex,
     r"non-manifold vertex 0: its 2 faces form 2 fans .*'bowtie'; e.g. faces 0 and 1"),
    ("bowtie-closed-cones", double_cone, r"non-manifold vertex 0: its 6 faces form 2 fans"),
    ("flipped-face", lambda: (V1, with_faces_flipped(F1, [7])),
     r"inconsistent orientation at edge \(\d+, \d+\): face \d+ .* both run from vertex \d+ to \d+; reversing the "
     r"vertex order of 1 of the 80 faces .* \(faces 7\)"),
    ("three-flipped-faces", lambda: (V1, with_faces_flipped(F1, [3, 10, 17])),
     r"inconsistent orientation .* 3 of the 80 faces .* \(faces 3, 10, 17\)"),
    ("moebius-strip", moebius, r"inconsistent orientation at edge .* the surface is not orientable"),
]


# Every entry that builds the topology refuses a bad mesh with the same message.
TOPOLOGY_ENTRIES = {
    "limit_points": lambda v, f: sorpia.limit_points(v, f),
    "limit_matrix": lambda v, f: sorpia.limit_matrix(f, len(v)),
    "interpolate": lambda v, f: sorpia.interpolate(v, f),
}


@pytest.mark.parametrize("entry", sorted(TOPOLOGY_ENTRIES))
@pytest.mark.parametrize("make, match", [c[1:] for c in BAD_TOPOLOGY], ids=[c[0] for c in BAD_TOPOLOGY])
def test_bad_topology_is_refused_naming_edge_vertex_or_faces(make, match, entry):
    v, f = make()
    with pytest.raises(sorpia.MeshError, match=match):
        TOPOLOGY_ENTRIES[entry](v, f)


VALID_ODD_MESHES = {
    "single-triangle": lambda: (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.5]]), np.array([[0, 1, 2]])),
    "all-boundary-strip": lambda: zigzag_strip(6),
    "two-components": lambda: (
        np.vstack([V1, V1[::-1]]), np.vstack([F1, len(V1) + (len(V1) - 1 - F1)])),
    "sphere-and-triangle": lambda: (
        np.vstack([V1, [[3, 0, 0], [4, 0, 0], [3, 1, 0]]]), np.vstack([F1, [[42, 43, 44]]])),
    "pole-360": lambda: sorpia.shapes.pole(360),
}


@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
@pytest.mark.parametrize("name", sorted(VALID_ODD_MESHES))
def test_unusual_valid_meshes_match_the_closed_form(name, boundary, closed_form):
    # 1e-14: both sides are the same closed-form masks in double precision.
    v, f = VALID_ODD_MESHES[name]()
    out = sorpia.limit_points(v, f, boundary=boundary)
    assert np.abs(out - closed_form(f, len(v), boundary) @ v).max() <= 1e-14


def test_components_are_independent():
    v, f = VALID_ODD_MESHES["two-components"]()
    both = sorpia.limit_points(v, f)
    assert np.array_equal(both[: len(V1)], sorpia.limit_points(V1, F1))
    # the second component is the first with its vertices numbered backwards
    assert np.abs(both[len(V1):][::-1] - sorpia.limit_points(V1, F1)).max() <= 1e-15  # summation order only


def test_unreferenced_vertices_warn_and_pass_through(closed_form):
    extra = np.array([[5.0, 6.0, 7.0], [-1.0, 2.5, 0.0]])
    v = np.vstack([extra[:1], V1, extra[1:]])  # unreferenced first and last
    f = F1 + 1
    with pytest.warns(sorpia.UnreferencedVerticesWarning, match="2 of 44 vertices belong to no face"):
        out = sorpia.limit_points(v, f)
    assert np.array_equal(out[[0, -1]], extra)
    assert np.abs(out - closed_form(f, len(v)) @ v).max() <= 1e-14


def test_pole_of_valence_360_is_interior_and_exact(closed_form):
    v, f = sorpia.shapes.pole(360)
    b = sorpia.limit_matrix(f, len(v))
    assert b[0].nnz == 361  # the centre and its 360 neighbours
    assert abs(b - closed_form(f, len(v))).max() <= 1e-15  # one rounding of the same formula


def test_valence_beyond_opensubdivs_limit_names_the_vertex():
    # OpenSubdiv refuses valence > 65535 without saying which vertex; pole(n)'s centre is vertex 0.
    v, f = sorpia.shapes.pole(65536)
    with pytest.raises(sorpia.MeshError, match=r"vertex 0 has 65536 neighbours: OpenSubdiv supports at most 65535"):
        sorpia.limit_points(v, f)


def test_no_warning_for_a_clean_mesh():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sorpia.limit_points(V1, F1)


# ----------------------------------------------------------------- files --

def file_digest(path) -> str:
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def write(path, content):
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    return path


QUAD_OBJ = """# a unit square as one quad, with texture coordinates, normals and a group
o square
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0.5
vt 0 0
vt 1 0
vn 0 0 1
g top
usemtl red
s off
f 1/1/1 2/2/1 3/1/1 4/2/1
"""

PLY_HEAD = ("ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty double x\nproperty double y\nproperty double z\n"
            "element face {nf}\nproperty list uchar int vertex_indices\nend_header\n")
TRIANGLE_PLY = PLY_HEAD.format(fmt="ascii", nv=3, nf=1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"

# (id, file name, content, message pattern): each names the file and, where
# there is one, the line (text) or the element (binary).
BAD_FILES = [
    ("empty", "empty.obj", b"", r"empty\.obj: the file is empty"),
    ("unknown-extension", "mesh.txt", "v 0 0 0\n", r"mesh\.txt: unknown mesh file extension '\.txt': use \.obj"),
    ("no-extension", "mesh", "v 0 0 0\n", r"mesh: unknown mesh file extension \(none\)"),
    ("obj-bad-number", "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n",
     r"bad\.obj, line 3: expected a number, found 'zero'"),
    ("obj-truncated-vertex", "cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1", r"cut\.obj, line 3: a vertex needs 3 coordinates"),
    ("obj-nan", "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", r"nan\.obj, line 2: coordinate 'nan' is not finite"),
    ("obj-index-out-of-range", "far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
     r"far\.obj, line 4: vertex index 4 is out of range: the file has 3 vertices"),
    ("obj-index-zero", "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", r"zero\.obj, line 4: vertex index 0"),
    ("obj-no-faces", "points.obj", "v 0 0 0\nv 1 0 0\n", r"points\.obj: has 2 vertices but no faces"),
    ("obj-two-vertex-face", "edge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
     r"edge\.obj, line 4: a face needs at least 3 vertices, this one has 2"),
    ("off-truncated", "cut.off", "OFF\n4 2 0\n" + "0.125 0.25 0.5\n" * 4 + "3 0 1 2\n",
     r"cut\.off: the file ends after 1 of 2 faces"),
    ("off-not-off", "mesh.off", "v 0 0 0\n", r"mesh\.off, line 1: an OFF file starts with 'OFF'"),
    ("ply-truncated", "cut.ply", TRIANGLE_PLY[:-8], r"cut\.ply.*(ends|more than)"),
    ("ply-binary-truncated", "cut-binary.ply",
     PLY_HEAD.format(fmt="binary_little_endian", nv=3, nf=1).encode() + np.zeros(9).tobytes() + b"\x03",
     r"cut-binary\.ply.*(ends|more than)"),
    # A header claiming 10**12 vertices fails on reading the header, before any
    # allocation (24 TB would raise MemoryError, not MeshFileError).
    ("ply-claims-1e12-vertices", "huge.ply", PLY_HEAD.format(fmt="binary_little_endian", nv=10**12, nf=1),
     r"huge\.ply, line 3: the header claims 1000000000000 'vertex' elements, more than the 0 bytes"),
    ("ply-claims-1e12-ascii", "huge-ascii.ply", PLY_HEAD.format(fmt="ascii", nv=10**12, nf=1) + "0 0 0\n",
     r"huge-ascii\.ply, line 3: the header claims 1000000000000 'vertex' elements"),
    ("off-claims-1e12-vertices", "huge.off", "OFF\n1000000000000 1 0\n0 0 0\n",
     r"huge\.off, line 2: the header claims 1000000000000 vertices"),
    ("stl-truncated-binary", "cut.stl", b"\0" * 80 + np.uint32(2).tobytes() + b"\0" * 60,
     r"cut\.stl: binary STL header announces 2 triangles \(184 bytes\) but the file has 144 bytes"),
    ("unknown-words-only", "words.obj", "qwerty uiop\n", r"words\.obj: no vertices: not a mesh file"),
    # the file's bytes are quoted escaped (raw, they made Python raise UnicodeDecodeError; found by fuzzing)
    ("non-utf8-bytes", "bytes.obj", b"v 0 0 0\n\xff\xfe junk\n", r"bytes\.obj, line 2: '\\xff\\xfe' is not an OBJ statement"),
    ("random-text", "noise.obj", "v 0 0 0\n3.14 = pi\n", r"noise\.obj, line 2: '3\.14' is not an OBJ statement"),
    # each reader's errors: the file, then the line and the problem
    ("relative-index", "bad.obj", "v 0 0 0\nf -1 -2 -3\n", r"bad\.obj.*line 2: relative vertex index -2"),
    ("obj-nan-no-faces", "bad.obj", "v 0 0 0\nv nan 0 0\n", r"bad\.obj.*line 2: coordinate 'nan' is not finite"),
    ("obj-garbage", "bad.obj", "v 0 0 0\n12 3 4\n", r"bad\.obj.*line 2: '12' is not an OBJ statement"),
    ("obj-short-vertex", "bad.obj", "v 0 0\n", r"bad\.obj.*line 1: a vertex needs 3 coordinates"),
    ("obj-number-with-two-points", "bad.obj", "v 0 0 1.2.3\n", r"bad\.obj.*line 1: expected a number, found '1\.2\.3'"),
    ("obj-binary", "bad.obj", "v 0 0 0\n\x01\x02 1\n", r"bad\.obj.*line 2: '\\x01\\x02' is not an OBJ statement"),
    ("no-faces", "bad.obj", "v 0 0 0\n", r"bad\.obj.*1 vertices but no faces"),
    ("off-index", "bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", r"bad\.off.*line 6: vertex index 3 is out of range"),
    ("off-inf", "bad.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", r"bad\.off.*line 4: coordinate 'inf' is not finite"),
    ("off-no-face-line", "bad.off", "OFF\n3 1 0\n0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n", r"bad\.off.*ends after 0 of 1 faces"),
    ("off-header", "bad.off", "OFFISH\n", r"bad\.off.*line 1: an OFF file starts with 'OFF'"),
    ("off-binary", "bad.off", "OFF BINARY\n", r"bad\.off.*binary OFF is not supported"),
    ("ply-huge", "bad.ply", "ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\n"
     "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
     r"bad\.ply.*line 3: the header claims 1000000000000 'vertex' elements"),
    ("ply-magic", "bad.ply", "plx\n", r"bad\.ply.*line 1: a PLY file starts with the line 'ply'"),
    ("ply-no-end", "bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", r"bad\.ply.*no 'end_header'"),
    ("ply-no-face", "bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
     "property float z\nend_header\n0 0 0\n", r"bad\.ply.*no 'face' or 'tristrips' element"),
    ("ply-no-z", "bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
     "end_header\n0 0\n", r"bad\.ply.*line 3: the vertex element has no property z"),
    ("ply-nan", "bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
     "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
     "0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n", r"bad\.ply.*line 11: coordinate 'NaN' is not finite"),
    ("stl-keyword", "bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertx 1 0 0\n",
     r"bad\.stl.*line 5: 'vertx' is not an ascii STL keyword"),
    ("stl-not-stl", "bad.stl", "hello", r"bad\.stl.*neither an ascii STL"),
    # One parser for double and float32: each type's range and message.
    ("obj-beyond-double", "bad.obj", "v 0 0 1e400\n", r"bad\.obj.*line 1: coordinate '1e400' is out of the range of double"),
    ("stl-beyond-float32", "bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 1e40\n",
     r"bad\.stl.*line 4: coordinate '1e40' is out of float32 range"),
    ("stl-bad-number", "bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 1.2.3\n",
     r"bad\.stl.*line 4: expected a number, found '1\.2\.3'"),
    ("stl-inf", "bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 inf 0\n",
     r"bad\.stl.*line 4: coordinate 'inf' is not finite"),
]


# Reader defects found by fuzzing and probing (README "Bad input and fuzzing"), now fixed in
# cpp/src/io_obj.cpp, io_ply.cpp and io.cpp (ac3ec66).
FIXED_READER_DEFECTS = [
    # the int64 index was cast to int32 before the range check: read as face (0, 1, 2)
    ("obj-index-beyond-int32", "wrap.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967299\n",
     r"wrap\.obj, line 4: vertex index 4294967299 is out of range"),
    # -i overflowed (undefined behaviour) in the relative-index check
    ("obj-index-llong-min", "min.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n",
     r"min\.obj, line 4: relative vertex index -9223372036854775808 points before the first vertex"),
    # idx.resize(4e9) before reading the indices: MemoryError (or the OOM killer for smaller lengths)
    ("ply-ascii-list-length-4e9", "list.ply",
     PLY_HEAD.format(fmt="ascii", nv=3, nf=1) + "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n",
     r"list\.ply, line 13: a list of 4000000000 items is longer than its line"),
    # raw bytes of a PLY element name in the message: Python raised UnicodeDecodeError
    ("ply-element-name-bytes", "name.ply", b"ply\nformat ascii 1.0\nelement v\xffrtex 100000\nproperty float x\nend_header\n",
     r"name\.ply, line 3: the header claims 100000 'v\\xffrtex' elements"),
]


@pytest.mark.parametrize("name, content, match", [c[1:] for c in BAD_FILES + FIXED_READER_DEFECTS],
                         ids=[c[0] for c in BAD_FILES + FIXED_READER_DEFECTS])
def test_bad_files_name_the_file_and_line(tmp_path, name, content, match):
    path = write(tmp_path / name, content)
    before = file_digest(path)
    with pytest.raises(sorpia.MeshFileError, match=match):
        sorpia.read_mesh(path)
    assert file_digest(path) == before  # a failed read leaves the file as it was


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                    reason="root reads a chmod 000 file anyway: the permission check cannot fail")
def test_unreadable_file(tmp_path):
    path = write(tmp_path / "locked.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    path.chmod(0)
    with pytest.raises(sorpia.MeshFileError, match=r"locked\.obj: cannot open the file: Permission denied"):
        sorpia.read_mesh(path)


def test_obj_with_polygons_normals_and_texture_coordinates(tmp_path):
    path = write(tmp_path / "quad.obj", QUAD_OBJ)
    before = file_digest(path)
    assert np.array_equal(sorpia.read_mesh(path)[1], [[0, 1, 2, 3]])  # kept as a quad unless asked
    v, f = sorpia.read_mesh(path, triangulate=True)
    # vt/vn/g/usemtl/s are ignored; the quad becomes the fan (1, 2, 3), (1, 3, 4) from its first vertex.
    assert np.array_equal(v, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.5]])
    assert np.array_equal(f, [[0, 1, 2], [0, 2, 3]])
    assert file_digest(path) == before


def test_valid_file_round_trips_and_is_not_modified(tmp_path):
    v, f = sorpia.shapes.irregular(200, seed=3)
    for name in ("m.obj", "m.off", "m.ply"):
        sorpia.write_mesh(tmp_path / name, v, f)
        before = file_digest(tmp_path / name)
        v2, f2 = sorpia.read_mesh(tmp_path / name)
        assert np.array_equal(v2, v) and np.array_equal(f2, f)  # exact: shortest round-trip decimals
        assert file_digest(tmp_path / name) == before


def test_file_with_bad_topology_reads_but_is_refused_on_use(tmp_path):
    # The readers return the arrays as stored; topology is checked where it matters, with face indices.
    path = write(tmp_path / "bowtie.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n")
    v, f = sorpia.read_mesh(path)
    with pytest.raises(sorpia.MeshError, match="non-manifold vertex 0"):
        sorpia.limit_points(v, f)


def test_path_with_nul_is_refused(tmp_path):
    # At the C level a NUL would truncate the path: 'a.obj\\0.ply' opened a.obj as PLY.
    write(tmp_path / "a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(sorpia.MeshFileError, match=r"the path contains a NUL character"):
        sorpia.read_mesh(str(tmp_path / "a.obj") + "\0.ply")


# ------------------------------------------------------------ parameters --
# tests/test_solvers.py::test_bad_parameters checks the bad values; these are the failure modes.

SOLVER_METHODS = ("pia", "wpia", "gs", "sor", "cg", "hss", "whss")


@pytest.mark.parametrize("method", SOLVER_METHODS)
def test_a_run_cut_short_warns_and_stays_finite(method):
    # omega = 1.99 (far past the best omega ~1 on these meshes) and 3 iterations: never converges.
    v, f = sorpia.shapes.irregular(300, seed=2)
    options = {"omega": 1.99} if method == "sor" else {}
    with pytest.warns(sorpia.ConvergenceWarning, match=rf"method='{method}' (reached max_iter = 3|diverged)"):
        res = sorpia.interpolate(v, f, method=method, max_iter=3, **options)
    assert not res.converged and res.stop_reason in ("max_iter", "diverged")
    assert res.iterations <= 3
    assert np.isfinite(res.control_vertices).all() and np.isfinite(res.history).all()


@pytest.mark.parametrize("method", SOLVER_METHODS)
def test_an_unreachable_tol_ends_at_rounding_level(method, recwarn):
    # tol = 1e-300 is below what double precision can reach: the run ends at the solvers'
    # documented rounding floor (E_k <= 64 eps max_i ||v_i^0||) or at max_iter, never loops on.
    v, f = sorpia.shapes.irregular(300, seed=2)
    res = sorpia.interpolate(v, f, method=method, tol=1e-300, max_iter=400)
    assert res.iterations <= 400
    assert np.isfinite(res.control_vertices).all() and np.isfinite(res.history).all()
    floor = 64 * np.finfo(float).eps * np.linalg.norm(v, axis=1).max()
    if res.converged:
        assert res.history[-1] * res.initial_error <= floor
    else:
        assert any(issubclass(w.category, sorpia.ConvergenceWarning) for w in recwarn)
    residual = sorpia.limit_points(res.control_vertices, f) - v
    assert np.abs(residual).max() <= 1e-12  # B V = V0 to rounding level either way


def test_every_warning_sorpia_issues_derives_from_one_base_class():
    # One filter catches them all: every UserWarning subclass the package exports derives from SorpiaWarning,
    # and the classes are the ones the modules raise (the same objects, not copies).
    exported = [getattr(sorpia, name) for name in sorpia.__all__]
    warning_classes = [c for c in exported if isinstance(c, type) and issubclass(c, Warning)]
    assert len(warning_classes) >= 7
    assert all(issubclass(c, sorpia.SorpiaWarning) for c in warning_classes)
    assert sorpia.solve.ConvergenceWarning is sorpia.errors.ConvergenceWarning
    with pytest.warns(sorpia.SorpiaWarning):
        sorpia.interpolate(V1, F1, method="pia", max_iter=1)


def test_modules_that_are_not_api_are_private():
    # The public modules are those the reference documents (docs/api.rst, docs/layout.md); helpers of the commands
    # and of the Python API (statistics layout, the non-manifold split, repair's wrapper, sharp edges, figures) are
    # private, so that renaming them breaks no user.
    import pkgutil

    public = {m.name for m in pkgutil.iter_modules(sorpia.__path__) if not m.name.startswith("_")}
    assert public == {"approximate", "blender", "cage", "cli", "energy", "errors", "fair", "io", "limit", "shapes",
                      "solve", "surface"}
