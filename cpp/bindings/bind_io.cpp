// Bindings of the mesh file readers and writers. Conversion and error
// translation only.
#include "bindings.hpp"
#include "sorpia/io.hpp"

#include <pybind11/stl.h>

#include <algorithm>
#include <optional>

namespace sorpia_py {
using namespace pybind11::literals;

void bind_io(py::module_& m) {
  m.def(
      "read_mesh",
      [](const std::string& path, bool triangulate, bool tags, bool attributes, bool points) {
        sorpia::MeshFile mesh;
        // A read interrupted by a signal (waiting on a pipe, a device) runs
        // Python's signal handlers: KeyboardInterrupt, or whatever a handler
        // raises, ends the read; a handler that returns lets it go on.
        {
          LongCall call;
          mesh = sorpia::read_mesh(path, sorpia::ReadOptions{triangulate, tags, attributes, points});
        }
        // sorpia.io.read_mesh makes its result of: vertices (n, 3); the faces,
        // (m, face_size) when face_vertex_counts is None, else the flat corner list;
        // face_vertex_counts; polygons split; with tags, (Tags, Boundary or None,
        // unknown tag names); with attributes, ((uv values, uv indices) or
        // None, (normal values, normal indices) or None).
        const bool uniform = mesh.face_vertex_counts.empty();
        py::object sizes =
            uniform ? py::object(py::none()) : py::object(to_numpy(std::move(mesh.face_vertex_counts), 0));
        py::object file_tags = py::none();
        if (tags) {
          py::object boundary = mesh.tags.boundary ? py::cast(*mesh.tags.boundary) : py::object(py::none());
          file_tags = py::make_tuple(py::cast(std::move(mesh.tags.tags)), boundary, py::cast(mesh.tags.unknown));
        }
        const auto channel = [](sorpia::FaceVarying& c) -> py::object {
          if (c.empty()) return py::none();
          return py::make_tuple(to_numpy(std::move(c.values), c.width), to_numpy(std::move(c.indices), 0));
        };
        py::object file_attributes = attributes ? py::object(py::make_tuple(channel(mesh.uvs), channel(mesh.normals)))
                                                : py::object(py::none());
        return py::make_tuple(to_numpy(std::move(mesh.vertices), 3),
                              to_numpy(std::move(mesh.face_vertex_indices), uniform ? mesh.face_size : 0), sizes,
                              mesh.polygons_split, file_tags, file_attributes);
      },
      "path"_a, "triangulate"_a, "tags"_a, "attributes"_a, "points"_a = false);
  m.def(
      "write_mesh",
      [](const std::string& path, const Vertices& vertices, const Faces& faces,
         const std::optional<Faces>& face_vertex_counts,
         std::int32_t face_size, bool binary, const std::optional<sorpia::Tags>& tags,
         std::optional<sorpia::Boundary> boundary, const std::optional<Vertices>& uv_values,
         const std::optional<Faces>& uv_indices, const std::optional<Vertices>& normal_values,
         const std::optional<Faces>& normal_indices) {
        check_shape(vertices, 3, "vertices");
        sorpia::MeshView view;
        view.vertices = vertices.data();
        view.n_vertices = static_cast<std::size_t>(vertices.shape(0));
        view.face_vertex_indices = faces.data();
        if (face_vertex_counts) {
          view.face_vertex_counts = face_vertex_counts->data();
          view.n_faces = static_cast<std::size_t>(face_vertex_counts->size());
          std::size_t total = 0;
          for (py::ssize_t i = 0; i < face_vertex_counts->size(); ++i)
            total += static_cast<std::size_t>(std::max(0, view.face_vertex_counts[i]));
          if (total != static_cast<std::size_t>(faces.size()))
            throw sorpia::ParameterError("write_mesh: the face sizes add up to " + std::to_string(total) +
                                         " corners but the faces list " + std::to_string(faces.size()));
        } else {
          if (face_size < 3) throw sorpia::MeshError("write_mesh: a face needs at least 3 vertices");
          view.face_size = face_size;
          view.n_faces = static_cast<std::size_t>(faces.size()) / static_cast<std::size_t>(face_size);
          if (view.n_faces * static_cast<std::size_t>(face_size) != static_cast<std::size_t>(faces.size()))
            throw sorpia::ParameterError("write_mesh: the faces do not divide into faces of " +
                                         std::to_string(face_size));
        }
        // Texture coordinates and normals: (values (k, width), one index per corner), shapes checked by sorpia.io.
        const auto channel = [&](const std::optional<Vertices>& values, const std::optional<Faces>& indices,
                                 sorpia::FaceVaryingView& out, const char* what) {
          if (!values || !indices) return;
          if (values->ndim() != 2 || static_cast<std::size_t>(indices->size()) != static_cast<std::size_t>(faces.size()))
            throw sorpia::ParameterError(std::string("write_mesh: ") + what +
                                         " need (values (k, width), one index per face corner)");
          out.values = values->data();
          out.n_values = static_cast<std::size_t>(values->shape(0));
          out.width = static_cast<int>(values->shape(1));
          out.indices = indices->data();
        };
        channel(uv_values, uv_indices, view.uvs, "texture coordinates");
        channel(normal_values, normal_indices, view.normals, "normals");
        sorpia::FileTags file_tags;
        if (tags) file_tags.tags = *tags;
        file_tags.boundary = boundary;
        py::gil_scoped_release release;
        sorpia::write_mesh(path, view, binary, &file_tags);
      },
      "path"_a, "vertices"_a.noconvert(), "face_vertex_indices"_a.noconvert(), "face_vertex_counts"_a.noconvert(),
      "face_size"_a,
      "binary"_a, "tags"_a, "boundary"_a, "uv_values"_a.noconvert() = py::none(), "uv_indices"_a.noconvert() = py::none(),
      "normal_values"_a.noconvert() = py::none(), "normal_indices"_a.noconvert() = py::none());
  m.def(
      "check_ply_per_vertex",
      [](const Faces& faces, const std::optional<Faces>& face_vertex_counts, std::int32_t face_size,
         std::size_t n_vertices, const Vertices& values, const Faces& indices, const std::string& what) {
        if (values.ndim() != 2 || indices.size() != faces.size())
          throw sorpia::ParameterError("check_ply_per_vertex: (values (k, width), one index per face corner)");
        sorpia::MeshView view;
        view.n_vertices = n_vertices;
        view.face_vertex_indices = faces.data();
        if (face_vertex_counts) {
          view.face_vertex_counts = face_vertex_counts->data();
          view.n_faces = static_cast<std::size_t>(face_vertex_counts->size());
        } else {
          view.face_size = face_size;
          view.n_faces = static_cast<std::size_t>(faces.size()) / static_cast<std::size_t>(std::max(face_size, 1));
        }
        // The views read faces.size() corners: the arrays must hold them (the core checks the indices in them).
        if (face_vertex_counts) {
          std::size_t total = 0;
          for (py::ssize_t f = 0; f < face_vertex_counts->size(); ++f)
            total += static_cast<std::size_t>(std::max(0, face_vertex_counts->data()[f]));
          if (total != static_cast<std::size_t>(faces.size()))
            throw sorpia::ParameterError("check_ply_per_vertex: the face sizes do not add up to the corners");
        }
        sorpia::FaceVaryingView channel;
        channel.values = values.data();
        channel.n_values = static_cast<std::size_t>(values.shape(0));
        channel.width = static_cast<int>(values.shape(1));
        channel.indices = indices.data();
        sorpia::check_ply_per_vertex(view, channel, what.c_str());
      },
      "face_vertex_indices"_a.noconvert(), "face_vertex_counts"_a.noconvert(), "face_size"_a, "n_vertices"_a,
      "values"_a.noconvert(), "indices"_a.noconvert(), "what"_a,
      "Raise ParameterError where PLY cannot hold the channel per vertex (write_mesh's check: the width, a seam).");
  m.def(
      "write_file_atomic",
      [](const std::string& path, const py::bytes& data) {
        std::string bytes = data;
        py::gil_scoped_release release;
        sorpia::write_file_atomic(path, bytes);
      },
      "path"_a, "data"_a, "Write bytes to path atomically (temporary file, fsync, rename).");
  m.def(
      "check_writable",
      [](const std::string& path) {
        py::gil_scoped_release release;
        sorpia::check_writable(path);
      },
      "path"_a, "Raise MeshFileError naming path when write_file_atomic(path, ...) could not start.");
}

}  // namespace sorpia_py
