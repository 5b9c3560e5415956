#pragma once
/// @file normal_matrix.hpp
/// The normal matrix A^T W A of a least-squares fit over the rows A of a
/// limit surface at data points (approximation's linear systems), formed on
/// the core's threads.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/limit.hpp"  // CsrMatrix

namespace sorpia {

/// A symmetric (n, n) sparse pattern with `blocks` values per entry.
struct NormalMatrix {
  std::size_t n = 0;
  int blocks = 1;
  std::vector<std::int64_t> indptr;   ///< n + 1 entries
  std::vector<std::int32_t> indices;  ///< columns, sorted within a row
  std::vector<double> values;         ///< (nnz, blocks) row-major
};

/// A^T W A for rows A (k, n) and per-row weights: with `weight_count` 0 (W = I),
/// 1 (a scalar w_r per row: sum_r w_r a_r a_r^T) or 6 (a symmetric 3x3 W_r per
/// row, stored xx, xy, xz, yy, yz, zz: the six (n, n) blocks sum_r W_r[c] a_r
/// a_r^T, the normal matrix of sum_r (A_r V - p_r)^T W_r (A_r V - p_r) over
/// the 3n unknowns V). Entries the rows make structurally nonzero are stored
/// (a zero from cancellation stays).
/// @param weights  (k, weight_count) row-major, or null when weight_count is 0
/// @throws ParameterError for a weight count other than 0, 1 or 6
NormalMatrix normal_matrix(const CsrMatrix& rows, const double* weights, int weight_count);

}  // namespace sorpia
