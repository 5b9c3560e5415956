// The sweep engine's vertex orders: breadth-first for poorly ordered
// meshes, slabs for threads, and the operator renumbered into either.
#include "vertex_order.hpp"

#include <algorithm>
#include <cstddef>

#include "sorpia/detail/parallel.hpp"
#include "sweep_plan.hpp"

namespace sorpia {
namespace detail {

std::vector<std::int32_t> locality_order(const Rows& op) {
  const auto n = static_cast<std::int32_t>(op.n);
  std::vector<std::int32_t> order;
  order.reserve(op.n);
  std::vector<std::uint8_t> seen(op.n, 0);
  // BFS of the component of `start`, appended to order; returns its last vertex.
  auto bfs = [&](std::int32_t start) {
    std::size_t head = order.size();
    order.push_back(start);
    seen[start] = 1;
    while (head < order.size()) {
      const std::int32_t i = order[head++];
      for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q) {
        const std::int32_t j = op.neighbors[q];
        if (!seen[j]) {
          seen[j] = 1;
          order.push_back(j);
        }
      }
    }
    return order.back();
  };
  for (std::int32_t s = 0; s < n; ++s) {
    if (seen[s]) continue;
    // A first search finds a far vertex; the order is the search from it.
    const std::size_t first = order.size();
    const std::int32_t far = bfs(s);
    for (std::size_t k = first; k < order.size(); ++k) seen[order[k]] = 0;
    order.resize(first);
    bfs(far);
  }
  return order;
}

std::vector<std::int32_t> slab_order(const Rows& op, const double* v0, int threads,
                                     std::vector<std::int32_t>& begin) {
  const auto n = static_cast<std::ptrdiff_t>(op.n);
  // The bounding box, each thread over its range, then combined.
  std::vector<double> box(6 * static_cast<std::size_t>(threads));
  for_each_task(true, threads, [&](int t) {
    double* b = box.data() + 6 * t;
    for (int a = 0; a < 3; ++a) b[a] = b[3 + a] = n ? v0[a] : 0.0;
    for (std::ptrdiff_t i = n * t / threads; i < n * (t + 1) / threads; ++i)
      for (int a = 0; a < 3; ++a) b[a] = std::min(b[a], v0[3 * i + a]), b[3 + a] = std::max(b[3 + a], v0[3 * i + a]);
  });
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = box[a], hi[a] = box[3 + a];
    for (int t = 1; t < threads; ++t) lo[a] = std::min(lo[a], box[6 * t + a]), hi[a] = std::max(hi[a], box[6 * t + 3 + a]);
  }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  // Work per thin slice of the axis, then slabs as runs of slices: O(n),
  // equal work to within a slice (1/4096 of a slab).
  const std::size_t slices = 4096 * static_cast<std::size_t>(threads);
  const double width = hi[axis] - lo[axis], scale = width > 0 ? static_cast<double>(slices) / width : 0.0;
  std::vector<std::int32_t> slice(op.n);
  std::vector<double> work(slices * threads, 0.0);  // per thread, then summed into the first
  for_each_task(true, threads, [&](int t) {
    double* w = work.data() + slices * static_cast<std::size_t>(t);
    for (std::ptrdiff_t i = n * t / threads; i < n * (t + 1) / threads; ++i) {
      const double f = (v0[3 * i + axis] - lo[axis]) * scale;  // NaN (a NaN in V0): slice 0
      slice[i] = f >= 0.0 ? static_cast<std::int32_t>(std::min<double>(f, static_cast<double>(slices - 1))) : 0;
      w[slice[i]] += op.offsets[i + 1] - op.offsets[i] + 2.0;  // as equal_work_ranges
    }
  });
  double total = 0.0;
  for (std::size_t k = 0; k < slices; ++k) {
    for (int t = 1; t < threads; ++t) work[k] += work[slices * t + k];
    total += work[k];
  }
  std::vector<std::int32_t> slab_of(slices);
  double sum = 0.0;
  for (std::size_t k = 0; k < slices; ++k) {
    slab_of[k] = std::min(threads - 1, static_cast<int>(sum / total * threads));
    sum += work[k];
  }
  // Counting sort by slab: stable, so each slab keeps the caller's order.
  begin.assign(static_cast<std::size_t>(threads) + 1, 0);
  for (std::ptrdiff_t i = 0; i < n; ++i) ++begin[slab_of[slice[i]] + 1];
  for (int t = 0; t < threads; ++t) begin[t + 1] += begin[t];
  std::vector<std::int32_t> perm(n), next(begin.begin(), begin.end() - 1);
  for (std::ptrdiff_t i = 0; i < n; ++i) perm[next[slab_of[slice[i]]]++] = static_cast<std::int32_t>(i);
  return perm;
}

Renumbered::Renumbered(const Rows& op, const std::int32_t* perm, const std::int32_t* inv,
                       int threads, bool parallel)
    : offsets(op.n + 1, false),
      neighbors(static_cast<std::size_t>(op.offsets[op.n]), false),
      diag(op.n, false) {
  const bool per_entry = !op.uniform();  // weight is unused, values holds every entry's
  if (per_entry)
    values = AlignedBuffer<double>(static_cast<std::size_t>(op.offsets[op.n]), false);
  else
    weight = AlignedBuffer<double>(op.n, false);
  offsets[0] = 0;
  for (std::size_t k = 0; k < op.n; ++k)
    offsets[k + 1] = offsets[k] + op.offsets[perm[k] + 1] - op.offsets[perm[k]];
  const auto n = static_cast<std::ptrdiff_t>(op.n);
  std::int32_t* nb = neighbors.data();
  double* val = values.data();
  const std::int32_t* off = offsets.data();
  double* d = diag.data();
  double* w = weight.data();
  for_each_index(parallel, threads, static_cast<std::size_t>(n), [&](std::size_t k) {
    const std::int32_t i = perm[k];
    std::int32_t out = off[k];
    for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q, ++out) {
      nb[out] = inv[op.neighbors[q]];
      if (per_entry) val[out] = op.values[q];
    }
    d[k] = op.diag[i];
    if (!per_entry) w[k] = op.weight[i];
  });
  view = {op.n, offsets.data(), neighbors.data(), diag.data(), weight.data(), values.data()};
}

OrderSurvey survey_order(const Rows& op, const std::vector<std::int32_t>& begin) {
  // 64 runs of 64 consecutive vertices, evenly spread: a few cache misses
  // a run rather than a few a vertex.
  const auto n = static_cast<std::int32_t>(op.n);
  constexpr std::int32_t kRuns = 64, kRun = 64;
  std::size_t count = 0, far = 0, interface = 0;
  int t = 0;
  for (std::int32_t r = 0; r < kRuns; ++r) {
    const std::int32_t b = static_cast<std::int32_t>(static_cast<std::int64_t>(n) * r / kRuns);
    for (std::int32_t i = b; i < std::min(n, b + kRun); ++i, ++count) {
      while (i >= begin[t + 1]) ++t;
      bool reaches = false, outside = false;
      for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q) {
        const std::int32_t j = op.neighbors[q];
        reaches |= j - i > kMaxLag;
        outside |= j < begin[t] || j >= begin[t + 1];
      }
      far += reaches;
      interface += outside;
    }
  }
  const double c = std::max<double>(1.0, static_cast<double>(count));
  return {static_cast<double>(far) / c, static_cast<double>(interface) / c};
}

}  // namespace detail
}  // namespace sorpia
