#pragma once
// The rows of B at the vertices whose Far Limit() changes with the level, for
// the surface layer (internal).
#include <cstdint>
#include <vector>

#include "sorpia/limit.hpp"
#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia::detail {

// The referenced vertices of the mesh whose Far Limit() changes with the
// level it is taken at (darts: interior vertices with exactly one infinitely
// sharp edge once their semi-sharp tags have decayed; under Catmull-Clark,
// smooth interior vertices of two faces) and their rows of B, the limit of
// their refinement (refined_rows.hpp). LimitSurface takes its corners at
// these vertices from them: Bfr's corner there is Far's Limit() after its
// local refinements.
struct LevelDependentRows {
  std::vector<std::int32_t> vertices;
  CsrMatrix rows;  // one row per entry of `vertices`, n_vertices columns
};
LevelDependentRows level_dependent_rows(const Topology& topology, Scheme scheme, Boundary boundary,
                                        const Tags& tags);

}  // namespace sorpia::detail
