"""Nothing the user gave is lost and every promise holds (issue 20, item 7): the
outputs are checked before the solve, the boundary rule is always written,
texture coordinates go from the input to the control mesh, and info's verdict
is fit's.

References: the files themselves, re-read, and parsed by hand where the point
is what another reader sees (OpenSubdiv's regression reader, far_utils.h, takes
edge-only when an OBJ has no `t interpolateboundary` line)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sorpia
from cli_support import assert_user_error

# far_utils.h's reading of `t interpolateboundary 1/0/0 MODE`, and its default without the line.
OSD_BOUNDARY_MODES = {1: "edge-and-corner", 2: "edge-only"}
OSD_DEFAULT_BOUNDARY = "edge-only"


def osd_boundary(text: str) -> str:
    """The boundary rule OpenSubdiv's regression reader takes from an OBJ file's text."""
    rule = OSD_DEFAULT_BOUNDARY
    for line in text.splitlines():
        words = line.split()
        if words[:3] == ["t", "interpolateboundary", "1/0/0"]:
            rule = OSD_BOUNDARY_MODES[int(words[3])]
    return rule


def uv_grid(tmp_path, name="grid.obj", nu=6, nv=5):
    """A quad grid with texture coordinates (x, y) / 4 and a normal per vertex, written as OBJ."""
    V, F = sorpia.shapes.quad_grid(nu, nv)
    corners = np.ascontiguousarray(F.reshape(-1), dtype=np.int32)
    uvs = sorpia.FaceVarying(V[:, :2] / 4.0, corners)
    normals = sorpia.FaceVarying(np.tile([[0.0, 0.0, 1.0]], (len(V), 1)), corners)
    sorpia.write_mesh(tmp_path / name, V, F, uvs=uvs, normals=normals)
    return tmp_path / name, V, F, uvs


def test_default_boundary_rule_is_written_and_read_back_as_opensubdiv_reads_it(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    V, F = sorpia.shapes.quad_grid(6, 5)
    sorpia.write_mesh("grid.obj", V, F)  # no tag: sorpia's default rule, edge-and-corner
    code, _, err = command("fit", "grid.obj", "-o", "c.obj")
    assert code == 0, err
    text = (tmp_path / "c.obj").read_text()
    assert osd_boundary(text) == "edge-and-corner"
    ctrl, F2, tags = sorpia.read_mesh("c.obj", tags=True)
    assert tags == {"boundary": "edge-and-corner"}
    diag = np.linalg.norm(V.max(0) - V.min(0))
    # The cage evaluated with the rule a reader takes from the file passes through the targets (1e-9 of the
    # diagonal: the solve's tol 1e-10 times the condition of B, far below the defect's size).
    err_read = np.abs(sorpia.limit_points(ctrl, F2, scheme="catmull-clark", boundary=osd_boundary(text)) - V).max()
    assert err_read < 1e-9 * diag
    # What the line prevents: without it OpenSubdiv's reader takes edge-only and misses the targets.
    untagged = "\n".join(line for line in text.splitlines() if not line.startswith("t "))
    err_untagged = np.abs(sorpia.limit_points(ctrl, F2, scheme="catmull-clark", boundary=osd_boundary(untagged))
                          - V).max()
    assert err_untagged > 1e-3 * diag


def test_fit_carries_texture_coordinates_not_normals(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    path, V, F, uvs = uv_grid(tmp_path)
    code, stdout, err = command("fit", path.name, "-o", "c.obj", "--report", "r.json")
    assert code == 0, err
    ctrl, F2, attributes = sorpia.read_mesh("c.obj", attributes=True)
    np.testing.assert_array_equal(F2, F)
    # Per corner, the control mesh's texture coordinates are the input's, exactly (shortest round-trip text).
    np.testing.assert_array_equal(attributes["uvs"].values[attributes["uvs"].indices], uvs.values[uvs.indices])
    assert "normals" not in attributes
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["attributes"]["uvs"] == "written" and report["attributes"]["normals"].startswith("not written")
    assert "texture coordinates written" in stdout


def seam_file(path, normals: bool):
    """A quad grid whose face 3 is given twice (repair drops one) and face 5 reversed (repair flips it back),
    written by hand with a seam everywhere: corner j of face f has texture coordinate (f, j) (and normal
    (0, f, j)), so only a per-corner reading passes. Returns the faces as written."""
    V, F = sorpia.shapes.quad_grid(5, 4)
    F = np.vstack([F, F[3:4]])
    F[5] = F[5, ::-1]
    corner = (lambda f, j: f"{4 * f + j + 1}/{4 * f + j + 1}") if normals else (lambda f, j: f"{4 * f + j + 1}")
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in V.tolist()]
    lines += [f"vt {f} {j}" for f in range(len(F)) for j in range(4)]
    lines += [f"vn 0 {f} {j}" for f in range(len(F)) for j in range(4)] if normals else []
    lines += ["f " + " ".join(f"{v + 1}/{corner(f, j)}" for j, v in enumerate(face)) for f, face in enumerate(F)]
    path.write_text("\n".join(lines) + "\n")
    return F


def test_fit_carries_texture_coordinates_through_triangulate_and_repair(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    F = seam_file(tmp_path / "seams.obj", normals=False)
    # Independent: the value of (input face, input vertex) straight from the lines above.
    value = {(f, int(v)): (float(f), float(j)) for f, face in enumerate(F) for j, v in enumerate(face)}
    code, _, err = command("fit", "seams.obj", "-o", "c.obj", "--repair", "--triangulate", "--report", "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    vertex_map = np.asarray(report["repair"]["vertex_map"])
    face_map = np.asarray(report["repair"]["face_map"])  # repaired face -> face of the triangulated input
    ctrl, T, attributes = sorpia.read_mesh("c.obj", attributes=True)
    # The triangulated input's face t comes from input face t // 2 (two triangles per quad, in order).
    got = attributes["uvs"].values[attributes["uvs"].indices].reshape(-1, 3, 2)
    for t, tri in enumerate(T):
        f = int(face_map[t]) // 2
        for c, v in enumerate(tri):
            assert tuple(got[t, c]) == value[(f, int(vertex_map[v]))]


def test_repair_keeps_texture_coordinates_and_normals(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    F = seam_file(tmp_path / "in.obj", normals=True)
    code, _, err = command("repair", "in.obj", "-o", "out.obj", "--report", "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    vertex_map, face_map = np.asarray(report["vertex_map"]), np.asarray(report["face_map"])
    _, G, attributes = sorpia.read_mesh("out.obj", attributes=True)
    assert len(G) == len(F) - 1  # the duplicate dropped
    uv = attributes["uvs"].values[attributes["uvs"].indices].reshape(len(G), 4, 2)
    normals = attributes["normals"].values[attributes["normals"].indices].reshape(len(G), 4, 3)
    for g, face in enumerate(G):
        f = int(face_map[g])
        for c, v in enumerate(face):
            j = F[f].tolist().index(int(vertex_map[v]))  # the input corner at the same input vertex
            assert tuple(uv[g, c]) == (f, j) and tuple(normals[g, c]) == (0, f, j)


def test_ply_control_mesh_takes_per_vertex_uvs_and_a_seam_is_warned_before_the_solve(tmp_path, monkeypatch,
                                                                                       command):
    monkeypatch.chdir(tmp_path)
    path, V, F, uvs = uv_grid(tmp_path)
    code, _, err = command("fit", path.name, "-o", "c.ply")
    assert code == 0, err
    _, _, attributes = sorpia.read_mesh("c.ply", attributes=True)
    np.testing.assert_array_equal(attributes["uvs"].values[attributes["uvs"].indices], uvs.values[uvs.indices])
    # A seam: PLY cannot hold it; the warning comes before the solve's summary, and the file is written without.
    seam = sorpia.FaceVarying(np.vstack([uvs.values, [[5.0, 5.0]]]), uvs.indices.copy())
    seam.indices[2] = len(V)
    sorpia.write_mesh("seam.obj", V, F, uvs=seam)
    code, stdout, err = command("fit", "seam.obj", "-o", "s.ply", "--report", "r.json")
    assert code == 0, err
    assert f"vertex {F[0, 2]} has different ones in different faces (a seam)" in err  # the PLY writer's words
    assert json.loads((tmp_path / "r.json").read_text())["attributes"]["uvs"].startswith("not written")
    assert sorpia.read_mesh("s.ply", attributes=True)[2] == {}


@pytest.mark.parametrize("options, words", [
    (("-o", "c.stl"), "-o c.stl: STL holds triangles only, and the control mesh has the input's faces (of 4"),
    (("-o", "c.obj", "--surface", "s.stl"), "--surface s.stl: STL holds triangles only, and the Catmull-Clark "
                                             "limit surface is a quad mesh"),
])
def test_an_output_that_cannot_hold_its_faces_is_refused_before_the_solve(tmp_path, monkeypatch, command,
                                                                         options, words):
    monkeypatch.chdir(tmp_path)
    V, F = sorpia.shapes.quad_grid(4, 4)
    sorpia.write_mesh("quads.obj", V, F)
    code, stdout, err = command("fit", "quads.obj", *options)
    assert_user_error(code, err)
    assert words in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quads.obj"]  # nothing written, no solve reported
    assert stdout == ""


def test_loop_surface_to_stl_is_written(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    V, F = sorpia.shapes.icosphere(1)
    sorpia.write_mesh("ico.obj", V, F)
    code, _, err = command("fit", "ico.obj", "-o", "c.stl", "--surface", "s.stl", "--level", "1")
    assert code == 0, err
    assert sorpia.read_mesh("s.stl")[1].shape == (len(F) * 4, 3)


@pytest.mark.parametrize("command_name", ["fit", "render"])
def test_a_mesh_whose_faces_are_all_holes_is_refused_before_the_solve(tmp_path, monkeypatch, command, command_name):
    if command_name == "render":
        pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")
    monkeypatch.chdir(tmp_path)
    V, F = sorpia.shapes.quad_grid(4, 4)
    sorpia.write_mesh("holes.obj", V, F, holes=np.arange(len(F)))
    args = {"fit": ("fit", "holes.obj", "-o", "c.obj", "--surface", "s.obj"),
            "render": ("render", "holes.obj", "-o", "r.png")}[command_name]
    code, stdout, err = command(*args)
    assert_user_error(code, err)
    assert f"every one of the {len(F)} faces is a hole, so the limit surface is empty" in err
    assert stdout == "" and not (tmp_path / args[3]).exists()
    with pytest.raises(sorpia.MeshError, match=f"every one of the {len(F)} faces is a hole"):
        sorpia.Interpolator(F, len(V), scheme="catmull-clark", holes=np.arange(len(F)))
    # Some faces holes is a mesh as before.
    sorpia.Interpolator(F, len(V), scheme="catmull-clark", holes=np.arange(len(F) - 1))


def test_render_a_crease_beside_a_hole(tmp_path, monkeypatch, command):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")
    monkeypatch.chdir(tmp_path)
    V, F = sorpia.shapes.quad_grid(5, 5)
    V[:, 2] = np.sin(V[:, 0] * 3) * 0.1
    # Faces 6 and 7 (neighbours) are holes; creases on two of face 6's inner edges: the one it shares with
    # face 7 (both sides holes) and one it shares with a face that is not a hole.
    holes = [6, 7]
    inner = [F[6, [j, (j + 1) % 4]] for j in range(4) if len(sorpia_faces_of_edge(F, F[6, [j, (j + 1) % 4]])) == 2]
    creases = np.array([next(e for e in inner if 7 not in sorpia_faces_of_edge(F, e)),
                        next(e for e in inner if 7 in sorpia_faces_of_edge(F, e))])
    sorpia.write_mesh("m.obj", V, F, creases=(creases, np.inf), holes=holes)
    code, _, err = command("render", "m.obj", "-o", "r.png", "--size", "300x250")
    assert code == 0, err
    assert (tmp_path / "r.png").stat().st_size > 0

    from sorpia._plotting import crease_curves

    surface = sorpia.LimitSurface(V, F, scheme="catmull-clark", creases=(creases, np.inf), holes=holes)
    points, normals = crease_curves(surface, F, creases, holes=holes)
    # Independent of the curve's evaluation: Bfr at a face corner is the vertex's limit position (B V).
    limit = sorpia.limit_points(V, F, scheme="catmull-clark", creases=(creases, np.inf), holes=holes)
    ends = np.stack([points[:, 0], points[:, -1]], axis=1)
    sides_both_holes = [all(f in holes for f in sorpia_faces_of_edge(F, e)) for e in creases]
    assert sides_both_holes == [False, True]  # the case each crease stands for
    for k, both in enumerate(sides_both_holes):
        if both:  # no surface on either side: no curve
            assert np.isnan(points[k]).all()
        else:
            np.testing.assert_allclose(ends[k], limit[creases[k]], atol=1e-12)  # rounding of Bfr and masks
            assert np.isfinite(normals[k]).all()


def sorpia_faces_of_edge(F, edge):
    """The faces having edge (a, b), by scanning rows: independent of plotting's edge search."""
    a, b = (int(x) for x in edge)
    return [f for f, face in enumerate(F.tolist())
            if any({face[j], face[(j + 1) % len(face)]} == {a, b} for j in range(len(face)))]


def quad_file(tmp_path, name, extra=""):
    V, F = sorpia.shapes.quad_grid(4, 4)
    sorpia.write_mesh(tmp_path / name, V, F)
    if extra:
        with open(tmp_path / name, "a") as fh:
            fh.write(extra)
    return name


def nonmanifold_file(tmp_path, name):
    """Three quads on one edge (a non-manifold edge)."""
    V = np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0.5], [-1, 1, 0.5], [0, 0, 1], [0, 1, 1]],
                 dtype=float)
    sorpia.write_mesh(tmp_path / name, V, [[0, 2, 3, 1], [0, 1, 5, 4], [1, 0, 6, 7]])
    return name


@pytest.mark.filterwarnings("default::sorpia.NonmanifoldWarning")  # printed by the command, as a user sees it
@pytest.mark.parametrize("make, options", [
    (lambda p: quad_file(p, "ok.obj"), ()),
    (lambda p: quad_file(p, "ib0.obj", "t interpolateboundary 1/0/0 0\n"), ()),
    (lambda p: quad_file(p, "ib0.obj", "t interpolateboundary 1/0/0 0\n"), ("--ignore-tags",)),
    (lambda p: quad_file(p, "chaikin.obj", "t creasemethod 0/0/1 chaikin\n"), ()),
    (lambda p: quad_file(p, "allholes.obj", "t hole 16/0/0 " + " ".join(map(str, range(16))) + "\n"), ()),
    (lambda p: quad_file(p, "ok.obj"), ("--scheme", "loop")),
    (lambda p: quad_file(p, "ok.obj"), ("--scheme", "loop", "--triangulate")),
    (lambda p: nonmanifold_file(p, "nm.obj"), ()),
    (lambda p: nonmanifold_file(p, "nm.obj"), ("--nonmanifold", "sharp")),
])
def test_info_verdict_is_fits(tmp_path, monkeypatch, command, make, options):
    monkeypatch.chdir(tmp_path)
    name = make(tmp_path)
    code, stdout, err = command("info", name, "--json", *options)
    assert code == 0, err
    verdict = json.loads(stdout)["pia"]
    fit_code, _, fit_err = command("fit", name, "-o", "c.obj", *options)
    assert fit_code in (0, 2), fit_err
    assert verdict["can_run"] == (fit_code == 0), (verdict, fit_err)
    if not verdict["can_run"]:
        # the same refusal in both: the last words of fit's message are in info's reason
        assert fit_err.strip().splitlines()[-1].split(": ")[-1] in verdict["reason"]
