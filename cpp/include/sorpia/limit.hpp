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
/// to_csr(limit_operator(topology, boundary, scheme)) (limit_operator.hpp):
/// OpenSubdiv's limit masks; unreferenced vertices get an identity row.
/// @param topology  the mesh connectivity
/// @param boundary  boundary interpolation rule
/// @param scheme    Loop (triangles only) or Catmull-Clark
/// @return B, (n_vertices, n_vertices), columns sorted within a row
CsrMatrix limit_matrix(const Topology& topology, Boundary boundary, Scheme scheme = Scheme::Loop);

/// Limit positions of the vertices, B V: apply(limit_operator(topology,
/// boundary, scheme), ...); unreferenced vertices are their own limit.
/// @param topology  the mesh connectivity
/// @param vertices  row-major (n_vertices, 3) control vertices
/// @param boundary  boundary interpolation rule
/// @param out       row-major (n_vertices, 3) limit positions (written)
/// @param scheme    Loop (triangles only) or Catmull-Clark
void limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out,
                  Scheme scheme = Scheme::Loop);

/// Reference, for tests: B recorded from OpenSubdiv's
/// Far::PrimvarRefinerReal<double>::Limit on an unrefined
/// Far::TopologyRefiner (the explicit zero weights OpenSubdiv gives interior
/// neighbours of boundary vertices dropped; identity rows for unreferenced
/// vertices). For Catmull-Clark on a mesh with a non-quad face, where Limit()
/// on the unrefined level would treat n-gons as quads, the limit of the
/// control vertices' children after one uniform refinement
/// (PrimvarRefinerReal::Interpolate, then Limit() on level 1), composed back
/// onto the control vertices. limit_matrix must equal it to rounding. It
/// builds a refiner, which costs several times limit_matrix.
CsrMatrix reference_limit_matrix(const Topology& topology, Boundary boundary, Scheme scheme = Scheme::Loop);

/// Reference, for tests: B V evaluated by Far::PrimvarRefinerReal<double>::Limit
/// (Catmull-Clark: reference_limit_matrix applied).
void reference_limit_points(const Topology& topology, const double* vertices, Boundary boundary, double* out,
                            Scheme scheme = Scheme::Loop);

}  // namespace sorpia
