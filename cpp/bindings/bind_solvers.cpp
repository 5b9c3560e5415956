// Bindings of the PIA-family solvers: the options, the result type and
// sorpia::Interpolator (one mesh, its rules and B: solve and update).
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "sorpia/interpolator.hpp"
#include "sorpia/solvers.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {

// An (n, k) array's k, checked: two dimensions, at least one column.
std::size_t columns_of(const py::array& a, const char* name) {
  if (a.ndim() != 2 || a.shape(1) < 1)
    throw sorpia::ParameterError(std::string(name) + " must have shape (n, k), k >= 1");
  return static_cast<std::size_t>(a.shape(1));
}

// A double that means "not used by this method" when NaN, as Python's None.
py::object optional_float(double x) { return std::isnan(x) ? py::object(py::none()) : py::object(py::float_(x)); }

// A (rows, cols) numpy view of a result's vector, kept alive by the result;
// read-only when `read_only`.
py::array view(const std::vector<double>& v, py::ssize_t cols, const py::object& owner, bool read_only = false) {
  py::array a = py::array_t<double>(numpy_shape(v, cols), v.data(), owner);
  if (read_only) a.attr("setflags")(py::arg("write") = false);
  return a;
}

// What the local updates call their results (SolveResult::variant): their
// vertices are read-only, since the next update from them relies on the
// residual the Interpolator keeps for them.
constexpr const char* kLocalVariant = "local";  // LocalSolver::update's variant

const char* const kResultDoc = R"doc(What a solve returns (sorpia.interpolate, Interpolator.solve).

``report()`` gives every attribute but control_vertices as a JSON-ready dict
(arrays as lists), as every sorpia result's report() does. ``errors`` is the
deprecated name of ``history`` (DeprecationWarning), for one release.

Attributes
----------
control_vertices : (n, k) float64
    V, in the input vertex order; B V = V0 to the tolerance reached. k = 3
    for vertices, the data's columns otherwise. Read-only in the result of
    an update (Interpolator.update), whose residual the Interpolator keeps
    for the next update.
iterations : int
    Iterations done (sweeps for "gs"/"sor", outer steps for "hss"/"whss"),
    counted from the start: 0 when a warm start already met tol. An update
    (Interpolator.update): 1 when it relaxed any vertex, else 0.
converged : bool
    history[-1] < tol, or E_k at the rounding floor (E_k <= 64 eps max_i ||v_i^0||),
    below which no method can go: a tol of 1e-300 ends there, converged.
history : (iterations + 1,) float64
    history[k] = E_k / E_0, E_0 = max_i ||v_i^0 - (B V0)_i|| the error of the
    cold start V = V0 whatever the start, so history[0] = 1 from a cold start
    and E(start) / E_0 from a warm one (`initial`, an update); a single 0.0
    when E_0 = 0: V0 already interpolates and is the result. An update:
    [E(previous) / E_0, E(result) / E_0] with E_0 of the new targets, E over
    the whole mesh.
method : str
omega : float or None
    "sor"/"gs": the omega used (1.0 for "gs"); None for other methods.
seconds : float
    Wall time of the whole call, every phase in `timings` included
    (timings["total"]).
stop_reason : {"converged", "max_iter", "diverged", "callback", "singular", "stalled", "slow"}
    "diverged": E_k rose above 10 times (the Krylov methods: 1e4 times) its
    lowest value before, or was not finite; control_vertices are then the
    iterate of the lowest E_k (`returned_iteration`). "singular": "cgls"
    ("auto"'s last resort) solved the least-squares problem, E_k / E_0 still
    above tol: B is singular and the targets have a part outside its range,
    control_vertices are the least-squares solution of least norm, and
    `worst_vertices` says where the targets are missed. "stalled": "gmres"
    made no progress over a whole cycle (B singular, or numerically so). "slow" (in `attempts` only): "auto"
    stopped "sor", whose rate would not reach tol by max_iter.
initial_error : float
    E_0, absolute.
variant : str
    The algorithm that made control_vertices: the method's name, "bicgstab"
    for "cg" on a mesh with boundary, and for "auto" the method it ended
    with ("sor", "gmres" or "cgls").
attempts : list of dict
    Every method run, in order, each {"method", "variant", "iterations",
    "stop_reason", "final_error" (its last E_k / E_0), "products",
    "seconds"}: one for an explicit method; for "auto" its "sor" run and,
    where that stopped short, "gmres" and "cgls". errors and iterations are
    those of the last.
returned_iteration : int
    The iteration whose iterate control_vertices holds: `iterations`, or
    after a divergence the one of the lowest E_k.
recommended : str or None
    Not converged: the method that would work here ("gmres" after a method
    that diverged or stopped at max_iter, "cgls" after "gmres" stalled);
    None otherwise.
worst_vertices : (m,) int64
    Not converged: the (at most 10) vertices where ||v_i^0 - (B V)_i|| is
    largest, largest first; empty when converged.
worst_residuals : (m,) float64
    Their residual norms ||v_i^0 - (B V)_i||, absolute.
max_error : float
    The largest miss of the returned control vertices, max_i ||v_i^0 -
    (B V)_i||, absolute: history[returned_iteration] * initial_error.
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
    measure of work comparable across methods (0 for an update).
relaxations : int
    Single-vertex relaxations (eq. 18 at one vertex): iterations * n for
    "sor"/"gs", those of the work list for an update, 0 for other methods.
timings : dict
    Seconds per phase: "topology" (faces validated, one-ring), "operator"
    (B from OpenSubdiv's limit masks), "estimate" (spectral estimates for the
    parameters: 0 when an Interpolator already holds them), "solve", and
    "total", equal to `seconds`.
)doc";

// The public attributes, in the order of the docstring (and of _fields).
const char* const kResultFields[] = {"control_vertices", "iterations",     "converged",       "history",
                                     "method",           "omega",          "seconds",         "stop_reason",
                                     "initial_error",    "variant",        "attempts",        "returned_iteration",
                                     "recommended",      "worst_vertices", "worst_residuals", "max_error",
                                     "rho",              "sigma",          "lambda_min",      "alpha",
                                     "weight",           "products",       "relaxations",     "timings"};

py::dict attempt_dict(const sorpia::Attempt& a) {
  py::dict d;
  d["method"] = sorpia::method_name(a.method);
  d["variant"] = a.variant;
  d["iterations"] = a.iterations;
  d["stop_reason"] = sorpia::stop_reason_name(a.stop_reason);
  d["final_error"] = a.final_error;
  d["products"] = a.products;
  d["seconds"] = a.seconds;
  return d;
}

py::tuple attempt_state(const sorpia::Attempt& a) {
  return py::make_tuple(static_cast<int>(a.method), a.variant, a.iterations, static_cast<int>(a.stop_reason),
                        a.final_error, a.products, a.seconds);
}

sorpia::Attempt attempt_from(const py::tuple& t) {
  sorpia::Attempt a;
  a.method = static_cast<sorpia::Method>(t[0].cast<int>());
  a.variant = t[1].cast<std::string>();
  a.iterations = t[2].cast<int>();
  a.stop_reason = static_cast<sorpia::StopReason>(t[3].cast<int>());
  a.final_error = t[4].cast<double>();
  a.products = t[5].cast<long long>();
  a.seconds = t[6].cast<double>();
  return a;
}

void bind_result(py::module_& m) {
  using R = sorpia::SolveResult;
  py::class_<R> cls(m, "InterpolationResult", kResultDoc);
  cls.def_property_readonly("control_vertices",
                            [](const py::object& self) {
                              const R& r = self.cast<const R&>();
                              return view(r.control_vertices, static_cast<py::ssize_t>(r.columns), self,
                                          r.variant == kLocalVariant);
                            })
      .def_property_readonly("history",
                             [](const py::object& self) { return view(self.cast<const R&>().errors, 0, self); })
      .def_property_readonly("errors",
                             [](const py::object& self) {
                               if (PyErr_WarnEx(PyExc_DeprecationWarning,
                                                "InterpolationResult.errors is deprecated: use history (the same "
                                                "array; the name every sorpia result uses)",
                                                1) != 0)
                                 throw py::error_already_set();
                               return view(self.cast<const R&>().errors, 0, self);
                             })
      .def_property_readonly("max_error",
                             [](const R& r) {
                               if (r.errors.empty()) return 0.0;
                               const auto k = static_cast<std::size_t>(r.returned_iteration);
                               return (k < r.errors.size() ? r.errors[k] : r.errors.back()) * r.initial_error;
                             })
      .def_readonly("iterations", &R::iterations)
      .def_property_readonly("converged", &R::converged)
      .def_property_readonly("method", [](const R& r) { return std::string(sorpia::method_name(r.method)); })
      .def_property_readonly("omega", [](const R& r) { return optional_float(r.omega); })
      .def_readonly("seconds", &R::seconds)
      .def_property_readonly("stop_reason", [](const R& r) { return std::string(sorpia::stop_reason_name(r.stop_reason)); })
      .def_readonly("initial_error", &R::initial_error)
      .def_readonly("variant", &R::variant)
      .def_property_readonly("attempts",
                             [](const R& r) {
                               py::list out;
                               for (const auto& a : r.attempts) out.append(attempt_dict(a));
                               return out;
                             })
      .def_readonly("returned_iteration", &R::returned_iteration)
      .def_property_readonly("recommended",
                             [](const R& r) -> py::object {
                               if (!r.recommended) return py::none();
                               return py::str(sorpia::method_name(*r.recommended));
                             })
      .def_property_readonly("worst_vertices", [](const R& r) { return to_numpy(r.worst_vertices, 0); })
      .def_property_readonly("worst_residuals", [](const R& r) { return to_numpy(r.worst_residuals, 0); })
      .def_property_readonly("rho", [](const R& r) { return optional_float(r.rho); })
      .def_property_readonly("sigma", [](const R& r) { return optional_float(r.sigma); })
      .def_property_readonly("lambda_min", [](const R& r) { return optional_float(r.lambda_min); })
      .def_property_readonly("alpha", [](const R& r) { return optional_float(r.alpha); })
      .def_property_readonly("weight", [](const R& r) { return optional_float(r.weight); })
      .def_readonly("products", &R::products)
      .def_readonly("relaxations", &R::relaxations)
      .def_property_readonly("timings",
                             [](const R& r) {
                               py::dict d;
                               d["topology"] = r.topology_seconds;
                               d["operator"] = r.operator_seconds;
                               d["estimate"] = r.estimate_seconds;
                               d["solve"] = r.solve_seconds;
                               d["total"] = r.seconds;
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
            py::list attempts;
            for (const auto& a : r.attempts) attempts.append(attempt_state(a));
            return py::make_tuple(r.control_vertices, r.errors, r.initial_error, r.iterations,
                                  static_cast<int>(r.stop_reason), static_cast<int>(r.method), r.variant, r.omega,
                                  r.reordered, r.rho, r.omega_clamped, r.sigma, r.lambda_min, r.alpha, r.weight,
                                  r.products, r.estimate_seconds, r.solve_seconds, r.topology_seconds,
                                  r.operator_seconds, r.seconds, r.columns, r.relaxations, attempts,
                                  r.returned_iteration, r.recommended ? static_cast<int>(*r.recommended) : -1,
                                  r.worst_vertices, r.worst_residuals);
          },
          [](const py::tuple& t) {
            if (t.size() != 28) throw std::runtime_error("InterpolationResult: bad pickle state");
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
            r.columns = t[21].cast<std::size_t>();
            r.relaxations = t[22].cast<long long>();
            for (const auto& a : t[23].cast<py::list>()) r.attempts.push_back(attempt_from(a.cast<py::tuple>()));
            r.returned_iteration = t[24].cast<int>();
            const int recommended = t[25].cast<int>();
            if (recommended >= 0) r.recommended = static_cast<sorpia::Method>(recommended);
            r.worst_vertices = t[26].cast<std::vector<std::int64_t>>();
            r.worst_residuals = t[27].cast<std::vector<double>>();
            return r;
          }))
      .def("report",
           [](const py::object& self) {
             // The result as JSON-ready values: arrays as lists, in the order of the docstring.
             py::dict d;
             for (const char* name : kResultFields) {
               if (std::string(name) == "control_vertices") continue;
               const py::object v = self.attr(name);
               d[name] = py::isinstance<py::array>(v) ? v.attr("tolist")() : v;
             }
             return d;
           },
           "Every attribute but control_vertices, JSON-ready (arrays as lists), as every sorpia result's report().")
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

  // sorpia::Interpolator: arrays and errors converted, nothing else.
  using sorpia::Interpolator;
  py::class_<Interpolator>(m, "Interpolator", "One mesh, its rules and B (sorpia::Interpolator).")
      .def(py::init([](const Faces& faces, std::size_t n_vertices, const sorpia::Rules& rules,
                       const std::optional<Faces>& vertex_map) {
             sorpia::Mesh mesh = faces_of(faces);
             std::vector<std::int32_t> map = vertex_map ? to_vector(*vertex_map) : std::vector<std::int32_t>{};
             py::gil_scoped_release release;
             return std::make_unique<Interpolator>(std::move(mesh), n_vertices, rules, std::move(map));
           }),
           "faces"_a.noconvert(), "n_vertices"_a, "rules"_a, py::kw_only(), "vertex_map"_a.noconvert() = py::none(),
           "Triangles, (m, 3); vertex_map: a non-manifold mesh's split (sorpia::Interpolator).")
      .def(py::init([](const Faces& face_vertex_counts, const Faces& face_vertex_indices, std::size_t n_vertices,
                       const sorpia::Rules& rules, const std::optional<Faces>& vertex_map) {
             sorpia::Mesh mesh = faces_of(face_vertex_counts, face_vertex_indices);
             std::vector<std::int32_t> map = vertex_map ? to_vector(*vertex_map) : std::vector<std::int32_t>{};
             py::gil_scoped_release release;
             return std::make_unique<Interpolator>(std::move(mesh), n_vertices, rules, std::move(map));
           }),
           "face_vertex_counts"_a.noconvert(), "face_vertex_indices"_a.noconvert(), "n_vertices"_a, "rules"_a,
           py::kw_only(), "vertex_map"_a.noconvert() = py::none(), "Polygons as counts and indices.")
      .def_property_readonly("topology", &Interpolator::topology, py::return_value_policy::reference_internal)
      .def_property_readonly("rules", &Interpolator::rules, py::return_value_policy::reference_internal)
      .def_property_readonly("n_vertices", &Interpolator::n_vertices)
      .def_property_readonly("build_timings",
                             [](const Interpolator& s) {
                               py::dict d;
                               d["topology"] = s.topology_seconds();
                               d["operator"] = s.operator_seconds();
                               return d;
                             })
      .def_property_readonly("uniform", [](const Interpolator& s) { return s.limit_operator().uniform(); })
      .def_property_readonly("offsets", [](const Interpolator& s) { return to_numpy(s.limit_operator().offsets, 0); })
      .def_property_readonly("neighbors",
                             [](const Interpolator& s) { return to_numpy(s.limit_operator().neighbors, 0); })
      .def_property_readonly("diag", [](const Interpolator& s) { return to_numpy(s.limit_operator().diag, 0); })
      .def_property_readonly("weight", [](const Interpolator& s) { return to_numpy(s.limit_operator().weight, 0); })
      .def("limit_matrix", [](const Interpolator& s) { return csr_tuple(sorpia::to_csr(s.limit_operator())); },
           "B as CSR arrays (data, indices, indptr).")
      .def_property_readonly("symmetrisable",
                             [](const Interpolator& s) { return sorpia::is_symmetrisable(s.limit_operator()); })
      .def_property_readonly(
          "symmetriser", [](const Interpolator& s) { return to_numpy(sorpia::symmetriser(s.limit_operator()), 0); },
          "Gamma^-1 with Gamma^-1 B symmetric on its two-way entries (sorpia::symmetriser), or empty.")
      .def(
          "apply",
          [](const Interpolator& s, const Vertices& x) {
            check_shape(x, 3, "x");
            check_rows(x, s.n_vertices(), "x", "the operator");
            Vertices y({x.shape(0), py::ssize_t{3}});
            sorpia::apply(s.limit_operator(), x.data(), y.mutable_data());
            return y;
          },
          "x"_a.noconvert(), "B x for (n, 3) x.")
      .def("lambda_min",
           [](Interpolator& s) { return sorpia::estimate_lambda_min(s.limit_operator(), s.spectral_cache()); },
           py::call_guard<LongCall>())
      .def("jacobi_rho",
           [](Interpolator& s) { return sorpia::estimate_jacobi_rho(s.limit_operator(), s.spectral_cache()); },
           py::call_guard<LongCall>())
      .def("hermitian_extremes",
           [](Interpolator& s) {
             const auto ends = [&] {
               LongCall call;
               return sorpia::estimate_hermitian_extremes(s.limit_operator(), s.spectral_cache());
             }();
             return py::make_tuple(ends.first, ends.second);
           })
      .def(
          "solve",
          [](Interpolator& s, const Vertices& v0, sorpia::SolveOptions opt, const py::object& callback,
             const std::optional<Vertices>& initial, bool keep_targets) {
            const std::size_t k = columns_of(v0, "vertices");
            check_rows(v0, s.n_vertices(), "vertices", "the mesh");
            if (initial) {
              check_shape(*initial, static_cast<py::ssize_t>(k), "initial");
              check_rows(*initial, s.n_vertices(), "initial", "the mesh");
            }
            // The callback runs with the GIL; what it raises (KeyboardInterrupt too) ends the solve.
            if (!callback.is_none())
              opt.callback = [callback](int k, double e) {
                py::gil_scoped_acquire acquire;
                return py::bool_(callback(k, e)).cast<bool>();
              };
            LongCall call;
            return s.solve(v0.data(), k, initial ? initial->data() : nullptr, opt, keep_targets);
          },
          "vertices"_a.noconvert(), "options"_a, "callback"_a, "initial"_a.noconvert() = py::none(),
          "keep_targets"_a = false,
          "sorpia::Interpolator::solve on (n, k) data with checked options, from `initial` when given. "
          "Returns an InterpolationResult.")
      .def(
          "update",
          [](Interpolator& s, const py::object& previous_obj, bool previous_is_last, const Faces& indices,
             const Vertices& positions, double tol, long long max_iter, bool in_place) {
            sorpia::SolveResult& previous = previous_obj.cast<sorpia::SolveResult&>();
            if (indices.ndim() != 1) throw sorpia::ParameterError("indices must be one-dimensional");
            const std::size_t k = s.targets_columns();
            if (k && (positions.ndim() != 2 || positions.shape(1) != static_cast<py::ssize_t>(k)))
              throw sorpia::ParameterError("positions must have shape (n, " + std::to_string(k) + ")");
            if (positions.ndim() != 2 || positions.shape(0) != indices.shape(0))
              throw sorpia::ParameterError("positions must have one row per index (" +
                                           std::to_string(indices.shape(0)) + ")");
            sorpia::SolveResult fresh;
            bool moved = false;
            {
              LongCall call;
              if (!in_place) {
                fresh.control_vertices = previous.control_vertices;
                fresh.columns = previous.columns;
              }
              moved = s.update(in_place ? previous : fresh, previous_is_last, indices.data(),
                               static_cast<std::size_t>(indices.shape(0)), positions.data(), tol, max_iter);
            }
            return py::make_tuple(in_place ? previous_obj : py::cast(std::move(fresh)), moved);
          },
          "previous"_a, "previous_is_last"_a, "indices"_a.noconvert(), "positions"_a.noconvert(), "tol"_a,
          "max_iter"_a, "in_place"_a,
          "sorpia::Interpolator::update from previous.control_vertices (in place, or on a copy). previous_is_last: "
          "previous is the last update's result, unchanged. Returns (result, whether the targets moved).")
      .def_property_readonly(
          "targets_columns",
          [](const Interpolator& s) {
            py::gil_scoped_release release;  // waits for an update in progress
            return s.targets_columns();
          },
          "k of the kept (n, k) targets; 0 before a solve that kept them.")
      .def_property_readonly(
          "targets",
          [](const Interpolator& s) -> py::object {
            std::vector<double> copy;
            std::size_t k = 0;
            {
              py::gil_scoped_release release;
              copy = s.targets(k);
            }
            if (k == 0) return py::none();
            return to_numpy(std::move(copy), static_cast<py::ssize_t>(k));
          },
          "A copy of the targets later updates move (None before a solve that kept them).");
  m.attr("YOUNG_RHO_CLAMP") = sorpia::young_rho_clamp;
  m.attr("MAX_THREADS") = sorpia::max_threads;
}

}  // namespace sorpia_py
