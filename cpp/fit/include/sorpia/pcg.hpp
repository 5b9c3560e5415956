#pragma once
/// @file pcg.hpp
/// The fitting layer's one preconditioned conjugate gradient method: on a
/// symmetric positive (semi)definite operator M over unknowns X (n, columns)
/// row-major, with a block-diagonal preconditioner (one scalar or one
/// columns x columns matrix per row of X) and a stop rule of the caller's.
/// Fair interpolation's energy minimisation (fair.hpp) and approximation's
/// normal equations (normal_matrix.hpp) both run on it.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace sorpia {

/// The preconditioner P, block diagonal over the rows of X: z_i = P_i r_i.
/// Exactly one of the two is filled.
struct BlockDiagonal {
  /// n entries: P_i = scalars[i] times the identity (Jacobi: the inverse of
  /// M's diagonal; 0 leaves row i out of the iteration).
  std::vector<double> scalars;
  /// n * columns * columns entries, row-major per row of X: P_i a full
  /// (symmetric) matrix (block Jacobi: the inverses of M's diagonal blocks).
  std::vector<double> blocks;
};

/// Where a run stands, given to the stop rule before each iteration. One
/// entry per system: each column of X when the columns are independent, one
/// when they are coupled.
struct PcgProgress {
  long long iteration = 0;        ///< iterations made so far
  std::vector<double> rz;         ///< r^T z (z = P r) now
  std::vector<double> rr;         ///< r^T r now
  /// alpha r^T z of the iteration just made (0 before the first, and for a
  /// system that did not move): the drop of x^T M x - 2 b^T x it made.
  std::vector<double> decrease;
  std::vector<char> active;       ///< false once a system has no descent left
};

/// q = M p, both (n, columns) row-major (q sized by the caller's apply).
using PcgApply = std::function<void(const std::vector<double>& p, std::vector<double>& q)>;
/// The caller's stop rule: a reason to stop now, or an empty string to go on.
using PcgStop = std::function<std::string(const PcgProgress&)>;

/// What pcg returns.
struct PcgResult {
  long long iterations = 0;
  /// The stop rule's reason, "max_iter", or "exact" (r^T z vanished in every
  /// system: nothing left to minimise).
  std::string stop_reason;
};

/// Preconditioned CG on M X = B from the given x, one product with M per
/// iteration for all columns.
/// @param n         rows of X
/// @param columns   columns of X (>= 1)
/// @param coupled   false: each column is its own system (its own step
///                  lengths; M acts on the columns alike, as a matrix
///                  applied to each coordinate); true: the n * columns
///                  unknowns are one system (M couples the columns)
/// @param x         in: the start; out: the result
/// @param r         in: the start's residual B - M x; out: the result's
///                  (as updated by the iteration)
/// @param max_iter  iterations at most (>= 0)
/// @param threads   threads for the vector updates (1: the calling thread;
///                  more only where the vectors are long enough to pay); the
///                  result does not depend on it (the sums are formed over
///                  fixed chunks of rows, in order)
/// The stop rule is asked before every iteration and after the last (it
/// sees every iterate); a system whose p^T M p or r^T z is not positive stops
/// moving (its active flag drops), and all of them stopped ends the run as
/// "exact", whatever the rule says.
PcgResult pcg(std::size_t n, int columns, bool coupled, const PcgApply& apply, const BlockDiagonal& precondition,
              const PcgStop& stop, std::vector<double>& x, std::vector<double>& r, long long max_iter, int threads);

}  // namespace sorpia
