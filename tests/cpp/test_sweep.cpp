// The "sor"/"gs" engine: the E_k computed inside the sweep against a separate
// residual pass and against B from scratch, threaded sweeps against the
// sequential one, the threads parameter. The threaded cases run their ranges
// on real threads (SweepRangesOnThreads): the meshes are below the
// production cut of vertices a thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "limit_case.hpp"
#include "parallel_ranges.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/topology.hpp"

namespace {

using Case = sorpia_test::LimitCase;
using sorpia_test::error_from_scratch;
using sorpia_test::limit_case;
using sorpia_test::max_abs_diff;
using sorpia_test::SweepRangesOnThreads;

// 0, ..., n-1 shuffled by std::mt19937(seed).
std::vector<std::int32_t> permutation(std::size_t n, unsigned seed) {
  std::vector<std::int32_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(seed));
  return perm;
}

// The same mesh with its vertices numbered at random (old vertex i is new
// vertex permutation(n, seed)[i]): every neighbour far away in index, so
// almost every residual is deferred past the sweep and the thread ranges
// share most vertices (interface).
sorpia::Mesh shuffled(const sorpia::Mesh& m, unsigned seed) {
  const std::vector<std::int32_t> perm = permutation(m.n_vertices(), seed);
  sorpia::Mesh out;
  out.vertices.resize(m.vertices.size());
  for (std::size_t i = 0; i < m.n_vertices(); ++i)
    for (int a = 0; a < 3; ++a) out.vertices[3 * perm[i] + a] = m.vertices[3 * i + a];
  for (std::int32_t f : m.face_vertex_indices) out.face_vertex_indices.push_back(perm[f]);
  return out;
}

// Meshes past the sweep's lag (the fused residual runs
// behind the front and the seams are deferred), with boundary, a pole, a
// scrambled vertex order, and an icosphere numbered level by level (its
// coarse quarter reaches far ahead: E_k by a residual pass; index ranges
// would share most vertices: slabs on two or more threads).
const std::vector<Case>& cases() {
  static const std::vector<Case> c = {
      limit_case(sorpia::irregular(26000, 7), "irregular"), limit_case(sorpia::torus(130, 130), "torus"),
      limit_case(sorpia::grid(90, 70), "grid"),             limit_case(sorpia::pole(48), "pole"),
      limit_case(shuffled(sorpia::irregular(40000, 3), 11), "shuffled"),
      limit_case(sorpia::icosphere(6), "icosphere")};
  return c;
}

sorpia::SolveResult run(const Case& c, int threads, bool two_pass, double omega = 1.0, int max_iter = 1000) {
  sorpia::SolveOptions opt;
  opt.method = sorpia::Method::Sor;
  opt.omega_rule = sorpia::OmegaRule::Given;
  opt.omega = omega;
  opt.threads = threads;
  opt.two_pass = two_pass;
  opt.max_iter = max_iter;
  return sorpia::solve(c.op, c.mesh.vertices.data(), opt);
}

double max_abs(const std::vector<double>& a) {
  double m = 0.0;
  for (double x : a) m = std::max(m, std::abs(x));
  return m;
}

TEST(Sweep, FusedErrorsEqualTwoPassBitForBit) {
  const SweepRangesOnThreads on_threads;
  // The fused sweep computes each residual by the same formula, in the same
  // summation order, from the same final values as the residual pass: the
  // E_k, the iterates and the iteration counts must agree exactly.
  for (const Case& c : cases())
    for (auto [threads, omega] : {std::pair{1, 1.0}, std::pair{2, 1.0}, std::pair{3, 1.3}}) {
      const sorpia::SolveResult fused = run(c, threads, false, omega);
      const sorpia::SolveResult two = run(c, threads, true, omega);
      ASSERT_TRUE(fused.converged()) << c.name;
      EXPECT_EQ(fused.iterations, two.iterations) << c.name << " threads " << threads;
      EXPECT_EQ(fused.initial_error, two.initial_error) << c.name;  // E_0 inside the first sweep
      EXPECT_EQ(fused.errors, two.errors) << c.name << " threads " << threads << " omega " << omega;
      EXPECT_EQ(fused.control_vertices, two.control_vertices) << c.name;
    }
}

TEST(Sweep, ErrorsArePapersEkFromScratch) {
  const SweepRangesOnThreads on_threads;
  // E_k after k sweeps, recomputed with the CSR matrix B (a different
  // summation order: equal to rounding, 1e-12 of E_0 covers it).
  for (const Case& c : cases())
    for (int threads : {1, 2}) {
      const sorpia::SolveResult full = run(c, threads, false);
      for (int k : {threads, 4}) {
        const sorpia::SolveResult part = run(c, threads, false, 1.0, k);
        ASSERT_EQ(part.iterations, k);
        EXPECT_EQ(part.errors, std::vector<double>(full.errors.begin(), full.errors.begin() + k + 1));
        EXPECT_NEAR(error_from_scratch(c, part.control_vertices) / part.initial_error, part.errors[k], 1e-12)
            << c.name << " k " << k;
      }
    }
}

TEST(Sweep, ThreadsGiveTheSequentialSolution) {
  const SweepRangesOnThreads on_threads;
  for (const Case& c : cases()) {
    const sorpia::SolveResult one = run(c, 1, false);
    ASSERT_TRUE(one.converged()) << c.name;
    for (int threads : {2, 3, 7}) {
      const sorpia::SolveResult t = run(c, threads, false);
      ASSERT_TRUE(t.converged()) << c.name << " threads " << threads;
      // Both stop at E_k < 1e-10 E_0; B's smallest eigenvalue is about 0.2,
      // so the two solutions differ by well under 1e-8 of the coordinates.
      EXPECT_LT(max_abs_diff(t.control_vertices, one.control_vertices), 1e-8 * max_abs(one.control_vertices))
          << c.name << " threads " << threads;
      // Gauss-Seidel with the interface vertices last: nearly the same ordering.
      EXPECT_LE(t.iterations, std::ceil(1.15 * one.iterations)) << c.name << " threads " << threads;
      EXPECT_LT(error_from_scratch(c, t.control_vertices), 1.01e-10 * t.initial_error) << c.name;
    }
  }
}

TEST(Sweep, RangesOnThreadsEqualRangesOneAfterAnother) {
  // No two vertices of different ranges are adjacent, and the interface runs
  // after the join: the iterates do not depend on whether the ranges run at
  // once, bit for bit (what the pool relies on when it runs them in turn). Only
  // where the ranges share few vertices (not the pole, the icosphere, or 7
  // ranges): crowded ranges are replaced by slabs only when they run on
  // threads.
  const std::vector<Case>& all = cases();
  for (const Case* c : {&all[0], &all[1], &all[2], &all[4]})
    for (int threads : {2, 3}) {
      sorpia::SolveResult at_once, in_turn;
      {
        const SweepRangesOnThreads on_threads;
        at_once = run(*c, threads, false, 1.0, 8);
      }
      {
        const SweepRangesOnThreads in_order(SweepRangesOnThreads::kNever);
        in_turn = run(*c, threads, false, 1.0, 8);
      }
      EXPECT_EQ(at_once.errors, in_turn.errors) << c->name << " threads " << threads;
      EXPECT_EQ(at_once.control_vertices, in_turn.control_vertices) << c->name << " threads " << threads;
      EXPECT_EQ(at_once.reordered, std::string(c->name) == "shuffled") << c->name << " threads " << threads;
      EXPECT_EQ(in_turn.reordered, at_once.reordered) << c->name << " threads " << threads;
    }
}

TEST(Sweep, PoorOrderIsSweptInItsOwnOrderAndReturnedInTheCallers) {
  const SweepRangesOnThreads on_threads;
  // The shuffled mesh is the irregular one renumbered: its solution must be
  // the same vertices renumbered, though the core sweeps it breadth-first.
  const sorpia::Mesh m = sorpia::irregular(40000, 3);
  const Case a = limit_case(m, "natural");
  const Case& b = cases()[4];  // shuffled(irregular(40000, 3), 11)
  const std::vector<std::int32_t> perm = permutation(m.n_vertices(), 11);  // as shuffled() numbered it
  for (int threads : {1, 2}) {
    const sorpia::SolveResult ra = run(a, threads, false), rb = run(b, threads, false);
    EXPECT_FALSE(ra.reordered);
    EXPECT_TRUE(rb.reordered);
    ASSERT_TRUE(rb.converged());
    double d = 0.0;
    for (std::size_t i = 0; i < m.n_vertices(); ++i)
      for (int c = 0; c < 3; ++c)
        d = std::max(d, std::abs(rb.control_vertices[3 * perm[i] + c] - ra.control_vertices[3 * i + c]));
    EXPECT_LT(d, 1e-8 * max_abs(ra.control_vertices));  // both to E_k < 1e-10 E_0
    EXPECT_LE(rb.iterations, std::ceil(1.15 * ra.iterations));
    EXPECT_LT(error_from_scratch(b, rb.control_vertices), 1.01e-10 * rb.initial_error);
  }
}

TEST(Sweep, CrowdedRangesAreSweptInSlabsAndReturnedInTheCallersOrder) {
  const SweepRangesOnThreads on_threads;
  // icosphere(6) split into two index ranges: the first holds every coarse
  // vertex, each with neighbours in both. On two or more threads the engine
  // sweeps slabs across the sphere instead; the irregular mesh's own ranges
  // share few vertices and are kept.
  const Case& ico = cases()[5];
  const sorpia::SolveResult one = run(ico, 1, false);
  EXPECT_FALSE(one.reordered);
  for (int threads : {2, 3}) {
    const sorpia::SolveResult t = run(ico, threads, false);
    EXPECT_TRUE(t.reordered) << threads;
    ASSERT_TRUE(t.converged());
    // The caller's order: the same vertices as the sequential sweep's, to
    // what the stopping rule leaves (see ThreadsGiveTheSequentialSolution).
    EXPECT_LT(max_abs_diff(t.control_vertices, one.control_vertices), 1e-8 * max_abs(one.control_vertices))
        << threads;
    EXPECT_LT(error_from_scratch(ico, t.control_vertices), 1.01e-10 * t.initial_error) << threads;
  }
  EXPECT_FALSE(run(cases()[0], 2, false).reordered);
}

TEST(Sweep, StopAtZeroReturnsV0) {
  const SweepRangesOnThreads on_threads;
  // Every vertex at one point: B V0 = V0 up to rounding (rows sum to 1), so
  // E_0 is at rounding level and the run stops at k = 0; the first sweep,
  // which computed E_0, must be undone. The icosphere is swept in slabs on
  // two threads: with no extent to cut, all its vertices fall in the first.
  for (sorpia::Mesh m : {sorpia::irregular(20000, 5), sorpia::icosphere(6)}) {
    for (std::size_t i = 0; i < m.n_vertices(); ++i)
      for (int a = 0; a < 3; ++a) m.vertices[3 * i + a] = 0.1 * (a + 1);
    const Case c = limit_case(m, "point");
    for (int threads : {1, 2}) {
      const sorpia::SolveResult r = run(c, threads, false);
      EXPECT_EQ(r.iterations, 0);
      EXPECT_TRUE(r.converged());
      EXPECT_EQ(r.control_vertices, m.vertices);
      EXPECT_EQ(r.reordered, threads == 2 && m.n_vertices() == 40962)
          << m.n_vertices();
    }
  }
}

TEST(Sweep, OneThreadIsTheTextbookSweepOrder) {
  // threads = 1 sweeps vertices 0, 1, ..., n-1: after one sweep V equals the
  // SOR formula applied in that order (same arithmetic as the engine).
  const Case& c = cases()[0];
  const sorpia::LimitOperator& op = c.op;
  std::vector<double> x = c.mesh.vertices;
  const double omega = 1.3;
  for (std::size_t i = 0; i < op.n; ++i) {
    double s[3] = {0, 0, 0};
    for (int p = op.offsets[i]; p < op.offsets[i + 1]; ++p)
      for (int a = 0; a < 3; ++a) s[a] += x[3 * op.neighbors[p] + a];
    for (int a = 0; a < 3; ++a)
      x[3 * i + a] += omega / op.diag[i] * (c.mesh.vertices[3 * i + a] - (op.diag[i] * x[3 * i + a] + op.weight[i] * s[a]));
  }
  EXPECT_EQ(run(c, 1, false, omega, 1).control_vertices, x);
}

TEST(Sweep, AnyColumnCountSweepsAsThreeColumns) {
  // (n, 5) data runs the row kernels on (n, k) arrays (solve_sor_columns),
  // (n, 3) data the engine's 4-lane rows: the columns of a sweep are
  // independent, so after the same sweeps (one thread: the engine in the
  // caller's order, as OneThreadIsTheTextbookSweepOrder checks) each column
  // has the bits of the 3-column solve. Uniform rows and per-entry weights.
  const Case& c = cases()[0];
  const sorpia::LimitOperator per_entry = sorpia::limit_operator(sorpia_test::perturbed(c.b, 0.3, 5));
  const std::vector<double>& v = c.mesh.vertices;
  const std::size_t n = c.op.n;
  std::vector<double> five(5 * n), b(3 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) five[5 * i + a] = v[3 * i + a];
    five[5 * i + 3] = b[3 * i] = 2.0 * v[3 * i];
    five[5 * i + 4] = b[3 * i + 1] = -v[3 * i + 1];
  }
  sorpia::SolveOptions opt;
  opt.method = sorpia::Method::Sor;
  opt.omega_rule = sorpia::OmegaRule::Given;
  opt.omega = 1.3;
  opt.threads = 1;
  opt.tol = 1e-300;  // never met: every run makes max_iter sweeps
  opt.max_iter = 4;
  for (const sorpia::LimitOperator* op : {&c.op, &per_entry}) {
    const sorpia::SolveResult r5 = sorpia::solve(*op, five.data(), 5, nullptr, opt);
    const sorpia::SolveResult ra = sorpia::solve(*op, v.data(), 3, nullptr, opt);
    const sorpia::SolveResult rb = sorpia::solve(*op, b.data(), 3, nullptr, opt);
    ASSERT_EQ(r5.iterations, 4);
    ASSERT_EQ(ra.iterations, 4);
    ASSERT_EQ(rb.iterations, 4);
    std::vector<double> split(5 * n);
    for (std::size_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) split[5 * i + a] = ra.control_vertices[3 * i + a];
      for (int a = 0; a < 2; ++a) split[5 * i + 3 + a] = rb.control_vertices[3 * i + a];
    }
    EXPECT_EQ(r5.control_vertices, split) << (op == &c.op ? "uniform rows" : "per-entry weights");
  }
}

TEST(Sweep, ThreadsParameterChecked) {
  const Case c = limit_case(sorpia::pole(48), "pole");  // parameter checks: no large case needed
  for (int bad : {0, -1, sorpia::max_threads + 1}) {
    sorpia::SolveOptions opt;
    opt.threads = bad;
    EXPECT_THROW(sorpia::solve(c.op, c.mesh.vertices.data(), opt), sorpia::ParameterError) << bad;
  }
  sorpia::SolveOptions opt;
  opt.method = sorpia::Method::Cg;
  opt.threads = 2;
  EXPECT_THROW(sorpia::solve(c.op, c.mesh.vertices.data(), opt), sorpia::ParameterError);
  opt.method = sorpia::Method::Gs;
  EXPECT_TRUE(sorpia::solve(c.op, c.mesh.vertices.data(), opt).converged());
  // More threads than vertices: empty ranges, still the solution.
  opt.threads = 64;
  EXPECT_TRUE(sorpia::solve(c.op, c.mesh.vertices.data(), opt).converged());
}

}  // namespace
