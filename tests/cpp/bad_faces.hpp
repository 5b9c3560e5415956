#pragma once
// Face lists that are no manifold surface, refused by both topology builds
// (test_validation.cpp, test_limit_operator.cpp) and repaired by test_repair.cpp.
#include <cstdint>
#include <vector>

namespace sorpia_test {

using Faces = std::vector<std::int32_t>;

// Two triangles sharing vertex 0 only: a bowtie of two open fans (5 vertices).
inline const Faces bowtie_open_fans = {0, 1, 2, 0, 3, 4};
// Two closed cones (tetrahedra) touching at their apex 0: a bowtie with no
// boundary edge anywhere (7 vertices).
inline const Faces bowtie_closed_cones = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2, 0, 4, 5, 0, 5, 6, 0, 6, 4, 4, 6, 5};
// Edge (0, 1) in three faces (5 vertices).
inline const Faces edge_with_three_faces = {0, 1, 2, 1, 0, 3, 0, 1, 4};

// A Moebius strip: a band of n quads (two triangles each) whose ends are glued
// with a half twist, so it has no consistent orientation (2 n vertices).
inline Faces moebius(int n) {
  Faces f;
  for (int i = 0; i < n; ++i) {
    const int a0 = 2 * i, a1 = 2 * i + 1;
    const int b0 = i + 1 < n ? 2 * i + 2 : 1, b1 = i + 1 < n ? 2 * i + 3 : 0;  // the twist
    f.insert(f.end(), {a0, b0, b1, a0, b1, a1});
  }
  return f;
}

}  // namespace sorpia_test
