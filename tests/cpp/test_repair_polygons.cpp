// sorpia::repair on polygon meshes: each kind of defect built in code on quad
// and mixed polygon meshes. Every repaired mesh is checked against OpenMesh's
// Mesh, independently of sorpia's validation (add_face refuses a complex
// edge or an orientation clash; every vertex must be manifold), and against
// the input: each output face is its input face (consecutive repeats dropped)
// renumbered through vertex_map, reversed if flipped. And sorpia's polygon
// Topology accepts it.
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>
#include <vector>

#include "expect_error.hpp"
#include "face_arrays.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/repair.hpp"
#include "sorpia/topology.hpp"

namespace {

using Ints = std::vector<std::int32_t>;

struct Poly {
  Ints counts, indices;
  std::size_t n_vertices = 0;

  void add(std::initializer_list<std::int32_t> face) {
    counts.push_back(static_cast<std::int32_t>(face.size()));
    indices.insert(indices.end(), face);
  }
  Ints face(std::size_t f) const {
    std::size_t at = 0;
    for (std::size_t g = 0; g < f; ++g) at += counts[g];
    return Ints(indices.begin() + at, indices.begin() + at + counts[f]);
  }
  std::size_t n_faces() const { return counts.size(); }
};

// An nx by ny grid of quads, counter-clockwise seen from +z ((nx + 1) (ny + 1) vertices).
Poly quad_grid(int nx, int ny) {
  Poly p;
  p.n_vertices = static_cast<std::size_t>((nx + 1) * (ny + 1));
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) p.add({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  return p;
}

// A closed cube of six quads on vertices offset .. offset + 7, outward.
void add_cube(Poly& p, std::int32_t offset) {
  const std::array<std::array<std::int32_t, 4>, 6> quads = {
      {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}};
  for (const auto& q : quads) p.add({q[0] + offset, q[1] + offset, q[2] + offset, q[3] + offset});
  p.n_vertices = std::max<std::size_t>(p.n_vertices, static_cast<std::size_t>(offset) + 8);
}

// A band of n quads glued with a half twist: no consistent orientation (2 n vertices).
Poly quad_moebius(int n) {
  Poly p;
  p.n_vertices = static_cast<std::size_t>(2 * n);
  for (int i = 0; i < n; ++i) {
    const int a0 = 2 * i, a1 = 2 * i + 1;
    const int b0 = i + 1 < n ? 2 * i + 2 : 1, b1 = i + 1 < n ? 2 * i + 3 : 0;  // the twist
    p.add({a0, b0, b1, a1});
  }
  return p;
}

// OpenMesh's Mesh takes every output face and finds every referenced vertex manifold.
void expect_openmesh_manifold(const Poly& p) {
  OpenMesh::PolyMesh_ArrayKernelT<> mesh;
  omerr().disable();
  for (std::size_t v = 0; v < p.n_vertices; ++v) mesh.add_vertex({0, 0, 0});
  for (std::size_t f = 0; f < p.n_faces(); ++f) {
    std::vector<OpenMesh::VertexHandle> vh;
    for (std::int32_t v : p.face(f)) vh.push_back(mesh.vertex_handle(v));
    ASSERT_TRUE(mesh.add_face(vh).is_valid()) << "OpenMesh refuses output face " << f;
  }
  for (auto vh : mesh.vertices())
    if (!mesh.is_isolated(vh)) {
      EXPECT_TRUE(mesh.is_manifold(vh)) << "vertex " << vh.idx();
    }
}

// `face` as a cycle starting at its smallest vertex, reversed first when `reverse`.
Ints cyclic(Ints face, bool reverse) {
  if (reverse) std::reverse(face.begin(), face.end());
  std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
  return face;
}

// `face` without its consecutive repeats (cyclically).
Ints without_repeats(const Ints& face) {
  Ints kept;
  for (std::size_t k = 0; k < face.size(); ++k)
    if (face[k] != face[(k + face.size() - 1) % face.size()]) kept.push_back(face[k]);
  return kept;
}

// Repairs `in`, checks what every repair must hold and returns the repaired mesh.
Poly repaired(const Poly& in, sorpia::RepairResult* result = nullptr) {
  sorpia::RepairResult r = sorpia::repair(sorpia_test::polygons(in.counts, in.indices), in.n_vertices);
  EXPECT_FALSE(r.report.empty());
  Poly out{r.faces.face_vertex_counts, r.faces.face_vertex_indices, r.vertex_map.size()};
  EXPECT_GE(out.n_vertices, in.n_vertices);
  for (std::size_t i = 0; i < out.n_vertices; ++i) {  // the input vertices in place, then copies of them
    if (i < in.n_vertices) EXPECT_EQ(r.vertex_map[i], static_cast<std::int32_t>(i));
    else EXPECT_LT(static_cast<std::size_t>(r.vertex_map[i]), in.n_vertices);
  }
  expect_openmesh_manifold(out);
  EXPECT_NO_THROW(sorpia::Topology(sorpia_test::polygons(out.counts, out.indices), out.n_vertices));
  const std::set<std::int32_t> flipped(r.report.flipped_faces.begin(), r.report.flipped_faces.end());
  EXPECT_EQ(r.face_map.size(), out.n_faces());
  for (std::size_t j = 0; j < out.n_faces(); ++j) {
    Ints mapped = out.face(j);
    for (auto& v : mapped) v = r.vertex_map[v];
    const std::int32_t f = r.face_map[j];
    EXPECT_EQ(cyclic(mapped, false), cyclic(without_repeats(in.face(f)), flipped.count(f) > 0)) << "face " << j;
  }
  // idempotent: the output is valid, so a second repair changes nothing
  EXPECT_TRUE(sorpia::repair(sorpia_test::polygons(out.counts, out.indices), out.n_vertices).report.empty());
  if (result) *result = std::move(r);
  return out;
}

}  // namespace

TEST(RepairPolygons, ValidPolygonMeshesComeBackUnchanged) {
  Poly cube;
  add_cube(cube, 0);
  Poly mixed = quad_grid(3, 2);  // a pentagon and a triangle on top of the grid
  mixed.n_vertices += 2;
  mixed.add({8, 9, 10, 11, 12});
  mixed.add({8, 12, 13});
  for (const Poly& p : {quad_grid(4, 3), cube, mixed}) {
    const sorpia::RepairResult r = sorpia::repair(sorpia_test::polygons(p.counts, p.indices), p.n_vertices);
    EXPECT_TRUE(r.report.empty());
    EXPECT_TRUE(r.faces.face_vertex_indices.empty() && r.faces.face_vertex_counts.empty() && r.vertex_map.empty());  // "use the input"
  }
}

TEST(RepairPolygons, OpenBowtieOfQuadsGetsOneVertexPerFan) {
  Poly p;
  p.n_vertices = 7;
  p.add({0, 1, 2, 3});
  p.add({0, 4, 5, 6});
  sorpia::RepairResult r;
  const Poly out = repaired(p, &r);
  EXPECT_EQ(r.report.bowtie_vertices, Ints{0});
  EXPECT_EQ(r.report.bowtie_copies, Ints{1});
  EXPECT_EQ(out.indices, (Ints{0, 1, 2, 3, 7, 4, 5, 6}));
  EXPECT_EQ(out.counts, (Ints{4, 4}));
}

TEST(RepairPolygons, ClosedBowtieOfTwoCubesAtOneVertex) {
  Poly p;
  add_cube(p, 0);
  add_cube(p, 8);
  for (auto& v : p.indices)
    if (v == 8) v = 6;  // the second cube's corner 8 welded onto the first's 6
  sorpia::RepairResult r;
  repaired(p, &r);
  EXPECT_EQ(r.report.bowtie_vertices, Ints{6});
  EXPECT_EQ(r.report.bowtie_copies, Ints{1});
  EXPECT_TRUE(r.report.flipped_faces.empty() && r.report.nonmanifold_edges.empty());
}

TEST(RepairPolygons, ThreeQuadSheetsOnOneEdge) {
  Poly p;
  p.n_vertices = 8;
  p.add({0, 1, 2, 3});
  p.add({1, 0, 4, 5});
  p.add({0, 1, 6, 7});
  sorpia::RepairResult r;
  const Poly out = repaired(p, &r);
  EXPECT_EQ(r.report.nonmanifold_edges, (std::vector<std::array<std::int32_t, 2>>{{0, 1}}));
  EXPECT_EQ(r.report.sheet_vertices, (Ints{0, 1}));
  EXPECT_EQ(r.report.sheet_copies, (Ints{1, 1}));
  EXPECT_EQ(out.indices, (Ints{0, 1, 2, 3, 1, 0, 4, 5, 8, 9, 6, 7}));
}

TEST(RepairPolygons, FourQuadSheetsFromTwoCubesSharingAnEdge) {
  Poly p;
  add_cube(p, 0);
  add_cube(p, 8);
  for (auto& v : p.indices) v = v == 8 ? 2 : v == 9 ? 3 : v;  // cube 2's edge (8, 9) welded onto (2, 3)
  sorpia::RepairResult r;
  const Poly out = repaired(p, &r);
  EXPECT_EQ(r.report.nonmanifold_edges.size(), 1u);
  EXPECT_EQ(r.report.sheet_vertices, (Ints{2, 3}));
  EXPECT_EQ(r.report.sheet_copies, (Ints{1, 1}));
  // two closed cubes again: every edge of two faces, 12 + 12 edges
  std::set<std::pair<std::int32_t, std::int32_t>> edges;
  for (std::size_t f = 0; f < out.n_faces(); ++f) {
    const Ints q = out.face(f);
    for (std::size_t k = 0; k < q.size(); ++k) edges.insert(std::minmax(q[k], q[(k + 1) % q.size()]));
  }
  EXPECT_EQ(edges.size(), 24u);
}

TEST(RepairPolygons, DuplicateAndReversedDuplicateQuadsKeepTheFirst) {
  const Poly grid = quad_grid(3, 3);
  Poly p = grid;
  const Ints q1 = grid.face(1), q4 = grid.face(4);
  p.add({q1[2], q1[3], q1[0], q1[1]});  // quad 1 again, rotated
  p.add({q4[0], q4[3], q4[2], q4[1]});  // quad 4 reversed
  p.add({q4[1], q4[0], q4[3], q4[2]});  // quad 4 reversed again, rotated
  sorpia::RepairResult r;
  const Poly out = repaired(p, &r);
  EXPECT_EQ(r.report.duplicate_faces, Ints{9});
  EXPECT_EQ(r.report.reversed_duplicate_faces, (Ints{10, 11}));
  EXPECT_EQ(out.indices, grid.indices);
}

TEST(RepairPolygons, QuadsSharingTwoEdgesAreNoDuplicates) {
  // two quads sharing two edges (at a vertex of two faces) are valid together;
  // with a third face on an edge of one of them, repair separates that edge only
  Poly p;
  p.n_vertices = 8;
  p.add({0, 1, 2, 3});
  p.add({2, 1, 0, 4});
  p.add({2, 3, 6});
  p.add({3, 2, 7});
  sorpia::RepairResult r;
  repaired(p, &r);
  EXPECT_TRUE(r.report.duplicate_faces.empty() && r.report.reversed_duplicate_faces.empty());
  EXPECT_EQ(r.report.nonmanifold_edges, (std::vector<std::array<std::int32_t, 2>>{{2, 3}}));
}

TEST(RepairPolygons, RepeatedCornersCollapseOrTheFaceIsRemoved) {
  // a triangle stored as a quad (a, b, c, c) and one with its repeat wrapping round are
  // kept as triangles; a face crossing itself at a vertex, or of one vertex, is removed
  const Poly grid = quad_grid(2, 1);  // vertices 0..5
  Poly p = grid;
  p.n_vertices = 9;
  p.add({2, 6, 5, 5});      // face 2: (2, 6, 5)
  p.add({6, 2, 7, 6});      // face 3: (6, 2, 7)... sharing edge (2, 6) with face 2 the other way
  p.add({7, 8, 7, 2});      // face 4: 7 twice, not consecutively: removed
  p.add({8, 8, 8, 8});      // face 5: removed
  sorpia::RepairResult r;
  const Poly out = repaired(p, &r);
  EXPECT_EQ(r.report.collapsed_faces, (Ints{2, 3}));
  EXPECT_EQ(r.report.degenerate_faces, (Ints{4, 5}));
  EXPECT_EQ(out.counts, (Ints{4, 4, 3, 3}));
  EXPECT_EQ(Ints(out.indices.begin() + 8, out.indices.end()), (Ints{2, 6, 5, 2, 7, 6}));
}

TEST(RepairPolygons, MixedOrientationFlipsTheFewerQuads) {
  const Poly grid = quad_grid(4, 4);
  Poly p = grid;
  std::size_t at = 0;
  for (std::size_t f = 0; f < p.n_faces(); at += p.counts[f], ++f)
    if (f == 3 || f == 7 || f == 8) std::reverse(p.indices.begin() + at + 1, p.indices.begin() + at + 4);
  sorpia::RepairResult r;
  const Poly out = repaired(p, &r);
  EXPECT_EQ(r.report.flipped_faces, (Ints{3, 7, 8}));
  EXPECT_EQ(out.indices, grid.indices);
}

TEST(RepairPolygons, QuadMoebiusStripIsCutAlongOneEdge) {
  sorpia::RepairResult r;
  const Poly out = repaired(quad_moebius(7), &r);
  ASSERT_EQ(r.report.cut_edges.size(), 1u);
  EXPECT_EQ(r.report.cut_copies, (Ints{1, 1}));
  EXPECT_EQ(out.n_vertices, 16u);
}

TEST(RepairPolygons, WhatRepairDoesNotChangeIsRefusedAsValidationRefusesIt) {
  Poly p;
  p.n_vertices = 5;
  p.add({0, 1, 2, 3});
  p.add({0, 3, 9});
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] { sorpia::repair(sorpia_test::polygons(p.counts, p.indices), p.n_vertices); }, {"out of range"});
  const Ints two = {4, 2}, idx = {0, 1, 2, 3, 0, 1};
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::repair(sorpia_test::polygons(two, idx), 4); },
                                               {"face 1 has 2 vertices"});
  Poly flat;
  flat.n_vertices = 3;
  flat.add({0, 1, 1});
  flat.add({2, 2, 2, 2});
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] { sorpia::repair(sorpia_test::polygons(flat.counts, flat.indices), flat.n_vertices); },
      {"no face is left"});
}

TEST(RepairPolygons, AUniformMeshIsTheMeshWithCounts) {
  // Quads given as a uniform sorpia::Mesh (face_size 4, no counts) repair and
  // split as the same quads with counts; repair gives counts, the split keeps
  // the input's form; the form is checked with Topology's messages.
  Poly p = quad_grid(3, 2);
  std::reverse(p.indices.begin() + 5, p.indices.begin() + 8);  // quad 1 flipped
  p.counts.push_back(4);
  p.indices.insert(p.indices.end(), p.indices.begin(), p.indices.begin() + 4);  // quad 0 twice
  sorpia::Mesh uniform;
  uniform.face_vertex_indices = p.indices;
  uniform.face_size = 4;
  const sorpia::Mesh counted = sorpia_test::polygons(p.counts, p.indices);
  const auto a = sorpia::repair(uniform, p.n_vertices), b = sorpia::repair(counted, p.n_vertices);
  EXPECT_EQ(a.report.duplicate_faces, Ints{6});
  EXPECT_EQ(a.report.flipped_faces, b.report.flipped_faces);
  EXPECT_EQ(a.faces.face_vertex_counts, Ints(6, 4));
  EXPECT_EQ(a.faces.face_vertex_indices, b.faces.face_vertex_indices);
  EXPECT_EQ(a.vertex_map, b.vertex_map);
  EXPECT_EQ(a.face_map, b.face_map);
  const auto s = sorpia::split_nonmanifold(uniform, p.n_vertices), t = sorpia::split_nonmanifold(counted, p.n_vertices);
  ASSERT_FALSE(s.empty());
  EXPECT_TRUE(s.faces.uniform());
  EXPECT_EQ(s.faces.face_size, 4);
  EXPECT_EQ(s.faces.face_vertex_indices, t.faces.face_vertex_indices);
  EXPECT_EQ(t.faces.face_vertex_counts, p.counts);
  EXPECT_EQ(s.vertex_map, t.vertex_map);

  uniform.face_size = 3;  // 28 indices
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::repair(uniform, p.n_vertices); },
                                               {"28 entries, not a multiple of face_size 3"});
  uniform.face_size = 2;
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::split_nonmanifold(uniform, p.n_vertices); },
                                               {"face_size is 2"});
  Ints short_indices(p.indices.begin(), p.indices.end() - 1);
  sorpia_test::expect_error<sorpia::MeshError>(
      [&] { sorpia::repair(sorpia_test::polygons(p.counts, short_indices), p.n_vertices); },
      {"face_vertex_counts sum to 28 but face_vertex_indices has 27 entries"});
}

TEST(RepairPolygons, TrianglesAsPolygonsRepairAsTriangles) {
  // the polygon entry on an all-triangle list makes the triangle entry's changes
  const std::vector<std::int32_t> tri = {0, 1, 2, 1, 0, 3, 0, 1, 4, 0, 5, 6, 2, 1, 0};
  const Ints counts(5, 3);
  const auto a = sorpia::repair(sorpia_test::triangles(tri), 7);
  const auto b = sorpia::repair(sorpia_test::polygons(counts, tri), 7);
  EXPECT_EQ(a.faces.face_vertex_indices, b.faces.face_vertex_indices);
  EXPECT_EQ(a.vertex_map, b.vertex_map);
  EXPECT_EQ(a.face_map, b.face_map);
  EXPECT_EQ(b.faces.face_vertex_counts, Ints(b.face_map.size(), 3));
  EXPECT_EQ(a.report.reversed_duplicate_faces, b.report.reversed_duplicate_faces);
  EXPECT_EQ(a.report.sheet_copies, b.report.sheet_copies);
}
