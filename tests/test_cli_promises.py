"""The promises `sorpia fit` keeps, kept by `approximate`, `fit --fair` and the
USD writer too (issue 33): every output written through one path that writes
the scheme, the boundary rule and the tags where the format holds them and
warns where it does not; outputs refused before the work where they cannot
hold the result; bad input refused with one line naming the file; the
figures of a summary labelled with their units. Each test reads what was
written back independently (usd-core's own API, or sorpia's readers) and
states its tolerance."""

from __future__ import annotations

import io
import json
import os
import re
import stat
import warnings

import numpy as np
import pytest

import sorpia
from sorpia import shapes

from cli_support import assert_user_error, write_obj


def scan_file(tmp_path, name="scan.ply", scale=1.0):
    """The data: the vertices (and faces) of a level-3 icosphere, 642 points on the unit sphere."""
    V, F = shapes.icosphere(3)
    V = np.asarray(V, float) * scale
    sorpia.write_mesh(tmp_path / name, V, F)
    return tmp_path / name, V, np.asarray(F)


def creased_cube_file(tmp_path, name="cube.obj", scale=1.0):
    """A Catmull-Clark cage: a cube of 6 quads (half side 0.6) with the four edges of its top face semi-sharp
    creases (sharpness 2) and one infinitely sharp corner, written as OBJ with its 't' tags."""
    V = np.array([[x, y, z] for z in (-0.6, 0.6) for y in (-0.6, 0.6) for x in (-0.6, 0.6)]) * scale
    F = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [1, 3, 7, 5], [3, 2, 6, 7], [2, 0, 4, 6]], np.int32)
    top = np.array([[4, 5], [5, 7], [7, 6], [6, 4]], np.int32)
    tags = {"creases": (top, np.full(4, 2.0)), "corners": (np.array([0], np.int32), np.array([10.0]))}
    sorpia.write_mesh(tmp_path / name, V, F, **tags)
    return tmp_path / name, V, F, tags


_STAGES = []  # the stages opened by usd_mesh, kept alive while their prims are read


def usd_mesh(path, prim=None):
    """The UsdGeom.Mesh of a written file, opened with usd-core's own API."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    _STAGES.append(stage)
    if prim is None:
        (prim,) = [p.GetPath() for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    return UsdGeom.Mesh(stage.GetPrimAtPath(str(prim)))


def edge_set(edges) -> set:
    return {tuple(sorted(map(int, e))) for e in np.asarray(edges).reshape(-1, 2)}


# --------------------------------------------------------------------------- item 1: one writer path

@pytest.mark.parametrize("kind", ["loop", "catmull-clark"])
def test_approximate_writes_scheme_boundary_and_tags_to_usd_as_to_obj(tmp_path, monkeypatch, command, kind):
    # The cage written to USD reads back, through usd-core's API, with the scheme, boundary rule and creases
    # the fit used (a Loop cage must not read back as USD's fallback catmullClark), the same as the OBJ of the
    # same run; its limit surface, read back by sorpia, is the OBJ cage's to float32 rounding (1e-6 of the
    # diagonal: points are float32 in USD).
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    monkeypatch.chdir(tmp_path)
    scan_file(tmp_path)
    if kind == "loop":
        sorpia.write_mesh(tmp_path / "cage.obj", *shapes.icosphere(1))
        extra = ["--sharp-angle", "5"]  # every edge of the level-1 icosphere (its dihedral angles are > 5 degrees)
    else:
        creased_cube_file(tmp_path, "cage.obj")
        extra = []
    args = ["scan.ply", "--cage", "cage.obj", "--iterations", 2, "--boundary", "edge-only", *extra]
    code, out_obj, err = command("approximate", *args, "-o", "out.obj", "--report", "obj.json")
    assert code == 0, err
    code, out_usd, err = command("approximate", *args, "-o", "out.usda", "--report", "usd.json")
    assert code == 0, err
    report = json.loads((tmp_path / "usd.json").read_text())
    mesh = usd_mesh(tmp_path / "out.usda")
    assert mesh.GetSubdivisionSchemeAttr().HasAuthoredValue()
    assert mesh.GetSubdivisionSchemeAttr().Get() == {"loop": "loop", "catmull-clark": "catmullClark"}[kind]
    assert mesh.GetInterpolateBoundaryAttr().Get() == "edgeOnly"
    Vo, Fo, tags_obj = sorpia.read_mesh(tmp_path / "out.obj", tags=True)
    usd_creases = np.array(mesh.GetCreaseIndicesAttr().Get())
    assert len(usd_creases) == 2 * report["tags"]["creases"]["count"] > 0
    assert edge_set(usd_creases) == edge_set(tags_obj["creases"][0])
    if kind == "catmull-clark":
        assert list(mesh.GetCornerIndicesAttr().Get()) == [0]
    Vu, Fu, tags_usd = sorpia.read_mesh(tmp_path / "out.usda", tags=True)
    assert tags_usd["scheme"] == kind
    np.testing.assert_array_equal(Vu, Vo.astype(np.float32).astype(np.float64))
    usd_rules = {k: v for k, v in tags_usd.items() if k != "scheme"}
    diag = np.linalg.norm(Vo.max(axis=0) - Vo.min(axis=0))
    gap = np.abs(sorpia.limit_points(Vu, Fu, scheme=kind, **usd_rules)
                 - sorpia.limit_points(Vo, Fo, scheme=kind, **tags_obj)).max()
    assert gap <= 1e-6 * diag
    # the summary names the tags (item 16) and says how far the cage as written (read back) is from the fitted one
    assert "creases" in out_usd and "boundary edge-only" in out_usd
    moved = np.abs(Vu - Vo).max()
    assert report["written_max_change"] == moved > 0 and f"moved by at most {moved:.3g} model units" in out_usd
    assert json.loads((tmp_path / "obj.json").read_text())["written_max_change"] == 0.0


def test_approximate_to_ply_warns_that_the_tags_are_left_out(tmp_path, monkeypatch, command):
    # PLY holds no sharpness tags: the cage is written without them, with the warning `fit` gives.
    monkeypatch.chdir(tmp_path)
    scan_file(tmp_path)
    creased_cube_file(tmp_path, "cage.obj")
    code, _, err = command("approximate", "scan.ply", "--cage", "cage.obj", "--iterations", 1, "-o", "out.ply")
    assert code == 0, err
    assert "sharpness tags (corners, creases) are not written" in err and "out.ply" in err
    code, _, err = command("fit", "cage.obj", "-o", "fit.ply")
    assert code == 0, err
    assert "sharpness tags (corners, creases) are not written" in err


def test_write_mesh_file_returns_what_the_file_holds_and_warns_of_what_it_cannot(tmp_path):
    # The library's one writer path: the rules the format holds are written, the others named in a
    # FormatWarning; what comes back is the file read back (float32 points for USD, exact for OBJ).
    from sorpia.io import write_mesh_file

    V, F = shapes.quad_grid(3, 3)
    V = np.asarray(V, float) + 0.1
    creases = (np.array([[0, 1]], np.int32), np.array([2.0]))
    tri = np.asarray(F)[:, :3]
    with pytest.warns(sorpia.FormatWarning) as caught:
        got = write_mesh_file(tmp_path / "a.off", V, tri, scheme="catmull-clark", boundary="edge-only",
                              creases=creases)
    text = " ".join(str(w.message) for w in caught)
    for said in ("sharpness tags (creases) are not written", "boundary rule edge-only is not written",
                 "scheme catmull-clark is not written"):
        assert said in text
    np.testing.assert_array_equal(got.vertices, V)
    assert set(got.dropped) == {"scheme", "boundary", "creases"} and got.written == ()
    # nothing a reader would miss: no warning (the default rule, the scheme auto picks, no tags)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_mesh_file(tmp_path / "b.off", V, tri, scheme="loop", boundary="edge-and-corner")
    got = write_mesh_file(tmp_path / "a.obj", V, F, scheme="catmull-clark", boundary="edge-only", creases=creases)
    assert set(got.written) >= {"boundary", "creases"} and got.dropped == ()
    np.testing.assert_array_equal(got.vertices, V)
    # a SubdivisionMesh is written with all its rules: USD holds them all, read back by usd-core's API
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    mesh = sorpia.SubdivisionMesh(V, tri, scheme="catmull-clark", boundary="edge-only", creases=creases)
    got = write_mesh_file(tmp_path / "m.usda", mesh)
    assert got.written == ("boundary", "creases", "scheme") and got.dropped == ()
    usd = usd_mesh(tmp_path / "m.usda")
    assert usd.GetSubdivisionSchemeAttr().Get() == "catmullClark"
    assert usd.GetInterpolateBoundaryAttr().Get() == "edgeOnly"
    assert list(usd.GetCreaseIndicesAttr().Get()) == [0, 1]
    np.testing.assert_array_equal(got.vertices, V.astype(np.float32).astype(np.float64))
    with pytest.raises(sorpia.ParameterError, match="the mesh carries its rules"):
        write_mesh_file(tmp_path / "n.usda", mesh, scheme="loop")


def test_approximate_carries_a_given_cages_texture_coordinates(tmp_path, monkeypatch, command):
    """The fit moves only the cage's vertices: the texture coordinates on its faces stay valid and are written
    (as fit writes the input's), read back from the file equal to the cage's; the summary says so."""
    monkeypatch.chdir(tmp_path)
    V, F = shapes.quad_grid(6, 6)
    F = np.asarray(F)
    uvs = (np.ascontiguousarray(V[:, :2]), F.ravel().copy())
    sorpia.write_mesh(tmp_path / "cage.obj", sorpia.SubdivisionMesh(V, F, uvs=uvs))
    sorpia.write_mesh(tmp_path / "dense.obj", *sorpia.limit_surface(V + 0.01 * np.sin(7 * V[:, [1, 2, 0]]), F,
                                                                     level=3))
    code, out, err = command("approximate", "dense.obj", "--cage", "cage.obj", "-o", "out.obj", "--iterations", 2)
    assert code == 0, err
    got, given = sorpia.read(tmp_path / "out.obj"), sorpia.read(tmp_path / "cage.obj")
    assert got.uvs is not None
    # the same corners get the same coordinates (OBJ's text round trip is the same for both files: exact)
    np.testing.assert_array_equal(got.uvs.values[got.uvs.indices], given.uvs.values[given.uvs.indices])
    assert re.search(r"attributes\s+texture coordinates written", out)
    assert not np.array_equal(got.vertices, given.vertices)  # the cage was fitted, not copied


# --------------------------------------------------------------------------- item 2: --prim

def test_approximate_reads_the_prim_it_is_given(tmp_path, monkeypatch, command):
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    from pxr import Usd, UsdGeom

    monkeypatch.chdir(tmp_path)
    V, F = shapes.icosphere(3)
    sorpia.write_mesh(tmp_path / "two.usda", V, F, prim="/World/A")
    stage = Usd.Stage.Open(str(tmp_path / "two.usda"))
    UsdGeom.Mesh.Define(stage, "/World/B").CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    stage.GetRootLayer().Save()
    sorpia.write_mesh(tmp_path / "cage.obj", *shapes.icosphere(1))
    code, _, err = command("approximate", "two.usda", "--cage", "cage.obj", "-o", "out.obj", "--iterations", 2)
    assert_user_error(code, err)
    assert "name the one to read" in err
    code, _, err = command("approximate", "two.usda", "--prim", "/World/A", "--cage", "cage.obj", "-o", "out.obj",
                           "--iterations", 2)
    assert code == 0, err
    points = sorpia.read_mesh(tmp_path / "two.usda", prim="/World/A")[0]
    want = sorpia.approximate(points, *shapes.icosphere(1), iterations=2)
    np.testing.assert_allclose(sorpia.read_mesh(tmp_path / "out.obj")[0], want.control_vertices, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- item 3: beyond float32

def test_coordinates_beyond_float32_are_refused_for_usd_before_the_work(tmp_path, monkeypatch, command):
    # Near 1e150 a USD file (float32 points) cannot hold the cage: refused as the STL writer refuses it,
    # before the solve (the report, written after it, is not written either), and nothing is left behind.
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    monkeypatch.chdir(tmp_path)
    V, F = shapes.irregular(200, seed=2)
    write_obj(tmp_path / "big.obj", np.asarray(V) * 1e150, F)
    scan_file(tmp_path, "bigscan.ply", scale=1e150)
    sorpia.write_mesh(tmp_path / "bigcage.obj", np.asarray(shapes.icosphere(1)[0]) * 1e150, shapes.icosphere(1)[1])
    runs = [("fit", "big.obj", "-o", "out.usda", "--report", "r.json"),
            ("fit", "big.obj", "--fair", "-o", "out.usdc", "--report", "r.json"),
            ("approximate", "bigscan.ply", "--cage", "bigcage.obj", "-o", "out.usd", "--report", "r.json")]
    for args in runs:
        code, _, err = command(*args)
        assert_user_error(code, err)
        assert "beyond float32" in err and "overflow" not in err, err
        assert sorted(p.name for p in tmp_path.iterdir()) == ["big.obj", "bigcage.obj", "bigscan.ply"], args
    with pytest.raises(sorpia.MeshError, match="vertex 0 has coordinate .* beyond float32, which USD stores"):
        sorpia.write_mesh(tmp_path / "lib.usda", np.asarray(V) * 1e150, F)
    assert not (tmp_path / "lib.usda").exists()


# --------------------------------------------------------------------------- item 4: file mode

@pytest.mark.parametrize("umask", [0o022, 0o077])
def test_usd_outputs_get_the_mode_of_obj_outputs(tmp_path, monkeypatch, command, umask):
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    monkeypatch.chdir(tmp_path)
    V, F = shapes.irregular(200, seed=2)
    write_obj(tmp_path / "in.obj", V, F)
    old = os.umask(umask)
    try:
        for out in ("out.obj", "out.usda", "out.usdc"):
            code, _, err = command("fit", "in.obj", "-o", out)
            assert code == 0, err
        sorpia.write_mesh(tmp_path / "lib.usd", V, F)
    finally:
        os.umask(old)
    modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in tmp_path.iterdir() if p.name != "in.obj"}
    assert modes == {name: 0o666 & ~umask for name in ("out.obj", "out.usda", "out.usdc", "lib.usd")}
    # A file replaced keeps its own mode, as the OBJ writer keeps it.
    os.chmod(tmp_path / "out.usda", 0o640)
    code, _, err = command("fit", "in.obj", "-o", "out.usda")
    assert code == 0, err
    assert stat.S_IMODE((tmp_path / "out.usda").stat().st_mode) == 0o640
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


# --------------------------------------------------------------------------- item 5: bad USD input

def usda_quads(path, body: str):
    path.write_text(f"""#usda 1.0
def Xform "World"
{{
    def Mesh "M"
    {{
        point3f[] points = [(0,0,0), (1,0,0), (1,1,0), (0,1,0), (2,0,0), (2,1,0)]
        int[] faceVertexCounts = [4, 4]
        int[] faceVertexIndices = [0, 1, 2, 3, 1, 4, 5, 2]
        {body}
    }}
}}
""")
    return path


@pytest.mark.parametrize("body, attribute, value", [
    ('token interpolateBoundary = "bogus"', "interpolateBoundary", "bogus"),
    ('uniform token subdivisionScheme = "Loop"', "subdivisionScheme", "Loop"),
    ('token triangleSubdivisionRule = "odd"', "triangleSubdivisionRule", "odd"),
])
def test_usd_tokens_sorpia_does_not_know_are_refused_by_name(tmp_path, command, body, attribute, value):
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    path = usda_quads(tmp_path / "a.usda", body)
    with pytest.raises(sorpia.MeshFileError, match=f"a.usda: /World/M: {attribute} = {value} is not a value"):
        sorpia.read_mesh(path, tags=True)
    code, _, err = command("fit", path, "-o", tmp_path / "out.obj")
    assert_user_error(code, err)
    assert f"{attribute} = {value}" in err and "a.usda" in err
    code, out, err = command("info", path, "--json")  # the mesh described, the verdict: fit refuses it
    assert code == 0, err
    assert f"{attribute} = {value}" in json.loads(out)["pia"]["reason"]
    assert not (tmp_path / "out.obj").exists()


CORRUPT_CHILD = """
import sys
import sorpia
data = open(sys.argv[1], "rb").read()
for offset in range(int(sys.argv[2]), len(data), int(sys.argv[3])):
    with open(sys.argv[4], "wb") as fh:
        fh.write(data[:offset] + bytes([data[offset] ^ 0xFF]) + data[offset + 1:])
    print(offset, end=" ", flush=True)
    try:
        sorpia.read_mesh(sys.argv[4], tags=True, attributes=True)
        print("read", flush=True)
    except sorpia.MeshFileError as exc:
        print("refused" if sys.argv[4] in str(exc) else "unnamed", flush=True)
    except Exception as exc:
        print("other:" + type(exc).__name__, flush=True)
"""


def test_corrupted_usdc_files_are_refused_naming_the_file(tmp_path):
    # Bytes of a small .usdc flipped one at a time (every third byte past the crate's 96-byte header): the file
    # reads (a value changed) or is refused with a MeshFileError naming it; never another exception (main at
    # dc25e4d: 27 KeyErrors and 57 pxr Tf.ErrorExceptions from inside a Get over every byte). usd-core itself
    # can crash or try to allocate without bound on some corruptions (offset 88 of this file segfaults in
    # Usd.Stage.Open, offset 816 asks for more memory than the machine has): the reads run in a child process
    # with 3 GB of address space, restarted after the offset where it died, and such offsets are only counted.
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    import resource
    import subprocess
    import sys

    V, F = shapes.quad_grid(2, 2)
    creases = (np.array([[0, 1]], np.int32), np.array([2.0]))
    good, bad = tmp_path / "good.usdc", tmp_path / "bad.usdc"
    sorpia.write_mesh(good, np.asarray(V, float), F, scheme="catmull-clark", creases=creases, boundary="edge-only")
    size, step = good.stat().st_size, 3

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))

    outcomes, start, died = {}, 96, 0
    while start < size:
        run = subprocess.run([sys.executable, "-c", CORRUPT_CHILD, str(good), str(start), str(step), str(bad)],
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, preexec_fn=limit,
                             timeout=300)
        words = run.stdout.split()
        seen = [int(offset) for offset in words[::2][:len(words) // 2]]
        outcomes.update(zip(seen, words[1::2]))
        if run.returncode == 0:
            break
        died += 1  # usd-core's own crash at the offset after the last one reported
        start = (seen[-1] if seen else start - step) + 2 * step
    assert died <= 3
    wrong = {k: v for k, v in outcomes.items() if v not in ("read", "refused")}
    assert not wrong, wrong
    assert list(outcomes.values()).count("refused") > 50


# --------------------------------------------------------------------------- item 7: units, no fake improvement

def test_approximate_summary_labels_its_units_and_says_when_nothing_changed(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    scan_file(tmp_path, scale=4.0)  # a diagonal of about 13.9: model units and diagonals differ
    sorpia.write_mesh(tmp_path / "cage.obj", np.asarray(shapes.icosphere(1)[0]) * 4.0, shapes.icosphere(1)[1])
    for fairness, unchanged in (("1e6", True), ("3e-4", False)):
        code, out, err = command("approximate", "scan.ply", "--cage", "cage.obj", "-o", "out.obj", "--iterations", 3,
                                 "--fairness", fairness, "--report", "r.json")
        assert code == 0, err
        report = json.loads((tmp_path / "r.json").read_text())
        assert (report["best_iteration"] == 0) == unchanged
        lines = [line for line in out.splitlines() if "data->surf" in line or "surf->data" in line]
        assert len(lines) == 2
        for line in lines:
            # every figure says its unit: model units or "of the diagonal"
            for part in line.split(";"):
                assert "model units" in part or "of the diagonal" in part or "unchanged" in part, line
        data_line = lines[0]
        f = report["final"]
        assert f"{f['rms_relative']:.3g}" in data_line and f"{f['rms']:.4g}" in data_line
        if unchanged:
            assert "unchanged" in data_line and "the cage as given: RMS" not in data_line
        else:
            assert f"{report['history'][0]['rms_relative']:.3g}" in data_line


# --------------------------------------------------------------------------- item 10: approximate's own errors

def test_approximate_errors_name_its_own_options(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    scan_file(tmp_path)
    V, F = shapes.quad_torus(12, 8)
    sorpia.write_mesh(tmp_path / "quads.obj", V, F)
    # a quad scan: --vertices decimates triangles; --triangulate is approximate's way out
    code, _, err = command("approximate", "quads.obj", "--vertices", 30, "-o", "out.obj")
    assert_user_error(code, err)
    assert "--triangulate" in err
    code, _, err = command("approximate", "quads.obj", "--vertices", 30, "--triangulate", "-o", "out.obj",
                           "--iterations", 1)
    assert code == 0, err
    assert len(sorpia.read_mesh(tmp_path / "out.obj")[0]) == 30
    # a quad cage with --scheme loop: the reason, not numpy's
    code, _, err = command("approximate", "scan.ply", "--cage", "quads.obj", "--scheme", "loop", "-o", "out2.obj")
    assert_user_error(code, err)
    assert "Loop subdivision needs triangles" in err and "vstack" not in err
    # a non-manifold cage: the way out is approximate's (sorpia repair), not --repair / --nonmanifold it lacks
    Vn = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0], [0.5, 0.5, 0.5]], float)
    Fn = np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4]], np.int32)
    write_obj(tmp_path / "nm.obj", Vn, Fn)
    code, _, err = command("approximate", "scan.ply", "--cage", "nm.obj", "-o", "out3.obj")
    assert_user_error(code, err)
    assert "nm.obj" in err and "non-manifold edge" in err
    assert "--nonmanifold" not in err and "--repair" not in err and "sorpia repair" in err


def test_a_decimated_cage_the_library_refuses_is_named_as_the_decimated_cage(tmp_path, monkeypatch, command):
    # Where decimation leaves a cage the fit refuses, the message says the indices are the decimated cage's
    # (not the input's) and offers approximate's own ways out. The decimation is replaced by one that returns a
    # cage with a bowtie vertex, as a decimation defect would.
    import sorpia.cli.approximate as cli_approximate

    monkeypatch.chdir(tmp_path)
    scan_file(tmp_path)
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0.5]], float)
    F = np.array([[0, 1, 2], [0, 3, 4]], np.int32)  # two fans meeting at vertex 0 only

    def bowtie(*args, **kwargs):
        return sorpia.Cage(V, F, None)

    monkeypatch.setattr(cli_approximate, "decimate", bowtie)
    code, _, err = command("approximate", "scan.ply", "--vertices", 5, "-o", "out.obj")
    assert_user_error(code, err)
    assert "the cage decimated from scan.ply" in err and "indices are the cage's" in err
    assert "non-manifold vertex 0" in err and "--cage CAGE" in err
    assert "--nonmanifold" not in err and "--repair" not in err
    assert not (tmp_path / "out.obj").exists()


# --------------------------------------------------------------------------- item 13: extreme scales

def test_fit_check_at_1e200_is_finite_and_small(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    V, F = shapes.irregular(300, seed=5)
    write_obj(tmp_path / "big.obj", np.asarray(V) * 1e200, F)
    code, out, err = command("fit", "big.obj", "-o", "out.obj", "--report", "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    # E_k/E_0 < 1e-10 (the default tol), E_0 of the order of the diagonal
    assert report["max_residual_relative"] is not None and report["max_residual_relative"] <= 1e-9
    assert "check = inf" not in out and "inf" not in out.split("check", 1)[1].splitlines()[0]


@pytest.mark.parametrize("membrane", [(), ("--membrane", "0.5")], ids=["thin-plate", "membrane"])
def test_fit_fair_energy_at_1e200_is_reported_scaled(tmp_path, monkeypatch, command, membrane):
    monkeypatch.chdir(tmp_path)
    V, F = shapes.irregular(300, seed=5)
    write_obj(tmp_path / "unit.obj", np.asarray(V), F)
    write_obj(tmp_path / "big.obj", np.asarray(V) * 1e200, F)
    ratios = []
    for name in ("unit", "big"):
        code, out, err = command("fit", f"{name}.obj", "--fair", "-o", f"{name}-fair.obj", "--report", f"{name}.json",
                                 *membrane)
        assert code == 0, err
        assert "nan" not in out and "inf" not in out, out
        ratios.append(json.loads((tmp_path / f"{name}.json").read_text())["energy_ratio"])
    # The ratio is scale-free: the same at 1e200 as at 1 (the solve runs scaled by a power of two, exactly).
    assert ratios[1] == pytest.approx(ratios[0], rel=1e-9)


# --------------------------------------------------------------------------- item 14: fair's check of the file

def test_fit_fair_to_usd_reports_the_miss_of_the_cage_as_written(tmp_path, monkeypatch, command):
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    monkeypatch.chdir(tmp_path)
    V, F = shapes.irregular(300, seed=5)
    V = np.asarray(V) * 3.0 + 0.37
    write_obj(tmp_path / "in.obj", V, F)
    code, out, err = command("fit", "in.obj", "--fair", "-o", "fair.usda", "--report", "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    Vc, Fc, tags = sorpia.read_mesh(tmp_path / "fair.usda", tags=True)
    scheme = tags.pop("scheme")
    miss = np.linalg.norm(sorpia.limit_points(Vc, Fc, scheme=scheme, **tags)[:len(V)] - V, axis=1).max()
    assert miss > 1e-12 * np.abs(V).max()  # float32 points: far above the float64 cage's miss
    assert report["max_residual"] == pytest.approx(miss, rel=1e-9)
    assert "as written" in out


# --------------------------------------------------------------------------- item 16: the smaller ones

def test_progress_lines_in_a_pipe_for_approximate_and_fit_fair(tmp_path, monkeypatch, command):
    # In a pipe (the test's stderr is no terminal) a long phase or iteration gets a plain line; the interval
    # is set to 0 so that this short run shows every one.
    from sorpia.cli import progress

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(progress, "PIPE_INTERVAL", 0.0)
    scan_file(tmp_path)
    sorpia.write_mesh(tmp_path / "cage.obj", *shapes.icosphere(1))
    code, _, err = command("approximate", "scan.ply", "--cage", "cage.obj", "-o", "out.obj", "--iterations", 2)
    assert code == 0, err
    assert re.search(r"^approximate: iteration 1, RMS .* of the diagonal", err, re.M), err
    V, F = shapes.irregular(200, seed=2)
    write_obj(tmp_path / "in.obj", V, F)
    code, _, err = command("fit", "in.obj", "--fair", "-o", "fair.obj")
    assert code == 0, err
    assert re.search(r"^fit --fair: fair interpolation", err, re.M), err


def test_the_live_progress_line_fits_80_columns():
    from sorpia.cli.progress import Progress

    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty = Tty()
    with Progress("approximate", stream=tty) as p:
        p.status("approximate: iteration 10, RMS 0.000123 (0.000456 of the diagonal), max 0.00789 (0.0123 of "
                 "the diagonal), 12.3 s")
        p.status(f"reading {'very-long-folder-name/' * 8}mesh.obj")
    for line in tty.getvalue().split("\r"):
        assert len(line) <= 80, line


@pytest.mark.parametrize("content, message", [
    (b"1 2 \xff\xfe 3\n", "is not UTF-8"),
    ("1_0\n".encode(), "'1_0' is not a vertex index"),
    ("\u0661\u0662\n".encode(), "is not a vertex index"),
])
def test_targets_file_words_are_ascii_digits_and_the_file_is_named(torus_file, tmp_path, command, content, message):
    src, _, _ = torus_file
    (tmp_path / "t.txt").write_bytes(content)
    code, _, err = command("fit", src, "--fair", "--targets", tmp_path / "t.txt", "-o", tmp_path / "out.obj")
    assert_user_error(code, err)
    assert message in err and "t.txt" in err


def test_levels_range_is_in_the_help_and_the_error(command):
    from sorpia.fair import MAX_LEVELS

    code, out, _ = command("fit", "--help")
    assert f"1 to {MAX_LEVELS}" in " ".join(out.split())
    code, _, err = command("fit", "x.obj", "--fair", "--levels", MAX_LEVELS + 2, "-o", "y.obj")
    assert code == 2 and f"1 to {MAX_LEVELS}" in err


def test_the_wrote_line_names_the_blender_script(tmp_path, command):
    src = tmp_path / "quads.obj"
    sorpia.write_mesh(src, *shapes.quad_torus(8, 6))
    for extra in ([], ["--fair"]):
        code, out, err = command("fit", src, *extra, "-o", tmp_path / "c.obj", "--blender", tmp_path / "c.py")
        assert code == 0, err
        wrote = [line for line in out.splitlines() if line.strip().startswith("wrote")][0]
        assert str(tmp_path / "c.py") in wrote


def test_info_on_usd_does_not_suggest_triangulate(tmp_path, command):
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    sorpia.write_mesh(tmp_path / "q.usda", *shapes.quad_grid(3, 3))
    for args in ([], ["--scheme", "loop"]):
        code, out, err = command("info", tmp_path / "q.usda", *args)
        assert code == 0, err
        assert "--triangulate" not in out, out


# --------------------------------------------------------------------------- the robust default's summary

def sphere_with_outliers(tmp_path, name="scan.ply", binary=False, count=20, factor=40.0):
    """The scan of scan_file with `count` of its points moved `factor` times as far from the centre (the unit
    sphere's points to radius `factor`); (path, points, inlier mask)."""
    V, F = shapes.icosphere(3)
    V = np.asarray(V, float)
    far = np.random.default_rng(5).choice(len(V), count, replace=False)
    V[far] *= factor
    inlier = np.ones(len(V), bool)
    inlier[far] = False
    sorpia.write_mesh(tmp_path / name, V, F, binary=binary)
    return tmp_path / name, V, inlier


def inlier_distances(cage_vertices, cage_faces, points, scheme="loop", level=7):
    """The points' distances to a cage's limit surface, measured independently of the fit's footpoints: to the
    tangent plane (the area-weighted normal) at the nearest vertex of its level-7 tessellation, a k-d tree's; off
    the true distance by about half the curvature times the squared spacing (3e-6 on the sphere)."""
    from scipy.spatial import cKDTree

    T, F = sorpia.limit_surface(cage_vertices, cage_faces, level=level, scheme=scheme)
    F = np.asarray(F)
    normals = np.zeros_like(T)
    face_normals = np.cross(T[F[:, 1]] - T[F[:, 0]], T[F[:, 2]] - T[F[:, 0]])
    for j in range(3):
        np.add.at(normals, F[:, j], face_normals)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    nearest = cKDTree(T).query(points)[1]
    return np.abs(np.einsum("ij,ij->i", points - T[nearest], normals[nearest]))


@pytest.mark.parametrize("stream", ["no", "yes"])
def test_robust_summary_gives_the_kept_points_rms_beside_the_cut_count(tmp_path, monkeypatch, command, stream):
    # 20 of the sphere's 642 points moved 40 times out: the RMS distance of all the points counts them, so on its
    # own it says the fit got no better (or worse) while the surface lies on the other points. The summary gives,
    # for the result and for the cage as given alike, the RMS distance of the points within the robust cut, in
    # both units, beside the count of points beyond it; the report the same figures, which agree with an
    # independent measurement of the 622 unmoved points' distances to the cage as written (5%: the measurement's
    # own error, and the report's are at the footpoints before the final search), and the stop reason names the
    # loss that decided.
    monkeypatch.chdir(tmp_path)
    _, P, inlier = sphere_with_outliers(tmp_path, binary=True)
    sorpia.write_mesh(tmp_path / "cage.obj", *shapes.icosphere(1))
    code, out, err = command("approximate", "scan.ply", "--cage", "cage.obj", "-o", "out.obj", "--report", "r.json",
                             "--stream", stream)
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    f, first = report["final"], report["history"][0]
    assert report["streamed"] == (stream == "yes")
    assert report["robust"] == "tukey" and report["robust_outliers"] == f["robust_cut"] == 20 == (~inlier).sum()
    assert first["robust_cut"] == 20
    wv, wf = sorpia.read_mesh(tmp_path / "out.obj")[:2]
    d = inlier_distances(wv, wf, P[inlier])
    true_rms = float(np.sqrt(np.mean(d ** 2)))
    assert abs(f["inlier_rms"] - true_rms) <= 0.05 * true_rms, (f["inlier_rms"], true_rms)
    assert f["inlier_rms_relative"] == pytest.approx(f["inlier_rms"] / report["diagonal"], rel=1e-12)
    assert f["inlier_rms"] < 0.2 * first["inlier_rms"]  # the fit got better where the loss keeps the data
    (kept,) = [line for line in out.splitlines() if line.lstrip().startswith("kept")]
    result, given = kept.split("; the cage as given: ")
    for part, rec in ((result, f), (given, first)):
        assert f"RMS {rec['inlier_rms_relative']:.3g} of the diagonal" in part, kept
        assert f"RMS {rec['inlier_rms']:.4g} model units" in part, kept
        assert f"{rec['robust_cut']} points beyond it" in part, kept
    (data_line,) = [line for line in out.splitlines() if "data->surf" in line]
    assert "over all the points" in data_line
    if report["stop_reason"] == "converged":
        assert "the robust loss (tukey) no longer fell" in out and "the RMS distance no longer fell" not in out


def streamed_cube_fit(tmp_path, command, output):
    """`sorpia approximate` of the sphere scan as a binary PLY streamed (--stream yes) with the creased cube cage,
    written to `output`; returns (report, the cube's tags)."""
    sorpia.write_mesh(tmp_path / "scan.ply", *shapes.icosphere(3), binary=True)
    _, _, _, tags = creased_cube_file(tmp_path, "cube.obj")
    code, out, err = command("approximate", "scan.ply", "--cage", "cube.obj", "-o", output, "--stream", "yes",
                             "--report", "r.json", "--force")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["streamed"]
    return report, tags


def test_streamed_fit_written_to_usd_reads_back_with_its_scheme_and_tags(tmp_path, monkeypatch, command):
    # A streamed fit's cage written to .usda reads back through usd-core's API with the scheme, boundary rule and
    # tags of the cage given, and its points are the streamed fit's (the same run to .obj) to float32 rounding
    # (1e-7 relative); the streamed fit is the in-memory one.
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
    monkeypatch.chdir(tmp_path)
    streamed_cube_fit(tmp_path, command, "cage.obj")
    streamed_cube_fit(tmp_path, command, "cage.usda")
    code, _, err = command("approximate", "scan.ply", "--cage", "cube.obj", "-o", "memory.obj", "--stream", "no")
    assert code == 0, err
    V = sorpia.read_mesh("cage.obj")[0]
    np.testing.assert_array_equal(V, sorpia.read_mesh("memory.obj")[0])
    _, _, _, tags = creased_cube_file(tmp_path, "cube.obj")
    mesh = usd_mesh(tmp_path / "cage.usda")
    assert mesh.GetSubdivisionSchemeAttr().Get() == "catmullClark"
    assert mesh.GetInterpolateBoundaryAttr().Get() == "edgeAndCorner"
    assert edge_set(np.asarray(mesh.GetCreaseIndicesAttr().Get())) == edge_set(tags["creases"][0])
    assert list(mesh.GetCreaseSharpnessesAttr().Get()) == [2.0] * 4
    assert list(mesh.GetCornerIndicesAttr().Get()) == [0] and list(mesh.GetCornerSharpnessesAttr().Get()) == [10.0]
    points = np.asarray(mesh.GetPointsAttr().Get(), float)
    assert np.abs(points - V).max() <= 1e-7 * np.abs(V).max()
