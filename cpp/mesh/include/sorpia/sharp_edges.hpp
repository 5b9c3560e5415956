#pragma once
/// @file sharp_edges.hpp
/// The edges of a polygon mesh whose faces meet at more than a given angle:
/// the infinitely sharp creases a CAD part's feature lines become.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace sorpia {

/// Every interior edge whose two faces' normals are more than
/// `angle_degrees` apart, on OpenMesh's half-edge mesh (PolyMesh with double
/// points). A face's normal is OpenMesh's calc_face_normal (Newell's method:
/// the cross product for a triangle, the area-weighted normal of a non-planar
/// polygon); the angle between unit normals n0, n1 is
/// atan2(|n0 x n1|, n0 . n1), 0 for coplanar faces and 180 for a fold back.
/// Boundary edges and edges beside a face of zero area are never sharp.
/// @param vertices            (n_vertices, 3)
/// @param face_vertex_counts  (n_faces,) corners per face
/// @param face_vertex_indices every face's corners, face after face
/// @param angle_degrees       in [0, 180]
/// @return (k, 2) row-major edges (a < b), sorted
/// @throw ParameterError for an angle outside [0, 180] or NaN; MeshError
///        naming the first face OpenMesh cannot add (an edge of three faces,
///        a bowtie vertex, inconsistent orientation)
std::vector<std::int32_t> sharp_edges(const double* vertices, std::size_t n_vertices,
                                      const std::int32_t* face_vertex_counts, std::size_t n_faces,
                                      const std::int32_t* face_vertex_indices, double angle_degrees);

}  // namespace sorpia
