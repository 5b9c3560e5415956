// fairness_matrix (cpp/fit): options refused with their names; K symmetric
// with the constants in its null space; the regular quad torus's diagonal
// against the bicubic B-spline's closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "expect_error.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/fairness.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/surface.hpp"

namespace {

using sorpia::CsrMatrix;

sorpia::LimitSurface quad_surface(const sorpia::Mesh& m) {
  const sorpia::Topology topo(m);
  return sorpia::LimitSurface(topo, m.vertices.data(), sorpia::Scheme::CatmullClark, sorpia::Boundary::EdgeAndCorner);
}

double entry(const CsrMatrix& k, std::size_t i, std::size_t j) {
  for (auto p = static_cast<std::size_t>(k.indptr[i]); p < static_cast<std::size_t>(k.indptr[i + 1]); ++p)
    if (static_cast<std::size_t>(k.indices[p]) == j) return k.data[p];
  return 0.0;
}

TEST(FairnessMatrix, RefusesOptionsByName) {
  const auto s = quad_surface(sorpia::quad_torus(6, 5));
  using sorpia::ParameterError;
  using sorpia_test::expect_error;
  expect_error<ParameterError>([&] { sorpia::fairness_matrix(s, -1.0, 0.0); }, {"thin_plate", ">= 0"});
  expect_error<ParameterError>([&] { sorpia::fairness_matrix(s, 1.0, NAN); }, {"membrane", "finite"});
  expect_error<ParameterError>([&] { sorpia::fairness_matrix(s, 0.0, 0.0); }, {"both 0"});
  expect_error<ParameterError>([&] { sorpia::fairness_matrix(s, 1.0, 0.0, {0, 4}); }, {"gauss_points", "1..16"});
  expect_error<ParameterError>([&] { sorpia::fairness_matrix(s, 1.0, 0.0, {4, 13}); }, {"depth", "0..12"});
}

TEST(FairnessMatrix, SymmetricWithConstantsInTheNullSpace) {
  // An irregular quad mesh and a polygon mesh: every derivative row sums to 0
  // (the stencils' weights sum to 1), and K is assembled as symmetric pairs.
  for (const auto& m : {sorpia::quad_irregular(300, 2), sorpia::polygon_torus(6, 5)}) {
    const auto s = quad_surface(m);
    const CsrMatrix k = sorpia::fairness_matrix(s, 1.0, 0.5);
    ASSERT_EQ(k.n_rows, m.n_vertices());
    double scale = 0.0;
    for (double x : k.data) scale = std::max(scale, std::abs(x));
    for (std::size_t i = 0; i < k.n_rows; ++i) {
      double sum = 0.0;
      for (auto p = static_cast<std::size_t>(k.indptr[i]); p < static_cast<std::size_t>(k.indptr[i + 1]); ++p) {
        sum += k.data[p];
        EXPECT_EQ(k.data[p], entry(k, static_cast<std::size_t>(k.indices[p]), i));
        if (p > static_cast<std::size_t>(k.indptr[i])) EXPECT_LT(k.indices[p - 1], k.indices[p]);
      }
      EXPECT_NEAR(sum, 0.0, 1e-12 * scale) << "row " << i;
    }
  }
}

TEST(FairnessMatrix, RegularTorusDiagonalIsTheBicubicClosedForm) {
  // Every vertex of the quad torus lies in 16 bicubic patches, once at each
  // of the 4 x 4 patch points: K_ii = sum over a, b of G2[a][a] G0[b][b] + 2
  // G1[a][a] G1[b][b] + G0[a][a] G2[b][b], G_k[a][a] the integral over [0, 1]
  // of the k-th derivative of the cubic B-spline piece a, squared.
  auto diag = [](int k, int a) {
    // The pieces (1 - t)^3/6, (3t^3 - 6t^2 + 4)/6, (-3t^3 + 3t^2 + 3t + 1)/6, t^3/6 as power coefficients.
    const double c[4][4] = {{1, -3, 3, -1}, {4, 0, -6, 3}, {1, 3, 3, -3}, {0, 0, 0, 1}};
    double p[4] = {c[a][0] / 6, c[a][1] / 6, c[a][2] / 6, c[a][3] / 6};
    for (int d = 0; d < k; ++d) {
      for (int i = 0; i < 3; ++i) p[i] = (i + 1) * p[i + 1];
      p[3] = 0.0;
    }
    double sum = 0.0;  // integral of p^2 over [0, 1]
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) sum += p[i] * p[j] / (i + j + 1);
    return sum;
  };
  double expected = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      expected += diag(2, a) * diag(0, b) + 2.0 * diag(1, a) * diag(1, b) + diag(0, a) * diag(2, b);
  const auto s = quad_surface(sorpia::quad_torus(8, 7));
  const CsrMatrix k = sorpia::fairness_matrix(s, 1.0, 0.0);
  for (std::size_t i = 0; i < k.n_rows; ++i) EXPECT_NEAR(entry(k, i, i), expected, 1e-12 * expected) << "vertex " << i;
}

}  // namespace
