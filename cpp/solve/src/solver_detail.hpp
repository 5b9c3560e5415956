#pragma once
// Kernels and the stopping monitor shared by the solver files (solvers.cpp,
// solver_krylov.cpp, spectral.cpp). Not a public header.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/interrupt.hpp"
#include "sorpia/detail/apply.hpp"
#include "sorpia/detail/scaling.hpp"
#include "sorpia/solvers.hpp"

namespace sorpia {
namespace detail {

// B^T in CSR: the rows of B^T hold, for column j of B, every row i referencing j
// with its weight w_i. Built once per solve that needs it (HSS).
struct Transposed {
  std::vector<std::int32_t> offsets, rows;
  std::vector<double> values;
};
Transposed transpose(const LimitOperator& op);

// y = B^T x for (n, k) x and y.
inline void apply_transpose_columns(const LimitOperator& op, const Transposed& t, std::size_t k, const double* x,
                                    double* y) {
  for (std::size_t j = 0; j < op.n; ++j) {
    double* yj = y + k * j;
    for (std::size_t c = 0; c < k; ++c) yj[c] = 0.0;
    for (std::int32_t p = t.offsets[j]; p < t.offsets[j + 1]; ++p)
      for (std::size_t c = 0; c < k; ++c) yj[c] += t.values[p] * x[k * t.rows[p] + c];
    for (std::size_t c = 0; c < k; ++c) yj[c] = op.diag[j] * x[k * j + c] + yj[c];
  }
}

// y = (B x + sign B^T x) / 2 for (n, k) x: H x for sign = 1, S x for sign = -1,
// H and S the symmetric and skew-symmetric parts of B. bx, btx: scratch, x's size.
inline void apply_part(const LimitOperator& op, const Transposed& t, std::size_t k, double sign, const double* x,
                       double* bx, double* btx, double* y) {
  apply_columns(op, k, x, bx);
  apply_transpose_columns(op, t, k, x, btx);
  for (std::size_t q = 0; q < k * op.n; ++q) y[q] = 0.5 * (bx[q] + sign * btx[q]);
}

// Gamma^-1 as a vector (sorpia::symmetriser): B = Gamma Upsilon with Upsilon
// symmetric on closed meshes (paper section 3.2), so B is self-adjoint in the
// inner product <x, y> = sum_i x_i y_i / gamma_i, and Gamma^-1 B = Upsilon is
// the row-scaled system. Uniform rows: 1 / w_i (1 on rows without
// neighbours). Rows with several weights where no such Gamma exists get 1
// (the plain inner product).
inline std::vector<double> gamma_inverse(const LimitOperator& op) {
  std::vector<double> g = symmetriser(op);
  if (g.empty()) g.assign(op.n, 1.0);
  return g;
}

// r = v0 - B v for (n, k) arrays (r may be null: only the norm); returns
// max_i ||r_i|| (the paper's E_k, the Euclidean norm over the k columns).
double residual(const LimitOperator& op, const double* v0, const double* v, double* r, std::size_t k = 3);

// max_i ||r_i|| over the rows of an (n, k) array.
inline double max_row_norm(const double* r, std::size_t n, std::size_t k = 3) {
  double m = 0.0;
  if (k == 3) {
    for (std::size_t i = 0; i < n; ++i) {
      const double e = r[3 * i] * r[3 * i] + r[3 * i + 1] * r[3 * i + 1] + r[3 * i + 2] * r[3 * i + 2];
      m = std::max(m, e);
    }
    return std::sqrt(m);
  }
  for (std::size_t i = 0; i < n; ++i) {
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) e += r[k * i + c] * r[k * i + c];
    m = std::max(m, e);
  }
  return std::sqrt(m);
}

// Seconds this thread has spent computing spectral estimates (not waiting for
// another thread's): solve() reports the part its parameters took.
extern thread_local double estimate_seconds_on_this_thread;

// scale_pow2 and scale_exponent: sorpia/detail/scaling.hpp, the core's one exact scaling by a power of two
// (the methods solve for V0 / 2^e, the iterates those of V0 scaled).

// Records E_k / E_0 and decides when to stop (paper section 5), the same for
// every method. A run whose error grows past divergence_growth(method) times
// the lowest before it, or turns non-finite, stops as diverged (the iterate
// is still finite; solve() then returns the lowest E_k's). E_k at rounding level
// (at most 64 eps max_i ||v_i^0||: nearly flat input, where E_0 itself is
// rounding noise) counts as converged: no method can go below it.
class Monitor {
 public:
  // scale: max_i ||v_i^0||
  Monitor(const SolveOptions& opt, SolveResult& res, double scale)
      : opt_(opt), res_(res), floor_(64.0 * 2.220446049250313e-16 * scale), growth_(divergence_growth(opt.method)) {
    res_.errors.clear();
    // A generous max_iter must not reserve memory it will not use.
    res_.errors.reserve(static_cast<std::size_t>(std::min(opt.max_iter, 4096LL)) + 1);
  }

  // A warm start, given e0 = E_0 of the cold start V^(0) = V0 before
  // start(): E_k / E_0 < tol is then the same guarantee from any start, and
  // start() gets the error of the warm start itself (errors[0]). Returns
  // whether to start from the warm start at all: not when E_0 = 0 (or NaN):
  // V0 solves it exactly, the answer whatever the start.
  bool warm_start(double e0) {
    if (!(e0 > 0.0)) return false;
    reference_ = e0;
    return true;
  }

  // The error of the start (E_0 unless warm_start() gave it); records it as
  // errors[0] and returns true when there is nothing to do (E_0 == 0: V0
  // already solves it; or the start already meets tol).
  bool start(double e) {
    const double e0 = std::isnan(reference_) ? e : reference_;
    res_.initial_error = e0;
    e0_ = e0;
    if (!(e0 > 0.0)) {
      res_.errors.push_back(0.0);
      res_.iterations = 0;
      res_.stop_reason = StopReason::Converged;
      if (opt_.callback) opt_.callback(0, 0.0);
      return true;
    }
    return record(e);
  }

  // The rounding level of E_k, 64 eps max_i ||v_i^0||: no method gets below it.
  double floor() const { return floor_; }

  // Whether record(e) would stop as converged: methods whose E_k comes from
  // an updated residual check the true one before they record it.
  bool converges(double e) const { return e / e0_ < opt_.tol || e <= floor_; }

  // Stops the run for a reason the method found itself ("stalled",
  // "singular") after the last record().
  void finish(StopReason r) { stop(r); }

  // E_k for the next k; returns true to stop. Polls for an interrupt first
  // (once per iteration, on the calling thread, between sweeps).
  bool record(double e) {
    poll_interrupt();
    const double rel = e / e0_;
    const int k = static_cast<int>(res_.errors.size());
    res_.errors.push_back(rel);
    res_.iterations = k;
    const bool asked = opt_.callback && opt_.callback(k, rel);
    if (!std::isfinite(rel) || rel > growth_ * best_) return stop(StopReason::Diverged);
    best_ = std::min(best_, rel);
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
  double growth_;
  double best_ = INFINITY;  // the lowest E_k / E_0 recorded so far
  double e0_ = 0.0;
  double reference_ = NAN;
};

// "sor" and "gs" (solver_sweep.cpp) on (n, 3) data: sweeps of V0 / 2^exponent
// with the fused E_k (or a residual pass when opt.two_pass), on opt.threads
// threads, from V0 or from `initial` (a warm start, (n, 3), scaled alike;
// null: cold); sets res.control_vertices (times 2^exponent), errors,
// iterations, stop reason. Uniform rows and rows with per-entry weights alike.
void solve_sor(const LimitOperator& op, const double* v0, int exponent, const SolveOptions& opt, double omega,
               SolveResult& res, const double* initial = nullptr);

// "sor" and "gs" on (n, k) data with k > 3 (the engine above holds up to 3
// columns; solve() pads fewer to 3): the same row kernels (relax_row,
// apply.hpp) in vertex order on one thread, E_k by a residual pass after each
// sweep, on res.control_vertices (V^(0) on entry).
void solve_sor_columns(const LimitOperator& op, const double* v0, std::size_t k, double omega, Monitor& mon,
                       SolveResult& res);

// The sweep runs its ranges on threads only from this many vertices a thread;
// with fewer, one after the other on the calling thread (the same arithmetic
// in the same order, so the same bits, except that crowded ranges are not
// replaced by slabs). Tests lower it to run small meshes on real threads;
// nothing else changes it.
extern std::size_t sweep_min_vertices_per_thread;

// The Krylov and HSS methods (solver_krylov.cpp) on (n, k) data, iterating on
// res.control_vertices, which holds V^(0) on entry.
void solve_cg(const LimitOperator& op, const double* v0, std::size_t k, Monitor& mon, SolveResult& res);
void solve_gmres(const LimitOperator& op, const double* v0, std::size_t k, Monitor& mon, SolveResult& res);
void solve_cgls(const LimitOperator& op, const double* v0, std::size_t k, Monitor& mon, SolveResult& res);
void solve_hss(const LimitOperator& op, const double* v0, std::size_t k, double alpha, double weight, Monitor& mon,
               SolveResult& res);

}  // namespace detail
}  // namespace sorpia
