// sorpia::split_nonmanifold (nonmanifold="sharp") against OpenSubdiv itself:
// Far's Limit() on the whole non-manifold mesh (a refiner built here from the
// raw faces, which OpenSubdiv accepts as they are) must equal, vertex by
// vertex, Far's Limit() on the split mesh with an infinitely sharp corner on
// every copy of each vertex in `corners` (and an infinitely sharp crease on
// each of `sharp_edges`), and Far's uniform refinement of both must make the
// same points. Generated meshes always; the
// OpenSubdiv non-manifold shapes of ../shared/meshes when present (their faces
// that repeat a vertex left out: the split refuses them).
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "expect_error.hpp"
#include "face_arrays.hpp"
#include "sorpia/detail/osd_refiner.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/io.hpp"
#include "sorpia/repair.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;
using Ints = std::vector<std::int32_t>;
using sorpia::detail::Point3;

struct Mesh {
  Ints counts, indices;
  std::size_t n_vertices = 0;
  void add(std::initializer_list<std::int32_t> f) {
    counts.push_back(static_cast<std::int32_t>(f.size()));
    indices.insert(indices.end(), f);
  }
  // The faces as the split takes them (with counts, also for triangles).
  sorpia::Mesh faces() const { return sorpia_test::polygons(counts, indices); }
};

// A refiner of the raw faces (OpenSubdiv takes non-manifold topology as it is).
std::unique_ptr<Far::TopologyRefiner> raw_refiner(const Mesh& m, sorpia::Scheme scheme, sorpia::Boundary boundary) {
  Far::TopologyDescriptor desc;
  desc.numVertices = static_cast<int>(m.n_vertices);
  desc.numFaces = static_cast<int>(m.counts.size());
  desc.numVertsPerFace = m.counts.data();
  desc.vertIndicesPerFace = m.indices.data();
  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(boundary == sorpia::Boundary::EdgeOnly
                                      ? Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                      : Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(Factory::Create(
      desc, Factory::Options(scheme == sorpia::Scheme::Loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK, sdc)));
  EXPECT_TRUE(refiner);
  return refiner;
}

// Far's Limit() of every vertex of the raw faces; unreferenced vertices: themselves.
std::vector<Point3> far_limit(const Mesh& m, const std::vector<Point3>& p, sorpia::Scheme scheme,
                              sorpia::Boundary boundary) {
  const std::unique_ptr<Far::TopologyRefiner> refiner = raw_refiner(m, scheme, boundary);
  std::vector<Point3> out(p.size());
  Far::PrimvarRefinerReal<double>(*refiner).Limit(p, out);
  std::set<std::int32_t> used(m.indices.begin(), m.indices.end());
  for (std::size_t v = 0; v < p.size(); ++v)
    if (!used.count(static_cast<std::int32_t>(v))) out[v] = p[v];
  return out;
}

// The points of `refiner`'s last level after refining `points` (its level 0)
// uniformly `levels` levels with Far's Interpolate().
std::vector<Point3> far_refined(Far::TopologyRefiner& refiner, std::vector<Point3> points, int levels) {
  refiner.RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
  const Far::PrimvarRefinerReal<double> primvars(refiner);
  for (int level = 1; level <= levels; ++level) {
    std::vector<Point3> next(static_cast<std::size_t>(refiner.GetLevel(level).GetNumVertices()));
    primvars.Interpolate(level, points, next);
    points = std::move(next);
  }
  return points;
}

// Every point of `a` is one of `b` (to `tol`), and the other way round.
void expect_same_points(const std::vector<Point3>& a, const std::vector<Point3>& b, double tol) {
  auto missing = [&](const std::vector<Point3>& from, const std::vector<Point3>& in) {
    std::size_t n = 0;
    for (const Point3& p : from)
      n += std::none_of(in.begin(), in.end(), [&](const Point3& q) {
        return std::abs(p.x - q.x) <= tol && std::abs(p.y - q.y) <= tol && std::abs(p.z - q.z) <= tol;
      });
    return n;
  };
  EXPECT_EQ(missing(a, b), 0u) << "points of the split's refinement that OpenSubdiv's of the raw mesh has not";
  EXPECT_EQ(missing(b, a), 0u) << "points of OpenSubdiv's refinement of the raw mesh that the split's has not";
}

// Checks the split of `m` against far_limit, and the points of both refined
// `refined_levels` levels (every edge and face point: also the sharpness of
// edges that no vertex row reads); returns the split.
sorpia::NonmanifoldSplit expect_split_is_opensubdiv(const Mesh& m, sorpia::Scheme scheme,
                                                    sorpia::Boundary boundary = sorpia::Boundary::EdgeAndCorner,
                                                    int refined_levels = 2) {
  const sorpia::NonmanifoldSplit s =
      sorpia::split_nonmanifold(m.faces(), m.n_vertices);
  EXPECT_FALSE(s.empty());
  if (s.empty()) return s;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  std::vector<double> p(3 * m.n_vertices);
  for (double& x : p) x = normal(rng);
  std::vector<Point3> points(m.n_vertices);
  for (std::size_t v = 0; v < m.n_vertices; ++v) points[v] = {p[3 * v], p[3 * v + 1], p[3 * v + 2]};
  const std::vector<Point3> want = far_limit(m, points, scheme, boundary);

  const std::size_t n_out = s.vertex_map.size();
  const sorpia::Topology split(s.faces, n_out);
  // A crease vertex's copy in a sheet of one face, which "edge-and-corner" would make a corner: the split is
  // taken under "edge-only", with the corners "edge-and-corner" makes (every other vertex of one face) as tags.
  const bool corner_sheets = boundary == sorpia::Boundary::EdgeAndCorner && !s.single_face_sheets.empty();
  auto crease_vertex = [&](std::int32_t v) {
    return std::binary_search(s.nonmanifold_vertices.begin(), s.nonmanifold_vertices.end(), v) &&
           !std::binary_search(s.corners.begin(), s.corners.end(), v);
  };
  sorpia::Tags tags;
  for (std::size_t o = 0; o < n_out; ++o)
    if ((std::binary_search(s.corners.begin(), s.corners.end(), s.vertex_map[o]) ||
         (corner_sheets && split.face_count(o) == 1 && !crease_vertex(s.vertex_map[o]))) &&
        !split.is_unreferenced(o)) {
      tags.corner_vertices.push_back(static_cast<std::int32_t>(o));
      tags.corner_sharpness.push_back(sorpia::kInfiniteSharpness);
    }
  for (const auto& [a, b] : s.sharp_edges) {
    tags.crease_vertices.insert(tags.crease_vertices.end(), {a, b});
    tags.crease_sharpness.push_back(sorpia::kInfiniteSharpness);
  }
  std::vector<double> q(3 * n_out), got(3 * n_out);
  for (std::size_t o = 0; o < n_out; ++o) std::copy_n(p.begin() + 3 * s.vertex_map[o], 3, q.begin() + 3 * o);
  const sorpia::detail::Refiner osd =
      sorpia::detail::make_refiner(split, scheme, corner_sheets ? sorpia::Boundary::EdgeOnly : boundary, tags);
  std::vector<Point3> gathered;
  sorpia::detail::gather_points(osd, q.data(), gathered);
  sorpia::detail::limit_positions(osd, gathered, q.data(), n_out, got.data());
  for (std::size_t o = 0; o < n_out; ++o) {
    const std::int32_t v = s.vertex_map[o];
    const Point3& w = want[v];
    EXPECT_NEAR(got[3 * o], w.x, 1e-14) << "output vertex " << o << " (input " << v << ")";
    EXPECT_NEAR(got[3 * o + 1], w.y, 1e-14) << "output vertex " << o << " (input " << v << ")";
    EXPECT_NEAR(got[3 * o + 2], w.z, 1e-14) << "output vertex " << o << " (input " << v << ")";
  }
  if (refined_levels > 0) {
    // Rounding: each refined point is a convex combination of O(1) inputs, a few levels deep.
    const std::unique_ptr<Far::TopologyRefiner> raw = raw_refiner(m, scheme, boundary);
    std::vector<Point3> split_points = far_refined(*osd.refiner, gathered, refined_levels);
    const std::set<std::int32_t> used(m.indices.begin(), m.indices.end());
    for (std::size_t v = 0; v < m.n_vertices; ++v)  // Far refines an unreferenced vertex to itself; the split leaves it out
      if (!used.count(static_cast<std::int32_t>(v))) split_points.push_back(points[v]);
    expect_same_points(split_points, far_refined(*raw, points, refined_levels), 1e-12);
  }
  return s;
}

// An open book: `pages` strips of 2 x `rows` quads (triangles: each quad split)
// sharing their spine, the edges (0, 1), (1, 2), ..., (rows - 1, rows).
Mesh book(int pages, int rows, bool triangles) {
  Mesh m;
  m.n_vertices = static_cast<std::size_t>((rows + 1) * (1 + 2 * pages));
  auto id = [&](int page, int column, int row) {  // column 0 is the spine
    return column == 0 ? row : (rows + 1) * (1 + 2 * page + column - 1) + row;
  };
  for (int page = 0; page < pages; ++page)
    for (int c = 0; c < 2; ++c)
      for (int r = 0; r < rows; ++r) {
        std::int32_t a = id(page, c, r), b = id(page, c + 1, r), cc = id(page, c + 1, r + 1), d = id(page, c, r + 1);
        if (page % 2) std::swap(b, d);  // alternate pages run the spine the other way
        if (triangles) {
          m.add({a, b, cc});
          m.add({a, cc, d});
        } else {
          m.add({a, b, cc, d});
        }
      }
  return m;
}

}  // namespace

TEST(NonmanifoldSharp, BookOfPagesMatchesOpenSubdiv) {
  for (bool triangles : {true, false})
    for (int pages : {3, 4}) {
      const Mesh m = book(pages, 3, triangles);
      const auto s = expect_split_is_opensubdiv(m, triangles ? sorpia::Scheme::Loop : sorpia::Scheme::CatmullClark);
      EXPECT_EQ(s.nonmanifold_edges.size(), 3u);
      EXPECT_EQ(s.nonmanifold_vertices, (Ints{0, 1, 2, 3}));
      EXPECT_EQ(s.corners, (Ints{0, 3}));  // the spine's ends; 1 and 2 are on an interior crease
      expect_split_is_opensubdiv(m, triangles ? sorpia::Scheme::Loop : sorpia::Scheme::CatmullClark,
                                 sorpia::Boundary::EdgeOnly);
    }
}

TEST(NonmanifoldSharp, BowtiesAndMisorientedFacesMatchOpenSubdiv) {
  Mesh cones;  // two closed cones (tetrahedra) touching at vertex 0
  cones.n_vertices = 7;
  for (auto f : {Ints{0, 1, 2}, Ints{0, 2, 3}, Ints{0, 3, 1}, Ints{1, 3, 2}, Ints{0, 4, 5}, Ints{0, 5, 6}, Ints{0, 6, 4},
                 Ints{4, 6, 5}}) {
    cones.counts.push_back(3);
    cones.indices.insert(cones.indices.end(), f.begin(), f.end());
  }
  EXPECT_EQ(expect_split_is_opensubdiv(cones, sorpia::Scheme::Loop).corners, Ints{0});

  Mesh grid = book(1, 4, false);  // one page: a 2 x 4 quad grid; reverse one inner quad
  std::reverse(grid.indices.begin() + 4 * 1 + 1, grid.indices.begin() + 4 * 1 + 4);
  const auto s = expect_split_is_opensubdiv(grid, sorpia::Scheme::CatmullClark);
  EXPECT_EQ(s.nonmanifold_edges.size(), 3u);  // the reversed quad's edges shared with another quad (its fourth is on the boundary)
}

TEST(NonmanifoldSharp, OneFaceSheetsAreReportedAndEdgeOnlyMatches) {
  Mesh m = book(3, 3, false);
  // a fourth page of one quad over the spine's vertex 1 (edges (0, 1) and (1, 2)): vertex 1 keeps the
  // crease rule, and its copy in that quad is a boundary vertex of one face
  const auto n = static_cast<std::int32_t>(m.n_vertices);
  m.add({0, 1, 2, n});
  m.n_vertices += 1;
  const auto s = expect_split_is_opensubdiv(m, sorpia::Scheme::CatmullClark, sorpia::Boundary::EdgeOnly);
  EXPECT_EQ(s.single_face_sheets, Ints{1});
  EXPECT_EQ(s.corners, (Ints{0, 2, 3}));
  expect_split_is_opensubdiv(m, sorpia::Scheme::CatmullClark);  // the other rows still match
}

// The faces of an n x n x n hex grid, every quad once, outward from the first
// hex that has it: edges of four faces inside, of three on the sides, whose
// crease vertices have sheets of one face (split under "edge-only" with the
// corners of "edge-and-corner" as tags, see expect_split_is_opensubdiv).
Mesh hex_grid_faces(int n, bool triangles) {
  Mesh m;
  m.n_vertices = static_cast<std::size_t>((n + 1) * (n + 1) * (n + 1));
  auto id = [&](int x, int y, int z) { return (x * (n + 1) + y) * (n + 1) + z; };
  const int quads[6][4][3] = {{{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
                              {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},
                              {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}};
  std::set<std::vector<std::int32_t>> seen;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z)
        for (const auto& q : quads) {
          Ints f;
          for (const auto& c : q) f.push_back(id(x + c[0], y + c[1], z + c[2]));
          Ints key = f;
          std::sort(key.begin(), key.end());
          if (!seen.insert(key).second) continue;
          if (triangles) {
            m.add({f[0], f[1], f[2]});
            m.add({f[0], f[2], f[3]});
          } else {
            m.add({f[0], f[1], f[2], f[3]});
          }
        }
  return m;
}

TEST(NonmanifoldSharp, HexGridFacesMatchOpenSubdivUnderBothBoundaryRules) {
  for (bool triangles : {false, true}) {
    const Mesh m = hex_grid_faces(2, triangles);
    const auto scheme = triangles ? sorpia::Scheme::Loop : sorpia::Scheme::CatmullClark;
    const auto s = expect_split_is_opensubdiv(m, scheme, sorpia::Boundary::EdgeAndCorner);
    EXPECT_FALSE(s.single_face_sheets.empty());
    expect_split_is_opensubdiv(m, scheme, sorpia::Boundary::EdgeOnly);
  }
}

TEST(NonmanifoldSharp, ManifoldMeshesAndWhatTheSplitRefuses) {
  const Mesh page = book(1, 3, true);
  EXPECT_TRUE(sorpia::split_nonmanifold(page.faces(), page.n_vertices).empty());
  Mesh degenerate = book(3, 2, false);
  degenerate.add({0, 0, 5});
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] {
        sorpia::split_nonmanifold(degenerate.faces(), degenerate.n_vertices);
      },
      {"repeats vertex 0", "nonmanifold=\"sharp\"", "repair"});
}

// A pillow (two faces with the same vertices in the opposite order) beside a
// third face on one of its edges: OpenSubdiv makes that edge (three faces)
// non-manifold, infinitely sharp. The pillow's two faces stay joined at both
// its ends in the split (one fan each, through the pillow's other edges), so
// the split mesh has them as the two faces of one edge again: an infinitely
// sharp crease there (sharp_edges) keeps OpenSubdiv's rule. The vertex rows do
// not read that edge (its ends are corners); the refined edge points do.
TEST(NonmanifoldSharp, PillowBesideAThirdFaceKeepsItsEdgeSharp) {
  for (const bool triangles : {true, false}) {
    Mesh m;
    if (triangles) {
      m.add({0, 1, 2});
      m.add({0, 2, 1});
      m.add({0, 1, 3});
      m.n_vertices = 4;
    } else {
      m.add({0, 1, 2, 3});
      m.add({0, 3, 2, 1});
      m.add({0, 1, 4, 5});
      m.n_vertices = 6;
    }
    Mesh two = m;  // the third face with its own pillow: two pillows on the edge
    const auto n = static_cast<std::int32_t>(m.n_vertices);
    if (triangles) {
      two.add({0, 3, 1});
    } else {
      two.add({0, 5, 4, 1});
    }
    Mesh fourth = m;  // and a fourth face, running the edge the other way
    if (triangles) {
      fourth.add({1, 0, n});
      fourth.n_vertices += 1;
    } else {
      fourth.add({1, 0, n, n + 1});
      fourth.n_vertices += 2;
    }
    const auto scheme = triangles ? sorpia::Scheme::Loop : sorpia::Scheme::CatmullClark;
    for (const Mesh* c : {&m, &two, &fourth})
      for (const auto boundary : {sorpia::Boundary::EdgeAndCorner, sorpia::Boundary::EdgeOnly}) {
        SCOPED_TRACE(std::string(triangles ? "triangles, " : "quads, ") +
                     (c == &m ? "a third face" : c == &two ? "two pillows" : "a third and a fourth face") + ", " +
                     (boundary == sorpia::Boundary::EdgeOnly ? "edge-only" : "edge-and-corner"));
        const auto s = expect_split_is_opensubdiv(*c, scheme, boundary, 3);
        EXPECT_EQ(s.nonmanifold_edges, (std::vector<std::array<std::int32_t, 2>>{{0, 1}}));
        EXPECT_EQ(s.corners, (Ints{0, 1}));
        EXPECT_EQ(s.sharp_edges.size(), c == &two ? 2u : 1u);
      }
  }
}

// A fin (one more face) on an edge of a closed surface: the surface's two
// faces of that edge lie in one fan at each of its ends (the fans round the
// surface), so the split joins them again there: sharp_edges, as for a pillow.
TEST(NonmanifoldSharp, FinOnAClosedSurfaceKeepsItsEdgeSharp) {
  for (const bool triangles : {true, false}) {
    const sorpia::Mesh closed = triangles ? sorpia::icosphere(1) : sorpia::quad_torus(6, 4);
    Mesh m;
    m.n_vertices = closed.n_vertices();
    m.counts = closed.counts();
    m.indices = closed.face_vertex_indices;
    const std::int32_t a = m.indices[0], b = m.indices[1], n = static_cast<std::int32_t>(m.n_vertices);
    if (triangles) {
      m.add({a, b, n});
      m.n_vertices += 1;
    } else {
      m.add({a, b, n, n + 1});
      m.n_vertices += 2;
    }
    const auto scheme = triangles ? sorpia::Scheme::Loop : sorpia::Scheme::CatmullClark;
    for (const auto boundary : {sorpia::Boundary::EdgeAndCorner, sorpia::Boundary::EdgeOnly}) {
      SCOPED_TRACE(triangles ? "icosphere" : "quad torus");
      const auto s = expect_split_is_opensubdiv(m, scheme, boundary);
      EXPECT_EQ(s.nonmanifold_edges, (std::vector<std::array<std::int32_t, 2>>{{std::min(a, b), std::max(a, b)}}));
      EXPECT_EQ(s.sharp_edges, (std::vector<std::array<std::int32_t, 2>>{{std::min(a, b), std::max(a, b)}}));
    }
  }
}

// OpenSubdiv's own non-manifold shapes, their faces that repeat a vertex left out.
TEST(NonmanifoldSharp, OpenSubdivShapesMatch) {
  const std::filesystem::path dir = std::filesystem::path(__FILE__).parent_path() / "../../../shared/meshes";
  int checked = 0;
  for (const char* name : {"osd_loop_nonman_edges.obj", "osd_loop_nonman_verts.obj", "osd_catmark_nonman_edges.obj",
                           "osd_catmark_nonman_verts.obj"}) {
    const auto path = dir / name;
    if (!std::filesystem::exists(path)) continue;
    const sorpia::MeshFile file = sorpia::read_mesh(path.string());
    Mesh m;
    m.n_vertices = file.n_vertices();
    for (std::size_t f = 0, at = 0; f < file.n_faces(); ++f) {
      const std::int32_t k = file.face_vertex_counts.empty() ? file.face_size : file.face_vertex_counts[f];
      const Ints face(file.face_vertex_indices.begin() + at, file.face_vertex_indices.begin() + at + k);
      at += k;
      if (std::set<std::int32_t>(face.begin(), face.end()).size() < face.size()) continue;
      m.counts.push_back(k);
      m.indices.insert(m.indices.end(), face.begin(), face.end());
    }
    SCOPED_TRACE(name);
    const bool loop = std::string(name).find("loop") != std::string::npos;
    expect_split_is_opensubdiv(m, loop ? sorpia::Scheme::Loop : sorpia::Scheme::CatmullClark);
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "../shared/meshes absent";
}

// Random corruptions of small closed and open meshes (faces reversed,
// duplicated, added on existing vertices, vertices welded), both schemes and
// boundary rules: wherever the split takes the mesh, it matches OpenSubdiv.
TEST(NonmanifoldSharp, RandomCorruptionsMatchOpenSubdiv) {
  std::vector<std::pair<Mesh, sorpia::Scheme>> bases;
  for (const auto& t : {sorpia::icosphere(1), sorpia::grid(4, 4)}) {
    Mesh m;
    m.n_vertices = t.n_vertices();
    m.counts.assign(t.n_faces(), 3);
    m.indices = t.face_vertex_indices;
    bases.push_back({m, sorpia::Scheme::Loop});
  }
  for (const auto& q : {sorpia::quad_torus(6, 4), sorpia::quad_grid(5, 4)}) {
    Mesh m;
    m.n_vertices = q.n_vertices();
    m.counts = q.face_vertex_counts;
    m.indices = q.face_vertex_indices;
    bases.push_back({m, sorpia::Scheme::CatmullClark});
  }
  int compared = 0, refused = 0;
  for (unsigned seed = 0; seed < 160; ++seed) {
    std::mt19937 rng(seed);
    auto [m, scheme] = bases[seed % bases.size()];
    std::vector<Ints> faces;
    for (std::size_t f = 0, at = 0; f < m.counts.size(); at += m.counts[f], ++f)
      faces.emplace_back(m.indices.begin() + at, m.indices.begin() + at + m.counts[f]);
    const int k = static_cast<int>(faces.front().size());
    for (int e = 0; e < 1 + static_cast<int>(rng() % 4); ++e) {
      const std::size_t i = rng() % faces.size();
      const auto v = [&] { return static_cast<std::int32_t>(rng() % m.n_vertices); };
      switch (rng() % 4) {
        case 0: std::reverse(faces[i].begin(), faces[i].end()); break;
        case 1: faces.push_back(faces[i]); break;
        case 2: {
          Ints f(static_cast<std::size_t>(k));
          for (auto& x : f) x = v();
          faces.push_back(f);
          break;
        }
        default: {
          const std::int32_t a = v(), b = v();
          for (auto& f : faces) std::replace(f.begin(), f.end(), b, a);
        }
      }
    }
    Mesh c;
    c.n_vertices = m.n_vertices;
    for (const auto& f : faces) {
      if (std::set<std::int32_t>(f.begin(), f.end()).size() < f.size()) continue;  // refused by the split
      c.counts.push_back(static_cast<std::int32_t>(f.size()));
      c.indices.insert(c.indices.end(), f.begin(), f.end());
    }
    if (c.counts.empty()) continue;
    sorpia::NonmanifoldSplit s;
    try {
      s = sorpia::split_nonmanifold(c.faces(), c.n_vertices);
    } catch (const sorpia::MeshError& e) {
      EXPECT_NE(std::string(e.what()).find("interior non-manifold crease"), std::string::npos) << e.what();
      ++refused;
      continue;
    }
    if (s.empty()) continue;
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_split_is_opensubdiv(c, scheme, sorpia::Boundary::EdgeOnly);
    expect_split_is_opensubdiv(c, scheme, sorpia::Boundary::EdgeAndCorner);
    ++compared;
  }
  EXPECT_GT(compared, 100) << refused << " refused";
}
