"""Repair of meshes whose sheets no orientation fits (issue 20, item 4): the
faces of a hexahedral grid (interior edges of four faces), closed boxes
touching along edges (a CAD model's parts), Moebius bands and a Klein bottle,
as quads and as triangles, all built in code. Checked independently of
sorpia's validation: every output sheet is consistently oriented and
manifold (test_fuzz.mesh_problems: each directed edge once, at most two faces
an edge, one fan a vertex), every vertex is its input vertex bit for bit,
every face its input face (reversed exactly where the report says), every
edge the report says was cut really separates its faces; and the fit of the
repaired mesh (its Interpolator, its scipy direct solve and its limit points)
passes through every input vertex at each copy. --nonmanifold sharp fits the
same files, under either boundary rule, the one given winning over the
file's."""

from __future__ import annotations

import itertools
import json
import warnings

import numpy as np
import pytest
import scipy.sparse.linalg

import sorpia
from sorpia._nonmanifold import NonmanifoldWarning
from test_fuzz import cycle, face_lists, mesh_problems
from test_repair_polygons import check_repaired

# The six quads of the unit cube at `corner`, outward, as offsets (x, y, z).
CUBE_QUADS = [[(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)], [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
              [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)], [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)],
              [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)], [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)]]


class Lattice:
    """Vertices on the integer lattice, numbered as first used, so that faces of several parts weld."""

    def __init__(self):
        self.ids: dict = {}

    def quad(self, cell, k):
        """Quad k of CUBE_QUADS of the unit cell at `cell`."""
        return [self.ids.setdefault(tuple(np.add(cell, d).tolist()), len(self.ids)) for d in CUBE_QUADS[k]]

    def vertices(self, seed=0):
        """The lattice points, moved off the lattice a little (no flat rings: B stays far from singular)."""
        p = np.array(sorted(self.ids, key=self.ids.get), float)
        return p + np.random.default_rng(seed).normal(scale=0.05, size=p.shape)


def orient(faces, how, v, seed=0):
    """Faces as built ("outward"), each with its normal along +x, +y or +z ("axis", as a grid exporter
    writes them), or half of them reversed at random ("random")."""
    faces = [list(f) for f in faces]
    if how == "axis":
        return [f if np.cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]]).sum() > 0 else f[::-1] for f in faces]
    if how == "random":
        flip = np.random.default_rng(seed).random(len(faces)) < 0.5
        return [f[::-1] if s else f for f, s in zip(faces, flip)]
    return faces


def hex_grid_faces(n, how="outward"):
    """Every quad face of every hex of an n x n x n grid once: interior edges of 4 faces, edges of 3 on
    the sides."""
    lat, faces, seen = Lattice(), [], set()
    for cell in itertools.product(range(n), repeat=3):
        for k in range(6):
            q = lat.quad(cell, k)
            if frozenset(q) not in seen:
                seen.add(frozenset(q))
                faces.append(q)
    v = lat.vertices()
    return v, np.array(orient(faces, how, v))


def boxes_on_edges(how="outward"):
    """Four closed 2 x 2 x 2 boxes (24 quads each) in a checkerboard: each two touch along an edge (two
    lattice edges of four faces), all four at the centre vertex; the second box inward."""
    lat, faces = Lattice(), []
    for b, origin in enumerate([(0, 0, 0), (2, 2, 0), (2, 0, 2), (0, 2, 2)]):
        for cell in itertools.product(range(2), repeat=3):
            for k in range(6):  # CUBE_QUADS[k] lies on side k % 2 of axis (z, z, y, y, x, x)[k]
                if cell[(2, 2, 1, 1, 0, 0)[k]] == k % 2:  # on the box's surface
                    q = lat.quad(np.add(origin, cell), k)
                    faces.append(q[::-1] if b == 1 else q)
    v = lat.vertices()
    return v, np.array(orient(faces, how, v))


def moebius_band(n, w):
    """A Moebius band n quads long and w wide, (n, j) glued to (0, w - j)."""
    def vid(i, j):
        return i * (w + 1) + j if i < n else w - j

    t = 2 * np.pi * np.arange(n) / n
    s = np.arange(w + 1) / w - 0.5
    r = 2 + s[None, :] * np.cos(t / 2)[:, None]
    v = np.stack([r * np.cos(t)[:, None], r * np.sin(t)[:, None], s[None, :] * np.sin(t / 2)[:, None]], -1)
    return v.reshape(-1, 3), np.array([[vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)]
                                        for i in range(n) for j in range(w)])


def klein_bottle(n, m):
    """A closed non-orientable surface of n m quads: (i, j) mod (n, m), (n, j) glued to (0, -j)."""
    def vid(i, j):
        return (0 if i == n else i) * m + (-j if i == n else j) % m

    v = np.random.default_rng(1).normal(size=(n * m, 3))
    return v, np.array([[vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)]
                        for i in range(n) for j in range(m)])


def triangles(faces):
    """Each quad (a, b, c, d) as (a, b, c), (a, c, d), for Loop."""
    f = np.asarray(faces)
    return np.vstack([f[:, [0, 1, 2]], f[:, [0, 2, 3]]])


def scheme_of(faces):
    return "loop" if np.asarray(faces).shape[1] == 3 else "catmull-clark"


def check_cuts(faces, result):
    """What the report says was cut is: each cut edge of two faces, and each pair left apart at a
    non-manifold edge, separates its faces at the output (no output edge joins two faces of one cut input
    edge unless both keep it as an edge of its own), and the vertex count adds up."""
    r = result.changes
    n = int(np.max(faces)) + 1
    assert len(result.vertices) == n + r["counts"]["sheet_copies"] + r["counts"]["bowtie_copies"] + \
        r["counts"]["cut_copies"]
    assert set(map(tuple, r["cut_nonmanifold_edges"])) <= set(map(tuple, r["nonmanifold_edges"]))
    out = face_lists(result.faces)
    users: dict = {}
    for j, f in enumerate(out):
        for a, b in zip(f, f[1:] + f[:1]):
            users.setdefault((min(a, b), max(a, b)), []).append(j)
    by_input: dict = {}
    for (a, b), js in users.items():
        p, q = sorted((int(result.vertex_map[a]), int(result.vertex_map[b])))
        by_input.setdefault((p, q), []).append(len(js))
    for e in map(tuple, r["cut_edges"]):
        # the two faces of a cut edge are on two output edges, one face each
        assert by_input[e] == [1, 1], (e, by_input[e])
    for e in map(tuple, r["cut_nonmanifold_edges"]):
        assert len(by_input[e]) >= 2, e


def check_fit(v, result):
    """The repaired mesh interpolated: its control vertices solve B x = V0 (B = sorpia.limit_matrix, V0 the
    input vertex of each output vertex) as scipy's direct solve does, and its limit points are the input
    vertices. Tolerances: the solve's tol (1e-12 relative) times the condition of these small B (< 1e3)."""
    scheme = "loop" if all(len(f) == 3 for f in face_lists(result.faces)) else "catmull-clark"
    target = np.asarray(v, float)[result.vertex_map]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sorpia.UnreferencedVerticesWarning)
        fit = sorpia.interpolate(result.vertices, result.faces, scheme=scheme, tol=1e-12, max_iter=5000)
        b = sorpia.limit_matrix(result.faces, len(result.vertices), scheme=scheme).tocsc()
        limit = sorpia.limit_points(fit.control_vertices, result.faces, scheme=scheme)
    assert fit.converged
    direct = scipy.sparse.linalg.spsolve(b, target)
    scale = np.abs(target).max()
    assert np.abs(b @ direct - target).max() <= 1e-12 * scale  # B is invertible here
    assert np.abs(fit.control_vertices - direct).max() <= 1e-8 * scale
    assert np.abs(limit - target).max() <= 1e-9 * scale


def repaired(v, f):
    r = sorpia.repair(v, f)
    check_repaired(v, f, r)  # valid and oriented (independently), vertices bit for bit, faces up to flips
    check_cuts(f, r)
    return r


MESHES = {
    "hex-grid": lambda: hex_grid_faces(2),
    "hex-grid-axis": lambda: hex_grid_faces(2, "axis"),
    "hex-grid-random": lambda: hex_grid_faces(2, "random"),
    "boxes": boxes_on_edges,
    "boxes-axis": lambda: boxes_on_edges("axis"),
    "boxes-random": lambda: boxes_on_edges("random"),
}


@pytest.mark.parametrize("tri", [False, True], ids=["quads", "triangles"])
@pytest.mark.parametrize("name", sorted(MESHES))
def test_sheets_that_no_orientation_fits_are_cut_and_fit(name, tri):
    v, f = MESHES[name]()
    if tri:
        f = triangles(f)
    r = repaired(v, f)
    assert r.changes["nonmanifold_edges"] and not r.changes["cut_edges"]  # cut at non-manifold edges only
    assert r.changes["counts"]["degenerate_faces"] + r.changes["counts"]["duplicate_faces"] == 0
    assert len(r.face_map) == len(f)  # no face lost
    if name == "hex-grid" and not tri:
        # its first hex's faces pair into a closed hexahedron of its own: a cube of valence-3 vertices, whose
        # Catmull-Clark B has the checkerboard null vector (sorpia.limit.singular_cubes); no fit to check
        b = sorpia.limit_matrix(r.faces, len(r.vertices), scheme="catmull-clark").toarray()
        assert np.linalg.matrix_rank(b) < len(b)
        return
    check_fit(v, r)


def test_the_grids_that_were_refused_are_cut_at_some_non_manifold_edges():
    # the faces of a hex grid with normals along the axes: pairing its sheets in face order alone makes a
    # part no orientation fits; some pairs are left apart (each face bordering the edge alone), not all
    v, f = hex_grid_faces(2, "axis")
    r = repaired(v, f)
    assert 0 < len(r.changes["cut_nonmanifold_edges"]) < len(r.changes["nonmanifold_edges"])


def test_sheets_that_orient_are_not_cut():
    # outward boxes: every pair made at an edge of four faces runs it both ways; nothing to cut or flip
    v, f = boxes_on_edges()
    r = repaired(v, f)
    assert not r.changes["cut_nonmanifold_edges"] and not r.changes["flipped_faces"]


def test_mixed_orientation_that_is_orientable_is_flipped_not_cut():
    v, f = hex_grid_faces(3)
    surface = [q for q in f.tolist() if sum(np.ptp(v[q], axis=0) > 0.5) == 2 and
               any(np.all(np.abs(v[q][:, a] - e) < 0.5) for a in range(3) for e in (0, 3))]
    surface = np.array(surface)  # the closed outer surface of the grid (54 quads), outward
    bad = surface.copy()
    bad[[3, 10, 11, 40]] = bad[[3, 10, 11, 40]][:, ::-1]
    r = repaired(v, bad)
    assert r.changes["flipped_faces"] == [3, 10, 11, 40] and not r.changes["cut_edges"]
    assert [cycle(q) for q in face_lists(r.faces)] == [cycle(q) for q in surface.tolist()]  # as built
    check_fit(v, r)


@pytest.mark.parametrize("tri", [False, True], ids=["quads", "triangles"])
@pytest.mark.parametrize("width", [1, 3, 6])
def test_a_moebius_band_is_cut_across_along_a_short_path(width, tri):
    v, f = moebius_band(12, width)
    if tri:
        f = triangles(f)
    assert mesh_problems(f, len(v)) == {"inconsistent orientation"}
    r = repaired(v, f)
    cut = r.changes["cut_edges"]
    # across the band, from one side to the other: at least `width` edges (the narrowest cut), and a step or
    # two more where the search from the middle of the band meets itself
    assert width <= len(cut) <= width + 2
    assert not r.changes["nonmanifold_edges"]
    check_fit(v, r)


def test_a_klein_bottle_is_cut_along_a_closed_path():
    v, f = klein_bottle(8, 6)
    r = repaired(v, f)
    cut = r.changes["cut_edges"]
    degree = np.bincount(np.ravel(cut), minlength=len(v))
    assert len(cut) <= 2 * 8 and set(degree[degree > 0].tolist()) == {2}  # a closed path: no end
    check_fit(v, r)


def sharp(call, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NonmanifoldWarning)
        return call(*args, nonmanifold="sharp", **kwargs)


@pytest.mark.parametrize("tri", [False, True], ids=["quads", "triangles"])
@pytest.mark.parametrize("name", ["hex-grid", "hex-grid-axis", "boxes", "boxes-axis"])
def test_the_same_files_fit_with_nonmanifold_sharp(name, tri):
    v, f = MESHES[name]()
    if tri:
        f = triangles(f)
    scheme = scheme_of(f)
    res = sharp(sorpia.interpolate, v, f, scheme=scheme, tol=1e-12)
    b = sharp(sorpia.limit_matrix, f, len(v), scheme=scheme).tocsc()
    assert res.converged
    direct = scipy.sparse.linalg.spsolve(b, v)
    assert np.abs(b @ res.control_vertices - v).max() <= 1e-9 * np.abs(v).max()
    assert np.abs(res.control_vertices - direct).max() <= 1e-8 * np.abs(v).max()


@pytest.mark.filterwarnings("default::sorpia.NonmanifoldWarning")
def test_hex_grid_file_fits_with_repair_and_with_nonmanifold_sharp(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    v, f = hex_grid_faces(2, "axis")
    sorpia.write_mesh("hex.obj", v, f)
    code, out, err = command("fit", "hex.obj", "-o", "ctrl.obj", "--repair", "--report", "r.json", "--tol", "1e-12")
    assert code == 0, err
    assert "no orientation fits" in out
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["repair"]["report"]["cut_nonmanifold_edges"] == sorpia.repair(v, f).changes["cut_nonmanifold_edges"]
    ctrl, faces = sorpia.read_mesh("ctrl.obj")
    target = v[np.asarray(data["repair"]["vertex_map"])]
    assert np.abs(sorpia.limit_points(ctrl, faces, scheme="catmull-clark") - target).max() <= 1e-9 * np.abs(v).max()
    code, _, err = command("fit", "hex.obj", "-o", "split.obj", "--nonmanifold", "sharp", "--report", "s.json",
                           "--tol", "1e-12")
    assert code == 0, err
    vertex_map = np.asarray(json.loads((tmp_path / "s.json").read_text())["nonmanifold"]["vertex_map"])
    ctrl, faces, tags = sorpia.read_mesh("split.obj", tags=True)  # refitted from the file as it is
    limit = sorpia.limit_points(ctrl, faces, scheme="catmull-clark", **tags)
    assert np.abs(limit - v[vertex_map]).max() <= 1e-9 * np.abs(v).max()


@pytest.mark.filterwarnings("default::sorpia.NonmanifoldWarning")
@pytest.mark.parametrize("in_file, option", [("edge-and-corner", "edge-only"), ("edge-only", "edge-and-corner")])
def test_nonmanifold_sharp_takes_the_boundary_option_over_the_file(tmp_path, monkeypatch, command, in_file, option):
    """Issue 20, item 5: --boundary wins over the file's 't interpolateboundary' under --nonmanifold sharp:
    the written split control mesh is the Python call's with that rule (and not the file's rule's), and its
    limit, refitted from the file as it is (its tags, its rule), passes through every input vertex at each
    copy."""
    from test_nonmanifold import book

    monkeypatch.chdir(tmp_path)
    # pages of quads on a spine, and a sheet of one quad over its crease vertex 1: the split depends on the rule
    # (that quad's copy of 1 keeps the crease rule; edge-and-corner makes its free vertex, of one face, a corner)
    v, f = book(3, 2, triangles=False)
    f = [list(q) for q in f] + [[0, 1, 2, len(v)]]
    v = np.vstack([v, [[0.5, -0.3, 2.0]]])
    sorpia.write_mesh("book.obj", v, f, boundary=in_file)
    code, _, err = command("fit", "book.obj", "-o", "split.obj", "--nonmanifold", "sharp", "--boundary", option,
                           "--report", "s.json", "--tol", "1e-12")
    assert code == 0, err
    vertex_map = np.asarray(json.loads((tmp_path / "s.json").read_text())["nonmanifold"]["vertex_map"])
    ctrl, faces, tags = sorpia.read_mesh("split.obj", tags=True)
    python = {rule: sharp(sorpia.interpolate, v, f, scheme="catmull-clark", boundary=rule, tol=1e-12)
              for rule in (in_file, option)}
    scale = np.abs(v).max()
    # both solve the same system to tol 1e-12: equal to its condition times that; the other rule is far off
    assert np.abs(ctrl[: len(v)] - python[option].control_vertices).max() <= 1e-9 * scale
    assert np.abs(ctrl[: len(v)] - python[in_file].control_vertices).max() >= 1e-3 * scale
    assert np.abs(ctrl - ctrl[vertex_map]).max() <= 1e-9 * scale  # each copy is its vertex's control point
    limit = sorpia.limit_points(ctrl, faces, scheme="catmull-clark", **tags)
    assert np.abs(limit - v[vertex_map]).max() <= 1e-9 * scale
