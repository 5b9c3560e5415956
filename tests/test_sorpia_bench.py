"""The sorpia-bench executable's interface (not its speed: timings live in
bench/)."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest

import sorpia

from conftest import installed_script


@pytest.fixture
def sorpia_bench():
    exe = installed_script("sorpia-bench") or shutil.which("sorpia-bench")
    if exe is None:
        pytest.skip("sorpia-bench is not installed next to this Python")
    return exe


def test_bench_bad_arguments_print_usage_and_exit_2(sorpia_bench):
    for args in (["--bogus", "grid:4x4"], [], ["grid:4x4", "--method", "nope"], ["grid:4x4", "--repeat", "0"],
                 ["icosphere:11"], ["cube:3"]):
        out = subprocess.run([sorpia_bench, *args], capture_output=True, text=True)
        assert out.returncode == 2, args
        assert "usage: sorpia-bench" in out.stderr, args


def test_bench_json_reports_the_mesh_and_a_converged_solve(sorpia_bench):
    out = subprocess.run([sorpia_bench, "grid:6x5", "pole:9", "--method", "sor,none", "--json"],
                         capture_output=True, text=True, check=True)
    report = json.loads(out.stdout)
    meshes = {m["mesh"]: m for m in report["meshes"]}
    assert meshes["grid:6x5"]["n_vertices"] == 30 and meshes["pole:9"]["n_vertices"] == 19
    for m in meshes.values():
        (sor,) = m["methods"]
        assert sor["method"] == "sor" and sor["stop"] == "converged"
        assert sor["final_error"] < 1e-10  # the default tol
        assert m["topology"] >= 0 and m["operator"] >= 0 and m["peak_rss_bytes"] > 0


def test_bench_writes_control_vertices_that_interpolate(sorpia_bench, tmp_path):
    subprocess.run([sorpia_bench, "grid:6x5", "--write", str(tmp_path), "--format", "obj"],
                   capture_output=True, text=True, check=True)
    V, F = sorpia.read_mesh(tmp_path / "grid_6x5.sor.obj")
    V0, F0 = sorpia.shapes.grid(6, 5)
    np.testing.assert_array_equal(F, F0)
    # B V reproduces the grid's vertices: E_k/E_0 < 1e-10 with E_0 of order
    # 0.1 here, and OBJ keeps every digit.
    np.testing.assert_allclose(sorpia.limit_points(V, F), V0, atol=1e-10)


def test_bench_times_fair_interpolation_and_approximation(sorpia_bench):
    # --task fair and --task approximate run the core's pipelines (sorpia::fair_interpolate, sorpia::approximate)
    # and report each phase; the figures are the pipelines' own: fair interpolation meets its targets to rounding
    # and bends less than the plain surface, approximation lowers the RMS distance of the cage as decimated.
    fair = json.loads(subprocess.run([sorpia_bench, "--task", "fair", "irregular:300", "--json"],
                                     capture_output=True, text=True, check=True).stdout)
    assert fair["task"] == "fair"
    (m,) = fair["meshes"]
    assert all(m[phase] >= 0 for phase in ("build", "plain", "refine", "energy", "setup", "solve", "total"))
    assert int(m["fine_vertices"]) > int(m["vertices"]) and m["stop"] == "converged"
    assert float(m["max_error"]) < 1e-12 and float(m["energy_over_plain"]) < 1
    approx = json.loads(subprocess.run([sorpia_bench, "--task", "approximate", "icosphere:4", "--cage-vertices", "60",
                                        "--iterations", "3", "--json"], capture_output=True, text=True,
                                       check=True).stdout)
    (a,) = approx["meshes"]
    assert all(a[phase] >= 0 for phase in ("cage", "surface", "footpoints", "rows", "normal", "solve", "report"))
    assert int(a["points"]) == 2562 and int(a["cage_vertices"]) == 60
    assert float(a["rms"]) < float(a["rms_start"]) and 1 <= int(a["iterations"]) <= 3
    out = subprocess.run([sorpia_bench, "--task", "nothing", "grid:6x5"], capture_output=True, text=True)
    assert out.returncode == 2 and "--task: interpolate, fair or approximate" in out.stderr
