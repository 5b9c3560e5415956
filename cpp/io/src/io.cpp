// Mesh files: dispatch by extension, loading, atomic writing, shared checks.
#include "sorpia/io.hpp"
#include "sorpia/interrupt.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "io_detail.hpp"

namespace sorpia {

namespace {
std::string errno_text(int err) { return std::strerror(err); }

// Closes a file descriptor however the scope ends (errno kept for the message).
struct CloseOnExit {
  int fd;
  ~CloseOnExit() {
    const int err = errno;
    ::close(fd);
    errno = err;
  }
};
}  // namespace

namespace detail::io {

std::string printable_path(const std::string& path) {
  static const char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(path.size());
  const auto* p = reinterpret_cast<const unsigned char*>(path.data());
  const std::size_t n = path.size();
  for (std::size_t i = 0; i < n;) {
    // Length of a valid UTF-8 sequence at i (0: not one).
    std::size_t len = 0;
    if (p[i] < 0x80) {
      len = 1;
    } else {
      const std::size_t want = p[i] >= 0xF0 && p[i] <= 0xF4 ? 4 : p[i] >= 0xE0 ? 3 : p[i] >= 0xC2 && p[i] < 0xE0 ? 2 : 0;
      len = want;
      for (std::size_t k = 1; k < want; ++k)
        if (i + k >= n || (p[i + k] & 0xC0) != 0x80) len = 0;
      if (want == 3 && len && ((p[i] == 0xE0 && p[i + 1] < 0xA0) || (p[i] == 0xED && p[i + 1] >= 0xA0))) len = 0;
      if (want == 4 && len && ((p[i] == 0xF0 && p[i + 1] < 0x90) || (p[i] == 0xF4 && p[i + 1] >= 0x90))) len = 0;
    }
    if (len == 0) {
      out += "\\x";
      out += hex[p[i] >> 4];
      out += hex[p[i] & 15];
      ++i;
    } else {
      out.append(path, i, len);
      i += len;
    }
  }
  return out;
}

namespace {

// Whether `start`, the first bytes of a file (all of it when shorter than the
// sniffed size), can begin a file of `format`; throws FileError naming what is
// wrong when it cannot. Only what the format fixes at its start is checked:
// "ply" for PLY, an OFF keyword for OFF, a statement keyword for OBJ; an STL
// file may start with anything.
void check_start(const FileData& f, MeshFormat format) {
  std::string_view text(f.bytes);
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.remove_prefix(3);
  // The first token of the first line that holds more than blanks and comments.
  std::string_view first;
  bool found = false;
  LineReader lines(text.data(), text.data() + text.size());
  std::string_view line;
  while (!found && lines.next(line)) {
    std::string_view rest = strip_comment(line);
    found = next_token(rest, first);
  }
  // The readers' own messages for the same mistakes.
  switch (format) {
    case MeshFormat::Ply:
      if (f.bytes.compare(0, 3, "ply") != 0 || (f.bytes.size() > 3 && f.bytes[3] != '\n' && f.bytes[3] != '\r'))
        fail(f, Where{"line", 1}, "a PLY file starts with the line 'ply'");
      break;
    case MeshFormat::Off:
      if (found && !is_off_keyword(first))
        fail(f, Where{"line", lines.number()}, "an OFF file starts with 'OFF'");
      break;
    case MeshFormat::Obj:
      if (found && !is_obj_keyword(first))
        fail(f, Where{"line", lines.number()}, quoted(first) + " is not an OBJ statement (not a text OBJ file?)");
      break;
    case MeshFormat::Stl:
      break;
  }
}

}  // namespace

FileData load_file(const std::string& path, MeshFormat format) {
  FileData f{path, {}};
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(f, "cannot open the file: " + errno_text(errno));
  if (S_ISDIR(st.st_mode)) fail(f, "is a directory, not a mesh file");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(f, "cannot open the file: " + errno_text(errno));
  const CloseOnExit close_fd{fd};
  // Regular files report their size; read to the end either way (pipes, /proc).
  // Past the sniffed part the buffer takes one byte more than the size: the
  // read that finds the end then has room, instead of doubling a buffer the
  // file already fills.
  constexpr std::size_t kSniffed = 1 << 16;
  constexpr std::size_t kChunk = std::size_t{1} << 24;
  const std::size_t capacity = S_ISREG(st.st_mode) ? static_cast<std::size_t>(st.st_size) + 1 : 0;
  f.bytes.resize(kSniffed);  // the first read fills at most the part check_start looks at
  std::size_t used = 0;
  bool checked = false;
  for (;;) {
    if (used == f.bytes.size()) {
      if (!checked) {
        check_start(f, format);
        checked = true;
      }
      f.bytes.resize(std::max(capacity, 2 * f.bytes.size()));
    }
    // In chunks of at most kChunk bytes, polling for an interrupt between them.
    const ssize_t r = ::read(fd, f.bytes.data() + used, std::min(kChunk, f.bytes.size() - used));
    if (r < 0) {
      // A signal, on a pipe or a device: the interrupt checker says whether to stop.
      if (errno == EINTR) {
        check_interrupt_now();
        continue;
      }
      fail(f, "cannot read the file: " + errno_text(errno));
    }
    if (r == 0) break;
    used += static_cast<std::size_t>(r);
    poll_interrupt();
  }
  f.bytes.resize(used);
  if (used == 0) fail(f, "the file is empty");
  if (!checked) check_start(f, format);
  return f;
}

}  // namespace detail::io

namespace {

// The temporary file of write_file_atomic(path): in the folder of `path`, so
// that rename() is atomic, named by a short fixed prefix and mkstemp's random
// part (a name near NAME_MAX still has room for it), hidden from `ls` and
// from globs like *.ply while it exists.
constexpr char kTemporaryName[] = ".sorpia-tmp-XXXXXX";

struct Target {
  bool exists = false;
  struct stat st {};
};

// What is at `path` now; throws FileError when it is a folder or cannot be
// looked up (a name too long for its folder, a missing or unreadable folder).
Target inspect_target(const detail::io::FileData& f) {
  Target t;
  t.exists = ::stat(f.path.c_str(), &t.st) == 0;
  if (!t.exists && errno != ENOENT) detail::io::fail(f, "cannot write the file: " + errno_text(errno));
  if (t.exists && S_ISDIR(t.st.st_mode)) detail::io::fail(f, "is a directory; give a file name");
  return t;
}

// Creates the temporary file for `f.path`; returns its descriptor and sets `tmp`.
int create_temporary(const detail::io::FileData& f, std::string& tmp) {
  const std::size_t slash = f.path.find_last_of('/');
  tmp = (slash == std::string::npos ? std::string() : f.path.substr(0, slash + 1)) + kTemporaryName;
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0) detail::io::fail(f, "cannot create a temporary file in its folder: " + errno_text(errno));
  return fd;
}

}  // namespace

void check_writable(const std::string& path) {
  const detail::io::FileData f{path, {}};
  inspect_target(f);
  std::string tmp;
  ::close(create_temporary(f, tmp));
  ::unlink(tmp.c_str());
}

void write_file_atomic(const std::string& path, const std::string& data) {
  using detail::io::fail;
  const detail::io::FileData f{path, {}};
  const Target target = inspect_target(f);
  std::string tmp;
  const int fd = create_temporary(f, tmp);
  auto abandon = [&](const std::string& what, int err) {
    ::close(fd);
    ::unlink(tmp.c_str());
    fail(f, what + ": " + errno_text(err));
  };
  // mkstemp makes the file 0600: give it the mode a plain open() would, or
  // the mode of the file it replaces.
  mode_t mode = 0;
  if (target.exists) {
    mode = target.st.st_mode & 07777;
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    mode = 0666 & ~mask;
  }
  if (::fchmod(fd, mode) != 0) abandon("cannot set the file mode", errno);
  // A signal during the write (EINTR) does not stop it: the call finishes or
  // fails (removing the temporary file) before a handler in the caller runs.
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t w = ::write(fd, data.data() + done, data.size() - done);
    if (w < 0) {
      if (errno == EINTR) continue;
      abandon("writing failed (nothing was changed)", errno);
    }
    done += static_cast<std::size_t>(w);
  }
  // On disk before the rename, so a crash leaves the old file or the new one.
  if (::fsync(fd) != 0) abandon("writing failed (nothing was changed)", errno);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail(f, "writing failed (nothing was changed): " + errno_text(err));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail(f, "cannot replace the file: " + errno_text(err));
  }
}

namespace detail::io {

namespace {

// The edges of a mesh, and the diagonals added to it, in one bucket per
// vertex (an edge is kept in the bucket of its smaller end). Each bucket's
// room is counted before anything is added: the mesh's edges plus every
// diagonal its polygons could take. Lookups scan one short bucket.
class EdgeBuckets {
 public:
  explicit EdgeBuckets(std::size_t n_vertices) : start_(n_vertices + 1, 0) {}
  // First pass: room for an edge (u, w).
  void count(std::int32_t u, std::int32_t w) { ++start_[static_cast<std::size_t>(std::min(u, w)) + 1]; }
  void allocate() {
    for (std::size_t v = 1; v < start_.size(); ++v) start_[v] += start_[v - 1];
    fill_.assign(start_.begin(), start_.end() - 1);
    other_.resize(start_.back());
  }
  void insert(std::int32_t u, std::int32_t w) { other_[fill_[std::min(u, w)]++] = std::max(u, w); }
  bool contains(std::int32_t u, std::int32_t w) const {
    const auto lo = static_cast<std::size_t>(std::min(u, w));
    const std::int32_t hi = std::max(u, w);
    for (std::size_t p = start_[lo]; p < fill_[lo]; ++p)
      if (other_[p] == hi) return true;
    return false;
  }

 private:
  std::vector<std::size_t> start_, fill_;
  std::vector<std::int32_t> other_;
};

double squared_distance(const std::vector<double>& v, std::int32_t a, std::int32_t b) {
  double s = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double d = v[3 * static_cast<std::size_t>(a) + c] - v[3 * static_cast<std::size_t>(b) + c];
    s += d * d;
  }
  return s;
}

}  // namespace

void triangulate_polygons(const PolygonSplits& polygons, const std::vector<double>& vertices,
                          std::vector<std::int32_t>& faces) {
  if (polygons.list.empty()) return;
  // Calls f(row) for every row of `faces` that is a triangle of the file (not
  // a row of the fans standing in for the polygons).
  const auto for_each_triangle = [&](auto f) {
    std::size_t next_polygon = 0;
    for (std::size_t row = 0; row < faces.size() / 3; ++row) {
      if (next_polygon < polygons.list.size() && row == polygons.list[next_polygon].first_row) {
        row += polygons.list[next_polygon++].k - 3;  // the fan's other rows
        continue;
      }
      f(faces.data() + 3 * row);
    }
  };
  // Calls f(u, w) for every side of every polygon, and g(u, w) for each
  // diagonal it may take (none beyond the fan from its first corner past
  // kMaxSearched corners).
  constexpr std::size_t kMaxSearched = 32;
  const auto for_each_polygon_edge = [&](auto side, auto diagonal) {
    for (const auto& p : polygons.list) {
      const std::int32_t* q = polygons.indices.data() + p.first_index;
      for (std::size_t c = 0; c < p.k; ++c) side(q[c], q[(c + 1) % p.k]);
      if (p.k > kMaxSearched) {
        for (std::size_t d = 2; d + 1 < p.k; ++d) diagonal(q[0], q[d]);
        continue;
      }
      for (std::size_t a = 0; a < p.k; ++a)
        for (std::size_t b = a + 2; b < p.k; ++b)
          if (!(a == 0 && b == p.k - 1)) diagonal(q[a], q[b]);
    }
  };
  EdgeBuckets edges(vertices.size() / 3);
  const auto count = [&](std::int32_t u, std::int32_t w) { edges.count(u, w); };
  const auto insert = [&](std::int32_t u, std::int32_t w) { edges.insert(u, w); };
  for_each_triangle([&](const std::int32_t* t) {
    for (int c = 0; c < 3; ++c) count(t[c], t[(c + 1) % 3]);
  });
  for_each_polygon_edge(count, count);
  edges.allocate();
  for_each_triangle([&](const std::int32_t* t) {
    for (int c = 0; c < 3; ++c) insert(t[c], t[(c + 1) % 3]);
  });
  for_each_polygon_edge(insert, [](std::int32_t, std::int32_t) {});

  for (const auto& p : polygons.list) {
    const std::int32_t* q = polygons.indices.data() + p.first_index;
    const std::size_t k = p.k;
    const auto is_new = [&](std::size_t corner) {  // every diagonal of the fan from `corner` is a new edge
      for (std::size_t d = 2; d + 1 < k; ++d)
        if (edges.contains(q[corner], q[(corner + d) % k])) return false;
      return true;
    };
    std::size_t corner = 0;
    if (k == 4) {
      // corner 0 cuts along (q0, q2), corner 1 along (q1, q3): the shorter first.
      const bool second_shorter = squared_distance(vertices, q[1], q[3]) < squared_distance(vertices, q[0], q[2]);
      const std::size_t first = second_shorter ? 1 : 0;
      corner = is_new(first) || !is_new(1 - first) ? first : 1 - first;
    } else if (k <= kMaxSearched) {
      for (std::size_t c = 0; c < k; ++c)
        if (is_new(c)) {
          corner = c;
          break;
        }
    }
    std::int32_t* out = faces.data() + 3 * p.first_row;
    for (std::size_t i = 1; i + 1 < k; ++i) {
      out[3 * (i - 1)] = q[corner];
      out[3 * (i - 1) + 1] = q[(corner + i) % k];
      out[3 * (i - 1) + 2] = q[(corner + i + 1) % k];
    }
    for (std::size_t d = 2; d + 1 < k; ++d) edges.insert(q[corner], q[(corner + d) % k]);
  }
}

std::vector<std::int32_t> triangle_rows(const PolygonSplits& polygons, const std::vector<std::int32_t>& holes) {
  // extra[i]: rows the polygons before polygons.list[i] add beyond one per face.
  std::vector<std::size_t> extra(polygons.list.size() + 1, 0);
  for (std::size_t i = 0; i < polygons.list.size(); ++i) extra[i + 1] = extra[i] + polygons.list[i].k - 3;
  std::vector<std::int32_t> rows;
  rows.reserve(holes.size());
  for (const std::int32_t h : holes) {
    const auto face = static_cast<std::size_t>(h);
    const auto it = std::lower_bound(polygons.list.begin(), polygons.list.end(), face,
                                     [](const PolygonSplits::Polygon& p, std::size_t f) { return p.face < f; });
    const auto i = static_cast<std::size_t>(it - polygons.list.begin());
    const std::size_t first = face + extra[i];
    const std::size_t count = it != polygons.list.end() && it->face == face ? it->k - 2 : 1;
    for (std::size_t r = 0; r < count; ++r) rows.push_back(static_cast<std::int32_t>(first + r));
  }
  return rows;
}

void split_corner_values(const PolygonSplits& polygons, const std::vector<std::int32_t>& faces,
                         std::vector<std::int32_t>& corner_values) {
  if (polygons.list.empty()) return;
  std::vector<std::int32_t> out(faces.size());
  std::size_t row = 0, corner = 0, next = 0;  // a row of `faces`, a corner of the file's faces, a polygon
  while (row < faces.size() / 3) {
    if (next < polygons.list.size() && polygons.list[next].first_row == row) {
      const auto& p = polygons.list[next++];
      const std::int32_t* q = polygons.indices.data() + p.first_index;
      for (std::size_t r = 0; r + 2 < p.k; ++r, ++row)
        for (std::size_t c = 3 * row; c < 3 * row + 3; ++c) {
          std::size_t j = 0;
          while (q[j] != faces[c]) ++j;  // every vertex of the split is one of the polygon's corners
          out[c] = corner_values[corner + j];
        }
      corner += p.k;
    } else {
      std::copy(corner_values.begin() + static_cast<std::ptrdiff_t>(corner),
                corner_values.begin() + static_cast<std::ptrdiff_t>(corner + 3), out.begin() + 3 * row);
      corner += 3, ++row;
    }
  }
  corner_values = std::move(out);
}

std::vector<double> per_vertex_values(const MeshView& m, const FaceVaryingView& channel, const char* what) {
  std::vector<double> out;
  if (!channel.width) return out;
  const int width = std::string_view(what) == "normals" ? 3 : 2;
  if (channel.width != width)
    throw ParameterError(std::string("PLY stores ") + what + " per vertex as " + std::to_string(width) +
                         " numbers; these have " + std::to_string(channel.width) + ": write them to .obj");
  const auto w = static_cast<std::size_t>(width);
  out.assign(w * m.n_vertices, 0.0);
  std::vector<std::int32_t> value_of(m.n_vertices, -1);
  std::size_t corner = 0;
  for_each_face(m, [&](const std::int32_t* f, std::size_t k) {
    for (std::size_t c = 0; c < k; ++c, ++corner) {
      const auto v = static_cast<std::size_t>(f[c]);
      const std::int32_t value = channel.indices[corner];
      const double* x = channel.values + w * static_cast<std::size_t>(value);
      if (value_of[v] < 0) {
        value_of[v] = value;
        std::copy(x, x + w, out.begin() + static_cast<std::ptrdiff_t>(w * v));
      } else if (value_of[v] != value && !std::equal(x, x + w, out.begin() + static_cast<std::ptrdiff_t>(w * v))) {
        throw ParameterError(std::string("PLY stores ") + what + " per vertex, but vertex " + std::to_string(v) +
                             " has different ones in different faces (a seam): write them to .obj, which holds "
                             "them per face corner");
      }
    }
  });
  return out;
}

MeshFile parse_mesh(const FileData& file, MeshFormat format, const ReadOptions& options) {
  PolygonSplits polygons;
  polygons.triangulate = options.triangulate;
  MeshFile mesh;
  switch (format) {
    case MeshFormat::Obj: mesh = read_obj(file, polygons, options.tags, options.attributes); break;
    case MeshFormat::Off: mesh = read_off(file, polygons); break;
    case MeshFormat::Ply: mesh = read_ply(file, polygons, options.attributes, options.points); break;
    case MeshFormat::Stl: mesh = read_stl(file, polygons); break;
  }
  if (mesh.n_vertices() == 0) fail(file, "no vertices: not a mesh file of this format, or an empty mesh");
  if (mesh.n_faces() == 0 && !options.points) fail(file, "has " + std::to_string(mesh.n_vertices()) + " vertices but no faces");
  if (mesh.n_vertices() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    fail(file, "more vertices than int32 indices hold");
  if (mesh.n_faces() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    fail(file, "more faces than int32 indices hold");
  triangulate_polygons(polygons, mesh.vertices, mesh.face_vertex_indices);
  if (!polygons.list.empty() && !mesh.tags.tags.holes.empty())
    mesh.tags.tags.holes = triangle_rows(polygons, mesh.tags.tags.holes);
  for (FaceVarying* channel : {&mesh.uvs, &mesh.normals}) {
    if (channel->empty()) continue;
    if (channel->indices.empty())
      channel->indices = mesh.face_vertex_indices;  // per vertex: each corner's value is its vertex's
    else
      split_corner_values(polygons, mesh.face_vertex_indices, channel->indices);
  }
  return mesh;
}

}  // namespace detail::io

MeshFormat mesh_format(const std::string& path) {
  // The C library would stop at the NUL: "a.obj\0.ply" would open a.obj as PLY.
  const std::size_t nul = path.find('\0');
  if (nul != std::string::npos)
    throw FileError(detail::io::printable_path(path.substr(0, nul)) + "...: the path contains a NUL character");
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  std::string ext;
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == "obj") return MeshFormat::Obj;
  if (ext == "off") return MeshFormat::Off;
  if (ext == "ply") return MeshFormat::Ply;
  if (ext == "stl") return MeshFormat::Stl;
  throw FileError(detail::io::printable_path(path) + ": unknown mesh file extension " + (ext.empty() ? std::string("(none)") : "'." + ext + "'") +
                  ": use .obj, .off, .ply or .stl");
}

MeshFile read_mesh(const std::string& path, const ReadOptions& options) {
  const MeshFormat format = mesh_format(path);
  return detail::io::parse_mesh(detail::io::load_file(path, format), format, options);
}

namespace {

// The checks of a mesh view before its faces are read: every face of 3 or more corners, each naming a vertex in
// range (write_mesh's words).
void check_faces(const MeshView& mesh) {
  std::size_t face = 0;
  detail::io::for_each_face(mesh, [&](const std::int32_t* f, std::size_t k) {
    if (k < 3 || k > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
      throw MeshError("write_mesh: face " + std::to_string(face) + " has " +
                      std::to_string(static_cast<std::int32_t>(k)) + " vertices; a face needs at least 3");
    for (std::size_t c = 0; c < k; ++c)
      if (f[c] < 0 || static_cast<std::size_t>(f[c]) >= mesh.n_vertices)
        throw MeshError("write_mesh: face " + std::to_string(face) + " has vertex index " + std::to_string(f[c]) +
                        " out of range [0, " + std::to_string(mesh.n_vertices) + ")");
    ++face;
  });
}

// A face-varying channel's values finite and its index of every corner in range.
void check_channel(const MeshView& mesh, const FaceVaryingView& channel, const char* what) {
  for (std::size_t i = 0; i < channel.n_values * static_cast<std::size_t>(channel.width); ++i)
    if (!std::isfinite(channel.values[i]))
      throw MeshError(std::string("write_mesh: ") + what + " value " +
                      std::to_string(i / static_cast<std::size_t>(channel.width)) + " is not finite");
  std::size_t corner = 0, face = 0;
  detail::io::for_each_face(mesh, [&](const std::int32_t*, std::size_t k) {
    for (std::size_t c = 0; c < k; ++c, ++corner)
      if (channel.indices[corner] < 0 || static_cast<std::size_t>(channel.indices[corner]) >= channel.n_values)
        throw MeshError(std::string("write_mesh: face ") + std::to_string(face) + " has " + what + " index " +
                        std::to_string(channel.indices[corner]) + " out of range [0, " +
                        std::to_string(channel.n_values) + ")");
    ++face;
  });
}

}  // namespace

void write_mesh(const std::string& path, const MeshView& mesh, bool binary, const FileTags* tags) {
  const MeshFormat format = mesh_format(path);
  const std::string where = detail::io::printable_path(path) + ": ";
  if (binary && (format == MeshFormat::Obj || format == MeshFormat::Off))
    throw ParameterError(where + "OBJ and OFF are text formats; binary=true is for .ply and .stl");
  const bool triangles = !mesh.face_vertex_counts && mesh.face_size == 3;
  if (format == MeshFormat::Stl && !triangles)
    throw ParameterError(where +
                         "STL stores triangles only; write polygons to .obj, .off or .ply, or triangulate them");
  if (tags && !tags->empty() && format != MeshFormat::Obj)
    throw ParameterError(where + "sharpness tags (creases, corners, holes, boundary) are written to .obj files only "
                         "(OpenSubdiv's 't' lines); no other format has them");
  if (mesh.n_vertices == 0 || mesh.n_faces == 0) throw MeshError("write_mesh: the mesh has no vertices or no faces");
  for (std::size_t i = 0; i < 3 * mesh.n_vertices; ++i)
    if (!std::isfinite(mesh.vertices[i]))
      throw MeshError("write_mesh: vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
  check_faces(mesh);
  if (tags) check_tags(tags->tags, mesh.n_vertices, mesh.n_faces);
  for (const auto* channel : {&mesh.uvs, &mesh.normals}) {
    if (!channel->width) continue;
    const char* what = channel == &mesh.uvs ? "texture coordinates" : "normals";
    if (format == MeshFormat::Off || format == MeshFormat::Stl)
      throw ParameterError(where + what + " are written to .obj and .ply files only");
    if (channel->width < 1 || channel->width > 3)
      throw ParameterError(where + what + " have 1 to 3 numbers each, not " + std::to_string(channel->width));
    check_channel(mesh, *channel, what);
  }
  std::string data;
  switch (format) {
    case MeshFormat::Obj: data = detail::io::format_obj(mesh, tags && !tags->empty() ? tags : nullptr); break;
    case MeshFormat::Off: data = detail::io::format_off(mesh); break;
    case MeshFormat::Ply: data = detail::io::format_ply(mesh, binary); break;
    case MeshFormat::Stl: data = detail::io::format_stl(mesh, binary); break;
  }
  write_file_atomic(path, data);
}

void check_ply_per_vertex(const MeshView& mesh, const FaceVaryingView& channel, const char* what) {
  check_faces(mesh);  // per_vertex_values reads each corner's vertex and value unchecked
  if (channel.width) check_channel(mesh, channel, what);
  detail::io::per_vertex_values(mesh, channel, what);
}

}  // namespace sorpia
