#pragma once
/// @file repair.hpp
/// Repair of a triangle or polygon list that sorpia::Topology refuses: the
/// fewest changes to the faces (no vertex moves) that make it a consistently
/// oriented manifold surface.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/mesh.hpp"

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
  /// order, removed (the first is kept), except where the two are a pillow
  /// (rule 2).
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
  /// Edges of three or more faces (among nonmanifold_edges) where a pair of
  /// faces was left unpaired, each face bordering the edge alone, because
  /// the pair would have joined a part that no orientation fits (rule 4).
  std::vector<std::array<std::int32_t, 2>> cut_nonmanifold_edges;
  /// Edges of two faces cut apart, each face bordering the edge alone, so
  /// that a part with no consistent orientation (a Moebius strip) can be
  /// oriented (rule 4).
  std::vector<std::array<std::int32_t, 2>> cut_edges;
  /// Vertices split by the cut of cut_edges (an end of such an edge that is
  /// no end of a non-manifold edge), and the number of copies each got.
  std::vector<std::int32_t> cut_vertices, cut_copies;
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
  /// The repaired faces, without coordinates (faces.vertices is empty), over
  /// vertex_map.size() vertices: a triangle list given without counts
  /// (Mesh::all_triangles) comes back so, any other mesh with its
  /// face_vertex_counts (a collapsed face has fewer corners than its input
  /// face). Empty for a valid input.
  Mesh faces;
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
///    way round) the first is kept, the others removed, except a pair in
///    the opposite order with no other face on their edges (a closed
///    'pillow' of two faces, valid), which is kept;
/// 3. at an edge of three or more faces, the faces are paired into sheets in
///    face order: the lowest-numbered unpaired face with the next unpaired
///    face that runs the edge the other way (else with the next unpaired face);
///    a face left over borders the edge alone. Every other edge joins its one
///    or two faces;
/// 4. the joins no orientation of the faces keeps are broken, each face then
///    bordering the edge alone. First, per part of faces joined by edges of
///    two faces, a breadth-first search orients the faces it reaches; where
///    a join disagrees (a twist: a Moebius strip, a Klein bottle), a search
///    from the face farthest from the part's boundary (the lowest of those;
///    the part's lowest face where it has no boundary) cuts each join that
///    disagrees, across a band where its two fronts meet ("cut_edges");
///    then the pairs of rule 3, in face order, join the parts
///    they connect, and a pair that would join two faces already oriented
///    against it is left unpaired ("cut_nonmanifold_edges"). Where every
///    part can be oriented with its pairs (as whenever the pairs run their
///    edges both ways) nothing is cut. The joins broken disagree with one
///    orientation of the whole, and every fan round a vertex holds an even
///    number of them or is open, so that rule 5 separates the two faces of
///    each at both ends of its edge;
/// 5. each vertex gets one copy per fan of faces joined by those edges (a
///    bowtie vertex one per fan, the ends of a non-manifold edge one per
///    sheet, the ends of a cut edge one per side): the fan holding the
///    vertex's first corner in face order keeps the input index, every other
///    fan gets a new vertex appended after the input ones, numbered in the
///    order of the fans' first corners;
/// 6. each connected component is oriented consistently: the faces of the
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
/// @param faces       the faces of a sorpia::Mesh (triangles or polygons, as
///                    Topology takes them; faces.vertices is not read) over
///                    n_vertices vertices
/// @throw MeshError   faces that all repeat a vertex; or
///                    a problem repair does not change (an index out of range,
///                    no faces, a vertex of more edges than OpenSubdiv takes,
///                    counts that do not add up to the indices), with
///                    sorpia::Topology's message. A polygon of fewer than
///                    three vertices is refused as the validation refuses it.
RepairResult repair(const Mesh& faces, std::size_t n_vertices);

/// For nonmanifold="sharp": the mesh kept as it is, but cut apart where
/// OpenSubdiv sees non-manifold topology, so that OpenSubdiv's own rules for
/// it become tags of a manifold mesh. OpenSubdiv (Far's
/// TopologyRefinerFactory, Vtr::Level) makes an edge non-manifold when three
/// or more faces use it or its two faces run it the same way, and makes it
/// infinitely sharp; a vertex is non-manifold on such an edge or where its
/// faces form several fans, and becomes an infinitely sharp corner, except on
/// an interior non-manifold crease (exactly two non-manifold edges, no
/// boundary edge, more faces than edges), where the two edges make it a
/// crease vertex.
///
/// The split joins only the two faces of an edge that run it opposite ways;
/// every other edge borders each of its faces alone, so that a non-manifold
/// edge becomes one boundary edge (infinitely sharp, as OpenSubdiv makes it)
/// per face, and each vertex gets one output vertex per fan (the first fan in
/// face order keeps the input index, copies are appended). Faces are neither
/// removed nor reversed. Where two faces of a non-manifold edge that run it
/// opposite ways lie in one fan at both its ends (a pillow beside a third
/// face), the split mesh has them as the two faces of one edge again: those
/// edges are `sharp_edges`. On the split mesh with an infinitely sharp corner
/// tag on every copy of each vertex in `corners` and an infinitely sharp
/// crease on each of sharp_edges, OpenSubdiv's refinement makes the points
/// of its refinement of the input mesh, and every vertex's limit row is
/// OpenSubdiv's row on the input mesh, its columns mapped through vertex_map;
/// a crease vertex's copies each lie on the boundary between the copies of
/// its two non-manifold edges, whose boundary rule is the crease rule, except
/// a copy in a fan of one face (`single_face_sheets`), which the
/// edge-and-corner boundary rule makes a corner (sorpia.nonmanifold.split
/// then solves the split under edge-only, with the corners edge-and-corner
/// makes, every other vertex of one face, as tags: OpenSubdiv's rows).
struct NonmanifoldSplit {
  /// The faces, their vertices renumbered, without coordinates (faces.vertices
  /// is empty), over vertex_map.size() vertices: counts as the input had
  /// them (none for Mesh::all_triangles).
  Mesh faces;
  std::vector<std::int32_t> vertex_map;   ///< for every output vertex, the input vertex it copies
  /// The non-manifold edges (lower, higher input vertex), OpenSubdiv's infinitely sharp ones.
  std::vector<std::array<std::int32_t, 2>> nonmanifold_edges;
  /// The non-manifold input vertices, and those of them that are corners.
  std::vector<std::int32_t> nonmanifold_vertices, corners;
  /// Crease vertices with a copy in a fan of one face.
  std::vector<std::int32_t> single_face_sheets;
  /// Edges of the split (lower, higher output vertex) whose two faces border
  /// a non-manifold input edge: to be tagged infinitely sharp creases.
  std::vector<std::array<std::int32_t, 2>> sharp_edges;

  /// True for a manifold mesh (then faces and vertex_map are empty: the input is the split).
  bool empty() const { return nonmanifold_vertices.empty(); }
};

/// The split of `faces` (the faces of a sorpia::Mesh, triangles or polygons
/// as Topology takes them, over n_vertices vertices; faces.vertices is not
/// read) described at NonmanifoldSplit.
/// @throw MeshError  a face that repeats a vertex (OpenSubdiv would give it a
///                   degenerate edge, which no sorpia mesh has); a crease
///                   vertex some fan of which is not bounded by its two
///                   non-manifold edges (the split would not reproduce its
///                   crease rule); a problem of the indices, as Topology says it
NonmanifoldSplit split_nonmanifold(const Mesh& faces, std::size_t n_vertices);

}  // namespace sorpia
