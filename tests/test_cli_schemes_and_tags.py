"""The command line's schemes and sharpness tags: --scheme auto|loop|catmull-clark, the tags of an OBJ file (used
by default, --ignore-tags), --sharp-angle, and what info and fit's report say of them."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sorpia
from cli_support import assert_user_error, write_obj


def cube_of_triangles():
    """A closed cube of 12 triangles: its 12 edges at 90 degrees, its 6 face diagonals flat."""
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    tris = [[a, b, c] for a, b, c, d in quads] + [[a, c, d] for a, b, c, d in quads]
    return v, np.array(tris), quads


def tagged_obj(path, v, faces, tag_lines):
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    path.write_text("\n".join(lines + tag_lines) + "\n")
    return path


def test_auto_scheme_is_loop_for_triangles_and_catmull_clark_for_polygons(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, tris, quads = cube_of_triangles()
    for name, faces, scheme, sizes in (("t.obj", tris, "loop", {"3": 12}), ("q.obj", quads, "catmull-clark",
                                                                            {"4": 6})):
        tagged_obj(tmp_path / name, v, faces, [])
        code, stdout, err = command("info", name, "--json")
        assert code == 0, err
        info = json.loads(stdout)
        assert info["scheme"] == scheme and info["face_sizes"] == sizes and info["pia"]["scheme"] == scheme
    # --scheme loop on the quads: the verdict is the refusal, naming the first face and both ways out
    code, stdout, err = command("info", "q.obj", "--json", "--scheme", "loop")
    assert code == 0, err
    verdict = json.loads(stdout)["pia"]
    assert verdict["can_run"] is False and "face 0 has 4 vertices" in verdict["reason"]
    # --triangulate makes the same file a Loop input
    code, stdout, err = command("info", "q.obj", "--json", "--triangulate")
    assert json.loads(stdout)["scheme"] == "loop" and json.loads(stdout)["face_sizes"] == {"3": 12}


def test_info_lists_the_tags_with_counts_and_sharpness(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, _, quads = cube_of_triangles()
    lines = ["t crease 2/1/0 0 1 10", "t crease 2/1/0 1 3 10", "t crease 2/1/0 3 2 2.5", "t corner 1/1/0 7 4",
             "t hole 1/0/0 5", "t interpolateboundary 1/0/0 2"]
    tagged_obj(tmp_path / "tags.obj", v, quads, lines)
    code, stdout, err = command("info", "tags.obj", "--json")
    assert code == 0, err
    info = json.loads(stdout)
    creases = info["tags"]["creases"]
    assert creases["count"] == 3 and creases["infinitely_sharp"] == 2 and creases["semi_sharp"] == 1
    assert creases["sharpness_histogram"] == {"2.5": 1, "10.0": 2}
    assert info["tags"]["corners"]["count"] == 1 and info["tags"]["holes"] == {"count": 1}
    assert info["boundary"] == "edge-only"  # the file's interpolateboundary, --boundary not given
    code, stdout, err = command("info", "tags.obj")
    assert code == 0, err
    assert "creases 3: 2 infinitely sharp, 1 semi-sharp (sharpness 2.5 x 1, 10 x 2)" in stdout
    assert "corners 1: 1 semi-sharp (sharpness 4 x 1)" in stdout and "holes 1" in stdout
    # --boundary wins over the tag; --ignore-tags drops them all
    code, stdout, err = command("info", "tags.obj", "--json", "--boundary", "edge-and-corner", "--ignore-tags")
    info = json.loads(stdout)
    assert info["boundary"] == "edge-and-corner" and set(info["tags"]) == {"from_file", "sharp_angle"}


def test_tags_sorpia_refuses_are_explained_by_info_and_refused_by_fit(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, tris, _ = cube_of_triangles()
    tagged_obj(tmp_path / "chaikin.obj", v, tris, ["t crease 2/1/0 0 1 3", "t creasemethod 0/0/1 chaikin"])
    code, stdout, err = command("info", "chaikin.obj", "--json")
    assert code == 0, err
    refused = json.loads(stdout)["tags"]["refused"]
    assert "chaikin.obj, line 22: tag 'creasemethod chaikin' is not supported" in refused
    code, _, err = command("fit", "chaikin.obj", "-o", "c.obj")
    assert_user_error(code, err)
    assert "creasemethod chaikin" in err
    # without the tags the cube fits with Loop
    code, _, err = command("fit", "chaikin.obj", "-o", "c.obj", "--ignore-tags", "--report", "r.json", "--quiet")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["scheme"] == "loop" and report["tags"]["from_file"] is False and report["face_sizes"] == {"3": 12}


def test_sharp_angle_marks_the_edges_numpy_finds(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, tris, _ = cube_of_triangles()
    rng = np.random.default_rng(2)
    v = v + rng.normal(0, 0.02, v.shape)  # the diagonals' faces no longer coplanar, by a few degrees
    write_obj(tmp_path / "cube.obj", v, tris)
    # Independent count: edges whose two triangles' normals differ by more than 45 degrees.
    normals = np.cross(v[tris[:, 1]] - v[tris[:, 0]], v[tris[:, 2]] - v[tris[:, 0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    faces_of: dict = {}
    for i, t in enumerate(tris.tolist()):
        for a, b in zip(t, t[1:] + t[:1]):
            faces_of.setdefault((min(a, b), max(a, b)), []).append(i)
    angles = {e: np.degrees(np.arccos(np.clip(normals[f0] @ normals[f1], -1, 1))) for e, (f0, f1) in faces_of.items()}
    expected = sorted(e for e, a in angles.items() if a > 45)
    assert len(expected) == 12  # the cube's edges, none of its diagonals
    code, stdout, err = command("info", "cube.obj", "--json", "--sharp-angle", "45")
    assert code == 0, err
    creases = json.loads(stdout)["tags"]["creases"]
    assert creases["count"] == 12 and creases["infinitely_sharp"] == 12
    assert sorpia.sharp_edges(v, tris, 45).tolist() == [list(e) for e in expected]
    code, _, err = command("info", "cube.obj", "--sharp-angle", "200")
    assert code == 2 and "expected an angle from 0 to 180 degrees" in err


def test_fit_report_records_scheme_and_tags(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, tris, _ = cube_of_triangles()
    write_obj(tmp_path / "cube.obj", v, tris)
    code, stdout, err = command("fit", "cube.obj", "-o", "c.obj", "--report", "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["scheme"] == "loop" and report["tags"] == {"from_file": True, "sharp_angle": None,
                                                             "written_to_output": []}
    assert "scheme      Loop, boundary edge-and-corner" in stdout
    # the control mesh is an OBJ without tag lines: nothing to keep
    assert "\nt " not in (tmp_path / "c.obj").read_text()


@pytest.mark.parametrize("option", ["--scheme", "--ignore-tags", "--sharp-angle"])
def test_every_solving_command_takes_the_scheme_options(option, command):
    for name in ("fit", "compare", "render", "info"):
        code, stdout, _ = command(name, "--help")
        assert code == 0 and option in stdout, name
    code, stdout, _ = command("demo", "--help")
    assert "--scheme" in stdout
