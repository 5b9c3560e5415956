"""`sorpia fit --fair` and `sorpia render --fair` run in-process: the fine
cage written is read back (with its tags) and checked through the fine
mesh's limit points; bad options are refused with one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sorpia

from cli_support import assert_user_error


def creased_quad_file(tmp_path):
    """A noisy quad grid with a semi-sharp crease line, written as OBJ with its 't crease' tags."""
    v, f = sorpia.shapes.quad_grid(6, 5)
    v = np.asarray(v, float)
    v[:, 2] = 0.1 * np.sin(4 * v[:, 0]) + 0.02 * np.random.default_rng(2).standard_normal(len(v))
    f = np.asarray(f)
    path = tmp_path / "creased.obj"
    sorpia.write_mesh(path, v, f, creases=(np.array([(f[k][1], f[k][2]) for k in (6, 7, 8)]), 1.5))
    return path, v, f


def test_fit_fair_writes_the_fine_cage_with_its_tags(tmp_path, command, monkeypatch):
    # The fine cage as written (OBJ, with the carried crease tags) has the
    # library's result's faces and tags, and its limit surface (read back,
    # tags from the file) passes through the given vertices: 1e-10 of the
    # size, the float64 round trip included.
    monkeypatch.chdir(tmp_path)
    src, v, f = creased_quad_file(tmp_path)
    out, report = tmp_path / "fair.obj", tmp_path / "fair.json"
    code, stdout, err = command("fit", src, "-o", out, "--fair", "--report", report)
    assert code == 0, err
    ref = sorpia.fair_interpolate(v, f, scheme="catmull-clark", tol=1e-10,
                                  creases=(np.array([(f[k][1], f[k][2]) for k in (6, 7, 8)]), 1.5))
    vc, fc, tags = sorpia.read_mesh(out, tags=True)
    np.testing.assert_array_equal(np.asarray(fc), ref.faces)
    assert tags["boundary"] == "edge-and-corner"
    edges, sharpness = tags["creases"]
    np.testing.assert_array_equal(np.sort(np.sort(edges, axis=1), axis=0),
                                  np.sort(np.sort(ref.creases[0], axis=1), axis=0))
    assert np.allclose(sharpness, 0.5, atol=1e-6)  # 1.5 decayed by one level
    hit = sorpia.limit_points(vc, fc, scheme="catmull-clark", **tags)[:len(v)]
    diag = np.linalg.norm(v.max(axis=0) - v.min(axis=0))
    assert np.abs(hit - v).max() <= 1e-10 * diag
    data = json.loads(report.read_text())
    assert data["fair"] is True and data["levels"] == 1 and data["targets"]["count"] == len(v)
    assert data["fine_mesh"] == {"vertices": len(ref.control_vertices), "faces": len(ref.faces), "face_kind": "quads"}
    assert data["energy"] == pytest.approx(ref.energy, rel=1e-9)
    assert data["energy"] <= data["plain_energy"]
    assert data["max_residual_relative"] <= 1e-12
    assert "ratio" in stdout and str(out) in stdout


def test_fit_fair_with_targets_levels_and_membrane(torus_file, tmp_path, command):
    # --targets FILE (comments, commas) and --levels 2 --membrane 0.5: the
    # listed vertices are met, the report counts them, the faces are two levels finer.
    src, v, f = torus_file
    targets = tmp_path / "targets.txt"
    targets.write_text("# every third vertex\n" + ", ".join(str(i) for i in range(0, len(v), 3)) + "\n")
    out, surf = tmp_path / "fair.obj", tmp_path / "surf.ply"
    code, _, err = command("fit", src, "-o", out, "--fair", "--targets", targets, "--levels", 2, "--membrane", 0.5,
                           "--surface", surf, "--level", 1, "-q")
    assert code == 0, err
    vc, fc = sorpia.read_mesh(out)
    assert len(fc) == len(f) * 16
    hit = sorpia.limit_points(vc, fc)[:len(v)]
    chosen = np.arange(0, len(v), 3)
    assert np.abs(hit[chosen] - v[chosen]).max() <= 1e-10 * np.linalg.norm(v.max(axis=0) - v.min(axis=0))
    assert np.abs(hit - v).max() > 1e-6  # the others are free
    _, fs = sorpia.read_mesh(surf)
    assert len(fs) == len(fc) * 4


@pytest.mark.parametrize("args, message", [
    (("--levels", 2), "--levels applies to fair interpolation only"),
    (("--membrane", 1), "--membrane applies to fair interpolation only"),
    (("--fair", "--method", "sor"), "--method cannot go with --fair"),
    (("--fair", "--keep-unconverged"), "--keep-unconverged cannot go with --fair"),
    (("--fair", "--membrane", "-1"), "membrane = -1.0 is negative"),
])
def test_fit_fair_refuses_options_that_do_not_apply(torus_file, tmp_path, command, args, message):
    src, _, _ = torus_file
    code, _, err = command("fit", src, "-o", tmp_path / "x.obj", *args)
    assert_user_error(code, err)
    assert message in err
    assert not (tmp_path / "x.obj").exists()


# The command line parses the file (a word that is no index: named with its line); the values are the library's
# to check, named with the file they came from.
@pytest.mark.parametrize("text, message", [
    ("1 2 x\n", "line 1: 'x' is not a vertex index"),
    ("1\n\n5 1\n", "t.txt: targets[2] = 1 repeats targets[0]"),
    ("# nothing\n", "t.txt: targets is empty"),
    ("0 100000\n", "t.txt: targets[1] = 100000 is out of range [0, "),
    ("0 99999999999999999999999\n", "t.txt: targets[1] = 2147483647 is out of range [0, "),
])
def test_a_bad_targets_file_is_refused_with_its_name(torus_file, tmp_path, command, text, message):
    src, _, _ = torus_file
    targets = tmp_path / "t.txt"
    targets.write_text(text)
    code, _, err = command("fit", src, "-o", tmp_path / "x.obj", "--fair", "--targets", targets)
    assert_user_error(code, err)
    assert message in err


def test_render_fair_draws_plain_and_fair(torus_file, tmp_path, command):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")
    src, _, _ = torus_file
    png = tmp_path / "fair.png"
    code, stdout, err = command("render", src, "-o", png, "--fair", "--level", 1, "--size", "400x300")
    assert code == 0, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "thin-plate energy" in stdout
    code, _, err = command("render", src, "-o", png, "--levels", 2, "--force")
    assert_user_error(code, err)


def test_fit_fair_says_the_inputs_texture_coordinates_are_not_written(tmp_path, command):
    """The fine cage has refined faces and fit --fair does not refine face-varying data: the input's UVs are
    named as not written (a warning), never dropped silently; plain fit writes them."""
    v, f = sorpia.shapes.quad_torus(8, 6)
    corners = np.ascontiguousarray(f.reshape(-1), dtype=np.int32)
    src = tmp_path / "textured.obj"
    sorpia.write_mesh(src, v, f, uvs=sorpia.FaceVarying(v[:, :2], corners))
    code, _, err = command("fit", src, "-o", tmp_path / "fair.obj", "--fair")
    assert code == 0 and "texture coordinates are not written" in err
    assert "uvs" not in sorpia.read_mesh(tmp_path / "fair.obj", attributes=True)[2]
    code, _, err = command("fit", src, "-o", tmp_path / "plain.obj")
    assert code == 0 and "texture coordinates" not in err
    assert "uvs" in sorpia.read_mesh(tmp_path / "plain.obj", attributes=True)[2]
