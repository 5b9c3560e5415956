// Bindings of the mesh file readers and writers. Conversion and error
// translation only.
#include "bindings.hpp"
#include "sorpia/io.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

void bind_io(py::module_& m) {
  m.def(
      "read_mesh",
      [](const std::string& path, bool triangulate) {
        sorpia::TriMesh mesh;
        std::size_t polygons = 0;
        // A read interrupted by a signal (waiting on a pipe, a device) runs
        // Python's signal handlers: KeyboardInterrupt, or whatever a handler
        // raises, ends the read; a handler that returns lets it go on.
        {
          LongCall call;
          mesh = sorpia::read_mesh(path, triangulate, &polygons);
        }
        // (vertices, faces, polygons split): sorpia.read_mesh returns the first two.
        return py::make_tuple(to_numpy(std::move(mesh.vertices), 3), to_numpy(std::move(mesh.faces), 3), polygons);
      },
      "path"_a, "triangulate"_a);
  m.def(
      "write_mesh",
      [](const std::string& path, const Vertices& vertices, const Faces& faces, bool binary) {
        check_shape(vertices, 3, "vertices");
        check_shape(faces, 3, "faces");
        const double* v = vertices.data();
        const std::int32_t* f = faces.data();
        const auto n = static_cast<std::size_t>(vertices.shape(0));
        const auto nf = static_cast<std::size_t>(faces.shape(0));
        py::gil_scoped_release release;
        sorpia::write_mesh(path, v, n, f, nf, binary);
      },
      "path"_a, "vertices"_a.noconvert(), "faces"_a.noconvert(), "binary"_a);
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
