// Mesh files: bit-exact round trips, errors that name the file and line,
// atomic writes.
#include <gtest/gtest.h>
#include <unistd.h>

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
sorpia::TriMesh awkward_mesh() {
  sorpia::TriMesh m;
  m.vertices = {1.0 / 3.0, M_PI * 1e-7, 1e300, -0.0, 5e-324, std::numeric_limits<double>::denorm_min() * 12345,
                0.1, 0.2, 0.30000000000000004, -std::numeric_limits<double>::max(), 2.2250738585072014e-308, 1.0};
  m.faces = {0, 1, 2, 0, 2, 3};
  return m;
}

TEST_F(IoTest, FloatFormatsRoundTripBitForBit) {
  const auto m = awkward_mesh();
  for (const auto& [name, binary] : {std::pair{"a.obj", false}, {"a.off", false}, {"a.ply", false}, {"b.ply", true}}) {
    sorpia::write_mesh(path(name), m.vertices.data(), m.n_vertices(), m.faces.data(), m.n_faces(), binary);
    const auto r = sorpia::read_mesh(path(name));
    ASSERT_EQ(r.vertices.size(), m.vertices.size()) << name;
    EXPECT_EQ(std::memcmp(r.vertices.data(), m.vertices.data(), 8 * m.vertices.size()), 0) << name;
    EXPECT_EQ(r.faces, m.faces) << name;
  }
}

TEST_F(IoTest, StlRoundsToFloat32AndMergesEqualCorners) {
  const auto m = sorpia::icosphere(1);
  sorpia::write_mesh(path("a.stl"), m.vertices.data(), m.n_vertices(), m.faces.data(), m.n_faces(), true);
  const auto r = sorpia::read_mesh(path("a.stl"));
  EXPECT_EQ(r.n_vertices(), m.n_vertices());  // corners merged back into the 42 vertices
  ASSERT_EQ(r.n_faces(), m.n_faces());
  for (std::size_t k = 0; k < r.faces.size(); ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(r.vertices[3 * r.faces[k] + c], static_cast<double>(static_cast<float>(m.vertices[3 * m.faces[k] + c])));
}

TEST_F(IoTest, PolygonIsAnErrorNamingItsLineUnlessTriangulated) {
  write_text("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n# a quad\nf 1 2 3 4\n");
  try {
    sorpia::read_mesh(path("quad.obj"));
    FAIL() << "a quad was accepted";
  } catch (const sorpia::FileError& e) {
    EXPECT_NE(std::string(e.what()).find("quad.obj, line 6: face with 4 vertices"), std::string::npos) << e.what();
  }
  std::size_t polygons = 99;
  const auto r = sorpia::read_mesh(path("quad.obj"), true, &polygons);
  EXPECT_EQ(r.faces, (std::vector<std::int32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(polygons, 1u);
}

TEST_F(IoTest, PolygonsSplitAreCounted) {
  // A triangle, two quads and a pentagon, in OBJ and OFF: 3 polygons split,
  // 1 + 2 + 2 + 3 triangles in all.
  write_text("mix.obj",
             "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
             "f 1 2 3\nf 1 2 3 4\nf 2 5 6 3\nf 1 2 5 6 4\n");
  write_text("mix.off", "OFF\n6 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n"
                        "3 0 1 2\n4 0 1 2 3\n4 1 4 5 2\n5 0 1 4 5 3\n");
  for (const char* name : {"mix.obj", "mix.off"}) {
    std::size_t polygons = 0;
    const auto r = sorpia::read_mesh(path(name), true, &polygons);
    EXPECT_EQ(polygons, 3u) << name;
    EXPECT_EQ(r.faces.size(), 3u * (1 + 2 + 2 + 3)) << name;
  }
  std::size_t polygons = 7;  // set, not added to
  write_text("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  sorpia::read_mesh(path("tri.obj"), true, &polygons);
  EXPECT_EQ(polygons, 0u);
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
  std::vector<std::int32_t> bad = m.faces;
  bad[4] = 99;  // out of range: refused before anything is written
  EXPECT_THROW(sorpia::write_mesh(path("keep.obj"), m.vertices.data(), m.n_vertices(), bad.data(), m.n_faces()),
               sorpia::MeshError);
  std::ifstream in(path("keep.obj"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "old");
  EXPECT_THROW(sorpia::write_mesh(path("missing/dir/x.obj"), m.vertices.data(), m.n_vertices(), m.faces.data(),
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
  sorpia::write_mesh(path(longest), m.vertices.data(), m.n_vertices(), m.faces.data(), m.n_faces());
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
