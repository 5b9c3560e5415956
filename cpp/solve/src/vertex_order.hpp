#pragma once
// The orders the sweep engine (solver_sweep.cpp) may sweep a mesh in instead
// of the caller's, how it decides, and the operator renumbered into one.
// Not a public header.
#include <cstdint>
#include <vector>

#include "aligned_buffer.hpp"
#include "sweep_kernels.hpp"

namespace sorpia {
namespace detail {

// A locality order for meshes whose own order is poor (a shuffled file, or
// an icosphere whose vertices come level by level): breadth-first search
// from the last vertex reached by a first search (Cuthill-McKee without its
// degree sort), component by component. Returns perm, perm[new] = old.
std::vector<std::int32_t> locality_order(const Rows& op);

// An order for threads when index ranges split the mesh badly (most vertices
// would be interface vertices, swept by one thread; an icosphere numbered
// level by level puts every coarse vertex in the first range, next to the
// second): slabs of equal work across the longest side of V0's bounding box,
// one per thread, each keeping the caller's vertex order (a good sweep order
// stays one; a breadth-first order would cost the icosphere's coarse-to-fine
// order sweeps). Only the slabs' common faces are interface.
// Returns perm (perm[new] = old); begin gets the slabs' starts.
std::vector<std::int32_t> slab_order(const Rows& op, const double* v0, int threads,
                                     std::vector<std::int32_t>& begin);

// op with its vertices renumbered: row k is row perm[k] of op, neighbours
// renamed by inv (inv[perm[k]] = k), in the same ring order, with the same
// weights.
struct Renumbered {
  AlignedBuffer<std::int32_t> offsets, neighbors;
  AlignedBuffer<double> diag, weight, values;
  Rows view{};

  Renumbered() = default;
  // parallel: copy the rows on `threads` threads.
  Renumbered(const Rows& op, const std::int32_t* perm, const std::int32_t* inv, int threads, bool parallel);
  Renumbered& operator=(Renumbered&&) = default;
};

// How a vertex order suits the engine, from a sample of the vertices (the
// choice it informs is about speed alone): the fraction reaching further
// ahead than kMaxLag, and the fraction with a neighbour in another of the
// index ranges `begin`.
struct OrderSurvey {
  double far = 0.0, interface = 0.0;
};
OrderSurvey survey_order(const Rows& op, const std::vector<std::int32_t>& begin);

// Too poor an order: more than half of the vertices reach further ahead than
// kMaxLag, so that most residuals wait for a second pass and most gathers
// miss the cache; swept in locality_order instead, in about as many sweeps.
// A merely imperfect order is kept: an icosphere numbered level by level
// (about a quarter far reaching) converges in fewer sweeps in that order than
// in a breadth-first one.
inline bool poor_order(const OrderSurvey& s) { return s.far > 0.5; }

// So many interface vertices that one thread would sweep a good part of the
// mesh alone: the ranges are replaced by slabs (slab_order).
inline bool crowded_interface(const OrderSurvey& s) { return s.interface > 1.0 / 16; }

}  // namespace detail
}  // namespace sorpia
