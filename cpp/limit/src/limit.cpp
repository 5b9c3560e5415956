#include "sorpia/limit.hpp"

#include <opensubdiv/far/error.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

#include "sorpia/detail/osd_refiner.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/limit_operator.hpp"

namespace sorpia {
namespace detail {

namespace {
// OpenSubdiv reports topology errors through a global callback; collect the
// message of the current thread's refiner build.
thread_local std::string osd_error;
void record_osd_error(Far::ErrorType, const char* message) { osd_error = message ? message : ""; }
}  // namespace

float osd_sharpness(double s) {
  return s >= kInfiniteSharpness ? OpenSubdiv::Sdc::Crease::SHARPNESS_INFINITE : static_cast<float>(s);
}

std::unique_ptr<Far::TopologyRefiner> create_refiner(const RefinerInput& input, Scheme scheme, Boundary boundary) {
  using namespace OpenSubdiv;
  Far::TopologyDescriptor desc;
  desc.numVertices = input.n_vertices;
  desc.numFaces = static_cast<int>(input.counts.size());
  desc.numVertsPerFace = input.counts.data();
  desc.vertIndicesPerFace = input.indices.data();
  desc.numCreases = static_cast<int>(input.crease_sharpness.size());
  desc.creaseVertexIndexPairs = input.crease_pairs.data();
  desc.creaseWeights = input.crease_sharpness.data();
  desc.numCorners = static_cast<int>(input.corner_sharpness.size());
  desc.cornerVertexIndices = input.corners.data();
  desc.cornerWeights = input.corner_sharpness.data();
  desc.numHoles = static_cast<int>(input.holes.size());
  desc.holeIndices = input.holes.data();
  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(boundary == Boundary::EdgeOnly ? Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                                                 : Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  Factory::Options options(scheme == Scheme::Loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK, sdc);
  osd_error.clear();
  Far::SetErrorCallback(record_osd_error);
  std::unique_ptr<Far::TopologyRefiner> refiner(Factory::Create(desc, options));
  Far::SetErrorCallback(nullptr);
  if (!refiner) throw MeshError("OpenSubdiv refused the mesh topology: " + osd_error);
  return refiner;
}

Refiner make_refiner(const Topology& topology, Scheme scheme, Boundary boundary, const Tags& tags) {
  using namespace OpenSubdiv;
  Refiner out;
  const std::size_t n = topology.n_vertices();
  out.to_osd.assign(n, -1);
  out.from_osd.reserve(n - topology.n_unreferenced());
  for (std::size_t v = 0; v < n; ++v)
    if (!topology.is_unreferenced(v)) {
      out.to_osd[v] = static_cast<std::int32_t>(out.from_osd.size());
      out.from_osd.push_back(static_cast<std::int32_t>(v));
    }
  if (scheme == Scheme::Loop) {
    const std::string not_triangles = loop_needs_triangles(topology);
    if (!not_triangles.empty()) throw MeshError(not_triangles);
  }
  check_surface_left(tags, topology.n_faces());
  const auto to_osd = [&](std::int32_t v, const char* what, std::size_t i) {
    if (out.to_osd[v] < 0)
      throw MeshError(std::string(what) + "[" + std::to_string(i) + "] names vertex " + std::to_string(v) +
                      ", which no face uses");
    return out.to_osd[v];
  };
  RefinerInput input;
  input.n_vertices = static_cast<int>(out.from_osd.size());
  input.counts = topology.face_counts();
  const std::vector<std::int32_t>& faces = topology.face_indices();
  input.indices.resize(faces.size());
  for (std::size_t k = 0; k < faces.size(); ++k) input.indices[k] = out.to_osd[faces[k]];
  for (std::size_t i = 0; i < tags.crease_vertices.size(); ++i)
    input.crease_pairs.push_back(to_osd(tags.crease_vertices[i], "creases", i / 2));
  for (std::size_t i = 0; i < tags.corner_vertices.size(); ++i)
    input.corners.push_back(to_osd(tags.corner_vertices[i], "corners", i));
  for (const double s : tags.crease_sharpness) input.crease_sharpness.push_back(osd_sharpness(s));
  for (const double s : tags.corner_sharpness) input.corner_sharpness.push_back(osd_sharpness(s));
  input.holes.assign(tags.holes.begin(), tags.holes.end());
  out.refiner = create_refiner(input, scheme, boundary);
  return out;
}

void gather_points(const Refiner& osd, const double* vertices, std::vector<Point3>& points) {
  points.resize(osd.from_osd.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double* p = vertices + 3 * static_cast<std::size_t>(osd.from_osd[i]);
    points[i] = Point3{p[0], p[1], p[2]};
  }
}

void limit_positions(const Refiner& osd, const std::vector<Point3>& points, const double* vertices,
                     std::size_t n, double* out) {
  std::vector<Point3> limit(points.size());
  OpenSubdiv::Far::PrimvarRefinerReal<double>(*osd.refiner).Limit(points, limit);
  std::copy(vertices, vertices + 3 * n, out);  // unreferenced vertices: limit is themselves
  for (std::size_t i = 0; i < limit.size(); ++i) {
    double* q = out + 3 * static_cast<std::size_t>(osd.from_osd[i]);
    q[0] = limit[i].x;
    q[1] = limit[i].y;
    q[2] = limit[i].z;
  }
}

UniformRefinement::UniformRefinement(const Refiner& base, std::size_t n_vertices, int levels, bool full_topology)
    : refiner_(Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Create(*base.refiner)),
      from_osd_(base.from_osd.data()),
      n_osd_(base.from_osd.size()),
      n_vertices_(n_vertices),
      levels_(levels) {
  if (levels > 0) {
    Far::TopologyRefiner::UniformOptions options(levels);
    options.fullTopologyInLastLevel = full_topology;
    poll_interrupt();
    refiner_->RefineUniform(options);
  }
  for (int l = 0; l < levels; ++l) {
    const Far::TopologyLevel& lv = refiner_->GetLevel(l);
    for (std::size_t v = 0; v < n_osd(); ++v)
      if (lv.GetVertexChildVertex(static_cast<int>(v)) != static_cast<int>(v))
        throw std::logic_error("OpenSubdiv's refinement does not order the children of vertices first");
  }
}

std::size_t UniformRefinement::n_fine_vertices() const {
  return n_vertices_ + (static_cast<std::size_t>(last().GetNumVertices()) - n_osd());
}

void UniformRefinement::interpolate(std::vector<Point3>& points) const {
  const Far::PrimvarRefinerReal<double> primvar(*refiner_);
  std::vector<Point3> next;
  for (int l = 1; l <= levels_; ++l) {
    poll_interrupt();
    next.resize(static_cast<std::size_t>(refiner_->GetLevel(l).GetNumVertices()));
    primvar.Interpolate(l, points, next);
    points.swap(next);
  }
}

}  // namespace detail

CsrMatrix limit_matrix(const Topology& topology, const Rules& rules) { return to_csr(limit_operator(topology, rules)); }

CsrMatrix limit_matrix(const Topology& topology, Boundary boundary, const Tags& tags) {
  return limit_matrix(topology, Rules{Scheme::Loop, boundary, tags});
}

void limit_points(const Topology& topology, const double* vertices, const Rules& rules, double* out,
                  std::size_t columns) {
  apply(limit_operator(topology, rules), vertices, columns, out);
}

void limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out) {
  limit_points(topology, vertices, Rules{Scheme::Loop, boundary, {}}, out);
}

void limit_points(const Topology& topology, const double* vertices, Boundary boundary, const Tags& tags,
                  double* out) {
  limit_points(topology, vertices, Rules{Scheme::Loop, boundary, tags}, out);
}

}  // namespace sorpia
