#pragma once
// Indices grouped by a small integer key (a stable counting sort), for a pass over them a group at a time: points
// by their face, a mesh's corners by their vertex.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sorpia/detail/parallel.hpp"

namespace sorpia {
namespace detail {

/// Indices 0 .. k - 1 grouped by keys[i] (stable: equal keys keep their order), keys in [0, n_keys), not checked:
/// place(i, s) is called once for each i, s its slot in the grouping (the slots of key x are first[x] .. first[x +
/// 1), first returned, n_keys + 1 entries). With n_tasks > 1 the keys are counted and the indices placed in that many
/// tasks (for_each_range over the indices; place is called from them, each slot once), each task's counts of every
/// key held at once (n_tasks times n_keys counts): the same slots whatever n_tasks.
template <class Place>
std::vector<std::size_t> group_by_key(const std::int32_t* keys, std::size_t k, std::size_t n_keys, Place place,
                                      int n_tasks = 1) {
  std::vector<std::size_t> first(n_keys + 1, 0);
  if (n_tasks <= 1) {
    for (std::size_t i = 0; i < k; ++i) ++first[static_cast<std::size_t>(keys[i]) + 1];
    for (std::size_t x = 0; x < n_keys; ++x) first[x + 1] += first[x];
    std::vector<std::size_t> at(first.begin(), first.end() - 1);
    for (std::size_t i = 0; i < k; ++i) place(i, at[static_cast<std::size_t>(keys[i])]++);
    return first;
  }
  // at[t][x]: first task t's count of key x, then the slot of its next index of key x.
  std::vector<std::vector<std::size_t>> at(static_cast<std::size_t>(n_tasks));
  for_each_range(true, n_tasks, k, [&](int t, std::size_t begin, std::size_t end) {
    std::vector<std::size_t>& a = at[static_cast<std::size_t>(t)];
    a.assign(n_keys, 0);
    for (std::size_t i = begin; i < end; ++i) ++a[static_cast<std::size_t>(keys[i])];
  });
  for (std::size_t x = 0; x < n_keys; ++x) {
    std::size_t s = first[x];
    for (std::vector<std::size_t>& a : at) {
      const std::size_t count = a[x];
      a[x] = s;
      s += count;
    }
    first[x + 1] = s;
  }
  for_each_range(true, n_tasks, k, [&](int t, std::size_t begin, std::size_t end) {
    std::vector<std::size_t>& a = at[static_cast<std::size_t>(t)];
    for (std::size_t i = begin; i < end; ++i) place(i, a[static_cast<std::size_t>(keys[i])]++);
  });
  return first;
}

/// Tasks for group_by_key of k indices over n_keys keys: on the core's threads where k is large against n_keys
/// (each task holds n_keys counts, and the counts are put together on one thread).
inline int grouping_tasks(std::size_t k, std::size_t n_keys) {
  return task_count(k, std::max<std::size_t>(65536, 4 * n_keys));
}

/// order[0 .. k) := 0 .. k - 1 ordered by keys[i] (group_by_key: order[s] is the index in slot s).
inline std::vector<std::size_t> order_by_key(const std::int32_t* keys, std::size_t k, std::size_t n_keys,
                                             std::size_t* order) {
  return group_by_key(keys, k, n_keys, [order](std::size_t i, std::size_t s) { order[s] = i; },
                      grouping_tasks(k, n_keys));
}

}  // namespace detail
}  // namespace sorpia
