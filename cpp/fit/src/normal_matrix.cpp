#include "sorpia/normal_matrix.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

namespace {

// Stored entries (of N and K together) per task of a product below which it runs on one thread.
constexpr std::size_t kEntriesPerTask = 100000;
// Stored entries of the rows A per task of the normal matrix's assembly, at least.
constexpr std::size_t kRowEntriesPerTask = 32768;

// The upper triangle (columns >= the row) of A^T W A, row by row: (row lengths, columns, values).
struct Upper {
  std::vector<std::int64_t> row_len;
  std::vector<std::int32_t> row_task;  // the task that made row i
  std::vector<std::int64_t> row_at;    // where row i starts in its task's entries
  std::vector<std::vector<std::int32_t>> part_idx;  // per task, its rows in the order it made them
  std::vector<std::vector<double>> part_val;
};

// Columns of a run's Gram row summed at once by gram_row, their sums held in registers.
constexpr std::size_t kGramColumns = 4;

// out[b * NB + c] += sum over the rows r0 .. r1 - 1 (a run with the same columns) of w_r[c] a_r[li] a_r[li + b],
// b < width, each sum added up over the rows in their order; w_r = weights[NB r ..] (1 when null). The weights'
// count a constant, so that each a_r[li + b] is read once for all NB sums; `scaled` holds w_r[c] a_r[li] per row.
template <int NB>
void gram_row(const CsrRows& A, const double* weights, std::size_t r0, std::size_t r1, std::int32_t li,
              std::size_t width, double* out, std::vector<double>& scaled) {
  scaled.resize((r1 - r0) * NB);
  for (std::size_t r = r0; r < r1; ++r) {
    const double a0 = A.data[A.indptr[r] + li];
    for (int c = 0; c < NB; ++c)
      scaled[(r - r0) * NB + static_cast<std::size_t>(c)] =
          a0 * (weights == nullptr ? 1.0 : weights[NB * r + static_cast<std::size_t>(c)]);
  }
  // kGramColumns columns at a time (then one at a time), each sum in a register over all the rows.
  const auto columns = [&](std::size_t b, auto count) {
    constexpr std::size_t kCount = decltype(count)::value;
    double acc[kCount][NB];
    for (std::size_t j = 0; j < kCount; ++j)
      for (int c = 0; c < NB; ++c) acc[j][c] = out[(b + j) * NB + static_cast<std::size_t>(c)];
    for (std::size_t r = r0; r < r1; ++r) {
      const double* a = A.data + A.indptr[r] + li + b;
      const double* w = &scaled[(r - r0) * NB];
      for (std::size_t j = 0; j < kCount; ++j)
        for (int c = 0; c < NB; ++c) acc[j][c] += w[c] * a[j];
    }
    for (std::size_t j = 0; j < kCount; ++j)
      for (int c = 0; c < NB; ++c) out[(b + j) * NB + static_cast<std::size_t>(c)] = acc[j][c];
  };
  std::size_t b = 0;
  for (; b + kGramColumns <= width; b += kGramColumns) columns(b, std::integral_constant<std::size_t, kGramColumns>{});
  for (; b < width; ++b) columns(b, std::integral_constant<std::size_t, 1>{});
}

}  // namespace

NormalMatrix normal_matrix(const CsrMatrix& rows, const double* weights, int weight_count) {
  return normal_matrix(CsrRows{rows.n_rows, rows.n_cols, rows.indptr.data(), rows.indices.data(), rows.data.data()},
                       weights, weight_count);
}

NormalMatrix normal_matrix(const CsrRows& A, const double* weights, int weight_count, const double* x,
                           double* rhs) {
  if (weight_count != 0 && weight_count != 1 && weight_count != 6)
    throw ParameterError("weight_count must be 0, 1 or 6, got " + std::to_string(weight_count));
  const std::size_t k = A.n_rows, n = A.n_cols;
  const bool with_rhs = x != nullptr && rhs != nullptr;
  const int nb = weight_count == 6 ? 6 : 1;
  const auto unb = static_cast<std::size_t>(nb);
  // Runs of consecutive rows with the same columns (the points of one face,
  // when the caller orders the rows by face): each run is visited once per
  // column it holds, its rows read in order.
  std::vector<std::size_t> run_start;
  for (std::size_t r = 0; r < k; ++r) {
    const bool same = r > 0 && A.indptr[r + 1] - A.indptr[r] == A.indptr[r] - A.indptr[r - 1] &&
                      std::equal(A.indices + A.indptr[r], A.indices + A.indptr[r + 1], A.indices + A.indptr[r - 1]);
    if (!same) run_start.push_back(r);
  }
  run_start.push_back(k);
  const std::size_t n_runs = run_start.size() - 1;
  // The runs' columns (A^T's rows over runs): for column j, (run, position of j in the run's columns).
  std::vector<std::int64_t> col_ptr(n + 1, 0);
  for (std::size_t q = 0; q < n_runs; ++q)
    for (std::int32_t p = A.indptr[run_start[q]]; p < A.indptr[run_start[q] + 1]; ++p)
      ++col_ptr[static_cast<std::size_t>(A.indices[p]) + 1];
  for (std::size_t j = 0; j < n; ++j) col_ptr[j + 1] += col_ptr[j];
  std::vector<std::int32_t> col_runs(static_cast<std::size_t>(col_ptr[n]));
  std::vector<std::int32_t> col_pos(col_runs.size());
  {
    std::vector<std::int64_t> next(col_ptr.begin(), col_ptr.end() - 1);
    for (std::size_t q = 0; q < n_runs; ++q) {
      const std::int32_t p0 = A.indptr[run_start[q]];
      for (std::int32_t p = p0; p < A.indptr[run_start[q] + 1]; ++p) {
        const auto slot = static_cast<std::size_t>(next[static_cast<std::size_t>(A.indices[p])]++);
        col_runs[slot] = static_cast<std::int32_t>(q);
        col_pos[slot] = p - p0;
      }
    }
  }
  poll_interrupt();
  // Row i of A^T W A on and above the diagonal from the runs holding column i (Gustavson; a run's columns are
  // sorted, so those >= i are its positions from i's on), a range of the rows' order `visit` per task.
  // Tasks by the work (the rows' stored entries) as well as by the rows, so that few rows with many points share
  // the work too.
  const auto nnz_rows = static_cast<std::size_t>(A.indptr[k]);
  const int tasks = static_cast<int>(std::clamp<std::size_t>(std::min(nnz_rows / kRowEntriesPerTask, n / 16), 1,
                                                             static_cast<std::size_t>(detail::available_processors())));
  // The rows in the order the runs first hold them (then those no run holds): consecutive rows share runs, whose
  // rows of A are then read again from the cache. Each row's sums (over its runs in their order) are the same in
  // any order of the rows.
  std::vector<std::int32_t> visit;
  visit.reserve(n);
  {
    std::vector<char> seen(n, 0);
    for (std::size_t q = 0; q < n_runs; ++q)
      for (std::int32_t p = A.indptr[run_start[q]]; p < A.indptr[run_start[q] + 1]; ++p) {
        const auto j = static_cast<std::size_t>(A.indices[p]);
        if (!seen[j]) {
          seen[j] = 1;
          visit.push_back(static_cast<std::int32_t>(j));
        }
      }
    for (std::size_t j = 0; j < n; ++j)
      if (!seen[j]) visit.push_back(static_cast<std::int32_t>(j));
  }
  // Column j's place in `visit`: a row's sums are held at their columns' places, near one another as the rows are.
  std::vector<std::int32_t> place(n);
  for (std::size_t s = 0; s < n; ++s) place[static_cast<std::size_t>(visit[s])] = static_cast<std::int32_t>(s);
  Upper up;
  up.part_idx.resize(static_cast<std::size_t>(tasks));
  up.part_val.resize(static_cast<std::size_t>(tasks));
  up.row_len.assign(n, 0);
  up.row_task.assign(n, 0);
  up.row_at.assign(n, 0);
  detail::for_each_task(tasks > 1, tasks, [&](int t) {
    const std::size_t first = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(tasks);
    const std::size_t last = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(tasks);
    std::vector<std::int32_t> marker(n, -1), touched;
    std::vector<double> acc(n * unb, 0.0), row, scaled;
    auto& out_idx = up.part_idx[static_cast<std::size_t>(t)];
    auto& out_val = up.part_val[static_cast<std::size_t>(t)];
    for (std::size_t s = first; s < last; ++s) {
      const auto i = static_cast<std::size_t>(visit[s]);
      if (t == 0 && (s - first) % 1024 == 0) poll_interrupt();
      touched.clear();
      double y[3] = {0.0, 0.0, 0.0};  // row i of A^T x
      for (std::int64_t q = col_ptr[i]; q < col_ptr[i + 1]; ++q) {
        const auto run = static_cast<std::size_t>(col_runs[static_cast<std::size_t>(q)]);
        const std::int32_t li = col_pos[static_cast<std::size_t>(q)];
        const std::size_t r0 = run_start[run], r1 = run_start[run + 1];
        const std::int32_t m = A.indptr[r0 + 1] - A.indptr[r0];
        const std::int32_t* cols = A.indices + A.indptr[r0];
        const auto width = static_cast<std::size_t>(m - li);
        if (with_rhs)
          for (std::size_t r = r0; r < r1; ++r) {
            const double a = A.data[A.indptr[r] + li];
            for (std::size_t c = 0; c < 3; ++c) y[c] += a * x[3 * r + c];
          }
        // Row li of the run's Gram matrix from column li on, sum_r w_r a_r[li] a_r[li:] ((width, nb) row-major),
        // added at its columns.
        row.assign(width * unb, 0.0);
        if (nb == 6)
          gram_row<6>(A, weights, r0, r1, li, width, row.data(), scaled);
        else
          gram_row<1>(A, weight_count == 0 ? nullptr : weights, r0, r1, li, width, row.data(), scaled);
        for (std::size_t b = 0; b < width; ++b) {
          const std::int32_t j = cols[static_cast<std::size_t>(li) + b];
          const auto at = static_cast<std::size_t>(place[static_cast<std::size_t>(j)]);
          double* dst = &acc[at * unb];
          if (marker[at] != static_cast<std::int32_t>(i)) {
            marker[at] = static_cast<std::int32_t>(i);
            touched.push_back(j);
            std::fill(dst, dst + nb, 0.0);
          }
          for (std::size_t c = 0; c < unb; ++c) dst[c] += row[b * unb + c];
        }
      }
      if (with_rhs) std::copy_n(y, 3, rhs + 3 * i);
      std::sort(touched.begin(), touched.end());
      up.row_len[i] = static_cast<std::int64_t>(touched.size());
      up.row_task[i] = t;
      up.row_at[i] = static_cast<std::int64_t>(out_idx.size());
      for (const std::int32_t j : touched) {
        out_idx.push_back(j);
        const double* src = &acc[static_cast<std::size_t>(place[static_cast<std::size_t>(j)]) * unb];
        out_val.insert(out_val.end(), src, src + nb);
      }
    }
  });
  // The whole matrix: row i is the mirrored entries (j, i) of the rows j < i, in order of j, then row i's own.
  NormalMatrix M;
  M.n = n;
  M.blocks = nb;
  std::vector<std::int64_t> lower(n + 1, 0);
  for (const auto& idx : up.part_idx)
    for (const std::int32_t j : idx) ++lower[static_cast<std::size_t>(j) + 1];
  // lower[j + 1] counts the upper entries in column j, the diagonal among them
  M.indptr.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    M.indptr[i + 1] = M.indptr[i] + (up.row_len[i] == 0 ? 0 : up.row_len[i] + lower[i + 1] - 1);
  const auto nnz = static_cast<std::size_t>(M.indptr[n]);
  M.indices.resize(nnz);
  M.values.resize(nnz * unb);
  std::vector<std::int64_t> next_lower(M.indptr.begin(), M.indptr.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    if (up.row_len[i] == 0) continue;  // a column no row reaches
    const auto& idx = up.part_idx[static_cast<std::size_t>(up.row_task[i])];
    const auto& val = up.part_val[static_cast<std::size_t>(up.row_task[i])];
    auto p = static_cast<std::size_t>(up.row_at[i]);
    auto own = static_cast<std::size_t>(M.indptr[i + 1] - up.row_len[i]);
    for (std::int64_t e = 0; e < up.row_len[i]; ++e, ++p, ++own) {
      const auto j = static_cast<std::size_t>(idx[p]);
      M.indices[own] = idx[p];
      std::copy(&val[p * unb], &val[p * unb] + nb, &M.values[own * unb]);
      if (j == i) continue;
      const auto slot = static_cast<std::size_t>(next_lower[j]++);
      M.indices[slot] = static_cast<std::int32_t>(i);
      std::copy(&val[p * unb], &val[p * unb] + nb, &M.values[slot * unb]);
    }
  }
  return M;
}

void blend_weights(const double* points, const double* normals, const double* row_weights, std::size_t k,
                   double tangential, double* weights, double* weighted_points) {
  for (std::size_t r = 0; r < k; ++r) {
    const double* nr = normals + 3 * r;
    const double* pr = points + 3 * r;
    const double w = row_weights == nullptr ? 1.0 : row_weights[r];
    const bool normal = nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2] > 0.0;  // false for zero and NaN
    const double c = normal ? (1.0 - tangential) * w : 0.0;                     // the n n^T part
    const double d = normal ? tangential * w : w;                               // the identity part
    const double n0 = normal ? nr[0] : 0.0, n1 = normal ? nr[1] : 0.0, n2 = normal ? nr[2] : 0.0;
    double* out = weights + 6 * r;
    out[0] = c * n0 * n0 + d;
    out[1] = c * n0 * n1;
    out[2] = c * n0 * n2;
    out[3] = c * n1 * n1 + d;
    out[4] = c * n1 * n2;
    out[5] = c * n2 * n2 + d;
    const double np = c * (n0 * pr[0] + n1 * pr[1] + n2 * pr[2]);
    weighted_points[3 * r] = d * pr[0] + np * n0;
    weighted_points[3 * r + 1] = d * pr[1] + np * n1;
    weighted_points[3 * r + 2] = d * pr[2] + np * n2;
  }
}

NormalEquations::NormalEquations(NormalMatrix normal, CsrMatrix fairness_matrix, double fairness, double proximal)
    : n_(std::move(normal)), k_(std::move(fairness_matrix)) {
  if (n_.blocks != 1 && n_.blocks != 6)
    throw ParameterError("the normal matrix must have 1 or 6 values per entry, got " + std::to_string(n_.blocks));
  if (k_.n_rows != 0 && (k_.n_rows != n_.n || k_.n_cols != n_.n))
    throw ParameterError("the fairness matrix is " + std::to_string(k_.n_rows) + " x " + std::to_string(k_.n_cols) +
                         " but the cage has " + std::to_string(n_.n) + " vertices");
  const auto nb = static_cast<std::size_t>(n_.blocks);
  double sum = 0.0;
  for (std::size_t i = 0; i < n_.n; ++i)
    for (std::int64_t p = n_.indptr[i]; p < n_.indptr[i + 1]; ++p)
      if (static_cast<std::size_t>(n_.indices[static_cast<std::size_t>(p)]) == i) {
        const double* v = &n_.values[static_cast<std::size_t>(p) * nb];
        sum += nb == 1 ? v[0] : v[0] + v[3] + v[5];
      }
  const double per = static_cast<double>(n_.n) * (nb == 1 ? 1.0 : 3.0);
  mean_diagonal_ = n_.n > 0 && sum != 0.0 ? sum / per : 1.0;
  mu_ = proximal * mean_diagonal_;
  c_ = fairness * mean_diagonal_;
}

void NormalEquations::apply(const double* x, double* out, int threads) const {
  const std::size_t n = n_.n;
  const std::size_t entries = n_.indices.size() + k_.indices.size();
  const int tasks = static_cast<int>(std::clamp<std::size_t>(entries / kEntriesPerTask, 1,
                                                             static_cast<std::size_t>(std::max(threads, 1))));
  const bool blocks = n_.blocks == 6;
  const bool has_k = k_.n_rows != 0;
  detail::for_each_index(tasks > 1, tasks, n, [&](std::size_t i) {
    double s0 = mu_ * x[3 * i], s1 = mu_ * x[3 * i + 1], s2 = mu_ * x[3 * i + 2];
    for (std::int64_t p = n_.indptr[i]; p < n_.indptr[i + 1]; ++p) {
      const auto up = static_cast<std::size_t>(p);
      const double* xj = x + 3 * static_cast<std::size_t>(n_.indices[up]);
      if (!blocks) {
        const double w = n_.values[up];
        s0 += w * xj[0];
        s1 += w * xj[1];
        s2 += w * xj[2];
        continue;
      }
      const double* b = &n_.values[6 * up];  // xx, xy, xz, yy, yz, zz
      s0 += b[0] * xj[0] + b[1] * xj[1] + b[2] * xj[2];
      s1 += b[1] * xj[0] + b[3] * xj[1] + b[4] * xj[2];
      s2 += b[2] * xj[0] + b[4] * xj[1] + b[5] * xj[2];
    }
    if (has_k) {
      double k0 = 0.0, k1 = 0.0, k2 = 0.0;
      for (std::int32_t p = k_.indptr[i]; p < k_.indptr[i + 1]; ++p) {
        const double w = k_.data[static_cast<std::size_t>(p)];
        const double* xj = x + 3 * static_cast<std::size_t>(k_.indices[static_cast<std::size_t>(p)]);
        k0 += w * xj[0];
        k1 += w * xj[1];
        k2 += w * xj[2];
      }
      s0 += c_ * k0;
      s1 += c_ * k1;
      s2 += c_ * k2;
    }
    out[3 * i] = s0;
    out[3 * i + 1] = s1;
    out[3 * i + 2] = s2;
  });
}

PcgResult NormalEquations::solve(const double* rhs, double* x, double rtol, long long max_iter, int threads) const {
  if (threads < 1) threads = detail::available_processors();
  const std::size_t n = n_.n;
  const bool blocks = n_.blocks == 6;
  // The diagonal (blocks) of the whole matrix, inverted.
  BlockDiagonal precondition;
  (blocks ? precondition.blocks : precondition.scalars).assign(blocks ? 9 * n : n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double shift = mu_;
    if (k_.n_rows != 0) {
      const auto* first = k_.indices.data() + k_.indptr[i];
      const auto* last = k_.indices.data() + k_.indptr[i + 1];
      const auto* it = std::lower_bound(first, last, static_cast<std::int32_t>(i));
      if (it != last && static_cast<std::size_t>(*it) == i)
        shift += c_ * k_.data[static_cast<std::size_t>(it - k_.indices.data())];
    }
    double d[6] = {shift, 0.0, 0.0, shift, 0.0, shift};
    for (std::int64_t p = n_.indptr[i]; p < n_.indptr[i + 1]; ++p)
      if (static_cast<std::size_t>(n_.indices[static_cast<std::size_t>(p)]) == i) {
        const double* v = &n_.values[static_cast<std::size_t>(p) * static_cast<std::size_t>(n_.blocks)];
        if (!blocks) {
          d[0] += v[0];
        } else {
          for (int c = 0; c < 6; ++c) d[c] += v[c];
        }
      }
    if (!blocks) {
      precondition.scalars[i] = d[0] > 0.0 ? 1.0 / d[0] : 1.0;
      continue;
    }
    // The inverse of the symmetric block [[a, b, c], [b, e, f], [c, f, g]] by its adjugate.
    const double a = d[0], b = d[1], c = d[2], e = d[3], f = d[4], g = d[5];
    const double A00 = e * g - f * f, A01 = c * f - b * g, A02 = b * f - c * e;
    const double A11 = a * g - c * c, A12 = b * c - a * f, A22 = a * e - b * b;
    const double det = a * A00 + b * A01 + c * A02;
    double* inv = &precondition.blocks[9 * i];
    if (det > 0.0 && std::isfinite(det)) {
      const double s = 1.0 / det;
      const double m[9] = {A00, A01, A02, A01, A11, A12, A02, A12, A22};
      for (int q = 0; q < 9; ++q) inv[q] = s * m[q];
    } else {  // not positive definite in rounding: the diagonal alone
      inv[0] = a > 0.0 ? 1.0 / a : 1.0;
      inv[4] = e > 0.0 ? 1.0 / e : 1.0;
      inv[8] = g > 0.0 ? 1.0 / g : 1.0;
    }
  }
  std::vector<double> xv(x, x + 3 * n), r(3 * n);
  apply(xv.data(), r.data(), threads);
  for (std::size_t i = 0; i < 3 * n; ++i) r[i] = rhs[i] - r[i];
  // The stop: each system's residual norm below rtol times its start's, or 1e-15 times its right-hand side's.
  const std::size_t systems = blocks ? 1 : 3;
  std::vector<double> limit(systems, 0.0), rhs2(systems, 0.0);
  for (std::size_t i = 0; i < 3 * n; ++i) {
    limit[blocks ? 0 : i % 3] += r[i] * r[i];
    rhs2[blocks ? 0 : i % 3] += rhs[i] * rhs[i];
  }
  for (std::size_t s = 0; s < systems; ++s)
    limit[s] = std::max(rtol * std::sqrt(limit[s]), 1e-15 * std::sqrt(rhs2[s]));
  const auto stop = [&](const PcgProgress& progress) -> std::string {
    for (std::size_t s = 0; s < systems; ++s)
      if (progress.active[s] && std::sqrt(progress.rr[s]) > limit[s]) return {};
    return "converged";
  };
  const PcgResult out = pcg(
      n, 3, blocks, [&](const std::vector<double>& p, std::vector<double>& q) { apply(p.data(), q.data(), threads); },
      precondition, stop, xv, r, max_iter, threads);
  std::copy(xv.begin(), xv.end(), x);
  return out;
}

}  // namespace sorpia
