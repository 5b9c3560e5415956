// The robust weights of approximation (sorpia/robust.hpp): the histogram's
// quantile against the exact order statistic of the same distances, chunks'
// histograms merged against the histogram of all the points, and the weight
// functions against the derivative of their loss (IRLS: w(d) = rho'(d) / 2d).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "expect_error.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/approximation.hpp"
#include "sorpia/robust.hpp"

namespace {

using sorpia::DistanceHistogram;
using sorpia::RobustLoss;
using sorpia::RobustOptions;

std::vector<double> lognormal(std::size_t k, unsigned seed) {
  std::mt19937 rng(seed);
  std::lognormal_distribution<double> g(-6.0, 1.5);  // distances around 2.5e-3 of a unit diagonal, 3 decades wide
  std::vector<double> d(k);
  for (double& x : d) x = g(rng);
  return d;
}

// The exact q-quantile by weight: the smallest distance with at least q of the weight at or below it.
double exact_quantile(std::vector<double> d, std::vector<double> w, double q) {
  std::vector<std::size_t> order(d.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return d[a] < d[b]; });
  double total = 0.0, below = 0.0;
  for (double x : w) total += x;
  for (std::size_t i : order) {
    below += w[i];
    if (below >= q * total) return d[i];
  }
  return d[order.back()];
}

TEST(Robust, QuantileWithinItsBinOfTheExactOne) {
  const auto d = lognormal(20000, 1);
  std::vector<double> w(d.size());
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.2, 3.0);
  for (double& x : w) x = u(rng);
  DistanceHistogram unweighted(1.0), weighted(1.0);
  unweighted.add(d.data(), nullptr, d.size());
  weighted.add(d.data(), w.data(), d.size());
  const double bin = std::exp2(1.0 / DistanceHistogram::kBinsPerOctave) - 1.0;  // 2.2%
  for (double q : {0.1, 0.5, 0.9, 0.99}) {
    const double exact = exact_quantile(d, std::vector<double>(d.size(), 1.0), q);
    EXPECT_NEAR(unweighted.quantile(q), exact, bin * exact) << q;
    const double exact_w = exact_quantile(d, w, q);
    EXPECT_NEAR(weighted.quantile(q), exact_w, bin * exact_w) << q;
  }
  EXPECT_DOUBLE_EQ(unweighted.total(), 20000.0);
}

TEST(Robust, WeightTwoIsTwoCopies) {
  const auto d = lognormal(3000, 3);
  std::vector<double> w(d.size(), 1.0), doubled(d);
  for (std::size_t i = 0; i < d.size(); i += 3) {
    w[i] = 2.0;
    doubled.push_back(d[i]);
  }
  DistanceHistogram a(0.5), b(0.5);
  a.add(d.data(), w.data(), d.size());
  b.add(doubled.data(), nullptr, doubled.size());
  for (double q : {0.25, 0.5, 0.75}) EXPECT_DOUBLE_EQ(a.quantile(q), b.quantile(q)) << q;
}

TEST(Robust, ChunksMergedAreTheWhole) {
  const auto d = lognormal(10007, 4);
  DistanceHistogram whole(2.0), merged(2.0);
  whole.add(d.data(), nullptr, d.size());
  for (std::size_t start = 0; start < d.size(); start += 999) {  // uneven chunks, merged last to first
    DistanceHistogram chunk(2.0);
    chunk.add(d.data() + start, nullptr, std::min<std::size_t>(999, d.size() - start));
    merged.merge(chunk);
  }
  for (double q : {0.05, 0.5, 0.95}) EXPECT_EQ(merged.quantile(q), whole.quantile(q)) << q;
  EXPECT_THROW(merged.merge(DistanceHistogram(1.0)), std::invalid_argument);
}

TEST(Robust, ZerosAndTheExtremes) {
  DistanceHistogram h(1.0);
  EXPECT_EQ(h.quantile(0.5), 0.0);  // empty
  const std::vector<double> d = {0.0, 0.0, 0.0, 1e-30, 1e30, 1e30};
  h.add(d.data(), nullptr, d.size());
  EXPECT_EQ(h.quantile(0.5), 0.0);  // half the weight at 0 or below 2^-64
  EXPECT_GE(h.quantile(0.99), std::exp2(DistanceHistogram::kHighestOctave - 1));  // the last bin holds the largest
  EXPECT_EQ(sorpia::robust_scale(h, RobustOptions{RobustLoss::Cauchy, 0.5, 1.0}, 1e-9), 1e-9);  // the floor
}

TEST(Robust, WeightsAreTheLossDerivative) {
  for (RobustLoss loss : {RobustLoss::None, RobustLoss::Cauchy, RobustLoss::Tukey}) {
    const RobustOptions o{loss, 0.5, 3.0};
    const double s = 0.01;
    for (double d : {1e-4, 0.005, 0.02, 0.029, 0.05, 1.0}) {
      double w = 0.0;
      sorpia::robust_factors(o, s, &d, 1, &w);
      const double h = 1e-7 * d;
      const double up = d + h, down = d - h;
      const double slope = (sorpia::robust_sums(o, s, &up, nullptr, 1).loss -
                            sorpia::robust_sums(o, s, &down, nullptr, 1).loss) / (2 * h);
      EXPECT_NEAR(w, slope / (2 * d), 1e-6) << sorpia::robust_loss_name(loss) << " d " << d;
      EXPECT_GE(w, 0.0);
      EXPECT_LE(w, 1.0);
    }
    // Near 0 every loss is d^2: the criterion is the RMS distance where no point is far.
    const double d = 1e-5;
    EXPECT_NEAR(sorpia::robust_sums(o, s, &d, nullptr, 1).loss, d * d, 1e-6 * d * d) << sorpia::robust_loss_name(loss);
  }
  // Tukey: beyond c s no pull, and the loss is flat there; Cauchy: the pull c s / d falls as 1 / d.
  const double far = 1.0;
  double w = 1.0;
  sorpia::robust_factors(RobustOptions{RobustLoss::Tukey, 0.5, 3.0}, 0.01, &far, 1, &w);
  EXPECT_EQ(w, 0.0);
  sorpia::robust_factors(RobustOptions{RobustLoss::Cauchy, 0.5, 3.0}, 0.01, &far, 1, &w);
  EXPECT_NEAR(w * far, 0.03 * 0.03 / far, 1e-3 * 0.03 * 0.03 / far);
}

TEST(Robust, SumsSplitThePointsAtTheCut) {
  // Against a direct count: the points within c s (weighted squares and weight) and the points of weight > 0
  // beyond it; a weight 0 adds nothing; chunks' sums added equal the sums of all the points.
  const std::vector<double> d = {0.0, 0.01, 0.029, 0.03, 0.031, 0.5, 2.0, 0.02};
  const std::vector<double> w = {1.0, 2.0, 0.5, 1.0, 1.0, 3.0, 0.0, 0.0};
  for (RobustLoss loss : {RobustLoss::None, RobustLoss::Cauchy, RobustLoss::Tukey}) {
    const RobustOptions o{loss, 0.5, 3.0};  // c s = 0.03
    const sorpia::RobustSums all = sorpia::robust_sums(o, 0.01, d.data(), w.data(), d.size());
    double squares = 0.0, weight = 0.0;
    long long cut = 0;
    for (std::size_t i = 0; i < d.size(); ++i) {
      if (w[i] == 0.0) continue;
      if (d[i] <= 0.03 + 1e-15) {
        squares += w[i] * d[i] * d[i];
        weight += w[i];
      } else {
        ++cut;
      }
    }
    EXPECT_NEAR(all.inlier_squares, squares, 1e-15);
    EXPECT_EQ(all.inlier_weight, weight);
    EXPECT_EQ(all.cut, cut);
    EXPECT_EQ(cut, 2);
    sorpia::RobustSums parts = sorpia::robust_sums(o, 0.01, d.data(), w.data(), 3);
    parts.add(sorpia::robust_sums(o, 0.01, d.data() + 3, w.data() + 3, d.size() - 3));
    EXPECT_NEAR(parts.loss, all.loss, 1e-15);
    EXPECT_EQ(parts.cut, all.cut);
    EXPECT_EQ(parts.inlier_weight, all.inlier_weight);
  }
}

TEST(Robust, DefaultsPerLoss) {
  // The one place of the defaults: approximation's default is Tukey's; each loss its own c; value-initialised
  // settings are least squares.
  const RobustOptions tukey = sorpia::robust_options(RobustLoss::Tukey);
  const RobustOptions cauchy = sorpia::robust_options(RobustLoss::Cauchy);
  EXPECT_EQ(tukey.loss, RobustLoss::Tukey);
  EXPECT_EQ(tukey.quantile, 0.9);
  EXPECT_EQ(tukey.c, 30.0);
  EXPECT_EQ(cauchy.loss, RobustLoss::Cauchy);
  EXPECT_EQ(cauchy.quantile, 0.9);
  EXPECT_EQ(cauchy.c, 12.0);
  EXPECT_EQ(sorpia::robust_options(RobustLoss::None).loss, RobustLoss::None);
  EXPECT_EQ(RobustOptions{}.loss, RobustLoss::None);
  const sorpia::ApproximationOptions defaults;
  EXPECT_EQ(defaults.robust.loss, tukey.loss);
  EXPECT_EQ(defaults.robust.quantile, tukey.quantile);
  EXPECT_EQ(defaults.robust.c, tukey.c);
}

TEST(Robust, LossNames) {
  for (RobustLoss loss : {RobustLoss::None, RobustLoss::Cauchy, RobustLoss::Tukey})
    EXPECT_EQ(sorpia::robust_loss(sorpia::robust_loss_name(loss)), loss);
  sorpia_test::expect_error<sorpia::ParameterError>([] { sorpia::robust_loss("huber"); },
                                                    {"robust = 'huber'", "none, cauchy, tukey"});
}

}  // namespace
