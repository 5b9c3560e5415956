#pragma once
// Internals shared by the mesh file readers and writers (io_*.cpp).
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/io.hpp"
#include "sorpia/shapes.hpp"

namespace sorpia::detail::io {

// A file's bytes: a buffer whose growth leaves the new bytes uninitialised,
// since read() is about to write them (a std::string would zero-fill every
// byte of the file first).
class Bytes {
 public:
  Bytes() = default;
  Bytes(const std::string& s) {  // NOLINT: implicit, for tests and the fuzz target
    resize(s.size());
    if (!s.empty()) std::memcpy(p_.get(), s.data(), s.size());
  }
  const char* data() const { return p_.get(); }
  char* data() { return p_.get(); }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  char operator[](std::size_t i) const { return p_[i]; }
  operator std::string_view() const { return {p_.get(), size_}; }
  int compare(std::size_t pos, std::size_t n, const char* s) const { return std::string_view(*this).compare(pos, n, s); }
  // n bytes: the first min(n, size()) kept, the rest uninitialised.
  void resize(std::size_t n) {
    if (n > capacity_) {
      std::unique_ptr<char[]> bigger(new char[n]);
      if (size_) std::memcpy(bigger.get(), p_.get(), size_);
      p_ = std::move(bigger);
      capacity_ = n;
    }
    size_ = n;
  }

 private:
  std::unique_ptr<char[]> p_;
  std::size_t size_ = 0, capacity_ = 0;
};

// A whole file in memory (the readers parse from memory: one read, no
// per-line stream overhead).
struct FileData {
  std::string path;
  Bytes bytes;
};

// `path` as messages show it: valid UTF-8 as it is, any other byte as \xNN
// (a file name need not be UTF-8; Python's message must be).
std::string printable_path(const std::string& path);

// Throws FileError when the file is missing, a directory, unreadable or empty,
// or when its start cannot begin a file of `format` (checked on the first
// 64 kB, before the rest is read: a device or a huge file of another kind
// fails at once instead of being read whole). Polls for an interrupt as
// read_mesh's contract says.
FileData load_file(const std::string& path, MeshFormat format);

// Where in a file something is: "line 12", "vertex 7", ...
struct Where {
  const char* kind;
  std::size_t index;
  std::string str() const { return std::string(kind) + " " + std::to_string(index); }
};

[[noreturn]] inline void fail(const FileData& f, const std::string& what) {
  throw FileError(printable_path(f.path) + ": " + what);
}
[[noreturn]] inline void fail(const FileData& f, const Where& w, const std::string& what) {
  throw FileError(printable_path(f.path) + ", " + w.str() + ": " + what);
}

// File text quoted for a message: at most 40 bytes, anything but printable
// ASCII as \xNN (the message must stay valid UTF-8 for Python).
inline std::string quoted(std::string_view t) {
  static const char hex[] = "0123456789abcdef";
  std::string out = "'";
  for (std::size_t i = 0; i < t.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(t[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (t.size() > 40) out += "...";
  return out + "'";
}

// Where the text of a file starts: after a UTF-8 byte-order mark, if any.
inline const char* text_begin(const FileData& f) {
  const char* p = f.bytes.data();
  return f.bytes.compare(0, 3, "\xEF\xBB\xBF") == 0 ? p + 3 : p;
}

// The parsers poll for an interrupt (sorpia/interrupt.hpp) once per this many
// lines or binary records.
constexpr std::size_t kRecordsPerPoll = std::size_t{1} << 16;

// Lines of a text buffer, without their "\n" or "\r\n"; numbered from 1. A
// buffer with no "\n" at all but a "\r" has classic Mac line ends: "\r" ends
// its lines. Polls for an interrupt every kRecordsPerPoll lines.
class LineReader {
 public:
  LineReader(const char* begin, const char* end)
      : p_(begin),
        end_(end),
        eol_(std::memchr(begin, '\n', static_cast<std::size_t>(end - begin)) == nullptr &&
                     std::memchr(begin, '\r', static_cast<std::size_t>(end - begin)) != nullptr
                 ? '\r'
                 : '\n') {}
  bool next(std::string_view& line) {
    if (p_ >= end_) return false;
    const auto* nl = static_cast<const char*>(std::memchr(p_, eol_, static_cast<std::size_t>(end_ - p_)));
    const char* stop = nl ? nl : end_;
    const char* q = stop;
    if (q > p_ && q[-1] == '\r') --q;
    line = std::string_view(p_, static_cast<std::size_t>(q - p_));
    p_ = nl ? nl + 1 : end_;
    if (++number_ % kRecordsPerPoll == 0) poll_interrupt();
    return true;
  }
  std::size_t number() const { return number_; }
  const char* position() const { return p_; }

 private:
  const char* p_;
  const char* end_;
  char eol_;
  std::size_t number_ = 0;
};

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Next whitespace-separated token of `rest` (which is advanced past it).
inline bool next_token(std::string_view& rest, std::string_view& token) {
  std::size_t i = 0;
  while (i < rest.size() && is_space(rest[i])) ++i;
  if (i == rest.size()) {
    rest = {};
    return false;
  }
  std::size_t j = i;
  while (j < rest.size() && !is_space(rest[j])) ++j;
  token = rest.substr(i, j - i);
  rest.remove_prefix(j);
  return true;
}

// The line without a trailing "# comment" and surrounding blanks.
inline std::string_view strip_comment(std::string_view line) {
  const std::size_t hash = line.find('#');
  if (hash != std::string_view::npos) line = line.substr(0, hash);
  while (!line.empty() && is_space(line.front())) line.remove_prefix(1);
  while (!line.empty() && is_space(line.back())) line.remove_suffix(1);
  return line;
}

// An OFF header keyword: [ST][C][N][4][n]OFF (the 4 and n, other dimensions,
// are refused by the reader).
inline bool is_off_keyword(std::string_view t) {
  if (t.size() < 3 || t.substr(t.size() - 3) != "OFF") return false;
  for (const char c : t.substr(0, t.size() - 3))
    if (std::string_view("STCN4n").find(c) == std::string_view::npos) return false;
  return true;
}

// An OBJ statement keyword (v, f, vt, usemtl, ...): letters and '_'.
inline bool is_obj_keyword(std::string_view t) {
  for (const char c : t)
    if (!std::isalpha(static_cast<unsigned char>(c)) && c != '_') return false;
  return !t.empty();
}

// The tokens of a text, across lines, with "#" comments and blank lines
// skipped: for formats whose records may run over several lines (OFF).
class TokenReader {
 public:
  TokenReader(const char* begin, const char* end) : lines_(begin, end), end_(end) {}
  // The next token; false at the end of the text.
  bool next(std::string_view& token) {
    while (!next_token(rest_, token)) {
      std::string_view line;
      if (!lines_.next(line)) return false;
      rest_ = strip_comment(line);
    }
    return true;
  }
  // Drops what is left of the current line (e.g. a colour after a record).
  void skip_line() { rest_ = {}; }
  // Whether the current line has more tokens.
  bool line_has_more() const {
    for (char c : rest_)
      if (!is_space(c)) return true;
    return false;
  }
  std::size_t line() const { return lines_.number(); }
  const char* position() const { return lines_.position(); }
  // Bytes not yet read as tokens: the rest of the current line and what follows it.
  std::size_t bytes_left() const { return rest_.size() + static_cast<std::size_t>(end_ - lines_.position()); }

 private:
  LineReader lines_;
  const char* end_;
  std::string_view rest_;
};

// Exact decimal -> T (std::from_chars: correctly rounded for floating T, so
// the shortest representation written by to_chars reads back bit for bit).
// A leading '+' is accepted (from_chars alone refuses it); text after the
// number is invalid_argument.
template <class T>
std::errc parse_number(std::string_view t, T& out) {
  const char* b = t.data();
  const char* e = b + t.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, out);
  if (r.ec != std::errc()) return r.ec;
  return r.ptr == e ? std::errc() : std::errc::invalid_argument;
}

inline bool parse_int(std::string_view t, long long& out) { return parse_number(t, out) == std::errc(); }

// Parses a coordinate as T (double; float for STL, whose coordinates are
// float32 by definition), refusing text that is not a number and non-finite values.
template <class T = double>
double parse_coordinate(const FileData& f, const Where& w, std::string_view token) {
  T x = 0;
  const std::errc ec = parse_number(token, x);
  if (ec == std::errc::result_out_of_range)
    fail(f, w,
         "coordinate " + quoted(token) +
             (std::is_same_v<T, float> ? " is out of float32 range" : " is out of the range of double"));
  if (ec != std::errc()) fail(f, w, "expected a number, found " + quoted(token));
  if (!std::isfinite(x)) fail(f, w, "coordinate " + quoted(token) + " is not finite");
  return x;
}

// What a reader does with faces of more than 3 vertices, and how many it met.
// Polygons to triangulate are kept (their fans hold their rows of the face
// list meanwhile) until the whole file is read: the split of each is chosen
// with every edge of the mesh known (triangulate_polygons).
struct PolygonSplits {
  bool triangulate = false;  // split each into triangles; else kept as they are
  struct Polygon {
    std::size_t face;         // its index among the file's faces
    std::size_t first_row;    // its k - 2 triangles are rows first_row .. first_row + k - 3 of the faces
    std::size_t first_index;  // its k corners are indices[first_index .. first_index + k)
    std::size_t k;
  };
  std::vector<Polygon> list;
  std::vector<std::int32_t> indices;
};

// Replaces the fans that stand for polygons by splits that keep the mesh
// manifold where one exists: a quad takes its shorter diagonal unless that
// diagonal is already an edge of the mesh (then the other one); a larger
// polygon is fanned from its first corner whose diagonals are all new edges
// (its first corner if none is, or if it has more than 32 corners). A new diagonal cannot repeat a face or give
// an edge a third face. PolygonSplits are taken in file order, each seeing the
// diagonals chosen before it. `vertices` (n, 3) give the diagonals' lengths.
void triangulate_polygons(const PolygonSplits& polygons, const std::vector<double>& vertices,
                          std::vector<std::int32_t>& faces);

// The rows of the triangles of the file's faces `holes` (indices among the
// file's faces, fewer than `n_file_faces`) once `polygons` are split: a
// triangle keeps its face, a polygon of k corners gives k - 2 rows.
std::vector<std::int32_t> triangle_rows(const PolygonSplits& polygons, const std::vector<std::int32_t>& holes);

// Collects faces (0-based indices) into a MeshFile: as they are, the sizes
// recorded only once a face differs from those before it; or, with
// triangulate, polygons as fans recorded for triangulate_polygons.
class FaceSink {
 public:
  FaceSink(const FileData& file, PolygonSplits& polygons, MeshFile& mesh)
      : file_(file), polygons_(polygons), mesh_(mesh) {}
  // `idx` holds k indices already checked to lie in [0, n_vertices) (or, in
  // OBJ, to be checked against the final vertex count: the fan's rows hold
  // every corner until then).
  void add(const std::int64_t* idx, std::size_t k, const Where& w) {
    if (mesh_.face_vertex_counts.empty() && k == static_cast<std::size_t>(mesh_.face_size) && k == 3) {
      mesh_.face_vertex_indices.insert(mesh_.face_vertex_indices.end(),
                                       {static_cast<std::int32_t>(idx[0]), static_cast<std::int32_t>(idx[1]),
                                        static_cast<std::int32_t>(idx[2])});
      ++n_faces_;
      return;
    }
    add_other(idx, k, w);
  }
  // Faces read so far (file faces: a polygon split counts once).
  std::size_t n_faces() const { return n_faces_; }

 private:
  void add_other(const std::int64_t* idx, std::size_t k, const Where& w) {
    if (k < 3) fail(file_, w, "a face needs at least 3 vertices, this one has " + std::to_string(k));
    if (polygons_.triangulate && k > 3) {
      ++mesh_.polygons_split;
      polygons_.list.push_back({n_faces_, mesh_.face_vertex_indices.size() / 3, polygons_.indices.size(), k});
      for (std::size_t i = 0; i < k; ++i) polygons_.indices.push_back(static_cast<std::int32_t>(idx[i]));
      for (std::size_t i = 1; i + 1 < k; ++i)
        mesh_.face_vertex_indices.insert(mesh_.face_vertex_indices.end(),
                                         {static_cast<std::int32_t>(idx[0]), static_cast<std::int32_t>(idx[i]),
                                          static_cast<std::int32_t>(idx[i + 1])});
      ++n_faces_;
      return;
    }
    if (k > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
      fail(file_, w, "a face of " + std::to_string(k) + " vertices: more than int32 counts hold");
    const auto size = static_cast<std::int32_t>(k);
    if (mesh_.face_vertex_counts.empty() && size != mesh_.face_size) {
      if (n_faces_ == 0)
        mesh_.face_size = size;  // the first face sets the common size
      else
        mesh_.face_vertex_counts.assign(n_faces_, mesh_.face_size);  // sizes differ from here on: record every one
    }
    if (!mesh_.face_vertex_counts.empty()) mesh_.face_vertex_counts.push_back(size);
    for (std::size_t i = 0; i < k; ++i) mesh_.face_vertex_indices.push_back(static_cast<std::int32_t>(idx[i]));
    ++n_faces_;
  }

  const FileData& file_;
  PolygonSplits& polygons_;
  MeshFile& mesh_;
  std::size_t n_faces_ = 0;
};

// Index check shared by the readers: 0 <= i < n.
inline void check_index(const FileData& f, const Where& w, long long i, std::size_t n) {
  if (i < 0 || static_cast<unsigned long long>(i) >= n)
    fail(f, w, "vertex index " + std::to_string(i) + " is out of range [0, " + std::to_string(n) + ")");
}

// Text output with exact numbers: std::to_chars writes the shortest text that
// reads back to the same double (or float).
class TextOut {
 public:
  explicit TextOut(std::size_t reserve = 0) { s_.reserve(reserve); }
  TextOut& operator<<(std::string_view text) {
    s_.append(text);
    return *this;
  }
  TextOut& operator<<(char c) {
    s_.push_back(c);
    return *this;
  }
  template <class T>
  TextOut& num(T value) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, value);
    s_.append(buf, r.ptr);
    return *this;
  }
  // "x y z"
  TextOut& xyz(const double* p) {
    num(p[0]) << ' ';
    num(p[1]) << ' ';
    return num(p[2]);
  }
  // "a b c ...": the k indices of a face, each plus `base` (1 for OBJ)
  TextOut& face(const std::int32_t* f, std::size_t k, int base) {
    for (std::size_t i = 0; i < k; ++i) {
      if (i) s_.push_back(' ');
      num(f[i] + base);
    }
    return *this;
  }
  std::string& str() { return s_; }

 private:
  std::string s_;
};

// The faces of a MeshView one by one: f(first corner, k).
template <class F>
void for_each_face(const MeshView& m, F f) {
  std::size_t at = 0;
  for (std::size_t i = 0; i < m.n_faces; ++i) {
    const auto k = static_cast<std::size_t>(m.face_vertex_counts ? m.face_vertex_counts[i] : m.face_size);
    f(m.face_vertex_indices + at, k);
    at += k;
  }
}

// The values of a face-varying channel per vertex (n_vertices, width), for
// formats that store them per vertex (PLY): empty when the channel is absent;
// a vertex no face uses gets zeros. Throws ParameterError naming `what` and
// the first vertex whose corners have different values (a seam), or when the
// width is not that of the format's properties (2 for texture coordinates, 3
// for normals).
std::vector<double> per_vertex_values(const MeshView& m, const FaceVaryingView& channel, const char* what);

// Moves values given per file corner (`corner_values`, one per corner of the
// file's faces, file order) onto the faces once `polygons` are split: a
// triangle's corner takes the value of its polygon's corner at the same vertex.
void split_corner_values(const PolygonSplits& polygons, const std::vector<std::int32_t>& faces,
                         std::vector<std::int32_t>& corner_values);

// The mesh in `file`, read as `format` (read_mesh without the path: the
// fuzz target feeds bytes here). Throws FileError for a malformed file and
// for a mesh without vertices or faces, or with more vertices than int32
// indices hold.
MeshFile parse_mesh(const FileData& file, MeshFormat format, const ReadOptions& options);

// Format readers and writers (io_obj.cpp, io_off.cpp, io_ply.cpp, io_stl.cpp).
// `tags`: read the OBJ `t` lines (read_obj only); `attributes`: texture
// coordinates and normals (ReadOptions::attributes), per file corner from
// read_obj, per vertex (indices empty) from read_ply.
MeshFile read_obj(const FileData& f, PolygonSplits& polygons, bool tags, bool attributes);
MeshFile read_off(const FileData& f, PolygonSplits& polygons);
MeshFile read_ply(const FileData& f, PolygonSplits& polygons, bool attributes, bool points = false);
MeshFile read_stl(const FileData& f, PolygonSplits& polygons);
std::string format_obj(const MeshView& m, const FileTags* tags);
std::string format_off(const MeshView& m);
std::string format_ply(const MeshView& m, bool binary);
std::string format_stl(const MeshView& m, bool binary);

}  // namespace sorpia::detail::io
