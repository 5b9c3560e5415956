"""Mesh files: exact round trips, other programs' files, errors with file and
line, atomic writes, and the real meshes in ../shared/meshes when present."""

from __future__ import annotations

import os
import re
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import sorpia

# Awkward float64 values: no short decimal, tiny, huge, negative zero, subnormals.
AWKWARD = np.array([
    [1 / 3, np.pi * 1e-7, 1e300],
    [-0.0, 5e-324, 2.2250738585072014e-308],
    [0.1, 0.2, 0.30000000000000004],
    [-1.7976931348623157e308, 4.9406564584124654e-320, 123456789.12345679],
])
AWKWARD_FACES = np.array([[0, 1, 2], [0, 2, 3], [1, 3, 2]])
EXACT_FORMATS = [("obj", False), ("off", False), ("ply", False), ("ply", True)]


def random_doubles(n, seed):
    """n x 3 doubles from random bit patterns (every exponent), finite."""
    rng = np.random.default_rng(seed)
    v = rng.integers(0, 2**64, size=(n, 3), dtype=np.uint64).view(np.float64)
    return np.where(np.isfinite(v), v, 0.5)


def same_bits(a, b):
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("ext,binary", EXACT_FORMATS)
def test_awkward_values_round_trip_bit_for_bit(tmp_path, ext, binary):
    path = tmp_path / f"m.{ext}"
    sorpia.write_mesh(path, AWKWARD, AWKWARD_FACES, binary=binary)
    v, f = sorpia.read_mesh(path)
    assert same_bits(v, AWKWARD)  # -0.0 and subnormals included
    assert f.dtype == np.int32 and np.array_equal(f, AWKWARD_FACES)


@pytest.mark.parametrize("ext,binary", EXACT_FORMATS)
def test_random_bit_patterns_round_trip_bit_for_bit(tmp_path, ext, binary):
    v0, f0 = sorpia.shapes.icosphere(2)
    v0 = random_doubles(len(v0), seed=len(ext) + binary)
    path = tmp_path / f"m.{ext}"
    sorpia.write_mesh(path, v0, f0, binary=binary)
    v, f = sorpia.read_mesh(path)
    assert same_bits(v, v0) and np.array_equal(f, f0)


@pytest.mark.parametrize("binary", [False, True])
def test_stl_stores_float32_and_merges_equal_corners(tmp_path, binary):
    # Vertices numbered in order of first appearance in the faces, as the STL
    # reader numbers them, so the round trip gives back the float32 rounding.
    v0, f0 = sorpia.shapes.icosphere(1)
    order = np.unique(f0.ravel(), return_index=True)[1]
    first_seen = f0.ravel()[np.sort(order)]
    rank = np.empty(len(v0), dtype=np.int64)
    rank[first_seen] = np.arange(len(v0))
    v0, f0 = v0[first_seen] * np.pi, rank[f0]
    path = tmp_path / "m.stl"
    sorpia.write_mesh(path, v0, f0, binary=binary)
    v, f = sorpia.read_mesh(path)
    assert same_bits(v, v0.astype(np.float32).astype(np.float64))
    assert np.array_equal(f, f0)
    if binary:
        assert path.stat().st_size == 84 + 50 * len(f0)
        assert not path.read_bytes().startswith(b"solid")  # other readers take that for ascii


def test_stl_refuses_coordinates_beyond_float32(tmp_path):
    with pytest.raises(sorpia.MeshError, match="beyond float32"):
        sorpia.write_mesh(tmp_path / "m.stl", AWKWARD, AWKWARD_FACES)


def test_binary_ply_is_what_the_header_says(tmp_path):
    # double x y z and "list uchar int": 24 bytes per vertex, 13 per face.
    v, f = sorpia.shapes.icosphere(1)
    path = tmp_path / "m.ply"
    sorpia.write_mesh(path, v, f, binary=True)
    data = path.read_bytes()
    head, body = data.split(b"end_header\n", 1)
    assert b"format binary_little_endian 1.0" in head and b"property double x" in head
    assert len(body) == 24 * len(v) + 13 * len(f)
    assert np.array_equal(np.frombuffer(body[: 24 * len(v)], "<f8").reshape(-1, 3), v)


def write_text(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text).lstrip("\n"))
    return path


def test_blender_style_obj_with_normals_texcoords_and_groups(tmp_path):
    path = write_text(tmp_path, "blender.obj", """
        # Blender v2.93.1 OBJ File: ''
        # www.blender.org
        mtllib cube.mtl
        o Tetra
        v 1.000000 1.000000 1.000000
        v -1.000000 -1.000000 1.000000
        v -1.000000 1.000000 -1.000000
        v 1.000000 -1.000000 -1.000000 1.0
        vt 0.875000 0.500000
        vt 0.625000 0.750000
        vt 0.625000 0.500000
        vn 0.5774 0.5774 0.5774
        vn -0.5774 -0.5774 0.5774
        usemtl Material
        s off
        f 1/1/1 2/2/1 4/3/1
        f 1//2 3//2 2//2
        g second
        f -4/1 -1/2 -2/3
        f 1 4 3
    """)
    v, f = sorpia.read_mesh(path)
    assert np.array_equal(v, [[1, 1, 1], [-1, -1, 1], [-1, 1, -1], [1, -1, -1]])
    assert np.array_equal(f, [[0, 1, 3], [0, 2, 1], [0, 3, 2], [0, 3, 2]])


def test_off_with_comments_colours_and_counts_on_the_header_line(tmp_path):
    path = write_text(tmp_path, "colours.off", """
        COFF 4 4 6
        # a tetrahedron with vertex colours
        0 0 0  255 0 0 255
        1 0 0  0 255 0 255   # x axis
        0 1 0  0 0 255 255

        0 0 1  9 9 9 255
        3 0 2 1  0.5 0.5 0.5
        3 0 1 3
        3 1 2 3
        3 0 3 2
    """)
    v, f = sorpia.read_mesh(path)
    assert np.array_equal(v, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert np.array_equal(f, [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def test_ascii_ply_with_extra_properties_and_elements(tmp_path):
    path = write_text(tmp_path, "extra.ply", """
        ply
        format ascii 1.0
        comment made by a scanner
        obj_info some text
        element vertex 4
        property float nx
        property float x
        property float y
        property float z
        property uchar red
        element face 2
        property uchar flags
        property list uchar int vertex_indices
        property list uchar float texcoord
        element edge 1
        property int vertex1
        property int vertex2
        end_header
        9 0 0 0 255
        9 1 0 0.5 0
        9 0 1 -0.25 7
        9 1 1 1e-3 7
        1 3 0 1 2 6 0 0 1 0 0 1
        0 3 2 1 3 0
        0 1
    """)
    v, f = sorpia.read_mesh(path)
    assert np.array_equal(v, [[0, 0, 0], [1, 0, 0.5], [0, 1, -0.25], [1, 1, 1e-3]])
    assert np.array_equal(f, [[0, 1, 2], [2, 1, 3]])


@pytest.mark.parametrize("endian", ["<", ">"])
def test_binary_ply_with_float_coordinates_uchar_counts_and_extra_properties(tmp_path, endian):
    name = "binary_little_endian" if endian == "<" else "binary_big_endian"
    header = (f"ply\nformat {name} 1.0\nelement vertex 3\nproperty float x\nproperty uchar quality\n"
              "property float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_index\n"
              "property int material\nend_header\n").encode()
    body = b"".join(struct.pack(endian + "fBff", *p) for p in [(0.1, 1, 0, 0), (1, 2, 0, 0), (0, 3, 1, 2.5)])
    body += struct.pack(endian + "B3Ii", 3, 0, 1, 2, 7)
    path = tmp_path / "f32.ply"
    path.write_bytes(header + body)
    v, f = sorpia.read_mesh(path)
    # float32 values widened exactly, as the file stores them.
    assert same_bits(v, np.array([[0.1, 0, 0], [1, 0, 0], [0, 1, 2.5]], dtype=np.float32).astype(np.float64))
    assert np.array_equal(f, [[0, 1, 2]])


def test_ascii_stl_from_another_program(tmp_path):
    path = write_text(tmp_path, "part.stl", """
        solid part exported by CAD
          facet normal 0.000000e+00 0.000000e+00 -1.000000e+00
            outer loop
              vertex 0.000000e+00 0.000000e+00 0.000000e+00
              vertex 0.000000e+00 1.000000e+00 0.000000e+00
              vertex 1.000000e+00 0.000000e+00 0.000000e+00
            endloop
          endfacet
          facet normal 0 0 -1
            outer loop
              vertex 1 0 0
              vertex 0 1 0
              vertex +1.0 1.0 -0.0
            endloop
          endfacet
        endsolid part
    """)
    v, f = sorpia.read_mesh(path)
    assert np.array_equal(v, [[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]])
    assert np.array_equal(f, [[0, 1, 2], [2, 1, 3]])


def test_binary_stl_whose_header_starts_with_solid(tmp_path):
    # Some exporters start the 80-byte header with "solid": the size rule decides.
    tri = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    path = tmp_path / "solid.stl"
    path.write_bytes(b"solid binary".ljust(80, b" ") + struct.pack("<I", 1) + tri)
    v, f = sorpia.read_mesh(path)
    assert np.array_equal(v, [[0, 0, 0], [1, 0, 0], [0, 1, 0]]) and np.array_equal(f, [[0, 1, 2]])


QUAD_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 5\nf 1 2 3 4\n"


@pytest.mark.parametrize("ext", ["obj", "off", "ply"])
def test_polygons_are_split_into_fans_when_asked(tmp_path, ext):
    v0 = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], dtype=float)
    text = {
        "obj": QUAD_OBJ,
        "off": "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n3 0 1 4\n4 0 1 2 3\n",
        "ply": ("ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty double z\n"
                "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n3 0 1 4\n4 0 1 2 3\n"),
    }[ext]
    path = tmp_path / f"poly.{ext}"
    path.write_text(text)
    v, f = sorpia.read_mesh(path)  # kept as they are: a triangle and a quad
    assert isinstance(f, sorpia.Polygons)
    assert f.face_vertex_counts.tolist() == [3, 4] and f.face_vertex_indices.tolist() == [0, 1, 4, 0, 1, 2, 3]
    v, f = sorpia.read_mesh(path, triangulate=True)
    assert np.array_equal(v, v0)
    assert np.array_equal(f, [[0, 1, 4], [0, 1, 2], [0, 2, 3]])


def test_mesh_file_error_is_a_value_error():
    assert issubclass(sorpia.MeshFileError, ValueError)


@pytest.mark.parametrize("ext", ["obj", "off", "ply", "stl"])
def test_missing_empty_directory_and_random_bytes_fail_cleanly(tmp_path, ext):
    with pytest.raises(sorpia.MeshFileError,
                       match=rf"missing\.{ext}: cannot open the file: No such file or directory"):
        sorpia.read_mesh(tmp_path / f"missing.{ext}")
    (tmp_path / f"folder.{ext}").mkdir()
    with pytest.raises(sorpia.MeshFileError, match=rf"folder\.{ext}: is a directory, not a mesh file"):
        sorpia.read_mesh(tmp_path / f"folder.{ext}")
    (tmp_path / f"empty.{ext}").write_bytes(b"")
    with pytest.raises(sorpia.MeshFileError, match="the file is empty"):
        sorpia.read_mesh(tmp_path / f"empty.{ext}")
    noise = tmp_path / f"noise.{ext}"
    noise.write_bytes(np.random.default_rng(5).integers(0, 256, 5000, dtype=np.uint8).tobytes())
    with pytest.raises(sorpia.MeshFileError, match=re.escape(str(noise))):
        sorpia.read_mesh(noise)


@pytest.mark.parametrize("ext", ["ply", "stl"])
def test_truncated_binary_files_are_reported(tmp_path, ext):
    v, f = sorpia.shapes.icosphere(1)
    path = tmp_path / f"m.{ext}"
    sorpia.write_mesh(path, v, f, binary=True)
    path.write_bytes(path.read_bytes()[:-7])
    with pytest.raises(sorpia.MeshFileError, match="ends inside|truncated"):
        sorpia.read_mesh(path)


def test_unknown_extension_is_refused(tmp_path):
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(sorpia.MeshFileError, match=r"unknown mesh file extension '\.xyz': use \.obj"):
        sorpia.write_mesh(tmp_path / "m.xyz", v, f)
    with pytest.raises(sorpia.MeshFileError, match=r"unknown mesh file extension \(none\)"):
        sorpia.read_mesh(tmp_path / "mesh")


def test_extension_case_does_not_matter(tmp_path):
    v, f = sorpia.shapes.icosphere(0)
    sorpia.write_mesh(tmp_path / "M.OBJ", v, f)
    assert same_bits(sorpia.read_mesh(tmp_path / "M.OBJ")[0], v)


def test_binary_obj_is_refused(tmp_path):
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(sorpia.ParameterError, match="OBJ and OFF are text formats"):
        sorpia.write_mesh(tmp_path / "m.obj", v, f, binary=True)


def test_vertex_order_and_unreferenced_vertices_are_kept(tmp_path):
    # No merging, no reordering: duplicated positions and an unused vertex survive.
    v0 = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [5, 5, 5]], dtype=float)
    f0 = np.array([[0, 1, 2], [3, 2, 0]])
    for ext, binary in EXACT_FORMATS:
        path = tmp_path / f"keep.{ext}"
        sorpia.write_mesh(path, v0, f0, binary=binary)
        v, f = sorpia.read_mesh(path)
        assert same_bits(v, v0) and np.array_equal(f, f0)


def leftovers(folder):
    return sorted(p.name for p in Path(folder).iterdir() if "sorpia-tmp" in p.name)


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    # A child process limited to 1000-byte files (RLIMIT_FSIZE, SIGXFSZ
    # ignored, so write() fails with EFBIG) writes a bigger mesh over an
    # existing file: the error names the file, the old content survives whole
    # and no temporary file is left. Works as root, unlike a read-only folder.
    target = tmp_path / "mesh.ply"
    target.write_bytes(b"old content")
    script = textwrap.dedent(f"""
        import resource, signal, sys
        import sorpia
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (1000, 1000))
        v, f = sorpia.shapes.icosphere(3)
        try:
            sorpia.write_mesh({str(target)!r}, v, f, binary=True)
        except sorpia.MeshFileError as e:
            print("MeshFileError:", e)
            sys.exit(0)
        sys.exit(1)
    """)
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "mesh.ply: writing failed (nothing was changed)" in run.stdout
    assert target.read_bytes() == b"old content"
    assert leftovers(tmp_path) == []


def test_bad_input_is_refused_before_the_file_is_touched(tmp_path):
    target = tmp_path / "mesh.obj"
    target.write_bytes(b"old content")
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(sorpia.MeshError, match="out of range"):
        sorpia.write_mesh(target, v, f + 1)
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(sorpia.MeshError, match=r"vertices\[3\].*not finite"):
        sorpia.write_mesh(target, bad, f)
    assert target.read_bytes() == b"old content" and leftovers(tmp_path) == []


def test_writing_over_a_directory_or_into_a_missing_folder_fails(tmp_path):
    v, f = sorpia.shapes.icosphere(0)
    (tmp_path / "d.obj").mkdir()
    with pytest.raises(sorpia.MeshFileError, match="is a directory"):
        sorpia.write_mesh(tmp_path / "d.obj", v, f)
    with pytest.raises(sorpia.MeshFileError, match="cannot create a temporary file"):
        sorpia.write_mesh(tmp_path / "no" / "such" / "m.obj", v, f)
    assert leftovers(tmp_path) == []


def test_a_write_replaces_an_existing_file_and_keeps_its_mode(tmp_path):
    target = tmp_path / "m.off"
    target.write_text("old")
    os.chmod(target, 0o640)
    v, f = sorpia.shapes.icosphere(1)
    sorpia.write_mesh(target, v, f)
    assert (target.stat().st_mode & 0o777) == 0o640
    assert same_bits(sorpia.read_mesh(target)[0], v)


SHARED_MESHES = Path(__file__).resolve().parents[2] / "shared" / "meshes"


def shared_mesh_counts():
    """(file, vertices, faces) from the table in ../shared/meshes/README.md."""
    readme = SHARED_MESHES / "README.md"
    if not readme.exists():
        return []
    rows = []
    for line in readme.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) > 3 and re.fullmatch(r"[\w.-]+\.(obj|off|ply|stl)", cells[0]):
            rows.append((cells[0], int(cells[1]), int(cells[2])))
    return rows


@pytest.mark.skipif(not SHARED_MESHES.exists(), reason="../shared/meshes is not present")
@pytest.mark.parametrize("name,n_vertices,n_faces", shared_mesh_counts() or [("none", 0, 0)])
def test_shared_meshes_read_with_the_counts_their_readme_lists(name, n_vertices, n_faces):
    v, f = sorpia.read_mesh(SHARED_MESHES / name)
    assert v.shape == (n_vertices, 3) and f.shape == (n_faces, 3)
    assert f.min() >= 0 and f.max() < n_vertices


# A tetrahedron written plainly, and the variants real tools write: each must
# read as exactly the same arrays (float64, order kept).
TETRA_V = np.array([[0, 0, 0], [1.5, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
TETRA_F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
TETRA_OBJ = "v 0 0 0\nv 1.5 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n"
TETRA_OFF_BODY = "0 0 0\n1.5 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n"


@pytest.mark.parametrize("name,text", [
    ("bom.obj", "\ufeff" + TETRA_OBJ),
    ("classic-mac-line-ends.obj", TETRA_OBJ.replace("\n", "\r")),
    ("continued-lines.obj", TETRA_OBJ.replace("v 1.5 0 0", "v 1.5 \\\n 0 0").replace("f 2 3 4", "f 2 \\  \n3 \\\n4")),
    ("weight-and-colours.obj", TETRA_OBJ.replace("v 0 0 0", "v 0 0 0 1.0").replace("v 0 1 0", "v 0 1 0 0.2 0.3 0.4")),
    ("bom.off", "\ufeffOFF\n4 4 6\n" + TETRA_OFF_BODY),
    ("counts-after-comments.off", "OFF\n# written by a tool\n\n# counts next\n4 4 6\n" + TETRA_OFF_BODY),
    ("counts-over-lines.off", "OFF\n4   # vertices\n4   # faces\n" + TETRA_OFF_BODY),
    ("no-edge-count.off", "OFF\n4 4\n" + TETRA_OFF_BODY),
    ("records-over-lines.off", "OFF\n4 4 6\n0 0 0\n1.5\n0 0\n0 1 0\n0 0 1\n3 0 2\n1\n3\n0 1 3\n3 1 2 3 0.5 0.5 0.5\n3 0 3 2\n"),
])
def test_file_variants_that_real_tools_write_read_exactly(tmp_path, name, text):
    path = tmp_path / name
    path.write_bytes(text.encode("utf-8"))
    v, f = sorpia.read_mesh(path)
    assert v.dtype == np.float64 and same_bits(v, TETRA_V)
    assert np.array_equal(f, TETRA_F)


def test_obj_vertex_line_with_a_word_is_refused_with_its_line(tmp_path):
    path = tmp_path / "word.obj"
    path.write_text(TETRA_OBJ.replace("v 0 1 0", "v 0 1 0 x"))
    with pytest.raises(sorpia.MeshFileError, match=r"word\.obj, line 3: expected a number, found 'x'"):
        sorpia.read_mesh(path)


def grid_strips(nu, nv):
    """Triangle strips of an nu x nv grid of vertices, one strip per row of
    quads joined by -1, and the grid's triangles as a consistent orientation
    would list them: quad (i, j) as (a, c, b) and (b, c, d) with a = (i, j),
    b = (i, j+1), c = (i+1, j), d = (i+1, j+1)."""
    idx = lambda i, j: i * nv + j  # noqa: E731
    strips, tris = [], []
    for i in range(nu - 1):
        for j in range(nv):
            strips += [idx(i, j), idx(i + 1, j)]
        strips.append(-1)
        for j in range(nv - 1):
            a, b, c, d = idx(i, j), idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1)
            tris += [(a, c, b), (b, c, d)]
    return strips[:-1], tris


def canonical(faces):
    """Faces as a set of cyclic rotations starting at the smallest index:
    equal sets mean the same triangles with the same orientation."""
    out = set()
    for t in np.asarray(faces).tolist():
        k = t.index(min(t))
        out.add(tuple(t[k:] + t[:k]))
    return out


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_tristrips_give_the_strips_triangles_in_one_orientation(tmp_path, encoding):
    nu, nv = 4, 5
    strips, tris = grid_strips(nu, nv)
    # the first two rows joined by degenerate triangles (repeat the last and the
    # next first vertex; the strip's parity is kept) instead of a -1 restart
    row = 2 * nv
    strips = strips[:row] + [strips[row - 1], strips[row + 1]] + strips[row + 1:]
    xs, ys = np.meshgrid(np.arange(nv, dtype=float), np.arange(nu, dtype=float))
    v = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(nu * nv)])
    header = (f"ply\nformat {encoding} 1.0\nelement vertex {len(v)}\nproperty double x\nproperty double y\n"
              f"property double z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n")
    if encoding == "ascii":
        body = "".join(" ".join(map(repr, p)) + "\n" for p in v.tolist())
        body += f"{len(strips)} " + " ".join(map(str, strips)) + "\n"
        data = (header + body).encode()
    else:
        e = "<" if encoding.endswith("little_endian") else ">"
        data = header.encode() + v.astype(e + "f8").tobytes()
        data += np.array([len(strips)] + strips, dtype=e + "i4").tobytes()
    path = tmp_path / "strips.ply"
    path.write_bytes(data)
    v2, f2 = sorpia.read_mesh(path)
    assert same_bits(v2, v)
    assert len(f2) == len(tris) and canonical(f2) == canonical(tris)
    # one orientation throughout: sorpia's validation accepts it as a surface
    assert np.allclose(sorpia.limit_points(sorpia.interpolate(v2, f2).control_vertices, f2), v, atol=1e-9)


def test_triangulation_never_repeats_a_face_when_a_manifold_split_exists(tmp_path):
    """Two quads over the same four vertices, the second listed from another
    corner: fanning both from their first vertex gives the triangle (a, b, c)
    twice (once reversed). The split must take the other diagonal for the
    second quad, which closes the two quads into a tetrahedron."""
    path = tmp_path / "pillow.obj"
    path.write_text("v 0 0 0\nv 0.5 -1 0.2\nv 1 0 0\nv 0.5 1 -0.2\nf 1 2 3 4\nf 3 2 1 4\n")
    v, f = sorpia.read_mesh(path, triangulate=True)
    assert len(canonical(f)) == 4 and len({tuple(sorted(t)) for t in f.tolist()}) == 4  # no face twice
    edges = {}
    for t in f.tolist():
        for a, b in zip(t, t[1:] + t[:1]):
            edges[tuple(sorted((a, b)))] = edges.get(tuple(sorted((a, b))), 0) + 1
    assert set(edges.values()) == {2}  # closed, every edge of two faces
    res = sorpia.interpolate(v, f)  # sorpia's validation accepts it: consistently oriented, manifold
    assert np.allclose(sorpia.limit_points(res.control_vertices, f), v, atol=1e-9)


def test_quads_are_cut_along_their_shorter_diagonal(tmp_path):
    """A grid of quads whose vertices lean one way or the other at random
    (some quads with equal diagonals): every quad's two triangles share its
    shorter diagonal."""
    rng = np.random.default_rng(5)
    nu, nv = 5, 6
    lean = rng.choice([-0.4, 0.4], size=(nu, nv))
    v = np.array([[j + lean[i, j] * i, i, 0.0] for i in range(nu) for j in range(nv)])
    quads = [(i * nv + j, i * nv + j + 1, (i + 1) * nv + j + 1, (i + 1) * nv + j)
             for i in range(nu - 1) for j in range(nv - 1)]
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in v.tolist()) + "".join(
        "f " + " ".join(str(k + 1) for k in q) + "\n" for q in quads)
    path = tmp_path / "grid.obj"
    path.write_text(text)
    _, f = sorpia.read_mesh(path, triangulate=True)
    for k, (a, b, c, d) in enumerate(quads):
        t1, t2 = set(f[2 * k]), set(f[2 * k + 1])
        shared = t1 & t2
        # a tie keeps the fan from the first corner, (a, c)
        short = {b, d} if np.linalg.norm(v[b] - v[d]) < np.linalg.norm(v[a] - v[c]) else {a, c}
        assert shared == short, k
        assert t1 | t2 == {a, b, c, d}


def test_file_names_that_are_not_utf8_read_and_write(tmp_path):
    """A file name the OS takes but that is not UTF-8 (the byte 0xe9 of a
    Latin-1 'é'), as Python gives it (surrogate escapes) and as bytes: the mesh
    round-trips bit for bit, and messages show the byte as \\xe9."""
    v, f = sorpia.shapes.icosphere(1)
    name = os.fsdecode(b"lat\xe9.ply")
    sorpia.write_mesh(tmp_path / name, v, f, binary=True)
    assert (os.fsencode(tmp_path) + b"/lat\xe9.ply") in [os.fsencode(p) for p in tmp_path.iterdir()]
    for path in (tmp_path / name, os.fsencode(tmp_path / name)):
        v2, f2 = sorpia.read_mesh(path)
        assert same_bits(v2, v) and np.array_equal(f2, f)
    with pytest.raises(sorpia.MeshFileError, match=r"lat\\xe9\.obj: cannot open the file"):
        sorpia.read_mesh(tmp_path / os.fsdecode(b"lat\xe9.obj"))


READ_UNDER_LIMIT = """
import resource, sys
import sorpia
resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))  # 1 GiB: the input is endless or 2 GiB
try:
    sorpia.read_mesh(sys.argv[1])
except sorpia.MeshFileError as e:
    print(e)
"""


@pytest.mark.parametrize("source,ext,match", [
    ("/dev/zero", "obj", r"line 1: '\\x00.*is not an OBJ statement"),
    ("/dev/zero", "off", r"line 1: an OFF file starts with 'OFF'"),
    ("/dev/urandom", "ply", r"line 1: a PLY file starts with the line 'ply'"),
    ("sparse", "ply", r"line 1: a PLY file starts with the line 'ply'"),
])
def test_endless_or_huge_input_of_another_kind_fails_on_its_start(tmp_path, source, ext, match):
    """The start of a file is checked before the rest is read: a device or a
    2 GiB file of zeros fails at once under a 1 GiB address-space limit
    instead of being read whole (MemoryError) or forever."""
    path = tmp_path / f"input.{ext}"
    if source == "sparse":
        with open(path, "wb") as fh:
            fh.truncate(2 << 30)
    else:
        if not os.path.exists(source):
            pytest.skip(f"{source} does not exist here")
        path.symlink_to(source)
    out = subprocess.run([sys.executable, "-c", READ_UNDER_LIMIT, str(path)], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert re.search(match, out.stdout), out.stdout
