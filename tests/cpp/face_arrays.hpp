#pragma once
// Test helpers: faces without coordinates as a sorpia::Mesh, and a Topology
// compared array by array with OpenMesh's one-ring (sorpia::reference_one_ring).
#include <gtest/gtest.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "sorpia/mesh.hpp"
#include "sorpia/reference.hpp"
#include "sorpia/topology.hpp"

namespace sorpia_test {

// Triangles, row-major (n, 3), without counts (Topology's triangle fast path).
inline sorpia::Mesh triangles(std::vector<std::int32_t> indices) {
  sorpia::Mesh m;
  m.face_vertex_indices = std::move(indices);
  return m;
}

// Polygons as counts and indices.
inline sorpia::Mesh polygons(std::vector<std::int32_t> counts, std::vector<std::int32_t> indices) {
  sorpia::Mesh m;
  m.face_vertex_counts = std::move(counts);
  m.face_vertex_indices = std::move(indices);
  return m;
}

// Topology's build and OpenMesh's (the reference) agree on every array: edge
// neighbours, and for polygons the faces and face neighbours.
inline void expect_same_topology(const sorpia::Topology& t, const sorpia::ReferenceOneRing& ref) {
  EXPECT_EQ(t.ring_offsets(), ref.offsets);
  EXPECT_EQ(t.ring_neighbors(), ref.neighbors);
  EXPECT_EQ(t.vertex_face_offsets(), ref.face_offsets);
  EXPECT_EQ(t.vertex_faces(), ref.faces);
  EXPECT_EQ(t.face_ring_offsets(), ref.face_ring_offsets);
  EXPECT_EQ(t.face_ring_neighbors(), ref.face_ring);
  EXPECT_EQ(t.n_edges(), ref.n_edges);
  EXPECT_EQ(t.n_boundary_edges(), ref.n_boundary_edges);
  EXPECT_EQ(t.n_unreferenced(), ref.n_unreferenced);
  for (std::size_t v = 0; v < t.n_vertices(); ++v) {
    ASSERT_EQ(t.is_boundary(v), ref.boundary[v] != 0) << "vertex " << v;
    ASSERT_EQ(t.face_count(v), ref.face_count[v]) << "vertex " << v;
    ASSERT_EQ(t.quad_ring(v), !ref.quad_ring.empty() && ref.quad_ring[v] != 0) << "vertex " << v;
  }
}

// Topology(faces, n_vertices) checked against OpenMesh's one-ring of the same faces.
inline void expect_reference_topology(const sorpia::Mesh& faces, std::size_t n_vertices) {
  expect_same_topology(sorpia::Topology(faces, n_vertices), sorpia::reference_one_ring(faces, n_vertices));
}

}  // namespace sorpia_test
