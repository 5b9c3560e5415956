"""Fair interpolation (sorpia.fair_interpolate): the refined control mesh and
its tags against OpenSubdiv's own surfaces, the solve against a dense KKT
solve with numpy, the targets through Bfr on the fine mesh, and bad input."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
import scipy.sparse

import sorpia
from sorpia import fair
from sorpia.errors import MeshError, ParameterError
from sorpia.surface import corner_uv

# Loop's child triangle j of a parent (a, b, c) in the parent's (u, v):
# corners 0..2 keep their corner first, child 3 is the middle one (Far's
# TriRefinement, as surface.cpp walks it).
LOOP_CHILD = np.array([[[0, 0], [0.5, 0], [0, 0.5]], [[0.5, 0], [1, 0], [0.5, 0.5]],
                       [[0, 0.5], [0.5, 0.5], [0, 1]], [[0.5, 0.5], [0, 0.5], [0.5, 0]]])
SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)


def diagonal(v):
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))


def noisy(vertices, scale, seed):
    rng = np.random.default_rng(seed)
    return np.asarray(vertices, float) + scale * rng.standard_normal(np.shape(vertices))


def face_rows(faces):
    return [list(f) for f in faces] if not isinstance(faces, np.ndarray) else faces.tolist()


def tagged(scheme):
    """A noisy mesh of each scheme with a boundary, semi-sharp and infinitely
    sharp creases, a semi-sharp corner and a hole; Catmull-Clark with a
    hexagon and two triangles among its quads."""
    if scheme == "loop":
        v, f = sorpia.shapes.grid(7, 6)
        f = np.asarray(f)
    else:
        v, f = sorpia.shapes.quad_grid(7, 6)
        f = face_rows(f)
        a, b = f[0], f[1]  # (a0, a1, a2, a3) and (a3, a2, b2, b3) share the edge a2-a3: one hexagon
        assert (b[0], b[1]) == (a[3], a[2])
        f[0] = [a[0], a[1], a[2], b[2], b[3], a[3]]
        del f[1]
        q = f[10]
        f[10:11] = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    v = noisy(v, 0.03, 7)
    v[:, 2] += 0.2 * np.sin(3 * v[:, 0]) * np.cos(2 * v[:, 1])
    rows = face_rows(f)
    creases = (np.array([[rows[3][0], rows[3][1]], [rows[12][1], rows[12][2]], [rows[20][0], rows[20][1]]]),
               np.array([1.5, np.inf, 2.3]))
    corners = (np.array([rows[17][2]]), np.array([2.7]))
    return v, f, dict(scheme=scheme, creases=creases, corners=corners, holes=np.array([25]))


def fine_energy(res, thin_plate=1.0, membrane=0.0):
    """K of the fine mesh with its tags (sorpia.fairness_matrix, with
    fair_interpolate's default depth 0), dense."""
    return sorpia.fairness_matrix(res.faces, len(res.control_vertices), thin_plate=thin_plate, membrane=membrane,
                                  depth=0, **fine_kwargs(res)).toarray()


def fine_kwargs(res):
    return dict(scheme=res.scheme, boundary=res.boundary, **res.tags)


# ---- the refined mesh ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
@pytest.mark.parametrize("levels", [1, 2])
def test_the_refined_mesh_has_the_coarse_limit_surface_at_its_vertices(scheme, boundary, levels):
    # R V on the fine mesh with the carried tags: its limit positions (the
    # fine mesh's B, sorpia.limit_points) are the coarse surface's at the
    # level-L vertices, which the coarse tessellation gives from Far's own
    # refinement and Limit(); vertex i < n is the child of input vertex i, at
    # B V. 1e-12 of the size: both sides are a few weighted sums.
    v, f, kw = tagged(scheme)
    res = sorpia.fair_interpolate(v, f, levels=levels, boundary=boundary, **kw)
    assert res.creases is not None and res.corners is not None and res.holes is not None
    fine = res.refinement @ v
    tess_v, _ = sorpia.LimitSurface(v, f, boundary=boundary, **kw).tessellate(levels)
    assert len(tess_v) == len(fine)
    got = sorpia.limit_points(fine, res.faces, **fine_kwargs(res))
    assert np.abs(got - tess_v).max() <= 1e-12 * diagonal(v)
    assert np.allclose(got[:len(v)], sorpia.limit_points(v, f, boundary=boundary, **kw), rtol=0, atol=1e-12)


def level_one_parameters(scheme, coarse_faces, fine_faces, st):
    """(coarse face, (u, v)) of the point (s, t) of each level-1 face. The
    children of face f come in one block (Far's order), child j at f's corner
    j: a triangle's or a quad's child lists that corner at its own position j
    (a quad's others: the midpoint of edge j, the centre, the midpoint of
    edge j - 1), a k-gon's child is sub-face j, corner j first. Checked: the
    child holds corner j's child, which keeps corner j's index, there."""
    rows = face_rows(coarse_faces)
    out_face, out_uv = [], []
    k = 0
    for f, corners in enumerate(rows):
        n_children = 4 if scheme == "loop" else len(corners)
        for j in range(n_children):
            child = fine_faces[k]
            if scheme == "loop":
                a, b, d = LOOP_CHILD[j]
                if j < 3:
                    assert child[j] == corners[j]
            elif len(corners) == 4:
                assert child[j] == corners[j]
                cj = SQUARE[j]
                image = [cj, (cj + SQUARE[(j + 1) % 4]) / 2, np.array([0.5, 0.5]), (cj + SQUARE[(j + 3) % 4]) / 2]
                a, b, d = image[(0 - j) % 4], image[(1 - j) % 4], image[(3 - j) % 4]
            else:
                assert child[0] == corners[j]
                a = np.array(corner_uv("catmull-clark", len(corners), j))
                b, d = a + [0.5, 0], a + [0, 0.5]
            s, t = st[k]
            out_face.append(f)
            out_uv.append(a + (np.asarray(b) - a) * s + (np.asarray(d) - a) * t)
            k += 1
    assert k == len(fine_faces)
    return np.array(out_face, np.int32), np.array(out_uv)


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
def test_the_refined_surface_is_the_coarse_surface_at_random_points(scheme):
    # Bfr on both meshes at random points of every fine face (not a hole),
    # mapped to the coarse face's parameters; away from the face corners
    # ((s, t) in [0.2, 0.8]), where Bfr's Gregory patches at extraordinary
    # vertices (corner pieces of side 1/16 of a face, not the same region on
    # the two meshes) would differ, both are the same polynomial pieces of
    # the one surface: 1e-12 of the size.
    v, f, kw = tagged(scheme)
    res = sorpia.fair_interpolate(v, f, **kw)
    rng = np.random.default_rng(3)
    st = rng.uniform(0.2, 0.8, size=(len(res.faces), 2))
    if scheme == "loop":
        st[:, 1] *= 1 - st[:, 0]  # inside the triangle
    face_ids, uv = level_one_parameters(scheme, f, res.faces, st)
    keep = ~np.isin(np.arange(len(res.faces)), res.holes)
    coarse = sorpia.LimitSurface(v, f, **kw).evaluate(face_ids[keep], uv[keep])
    fine = sorpia.LimitSurface(res.refinement @ v, res.faces, **fine_kwargs(res)).evaluate(
        np.flatnonzero(keep).astype(np.int32), st[keep])
    assert np.abs(coarse - fine).max() <= 1e-12 * diagonal(v)


def test_tags_are_decayed_as_far_carries_them():
    # One semi-sharp crease of 2.3 on a closed mesh: level 1 carries its two
    # child edges at 1.3 (Far keeps float sharpness), level 2 four at 0.3,
    # level 3 none; an infinitely sharp one stays infinite at every level.
    v, f = sorpia.shapes.icosphere(0)
    edge = np.array([[f[0][0], f[0][1]]])
    for sharpness, levels, count, value in [(2.3, 1, 2, 1.3), (2.3, 2, 4, 0.3), (2.3, 3, 0, None),
                                            (np.inf, 3, 8, sorpia._core.INFINITE_SHARPNESS)]:
        res = sorpia.fair_interpolate(v, f, levels=levels, creases=(edge, sharpness))
        if count == 0:
            assert res.creases is None
            continue
        edges, s = res.creases
        assert len(s) == count and np.allclose(s, value, atol=1e-6)
        assert res.corners is None and res.holes is None


def test_vertex_children_are_not_in_each_others_limit_masks():
    # The observation the solve relies on: from level 1 on, the fine B
    # restricted to the input vertices' children is diagonal (each one's
    # limit mask covers only edge and face children), with semi-sharp and
    # infinitely sharp tags too. Read from sorpia.limit_matrix of the fine mesh.
    for scheme in ("loop", "catmull-clark"):
        v, f, kw = tagged(scheme)
        res = sorpia.fair_interpolate(v, f, **kw)
        b = sorpia.limit_matrix(res.faces, len(res.control_vertices), **fine_kwargs(res)).tocsr()
        block = b[:len(v)][:, :len(v)]
        assert (block - scipy.sparse.diags(block.diagonal())).count_nonzero() == 0


# ---- the solve ------------------------------------------------------------------------------------------------


def dense_kkt(res, targets_xyz, k):
    """min tr(V^T K V) subject to B_t V = T by numpy's dense solve of the KKT system."""
    n = len(res.control_vertices)
    b = sorpia.limit_matrix(res.faces, n, **fine_kwargs(res)).toarray()[res.targets]
    m = len(res.targets)
    kkt = np.block([[2 * k, b.T], [b, np.zeros((m, m))]])
    rhs = np.vstack([np.zeros((n, 3)), targets_xyz])
    return np.linalg.solve(kkt, rhs)[:n]


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
@pytest.mark.parametrize("partial", [False, True])
def test_the_solve_is_the_dense_kkt_solution(scheme, partial):
    # The conjugate gradients on the eliminated system against numpy's direct
    # KKT solve, with creases, a corner and a hole, every vertex or half of
    # them as targets; tol 1e-14 leaves the iteration at rounding level:
    # same control mesh to 1e-9 of the size.
    v, f, kw = tagged(scheme)
    targets = np.arange(0, len(v), 2) if partial else None
    res = sorpia.fair_interpolate(v, f, targets=targets, tol=1e-14, membrane=0.1, **kw)
    assert res.converged
    ref = dense_kkt(res, v[res.targets], fine_energy(res, membrane=0.1))
    assert np.abs(res.control_vertices - ref).max() <= 1e-9 * diagonal(v)



@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
@pytest.mark.parametrize("partial", [False, True])
def test_the_default_stopping_rule_leaves_the_energy_within_tol_of_the_minimum(scheme, partial):
    # The default tol (1e-6) bounds how far the energy is above the least
    # energy, which the dense KKT solve gives: relative excess within tol
    # (the rule's estimate is a lower bound, close when the energy falls
    # fast; here the excess is about 1e-8 at most). The vertices lie within
    # 1e-4 of the size of the minimiser's (4e-5 at most here: the energy's
    # excess is quadratic in their distance, so it settles well before they
    # do), the targets exact whatever the iteration stops at.
    v, f, kw = tagged(scheme)
    targets = np.arange(0, len(v), 2) if partial else None
    res = sorpia.fair_interpolate(v, f, targets=targets, **kw)
    assert res.converged
    k = fine_energy(res)
    ref = dense_kkt(res, v[res.targets], k)
    least = float(np.trace(ref.T @ k @ ref))
    assert least <= res.energy <= least * (1 + 1e-6)
    assert np.abs(res.control_vertices - ref).max() <= 1e-4 * diagonal(v)
    assert res.max_error_relative <= 1e-13


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
def test_the_start_is_the_plain_control_mesh_refined(scheme):
    # The start R V_plain comes from Far's PrimvarRefiner level by level, R
    # (FairResult.refinement, built on first access and kept) from Far's
    # stencil tables factorised over the levels: the same weights by two
    # paths, so the same points to rounding (1e-14 of the size), on two
    # levels with tags.
    v, f, kw = tagged(scheme)
    res = sorpia.fair_interpolate(v, f, levels=2, max_iter=1, **kw)
    options = dict(boundary="edge-and-corner", **kw)
    topology = sorpia.solve.Interpolator._for_vertices(f, len(v), options, "error").topology
    rules = sorpia._validate.as_rules(f, len(v), **options)[2]
    plain = np.asarray(res.plain.control_vertices)
    got = sorpia._core.refine_uniform(topology, rules, 2, vertices=plain, refinement=False)
    assert "refinement" not in got
    assert res.refinement is res.refinement
    assert res.refinement.shape == (len(res.control_vertices), len(v))
    assert np.abs(got["vertices"] - res.refinement @ plain).max() <= 1e-14 * diagonal(v)


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
def test_the_reference_metric_solve_is_the_dense_kkt_solution(scheme):
    # metric="reference": K measured in the input mesh's own limit surface
    # (the input refined, R V0), the same constrained minimum as a dense KKT
    # solve with that K from sorpia.fairness_matrix.
    v, f = (sorpia.shapes.icosphere(1) if scheme == "loop" else sorpia.shapes.quad_torus(8, 6))
    v = np.asarray(v, float) + 0.03 * np.random.default_rng(7).standard_normal(np.shape(v))
    res = sorpia.fair_interpolate(v, f, scheme=scheme, metric="reference", tol=1e-14)
    assert res.converged
    k = sorpia.fairness_matrix(res.faces, len(res.control_vertices), scheme=scheme, depth=0,
                               reference=res.refinement @ v).toarray()
    ref = dense_kkt(res, v[res.targets], k)
    assert np.abs(res.control_vertices - ref).max() <= 1e-9 * diagonal(v)  # as the parametric test above


@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
def test_the_targets_are_met_through_bfr_on_the_fine_mesh(scheme):
    # OpenSubdiv's Bfr on the fine mesh at a face corner of each target's
    # vertex (its limit position) gives the target: 1e-10 of the size, as
    # interpolate's tolerance; the non-targets are free.
    v, f, kw = tagged(scheme)
    targets = np.arange(1, len(v), 3)
    res = sorpia.fair_interpolate(v, f, targets=targets, **kw)
    faces = np.asarray(res.faces)
    face_ids, uv, shown = [], [], []
    for t in targets:
        around = [(face, corner) for face, corner in np.argwhere(faces == t) if face not in res.holes]
        if around:  # a vertex inside the hole has no surface to show it
            face_ids.append(around[0][0])
            uv.append(corner_uv(res.scheme, faces.shape[1], int(around[0][1])))
            shown.append(t)
    assert len(shown) >= len(targets) - 2
    hit = sorpia.LimitSurface(res.control_vertices, res.faces, **fine_kwargs(res)).evaluate(
        np.array(face_ids, np.int32), np.array(uv, float))
    assert np.abs(hit - v[shown]).max() <= 1e-10 * diagonal(v)
    assert res.max_error_relative <= 1e-12
    np.testing.assert_array_equal(res.targets, targets)


def test_the_energy_falls_from_the_plain_interpolation():
    # The iteration starts from the plain interpolation refined: plain_energy
    # is tr(W^T K W) of W = R V_plain (numpy), the energies never rise, and
    # the result bends less than plain on a noisy mesh.
    v, f = sorpia.shapes.icosphere(2)
    v = noisy(v, 0.03, 1)
    res = sorpia.fair_interpolate(v, f, tol=1e-10)
    k = fine_energy(res)
    w = res.refinement @ np.asarray(res.plain.control_vertices)
    assert res.plain_energy == pytest.approx(np.trace(w.T @ k @ w), rel=1e-10)
    assert res.energy == pytest.approx(np.trace(res.control_vertices.T @ k @ res.control_vertices), rel=1e-10)
    assert np.all(np.diff(res.history) <= 1e-12 * res.history[0])
    assert res.energy < res.plain_energy
    assert res.history[-1] == pytest.approx(res.energy, rel=1e-8)


def test_targets_on_a_plane_give_a_control_mesh_on_it():
    # The minimiser is linear in the targets, column by column: targets with
    # z = 0.3 x - 0.2 y give control vertices with the same relation, once
    # each column is solved closely (tol 1e-14), whatever K is. The iteration
    # stops on the energy, whose distance to the minimum is quadratic in the
    # vertices' distance to it: at tol 1e-14 the energy has stopped falling
    # (its steps are at rounding level) while the vertices may still be
    # 1e-11 or so from the minimiser's (0.3 of the grid's side is the scale).
    v, f = sorpia.shapes.grid(5, 5)
    v = np.asarray(v, float)
    v[:, 2] = 0.3 * v[:, 0] - 0.2 * v[:, 1]
    res = sorpia.fair_interpolate(v, f, boundary="edge-only", tol=1e-14)
    c = res.control_vertices
    assert np.abs(c[:, 2] - (0.3 * c[:, 0] - 0.2 * c[:, 1])).max() <= 1e-10


def test_one_target_on_a_flat_regular_grid_leaves_a_semidefinite_system():
    # The thin plate alone on a flat regular Catmull-Clark grid with one
    # target: the reduced energy is only semidefinite (a plane through the
    # target costs nothing); the conjugate gradients on the consistent system
    # converge to a minimiser of energy zero (rounding: 1e-10 of the start's)
    # and the target is met.
    v, f = sorpia.shapes.quad_grid(8, 8)
    v = np.asarray(v, float)
    v[:, 2] = 0.05 * np.random.default_rng(3).standard_normal(len(v))
    res = sorpia.fair_interpolate(v, f, scheme="catmull-clark", boundary="edge-only", targets=[27])
    assert res.converged
    assert res.energy <= 1e-10 * res.plain_energy
    hit = sorpia.limit_points(res.control_vertices, res.faces, **fine_kwargs(res))[27]
    assert np.abs(hit - v[27]).max() <= 1e-14


# ---- bad input ----------------------------------------------------------------------------------------------


@pytest.fixture
def ico():
    v, f = sorpia.shapes.icosphere(1)
    return np.asarray(v, float), f


@pytest.mark.parametrize("targets, message", [
    ([0, 42], r"targets\[1\] = 42 is out of range \[0, 42\)"),
    ([-1], r"targets\[0\] = -1 is out of range"),
    ([3, 5, 3], r"targets\[2\] = 3 repeats targets\[0\]"),
    ([], "targets is empty"),
    ([[0, 1]], r"targets must have shape \(k,\), got \(1, 2\)"),
    ([2**40], r"targets\[0\] = 2147483647 is out of range \[0, 42\)"),
])
def test_bad_targets_are_refused(ico, targets, message):
    with pytest.raises(ParameterError, match=message):
        sorpia.fair_interpolate(*ico, targets=np.array(targets, dtype=np.int64))


def test_float_targets_are_refused(ico):
    with pytest.raises(TypeError, match="targets must be integer vertex indices"):
        sorpia.fair_interpolate(*ico, targets=[0.0, 1.0])


@pytest.mark.parametrize("options, message", [
    (dict(levels=0), r"levels must be an integer in 1\.\.10, got 0"),
    (dict(levels=11), r"levels must be an integer in 1\.\.10, got 11"),
    (dict(levels=True), r"levels = True must be an integer in 1\.\.10"),
    (dict(levels=1.0), r"levels = 1\.0 must be an integer in 1\.\.10"),
    (dict(levels=2**40), r"levels must be an integer in 1\.\.10, got 2147483647"),
    (dict(thin_plate=-1.0), r"thin_plate = -1\.0 is negative: the energy's weights must be >= 0"),
    (dict(thin_plate=-1e-300), r"thin_plate = -1e-300 is negative"),
    (dict(membrane=-0.5), "membrane = -0.5 is negative"),
    (dict(membrane=float("nan")), "membrane must be a finite real number"),
    (dict(thin_plate=0.0, membrane=0.0), "thin_plate and membrane are both 0"),
    (dict(tol=0.0), r"tol must be a real number in \(0, 1\), got 0\.0"),
    (dict(tol=1.5), r"tol must be a real number in \(0, 1\), got 1\.5"),
    (dict(tol="1e-6"), r"tol must be a real number, got '1e-6'"),
    (dict(max_iter=0), r"max_iter = 0 must be an integer >= 1"),
    (dict(threads=0), r"threads = 0 must be an integer in 1\.\."),
    (dict(semi_sharp="layer"), "semi_sharp must be one of 'sharp', 'as-tagged'"),
    (dict(depth=13), r"depth must be in 0\.\.12, got 13"),
    (dict(metric="surface"), "metric must be one of 'parameter', 'reference'"),
    (dict(depth=1.5), "depth = 1.5 must be an integer"),
])
def test_bad_options_are_refused(ico, options, message):
    with pytest.raises(ParameterError, match=message):
        sorpia.fair_interpolate(*ico, **options)


def test_a_nonmanifold_mesh_is_refused_with_the_way_out_fair_interpolation_has():
    """An edge of three faces: named as interpolate names it, with the repair as the way out and not
    nonmanifold="sharp", which fair interpolation does not take."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1]], float)
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    with pytest.raises(MeshError, match=r"non-manifold edge \(0, 1\).*--repair.*fair interpolation takes "
                       "manifold meshes only") as info:
        sorpia.fair_interpolate(V, F)
    assert "nonmanifold=" not in str(info.value)


def test_a_fine_mesh_beyond_int32_is_refused_before_any_work():
    # levels 10 on 1280 triangles: 1280 * 4^10 = 1.3G faces, more corners than int32 indices hold.
    v, f = sorpia.shapes.icosphere(3)
    with pytest.raises(ParameterError, match="levels = 10 would make 1342177280 triangles from 1280 faces, more "
                                             "than int32 indices hold"):
        sorpia.fair_interpolate(v, f, levels=10)


def test_a_fine_mesh_beyond_the_memory_left_is_refused_before_any_work(tmp_path):
    # Under an address-space limit 256 MiB above what the process has, levels
    # 6 on 320 triangles (1.3M fine triangles, refinement_bytes above 1 GB) is
    # refused at once by the estimate, with the numbers; levels 1 runs.
    mib = 2 ** 20
    if sorpia._core.available_memory_bytes() < 512 * mib:
        pytest.skip("less than 512 MiB free here: the limit would not be what binds")
    assert sorpia._core.refinement_bytes(162, 320, 6, sorpia._core.Scheme.loop) > 256 * mib
    script = textwrap.dedent(f"""
        import resource, sys, time
        import numpy as np, sorpia
        def vm():
            for line in open("/proc/self/status"):
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
        resource.setrlimit(resource.RLIMIT_AS, (vm() + {256 * mib}, vm() + {256 * mib}))
        v, f = sorpia.shapes.icosphere(2)
        t = time.perf_counter()
        try:
            sorpia.fair_interpolate(v, f, levels=6)
        except sorpia.ParameterError as exc:
            print(exc)
            assert time.perf_counter() - t < 1.0
        print(len(sorpia.fair_interpolate(v, f, levels=1).faces))
    """)
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    first, second = run.stdout.strip().splitlines()
    assert first.startswith("levels = 6 makes 1310720 triangles and needs about ") and "use fewer levels" in first
    assert second == str(320 * 4)


@pytest.mark.parametrize("metric", ["parameter", "reference"])
@pytest.mark.parametrize("scheme", ["loop", "catmull-clark"])
@pytest.mark.parametrize("scale", [1e155, 1e-155])
def test_coordinates_near_the_limits_of_double(scheme, scale, metric):
    """Vertices at 1e155 (whose squares overflow) and 1e-155 (whose squares underflow) give the control mesh of
    the same vertices at scale 1, times the scale (fair_solve works scaled by a power of two; the reference
    metric's thin plate is unchanged when data and reference scale together), and the targets are met through
    the fine mesh's limit points."""
    v, f = (sorpia.shapes.icosphere(1) if scheme == "loop" else sorpia.shapes.quad_torus(8, 6))
    v = np.asarray(v, float)
    one = sorpia.fair_interpolate(v, f, scheme=scheme, metric=metric)
    big = sorpia.fair_interpolate(v * scale, f, scheme=scheme, metric=metric)
    assert np.isfinite(big.control_vertices).all()
    if metric == "reference":  # scale-free: the same energy
        assert big.energy == pytest.approx(one.energy, rel=1e-10)
        assert big.energy_exponent == 0
    else:  # the energies scale with the square of the coordinates: exact in units of 2^energy_exponent
        e = sorpia._core.scale_exponent(v * scale)
        assert e != 0 and big.energy_exponent == 2 * e
        for scaled, plain in ((big.energy_scaled, one.energy), (big.plain_energy_scaled, one.plain_energy)):
            assert scaled == pytest.approx(plain * (scale * 2.0 ** -e) ** 2, rel=1e-10)
        # in model units they leave double's range: 1e310 overflows, 1e-310 is subnormal
        assert big.energy == np.inf if scale > 1 else 0 <= big.energy < 1e-300
    # the ratio, from the scaled energies, is the same at every scale (energy in model units: inf or 0 at 1e+-155)
    assert big.energy_ratio == pytest.approx(one.energy_ratio, rel=1e-10) and big.energy_ratio <= 1 + 1e-12
    np.testing.assert_allclose(big.control_vertices / scale, one.control_vertices, rtol=0, atol=1e-12)
    limit = sorpia.limit_points(big.control_vertices / scale, big.faces, scheme=scheme, **big.tags)
    assert np.abs(limit[:len(v)] - v).max() <= 1e-12


def test_reference_metric_with_a_membrane_beyond_double_range_is_refused():
    v, f = sorpia.shapes.icosphere(1)
    with pytest.raises(ParameterError, match=r"metric='reference' with a membrane term needs coordinates within "
                       r"2\^\+-200"):
        sorpia.fair_interpolate(np.asarray(v, float) * 1e155, f, metric="reference", membrane=0.5)


def test_empty_target_list_and_a_loop_pillow_are_named():
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(sorpia.ParameterError, match="targets is empty"):
        sorpia.fair_interpolate(v, f, targets=[])
    with pytest.raises(sorpia.MeshError, match="pillow"):
        sorpia.fair_interpolate(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.]]), np.array([[0, 1, 2], [0, 2, 1]]),
                                scheme="loop")
