// The reference one-ring (reference.hpp): OpenMesh's half-edge mesh, built
// face by face with add_face and flattened by its circulators, for the tests.
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

#include "sorpia/errors.hpp"
#include "sorpia/reference.hpp"

namespace sorpia {

namespace {

// TriMesh for triangles, PolyMesh for polygons; flattened by circulating
// clockwise round each vertex, rotated so that an interior ring starts at the
// second corner of the lowest-numbered face around the vertex (where
// sorpia::Topology starts it).
template <class OMesh>
ReferenceOneRing one_ring_openmesh(const Mesh& faces, std::size_t n_vertices, bool polygons) {
  omerr().disable();  // a refused add_face is reported below, by face
  ReferenceOneRing r;
  OMesh mesh;
  for (std::size_t v = 0; v < n_vertices; ++v) mesh.add_vertex(typename OMesh::Point(0, 0, 0));
  r.face_count.assign(n_vertices, 0);
  const std::vector<std::int32_t> counts = faces.counts();
  std::vector<typename OMesh::VertexHandle> handles;
  for (std::size_t f = 0, at = 0; f < counts.size(); at += static_cast<std::size_t>(counts[f]), ++f) {
    handles.clear();
    for (std::size_t h = at; h < at + static_cast<std::size_t>(counts[f]); ++h) {
      ++r.face_count[faces.face_vertex_indices[h]];
      handles.push_back(mesh.vertex_handle(faces.face_vertex_indices[h]));
    }
    if (!mesh.add_face(handles).is_valid())
      throw MeshError("face " + std::to_string(f) + " cannot join OpenMesh's half-edge mesh");
  }
  r.n_edges = mesh.n_edges();
  for (const auto e : mesh.edges()) r.n_boundary_edges += mesh.is_boundary(e);

  r.offsets.assign(n_vertices + 1, 0);
  r.boundary.assign(n_vertices, 0);
  if (polygons) {
    r.face_offsets.assign(n_vertices + 1, 0);
    r.face_ring_offsets.assign(n_vertices + 1, 0);
    r.quad_ring.assign(n_vertices, 0);
  }
  std::vector<std::int32_t> vertex_faces, face_ring_sizes, face_ring;  // of one vertex, in circulation order
  for (std::size_t v = 0; v < n_vertices; ++v) {
    const auto vh = mesh.vertex_handle(static_cast<int>(v));
    r.offsets[v] = static_cast<std::int32_t>(r.neighbors.size());
    if (polygons) {
      r.face_offsets[v] = static_cast<std::int32_t>(r.faces.size());
      r.face_ring_offsets[v] = static_cast<std::int32_t>(r.face_ring.size());
    }
    if (r.face_count[v] == 0) {
      ++r.n_unreferenced;
      continue;
    }
    // OpenMesh joins the fans of a 'bowtie' through their boundary gaps: its
    // own test of more than one gap refuses it.
    if (!mesh.is_manifold(vh))
      throw MeshError("vertex " + std::to_string(v) + ": OpenMesh finds it non-manifold (more than one gap)");
    // A boundary vertex's outgoing half-edge is its boundary half-edge: start
    // there so the ring runs from one boundary neighbour to the other.
    const auto h0 = mesh.halfedge_handle(vh);
    const bool on_boundary = mesh.is_boundary(h0);
    r.boundary[v] = on_boundary;
    int faces_seen = 0, lowest_face = -1;
    std::size_t lowest_at = 0;
    vertex_faces.clear();
    face_ring_sizes.clear();
    face_ring.clear();
    bool quads = true;
    auto h = h0;
    do {
      if (!mesh.is_boundary(h)) {
        ++faces_seen;
        if (lowest_face < 0 || mesh.face_handle(h).idx() < lowest_face) {
          lowest_face = mesh.face_handle(h).idx();
          lowest_at = r.neighbors.size() - static_cast<std::size_t>(r.offsets[v]);
        }
      }
      r.neighbors.push_back(mesh.to_vertex_handle(h).idx());
      const auto across = mesh.opposite_halfedge_handle(h);  // x -> v, in the face after x clockwise
      h = mesh.next_halfedge_handle(across);                  // clockwise
      if (polygons && !mesh.is_boundary(across)) {
        // The face between x and the next neighbour y: its vertices from the
        // one after y to the one before x, counter-clockwise.
        const std::size_t before = face_ring.size();
        const auto x = mesh.from_vertex_handle(across);
        for (auto g = mesh.next_halfedge_handle(h); mesh.to_vertex_handle(g) != x; g = mesh.next_halfedge_handle(g))
          face_ring.push_back(mesh.to_vertex_handle(g).idx());
        vertex_faces.push_back(mesh.face_handle(across).idx());
        face_ring_sizes.push_back(static_cast<std::int32_t>(face_ring.size() - before));
        quads = quads && face_ring.size() - before == 1;
      }
    } while (h != h0);
    if (faces_seen != r.face_count[v])
      throw MeshError("vertex " + std::to_string(v) + ": its faces form more than one fan (OpenMesh's circulator " +
                      "passes " + std::to_string(faces_seen) + " of its " + std::to_string(r.face_count[v]) + ")");
    // h = v -> x lies in the face (v, x, .): start an interior ring at the x
    // of the lowest-numbered face. The faces listed after neighbour j are
    // those between j and j + 1: they rotate with the neighbours.
    if (!on_boundary) {
      std::rotate(r.neighbors.begin() + r.offsets[v], r.neighbors.begin() + r.offsets[v] + lowest_at,
                  r.neighbors.end());
      if (polygons) {
        const auto at = static_cast<std::ptrdiff_t>(lowest_at);
        const std::ptrdiff_t skip = std::accumulate(face_ring_sizes.begin(), face_ring_sizes.begin() + at, 0);
        std::rotate(vertex_faces.begin(), vertex_faces.begin() + at, vertex_faces.end());
        std::rotate(face_ring.begin(), face_ring.begin() + skip, face_ring.end());
      }
    }
    if (polygons) {
      r.faces.insert(r.faces.end(), vertex_faces.begin(), vertex_faces.end());
      r.face_ring.insert(r.face_ring.end(), face_ring.begin(), face_ring.end());
      r.quad_ring[v] = quads;
    }
  }
  r.offsets[n_vertices] = static_cast<std::int32_t>(r.neighbors.size());
  if (polygons) {
    r.face_offsets[n_vertices] = static_cast<std::int32_t>(r.faces.size());
    r.face_ring_offsets[n_vertices] = static_cast<std::int32_t>(r.face_ring.size());
  }
  return r;
}

}  // namespace

ReferenceOneRing reference_one_ring(const Mesh& faces, std::size_t n_vertices) {
  const std::vector<std::int32_t> counts = faces.counts();
  const bool triangles = std::all_of(counts.begin(), counts.end(), [](std::int32_t k) { return k == 3; });
  return triangles ? one_ring_openmesh<OpenMesh::TriMesh_ArrayKernelT<>>(faces, n_vertices, false)
                   : one_ring_openmesh<OpenMesh::PolyMesh_ArrayKernelT<>>(faces, n_vertices, true);
}

}  // namespace sorpia
