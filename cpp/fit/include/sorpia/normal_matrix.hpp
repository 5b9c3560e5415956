#pragma once
/// @file normal_matrix.hpp
/// The normal equations of a least-squares fit over the rows A of a limit
/// surface at data points (approximation's linear systems): the normal
/// matrix A^T W A, formed on the core's threads, and the system with a
/// proximal and a fairness term, solved by the layer's PCG (pcg.hpp).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "sorpia/limit.hpp"  // CsrMatrix
#include "sorpia/pcg.hpp"

namespace sorpia {

/// A symmetric (n, n) sparse pattern with `blocks` values per entry.
struct NormalMatrix {
  std::size_t n = 0;
  int blocks = 1;
  std::vector<std::int64_t> indptr;   ///< n + 1 entries
  std::vector<std::int32_t> indices;  ///< columns, sorted within a row
  std::vector<double> values;         ///< (nnz, blocks) row-major
};

/// CSR rows held elsewhere (borrowed, not copied: e.g. numpy's arrays).
struct CsrRows {
  std::size_t n_rows = 0;
  std::size_t n_cols = 0;
  const std::int32_t* indptr = nullptr;   ///< n_rows + 1 entries
  const std::int32_t* indices = nullptr;  ///< sorted and distinct within a row (relied on)
  const double* data = nullptr;
};

/// The pattern of NormalBlocks' matrix, which the blocks' columns alone fix:
/// made by NormalBlocks and kept by a caller whose next blocks may have the
/// same columns (approximation's next update, its points on the same faces),
/// so that it is made once. Immutable once made: one may be shared.
struct NormalPattern;

/// A^T W A and A^T x summed a block of rows at a time: a block is rows with
/// the same columns (the points of one face), dense. The blocks' columns are
/// given first, which fixes the matrix's pattern; each block's share is then
/// formed on its own, in the cache, by whichever thread adds it (each entry
/// a sum over the block's rows in their order), and added into the pattern
/// in the order of the blocks' numbers (a run of blocks once all of them and
/// every run before it are in, by the thread that completes them), so that
/// the sums do not depend on the threads. Weights as normal_matrix's.
class NormalBlocks {
 public:
  /// @param n        columns of A (the cage's vertices)
  /// @param offsets, columns  block b's columns (sorted, distinct, each < n)
  ///                 are columns[offsets[b] .. offsets[b + 1])
  /// @param kept     where not null, the pattern is *kept where that was
  ///                 made from the same n, offsets and columns, else it is
  ///                 made (on the core's threads) and stored into *kept
  /// @throws ParameterError for a weight count other than 0, 1 or 6
  NormalBlocks(std::size_t n, int weight_count, std::vector<std::int64_t> offsets, std::vector<std::int32_t> columns,
               std::shared_ptr<const NormalPattern>* kept = nullptr);
  ~NormalBlocks();
  NormalBlocks(const NormalBlocks&) = delete;
  NormalBlocks& operator=(const NormalBlocks&) = delete;
  /// Block b (each number once; different blocks may be added concurrently):
  /// `count` rows (count, width) row-major over its columns, their weights
  /// (count, weight_count) row-major (null for weight count 0) and x
  /// (count, 3), or null for no right-hand side. A block of 0 rows adds
  /// nothing (its columns may be given as none).
  void add(std::size_t b, const double* rows, std::size_t count, const double* weights, const double* x);
  /// The normal matrix once every block is added (entries no row makes
  /// structurally nonzero are not stored) and, unless rhs is null, rhs
  /// (n, 3) := A^T x, written in full.
  /// @throws ParameterError when a block was not added
  NormalMatrix finish(double* rhs);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// A^T W A for rows A (k, n) and per-row weights: with `weight_count` 0 (W = I),
/// 1 (a scalar w_r per row: sum_r w_r a_r a_r^T) or 6 (a symmetric 3x3 W_r per
/// row, stored xx, xy, xz, yy, yz, zz: the six (n, n) blocks sum_r W_r[c] a_r
/// a_r^T, the normal matrix of sum_r (A_r V - p_r)^T W_r (A_r V - p_r) over
/// the 3n unknowns V). Entries the rows make structurally nonzero are stored
/// (a zero from cancellation stays). Each run of consecutive rows with the
/// same columns (the points of one face, when the caller orders the rows by
/// face) is one block of NormalBlocks, the runs numbered in order.
/// @param weights  (k, weight_count) row-major, or null when weight_count is 0
/// @param x, rhs   with both given, rhs (n, 3) := A^T x for x (k, 3) in the
///                 same pass; rhs is written in full
/// @throws ParameterError for a weight count other than 0, 1 or 6
NormalMatrix normal_matrix(const CsrRows& rows, const double* weights, int weight_count, const double* x = nullptr,
                           double* rhs = nullptr);
NormalMatrix normal_matrix(const CsrMatrix& rows, const double* weights, int weight_count);

/// The weights of the tangent-distance blend for normal_matrix: for each row
/// r, W_r = w_r (t I + (1 - t) n_r n_r^T), n_r the unit normal at the point's
/// footpoint (a zero or non-finite normal keeps W_r = w_r I), stored xx, xy,
/// xz, yy, yz, zz into weights (k, 6), and W_r p_r into weighted_points (k, 3).
/// @param row_weights  w_r (k), or null for all 1
void blend_weights(const double* points, const double* normals, const double* row_weights, std::size_t k,
                   double tangential, double* weights, double* weighted_points);

/// The normal equations of one least-squares update of control vertices X
/// (n, 3) row-major, with a proximal term mu |X - X_prev|^2 and a fairness
/// term c tr(X^T K X):
///     (N + mu I + c K) X = rhs,
/// N = A^T W A from normal_matrix: with 1 value per entry the same matrix on
/// each coordinate (three independent systems, one per column of X); with 6
/// the 3x3 blocks of one system over the 3n unknowns x0, y0, z0, x1, ...
/// (K on each coordinate). mu and c are given relative to N's mean diagonal.
class NormalEquations {
 public:
  /// @param normal    N (blocks 1 or 6)
  /// @param fairness_matrix  K, (n, n) symmetric positive semidefinite, or
  ///                  empty (no rows) for none
  /// @param fairness  c divided by mean_diagonal() (>= 0)
  /// @param proximal  mu divided by mean_diagonal() (> 0 keeps the system
  ///                  positive definite where no row reaches a vertex)
  /// @throws ParameterError for K of another size or N with another
  ///         number of values per entry
  NormalEquations(NormalMatrix normal, CsrMatrix fairness_matrix, double fairness, double proximal);

  std::size_t n() const { return n_.n; }
  /// The mean of N's diagonal (with 6 values per entry: of its xx, yy and
  /// zz entries), or 1 where it is 0.
  double mean_diagonal() const { return mean_diagonal_; }
  double mu() const { return mu_; }

  /// out = (N + mu I + c K) x, both (n, 3) row-major, on up to `threads`
  /// threads where the matrix is large enough to pay.
  void apply(const double* x, double* out, int threads = 1) const;

  /// PCG (sorpia::pcg) from x (in: the start, out: the result): Jacobi with
  /// 1 value per entry, block Jacobi (the inverses of the 3x3 diagonal
  /// blocks) with 6. Stops when every system's residual norm is below rtol
  /// times its value at the start (or 1e-15 times its right-hand side's), or
  /// after max_iter iterations. Products with the matrix on up to `threads`
  /// threads (0: the processors this process may run on), where the matrix
  /// is large enough to pay.
  PcgResult solve(const double* rhs, double* x, double rtol, long long max_iter, int threads) const;

 private:
  NormalMatrix n_;
  CsrMatrix k_;
  double mean_diagonal_ = 1.0, mu_ = 0.0, c_ = 0.0;
};

}  // namespace sorpia
