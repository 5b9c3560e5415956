"""`sorpia demo` run in-process, with and without matplotlib."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import sorpia

from cli_support import assert_user_error


def test_demo_writes_everything_in_a_new_folder(tmp_path, monkeypatch, command):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (pip install 'sorpia[plot]')")
    from matplotlib.image import imread

    monkeypatch.chdir(tmp_path)
    code, stdout, err = command("demo")
    assert code == 0, err
    (folder,) = [p for p in tmp_path.iterdir() if p.name.startswith("sorpia-demo")]
    # Every capability: interpolation (fit, compare, render), fair interpolation and approximation, each with
    # its picture.
    names = {"sample.obj", "control.obj", "surface.obj", "fit-report.json", "table.md", "table.csv",
             "compare.json", "convergence.png", "figure3.png", "fair.obj", "fair-report.json", "fair.png",
             "cage.obj", "approximation.obj", "approximation-report.json", "approximation.png"}
    assert {p.name for p in folder.iterdir()} == names
    for n in names:
        assert n in stdout
    V0, F = sorpia.read_mesh(folder / "sample.obj")
    Vc, _ = sorpia.read_mesh(folder / "control.obj")
    assert np.abs(sorpia.limit_matrix(F, len(V0)) @ Vc - V0).max() < 1e-9
    for png in ("figure3.png", "fair.png", "approximation.png"):
        assert imread(folder / png).shape[:2] == (1000, 1200)
    assert json.loads((folder / "fit-report.json").read_text())["converged"] is True
    # the fair cage, read back with its tags, passes through the sample's vertices (1e-9 of its size)
    Vf, Ff, tags = sorpia.read_mesh(folder / "fair.obj", tags=True)
    assert np.abs(sorpia.limit_points(Vf, Ff, **tags)[:len(V0)] - V0).max() < 1e-9
    # the approximation: the decimated cage's faces, fitted closer to the data than the cage as given
    approx = json.loads((folder / "approximation-report.json").read_text())
    cage_v, cage_f = sorpia.read_mesh(folder / "cage.obj")
    fitted_v, fitted_f = sorpia.read_mesh(folder / "approximation.obj")
    np.testing.assert_array_equal(fitted_f, cage_f)
    assert approx["final"]["rms"] < approx["history"][0]["rms"]


def test_without_matplotlib_figures_are_refused_and_the_rest_runs(torus_file, tmp_path, monkeypatch, command):
    # None in sys.modules makes `import matplotlib` raise ImportError, as when it is not installed.
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    src, _, _ = torus_file
    code, _, err = command("render", src, "-o", tmp_path / "f.png")
    assert_user_error(code, err)
    assert "pip install matplotlib" in err and not (tmp_path / "f.png").exists()
    code, _, err = command("compare", src, "--methods", "sor", "--plot", tmp_path / "p.png")
    assert_user_error(code, err)
    assert command("fit", src, "-o", tmp_path / "c.obj", "-q")[0] == 0
    code, stdout, err = command("demo", "--out", tmp_path / "d")
    assert code == 0, err
    assert "no figures" in stdout
    written = {p.name for p in (tmp_path / "d").iterdir()}
    assert "control.obj" in written and "table.md" in written and not any(n.endswith(".png") for n in written)
