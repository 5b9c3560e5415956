// Bindings of what describes and checks a mesh without solving: its statistics
// and the residual of a fit.
#include <pybind11/stl.h>

#include <algorithm>

#include "bindings.hpp"
#include "sorpia/limit_residual.hpp"
#include "sorpia/mesh_statistics.hpp"
#include "sorpia/sharp_edges.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {

py::dict statistics_dict(sorpia::MeshStatistics&& s) {
  py::dict d;
  d["vertices"] = s.n_vertices;
  d["faces"] = s.n_faces;
  d["edges"] = s.n_edges;
  d["boundary_edges"] = s.n_boundary_edges;
  d["boundary_loops"] = s.n_boundary_loops;
  d["euler_characteristic"] = s.euler_characteristic;
  d["genus"] = s.genus ? py::object(py::int_(*s.genus)) : py::object(py::none());
  d["components"] = s.n_components;
  d["unreferenced_vertices"] = s.n_unreferenced;
  d["valence_min"] = s.valence_min;
  d["valence_max"] = s.valence_max;
  d["interior_valences"] = s.interior_valences;
  d["boundary_valences"] = s.boundary_valences;
  const auto k = static_cast<py::ssize_t>(s.extraordinary.size());
  py::array_t<std::int32_t> vertex(k), valence(k);
  py::array_t<bool> boundary(k);
  auto* pv = vertex.mutable_data();
  auto* pn = valence.mutable_data();
  auto* pb = boundary.mutable_data();
  for (const auto& e : s.extraordinary) *pv++ = e.vertex, *pn++ = e.valence, *pb++ = e.boundary;
  // (vertex, valence, on the boundary), three arrays in increasing vertex order.
  d["extraordinary"] = py::make_tuple(vertex, valence, boundary);
  return d;
}

}  // namespace

void bind_mesh_checks(py::module_& m) {
  m.def(
      "sharp_edges",
      [](const Vertices& vertices, const Faces& face_vertex_counts, const Faces& face_vertex_indices,
         double angle_degrees) {
        check_shape(vertices, 3, "vertices");
        long long corners = 0;
        for (py::ssize_t f = 0; f < face_vertex_counts.size(); ++f)
          corners += std::max(face_vertex_counts.data()[f], 0);
        if (corners != static_cast<long long>(face_vertex_indices.size()))
          throw sorpia::ParameterError("face_vertex_counts add up to " + std::to_string(corners) +
                                       " corners but face_vertex_indices holds " +
                                       std::to_string(face_vertex_indices.size()));
        std::vector<std::int32_t> edges;
        {
          py::gil_scoped_release release;
          edges = sorpia::sharp_edges(vertices.data(), static_cast<std::size_t>(vertices.shape(0)),
                                      face_vertex_counts.data(), static_cast<std::size_t>(face_vertex_counts.size()),
                                      face_vertex_indices.data(), angle_degrees);
        }
        return to_numpy(std::move(edges), 2);
      },
      "vertices"_a.noconvert(), "face_vertex_counts"_a.noconvert(), "face_vertex_indices"_a.noconvert(),
      "angle_degrees"_a, "(k, 2) edges whose faces meet at more than angle_degrees (sorpia::sharp_edges).");
  m.def(
      "regular_valence",
      [](sorpia::Scheme scheme) {
        const sorpia::RegularValence r = sorpia::regular_valence(scheme);
        return py::make_tuple(r.interior, r.boundary);
      },
      "scheme"_a, "(inside, on the boundary): the valences of a regular vertex (sorpia::regular_valence).");
  m.def(
      "mesh_statistics",
      [](const sorpia::Topology& topology, sorpia::Scheme scheme) {
        sorpia::MeshStatistics s;
        {
          py::gil_scoped_release release;
          s = sorpia::mesh_statistics(topology, scheme);
        }
        return statistics_dict(std::move(s));
      },
      "topology"_a, "scheme"_a = sorpia::Scheme::Loop,
      "Statistics of a validated mesh (a dict), from its one-ring; extraordinary vertices as the scheme has them.");
  m.def(
      "face_list_statistics",
      [](const Faces& faces, std::size_t n_vertices) -> py::object {
        const sorpia::Mesh mesh = faces_of(faces);
        std::optional<sorpia::MeshStatistics> s;
        {
          py::gil_scoped_release release;
          s = sorpia::face_list_statistics(mesh, n_vertices);
        }
        if (!s) return py::none();
        return statistics_dict(std::move(*s));
      },
      "faces"_a.noconvert(), "n_vertices"_a,
      "Statistics of a raw triangle list that may fail validation (genus None); None without faces or with an "
      "index out of range.");
  m.def(
      "limit_residual",
      [](const sorpia::Topology& topology, const Vertices& control, const Vertices& target,
         sorpia::Boundary b) {
        check_shape(control, 3, "control");
        check_shape(target, 3, "target");
        check_rows(control, topology.n_vertices(), "control", "the topology");
        check_rows(target, topology.n_vertices(), "target", "the topology");
        py::array_t<double> norms(static_cast<py::ssize_t>(topology.n_vertices()));
        double* r = norms.mutable_data();
        sorpia::LimitResidual res;
        {
          py::gil_scoped_release release;
          res = sorpia::limit_residual(topology, control.data(), target.data(), b, r);
        }
        return py::make_tuple(res.max, res.argmax, norms);
      },
      "topology"_a, "control"_a.noconvert(), "target"_a.noconvert(), "boundary"_a,
      "(max, argmax, norms): r_i = |(B V)_i - V0_i| from OpenSubdiv's limit masks over the one-ring.");
}

}  // namespace sorpia_py
