// Polygon topology: the one-ring (edge and face neighbours) against OpenMesh's
// PolyMesh (sorpia::reference_one_ring) and against the face list itself; the
// face checks on polygons; triangles given with counts unchanged.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "expect_error.hpp"
#include "face_arrays.hpp"
#include "poly_meshes.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace {

using sorpia::Mesh;
using sorpia_test::polygons;

TEST(PolygonTopology, OneRingEqualsOpenMeshPolyMesh) {
  for (const auto& [name, m] : sorpia_test::polygon_meshes()) {
    SCOPED_TRACE(name);
    const sorpia::Topology t(m);
    ASSERT_TRUE(t.has_face_ring());
    sorpia_test::expect_same_topology(t, sorpia::reference_one_ring(m, m.n_vertices()));
  }
}

// Against the face list alone: face j of vertex v has v's corner with
// prev = ring[j] and next = ring[j + 1], and its face neighbours are the
// face's vertices after next up to before prev; every face at v appears once;
// quad_ring says whether all of them are quads.
TEST(PolygonTopology, FaceRingIsTheFacesBetweenConsecutiveNeighbours) {
  for (const auto& [name, m] : sorpia_test::polygon_meshes()) {
    SCOPED_TRACE(name);
    const auto t = sorpia::Topology(m);
    if (!t.has_face_ring()) continue;
    const auto& off = t.face_offsets();
    const auto& idx = t.face_indices();
    std::vector<int> faces_at(m.n_vertices(), 0);
    for (std::int32_t v : idx) ++faces_at[v];
    for (std::size_t v = 0; v < m.n_vertices(); ++v) {
      const int lo = t.ring_offsets()[v], hi = t.ring_offsets()[v + 1], k = hi - lo;
      const int f_lo = t.vertex_face_offsets()[v], f_hi = t.vertex_face_offsets()[v + 1];
      ASSERT_EQ(f_hi - f_lo, faces_at[v]) << "vertex " << v;
      ASSERT_EQ(f_hi - f_lo, t.is_boundary(v) ? k - 1 : k) << "vertex " << v;
      int r = t.face_ring_offsets()[v];
      bool quads = faces_at[v] > 0;
      std::vector<int> seen;
      for (int j = 0; j < f_hi - f_lo; ++j) {
        const int f = t.vertex_faces()[f_lo + j];
        seen.push_back(f);
        const int n = off[f + 1] - off[f];
        quads = quads && n == 4;
        int p = 0;
        while (idx[off[f] + p] != static_cast<int>(v)) ++p;
        EXPECT_EQ(idx[off[f] + (p + n - 1) % n], t.ring_neighbors()[lo + j]) << "vertex " << v << " face " << f;
        EXPECT_EQ(idx[off[f] + (p + 1) % n], t.ring_neighbors()[lo + (j + 1) % k]) << "vertex " << v;
        for (int s = 2; s < n - 1; ++s) EXPECT_EQ(t.face_ring_neighbors()[r++], idx[off[f] + (p + s) % n]);
      }
      EXPECT_EQ(r, t.face_ring_offsets()[v + 1]);
      std::sort(seen.begin(), seen.end());
      EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end()) << "vertex " << v;
      EXPECT_EQ(t.quad_ring(v), quads) << "vertex " << v;
    }
  }
}

TEST(PolygonTopology, TrianglesWithCountsAreTheTriangleTopology) {
  const sorpia::Mesh tri = sorpia::irregular(2000, 3);
  const std::vector<std::int32_t> counts(tri.n_faces(), 3);
  const sorpia::Topology a(tri);
  const sorpia::Topology b(polygons(counts, tri.face_vertex_indices), tri.n_vertices());
  EXPECT_TRUE(b.all_triangles());
  EXPECT_FALSE(b.has_face_ring());
  EXPECT_EQ(a.ring_offsets(), b.ring_offsets());
  EXPECT_EQ(a.ring_neighbors(), b.ring_neighbors());
  EXPECT_EQ(a.faces(), b.faces());
  EXPECT_EQ(b.face_counts(), counts);
  for (std::size_t f = 0; f <= tri.n_faces(); ++f) ASSERT_EQ(b.face_offsets()[f], static_cast<int>(3 * f));
}

// A uniform mesh given by face_size alone (no counts) is the mesh with its
// counts written out; counts and face_size that do not fit the indices are refused.
TEST(PolygonTopology, UniformFaceSizeIsTheMeshWithCounts) {
  const Mesh quads = sorpia::quad_irregular(300, 2);
  Mesh uniform = quads;
  uniform.face_vertex_counts.clear();
  uniform.face_size = 4;
  const sorpia::Topology a(quads), b(uniform);
  EXPECT_TRUE(b.all_quads());
  EXPECT_EQ(a.face_offsets(), b.face_offsets());
  EXPECT_EQ(a.ring_neighbors(), b.ring_neighbors());
  EXPECT_EQ(a.face_ring_neighbors(), b.face_ring_neighbors());
  Mesh bad = uniform;
  bad.face_size = 2;
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::Topology t(bad); }, {"face_size is 2", "at least 3"});
  bad.face_size = 5;
  ASSERT_NE(uniform.face_vertex_indices.size() % 5, 0u);
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::Topology t(bad); }, {"not a multiple of face_size 5"});
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] { sorpia::Topology t(polygons({4, 4}, {0, 1, 2, 3, 0, 3, 2}), 4); },
      {"face_vertex_counts sum to 8 but face_vertex_indices has 7 entries"});
}

TEST(PolygonTopology, QuadTorusIsRegular) {
  const Mesh m = sorpia::quad_torus(7, 5);
  const auto t = sorpia::Topology(m);
  EXPECT_TRUE(t.all_quads());
  EXPECT_EQ(t.n_edges(), 2 * m.n_vertices());
  for (std::size_t v = 0; v < m.n_vertices(); ++v) {
    EXPECT_EQ(t.valence(v), 4);
    EXPECT_TRUE(t.quad_ring(v));
    EXPECT_EQ(t.face_ring_offsets()[v + 1] - t.face_ring_offsets()[v], 4);
  }
  EXPECT_THROW(static_cast<void>(t.faces()), std::logic_error);
}

void expect_refused(const std::vector<std::int32_t>& counts, const std::vector<std::int32_t>& indices, int n_vertices,
                    const std::vector<std::string>& parts) {
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::Topology(polygons(counts, indices), n_vertices); },
                                               parts);
}

TEST(PolygonTopology, BadPolygonsAreNamed) {
  expect_refused({4, 2}, {0, 1, 2, 3, 0, 1}, 4, {"face 1 has 2 vertices", "at least 3"});
  expect_refused({4, 0}, {0, 1, 2, 3}, 4, {"face 1 has 0 vertices"});
  expect_refused({4, 4}, {0, 1, 2, 3, 0, 4, 5, 4}, 6, {"face 1 (0, 4, 5, 4)", "repeats vertex 4", "polygon"});
  expect_refused({4}, {0, 1, 2, 9}, 4, {"face 0 (0, 1, 2, 9)", "out of range [0, 4)"});
  // three quads on edge (0, 1)
  expect_refused({4, 4, 4}, {0, 1, 2, 3, 1, 0, 4, 5, 1, 0, 6, 7}, 8,
                 {"non-manifold edge (0, 1)", "shared by 3 faces", "faces 0, 1, 2"});
  // two quads running 0 -> 1 the same way
  expect_refused({4, 4}, {0, 1, 2, 3, 0, 1, 4, 5}, 6,
                 {"inconsistent orientation at edge (0, 1)", "face 0 (0, 1, 2, 3)", "face 1 (0, 1, 4, 5)",
                  "reversing the vertex order of 1"});
  // two quads meeting only at vertex 0
  expect_refused({4, 4}, {0, 1, 2, 3, 0, 4, 5, 6}, 7, {"non-manifold vertex 0", "bowtie"});
}

// Two polygons with the same vertices in the same cyclic order are refused,
// naming both, as two such triangles are; in the opposite order they are a
// closed 'pillow' of two faces (valid: OpenSubdiv takes it), refused only
// with a third face on one of their edges (named by that edge on the polygon
// path, as duplicates on the triangle path). Not duplicates: two quads that share only
// the two edges at a vertex of two faces (next test).
TEST(PolygonTopology, DuplicatePolygonsAreNamedAndPillowsAccepted) {
  expect_refused({4, 4, 4}, {0, 1, 2, 3, 0, 3, 2, 1, 1, 4, 5, 2}, 6,
                 {"non-manifold edge (1, 2)", "faces 0, 1, 2"});  // a third face on edge (1, 2)
  expect_refused({4, 4, 4}, {0, 1, 2, 3, 4, 5, 6, 7, 2, 3, 0, 1}, 8,
                 {"duplicate faces", "face 0 (0, 1, 2, 3)", "face 2 (2, 3, 0, 1)", "same cyclic order"});
  expect_refused({3, 3, 4}, {0, 1, 2, 0, 2, 1, 1, 3, 4, 2}, 5, {"non-manifold edge (1, 2)", "faces 0, 1, 2"});
  const std::vector<std::pair<std::vector<std::int32_t>, std::vector<std::int32_t>>> pillows = {
      {{4, 4}, {0, 1, 2, 3, 0, 3, 2, 1}},
      {{4, 4, 4}, {0, 1, 2, 3, 0, 3, 2, 1, 4, 5, 6, 7}},
      {{4, 4, 3}, {0, 1, 2, 3, 0, 3, 2, 1, 4, 5, 6}},
      {{3, 3, 4}, {0, 1, 2, 0, 2, 1, 3, 4, 5, 6}}};
  for (const auto& [counts, idx] : pillows) {
    const std::size_t n = static_cast<std::size_t>(*std::max_element(idx.begin(), idx.end()) + 1);
    const sorpia::Topology t(polygons(counts, idx), n);
    for (std::size_t v = 0; v < static_cast<std::size_t>(counts[0]); ++v) {
      EXPECT_FALSE(t.is_boundary(v));
      EXPECT_EQ(t.valence(v), 2);
    }
    sorpia_test::expect_reference_topology(polygons(counts, idx), n);
  }
}

// Two quads sharing both edges at vertex 1 make it an interior vertex of two
// faces (OpenSubdiv's "valence 2"), which polygon meshes may have; as
// triangles the same pair would be one face given twice.
TEST(PolygonTopology, VertexOfTwoFacesIsAccepted) {
  const std::vector<std::int32_t> counts = {4, 4}, idx = {0, 1, 2, 3, 2, 1, 0, 4};
  const sorpia::Topology t(polygons(counts, idx), 5);
  EXPECT_FALSE(t.is_boundary(1));
  EXPECT_EQ(t.valence(1), 2);
  EXPECT_EQ(t.face_count(1), 2);
  sorpia_test::expect_reference_topology(polygons(counts, idx), 5);
}

}  // namespace
