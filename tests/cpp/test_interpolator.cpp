// sorpia::Interpolator: its solve is sorpia::solve on B from OpenSubdiv's
// reference build (bit for bit with the same operator), its update meets the
// guarantee of a full solve against OpenSubdiv's CSR matrix, and what it
// refuses or cannot do changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "limit_case.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interpolator.hpp"

namespace {

// max_i ||t_i - (B v)_i|| with B from OpenSubdiv's Far Limit() (CSR).
double error_of(const sorpia::CsrMatrix& b, const std::vector<double>& t, const std::vector<double>& v) {
  double e = 0.0;
  for (std::size_t i = 0; i < b.n_rows; ++i) {
    double s = 0.0;
    for (int c = 0; c < 3; ++c) {
      double bv = 0.0;
      for (std::int32_t p = b.indptr[i]; p < b.indptr[i + 1]; ++p) bv += b.data[p] * v[3 * b.indices[p] + c];
      s += (t[3 * i + c] - bv) * (t[3 * i + c] - bv);
    }
    e = std::max(e, std::sqrt(s));
  }
  return e;
}

sorpia::Interpolator make(const sorpia::Mesh& m) {
  return sorpia::Interpolator(m, m.n_vertices(), sorpia::Rules{});
}

TEST(Interpolator, SolveIsTheCoreSolveOnItsOperator) {
  const auto c = sorpia_test::limit_case(sorpia::irregular(2000, 5));
  sorpia::Interpolator interp = make(c.mesh);
  for (sorpia::Method method : {sorpia::Method::Sor, sorpia::Method::Cg, sorpia::Method::Wpia}) {
    sorpia::SolveOptions opt;
    opt.method = method;
    const sorpia::SolveResult a = interp.solve(c.mesh.vertices.data(), 3, nullptr, opt);
    const sorpia::SolveResult b = sorpia::solve(c.op, c.mesh.vertices.data(), opt);
    EXPECT_EQ(a.control_vertices, b.control_vertices) << sorpia::method_name(method);
    EXPECT_EQ(a.errors, b.errors) << sorpia::method_name(method);
    // Against OpenSubdiv's B: the guarantee of the stopping rule.
    if (a.converged())
      EXPECT_LT(error_of(c.b, c.mesh.vertices, a.control_vertices),
              1e-10 * error_of(c.b, c.mesh.vertices, c.mesh.vertices) * 1.0001);
  }
}

TEST(Interpolator, UpdateMeetsTheGuaranteeAndFailuresChangeNothing) {
  const auto c = sorpia_test::limit_case(sorpia::irregular(2000, 5));
  sorpia::Interpolator interp = make(c.mesh);
  sorpia::SolveResult r = interp.solve(c.mesh.vertices.data(), 3, nullptr, sorpia::SolveOptions{});
  std::vector<double> targets = c.mesh.vertices;
  const std::int32_t i = 17;
  const double moved[3] = {targets[3 * i] + 0.2, targets[3 * i + 1], targets[3 * i + 2] - 0.1};
  ASSERT_TRUE(interp.update(r, false, &i, 1, moved, 1e-10, 1000));
  for (int c3 = 0; c3 < 3; ++c3) targets[3 * i + c3] = moved[c3];
  EXPECT_LT(error_of(c.b, targets, r.control_vertices), 1e-10 * error_of(c.b, targets, targets));

  // max_iter reached: rolled back, the vertices and targets as before.
  const std::vector<double> before = r.control_vertices;
  const std::int32_t j = 40;
  const double far[3] = {5.0, 5.0, 5.0};
  EXPECT_FALSE(interp.update(r, true, &j, 1, far, 1e-300, 1));
  EXPECT_EQ(r.stop_reason, sorpia::StopReason::MaxIter);
  EXPECT_EQ(r.control_vertices, before);
  std::size_t k = 0;
  EXPECT_EQ(interp.targets(k), targets);

  // Refused before any change: not finite, beyond max_coordinate, not a vertex.
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), 1e151}) {
    const double p[3] = {0.0, bad, 0.0};
    EXPECT_THROW(interp.update(r, true, &j, 1, p, 1e-10, 1000), sorpia::ParameterError);
  }
  const std::int32_t outside = static_cast<std::int32_t>(c.mesh.n_vertices());
  EXPECT_THROW(interp.update(r, true, &outside, 1, moved, 1e-10, 1000), sorpia::ParameterError);
  EXPECT_EQ(interp.targets(k), targets);
  EXPECT_EQ(r.control_vertices, before);
}

TEST(Interpolator, WarmStartsBeyondTheTargetsScaleAreRefused) {
  const auto c = sorpia_test::limit_case(sorpia::irregular(500, 2));
  sorpia::Interpolator interp = make(c.mesh);
  std::vector<double> initial = c.mesh.vertices;
  initial[7] = 1e200;
  EXPECT_THROW(interp.solve(c.mesh.vertices.data(), 3, initial.data(), sorpia::SolveOptions{}),
               sorpia::ParameterError);
  // Targets of 2^700 are scaled exactly by the solvers: a start of their size is accepted.
  std::vector<double> huge = c.mesh.vertices;
  for (double& x : huge) x = std::ldexp(x, 700);
  const sorpia::SolveResult r = interp.solve(huge.data(), 3, huge.data(), sorpia::SolveOptions{});
  EXPECT_TRUE(r.converged());
}

}  // namespace
