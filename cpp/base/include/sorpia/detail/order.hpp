#pragma once
// Indices grouped by a small integer key: the one counting sort of points by their face (footpoints' re-projection,
// the limit surface's per-face evaluations).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/detail/parallel.hpp"

namespace sorpia {
namespace detail {

/// order[0 .. k) := 0 .. k - 1 ordered by keys[i] (stable: equal keys keep their order), keys in [0, n_keys), not
/// checked. Returns first (n_keys + 1 entries): the indices of key x are order[first[x] .. first[x + 1]).
/// On the core's threads where k is large against n_keys: each of t ranges of the indices counts its keys and places
/// its indices after those of the ranges before it (the same order; t times n_keys counts held).
inline std::vector<std::size_t> order_by_key(const std::int32_t* keys, std::size_t k, std::size_t n_keys,
                                             std::size_t* order) {
  const int tasks = task_count(k, std::max<std::size_t>(65536, 4 * n_keys));
  const auto t_count = static_cast<std::size_t>(tasks);
  std::vector<std::size_t> first(n_keys + 1, 0);
  // Range r's count of key x (at[r * n_keys + x]), then where its next index of key x goes.
  std::vector<std::size_t> at(t_count * n_keys, 0);
  for_each_task(tasks > 1, tasks, [&](int t) {
    const auto r = static_cast<std::size_t>(t);
    std::size_t* count = at.data() + r * n_keys;
    for (std::size_t i = k * r / t_count; i < k * (r + 1) / t_count; ++i) ++count[static_cast<std::size_t>(keys[i])];
  });
  std::size_t sum = 0;
  for (std::size_t x = 0; x < n_keys; ++x) {
    first[x] = sum;
    for (std::size_t r = 0; r < t_count; ++r) {
      const std::size_t c = at[r * n_keys + x];
      at[r * n_keys + x] = sum;
      sum += c;
    }
  }
  first[n_keys] = sum;
  for_each_task(tasks > 1, tasks, [&](int t) {
    const auto r = static_cast<std::size_t>(t);
    std::size_t* next = at.data() + r * n_keys;
    for (std::size_t i = k * r / t_count; i < k * (r + 1) / t_count; ++i) order[next[static_cast<std::size_t>(keys[i])]++] = i;
  });
  return first;
}

}  // namespace detail
}  // namespace sorpia
