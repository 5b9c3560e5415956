// LimitSurface: corners and tessellated control vertices are the limit points.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/surface.hpp"

namespace {

using sorpia::Boundary;

TEST(LimitSurface, CornersEqualLimitPointsUnderBothBoundaryRules) {
  // (0,0), (1,0), (0,1) are the face's vertices 0, 1, 2. Bfr and Far's Limit
  // use different arithmetic: 1e-14 on a unit-sized mesh.
  const auto m = sorpia::grid(6, 5);
  const sorpia::Topology topo(m.faces.data(), m.n_faces(), m.n_vertices());
  for (const Boundary b : {Boundary::EdgeAndCorner, Boundary::EdgeOnly}) {
    std::vector<double> lp(m.vertices.size());
    sorpia::limit_points(topo, m.vertices.data(), b, lp.data());
    const sorpia::LimitSurface s(topo, m.vertices.data(), sorpia::Scheme::Loop, b);
    std::vector<std::int32_t> ids;
    std::vector<double> uv;
    for (std::size_t f = 0; f < m.n_faces(); ++f)
      for (const auto& c : {std::pair{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}}) {
        ids.push_back(static_cast<std::int32_t>(f));
        uv.insert(uv.end(), {c.first, c.second});
      }
    std::vector<double> p(3 * ids.size());
    s.evaluate(ids.data(), uv.data(), ids.size(), p.data(), nullptr, nullptr, nullptr);
    for (std::size_t i = 0; i < ids.size(); ++i)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(p[3 * i + c], lp[3 * m.faces[i] + c], 1e-14) << "point " << i;
  }
}

TEST(LimitSurface, TessellationStartsWithTheLimitPointsAndGrowsFourfold) {
  const auto m = sorpia::icosphere(1);
  const sorpia::Topology topo(m.faces.data(), m.n_faces(), m.n_vertices());
  sorpia::LimitSurface s(topo, m.vertices.data(), sorpia::Scheme::Loop, Boundary::EdgeAndCorner);
  std::vector<double> lp(m.vertices.size());
  sorpia::limit_points(topo, m.vertices.data(), Boundary::EdgeAndCorner, lp.data());
  const auto t = s.tessellate(2);
  EXPECT_EQ(t.n_faces(), 16 * m.n_faces());
  EXPECT_EQ(t.n_vertices(), 10u * 16 * 4 + 2);  // icosphere(3)'s count
  EXPECT_TRUE(std::equal(lp.begin(), lp.end(), t.vertices.begin()));
  // Every tessellated vertex lies inside the unit sphere (Loop surfaces shrink).
  for (std::size_t i = 0; i < t.n_vertices(); ++i)
    EXPECT_LT(std::hypot(t.vertices[3 * i], t.vertices[3 * i + 1], t.vertices[3 * i + 2]), 1.0);
}

TEST(LimitSurface, RefusesBadLevelsAndPoints) {
  const auto m = sorpia::icosphere(0);
  const sorpia::Topology topo(m.faces.data(), m.n_faces(), m.n_vertices());
  sorpia::LimitSurface s(topo, m.vertices.data(), sorpia::Scheme::Loop, Boundary::EdgeAndCorner);
  EXPECT_THROW(s.tessellate(16), sorpia::ParameterError);
  const std::int32_t bad_face = 20;
  const double uv[2] = {0.2, 0.2};
  double p[3];
  EXPECT_THROW(s.evaluate(&bad_face, uv, 1, p, nullptr, nullptr, nullptr), sorpia::ParameterError);
  const std::int32_t face = 0;
  const double outside[2] = {0.7, 0.7};
  EXPECT_THROW(s.evaluate(&face, outside, 1, p, nullptr, nullptr, nullptr), sorpia::ParameterError);
  EXPECT_GT(sorpia::tessellation_bytes(sorpia::Scheme::Loop, m.n_vertices(), m.n_faces(), 0, 15), std::size_t{1} << 40);
}

}  // namespace
