"""USD files in read_mesh, write_mesh and the command: every attribute written
is read back, by sorpia and by usd-core's own UsdGeom API; a stage's other
prims survive `sorpia fit in.usd -o out.usd`; what sorpia cannot fit is
refused by name."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import sorpia
from sorpia import MeshFileError, ParameterError, UsdWarning

pxr = pytest.importorskip("pxr", reason="usd-core is not installed (pip install 'sorpia[usd]')")
from pxr import Gf, Usd, UsdGeom, Vt  # noqa: E402

from cli_support import assert_user_error  # noqa: E402


def tagged_polygons():
    """The polygon torus (pentagons, hexagons, quads, triangles) with float32
    coordinates (USD's points are float32: then a round trip is exact), a
    semi-sharp and an infinitely sharp crease, a corner, a hole and texture
    coordinates with a seam."""
    V, F = sorpia.shapes.polygon_torus(8, 6, seed=3)
    V = V.astype(np.float32).astype(np.float64)
    counts, indices = F.face_vertex_counts, F.face_vertex_indices
    first = indices[:counts[0]]
    edges = np.array([[first[0], first[1]], [first[1], first[2]]], dtype=np.int32)
    uv_values = np.random.default_rng(1).random((len(indices), 2))
    tags = {"creases": (edges, np.array([2.5, 10.0])), "corners": (np.array([int(first[-1])], np.int32),
                                                                   np.array([10.0])),
            "holes": np.array([len(counts) - 1], np.int32), "boundary": "edge-only", "scheme": "catmull-clark"}
    uvs = sorpia.FaceVarying(uv_values, np.arange(len(indices), dtype=np.int32))
    return V, F, tags, uvs


@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usd"])
def test_round_trip_every_attribute(tmp_path, suffix):
    V, F, tags, uvs = tagged_polygons()
    path = tmp_path / f"cage{suffix}"
    sorpia.write_mesh(path, V, F, uvs=uvs, **tags)
    V2, F2, tags2, attributes = sorpia.read_mesh(path, tags=True, attributes=True)
    # Points float32 in the file, exactly representable here: equal to the bit.
    assert np.array_equal(V2, V)
    assert np.array_equal(F2.face_vertex_counts, F.face_vertex_counts)
    assert np.array_equal(F2.face_vertex_indices, F.face_vertex_indices)
    assert set(tags2) == set(tags)
    for key in ("creases", "corners"):
        assert np.array_equal(np.asarray(tags2[key][0]).reshape(tags[key][0].shape), tags[key][0])
        assert np.array_equal(tags2[key][1], tags[key][1])  # 2.5 and 10 are float32 exactly
    assert np.array_equal(tags2["holes"], tags["holes"])
    assert tags2["boundary"] == "edge-only" and tags2["scheme"] == "catmull-clark"
    # Texture coordinates are double2 in the file (texCoord2d): the values, per corner, exactly.
    assert np.array_equal(attributes["uvs"].values[attributes["uvs"].indices], uvs.values[uvs.indices])


def test_usd_api_reads_what_was_written(tmp_path):
    """usd-core's own UsdGeom API (not sorpia's reader) sees the mesh, its scheme and its tags."""
    V, F, tags, uvs = tagged_polygons()
    path = tmp_path / "cage.usda"
    sorpia.write_mesh(path, V, F, uvs=uvs, **tags)
    stage = Usd.Stage.Open(str(path))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Mesh"))
    assert stage.GetDefaultPrim().GetPath() == mesh.GetPath()
    assert np.array_equal(np.array(mesh.GetPointsAttr().Get(), dtype=np.float64), V)
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == F.face_vertex_counts.tolist()
    assert list(mesh.GetFaceVertexIndicesAttr().Get()) == F.face_vertex_indices.tolist()
    assert mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.catmullClark
    assert mesh.GetInterpolateBoundaryAttr().Get() == UsdGeom.Tokens.edgeOnly
    assert list(mesh.GetCreaseIndicesAttr().Get()) == tags["creases"][0].reshape(-1).tolist()
    assert list(mesh.GetCreaseLengthsAttr().Get()) == [2, 2]
    assert list(mesh.GetCreaseSharpnessesAttr().Get()) == [2.5, 10.0]
    assert list(mesh.GetCornerIndicesAttr().Get()) == tags["corners"][0].tolist()
    assert list(mesh.GetCornerSharpnessesAttr().Get()) == [10.0]
    assert list(mesh.GetHoleIndicesAttr().Get()) == tags["holes"].tolist()
    st = UsdGeom.PrimvarsAPI(mesh.GetPrim()).GetPrimvar("st")
    assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    assert np.array_equal(np.array(st.ComputeFlattened()), uvs.values[uvs.indices])
    extent = np.array(mesh.GetExtentAttr().Get())
    assert np.array_equal(extent, np.array([V.min(axis=0), V.max(axis=0)]))  # float32 extremes: exact
    assert UsdGeom.Mesh.ValidateTopology(mesh.GetFaceVertexIndicesAttr().Get(),
                                         mesh.GetFaceVertexCountsAttr().Get(), len(V))[0]


def test_obj_usd_obj_keeps_tags_and_points(tmp_path):
    """OBJ with tags -> USD -> OBJ: the same file contents (points float32-exact, tags exactly)."""
    V, F, tags, _ = tagged_polygons()
    scheme = tags.pop("scheme")
    sorpia.write_mesh(tmp_path / "a.obj", V, F, **tags)
    V1, F1, t1 = sorpia.read_mesh(tmp_path / "a.obj", tags=True)
    sorpia.write_mesh(tmp_path / "b.usdc", V1, F1, scheme=scheme, **t1)
    V2, F2, t2 = sorpia.read_mesh(tmp_path / "b.usdc", tags=True)
    assert t2.pop("scheme") == scheme
    sorpia.write_mesh(tmp_path / "c.obj", V2, F2, **t2)
    assert (tmp_path / "c.obj").read_bytes() == (tmp_path / "a.obj").read_bytes()


def write_usda(path, body: str, points="[(0,0,0), (1,0,0), (1,1,0), (0,1,0), (2,0,0), (2,1,0)]",
               faces="[4, 4]", indices="[0, 1, 2, 3, 1, 4, 5, 2]"):
    """A stage written by hand: one mesh /World/M (two quads side by side) with `body` added to its attributes."""
    path.write_text(f"""#usda 1.0
def Xform "World"
{{
    def Mesh "M"
    {{
        point3f[] points = {points}
        int[] faceVertexCounts = {faces}
        int[] faceVertexIndices = {indices}
        {body}
    }}
}}
""")
    return path


def test_crease_chains_expand_to_edges(tmp_path):
    """A crease of 3 vertices is its 2 edges; a sharpness per crease or per edge."""
    body = "int[] creaseIndices = [3, 2, 5, 0, 1]\nint[] creaseLengths = [3, 2]\n"
    path = write_usda(tmp_path / "a.usda", body + "float[] creaseSharpnesses = [1.5, 10]")
    _, _, tags = sorpia.read_mesh(path, tags=True)
    assert tags["creases"][0].tolist() == [[3, 2], [2, 5], [0, 1]]
    assert tags["creases"][1].tolist() == [1.5, 1.5, 10.0]
    path = write_usda(tmp_path / "b.usda", body + "float[] creaseSharpnesses = [1, 2, 3]")
    assert sorpia.read_mesh(path, tags=True)[2]["creases"][1].tolist() == [1.0, 2.0, 3.0]
    path = write_usda(tmp_path / "c.usda", body + "float[] creaseSharpnesses = [1, 2, 3, 4]")
    with pytest.raises(MeshFileError, match="one per crease \\(2\\) or one per crease edge \\(3\\)"):
        sorpia.read_mesh(path, tags=True)


def test_unauthored_rules_are_usd_fallbacks(tmp_path):
    """No subdivisionScheme, no interpolateBoundary: USD's fallbacks, catmullClark and edgeAndCorner."""
    _, F, tags = sorpia.read_mesh(write_usda(tmp_path / "a.usda", ""), tags=True)
    assert F.shape == (2, 4)
    assert tags == {"scheme": "catmull-clark", "boundary": "edge-and-corner"}


@pytest.mark.parametrize("body, message", [
    ('uniform token subdivisionScheme = "bilinear"', "subdivisionScheme = bilinear is refused"),
    ('uniform token subdivisionScheme = "none"', "subdivisionScheme = none is refused"),
    ('token interpolateBoundary = "none"', "interpolateBoundary = none is refused"),
    ('token triangleSubdivisionRule = "smooth"', "triangleSubdivisionRule = smooth is refused"),
])
def test_rules_sorpia_has_not_are_refused(tmp_path, body, message):
    path = write_usda(tmp_path / "a.usda", body)
    with pytest.raises(MeshFileError, match=message):
        sorpia.read_mesh(path, tags=True)
    assert sorpia.read_mesh(path)[0].shape == (6, 3)  # without tags, the mesh reads


def test_info_gives_a_verdict_on_rules_sorpia_has_not(tmp_path, command):
    """`sorpia info` describes a bilinear mesh and says fit refuses it (exit 0), where fit stops with the reader's error."""
    path = write_usda(tmp_path / "a.usda", 'uniform token subdivisionScheme = "bilinear"')
    code, out, err = command("info", path, "--json")
    assert code == 0
    info = json.loads(out)
    assert info["faces"] == 2 and not info["pia"]["can_run"]
    assert "subdivisionScheme = bilinear is refused" in info["pia"]["reason"]
    code, _, err = command("fit", path, "-o", tmp_path / "out.obj")
    assert code == 2 and "subdivisionScheme = bilinear is refused" in err


def test_bad_stages(tmp_path):
    bad = write_usda(tmp_path / "bad.usda", "", indices="[0, 1, 2, 3, 1, 4, 9, 2]")
    with pytest.raises(MeshFileError, match="invalid topology: Out of range face vertex index 9"):
        sorpia.read_mesh(bad)
    (tmp_path / "empty.usda").write_text('#usda 1.0\ndef Xform "World"\n{\n}\n')
    with pytest.raises(MeshFileError, match="has no Mesh prim"):
        sorpia.read_mesh(tmp_path / "empty.usda")
    two = tmp_path / "two.usda"
    sorpia.write_mesh(two, *sorpia.shapes.quad_grid(3, 3), prim="/A/M")
    stage = Usd.Stage.Open(str(two))
    UsdGeom.Mesh.Define(stage, "/B").CreatePointsAttr([(0, 0, 0)])
    stage.Save()
    with pytest.raises(MeshFileError, match="2 Mesh prims \\(/A/M, /B\\): name the one"):
        sorpia.read_mesh(two)
    with pytest.raises(MeshFileError, match="prim /A is not a Mesh; its meshes: /A/M, /B"):
        sorpia.read_mesh(two, prim="/A")
    assert sorpia.read_mesh(two, prim="/A/M")[0].shape == (9, 3)
    (tmp_path / "junk.usda").write_text("not usd at all\n")
    with pytest.raises(MeshFileError, match="junk.usda: not a readable USD stage"):
        sorpia.read_mesh(tmp_path / "junk.usda")
    with pytest.raises(MeshFileError, match="triangulate is not available for USD"):
        sorpia.read_mesh(two, triangulate=True, prim="/A/M")
    with pytest.raises(ParameterError, match="scheme apply to USD files only"):
        sorpia.write_mesh(tmp_path / "x.obj", *sorpia.shapes.quad_grid(3, 3), scheme="catmull-clark")


def test_time_sampled_points(tmp_path):
    """Points with time samples: the default value is read (said in a UsdWarning), else the first sample."""
    V, F = sorpia.shapes.quad_grid(3, 3)
    V = V.astype(np.float32).astype(np.float64)
    path = tmp_path / "anim.usda"
    sorpia.write_mesh(path, V, F)
    stage = Usd.Stage.Open(str(path))
    points = UsdGeom.Mesh(stage.GetPrimAtPath("/Mesh")).GetPointsAttr()
    points.Set(Vt.Vec3fArray.FromNumpy((V + 1).astype(np.float32)), 3.0)
    stage.Save()
    with pytest.warns(UsdWarning, match="1 time samples: read the default value"):
        assert np.array_equal(sorpia.read_mesh(path)[0], V)
    points.Clear()
    points.Set(Vt.Vec3fArray.FromNumpy((V + 2).astype(np.float32)), 5.0)
    stage.Save()
    with pytest.warns(UsdWarning, match="no default value: read the sample at time 5"):
        assert np.array_equal(sorpia.read_mesh(path)[0], V + 2)


def test_vertex_and_indexed_primvars(tmp_path):
    """st given per vertex, and normals per face corner through indices: both as FaceVarying."""
    body = ('texCoord2f[] primvars:st = [(0,0), (1,0), (1,1), (0,1), (2,0), (2,1)] (interpolation = "vertex")\n'
            'normal3f[] primvars:normals = [(0,0,1), (0,0,-1)] (interpolation = "faceVarying")\n'
            'int[] primvars:normals:indices = [0, 0, 0, 0, 1, 1, 1, 1]\n'
            'color3f[] primvars:displayColor = [(1,0,0)] (interpolation = "constant")')
    _, F, attributes = sorpia.read_mesh(write_usda(tmp_path / "a.usda", body), attributes=True)
    uvs, normals = attributes["uvs"], attributes["normals"]
    assert np.array_equal(uvs.values[uvs.indices], np.array([[0, 0], [1, 0], [1, 1], [0, 1]] * 1 + [
        [1, 0], [2, 0], [2, 1], [1, 1]], dtype=float))
    assert np.array_equal(normals.values[normals.indices][:, 2], [1, 1, 1, 1, -1, -1, -1, -1])
    # The normals attribute (not a primvar), per vertex: each corner takes its vertex's normal.
    body = 'normal3f[] normals = [(0,0,1), (0,0,2), (0,0,3), (0,0,4), (0,0,5), (0,0,6)] (interpolation = "vertex")'
    _, F, attributes = sorpia.read_mesh(write_usda(tmp_path / "n.usda", body), attributes=True)
    normals = attributes["normals"]
    assert np.array_equal(normals.values[normals.indices][:, 2], F.reshape(-1) + 1)
    body = 'texCoord2f[] primvars:st = [(0,0), (1,1)] (interpolation = "uniform")'
    with pytest.warns(UsdWarning, match="primvars:st: left out: uniform interpolation"):
        assert "uvs" not in sorpia.read_mesh(write_usda(tmp_path / "b.usda", body), attributes=True)[2]


def test_without_usd_core_the_error_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pxr", None)  # import pxr fails, as without usd-core
    with pytest.raises(MeshFileError, match=r"usd-core.*pip install 'sorpia\[usd\]'"):
        sorpia.read_mesh(tmp_path / "a.usda")
    with pytest.raises(MeshFileError, match=r"pip install 'sorpia\[usd\]'"):
        sorpia.write_mesh(tmp_path / "a.usda", *sorpia.shapes.quad_grid(3, 3))
    assert not (tmp_path / "a.usda").exists()


# ---- the command ------------------------------------------------------------

def scene(path, V, F, **tags):
    """A stage with the mesh under a transformed Xform, a second prim (a sphere)
    and a mesh primvar (displayColor, per vertex): what fit must keep."""
    sorpia.write_mesh(path, V, F, prim="/World/Cage", **tags)
    stage = Usd.Stage.Open(str(path))
    UsdGeom.Xformable(stage.GetPrimAtPath("/World")).AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    UsdGeom.Sphere.Define(stage, "/World/Ball").CreateRadiusAttr(0.5)
    color = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/World/Cage")).CreatePrimvar(
        "displayColor", pxr.Sdf.ValueTypeNames.Color3fArray, UsdGeom.Tokens.vertex)
    color.Set(Vt.Vec3fArray.FromNumpy(np.linspace(0, 1, 3 * len(V), dtype=np.float32).reshape(-1, 3)))
    stage.Save()
    return stage


def test_fit_usd_keeps_the_stage(command, tmp_path):
    V, F = sorpia.shapes.quad_grid(6, 5)
    V = V.astype(np.float32).astype(np.float64)
    edges = np.array([[7, 8], [8, 9]], dtype=np.int32)
    tags = {"creases": (edges, np.array([10.0, 3.0])), "corners": (np.array([0], np.int32), np.array([2.0])),
            "boundary": "edge-only"}
    scene(tmp_path / "in.usda", V, F, scheme="catmull-clark", **tags)
    before = (tmp_path / "in.usda").read_bytes()
    code, out, err = command("fit", str(tmp_path / "in.usda"), "-o", str(tmp_path / "out.usdc"), "-q")
    assert code == 0, err
    assert (tmp_path / "in.usda").read_bytes() == before  # the input is never modified
    stage = Usd.Stage.Open(str(tmp_path / "out.usdc"))
    assert list(UsdGeom.Xformable(stage.GetPrimAtPath("/World")).GetOrderedXformOps()[0].Get()) == [1, 2, 3]
    assert UsdGeom.Sphere(stage.GetPrimAtPath("/World/Ball")).GetRadiusAttr().Get() == 0.5
    color = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/World/Cage")).GetPrimvar("displayColor")
    assert len(color.Get()) == len(V)
    # The fitted cage as written (float32), read back: its limit points (sorpia's Bfr evaluation, the file's
    # scheme and tags) pass through the input's points to float32 rounding of the diagonal.
    ctrl, F2, tags2 = sorpia.read_mesh(tmp_path / "out.usdc", tags=True)
    assert tags2.pop("scheme") == "catmull-clark"
    assert np.array_equal(F2, F) and tags2["boundary"] == "edge-only"
    assert np.array_equal(tags2["creases"][0], edges) and tags2["creases"][1].tolist() == [10.0, 3.0]
    # To the bit what the library fits with the file's scheme and tags (the same solve), rounded to float32.
    library = sorpia.interpolate(V, F, scheme="catmull-clark", **tags).control_vertices
    assert np.array_equal(ctrl, library.astype(np.float32).astype(np.float64))
    limit = sorpia.limit_points(ctrl, F2, scheme="catmull-clark", **tags2)
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    assert np.abs(limit - V).max() < 1e-6 * diagonal  # float32 coordinates: a few ulps of the diagonal
    assert not np.array_equal(ctrl, V)


def test_fit_usd_scheme_auto_follows_the_file(command, tmp_path):
    """Triangles marked catmullClark are fitted with Catmull-Clark (auto would pick Loop for an OBJ)."""
    V, F = sorpia.shapes.icosphere(1)
    sorpia.write_mesh(tmp_path / "tri.usda", V, F, scheme="catmull-clark")
    code, out, err = command("fit", str(tmp_path / "tri.usda"), "-o", str(tmp_path / "out.usda"),
                             "--report", str(tmp_path / "r.json"))
    assert code == 0, err
    assert "Catmull-Clark" in out
    sorpia.write_mesh(tmp_path / "tri.usda", V, F, scheme="loop")
    code, out, err = command("fit", str(tmp_path / "tri.usda"), "-o", str(tmp_path / "out.obj"))
    assert code == 0 and "scheme      Loop" in out, err


def test_fit_several_meshes_needs_prim(command, tmp_path):
    V, F = sorpia.shapes.quad_grid(4, 4)
    stage = scene(tmp_path / "in.usda", V, F)
    UsdGeom.Mesh.Define(stage, "/Other")
    stage.Save()
    code, out, err = command("fit", str(tmp_path / "in.usda"), "-o", str(tmp_path / "out.usda"))
    assert_user_error(code, err)
    assert "2 Mesh prims (/World/Cage, /Other)" in err
    code, out, err = command("fit", str(tmp_path / "in.usda"), "-o", str(tmp_path / "out.usda"), "-q",
                             "--prim", "/World/Cage")
    assert code == 0, err
    stage = Usd.Stage.Open(str(tmp_path / "out.usda"))
    assert stage.GetPrimAtPath("/Other").IsA(UsdGeom.Mesh)


@pytest.mark.filterwarnings("default::sorpia.NonmanifoldWarning")  # printed by the command, as a user sees it
@pytest.mark.filterwarnings("default::sorpia.UsdWarning")
def test_fit_repair_blocks_primvars_that_no_longer_fit(command, tmp_path):
    """--nonmanifold sharp adds vertices: the per-vertex displayColor no longer fits and is blocked, said."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0], [1, 1, 1]], dtype=float)
    F = np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4], [0, 2, 5]], dtype=np.int32)  # edge 0-1 of three faces
    scene(tmp_path / "in.usda", V, F, scheme="loop")
    code, out, err = command("fit", str(tmp_path / "in.usda"), "-o", str(tmp_path / "out.usda"), "-q",
                             "--nonmanifold", "sharp")
    assert code == 0, err
    assert "primvars displayColor no longer fit them: blocked" in err
    stage = Usd.Stage.Open(str(tmp_path / "out.usda"))
    cage = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Cage"))
    assert len(cage.GetPointsAttr().Get()) > len(V)
    assert UsdGeom.PrimvarsAPI(cage.GetPrim()).GetPrimvar("displayColor").Get() is None


@pytest.mark.filterwarnings("default::sorpia.UsdWarning")  # printed by the command, as a user sees it
def test_repair_and_info_read_usd(command, tmp_path):
    """repair keeps the stage as fit does; info describes a USD mesh with its scheme and tags."""
    V, F = sorpia.shapes.quad_grid(4, 4)
    scene(tmp_path / "in.usda", V, np.vstack([F, F[:1]]), creases=(np.array([[5, 6]]), 4.0))  # a duplicated face
    code, out, err = command("repair", str(tmp_path / "in.usda"), "-o", str(tmp_path / "out.usda"))
    assert code == 0, err
    assert "primvars displayColor no longer fit them" in err  # the faces changed (the duplicate removed)
    stage = Usd.Stage.Open(str(tmp_path / "out.usda"))
    assert UsdGeom.Sphere(stage.GetPrimAtPath("/World/Ball")).GetRadiusAttr().Get() == 0.5
    _, F2, tags = sorpia.read_mesh(tmp_path / "out.usda", tags=True)
    assert np.array_equal(F2, F) and tags["creases"][0].tolist() == [[5, 6]]
    code, out, err = command("info", str(tmp_path / "out.usda"))
    assert code == 0, err
    assert "Catmull-Clark, boundary edge-and-corner" in out and "creases 1: 1 semi-sharp" in out
    code, out, err = command("info", str(tmp_path / "out.usda"), "--scheme", "loop")
    assert code == 0 and "Loop subdivision needs triangles; pass --scheme catmull-clark" in out, err
    sorpia.write_mesh(tmp_path / "loop.usda", V, F, scheme="loop")  # quads marked loop: refused by fit, said why
    code, out, err = command("fit", str(tmp_path / "loop.usda"), "-o", str(tmp_path / "o.usda"))
    assert_user_error(code, err)
    assert "needs triangles (the file's subdivisionScheme is loop); pass --scheme catmull-clark" in err


@pytest.mark.filterwarnings("default::sorpia.UsdWarning")  # printed by the command, as a user sees it
def test_fit_time_sampled_points_fits_one_time_and_says_so(command, tmp_path):
    """Time-sampled points: the default time is fitted (a warning says so) and the cage is written without
    samples, so that no other pose overrides it."""
    V, F = sorpia.shapes.quad_grid(5, 5)
    V = V.astype(np.float32).astype(np.float64)
    stage = scene(tmp_path / "in.usda", V, F)
    points = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Cage")).GetPointsAttr()
    points.Set(Vt.Vec3fArray.FromNumpy((V * 2).astype(np.float32)), 10.0)
    stage.Save()
    code, out, err = command("fit", str(tmp_path / "in.usda"), "-o", str(tmp_path / "out.usda"), "-q")
    assert code == 0, err
    assert "points has 1 time samples: read the default value" in err
    out_stage = Usd.Stage.Open(str(tmp_path / "out.usda"))
    cage = UsdGeom.Mesh(out_stage.GetPrimAtPath("/World/Cage"))
    assert cage.GetPointsAttr().GetNumTimeSamples() == 0
    ctrl = np.array(cage.GetPointsAttr().Get(10.0), dtype=np.float64)  # any time: the fitted cage
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    assert np.abs(sorpia.limit_points(ctrl, F, scheme="catmull-clark") - V).max() < 1e-6 * diagonal
