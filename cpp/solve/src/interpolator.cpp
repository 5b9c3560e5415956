// The Interpolator (interpolator.hpp): one mesh, its rules and B, with solves
// and local updates on it.
#include "sorpia/interpolator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "solver_detail.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/detail/clock.hpp"

namespace sorpia {

namespace {

using detail::Clock;
using detail::seconds_since;

// A double as Python's repr writes it (the messages' convention).
std::string repr(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[32];
  for (int digits = 15; digits <= 17; ++digits) {  // the shortest that reads back
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return buf;
}

template <class Build>
Topology timed(Build build, double& seconds) {
  const auto t0 = Clock::now();
  Topology t = build();
  seconds = seconds_since(t0);
  return t;
}

}  // namespace

double check_values(const double* x, std::size_t rows, std::size_t k, const char* name, double bound) {
  double largest = 0.0;
  for (std::size_t i = 0; i < rows * k; ++i) {
    const double magnitude = std::fabs(x[i]);
    if (magnitude <= bound) {  // false for NaN too
      largest = std::max(largest, magnitude);
      continue;
    }
    const std::string where = std::string(name) + "[" + std::to_string(i / k) + ", " + std::to_string(i % k) +
                              "] = " + repr(x[i]);
    if (!std::isfinite(x[i])) throw ParameterError(where + " is not finite");
    throw ParameterError(where + " is beyond " + repr(bound) + ", the largest magnitude accepted here (the " +
                         "squared norms of the residual would overflow; sorpia::max_coordinate): scale it down");
  }
  return largest;
}

Interpolator::Interpolator(Mesh faces, std::size_t n_vertices, Rules rules, std::vector<std::int32_t> vertex_map)
    : topology_(timed([&] { return Topology(std::move(faces), n_vertices); }, topology_seconds_)),
      rules_(std::move(rules)) {
  build_operator();
  if (!vertex_map.empty()) set_vertex_map(std::move(vertex_map));
}

Interpolator::Interpolator(Topology topology, Rules rules) : topology_(std::move(topology)), rules_(std::move(rules)) {
  build_operator();
}

Interpolator::Interpolator(Topology topology, Rules rules, LimitOperator b)
    : topology_(std::move(topology)), rules_(std::move(rules)), op_(std::move(b)), n_(op_.n) {}

void Interpolator::build_operator() {
  const auto t0 = Clock::now();
  op_ = sorpia::limit_operator(topology_, rules_);
  operator_seconds_ = seconds_since(t0);
  n_ = op_.n;
}

void Interpolator::set_vertex_map(std::vector<std::int32_t> vertex_map) {
  const std::size_t m = op_.n;
  std::size_t n = 0;
  while (n < vertex_map.size() && vertex_map[n] == static_cast<std::int32_t>(n)) ++n;
  if (vertex_map.size() != m || n == 0)
    throw std::logic_error("Interpolator: vertex_map must have one entry per vertex, the first n the identity");
  for (std::size_t j = n; j < m; ++j)
    if (vertex_map[j] < 0 || static_cast<std::size_t>(vertex_map[j]) >= n)
      throw std::logic_error("Interpolator: vertex_map[" + std::to_string(j) + "] is not one of the first vertices");
  copy_offsets_.assign(n + 1, 0);
  for (std::size_t j = n; j < m; ++j) ++copy_offsets_[vertex_map[j] + 1];
  for (std::size_t i = 0; i < n; ++i) copy_offsets_[i + 1] += copy_offsets_[i];
  copies_.resize(m - n);
  std::vector<std::int32_t> at(copy_offsets_.begin(), copy_offsets_.end() - 1);
  for (std::size_t j = n; j < m; ++j) copies_[at[vertex_map[j]]++] = static_cast<std::int32_t>(j);
  vertex_map_ = std::move(vertex_map);
  n_ = n;
}

std::vector<double> Interpolator::expanded(const double* x, std::size_t k) const {
  std::vector<double> out(op_.n * k);
  for (std::size_t j = 0; j < op_.n; ++j) {
    const std::size_t i = vertex_map_.empty() ? j : static_cast<std::size_t>(vertex_map_[j]);
    std::copy(x + k * i, x + k * (i + 1), out.begin() + static_cast<std::ptrdiff_t>(k * j));
  }
  return out;
}

void Interpolator::expand_moves(const std::int32_t* indices, std::size_t count, const double* positions,
                                std::size_t k, std::vector<std::int32_t>& rows, std::vector<double>& values) const {
  for (std::size_t q = 0; q < count; ++q) {
    const std::int32_t i = indices[q];
    rows.push_back(i);
    values.insert(values.end(), positions + k * q, positions + k * (q + 1));
    for (std::int32_t p = copy_offsets_[i]; p < copy_offsets_[i + 1]; ++p) {
      rows.push_back(copies_[p]);
      values.insert(values.end(), positions + k * q, positions + k * (q + 1));
    }
  }
}

SolveResult Interpolator::solve(const double* v0, std::size_t k, const double* initial, const SolveOptions& opt,
                                bool keep_targets) {
  if (k < 1) throw ParameterError("vertices must have shape (n, k), k >= 1");
  check_options(opt);
  const double largest = check_values(v0, n_, k, "vertices", INFINITY);
  if (initial)  // within the bound once scaled as the solvers scale V0
    check_values(initial, n_, k, "initial", std::ldexp(max_coordinate, detail::scale_exponent(v0, n_ * k)));
  std::vector<double> split_v0, split_initial;  // a split's rows: every copy its vertex's
  if (!vertex_map_.empty()) {
    split_v0 = expanded(v0, k);
    v0 = split_v0.data();
    if (initial) initial = (split_initial = expanded(initial, k)).data();
  }
  SolveResult r = sorpia::solve(op_, v0, k, initial, opt, &cache_);
  r.control_vertices.resize(n_ * k);  // the caller's vertices, the first rows
  if (keep_targets) {
    const std::lock_guard<std::mutex> lock(*targets_mutex_);
    solved_targets_.assign(v0, v0 + k * op_.n);
    solved_k_ = k;
    solved_options_ = opt;
    solved_options_.callback = nullptr;  // the caller's, for that solve only
    targets_max_ = largest;
  }
  return r;
}

bool Interpolator::update(SolveResult& r, bool result_is_last, const std::int32_t* indices, std::size_t count,
                          const double* positions, double tol, long long max_iter) {
  const auto t0 = Clock::now();
  SolveOptions limits;
  limits.tol = tol;
  limits.max_iter = max_iter;
  check_options(limits);
  const std::lock_guard<std::mutex> lock(*targets_mutex_);
  if (!local_ && solved_k_ == 0)
    throw ParameterError("update needs the targets of a solve first: call solve(vertices)");
  const std::size_t n = n_;
  const std::size_t k = solved_k_ ? solved_k_ : local_->columns();
  if (r.columns != k || r.control_vertices.size() != k * n)
    throw ParameterError("previous has shape (" + std::to_string(r.columns ? r.control_vertices.size() / r.columns : 0) +
                         ", " + std::to_string(r.columns) + ") but the targets are (" + std::to_string(n) + ", " +
                         std::to_string(k) + ")");
  for (std::size_t q = 0; q < count; ++q)
    if (indices[q] < 0 || static_cast<std::size_t>(indices[q]) >= n)
      throw ParameterError("indices[" + std::to_string(q) + "] = " + std::to_string(indices[q]) +
                           " is not a vertex (0.." + std::to_string(n - 1) + ")");
  check_values(positions, count, k, "positions");
  if (targets_max_ > max_coordinate)
    throw ParameterError("update needs targets within " + repr(max_coordinate) +
                         " in magnitude (the local relaxation does not rescale them), but the last solve's reach " +
                         repr(targets_max_) + ": solve the moved targets instead");

  if (!local_) local_ = std::make_unique<LocalSolver>(op_);
  if (solved_k_) {
    local_->set_targets(std::move(solved_targets_), solved_k_);
    solved_targets_ = {};
    solved_k_ = 0;
    result_is_last = false;
  }
  // What a local update reports (LocalSolver::update fills the rest).
  r.rho = r.sigma = r.lambda_min = r.alpha = r.weight = NAN;
  r.omega_clamped = r.reordered = false;
  r.attempts.clear();
  r.recommended.reset();
  r.worst_vertices.clear();
  r.worst_residuals.clear();
  r.estimate_seconds = r.topology_seconds = r.operator_seconds = 0.0;
  // At most max_iter sweeps' worth of relaxations.
  const long long nn = static_cast<long long>(std::max<std::size_t>(op_.n, 1));
  const long long cap = max_iter > std::numeric_limits<long long>::max() / nn ? std::numeric_limits<long long>::max()
                                                                              : max_iter * nn;
  // A split works on all its rows: the start's copies are their vertices'
  // (so its residual is computed in full), the moves go to every copy, and
  // the caller's rows are written back into r's vertices (in place).
  std::vector<double> split_v;
  std::vector<std::int32_t> split_rows;
  std::vector<double> split_positions;
  double* v = r.control_vertices.data();
  if (!vertex_map_.empty()) {
    split_v = expanded(v, k);
    v = split_v.data();
    expand_moves(indices, count, positions, k, split_rows, split_positions);
    indices = split_rows.data(), count = split_rows.size(), positions = split_positions.data();
    result_is_last = false;
  }
  const auto write_back = [&] {
    if (!vertex_map_.empty()) std::copy(v, v + n * k, r.control_vertices.begin());
  };
  local_->update(v, result_is_last, indices, count, positions, tol, cap, r);
  r.returned_iteration = r.iterations;
  bool moved = r.converged();
  if (!moved) {
    // Local Gauss-Seidel diverges where B is indefinite: the new targets
    // solved in full by the last solve's method, from the start.
    const StopReason local_stop = r.stop_reason;
    std::vector<double> targets = local_->targets();  // the moved ones
    local_->undo(v);
    if (local_stop == StopReason::Diverged) {
      SolveOptions opt = solved_options_;
      opt.tol = tol;
      opt.max_iter = max_iter;
      SolveResult full = sorpia::solve(op_, targets.data(), k, v, opt, &cache_);
      if (full.converged()) {
        local_->set_targets(std::move(targets), k);
        std::copy(full.control_vertices.begin(), full.control_vertices.end(), v);
        moved = true;
      }
      // That solve's report, with its vertices or (failed) the start's, in r's vertex array.
      full.control_vertices = std::move(r.control_vertices);
      r = std::move(full);
      if (vertex_map_.empty()) v = r.control_vertices.data();
    }
  }
  write_back();
  r.solve_seconds = r.seconds = seconds_since(t0);
  return moved;
}

std::size_t Interpolator::targets_columns() const {
  const std::lock_guard<std::mutex> lock(*targets_mutex_);
  return solved_k_ ? solved_k_ : local_ && local_->has_targets() ? local_->columns() : 0;
}

std::vector<double> Interpolator::targets(std::size_t& k) const {
  const std::lock_guard<std::mutex> lock(*targets_mutex_);
  k = solved_k_ ? solved_k_ : local_ && local_->has_targets() ? local_->columns() : 0;
  std::vector<double> out = solved_k_ ? solved_targets_ : local_ && local_->has_targets() ? local_->targets()
                                                                                          : std::vector<double>{};
  out.resize(n_ * k);  // the caller's vertices, the first rows
  return out;
}

}  // namespace sorpia
