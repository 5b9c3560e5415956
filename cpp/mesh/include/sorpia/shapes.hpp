#pragma once
/// @file shapes.hpp
/// Generated triangle and polygon meshes (sorpia::Mesh) for tests, benchmarks and the demo.

#include <cstdint>

#include "sorpia/mesh.hpp"

namespace sorpia {

// The triangle shapes give a Mesh of triangles without counts
// (all_triangles(): face_vertex_indices is the row-major (n_faces, 3) array,
// counter-clockwise seen from outside); the polygon shapes give their counts.

/// Unit sphere: the icosahedron split `level` times (each face into 4), new
/// vertices pushed to the sphere. 10*4^level + 2 vertices; valences 5 (12 of
/// them) and 6. @param level 0..10
Mesh icosphere(int level);

/// Torus with radii 1 and 0.4, an nu x nv grid of vertices, every vertex of
/// valence 6 (the regular case). @param nu, nv at least 3
Mesh torus(int nu, int nv);

/// An open, wavy square patch z = 0.1 sin(2 pi x) cos(2 pi y) on an nu x nv grid
/// of vertices: boundary vertices of valence 3 and 4, two one-face corners of
/// valence 2. @param nu, nv at least 2
Mesh grid(int nu, int nv);

/// A disk with one interior vertex of valence n (a pole) at the centre, two
/// rings of n vertices around it. @param n at least 3
Mesh pole(int n);

/// An irregular closed mesh of about `n_vertices` vertices: a torus whose edges
/// are flipped at random (OpenMesh's flip, keeping valences in 3..12), so that
/// most vertices are extraordinary. Deterministic for a given seed.
Mesh irregular(int n_vertices, std::uint32_t seed = 1);

/// The torus of torus(nu, nv) as nu x nv quads: every vertex of valence 4.
Mesh quad_torus(int nu, int nv);

/// The patch of grid(nu, nv) as (nu - 1) x (nv - 1) quads: boundary vertices of
/// valence 3, four one-face corners of valence 2.
Mesh quad_grid(int nu, int nv);

/// A closed all-quad mesh with irregular vertices: irregular(n_vertices / 6,
/// seed) with each triangle split into three quads (its centroid joined to
/// its edge midpoints). About n_vertices vertices: the triangle mesh's own
/// (valences 3..12), the edge midpoints (valence 4) and the centroids
/// (valence 3), numbered in the order the faces first reach them.
/// @param n_vertices at least 96
Mesh quad_irregular(int n_vertices, std::uint32_t seed = 1);

/// quad_torus(nu, nv) with about 10% of its quads split into two triangles,
/// 7% joined with half of their neighbour into pentagons and 7% joined with
/// their neighbour into hexagons, at random: triangles, quads and n-gons
/// mixed, vertices of valence 3 to 6 (never 2: no two joins are stacked).
/// Deterministic for a given seed.
/// @param nu, nv at least 4
Mesh polygon_torus(int nu, int nv, std::uint32_t seed = 1);

}  // namespace sorpia
