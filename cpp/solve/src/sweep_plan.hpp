#pragma once
// How the sweep engine (solver_sweep.cpp) divides one operator among its
// threads and places E_k's residuals: the ranges, the interface vertices and
// the deferred residuals. Not a public header.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sweep_kernels.hpp"

namespace sorpia {
namespace detail {

// The largest lag of the residual front behind the update front.
constexpr std::int32_t kMaxLag = 8192;

// Ranges, interface and deferred vertices of one operator and thread count.
struct Plan {
  std::vector<std::int32_t> begin;      // ranges: [begin[t], begin[t + 1]), t < threads
  std::vector<std::uint8_t> flags;      // kInterface | kDeferred per vertex
  std::vector<std::int32_t> interface;  // ascending
  // The deferred vertices: first those of range 0 whose neighbours are all
  // swept by its thread, [local[0], local[1]), then range 1's, ..., then,
  // from local[threads], the others (a neighbour, or the vertex itself,
  // swept with the interface). Ascending within each part.
  std::vector<std::int32_t> deferred;
  std::vector<std::size_t> local;
  std::int32_t lag = 0;
};

// Index ranges of equal work, one per thread: starts, threads + 1 of them,
// the last n. A vertex costs its neighbours plus about two neighbours' worth
// of its own loads and arithmetic.
std::vector<std::int32_t> equal_work_ranges(const Rows& op, int threads);

// The plan for the ranges `begin` (threads + 1 starts, the last n).
// parallel: run its passes on the threads (the plan does not depend on it).
Plan make_plan(const Rows& op, int threads, bool parallel, const std::vector<std::int32_t>& begin);

}  // namespace detail
}  // namespace sorpia
