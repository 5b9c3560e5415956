// The baseline build of the sweep's kernels, the run-time choice between it
// and the AVX2 build, and the choice of slot count.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>

#include "sweep_kernels_impl.hpp"

namespace sorpia {
namespace detail {

const Kernels& uniform_kernels(int choice) {
#ifdef SORPIA_AVX2_KERNELS
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  if (has_avx2) return avx2_uniform_kernels(choice);
#endif
  return slot_kernels(choice);
}

const Kernels& per_entry_kernels() {
#ifdef SORPIA_AVX2_KERNELS
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  if (has_avx2) return avx2_per_entry_kernels();
#endif
  return kernel_table<kPerEntry>;
}

// The slot count K with the least expected cost per vertex: a slot costs
// about one cycle, a vertex of valence above K (a loop exit the branch
// predictor cannot know) about 15. A mesh of one valence gets the plain loop
// (its exit always predicted); a mesh of valences 3..12, nine in ten at most
// 8, gets K = 8.
int choose_slots(const Rows& op) {
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
      cost = 15.0 * (1.0 - static_cast<double>(most) / n);
    } else {
      cost = static_cast<double>(k) + 15.0 * static_cast<double>(above[static_cast<std::size_t>(k)]) / n;
    }
    // The plain loop also skips the mask: prefer it on a tie.
    if (choice == 0) cost -= 0.5;
    if (std::isnan(best_cost) || cost < best_cost) best_cost = cost, best = choice;
  }
  return best;
}

}  // namespace detail
}  // namespace sorpia
