// The limit operator: built from OpenSubdiv's limit masks or from a CSR
// matrix, converted back to CSR, applied.
#include "sorpia/limit_operator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "catmark_rows.hpp"
#include "refined_rows.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/detail/apply.hpp"
#include "sorpia/limit_masks.hpp"

namespace sorpia {

namespace {

// The mask vertices of a row: all ring neighbours, the two boundary (or
// crease) neighbours, or none.
enum class MaskVertices { Ring, Ends, None };

// A row of a uniform operator: its weights and which neighbours carry `weight`.
struct UniformRow {
  LimitMask mask;
  MaskVertices vertices;
  std::int32_t ends[2];  // MaskVertices::Ends: the two neighbours
};

// The rule of vertex v without tags: smooth inside, crease on the boundary
// (the two boundary neighbours, first and last in the ring), corner for a
// one-face vertex under "edge-and-corner" and for an unreferenced vertex.
UniformRow untagged_row(const Topology& topology, std::size_t v, Boundary boundary) {
  const LimitMask m = limit_mask(topology, v, boundary);
  if (m.weight == 0.0) return {m, MaskVertices::None, {}};
  if (!topology.is_boundary(v)) return {m, MaskVertices::Ring, {}};
  const auto& ring = topology.ring_neighbors();
  return {m, MaskVertices::Ends, {ring[topology.ring_offsets()[v]], ring[topology.ring_offsets()[v + 1] - 1]}};
}

// A uniform operator with the rule of each vertex from `row(v)`.
template <class RowRule>
LimitOperator uniform_operator(const Topology& topology, RowRule row) {
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
    const UniformRow r = row(v);
    op.diag[v] = r.mask.diag;
    op.weight[v] = r.mask.weight;
    std::int32_t* first = op.neighbors.data() + out;
    if (r.vertices == MaskVertices::Ends) {
      first[0] = r.ends[0];
      first[1] = r.ends[1];
      out += 2;
    } else if (r.vertices == MaskVertices::Ring) {
      std::copy(ring.begin() + offsets[v], ring.begin() + offsets[v + 1], first);
      out += offsets[v + 1] - offsets[v];
    }
    std::sort(first, op.neighbors.data() + out);
  }
  op.offsets[n] = out;
  op.neighbors.resize(out);
  return op;
}

// The rule of a Loop vertex whose tags are all infinitely sharp (OpenSubdiv's
// Sdc::Crease rules, boundary edges counting as sharp edges): an infinitely
// sharp corner keeps itself; with one sharp edge (a dart) the smooth rule (its
// row is replaced by the limit of its refinement afterwards), two
// the crease rule on their ends, three or more the corner rule.
UniformRow infinitely_sharp_row(const Topology& topology, std::size_t v, Boundary boundary,
                                const detail::VertexTags& tags) {
  if (tags.infinite(tags.corner[v])) return {corner_limit_mask(), MaskVertices::None, {}};
  const auto& ring = topology.ring_neighbors();
  const std::int32_t first = ring[topology.ring_offsets()[v]], last = ring[topology.ring_offsets()[v + 1] - 1];
  int sharp = 0;
  std::int32_t ends[2] = {};
  for (std::int32_t p = tags.crease_offsets[v]; p < tags.crease_offsets[v + 1]; ++p) {
    const std::int32_t w = tags.crease_other[p];
    if (topology.is_boundary(v) && (w == first || w == last)) continue;  // sharp already
    if (sharp < 2) ends[sharp] = w;
    ++sharp;
  }
  if (topology.is_boundary(v)) {
    if (sharp == 0) return untagged_row(topology, v, boundary);
    return {corner_limit_mask(), MaskVertices::None, {}};
  }
  if (sharp <= 1) return untagged_row(topology, v, boundary);
  if (sharp == 2) return {crease_limit_mask(), MaskVertices::Ends, {ends[0], ends[1]}};
  return {corner_limit_mask(), MaskVertices::None, {}};
}

// `b` with the rows of `vertices` replaced by `rows` (refined_limit_rows' form).
CsrMatrix replace_rows(const CsrMatrix& b, const std::vector<std::int32_t>& vertices, const CsrMatrix& rows) {
  std::vector<std::int32_t> slot(b.n_rows, -1);
  for (std::size_t k = 0; k < vertices.size(); ++k) slot[vertices[k]] = static_cast<std::int32_t>(k);
  CsrMatrix out;
  out.n_rows = b.n_rows;
  out.n_cols = b.n_cols;
  out.indptr.assign(1, 0);
  out.indices.reserve(b.indices.size() + rows.indices.size());
  out.data.reserve(out.indices.capacity());
  for (std::size_t i = 0; i < b.n_rows; ++i) {
    const CsrMatrix& from = slot[i] < 0 ? b : rows;
    const std::size_t r = slot[i] < 0 ? i : static_cast<std::size_t>(slot[i]);
    out.indices.insert(out.indices.end(), from.indices.begin() + from.indptr[r], from.indices.begin() + from.indptr[r + 1]);
    out.data.insert(out.data.end(), from.data.begin() + from.indptr[r], from.data.begin() + from.indptr[r + 1]);
    out.indptr.push_back(static_cast<std::int32_t>(out.indices.size()));
  }
  return out;
}

}  // namespace

std::string loop_needs_triangles(const Topology& topology) {
  std::size_t f = 0;
  while (f < topology.n_faces() && topology.face_size(f) == 3) ++f;
  if (f == topology.n_faces()) return {};
  return "face " + std::to_string(f) + " has " + std::to_string(topology.face_size(f)) +
         " vertices: Loop subdivision needs triangles; triangulate the mesh or use the Catmull-Clark scheme";
}

namespace {

// Catmull-Clark: the masks' operator (detail::catmark_limit_operator) with the
// rows whose level (detail::row_levels) the masks do not give replaced by
// OpenSubdiv's refinement around their vertex (refined_rows.hpp): vertices a
// tag touches (a crease edge or a corner at them), and darts and interior
// vertices of two faces (their Sdc limit masks, the smooth mask and the corner
// mask, are not the limit of their refinement: they get that limit).
LimitOperator catmark_operator(const Topology& topology, Boundary boundary, const Tags& tags) {
  LimitOperator op = detail::catmark_limit_operator(topology, boundary);
  const std::size_t n = topology.n_vertices();
  const auto valence_two = [&](std::size_t v) {
    return !topology.is_unreferenced(v) && !topology.is_boundary(v) && topology.valence(v) == 2;
  };
  bool any_valence_two = false;
  for (std::size_t v = 0; v < n && !any_valence_two; ++v) any_valence_two = valence_two(v);
  if (tags.empty() && !any_valence_two) return op;
  const detail::VertexTags vt = detail::vertex_tags(topology, tags);
  const std::vector<int> level = detail::row_levels(topology, Scheme::CatmullClark, vt);
  std::vector<std::int32_t> refined;
  std::vector<int> refined_levels;
  for (std::size_t v = 0; v < n; ++v) {
    const auto i = static_cast<std::int32_t>(v);
    if (topology.is_unreferenced(v)) continue;
    const bool tagged = vt.crease_offsets[v + 1] > vt.crease_offsets[v] || vt.corner[v] > 0.0f;
    if (tagged || valence_two(v) || vt.level_dependent(topology, Scheme::CatmullClark, i)) {
      refined.push_back(i);
      refined_levels.push_back(level[v]);
    }
  }
  if (refined.empty()) return op;
  return limit_operator(replace_rows(
      to_csr(op), refined,
      detail::refined_limit_rows(topology, Scheme::CatmullClark, boundary, vt, refined, refined_levels)));
}

}  // namespace

LimitOperator limit_operator(const Topology& topology, Boundary boundary) {
  return limit_operator(topology, boundary, Tags{});
}

LimitOperator limit_operator(const Topology& topology, Boundary boundary, const Tags& tags) {
  if (!topology.all_triangles()) throw MeshError(loop_needs_triangles(topology));
  if (tags.empty())
    return uniform_operator(topology, [&](std::size_t v) { return untagged_row(topology, v, boundary); });
  const detail::VertexTags vt = detail::vertex_tags(topology, tags);
  // Rows with a semi-sharp tag come from OpenSubdiv's refinement, darts from
  // the limit of their refinement (refined_rows.hpp); every other row is the
  // same at any level.
  const std::vector<int> level = detail::row_levels(topology, Scheme::Loop, vt);
  std::vector<std::int32_t> refined;
  std::vector<int> refined_levels;
  for (std::size_t v = 0; v < topology.n_vertices(); ++v)
    if (level[v] > 0 || vt.level_dependent(topology, Scheme::Loop, static_cast<std::int32_t>(v))) {
      refined.push_back(static_cast<std::int32_t>(v));
      refined_levels.push_back(level[v]);
    }
  LimitOperator op =
      uniform_operator(topology, [&](std::size_t v) { return infinitely_sharp_row(topology, v, boundary, vt); });
  if (refined.empty()) return op;
  return limit_operator(
      replace_rows(to_csr(op), refined, detail::refined_limit_rows(topology, Scheme::Loop, boundary, vt, refined, refined_levels)));
}

LimitOperator limit_operator(const Topology& topology, const Rules& rules) {
  if (rules.scheme == Scheme::CatmullClark) return catmark_operator(topology, rules.boundary, rules.tags);
  return limit_operator(topology, rules.boundary, rules.tags);
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

void apply(const LimitOperator& op, const double* x, double* y) { detail::apply_columns(op, 3, x, y); }

void apply(const LimitOperator& op, const double* x, std::size_t k, double* y) {
  detail::apply_columns(op, k, x, y);
}

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
