#include "sorpia/fair.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/detail/repr.hpp"
#include "sorpia/detail/scaling.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/pcg.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/detail/clock.hpp"

namespace sorpia {

namespace {

using detail::Clock;
using detail::seconds_since;

using Col3 = std::array<double, 3>;

// Rows per task of a product with K below which it runs on one thread.
constexpr std::size_t kRowsPerTask = 20000;

// The constraints eliminated: V_t = g_t - sum_j m_tj V_j for each target t,
// and the transposed entries (for each free j: the targets whose row has j).
struct Elimination {
  std::vector<std::int32_t> targets;          // fine indices
  std::vector<double> g;                      // (k, 3): T_t / B_tt
  std::vector<std::int32_t> offsets, cols;    // rows of m
  std::vector<double> weights;
  std::vector<std::int32_t> t_offsets, t_rows;  // m^T by free vertex: positions in `targets`
  std::vector<double> t_weights;
  std::vector<char> is_target;
};

// K's entry (i, j), by a scan of row i (0 when absent): K's columns may come
// in any order within a row (fairness_matrix's sorted_columns = false).
double entry(const CsrMatrix& k, std::int32_t i, std::int32_t j) {
  for (std::int32_t p = k.indptr[i]; p < k.indptr[i + 1]; ++p)
    if (k.indices[p] == j) return k.data[p];
  return 0.0;
}

class Problem {
 public:
  Problem(const CsrMatrix& k, Elimination&& e, int threads) : k_(k), e_(std::move(e)), threads_(threads) {
    const std::size_t n = k_.n_rows;
    tasks_ = static_cast<int>(std::clamp<std::size_t>(n / kRowsPerTask, 1, static_cast<std::size_t>(threads_)));
    y_.assign(3 * n, 0.0);
  }

  std::size_t n() const { return k_.n_rows; }

  // The full V of the free vertices' values in x (target rows of x ignored),
  // written into v: v = S x + g.
  void expand(const std::vector<double>& x, std::vector<double>& v, bool with_g) const {
    v = x;
    for (std::size_t t = 0; t < e_.targets.size(); ++t) {
      Col3 s{0.0, 0.0, 0.0};
      if (with_g) s = {e_.g[3 * t], e_.g[3 * t + 1], e_.g[3 * t + 2]};
      for (std::int32_t p = e_.offsets[t]; p < e_.offsets[t + 1]; ++p) {
        const double* xj = &x[3 * static_cast<std::size_t>(e_.cols[p])];
        for (int c = 0; c < 3; ++c) s[c] -= e_.weights[p] * xj[c];
      }
      std::copy(s.begin(), s.end(), &v[3 * static_cast<std::size_t>(e_.targets[t])]);
    }
  }

  // out = K v (v and out (n, 3)).
  void apply_k(const std::vector<double>& v, std::vector<double>& out) const {
    out.resize(v.size());
    detail::for_each_index(tasks_ > 1, tasks_, n(), [&](std::size_t i) {
      double a = 0.0, b = 0.0, c = 0.0;
      for (std::int32_t p = k_.indptr[i]; p < k_.indptr[i + 1]; ++p) {
        const double w = k_.data[p];
        const double* x = &v[3 * static_cast<std::size_t>(k_.indices[p])];
        a += w * x[0];
        b += w * x[1];
        c += w * x[2];
      }
      out[3 * i] = a;
      out[3 * i + 1] = b;
      out[3 * i + 2] = c;
    });
  }

  // out = S^T z: z on the free rows, minus m^T z_t, target rows zero.
  void restrict_to_free(std::vector<double>& z) const {
    for (std::size_t t = 0; t < e_.targets.size(); ++t) {
      const double* zt = &z[3 * static_cast<std::size_t>(e_.targets[t])];
      for (std::int32_t p = e_.offsets[t]; p < e_.offsets[t + 1]; ++p) {
        double* zj = &z[3 * static_cast<std::size_t>(e_.cols[p])];
        for (int c = 0; c < 3; ++c) zj[c] -= e_.weights[p] * zt[c];
      }
    }
    for (const std::int32_t t : e_.targets)
      for (int c = 0; c < 3; ++c) z[3 * static_cast<std::size_t>(t) + c] = 0.0;
  }

  // out = A x = S^T K S x (the reduced Hessian, halved).
  void apply(const std::vector<double>& x, std::vector<double>& out) {
    expand(x, y_, false);
    apply_k(y_, out);
    restrict_to_free(out);
  }

  // diag(S^T K S), 0 on target rows: for free j, K_jj - 2 sum_t m_tj K_tj
  // + sum_{t, t'} m_tj m_t'j K_tt' over the targets t, t' whose rows have j,
  // gathered target by target with K's row t spread out once (its entries
  // found by column without a search).
  std::vector<double> diagonal() const {
    std::vector<double> d(n(), 0.0);
    for (std::size_t j = 0; j < n(); ++j)
      if (!e_.is_target[j]) d[j] = entry(k_, static_cast<std::int32_t>(j), static_cast<std::int32_t>(j));
    std::vector<std::int32_t> at(n(), -1);  // column -> its place in K's row t, -1 elsewhere
    const auto k_tj = [&](std::int32_t j) { return at[static_cast<std::size_t>(j)] < 0 ? 0.0 : k_.data[at[j]]; };
    for (std::size_t i = 0; i < e_.targets.size(); ++i) {
      const auto t = static_cast<std::size_t>(e_.targets[i]);
      for (std::int32_t p = k_.indptr[t]; p < k_.indptr[t + 1]; ++p) at[static_cast<std::size_t>(k_.indices[p])] = p;
      for (std::int32_t q = e_.offsets[i]; q < e_.offsets[i + 1]; ++q) {
        const auto j = static_cast<std::size_t>(e_.cols[q]);
        const double w = e_.weights[q];
        double s = -2.0 * w * k_tj(e_.cols[q]);
        for (std::int32_t r = e_.t_offsets[j]; r < e_.t_offsets[j + 1]; ++r)
          s += w * e_.t_weights[r] * k_tj(e_.targets[e_.t_rows[r]]);
        d[j] += s;
      }
      for (std::int32_t p = k_.indptr[t]; p < k_.indptr[t + 1]; ++p) at[static_cast<std::size_t>(k_.indices[p])] = -1;
    }
    return d;
  }

  const Elimination& elimination() const { return e_; }

 private:
  const CsrMatrix& k_;
  Elimination e_;
  int threads_;
  int tasks_ = 1;
  std::vector<double> y_;
};

Col3 dots(const std::vector<double>& a, const std::vector<double>& b) {
  Col3 s{0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < a.size(); i += 3)
    for (int c = 0; c < 3; ++c) s[c] += a[i + c] * b[i + c];
  return s;
}

double energy_of(const Problem& problem, const std::vector<double>& v, std::vector<double>& kv) {
  problem.apply_k(v, kv);
  const Col3 e = dots(v, kv);
  return e[0] + e[1] + e[2];
}

// The window of the stopping rule after k iterations: k / 5, at least 2 (or
// `window` when smaller) and at most `window`. E_{k-d} - E_k estimates from
// below how far the energy of x_{k-d} is above the minimum (the energy falls
// by the rest of that distance in the iterations to come); the estimate is
// close when the energy falls fast over the window, as it does where the
// iteration needs few steps, and the window grows with the iterations so
// that a slow iteration is judged over as many as before (FairOptions::window).
std::size_t energy_window(long long k, int window) {
  return static_cast<std::size_t>(std::clamp<long long>(k / 5, std::min(2, window), window));
}

void check_options(const FairOptions& o) {
  if (!(o.tol > 0.0 && std::isfinite(o.tol)))
    throw ParameterError("tol must be a positive finite number, got " + detail::repr(o.tol));
  if (o.window < 1) throw ParameterError("window = " + std::to_string(o.window) + " must be >= 1");
  if (o.max_iter < 1) throw ParameterError("max_iter = " + std::to_string(o.max_iter) + " must be an integer >= 1");
  if (o.threads < 1 || o.threads > max_threads)
    throw ParameterError("threads = " + std::to_string(o.threads) + " must be an integer in 1.." +
                         std::to_string(max_threads));
}

}  // namespace

namespace {

// fair_solve on data whose magnitude is within 2^+-200 (see fair_solve).
FairSolution solve_scaled(const Topology& topology, const Rules& rules, const CsrMatrix& energy,
                          const std::int32_t* targets, std::size_t n_targets, const double* positions,
                          const double* start, const FairOptions& options) {
  const auto t_setup = Clock::now();
  const std::size_t n = topology.n_vertices();
  if (energy.n_rows != n || energy.n_cols != n)
    throw ParameterError("the fairness matrix is " + std::to_string(energy.n_rows) + " x " +
                         std::to_string(energy.n_cols) + " but the mesh has " + std::to_string(n) + " vertices");
  Elimination e;
  e.is_target.assign(n, 0);
  for (std::size_t i = 0; i < n_targets; ++i) {
    const std::int32_t t = targets[i];
    if (t < 0 || static_cast<std::size_t>(t) >= n)
      throw ParameterError("targets[" + std::to_string(i) + "] = " + std::to_string(t) + " is out of range [0, " +
                           std::to_string(n) + ")");
    if (e.is_target[t])
      throw ParameterError("targets[" + std::to_string(i) + "] = " + std::to_string(t) + " is repeated");
    e.is_target[t] = 1;
  }
  const LimitOperator b = limit_operator(topology, rules);
  poll_interrupt();
  e.targets.assign(targets, targets + n_targets);
  e.g.resize(3 * n_targets);
  e.offsets.push_back(0);
  std::vector<std::int32_t> count(n + 1, 0);
  for (std::size_t i = 0; i < n_targets; ++i) {
    const std::int32_t t = targets[i];
    const double d = b.diag[t];
    for (int c = 0; c < 3; ++c) e.g[3 * i + c] = positions[3 * i + c] / d;
    for (std::int32_t p = b.offsets[t]; p < b.offsets[t + 1]; ++p) {
      const double w = b.entry(static_cast<std::size_t>(t), static_cast<std::size_t>(p));
      if (w == 0.0) continue;
      const std::int32_t j = b.neighbors[p];
      if (e.is_target[j])
        throw std::logic_error("targets " + std::to_string(t) + " and " + std::to_string(j) +
                               " share a row of the limit matrix: the constraints are not diagonal");
      e.cols.push_back(j);
      e.weights.push_back(w / d);
      ++count[j + 1];
    }
    e.offsets.push_back(static_cast<std::int32_t>(e.cols.size()));
  }
  for (std::size_t j = 0; j < n; ++j) count[j + 1] += count[j];
  e.t_offsets = count;
  e.t_rows.resize(e.cols.size());
  e.t_weights.resize(e.cols.size());
  for (std::size_t i = 0; i < n_targets; ++i)
    for (std::int32_t p = e.offsets[i]; p < e.offsets[i + 1]; ++p) {
      const std::int32_t slot = count[e.cols[p]]++;
      e.t_rows[slot] = static_cast<std::int32_t>(i);
      e.t_weights[slot] = e.weights[p];
    }

  FairSolution out;
  out.free_vertices = n - n_targets;
  Problem problem(energy, std::move(e), options.threads);
  std::vector<double> diag = problem.diagonal();
  std::vector<double> kv;
  out.start_energy = energy_of(problem, std::vector<double>(start, start + 3 * n), kv);

  // x: the free vertices (target rows zero); V = S x + g.
  std::vector<double> x(start, start + 3 * n), v;
  for (const std::int32_t t : problem.elimination().targets)
    for (int c = 0; c < 3; ++c) x[3 * static_cast<std::size_t>(t) + c] = 0.0;
  problem.expand(x, v, true);
  double e_now = energy_of(problem, v, kv);
  // r = -S^T K V: the negative gradient of E / 2 in the free vertices.
  std::vector<double> r = kv;
  problem.restrict_to_free(r);
  for (double& ri : r) ri = -ri;
  // Jacobi: the inverse of diag(S^T K S), 0 on the target rows (they stay 0).
  BlockDiagonal jacobi;
  jacobi.scalars.resize(n);
  for (std::size_t i = 0; i < n; ++i) jacobi.scalars[i] = diag[i] > 0.0 ? 1.0 / diag[i] : 0.0;
  out.setup_seconds = seconds_since(t_setup);

  const auto t_solve = Clock::now();
  // The energy tracked by the iteration: E_k = E_{k-1} minus each column's step's decrease; the stop rule is the
  // relative change over the last energy_window iterations.
  const auto stop = [&](const PcgProgress& progress) -> std::string {
    if (progress.iteration > 0) {
      for (const double d : progress.decrease) e_now -= d;
      e_now = std::max(e_now, 0.0);
    }
    out.energies.push_back(e_now);
    const std::size_t w = energy_window(static_cast<long long>(out.energies.size()) - 1, options.window);
    if (out.energies.size() > w && out.energies[out.energies.size() - 1 - w] - e_now <= options.tol * e_now)
      return "converged";
    return {};
  };
  const PcgResult run = pcg(
      n, 3, false, [&](const std::vector<double>& pv, std::vector<double>& qv) { problem.apply(pv, qv); }, jacobi,
      stop, x, r, options.max_iter, options.threads);
  out.iterations = run.iterations;
  out.stop_reason = run.stop_reason;
  out.seconds = seconds_since(t_solve);

  problem.expand(x, out.vertices, true);
  out.energy = energy_of(problem, out.vertices, kv);
  // The targets, checked through B's rows.
  for (std::size_t i = 0; i < n_targets; ++i) {
    const std::int32_t t = targets[i];
    Col3 s;
    for (int c = 0; c < 3; ++c) s[c] = b.diag[t] * out.vertices[3 * static_cast<std::size_t>(t) + c];
    for (std::int32_t pp = b.offsets[t]; pp < b.offsets[t + 1]; ++pp) {
      const double wgt = b.entry(static_cast<std::size_t>(t), static_cast<std::size_t>(pp));
      for (int c = 0; c < 3; ++c) s[c] += wgt * out.vertices[3 * static_cast<std::size_t>(b.neighbors[pp]) + c];
    }
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c) d2 += (s[c] - positions[3 * i + c]) * (s[c] - positions[3 * i + c]);
    out.max_error = std::max(out.max_error, std::sqrt(d2));
  }
  return out;
}

}  // namespace

FairSolution fair_solve(const Topology& topology, const Rules& rules, const CsrMatrix& energy,
                        const std::int32_t* targets, std::size_t n_targets, const double* positions,
                        const double* start, const FairOptions& options) {
  check_options(options);
  // The energy squares the coordinates and the iteration multiplies them
  // further: data beyond 2^+-200 in magnitude is solved scaled by a power of
  // two (exact, as sorpia::solve scales its targets: detail/scaling.hpp), the result scaled back.
  const int e = detail::scale_exponent(detail::largest_magnitude(
      start, 3 * topology.n_vertices(), detail::largest_magnitude(positions, 3 * n_targets)));
  if (e == 0) return solve_scaled(topology, rules, energy, targets, n_targets, positions, start, options);
  std::vector<double> p(positions, positions + 3 * n_targets), v(start, start + 3 * topology.n_vertices());
  detail::scale_pow2(p.data(), p.size(), -e);
  detail::scale_pow2(v.data(), v.size(), -e);
  FairSolution out = solve_scaled(topology, rules, energy, targets, n_targets, p.data(), v.data(), options);
  detail::scale_pow2(out.vertices.data(), out.vertices.size(), e);
  out.energy_exponent = 2 * e;  // the energies stay scaled: in the caller's units they may overflow
  out.max_error = std::ldexp(out.max_error, e);
  return out;
}

}  // namespace sorpia
