// The AVX2 build of the sweep kernels (uniform rows and per-entry weights):
// one 256-bit load and add (and multiply, per entry) per neighbour. CMake compiles this unit alone with -mavx2 (and without -mfma, so
// that no multiply-add is contracted and the bits are the baseline build's)
// and defines SORPIA_AVX2_KERNELS where it can; uniform_kernels picks it at
// run time on processors that have AVX2 (uniform_kernels, per_entry_kernels).
#ifdef SORPIA_AVX2_KERNELS
#include "sweep_kernels_impl.hpp"

namespace sorpia {
namespace detail {

const Kernels& avx2_uniform_kernels(int choice) { return slot_kernels(choice); }

const Kernels& avx2_per_entry_kernels() { return kernel_table<kPerEntry>; }

}  // namespace detail
}  // namespace sorpia
#endif
