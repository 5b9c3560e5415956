#pragma once
/// @file fair.hpp
/// Fair interpolation (Halstead, Kass and DeRose 1993): on a control mesh
/// finer than the targets (sorpia::refine_uniform), the control vertices V
/// whose limit surface passes through the targets and whose fairness energy
/// tr(V^T K V) is least.
///
/// The targets are the limit positions of some of the fine mesh's vertices
/// (the children of the coarse vertices), rows of the fine mesh's limit
/// matrix B: B_t V = T_t. From one level of refinement on, no such vertex is
/// in another's limit mask (a vertex child's mask covers the faces around it,
/// whose other corners are edge and face children), so the constraints
/// restricted to the target vertices are diagonal, and
///     V_t = (T_t - sum_{j != t} B_tj V_j) / B_tt
/// eliminates them exactly: the energy becomes an unconstrained quadratic in
/// the other (free) vertices, solved by the fitting layer's conjugate
/// gradients (sorpia::pcg) with Jacobi preconditioning (each column of V on
/// its own, one product with K per iteration for all three). Whatever the iteration stops at, the targets are
/// met to rounding.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sorpia/limit.hpp"
#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// When the conjugate gradients stop.
struct FairOptions {
  /// Stop when the energy fell by at most tol times its value over the last
  /// d iterations (the relative energy change), d = k / 5 after k iterations,
  /// at least 2 and at most `window`. The fall over the last d iterations is
  /// how far the energy d iterations ago was above the minimum, less what is
  /// still to come: close to all of it where the energy falls fast (every
  /// vertex a target, where the reduced system is well conditioned), and the
  /// window grows with the iterations so that a slow iteration (few targets,
  /// a face metric) is judged over up to `window`. Positive and finite.
  double tol = 1e-6;
  /// The most iterations the change is measured over, >= 1.
  int window = 10;
  /// At most this many iterations, >= 1.
  long long max_iter = 2000;
  /// Threads for the products with K and the CG's vector updates (1..max_threads;
  /// the vector updates use more than one only above 100,000 vertices).
  int threads = 1;
};

/// What fair_solve returns.
struct FairSolution {
  std::vector<double> vertices;  ///< (n_vertices, 3) row-major: V
  /// energies[k]: the energy after k iterations, tracked by the iteration
  /// (E_0 computed, then E_k = E_{k-1} minus each column's step's decrease,
  /// alpha_k r_k^T z_k); energies[0] that of the start.
  std::vector<double> energies;
  double energy = 0.0;         ///< tr(V^T K V) of the result, computed
  double start_energy = 0.0;   ///< tr(V^T K V) of the start as given
  /// energies, energy and start_energy are in units of 2^energy_exponent:
  /// 0, except for data solved scaled (beyond 2^+-200 in magnitude), whose
  /// energies (squares of coordinates) would leave double's range in the
  /// caller's units; their ratios are the caller's.
  int energy_exponent = 0;
  long long iterations = 0;
  /// "converged" (the tol rule), "max_iter", "exact" (the gradient vanished
  /// in every column: nothing left to minimise).
  std::string stop_reason;
  double max_error = 0.0;      ///< max over targets of ||(B V)_t - T_t||
  std::size_t free_vertices = 0;
  double seconds = 0.0;        ///< the iteration (without building B)
  double setup_seconds = 0.0;  ///< B of the fine mesh, the elimination, the preconditioner
};

/// Minimises tr(V^T K V) subject to (B V)_t = T_t for each target t.
/// @param topology  the fine mesh (sorpia::refine_uniform's faces)
/// @param rules     its rules (the refined tags)
/// @param energy    K, (n, n), symmetric positive semidefinite (only its
///                  pattern's symmetry is relied on: K's rows are read, as
///                  K x and for its diagonal; columns in any order within a
///                  row)
/// @param targets   k distinct vertex indices, whose rows of B have no other
///                  target in them (the children of coarse vertices)
/// @param positions (k, 3) row-major T
/// @param start     (n, 3) row-major: a start; its target rows are replaced
///                  by the elimination
/// @throws ParameterError for a target out of range or repeated, or options
///         out of range; std::logic_error when two targets share a row of B
FairSolution fair_solve(const Topology& topology, const Rules& rules, const CsrMatrix& energy,
                        const std::int32_t* targets, std::size_t n_targets, const double* positions,
                        const double* start, const FairOptions& options);

}  // namespace sorpia
