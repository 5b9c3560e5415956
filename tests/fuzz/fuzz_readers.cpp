// libFuzzer target over sorpia's mesh file readers (OBJ, OFF, PLY, STL) and,
// for what they accept, the topology validation and the OpenSubdiv limit.
// Not part of the normal build or test run: see run.sh and the README section
// "Bad input and fuzzing".
//
// Input: byte 0 chooses the reader and the triangulate flag ('o' OBJ, 'f' OFF,
// 'p' PLY, 's' STL; upper case = triangulate; any other byte b: reader b % 4,
// triangulate b & 4); the rest is the file's content.
//
// Expected outcomes: a mesh, sorpia::FileError (bad file) or sorpia::MeshError
// (bad topology). Anything else (another exception such as std::bad_alloc,
// a sanitizer report, a crash, a timeout) is a finding: the target aborts.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "io_detail.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/topology.hpp"

namespace {

[[noreturn]] void finding(const char* what) {
  std::fprintf(stderr, "sorpia fuzz finding: %s\n", what);
  std::abort();
}

// Error messages go to a terminal or to Python (as UTF-8): they must be
// printable ASCII (plus the file's path, which is ours here).
// SORPIA_FUZZ_MESSAGES=0 turns this check off, to look past a known defect.
void check_message(const std::exception& e) {
  static const bool enabled = [] {
    const char* s = std::getenv("SORPIA_FUZZ_MESSAGES");
    return !(s && std::string(s) == "0");
  }();
  if (!enabled) return;
  for (const char* p = e.what(); *p; ++p) {
    const auto c = static_cast<unsigned char>(*p);
    if (c < 0x20 || c > 0x7e) finding((std::string("unprintable byte in the message: ") + e.what()).c_str());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  namespace io = sorpia::detail::io;
  using sorpia::MeshFormat;
  static const MeshFormat formats[] = {MeshFormat::Obj, MeshFormat::Off, MeshFormat::Ply, MeshFormat::Stl};
  const char mode = static_cast<char>(data[0]);
  int reader = 0;
  bool triangulate = false;
  switch (mode) {
    case 'o': case 'O': reader = 0; break;
    case 'f': case 'F': reader = 1; break;
    case 'p': case 'P': reader = 2; break;
    case 's': case 'S': reader = 3; break;
    default: reader = data[0] % 4; triangulate = data[0] & 4;
  }
  if (mode >= 'A' && mode <= 'Z') triangulate = true;
  io::FileData file{"fuzz", std::string(reinterpret_cast<const char*>(data) + 1, size - 1)};
  if (file.bytes.empty()) return 0;  // load_file refuses empty files before any reader runs
  sorpia::MeshFile mesh;
  try {
    mesh = io::parse_mesh(file, formats[reader], sorpia::ReadOptions{triangulate, true, true});
  } catch (const sorpia::FileError& e) {
    check_message(e);
    return 0;
  } catch (const std::exception& e) {
    finding((std::string("reader threw a non-FileError: ") + e.what()).c_str());
  }
  // What a reader accepts is well formed: indices in range, finite coordinates.
  const std::size_t n = mesh.n_vertices();
  for (const std::int32_t i : mesh.face_vertex_indices)
    if (i < 0 || static_cast<std::size_t>(i) >= n) finding("reader returned a face index out of range");
  for (const double x : mesh.vertices)
    if (!(x - x == 0)) finding("reader returned a non-finite coordinate");
  std::size_t corners = 0;
  for (std::size_t f = 0; f < mesh.n_faces(); ++f) {
    const std::int32_t k = mesh.face_vertex_counts.empty() ? mesh.face_size : mesh.face_vertex_counts[f];
    if (k < 3) finding("reader returned a face of fewer than 3 vertices");
    corners += static_cast<std::size_t>(k);
  }
  if (corners != mesh.face_vertex_indices.size()) finding("reader's face sizes do not add up to its corner list");
  for (const std::int32_t h : mesh.tags.tags.holes)
    if (h < 0 || static_cast<std::size_t>(h) >= mesh.n_faces()) finding("reader returned a hole out of range");
  for (const std::int32_t v : mesh.tags.tags.crease_vertices)
    if (v < 0 || static_cast<std::size_t>(v) >= n) finding("reader returned a crease vertex out of range");
  for (const sorpia::FaceVarying* channel : {&mesh.uvs, &mesh.normals}) {
    if (channel->empty()) continue;
    if (channel->indices.size() != mesh.face_vertex_indices.size()) finding("reader returned attributes not one per corner");
    for (const std::int32_t i : channel->indices)  // -1: a corner without a value (OBJ)
      if (i < -1 || (i >= 0 && static_cast<std::size_t>(i) >= channel->n_values()))
        finding("reader returned an attribute index out of range");
    for (const double x : channel->values)
      if (!(x - x == 0)) finding("reader returned a non-finite attribute");
  }
  if (!mesh.all_triangles()) return 0;  // the limit below is Loop's
  try {
    const sorpia::Topology topo(mesh, n);
    std::vector<double> out(mesh.vertices.size());
    sorpia::limit_points(topo, mesh.vertices.data(), sorpia::Boundary::EdgeOnly, out.data());
    for (const double x : out)
      if (!(x - x == 0)) finding("limit point not finite");
  } catch (const sorpia::MeshError& e) {
    check_message(e);
  } catch (const std::exception& e) {
    finding((std::string("topology/limit threw a non-MeshError: ") + e.what()).c_str());
  }
  return 0;
}
