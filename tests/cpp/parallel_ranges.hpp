#pragma once
// A test-only knob of the sweep: how many vertices a thread it needs before it
// runs its ranges on real threads (solver_detail.hpp). The sweep tests use
// meshes of a few thousand vertices, below the production cut, and would
// otherwise run their ranges one after another.
#include <cstddef>
#include <limits>

#include "solver_detail.hpp"

namespace sorpia_test {

// For its lifetime, the sweep runs ranges of at least `per_thread` vertices on
// threads (1: always; SIZE_MAX: never, one after another on the caller).
class SweepRangesOnThreads {
 public:
  explicit SweepRangesOnThreads(std::size_t per_thread = 1)
      : saved_(sorpia::detail::sweep_min_vertices_per_thread) {
    sorpia::detail::sweep_min_vertices_per_thread = per_thread;
  }
  ~SweepRangesOnThreads() { sorpia::detail::sweep_min_vertices_per_thread = saved_; }
  SweepRangesOnThreads(const SweepRangesOnThreads&) = delete;
  SweepRangesOnThreads& operator=(const SweepRangesOnThreads&) = delete;

  static constexpr std::size_t kNever = std::numeric_limits<std::size_t>::max();

 private:
  std::size_t saved_;
};

}  // namespace sorpia_test
