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
  // A's columns (A^T's rows): for column i, the rows r holding it.
  std::vector<std::int64_t> col_ptr(n + 1, 0);
  for (const std::int32_t j : A.indices) ++col_ptr[static_cast<std::size_t>(j) + 1];
  for (std::size_t j = 0; j < n; ++j) col_ptr[j + 1] += col_ptr[j];
  std::vector<std::int32_t> col_rows(A.indices.size());
  std::vector<double> col_vals(A.indices.size());
  {
    std::vector<std::int64_t> next(col_ptr.begin(), col_ptr.end() - 1);
    for (std::size_t r = 0; r < k; ++r)
      for (std::int32_t p = A.indptr[r]; p < A.indptr[r + 1]; ++p) {
        const auto q = static_cast<std::size_t>(next[static_cast<std::size_t>(A.indices[p])]++);
        col_rows[q] = static_cast<std::int32_t>(r);
        col_vals[q] = A.data[p];
      }
  }
  poll_interrupt();
  // Row i of A^T W A from column i of A (Gustavson), a range of rows per task.
  const int tasks = std::max(1, std::min(detail::available_processors(), static_cast<int>(n / 256 + 1)));
  std::vector<std::vector<std::int32_t>> part_idx(static_cast<std::size_t>(tasks));
  std::vector<std::vector<double>> part_val(static_cast<std::size_t>(tasks));
  std::vector<std::int64_t> row_len(n, 0);
  detail::for_each_task(tasks > 1, tasks, [&](int t) {
    const std::size_t first = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(tasks);
    const std::size_t last = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(tasks);
    std::vector<std::int32_t> marker(n, -1), touched;
    std::vector<double> acc(n * static_cast<std::size_t>(nb), 0.0);
    auto& out_idx = part_idx[static_cast<std::size_t>(t)];
    auto& out_val = part_val[static_cast<std::size_t>(t)];
    for (std::size_t i = first; i < last; ++i) {
      if (t == 0 && (i - first) % 4096 == 0) poll_interrupt();
      touched.clear();
      for (std::int64_t q = col_ptr[i]; q < col_ptr[i + 1]; ++q) {
        const auto r = static_cast<std::size_t>(col_rows[static_cast<std::size_t>(q)]);
        const double a = col_vals[static_cast<std::size_t>(q)];
        double w[6] = {a, 0, 0, 0, 0, 0};
        if (weight_count == 1) w[0] = a * weights[r];
        if (weight_count == 6)
          for (int c = 0; c < 6; ++c) w[c] = a * weights[6 * r + static_cast<std::size_t>(c)];
        for (std::int32_t p = A.indptr[r]; p < A.indptr[r + 1]; ++p) {
          const auto j = static_cast<std::size_t>(A.indices[p]);
          double* dst = &acc[j * static_cast<std::size_t>(nb)];
          if (marker[j] != static_cast<std::int32_t>(i)) {
            marker[j] = static_cast<std::int32_t>(i);
            touched.push_back(static_cast<std::int32_t>(j));
            std::fill(dst, dst + nb, 0.0);
          }
          const double b = A.data[p];
          for (int c = 0; c < nb; ++c) dst[c] += w[c] * b;
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
