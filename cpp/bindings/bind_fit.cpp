// Bindings of the fitting layer: the fairness matrix, uniform refinement
// with its matrix R, and the fair solve. Conversion and error translation only.
#include <optional>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sorpia/fair.hpp"
#include "sorpia/fairness.hpp"
#include "sorpia/refine.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {
using Indices = py::array_t<std::int32_t, py::array::c_style>;
using Doubles = py::array_t<double, py::array::c_style>;

// A square CSR matrix from scipy's (data, indices, indptr), checked for shape
// and index ranges (what the core's loops rely on).
sorpia::CsrMatrix csr_from(const Doubles& data, const Indices& indices, const Indices& indptr, std::size_t n,
                           const char* name) {
  if (data.ndim() != 1 || indices.ndim() != 1 || indptr.ndim() != 1 ||
      static_cast<std::size_t>(indptr.shape(0)) != n + 1 || data.shape(0) != indices.shape(0))
    throw sorpia::ParameterError(std::string(name) + " must be an (n, n) CSR matrix with n = " + std::to_string(n));
  sorpia::CsrMatrix m;
  m.n_rows = m.n_cols = n;
  m.data = to_vector(data);
  m.indices = to_vector(indices);
  m.indptr = to_vector(indptr);
  if (m.indptr.front() != 0 || m.indptr.back() != static_cast<std::int32_t>(m.indices.size()))
    throw sorpia::ParameterError(std::string(name) + ": indptr does not span its entries");
  for (std::size_t i = 0; i < n; ++i) {
    if (m.indptr[i + 1] < m.indptr[i]) throw sorpia::ParameterError(std::string(name) + ": indptr decreases");
    for (std::int32_t p = m.indptr[i]; p < m.indptr[i + 1]; ++p)
      if (m.indices[p] < 0 || static_cast<std::size_t>(m.indices[p]) >= n ||
          (p > m.indptr[i] && m.indices[p] <= m.indices[p - 1]))
        throw sorpia::ParameterError(std::string(name) + ": row " + std::to_string(i) +
                                     " has column indices out of range or not sorted");
  }
  return m;
}
}  // namespace

void bind_fit(py::module_& m) {
  m.def(
      "fairness_matrix",
      [](const sorpia::LimitSurface& surface, double thin_plate, double membrane, int gauss_points, int depth,
         bool reuse, std::optional<Vertices> reference) {
        if (reference) {
          check_shape(*reference, 3, "reference");
          check_rows(*reference, surface.n_vertices(), "reference", "the surface");
        }
        sorpia::CsrMatrix k;
        {
          LongCall call;
          k = sorpia::fairness_matrix(surface, thin_plate, membrane,
                                     sorpia::FairnessQuadrature{gauss_points, depth, reuse},
                                     reference ? reference->data() : nullptr);
        }
        return csr_tuple(std::move(k));
      },
      "surface"_a, "thin_plate"_a, "membrane"_a, "gauss_points"_a, "depth"_a, "reuse"_a = true,
      "reference"_a.noconvert() = py::none(),
      "Fairness matrix K (thin-plate and membrane energy) as CSR arrays (data, indices, indptr); reuse=False\n"
      "integrates every face on its own (FairnessQuadrature::reuse); reference: (n, 3) control vertices whose\n"
      "limit surface gives each face its metric (sorpia::fairness_matrix).");
  m.def(
      "refine_uniform",
      [](const sorpia::Topology& topology, const sorpia::Rules& rules, int levels) {
        sorpia::RefinedMesh r;
        {
          LongCall call;
          r = sorpia::refine_uniform(topology, rules, levels);
        }
        py::dict out;
        const auto face_size = r.mesh.face_size;
        out["faces"] = to_numpy(std::move(r.mesh.face_vertex_indices), face_size);
        out["n_vertices"] = r.n_vertices;
        out["tags"] = std::move(r.tags);
        out["refinement"] = csr_tuple(std::move(r.refinement));
        out["coarse_face"] = to_numpy(std::move(r.coarse_face), 0);
        return out;
      },
      "topology"_a, "rules"_a, "levels"_a,
      "The mesh refined `levels` times by OpenSubdiv's Far (sorpia::refine_uniform): a dict with faces, "
      "n_vertices, tags, refinement (R as CSR arrays (data, indices, indptr)) and coarse_face.");
  m.def("refinement_bytes",
        [](std::size_t n_vertices, std::size_t n_faces, int levels, sorpia::Scheme scheme,
           std::size_t n_face_vertices) {
          return sorpia::refinement_bytes(scheme, n_vertices, n_faces, n_face_vertices, levels);
        },
        "n_vertices"_a, "n_faces"_a, "levels"_a, "scheme"_a, "n_face_vertices"_a = 0);
  m.attr("MAX_REFINEMENT_LEVELS") = sorpia::kMaxRefinementLevels;

  m.def(
      "fair_solve",
      [](const sorpia::Topology& topology, const sorpia::Rules& rules, const Doubles& k_data, const Indices& k_indices,
         const Indices& k_indptr, const Indices& targets, const Vertices& positions, const Vertices& start,
         double tol, int window, long long max_iter, int threads) {
        const std::size_t n = topology.n_vertices();
        const sorpia::CsrMatrix k = csr_from(k_data, k_indices, k_indptr, n, "the fairness matrix");
        if (targets.ndim() != 1) throw sorpia::ParameterError("targets must be one-dimensional");
        check_shape(positions, 3, "positions");
        if (positions.shape(0) != targets.shape(0))
          throw sorpia::ParameterError("positions must have one row per target");
        check_shape(start, 3, "start");
        check_rows(start, n, "start", "the fine mesh");
        sorpia::FairOptions options;
        options.tol = tol;
        options.window = window;
        options.max_iter = max_iter;
        options.threads = threads;
        sorpia::FairSolution s;
        {
          LongCall call;
          s = sorpia::fair_solve(topology, rules, k, targets.data(), static_cast<std::size_t>(targets.shape(0)),
                                 positions.data(), start.data(), options);
        }
        py::dict out;
        out["vertices"] = to_numpy(std::move(s.vertices), 3);
        out["energies"] = to_numpy(std::move(s.energies), 0);
        out["energy"] = s.energy;
        out["start_energy"] = s.start_energy;
        out["iterations"] = s.iterations;
        out["stop_reason"] = s.stop_reason;
        out["max_error"] = s.max_error;
        out["free_vertices"] = s.free_vertices;
        out["seconds"] = s.seconds;
        out["setup_seconds"] = s.setup_seconds;
        return out;
      },
      "topology"_a, "rules"_a, "k_data"_a.noconvert(), "k_indices"_a.noconvert(), "k_indptr"_a.noconvert(),
      "targets"_a.noconvert(), "positions"_a.noconvert(), "start"_a.noconvert(), "tol"_a, "window"_a, "max_iter"_a,
      "threads"_a,
      "Least tr(V^T K V) with the limit positions of `targets` at `positions` (sorpia::fair_solve): a dict.");
}

}  // namespace sorpia_py
