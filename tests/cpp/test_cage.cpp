// sorpia::decimate and sorpia::quads_from_triangles through the C++ API: the
// paths the Python layer does not take (faces with counts), the split's
// geometry against closed forms, and the Catmull-Clark cage's pairing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "expect_error.hpp"
#include "sorpia/cage.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/shapes.hpp"

namespace {

using sorpia_test::expect_error;

TEST(Cage, OneTriangleSplitsIntoThreeQuadsAtItsCentroidAndMidpoints) {
  sorpia::Mesh tri;
  tri.vertices = {0, 0, 0, 3, 0, 0, 0, 3, 0};
  tri.face_vertex_indices = {0, 1, 2};
  const sorpia::Mesh q = sorpia::quads_from_triangles(tri);
  ASSERT_EQ(q.n_faces(), 3u);
  ASSERT_EQ(q.n_vertices(), 7u);  // 3 corners, 3 midpoints, 1 centroid
  const auto p = [&](std::int32_t v) { return std::vector<double>(&q.vertices[3 * v], &q.vertices[3 * v + 3]); };
  // Corner k's quad: (t[k], mid(t[k], t[k+1]), centroid, mid(t[k-1], t[k])), counter-clockwise as the triangle.
  const std::vector<std::vector<double>> expected[3] = {
      {{0, 0, 0}, {1.5, 0, 0}, {1, 1, 0}, {0, 1.5, 0}},
      {{3, 0, 0}, {1.5, 1.5, 0}, {1, 1, 0}, {1.5, 0, 0}},
      {{0, 3, 0}, {0, 1.5, 0}, {1, 1, 0}, {1.5, 1.5, 0}}};
  for (int f = 0; f < 3; ++f)
    for (int c = 0; c < 4; ++c) EXPECT_EQ(p(q.face_vertex_indices[4 * f + c]), expected[f][c]) << f << " " << c;
}

TEST(Cage, FacesGivenWithCountsOfThreeDecimateAsWithout) {
  const sorpia::Mesh sphere = sorpia::icosphere(3);
  sorpia::Mesh counted = sphere;
  counted.face_vertex_counts.assign(sphere.n_faces(), 3);
  const sorpia::Mesh a = sorpia::decimate(sphere, 100), b = sorpia::decimate(counted, 100);
  EXPECT_EQ(a.n_vertices(), 100u);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.face_vertex_indices, b.face_vertex_indices);
  counted.face_vertex_counts[7] = 4;
  counted.face_vertex_counts[8] = 2;
  expect_error<sorpia::MeshError>([&] { sorpia::decimate(counted, 100); }, {"face 7 has 4 corners", "triangulate"});
}

TEST(Cage, CatmullClarkPairsTheLoopCagesTrianglesIntoQuads) {
  const sorpia::Mesh sphere = sorpia::icosphere(3);  // 642 vertices, 1280 faces
  sorpia::DecimateOptions options;
  options.scheme = sorpia::Scheme::CatmullClark;
  for (std::size_t n : {642u, 300u, 40u}) {
    const sorpia::Mesh tri = sorpia::decimate(sphere, n), q = sorpia::decimate(sphere, n, options);
    EXPECT_EQ(q.n_vertices(), n);  // the count asked, as Loop's: pairing keeps the vertices
    EXPECT_EQ(q.vertices, tri.vertices);
    // Each quad (a, d, b, c) is the triangles (a, b, c) and (b, a, d): the faces are tri's triangles, grouped.
    std::multiset<std::vector<std::int32_t>> got, want;
    const auto add = [](std::multiset<std::vector<std::int32_t>>& to, std::vector<std::int32_t> t) {
      std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
      to.insert(t);
    };
    std::size_t corner = 0, quads = 0;
    for (const std::int32_t k : q.counts()) {
      const std::int32_t* x = &q.face_vertex_indices[corner];
      ASSERT_TRUE(k == 3 || k == 4);
      if (k == 3) add(got, {x[0], x[1], x[2]});
      else {
        add(got, {x[0], x[2], x[3]});
        add(got, {x[2], x[0], x[1]});
        ++quads;
      }
      corner += static_cast<std::size_t>(k);
    }
    for (std::size_t f = 0; f < tri.n_faces(); ++f)
      add(want, {tri.face_vertex_indices[3 * f], tri.face_vertex_indices[3 * f + 1], tri.face_vertex_indices[3 * f + 2]});
    EXPECT_EQ(got, want) << n;
    EXPECT_GE(2 * quads, tri.n_faces() * 8 / 10) << n;  // most paired (80% stated)
  }
  expect_error<sorpia::MeshError>([&] { sorpia::decimate(sphere, 643, options); },
                                  {"643 vertices asked", "642 vertices"});
  options.max_normal_deviation = 0;
  expect_error<sorpia::ParameterError>([&] { sorpia::decimate(sphere, 100, options); }, {"max_normal_deviation"});
}

TEST(Cage, StoppedReturnsTheMeshTheGuardsStoppedAtWithTheErrorsWords) {
  // A 30 x 30 grid wavy along two sides: with max_boundary_angle 0 the 60
  // vertices where those sides turn stay, so 50 cannot be reached.
  const sorpia::Mesh grid = sorpia::grid(30, 30);
  for (const auto scheme : {sorpia::Scheme::Loop, sorpia::Scheme::CatmullClark}) {
    sorpia::DecimateOptions options;
    options.scheme = scheme;
    options.max_boundary_angle = 0;
    std::string thrown;
    try {
      sorpia::decimate(grid, 50, options);
    } catch (const sorpia::MeshError& e) {
      thrown = e.what();
    }
    ASSERT_NE(thrown.find("decimate stopped at"), std::string::npos);
    std::string stopped;
    const sorpia::Mesh reached = sorpia::decimate(grid, 50, options, &stopped);
    EXPECT_EQ(stopped, thrown);
    EXPECT_NE(stopped.find("stopped at " + std::to_string(reached.n_vertices()) + " vertices"), std::string::npos);
    EXPECT_GE(reached.n_vertices(), 60u);
    // A count reached: the mesh asked, and `stopped` cleared.
    const std::size_t n = 400;
    const sorpia::Mesh full = sorpia::decimate(grid, n, options, &stopped);
    EXPECT_TRUE(stopped.empty());
    EXPECT_LE(full.n_vertices(), n);
    EXPECT_GE(full.n_vertices() + 5, n);
  }
}

TEST(Cage, ClusteringGivesTheSameCageOnOneThreadAsOnAll) {
  // A torus of 210,000 vertices, clustered before its decimation (its passes
  // in tasks over ranges of vertices, faces and clusters), with its vertices
  // numbered in a scrambled order, so that every task's range borders every
  // other's, and moved along the torus's normals by up to 1.7 vertex
  // spacings, so that the grid is laid over the smoothed positions too.
  const sorpia::Mesh torus = sorpia::torus(700, 300);
  const std::size_t n = torus.n_vertices();
  std::size_t step = 7919;
  while (std::gcd(step, n) != 1) ++step;
  const double spacing = 2 * M_PI * 0.4 / 300;
  sorpia::Mesh mesh;
  mesh.vertices.resize(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double* p = &torus.vertices[3 * i];
    const double ring = std::hypot(p[0], p[1]);
    const double normal[3] = {(p[0] - p[0] / ring) / 0.4, (p[1] - p[1] / ring) / 0.4, p[2] / 0.4};
    const double u = static_cast<double>(static_cast<std::uint32_t>(i * 2654435761u)) / 4294967296.0 * 2 - 1;
    for (int c = 0; c < 3; ++c) mesh.vertices[3 * (i * step % n) + c] = p[c] + normal[c] * 1.7 * spacing * u;
  }
  for (const std::int32_t v : torus.face_vertex_indices)
    mesh.face_vertex_indices.push_back(static_cast<std::int32_t>(static_cast<std::size_t>(v) * step % n));
  const sorpia::Mesh all = sorpia::decimate(mesh, 2000);
  sorpia::Mesh one;
  {
    const sorpia::detail::ThreadCap cap(1);
    one = sorpia::decimate(mesh, 2000);
  }
  ASSERT_EQ(all.n_vertices(), 2000u);
  EXPECT_EQ(one.vertices, all.vertices);
  EXPECT_EQ(one.face_vertex_indices, all.face_vertex_indices);
}

}  // namespace
