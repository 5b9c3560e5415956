#pragma once
/// @file topology.hpp
/// Polygon-mesh topology: validation, half-edge connectivity and the flat
/// one-ring structure the limit operator and the solvers run over.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "sorpia/mesh.hpp"
#include "sorpia/subdivision.hpp"

namespace sorpia {

/// Whether Topology(faces, n_vertices) accepts these faces (faces.vertices is
/// not read), found by its checks without building the one-ring or naming
/// the problem.
bool faces_valid(const Mesh& faces, std::size_t n_vertices);

/// Connectivity of a polygon mesh (triangles, quads, any n-gons), built once
/// and shared by the limit operator, the solvers and surface evaluation.
///
/// It is built from a sorpia::Mesh, whose faces are given as OpenSubdiv's
/// Far::TopologyDescriptor and USD take them: face f has face_counts()[f]
/// vertices, face_indices()[face_offsets()[f] .. face_offsets()[f + 1]),
/// counter-clockwise seen from outside.
///
/// The constructor validates the faces (indices in range, at least three
/// vertices and no repeated vertex in a face, every edge shared by at most two
/// faces, consistent orientation, manifold vertices) and throws
/// sorpia::MeshError naming the first offending face, edge or vertex. The
/// half-edges are then matched into a flat CSR one-ring in linear time,
/// straight from the face array, so that no circulator runs in an inner loop
/// (the tests compare it with OpenMesh's half-edge one-ring, a reference
/// that tests/reference builds).
///
/// Edge neighbours (ring_*) exist for every mesh. The face neighbours
/// (vertex_faces, face_ring_*), which only Catmull-Clark needs, are built when
/// some face is not a triangle (has_face_ring()); an all-triangle mesh builds
/// exactly what Loop reads and nothing more.
class Topology {
 public:
  /// The faces of `mesh` over its mesh.n_vertices() vertices (some may be
  /// unreferenced; the coordinates are not read). A triangle mesh given
  /// without counts (Mesh::all_triangles) takes the fast path that stores no
  /// counts or offsets; counts that are all 3, or a uniform `face_size` of 3,
  /// give the same Topology.
  /// @throw MeshError for faces of fewer than three corners, counts that do
  ///        not add up to the indices given, and everything listed above
  explicit Topology(const Mesh& mesh);
  /// Faces without coordinates: those of `faces` over `n_vertices` vertices
  /// (faces.vertices is not read and may be empty). Its face arrays are taken
  /// over when it is passed as an rvalue.
  Topology(Mesh faces, std::size_t n_vertices);

  std::size_t n_vertices() const { return n_vertices_; }
  std::size_t n_faces() const { return n_faces_; }
  /// Number of vertices of face f.
  std::int32_t face_size(std::size_t f) const {
    return all_triangles_ ? 3 : face_offsets_[f + 1] - face_offsets_[f];
  }
  /// Where face f's vertices start in face_indices().
  std::int32_t face_offset(std::size_t f) const {
    return all_triangles_ ? static_cast<std::int32_t>(3 * f) : face_offsets_[f];
  }
  /// The vertices of every face, face after face, as given.
  const std::vector<std::int32_t>& face_indices() const { return face_indices_; }
  /// Number of vertices of each face (a new array: a triangle mesh stores none).
  std::vector<std::int32_t> face_counts() const;
  /// n_faces + 1 entries, face f's vertices start at face_indices()[face_offsets()[f]]
  /// (a new array: a triangle mesh stores none).
  std::vector<std::int32_t> face_offsets() const;
  /// Every face is a triangle (face_indices() is then the row-major (n_faces, 3) array).
  bool all_triangles() const { return all_triangles_; }
  /// Every face is a quad.
  bool all_quads() const { return all_quads_; }
  /// Row-major (n_faces, 3) triangles, as given; only for all_triangles() meshes.
  /// @throw std::logic_error on a mesh with other polygons
  const std::vector<std::int32_t>& faces() const;

  /// One-ring CSR: the edge neighbours of vertex i are
  /// ring_neighbors()[ring_offsets()[i] .. ring_offsets()[i+1]).
  /// Clockwise (seen from the side the faces are counter-clockwise): for a
  /// boundary vertex the first and the last neighbour are the two neighbours
  /// along the boundary; an interior vertex starts at the second corner of the
  /// lowest-numbered face around it.
  const std::vector<std::int32_t>& ring_offsets() const { return ring_offsets_; }
  const std::vector<std::int32_t>& ring_neighbors() const { return ring_neighbors_; }

  /// Whether the face neighbours below were built (some face is not a triangle).
  bool has_face_ring() const { return !vertex_face_offsets_.empty(); }
  /// The faces at vertex i in ring order, vertex_faces()[vertex_face_offsets()[i]
  /// .. vertex_face_offsets()[i+1]) (face_count(i) of them): the j-th lies
  /// between edge neighbours j and j+1 of the ring (j+1 taken cyclically for an
  /// interior vertex). Empty unless has_face_ring().
  const std::vector<std::int32_t>& vertex_face_offsets() const { return vertex_face_offsets_; }
  const std::vector<std::int32_t>& vertex_faces() const { return vertex_faces_; }
  /// The face neighbours of vertex i: for each of its faces in ring order, the
  /// face's vertices other than i and the two edge neighbours it lies between,
  /// in the face's (counter-clockwise) order: none for a triangle, the
  /// opposite corner of a quad, n - 3 vertices for an n-gon.
  /// face_ring_neighbors()[face_ring_offsets()[i] .. face_ring_offsets()[i+1]).
  /// Empty unless has_face_ring().
  const std::vector<std::int32_t>& face_ring_offsets() const { return face_ring_offsets_; }
  const std::vector<std::int32_t>& face_ring_neighbors() const { return face_ring_neighbors_; }
  /// Every face at vertex i is a quad (its face neighbours are then one
  /// opposite corner per face). False for a triangle mesh and an unreferenced vertex.
  bool quad_ring(std::size_t i) const { return has_face_ring() && quad_ring_[i] != 0; }

  /// Number of edges at vertex i.
  int valence(std::size_t i) const { return ring_offsets_[i + 1] - ring_offsets_[i]; }
  /// Number of faces at vertex i (valence - 1 on the boundary, valence inside).
  int face_count(std::size_t i) const { return face_count_[i]; }
  bool is_boundary(std::size_t i) const { return boundary_[i] != 0; }
  /// A vertex no face references: its limit is itself.
  bool is_unreferenced(std::size_t i) const { return ring_offsets_[i + 1] == ring_offsets_[i]; }

  /// The half-edge across each half-edge. Half-edge h = face_offset(f) + i
  /// runs from corner i of face f to corner i + 1 (face_indices()[h] to the
  /// face's next corner); half_edge_twins()[h] is the half-edge of the other
  /// face on that edge (which runs the other way), or -1 on the boundary.
  /// Computed by detail::EdgeGroups (half_edges.hpp), the matcher the face
  /// checks' messages, repair and the statistics use, on the first call (the
  /// build matches edges per vertex and stores no half-edges) and kept: later
  /// calls, from any thread, return the same array (a copy of the Topology
  /// shares it), valid while this Topology lives and is not assigned to.
  const std::vector<std::int32_t>& half_edge_twins() const;
  /// For each of k vertex pairs (pairs[2i], pairs[2i + 1]), either order, the
  /// lower-numbered half-edge of the edge between them (numbered as in
  /// half_edge_twins), or -1 where they share no edge. Computed on each call
  /// (detail::EdgeGroups).
  std::vector<std::int32_t> find_half_edges(const std::int32_t* pairs, std::size_t k) const;

  std::size_t n_edges() const { return n_edges_; }
  std::size_t n_boundary_edges() const { return n_boundary_edges_; }
  std::size_t n_unreferenced() const { return n_unreferenced_; }

 private:
  // The faces' checks of form and their arrays (taken over), then build().
  void init(Mesh faces);
  void build();

  std::size_t n_vertices_ = 0;
  std::size_t n_faces_ = 0;
  std::vector<std::int32_t> face_indices_;
  std::vector<std::int32_t> face_offsets_;  // n_faces + 1, or empty when all_triangles_
  bool all_triangles_ = true;
  bool all_quads_ = false;
  std::vector<std::int32_t> ring_offsets_;
  std::vector<std::int32_t> ring_neighbors_;
  std::vector<std::int32_t> face_count_;
  std::vector<std::uint8_t> boundary_;
  std::vector<std::int32_t> vertex_face_offsets_;
  std::vector<std::int32_t> vertex_faces_;
  std::vector<std::int32_t> face_ring_offsets_;
  std::vector<std::int32_t> face_ring_neighbors_;
  std::vector<std::uint8_t> quad_ring_;
  std::size_t n_edges_ = 0;
  std::size_t n_boundary_edges_ = 0;
  std::size_t n_unreferenced_ = 0;
  // half_edge_twins(), made once on first use; shared by copies (their faces are the same).
  struct Twins {
    std::once_flag made;
    std::vector<std::int32_t> twins;
  };
  mutable std::shared_ptr<Twins> twins_ = std::make_shared<Twins>();
};

}  // namespace sorpia
