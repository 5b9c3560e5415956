// sorpia._reference: the reference builds (tests/reference) for the Python
// tests, a module built only with SORPIA_BUILD_TESTS: B from Far's Limit()
// and the one-ring from OpenMesh. It takes the Topology and Rules objects of
// sorpia._core (imported first, which also registers the translation of
// sorpia's exceptions).
#include "../../cpp/bindings/bindings.hpp"
#include "sorpia/reference.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

PYBIND11_MODULE(_reference, m) {
  m.doc() = "Reference builds for sorpia's tests: B from OpenSubdiv's Far::Limit(), the one-ring from OpenMesh";
  py::module_::import("sorpia._core");
  m.def(
      "reference_limit_matrix",
      [](const sorpia::Topology& topology, const sorpia::Rules& rules) {
        sorpia::CsrMatrix b;
        {
          py::gil_scoped_release release;
          b = sorpia::reference_limit_matrix(topology, rules);
        }
        return sorpia_py::csr_tuple(std::move(b));
      },
      "topology"_a, "rules"_a,
      "B from OpenSubdiv's refinement of the whole mesh until every semi-sharp tag has decayed (and, for "
      "Catmull-Clark with a non-quad face, at least once) and Limit() on the last level "
      "(sorpia::reference_limit_matrix), as CSR arrays (data, indices, indptr).");
  m.def(
      "reference_one_ring",
      [](const sorpia_py::Faces& face_vertex_counts, const sorpia_py::Faces& face_vertex_indices,
         std::size_t n_vertices) {
        const sorpia::Mesh faces = sorpia_py::faces_of(face_vertex_counts, face_vertex_indices);
        sorpia::ReferenceOneRing r;
        {
          py::gil_scoped_release release;
          r = sorpia::reference_one_ring(faces, n_vertices);
        }
        using sorpia_py::to_numpy;
        py::dict d;
        d["ring_offsets"] = to_numpy(r.offsets, 0);
        d["ring_neighbors"] = to_numpy(r.neighbors, 0);
        d["is_boundary"] = to_numpy(r.boundary, 0).attr("astype")("bool");
        d["vertex_face_offsets"] = to_numpy(r.face_offsets, 0);
        d["vertex_faces"] = to_numpy(r.faces, 0);
        d["face_ring_offsets"] = to_numpy(r.face_ring_offsets, 0);
        d["face_ring_neighbors"] = to_numpy(r.face_ring, 0);
        d["n_edges"] = r.n_edges;
        d["n_boundary_edges"] = r.n_boundary_edges;
        d["n_unreferenced"] = r.n_unreferenced;
        return d;
      },
      "face_vertex_counts"_a.noconvert(), "face_vertex_indices"_a.noconvert(), "n_vertices"_a,
      "The one-ring of the faces from OpenMesh's half-edge mesh and its circulators (sorpia::reference_one_ring), "
      "as a dict named after Topology's properties.");
}
