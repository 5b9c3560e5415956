// Bindings of the fitting layer (the fairness matrix). Conversion and error
// translation only.
#include "bindings.hpp"
#include "sorpia/fairness.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

void bind_fit(py::module_& m) {
  m.def(
      "fairness_matrix",
      [](const sorpia::LimitSurface& surface, double thin_plate, double membrane, int gauss_points, int depth) {
        sorpia::CsrMatrix k;
        {
          LongCall call;
          k = sorpia::fairness_matrix(surface, thin_plate, membrane, sorpia::FairnessQuadrature{gauss_points, depth});
        }
        return csr_tuple(std::move(k));
      },
      "surface"_a, "thin_plate"_a, "membrane"_a, "gauss_points"_a, "depth"_a,
      "Fairness matrix K (thin-plate and membrane energy) as CSR arrays (data, indices, indptr).");
}

}  // namespace sorpia_py
