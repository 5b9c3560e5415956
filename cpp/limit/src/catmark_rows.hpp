#pragma once
// The Catmull-Clark limit operator's builder (internal; limit_operator.hpp's
// limit_operator(topology, Scheme::CatmullClark, boundary, tags) calls it).
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "sorpia/limit_operator.hpp"
#include "sorpia/topology.hpp"

namespace sorpia::detail {

// B for Catmull-Clark, rows in `values`: OpenSubdiv's CATMARK limit masks for
// vertices whose faces are all quads (what Far::PrimvarRefinerReal::Limit
// gives) and for boundary vertices (the crease rule; a one-face corner under
// Boundary::EdgeAndCorner keeps itself); the limit after one uniform
// refinement, composed back, for interior vertices with a non-quad face.
LimitOperator catmark_limit_operator(const Topology& topology, Boundary boundary);

// The row of interior vertex v after one uniform Catmull-Clark refinement
// (face, edge and vertex points), then the limit mask of v's child: sorted
// (column, weight) pairs, v's own among them. Its support is v's faces' vertices.
void catmark_refined_row(const Topology& topology, std::size_t v, std::vector<std::pair<std::int32_t, double>>& row);

}  // namespace sorpia::detail
