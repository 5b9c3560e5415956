#pragma once
// Face lists that are no manifold surface, refused by both topology builds
// (test_validation.cpp, test_fast_operator.cpp).
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

}  // namespace sorpia_test
