#include "sorpia/cage.hpp"

#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Decimater/Observer.hh>

#include <algorithm>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "openmesh_types.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {
namespace {

using detail::OMesh;

// A binary module: a boundary vertex v0 collapses (along the boundary, the
// only way BaseDecimaterT lets it) only where the boundary turns by at most
// the given angle at v0, between its incoming and outgoing boundary edges.
template <class MeshT>
class ModBoundaryAngleT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModBoundaryAngleT, MeshT, BoundaryAngle);

  explicit ModBoundaryAngleT(MeshT& mesh) : Base(mesh, true) {}

  void set_max_angle(double degrees) { min_cos_ = std::cos(degrees * (M_PI / 180.0)); }

  float collapse_priority(const CollapseInfo& ci) override {
    MeshT& m = Base::mesh();
    if (!m.is_boundary(ci.v0)) return Base::LEGAL_COLLAPSE;
    // v0's outgoing boundary half-edge (no face on its left) and the one that enters v0.
    const auto out = m.halfedge_handle(ci.v0);
    const auto in = m.prev_halfedge_handle(out);
    const auto a = m.point(m.to_vertex_handle(out)) - m.point(ci.v0);
    const auto b = m.point(ci.v0) - m.point(m.from_vertex_handle(in));
    const double la = a.norm(), lb = b.norm();
    if (la == 0.0 || lb == 0.0) return Base::LEGAL_COLLAPSE;  // a zero-length edge turns nowhere
    return OpenMesh::dot(a, b) >= min_cos_ * la * lb ? Base::LEGAL_COLLAPSE : Base::ILLEGAL_COLLAPSE;
  }

 private:
  double min_cos_ = 1.0;
};

// Polls for Ctrl-C between collapses; an Interrupted is kept and rethrown
// after DecimaterT has returned (never thrown through OpenMesh).
class InterruptObserver : public OpenMesh::Decimater::Observer {
 public:
  InterruptObserver() : Observer(1024) {}
  void notify(size_t) override {
    try {
      poll_interrupt();
    } catch (...) {
      stopped_ = std::current_exception();
    }
  }
  bool abort() const override { return static_cast<bool>(stopped_); }
  void rethrow() const {
    if (stopped_) std::rethrow_exception(stopped_);
  }

 private:
  std::exception_ptr stopped_;
};

void check_options(const DecimateOptions& o) {
  if (!(o.max_normal_deviation > 0.0 && o.max_normal_deviation <= 180.0))
    throw ParameterError("max_normal_deviation " + std::to_string(o.max_normal_deviation) +
                         " must be in (0, 180] degrees");
  if (!(o.max_aspect_ratio >= 1.0 && std::isfinite(o.max_aspect_ratio)))
    throw ParameterError("max_aspect_ratio " + std::to_string(o.max_aspect_ratio) + " must be finite and at least 1");
  if (!(o.max_boundary_angle >= 0.0 && o.max_boundary_angle <= 180.0))
    throw ParameterError("max_boundary_angle " + std::to_string(o.max_boundary_angle) +
                         " must be in [0, 180] degrees");
}

// The mesh's referenced vertices and its triangles in OpenMesh; `kept[i]` is
// the input number of OpenMesh's vertex i.
OMesh to_openmesh(const Mesh& mesh, std::vector<std::int32_t>& kept) {
  if (!mesh.uniform())
    for (std::size_t f = 0; f < mesh.face_vertex_counts.size(); ++f)
      if (mesh.face_vertex_counts[f] != 3)
        throw MeshError("decimate takes triangles: face " + std::to_string(f) + " has " +
                        std::to_string(mesh.face_vertex_counts[f]) + " corners (triangulate the mesh first)");
  if (mesh.uniform() && mesh.face_size != 3)
    throw MeshError("decimate takes triangles: every face has " + std::to_string(mesh.face_size) +
                    " corners (triangulate the mesh first)");
  const std::size_t n = mesh.n_vertices(), n_faces = mesh.face_vertex_indices.size() / 3;
  std::vector<std::int32_t> handle(n, -1);
  for (std::size_t i = 0; i < mesh.face_vertex_indices.size(); ++i) {
    const std::int32_t v = mesh.face_vertex_indices[i];
    if (v < 0 || static_cast<std::size_t>(v) >= n)
      throw MeshError("decimate: face " + std::to_string(i / 3) + " has vertex index " + std::to_string(v) +
                      " out of range [0, " + std::to_string(n) + ")");
    handle[static_cast<std::size_t>(v)] = 0;
  }
  detail::silence_openmesh();
  OMesh om;
  kept.clear();
  for (std::size_t v = 0; v < n; ++v)
    if (handle[v] == 0) {
      handle[v] = static_cast<std::int32_t>(kept.size());
      kept.push_back(static_cast<std::int32_t>(v));
    }
  om.reserve(kept.size(), 3 * n_faces / 2 + kept.size(), n_faces);
  for (const std::int32_t v : kept) om.add_vertex({mesh.vertices[3 * v], mesh.vertices[3 * v + 1], mesh.vertices[3 * v + 2]});
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::int32_t* t = &mesh.face_vertex_indices[3 * f];
    const OMesh::VertexHandle c[3] = {OMesh::VertexHandle(handle[t[0]]), OMesh::VertexHandle(handle[t[1]]),
                                      OMesh::VertexHandle(handle[t[2]])};
    if (!om.add_face(c[0], c[1], c[2]).is_valid())
      throw MeshError("decimate: face " + std::to_string(f) +
                      " cannot join OpenMesh's half-edge mesh (a repeated vertex, an edge of three or more faces, a "
                      "bowtie vertex or a face oriented against its neighbours); sorpia.repair makes such a mesh valid");
  }
  return om;
}

// The vertices of quads_from_triangles(om) once garbage-collected: one per
// vertex, edge and face.
std::size_t quad_vertices(const OMesh& om) { return om.n_vertices() + om.n_edges() + om.n_faces(); }

Mesh from_openmesh(const OMesh& om) {
  Mesh out;
  out.vertices.reserve(3 * om.n_vertices());
  for (const auto vh : om.vertices()) {
    const auto& p = om.point(vh);
    out.vertices.insert(out.vertices.end(), {p[0], p[1], p[2]});
  }
  out.face_vertex_indices.reserve(3 * om.n_faces());
  for (const auto fh : om.faces())
    for (const auto vh : om.fv_range(fh)) out.face_vertex_indices.push_back(vh.idx());
  return out;
}

}  // namespace

Mesh decimate(const Mesh& mesh, std::size_t n_vertices, const DecimateOptions& options) {
  check_options(options);
  if (n_vertices < 4) throw ParameterError("a cage needs at least 4 vertices, got " + std::to_string(n_vertices));
  // OpenMesh's normals and quadrics square and multiply coordinates, and its
  // degeneracy checks are absolute: coordinates beyond 2^+-20 in magnitude
  // are decimated scaled by a power of two (exact; a half-edge collapse keeps
  // the surviving vertices where they are) and scaled back.
  double largest = 0.0;
  for (const double x : mesh.vertices) largest = std::max(largest, std::abs(x));
  int e = 0;
  if (largest > 0.0 && std::isfinite(largest)) std::frexp(largest, &e);
  if (std::abs(e) <= 20) e = 0;
  Mesh scaled;
  if (e != 0) {
    scaled = mesh;
    for (double& x : scaled.vertices) x = std::ldexp(x, -e);
  }
  std::vector<std::int32_t> kept;
  OMesh om = to_openmesh(e != 0 ? scaled : mesh, kept);
  const std::size_t start = om.n_vertices();
  const bool quads = options.scheme == Scheme::CatmullClark;
  const std::size_t have = quads ? quad_vertices(om) : start;
  const char* what = quads ? " vertices as quads (vertices + edges + faces)" : " vertices";
  if (n_vertices > have)
    throw MeshError("decimate: " + std::to_string(n_vertices) + " vertices asked but the mesh has " +
                    std::to_string(have) + what + (kept.size() < mesh.n_vertices() ? " in its faces" : ""));

  using Decimater = OpenMesh::Decimater::DecimaterT<OMesh>;
  Decimater decimater(om);
  OpenMesh::Decimater::ModQuadricT<OMesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<OMesh>::Handle normals;
  OpenMesh::Decimater::ModAspectRatioT<OMesh>::Handle aspect;
  ModBoundaryAngleT<OMesh>::Handle boundary;
  decimater.add(quadric);
  decimater.add(normals);
  decimater.add(aspect);
  decimater.add(boundary);
  decimater.module(normals).set_max_normal_deviation(options.max_normal_deviation);
  decimater.module(aspect).set_aspect_ratio(static_cast<float>(options.max_aspect_ratio));
  decimater.module(boundary).set_max_angle(options.max_boundary_angle);
  InterruptObserver observer;
  decimater.set_observer(&observer);
  if (!decimater.initialize()) throw MeshError("decimate: OpenMesh's decimater did not initialize");

  // Loop: one pass to the count. Catmull-Clark: a collapse removes 4 (on the
  // boundary) to 6 (inside) quad vertices; collapse a sixth of the excess at
  // a time (never overshooting by more than 5). Garbage collection
  // after each pass keeps the counts exact; the next pass rebuilds its heap.
  std::size_t count = have;
  while (count > n_vertices) {
    const std::size_t excess = count - n_vertices;
    const std::size_t collapses = quads ? std::max<std::size_t>(excess / 6, 1) : excess;
    const std::size_t made = decimater.decimate(collapses);
    observer.rethrow();
    om.garbage_collection();
    count = quads ? quad_vertices(om) : om.n_vertices();
    if (made == 0) break;
  }
  if (count > n_vertices || (quads && count + 5 < n_vertices))
    throw MeshError("decimate stopped at " + std::to_string(count) + what + " of the " + std::to_string(n_vertices) +
                    " asked (from " + std::to_string(have) +
                    "): every further collapse would flip a normal, thin a face or cut a boundary corner "
                    "(max_normal_deviation, max_aspect_ratio, max_boundary_angle)");
  Mesh triangles = from_openmesh(om);
  for (double& x : triangles.vertices) x = std::ldexp(x, e);
  return quads ? quads_from_triangles(triangles) : triangles;
}

Mesh quads_from_triangles(const Mesh& tri) {
  if (!tri.all_triangles()) throw MeshError("quads_from_triangles takes a triangle mesh");
  Mesh m;
  m.vertices = tri.vertices;
  const auto point = [&](std::initializer_list<std::int32_t> corners) {
    const auto v = static_cast<std::int32_t>(m.n_vertices());
    double p[3] = {0, 0, 0};
    for (std::int32_t c : corners)
      for (int k = 0; k < 3; ++k) p[k] += tri.vertices[3 * c + k] / static_cast<double>(corners.size());
    m.vertices.insert(m.vertices.end(), p, p + 3);
    return v;
  };
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> midpoints;
  const auto midpoint = [&](std::int32_t a, std::int32_t b) {
    const auto key = std::minmax(a, b);
    const auto it = midpoints.find(key);
    if (it != midpoints.end()) return it->second;
    const std::int32_t v = point({a, b});
    midpoints.emplace(key, v);
    return v;
  };
  m.face_vertex_counts.assign(3 * tri.n_faces(), 4);
  m.face_vertex_indices.reserve(12 * tri.n_faces());
  for (std::size_t f = 0; f < tri.n_faces(); ++f) {
    const std::int32_t* t = tri.face_vertex_indices.data() + 3 * f;
    const std::int32_t c = point({t[0], t[1], t[2]});
    const std::int32_t mid[3] = {midpoint(t[0], t[1]), midpoint(t[1], t[2]), midpoint(t[2], t[0])};
    // corner k: (t[k], mid(k, k+1), centroid, mid(k-1, k)), counter-clockwise as the triangle
    for (int k = 0; k < 3; ++k)
      m.face_vertex_indices.insert(m.face_vertex_indices.end(), {t[k], mid[k], c, mid[(k + 2) % 3]});
  }
  return m;
}

}  // namespace sorpia
