// The limit operator: built from OpenSubdiv's limit masks or from a CSR
// matrix, converted back to CSR, applied.
#include "sorpia/limit_operator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "sorpia/errors.hpp"

#include "catmark_rows.hpp"
#include "solver_detail.hpp"
#include "sorpia/limit_masks.hpp"

namespace sorpia {

std::string loop_needs_triangles(const Topology& topology) {
  std::size_t f = 0;
  while (f < topology.n_faces() && topology.face_size(f) == 3) ++f;
  if (f == topology.n_faces()) return {};
  return "face " + std::to_string(f) + " has " + std::to_string(topology.face_size(f)) +
         " vertices: Loop subdivision needs triangles; triangulate the mesh or use the Catmull-Clark scheme";
}

LimitOperator limit_operator(const Topology& topology, Boundary boundary, Scheme scheme) {
  if (scheme == Scheme::CatmullClark) return detail::catmark_limit_operator(topology, boundary);
  if (!topology.all_triangles()) throw MeshError(loop_needs_triangles(topology));
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

namespace {
// Where row j stores column i, or -1. Rows are short (valence), so a linear
// scan of row j is cheaper than sorting.
std::int32_t mirror(const LimitOperator& op, std::int32_t i, std::int32_t j) {
  const auto* first = op.neighbors.data() + op.offsets[j];
  const auto* last = op.neighbors.data() + op.offsets[j + 1];
  const auto* at = std::find(first, last, i);
  return at == last ? -1 : static_cast<std::int32_t>(at - op.neighbors.data());
}
}  // namespace

std::vector<double> symmetriser(const LimitOperator& op) {
  std::vector<double> d(op.n, 0.0);
  if (op.uniform()) {
    for (std::size_t i = 0; i < op.n; ++i) d[i] = op.weight[i] > 0.0 ? 1.0 / op.weight[i] : 1.0;
    return d;
  }
  std::vector<std::int32_t> queue;
  for (std::size_t s = 0; s < op.n; ++s) {
    if (d[s] != 0.0) continue;
    d[s] = op.offsets[s + 1] > op.offsets[s] ? 1.0 / op.values[op.offsets[s]] : 1.0;
    queue.assign(1, static_cast<std::int32_t>(s));
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::int32_t i = queue[q];
      for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
        const std::int32_t j = op.neighbors[p], pm = mirror(op, i, j);
        if (pm < 0) continue;  // a one-way entry
        const double want = d[i] * op.values[p] / op.values[pm];
        if (d[j] == 0.0) {
          d[j] = want;
          queue.push_back(j);
        } else if (std::abs(d[j] - want) > 1e-12 * d[j]) {
          return {};
        }
      }
    }
  }
  return d;
}

bool is_symmetrisable(const LimitOperator& op) {
  // (i, j) stored => (j, i) stored.
  for (std::size_t i = 0; i < op.n; ++i)
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p)
      if (mirror(op, static_cast<std::int32_t>(i), op.neighbors[p]) < 0) return false;
  return op.uniform() || !symmetriser(op).empty();
}

}  // namespace sorpia
