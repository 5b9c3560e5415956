"""The `sorpia` command driven as a user drives it: subprocesses of
`python -m sorpia` and of the installed `sorpia` script, on mesh files written
into tmp_path; the files it writes are read back and checked against the
Python API and against independent computations."""

from __future__ import annotations

import csv
import io
import json
import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import numpy as np
import pytest

import sorpia
from sorpia import cli

from conftest import installed_script

TOLERANCE_HEADERS = [f"1e-{j}" for j in range(1, 11)]


def run(*args, cwd, script=False, timeout=300, env=None):
    """Run the command; returns the CompletedProcess (text)."""
    exe = [str(_script())] if script else [sys.executable, "-m", "sorpia"]
    return subprocess.run([*exe, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env=None if env is None else {**os.environ, **env})


def _script() -> Path:
    path = installed_script("sorpia")
    if path is None:
        pytest.skip(f"the sorpia script is not installed next to this Python ({sysconfig.get_path('scripts')})")
    return path


def write_obj(path: Path, vertices, faces) -> Path:
    """An OBJ file written by hand, every float with 17 significant digits
    (repr), so the file holds exactly the float64 vertices the test compares."""
    lines = ["# written by tests/test_cli.py"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=float).tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(faces).tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path


def assert_user_error(proc):
    """Exit code 2, a message on stderr naming the problem, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stderr
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith("sorpia") and "error:" in last, proc.stderr


# Two inputs: closed with valences 3 to 12 (most vertices extraordinary), and
# open with a boundary and two one-face corners.
MESHES = {
    "irregular-torus": lambda: sorpia.shapes.irregular(300, seed=5),
    "grid-boundary": lambda: sorpia.shapes.grid(8, 7),
}


@pytest.fixture(params=sorted(MESHES))
def mesh_file(request, tmp_path):
    V, F = MESHES[request.param]()
    return request.param, write_obj(tmp_path / f"{request.param}.obj", V, F), np.asarray(V), np.asarray(F)


@pytest.fixture
def torus_file(tmp_path):
    V, F = MESHES["irregular-torus"]()
    return write_obj(tmp_path / "torus.obj", V, F), np.asarray(V), np.asarray(F)


def test_help_explains_every_option_with_its_default(tmp_path):
    parser = cli.build_parser()
    subparsers = next(a for a in parser._actions if a.dest == "command").choices
    top = run("--help", cwd=tmp_path)
    assert top.returncode == 0
    for name, sub in subparsers.items():
        assert name in top.stdout
        # A wide terminal, so that argparse does not break 'edge-and-corner' at a hyphen.
        proc = run(name, "--help", cwd=tmp_path, env={"COLUMNS": "400"})
        assert proc.returncode == 0, proc.stderr
        text = " ".join(proc.stdout.split())
        for action in sub._actions:
            if not action.option_strings or action.dest == "help":
                continue
            assert action.option_strings[-1] in text, (name, action.option_strings)
            assert action.help, (name, action.option_strings)
            if action.default not in (None, False):
                shown = action.default if isinstance(action.default, str) else repr(action.default)
                assert f"(default: {shown})" in text, (name, action.option_strings, shown)
        assert "exit codes" in text


def test_script_and_module_are_the_same_program(tmp_path):
    by_script = run("--version", cwd=tmp_path, script=True)
    by_module = run("--version", cwd=tmp_path)
    assert by_script.returncode == by_module.returncode == 0
    assert by_script.stdout == by_module.stdout == f"sorpia {sorpia.__version__}\n"


def test_fit_writes_a_control_mesh_that_interpolates_the_file(mesh_file, tmp_path):
    name, src, V0, F = mesh_file
    before = src.read_bytes()
    out, surf, report = tmp_path / "ctrl.obj", tmp_path / "surf.obj", tmp_path / "report.json"
    level = 1
    proc = run("fit", src, "-o", out, "--surface", surf, "--level", level, "--report", report, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
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
    assert data["method"] == "sor" and data["converged"] is True
    assert data["iterations"] == ref.iterations == len(data["errors"]) - 1
    np.testing.assert_allclose(data["errors"], ref.errors, rtol=1e-9, atol=1e-15)
    assert data["omega"] == pytest.approx(ref.omega, rel=1e-12)
    assert data["errors"][-1] < 1e-10 <= data["errors"][-2]  # the paper's stopping rule
    assert data["mesh"]["vertices"] == len(V0) and data["mesh"]["faces"] == len(F)
    assert data["max_residual"] == pytest.approx(np.linalg.norm(B @ Vc - V0, axis=1).max(), abs=1e-13)
    for phase in ("read", "fit", "write", "surface"):
        assert data["timings"][phase] >= 0
    # The summary names the figures a user looks for.
    assert f"converged in {ref.iterations} iterations" in proc.stdout
    assert str(out) in proc.stdout


def test_fit_quiet_prints_nothing(torus_file, tmp_path):
    src, _, _ = torus_file
    proc = run("fit", src, "-o", tmp_path / "c.ply", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0
    assert proc.stdout == "" and proc.stderr == ""


def test_fit_not_converged_exits_1_and_still_writes(torus_file, tmp_path):
    src, V0, F = torus_file
    out, report = tmp_path / "ctrl.off", tmp_path / "r.json"
    proc = run("fit", src, "-o", out, "--method", "pia", "--max-iter", 3, "--report", report, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    assert "NOT converged" in proc.stdout and "Traceback" not in proc.stderr
    data = json.loads(report.read_text())
    assert data["converged"] is False and data["iterations"] == 3 and len(data["errors"]) == 4
    Vc, _ = sorpia.read_mesh(out)
    # Three PIA steps from V0 (paper eq. 9), computed independently with B.
    B = sorpia.limit_matrix(F, len(V0))
    V = V0.copy()
    for _ in range(3):
        V = V + (V0 - B @ V)
    np.testing.assert_allclose(Vc, V, rtol=0, atol=1e-12)


@pytest.mark.parametrize("case", ["missing-file", "output-is-input", "output-is-input-other-spelling",
                                  "omega-out-of-range", "omega-not-a-number", "unknown-method",
                                  "unknown-output-format", "missing-folder", "non-manifold", "garbage-file"])
def test_bad_input_exits_2_with_one_line(case, torus_file, tmp_path):
    src, V0, F = torus_file
    before = src.read_bytes()
    out = tmp_path / "ctrl.obj"
    args = {
        "missing-file": ["fit", tmp_path / "nope.obj", "-o", out],
        "output-is-input": ["fit", src, "-o", src],
        "output-is-input-other-spelling": ["fit", src, "-o", f"./{src.name}"],
        "omega-out-of-range": ["fit", src, "-o", out, "--omega", "2.5"],
        "omega-not-a-number": ["fit", src, "-o", out, "--omega", "fast"],
        "unknown-method": ["compare", src, "--methods", "sor,newton"],
        "unknown-output-format": ["fit", src, "-o", tmp_path / "ctrl.xyz"],
        "missing-folder": ["fit", src, "-o", tmp_path / "no" / "ctrl.obj"],
        "non-manifold": ["fit", write_obj(tmp_path / "nm.obj", np.eye(4, 3),
                                          [[0, 1, 2], [0, 1, 3], [1, 0, 2]]), "-o", out],
        "garbage-file": ["info", tmp_path / "junk.obj"],
    }[case]
    (tmp_path / "junk.obj").write_bytes(b"v 1 2\nf 1 2 3 x\n\x00\xff")
    proc = run(*args, cwd=tmp_path)
    assert_user_error(proc)
    assert src.read_bytes() == before
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]  # no temporary file left


def test_polygons_are_refused_unless_triangulate(tmp_path):
    # Two quads of a strip, by hand: OBJ faces of 4 vertices.
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0.5], [2, 1, 0.5]], dtype=float)
    src = tmp_path / "quads.obj"
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist()) + "f 1 2 3 4\nf 2 5 6 3\n")
    refused = run("fit", src, "-o", tmp_path / "c.ply", cwd=tmp_path)
    assert_user_error(refused)
    assert "--triangulate" in refused.stderr
    info = run("info", src, "--json", cwd=tmp_path)
    assert info.returncode == 0, info.stderr
    described = json.loads(info.stdout)
    verdict = described["loop_pia"]
    assert verdict["can_run"] is False and "--triangulate" in verdict["reason"]
    # With --triangulate the same fan triangulation is described (one read
    # either way), and nothing stands in the way of a fit.
    info_t = run("info", src, "--json", "--triangulate", cwd=tmp_path)
    assert info_t.returncode == 0, info_t.stderr
    described_t = json.loads(info_t.stdout)
    assert described["triangulated"] is True and described_t["triangulated"] is True
    assert described_t["loop_pia"]["can_run"] is True
    for key in ("vertices", "faces", "edges"):
        assert described[key] == described_t[key], key

    out = tmp_path / "c.ply"
    done = run("fit", src, "-o", out, "--triangulate", "--binary", "--quiet", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert out.read_bytes().startswith(b"ply\nformat binary_little_endian")
    Vc, Fc = sorpia.read_mesh(out)
    # Fans from each polygon's first vertex: (0,1,2), (0,2,3) and (1,4,5), (1,5,2).
    np.testing.assert_array_equal(Fc, [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    assert np.abs(sorpia.limit_matrix(Fc, len(V)) @ Vc - V).max() < 1e-9


def test_force_overwrites_the_input(torus_file, tmp_path):
    src, V0, F = torus_file
    proc = run("fit", src, "-o", src, "--force", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
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
def test_output_that_is_the_input_through_a_link_is_refused(kind, torus_file, tmp_path):
    # -o naming the input file by another path (a link) is refused as -o equal to the input is:
    # exit 2, one line naming the option and the path, and the file keeps its bytes.
    src, V0, F = torus_file
    before = src.read_bytes()
    inp, out = _link(kind, src, tmp_path)
    proc = run("fit", inp, "-o", out, "--quiet", cwd=tmp_path)
    assert_user_error(proc)
    assert proc.stderr.strip().splitlines() == [f"sorpia: error: -o {out} is the input file: refusing to overwrite it "
                                                f"(pass --force to do so)"]
    assert src.read_bytes() == before
    assert not [p for p in tmp_path.rglob("*") if ".sorpia-tmp" in p.name]  # refused before any write


def test_force_through_a_symlink_writes_the_output_path(torus_file, tmp_path):
    # With --force the control mesh is written to the -o path. The write is atomic (a temporary
    # file renamed over the path), so the rename replaces the symlink itself: -o then reads back
    # the control mesh and the file the link pointed to keeps its bytes.
    src, V0, F = torus_file
    before = src.read_bytes()
    inp, out = _link("symlink", src, tmp_path)
    proc = run("fit", inp, "-o", out, "--force", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    Vc, _ = sorpia.read_mesh(out)
    assert np.abs(sorpia.limit_matrix(F, len(V0)) @ Vc - V0).max() < 1e-9  # B Vc = V0 to the solver's tol
    assert not out.is_symlink() and src.read_bytes() == before


def test_compare_writes_table_1_and_figure_7(torus_file, tmp_path):
    from matplotlib.image import imread

    src, V0, F = torus_file
    table, table_csv, js, plot = (tmp_path / n for n in ("t.md", "t.csv", "t.json", "p.png"))
    proc = run("compare", src, "--table", table, "--csv", table_csv, "--json", js, "--plot", plot, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    md = table.read_text()
    assert md.strip() in proc.stdout  # the printed table is the written one
    header = md.splitlines()[0]
    for tol in TOLERANCE_HEADERS:
        assert f"| {tol} |" in header
    for method in cli.METHODS:
        assert f"| {cli.METHOD_LABELS[method]} |" in md

    rows = list(csv.DictReader(io.StringIO(table_csv.read_text())))
    assert [r["method"] for r in rows] == list(cli.METHODS)
    data = json.loads(js.read_text())
    # The Python API, same run: one Interpolator, every method solved on it, as compare does.
    interp = sorpia.Interpolator(F, len(V0))
    # The build is reported once, with the phases Interpolator reports, and is in no row.
    assert set(interp.build_timings) <= set(data["setup"])
    assert data["setup"]["wall_seconds"] >= 0 and data["setup"]["cpu_seconds"] >= 0
    assert "Not included: reading the file and the topology and limit operator" in proc.stdout
    for row, entry in zip(rows, data["methods"]):
        ref = interp.solve(V0, method=entry["method"])
        assert entry["result"]["timings"]["topology"] == entry["result"]["timings"]["operator"] == 0
        assert entry["threads"] == 1 and entry["cpu_clock"] == "thread"
        assert entry["iterations"] == ref.iterations == int(row["iterations"])
        np.testing.assert_allclose(entry["errors"], ref.errors, rtol=1e-9, atol=1e-15)
        # iterations to reach 1e-j: the first k with E_k/E_0 < 1e-j, from the errors themselves
        errors = np.asarray(ref.errors)
        for j, tol in enumerate(TOLERANCE_HEADERS, start=1):
            expected = int(np.flatnonzero(errors < 10.0 ** -j)[0])
            assert entry["reached"][j - 1] == expected == int(row[f"iterations_to_{tol}"])
    # The spectral estimates are shared: W-HSS (after HSS in METHODS) needs H's
    # extremes, which HSS computed, so it spends no time estimating them again.
    timings = {e["method"]: e["result"]["timings"] for e in data["methods"]}
    assert timings["hss"]["estimate"] > 0 and timings["whss"]["estimate"] == 0
    image = imread(plot)
    assert image.shape[:2] == (560, 900)  # plotting.convergence_figure's default size
    assert image[..., :3].std() > 0.01  # not a blank image


def test_fit_threads_agrees_with_one_thread(torus_file, tmp_path):
    src, V0, F = torus_file
    ctrl, reports = {}, {}
    for n in (1, 2):
        out, report = tmp_path / f"c{n}.obj", tmp_path / f"r{n}.json"
        proc = run("fit", src, "-o", out, "--threads", n, "--report", report, "--quiet", cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
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


@pytest.mark.parametrize("args", [["fit", "-o", "c.obj", "--threads", "0"],
                                  ["compare", "--methods", "pia", "--threads", "0"],
                                  ["render", "-o", "f.png", "--threads", "0"],
                                  ["fit", "-o", "c.obj", "--method", "pia", "--threads", "2"]],
                         ids=["fit-0", "compare-0", "render-0", "fit-pia-2"])
def test_bad_threads_exit_2_with_one_line(args, torus_file, tmp_path):
    src, _, _ = torus_file
    proc = run(args[0], src, *args[1:], cwd=tmp_path)
    assert_user_error(proc)
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert "--threads" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["torus.obj"]  # nothing written


def test_compare_not_converged_exits_1_with_dashes(torus_file, tmp_path):
    src, _, _ = torus_file
    table, table_csv = tmp_path / "t.md", tmp_path / "t.csv"
    proc = run("compare", src, "--methods", "pia,sor", "--max-iter", 5, "--table", table, "--csv", table_csv,
               cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    assert "NOT converged" in proc.stdout and "Traceback" not in proc.stderr
    rows = list(csv.DictReader(io.StringIO(table_csv.read_text())))
    assert [r["converged"] for r in rows] == ["False", "False"]
    assert rows[0]["iterations_to_1e-10"] == ""  # not reached in 5 PIA steps
    pia_row = next(line for line in table.read_text().splitlines() if "| PIA |" in line)
    assert pia_row.rstrip().split("|")[-4].strip() == "-"  # the 1e-10 column


def test_render_draws_figure_3(torus_file, tmp_path):
    from matplotlib.image import imread

    src, _, _ = torus_file
    fig = tmp_path / "fig3.png"
    proc = run("render", src, "-o", fig, "--level", 1, "--size", "640x480", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    image = imread(fig)
    assert image.shape[:2] == (480, 640)
    rgb = image[..., :3]
    red = (rgb[..., 0] > 0.7) & (rgb[..., 1] < 0.3) & (rgb[..., 2] < 0.3)
    blue = (rgb[..., 2] > 0.6) & (rgb[..., 0] < 0.3)
    assert red.sum() > 50 and blue.sum() > 20  # the given (red) and control (blue) vertices are drawn


def independent_counts(F, n):
    """Edges, boundary edges and valences from the face array alone."""
    half = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    edges, counts = np.unique(np.sort(half, axis=1), axis=0, return_counts=True)
    valence = np.bincount(edges.ravel(), minlength=n)
    on_boundary = np.zeros(n, bool)
    on_boundary[edges[counts == 1].ravel()] = True
    extraordinary = np.where(on_boundary, valence != 4, valence != 6)
    return len(edges), int((counts == 1).sum()), valence, extraordinary


@pytest.mark.parametrize("name, genus, loops", [("irregular-torus", 1, 0), ("grid-boundary", 0, 1)])
def test_info_json_counts(name, genus, loops, tmp_path):
    V, F = MESHES[name]()
    src = write_obj(tmp_path / "m.obj", V, F)
    proc = run("info", src, "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    info = json.loads(proc.stdout)
    n_edges, n_bnd, valence, extra = independent_counts(np.asarray(F), len(V))
    assert (info["vertices"], info["faces"], info["edges"], info["boundary_edges"]) == (len(V), len(F), n_edges,
                                                                                        n_bnd)
    assert info["euler_characteristic"] == len(V) - n_edges + len(F) == 2 - 2 * genus - loops
    assert (info["genus"], info["boundary_loops"], info["components"]) == (genus, loops, 1)
    assert info["extraordinary_vertices"] == int(extra.sum())
    assert [e[0] for e in info["extraordinary"]] == np.flatnonzero(extra).tolist()
    assert sum(sum(h.values()) for h in info["valence_histogram"].values()) == len(V)
    assert info["valence_max"] == valence.max()
    assert info["loop_pia"]["can_run"] is True


def test_info_says_why_loop_pia_cannot_run(tmp_path):
    # Two triangles that traverse edge (0, 1) the same way: inconsistent orientation.
    src = write_obj(tmp_path / "flip.obj", np.eye(4, 3), [[0, 1, 2], [0, 1, 3]])
    proc = run("info", src, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "cannot run" in proc.stdout and "orientation" in proc.stdout


# Bad topology written by hand in both text formats, the verdict compared with the
# message of sorpia's own validation (the Python API), not with a text of our own.
MOEBIUS_OFF = """OFF
# the smallest Moebius strip: 5 vertices, faces (i, i+1, i+2) mod 5; each edge (i, i+1)
# is run the same way by its two faces and no choice of orientations can mend all five
5 5 0
1 0 0
0.31 0.95 0.2
-0.81 0.59 -0.2
-0.81 -0.59 0.2
0.31 -0.95 -0.2
3 0 1 2
3 1 2 3
3 2 3 4
3 3 4 0
3 4 0 1
"""

BOWTIE_OBJ = """# two fans around vertex 4 (OBJ index 5), one of three triangles above and one of two
# below, that share only that vertex: a non-manifold ('bowtie') vertex
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
v 0.5 0.5 0
v 0 0 -1
v 1 0 -1
v 1 1 -1
f 5 1 2
f 5 2 3
f 5 3 4
f 5 6 7
f 5 7 8
"""

@pytest.mark.parametrize("name, content, problem", [
    ("moebius.off", MOEBIUS_OFF, "the surface is not orientable"),
    ("bowtie.obj", BOWTIE_OBJ, "non-manifold vertex 4:"),
], ids=["moebius", "bowtie"])
def test_info_and_fit_name_the_topology_problem_as_the_api_does(name, content, problem, tmp_path):
    src = tmp_path / name
    src.write_text(content)
    V, F = sorpia.read_mesh(src)
    with pytest.raises(sorpia.MeshError) as refused:
        sorpia.limit_points(V, F)
    expected = str(refused.value)
    assert problem in expected  # the API names the problem (and, for the bowtie, the vertex index)

    text = run("info", src, cwd=tmp_path)
    assert text.returncode == 0, text.stderr  # info describes a mesh Loop PIA cannot run on; not an error
    verdict = [line for line in text.stdout.splitlines() if line.startswith("Loop PIA")]
    assert len(verdict) == 1 and verdict[0].endswith(f"cannot run: {expected}")
    as_json = run("info", src, "--json", cwd=tmp_path)
    assert as_json.returncode == 0, as_json.stderr
    assert json.loads(as_json.stdout)["loop_pia"] == {"can_run": False, "reason": expected, "notes": []}
    assert json.loads(as_json.stdout)["genus"] is None  # undetermined for an invalid surface

    fit = run("fit", src, "-o", tmp_path / "c.obj", "--quiet", cwd=tmp_path)
    assert_user_error(fit)
    assert expected in fit.stderr
    assert not (tmp_path / "c.obj").exists()


def test_demo_writes_everything_in_a_new_folder(tmp_path):
    from matplotlib.image import imread

    proc = run("demo", cwd=tmp_path, script=True)
    assert proc.returncode == 0, proc.stderr
    (folder,) = [p for p in tmp_path.iterdir() if p.name.startswith("sorpia-demo")]
    names = {"sample.obj", "control.obj", "surface.obj", "fit-report.json", "table.md", "table.csv",
             "compare.json", "convergence.png", "figure3.png"}
    assert {p.name for p in folder.iterdir()} == names
    for n in names:
        assert n in proc.stdout
    V0, F = sorpia.read_mesh(folder / "sample.obj")
    Vc, _ = sorpia.read_mesh(folder / "control.obj")
    assert np.abs(sorpia.limit_matrix(F, len(V0)) @ Vc - V0).max() < 1e-9
    assert imread(folder / "figure3.png").shape[:2] == (1000, 1200)
    assert json.loads((folder / "fit-report.json").read_text())["converged"] is True


def test_progress_line_on_a_terminal_plain_lines_in_a_pipe():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty, pipe, off = Tty(), io.StringIO(), io.StringIO()
    for stream, enabled in ((tty, True), (pipe, True), (off, False)):
        with cli.Progress("SOR-PIA", enabled=enabled, stream=stream) as p:
            p.status("reading mesh.obj")  # phases: on a terminal only
            p.interval = 0.0  # show every call
            for k, e in enumerate([1.0, 0.1, 0.01]):
                assert p(k, e) is False  # never stops the solver
    assert "reading mesh.obj" in tty.getvalue() and "reading" not in pipe.getvalue()
    assert tty.getvalue().count("\r") >= 4 and "\n" not in tty.getvalue()
    assert tty.getvalue().endswith("\r")  # the live line is erased at the end
    assert pipe.getvalue().splitlines()[-1] == pipe.getvalue().splitlines()[-1].strip()
    assert len(pipe.getvalue().splitlines()) == 3 and "E_k/E_0 = 1.000e-02" in pipe.getvalue()
    assert off.getvalue() == ""


def test_atomic_output_keeps_the_old_file_on_failure(tmp_path):
    target = tmp_path / "table.md"
    target.write_text("old")
    with pytest.raises(RuntimeError, match="disk full"):
        with cli.atomic_output(target) as tmp:
            Path(tmp).write_text("half writ")
            raise RuntimeError("disk full")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["table.md"]
    cli.write_text(target, "new")
    assert target.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["table.md"]


def test_without_matplotlib_figures_are_refused_and_the_rest_runs(torus_file, tmp_path):
    # A matplotlib package that cannot be imported, first on the path.
    fake = tmp_path / "no-mpl" / "matplotlib"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('matplotlib hidden by the test')\n")
    env = {"PYTHONPATH": str(fake.parent)}
    src, _, _ = torus_file
    proc = run("render", src, "-o", tmp_path / "f.png", cwd=tmp_path, env=env)
    assert_user_error(proc)
    assert "pip install matplotlib" in proc.stderr and not (tmp_path / "f.png").exists()
    proc = run("compare", src, "--methods", "sor", "--plot", tmp_path / "p.png", cwd=tmp_path, env=env)
    assert_user_error(proc)
    assert run("fit", src, "-o", tmp_path / "c.obj", "-q", cwd=tmp_path, env=env).returncode == 0
    demo = run("demo", "--out", tmp_path / "d", cwd=tmp_path, env=env)
    assert demo.returncode == 0, demo.stderr
    assert "no figures" in demo.stdout
    written = {p.name for p in (tmp_path / "d").iterdir()}
    assert "control.obj" in written and "table.md" in written and not any(n.endswith(".png") for n in written)
