#pragma once
/// @file mesh.hpp
/// sorpia::Mesh, the one mesh container of the C++ core: what the shapes
/// make, the readers return (MeshFile adds the file's tags and attributes)
/// and tessellation gives.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace sorpia {

/// A polygon mesh: vertices and faces in the counts + indices form of
/// OpenSubdiv's Far::TopologyDescriptor (numVertsPerFace, vertIndicesPerFace)
/// and USD (faceVertexCounts, faceVertexIndices). The fast path for triangle
/// (and all-quad) meshes: when every face has the same number of corners,
/// `face_vertex_counts` may stay empty and `face_size` holds that number, so
/// such a mesh costs nothing beyond its index list.
struct Mesh {
  std::vector<double> vertices;                   ///< (n_vertices, 3), row-major
  std::vector<std::int32_t> face_vertex_counts;   ///< corners per face; empty when every face has `face_size`
  std::vector<std::int32_t> face_vertex_indices;  ///< every face's corners, face after face, counter-clockwise
  std::int32_t face_size = 3;                     ///< the corners of every face when face_vertex_counts is empty

  std::size_t n_vertices() const { return vertices.size() / 3; }
  std::size_t n_faces() const {
    return uniform() ? face_vertex_indices.size() / static_cast<std::size_t>(face_size) : face_vertex_counts.size();
  }
  /// Every face has `face_size` corners (face_vertex_counts is empty).
  bool uniform() const { return face_vertex_counts.empty(); }
  /// Every face is a triangle given without counts (face_vertex_indices is the row-major (n_faces, 3) array).
  bool all_triangles() const { return uniform() && face_size == 3; }
  /// The corners of every face (a new array: `face_size` repeated for a uniform mesh).
  std::vector<std::int32_t> counts() const {
    return uniform() ? std::vector<std::int32_t>(n_faces(), face_size) : face_vertex_counts;
  }
};

}  // namespace sorpia
