#pragma once
// The unit normal of a surface from its two tangents, at any scale of the
// coordinates: shared by the limit surface's evaluation (cpp/surface) and the
// footpoints of approximation (cpp/fit).
#include <algorithm>
#include <cmath>

namespace sorpia {
namespace detail {

// v scaled by a power of two (exactly) so that its largest component lies in
// [0.5, 1): products and squares of such vectors neither overflow nor underflow.
inline void scale_to_unit(const double* v, double* out) {
  const double m = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])});
  int e = 0;
  if (m > 0.0 && std::isfinite(m)) std::frexp(m, &e);
  if (e >= -1021 && e <= 1022) {  // 2^-e a normal double: the product is ldexp's, exactly
    const double f = std::ldexp(1.0, -e);
    for (int c = 0; c < 3; ++c) out[c] = v[c] * f;
    return;
  }
  for (int c = 0; c < 3; ++c) out[c] = std::ldexp(v[c], -e);
}

// The unit normal du x dv / |du x dv| at any scale of the coordinates (the
// plain formula squares the cross product: it overflows from about 1e77 and
// underflows below about 1e-77); zero where du and dv are parallel or zero.
inline void unit_normal(const double* du, const double* dv, double* out) {
  double a[3], b[3], n[3], u[3];
  scale_to_unit(du, a);
  scale_to_unit(dv, b);
  n[0] = a[1] * b[2] - a[2] * b[1];
  n[1] = a[2] * b[0] - a[0] * b[2];
  n[2] = a[0] * b[1] - a[1] * b[0];
  scale_to_unit(n, u);
  const double len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int c = 0; c < 3; ++c) out[c] = len > 0.0 ? u[c] / len : 0.0;
}

}  // namespace detail
}  // namespace sorpia
