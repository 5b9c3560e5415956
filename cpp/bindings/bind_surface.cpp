// Bindings of the limit surface (LimitSurface: Bfr evaluation and uniform
// tessellation). Conversion and error translation only.
#include <algorithm>

#include "bindings.hpp"
#include "sorpia/subface_grid.hpp"
#include "sorpia/surface.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {
using FaceIds = py::array_t<std::int32_t, py::array::c_style>;

void check_vertices(const Vertices& a, std::size_t n_vertices) {
  check_shape(a, 3, "vertices");
  check_rows(a, n_vertices, "vertices", "the mesh");
}

// k points of a surface: face_ids (k,) and uv (k, 2).
void check_points(const FaceIds& face_ids, const Vertices& uv) {
  check_shape(uv, 2, "uv");
  if (face_ids.ndim() != 1 || face_ids.shape(0) != uv.shape(0))
    throw sorpia::ParameterError("face_ids must have shape (k,) with k = len(uv) = " + std::to_string(uv.shape(0)));
}

// (vertices (n, 3), faces, face_counts): faces (m, k) with face_counts None
// when every face has k vertices (every tessellation but Catmull-Clark's
// level 0 of a mixed mesh), else the concatenated indices and the counts.
py::tuple tessellation_tuple(sorpia::Mesh&& t) {
  auto vertices = to_numpy(std::move(t.vertices), 3);
  const auto& c = t.face_vertex_counts;
  if (!c.empty() && std::all_of(c.begin(), c.end(), [&](std::int32_t k) { return k == c.front(); }))
    return py::make_tuple(vertices, to_numpy(std::move(t.face_vertex_indices), c.front()), py::none());
  return py::make_tuple(vertices, to_numpy(std::move(t.face_vertex_indices), 0),
                        to_numpy(std::move(t.face_vertex_counts), 0));
}
}  // namespace

void bind_surface(py::module_& m) {
  py::class_<sorpia::LimitSurface>(m, "LimitSurface")
      .def(py::init([](const sorpia::Topology& topology, const Vertices& vertices, sorpia::Scheme scheme,
                       sorpia::Boundary b, const sorpia::Tags& tags) {
             check_vertices(vertices, topology.n_vertices());
             const double* v = vertices.data();
             py::gil_scoped_release release;
             return sorpia::LimitSurface(topology, v, scheme, b, tags);
           }),
           "topology"_a, "vertices"_a.noconvert(), "scheme"_a, "boundary"_a, "tags"_a)
      .def_property_readonly("n_vertices", &sorpia::LimitSurface::n_vertices)
      .def_property_readonly("n_faces", &sorpia::LimitSurface::n_faces)
      .def_property_readonly("scheme", &sorpia::LimitSurface::scheme)
      .def_property_readonly("boundary", &sorpia::LimitSurface::boundary)
      .def("set_vertices",
           [](sorpia::LimitSurface& s, const Vertices& vertices) {
             check_vertices(vertices, s.n_vertices());
             s.set_vertices(vertices.data());
           },
           "vertices"_a.noconvert())
      .def("get_vertices",
           [](const sorpia::LimitSurface& s) {
             Vertices out({static_cast<py::ssize_t>(s.n_vertices()), py::ssize_t{3}});
             s.get_vertices(out.mutable_data());
             return out;
           })
      .def("evaluate",
           [](const sorpia::LimitSurface& s, const FaceIds& face_ids, const Vertices& uv, bool derivatives) {
             check_points(face_ids, uv);
             const auto k = static_cast<std::size_t>(uv.shape(0));
             const std::vector<py::ssize_t> shape{uv.shape(0), py::ssize_t{3}};
             Vertices p(shape);
             double* pp = p.mutable_data();
             const std::int32_t* f = face_ids.data();
             const double* t = uv.data();
             if (!derivatives) {
               {
                 LongCall call;
                 s.evaluate(f, t, k, pp, nullptr, nullptr, nullptr);
               }
               return py::object(p);
             }
             Vertices du(shape), dv(shape), nrm(shape);
             double *a = du.mutable_data(), *b = dv.mutable_data(), *c = nrm.mutable_data();
             {
               LongCall call;
               s.evaluate(f, t, k, pp, a, b, c);
             }
             return py::object(py::make_tuple(p, du, dv, nrm));
           },
           "face_ids"_a.noconvert(), "uv"_a.noconvert(), "derivatives"_a)
      .def("rows",
           [](const sorpia::LimitSurface& s, const FaceIds& face_ids, const Vertices& uv, int derivatives) {
             check_points(face_ids, uv);
             sorpia::SurfaceRows r;
             {
               LongCall call;
               r = s.rows(face_ids.data(), uv.data(), static_cast<std::size_t>(uv.shape(0)), derivatives);
             }
             // The matrices asked for: 1, 3 or 6 (the first of SurfaceRows' order).
             sorpia::CsrMatrix* mats[] = {&r.position, &r.du, &r.dv, &r.duu, &r.duv, &r.dvv};
             py::list out;
             for (int d = 0; d < (derivatives == 0 ? 1 : derivatives == 1 ? 3 : 6); ++d)
               out.append(csr_tuple(std::move(*mats[d])));
             return out;
           },
           "face_ids"_a.noconvert(), "uv"_a.noconvert(), "derivatives"_a)
      .def("tessellate",
           [](sorpia::LimitSurface& s, int level) {
             sorpia::Mesh t;
             {
               LongCall call;
               t = s.tessellate(level);
             }
             return tessellation_tuple(std::move(t));
           },
           "level"_a);

  m.def("tessellation_bytes",
        [](std::size_t n_vertices, std::size_t n_faces, int level, sorpia::Scheme scheme,
           std::size_t n_face_vertices) {
          return sorpia::tessellation_bytes(scheme, n_vertices, n_faces, n_face_vertices, level);
        },
        "n_vertices"_a, "n_faces"_a, "level"_a, "scheme"_a = sorpia::Scheme::Loop, "n_face_vertices"_a = 0);
  m.def("available_memory_bytes", &sorpia::available_memory_bytes);
  m.def("subface_columns", &sorpia::subface_columns, "face_size"_a);
}

}  // namespace sorpia_py
