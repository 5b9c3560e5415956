// The fit layer's refinement (sorpia::refine_uniform) and fair solve
// (sorpia::fair_solve), against the surface layer's tessellation and the limit
// layer's B.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sorpia/errors.hpp"
#include "sorpia/fair.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/refine.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/surface.hpp"

namespace {

using sorpia::Boundary;
using sorpia::Scheme;

std::vector<double> times(const sorpia::CsrMatrix& r, const std::vector<double>& v) {
  std::vector<double> out(3 * r.n_rows, 0.0);
  for (std::size_t i = 0; i < r.n_rows; ++i)
    for (std::int32_t p = r.indptr[i]; p < r.indptr[i + 1]; ++p)
      for (int c = 0; c < 3; ++c) out[3 * i + c] += r.data[p] * v[3 * static_cast<std::size_t>(r.indices[p]) + c];
  return out;
}

sorpia::Rules creased_rules(const sorpia::Mesh& m) {
  sorpia::Rules rules{Scheme::Loop, Boundary::EdgeAndCorner, {}};
  const auto* f = m.face_vertex_indices.data();
  rules.tags.crease_vertices = {f[0], f[1], f[9], f[10]};
  rules.tags.crease_sharpness = {1.5, sorpia::kInfiniteSharpness};
  rules.tags.corner_vertices = {f[20]};
  rules.tags.corner_sharpness = {2.5};
  return rules;
}

TEST(RefineUniform, RefinedControlMeshHasTheCoarseLimitPointsAtEveryVertex) {
  // B_fine (R V) with the carried tags equals the coarse surface's
  // tessellation at the same level (Far's refinement and Limit()), vertex by
  // vertex: both are short weighted sums, 1e-13 on a unit-sized mesh.
  const auto m = sorpia::grid(7, 6);
  const sorpia::Topology topo(m);
  const sorpia::Rules rules = creased_rules(m);
  for (int levels = 1; levels <= 2; ++levels) {
    const sorpia::RefinedMesh fine = sorpia::refine_uniform(topo, rules, levels);
    ASSERT_EQ(fine.mesh.n_faces(), m.n_faces() * (levels == 1 ? 4u : 16u));
    EXPECT_FALSE(fine.tags.crease_sharpness.empty());
    const std::vector<double> rv = times(fine.refinement, m.vertices);
    const sorpia::Topology fine_topo(fine.mesh, fine.n_vertices);
    std::vector<double> got(rv.size());
    sorpia::limit_points(fine_topo, rv.data(), sorpia::Rules{Scheme::Loop, rules.boundary, fine.tags}, got.data());
    sorpia::LimitSurface surface(topo, m.vertices.data(), Scheme::Loop, rules.boundary, rules.tags);
    const sorpia::Mesh tess = surface.tessellate(levels);
    ASSERT_EQ(tess.vertices.size(), got.size());
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], tess.vertices[i], 1e-13) << "entry " << i;
  }
}

TEST(RefineUniform, LevelsOutOfRangeAreRefused) {
  const auto m = sorpia::icosphere(0);
  const sorpia::Topology topo(m);
  EXPECT_THROW(sorpia::refine_uniform(topo, sorpia::Rules{}, 0), sorpia::ParameterError);
  EXPECT_THROW(sorpia::refine_uniform(topo, sorpia::Rules{}, sorpia::kMaxRefinementLevels + 1),
               sorpia::ParameterError);
}

TEST(FairSolve, TargetsAreMetAndTheEnergyFallsFromTheStart) {
  // K = I (a positive definite stand-in): the solve meets B_t V = T_t to
  // rounding whatever it stops at, and the energy is at most the start's.
  const auto m = sorpia::icosphere(1);
  const sorpia::Topology topo(m);
  const sorpia::Rules rules{Scheme::Loop, Boundary::EdgeAndCorner, {}};
  const sorpia::RefinedMesh fine = sorpia::refine_uniform(topo, rules, 1);
  const sorpia::Topology fine_topo(fine.mesh, fine.n_vertices);
  const sorpia::Rules fine_rules{Scheme::Loop, rules.boundary, fine.tags};
  sorpia::CsrMatrix k;
  k.n_rows = k.n_cols = fine.n_vertices;
  for (std::size_t i = 0; i <= fine.n_vertices; ++i) k.indptr.push_back(static_cast<std::int32_t>(i));
  for (std::size_t i = 0; i < fine.n_vertices; ++i) k.indices.push_back(static_cast<std::int32_t>(i));
  k.data.assign(fine.n_vertices, 1.0);
  std::vector<std::int32_t> targets;
  std::vector<double> positions;
  for (std::size_t v = 0; v < m.n_vertices(); v += 2) {
    targets.push_back(static_cast<std::int32_t>(v));
    positions.insert(positions.end(), &m.vertices[3 * v], &m.vertices[3 * v + 3]);
  }
  const std::vector<double> start = times(fine.refinement, m.vertices);
  const sorpia::FairSolution s = sorpia::fair_solve(fine_topo, fine_rules, k, targets.data(), targets.size(),
                                                    positions.data(), start.data(), sorpia::FairOptions{});
  EXPECT_EQ(s.stop_reason, "converged");
  EXPECT_LE(s.energy, s.energies.front() * (1 + 1e-12));
  const sorpia::LimitOperator b = sorpia::limit_operator(fine_topo, fine_rules);
  std::vector<double> bv(s.vertices.size());
  sorpia::apply(b, s.vertices.data(), bv.data());
  for (std::size_t i = 0; i < targets.size(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(bv[3 * targets[i] + c], positions[3 * i + c], 1e-14);
  EXPECT_LE(s.max_error, 1e-14);

  std::vector<std::int32_t> repeated = {0, 2, 0};
  EXPECT_THROW(sorpia::fair_solve(fine_topo, fine_rules, k, repeated.data(), 3, positions.data(), start.data(),
                                  sorpia::FairOptions{}),
               sorpia::ParameterError);
  std::vector<std::int32_t> outside = {static_cast<std::int32_t>(fine.n_vertices)};
  EXPECT_THROW(sorpia::fair_solve(fine_topo, fine_rules, k, outside.data(), 1, positions.data(), start.data(),
                                  sorpia::FairOptions{}),
               sorpia::ParameterError);
}

}  // namespace
