#include "sorpia/approximation.hpp"

#include <time.h>

#include <algorithm>
#include <array>
#include <memory>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "sorpia/detail/pairwise.hpp"
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

using detail::pairwise_sum;

// The length of the diagonal of the points' bounding box, scaled before squaring (coordinates beyond 1e154
// square to inf): |e| for the extent e divided by its largest component, times that component. The sum of the
// three squares is formed with fused multiply-adds, ((x0 x0 + x1 x1) + x2 x2) each rounded once, as numpy's
// norm of a 3-vector computes it through OpenBLAS's dot: the same bits as before this driver.
double bounding_box_diagonal(const PointExtent& box) {
  if (box.count == 0) return 0.0;
  const double ext[3] = {box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]};
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
void check_spread(PointChunks& chunks, const PointExtent& box, double diagonal) {
  const std::size_t k = box.weighted;  // the points that count (weight > 0)
  if (!(diagonal > 0))
    throw MeshError("the points all lie at one place (" + std::to_string(k) +
                         (k == 1 ? " point" : " points, all equal") +
                         "): there is no surface to fit; give points that span the surface");
  // The moments about the box's centre (each coordinate within the diagonal's half of it), over the diagonal.
  const double center[3] = {0.5 * (box.lo[0] + box.hi[0]), 0.5 * (box.lo[1] + box.hi[1]),
                            0.5 * (box.lo[2] + box.hi[2])};
  const PointMoments m = chunks.moments(center, diagonal);
  const auto kd = static_cast<double>(m.count);
  double mean_d[3], mean[3];
  for (int c = 0; c < 3; ++c) {
    mean_d[c] = m.sum[c] / kd;
    mean[c] = center[c] + diagonal * mean_d[c];
  }
  double a[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a[r][c] = m.sum2[3 * r + c] - kd * mean_d[r] * mean_d[c];
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
  // the largest distance from the line, over the diagonal
  if (chunks.line_offset(mean, u, diagonal) <= 1e-12)
    throw MeshError("the points all lie on one line (" + std::to_string(k) +
                         " points): no surface is determined by them; give points that span the surface");
}

void check_options(const ApproximationOptions& o) {
  const auto nonnegative = [](double v, const char* name) {
    if (!(std::isfinite(v) && v >= 0))
      throw ParameterError(std::string(name) + " = " + detail::repr(v) + " must be a finite number >= 0");
  };
  if (o.iterations < 1) throw ParameterError("iterations = " + std::to_string(o.iterations) + " must be an integer >= 1");
  if (o.coarse_iterations < 0)
    throw ParameterError("coarse_iterations = " + std::to_string(o.coarse_iterations) + " must be an integer >= 0");
  if (!(std::isfinite(o.coarse_points) && o.coarse_points > 0))
    throw ParameterError("coarse_points = " + detail::repr(o.coarse_points) + " must be a finite number > 0");
  nonnegative(o.coarse_tol, "coarse_tol");
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

}  // namespace

bool rms_levelled(const std::vector<double>& bests, double tol, int window) {
  const auto w = static_cast<std::size_t>(std::max(window, 1));
  if (bests.size() <= w) return false;
  const double before = bests[bests.size() - 1 - w];
  return before - bests.back() <= static_cast<double>(window) * tol * before;
}

ApproximationResult approximate(LimitSurface& surface, PointChunks& chunks, const ApproximationOptions& options,
                                const ApproximationProgress& progress) {
  const auto t0 = Clock::now();
  const double c0 = cpu_now();
  check_options(options);
  const std::size_t k = chunks.size();
  if (k == 0) throw MeshError("points is empty: there is nothing to approximate");
  const PointExtent box0 = chunks.extent();
  if (box0.weighted == 0) throw ParameterError("weights are all 0: no point would count");
  const Topology& topology = surface.topology();
  const std::size_t n = surface.n_vertices();
  std::vector<double> V(3 * n);
  surface.get_vertices(V.data());

  // Squared distances, areas and the solver's norms of data beyond 2^+-200 would overflow or underflow: such data
  // is fitted scaled by a power of two (exact), and records and results come back in the caller's units.
  const int e = detail::scale_exponent(detail::largest_magnitude(V.data(), V.size(), box0.largest));
  PointExtent box = box0;
  if (e != 0) {
    chunks.scale(e);
    for (int c = 0; c < 3; ++c) {
      box.lo[c] = std::ldexp(box.lo[c], -e);
      box.hi[c] = std::ldexp(box.hi[c], -e);
    }
    detail::scale_pow2(V.data(), V.size(), -e);
    surface.set_vertices(V.data());
  }
  const double diagonal = bounding_box_diagonal(box);
  check_spread(chunks, box, diagonal);
  const double unit = diagonal;
  const auto set_vertices = [&](const std::vector<double>& x) {
    surface.set_vertices(x.data());
    chunks.set_control_vertices(x.data(), n);
  };
  chunks.set_control_vertices(V.data(), n);

  ApproximationResult out;
  Phases phases;
  // The RMS distance of the points the sums are of (all k, or the coarse iterations' sample), weighted: sum w d^2
  // over their count (the weights of mean 1).
  const auto counted = [&](const DistanceSums& d) { return static_cast<double>(d.count > 0 ? d.count : k); };
  const auto rms = [&](const DistanceSums& d) { return std::sqrt(d.squares / counted(d)); };
  std::unique_ptr<PointIndex> data_index;
  std::vector<std::int64_t> nearest;
  std::vector<double> near_distance;
  // The surface-to-data distances of the surface's current state into rec (the data's k-d tree built once).
  const auto measure_surface = [&](ApproximationRecord& rec) {
    phases.timed(&ApproximationTimings::report, [&] {
      if (!data_index) {
        const std::vector<double> sample = chunks.sample();
        data_index = std::make_unique<PointIndex>(sample.data(), sample.size() / 3);
      }
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
    std::vector<double> s2(near_distance.size());
    for (std::size_t i = 0; i < s2.size(); ++i) s2[i] = near_distance[i] * near_distance[i];
    const double srms = std::sqrt(pairwise_sum(s2.data(), s2.size()) / static_cast<double>(s2.size()));
    const double smax = near_distance.empty() ? 0.0 : *std::max_element(near_distance.begin(), near_distance.end());
    rec.surface_rms_relative = srms / unit;
    rec.surface_max_relative = smax / unit;
    rec.surface_rms = std::ldexp(srms, e);
    rec.surface_max = std::ldexp(smax, e);
  };
  // The robust fit (sorpia/robust.hpp): the scale of the chunks' current distances (a histogram merged over the
  // chunks), which weighs the points in the next update, and the criterion that picks the iterate returned and
  // stops the run (the RMS distance without a robust loss). The scale is at least 1e-4 of the diagonal, so no
  // point within 30 times that is an outlier: on data the surface reaches to rounding the scale would fall with the
  // fit and cut the points that converge last (and a cut point drifts away).
  const bool robust = options.robust.loss != RobustLoss::None;
  const double scale_floor = 1e-4 * unit;
  double current_scale = 0.0;
  const auto measure_scale = [&] {
    if (robust) current_scale = robust_scale(chunks.distance_histogram(unit), options.robust, scale_floor);
  };
  double current_loss = 0.0;  // the criterion at the last measured distances (robust), in the fit's units
  RobustSums current_robust;    // their robust sums at current_scale
  // The criterion at the chunks' current distances d (their robust sums at current_scale with a robust loss).
  const auto measure_criterion = [&](const DistanceSums& d) {
    if (!robust) return rms(d);
    current_robust = chunks.robust_sums(options.robust, current_scale);
    current_loss = std::sqrt(current_robust.loss / counted(d));  // over the points the sums are of, as rms
    return current_loss;
  };
  const auto criterion = [&](const DistanceSums& d) { return robust ? current_loss : rms(d); };
  const double not_measured = std::numeric_limits<double>::quiet_NaN();
  const auto record = [&](int iteration, const DistanceSums& distances, long long solver_iterations,
                          const std::array<double, 2>& move) {
    ApproximationRecord rec;
    rec.iteration = iteration;
    rec.points = distances.count;
    rec.move_max_relative = move[0];
    rec.move_rms_relative = move[1];
    rec.rms = rms(distances);
    rec.max = distances.max;
    rec.rms_relative = rec.rms / unit;
    rec.max_relative = rec.max / unit;
    rec.rms = std::ldexp(rec.rms, e);
    rec.max = std::ldexp(rec.max, e);
    rec.surface_rms = rec.surface_max = rec.surface_rms_relative = rec.surface_max_relative = not_measured;
    if (options.report_each) measure_surface(rec);
    if (robust) {
      rec.robust_scale = std::ldexp(current_scale, e);
      measure_criterion(distances);
      const RobustSums& r = current_robust;
      const double inlier = r.inlier_weight > 0 ? std::sqrt(r.inlier_squares / r.inlier_weight) : 0.0;
      rec.robust_loss_relative = current_loss / unit;
      rec.robust_loss = std::ldexp(current_loss, e);
      rec.inlier_rms_relative = inlier / unit;
      rec.inlier_rms = std::ldexp(inlier, e);
      rec.robust_cut = r.cut;
    }
    rec.solver_iterations = solver_iterations;
    rec.seconds = seconds_since(t0);
    out.history.push_back(rec);
    if (progress) progress(rec);
    return rec;
  };
  const auto footpoints = [&](auto&& fn) { return phases.timed(&ApproximationTimings::footpoints, fn); };

  CsrMatrix K;
  if (options.fairness > 0) {
    FairnessQuadrature quadrature;
    quadrature.depth = options.fairness_depth;
    K = fairness_matrix(topology,
                        Rules{surface.scheme(), surface.boundary(), energy_tags(surface.tags(), SemiSharp::Sharp)},
                        1.0, 0.0, quadrature);
  }
  const bool cg = options.update == ApproximationUpdate::CG;
  out.stop_reason = "max_iter";
  int searched = 0;  // the iteration after which every footpoint was last searched for afresh
  int fresh_iteration = -1;  // the iteration of the chunks' last fresh search, kept for the final step
  int done = 0;
  // Each chunk's rows and sums (summed in the chunks' order), timed as "normal" less the chunks' rows.
  const auto sums = [&] {
    NormalSums s = phases.timed(&ApproximationTimings::normal, [&] {
      return robust ? chunks.robust_normal_sums(options.tangential, options.robust, current_scale)
                    : chunks.normal_sums(options.tangential);
    });
    phases.wall.normal -= s.rows_seconds;
    phases.cpu.normal -= s.rows_cpu;
    phases.wall.rows += s.rows_seconds;
    phases.cpu.rows += s.rows_cpu;
    return s;
  };
  // How far an update moved the control vertices that a face uses, over the diagonal: {largest, RMS}.
  const auto moved = [&](const std::vector<double>& before) -> std::array<double, 2> {
    double largest = 0.0;
    std::vector<double> squares;
    squares.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (topology.n_unreferenced() > 0 && topology.is_unreferenced(i)) continue;
      const double d[3] = {V[3 * i] - before[3 * i], V[3 * i + 1] - before[3 * i + 1], V[3 * i + 2] - before[3 * i + 2]};
      const double s2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      largest = std::max(largest, s2);
      squares.push_back(s2);
    }
    const double rms_move = squares.empty() ? 0.0 : std::sqrt(pairwise_sum(squares.data(), squares.size()) /
                                                                  static_cast<double>(squares.size()));
    return {std::sqrt(largest) / unit, rms_move / unit};
  };
  std::vector<double> V_before;
  // One update of V from the current footpoints (step 2): the solver's iterations.
  const auto update = [&](int it) -> long long {
    poll_interrupt();
    V_before = V;
    NormalSums S = sums();
    long long used = 0;
    std::vector<double> rhs = std::move(S.rhs);
    if (cg) {
      NormalEquations M = phases.timed(&ApproximationTimings::normal, [&] {
        NormalEquations eq(std::move(S.matrix), K, options.fairness, options.proximal);
        for (std::size_t i = 0; i < rhs.size(); ++i) rhs[i] += eq.mu() * V[i];
        return eq;
      });
      const PcgResult res = phases.timed(&ApproximationTimings::solve, [&] {
        return M.solve(rhs.data(), V.data(), options.solver_tol, options.solver_max_iter, 0);
      });
      used = res.iterations;
    } else {
      Sparse M = phases.timed(&ApproximationTimings::normal, [&] {
        NormalMatrix& N = S.matrix;
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
        for (std::size_t i = 0; i < rhs.size(); ++i) rhs[i] += mu * V[i];
        return m;
      });
      used = phases.timed(&ApproximationTimings::solve,
                          [&] { return lspia(M, rhs, V, options.solver_tol, options.solver_max_iter); });
    }
    for (std::size_t i = 0; i < V.size(); ++i)
      if (!std::isfinite(V[i]))
        throw ParameterError("approximation's update " + std::to_string(it) + " gave control vertex " +
                             std::to_string(i / 3) + " a value that is not finite");
    set_vertices(V);
    return used;
  };

  // Coarse iterations (step 1b): updates on the fixed sample until coarse_iterations ran or one lowered the
  // sample's lowest criterion by at most coarse_tol of it (near the noise floor the sample's fit follows its own
  // noise, which the updates on all points then take back: no gain, and the stop rule waits for it); the last one's
  // footpoints are all points'. At least window + 1 updates stay for all points: the first takes back what the
  // sample's fit made of the sample's own points, the stop rule's window follows it.
  const std::size_t n_used = n - topology.n_unreferenced();
  const double wanted = options.coarse_points * static_cast<double>(n_used);
  const int coarse_most = wanted <= 0.5 * static_cast<double>(k)
                              ? std::max(0, std::min(options.coarse_iterations, options.iterations - options.window - 1))
                              : 0;
  if (coarse_most > 0) chunks.set_sample(static_cast<std::size_t>(wanted));
  DistanceSums feet = footpoints([&] { return chunks.search(options.footpoints); });
  measure_scale();
  record(0, feet, 0, {0.0, 0.0});
  std::vector<double> sample_bests{criterion(feet)};  // the sample's lowest criterion so far, after each update
  int coarse = 0;
  for (int it = 1; it <= coarse_most; ++it) {
    const long long used = update(it);
    bool last = it == coarse_most;
    if (!last) {
      feet = footpoints([&] { return chunks.refine(options.footpoints); });
      measure_scale();
      sample_bests.push_back(std::min(sample_bests.back(), measure_criterion(feet)));
      last = rms_levelled(sample_bests, options.coarse_tol, 1);
    }
    if (last) {
      chunks.set_sample(0);
      feet = footpoints([&] { return chunks.search(options.footpoints); });
      measure_scale();
    }
    record(it, feet, used, moved(V_before));
    if (last) {
      coarse = it;
      break;
    }
  }
  done = coarse;
  chunks.keep_best();
  struct Best {
    double rms;
    std::vector<double> V;
    int iteration;
  } best{criterion(feet), V, coarse};
  std::vector<double> bests{best.rms};  // the lowest RMS so far, after each iteration on all points
  searched = coarse;

  for (int it = coarse + 1; it <= options.iterations; ++it) {
    const long long used = update(it);
    // The last iteration's footpoints are the fresh search's (refine_fresh: re-projection and search in one, to
    // full precision): its record holds true distances, and when it is the iterate returned, the final search is
    // this one.
    const bool last = it == options.iterations;
    feet = footpoints([&] { return last ? chunks.refine_fresh(options.footpoints) : chunks.refine(options.footpoints); });
    measure_scale();
    done = it;
    const ApproximationRecord rec = record(it, feet, used, moved(V_before));
    const double current = criterion(feet);
    if (current <= best.rms) {
      best = Best{current, V, it};
      chunks.keep_best();
    }
    if (last && best.iteration == it) fresh_iteration = it;
    bests.push_back(best.rms);
    if (rec.rms_relative <= options.exact) {
      out.stop_reason = "exact";
      break;
    }
    const bool levelled = rms_levelled(bests, options.tol, options.window);
    if (it == options.iterations || it - searched < options.window || !levelled) continue;
    // Re-projection from the previous footpoints finds local minima of the distance: before stopping, every
    // footpoint is searched for afresh (every start that may lie near a closer point: FootpointSearch::closer)
    // and the closer one kept; a gain of more than tol goes on.
    searched = it;
    const DistanceSums merged =
        footpoints([&] { return chunks.search_fresh(options.footpoints, options.closer * unit); });
    // (The footpoints' gain is a gain in distance: RMS against RMS, with a robust loss too.)
    if (rms(merged) < (1 - options.tol) * rms(feet)) {
      chunks.keep_fresh(options.closer * unit);
      measure_scale();
      continue;
    }
    out.stop_reason = "converged";
    if (best.iteration == it) fresh_iteration = it;  // the fresh search was made on the iterate returned: reused
    break;
  }
  // Reported distances are true distances (issue 33, 6): re-projection from the previous footpoints keeps a point
  // in a local minimum of its distance, so the returned iterate's footpoints are searched for afresh (every start
  // that may lie near a closer point: FootpointSearch::closer), any closer one kept, and its record measured again
  // from them before the result reports it.
  if (best.iteration != fresh_iteration) {
    // The fresh search starts from the current footpoints, which must be the surface's: those of an earlier
    // iterate returned are refined onto it first.
    if (best.iteration != done) {
      set_vertices(best.V);
      footpoints([&] { return chunks.refine(options.footpoints); });
    }
    footpoints([&] { return chunks.search_fresh(options.footpoints, options.closer * unit); });
  }
  const DistanceSums final_feet = chunks.keep_fresh_in_best();
  ApproximationRecord& rec = out.history[static_cast<std::size_t>(best.iteration)];
  if (!options.report_each) measure_surface(rec);  // the surface holds the returned iterate
  if (final_feet.changed > 0) {
    const double r = rms(final_feet), m = final_feet.max;
    rec.rms_relative = r / unit;
    rec.max_relative = m / unit;
    rec.rms = std::ldexp(r, e);
    rec.max = std::ldexp(m, e);
  }
  // The iterate of the lowest RMS distance (an update that raised it is not returned).
  out.iterations = done;
  out.coarse_iterations = coarse;
  out.best_iteration = best.iteration;
  out.control_vertices = std::move(best.V);
  detail::scale_pow2(out.control_vertices.data(), out.control_vertices.size(), e);
  surface.set_vertices(out.control_vertices.data());
  out.footpoints = chunks.best_footpoints();
  if (robust) {  // the returned iterate's record's: its scale and cut before the final search
    out.robust_scale = rec.robust_scale;
    out.robust_outliers = rec.robust_cut;
  }
  detail::scale_pow2(out.footpoints.distances.data(), out.footpoints.distances.size(), e);
  out.diagonal = std::ldexp(diagonal, e);
  out.seconds = phases.wall;
  out.cpu_seconds = phases.cpu;
  out.seconds.total = seconds_since(t0);
  out.cpu_seconds.total = cpu_now() - c0;
  return out;
}

ApproximationResult approximate(LimitSurface& surface, const double* points, std::size_t k, const double* weights,
                                const ApproximationOptions& options, const ApproximationProgress& progress) {
  InMemoryChunks chunks(surface, points, k, weights, options.chunk_points);
  return approximate(surface, chunks, options, progress);
}

}  // namespace sorpia
