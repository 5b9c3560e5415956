#pragma once
/// @file limit_operator.hpp
/// The limit matrix B (paper eq. 6-7) in the one form the core uses for it:
/// limit_points, limit_matrix, every solver and the surface's limit points
/// all read a LimitOperator.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/limit.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {

/// B as a diagonal plus the off-diagonal entries of each row.
///
/// Row i is diag[i] on vertex i and, for p in [offsets[i], offsets[i+1]),
/// the weight of row p on vertex neighbors[p]: `values[p]` when `values` is
/// not empty, else `weight[i]` for every p (a uniform row). Every Loop limit
/// mask is uniform (interior vertex of valence n: alpha_n and (1 - alpha_n)/n,
/// paper eq. 5; boundary vertex: 2/3 and 1/6 on its two boundary neighbours;
/// a one-face corner under "edge-and-corner" and an unreferenced vertex: 1 and
/// no neighbours), so a Loop operator leaves `values` empty and the kernels
/// take the uniform path, which reads one weight per row. Rows with several
/// weights (Catmull-Clark's edge and face neighbours, crease rows) fill
/// `values`, one entry per neighbour; `weight` is then unused.
/// The diagonal is positive; neighbours are sorted within a row and exclude i.
struct LimitOperator {
  std::size_t n = 0;                    ///< number of vertices (rows)
  std::vector<std::int32_t> offsets;    ///< n + 1 entries
  std::vector<std::int32_t> neighbors;  ///< columns of the off-diagonal entries of each row
  std::vector<double> diag;             ///< B_ii (alpha_i in the paper)
  std::vector<double> weight;           ///< uniform rows: the weight of every neighbour of row i (0: none)
  std::vector<double> values;           ///< empty, or the weight of each entry of `neighbors`

  /// True when every row has one weight for all its neighbours (`values` empty).
  bool uniform() const { return values.empty(); }
  /// The weight of entry p of row i.
  double entry(std::size_t i, std::size_t p) const { return values.empty() ? weight[i] : values[p]; }
};

/// B from OpenSubdiv's Loop limit masks (sorpia::limit_mask, limit_masks.hpp),
/// one row per vertex, in O(n_vertices + n_edges): the production build of B.
/// Equal to reference_limit_matrix (OpenSubdiv's Far Limit()) to rounding
/// (tests/cpp/test_limit_operator.cpp).
LimitOperator limit_operator(const Topology& topology, Boundary boundary);

/// B with OpenSubdiv's sharpness tags (Far::TopologyDescriptor's creases,
/// corners and holes; a tag given twice counts with its last sharpness).
/// Rows of vertices no tag touches are the masks above. Infinitely sharp tags
/// keep the uniform form (Sdc's rules, boundary edges counting as sharp
/// edges): at an infinitely sharp corner, or at three or more sharp edges, the
/// vertex keeps itself; at two, the crease rule 2/3 and 1/6 on their two ends;
/// at one (a dart), the smooth rule. With semi-sharp tags, B is OpenSubdiv's
/// Limit() after uniform refinement to ceil(the largest finite sharpness)
/// levels, composed back to the control vertices: a vertex with a semi-sharp
/// edge or corner gets its row from that refinement (rows of any width:
/// `values` is then filled), and so does a dart, whose Sdc limit mask (the
/// smooth one) gives a different point at each level; every other row is the
/// same at any level. Holes change no
/// row of B (Far's refinement and Limit() treat a hole's vertices as if the
/// face were there); they only cut faces out of the surface.
/// @throw MeshError naming the first crease that is not an edge of the mesh
LimitOperator limit_operator(const Topology& topology, Boundary boundary, const Tags& tags);

/// B under either scheme with OpenSubdiv's sharpness tags: Loop as above;
/// Catmull-Clark with every row from OpenSubdiv's refinement around its vertex
/// and Limit() (a row needs no level on a ring of quads, one next to another
/// polygon, and its semi-sharp tags' decay; darts and interior vertices of two
/// faces, whose Sdc limit masks change with the level, the deepest), equal to
/// OpenSubdiv's Limit() of the whole mesh refined to the deepest of those
/// levels.
/// @throw MeshError naming the first crease that is not an edge of the mesh
LimitOperator limit_operator(const Topology& topology, Scheme scheme, Boundary boundary, const Tags& tags);

/// The compact form of a square CSR matrix whose rows each have a positive
/// diagonal entry (explicit zero off-diagonal entries are dropped). Rows whose
/// off-diagonal entries are all equal are stored uniform; if any row is not,
/// every row's weights go to `values`.
/// @throw std::logic_error when B is not square or a row has no positive diagonal
LimitOperator limit_operator(const CsrMatrix& b);

/// B as CSR (columns sorted within a row, diagonal included).
CsrMatrix to_csr(const LimitOperator& op);

/// y = B x, x and y row-major (n, 3), distinct arrays.
void apply(const LimitOperator& op, const double* x, double* y);

/// True when B = Gamma Upsilon with Gamma = diag(weight) and Upsilon symmetric
/// (paper section 3.2): uniform rows, a symmetric neighbour pattern, and no
/// row with neighbours referenced by a row without: closed Loop meshes (plus
/// unreferenced vertices). Boundaries break it.
bool is_symmetrisable(const LimitOperator& op);

}  // namespace sorpia
