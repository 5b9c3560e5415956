// Object File Format (OFF, as Geomview and CGAL write it): a header "OFF"
// (or COFF, NOFF, CNOFF, STOFF...: extra per-vertex numbers are ignored), the
// counts "n_vertices n_faces n_edges" (on the header line or the next one),
// one vertex per line, then one face per line "k i_1 ... i_k [colour]" with
// 0-based indices. "#" starts a comment anywhere.
#include <string>

#include "io_detail.hpp"

namespace sorpia::detail::io {

namespace {

bool is_off_keyword(std::string_view t) {
  // [ST][C][N][4][n]OFF; the 4 and n (other dimensions) are refused later.
  if (t.size() < 3 || t.substr(t.size() - 3) != "OFF") return false;
  for (const char c : t.substr(0, t.size() - 3))
    if (std::string_view("STCN4n").find(c) == std::string_view::npos) return false;
  return true;
}

// Next line holding something other than blanks and comments.
bool next_content(LineReader& lines, std::string_view& content) {
  std::string_view line;
  while (lines.next(line)) {
    content = strip_comment(line);
    if (!content.empty()) return true;
  }
  return false;
}

std::size_t parse_count(const FileData& f, const Where& w, std::string_view rest_tok, const char* what) {
  long long c = 0;
  if (!parse_int(rest_tok, c) || c < 0)
    fail(f, w, std::string("expected the number of ") + what + ", found " + quoted(rest_tok));
  return static_cast<std::size_t>(c);
}

}  // namespace

TriMesh read_off(const FileData& f, Polygons& polygons) {
  LineReader lines(f.bytes.data(), f.bytes.data() + f.bytes.size());
  std::string_view rest, tok;
  if (!next_content(lines, rest) || !next_token(rest, tok) || !is_off_keyword(tok))
    fail(f, Where{"line", lines.number()}, "an OFF file starts with 'OFF'");
  if (tok.find('4') != std::string_view::npos || tok.find('n') != std::string_view::npos)
    fail(f, Where{"line", lines.number()}, quoted(tok) + " (not 3-dimensional) is not supported");
  std::string_view after = rest;
  if (next_token(after, tok) && tok == "BINARY")
    fail(f, Where{"line", lines.number()}, "binary OFF is not supported; write it as text OFF or PLY");
  if (!next_token(rest, tok) && (!next_content(lines, rest) || !next_token(rest, tok)))
    fail(f, "the file ends before the vertex and face counts");
  const Where counts_at{"line", lines.number()};
  const std::size_t nv = parse_count(f, counts_at, tok, "vertices");
  if (!next_token(rest, tok)) fail(f, counts_at, "expected the number of faces after the number of vertices");
  const std::size_t nf = parse_count(f, counts_at, tok, "faces");
  // A header claiming more than the file can hold fails here, before any
  // allocation: a vertex line is at least 6 bytes ("0 0 0\n"), a face 8.
  const auto left = static_cast<std::size_t>(f.bytes.data() + f.bytes.size() - lines.position());
  if (nv > left / 6 || nf > left / 8 || nv * 6 + nf * 8 > left + 2)
    fail(f, counts_at,
         "the header claims " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
             " faces, more than the remaining " + std::to_string(left) + " bytes can hold");

  TriMesh mesh;
  mesh.vertices.resize(3 * nv);
  for (std::size_t i = 0; i < nv; ++i) {
    if (!next_content(lines, rest))
      fail(f, "the file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    const Where w{"line", lines.number()};
    for (int c = 0; c < 3; ++c) {
      if (!next_token(rest, tok)) fail(f, w, "a vertex needs 3 coordinates");
      mesh.vertices[3 * i + c] = parse_coordinate(f, w, tok);
    }
  }
  mesh.faces.reserve(3 * nf);
  FaceSink sink(f, polygons, mesh.faces);
  std::vector<std::int64_t> idx;
  for (std::size_t i = 0; i < nf; ++i) {
    if (!next_content(lines, rest))
      fail(f, "the file ends after " + std::to_string(i) + " of " + std::to_string(nf) + " faces");
    const Where w{"line", lines.number()};
    long long k = 0;
    if (!next_token(rest, tok) || !parse_int(tok, k) || k < 0)
      fail(f, w, "expected the number of vertices of a face");
    if (static_cast<unsigned long long>(k) > rest.size() / 2 + 1)  // before allocating for it
      fail(f, w, "a face of " + std::to_string(k) + " vertices is longer than its line");
    idx.resize(static_cast<std::size_t>(k));
    for (auto& x : idx) {
      long long v = 0;
      if (!next_token(rest, tok)) fail(f, w, "the face has fewer than the " + std::to_string(k) + " indices it announces");
      if (!parse_int(tok, v)) fail(f, w, "expected a vertex index, found " + quoted(tok));
      check_index(f, w, v, nv);
      x = v;
    }
    sink.add(idx.data(), idx.size(), w);  // anything after the indices (a colour) is ignored
  }
  return mesh;
}

std::string format_off(const double* v, std::size_t n, const std::int32_t* faces, std::size_t m) {
  TextOut out(n * 60 + m * 30);
  out << "OFF\n" << std::to_string(n) << ' ' << std::to_string(m) << " 0\n";
  for (std::size_t i = 0; i < n; ++i) out.xyz(v + 3 * i) << '\n';
  for (std::size_t i = 0; i < m; ++i) (out << "3 ").triangle(faces + 3 * i, 0) << '\n';
  return std::move(out.str());
}

}  // namespace sorpia::detail::io
