#include "sorpia/limit.hpp"

#include <opensubdiv/far/error.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

#include "sorpia/detail/osd_refiner.hpp"
#include "sorpia/errors.hpp"
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

}  // namespace detail

namespace {

// Primvar types that let PrimvarRefinerReal<double>::Limit write the weights
// of each limit mask instead of combining positions: row i of B. Limit()
// visits the vertices in order (Clear() then AddWithWeight() per vertex), so
// the rows are appended straight into CSR arrays; rows of unreferenced
// vertices, which OpenSubdiv never sees, are identity rows filled in between.
struct SourceIndex {
  std::int32_t index;
};
struct SourceIndices {
  const std::vector<std::int32_t>* from_osd;
  SourceIndex operator[](int i) const { return SourceIndex{(*from_osd)[i]}; }
};
struct CsrBuilder {
  CsrMatrix* b;
  std::size_t next_row = 0;  // rows [0, next_row) are started
  void start_row(std::size_t row) {
    if (row < next_row) throw std::logic_error("sorpia: OpenSubdiv Limit() visited vertices out of order");
    close_row();
    for (; next_row < row; ++next_row) {  // unreferenced vertices in between
      b->indices.push_back(static_cast<std::int32_t>(next_row));
      b->data.push_back(1.0);
      b->indptr[next_row + 1] = static_cast<std::int32_t>(b->indices.size());
    }
    ++next_row;
  }
  // Sort the entries of the last started row by column and set its end.
  void close_row() {
    if (next_row == 0) return;
    const std::int32_t lo = b->indptr[next_row - 1];
    const auto hi = static_cast<std::int32_t>(b->indices.size());
    std::pair<std::int32_t, double> tmp[64];
    std::vector<std::pair<std::int32_t, double>> big;
    auto* e = tmp;
    if (hi - lo > 64) {
      big.resize(hi - lo);
      e = big.data();
    }
    for (std::int32_t p = lo; p < hi; ++p) e[p - lo] = {b->indices[p], b->data[p]};
    std::sort(e, e + (hi - lo));
    for (std::int32_t p = lo; p < hi; ++p) std::tie(b->indices[p], b->data[p]) = e[p - lo];
    b->indptr[next_row] = hi;
  }
};
struct RowRecorder {
  CsrBuilder* builder;
  std::int32_t row;
  void Clear() { builder->start_row(static_cast<std::size_t>(row)); }
  void AddWithWeight(const SourceIndex& s, double w) {
    // OpenSubdiv lists interior neighbours of boundary vertices with weight 0.
    if (w != 0.0) {
      builder->b->indices.push_back(s.index);
      builder->b->data.push_back(w);
    }
  }
};
struct RowRecorders {
  CsrBuilder* builder;
  const std::vector<std::int32_t>* from_osd;
  RowRecorder operator[](int i) const { return RowRecorder{builder, (*from_osd)[i]}; }
};

}  // namespace

CsrMatrix reference_limit_matrix(const Topology& topology, Boundary boundary) {
  const auto osd = detail::make_refiner(topology, Scheme::Loop, boundary);
  const std::size_t n = topology.n_vertices();
  CsrMatrix b;
  b.n_rows = b.n_cols = n;
  b.indptr.assign(n + 1, 0);
  b.indices.reserve(n + topology.ring_neighbors().size());
  b.data.reserve(n + topology.ring_neighbors().size());
  CsrBuilder builder{&b};
  SourceIndices src{&osd.from_osd};
  RowRecorders dst{&builder, &osd.from_osd};
  OpenSubdiv::Far::PrimvarRefinerReal<double>(*osd.refiner).Limit(src, dst);
  builder.start_row(n);  // closes the last row and fills trailing unreferenced rows
  return b;
}

void reference_limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out) {
  const auto osd = detail::make_refiner(topology, Scheme::Loop, boundary);
  std::vector<detail::Point3> points;
  detail::gather_points(osd, vertices, points);
  detail::limit_positions(osd, points, vertices, topology.n_vertices(), out);
}

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
