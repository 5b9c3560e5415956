// B with sharpness tags (creases, corners, holes; infinitely sharp and
// semi-sharp) against OpenSubdiv's refinement of the whole mesh and Limit()
// on its last level (detail::reference_limit_matrix), row by row.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "darts.hpp"
#include "expect_error.hpp"
#include "sorpia/reference.hpp"
#include "refined_rows.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/shapes.hpp"

namespace {

using sorpia::Boundary;
using sorpia::Scheme;
using sorpia::Tags;

// The largest difference between two CSR matrices of the same shape, entry
// by entry, in the rows `skip` does not mark (none when empty).
double max_entry_diff(const sorpia::CsrMatrix& a, const sorpia::CsrMatrix& b, const std::vector<bool>& skip = {}) {
  EXPECT_EQ(a.n_rows, b.n_rows);
  double worst = 0.0;
  for (std::size_t i = 0; i < std::min(a.n_rows, b.n_rows); ++i) {
    if (!skip.empty() && skip[i]) continue;
    std::map<std::int32_t, double> d;
    for (auto p = a.indptr[i]; p < a.indptr[i + 1]; ++p) d[a.indices[p]] += a.data[p];
    for (auto p = b.indptr[i]; p < b.indptr[i + 1]; ++p) d[b.indices[p]] -= b.data[p];
    for (const auto& [j, x] : d) worst = std::max(worst, std::abs(x));
  }
  return worst;
}

// Edges of the mesh (a < b), in a fixed order.
std::vector<std::pair<std::int32_t, std::int32_t>> edges(const sorpia::Topology& t) {
  std::vector<std::pair<std::int32_t, std::int32_t>> out;
  for (std::size_t v = 0; v < t.n_vertices(); ++v)
    for (auto p = t.ring_offsets()[v]; p < t.ring_offsets()[v + 1]; ++p)
      if (static_cast<std::size_t>(t.ring_neighbors()[p]) > v)
        out.emplace_back(static_cast<std::int32_t>(v), t.ring_neighbors()[p]);
  return out;
}

// Random tags: a share of the edges creased (sharpness drawn from `levels`,
// each a value or infinity), a few corners and holes.
Tags random_tags(const sorpia::Topology& t, unsigned seed, const std::vector<double>& sharpness, double share) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Tags tags;
  for (const auto& [a, b] : edges(t))
    if (u(rng) < share) {
      tags.crease_vertices.insert(tags.crease_vertices.end(), {a, b});
      tags.crease_sharpness.push_back(sharpness[rng() % sharpness.size()]);
    }
  for (std::size_t v = 0; v < t.n_vertices(); ++v)
    if (u(rng) < share / 4) {
      tags.corner_vertices.push_back(static_cast<std::int32_t>(v));
      tags.corner_sharpness.push_back(sharpness[rng() % sharpness.size()]);
    }
  for (std::size_t f = 0; f < t.n_faces(); ++f)
    if (u(rng) < share / 4) tags.holes.push_back(static_cast<std::int32_t>(f));
  return tags;
}

struct Case {
  std::string name;
  sorpia::Mesh mesh;
};

std::vector<Case> meshes() {
  return {{"icosphere(2)", sorpia::icosphere(2)},
          {"torus(9, 7)", sorpia::torus(9, 7)},
          {"grid(7, 6)", sorpia::grid(7, 6)},
          {"irregular(150)", sorpia::irregular(150, 3)}};
}

const double kInf = std::numeric_limits<double>::infinity();

void expect_rows_match(const Case& c, const Tags& tags, Boundary boundary, const std::string& what) {
  const sorpia::Topology t(c.mesh);
  const auto op = sorpia::limit_operator(t, boundary, tags);
  const auto ref = sorpia::reference_limit_matrix(t, sorpia::Rules{Scheme::Loop, boundary, tags});
  // Darts: test_darts.cpp.
  EXPECT_LE(max_entry_diff(sorpia::to_csr(op), ref, sorpia_test::darts(t, tags)), 1e-14) << c.name << " " << what;
}

// Infinitely sharp rows are Sdc's and keep the one-weight form, except at
// darts, whose rows (the limit of their refinement) have several weights.
TEST(Creases, InfinitelySharpRowsAreFarsAndStayUniformWithoutDarts) {
  for (const auto& c : meshes())
    for (unsigned seed : {1u, 2u, 3u})
      for (Boundary b : {Boundary::EdgeAndCorner, Boundary::EdgeOnly}) {
        const sorpia::Topology t(c.mesh);
        const Tags tags = random_tags(t, seed, {kInf, 10.0, 12.5}, 0.15);
        ASSERT_FALSE(tags.crease_sharpness.empty());
        const auto darts = sorpia_test::darts(t, tags);
        EXPECT_EQ(sorpia::limit_operator(t, b, tags).uniform(), std::count(darts.begin(), darts.end(), true) == 0)
            << c.name;
        expect_rows_match(c, tags, b, "infinitely sharp, seed " + std::to_string(seed));
      }
}

TEST(Creases, SemiSharpRowsAreFarsRefinedLimit) {
  for (const auto& c : meshes())
    for (unsigned seed : {4u, 5u})
      for (Boundary b : {Boundary::EdgeAndCorner, Boundary::EdgeOnly}) {
        const sorpia::Topology t(c.mesh);
        // Up to 3 levels of refinement of the whole mesh for the reference.
        const Tags tags = random_tags(t, seed, {0.3, 1.0, 1.5, 2.0, 2.7, kInf}, 0.12);
        const auto op = sorpia::limit_operator(t, b, tags);
        EXPECT_FALSE(op.uniform()) << c.name;
        expect_rows_match(c, tags, b, "semi-sharp, seed " + std::to_string(seed));
      }
}

TEST(Creases, HolesAloneChangeNoRow) {
  for (const auto& c : meshes()) {
    const sorpia::Topology t(c.mesh);
    Tags tags;
    for (std::size_t f = 0; f < t.n_faces(); f += 3) tags.holes.push_back(static_cast<std::int32_t>(f));
    const auto ref = sorpia::reference_limit_matrix(t, sorpia::Rules{Scheme::Loop, Boundary::EdgeAndCorner, tags});
    EXPECT_LE(max_entry_diff(sorpia::limit_matrix(t, Boundary::EdgeAndCorner), ref), 1e-15) << c.name;
  }
}

// A crease given twice counts with its last sharpness, as in Far's descriptor.
TEST(Creases, RepeatedCreaseTakesTheLastSharpness) {
  const Case c{"icosphere(1)", sorpia::icosphere(1)};
  const sorpia::Topology t(c.mesh);
  const auto e = edges(t);
  Tags twice;
  twice.crease_vertices = {e[0].first, e[0].second, e[0].second, e[0].first};
  twice.crease_sharpness = {kInf, 1.5};
  Tags once;
  once.crease_vertices = {e[0].first, e[0].second};
  once.crease_sharpness = {1.5};
  const auto a = sorpia::to_csr(sorpia::limit_operator(t, Boundary::EdgeAndCorner, twice));
  const auto b = sorpia::to_csr(sorpia::limit_operator(t, Boundary::EdgeAndCorner, once));
  EXPECT_EQ(a.data, b.data);
  EXPECT_LE(max_entry_diff(a, sorpia::reference_limit_matrix(t, sorpia::Rules{Scheme::Loop, Boundary::EdgeAndCorner, twice})),
            1e-14);
}

TEST(Creases, ACreaseThatIsNoEdgeIsNamed) {
  const auto m = sorpia::icosphere(1);
  const sorpia::Topology t(m);
  const auto e = edges(t);
  // Two vertices that share no edge: 0 and a vertex outside its ring.
  std::int32_t far = 0;
  for (std::int32_t v = 1; v < static_cast<std::int32_t>(t.n_vertices()); ++v)
    if (std::find(t.ring_neighbors().begin() + t.ring_offsets()[0], t.ring_neighbors().begin() + t.ring_offsets()[1],
                  v) == t.ring_neighbors().begin() + t.ring_offsets()[1]) {
      far = v;
      break;
    }
  Tags tags;
  tags.crease_vertices = {e[0].first, e[0].second, 0, far};
  tags.crease_sharpness = {1.0, 2.0};
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] { sorpia::limit_operator(t, Boundary::EdgeAndCorner, tags); },
      {"creases[1] = [0, " + std::to_string(far) + "] is not an edge of the mesh"});
}

// Catmull-Clark: every row from the local refiners against the whole mesh
// refined by OpenSubdiv, with and without tags, on quads and mixed polygons.
TEST(Creases, CatmullClarkRowsAreFarsRefinedLimit) {
  const std::vector<std::pair<std::string, sorpia::Mesh>> polys = {
      {"quad_torus(8, 6)", sorpia::quad_torus(8, 6)},
      {"quad_grid(6, 5)", sorpia::quad_grid(6, 5)},
      {"quad_irregular(300)", sorpia::quad_irregular(300, 2)},
      {"polygon_torus(9, 7)", sorpia::polygon_torus(9, 7, 3)}};
  for (const auto& [name, m] : polys)
    for (Boundary b : {Boundary::EdgeAndCorner, Boundary::EdgeOnly})
      for (unsigned seed : {0u, 6u}) {
        const sorpia::Topology t(m);
        const Tags tags = seed ? random_tags(t, seed, {0.5, 1.0, 2.0, 2.5, kInf}, 0.12) : Tags{};
        const auto op = sorpia::limit_operator(t, sorpia::Rules{Scheme::CatmullClark, b, tags});
        const auto ref = sorpia::reference_limit_matrix(t, sorpia::Rules{Scheme::CatmullClark, b, tags});
        EXPECT_LE(max_entry_diff(sorpia::to_csr(op), ref, sorpia_test::darts(t, tags)), 1e-14)
            << name << " seed " << seed;
      }
}

}  // namespace
