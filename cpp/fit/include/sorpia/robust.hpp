#pragma once
/// @file robust.hpp
/// Robust weights for approximation (docs/approximation.md, "Robustness"):
/// iteratively reweighted least squares. Before each update every point's
/// weight is multiplied by a factor of its footpoint distance d,
///
///   w(d) = psi(r) / r,  r = d / (c s),
///
/// from an M-estimator's loss rho (psi = rho'/2), so that a point far from
/// where the rest of the data puts the surface (an outlier, or many
/// duplicates of one) pulls on the cage with a bounded, vanishing, force.
/// s is a robust scale of the distances: a quantile of them (by weight), the
/// same for every point. The fit then minimises sum_i w_i rho(d_i): the
/// run's criterion (robust_rms) replaces the RMS distance in the choice of
/// the iterate returned and in the stop rule.
///
/// Made for data in chunks (out of core, or on a cluster's workers): the
/// scale comes from a DistanceHistogram, whose per-chunk histograms add up
/// (merge) to the histogram of all the points, whatever the order; the
/// factors and the criterion's sums are per point given the scale.

#include <cstddef>
#include <string>
#include <vector>

namespace sorpia {

/// The loss of a robust fit, as a weight function of r = d / (c s).
enum class RobustLoss {
  None,    ///< least squares: w = 1 (rho = d^2)
  Cauchy,  ///< w = 1 / (1 + r^2): a far point's pull falls as 1 / d (rho = (c s)^2 log(1 + r^2))
  Tukey,   ///< Tukey's biweight: w = (1 - r^2)^2 for r < 1, else 0: a point beyond c s does not pull at all
};

/// The loss by name ("none", "cauchy", "tukey"); ParameterError naming the
/// option `what` and the names otherwise.
RobustLoss robust_loss(const std::string& name, const char* what = "robust");
/// The name of a loss (robust_loss's inverse).
const char* robust_loss_name(RobustLoss loss);

/// A robust fit's settings (ApproximationOptions::robust). Value-initialised:
/// least squares (the quantile and c unused); robust_options gives each
/// loss's defaults.
struct RobustOptions {
  RobustLoss loss = RobustLoss::None;
  /// s: this quantile of the distances (by weight), in (0, 1).
  double quantile = 0.9;
  /// c, the loss's tuning constant in units of s, finite, > 0.
  double c = 1.0;
};

/// A loss's default settings, the one place they are set (approximation's
/// default is robust_options(RobustLoss::Tukey); the bindings, the Python
/// API and the command line take them from here; docs/approximation.md,
/// "Robustness", has the measurements): the scale s at the 90th percentile
/// of the distances; Tukey's biweight cutting at c = 30 s, beyond the
/// largest distance of every clean scan measured (so that clean data is
/// fitted as by least squares) and short of points a tenth of the diagonal
/// away; Cauchy's at c = 12 s, where its slower fall of the weight damps
/// those points as much. None: RobustOptions{}.
RobustOptions robust_options(RobustLoss loss);

/// The distances' weighted histogram in bins of ratio 2^(1/kBinsPerOctave)
/// from `unit` * 2^kLowestOctave up to `unit` * 2^kHighestOctave (the
/// smaller ones in a bin of zeros, the larger in the last): a scale's
/// statistic that chunks of points compute on their own and merge.
class DistanceHistogram {
 public:
  static constexpr int kBinsPerOctave = 32;
  static constexpr int kLowestOctave = -64;
  static constexpr int kHighestOctave = 64;

  /// @param unit  the distances' unit (the data's diagonal), finite, > 0
  explicit DistanceHistogram(double unit);
  /// A copy of a histogram of `unit` from its total() and mass(), as
  /// another process sends them; ParameterError for another count of bins,
  /// or a total or mass not finite or negative.
  DistanceHistogram(double unit, double total, std::vector<double> mass);
  double unit() const { return unit_; }
  /// The weight in each bin: the bin of zeros, then the bins in order.
  const std::vector<double>& mass() const { return mass_; }
  /// Adds k distances (finite, >= 0) with their weights (nullptr: 1 each).
  void add(const double* distances, const double* weights, std::size_t k);
  /// Adds another histogram of the same unit (std::invalid_argument otherwise).
  void merge(const DistanceHistogram& other);
  /// The total weight added.
  double total() const { return total_; }
  /// The q-quantile of the distances by weight, q in [0, 1]: the distance
  /// below which a fraction q of the weight lies, interpolated
  /// geometrically within its bin (a relative error below 2^(1/32) - 1 =
  /// 2.2%); 0 when the weight below it is all in the bin of zeros; 0 for an
  /// empty histogram.
  double quantile(double q) const;

 private:
  double unit_;
  double total_ = 0.0;
  std::vector<double> mass_;  // [0]: below the lowest edge; [1 + b]: bin b
};

/// The scale s of the distances: `options.quantile` of the histogram, but at
/// least `floor` (> 0: with data on the surface to rounding the scale would
/// be 0 and every point an outlier).
double robust_scale(const DistanceHistogram& histogram, const RobustOptions& options, double floor);

/// out[i] = w(distances[i]) for the loss at scale s (> 0): the factor of
/// point i's weight in the next update, in [0, 1]. out may be distances.
void robust_factors(const RobustOptions& options, double scale, const double* distances, std::size_t k,
                    double* out);

/// A robust fit's sums over points at a scale s (> 0), added over chunks
/// (add): the criterion's sum w rho(d), and the split of the points at the
/// cut c s (with Tukey the points beyond it do not pull at all; with Cauchy
/// they pull little), so that a report can give the distances of the
/// points the fit keeps beside the count of those it cuts.
struct RobustSums {
  /// sum_i w_i rho(d_i), rho scaled so that rho(d) = d^2 + O(d^4 / (c s)^2)
  /// for small d: with RobustLoss::None the sum of squares.
  double loss = 0.0;
  /// sum w d^2 and sum w over the points within the cut (d <= c s).
  double inlier_squares = 0.0, inlier_weight = 0.0;
  /// The points of weight > 0 beyond the cut (d > c s).
  long long cut = 0;
  void add(const RobustSums& other);
};

/// The sums of k distances with their weights (nullptr: 1 each; a weight 0
/// adds nothing) for the loss at scale s.
RobustSums robust_sums(const RobustOptions& options, double scale, const double* distances, const double* weights,
                       std::size_t k);

}  // namespace sorpia
