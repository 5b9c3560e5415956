#pragma once
/// @file repair.hpp
/// Repair of a triangle or polygon list that sorpia::Topology refuses: the
/// fewest changes to the faces (no vertex moves) that make it a consistently
/// oriented manifold surface.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace sorpia {

/// Every change sorpia::repair made, in the input's indices.
struct RepairReport {
  /// Faces with a repeated vertex that are no polygon without their
  /// consecutive repeats (every degenerate triangle), removed.
  std::vector<std::int32_t> degenerate_faces;
  /// Polygons with a repeated vertex that are a polygon of three or more
  /// distinct vertices once their consecutive repeats (cyclically) are
  /// dropped: kept with those corners dropped.
  std::vector<std::int32_t> collapsed_faces;
  /// Faces with the same vertices in the same cyclic order as an earlier
  /// face, removed (the first of the equal faces is kept).
  std::vector<std::int32_t> duplicate_faces;
  /// Faces with the same vertices as an earlier face in the opposite cyclic
  /// order, removed (the first is kept).
  std::vector<std::int32_t> reversed_duplicate_faces;
  /// Edges (lower, higher vertex) of three or more faces (after removing the
  /// duplicates), whose sheets were separated.
  std::vector<std::array<std::int32_t, 2>> nonmanifold_edges;
  /// Vertices split to separate the sheets of a non-manifold edge (an end of
  /// such an edge), and the number of copies each got.
  std::vector<std::int32_t> sheet_vertices, sheet_copies;
  /// Vertices where fans of faces met at a point only ('bowties'), split into
  /// one vertex per fan, and the number of copies each got.
  std::vector<std::int32_t> bowtie_vertices, bowtie_copies;
  /// Faces whose vertex order was reversed to orient their component consistently.
  std::vector<std::int32_t> flipped_faces;

  /// True when repair changed nothing (the input was a valid mesh).
  bool empty() const;
};

/// The repaired mesh as indices: output vertex i copies input vertex
/// vertex_map[i]; output face j is input face face_map[j], its vertex indices
/// renumbered (and reversed if it was flipped: first corner kept, the others
/// in the opposite order), without the corners dropped from a collapsed face.
struct RepairResult {
  std::vector<std::int32_t> faces;        ///< the vertices of every face, face after face
  std::vector<std::int32_t> face_counts;  ///< polygons: the vertex count of each face; empty for triangles
  std::vector<std::int32_t> vertex_map;  ///< n_vertices + the copies; vertex_map[i] = i for i < n_vertices
  std::vector<std::int32_t> face_map;    ///< one entry per output face
  RepairReport report;
};

/// Makes `faces` a valid sorpia::Topology, changing only what must change:
///
/// 1. a face with a repeated vertex loses its consecutive repeats (cyclically:
///    (a, b, b, c) and (a, b, c, a) become (a, b, c)) when what is left is a
///    polygon of three or more distinct vertices; otherwise (every triangle
///    with a repeat, (a, b, a, c)) it is removed;
/// 2. of faces with the same vertices in the same cyclic sequence (either
///    way round) the first is kept, the others removed;
/// 3. at an edge of three or more faces, the faces are paired into sheets in
///    face order: the lowest-numbered unpaired face with the next unpaired
///    face that runs the edge the other way (else with the next unpaired face);
///    a face left over borders the edge alone. Every other edge joins its one
///    or two faces;
/// 4. each vertex gets one copy per fan of faces joined by those edges (a
///    bowtie vertex one per fan, the ends of a non-manifold edge one per
///    sheet): the fan holding the vertex's first corner in face order keeps
///    the input index, every other fan gets a new vertex appended after the
///    input ones, numbered in the order of the fans' first corners;
/// 5. each connected component is oriented consistently: the faces of the
///    smaller of its two orientation classes are reversed (on a tie, those
///    disagreeing with the component's lowest-numbered face). A face is
///    reversed keeping its first corner: (a, b, c, d) becomes (a, d, c, b).
///
/// No vertex is moved or dropped (vertices used only by removed faces, and
/// unreferenced ones, stay as unreferenced vertices). A valid input costs
/// sorpia::faces_valid alone and comes back with an empty report and empty
/// arrays: the input is the result, nothing is copied. Repair is idempotent:
/// its output is valid.
///
/// @param faces       row-major (n_faces, 3) vertex indices in [0, n_vertices)
/// @throw MeshError   a component that has no consistent orientation (a
///                    Moebius strip), named by its lowest face and its size;
///                    faces that all repeat a vertex; or
///                    a problem repair does not change (an index out of range,
///                    no faces, a vertex of more edges than OpenSubdiv takes),
///                    with sorpia::Topology's message
RepairResult repair(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices);

/// The same rules for polygons in the counts + indices form of sorpia::Topology
/// (face f has face_vertex_counts[f] >= 3 vertices, listed in
/// face_vertex_indices after those of the faces before it). The result's faces
/// are polygons with their face_counts (a collapsed face has fewer vertices
/// than its input face); the same errors, and a face of fewer than three
/// vertices is refused as the validation refuses it.
RepairResult repair(const std::int32_t* face_vertex_counts, std::size_t n_faces, const std::int32_t* face_vertex_indices,
                    std::size_t n_vertices);

}  // namespace sorpia
