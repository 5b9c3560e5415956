#pragma once
// The sweep's inner loops, included by exactly the translation units that
// build them for one instruction set each (sweep_kernels.cpp: baseline;
// sweep_kernels_avx2.cpp: -mavx2). Everything here has internal linkage, so
// no function compiled for AVX2 can stand in for a baseline one at link time;
// for the same reason the loops call no inline function of the standard
// library that the compiler might leave out of line, and the row kernels of
// apply.hpp they call are always inlined (no out-of-line copy is emitted).
// Not a public header.
//
// The rows are the row kernels of sorpia/detail/apply.hpp on 4-lane rows:
// the arithmetic is per lane in the same order as on (n, k) arrays, so both
// builds give the same bits as every other product with B: the AVX2 unit is
// compiled without FMA, so nothing is contracted.
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "sweep_kernels.hpp"

namespace sorpia {
namespace detail {
namespace {

// The template argument of the kernels for rows with per-entry weights.
constexpr int kPerEntry = -1;

// The kind of rows (apply.hpp) of the kernels for K.
template <int K>
using KindOf = std::conditional_t<K == kPerEntry, PerEntryRows, UniformRows>;

inline double larger(double a, double b) { return a < b ? b : a; }
inline std::int32_t smaller(std::int32_t a, std::int32_t b) { return b < a ? b : a; }

// Row j of x as the row kernels read it.
struct Lanes {
  const d4* x;
  __attribute__((always_inline)) const d4& operator()(std::int32_t j) const { return x[j]; }
};

// The sum of the neighbours' rows of x (uniform rows), in neighbour order,
// the first K neighbours by a loop of fixed length K: a loop over each
// vertex's own count mispredicts its exit about once per vertex on meshes
// that mix valences, the largest cost of a sweep on such meshes. Slots past
// the valence add the zero row n, and adding +0.0 leaves every sum bit for
// bit as NeighbourSum (apply.hpp) gives it. K (a multiple of 4) is chosen per
// mesh from its valences (choose_slots); K = 0 is NeighbourSum's loop.
template <int K>
struct SlotSum {
  const Ctx& c;
  __attribute__((always_inline)) d4 operator()(std::int32_t i) const {
    const std::int32_t b = c.rows.offsets[i], v = c.rows.offsets[i + 1] - b;
    const std::int32_t* q = c.rows.neighbors + b;
    d4 s{};
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
};

__attribute__((always_inline)) inline d4 v0_row(const Ctx& c, std::int32_t i) {
  const double* y = c.v0 + 3 * static_cast<std::ptrdiff_t>(i);
  return d4{y[0], y[1], y[2], 0.0};
}

// v_i^0 - (B x)_i.
template <int K>
__attribute__((always_inline)) inline d4 residual(const Ctx& c, std::int32_t i) {
  return v0_row(c, i) - row_product<KindOf<K>, d4>(c.rows, Lanes{c.x}, i, SlotSum<K>{c});
}

// ||v_i^0 - (B x)_i||^2, as residual() (solver_detail.hpp) computes it.
template <int K>
__attribute__((always_inline)) inline double residual_sq(const Ctx& c, std::int32_t i) {
  const d4 r = residual<K>(c, i);
  return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
}

// One vertex of the SOR-PIA sweep (paper eq. 18), with the neighbours as
// they are now.
template <int K>
__attribute__((always_inline)) inline void update(const Ctx& c, std::int32_t i) {
  c.x[i] += relaxation(c.rows, i, c.omega, residual<K>(c, i));
}

// The row of x the front will first need `lag` vertices from now: on
// irregular meshes the farthest neighbours are reached out of order, which
// the hardware prefetcher does not follow.
__attribute__((always_inline)) inline void prefetch_ahead(const Ctx& c, std::int32_t i) {
  __builtin_prefetch(c.x + smaller(i + c.lag, c.n), 1);
}

// What the front does to vertex i.
enum class Front {
  Sweep,  // update it (interface vertices excepted)
  Init,   // x_i = v_i^0, every vertex: the residual lag behind is then E_0's
};

// Sweep [b, e) in order, skipping interface vertices (or with Front::Init,
// set x = V0 there); with Fused, also the residuals of its non-deferred
// vertices, lag behind. Returns their max ||r||^2.
template <bool Fused, int K, Front F>
double sweep_range(const Ctx& shared, std::int32_t b, std::int32_t e) {
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
      if (j >= b && !(c.flags[j] & kDeferred)) m = larger(m, residual_sq<K>(c, j));
    }
  }
  if (Fused)
    for (std::int32_t j = b < e - c.lag ? e - c.lag : b; j < e; ++j)
      if (!(c.flags[j] & kDeferred)) m = larger(m, residual_sq<K>(c, j));
  return m;
}

template <int K>
double residual_range(const Ctx& c, std::int32_t b, std::int32_t e) {
  double m = 0.0;
  for (std::int32_t i = b; i < e; ++i) {
    prefetch_ahead(c, i);
    m = larger(m, residual_sq<K>(c, i));
  }
  return m;
}

template <int K>
double residual_list(const Ctx& c, const std::int32_t* l, std::size_t k) {
  double m = 0.0;
  for (std::size_t t = 0; t < k; ++t) m = larger(m, residual_sq<K>(c, l[t]));
  return m;
}

template <int K>
void update_list(const Ctx& c, const std::int32_t* l, std::size_t k) {
  for (std::size_t t = 0; t < k; ++t) update<K>(c, l[t]);
}

template <int K>
const Kernels kernel_table{&sweep_range<true, K, Front::Sweep>, &sweep_range<true, K, Front::Init>,
                           &sweep_range<false, K, Front::Sweep>, &residual_range<K>,
                           &residual_list<K>, &update_list<K>};

// The uniform-row kernels for kSlotChoices[choice], built for this unit's
// instruction set.
const Kernels& slot_kernels(int choice) {
  static_assert(sizeof kSlotChoices / sizeof kSlotChoices[0] == 4, "one table per slot choice");
  static const Kernels* const set[] = {&kernel_table<kSlotChoices[0]>, &kernel_table<kSlotChoices[1]>,
                                       &kernel_table<kSlotChoices[2]>, &kernel_table<kSlotChoices[3]>};
  return *set[choice];
}

}  // namespace
}  // namespace detail
}  // namespace sorpia
