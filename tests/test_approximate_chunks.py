"""Approximation over chunks of points (sorpia::PointChunks): the same fit however the points are cut, from a
Python backend, and streamed from .npy and binary PLY files. The reference is the one-chunk in-memory run; the
footpoints do not depend on the cutting (each point's search depends on that point alone), the sums only by
rounding (1e-10 relative), and a backend that returns its chunks' sums in order gives the same bits."""

import json

import numpy as np
import pytest

import sorpia
from sorpia import _core, shapes
from sorpia.approximate import approximate
from sorpia.surface import LimitSurface


def noisy_samples(k=3000, seed=1, noise=1e-3):
    """Points near the limit surface of a perturbed icosphere cage (Gaussian noise of this deviation per
    coordinate; the surface's radius about 1), and a start cage (the sphere)."""
    V, F = shapes.icosphere(2)
    rng = np.random.default_rng(seed)
    target = LimitSurface(V * (1 + 0.1 * rng.standard_normal((len(V), 1))), F, scheme="loop")
    fid = rng.integers(0, target.n_faces, k).astype(np.int32)
    uv = rng.random((k, 2))
    flip = uv.sum(axis=1) > 1
    uv[flip] = 1 - uv[flip]
    P = target.evaluate(fid, uv) + noise * rng.standard_normal((k, 3))
    return np.ascontiguousarray(P), V, F


def relative(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(np.asarray(b))))


@pytest.mark.parametrize("tangential", [0.1, 1.0])
def test_many_chunks_equal_one(tangential):
    # One update from the same footpoints: the sums differ by their order's rounding only, and the solve with them
    # by 1e-13. Later iterations re-project the footpoints from different control vertices, each stopped at its
    # step's tolerance (1e-5 in (u, v), a predicted decrease below 1e-6 of the distance): control vertices 1e-14
    # apart give footpoints (and so updates) that far apart unless a point's step lies at the tolerance, where it
    # may stop in one and not the other (measured: 2e-14 to 1.4e-13 after 2 to 6 iterations).
    P, V, F = noisy_samples()
    w = np.random.default_rng(5).random(len(P)) + 0.5
    first = [approximate(P, V, F, tangential=tangential, weights=w, iterations=1, chunk_points=c)
             for c in (1 << 20, 701)]
    assert relative(first[1].control_vertices, first[0].control_vertices) < 1e-12
    assert abs(first[1].rms - first[0].rms) <= 1e-12 * first[0].rms
    one = approximate(P, V, F, tangential=tangential, weights=w, iterations=6)
    many = approximate(P, V, F, tangential=tangential, weights=w, iterations=6, chunk_points=701)
    assert one.iterations == many.iterations and one.best_iteration == many.best_iteration
    assert relative(many.control_vertices, one.control_vertices) < 5e-9
    assert abs(many.rms - one.rms) <= 5e-9 * one.rms
    np.testing.assert_array_equal(many.face_ids, one.face_ids)
    np.testing.assert_allclose(many.distances, one.distances, rtol=0, atol=5e-9 * one.diagonal)


class PythonChunks(_core.PointChunks):
    """A backend in Python over _core.ApproximationChunk objects (what a Dask backend runs on its workers),
    returning each chunk's sums in order."""

    def __init__(self, P, V, F, chunk_points):
        super().__init__()
        self.chunks = [_core.ApproximationChunk(P[i:i + chunk_points], None, i) for i in range(0, len(P), chunk_points)]
        self.surface = LimitSurface(V, F, scheme="loop")
        self.search_ = None
        self.calls = []

    def size(self):
        return sum(c.size for c in self.chunks)

    def extent(self):
        return [c.extent() for c in self.chunks]

    def scale(self, e):
        for c in self.chunks:
            c.scale(e)

    def moments(self, center, diagonal):
        return [c.moments(center, diagonal) for c in self.chunks]

    def line_offset(self, mean, axis, diagonal):
        return [c.line_offset(mean, axis, diagonal) for c in self.chunks]

    def set_control_vertices(self, V):
        self.surface.set_vertices(V)
        self.search_ = None

    def _search(self, grid, max_steps):
        if self.search_ is None:
            self.search_ = _core.FootpointSearch(self.surface._surface, grid, max_steps)
        return self.search_

    def search(self, grid, max_steps):
        self.calls.append("search")
        s = self._search(grid, max_steps)
        return [c.search(s) for c in self.chunks]

    def refine(self, grid, max_steps):
        self.calls.append("refine")
        return [c.refine(self.surface._surface, grid, max_steps) for c in self.chunks]

    def keep_best(self):
        for c in self.chunks:
            c.keep_best()

    def search_fresh(self, grid, max_steps, closer):
        self.calls.append("search_fresh")
        s = self._search(grid, max_steps)
        return [c.search_fresh(s, closer) for c in self.chunks]

    def refine_fresh(self, grid, max_steps):
        self.calls.append("refine_fresh")
        s = self._search(grid, max_steps)
        return [c.refine_fresh(s) for c in self.chunks]

    def keep_fresh(self, closer):
        for c in self.chunks:
            c.keep_fresh(closer)

    def keep_fresh_in_best(self):
        return [c.keep_fresh_in_best() for c in self.chunks]

    def normal_sums(self, tangential):
        self.calls.append("normal_sums")
        return [c.normal_sums(self.surface._surface, tangential) for c in self.chunks]

    def sample(self):
        return np.concatenate([c.points for c in self.chunks])

    def best_footpoints(self):
        parts = [c.best_footpoints() for c in self.chunks]
        return tuple(np.concatenate([p[j] for p in parts]) for j in range(3))


def core_run(surface, chunks, **kw):
    o = dict(iterations=6, tol=3e-3, fairness=3e-4, tangential=0.1, method="cg", solver_tol=1e-3,
             solver_max_iter=2000, grid=4, newton_steps=10, report_level=2, callback=None)
    robust = {"robust": "none", **{key: kw.pop(key) for key in ("robust", "robust_quantile", "robust_c", "coarse_iterations",
                                                             "coarse_points") if key in kw}}
    o.update(kw)
    return _core.approximate(surface._surface, chunks, *o.values(), report_each=True, **robust)


def test_python_backend_gives_the_same_bits():
    P, V, F = noisy_samples()
    ref_surface = LimitSurface(V, F, scheme="loop")
    ref = core_run(ref_surface, _core.InMemoryChunks(ref_surface._surface, P, None, 500))
    backend = PythonChunks(P, V, F, 500)
    surface = LimitSurface(V, F, scheme="loop")
    out = core_run(surface, backend)
    np.testing.assert_array_equal(out["control_vertices"], ref["control_vertices"])
    np.testing.assert_array_equal(out["face_ids"], ref["face_ids"])
    np.testing.assert_array_equal(out["distances"], ref["distances"])
    assert [h["rms"] for h in out["history"]] == [h["rms"] for h in ref["history"]]
    assert backend.calls[0] == "search" and backend.calls[1] == "normal_sums" and "refine" in backend.calls


def test_python_backend_errors_propagate():
    P, V, F = noisy_samples(500)

    class Broken(PythonChunks):
        def normal_sums(self, tangential):
            raise RuntimeError("worker lost")

    surface = LimitSurface(V, F, scheme="loop")
    with pytest.raises(RuntimeError, match="worker lost"):
        core_run(surface, Broken(P, V, F, 100))


class PythonRobustChunks(PythonChunks):
    """PythonChunks with the robust fit's three calls, each chunk's result in order."""

    def distance_histogram(self, unit):
        return [c.distance_histogram(unit) for c in self.chunks]

    def robust_sums(self, robust, scale):
        return [c.robust_sums(robust, scale) for c in self.chunks]

    def robust_normal_sums(self, tangential, robust, scale):
        self.calls.append("robust_normal_sums")
        return [c.robust_normal_sums(self.surface._surface, tangential, robust, scale) for c in self.chunks]


def with_outliers(P, count, seed=7):
    """P with `count` points moved far off (five diagonals, at random), and their indices."""
    rng = np.random.default_rng(seed)
    far = rng.choice(len(P), count, replace=False)
    P = P.copy()
    P[far] += rng.normal(scale=5 * np.linalg.norm(np.ptp(P, axis=0)), size=(count, 3))
    return P, far


@pytest.mark.parametrize("robust", ["tukey", "cauchy"])
def test_python_backend_fits_robustly_as_the_core(robust):
    # With far outliers the robust factors change the fit (a test that a backend ignoring them would fail): a
    # Python backend with the robust calls gives the core's bits, chunk by chunk.
    P, V, F = noisy_samples()
    P, far = with_outliers(P, 30)
    kw = dict(robust=robust)  # the loss's defaults (the core's robust_options)
    ref_surface = LimitSurface(V, F, scheme="loop")
    ref = core_run(ref_surface, _core.InMemoryChunks(ref_surface._surface, P, None, 500), **kw)
    plain = core_run(LimitSurface(V, F, scheme="loop"), _core.InMemoryChunks(ref_surface._surface, P, None, 500))
    assert relative(plain["control_vertices"], ref["control_vertices"]) > 1e-3  # the outliers moved the plain fit
    backend = PythonRobustChunks(P, V, F, 500)
    out = core_run(LimitSurface(V, F, scheme="loop"), backend, **kw)
    np.testing.assert_array_equal(out["control_vertices"], ref["control_vertices"])
    assert [h["rms"] for h in out["history"]] == [h["rms"] for h in ref["history"]]
    assert out["robust_scale"] == ref["robust_scale"] and "robust_normal_sums" in backend.calls


def test_python_backend_without_the_robust_calls_is_refused_when_robust():
    P, V, F = noisy_samples(500)
    with pytest.raises(sorpia.ParameterError, match="cannot fit robustly .* pass robust = 'none'"):
        core_run(LimitSurface(V, F, scheme="loop"), PythonChunks(P, V, F, 100), robust="tukey")


# ---- coarse iterations: updates on a fixed sample of the points first ----------------------------------------

def sample_mask(k, sample_points):
    """Which of k points are in the fixed sample of about sample_points (the core's point_sample_mask)."""
    return np.asarray(_core.point_sample_mask(0, k, k, sample_points), dtype=bool)


def test_coarse_iterations_are_the_samples_fit_then_all_points_fit():
    # Independent of the driver's coarse phase: the fit of the sample alone for its 2 updates, then the fit of all
    # points from the iterate it reached (a fresh search, 4 updates) give the same control vertices and records.
    P, V, F = noisy_samples()
    mask = sample_mask(len(P), 8 * len(V))
    kw = dict(tol=0.0, robust="none")
    both = approximate(P, V, F, iterations=6, coarse_iterations=2, coarse_points=8, **kw)
    sample = approximate(P[mask], V, F, iterations=2, coarse_iterations=0, **kw)
    assert sample.best_iteration == 2  # its last iterate is the one the coarse phase hands on
    rest = approximate(P, sample.control_vertices, F, iterations=4, coarse_iterations=0, **kw)
    assert both.coarse_iterations == 2 and both.iterations == 6 and 0 < mask.sum() < len(P) // 2
    assert [h["points"] for h in both.history] == [mask.sum()] * 2 + [len(P)] * 5
    for a, b in zip(both.history, sample.history[:2] + rest.history, strict=True):
        assert abs(a["rms"] - b["rms"]) <= 1e-12 * b["rms"], a["iteration"]
    assert relative(both.control_vertices, rest.control_vertices) < 1e-12
    assert both.best_iteration == 2 + rest.best_iteration


def levelled_at(criteria, coarse_tol, most):
    """The update after which the coarse phase ends, from the criterion of the sample fitted alone after each
    update (criteria[0]: the start's): the first whose lowest so far fell by at most coarse_tol of the one before,
    else `most`; and how far each fall up to it lay from coarse_tol (of the lowest before)."""
    best = [criteria[0]]
    margins = []
    for j in range(1, most):
        best.append(min(best[-1], criteria[j]))
        fall = (best[-2] - best[-1]) / best[-2]
        margins.append(abs(fall - coarse_tol))
        if fall <= coarse_tol:
            return j, margins
    return most, margins


def test_coarse_updates_end_where_the_samples_fit_levels():
    # coarse_iterations is at most: the phase ends after the first update that lowered the sample's lowest RMS by
    # at most coarse_tol of it, found here from the sample fitted alone; the run is then that fit for those updates
    # followed by the fit of all points from its iterate (1e-12).
    P, V, F = noisy_samples()
    mask = sample_mask(len(P), 8 * len(V))
    kw = dict(tol=0.0, robust="none")
    sample = approximate(P[mask], V, F, iterations=6, coarse_iterations=0, **kw)
    j, margins = levelled_at([h["rms"] for h in sample.history], 0.03, 6)
    assert 1 < j < 6 and min(margins) > 1e-3  # the rule ends it early, and no fall lies at the threshold
    both = approximate(P, V, F, iterations=10, coarse_iterations=6, coarse_points=8, coarse_tol=0.03, **kw)
    assert both.coarse_iterations == j
    assert [h["points"] for h in both.history] == [mask.sum()] * j + [len(P)] * (11 - j)
    start = approximate(P[mask], V, F, iterations=j, coarse_iterations=0, **kw)
    rest = approximate(P, start.control_vertices, F, iterations=10 - j, coarse_iterations=0, **kw)
    for a, b in zip(both.history, start.history[:j] + rest.history, strict=True):
        assert abs(a["rms"] - b["rms"]) <= 1e-12 * b["rms"], a["iteration"]
    assert relative(both.control_vertices, rest.control_vertices) < 1e-12
    # coarse_tol 0: the phase ends only after an update that did not lower the sample's RMS; here none
    fixed = approximate(P, V, F, iterations=10, coarse_iterations=6, coarse_points=8, coarse_tol=0.0, **kw)
    assert fixed.coarse_iterations == 6


def test_noisy_data_ends_the_coarse_updates_early():
    # With the defaults (16 points per control vertex, coarse_tol, the robust loss): on clean data the sample's
    # fit falls by more than coarse_tol per update and all coarse_iterations run; with noise of 1e-2 (a hundred
    # times the clean fit's RMS) it reaches the noise floor in a few updates and the phase ends there, at the
    # update found from the sample fitted alone (its robust criterion within 1e-3 of the coarse records', as
    # test_coarse_records_give_the_robust_loss_of_the_sample_as_its_own_fit_does checks), and the result within 1%
    # of the RMS of the fit without coarse updates.
    for noise, early in ((0.0, False), (1e-2, True)):
        P, V, F = noisy_samples(12000, noise=noise)
        mask = sample_mask(len(P), 16 * len(V))
        most = _core.DEFAULT_COARSE_ITERATIONS
        sample = approximate(P[mask], V, F, iterations=most, tol=0.0, coarse_iterations=0)
        j, margins = levelled_at([h["robust_loss"] for h in sample.history], _core.DEFAULT_COARSE_TOL, most)
        assert min(margins) > 2.5e-3  # each criterion within 1e-3 of the records': each fall within about 2e-3
        run = approximate(P, V, F)
        assert run.coarse_iterations == j, noise
        assert (j <= 3 if early else j == most), (noise, j)
        if early:
            plain = approximate(P, V, F, coarse_iterations=0)
            assert run.rms <= 1.01 * plain.rms


def test_coarse_records_give_the_robust_loss_of_the_sample_as_its_own_fit_does():
    # The robust criterion of a coarse record is over the sample's points, as its RMS: that of the sample fitted
    # alone, not scaled down by the sqrt of the share of the points in the sample (below 0.5 here). Within 1e-3:
    # the sample alone has its own diagonal, the unit of the scale's histogram bins and of its floor.
    P, V, F = noisy_samples()
    mask = sample_mask(len(P), 8 * len(V))
    both = approximate(P, V, F, iterations=6, tol=0.0, coarse_iterations=2, coarse_points=8, robust="tukey")
    sample = approximate(P[mask], V, F, iterations=2, tol=0.0, coarse_iterations=0, robust="tukey")
    for a, b in zip(both.history[:2], sample.history[:2], strict=True):  # record 2 is of all points
        for key in ("robust_loss", "inlier_rms"):  # the scale itself: to the histogram's bins (its unit differs)
            assert abs(a[key] - b[key]) <= 1e-3 * b[key], (a["iteration"], key, a[key], b[key])
        assert a["robust_cut"] == b["robust_cut"]
    assert mask.sum() < 0.5 * len(P)


def test_coarse_fit_reaches_the_full_fit():
    # On points near a known surface with noise 1e-3 the fit whose first 4 of 8 updates see 8 points per control
    # vertex ends within 1% of the RMS of the fit whose 8 see all of them, and its surface within a tenth of the
    # noise of that fit's (the RMS distance of its tessellation's vertices to that surface, by a footpoint search).
    P, V, F = noisy_samples(6000)
    full = approximate(P, V, F, iterations=8, tol=0.0, coarse_iterations=0)
    coarse = approximate(P, V, F, iterations=8, tol=0.0, coarse_iterations=4, coarse_points=8)
    assert coarse.coarse_iterations == 4
    assert coarse.rms <= 1.01 * full.rms
    S = LimitSurface(full.control_vertices, F, scheme="loop")
    T = LimitSurface(coarse.control_vertices, F, scheme="loop")
    on_t = _core.ApproximationChunk(np.ascontiguousarray(T.tessellate(3)[0]), None, 0)
    squares, _, count = on_t.search(_core.FootpointSearch(S._surface, 8, 20))[:3]
    assert np.sqrt(squares / count) < 1e-4


def test_a_chunk_keeps_its_own_order_inside_and_the_given_order_outside():
    # The chunk holds its points in spatial order; what leaves it is in the order as given: its points, its best
    # footpoints (each point's search is its own: closest_points' on the same points, bit for bit), its sample's
    # choice (point_sample_mask over the positions as given) and a message naming a point.
    P, V, F = noisy_samples(2000)
    first, k = 300, 5000  # the chunk's place among all points
    chunk = _core.ApproximationChunk(P, None, first)
    np.testing.assert_array_equal(chunk.points, P)
    S = LimitSurface(V, F, scheme="loop")
    chunk.search(_core.FootpointSearch(S._surface, 4, 10))
    chunk.keep_best()
    face_ids, uv, distances = chunk.best_footpoints()
    ref = _core.closest_points(S._surface, S._topology, P, 4, 10)
    np.testing.assert_array_equal(face_ids, ref[0])
    np.testing.assert_array_equal(uv, ref[1])
    np.testing.assert_array_equal(distances, ref[3])
    sample = chunk.sampled(k, 700).points
    chosen = P[_core.point_sample_mask(first, len(P), k, 700)]
    assert 0 < len(sample) < len(P)
    np.testing.assert_array_equal(np.unique(sample, axis=0), np.unique(chosen, axis=0))
    w = np.ones(len(P))
    w[[17, 1500]] = -1.0
    with pytest.raises(ValueError, match=r"weights\[317\] = -1\.0"):
        _core.ApproximationChunk(P, w, first).extent()


def test_coarse_sample_does_not_depend_on_the_chunks():
    P, V, F = noisy_samples()
    kw = dict(iterations=7, coarse_iterations=3, coarse_points=8)
    one = approximate(P, V, F, **kw)
    many = approximate(P, V, F, chunk_points=701, **kw)
    assert [h["points"] for h in one.history] == [h["points"] for h in many.history]
    assert one.best_iteration == many.best_iteration
    assert relative(many.control_vertices, one.control_vertices) < 5e-9


def test_no_coarse_iterations_where_the_sample_holds_over_half_the_points():
    P, V, F = noisy_samples()
    plain = approximate(P, V, F, iterations=8, coarse_iterations=0)
    dense = approximate(P, V, F, iterations=8, coarse_iterations=3, coarse_points=len(P) / len(V))
    assert dense.coarse_iterations == 0 and all(h["points"] == len(P) for h in dense.history)
    np.testing.assert_array_equal(dense.control_vertices, plain.control_vertices)
    # and at least window + 1 = 4 updates on all points: coarse_iterations beyond iterations - 4 is cut there, to
    # none below 5 iterations (then the run is the one without them)
    short = approximate(P, V, F, iterations=6, coarse_iterations=5, coarse_points=8, coarse_tol=0.0)
    assert short.coarse_iterations == 2 and [h["points"] == len(P) for h in short.history] == [False] * 2 + [True] * 5
    four = approximate(P, V, F, iterations=4, coarse_iterations=5, coarse_points=8)
    np.testing.assert_array_equal(four.control_vertices, approximate(P, V, F, iterations=4, coarse_iterations=0)
                                  .control_vertices)
    assert four.coarse_iterations == 0


@pytest.mark.parametrize("option,value,message", [
    ("coarse_iterations", -1, "coarse_iterations = -1 must be an integer >= 0"),
    ("coarse_points", 0.0, "coarse_points = 0.0 must be a finite number > 0"),
    ("coarse_points", float("nan"), "coarse_points = nan must be a finite number > 0"),
    ("coarse_tol", -0.5, "coarse_tol = -0.5 must be a finite number >= 0"),
    ("coarse_tol", float("inf"), "coarse_tol = inf must be a finite number >= 0"),
])
def test_bad_coarse_options_are_named(option, value, message):
    P, V, F = noisy_samples(500)
    with pytest.raises(sorpia.ParameterError, match=message):
        approximate(P, V, F, **{option: value})


def test_coarse_streamed_file_equals_in_memory(tmp_path):
    P, V, F = noisy_samples()
    path = tmp_path / "points.npy"
    np.save(path, P)
    kw = dict(iterations=7, coarse_iterations=3, coarse_points=8.0)
    ref_surface = LimitSurface(V, F, scheme="loop")
    ref = core_run(ref_surface, _core.InMemoryChunks(ref_surface._surface, P, None, 700), **kw)
    surface = LimitSurface(V, F, scheme="loop")
    out = core_run(surface, _core.FileChunks(surface._surface, str(path), 700, str(tmp_path), 10**6), **kw)
    assert out["coarse_iterations"] == 3
    np.testing.assert_array_equal(out["control_vertices"], ref["control_vertices"])
    assert [h["rms"] for h in out["history"]] == [h["rms"] for h in ref["history"]]


class PythonSampledChunks(PythonChunks):
    """PythonChunks with set_sample: the chunks' sampled ones for the calls that follow (as the Dask host)."""

    def set_sample(self, sample_points):
        if sample_points == 0:
            self.chunks = self.all_chunks
        else:
            self.all_chunks = self.chunks
            k = self.size()
            self.chunks = [c.sampled(k, sample_points) for c in self.chunks]


def test_python_backend_runs_coarse_iterations_as_the_core():
    P, V, F = noisy_samples()
    kw = dict(iterations=7, coarse_iterations=3, coarse_points=8.0)
    ref_surface = LimitSurface(V, F, scheme="loop")
    ref = core_run(ref_surface, _core.InMemoryChunks(ref_surface._surface, P, None, 500), **kw)
    out = core_run(LimitSurface(V, F, scheme="loop"), PythonSampledChunks(P, V, F, 500), **kw)
    np.testing.assert_array_equal(out["control_vertices"], ref["control_vertices"])
    assert [h["rms"] for h in out["history"]] == [h["rms"] for h in ref["history"]]
    with pytest.raises(sorpia.ParameterError, match="no set_sample.*pass coarse_iterations = 0"):
        core_run(LimitSurface(V, F, scheme="loop"), PythonChunks(P, V, F, 500), **kw)


def write_ply(path, P, dtype, extra=True):
    """A binary little-endian PLY with the points as vertex x, y, z of `dtype` (and, with extra, an int property
    and an rgb before and after them, which the reader must skip), and a face element after the vertices."""
    t = "float" if dtype == np.float32 else "double"
    fields = ([("id", "<i4")] if extra else []) + [("x", dtype), ("y", dtype), ("z", dtype)] + \
        ([("r", "u1"), ("g", "u1"), ("b", "u1")] if extra else [])
    rec = np.zeros(len(P), dtype=fields)
    rec["x"], rec["y"], rec["z"] = P[:, 0], P[:, 1], P[:, 2]
    props = (["property int id"] if extra else []) + [f"property {t} {c}" for c in "xyz"] + \
        (["property uchar red", "property uchar green", "property uchar blue"] if extra else [])
    header = "\n".join(["ply", "format binary_little_endian 1.0", f"element vertex {len(P)}", *props,
                        "element face 1", "property list uchar int vertex_indices", "end_header"]) + "\n"
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(rec.tobytes())
        f.write(np.array([3], np.uint8).tobytes() + np.array([0, 1, 2], "<i4").tobytes())


@pytest.mark.parametrize("kind", ["npy64", "npy32", "ply64", "ply32"])
def test_streamed_file_equals_in_memory(tmp_path, kind):
    P, V, F = noisy_samples()
    dtype = np.float32 if kind.endswith("32") else np.float64
    Pd = P.astype(dtype)
    path = tmp_path / ("points.npy" if kind.startswith("npy") else "points.ply")
    if kind.startswith("npy"):
        np.save(path, Pd)
    else:
        write_ply(path, Pd, dtype)
    ref_surface = LimitSurface(V, F, scheme="loop")
    ref = core_run(ref_surface, _core.InMemoryChunks(ref_surface._surface, Pd.astype(np.float64), None, 700))
    surface = LimitSurface(V, F, scheme="loop")
    out = core_run(surface, _core.FileChunks(surface._surface, str(path), 700, str(tmp_path), 10**6))
    np.testing.assert_array_equal(out["control_vertices"], ref["control_vertices"])
    assert [h["rms"] for h in out["history"]] == [h["rms"] for h in ref["history"]]
    assert [h["surface_rms"] for h in out["history"]] == [h["surface_rms"] for h in ref["history"]]
    assert len(out["face_ids"]) == 0  # not kept for streamed data
    assert not list(tmp_path.glob("sorpia-chunks-*"))  # the spill file is unlinked at once


def test_streamed_sample_is_fixed_and_near(tmp_path):
    # With more points than the sample, the report's surface-to-data distances come from a fixed sample: the same
    # for any chunking, and no nearer than from all points (a subset's nearest point is no nearer).
    P, V, F = noisy_samples(4000)
    np.save(tmp_path / "p.npy", P)
    runs = []
    for chunk in (300, 1000):
        surface = LimitSurface(V, F, scheme="loop")
        runs.append(core_run(surface, _core.FileChunks(surface._surface, str(tmp_path / "p.npy"), chunk,
                                                       str(tmp_path), 1000), iterations=2))
    surface = LimitSurface(V, F, scheme="loop")
    full = core_run(surface, _core.InMemoryChunks(surface._surface, P, None, 1000), iterations=2)
    assert runs[0]["history"][0]["surface_rms"] == runs[1]["history"][0]["surface_rms"]
    assert runs[0]["history"][0]["surface_rms"] >= full["history"][0]["surface_rms"]
    np.testing.assert_array_equal(runs[1]["control_vertices"], full["control_vertices"])  # the report is no part of the fit


@pytest.mark.parametrize("text,message", [
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
     b"0 0 0\n", "ascii PLY"),
    (b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
     b"property float z\nend_header\n" + bytes(12), "need 60"),
    (b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n",
     "x, y and z"),
    (b"hello", "neither a PLY nor a .npy"),
])
def test_bad_files_are_named(tmp_path, text, message):
    path = tmp_path / "bad.ply"
    path.write_bytes(text)
    surface = LimitSurface(*shapes.icosphere(1), scheme="loop")
    with pytest.raises(ValueError, match=message) as info:
        _core.FileChunks(surface._surface, str(path), 100, str(tmp_path), 1000)
    assert "bad.ply" in str(info.value)


def test_approximate_takes_a_path(tmp_path):
    # sorpia.approximate(path) streams the file: the same fit as the array's (the same chunks), the footpoints not
    # kept, n_points counted; weights and faces refused with a file.
    P, V, F = noisy_samples()
    np.save(tmp_path / "p.npy", P)
    ref = approximate(P, V, F, chunk_points=1000, iterations=4)
    out = approximate(tmp_path / "p.npy", V, F, chunk_points=1000, iterations=4, spill_directory=tmp_path)
    np.testing.assert_array_equal(out.control_vertices, ref.control_vertices)
    assert out.rms == ref.rms and out.n_points == len(P) and out.report()["n_points"] == len(P)
    assert len(out.face_ids) == 0 and out.points == str(tmp_path / "p.npy")
    with pytest.raises(sorpia.ParameterError, match="weights= and faces="):
        approximate(str(tmp_path / "p.npy"), V, F, weights=np.ones(len(P)))
    assert _core.point_file_points(str(tmp_path / "p.npy")) == len(P)


def test_command_streams_a_binary_ply(tmp_path, monkeypatch, command):
    # `sorpia approximate scan.ply --cage cage.obj --stream yes`: the points read a chunk at a time, the fit the
    # array's (the same chunks: the same bits, checked on the report's RMS and the cage read back to OBJ's 17
    # digits); --vertices and --sampling, which need the mesh in memory, refused by name.
    monkeypatch.chdir(tmp_path)
    P, V, F = noisy_samples()
    write_ply(tmp_path / "scan.ply", P, np.float64, extra=False)
    sorpia.write_mesh(tmp_path / "cage.obj", V, F)
    code, out, err = command("approximate", "scan.ply", "--cage", "cage.obj", "-o", "out.obj", "--stream", "yes",
                             "--iterations", 3, "--report", "r.json", "--quiet")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    cage_v, cage_f = sorpia.read_mesh(tmp_path / "cage.obj")[:2]
    ref = approximate(P, cage_v, cage_f, iterations=3)
    assert report["streamed"] and report["input_points"] == len(P) and report["rms"] == ref.rms
    np.testing.assert_allclose(sorpia.read_mesh(tmp_path / "out.obj")[0], ref.control_vertices, rtol=1e-15,
                               atol=1e-15)
    code, out, err = command("approximate", "scan.ply", "--vertices", 50, "-o", "o2.obj", "--stream", "yes")
    assert code != 0 and "--cage" in err
    (tmp_path / "text.ply").write_text("ply\nformat ascii 1.0\nelement vertex 0\nend_header\n")
    code, out, err = command("approximate", "text.ply", "--cage", "cage.obj", "-o", "o3.obj", "--stream", "yes")
    assert code != 0 and "ascii" in err


def test_surface_report_at_the_end_is_the_returned_iterates():
    # Without report_each the surface-to-data distances are measured once, for the returned iterate: the same
    # figures as measured at every iteration, None in the other records; the fit itself is unchanged.
    P, V, F = noisy_samples()
    each = approximate(P, V, F, iterations=4, report_each=True)
    end = approximate(P, V, F, iterations=4)
    np.testing.assert_array_equal(end.control_vertices, each.control_vertices)
    b = end.best_iteration
    for key in ("surface_rms", "surface_max", "surface_rms_relative", "surface_max_relative"):
        assert end.history[b][key] == each.history[b][key]
        assert all(h[key] is None for i, h in enumerate(end.history) if i != b)
    assert [h["rms"] for h in end.history] == [h["rms"] for h in each.history]
    json.dumps(end.report())
