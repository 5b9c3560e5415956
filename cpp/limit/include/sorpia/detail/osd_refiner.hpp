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
// (Loop with a non-triangle face), a tag names a vertex no face uses, or
// every face is a hole (the limit surface is empty).
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

// A Refiner's mesh refined uniformly by Far: the one refinement that
// LimitSurface::tessellate (the limit surface as a mesh) and refine_uniform
// (the finer control mesh and its matrix R) share. The refiner made here
// shares `base`'s level 0 (Far::TopologyRefinerFactory::Create of a
// refiner), so `base` must outlive it. Far orders the children of vertices
// first, so vertex j < n_osd() of every level descends from vertex j of
// level 0 (checked by the constructor: the numbering below relies on it).
class UniformRefinement {
 public:
  // `base` (of a mesh of n_vertices vertices) refined `levels` >= 0 times,
  // the last level with its full topology (edges, vertex-face relations:
  // Limit() and the sharpness of edges need them) when `full_topology`.
  // Polls sorpia::poll_interrupt() before refining.
  UniformRefinement(const Refiner& base, std::size_t n_vertices, int levels, bool full_topology);
  const Far::TopologyRefiner& refiner() const { return *refiner_; }
  int levels() const { return levels_; }
  const Far::TopologyLevel& last() const { return refiner_->GetLevel(levels_); }
  // The referenced vertices, the vertices of level 0.
  std::size_t n_osd() const { return n_osd_; }
  // Vertices of the last level in sorpia's numbering: the n_vertices of the
  // mesh (an unreferenced one stays unreferenced), then the ones Far adds.
  std::size_t n_fine_vertices() const;
  // sorpia's index of vertex j of the last level: the mesh vertex it descends
  // from for j < n_osd(), else n_vertices + j - n_osd().
  std::int32_t fine_index(int j) const {
    const auto u = static_cast<std::size_t>(j);
    return u < n_osd_ ? from_osd_[u] : static_cast<std::int32_t>(n_vertices_ + u - n_osd_);
  }
  // `points`, level 0's (gather_points), carried to the last level by Far's
  // PrimvarRefinerReal<double>::Interpolate, level by level (polling before
  // each level).
  void interpolate(std::vector<Point3>& points) const;

 private:
  std::unique_ptr<Far::TopologyRefiner> refiner_;
  const std::int32_t* from_osd_;  // base's from_osd
  std::size_t n_osd_;
  std::size_t n_vertices_;
  int levels_;
};

}  // namespace sorpia::detail
