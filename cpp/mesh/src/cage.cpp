#include "sorpia/cage.hpp"

#include <OpenMesh/Tools/Decimater/BaseDecimaterT.hh>
#include <OpenMesh/Core/Utils/vector_cast.hh>
#include <OpenMesh/Core/Geometry/QuadricT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/Observer.hh>
#include <OpenMesh/Tools/Utils/HeapT.hh>

#include <algorithm>
#include <array>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "openmesh_types.hpp"
#include "sorpia/detail/order.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/detail/scratch.hpp"
#include "sorpia/detail/spatial.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/topology.hpp"

namespace sorpia {
namespace {

using detail::OMesh;

// A binary module: a boundary vertex v0 collapses (along the boundary, the
// only way BaseDecimaterT lets it) only where the boundary turns by at most
// the given angle at v0, between its incoming and outgoing boundary edges.
template <class MeshT>
class ModBoundaryAngleT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModBoundaryAngleT, MeshT, BoundaryAngle);

  explicit ModBoundaryAngleT(MeshT& mesh) : Base(mesh, true) {}

  void set_max_angle(double degrees) { min_cos_ = std::cos(degrees * (M_PI / 180.0)); }

  float collapse_priority(const CollapseInfo& ci) override {
    MeshT& m = Base::mesh();
    if (!m.is_boundary(ci.v0)) return Base::LEGAL_COLLAPSE;
    // v0's outgoing boundary half-edge (no face on its left) and the one that enters v0.
    const auto out = m.halfedge_handle(ci.v0);
    const auto in = m.prev_halfedge_handle(out);
    const auto a = m.point(m.to_vertex_handle(out)) - m.point(ci.v0);
    const auto b = m.point(ci.v0) - m.point(m.from_vertex_handle(in));
    const double la = a.norm(), lb = b.norm();
    if (la == 0.0 || lb == 0.0) return Base::LEGAL_COLLAPSE;  // a zero-length edge turns nowhere
    return OpenMesh::dot(a, b) >= min_cos_ * la * lb ? Base::LEGAL_COLLAPSE : Base::ILLEGAL_COLLAPSE;
  }

 private:
  double min_cos_ = 1.0;
};

using Quadric = OpenMesh::Geometry::QuadricT<double>;

// A face's quadric as OpenMesh's ModQuadricT makes it: its plane's, weighted by its area.
Quadric face_quadric(const OpenMesh::Vec3d& p0, const OpenMesh::Vec3d& p1, const OpenMesh::Vec3d& p2) {
  OpenMesh::Vec3d n = (p1 - p0) % (p2 - p0);
  double area = n.norm();
  if (area > FLT_MIN) {
    n /= area;
    area *= 0.5;
  }
  Quadric q(n[0], n[1], n[2], -(p0 | n));
  q *= area;
  return q;
}

// Garland and Heckbert's quadric error, as OpenMesh's ModQuadricT computes
// it (its initialize, priority and postprocess; no maximum error), with
// error(v0, v1) read in place: the decimation costs every outgoing collapse
// of a vertex at each step, where ModQuadricT's priority takes a whole
// CollapseInfo through a virtual call.
template <class MeshT>
class ModQuadricErrorT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModQuadricErrorT, MeshT, QuadricError);
  using VertexHandle = typename MeshT::VertexHandle;

  explicit ModQuadricErrorT(MeshT& mesh) : Base(mesh, false) {
    mesh.add_property(quadrics_);
    mesh.add_property(sites_);
  }
  ~ModQuadricErrorT() override {
    Base::mesh().remove_property(quadrics_);
    Base::mesh().remove_property(sites_);
  }

  // The vertices' quadrics initialize() takes, in the order of the mesh's
  // vertices, where the mesh's faces are not those to measure the error on
  // (a clustered mesh: each vertex the sum of its cluster's).
  void set_quadrics(std::vector<Quadric> quadrics) { given_ = std::move(quadrics); }

  // Each vertex's quadric: the sum over its faces of the face plane's (face_quadric), or as set_quadrics gave it.
  void initialize() override {
    MeshT& m = Base::mesh();
    if (!given_.empty()) {
      for (const auto v : m.vertices()) m.property(quadrics_, v) = given_[static_cast<std::size_t>(v.idx())];
    } else {
      for (const auto v : m.vertices()) m.property(quadrics_, v).clear();
      for (const auto f : m.faces()) {
        auto fv = m.cfv_iter(f);
        const VertexHandle a = *fv, b = *++fv, c = *++fv;
        const Quadric q = face_quadric(m.point(a), m.point(b), m.point(c));
        m.property(quadrics_, a) += q;
        m.property(quadrics_, b) += q;
        m.property(quadrics_, c) += q;
      }
    }
    for (const auto v : m.vertices()) {
      Site& s = m.property(sites_, v);
      s.p = m.point(v);
      s.own = m.property(quadrics_, v)(s.p);
    }
  }

  // The error of collapsing v0 onto v1 (v0 removed, v1 kept where it is), (Q0 + Q1)(p1).
  float error(VertexHandle v0, VertexHandle v1) {
    Quadric q = quadric(v0);
    q += quadric(v1);
    return static_cast<float>(q(Base::mesh().point(v1)));
  }
  // The same as Q0(p1) + Q1(p1), the second term kept per vertex (it changes
  // only where a collapse adds to Q1), so that costing v0's collapses reads
  // its neighbours' points and not their quadrics; equal to error() up to
  // rounding (which decides between collapses of equal cost, so error() alone
  // costs a mesh decimated from the heap alone: the cages of before).
  float split_error(const Quadric& q0, VertexHandle v1) {
    const Site& s = Base::mesh().property(sites_, v1);
    return static_cast<float>(q0(s.p) + s.own);
  }
  const Quadric& quadric(VertexHandle v) { return Base::mesh().property(quadrics_, v); }

  float collapse_priority(const CollapseInfo& ci) override { return error(ci.v0, ci.v1); }
  void postprocess_collapse(const CollapseInfo& ci) override {
    MeshT& m = Base::mesh();
    m.property(quadrics_, ci.v1) += m.property(quadrics_, ci.v0);
    Site& s = m.property(sites_, ci.v1);
    s.own = m.property(quadrics_, ci.v1)(s.p);
  }

 private:
  // A vertex's point (a half-edge collapse moves none) and its own quadric's error there, side by side.
  struct Site {
    OpenMesh::Vec3d p;
    double own;
  };
  OpenMesh::VPropHandleT<Quadric> quadrics_;
  OpenMesh::VPropHandleT<Site> sites_;
  std::vector<Quadric> given_;
};

// Polls for Ctrl-C between collapses; an Interrupted is kept and rethrown
// after DecimaterT has returned (never thrown through OpenMesh).
class InterruptObserver : public OpenMesh::Decimater::Observer {
 public:
  InterruptObserver() : Observer(1024) {}
  void notify(size_t) override {
    try {
      poll_interrupt();
    } catch (...) {
      stopped_ = std::current_exception();
    }
  }
  bool abort() const override { return static_cast<bool>(stopped_); }
  void rethrow() const {
    if (stopped_) std::rethrow_exception(stopped_);
  }

 private:
  std::exception_ptr stopped_;
};

// OpenMesh's Decimater framework (BaseDecimaterT: its modules, its legality
// test, OpenMesh's collapse) driven lazily. Each vertex waits in the heap under
// the priority module's cost (the quadric error) of its cheapest outgoing
// collapse not refused; the legality test (is_collapse_ok and the Decimater's
// boundary rules) and the binary modules (the guards) judge only the collapse
// at the heap's front. A refused collapse is marked and its vertex goes back
// under its next cheapest. After a collapse the removed vertex's one-ring is
// costed again, as DecimaterT does, and the refusals are lifted wherever a
// one-ring their tests read has changed. DecimaterT instead runs every test on
// every outgoing half-edge of every vertex it costs, most of its time (and at
// the front only the legality test).
class LazyDecimater : public OpenMesh::Decimater::BaseDecimaterT<OMesh> {
 public:
  using Base = OpenMesh::Decimater::BaseDecimaterT<OMesh>;
  using VertexHandle = OMesh::VertexHandle;
  using HalfedgeHandle = OMesh::HalfedgeHandle;

  using Quadric = ModQuadricErrorT<OMesh>;

  explicit LazyDecimater(OMesh& mesh) : Base(mesh), mesh_(mesh) {}

  // Collapses until `count` (one less after each collapse: a half-edge
  // collapse removes one vertex) is at most `target`, or no collapse is
  // allowed; returns the collapses made. `priority` is the priority module;
  // initialize() must have succeeded.
  std::size_t decimate_to(std::size_t& count, std::size_t target, Quadric& priority) {
    priority_module_ = &priority;
    target_.assign(mesh_.n_vertices(), HalfedgeHandle());
    priority_.assign(mesh_.n_vertices(), -1.0f);
    position_.assign(mesh_.n_vertices(), -1);
    refused_.assign(mesh_.n_halfedges(), 0);
    Heap heap{HeapInterface{this}};
    heap_ = &heap;
    heap.reserve(mesh_.n_vertices());
    // The vertices costed in tasks (best_collapse reads the mesh and writes
    // the vertex's own entries), then put in the heap in their order, as
    // cost() puts them.
    const int tasks = detail::task_count(mesh_.n_vertices(), 4096);
    detail::for_each_index(tasks > 1, tasks, mesh_.n_vertices(), [&](std::size_t i) {
      const VertexHandle v(static_cast<int>(i));
      if (!mesh_.status(v).deleted()) best_collapse(v);
    });
    for (const auto v : mesh_.vertices())
      if (!mesh_.status(v).deleted() && target_[v.idx()].is_valid()) heap.insert(v);
    std::vector<VertexHandle> support;
    std::size_t made = 0;
    while (count > target && !heap.empty()) {
      const VertexHandle v = heap.front();
      const HalfedgeHandle h = target_[v.idx()];
      heap.pop_front();
      CollapseInfo ci(mesh_, h);
      if (!allowed(ci)) {
        refused_[h.idx()] = 1;
        cost(v);
        continue;
      }
      --count;  // count > target >= 0
      collapse(ci, support);
      // The removed vertex's one-ring is costed again, as DecimaterT does. A
      // refusal stands while the one-rings its tests read stay as they were:
      // those of the collapse's two ends.
      for (const VertexHandle w : support) {
        for (const auto out : mesh_.voh_range(w)) refused_[out.idx()] = 0;
        cost(w);
      }
      for (const VertexHandle w : support)
        for (const auto in : mesh_.vih_range(w))
          if (refused_[in.idx()]) {
            refused_[in.idx()] = 0;
            cost(mesh_.from_vertex_handle(in));
          }
      if (!this->notify_observer(++made)) break;
    }
    heap_ = nullptr;
    return made;
  }

  // Collapses in rounds until `count` is at most `target` or a round makes
  // none; returns the collapses made. Each round costs every vertex (its
  // cheapest outgoing collapse not refused, under `priority`), takes as its
  // threshold the cost of the cheapest kRoundShare of them, and sweeps the
  // vertices in their order in memory, collapsing each at or under the
  // threshold whose one-ring no collapse of the round has touched (its cost
  // is then current); the legality test and the guards judge each, as in
  // decimate_to. The sweep reads the mesh in its order in memory (vertices
  // in Morton order: to_openmesh), where the heap's order jumps across all
  // of it: the decimation of a large mesh is bound by that memory traffic.
  std::size_t decimate_in_rounds(std::size_t& count, std::size_t target, Quadric& priority) {
    constexpr double kRoundShare = 0.3;
    priority_module_ = &priority;
    const std::size_t n = mesh_.n_vertices();
    target_.assign(n, HalfedgeHandle());
    priority_.assign(n, -1.0f);
    refused_.assign(mesh_.n_halfedges(), 0);
    std::vector<int> touched(n, -1);  // the round whose collapse last touched the vertex
    std::vector<float> costs;
    std::vector<VertexHandle> ring;
    std::size_t made = 0;
    for (int round = 0; count > target; ++round) {
      // Costed again: the vertices a collapse or a refusal of the round before touched (the rest stand).
      costs.clear();
      for (const auto v : mesh_.vertices()) {
        if ((v.idx() & 0xffff) == 0) poll_interrupt();
        if (mesh_.status(v).deleted()) continue;
        if (round == 0 || touched[v.idx()] == round - 1) best_collapse(v, true);
        if (target_[v.idx()].is_valid()) costs.push_back(priority_[v.idx()]);
      }
      if (costs.empty()) break;
      const std::size_t want = std::min(count - target, std::max<std::size_t>(
                                                            1, static_cast<std::size_t>(kRoundShare * costs.size())));
      std::nth_element(costs.begin(), costs.begin() + static_cast<std::ptrdiff_t>(want - 1), costs.end());
      const float threshold = costs[want - 1];
      const std::size_t before = made;
      for (const auto v : mesh_.vertices()) {
        if (count <= target) break;
        const int i = v.idx();
        if (touched[i] == round || mesh_.status(v).deleted() || !target_[i].is_valid() || priority_[i] > threshold)
          continue;
        const HalfedgeHandle h = target_[i];
        CollapseInfo ci(mesh_, h);
        if (!allowed(ci)) {
          refused_[h.idx()] = 1;
          touched[i] = round;
          continue;
        }
        // Touched: both ends' one-rings, whose costs and tests the collapse changes.
        for (const auto w : mesh_.vv_range(ci.v1)) touched[w.idx()] = round;
        --count;  // count > target >= 0
        collapse(ci, ring);
        // A refusal stands while the one-rings its tests read stay as they were (decimate_to).
        for (const VertexHandle w : ring) {
          touched[w.idx()] = round;
          for (const auto out : mesh_.voh_range(w)) refused_[out.idx()] = 0;
          for (const auto in : mesh_.vih_range(w)) refused_[in.idx()] = 0;
        }
        if (!this->notify_observer(++made)) return made;
      }
      // A round that makes few collapses leaves the rest to the heap.
      if (made - before < count / 100) break;
    }
    return made;
  }

 private:
  struct HeapInterface {
    LazyDecimater* d;
    bool less(VertexHandle a, VertexHandle b) const { return d->priority_[a.idx()] < d->priority_[b.idx()]; }
    bool greater(VertexHandle a, VertexHandle b) const { return d->priority_[a.idx()] > d->priority_[b.idx()]; }
    int get_heap_position(VertexHandle v) const { return d->position_[v.idx()]; }
    void set_heap_position(VertexHandle v, int p) { d->position_[v.idx()] = p; }
  };
  using Heap = OpenMesh::Utils::HeapT<VertexHandle, HeapInterface>;

  // v in the heap under its cheapest collapse not refused, or out of it.
  void cost(VertexHandle v) {
    best_collapse(v);
    const bool stored = heap_->is_stored(v);
    if (target_[v.idx()].is_valid())
      stored ? heap_->update(v) : heap_->insert(v);
    else if (stored)
      heap_->remove(v);
  }

  // The legality test and the guards (the binary modules) pass the collapse.
  bool allowed(const CollapseInfo& ci) { return legal(ci) && Base::collapse_priority(ci) >= 0.0f; }

  // OpenMesh's legality test, BaseDecimaterT::is_collapse_legal with
  // TriConnectivity::is_collapse_ok, for a triangle mesh none of whose
  // vertices is locked or a feature: the same verdict on every collapse,
  // its tests ordered to read less (a valence before a search for an edge)
  // and the one-rings compared in a local list, where OpenMesh tags and
  // untags the vertices of both in the mesh.
  bool legal(const CollapseInfo& ci) {
    const OMesh& m = mesh_;
    if (m.status(m.edge_handle(ci.v0v1)).deleted() || m.status(ci.v0).deleted() || m.status(ci.v1).deleted())
      return false;
    // A side triangle whose two other edges are both on the boundary would be left dangling.
    if (ci.fl.is_valid() && m.is_boundary(ci.vlv1) && m.is_boundary(ci.v0vl)) return false;
    if (ci.fr.is_valid() && m.is_boundary(ci.vrv0) && m.is_boundary(ci.v1vr)) return false;
    if (ci.vl == ci.vr) return false;  // both invalid (an edge of no face) or the same vertex
    // A boundary vertex goes only onto a boundary vertex, along a boundary
    // edge (an inner edge between two boundary vertices has both vl and vr).
    if (m.is_boundary(ci.v0) && (!m.is_boundary(ci.v1) || (ci.vl.is_valid() && ci.vr.is_valid()))) return false;
    // v0 with fewer than two faces.
    if (m.cw_rotated_halfedge_handle(m.cw_rotated_halfedge_handle(ci.v0v1)) == ci.v0v1) return false;
    // The one-rings of v0 and v1 may share only vl and vr.
    ring_.clear();
    for (const auto w : m.vv_range(ci.v1))
      if (w != ci.vl && w != ci.vr) ring_.push_back(w);
    for (const auto w : m.vv_range(ci.v0))
      if (std::find(ring_.begin(), ring_.end(), w) != ring_.end()) return false;
    // A tetrahedron's last two faces: vl and vr joined, each of valence 3.
    if (ci.vl.is_valid() && ci.vr.is_valid() && valence_is_3(ci.vl) && valence_is_3(ci.vr) &&
        m.find_halfedge(ci.vl, ci.vr).is_valid())
      return false;
    return true;
  }

  bool valence_is_3(VertexHandle v) const {
    int n = 0;
    for (auto it = mesh_.cvv_iter(v); it.is_valid() && n < 4; ++it) ++n;
    return n == 3;
  }

  // Makes the collapse, with the modules' pre- and postprocessing and the
  // face normals (the normal guard's) around it; `ring` is v0's one-ring
  // before it.
  void collapse(CollapseInfo& ci, std::vector<VertexHandle>& ring) {
    ring.clear();
    for (const auto w : mesh_.vv_range(ci.v0)) ring.push_back(w);
    this->preprocess_collapse(ci);
    mesh_.collapse(ci.v0v1);
    if (mesh_.has_face_normals())
      for (const auto f : mesh_.vf_range(ci.v1))
        if (!mesh_.status(f).deleted()) mesh_.set_normal(f, mesh_.calc_face_normal(f));
    this->postprocess_collapse(ci);
  }

  // target_[v] and priority_[v]: v's cheapest outgoing collapse not refused
  // and its cost (the quadric's error(), or with `split` its split_error()),
  // or an invalid handle and -1.
  void best_collapse(VertexHandle v, bool split = false) {
    float best = FLT_MAX;
    HalfedgeHandle target;
    const auto q = priority_module_->quadric(v);
    for (const auto h : mesh_.voh_range(v)) {
      if (refused_[h.idx()]) continue;
      const VertexHandle to = mesh_.to_vertex_handle(h);
      const float p = split ? priority_module_->split_error(q, to) : priority_module_->error(v, to);
      if (p >= 0.0f && p < best) {
        best = p;
        target = h;
      }
    }
    target_[v.idx()] = target;
    priority_[v.idx()] = target.is_valid() ? best : -1.0f;
  }

  OMesh& mesh_;
  Quadric* priority_module_ = nullptr;
  Heap* heap_ = nullptr;
  std::vector<HalfedgeHandle> target_;
  std::vector<float> priority_;
  std::vector<int> position_;
  std::vector<char> refused_;
  std::vector<VertexHandle> ring_;  // legal()'s list
};

// From this many vertices a mesh is clustered first, or decimated in its
// vertices' Morton order and first in rounds (to_openmesh, decimate): it no
// longer fits in the processor's caches, and the memory traffic bounds the
// decimation.
constexpr std::size_t kLargeMesh = 200000;
// A large mesh's collapses down to this many times the count are made in
// bulk (by clustering or in rounds: decimate), the rest one by one.
constexpr std::size_t kBulkFactor = 4;

void check_options(const DecimateOptions& o) {
  if (!(o.max_normal_deviation > 0.0 && o.max_normal_deviation <= 180.0))
    throw ParameterError("max_normal_deviation " + std::to_string(o.max_normal_deviation) +
                         " must be in (0, 180] degrees");
  if (!(o.max_aspect_ratio >= 1.0 && std::isfinite(o.max_aspect_ratio)))
    throw ParameterError("max_aspect_ratio " + std::to_string(o.max_aspect_ratio) + " must be finite and at least 1");
  if (!(o.max_boundary_angle >= 0.0 && o.max_boundary_angle <= 180.0))
    throw ParameterError("max_boundary_angle " + std::to_string(o.max_boundary_angle) +
                         " must be in [0, 180] degrees");
}

// The mesh's referenced vertices and its triangles in OpenMesh; `kept[i]` is
// the input number of OpenMesh's vertex i. `spatial`: in Morton order
// whatever the size (a clustered mesh, whose vertices keep the input's
// order: the cage's vertices and faces come out in OpenMesh's order, and the
// fit reads the rows of a face's vertices together).
OMesh to_openmesh(const Mesh& mesh, std::vector<std::int32_t>& kept, bool spatial = false) {
  if (!mesh.uniform())
    for (std::size_t f = 0; f < mesh.face_vertex_counts.size(); ++f)
      if (mesh.face_vertex_counts[f] != 3)
        throw MeshError("decimate takes triangles: face " + std::to_string(f) + " has " +
                        std::to_string(mesh.face_vertex_counts[f]) + " corners (triangulate the mesh first)");
  if (mesh.uniform() && mesh.face_size != 3)
    throw MeshError("decimate takes triangles: every face has " + std::to_string(mesh.face_size) +
                    " corners (triangulate the mesh first)");
  const std::size_t n = mesh.n_vertices(), n_faces = mesh.face_vertex_indices.size() / 3;
  std::vector<std::int32_t> handle(n, -1);
  for (std::size_t i = 0; i < mesh.face_vertex_indices.size(); ++i) {
    const std::int32_t v = mesh.face_vertex_indices[i];
    if (v < 0 || static_cast<std::size_t>(v) >= n)
      throw MeshError("decimate: face " + std::to_string(i / 3) + " has vertex index " + std::to_string(v) +
                      " out of range [0, " + std::to_string(n) + ")");
    handle[static_cast<std::size_t>(v)] = 0;
  }
  detail::silence_openmesh();
  OMesh om;
  kept.clear();
  for (std::size_t v = 0; v < n; ++v)
    if (handle[v] == 0) kept.push_back(static_cast<std::int32_t>(v));
  // A large mesh: the vertices in Morton order (the bounding box cut into
  // 2^21 steps an axis, the bits interleaved) and each face after its first
  // corner's (below), so that a one-ring lies together in memory, which the
  // decimation's sweeps and collapses read at every step. A smaller one in
  // the input's order.
  const bool morton = spatial || kept.size() >= kLargeMesh;
  if (morton) {
    std::vector<double> at(3 * kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) std::copy_n(&mesh.vertices[3 * static_cast<std::size_t>(kept[i])], 3, &at[3 * i]);
    const std::vector<std::size_t> order = detail::spatial_order(at.data(), kept.size());
    std::vector<std::int32_t> sorted(kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) sorted[i] = kept[order[i]];
    kept = std::move(sorted);
  }
  for (std::size_t i = 0; i < kept.size(); ++i) handle[static_cast<std::size_t>(kept[i])] = static_cast<std::int32_t>(i);
  std::vector<std::int32_t> face_order(n_faces);
  if (morton) {  // each face after its first corner's (a counting sort)
    std::vector<std::int32_t> first(kept.size() + 1, 0);
    for (std::size_t f = 0; f < n_faces; ++f) ++first[static_cast<std::size_t>(handle[mesh.face_vertex_indices[3 * f]]) + 1];
    for (std::size_t i = 0; i < kept.size(); ++i) first[i + 1] += first[i];
    for (std::size_t f = 0; f < n_faces; ++f)
      face_order[static_cast<std::size_t>(first[static_cast<std::size_t>(handle[mesh.face_vertex_indices[3 * f]])]++)] =
          static_cast<std::int32_t>(f);
  } else {
    for (std::size_t f = 0; f < n_faces; ++f) face_order[f] = static_cast<std::int32_t>(f);
  }
  om.reserve(kept.size(), 3 * n_faces / 2 + kept.size(), n_faces);
  for (const std::int32_t v : kept) om.add_vertex({mesh.vertices[3 * v], mesh.vertices[3 * v + 1], mesh.vertices[3 * v + 2]});
  for (std::size_t k = 0; k < n_faces; ++k) {
    if ((k & 0xffff) == 0) poll_interrupt();  // seconds at a few million faces
    const std::size_t f = static_cast<std::size_t>(face_order[k]);
    const std::int32_t* t = &mesh.face_vertex_indices[3 * f];
    const OMesh::VertexHandle c[3] = {OMesh::VertexHandle(handle[t[0]]), OMesh::VertexHandle(handle[t[1]]),
                                      OMesh::VertexHandle(handle[t[2]])};
    if (!om.add_face(c[0], c[1], c[2]).is_valid()) {
      // OpenMesh says only that the face does not fit; the project's one check of a mesh's form names the
      // problem (the edge, the faces, the fix) as every other refusal does. Run on this failure path only.
      try {
        const Topology named(mesh);
      } catch (const MeshError& e) {
        throw MeshError("decimate: face " + std::to_string(f) + " cannot join OpenMesh's half-edge mesh: " +
                        e.what());
      }
      throw MeshError("decimate: face " + std::to_string(f) +
                      " cannot join OpenMesh's half-edge mesh (a repeated vertex, an edge of three or more faces, a "
                      "bowtie vertex or a face oriented against its neighbours); sorpia.repair makes such a mesh valid");
    }
  }
  return om;
}


// The link of a vertex v of a triangle mesh, one edge e[i].a -> e[i].b for
// each of its k faces (v, a, b), as a manifold oriented mesh has it: a
// single cycle of at least 3 edges (kInner) or a single path (kOnBoundary);
// anything else (an edge of three faces or of two faces oriented alike, a
// fan of several pieces, a repeated vertex) is kNotManifold.
enum class Link { kNotManifold, kInner, kOnBoundary };

struct LinkEdge {
  std::int32_t a, b;
};

Link link_of(std::int32_t v, const LinkEdge* e, std::size_t k) {
  std::size_t starts = 0, start = 0;
  for (std::size_t i = 0; i < k; ++i) {
    if (e[i].a == v || e[i].b == v || e[i].a == e[i].b) return Link::kNotManifold;
    bool entered = false;  // some edge ends where edge i starts
    for (std::size_t j = 0; j < k; ++j) {
      if (j != i && (e[j].a == e[i].a || e[j].b == e[i].b)) return Link::kNotManifold;
      entered |= e[j].b == e[i].a;
    }
    if (!entered) {
      ++starts;
      start = i;
    }
  }
  if (starts > 1) return Link::kNotManifold;
  // Walk from the path's start (or around the cycle): every edge must be reached.
  std::size_t walked = 1;
  for (std::size_t i = start;;) {
    std::size_t next = k;
    for (std::size_t j = 0; j < k; ++j)
      if (e[j].a == e[i].b) next = j;
    if (next == k || next == start) break;
    i = next;
    ++walked;
  }
  if (walked != k) return Link::kNotManifold;
  if (starts == 1) return Link::kOnBoundary;
  return k >= 3 ? Link::kInner : Link::kNotManifold;
}

// A mesh's vertices clustered before its decimation, as Lindstrom's
// out-of-core simplification does (Lindstrom 2000): a uniform grid's cells,
// each cell's vertices joined by the mesh's edges a cluster, each cluster
// one vertex (its representative) carrying the sum of its vertices'
// quadrics, and the faces with three clusters kept. The representative is
// the cluster's vertex where the cluster's quadric is least: an input
// vertex, as a collapse keeps one. A cluster is what collapses inside it
// would make, and the decimation goes on from it as if it had made them.
struct Clustering {
  Mesh mesh;                         // the representatives' input coordinates and the faces kept
  std::vector<std::int32_t> source;  // each of mesh's vertices: its representative's input number
  std::vector<Quadric> quadrics;     // each of mesh's vertices: the sum of its cluster's vertices' quadrics
};

// Rounds of smoothing of the positions the clustering's grid cells are
// taken from, on its second try (cluster_vertices): each moves a vertex
// halfway to the mean of its neighbours (over its faces' corners), which
// damps a noise at the vertices' own spacing by about half a round, so that
// a cell cuts the surface in one disc where the noise folded it in and out
// of the cell; it reaches about sqrt(rounds) spacings, below a cell's side
// (several spacings: kBulkFactor clusters per vertex asked of a mesh of more
// than twice as many).
constexpr int kGridSmoothRounds = 4;

// The decimation's passes over flat arrays (its bounds, cluster_vertices)
// run in tasks over contiguous ranges (detail::for_each_range) of at least
// this many vertices, corners, faces or clusters each; every result is the
// same whatever the number of tasks.
constexpr std::size_t kArrayTaskItems = 16384;

int array_tasks(std::size_t n) { return detail::task_count(n, kArrayTaskItems); }

// The sum over the tasks of count(t, first, last), the tasks over [0, n) as
// by detail::for_each_range.
template <class Count>
std::size_t sum_over_ranges(int tasks, std::size_t n, Count count) {
  std::vector<std::size_t> part(static_cast<std::size_t>(tasks), 0);
  detail::for_each_range(tasks > 1, tasks, n, [&](int t, std::size_t first, std::size_t last) {
    part[static_cast<std::size_t>(t)] = count(t, first, last);
  });
  std::size_t sum = 0;
  for (const std::size_t s : part) sum += s;
  return sum;
}

// The task (of n_tasks) that joins the vertices of a grid cell (its key) in
// cluster_vertices: a hash, so that the tasks share the cells about evenly
// whatever the order of the vertices.
int cell_task(std::uint64_t key, int n_tasks) {
  return static_cast<int>((((key * 0x9E3779B97F4A7C15ull) >> 32) * static_cast<std::uint64_t>(n_tasks)) >> 32);
}

std::size_t next_corner(std::size_t c) { return c - c % 3 + (c + 1) % 3; }
std::size_t prev_corner(std::size_t c) { return c - c % 3 + (c + 2) % 3; }

// The links of the labels of a triangle mesh's corners (a vertex's number,
// or a cluster's, in [0, n)): label x's edges are edge[first[x] .. first[x +
// 1]), one for each corner of x, from its next corner's label to its
// previous one's, in the order of the corners (detail::group_by_key), laid
// out together so that the passes over them read them in order.
struct Links {
  std::vector<std::size_t> first;
  std::unique_ptr<LinkEdge[]> edge;
  Links(const std::int32_t* label, std::size_t k, std::size_t n) : edge(new LinkEdge[k]) {
    first = detail::group_by_key(
        label, k, n,
        [&](std::size_t c, std::size_t s) {
          edge[s] = {label[next_corner(c)], label[prev_corner(c)]};
        },
        detail::grouping_tasks(k, n));
  }
  std::size_t size() const { return first.size() - 1; }
  const LinkEdge* begin(std::size_t x) const { return edge.get() + first[x]; }
  const LinkEdge* end(std::size_t x) const { return edge.get() + first[x + 1]; }
  // on_link(x, its Link) for each label x with corners, in tasks over the
  // labels: on_link writes x's own entries only.
  template <class OnLink>
  void judge(OnLink on_link) const {
    const std::size_t n = size();
    const int tasks = array_tasks(n);
    detail::for_each_range(tasks > 1, tasks, n, [&](int t, std::size_t first_x, std::size_t last_x) {
      for (std::size_t x = first_x; x < last_x; ++x) {
        if (t == 0 && ((x - first_x) & 0xffff) == 0) poll_interrupt();
        if (begin(x) != end(x))
          on_link(x, link_of(static_cast<std::int32_t>(x), begin(x), static_cast<std::size_t>(end(x) - begin(x))));
      }
    });
  }
};

// `p` smoothed by `rounds` rounds (kGridSmoothRounds) over the triangles
// whose vertices' links are `links`, the vertices `fixed` where they are. A
// vertex's sum of its neighbours is taken over its corners in their order,
// the same whatever the tasks.
std::vector<OpenMesh::Vec3d> smoothed(const std::vector<OpenMesh::Vec3d>& p, const Links& links,
                                      const std::vector<char>& fixed, int rounds) {
  std::vector<OpenMesh::Vec3d> q(p), next(p.size());
  const int tasks = array_tasks(p.size());
  for (int r = 0; r < rounds; ++r) {
    detail::for_each_index(tasks > 1, tasks, p.size(), [&](std::size_t v) {
      if (links.begin(v) == links.end(v) || fixed[v]) {
        next[v] = q[v];
        return;
      }
      // The neighbours summed: each edge of a face once per face.
      OpenMesh::Vec3d sum(0.0, 0.0, 0.0);
      for (const LinkEdge* e = links.begin(v); e != links.end(v); ++e) sum += q[e->a] + q[e->b];
      next[v] = 0.5 * q[v] + (0.5 / static_cast<std::int32_t>(2 * (links.end(v) - links.begin(v)))) * sum;
    });
    q.swap(next);
  }
  return q;
}

// Clusters `mesh` (in the decimation's coordinates, `to_frame`) into about
// `n_clusters` vertices. Vertices on the boundary stay as they are, so that
// no hole closes and the boundary angle guard judges the boundary as before;
// where the clusters leave a vertex whose link (link_of) is not a single
// fan, the boundary's a path and an inner one a cycle, the mesh is mended
// and judged again, until none is: a cluster between two others only joins
// one of them, any other such cluster is split back into its vertices (a
// single vertex: its neighbouring clusters are). The grid's cells are taken
// from the positions as they are first; where the mending does not settle
// within kJoinPasses passes (a noise at the vertices' spacing folds the
// surface in and out of the cells, so that the clusters split back towards
// the input's vertices), from the positions smoothed (kGridSmoothRounds)
// instead, the mesh and its quadrics as they are. False (nothing clustered)
// for a mesh not manifold itself, whose refusal is the decimation's to name,
// and where the grid or the mending does not settle.
template <class ToFrame>
bool cluster_vertices(const Mesh& mesh, std::size_t n_clusters, const ToFrame& to_frame, Clustering& out) {
  const std::size_t nv = mesh.n_vertices();
  const std::int32_t* idx = mesh.face_vertex_indices.data();
  const std::size_t n_corners = mesh.face_vertex_indices.size(), nf = n_corners / 3;
  if (mesh.uniform() ? mesh.face_size != 3
                     : std::any_of(mesh.face_vertex_counts.begin(), mesh.face_vertex_counts.end(),
                                   [](std::int32_t c) { return c != 3; }))
    return false;
  const int vertex_tasks = array_tasks(nv), corner_tasks = array_tasks(n_corners), face_tasks = array_tasks(nf);
  const std::size_t out_of_range = sum_over_ranges(corner_tasks, n_corners, [&](int, std::size_t first, std::size_t last) {
    std::size_t bad = 0;
    for (std::size_t c = first; c < last; ++c) bad += idx[c] < 0 || static_cast<std::size_t>(idx[c]) >= nv;
    return bad;
  });
  if (out_of_range > 0) return false;
  std::vector<OpenMesh::Vec3d> p(nv);
  detail::for_each_index(vertex_tasks > 1, vertex_tasks, nv,
                         [&](std::size_t v) { p[v] = to_frame(&mesh.vertices[3 * v]); });

  // The arrays that tasks fill first, taken unfilled (their pages first
  // touched by the tasks).
  detail::Scratch::Frame frame(nullptr);
  const Links vertex_links(idx, n_corners, nv);
  std::vector<char> boundary(nv, 0), used(nv, 0), bad(nv, 0);
  vertex_links.judge([&](std::size_t v, Link kind) {
    used[v] = 1;
    boundary[v] = kind == Link::kOnBoundary;
    bad[v] = kind == Link::kNotManifold;
  });
  if (std::find(bad.begin(), bad.end(), 1) != bad.end()) return false;
  // Kept out of clusters: the boundary's vertices and their neighbours, so
  // that the faces along the boundary are the input's and the heap shapes
  // that strip collapse by collapse (no cluster fans out to many boundary
  // vertices in thin triangles).
  char* const keep = frame.take<char>(nv);
  detail::for_each_index(vertex_tasks > 1, vertex_tasks, nv, [&](std::size_t v) {
    char k = boundary[v];
    for (const LinkEdge* e = vertex_links.begin(v); !k && e != vertex_links.end(v); ++e)
      k = boundary[e->a] || boundary[e->b];
    keep[v] = k;
  });
  std::vector<std::int32_t> boundary_vertices;
  for (std::size_t v = 0; v < nv; ++v)
    if (boundary[v]) boundary_vertices.push_back(static_cast<std::int32_t>(v));
  const std::size_t n_used = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1));
  double area = 0.0;  // summed in the order of the faces
  {
    detail::Scratch::Frame areas(&frame.scratch());
    double* const face_area = areas.take<double>(nf);
    detail::for_each_index(face_tasks > 1, face_tasks, nf, [&](std::size_t f) {
      face_area[f] = 0.5 * ((p[idx[3 * f + 1]] - p[idx[3 * f]]) % (p[idx[3 * f + 2]] - p[idx[3 * f]])).norm();
    });
    for (std::size_t f = 0; f < nf; ++f) area += face_area[f];
  }

  // The grid: a cell of side h meets about 1.5 area / h^2 of a surface's
  // cells (a plane's average over its orientations), and the cell's patch
  // is one cluster; h is corrected from the clusters it gave.
  std::int32_t* const cluster = frame.take<std::int32_t>(nv);
  std::int32_t* const parent = frame.take<std::int32_t>(nv);
  std::int32_t* const number = frame.take<std::int32_t>(nv);  // a root's cluster
  std::uint64_t* const cell = frame.take<std::uint64_t>(nv);
  // Sets joined under their least vertex: parent[x] <= x throughout, and a
  // set's root is its least vertex.
  const auto find = [&](std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  const auto unite = [&](std::int32_t u, std::int32_t w) {
    u = find(u);
    w = find(w);
    if (u == w) return false;
    if (u < w) std::swap(u, w);
    parent[u] = w;
    return true;
  };
  std::vector<std::int32_t> faces;
  // Each input corner's cluster, as the faces were last keyed.
  std::int32_t* const face_clusters = frame.take<std::int32_t>(n_corners);
  std::vector<std::array<std::int32_t, 3>> keys;
  std::vector<std::vector<std::array<std::int32_t, 3>>> task_keys(static_cast<std::size_t>(face_tasks));
  std::vector<char> split;
  std::int32_t n_numbered = 0;
  for (const bool smooth : {false, true}) {
    const std::vector<OpenMesh::Vec3d> p_smoothed =
        smooth ? smoothed(p, vertex_links, boundary, kGridSmoothRounds) : std::vector<OpenMesh::Vec3d>();
    const std::vector<OpenMesh::Vec3d>& q = smooth ? p_smoothed : p;  // the cells' positions
    double h = std::sqrt(1.5 * area / static_cast<double>(n_clusters));
    for (int attempt = 0; attempt < 3; ++attempt) {
      if (!(h > 0.0 && std::isfinite(h))) return false;
      detail::for_each_index(vertex_tasks > 1, vertex_tasks, nv, [&](std::size_t v) {
        std::uint64_t key = 0;
        for (int c = 0; c < 3; ++c)
          key |= static_cast<std::uint64_t>(std::clamp(std::floor((q[v][c] + 1.0) / h), 0.0, 2097151.0)) << (21 * c);
        cell[v] = key;
        parent[v] = static_cast<std::int32_t>(v);
      });
      // Each edge whose ends share a cell, neither kept, joins their sets,
      // in tasks that each take the cells of one share of their hashes
      // (cell_task): a set lies in one cell, so each task's finds and joins
      // stay in its own sets. The sets are the same in any order of the
      // joins. An edge inside the mesh is taken once, from its lesser end u
      // in the face where it runs u -> w (a boundary edge's ends are kept).
      const std::size_t joined = sum_over_ranges(vertex_tasks, nv, [&](int t, std::size_t, std::size_t) {
        std::size_t made = 0;
        for (std::size_t u = 0; u < nv; ++u) {
          if (keep[u] || cell_task(cell[u], vertex_tasks) != t) continue;
          for (const LinkEdge* e = vertex_links.begin(u); e != vertex_links.end(u); ++e)
            if (static_cast<std::size_t>(e->a) > u && cell[u] == cell[e->a] && !keep[e->a])
              made += unite(static_cast<std::int32_t>(u), e->a);
        }
        return made;
      });
      const std::size_t n_made = n_used - joined;  // each join makes one set of used vertices fewer
      const double ratio = static_cast<double>(n_made) / static_cast<double>(n_clusters);
      if (ratio > 0.9 && ratio < 1.15) break;
      h *= std::sqrt(ratio);
    }
    // Clusters numbered in the order of their first vertex (their root).
    {
      std::vector<std::int32_t> roots_before(static_cast<std::size_t>(vertex_tasks) + 1, 0);
      detail::for_each_range(vertex_tasks > 1, vertex_tasks, nv, [&](int t, std::size_t first, std::size_t last) {
        std::int32_t roots = 0;
        for (std::size_t v = first; v < last; ++v) roots += parent[v] == static_cast<std::int32_t>(v);
        roots_before[static_cast<std::size_t>(t) + 1] = roots;
      });
      for (std::size_t t = 0; t + 1 < roots_before.size(); ++t) roots_before[t + 1] += roots_before[t];
      n_numbered = roots_before.back();
      detail::for_each_range(vertex_tasks > 1, vertex_tasks, nv, [&](int t, std::size_t first, std::size_t last) {
        std::int32_t x = roots_before[static_cast<std::size_t>(t)];
        for (std::size_t v = first; v < last; ++v)
          if (parent[v] == static_cast<std::int32_t>(v)) number[v] = x++;
      });
      detail::for_each_index(vertex_tasks > 1, vertex_tasks, nv, [&](std::size_t v) {
        std::int32_t r = static_cast<std::int32_t>(v);
        while (parent[r] != r) r = parent[r];
        cluster[v] = number[r];
      });
    }

    // The clustered faces; a cluster whose link is not as its vertices' (an
    // inner cluster's a cycle, a boundary vertex's a path) is split, with its
    // neighbours, into its vertices, until none is.
    // Joins can make new folds where slivers lie side by side; after these
    // passes a sliver is split like any other cluster, which settles: a mesh
    // of single vertices is the input, manifold.
    constexpr int kJoinPasses = 8;
    bool settled = false;
    for (int pass = 0;; ++pass) {
      // Each face over three clusters once (several input faces can span the
      // same three), keyed by its corners turned to put the least first: in
      // tasks over the faces, each task's keys sorted, then merged.
      detail::for_each_range(face_tasks > 1, face_tasks, nf, [&](int t, std::size_t first, std::size_t last) {
        auto& part = task_keys[static_cast<std::size_t>(t)];
        part.clear();
        for (std::size_t f = first; f < last; ++f) {
          std::int32_t* c = &face_clusters[3 * f];
          for (int k = 0; k < 3; ++k) c[k] = cluster[idx[3 * f + k]];
          if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) continue;
          const int least = c[1] < c[0] ? (c[2] < c[1] ? 2 : 1) : (c[2] < c[0] ? 2 : 0);
          part.push_back({c[least], c[(least + 1) % 3], c[(least + 2) % 3]});
        }
        std::sort(part.begin(), part.end());
        part.erase(std::unique(part.begin(), part.end()), part.end());
      });
      keys.swap(task_keys[0]);
      for (std::size_t t = 1; t < task_keys.size(); ++t) {
        std::vector<std::array<std::int32_t, 3>> merged(keys.size() + task_keys[t].size());
        std::merge(keys.begin(), keys.end(), task_keys[t].begin(), task_keys[t].end(), merged.begin());
        merged.erase(std::unique(merged.begin(), merged.end()), merged.end());
        keys.swap(merged);
      }
      faces.clear();
      for (const auto& t : keys) faces.insert(faces.end(), t.begin(), t.end());
      const std::size_t n = static_cast<std::size_t>(n_numbered);
      // A cluster's boundary: one of its vertices is on the input's (then it is that vertex alone).
      std::vector<char> on_boundary(n, 0);
      for (const std::int32_t v : boundary_vertices) on_boundary[cluster[v]] = 1;
      split.assign(n, 0);
      // A cluster between two others only (two faces over the same three
      // clusters, oriented against each other: a sliver a cell's corner cut
      // off) joins one of them not on the boundary, which closes the fold.
      // Judged in tasks; the joins then taken in the order of the clusters.
      std::vector<std::int32_t> join_to(n, -1);
      const Links cluster_links(faces.data(), faces.size(), n);
      cluster_links.judge([&](std::size_t x, Link kind) {
        if (kind == (on_boundary[x] ? Link::kOnBoundary : Link::kInner)) return;
        const LinkEdge* e = cluster_links.begin(x);
        if (pass < kJoinPasses && !on_boundary[x] && cluster_links.end(x) - e == 2 && e[0].a == e[1].b &&
            e[1].a == e[0].b && !(on_boundary[e[0].a] && on_boundary[e[1].a])) {
          join_to[x] = on_boundary[e[0].a] ? e[1].a : e[0].a;
          return;
        }
        split[x] = 1;
      });
      std::size_t n_split = static_cast<std::size_t>(std::count(split.begin(), split.end(), 1));
      std::vector<std::int32_t> joins;
      for (std::size_t x = 0; x < n; ++x)
        if (join_to[x] >= 0) joins.insert(joins.end(), {static_cast<std::int32_t>(x), join_to[x]});
      std::vector<std::int32_t> into(n, -1);
      for (std::size_t i = 0; i < joins.size(); i += 2) into[joins[i]] = joins[i + 1];
      std::size_t n_joined = 0;
      for (std::size_t i = 0; i < joins.size(); i += 2)
        if (into[joins[i + 1]] >= 0) {  // its neighbour joins another: split it instead
          into[joins[i]] = -1;
          split[joins[i]] = 1;
          ++n_split;
        } else {
          ++n_joined;
        }
      if (n_joined > 0)
        detail::for_each_index(vertex_tasks > 1, vertex_tasks, nv, [&](std::size_t v) {
          if (into[cluster[v]] >= 0) cluster[v] = into[cluster[v]];
        });
      if (n_split == 0 && n_joined == 0) {
        settled = true;
        break;
      }
      if (pass == (smooth ? kJoinPasses + 16 : kJoinPasses - 1)) break;
      if (n_joined > 0) continue;  // the splits were judged before the joins
      std::vector<std::int32_t> members(n, 0);
      for (std::size_t v = 0; v < nv; ++v) ++members[cluster[v]];
      for (std::size_t c = 0; c < faces.size(); ++c)
        if (split[faces[c]] == 1 && members[faces[c]] == 1)
          for (const std::size_t d : {next_corner(c), prev_corner(c)})
            if (!split[faces[d]]) split[faces[d]] = 2;
      std::vector<char> seen(n, 0);  // each split cluster keeps its number for its first vertex
      for (std::size_t v = 0; v < nv; ++v) {
        const std::int32_t x = cluster[v];
        if (!split[x]) continue;
        if (seen[x]) cluster[v] = n_numbered++;
        seen[x] = 1;
      }
    }
    if (settled) break;
    if (smooth) return false;
  }
  // Far fewer clusters in faces than asked (a grid the correction did not
  // settle): the heap would have too few collapses left to shape the cage.
  {
    std::vector<char> in_faces(static_cast<std::size_t>(n_numbered), 0);
    for (const std::int32_t x : faces) in_faces[static_cast<std::size_t>(x)] = 1;
    if (2 * static_cast<std::size_t>(std::count(in_faces.begin(), in_faces.end(), 1)) < n_clusters) return false;
  }

  // The clusters' quadrics: each the sum of the quadrics of the input's
  // faces (degenerate or not) over their corners in it, in the order of the
  // faces. In tasks over ranges of the clusters of about as many vertices
  // each (a cluster's faces about twice its vertices), each task over all
  // faces (the clusters of their corners as last keyed: the clusters
  // settled).
  const std::size_t n = static_cast<std::size_t>(n_numbered);
  out.quadrics.assign(n, Quadric());
  for (auto& q : out.quadrics) q.clear();
  const int quadric_tasks = array_tasks(n);
  std::vector<std::size_t> cut(static_cast<std::size_t>(quadric_tasks) + 1, n);  // task t's clusters: cut[t] ..
  cut[0] = 0;
  if (quadric_tasks > 1) {
    std::vector<std::vector<std::int32_t>> members(static_cast<std::size_t>(vertex_tasks));
    detail::for_each_range(vertex_tasks > 1, vertex_tasks, nv, [&](int t, std::size_t first, std::size_t last) {
      auto& m = members[static_cast<std::size_t>(t)];
      m.assign(n, 0);
      for (std::size_t v = first; v < last; ++v) ++m[static_cast<std::size_t>(cluster[v])];
    });
    std::size_t seen = 0, t = 1;
    for (std::size_t x = 0; x < n && t < cut.size() - 1; ++x) {
      for (const auto& m : members) seen += static_cast<std::size_t>(m[x]);
      while (t < cut.size() - 1 && seen * static_cast<std::size_t>(quadric_tasks) >= nv * t) cut[t++] = x + 1;
    }
  }
  detail::for_each_task(quadric_tasks > 1, quadric_tasks, [&](int t) {
    const std::size_t first = cut[static_cast<std::size_t>(t)], last = cut[static_cast<std::size_t>(t) + 1];
    for (std::size_t f = 0; f < nf; ++f) {
      if (t == 0 && (f & 0xffff) == 0) poll_interrupt();
      const std::int32_t* c = &face_clusters[3 * f];
      const bool in[3] = {static_cast<std::size_t>(c[0]) - first < last - first,
                          static_cast<std::size_t>(c[1]) - first < last - first,
                          static_cast<std::size_t>(c[2]) - first < last - first};
      if (!(in[0] || in[1] || in[2])) continue;
      const Quadric q = face_quadric(p[idx[3 * f]], p[idx[3 * f + 1]], p[idx[3 * f + 2]]);
      for (int k = 0; k < 3; ++k)
        if (in[k]) out.quadrics[static_cast<std::size_t>(c[k])] += q;
    }
  });
  // Each cluster's representative: its first vertex where its quadric is
  // least. In tasks over the vertices, each task's then taken in their
  // order where less.
  {
    std::vector<std::vector<double>> least(static_cast<std::size_t>(vertex_tasks));
    std::vector<std::vector<std::int32_t>> source(static_cast<std::size_t>(vertex_tasks));
    detail::for_each_range(vertex_tasks > 1, vertex_tasks, nv, [&](int t, std::size_t first, std::size_t last) {
      auto& l = least[static_cast<std::size_t>(t)];
      auto& s = source[static_cast<std::size_t>(t)];
      l.assign(n, HUGE_VAL);
      s.assign(n, -1);
      for (std::size_t v = first; v < last; ++v) {
        if (!used[v]) continue;
        const std::size_t x = static_cast<std::size_t>(cluster[v]);
        const double e = out.quadrics[x](p[v]);
        if (e < l[x]) {
          l[x] = e;
          s[x] = static_cast<std::int32_t>(v);
        }
      }
    });
    for (std::size_t t = 1; t < least.size(); ++t)
      for (std::size_t x = 0; x < n; ++x)
        if (least[t][x] < least[0][x]) {
          least[0][x] = least[t][x];
          source[0][x] = source[t][x];
        }
    out.source = std::move(source[0]);
  }
  out.mesh = Mesh();
  out.mesh.vertices.resize(3 * n, 0.0);
  for (std::size_t x = 0; x < n; ++x)
    if (out.source[x] >= 0) std::copy_n(&mesh.vertices[3 * static_cast<std::size_t>(out.source[x])], 3, &out.mesh.vertices[3 * x]);
  out.mesh.face_vertex_indices = std::move(faces);
  out.mesh.face_size = 3;
  return true;
}

// A quad made of the two triangles on either side of interior edge e, or
// none: h = e's half-edge from a to b in triangle (a, b, c), its opposite in
// (b, a, d); the quad is (a, d, b, c), oriented as the triangles.
struct QuadCandidate {
  double quality = -1.0;  // below 0: not a quad to make
  OMesh::VertexHandle corners[4];
};

// A quad's quality in [0, 1] (1: a planar square-cornered quad), or -1 for
// one not to make: 1 - (its worst corner's departure from a right angle)/90
// degrees - (1 - cos of the angle between its two triangles' normals)/2;
// a quad with a corner of 180 degrees or more (not convex: its two triangles
// fold over their shared diagonal) is -1. Angles are invariant under the
// decimation's centring and scaling, so the quality is the input's.
double quad_quality(const OMesh& om, const OMesh::VertexHandle (&q)[4]) {
  using V = OMesh::Point;
  const V p[4] = {om.point(q[0]), om.point(q[1]), om.point(q[2]), om.point(q[3])};
  // The triangles (a, b, c) = (q0, q2, q3) and (b, a, d) = (q2, q0, q1).
  V n1 = OpenMesh::cross(p[2] - p[0], p[3] - p[0]), n2 = OpenMesh::cross(p[0] - p[2], p[1] - p[2]);
  const double l1 = n1.norm(), l2 = n2.norm();
  if (!(l1 > 0.0 && l2 > 0.0)) return -1.0;
  n1 /= l1;
  n2 /= l2;
  const V normal = n1 + n2;
  double worst = 0.0;
  for (int i = 0; i < 4; ++i) {
    const V next = p[(i + 1) % 4] - p[i], prev = p[(i + 3) % 4] - p[i];
    const double ln = next.norm(), lp = prev.norm();
    if (!(ln > 0.0 && lp > 0.0)) return -1.0;
    if (OpenMesh::dot(OpenMesh::cross(next, prev), normal) <= 0.0) return -1.0;  // a reflex corner
    const double angle = std::acos(std::clamp(OpenMesh::dot(next, prev) / (ln * lp), -1.0, 1.0));
    worst = std::max(worst, std::abs(angle - M_PI / 2));
  }
  return 1.0 - worst / (M_PI / 2) - 0.5 * (1.0 - OpenMesh::dot(n1, n2));
}

// The decimated triangles paired into quads across their edges, greedily by
// quad_quality (best first), then improved along augmenting paths (an
// unpaired triangle takes a neighbour from its partner, which takes another,
// ... until one takes another unpaired triangle: two triangles fewer left
// over). Triangles that find no partner stay
// triangles. A pairing removes the shared edge, so it is refused where a
// vertex of that edge would be left with fewer than three edges inside the
// mesh (two on the boundary): Catmull-Clark's rules want no valence-2
// vertex inside. `positions` are the input's coordinates of om's vertices.
Mesh paired_quads(const OMesh& om, const std::vector<double>& positions) {
  const std::size_t n_faces = om.n_faces();
  std::vector<std::int32_t> mate(n_faces, -1), valence(om.n_vertices(), 0);
  std::vector<OMesh::EdgeHandle> across(n_faces);  // the edge a paired face shares with its mate
  for (const auto v : om.vertices()) valence[v.idx()] = static_cast<std::int32_t>(om.valence(v));
  const auto ends_keep_valence = [&](OMesh::EdgeHandle e) {
    for (const auto v : {om.from_vertex_handle(om.halfedge_handle(e, 0)), om.to_vertex_handle(om.halfedge_handle(e, 0))})
      if (valence[v.idx()] - 1 < (om.is_boundary(v) ? 2 : 3)) return false;
    return true;
  };
  std::vector<QuadCandidate> candidate(om.n_edges());
  std::vector<std::pair<double, int>> order;
  for (const auto e : om.edges()) {
    if (om.is_boundary(e)) continue;
    const auto h = om.halfedge_handle(e, 0), o = om.halfedge_handle(e, 1);
    QuadCandidate& c = candidate[e.idx()];
    c.corners[0] = om.from_vertex_handle(h);
    c.corners[1] = om.to_vertex_handle(om.next_halfedge_handle(o));
    c.corners[2] = om.to_vertex_handle(h);
    c.corners[3] = om.to_vertex_handle(om.next_halfedge_handle(h));
    c.quality = quad_quality(om, c.corners);
    if (c.quality >= 0.0) order.emplace_back(c.quality, e.idx());
  }
  std::stable_sort(order.begin(), order.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  const auto faces_of = [&](OMesh::EdgeHandle e) {
    return std::make_pair(om.face_handle(om.halfedge_handle(e, 0)).idx(), om.face_handle(om.halfedge_handle(e, 1)).idx());
  };
  const auto set_pair = [&](OMesh::EdgeHandle e, bool on) {
    const auto [f, g] = faces_of(e);
    mate[f] = on ? g : -1;
    mate[g] = on ? f : -1;
    across[f] = across[g] = on ? e : OMesh::EdgeHandle();
    const int step = on ? -1 : 1;
    valence[om.from_vertex_handle(om.halfedge_handle(e, 0)).idx()] += step;
    valence[om.to_vertex_handle(om.halfedge_handle(e, 0)).idx()] += step;
  };
  const auto can_pair = [&](OMesh::EdgeHandle e) {
    if (om.is_boundary(e) || candidate[e.idx()].quality < 0.0) return false;
    const auto [f, g] = faces_of(e);
    return mate[f] < 0 && mate[g] < 0 && ends_keep_valence(e);
  };
  for (const auto& [quality, e] : order)
    if (can_pair(OMesh::EdgeHandle(e))) set_pair(OMesh::EdgeHandle(e), true);
  // Augmenting paths: from an unpaired triangle t, a breadth-first search
  // along alternating paths t -e1- u1 =paired= w1 -e2- u2 =paired= w2 ... -ek- x
  // to another unpaired triangle x (at most kMaxSteps paired faces between;
  // every edge taken a candidate quad), then each pair on the path moves one
  // step: (t, u1), (w1, u2), ..., (w_{k-1}, x), one quad more. A path whose
  // new pairs would break a valence is put back as it was.
  constexpr int kMaxSteps = 6;
  std::vector<int> parent_edge(n_faces, -1), seen(n_faces, -1);
  std::vector<OMesh::FaceHandle> frontier, next;
  for (int sweep = 0; sweep < 3; ++sweep) {
    bool changed = false;
    for (const auto t : om.faces()) {
      if (mate[t.idx()] >= 0) continue;
      // seen[f] == t: reached in this search; parent_edge[u]: the edge u was entered by.
      seen[t.idx()] = t.idx();
      frontier.assign(1, t);
      OMesh::FaceHandle found;
      for (int step = 0; step <= kMaxSteps && !found.is_valid() && !frontier.empty(); ++step) {
        next.clear();
        for (const auto w : frontier) {
          for (const auto h : om.fh_range(w)) {
            const auto e = om.edge_handle(h);
            if (om.is_boundary(e) || candidate[e.idx()].quality < 0.0 || e == across[w.idx()]) continue;
            const auto u = om.opposite_face_handle(h);
            if (seen[u.idx()] == t.idx()) continue;
            seen[u.idx()] = t.idx();
            parent_edge[u.idx()] = e.idx();
            if (mate[u.idx()] < 0) {
              found = u;
              break;
            }
            const auto w2 = OMesh::FaceHandle(mate[u.idx()]);
            if (seen[w2.idx()] == t.idx() || step == kMaxSteps) continue;
            seen[w2.idx()] = t.idx();
            next.push_back(w2);
          }
          if (found.is_valid()) break;
        }
        frontier.swap(next);
      }
      if (!found.is_valid()) continue;
      // The path back from found: new edges (entered by) and old pairs (u's partner edge).
      std::vector<OMesh::EdgeHandle> added, removed;
      for (auto u = found;;) {
        const OMesh::EdgeHandle e(parent_edge[u.idx()]);
        added.push_back(e);
        const auto [f, g] = faces_of(e);
        const auto w = OMesh::FaceHandle(f == u.idx() ? g : f);
        if (w == t) break;
        removed.push_back(across[w.idx()]);
        u = OMesh::FaceHandle(mate[w.idx()]);
      }
      for (const auto e : removed) set_pair(e, false);
      std::size_t made = 0;
      while (made < added.size() && can_pair(added[made])) set_pair(added[made++], true);
      if (made == added.size()) {
        changed = true;
        continue;
      }
      while (made > 0) set_pair(added[--made], false);
      for (const auto e : removed) set_pair(e, true);
    }
    if (!changed) break;
  }
  Mesh out;
  out.vertices = positions;
  for (const auto f : om.faces()) {
    const int g = mate[f.idx()];
    if (g >= 0 && g < f.idx()) continue;  // the quad was written with its first face
    if (g < 0) {
      out.face_vertex_counts.push_back(3);
      for (const auto v : om.fv_range(f)) out.face_vertex_indices.push_back(v.idx());
    } else {
      out.face_vertex_counts.push_back(4);
      for (const auto v : candidate[across[f.idx()].idx()].corners) out.face_vertex_indices.push_back(v.idx());
    }
  }
  return out;
}

Mesh from_openmesh(const OMesh& om) {
  Mesh out;
  out.vertices.reserve(3 * om.n_vertices());
  for (const auto vh : om.vertices()) {
    const auto& p = om.point(vh);
    out.vertices.insert(out.vertices.end(), {p[0], p[1], p[2]});
  }
  out.face_vertex_indices.reserve(3 * om.n_faces());
  for (const auto fh : om.faces())
    for (const auto vh : om.fv_range(fh)) out.face_vertex_indices.push_back(vh.idx());
  return out;
}

}  // namespace

Mesh decimate(const Mesh& mesh, std::size_t n_vertices, const DecimateOptions& options, std::string* stopped) {
  check_options(options);
  if (stopped != nullptr) stopped->clear();
  if (n_vertices < 4) throw ParameterError("a cage needs at least 4 vertices, got " + std::to_string(n_vertices));
  // OpenMesh's quadric of a face holds its plane's offset d = -n.p and d^2,
  // and a point's error is the sum of terms of the order of |p|^2 that
  // cancel: far from the origin (1e6 on a scan of unit size: terms of 1e12,
  // rounded by 1e-4, errors of 1e-6) rounding decides the collapses. Its
  // normals and degeneracy checks are absolute too. So the mesh is
  // decimated in coordinates centred on the bounding box of its vertices in
  // faces and scaled by a power of two to a half-extent in [1/2, 1), and the
  // cage takes its vertices from the input (a half-edge collapse moves no
  // vertex): the same cage wherever the mesh lies and whatever its size, up
  // to the rounding of the centred coordinates.
  std::size_t have = 0;  // the vertices in faces (an index out of range is to_openmesh's to refuse)
  double centre[3];
  int e = 0;
  {
    // In tasks: the vertices in faces marked, then each task's count and
    // bounds over its vertices, taken in the tasks' order.
    const std::size_t nv = mesh.n_vertices(), k = mesh.face_vertex_indices.size();
    const std::unique_ptr<std::atomic<char>[]> used(new std::atomic<char>[nv]());
    const int corner_tasks = array_tasks(k), vertex_tasks = array_tasks(nv);
    detail::for_each_index(corner_tasks > 1, corner_tasks, k, [&](std::size_t c) {
      const std::int32_t v = mesh.face_vertex_indices[c];
      if (v >= 0 && static_cast<std::size_t>(v) < nv) used[static_cast<std::size_t>(v)].store(1, std::memory_order_relaxed);
    });
    struct Bounds {
      std::size_t have = 0;
      double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    };
    std::vector<Bounds> part(static_cast<std::size_t>(vertex_tasks));
    detail::for_each_range(vertex_tasks > 1, vertex_tasks, nv, [&](int t, std::size_t first, std::size_t last) {
      Bounds& b = part[static_cast<std::size_t>(t)];
      for (std::size_t v = first; v < last; ++v) {
        if (!used[v].load(std::memory_order_relaxed)) continue;
        ++b.have;
        for (int c = 0; c < 3; ++c) {
          b.lo[c] = std::min(b.lo[c], mesh.vertices[3 * v + c]);
          b.hi[c] = std::max(b.hi[c], mesh.vertices[3 * v + c]);
        }
      }
    });
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (const Bounds& b : part) {
      have += b.have;
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], b.lo[c]);
        hi[c] = std::max(hi[c], b.hi[c]);
      }
    }
    double half = 0.0;
    for (int c = 0; c < 3; ++c) {
      centre[c] = lo[c] + 0.5 * (hi[c] - lo[c]);
      half = std::max(half, 0.5 * (hi[c] - lo[c]));
    }
    if (half > 0.0 && std::isfinite(half)) std::frexp(half, &e);
  }
  // x scaled by 2^-e: a product with 2^-e, rounded once as ldexp rounds,
  // where 2^-e is a normal number.
  const double scale = std::ldexp(1.0, -e);
  const bool by_product = e > -1000 && e < 1000;
  const auto to_frame = [&](const double* x) {
    if (!by_product)
      return OpenMesh::Vec3d(std::ldexp(x[0] - centre[0], -e), std::ldexp(x[1] - centre[1], -e),
                             std::ldexp(x[2] - centre[2], -e));
    return OpenMesh::Vec3d((x[0] - centre[0]) * scale, (x[1] - centre[1]) * scale, (x[2] - centre[2]) * scale);
  };
  // A large mesh of more than twice kBulkFactor times the count is
  // clustered (cluster_vertices) to kBulkFactor times the count before
  // OpenMesh sees it: clustering is a few passes over flat arrays, each
  // collapse in OpenMesh's half-edge mesh jumps in memory. Nearer the count
  // a grid's cells would hold too few vertices to cluster.
  Clustering clustered;
  const bool clustering = have >= kLargeMesh && have > 2 * kBulkFactor * n_vertices &&
                          cluster_vertices(mesh, kBulkFactor * n_vertices, to_frame, clustered);
  std::vector<std::int32_t> kept;
  OMesh om = clustering ? to_openmesh(clustered.mesh, kept, true) : to_openmesh(mesh, kept);
  for (const auto vh : om.vertices()) {
    auto& p = om.point(vh);
    p = to_frame(p.data());
  }
  // Each OpenMesh vertex's input vertex, kept through the garbage collection.
  OpenMesh::VPropHandleT<std::int32_t> source;
  om.add_property(source);
  for (const auto vh : om.vertices()) {
    const std::int32_t k = kept[static_cast<std::size_t>(vh.idx())];
    om.property(source, vh) = clustering ? clustered.source[static_cast<std::size_t>(k)] : k;
  }
  const bool quads = options.scheme == Scheme::CatmullClark;
  if (n_vertices > have)
    throw MeshError("decimate: " + std::to_string(n_vertices) + " vertices asked but the mesh has " +
                    std::to_string(have) + " vertices" + (have < mesh.n_vertices() ? " in its faces" : ""));

  LazyDecimater decimater(om);
  ModQuadricErrorT<OMesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<OMesh>::Handle normals;
  OpenMesh::Decimater::ModAspectRatioT<OMesh>::Handle aspect;
  ModBoundaryAngleT<OMesh>::Handle boundary;
  // The binary modules run in this order: the cheapest first.
  decimater.add(quadric);
  decimater.add(boundary);
  decimater.add(aspect);
  decimater.add(normals);
  decimater.module(normals).set_max_normal_deviation(options.max_normal_deviation);
  decimater.module(aspect).set_aspect_ratio(static_cast<float>(options.max_aspect_ratio));
  decimater.module(boundary).set_max_angle(options.max_boundary_angle);
  InterruptObserver observer;
  decimater.set_observer(&observer);
  if (clustering) {  // the clusters' quadrics, of the input's faces
    std::vector<Quadric> given(om.n_vertices());
    for (const auto vh : om.vertices())
      given[static_cast<std::size_t>(vh.idx())] = clustered.quadrics[static_cast<std::size_t>(kept[static_cast<std::size_t>(vh.idx())])];
    decimater.module(quadric).set_quadrics(std::move(given));
  }
  if (!decimater.initialize()) throw MeshError("decimate: OpenMesh's decimater did not initialize");

  // One pass to the count, for both schemes: Catmull-Clark's quads are the
  // decimated triangles paired (paired_quads), which keeps the vertices.
  // A large mesh (kLargeMesh vertices or more) still above kBulkFactor
  // times the count (not clustered, or clustered to as many) is decimated
  // first in rounds (decimate_in_rounds) down to that, then compacted, and
  // the rest from the heap (decimate_to), which orders the last collapses,
  // those that shape the cage, one by one; a smaller mesh from the heap
  // alone.
  std::size_t count = om.n_vertices();
  if (count >= kLargeMesh && count > kBulkFactor * n_vertices) {
    decimater.decimate_in_rounds(count, kBulkFactor * n_vertices, decimater.module(quadric));
    observer.rethrow();
    om.garbage_collection();
  }
  decimater.decimate_to(count, n_vertices, decimater.module(quadric));
  observer.rethrow();
  om.garbage_collection();
  count = om.n_vertices();
  if (count > n_vertices) {
    std::string why = "decimate stopped at " + std::to_string(count) + " vertices of the " +
                      std::to_string(n_vertices) + " asked (from " + std::to_string(have) +
                      "): every further collapse would flip a normal, thin a face or cut a boundary corner "
                      "(max_normal_deviation, max_aspect_ratio, max_boundary_angle)";
    // Where the boundary holds the cage up, say so, with the way out: a scan
    // with many holes keeps at least three vertices of each (OpenMesh's
    // is_collapse_ok closes no hole), so the cage has more vertices than
    // asked (issue 33, item 11: 1517 for 150 on a scan with 47 boundary
    // loops, when a Catmull-Clark cage split a coarser decimation's triangles
    // into three quads; its vertices are now the triangles', as Loop's).
    std::size_t on_boundary = 0, loops = 0;
    {
      std::vector<char> seen(om.n_halfedges(), 0);
      for (const auto vh : om.vertices()) on_boundary += om.is_boundary(vh);
      for (const auto hh : om.halfedges()) {
        if (!om.is_boundary(hh) || seen[static_cast<std::size_t>(hh.idx())]) continue;
        ++loops;
        for (auto h = hh; !seen[static_cast<std::size_t>(h.idx())]; h = om.next_halfedge_handle(h))
          seen[static_cast<std::size_t>(h.idx())] = 1;
      }
    }
    if (on_boundary > 0)
      why += "; " + std::to_string(on_boundary) + " of the cage's " + std::to_string(om.n_vertices()) +
             " vertices lie on its " + std::to_string(loops) + " boundary loop" + (loops == 1 ? "" : "s") +
             ": each loop keeps at least 3 (no collapse closes a hole) and max_boundary_angle (" +
             std::to_string(static_cast<int>(options.max_boundary_angle)) +
             " degrees) those where it turns by more, so fill small holes first or raise max_boundary_angle (up to "
             "180)";
    // A cage that keeps every vertex of the mesh has as many control
    // vertices as the mesh (the data, when its vertices are the points)
    // has points: no lighter than the data, and the fit of the points
    // by it is not determined. Refused, whatever `stopped` asks.
    if (count >= have)
      throw MeshError(why + "; no collapse at all is allowed, so the cage would keep all " + std::to_string(have) +
                      " vertices, as many control vertices as the mesh has points: no fit is determined by it. Ask "
                      "for a cage on a mesh whose holes are filled or small parts removed, or give a cage of your own");
    if (stopped == nullptr) throw MeshError(why);
    *stopped = std::move(why);
  }
  Mesh triangles = from_openmesh(om);
  for (const auto vh : om.vertices())
    std::copy_n(&mesh.vertices[3 * static_cast<std::size_t>(om.property(source, vh))], 3,
                &triangles.vertices[3 * static_cast<std::size_t>(vh.idx())]);
  return quads ? paired_quads(om, triangles.vertices) : triangles;
}

Mesh quads_from_triangles(const Mesh& tri) {
  if (!tri.all_triangles()) throw MeshError("quads_from_triangles takes a triangle mesh");
  Mesh m;
  m.vertices = tri.vertices;
  const auto point = [&](std::initializer_list<std::int32_t> corners) {
    const auto v = static_cast<std::int32_t>(m.n_vertices());
    double p[3] = {0, 0, 0};
    for (std::int32_t c : corners)
      for (int k = 0; k < 3; ++k) p[k] += tri.vertices[3 * c + k] / static_cast<double>(corners.size());
    m.vertices.insert(m.vertices.end(), p, p + 3);
    return v;
  };
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> midpoints;
  const auto midpoint = [&](std::int32_t a, std::int32_t b) {
    const auto key = std::minmax(a, b);
    const auto it = midpoints.find(key);
    if (it != midpoints.end()) return it->second;
    const std::int32_t v = point({a, b});
    midpoints.emplace(key, v);
    return v;
  };
  m.face_vertex_counts.assign(3 * tri.n_faces(), 4);
  m.face_vertex_indices.reserve(12 * tri.n_faces());
  for (std::size_t f = 0; f < tri.n_faces(); ++f) {
    const std::int32_t* t = tri.face_vertex_indices.data() + 3 * f;
    const std::int32_t c = point({t[0], t[1], t[2]});
    const std::int32_t mid[3] = {midpoint(t[0], t[1]), midpoint(t[1], t[2]), midpoint(t[2], t[0])};
    // corner k: (t[k], mid(k, k+1), centroid, mid(k-1, k)), counter-clockwise as the triangle
    for (int k = 0; k < 3; ++k)
      m.face_vertex_indices.insert(m.face_vertex_indices.end(), {t[k], mid[k], c, mid[(k + 2) % 3]});
  }
  return m;
}

}  // namespace sorpia
