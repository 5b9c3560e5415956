#pragma once
// The order of points along a Morton curve, shared by the footpoint queries and the decimation's layout.
#include <cstddef>
#include <vector>

namespace sorpia::detail {

// The order of k points (row-major (k, 3)) along a Morton (Z-order) curve over their bounding box, 21 bits an
// axis, ties in index order: neighbours in this order are near in space, so that work taken in it finds what
// it reads (a tree's nodes, a one-ring) in cache.
std::vector<std::size_t> spatial_order(const double* p, std::size_t k);

}  // namespace sorpia::detail
