"""`sorpia fit` run in-process: the control mesh it writes is read back and
checked against the Python API and an independent limit matrix."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

import sorpia

from cli_support import assert_user_error


def test_fit_writes_a_control_mesh_that_interpolates_the_file(mesh_file, tmp_path, command):
    name, src, V0, F = mesh_file
    before = src.read_bytes()
    out, surf, report = tmp_path / "ctrl.obj", tmp_path / "surf.obj", tmp_path / "report.json"
    level = 1
    code, stdout, err = command("fit", src, "-o", out, "--surface", surf, "--level", level, "--report", report)
    assert code == 0, err
    assert src.read_bytes() == before  # the input is only read

    Vc, Fc = sorpia.read_mesh(out)
    np.testing.assert_array_equal(Fc, F)  # same faces, same vertex order
    # B V_ctrl = V0 up to tol 1e-10 relative to E_0 (about the shrinkage,
    # < 1 on these unit-size meshes) plus exact float64 file round trips:
    # 1e-9 absolute leaves a margin of 10 at least.
    B = sorpia.limit_matrix(F, len(V0))
    assert np.abs(B @ Vc - V0).max() < 1e-9

    Vs, Fs = sorpia.read_mesh(surf)
    assert len(Fs) == len(F) * 4 ** level

    data = json.loads(report.read_text())
    ref = sorpia.interpolate(V0, F)  # the same run through the Python API
    assert data["method"] == "auto" and data["converged"] is True
    # An ordinary mesh: auto's sor run makes the result, nothing else is tried.
    assert data["variant"] == "sor" and data["stop_reason"] == "converged"
    assert [a["method"] for a in data["attempts"]] == ["sor"]
    assert data["iterations"] == ref.iterations == len(data["history"]) - 1
    np.testing.assert_allclose(data["history"], ref.history, rtol=1e-9, atol=1e-15)
    assert data["omega"] == pytest.approx(ref.omega, rel=1e-12)
    assert data["history"][-1] < 1e-10 <= data["history"][-2]  # the paper's stopping rule
    assert data["mesh"]["vertices"] == len(V0) and data["mesh"]["faces"] == len(F)
    # The check is computed independently of the solver; against scipy's B V - V0 it agrees to rounding.
    assert data["max_residual"] == pytest.approx(np.linalg.norm(B @ Vc - V0, axis=1).max(), abs=1e-13)
    for phase in ("read", "statistics", "fit", "write", "surface", "check"):
        assert data["timings"][phase] >= 0
    assert set(ref.timings) == {k[4:] for k in data["timings"] if k.startswith("fit.")}
    # The summary names the figures a user looks for.
    assert f"converged in {ref.iterations} iterations" in stdout
    assert str(out) in stdout


def test_fit_quiet_prints_nothing(torus_file, tmp_path, command):
    src, _, _ = torus_file
    assert command("fit", src, "-o", tmp_path / "c.ply", "--quiet") == (0, "", "")


def test_fit_not_converged_exits_1_and_writes_only_when_asked(torus_file, tmp_path, command):
    src, V0, F = torus_file
    out, report = tmp_path / "ctrl.off", tmp_path / "r.json"
    code, stdout, err = command("fit", src, "-o", out, "--method", "pia", "--max-iter", 3, "--report", report)
    assert code == 1, err
    assert "NOT converged (max_iter)" in stdout and "Traceback" not in err
    assert "--keep-unconverged" in stdout and not out.exists()
    data = json.loads(report.read_text())
    assert data["converged"] is False and data["iterations"] == 3 and len(data["history"]) == 4
    assert data["stop_reason"] == "max_iter" and data["recommended"] == "gmres" and data["not_written"] == [str(out)]
    code, stdout, err = command("fit", src, "-o", out, "--method", "pia", "--max-iter", 3, "--keep-unconverged")
    assert code == 1, err
    Vc, _ = sorpia.read_mesh(out)
    # Three PIA steps from V0 (paper eq. 9), computed independently with B.
    B = sorpia.limit_matrix(F, len(V0))
    V = V0.copy()
    for _ in range(3):
        V = V + (V0 - B @ V)
    np.testing.assert_allclose(Vc, V, rtol=0, atol=1e-12)


def test_polygons_are_refused_by_loop_unless_triangulate(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    # Two quads of a strip, by hand: OBJ faces of 4 vertices.
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0.5], [2, 1, 0.5]], dtype=float)
    src = tmp_path / "quads.obj"
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist()) + "f 1 2 3 4\nf 2 5 6 3\n")
    code, _, err = command("fit", src, "-o", tmp_path / "c.ply", "--scheme", "loop")
    assert_user_error(code, err)
    assert "face 0 has 4 vertices and Loop subdivision needs triangles" in err
    assert "--triangulate" in err and "--scheme catmull-clark" in err
    code, stdout, err = command("info", src, "--json")
    assert code == 0, err
    described = json.loads(stdout)
    verdict = described["loop_pia"]
    assert verdict["can_run"] is False and "--triangulate" in verdict["reason"]
    assert described["scheme"] == "catmull-clark" and described["face_sizes"] == {"4": 2}
    # Under Catmull-Clark the two quads are counted as they are (6 vertices, 2 faces, 7 edges); with
    # --triangulate the 4 triangles (9 edges), and nothing stands in the way of a Loop fit.
    assert described["triangulated"] is False and (described["faces"], described["edges"]) == (2, 7)
    code, stdout, err = command("info", src, "--json", "--triangulate")
    assert code == 0, err
    described_t = json.loads(stdout)
    assert described_t["triangulated"] is True and (described_t["faces"], described_t["edges"]) == (4, 9)
    assert described_t["loop_pia"]["can_run"] is True and described_t["scheme"] == "loop"
    # --scheme loop without --triangulate: counted as the triangulation, the verdict the refusal
    code, stdout, err = command("info", src, "--json", "--scheme", "loop")
    described_l = json.loads(stdout)
    assert described_l["triangulated"] is True and described_l["edges"] == 9
    assert described_l["pia"]["can_run"] is False and "--triangulate" in described_l["pia"]["reason"]

    out = tmp_path / "c.ply"
    assert command("fit", src, "-o", out, "--triangulate", "--binary", "--quiet")[0] == 0
    assert out.read_bytes().startswith(b"ply\nformat binary_little_endian")
    Vc, Fc = sorpia.read_mesh(out)
    # Fans from each polygon's first vertex: (0,1,2), (0,2,3) and (1,4,5), (1,5,2).
    np.testing.assert_array_equal(Fc, [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    assert np.abs(sorpia.limit_matrix(Fc, len(V)) @ Vc - V).max() < 1e-9


def test_force_overwrites_the_input(torus_file, command):
    src, V0, F = torus_file
    code, _, err = command("fit", src, "-o", src, "--force", "--quiet")
    assert code == 0, err
    Vc, _ = sorpia.read_mesh(src)
    assert np.abs(sorpia.limit_matrix(F, len(V0)) @ Vc - V0).max() < 1e-9


def _link(kind: str, src: Path, tmp_path: Path) -> tuple[Path, Path]:
    """(input, output) naming one file through a link made as `kind` says."""
    (tmp_path / "sub").mkdir()
    links = {
        "symlink": (src, tmp_path / "link.obj", src.name),
        "symlink-absolute": (src, tmp_path / "link.obj", src.resolve()),
        "symlink-other-folder": (src, tmp_path / "sub" / "link.obj", Path("..") / src.name),
        "input-is-the-symlink": (tmp_path / "link.obj", src, src.name),
    }
    if kind == "hard-link":
        os.link(src, tmp_path / "sub" / "hard.obj")
        return src, tmp_path / "sub" / "hard.obj"
    inp, out, target = links[kind]
    link = out if inp == src else inp
    try:
        os.symlink(target, link)
    except (OSError, NotImplementedError) as exc:  # Windows without the privilege
        pytest.skip(f"cannot make a symlink here: {exc}")
    return inp, out


@pytest.mark.parametrize("kind", ["symlink", "symlink-absolute", "symlink-other-folder", "input-is-the-symlink",
                                  "hard-link"])
def test_output_that_is_the_input_through_a_link_is_refused(kind, torus_file, tmp_path, command):
    # -o naming the input file by another path (a link) is refused as -o equal to the input is:
    # exit 2, one line naming the option and the path, and the file keeps its bytes.
    src, V0, F = torus_file
    before = src.read_bytes()
    inp, out = _link(kind, src, tmp_path)
    code, _, err = command("fit", inp, "-o", out, "--quiet")
    assert_user_error(code, err)
    assert err.strip().splitlines() == [f"sorpia: error: -o {out} is the input file: refusing to overwrite it "
                                        f"(pass --force to do so)"]
    assert src.read_bytes() == before
    assert not [p for p in tmp_path.rglob("*") if ".sorpia-tmp" in p.name]  # refused before any write


def test_force_through_a_symlink_writes_the_output_path(torus_file, tmp_path, command):
    # With --force the control mesh is written to the -o path. The write is atomic (a temporary
    # file renamed over the path), so the rename replaces the symlink itself: -o then reads back
    # the control mesh and the file the link pointed to keeps its bytes.
    src, V0, F = torus_file
    before = src.read_bytes()
    inp, out = _link("symlink", src, tmp_path)
    code, _, err = command("fit", inp, "-o", out, "--force", "--quiet")
    assert code == 0, err
    Vc, _ = sorpia.read_mesh(out)
    assert np.abs(sorpia.limit_matrix(F, len(V0)) @ Vc - V0).max() < 1e-9  # B Vc = V0 to the solver's tol
    assert not out.is_symlink() and src.read_bytes() == before


def test_fit_threads_agrees_with_one_thread(torus_file, tmp_path, command):
    src, V0, F = torus_file
    ctrl, reports = {}, {}
    for n in (1, 2):
        out, report = tmp_path / f"c{n}.obj", tmp_path / f"r{n}.json"
        code, _, err = command("fit", src, "-o", out, "--threads", n, "--report", report, "--quiet")
        assert code == 0, err
        ctrl[n], _ = sorpia.read_mesh(out)
        reports[n] = json.loads(report.read_text())
        assert reports[n]["threads"] == n
    # Two threads sweep the vertices in another order (index ranges, then the
    # shared vertices): both stop at E_k/E_0 < 1e-10, so the control vertices
    # agree to about that relative to their size; 1e-8 leaves a margin of 100.
    scale = np.abs(ctrl[1]).max()
    assert np.abs(ctrl[2] - ctrl[1]).max() < 1e-8 * scale
    # Iteration counts within 15% (solve.py: "within a few percent").
    assert abs(reports[2]["iterations"] - reports[1]["iterations"]) <= 0.15 * reports[1]["iterations"]


@pytest.mark.parametrize("scheme, mesh", [("loop", sorpia.shapes.torus(8, 6)), ("catmull-clark", None)])
def test_surface_memory_check_counts_the_scheme_s_faces(scheme, mesh, tmp_path, command, monkeypatch):
    """--surface is refused before the solve when the tessellation would not fit; the face count in the
    message is the count limit_surface produces at that level (quads for Catmull-Clark, including a
    pentagon's five at level 1), not the triangle count."""
    if mesh is None:  # a quad strip with a pentagon: mixed polygons under Catmull-Clark
        V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0], [2.5, 0.5, 0]], float)
        F = sorpia.Polygons(np.array([4, 5]), np.array([0, 1, 4, 3, 1, 2, 6, 5, 4]))
    else:
        V, F = mesh
    src = tmp_path / "in.obj"
    sorpia.write_mesh(src, V, F)
    level = 2
    expected = len(sorpia.limit_surface(V, F, level=level, scheme=scheme)[1])
    monkeypatch.setattr(sorpia._core, "available_memory_bytes", lambda: 1)
    code, _, err = command("fit", src, "-o", tmp_path / "c.obj", "--surface", tmp_path / "s.obj", "--level",
                           level, "--scheme", scheme)
    assert code != 0
    assert "is left to this process" in err
    assert f"({expected} " in err
    assert not (tmp_path / "c.obj").exists()  # refused before the solve
