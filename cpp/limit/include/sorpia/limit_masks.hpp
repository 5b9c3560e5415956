#pragma once
/// @file limit_masks.hpp
/// OpenSubdiv's Loop and Catmull-Clark limit masks, vertex by vertex, without a
/// Far::TopologyRefiner: the rows of B (limit_operator.hpp builds B from them).
///
/// Every Loop limit mask is a weight on the vertex and one equal weight on
/// each vertex of its mask. The weights are OpenSubdiv's own, computed by
/// Sdc::Scheme<SCHEME_LOOP>::ComputeVertexLimitMask, the routine
/// Far::PrimvarRefinerReal<double>::Limit calls; only the refiner that Limit
/// needs around it is skipped.

#include <cstddef>

#include "sorpia/topology.hpp"

namespace sorpia {

/// One Loop limit mask: `diag` on the vertex itself, `weight` on each vertex of
/// its mask (all ring neighbours inside, the two boundary neighbours on the
/// boundary, none at a corner).
struct LimitMask {
  double diag = 1.0;
  double weight = 0.0;
};

/// Smooth rule, an interior vertex of valence n (paper eq. 5):
/// weight = 1 / (n + 3 / (8 gamma)), gamma = (5/8 - beta^2) / n,
/// beta = 3/8 + cos(2 pi / n) / 4, diag = 1 - n weight  (alpha_n = 3 / (3 + 8 n beta_n));
/// n = 6 gives 1/2 and 1/12; n = 2 (a vertex of a pillow: two triangles with
/// the same vertices in the opposite order) is also the limit of refinement
/// there, whose one-ring stays a pillow. Tabulated for small n.
/// @param valence at least 2
LimitMask smooth_limit_mask(int valence);
/// Crease rule, a boundary vertex: 2/3 and 1/6 on its two boundary neighbours.
LimitMask crease_limit_mask();
/// Corner rule (a one-face corner under Boundary::EdgeAndCorner): 1, no neighbours.
LimitMask corner_limit_mask();

/// The limit mask of vertex i: smooth inside, crease on the boundary, corner
/// for a one-face vertex under Boundary::EdgeAndCorner; an unreferenced vertex
/// gets (1, no neighbours). Its mask vertices are the whole ring inside and
/// topology.ring_neighbors() first and last on the boundary.
LimitMask limit_mask(const Topology& topology, std::size_t i, Boundary boundary);

/// One Catmull-Clark limit mask (Sdc::Scheme<SCHEME_CATMARK>), of a vertex
/// whose faces are all quads: `diag` on the vertex, `edge` on each edge
/// neighbour, `face` on the opposite corner of each quad (where
/// Far::PrimvarRefinerReal::Limit applies the face weights).
struct CatmarkMask {
  double diag = 1.0;
  double edge = 0.0;
  double face = 0.0;
};

/// Smooth rule, an interior vertex of valence n in a quad ring:
/// face = 1 / (n (n + 5)), edge = 4 face, diag = 1 - n (edge + face), i.e.
/// (n^2 v + 4 sum e_j + sum f_j) / (n (n + 5)); n = 4 gives 4/9, 1/9, 1/36.
/// Valence 2 is OpenSubdiv's corner rule (1, 0, 0). @param valence at least 2
CatmarkMask catmark_smooth_limit_mask(int valence);
/// Crease rule, a boundary vertex: 2/3 and 1/6 on its two boundary neighbours (no face weight).
CatmarkMask catmark_crease_limit_mask();

}  // namespace sorpia
