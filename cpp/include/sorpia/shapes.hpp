#pragma once
/// @file shapes.hpp
/// Generated triangle meshes for tests, benchmarks and the demo.

#include <cstdint>
#include <vector>

namespace sorpia {

/// A triangle mesh as flat row-major arrays.
struct TriMesh {
  std::vector<double> vertices;      ///< (n, 3)
  std::vector<std::int32_t> faces;   ///< (m, 3), counter-clockwise seen from outside

  std::size_t n_vertices() const { return vertices.size() / 3; }
  std::size_t n_faces() const { return faces.size() / 3; }
};

/// Unit sphere: the icosahedron split `level` times (each face into 4), new
/// vertices pushed to the sphere. 10*4^level + 2 vertices; valences 5 (12 of
/// them) and 6. @param level 0..10
TriMesh icosphere(int level);

/// Torus with radii 1 and 0.4, an nu x nv grid of vertices, every vertex of
/// valence 6 (the regular case). @param nu, nv at least 3
TriMesh torus(int nu, int nv);

/// An open, wavy square patch z = 0.1 sin(2 pi x) cos(2 pi y) on an nu x nv grid
/// of vertices: boundary vertices of valence 3 and 4, two one-face corners of
/// valence 2. @param nu, nv at least 2
TriMesh grid(int nu, int nv);

/// A disk with one interior vertex of valence n (a pole) at the centre, two
/// rings of n vertices around it. @param n at least 3
TriMesh pole(int n);

/// An irregular closed mesh of about `n_vertices` vertices: a torus whose edges
/// are flipped at random (OpenMesh's flip, keeping valences in 3..12), so that
/// most vertices are extraordinary. Deterministic for a given seed.
TriMesh irregular(int n_vertices, std::uint32_t seed = 1);

}  // namespace sorpia
