#pragma once
// The sweep's inner loops ("sor"/"gs", solver_sweep.cpp) as the engine sees
// them: the arrays they read (Ctx), one table of function pointers per slot
// count, and the choice among them. The loops themselves are in
// sweep_kernels_impl.hpp, compiled once for the baseline instruction set
// (sweep_kernels.cpp) and once for AVX2 (sweep_kernels_avx2.cpp), picked at
// run time. Not a public header.
#include <cstddef>
#include <cstdint>

// Every function taking or returning these vectors is internal: the ABI note
// about passing AVX vectors without AVX does not concern us (here or in the
// row kernels of apply.hpp, instantiated for them).
#pragma GCC diagnostic ignored "-Wpsabi"

#include "sorpia/detail/apply.hpp"

namespace sorpia {
namespace detail {

typedef double d4 __attribute__((vector_size(32)));
typedef std::int32_t i4 __attribute__((vector_size(16)));
typedef std::uint32_t u4 __attribute__((vector_size(16)));

// Per-vertex flags of the plan (sweep_plan.hpp).
constexpr std::uint8_t kInterface = 1;  // swept after the ranges, by one thread
constexpr std::uint8_t kDeferred = 2;   // residual after the sweep, not in it

// What the kernels read and write.
struct Ctx {
  Rows rows;                  // the operator swept: the caller's, or a renumbered copy (Renumbered)
  std::int32_t n;             // the zero row of x
  std::int32_t slots_end;     // the slot kernels may read K entries of neighbors from offsets[i] for i below it
  const double* v0;           // (n, 3)
  d4* x;                      // (n + 1, 4), row n and lane 3 zero
  const std::uint8_t* flags;
  double omega;
  std::int32_t lag;           // residual front behind the update front, and the prefetch distance ahead of it
};

// The kernels for one kind of row (a slot count K for uniform rows, or
// per-entry weights). Each computes ||v_i^0 - (B x)_i||^2 and the update of
// eq. 18 by the row kernels of detail/apply.hpp, so a residual inside the
// sweep and one in a separate pass give the same bits, those of every other
// product with B.
struct Kernels {
  // Sweep [b, e) in vertex order, skipping interface vertices; returns the max
  // ||r||^2 of its non-deferred vertices, lag behind the front.
  double (*sweep_fused)(const Ctx&, std::int32_t, std::int32_t);
  // x = V0 on [b, e), and E_0's residuals as in sweep_fused.
  double (*init_fused)(const Ctx&, std::int32_t, std::int32_t);
  // Sweep [b, e) as sweep_fused, without residuals (returns 0).
  double (*sweep_plain)(const Ctx&, std::int32_t, std::int32_t);
  // Max ||r||^2 over [b, e).
  double (*residual_range)(const Ctx&, std::int32_t, std::int32_t);
  // Max ||r||^2 over the k vertices of l.
  double (*residual_list)(const Ctx&, const std::int32_t*, std::size_t);
  // Update the k vertices of l, in that order.
  void (*update_list)(const Ctx&, const std::int32_t*, std::size_t);
};

// Slot counts offered for uniform rows; 0 = the plain loop.
constexpr int kSlotChoices[] = {0, 4, 8, 12};

// The rows of x (n + 1) the slot kernels can address: they form byte
// offsets 32 * row in 32-bit lanes. Larger meshes (over 134M vertices) take
// the plain loop, which indexes with full-width integers.
constexpr std::size_t kMaxSlotRows = std::size_t{1} << 27;

// Index into kSlotChoices for op's valences (uniform rows).
int choose_slots(const Rows& op);

// The kernels for uniform rows with kSlotChoices[choice] slots: the AVX2 build
// where the processor has it, else the baseline one (the same bits).
const Kernels& uniform_kernels(int choice);

// The kernels for rows with per-entry weights (Rows::values): the AVX2
// build where the processor has it, else the baseline one (the same bits).
const Kernels& per_entry_kernels();

// The AVX2 builds of uniform_kernels and per_entry_kernels
// (sweep_kernels_avx2.cpp), present when CMake compiles that unit with -mavx2
// (SORPIA_AVX2_KERNELS).
const Kernels& avx2_uniform_kernels(int choice);
const Kernels& avx2_per_entry_kernels();

}  // namespace detail
}  // namespace sorpia
