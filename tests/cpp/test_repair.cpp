// sorpia::repair on each kind of defect, built in code. Every repaired mesh is
// checked against OpenMesh, independently of sorpia's validation: each face
// goes into a half-edge mesh by add_face (which refuses a complex edge or an
// orientation clash) and every vertex must be manifold there; and against the
// input: each output face is its input face renumbered through vertex_map.
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <set>
#include <vector>

#include "bad_faces.hpp"
#include "expect_error.hpp"
#include "face_arrays.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/repair.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace {

using sorpia_test::Faces;
using Ints = std::vector<std::int32_t>;

// OpenMesh takes every face of `faces` and finds every referenced vertex manifold.
void expect_openmesh_manifold(const Faces& faces, std::size_t n_vertices) {
  OpenMesh::TriMesh_ArrayKernelT<> mesh;
  omerr().disable();
  for (std::size_t v = 0; v < n_vertices; ++v) mesh.add_vertex({0, 0, 0});
  for (std::size_t f = 0; f < faces.size() / 3; ++f) {
    ASSERT_TRUE(mesh.add_face(mesh.vertex_handle(faces[3 * f]), mesh.vertex_handle(faces[3 * f + 1]),
                              mesh.vertex_handle(faces[3 * f + 2]))
                    .is_valid())
        << "OpenMesh refuses output face " << f;
  }
  for (auto vh : mesh.vertices())
    if (!mesh.is_isolated(vh)) {
      EXPECT_TRUE(mesh.is_manifold(vh)) << "vertex " << vh.idx();
    }
}

// The three corners of face f, rotated to start at the smallest, reversed when `reverse`.
std::array<std::int32_t, 3> cyclic(const std::int32_t* t, bool reverse) {
  std::array<std::int32_t, 3> c = {t[0], reverse ? t[2] : t[1], reverse ? t[1] : t[2]};
  std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
  return c;
}

// Repairs `faces`, checks what every repair must hold and returns the result.
sorpia::RepairResult repaired(const Faces& faces, std::size_t n_vertices) {
  sorpia::RepairResult r = sorpia::repair(sorpia_test::triangles(faces), n_vertices);
  EXPECT_FALSE(r.report.empty());
  const std::size_t n_out = r.vertex_map.size();
  EXPECT_GE(n_out, n_vertices);
  for (std::size_t i = 0; i < n_out; ++i) {  // the input vertices in place, then copies of them
    if (i < n_vertices) EXPECT_EQ(r.vertex_map[i], static_cast<std::int32_t>(i));
    else EXPECT_LT(static_cast<std::size_t>(r.vertex_map[i]), n_vertices);
  }
  EXPECT_NO_THROW(sorpia::Topology(sorpia_test::triangles(r.faces.face_vertex_indices), n_out));
  expect_openmesh_manifold(r.faces.face_vertex_indices, n_out);
  // each output face: its input face, renumbered, reversed if flipped
  const std::set<std::int32_t> flipped(r.report.flipped_faces.begin(), r.report.flipped_faces.end());
  EXPECT_EQ(r.face_map.size(), r.faces.face_vertex_indices.size() / 3);
  for (std::size_t j = 0; j < r.face_map.size(); ++j) {
    const std::int32_t f = r.face_map[j];
    const std::array<std::int32_t, 3> mapped = {r.vertex_map[r.faces.face_vertex_indices[3 * j]], r.vertex_map[r.faces.face_vertex_indices[3 * j + 1]],
                                                r.vertex_map[r.faces.face_vertex_indices[3 * j + 2]]};
    EXPECT_EQ(cyclic(mapped.data(), false), cyclic(faces.data() + 3 * f, flipped.count(f) > 0)) << "face " << j;
  }
  // idempotent: the output is valid, so a second repair changes nothing
  EXPECT_TRUE(sorpia::repair(r.faces, n_out).report.empty());
  return r;
}

}  // namespace

TEST(Repair, ValidMeshesComeBackUnchanged) {
  for (const auto& m : {sorpia::icosphere(2), sorpia::grid(5, 4), sorpia::irregular(300, 2), sorpia::pole(9)}) {
    const sorpia::RepairResult r = sorpia::repair(m, m.n_vertices());
    EXPECT_TRUE(r.report.empty());
    EXPECT_TRUE(r.faces.face_vertex_indices.empty() && r.vertex_map.empty() && r.face_map.empty());  // "use the input"
  }
}

TEST(Repair, OpenBowtieGetsOneVertexPerFan) {
  const auto r = repaired(sorpia_test::bowtie_open_fans, 5);
  EXPECT_EQ(r.report.bowtie_vertices, Ints{0});
  EXPECT_EQ(r.report.bowtie_copies, Ints{1});
  EXPECT_EQ(r.faces.face_vertex_indices, (Faces{0, 1, 2, 5, 3, 4}));  // the first fan keeps vertex 0, the second gets copy 5
  EXPECT_TRUE(r.report.sheet_vertices.empty() && r.report.flipped_faces.empty());
}

TEST(Repair, ClosedBowtieGetsOneVertexPerCone) {
  const auto r = repaired(sorpia_test::bowtie_closed_cones, 7);
  EXPECT_EQ(r.report.bowtie_vertices, Ints{0});
  EXPECT_EQ(r.report.bowtie_copies, Ints{1});
  EXPECT_EQ(r.vertex_map.size(), 8u);
  EXPECT_EQ(r.vertex_map[7], 0);
  // the first cone (faces 0-3) keeps vertex 0; the second's apex (faces 4-6) is the copy
  EXPECT_EQ(std::count(r.faces.face_vertex_indices.begin(), r.faces.face_vertex_indices.begin() + 12, 7), 0);
  for (int f = 4; f < 7; ++f) EXPECT_EQ(r.faces.face_vertex_indices[3 * f], 7);
}

TEST(Repair, ThreeSheetsOnOneEdge) {
  // faces 0 and 1 run edge (0, 1) both ways: they stay one sheet; face 2 leaves with copies of 0 and 1
  const auto r = repaired(sorpia_test::edge_with_three_faces, 5);
  EXPECT_EQ(r.report.nonmanifold_edges, (std::vector<std::array<std::int32_t, 2>>{{0, 1}}));
  EXPECT_EQ(r.report.sheet_vertices, (Ints{0, 1}));
  EXPECT_EQ(r.report.sheet_copies, (Ints{1, 1}));
  EXPECT_EQ(r.faces.face_vertex_indices, (Faces{0, 1, 2, 1, 0, 3, 5, 6, 4}));
}

TEST(Repair, FourSheetsOnOneEdgeFromTwoClosedSurfaces) {
  // Two tetrahedra, (0, 1, 2, 3) and (0, 1, 4, 5), sharing edge (0, 1). The faces at the edge are
  // interleaved: face order alone would pair faces 0 and 1; the direction rule pairs each tetrahedron's own.
  const Faces f = {0, 1, 2, 0, 1, 4, 1, 0, 3, 1, 0, 5,  // the four faces at edge (0, 1)
                   0, 2, 3, 1, 3, 2, 0, 4, 5, 1, 5, 4};
  const auto r = repaired(f, 6);
  EXPECT_EQ(r.report.nonmanifold_edges.size(), 1u);
  EXPECT_EQ(r.report.sheet_vertices, (Ints{0, 1}));
  EXPECT_EQ(r.report.sheet_copies, (Ints{1, 1}));
  // a closed result: every edge has two faces
  const sorpia::Topology topo(sorpia_test::triangles(r.faces.face_vertex_indices), r.vertex_map.size());
  EXPECT_EQ(topo.n_boundary_edges(), 0u);
  EXPECT_EQ(r.faces.face_vertex_indices, (Faces{0, 1, 2, 6, 7, 4, 1, 0, 3, 7, 6, 5, 0, 2, 3, 1, 3, 2, 6, 4, 5, 7, 5, 4}));
}

TEST(Repair, DuplicateAndReversedDuplicateFacesKeepTheFirst) {
  auto m = sorpia::icosphere(1);
  Faces f = m.face_vertex_indices;
  f.insert(f.end(), {m.face_vertex_indices[4], m.face_vertex_indices[5], m.face_vertex_indices[3]});  // face 1 again, rotated
  f.insert(f.end(), {m.face_vertex_indices[6], m.face_vertex_indices[8], m.face_vertex_indices[7]});  // face 2 reversed
  const auto r = repaired(f, m.n_vertices());
  EXPECT_EQ(r.report.duplicate_faces, Ints{80});
  EXPECT_EQ(r.report.reversed_duplicate_faces, Ints{81});
  EXPECT_EQ(r.faces.face_vertex_indices, m.face_vertex_indices);
}

TEST(Repair, DegenerateFacesAreRemovedAndTheirVerticesKept) {
  auto m = sorpia::grid(3, 3);
  Faces f = m.face_vertex_indices;
  f.insert(f.begin(), {4, 4, 9});  // vertex 9 is new: used by this face only
  const auto r = repaired(f, 10);
  EXPECT_EQ(r.report.degenerate_faces, Ints{0});
  EXPECT_EQ(r.vertex_map.size(), 10u);
  EXPECT_EQ(r.faces.face_vertex_indices, m.face_vertex_indices);
}

TEST(Repair, MixedOrientationFlipsTheFewerFaces) {
  auto m = sorpia::icosphere(2);
  Faces f = m.face_vertex_indices;
  for (int g : {3, 50, 51, 200}) std::swap(f[3 * g + 1], f[3 * g + 2]);
  const auto r = repaired(f, m.n_vertices());
  EXPECT_EQ(r.report.flipped_faces, (Ints{3, 50, 51, 200}));
  EXPECT_EQ(r.faces.face_vertex_indices, m.face_vertex_indices);
  // a whole component reversed is consistent: left as it is
  Faces all = m.face_vertex_indices;
  for (std::size_t g = 0; g < m.n_faces(); ++g) std::swap(all[3 * g + 1], all[3 * g + 2]);
  EXPECT_TRUE(sorpia::repair(sorpia_test::triangles(all), m.n_vertices()).report.empty());
}

TEST(Repair, MoebiusStripIsCutAlongOneEdge) {
  // a band one quad wide: every vertex on its boundary, so one edge across it, its ends split, orients it
  const auto r = repaired(sorpia_test::moebius(8), 16);
  ASSERT_EQ(r.report.cut_edges.size(), 1u);
  EXPECT_EQ(r.report.cut_vertices, (Ints{r.report.cut_edges[0][0], r.report.cut_edges[0][1]}));
  EXPECT_EQ(r.report.cut_copies, (Ints{1, 1}));
  EXPECT_TRUE(r.report.nonmanifold_edges.empty() && r.report.cut_nonmanifold_edges.empty());
  EXPECT_EQ(r.vertex_map.size(), 18u);
}

TEST(Repair, WhatRepairDoesNotChangeIsRefusedAsValidationRefusesIt) {
  const Faces f = {0, 1, 2, 0, 2, 9};
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::repair(sorpia_test::triangles(f), 4); }, {"out of range"});
  sorpia_test::expect_error<sorpia::MeshError>([&] { sorpia::repair(sorpia_test::triangles({}), 4); }, {"no faces"});
}

TEST(Repair, ManyDefectsAtOnceOnAnIrregularMesh) {
  auto m = sorpia::irregular(2000, 4);
  Faces f = m.face_vertex_indices;
  const auto n = static_cast<std::int32_t>(m.n_vertices());
  for (int g = 0; g < 40; ++g) std::swap(f[3 * (50 * g) + 1], f[3 * (50 * g) + 2]);   // flipped
  for (int g = 0; g < 20; ++g) {  // duplicates
    const std::int32_t* t = m.face_vertex_indices.data() + 3 * (17 * g + 1);
    f.insert(f.end(), {t[0], t[1], t[2]});
  }
  for (int g = 0; g < 10; ++g) {  // a third face on an edge
    const std::int32_t* t = m.face_vertex_indices.data() + 3 * (31 * g + 3);
    f.insert(f.end(), {t[0], t[1], n + 20 + g});
  }
  for (int g = 0; g < 10; ++g) f.insert(f.end(), {(13 * g) % n, n + 2 * g, n + 2 * g + 1});  // bowties
  const auto r = repaired(f, m.n_vertices() + 30);
  EXPECT_EQ(r.report.duplicate_faces.size() + r.report.reversed_duplicate_faces.size(), 20u);
  EXPECT_EQ(r.report.nonmanifold_edges.size(), 10u);
  for (int g = 0; g < 10; ++g) {
    const std::int32_t v = (13 * g) % n;
    const auto& bow = r.report.bowtie_vertices;
    const auto& sheet = r.report.sheet_vertices;
    EXPECT_TRUE(std::count(bow.begin(), bow.end(), v) + std::count(sheet.begin(), sheet.end(), v) == 1) << v;
  }
}
