// sorpia._reference: the reference builds of B (tests/reference) for the
// Python tests, a module built only with SORPIA_BUILD_TESTS. It takes the
// Topology and Rules objects of sorpia._core (imported first, which also
// registers the translation of sorpia's exceptions).
#include "../../cpp/bindings/bindings.hpp"
#include "sorpia/reference.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

PYBIND11_MODULE(_reference, m) {
  m.doc() = "Reference builds of the limit matrix B from OpenSubdiv's Far::Limit(), for sorpia's tests";
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
}
