#pragma once
// numpy's pairwise summation, shared by approximation's driver and its chunks.
#include <cstddef>

namespace sorpia::detail {

// The sum of a[0..n) by numpy's pairwise summation (its add.reduce on a contiguous float64 array: blocks of at
// most 128 summed with 8 accumulators, halves summed recursively). The RMS distances and the mean diagonal are
// summed so because the fit's figures, which its stop rule compares, were numpy's before this driver: the same
// bits (bench/bit_identical.py), and pairwise summation's error, O(log n) roundings rather than O(n).
inline double pairwise_sum(const double* a, std::size_t n) {
  if (n < 8) {
    double res = 0.0;
    for (std::size_t i = 0; i < n; ++i) res += a[i];
    return res;
  }
  if (n <= 128) {
    double r[8];
    for (int j = 0; j < 8; ++j) r[j] = a[j];
    std::size_t i = 8;
    for (; i < n - n % 8; i += 8)
      for (std::size_t j = 0; j < 8; ++j) r[j] += a[i + j];
    double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) res += a[i];
    return res;
  }
  std::size_t n2 = n / 2;
  n2 -= n2 % 8;
  return pairwise_sum(a, n2) + pairwise_sum(a + n2, n - n2);
}

}  // namespace sorpia::detail
