// The sweep engine's plan: ranges of equal work, interface vertices, the
// lag of the fused residual and the deferred residuals.
#include "sweep_plan.hpp"

#include "sorpia/detail/parallel.hpp"

#include <algorithm>
#include <cstring>

namespace sorpia {
namespace detail {
namespace {

// The first 4 kRingGroups neighbours of vertex i in s, the slots past its
// valence holding i itself; returns where the rest of its neighbours begin in
// nb (they end at nb + off[i + 1]). A loop of fixed length, as in ring_sum,
// for make_plan's passes over the rings: a loop over each vertex's own count
// mispredicts its exit about once a vertex on meshes that mix valences.
constexpr int kRingGroups = 3;
// nnz: the length of nb.
inline const std::int32_t* ring_slots(const std::int32_t* off, const std::int32_t* nb, std::int32_t nnz,
                                      std::int32_t i, i4 (&s)[kRingGroups]) {
  const std::int32_t b = off[i], v = off[i + 1] - b;
  const i4 lane = {0, 1, 2, 3}, valence = {v, v, v, v}, self = {i, i, i, i};
  for (int g = 0; g < kRingGroups; ++g) {
    i4 j = self;
    if (__builtin_expect(b + 4 * (g + 1) <= nnz, 1)) {
      std::memcpy(&j, nb + b + 4 * g, sizeof j);  // selected by a mask, as in ring_sum
    } else {
      for (int a = 0; a < 4 && 4 * g + a < v; ++a) j[a] = nb[b + 4 * g + a];
    }
    const i4 real = (lane + 4 * g) < valence;
    s[g] = (j & real) | (self & ~real);
  }
  return nb + b + std::min(v, 4 * kRingGroups);
}

}  // namespace

std::vector<std::int32_t> equal_work_ranges(const Rows& op, int threads) {
  const auto n = static_cast<std::int32_t>(op.n);
  const std::int32_t* off = op.offsets;
  const double total = static_cast<double>(off[n]) + 2.0 * n;
  std::vector<std::int32_t> begin(static_cast<std::size_t>(threads) + 1, n);
  begin[0] = 0;
  for (int t = 1; t < threads; ++t) {
    const double target = total * t / threads;
    std::int32_t lo = begin[t - 1], hi = n;  // first i with cost(i) >= target
    while (lo < hi) {
      const std::int32_t mid = lo + (hi - lo) / 2;
      if (off[mid] + 2.0 * mid < target) lo = mid + 1;
      else hi = mid;
    }
    begin[t] = lo;
  }
  return begin;
}

Plan make_plan(const Rows& op, int threads, [[maybe_unused]] bool parallel,
               const std::vector<std::int32_t>& begin) {
  const auto n = static_cast<std::int32_t>(op.n);
  const std::int32_t* off = op.offsets;
  const std::int32_t* nb = op.neighbors;
  Plan p;
  p.begin = begin;
  p.flags.assign(op.n, 0);
  // Per-range lists, reserved here: nothing may throw (bad_alloc) inside a
  // parallel region, where it would end the process.
  std::vector<std::vector<std::int32_t>> per_range(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) per_range[t].reserve(static_cast<std::size_t>(p.begin[t + 1] - p.begin[t]));
  // One pass over the rings, range by range: interface vertices (a
  // neighbour in another range), and the forward reach max(N(i)) - i of each
  // vertex, for the lag below.
  std::vector<std::int32_t> reach(op.n);
  std::vector<std::vector<std::int32_t>> reach_count(static_cast<std::size_t>(threads),
                                                     std::vector<std::int32_t>(kMaxLag + 2, 0));
  for_each_task(parallel, threads, [&](int t) {
    const std::int32_t lo = p.begin[t], hi = p.begin[t + 1];
    std::int32_t* count = reach_count[t].data();
    for (std::int32_t i = lo; i < hi; ++i) {
      i4 s[kRingGroups];
      const std::int32_t* rest = ring_slots(off, nb, off[n], i, s);
      i4 m = s[0], out = (s[0] < lo) | (s[0] >= hi);
      for (int g = 1; g < kRingGroups; ++g) {
        m = m > s[g] ? m : s[g];
        out |= (s[g] < lo) | (s[g] >= hi);
      }
      // i itself counts too: a vertex with every neighbour below it reaches 0.
      std::int32_t r = std::max(std::max(std::max(m[0], m[1]), std::max(m[2], m[3])), i);
      bool outside = (out[0] | out[1] | out[2] | out[3]) != 0;
      for (const std::int32_t* q = rest; q < nb + off[i + 1]; ++q) {
        r = std::max(r, *q);
        outside |= *q < lo || *q >= hi;
      }
      reach[i] = r - i;
      ++count[std::min(reach[i], kMaxLag + 1)];
      if (outside) {  // never with one range
        p.flags[i] = kInterface;
        per_range[t].push_back(i);
      }
    }
  });
  for (auto& r : per_range) p.interface.insert(p.interface.end(), r.begin(), r.end());
  for (int t = 1; t < threads; ++t)
    for (int k = 0; k < kMaxLag + 2; ++k) reach_count[0][k] += reach_count[t][k];
  // The lag: the forward reach of all but about 1/1024 of the vertices, so
  // that the residual front stays close behind the update front (its rows
  // still in L2) and few residuals are deferred: a deferred residual gathers
  // from far rows, a cache miss each.
  std::int64_t beyond = n;
  p.lag = 0;
  while (p.lag <= kMaxLag && (beyond -= reach_count[0][p.lag]) > n / 1024) ++p.lag;
  p.lag = std::max<std::int32_t>(p.lag, 1);
  // Deferred: the residual of i is not final lag vertices later, because i or
  // a neighbour is swept in the interface phase, or a neighbour lies beyond the lag.
  std::vector<std::vector<std::int32_t>> after_interface(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) after_interface[t].reserve(p.interface.size());
  for_each_task(parallel, threads, [&](int t) {
    per_range[t].clear();
    for (std::int32_t i = p.begin[t]; i < p.begin[t + 1]; ++i) {
      bool touches_interface = p.flags[i] & kInterface;
      if (threads > 1 && !touches_interface) {
        i4 s[kRingGroups];
        const std::int32_t* rest = ring_slots(off, nb, off[n], i, s);
        std::uint8_t f = 0;
        for (int g = 0; g < kRingGroups; ++g)
          for (int a = 0; a < 4; ++a) f |= p.flags[s[g][a]];
        for (const std::int32_t* q = rest; q < nb + off[i + 1]; ++q) f |= p.flags[*q];
        touches_interface = f & kInterface;
      }
      if (touches_interface || reach[i] > p.lag) {
        p.flags[i] |= kDeferred;
        (touches_interface ? after_interface[t] : per_range[t]).push_back(i);
      }
    }
  });
  p.local.push_back(0);
  for (auto& r : per_range) {
    p.deferred.insert(p.deferred.end(), r.begin(), r.end());
    p.local.push_back(p.deferred.size());
  }
  for (auto& r : after_interface) p.deferred.insert(p.deferred.end(), r.begin(), r.end());
  return p;
}

}  // namespace detail
}  // namespace sorpia
