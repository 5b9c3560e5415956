#include "sorpia/robust.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "sorpia/detail/parallel.hpp"
#include "sorpia/detail/repr.hpp"
#include "sorpia/errors.hpp"

namespace sorpia {

RobustLoss robust_loss(const std::string& name, const char* what) {
  if (name == "none") return RobustLoss::None;
  if (name == "cauchy") return RobustLoss::Cauchy;
  if (name == "tukey") return RobustLoss::Tukey;
  throw ParameterError(std::string(what) + " = '" + name + "' must be one of none, cauchy, tukey");
}

RobustOptions robust_options(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::Cauchy: return {loss, 0.9, 12.0};
    case RobustLoss::Tukey: return {loss, 0.9, 30.0};
    case RobustLoss::None: break;
  }
  return RobustOptions{};
}

const char* robust_loss_name(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::Cauchy: return "cauchy";
    case RobustLoss::Tukey: return "tukey";
    case RobustLoss::None: break;
  }
  return "none";
}

namespace {
// Points per task of the per-point loops below, at least.
constexpr std::size_t kPointsPerTask = 65536;

constexpr int kBins = (DistanceHistogram::kHighestOctave - DistanceHistogram::kLowestOctave) *
                      DistanceHistogram::kBinsPerOctave;
}  // namespace

DistanceHistogram::DistanceHistogram(double unit) : unit_(unit), mass_(1 + static_cast<std::size_t>(kBins), 0.0) {
  if (!(std::isfinite(unit) && unit > 0))
    throw std::invalid_argument("DistanceHistogram: the unit must be a finite number > 0");
}

DistanceHistogram::DistanceHistogram(double unit, double total, std::vector<double> mass)
    : DistanceHistogram(unit) {
  if (!(std::isfinite(total) && total >= 0))
    throw ParameterError("a distance histogram's total weight is " + detail::repr(total) +
                         ": it must be a finite number >= 0");
  if (mass.size() != mass_.size())
    throw ParameterError("a distance histogram has " + std::to_string(mass_.size()) + " bins, not " +
                         std::to_string(mass.size()));
  for (std::size_t b = 0; b < mass.size(); ++b) {
    if (!(std::isfinite(mass[b]) && mass[b] >= 0))
      throw ParameterError("a distance histogram's bin " + std::to_string(b) + " holds " + detail::repr(mass[b]) +
                           ": a mass must be a finite number >= 0");
  }
  total_ = total;
  mass_ = std::move(mass);
}

void DistanceHistogram::add(const double* distances, const double* weights, std::size_t k) {
  // Each distance's bin (in ranges of points per task), then the weights added up in the points' order.
  const std::unique_ptr<std::uint32_t[]> bins(new std::uint32_t[k]);
  const int tasks = detail::task_count(k, kPointsPerTask);
  detail::for_each_index(tasks > 1, tasks, k, [&](std::size_t i) {
    const double x = distances[i] / unit_;
    std::uint32_t slot = 0;  // the bin of zeros: below unit 2^kLowestOctave
    if (x > 0) {
      // bin b holds [2^(lo + b / B), 2^(lo + (b + 1) / B)); the largest distances stay in the last bin
      const double b = std::floor((std::log2(x) - kLowestOctave) * kBinsPerOctave);
      if (b >= 0) slot = 1 + static_cast<std::uint32_t>(std::min(b, static_cast<double>(kBins - 1)));
    }
    bins[i] = slot;
  });
  for (std::size_t i = 0; i < k; ++i) {
    const double w = weights ? weights[i] : 1.0;
    if (w == 0.0) continue;
    mass_[bins[i]] += w;
    total_ += w;
  }
}

void DistanceHistogram::merge(const DistanceHistogram& other) {
  if (other.unit_ != unit_) throw std::invalid_argument("DistanceHistogram::merge: the units differ");
  for (std::size_t i = 0; i < mass_.size(); ++i) mass_[i] += other.mass_[i];
  total_ += other.total_;
}

double DistanceHistogram::quantile(double q) const {
  if (!(total_ > 0)) return 0.0;
  const double target = std::clamp(q, 0.0, 1.0) * total_;
  double below = mass_[0];
  if (target <= below) return 0.0;
  for (std::size_t b = 0; b < static_cast<std::size_t>(kBins); ++b) {
    const double m = mass_[1 + b];
    if (m > 0 && below + m >= target) {
      const double t = std::clamp((target - below) / m, 0.0, 1.0);
      return unit_ * std::exp2(kLowestOctave + (static_cast<double>(b) + t) / kBinsPerOctave);
    }
    below += m;
  }
  // rounding left the target above the last bin's cumulative mass: the upper edge of the last nonempty bin
  for (std::size_t b = static_cast<std::size_t>(kBins); b-- > 0;)
    if (mass_[1 + b] > 0) return unit_ * std::exp2(kLowestOctave + (static_cast<double>(b) + 1) / kBinsPerOctave);
  return 0.0;
}

double robust_scale(const DistanceHistogram& histogram, const RobustOptions& options, double floor) {
  return std::max(histogram.quantile(options.quantile), floor);
}

void robust_factors(const RobustOptions& options, double scale, const double* distances, std::size_t k,
                    double* out) {
  const double cs = options.c * scale;
  const int tasks = detail::task_count(k, kPointsPerTask);
  detail::for_each_index(tasks > 1, tasks, k, [&](std::size_t i) {
    const double r = distances[i] / cs;
    switch (options.loss) {
      case RobustLoss::None: out[i] = 1.0; break;
      case RobustLoss::Cauchy: out[i] = 1.0 / (1.0 + r * r); break;
      case RobustLoss::Tukey: {
        const double u = 1.0 - r * r;
        out[i] = r < 1.0 ? u * u : 0.0;
        break;
      }
    }
  });
}

void RobustSums::add(const RobustSums& other) {
  loss += other.loss;
  inlier_squares += other.inlier_squares;
  inlier_weight += other.inlier_weight;
  cut += other.cut;
}

RobustSums robust_sums(const RobustOptions& options, double scale, const double* distances, const double* weights,
                       std::size_t k) {
  const double cs = options.c * scale, cs2 = cs * cs;
  // Each point's loss (in ranges of points per task), then the sums in the points' order.
  const std::unique_ptr<double[]> loss(new double[k]);
  const int tasks = detail::task_count(k, kPointsPerTask);
  detail::for_each_index(tasks > 1, tasks, k, [&](std::size_t i) {
    const double w = weights ? weights[i] : 1.0;
    const double d = distances[i], r = d / cs;
    double rho = d * d;
    if (options.loss == RobustLoss::Cauchy) {
      rho = cs2 * std::log1p(r * r);
    } else if (options.loss == RobustLoss::Tukey) {
      // (c s)^2 / 3 (1 - (1 - x)^3), x = r^2 <= 1, expanded: no cancellation for small r
      const double x = std::min(r * r, 1.0);
      rho = cs2 / 3.0 * (x * (3.0 - 3.0 * x + x * x));
    }
    loss[i] = w * rho;
  });
  RobustSums sums;
  for (std::size_t i = 0; i < k; ++i) {
    const double w = weights ? weights[i] : 1.0;
    if (w == 0.0) continue;
    const double d = distances[i];
    sums.loss += loss[i];
    if (d <= cs) {
      sums.inlier_squares += w * d * d;
      sums.inlier_weight += w;
    } else {
      ++sums.cut;
    }
  }
  return sums;
}

}  // namespace sorpia
