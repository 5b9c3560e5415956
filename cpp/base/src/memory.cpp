// Memory left to the process: the system's, its rlimits', its cgroups'.
#include "sorpia/memory.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace sorpia {

namespace {

using detail::kNoLimit;

// The first whitespace-separated number in a file, or none (missing file,
// "max", anything else).
std::optional<std::uint64_t> read_number(const std::string& file) {
  std::ifstream in(file);
  std::uint64_t value = 0;
  if (in >> value) return value;
  return std::nullopt;
}

// The value of `key` in a "key value [unit]" file (/proc/meminfo,
// /proc/self/status, memory.stat), or none.
std::optional<std::uint64_t> read_key(const std::string& file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string name;
    std::uint64_t value = 0;
    if (fields >> name && name == key && fields >> value) return value;
  }
  return std::nullopt;
}

// The folders of the process's memory cgroup and of every cgroup above it,
// innermost first, under the mount point `mount`; `path` is the cgroup as
// /proc/self/cgroup names it. A path the mount does not show (a container
// that sees only its own cgroup, mounted at `mount`) leaves the mount point.
std::vector<std::string> cgroup_folders(const std::string& mount, std::string path) {
  std::vector<std::string> out;
  while (!path.empty() && path != "/") {
    out.push_back(mount + path);
    path.erase(path.find_last_of('/'));
  }
  out.push_back(mount);
  return out;
}

// The memory cgroup path of the process: v2's "0::PATH" line (`v2` true) or
// the v1 line whose controllers include "memory"; empty when there is none.
std::string cgroup_path(const std::string& proc, bool v2) {
  std::ifstream in(proc + "/self/cgroup");
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t a = line.find(':'), b = a == std::string::npos ? a : line.find(':', a + 1);
    if (b == std::string::npos) continue;
    const std::string id = line.substr(0, a), controllers = "," + line.substr(a + 1, b - a - 1) + ",";
    if (v2 ? id == "0" && controllers == ",," : controllers.find(",memory,") != std::string::npos)
      return line.substr(b + 1);
  }
  return {};
}

// What the cgroup limits leave, or kNoLimit: for each folder with a limit,
// the limit less its usage less its inactive file cache.
std::uint64_t cgroup_left(const std::vector<std::string>& folders, const char* limit_file, const char* usage_file,
                          const char* inactive_key) {
  std::uint64_t left = kNoLimit;
  for (const auto& folder : folders) {
    const auto limit = read_number(folder + "/" + limit_file);
    const auto usage = read_number(folder + "/" + usage_file);
    if (!limit || !usage) continue;
    const std::uint64_t inactive = read_key(folder + "/memory.stat", inactive_key).value_or(0);
    const std::uint64_t used = *usage > inactive ? *usage - inactive : 0;
    left = std::min(left, *limit > used ? *limit - used : 0);
  }
  return left;
}

}  // namespace

namespace detail {

std::size_t available_memory_bytes(const std::string& proc, const std::string& cgroup_root, std::uint64_t as_limit,
                                   std::uint64_t data_limit) {
  std::uint64_t left = kNoLimit;
  const auto take = [&left](std::uint64_t v) { left = std::min(left, v); };
  if (const auto kib = read_key(proc + "/meminfo", "MemAvailable:")) take(*kib * 1024);
  const auto rlimit_left = [&](std::uint64_t limit, const char* key) {
    if (limit == kNoLimit) return;
    const auto kib = read_key(proc + "/self/status", key);
    const std::uint64_t used = kib ? *kib * 1024 : 0;
    take(limit > used ? limit - used : 0);
  };
  rlimit_left(as_limit, "VmSize:");
  rlimit_left(data_limit, "VmData:");
  // cgroup v2: one hierarchy, mounted at the root (or at unified/ beside v1's).
  const std::string v2 = cgroup_path(proc, true);
  if (!v2.empty())
    for (const char* mount : {"", "/unified"})
      take(cgroup_left(cgroup_folders(cgroup_root + mount, v2), "memory.max", "memory.current", "inactive_file"));
  const std::string v1 = cgroup_path(proc, false);
  if (!v1.empty())
    take(cgroup_left(cgroup_folders(cgroup_root + "/memory", v1), "memory.limit_in_bytes", "memory.usage_in_bytes",
                     "total_inactive_file"));
  if (left == kNoLimit) return 0;
  return static_cast<std::size_t>(std::max<std::uint64_t>(left, 1));
}

}  // namespace detail

std::string human_bytes(double b) {
  char buf[64];
  if (b >= 1e9)
    std::snprintf(buf, sizeof buf, "%.1f GB", b / 1e9);
  else
    std::snprintf(buf, sizeof buf, "%.0f MB", b / 1e6);
  return buf;
}

std::size_t available_memory_bytes() {
  const auto soft = [](int resource) {
    struct rlimit r {};
    return ::getrlimit(resource, &r) == 0 && r.rlim_cur != RLIM_INFINITY ? static_cast<std::uint64_t>(r.rlim_cur)
                                                                         : detail::kNoLimit;
  };
  return detail::available_memory_bytes("/proc", "/sys/fs/cgroup", soft(RLIMIT_AS), soft(RLIMIT_DATA));
}

}  // namespace sorpia
