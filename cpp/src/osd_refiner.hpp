#pragma once
// Building an OpenSubdiv Loop refiner from a sorpia::Topology (internal).
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefiner.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "sorpia/topology.hpp"

namespace sorpia::detail {

namespace Far = OpenSubdiv::Far;

// OpenSubdiv is given only the referenced vertices (an isolated vertex has no
// Loop limit); `to_osd[v]` is vertex v's index in the refiner, or -1, and
// `from_osd` is its inverse.
struct LoopRefiner {
  std::unique_ptr<Far::TopologyRefiner> refiner;
  std::vector<std::int32_t> to_osd;
  std::vector<std::int32_t> from_osd;
};

// A refiner for `desc` under `scheme` and `boundary` (Sdc's other options at
// their defaults: CREASE_UNIFORM, the rules sorpia's limit masks assume).
// Throws sorpia::MeshError when OpenSubdiv refuses the topology.
std::unique_ptr<Far::TopologyRefiner> create_refiner(const Far::TopologyDescriptor& desc, Scheme scheme,
                                                     Boundary boundary);

// Throws sorpia::MeshError when OpenSubdiv refuses the topology.
LoopRefiner make_loop_refiner(const Topology& topology, Boundary boundary);

// A position as OpenSubdiv's PrimvarRefiner combines them (Clear, AddWithWeight).
struct Point3 {
  double x, y, z;
  void Clear() { x = y = z = 0.0; }
  void AddWithWeight(const Point3& p, double w) {
    x += w * p.x;
    y += w * p.y;
    z += w * p.z;
  }
};

// points = the referenced rows of `vertices` (row-major (n, 3)), in the refiner's order.
void gather_points(const LoopRefiner& osd, const double* vertices, std::vector<Point3>& points);

// out = B V (row-major (n, 3)): `vertices` with each referenced vertex's row
// replaced by its limit position, from the unrefined refiner's Limit() on
// `points` (gather_points of `vertices`); an unreferenced vertex is its own limit.
void limit_positions(const LoopRefiner& osd, const std::vector<Point3>& points, const double* vertices,
                     std::size_t n, double* out);

}  // namespace sorpia::detail
