// The core's fork-join pool: every task runs once, exceptions come back to
// the caller, and a forked child can run tasks too (libgomp hangs there).
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdint>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "sorpia/detail/order.hpp"
#include "sorpia/detail/parallel.hpp"

namespace {

using sorpia::detail::available_processors;
using sorpia::detail::for_each_index;
using sorpia::detail::max_over_tasks;
using sorpia::detail::run_tasks;

TEST(Parallel, EveryTaskRunsOnceOnDistinctThreads) {
  for (int n : {1, 2, 3, 8}) {
    std::vector<std::atomic<int>> runs(n);
    std::vector<std::thread::id> who(n);
    run_tasks(n, [&](int t) {
      ++runs[t];
      who[t] = std::this_thread::get_id();
    });
    for (int t = 0; t < n; ++t) EXPECT_EQ(runs[t].load(), 1) << "task " << t << " of " << n;
    EXPECT_EQ(who[0], std::this_thread::get_id());  // task 0 on the caller
    for (int t = 1; t < n; ++t) EXPECT_NE(who[t], who[0]);
  }
}

TEST(Parallel, AThreadCapBoundsTheProcessorsWhileItLives) {
  // The uncapped count is the affinity mask's (sched_getaffinity, read here
  // on its own); a cap lowers it on this thread only, nested caps keep the
  // smallest, and each cap's end restores what was before.
  cpu_set_t set;
  CPU_ZERO(&set);
  ASSERT_EQ(sched_getaffinity(0, sizeof set, &set), 0);
  const int all = CPU_COUNT(&set);
  EXPECT_EQ(available_processors(), all);
  {
    const sorpia::detail::ThreadCap one(1);
    EXPECT_EQ(available_processors(), 1);
    int elsewhere = 0;
    std::thread([&] { elsewhere = available_processors(); }).join();
    EXPECT_EQ(elsewhere, all);  // another thread is not capped
    {
      const sorpia::detail::ThreadCap more(4);  // a larger cap inside a smaller one
      EXPECT_EQ(available_processors(), 1);
    }
    EXPECT_EQ(available_processors(), 1);
  }
  EXPECT_EQ(available_processors(), all);
  {
    const sorpia::detail::ThreadCap none(0);  // < 1: no cap
    EXPECT_EQ(available_processors(), all);
  }
}

TEST(Parallel, RangesCoverEachIndexOnce) {
  for (bool parallel : {true, false}) {
    std::vector<int> hits(1000, 0);
    for_each_index(parallel, 3, hits.size(), [&](std::size_t i) { ++hits[i]; });
    for (int h : hits) ASSERT_EQ(h, 1);
  }
  EXPECT_EQ(max_over_tasks(true, 5, [](int t) { return t == 3 ? 7.0 : 1.0; }), 7.0);
}

// The helpers that cut a loop into ranges give what the loop in order gives, with the pool's threads and with one
// (ThreadCap(1)).
TEST(Parallel, OrderByKeyIsTheStableSortByKey) {
  std::mt19937 rng(5);
  for (const std::size_t n_keys : {std::size_t{1}, std::size_t{7}, std::size_t{3000}}) {
    std::vector<std::int32_t> keys(400000);
    for (std::int32_t& k : keys) k = static_cast<std::int32_t>(rng() % n_keys);
    std::vector<std::size_t> expect(keys.size());
    std::iota(expect.begin(), expect.end(), std::size_t{0});
    std::stable_sort(expect.begin(), expect.end(), [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });
    for (int cap : {0, 1}) {
      const sorpia::detail::ThreadCap limit(cap);
      std::vector<std::size_t> order(keys.size());
      const std::vector<std::size_t> first = sorpia::detail::order_by_key(keys.data(), keys.size(), n_keys, order.data());
      ASSERT_EQ(order, expect) << n_keys << " keys, cap " << cap;
      ASSERT_EQ(first.size(), n_keys + 1);
      for (std::size_t x = 0; x < n_keys; ++x)
        ASSERT_EQ(first[x + 1] - first[x], static_cast<std::size_t>(std::count(keys.begin(), keys.end(), static_cast<std::int32_t>(x))));
    }
  }
}

TEST(Parallel, KeepInOrderIsTheFilterInOrder) {
  const std::size_t n = 100000;
  std::vector<std::size_t> in(n);
  for (std::size_t j = 0; j < n; ++j) in[j] = (j * 7919) % 1000;
  std::vector<std::size_t> expect;
  for (std::size_t j = 0; j < n; ++j)
    if (in[j] % 3 == 0) expect.push_back(in[j] + 1);
  for (int cap : {0, 1}) {
    const sorpia::detail::ThreadCap limit(cap);
    std::vector<std::size_t> staging(n), out(in);  // out is also the array read: written after every range is read
    std::vector<int> calls(n, 0);
    const std::size_t kept = sorpia::detail::keep_in_order(
        n, 1000, [&](std::size_t j) { return ++calls[j], out[j] % 3 == 0; }, [&](std::size_t j) { return out[j] + 1; },
        staging.data(), out.data());
    out.resize(kept);
    EXPECT_EQ(out, expect) << "cap " << cap;
    EXPECT_EQ(std::count(calls.begin(), calls.end(), 1), static_cast<std::ptrdiff_t>(n));  // keep once per index
  }
}

TEST(Parallel, CheckEachIndexThrowsWhatTheFirstFailureThrows) {
  for (int cap : {0, 1}) {
    const sorpia::detail::ThreadCap limit(cap);
    try {
      sorpia::detail::check_each_index(100000, 1000, [](std::size_t i) {
        if (i == 90000 || i == 30000 || i == 70000) throw std::runtime_error(std::to_string(i));
      });
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "30000");
    }
  }
  sorpia::detail::check_each_index(100000, 1000, [](std::size_t) {});
}

TEST(Parallel, CopyInRangesCopies) {
  std::vector<double> from(300000);
  for (std::size_t i = 0; i < from.size(); ++i) from[i] = 0.5 * static_cast<double>(i);
  std::vector<double> same(from.size(), -1.0), other(3, -1.0);
  sorpia::detail::copy_in_ranges(from, same, 1000);
  sorpia::detail::copy_in_ranges(from, other, 1000);
  EXPECT_EQ(same, from);
  EXPECT_EQ(other, from);
}


TEST(Parallel, GroupByKeyInTasksPlacesAsAStableSort) {
  // 100,000 indices under 1,000 keys (a multiplicative hash, keys 0 and 999 unused), grouped in 1, 2 and 5 tasks:
  // each slot holds the index std::stable_sort puts there, each key's slots start where its smaller keys' end.
  const std::size_t k = 100000, n_keys = 1000;
  std::vector<std::int32_t> keys(k);
  for (std::size_t i = 0; i < k; ++i) keys[i] = 1 + static_cast<std::int32_t>(i * 2654435761u % 997u);
  std::vector<std::size_t> expected(k);
  std::iota(expected.begin(), expected.end(), std::size_t{0});
  std::stable_sort(expected.begin(), expected.end(), [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });
  for (const int tasks : {1, 2, 5}) {
    std::vector<std::size_t> order(k, k);
    const std::vector<std::size_t> first = sorpia::detail::group_by_key(
        keys.data(), k, n_keys, [&](std::size_t i, std::size_t s) { order[s] = i; }, tasks);
    EXPECT_EQ(order, expected) << tasks;
    ASSERT_EQ(first.size(), n_keys + 1);
    for (std::size_t x = 0; x < n_keys; ++x)
      EXPECT_EQ(first[x + 1] - first[x], static_cast<std::size_t>(std::count(keys.begin(), keys.end(), x))) << x;
    EXPECT_EQ(first[0], 0u);
  }
}

TEST(Parallel, ATaskExceptionReachesTheCallerAfterAllTasks) {
  std::atomic<int> ran{0};
  EXPECT_THROW(run_tasks(4,
                         [&](int t) {
                           ++ran;
                           if (t == 2) throw std::runtime_error("task 2");
                         }),
               std::runtime_error);
  EXPECT_EQ(ran.load(), 4);
  std::atomic<int> again{0};
  run_tasks(4, [&](int) { ++again; });  // the pool still works
  EXPECT_EQ(again.load(), 4);
}

TEST(Parallel, AForkedChildRunsTasksOnThreadsOfItsOwn) {
  run_tasks(3, [](int) {});  // the parent's workers exist
  ASSERT_GE(sorpia::detail::pool_workers(), 2);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    alarm(20);  // a hang ends the child with SIGALRM
    std::atomic<int> ran{0};
    run_tasks(3, [&](int) { ++ran; });
    _exit(ran.load() == 3 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "the child hung or crashed (signal " << WTERMSIG(status) << ")";
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
