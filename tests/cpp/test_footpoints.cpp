// FootpointSearch and PointIndex::nearest_accepted against brute force: a
// sorted scan of every point for the k-d tree, and for the re-search of
// footpoints refinement from a start in every face (a dense set of starts
// whose closest result is the closest point of the surface). Tolerance 1e-8
// of the diagonal: near a focal point of the surface (a point about a radius
// of curvature off it) Gauss-Newton converges slowly, and a refinement's
// 100 steps leave it that far from its minimum.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "expect_error.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/footpoints.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/surface.hpp"
#include "sorpia/topology.hpp"

namespace {

using sorpia::Boundary;
using sorpia::Scheme;

TEST(PointIndex, LeastRankedIsTheSortedScanOfTheRanksBelowTheBound) {
  // rank = distance - slack_i (slack_i in [0, 0.2], +inf for every third
  // point): the k least below the bound, as a scan of every point finds them,
  // with the slack given per query (0.2) or per point (set_slack).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> points(3 * 2000), queries(3 * 50), slack(2000);
  for (double& x : points) x = u(rng);
  for (double& x : queries) x = 1.2 * u(rng);
  for (double& s : slack) s = 0.1 + 0.1 * u(rng);
  sorpia::PointIndex with_slack(points.data(), 2000);
  with_slack.set_slack(slack.data());
  const sorpia::PointIndex& per_point = with_slack;
  const sorpia::PointIndex plain(points.data(), 2000);
  const auto rank = [&](std::int64_t i, double d) {
    return i % 3 == 0 ? std::numeric_limits<double>::infinity() : d - slack[static_cast<std::size_t>(i)];
  };
  for (const sorpia::PointIndex* index : {&plain, &per_point})
  for (std::size_t q = 0; q < 50; ++q)
    for (const double bound : {0.05, 0.4, 10.0})
      for (const std::size_t k : {std::size_t{1}, std::size_t{7}, std::size_t{3000}}) {
        std::vector<std::pair<double, std::int64_t>> scan;
        for (std::int64_t i = 0; i < 2000; ++i) {
          const double* p = &points[3 * static_cast<std::size_t>(i)];
          const double* x = &queries[3 * q];
          const double r = rank(i, std::sqrt((p[0] - x[0]) * (p[0] - x[0]) + (p[1] - x[1]) * (p[1] - x[1]) +
                                             (p[2] - x[2]) * (p[2] - x[2])));
          if (r < bound) scan.emplace_back(r, i);
        }
        std::sort(scan.begin(), scan.end());
        scan.resize(std::min(scan.size(), k));
        std::vector<std::int64_t> found(std::min<std::size_t>(k, 2000));
        std::vector<double> value(found.size());
        const std::size_t got = index->least_ranked(&queries[3 * q], bound, 0.2, k, rank, found.data(), value.data());
        ASSERT_EQ(got, scan.size()) << "query " << q << " bound " << bound << " k " << k << " per point "
                                    << (index == &per_point);
        for (std::size_t j = 0; j < got; ++j) {
          EXPECT_EQ(found[j], scan[j].second);
          EXPECT_NEAR(value[j], scan[j].first, 1e-15);
        }
      }
}

// A bumpy closed surface: icosphere(2)'s control vertices moved radially by
// 0.35 sin(5x) sin(5y) sin(5z), and points around it up to 0.25 off it, where
// the nearest grid sample's basin is often not the closest point's.
struct Bumpy {
  sorpia::Mesh cage = sorpia::icosphere(2);
  std::vector<double> points;
  Bumpy(std::size_t k) {
    for (std::size_t i = 0; i < cage.n_vertices(); ++i) {
      double* v = &cage.vertices[3 * i];
      const double r = 1.0 + 0.35 * std::sin(5 * v[0]) * std::sin(5 * v[1]) * std::sin(5 * v[2]);
      for (int c = 0; c < 3; ++c) v[c] *= r;
    }
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> radius(0.75, 1.25);
    for (std::size_t i = 0; i < k; ++i) {
      double x[3] = {g(rng), g(rng), g(rng)};
      const double s = radius(rng) / std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
      for (double c : x) points.push_back(c * s);
    }
  }
};

// The closest point's distance by brute force: refinement from 4 starts in
// every face (the centre and points towards the corners), 400 steps at most,
// the least distance found.
std::vector<double> brute_force(const sorpia::LimitSurface& surface, const sorpia::Topology& topology,
                                const std::vector<double>& points) {
  const std::size_t k = points.size() / 3, m = topology.n_faces();
  const double starts[4][2] = {{1.0 / 3, 1.0 / 3}, {0.1, 0.1}, {0.8, 0.1}, {0.1, 0.8}};
  sorpia::Footpoints fp;
  std::vector<double> x;
  for (std::size_t i = 0; i < k; ++i)
    for (std::size_t f = 0; f < m; ++f)
      for (const auto& s : starts) {
        fp.face_ids.push_back(static_cast<std::int32_t>(f));
        fp.uv.push_back(s[0]);
        fp.uv.push_back(s[1]);
        x.insert(x.end(), &points[3 * i], &points[3 * i] + 3);
      }
  sorpia::FootpointOptions options;
  options.max_steps = 400;
  sorpia::refine_footpoints(surface, topology, x.data(), x.size() / 3, options, fp);
  std::vector<double> least(k);
  for (std::size_t i = 0; i < k; ++i)
    least[i] = *std::min_element(fp.distances.begin() + static_cast<std::ptrdiff_t>(i * m * 4),
                                 fp.distances.begin() + static_cast<std::ptrdiff_t>((i + 1) * m * 4));
  return least;
}

TEST(FootpointSearch, CloserFindsTheClosestPointWhereTheGridsNearestSampleMissesIt) {
  const Bumpy bumpy(200);
  const sorpia::Topology topology(bumpy.cage);
  const sorpia::LimitSurface surface(topology, bumpy.cage.vertices.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  const std::size_t k = bumpy.points.size() / 3;
  const sorpia::FootpointOptions options{4, 10, 8, 0.0};
  const sorpia::FootpointSearch search(surface, topology, options);
  sorpia::Footpoints fp = search.find(bumpy.points.data(), k);
  // find is closest_points, bit for bit.
  const sorpia::Footpoints direct = sorpia::closest_points(surface, topology, bumpy.points.data(), k, options);
  EXPECT_EQ(fp.distances, direct.distances);
  EXPECT_EQ(fp.face_ids, direct.face_ids);
  const std::vector<double> before = fp.distances;
  sorpia::Footpoints from_find = fp;  // closer told the footpoints are find's: the nearest sample not again
  search.closer(bumpy.points.data(), k, from_find, true);
  const std::size_t moved = search.closer(bumpy.points.data(), k, fp);
  const std::vector<double> least = brute_force(surface, topology, bumpy.points);
  const double diagonal = 2.0 * std::sqrt(3.0) * 1.35;  // at most: the cage within the sphere of radius 1.35
  std::size_t missed = 0;
  for (std::size_t i = 0; i < k; ++i) {
    missed += before[i] > least[i] + 1e-6 * diagonal;
    EXPECT_LE(fp.distances[i], before[i]) << "point " << i;
    EXPECT_LE(fp.distances[i], least[i] + 1e-8 * diagonal) << "point " << i << " before " << before[i] << " excess " << (fp.distances[i] - least[i]) / diagonal;
    EXPECT_GE(fp.distances[i], least[i] - 1e-8 * diagonal) << "point " << i;
    EXPECT_LE(from_find.distances[i], before[i]);
    EXPECT_NEAR(from_find.distances[i], least[i], 1e-8 * diagonal) << "point " << i;
    // The footpoint reported is that of its (face, u, v) on the surface.
    double p[3];
    surface.evaluate(&fp.face_ids[i], &fp.uv[2 * i], 1, p, nullptr, nullptr, nullptr);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(fp.positions[3 * i + c], p[c], 1e-14);
  }
  // The case is one where the grid's nearest sample misses: the re-search
  // has work, and moved every point it had to.
  EXPECT_GE(missed, 5u);
  EXPECT_GE(moved, missed);
  // A second re-search finds nothing closer.
  std::vector<double> once = fp.distances;
  search.closer(bumpy.points.data(), k, fp);
  for (std::size_t i = 0; i < k; ++i) EXPECT_GE(fp.distances[i], once[i] - 1e-12 * diagonal);
}

TEST(PointIndex, RefitToMovedPointsFindsTheNearestAsAScan) {
  // The tree built on points, refitted to them moved (by up to 0.05 and, for
  // every tenth point, across the cube): nearest is a scan of the moved points.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> points(3 * 3000), queries(3 * 200);
  for (double& x : points) x = u(rng);
  for (double& x : queries) x = 1.2 * u(rng);
  sorpia::PointIndex index(points.data(), 3000);
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = (i / 3) % 10 == 0 ? u(rng) : points[i] + 0.05 * u(rng);
  index.refit(points.data());
  std::vector<std::int64_t> found(200);
  std::vector<double> distance(200);
  index.nearest(queries.data(), 200, found.data(), distance.data());
  for (std::size_t q = 0; q < 200; ++q) {
    double least = std::numeric_limits<double>::infinity();
    std::int64_t at = -1;
    for (std::size_t i = 0; i < 3000; ++i) {
      const double* p = &points[3 * i];
      const double* x = &queries[3 * q];
      const double d = std::sqrt((p[0] - x[0]) * (p[0] - x[0]) + (p[1] - x[1]) * (p[1] - x[1]) + (p[2] - x[2]) * (p[2] - x[2]));
      if (d < least) least = d, at = static_cast<std::int64_t>(i);
    }
    EXPECT_EQ(found[q], at) << "query " << q;
    EXPECT_EQ(distance[q], least) << "query " << q;
  }
}

TEST(FootpointSearch, APreviousStatesSearchTakenOverGivesAFreshSearchsResults) {
  // A search on the bumpy surface taken over by one on the surface moved
  // (find and closer as a search built afresh on it), and closer from the
  // previous state's footpoints given as starts (distance +inf): the closest
  // points, as brute force finds them.
  const Bumpy bumpy(200);
  const sorpia::Topology topology(bumpy.cage);
  sorpia::LimitSurface surface(topology, bumpy.cage.vertices.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  const std::size_t k = bumpy.points.size() / 3;
  const sorpia::FootpointOptions options{4, 10, 8, 0.0};
  sorpia::FootpointSearch before(surface, topology, options);
  sorpia::Footpoints fp = before.find(bumpy.points.data(), k);
  std::vector<double> moved = bumpy.cage.vertices;
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i] *= 1.0 + 0.05 * std::sin(3.0 * static_cast<double>(i));
  surface.set_vertices(moved.data());
  const sorpia::FootpointSearch after(surface, topology, options, &before);
  const sorpia::FootpointSearch fresh(surface, topology, options);
  const sorpia::Footpoints a = after.find(bumpy.points.data(), k), b = fresh.find(bumpy.points.data(), k);
  EXPECT_EQ(a.face_ids, b.face_ids);
  EXPECT_EQ(a.distances, b.distances);
  sorpia::Footpoints ca = a, cb = b;
  after.closer(bumpy.points.data(), k, ca);
  fresh.closer(bumpy.points.data(), k, cb);
  EXPECT_EQ(ca.distances, cb.distances);
  std::fill(fp.distances.begin(), fp.distances.end(), std::numeric_limits<double>::infinity());
  after.closer(bumpy.points.data(), k, fp);
  const std::vector<double> least = brute_force(surface, topology, bumpy.points);
  const double diagonal = 2.0 * std::sqrt(3.0) * 1.45;  // at most: the cage within the sphere of radius 1.45
  for (std::size_t i = 0; i < k; ++i) EXPECT_NEAR(fp.distances[i], least[i], 1e-8 * diagonal) << "point " << i;
}

TEST(FootpointSearch, CloserRefusesFootpointsThatDisagreeWithThePoints) {
  const sorpia::Mesh cage = sorpia::icosphere(1);
  const sorpia::Topology topology(cage);
  const sorpia::LimitSurface surface(topology, cage.vertices.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  const sorpia::FootpointSearch search(surface, topology, {4, 10, 8, 0.0});
  const std::vector<double> points = {0.0, 0.0, 2.0, 0.0, 2.0, 0.0};
  sorpia::Footpoints fp = search.find(points.data(), 2);
  fp.distances.pop_back();
  sorpia_test::expect_error<sorpia::ParameterError>([&] { search.closer(points.data(), 2, fp); },
                                                    {"2 faces, 2 parameters and 1 distances for 2 points"});
  fp.distances.push_back(1.0);
  fp.face_ids[1] = 80;
  sorpia_test::expect_error<sorpia::ParameterError>([&] { search.closer(points.data(), 2, fp); },
                                                    {"face_ids[1] = 80 is out of range [0, 80)"});
}

TEST(RefineFootpoints, ALooseUvToleranceLeavesTheDistanceExactToItsRelativeTolerance) {
  // Footpoints on one surface re-projected onto the surface of the cage
  // grown by 2%, once with the default tolerance (to rounding) and once with
  // uv_tolerance = 1e-5 from the same starts: the same minima, the loose
  // distances exact to 1e-5 relatively (1e-6 predicted; Gauss-Newton's
  // linear convergence leaves a few times that), and points on the surface
  // still at distance zero to rounding.
  const Bumpy bumpy(300);
  const sorpia::Topology topology(bumpy.cage);
  const sorpia::LimitSurface before(topology, bumpy.cage.vertices.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  std::vector<double> grown = bumpy.cage.vertices;
  for (double& x : grown) x *= 1.02;
  const sorpia::LimitSurface after(topology, grown.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  std::vector<double> points = bumpy.points;
  std::vector<std::int32_t> on_faces;
  std::vector<double> on_uv;
  for (std::int32_t f = 0; f < static_cast<std::int32_t>(topology.n_faces()); f += 7) {
    on_faces.push_back(f);
    on_uv.push_back(0.2 + 0.001 * f);
    on_uv.push_back(0.3);
  }
  std::vector<double> on(3 * on_faces.size());
  after.evaluate(on_faces.data(), on_uv.data(), on_faces.size(), on.data(), nullptr, nullptr, nullptr);
  points.insert(points.end(), on.begin(), on.end());
  const std::size_t k = points.size() / 3, k_off = bumpy.points.size() / 3;
  const sorpia::Footpoints start = sorpia::closest_points(before, topology, points.data(), k, {});
  sorpia::Footpoints strict = start, loose = start;
  sorpia::FootpointOptions options;
  options.grid = 0;
  sorpia::refine_footpoints(after, topology, points.data(), k, options, strict);
  options.uv_tolerance = 1e-5;
  sorpia::refine_footpoints(after, topology, points.data(), k, options, loose);
  const double diagonal = 2.0 * std::sqrt(3.0) * 1.4;
  for (std::size_t i = 0; i < k; ++i) {
    if (i < k_off) {
      EXPECT_GE(loose.distances[i], strict.distances[i] - 1e-12 * diagonal) << "point " << i;
      EXPECT_LE(loose.distances[i], strict.distances[i] * (1.0 + 1e-5) + 1e-12 * diagonal) << "point " << i;
    } else {
      EXPECT_LE(strict.distances[i], 1e-12 * diagonal) << "point " << i;
      EXPECT_LE(loose.distances[i], 1e-12 * diagonal) << "point " << i;
    }
  }
  for (const double bad : {-1e-3, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    options.uv_tolerance = bad;
    sorpia::Footpoints fp = start;
    sorpia_test::expect_error<sorpia::ParameterError>(
        [&] { sorpia::refine_footpoints(after, topology, points.data(), k, options, fp); },
        {"uv_tolerance = ", "must be in [0, 1)"});
  }
}

}  // namespace

// On a smooth closed surface (icosphere(3)'s Loop surface) with points near
// it, most points are certified, and nearly all of those have a clearance
// of at least twice their distance, so that they take their candidates from
// their face's near samples without a query; the results are those of every
// start (certify false, the exhaustive rule) and of the brute force within
// 1e-9 of the diagonal.
TEST(FootpointSearch, CloserTakesTheNearSamplesOfCertifiedPointsWithClearance) {
  const sorpia::Mesh cage = sorpia::icosphere(3);
  const sorpia::Topology topology(cage);
  const sorpia::LimitSurface surface(topology, cage.vertices.data(), Scheme::Loop, Boundary::EdgeAndCorner);
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  // About 0.003 off the surface (the limit surface is round to about 1e-3
  // of its radius, that of the limit point at a face's centre).
  const std::int32_t face = 0;
  const double centre[2] = {1.0 / 3, 1.0 / 3};
  double on[3];
  surface.evaluate(&face, centre, 1, on, nullptr, nullptr, nullptr);
  const double r0 = std::sqrt(on[0] * on[0] + on[1] * on[1] + on[2] * on[2]);
  std::uniform_real_distribution<double> radius(0.997 * r0, 1.003 * r0);
  std::vector<double> points;
  for (int i = 0; i < 300; ++i) {
    double x[3] = {g(rng), g(rng), g(rng)};
    const double s = radius(rng) / std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (double c : x) points.push_back(c * s);
  }
  const std::size_t k = points.size() / 3;
  sorpia::FootpointOptions options{4, 10, 8, 0.0};
  const sorpia::FootpointSearch search(surface, topology, options);
  sorpia::Footpoints fp = search.find(points.data(), k);
  sorpia::Footpoints every = fp;
  std::size_t certified = 0, listed = 0;
  search.closer(points.data(), k, fp, false, &certified, &listed);
  EXPECT_GT(certified, 9 * k / 10);
  EXPECT_GT(listed, 9 * certified / 10);
  EXPECT_LE(listed, certified);
  options.certify = false;
  const sorpia::FootpointSearch exhaustive(surface, topology, options);
  std::size_t none = 1, none_listed = 1;
  exhaustive.closer(points.data(), k, every, false, &none, &none_listed);
  EXPECT_EQ(none, 0u);
  EXPECT_EQ(none_listed, 0u);
  const std::vector<double> least = brute_force(surface, topology, std::vector<double>(points.begin(), points.begin() + 150));
  const double diagonal = 2.0 * std::sqrt(3.0);  // at most: the limit surface lies within the unit sphere
  for (std::size_t i = 0; i < k; ++i) {
    EXPECT_LE(fp.distances[i], every.distances[i] + 1e-9 * diagonal) << "point " << i;
    if (i < least.size()) EXPECT_LE(fp.distances[i], least[i] + 1e-9 * diagonal) << "point " << i;
  }
}
