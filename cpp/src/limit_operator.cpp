// The limit operator: built from OpenSubdiv's limit masks or from a CSR
// matrix, converted back to CSR, applied.
#include "sorpia/limit_operator.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "solver_detail.hpp"
#include "sorpia/limit_masks.hpp"

namespace sorpia {

LimitOperator limit_operator(const Topology& topology, Boundary boundary) {
  const std::size_t n = topology.n_vertices();
  const auto& offsets = topology.ring_offsets();
  const auto& ring = topology.ring_neighbors();
  LimitOperator op;
  op.n = n;
  op.offsets.resize(n + 1);
  op.diag.resize(n);
  op.weight.resize(n);
  op.neighbors.resize(ring.size());  // an upper bound: creases and corners keep fewer
  std::int32_t out = 0;
  for (std::size_t v = 0; v < n; ++v) {
    op.offsets[v] = out;
    const LimitMask m = limit_mask(topology, v, boundary);
    op.diag[v] = m.diag;
    op.weight[v] = m.weight;
    if (m.weight == 0.0) continue;  // a corner (or unreferenced vertex) keeps itself
    std::int32_t* row = op.neighbors.data() + out;
    if (topology.is_boundary(v)) {  // the crease rule: only the two boundary neighbours count
      row[0] = ring[offsets[v]];
      row[1] = ring[offsets[v + 1] - 1];
      out += 2;
    } else {
      std::copy(ring.begin() + offsets[v], ring.begin() + offsets[v + 1], row);
      out += offsets[v + 1] - offsets[v];
    }
    std::sort(row, op.neighbors.data() + out);
  }
  op.offsets[n] = out;
  op.neighbors.resize(out);
  return op;
}

LimitOperator limit_operator(const CsrMatrix& b) {
  if (b.n_rows != b.n_cols) throw std::logic_error("sorpia::limit_operator: B is not square");
  LimitOperator op;
  op.n = b.n_rows;
  op.offsets.assign(op.n + 1, 0);
  op.neighbors.reserve(b.indices.size());
  op.diag.assign(op.n, 0.0);
  op.weight.assign(op.n, 0.0);
  std::vector<double> values;
  values.reserve(b.indices.size());
  bool uniform = true;
  for (std::size_t i = 0; i < op.n; ++i) {
    bool has_diag = false;
    for (std::int32_t p = b.indptr[i]; p < b.indptr[i + 1]; ++p) {
      const std::int32_t j = b.indices[p];
      if (static_cast<std::size_t>(j) == i) {
        op.diag[i] = b.data[p];
        has_diag = true;
        continue;
      }
      if (b.data[p] == 0.0) continue;  // an explicit zero is no neighbour
      if (static_cast<std::int32_t>(op.neighbors.size()) == op.offsets[i])
        op.weight[i] = b.data[p];
      else if (b.data[p] != op.weight[i])
        uniform = false;
      op.neighbors.push_back(j);
      values.push_back(b.data[p]);
    }
    if (!has_diag || !(op.diag[i] > 0.0))
      throw std::logic_error("sorpia::limit_operator: row " + std::to_string(i) + " of B has no positive diagonal");
    op.offsets[i + 1] = static_cast<std::int32_t>(op.neighbors.size());
  }
  if (!uniform) op.values = std::move(values);
  return op;
}

CsrMatrix to_csr(const LimitOperator& op) {
  CsrMatrix b;
  b.n_rows = b.n_cols = op.n;
  b.indptr.resize(op.n + 1);
  b.indices.resize(op.n + op.neighbors.size());
  b.data.resize(b.indices.size());
  std::size_t p = 0;
  const auto put = [&](std::int32_t j, double w) {
    b.indices[p] = j;
    b.data[p++] = w;
  };
  for (std::size_t i = 0; i < op.n; ++i) {
    b.indptr[i] = static_cast<std::int32_t>(p);
    const auto self = static_cast<std::int32_t>(i);
    bool diag_done = false;
    for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q) {
      if (!diag_done && op.neighbors[q] > self) {
        put(self, op.diag[i]);
        diag_done = true;
      }
      put(op.neighbors[q], op.entry(i, q));
    }
    if (!diag_done) put(self, op.diag[i]);
  }
  b.indptr[op.n] = static_cast<std::int32_t>(p);
  return b;
}

void apply(const LimitOperator& op, const double* x, double* y) { detail::apply_cols<3>(op, x, y); }

bool is_symmetrisable(const LimitOperator& op) {
  if (!op.uniform()) return false;
  // (i, j) stored => (j, i) stored. Rows are short (valence), so a linear scan
  // of row j is cheaper than sorting.
  for (std::size_t i = 0; i < op.n; ++i)
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
      const std::int32_t j = op.neighbors[p];
      const auto* first = op.neighbors.data() + op.offsets[j];
      const auto* last = op.neighbors.data() + op.offsets[j + 1];
      if (std::find(first, last, static_cast<std::int32_t>(i)) == last) return false;
    }
  return true;
}

}  // namespace sorpia
