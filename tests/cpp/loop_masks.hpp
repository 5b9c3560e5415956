#pragma once
// Closed-form Loop limit masks, written independently of the core, for tests.
#include <cmath>

namespace sorpia_test {

// alpha_n = 3 / (3 + 8 n beta_n), n beta_n = 5/8 - (3/8 + cos(2 pi / n) / 4)^2
inline double loop_alpha(int n) {
  const double c = 3.0 / 8.0 + std::cos(2.0 * M_PI / n) / 4.0;
  return 3.0 / (3.0 + 8.0 * (5.0 / 8.0 - c * c));
}

}  // namespace sorpia_test
