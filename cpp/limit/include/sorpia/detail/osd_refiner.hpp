#pragma once
// Building an OpenSubdiv refiner from a sorpia::Topology (internal).
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefiner.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "sorpia/subdivision.hpp"
#include "sorpia/topology.hpp"

namespace sorpia::detail {

namespace Far = OpenSubdiv::Far;

// OpenSubdiv is given only the referenced vertices (an isolated vertex has no
// limit); `to_osd[v]` is vertex v's index in the refiner, or -1, and
// `from_osd` is its inverse. Faces keep their indices.
struct Refiner {
  std::unique_ptr<Far::TopologyRefiner> refiner;
  std::vector<std::int32_t> to_osd;
  std::vector<std::int32_t> from_osd;
};

// Far's float sharpness of a sorpia sharpness: kInfiniteSharpness and above
// become Sdc::Crease::SHARPNESS_INFINITE.
float osd_sharpness(double s);

// The arrays a Far::TopologyDescriptor points to: the faces, and the tags in
// the refiner's own vertex and face numbering (sharpness as osd_sharpness).
struct RefinerInput {
  int n_vertices = 0;
  std::vector<int> counts, indices;
  std::vector<int> crease_pairs;  // (k, 2) row-major
  std::vector<float> crease_sharpness;
  std::vector<int> corners;
  std::vector<float> corner_sharpness;
  std::vector<int> holes;
};

// A refiner for `input` under `scheme` and `boundary` (Sdc's other options at
// their defaults: CREASE_UNIFORM, the rules sorpia's limit masks assume).
// Throws sorpia::MeshError when OpenSubdiv refuses the topology.
std::unique_ptr<Far::TopologyRefiner> create_refiner(const RefinerInput& input, Scheme scheme, Boundary boundary);

// The unrefined Far::TopologyRefiner of the mesh under `scheme` and
// `boundary`, with the sharpness tags in its TopologyDescriptor (creases and
// corners mapped through to_osd; sharpness as float, kInfiniteSharpness and
// above as Sdc::Crease::SHARPNESS_INFINITE). `tags` must have passed
// check_tags. Throws sorpia::MeshError when OpenSubdiv refuses the topology
// (Loop with a non-triangle face) or a tag names a vertex no face uses.
Refiner make_refiner(const Topology& topology, Scheme scheme, Boundary boundary, const Tags& tags = {});

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
void gather_points(const Refiner& osd, const double* vertices, std::vector<Point3>& points);

// out = B V (row-major (n, 3)): `vertices` with each referenced vertex's row
// replaced by its limit position, from the unrefined refiner's Limit() on
// `points` (gather_points of `vertices`); an unreferenced vertex is its own limit.
void limit_positions(const Refiner& osd, const std::vector<Point3>& points, const double* vertices,
                     std::size_t n, double* out);

}  // namespace sorpia::detail
