#include "sorpia/surface.hpp"

#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/bfr/surfaceFactoryCache.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <mutex>
#include <numeric>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include "parallel.hpp"
#include "osd_refiner.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

namespace {

namespace Bfr = OpenSubdiv::Bfr;
namespace Far = OpenSubdiv::Far;

// A thread-safe cache lets every thread of evaluate() share one factory (irregular
// patches are built once per distinct vertex neighbourhood, then reused).
using ThreadedCache = Bfr::SurfaceFactoryCacheThreaded<std::shared_mutex, std::shared_lock<std::shared_mutex>,
                                                       std::unique_lock<std::shared_mutex>>;
using SurfaceFactory = Bfr::RefinerSurfaceFactory<ThreadedCache>;

using detail::Point3;

// Bytes per refined face held by a uniformly refined Loop TopologyRefiner
// with full topology (all levels together, ~4/3 of the last level) and the
// position buffers, for the memory check before a tessellation;
// bench/io_speed.py prints the peak it measures beside this estimate.
constexpr double kRefinerBytesPerFace = 220.0;

std::string human_bytes(double b) {
  char buf[64];
  if (b >= 1e9)
    std::snprintf(buf, sizeof buf, "%.1f GB", b / 1e9);
  else
    std::snprintf(buf, sizeof buf, "%.0f MB", b / 1e6);
  return buf;
}

constexpr int kApproxLevelSmooth = 4;

// Faces per chunk that a thread takes at a time in evaluate(); also the least
// work per thread.
constexpr std::ptrdiff_t kFacesPerChunk = 64;

// Threads for `n_groups` faces: no more than there are chunks, so a small
// query runs on the calling thread alone, and no more than the processors.
int evaluate_threads(std::ptrdiff_t n_groups) {
  const std::ptrdiff_t chunks = (n_groups + kFacesPerChunk - 1) / kFacesPerChunk;
  return static_cast<int>(
      std::max<std::ptrdiff_t>(1, std::min<std::ptrdiff_t>(detail::available_processors(), chunks)));
}

// Bfr evaluates on the closed triangle; a parameter a rounding error outside is
// pulled back onto it, anything further out is refused.
constexpr double kUvSlack = 1e-12;

}  // namespace

std::size_t tessellation_bytes(std::size_t n_vertices, std::size_t n_faces, int level) {
  const double grow = std::pow(4.0, level);
  const double faces = static_cast<double>(n_faces) * grow;
  const double verts = static_cast<double>(n_vertices) + faces / 2.0 + 2.0 * static_cast<double>(n_faces);
  // refiner (every level) + output arrays: vertices (24 B) and faces (12 B),
  // each held twice while the Python layer copies them.
  const double bytes = faces * kRefinerBytesPerFace + 2.0 * (24.0 * verts + 12.0 * faces);
  return bytes >= static_cast<double>(std::numeric_limits<std::size_t>::max())
             ? std::numeric_limits<std::size_t>::max()
             : static_cast<std::size_t>(bytes);
}

struct LoopSurface::Impl {
  Topology topology;
  Boundary boundary;
  detail::Refiner base;               // unrefined: Bfr and the limit positions of control vertices
  std::unique_ptr<SurfaceFactory> factory;
  std::vector<double> vertices;       // (n, 3), as given
  std::vector<Point3> points;         // referenced vertices in OpenSubdiv's order
  // Uniformly refined to refined_level (built on demand); shares base's level
  // 0 (Far::TopologyRefinerFactory::Create), so it is declared after base and
  // destroyed before it.
  std::unique_ptr<Far::TopologyRefiner> refined;
  int refined_level = -1;
  // The Python binding releases the GIL: evaluate() may run in several
  // threads at once, set_vertices() and tessellate() change state.
  mutable std::shared_mutex mutex;

  Impl(const Topology& t, Boundary b) : topology(t), boundary(b), base(detail::make_refiner(t, Scheme::Loop, b)) {}
};

namespace {

// v scaled by a power of two (exactly) so that its largest component lies in
// [0.5, 1): products and squares of such vectors neither overflow nor underflow.
void scale_to_unit(const double* v, double* out) {
  const double m = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])});
  int e = 0;
  if (m > 0.0 && std::isfinite(m)) std::frexp(m, &e);
  for (int c = 0; c < 3; ++c) out[c] = std::ldexp(v[c], -e);
}

// The unit normal du x dv / |du x dv| at any scale of the coordinates (the
// plain formula squares the cross product: it overflows from about 1e77 and
// underflows below about 1e-77); zero where du and dv are parallel or zero.
void unit_normal(const double* du, const double* dv, double* out) {
  double a[3], b[3], n[3], u[3];
  scale_to_unit(du, a);
  scale_to_unit(dv, b);
  n[0] = a[1] * b[2] - a[2] * b[1];
  n[1] = a[2] * b[0] - a[0] * b[2];
  n[2] = a[0] * b[1] - a[1] * b[0];
  scale_to_unit(n, u);
  const double len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int c = 0; c < 3; ++c) out[c] = len > 0.0 ? u[c] / len : 0.0;
}

}  // namespace

LoopSurface::LoopSurface(const Topology& topology, const double* vertices, Boundary boundary)
    : impl_(std::make_unique<Impl>(topology, boundary)) {
  Bfr::SurfaceFactory::Options options;
  // Bfr represents the surface next to an extraordinary vertex by Gregory
  // triangles after this many local refinements (default 2): 4 shrinks that
  // region to the corner triangles of side 1/16, where OpenSubdiv's derivatives
  // are approximate (it drops the derivative of the rational Gregory weights),
  // at a small cost in evaluation time.
  options.SetApproxLevelSmooth(kApproxLevelSmooth);
  impl_->factory = std::make_unique<SurfaceFactory>(*impl_->base.refiner, options);
  set_vertices(vertices);
}

LoopSurface::~LoopSurface() = default;
LoopSurface::LoopSurface(LoopSurface&&) noexcept = default;
LoopSurface& LoopSurface::operator=(LoopSurface&&) noexcept = default;

std::size_t LoopSurface::n_vertices() const { return impl_->topology.n_vertices(); }
std::size_t LoopSurface::n_faces() const { return impl_->topology.n_faces(); }
Boundary LoopSurface::boundary() const { return impl_->boundary; }

void LoopSurface::set_vertices(const double* vertices) {
  const std::unique_lock<std::shared_mutex> lock(impl_->mutex);
  const std::size_t n = n_vertices();
  impl_->vertices.assign(vertices, vertices + 3 * n);
  detail::gather_points(impl_->base, vertices, impl_->points);
}

void LoopSurface::get_vertices(double* out) const {
  const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
  std::copy(impl_->vertices.begin(), impl_->vertices.end(), out);
}

void LoopSurface::evaluate(const std::int32_t* face_ids, const double* uv, std::size_t k, double* positions,
                           double* du, double* dv, double* normals) const {
  const std::size_t n_f = n_faces();
  std::vector<double> params(uv, uv + 2 * k);
  for (std::size_t i = 0; i < k; ++i) {
    if (face_ids[i] < 0 || static_cast<std::size_t>(face_ids[i]) >= n_f)
      throw ParameterError("face_ids[" + std::to_string(i) + "] = " + std::to_string(face_ids[i]) +
                           " is out of range [0, " + std::to_string(n_f) + ")");
    double& u = params[2 * i];
    double& v = params[2 * i + 1];
    if (!(u >= -kUvSlack && v >= -kUvSlack && u + v <= 1.0 + kUvSlack))
      throw ParameterError("uv[" + std::to_string(i) + "] = (" + std::to_string(u) + ", " + std::to_string(v) +
                           ") is outside the triangle u >= 0, v >= 0, u + v <= 1");
    u = std::max(u, 0.0);
    v = std::max(v, 0.0);
    if (u + v > 1.0) {
      const double s = u + v;
      u /= s;
      v /= s;
    }
  }
  // Group the points by face so that each face's surface is built once.
  std::vector<std::size_t> order(k);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return face_ids[a] < face_ids[b]; });
  std::vector<std::size_t> group_start;
  for (std::size_t j = 0; j < k; ++j)
    if (j == 0 || face_ids[order[j]] != face_ids[order[j - 1]]) group_start.push_back(j);
  group_start.push_back(k);
  const auto n_groups = static_cast<std::ptrdiff_t>(group_start.size()) - 1;

  const SurfaceFactory& factory = *impl_->factory;
  const bool want_derivs = du || dv || normals;
  const std::shared_lock<std::shared_mutex> lock(impl_->mutex);
  const double* mesh_points = &impl_->points.data()->x;
  std::atomic<int> failed_face{-1};
  // Each point is computed alone, so the thread count changes nothing in the
  // results. Chunks of faces are handed out in turn (their costs differ).
  std::atomic<std::ptrdiff_t> next_chunk{0};
  std::atomic<bool> stop{false};
  const int threads = evaluate_threads(n_groups);
  detail::for_each_task(threads > 1, threads, [&](int) {
    Bfr::Surface<double> surface;
    std::vector<double> patch;
    const Bfr::Surface<double>::PointDescriptor desc(3);
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
        if (!factory.InitVertexSurface(face, &surface)) {
          failed_face = face;
          continue;
        }
        patch.resize(3 * static_cast<std::size_t>(surface.GetNumPatchPoints()));
        surface.PreparePatchPoints(mesh_points, desc, patch.data(), desc);
        for (std::size_t j = group_start[g]; j < group_start[g + 1]; ++j) {
          const std::size_t i = order[j];
          double p[3], d1[3], d2[3];
          if (want_derivs)
            surface.Evaluate(&params[2 * i], patch.data(), desc, p, d1, d2);
          else
            surface.Evaluate(&params[2 * i], patch.data(), desc, p);
          std::copy(p, p + 3, positions + 3 * i);
          if (du) std::copy(d1, d1 + 3, du + 3 * i);
          if (dv) std::copy(d2, d2 + 3, dv + 3 * i);
          if (normals) unit_normal(d1, d2, normals + 3 * i);
        }
      }
    }
  });
  if (failed_face >= 0)
    throw MeshError("OpenSubdiv's Bfr could not build the limit surface of face " + std::to_string(failed_face.load()));
}

// The output loops of tessellate() poll for an interrupt once per this many rows.
constexpr std::size_t kRowsPerPoll = std::size_t{1} << 16;

TriMesh LoopSurface::tessellate(int level) {
  if (level < 0 || level > 15)
    throw ParameterError("level must be in 0..15, got " + std::to_string(level));
  const std::size_t n = n_vertices();
  const std::size_t m = n_faces();
  const double out_faces = static_cast<double>(m) * std::pow(4.0, level);
  if (out_faces > static_cast<double>(std::numeric_limits<std::int32_t>::max()))
    throw ParameterError("level " + std::to_string(level) + " would make " + std::to_string(out_faces) +
                         " triangles from " + std::to_string(m) + " (4^level per face), more than int32 indices hold");
  const std::size_t need = tessellation_bytes(n, m, level);
  const std::size_t avail = available_memory_bytes();
  if (avail != 0 && need > avail)
    throw ParameterError("level " + std::to_string(level) + " makes " + std::to_string(static_cast<long long>(out_faces)) +
                         " triangles (4^level per face) and needs about " + human_bytes(static_cast<double>(need)) +
                         ", but only " + human_bytes(static_cast<double>(avail)) +
                         " of memory is available: use a lower level, or evaluate_limit at the points you need");
  const std::unique_lock<std::shared_mutex> lock(impl_->mutex);

  // Polls for an interrupt between the steps (OpenSubdiv's calls run whole).
  if (impl_->refined_level != level) {
    impl_->refined.reset();  // free the old one before building the new one
    // The topology was converted and checked once, for base: share its level 0.
    impl_->refined.reset(Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Create(*impl_->base.refiner));
    if (level > 0) {
      Far::TopologyRefiner::UniformOptions options(level);
      // Limit() on the last level needs its full topology: without it
      // OpenSubdiv prints an error and leaves the output untouched.
      options.fullTopologyInLastLevel = true;
      poll_interrupt();
      impl_->refined->RefineUniform(options);
    }
    impl_->refined_level = level;
  }
  const Far::TopologyRefiner& refiner = *impl_->refined;
  Far::PrimvarRefinerReal<double> primvar(refiner);

  std::vector<Point3> src = impl_->points, dst;
  for (int l = 1; l <= level; ++l) {
    poll_interrupt();
    dst.resize(static_cast<std::size_t>(refiner.GetLevel(l).GetNumVertices()));
    primvar.Interpolate(l, src, dst);
    std::swap(src, dst);
  }
  poll_interrupt();
  std::vector<Point3> limit(src.size());
  primvar.Limit(src, limit);
  poll_interrupt();
  std::vector<Point3>().swap(src);

  // Refined vertices are ordered children of vertices first
  // (orderVerticesFromFacesFirst = false), so the first n_osd of every level
  // descend from the control vertices, in order.
  const auto& from = impl_->base.from_osd;
  const std::size_t n_osd = from.size();
  const std::size_t n_out = n + (limit.size() - n_osd);
  TriMesh out;
  out.vertices.resize(3 * n_out);
  // Control vertices: B V exactly as sorpia::limit_points computes it (the
  // refined level gives the same point up to rounding).
  limit_points(impl_->topology, impl_->vertices.data(), impl_->boundary, out.vertices.data());
  for (std::size_t i = n_osd; i < limit.size(); ++i) {
    if (i % kRowsPerPoll == 0) poll_interrupt();
    double* q = &out.vertices[3 * (n + i - n_osd)];
    q[0] = limit[i].x;
    q[1] = limit[i].y;
    q[2] = limit[i].z;
  }
  const auto& last = refiner.GetLevel(level);
  const auto n_faces_out = static_cast<std::size_t>(last.GetNumFaces());
  out.faces.resize(3 * n_faces_out);
  const auto to_out = [&](int i) {
    return static_cast<std::int32_t>(static_cast<std::size_t>(i) < n_osd ? static_cast<std::size_t>(from[i])
                                                                         : n + static_cast<std::size_t>(i) - n_osd);
  };
  for (std::size_t f = 0; f < n_faces_out; ++f) {
    if (f % kRowsPerPoll == 0) poll_interrupt();
    const auto fv = last.GetFaceVertices(static_cast<int>(f));
    for (int c = 0; c < 3; ++c) out.faces[3 * f + c] = to_out(fv[c]);
  }
  return out;
}

}  // namespace sorpia
