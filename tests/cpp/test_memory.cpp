// available_memory_bytes on made-up /proc and cgroup trees: each source
// alone, then the least of them; limits of cgroups above the process's own.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "sorpia/memory.hpp"

namespace {

namespace fs = std::filesystem;
using sorpia::detail::kNoLimit;
constexpr std::uint64_t KiB = 1024, MiB = 1024 * KiB;

class MemoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("sorpia_memory_test_" + std::to_string(::getpid()));
    fs::create_directories(root_ / "proc" / "self");
    fs::create_directories(root_ / "cgroup");
  }
  void TearDown() override { fs::remove_all(root_); }
  void write(const std::string& relative, const std::string& text) const {
    fs::create_directories((root_ / relative).parent_path());
    std::ofstream(root_ / relative) << text;
  }
  std::size_t available(std::uint64_t as_limit = kNoLimit, std::uint64_t data_limit = kNoLimit) const {
    return sorpia::detail::available_memory_bytes((root_ / "proc").string(), (root_ / "cgroup").string(), as_limit,
                                                  data_limit);
  }
  fs::path root_;
};

TEST_F(MemoryTest, NothingKnownIsZero) { EXPECT_EQ(available(), 0u); }

TEST_F(MemoryTest, MemAvailableAlone) {
  write("proc/meminfo", "MemTotal:       4000 kB\nMemFree:         100 kB\nMemAvailable:    3000 kB\n");
  EXPECT_EQ(available(), 3000 * KiB);
}

TEST_F(MemoryTest, RlimitsLeaveTheLimitLessWhatTheProcessHas) {
  write("proc/meminfo", "MemAvailable: 1000000 kB\n");
  write("proc/self/status", "Name:\tpython\nVmSize:\t  409600 kB\nVmData:\t  102400 kB\n");
  EXPECT_EQ(available(500 * MiB), 100 * MiB);                 // ulimit -v: 500 MiB less VmSize 400 MiB
  EXPECT_EQ(available(kNoLimit, 150 * MiB), 50 * MiB);        // ulimit -d: 150 MiB less VmData 100 MiB
  EXPECT_EQ(available(500 * MiB, 150 * MiB), 50 * MiB);       // the lesser
  EXPECT_EQ(available(300 * MiB), 1u);                        // used up: known, nothing left
}

TEST_F(MemoryTest, CgroupV2LimitsOfTheProcessesCgroupAndItsParents) {
  write("proc/meminfo", "MemAvailable: 8000000 kB\n");
  write("proc/self/cgroup", "0::/batch/job7\n");
  // The job's own limit: 1000 MiB, 700 MiB used of which 200 MiB inactive file cache.
  write("cgroup/batch/job7/memory.max", std::to_string(1000 * MiB) + "\n");
  write("cgroup/batch/job7/memory.current", std::to_string(700 * MiB) + "\n");
  write("cgroup/batch/job7/memory.stat", "anon 1\ninactive_file " + std::to_string(200 * MiB) + "\nactive_file 5\n");
  write("cgroup/batch/memory.max", "max\n");
  write("cgroup/batch/memory.current", std::to_string(900 * MiB) + "\n");
  EXPECT_EQ(available(), 500 * MiB);
  // A parent's tighter limit counts too.
  write("cgroup/batch/memory.max", std::to_string(1200 * MiB) + "\n");
  EXPECT_EQ(available(), 300 * MiB);
}

TEST_F(MemoryTest, CgroupV2SeenFromInsideItsNamespace) {
  // The container sees its own cgroup as "/" at the mount point.
  write("proc/self/cgroup", "0::/\n");
  write("cgroup/memory.max", std::to_string(64 * MiB) + "\n");
  write("cgroup/memory.current", std::to_string(16 * MiB) + "\n");
  EXPECT_EQ(available(), 48 * MiB);
}

TEST_F(MemoryTest, CgroupV1MemoryController) {
  write("proc/meminfo", "MemAvailable: 8000000 kB\n");
  write("proc/self/cgroup", "5:cpu,cpuacct:/\n4:memory:/process_api/abc\n0::/\n");
  write("cgroup/memory/process_api/abc/memory.limit_in_bytes", std::to_string(2048 * MiB) + "\n");
  write("cgroup/memory/process_api/abc/memory.usage_in_bytes", std::to_string(1024 * MiB) + "\n");
  write("cgroup/memory/process_api/abc/memory.stat",
        "inactive_file 1\ntotal_inactive_file " + std::to_string(512 * MiB) + "\n");
  // The root's "no limit" is a huge number, not a limit that binds.
  write("cgroup/memory/memory.limit_in_bytes", "9223372036854771712\n");
  write("cgroup/memory/memory.usage_in_bytes", std::to_string(4096 * MiB) + "\n");
  EXPECT_EQ(available(), 1536 * MiB);
}

}  // namespace
