#pragma once
// Which vertices are darts, from the topology and the tags alone: the
// whole-mesh comparisons of B with Far's Limit() after L levels skip their
// rows, which are the limit of refinement (L -> infinity) and no finite level
// gives; test_darts.cpp checks those.
#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia_test {

// Interior vertices with exactly one infinitely sharp crease edge and no
// infinitely sharp corner (a crease or corner given twice counts with its
// last sharpness).
inline std::vector<bool> darts(const sorpia::Topology& t, const sorpia::Tags& tags) {
  std::map<std::pair<std::int32_t, std::int32_t>, double> crease;
  for (std::size_t i = 0; i < tags.n_creases(); ++i) {
    const std::int32_t a = tags.crease_vertices[2 * i], b = tags.crease_vertices[2 * i + 1];
    crease[{std::min(a, b), std::max(a, b)}] = tags.crease_sharpness[i];
  }
  std::map<std::int32_t, double> corner;
  for (std::size_t i = 0; i < tags.n_corners(); ++i) corner[tags.corner_vertices[i]] = tags.corner_sharpness[i];
  std::vector<int> sharp(t.n_vertices(), 0);
  for (const auto& [ab, s] : crease)
    if (s >= sorpia::kInfiniteSharpness) ++sharp[ab.first], ++sharp[ab.second];
  std::vector<bool> out(t.n_vertices(), false);
  for (std::size_t v = 0; v < t.n_vertices(); ++v) {
    const auto c = corner.find(static_cast<std::int32_t>(v));
    out[v] = !t.is_unreferenced(v) && !t.is_boundary(v) && sharp[v] == 1 &&
             (c == corner.end() || c->second < sorpia::kInfiniteSharpness);
  }
  return out;
}

}  // namespace sorpia_test
