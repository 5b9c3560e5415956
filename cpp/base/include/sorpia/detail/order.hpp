#pragma once
// Indices grouped by a small integer key: the one counting sort of points by their face (footpoints' re-projection,
// the limit surface's per-face evaluations).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace sorpia {
namespace detail {

/// order[0 .. k) := 0 .. k - 1 ordered by keys[i] (stable: equal keys keep their order), keys in [0, n_keys), not
/// checked. Returns first (n_keys + 1 entries): the indices of key x are order[first[x] .. first[x + 1]).
inline std::vector<std::size_t> order_by_key(const std::int32_t* keys, std::size_t k, std::size_t n_keys,
                                             std::size_t* order) {
  std::vector<std::size_t> first(n_keys + 1, 0);
  for (std::size_t i = 0; i < k; ++i) ++first[static_cast<std::size_t>(keys[i]) + 1];
  for (std::size_t x = 0; x < n_keys; ++x) first[x + 1] += first[x];
  std::vector<std::size_t> at(first.begin(), first.end() - 1);
  for (std::size_t i = 0; i < k; ++i) order[at[static_cast<std::size_t>(keys[i])]++] = i;
  return first;
}

}  // namespace detail
}  // namespace sorpia
