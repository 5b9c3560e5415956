#pragma once
/// @file reference.hpp
/// Reference builds for the tests only (the library sorpia_reference, built
/// with SORPIA_BUILD_TESTS, and the test-only module sorpia._reference): the
/// limit matrix B from OpenSubdiv's own Far::Limit(), the independent
/// computation the production build (sorpia::limit_operator, from Sdc's limit
/// masks and local refinement) is checked against, and the one-ring from
/// OpenMesh's half-edge mesh, which sorpia::Topology's is checked against.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/limit.hpp"
#include "sorpia/mesh.hpp"

namespace sorpia {

/// Reference, for tests: B recorded from OpenSubdiv's
/// Far::PrimvarRefinerReal<double>::Limit on an unrefined Loop
/// Far::TopologyRefiner (the explicit zero weights OpenSubdiv gives interior
/// neighbours of boundary vertices dropped; identity rows for unreferenced
/// vertices). limit_matrix must equal it to rounding. It builds a refiner,
/// which costs several times limit_matrix.
CsrMatrix reference_limit_matrix(const Topology& topology, Boundary boundary);

/// Reference, for tests: B of the whole mesh with its sharpness tags, from
/// one Far::TopologyRefiner of the whole mesh refined uniformly until every
/// semi-sharp tag has decayed (ceil of the largest finite sharpness, after
/// repeated tags are resolved as OpenSubdiv resolves them: the last counts),
/// and for Catmull-Clark at least once when a face is not a quad (Limit() on
/// an unrefined level would treat an n-gon as a quad),
/// PrimvarRefinerReal<double>::Interpolate level by level and Limit() on the
/// last level, composed back to the control vertices (identity rows for
/// unreferenced vertices). limit_matrix(topology, rules) must equal it to
/// rounding. Its cost grows as 4^levels.
/// @throw MeshError naming the first crease that is not an edge of the mesh
CsrMatrix reference_limit_matrix(const Topology& topology, const Rules& rules);

/// Reference, for tests: B V evaluated by Far::PrimvarRefinerReal<double>::Limit (Loop).
void reference_limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out);

/// Reference, for tests: the one-ring of a mesh from OpenMesh's half-edge
/// mesh (TriMesh for triangles, PolyMesh otherwise, add_face per face, then
/// its circulators), in sorpia::Topology's layout: the arrays of the same
/// names there (ring_offsets = offsets, ring_neighbors = neighbors,
/// vertex_face_offsets = face_offsets, vertex_faces = faces,
/// face_ring_offsets, face_ring_neighbors = face_ring; the last four, and
/// quad_ring, empty for a triangle mesh) must equal these.
struct ReferenceOneRing {
  std::vector<std::int32_t> offsets, neighbors, face_count;
  std::vector<std::uint8_t> boundary;
  std::vector<std::int32_t> face_offsets, faces, face_ring_offsets, face_ring;
  std::vector<std::uint8_t> quad_ring;
  std::size_t n_edges = 0, n_boundary_edges = 0, n_unreferenced = 0;
};

/// The faces of `faces` over n_vertices vertices (its coordinates are not
/// read), which sorpia::Topology accepts (OpenMesh aborts on a repeated
/// vertex in a face).
/// @throw MeshError when OpenMesh refuses a face, finds a vertex non-manifold
///        (more than one boundary gap) or circulates round a vertex without
///        passing all its faces (more than one fan)
ReferenceOneRing reference_one_ring(const Mesh& faces, std::size_t n_vertices);

}  // namespace sorpia
