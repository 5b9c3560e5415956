#include "sorpia/surface.hpp"

#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/bfr/surfaceFactoryCache.h>
#include <opensubdiv/far/error.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#include <opensubdiv/version.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/detail/level_dependent_rows.hpp"
#include "sorpia/detail/order.hpp"
#include "sorpia/detail/osd_refiner.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/detail/unit_normal.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/subface_grid.hpp"

namespace sorpia {

namespace {

namespace Bfr = OpenSubdiv::Bfr;
namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

// A thread-safe cache lets every thread of evaluate() share one factory (irregular
// patches are built once per distinct vertex neighbourhood, then reused).
using ThreadedCache = Bfr::SurfaceFactoryCacheThreaded<std::shared_mutex, std::shared_lock<std::shared_mutex>,
                                                       std::unique_lock<std::shared_mutex>>;
using SurfaceFactory = Bfr::RefinerSurfaceFactory<ThreadedCache>;

// OpenSubdiv before 3.6.1 (its pull request 1353): Bfr builds the irregular
// patch of a face with a corner at an interior vertex of two faces (where the
// control hull folds over itself) from the face's own mesh indices, which
// vertices repeat around the face, but caches it under the face's topology
// alone; a later face of the same topology whose indices repeat differently
// gets that patch, wrong for it (measured: corners of such faces 1e-2 of the
// diagonal off B V on quad_irregular(1200) with 20 of its quads split). Such
// faces are built by a factory without a cache (BfrSurfaces).
constexpr bool kBfrCachesFoldedPatchesWrongly = OPENSUBDIV_VERSION_NUMBER < 30601;

using detail::Point3;

// Bytes per refined face held by a uniformly refined TopologyRefiner with
// full topology (all levels together, ~4/3 of the last level) and the
// position buffers, for the memory check before a tessellation;
// bench/io_speed.py prints the peak it measures beside this estimate (both
// schemes: it measures Loop and Catmull-Clark).
constexpr double kRefinerBytesPerTriangle = 220.0;
constexpr double kRefinerBytesPerQuad = 300.0;

// Bfr represents the surface next to an extraordinary vertex by Gregory
// patches after this many local refinements (default 2): 4 shrinks that
// region to the corners of side 1/16, where OpenSubdiv's derivatives are
// approximate (it drops the derivative of the rational Gregory weights), at a
// small cost in evaluation time.
constexpr int kApproxLevelSmooth = 4;
// The smooth level on a mesh with darts (an interior vertex with one
// infinitely sharp edge): Bfr's corner there is Far's Limit() after this many
// local refinements, which is not the limit (evaluate() takes the corner
// itself from B), so the points next to it jump by that point's distance to
// the limit, which shrinks as rho^level (rho about 1/3 at the regular
// valences). One level for the whole surface: a higher level for the faces at
// darts alone would crack their other edges, where a neighbouring face
// approximates an extraordinary vertex at the lower level.
constexpr int kApproxLevelDarts = 10;
// Local refinements around semi-sharp features (default 6): 10, the deepest
// OpenSubdiv isolates, so that every semi-sharp feature (sharpness below 10)
// has decayed before Bfr stops refining.
constexpr int kApproxLevelSharp = 10;

// Faces per chunk that a thread takes at a time in evaluate(); also the least
// work per thread.
constexpr std::ptrdiff_t kFacesPerChunk = 64;

// Points per task of rows()' copy into the matrices, at least.
constexpr std::size_t kRowsPerCopyTask = 65536;
// Points per task of the checks of faces and parameters (and of the largest face id), at least.
constexpr std::size_t kPointsPerCheckTask = 65536;
// Faces per task of position_blocks' columns, at least.
constexpr std::size_t kFacesPerColumnsTask = 4096;

// Threads for `n_groups` faces: no more than there are chunks, so a small
// query runs on the calling thread alone, and no more than the processors.
int evaluate_threads(std::ptrdiff_t n_groups) {
  const std::ptrdiff_t chunks = (n_groups + kFacesPerChunk - 1) / kFacesPerChunk;
  return static_cast<int>(
      std::max<std::ptrdiff_t>(1, std::min<std::ptrdiff_t>(detail::available_processors(), chunks)));
}

// Bfr evaluates on the closed face domain; a parameter a rounding error outside
// is pulled back onto it, anything further out is refused.
constexpr double kUvSlack = 1e-12;

// Faces of the tessellation at `level` (see LimitSurface::tessellate).
double tessellated_faces(Scheme scheme, std::size_t n_faces, std::size_t n_face_vertices, int level) {
  if (scheme == Scheme::Loop || level == 0) return static_cast<double>(n_faces) * std::pow(4.0, level);
  return static_cast<double>(n_face_vertices) * std::pow(4.0, level - 1);
}

std::string face_words(Scheme scheme, double faces, int level) {
  char count[32];
  std::snprintf(count, sizeof count, "%.0f", faces);
  if (scheme == Scheme::Loop) return std::string(count) + " triangles (4^level per face)";
  if (level == 0) return std::string(count) + " faces";
  return std::string(count) + " quads (k 4^(level-1) per k-sided face)";
}

// The Bfr surfaces of one limit surface's faces and their patch points at the
// current control vertices: each face's Bfr::Surface is built on its first
// use and kept (it depends on the topology and the rules alone), from
// `cached` (one factory whose cache shares irregular patches between faces of
// the same topology) for every face but those Bfr must build on their own
// (see kBfrCachesFoldedPatchesWrongly), which a factory without a cache
// builds; its patch points (Bfr::Surface::PreparePatchPoints) are prepared on
// the face's first evaluation after each change of the control vertices
// (invalidate()) and kept until the next, so that every evaluation of the
// face until then (Gauss-Newton steps, grid samples, rounds of a search)
// uses them as they are; its columns (its control points as mesh vertices)
// are made on their first use and kept. Each is made by whichever thread
// asks first, under a lock per face (striped), and read without one after.
class BfrSurfaces {
 public:
  BfrSurfaces(const Far::TopologyRefiner& refiner, const Topology& t, Bfr::SurfaceFactory::Options options)
      : cached_(refiner, options), faces_(std::make_unique<Face[]>(t.n_faces())), n_faces_(t.n_faces()) {
    if (!kBfrCachesFoldedPatchesWrongly) return;
    const auto& fi = t.face_indices();
    bool any = false;
    for (std::size_t f = 0; f < t.n_faces(); ++f) {
      const std::int32_t o = t.face_offset(f);
      bool alone = false;
      for (std::int32_t i = 0; i < t.face_size(f); ++i) {
        const auto v = static_cast<std::size_t>(fi[static_cast<std::size_t>(o + i)]);
        alone = alone || (!t.is_boundary(v) && t.face_count(v) == 2);
      }
      faces_[f].alone = alone;
      any = any || alone;
    }
    if (!any) return;
    options.EnableCaching(false);
    uncached_ = std::make_unique<Bfr::RefinerSurfaceFactory<>>(refiner, options);
  }

  // Face `face`'s Bfr surface, built on its first use (safe from several
  // threads); null where Bfr cannot build it.
  const Bfr::Surface<double>* get(int face) const {
    Face& f = faces_[static_cast<std::size_t>(face)];
    std::uint8_t state = f.built.load(std::memory_order_acquire);
    if (state == kNotBuilt) {
      const std::lock_guard<std::mutex> lock(stripe(face));
      state = f.built.load(std::memory_order_relaxed);
      if (state == kNotBuilt) {
        const bool ok = f.alone ? uncached_->InitVertexSurface(face, &f.surface)
                                : cached_.InitVertexSurface(face, &f.surface);
        state = ok ? kValid : kInvalid;
        f.built.store(state, std::memory_order_release);
      }
    }
    return state == kValid ? &f.surface : nullptr;
  }

  // The patch points of face `face` (whose surface get() returned) at the
  // control points `mesh_points` (in OpenSubdiv's order, the current ones:
  // prepared once after each invalidate()), as Bfr::Surface::Evaluate takes
  // them (3 doubles each).
  const double* patch_points(int face, const double* mesh_points) const {
    Face& f = faces_[static_cast<std::size_t>(face)];
    if (f.prepared.load(std::memory_order_acquire) != generation_) {
      const std::lock_guard<std::mutex> lock(stripe(face));
      if (f.prepared.load(std::memory_order_relaxed) != generation_) {
        const Bfr::Surface<double>::PointDescriptor desc(3);
        f.patch.resize(3 * static_cast<std::size_t>(f.surface.GetNumPatchPoints()));
        f.surface.PreparePatchPoints(mesh_points, desc, f.patch.data(), desc);
        f.prepared.store(generation_, std::memory_order_release);
      }
    }
    return f.patch.data();
  }

  // Face `face`'s control points (of the surface get() returned) as mesh
  // vertices (`from_osd`), sorted and distinct: the columns of its points'
  // rows, made on the face's first use and kept (they depend on the topology
  // alone).
  const std::vector<std::int32_t>& columns(int face, const std::vector<std::int32_t>& from_osd) const {
    Face& f = faces_[static_cast<std::size_t>(face)];
    if (!f.has_columns.load(std::memory_order_acquire)) {
      const std::lock_guard<std::mutex> lock(stripe(face));
      if (!f.has_columns.load(std::memory_order_relaxed)) {
        std::vector<int> cv(static_cast<std::size_t>(f.surface.GetNumControlPoints()));
        f.surface.GetControlPointIndices(cv.data());
        f.columns.resize(cv.size());
        for (std::size_t c = 0; c < cv.size(); ++c) f.columns[c] = from_osd[static_cast<std::size_t>(cv[c])];
        std::sort(f.columns.begin(), f.columns.end());
        f.columns.erase(std::unique(f.columns.begin(), f.columns.end()), f.columns.end());
        f.has_columns.store(true, std::memory_order_release);
      }
    }
    return f.columns;
  }

  // The control vertices changed: every face's patch points are prepared
  // again on its next use. The caller holds the surface's lock exclusively.
  void invalidate() { ++generation_; }

  // A face's parameterisation (the same from either factory).
  Bfr::Parameterization parameterization(int face) const { return cached_.GetFaceParameterization(face); }

 private:
  static constexpr std::uint8_t kNotBuilt = 0, kValid = 1, kInvalid = 2;
  struct Face {
    Bfr::Surface<double> surface;
    std::vector<double> patch;
    std::vector<std::int32_t> columns;       // columns()'s
    std::atomic<std::uint64_t> prepared{0};  // the generation the patch points are of (0: none)
    std::atomic<std::uint8_t> built{kNotBuilt};
    std::atomic<bool> has_columns{false};
    bool alone = false;  // built by uncached_
  };
  std::mutex& stripe(int face) const { return stripes_[static_cast<std::size_t>(face) % kStripes]; }

 public:
  std::size_t n_faces() const { return n_faces_; }

 private:
  SurfaceFactory cached_;
  std::unique_ptr<Bfr::RefinerSurfaceFactory<>> uncached_;  // null when no face is alone
  std::unique_ptr<Face[]> faces_;
  std::size_t n_faces_;
  std::uint64_t generation_ = 1;
  static constexpr std::size_t kStripes = 64;
  mutable std::mutex stripes_[kStripes];
};

}  // namespace

std::size_t tessellation_bytes(Scheme scheme, std::size_t n_vertices, std::size_t n_faces,
                               std::size_t n_face_vertices, int level) {
  if (n_face_vertices == 0) n_face_vertices = n_faces * (scheme == Scheme::Loop ? 3 : 4);
  const double faces = tessellated_faces(scheme, n_faces, n_face_vertices, level);
  const bool quads = scheme == Scheme::CatmullClark;
  // Euler: a closed triangle mesh has about half as many vertices as faces, a
  // quad mesh as many.
  const double verts = static_cast<double>(n_vertices) + (quads ? faces : faces / 2.0) +
                       2.0 * static_cast<double>(n_faces);
  // refiner (every level) + output arrays: vertices (24 B) and faces (4 B a
  // corner), each held twice while the Python layer copies them.
  const double bytes = faces * (quads ? kRefinerBytesPerQuad : kRefinerBytesPerTriangle) +
                       2.0 * (24.0 * verts + (quads ? 16.0 : 12.0) * faces);
  return bytes >= static_cast<double>(std::numeric_limits<std::size_t>::max())
             ? std::numeric_limits<std::size_t>::max()
             : static_cast<std::size_t>(bytes);
}

struct LimitSurface::Impl {
  Topology topology;
  Scheme scheme;
  Boundary boundary;
  Tags tags;
  detail::Refiner base;  // unrefined, with the tags: Bfr and the limit positions of control vertices
  std::unique_ptr<BfrSurfaces> factory;
  std::vector<double> vertices;  // (n, 3), as given
  std::vector<Point3> points;    // referenced vertices in OpenSubdiv's order
  // Darts and Catmull-Clark's interior vertices of two faces
  // (detail::level_dependent_rows): Bfr's corner there is Far's Limit() after
  // its local refinements, not the limit of refinement, so evaluate() takes
  // such a corner from the vertex's row of B (exact_slot[v]: v's row in
  // exact.rows, or -1) at the current vertices.
  detail::LevelDependentRows exact;
  std::vector<std::int32_t> exact_slot;
  std::vector<double> exact_points;  // (exact.vertices, 3)
  // Faces at a dart of two faces (an interior vertex of two faces with one
  // infinitely sharp edge): OpenSubdiv's Bfr before 3.6.1 builds a wrong
  // patch there and writes out of bounds (OpenSubdiv pull request 1336), so
  // evaluation refuses them (bfr_unsafe[f]: that vertex, or -1; empty when
  // there are none or OpenSubdiv is new enough).
  std::vector<std::int32_t> bfr_unsafe;
  bool has_darts = false;  // among exact.vertices
  // Uniformly refined to refined_level (built on demand); shares base's level
  // 0 (Far::TopologyRefinerFactory::Create), so it is declared after base and
  // destroyed before it.
  std::unique_ptr<detail::UniformRefinement> refined;
  int refined_level = -1;
  // The Python binding releases the GIL: evaluate() may run in several
  // threads at once, set_vertices() and tessellate() change state.
  mutable std::shared_mutex mutex;

  Impl(const Topology& t, Scheme s, Boundary b, const Tags& g)
      : topology(t),
        scheme(s),
        boundary(b),
        tags(g),
        base(detail::make_refiner(t, s, b, g)),
        exact(detail::level_dependent_rows(t, s, b, g)) {
    if (exact.vertices.empty()) return;
    exact_slot.assign(t.n_vertices(), -1);
    for (std::size_t k = 0; k < exact.vertices.size(); ++k)
      exact_slot[exact.vertices[k]] = static_cast<std::int32_t>(k);
    const Far::TopologyLevel& level0 = base.refiner->GetLevel(0);
    for (const std::int32_t v : exact.vertices) {
      const int o = base.to_osd[v];
      bool sharp = false;  // a dart: level-dependent with an infinitely sharp edge
      for (const int e : level0.GetVertexEdges(o)) sharp = sharp || level0.IsEdgeInfSharp(e);
      has_darts = has_darts || sharp;
      if (!sharp || level0.GetVertexFaces(o).size() != 2 || OPENSUBDIV_VERSION_NUMBER >= 30601) continue;
      if (bfr_unsafe.empty()) bfr_unsafe.assign(t.n_faces(), -1);
      for (const int f : level0.GetVertexFaces(o)) bfr_unsafe[f] = v;
    }
  }
};

namespace {

std::string uv_str(double u, double v) { return "(" + std::to_string(u) + ", " + std::to_string(v) + ")"; }

// Checks (u, v) against the domain of a face with parameterisation `param`
// (see surface.hpp) and pulls a point a rounding error outside onto it.
void check_uv(const Bfr::Parameterization& param, std::size_t i, double& u, double& v) {
  const auto where = [&] { return "uv[" + std::to_string(i) + "] = " + uv_str(u, v); };
  switch (param.GetType()) {
    case Bfr::Parameterization::TRI:
      if (!(u >= -kUvSlack && v >= -kUvSlack && u + v <= 1.0 + kUvSlack))
        throw ParameterError(where() + " is outside the triangle u >= 0, v >= 0, u + v <= 1");
      u = std::max(u, 0.0);
      v = std::max(v, 0.0);
      if (u + v > 1.0) {
        const double s = u + v;
        u /= s;
        v /= s;
      }
      return;
    case Bfr::Parameterization::QUAD:
      if (!(u >= -kUvSlack && v >= -kUvSlack && u <= 1.0 + kUvSlack && v <= 1.0 + kUvSlack))
        throw ParameterError(where() + " is outside the quad's unit square 0 <= u, v <= 1");
      u = std::clamp(u, 0.0, 1.0);
      v = std::clamp(v, 0.0, 1.0);
      return;
    case Bfr::Parameterization::QUAD_SUBFACES: {
      // Sub-face j is [x_j, x_j + 1/2] x [y_j, y_j + 1/2], (x_j, y_j) = (j mod
      // w, j div w) (Bfr's GetVertexCoord(j)); the tile of (u, v) is the
      // corner at or below it, as Bfr's ConvertCoordToSubFace rounds.
      const int k = param.GetFaceSize();
      const int w = subface_columns(k);
      const double tile_u = std::floor(u + kUvSlack), tile_v = std::floor(v + kUvSlack);
      const double su = u - tile_u, sv = v - tile_v;
      const double j = tile_v * w + tile_u;
      if (!(tile_u >= 0.0 && tile_u < w && tile_v >= 0.0 && j < k && su <= 0.5 + kUvSlack && sv <= 0.5 + kUvSlack))
        throw ParameterError(where() + " is in none of the " + std::to_string(k) + " sub-faces of this " +
                             std::to_string(k) + "-sided face: sub-face j is the square of side 1/2 at (j mod " +
                             std::to_string(w) + ", j div " + std::to_string(w) + "), j < " + std::to_string(k));
      u = tile_u + std::clamp(su, 0.0, 0.5);
      v = tile_v + std::clamp(sv, 0.0, 0.5);
      return;
    }
  }
}

}  // namespace

LimitSurface::LimitSurface(const Topology& topology, const double* vertices, Scheme scheme, Boundary boundary,
                           const Tags& tags)
    : impl_(std::make_unique<Impl>(topology, scheme, boundary, tags)) {
  Bfr::SurfaceFactory::Options options;
  options.SetApproxLevelSmooth(impl_->has_darts ? kApproxLevelDarts : kApproxLevelSmooth);
  options.SetApproxLevelSharp(kApproxLevelSharp);
  impl_->factory = std::make_unique<BfrSurfaces>(*impl_->base.refiner, impl_->topology, options);
  set_vertices(vertices);
}

LimitSurface::~LimitSurface() = default;
LimitSurface::LimitSurface(LimitSurface&&) noexcept = default;
LimitSurface& LimitSurface::operator=(LimitSurface&&) noexcept = default;

std::size_t LimitSurface::n_vertices() const { return impl_->topology.n_vertices(); }
std::size_t LimitSurface::n_faces() const { return impl_->topology.n_faces(); }
Scheme LimitSurface::scheme() const { return impl_->scheme; }
Boundary LimitSurface::boundary() const { return impl_->boundary; }
const Tags& LimitSurface::tags() const { return impl_->tags; }
const Topology& LimitSurface::topology() const { return impl_->topology; }

void LimitSurface::set_vertices(const double* vertices) {
  const std::unique_lock<std::shared_mutex> lock(impl_->mutex);
  const std::size_t n = n_vertices();
  impl_->vertices.assign(vertices, vertices + 3 * n);
  detail::gather_points(impl_->base, vertices, impl_->points);
  impl_->factory->invalidate();
  const CsrMatrix& rows = impl_->exact.rows;
  impl_->exact_points.assign(3 * rows.n_rows, 0.0);
  for (std::size_t k = 0; k < rows.n_rows; ++k)
    for (std::int32_t p = rows.indptr[k]; p < rows.indptr[k + 1]; ++p)
      for (int c = 0; c < 3; ++c) impl_->exact_points[3 * k + c] += rows.data[p] * vertices[3 * rows.indices[p] + c];
}

void LimitSurface::get_vertices(double* out) const {
  const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
  std::copy(impl_->vertices.begin(), impl_->vertices.end(), out);
}

namespace {

// The faces the k points lie in (ids checked), numbered in increasing order
// of the face: slot[f] is face f's number (-1 for a face with no point),
// face[b] the face numbered b.
struct FaceSlots {
  std::vector<std::int32_t> slot, face;
};
FaceSlots face_slots(const std::int32_t* face_ids, std::size_t k, std::size_t n_faces) {
  FaceSlots out;
  out.slot.assign(n_faces, -1);
  for (std::size_t i = 0; i < k; ++i) out.slot[static_cast<std::size_t>(face_ids[i])] = 0;
  for (std::size_t f = 0; f < n_faces; ++f)
    if (out.slot[f] == 0) {
      out.slot[f] = static_cast<std::int32_t>(out.face.size());
      out.face.push_back(static_cast<std::int32_t>(f));
    }
  return out;
}

// Calls fn(surface, face, first, last) for each face of the k points, in
// parallel over chunks of faces: [first, last) are the indices of that face's
// points, `surface` its Bfr surface. Each point is computed alone, so the
// thread count changes nothing in the results. The caller holds the
// surface's lock.
template <class Fn>
void for_each_face_surface(const BfrSurfaces& factory, const std::int32_t* face_ids, std::size_t k, Fn fn) {
  // Group the points by face (stable: by face, then index) so that each
  // face's surface is built once; the ids are checked, in [0, n_faces).
  std::vector<std::size_t> order(k);
  std::vector<std::size_t> group_start;  // the faces with points
  const std::size_t n_keys = factory.n_faces();
  if (k < n_keys / 16) {
    // Few points on many faces (a re-projection's later rounds): sorted (the same order, by face then index)
    // without the counting sort's pass over every face.
    for (std::size_t i = 0; i < k; ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return face_ids[a] < face_ids[b]; });
    for (std::size_t j = 0; j < k; ++j)
      if (j == 0 || face_ids[order[j]] != face_ids[order[j - 1]]) group_start.push_back(j);
  } else {
    const std::vector<std::size_t> first = detail::order_by_key(face_ids, k, n_keys, order.data());
    for (std::size_t f = 0; f + 1 < first.size(); ++f)
      if (first[f + 1] > first[f]) group_start.push_back(first[f]);
  }
  group_start.push_back(k);
  const auto n_groups = static_cast<std::ptrdiff_t>(group_start.size()) - 1;

  std::atomic<int> failed_face{-1};
  // Chunks of faces are handed out in turn (their costs differ).
  std::atomic<std::ptrdiff_t> next_chunk{0};
  std::atomic<bool> stop{false};
  const int threads = evaluate_threads(n_groups);
  detail::for_each_task(threads > 1, threads, [&](int) {
    for (;;) {
      // Only the calling thread's poll can throw (workers have no checker);
      // the others then stop at their next chunk.
      if (stop) break;
      try {
        poll_interrupt();
      } catch (...) {
        stop = true;
        throw;
      }
      const std::ptrdiff_t first = kFacesPerChunk * next_chunk++;
      if (first >= n_groups) break;
      for (std::ptrdiff_t g = first; g < std::min(n_groups, first + kFacesPerChunk); ++g) {
        const int face = face_ids[order[group_start[g]]];
        const Bfr::Surface<double>* built = factory.get(face);
        if (!built) {
          failed_face = face;
          continue;
        }
        fn(*built, face, order.data() + group_start[g], order.data() + group_start[g + 1]);
      }
    }
  });
  if (failed_face >= 0)
    throw MeshError("OpenSubdiv's Bfr could not build the limit surface of face " + std::to_string(failed_face.load()));
}

// Bfr evaluation of k checked points (face_ids[i], params[2i..2i+1]) of the
// surface whose control points (in OpenSubdiv's order) are `mesh_points`;
// derivative outputs may be null. The caller holds the surface's lock.
void evaluate_points(const BfrSurfaces& factory, const double* mesh_points, const std::int32_t* face_ids,
                     const double* params, std::size_t k, double* positions, double* du, double* dv,
                     double* normals) {
  const bool want_derivs = du || dv || normals;
  const Bfr::Surface<double>::PointDescriptor desc(3);
  for_each_face_surface(factory, face_ids, k,
                        [&](const Bfr::Surface<double>& surface, int face, const std::size_t* first,
                            const std::size_t* last) {
                          const double* patch = factory.patch_points(face, mesh_points);
                          for (const std::size_t* it = first; it != last; ++it) {
                            const std::size_t i = *it;
                            double p[3], d1[3], d2[3];
                            if (want_derivs)
                              surface.Evaluate(&params[2 * i], patch, desc, p, d1, d2);
                            else
                              surface.Evaluate(&params[2 * i], patch, desc, p);
                            std::copy(p, p + 3, positions + 3 * i);
                            if (du) std::copy(d1, d1 + 3, du + 3 * i);
                            if (dv) std::copy(d2, d2 + 3, dv + 3 * i);
                            if (normals) detail::unit_normal(d1, d2, normals + 3 * i);
                          }
                        });
}

// Whether Bfr's second-derivative stencils s[3..5] at `uv` of an irregular
// Loop face carry the wrong sign. OpenSubdiv (3.5 and 3.6:
// Far::internal::EvaluatePatchBasisNormalized) scales the second derivatives
// of a sub-patch rotated by 180 degrees (the middle triangle of a split
// triangle) by derivSign * d1Scale^2 with d1Scale already signed, so they
// come out negated there; the rotation is internal to Bfr's patch tree.
// Decided against a one-sided difference of the first-derivative stencils
// towards the triangle's centre, h = 2^-20 (the derivative of du along that
// direction, duu d_u + duv d_v, is what it approximates to O(h)); `scratch`
// holds the stencils at the shifted point.
bool second_derivatives_reversed(const Bfr::Surface<double>& surface, const double* uv, double* const s[6],
                                 std::vector<double>& scratch) {
  const int n = surface.GetNumControlPoints();
  double d[2] = {1.0 / 3.0 - uv[0], 1.0 / 3.0 - uv[1]};
  const double len = std::hypot(d[0], d[1]);
  if (len < 1e-3) {  // at the centre: along u (the centre is far from every edge)
    d[0] = 1.0;
    d[1] = 0.0;
  } else {
    d[0] /= len;
    d[1] /= len;
  }
  const double h = std::ldexp(1.0, -20);
  const double shifted[2] = {uv[0] + h * d[0], uv[1] + h * d[1]};
  scratch.resize(3 * static_cast<std::size_t>(n));
  surface.EvaluateStencil(shifted, scratch.data(), scratch.data() + n, scratch.data() + 2 * n);
  // (du(shifted) - du(uv)) / h against duu d_u + duv d_v, and likewise dv.
  double agree = 0.0;
  for (int c = 0; c < n; ++c) {
    const double fu = (scratch[n + c] - s[1][c]) / h, fv = (scratch[2 * n + c] - s[2][c]) / h;
    agree += fu * (s[3][c] * d[0] + s[4][c] * d[1]) + fv * (s[4][c] * d[0] + s[5][c] * d[1]);
  }
  return agree < 0.0;
}

// The stencils of one face's points: the face's control points as mesh
// vertices (sorted, distinct) and, per point and per matrix d, one weight per
// column (weights[d][j * columns.size() + c]).
struct FaceStencils {
  std::vector<std::int32_t> columns;
  std::vector<double> weights[6];
};

// The stencils of k checked points (face_ids[i], params[2i..2i+1]) a face at
// a time, on the core's threads (for_each_face_surface): fn(face, first,
// last, stencils) with [first, last) the indices of the face's points and
// `stencils` their matrices 0 .. derivatives' (position; du, dv; duu, duv,
// dvv), a thread's buffer that fn may take. OpenSubdiv's second derivatives
// on the rotated middle sub-patches of irregular Loop faces are corrected
// (see second_derivatives_reversed). The caller holds the surface's lock.
template <class Fn>
void face_stencils(const BfrSurfaces& factory, const std::vector<std::int32_t>& from_osd,
                   const std::int32_t* face_ids, const double* params, std::size_t k, int derivatives, Fn fn) {
  const int n_mats = derivatives == 0 ? 1 : derivatives == 1 ? 3 : 6;
  for_each_face_surface(
      factory, face_ids, k,
      [&](const Bfr::Surface<double>& surface, int face, const std::size_t* first, const std::size_t* last) {
        thread_local FaceStencils out;
        const int n_cv = surface.GetNumControlPoints();
        thread_local std::vector<int> cv;
        thread_local std::vector<double> w, w2;
        thread_local std::vector<std::int32_t> slot, mapped;
        cv.resize(n_cv);
        surface.GetControlPointIndices(cv.data());
        // A mesh vertex may be more than one control point of the surface
        // (a face meeting itself around a vertex): its weights add up.
        mapped.resize(n_cv);
        for (int c = 0; c < n_cv; ++c) mapped[c] = from_osd[cv[c]];
        slot.resize(n_cv);
        std::vector<std::int32_t>& cols = out.columns;
        cols = factory.columns(face, from_osd);
        for (int c = 0; c < n_cv; ++c)
          slot[c] = static_cast<std::int32_t>(std::lower_bound(cols.begin(), cols.end(), mapped[c]) - cols.begin());
        const std::size_t width = cols.size(), count = static_cast<std::size_t>(last - first);
        for (int d = 0; d < n_mats; ++d) out.weights[d].assign(count * width, 0.0);
        w.resize(6 * static_cast<std::size_t>(n_cv));
        double* s[6];
        for (int d = 0; d < 6; ++d) s[d] = w.data() + d * n_cv;
        for (std::size_t j = 0; j < count; ++j) {
          const double* t = &params[2 * first[j]];
          if (derivatives == 0)
            surface.EvaluateStencil(t, s[0]);
          else if (derivatives == 1)
            surface.EvaluateStencil(t, s[0], s[1], s[2]);
          else {
            surface.EvaluateStencil(t, s[0], s[1], s[2], s[3], s[4], s[5]);
            if (!surface.IsRegular() && surface.GetParameterization().GetType() == Bfr::Parameterization::TRI &&
                second_derivatives_reversed(surface, t, s, w2))
              for (int d = 3; d < 6; ++d)
                for (int c = 0; c < n_cv; ++c) s[d][c] = -s[d][c];
          }
          for (int d = 0; d < n_mats; ++d)
            for (int c = 0; c < n_cv; ++c) out.weights[d][j * width + slot[c]] += s[d][c];
        }
        fn(face, first, last, out);
      });
}

}  // namespace

void LimitSurface::visit_faces(const std::int32_t* face_ids, std::size_t k,
                               const std::function<void(std::int32_t, const std::size_t*, const std::size_t*,
                                                        const FaceEvaluation&)>& visit) const {
  check_faces(face_ids, k);
  const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
  const double* mesh_points = &impl_->points.data()->x;
  const Bfr::Surface<double>::PointDescriptor desc(3);
  for_each_face_surface(*impl_->factory, face_ids, k,
                        [&](const Bfr::Surface<double>& surface, int face, const std::size_t* first,
                            const std::size_t* last) {
                          const double* patch = impl_->factory->patch_points(face, mesh_points);
                          const FaceEvaluation evaluate = [&](const double* uv, double* p, double* du, double* dv) {
                            surface.Evaluate(uv, patch, desc, p, du, dv);
                          };
                          visit(face, first, last, evaluate);
                        });
}

void LimitSurface::check_faces(const std::int32_t* face_ids, std::size_t k) const {
  const std::size_t n_f = n_faces();
  const auto& level0 = impl_->base.refiner->GetLevel(0);
  detail::check_each_index(k, kPointsPerCheckTask, [&](std::size_t i) {
    const std::int32_t f = face_ids[i];
    if (f < 0 || static_cast<std::size_t>(f) >= n_f)
      throw ParameterError("face_ids[" + std::to_string(i) + "] = " + std::to_string(f) + " is out of range [0, " +
                           std::to_string(n_f) + ")");
    if (level0.IsFaceHole(f))
      throw ParameterError("face_ids[" + std::to_string(i) + "] = " + std::to_string(f) +
                           " is a hole: it has no limit surface");
    if (!impl_->bfr_unsafe.empty() && impl_->bfr_unsafe[f] >= 0)
      throw MeshError("face_ids[" + std::to_string(i) + "] = " + std::to_string(f) + " is at vertex " +
                      std::to_string(impl_->bfr_unsafe[f]) +
                      ", an interior vertex of two faces with one infinitely sharp edge, where OpenSubdiv's Bfr "
                      "before 3.6.1 (this build has " + std::to_string(OPENSUBDIV_VERSION_NUMBER) +
                      ") evaluates no valid surface: remove that sharp edge, or split the vertex's faces");
  });
}

void LimitSurface::checked_params(const std::int32_t* face_ids, const double* uv, std::size_t k,
                                  double* params) const {
  check_faces(face_ids, k);
  const BfrSurfaces& factory = *impl_->factory;
  detail::check_each_index(k, kPointsPerCheckTask, [&](std::size_t i) {
    params[2 * i] = uv[2 * i];
    params[2 * i + 1] = uv[2 * i + 1];
    check_uv(factory.parameterization(face_ids[i]), i, params[2 * i], params[2 * i + 1]);
  });
}

std::vector<std::int32_t> LimitSurface::exact_corners(const std::int32_t* face_ids, const double* params,
                                                      std::size_t k) const {
  std::vector<std::int32_t> slots;
  if (impl_->exact.vertices.empty()) return slots;
  slots.assign(k, -1);
  const Topology& t = impl_->topology;
  const BfrSurfaces& factory = *impl_->factory;
  for (std::size_t i = 0; i < k; ++i) {
    const std::int32_t f = face_ids[i];
    const std::int32_t* fv = t.face_indices().data() + t.face_offset(f);
    for (int j = 0; j < t.face_size(f); ++j) {
      const std::int32_t slot = impl_->exact_slot[fv[j]];
      if (slot < 0) continue;
      double corner[2];
      factory.parameterization(f).GetVertexCoord(j, corner);
      if (corner[0] == params[2 * i] && corner[1] == params[2 * i + 1]) slots[i] = slot;
    }
  }
  return slots;
}

void LimitSurface::evaluate(const std::int32_t* face_ids, const double* uv, std::size_t k, double* positions,
                            double* du, double* dv, double* normals) const {
  std::vector<double> params(2 * k);
  checked_params(face_ids, uv, k, params.data());
  const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
  evaluate_points(*impl_->factory, &impl_->points.data()->x, face_ids, params.data(), k, positions, du, dv,
                  normals);
  // A point at the corner of a dart or a vertex of two faces: its limit
  // position (see Impl::exact).
  const std::vector<std::int32_t> slots = exact_corners(face_ids, params.data(), k);
  for (std::size_t i = 0; i < slots.size(); ++i)
    if (slots[i] >= 0)
      std::copy_n(&impl_->exact_points[3 * static_cast<std::size_t>(slots[i])], 3, positions + 3 * i);
}

SurfaceRows LimitSurface::rows(const std::int32_t* face_ids, const double* uv, std::size_t k, int derivatives) const {
  SurfaceRows out;
  CsrMatrix* mats[6] = {&out.position, &out.du, &out.dv, &out.duu, &out.duv, &out.dvv};
  detail::Scratch scratch;
  const detail::Scratch::Frame frame(&scratch);
  make_rows(face_ids, uv, k, derivatives, scratch, [&](int d, std::vector<std::int32_t>&& indptr) {
    CsrMatrix& m = *mats[d];
    m.n_rows = k;
    m.n_cols = n_vertices();
    m.indptr = std::move(indptr);
    m.indices.resize(static_cast<std::size_t>(m.indptr[k]));
    m.data.resize(static_cast<std::size_t>(m.indptr[k]));
    return RowsTarget{m.indptr.data(), m.indices.data(), m.data.data()};
  });
  return out;
}

void LimitSurface::position_blocks(
    const std::int32_t* face_ids, const double* uv, std::size_t k, detail::Scratch& scratch,
    const std::function<void(std::vector<std::int64_t>&& offsets, std::vector<std::int32_t>&& columns)>& start,
    const std::function<void(const PositionBlock&)>& visit) const {
  detail::Scratch::Frame frame(&scratch);
  double* const params = frame.take<double>(2 * k);
  checked_params(face_ids, uv, k, params);
  // The faces' blocks in increasing order of the face (the ids are checked), then the points with B's rows.
  const FaceSlots blocks = face_slots(face_ids, k, n_faces());
  const std::vector<std::int32_t>& face_block = blocks.slot;
  const std::vector<std::int32_t>& used = blocks.face;  // the faces' blocks' faces
  const std::size_t n_used = used.size();
  const std::vector<std::int32_t> slots = exact_corners(face_ids, params, k);
  const auto from_b = [&](std::size_t i) { return !slots.empty() && slots[i] >= 0; };
  const CsrMatrix& exact = impl_->exact.rows;
  const std::vector<std::int32_t>& from_osd = impl_->base.from_osd;
  {
    // Every block's columns: a face's control points (BfrSurfaces::columns; none where all its points have B's
    // rows, or where Bfr cannot build the face, for which face_stencils below throws), then B's rows'.
    std::vector<char> any_face_row(slots.empty() ? 0 : n_used, 0);
    for (std::size_t i = 0; i < slots.size(); ++i)
      if (!from_b(i)) any_face_row[static_cast<std::size_t>(face_block[static_cast<std::size_t>(face_ids[i])])] = 1;
    std::vector<const std::vector<std::int32_t>*> face_columns(n_used, nullptr);
    {
      const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
      const BfrSurfaces& factory = *impl_->factory;
      const int tasks = detail::task_count(n_used, kFacesPerColumnsTask);
      detail::for_each_index(tasks > 1, tasks, n_used, [&](std::size_t b) {
        if ((any_face_row.empty() || any_face_row[b]) && factory.get(used[b]) != nullptr)
          face_columns[b] = &factory.columns(used[b], from_osd);
      });
    }
    // The faces' columns placed by their offsets, copied on the core's threads.
    std::vector<std::int64_t> offsets(n_used + 1, 0);
    for (std::size_t b = 0; b < n_used; ++b)
      offsets[b + 1] = offsets[b] + static_cast<std::int64_t>(face_columns[b] ? face_columns[b]->size() : 0);
    std::vector<std::int32_t> columns(static_cast<std::size_t>(offsets[n_used]));
    const int tasks = detail::task_count(n_used, kFacesPerColumnsTask);
    detail::for_each_index(tasks > 1, tasks, n_used, [&](std::size_t b) {
      if (face_columns[b] != nullptr)
        std::copy(face_columns[b]->begin(), face_columns[b]->end(), columns.begin() + offsets[b]);
    });
    for (std::size_t i = 0; i < slots.size(); ++i)
      if (from_b(i)) {
        columns.insert(columns.end(), exact.indices.begin() + exact.indptr[slots[i]],
                       exact.indices.begin() + exact.indptr[slots[i] + 1]);
        offsets.push_back(static_cast<std::int64_t>(columns.size()));
      }
    start(std::move(offsets), std::move(columns));
  }
  {
    const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
    face_stencils(*impl_->factory, from_osd, face_ids, params, k, 0,
                  [&](int face, const std::size_t* first, const std::size_t* last, FaceStencils& s) {
                    PositionBlock b;
                    b.index = static_cast<std::size_t>(face_block[static_cast<std::size_t>(face)]);
                    b.columns = s.columns.data();
                    b.width = s.columns.size();
                    b.points = first;
                    b.count = static_cast<std::size_t>(last - first);
                    b.rows = s.weights[0].data();
                    thread_local std::vector<std::size_t> kept;
                    if (std::any_of(first, last, from_b)) {  // the face's other points (none: no columns, as start gave)
                      kept.clear();
                      for (const std::size_t* i = first; i != last; ++i) {
                        if (from_b(*i)) continue;
                        std::copy_n(&s.weights[0][static_cast<std::size_t>(i - first) * b.width], b.width,
                                    &s.weights[0][kept.size() * b.width]);
                        kept.push_back(*i);
                      }
                      b.points = kept.data();
                      b.count = kept.size();
                      if (kept.empty()) {
                        b.columns = nullptr;
                        b.width = 0;
                        b.rows = nullptr;
                      }
                    }
                    visit(b);
                  });
  }
  std::size_t next = n_used;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (!from_b(i)) continue;
    const std::int32_t b0 = exact.indptr[slots[i]], b1 = exact.indptr[slots[i] + 1];
    PositionBlock b;
    b.index = next++;
    b.columns = exact.indices.data() + b0;
    b.width = static_cast<std::size_t>(b1 - b0);
    b.points = &i;
    b.count = 1;
    b.rows = exact.data.data() + b0;
    visit(b);
  }
}

void LimitSurface::make_rows(const std::int32_t* face_ids, const double* uv, std::size_t k, int derivatives,
                             detail::Scratch& scratch, const RowsStore& store) const {
  if (derivatives < 0 || derivatives > 2)
    throw ParameterError("derivatives = " + std::to_string(derivatives) +
                         " must be 0 (positions), 1 (and first derivatives) or 2 (and second derivatives)");
  // The point's index among its face's points: in the caller's frame, as store's arrays, which the parameters'
  // frame (ended before store) leaves room for.
  std::size_t* const rank = scratch.take<std::size_t>(k);
  std::optional<detail::Scratch::Frame> params_frame(std::in_place, &scratch);
  double* const params = params_frame->take<double>(2 * k);
  checked_params(face_ids, uv, k, params);
  const int n_mats = derivatives == 0 ? 1 : derivatives == 1 ? 3 : 6;
  const std::vector<std::int32_t>& from_osd = impl_->base.from_osd;

  // Stencils per face of the points (the faces in increasing order) and each face's slot among them (the ids
  // are checked).
  const FaceSlots faces_used = face_slots(face_ids, k, n_faces());
  const std::vector<std::int32_t>& face_slot = faces_used.slot;
  std::vector<FaceStencils> stencils(faces_used.face.size());
  {
    const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
    face_stencils(*impl_->factory, from_osd, face_ids, params, k, derivatives,
                  [&](int face, const std::size_t* first, const std::size_t* last, FaceStencils& face_rows) {
                    for (const std::size_t* i = first; i != last; ++i) rank[*i] = static_cast<std::size_t>(i - first);
                    stencils[static_cast<std::size_t>(face_slot[static_cast<std::size_t>(face)])] =
                        std::move(face_rows);
                  });
  }

  // Points at the corner of a vertex whose position row is B's (see evaluate()).
  const std::vector<std::int32_t> slots = exact_corners(face_ids, params, k);
  params_frame.reset();
  const CsrMatrix& exact = impl_->exact.rows;
  // The rows are copied out in ranges of points, one per task.
  const int copy_tasks = detail::task_count(k, kRowsPerCopyTask);
  for (int d = 0; d < n_mats; ++d) {
    std::vector<std::int32_t> indptr(k + 1, 0);
    const auto stencil_of = [&](std::size_t i) -> const FaceStencils& {
      return stencils[static_cast<std::size_t>(face_slot[static_cast<std::size_t>(face_ids[i])])];
    };
    const auto from_b = [&](std::size_t i) { return d == 0 && !slots.empty() && slots[i] >= 0; };
    for (std::size_t i = 0; i < k; ++i) {
      const std::size_t width = from_b(i) ? static_cast<std::size_t>(exact.indptr[slots[i] + 1] - exact.indptr[slots[i]])
                                          : stencil_of(i).columns.size();
      if (width > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() - indptr[i]))
        throw ParameterError("rows: more than 2^31 - 1 weights in all; ask for fewer points at a time");
      indptr[i + 1] = indptr[i] + static_cast<std::int32_t>(width);
    }
    const RowsTarget to = store(d, std::move(indptr));
    detail::for_each_index(copy_tasks > 1, copy_tasks, k, [&](std::size_t i) {
      const auto at = static_cast<std::size_t>(to.indptr[i]);
      if (from_b(i)) {
        const std::int32_t b0 = exact.indptr[slots[i]], b1 = exact.indptr[slots[i] + 1];
        std::copy(exact.indices.begin() + b0, exact.indices.begin() + b1, to.indices + at);
        std::copy(exact.data.begin() + b0, exact.data.begin() + b1, to.data + at);
        return;
      }
      const FaceStencils& f = stencil_of(i);
      const std::size_t width = f.columns.size();
      std::copy(f.columns.begin(), f.columns.end(), to.indices + at);
      std::copy_n(f.weights[d].begin() + rank[i] * width, width, to.data + at);
    });
  }
}

FaceControlPoints LimitSurface::control_points(const std::int32_t* face_ids, std::size_t k) const {
  // The corner (0, 0) lies in every face's domain: the checks are evaluate()'s.
  const std::vector<double> corner(2 * k, 0.0);
  std::vector<double> params(2 * k);
  checked_params(face_ids, corner.data(), k, params.data());
  const std::vector<std::int32_t>& from_osd = impl_->base.from_osd;
  std::vector<std::vector<std::int32_t>> per_point(k);
  FaceControlPoints out;
  out.regular.assign(k, 0);
  {
    const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
    for_each_face_surface(
        *impl_->factory, face_ids, k,
        [&](const Bfr::Surface<double>& surface, int, const std::size_t* first, const std::size_t* last) {
          thread_local std::vector<int> cv;
          cv.resize(static_cast<std::size_t>(surface.GetNumControlPoints()));
          surface.GetControlPointIndices(cv.data());
          for (const std::size_t* i = first; i != last; ++i) {
            per_point[*i].resize(cv.size());
            for (std::size_t c = 0; c < cv.size(); ++c) per_point[*i][c] = from_osd[static_cast<std::size_t>(cv[c])];
            out.regular[*i] = static_cast<std::uint8_t>(surface.IsRegular());
          }
        });
  }
  out.offsets.assign(k + 1, 0);
  for (std::size_t i = 0; i < k; ++i)
    out.offsets[i + 1] = out.offsets[i] + static_cast<std::int64_t>(per_point[i].size());
  out.indices.resize(static_cast<std::size_t>(out.offsets[k]));
  for (std::size_t i = 0; i < k; ++i)
    std::copy(per_point[i].begin(), per_point[i].end(), out.indices.begin() + out.offsets[i]);
  return out;
}

// The output loops of tessellate() poll for an interrupt once per this many rows.
constexpr std::size_t kRowsPerPoll = std::size_t{1} << 16;

namespace {

// (u, v) of corner `corner` of face `face` of level `level` of a uniformly
// refined refiner, in the parameterisation of the control face it comes from
// (written to *control_face). Walks up the parent faces: child j of a face
// covers the part of its parent at the parent's corner j (Far's
// QuadRefinement and TriRefinement), an affine image of the child's own
// domain; every coordinate is dyadic, so the result is exact.
void refined_corner_uv(const Far::TopologyRefiner& refiner, const BfrSurfaces& factory, int level, int face,
                       int corner, int* control_face, double uv[2]) {
  const bool tri = refiner.GetSchemeType() == Sdc::SCHEME_LOOP;
  static constexpr double kSquare[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  static constexpr double kTriangle[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  if (level == 0) {
    factory.parameterization(face).GetVertexCoord(corner, uv);
    *control_face = face;
    return;
  }
  uv[0] = tri ? kTriangle[corner][0] : kSquare[corner][0];
  uv[1] = tri ? kTriangle[corner][1] : kSquare[corner][1];
  for (int l = level; l >= 1; --l) {
    const int parent = refiner.GetLevel(l).GetFaceParentFace(face);
    const auto children = refiner.GetLevel(l - 1).GetFaceChildFaces(parent);
    int j = 0;
    while (children[j] != face) ++j;
    // Images in the parent's domain of the child's local (0, 0), (1, 0), (0, 1).
    double a[2], b[2], d[2];
    const auto set = [](double* p, double x, double y) { p[0] = x, p[1] = y; };
    const auto mid = [](double* p, const double* x, const double* y) {
      p[0] = 0.5 * (x[0] + y[0]), p[1] = 0.5 * (x[1] + y[1]);
    };
    if (tri) {
      // Children 0..2 at the corners keep the corner first in place; child 3
      // is the middle one, (m1, m2, m0) with m_i the midpoint of edge i.
      static constexpr double kChild[4][3][2] = {{{0, 0}, {0.5, 0}, {0, 0.5}},
                                                 {{0.5, 0}, {1, 0}, {0.5, 0.5}},
                                                 {{0, 0.5}, {0.5, 0.5}, {0, 1}},
                                                 {{0.5, 0.5}, {0, 0.5}, {0.5, 0}}};
      set(a, kChild[j][0][0], kChild[j][0][1]);
      set(b, kChild[j][1][0], kChild[j][1][1]);
      set(d, kChild[j][2][0], kChild[j][2][1]);
    } else if (l - 1 > 0 || refiner.GetLevel(0).GetFaceVertices(parent).size() == 4) {
      // Child j of a quad lists the parent's corner j at its own position j,
      // then the midpoints of edges j, the centre and the midpoint of edge j - 1.
      const auto image = [&](int i, double* p) {
        const int r = (i - j + 4) % 4;
        const double* cj = kSquare[j];
        if (r == 0) set(p, cj[0], cj[1]);
        if (r == 1) mid(p, cj, kSquare[(j + 1) % 4]);
        if (r == 2) set(p, 0.5, 0.5);
        if (r == 3) mid(p, cj, kSquare[(j + 3) % 4]);
      };
      image(0, a);
      image(1, b);
      image(3, d);
    } else {
      // Child j of a k-gon (k != 4) is sub-face j, corner j first.
      double x[2];
      factory.parameterization(parent).GetVertexCoord(j, x);
      set(a, x[0], x[1]);
      set(b, x[0] + 0.5, x[1]);
      set(d, x[0], x[1] + 0.5);
    }
    const double u = uv[0], v = uv[1];
    uv[0] = a[0] + (b[0] - a[0]) * u + (d[0] - a[0]) * v;
    uv[1] = a[1] + (b[1] - a[1]) * u + (d[1] - a[1]) * v;
    face = parent;
  }
  *control_face = face;
}

bool semi_sharp(float sharpness) { return sharpness > 0.0f && sharpness < static_cast<float>(kInfiniteSharpness); }

// Vertices of `level` whose limit Far's Limit() on that level does not give:
// a vertex with a semi-sharp sharpness or edge (its rule changes on a later
// level) and, under Catmull-Clark, a vertex of a non-quad face (the limit mask
// takes a face's vertex two after the vertex as the opposite one).
std::vector<int> inexact_limit_vertices(const Far::TopologyRefiner& refiner, int level) {
  const auto& lv = refiner.GetLevel(level);
  const bool catmark = refiner.GetSchemeType() == Sdc::SCHEME_CATMARK;
  std::vector<int> out;
  for (int v = 0; v < lv.GetNumVertices(); ++v) {
    bool inexact = semi_sharp(lv.GetVertexSharpness(v));
    for (const int e : lv.GetVertexEdges(v)) inexact = inexact || semi_sharp(lv.GetEdgeSharpness(e));
    if (catmark)
      for (const int f : lv.GetVertexFaces(v)) inexact = inexact || lv.GetFaceVertices(f).size() != 4;
    if (inexact) out.push_back(v);
  }
  return out;
}

}  // namespace

Mesh LimitSurface::tessellate(int level) {
  if (level < 0 || level > 15)
    throw ParameterError("level must be in 0..15, got " + std::to_string(level));
  const Scheme scheme = impl_->scheme;
  const std::size_t n = n_vertices();
  const std::size_t m = n_faces();
  const auto n_face_vertices = static_cast<std::size_t>(impl_->base.refiner->GetLevel(0).GetNumFaceVertices());
  const double out_faces = tessellated_faces(scheme, m, n_face_vertices, level);
  if (out_faces > static_cast<double>(std::numeric_limits<std::int32_t>::max()))
    throw ParameterError("level " + std::to_string(level) + " would make " + face_words(scheme, out_faces, level) +
                         " from " + std::to_string(m) + ", more than int32 indices hold");
  const std::size_t need = tessellation_bytes(scheme, n, m, n_face_vertices, level);
  const std::size_t avail = available_memory_bytes();
  if (avail != 0 && need > avail)
    throw ParameterError("level " + std::to_string(level) + " makes " + face_words(scheme, out_faces, level) +
                         " and needs about " + human_bytes(static_cast<double>(need)) + ", but only " +
                         human_bytes(static_cast<double>(avail)) +
                         " of memory is available: use a lower level, or evaluate_limit at the points you need");
  const std::unique_lock<std::shared_mutex> lock(impl_->mutex);

  // Polls for an interrupt between the steps (OpenSubdiv's calls run whole).
  if (impl_->refined_level != level) {
    impl_->refined.reset();  // free the old one before building the new one
    // The topology was converted and checked once, for base: the refinement
    // shares its level 0. Limit() on the last level needs its full topology:
    // without it OpenSubdiv prints an error and leaves the output untouched.
    impl_->refined = std::make_unique<detail::UniformRefinement>(impl_->base, n, level, true);
    impl_->refined_level = level;
  }
  const detail::UniformRefinement& uniform = *impl_->refined;
  const Far::TopologyRefiner& refiner = uniform.refiner();
  Far::PrimvarRefinerReal<double> primvar(refiner);

  std::vector<Point3> src = impl_->points;
  uniform.interpolate(src);
  poll_interrupt();
  std::vector<Point3> limit(src.size());
  primvar.Limit(src, limit);
  poll_interrupt();
  std::vector<Point3>().swap(src);

  // Where Limit() is not the limit, Bfr evaluates the control faces' surface
  // at the vertex's parameter (exact at the corners of its refined patches).
  const auto& last = uniform.last();
  // Only semi-sharp tags, or Catmull-Clark's level 0 of a mesh with other
  // faces than quads, make such vertices: the common case skips the search.
  if (impl_->tags.max_semi_sharpness() > 0.0 ||
      (scheme == Scheme::CatmullClark && level == 0 && n_face_vertices != 4 * m)) {
    const std::vector<int> fix = inexact_limit_vertices(refiner, level);
    std::vector<int> fixed;
    std::vector<std::int32_t> face_ids;
    std::vector<double> params;
    for (const int v : fix) {
      const auto faces = last.GetVertexFaces(v);
      const auto corners = last.GetVertexFaceLocalIndices(v);
      int k = 0;
      while (k < faces.size() && last.IsFaceHole(faces[k])) ++k;
      if (k == faces.size()) continue;  // only in holes: no face shows it
      int control_face = 0;
      double uv[2];
      refined_corner_uv(refiner, *impl_->factory, level, faces[k], corners[k], &control_face, uv);
      // Bfr cannot evaluate there (Impl::bfr_unsafe): Limit() at this level stays.
      if (!impl_->bfr_unsafe.empty() && impl_->bfr_unsafe[control_face] >= 0) continue;
      fixed.push_back(v);
      face_ids.push_back(control_face);
      params.insert(params.end(), uv, uv + 2);
    }
    std::vector<double> p(3 * fixed.size());
    evaluate_points(*impl_->factory, &impl_->points.data()->x, face_ids.data(), params.data(), fixed.size(),
                    p.data(), nullptr, nullptr, nullptr);
    for (std::size_t i = 0; i < fixed.size(); ++i) limit[fixed[i]] = Point3{p[3 * i], p[3 * i + 1], p[3 * i + 2]};
  }

  // The first n_osd vertices of the level descend from the control vertices
  // (UniformRefinement::fine_index): they are B V; the others follow.
  const std::size_t n_osd = uniform.n_osd();
  const auto n_level = static_cast<std::size_t>(last.GetNumVertices());
  const std::size_t n_out = uniform.n_fine_vertices();
  Mesh out;
  out.vertices.resize(3 * n_out);
  // Control vertices: B V exactly as sorpia::limit_points computes it (one
  // B; the refined level gives the same points up to rounding, except at the
  // few vertices whose Sdc limit mask is not the limit of their refinement,
  // darts and Catmull-Clark's interior vertices of two faces).
  apply(limit_operator(impl_->topology, Rules{scheme, impl_->boundary, impl_->tags}), impl_->vertices.data(),
        out.vertices.data());
  for (std::size_t i = n_osd; i < n_level; ++i) {
    if (i % kRowsPerPoll == 0) poll_interrupt();
    double* q = &out.vertices[3 * static_cast<std::size_t>(uniform.fine_index(static_cast<int>(i)))];
    q[0] = limit[i].x;
    q[1] = limit[i].y;
    q[2] = limit[i].z;
  }
  std::vector<Point3>().swap(limit);

  const auto n_faces_level = static_cast<std::size_t>(last.GetNumFaces());
  out.face_vertex_counts.reserve(n_faces_level);
  out.face_vertex_indices.reserve(static_cast<std::size_t>(last.GetNumFaceVertices()));
  for (std::size_t f = 0; f < n_faces_level; ++f) {
    if (f % kRowsPerPoll == 0) poll_interrupt();
    if (last.IsFaceHole(static_cast<int>(f))) continue;
    const auto fv = last.GetFaceVertices(static_cast<int>(f));
    out.face_vertex_counts.push_back(fv.size());
    for (int c = 0; c < fv.size(); ++c) out.face_vertex_indices.push_back(uniform.fine_index(fv[c]));
  }
  return out;
}

}  // namespace sorpia
