// Catmull-Clark's B (sorpia::limit_operator with Scheme::CatmullClark) against
// OpenSubdiv's Far (Limit() on the unrefined refiner for quad meshes; one
// uniform refinement, Interpolate and Limit() composed for meshes with other
// polygons) and against the closed-form masks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "catmark_rows.hpp"
#include "darts.hpp"
#include "expect_error.hpp"
#include "poly_meshes.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/reference.hpp"
#include "sorpia/limit_masks.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace {

using sorpia::Boundary;
using sorpia::Scheme;

// Row i of a CSR matrix as column -> weight.
std::map<int, double> row(const sorpia::CsrMatrix& b, std::size_t i) {
  std::map<int, double> r;
  for (std::int32_t p = b.indptr[i]; p < b.indptr[i + 1]; ++p) r[b.indices[p]] = b.data[p];
  return r;
}

// A disk of n quads round vertex 0 (valence n, interior): edge neighbours
// 1..n, opposite corners n+1..2n.
sorpia::Mesh quad_pole(int n) {
  sorpia::Mesh m;
  m.vertices.assign(3 * (2 * n + 1), 0.0);
  for (int j = 0; j < n; ++j) {
    m.face_vertex_counts.push_back(4);
    m.face_vertex_indices.insert(m.face_vertex_indices.end(), {0, 1 + j, n + 1 + j, 1 + (j + 1) % n});
  }
  return m;
}

TEST(Catmark, EveryRowEqualsOpenSubdivFar) {
  for (const auto& [name, m] : sorpia_test::polygon_meshes())
    for (auto rule : {Boundary::EdgeOnly, Boundary::EdgeAndCorner}) {
      SCOPED_TRACE(name + (rule == Boundary::EdgeOnly ? " edge-only" : " edge-and-corner"));
      const auto t = sorpia::Topology(m);
      const auto fast = sorpia::limit_matrix(t, sorpia::Rules{Scheme::CatmullClark, rule});
      const auto ref = sorpia::reference_limit_matrix(t, sorpia::Rules{Scheme::CatmullClark, rule});
      ASSERT_EQ(fast.n_rows, m.n_vertices());
      for (std::size_t i = 0; i < fast.n_rows; ++i) {
        const auto a = row(fast, i), b = row(ref, i);
        ASSERT_EQ(a.size(), b.size()) << "row " << i;
        for (const auto& [j, w] : b) {
          ASSERT_EQ(a.count(j), 1u) << "row " << i << " lacks column " << j;
          ASSERT_NEAR(a.at(j), w, 1e-15) << "row " << i << " column " << j;
        }
      }
    }
}

// The composed rows are what Limit() gives after refining: one more check of
// that reference on a quad mesh, where it must equal Limit() on level 0.
TEST(Catmark, RefinedRowsOfQuadVerticesEqualTheirMasks) {
  const auto m = sorpia::quad_irregular(600, 3);
  const auto t = sorpia::Topology(m);
  const auto op = sorpia::limit_operator(t, sorpia::Rules{Scheme::CatmullClark, Boundary::EdgeAndCorner});
  std::vector<std::pair<std::int32_t, double>> refined;
  for (std::size_t v = 0; v < t.n_vertices(); ++v) {
    if (t.is_boundary(v) || t.is_unreferenced(v)) continue;
    sorpia::detail::catmark_refined_row(t, v, refined);
    std::map<int, double> a;
    for (const auto& [j, w] : refined) a[j] = w;
    ASSERT_NEAR(a[static_cast<int>(v)], op.diag[v], 1e-15) << "vertex " << v;
    for (std::int32_t p = op.offsets[v]; p < op.offsets[v + 1]; ++p)
      ASSERT_NEAR(a[op.neighbors[p]], op.values[p], 1e-15) << "vertex " << v;
    ASSERT_EQ(a.size(), static_cast<std::size_t>(op.offsets[v + 1] - op.offsets[v] + 1)) << "vertex " << v;
  }
}

// Interior vertex of valence n in a quad ring: (n^2 v + 4 sum e_j + sum f_j) / (n (n + 5)).
TEST(Catmark, InteriorMaskIsTheClosedForm) {
  for (int n = 3; n <= 12; ++n) {
    SCOPED_TRACE("valence " + std::to_string(n));
    const auto t = sorpia::Topology(quad_pole(n));
    const auto b = sorpia::limit_matrix(t, sorpia::Rules{Scheme::CatmullClark, Boundary::EdgeAndCorner});
    const auto r = row(b, 0);
    const double denom = n * (n + 5.0);
    ASSERT_EQ(r.size(), static_cast<std::size_t>(2 * n + 1));
    EXPECT_NEAR(r.at(0), n * n / denom, 1e-15);
    for (int j = 1; j <= n; ++j) EXPECT_NEAR(r.at(j), 4 / denom, 1e-15);
    for (int j = n + 1; j <= 2 * n; ++j) EXPECT_NEAR(r.at(j), 1 / denom, 1e-15);
  }
  // the figures measured with OpenSubdiv 3.5 (issue 13)
  const auto m3 = sorpia::catmark_smooth_limit_mask(3), m5 = sorpia::catmark_smooth_limit_mask(5);
  EXPECT_NEAR(m3.diag, 0.375, 1e-15);
  EXPECT_NEAR(m3.edge, 1.0 / 6, 1e-15);
  EXPECT_NEAR(m3.face, 1.0 / 24, 1e-15);
  EXPECT_NEAR(m5.diag, 0.5, 1e-15);
  EXPECT_NEAR(m5.edge, 0.08, 1e-15);
  EXPECT_NEAR(m5.face, 0.02, 1e-15);
}

// Boundary (v_prev + 4 v + v_next) / 6; a one-face corner keeps itself under
// edge-and-corner and takes the boundary rule under edge-only.
TEST(Catmark, BoundaryAndCornerRules) {
  const auto m = sorpia::quad_grid(5, 4);
  const auto t = sorpia::Topology(m);
  for (auto rule : {Boundary::EdgeOnly, Boundary::EdgeAndCorner}) {
    const auto b = sorpia::limit_matrix(t, sorpia::Rules{Scheme::CatmullClark, rule});
    for (std::size_t v = 0; v < t.n_vertices(); ++v) {
      if (!t.is_boundary(v)) continue;
      const auto r = row(b, v);
      const int lo = t.ring_offsets()[v], hi = t.ring_offsets()[v + 1];
      if (t.face_count(v) == 1 && rule == Boundary::EdgeAndCorner) {
        ASSERT_EQ(r.size(), 1u);
        EXPECT_EQ(r.at(static_cast<int>(v)), 1.0);
        continue;
      }
      ASSERT_EQ(r.size(), 3u) << "vertex " << v;
      EXPECT_NEAR(r.at(static_cast<int>(v)), 2.0 / 3, 1e-15);
      EXPECT_NEAR(r.at(t.ring_neighbors()[lo]), 1.0 / 6, 1e-15);
      EXPECT_NEAR(r.at(t.ring_neighbors()[hi - 1]), 1.0 / 6, 1e-15);
    }
  }
}

TEST(Catmark, RowsSumToOne) {
  for (const auto& [name, m] : sorpia_test::polygon_meshes()) {
    SCOPED_TRACE(name);
    const auto op = sorpia::limit_operator(sorpia::Topology(m), sorpia::Rules{Scheme::CatmullClark, Boundary::EdgeAndCorner});
    for (std::size_t i = 0; i < op.n; ++i) {
      double s = op.diag[i];
      for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) s += op.entry(i, p);
      ASSERT_NEAR(s, 1.0, 1e-14) << "row " << i;
      ASSERT_GT(op.diag[i], 0.0) << "row " << i;
    }
  }
}

// With sharpness tags the rows of the tagged vertices come from OpenSubdiv's
// refinement, refined at least once next to non-quad faces: the whole
// operator against one refinement of the whole mesh, except the darts' rows
// (the limit of their refinement, which no finite level gives: test_darts.cpp).
TEST(Catmark, TaggedRowsEqualTheWholeMeshRefinement) {
  for (const char* name : {"quad-irregular", "polygon-torus", "quad-grid"}) {
    SCOPED_TRACE(name);
    sorpia::Mesh m;
    for (const auto& [n, mesh] : sorpia_test::polygon_meshes())
      if (n == name) m = mesh;
    const auto t = sorpia::Topology(m);
    sorpia::Tags tags;
    // a chain of edges from vertex 0, alternately infinitely sharp and semi-sharp, and two corners
    std::int32_t v = 0;
    for (int k = 0; k < 6; ++k) {
      const std::int32_t w = t.ring_neighbors()[t.ring_offsets()[v] + 1];
      tags.crease_vertices.insert(tags.crease_vertices.end(), {v, w});
      tags.crease_sharpness.push_back(k % 2 ? 1.5 : sorpia::kInfiniteSharpness);
      v = w;
    }
    tags.corner_vertices = {v, static_cast<std::int32_t>(t.n_vertices() / 2)};
    tags.corner_sharpness = {2.0, sorpia::kInfiniteSharpness};
    for (auto rule : {Boundary::EdgeOnly, Boundary::EdgeAndCorner}) {
      const auto fast = sorpia::limit_matrix(t, sorpia::Rules{Scheme::CatmullClark, rule, tags});
      const auto ref = sorpia::reference_limit_matrix(t, sorpia::Rules{Scheme::CatmullClark, rule, tags});
      const auto darts = sorpia_test::darts(t, tags);
      for (std::size_t i = 0; i < fast.n_rows; ++i) {
        if (darts[i]) continue;
        const auto a = row(fast, i), b = row(ref, i);
        ASSERT_EQ(a.size(), b.size()) << "row " << i;
        for (const auto& [j, w] : b) ASSERT_NEAR(a.at(j), w, 1e-14) << "row " << i << " column " << j;
      }
    }
  }
}

TEST(Catmark, LoopRefusesPolygonsNamingTheFace) {
  const auto t = sorpia::Topology(sorpia::polygon_torus(8, 6, 2));
  std::size_t f = 0;
  while (t.face_size(f) == 3) ++f;
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::limit_operator(t, Boundary::EdgeAndCorner); },
                                               {"face " + std::to_string(f) + " has", "Loop subdivision needs "
                                                                                       "triangles", "Catmull-Clark"});
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] { sorpia::reference_limit_matrix(t, Boundary::EdgeAndCorner); }, {"Loop subdivision needs triangles"});
}

}  // namespace
