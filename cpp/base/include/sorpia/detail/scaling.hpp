#pragma once
/// @file scaling.hpp
/// The one exact scaling of data by a power of two that every solve in the
/// core applies to data of extreme magnitude (interpolation's targets, fair
/// interpolation's targets and start, approximation's points and cage).
///
/// Squared norms of values beyond about 1e154 overflow and those of values
/// below about 1e-154 underflow; within 2^+-200 no squared norm down to
/// rounding level (2^-53 of the largest value) can do either. Data whose
/// largest magnitude is outside 2^+-200 is therefore solved as data / 2^e,
/// 2^e about its largest magnitude, and the results scaled back by 2^e:
/// multiplying by a power of two is exact (short of subnormal results), and
/// the solves are linear or homogeneous in the data, so every iterate is that
/// of the data scaled. Within 2^+-200 the exponent is 0 and nothing is copied.

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace sorpia::detail {

/// The largest |x[k]| for k < count (0 for none), the running maximum over
/// several arrays when `so_far` is the previous one.
inline double largest_magnitude(const double* x, std::size_t count, double so_far = 0.0) {
  for (std::size_t k = 0; k < count; ++k) so_far = std::max(so_far, std::abs(x[k]));
  return so_far;
}

/// The exponent e with 2^(e-1) <= largest < 2^e (std::frexp's) when that is
/// beyond 2^+-200 (|e| > 200), else 0; 0 for 0 and for a non-finite value.
inline int scale_exponent(double largest) {
  int e = 0;
  if (largest > 0.0 && std::isfinite(largest)) std::frexp(largest, &e);
  return std::abs(e) <= 200 ? 0 : e;
}

/// scale_exponent of the largest magnitude of x[0..count).
inline int scale_exponent(const double* x, std::size_t count) {
  return scale_exponent(largest_magnitude(x, count));
}

/// x[k] *= 2^e for k < n: exactly, or rounded as std::ldexp rounds a
/// subnormal result. Multiplying by a normal power of two does that at a
/// fraction of ldexp's cost; 2^e outside the normal range needs ldexp itself.
inline void scale_pow2(double* x, std::size_t n, int e) {
  if (e == 0) return;
  if (e > -1000 && e < 1000) {
    const double f = std::ldexp(1.0, e);
    for (std::size_t k = 0; k < n; ++k) x[k] *= f;
  } else {
    for (std::size_t k = 0; k < n; ++k) x[k] = std::ldexp(x[k], e);
  }
}

}  // namespace sorpia::detail
