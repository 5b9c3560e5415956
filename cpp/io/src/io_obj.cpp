// Wavefront OBJ: "v x y z" vertices and "f" faces (1-based indices, "a",
// "a/b", "a//c", "a/b/c" forms, negative indices counted from the last vertex
// read), and, when asked, OpenSubdiv's "t" tag lines (FileTags in
// sorpia/io.hpp) and the texture coordinates ("vt u [v [w]]") and normals
// ("vn x y z") with the faces' indices of them (MeshFile::uvs, normals:
// face-varying). Every other statement (vp, g, o, s, usemtl, mtllib, l, p,
// curves, ...) is skipped. A line ending in "\\" continues on the next; a
// UTF-8 byte-order mark is skipped; after "v x y z" only numbers may follow
// (the weight w, or colours).
#include <algorithm>
#include <cctype>
#include <limits>
#include <utility>

#include "io_detail.hpp"

namespace sorpia::detail::io {

namespace {
// A line ending in a backslash (blanks after it allowed) continues on the next.
bool continues(std::string_view line) {
  while (!line.empty() && is_space(line.back())) line.remove_suffix(1);
  return !line.empty() && line.back() == '\\';
}


// One `t` line: its name and its integer, number and word arguments.
struct TagLine {
  std::string_view name;
  std::vector<long long> ints;
  std::vector<double> floats;
  std::vector<std::string_view> strings;
};

TagLine parse_tag(const FileData& f, const Where& w, std::string_view rest) {
  TagLine t;
  std::string_view tok;
  if (!next_token(rest, t.name)) fail(f, w, "a 't' line needs a tag name and its argument counts I/F/S");
  long long counts[3] = {0, 0, 0};
  {
    if (!next_token(rest, tok)) fail(f, w, "tag " + quoted(t.name) + " needs its argument counts I/F/S");
    std::string_view c = tok;
    for (int k = 0; k < 3; ++k) {
      const std::size_t slash = k < 2 ? c.find('/') : c.size();
      if (slash == std::string_view::npos || !parse_int(c.substr(0, slash), counts[k]) || counts[k] < 0)
        fail(f, w, "tag " + quoted(t.name) + ": expected argument counts I/F/S (e.g. 2/1/0), found " + quoted(tok));
      c = k < 2 ? c.substr(slash + 1) : c;
    }
    // Each argument is at least one character and a blank: a bad count fails before any allocation.
    if (static_cast<unsigned long long>(counts[0]) + counts[1] + counts[2] > rest.size())
      fail(f, w, "tag " + quoted(t.name) + ": " + quoted(tok) + " counts more arguments than the line holds");
  }
  const auto need = [&](const char* what) {
    if (!next_token(rest, tok))
      fail(f, w, "tag " + quoted(t.name) + ": the line ends before its " + what + " arguments are all given");
    return tok;
  };
  t.ints.resize(static_cast<std::size_t>(counts[0]));
  for (auto& x : t.ints)
    if (!parse_int(need("integer"), x))
      fail(f, w, "tag " + quoted(t.name) + ": expected an integer, found " + quoted(tok));
  t.floats.resize(static_cast<std::size_t>(counts[1]));
  for (auto& x : t.floats) {
    if (parse_number(need("number"), x) != std::errc() || std::isnan(x))
      fail(f, w, "tag " + quoted(t.name) + ": expected a number, found " + quoted(tok));
  }
  t.strings.resize(static_cast<std::size_t>(counts[2]));
  for (auto& x : t.strings) x = need("word");
  if (next_token(rest, tok))
    fail(f, w, "tag " + quoted(t.name) + ": " + quoted(tok) + " after the arguments its counts announce");
  return t;
}

// The tags of a file, collected line by line (FileTags), with the lines of
// the indices checked once the whole file is read.
class TagReader {
 public:
  explicit TagReader(const FileData& f) : f_(f) {}

  void add(const Where& w, std::string_view rest, FileTags& out) {
    const TagLine t = parse_tag(f_, w, rest);
    const std::string name = quoted(t.name);
    // One sharpness for all, or one per tag; negative counts as 0 (OpenSubdiv: max(0, s)).
    const auto sharpness = [&](std::size_t n_tags, std::size_t i) {
      if (t.floats.size() != 1 && t.floats.size() != n_tags)
        fail(f_, w, "tag " + name + ": " + std::to_string(n_tags) +
                        " tags need one sharpness for all or one each, found " + std::to_string(t.floats.size()));
      return std::max(0.0, t.floats[t.floats.size() == 1 ? 0 : i]);
    };
    if (t.name == "crease") {
      if (t.ints.empty() || t.ints.size() % 2)
        fail(f_, w, "tag 'crease' takes vertex pairs (A B for an edge), found " + std::to_string(t.ints.size()) +
                        " integers");
      for (std::size_t e = 0; e < t.ints.size() / 2; ++e) {
        const long long a = t.ints[2 * e], b = t.ints[2 * e + 1];
        if (a == b)
          fail(f_, w, "tag 'crease': edge (" + std::to_string(a) + ", " + std::to_string(b) + ") has one vertex twice");
        vertex(w, a, out.tags.crease_vertices);
        vertex(w, b, out.tags.crease_vertices);
        out.tags.crease_sharpness.push_back(sharpness(t.ints.size() / 2, e));
      }
    } else if (t.name == "corner") {
      if (t.ints.empty()) fail(f_, w, "tag 'corner' names no vertex");
      for (std::size_t i = 0; i < t.ints.size(); ++i) {
        vertex(w, t.ints[i], out.tags.corner_vertices);
        out.tags.corner_sharpness.push_back(sharpness(t.ints.size(), i));
      }
    } else if (t.name == "hole") {
      for (const long long h : t.ints) {
        if (h < 0 || h > std::numeric_limits<std::int32_t>::max())
          fail(f_, w, "tag 'hole': face " + std::to_string(h) + " is out of range");
        hole_lines_.push_back(w.index);
        out.tags.holes.push_back(static_cast<std::int32_t>(h));
      }
    } else if (t.name == "interpolateboundary") {
      if (t.ints.size() != 1)
        fail(f_, w, "tag 'interpolateboundary' takes one integer (1 edge-and-corner, 2 edge-only)");
      if (t.ints[0] == 1)
        out.boundary = Boundary::EdgeAndCorner;
      else if (t.ints[0] == 2)
        out.boundary = Boundary::EdgeOnly;
      else if (t.ints[0] == 0)
        fail(f_, w, "tag 'interpolateboundary 0' (no boundary interpolation, OpenSubdiv's VTX_BOUNDARY_NONE) is not "
                    "supported: sorpia's boundary rules are 1 (edge-and-corner) and 2 (edge-only)");
      else
        fail(f_, w, "tag 'interpolateboundary': unknown mode " + std::to_string(t.ints[0]) +
                        " (1 edge-and-corner, 2 edge-only)");
    } else if (t.name == "creasemethod") {
      one_word_option(t, w, "method", "normal", "chaikin",
                      "sorpia's semi-sharp creases decay uniformly (OpenSubdiv's CREASE_UNIFORM, 'normal')");
    } else if (t.name == "smoothtriangles") {
      one_word_option(t, w, "value", "catmark", "smooth",
                      "sorpia's Catmull-Clark triangles follow the Catmull-Clark rule (OpenSubdiv's TRI_SUB_CATMARK, "
                      "'catmark')");
    } else if (t.name != "facevaryinginterpolateboundary" && t.name != "facevaryingpropagatecorners") {
      // Unknown names are skipped, as OpenSubdiv's parser skips them, and listed.
      auto it = unknown_.begin();
      while (it != unknown_.end() && it->name != t.name) ++it;
      if (it == unknown_.end())
        unknown_.push_back({std::string(t.name), 1, w.index});
      else
        ++it->count;
    }
  }

  // Checks the indices against the mesh read (n vertices, m file faces) and fills out.unknown.
  void finish(std::size_t n_vertices, std::size_t n_faces, FileTags& out) const {
    for (const auto& [value, line] : vertex_lines_)
      if (static_cast<std::size_t>(value) >= n_vertices)
        fail(f_, Where{"line", line},
             "tag vertex " + std::to_string(value) + " is out of range: the file has " + std::to_string(n_vertices) +
                 " vertices (tag indices are 0-based)");
    for (std::size_t i = 0; i < out.tags.holes.size(); ++i)
      if (static_cast<std::size_t>(out.tags.holes[i]) >= n_faces)
        fail(f_, Where{"line", hole_lines_[i]},
             "tag 'hole': face " + std::to_string(out.tags.holes[i]) + " is out of range: the file has " +
                 std::to_string(n_faces) + " faces (tag indices are 0-based)");
    for (const auto& u : unknown_)
      out.unknown.push_back(quoted(u.name) + ": " + std::to_string(u.count) + (u.count == 1 ? " tag" : " tags") +
                            (u.count == 1 ? ", on line " : ", the first on line ") + std::to_string(u.line));
  }

 private:
  // A tag of one word whose only value sorpia implements is `supported`:
  // `refused` fails with `why`, any other word as unknown `kind`.
  void one_word_option(const TagLine& t, const Where& w, const char* kind, const std::string& supported,
                       const std::string& refused, const char* why) {
    const std::string name(t.name);
    if (t.strings.size() != 1) fail(f_, w, "tag '" + name + "' takes one word (" + supported + " or " + refused + ")");
    if (t.strings[0] == refused) fail(f_, w, "tag '" + name + " " + refused + "' is not supported: " + why);
    if (t.strings[0] != supported) fail(f_, w, "tag '" + name + "': unknown " + kind + " " + quoted(t.strings[0]));
  }

  void vertex(const Where& w, long long v, std::vector<std::int32_t>& out) {
    if (v < 0 || v > std::numeric_limits<std::int32_t>::max())
      fail(f_, w, "tag vertex " + std::to_string(v) + " is out of range (tag indices are 0-based)");
    vertex_lines_.push_back({v, w.index});
    out.push_back(static_cast<std::int32_t>(v));
  }
  struct Unknown {
    std::string name;
    std::size_t count, line;
  };
  const FileData& f_;
  std::vector<std::pair<long long, std::size_t>> vertex_lines_;  // (vertex, line) of every tag vertex
  std::vector<std::size_t> hole_lines_;
  std::vector<Unknown> unknown_;
};

}  // namespace

// The values of "vt" or "vn" lines and the faces' indices of them, one per
// file corner (-1 where a corner names none), checked once the file is read.
struct CornerValues {
  const char* what;                  // "texture coordinate", "normal"
  std::vector<double> values;        // 3 numbers per value, missing ones 0
  int width = 0;                     // the most numbers a line gave
  std::vector<std::int32_t> indices;
  std::vector<std::pair<std::size_t, std::size_t>> pending;  // (corner, line): indices past the values read so far
  bool any = false;                  // a corner names a value
  std::size_t leading = 0;           // corners naming none before the first that does (a file without any: no list)

  void add_value(const FileData& f, const Where& w, std::string_view rest, int min, int max) {
    std::string_view tok;
    int count = 0;
    double x[3] = {0, 0, 0};
    while (next_token(rest, tok)) {
      if (count == max) fail(f, w, std::string("a ") + what + " has at most " + std::to_string(max) + " numbers");
      x[count++] = parse_coordinate(f, w, tok);
    }
    if (count < min) fail(f, w, std::string("a ") + what + " needs " + std::to_string(min) + " numbers");
    width = std::max(width, count);
    values.insert(values.end(), x, x + 3);
  }
  // Index text `t` of a corner ("" for none), OBJ's 1-based or negative relative form.
  void add_index(const FileData& f, const Where& w, std::string_view t) {
    if (t.empty()) {
      if (any)
        indices.push_back(-1);
      else
        ++leading;
      return;
    }
    if (!any) indices.assign(leading, -1);
    const auto n = static_cast<long long>(values.size() / 3);
    long long i = 0;
    if (!parse_int(t, i)) fail(f, w, std::string("expected a ") + what + " index, found " + quoted(t));
    if (i == 0) fail(f, w, std::string(what) + " index 0: OBJ indices start at 1");
    if (i < 0 && i < -n)
      fail(f, w, std::string("relative ") + what + " index " + std::to_string(i) + " points before the first one");
    if (i > std::numeric_limits<std::int32_t>::max())
      fail(f, w, std::string(what) + " index " + std::to_string(i) + " is out of range");
    i = i < 0 ? i + n : i - 1;
    if (i >= n) pending.push_back({indices.size(), w.index});
    indices.push_back(static_cast<std::int32_t>(i));
    any = true;
  }
  // Into `out` (none when no corner names a value).
  void finish(const FileData& f, FaceVarying& out) {
    const std::size_t n = values.size() / 3;
    for (const auto& [corner, line] : pending)
      if (static_cast<std::size_t>(indices[corner]) >= n)
        fail(f, Where{"line", line}, std::string(what) + " index " + std::to_string(indices[corner] + 1) +
                                         " is out of range: the file has " + std::to_string(n));
    if (!any) return;
    out.width = std::max(width, 2);
    out.values.resize(n * static_cast<std::size_t>(out.width));
    for (std::size_t i = 0; i < n; ++i)
      std::copy(values.begin() + static_cast<std::ptrdiff_t>(3 * i),
                values.begin() + static_cast<std::ptrdiff_t>(3 * i + out.width),
                out.values.begin() + static_cast<std::ptrdiff_t>(i * out.width));
    out.indices = std::move(indices);
  }
};

MeshFile read_obj(const FileData& f, PolygonSplits& polygons, bool tags, bool attributes) {
  MeshFile mesh;
  mesh.vertices.reserve(f.bytes.size() / 16);
  mesh.face_vertex_indices.reserve(f.bytes.size() / 16);
  FaceSink sink(f, polygons, mesh);
  TagReader tag_reader(f);
  // Faces may name vertices defined further down: positive indices past the
  // vertices read so far are checked at the end (indices, line).
  struct Pending {
    std::size_t first, end, line;
  };
  std::vector<Pending> pending;
  std::vector<std::int64_t> idx;
  CornerValues uvs{"texture coordinate"}, normals{"normal"};
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
        const std::size_t slash = tok.find('/');
        const std::string_view v = tok.substr(0, slash);
        if (attributes) {  // "a", "a/b", "a//c", "a/b/c"
          std::string_view b, c;
          if (slash != std::string_view::npos) {
            b = tok.substr(slash + 1);
            const std::size_t second = b.find('/');
            if (second != std::string_view::npos) c = b.substr(second + 1), b = b.substr(0, second);
          }
          uvs.add_index(f, w, b);
          normals.add_index(f, w, c);
        }
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
      const std::size_t before = mesh.face_vertex_indices.size();
      sink.add(idx.data(), idx.size(), w);
      if (forward) pending.push_back({before, mesh.face_vertex_indices.size(), w.index});
    } else if (attributes && tok == "vt") {
      uvs.add_value(f, w, rest, 1, 3);
    } else if (attributes && tok == "vn") {
      normals.add_value(f, w, rest, 3, 3);
    } else if (tags && tok == "t") {
      tag_reader.add(w, rest, mesh.tags);
    } else if (!is_obj_keyword(tok)) {
      fail(f, w, quoted(tok) + " is not an OBJ statement (not a text OBJ file?)");
    }
  }
  const std::size_t n = mesh.n_vertices();
  for (const Pending& p : pending)
    for (std::size_t k = p.first; k < p.end; ++k)
      if (static_cast<std::size_t>(mesh.face_vertex_indices[k]) >= n)
        fail(f, Where{"line", p.line},
             "vertex index " + std::to_string(mesh.face_vertex_indices[k] + 1) + " is out of range: the file has " +
                 std::to_string(n) + " vertices");
  if (tags) tag_reader.finish(n, sink.n_faces(), mesh.tags);
  if (attributes) {
    uvs.finish(f, mesh.uvs);
    normals.finish(f, mesh.normals);
  }
  return mesh;
}

std::string format_obj(const MeshView& m, const FileTags* tags) {
  TextOut out(m.n_vertices * 60 + m.n_faces * 30);
  out << "# written by sorpia " << SORPIA_VERSION << ": " << std::to_string(m.n_vertices) << " vertices, "
      << std::to_string(m.n_faces) << (m.face_vertex_counts || m.face_size != 3 ? " faces\n" : " triangles\n");
  for (std::size_t i = 0; i < m.n_vertices; ++i) (out << "v ").xyz(m.vertices + 3 * i) << '\n';
  for (std::size_t i = 0; i < m.uvs.n_values; ++i) {
    out << "vt";
    for (int c = 0; c < m.uvs.width; ++c) (out << ' ').num(m.uvs.values[i * static_cast<std::size_t>(m.uvs.width) + c]);
    out << '\n';
  }
  for (std::size_t i = 0; i < m.normals.n_values; ++i) (out << "vn ").xyz(m.normals.values + 3 * i) << '\n';
  if (!m.uvs.width && !m.normals.width) {
    for_each_face(m, [&](const std::int32_t* f, std::size_t k) { (out << "f ").face(f, k, 1) << '\n'; });
  } else {  // "f a/b/c ...", "a/b" or "a//c"
    for_each_face(m, [&](const std::int32_t* f, std::size_t k) {
      const auto corner = static_cast<std::size_t>(f - m.face_vertex_indices);
      out << 'f';
      for (std::size_t c = 0; c < k; ++c) {
        (out << ' ').num(f[c] + 1);
        if (m.uvs.width) (out << '/').num(m.uvs.indices[corner + c] + 1);
        if (m.normals.width) (m.uvs.width ? out << '/' : out << "//").num(m.normals.indices[corner + c] + 1);
      }
      out << '\n';
    });
  }
  if (!tags) return std::move(out.str());
  // One tag a line, as OpenSubdiv's shapes have them (its parser reads lines of at most 255 characters).
  const Tags& t = tags->tags;
  for (std::size_t i = 0; i < t.n_creases(); ++i) {
    (out << "t crease 2/1/0 ").face(t.crease_vertices.data() + 2 * i, 2, 0) << ' ';
    out.num(t.crease_sharpness[i]) << '\n';
  }
  for (std::size_t i = 0; i < t.n_corners(); ++i) {
    (out << "t corner 1/1/0 ").num(t.corner_vertices[i]) << ' ';
    out.num(t.corner_sharpness[i]) << '\n';
  }
  for (const std::int32_t h : t.holes) (out << "t hole 1/0/0 ").num(h) << '\n';
  if (tags->boundary)
    out << (*tags->boundary == Boundary::EdgeAndCorner ? "t interpolateboundary 1/0/0 1\n"
                                                         : "t interpolateboundary 1/0/0 2\n");
  return std::move(out.str());
}

}  // namespace sorpia::detail::io
