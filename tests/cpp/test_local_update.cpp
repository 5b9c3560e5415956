// Local re-solves (sorpia::LocalSolver) and warm starts: the guarantee of a
// full solve (E / E_0 < tol over the whole mesh, E_0 of the new targets),
// checked with the residual from OpenSubdiv's CSR matrix (limit_case.hpp),
// on uniform operators and on operators with per-entry weights.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "limit_case.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/local_update.hpp"
#include "sorpia/solvers.hpp"

namespace {

using sorpia_test::LimitCase;

// max_i ||t_i - (B v)_i|| over (n, k) rows, from the CSR matrix b: E of
// control vertices v for targets t (E_0 for v = t).
double error_of(const sorpia::CsrMatrix& b, const std::vector<double>& t, const std::vector<double>& v,
                std::size_t k = 3) {
  double e = 0.0;
  for (std::size_t i = 0; i < b.n_rows; ++i) {
    double s = 0.0;
    for (std::size_t c = 0; c < k; ++c) {
      double bv = 0.0;
      for (std::int32_t p = b.indptr[i]; p < b.indptr[i + 1]; ++p) bv += b.data[p] * v[k * b.indices[p] + c];
      s += (t[k * i + c] - bv) * (t[k * i + c] - bv);
    }
    e = std::max(e, std::sqrt(s));
  }
  return e;
}

// Options of `method` to 1e-10, max_iter 5000.
sorpia::SolveOptions options(sorpia::Method method) {
  sorpia::SolveOptions opt;
  opt.method = method;
  opt.tol = 1e-10;
  opt.max_iter = 5000;
  return opt;
}

std::vector<LimitCase> cases() {
  std::vector<LimitCase> out;
  out.push_back(sorpia_test::limit_case(sorpia::irregular(3000, 3), "irregular"));
  out.push_back(sorpia_test::limit_case(sorpia::grid(50, 40), "grid"));
  for (const char* name : {"irregular weighted", "grid weighted"}) {
    LimitCase c = sorpia_test::limit_case(name[0] == 'i' ? sorpia::irregular(3000, 3) : sorpia::grid(50, 40), name);
    c.b = sorpia_test::perturbed(std::move(c.b), 0.2, 7);
    c.op = sorpia::limit_operator(c.b);
    out.push_back(std::move(c));
  }
  return out;
}

sorpia::SolveResult full_solve(const LimitCase& c, const std::vector<double>& v0, double tol,
                               const double* initial = nullptr) {
  sorpia::SolveOptions opt;
  opt.tol = tol;
  opt.max_iter = 10000;
  return sorpia::solve(c.op, v0.data(), 3, initial, opt);
}

double diagonal(const std::vector<double>& v) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t k = 0; k < v.size(); ++k) lo[k % 3] = std::min(lo[k % 3], v[k]), hi[k % 3] = std::max(hi[k % 3], v[k]);
  return std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
}

TEST(LocalUpdate, MeetsTheFullSolveGuaranteeAndComposes) {
  for (const LimitCase& c : cases()) {
    SCOPED_TRACE(c.name);
    ASSERT_EQ(c.op.uniform(), std::string(c.name).find("weighted") == std::string::npos);
    const double tol = 1e-10;
    std::vector<double> targets = c.mesh.vertices;
    sorpia::SolveResult solved = full_solve(c, targets, tol);
    ASSERT_TRUE(solved.converged());
    sorpia::LocalSolver local(c.op);
    local.set_targets(targets, 3);
    std::vector<double> v = solved.control_vertices;
    const double step = 0.01 * diagonal(targets);
    // One target, then a second elsewhere starting from the first's result
    // (kept residual), then a patch of them: each meets the guarantee for the
    // targets moved so far.
    const std::size_t n = c.op.n;
    const std::vector<std::vector<std::int32_t>> moves = {
        {static_cast<std::int32_t>(n / 2)},
        {static_cast<std::int32_t>(n / 5)},
        {3, 4, 5, 6, 7, 8, 9, 10, 11, 12, static_cast<std::int32_t>(n - 1)}};
    bool last = false;
    for (const auto& idx : moves) {
      std::vector<double> pos;
      for (std::int32_t i : idx) {
        for (int a = 0; a < 3; ++a) targets[3 * i + a] += step * (a == 2 ? 1.0 : 0.5);
        pos.insert(pos.end(), targets.begin() + 3 * i, targets.begin() + 3 * i + 3);
      }
      sorpia::SolveResult r;
      local.update(v.data(), last, idx.data(), idx.size(), pos.data(), tol, 1000LL * n, r);
      last = true;
      ASSERT_TRUE(r.converged()) << sorpia::stop_reason_name(r.stop_reason);
      EXPECT_EQ(local.targets(), targets);
      const double e0 = error_of(c.b, targets, targets);
      EXPECT_NEAR(r.initial_error, e0, 1e-12 * e0);
      // E / E_0 < tol from scratch: the kept residuals are recomputed from
      // rows, so the independent product agrees to rounding.
      EXPECT_LT(error_of(c.b, targets, v), tol * e0 * (1 + 1e-6));
      ASSERT_EQ(r.errors.size(), 2u);
      EXPECT_GT(r.errors[0], tol);
      EXPECT_LT(r.errors[1], tol);
      EXPECT_GT(r.relaxations, 0);
      // The same solution as a full solve of the new targets, to the
      // tolerance: both have residuals below tol E_0 and B^-1 is bounded by
      // 1 / 0.2 in the max norm of the rows (generously: 100).
      const sorpia::SolveResult ref = full_solve(c, targets, 1e-13);
      EXPECT_LT(sorpia_test::max_abs_diff(ref.control_vertices, v), 100 * tol * e0);
    }
  }
}

// A mesh solved to 1e-10, with a LocalSolver holding its vertices as targets.
struct Solved {
  explicit Solved(const sorpia::Mesh& m)
      : c(sorpia_test::limit_case(m, "irregular")),
        targets(c.mesh.vertices),
        solved(full_solve(c, targets, 1e-10)),
        local(c.op),
        v(solved.control_vertices) {
    local.set_targets(targets, 3);
  }
  const LimitCase c;
  std::vector<double> targets;
  const sorpia::SolveResult solved;
  sorpia::LocalSolver local;
  std::vector<double> v;
};

TEST(LocalUpdate, OneTargetStaysLocal) {
  Solved s(sorpia::irregular(20000, 5));
  const LimitCase& c = s.c;
  std::vector<double>& targets = s.targets;
  std::vector<double>& v = s.v;
  const std::int32_t i = 777;
  targets[3 * i] += 0.01 * diagonal(targets);
  sorpia::SolveResult r;
  s.local.update(v.data(), false, &i, 1, &targets[3 * i], 1e-10, 1000LL * c.op.n, r);
  ASSERT_TRUE(r.converged());
  EXPECT_LT(error_of(c.b, targets, v), 1e-10 * error_of(c.b, targets, targets) * (1 + 1e-6));
  // A neighbourhood, not the mesh: far fewer relaxations than one sweep.
  EXPECT_LT(r.relaxations, static_cast<long long>(c.op.n) / 4);
}

TEST(LocalUpdate, InterruptedUpdateIsTakenBack) {
  Solved s(sorpia::irregular(20000, 5));
  const std::vector<double> before = s.targets;
  // A patch of targets moved: far more relaxations than the 4096 between polls.
  std::vector<std::int32_t> idx;
  std::vector<double> pos;
  for (std::int32_t i = 100; i < 300; ++i) {
    idx.push_back(i);
    for (int a = 0; a < 3; ++a) pos.push_back(s.targets[3 * i + a] += (a == 2 ? 0.05 : 0.0));
  }
  std::vector<double> start = s.v;
  sorpia::SolveResult r;
  {
    const sorpia::InterruptScope scope([] { return true; });
    std::this_thread::sleep_for(sorpia::kInterruptPollInterval * 3 / 2);
    EXPECT_THROW(s.local.update(start.data(), false, idx.data(), idx.size(), pos.data(), 1e-10, 1LL << 40, r),
                 sorpia::Interrupted);
  }
  // Nothing changed: the targets and the start's vertices are as before the call.
  EXPECT_EQ(s.local.targets(), before);
  EXPECT_EQ(start, s.v);
  // The same update again, uninterrupted, is that of a fresh solver, bit for bit.
  std::vector<double> fresh_v = s.v;
  sorpia::LocalSolver fresh(s.c.op);
  fresh.set_targets(before, 3);
  sorpia::SolveResult ref;
  fresh.update(fresh_v.data(), false, idx.data(), idx.size(), pos.data(), 1e-10, 1LL << 40, ref);
  s.local.update(s.v.data(), true, idx.data(), idx.size(), pos.data(), 1e-10, 1LL << 40, r);
  ASSERT_TRUE(r.converged());
  EXPECT_EQ(r.relaxations, ref.relaxations);
  EXPECT_EQ(s.v, fresh_v);
  EXPECT_LT(error_of(s.c.b, s.targets, s.v), 1e-10 * error_of(s.c.b, s.targets, s.targets) * (1 + 1e-6));
}

TEST(LocalUpdate, NothingToDoAndBadIndex) {
  Solved s(sorpia::irregular(500, 2));
  std::vector<double>& targets = s.targets;
  std::vector<double>& v = s.v;
  // The same position again: the start already meets tol, nothing relaxed.
  const std::int32_t i = 10;
  sorpia::SolveResult r;
  s.local.update(v.data(), false, &i, 1, &targets[3 * i], 1e-10, 1000, r);
  EXPECT_TRUE(r.converged());
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(r.relaxations, 0);
  EXPECT_EQ(v, s.solved.control_vertices);
  const std::int32_t bad = static_cast<std::int32_t>(s.c.op.n);
  EXPECT_THROW(s.local.update(v.data(), true, &bad, 1, targets.data(), 1e-10, 1000, r), sorpia::ParameterError);
}

TEST(WarmStart, SameGuaranteeEveryMethod) {
  for (const LimitCase& c : cases()) {
    SCOPED_TRACE(c.name);
    std::vector<double> v0 = c.mesh.vertices;
    const sorpia::SolveResult first = full_solve(c, v0, 1e-12);
    // The next frame: every target moved a little.
    for (std::size_t k = 0; k < v0.size(); ++k) v0[k] += 1e-3 * std::sin(static_cast<double>(k));
    const double e0 = error_of(c.b, v0, v0);
    for (sorpia::Method m : sorpia::all_methods) {
      SCOPED_TRACE(sorpia::method_name(m));
      const sorpia::SolveOptions opt = options(m);
      const sorpia::SolveResult warm = sorpia::solve(c.op, v0.data(), 3, first.control_vertices.data(), opt);
      ASSERT_TRUE(warm.converged());
      EXPECT_NEAR(warm.initial_error, e0, 1e-12 * e0);  // E_0 of the cold start
      EXPECT_LT(warm.errors[0], 1.0);
      EXPECT_NEAR(warm.errors[0], error_of(c.b, v0, first.control_vertices) / e0, 1e-9);
      EXPECT_LT(error_of(c.b, v0, warm.control_vertices), 1e-10 * e0 * (1 + 1e-6));
    }
    // A start that already meets tol: no iteration, the start returned.
    sorpia::SolveOptions opt;
    opt.tol = 1e-6;
    const sorpia::SolveResult exact = full_solve(c, v0, 1e-12);
    const sorpia::SolveResult again = sorpia::solve(c.op, v0.data(), 3, exact.control_vertices.data(), opt);
    EXPECT_EQ(again.iterations, 0);
    EXPECT_EQ(again.control_vertices, exact.control_vertices);
  }
}


TEST(Columns, AnyKEveryMethodAndLocalUpdate) {
  for (const LimitCase& c : cases()) {
    SCOPED_TRACE(c.name);
    for (std::size_t k : {1u, 2u, 5u}) {
      SCOPED_TRACE(k);
      std::vector<double> v0(k * c.op.n);
      for (std::size_t q = 0; q < v0.size(); ++q) v0[q] = std::sin(0.37 * static_cast<double>(q));
      const double e0 = error_of(c.b, v0, v0, k);
      for (sorpia::Method m : sorpia::all_methods) {
        SCOPED_TRACE(sorpia::method_name(m));
        const sorpia::SolveResult r = sorpia::solve(c.op, v0.data(), k, nullptr, options(m));
        ASSERT_TRUE(r.converged());
        EXPECT_EQ(r.columns, k);
        EXPECT_NEAR(r.initial_error, e0, 1e-12 * e0);
        EXPECT_LT(error_of(c.b, v0, r.control_vertices, k), 1e-10 * e0 * (1 + 1e-6));
      }
      // One update of k-column targets.
      sorpia::SolveOptions opt;
      std::vector<double> v = sorpia::solve(c.op, v0.data(), k, nullptr, opt).control_vertices;
      sorpia::LocalSolver local(c.op);
      local.set_targets(v0, k);
      const std::int32_t i = static_cast<std::int32_t>(c.op.n / 3);
      for (std::size_t a = 0; a < k; ++a) v0[k * i + a] += 0.5;
      sorpia::SolveResult r;
      local.update(v.data(), false, &i, 1, &v0[k * i], 1e-10, 1000LL * c.op.n, r);
      ASSERT_TRUE(r.converged());
      EXPECT_LT(error_of(c.b, v0, v, k), 1e-10 * error_of(c.b, v0, v0, k) * (1 + 1e-6));
    }
  }
}

}  // namespace
