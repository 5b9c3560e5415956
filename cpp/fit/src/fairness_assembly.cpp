#include "fairness_assembly.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"

namespace sorpia::fairness_detail {

namespace {

// Adds coef * row r of m to the dense row `a` (over the element's columns).
void add_row(const CsrMatrix& m, std::size_t r, double coef, const std::vector<std::int32_t>& local, double* a) {
  if (coef == 0.0) return;
  for (auto p = static_cast<std::size_t>(m.indptr[r]); p < static_cast<std::size_t>(m.indptr[r + 1]); ++p)
    a[static_cast<std::size_t>(local[static_cast<std::size_t>(m.indices[p])])] += coef * m.data[p];
}

// E += s a a^T on the upper triangle (n x n, row-major).
void add_outer(double s, const double* a, std::size_t n, double* e) {
  for (std::size_t i = 0; i < n; ++i) {
    const double ai = s * a[i];
    if (ai == 0.0) continue;
    double* row = e + i * n;
    for (std::size_t j = i; j < n; ++j) row[j] += ai * a[j];
  }
}

// A face's element as assemble reads it: its columns and its matrix.
struct FaceElement {
  const std::int32_t* columns;
  const double* matrix;  // n x n, row-major
  std::size_t n;
};

// Per face (empty for holes), its element, once every class's matrix is stored.
std::vector<FaceElement> face_elements(const Elements& el) {
  std::vector<FaceElement> out(el.face_class.size(), FaceElement{nullptr, nullptr, 0});
  for (std::size_t f = 0; f < out.size(); ++f)
    if (el.live(f))
      out[f] = {el.columns(f), el.element[static_cast<std::size_t>(el.face_class[f])].data(), el.n_columns(f)};
  return out;
}

// Row i of a face's element matrix (its row of the face's i-th column) added
// into `row` at the slots of the face's columns: row[slot[j]] += E[i][j]. The
// one step where a face's element matrix enters K.
inline void add_element_row(const FaceElement& face, std::size_t i, const std::int32_t* slot, double* row) {
  const double* e = face.matrix + i * face.n;
  for (std::size_t j = 0; j < face.n; ++j) row[slot[j]] += e[j];
}

// Rows assemble builds before it reserves the rest of its arrays by their
// lengths so far.
constexpr std::size_t kRowsToEstimate = 1024;

}  // namespace

// A face's element matrix from the rows of its pieces' points: w.e (upper
// triangle, row-major) over the sorted global columns w.cols, w.local their
// places (store_element clears them).
void element_matrix(const SurfaceRows& rows, const double* weights, const Piece* pieces, std::size_t n_pieces,
                 const ElementRules& er, const std::vector<Term>& terms, Worker& w) {
  const CsrMatrix* d[6] = {&rows.position, &rows.du, &rows.dv, &rows.duu, &rows.duv, &rows.dvv};
  const std::size_t r0 = pieces[0].first, r1 = pieces[n_pieces - 1].first + pieces[n_pieces - 1].count;
  w.cols.clear();
  for (const CsrMatrix* m : d) {
    if (m == d[0]) continue;  // positions do not enter the energy
    for (auto p = static_cast<std::size_t>(m->indptr[r0]); p < static_cast<std::size_t>(m->indptr[r1]); ++p) {
      const std::int32_t c = m->indices[p];
      if (w.local[static_cast<std::size_t>(c)] < 0) {
        w.local[static_cast<std::size_t>(c)] = 0;
        w.cols.push_back(c);
      }
    }
  }
  std::sort(w.cols.begin(), w.cols.end());
  const std::size_t n = w.cols.size();
  for (std::size_t i = 0; i < n; ++i) w.local[static_cast<std::size_t>(w.cols[i])] = static_cast<std::int32_t>(i);
  w.e.assign(n * n, 0.0);
  const std::size_t nd = ExactForms::kData;
  for (std::size_t pi = 0; pi < n_pieces; ++pi) {
    const Piece& pc = pieces[pi];
    if (!pc.exact) {
      w.a.resize(n);
      for (std::size_t r = pc.first; r < pc.first + pc.count; ++r)
        for (const Term& t : terms) {
          std::fill(w.a.begin(), w.a.end(), 0.0);
          for (int i = 0; i < 5; ++i) add_row(*d[i + 1], r, t.coef[i], w.local, w.a.data());
          add_outer(weights[r] * t.weight, w.a.data(), n, w.e.data());
        }
      continue;
    }
    // The data (derivatives in the piece's (s, t) = (u, v) / h) as dense rows.
    w.a.assign(nd * n, 0.0);
    const double h = pc.scale;
    for (std::size_t q = 0; q < pc.count; ++q) {
      const std::size_t r = pc.first + q;
      double* a = w.a.data() + q * 5 * n;
      add_row(*d[1], r, h, w.local, a);
      add_row(*d[2], r, h, w.local, a + n);
      add_row(*d[3], r, h * h, w.local, a + 2 * n);
      add_row(*d[4], r, h * h, w.local, a + 3 * n);
      add_row(*d[5], r, h * h, w.local, a + 4 * n);
    }
    // E += D^T Q D, Q = thin_plate h^-2 Q_tp + membrane Q_mb.
    const double tp = er.thin_plate / (pc.scale * pc.scale);
    w.qd.assign(nd * n, 0.0);
    for (std::size_t i = 0; i < nd; ++i)
      for (std::size_t j = 0; j < nd; ++j) {
        const double q = tp * er.exact.thin_plate[i * nd + j] + er.membrane * er.exact.membrane[i * nd + j];
        if (q == 0.0) continue;
        const double* dj = w.a.data() + j * n;
        double* out = w.qd.data() + i * n;
        for (std::size_t k = 0; k < n; ++k) out[k] += q * dj[k];
      }
    for (std::size_t i = 0; i < nd; ++i) {
      const double* di = w.a.data() + i * n;
      const double* qi = w.qd.data() + i * n;
      for (std::size_t a = 0; a < n; ++a) {
        if (di[a] == 0.0) continue;
        double* row = w.e.data() + a * n;
        for (std::size_t b = a; b < n; ++b) row[b] += di[a] * qi[b];
      }
    }
  }
}

// The element matrix of element_matrix (w.e, upper triangle over w.cols) as
// the full symmetric matrix of class c over its columns: for a shared class
// the control points `cv` of its representative (distinct, in its class's order),
// else the face's own columns w.cols. Clears w.local.
void store_element(Worker& w, const std::int32_t* cv, std::size_t n_cv, std::size_t c, Elements& el) {
  const std::size_t n = w.cols.size();
  std::vector<double>& out = el.element[c];
  if (!el.shared[c]) {
    el.own_columns[c] = w.cols;
    out.resize(n * n);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i; j < n; ++j) out[i * n + j] = out[j * n + i] = w.e[i * n + j];
  } else {
    out.assign(n_cv * n_cv, 0.0);
    // Each column at its first listing; a repeat (the list names the vertex
    // again) and a control point without weight at any point stay zero.
    std::size_t found = 0;
    w.first.assign(n_cv, -1);
    for (std::size_t i = 0; i < n_cv; ++i) {
      const std::int32_t a = w.local[static_cast<std::size_t>(cv[i])];
      if (a < 0 || std::find(cv, cv + i, cv[i]) != cv + i) continue;
      w.first[i] = a;
      ++found;
    }
    if (found != n)
      throw std::logic_error("a face's stencils reach beyond its control points: the fairness matrix would lose "
                             "entries");
    for (std::size_t i = 0; i < n_cv; ++i) {
      const std::int32_t a = w.first[i];
      if (a < 0) continue;
      for (std::size_t j = 0; j < n_cv; ++j) {
        const std::int32_t b = w.first[j];
        if (b < 0) continue;
        const auto lo = static_cast<std::size_t>(std::min(a, b)), hi = static_cast<std::size_t>(std::max(a, b));
        out[i * n_cv + j] = w.e[lo * n + hi];
      }
    }
  }
  for (const std::int32_t col : w.cols) w.local[static_cast<std::size_t>(col)] = -1;
}

// K in CSR from the element matrices, assembled row by row (threads take
// ranges of rows): row r's columns are the union of the columns of the faces
// that have r among theirs, sorted (or, without sorted_columns, in the order
// they first appear); its values the sum of those faces' rows for r
// (add_element_row, from the slots found with the columns). No list of
// entries, no sort of all entries: each row's few columns are sorted on
// their own.
CsrMatrix assemble(const Elements& el, std::size_t n_rows, int n_threads, bool sorted_columns) {
  const std::vector<FaceElement> faces = face_elements(el);
  const std::size_t n_faces = faces.size();
  std::size_t max_n = 0;
  for (const FaceElement& face : faces) max_n = std::max(max_n, face.n);
  // Per vertex, its incidences (face, place among the face's columns).
  std::vector<std::int64_t> start(n_rows + 1, 0);
  for (const FaceElement& face : faces)
    for (std::size_t i = 0; i < face.n; ++i) ++start[static_cast<std::size_t>(face.columns[i]) + 1];
  for (std::size_t v = 0; v < n_rows; ++v) start[v + 1] += start[v];
  std::vector<std::pair<std::int32_t, std::int32_t>> incidence(static_cast<std::size_t>(start[n_rows]));
  {
    std::vector<std::int64_t> cursor(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < n_faces; ++f)
      for (std::size_t i = 0; i < faces[f].n; ++i)
        incidence[static_cast<std::size_t>(cursor[static_cast<std::size_t>(faces[f].columns[i])]++)] = {
            static_cast<std::int32_t>(f), static_cast<std::int32_t>(i)};
  }
  // Each task's rows, into arrays of its own (the final ones for one task).
  struct Part {
    std::vector<std::int32_t> indices;
    std::vector<double> data;
  };
  std::vector<Part> parts(static_cast<std::size_t>(n_threads));
  std::vector<std::int64_t> count(n_rows + 1, 0);
  const auto nt = static_cast<std::size_t>(n_threads);
  detail::for_each_task(n_threads > 1, n_threads, [&](int t) {
    const auto ut = static_cast<std::size_t>(t);
    const std::size_t r0 = n_rows * ut / nt, r1 = n_rows * (ut + 1) / nt;
    Part& part = parts[ut];
    // place[col]: the column's slot in the row being built (its first
    // appearance), -1 elsewhere; slots[q]: the slot of the q-th (incidence,
    // column) pair of the row, so that the values are summed from this
    // buffer without looking the columns up again.
    std::vector<std::int32_t> place(n_rows, -1), slots;
    std::vector<std::int32_t> cols;
    std::vector<double> sums;
    for (std::size_t r = r0; r < r1; ++r) {
      if (r == r0 + kRowsToEstimate) {  // the entries per incidence so far, times the incidences left, and a tenth
        const double per_incidence = static_cast<double>(part.indices.size()) /
                                     static_cast<double>(std::max<std::int64_t>(1, start[r] - start[r0]));
        const auto want = part.indices.size() +
                          static_cast<std::size_t>(1.1 * per_incidence * static_cast<double>(start[r1] - start[r]));
        part.indices.reserve(want);
        part.data.reserve(want);
      }
      const auto p0 = static_cast<std::size_t>(start[r]), p1 = static_cast<std::size_t>(start[r + 1]);
      if (slots.size() < (p1 - p0) * max_n) slots.resize((p1 - p0) * max_n);
      if (cols.size() < (p1 - p0) * max_n) cols.resize((p1 - p0) * max_n);
      std::int32_t* slot = slots.data();
      std::int32_t n_cols = 0;
      for (std::size_t p = p0; p < p1; ++p) {
        const FaceElement& face = faces[static_cast<std::size_t>(incidence[p].first)];
        for (std::size_t j = 0; j < face.n; ++j) {
          const std::int32_t c = face.columns[j];
          std::int32_t at = place[static_cast<std::size_t>(c)];
          if (at < 0) {
            at = n_cols++;
            place[static_cast<std::size_t>(c)] = at;
            cols[static_cast<std::size_t>(at)] = c;
          }
          *slot++ = at;
        }
      }
      // The values in the incidences' order (each slot's sum as add_element_row forms it).
      sums.assign(static_cast<std::size_t>(n_cols), 0.0);
      slot = slots.data();
      for (std::size_t p = p0; p < p1; ++p) {
        const FaceElement& face = faces[static_cast<std::size_t>(incidence[p].first)];
        add_element_row(face, static_cast<std::size_t>(incidence[p].second), slot, sums.data());
        slot += face.n;
      }
      if (sorted_columns) std::sort(cols.begin(), cols.begin() + n_cols);
      for (std::int32_t k = 0; k < n_cols; ++k) {
        const std::int32_t c = cols[static_cast<std::size_t>(k)];
        part.indices.push_back(c);
        part.data.push_back(sums[static_cast<std::size_t>(place[static_cast<std::size_t>(c)])]);
        place[static_cast<std::size_t>(c)] = -1;
      }
      count[r + 1] = n_cols;
    }
  });
  for (std::size_t r = 0; r < n_rows; ++r) count[r + 1] += count[r];
  if (count[n_rows] > static_cast<std::int64_t>(INT32_MAX))
    throw ParameterError("the fairness matrix has " + std::to_string(count[n_rows]) +
                         " entries, more than 32-bit CSR indices address");
  CsrMatrix k;
  k.n_rows = k.n_cols = n_rows;
  k.indptr.resize(n_rows + 1);
  for (std::size_t r = 0; r <= n_rows; ++r) k.indptr[r] = static_cast<std::int32_t>(count[r]);
  if (n_threads == 1) {
    k.indices = std::move(parts[0].indices);
    k.data = std::move(parts[0].data);
    return k;
  }
  k.indices.resize(static_cast<std::size_t>(count[n_rows]));
  k.data.resize(k.indices.size());
  detail::for_each_task(true, n_threads, [&](int t) {
    const auto ut = static_cast<std::size_t>(t);
    const auto at = static_cast<std::size_t>(count[n_rows * ut / nt]);
    std::copy(parts[ut].indices.begin(), parts[ut].indices.end(), k.indices.begin() + static_cast<std::ptrdiff_t>(at));
    std::copy(parts[ut].data.begin(), parts[ut].data.end(), k.data.begin() + static_cast<std::ptrdiff_t>(at));
  });
  return k;
}
}  // namespace sorpia::fairness_detail
