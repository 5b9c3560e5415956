#pragma once
/// @file io.hpp
/// Mesh files that keep every digit: OBJ, OFF, PLY (ascii, binary little- and
/// big-endian on reading) and STL (ascii, binary); polygons of any size (STL:
/// triangles), and OpenSubdiv's sharpness tags in OBJ files.
///
/// Text numbers are written in the shortest form that reads back to the same
/// double (std::to_chars) and parsed with std::from_chars, so a float64
/// coordinate round-trips bit for bit through OBJ, OFF and PLY (PLY stores
/// `double` properties). STL stores float32 by definition: the writers round
/// to float32.
///
/// Vertex order is kept (no merging, no reordering) for OBJ, OFF and PLY.
/// STL has no shared vertices: the reader merges corners whose three
/// coordinates are equal (exact comparison, no tolerance), numbering vertices
/// in order of first appearance.
///
/// Every failure throws sorpia::FileError naming the file and the line (text)
/// or the element (binary).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sorpia/mesh.hpp"
#include "sorpia/subdivision.hpp"

namespace sorpia {

enum class MeshFormat { Obj, Off, Ply, Stl };

/// The tags of an OBJ file, as OpenSubdiv's regression shapes write them and
/// its shape parser (regression/common/shape_utils.cpp, far_utils.h) reads
/// them: a line `t NAME I/F/S` followed by I integers, F numbers and S words.
///   t crease 2/1/0 A B S        edge (A, B), 0-based vertices, sharpness S;
///                                2k integers are k edges (pairs, not a chain),
///                                with one sharpness for all or one each
///   t corner 1/1/0 V S          vertex V; k vertices with one or k sharpnesses
///   t hole K/0/0 F ...          faces (0-based, file order)
///   t interpolateboundary 1/0/0 MODE   1: edge-and-corner, 2: edge-only
///                                (0, none, is refused: sorpia has no such rule)
///   t creasemethod 0/0/1 normal  ("chaikin" is refused)
///   t smoothtriangles 0/0/1 catmark  ("smooth" is refused)
/// A negative sharpness counts as 0, as OpenSubdiv reads it. The face-varying
/// tags (facevaryinginterpolateboundary, facevaryingpropagatecorners) do not
/// change positions and are skipped; other names are skipped and listed in
/// `unknown`.
struct FileTags {
  Tags tags;                        ///< creases, corners, holes (with triangulate: rows of the triangles)
  std::optional<Boundary> boundary;  ///< the interpolateboundary tag, when the file has one
  /// A tag name sorpia does not know, with its count and first line, one
  /// entry per name: "'foo': 3 tags, the first on line 12".
  std::vector<std::string> unknown;
  bool empty() const { return tags.empty() && !boundary; }
};

/// A face-varying channel as OpenSubdiv's Far::TopologyDescriptor::FVarChannel
/// holds one: values, and for every face corner (in the order of the faces'
/// corners) the index of its value. Texture coordinates (OBJ `vt`, PLY `u v`)
/// and normals (OBJ `vn`, PLY `nx ny nz`). A per-vertex attribute (PLY) has
/// one value per vertex and the faces' vertex indices as its value indices.
struct FaceVarying {
  std::vector<double> values;         ///< (n_values, width)
  std::vector<std::int32_t> indices;  ///< one per face corner; -1: this corner has no value (OBJ `f a b/c ...`)
  int width = 0;                      ///< numbers per value (2 or 3 for texture coordinates, 3 for normals); 0: none
  bool empty() const { return width == 0; }
  std::size_t n_values() const { return width ? values.size() / static_cast<std::size_t>(width) : 0; }
};

/// A FaceVarying borrowed from the caller (MeshView).
struct FaceVaryingView {
  const double* values = nullptr;  ///< (n_values, width), finite
  std::size_t n_values = 0;
  int width = 0;                         ///< 0: none
  const std::int32_t* indices = nullptr;  ///< one per face corner, in [0, n_values)
};

/// The format named by the file's extension (.obj, .off, .ply, .stl, any case).
/// @throws FileError for any other extension
MeshFormat mesh_format(const std::string& path);

/// A mesh as a file holds it: a sorpia::Mesh (vertices in file order, faces
/// in the counts + indices form, face_vertex_counts empty when every face has
/// the same number of corners) and what else the file says.
struct MeshFile : Mesh {
  std::size_t polygons_split = 0;  ///< faces of more than 3 corners split (ReadOptions::triangulate)
  FileTags tags;                   ///< the OBJ file's `t` lines (ReadOptions::tags)
  FaceVarying uvs;      ///< texture coordinates (ReadOptions::attributes), following the faces as triangulated
  FaceVarying normals;  ///< normals (ReadOptions::attributes), as `uvs`
};

struct ReadOptions {
  /// Split faces of more than 3 corners into triangles, each polygon's
  /// triangles in its place in the face order. The split keeps the mesh
  /// manifold where it can: a quad is cut along its shorter diagonal unless
  /// that diagonal is already an edge of the mesh (then along the other), a
  /// larger polygon is fanned from its first corner whose diagonals are all
  /// new edges (else, and beyond 32 corners, from its first corner); polygons
  /// in file order. Hole tags are mapped to the triangles of their faces.
  bool triangulate = false;
  /// Read OpenSubdiv's `t` tag lines of an OBJ file (FileTags); without it
  /// they are skipped unread, as every other OBJ statement sorpia does not use.
  bool tags = false;
  /// Read texture coordinates and normals (MeshFile::uvs, normals): OBJ `vt`
  /// and `vn` with the faces' `a/b/c` indices (face-varying), PLY per-vertex
  /// `u v` (or `s t`, `texture_u texture_v`, `texture_s texture_t`) and `nx ny
  /// nz`. Without it they are skipped unread. OFF and STL give none.
  bool attributes = false;
  /// Accept a file without faces, a point cloud (a PLY file with no face
  /// element, an OBJ file of `v` lines, an OFF file of 0 faces): its
  /// vertices with no faces. Without it such a file is refused.
  bool points = false;
};

/// Read a mesh.
/// @param path     an .obj, .off, .ply or .stl file
/// @return vertices and faces in file order (polygons kept as they are
///         unless options.triangulate), and the tags when options.tags
/// The read polls the calling thread's interrupt checker
/// (sorpia/interrupt.hpp) after each chunk, and asks it at once when a signal
/// interrupts a read that waits (a pipe, a device); when the checker returns
/// false, the read goes on.
/// @throws Interrupted when the checker says stop
/// @throws FileError when the file is missing, unreadable, malformed,
///         truncated, has an index out of range, a face of fewer than 3
///         vertices, a non-finite coordinate, no vertices or no faces, or (with
///         options.tags) a malformed tag or one whose rule sorpia does not have
MeshFile read_mesh(const std::string& path, const ReadOptions& options = {});

/// A mesh to write, borrowed from the caller: a sorpia::Mesh by pointers.
struct MeshView {
  const double* vertices = nullptr;  ///< (n_vertices, 3), finite
  std::size_t n_vertices = 0;
  const std::int32_t* face_vertex_indices = nullptr;  ///< every face's corners, face after face, in [0, n_vertices)
  std::size_t n_faces = 0;
  const std::int32_t* face_vertex_counts = nullptr;  ///< (n_faces,) corners per face (at least 3); null: face_size
  std::int32_t face_size = 3;
  FaceVaryingView uvs;      ///< texture coordinates to write (OBJ `vt`; PLY `u v` when each vertex has one value)
  FaceVaryingView normals;  ///< normals to write (OBJ `vn`; PLY `nx ny nz` when each vertex has one value)
};

/// Write a mesh atomically: to a temporary file in the same folder, then
/// renamed over `path`, so that a failure leaves no partial file and an
/// existing file untouched. OBJ, OFF and PLY take any polygons, STL triangles
/// only; tags are written to OBJ only (`t` lines, one tag a line, as
/// OpenSubdiv's shapes have them).
/// @param binary      binary PLY (little-endian) or STL; OBJ and OFF are text only
/// @param tags        null or empty: no tag lines
/// @throws FileError when the file cannot be written; MeshError for a bad
///         index, a face of fewer than 3 corners or a non-finite coordinate;
///         ParameterError for binary OBJ/OFF, polygons to STL, tags to
///         anything but OBJ, texture coordinates or normals to OFF or STL, or
///         to PLY where a vertex has several different values (a seam: OBJ
///         holds them per corner); MeshError for a value index out of range
///         or a non-finite value
void write_mesh(const std::string& path, const MeshView& mesh, bool binary = false, const FileTags* tags = nullptr);

/// write_mesh of a sorpia::Mesh.
inline void write_mesh(const std::string& path, const Mesh& mesh, bool binary = false) {
  write_mesh(path,
             MeshView{mesh.vertices.data(), mesh.n_vertices(), mesh.face_vertex_indices.data(), mesh.n_faces(),
                      mesh.uniform() ? nullptr : mesh.face_vertex_counts.data(), mesh.face_size, {}, {}},
             binary);
}

/// write_mesh of a triangle mesh: faces (n_faces, 3).
inline void write_mesh(const std::string& path, const double* vertices, std::size_t n_vertices,
                       const std::int32_t* faces, std::size_t n_faces, bool binary = false) {
  write_mesh(path, MeshView{vertices, n_vertices, faces, n_faces, nullptr, 3, {}, {}}, binary);
}

/// The check write_mesh makes of a face-varying channel for PLY, which
/// stores one value per vertex: the channel's width is that of PLY's
/// properties (2 numbers for texture coordinates, 3 for normals: `what` is
/// "texture coordinates" or "normals") and every corner of a vertex has the
/// same value (no seam). For a check before long work, with the writer's
/// words.
/// @throws ParameterError naming the first vertex with several values, or the width;
///         MeshError for a face or a corner's value index out of range (write_mesh's checks)
void check_ply_per_vertex(const MeshView& mesh, const FaceVaryingView& channel, const char* what);

/// Write `data` to `path` atomically, as write_mesh writes its bytes: to a
/// temporary file in the same folder (".sorpia-tmp-" and 6 random
/// characters, whatever the length of `path`'s name; the mode of the file it
/// replaces, or the umask's), fsync, then renamed over `path`. A failure
/// removes the temporary file and leaves `path` as it was. A signal does not
/// interrupt it: the call finishes or fails first. Every file sorpia writes
/// goes through it.
/// @throws FileError naming the path when the file cannot be written
void write_file_atomic(const std::string& path, const std::string& data);

/// Whether write_file_atomic(path, ...) can start: `path` is not a folder,
/// its name fits its folder (NAME_MAX), and a temporary file can be created
/// (and is removed again) in the folder. For checks before long work; the
/// disk can still fill up meanwhile.
/// @throws FileError naming the path, with the words write_file_atomic would use
void check_writable(const std::string& path);

}  // namespace sorpia
