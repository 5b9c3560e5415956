#pragma once
// Polygon meshes for the topology and limit tests: quads (closed, open,
// irregular), mixed triangles/quads/pentagons/hexagons, and scrambled copies
// (faces shuffled, corners rotated, unreferenced vertices appended).
#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "sorpia/shapes.hpp"

namespace sorpia_test {

inline sorpia::Mesh scrambled(const sorpia::Mesh& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::int32_t> off(m.n_faces() + 1, 0);
  for (std::size_t f = 0; f < m.n_faces(); ++f) off[f + 1] = off[f] + m.face_vertex_counts[f];
  std::vector<std::size_t> order(m.n_faces());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  sorpia::Mesh s;
  s.vertices = m.vertices;
  for (std::size_t f : order) {
    const int n = m.face_vertex_counts[f], r = static_cast<int>(rng() % n);
    s.face_vertex_counts.push_back(n);
    for (int k = 0; k < n; ++k) s.face_vertex_indices.push_back(m.face_vertex_indices[off[f] + (k + r) % n]);
  }
  s.vertices.insert(s.vertices.end(), 6, 0.5);
  return s;
}

// A single polygon of n vertices (all boundary).
inline sorpia::Mesh ngon(int n) {
  sorpia::Mesh m;
  for (int k = 0; k < n; ++k) m.vertices.insert(m.vertices.end(), {1.0 * k, 0.5 * k * k, 0.0});
  m.face_vertex_counts = {n};
  for (int k = 0; k < n; ++k) m.face_vertex_indices.push_back(k);
  return m;
}

struct NamedPoly {
  std::string name;
  sorpia::Mesh mesh;
};

inline std::vector<NamedPoly> polygon_meshes() {
  return {{"quad-torus", sorpia::quad_torus(8, 6)},
          {"quad-grid", sorpia::quad_grid(7, 5)},
          {"quad-irregular", sorpia::quad_irregular(1200, 2)},
          {"polygon-torus", sorpia::polygon_torus(12, 10, 3)},
          {"pentagon", ngon(5)},
          {"quad-grid-scrambled", scrambled(sorpia::quad_grid(6, 6), 4)},
          {"polygon-torus-scrambled", scrambled(sorpia::polygon_torus(10, 8, 5), 6)},
          {"quad-irregular-scrambled", scrambled(sorpia::quad_irregular(600, 7), 8)}};
}

}  // namespace sorpia_test
