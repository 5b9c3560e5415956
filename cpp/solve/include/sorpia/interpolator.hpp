#pragma once
/// @file interpolator.hpp
/// One mesh, its subdivision rules and its limit operator B, built once:
/// solve B V = V0 for any targets, and re-solve locally after a few move.
///
/// The Interpolator owns the Topology, B (LimitOperator), the spectral
/// estimates (SpectralCache), the targets of its last solve and the
/// LocalSolver that moves them. It is what Python's sorpia.Interpolator and
/// sorpia.interpolate wrap and what sorpia-bench times; every check of the
/// data it is given (shapes, finite values within max_coordinate, indices)
/// is made here, once, before any state changes.
///
/// Rows of the limit surface at arbitrary points (face, u, v) are the surface
/// layer's LimitSurface::rows (sparse combinations of control vertices, the
/// same kind of object as B's rows at the vertices); fair interpolation and
/// approximation of scans compose them in the fit layer above this one
/// (fairness.hpp, fair.hpp, footpoints.hpp), where the solves on those rows
/// live. solve() and update() are the vertex rows' contract alone.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "sorpia/limit_operator.hpp"
#include "sorpia/local_update.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// The bound on values that keeps the squared norms in E_k finite: a row of
/// k values at most 1e150 in magnitude squares to at most k 1e300, below the
/// largest double (1.8e308) for k up to 10^8, with room for B V (rows of
/// weights summing to 1, a small multiple of the largest value at most). Targets of any finite magnitude are solved
/// (sorpia::solve scales them by a power of two, 2^e ~ max |V0| beyond
/// 2^+-200, exactly); a warm start may be at most max_coordinate times that
/// scale (1 within 2^+-200); local updates do not rescale, so their
/// positions and the kept targets must be within max_coordinate.
constexpr double max_coordinate = 1e150;

/// Checks that every value of the row-major (rows, k) array `x` is finite and
/// at most `bound` in magnitude; returns the largest magnitude.
/// @throw ParameterError naming `name`, the first bad row and column and its
///        value, e.g. "vertices[3, 1] = inf is not finite"
double check_values(const double* x, std::size_t rows, std::size_t k, const char* name,
                    double bound = max_coordinate);

/// One mesh and its rules: B built once; solves and local updates on it.
/// Thread-safe for concurrent solves (the spectral cache is), and one update
/// (or solve keeping its targets) at a time changes the targets.
class Interpolator {
 public:
  /// The faces of `faces` over n_vertices vertices (Topology(Mesh,
  /// std::size_t): its coordinates are not read, its face arrays are taken
  /// over when it is passed as an rvalue; a triangle mesh without counts
  /// takes Topology's triangle fast path).
  ///
  /// `vertex_map`, when not empty, makes the mesh a manifold split of the
  /// caller's non-manifold mesh (sorpia::split_nonmanifold; its rules carry
  /// OpenSubdiv's rules for non-manifold topology as tags): the caller's
  /// vertex each of the n_vertices vertices copies, the first n being the
  /// caller's n vertices themselves (vertex_map[i] = i). Solves and updates
  /// then take and return the caller's n rows: targets, warm starts and
  /// positions go to every copy of their vertex, and results hold the rows
  /// of the caller's vertices.
  /// @throw std::logic_error when vertex_map does not have that form
  Interpolator(Mesh faces, std::size_t n_vertices, Rules rules, std::vector<std::int32_t> vertex_map = {});
  /// A topology already built (taken over).
  Interpolator(Topology topology, Rules rules);
  /// A topology and B already built (taken over): B from elsewhere than
  /// limit_operator(topology, rules), e.g. OpenSubdiv's reference build, for
  /// benchmarks and tests.
  Interpolator(Topology topology, Rules rules, LimitOperator b);
  /// Not copied or moved: the local solver refers to B.
  Interpolator(const Interpolator&) = delete;
  Interpolator& operator=(const Interpolator&) = delete;

  const Topology& topology() const { return topology_; }
  const Rules& rules() const { return rules_; }
  const LimitOperator& limit_operator() const { return op_; }
  SpectralCache& spectral_cache() { return cache_; }
  /// The caller's vertices (those of the split's vertex map, else B's rows).
  std::size_t n_vertices() const { return n_; }
  /// Seconds spent building the topology and B (0 for a topology given).
  double topology_seconds() const { return topology_seconds_; }
  double operator_seconds() const { return operator_seconds_; }

  /// Solves B V = V0 (sorpia::solve on B with the kept spectral estimates).
  /// @param v0       row-major (n, k) targets, finite
  /// @param k        columns >= 1
  /// @param initial  row-major (n, k) warm start, finite, within
  ///                 max_coordinate times the targets' scale, or null
  /// @param opt      solver options (check_options)
  /// @param keep_targets  the targets of later updates become v0 (a copy),
  ///                 and the options those of an update's fallback solve
  /// @return the result in the caller's vertex order, with topology_seconds
  ///         and operator_seconds 0 (the build is timed once, above)
  /// @throw ParameterError for bad values (before any state changes)
  SolveResult solve(const double* v0, std::size_t k, const double* initial, const SolveOptions& opt,
                    bool keep_targets = true);

  /// Moves the kept targets at `indices` (count of them) to `positions`
  /// (row-major (count, k), checked as solve's targets) and re-solves from
  /// `result.control_vertices` ((n, k) previous control vertices, changed in
  /// place) by local relaxation (LocalSolver::update, at most max_iter * n
  /// relaxations). `result_is_last`: `result` is the one the last update
  /// returned, unchanged since, whose residual is kept. Every other field of
  /// `result` is set for this update.
  ///
  /// The relaxation is Gauss-Seidel on a work list: where Gauss-Seidel
  /// diverges (B indefinite, e.g. interior vertices of valence 2) it stops at
  /// the first sign (the largest residual past 1e6 times that of the start
  /// and of the cold start) and the new targets are solved in full instead,
  /// by sorpia::solve with the options of the last solve that kept its
  /// targets, from v: `res` is then that solve's result.
  ///
  /// When neither meets tol, nothing changes: the targets, the kept residual
  /// and the vertices are as before the call; `result` says why (stop_reason
  /// max_iter or diverged, errors [E(start) / E_0, E(last iterate) / E_0]
  /// for the new targets).
  /// @return true when the targets moved (tol met), false when rolled back
  /// @throw ParameterError before any state changes: no solve kept its targets
  ///        yet, the vertices' shape differs from the targets', an index
  ///        outside [0, n), positions not finite or beyond max_coordinate,
  ///        kept targets beyond max_coordinate, tol or max_iter out of range
  ///        (check_options)
  bool update(SolveResult& result, bool result_is_last, const std::int32_t* indices, std::size_t count,
              const double* positions, double tol, long long max_iter);

  /// k of the kept targets; 0 before a solve that kept them.
  std::size_t targets_columns() const;
  /// A copy of the kept (n, k) targets, k set (empty, k = 0, before a solve that kept them).
  std::vector<double> targets(std::size_t& k) const;

 private:
  void build_operator();
  void set_vertex_map(std::vector<std::int32_t> vertex_map);
  // The caller's (rows, k) array on B's rows: each copy gets its vertex's row.
  std::vector<double> expanded(const double* x, std::size_t k) const;
  // Positions of the caller's indices as positions of B's rows (every copy).
  void expand_moves(const std::int32_t* indices, std::size_t count, const double* positions, std::size_t k,
                    std::vector<std::int32_t>& rows, std::vector<double>& values) const;

  Topology topology_;
  Rules rules_;
  LimitOperator op_;
  SpectralCache cache_;
  double topology_seconds_ = 0.0, operator_seconds_ = 0.0;
  std::size_t n_ = 0;  // the caller's vertices
  // A split's copies: vertex_map_ (empty when B's rows are the caller's
  // vertices) and, per caller vertex, its copies beyond the first n rows.
  std::vector<std::int32_t> vertex_map_, copy_offsets_, copies_;
  // The targets of the last solve that kept them, not yet in `local_` (an
  // update hands them over), and that solve's options (callback dropped).
  std::vector<double> solved_targets_;
  std::size_t solved_k_ = 0;
  SolveOptions solved_options_;
  double targets_max_ = 0.0;  // max |v0| of the last solve keeping its targets
  std::unique_ptr<LocalSolver> local_;
  // Held while the targets or local_ are read or changed.
  std::unique_ptr<std::mutex> targets_mutex_ = std::make_unique<std::mutex>();
};

}  // namespace sorpia
