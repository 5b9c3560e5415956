// Operators whose rows have several weights (LimitOperator::values): every
// method against a dense direct solve, and the sweep's fused E_k, threads and
// vertex orders on them. The operators are Loop limit matrices from
// OpenSubdiv with each row's off-diagonal weights perturbed (row sums and
// diagonal kept), built with sorpia::limit_operator(CsrMatrix).
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
#include "sorpia/limit.hpp"
#include "sorpia/reference.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/topology.hpp"

namespace {

using sorpia_test::error_from_scratch;
using sorpia_test::max_abs_diff;
using sorpia_test::perturbed;
using sorpia_test::SweepRangesOnThreads;

// The mesh, the perturbed matrix as b (what error_from_scratch measures
// with) and the operator built from it.
using WeightedCase = sorpia_test::LimitCase;

WeightedCase weighted_case(const sorpia::Mesh& m, const char* name, unsigned seed) {
  const sorpia::Topology topo(m);
  sorpia::CsrMatrix b = perturbed(sorpia::reference_limit_matrix(topo, sorpia::Boundary::EdgeAndCorner), 0.2, seed);
  sorpia::LimitOperator op = sorpia::limit_operator(b);
  return {name, m, std::move(b), std::move(op)};
}

// X with B X = V (n, 3) by Gaussian elimination with partial pivoting on the
// dense B: independent of every solver.
std::vector<double> dense_solve(const sorpia::CsrMatrix& b, const std::vector<double>& v) {
  const std::size_t n = b.n_rows;
  std::vector<double> a(n * n, 0.0), x = v;
  for (std::size_t i = 0; i < n; ++i)
    for (std::int32_t p = b.indptr[i]; p < b.indptr[i + 1]; ++p) a[i * n + b.indices[p]] += b.data[p];
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t piv = k;
    for (std::size_t i = k + 1; i < n; ++i)
      if (std::abs(a[i * n + k]) > std::abs(a[piv * n + k])) piv = i;
    if (piv != k) {
      std::swap_ranges(a.begin() + k * n, a.begin() + (k + 1) * n, a.begin() + piv * n);
      std::swap_ranges(x.begin() + 3 * k, x.begin() + 3 * k + 3, x.begin() + 3 * piv);
    }
    for (std::size_t i = k + 1; i < n; ++i) {
      const double f = a[i * n + k] / a[k * n + k];
      if (f == 0.0) continue;
      for (std::size_t j = k; j < n; ++j) a[i * n + j] -= f * a[k * n + j];
      for (int c = 0; c < 3; ++c) x[3 * i + c] -= f * x[3 * k + c];
    }
  }
  for (std::size_t k = n; k-- > 0;) {
    for (std::size_t j = k + 1; j < n; ++j)
      for (int c = 0; c < 3; ++c) x[3 * k + c] -= a[k * n + j] * x[3 * j + c];
    for (int c = 0; c < 3; ++c) x[3 * k + c] /= a[k * n + k];
  }
  return x;
}

// max_k |a_k|
double max_abs(const std::vector<double>& a) { return max_abs_diff(a, std::vector<double>(a.size(), 0.0)); }

sorpia::SolveResult run(const WeightedCase& c, sorpia::Method method, int threads = 1, bool two_pass = false,
                        int max_iter = 5000, double tol = 1e-12) {
  sorpia::SolveOptions opt;
  opt.method = method;
  opt.threads = threads;
  opt.two_pass = two_pass;
  opt.max_iter = max_iter;
  opt.tol = tol;
  return sorpia::solve(c.op, c.mesh.vertices.data(), opt);
}

TEST(PerEntryWeights, EveryMethodGivesTheDirectSolution) {
  // A closed mesh and one with boundary and one-face corners, small enough
  // for a dense solve.
  const std::vector<WeightedCase> cases = {weighted_case(sorpia::irregular(300, 5), "irregular", 1),
                                           weighted_case(sorpia::grid(16, 12), "grid", 2)};
  for (const WeightedCase& c : cases) {
    ASSERT_FALSE(c.op.uniform()) << c.name;
    ASSERT_FALSE(sorpia::is_symmetrisable(c.op)) << c.name;
    const std::vector<double> ref = dense_solve(c.b, c.mesh.vertices);
    for (sorpia::Method m : {sorpia::Method::Pia, sorpia::Method::Wpia, sorpia::Method::Gs, sorpia::Method::Sor,
                             sorpia::Method::Cg, sorpia::Method::Hss, sorpia::Method::Whss}) {
      const sorpia::SolveResult r = run(c, m);
      const char* name = sorpia::method_name(m);
      ASSERT_TRUE(r.converged()) << c.name << " " << name << " " << sorpia::stop_reason_name(r.stop_reason);
      // E_k < 1e-12 E_0 and B's eigenvalues stay near the Loop matrix's, in
      // about [0.2, 1]: the error in V is a few 1e-12 E_0, under 1e-9 of the
      // coordinates.
      EXPECT_LT(max_abs_diff(r.control_vertices, ref), 1e-9 * max_abs(ref)) << c.name << " " << name;
      EXPECT_LT(error_from_scratch(c, r.control_vertices), 1.01e-12 * r.initial_error) << c.name << " " << name;
      if (m == sorpia::Method::Cg) {
        EXPECT_EQ(r.variant, "bicgstab") << c.name;  // B is not symmetrisable
      }
    }
  }
}

// Past the sweep's lag (its residual front runs behind the update front and
// the torus's seams are deferred), with a boundary, in a shuffled order (swept
// breadth-first) and level by level (swept in slabs on threads).
const std::vector<WeightedCase>& sweep_cases() {
  static const std::vector<WeightedCase> c = [] {
    sorpia::Mesh shuffled = sorpia::irregular(30000, 3);
    std::vector<std::int32_t> perm(shuffled.n_vertices());
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), std::mt19937(11));
    std::vector<double> v(shuffled.vertices.size());
    for (std::size_t i = 0; i < perm.size(); ++i)
      for (int a = 0; a < 3; ++a) v[3 * perm[i] + a] = shuffled.vertices[3 * i + a];
    shuffled.vertices = v;
    for (std::int32_t& f : shuffled.face_vertex_indices) f = perm[f];
    return std::vector<WeightedCase>{weighted_case(sorpia::irregular(20000, 7), "irregular", 3),
                                     weighted_case(sorpia::torus(120, 110), "torus", 4),
                                     weighted_case(sorpia::grid(90, 70), "grid", 5),
                                     weighted_case(shuffled, "shuffled", 6),
                                     weighted_case(sorpia::icosphere(6), "icosphere", 7)};
  }();
  return c;
}

TEST(PerEntryWeights, FusedErrorsEqualTwoPassAndTheResidualFromScratch) {
  // The fused E_k against the residual pass (bit for bit, on one thread and
  // on real threads), and the last E_k against B from scratch (another
  // summation order: to rounding, 1e-12 of E_0).
  const SweepRangesOnThreads on_threads;
  for (const WeightedCase& c : sweep_cases())
    for (int threads : {1, 3}) {
      const sorpia::SolveResult fused = run(c, sorpia::Method::Gs, threads, false, 6);
      const sorpia::SolveResult two = run(c, sorpia::Method::Gs, threads, true, 6);
      ASSERT_EQ(fused.iterations, 6) << c.name;
      EXPECT_EQ(fused.errors, two.errors) << c.name << " threads " << threads;
      EXPECT_EQ(fused.control_vertices, two.control_vertices) << c.name << " threads " << threads;
      EXPECT_NEAR(error_from_scratch(c, fused.control_vertices) / fused.initial_error, fused.errors.back(), 1e-12)
          << c.name << " threads " << threads;
    }
}

TEST(PerEntryWeights, SweepConvergesInEveryOrderAndOnThreads) {
  // The shuffled mesh is swept breadth-first, the icosphere in slabs on
  // threads: the renumbered operator must carry each entry's weight along.
  const SweepRangesOnThreads on_threads;
  for (const WeightedCase& c : sweep_cases()) {
    const sorpia::SolveResult one = run(c, sorpia::Method::Sor, 1, false, 1000, 1e-10);
    ASSERT_TRUE(one.converged()) << c.name;
    EXPECT_LT(error_from_scratch(c, one.control_vertices), 1.01e-10 * one.initial_error) << c.name;
    EXPECT_EQ(one.reordered, std::string(c.name) == "shuffled") << c.name;
    for (int threads : {2, 3}) {
      const sorpia::SolveResult t = run(c, sorpia::Method::Sor, threads, false, 1000, 1e-10);
      ASSERT_TRUE(t.converged()) << c.name << " threads " << threads;
      EXPECT_LT(error_from_scratch(c, t.control_vertices), 1.01e-10 * t.initial_error) << c.name << " " << threads;
      EXPECT_LT(max_abs_diff(t.control_vertices, one.control_vertices), 1e-8 * max_abs(one.control_vertices))
          << c.name << " threads " << threads;
      EXPECT_LE(t.iterations, std::ceil(1.15 * one.iterations)) << c.name << " threads " << threads;
      const std::string name = c.name;
      EXPECT_EQ(t.reordered, name == "shuffled" || name == "icosphere")
          << name << " threads " << threads;
    }
  }
}

}  // namespace
