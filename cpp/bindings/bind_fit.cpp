// Bindings of the fitting layer: the fairness matrix, uniform refinement
// with its matrix R, and the fair solve. Conversion and error translation only.
#include <optional>

#include <pybind11/stl.h>

#include <chrono>
#include <vector>

#include "bindings.hpp"
#include "sorpia/detail/parallel.hpp"
#include "sorpia/fair.hpp"
#include "sorpia/fairness.hpp"
#include "sorpia/refine.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {
using Indices = py::array_t<std::int32_t, py::array::c_style>;

}  // namespace

void bind_fit(py::module_& m) {
  m.def(
      "fairness_matrix",
      [](const sorpia::Topology& topology, const sorpia::Rules& rules, double thin_plate, double membrane,
         int gauss_points, int depth, bool reuse, std::optional<Vertices> reference) {
        if (reference) {
          check_shape(*reference, 3, "reference");
          check_rows(*reference, topology.n_vertices(), "reference", "the surface");
        }
        sorpia::CsrMatrix k;
        {
          LongCall call;
          k = sorpia::fairness_matrix(topology, rules, thin_plate, membrane,
                                     sorpia::FairnessQuadrature{gauss_points, depth, reuse},
                                     reference ? reference->data() : nullptr);
        }
        return csr_tuple(std::move(k));
      },
      "topology"_a, "rules"_a, "thin_plate"_a, "membrane"_a, "gauss_points"_a, "depth"_a, "reuse"_a = true,
      "reference"_a.noconvert() = py::none(),
      "Fairness matrix K (thin-plate and membrane energy) as CSR arrays (data, indices, indptr); reuse=False\n"
      "integrates every face on its own (FairnessQuadrature::reuse); reference: (n, 3) control vertices whose\n"
      "limit surface gives each face its metric (sorpia::fairness_matrix).");
  m.def(
      "refine_uniform",
      [](const sorpia::Topology& topology, const sorpia::Rules& rules, int levels, std::optional<Vertices> vertices,
         bool refinement) {
        if (vertices) {
          check_shape(*vertices, 3, "vertices");
          check_rows(*vertices, topology.n_vertices(), "vertices", "the mesh");
        }
        sorpia::RefinedMesh r;
        {
          LongCall call;
          r = sorpia::refine_uniform(topology, rules, levels, vertices ? vertices->data() : nullptr, refinement);
        }
        py::dict out;
        const auto face_size = r.mesh.face_size;
        out["faces"] = to_numpy(std::move(r.mesh.face_vertex_indices), face_size);
        out["n_vertices"] = r.n_vertices;
        out["tags"] = std::move(r.tags);
        if (refinement) out["refinement"] = csr_tuple(std::move(r.refinement));
        if (vertices) out["vertices"] = to_numpy(std::move(r.vertices), 3);
        out["coarse_face"] = to_numpy(std::move(r.coarse_face), 0);
        return out;
      },
      "topology"_a, "rules"_a, "levels"_a, "vertices"_a.noconvert() = py::none(), "refinement"_a = true,
      "The mesh refined `levels` times by OpenSubdiv's Far (sorpia::refine_uniform): a dict with faces, "
      "n_vertices, tags, refinement (R as CSR arrays (data, indices, indptr); left out with refinement=False), "
      "vertices (R V, with vertices= V) and coarse_face.");
  m.def(
      "check_refinement",
      [](const sorpia::Topology& topology, const sorpia::Rules& rules, int levels) {
        sorpia::check_refinement(topology, rules, levels);
      },
      "topology"_a, "rules"_a, "levels"_a,
      "refine_uniform's checks before any work (sorpia::check_refinement): raises for levels it refuses.");
  m.def("refinement_bytes",
        [](std::size_t n_vertices, std::size_t n_faces, int levels, sorpia::Scheme scheme,
           std::size_t n_face_vertices) {
          return sorpia::refinement_bytes(scheme, n_vertices, n_faces, n_face_vertices, levels);
        },
        "n_vertices"_a, "n_faces"_a, "levels"_a, "scheme"_a, "n_face_vertices"_a = 0);
  m.attr("MAX_REFINEMENT_LEVELS") = sorpia::kMaxRefinementLevels;

  m.def(
      "fair_solve",
      [](const sorpia::Topology& topology, const sorpia::Rules& rules, double thin_plate, double membrane,
         const Indices& targets, const Vertices& positions, const Vertices& start, double tol, int window,
         long long max_iter, int threads, std::optional<sorpia::Tags> energy_tags, int depth,
         std::optional<Vertices> reference) {
        const std::size_t n = topology.n_vertices();
        if (reference) {
          check_shape(*reference, 3, "reference");
          check_rows(*reference, n, "reference", "the fine mesh");
        }
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
        double energy_seconds = 0.0;
        {
          LongCall call;
          // `threads` caps K's assembly and Bfr's evaluation in it too.
          const sorpia::detail::ThreadCap cap(threads);
          // K stays in the core: built here, used by fair_solve, never copied.
          const auto t0 = std::chrono::steady_clock::now();
          sorpia::FairnessQuadrature quadrature;
          quadrature.depth = depth;
          const sorpia::CsrMatrix k = sorpia::fairness_matrix(
              topology, sorpia::Rules{rules.scheme, rules.boundary, energy_tags ? *energy_tags : rules.tags},
              thin_plate, membrane, quadrature, reference ? reference->data() : nullptr,
              /*sorted_columns=*/false);
          energy_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
        out["energy_seconds"] = energy_seconds;
        return out;
      },
      "topology"_a, "rules"_a, "thin_plate"_a, "membrane"_a, "targets"_a.noconvert(), "positions"_a.noconvert(),
      "start"_a.noconvert(), "tol"_a, "window"_a, "max_iter"_a, "threads"_a, "energy_tags"_a = py::none(),
      "depth"_a = sorpia::FairnessQuadrature{}.depth, "reference"_a.noconvert() = py::none(),
      "Least tr(V^T K V) with the limit positions of `targets` at `positions` (sorpia::fair_solve), K the\n"
      "fairness matrix of the topology under `rules` with the given weights (sorpia::fairness_matrix; its tags\n"
      "energy_tags when given, the quadrature's depth, the reference metric when given): a dict, with\n"
      "energy_seconds (K) besides the solve's own.");
}

}  // namespace sorpia_py
