// Object File Format (OFF, as Geomview, CGAL and libigl write it): a header
// "OFF" (or COFF, NOFF, CNOFF, STOFF...: extra per-vertex numbers are
// ignored), the counts "n_vertices n_faces [n_edges]", the vertices "x y z
// [extras]" one per line, then the faces "k i_1 ... i_k [colour]" with 0-based
// indices. "#" starts a comment anywhere; a UTF-8 byte-order mark is skipped.
// Counts and records may run over several lines (libigl and pymeshlab read
// such files): a vertex ends at its third coordinate, a face at its k-th
// index, and the rest of that line (extras, a colour) is ignored.
#include <string>

#include "io_detail.hpp"

namespace sorpia::detail::io {

namespace {

std::size_t parse_count(const FileData& f, const Where& w, std::string_view rest_tok, const char* what) {
  long long c = 0;
  if (!parse_int(rest_tok, c) || c < 0)
    fail(f, w, std::string("expected the number of ") + what + ", found " + quoted(rest_tok));
  return static_cast<std::size_t>(c);
}

}  // namespace

MeshFile read_off(const FileData& f, PolygonSplits& polygons) {
  TokenReader in(text_begin(f), f.bytes.data() + f.bytes.size());
  std::string_view tok;
  const auto at = [&in] { return Where{"line", in.line()}; };
  if (!in.next(tok) || !is_off_keyword(tok)) fail(f, at(), "an OFF file starts with 'OFF'");
  if (tok.find('4') != std::string_view::npos || tok.find('n') != std::string_view::npos)
    fail(f, at(), quoted(tok) + " (not 3-dimensional) is not supported");
  if (in.line_has_more() && in.next(tok)) {
    if (tok == "BINARY") fail(f, at(), "binary OFF is not supported; write it as text OFF or PLY");
  } else if (!in.next(tok)) {
    fail(f, "the file ends before the vertex and face counts");
  }
  const std::size_t nv = parse_count(f, at(), tok, "vertices");
  if (!in.next(tok)) fail(f, at(), "expected the number of faces after the number of vertices");
  const Where counts_at = at();
  const std::size_t nf = parse_count(f, counts_at, tok, "faces");
  if (in.line_has_more()) {  // the edge count, which nothing needs
    in.next(tok);
    parse_count(f, counts_at, tok, "edges");
  }
  // A header claiming more than the file can hold fails here, before any
  // allocation: a vertex is at least 6 bytes ("0 0 0\n"), a face 8.
  const auto left = static_cast<std::size_t>(f.bytes.data() + f.bytes.size() - in.position());
  if (nv > left / 6 || nf > left / 8 || nv * 6 + nf * 8 > left + 2)
    fail(f, counts_at,
         "the header claims " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
             " faces, more than the remaining " + std::to_string(left) + " bytes can hold");

  MeshFile mesh;
  mesh.vertices.resize(3 * nv);
  for (std::size_t i = 0; i < nv; ++i) {
    for (int c = 0; c < 3; ++c) {
      if (!in.next(tok))
        fail(f, "the file ends " + std::string(c ? "inside vertex " : "after ") + std::to_string(i) +
                    (c ? "" : " of " + std::to_string(nv) + " vertices"));
      mesh.vertices[3 * i + c] = parse_coordinate(f, at(), tok);
    }
    in.skip_line();
  }
  mesh.face_vertex_indices.reserve(3 * nf);
  FaceSink sink(f, polygons, mesh);
  std::vector<std::int64_t> idx;
  for (std::size_t i = 0; i < nf; ++i) {
    if (!in.next(tok)) fail(f, "the file ends after " + std::to_string(i) + " of " + std::to_string(nf) + " faces");
    const Where w = at();
    long long k = 0;
    if (!parse_int(tok, k) || k < 0) fail(f, w, "expected the number of vertices of a face, found " + quoted(tok));
    const std::size_t rest = in.bytes_left();
    if (static_cast<unsigned long long>(k) > rest / 2 + 1)  // each index takes 2 bytes: before allocating for it
      fail(f, w, "a face of " + std::to_string(k) + " vertices is longer than the rest of the file");
    idx.resize(static_cast<std::size_t>(k));
    for (auto& x : idx) {
      long long v = 0;
      if (!in.next(tok)) fail(f, w, "the file ends inside a face of " + std::to_string(k) + " vertices");
      if (!parse_int(tok, v)) fail(f, at(), "expected a vertex index, found " + quoted(tok));
      check_index(f, at(), v, nv);
      x = v;
    }
    in.skip_line();  // a colour after the indices is ignored
    sink.add(idx.data(), idx.size(), w);
  }
  return mesh;
}

std::string format_off(const MeshView& m) {
  TextOut out(m.n_vertices * 60 + m.n_faces * 30);
  out << "OFF\n" << std::to_string(m.n_vertices) << ' ' << std::to_string(m.n_faces) << " 0\n";
  for (std::size_t i = 0; i < m.n_vertices; ++i) out.xyz(m.vertices + 3 * i) << '\n';
  for_each_face(m, [&](const std::int32_t* f, std::size_t k) { (out.num(k) << ' ').face(f, k, 0) << '\n'; });
  return std::move(out.str());
}

}  // namespace sorpia::detail::io
