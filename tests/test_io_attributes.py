"""Texture coordinates and normals through read_mesh / write_mesh (attributes=True, uvs=, normals=).

The reference is the file text itself: each test writes its file by hand and
parses the `vt`/`vn`/`f a/b/c` statements (or the PLY columns) with a few lines
of Python, independently of the C++ readers, and files written by write_mesh
are read back."""

from __future__ import annotations

import numpy as np
import pytest

import sorpia
from sorpia import AttributeWarning, FaceVarying, MeshFileError, ParameterError

# Two quads and a triangle sharing edges, with a UV seam at vertex 1
# (two texture coordinates) and normals per corner; mixed index forms
# (positive, negative, a/b/c and a//c on separate files).
OBJ = """\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0.5
v 2 1 0.25
v 1.5 2 0
vt 0 0
vt 0.25 0
vt 0.25 0.25
vt 0 0.25
vt 0.75 0
vt 0.5 0.5
vt 0.125 0.875
vn 0 0 1
vn 0.6 0 0.8
f 1/1/1 2/2/1 3/3/1 4/4/1
f 2/5/2 5/6/2 -2/-1/-1
f 3/3/1 6/6/2 7/7/1 4/4/1
"""


def parse_obj_corners(text: str):
    """(vertex, uv value, normal value) per corner, straight from the file text: an independent reader."""
    vt, vn, corners = [], [], []
    for line in text.splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "vt":
            vt.append([float(x) for x in words[1:]])
        elif words[0] == "vn":
            vn.append([float(x) for x in words[1:]])
        elif words[0] == "v":
            corners.append(None)  # keeps the count of vertices read so far in the list below
        elif words[0] == "f":
            n_v = sum(c is None for c in corners)
            for w in words[1:]:
                parts = w.split("/")
                idx = [int(p) if p else None for p in parts] + [None] * (3 - len(parts))
                v = idx[0] - 1 if idx[0] > 0 else idx[0] + n_v
                t = None if idx[1] is None else (idx[1] - 1 if idx[1] > 0 else idx[1] + len(vt))
                n = None if idx[2] is None else (idx[2] - 1 if idx[2] > 0 else idx[2] + len(vn))
                corners.append((v, None if t is None else vt[t], None if n is None else vn[n]))
    return [c for c in corners if c is not None]


def corner_values(faces, channel: FaceVarying):
    """(vertex, value) per corner of read_mesh's faces."""
    verts = (np.asarray(faces).reshape(-1) if isinstance(faces, np.ndarray)
             else np.asarray(faces.face_vertex_indices))
    return verts, channel.values[channel.indices]


def test_obj_uvs_and_normals_read_per_corner(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text(OBJ)
    V, F, attributes = sorpia.read_mesh(path, attributes=True)
    expected = parse_obj_corners(OBJ)
    verts, uv = corner_values(F, attributes["uvs"])
    _, normals = corner_values(F, attributes["normals"])
    assert verts.tolist() == [c[0] for c in expected]
    # Exact: short decimals parse to the same doubles in both readers.
    np.testing.assert_array_equal(uv, [c[1] for c in expected])
    np.testing.assert_array_equal(normals, [c[2] for c in expected])
    # The seam: vertex 1 has two texture coordinates.
    assert {tuple(x) for x in uv[verts == 1]} == {(0.25, 0.0), (0.75, 0.0)}
    # Without attributes=True the same two values as before.
    assert len(sorpia.read_mesh(path)) == 2


def test_obj_round_trip_is_exact(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text(OBJ)
    V, F, attributes = sorpia.read_mesh(path, attributes=True)
    rng = np.random.default_rng(3)
    uvs = FaceVarying(rng.random(attributes["uvs"].values.shape), attributes["uvs"].indices)  # full-precision values
    out = tmp_path / "out.obj"
    sorpia.write_mesh(out, V, F, uvs=uvs, normals=attributes["normals"])
    V2, F2, again = sorpia.read_mesh(out, attributes=True)
    np.testing.assert_array_equal(V2, V)
    for name, channel in (("uvs", uvs), ("normals", attributes["normals"])):
        # Values per corner are compared (the indices may be renumbered by a writer; this one keeps them).
        np.testing.assert_array_equal(corner_values(F2, again[name])[1], corner_values(F, channel)[1])
    # The text holds the a/b/c corners.
    assert "f 1/1/1 2/2/1 3/3/1 4/4/1" in out.read_text()


def test_obj_triangulated_corners_keep_their_polygon_values(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text(OBJ)
    V, T, attributes = sorpia.read_mesh(path, triangulate=True, attributes=True)
    assert T.shape == (2 + 1 + 2, 3)  # file order: a quad's 2 triangles, the triangle, the other quad's 2
    expected = parse_obj_corners(OBJ)
    # The file's faces by corner: (face, vertex) -> value, from the independent parse.
    sizes = [4, 3, 4]
    owner = np.repeat(np.arange(3), sizes)
    by_face_vertex = {(int(f), c[0]): c[1] for f, c in zip(owner, expected)}
    rows_of_face = [0, 0, 1, 2, 2]  # the quad's two triangles, the triangle, the last quad's two
    verts, uv = corner_values(T, attributes["uvs"])
    for k, (v, value) in enumerate(zip(verts.tolist(), uv.tolist())):
        assert by_face_vertex[(rows_of_face[k // 3], v)] == value


def test_ply_per_vertex_round_trip_and_seam_refused(tmp_path):
    V, F = sorpia.shapes.quad_grid(4, 3)
    rng = np.random.default_rng(1)
    per_vertex = FaceVarying(rng.random((len(V), 2)), np.ascontiguousarray(F.reshape(-1), dtype=np.int32))
    normals = FaceVarying(rng.normal(size=(len(V), 3)), per_vertex.indices)
    for binary in (False, True):
        out = tmp_path / f"m{int(binary)}.ply"
        sorpia.write_mesh(out, V, F, binary=binary, uvs=per_vertex, normals=normals)
        V2, F2, again = sorpia.read_mesh(out, attributes=True)
        np.testing.assert_array_equal(F2, F)
        np.testing.assert_array_equal(again["uvs"].values[again["uvs"].indices], per_vertex.values[per_vertex.indices])
        np.testing.assert_array_equal(again["normals"].values[again["normals"].indices],
                                      normals.values[normals.indices])
    # A seam (vertex F[0, 2], in four faces, with two values) cannot be stored per vertex.
    seam = FaceVarying(np.vstack([per_vertex.values, [[9.0, 9.0]]]), per_vertex.indices.copy())
    seam.indices[2] = len(V)
    with pytest.raises(ParameterError, match=f"vertex {F[0, 2]} has different"):
        sorpia.write_mesh(tmp_path / "seam.ply", V, F, uvs=seam)
    with pytest.raises(ParameterError, match="written to .obj and .ply files only"):
        sorpia.write_mesh(tmp_path / "m.off", V, F, uvs=per_vertex)


def test_the_ply_per_vertex_check_before_the_work_refuses_what_the_writer_refuses():
    # The check made before long work (sorpia::check_ply_per_vertex, through io.attribute_refusal's binding) is the
    # writer's, indices included: a value index or a vertex index out of range is refused with write_mesh's words
    # (MeshError), not read past the arrays; a seam as the writer says it.
    from sorpia import MeshError, _core

    V, F = sorpia.shapes.quad_grid(4, 3)
    corners = np.ascontiguousarray(F.reshape(-1), dtype=np.int32)
    values = np.random.default_rng(1).random((len(V), 2))

    def check(corners, indices, n_vertices=len(V)):
        _core.check_ply_per_vertex(corners, None, 4, n_vertices, values, indices, "texture coordinates")

    check(corners, corners.copy())  # one value per vertex: held
    bad = corners.copy()
    bad[5] = len(V) + 7
    with pytest.raises(MeshError, match=f"write_mesh: face 1 has texture coordinates index {len(V) + 7} out of range"):
        check(corners, bad)
    with pytest.raises(MeshError, match="write_mesh: face 0 has vertex index .* out of range"):
        check(corners, corners.copy(), n_vertices=2)
    seam = corners.copy()
    seam[2] = (seam[2] + 1) % len(V)
    with pytest.raises(ParameterError, match="has different ones in different faces"):
        check(corners, seam)


def test_ply_reads_the_common_property_names(tmp_path):
    # float s/t and texture_u/texture_v, written by hand; the values are exact in float32.
    for names in (("s", "t"), ("texture_u", "texture_v")):
        path = tmp_path / f"{names[0]}.ply"
        path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                        f"property float z\nproperty float {names[0]}\nproperty float nz\nproperty float "
                        f"{names[1]}\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                        "0 0 0 0.5 1 0.25\n1 0 0 0.75 1 0.5\n0 1 0 0.125 1 1\n3 0 1 2\n")
        V, F, attributes = sorpia.read_mesh(path, attributes=True)
        np.testing.assert_array_equal(attributes["uvs"].values, [[0.5, 0.25], [0.75, 0.5], [0.125, 1.0]])
        np.testing.assert_array_equal(attributes["uvs"].indices, [0, 1, 2])
        assert "normals" not in attributes  # nz alone is no normal


def test_partial_uvs_dropped_with_a_warning(tmp_path):
    path = tmp_path / "partial.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\nf 2 4 3\n")
    with pytest.warns(AttributeWarning, match="texture coordinates dropped: 3 of 6 face corners"):
        _, _, attributes = sorpia.read_mesh(path, attributes=True)
    assert attributes == {}


def test_bad_uv_index_names_its_line(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/2\n")
    with pytest.raises(MeshFileError, match=r"line 5: texture coordinate index 2 is out of range"):
        sorpia.read_mesh(path, attributes=True)
    # Without attributes the texture indices are not read, as before.
    assert sorpia.read_mesh(path)[1].shape == (1, 3)
