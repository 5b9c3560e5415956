"""nonmanifold="sharp": OpenSubdiv's rules for non-manifold topology. The split
itself is compared with Far's Limit() on the whole raw mesh in
tests/cpp/test_nonmanifold_sharp.cpp; here the public API is checked against
the closed forms of those rules (a corner row is the identity, an interior
non-manifold crease row 2/3 v + 1/6 of its two crease neighbours), against the
rows of the same mesh without its non-manifold parts (far from them nothing
changes), and the fit passes through every vertex. Meshes built in code, and
OpenSubdiv's non-manifold shapes of ../shared/meshes when present."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import sorpia
from sorpia import NonmanifoldWarning, _nonmanifold
from test_io import SHARED_MESHES


def book(pages, rows, triangles=True):
    """`pages` strips of 2 x `rows` quads (or their triangles) sharing the spine 0, 1, ..., rows: every spine
    edge non-manifold, its inner vertices on an interior non-manifold crease, its ends corners."""
    def vid(page, column, row):
        return row if column == 0 else (rows + 1) * (1 + 2 * page + column - 1) + row

    faces = []
    for page in range(pages):
        for c in range(2):
            for r in range(rows):
                a, b, cc, d = vid(page, c, r), vid(page, c + 1, r), vid(page, c + 1, r + 1), vid(page, c, r + 1)
                if page % 2:
                    b, d = d, b
                faces += [[a, b, cc], [a, cc, d]] if triangles else [[a, b, cc, d]]
    n = (rows + 1) * (1 + 2 * pages)
    x = np.random.default_rng(pages + rows).normal(size=(n, 3))
    return x, np.array(faces)


def sharp(call, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NonmanifoldWarning)
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        return call(*args, nonmanifold="sharp", **kwargs)


@pytest.mark.parametrize("scheme, triangles", [("loop", True), ("catmull-clark", False)])
def test_rows_are_opensubdivs_rules(scheme, triangles):
    v, f = book(3, 3, triangles)
    b = sharp(sorpia.limit_matrix, f, len(v), scheme=scheme).toarray()
    for corner in (0, 3):  # the spine's ends: identity rows
        assert np.array_equal(b[corner], np.eye(len(v))[corner])
    for v_, (a, c) in ((1, (0, 2)), (2, (1, 3))):  # inner spine vertices: the crease rule along the spine
        want = np.zeros(len(v))
        want[[v_, a, c]] = [2 / 3, 1 / 6, 1 / 6]
        assert np.abs(b[v_] - want).max() <= 1e-15
    # a vertex away from the spine has the row it has in its page alone (a manifold mesh)
    page = f[: len(f) // 3]
    far = 4 * 2 + 2  # column 2 of page 0, row 2: vid(0, 2, 2)
    used = np.unique(page)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        alone = sorpia.limit_matrix(page, len(v), scheme=scheme).toarray()
    assert far in used
    assert np.abs(b[far] - alone[far]).max() <= 1e-15
    # limit_points is B V
    assert np.abs(sharp(sorpia.limit_points, v, f, scheme=scheme) - b @ v).max() <= 1e-14


@pytest.mark.parametrize("scheme, triangles", [("loop", True), ("catmull-clark", False)])
def test_fit_passes_through_every_vertex(scheme, triangles):
    v, f = book(4, 3, triangles)
    res = sharp(sorpia.interpolate, v, f, scheme=scheme)
    assert res.converged and res.control_vertices.shape == v.shape
    b = sharp(sorpia.limit_matrix, f, len(v), scheme=scheme)
    assert np.abs(b @ res.control_vertices - v).max() <= 1e-8 * np.abs(v).max()


@pytest.mark.parametrize("scheme, triangles", [("loop", True), ("catmull-clark", False)])
@pytest.mark.parametrize("in_place", [False, True])
def test_interpolator_sharp_solves_and_updates_the_input_vertices(scheme, triangles, in_place):
    """Interpolator(nonmanifold="sharp") returns the one result type with the
    input vertices' rows, and update moves a target (all its copies in the
    split): each result equals scipy's direct solve of the input mesh's B
    (limit_matrix with nonmanifold="sharp") to 1e-8 (tol 1e-10 on E/E_0)."""
    import scipy.sparse.linalg

    v, f = book(4, 3, triangles)
    b = sharp(sorpia.limit_matrix, f, len(v), scheme=scheme).tocsc()
    interp = sharp(sorpia.Interpolator, f, len(v), scheme=scheme)
    assert interp.n_vertices == len(v)
    assert (abs(interp.limit_matrix() - b)).max() == 0
    res = interp.solve(v, initial=v)
    assert isinstance(res, sorpia.InterpolationResult) and res.converged
    targets = v.copy()
    for i in (1, 5, 0):  # a crease vertex (copied in every page), an ordinary one, a corner
        targets[i] += 0.1
        res = interp.update(res, [i], targets[i], in_place=in_place)
        assert res.converged and res.control_vertices.shape == v.shape
        direct = scipy.sparse.linalg.spsolve(b, targets)
        assert np.abs(res.control_vertices - direct).max() <= 1e-8 * np.abs(direct).max()
        np.testing.assert_array_equal(interp.targets, targets)
    whole = sharp(sorpia.interpolate, v, f, scheme=scheme)
    assert isinstance(whole, sorpia.InterpolationResult)


def test_bowtie_vertex_is_a_corner_and_warned():
    cones = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2], [0, 4, 5], [0, 5, 6], [0, 6, 4], [4, 6, 5]])
    v = np.random.default_rng(1).normal(size=(7, 3))
    with pytest.warns(NonmanifoldWarning, match="undefined"):
        limit = sorpia.limit_points(v, cones, nonmanifold="sharp")
    assert np.array_equal(limit[0], v[0])
    # vertex 1 is manifold: its row is that of the first cone alone
    alone = sorpia.limit_points(v[:4], cones[:4])
    assert np.abs(limit[1:4] - alone[1:4]).max() <= 1e-15


def test_default_error_names_both_ways_out():
    v, f = book(3, 2)
    with pytest.raises(sorpia.MeshError, match=r"non-manifold edge.*--repair.*--nonmanifold sharp"):
        sorpia.limit_points(v, f)
    with pytest.raises(sorpia.ParameterError, match="nonmanifold"):
        sorpia.limit_points(v, f, nonmanifold="smooth")


def test_a_manifold_mesh_is_unchanged_by_sharp():
    v, f = sorpia.shapes.icosphere(2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", NonmanifoldWarning)  # no warning: nothing non-manifold
        assert np.array_equal(sorpia.limit_points(v, f, nonmanifold="sharp"), sorpia.limit_points(v, f))


def test_what_the_split_refuses():
    v, f = book(3, 2, triangles=False)
    with pytest.raises(sorpia.MeshError, match="repeats vertex.*repair"):
        sharp(sorpia.limit_points, v, np.vstack([f, [[0, 0, 4, 5]]]), scheme="catmull-clark")


def test_a_sheet_of_one_face_at_a_crease_vertex_keeps_the_crease_rule():
    # a sheet of one quad over crease vertex 1: its copy there is a boundary vertex of one face, which
    # "edge-and-corner" would make a corner; OpenSubdiv gives vertex 1 the crease rule under both rules, and
    # makes the quad's free vertex (one face) a corner under "edge-and-corner" only
    v, f = book(3, 2, triangles=False)
    single = [list(q) for q in f] + [[0, 1, 2, len(v)]]
    w = np.vstack([v, [[0.0, 0.0, 9.0]]])
    crease = np.zeros(len(w))
    crease[[1, 0, 2]] = [2 / 3, 1 / 6, 1 / 6]
    rows = {rule: sharp(sorpia.limit_matrix, single, len(w), boundary=rule, scheme="catmull-clark").toarray()
            for rule in ("edge-and-corner", "edge-only")}
    for b in rows.values():
        assert np.abs(b[1] - crease).max() <= 1e-15
    assert np.array_equal(rows["edge-and-corner"][len(v)], np.eye(len(w))[len(v)])
    assert rows["edge-only"][len(v), len(v)] < 1
    res = sharp(sorpia.interpolate, w, single, scheme="catmull-clark", tol=1e-12)
    assert np.abs(rows["edge-and-corner"] @ res.control_vertices - w).max() <= 1e-9 * np.abs(w).max()


def test_tags_are_kept_away_from_the_crease():
    v, f = book(3, 3)
    # two crease edges through vertex 6, inside page 0 (its middle column): the crease rule there
    b = sharp(sorpia.limit_matrix, f, len(v), creases=([[5, 6], [6, 7]], 10.0)).toarray()
    want = np.zeros(len(v))
    want[[6, 5, 7]] = [2 / 3, 1 / 6, 1 / 6]
    assert np.abs(b[6] - want).max() <= 1e-15
    with pytest.raises(sorpia.MeshError, match="interior non-manifold crease"):
        sharp(sorpia.limit_matrix, f, len(v), creases=([[1, 4 * 1 + 1]], 10.0))


NONMAN = [SHARED_MESHES / name for name in ("osd_loop_nonman_edges.obj", "osd_loop_nonman_verts.obj",
                                            "osd_catmark_nonman_edges.obj", "osd_catmark_nonman_verts.obj")]


@pytest.mark.parametrize("path", NONMAN, ids=lambda p: p.name)
def test_opensubdiv_shapes_fit_through_their_vertices(path):
    if not path.exists():
        pytest.skip("../shared/meshes absent")
    v, f = sorpia.read_mesh(path)
    faces = f.tolist() if isinstance(f, np.ndarray) else [
        list(map(int, x)) for x in np.split(f.face_vertex_indices, np.cumsum(f.face_vertex_counts)[:-1])]
    faces = [x for x in faces if len(set(x)) == len(x)]  # faces that repeat a vertex: refused, left out
    scheme = "loop" if "loop" in path.name else "catmull-clark"
    if scheme == "loop":
        faces = np.array(faces)
    res = sharp(sorpia.interpolate, v, faces, scheme=scheme)
    b = sharp(sorpia.limit_matrix, faces, len(v), scheme=scheme)
    assert res.converged
    assert np.abs(b @ res.control_vertices - v).max() <= 1e-8 * np.abs(v).max()
    # every row is one diagonal weight and one equal weight on some neighbours (the form OpenSubdiv keeps)
    b = b.tocsr()
    for i in range(b.shape[0]):
        row = b.data[b.indptr[i]:b.indptr[i + 1]]
        off = row[b.indices[b.indptr[i]:b.indptr[i + 1]] != i]
        if scheme == "loop":
            assert len(off) == 0 or np.ptp(off) <= 1e-15


# shown as the command shows warnings (pytest's own filter would raise it)
@pytest.mark.filterwarnings("default::sorpia.NonmanifoldWarning")
def test_fit_on_the_command_line(tmp_path, monkeypatch, command):
    """sorpia fit --nonmanifold sharp writes the split control mesh with its corner tags: refitted from the file as
    it is, its limit passes through every input vertex at each of its copies."""
    from cli_support import write_obj

    monkeypatch.chdir(tmp_path)
    v, f = book(3, 3)
    write_obj(tmp_path / "book.obj", v, f)
    code, _, err = command("fit", "book.obj", "-o", "ctrl.obj")
    assert code != 0 and "--nonmanifold sharp" in err and "--repair" in err
    code, out, err = command("fit", "book.obj", "-o", "ctrl.obj", "--nonmanifold", "sharp", "--report", "r.json")
    assert code == 0, err
    assert "undefined" in err and "nonmanifold" in out
    report = json.loads((tmp_path / "r.json").read_text())["nonmanifold"]
    assert report["corners"] == [0, 3] and report["nonmanifold_vertices"] == [0, 1, 2, 3]
    ctrl, faces, tags = sorpia.read_mesh("ctrl.obj", tags=True)
    vertex_map = np.asarray(report["vertex_map"])
    assert sorted(vertex_map[tags["corners"][0]].tolist()) == [0] * 3 + [3] * 3  # every copy of the corners
    limit = sorpia.limit_points(ctrl, faces, corners=tags["corners"])
    assert np.abs(limit - v[vertex_map]).max() <= 1e-8 * np.abs(v).max()


@pytest.mark.filterwarnings("default::sorpia.NonmanifoldWarning")
def test_the_fan_shape_fits_on_the_command_line(tmp_path, command):
    """osd_catmark_fan.obj (quads fanned round edges of 3 and more faces): fit --nonmanifold sharp, the written
    split control mesh refitted as it is passes through every input vertex at each of its copies."""
    path = SHARED_MESHES / "osd_catmark_fan.obj"
    if not path.exists():
        pytest.skip("../shared/meshes absent")
    v, _ = sorpia.read_mesh(path)
    code, _, err = command("fit", path, "-o", tmp_path / "c.obj", "-q", "--nonmanifold", "sharp",
                           "--report", tmp_path / "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())["nonmanifold"]
    assert report["nonmanifold_edges"]
    ctrl, faces, tags = sorpia.read_mesh(tmp_path / "c.obj", tags=True)
    limit = sorpia.limit_points(ctrl, faces, scheme="catmull-clark", corners=tags["corners"])
    assert np.abs(limit - v[report["vertex_map"]]).max() <= 1e-9 * np.abs(v).max()


@pytest.mark.parametrize("scheme, triangles", [("loop", True), ("catmull-clark", False)])
def test_limit_surface_takes_nonmanifold_sharp(scheme, triangles):
    # LimitSurface, evaluate_limit and limit_surface with nonmanifold="sharp": at every face corner (Bfr) and in the
    # tessellation's first rows the surface of the input vertices is B V with B = limit_matrix(nonmanifold="sharp")
    # (independent of the surface code: the rows are checked against OpenSubdiv's rules above); 1e-12 of the
    # coordinates' size is rounding.
    v, f = book(3, 2, triangles)
    b = sharp(sorpia.limit_matrix, f, len(v), scheme=scheme)
    want = b @ v
    corners = [0.0, 0.0], [1.0, 0.0], ([0.0, 1.0] if triangles else [1.0, 1.0])
    face_ids = np.repeat(np.arange(len(f)), 3)
    uv = np.tile(np.array(corners), (len(f), 1))
    vertex_at = f[:, [0, 1, 2]].ravel()  # (0,0), (1,0) and the third corner of each face
    got = sharp(sorpia.evaluate_limit, v, f, face_ids, uv, scheme=scheme)
    assert np.abs(got - want[vertex_at]).max() <= 1e-12 * np.abs(v).max()
    surface = sharp(sorpia.LimitSurface, v, f, scheme=scheme)
    surface.set_vertices(2 * v)  # the input's rows, mapped onto the split's copies
    assert np.abs(surface.evaluate(face_ids, uv) - 2 * want[vertex_at]).max() <= 1e-12 * np.abs(v).max()
    vs, _ = sharp(sorpia.limit_surface, v, f, level=1, scheme=scheme)
    assert np.abs(vs[: len(v)] - want).max() <= 1e-12 * np.abs(v).max()
    with pytest.raises(sorpia.MeshError, match="non-manifold"):
        sorpia.LimitSurface(v, f, scheme=scheme)


@pytest.mark.parametrize("scheme, faces", [("loop", [[0, 1, 2], [0, 2, 1], [0, 1, 3]]),
                                           ("catmull-clark", [[0, 1, 2, 3], [0, 3, 2, 1], [0, 1, 4, 5]])])
def test_pillow_beside_a_third_face_keeps_its_edge_sharp(scheme, faces):
    # Edge (0, 1) has three faces: OpenSubdiv makes it infinitely sharp and its ends corners, so the limit surface
    # along it is the segment from vertex 0 to vertex 1 (the crease rule puts every refined point of the edge on it)
    # on each of its faces, the pillow's two (joined again in the split) included. 1e-12 of the coordinates' size is
    # rounding; the pillow's faces left smooth there bulged off it by about 0.2.
    f = np.array(faces)
    v = np.random.default_rng(5).normal(size=(f.max() + 1, 3))
    surface = sharp(sorpia.LimitSurface, v, f, scheme=scheme)
    t = np.linspace(0.0, 1.0, 9)
    along = np.column_stack([t, np.zeros_like(t)])  # from corner 0 (vertex 0) to corner 1 (vertex 1)
    back = along[:, ::-1]  # the pillow's second face runs (0, ..., 1): from its last corner (vertex 1) to vertex 0
    direction = (v[1] - v[0]) / np.linalg.norm(v[1] - v[0])
    for face, uv in ((0, along), (1, back), (2, along)):
        p = surface.evaluate(np.full(len(t), face), uv) - v[0]
        off_line = p - np.outer(p @ direction, direction)
        assert np.abs(off_line).max() <= 1e-12 * np.abs(v).max(), face
    with pytest.warns(NonmanifoldWarning):
        split = _nonmanifold.split(f, len(v))
    assert split.report["sharp_edges"] == [[0, 1]]
    edges, sharpness = split.tags["creases"]
    assert edges.tolist() == [[0, 1]] and (sharpness >= 10).all()  # OpenSubdiv's infinite sharpness (Sdc: 10)
