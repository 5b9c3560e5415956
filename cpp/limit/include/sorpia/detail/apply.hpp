#pragma once
// The row kernels of the limit operator: (B x)_i, the residual row
// v0_i - (B x)_i and the Gauss-Seidel relaxation of one row (paper eq. 18).
// Every product with B (sorpia::apply, the solvers' residuals and products)
// and every Gauss-Seidel sweep (the sweep engine for any number of columns,
// the local solver) is an instance of these templates, so they all compute
// one formula in one summation order. Not a public header (sorpia/detail/
// headers are the layers' shared internals).
//
// A row of the data is a value of type R: Row<K> for (n, K) arrays, or the
// sweep engine's 4-lane vector. x is read through a callable x(j) giving row
// j as an R. The kernels are always inlined: the sweep engine compiles them
// once for each instruction set, and no copy may stand in for another.
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "sorpia/limit_operator.hpp"

#define SORPIA_ROW_KERNEL __attribute__((always_inline)) inline

namespace sorpia {
namespace detail {

// A LimitOperator's arrays as the row kernels read them: the operator's own
// (rows_of), or a renumbered copy (the sweep engine's).
struct Rows {
  std::size_t n;
  const std::int32_t* offsets;    // n + 1
  const std::int32_t* neighbors;
  const double* diag;
  const double* weight;           // uniform rows: one weight per row
  const double* values;           // rows with several weights: one per entry of neighbors; else null
  bool uniform() const { return values == nullptr; }
};

inline Rows rows_of(const LimitOperator& op) {
  return {op.n,           op.offsets.data(), op.neighbors.data(), op.diag.data(), op.weight.data(),
          op.uniform() ? nullptr : op.values.data()};
}

// The kinds of rows, as template arguments: one weight per row (every Loop
// row) or one per entry.
struct UniformRows {
  static constexpr bool uniform = true;
};
struct PerEntryRows {
  static constexpr bool uniform = false;
};

// f(UniformRows{}) or f(PerEntryRows{}) by op's kind: the choice made once
// for a whole loop.
template <class F>
decltype(auto) with_row_kind(const Rows& op, F&& f) {
  if (op.uniform()) return f(UniformRows{});
  return f(PerEntryRows{});
}

// One row of K columns (K known at compile time) as a value, with the
// arithmetic the kernels use, column by column.
template <int K>
struct Row {
  double c[K];
  static SORPIA_ROW_KERNEL Row load(const double* p) {
    Row r;
    for (int a = 0; a < K; ++a) r.c[a] = p[a];
    return r;
  }
  SORPIA_ROW_KERNEL void store(double* p) const {
    for (int a = 0; a < K; ++a) p[a] = c[a];
  }
  SORPIA_ROW_KERNEL Row& operator+=(const Row& o) {
    for (int a = 0; a < K; ++a) c[a] += o.c[a];
    return *this;
  }
  friend SORPIA_ROW_KERNEL Row operator+(Row x, const Row& y) { return x += y; }
  friend SORPIA_ROW_KERNEL Row operator-(Row x, const Row& y) {
    for (int a = 0; a < K; ++a) x.c[a] -= y.c[a];
    return x;
  }
  friend SORPIA_ROW_KERNEL Row operator*(double s, Row x) {
    for (int a = 0; a < K; ++a) x.c[a] = s * x.c[a];
    return x;
  }
};

// ||r||^2, the columns in order.
template <int K>
SORPIA_ROW_KERNEL double norm2(const Row<K>& r) {
  double e = 0.0;
  for (int a = 0; a < K; ++a) e += r.c[a] * r.c[a];
  return e;
}

// Row j of an (n, K) array, or column `col` of an (n, stride) array as Row<1>.
template <int K>
struct RowReader {
  const double* x;
  std::size_t stride = K, col = 0;
  SORPIA_ROW_KERNEL Row<K> operator()(std::size_t j) const { return Row<K>::load(x + stride * j + col); }
};

// The sum of the neighbours' rows of x (uniform rows), in neighbour order,
// from +0.0.
template <class R, class X>
struct NeighbourSum {
  const Rows& op;
  const X& x;
  template <class I>
  SORPIA_ROW_KERNEL R operator()(I i) const {
    R s{};
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) s += x(op.neighbors[p]);
    return s;
  }
};

// (B x)_i: diag_i x_i + weight_i (the sum of the neighbours) for uniform rows
// (sum(i): that sum, NeighbourSum or a gather giving the same bits), diag_i
// x_i + sum_p values_p x_p, in neighbour order, for per-entry weights.
template <class Kind, class R, class X, class I, class Sum>
SORPIA_ROW_KERNEL R row_product(const Rows& op, const X& x, I i, const Sum& sum) {
  if constexpr (Kind::uniform) {
    const R s = sum(i);  // first: the gather is the long part, the diagonal term waits for it
    return op.diag[i] * x(i) + op.weight[i] * s;
  } else {
    R s{};
    for (std::int32_t p = op.offsets[i]; p < op.offsets[i + 1]; ++p) s += op.values[p] * x(op.neighbors[p]);
    return op.diag[i] * x(i) + s;
  }
}

template <class Kind, class R, class X, class I>
SORPIA_ROW_KERNEL R row_product(const Rows& op, const X& x, I i) {
  return row_product<Kind, R>(op, x, i, NeighbourSum<R, X>{op, x});
}

// The Gauss-Seidel relaxation of row i given its residual r_i = v0_i - (B
// x)_i (paper eq. 18): x_i += omega r_i / diag_i. relaxation_factor: omega /
// diag_i; relaxation: the change of x_i, that factor times r_i.
template <class I>
SORPIA_ROW_KERNEL double relaxation_factor(const Rows& op, I i, double omega) {
  return omega / op.diag[i];
}

template <class R, class I>
SORPIA_ROW_KERNEL R relaxation(const Rows& op, I i, double omega, const R& r) {
  return relaxation_factor(op, i, omega) * r;
}

// The same, the residual from x as it is now: one row of a sweep.
template <class Kind, class R, class X, class I, class Sum>
SORPIA_ROW_KERNEL R relaxation(const Rows& op, const X& x, const R& v0_i, I i, double omega, const Sum& sum) {
  return relaxation(op, i, omega, v0_i - row_product<Kind, R>(op, x, i, sum));
}

// (n, k) arrays, K = k known at compile time or 0 for k at run time (then
// column by column: the columns of B x are independent, so the same bits).

// r_i = v0_i - (B v)_i into r[0..k) (r may be null); returns ||r_i||^2.
template <int K, class Kind>
SORPIA_ROW_KERNEL double residual_row(const Rows& op, const double* v0, const double* v, std::size_t k,
                                      std::size_t i, double* r) {
  if constexpr (K > 0) {
    const RowReader<K> x{v};
    const Row<K> ri = Row<K>::load(v0 + K * i) - row_product<Kind, Row<K>>(op, x, i);
    if (r) ri.store(r);
    return norm2(ri);
  } else {
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) {
      const RowReader<1> x{v, k, c};
      const double rc = v0[k * i + c] - row_product<Kind, Row<1>>(op, x, i).c[0];
      if (r) r[c] = rc;
      e += rc * rc;
    }
    return e;
  }
}

// (B v)_i into bv[0..k).
template <int K, class Kind>
SORPIA_ROW_KERNEL void row_product_cols(const Rows& op, const double* v, std::size_t k, std::size_t i,
                                        double* bv) {
  if constexpr (K > 0) {
    row_product<Kind, Row<K>>(op, RowReader<K>{v}, i).store(bv);
  } else {
    for (std::size_t c = 0; c < k; ++c) bv[c] = row_product<Kind, Row<1>>(op, RowReader<1>{v, k, c}, i).c[0];
  }
}

// One Gauss-Seidel row of (n, k) data in place: v_i += omega (v0_i - (B v)_i) / diag_i.
template <int K, class Kind>
SORPIA_ROW_KERNEL void relax_row(const Rows& op, const double* v0, double* v, std::size_t k, std::size_t i,
                                 double omega) {
  if constexpr (K > 0) {
    const RowReader<K> x{v};
    const Row<K> d = relaxation<Kind, Row<K>>(op, x, Row<K>::load(v0 + K * i), i, omega,
                                                NeighbourSum<Row<K>, RowReader<K>>{op, x});
    (x(i) + d).store(v + K * i);
  } else {
    for (std::size_t c = 0; c < k; ++c) {
      const RowReader<1> x{v, k, c};
      const Row<1> d = relaxation<Kind, Row<1>>(op, x, Row<1>::load(v0 + k * i + c), i, omega,
                                                  NeighbourSum<Row<1>, RowReader<1>>{op, x});
      v[k * i + c] += d.c[0];
    }
  }
}

// f(std::integral_constant<int, K>) with K = k for the small k, else 0.
template <class F>
decltype(auto) with_columns(std::size_t k, F&& f) {
  switch (k) {
    case 1: return f(std::integral_constant<int, 1>{});
    case 2: return f(std::integral_constant<int, 2>{});
    case 3: return f(std::integral_constant<int, 3>{});
    case 4: return f(std::integral_constant<int, 4>{});
    default: return f(std::integral_constant<int, 0>{});
  }
}

// y = B x for (n, k) x and y, any k >= 1.
inline void apply_columns(const LimitOperator& op, std::size_t k, const double* x, double* y) {
  const Rows rows = rows_of(op);
  with_columns(k, [&](auto cols) {
    with_row_kind(rows, [&](auto kind) {
      for (std::size_t i = 0; i < rows.n; ++i) row_product_cols<cols(), decltype(kind)>(rows, x, k, i, y + k * i);
    });
  });
}

}  // namespace detail
}  // namespace sorpia
