// Local re-solves (local_update.hpp): a work-list Gauss-Seidel over the rows
// of B, driven by kept residuals.
//
// Moving target i changes one residual, r_i (r = V0 - B V), and the cold
// residuals (V0 - B V0) of row i and of the rows reading vertex i: B's
// transpose. Relaxing vertex i (eq. 18 at one vertex, omega = 1:
// v_i += r_i / B_ii) zeroes r_i and changes r_j by -B_ji delta for the rows
// j reading i, again B's transpose. A vertex enters the work list when its
// residual reaches the threshold tol * E_0 (and the rounding floor); when
// the list runs dry, every residual changed is recomputed from its row (the
// incremental ones carry rounding) and the rows still at the threshold go
// back to the list. The result meets E / E_0 < tol over the whole mesh: the
// rows never touched keep their residuals, below the threshold unless the
// start was not, and those are in the list from the start.
#include "sorpia/local_update.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include "solver_detail.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {

void MaxTree::assign(const std::vector<double>& values) {
  size_ = 1;
  while (size_ < values.size()) size_ *= 2;
  t_.assign(2 * size_, 0.0);
  std::copy(values.begin(), values.end(), t_.begin() + static_cast<std::ptrdiff_t>(size_));
  for (std::size_t p = size_ - 1; p >= 1; --p) t_[p] = std::max(t_[2 * p], t_[2 * p + 1]);
}

void MaxTree::set(std::size_t i, double value) {
  std::size_t p = size_ + i;
  t_[p] = value;
  for (p /= 2; p >= 1; p /= 2) {
    const double m = std::max(t_[2 * p], t_[2 * p + 1]);
    if (t_[p] == m) break;  // the maxima above are unchanged too
    t_[p] = m;
  }
}

void MaxTree::collect(double threshold, std::vector<std::int32_t>& out) const {
  if (t_.size() < 2 || !(t_[1] >= threshold)) return;
  std::vector<std::size_t> stack{1};
  while (!stack.empty()) {
    const std::size_t p = stack.back();
    stack.pop_back();
    if (p >= size_) {
      out.push_back(static_cast<std::int32_t>(p - size_));
      continue;
    }
    for (std::size_t c : {2 * p + 1, 2 * p})
      if (t_[c] >= threshold) stack.push_back(c);
  }
}

namespace {

// ||x_i||^2 of each row of an (n, k) array.
std::vector<double> row_norms2(const std::vector<double>& x, std::size_t k) {
  std::vector<double> out(x.size() / k);
  for (std::size_t i = 0; i < out.size(); ++i) {
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) e += x[k * i + c] * x[k * i + c];
    out[i] = e;
  }
  return out;
}

}  // namespace

LocalSolver::LocalSolver(const LimitOperator& op) : op_(op), mark_(op.n, 0), logged_(op.n, 0) {
  detail::Transposed t = detail::transpose(op);
  t_offsets_ = std::move(t.offsets);
  t_rows_ = std::move(t.rows);
  t_values_ = std::move(t.values);
}

double LocalSolver::residual_row(const double* v, std::size_t i, double* r) const {
  const detail::Rows rows = detail::rows_of(op_);
  return detail::with_row_kind(rows, [&](auto kind) {
    return detail::residual_row<0, decltype(kind)>(rows, targets_.data(), v, k_, i, r);
  });
}

double LocalSolver::cold_row(std::size_t i) { return residual_row(targets_.data(), i, scratch_.data()); }

void LocalSolver::set_targets(std::vector<double> targets, std::size_t k) {
  if (k < 1 || targets.size() != k * op_.n)
    throw std::logic_error("LocalSolver::set_targets: targets are not (n, k)");
  k_ = k;
  targets_ = std::move(targets);
  scratch_.resize(k);
  std::vector<double> cold(k * op_.n);
  detail::residual(op_, targets_.data(), targets_.data(), cold.data(), k);
  cold_.assign(row_norms2(cold, k));
  target_norm_.assign(row_norms2(targets_, k));
  residual_valid_ = false;
}

// The work list from `work` (the rows at the threshold) until it runs dry
// and every row changed, recomputed from its row, is below the threshold, or
// until max_relaxations (`stopped`). K: the columns when known at compile
// time (3), 0 for k_ at run time; Kind: op_'s rows. Each relaxation and each
// residual recomputed from its row is the row kernels' (apply.hpp), those of
// the full sweep. Returns the relaxations done.
template <int K, class Kind>
long long LocalSolver::relax(double* v, std::vector<std::int32_t>& work, double threshold, double limit,
                             long long max_relaxations, bool& stopped, bool& diverged) {
  const std::size_t k = K ? static_cast<std::size_t>(K) : k_;
  const auto norm2 = [k](const double* x) {
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) e += x[c] * x[c];
    return e;
  };
  const detail::Rows rows = detail::rows_of(op_);
  std::vector<std::int32_t> changed;
  double delta[K ? K : 1];
  std::vector<double> delta_run(K ? 0 : k);
  double* const d = K ? delta : delta_run.data();
  // The arrays as local pointers: stores through v and r would otherwise
  // make the compiler reload every member at each neighbour.
  std::uint8_t* const mark = mark_.data();
  double* const res = r_.data();
  const std::int32_t* const t_off = t_offsets_.data();
  const std::int32_t* const t_rows = t_rows_.data();
  const double* const t_val = t_values_.data();
  for (std::int32_t i : work) mark[i] |= 1;
  long long relaxations = 0;
  while (!work.empty() && !stopped) {
    // The list as a queue: relaxing in the order vertices enter it sweeps
    // outwards from the moved targets, ring by ring. The residuals are kept
    // by increments here, recomputed from their rows below.
    for (std::size_t head = 0; head < work.size(); ++head) {
      const std::size_t i = static_cast<std::size_t>(work[head]);
      mark[i] &= static_cast<std::uint8_t>(~1u);
      double* ri = res + k * i;
      const double e = norm2(ri);
      if (!(e >= threshold)) continue;
      if (relaxations >= max_relaxations || !(e <= limit)) {
        stopped = true;
        diverged = !(e <= limit);
        break;
      }
      ++relaxations;
      if ((relaxations & 4095) == 0) poll_interrupt();
      const double f = detail::relaxation_factor(rows, i, 1.0);
      if (!logged_[i]) log_row(v, i);
      for (std::size_t c = 0; c < k; ++c) {
        d[c] = f * ri[c];
        v[k * i + c] += d[c];
        ri[c] = 0.0;
      }
      if (!(mark[i] & 2)) changed.push_back(static_cast<std::int32_t>(i));
      mark[i] |= 2;
      for (std::int32_t p = t_off[i]; p < t_off[i + 1]; ++p) {
        const std::size_t j = static_cast<std::size_t>(t_rows[p]);
        if (!logged_[j]) log_row(v, j);
        double* rj = res + k * j;
        const double w = t_val[p];
        for (std::size_t c = 0; c < k; ++c) rj[c] -= w * d[c];
        const std::uint8_t mj = mark[j];
        if (!(mj & 2)) changed.push_back(static_cast<std::int32_t>(j));
        if (!(mj & 1) && norm2(rj) >= threshold) {
          mark[j] = 3;
          work.push_back(static_cast<std::int32_t>(j));
        } else {
          mark[j] = mj | 2;
        }
      }
    }
    for (std::int32_t i : work) mark_[i] &= static_cast<std::uint8_t>(~1u);
    work.clear();
    // Every residual changed, from its row; those still at the threshold go round again.
    for (std::int32_t j : changed) {
      double* rj = &r_[k * static_cast<std::size_t>(j)];
      const double e = detail::residual_row<K, Kind>(rows, targets_.data(), v, k, static_cast<std::size_t>(j), rj);
      residual_.set(static_cast<std::size_t>(j), e);
      mark_[j] = 0;
      if (!stopped && e >= threshold) {
        mark_[j] = 1;
        work.push_back(j);
      }
    }
    changed.clear();
  }
  for (std::int32_t i : work) mark_[i] = 0;
  return relaxations;
}

void LocalSolver::log_row(const double* v, std::size_t i) {
  logged_[i] = 1;
  log_rows_.push_back(static_cast<std::int32_t>(i));
  log_v_.insert(log_v_.end(), v + k_ * i, v + k_ * (i + 1));
  log_r_.insert(log_r_.end(), r_.begin() + static_cast<std::ptrdiff_t>(k_ * i),
                r_.begin() + static_cast<std::ptrdiff_t>(k_ * (i + 1)));
}

void LocalSolver::undo(double* v) {
  const std::size_t k = k_;
  for (std::size_t q = 0; q < log_rows_.size(); ++q) {
    const std::size_t i = static_cast<std::size_t>(log_rows_[q]);
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) {
      v[k * i + c] = log_v_[k * q + c];
      r_[k * i + c] = log_r_[k * q + c];
      e += r_[k * i + c] * r_[k * i + c];
    }
    residual_.set(i, e);
    logged_[i] = 0;
  }
  // In reverse: an index moved twice gets its first value back.
  for (std::size_t q = log_targets_.size(); q-- > 0;) {
    const std::size_t i = static_cast<std::size_t>(log_targets_[q]);
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) {
      targets_[k * i + c] = log_target_values_[k * q + c];
      e += targets_[k * i + c] * targets_[k * i + c];
    }
    target_norm_.set(i, e);
  }
  for (std::int32_t j : log_cold_) cold_.set(static_cast<std::size_t>(j), cold_row(static_cast<std::size_t>(j)));
  residual_valid_ = log_residual_valid_;
  log_rows_.clear(), log_targets_.clear(), log_cold_.clear();
  log_v_.clear(), log_r_.clear(), log_target_values_.clear();
}

void LocalSolver::update(double* v, bool v_is_last, const std::int32_t* indices, std::size_t count,
                         const double* positions, double tol, long long max_relaxations, SolveResult& res) {
  if (!has_targets()) throw std::logic_error("LocalSolver::update before set_targets");
  const std::size_t n = op_.n, k = k_;
  for (std::size_t q = 0; q < count; ++q)
    if (indices[q] < 0 || static_cast<std::size_t>(indices[q]) >= n)
      throw ParameterError("indices[" + std::to_string(q) + "] = " + std::to_string(indices[q]) +
                           " is not a vertex (0.." + std::to_string(n - 1) + ")");
  const auto norm2 = [k](const double* x) {
    double e = 0.0;
    for (std::size_t c = 0; c < k; ++c) e += x[c] * x[c];
    return e;
  };

  // The undo log of the last update, dropped.
  for (std::int32_t i : log_rows_) logged_[i] = 0;
  log_rows_.clear(), log_targets_.clear(), log_cold_.clear();
  log_v_.clear(), log_r_.clear(), log_target_values_.clear();
  log_residual_valid_ = v_is_last && residual_valid_;

  // The start's residual, in full unless it is the last update's result.
  if (!v_is_last || !residual_valid_) {
    r_.resize(k * n);
    detail::residual(op_, targets_.data(), v, r_.data(), k);
    residual_.assign(row_norms2(r_, k));
    residual_valid_ = true;
  }

  // Move the targets: r_i by the move, the cold residuals of row i and of
  // the rows reading i from their rows.
  std::vector<std::int32_t> cold_dirty;
  for (std::size_t q = 0; q < count; ++q) {
    const std::size_t i = static_cast<std::size_t>(indices[q]);
    log_targets_.push_back(static_cast<std::int32_t>(i));
    log_target_values_.insert(log_target_values_.end(), &targets_[k * i], &targets_[k * i] + k);
    for (std::size_t c = 0; c < k; ++c) targets_[k * i + c] = positions[k * q + c];
    if (!logged_[i]) log_row(v, i);
    residual_.set(i, residual_row(v, i, &r_[k * i]));  // exact, as every residual kept
    target_norm_.set(i, norm2(&targets_[k * i]));
    cold_dirty.push_back(static_cast<std::int32_t>(i));
    for (std::int32_t p = t_offsets_[i]; p < t_offsets_[i + 1]; ++p) cold_dirty.push_back(t_rows_[p]);
  }
  for (std::int32_t j : cold_dirty) cold_.set(static_cast<std::size_t>(j), cold_row(static_cast<std::size_t>(j)));
  log_cold_ = cold_dirty;

  res.method = Method::Gs;
  res.variant = "local";  // bind_solvers.cpp keys read-only vertices on it
  res.omega = 1.0;
  res.columns = k;
  res.relaxations = 0;
  res.products = 0;
  res.iterations = 0;
  const double e0 = std::sqrt(cold_.max());
  res.initial_error = e0;
  const double floor = 64.0 * 2.220446049250313e-16 * std::sqrt(target_norm_.max());
  const double e_start = std::sqrt(residual_.max());
  res.stop_reason = StopReason::Converged;
  if (!(e0 > 0.0)) {
    // V0 interpolates itself exactly: it is the answer (O(n), as a solve's).
    std::copy(targets_.begin(), targets_.end(), v);
    std::fill(r_.begin(), r_.end(), 0.0);
    residual_.assign(std::vector<double>(n, 0.0));
    res.errors.assign(1, 0.0);
    return;
  }
  res.errors.assign(1, e_start / e0);
  // Relax a row while ||r_i|| >= tol E_0 and above the rounding floor.
  const double bound = std::max(tol * e0, std::nextafter(floor, INFINITY));
  const double threshold = bound * bound;
  if (e_start < bound) return;

  std::vector<std::int32_t> work;
  residual_.collect(threshold, work);
  bool stopped = false, diverged = false;
  long long relaxations = 0;
  // Divergence: a residual past 1e6 times the start's and E_0 (as a solve's).
  const double limit = 1e6 * std::max(e_start, e0);
  try {
    relaxations = detail::with_row_kind(detail::rows_of(op_), [&](auto kind) {
      using Kind = decltype(kind);
      return k == 3 ? relax<3, Kind>(v, work, threshold, limit * limit, max_relaxations, stopped, diverged)
                    : relax<0, Kind>(v, work, threshold, limit * limit, max_relaxations, stopped, diverged);
    });
  } catch (...) {
    // Interrupted (poll_interrupt): the update taken back whole (targets,
    // kept residual, v), the marks back to zero.
    std::fill(mark_.begin(), mark_.end(), 0);
    undo(v);
    throw;
  }
  res.relaxations = relaxations;
  res.iterations = relaxations > 0 ? 1 : 0;
  const double e_end = std::sqrt(residual_.max());
  if (res.iterations) res.errors.push_back(e_end / e0);
  res.stop_reason = e_end < bound ? StopReason::Converged : diverged ? StopReason::Diverged : StopReason::MaxIter;
}

}  // namespace sorpia
