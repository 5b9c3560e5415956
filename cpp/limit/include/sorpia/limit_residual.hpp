#pragma once
/// @file limit_residual.hpp
/// How far the limit surface of control vertices V misses target points V0:
/// r_i = ||(B V)_i - v0_i||, with (B V)_i evaluated from OpenSubdiv's limit
/// mask of vertex i (sorpia::limit_mask) over the topology's one-ring.
///
/// A check of a solve that shares nothing with the solvers but the topology:
/// not their operator arrays, vertex order or sweep, so a wrong weight, a
/// wrong reordering or a wrong sweep shows as a large residual.

#include <cstddef>

#include "sorpia/topology.hpp"

namespace sorpia {

struct LimitResidual {
  double max = 0.0;         ///< max_i r_i (0 for no vertices)
  std::size_t argmax = 0;   ///< the first vertex where it is reached
};

/// @param control  row-major (n_vertices, 3) control vertices V
/// @param target   row-major (n_vertices, 3) points V0
/// @param norms    when not null, r_i for every vertex (n_vertices values, written)
LimitResidual limit_residual(const Topology& topology, const double* control, const double* target,
                             Boundary boundary, double* norms = nullptr);

}  // namespace sorpia
