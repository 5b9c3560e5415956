// The fit layer's pipelines: fair interpolation (sorpia::fair_interpolate)
// against the same result assembled step by step from the layer's functions,
// and approximation (sorpia::approximate) against a dense solve of one
// update's normal equations on a tiny cage; both under the core's exact
// scaling by a power of two.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "expect_error.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/approximation.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/fair.hpp"
#include "sorpia/fair_interpolation.hpp"
#include "sorpia/fairness.hpp"
#include "sorpia/footpoints.hpp"
#include "sorpia/interpolator.hpp"
#include "sorpia/normal_matrix.hpp"
#include "sorpia/point_chunks.hpp"
#include "sorpia/refine.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/surface.hpp"

namespace {

using sorpia::Boundary;
using sorpia::Scheme;

std::vector<double> noisy(const sorpia::Mesh& m, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, amplitude);
  std::vector<double> v = m.vertices;
  for (double& x : v) x += g(rng);
  return v;
}

std::vector<double> scaled(std::vector<double> v, int e) {
  for (double& x : v) x = std::ldexp(x, e);
  return v;
}

sorpia::Rules tagged(const sorpia::Mesh& m) {
  sorpia::Rules rules{Scheme::Loop, Boundary::EdgeAndCorner, {}};
  const auto* f = m.face_vertex_indices.data();
  rules.tags.crease_vertices = {f[0], f[1]};
  rules.tags.crease_sharpness = {1.5};
  return rules;
}

TEST(FairInterpolate, EqualsThePipelineAssembledStepByStep) {
  // The driver runs the layer's own functions in order; assembled here by hand from them (plain solve,
  // refine_uniform, the fine topology, K with the semi-sharp crease made sharp, fair_solve) the result is the
  // same to the bit: the same operations on the same values.
  const sorpia::Mesh m = sorpia::irregular(300, 3);
  const std::vector<double> v0 = noisy(m, 0.01, 1);
  const sorpia::Rules rules = tagged(m);
  std::vector<std::int32_t> targets;
  for (std::int32_t i = 0; i < static_cast<std::int32_t>(m.n_vertices()); i += 2) targets.push_back(i);
  for (const int levels : {1, 2}) {
    sorpia::FairInterpolationOptions o;
    o.levels = levels;
    o.membrane = 0.1;
    sorpia::Interpolator interp(sorpia::Topology(m), rules);
    const auto got = sorpia::fair_interpolate(interp, v0.data(), targets.data(), targets.size(), o);

    sorpia::Interpolator again(sorpia::Topology(m), rules);
    const sorpia::SolveResult plain = again.solve(v0.data(), 3, nullptr, o.plain, true);
    const sorpia::RefinedMesh fine =
        sorpia::refine_uniform(again.topology(), rules, levels, plain.control_vertices.data(), false);
    const sorpia::Topology fine_topology(fine.mesh, fine.n_vertices);
    sorpia::Tags sharp = fine.tags;
    for (double& s : sharp.crease_sharpness)
      if (s > 0) s = sorpia::kInfiniteSharpness;
    sorpia::FairnessQuadrature q;
    q.depth = 0;
    const sorpia::CsrMatrix k = sorpia::fairness_matrix(fine_topology, sorpia::Rules{Scheme::Loop, rules.boundary, sharp},
                                                        1.0, 0.1, q, nullptr, false);
    std::vector<double> positions;
    for (const std::int32_t t : targets)
      for (int c = 0; c < 3; ++c) positions.push_back(v0[3 * static_cast<std::size_t>(t) + c]);
    const sorpia::FairSolution want =
        sorpia::fair_solve(fine_topology, sorpia::Rules{Scheme::Loop, rules.boundary, fine.tags}, k, targets.data(),
                           targets.size(), positions.data(), fine.vertices.data(), o.solve);
    EXPECT_EQ(got.plain.control_vertices, plain.control_vertices);
    EXPECT_EQ(got.fine.mesh.face_vertex_indices, fine.mesh.face_vertex_indices);
    EXPECT_EQ(got.fine.n_vertices, fine.n_vertices);
    EXPECT_EQ(got.solution.vertices, want.vertices) << "levels " << levels;
    EXPECT_EQ(got.solution.energies, want.energies);
    EXPECT_EQ(got.solution.iterations, want.iterations);
    EXPECT_EQ(got.solution.stop_reason, want.stop_reason);
    EXPECT_LT(got.solution.energy, got.solution.start_energy);  // fairer than the plain surface
    EXPECT_LT(got.solution.max_error, 1e-12);                    // the targets met to rounding
  }
}

TEST(FairInterpolate, DataBeyondTwoToThe200IsSolvedScaledExactly) {
  // The core's one scaling (detail/scaling.hpp): 2^300 V0 and 2^-300 V0 give 2^+-300 times V0's control
  // vertices, bit for bit (a power of two is exact, and the pipeline is homogeneous in the data); with the
  // reference metric too, whose thin-plate energy is scale-free.
  const sorpia::Mesh m = sorpia::irregular(200, 5);
  const std::vector<double> v0 = noisy(m, 0.01, 2);
  for (const bool reference : {false, true}) {
    sorpia::FairInterpolationOptions o;
    o.reference_metric = reference;
    sorpia::Interpolator a(sorpia::Topology(m), sorpia::Rules{});
    const auto one = sorpia::fair_interpolate(a, v0.data(), nullptr, 0, o);
    for (const int e : {300, -300}) {
      sorpia::Interpolator b(sorpia::Topology(m), sorpia::Rules{});
      const std::vector<double> big = scaled(v0, e);
      const auto far = sorpia::fair_interpolate(b, big.data(), nullptr, 0, o);
      EXPECT_EQ(far.solution.vertices, scaled(one.solution.vertices, e)) << "reference " << reference << " e " << e;
      EXPECT_EQ(far.solution.iterations, one.solution.iterations);
    }
  }
  sorpia::FairInterpolationOptions o;
  o.reference_metric = true;
  o.membrane = 1.0;
  sorpia::Interpolator c(sorpia::Topology(m), sorpia::Rules{});
  const std::vector<double> big = scaled(v0, 300);
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::fair_interpolate(c, big.data(), nullptr, 0, o); }, {"membrane term needs coordinates within 2^+-200"});
}

TEST(FairInterpolate, RefusesOptionsBeforeAnyWork) {
  const sorpia::Mesh m = sorpia::icosphere(1);
  sorpia::Interpolator interp(sorpia::Topology(m), sorpia::Rules{});
  sorpia::FairInterpolationOptions o;
  o.levels = 0;
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::fair_interpolate(interp, m.vertices.data(), nullptr, 0, o); }, {"levels must be an integer in 1..10, got 0"});
  o.levels = 1;
  o.thin_plate = 0.0;
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::fair_interpolate(interp, m.vertices.data(), nullptr, 0, o); }, {"thin_plate and membrane are both 0"});
  o.thin_plate = 1.0;
  const std::int32_t out_of_range[] = {0, 99};
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::fair_interpolate(interp, m.vertices.data(), out_of_range, 2, o); }, {"targets[1] = 99 is out of range [0, 42)"});
}

// ---- approximation -----------------------------------------------------------

// x with a x = b for a dense symmetric positive definite (n, n) a: Cholesky, in long double.
std::vector<double> dense_solve(const std::vector<long double>& a, const std::vector<long double>& b, std::size_t n) {
  std::vector<long double> l(n * n, 0.0L);
  for (std::size_t j = 0; j < n; ++j) {
    long double d = a[j * n + j];
    for (std::size_t k = 0; k < j; ++k) d -= l[j * n + k] * l[j * n + k];
    l[j * n + j] = std::sqrt(d);
    for (std::size_t i = j + 1; i < n; ++i) {
      long double s = a[i * n + j];
      for (std::size_t k = 0; k < j; ++k) s -= l[i * n + k] * l[j * n + k];
      l[i * n + j] = s / l[j * n + j];
    }
  }
  std::vector<long double> y(n);
  for (std::size_t i = 0; i < n; ++i) {
    long double s = b[i];
    for (std::size_t k = 0; k < i; ++k) s -= l[i * n + k] * y[k];
    y[i] = s / l[i * n + i];
  }
  std::vector<double> x(n);
  std::vector<long double> xl(n);
  for (std::size_t i = n; i-- > 0;) {
    long double s = y[i];
    for (std::size_t k = i + 1; k < n; ++k) s -= l[k * n + i] * xl[k];
    xl[i] = s / l[i * n + i];
    x[i] = static_cast<double>(xl[i]);
  }
  return x;
}

struct TinyFit {
  sorpia::Mesh cage = sorpia::icosphere(0);  // 12 vertices
  std::vector<double> start, points;
  TinyFit() {
    // Points on the limit surface of the cage inflated by 10%, plus noise; the fit starts from the cage moved.
    const sorpia::Topology topology(cage);
    std::vector<double> big = cage.vertices;
    for (double& x : big) x *= 1.1;
    sorpia::LimitSurface truth(topology, big.data(), Scheme::Loop, Boundary::EdgeAndCorner);
    const sorpia::Mesh tess = truth.tessellate(2);
    points = noisy(tess, 1e-3, 7);
    start = noisy(cage, 0.03, 8);
  }
};

// One update of approximate from `start` (the control vertices of `surface`, whose rules are `rules`), by a dense
// solve of its normal equations with the given footpoints of the points (face ids, uv and unit normals there):
// (A^T W A + c K + mu I) V = A^T W P + mu V_start over the 3n unknowns (x0, y0, z0, x1, ...), A from rows() (a
// point's row at a time), W_r = t I + (1 - t) n_r n_r^T (I where there is no normal), c and mu the fairness and proximal weights times the
// mean diagonal of A^T W A (of its xx, yy and zz entries).
std::vector<double> dense_update(const sorpia::LimitSurface& surface, const sorpia::Rules& rules,
                                 const std::vector<double>& start, const std::vector<double>& points,
                                 const std::int32_t* face_ids, const double* uv, const double* normals,
                                 double fairness, double tangential) {
  const std::size_t k = points.size() / 3, n = surface.n_vertices(), m = 3 * n;
  const sorpia::CsrMatrix a = surface.rows(face_ids, uv, k, 0).position;
  std::vector<long double> M(m * m, 0.0L), rhs(m, 0.0L);
  for (std::size_t r = 0; r < k; ++r) {
    const double* nr = &normals[3 * r];
    // No normal (zero or not finite: Bfr's at a Catmull-Clark vertex of two faces): W_r = I (blend_weights).
    const bool normal = nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2] > 0.0;
    const double t = normal ? tangential : 1.0;
    long double w[3][3];
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) w[c][d] = normal ? (1 - t) * nr[c] * nr[d] + (c == d ? t : 0.0) : (c == d ? 1.0 : 0.0);
    for (std::int32_t p = a.indptr[r]; p < a.indptr[r + 1]; ++p) {
      const std::size_t i = static_cast<std::size_t>(a.indices[p]);
      for (int c = 0; c < 3; ++c) {
        for (int d = 0; d < 3; ++d) rhs[3 * i + c] += a.data[p] * w[c][d] * points[3 * r + d];
        for (std::int32_t q = a.indptr[r]; q < a.indptr[r + 1]; ++q)
          for (int d = 0; d < 3; ++d)
            M[(3 * i + c) * m + 3 * static_cast<std::size_t>(a.indices[q]) + d] += a.data[p] * a.data[q] * w[c][d];
      }
    }
  }
  long double mean = 0.0L;
  for (std::size_t i = 0; i < m; ++i) mean += M[i * m + i];
  mean /= static_cast<long double>(m);
  sorpia::FairnessQuadrature q;
  q.depth = 0;
  const sorpia::CsrMatrix kk = sorpia::fairness_matrix(surface.topology(), rules, 1.0, 0.0, q);
  for (std::size_t i = 0; i < n; ++i)
    for (std::int32_t p = kk.indptr[i]; p < kk.indptr[i + 1]; ++p)
      for (int c = 0; c < 3; ++c)
        M[(3 * i + c) * m + 3 * static_cast<std::size_t>(kk.indices[p]) + c] += fairness * mean * kk.data[p];
  const long double mu = 1e-6L * mean;
  for (std::size_t i = 0; i < m; ++i) {
    M[i * m + i] += mu;
    rhs[i] += mu * start[i];
  }
  return dense_solve(M, rhs, m);
}

// The update of TinyFit from the footpoints of its start (closest_points).
std::vector<double> dense_update(const TinyFit& fit, double fairness, double tangential) {
  const sorpia::Topology topology(fit.cage);
  sorpia::LimitSurface surface(topology, fit.start.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  const sorpia::Footpoints feet =
      sorpia::closest_points(surface, topology, fit.points.data(), fit.points.size() / 3, {4, 10});
  return dense_update(surface, sorpia::Rules{}, fit.start, fit.points, feet.face_ids.data(), feet.uv.data(),
                      feet.normals.data(), fairness, tangential);
}

TEST(NormalMatrix, RhsIsTheRowByRowProduct) {
  // normal_matrix's A^T x alongside A^T W A equals the product summed row by row in order (to rounding: each run's
  // share is summed first, 1e-14 of the sum of the terms' magnitudes), and the matrix is the one made without it:
  // rows in runs of equal columns (a face's points) and alone, enough entries for several tasks.
  std::mt19937 rng(5);
  const std::size_t n = 400;
  std::vector<std::int32_t> indptr{0}, indices;
  std::vector<double> data;
  while (indices.size() < 200000) {
    std::vector<std::int32_t> cols(n);
    for (std::size_t j = 0; j < n; ++j) cols[j] = static_cast<std::int32_t>(j);
    std::shuffle(cols.begin(), cols.end(), rng);
    cols.resize(6 + rng() % 14);
    std::sort(cols.begin(), cols.end());
    for (std::size_t r = 0, run = 1 + rng() % 40; r < run; ++r) {
      for (const std::int32_t c : cols) {
        indices.push_back(c);
        data.push_back(std::uniform_real_distribution<double>(-1.0, 1.0)(rng));
      }
      indptr.push_back(static_cast<std::int32_t>(indices.size()));
    }
  }
  const std::size_t k = indptr.size() - 1;
  const sorpia::CsrRows a{k, n, indptr.data(), indices.data(), data.data()};
  std::vector<double> x(3 * k), w(6 * k);
  for (double& v : x) v = std::uniform_real_distribution<double>(-2.0, 2.0)(rng);
  for (double& v : w) v = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  std::vector<double> expected(3 * n, 0.0), magnitude(3 * n, 0.0);
  for (std::size_t r = 0; r < k; ++r)
    for (std::int32_t p = indptr[r]; p < indptr[r + 1]; ++p)
      for (std::size_t c = 0; c < 3; ++c) {
        expected[3 * static_cast<std::size_t>(indices[p]) + c] += data[p] * x[3 * r + c];
        magnitude[3 * static_cast<std::size_t>(indices[p]) + c] += std::abs(data[p] * x[3 * r + c]);
      }
  for (const int count : {0, 6}) {
    std::vector<double> rhs(3 * n, -1.0);
    const sorpia::NormalMatrix with = sorpia::normal_matrix(a, count ? w.data() : nullptr, count, x.data(), rhs.data());
    const sorpia::NormalMatrix without = sorpia::normal_matrix(a, count ? w.data() : nullptr, count);
    for (std::size_t i = 0; i < 3 * n; ++i) EXPECT_NEAR(rhs[i], expected[i], 1e-14 * magnitude[i]) << count << " " << i;
    EXPECT_EQ(with.indptr, without.indptr);
    EXPECT_EQ(with.indices, without.indices);
    EXPECT_EQ(with.values, without.values);
  }
}

// ApproximationChunk::normal_sums at the chunk's current footpoints (its points `points`, weights `weights`):
// the same sums bit for bit on one thread as on all, on a pattern made and on the one kept from the call before;
// and normal_matrix of LimitSurface::rows' position matrix in face order (the rows, weights and weighted points
// made apart, the rows a point at a time: B's at a level-dependent vertex's corner; normal_matrix itself is held
// to scipy by test_normal_equations.py) to 1e-13 of the largest entry, with the tangent blend (6 values per
// entry) and with weights (1).
// `state` (per point in the order the points were given) in the chunk's own order (ApproximationChunk holds its
// points in spatial order: point i of its order is point given(i) as given), as its current footpoints.
sorpia::ApproximationChunk::State in_chunk_order(const sorpia::ApproximationChunk& chunk,
                                                 const sorpia::ApproximationChunk::State& state) {
  sorpia::ApproximationChunk::State out;
  const std::size_t k = chunk.size();
  out.face_ids.resize(k);
  out.uv.resize(2 * k);
  out.distances.resize(state.distances.empty() ? 0 : k);
  out.normals.resize(state.normals.empty() ? 0 : 3 * k);
  for (std::size_t i = 0; i < k; ++i) {
    const std::size_t j = chunk.given(i);
    out.face_ids[i] = state.face_ids[j];
    std::copy_n(&state.uv[2 * j], 2, &out.uv[2 * i]);
    if (!out.distances.empty()) out.distances[i] = state.distances[j];
    if (!out.normals.empty()) std::copy_n(&state.normals[3 * j], 3, &out.normals[3 * i]);
  }
  return out;
}

void expect_normal_sums_are_the_rows_products(const sorpia::ApproximationChunk& chunk,
                                              const sorpia::LimitSurface& surface, const std::vector<double>& points,
                                              const std::vector<double>& weights) {
  const sorpia::ApproximationChunk::State& state = chunk.current;
  const std::size_t k = state.face_ids.size(), n = surface.n_vertices();
  // The rows in face order (a stable sort), their weights and weighted points, for normal_matrix.
  std::vector<std::size_t> order(k);
  for (std::size_t i = 0; i < k; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return state.face_ids[a] < state.face_ids[b]; });
  std::vector<std::int32_t> face_o(k);
  std::vector<double> uv_o(2 * k), p_o(3 * k), n_o(3 * k), w_o(k);
  for (std::size_t i = 0; i < k; ++i) {
    const std::size_t o = order[i];
    face_o[i] = state.face_ids[o];
    std::copy_n(&state.uv[2 * o], 2, &uv_o[2 * i]);
    std::copy_n(&points[3 * chunk.given(o)], 3, &p_o[3 * i]);  // the state is in the chunk's order
    std::copy_n(&state.normals[3 * o], 3, &n_o[3 * i]);
    w_o[i] = weights[chunk.given(o)];
  }
  const sorpia::CsrMatrix a = surface.rows(face_o.data(), uv_o.data(), k, 0).position;
  for (const double tangential : {0.1, 1.0}) {
    const sorpia::NormalSums all = chunk.normal_sums(surface, tangential);
    sorpia::NormalSums one;
    {
      const sorpia::detail::ThreadCap cap(1);
      one = chunk.normal_sums(surface, tangential);
    }
    EXPECT_EQ(one.matrix.indptr, all.matrix.indptr);
    EXPECT_EQ(one.matrix.indices, all.matrix.indices);
    EXPECT_EQ(one.matrix.values, all.matrix.values) << tangential;
    EXPECT_EQ(one.rhs, all.rhs) << tangential;
    std::vector<double> w6(6 * k), wp(3 * k);
    if (tangential != 1.0) {
      sorpia::blend_weights(p_o.data(), n_o.data(), w_o.data(), k, tangential, w6.data(), wp.data());
    } else {
      for (std::size_t i = 0; i < 3 * k; ++i) wp[i] = w_o[i / 3] * p_o[i];
    }
    const int count = tangential != 1.0 ? 6 : 1;
    std::vector<double> rhs(3 * n);
    const sorpia::NormalMatrix ref = sorpia::normal_matrix(
        sorpia::CsrRows{k, n, a.indptr.data(), a.indices.data(), a.data.data()},
        count == 6 ? w6.data() : w_o.data(), count, wp.data(), rhs.data());
    ASSERT_EQ(ref.indptr, all.matrix.indptr);
    ASSERT_EQ(ref.indices, all.matrix.indices);
    double largest = 0.0, worst = 0.0, largest_rhs = 0.0, worst_rhs = 0.0;
    for (std::size_t e = 0; e < ref.values.size(); ++e) {
      largest = std::max(largest, std::abs(ref.values[e]));
      worst = std::max(worst, std::abs(ref.values[e] - all.matrix.values[e]));
    }
    for (std::size_t e = 0; e < rhs.size(); ++e) {
      largest_rhs = std::max(largest_rhs, std::abs(rhs[e]));
      worst_rhs = std::max(worst_rhs, std::abs(rhs[e] - all.rhs[e]));
    }
    EXPECT_LE(worst, 1e-13 * largest) << tangential;
    EXPECT_LE(worst_rhs, 1e-13 * largest_rhs) << tangential;
  }
}

// k random footpoints on `surface` (every face but `avoid`; uv uniform in the face's domain), their normals, and
// points 1e-3 off their positions.
std::vector<double> random_footpoints(const sorpia::LimitSurface& surface, std::size_t k, unsigned seed,
                                      std::int32_t avoid, sorpia::ApproximationChunk::State& state) {
  const std::size_t m = surface.n_faces();
  const bool quads = surface.scheme() == Scheme::CatmullClark;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  state.face_ids.resize(k);
  state.uv.resize(2 * k);
  state.distances.assign(k, 0.0);
  state.normals.resize(3 * k);
  for (std::size_t i = 0; i < k; ++i) {
    do state.face_ids[i] = static_cast<std::int32_t>(rng() % m);
    while (state.face_ids[i] == avoid);
    const double u = unit(rng), v = unit(rng);
    const bool fold = !quads && u + v > 1.0;
    state.uv[2 * i] = fold ? 1.0 - u : u;
    state.uv[2 * i + 1] = fold ? 1.0 - v : v;
  }
  std::vector<double> at(3 * k), points(3 * k);
  surface.evaluate(state.face_ids.data(), state.uv.data(), k, at.data(), nullptr, nullptr, state.normals.data());
  for (std::size_t i = 0; i < 3 * k; ++i) points[i] = at[i] + 1e-3 * (unit(rng) - 0.5);
  return points;
}

TEST(NormalSums, SameOnOneThreadAsOnAllAndEqualToTheRowsProducts) {
  // Many faces (several tasks, many runs of blocks).
  const sorpia::Mesh mesh = sorpia::irregular(3000);
  const sorpia::Topology t(mesh);
  const sorpia::LimitSurface surface(t, mesh.vertices.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  const std::size_t k = 60000;
  sorpia::ApproximationChunk::State state;
  const std::vector<double> points = random_footpoints(surface, k, 11, -1, state);
  std::vector<double> weights(k);
  std::mt19937 rng(12);
  for (double& w : weights) w = 0.5 + std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  sorpia::ApproximationChunk chunk(points.data(), k, weights.data(), 0);
  chunk.current = in_chunk_order(chunk, state);
  expect_normal_sums_are_the_rows_products(chunk, surface, points, weights);
}

// A cage with level-dependent vertices (where a point at a face's corner has B's row, LimitSurface::rows, its
// block one of its own in position_blocks): Loop's icosphere(1) with one infinitely sharp edge (its two ends
// darts), or Catmull-Clark's quad torus with its quad 0 split along a diagonal through its centre (an interior
// vertex of two faces).
struct CornerCage {
  sorpia::Mesh mesh;
  Scheme scheme = Scheme::Loop;
  sorpia::Tags tags;
  std::vector<std::int32_t> level_dependent;
  // Every corner of a face at a level-dependent vertex: (face, its corner's u, v).
  std::vector<std::pair<std::int32_t, std::array<double, 2>>> corners;
  explicit CornerCage(Scheme s) : scheme(s) {
    if (s == Scheme::Loop) {
      mesh = sorpia::icosphere(1);
      const std::int32_t* f = mesh.face_vertex_indices.data();
      tags.crease_vertices = {f[0], f[1]};
      tags.crease_sharpness = {sorpia::kInfiniteSharpness};
      level_dependent = {f[0], f[1]};
    } else {
      mesh = sorpia::quad_torus(6, 4);
      std::vector<std::int32_t>& fi = mesh.face_vertex_indices;
      const std::int32_t a = fi[0], c = fi[2], d = fi[3];
      const auto middle = static_cast<std::int32_t>(mesh.n_vertices());
      for (int x = 0; x < 3; ++x) {
        double centre = 0.0;
        for (int j = 0; j < 4; ++j) centre += 0.25 * mesh.vertices[3 * static_cast<std::size_t>(fi[j]) + x];
        mesh.vertices.push_back(centre);
      }
      fi[3] = middle;  // (a, b, c, middle) and (middle, c, d, a)
      fi.insert(fi.end(), {middle, c, d, a});
      if (!mesh.uniform()) mesh.face_vertex_counts.push_back(4);
      level_dependent = {middle};
    }
    const std::size_t size = s == Scheme::Loop ? 3 : 4;  // every face's corners
    const double tri[3][2] = {{0, 0}, {1, 0}, {0, 1}}, quad[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (std::size_t f = 0; f < mesh.n_faces(); ++f)
      for (std::size_t j = 0; j < size; ++j)
        if (std::count(level_dependent.begin(), level_dependent.end(), mesh.face_vertex_indices[size * f + j])) {
          const double* uv = size == 3 ? tri[j] : quad[j];
          corners.push_back({static_cast<std::int32_t>(f), {uv[0], uv[1]}});
        }
  }
};

TEST(NormalSums, AtTheCornersOfDartsAndOfVerticesOfTwoFacesAreTheRowsProducts) {
  // As above with a third of the points at the corners of level-dependent vertices (B's rows), every point of
  // one face there (its block of no points); then the footpoints moved to other faces on the same chunk (the
  // kept pattern replaced).
  for (const Scheme scheme : {Scheme::Loop, Scheme::CatmullClark}) {
    const CornerCage cage(scheme);
    const sorpia::Topology t(cage.mesh);
    const sorpia::LimitSurface surface(t, cage.mesh.vertices.data(), scheme, Boundary::EdgeAndCorner, cage.tags);
    // B's row at a corner has other columns than the face's points' rows.
    const auto [f0, corner] = cage.corners[0];
    const double both[4] = {corner[0], corner[1], scheme == Scheme::Loop ? 0.3 : 0.5, 0.3};
    const std::int32_t faces[2] = {f0, f0};
    const sorpia::CsrMatrix two = surface.rows(faces, both, 2, 0).position;
    EXPECT_FALSE(std::equal(two.indices.begin(), two.indices.begin() + two.indptr[1], two.indices.begin() + two.indptr[1],
                            two.indices.end()));
    const std::size_t k = 6000;
    sorpia::ApproximationChunk chunk;
    for (const unsigned seed : {21u, 22u}) {
      sorpia::ApproximationChunk::State state;
      std::vector<double> points = random_footpoints(surface, k, seed, seed == 21u ? f0 : -1, state);
      std::vector<double> weights(k, 1.0);
      std::mt19937 rng(seed);
      std::vector<std::size_t> at;  // the points moved to corners
      for (std::size_t i = 0; i < k; i += 3) {
        const auto& [f, uv] = cage.corners[rng() % cage.corners.size()];
        state.face_ids[i] = f;
        state.uv[2 * i] = uv[0];
        state.uv[2 * i + 1] = uv[1];
        weights[i] = 0.5 + 0.001 * static_cast<double>(rng() % 1000);
        at.push_back(i);
      }
      std::vector<std::int32_t> at_faces;
      std::vector<double> at_uv, at_p(3 * at.size()), at_n(3 * at.size());
      for (const std::size_t i : at) {
        at_faces.push_back(state.face_ids[i]);
        at_uv.insert(at_uv.end(), {state.uv[2 * i], state.uv[2 * i + 1]});
      }
      surface.evaluate(at_faces.data(), at_uv.data(), at.size(), at_p.data(), nullptr, nullptr, at_n.data());
      for (std::size_t j = 0; j < at.size(); ++j)
        for (std::size_t c = 0; c < 3; ++c) {
          points[3 * at[j] + c] = at_p[3 * j + c] + 1e-3 * static_cast<double>(c + 1);
          state.normals[3 * at[j] + c] = at_n[3 * j + c];
        }
      if (seed == 21u) chunk = sorpia::ApproximationChunk(points.data(), k, weights.data(), 0);
      else chunk.set_points(points, weights);
      chunk.current = in_chunk_order(chunk, state);
      expect_normal_sums_are_the_rows_products(chunk, surface, points, weights);
    }
  }
}

// Points in memory whose search gives the footpoints `feet` (every point's) instead of searching, so that the
// driver's update is made from them.
class GivenFootpoints : public sorpia::InMemoryChunks {
 public:
  GivenFootpoints(sorpia::LimitSurface& surface, const std::vector<double>& points, sorpia::ApproximationChunk::State feet)
      : InMemoryChunks(surface, points.data(), points.size() / 3, nullptr, std::size_t{1} << 20), feet_(std::move(feet)) {}
  sorpia::DistanceSums search(const sorpia::FootpointOptions&) override {
    sorpia::ApproximationChunk& chunk = load(0, kPoints | kCurrent);
    chunk.current = in_chunk_order(chunk, feet_);
    sorpia::DistanceSums d;
    for (const double x : feet_.distances) {
      d.squares += x * x;
      d.max = std::max(d.max, x);
    }
    d.count = feet_.distances.size();
    return d;
  }

 private:
  sorpia::ApproximationChunk::State feet_;
};

TEST(Approximate, OneUpdateFromFootpointsAtDartsCornersEqualsADenseSolve) {
  // Points near the limit surface of a CornerCage inflated by 10%, their footpoints on the cage's (closest_points),
  // a third of them moved to the corners of its level-dependent vertices (the points there the inflated surface's
  // corners, 1e-3 off): one update by the driver (normal_sums, a face's points at a time and B's rows' points in
  // blocks of their own) equals the dense solve of the normal equations made a point's row at a time, to 1e-9.
  for (const Scheme scheme : {Scheme::Loop, Scheme::CatmullClark})
  for (const double tangential : {1.0, 0.1}) {
    const CornerCage cage(scheme);
    const sorpia::Topology topology(cage.mesh);
    const sorpia::Rules rules{scheme, Boundary::EdgeAndCorner, cage.tags};
    std::vector<double> big = cage.mesh.vertices;
    for (double& x : big) x *= 1.1;
    const sorpia::LimitSurface truth(topology, big.data(), scheme, Boundary::EdgeAndCorner, cage.tags);
    const std::size_t k = 900;
    sorpia::ApproximationChunk::State on_truth;
    std::vector<double> points = random_footpoints(truth, k, 31, -1, on_truth);
    sorpia::LimitSurface start(topology, cage.mesh.vertices.data(), scheme, Boundary::EdgeAndCorner, cage.tags);
    const sorpia::Footpoints found = sorpia::closest_points(start, topology, points.data(), k, {4, 10});
    sorpia::ApproximationChunk::State feet;
    feet.face_ids = found.face_ids;
    feet.uv = found.uv;
    std::mt19937 rng(32);
    for (std::size_t i = 0; i < k; i += 3) {
      const auto& [f, uv] = cage.corners[rng() % cage.corners.size()];
      feet.face_ids[i] = f;
      feet.uv[2 * i] = uv[0];
      feet.uv[2 * i + 1] = uv[1];
      truth.evaluate(&f, uv.data(), 1, &points[3 * i], nullptr, nullptr, nullptr);
      for (std::size_t c = 0; c < 3; ++c) points[3 * i + c] += 1e-3 * static_cast<double>(c + 1);
    }
    std::vector<double> at(3 * k);
    feet.normals.resize(3 * k);
    start.evaluate(feet.face_ids.data(), feet.uv.data(), k, at.data(), nullptr, nullptr, feet.normals.data());
    for (std::size_t i = 0; i < k; ++i)
      feet.distances.push_back(std::hypot(points[3 * i] - at[3 * i], points[3 * i + 1] - at[3 * i + 1],
                                          points[3 * i + 2] - at[3 * i + 2]));
    const std::vector<double> want = dense_update(start, rules, cage.mesh.vertices, points, feet.face_ids.data(),
                                                  feet.uv.data(), feet.normals.data(), 0.0, tangential);
    GivenFootpoints chunks(start, points, feet);
    sorpia::ApproximationOptions o;
    o.iterations = 1;
    o.tangential = tangential;
    o.fairness = 0.0;
    o.solver_tol = 1e-14;
    o.solver_max_iter = 1000000;
    o.robust.loss = sorpia::RobustLoss::None;
    const auto r = sorpia::approximate(start, chunks, o);
    ASSERT_EQ(r.best_iteration, 1) << "the update lowers the RMS distance";
    ASSERT_EQ(r.control_vertices.size(), want.size());
    for (std::size_t i = 0; i < want.size(); ++i)
      EXPECT_NEAR(r.control_vertices[i], want[i], 1e-9) << "entry " << i << " scheme " << static_cast<int>(scheme)
                                                         << " tangential " << tangential;
  }
}

TEST(Approximate, OneUpdateEqualsADenseSolveOfItsNormalEquations) {
  // One iteration, the update solved to 1e-14 of its residual: V is the dense solution (long double Cholesky of
  // the 36 x 36 system, independent of the core's sparse normal matrix and PCG) to 1e-9 of the cage's size (the
  // PCG's 1e-14 residual times the system's condition, a few thousand with the proximal term alone), for point
  // distance, the tangent-distance blend, with and without the fairness term, by CG and by LSPIA; and with the
  // points cut into chunks (of 7, of 1: the chunks' normal sums added in order, patterns merged or added in
  // place), the same solution.
  const TinyFit fit;
  struct Case {
    sorpia::ApproximationUpdate update;
    double tangential, fairness;
  };
  for (const Case c : {Case{sorpia::ApproximationUpdate::CG, 1.0, 0.0}, Case{sorpia::ApproximationUpdate::CG, 1.0, 1e-3},
                       Case{sorpia::ApproximationUpdate::CG, 0.1, 1e-3},
                       Case{sorpia::ApproximationUpdate::LSPIA, 1.0, 1e-3}})
  for (const std::size_t chunk : {std::size_t{1} << 20, std::size_t{7}, std::size_t{1}}) {
    const sorpia::Topology topology(fit.cage);
    sorpia::LimitSurface surface(topology, fit.start.data(), Scheme::Loop, Boundary::EdgeAndCorner);
    sorpia::ApproximationOptions o;
    o.iterations = 1;
    o.update = c.update;
    o.tangential = c.tangential;
    o.fairness = c.fairness;
    o.solver_tol = 1e-14;
    o.solver_max_iter = 1000000;
    o.robust.loss = sorpia::RobustLoss::None;  // the least-squares update the dense solve makes
    o.chunk_points = chunk;
    const auto r = sorpia::approximate(surface, fit.points.data(), fit.points.size() / 3, nullptr, o);
    ASSERT_EQ(r.best_iteration, 1) << "the update lowers the RMS distance";
    const std::vector<double> want = dense_update(fit, c.fairness, c.tangential);
    ASSERT_EQ(r.control_vertices.size(), want.size());
    for (std::size_t i = 0; i < want.size(); ++i)
      EXPECT_NEAR(r.control_vertices[i], want[i], 1e-9) << "entry " << i << " tangential " << c.tangential
                                                         << " fairness " << c.fairness << " chunks of " << chunk;
    EXPECT_LT(r.history[1].rms, r.history[0].rms);
    EXPECT_EQ(r.iterations, 1);
    EXPECT_EQ(r.stop_reason, "max_iter");
  }
}

TEST(Approximate, StopsAndReportsAsItsHistorySays) {
  // The run's figures: record 0 is the cage as given, each later one an update's; the returned iterate is that
  // of the lowest RMS; the relative figures are the absolute ones over the diagonal of the points' box.
  const TinyFit fit;
  const sorpia::Topology topology(fit.cage);
  sorpia::LimitSurface surface(topology, fit.start.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  std::vector<int> seen;
  sorpia::ApproximationOptions o;
  o.robust.loss = sorpia::RobustLoss::None;  // the iterate of the lowest RMS (a robust loss: of its criterion)
  const auto r = sorpia::approximate(surface, fit.points.data(), fit.points.size() / 3, nullptr, o,
                                     [&](const sorpia::ApproximationRecord& rec) { seen.push_back(rec.iteration); });
  ASSERT_EQ(r.history.size(), static_cast<std::size_t>(r.iterations) + 1);
  ASSERT_EQ(seen.size(), r.history.size());
  double lowest = INFINITY;
  int at = -1;
  for (std::size_t i = 0; i < r.history.size(); ++i) {
    EXPECT_EQ(seen[i], static_cast<int>(i));
    EXPECT_DOUBLE_EQ(r.history[i].rms_relative, r.history[i].rms / r.diagonal);
    if (r.history[i].rms < lowest) lowest = r.history[i].rms, at = static_cast<int>(i);
  }
  EXPECT_EQ(r.best_iteration, at);
  double d2 = 0.0;
  for (const double d : r.footpoints.distances) d2 += d * d;
  EXPECT_NEAR(std::sqrt(d2 / static_cast<double>(r.footpoints.distances.size())), lowest, 1e-15);
  EXPECT_TRUE(r.stop_reason == "converged" || r.stop_reason == "max_iter");
}

TEST(Approximate, DataBeyondTwoToThe200IsFittedScaledExactly) {
  // 2^300 times the points and the cage: 2^300 times the control vertices and absolute figures, bit for bit;
  // the relative figures the same (the core's one scaling, detail/scaling.hpp).
  const TinyFit fit;
  const sorpia::Topology topology(fit.cage);
  sorpia::ApproximationOptions o;
  o.iterations = 3;
  sorpia::LimitSurface one_surface(topology, fit.start.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  const auto one = sorpia::approximate(one_surface, fit.points.data(), fit.points.size() / 3, nullptr, o);
  const std::vector<double> big_start = scaled(fit.start, 300), big_points = scaled(fit.points, 300);
  sorpia::LimitSurface big_surface(topology, big_start.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  const auto big = sorpia::approximate(big_surface, big_points.data(), big_points.size() / 3, nullptr, o);
  EXPECT_EQ(big.control_vertices, scaled(one.control_vertices, 300));
  EXPECT_EQ(big.footpoints.distances, scaled(one.footpoints.distances, 300));
  ASSERT_EQ(big.history.size(), one.history.size());
  for (std::size_t i = 0; i < one.history.size(); ++i) {
    EXPECT_EQ(big.history[i].rms, std::ldexp(one.history[i].rms, 300));
    EXPECT_EQ(big.history[i].rms_relative, one.history[i].rms_relative);
  }
}

TEST(Approximate, RefusesBadOptionsAndData) {
  const TinyFit fit;
  const sorpia::Topology topology(fit.cage);
  sorpia::LimitSurface surface(topology, fit.start.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  sorpia::ApproximationOptions o;
  o.update = sorpia::ApproximationUpdate::LSPIA;
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::approximate(surface, fit.points.data(), 3, nullptr, o); }, {"it takes tangential = 1 only"});
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::approximate(surface, fit.points.data(), 0, nullptr, {}); }, {"points is empty"});
  const double zero[3] = {0.0, 0.0, 0.0};
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::approximate(surface, fit.points.data(), 3, zero, {}); }, {"weights are all 0"});
}

TEST(Approximate, StopRuleLooksAtThreeIterations) {
  // The rule on the lowest RMS after each iteration: one small step before large ones (a plateau) does not stop
  // a run; three small ones in a row do; with tol = 0 only no decrease at all over three does.
  EXPECT_FALSE(sorpia::rms_levelled({1.0, 0.9999, 0.5}, 1e-3, 3));
  EXPECT_FALSE(sorpia::rms_levelled({1.0, 0.9999, 0.9998, 0.5}, 1e-3, 3));
  EXPECT_FALSE(sorpia::rms_levelled({0.2, 0.1, 0.09995, 0.0999}, 1e-3, 3));
  EXPECT_TRUE(sorpia::rms_levelled({1.0, 0.9999, 0.9998, 0.9997}, 1e-3, 3));
  EXPECT_TRUE(sorpia::rms_levelled({0.5, 0.3, 0.2999, 0.2998, 0.2998}, 1e-3, 3));
  EXPECT_FALSE(sorpia::rms_levelled({1.0, 1.0, 1.0, 0.9999}, 0.0, 3));
  EXPECT_TRUE(sorpia::rms_levelled({1.0, 0.5, 0.5, 0.5, 0.5}, 0.0, 3));
}

}  // namespace
