#pragma once
// B x, the one product of the limit operator with (n, k) data: used by
// sorpia::apply (limit_operator.cpp) and by every solver. Not a public header
// (sorpia/detail/ headers are the layers' shared internals).
#include <cstddef>
#include <cstdint>

#include "sorpia/limit_operator.hpp"

namespace sorpia {
namespace detail {

// y = B x for C interleaved columns (C = 3: vertices; C = 1: a scalar field).
// Uniform rows: diag x_i + weight (sum of the neighbours), in neighbour order.
template <int C>
inline void apply_cols(const LimitOperator& op, const double* x, double* y) {
  const std::int32_t* off = op.offsets.data();
  const std::int32_t* nb = op.neighbors.data();
  if (op.uniform()) {
    for (std::size_t i = 0; i < op.n; ++i) {
      double s[C] = {};
      for (std::int32_t p = off[i]; p < off[i + 1]; ++p)
        for (int c = 0; c < C; ++c) s[c] += x[C * nb[p] + c];
      for (int c = 0; c < C; ++c) y[C * i + c] = op.diag[i] * x[C * i + c] + op.weight[i] * s[c];
    }
    return;
  }
  const double* val = op.values.data();
  for (std::size_t i = 0; i < op.n; ++i) {
    double s[C] = {};
    for (std::int32_t p = off[i]; p < off[i + 1]; ++p)
      for (int c = 0; c < C; ++c) s[c] += val[p] * x[C * nb[p] + c];
    for (int c = 0; c < C; ++c) y[C * i + c] = op.diag[i] * x[C * i + c] + s[c];
  }
}

// (B v)_i for (n, 3) rows of v, written to bv[0..3): the formula of apply_cols<3>.
inline void row_product(const LimitOperator& op, const double* v, std::size_t i, double* bv) {
  double s[3] = {0.0, 0.0, 0.0};
  if (op.uniform()) {
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
      const double* q = v + 3 * op.neighbors[p];
      s[0] += q[0];
      s[1] += q[1];
      s[2] += q[2];
    }
    for (int c = 0; c < 3; ++c) bv[c] = op.diag[i] * v[3 * i + c] + op.weight[i] * s[c];
    return;
  }
  for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
    const double* q = v + 3 * op.neighbors[p];
    const double w = op.values[p];
    s[0] += w * q[0];
    s[1] += w * q[1];
    s[2] += w * q[2];
  }
  for (int c = 0; c < 3; ++c) bv[c] = op.diag[i] * v[3 * i + c] + s[c];
}

// (B v)_i for (n, k) rows of v, any k, written to bv[0..k): the formula of
// apply_cols<k> (for k = 3 that of row_product). K: k known at compile time
// (K = k), or 0 for k at run time.
template <int K = 0>
inline void row_product_cols(const LimitOperator& op, const double* v, std::size_t k_run, std::size_t i, double* bv) {
  const std::size_t k = K ? static_cast<std::size_t>(K) : k_run;
  for (std::size_t c = 0; c < k; ++c) bv[c] = 0.0;
  for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) {
    const double* q = v + k * static_cast<std::size_t>(op.neighbors[p]);
    if (op.uniform()) {
      for (std::size_t c = 0; c < k; ++c) bv[c] += q[c];
    } else {
      const double w = op.values[p];
      for (std::size_t c = 0; c < k; ++c) bv[c] += w * q[c];
    }
  }
  const double d = op.diag[i], w = op.uniform() ? op.weight[i] : 1.0;
  for (std::size_t c = 0; c < k; ++c) bv[c] = d * v[k * i + c] + (op.uniform() ? w * bv[c] : bv[c]);
}

// y = B x for (n, k) x and y, any k >= 1: apply_cols<k> for the small k,
// row_product_cols beyond.
inline void apply_columns(const LimitOperator& op, std::size_t k, const double* x, double* y) {
  switch (k) {
    case 1: apply_cols<1>(op, x, y); return;
    case 2: apply_cols<2>(op, x, y); return;
    case 3: apply_cols<3>(op, x, y); return;
    case 4: apply_cols<4>(op, x, y); return;
    default:
      for (std::size_t i = 0; i < op.n; ++i) row_product_cols(op, x, k, i, y + k * i);
  }
}

}  // namespace detail
}  // namespace sorpia
