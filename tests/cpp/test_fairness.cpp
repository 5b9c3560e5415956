// fairness_matrix (cpp/fit): options refused with their names; K symmetric
// with the constants in its null space; the regular quad torus's diagonal
// against the bicubic B-spline's closed form; K with shared element matrices
// equal to K integrated face by face.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
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

// `m` without the faces in `drop` (which share no vertex, so that every new
// boundary is a manifold loop): boundaries inside an irregular mesh.
sorpia::Mesh without_faces(const sorpia::Mesh& m, const std::vector<std::size_t>& drop) {
  sorpia::Mesh out = m;
  out.face_vertex_indices.clear();
  out.face_vertex_counts.clear();
  const std::vector<std::int32_t> counts = m.counts();
  std::size_t at = 0;
  for (std::size_t f = 0; f < m.n_faces(); ++f) {
    const auto k = static_cast<std::size_t>(counts[f]);
    if (std::find(drop.begin(), drop.end(), f) == drop.end()) {
      out.face_vertex_indices.insert(out.face_vertex_indices.end(),
                                     m.face_vertex_indices.begin() + static_cast<std::ptrdiff_t>(at),
                                     m.face_vertex_indices.begin() + static_cast<std::ptrdiff_t>(at + k));
      if (!m.uniform()) out.face_vertex_counts.push_back(counts[f]);
    }
    at += k;
  }
  return out;
}

// The largest difference of two matrices' entries over the largest entry.
double relative_difference(const CsrMatrix& a, const CsrMatrix& b) {
  double diff = 0.0, scale = 0.0;
  for (const CsrMatrix* x : {&a, &b})
    for (std::size_t i = 0; i < x->n_rows; ++i)
      for (auto p = static_cast<std::size_t>(x->indptr[i]); p < static_cast<std::size_t>(x->indptr[i + 1]); ++p) {
        const auto j = static_cast<std::size_t>(x->indices[p]);
        scale = std::max(scale, std::abs(x->data[p]));
        diff = std::max(diff, std::abs(entry(a, i, j) - entry(b, i, j)));
      }
  return diff / scale;
}

TEST(FairnessMatrix, SharedElementMatricesGiveTheFaceByFaceMatrix) {
  // Faces of one local topology share one element matrix (reuse = true); the
  // reference integrates every face on its own. Meshes with many
  // configurations: extraordinary vertices inside and on boundaries (dropped
  // faces), grids' boundary corners, n-gons (their neighbours integrated on
  // their own), once-refined meshes (mostly shared), creases, a corner and a
  // hole (faces touching them integrated on their own). The same integrals
  // summed in another order: 1e-12 of the largest entry. And the rows with
  // their columns left unsorted.
  struct Case {
    std::string name;
    sorpia::Mesh mesh;
    sorpia::Scheme scheme;
    sorpia::Tags tags;
  };
  // An infinitely sharp and a semi-sharp crease along two edges of face 5, a
  // corner at a vertex of face 60, face 30 a hole.
  auto tagged = [](const sorpia::Mesh& m) {
    const std::vector<std::int32_t> counts = m.counts();
    auto first = [&](std::size_t f) {
      return m.face_vertex_indices.data() + std::accumulate(counts.begin(), counts.begin() + f, std::size_t{0});
    };
    const std::int32_t* f5 = first(5);
    sorpia::Tags t;
    t.crease_vertices = {f5[0], f5[1], f5[1], f5[2]};
    t.crease_sharpness = {sorpia::kInfiniteSharpness, 1.5};
    t.corner_vertices = {*first(60)};
    t.corner_sharpness = {2.0};
    t.holes = {30};
    return t;
  };
  const auto loop = sorpia::Scheme::Loop;
  const auto cc = sorpia::Scheme::CatmullClark;
  std::vector<Case> cases = {
      {"loop irregular, boundaries", without_faces(sorpia::irregular(150, 3), {0, 50, 100}), loop, {}},
      {"loop grid", sorpia::grid(5, 4), loop, {}},
      {"loop irregular, tags", sorpia::irregular(150, 3), loop, tagged(sorpia::irregular(150, 3))},
      {"cc irregular, boundaries", without_faces(sorpia::quad_irregular(150, 3), {0, 50, 100}), cc, {}},
      {"cc grid", sorpia::quad_grid(5, 4), cc, {}},
      {"cc polygons, boundary", without_faces(sorpia::polygon_torus(7, 6), {0, 20}), cc, {}},
      {"cc irregular, tags", sorpia::quad_irregular(150, 3), cc, tagged(sorpia::quad_irregular(150, 3))},
  };
  for (std::size_t c = 0; c < 2; ++c) {  // once refined: a few configurations, many faces each
    const sorpia::Topology topo(cases[3 * c].mesh);
    sorpia::LimitSurface s(topo, cases[3 * c].mesh.vertices.data(), cases[3 * c].scheme,
                           sorpia::Boundary::EdgeAndCorner);
    cases.push_back({cases[3 * c].name + ", refined once", s.tessellate(1), cases[3 * c].scheme, {}});
  }
  for (const Case& c : cases) {
    const sorpia::Topology topo(c.mesh);
    const sorpia::LimitSurface s(topo, c.mesh.vertices.data(), c.scheme, sorpia::Boundary::EdgeAndCorner, c.tags);
    sorpia::FairnessQuadrature alone;
    alone.reuse = false;
    const CsrMatrix shared = sorpia::fairness_matrix(s, 1.0, 0.5);
    const CsrMatrix reference = sorpia::fairness_matrix(s, 1.0, 0.5, alone);
    EXPECT_LE(relative_difference(shared, reference), 1e-12) << c.name;
    // Unsorted rows (what fair_solve takes): the same entries exactly, each
    // row's columns distinct, the same rows' lengths.
    const CsrMatrix unsorted = sorpia::fairness_matrix(s, 1.0, 0.5, {}, nullptr, /*sorted_columns=*/false);
    EXPECT_EQ(unsorted.indptr, shared.indptr) << c.name;
    EXPECT_EQ(relative_difference(unsorted, shared), 0.0) << c.name;
    for (std::size_t i = 0; i < unsorted.n_rows; ++i) {
      std::vector<std::int32_t> cols(unsorted.indices.begin() + unsorted.indptr[i],
                                     unsorted.indices.begin() + unsorted.indptr[i + 1]);
      std::sort(cols.begin(), cols.end());
      EXPECT_EQ(std::adjacent_find(cols.begin(), cols.end()), cols.end()) << c.name << " row " << i;
    }
  }
}

}  // namespace
