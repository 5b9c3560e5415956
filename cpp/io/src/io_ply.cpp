// Stanford PLY: ascii, binary_little_endian and binary_big_endian on reading;
// ascii and binary_little_endian with `double` coordinates on writing.
// The "vertex" element's x, y, z (any numeric type) and the "face" element's
// "vertex_indices" (or "vertex_index") list are read, or, without a "face"
// element, the triangle strips of a "tristrips" element (as several of
// Stanford's scans come); with ReadOptions::attributes also the vertex
// element's texture coordinates (u v, s t, texture_u texture_v or texture_s
// texture_t) and normals (nx ny nz); every other property and element is
// skipped. The writer writes texture coordinates (u v) and normals (nx ny nz)
// per vertex, after x y z.
#include <algorithm>
#include <cmath>
#include <string>

#include "io_detail.hpp"

namespace sorpia::detail::io {

namespace {

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64 };

bool parse_type(std::string_view t, PlyType& out) {
  static const struct {
    const char* name;
    PlyType type;
  } names[] = {{"char", PlyType::I8},    {"int8", PlyType::I8},     {"uchar", PlyType::U8},
               {"uint8", PlyType::U8},   {"short", PlyType::I16},   {"int16", PlyType::I16},
               {"ushort", PlyType::U16}, {"uint16", PlyType::U16},  {"int", PlyType::I32},
               {"int32", PlyType::I32},  {"uint", PlyType::U32},    {"uint32", PlyType::U32},
               {"float", PlyType::F32},  {"float32", PlyType::F32}, {"double", PlyType::F64},
               {"float64", PlyType::F64}};
  for (const auto& n : names)
    if (t == n.name) {
      out = n.type;
      return true;
    }
  return false;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::I8:
    case PlyType::U8: return 1;
    case PlyType::I16:
    case PlyType::U16: return 2;
    case PlyType::I32:
    case PlyType::U32:
    case PlyType::F32: return 4;
    case PlyType::F64: return 8;
  }
  return 0;
}

bool is_float(PlyType t) { return t == PlyType::F32 || t == PlyType::F64; }

template <class T>
T load(const char* p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

// A binary scalar as a double (exact for every PLY type).
double load_number(const char* p, PlyType t, bool swap) {
  switch (t) {
    case PlyType::I8: return load<std::int8_t>(p, swap);
    case PlyType::U8: return load<std::uint8_t>(p, swap);
    case PlyType::I16: return load<std::int16_t>(p, swap);
    case PlyType::U16: return load<std::uint16_t>(p, swap);
    case PlyType::I32: return load<std::int32_t>(p, swap);
    case PlyType::U32: return load<std::uint32_t>(p, swap);
    case PlyType::F32: return load<float>(p, swap);
    case PlyType::F64: return load<double>(p, swap);
  }
  return 0;
}

struct Property {
  std::string name;
  PlyType type = PlyType::F32;
  bool is_list = false;
  PlyType count_type = PlyType::U8;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> props;
  std::size_t line = 0;
  // Smallest size of one item in the data: binary bytes (lists empty) or, in
  // ascii, two characters per value ("0 ").
  std::size_t min_bytes(bool binary) const {
    std::size_t s = 0;
    for (const auto& p : props) s += binary ? type_size(p.is_list ? p.count_type : p.type) : 2;
    return s;
  }
  bool fixed_size() const {
    for (const auto& p : props)
      if (p.is_list) return false;
    return true;
  }
};

enum class Encoding { Ascii, LittleEndian, BigEndian };

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  const char* data = nullptr;  // first byte after "end_header\n"
  std::size_t data_line = 0;   // line number of the first data line (ascii)
};

Header parse_header(const FileData& f) {
  Header h;
  LineReader lines(f.bytes.data(), f.bytes.data() + f.bytes.size());
  std::string_view line, rest, tok;
  if (!lines.next(line) || line != "ply") fail(f, Where{"line", 1}, "a PLY file starts with the line 'ply'");
  bool has_format = false;
  for (;;) {
    if (!lines.next(line)) fail(f, "the header has no 'end_header' line");
    const Where w{"line", lines.number()};
    rest = line;
    if (!next_token(rest, tok)) continue;
    if (tok == "end_header") break;
    if (tok == "comment" || tok == "obj_info") continue;
    if (tok == "format") {
      std::string_view version;
      if (!next_token(rest, tok) || !next_token(rest, version)) fail(f, w, "expected 'format <encoding> 1.0'");
      if (tok == "ascii")
        h.encoding = Encoding::Ascii;
      else if (tok == "binary_little_endian")
        h.encoding = Encoding::LittleEndian;
      else if (tok == "binary_big_endian")
        h.encoding = Encoding::BigEndian;
      else
        fail(f, w, "unknown PLY format " + quoted(tok));
      has_format = true;
    } else if (tok == "element") {
      Element e;
      std::string_view name, count;
      long long c = 0;
      if (!next_token(rest, name) || !next_token(rest, count) || !parse_int(count, c) || c < 0)
        fail(f, w, "expected 'element <name> <count>'");
      e.name = std::string(name);
      e.count = static_cast<std::size_t>(c);
      e.line = w.index;
      h.elements.push_back(std::move(e));
    } else if (tok == "property") {
      if (h.elements.empty()) fail(f, w, "a property before any element");
      Property p;
      std::string_view t1, t2, name;
      if (!next_token(rest, t1)) fail(f, w, "expected 'property <type> <name>'");
      if (t1 == "list") {
        p.is_list = true;
        if (!next_token(rest, t1) || !next_token(rest, t2) || !next_token(rest, name))
          fail(f, w, "expected 'property list <count type> <item type> <name>'");
        if (!parse_type(t1, p.count_type) || is_float(p.count_type))
          fail(f, w, "a list count must have an integer type, got " + quoted(t1));
        if (!parse_type(t2, p.type)) fail(f, w, "unknown property type " + quoted(t2));
      } else {
        if (!parse_type(t1, p.type)) fail(f, w, "unknown property type " + quoted(t1));
        if (!next_token(rest, name)) fail(f, w, "expected 'property <type> <name>'");
      }
      p.name = std::string(name);
      h.elements.back().props.push_back(std::move(p));
    } else {
      fail(f, w, "unknown header line " + quoted(line));
    }
  }
  if (!has_format) fail(f, "the header has no 'format' line");
  h.data = lines.position();
  h.data_line = lines.number() + 1;
  // Counts that the data cannot hold fail now, before any allocation.
  const auto left = static_cast<std::size_t>(f.bytes.data() + f.bytes.size() - h.data);
  std::size_t need = 0;
  for (const auto& e : h.elements) {
    const std::size_t per = std::max<std::size_t>(e.min_bytes(h.encoding != Encoding::Ascii), 1);
    if (e.count > left / per || need + e.count * per > left + 1)
      fail(f, Where{"line", e.line},
           "the header claims " + std::to_string(e.count) + " " + quoted(e.name) + " elements, more than the " +
               std::to_string(left) + " bytes after the header can hold");
    need += e.count * per;
  }
  return h;
}

// Where the coordinates and the face indices are.
struct Layout {
  const Element* vertex = nullptr;
  // The vertex properties read, by slot: x y z, then (ReadOptions::attributes)
  // the texture coordinates u v and the normal nx ny nz; -1 where absent.
  int xyz[3] = {-1, -1, -1};
  int uv[2] = {-1, -1};
  int normal[3] = {-1, -1, -1};
  // The place of vertex property k of vertex i in `mesh`, or null when it is not read.
  double* target(MeshFile& mesh, int k, std::size_t i) const {
    for (int c = 0; c < 3; ++c)
      if (k == xyz[c]) return mesh.vertices.data() + 3 * i + c;
    for (int c = 0; c < 2; ++c)
      if (k == uv[c]) return mesh.uvs.values.data() + 2 * i + c;
    for (int c = 0; c < 3; ++c)
      if (k == normal[c]) return mesh.normals.values.data() + 3 * i + c;
    return nullptr;
  }
  // Sizes the arrays of the vertex properties read for n vertices.
  void allocate(MeshFile& mesh, std::size_t n) const {
    mesh.vertices.resize(3 * n);
    if (uv[0] >= 0) mesh.uvs.values.resize(2 * n), mesh.uvs.width = 2;
    if (normal[0] >= 0) mesh.normals.values.resize(3 * n), mesh.normals.width = 3;
  }
  const Element* face = nullptr;  // the "face" element, or else the "tristrips" element
  int indices = -1;
  bool strips = false;  // face is "tristrips": its lists are triangle strips
};

// The faces of a list of indices: the polygon itself, or, for a "tristrips"
// element, the triangles of its strips. A strip (v0, v1, v2, v3, ...) gives
// (v0, v1, v2), (v2, v1, v3), (v2, v3, v4), ...: every other triangle reversed
// so that all have the strip's orientation; -1 ends a strip and starts
// another. Triangles with a repeated vertex join strips and are no faces.
void add_faces(const Layout& l, const std::int64_t* idx, std::size_t n, FaceSink& sink, const Where& w) {
  if (!l.strips) {
    sink.add(idx, n, w);
    return;
  }
  std::size_t start = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (idx[k] < 0) {
      start = k + 1;
      continue;
    }
    if (k < start + 2) continue;
    const bool odd = (k - start) % 2 == 1;
    const std::int64_t t[3] = {odd ? idx[k - 1] : idx[k - 2], odd ? idx[k - 2] : idx[k - 1], idx[k]};
    if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) sink.add(t, 3, w);
  }
}

// The scalar property of `e` named `name`, or -1.
int find_scalar(const Element& e, std::string_view name) {
  for (int k = 0; k < static_cast<int>(e.props.size()); ++k)
    if (e.props[k].name == name && !e.props[k].is_list) return k;
  return -1;
}

Layout find_layout(const FileData& f, const Header& h, bool attributes, bool points) {
  Layout l;
  for (const auto& e : h.elements) {
    if (e.name == "vertex" && !l.vertex) {
      l.vertex = &e;
      for (int c = 0; c < 3; ++c) {
        l.xyz[c] = find_scalar(e, std::string(1, static_cast<char>('x' + c)));
        if (l.xyz[c] < 0)
          fail(f, Where{"line", e.line}, std::string("the vertex element has no property ") + char('x' + c));
      }
      if (attributes) {
        // Texture coordinates by the names the common writers use (Blender, MeshLab, trimesh, Open3D).
        static const char* const uv_names[][2] = {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"},
                                                  {"texture_s", "texture_t"}};
        for (const auto& names : uv_names) {
          const int a = find_scalar(e, names[0]), b = find_scalar(e, names[1]);
          if (a >= 0 && b >= 0) {
            l.uv[0] = a, l.uv[1] = b;
            break;
          }
        }
        const int n[3] = {find_scalar(e, "nx"), find_scalar(e, "ny"), find_scalar(e, "nz")};
        if (n[0] >= 0 && n[1] >= 0 && n[2] >= 0) std::copy(n, n + 3, l.normal);
      }
    }
    if ((e.name == "face" && (!l.face || l.strips)) || (e.name == "tristrips" && !l.face)) {
      l.face = &e;
      l.strips = e.name == "tristrips";
      for (int k = 0; k < static_cast<int>(e.props.size()); ++k)
        if (e.props[k].is_list && (e.props[k].name == "vertex_indices" || e.props[k].name == "vertex_index")) {
          l.indices = k;
          break;
        }
      if (l.indices < 0) fail(f, Where{"line", e.line}, "the " + e.name + " element has no list 'vertex_indices'");
      if (is_float(e.props[l.indices].type))
        fail(f, Where{"line", e.line}, "vertex_indices must have an integer type");
    }
  }
  if (!l.vertex) fail(f, "no 'vertex' element in the header");
  if (!l.face && !points) fail(f, "no 'face' or 'tristrips' element in the header: sorpia needs a triangle mesh");
  return l;
}

MeshFile read_binary(const FileData& f, const Header& h, const Layout& l, PolygonSplits& polygons) {
  const bool swap = h.encoding == Encoding::BigEndian;
  const char* p = h.data;
  const char* end = f.bytes.data() + f.bytes.size();
  MeshFile mesh;
  FaceSink sink(f, polygons, mesh);
  std::vector<std::int64_t> idx;
  const std::size_t nv = l.vertex->count;
  auto truncated = [&](const Element& e, std::size_t i) {
    fail(f, Where{"element", i},
         "the file ends inside element " + std::to_string(i) + " of " + std::to_string(e.count) + " " + quoted(e.name));
  };
  for (const auto& e : h.elements) {
    const bool is_vertex = &e == l.vertex;
    const bool is_face = &e == l.face;
    if (is_vertex) l.allocate(mesh, e.count);
    if (is_face) mesh.face_vertex_indices.reserve(3 * e.count);
    if (e.fixed_size()) {
      std::size_t stride = 0;
      std::vector<std::size_t> offset;
      for (const auto& pr : e.props) offset.push_back(stride), stride += type_size(pr.type);
      if (static_cast<std::size_t>(end - p) / std::max<std::size_t>(stride, 1) < e.count)
        truncated(e, static_cast<std::size_t>(end - p) / std::max<std::size_t>(stride, 1));
      if (is_vertex) {
        const PlyType t[3] = {e.props[l.xyz[0]].type, e.props[l.xyz[1]].type, e.props[l.xyz[2]].type};
        const std::size_t o[3] = {offset[l.xyz[0]], offset[l.xyz[1]], offset[l.xyz[2]]};
        double* out = mesh.vertices.data();
        const bool plain = !swap && stride == 24 && o[0] == 0 && o[1] == 8 && o[2] == 16 &&
                           t[0] == PlyType::F64 && t[1] == PlyType::F64 && t[2] == PlyType::F64;
        if (plain) {  // what sorpia writes: x y z double, nothing else
          if (e.count) std::memcpy(out, p, 24 * e.count);  // out is null when the vertex element is empty
        } else {
          for (std::size_t i = 0; i < e.count; ++i)
            for (int c = 0; c < 3; ++c) out[3 * i + c] = load_number(p + i * stride + o[c], t[c], swap);
        }
        for (std::size_t i = 0; i < 3 * e.count; ++i)
          if (!std::isfinite(out[i])) fail(f, Where{"vertex", i / 3}, "a coordinate is not finite");
        for (int k : {l.uv[0], l.uv[1], l.normal[0], l.normal[1], l.normal[2]}) {
          if (k < 0) continue;
          const auto uk = static_cast<std::size_t>(k);
          for (std::size_t i = 0; i < e.count; ++i) {
            const double x = load_number(p + i * stride + offset[uk], e.props[uk].type, swap);
            if (!std::isfinite(x)) fail(f, Where{"vertex", i}, "property " + quoted(e.props[uk].name) + " is not finite");
            *l.target(mesh, k, i) = x;
          }
        }
      }
      p += stride * e.count;
      continue;
    }
    for (std::size_t i = 0; i < e.count; ++i) {
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const Property& pr = e.props[k];
        if (!pr.is_list) {
          const std::size_t s = type_size(pr.type);
          if (static_cast<std::size_t>(end - p) < s) truncated(e, i);
          if (double* to = is_vertex ? l.target(mesh, static_cast<int>(k), i) : nullptr) {
            const double x = load_number(p, pr.type, swap);
            if (!std::isfinite(x)) fail(f, Where{"vertex", i}, "property " + quoted(pr.name) + " is not finite");
            *to = x;
          }
          p += s;
          continue;
        }
        const std::size_t cs = type_size(pr.count_type);
        if (static_cast<std::size_t>(end - p) < cs) truncated(e, i);
        const double count = load_number(p, pr.count_type, swap);
        p += cs;
        if (count < 0) fail(f, Where{"element", i}, "a negative list length in " + quoted(e.name));
        const auto n = static_cast<std::size_t>(count);
        const std::size_t s = type_size(pr.type);
        if (static_cast<std::size_t>(end - p) / s < n) truncated(e, i);
        if (is_face && static_cast<int>(k) == l.indices) {
          idx.resize(n);
          for (std::size_t j = 0; j < n; ++j) {
            const double v = load_number(p + j * s, pr.type, swap);
            if (!(l.strips && v == -1)) check_index(f, Where{"face", i}, static_cast<long long>(v), nv);
            idx[j] = static_cast<std::int64_t>(v);
          }
          add_faces(l, idx.data(), n, sink, Where{"face", i});
        }
        p += n * s;
      }
    }
  }
  return mesh;
}

MeshFile read_ascii(const FileData& f, const Header& h, const Layout& l, PolygonSplits& polygons) {
  LineReader lines(h.data, f.bytes.data() + f.bytes.size());
  const std::size_t first_line = h.data_line - 1;
  MeshFile mesh;
  FaceSink sink(f, polygons, mesh);
  std::vector<std::int64_t> idx;
  const std::size_t nv = l.vertex->count;
  std::string_view line, rest, tok;
  for (const auto& e : h.elements) {
    const bool is_vertex = &e == l.vertex;
    const bool is_face = &e == l.face;
    if (is_vertex) l.allocate(mesh, e.count);
    if (is_face) mesh.face_vertex_indices.reserve(3 * e.count);
    for (std::size_t i = 0; i < e.count; ++i) {
      do {
        if (!lines.next(line))
          fail(f, "the file ends after " + std::to_string(i) + " of " + std::to_string(e.count) + " " + quoted(e.name) +
                      " elements");
        rest = line;
      } while (strip_comment(line).empty());
      const Where w{"line", first_line + lines.number()};
      auto need = [&]() {
        if (!next_token(rest, tok)) fail(f, w, "the line ends before the properties of the " + quoted(e.name) + " element");
        return tok;
      };
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const Property& pr = e.props[k];
        if (!pr.is_list) {
          const std::string_view t = need();
          if (double* to = is_vertex ? l.target(mesh, static_cast<int>(k), i) : nullptr) *to = parse_coordinate(f, w, t);
          continue;
        }
        long long n = 0;
        if (!parse_int(need(), n) || n < 0) fail(f, w, "expected a list length, found " + quoted(tok));
        // Each item takes at least two characters of the line: a bad length
        // fails here, before anything is allocated for it.
        if (static_cast<unsigned long long>(n) > rest.size() / 2 + 1)
          fail(f, w, "a list of " + std::to_string(n) + " items is longer than its line");
        const bool wanted = is_face && static_cast<int>(k) == l.indices;
        if (wanted) idx.resize(static_cast<std::size_t>(n));
        for (long long j = 0; j < n; ++j) {
          const std::string_view t = need();
          if (!wanted) continue;
          long long v = 0;
          if (!parse_int(t, v)) fail(f, w, "expected a vertex index, found " + quoted(t));
          if (!(l.strips && v == -1)) check_index(f, w, v, nv);
          idx[static_cast<std::size_t>(j)] = v;
        }
        if (wanted) add_faces(l, idx.data(), idx.size(), sink, w);
      }
    }
  }
  return mesh;
}

}  // namespace

MeshFile read_ply(const FileData& f, PolygonSplits& polygons, bool attributes, bool points) {
  const Header h = parse_header(f);
  const Layout l = find_layout(f, h, attributes, points);
  return h.encoding == Encoding::Ascii ? read_ascii(f, h, l, polygons) : read_binary(f, h, l, polygons);
}

std::string format_ply(const MeshView& mesh, bool binary) {
  static_assert(sizeof(double) == 8 && sizeof(std::int32_t) == 4, "PLY double and int");
  const double* v = mesh.vertices;
  const std::size_t n = mesh.n_vertices, m = mesh.n_faces;
  // The list's count is a uchar unless a face has more than 255 corners.
  std::size_t n_indices = 0, largest = 0;
  for_each_face(mesh, [&](const std::int32_t*, std::size_t k) {
    n_indices += k;
    largest = std::max(largest, k);
  });
  const bool wide = largest > 255;
  // Per-vertex texture coordinates and normals (per_vertex_values refuses seams).
  const std::vector<double> uvs = per_vertex_values(mesh, mesh.uvs, "texture coordinates");
  const std::vector<double> normals = per_vertex_values(mesh, mesh.normals, "normals");
  const std::size_t uw = uvs.empty() ? 0 : 2, nw = normals.empty() ? 0 : 3, width = 3 + uw + nw;
  TextOut out(binary ? 300 + 8 * width * n + (wide ? 4 : 1) * m + 4 * n_indices : n * 20 * width + m * 30);
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment written by sorpia "
      << SORPIA_VERSION << "\nelement vertex " << std::to_string(n)
      << "\nproperty double x\nproperty double y\nproperty double z\n"
      << (uw ? "property double u\nproperty double v\n" : "")
      << (nw ? "property double nx\nproperty double ny\nproperty double nz\n" : "") << "element face "
      << std::to_string(m)
      << (wide ? "\nproperty list int int vertex_indices\nend_header\n"
               : "\nproperty list uchar int vertex_indices\nend_header\n");
  std::string& s = out.str();
  // Vertex i's record: x y z [u v] [nx ny nz].
  const auto record = [&](std::size_t i, double* r) {
    std::copy(v + 3 * i, v + 3 * i + 3, r);
    if (uw) std::copy(uvs.data() + 2 * i, uvs.data() + 2 * i + 2, r + 3);
    if (nw) std::copy(normals.data() + 3 * i, normals.data() + 3 * i + 3, r + 3 + uw);
  };
  if (!binary) {
    double r[8];
    for (std::size_t i = 0; i < n; ++i) {
      record(i, r);
      for (std::size_t c = 0; c < width; ++c) (c ? out << ' ' : out).num(r[c]);
      out << '\n';
    }
    for_each_face(mesh, [&](const std::int32_t* f, std::size_t k) { (out.num(k) << ' ').face(f, k, 0) << '\n'; });
    return std::move(s);
  }
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the binary PLY writer assumes a little-endian machine"
#endif
  const std::size_t head = s.size();
  s.resize(head + 8 * width * n + (wide ? 4 : 1) * m + 4 * n_indices);
  char* p = s.data() + head;
  if (width == 3) {
    std::memcpy(p, v, 24 * n);
  } else {
    double r[8];
    for (std::size_t i = 0; i < n; ++i) {
      record(i, r);
      std::memcpy(p + 8 * width * i, r, 8 * width);
    }
  }
  p += 8 * width * n;
  if (!mesh.face_vertex_counts && mesh.face_size == 3) {  // triangles: fixed 13-byte records
    for (std::size_t i = 0; i < m; ++i, p += 13) {
      p[0] = 3;
      std::memcpy(p + 1, mesh.face_vertex_indices + 3 * i, 12);
    }
    return std::move(s);
  }
  for_each_face(mesh, [&](const std::int32_t* f, std::size_t k) {
    if (wide) {
      const auto c = static_cast<std::int32_t>(k);
      std::memcpy(p, &c, 4);
      p += 4;
    } else {
      *p++ = static_cast<char>(static_cast<unsigned char>(k));
    }
    std::memcpy(p, f, 4 * k);
    p += 4 * k;
  });
  return std::move(s);
}

}  // namespace sorpia::detail::io
