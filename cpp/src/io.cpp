// Mesh files: dispatch by extension, loading, atomic writing, shared checks.
#include "sorpia/io.hpp"

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
}  // namespace

namespace detail::io {

FileData load_file(const std::string& path) {
  FileData f{path, {}};
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(f, "cannot open the file: " + errno_text(errno));
  if (S_ISDIR(st.st_mode)) fail(f, "is a directory, not a mesh file");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(f, "cannot open the file: " + errno_text(errno));
  // Regular files report their size; read to the end either way (pipes, /proc).
  // One byte more than the size: the read that finds the end then has room,
  // instead of doubling (and zero-filling) a buffer the file already fills.
  const std::size_t capacity = S_ISREG(st.st_mode) ? static_cast<std::size_t>(st.st_size) + 1 : 0;
  f.bytes.resize(std::max<std::size_t>(capacity, 1 << 16));
  std::size_t used = 0;
  for (;;) {
    if (used == f.bytes.size()) f.bytes.resize(2 * f.bytes.size());
    const ssize_t r = ::read(fd, f.bytes.data() + used, f.bytes.size() - used);
    if (r < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      fail(f, "cannot read the file: " + errno_text(err));
    }
    if (r == 0) break;
    used += static_cast<std::size_t>(r);
  }
  ::close(fd);
  f.bytes.resize(used);
  if (used == 0) fail(f, "the file is empty");
  return f;
}

}  // namespace detail::io

void write_file_atomic(const std::string& path, const std::string& data) {
  using detail::io::fail;
  const detail::io::FileData f{path, {}};
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode)) fail(f, "is a directory; give a file name");
  // The temporary file lives in the same folder so that rename() is atomic.
  std::string tmp = path + ".sorpia-tmp-XXXXXX";
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0) fail(f, "cannot create a temporary file in its folder: " + errno_text(errno));
  auto abandon = [&](const std::string& what, int err) {
    ::close(fd);
    ::unlink(tmp.c_str());
    fail(f, what + ": " + errno_text(err));
  };
  // mkstemp makes the file 0600: give it the mode a plain open() would, or
  // the mode of the file it replaces.
  mode_t mode = 0;
  if (exists) {
    mode = st.st_mode & 07777;
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    mode = 0666 & ~mask;
  }
  if (::fchmod(fd, mode) != 0) abandon("cannot set the file mode", errno);
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

TriMesh parse_mesh(const FileData& file, MeshFormat format, Polygons& polygons) {
  TriMesh mesh;
  switch (format) {
    case MeshFormat::Obj: mesh = read_obj(file, polygons); break;
    case MeshFormat::Off: mesh = read_off(file, polygons); break;
    case MeshFormat::Ply: mesh = read_ply(file, polygons); break;
    case MeshFormat::Stl: mesh = read_stl(file, polygons); break;
  }
  if (mesh.n_vertices() == 0) fail(file, "no vertices: not a mesh file of this format, or an empty mesh");
  if (mesh.n_faces() == 0)
    fail(file, "has " + std::to_string(mesh.n_vertices()) + " vertices but no faces: sorpia needs a triangle mesh");
  if (mesh.n_vertices() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    fail(file, "more vertices than int32 indices hold");
  return mesh;
}

}  // namespace detail::io

MeshFormat mesh_format(const std::string& path) {
  // The C library would stop at the NUL: "a.obj\0.ply" would open a.obj as PLY.
  const std::size_t nul = path.find('\0');
  if (nul != std::string::npos)
    throw FileError(path.substr(0, nul) + "...: the path contains a NUL character");
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  std::string ext;
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == "obj") return MeshFormat::Obj;
  if (ext == "off") return MeshFormat::Off;
  if (ext == "ply") return MeshFormat::Ply;
  if (ext == "stl") return MeshFormat::Stl;
  throw FileError(path + ": unknown mesh file extension " + (ext.empty() ? std::string("(none)") : "'." + ext + "'") +
                  ": use .obj, .off, .ply or .stl");
}

TriMesh read_mesh(const std::string& path, bool triangulate, std::size_t* polygons) {
  const MeshFormat format = mesh_format(path);
  detail::io::Polygons p;
  p.triangulate = triangulate;
  TriMesh mesh = detail::io::parse_mesh(detail::io::load_file(path), format, p);
  if (polygons) *polygons = p.split;
  return mesh;
}

void write_mesh(const std::string& path, const double* vertices, std::size_t n_vertices, const std::int32_t* faces,
                std::size_t n_faces, bool binary) {
  const MeshFormat format = mesh_format(path);
  if (binary && (format == MeshFormat::Obj || format == MeshFormat::Off))
    throw ParameterError(path + ": OBJ and OFF are text formats; binary=true is for .ply and .stl");
  if (n_vertices == 0 || n_faces == 0) throw MeshError("write_mesh: the mesh has no vertices or no faces");
  for (std::size_t i = 0; i < 3 * n_vertices; ++i)
    if (!std::isfinite(vertices[i]))
      throw MeshError("write_mesh: vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
  for (std::size_t i = 0; i < 3 * n_faces; ++i)
    if (faces[i] < 0 || static_cast<std::size_t>(faces[i]) >= n_vertices)
      throw MeshError("write_mesh: face " + std::to_string(i / 3) + " has vertex index " + std::to_string(faces[i]) +
                      " out of range [0, " + std::to_string(n_vertices) + ")");
  std::string data;
  switch (format) {
    case MeshFormat::Obj: data = detail::io::format_obj(vertices, n_vertices, faces, n_faces); break;
    case MeshFormat::Off: data = detail::io::format_off(vertices, n_vertices, faces, n_faces); break;
    case MeshFormat::Ply: data = detail::io::format_ply(vertices, n_vertices, faces, n_faces, binary); break;
    case MeshFormat::Stl: data = detail::io::format_stl(vertices, n_vertices, faces, n_faces, binary); break;
  }
  write_file_atomic(path, data);
}

}  // namespace sorpia
