#pragma once
/// @file topology.hpp
/// Triangle-mesh topology: validation, half-edge connectivity (OpenMesh) and
/// the flat one-ring structure the limit operator and the solvers run over.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sorpia/subdivision.hpp"

namespace sorpia {

/// How sorpia::Topology turns the validated faces into its one-ring. Both give
/// the same arrays (tests/cpp/test_fast_operator.cpp checks it).
enum class TopologyBuild {
  /// Linear-time half-edge matching on the face array (the default): faster
  /// than OpenMesh's add_face, and no half-edge mesh in memory.
  Direct,
  /// OpenMesh's TriMesh: add_face per face, then circulators (the reference).
  OpenMesh,
};

/// Whether the sorpia::Topology constructor accepts these faces, found by its
/// checks without building the one-ring or naming the problem.
bool faces_valid(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices);

/// Connectivity of a triangle mesh, built once and shared by the limit
/// operator, the solvers and surface evaluation.
///
/// The constructor validates the faces (indices in range, no repeated vertex in
/// a face, every edge shared by at most two faces, consistent orientation,
/// manifold vertices) and throws sorpia::MeshError naming the first offending
/// face, edge or vertex. The half-edges are then matched into a flat CSR
/// one-ring (directly from the faces by default, or through OpenMesh), so that
/// no circulator runs in an inner loop.
class Topology {
 public:
  /// @param faces       row-major (n_faces, 3) vertex indices
  /// @param n_faces     number of triangles
  /// @param n_vertices  number of vertices (some may be unreferenced)
  Topology(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices);
  /// As above, choosing how the one-ring is built (see TopologyBuild).
  Topology(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices, TopologyBuild build);

  std::size_t n_vertices() const { return n_vertices_; }
  std::size_t n_faces() const { return faces_.size() / 3; }
  /// Row-major (n_faces, 3) vertex indices, as given.
  const std::vector<std::int32_t>& faces() const { return faces_; }

  /// One-ring CSR: the neighbours of vertex i are
  /// ring_neighbors()[ring_offsets()[i] .. ring_offsets()[i+1]).
  /// Clockwise (seen from the side the faces are counter-clockwise): for a
  /// boundary vertex the first and the last neighbour are the two neighbours
  /// along the boundary; an interior vertex starts at the second corner of the
  /// lowest-numbered face around it.
  const std::vector<std::int32_t>& ring_offsets() const { return ring_offsets_; }
  const std::vector<std::int32_t>& ring_neighbors() const { return ring_neighbors_; }

  /// Number of edges at vertex i.
  int valence(std::size_t i) const { return ring_offsets_[i + 1] - ring_offsets_[i]; }
  /// Number of faces at vertex i (valence - 1 on the boundary, valence inside).
  int face_count(std::size_t i) const { return face_count_[i]; }
  bool is_boundary(std::size_t i) const { return boundary_[i] != 0; }
  /// A vertex no face references: its limit is itself.
  bool is_unreferenced(std::size_t i) const { return ring_offsets_[i + 1] == ring_offsets_[i]; }

  std::size_t n_edges() const { return n_edges_; }
  std::size_t n_boundary_edges() const { return n_boundary_edges_; }
  std::size_t n_unreferenced() const { return n_unreferenced_; }

 private:
  std::size_t n_vertices_ = 0;
  std::vector<std::int32_t> faces_;
  std::vector<std::int32_t> ring_offsets_;
  std::vector<std::int32_t> ring_neighbors_;
  std::vector<std::int32_t> face_count_;
  std::vector<std::uint8_t> boundary_;
  std::size_t n_edges_ = 0;
  std::size_t n_boundary_edges_ = 0;
  std::size_t n_unreferenced_ = 0;
};

}  // namespace sorpia
