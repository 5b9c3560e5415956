#pragma once
/// @file limit.hpp
/// The limit operator B (paper eq. 6-7) as OpenSubdiv defines it, for Loop
/// and Catmull-Clark.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// Compressed sparse row matrix (double values, int32 indices), the layout of
/// scipy.sparse.csr_matrix.
struct CsrMatrix {
  std::size_t n_rows = 0;
  std::size_t n_cols = 0;
  std::vector<std::int32_t> indptr;   ///< n_rows + 1 entries
  std::vector<std::int32_t> indices;  ///< column of each stored value, sorted within a row
  std::vector<double> data;
};

/// The limit matrix B: row i holds the limit mask of vertex i, so that
/// B V gives the limit positions of the control vertices V.
/// to_csr(limit_operator(topology, rules)) (limit_operator.hpp):
/// OpenSubdiv's limit masks; unreferenced vertices get an identity row.
/// @param topology  the mesh connectivity
/// @param rules     scheme (Loop: triangles only), boundary rule, sharpness tags
/// @return B, (n_vertices, n_vertices), columns sorted within a row
CsrMatrix limit_matrix(const Topology& topology, const Rules& rules);
/// Loop: limit_matrix(topology, Rules{Scheme::Loop, boundary, tags}).
CsrMatrix limit_matrix(const Topology& topology, Boundary boundary, const Tags& tags = Tags{});

/// Limit positions of the vertices, B V: apply(limit_operator(topology,
/// rules), ...); unreferenced vertices are their own limit.
/// @param topology  the mesh connectivity
/// @param vertices  row-major (n_vertices, 3) control vertices
/// @param rules     scheme (Loop: triangles only), boundary rule, sharpness tags
/// @param out       row-major (n_vertices, 3) limit positions (written)
/// @param columns   k of (n_vertices, k) data in `vertices` and `out` (any per-vertex data, each column mapped alike)
void limit_points(const Topology& topology, const double* vertices, const Rules& rules, double* out,
                  std::size_t columns = 3);
/// Loop without tags.
void limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out);
/// Loop with OpenSubdiv's sharpness tags.
void limit_points(const Topology& topology, const double* vertices, Boundary boundary, const Tags& tags,
                  double* out);

}  // namespace sorpia
