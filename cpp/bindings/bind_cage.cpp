// Bindings of the cage a dense mesh is decimated to (sorpia/cage.hpp).
#include "bindings.hpp"
#include "sorpia/cage.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

void bind_cage(py::module_& m) {
  m.def(
      "decimate",
      [](const Vertices& vertices, const Faces& triangles, std::size_t n_vertices, sorpia::Scheme scheme,
         double max_normal_deviation, double max_aspect_ratio, double max_boundary_angle, bool strict) {
        check_shape(vertices, 3, "vertices");
        check_shape(triangles, 3, "faces");
        sorpia::Mesh mesh;
        mesh.vertices = to_vector(vertices);
        mesh.face_vertex_indices = to_vector(triangles);
        sorpia::DecimateOptions options;
        options.scheme = scheme;
        options.max_normal_deviation = max_normal_deviation;
        options.max_aspect_ratio = max_aspect_ratio;
        options.max_boundary_angle = max_boundary_angle;
        sorpia::Mesh cage;
        std::string stopped;
        {
          LongCall call;
          cage = sorpia::decimate(mesh, n_vertices, options, strict ? nullptr : &stopped);
        }
        return py::make_tuple(mesh_tuple(std::move(cage)), stopped.empty() ? py::object(py::none()) : py::str(stopped));
      },
      "vertices"_a.noconvert(), "triangles"_a.noconvert(), "n_vertices"_a, "scheme"_a, "max_normal_deviation"_a,
      "max_aspect_ratio"_a, "max_boundary_angle"_a, "strict"_a,
      "The cage of a triangle mesh (sorpia::decimate) and, unless strict, why the guards stopped it short (None "
      "when the count was reached): ((vertices, triangles) under Loop, (vertices, face_vertex_counts, "
      "face_vertex_indices) under Catmull-Clark; message).");
}

}  // namespace sorpia_py
