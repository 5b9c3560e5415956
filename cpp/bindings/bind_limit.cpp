// Bindings of the topology, the limit operator and the generated shapes.
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/shapes.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

void bind_limit(py::module_& m) {
  py::enum_<sorpia::Boundary>(m, "Boundary", "Boundary interpolation rule (sorpia::Boundary).")
      .value("edge_and_corner", sorpia::Boundary::EdgeAndCorner)
      .value("edge_only", sorpia::Boundary::EdgeOnly);
  m.def("parse_boundary", &sorpia::parse_boundary, "name"_a);
  m.def("boundary_name", &sorpia::boundary_name, "boundary"_a);
  py::enum_<sorpia::Scheme>(m, "Scheme", "Subdivision scheme (sorpia::Scheme).")
      .value("loop", sorpia::Scheme::Loop)
      .value("catmull_clark", sorpia::Scheme::CatmullClark);
  m.def("parse_scheme", &sorpia::parse_scheme, "name"_a);
  m.def("scheme_name", &sorpia::scheme_name, "scheme"_a);
  m.attr("INFINITE_SHARPNESS") = sorpia::kInfiniteSharpness;

  // Tags are built from arrays _validate.as_tags has already converted; the
  // constructor copies them and runs the core's checks (sorpia::check_tags).
  using Doubles = py::array_t<double, py::array::c_style>;
  py::class_<sorpia::Tags>(m, "Tags", "OpenSubdiv's sharpness tags (sorpia::Tags).")
      .def(py::init([](const Faces& crease_vertices, const Doubles& crease_sharpness, const Faces& corner_vertices,
                        const Doubles& corner_sharpness, const Faces& holes, std::size_t n_vertices,
                        std::size_t n_faces) {
             sorpia::Tags t{to_vector(crease_vertices), to_vector(crease_sharpness), to_vector(corner_vertices),
                            to_vector(corner_sharpness), to_vector(holes)};
             sorpia::check_tags(t, n_vertices, n_faces);
             return t;
           }),
           "crease_vertices"_a.noconvert(), "crease_sharpness"_a.noconvert(), "corner_vertices"_a.noconvert(),
           "corner_sharpness"_a.noconvert(), "holes"_a.noconvert(), "n_vertices"_a, "n_faces"_a)
      .def(py::init<>())
      .def_property_readonly("crease_vertices",
                             [](const sorpia::Tags& t) {
                               return to_numpy(t.crease_vertices, 2);
                             })
      .def_property_readonly("crease_sharpness", [](const sorpia::Tags& t) { return to_numpy(t.crease_sharpness, 0); })
      .def_property_readonly("corner_vertices", [](const sorpia::Tags& t) { return to_numpy(t.corner_vertices, 0); })
      .def_property_readonly("corner_sharpness", [](const sorpia::Tags& t) { return to_numpy(t.corner_sharpness, 0); })
      .def_property_readonly("holes", [](const sorpia::Tags& t) { return to_numpy(t.holes, 0); })
      .def("empty", &sorpia::Tags::empty)
      .def("max_semi_sharpness", &sorpia::Tags::max_semi_sharpness);

  py::class_<sorpia::Rules>(m, "Rules", "Scheme, boundary rule and sharpness tags (sorpia::Rules).")
      .def(py::init([](sorpia::Scheme scheme, sorpia::Boundary boundary, const sorpia::Tags& tags) {
             return sorpia::Rules{scheme, boundary, tags};
           }),
           py::kw_only(), "scheme"_a = sorpia::Scheme::Loop, "boundary"_a = sorpia::Boundary::EdgeAndCorner,
           "tags"_a = sorpia::Tags{})
      .def_readonly("scheme", &sorpia::Rules::scheme)
      .def_readonly("boundary", &sorpia::Rules::boundary)
      .def_readonly("tags", &sorpia::Rules::tags);

  py::class_<sorpia::Topology>(m, "Topology")
      .def(py::init([](const Faces& faces, std::size_t n_vertices) {
             sorpia::Mesh mesh = faces_of(faces);
             py::gil_scoped_release release;
             return sorpia::Topology(std::move(mesh), n_vertices);
           }),
           "faces"_a.noconvert(), "n_vertices"_a)
      .def(py::init([](const Faces& face_vertex_counts, const Faces& face_vertex_indices, std::size_t n_vertices) {
             sorpia::Mesh mesh = faces_of(face_vertex_counts, face_vertex_indices);
             py::gil_scoped_release release;
             return sorpia::Topology(std::move(mesh), n_vertices);
           }),
           "face_vertex_counts"_a.noconvert(), "face_vertex_indices"_a.noconvert(), "n_vertices"_a)
      .def_property_readonly("n_vertices", &sorpia::Topology::n_vertices)
      .def_property_readonly("n_faces", &sorpia::Topology::n_faces)
      .def_property_readonly("n_edges", &sorpia::Topology::n_edges)
      .def_property_readonly("n_boundary_edges", &sorpia::Topology::n_boundary_edges)
      .def_property_readonly("n_unreferenced", &sorpia::Topology::n_unreferenced)
      .def_property_readonly("ring_offsets", [](const sorpia::Topology& t) { return to_numpy(t.ring_offsets(), 0); })
      .def_property_readonly("ring_neighbors",
                             [](const sorpia::Topology& t) { return to_numpy(t.ring_neighbors(), 0); })
      .def_property_readonly("face_counts", [](const sorpia::Topology& t) { return to_numpy(t.face_counts(), 0); })
      .def_property_readonly("face_offsets", [](const sorpia::Topology& t) { return to_numpy(t.face_offsets(), 0); })
      .def_property_readonly("face_indices", [](const sorpia::Topology& t) { return to_numpy(t.face_indices(), 0); })
      .def_property_readonly("all_triangles", &sorpia::Topology::all_triangles)
      .def_property_readonly("all_quads", &sorpia::Topology::all_quads)
      .def_property_readonly("vertex_face_offsets",
                             [](const sorpia::Topology& t) { return to_numpy(t.vertex_face_offsets(), 0); })
      .def_property_readonly("vertex_faces", [](const sorpia::Topology& t) { return to_numpy(t.vertex_faces(), 0); })
      .def_property_readonly("face_ring_offsets",
                             [](const sorpia::Topology& t) { return to_numpy(t.face_ring_offsets(), 0); })
      .def_property_readonly("face_ring_neighbors",
                             [](const sorpia::Topology& t) { return to_numpy(t.face_ring_neighbors(), 0); })
      .def_property_readonly("is_boundary", [](const sorpia::Topology& t) {
        py::array_t<bool> out(static_cast<py::ssize_t>(t.n_vertices()));
        auto* p = out.mutable_data();
        for (std::size_t i = 0; i < t.n_vertices(); ++i) p[i] = t.is_boundary(i);
        return out;
      });

  // B as CSR arrays (data, indices, indptr), built by `build` with the GIL released.
  const auto csr_of = [](auto build) {
    sorpia::CsrMatrix mat;
    {
      py::gil_scoped_release release;
      mat = build();
    }
    return csr_tuple(std::move(mat));
  };
  m.def(
      "limit_matrix",
      [csr_of](const sorpia::Topology& topology, const sorpia::Rules& rules) {
        return csr_of([&] { return sorpia::limit_matrix(topology, rules); });
      },
      "topology"_a, "rules"_a, "Limit matrix B as CSR arrays (data, indices, indptr).");
  m.def(
      "limit_points",
      [](const sorpia::Topology& topology, const Vertices& vertices, const sorpia::Rules& rules) {
        if (vertices.ndim() != 2 || vertices.shape(1) < 1)
          throw sorpia::ParameterError("vertices must have shape (n, k), k >= 1");
        check_rows(vertices, topology.n_vertices(), "vertices", "the topology");
        const auto k = static_cast<std::size_t>(vertices.shape(1));
        Vertices out({vertices.shape(0), vertices.shape(1)});
        double* dst = out.mutable_data();
        const double* src = vertices.data();
        {
          py::gil_scoped_release release;
          sorpia::limit_points(topology, src, rules, dst, k);
        }
        return out;
      },
      "topology"_a, "vertices"_a.noconvert(), "rules"_a, "Limit positions B V of (n, k) data, (n, k).");

  m.def("icosphere", [](int level) { return mesh_tuple(sorpia::icosphere(level)); }, "level"_a);
  m.def("torus", [](int nu, int nv) { return mesh_tuple(sorpia::torus(nu, nv)); }, "nu"_a, "nv"_a);
  m.def("grid", [](int nu, int nv) { return mesh_tuple(sorpia::grid(nu, nv)); }, "nu"_a, "nv"_a);
  m.def("pole", [](int n) { return mesh_tuple(sorpia::pole(n)); }, "n"_a);
  m.def("irregular", [](int n, std::uint32_t seed) { return mesh_tuple(sorpia::irregular(n, seed)); }, "n_vertices"_a,
        "seed"_a = 1);
  m.def("quad_torus", [](int nu, int nv) { return mesh_tuple(sorpia::quad_torus(nu, nv)); }, "nu"_a, "nv"_a);
  m.def("quad_grid", [](int nu, int nv) { return mesh_tuple(sorpia::quad_grid(nu, nv)); }, "nu"_a, "nv"_a);
  m.def("quad_irregular", [](int n, std::uint32_t seed) { return mesh_tuple(sorpia::quad_irregular(n, seed)); },
        "n_vertices"_a, "seed"_a = 1);
  m.def("polygon_torus",
        [](int nu, int nv, std::uint32_t seed) { return mesh_tuple(sorpia::polygon_torus(nu, nv, seed)); }, "nu"_a,
        "nv"_a, "seed"_a = 1);
}

}  // namespace sorpia_py
