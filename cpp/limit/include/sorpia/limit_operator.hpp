#pragma once
/// @file limit_operator.hpp
/// The limit matrix B (paper eq. 6-7) in the one form the core uses for it:
/// limit_points, limit_matrix, every solver and the surface's limit points
/// all read a LimitOperator.

#include <cstddef>
#include <cstdint>
#include <string>
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

/// B of a Loop mesh from OpenSubdiv's Loop limit masks (sorpia::limit_mask,
/// limit_masks.hpp), one uniform row per vertex, in O(n_vertices + n_edges):
/// the production build of B. Equal to reference_limit_matrix (OpenSubdiv's
/// Far Limit()) to rounding (tests/cpp/test_limit_operator.cpp).
/// @throw MeshError naming the first face that is not a triangle
LimitOperator limit_operator(const Topology& topology, Boundary boundary);

/// Empty when every face is a triangle, else the message naming the first
/// face that is not (Loop's refusal).
std::string loop_needs_triangles(const Topology& topology);

/// Loop's B with OpenSubdiv's sharpness tags (Far::TopologyDescriptor's creases,
/// corners and holes; a tag given twice counts with its last sharpness).
/// Every row is the limit of OpenSubdiv's refinement. Rows of vertices no tag
/// touches are the masks above. Infinitely sharp tags keep the uniform form
/// (Sdc's rules, boundary edges counting as sharp edges): at an infinitely
/// sharp corner, or at three or more sharp edges, the vertex keeps itself; at
/// two, the crease rule 2/3 and 1/6 on their two ends. With semi-sharp tags,
/// a vertex with a semi-sharp edge or corner gets OpenSubdiv's Limit() after
/// uniform refinement around it to ceil(its largest finite sharpness)
/// levels, composed back to the control vertices (rows of any width:
/// `values` is then filled); every other row is the same at any level. A
/// dart (an interior vertex with one infinitely sharp edge once its
/// semi-sharp tags have decayed) gets the limit of its refinement, which
/// Far's Limit() at no finite level gives (Sdc's smooth limit mask ignores
/// that the sharp edge's children are midpoints): the dominant left
/// eigenvector of its local subdivision matrix (detail::refined_limit_rows),
/// a row with several weights, so a mesh with a dart fills `values`. Holes
/// change no row of B (Far's refinement and Limit() treat a hole's vertices
/// as if the face were there); they only cut faces out of the surface.
/// @throw MeshError naming the first crease that is not an edge of the mesh,
///        or the first face that is not a triangle
LimitOperator limit_operator(const Topology& topology, Boundary boundary, const Tags& tags);

/// B under the rules: either scheme, with OpenSubdiv's sharpness tags (empty: none).
/// Loop as above. Catmull-Clark (rows in `values`), equal to OpenSubdiv's
/// Limit() of the whole mesh refined to the deepest level detail::row_levels
/// gives (tests/cpp/test_catmark.cpp): Sdc's CATMARK limit masks where every
/// face at the vertex is a quad (interior valence n: (n^2 v + 4 sum e_j +
/// sum f_j) / (n (n + 5)), f_j the opposite corners, where Far's Limit()
/// puts the face weights) and on the boundary ((v_prev + 4 v + v_next) / 6;
/// a one-face corner keeps itself under EdgeAndCorner); an interior vertex
/// with a non-quad face gets its limit after one uniform refinement,
/// composed back onto its faces' vertices (detail::catmark_refined_row). Rows
/// of vertices a tag touches come from OpenSubdiv's refinement around the
/// vertex and Limit() at their row level; darts, as under Loop, and interior
/// vertices of two faces (to which Sdc gives the corner mask: Far's Limit()
/// after L levels is the vertex's level-L point) get the limit of their
/// refinement, the dominant left eigenvector of their local subdivision
/// matrix (those rows are not Far's Limit() at any level:
/// tests/cpp/test_darts.cpp checks them against Far refined around the vertex
/// until it no longer changes).
/// @throw MeshError naming the first crease that is not an edge of the mesh
LimitOperator limit_operator(const Topology& topology, const Rules& rules);

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
/// y = B x, x and y row-major (n, k) for any k >= 1 (each column mapped alike), distinct arrays.
void apply(const LimitOperator& op, const double* x, std::size_t k, double* y);

/// Gamma^-1 of B = Gamma Upsilon with Gamma diagonal, positive, and Upsilon
/// symmetric on the entries whose mirror is stored (paper section 3.2): d with
/// d_i B_ij = d_j B_ji for every such pair. Uniform rows always have one,
/// d_i = 1 / weight_i (1 on rows without neighbours). Rows with several
/// weights: found by propagating d_j = d_i B_ij / B_ji over the two-way
/// entries, each connected part starting from 1 / (its first off-diagonal
/// weight); empty when some pair contradicts it (relative 1e-12).
/// Catmull-Clark rows of quad rings have one (d_i proportional to n_i (n_i + 5),
/// edge weight 4 and face weight 1 in Upsilon).
std::vector<double> symmetriser(const LimitOperator& op);

/// True when B = Gamma Upsilon with Upsilon symmetric (symmetriser exists) and
/// the neighbour pattern is symmetric (no row with neighbours referenced by a
/// row without): closed Loop meshes and closed quad meshes (plus unreferenced
/// vertices). Boundaries break it.
bool is_symmetrisable(const LimitOperator& op);

}  // namespace sorpia
