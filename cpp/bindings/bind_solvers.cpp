// Bindings of the PIA-family solvers: the compact limit operator with its
// spectral-estimate cache (built once per mesh) and solve().
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "sorpia/solvers.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {

// One mesh's operator and the spectral estimates found so far.
struct OperatorState {
  sorpia::LimitOperator op;
  sorpia::SpectralCache cache;
};

py::dict result_dict(sorpia::SolveResult&& r) {
  py::dict d;
  d["control_vertices"] = to_numpy(std::move(r.control_vertices), 3);
  d["errors"] = to_numpy(std::move(r.errors), 0);
  d["initial_error"] = r.initial_error;
  d["iterations"] = r.iterations;
  d["stop_reason"] = sorpia::stop_reason_name(r.stop_reason);
  d["method"] = sorpia::method_name(r.method);
  d["variant"] = r.variant;
  d["omega"] = r.omega;
  d["rho"] = r.rho;
  d["omega_clamped"] = r.omega_clamped;
  d["sigma"] = r.sigma;
  d["lambda_min"] = r.lambda_min;
  d["alpha"] = r.alpha;
  d["weight"] = r.weight;
  d["products"] = r.products;
  d["estimate_seconds"] = r.estimate_seconds;
  d["solve_seconds"] = r.solve_seconds;
  return d;
}

}  // namespace

void bind_solvers(py::module_& m) {
  py::enum_<sorpia::Method> method(m, "Method", "The PIA-family methods (sorpia::Method).");
  for (sorpia::Method v : sorpia::all_methods) method.value(sorpia::method_name(v), v);
  py::enum_<sorpia::OmegaRule>(m, "OmegaRule", "How 'sor' chooses omega (sorpia::OmegaRule).")
      .value("given", sorpia::OmegaRule::Given)
      .value("young", sorpia::OmegaRule::Young)
      .value("auto", sorpia::OmegaRule::Auto);
  m.def("parse_method", &sorpia::parse_method, "name"_a);
  m.def("method_names", [] {
    std::vector<std::string> names;
    for (sorpia::Method v : sorpia::all_methods) names.emplace_back(sorpia::method_name(v));
    return names;
  });

  // Options cross into C++ once, typed, and are checked by the core's
  // check_options (ParameterError) when constructed.
  py::class_<sorpia::SolveOptions>(m, "SolveOptions")
      .def(py::init([](sorpia::Method method, sorpia::OmegaRule omega_rule, double omega, std::optional<double> sigma,
                       std::optional<double> alpha, std::optional<double> weight, double tol, long long max_iter,
                       int threads) {
             sorpia::SolveOptions o;
             o.method = method;
             o.omega_rule = omega_rule;
             o.omega = omega;
             o.sigma = sigma;
             o.alpha = alpha;
             o.weight = weight;
             o.tol = tol;
             o.max_iter = max_iter;
             o.threads = threads;
             sorpia::check_options(o);
             return o;
           }),
           py::kw_only(), "method"_a, "omega_rule"_a, "omega"_a, "sigma"_a, "alpha"_a, "weight"_a, "tol"_a,
           "max_iter"_a, "threads"_a)
      .def_readonly("method", &sorpia::SolveOptions::method)
      .def_readonly("omega_rule", &sorpia::SolveOptions::omega_rule)
      .def_readonly("tol", &sorpia::SolveOptions::tol)
      .def_readonly("max_iter", &sorpia::SolveOptions::max_iter)
      .def_readonly("threads", &sorpia::SolveOptions::threads);
  m.def(
      "parse_omega",
      [](const std::string& text) {
        sorpia::SolveOptions o;
        sorpia::parse_omega(text, o);
        return py::make_tuple(o.omega_rule, o.omega);
      },
      "text"_a, "(OmegaRule, omega) from 'auto', 'young' or a number.");

  py::class_<OperatorState>(m, "LimitOperator")
      .def(py::init([](const sorpia::Topology& topology, sorpia::Boundary b) {
             py::gil_scoped_release release;
             return OperatorState{sorpia::limit_operator(topology, b), {}};
           }),
           "topology"_a, "boundary"_a)
      .def_property_readonly("n", [](const OperatorState& s) { return s.op.n; })
      .def_property_readonly("offsets", [](const OperatorState& s) { return to_numpy(s.op.offsets, 0); })
      .def_property_readonly("neighbors", [](const OperatorState& s) { return to_numpy(s.op.neighbors, 0); })
      .def_property_readonly("diag", [](const OperatorState& s) { return to_numpy(s.op.diag, 0); })
      .def_property_readonly("weight", [](const OperatorState& s) { return to_numpy(s.op.weight, 0); })
      .def("limit_matrix", [](const OperatorState& s) { return csr_tuple(sorpia::to_csr(s.op)); },
           "B as CSR arrays (data, indices, indptr).")
      .def_property_readonly("symmetrisable", [](const OperatorState& s) { return sorpia::is_symmetrisable(s.op); })
      .def(
          "apply",
          [](const OperatorState& s, const Vertices& x) {
            check_shape(x, 3, "x");
            check_rows(x, s.op.n, "x", "the operator");
            Vertices y({x.shape(0), py::ssize_t{3}});
            sorpia::apply(s.op, x.data(), y.mutable_data());
            return y;
          },
          "x"_a.noconvert(), "B x for (n, 3) x.")
      .def("lambda_min", [](OperatorState& s) { return sorpia::estimate_lambda_min(s.op, s.cache); })
      .def("jacobi_rho", [](OperatorState& s) { return sorpia::estimate_jacobi_rho(s.op, s.cache); })
      .def("hermitian_extremes",
           [](OperatorState& s) {
             // The pair itself: reading s.cache.hermitian_max as a second argument
             // could happen before the estimate fills it (unsequenced).
             const auto [lo, hi] = sorpia::estimate_hermitian_extremes(s.op, s.cache);
             return py::make_tuple(lo, hi);
           })
      .def(
          "solve",
          [](OperatorState& s, const Vertices& v0, sorpia::SolveOptions opt, const py::object& callback) {
            check_shape(v0, 3, "vertices");
            check_rows(v0, s.op.n, "vertices", "the mesh");
            // No callback: the core never leaves C++ during the iteration.
            if (!callback.is_none())
              opt.callback = [callback](int k, double e) {
                py::gil_scoped_acquire acquire;
                return py::bool_(callback(k, e)).cast<bool>();
              };
            sorpia::SolveResult r;
            {
              py::gil_scoped_release release;
              r = sorpia::solve(s.op, v0.data(), opt, &s.cache);
            }
            return result_dict(std::move(r));
          },
          "vertices"_a.noconvert(), "options"_a, "callback"_a,
          "Solve B V = V0 with checked options. Returns a dict of the result fields.");
  m.attr("YOUNG_RHO_CLAMP") = sorpia::young_rho_clamp;
  m.attr("MAX_THREADS") = sorpia::max_threads;
}

}  // namespace sorpia_py
