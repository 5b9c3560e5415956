// STL, ascii and binary. STL stores each triangle's three corners (float32 in
// binary files, by definition) and no shared vertices, so the reader merges
// corners whose coordinates are exactly equal (-0.0 == 0.0, no tolerance),
// numbering vertices in order of first appearance. Coordinates are float32 in
// both encodings: ascii numbers are read as float32 (std::from_chars<float>,
// correctly rounded) and widened exactly, the writers round to float32 and
// write unit facet normals.
#include <cmath>
#include <limits>
#include <unordered_map>

#include "io_detail.hpp"

namespace sorpia::detail::io {

namespace {

struct Key {
  std::uint64_t b[3];
  bool operator==(const Key& o) const { return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2]; }
};
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (const std::uint64_t x : k.b) h = (h ^ x) * 1099511628211ull ^ (x >> 29);
    return static_cast<std::size_t>(h);
  }
};

// Merges exactly equal corners into one vertex.
class Welder {
 public:
  Welder(MeshFile& mesh, std::size_t n_triangles) : mesh_(mesh) { map_.reserve(n_triangles / 2 + 16); }
  std::int64_t add(const double p[3]) {
    Key k{};
    for (int c = 0; c < 3; ++c) {
      const double x = p[c] == 0.0 ? 0.0 : p[c];  // one key for -0.0 and 0.0
      std::memcpy(&k.b[c], &x, 8);
    }
    const auto next = static_cast<std::int64_t>(mesh_.n_vertices());
    const auto [it, inserted] = map_.emplace(k, next);
    if (inserted) mesh_.vertices.insert(mesh_.vertices.end(), p, p + 3);
    return it->second;
  }

 private:
  MeshFile& mesh_;
  std::unordered_map<Key, std::int64_t, KeyHash> map_;
};

MeshFile read_binary(const FileData& f, std::size_t count) {
  MeshFile mesh;
  mesh.face_vertex_indices.reserve(3 * count);
  Welder weld(mesh, count);
  const char* p = f.bytes.data() + 84;
  // A binary facet has three corners by layout: no polygons, straight to the faces.
  for (std::size_t t = 0; t < count; ++t, p += 50) {
    if (t % kRecordsPerPoll == 0) poll_interrupt();
    for (int c = 0; c < 3; ++c) {
      float q[3];
      std::memcpy(q, p + 12 + 12 * c, 12);  // after the normal
      const double d[3] = {q[0], q[1], q[2]};
      if (!std::isfinite(d[0]) || !std::isfinite(d[1]) || !std::isfinite(d[2]))
        fail(f, Where{"triangle", t}, "a coordinate is not finite");
      mesh.face_vertex_indices.push_back(static_cast<std::int32_t>(weld.add(d)));
    }
  }
  return mesh;
}

MeshFile read_ascii(const FileData& f, PolygonSplits& polygons) {
  MeshFile mesh;
  Welder weld(mesh, f.bytes.size() / 200);
  FaceSink sink(f, polygons, mesh);
  LineReader lines(f.bytes.data(), f.bytes.data() + f.bytes.size());
  std::string_view line, rest, tok;
  std::vector<std::int64_t> loop;
  bool in_loop = false;
  while (lines.next(line)) {
    rest = line;
    if (!next_token(rest, tok)) continue;
    const Where w{"line", lines.number()};
    if (tok == "vertex") {
      if (!in_loop) fail(f, w, "'vertex' outside 'outer loop'");
      double p[3];
      for (double& x : p) {
        if (!next_token(rest, tok)) fail(f, w, "a vertex needs 3 coordinates");
        x = parse_coordinate<float>(f, w, tok);  // as the float32 the format defines
      }
      loop.push_back(weld.add(p));
    } else if (tok == "outer") {
      in_loop = true;
      loop.clear();
    } else if (tok == "endloop") {
      if (!in_loop) fail(f, w, "'endloop' without 'outer loop'");
      sink.add(loop.data(), loop.size(), w);
      in_loop = false;
    } else if (tok != "solid" && tok != "endsolid" && tok != "facet" && tok != "endfacet") {
      fail(f, w, quoted(tok) + " is not an ascii STL keyword");
    }
  }
  if (in_loop) fail(f, "the file ends inside an 'outer loop'");
  return mesh;
}

// Facet normal of a float32 triangle, unit length (zero when degenerate).
void facet(const double* v, const std::int32_t* t, float out[12]) {
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) out[3 + 3 * c + k] = static_cast<float>(v[3 * t[c] + k]);
  const double a[3] = {double(out[6]) - out[3], double(out[7]) - out[4], double(out[8]) - out[5]};
  const double b[3] = {double(out[9]) - out[3], double(out[10]) - out[4], double(out[11]) - out[5]};
  const double n[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int k = 0; k < 3; ++k) out[k] = len > 0 ? static_cast<float>(n[k] / len) : 0.0f;
}

}  // namespace

MeshFile read_stl(const FileData& f, PolygonSplits& polygons) {
  const std::size_t size = f.bytes.size();
  // Binary files may begin with "solid" too: the size decides first.
  std::uint32_t count = 0;
  if (size >= 84) {
    std::memcpy(&count, f.bytes.data() + 80, 4);
    if (size == 84 + 50 * static_cast<std::size_t>(count)) return read_binary(f, count);
  }
  std::string_view head(f.bytes.data(), std::min<std::size_t>(size, 512)), tok;
  if (next_token(head, tok) && tok == "solid") return read_ascii(f, polygons);
  if (size < 84) fail(f, "neither an ascii STL (starting with 'solid') nor a binary STL (at least 84 bytes)");
  fail(f, "binary STL header announces " + std::to_string(count) + " triangles (" +
              std::to_string(84 + 50 * static_cast<std::size_t>(count)) + " bytes) but the file has " +
              std::to_string(size) + " bytes (truncated or not an STL file)");
}

std::string format_stl(const MeshView& mesh, bool binary) {
  // write_mesh refuses polygons for STL before this is called.
  const double* v = mesh.vertices;
  const std::int32_t* faces = mesh.face_vertex_indices;
  const std::size_t n = mesh.n_vertices, m = mesh.n_faces;
  for (std::size_t i = 0; i < 3 * n; ++i)
    if (std::fabs(v[i]) > std::numeric_limits<float>::max())
      throw MeshError("write_mesh: vertex " + std::to_string(i / 3) + " has coordinate " + std::to_string(v[i]) +
                      ", beyond float32, which STL stores");
  float tri[12];
  if (binary) {
    std::string s(84 + 50 * m, '\0');
    const std::string_view title = "binary STL written by sorpia";  // must not begin with "solid"
    std::memset(s.data(), ' ', 80);
    std::memcpy(s.data(), title.data(), title.size());
    const auto count = static_cast<std::uint32_t>(m);
    std::memcpy(s.data() + 80, &count, 4);
    for (std::size_t i = 0; i < m; ++i) {
      facet(v, faces + 3 * i, tri);
      std::memcpy(s.data() + 84 + 50 * i, tri, 48);  // the 2 attribute bytes stay 0
    }
    return s;
  }
  TextOut out(m * 250);
  out << "solid sorpia\n";
  for (std::size_t i = 0; i < m; ++i) {
    facet(v, faces + 3 * i, tri);
    out << "facet normal ";
    out.num(tri[0]) << ' ';
    out.num(tri[1]) << ' ';
    out.num(tri[2]) << "\n outer loop\n";
    for (int c = 1; c < 4; ++c) {
      out << "  vertex ";
      out.num(tri[3 * c]) << ' ';
      out.num(tri[3 * c + 1]) << ' ';
      out.num(tri[3 * c + 2]) << '\n';
    }
    out << " endloop\nendfacet\n";
  }
  out << "endsolid sorpia\n";
  return std::move(out.str());
}

}  // namespace sorpia::detail::io
