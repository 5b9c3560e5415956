// Bindings of the PIA-family solvers: the compact limit operator with its
// spectral-estimate cache (built once per mesh) and solve().
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <iterator>
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

// A double that means "not used by this method" when NaN, as Python's None.
py::object optional_float(double x) { return std::isnan(x) ? py::object(py::none()) : py::object(py::float_(x)); }

// A (rows, cols) numpy view of a result's vector, kept alive by the result.
py::array view(const std::vector<double>& v, py::ssize_t cols, const py::object& owner) {
  return py::array_t<double>(numpy_shape(v, cols), v.data(), owner);
}

const char* const kResultDoc = R"doc(What a solve returns (sorpia.interpolate, Interpolator.solve).

Attributes
----------
control_vertices : (n, 3) float64
    V, in the input vertex order; B V = V0 to the tolerance reached.
iterations : int
    Iterations done (sweeps for "gs"/"sor", outer steps for "hss"/"whss").
converged : bool
    errors[-1] < tol, or E_k at the rounding floor (E_k <= 64 eps max_i ||v_i^0||),
    below which no method can go: a tol of 1e-300 ends there, converged.
errors : (iterations + 1,) float64
    errors[k] = E_k / E_0, so errors[0] = 1 (a single 0.0 when E_0 = 0:
    V0 already interpolates and nothing is done).
method : str
omega : float or None
    "sor"/"gs": the omega used (1.0 for "gs"); None for other methods.
seconds : float
    Wall time of the whole call, every phase in `timings` included.
stop_reason : {"converged", "max_iter", "diverged", "callback"}
initial_error : float
    E_0, absolute.
variant : str
    The algorithm that ran: the method's name, or "bicgstab" for "cg" on a
    mesh with boundary.
rho : float or None
    omega="young": the estimated spectral radius of I - D^-1 B.
sigma : float or None
    "pia"/"wpia": the step.
lambda_min : float or None
    "wpia": the estimated smallest eigenvalue of B.
alpha : float or None
    "hss"/"whss": the shift.
weight : float or None
    "hss"/"whss": the relaxation weight.
products : int
    Applications of B (or B^T) in the iteration, inner solves included: a
    measure of work comparable across methods.
timings : dict
    Seconds per phase: "topology" (faces validated, one-ring), "operator"
    (B from OpenSubdiv's limit masks), "estimate" (spectral estimates for the
    parameters: 0 when an Interpolator already holds them), "solve".
)doc";

// The public attributes, in the order of the docstring (and of _fields).
const char* const kResultFields[] = {"control_vertices", "iterations", "converged",  "errors", "method",
                                     "omega",            "seconds",    "stop_reason", "initial_error",
                                     "variant",          "rho",        "sigma",       "lambda_min",
                                     "alpha",            "weight",     "products",    "timings"};

void bind_result(py::module_& m) {
  using R = sorpia::SolveResult;
  py::class_<R> cls(m, "InterpolationResult", kResultDoc);
  cls.def_property_readonly("control_vertices",
                            [](const py::object& self) { return view(self.cast<const R&>().control_vertices, 3, self); })
      .def_property_readonly("errors", [](const py::object& self) { return view(self.cast<const R&>().errors, 0, self); })
      .def_readonly("iterations", &R::iterations)
      .def_property_readonly("converged", &R::converged)
      .def_property_readonly("method", [](const R& r) { return std::string(sorpia::method_name(r.method)); })
      .def_property_readonly("omega", [](const R& r) { return optional_float(r.omega); })
      .def_readonly("seconds", &R::seconds)
      .def_property_readonly("stop_reason", [](const R& r) { return std::string(sorpia::stop_reason_name(r.stop_reason)); })
      .def_readonly("initial_error", &R::initial_error)
      .def_readonly("variant", &R::variant)
      .def_property_readonly("rho", [](const R& r) { return optional_float(r.rho); })
      .def_property_readonly("sigma", [](const R& r) { return optional_float(r.sigma); })
      .def_property_readonly("lambda_min", [](const R& r) { return optional_float(r.lambda_min); })
      .def_property_readonly("alpha", [](const R& r) { return optional_float(r.alpha); })
      .def_property_readonly("weight", [](const R& r) { return optional_float(r.weight); })
      .def_readonly("products", &R::products)
      .def_property_readonly("timings",
                             [](const R& r) {
                               py::dict d;
                               d["topology"] = r.topology_seconds;
                               d["operator"] = r.operator_seconds;
                               d["estimate"] = r.estimate_seconds;
                               d["solve"] = r.solve_seconds;
                               return d;
                             })
      .def_readonly("omega_clamped", &R::omega_clamped, "omega='young' met rho >= YOUNG_RHO_CLAMP.")
      .def(
          "_record_build",
          [](R& r, double seconds, double topology_seconds, double operator_seconds) {
            r.seconds = seconds;
            r.topology_seconds = topology_seconds;
            r.operator_seconds = operator_seconds;
          },
          "seconds"_a, "topology_seconds"_a, "operator_seconds"_a,
          "For sorpia's Python layer: the whole call's wall time and the build phases it timed.")
      .def(py::pickle(
          [](const R& r) {
            return py::make_tuple(r.control_vertices, r.errors, r.initial_error, r.iterations,
                                  static_cast<int>(r.stop_reason), static_cast<int>(r.method), r.variant, r.omega,
                                  r.reordered, r.rho, r.omega_clamped, r.sigma, r.lambda_min, r.alpha, r.weight,
                                  r.products, r.estimate_seconds, r.solve_seconds, r.topology_seconds,
                                  r.operator_seconds, r.seconds);
          },
          [](const py::tuple& t) {
            if (t.size() != 21) throw std::runtime_error("InterpolationResult: bad pickle state");
            R r;
            r.control_vertices = t[0].cast<std::vector<double>>();
            r.errors = t[1].cast<std::vector<double>>();
            r.initial_error = t[2].cast<double>();
            r.iterations = t[3].cast<int>();
            r.stop_reason = static_cast<sorpia::StopReason>(t[4].cast<int>());
            r.method = static_cast<sorpia::Method>(t[5].cast<int>());
            r.variant = t[6].cast<std::string>();
            r.omega = t[7].cast<double>();
            r.reordered = t[8].cast<bool>();
            r.rho = t[9].cast<double>();
            r.omega_clamped = t[10].cast<bool>();
            r.sigma = t[11].cast<double>();
            r.lambda_min = t[12].cast<double>();
            r.alpha = t[13].cast<double>();
            r.weight = t[14].cast<double>();
            r.products = t[15].cast<long long>();
            r.estimate_seconds = t[16].cast<double>();
            r.solve_seconds = t[17].cast<double>();
            r.topology_seconds = t[18].cast<double>();
            r.operator_seconds = t[19].cast<double>();
            r.seconds = t[20].cast<double>();
            return r;
          }))
      .def("__repr__", [](const py::object& self) {
        std::string out = "InterpolationResult(";
        for (const char* name : kResultFields) {
          if (name != kResultFields[0]) out += ", ";
          const py::object v = self.attr(name);
          // Arrays by shape: a million control vertices are no repr.
          out += std::string(name) + "=" +
                 (py::isinstance<py::array>(v) ? "<array " + py::str(v.attr("shape")).cast<std::string>() + ">"
                                                : py::repr(v).cast<std::string>());
        }
        return out + ")";
      });
  py::tuple fields(std::size(kResultFields));
  for (std::size_t k = 0; k < std::size(kResultFields); ++k) fields[k] = py::str(kResultFields[k]);
  cls.attr("_fields") = fields;
}

}  // namespace

void bind_solvers(py::module_& m) {
  bind_result(m);
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
      .def(py::init([](const sorpia::Topology& topology, sorpia::Boundary b, const sorpia::Tags& tags,
                       sorpia::Scheme scheme) {
             py::gil_scoped_release release;
             return OperatorState{sorpia::limit_operator(topology, scheme, b, tags), {}};
           }),
           "topology"_a, "boundary"_a, "tags"_a = sorpia::Tags{}, "scheme"_a = sorpia::Scheme::Loop)
      .def_property_readonly("uniform", [](const OperatorState& s) { return s.op.uniform(); })
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
      .def("lambda_min", [](OperatorState& s) { return sorpia::estimate_lambda_min(s.op, s.cache); },
           py::call_guard<LongCall>())
      .def("jacobi_rho", [](OperatorState& s) { return sorpia::estimate_jacobi_rho(s.op, s.cache); },
           py::call_guard<LongCall>())
      .def("hermitian_extremes",
           [](OperatorState& s) {
             // The pair itself: reading s.cache.hermitian_max as a second argument
             // could happen before the estimate fills it (unsequenced).
             std::pair<double, double> ends;
             {
               LongCall call;
               ends = sorpia::estimate_hermitian_extremes(s.op, s.cache);
             }
             return py::make_tuple(ends.first, ends.second);
           })
      .def(
          "solve",
          [](OperatorState& s, const Vertices& v0, sorpia::SolveOptions opt, const py::object& callback) {
            check_shape(v0, 3, "vertices");
            check_rows(v0, s.op.n, "vertices", "the mesh");
            // The callback runs with the GIL; what it raises (KeyboardInterrupt too) ends the solve.
            if (!callback.is_none())
              opt.callback = [callback](int k, double e) {
                py::gil_scoped_acquire acquire;
                return py::bool_(callback(k, e)).cast<bool>();
              };
            sorpia::SolveResult r;
            {
              LongCall call;
              r = sorpia::solve(s.op, v0.data(), opt, &s.cache);
            }
            return r;
          },
          "vertices"_a.noconvert(), "options"_a, "callback"_a,
          "Solve B V = V0 with checked options. Returns an InterpolationResult.");
  m.attr("YOUNG_RHO_CLAMP") = sorpia::young_rho_clamp;
  m.attr("MAX_THREADS") = sorpia::max_threads;
}

}  // namespace sorpia_py
