// The reference builds of B (reference.hpp): OpenSubdiv's Far::Limit(),
// recorded row by row, for the tests.
#include "sorpia/reference.hpp"

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyRefiner.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "refined_rows.hpp"
#include "sorpia/detail/osd_refiner.hpp"

namespace sorpia {

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

namespace {

// A primvar that is a sparse row of weights over the control vertices.
struct SparseRow {
  std::vector<std::pair<std::int32_t, double>> e;
  void Clear() { e.clear(); }
  void AddWithWeight(const SparseRow& src, double w) {
    for (const auto& [j, x] : src.e) {
      auto it = std::find_if(e.begin(), e.end(), [j = j](const auto& q) { return q.first == j; });
      if (it == e.end())
        e.emplace_back(j, w * x);
      else
        it->second += w * x;
    }
  }
};

}  // namespace

CsrMatrix reference_limit_matrix(const Topology& topology, const Rules& rules) {
  using namespace detail;
  const Scheme scheme = rules.scheme;
  const Boundary boundary = rules.boundary;
  const Tags& tags = rules.tags;
  const std::size_t n = topology.n_vertices();
  const VertexTags vt = vertex_tags(topology, tags);  // checks the creases against the topology
  const Refiner osd = make_refiner(topology, scheme, boundary, tags);
  const auto& refiner = osd.refiner;
  const std::vector<std::int32_t>& to_osd = osd.to_osd;
  const std::vector<std::int32_t>& from_osd = osd.from_osd;

  const std::vector<int> row_level = row_levels(topology, scheme, vt);
  const int levels = row_level.empty() ? 0 : *std::max_element(row_level.begin(), row_level.end());
  std::vector<SparseRow> rows(from_osd.size()), next;
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i].e.emplace_back(from_osd[i], 1.0);
  if (levels > 0) {
    Far::TopologyRefiner::UniformOptions options(levels);
    options.fullTopologyInLastLevel = true;
    refiner->RefineUniform(options);
  }
  const Far::PrimvarRefinerReal<double> primvar(*refiner);
  std::vector<int> descendant(from_osd.size());
  std::iota(descendant.begin(), descendant.end(), 0);
  for (int l = 1; l <= levels; ++l) {
    next.assign(refiner->GetLevel(l).GetNumVertices(), SparseRow{});
    primvar.Interpolate(l, rows, next);
    rows.swap(next);
    for (int& c : descendant) c = refiner->GetLevel(l - 1).GetVertexChildVertex(c);
  }
  std::vector<SparseRow> limit(rows.size());
  primvar.Limit(rows, limit);

  CsrMatrix b;
  b.n_rows = b.n_cols = n;
  b.indptr.assign(1, 0);
  std::vector<std::int32_t> cols;
  std::vector<double> w;
  for (std::size_t v = 0; v < n; ++v) {
    cols.clear();
    w.clear();
    if (to_osd[v] < 0) {
      cols.push_back(static_cast<std::int32_t>(v));
      w.push_back(1.0);
    } else {
      for (const auto& [j, x] : limit[descendant[to_osd[v]]].e) {
        cols.push_back(j);
        w.push_back(x);
      }
    }
    append_row(b, cols, w);
  }
  return b;
}

}  // namespace sorpia
