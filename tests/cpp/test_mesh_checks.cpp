// Mesh statistics and the fit's residual check against closed forms and
// against OpenSubdiv's own limit evaluation (Far::PrimvarRefiner::Limit).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "face_arrays.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/limit_residual.hpp"
#include "sorpia/mesh_statistics.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace {

sorpia::Topology topology_of(const sorpia::Mesh& m) {
  return sorpia::Topology(m);
}

TEST(MeshStatistics, TorusAndGridMatchTheirClosedForms) {
  const auto torus = sorpia::torus(8, 5);  // V = 40, all valence 6: E = 3V, F = 2V, genus 1
  const auto t = sorpia::mesh_statistics(topology_of(torus));
  EXPECT_EQ(t.n_edges, 120u);
  EXPECT_EQ(t.n_boundary_edges, 0u);
  EXPECT_EQ(t.n_boundary_loops, 0u);
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_EQ(t.genus, 1);
  EXPECT_EQ(t.n_components, 1u);
  EXPECT_TRUE(t.extraordinary.empty());
  ASSERT_EQ(t.interior_valences.size(), 7u);
  EXPECT_EQ(t.interior_valences[6], 40u);

  const auto grid = sorpia::grid(6, 4);  // a disc: V - E + F = 1, one loop round 2 (5 + 3) edges
  const auto g = sorpia::mesh_statistics(topology_of(grid));
  EXPECT_EQ(g.n_faces, 2u * 5 * 3);
  EXPECT_EQ(g.euler_characteristic, 1);
  EXPECT_EQ(g.n_boundary_edges, 16u);
  EXPECT_EQ(g.n_boundary_loops, 1u);
  EXPECT_EQ(g.genus, 0);
}

TEST(MeshStatistics, RawFaceListCountsEqualTheTopologys) {
  for (const auto& m : {sorpia::irregular(300, 2), sorpia::grid(7, 5), sorpia::pole(9)}) {
    const auto a = sorpia::mesh_statistics(topology_of(m));
    const auto b = sorpia::face_list_statistics(m, m.n_vertices());
    ASSERT_TRUE(b.has_value());
    EXPECT_FALSE(b->genus.has_value());
    EXPECT_EQ(a.n_edges, b->n_edges);
    EXPECT_EQ(a.n_boundary_edges, b->n_boundary_edges);
    EXPECT_EQ(a.n_boundary_loops, b->n_boundary_loops);
    EXPECT_EQ(a.n_components, b->n_components);
    EXPECT_EQ(a.euler_characteristic, b->euler_characteristic);
    EXPECT_EQ(a.interior_valences, b->interior_valences);
    EXPECT_EQ(a.boundary_valences, b->boundary_valences);
    ASSERT_EQ(a.extraordinary.size(), b->extraordinary.size());
    for (std::size_t i = 0; i < a.extraordinary.size(); ++i) {
      EXPECT_EQ(a.extraordinary[i].vertex, b->extraordinary[i].vertex);
      EXPECT_EQ(a.extraordinary[i].valence, b->extraordinary[i].valence);
    }
  }
}

TEST(MeshStatistics, BowtieHasTwoLoopsTouchingAtOneVertex) {
  // Two fans round vertex 0 sharing only it: loops 0-1-2-3 and 0-4-5.
  const std::vector<std::int32_t> faces = {0, 1, 2, 0, 2, 3, 0, 4, 5};
  const auto s = sorpia::face_list_statistics(sorpia_test::triangles(faces), 6);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->n_boundary_loops, 2u);
  EXPECT_EQ(s->n_components, 1u);
  EXPECT_FALSE(sorpia::face_list_statistics(sorpia_test::triangles(faces), 5).has_value());  // index 5 out of range
}

TEST(MeshStatistics, RawFaceListIsATriangleList) {
  // Polygons (with counts, or a uniform face_size other than 3) are counted from a Topology only.
  const sorpia::Mesh quads = sorpia::quad_grid(2, 2);
  EXPECT_THROW(sorpia::face_list_statistics(quads, quads.n_vertices()), sorpia::MeshError);
  sorpia::Mesh uniform = quads;
  uniform.face_vertex_counts.clear();
  uniform.face_size = 4;
  EXPECT_THROW(sorpia::face_list_statistics(uniform, uniform.n_vertices()), sorpia::MeshError);
}

TEST(LimitResidual, IsZeroAgainstOpenSubdivsLimitAndNamesTheWorstVertex) {
  for (const auto boundary : {sorpia::Boundary::EdgeAndCorner, sorpia::Boundary::EdgeOnly}) {
    for (const auto& m : {sorpia::irregular(400, 3), sorpia::grid(6, 5), sorpia::pole(11)}) {
      const auto topo = topology_of(m);
      std::vector<double> limit(m.vertices.size());
      sorpia::limit_points(topo, m.vertices.data(), boundary, limit.data());
      std::vector<double> norms(m.n_vertices());
      const auto r = sorpia::limit_residual(topo, m.vertices.data(), limit.data(), boundary, norms.data());
      EXPECT_LT(r.max, 1e-14);
      limit[3 * 7 + 1] += 0.5;  // the target of vertex 7 moved: the check sees it there
      const auto moved = sorpia::limit_residual(topo, m.vertices.data(), limit.data(), boundary);
      EXPECT_NEAR(moved.max, 0.5, 1e-14);
      EXPECT_EQ(moved.argmax, 7u);
    }
  }
}

}  // namespace
