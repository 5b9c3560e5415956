// The half-edge matcher (sorpia/detail/half_edges.hpp's EdgeGroups) against a
// grouping by a std::map from (lower, higher end) to half-edges: the same
// edges in the same order, each with the same half-edges, on triangles and
// polygons with edges of one, two and three faces, and with half-edges left
// out.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "sorpia/detail/half_edges.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace {

using Ints = std::vector<std::int32_t>;
using Groups = std::vector<std::pair<std::pair<std::int32_t, std::int32_t>, Ints>>;

Groups by_map(const sorpia::detail::FaceList& fl, const std::vector<bool>& keep) {
  std::map<std::pair<std::int32_t, std::int32_t>, Ints> m;
  for (std::size_t h = 0; h < fl.n_corners(); ++h) {
    if (!keep[h]) continue;
    const std::int32_t a = fl.idx[h], b = fl.idx[fl.next(h)];
    m[{std::min(a, b), std::max(a, b)}].push_back(static_cast<std::int32_t>(h));  // h ascending: id order
  }
  return Groups(m.begin(), m.end());
}

Groups by_matcher(const sorpia::detail::FaceList& fl, std::size_t n_vertices, const std::vector<bool>& keep) {
  Groups g;
  sorpia::detail::EdgeGroups(fl, n_vertices, [&](std::size_t h) { return keep[h]; })
      .for_each([&](std::int32_t a, std::int32_t b, const std::int32_t* hs, std::int32_t k) {
        g.push_back({{a, b}, Ints(hs, hs + k)});
      });
  return g;
}

void expect_same_groups(const sorpia::detail::FaceList& fl, std::size_t n_vertices) {
  std::vector<bool> all(fl.n_corners(), true), some(fl.n_corners());
  for (std::size_t h = 0; h < some.size(); ++h) some[h] = h % 7 != 3;
  for (const auto& keep : {all, some}) {
    const Groups want = by_map(fl, keep), got = by_matcher(fl, n_vertices, keep);
    EXPECT_EQ(got, want);
    // mates(): the other half-edge of an edge of two, `single` for one, `many` for more.
    const sorpia::detail::EdgeGroups groups(fl, n_vertices, [&](std::size_t h) { return keep[h]; });
    const Ints mate = groups.mates(-1, -2);
    for (const auto& [edge, hs] : want)
      for (std::size_t i = 0; i < hs.size(); ++i)
        EXPECT_EQ(mate[hs[i]], hs.size() == 1 ? -1 : hs.size() == 2 ? hs[1 - i] : -2);
  }
}

TEST(EdgeGroups, TrianglesWithAnEdgeOfThreeFacesMatchAMap) {
  sorpia::Mesh m = sorpia::torus(6, 5);
  const auto n = static_cast<std::int32_t>(m.n_vertices());
  // A third face on the first edge, and a dangling face: edges of 3 and of 1 faces.
  m.face_vertex_indices.insert(m.face_vertex_indices.end(),
                               {m.face_vertex_indices[0], m.face_vertex_indices[1], n, n, n + 1, n + 2});
  const sorpia::detail::FaceList fl{m.face_vertex_indices.data(), nullptr, nullptr, m.n_faces()};
  expect_same_groups(fl, m.n_vertices() + 3);
}

TEST(EdgeGroups, PolygonsMatchAMap) {
  const sorpia::Mesh m = sorpia::polygon_torus(8, 6, 3);
  const Ints off = sorpia::detail::polygon_offsets(m.face_vertex_counts.data(), m.n_faces());
  const Ints corner_face = sorpia::detail::corner_faces(off);
  const sorpia::detail::FaceList fl{m.face_vertex_indices.data(), off.data(), corner_face.data(), m.n_faces()};
  expect_same_groups(fl, m.n_vertices());
}

}  // namespace

namespace {

// Topology::half_edge_twins and find_half_edges against a std::map from the
// directed edge (a, b) to its half-edge, on triangles, quads and mixed
// polygons, closed and open: the twin of a -> b is b -> a, or -1 on the
// boundary; every edge is found from either end, a pair that is no edge is not.
TEST(Topology, HalfEdgeTwinsAndFoundEdgesMatchAMap) {
  for (const sorpia::Mesh& m : {sorpia::irregular(300, 2), sorpia::grid(6, 5), sorpia::quad_irregular(300, 2),
                                sorpia::polygon_torus(8, 6, 2), sorpia::quad_grid(5, 4)}) {
    const sorpia::Topology t(m);
    const auto& fi = t.face_indices();
    std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> directed;
    for (std::size_t f = 0; f < t.n_faces(); ++f)
      for (std::int32_t i = 0; i < t.face_size(f); ++i) {
        const std::int32_t h = t.face_offset(f) + i;
        directed[{fi[h], fi[t.face_offset(f) + (i + 1) % t.face_size(f)]}] = h;
      }
    const Ints twin = t.half_edge_twins();
    ASSERT_EQ(twin.size(), fi.size());
    std::size_t boundary = 0;
    Ints pairs, lowest;
    for (const auto& [ab, h] : directed) {
      const auto it = directed.find({ab.second, ab.first});
      EXPECT_EQ(twin[static_cast<std::size_t>(h)], it == directed.end() ? -1 : it->second) << "half-edge " << h;
      boundary += it == directed.end();
      pairs.insert(pairs.end(), {ab.second, ab.first});  // from the other end
      lowest.push_back(it == directed.end() ? h : std::min(h, it->second));
    }
    EXPECT_EQ(boundary, t.n_boundary_edges());
    EXPECT_EQ(t.find_half_edges(pairs.data(), pairs.size() / 2), lowest);
    const std::int32_t far[2] = {fi[0], fi[0]};  // a vertex and itself: no edge
    EXPECT_EQ(t.find_half_edges(far, 1), Ints{-1});
  }
}

}  // namespace
