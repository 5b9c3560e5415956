// The limit matrix from OpenSubdiv against the closed-form Loop masks.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <vector>

#include "expect_error.hpp"
#include "face_arrays.hpp"
#include "loop_masks.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/reference.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

using sorpia_test::loop_alpha;

namespace {

// Vertex neighbours and boundary flags computed from the face list alone.
struct Rings {
  std::vector<std::set<int>> nbr;
  std::vector<bool> boundary;
  std::vector<std::set<int>> boundary_nbr;
  std::vector<int> faces;
};

Rings rings_of(const sorpia::Mesh& m) {
  Rings r;
  const std::size_t n = m.n_vertices();
  r.nbr.resize(n);
  r.boundary.assign(n, false);
  r.boundary_nbr.resize(n);
  r.faces.assign(n, 0);
  std::map<std::pair<int, int>, int> edge_use;
  for (std::size_t f = 0; f < m.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = m.face_vertex_indices[3 * f + k], b = m.face_vertex_indices[3 * f + (k + 1) % 3];
      r.nbr[a].insert(b);
      r.nbr[b].insert(a);
      ++r.faces[a];
      ++edge_use[{std::min(a, b), std::max(a, b)}];
    }
  for (auto& [e, c] : edge_use)
    if (c == 1) {
      r.boundary[e.first] = r.boundary[e.second] = true;
      r.boundary_nbr[e.first].insert(e.second);
      r.boundary_nbr[e.second].insert(e.first);
    }
  return r;
}

double entry(const sorpia::CsrMatrix& b, int i, int j) {
  for (int p = b.indptr[i]; p < b.indptr[i + 1]; ++p)
    if (b.indices[p] == j) return b.data[p];
  return 0.0;
}

// Every entry of B equals the closed-form mask to `tol`.
void expect_closed_form(const sorpia::Mesh& m, sorpia::Boundary rule, double tol) {
  const sorpia::Topology topo(m);
  const auto b = sorpia::limit_matrix(topo, rule);
  const Rings r = rings_of(m);
  ASSERT_EQ(b.n_rows, m.n_vertices());
  for (std::size_t i = 0; i < m.n_vertices(); ++i) {
    std::map<int, double> expected;
    if (!r.boundary[i]) {
      const int n = static_cast<int>(r.nbr[i].size());
      const double a = loop_alpha(n);
      expected[i] = a;
      for (int j : r.nbr[i]) expected[j] = (1 - a) / n;
    } else if (r.faces[i] == 1 && rule == sorpia::Boundary::EdgeAndCorner) {
      expected[i] = 1.0;
    } else {
      expected[i] = 2.0 / 3.0;
      for (int j : r.boundary_nbr[i]) expected[j] = 1.0 / 6.0;
    }
    double row_sum = 0;
    for (int p = b.indptr[i]; p < b.indptr[i + 1]; ++p) {
      ASSERT_TRUE(expected.count(b.indices[p])) << "unexpected entry (" << i << ", " << b.indices[p] << ")";
      row_sum += b.data[p];
    }
    for (auto& [j, w] : expected) EXPECT_NEAR(entry(b, static_cast<int>(i), j), w, tol) << "B(" << i << ", " << j << ")";
    EXPECT_NEAR(row_sum, 1.0, 1e-14) << "row " << i << " is not affine";
  }
}

}  // namespace

// 1e-14: OpenSubdiv computes the same closed forms in double; the difference
// is a few rounding errors of the trigonometric expression.
TEST(LimitMatrix, ClosedIrregularMeshMatchesClosedForm) {
  expect_closed_form(sorpia::irregular(600, 7), sorpia::Boundary::EdgeOnly, 1e-14);
}

TEST(LimitMatrix, IcosphereMatchesClosedForm) { expect_closed_form(sorpia::icosphere(2), sorpia::Boundary::EdgeOnly, 1e-14); }

TEST(LimitMatrix, BoundaryMasksBothRules) {
  expect_closed_form(sorpia::grid(7, 5), sorpia::Boundary::EdgeOnly, 1e-14);
  expect_closed_form(sorpia::grid(7, 5), sorpia::Boundary::EdgeAndCorner, 1e-14);
}

TEST(LimitMatrix, HighValencePole) { expect_closed_form(sorpia::pole(64), sorpia::Boundary::EdgeOnly, 1e-14); }

TEST(LimitMatrix, KnownValuesFromTheLiterature) {
  // alpha_5 and alpha_6 of the paper's eq. 5, evaluated to 17 digits.
  EXPECT_NEAR(loop_alpha(6), 0.5, 1e-16);
  EXPECT_NEAR(loop_alpha(5), 0.47142172687440287, 1e-16);
}

// limit_points against OpenSubdiv's own Far Limit() on a refiner: 1e-15 is a
// few ulps of the unit-scale coordinates (the weights agree to rounding and the
// sums run in another order).
TEST(LimitPoints, EqualsOpenSubdivLimit) {
  for (auto rule : {sorpia::Boundary::EdgeOnly, sorpia::Boundary::EdgeAndCorner}) {
    const auto m = sorpia::irregular(400, 3);
    const sorpia::Topology topo(m);
    std::vector<double> ref(m.vertices.size()), lp(m.vertices.size());
    sorpia::reference_limit_points(topo, m.vertices.data(), rule, ref.data());
    sorpia::limit_points(topo, m.vertices.data(), rule, lp.data());
    for (std::size_t k = 0; k < ref.size(); ++k) EXPECT_NEAR(ref[k], lp[k], 1e-15);
  }
}

TEST(LimitMatrix, UnreferencedVertexGetsIdentityRow) {
  auto m = sorpia::icosphere(1);
  m.vertices.insert(m.vertices.end(), {5.0, 5.0, 5.0});  // vertex no face uses
  const sorpia::Topology topo(m);
  EXPECT_EQ(topo.n_unreferenced(), 1u);
  const auto b = sorpia::limit_matrix(topo, sorpia::Boundary::EdgeOnly);
  const int last = static_cast<int>(m.n_vertices()) - 1;
  EXPECT_EQ(b.indptr[last + 1] - b.indptr[last], 1);
  EXPECT_EQ(entry(b, last, last), 1.0);
}

TEST(Topology, RefusesBadFacesWithTheirIndex) {
  const std::vector<std::int32_t> out_of_range = {0, 1, 2, 0, 2, 9};
  EXPECT_THROW(sorpia::Topology(sorpia_test::triangles(out_of_range), 4), sorpia::MeshError);
  const std::vector<std::int32_t> repeated = {0, 1, 2, 0, 2, 2};
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::Topology topo(sorpia_test::triangles(repeated), 4); }, {"face 1"});
  const std::vector<std::int32_t> fin = {0, 1, 2, 0, 1, 3, 1, 0, 4};  // edge (0,1) in three faces
  EXPECT_THROW(sorpia::Topology(sorpia_test::triangles(fin), 5), sorpia::MeshError);
}

TEST(Topology, BoundaryRingStartsAndEndsOnTheBoundary) {
  const auto m = sorpia::grid(5, 5);
  const sorpia::Topology topo(m);
  const Rings r = rings_of(m);
  for (std::size_t v = 0; v < m.n_vertices(); ++v) {
    ASSERT_EQ(topo.is_boundary(v), r.boundary[v]);
    const auto& o = topo.ring_offsets();
    const auto& nb = topo.ring_neighbors();
    ASSERT_EQ(static_cast<std::size_t>(o[v + 1] - o[v]), r.nbr[v].size());
    if (r.boundary[v]) {
      EXPECT_TRUE(r.boundary_nbr[v].count(nb[o[v]]));
      EXPECT_TRUE(r.boundary_nbr[v].count(nb[o[v + 1] - 1]));
    }
  }
}
