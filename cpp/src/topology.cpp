#include "sorpia/topology.hpp"

#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <limits>
#include <mutex>
#include <string>

#include "openmesh_types.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {
namespace detail {
void silence_openmesh() {
  static std::once_flag once;
  std::call_once(once, [] {
    omlog().disable();
    omout().disable();
    omerr().disable();
  });
}
}  // namespace detail

namespace {

std::string face_str(std::size_t f, const std::int32_t* faces) {
  return "face " + std::to_string(f) + " (" + std::to_string(faces[3 * f]) + ", " +
         std::to_string(faces[3 * f + 1]) + ", " + std::to_string(faces[3 * f + 2]) + ")";
}

// Checks what OpenMesh would not: indices in range and distinct (OpenMesh
// aborts on a repeated vertex), at most two faces per edge and consistent
// orientation (OpenMesh would fail add_face without saying why). Edges are
// bucketed by their smaller vertex (a counting sort: linear time).
// Returns the number of edges and of boundary edges.
std::pair<std::size_t, std::size_t> validate_faces(const std::int32_t* faces, std::size_t n_faces,
                                                   std::size_t n_vertices) {
  if (n_vertices > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw MeshError("too many vertices: " + std::to_string(n_vertices) + " (at most 2^31 - 1)");
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::int32_t* t = faces + 3 * f;
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= n_vertices)
        throw MeshError(face_str(f, faces) + " has vertex index " + std::to_string(t[k]) +
                        " out of range [0, " + std::to_string(n_vertices) + ")");
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw MeshError(face_str(f, faces) + " repeats a vertex (degenerate triangle)");
  }
  std::vector<std::int32_t> start(n_vertices + 1, 0);
  for (std::size_t h = 0; h < 3 * n_faces; ++h) {
    const std::int32_t a = faces[h], b = faces[h - h % 3 + (h % 3 + 1) % 3];
    ++start[std::min(a, b) + 1];
  }
  for (std::size_t v = 0; v < n_vertices; ++v) start[v + 1] += start[v];
  std::vector<std::int32_t> fill(start.begin(), start.end() - 1);
  std::vector<std::int32_t> bucket(3 * n_faces);  // half-edge ids
  for (std::size_t h = 0; h < 3 * n_faces; ++h) {
    const std::int32_t a = faces[h], b = faces[h - h % 3 + (h % 3 + 1) % 3];
    bucket[fill[std::min(a, b)]++] = static_cast<std::int32_t>(h);
  }
  auto head = [&](std::int32_t h) { return faces[h - h % 3 + (h % 3 + 1) % 3]; };
  std::size_t n_edges = 0, n_boundary = 0;
  for (std::size_t v = 0; v < n_vertices; ++v) {
    const std::int32_t lo = start[v], hi = start[v + 1];
    for (std::int32_t i = lo; i < hi; ++i) {
      const std::int32_t hi_ = bucket[i];
      const std::int32_t other = std::max(faces[hi_], head(hi_));
      bool first = true;
      for (std::int32_t j = lo; j < i; ++j)
        if (std::max(faces[bucket[j]], head(bucket[j])) == other) first = false;
      if (!first) continue;
      // the half-edges of edge (v, other)
      std::int32_t users[3] = {-1, -1, -1};
      int count = 0;
      for (std::int32_t j = i; j < hi; ++j) {
        const std::int32_t hj = bucket[j];
        if (std::max(faces[hj], head(hj)) != other) continue;
        if (count < 3) users[count] = hj;
        ++count;
      }
      ++n_edges;
      const std::string edge = "edge (" + std::to_string(v) + ", " + std::to_string(other) + ")";
      if (count > 2)
        throw MeshError("non-manifold " + edge + ": shared by " + std::to_string(count) +
                        " faces (faces " + std::to_string(users[0] / 3) + ", " + std::to_string(users[1] / 3) +
                        ", " + std::to_string(users[2] / 3) + ", ...)");
      if (count == 1) {
        ++n_boundary;
      } else if (faces[users[0]] == faces[users[1]]) {
        const std::int32_t f0 = users[0] / 3, f1 = users[1] / 3;
        std::int32_t s0[3] = {faces[3 * f0], faces[3 * f0 + 1], faces[3 * f0 + 2]};
        std::int32_t s1[3] = {faces[3 * f1], faces[3 * f1 + 1], faces[3 * f1 + 2]};
        std::sort(s0, s0 + 3);
        std::sort(s1, s1 + 3);
        if (std::equal(s0, s0 + 3, s1))
          throw MeshError("duplicate faces: " + face_str(f0, faces) + " and " + face_str(f1, faces) +
                          " have the same vertices");
        throw MeshError("inconsistent orientation at " + edge + ": " + face_str(f0, faces) + " and " +
                        face_str(f1, faces) + " traverse it in the same direction (flip one of them)");
      }
    }
  }
  return {n_edges, n_boundary};
}

}  // namespace

Topology::Topology(const std::int32_t* faces, std::size_t n_faces, std::size_t n_vertices)
    : n_vertices_(n_vertices), faces_(faces, faces + 3 * n_faces) {
  detail::silence_openmesh();
  std::tie(n_edges_, n_boundary_edges_) = validate_faces(faces, n_faces, n_vertices);

  detail::OMesh mesh;
  mesh.reserve(n_vertices, n_edges_, n_faces);
  for (std::size_t v = 0; v < n_vertices; ++v) mesh.add_vertex(detail::OMesh::Point(0, 0, 0));
  face_count_.assign(n_vertices, 0);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::int32_t* t = faces + 3 * f;
    for (int k = 0; k < 3; ++k) ++face_count_[t[k]];
    const auto fh = mesh.add_face(mesh.vertex_handle(t[0]), mesh.vertex_handle(t[1]), mesh.vertex_handle(t[2]));
    if (!fh.is_valid())
      throw MeshError(face_str(f, faces) +
                      " makes a non-manifold vertex (two fans of faces meet at one vertex, a 'bowtie')");
  }

  // Flatten the half-edge structure into a CSR one-ring.
  ring_offsets_.assign(n_vertices + 1, 0);
  boundary_.assign(n_vertices, 0);
  ring_neighbors_.reserve(2 * n_edges_);
  for (std::size_t v = 0; v < n_vertices; ++v) {
    const auto vh = mesh.vertex_handle(static_cast<int>(v));
    ring_offsets_[v] = static_cast<std::int32_t>(ring_neighbors_.size());
    if (face_count_[v] == 0) {
      ++n_unreferenced_;
      continue;
    }
    // A boundary vertex's outgoing half-edge is its boundary half-edge: start
    // there so the ring runs from one boundary neighbour to the other.
    const auto h0 = mesh.halfedge_handle(vh);
    const bool on_boundary = mesh.is_boundary(h0);
    boundary_[v] = on_boundary;
    int faces_seen = 0;
    auto h = h0;
    do {
      ring_neighbors_.push_back(mesh.to_vertex_handle(h).idx());
      if (!mesh.is_boundary(h)) ++faces_seen;
      h = mesh.next_halfedge_handle(mesh.opposite_halfedge_handle(h));  // clockwise
    } while (h != h0);
    if (faces_seen != face_count_[v])
      throw MeshError("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(face_count_[v]) +
                      " faces form more than one fan (a 'bowtie'); split it into one vertex per fan");
  }
  ring_offsets_[n_vertices] = static_cast<std::int32_t>(ring_neighbors_.size());
}

}  // namespace sorpia
