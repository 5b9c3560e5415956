#pragma once
/// @file shapes.hpp
/// Generated triangle and polygon meshes for tests, benchmarks and the demo.

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

/// A polygon mesh in the counts + indices form (Far::TopologyDescriptor's).
struct PolyMesh {
  std::vector<double> vertices;            ///< (n, 3)
  std::vector<std::int32_t> face_counts;   ///< vertices of each face
  std::vector<std::int32_t> face_indices;  ///< the faces' vertices, face after face, counter-clockwise

  std::size_t n_vertices() const { return vertices.size() / 3; }
  std::size_t n_faces() const { return face_counts.size(); }
};

/// The torus of torus(nu, nv) as nu x nv quads: every vertex of valence 4.
PolyMesh quad_torus(int nu, int nv);

/// The patch of grid(nu, nv) as (nu - 1) x (nv - 1) quads: boundary vertices of
/// valence 3, four one-face corners of valence 2.
PolyMesh quad_grid(int nu, int nv);

/// A closed all-quad mesh with irregular vertices: irregular(n_vertices / 6,
/// seed) with each triangle split into three quads (its centroid joined to
/// its edge midpoints). About n_vertices vertices: the triangle mesh's own
/// (valences 3..12), the edge midpoints (valence 4) and the centroids
/// (valence 3), numbered in the order the faces first reach them.
/// @param n_vertices at least 96
PolyMesh quad_irregular(int n_vertices, std::uint32_t seed = 1);

/// quad_torus(nu, nv) with about 10% of its quads split into two triangles,
/// 7% joined with half of their neighbour into pentagons and 7% joined with
/// their neighbour into hexagons, at random: triangles, quads and n-gons
/// mixed, vertices of valence 3 to 6 (never 2: no two joins are stacked).
/// Deterministic for a given seed.
/// @param nu, nv at least 4
PolyMesh polygon_torus(int nu, int nv, std::uint32_t seed = 1);

}  // namespace sorpia
