#pragma once
/// @file limit.hpp
/// The Loop limit operator B (paper eq. 6-7) as OpenSubdiv defines it.

#include <cstddef>
#include <cstdint>
#include <vector>

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

/// The Loop limit matrix B: row i holds the limit mask of vertex i, so that
/// B V gives the limit positions of the control vertices V.
///
/// Built by recording the weights of OpenSubdiv's
/// Far::PrimvarRefinerReal<double>::Limit on an unrefined Loop refiner; the
/// explicit zero weights OpenSubdiv gives interior neighbours of boundary
/// vertices are dropped. Unreferenced vertices get an identity row.
/// @param topology  the mesh connectivity
/// @param boundary  boundary interpolation rule
/// @return B, (n_vertices, n_vertices)
CsrMatrix limit_matrix(const Topology& topology, Boundary boundary);

/// Loop limit positions of the vertices, B V, evaluated by OpenSubdiv's
/// Far::PrimvarRefinerReal<double>::Limit.
/// @param topology  the mesh connectivity
/// @param vertices  row-major (n_vertices, 3) control vertices
/// @param boundary  boundary interpolation rule
/// @param out       row-major (n_vertices, 3) limit positions (written)
void limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out);

/// y = A x for row-major (n, 3) x and y.
void multiply(const CsrMatrix& a, const double* x, double* y);

}  // namespace sorpia
