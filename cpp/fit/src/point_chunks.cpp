#include "sorpia/point_chunks.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <time.h>
#include <utility>
#include <vector>

#include "sorpia/detail/clock.hpp"
#include "sorpia/detail/pairwise.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/detail/repr.hpp"
#include "sorpia/detail/spatial.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"

namespace sorpia {

namespace {

// The iterations' re-projection (ApproximationChunk::refine) stops a point at a step below this in (u, v) where
// its distance is exact to 1e-6 relatively (FootpointOptions::uv_tolerance): its footpoint only drives the next
// update, whose rows move by first order in it (about 1e-5 of a face's size, far below a fit's distances), and the
// distances reported come from FootpointSearch::closer's re-search, polished to rounding.
constexpr double kIterationUvTolerance = 1e-5;
// Points (or values) per task, at least, of a chunk's loops over its points that are a few operations each.
constexpr std::size_t kValuesPerTask = 65536;

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

ApproximationChunk::State from_footpoints(Footpoints&& f) {
  ApproximationChunk::State s;
  s.face_ids = std::move(f.face_ids);
  s.uv = std::move(f.uv);
  s.distances = std::move(f.distances);
  s.normals = std::move(f.normals);
  return s;
}

}  // namespace

void add(DistanceSums& total, const DistanceSums& chunk) {
  total.squares += chunk.squares;
  total.max = std::max(total.max, chunk.max);
  total.count += chunk.count;
  total.changed += chunk.changed;
}

void add(PointExtent& total, const PointExtent& chunk) {
  if (chunk.count == 0) return;
  for (int c = 0; chunk.weighted > 0 && c < 3; ++c) {  // the box of the points that count
    total.lo[c] = total.weighted == 0 ? chunk.lo[c] : std::min(total.lo[c], chunk.lo[c]);
    total.hi[c] = total.weighted == 0 ? chunk.hi[c] : std::max(total.hi[c], chunk.hi[c]);
  }
  total.largest = std::max(total.largest, chunk.largest);
  total.count += chunk.count;
  total.weighted += chunk.weighted;
}

void add(PointMoments& total, const PointMoments& chunk) {
  total.count += chunk.count;
  for (int c = 0; c < 3; ++c) total.sum[c] += chunk.sum[c];
  for (int c = 0; c < 9; ++c) total.sum2[c] += chunk.sum2[c];
}

void add(NormalSums& total, NormalSums&& chunk) {
  const double rows_seconds = total.rows_seconds + chunk.rows_seconds, rows_cpu = total.rows_cpu + chunk.rows_cpu;
  if (total.matrix.indptr.empty()) {
    total = std::move(chunk);
  } else {
    NormalMatrix& a = total.matrix;
    const NormalMatrix& b = chunk.matrix;
    if (a.n != b.n || a.blocks != b.blocks || chunk.rhs.size() != total.rhs.size())
      throw ParameterError("normal sums of " + std::to_string(b.n) + " vertices and " + std::to_string(b.blocks) +
                           " values per entry cannot be added to " + std::to_string(a.n) + " and " +
                           std::to_string(a.blocks));
    for (std::size_t i = 0; i < total.rhs.size(); ++i) total.rhs[i] += chunk.rhs[i];
    const auto nb = static_cast<std::size_t>(a.blocks);
    // Where every entry of the chunk's pattern is in the total's (as soon as the chunks added cover the cage's
    // faces), its values are added in place; else the patterns are merged.
    bool within = true;
    for (std::size_t i = 0; i < a.n && within; ++i) {
      auto p = static_cast<std::size_t>(a.indptr[i]);
      const auto pe = static_cast<std::size_t>(a.indptr[i + 1]);
      for (auto q = static_cast<std::size_t>(b.indptr[i]); q < static_cast<std::size_t>(b.indptr[i + 1]); ++q) {
        while (p < pe && a.indices[p] < b.indices[q]) ++p;
        if (p == pe || a.indices[p] != b.indices[q]) {
          within = false;
          break;
        }
      }
    }
    if (within) {
      for (std::size_t i = 0; i < a.n; ++i) {
        auto p = static_cast<std::size_t>(a.indptr[i]);
        for (auto q = static_cast<std::size_t>(b.indptr[i]); q < static_cast<std::size_t>(b.indptr[i + 1]); ++q) {
          while (a.indices[p] < b.indices[q]) ++p;
          for (std::size_t t = 0; t < nb; ++t) a.values[nb * p + t] += b.values[nb * q + t];
        }
      }
      total.rows_seconds = rows_seconds;
      total.rows_cpu = rows_cpu;
      return;
    }
    NormalMatrix m;
    m.n = a.n;
    m.blocks = a.blocks;
    m.indptr.assign(a.n + 1, 0);
    m.indices.reserve(std::max(a.indices.size(), b.indices.size()));
    m.values.reserve(nb * std::max(a.indices.size(), b.indices.size()));
    for (std::size_t i = 0; i < a.n; ++i) {
      auto p = static_cast<std::size_t>(a.indptr[i]);
      auto q = static_cast<std::size_t>(b.indptr[i]);
      const auto pe = static_cast<std::size_t>(a.indptr[i + 1]), qe = static_cast<std::size_t>(b.indptr[i + 1]);
      while (p < pe || q < qe) {
        const std::int32_t ja = p < pe ? a.indices[p] : INT32_MAX, jb = q < qe ? b.indices[q] : INT32_MAX;
        if (ja == jb) {
          m.indices.push_back(ja);
          for (std::size_t t = 0; t < nb; ++t) m.values.push_back(a.values[nb * p + t] + b.values[nb * q + t]);
          ++p;
          ++q;
        } else if (ja < jb) {
          m.indices.push_back(ja);
          m.values.insert(m.values.end(), a.values.begin() + static_cast<std::ptrdiff_t>(nb * p),
                          a.values.begin() + static_cast<std::ptrdiff_t>(nb * (p + 1)));
          ++p;
        } else {
          m.indices.push_back(jb);
          m.values.insert(m.values.end(), b.values.begin() + static_cast<std::ptrdiff_t>(nb * q),
                          b.values.begin() + static_cast<std::ptrdiff_t>(nb * (q + 1)));
          ++q;
        }
      }
      m.indptr[i + 1] = static_cast<std::int64_t>(m.indices.size());
    }
    total.matrix = std::move(m);
  }
  total.rows_seconds = rows_seconds;
  total.rows_cpu = rows_cpu;
}

// ---------------------------------------------------------------------------------------------------------------
// ApproximationChunk

ApproximationChunk::ApproximationChunk(const double* points, std::size_t k, const double* weights, std::size_t first)
    : k_(k), first_(first), points_(points, points + 3 * k) {
  if (weights) weights_.assign(weights, weights + k);
  arrange();
}

void ApproximationChunk::set_points(std::vector<double> points, std::vector<double> weights) {
  if (points.size() != 3 * k_ || (!weights.empty() && weights.size() != k_))
    throw ParameterError("a chunk of " + std::to_string(k_) + " points was given " +
                         std::to_string(points.size() / 3) + " points");
  points_ = std::move(points);
  weights_ = std::move(weights);
  arrange();
}

void ApproximationChunk::arrange() {
  order_.clear();
  if (k_ < 2 || k_ > std::numeric_limits<std::uint32_t>::max()) return;
  for (const double v : points_)
    if (!std::isfinite(v)) return;
  const std::vector<std::size_t> order = detail::spatial_order(points_.data(), k_);
  std::vector<double> points(3 * k_), weights(weights_.size());
  order_.resize(k_);
  const int tasks = detail::task_count(k_, 65536);
  detail::for_each_index(tasks > 1, tasks, k_, [&](std::size_t i) {
    const std::size_t j = order[i];
    order_[i] = static_cast<std::uint32_t>(j);
    std::copy_n(&points_[3 * j], 3, &points[3 * i]);
    if (!weights.empty()) weights[i] = weights_[j];
  });
  points_ = std::move(points);
  weights_ = std::move(weights);
}

PointExtent ApproximationChunk::extent() const {
  PointExtent e;
  // (Points not all finite are as given: arrange() leaves them.)
  for (std::size_t i = 0; i < 3 * k_; ++i)
    if (!std::isfinite(points_[i])) throw MeshError("points[" + std::to_string(first_ + i / 3) + "] is not finite");
  // The first weight as given that is wrong.
  std::size_t bad = k_;
  for (std::size_t i = 0; i < weights_.size(); ++i)
    if (!(std::isfinite(weights_[i]) && weights_[i] >= 0) && (bad == k_ || given(i) < given(bad))) bad = i;
  if (bad < k_)
    throw ParameterError("weights[" + std::to_string(first_ + given(bad)) + "] = " + detail::repr(weights_[bad]) +
                         " must be a finite number >= 0");
  e.count = k_;
  if (k_ == 0) return e;
  e.weighted = weights_.empty() ? k_ : static_cast<std::size_t>(std::count_if(
                                           weights_.begin(), weights_.end(), [](double w) { return w > 0; }));
  bool first = true;
  for (std::size_t i = 0; i < k_; ++i) {
    for (std::size_t c = 0; c < 3; ++c) e.largest = std::max(e.largest, std::abs(points_[3 * i + c]));
    if (!counts(i)) continue;  // a point of weight 0 is no data: outside the box (it is still scaled)
    for (std::size_t c = 0; c < 3; ++c) {
      const double v = points_[3 * i + c];
      e.lo[c] = first ? v : std::min(e.lo[c], v);
      e.hi[c] = first ? v : std::max(e.hi[c], v);
    }
    first = false;
  }
  return e;
}

void ApproximationChunk::scale(int e) {
  for (double& v : points_) v = std::ldexp(v, -e);
}

PointMoments ApproximationChunk::moments(const double center[3], double diagonal) const {
  PointMoments m;
  for (std::size_t i = 0; i < k_; ++i) {
    if (!counts(i)) continue;
    ++m.count;
    double d[3];
    for (std::size_t c = 0; c < 3; ++c) d[c] = (points_[3 * i + c] - center[c]) / diagonal;
    for (int r = 0; r < 3; ++r) {
      m.sum[r] += d[r];
      for (int c = 0; c < 3; ++c) m.sum2[3 * r + c] += d[r] * d[c];
    }
  }
  return m;
}

double ApproximationChunk::line_offset(const double mean[3], const double axis[3], double diagonal) const {
  double off = 0.0;
  for (std::size_t i = 0; i < k_; ++i) {
    if (!counts(i)) continue;
    double d[3];
    for (std::size_t c = 0; c < 3; ++c) d[c] = (points_[3 * i + c] - mean[c]) / diagonal;
    const double along = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
    double r2 = 0.0;
    for (int c = 0; c < 3; ++c) r2 += (d[c] - along * axis[c]) * (d[c] - along * axis[c]);
    off = std::max(off, std::sqrt(r2));
  }
  return off;
}

DistanceSums ApproximationChunk::sums(const std::vector<double>& d, detail::Scratch* scratch) const {
  DistanceSums s;
  s.count = k_;
  if (k_ == 0) return s;
  detail::Scratch::Frame frame(scratch);
  double* const squares = frame.take<double>(k_);
  const int tasks = detail::task_count(k_, kValuesPerTask);
  const auto t_count = static_cast<std::size_t>(tasks);
  s.max = detail::max_over_tasks(tasks > 1, tasks, [&](int t) {
    const auto r = static_cast<std::size_t>(t);
    double most = 0.0;
    for (std::size_t i = k_ * r / t_count; i < k_ * (r + 1) / t_count; ++i) {
      squares[i] = weights_.empty() ? d[i] * d[i] : weights_[i] * (d[i] * d[i]);
      if (counts(i)) most = std::max(most, d[i]);
    }
    return most;
  });
  s.squares = detail::pairwise_sum(squares, k_);
  return s;
}

DistanceSums ApproximationChunk::search(const FootpointSearch& search, detail::Scratch* scratch) {
  current = from_footpoints(search.find(points_.data(), k_, scratch));
  return sums(current.distances, scratch);
}

DistanceSums ApproximationChunk::refine(const LimitSurface& surface, const FootpointOptions& options,
                                        detail::Scratch* scratch) {
  Footpoints from;
  from.face_ids = std::move(current.face_ids);
  from.uv = std::move(current.uv);
  from.distances = std::move(current.distances);  // written in place
  from.normals = std::move(current.normals);
  FootpointOptions refine = options;
  refine.grid = 0;
  refine.uv_tolerance = kIterationUvTolerance;
  refine_footpoints(surface, surface.topology(), points_.data(), k_, refine, from, scratch);
  current = from_footpoints(std::move(from));
  return sums(current.distances, scratch);
}

void ApproximationChunk::keep_best() {
  detail::copy_in_ranges(current.face_ids, best.face_ids, kValuesPerTask);
  detail::copy_in_ranges(current.uv, best.uv, kValuesPerTask);
  detail::copy_in_ranges(current.distances, best.distances, kValuesPerTask);
}

DistanceSums ApproximationChunk::search_fresh(const FootpointSearch& search, double closer) {
  // From the current footpoints (of the search's surface), every start that may lie near a closer point: the
  // grid's nearest sample and the samples of the candidates' bound, less those the certificate leaves out
  // (FootpointSearch::closer).
  Footpoints from;
  from.face_ids = current.face_ids;
  from.uv = current.uv;
  from.distances = current.distances;
  from.normals = current.normals;
  search.closer(points_.data(), k_, from, false);
  fresh = from_footpoints(std::move(from));
  std::vector<double> merged(k_);
  for (std::size_t i = 0; i < k_; ++i)
    merged[i] = fresh.distances[i] < current.distances[i] - closer ? fresh.distances[i] : current.distances[i];
  return sums(merged);
}

DistanceSums ApproximationChunk::refine_fresh(const FootpointSearch& search) {
  Footpoints from;
  from.face_ids = std::move(current.face_ids);
  from.uv = std::move(current.uv);
  from.normals = std::move(current.normals);  // written in place
  from.distances.assign(k_, std::numeric_limits<double>::infinity());  // (face, u, v) as starts only
  search.closer(points_.data(), k_, from, false);
  fresh = from_footpoints(std::move(from));
  current = fresh;
  return sums(current.distances);
}

void ApproximationChunk::keep_fresh(double closer) {
  for (std::size_t i = 0; i < k_; ++i)
    if (fresh.distances[i] < current.distances[i] - closer) {
      current.face_ids[i] = fresh.face_ids[i];
      current.distances[i] = fresh.distances[i];
      for (std::size_t c = 0; c < 2; ++c) current.uv[2 * i + c] = fresh.uv[2 * i + c];
      for (std::size_t c = 0; c < 3; ++c) current.normals[3 * i + c] = fresh.normals[3 * i + c];
    }
  fresh = State{};
}

DistanceSums ApproximationChunk::keep_fresh_in_best() {
  std::size_t changed = 0;
  for (std::size_t i = 0; i < k_; ++i)
    if (fresh.distances[i] < best.distances[i]) {
      best.face_ids[i] = fresh.face_ids[i];
      best.uv[2 * i] = fresh.uv[2 * i];
      best.uv[2 * i + 1] = fresh.uv[2 * i + 1];
      best.distances[i] = fresh.distances[i];
      ++changed;
    }
  DistanceSums s = sums(best.distances);
  s.changed = changed;
  return s;
}

NormalSums ApproximationChunk::normal_sums(const LimitSurface& surface, double tangential,
                                           const RobustOptions* robust, double scale,
                                           detail::Scratch* scratch) const {
  const std::size_t k = k_;
  const bool weighted = !weights_.empty() || robust != nullptr;
  detail::Scratch::Frame frame(scratch);
  double* factors = nullptr;  // the robust factors of the points' weights, in point order
  if (robust) {
    factors = frame.take<double>(k);
    robust_factors(*robust, scale, current.distances.data(), k, factors);
  }
  const bool blend = tangential != 1.0;
  const int weight_count = blend ? 6 : weighted ? 1 : 0;
  NormalSums out;
  const auto t0 = detail::Clock::now();
  const double c0 = cpu_seconds();
  const std::size_t n_faces = surface.n_faces();
  detail::check_each_index(k, kValuesPerTask, [&](std::size_t i) {
    const std::int32_t f = current.face_ids[i];
    if (f < 0 || static_cast<std::size_t>(f) >= n_faces)
      throw ParameterError("face_ids[" + std::to_string(first_ + given(i)) + "] = " + std::to_string(f) +
                           " is out of range [0, " + std::to_string(n_faces) + ")");
  });
  // Each block of rows (a face's points) is weighted and multiplied out where it is made, in the cache, and added
  // into the pattern of the blocks' columns in the blocks' order (NormalBlocks).
  std::unique_ptr<NormalBlocks> blocks;
  std::shared_ptr<const NormalPattern> pattern = std::atomic_load(&normal_pattern_);
  surface.position_blocks(
      current.face_ids.data(), current.uv.data(), k, frame.scratch(),
      [&](std::vector<std::int64_t>&& offsets, std::vector<std::int32_t>&& columns) {
        blocks = std::make_unique<NormalBlocks>(surface.n_vertices(), weight_count, std::move(offsets),
                                                std::move(columns), &pattern);
        std::atomic_store(&normal_pattern_, pattern);
      },
      [&](const PositionBlock& b) {
        // The block's points, weights and weighted points (W p), in the block's order.
        thread_local std::vector<double> p, w, normals, w6, wp;
        const std::size_t m = b.count;
        p.resize(3 * m);
        w.resize(weighted ? m : 0);
        normals.resize(blend ? 3 * m : 0);
        w6.resize(blend ? 6 * m : 0);
        wp.resize(3 * m);
        for (std::size_t j = 0; j < m; ++j) {
          const std::size_t o = b.points[j];
          for (std::size_t c = 0; c < 3; ++c) p[3 * j + c] = points_[3 * o + c];
          if (weighted) w[j] = (weights_.empty() ? 1.0 : weights_[o]) * (robust ? factors[o] : 1.0);
          if (blend)
            for (std::size_t c = 0; c < 3; ++c) normals[3 * j + c] = current.normals[3 * o + c];
        }
        if (blend)
          blend_weights(p.data(), normals.data(), weighted ? w.data() : nullptr, m, tangential, w6.data(), wp.data());
        else
          for (std::size_t i = 0; i < 3 * m; ++i) wp[i] = weighted ? w[i / 3] * p[i] : p[i];
        blocks->add(b.index, b.rows, m, blend ? w6.data() : weighted ? w.data() : nullptr, wp.data());
      });
  out.rows_seconds = detail::seconds_since(t0);
  out.rows_cpu = cpu_seconds() - c0;
  out.rhs.resize(3 * surface.n_vertices());
  out.matrix = blocks->finish(out.rhs.data());
  return out;
}

ApproximationChunk ApproximationChunk::sampled(std::size_t k, std::size_t sample_points) const {
  const std::vector<char> in = point_sample_mask(first_, k_, k, sample_points);  // by position as given
  std::vector<double> points, weights;
  for (std::size_t i = 0; i < k_; ++i)
    if (in[given(i)]) {
      points.insert(points.end(), &points_[3 * i], &points_[3 * i + 3]);
      if (!weights_.empty()) weights.push_back(weights_[i]);
    }
  return ApproximationChunk(points.data(), points.size() / 3, weights_.empty() ? nullptr : weights.data(), first_);
}

Footpoints ApproximationChunk::best_footpoints() const {
  Footpoints f;
  if (order_.empty() || best.face_ids.size() != k_) {
    f.face_ids = best.face_ids;
    f.uv = best.uv;
    f.distances = best.distances;
    return f;
  }
  f.face_ids.resize(k_);
  f.uv.resize(2 * k_);
  f.distances.resize(k_);
  for (std::size_t i = 0; i < k_; ++i) {
    const std::size_t j = order_[i];
    f.face_ids[j] = best.face_ids[i];
    f.uv[2 * j] = best.uv[2 * i];
    f.uv[2 * j + 1] = best.uv[2 * i + 1];
    f.distances[j] = best.distances[i];
  }
  return f;
}

// ---------------------------------------------------------------------------------------------------------------
// LocalChunks

std::size_t LocalChunks::size() { return total_points(); }

PointExtent LocalChunks::extent() {
  PointExtent t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    add(t, load(c, kPoints).extent());
    store(c, 0);
  }
  return t;
}

void LocalChunks::scale(int e) {
  scale_ = e;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    load(c, kPoints).scale(e);
    store(c, 0);
  }
}

PointMoments LocalChunks::moments(const double center[3], double diagonal) {
  PointMoments t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    add(t, load(c, kPoints).moments(center, diagonal));
    store(c, 0);
  }
  return t;
}

double LocalChunks::line_offset(const double mean[3], const double axis[3], double diagonal) {
  double off = 0.0;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    off = std::max(off, load(c, kPoints).line_offset(mean, axis, diagonal));
    store(c, 0);
  }
  return off;
}

void LocalChunks::set_control_vertices(const double*, std::size_t) { retire_search(); }

void LocalChunks::retire_search() {
  if (!search_) return;
  search_->retire();
  retired_ = std::move(search_);
}

const FootpointSearch& LocalChunks::footpoint_search(const FootpointOptions& options) {
  if (!search_ || search_options_.grid != options.grid || search_options_.max_steps != options.max_steps) {
    retire_search();
    // The retired search's grid and tree partition taken over (the surface's topology is the same).
    search_ = std::make_unique<FootpointSearch>(surface_, surface_.topology(), options, retired_.get());
    retired_.reset();
    search_options_ = options;
  }
  return *search_;
}

DistanceSums LocalChunks::search(const FootpointOptions& options) {
  const FootpointSearch& s = footpoint_search(options);
  DistanceSums t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    poll_interrupt();
    add(t, chunk(c, kPoints).search(s, &scratch_));
    put(c, kCurrent);
  }
  return t;
}

DistanceSums LocalChunks::refine(const FootpointOptions& options) {
  DistanceSums t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    poll_interrupt();
    add(t, chunk(c, kPoints | kCurrent).refine(surface_, options, &scratch_));
    put(c, kCurrent);
  }
  return t;
}

void LocalChunks::keep_best() {
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    chunk(c, kCurrent).keep_best();
    put(c, kBest);
  }
}

DistanceSums LocalChunks::search_fresh(const FootpointOptions& options, double closer) {
  scratch_.release();
  const FootpointSearch& s = footpoint_search(options);
  DistanceSums t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    poll_interrupt();
    add(t, chunk(c, kPoints | kCurrent).search_fresh(s, closer));
    put(c, kFresh);
  }
  return t;
}

DistanceSums LocalChunks::refine_fresh(const FootpointOptions& options) {
  scratch_.release();
  const FootpointSearch& s = footpoint_search(options);
  DistanceSums t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    poll_interrupt();
    add(t, chunk(c, kPoints | kCurrent).refine_fresh(s));
    put(c, kCurrent | kFresh);
  }
  return t;
}

void LocalChunks::keep_fresh(double closer) {
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    chunk(c, kCurrent | kFresh).keep_fresh(closer);
    put(c, kCurrent);
  }
}

DistanceSums LocalChunks::keep_fresh_in_best() {
  DistanceSums t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    add(t, chunk(c, kBest | kFresh).keep_fresh_in_best());
    put(c, kBest);
  }
  return t;
}

NormalSums LocalChunks::normal_sums(double tangential) { return chunks_normal_sums(tangential, nullptr, 0.0); }

NormalSums LocalChunks::chunks_normal_sums(double tangential, const RobustOptions* robust, double scale) {
  // The normal sums end a surface state's calls (the update that follows sets new control vertices): its search
  // is given back before the sums' arrays are taken (all but what the next search takes over).
  retire_search();
  NormalSums t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    poll_interrupt();
    add(t, chunk(c, kPoints | kCurrent).normal_sums(surface_, tangential, robust, scale, &scratch_));
    put(c, 0);
  }
  return t;
}

DistanceHistogram ApproximationChunk::distance_histogram(double unit) const {
  DistanceHistogram h(unit);
  h.add(current.distances.data(), weights_.empty() ? nullptr : weights_.data(), k_);
  return h;
}

RobustSums ApproximationChunk::robust_sums(const RobustOptions& robust, double scale) const {
  return sorpia::robust_sums(robust, scale, current.distances.data(),
                                 weights_.empty() ? nullptr : weights_.data(), k_);
}

namespace {
[[noreturn]] void no_robust() {
  throw ParameterError("this backend of chunks cannot fit robustly (it has no distance_histogram, "
                       "robust_sums, robust_normal_sums): pass robust = 'none'");
}
}  // namespace

DistanceSums PointChunks::refine_fresh(const FootpointOptions& options) {
  refine(options);
  return search_fresh(options, 0.0);
}

void PointChunks::set_sample(std::size_t) {
  throw ParameterError("this backend of chunks cannot run coarse iterations on a sample of the points (it has no "
                       "set_sample): pass coarse_iterations = 0");
}

DistanceHistogram PointChunks::distance_histogram(double) { no_robust(); }
RobustSums PointChunks::robust_sums(const RobustOptions&, double) { no_robust(); }
NormalSums PointChunks::robust_normal_sums(double, const RobustOptions&, double) { no_robust(); }

DistanceHistogram LocalChunks::distance_histogram(double unit) {
  DistanceHistogram t(unit);
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    t.merge(chunk(c, kCurrent).distance_histogram(unit));
    put(c, 0);
  }
  return t;
}

RobustSums LocalChunks::robust_sums(const RobustOptions& robust, double scale) {
  RobustSums t;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    t.add(chunk(c, kCurrent).robust_sums(robust, scale));
    put(c, 0);
  }
  return t;
}

NormalSums LocalChunks::robust_normal_sums(double tangential, const RobustOptions& robust, double scale) {
  return chunks_normal_sums(tangential, &robust, scale);
}

void LocalChunks::set_sample(std::size_t sample_points) {
  sampled_.clear();
  if (sample_points == 0) return;
  sampled_.reserve(n_chunks());
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    sampled_.push_back(load(c, kPoints).sampled(total_points(), sample_points));
    store(c, 0);
  }
}

std::vector<double> LocalChunks::sample() {
  std::vector<double> out;
  out.reserve(3 * total_points());
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    const ApproximationChunk& chunk = load(c, kPoints);
    const auto& p = chunk.points();
    for (std::size_t i = 0; i < chunk.size(); ++i)
      if (chunk.counts(i)) out.insert(out.end(), p.begin() + static_cast<std::ptrdiff_t>(3 * i),
                                      p.begin() + static_cast<std::ptrdiff_t>(3 * i + 3));
    store(c, 0);
  }
  return out;
}

Footpoints LocalChunks::best_footpoints() {
  scratch_.release();
  Footpoints out;
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    Footpoints f = load(c, kBest).best_footpoints();  // a copy in the order given: the first chunk's is kept whole
    if (c == 0) {
      out.face_ids = std::move(f.face_ids);
      out.uv = std::move(f.uv);
      out.distances = std::move(f.distances);
    } else {
      out.face_ids.insert(out.face_ids.end(), f.face_ids.begin(), f.face_ids.end());
      out.uv.insert(out.uv.end(), f.uv.begin(), f.uv.end());
      out.distances.insert(out.distances.end(), f.distances.begin(), f.distances.end());
    }
    store(c, 0);
  }
  return out;
}

InMemoryChunks::InMemoryChunks(LimitSurface& surface, const double* points, std::size_t k, const double* weights,
                               std::size_t chunk_points)
    : LocalChunks(surface), k_(k) {
  if (chunk_points == 0) throw ParameterError("chunk_points = 0 must be >= 1");
  for (std::size_t first = 0; first < k; first += chunk_points) {
    const std::size_t m = std::min(chunk_points, k - first);
    chunks_.emplace_back(points + 3 * first, m, weights ? weights + first : nullptr, first);
  }
}

}  // namespace sorpia

// ---------------------------------------------------------------------------------------------------------------
// FileChunks

namespace sorpia {

namespace {

[[noreturn]] void file_error(const std::string& path, const std::string& what) {
  throw FileError("cannot stream points from '" + path + "': " + what);
}

void read_all(int fd, void* buffer, std::size_t bytes, std::size_t offset, const std::string& path) {
  auto* p = static_cast<char*>(buffer);
  while (bytes > 0) {
    const ssize_t got = ::pread(fd, p, bytes, static_cast<off_t>(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) file_error(path, got == 0 ? "it ends early (truncated)" : std::strerror(errno));
    p += got;
    bytes -= static_cast<std::size_t>(got);
    offset += static_cast<std::size_t>(got);
  }
}

void write_all(int fd, const void* buffer, std::size_t bytes, std::size_t offset, const std::string& path) {
  const auto* p = static_cast<const char*>(buffer);
  while (bytes > 0) {
    const ssize_t put = ::pwrite(fd, p, bytes, static_cast<off_t>(offset));
    if (put < 0 && errno == EINTR) continue;
    if (put <= 0) file_error(path, std::string("the spill file cannot be written: ") + std::strerror(errno));
    p += put;
    bytes -= static_cast<std::size_t>(put);
    offset += static_cast<std::size_t>(put);
  }
}

// The size in bytes of a PLY scalar type, 0 for an unknown name.
std::size_t ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// A 64-bit mix of i (splitmix64's finaliser): the fixed sample's choice of point i, the same for any chunking.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Points first .. first + count of a file of layout l open as fd, as float64 (row-major (count, 3)).
std::vector<double> decode_points(int fd, const PointFileLayout& l, std::size_t first, std::size_t count,
                                  const std::string& path) {
  std::vector<char> raw(count * l.stride);
  read_all(fd, raw.data(), raw.size(), l.offset + first * l.stride, path);
  std::vector<double> p(3 * count);
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t c = 0; c < 3; ++c) {
      const char* at = raw.data() + i * l.stride + l.x_offset[c];
      if (l.float64) {
        std::memcpy(&p[3 * i + c], at, 8);
      } else {
        float f;
        std::memcpy(&f, at, 4);
        p[3 * i + c] = static_cast<double>(f);
      }
    }
  return p;
}

// A file open for reading, closed when it goes out of scope.
struct ReadOnlyFile {
  int fd;
  explicit ReadOnlyFile(const std::string& path) : fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {
    if (fd < 0) file_error(path, std::strerror(errno));
  }
  ~ReadOnlyFile() { ::close(fd); }
  ReadOnlyFile(const ReadOnlyFile&) = delete;
  ReadOnlyFile& operator=(const ReadOnlyFile&) = delete;
};

// The spill file's arrays, per point: current (face, uv, distance, normal), best (face, uv, distance), fresh (as
// current). Each array holds all points, chunk c's at its first point.
constexpr std::size_t kStateBytes[3] = {4 + 16 + 8 + 24, 4 + 16 + 8, 4 + 16 + 8 + 24};

}  // namespace

PointFileLayout point_file_layout(const std::string& path) {
  PointFileLayout out;
  const ReadOnlyFile file(path);
  const int fd = file.fd;
  const off_t end = ::lseek(fd, 0, SEEK_END);
  if (end < 0) file_error(path, std::strerror(errno));
  const auto file_size = static_cast<std::size_t>(end);
  std::string head(std::min<std::size_t>(file_size, 65536), '\0');
  read_all(fd, head.data(), head.size(), 0, path);
  if (head.rfind("ply", 0) == 0) {
    const auto stop = head.find("end_header");
    if (stop == std::string::npos) file_error(path, "its PLY header has no end_header within 64 KiB");
    const auto body = head.find('\n', stop);
    if (body == std::string::npos) file_error(path, "its PLY header is truncated");
    out.offset = body + 1;
    std::istringstream lines(head.substr(0, stop));
    std::string line;
    bool format = false, in_vertex = false, seen_vertex = false;
    std::size_t found = 0;
    while (std::getline(lines, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      std::istringstream words(line);
      std::string word;
      words >> word;
      if (word == "format") {
        std::string kind;
        words >> kind;
        if (kind != "binary_little_endian")
          file_error(path, "it is a " + kind + " PLY: streaming reads binary_little_endian PLY (or .npy)");
        format = true;
      } else if (word == "element") {
        std::string name;
        std::size_t count = 0;
        words >> name >> count;
        if (!seen_vertex && name != "vertex")
          file_error(path, "its element '" + name + "' comes before 'vertex': streaming needs the vertices first");
        in_vertex = name == "vertex";
        if (in_vertex) {
          seen_vertex = true;
          out.k = count;
        }
      } else if (word == "property" && in_vertex) {
        std::string type, name;
        words >> type >> name;
        if (type == "list") file_error(path, "its vertex element has a list property");
        const std::size_t bytes = ply_type_size(type);
        if (bytes == 0) file_error(path, "its vertex property '" + name + "' has the unknown type '" + type + "'");
        const int c = name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
        if (c >= 0) {
          const bool f64 = bytes == 8 && type != "int64";
          if (!(type == "float" || type == "float32" || type == "double" || type == "float64"))
            file_error(path, "its vertex property '" + name + "' is " + type + ": x, y, z must be float or double");
          if (found > 0 && f64 != out.float64) file_error(path, "its x, y, z are not all of one type");
          out.float64 = f64;
          out.x_offset[c] = out.stride;
          found |= std::size_t{1} << c;
        }
        out.stride += bytes;
      }
    }
    if (!format) file_error(path, "its PLY header has no format line");
    if (!seen_vertex || found != 7) file_error(path, "it has no vertex element with x, y and z");
  } else if (head.size() >= 10 && head.compare(0, 6, "\x93NUMPY") == 0) {
    const auto major = static_cast<unsigned char>(head[6]);
    std::size_t len = 0, start = 0;
    if (major == 1) {
      len = static_cast<unsigned char>(head[8]) | (static_cast<std::size_t>(static_cast<unsigned char>(head[9])) << 8);
      start = 10;
    } else {
      for (int b = 0; b < 4; ++b) len |= static_cast<std::size_t>(static_cast<unsigned char>(head[8 + b])) << (8 * b);
      start = 12;
    }
    if (start + len > head.size()) file_error(path, "its .npy header is truncated");
    const std::string dict = head.substr(start, len);
    out.offset = start + len;
    const auto value = [&](const std::string& key) {
      const auto p = dict.find("'" + key + "'");
      if (p == std::string::npos) file_error(path, "its .npy header has no '" + key + "'");
      const auto colon = dict.find(':', p);
      return dict.substr(colon + 1);
    };
    const std::string descr = value("descr");
    if (descr.find("<f8") != std::string::npos)
      out.float64 = true;
    else if (descr.find("<f4") != std::string::npos)
      out.float64 = false;
    else
      file_error(path, "its .npy dtype is not little-endian float32 or float64");
    if (value("fortran_order").find("False") == std::string::npos) file_error(path, "its .npy array is not in C order");
    const std::string shape = value("shape");
    std::size_t rows = 0, cols = 0;
    if (std::sscanf(shape.c_str(), " (%zu , %zu )", &rows, &cols) != 2 &&
        std::sscanf(shape.c_str(), " (%zu, %zu)", &rows, &cols) != 2)
      file_error(path, "its .npy shape is not (k, 3)");
    if (cols != 3) file_error(path, "its .npy shape is (" + std::to_string(rows) + ", " + std::to_string(cols) + "), not (k, 3)");
    out.k = rows;
    out.stride = out.float64 ? 24 : 12;
    out.x_offset[0] = 0;
    out.x_offset[1] = out.stride / 3;
    out.x_offset[2] = 2 * out.stride / 3;
  } else {
    file_error(path, "it is neither a PLY nor a .npy file");
  }
  if (out.offset + out.k * out.stride > file_size)
    file_error(path, "it holds " + std::to_string(file_size - out.offset) + " bytes of points where " +
                         std::to_string(out.k) + " points need " + std::to_string(out.k * out.stride));
  return out;
}

FileChunks::FileChunks(LimitSurface& surface, const std::string& path, std::size_t chunk_points,
                       const std::string& spill_directory, std::size_t sample_points)
    : LocalChunks(surface), path_(path), chunk_points_(chunk_points), sample_points_(sample_points) {
  if (chunk_points == 0) throw ParameterError("chunk_points = 0 must be >= 1");
  layout_ = point_file_layout(path);
  k_ = layout_.k;
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) file_error(path, std::strerror(errno));
  std::string spill = (spill_directory.empty() ? std::string("/tmp") : spill_directory) + "/sorpia-chunks-XXXXXX";
  spill_fd_ = ::mkstemp(spill.data());
  if (spill_fd_ < 0) file_error(path, "no spill file in '" + spill_directory + "': " + std::strerror(errno));
  ::unlink(spill.c_str());  // removed when closed, whatever ends the run
  spill_path_ = spill;
}

FileChunks::~FileChunks() {
  if (fd_ >= 0) ::close(fd_);
  if (spill_fd_ >= 0) ::close(spill_fd_);
}

std::vector<double> FileChunks::read_points(std::size_t first, std::size_t count) const {
  std::vector<double> p = decode_points(fd_, layout_, first, count, path_);
  if (scale_ != 0)
    for (double& v : p) v = std::ldexp(v, -scale_);
  return p;
}

namespace {

template <class T>
void spill_array(bool write, int fd, std::vector<T>& v, std::size_t per_point, std::size_t base, std::size_t first,
                 std::size_t count, const std::string& path) {
  const std::size_t bytes = per_point * count;
  if (write) {
    if (v.size() * sizeof(T) != bytes) return;  // not held: nothing to keep
    write_all(fd, v.data(), bytes, base + per_point * first, path);
  } else {
    v.resize(bytes / sizeof(T));
    read_all(fd, v.data(), bytes, base + per_point * first, path);
  }
}

// Reads or writes state `s` (0 current, 1 best, 2 fresh) of points [first, first + count) of k.
void spill_state(bool write, int fd, ApproximationChunk::State& st, int s, std::size_t k, std::size_t first,
                 std::size_t count, const std::string& path) {
  std::size_t base = 0;
  for (int t = 0; t < s; ++t) base += kStateBytes[t] * k;
  spill_array(write, fd, st.face_ids, 4, base, first, count, path);
  base += 4 * k;
  spill_array(write, fd, st.uv, 16, base, first, count, path);
  base += 16 * k;
  spill_array(write, fd, st.distances, 8, base, first, count, path);
  base += 8 * k;
  if (s != 1) spill_array(write, fd, st.normals, 24, base, first, count, path);
}

}  // namespace

ApproximationChunk& FileChunks::load(std::size_t c, unsigned needs) {
  const std::size_t first = c * chunk_points_, count = std::min(chunk_points_, k_ - first);
  chunk_ = ApproximationChunk();
  chunk_.k_ = count;
  chunk_.first_ = first;
  if (needs & kPoints) {
    chunk_.points_ = read_points(first, count);
    chunk_.arrange();  // the order its states were stored in
  }
  ApproximationChunk::State* states[3] = {&chunk_.current, &chunk_.best, &chunk_.fresh};
  const unsigned bits[3] = {kCurrent, kBest, kFresh};
  for (int s = 0; s < 3; ++s)
    if (needs & bits[s]) spill_state(false, spill_fd_, *states[s], s, k_, first, count, spill_path_);
  return chunk_;
}

void FileChunks::store(std::size_t c, unsigned changed) {
  const std::size_t first = c * chunk_points_, count = std::min(chunk_points_, k_ - first);
  ApproximationChunk::State* states[3] = {&chunk_.current, &chunk_.best, &chunk_.fresh};
  const unsigned bits[3] = {kCurrent, kBest, kFresh};
  for (int s = 0; s < 3; ++s)
    if (changed & bits[s]) spill_state(true, spill_fd_, *states[s], s, k_, first, count, spill_path_);
  chunk_ = ApproximationChunk();
}

std::vector<double> FileChunks::sample() {
  std::vector<double> out;
  out.reserve(3 * std::min(k_, sample_points_ + sample_points_ / 16 + 64));
  for (std::size_t c = 0; c < n_chunks(); ++c) {
    poll_interrupt();
    const std::size_t first = c * chunk_points_, count = std::min(chunk_points_, k_ - first);
    const std::vector<double> p = read_points(first, count);
    const std::vector<char> in = point_sample_mask(first, count, k_, sample_points_);
    for (std::size_t i = 0; i < count; ++i)
      if (in[i]) out.insert(out.end(), &p[3 * i], &p[3 * i + 3]);
  }
  return out;
}

std::vector<double> read_point_file(const std::string& path, std::size_t first, std::size_t count) {
  const PointFileLayout layout = point_file_layout(path);
  if (first > layout.k || count > layout.k - first)
    throw ParameterError("points " + std::to_string(first) + " .. " + std::to_string(first + count) + " of '" +
                         path + "': it holds " + std::to_string(layout.k));
  const ReadOnlyFile file(path);
  const int fd = file.fd;
  return decode_points(fd, layout, first, count, path);
}

std::vector<char> point_sample_mask(std::size_t first, std::size_t count, std::size_t k, std::size_t sample_points) {
  const bool all = k <= sample_points;
  // point i is in the sample when mix(i) falls below this share of 2^64
  const long double share = all ? 1.0L : static_cast<long double>(sample_points) / static_cast<long double>(k);
  const auto below = static_cast<std::uint64_t>(share * 18446744073709551615.0L);
  std::vector<char> in(count);
  for (std::size_t i = 0; i < count; ++i) in[i] = all || mix(first + i) < below;
  return in;
}

}  // namespace sorpia
