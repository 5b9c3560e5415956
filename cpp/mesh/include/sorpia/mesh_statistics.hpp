#pragma once
/// @file mesh_statistics.hpp
/// Counts that describe a mesh (the paper's Table 2 and more): edges,
/// boundary loops, components, Euler characteristic, genus, valences and the
/// extraordinary vertices.
///
/// Two sources, one counting: a validated sorpia::Topology (its one-ring is
/// the edge list, nothing is rebuilt), or a raw face list that may fail
/// validation (its edges found by sorting the half-edges), so that a mesh
/// Loop PIA refuses can still be described.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// A vertex is regular for Loop subdivision with 6 edges inside the mesh and 4
/// on its boundary; any other valence makes it extraordinary (paper section 2).
constexpr int regular_interior_valence = 6;
constexpr int regular_boundary_valence = 4;

/// The valences of a regular vertex, inside the mesh and on its boundary:
/// Loop 6 and 4, Catmull-Clark 4 and 3 (the valences of a regular quad grid).
struct RegularValence {
  int interior, boundary;
};
RegularValence regular_valence(Scheme scheme);

/// An extraordinary vertex: its index, valence and whether it is on the boundary.
struct ExtraordinaryVertex {
  std::int32_t vertex;
  std::int32_t valence;
  bool boundary;
};

struct MeshStatistics {
  std::size_t n_vertices = 0;
  std::size_t n_faces = 0;
  std::size_t n_edges = 0;           ///< undirected edges (a face's repeated vertex makes none)
  std::size_t n_boundary_edges = 0;  ///< edges of exactly one face
  /// Closed chains of boundary edges. Two loops that touch at a vertex (a
  /// "bowtie") count as two: at such a vertex each boundary edge coming in is
  /// followed by the one going out of the same fan of faces. Where the fans
  /// cannot be told apart (edges of three faces, flipped faces), the connected
  /// pieces of the boundary edges are counted instead.
  std::size_t n_boundary_loops = 0;
  std::size_t n_components = 0;      ///< connected pieces of the referenced vertices
  std::size_t n_unreferenced = 0;    ///< vertices no face references
  std::int64_t euler_characteristic = 0;  ///< V - E + F over the referenced vertices
  /// Sum over components of (2 - chi_c - b_c) / 2; known for a validated mesh
  /// (a Topology) only: a surface that is not an oriented manifold has none.
  std::optional<std::int64_t> genus;
  int valence_min = 0;  ///< over referenced vertices
  int valence_max = 0;
  /// [k]: referenced vertices of valence k off the boundary (interior) and on it.
  std::vector<std::size_t> interior_valences;
  std::vector<std::size_t> boundary_valences;
  /// In increasing vertex order: a valence other than the scheme's regular
  /// one (regular_valence), inside or on the boundary.
  std::vector<ExtraordinaryVertex> extraordinary;
};

/// The statistics of a validated mesh (any polygons), from its one-ring, in
/// O(n_vertices + n_edges + n_faces); extraordinary vertices as `scheme` has them.
MeshStatistics mesh_statistics(const Topology& topology, Scheme scheme = Scheme::Loop);

/// The statistics of a raw triangle list that may fail sorpia's validation
/// (non-manifold edges or vertices, flipped faces, duplicates, repeated
/// vertices in a face); genus stays unknown. `faces` is a triangle list
/// (Mesh::all_triangles) over n_vertices vertices; faces.vertices is not read.
/// std::nullopt when there is no face or an index is outside [0, n_vertices):
/// there is no edge list to count.
/// @throw MeshError  faces that are not a triangle list given without counts
std::optional<MeshStatistics> face_list_statistics(const Mesh& faces, std::size_t n_vertices);

}  // namespace sorpia
