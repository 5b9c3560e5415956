// sorpia::Topology refuses bad faces before OpenMesh and OpenSubdiv see them
// (OpenMesh aborts on a repeated vertex and accepts bowties; OpenSubdiv makes
// non-manifold vertices corners), with a message naming the face, edge or
// vertex; and accepts the unusual but valid meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

#include "bad_faces.hpp"
#include "expect_error.hpp"
#include "face_arrays.hpp"
#include "loop_masks.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace {

using sorpia_test::Faces;

// The Topology constructor throws MeshError whose message contains every one of `parts`.
void expect_refused(const Faces& faces, std::size_t n_vertices, const std::vector<std::string>& parts) {
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] { sorpia::Topology topo(sorpia_test::triangles(faces), n_vertices); }, parts);
}

}  // namespace

TEST(Validation, IndexOutOfRangeNamesTheFaceAndIndex) {
  expect_refused({0, 1, 2, 0, 2, 9}, 4, {"face 1 (0, 2, 9)", "vertex index 9", "[0, 4)"});
  expect_refused({0, 1, 2, 0, -1, 2}, 4, {"face 1", "vertex index -1"});
}

TEST(Validation, RepeatedVertexNamesTheFace) {
  // OpenMesh's add_face would abort (assert) on this face.
  expect_refused({0, 1, 2, 0, 2, 2}, 4, {"face 1 (0, 2, 2)", "repeats vertex 2"});
}

TEST(Validation, NoFacesIsRefused) { expect_refused({}, 3, {"no faces"}); }

TEST(Validation, DuplicateFacesInTheSameOrderOrBesideAThirdFace) {
  expect_refused({0, 1, 2, 1, 3, 2, 2, 0, 1}, 4, {"duplicate faces", "face 0 (0, 1, 2)", "face 2 (2, 0, 1)"});
  // reversed with a third face on edge (1, 2): non-manifold there
  expect_refused({0, 1, 2, 0, 2, 1, 1, 3, 2}, 4,
                 {"duplicate faces", "face 0 (0, 1, 2)", "face 1 (0, 2, 1)", "in the opposite order"});
}

// Reversed alone (every edge of two opposite faces: a closed 'pillow', which
// OpenSubdiv takes; issue 20) and beside other faces: valid, each vertex
// interior of valence 2, the same one-ring as OpenMesh's.
TEST(Validation, PillowsAreAccepted) {
  for (const Faces& faces : {Faces{0, 1, 2, 0, 2, 1}, Faces{0, 1, 2, 0, 2, 1, 3, 4, 5}}) {
    const std::size_t n = faces.size() == 6 ? 3 : 6;
    EXPECT_TRUE(sorpia::faces_valid(sorpia_test::triangles(faces), n));
    const sorpia::Topology t(sorpia_test::triangles(faces), n);
    for (std::size_t v = 0; v < 3; ++v) {
      EXPECT_FALSE(t.is_boundary(v));
      EXPECT_EQ(t.valence(v), 2);
    }
    sorpia_test::expect_reference_topology(sorpia_test::triangles(faces), n);
  }
}

TEST(Validation, NonManifoldEdgeNamesTheEdgeAndItsFaces) {
  expect_refused(sorpia_test::edge_with_three_faces, 5, {"non-manifold edge (0, 1)", "3 faces", "faces 0, 1, 2"});
}

TEST(Validation, InconsistentOrientationSaysWhichFacesToFlip) {
  auto m = sorpia::icosphere(1);
  std::swap(m.face_vertex_indices[3 * 7 + 1], m.face_vertex_indices[3 * 7 + 2]);  // reverse face 7
  expect_refused(m.face_vertex_indices, m.n_vertices(), {"inconsistent orientation at edge", "face 7", "1 of the 80 faces",
                                           "(faces 7)"});
}

TEST(Validation, MoebiusStripIsNotOrientable) {
  const Faces f = sorpia_test::moebius(8);
  expect_refused(f, 16, {"inconsistent orientation", "not orientable"});
}

TEST(Validation, BowtieVertexIsNamed) {
  // Two triangles sharing vertex 0 only: OpenMesh accepts this without complaint.
  expect_refused(sorpia_test::bowtie_open_fans, 5, {"non-manifold vertex 0", "2 fans", "faces 0 and 1"});
  // Two closed cones touching at their apex 0: no boundary edge anywhere.
  expect_refused(sorpia_test::bowtie_closed_cones, 7, {"non-manifold vertex 0", "6 faces form 2 fans"});
}

TEST(Validation, UnusualButValidMeshesAreAccepted) {
  const Faces single = {0, 1, 2};
  EXPECT_EQ(sorpia::Topology(sorpia_test::triangles(single), 3).n_boundary_edges(), 3u);
  // a strip: every vertex on the boundary
  const Faces strip = {0, 1, 2, 2, 1, 3, 2, 3, 4, 4, 3, 5};
  const sorpia::Topology s(sorpia_test::triangles(strip), 6);
  for (std::size_t v = 0; v < 6; ++v) EXPECT_TRUE(s.is_boundary(v));
  EXPECT_EQ(s.n_edges(), 9u);
  // two components (an icosphere and a disjoint triangle) and an unreferenced vertex
  auto m = sorpia::icosphere(1);
  const auto n = static_cast<std::int32_t>(m.n_vertices());
  m.face_vertex_indices.insert(m.face_vertex_indices.end(), {n, n + 1, n + 2});
  const sorpia::Topology two(m, m.n_vertices() + 4);
  EXPECT_EQ(two.n_unreferenced(), 1u);
  EXPECT_EQ(two.n_boundary_edges(), 3u);
}

TEST(Validation, Valence360PoleMatchesTheClosedForm) {
  // The closed-form mask alpha_n (paper eq. 5, loop_masks.hpp);
  // pole(n): the centre (vertex 0) is an interior vertex of valence n.
  const auto m = sorpia::pole(360);
  const sorpia::Topology topo(m);
  ASSERT_EQ(topo.valence(0), 360);
  const auto b = sorpia::limit_matrix(topo, sorpia::Boundary::EdgeOnly);
  const double alpha = sorpia_test::loop_alpha(360);
  ASSERT_EQ(b.indptr[1] - b.indptr[0], 361);
  for (std::int32_t p = b.indptr[0]; p < b.indptr[1]; ++p)
    EXPECT_NEAR(b.data[p], b.indices[p] == 0 ? alpha : (1 - alpha) / 360.0, 1e-15);  // double rounding only
}

TEST(Validation, ValenceBeyondOpenSubdivsLimitNamesTheVertex) {
  const auto m = sorpia::pole(65536);  // its centre, vertex 0, has 65536 neighbours
  expect_refused(m.face_vertex_indices, m.n_vertices(), {"vertex 0 has 65536 neighbours", "at most 65535"});
  const auto ok = sorpia::pole(65535);
  EXPECT_EQ(sorpia::Topology(ok).valence(0), 65535);
}

TEST(Validation, FaceOrderDoesNotMatter) {
  // A shuffled face order must give the same rings.
  const auto m = sorpia::irregular(400, 3);
  std::vector<std::size_t> order(m.n_faces());
  std::iota(order.begin(), order.end(), 0);
  std::reverse(order.begin(), order.end());
  for (std::size_t i = 0; i + 7 < order.size(); i += 7) std::swap(order[i], order[i + 3]);
  Faces shuffled;
  for (std::size_t f : order) shuffled.insert(shuffled.end(), m.face_vertex_indices.begin() + 3 * f, m.face_vertex_indices.begin() + 3 * f + 3);
  const sorpia::Topology a(m);
  const sorpia::Topology b(sorpia_test::triangles(shuffled), m.n_vertices());
  EXPECT_EQ(a.n_edges(), b.n_edges());
  for (std::size_t v = 0; v < m.n_vertices(); ++v) EXPECT_EQ(a.valence(v), b.valence(v));
}

TEST(Validation, BowtieOfAnOpenAndAClosedFanIsNamed) {
  // Vertex 0: an open fan (faces 0, 1: two boundary edges at 0, as one fan
  // has) and a closed cone (faces 2-5): only walking the fans tells them apart.
  expect_refused({0, 1, 2, 0, 2, 3, 0, 4, 5, 0, 5, 6, 0, 6, 4, 4, 6, 5}, 7,
                 {"non-manifold vertex 0: its 5 faces form 2 fans", "faces 0 and 2"});
}

TEST(Validation, ProblemsAreNamedInAFixedOrder) {
  // Edges of 3+ faces and duplicate faces come before orientation: face 7
  // reversed and, on higher-numbered vertices, a third face on an edge.
  auto m = sorpia::icosphere(1);
  const auto n = static_cast<std::int32_t>(m.n_vertices());
  std::swap(m.face_vertex_indices[3 * 7 + 1], m.face_vertex_indices[3 * 7 + 2]);
  const std::int32_t a = m.face_vertex_indices[3 * 70], b = m.face_vertex_indices[3 * 70 + 1];
  m.face_vertex_indices.insert(m.face_vertex_indices.end(), {a, b, n});
  expect_refused(m.face_vertex_indices, m.n_vertices() + 1,
                 {"non-manifold edge (" + std::to_string(std::min(a, b)) + ", " + std::to_string(std::max(a, b)) + ")"});

  // Of several misoriented edges the first by (lower end, higher end) is named,
  // found here by comparing every pair of faces.
  m = sorpia::icosphere(1);
  std::swap(m.face_vertex_indices[3 * 7 + 1], m.face_vertex_indices[3 * 7 + 2]);
  std::swap(m.face_vertex_indices[3 * 60 + 1], m.face_vertex_indices[3 * 60 + 2]);
  std::pair<std::int32_t, std::int32_t> first{n, n};
  for (std::size_t f = 0; f < m.n_faces(); ++f)
    for (std::size_t g = f + 1; g < m.n_faces(); ++g)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const std::int32_t p = m.face_vertex_indices[3 * f + i], q = m.face_vertex_indices[3 * f + (i + 1) % 3];
          if (p == m.face_vertex_indices[3 * g + j] && q == m.face_vertex_indices[3 * g + (j + 1) % 3])
            first = std::min(first, std::make_pair(std::min(p, q), std::max(p, q)));
        }
  ASSERT_LT(first.first, n);
  expect_refused(m.face_vertex_indices, m.n_vertices(),
                 {"inconsistent orientation at edge (" + std::to_string(first.first) + ", " +
                  std::to_string(first.second) + ")"});
}
