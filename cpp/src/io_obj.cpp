// Wavefront OBJ: "v x y z" vertices and "f" faces (1-based indices, "a",
// "a/b", "a//c", "a/b/c" forms, negative indices counted from the last vertex
// read). Every other statement (vt, vn, vp, g, o, s, usemtl, mtllib, l, p,
// curves, ...) is skipped. A line ending in "\\" continues on the next; a
// UTF-8 byte-order mark is skipped; after "v x y z" only numbers may follow
// (the weight w, or colours).
#include <cctype>
#include <limits>

#include "io_detail.hpp"

namespace sorpia::detail::io {

namespace {
// A line ending in a backslash (blanks after it allowed) continues on the next.
bool continues(std::string_view line) {
  while (!line.empty() && is_space(line.back())) line.remove_suffix(1);
  return !line.empty() && line.back() == '\\';
}

}  // namespace

TriMesh read_obj(const FileData& f, Polygons& polygons) {
  TriMesh mesh;
  mesh.vertices.reserve(f.bytes.size() / 16);
  mesh.faces.reserve(f.bytes.size() / 16);
  FaceSink sink(f, polygons, mesh.faces);
  // Faces may name vertices defined further down: positive indices past the
  // vertices read so far are checked at the end (face row, line).
  struct Pending {
    std::size_t first_row, end_row, line;
  };
  std::vector<Pending> pending;
  std::vector<std::int64_t> idx;
  LineReader lines(text_begin(f), f.bytes.data() + f.bytes.size());
  std::string_view line, tok;
  std::string joined;  // a statement continued over lines ending in '\\'
  while (lines.next(line)) {
    const Where w{"line", lines.number()};
    if (continues(line)) {
      joined.assign(line.substr(0, line.rfind('\\'))) += ' ';
      while (lines.next(line) && continues(line)) joined.append(line.substr(0, line.rfind('\\'))) += ' ';
      if (!continues(line)) joined.append(line);
      line = joined;
    }
    std::string_view rest = strip_comment(line);
    if (!next_token(rest, tok)) continue;
    if (tok == "v") {
      double p[3];
      for (double& x : p) {
        if (!next_token(rest, tok)) fail(f, w, "a vertex needs 3 coordinates");
        x = parse_coordinate(f, w, tok);
      }
      // A 4th number (the weight w) or colours are ignored; anything else is
      // not a vertex line (e.g. several statements run together).
      while (next_token(rest, tok)) parse_coordinate(f, w, tok);
      mesh.vertices.insert(mesh.vertices.end(), p, p + 3);
    } else if (tok == "f") {
      idx.clear();
      const auto n = static_cast<long long>(mesh.n_vertices());
      bool forward = false;
      while (next_token(rest, tok)) {
        const std::string_view v = tok.substr(0, tok.find('/'));
        long long i = 0;
        if (!parse_int(v, i)) fail(f, w, "expected a vertex index, found " + quoted(tok));
        if (i == 0) fail(f, w, "vertex index 0: OBJ indices start at 1");
        if (i < 0) {
          if (i < -n)  // not -i > n: -LLONG_MIN overflows
            fail(f, w, "relative vertex index " + std::to_string(i) + " points before the first vertex (" +
                           std::to_string(n) + " read so far)");
          i += n;
        } else {
          // Checked before the faces are stored as int32, where it would wrap.
          if (i > std::numeric_limits<std::int32_t>::max())
            fail(f, w, "vertex index " + std::to_string(i) + " is out of range: more than int32 indices hold");
          i -= 1;
          forward = forward || i >= n;
        }
        idx.push_back(i);
      }
      const std::size_t before = mesh.faces.size();
      sink.add(idx.data(), idx.size(), w);
      if (forward) pending.push_back({before / 3, mesh.faces.size() / 3, w.index});
    } else if (!is_obj_keyword(tok)) {
      fail(f, w, quoted(tok) + " is not an OBJ statement (not a text OBJ file?)");
    }
  }
  const std::size_t n = mesh.n_vertices();
  for (const Pending& p : pending)
    for (std::size_t k = 3 * p.first_row; k < 3 * p.end_row; ++k)
      if (static_cast<std::size_t>(mesh.faces[k]) >= n)
        fail(f, Where{"line", p.line},
             "vertex index " + std::to_string(mesh.faces[k] + 1) + " is out of range: the file has " +
                 std::to_string(n) + " vertices");
  return mesh;
}

std::string format_obj(const double* v, std::size_t n, const std::int32_t* faces, std::size_t m) {
  TextOut out(n * 60 + m * 30);
  out << "# written by sorpia " << SORPIA_VERSION << ": " << std::to_string(n) << " vertices, " << std::to_string(m)
      << " triangles\n";
  for (std::size_t i = 0; i < n; ++i) (out << "v ").xyz(v + 3 * i) << '\n';
  for (std::size_t i = 0; i < m; ++i) (out << "f ").triangle(faces + 3 * i, 1) << '\n';
  return std::move(out.str());
}

}  // namespace sorpia::detail::io
