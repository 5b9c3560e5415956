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
// Values of the blocks' Gram matrices per task of the assembly, at least.
constexpr std::size_t kGramValuesPerTask = 32768;
// Stored entries of the rows per task of normal_matrix's blocks, at least.
constexpr std::size_t kRowEntriesPerTask = 32768;

// Columns of a block's Gram row summed at once by gram_row, their sums held in registers.
constexpr std::size_t kGramColumns = 4;

// Where row li of a Gram matrix of `width` columns starts among its packed rows on and above the diagonal (in
// entries).
std::size_t packed_row(std::size_t li, std::size_t width) { return li * (2 * width + 1 - li) / 2; }

// out[b * NB + c] = sum over the rows r < count of a block (count, stride) of w_r[c] a_r[li] a_r[li + b],
// b < width, each sum added up over the rows in their order from 0; w_r = weights[NB r ..] (1 when null). The
// weights' count a constant, so that each a_r[li + b] is read once for all NB sums; `scaled` holds w_r[c] a_r[li]
// per row.
template <int NB>
void gram_row(const double* rows, std::size_t stride, std::size_t count, const double* weights, std::size_t li,
              std::size_t width, double* out, std::vector<double>& scaled) {
  scaled.resize(count * NB);
  for (std::size_t r = 0; r < count; ++r) {
    const double a0 = rows[r * stride + li];
    for (int c = 0; c < NB; ++c)
      scaled[r * NB + static_cast<std::size_t>(c)] =
          a0 * (weights == nullptr ? 1.0 : weights[NB * r + static_cast<std::size_t>(c)]);
  }
  // kGramColumns columns at a time (then one at a time), each sum in a register over all the rows.
  const auto columns = [&](std::size_t b, auto n_columns) {
    constexpr std::size_t kCount = decltype(n_columns)::value;
    double acc[kCount][NB] = {};
    for (std::size_t r = 0; r < count; ++r) {
      const double* a = rows + r * stride + li + b;
      const double* w = &scaled[r * NB];
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

NormalBlocks::NormalBlocks(std::size_t n, std::size_t blocks, int weight_count)
    : n_(n), weight_count_(weight_count), blocks_per_entry_(weight_count == 6 ? 6 : 1), blocks_(blocks) {
  if (weight_count != 0 && weight_count != 1 && weight_count != 6)
    throw ParameterError("weight_count must be 0, 1 or 6, got " + std::to_string(weight_count));
}

void NormalBlocks::add(std::size_t b, const std::int32_t* columns, std::size_t width, const double* rows,
                       std::size_t count, const double* weights, const double* x) {
  Block& out = blocks_[b];
  if (count == 0) return;  // no rows: no entries
  out.columns.assign(columns, columns + width);
  const auto nb = static_cast<std::size_t>(blocks_per_entry_);
  out.gram.resize(packed_row(width, width) * nb);
  thread_local std::vector<double> scaled;
  for (std::size_t li = 0; li < width; ++li) {
    double* row = &out.gram[packed_row(li, width) * nb];
    if (nb == 6)
      gram_row<6>(rows, width, count, weights, li, width - li, row, scaled);
    else
      gram_row<1>(rows, width, count, weight_count_ == 0 ? nullptr : weights, li, width - li, row, scaled);
  }
  out.rhs.clear();
  if (x == nullptr) return;
  out.rhs.assign(3 * width, 0.0);
  for (std::size_t r = 0; r < count; ++r)
    for (std::size_t li = 0; li < width; ++li) {
      const double a = rows[r * width + li];
      for (std::size_t c = 0; c < 3; ++c) out.rhs[3 * li + c] += a * x[3 * r + c];
    }
}

NormalMatrix NormalBlocks::assemble(double* rhs) const {
  const std::size_t n = n_, n_blocks = blocks_.size();
  const int nb = blocks_per_entry_;
  const auto unb = static_cast<std::size_t>(nb);
  // The blocks' columns (A^T's rows over blocks): for column j, (block, position of j in the block's columns).
  std::vector<std::int64_t> col_ptr(n + 1, 0);
  std::size_t gram_values = 0;
  for (const Block& q : blocks_) {
    for (const std::int32_t j : q.columns) ++col_ptr[static_cast<std::size_t>(j) + 1];
    gram_values += q.gram.size();
  }
  for (std::size_t j = 0; j < n; ++j) col_ptr[j + 1] += col_ptr[j];
  std::vector<std::int32_t> col_blocks(static_cast<std::size_t>(col_ptr[n]));
  std::vector<std::int32_t> col_pos(col_blocks.size());
  {
    std::vector<std::int64_t> next(col_ptr.begin(), col_ptr.end() - 1);
    for (std::size_t q = 0; q < n_blocks; ++q) {
      const std::vector<std::int32_t>& cols = blocks_[q].columns;
      for (std::size_t p = 0; p < cols.size(); ++p) {
        const auto slot = static_cast<std::size_t>(next[static_cast<std::size_t>(cols[p])]++);
        col_blocks[slot] = static_cast<std::int32_t>(q);
        col_pos[slot] = static_cast<std::int32_t>(p);
      }
    }
  }
  poll_interrupt();
  // Row i of A^T W A on and above the diagonal from the blocks holding column i, in their order (Gustavson; a
  // block's columns are sorted, so those >= i are its positions from i's on), a range of the rows' order `visit`
  // per task.
  const int tasks = static_cast<int>(std::clamp<std::size_t>(std::min(gram_values / kGramValuesPerTask, n / 16), 1,
                                                             static_cast<std::size_t>(detail::available_processors())));
  // The rows in the order the blocks first hold them (then those no block holds): consecutive rows share blocks,
  // whose Gram matrices are then read again from the cache. Each row's sums (over its blocks in their order) are the
  // same in any order of the rows.
  std::vector<std::int32_t> visit;
  visit.reserve(n);
  {
    std::vector<char> seen(n, 0);
    for (const Block& q : blocks_)
      for (const std::int32_t j : q.columns)
        if (!seen[static_cast<std::size_t>(j)]) {
          seen[static_cast<std::size_t>(j)] = 1;
          visit.push_back(j);
        }
    for (std::size_t j = 0; j < n; ++j)
      if (!seen[j]) visit.push_back(static_cast<std::int32_t>(j));
  }
  // Column j's place in `visit`: a row's sums are held at their columns' places, near one another as the rows are.
  std::vector<std::int32_t> place(n);
  for (std::size_t s = 0; s < n; ++s) place[static_cast<std::size_t>(visit[s])] = static_cast<std::int32_t>(s);
  // Pass 1, the pattern: row i's columns on and above the diagonal (sorted) from the blocks holding column i, a
  // range of the rows' order `visit` per task.
  std::vector<std::vector<std::int32_t>> part_idx(static_cast<std::size_t>(tasks));  // per task, its rows' columns
  std::vector<std::int64_t> row_len(n, 0), row_at(n, 0);  // row i's entries: part_idx[row_task[i]][row_at[i] ..]
  std::vector<std::int32_t> row_task(n, 0);
  const auto first_of = [&](int t) { return n * static_cast<std::size_t>(t) / static_cast<std::size_t>(tasks); };
  detail::for_each_task(tasks > 1, tasks, [&](int t) {
    std::vector<std::int32_t> marker(n, -1), touched;
    auto& out_idx = part_idx[static_cast<std::size_t>(t)];
    for (std::size_t s = first_of(t); s < first_of(t + 1); ++s) {
      const auto i = static_cast<std::size_t>(visit[s]);
      if (t == 0 && (s - first_of(t)) % 1024 == 0) poll_interrupt();
      touched.clear();
      for (std::int64_t e = col_ptr[i]; e < col_ptr[i + 1]; ++e) {
        const auto q = static_cast<std::size_t>(col_blocks[static_cast<std::size_t>(e)]);
        const std::vector<std::int32_t>& cols = blocks_[q].columns;
        for (auto b = static_cast<std::size_t>(col_pos[static_cast<std::size_t>(e)]); b < cols.size(); ++b)
          if (marker[static_cast<std::size_t>(cols[b])] != static_cast<std::int32_t>(i)) {
            marker[static_cast<std::size_t>(cols[b])] = static_cast<std::int32_t>(i);
            touched.push_back(cols[b]);
          }
      }
      std::sort(touched.begin(), touched.end());
      row_len[i] = static_cast<std::int64_t>(touched.size());
      row_task[i] = t;
      row_at[i] = static_cast<std::int64_t>(out_idx.size());
      out_idx.insert(out_idx.end(), touched.begin(), touched.end());
    }
  });
  // The whole matrix's pattern: row i is the mirrored entries (j, i) of the rows j < i, in order of j, then row
  // i's own; and where each entry above the diagonal is mirrored (-1 on the diagonal).
  NormalMatrix M;
  M.n = n;
  M.blocks = nb;
  std::vector<std::int64_t> lower(n + 1, 0);
  for (const auto& idx : part_idx)
    for (const std::int32_t j : idx) ++lower[static_cast<std::size_t>(j) + 1];
  // lower[j + 1] counts the upper entries in column j, the diagonal among them
  M.indptr.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    M.indptr[i + 1] = M.indptr[i] + (row_len[i] == 0 ? 0 : row_len[i] + lower[i + 1] - 1);
  const auto nnz = static_cast<std::size_t>(M.indptr[n]);
  M.indices.resize(nnz);
  std::vector<std::vector<std::int64_t>> part_mirror(static_cast<std::size_t>(tasks));
  for (std::size_t t = 0; t < part_idx.size(); ++t) part_mirror[t].resize(part_idx[t].size());
  {
    std::vector<std::int64_t> next_lower(M.indptr.begin(), M.indptr.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& idx = part_idx[static_cast<std::size_t>(row_task[i])];
      auto& mirror = part_mirror[static_cast<std::size_t>(row_task[i])];
      auto p = static_cast<std::size_t>(row_at[i]);
      auto own = static_cast<std::size_t>(M.indptr[i + 1] - row_len[i]);
      for (std::int64_t e = 0; e < row_len[i]; ++e, ++p, ++own) {
        const auto j = static_cast<std::size_t>(idx[p]);
        M.indices[own] = idx[p];
        mirror[p] = -1;
        if (j == i) continue;
        mirror[p] = next_lower[j]++;
        M.indices[static_cast<std::size_t>(mirror[p])] = static_cast<std::int32_t>(i);
      }
    }
  }
  // Pass 2, the values: row i's entries summed over its blocks in their order (the sums held at their columns'
  // places in `visit`, near one another as the rows are), each written to its place and its mirror's.
  M.values.resize(nnz * unb);
  detail::for_each_task(tasks > 1, tasks, [&](int t) {
    std::vector<double> acc(n * unb, 0.0);
    const auto& idx = part_idx[static_cast<std::size_t>(t)];
    const auto& mirror = part_mirror[static_cast<std::size_t>(t)];
    for (std::size_t s = first_of(t); s < first_of(t + 1); ++s) {
      const auto i = static_cast<std::size_t>(visit[s]);
      if (t == 0 && (s - first_of(t)) % 1024 == 0) poll_interrupt();
      const auto p0 = static_cast<std::size_t>(row_at[i]), p1 = p0 + static_cast<std::size_t>(row_len[i]);
      for (std::size_t p = p0; p < p1; ++p) {
        double* dst = &acc[static_cast<std::size_t>(place[static_cast<std::size_t>(idx[p])]) * unb];
        std::fill(dst, dst + nb, 0.0);
      }
      double y[3] = {0.0, 0.0, 0.0};  // row i of A^T x
      for (std::int64_t e = col_ptr[i]; e < col_ptr[i + 1]; ++e) {
        const Block& q = blocks_[static_cast<std::size_t>(col_blocks[static_cast<std::size_t>(e)])];
        const auto li = static_cast<std::size_t>(col_pos[static_cast<std::size_t>(e)]);
        const std::size_t width = q.columns.size();
        if (rhs != nullptr)
          for (std::size_t c = 0; c < 3; ++c) y[c] += q.rhs[3 * li + c];
        // Row li of the block's Gram matrix from column li on, added at its columns.
        const double* row = &q.gram[packed_row(li, width) * unb];
        for (std::size_t b = 0; b < width - li; ++b) {
          double* dst = &acc[static_cast<std::size_t>(place[static_cast<std::size_t>(q.columns[li + b])]) * unb];
          for (std::size_t c = 0; c < unb; ++c) dst[c] += row[b * unb + c];
        }
      }
      if (rhs != nullptr) std::copy_n(y, 3, rhs + 3 * i);
      auto own = static_cast<std::size_t>(M.indptr[i + 1] - row_len[i]);
      for (std::size_t p = p0; p < p1; ++p, ++own) {
        const double* src = &acc[static_cast<std::size_t>(place[static_cast<std::size_t>(idx[p])]) * unb];
        std::copy(src, src + nb, &M.values[own * unb]);
        if (mirror[p] >= 0) std::copy(src, src + nb, &M.values[static_cast<std::size_t>(mirror[p]) * unb]);
      }
    }
  });
  return M;
}

NormalMatrix normal_matrix(const CsrMatrix& rows, const double* weights, int weight_count) {
  return normal_matrix(CsrRows{rows.n_rows, rows.n_cols, rows.indptr.data(), rows.indices.data(), rows.data.data()},
                       weights, weight_count);
}

NormalMatrix normal_matrix(const CsrRows& A, const double* weights, int weight_count, const double* x,
                           double* rhs) {
  const std::size_t k = A.n_rows;
  // Runs of consecutive rows with the same columns: their entries are a dense block (rows, width) in place.
  std::vector<std::size_t> run_start;
  for (std::size_t r = 0; r < k; ++r) {
    const bool same = r > 0 && A.indptr[r + 1] - A.indptr[r] == A.indptr[r] - A.indptr[r - 1] &&
                      std::equal(A.indices + A.indptr[r], A.indices + A.indptr[r + 1], A.indices + A.indptr[r - 1]);
    if (!same) run_start.push_back(r);
  }
  run_start.push_back(k);
  const std::size_t n_runs = run_start.size() - 1;
  NormalBlocks blocks(A.n_cols, n_runs, weight_count);
  const bool with_rhs = x != nullptr && rhs != nullptr;
  const auto nb = static_cast<std::size_t>(weight_count);
  const int tasks = detail::task_count(static_cast<std::size_t>(A.indptr[k]), kRowEntriesPerTask);
  detail::for_each_index(tasks > 1, tasks, n_runs, [&](std::size_t q) {
    const std::size_t r0 = run_start[q], r1 = run_start[q + 1];
    const auto width = static_cast<std::size_t>(A.indptr[r0 + 1] - A.indptr[r0]);
    blocks.add(q, A.indices + A.indptr[r0], width, A.data + A.indptr[r0], r1 - r0,
               weights == nullptr ? nullptr : weights + nb * r0, with_rhs ? x + 3 * r0 : nullptr);
  });
  return blocks.assemble(with_rhs ? rhs : nullptr);
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
