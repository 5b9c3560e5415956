#pragma once
/// @file local_update.hpp
/// Local re-solves: after a few targets V0 move, relax only the vertices whose
/// residual exceeds the tolerance (a work-list Gauss-Seidel, Southwell's
/// relaxation with a threshold), instead of sweeping the whole mesh.
///
/// B is well conditioned, so the change of the solution caused by moving one
/// target decays geometrically with the distance in rings: the work list
/// stays in a neighbourhood of the moved targets. The guarantee is that of a
/// full solve of the new targets: E / E_0 < tol over the whole mesh, E the
/// largest residual max_i ||v_i^0 - (B V)_i|| and E_0 that of the cold start,
/// max_i ||v_i^0 - (B V0)_i||, both of the new targets. To know them without
/// a pass over the mesh, the solver keeps every row's residual and its cold
/// residual, with a tree of their maxima updated where they change.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/limit_operator.hpp"
#include "sorpia/solvers.hpp"

namespace sorpia {

/// Largest of n values with point updates and "all values at or above t" in
/// O(log n) each (a binary max tree).
class MaxTree {
 public:
  MaxTree() = default;
  /// All n values at once, O(n).
  void assign(const std::vector<double>& values);
  void set(std::size_t i, double value);
  double max() const { return t_.size() > 1 ? t_[1] : 0.0; }
  double at(std::size_t i) const { return t_[size_ + i]; }
  /// Appends to `out` every i whose value is >= threshold.
  void collect(double threshold, std::vector<std::int32_t>& out) const;

 private:
  std::size_t size_ = 0;   // leaves: a power of two >= n
  std::vector<double> t_;  // t_[1] the root, leaves from size_
};

/// The state of local re-solves on one operator: the targets (the V0 of the
/// last solve, moved by each update), the residual of the iterate the last
/// update returned, and B's transpose (whose residuals change when a vertex
/// moves). Works on any LimitOperator (uniform rows or per-entry values).
/// The operator must outlive the solver.
class LocalSolver {
 public:
  /// Builds B's transpose, O(n + nnz).
  explicit LocalSolver(const LimitOperator& op);

  /// The targets V0, row-major (n, k): taken over, with their cold residuals
  /// (O(n)). The next update computes its start's residual in full.
  void set_targets(std::vector<double> targets, std::size_t k);
  bool has_targets() const { return k_ > 0; }
  std::size_t columns() const { return k_; }
  const std::vector<double>& targets() const { return targets_; }

  /// Moves the targets at `indices` (count of them, each in [0, n); a repeated
  /// index takes its last position) to `positions` (row-major (count, k),
  /// finite), then relaxes `v` (row-major (n, k), in place) until
  /// E / E_0 < tol or E <= 64 eps max_i ||v_i^0|| (the rounding floor of
  /// every solve) for the new targets, or until max_relaxations.
  ///
  /// `v_is_last`: v is the iterate the previous update returned, unchanged,
  /// so its residual is the one kept; otherwise (the first update, a solve's
  /// result) it is computed in full first, O(n).
  ///
  /// The relaxation stops as diverged at the first relaxation of a row whose
  /// residual exceeds 1e6 times the larger of E(start) and E_0, or is not
  /// finite (Gauss-Seidel diverges where B is indefinite): v stays finite.
  ///
  /// Fills in `res` (its control_vertices are left alone): method "gs",
  /// variant "local", omega 1; errors = [E(start) / E_0] and, when a vertex
  /// was relaxed, E(end) / E_0 after it (iterations 0 or 1); relaxations;
  /// initial_error = E_0; stop_reason converged, max_iter or diverged.
  /// @throw ParameterError for an index outside [0, n)
  /// @throw Interrupted (poll_interrupt) after taking the update back (undo)
  void update(double* v, bool v_is_last, const std::int32_t* indices, std::size_t count, const double* positions,
              double tol, long long max_relaxations, SolveResult& res);

  /// Takes the last update back: its targets, and the rows of `v` (the
  /// array that update changed) and of the kept residual it changed, O(rows
  /// changed). The kept residual stays valid when that update started from
  /// the last result; otherwise the next update computes its start's in full.
  void undo(double* v);

 private:
  double residual_row(const double* v, std::size_t i, double* r) const;  // r = v0_i - (B v)_i; ||r||^2
  double cold_row(std::size_t i);                                        // ||v0_i - (B V0)_i||^2
  // K: the columns when known at compile time (apply.hpp), Kind: op's rows.
  template <int K, class Kind>
  long long relax(double* v, std::vector<std::int32_t>& work, double threshold, double limit, long long max_relaxations,
                  bool& stopped, bool& diverged);
  void log_row(const double* v, std::size_t i);  // keeps row i of v and r_ for undo, once per update

  const LimitOperator& op_;
  std::vector<std::int32_t> t_offsets_, t_rows_;  // B^T: the rows reading each vertex
  std::vector<double> t_values_;                  // and their weights
  std::size_t k_ = 0;
  std::vector<double> targets_;   // (n, k)
  MaxTree cold_, target_norm_;    // ||v0_i - (B V0)_i||^2, ||v0_i||^2
  std::vector<double> r_;         // (n, k): v0 - B v of the last update's result
  MaxTree residual_;              // ||r_i||^2
  bool residual_valid_ = false;
  std::vector<std::uint8_t> mark_;  // 1: in the work list, 2: residual changed this update
  std::vector<double> scratch_;     // k: one row
  // The last update's undo log: rows of v and r_ before their first change,
  // target rows before each move (in order), the rows whose cold residual
  // changed, and whether the kept residual was valid before it.
  std::vector<std::uint8_t> logged_;
  std::vector<std::int32_t> log_rows_, log_targets_, log_cold_;
  std::vector<double> log_v_, log_r_, log_target_values_;
  bool log_residual_valid_ = false;
};

}  // namespace sorpia
