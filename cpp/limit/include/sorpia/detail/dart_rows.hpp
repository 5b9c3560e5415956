#pragma once
// The rows of B at darts, for the surface layer (internal).
#include <cstdint>
#include <vector>

#include "sorpia/limit.hpp"
#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia::detail {

// The darts of the mesh under `tags` (interior vertices with exactly one
// infinitely sharp edge once their semi-sharp tags have decayed; referenced
// vertices only) and their rows of B, the limit of their refinement
// (refined_rows.hpp). LimitSurface takes its corners at darts from them:
// Bfr's corner there is Far's Limit() after its local refinements.
struct DartRows {
  std::vector<std::int32_t> vertices;
  CsrMatrix rows;  // one row per entry of `vertices`, n_vertices columns
};
DartRows dart_rows(const Topology& topology, Scheme scheme, Boundary boundary, const Tags& tags);

}  // namespace sorpia::detail
