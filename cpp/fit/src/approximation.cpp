#include "sorpia/approximation.hpp"

#include <time.h>

#include <algorithm>
#include <array>
#include <memory>
#include <chrono>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/detail/repr.hpp"
#include "sorpia/detail/scaling.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/fair_interpolation.hpp"  // energy_tags
#include "sorpia/fairness.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/normal_matrix.hpp"
#include "sorpia/detail/clock.hpp"

namespace sorpia {

namespace {

using detail::Clock;
using detail::seconds_since;
double cpu_now() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The sum of a[0..n) by numpy's pairwise summation (its add.reduce on a contiguous float64 array: blocks of at
// most 128 summed with 8 accumulators, halves summed recursively). The RMS distances and the mean diagonal are
// summed so because the fit's figures, which its stop rule compares, were numpy's before this driver: the same
// bits (bench/bit_identical.py), and pairwise summation's error, O(log n) roundings rather than O(n).
double pairwise_sum(const double* a, std::size_t n) {
  if (n < 8) {
    double res = 0.0;
    for (std::size_t i = 0; i < n; ++i) res += a[i];
    return res;
  }
  if (n <= 128) {
    double r[8];
    for (int j = 0; j < 8; ++j) r[j] = a[j];
    std::size_t i = 8;
    for (; i < n - n % 8; i += 8)
      for (std::size_t j = 0; j < 8; ++j) r[j] += a[i + j];
    double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) res += a[i];
    return res;
  }
  std::size_t n2 = n / 2;
  n2 -= n2 % 8;
  return pairwise_sum(a, n2) + pairwise_sum(a + n2, n - n2);
}

// The length of the diagonal of the points' bounding box, scaled before squaring (coordinates beyond 1e154
// square to inf): |e| for the extent e divided by its largest component, times that component. The sum of the
// three squares is formed with fused multiply-adds, ((x0 x0 + x1 x1) + x2 x2) each rounded once, as numpy's
// norm of a 3-vector computes it through OpenBLAS's dot: the same bits as before this driver.
double bounding_box_diagonal(const double* p, std::size_t k) {
  if (k == 0) return 0.0;
  double lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
  for (std::size_t i = 1; i < k; ++i)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], p[3 * i + static_cast<std::size_t>(c)]);
      hi[c] = std::max(hi[c], p[3 * i + static_cast<std::size_t>(c)]);
    }
  const double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  const double scale = std::max({std::abs(ext[0]), std::abs(ext[1]), std::abs(ext[2])});
  if (!(scale > 0)) return 0.0;
  const double x[3] = {ext[0] / scale, ext[1] / scale, ext[2] / scale};
  return scale * std::sqrt(std::fma(x[2], x[2], std::fma(x[1], x[1], x[0] * x[0])));
}

// Data a surface can be fitted to: points that span more than a line (issue 33, 8). All at one place (one point,
// or every point a duplicate of the first), the fit would collapse the cage onto it; on one line, the cage onto
// the line: no surface is determined by them. A line: every point within 1e-12 of the diagonal of the line
// through the points' mean along their covariance's main axis (found by power iteration: for points on a line
// the covariance is that axis's outer product, so one step finds it; for any other points no line holds them all
// that closely, whatever its direction).
void check_spread(const double* p, std::size_t k, double diagonal) {
  if (!(diagonal > 0))
    throw MeshError("the points all lie at one place (" + std::to_string(k) +
                         (k == 1 ? " point" : " points, all equal") +
                         "): there is no surface to fit; give points that span the surface");
  double mean[3] = {0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < k; ++i)
    for (std::size_t c = 0; c < 3; ++c) mean[c] += p[3 * i + c] / static_cast<double>(k);
  double a[3][3] = {};
  for (std::size_t i = 0; i < k; ++i) {
    double d[3];
    for (std::size_t c = 0; c < 3; ++c) d[c] = (p[3 * i + c] - mean[c]) / diagonal;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) a[r][c] += d[r] * d[c];
  }
  double u[3] = {1.0, 0.7, 0.4};
  for (int it = 0; it < 100; ++it) {
    double w[3];
    for (int r = 0; r < 3; ++r) w[r] = a[r][0] * u[0] + a[r][1] * u[1] + a[r][2] * u[2];
    const double norm = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(norm > 0)) break;
    for (int r = 0; r < 3; ++r) u[r] = w[r] / norm;
  }
  const double un = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (double& x : u) x /= un;
  double off = 0.0;  // the largest distance from the line, over the diagonal
  for (std::size_t i = 0; i < k; ++i) {
    double d[3];
    for (std::size_t c = 0; c < 3; ++c) d[c] = (p[3 * i + c] - mean[c]) / diagonal;
    const double along = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
    double r2 = 0.0;
    for (int c = 0; c < 3; ++c) r2 += (d[c] - along * u[c]) * (d[c] - along * u[c]);
    off = std::max(off, std::sqrt(r2));
  }
  if (off <= 1e-12)
    throw MeshError("the points all lie on one line (" + std::to_string(k) +
                         " points): no surface is determined by them; give points that span the surface");
}

void check_options(const ApproximationOptions& o) {
  const auto nonnegative = [](double v, const char* name) {
    if (!(std::isfinite(v) && v >= 0))
      throw ParameterError(std::string(name) + " = " + detail::repr(v) + " must be a finite number >= 0");
  };
  if (o.iterations < 1) throw ParameterError("iterations = " + std::to_string(o.iterations) + " must be an integer >= 1");
  nonnegative(o.tol, "tol");
  nonnegative(o.fairness, "fairness");
  nonnegative(o.tangential, "tangential");
  if (o.tangential > 1) throw ParameterError("tangential = " + detail::repr(o.tangential) + " must be in [0, 1]");
  if (o.update == ApproximationUpdate::LSPIA && o.tangential != 1.0)
    throw ParameterError("method = 'lspia' moves each coordinate on its own: it takes tangential = 1 only");
  nonnegative(o.solver_tol, "solver_tol");
  if (o.solver_max_iter < 1)
    throw ParameterError("solver_max_iter = " + std::to_string(o.solver_max_iter) + " must be an integer >= 1");
  if (o.footpoints.grid < 1 || o.footpoints.grid > 64)
    throw ParameterError("grid = " + std::to_string(o.footpoints.grid) + " must be in 1..64");
  if (o.footpoints.max_steps < 1)
    throw ParameterError("newton_steps = " + std::to_string(o.footpoints.max_steps) + " must be an integer >= 1");
  if (o.report_level < 0 || o.report_level > 15)
    throw ParameterError("report_level = " + std::to_string(o.report_level) + " must be in 0..15");
  if (o.fairness_depth < 0 || o.fairness_depth > 12)
    throw ParameterError("fairness_depth = " + std::to_string(o.fairness_depth) + " must be in 0..12");
  if (!(std::isfinite(o.proximal) && o.proximal > 0))
    throw ParameterError("proximal = " + detail::repr(o.proximal) + " must be a finite number > 0");
  if (o.window < 1) throw ParameterError("window = " + std::to_string(o.window) + " must be >= 1");
  nonnegative(o.exact, "exact");
  nonnegative(o.closer, "closer");
  if (!(o.robust.quantile > 0 && o.robust.quantile < 1))
    throw ParameterError("robust_quantile = " + detail::repr(o.robust.quantile) + " must be in (0, 1)");
  if (!(std::isfinite(o.robust.c) && o.robust.c > 0))
    throw ParameterError("robust_c = " + detail::repr(o.robust.c) + " must be a finite number > 0");
}

// y (n, 3) = A^T x for A (k, n) and x (k, 3): row by row of A in order, each entry's product added to its
// column's row of y (the order of scipy's A.T @ x, which this driver replaced).
std::vector<double> transposed_times(const CsrMatrix& a, const double* x) {
  std::vector<double> y(3 * a.n_cols, 0.0);
  for (std::size_t r = 0; r < a.n_rows; ++r)
    for (std::int32_t p = a.indptr[r]; p < a.indptr[r + 1]; ++p) {
      const double w = a.data[static_cast<std::size_t>(p)];
      double* yj = &y[3 * static_cast<std::size_t>(a.indices[static_cast<std::size_t>(p)])];
      for (std::size_t c = 0; c < 3; ++c) yj[c] += w * x[3 * r + c];
    }
  return y;
}

// A sparse matrix with sorted, distinct columns per row (what the LSPIA update works on).
struct Sparse {
  std::size_t n = 0;
  std::vector<std::int64_t> indptr;
  std::vector<std::int32_t> indices;
  std::vector<double> data;
};

// a + s b for a and b with sorted, distinct columns: the union of the patterns, entries that sum to exactly 0
// left out (as scipy's canonical sparse sum, whose bits the LSPIA update keeps). s b is formed first.
Sparse plus(const Sparse& a, const CsrMatrix* b, double s, bool identity) {
  Sparse out;
  out.n = a.n;
  out.indptr.assign(a.n + 1, 0);
  out.indices.reserve(a.indices.size() + a.n);
  out.data.reserve(a.data.size() + a.n);
  const auto push = [&](std::int32_t j, double v) {
    if (v != 0.0) {
      out.indices.push_back(j);
      out.data.push_back(v);
    }
  };
  for (std::size_t i = 0; i < a.n; ++i) {
    auto p = static_cast<std::size_t>(a.indptr[i]);
    const auto pe = static_cast<std::size_t>(a.indptr[i + 1]);
    // b's row: the identity's one entry (i, s), or b's entries scaled
    std::size_t q = 0, qe = 1;
    if (!identity) {
      q = static_cast<std::size_t>(b->indptr[i]);
      qe = static_cast<std::size_t>(b->indptr[i + 1]);
    }
    const auto b_col = [&](std::size_t t) { return identity ? static_cast<std::int32_t>(i) : b->indices[t]; };
    const auto b_val = [&](std::size_t t) { return identity ? s : s * b->data[t]; };
    while (p < pe && q < qe) {
      const std::int32_t ja = a.indices[p], jb = b_col(q);
      if (ja == jb) {
        push(ja, a.data[p++] + b_val(q++));
      } else if (ja < jb) {
        push(ja, a.data[p++] + 0.0);
      } else {
        push(jb, 0.0 + b_val(q++));
      }
    }
    for (; p < pe; ++p) push(a.indices[p], a.data[p] + 0.0);
    for (; q < qe; ++q) push(b_col(q), 0.0 + b_val(q));
    out.indptr[i + 1] = static_cast<std::int64_t>(out.indices.size());
  }
  return out;
}

// y = M x, x and y (n, 3): each row's products summed in column order from 0.
void times(const Sparse& m, const std::vector<double>& x, std::vector<double>& y) {
  y.assign(3 * m.n, 0.0);
  for (std::size_t i = 0; i < m.n; ++i)
    for (auto p = static_cast<std::size_t>(m.indptr[i]); p < static_cast<std::size_t>(m.indptr[i + 1]); ++p) {
      const double a = m.data[p];
      const double* xj = &x[3 * static_cast<std::size_t>(m.indices[p])];
      for (std::size_t c = 0; c < 3; ++c) y[3 * i + c] += a * xj[c];
    }
}

// The Euclidean norm of each column of r (n, 3), its squares summed row after row.
std::array<double, 3> column_norms(const std::vector<double>& r) {
  std::array<double, 3> s{0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < r.size(); i += 3)
    for (std::size_t c = 0; c < 3; ++c) s[c] += r[i + c] * r[i + c];
  for (double& v : s) v = std::sqrt(v);
  return s;
}

// LSPIA (Deng and Lin 2014) on M x = rhs from x: x += D^-1 (rhs - M x), D the row sums of |M| (0 leaves a row
// where it is). Without the fairness and proximal terms M = A^T A with A >= 0 and rows summing to 1, so D_j is the
// sum of column j of A: each control vertex moves by its points' residuals weighted by the basis, divided by the
// sum of those weights. Stops when every column's residual is below rtol times its initial one (or 1e-15 times
// its right-hand side's). Returns the iterations made.
long long lspia(const Sparse& m, const std::vector<double>& rhs, std::vector<double>& x, double rtol,
                long long max_iter) {
  std::vector<double> inv(m.n, 0.0);
  for (std::size_t i = 0; i < m.n; ++i) {
    const auto p = static_cast<std::size_t>(m.indptr[i]), pe = static_cast<std::size_t>(m.indptr[i + 1]);
    if (p == pe) continue;
    // the first entry, then the rest by pairwise summation (numpy's reduceat over a row, as before this driver)
    std::vector<double> rest(pe - p - 1);
    for (std::size_t t = p + 1; t < pe; ++t) rest[t - p - 1] = std::abs(m.data[t]);
    const double scale = std::abs(m.data[p]) + pairwise_sum(rest.data(), rest.size());
    inv[i] = scale > 0 ? 1.0 / scale : 0.0;
  }
  std::vector<double> mx, r(rhs.size());
  const auto residual = [&] {
    times(m, x, mx);
    for (std::size_t t = 0; t < r.size(); ++t) r[t] = rhs[t] - mx[t];
  };
  residual();
  const auto r0 = column_norms(r), b = column_norms(rhs);
  std::array<double, 3> stop{};
  for (std::size_t c = 0; c < 3; ++c) stop[c] = std::max(rtol * r0[c], 1e-15 * b[c]);
  for (long long k = 1; k <= max_iter; ++k) {
    const auto now = column_norms(r);
    if (now[0] <= stop[0] && now[1] <= stop[1] && now[2] <= stop[2]) return k - 1;
    poll_interrupt();
    for (std::size_t i = 0; i < m.n; ++i)
      for (std::size_t c = 0; c < 3; ++c) x[3 * i + c] += inv[i] * r[3 * i + c];
    residual();
  }
  return max_iter;
}

// Adds the wall and CPU seconds of `fn` to a phase's.
class Phases {
 public:
  ApproximationTimings wall, cpu;
  template <class F>
  auto timed(double ApproximationTimings::*phase, F&& fn) {
    const auto t = Clock::now();
    const double c = cpu_now();
    struct Add {
      Phases* self;
      double ApproximationTimings::*phase;
      Clock::time_point t;
      double c;
      ~Add() {
        self->wall.*phase += seconds_since(t);
        self->cpu.*phase += cpu_now() - c;
      }
    } add{this, phase, t, c};
    return fn();
  }
};

// A footpoint state: what the loop keeps of Footpoints (positions are not used).
struct Feet {
  std::vector<std::int32_t> face_ids;
  std::vector<double> uv, distances, normals;
  explicit Feet(Footpoints&& f)
      : face_ids(std::move(f.face_ids)), uv(std::move(f.uv)), distances(std::move(f.distances)),
        normals(std::move(f.normals)) {}
  Feet() = default;
};

}  // namespace

bool rms_levelled(const std::vector<double>& bests, double tol, int window) {
  const auto w = static_cast<std::size_t>(std::max(window, 1));
  if (bests.size() <= w) return false;
  const double before = bests[bests.size() - 1 - w];
  return before - bests.back() <= static_cast<double>(window) * tol * before;
}

ApproximationResult approximate(LimitSurface& surface, const double* points, std::size_t k, const double* weights,
                                const ApproximationOptions& options, const ApproximationProgress& progress) {
  const auto t0 = Clock::now();
  const double c0 = cpu_now();
  check_options(options);
  if (k == 0) throw MeshError("points is empty: there is nothing to approximate");
  for (std::size_t i = 0; i < 3 * k; ++i)
    if (!std::isfinite(points[i])) throw MeshError("points[" + std::to_string(i / 3) + "] is not finite");
  if (weights) {
    bool any = false;
    for (std::size_t i = 0; i < k; ++i) {
      if (!(std::isfinite(weights[i]) && weights[i] >= 0))
        throw ParameterError("weights[" + std::to_string(i) + "] = " + detail::repr(weights[i]) +
                             " must be a finite number >= 0");
      any = any || weights[i] > 0;
    }
    if (!any) throw ParameterError("weights are all 0: no point would count");
  }
  const Topology& topology = surface.topology();
  const std::size_t n = surface.n_vertices();
  std::vector<double> V(3 * n);
  surface.get_vertices(V.data());

  // Squared distances, areas and the solver's norms of data beyond 2^+-200 would overflow or underflow: such data
  // is fitted scaled by a power of two (exact), and records and results come back in the caller's units.
  const int e = detail::scale_exponent(detail::largest_magnitude(V.data(), V.size(),
                                                                 detail::largest_magnitude(points, 3 * k)));
  std::vector<double> scaled;
  if (e != 0) {
    scaled.assign(points, points + 3 * k);
    detail::scale_pow2(scaled.data(), scaled.size(), -e);
    points = scaled.data();
    detail::scale_pow2(V.data(), V.size(), -e);
    surface.set_vertices(V.data());
  }
  const double diagonal = bounding_box_diagonal(points, k);
  check_spread(points, k, diagonal);
  const double unit = diagonal;

  ApproximationResult out;
  Phases phases;
  std::vector<double> squares(k);
  // The RMS distance of the points, weighted: sum w d^2 / k (the weights of mean 1).
  const auto rms = [&](const std::vector<double>& d) {
    for (std::size_t i = 0; i < k; ++i) squares[i] = weights ? weights[i] * (d[i] * d[i]) : d[i] * d[i];
    return std::sqrt(pairwise_sum(squares.data(), k) / static_cast<double>(k));
  };
  // The robust fit (sorpia/robust.hpp): the scale of a state's distances, the factors of the points' weights in
  // the next update (fit_w: the caller's weights times them), and the criterion that picks the iterate returned
  // and stops the run (the RMS distance without a robust loss).
  const bool robust = options.robust.loss != RobustLoss::None;
  // Distances below 1e-5 of the diagonal never make a point an outlier: on data the surface reaches to rounding
  // the scale would fall with the fit and cut the points that converge last.
  const double scale_floor = 1e-5 * unit;
  const auto robust_scale_of = [&](const std::vector<double>& d) {
    DistanceHistogram histogram(unit);
    histogram.add(d.data(), weights, k);
    return robust_scale(histogram, options.robust, scale_floor);
  };
  std::vector<double> fit_w;
  const auto criterion = [&](const std::vector<double>& d) {
    if (!robust) return rms(d);
    return std::sqrt(robust_loss_sum(options.robust, robust_scale_of(d), d.data(), weights, k) /
                     static_cast<double>(k));
  };
  std::unique_ptr<PointIndex> data_index;
  std::vector<std::int64_t> nearest;
  std::vector<double> near_distance;
  const auto record = [&](int iteration, const std::vector<double>& distances, long long solver_iterations) {
    phases.timed(&ApproximationTimings::report, [&] {
      if (!data_index) data_index = std::make_unique<PointIndex>(points, k);
      const Mesh mesh = surface.tessellate(options.report_level);
      const std::size_t nv = mesh.n_vertices();
      nearest.resize(nv);
      near_distance.resize(nv);
      data_index->nearest(mesh.vertices.data(), nv, nearest.data(), near_distance.data());
      // Vertex i < n of the tessellation is control vertex i at its limit position; a control vertex no face uses
      // stays where it is and is no point of the surface: left out of the surface's distances (issue 33, 12).
      if (topology.n_unreferenced() > 0) {
        std::size_t kept = 0;
        for (std::size_t i = 0; i < nv; ++i)
          if (i >= n || !topology.is_unreferenced(i)) near_distance[kept++] = near_distance[i];
        near_distance.resize(kept);
      }
      return 0;
    });
    ApproximationRecord rec;
    rec.iteration = iteration;
    rec.rms = rms(distances);
    rec.max = *std::max_element(distances.begin(), distances.end());
    std::vector<double> s2(near_distance.size());
    for (std::size_t i = 0; i < s2.size(); ++i) s2[i] = near_distance[i] * near_distance[i];
    rec.surface_rms = std::sqrt(pairwise_sum(s2.data(), s2.size()) / static_cast<double>(s2.size()));
    rec.surface_max = near_distance.empty() ? 0.0 : *std::max_element(near_distance.begin(), near_distance.end());
    rec.rms_relative = rec.rms / unit;
    rec.max_relative = rec.max / unit;
    rec.surface_rms_relative = rec.surface_rms / unit;
    rec.surface_max_relative = rec.surface_max / unit;
    rec.rms = std::ldexp(rec.rms, e);
    rec.max = std::ldexp(rec.max, e);
    rec.surface_rms = std::ldexp(rec.surface_rms, e);
    rec.surface_max = std::ldexp(rec.surface_max, e);
    if (robust) rec.robust_scale = std::ldexp(robust_scale_of(distances), e);
    rec.solver_iterations = solver_iterations;
    rec.seconds = seconds_since(t0);
    out.history.push_back(rec);
    if (progress) progress(rec);
    return rec;
  };
  const auto search = [&] {
    return Feet(phases.timed(&ApproximationTimings::footpoints,
                             [&] { return closest_points(surface, topology, points, k, options.footpoints); }));
  };

  Feet feet = search();
  record(0, feet.distances, 0);
  struct Best {
    double rms;
    std::vector<double> V;
    std::vector<std::int32_t> face_ids;
    std::vector<double> uv, distances;
    int iteration;
  } best{criterion(feet.distances), V, feet.face_ids, feet.uv, feet.distances, 0};
  std::vector<double> bests{best.rms};  // the lowest RMS so far, after each iteration

  CsrMatrix K;
  if (options.fairness > 0) {
    FairnessQuadrature quadrature;
    quadrature.depth = options.fairness_depth;
    K = fairness_matrix(topology,
                        Rules{surface.scheme(), surface.boundary(), energy_tags(surface.tags(), SemiSharp::Sharp)},
                        1.0, 0.0, quadrature);
  }
  const bool cg = options.update == ApproximationUpdate::CG;
  const bool blend = options.tangential != 1.0;
  out.stop_reason = "max_iter";
  int searched = 0;  // the iteration after which every footpoint was last searched for afresh
  Feet last_fresh;           // the last fresh search, made at iteration fresh_iteration
  int fresh_iteration = -1;
  int done = 0;
  std::vector<std::size_t> order(k);
  std::vector<std::int32_t> face_o(k);
  std::vector<double> uv_o(2 * k), points_o(3 * k), normals_o(3 * k), w_o, wp(3 * k), w6;
  if (weights || robust) w_o.resize(k);
  const double* fit_weights = weights;  // the points' weights in the updates
  if (blend) w6.resize(6 * k);
  for (int it = 1; it <= options.iterations; ++it) {
    poll_interrupt();
    if (robust) {
      fit_w.resize(k);
      robust_factors(options.robust, robust_scale_of(feet.distances), feet.distances.data(), k, fit_w.data());
      if (weights)
        for (std::size_t i = 0; i < k; ++i) fit_w[i] *= weights[i];
      fit_weights = fit_w.data();
    }
    // The rows in face order: the points of a face share their columns, which the normal matrix reads once.
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return feet.face_ids[a] < feet.face_ids[b]; });
    for (std::size_t i = 0; i < k; ++i) {
      const std::size_t o = order[i];
      face_o[i] = feet.face_ids[o];
      uv_o[2 * i] = feet.uv[2 * o];
      uv_o[2 * i + 1] = feet.uv[2 * o + 1];
    }
    // The rows A, the largest array of a run, live only until the normal equations are formed from them.
    CsrMatrix A = phases.timed(&ApproximationTimings::rows,
                               [&] { return surface.rows(face_o.data(), uv_o.data(), k, 0).position; });
    long long used = 0;
    std::vector<double> rhs;
    if (cg) {
      NormalEquations M = phases.timed(&ApproximationTimings::normal, [&] {
        for (std::size_t i = 0; i < k; ++i) {
          const std::size_t o = order[i];
          for (std::size_t c = 0; c < 3; ++c) {
            points_o[3 * i + c] = points[3 * o + c];
            normals_o[3 * i + c] = feet.normals[3 * o + c];
          }
          if (fit_weights) w_o[i] = fit_weights[o];
        }
        const double* w = nullptr;
        int count = 0;
        if (blend) {
          blend_weights(points_o.data(), normals_o.data(), fit_weights ? w_o.data() : nullptr, k, options.tangential,
                        w6.data(), wp.data());
          w = w6.data();
          count = 6;
        } else {
          for (std::size_t i = 0; i < 3 * k; ++i) wp[i] = fit_weights ? w_o[i / 3] * points_o[i] : points_o[i];
          if (fit_weights) {
            w = w_o.data();
            count = 1;
          }
        }
        NormalEquations eq(normal_matrix(A, w, count), K, options.fairness, options.proximal);
        rhs = transposed_times(A, wp.data());
        for (std::size_t i = 0; i < rhs.size(); ++i) rhs[i] += eq.mu() * V[i];
        return eq;
      });
      A = CsrMatrix{};
      const PcgResult res = phases.timed(&ApproximationTimings::solve, [&] {
        return M.solve(rhs.data(), V.data(), options.solver_tol, options.solver_max_iter, 0);
      });
      used = res.iterations;
    } else {
      Sparse M = phases.timed(&ApproximationTimings::normal, [&] {
        for (std::size_t i = 0; i < k; ++i) {
          const std::size_t o = order[i];
          for (std::size_t c = 0; c < 3; ++c) points_o[3 * i + c] = points[3 * o + c];
          if (fit_weights) w_o[i] = fit_weights[o];
        }
        for (std::size_t i = 0; i < 3 * k; ++i) wp[i] = fit_weights ? w_o[i / 3] * points_o[i] : points_o[i];
        NormalMatrix N = normal_matrix(A, fit_weights ? w_o.data() : nullptr, fit_weights ? 1 : 0);
        Sparse ata;
        ata.n = N.n;
        ata.indptr = std::move(N.indptr);
        ata.indices = std::move(N.indices);
        ata.data = std::move(N.values);
        std::vector<double> diagonal_of(n, 0.0);
        for (std::size_t i = 0; i < n; ++i)
          for (auto p = static_cast<std::size_t>(ata.indptr[i]); p < static_cast<std::size_t>(ata.indptr[i + 1]); ++p)
            if (static_cast<std::size_t>(ata.indices[p]) == i) diagonal_of[i] += ata.data[p];
        double mean_diagonal = pairwise_sum(diagonal_of.data(), n) / static_cast<double>(n);
        if (mean_diagonal == 0.0) mean_diagonal = 1.0;
        const double mu = options.proximal * mean_diagonal;
        Sparse m = plus(ata, nullptr, mu, true);
        if (!K.indptr.empty()) m = plus(m, &K, options.fairness * mean_diagonal, false);
        rhs = transposed_times(A, wp.data());
        for (std::size_t i = 0; i < rhs.size(); ++i) rhs[i] += mu * V[i];
        return m;
      });
      A = CsrMatrix{};
      used = phases.timed(&ApproximationTimings::solve,
                          [&] { return lspia(M, rhs, V, options.solver_tol, options.solver_max_iter); });
    }
    for (std::size_t i = 0; i < V.size(); ++i)
      if (!std::isfinite(V[i]))
        throw ParameterError("approximation's update " + std::to_string(it) + " gave control vertex " +
                             std::to_string(i / 3) + " a value that is not finite");
    surface.set_vertices(V.data());
    feet = Feet(phases.timed(&ApproximationTimings::footpoints, [&] {
      Footpoints from;
      from.face_ids = feet.face_ids;
      from.uv = feet.uv;
      FootpointOptions refine = options.footpoints;
      refine.grid = 0;
      refine_footpoints(surface, topology, points, k, refine, from);
      return from;
    }));
    done = it;
    const ApproximationRecord rec = record(it, feet.distances, used);
    const double current = criterion(feet.distances);
    if (current <= best.rms) best = Best{current, V, feet.face_ids, feet.uv, feet.distances, it};
    bests.push_back(best.rms);
    if (rec.rms_relative <= options.exact) {
      out.stop_reason = "exact";
      break;
    }
    const bool levelled = rms_levelled(bests, options.tol, options.window);
    if (it == options.iterations || it - searched < options.window || !levelled) continue;
    // Re-projection from the previous footpoints finds local minima of the distance: before stopping, every
    // footpoint is searched for afresh (the grid's nearest sample, then Gauss-Newton) and the closer one kept; a
    // gain of more than tol goes on.
    searched = it;
    Feet fresh = search();
    std::vector<char> closer(k);
    std::vector<double> merged(k);
    for (std::size_t i = 0; i < k; ++i) {
      closer[i] = fresh.distances[i] < feet.distances[i] - options.closer * unit;
      merged[i] = closer[i] ? fresh.distances[i] : feet.distances[i];
    }
    if (criterion(merged) < (1 - options.tol) * current) {
      for (std::size_t i = 0; i < k; ++i)
        if (closer[i]) {
          feet.face_ids[i] = fresh.face_ids[i];
          feet.distances[i] = fresh.distances[i];
          for (std::size_t c = 0; c < 2; ++c) feet.uv[2 * i + c] = fresh.uv[2 * i + c];
          for (std::size_t c = 0; c < 3; ++c) feet.normals[3 * i + c] = fresh.normals[3 * i + c];
        }
      continue;
    }
    out.stop_reason = "converged";
    if (best.iteration == it) {  // the fresh search was made on the iterate returned: the final step reuses it
      last_fresh = std::move(fresh);
      fresh_iteration = it;
    }
    break;
  }
  // Reported distances are true distances (issue 33, 6): re-projection from the previous footpoints keeps a point
  // in a local minimum of its distance, so the returned iterate's footpoints are searched for afresh (the grid's
  // nearest sample, then Gauss-Newton: closest_points), any closer one kept, and its record measured again from
  // them before the result reports it.
  if (best.iteration != fresh_iteration) {
    surface.set_vertices(best.V.data());
    last_fresh = search();
  }
  bool closer_found = false;
  for (std::size_t i = 0; i < k; ++i)
    if (last_fresh.distances[i] < best.distances[i]) {
      best.face_ids[i] = last_fresh.face_ids[i];
      best.uv[2 * i] = last_fresh.uv[2 * i];
      best.uv[2 * i + 1] = last_fresh.uv[2 * i + 1];
      best.distances[i] = last_fresh.distances[i];
      closer_found = true;
    }
  if (closer_found) {
    ApproximationRecord& rec = out.history[static_cast<std::size_t>(best.iteration)];
    const double r = rms(best.distances), m = *std::max_element(best.distances.begin(), best.distances.end());
    rec.rms_relative = r / unit;
    rec.max_relative = m / unit;
    rec.rms = std::ldexp(r, e);
    rec.max = std::ldexp(m, e);
    if (robust) rec.robust_scale = std::ldexp(robust_scale_of(best.distances), e);
  }
  // The iterate of the lowest RMS distance (an update that raised it is not returned).
  out.iterations = done;
  out.best_iteration = best.iteration;
  out.control_vertices = std::move(best.V);
  detail::scale_pow2(out.control_vertices.data(), out.control_vertices.size(), e);
  surface.set_vertices(out.control_vertices.data());
  out.footpoints.face_ids = std::move(best.face_ids);
  out.footpoints.uv = std::move(best.uv);
  if (robust) {
    const double s = robust_scale_of(best.distances);
    for (double d : best.distances) out.robust_outliers += d > options.robust.c * s;
    out.robust_scale = std::ldexp(s, e);
  }
  out.footpoints.distances = std::move(best.distances);
  detail::scale_pow2(out.footpoints.distances.data(), out.footpoints.distances.size(), e);
  out.diagonal = std::ldexp(diagonal, e);
  out.seconds = phases.wall;
  out.cpu_seconds = phases.cpu;
  out.seconds.total = seconds_since(t0);
  out.cpu_seconds.total = cpu_now() - c0;
  return out;
}

}  // namespace sorpia
