#pragma once
/// @file io.hpp
/// Triangle-mesh files that keep every digit: OBJ, OFF, PLY (ascii, binary
/// little- and big-endian on reading) and STL (ascii, binary).
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
#include <string>

#include "sorpia/shapes.hpp"

namespace sorpia {

enum class MeshFormat { Obj, Off, Ply, Stl };

/// The format named by the file's extension (.obj, .off, .ply, .stl, any case).
/// @throws FileError for any other extension
MeshFormat mesh_format(const std::string& path);

/// Read a triangle mesh.
/// @param path         an .obj, .off, .ply or .stl file
/// @param triangulate  split polygons into triangles; when false a polygon is
///                     an error naming its line. The split keeps the mesh
///                     manifold where it can: a quad is cut along its shorter
///                     diagonal unless that diagonal is already an edge of the
///                     mesh (then along the other), a larger polygon is fanned
///                     from its first corner whose diagonals are all new edges
///                     (else, and beyond 32 corners, from its first corner);
///                     polygons in file order.
/// @param polygons     when not null, set to the number of faces of more
///                     than 3 vertices split (0 without triangulate)
/// @return vertices (n, 3) and faces (m, 3), in file order
/// The read polls the calling thread's interrupt checker
/// (sorpia/interrupt.hpp) after each chunk, and asks it at once when a signal
/// interrupts a read that waits (a pipe, a device); when the checker returns
/// false, the read goes on.
/// @throws Interrupted when the checker says stop
/// @throws FileError when the file is missing, unreadable, malformed,
///         truncated, has an index out of range, a non-finite coordinate,
///         no vertices or no faces
TriMesh read_mesh(const std::string& path, bool triangulate = false, std::size_t* polygons = nullptr);

/// Write a triangle mesh atomically: to a temporary file in the same folder,
/// then renamed over `path`, so that a failure leaves no partial file and an
/// existing file untouched.
/// @param path        an .obj, .off, .ply or .stl file
/// @param vertices    row-major (n_vertices, 3), finite
/// @param faces       row-major (n_faces, 3) indices in [0, n_vertices)
/// @param binary      binary PLY (little-endian) or STL; OBJ and OFF are text only
/// @throws FileError when the file cannot be written; MeshError for a bad
///         index or a non-finite coordinate; ParameterError for binary OBJ/OFF
void write_mesh(const std::string& path, const double* vertices, std::size_t n_vertices, const std::int32_t* faces,
                std::size_t n_faces, bool binary = false);

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
