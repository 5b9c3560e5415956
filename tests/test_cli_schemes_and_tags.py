"""The command line's schemes and sharpness tags: --scheme auto|loop|catmull-clark, the tags of an OBJ file (used
by default, --ignore-tags), --sharp-angle, and what info and fit's report say of them."""

from __future__ import annotations

import json
from pathlib import Path

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
                                                             "written_to_output": ["boundary"]}
    assert "scheme      Loop, boundary edge-and-corner" in stdout
    # no sharpness tags to keep; the boundary rule is always written (test_cli_outputs.py)
    tag_lines = [line for line in (tmp_path / "c.obj").read_text().splitlines() if line.startswith("t ")]
    assert tag_lines == ["t interpolateboundary 1/0/0 1"]


@pytest.mark.parametrize("option", ["--scheme", "--ignore-tags", "--sharp-angle"])
def test_every_solving_command_takes_the_scheme_options(option, command):
    for name in ("fit", "compare", "render", "info"):
        code, stdout, _ = command(name, "--help")
        assert code == 0 and option in stdout, name
    code, stdout, _ = command("demo", "--help")
    assert "--scheme" in stdout


def test_fit_solves_with_the_file_tags_and_writes_them_with_the_control_mesh(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, tris, _ = cube_of_triangles()
    v = v + np.random.default_rng(4).normal(0, 0.03, v.shape)
    lines = ["t crease 2/1/0 0 1 10", "t crease 2/1/0 1 3 10", "t crease 2/1/0 3 2 2.5", "t corner 1/1/0 7 1.5",
             "t interpolateboundary 1/0/0 2"]
    tagged_obj(tmp_path / "tags.obj", v, tris, lines)
    code, stdout, err = command("fit", "tags.obj", "-o", "c.obj", "--report", "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["tags"]["creases"]["count"] == 3 and report["tags"]["corners"]["count"] == 1
    assert report["tags"]["written_to_output"] == ["boundary", "corners", "creases"]
    _, _, tags = sorpia.read_mesh("tags.obj", tags=True)
    ctrl, f, written = sorpia.read_mesh("c.obj", tags=True)
    assert np.array_equal(f, tris) and written.keys() == tags.keys()
    for key in ("creases", "corners"):
        assert np.array_equal(written[key][0], tags[key][0]) and written[key][1].tobytes() == tags[key][1].tobytes()
    # The control mesh's limit, with the tags it carries, passes through the given vertices.
    limit = sorpia.limit_points(ctrl, f, **written)
    assert np.abs(limit - v).max() < 1e-9
    # Without the tags the same control mesh's limit misses them: the tags were used.
    assert np.abs(sorpia.limit_points(ctrl, f, boundary="edge-only") - v).max() > 1e-3
    # A format without tags: the control mesh is written without them, with a warning saying so.
    code, _, err = command("fit", "tags.obj", "-o", "c.ply", "--quiet")
    assert code == 0 and "sharpness tags (corners, creases) are not written: only .obj and USD files hold them" in err


def test_fit_with_sharp_angle_writes_the_creases_it_found(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, tris, _ = cube_of_triangles()
    write_obj(tmp_path / "cube.obj", v, tris)
    code, _, err = command("fit", "cube.obj", "-o", "c.obj", "--sharp-angle", "60", "--quiet")
    assert code == 0, err
    ctrl, f, tags = sorpia.read_mesh("c.obj", tags=True)
    edges, sharpness = tags["creases"]
    assert edges.tolist() == sorpia.sharp_edges(v, tris, 60).tolist() and (sharpness == 10).all()
    # Every vertex of a cube with all 12 edges sharp is a corner: the limit is the control mesh itself.
    assert np.array_equal(ctrl, v)


def test_render_draws_the_file_creases_in_orange(tmp_path, monkeypatch, command):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")
    from matplotlib.image import imread

    monkeypatch.chdir(tmp_path)
    v, tris, _ = cube_of_triangles()
    tagged_obj(tmp_path / "tags.obj", v, tris, ["t crease 2/1/0 0 1 10", "t crease 2/1/0 1 3 10"])

    def orange_pixels(png):
        image = imread(png)[:, :, :3]
        return int((np.abs(image - np.array([1.0, 0x7F / 255, 0x0E / 255])).max(axis=2) < 0.08).sum())

    code, stdout, err = command("render", "tags.obj", "-o", "with.png", "--size", "400x320", "--level", "2")
    assert code == 0, err
    code, _, err = command("render", "tags.obj", "-o", "without.png", "--size", "400x320", "--level", "2",
                           "--ignore-tags")
    assert code == 0, err
    assert orange_pixels("with.png") > 50 and orange_pixels("without.png") == 0


def _solves(scheme: str) -> bool:
    """Whether this build's Interpolator takes the scheme (Catmull-Clark arrives with the catmark branch)."""
    import inspect

    return scheme == "loop" or "scheme" in inspect.signature(sorpia.Interpolator).parameters


CATMULL_CLARK = pytest.mark.skipif(not _solves("catmull-clark"), reason="Interpolator takes no scheme= yet")


def quad_torus(nu: int, nv: int):
    """A torus of nu x nv quads (every vertex of valence 4), its vertices moved a little at random."""
    u, w = np.meshgrid(2 * np.pi * np.arange(nu) / nu, 2 * np.pi * np.arange(nv) / nv, indexing="ij")
    r = 1.0 + 0.4 * np.cos(w)
    v = np.column_stack([(r * np.cos(u)).ravel(), (r * np.sin(u)).ravel(), (0.4 * np.sin(w)).ravel()])
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    quads = np.column_stack([(i * nv + j).ravel(), (((i + 1) % nu) * nv + j).ravel(),
                             (((i + 1) % nu) * nv + (j + 1) % nv).ravel(), (i * nv + (j + 1) % nv).ravel()])
    return v + np.random.default_rng(6).normal(0, 0.02, v.shape), quads


@CATMULL_CLARK
def test_fit_solves_a_quad_mesh_with_catmull_clark_by_default(tmp_path, monkeypatch, command):
    # (Not a cube: a cube's Catmull-Clark limit matrix is singular, the vector +1/-1 on alternate vertices
    # gives (9 - 4*3 + 3)/24 = 0, so no interpolating control mesh need exist.)
    monkeypatch.chdir(tmp_path)
    v, quads = quad_torus(8, 6)
    tagged_obj(tmp_path / "q.obj", v, quads, ["t crease 2/1/0 0 1 1.5", "t crease 2/1/0 1 2 10"])
    code, stdout, err = command("fit", "q.obj", "-o", "c.obj", "--report", "r.json")
    assert code == 0, err
    assert json.loads((tmp_path / "r.json").read_text())["scheme"] == "catmull-clark"
    ctrl, f, tags = sorpia.read_mesh("c.obj", tags=True)
    assert np.array_equal(f, quads) and tags["creases"][0].tolist() == [[0, 1], [1, 2]]
    limit = sorpia.limit_points(ctrl, f, scheme="catmull-clark", **tags)
    assert np.abs(limit - v).max() < 1e-9
    code, stdout, err = command("info", "q.obj", "--json")
    assert json.loads(stdout)["pia"] == {"scheme": "catmull-clark", "can_run": True, "reason": None}


# The manifold ones: catmark_fan has edges of 3 faces (test_nonmanifold.py fits it with --nonmanifold sharp).
SHARED = [p for p in sorted((Path(__file__).resolve().parents[2] / "shared" / "meshes").glob("osd_*.obj"))
          if "nonman" not in p.name and p.name != "osd_catmark_fan.obj"]


@pytest.mark.skipif(not SHARED, reason="../shared/meshes is not present")
@pytest.mark.parametrize("path", SHARED or [None], ids=[p.name for p in SHARED] or ["none"])
def test_opensubdiv_shapes_fit_with_their_tags(path, tmp_path, command):
    """Every osd_* shape through `sorpia fit` with its tags: fitted (its limit, with the tags written to the
    control mesh, through the given vertices), or stopped at --max-iter with exit 1 and everything written (the
    car's Catmull-Clark B is singular), or refused with the topology's message (the fan has an edge of 3 faces)."""
    v, f, tags = sorpia.read_mesh(path, tags=True)
    scheme = "loop" if isinstance(f, np.ndarray) and f.shape[1] == 3 else "catmull-clark"
    if not _solves(scheme):
        pytest.skip("Interpolator takes no scheme= yet")
    out = tmp_path / "c.obj"
    code, _, err = command("fit", path, "-o", out, "--quiet", "--report", tmp_path / "r.json", "--max-iter", "300")
    if code == 2:
        assert_user_error(code, err)
        assert "PIA cannot run on this mesh: non-manifold" in err
        return
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["scheme"] == scheme and report["converged"] is (code == 0)
    ctrl, f2, written = sorpia.read_mesh(out, tags=True)
    # The tags as read, and the boundary rule solved with, always written (OpenSubdiv's reader takes edge-only
    # where the line is missing).
    assert written.keys() - {"boundary"} == tags.keys() - {"boundary"}
    assert written["boundary"] == report["boundary"]
    limit = sorpia.limit_points(ctrl, f2, **({} if scheme == "loop" else {"scheme": scheme}), **written)
    diagonal = np.linalg.norm(v.max(axis=0) - v.min(axis=0))
    # The report's check of what was written agrees with limit_points on the file read back (to rounding).
    # max_residual is a row norm, max_i ||(B V)_i - v0_i||, under every scheme (as E_k is).
    assert report["max_residual"] == pytest.approx(np.linalg.norm(limit - v, axis=1).max(), rel=1e-6,
                                                   abs=1e-11 * diagonal)
    if code == 0:
        assert np.abs(limit - v).max() < 1e-9 * diagonal


def test_info_explains_a_crease_that_is_not_an_edge(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, tris, _ = cube_of_triangles()
    tagged_obj(tmp_path / "bad.obj", v, tris, ["t crease 2/1/0 0 7 10"])  # opposite corners of the cube
    with pytest.raises(sorpia.MeshError) as refused:
        sorpia.Interpolator(tris, len(v), creases=([[0, 7]], 10.0))
    code, stdout, err = command("info", "bad.obj", "--json")
    assert code == 0, err
    assert json.loads(stdout)["pia"] == {"scheme": "loop", "can_run": False, "reason": str(refused.value)}
    code, _, err = command("fit", "bad.obj", "-o", "c.obj")
    assert_user_error(code, err)
    assert str(refused.value) in err and "Loop PIA cannot run on this mesh" in err


def test_info_counts_a_quad_mesh_as_catmull_clark_sees_it(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, quads = quad_torus(8, 6)
    open_quads = quads[quads.max(axis=1) < 6 * 7]  # drop the faces of the last ring of the torus: an open tube
    for name, faces in (("torus.obj", quads), ("tube.obj", open_quads)):
        tagged_obj(tmp_path / name, v, faces, [])
        code, stdout, err = command("info", name, "--json")
        assert code == 0, err
        info = json.loads(stdout)
        # Independent counts from the face list: edges, Euler characteristic, valences.
        edges = {tuple(sorted(e)) for f in faces.tolist() for e in zip(f, f[1:] + f[:1])}
        used = np.unique(faces)
        sides = np.zeros(len(v), int)
        for a, b in edges:
            sides[a] += 1
            sides[b] += 1
        assert info["faces"] == len(faces) and info["edges"] == len(edges)
        assert info["euler_characteristic"] == len(used) - len(edges) + len(faces)
        assert info["genus"] == (1 if name == "torus.obj" else 0)  # a torus; a tube (chi 0, 2 boundary loops)
        assert info["boundary_loops"] == (0 if name == "torus.obj" else 2)
        # Regular under Catmull-Clark: valence 4 inside, 3 on the boundary; every vertex here is regular.
        assert info["regular_valence"] == [4, 3] and info["extraordinary_vertices"] == 0
        assert sorted(set(sides[used])) == ([4] if name == "torus.obj" else [3, 4])


@CATMULL_CLARK
def test_demo_with_catmull_clark_fits_its_quad_sample(tmp_path, command):
    code, stdout, err = command("demo", "--scheme", "catmull-clark", "--out", tmp_path / "d", "--quiet")
    assert code == 0, err
    v, f = sorpia.read_mesh(tmp_path / "d" / "sample.obj")
    assert f.shape[1] == 4
    report = json.loads((tmp_path / "d" / "fit-report.json").read_text())
    assert report["scheme"] == "catmull-clark" and report["converged"]
    ctrl, _ = sorpia.read_mesh(tmp_path / "d" / "control.obj")
    assert np.abs(sorpia.limit_points(ctrl, f, scheme="catmull-clark") - v).max() < 1e-9
