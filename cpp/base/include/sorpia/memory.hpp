#pragma once
/// @file memory.hpp
/// How much memory this process can still take, for the checks that refuse
/// work too big for it before it starts (a tessellation level, the command
/// line's --level).

#include <cstddef>
#include <cstdint>
#include <string>

namespace sorpia {

/// Memory this process can take now, in bytes; 0 when nothing is known. The
/// least of
///  - the system's MemAvailable (/proc/meminfo);
///  - what the soft address-space and data limits (RLIMIT_AS: `ulimit -v`,
///    RLIMIT_DATA: `ulimit -d`) leave above the process's VmSize and VmData;
///  - what the memory limit of the process's cgroup, and of each cgroup above
///    it, leaves above its usage less its inactive file cache (which the
///    kernel reclaims first): cgroup v2 memory.max and memory.current, v1
///    memory.limit_in_bytes and memory.usage_in_bytes.
/// A limit used up gives 1 (known, and nothing left), not 0.
std::size_t available_memory_bytes();

/// A byte count for a message: "1.5 GB" from 1e9 on, else "420 MB".
std::string human_bytes(double bytes);

namespace detail {

/// No limit, for the arguments below.
inline constexpr std::uint64_t kNoLimit = ~std::uint64_t{0};

/// available_memory_bytes() with its sources given: `proc` stands for /proc,
/// `cgroup_root` for /sys/fs/cgroup, `as_limit` and `data_limit` for the soft
/// RLIMIT_AS and RLIMIT_DATA (kNoLimit: none). Tests pass made-up trees.
std::size_t available_memory_bytes(const std::string& proc, const std::string& cgroup_root, std::uint64_t as_limit,
                                   std::uint64_t data_limit);

}  // namespace detail
}  // namespace sorpia
