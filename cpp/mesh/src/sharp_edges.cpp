#include "sorpia/sharp_edges.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "openmesh_types.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {

std::vector<std::int32_t> sharp_edges(const double* vertices, std::size_t n_vertices,
                                      const std::int32_t* face_vertex_counts, std::size_t n_faces,
                                      const std::int32_t* face_vertex_indices, double angle_degrees) {
  if (!(angle_degrees >= 0.0 && angle_degrees <= 180.0))
    throw ParameterError("sharp angle " + std::to_string(angle_degrees) + " must be in [0, 180] degrees");
  detail::silence_openmesh();
  detail::OPolyMesh mesh;
  mesh.reserve(n_vertices, 0, n_faces);
  std::vector<detail::OPolyMesh::VertexHandle> handles(n_vertices);
  for (std::size_t i = 0; i < n_vertices; ++i)
    handles[i] = mesh.add_vertex({vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]});
  std::vector<detail::OPolyMesh::VertexHandle> corners;
  std::size_t at = 0;
  for (std::size_t f = 0; f < n_faces; ++f) {
    corners.clear();
    const auto k = static_cast<std::size_t>(std::max(face_vertex_counts[f], 0));
    for (std::size_t c = 0; c < k; ++c) {
      const std::int32_t v = face_vertex_indices[at + c];
      if (v < 0 || static_cast<std::size_t>(v) >= n_vertices)
        throw MeshError("sharp edges: face " + std::to_string(f) + " has vertex index " + std::to_string(v) +
                        " out of range [0, " + std::to_string(n_vertices) + ")");
      corners.push_back(handles[static_cast<std::size_t>(v)]);
    }
    at += k;
    if (!mesh.add_face(corners).is_valid())
      throw MeshError("sharp edges: face " + std::to_string(f) +
                      " cannot join OpenMesh's half-edge mesh (fewer than 3 vertices, a repeated vertex, an edge of "
                      "three or more faces, a bowtie vertex or a face oriented against its neighbours); "
                      "sorpia.repair makes such a mesh valid");
  }
  // Between unit normals, angle > threshold  <=>  atan2(|n0 x n1|, n0 . n1) > threshold.
  const double threshold = angle_degrees * (M_PI / 180.0);
  std::vector<OpenMesh::Vec3d> normals(n_faces);
  for (const auto fh : mesh.faces()) normals[static_cast<std::size_t>(fh.idx())] = mesh.calc_face_normal(fh);
  std::vector<std::pair<std::int32_t, std::int32_t>> sharp;
  for (const auto eh : mesh.edges()) {
    if (mesh.is_boundary(eh)) continue;
    const auto h0 = mesh.halfedge_handle(eh, 0), h1 = mesh.halfedge_handle(eh, 1);
    const auto& n0 = normals[static_cast<std::size_t>(mesh.face_handle(h0).idx())];
    const auto& n1 = normals[static_cast<std::size_t>(mesh.face_handle(h1).idx())];
    if (n0.sqrnorm() == 0.0 || n1.sqrnorm() == 0.0) continue;  // a face of zero area has no normal
    if (std::atan2(OpenMesh::cross(n0, n1).norm(), OpenMesh::dot(n0, n1)) <= threshold) continue;
    const int a = mesh.from_vertex_handle(h0).idx(), b = mesh.to_vertex_handle(h0).idx();
    sharp.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(sharp.begin(), sharp.end());
  std::vector<std::int32_t> out;
  out.reserve(2 * sharp.size());
  for (const auto& [a, b] : sharp) out.insert(out.end(), {a, b});
  return out;
}

}  // namespace sorpia
