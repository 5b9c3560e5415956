#pragma once
// The flat one-ring of a validated polygon mesh (internal; see topology.hpp).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace sorpia::detail {

// Corner of a face (v, a, ..., b) at v, counter-clockwise: `next` = a, `prev` = b.
// Going clockwise round v, the ring passes b and then a: the step from
// neighbour x is to the `next` of the corner whose `prev` is x.
struct Corner {
  std::int32_t next;
  std::int32_t prev;
};

// The corners of a triangle list bucketed by vertex (a counting sort, linear
// time), in face order within a bucket: vertex v's corners are
// corners[start[v] .. start[v + 1]). Used by validate_faces (topology.cpp).
// `faces` must hold indices in [0, n_vertices).
struct CornerBuckets {
  std::vector<std::int32_t> start;     // n_vertices + 1
  std::unique_ptr<Corner[]> corners;   // one per corner of every face
  std::unique_ptr<std::int32_t[]> ids; // polygons only: the index of each corner in the face list
};
CornerBuckets bucket_corners(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices);
// The same for polygons: face f is indices[offsets[f] .. offsets[f + 1]); also fills `ids`.
CornerBuckets bucket_polygon_corners(const std::int32_t* indices, const std::int32_t* offsets, std::size_t n_faces,
                                     std::size_t n_vertices);

// Throws the MeshError of a vertex whose `n_faces` faces form more than one
// fan (the OpenMesh build finds it while circulating).
[[noreturn]] void refuse_second_fan(std::size_t v, int n_faces);

// What sorpia::Topology keeps of the half-edge structure: per vertex its
// neighbours in clockwise order (a boundary vertex from one boundary neighbour
// to the other; an interior vertex starting at the second corner of the
// lowest-numbered face around it), its number of faces and whether it is on
// the boundary.
// For polygon meshes also the faces round each vertex in ring order and their
// other vertices (Topology::vertex_faces, face_ring_neighbors).
struct OneRing {
  std::vector<std::int32_t> offsets;    // n_vertices + 1
  std::vector<std::int32_t> neighbors;  // 2 n_edges
  std::vector<std::int32_t> face_count;
  std::vector<std::uint8_t> boundary;
  std::size_t n_unreferenced = 0;
  // polygons only (empty for triangles)
  std::vector<std::int32_t> face_offsets;        // n_vertices + 1
  std::vector<std::int32_t> faces;               // sum of face_count
  std::vector<std::int32_t> face_ring_offsets;   // n_vertices + 1
  std::vector<std::int32_t> face_ring;           // the faces' other vertices
  std::vector<std::uint8_t> quad_ring;           // every face at the vertex is a quad
};

}  // namespace sorpia::detail
