// The SOR-PIA / Gauss-Seidel engine ("sor" and "gs"): one pass over the mesh
// per iteration that both sweeps (paper eq. 18) and yields the paper's E_k of
// the new iterate, exactly; optionally on several threads.
//
// Fused E_k. E_k = max_i ||v_i^0 - (B V^(k))_i|| needs every neighbour of i at
// its value after sweep k. In sweep order, vertex j's neighbours are all final
// once the sweep has passed max(N(j)); on meshes whose vertex order is
// spatially coherent that is a few rows later. So the residual of vertex j is
// computed in the same loop, `lag` vertices behind the update front, by the
// same formula and summation order as a separate residual pass: the E_k are
// bit for bit those of the two-pass method (tested), while V, V0 and the
// neighbour lists are still in cache. Vertices with a neighbour beyond the lag
// (seams such as a torus's wrap-around) are marked "deferred" once per solve
// and get their residual after the sweep. A mesh in a very poor order (most
// vertices deferred, e.g. a shuffled file) is swept in a breadth-first order
// of its own (locality_order) and handed back in the caller's order. When
// more than 1/8 of the residuals would be deferred all the same, E_k comes
// from a residual pass after each sweep instead (Engine::fused_pays). E_0
// comes from the pass that sets V^(0) = V0 (Engine::start).
//
// Threads. The vertices are split into contiguous index ranges of equal work,
// one per thread, or, when that would leave many vertices with a neighbour in
// another range, renumbered into slabs across the mesh first (slab_order,
// each keeping the caller's order). A vertex with a neighbour in another
// range is an "interface" vertex: the ranges sweep their other vertices in
// parallel, in vertex order (no two of them are adjacent across ranges, so
// the result does not depend on timing), then one thread sweeps the
// interface vertices in vertex order. This is Gauss-Seidel in a slightly
// different vertex order (interface vertices last), so the iteration count
// stays about that of the sequential sweep (a multicolour order would change
// the ordering of every vertex). One fork and one join per sweep: each thread
// also computes the deferred residuals of its own range; the interface
// vertices, and the residuals that need them, run on the calling thread
// after the join.
//
// Layout. V is held as (n + 1, 4) doubles, the fourth lane and the last row
// zero, so a neighbour is one 32-byte load; V0 is read in place (n, 3). The
// arithmetic is per lane in the same order as the scalar formula, and an AVX2
// build of the kernels (picked at run time) gives the same bits as the
// baseline one (no FMA contraction: the target is avx2 alone).
#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <new>
#include <string>
#include <vector>

#include <omp.h>

#include "solver_detail.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {
namespace detail {
namespace {

// Every function taking or returning d4 is internal and inlined: the ABI
// note about passing AVX vectors without AVX does not concern us.
#pragma GCC diagnostic ignored "-Wpsabi"
typedef double d4 __attribute__((vector_size(32)));
typedef std::int32_t i4 __attribute__((vector_size(16)));
typedef std::uint32_t u4 __attribute__((vector_size(16)));

// n values of T, uninitialised (no pass to zero them, no page faulted in
// before its first use), 64-byte aligned, so that a row of x never straddles
// a cache line; with huge_pages, and when large, on a 2 MB boundary with
// transparent huge pages asked for: they save most of the page faults and
// TLB misses of x, the array the sweep gathers from (irregular:1000000:
// 0.258 s to solve with them, 0.273 s without). Not for the engine's other
// copies: a fresh huge page here took 2 to 20 times as long to fault in, at
// random (the renumbered operator of icosphere:8 in 4 ms or 80 ms, 7.5 ms
// steadily in 4 kB pages).
// std::vector<d4> would not even guarantee 32 bytes: the baseline target caps
// vector alignment at 16.
template <class T>
class Buffer {
 public:
  Buffer() = default;
  Buffer(std::size_t n, bool huge_pages) {
    const std::size_t bytes = std::max<std::size_t>(sizeof(T) * n, 64);
    const std::size_t align = huge_pages && bytes >= kHuge ? kHuge : 64;
    const std::size_t rounded = (bytes + align - 1) / align * align;
    void* p = std::aligned_alloc(align, rounded);
    if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    if (align == kHuge) madvise(p, rounded, MADV_HUGEPAGE);  // advice only: failure is harmless
#endif
    data_ = static_cast<T*>(p);
  }
  ~Buffer() { std::free(data_); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer& operator=(Buffer&& o) noexcept {
    std::swap(data_, o.data_);
    return *this;
  }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  static constexpr std::size_t kHuge = std::size_t{1} << 21;
  T* data_ = nullptr;
};

// A LimitOperator's arrays as the engine reads them: the caller's, or a
// renumbered copy of its own (Renumbered).
struct OpView {
  std::size_t n;
  const std::int32_t* offsets;  // n + 1
  const std::int32_t* neighbors;
  const double* diag;
  const double* weight;
};

OpView view(const LimitOperator& op) {
  return {op.n, op.offsets.data(), op.neighbors.data(), op.diag.data(), op.weight.data()};
}

constexpr std::uint8_t kInterface = 1;  // swept after the ranges, by one thread
constexpr std::uint8_t kDeferred = 2;   // residual after the sweep, not in it

// The largest lag of the residual front behind the update front.
constexpr std::int32_t kMaxLag = 8192;

struct Ctx {
  const std::int32_t* off;
  const std::int32_t* nb;
  std::int32_t n;             // the zero row of x
  std::int32_t slots_end;     // vertices below it may read kSlots entries of nb from off[i]
  const double* diag;
  const double* weight;
  const double* v0;           // (n, 3)
  d4* x;                      // (n + 1, 4), row n and lane 3 zero
  const std::uint8_t* flags;
  double omega;
  std::int32_t lag;           // residual front behind the update front, and the prefetch distance ahead of it
};

inline d4 splat(double a) { return d4{a, a, a, a}; }

// Sum of the neighbours' rows of x, in neighbour order (as neighbour_sum).
// The first K neighbours are summed by a loop of fixed length K: a loop over
// each vertex's own count mispredicts its exit about once per vertex on
// meshes that mix valences, which measured as the largest cost of a sweep on
// such meshes ("sor" on irregular:1000000: 0.48 s with the plain loop, 0.34 s
// with 8 slots selected one by one, 0.26 s selected four at a time). Slots
// past the valence add the zero row n, and adding +0.0 leaves every sum bit
// for bit as the plain loop gives it. K (a multiple of 4) is chosen per mesh
// from its valences (choose_slots); K = 0 is the plain loop.
template <int K>
__attribute__((always_inline)) inline d4 ring_sum(const Ctx& c, std::int32_t i) {
  const std::int32_t b = c.off[i], v = c.off[i + 1] - b;
  const std::int32_t* q = c.nb + b;
  d4 s = splat(0.0);
  std::int32_t k = 0;
  if (K > 0 && __builtin_expect(i < c.slots_end, 1)) {
    // Four slots at a time: the indices, or the zero row past the valence,
    // chosen by a vector mask and turned into byte offsets in one go (a
    // scalar select per slot costs seven instructions; written as a
    // conditional, GCC turns it back into a branch per slot).
    const i4 lane = {0, 1, 2, 3};
    const i4 valence = {v, v, v, v}, zero_row = {c.n, c.n, c.n, c.n};
    const char* base = reinterpret_cast<const char*>(c.x);
    for (; k < K; k += 4) {
      i4 j;
      std::memcpy(&j, q + k, sizeof j);  // readable below slots_end
      const i4 real = (lane + k) < valence;
      // Unsigned: a lane moved to a register is zero-extended for free,
      // where a signed one took a sign extension per neighbour; 32 * row
      // is exact below kMaxSlotRows rows.
      const u4 bytes = reinterpret_cast<u4>((j & real) | (zero_row & ~real)) << 5;
      for (int a = 0; a < 4; ++a) s += *reinterpret_cast<const d4*>(base + bytes[a]);
    }
  }
  for (; k < v; ++k) s += c.x[q[k]];
  return s;
}

__attribute__((always_inline)) inline d4 v0_row(const Ctx& c, std::int32_t i) {
  const double* y = c.v0 + 3 * static_cast<std::ptrdiff_t>(i);
  return d4{y[0], y[1], y[2], 0.0};
}

// ||v_i^0 - (B x)_i||^2, as residual() computes it.
template <int K>
__attribute__((always_inline)) inline double residual_sq(const Ctx& c, std::int32_t i) {
  const d4 s = ring_sum<K>(c, i);
  const d4 r = v0_row(c, i) - (splat(c.diag[i]) * c.x[i] + splat(c.weight[i]) * s);
  return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
}

// One vertex of the SOR-PIA sweep (paper eq. 18): d_i = (v_i^0 - v_i^inf) /
// alpha_i with the neighbours as they are now, v_i += omega d_i.
template <int K>
__attribute__((always_inline)) inline void update(const Ctx& c, std::int32_t i) {
  const d4 s = ring_sum<K>(c, i);
  const double d = c.diag[i];
  const d4 r = v0_row(c, i) - (splat(d) * c.x[i] + splat(c.weight[i]) * s);
  c.x[i] += splat(c.omega / d) * r;
}

// The row of x the front will first need `lag` vertices from now: on
// irregular meshes the farthest neighbours are reached out of order, which
// the hardware prefetcher does not follow (0.63 s -> 0.49 s on irregular:1000000).
__attribute__((always_inline)) inline void prefetch_ahead(const Ctx& c, std::int32_t i) {
  __builtin_prefetch(c.x + std::min(i + c.lag, c.n), 1);
}

// What the front does to vertex i.
enum class Front {
  Sweep,  // update it (interface vertices excepted)
  Init,   // x_i = v_i^0, every vertex: the residual lag behind is then E_0's
};

// Sweep [b, e) in order, skipping interface vertices (or with Front::Init,
// set x = V0 there); with Fused, also the residuals of its non-deferred
// vertices, lag behind. Returns their max ||r||^2.
template <bool Fused, int K, Front F = Front::Sweep>
__attribute__((always_inline)) inline double sweep_range_body(const Ctx& shared, std::int32_t b, std::int32_t e) {
  // A copy of its own: the stores to x could alias a shared Ctx for all the
  // compiler knows, which would reload its fields at every vertex.
  const Ctx c = shared;
  double m = 0.0;
  for (std::int32_t i = b; i < e; ++i) {
    if (F == Front::Init) {
      c.x[i] = v0_row(c, i);
    } else {
      prefetch_ahead(c, i);
      if (!(c.flags[i] & kInterface)) update<K>(c, i);
    }
    if (Fused) {
      const std::int32_t j = i - c.lag;
      if (j >= b && !(c.flags[j] & kDeferred)) m = std::max(m, residual_sq<K>(c, j));
    }
  }
  if (Fused)
    for (std::int32_t j = std::max(b, e - c.lag); j < e; ++j)
      if (!(c.flags[j] & kDeferred)) m = std::max(m, residual_sq<K>(c, j));
  return m;
}

template <int K>
__attribute__((always_inline)) inline double residual_range_body(const Ctx& c, std::int32_t b, std::int32_t e) {
  double m = 0.0;
  for (std::int32_t i = b; i < e; ++i) {
    prefetch_ahead(c, i);
    m = std::max(m, residual_sq<K>(c, i));
  }
  return m;
}

template <int K>
__attribute__((always_inline)) inline double residual_list_body(const Ctx& c, const std::int32_t* l, std::size_t k) {
  double m = 0.0;
  for (std::size_t t = 0; t < k; ++t) m = std::max(m, residual_sq<K>(c, l[t]));
  return m;
}

template <int K>
__attribute__((always_inline)) inline void update_list_body(const Ctx& c, const std::int32_t* l, std::size_t k) {
  for (std::size_t t = 0; t < k; ++t) update<K>(c, l[t]);
}

// The kernels for one slot count K, built for the baseline instruction set and
// for AVX2 (one 256-bit load and add per neighbour): the same arithmetic,
// lane by lane, so the same bits (no FMA: the target is avx2 alone).
struct Kernels {
  double (*sweep_fused)(const Ctx&, std::int32_t, std::int32_t);
  double (*init_fused)(const Ctx&, std::int32_t, std::int32_t);  // x = V0 and E_0's residuals
  double (*sweep_plain)(const Ctx&, std::int32_t, std::int32_t);
  double (*residual_range)(const Ctx&, std::int32_t, std::int32_t);
  double (*residual_list)(const Ctx&, const std::int32_t*, std::size_t);
  void (*update_list)(const Ctx&, const std::int32_t*, std::size_t);
};

#define SORPIA_SWEEP_KERNELS(NAME, ATTR, K)                                                                         \
  ATTR double NAME##K##_sweep_fused(const Ctx& c, std::int32_t b, std::int32_t e) {                                \
    return sweep_range_body<true, K>(c, b, e);                                                                     \
  }                                                                                                                \
  ATTR double NAME##K##_init_fused(const Ctx& c, std::int32_t b, std::int32_t e) {                                 \
    return sweep_range_body<true, K, Front::Init>(c, b, e);                                                        \
  }                                                                                                                \
  ATTR double NAME##K##_sweep_plain(const Ctx& c, std::int32_t b, std::int32_t e) {                                \
    return sweep_range_body<false, K>(c, b, e);                                                                    \
  }                                                                                                                \
  ATTR double NAME##K##_residual_range(const Ctx& c, std::int32_t b, std::int32_t e) {                             \
    return residual_range_body<K>(c, b, e);                                                                        \
  }                                                                                                                \
  ATTR double NAME##K##_residual_list(const Ctx& c, const std::int32_t* l, std::size_t k) {                       \
    return residual_list_body<K>(c, l, k);                                                                         \
  }                                                                                                                \
  ATTR void NAME##K##_update_list(const Ctx& c, const std::int32_t* l, std::size_t k) {                            \
    update_list_body<K>(c, l, k);                                                                                  \
  }                                                                                                                \
  const Kernels NAME##K##_kernels{NAME##K##_sweep_fused,    NAME##K##_init_fused,     NAME##K##_sweep_plain,       \
                                  NAME##K##_residual_range, NAME##K##_residual_list, NAME##K##_update_list};

// Slot counts offered; 0 = the plain loop.
constexpr int kSlotChoices[] = {0, 4, 8, 12};

// The rows of x (n + 1) the slot kernels can address: they form byte
// offsets 32 * row in 32-bit lanes. Larger meshes (over 134M vertices) take
// the plain loop, which indexes with full-width integers.
constexpr std::size_t kMaxSlotRows = std::size_t{1} << 27;

#define SORPIA_SWEEP_KERNEL_SET(NAME, ATTR) \
  SORPIA_SWEEP_KERNELS(NAME, ATTR, 0)       \
  SORPIA_SWEEP_KERNELS(NAME, ATTR, 4)       \
  SORPIA_SWEEP_KERNELS(NAME, ATTR, 8)       \
  SORPIA_SWEEP_KERNELS(NAME, ATTR, 12)      \
  const Kernels* const NAME##_set[] = {&NAME##0_kernels, &NAME##4_kernels, &NAME##8_kernels, &NAME##12_kernels};

SORPIA_SWEEP_KERNEL_SET(base, )
#if defined(__x86_64__) && defined(__GNUC__)
SORPIA_SWEEP_KERNEL_SET(avx2, __attribute__((target("avx2"))))
#endif
#undef SORPIA_SWEEP_KERNEL_SET
#undef SORPIA_SWEEP_KERNELS

// The kernels for kSlotChoices[choice].
const Kernels& kernels(int choice) {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  if (has_avx2) return *avx2_set[choice];
#endif
  return *base_set[choice];
}

// The slot count K with the least expected cost per vertex: a slot costs
// about one cycle, a vertex of valence above K (a loop exit the branch
// predictor cannot know) about 15. A mesh of one valence gets the plain loop
// (its exit always predicted); irregular:1000000 (valences 3..12, 90% at
// most 8) gets K = 8.
int choose_slots(const OpView& op) {
  std::vector<std::int64_t> above(kSlotChoices[std::size(kSlotChoices) - 1] + 2, 0);
  for (std::size_t i = 0; i < op.n; ++i) {
    const std::int32_t v = op.offsets[i + 1] - op.offsets[i];
    ++above[std::min<std::size_t>(static_cast<std::size_t>(v), above.size() - 1)];
  }
  // above[v] = vertices of valence > v
  std::int64_t rest = static_cast<std::int64_t>(op.n);
  for (std::size_t v = 0; v < above.size(); ++v) above[v] = (rest -= above[v]);
  int best = 0;
  double best_cost = NAN;
  const double n = std::max<double>(1.0, static_cast<double>(op.n));
  for (int choice = 0; choice < static_cast<int>(std::size(kSlotChoices)); ++choice) {
    const int k = kSlotChoices[choice];
    // The plain loop: every vertex whose valence differs from the last
    // one's mispredicts; estimated as all but the most common valence.
    double cost;
    if (k == 0) {
      std::int64_t most = 0;
      for (std::size_t v = 0; v + 1 < above.size(); ++v)
        most = std::max(most, (v ? above[v - 1] : static_cast<std::int64_t>(op.n)) - above[v]);
      cost = 15.0 * (1.0 - static_cast<double>(most) / n) + 0.0;
    } else {
      cost = static_cast<double>(k) + 15.0 * static_cast<double>(above[static_cast<std::size_t>(k)]) / n;
    }
    // The plain loop also skips the mask: prefer it on a tie.
    if (choice == 0) cost -= 0.5;
    if (std::isnan(best_cost) || cost < best_cost) best_cost = cost, best = choice;
  }
  return best;
}

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

// The first 4 kRingGroups neighbours of vertex i in s, the slots past its
// valence holding i itself; returns where the rest of its neighbours begin in
// nb (they end at nb + off[i + 1]). A loop of fixed length, as in ring_sum,
// for make_plan's passes over the rings: a loop over each vertex's own count
// mispredicts its exit about once a vertex, which made the reach pass 9 ms of
// the 12 ms of make_plan on irregular:1000000 (2.5 ms this way).
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

// Index ranges of equal work, one per thread: starts, threads + 1 of them,
// the last n. A vertex costs its neighbours plus about two neighbours' worth
// of its own loads and arithmetic.
std::vector<std::int32_t> equal_work_ranges(const OpView& op, int threads) {
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

// parallel: run the passes on the threads (their results do not depend on it).
// begin: the ranges' starts (threads + 1 of them, the last n).
Plan make_plan(const OpView& op, int threads, bool parallel, const std::vector<std::int32_t>& begin) {
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
#pragma omp parallel for num_threads(threads) schedule(static, 1) if (parallel)
  for (int t = 0; t < threads; ++t) {
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
  }
  for (auto& r : per_range) p.interface.insert(p.interface.end(), r.begin(), r.end());
  for (int t = 1; t < threads; ++t)
    for (int k = 0; k < kMaxLag + 2; ++k) reach_count[0][k] += reach_count[t][k];
  // The lag: the forward reach of all but about 1/1024 of the vertices, so
  // that the residual front stays close behind the update front (its rows
  // still in L2) and few residuals are deferred: a deferred residual gathers
  // from far rows, cache misses each (irregular:1000000, sor: 0.46 s with
  // 1/20 deferred, 0.34 s with 1/128, 0.32 s with 1/1024).
  std::int64_t beyond = n;
  p.lag = 0;
  while (p.lag <= kMaxLag && (beyond -= reach_count[0][p.lag]) > n / 1024) ++p.lag;
  p.lag = std::max<std::int32_t>(p.lag, 1);
  // Deferred: the residual of i is not final lag vertices later, because i or
  // a neighbour is swept in the interface phase, or a neighbour lies beyond the lag.
  std::vector<std::vector<std::int32_t>> after_interface(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) after_interface[t].reserve(p.interface.size());
#pragma omp parallel for num_threads(threads) schedule(static, 1) if (parallel)
  for (int t = 0; t < threads; ++t) {
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
  }
  p.local.push_back(0);
  for (auto& r : per_range) {
    p.deferred.insert(p.deferred.end(), r.begin(), r.end());
    p.local.push_back(p.deferred.size());
  }
  for (auto& r : after_interface) p.deferred.insert(p.deferred.end(), r.begin(), r.end());
  return p;
}

// A locality order for meshes whose own order is poor (a shuffled file, or
// an icosphere whose vertices come level by level): breadth-first search
// from the last vertex reached by a first search (Cuthill-McKee without its
// degree sort), component by component. Returns perm, perm[new] = old.
std::vector<std::int32_t> locality_order(const OpView& op) {
  const auto n = static_cast<std::int32_t>(op.n);
  std::vector<std::int32_t> order;
  order.reserve(op.n);
  std::vector<std::uint8_t> seen(op.n, 0);
  // BFS of the component of `start`, appended to order; returns its last vertex.
  auto bfs = [&](std::int32_t start) {
    std::size_t head = order.size();
    order.push_back(start);
    seen[start] = 1;
    while (head < order.size()) {
      const std::int32_t i = order[head++];
      for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q) {
        const std::int32_t j = op.neighbors[q];
        if (!seen[j]) {
          seen[j] = 1;
          order.push_back(j);
        }
      }
    }
    return order.back();
  };
  for (std::int32_t s = 0; s < n; ++s) {
    if (seen[s]) continue;
    // A first search finds a far vertex; the order is the search from it.
    const std::size_t first = order.size();
    const std::int32_t far = bfs(s);
    for (std::size_t k = first; k < order.size(); ++k) seen[order[k]] = 0;
    order.resize(first);
    bfs(far);
  }
  return order;
}

// An order for threads when index ranges split the mesh badly (most vertices
// would be interface vertices, swept by one thread: icosphere:8 comes level by
// level, so that the coarse vertices of the first range touch the second):
// slabs of equal work across the longest side of V0's bounding box, one per
// thread, each keeping the caller's vertex order (a good sweep order stays
// one: icosphere:8's coarse-to-fine order converges in 16 sweeps, a
// breadth-first one in 23). Only the slabs' common faces are interface.
// Returns perm (perm[new] = old); begin gets the slabs' starts.
std::vector<std::int32_t> slab_order(const OpView& op, const double* v0, int threads,
                                     std::vector<std::int32_t>& begin) {
  const auto n = static_cast<std::ptrdiff_t>(op.n);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = n ? v0[a] : 0.0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(min : lo[:3]) reduction(max : hi[:3])
  for (std::ptrdiff_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v0[3 * i + a]), hi[a] = std::max(hi[a], v0[3 * i + a]);
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  // Work per thin slice of the axis, then slabs as runs of slices: O(n),
  // equal work to within a slice (1/4096 of a slab).
  const std::size_t slices = 4096 * static_cast<std::size_t>(threads);
  const double width = hi[axis] - lo[axis], scale = width > 0 ? static_cast<double>(slices) / width : 0.0;
  std::vector<std::int32_t> slice(op.n);
  std::vector<double> work(slices * threads, 0.0);  // per thread, then summed into the first
#pragma omp parallel num_threads(threads)
  {
    double* w = work.data() + slices * static_cast<std::size_t>(omp_get_thread_num());
#pragma omp for schedule(static)
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const double f = (v0[3 * i + axis] - lo[axis]) * scale;  // NaN (a NaN in V0): slice 0
      slice[i] = f >= 0.0 ? static_cast<std::int32_t>(std::min<double>(f, static_cast<double>(slices - 1))) : 0;
      w[slice[i]] += op.offsets[i + 1] - op.offsets[i] + 2.0;  // as equal_work_ranges
    }
  }
  double total = 0.0;
  for (std::size_t k = 0; k < slices; ++k) {
    for (int t = 1; t < threads; ++t) work[k] += work[slices * t + k];
    total += work[k];
  }
  std::vector<std::int32_t> slab_of(slices);
  double sum = 0.0;
  for (std::size_t k = 0; k < slices; ++k) {
    slab_of[k] = std::min(threads - 1, static_cast<int>(sum / total * threads));
    sum += work[k];
  }
  // Counting sort by slab: stable, so each slab keeps the caller's order.
  begin.assign(static_cast<std::size_t>(threads) + 1, 0);
  for (std::ptrdiff_t i = 0; i < n; ++i) ++begin[slab_of[slice[i]] + 1];
  for (int t = 0; t < threads; ++t) begin[t + 1] += begin[t];
  std::vector<std::int32_t> perm(n), next(begin.begin(), begin.end() - 1);
  for (std::ptrdiff_t i = 0; i < n; ++i) perm[next[slab_of[slice[i]]]++] = static_cast<std::int32_t>(i);
  return perm;
}

// op with its vertices renumbered: row k is row perm[k] of op, neighbours
// renamed by inv (inv[perm[k]] = k), in the same ring order.
struct Renumbered {
  Buffer<std::int32_t> offsets, neighbors;
  Buffer<double> diag, weight;
  OpView view{};

  Renumbered() = default;
  Renumbered(const OpView& op, const std::int32_t* perm, const std::int32_t* inv, int threads, bool parallel)
      : offsets(op.n + 1, false),
        neighbors(static_cast<std::size_t>(op.offsets[op.n]), false),
        diag(op.n, false),
        weight(op.n, false) {
    offsets[0] = 0;
    for (std::size_t k = 0; k < op.n; ++k)
      offsets[k + 1] = offsets[k] + op.offsets[perm[k] + 1] - op.offsets[perm[k]];
    const auto n = static_cast<std::ptrdiff_t>(op.n);
    std::int32_t* nb = neighbors.data();
    const std::int32_t* off = offsets.data();
    double* d = diag.data();
    double* w = weight.data();
#pragma omp parallel for num_threads(threads) schedule(static) if (parallel)
    for (std::ptrdiff_t k = 0; k < n; ++k) {
      const std::int32_t i = perm[k];
      std::int32_t out = off[k];
      for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q) nb[out++] = inv[op.neighbors[q]];
      d[k] = op.diag[i];
      w[k] = op.weight[i];
    }
    view = {op.n, offsets.data(), neighbors.data(), diag.data(), weight.data()};
  }
  Renumbered& operator=(Renumbered&&) = default;
};

// How a vertex order suits the engine, from a sample of the vertices (the
// choice it informs is about speed alone): the fraction reaching further
// ahead than kMaxLag, and the fraction with a neighbour in another of the
// index ranges `begin`.
struct OrderSurvey {
  double far = 0.0, interface = 0.0;
};

OrderSurvey survey_order(const OpView& op, const std::vector<std::int32_t>& begin) {
  // 64 runs of 64 consecutive vertices, evenly spread: a few cache misses
  // a run rather than a few a vertex.
  const auto n = static_cast<std::int32_t>(op.n);
  constexpr std::int32_t kRuns = 64, kRun = 64;
  std::size_t count = 0, far = 0, interface = 0;
  int t = 0;
  for (std::int32_t r = 0; r < kRuns; ++r) {
    const std::int32_t b = static_cast<std::int32_t>(static_cast<std::int64_t>(n) * r / kRuns);
    for (std::int32_t i = b; i < std::min(n, b + kRun); ++i, ++count) {
      while (i >= begin[t + 1]) ++t;
      bool reaches = false, outside = false;
      for (std::int32_t q = op.offsets[i]; q < op.offsets[i + 1]; ++q) {
        const std::int32_t j = op.neighbors[q];
        reaches |= j - i > kMaxLag;
        outside |= j < begin[t] || j >= begin[t + 1];
      }
      far += reaches;
      interface += outside;
    }
  }
  const double c = std::max<double>(1.0, static_cast<double>(count));
  return {static_cast<double>(far) / c, static_cast<double>(interface) / c};
}

// Too poor an order: more than half of the vertices reach further ahead than
// kMaxLag, so that most residuals wait for a second pass and most gathers
// miss the cache (irregular:1000000 with its vertices shuffled: 2.3 s to
// solve, 0.56 s reordered, 21 sweeps either way). A merely imperfect order is
// kept: icosphere:8 comes level by level (26% far reaching) and converges in
// 16 sweeps in that order, 23 in the breadth-first one, so reordering it
// would not pay.
bool poor_order(const OrderSurvey& s) { return s.far > 0.5; }

// So many interface vertices that one thread would sweep a good part of the
// mesh alone (icosphere:8 split in two index ranges: 67%): the ranges are
// replaced by slabs (slab_order).
bool crowded_interface(const OrderSurvey& s) {
  return s.interface > 1.0 / 16;
}

class Engine {
 public:
  // v0: the caller's (n, 3) vertices, solved for as V0 / 2^exponent (in place
  // when exponent = 0 and the order is kept).
  Engine(const LimitOperator& op, const double* v0, int exponent, double omega, int threads)
      : op_(view(op)),
        // Below about 8k vertices a thread, waking the threads costs more
        // than they save; the ranges then run one after the other (the same
        // order, so the same result).
        parallel_(threads > 1 && op.n >= 8192 * static_cast<std::size_t>(threads)),
        x_(op.n + 1, true),
        exponent_(exponent) {
    x_[op.n] = splat(0.0);  // the zero row
    std::vector<std::int32_t> begin = equal_work_ranges(op_, threads);
    const OrderSurvey survey = survey_order(op_, begin);
    const bool poor = poor_order(survey);
    if (poor) {
      // Sweep in a locality order instead (a Gauss-Seidel order like any
      // other: same solution, iteration counts within a few percent), and
      // hand the control vertices back in the caller's order.
      perm_ = locality_order(op_);
    } else if (parallel_ && crowded_interface(survey)) {
      perm_ = slab_order(op_, v0, threads, begin);
    }
    const std::size_t n = op.n;
    if (!perm_.empty() || exponent_ != 0) v0_ = Buffer<double>(3 * n, false);
    if (!perm_.empty()) {
      inv_.resize(n);
      for (std::size_t k = 0; k < n; ++k) inv_[perm_[k]] = static_cast<std::int32_t>(k);
      reordered_ = Renumbered(op_, perm_.data(), inv_.data(), threads, parallel_);
      op_ = reordered_.view;
      if (poor) begin = equal_work_ranges(op_, threads);
      double* w = v0_.data();
      const std::int32_t* perm = perm_.data();
#pragma omp parallel for num_threads(threads) schedule(static) if (parallel_)
      for (std::size_t k = 0; k < n; ++k)
        for (int a = 0; a < 3; ++a) w[3 * k + a] = v0[3 * static_cast<std::size_t>(perm[k]) + a];
    } else if (exponent_ != 0) {
      std::memcpy(v0_.data(), v0, 3 * n * sizeof(double));
    }
    if (v0_.data()) {
      scale_pow2(v0_.data(), 3 * n, -exponent_);
      v0 = v0_.data();
    }
    plan_ = make_plan(op_, threads, parallel_, begin);
    const int choice = n + 1 <= kMaxSlotRows ? choose_slots(op_) : 0;  // index into kSlotChoices
    k_ = &kernels(choice);
    const std::int32_t nnz = op_.offsets[n];
    auto slots_end = static_cast<std::int32_t>(n);
    while (slots_end > 0 && op_.offsets[slots_end - 1] + kSlotChoices[choice] > nnz) --slots_end;
    ctx_ = Ctx{op_.offsets,  op_.neighbors, static_cast<std::int32_t>(n), slots_end, op_.diag, op_.weight, v0,
               x_.data(), plan_.flags.data(), omega, plan_.lag};
  }

  // Whether E_k inside the sweep is faster than a residual pass after it.
  // Not when many residuals are deferred: each gathers its neighbours from
  // rows long evicted (icosphere:8, whose coarse vertices, a quarter, reach
  // far ahead: 16 sweeps in 0.246 s fused, 0.226 s with residual passes).
  // Either way gives the same E_k, bit for bit.
  bool fused_pays() const {
    return plan_.deferred.size() <= op_.n / 8;
  }

  // Whether the vertices are swept in another order than the caller's.
  bool reordered() const { return !perm_.empty(); }

  int threads() const { return static_cast<int>(plan_.begin.size()) - 1; }

  // max_i ||v_i^0|| of the (scaled) V0: the monitor's rounding level.
  double scale() const { return max_row_norm(ctx_.v0, op_.n); }

  // Sets V^(0) = V0 and returns E_0, in one pass: the residuals run lag
  // behind the rows being set, as in a fused sweep (the same bits as
  // residual(), without reading x back from memory).
  // On the calling thread alone, the ranges one after the other: threads
  // writing the fresh rows of x at once took 36 ms instead of 5 in about one
  // process of three (2 threads, irregular:1000000; page faults on one
  // mapping), one thread takes 8.5 ms.
  double start() {
    const int t_count = threads();
    double m = 0.0;
    for (int t = 0; t < t_count; ++t) m = std::max(m, k_->init_fused(ctx_, plan_.begin[t], plan_.begin[t + 1]));
    m = std::max(m, k_->residual_list(ctx_, plan_.deferred.data(), plan_.deferred.size()));
    return std::sqrt(m);
  }

  // E of the current iterate, by a residual pass.
  double residual() const {
    const int t_count = threads();
    double m = 0.0;
#pragma omp parallel for num_threads(t_count) schedule(static, 1) reduction(max : m) if (parallel_)
    for (int t = 0; t < t_count; ++t) m = std::max(m, k_->residual_range(ctx_, plan_.begin[t], plan_.begin[t + 1]));
    return std::sqrt(m);
  }

  // One sweep; fused: returns E of the new iterate, else NaN. The ranges run
  // in parallel; the interface vertices and the deferred residuals (a few
  // percent of the vertices on a well-ordered mesh) run on the calling thread
  // after the join: one fork and one join per sweep, the fewest waits for
  // threads that the system may have descheduled.
  double sweep(bool fused) {
    const int t_count = threads();
    const auto sweep_range = fused ? k_->sweep_fused : k_->sweep_plain;
    double m = 0.0;
    const std::int32_t* deferred = plan_.deferred.data();
#pragma omp parallel for num_threads(t_count) schedule(static, 1) reduction(max : m) if (parallel_)
    for (int t = 0; t < t_count; ++t) {
      m = std::max(m, sweep_range(ctx_, plan_.begin[t], plan_.begin[t + 1]));
      // The deferred residuals of the range's own vertices, final now.
      if (fused) m = std::max(m, k_->residual_list(ctx_, deferred + plan_.local[t], plan_.local[t + 1] - plan_.local[t]));
    }
    k_->update_list(ctx_, plan_.interface.data(), plan_.interface.size());
    if (!fused) return NAN;
    const std::size_t rest = plan_.local[t_count];
    m = std::max(m, k_->residual_list(ctx_, deferred + rest, plan_.deferred.size() - rest));
    return std::sqrt(m);
  }

  // (n, 3) control vertices, times 2^exponent().
  void write(double* v) const {
    const auto n = static_cast<std::ptrdiff_t>(op_.n);
#pragma omp parallel for num_threads(threads()) schedule(static) if (parallel_)
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const d4& y = x_[perm_.empty() ? i : inv_[i]];
      for (int a = 0; a < 3; ++a) v[3 * i + a] = y[a];
    }
    scale_pow2(v, 3 * n, exponent_);
  }

 private:
  OpView op_;                             // the operator swept: the caller's or reordered_
  bool parallel_;                         // threads really run in parallel
  std::vector<std::int32_t> perm_, inv_;  // the sweep's order (empty: the caller's): perm[new] = old
  Renumbered reordered_;                  // the caller's operator in that order
  Plan plan_;
  const Kernels* k_ = nullptr;
  Buffer<d4> x_;                          // (n + 1) rows
  int exponent_;
  Buffer<double> v0_;                     // V0 reordered and/or divided by 2^exponent, when either applies
  Ctx ctx_;
};

}  // namespace

void solve_sor(const LimitOperator& op, const double* v0, int exponent, const SolveOptions& opt, double omega,
               SolveResult& res) {
  Engine engine(op, v0, exponent, omega, opt.threads);
  res.reordered = engine.reordered();
  const bool fused = !opt.two_pass && engine.fused_pays();
  const double e0 = engine.start();
  Monitor mon(opt, res, engine.scale());
  if (!mon.start(e0)) {
    for (;;) {
      double e = engine.sweep(fused);
      res.products += 2;  // a sweep and a residual, fused or not
      if (!fused) e = engine.residual();
      if (mon.record(e)) break;
    }
  }
  res.control_vertices.resize(3 * op.n);
  engine.write(res.control_vertices.data());
}

}  // namespace detail
}  // namespace sorpia
