#pragma once
// Fork-join parallelism for the core, on a pool of std::threads of its own
// instead of OpenMP: a process that forks after a parallel solve gets a child
// that can solve in parallel too (libgomp's pool hangs in the child), and a
// thread that cannot be started (a memory or process limit) makes the work run
// on the calling thread instead of ending the process (libgomp exits).
#include <algorithm>
#include <cstddef>
#include <exception>
#include <functional>
#include <vector>

namespace sorpia {
namespace detail {

/// Runs task(t) for t = 0 .. n_tasks - 1 and returns when all have returned:
/// task 0 on the calling thread, the others on pool workers. Tasks must not
/// depend on running at the same time: where workers cannot be had, the tasks
/// run one after another on the calling thread, with the same results. The
/// first exception a task throws is rethrown here, after every task has ended.
/// Not reentrant: a task must not call run_tasks.
void run_tasks(int n_tasks, const std::function<void(int)>& task);

/// Workers the pool holds now (for tests).
int pool_workers();

/// The processors this process may run on (its affinity mask), at least 1,
/// and no more than the cap a ThreadCap on the calling thread sets.
int available_processors();

/// Caps available_processors() on the calling thread while it lives, so that
/// the work below a call that takes a thread count (fair interpolation's
/// fairness matrix and Bfr's evaluation in it) runs on no more threads than
/// asked. Nested caps: the smallest holds. n < 1 caps nothing.
class ThreadCap {
 public:
  explicit ThreadCap(int n);
  ~ThreadCap();
  ThreadCap(const ThreadCap&) = delete;
  ThreadCap& operator=(const ThreadCap&) = delete;

 private:
  int previous_;
};

/// Tasks for n items of at least `per_task` items each: ceil(n / per_task),
/// at most available_processors(), at least 1.
int task_count(std::size_t n, std::size_t per_task);

/// task(t) for t in [0, n_tasks): through run_tasks when `parallel`, else one
/// after another on the calling thread.
inline void for_each_task(bool parallel, int n_tasks, const std::function<void(int)>& task) {
  if (parallel) {
    run_tasks(n_tasks, task);
  } else {
    for (int t = 0; t < n_tasks; ++t) task(t);
  }
}

/// body(t, first, last) for each task t in [0, n_tasks), [first, last) the
/// t-th of n_tasks contiguous ranges of near-equal length that cut [0, n) in
/// order (a static schedule), the tasks run as by for_each_task.
template <class Body>
void for_each_range(bool parallel, int n_tasks, std::size_t n, Body body) {
  const auto t_count = static_cast<std::size_t>(n_tasks < 1 ? 1 : n_tasks);
  for_each_task(parallel, static_cast<int>(t_count), [&](int t) {
    const auto k = static_cast<std::size_t>(t);
    body(t, n * k / t_count, n * (k + 1) / t_count);
  });
}

/// body(i) for i in [0, n), cut into n_tasks ranges as by for_each_range.
template <class Body>
void for_each_index(bool parallel, int n_tasks, std::size_t n, Body body) {
  for_each_range(parallel, n_tasks, n, [&](int, std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) body(i);
  });
}

/// check(i) for i in [0, n), in ranges of at least `per_task` indices on the
/// core's threads; what the first i to throw throws is thrown (as by a loop in
/// order: each range stops at its first, the lowest range's is rethrown).
template <class Check>
void check_each_index(std::size_t n, std::size_t per_task, Check check) {
  const int tasks = task_count(n, per_task);
  std::vector<std::exception_ptr> failed(static_cast<std::size_t>(tasks));
  for_each_range(tasks > 1, tasks, n, [&](int t, std::size_t first, std::size_t last) {
    try {
      for (std::size_t i = first; i < last; ++i) check(i);
    } catch (...) {
      failed[static_cast<std::size_t>(t)] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
}

/// The values value(j) of the j in [0, n) with keep(j), in the order of j,
/// written to out[0 ..); returns how many. keep and value are called once per
/// j (keep first), in ranges of at least `per_task` indices on the core's
/// threads: each range's values are staged at its own start in `staging` (n
/// entries, not overlapping out), then copied to their places once every
/// range is done (so out may be the array keep and value read).
template <class T, class Keep, class Value>
std::size_t keep_in_order(std::size_t n, std::size_t per_task, Keep keep, Value value, T* staging, T* out) {
  const int tasks = task_count(n, per_task);
  const auto t_count = static_cast<std::size_t>(tasks);
  std::vector<std::size_t> kept(t_count + 1, 0);  // per range its count, then where its values go
  for_each_range(tasks > 1, tasks, n, [&](int t, std::size_t first, std::size_t last) {
    std::size_t w = first;
    for (std::size_t j = first; j < last; ++j)
      if (keep(j)) staging[w++] = value(j);
    kept[static_cast<std::size_t>(t) + 1] = w - first;
  });
  for (std::size_t r = 0; r < t_count; ++r) kept[r + 1] += kept[r];
  for_each_range(tasks > 1, tasks, n, [&](int t, std::size_t first, std::size_t) {
    const auto r = static_cast<std::size_t>(t);
    std::copy(staging + first, staging + first + (kept[r + 1] - kept[r]), out + kept[r]);
  });
  return kept[t_count];
}

/// to := from: where to has from's size, copied in ranges of at least
/// `per_task` values on the core's threads (else copied whole: a resize would
/// write every value twice).
template <class T>
void copy_in_ranges(const std::vector<T>& from, std::vector<T>& to, std::size_t per_task) {
  if (to.size() != from.size()) {
    to = from;
    return;
  }
  const int tasks = task_count(from.size(), per_task);
  for_each_range(tasks > 1, tasks, from.size(), [&](int, std::size_t first, std::size_t last) {
    std::copy(from.begin() + static_cast<std::ptrdiff_t>(first), from.begin() + static_cast<std::ptrdiff_t>(last),
              to.begin() + static_cast<std::ptrdiff_t>(first));
  });
}

/// The largest of f(t) for t in [0, n_tasks) (0 for none), the tasks run as by
/// for_each_task.
template <class F>
double max_over_tasks(bool parallel, int n_tasks, F f) {
  std::vector<double> part(static_cast<std::size_t>(n_tasks > 0 ? n_tasks : 0), 0.0);
  for_each_task(parallel, n_tasks, [&](int t) { part[static_cast<std::size_t>(t)] = f(t); });
  double m = 0.0;
  for (double x : part) m = x > m ? x : m;
  return m;
}

}  // namespace detail
}  // namespace sorpia
