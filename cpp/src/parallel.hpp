#pragma once
// Fork-join parallelism for the core, on a pool of std::threads of its own
// instead of OpenMP: a process that forks after a parallel solve gets a child
// that can solve in parallel too (libgomp's pool hangs in the child), and a
// thread that cannot be started (a memory or process limit) makes the work run
// on the calling thread instead of ending the process (libgomp exits).
#include <cstddef>
#include <functional>

namespace sorpia {
namespace detail {

/// Runs task(t) for t = 0 .. n_tasks - 1 and returns when all have returned:
/// task 0 on the calling thread, the others on pool workers. Tasks must not
/// depend on running at the same time: where workers cannot be had, the tasks
/// run one after another on the calling thread, with the same results. The
/// first exception a task throws is rethrown here, after every task has ended.
/// Not reentrant: a task must not call run_tasks.
void run_tasks(int n_tasks, const std::function<void(int)>& task);

/// run_tasks over [0, n) cut into n_tasks contiguous ranges of near-equal
/// length: body(begin, end, t) for range t.
inline void parallel_ranges(int n_tasks, std::size_t n,
                            const std::function<void(std::size_t, std::size_t, int)>& body) {
  const auto t_count = static_cast<std::size_t>(n_tasks < 1 ? 1 : n_tasks);
  run_tasks(static_cast<int>(t_count), [&](int t) {
    const auto k = static_cast<std::size_t>(t);
    body(n * k / t_count, n * (k + 1) / t_count, t);
  });
}

/// Workers the pool holds now (for tests).
int pool_workers();

}  // namespace detail
}  // namespace sorpia
