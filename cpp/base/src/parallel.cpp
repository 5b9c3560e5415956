#include "sorpia/detail/parallel.hpp"

#include <pthread.h>
#include <sched.h>

#include <condition_variable>
#include <exception>
#include <mutex>
#include <new>
#include <system_error>
#include <thread>
#include <algorithm>

namespace sorpia {
namespace detail {
namespace {

// Workers wait for a generation number to change, run their task of the
// current job, and count down. One job at a time (a mutex serialises callers).
class Pool {
 public:
  void run(int n_tasks, const std::function<void(int)>& task) {
    if (n_tasks <= 1) {
      if (n_tasks == 1) task(0);
      return;
    }
    // One job at a time; a caller that finds the pool busy (another thread's
    // solve) runs its tasks itself, with the same results.
    std::unique_lock<std::mutex> job_lock(job_mutex_, std::try_to_lock);
    const int helpers = job_lock.owns_lock() ? grow(n_tasks - 1) : 0;  // workers taking tasks 1 .. helpers
    if (helpers == 0) {
      for (int t = 0; t < n_tasks; ++t) task(t);
      return;
    }
    std::exception_ptr error;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      task_ = &task;
      active_ = helpers;
      pending_ = helpers;
      error_ = nullptr;
      ++generation_;
    }
    wake_.notify_all();
    // The caller takes task 0 and whatever no worker could take.
    const auto run_here = [&](int t) {
      try {
        task(t);
      } catch (...) {
        if (!error) error = std::current_exception();
      }
    };
    run_here(0);
    for (int t = helpers + 1; t < n_tasks; ++t) run_here(t);
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return pending_ == 0; });
    task_ = nullptr;
    if (!error) error = error_;
    lock.unlock();
    if (error) std::rethrow_exception(error);
  }

  int size() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return workers_;
  }

  // After fork() the child has the pool's memory but none of its threads (and
  // maybe a mutex some thread held): start over with an empty pool. The old
  // one is left as it is, never destroyed (its threads do not exist here).
  static void reset_in_child() { instance_ = new Pool(); }

  static Pool& instance() { return *instance_; }

 private:
  // Starts workers until there are `want` (or as many as could be started);
  // returns how many there are.
  int grow(int want) {
    const std::lock_guard<std::mutex> lock(mutex_);
    while (workers_ < want) {
      const int index = workers_ + 1;  // the task index it takes
      try {
        // It starts from the current generation: the job about to be posted is its first.
        std::thread([this, index, seen = generation_] { work(index, seen); }).detach();
      } catch (const std::system_error&) {  // no thread to be had: the caller runs the rest
        break;
      } catch (const std::bad_alloc&) {
        break;
      }
      ++workers_;
    }
    return std::min(workers_, want);
  }

  void work(int index, unsigned long long seen) {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return generation_ != seen; });
      seen = generation_;
      if (index > active_) continue;  // not needed for this job
      const std::function<void(int)>* task = task_;
      lock.unlock();
      std::exception_ptr failure;
      try {
        (*task)(index);
      } catch (...) {
        failure = std::current_exception();
      }
      lock.lock();
      if (failure && !error_) error_ = failure;
      if (--pending_ == 0) done_.notify_one();
    }
  }

  std::mutex job_mutex_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  int workers_ = 0;  // detached threads, waiting in work()
  const std::function<void(int)>* task_ = nullptr;
  int active_ = 0, pending_ = 0;
  unsigned long long generation_ = 0;
  std::exception_ptr error_;
  static Pool* instance_;
};

Pool* Pool::instance_ = [] {
  pthread_atfork(nullptr, nullptr, [] { Pool::reset_in_child(); });
  return new Pool();
}();

}  // namespace

void run_tasks(int n_tasks, const std::function<void(int)>& task) { Pool::instance().run(n_tasks, task); }

int pool_workers() { return Pool::instance().size(); }

namespace {
// The calling thread's cap (ThreadCap); 0: none.
thread_local int thread_cap = 0;
}  // namespace

int available_processors() {
  cpu_set_t set;
  CPU_ZERO(&set);
  int n = 0;
  if (sched_getaffinity(0, sizeof set, &set) == 0)
    n = std::max(1, CPU_COUNT(&set));
  else
    n = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return thread_cap > 0 ? std::min(n, thread_cap) : n;
}

int task_count(std::size_t n, std::size_t per_task) {
  const std::size_t want = (n + per_task - 1) / per_task;
  return static_cast<int>(
      std::max<std::size_t>(1, std::min<std::size_t>(want, static_cast<std::size_t>(available_processors()))));
}

ThreadCap::ThreadCap(int n) : previous_(thread_cap) {
  if (n >= 1) thread_cap = previous_ > 0 ? std::min(previous_, n) : n;
}

ThreadCap::~ThreadCap() { thread_cap = previous_; }

}  // namespace detail
}  // namespace sorpia
