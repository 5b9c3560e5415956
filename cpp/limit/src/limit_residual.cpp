#include "sorpia/limit_residual.hpp"

#include <cmath>

#include "sorpia/limit_masks.hpp"

namespace sorpia {

LimitResidual limit_residual(const Topology& topology, const double* control, const double* target,
                             Boundary boundary, double* norms) {
  const auto& offsets = topology.ring_offsets();
  const auto& ring = topology.ring_neighbors();
  LimitResidual out;
  for (std::size_t i = 0; i < topology.n_vertices(); ++i) {
    const LimitMask mask = limit_mask(topology, i, boundary);
    double p[3];
    for (int k = 0; k < 3; ++k) p[k] = mask.diag * control[3 * i + k];
    auto add = [&](std::int32_t j) {
      for (int k = 0; k < 3; ++k) p[k] += mask.weight * control[3 * static_cast<std::size_t>(j) + k];
    };
    if (mask.weight != 0.0) {
      const std::int32_t first = offsets[i], last = offsets[i + 1] - 1;
      if (topology.is_boundary(i)) {  // the crease mask: the two boundary neighbours, first and last of the ring
        add(ring[first]);
        add(ring[last]);
      } else {
        for (std::int32_t q = first; q <= last; ++q) add(ring[q]);
      }
    }
    const double dx = p[0] - target[3 * i], dy = p[1] - target[3 * i + 1], dz = p[2] - target[3 * i + 2];
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (norms) norms[i] = r;
    if (r > out.max || (std::isnan(r) && !std::isnan(out.max))) {  // a NaN residual is the worst
      out.max = r;
      out.argmax = i;
    }
  }
  return out;
}

}  // namespace sorpia
