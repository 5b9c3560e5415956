"""Mesh files with polygons and OpenSubdiv's sharpness tags: what the readers
return (the (m, k) array or sorpia.Polygons), bit-exact round trips through
write_mesh, the `t` lines as OpenSubdiv's shape parser reads them (checked
against an independent parser of the same rules on OpenSubdiv's own shapes in
../shared/meshes when present), and sorpia.sharp_edges against numpy."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import sorpia

SHARED_MESHES = Path(__file__).resolve().parents[2] / "shared" / "meshes"


def mixed_mesh():
    """Vertices and the faces (a triangle, a quad, a pentagon, a quad) of a strip, irrational coordinates."""
    rng = np.random.default_rng(7)
    v = rng.standard_normal((9, 3)) / 3.0
    faces = [[0, 1, 2], [0, 2, 3, 4], [2, 5, 6, 7, 3], [3, 7, 8, 4]]
    return v, faces


def obj_text(v, faces, extra: str = "") -> str:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    return "\n".join(lines) + "\n" + extra


def off_multiline_text(v, faces) -> str:
    """OFF with every face record spread over two lines and a comment between them."""
    lines = ["OFF", f"{len(v)} {len(faces)} 0"] + [f"{x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    for f in faces:
        lines += [f"{len(f)} {f[0]}  # the first corner", " ".join(map(str, f[1:]))]
    return "\n".join(lines) + "\n"


def ply_text(v, faces) -> str:
    head = ["ply", "format ascii 1.0", f"element vertex {len(v)}", "property double x", "property double y",
            "property double z", f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    return "\n".join(head + [f"{x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
                     + [f"{len(f)} " + " ".join(map(str, f)) for f in faces]) + "\n"


def as_lists(faces):
    """Faces as read_mesh returns them, as a list of index lists."""
    if isinstance(faces, sorpia.Polygons):
        ends = np.cumsum(faces.face_vertex_counts)
        return [c.tolist() for c in np.split(faces.face_vertex_indices, ends[:-1])]
    return faces.tolist()


@pytest.mark.parametrize("fmt", ["obj", "off-multiline", "ply"])
def test_mixed_polygons_read_as_counts_and_indices(tmp_path, fmt):
    v, faces = mixed_mesh()
    text = {"obj": obj_text, "off-multiline": off_multiline_text, "ply": ply_text}[fmt](v, faces)
    path = tmp_path / f"mixed.{fmt.split('-')[0]}"
    path.write_text(text)
    w, f = sorpia.read_mesh(path)
    assert isinstance(f, sorpia.Polygons)
    assert f.face_vertex_counts.dtype == np.int32 and f.face_vertex_indices.dtype == np.int32
    assert f.face_vertex_counts.tolist() == [3, 4, 5, 4]
    assert as_lists(f) == faces
    assert w.tobytes() == v.tobytes()  # repr() of a float64 reads back bit for bit
    # triangulate: (m, 3), k - 2 triangles per face in its place, every corner a corner of its face
    w, t = sorpia.read_mesh(path, triangulate=True)
    assert t.shape == (1 + 2 + 3 + 2, 3)
    rows = np.cumsum([0] + [len(p) - 2 for p in faces])
    for p, a, b in zip(faces, rows[:-1], rows[1:]):
        assert set(t[a:b].ravel()) == set(p)


def test_uniform_faces_come_back_as_an_m_by_k_array(tmp_path):
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], dtype=float)
    quads = [[0, 1, 2, 3], [1, 4, 5, 2]]
    (tmp_path / "q.obj").write_text(obj_text(v, quads))
    _, f = sorpia.read_mesh(tmp_path / "q.obj")
    assert isinstance(f, np.ndarray) and f.dtype == np.int32 and f.tolist() == quads


@pytest.mark.parametrize("name,binary", [("m.obj", False), ("m.off", False), ("m.ply", False), ("m.ply", True)])
def test_polygons_round_trip_bit_for_bit(tmp_path, name, binary):
    v, faces = mixed_mesh()
    sorpia.write_mesh(tmp_path / name, v, faces, binary=binary)
    w, f = sorpia.read_mesh(tmp_path / name)
    assert w.tobytes() == v.tobytes() and as_lists(f) == faces
    # the Polygons form and an (m, 4) array too
    sorpia.write_mesh(tmp_path / name, v, f, binary=binary)
    assert as_lists(sorpia.read_mesh(tmp_path / name)[1]) == faces
    quads = np.array([[0, 2, 3, 4], [3, 7, 8, 4]], dtype=np.int64)
    sorpia.write_mesh(tmp_path / name, v, quads, binary=binary)
    assert np.array_equal(sorpia.read_mesh(tmp_path / name)[1], quads)


def test_writing_polygons_to_stl_and_tags_to_other_formats_are_clear_errors(tmp_path):
    v, faces = mixed_mesh()
    with pytest.raises(sorpia.ParameterError, match="STL stores triangles only"):
        sorpia.write_mesh(tmp_path / "m.stl", v, faces)
    with pytest.raises(sorpia.ParameterError, match=r"\.obj files only"):
        sorpia.write_mesh(tmp_path / "m.ply", v, faces, creases=([[0, 1]], 2.0))
    with pytest.raises(sorpia.MeshError, match=r"faces\[1\] has 2 vertices: a face needs at least 3"):
        sorpia.write_mesh(tmp_path / "m.obj", v, [[0, 1, 2], [3, 4]])
    with pytest.raises(sorpia.MeshError, match="out of range"):
        sorpia.write_mesh(tmp_path / "m.obj", v, [[0, 1, 2], [3, 4, 99]])
    assert not list(tmp_path.iterdir())  # nothing written


TAGGED = """t crease 2/1/0 0 1 2.5
t crease 4/1/0 1 2 2 3 10
t crease 4/2/0 7 8 8 4 1.25 -3
t corner 1/1/0 5 0.7
t hole 1/0/0 2
t interpolateboundary 1/0/0 2
t creasemethod 0/0/1 normal
t smoothtriangles 0/0/1 catmark
t facevaryinginterpolateboundary 1/0/0 1
"""


def test_tags_are_read_as_opensubdiv_reads_them(tmp_path):
    v, faces = mixed_mesh()
    path = tmp_path / "tags.obj"
    path.write_text(obj_text(v, faces, TAGGED))
    assert len(sorpia.read_mesh(path)) == 2  # tags only when asked
    w, f, tags = sorpia.read_mesh(path, tags=True)
    assert set(tags) == {"creases", "corners", "holes", "boundary"}
    edges, sharpness = tags["creases"]
    # pairs, not a chain: (1 2 2 3) is the edges (1, 2) and (2, 3); a negative sharpness reads as 0
    assert edges.dtype == np.int32 and edges.tolist() == [[0, 1], [1, 2], [2, 3], [7, 8], [8, 4]]
    assert sharpness.dtype == np.float64 and sharpness.tolist() == [2.5, 10, 10, 1.25, 0]
    assert tags["corners"][0].tolist() == [5] and tags["corners"][1].tolist() == [0.7]
    assert tags["holes"].tolist() == [2] and tags["boundary"] == "edge-only"
    # with triangulate the hole is the three triangles of the pentagon (rows 3, 4, 5)
    _, t, ttags = sorpia.read_mesh(path, triangulate=True, tags=True)
    assert ttags["holes"].tolist() == [3, 4, 5] and set(t[3:6].ravel()) == set(faces[2])
    assert ttags["creases"][0].tolist() == edges.tolist()


def test_tags_round_trip_bit_for_bit(tmp_path):
    v, faces = mixed_mesh()
    src = tmp_path / "in.obj"
    src.write_text(obj_text(v, faces, "t crease 2/1/0 2 3 0.30000000000000004\nt crease 2/1/0 3 4 1e-300\n"
                                      "t corner 1/1/0 8 7.9\nt hole 1/0/0 0\nt interpolateboundary 1/0/0 1\n"))
    w, f, tags = sorpia.read_mesh(src, tags=True)
    sorpia.write_mesh(tmp_path / "out.obj", w, f, **tags)
    w2, f2, tags2 = sorpia.read_mesh(tmp_path / "out.obj", tags=True)
    assert w2.tobytes() == w.tobytes() and as_lists(f2) == as_lists(f)
    assert tags2.keys() == tags.keys()
    for key in ("creases", "corners"):
        assert tags2[key][0].tolist() == tags[key][0].tolist()
        assert tags2[key][1].tobytes() == tags[key][1].tobytes()
    assert tags2["holes"].tolist() == [0] and tags2["boundary"] == "edge-and-corner"


@pytest.mark.parametrize("line,message", [
    ("t creasemethod 0/0/1 chaikin", "line 14: tag 'creasemethod chaikin' is not supported"),
    ("t interpolateboundary 1/0/0 0", "line 14: tag 'interpolateboundary 0'"),
    ("t smoothtriangles 0/0/1 smooth", "line 14: tag 'smoothtriangles smooth' is not supported"),
    ("t crease 2/1/0 0 99 1", "line 14: tag vertex 99 is out of range: the file has 9 vertices"),
    ("t hole 1/0/0 4", "line 14: tag 'hole': face 4 is out of range: the file has 4 faces"),
    ("t crease 3/1/0 0 1 2 1", "line 14: tag 'crease' takes vertex pairs"),
    ("t corner 1/1/0 3", "line 14: tag 'corner': the line ends before its number arguments"),
])
def test_bad_tags_name_the_file_and_line(tmp_path, line, message):
    v, faces = mixed_mesh()
    path = tmp_path / "bad.obj"
    path.write_text(obj_text(v, faces, line + "\n"))
    with pytest.raises(sorpia.MeshFileError, match=r"bad\.obj, " + message.replace("(", r"\(").replace(")", r"\)")):
        sorpia.read_mesh(path, tags=True)
    sorpia.read_mesh(path)  # without tags=True the line is not read


def test_unknown_tags_are_skipped_with_a_warning(tmp_path):
    v, faces = mixed_mesh()
    path = tmp_path / "odd.obj"
    path.write_text(obj_text(v, faces, "t vertexcolour 0/3/0 1 0 0\nt vertexcolour 0/3/0 0 1 0\n"))
    with pytest.warns(sorpia.UnknownTagWarning, match="'vertexcolour': 2 tags, the first on line 14"):
        _, _, tags = sorpia.read_mesh(path, tags=True)
    assert tags == {}


# ---------------------------------------------------------------- OpenSubdiv's shapes

def opensubdiv_parse(text: str):
    """OpenSubdiv's regression/common/shape_utils.cpp parseObj and parseTag, and the
    tag rules of far_utils.h (assignComponentTags, GetSdcOptions), written out
    independently: vertices, faces (lists of 0-based indices) and the tags."""
    verts, faces, creases, corners, holes, boundary = [], [], {}, {}, [], None
    for line in text.splitlines():
        if line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            faces.append([int(tok.split("/")[0]) - 1 for tok in line.split()[1:]])
        elif line.startswith("t "):
            tok = line.split()
            name, (ni, nf, ns) = tok[1], map(int, tok[2].split("/"))
            ints = [int(x) for x in tok[3:3 + ni]]
            floats = [float(x) for x in tok[3 + ni:3 + ni + nf]]
            if name == "crease":
                for j in range(0, len(ints) - 1, 2):
                    creases[(ints[j], ints[j + 1])] = max(0.0, floats[j // 2] if nf > 1 else floats[0])
            elif name == "corner":
                for j, vtx in enumerate(ints):
                    corners[vtx] = max(0.0, floats[j] if nf > 1 else floats[0])
            elif name == "hole":
                holes += ints
            elif name == "interpolateboundary":
                boundary = {1: "edge-and-corner", 2: "edge-only"}[ints[0]]
    return np.array(verts), faces, creases, corners, holes, boundary


OSD_SHAPES = sorted(SHARED_MESHES.glob("osd_*.obj")) if SHARED_MESHES.exists() else []


@pytest.mark.skipif(not OSD_SHAPES, reason="../shared/meshes is not present")
@pytest.mark.parametrize("path", OSD_SHAPES or [None], ids=[p.name for p in OSD_SHAPES] or ["none"])
def test_opensubdiv_shapes_read_as_opensubdiv_reads_them(path):
    verts, faces, creases, corners, holes, boundary = opensubdiv_parse(path.read_text())
    v, f, tags = sorpia.read_mesh(path, tags=True)
    np.testing.assert_array_equal(v, verts)  # both correctly rounded from the same decimals
    assert as_lists(f) == faces
    if creases:
        edges, sharpness = tags["creases"]
        assert {(a, b): s for (a, b), s in zip(edges.tolist(), sharpness.tolist())} == creases
        assert len(edges) == len(creases)  # no edge tagged twice in these files
    else:
        assert "creases" not in tags
    got_corners = dict(zip(*(a.tolist() for a in tags["corners"]))) if "corners" in tags else {}
    assert got_corners == corners
    assert tags.get("holes", np.zeros(0)).tolist() == holes
    assert tags.get("boundary") == boundary


# ---------------------------------------------------------------- sharp edges

def numpy_sharp_edges(v, faces, angle):
    """Edges whose two faces' Newell normals are more than `angle` degrees apart, from the face list."""
    normals = []
    for f in faces:
        p = v[f]
        q = np.roll(p, -1, axis=0)
        a, b = p - q, p + q
        n = np.array([(a[:, 1] * b[:, 2]).sum(), (a[:, 2] * b[:, 0]).sum(), (a[:, 0] * b[:, 1]).sum()])
        normals.append(n / np.linalg.norm(n))
    sides: dict = {}
    for i, f in enumerate(faces):
        for a, b in zip(f, f[1:] + f[:1]):
            sides.setdefault((min(a, b), max(a, b)), []).append(i)
    sharp = []
    for edge, fs in sides.items():
        if len(fs) == 2:
            n0, n1 = normals[fs[0]], normals[fs[1]]
            if np.degrees(np.arctan2(np.linalg.norm(np.cross(n0, n1)), n0 @ n1)) > angle:
                sharp.append(list(edge))
    return sorted(sharp)


def test_sharp_edges_of_a_cube_and_a_noisy_mixed_mesh():
    cube_v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    cube_f = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    edges = sorpia.sharp_edges(cube_v, cube_f, 89.0)
    assert edges.dtype == np.int32 and edges.shape == (12, 2)
    assert edges.tolist() == numpy_sharp_edges(cube_v, cube_f, 89.0)
    assert len(sorpia.sharp_edges(cube_v, np.array(cube_f), 90.0)) == 0  # exactly 90: not more than 90
    # A bumpy open grid of quads, triangles and a pentagon: every threshold agrees with numpy.
    rng = np.random.default_rng(3)
    n = 6
    grid = np.array([[i, j, 0.0] for i in range(n) for j in range(n)]) + rng.normal(0, 0.25, (n * n, 3))
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1, i * n + j + 1
            faces += [[a, b, c], [a, c, d]] if (i + j) % 3 == 0 else [[a, b, c, d]]
    for angle in (0.0, 10.0, 25.0, 40.0, 180.0):
        assert sorpia.sharp_edges(grid, faces, angle).tolist() == numpy_sharp_edges(grid, faces, angle), angle


def test_sharp_edges_refuse_a_bad_angle_and_a_non_manifold_mesh():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0]], dtype=float)
    with pytest.raises(sorpia.ParameterError, match="must be in \\[0, 180\\]"):
        sorpia.sharp_edges(v, [[0, 1, 2]], 200)
    with pytest.raises(sorpia.MeshError, match="face 2 cannot join OpenMesh's half-edge mesh"):
        sorpia.sharp_edges(v, [[0, 1, 2], [1, 0, 3], [0, 1, 4]], 30)  # edge (0, 1) in three faces


def test_no_warning_for_a_file_without_tags(tmp_path):
    v, faces = mixed_mesh()
    (tmp_path / "plain.obj").write_text(obj_text(v, faces))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert sorpia.read_mesh(tmp_path / "plain.obj", tags=True)[2] == {}
