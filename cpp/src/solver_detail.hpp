#pragma once
// Kernels and the stopping monitor shared by the solver files (solvers.cpp,
// solver_krylov.cpp, spectral.cpp). Not a public header.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/interrupt.hpp"
#include "sorpia/solvers.hpp"

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

// B^T in CSR: the rows of B^T hold, for column j of B, every row i referencing j
// with its weight w_i. Built once per solve that needs it (HSS).
struct Transposed {
  std::vector<std::int32_t> offsets, rows;
  std::vector<double> values;
};
Transposed transpose(const LimitOperator& op);

// y = B^T x (C columns).
template <int C>
inline void apply_transpose_cols(const LimitOperator& op, const Transposed& t, const double* x, double* y) {
  for (std::size_t j = 0; j < op.n; ++j) {
    double s[C] = {};
    for (std::int32_t p = t.offsets[j]; p < t.offsets[j + 1]; ++p)
      for (int c = 0; c < C; ++c) s[c] += t.values[p] * x[C * t.rows[p] + c];
    for (int c = 0; c < C; ++c) y[C * j + c] = op.diag[j] * x[C * j + c] + s[c];
  }
}

// y = (B x + sign B^T x) / 2 (C columns): H x for sign = 1, S x for sign = -1,
// H and S the symmetric and skew-symmetric parts of B. bx, btx: scratch, x's size.
template <int C>
inline void apply_part(const LimitOperator& op, const Transposed& t, double sign, const double* x, double* bx,
                       double* btx, double* y) {
  apply_cols<C>(op, x, bx);
  apply_transpose_cols<C>(op, t, x, btx);
  for (std::size_t k = 0; k < C * op.n; ++k) y[k] = 0.5 * (bx[k] + sign * btx[k]);
}

// Gamma^-1 as a vector: 1 / w_i per row (1 on rows without neighbours). B =
// Gamma Upsilon with Upsilon symmetric on closed meshes (paper section 3.2), so
// B is self-adjoint in the inner product <x, y> = sum_i x_i y_i / w_i, and
// Gamma^-1 B = Upsilon is the row-scaled system.
// Rows with several weights have no such Gamma: they get 1 (the plain inner product).
inline std::vector<double> gamma_inverse(const LimitOperator& op) {
  std::vector<double> g(op.n, 1.0);
  if (!op.uniform()) return g;
  for (std::size_t i = 0; i < op.n; ++i) g[i] = op.weight[i] > 0.0 ? 1.0 / op.weight[i] : 1.0;
  return g;
}

// r = v0 - B v (r may be null: only the norm); returns max_i ||r_i|| (the paper's E_k).
double residual(const LimitOperator& op, const double* v0, const double* v, double* r);

inline double max_row_norm(const double* r, std::size_t n) {
  double m = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double e = r[3 * i] * r[3 * i] + r[3 * i + 1] * r[3 * i + 1] + r[3 * i + 2] * r[3 * i + 2];
    m = std::max(m, e);
  }
  return std::sqrt(m);
}

// Seconds this thread has spent computing spectral estimates (not waiting for
// another thread's): solve() reports the part its parameters took.
extern thread_local double estimate_seconds_on_this_thread;

// x[k] *= 2^e for k < n (exactly, or rounded as ldexp rounds a subnormal).
void scale_pow2(double* x, std::size_t n, int e);

// Records E_k / E_0 and decides when to stop (paper section 5), the same for
// every method. A run whose error grows past 1e6 E_0 or turns non-finite
// stops as diverged while the iterate is still finite. E_k at rounding level
// (at most 64 eps max_i ||v_i^0||: nearly flat input, where E_0 itself is
// rounding noise) counts as converged: no method can go below it.
class Monitor {
 public:
  static constexpr double divergence_limit = 1e6;

  // scale: max_i ||v_i^0||
  Monitor(const SolveOptions& opt, SolveResult& res, double scale)
      : opt_(opt), res_(res), floor_(64.0 * 2.220446049250313e-16 * scale) {
    res_.errors.clear();
    // A generous max_iter must not reserve memory it will not use.
    res_.errors.reserve(static_cast<std::size_t>(std::min(opt.max_iter, 4096LL)) + 1);
  }

  // E_0; returns true when there is nothing to do (E_0 == 0: V0 already solves it).
  bool start(double e0) {
    res_.initial_error = e0;
    e0_ = e0;
    if (!(e0 > 0.0)) {
      res_.errors.push_back(0.0);
      res_.iterations = 0;
      res_.stop_reason = StopReason::Converged;
      if (opt_.callback) opt_.callback(0, 0.0);
      return true;
    }
    return record(e0);
  }

  // The rounding level of E_k, 64 eps max_i ||v_i^0||: no method gets below it.
  double floor() const { return floor_; }

  // Whether record(e) would stop as converged: methods whose E_k comes from
  // an updated residual check the true one before they record it.
  bool converges(double e) const { return e / e0_ < opt_.tol || e <= floor_; }

  // E_k for the next k; returns true to stop. Polls for an interrupt first
  // (once per iteration, on the calling thread, between sweeps).
  bool record(double e) {
    poll_interrupt();
    const double rel = e / e0_;
    const int k = static_cast<int>(res_.errors.size());
    res_.errors.push_back(rel);
    res_.iterations = k;
    const bool asked = opt_.callback && opt_.callback(k, rel);
    if (!std::isfinite(rel) || rel > divergence_limit) return stop(StopReason::Diverged);
    if (rel < opt_.tol || e <= floor_) return stop(StopReason::Converged);
    if (asked) return stop(StopReason::Callback);
    if (k >= opt_.max_iter) return stop(StopReason::MaxIter);
    return false;
  }

 private:
  bool stop(StopReason r) {
    res_.stop_reason = r;
    return true;
  }
  const SolveOptions& opt_;
  SolveResult& res_;
  double floor_;
  double e0_ = 0.0;
};

// "sor" and "gs" (solver_sweep.cpp): sweeps of V0 / 2^exponent with the fused
// E_k (or a residual pass when opt.two_pass), on opt.threads threads; sets
// res.control_vertices (times 2^exponent), errors, iterations, stop reason.
// Uniform rows and rows with per-entry weights alike.
void solve_sor(const LimitOperator& op, const double* v0, int exponent, const SolveOptions& opt, double omega,
               SolveResult& res);

// The sweep runs its ranges on threads only from this many vertices a thread;
// with fewer, one after the other on the calling thread (the same arithmetic
// in the same order, so the same bits, except that crowded ranges are not
// replaced by slabs). Tests lower it to run small meshes on real threads;
// nothing else changes it.
extern std::size_t sweep_min_vertices_per_thread;

// The Krylov and HSS methods (solver_krylov.cpp), iterating on
// res.control_vertices, which holds V^(0) on entry.
void solve_cg(const LimitOperator& op, const double* v0, Monitor& mon, SolveResult& res);
void solve_hss(const LimitOperator& op, const double* v0, double alpha, double weight, Monitor& mon,
               SolveResult& res);

}  // namespace detail
}  // namespace sorpia
