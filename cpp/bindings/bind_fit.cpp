// Bindings of the fitting layer: the fairness matrix, uniform refinement
// with its matrix R, and fair interpolation's pipeline (sorpia::fair_interpolate). Conversion and error translation only.
#include <optional>

#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "bindings.hpp"
#include "sorpia/fair_interpolation.hpp"
#include "sorpia/interpolator.hpp"
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
      "fair_interpolate",
      [](sorpia::Interpolator& coarse, const Vertices& vertices, const Indices& targets,
         const sorpia::SolveOptions& plain, int levels, double thin_plate, double membrane, double tol, int window,
         long long max_iter, int threads, const std::string& semi_sharp, int depth, bool reference) {
        check_shape(vertices, 3, "vertices");
        check_rows(vertices, coarse.n_vertices(), "vertices", "the mesh");
        if (targets.ndim() != 1) {
          std::string shape;
          for (py::ssize_t d = 0; d < targets.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(targets.shape(d));
          throw sorpia::ParameterError("targets must have shape (k,), got (" + shape + (targets.ndim() == 1 ? ",)" : ")"));
        }
        sorpia::FairInterpolationOptions options;
        options.levels = levels;
        options.thin_plate = thin_plate;
        options.membrane = membrane;
        options.solve.tol = tol;
        options.solve.window = window;
        options.solve.max_iter = max_iter;
        options.solve.threads = threads;
        if (semi_sharp != "sharp" && semi_sharp != "as-tagged")
          throw sorpia::ParameterError("semi_sharp must be 'sharp' or 'as-tagged', got '" + semi_sharp + "'");
        options.semi_sharp = semi_sharp == "sharp" ? sorpia::SemiSharp::Sharp : sorpia::SemiSharp::AsTagged;
        options.depth = depth;
        options.reference_metric = reference;
        options.plain = plain;
        sorpia::FairInterpolationResult r;
        {
          LongCall call;
          r = sorpia::fair_interpolate(coarse, vertices.data(), targets.data(),
                                       static_cast<std::size_t>(targets.shape(0)), options);
        }
        py::dict out;
        out["plain"] = py::cast(std::move(r.plain));
        const auto face_size = r.fine.mesh.face_size;
        out["faces"] = to_numpy(std::move(r.fine.mesh.face_vertex_indices), face_size);
        out["n_vertices"] = r.fine.n_vertices;
        out["tags"] = std::move(r.fine.tags);
        if (!r.fine.refinement.indptr.empty()) out["refinement"] = csr_tuple(std::move(r.fine.refinement));
        sorpia::FairSolution& s = r.solution;
        out["vertices"] = to_numpy(std::move(s.vertices), 3);
        out["energies"] = to_numpy(std::move(s.energies), 0);
        out["energy"] = s.energy;
        out["start_energy"] = s.start_energy;
        out["energy_exponent"] = s.energy_exponent;
        out["iterations"] = s.iterations;
        out["stop_reason"] = s.stop_reason;
        out["max_error"] = s.max_error;
        py::dict seconds;
        seconds["plain"] = r.plain_seconds;
        seconds["refine"] = r.refine_seconds;
        seconds["energy"] = r.energy_seconds;
        seconds["setup"] = s.setup_seconds;
        seconds["solve"] = s.seconds;
        out["seconds"] = seconds;
        return out;
      },
      "interpolator"_a, "vertices"_a.noconvert(), "targets"_a.noconvert(), "plain"_a, "levels"_a, "thin_plate"_a,
      "membrane"_a, "tol"_a, "window"_a, "max_iter"_a, "threads"_a, "semi_sharp"_a, "depth"_a, "reference"_a,
      "Fair interpolation's pipeline (sorpia::fair_interpolate): the plain solve on the Interpolator's mesh, the\n"
      "refinement, K and the fair solve. A dict: plain (InterpolationResult), faces, n_vertices, tags (the fine\n"
      "mesh's), refinement (R as CSR arrays, only where the reference metric built it), vertices, energies,\n"
      "energy, start_energy, energy_exponent (the energies are in units of 2^energy_exponent), iterations,\n"
      "stop_reason, max_error and seconds per phase.");
}

}  // namespace sorpia_py
