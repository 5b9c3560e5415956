// Binding of sorpia::repair.
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sorpia/repair.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {

// The report as plain Python lists and ints (JSON-able), one key per kind of change.
py::dict report_dict(const sorpia::RepairReport& r) {
  py::dict d;
  d["degenerate_faces"] = py::cast(r.degenerate_faces);
  d["collapsed_faces"] = py::cast(r.collapsed_faces);
  d["duplicate_faces"] = py::cast(r.duplicate_faces);
  d["reversed_duplicate_faces"] = py::cast(r.reversed_duplicate_faces);
  d["nonmanifold_edges"] = py::cast(r.nonmanifold_edges);
  d["sheet_vertices"] = py::cast(r.sheet_vertices);
  d["sheet_copies"] = py::cast(r.sheet_copies);
  d["bowtie_vertices"] = py::cast(r.bowtie_vertices);
  d["bowtie_copies"] = py::cast(r.bowtie_copies);
  d["cut_nonmanifold_edges"] = py::cast(r.cut_nonmanifold_edges);
  d["cut_edges"] = py::cast(r.cut_edges);
  d["cut_vertices"] = py::cast(r.cut_vertices);
  d["cut_copies"] = py::cast(r.cut_copies);
  d["flipped_faces"] = py::cast(r.flipped_faces);
  return d;
}

// nonmanifold="sharp"'s split as Python lists (JSON-able).
py::dict split_dict(const sorpia::NonmanifoldSplit& s) {
  py::dict d;
  d["nonmanifold_edges"] = py::cast(s.nonmanifold_edges);
  d["nonmanifold_vertices"] = py::cast(s.nonmanifold_vertices);
  d["corners"] = py::cast(s.corners);
  d["single_face_sheets"] = py::cast(s.single_face_sheets);
  d["sharp_edges"] = py::cast(s.sharp_edges);
  return d;
}

}  // namespace

void bind_repair(py::module_& m) {
  m.def(
      "repair",
      [](const Faces& faces, std::size_t n_vertices) -> py::object {
        const sorpia::Mesh mesh = faces_of(faces);
        sorpia::RepairResult r;
        {
          py::gil_scoped_release release;
          r = sorpia::repair(mesh, n_vertices);
        }
        if (r.report.empty()) return py::none();
        py::dict report = report_dict(r.report);
        return py::make_tuple(to_numpy(std::move(r.faces.face_vertex_indices), 3), to_numpy(std::move(r.vertex_map), 0),
                              to_numpy(std::move(r.face_map), 0), report);
      },
      "faces"_a.noconvert(), "n_vertices"_a,
      "sorpia::repair: None for a valid mesh, else (faces, vertex_map, face_map, report dict).");
  m.def(
      "repair_polygons",
      [](const Faces& counts, const Faces& indices, std::size_t n_vertices) -> py::object {
        const sorpia::Mesh mesh = faces_of(counts, indices);
        sorpia::RepairResult r;
        {
          py::gil_scoped_release release;
          r = sorpia::repair(mesh, n_vertices);
        }
        if (r.report.empty()) return py::none();
        py::dict report = report_dict(r.report);
        return py::make_tuple(to_numpy(std::move(r.faces.face_vertex_counts), 0),
                              to_numpy(std::move(r.faces.face_vertex_indices), 0),
                              to_numpy(std::move(r.vertex_map), 0), to_numpy(std::move(r.face_map), 0), report);
      },
      "face_vertex_counts"_a.noconvert(), "face_vertex_indices"_a.noconvert(), "n_vertices"_a,
      "sorpia::repair of polygons: None for a valid mesh, else (face_vertex_counts, face_vertex_indices, "
      "vertex_map, face_map, report dict).");
  m.def(
      "split_nonmanifold",
      [](const Faces& faces, std::size_t n_vertices) -> py::object {
        const sorpia::Mesh mesh = faces_of(faces);
        sorpia::NonmanifoldSplit s;
        {
          py::gil_scoped_release release;
          s = sorpia::split_nonmanifold(mesh, n_vertices);
        }
        if (s.empty()) return py::none();
        py::dict report = split_dict(s);
        return py::make_tuple(to_numpy(std::move(s.faces.face_vertex_indices), 3), to_numpy(std::move(s.vertex_map), 0),
                              report);
      },
      "faces"_a.noconvert(), "n_vertices"_a,
      "sorpia::split_nonmanifold: None for a manifold mesh, else (faces, vertex_map, report dict).");
  m.def(
      "split_nonmanifold_polygons",
      [](const Faces& counts, const Faces& indices, std::size_t n_vertices) -> py::object {
        const sorpia::Mesh mesh = faces_of(counts, indices);
        sorpia::NonmanifoldSplit s;
        {
          py::gil_scoped_release release;
          s = sorpia::split_nonmanifold(mesh, n_vertices);
        }
        if (s.empty()) return py::none();
        py::dict report = split_dict(s);
        return py::make_tuple(to_numpy(std::move(s.faces.face_vertex_counts), 0),
                              to_numpy(std::move(s.faces.face_vertex_indices), 0),
                              to_numpy(std::move(s.vertex_map), 0), report);
      },
      "face_vertex_counts"_a.noconvert(), "face_vertex_indices"_a.noconvert(), "n_vertices"_a,
      "sorpia::split_nonmanifold of polygons: None for a manifold mesh, else (face_vertex_counts, "
      "face_vertex_indices, vertex_map, report dict).");
}

}  // namespace sorpia_py
