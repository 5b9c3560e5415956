// The solvers against dense references: the compact operator, one SOR-PIA
// sweep, one PIA step, the full solves, the stopping monitor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include "limit_case.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/topology.hpp"

namespace {

using Dense = std::vector<std::vector<double>>;

Dense dense_of(const sorpia::CsrMatrix& b) {
  Dense d(b.n_rows, std::vector<double>(b.n_cols, 0.0));
  for (std::size_t i = 0; i < b.n_rows; ++i)
    for (int p = b.indptr[i]; p < b.indptr[i + 1]; ++p) d[i][b.indices[p]] += b.data[p];
  return d;
}

using Case = sorpia_test::LimitCase;
using sorpia_test::error_from_scratch;
using sorpia_test::limit_case;
using sorpia_test::max_abs_diff;
using sorpia_test::multiply;

std::vector<Case> cases() {
  return {limit_case(sorpia::irregular(150, 3)), limit_case(sorpia::grid(6, 5)), limit_case(sorpia::pole(40))};
}

TEST(LimitOperator, ReproducesTheOpenSubdivMatrix) {
  for (const Case& c : cases()) {
    const Dense d = dense_of(c.b);
    Dense e(c.op.n, std::vector<double>(c.op.n, 0.0));
    for (std::size_t i = 0; i < c.op.n; ++i) {
      e[i][i] += c.op.diag[i];
      for (int p = c.op.offsets[i]; p < c.op.offsets[i + 1]; ++p) e[i][c.op.neighbors[p]] += c.op.weight[i];
    }
    for (std::size_t i = 0; i < c.op.n; ++i)
      for (std::size_t j = 0; j < c.op.n; ++j) ASSERT_EQ(d[i][j], e[i][j]) << i << "," << j;  // exact copy
    std::vector<double> y1(3 * c.op.n), y2(3 * c.op.n);
    sorpia::apply(c.op, c.mesh.vertices.data(), y1.data());
    multiply(c.b, c.mesh.vertices.data(), y2.data());
    EXPECT_LT(max_abs_diff(y1, y2), 1e-15);  // same sums, different order
  }
}

// A row with unequal neighbour weights makes the operator non-uniform: every
// entry keeps its own weight, and apply and to_csr give the matrix back.
TEST(LimitOperator, KeepsRowsWithSeveralWeights) {
  sorpia::CsrMatrix b;
  b.n_rows = b.n_cols = 3;
  b.indptr = {0, 3, 4, 6};
  b.indices = {0, 1, 2, 1, 0, 2};
  b.data = {0.5, 0.2, 0.3, 1.0, 0.25, 0.75};  // row 0: unequal neighbour weights
  const auto op = sorpia::limit_operator(b);
  ASSERT_FALSE(op.uniform());
  EXPECT_FALSE(sorpia::is_symmetrisable(op));
  const auto back = sorpia::to_csr(op);
  EXPECT_EQ(back.indptr, b.indptr);
  EXPECT_EQ(back.indices, (std::vector<std::int32_t>{0, 1, 2, 1, 0, 2}));
  EXPECT_EQ(back.data, b.data);
  const std::vector<double> x = {1, 2, 3, -1, 0.5, 4, 0.25, -2, 8};
  std::vector<double> y1(9), y2(9);
  sorpia::apply(op, x.data(), y1.data());
  multiply(b, x.data(), y2.data());
  EXPECT_LT(max_abs_diff(y1, y2), 1e-15);  // same products, summed in another order
}

TEST(LimitOperator, RefusesRowsWithoutPositiveDiagonal) {
  sorpia::CsrMatrix b;
  b.n_rows = b.n_cols = 2;
  b.indptr = {0, 2, 3};
  b.indices = {0, 1, 0};
  b.data = {0.5, 0.5, 1.0};  // row 1 has no diagonal entry
  EXPECT_THROW(sorpia::limit_operator(b), std::logic_error);
}

TEST(LimitOperator, SymmetrisableExactlyWhenClosed) {
  EXPECT_TRUE(sorpia::is_symmetrisable(limit_case(sorpia::irregular(150, 3)).op));
  EXPECT_FALSE(sorpia::is_symmetrisable(limit_case(sorpia::grid(6, 5)).op));
}

// One SOR sweep by the textbook formula on the dense matrix:
// x_i <- x_i + omega (b_i - sum_j B_ij x_j) / B_ii, j < i already updated.
TEST(Solve, OneSorSweepEqualsDenseReference) {
  for (const Case& c : cases()) {
    const Dense d = dense_of(c.b);
    const std::size_t n = c.op.n;
    const double omega = 1.3;
    std::vector<double> x = c.mesh.vertices;
    const std::vector<double>& v0 = c.mesh.vertices;
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        double s = 0.0;
        for (std::size_t j = 0; j < n; ++j) s += d[i][j] * x[3 * j + k];
        x[3 * i + k] += omega * (v0[3 * i + k] - s) / d[i][i];
      }
    sorpia::SolveOptions opt;
    opt.method = sorpia::Method::Sor;
    opt.omega_rule = sorpia::OmegaRule::Given;
    opt.omega = omega;
    opt.max_iter = 1;
    const sorpia::SolveResult r = sorpia::solve(c.op, v0.data(), opt);
    EXPECT_EQ(r.iterations, 1);
    EXPECT_LT(max_abs_diff(r.control_vertices, x), 1e-14);
  }
}

TEST(Solve, OnePiaStepEqualsDenseReference) {
  for (const Case& c : cases()) {
    const Dense d = dense_of(c.b);
    const std::vector<double>& v0 = c.mesh.vertices;
    std::vector<double> x = v0;
    for (std::size_t i = 0; i < c.op.n; ++i)
      for (int k = 0; k < 3; ++k) {
        double s = 0.0;
        for (std::size_t j = 0; j < c.op.n; ++j) s += d[i][j] * v0[3 * j + k];
        x[3 * i + k] += v0[3 * i + k] - s;
      }
    sorpia::SolveOptions opt;
    opt.method = sorpia::Method::Pia;
    opt.max_iter = 1;
    EXPECT_LT(max_abs_diff(sorpia::solve(c.op, v0.data(), opt).control_vertices, x), 1e-14);
  }
}

TEST(Solve, EveryMethodSolvesBVEqualsV0) {
  using M = sorpia::Method;
  for (const Case& c : cases())
    for (M m : {M::Pia, M::Wpia, M::Gs, M::Sor, M::Cg, M::Hss, M::Whss, M::Gmres, M::Cgls, M::Auto}) {
      sorpia::SolveOptions opt;
      opt.method = m;
      const sorpia::SolveResult r = sorpia::solve(c.op, c.mesh.vertices.data(), opt);
      ASSERT_TRUE(r.converged()) << sorpia::method_name(m);
      ASSERT_EQ(r.errors.size(), static_cast<std::size_t>(r.iterations) + 1);
      // The paper's stopping rule, recomputed from scratch (Krylov methods
      // track a recursive residual: allow rounding on top of it).
      EXPECT_LT(error_from_scratch(c, r.control_vertices), 1.01e-10 * r.initial_error + 1e-15)
          << sorpia::method_name(m);
    }
}

// Not a Loop matrix: diag 0.1 and two neighbours of weight 0.45 on 3
// vertices, eigenvalues 1 and -0.35 (twice): invertible, indefinite, and
// I - B has eigenvalues beyond -1, so PIA diverges.
sorpia::LimitOperator indefinite_triangle() {
  sorpia::LimitOperator op;
  op.n = 3;
  op.offsets = {0, 2, 4, 6};
  op.neighbors = {1, 2, 0, 2, 0, 1};
  op.diag = {0.1, 0.1, 0.1};
  op.weight = {0.45, 0.45, 0.45};
  return op;
}

TEST(Solve, DivergenceStopsWhileFinite) {
  const sorpia::LimitOperator op = indefinite_triangle();
  const std::vector<double> v0 = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  sorpia::SolveOptions opt;
  opt.method = sorpia::Method::Pia;
  const sorpia::SolveResult r = sorpia::solve(op, v0.data(), opt);
  EXPECT_EQ(r.stop_reason, sorpia::StopReason::Diverged);
  for (double x : r.control_vertices) EXPECT_TRUE(std::isfinite(x));
}

// max_i ||v0_i - (B x)_i||, by the public B x.
double max_residual(const sorpia::LimitOperator& op, const std::vector<double>& v0, const std::vector<double>& x) {
  std::vector<double> bx(x.size());
  sorpia::apply(op, x.data(), bx.data());
  double m = 0.0;
  for (std::size_t i = 0; i < op.n; ++i)
    m = std::max(m, std::hypot(v0[3 * i] - bx[3 * i], v0[3 * i + 1] - bx[3 * i + 1], v0[3 * i + 2] - bx[3 * i + 2]));
  return m;
}

TEST(Solve, DivergenceReturnsTheBestIterateAndAutoFallsBackToGmres) {
  const sorpia::LimitOperator op = indefinite_triangle();
  const std::vector<double> v0 = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  using M = sorpia::Method;
  for (M m : {M::Pia, M::Gs, M::Sor}) {
    sorpia::SolveOptions opt;
    opt.method = m;
    const sorpia::SolveResult r = sorpia::solve(op, v0.data(), opt);
    ASSERT_EQ(r.stop_reason, sorpia::StopReason::Diverged) << sorpia::method_name(m);
    const auto best = std::min_element(r.errors.begin(), r.errors.end()) - r.errors.begin();
    EXPECT_EQ(r.returned_iteration, best);
    // The first E_k above 10 times the lowest before it (sorpia::divergence_growth).
    EXPECT_GT(r.errors.back(), 10.0 * *std::min_element(r.errors.begin(), r.errors.end() - 1));
    EXPECT_NEAR(max_residual(op, v0, r.control_vertices) / r.initial_error, r.errors[best], 1e-12);
    ASSERT_TRUE(r.recommended.has_value());
    EXPECT_EQ(*r.recommended, M::Gmres);
    EXPECT_EQ(r.worst_vertices.size(), 3u);
  }
  sorpia::SolveOptions opt;
  opt.method = M::Auto;
  const sorpia::SolveResult r = sorpia::solve(op, v0.data(), opt);
  ASSERT_TRUE(r.converged());
  EXPECT_EQ(r.variant, "gmres");
  ASSERT_EQ(r.attempts.size(), 2u);
  EXPECT_EQ(r.attempts[0].method, M::Sor);
  EXPECT_EQ(r.attempts[1].method, M::Gmres);
  EXPECT_LT(max_residual(op, v0, r.control_vertices), 1e-10 * r.initial_error);
}

TEST(Solve, SingularBGetsTheLeastSquaresSolutionOfLeastNorm) {
  // B = [[1/2, 1/2], [1/2, 1/2]] = u u^T, u = (1, 1) / sqrt(2): rank 1, and
  // pinv(B) = B. Targets (1, 0, 0), (0, 0, 0) have a part outside B's range.
  sorpia::LimitOperator op;
  op.n = 2;
  op.offsets = {0, 1, 2};
  op.neighbors = {1, 0};
  op.diag = {0.5, 0.5};
  op.weight = {0.5, 0.5};
  const std::vector<double> v0 = {1, 0, 0, 0, 0, 0};
  sorpia::SolveOptions opt;
  opt.method = sorpia::Method::Auto;
  const sorpia::SolveResult r = sorpia::solve(op, v0.data(), opt);
  EXPECT_EQ(r.stop_reason, sorpia::StopReason::Singular);
  EXPECT_EQ(r.variant, "cgls");
  // pinv(B) V0 = B V0 = (1/2, 0, 0) on both rows; the residual (1/2, -1/2) in x.
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.control_vertices[3 * i], 0.5, 1e-12);
    EXPECT_NEAR(r.control_vertices[3 * i + 1], 0.0, 1e-12);
  }
  ASSERT_EQ(r.worst_residuals.size(), 2u);
  EXPECT_NEAR(r.worst_residuals[0], 0.5, 1e-12);
}

TEST(Solve, ParametersAreChecked) {
  const Case c = limit_case(sorpia::irregular(150, 3));
  sorpia::SolveOptions opt;
  opt.omega_rule = sorpia::OmegaRule::Given;
  opt.omega = 2.0;
  EXPECT_THROW(sorpia::solve(c.op, c.mesh.vertices.data(), opt), sorpia::ParameterError);
  opt.omega = 1.0;
  opt.tol = std::nan("");
  EXPECT_THROW(sorpia::solve(c.op, c.mesh.vertices.data(), opt), sorpia::ParameterError);
  opt.tol = 1e-10;
  opt.max_iter = 0;
  EXPECT_THROW(sorpia::solve(c.op, c.mesh.vertices.data(), opt), sorpia::ParameterError);
  EXPECT_THROW(sorpia::parse_method("jacobi"), sorpia::ParameterError);
}

TEST(Omega, YoungFormulaAndClamp) {
  bool clamped = true;
  EXPECT_DOUBLE_EQ(sorpia::young_omega(0.6, &clamped), 2.0 / (1.0 + 0.8));
  EXPECT_FALSE(clamped);
  const double at_clamp = 2.0 / (1.0 + std::sqrt(1.0 - sorpia::young_rho_clamp * sorpia::young_rho_clamp));
  EXPECT_DOUBLE_EQ(sorpia::young_omega(1.002, &clamped), at_clamp);
  EXPECT_TRUE(clamped);
  EXPECT_DOUBLE_EQ(sorpia::young_omega(std::nan(""), &clamped), at_clamp);
  EXPECT_TRUE(clamped);
}

}  // namespace

// Values appear in option messages as Python's repr() writes them, so that the
// same mistake reads the same from Python, the command line and C++.
TEST(SolveOptions, MessagesWriteValuesAsPythonRepr) {
  const auto message = [](const sorpia::SolveOptions& o) {
    try {
      sorpia::check_options(o);
    } catch (const sorpia::ParameterError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  sorpia::SolveOptions o;
  o.omega_rule = sorpia::OmegaRule::Given;
  o.omega = 2.0;
  EXPECT_EQ(message(o), "omega = 2.0 is outside (0, 2)");
  o.omega = 1.5;
  o.method = sorpia::Method::Pia;
  EXPECT_EQ(message(o), "omega = 1.5 applies to method='sor' or 'auto' only (method='pia')");
  o = {};
  o.tol = -1.5e-7;
  EXPECT_EQ(message(o), "tol = -1.5e-07 must be a positive finite number");
  o = {};
  o.method = sorpia::Method::Cg;
  o.threads = 2;
  EXPECT_EQ(message(o), "threads = 2 applies to method='sor', 'gs' or 'auto' only (method='cg')");
  o = {};
  o.method = sorpia::Method::Wpia;
  o.sigma = 0.001;
  EXPECT_EQ(message(o), "accepted");
  o.sigma = 1e16;
  EXPECT_EQ(message(o), "sigma = 1e+16 is outside (0, 2)");
  o = {};
  o.max_iter = sorpia::max_iterations + 1;
  EXPECT_EQ(message(o), "max_iter = 2147483648 is too large (at most 2**31 - 1)");
  EXPECT_THROW(sorpia::parse_omega("fast", o), sorpia::ParameterError);
}

// One cache shared by solves on several threads (an Interpolator used from a
// thread pool): the estimate is computed once, the others wait for it and
// report no estimating time of their own. Had every thread computed its own,
// several would report one.
TEST(SpectralCache, SharedByThreadsEstimatesOnce) {
  const auto c = limit_case(sorpia::irregular(4000, 5));
  sorpia::SpectralCache cache;
  sorpia::SolveOptions opt;
  opt.method = sorpia::Method::Wpia;
  opt.max_iter = 1;
  std::vector<sorpia::SolveResult> res(4);
  std::vector<std::thread> threads;
  for (auto& r : res)
    threads.emplace_back([&, p = &r] { *p = sorpia::solve(c.op, c.mesh.vertices.data(), opt, &cache); });
  for (auto& t : threads) t.join();
  int computed = 0;
  for (const auto& r : res) {
    EXPECT_EQ(r.lambda_min, res[0].lambda_min);
    computed += r.estimate_seconds > 0.0;
  }
  EXPECT_EQ(computed, 1);
  EXPECT_GT(cache.seconds, 0.0);
}
