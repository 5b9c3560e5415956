// LimitSurface: corners and tessellated control vertices are the limit points.
#include <gtest/gtest.h>
#include <opensubdiv/bfr/parameterization.h>

#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <thread>
#include <vector>

#include "sorpia/detail/osd_refiner.hpp"

#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/subface_grid.hpp"
#include "sorpia/surface.hpp"

namespace {

using sorpia::Boundary;

TEST(SubfaceGrid, IsBfrsQuadSubfaceParameterization) {
  // Every corner j of a k-gon (k != 4) under Catmull-Clark where Bfr puts it,
  // for k = 3..64 (columns 2, 3, then 1 + floor(sqrt(k - 1))).
  namespace Bfr = OpenSubdiv::Bfr;
  for (int k = 3; k <= 64; ++k) {
    if (k == 4) continue;
    const Bfr::Parameterization param(OpenSubdiv::Sdc::SCHEME_CATMARK, k);
    ASSERT_EQ(param.GetType(), Bfr::Parameterization::QUAD_SUBFACES) << k;
    const int w = sorpia::subface_columns(k);
    for (int j = 0; j < k; ++j) {
      double bfr[2], ours[2];
      param.GetVertexCoord(j, bfr);
      sorpia::subface_origin(w, j, ours);
      EXPECT_EQ(ours[0], bfr[0]) << "k " << k << " corner " << j;
      EXPECT_EQ(ours[1], bfr[1]) << "k " << k << " corner " << j;
    }
  }
  EXPECT_EQ(sorpia::subface_columns(10), 4);  // 1 + sqrt(9): a perfect square, where a float root could round down
  EXPECT_THROW(sorpia::subface_columns(2), sorpia::ParameterError);
}

TEST(LimitSurface, CornersEqualLimitPointsUnderBothBoundaryRules) {
  // (0,0), (1,0), (0,1) are the face's vertices 0, 1, 2. Bfr and Far's Limit
  // use different arithmetic: 1e-14 on a unit-sized mesh.
  const auto m = sorpia::grid(6, 5);
  const sorpia::Topology topo(m);
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
        EXPECT_NEAR(p[3 * i + c], lp[3 * m.face_vertex_indices[i] + c], 1e-14) << "point " << i;
  }
}

TEST(LimitSurface, TessellationStartsWithTheLimitPointsAndGrowsFourfold) {
  const auto m = sorpia::icosphere(1);
  const sorpia::Topology topo(m);
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
  const sorpia::Topology topo(m);
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

namespace {

// Corner j of a k-gon in Bfr's parameterisation under Catmull-Clark (surface.hpp).
std::pair<double, double> catmark_corner(int k, int j) {
  if (k == 4) return {static_cast<double>(j == 1 || j == 2), static_cast<double>(j >= 2)};
  const int w = k < 10 ? (k < 5 ? 2 : 3) : 1 + static_cast<int>(std::sqrt(static_cast<double>(k - 1)));
  return {static_cast<double>(j % w), static_cast<double>(j / w)};
}

TEST(LimitSurface, CatmullClarkPolygonsGiveQuadsAndExactCorners) {
  // Mixed triangles, quads, pentagons and hexagons: level 0 is the control
  // polygons, level 1 one quad per corner, level 2 four times as many; Bfr at
  // every corner equals the tessellation's control vertex (Far refinement +
  // Limit(), or Bfr where Far's Limit() does not apply) to 1e-12.
  const sorpia::Mesh m = sorpia::polygon_torus(10, 6, 3);
  const sorpia::Topology topo(m);
  sorpia::LimitSurface s(topo, m.vertices.data(), sorpia::Scheme::CatmullClark, Boundary::EdgeAndCorner);
  const sorpia::Mesh t0 = s.tessellate(0), t1 = s.tessellate(1), t2 = s.tessellate(2);
  EXPECT_EQ(t0.face_vertex_counts, m.face_vertex_counts);
  EXPECT_EQ(t0.face_vertex_indices, m.face_vertex_indices);
  EXPECT_EQ(t1.n_faces(), m.face_vertex_indices.size());
  EXPECT_EQ(t2.n_faces(), 4 * m.face_vertex_indices.size());
  for (const auto* t : {&t1, &t2})
    EXPECT_TRUE(std::all_of(t->face_vertex_counts.begin(), t->face_vertex_counts.end(), [](int k) { return k == 4; }));
  std::vector<std::int32_t> ids;
  std::vector<double> uv;
  for (std::size_t f = 0, o = 0; f < m.n_faces(); o += m.face_vertex_counts[f++])
    for (int j = 0; j < m.face_vertex_counts[f]; ++j) {
      const auto c = catmark_corner(m.face_vertex_counts[f], j);
      ids.push_back(static_cast<std::int32_t>(f));
      uv.insert(uv.end(), {c.first, c.second});
    }
  std::vector<double> p(3 * ids.size());
  s.evaluate(ids.data(), uv.data(), ids.size(), p.data(), nullptr, nullptr, nullptr);
  for (const auto* t : {&t0, &t1, &t2})
    for (std::size_t i = 0; i < ids.size(); ++i)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(p[3 * i + c], t->vertices[3 * static_cast<std::size_t>(m.face_vertex_indices[i]) + c], 1e-12);
}

}  // namespace

namespace {

// Bfr's own evaluation of every face of a surface at `uv` (one parameter for
// all faces, away from the corners), each face's Bfr::Surface built by a
// factory without a cache and its patch points prepared at `vertices`:
// positions, du and dv, (3 m) each.
std::vector<double> bfr_evaluation(const sorpia::Topology& t, sorpia::Scheme scheme, const double* vertices,
                                   const double* uv) {
  namespace Bfr = OpenSubdiv::Bfr;
  const sorpia::detail::Refiner r = sorpia::detail::make_refiner(t, scheme, Boundary::EdgeAndCorner);
  Bfr::SurfaceFactory::Options options;
  options.SetApproxLevelSmooth(4);  // surface.cpp's kApproxLevelSmooth (no darts here)
  options.SetApproxLevelSharp(10);
  options.EnableCaching(false);
  const Bfr::RefinerSurfaceFactory<> factory(*r.refiner, options);
  std::vector<double> points(3 * r.from_osd.size()), patch, out(9 * t.n_faces());
  for (std::size_t k = 0; k < r.from_osd.size(); ++k) std::copy_n(&vertices[3 * r.from_osd[k]], 3, &points[3 * k]);
  const std::size_t m = t.n_faces();
  for (std::size_t f = 0; f < m; ++f) {
    Bfr::Surface<double> s;
    EXPECT_TRUE(factory.InitVertexSurface(static_cast<int>(f), &s));
    patch.resize(3 * static_cast<std::size_t>(s.GetNumPatchPoints()));
    s.PreparePatchPoints(points.data(), 3, patch.data(), 3);
    s.Evaluate(uv, patch.data(), 3, &out[3 * f], &out[3 * (m + f)], &out[3 * (2 * m + f)]);
  }
  return out;
}

TEST(LimitSurface, PreparedPatchPointsFollowTheControlVertices) {
  // LimitSurface keeps each face's Bfr surface and its patch points between
  // evaluations until the control vertices change. After set_vertices, every
  // face's evaluation (positions and first derivatives) equals Bfr's own,
  // from a factory without a cache at the new vertices, bit for bit: also
  // when two threads evaluate the faces at once, both preparing them, and
  // after the faces' patch points had been prepared at the old vertices.
  // Loop on an irregular torus (irregular patches at its extraordinary
  // vertices), Catmull-Clark on polygons (quad sub-faces).
  for (const auto scheme : {sorpia::Scheme::Loop, sorpia::Scheme::CatmullClark}) {
    const sorpia::Mesh mesh = scheme == sorpia::Scheme::Loop ? sorpia::irregular(200) : sorpia::polygon_torus(8, 5, 2);
    const sorpia::Topology t(mesh);
    const std::size_t m = t.n_faces();
    std::vector<double> moved = mesh.vertices;
    for (std::size_t i = 0; i < moved.size(); ++i) moved[i] += 0.01 * std::sin(7.0 * static_cast<double>(i));
    const double uv[2] = {0.3, 0.2};
    std::vector<std::int32_t> ids(m);
    std::vector<double> uvs(2 * m);
    for (std::size_t f = 0; f < m; ++f) {
      ids[f] = static_cast<std::int32_t>(f);
      std::copy_n(uv, 2, &uvs[2 * f]);
    }
    sorpia::LimitSurface s(t, mesh.vertices.data(), scheme, Boundary::EdgeAndCorner);
    const auto evaluate = [&](std::vector<double>& out) {
      out.assign(9 * m, 0.0);
      s.evaluate(ids.data(), uvs.data(), m, out.data(), out.data() + 3 * m, out.data() + 6 * m, nullptr);
    };
    std::vector<double> first, second, third;
    evaluate(first);
    EXPECT_EQ(first, bfr_evaluation(t, scheme, mesh.vertices.data(), uv));
    s.set_vertices(moved.data());
    std::thread other([&] { evaluate(second); });
    evaluate(third);
    other.join();
    const std::vector<double> expected = bfr_evaluation(t, scheme, moved.data(), uv);
    EXPECT_EQ(second, expected);
    EXPECT_EQ(third, expected);
    EXPECT_NE(first, expected);
  }
}

TEST(LimitSurface, PositionBlocksAreRowsPositionMatrix) {
  // position_blocks gives rows()'s position matrix, row for row, each point
  // in one block (a face's points in increasing order, sharing its columns),
  // also for many points (many threads) and at faces' corners (B's rows);
  // and that matrix times the control vertices is evaluate()'s positions.
  for (const auto scheme : {sorpia::Scheme::Loop, sorpia::Scheme::CatmullClark}) {
    const sorpia::Mesh mesh = scheme == sorpia::Scheme::Loop ? sorpia::irregular(200) : sorpia::polygon_torus(8, 5, 2);
    const sorpia::Topology t(mesh);
    const std::size_t m = t.n_faces(), k = 150000;
    const double params[3][2] = {{0.3, 0.2}, {0.0, 0.0}, {0.1, 0.45}};
    std::vector<std::int32_t> ids(k);
    std::vector<double> uvs(2 * k);
    for (std::size_t i = 0; i < k; ++i) {
      ids[i] = static_cast<std::int32_t>((7 * i) % m);
      std::copy_n(params[i % 3], 2, &uvs[2 * i]);
    }
    const sorpia::LimitSurface s(t, mesh.vertices.data(), scheme, Boundary::EdgeAndCorner);
    const sorpia::CsrMatrix a = s.rows(ids.data(), uvs.data(), k, 1).position;
    std::size_t n_blocks = 0;
    std::vector<int> seen_block;
    std::vector<std::int64_t> block_offsets;
    std::vector<std::int32_t> block_columns;
    std::vector<std::vector<std::int32_t>> cols(k);
    std::vector<std::vector<double>> vals(k);
    std::vector<std::int64_t> block_of(k, -1);
    std::mutex mutex;
    sorpia::detail::Scratch scratch;
    s.position_blocks(
        ids.data(), uvs.data(), k, scratch,
        [&](std::vector<std::int64_t>&& offsets, std::vector<std::int32_t>&& columns) {
          n_blocks = offsets.size() - 1;
          seen_block.assign(n_blocks, 0);
          block_offsets = std::move(offsets);
          block_columns = std::move(columns);
        },
        [&](const sorpia::PositionBlock& b) {
          const std::lock_guard<std::mutex> lock(mutex);
          ASSERT_LT(b.index, n_blocks);
          ++seen_block[b.index];
          // start's columns of the block are its own (none for a face whose points all have B's rows)
          const auto c0 = static_cast<std::size_t>(block_offsets[b.index]);
          const auto c1 = static_cast<std::size_t>(block_offsets[b.index + 1]);
          if (b.count > 0)
            EXPECT_TRUE(c1 - c0 == b.width && std::equal(b.columns, b.columns + b.width, &block_columns[c0]));
          for (std::size_t j = 0; j < b.count; ++j) {
            const std::size_t i = b.points[j];
            if (j > 0) EXPECT_LT(b.points[j - 1], i);
            EXPECT_EQ(block_of[i], -1) << "point " << i << " in two blocks";
            block_of[i] = static_cast<std::int64_t>(b.index);
            cols[i].assign(b.columns, b.columns + b.width);
            vals[i].assign(b.rows + j * b.width, b.rows + (j + 1) * b.width);
          }
        });
    EXPECT_TRUE(std::all_of(seen_block.begin(), seen_block.end(), [](int c) { return c == 1; }));
    std::size_t differ = 0;
    for (std::size_t i = 0; i < k; ++i) {
      const auto p0 = static_cast<std::size_t>(a.indptr[i]), p1 = static_cast<std::size_t>(a.indptr[i + 1]);
      const auto at = static_cast<std::ptrdiff_t>(p0);
      const bool same = block_of[i] >= 0 && cols[i].size() == p1 - p0 &&
                        std::equal(cols[i].begin(), cols[i].end(), a.indices.begin() + at) &&
                        std::equal(vals[i].begin(), vals[i].end(), a.data.begin() + at);
      differ += same ? 0 : 1;
    }
    EXPECT_EQ(differ, 0u) << "scheme " << static_cast<int>(scheme);
    // The faces' blocks in increasing order of the face (every face has points: face f's block is f), then one
    // block per point with B's row.
    ASSERT_GE(n_blocks, m);
    for (std::size_t i = 0; i < k; ++i)
      if (block_of[i] < static_cast<std::int64_t>(m)) EXPECT_EQ(block_of[i], ids[i]) << "point " << i;
    std::vector<double> positions(3 * k);
    s.evaluate(ids.data(), uvs.data(), k, positions.data(), nullptr, nullptr, nullptr);
    double worst = 0.0;
    for (std::size_t i = 0; i < k; ++i)
      for (int c = 0; c < 3; ++c) {
        double p = 0.0;
        for (std::size_t q = 0; q < cols[i].size(); ++q)
          p += vals[i][q] * mesh.vertices[3 * static_cast<std::size_t>(cols[i][q]) + c];
        worst = std::max(worst, std::abs(p - positions[3 * i + c]));
      }
    EXPECT_LT(worst, 1e-12) << "scheme " << static_cast<int>(scheme);
  }
}

}  // namespace
