// The Catmull-Clark limit operator: one row per vertex from OpenSubdiv's
// CATMARK limit masks (limit_masks.hpp) on the flat one-ring, and for the
// vertices of non-quad faces the limit after one uniform refinement composed
// back onto the control vertices.
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "catmark_rows.hpp"
#include "sorpia/limit_masks.hpp"
#include "sorpia/limit_operator.hpp"

namespace sorpia {
namespace detail {

namespace {

// One row being summed: (column, weight) pairs, merged by column at the end.
struct RowSum {
  std::vector<std::pair<std::int32_t, double>> entries;
  void add(std::int32_t j, double w) { entries.emplace_back(j, w); }
  // Sorted by column, equal columns summed.
  void merge() {
    std::sort(entries.begin(), entries.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    std::size_t out = 0;
    for (std::size_t p = 0; p < entries.size(); ++p) {
      if (out > 0 && entries[out - 1].first == entries[p].first)
        entries[out - 1].second += entries[p].second;
      else
        entries[out++] = entries[p];
    }
    entries.resize(out);
  }
};

}  // namespace

void catmark_refined_row(const Topology& t, std::size_t v, std::vector<std::pair<std::int32_t, double>>& row) {
  // Interior vertex v of valence n: ring e_0..e_{n-1}, face j between e_j and
  // e_{j+1} with vertices (v, e_{j+1}, its face neighbours..., e_j).
  // One Catmull-Clark step (Sdc::Scheme<SCHEME_CATMARK>'s smooth masks,
  // triangles refined as any face): face point F'_j = centroid of face j; edge
  // point e'_j = (v + e_j + F'_{j-1} + F'_j) / 4; vertex point
  // v' = (n - 2)/n v + 1/n^2 (sum e_j + sum F'_j). The child v' has valence n
  // in a quad ring whose opposite corners are the face points, so its limit is
  // d v' + w_e sum e'_j + w_f sum F'_j with catmark_smooth_limit_mask(n).
  const auto& ring = t.ring_neighbors();
  const auto& fring = t.face_ring_neighbors();
  const std::int32_t lo = t.ring_offsets()[v], n = t.ring_offsets()[v + 1] - lo;
  const CatmarkMask m = catmark_smooth_limit_mask(n);
  const double nn = static_cast<double>(n) * n;
  const auto self = static_cast<std::int32_t>(v);
  RowSum r;
  r.add(self, m.diag * (n - 2) / n + n * m.edge / 4);
  const double edge_weight = m.diag / nn + m.edge / 4;
  const double face_weight = m.diag / nn + m.edge / 2 + m.face;  // F'_j: in v', e'_{j} and e'_{j+1}, and itself
  // An all-triangle topology keeps no face ring: every face is (v, e_{j+1}, e_j).
  const bool triangles = !t.has_face_ring();
  std::int32_t fr = triangles ? 0 : t.face_ring_offsets()[v];
  for (std::int32_t j = 0; j < n; ++j) {
    r.add(ring[lo + j], edge_weight);
    const std::int32_t next = ring[lo + (j + 1) % n];
    const std::int32_t size = triangles ? 3 : t.face_size(t.vertex_faces()[t.vertex_face_offsets()[v] + j]);
    const double w = face_weight / size;
    r.add(self, w);
    r.add(next, w);
    r.add(ring[lo + j], w);
    for (std::int32_t k = 0; k < size - 3; ++k) r.add(fring[fr++], w);
  }
  r.merge();
  row = std::move(r.entries);
}

LimitOperator catmark_limit_operator(const Topology& t, Boundary boundary) {
  const std::size_t n = t.n_vertices();
  const auto& offsets = t.ring_offsets();
  const auto& ring = t.ring_neighbors();
  const auto& fr_off = t.face_ring_offsets();
  const auto& fring = t.face_ring_neighbors();
  // Rows in `values`; `weight` unused (zero).
  LimitOperator op{n, std::vector<std::int32_t>(n + 1), {}, std::vector<double>(n), std::vector<double>(n, 0.0), {}};
  op.neighbors.reserve(ring.size() + fring.size());
  op.values.reserve(ring.size() + fring.size());
  RowSum r;
  std::vector<std::pair<std::int32_t, double>> refined;
  for (std::size_t v = 0; v < n; ++v) {
    op.offsets[v] = static_cast<std::int32_t>(op.neighbors.size());
    const auto self = static_cast<std::int32_t>(v);
    r.entries.clear();
    if (t.is_unreferenced(v) || (t.is_boundary(v) && t.face_count(v) == 1 && boundary == Boundary::EdgeAndCorner)) {
      op.diag[v] = 1.0;  // its own limit / the corner rule
      continue;
    }
    if (t.is_boundary(v)) {  // the crease rule: only the two boundary neighbours, whatever the faces
      const CatmarkMask m = catmark_crease_limit_mask();
      op.diag[v] = m.diag;
      r.add(ring[offsets[v]], m.edge);
      r.add(ring[offsets[v + 1] - 1], m.edge);
    } else if (t.quad_ring(v)) {  // Far's Limit(): edge weights on the ring, face weights on opposite corners
      const CatmarkMask m = catmark_smooth_limit_mask(t.valence(v));
      op.diag[v] = m.diag;
      if (m.edge != 0.0 || m.face != 0.0) {  // valence 2 is a corner
        for (std::int32_t p = offsets[v]; p < offsets[v + 1]; ++p) r.add(ring[p], m.edge);
        for (std::int32_t p = fr_off[v]; p < fr_off[v + 1]; ++p) r.add(fring[p], m.face);
      }
    } else {  // a non-quad face at v: the limit after one refinement
      catmark_refined_row(t, v, refined);
      for (const auto& [j, w] : refined)
        if (j == self)
          op.diag[v] = w;
        else
          r.add(j, w);
    }
    r.merge();
    for (const auto& [j, w] : r.entries) {
      op.neighbors.push_back(j);
      op.values.push_back(w);
    }
  }
  op.offsets[n] = static_cast<std::int32_t>(op.neighbors.size());
  // A mesh whose rows have no neighbours at all keeps `values` empty (uniform).
  if (op.neighbors.empty()) op.values.clear();
  return op;
}

}  // namespace detail
}  // namespace sorpia
