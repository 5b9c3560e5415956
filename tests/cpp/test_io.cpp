// Mesh files: bit-exact round trips, errors that name the file and line,
// atomic writes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "expect_error.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/io.hpp"
#include "sorpia/shapes.hpp"

namespace {

namespace fs = std::filesystem;

class IoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("sorpia_io_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write_text(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }
  fs::path dir_;
};

// float64 values with no short decimal form, extremes, -0.0 and subnormals.
sorpia::Mesh awkward_mesh() {
  sorpia::Mesh m;
  m.vertices = {1.0 / 3.0, M_PI * 1e-7, 1e300, -0.0, 5e-324, std::numeric_limits<double>::denorm_min() * 12345,
                0.1, 0.2, 0.30000000000000004, -std::numeric_limits<double>::max(), 2.2250738585072014e-308, 1.0};
  m.face_vertex_indices = {0, 1, 2, 0, 2, 3};
  return m;
}

TEST_F(IoTest, FloatFormatsRoundTripBitForBit) {
  const auto m = awkward_mesh();
  for (const auto& [name, binary] : {std::pair{"a.obj", false}, {"a.off", false}, {"a.ply", false}, {"b.ply", true}}) {
    sorpia::write_mesh(path(name), m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(), m.n_faces(), binary);
    const auto r = sorpia::read_mesh(path(name));
    ASSERT_EQ(r.vertices.size(), m.vertices.size()) << name;
    EXPECT_EQ(std::memcmp(r.vertices.data(), m.vertices.data(), 8 * m.vertices.size()), 0) << name;
    EXPECT_EQ(r.face_vertex_indices, m.face_vertex_indices) << name;
  }
}

// write_mesh(Mesh) and read_mesh agree on the one mesh type: a mixed polygon
// mesh keeps its counts, a uniform one (quads, triangles) comes back with
// empty counts and its face size. Compared with the mesh written, exactly.
TEST_F(IoTest, MeshRoundTripKeepsCountsAndUniformFaces) {
  sorpia::Mesh quads = sorpia::quad_grid(4, 3);
  quads.face_vertex_counts.clear();  // the uniform form: every face has face_size corners
  quads.face_size = 4;
  for (const auto& [name, m] : {std::pair{"poly.obj", sorpia::polygon_torus(6, 5, 2)}, {"quads.ply", quads},
                                {"tri.off", sorpia::torus(5, 4)}}) {
    sorpia::write_mesh(path(name), m, false);
    const sorpia::MeshFile r = sorpia::read_mesh(path(name));
    EXPECT_EQ(r.vertices, m.vertices) << name;
    EXPECT_EQ(r.face_vertex_indices, m.face_vertex_indices) << name;
    EXPECT_EQ(r.counts(), m.counts()) << name;
    const bool mixed = !m.uniform() && std::any_of(m.face_vertex_counts.begin(), m.face_vertex_counts.end(),
                                                   [&](std::int32_t k) { return k != m.face_vertex_counts[0]; });
    EXPECT_EQ(r.uniform(), !mixed) << name;
    EXPECT_EQ(r.n_faces(), m.n_faces()) << name;
  }
}

TEST_F(IoTest, StlRoundsToFloat32AndMergesEqualCorners) {
  const auto m = sorpia::icosphere(1);
  sorpia::write_mesh(path("a.stl"), m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(), m.n_faces(), true);
  const auto r = sorpia::read_mesh(path("a.stl"));
  EXPECT_EQ(r.n_vertices(), m.n_vertices());  // corners merged back into the 42 vertices
  ASSERT_EQ(r.n_faces(), m.n_faces());
  for (std::size_t k = 0; k < r.face_vertex_indices.size(); ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(r.vertices[3 * r.face_vertex_indices[k] + c], static_cast<double>(static_cast<float>(m.vertices[3 * m.face_vertex_indices[k] + c])));
}

TEST_F(IoTest, PolygonsAreKeptUnlessTriangulated) {
  write_text("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n# a quad\nf 1 2 3 4\n");
  const auto q = sorpia::read_mesh(path("quad.obj"));
  EXPECT_EQ(q.face_vertex_indices, (std::vector<std::int32_t>{0, 1, 2, 3}));
  EXPECT_TRUE(q.face_vertex_counts.empty());
  EXPECT_EQ(q.face_size, 4);
  EXPECT_EQ(q.n_faces(), 1u);
  EXPECT_EQ(q.polygons_split, 0u);
  const auto r = sorpia::read_mesh(path("quad.obj"), {true, false});
  EXPECT_EQ(r.face_vertex_indices, (std::vector<std::int32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_TRUE(r.all_triangles());
  EXPECT_EQ(r.polygons_split, 1u);
}

TEST_F(IoTest, MixedPolygonsKeepTheirSizesAndSplitsAreCounted) {
  // A triangle, two quads and a pentagon, in OBJ and OFF: sizes 3, 4, 4, 5 as
  // read; 3 polygons split, 1 + 2 + 2 + 3 triangles in all, with triangulate.
  write_text("mix.obj",
             "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
             "f 1 2 3\nf 1 2 3 4\nf 2 5 6 3\nf 1 2 5 6 4\n");
  write_text("mix.off", "OFF\n6 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n"
                        "3 0 1 2\n4 0 1 2 3\n4 1 4 5 2\n5 0 1 4 5 3\n");
  const std::vector<std::int32_t> corners{0, 1, 2, 0, 1, 2, 3, 1, 4, 5, 2, 0, 1, 4, 5, 3};
  for (const char* name : {"mix.obj", "mix.off"}) {
    const auto kept = sorpia::read_mesh(path(name));
    EXPECT_EQ(kept.face_vertex_counts, (std::vector<std::int32_t>{3, 4, 4, 5})) << name;
    EXPECT_EQ(kept.face_vertex_indices, corners) << name;
    const auto r = sorpia::read_mesh(path(name), {true, false});
    EXPECT_EQ(r.polygons_split, 3u) << name;
    EXPECT_EQ(r.face_vertex_indices.size(), 3u * (1 + 2 + 2 + 3)) << name;
    EXPECT_TRUE(r.all_triangles()) << name;
  }
  write_text("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(sorpia::read_mesh(path("tri.obj"), {true, false}).polygons_split, 0u);
}

TEST_F(IoTest, PolygonsRoundTripInEveryFormatButStl) {
  // Sizes 5, 3, 4 (the first face sets no common size) and a 300-gon (PLY's
  // uchar count cannot hold it: the writer switches to an int count).
  std::vector<double> v;
  for (int i = 0; i < 300; ++i) v.insert(v.end(), {std::cos(i * 0.02), std::sin(i * 0.02), i / 7.0});
  std::vector<std::int32_t> sizes{5, 3, 4, 300}, faces{0, 1, 2, 3, 4, 4, 5, 6, 6, 7, 8, 9};
  for (int i = 0; i < 300; ++i) faces.push_back(299 - i);
  const sorpia::MeshView view{v.data(), 300, faces.data(), sizes.size(), sizes.data(), 3};
  for (const auto& [name, binary] : {std::pair{"p.obj", false}, {"p.off", false}, {"p.ply", false}, {"q.ply", true}}) {
    sorpia::write_mesh(path(name), view, binary);
    const auto r = sorpia::read_mesh(path(name));
    EXPECT_EQ(r.vertices, v) << name;
    EXPECT_EQ(r.face_vertex_indices, faces) << name;
    EXPECT_EQ(r.face_vertex_counts, sizes) << name;
  }
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::write_mesh(path("p.stl"), view); }, {"STL stores triangles only"});
}

TEST_F(IoTest, ObjTagsAsOpenSubdivReadsThem) {
  write_text("tags.obj",
             "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
             "f 1 2 3 4\nf 2 5 6 3\n"
             "t crease 2/1/0 0 1 2.5\n"
             "t crease 4/1/0 1 2  2 3 10\n"     // two edges (pairs), one sharpness
             "t crease 4/2/0 4 5 5 2 1 -3\n"    // one each; negative counts as 0
             "t corner 1/1/0 4 0.7\n"
             "t hole 1/0/0 1\n"
             "t interpolateboundary 1/0/0 2\n"
             "t creasemethod 0/0/1 normal\n"
             "t facevaryinginterpolateboundary 1/0/0 1\n"
             "t mystery 0/0/0\nt mystery 1/0/0 3\n");
  const auto m = sorpia::read_mesh(path("tags.obj"), {false, true});
  EXPECT_EQ(m.tags.tags.crease_vertices, (std::vector<std::int32_t>{0, 1, 1, 2, 2, 3, 4, 5, 5, 2}));
  EXPECT_EQ(m.tags.tags.crease_sharpness, (std::vector<double>{2.5, 10, 10, 1, 0}));
  EXPECT_EQ(m.tags.tags.corner_vertices, (std::vector<std::int32_t>{4}));
  EXPECT_EQ(m.tags.tags.corner_sharpness, (std::vector<double>{0.7}));
  EXPECT_EQ(m.tags.tags.holes, (std::vector<std::int32_t>{1}));
  ASSERT_TRUE(m.tags.boundary.has_value());
  EXPECT_EQ(*m.tags.boundary, sorpia::Boundary::EdgeOnly);
  ASSERT_EQ(m.tags.unknown.size(), 1u);
  EXPECT_EQ(m.tags.unknown[0], "'mystery': 2 tags, the first on line 17");
  EXPECT_TRUE(sorpia::read_mesh(path("tags.obj")).tags.empty());  // not read unless asked
  // With triangulate, the hole is the two triangles of face 1.
  EXPECT_EQ(sorpia::read_mesh(path("tags.obj"), {true, true}).tags.tags.holes, (std::vector<std::int32_t>{2, 3}));
}

TEST_F(IoTest, TagsRoundTripBitForBit) {
  write_text("in.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3 4\nf 2 5 6 3\n"
                       "t crease 2/1/0 1 2 0.30000000000000004\nt corner 1/1/0 0 inf\nt hole 1/0/0 0\n"
                       "t interpolateboundary 1/0/0 1\n");
  const auto m = sorpia::read_mesh(path("in.obj"), {false, true});
  const sorpia::MeshView view{m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(), m.n_faces(), nullptr, m.face_size};
  sorpia::write_mesh(path("out.obj"), view, false, &m.tags);
  const auto r = sorpia::read_mesh(path("out.obj"), {false, true});
  EXPECT_EQ(r.tags.tags.crease_vertices, m.tags.tags.crease_vertices);
  EXPECT_EQ(std::memcmp(r.tags.tags.crease_sharpness.data(), m.tags.tags.crease_sharpness.data(), 8), 0);
  EXPECT_EQ(r.tags.tags.corner_sharpness, m.tags.tags.corner_sharpness);
  EXPECT_TRUE(std::isinf(r.tags.tags.corner_sharpness[0]));
  EXPECT_EQ(r.tags.tags.holes, m.tags.tags.holes);
  EXPECT_EQ(r.tags.boundary, m.tags.boundary);
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::write_mesh(path("out.ply"), view, false, &m.tags); }, {".obj files only"});
}

// Texture coordinates and normals: per corner from OBJ (the values each corner names in the text, relative indices
// too), kept through triangulation by vertex, written back as "f a/b/c"; per vertex from and to PLY.
TEST_F(IoTest, ObjFaceVaryingValuesFollowTheirCorners) {
  write_text("in.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nvt 0 0\nvt 0.5 0\nvt 0.5 0.5\nvt 0 0.5\n"
                       "vt 0.75 0.25\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf 2/-1/-1 5/-1/1 3/3/1\n");
  sorpia::ReadOptions options;
  options.attributes = true;
  const auto m = sorpia::read_mesh(path("in.obj"), options);
  ASSERT_EQ(m.uvs.width, 2);
  EXPECT_EQ(m.uvs.indices, (std::vector<std::int32_t>{0, 1, 2, 3, 4, 4, 2}));  // vt -1 of 5 read: the 5th (index 4)
  EXPECT_EQ(m.normals.indices, (std::vector<std::int32_t>(7, 0)));
  EXPECT_EQ(m.uvs.values[2 * 4], 0.75);
  // Triangulated: each triangle corner keeps the value its quad corner had at the same vertex.
  options.triangulate = true;
  const auto t = sorpia::read_mesh(path("in.obj"), options);
  ASSERT_EQ(t.face_vertex_indices.size(), t.uvs.indices.size());
  const std::int32_t quad_value[4] = {0, 1, 2, 3};  // vertex v of the quad has value v
  for (std::size_t c = 0; c < 6; ++c) EXPECT_EQ(t.uvs.indices[c], quad_value[t.face_vertex_indices[c]]) << c;
  // Written back and read again: the same value at every corner.
  sorpia::MeshView view{m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(), m.n_faces(), m.face_vertex_counts.data(), 0};
  view.uvs = {m.uvs.values.data(), m.uvs.n_values(), m.uvs.width, m.uvs.indices.data()};
  view.normals = {m.normals.values.data(), m.normals.n_values(), m.normals.width, m.normals.indices.data()};
  sorpia::write_mesh(path("out.obj"), view);
  options.triangulate = false;
  const auto r = sorpia::read_mesh(path("out.obj"), options);
  ASSERT_EQ(r.uvs.indices.size(), m.uvs.indices.size());
  for (std::size_t c = 0; c < r.uvs.indices.size(); ++c)
    for (int k = 0; k < 2; ++k) EXPECT_EQ(r.uvs.values[2 * r.uvs.indices[c] + k], m.uvs.values[2 * m.uvs.indices[c] + k]);
  // PLY holds one value per vertex: vertex 1 has two (0.5 0 and 0.75 0.25).
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::write_mesh(path("out.ply"), view); },
                                                    {"vertex 1 has different ones in different faces"});
  sorpia_test::expect_error<sorpia::ParameterError>([&] { sorpia::write_mesh(path("out.off"), view); },
                                                    {".obj and .ply files only"});
  // An index past the values names its line, once the whole file is read.
  write_text("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2 2/1 3/1\nvt 0 0\n");
  sorpia_test::expect_error<sorpia::FileError>([&] { sorpia::read_mesh(path("bad.obj"), options); },
                                               {"line 4: texture coordinate index 2 is out of range"});
}

TEST_F(IoTest, PlyPerVertexValuesRoundTrip) {
  const auto m = sorpia::icosphere(1);
  std::vector<double> uv(2 * m.n_vertices()), normal(m.vertices);
  for (std::size_t i = 0; i < uv.size(); ++i) uv[i] = 1.0 / (3.0 + static_cast<double>(i));
  sorpia::MeshView view{m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(), m.n_faces(), nullptr, 3};
  view.uvs = {uv.data(), m.n_vertices(), 2, m.face_vertex_indices.data()};  // per vertex: the corner's vertex is its value
  view.normals = {normal.data(), m.n_vertices(), 3, m.face_vertex_indices.data()};
  sorpia::ReadOptions options;
  options.attributes = true;
  for (const bool binary : {false, true}) {
    sorpia::write_mesh(path("a.ply"), view, binary);
    const auto r = sorpia::read_mesh(path("a.ply"), options);
    EXPECT_EQ(r.uvs.values, uv) << binary;  // bit for bit: double properties
    EXPECT_EQ(r.normals.values, normal) << binary;
    EXPECT_EQ(r.uvs.indices, m.face_vertex_indices) << binary;
    EXPECT_EQ(r.vertices, m.vertices) << binary;
  }
}

TEST_F(IoTest, BadTagsNameTheirLine) {
  const std::string head = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
  const std::pair<const char*, const char*> cases[] = {
      {"t crease 3/1/0 0 1 2 5\n", "line 5: tag 'crease' takes vertex pairs"},
      {"t crease 2/1/0 0 1\n", "line 5: tag 'crease': the line ends before its number arguments"},
      {"t crease 2/1/0 0 7 1\n", "line 5: tag vertex 7 is out of range: the file has 3 vertices"},
      {"t crease 2/1/0 1 1 1\n", "line 5: tag 'crease': edge (1, 1) has one vertex twice"},
      {"t crease 2/1/0 0 1 nan\n", "line 5: tag 'crease': expected a number, found 'nan'"},
      {"t crease 4/3/0 0 1 1 2 1 2 3\n", "2 tags need one sharpness for all or one each, found 3"},
      {"t hole 1/0/0 1\n", "line 5: tag 'hole': face 1 is out of range: the file has 1 faces"},
      {"t interpolateboundary 1/0/0 0\n", "line 5: tag 'interpolateboundary 0' (no boundary interpolation"},
      {"t creasemethod 0/0/1 chaikin\n", "line 5: tag 'creasemethod chaikin' is not supported"},
      {"t smoothtriangles 0/0/1 smooth\n", "line 5: tag 'smoothtriangles smooth' is not supported"},
      {"t crease 2/1 0 1 1\n", "line 5: tag 'crease': expected argument counts I/F/S"},
      {"t crease 2/1/0 0 1 1 extra\n", "line 5: tag 'crease': 'extra' after the arguments"},
      {"t crease 900/1/0 0 1 1\n", "counts more arguments than the line holds"},
  };
  for (const auto& [line, message] : cases) {
    write_text("bad.obj", head + line);
    sorpia_test::expect_error<sorpia::FileError>([&] { sorpia::read_mesh(path("bad.obj"), {false, true}); }, {message});
    EXPECT_NO_THROW(sorpia::read_mesh(path("bad.obj"))) << line;  // tags not asked for: not read
  }
}

TEST_F(IoTest, HeaderClaimingATrillionVerticesFailsAtOnce) {
  write_text("huge.ply",
             "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty double x\n"
             "property double y\nproperty double z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n");
  EXPECT_THROW(sorpia::read_mesh(path("huge.ply")), sorpia::FileError);
}

TEST_F(IoTest, FailedWriteKeepsTheOldFile) {
  write_text("keep.obj", "old");
  const auto m = sorpia::icosphere(0);
  std::vector<std::int32_t> bad = m.face_vertex_indices;
  bad[4] = 99;  // out of range: refused before anything is written
  EXPECT_THROW(sorpia::write_mesh(path("keep.obj"), m.vertices.data(), m.n_vertices(), bad.data(), m.n_faces()),
               sorpia::MeshError);
  std::ifstream in(path("keep.obj"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "old");
  EXPECT_THROW(sorpia::write_mesh(path("missing/dir/x.obj"), m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(),
                                  m.n_faces()),
               sorpia::FileError);
  std::size_t n_files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++n_files;
  EXPECT_EQ(n_files, 1u);  // no temporary file left
}

TEST_F(IoTest, NamesOfNameMaxBytesAreWrittenLongerOnesRefusedBeforeAnyFile) {
  // The temporary file's name does not grow with the target's.
  const long name_max = ::pathconf(dir_.c_str(), _PC_NAME_MAX);
  ASSERT_GT(name_max, 8);
  const std::string longest = std::string(static_cast<std::size_t>(name_max) - 4, 'c') + ".obj";
  sorpia::check_writable(path(longest));
  const auto m = sorpia::icosphere(1);
  sorpia::write_mesh(path(longest), m.vertices.data(), m.n_vertices(), m.face_vertex_indices.data(), m.n_faces());
  EXPECT_EQ(sorpia::read_mesh(path(longest)).vertices, m.vertices);
  const std::string too_long = "c" + longest;
  sorpia_test::expect_error<sorpia::FileError>([&] { sorpia::check_writable(path(too_long)); },
                                               {"File name too long"});
  sorpia_test::expect_error<sorpia::FileError>(
      [&] { sorpia::write_file_atomic(path(too_long), "data"); }, {"File name too long"});
  std::size_t n_files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++n_files;
  EXPECT_EQ(n_files, 1u);  // the longest name only: check_writable's temporary file is gone
}

TEST_F(IoTest, UnknownExtensionAndMissingFile) {
  EXPECT_THROW(sorpia::mesh_format("mesh.xyz"), sorpia::FileError);
  EXPECT_EQ(sorpia::mesh_format("dir.v2/Mesh.PLY"), sorpia::MeshFormat::Ply);
  EXPECT_THROW(sorpia::read_mesh(path("nothing.off")), sorpia::FileError);
}

}  // namespace
