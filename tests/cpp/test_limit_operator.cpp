// The limit operator as the core builds it (its one-ring, OpenSubdiv's limit
// masks without a refiner) against the reference path (OpenMesh's one-ring,
// OpenSubdiv's Far Limit(): tests/reference).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "bad_faces.hpp"
#include "expect_error.hpp"
#include "face_arrays.hpp"
#include "loop_masks.hpp"
#include "poly_meshes.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/reference.hpp"
#include "sorpia/limit_masks.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/topology.hpp"

namespace {

using sorpia::Boundary;

// A boundary vertex (0) with n - 1 faces: the high-valence boundary case.
sorpia::Mesh fan(int n) {
  sorpia::Mesh m;
  m.vertices.assign(3 * (n + 1), 0.0);
  for (int i = 1; i < n; ++i) m.face_vertex_indices.insert(m.face_vertex_indices.end(), {0, i, i + 1});
  return m;
}

// The same mesh with its faces shuffled, each face's corners rotated at random
// and two unreferenced vertices appended: the one-ring must not depend on
// the face order OpenMesh's add_face happens to see.
sorpia::Mesh scrambled(sorpia::Mesh m, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::size_t> order(m.n_faces());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<std::int32_t> faces;
  for (std::size_t f : order) {
    const int r = static_cast<int>(rng() % 3);
    for (int k = 0; k < 3; ++k) faces.push_back(m.face_vertex_indices[3 * f + (k + r) % 3]);
  }
  m.face_vertex_indices = faces;
  m.vertices.insert(m.vertices.end(), 6, 0.5);
  return m;
}

struct Named {
  std::string name;
  sorpia::Mesh mesh;
};

// Closed irregular (valences 3..12), closed with valence 5 and 6, boundary
// with one-face corners, a valence-64 pole, a valence-40 boundary vertex, a
// single triangle, and scrambled copies.
std::vector<Named> meshes() {
  return {{"irregular", sorpia::irregular(3000, 5)},
          {"icosphere", sorpia::icosphere(3)},
          {"torus", sorpia::torus(9, 5)},
          {"grid", sorpia::grid(9, 7)},
          {"pole64", sorpia::pole(64)},
          {"fan41", fan(41)},
          {"triangle", fan(2)},
          {"irregular-scrambled", scrambled(sorpia::irregular(2000, 9), 3)},
          {"grid-scrambled", scrambled(sorpia::grid(8, 6), 4)},
          {"pole-scrambled", scrambled(sorpia::pole(30), 5)}};
}

TEST(FastTopology, OneRingEqualsOpenMesh) {
  for (const auto& [name, m] : meshes()) {
    SCOPED_TRACE(name);
    sorpia_test::expect_reference_topology(m, m.n_vertices());
  }
}

// The ring is the set of vertices sharing an edge with v, counted from the
// faces alone, and consecutive ring entries (clockwise) are the two other
// corners of one face, in the order (next, current) of that face.
TEST(FastTopology, OneRingIsTheClockwiseFan) {
  for (const auto& [name, m] : meshes()) {
    SCOPED_TRACE(name);
    const auto t = sorpia::Topology(m);
    std::vector<std::vector<std::pair<int, int>>> wedges(m.n_vertices());  // (next, prev) per corner
    for (std::size_t f = 0; f < m.n_faces(); ++f)
      for (int k = 0; k < 3; ++k)
        wedges[m.face_vertex_indices[3 * f + k]].push_back({m.face_vertex_indices[3 * f + (k + 1) % 3], m.face_vertex_indices[3 * f + (k + 2) % 3]});
    for (std::size_t v = 0; v < m.n_vertices(); ++v) {
      const int lo = t.ring_offsets()[v], hi = t.ring_offsets()[v + 1];
      const int steps = t.is_boundary(v) ? hi - lo - 1 : hi - lo;
      ASSERT_EQ(steps, static_cast<int>(wedges[v].size())) << "vertex " << v;
      for (int s = 0; s < steps; ++s) {
        const int x = t.ring_neighbors()[lo + s], y = t.ring_neighbors()[lo + (s + 1) % (hi - lo)];
        const std::pair<int, int> w{y, x};
        EXPECT_NE(std::find(wedges[v].begin(), wedges[v].end(), w), wedges[v].end())
            << "vertex " << v << ": " << x << " -> " << y << " is not a face's clockwise step";
      }
    }
  }
}

// Each bad mesh is refused by Topology, naming the problem, and those that
// OpenMesh can be given (it aborts on a repeated or out-of-range vertex) by
// OpenMesh's own half-edge build too: add_face refuses the edge of three faces
// and the misoriented edge, and its circulator passes one fan of a bowtie.
TEST(FastTopology, BadMeshesRefusedByTopologyAndOpenMesh) {
  struct Bad {
    std::string what;
    std::vector<std::int32_t> faces;
    bool openmesh;
  };
  const std::vector<Bad> bad = {
      {"bowtie of two open fans", sorpia_test::bowtie_open_fans, true},
      {"two closed cones at one apex", sorpia_test::bowtie_closed_cones, true},
      {"edge with three faces", sorpia_test::edge_with_three_faces, true},
      {"inconsistent orientation", {0, 1, 2, 0, 1, 3}, true},
      {"repeated vertex", {0, 1, 1}, false},
      {"index out of range", {0, 1, 9}, false},
  };
  for (const auto& [what, faces, openmesh] : bad) {
    SCOPED_TRACE(what);
    const sorpia::Mesh m = sorpia_test::triangles(faces);
    EXPECT_THROW(sorpia::Topology(m, 7), sorpia::MeshError);
    if (openmesh) {
      EXPECT_THROW(sorpia::reference_one_ring(m, 7), sorpia::MeshError);
    }
  }
}

// Masks from Sdc against the closed form written independently in
// loop_masks.hpp. 1e-15: both evaluate the same trigonometric expression in
// double, in a different order (a few ulps).
TEST(LimitMasks, SmoothMaskIsTheClosedForm) {
  for (int n = 2; n <= 200; ++n) {  // 2: a vertex of a pillow
    const auto m = sorpia::smooth_limit_mask(n);
    EXPECT_NEAR(m.diag, sorpia_test::loop_alpha(n), 1e-15) << "valence " << n;
    EXPECT_NEAR(m.weight, (1 - sorpia_test::loop_alpha(n)) / n, 1e-15) << "valence " << n;
  }
  EXPECT_EQ(sorpia::smooth_limit_mask(6).diag, 0.5);
  EXPECT_EQ(sorpia::smooth_limit_mask(6).weight, 1.0 / 12.0);
  EXPECT_NEAR(sorpia::crease_limit_mask().diag, 2.0 / 3.0, 1e-16);
  EXPECT_NEAR(sorpia::crease_limit_mask().weight, 1.0 / 6.0, 1e-16);
  EXPECT_EQ(sorpia::corner_limit_mask().diag, 1.0);
  EXPECT_EQ(sorpia::corner_limit_mask().weight, 0.0);
  EXPECT_THROW(sorpia::smooth_limit_mask(1), sorpia::ParameterError);
}

// The masks path against OpenSubdiv's Far Limit(): same pattern, and values
// within 1e-15 (both run Sdc's mask code in double; in practice they are equal).
TEST(LimitMasks, MatrixEqualsOpenSubdivLimit) {
  for (const auto& [name, m] : meshes())
    for (auto rule : {Boundary::EdgeOnly, Boundary::EdgeAndCorner}) {
      SCOPED_TRACE(name + (rule == Boundary::EdgeOnly ? " edge-only" : " edge-and-corner"));
      const auto t = sorpia::Topology(m);
      const auto ref = sorpia::reference_limit_matrix(t, rule);
      const auto fast = sorpia::limit_matrix(t, rule);
      ASSERT_EQ(fast.n_rows, ref.n_rows);
      ASSERT_EQ(fast.indptr, ref.indptr);
      ASSERT_EQ(fast.indices, ref.indices);
      double worst = 0;
      for (std::size_t p = 0; p < ref.data.size(); ++p) worst = std::max(worst, std::abs(fast.data[p] - ref.data[p]));
      EXPECT_LE(worst, 1e-15);
    }
}

TEST(LimitMasks, OperatorEqualsTheSolversCompactForm) {
  for (const auto& [name, m] : meshes())
    for (auto rule : {Boundary::EdgeOnly, Boundary::EdgeAndCorner}) {
      SCOPED_TRACE(name);
      const auto t = sorpia::Topology(m);
      const auto ref = sorpia::limit_operator(sorpia::reference_limit_matrix(t, rule));
      const auto fast = sorpia::limit_operator(t, rule);
      EXPECT_TRUE(fast.uniform());
      EXPECT_TRUE(ref.uniform());
      ASSERT_EQ(fast.n, ref.n);
      EXPECT_EQ(fast.offsets, ref.offsets);
      EXPECT_EQ(fast.neighbors, ref.neighbors);
      for (std::size_t i = 0; i < ref.n; ++i) {
        ASSERT_NEAR(fast.diag[i], ref.diag[i], 1e-15) << "row " << i;
        ASSERT_NEAR(fast.weight[i], ref.weight[i], 1e-15) << "row " << i;
      }
    }
}

// Per-vertex query agrees with the assembled operator.
TEST(LimitMasks, PerVertexMaskMatchesOperator) {
  const auto m = sorpia::grid(6, 5);
  const auto t = sorpia::Topology(m);
  const auto op = sorpia::limit_operator(t, Boundary::EdgeAndCorner);
  for (std::size_t i = 0; i < m.n_vertices(); ++i) {
    const auto mask = sorpia::limit_mask(t, i, Boundary::EdgeAndCorner);
    EXPECT_EQ(mask.diag, op.diag[i]);
    EXPECT_EQ(mask.weight, op.weight[i]);
  }
}

}  // namespace
