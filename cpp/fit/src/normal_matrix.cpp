#include "sorpia/normal_matrix.hpp"

#include <algorithm>
#include <string>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

NormalMatrix normal_matrix(const CsrMatrix& A, const double* weights, int weight_count) {
  if (weight_count != 0 && weight_count != 1 && weight_count != 6)
    throw ParameterError("weight_count must be 0, 1 or 6, got " + std::to_string(weight_count));
  const std::size_t k = A.n_rows, n = A.n_cols;
  const int nb = weight_count == 6 ? 6 : 1;
  // Runs of consecutive rows with the same columns (the points of one face,
  // when the caller orders the rows by face): each run is visited once per
  // column it holds, its rows read in order.
  std::vector<std::size_t> run_start;
  for (std::size_t r = 0; r < k; ++r) {
    const bool same = r > 0 && A.indptr[r + 1] - A.indptr[r] == A.indptr[r] - A.indptr[r - 1] &&
                      std::equal(A.indices.begin() + A.indptr[r], A.indices.begin() + A.indptr[r + 1],
                                 A.indices.begin() + A.indptr[r - 1]);
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
  // Row i of A^T W A from the runs holding column i (Gustavson), a range of rows per task.
  const int tasks = std::max(1, std::min(detail::available_processors(), static_cast<int>(n / 256 + 1)));
  std::vector<std::vector<std::int32_t>> part_idx(static_cast<std::size_t>(tasks));
  std::vector<std::vector<double>> part_val(static_cast<std::size_t>(tasks));
  std::vector<std::int64_t> row_len(n, 0);
  detail::for_each_task(tasks > 1, tasks, [&](int t) {
    const std::size_t first = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(tasks);
    const std::size_t last = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(tasks);
    std::vector<std::int32_t> marker(n, -1), touched;
    std::vector<double> acc(n * static_cast<std::size_t>(nb), 0.0), row;
    auto& out_idx = part_idx[static_cast<std::size_t>(t)];
    auto& out_val = part_val[static_cast<std::size_t>(t)];
    for (std::size_t i = first; i < last; ++i) {
      if (t == 0 && (i - first) % 1024 == 0) poll_interrupt();
      touched.clear();
      for (std::int64_t q = col_ptr[i]; q < col_ptr[i + 1]; ++q) {
        const auto run = static_cast<std::size_t>(col_runs[static_cast<std::size_t>(q)]);
        const std::int32_t li = col_pos[static_cast<std::size_t>(q)];
        const std::size_t r0 = run_start[run], r1 = run_start[run + 1];
        const std::int32_t m = A.indptr[r0 + 1] - A.indptr[r0];
        const std::int32_t* cols = A.indices.data() + A.indptr[r0];
        // Row li of the run's Gram matrix, sum_r w_r a_r[li] a_r, then added at the run's columns.
        row.assign(static_cast<std::size_t>(m) * static_cast<std::size_t>(nb), 0.0);
        for (std::size_t r = r0; r < r1; ++r) {
          const double* a = A.data.data() + A.indptr[r];
          for (int c = 0; c < nb; ++c) {
            const double w = a[li] * (weight_count == 0 ? 1.0 : weights[static_cast<std::size_t>(weight_count) * r +
                                                                         static_cast<std::size_t>(c)]);
            double* dst = row.data() + static_cast<std::size_t>(c) * static_cast<std::size_t>(m);
            for (std::int32_t b = 0; b < m; ++b) dst[b] += w * a[b];
          }
        }
        for (std::int32_t b = 0; b < m; ++b) {
          const auto j = static_cast<std::size_t>(cols[b]);
          double* dst = &acc[j * static_cast<std::size_t>(nb)];
          if (marker[j] != static_cast<std::int32_t>(i)) {
            marker[j] = static_cast<std::int32_t>(i);
            touched.push_back(static_cast<std::int32_t>(j));
            std::fill(dst, dst + nb, 0.0);
          }
          for (int c = 0; c < nb; ++c) dst[c] += row[static_cast<std::size_t>(c) * static_cast<std::size_t>(m) +
                                                     static_cast<std::size_t>(b)];
        }
      }
      std::sort(touched.begin(), touched.end());
      row_len[i] = static_cast<std::int64_t>(touched.size());
      for (const std::int32_t j : touched) {
        out_idx.push_back(j);
        const double* src = &acc[static_cast<std::size_t>(j) * static_cast<std::size_t>(nb)];
        out_val.insert(out_val.end(), src, src + nb);
      }
    }
  });
  NormalMatrix M;
  M.n = n;
  M.blocks = nb;
  M.indptr.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) M.indptr[i + 1] = M.indptr[i] + row_len[i];
  M.indices.reserve(static_cast<std::size_t>(M.indptr[n]));
  M.values.reserve(static_cast<std::size_t>(M.indptr[n]) * static_cast<std::size_t>(nb));
  for (int t = 0; t < tasks; ++t) {
    M.indices.insert(M.indices.end(), part_idx[static_cast<std::size_t>(t)].begin(),
                     part_idx[static_cast<std::size_t>(t)].end());
    M.values.insert(M.values.end(), part_val[static_cast<std::size_t>(t)].begin(),
                    part_val[static_cast<std::size_t>(t)].end());
  }
  return M;
}

}  // namespace sorpia
