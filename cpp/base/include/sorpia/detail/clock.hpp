#pragma once
// The clock the core's drivers time their phases with (wall time, monotonic), shared so that every Result's
// seconds are measured the same way.
#include <chrono>

namespace sorpia::detail {

using Clock = std::chrono::steady_clock;

/// Seconds elapsed since `t0` (a Clock::now() taken earlier).
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace sorpia::detail
