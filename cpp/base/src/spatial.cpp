#include "sorpia/detail/spatial.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>

#include "sorpia/detail/parallel.hpp"

namespace sorpia::detail {

namespace {

// Spreads the low 21 bits of x to every third bit (a Morton code's one axis).
std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

std::vector<std::size_t> spatial_order(const double* p, std::size_t k) {
  if (k == 0) return {};
  const int tasks = task_count(k, 65536);
  std::vector<std::size_t> run_start(static_cast<std::size_t>(tasks) + 1);
  for (int t = 0; t <= tasks; ++t)
    run_start[static_cast<std::size_t>(t)] = k * static_cast<std::size_t>(t) / static_cast<std::size_t>(tasks);
  // The bounding box: each range's on the core's threads, then theirs (the same box).
  std::vector<std::array<double, 6>> box(static_cast<std::size_t>(tasks));
  for_each_task(tasks > 1, tasks, [&](int t) {
    double lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
    for (std::size_t i = run_start[static_cast<std::size_t>(t)]; i < run_start[static_cast<std::size_t>(t) + 1]; ++i)
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], p[3 * i + c]), hi[c] = std::max(hi[c], p[3 * i + c]);
    box[static_cast<std::size_t>(t)] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  });
  double lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
  for (const std::array<double, 6>& b : box)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], b[c]), hi[c] = std::max(hi[c], b[3 + c]);
  std::vector<std::pair<std::uint64_t, std::size_t>> keyed(k);
  // Keys and sorted runs on the core's threads, the runs merged after (the
  // pairs are distinct: the same order as one sort).
  for_each_task(tasks > 1, tasks, [&](int t) {
    const std::size_t first = run_start[static_cast<std::size_t>(t)], last = run_start[static_cast<std::size_t>(t) + 1];
    for (std::size_t i = first; i < last; ++i) {
      std::uint64_t code = 0;
      for (int c = 0; c < 3; ++c) {
        const double span = hi[c] - lo[c];
        const double u = span > 0 && std::isfinite(span) ? (p[3 * i + c] - lo[c]) / span : 0.0;
        code |= spread3(static_cast<std::uint64_t>(std::clamp(u, 0.0, 1.0) * 2097151.0)) << c;
      }
      keyed[i] = {code, i};
    }
    std::sort(keyed.begin() + static_cast<std::ptrdiff_t>(first), keyed.begin() + static_cast<std::ptrdiff_t>(last));
  });
  for (std::size_t t = 1; t < static_cast<std::size_t>(tasks); ++t)
    std::inplace_merge(keyed.begin(), keyed.begin() + static_cast<std::ptrdiff_t>(run_start[t]),
                       keyed.begin() + static_cast<std::ptrdiff_t>(run_start[t + 1]));
  std::vector<std::size_t> order(k);
  for_each_index(tasks > 1, tasks, k, [&](std::size_t i) { order[i] = keyed[i].second; });
  return order;
}

}  // namespace sorpia::detail
