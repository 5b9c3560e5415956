// Bindings of approximation (cpp/fit footpoints.hpp, normal_matrix.hpp): the
// k-d tree, the footpoints of data points on a limit surface, and the normal
// matrix of the fit and its normal equations (solved by the fitting layer's
// PCG), and approximation's pipeline (approximation.hpp). Conversion and error
// translation only.
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sorpia/approximation.hpp"
#include "sorpia/detail/scaling.hpp"
#include "sorpia/footpoints.hpp"
#include "sorpia/normal_matrix.hpp"

namespace sorpia_py {
using namespace pybind11::literals;

namespace {
using FaceIds = py::array_t<std::int32_t, py::array::c_style>;

py::tuple footpoint_tuple(sorpia::Footpoints&& fp) {
  return py::make_tuple(to_numpy(std::move(fp.face_ids), 0), to_numpy(std::move(fp.uv), 2),
                        to_numpy(std::move(fp.positions), 3), to_numpy(std::move(fp.distances), 0),
                        to_numpy(std::move(fp.normals), 3));
}

using Indices32 = py::array_t<std::int32_t, py::array::c_style>;

// Rows A (k, n_cols) as CSR arrays and per-row weights ((k, 1) or (k, 6), or None), checked and borrowed (the
// arrays must outlive it).
struct NormalInput {
  sorpia::CsrRows rows;
  const double* weights = nullptr;
  int count = 0;

  NormalInput(const Indices32& indptr, const Indices32& indices, const Vertices& data, std::size_t n_cols,
              const py::object& w) {
    if (indptr.ndim() != 1 || indptr.shape(0) < 1 || indices.ndim() != 1 || data.ndim() != 1)
      throw sorpia::ParameterError("normal_matrix: indptr, indices and data must be one-dimensional");
    rows = {static_cast<std::size_t>(indptr.shape(0)) - 1, n_cols, indptr.data(), indices.data(), data.data()};
    const auto nnz = static_cast<std::size_t>(indices.shape(0));
    if (static_cast<std::size_t>(data.shape(0)) != nnz || indptr.data()[0] != 0 ||
        static_cast<std::size_t>(indptr.data()[rows.n_rows]) != nnz)
      throw sorpia::ParameterError("normal_matrix: indptr, indices and data disagree");
    for (std::size_t r = 0; r < rows.n_rows; ++r)
      if (rows.indptr[r + 1] < rows.indptr[r]) throw sorpia::ParameterError("normal_matrix: indptr decreases");
    for (std::size_t p = 0; p < nnz; ++p)
      if (rows.indices[p] < 0 || static_cast<std::size_t>(rows.indices[p]) >= n_cols)
        throw sorpia::ParameterError("normal_matrix: a column index is out of range");
    for (std::size_t r = 0; r < rows.n_rows; ++r)
      for (std::int32_t p = rows.indptr[r] + 1; p < rows.indptr[r + 1]; ++p)
        if (rows.indices[p] <= rows.indices[p - 1])
          throw sorpia::ParameterError("normal_matrix: the columns of row " + std::to_string(r) +
                                       " are not sorted and distinct");
    if (!w.is_none()) {
      weights_ = w.cast<Vertices>();
      if (weights_.ndim() != 2 || static_cast<std::size_t>(weights_.shape(0)) != rows.n_rows)
        throw sorpia::ParameterError("weights must have one row per row of A");
      count = static_cast<int>(weights_.shape(1));
      weights = weights_.data();
    }
  }

 private:
  Vertices weights_;
};

// A record as the Python layer's history holds it (keys in this order).
py::dict record_dict(const sorpia::ApproximationRecord& r, double offset) {
  py::dict d;
  d["iteration"] = r.iteration;
  d["rms"] = r.rms;
  d["max"] = r.max;
  d["surface_rms"] = r.surface_rms;
  d["surface_max"] = r.surface_max;
  d["rms_relative"] = r.rms_relative;
  d["max_relative"] = r.max_relative;
  d["surface_rms_relative"] = r.surface_rms_relative;
  d["surface_max_relative"] = r.surface_max_relative;
  d["robust_scale"] = r.robust_scale;
  d["solver_iterations"] = r.solver_iterations;
  d["seconds"] = r.seconds + offset;
  return d;
}

py::dict timings_dict(const sorpia::ApproximationTimings& t) {
  py::dict d;
  d["footpoints"] = t.footpoints;
  d["rows"] = t.rows;
  d["normal"] = t.normal;
  d["solve"] = t.solve;
  d["report"] = t.report;
  d["total"] = t.total;
  return d;
}

sorpia::FootpointOptions footpoint_options(int grid, int max_steps) {
  sorpia::FootpointOptions o;
  o.grid = grid;
  o.max_steps = max_steps;
  return o;
}
}  // namespace

void bind_approximate(py::module_& m) {
  py::class_<sorpia::PointIndex>(m, "PointIndex")
      .def(py::init([](const Vertices& points) {
             check_shape(points, 3, "points");
             const double* p = points.data();
             const auto n = static_cast<std::size_t>(points.shape(0));
             py::gil_scoped_release release;
             return sorpia::PointIndex(p, n);
           }),
           "points"_a.noconvert())
      .def_property_readonly("size", &sorpia::PointIndex::size)
      .def("nearest",
           [](const sorpia::PointIndex& index, const Vertices& queries) {
             check_shape(queries, 3, "queries");
             const auto k = static_cast<std::size_t>(queries.shape(0));
             py::array_t<std::int64_t> nearest(static_cast<py::ssize_t>(k));
             py::array_t<double> distance(static_cast<py::ssize_t>(k));
             std::int64_t* ni = nearest.mutable_data();
             double* d = distance.mutable_data();
             const double* q = queries.data();
             {
               LongCall call;
               index.nearest(q, k, ni, d);
             }
             return py::make_tuple(nearest, distance);
           },
           "queries"_a.noconvert());

  m.def("closest_points",
        [](const sorpia::LimitSurface& surface, const sorpia::Topology& topology, const Vertices& points, int grid,
           int max_steps) {
          check_shape(points, 3, "points");
          const auto n = static_cast<std::size_t>(points.shape(0));
          const double* p = points.data();
          sorpia::Footpoints fp;
          {
            LongCall call;
            fp = sorpia::closest_points(surface, topology, p, n, footpoint_options(grid, max_steps));
          }
          return footpoint_tuple(std::move(fp));
        },
        "surface"_a, "topology"_a, "points"_a.noconvert(), "grid"_a, "max_steps"_a);

  m.def("normal_matrix",
        [](const Indices32& indptr, const Indices32& indices, const Vertices& data, std::size_t n_cols,
           const py::object& weights) {
          const NormalInput in(indptr, indices, data, n_cols, weights);
          sorpia::NormalMatrix M;
          {
            LongCall call;
            M = sorpia::normal_matrix(in.rows, in.weights, in.count);
          }
          const int nb = M.blocks;
          return py::make_tuple(to_numpy(std::move(M.indptr), 0), to_numpy(std::move(M.indices), 0),
                                to_numpy(std::move(M.values), nb));
        },
        "indptr"_a.noconvert(), "indices"_a.noconvert(), "data"_a.noconvert(), "n_cols"_a, "weights"_a);

  m.def("blend_weights",
        [](const Vertices& points, const Vertices& normals, double tangential, const py::object& row_weights) {
          check_shape(points, 3, "points");
          check_shape(normals, 3, "normals");
          const auto k = static_cast<std::size_t>(points.shape(0));
          if (static_cast<std::size_t>(normals.shape(0)) != k)
            throw sorpia::ParameterError("normals must have one row per point");
          Vertices w;
          if (!row_weights.is_none()) {
            w = row_weights.cast<Vertices>();
            if (w.ndim() != 1 || static_cast<std::size_t>(w.shape(0)) != k)
              throw sorpia::ParameterError("weights must have one entry per point");
          }
          std::vector<double> weights(6 * k), weighted(3 * k);
          sorpia::blend_weights(points.data(), normals.data(), row_weights.is_none() ? nullptr : w.data(), k,
                                tangential, weights.data(), weighted.data());
          return py::make_tuple(to_numpy(std::move(weights), 6), to_numpy(std::move(weighted), 3));
        },
        "points"_a.noconvert(), "normals"_a.noconvert(), "tangential"_a, "weights"_a = py::none(),
        "(W (k, 6), W p (k, 3)) of the tangent-distance blend (sorpia::blend_weights).");

  py::class_<sorpia::NormalEquations>(m, "NormalEquations")
      .def(py::init([](const Indices32& indptr, const Indices32& indices, const Vertices& data, std::size_t n_cols,
                       const py::object& weights, const py::object& fairness_matrix, double fairness,
                       double proximal) {
             const NormalInput in(indptr, indices, data, n_cols, weights);
             sorpia::CsrMatrix k;
             if (!fairness_matrix.is_none()) {
               const auto t = fairness_matrix.cast<py::tuple>();  // (data, indices, indptr), as csr_tuple gives
               k.n_rows = k.n_cols = n_cols;
               k.data = to_vector(t[0].cast<py::array_t<double, py::array::c_style>>());
               k.indices = to_vector(t[1].cast<Indices32>());
               k.indptr = to_vector(t[2].cast<Indices32>());
               if (k.indptr.size() != n_cols + 1 || k.indices.size() != k.data.size() || k.indptr.front() != 0 ||
                   static_cast<std::size_t>(k.indptr.back()) != k.data.size())
                 throw sorpia::ParameterError("NormalEquations: the fairness matrix's arrays disagree with " +
                                              std::to_string(n_cols) + " vertices");
               // Products read x at every column and the preconditioner finds the diagonal by binary search.
               for (std::size_t r = 0; r < n_cols; ++r) {
                 if (k.indptr[r + 1] < k.indptr[r])
                   throw sorpia::ParameterError("NormalEquations: the fairness matrix's indptr decreases");
                 for (std::int32_t p = k.indptr[r]; p < k.indptr[r + 1]; ++p) {
                   const auto up = static_cast<std::size_t>(p);
                   if (k.indices[up] < 0 || static_cast<std::size_t>(k.indices[up]) >= n_cols ||
                       (p > k.indptr[r] && k.indices[up] <= k.indices[up - 1]))
                     throw sorpia::ParameterError("NormalEquations: the fairness matrix's row " + std::to_string(r) +
                                                  " has a column out of range or out of order");
                 }
               }
             }
             LongCall call;
             return sorpia::NormalEquations(sorpia::normal_matrix(in.rows, in.weights, in.count), std::move(k),
                                            fairness, proximal);
           }),
           "indptr"_a.noconvert(), "indices"_a.noconvert(), "data"_a.noconvert(), "n_cols"_a, "weights"_a,
           "fairness_matrix"_a, "fairness"_a, "proximal"_a)
      .def_property_readonly("mean_diagonal", &sorpia::NormalEquations::mean_diagonal)
      .def_property_readonly("mu", &sorpia::NormalEquations::mu)
      .def("apply",
           [](const sorpia::NormalEquations& e, const Vertices& x) {
             check_shape(x, 3, "x");
             check_rows(x, e.n(), "x", "the normal equations");
             std::vector<double> out(3 * e.n());
             e.apply(x.data(), out.data());
             return to_numpy(std::move(out), 3);
           },
           "x"_a.noconvert())
      .def("solve",
           [](const sorpia::NormalEquations& e, const Vertices& rhs, const Vertices& start, double rtol,
              long long max_iter, int threads) {
             check_shape(rhs, 3, "rhs");
             check_rows(rhs, e.n(), "rhs", "the normal equations");
             check_shape(start, 3, "start");
             check_rows(start, e.n(), "start", "the normal equations");
             std::vector<double> x(start.data(), start.data() + 3 * e.n());
             sorpia::PcgResult res;
             {
               LongCall call;
               res = e.solve(rhs.data(), x.data(), rtol, max_iter, threads);
             }
             return py::make_tuple(to_numpy(std::move(x), 3), res.iterations, res.stop_reason);
           },
           "rhs"_a.noconvert(), "start"_a.noconvert(), "rtol"_a, "max_iter"_a, "threads"_a = 0,
           "(N + mu I + c K) X = rhs by the fitting layer's PCG from `start` (sorpia::NormalEquations::solve):\n"
           "(X, iterations, stop_reason).");

  m.def("refine_footpoints",
        [](const sorpia::LimitSurface& surface, const sorpia::Topology& topology, const Vertices& points,
           const FaceIds& face_ids, const Vertices& uv, int max_steps) {
          check_shape(points, 3, "points");
          check_shape(uv, 2, "uv");
          const auto n = static_cast<std::size_t>(points.shape(0));
          if (face_ids.ndim() != 1 || static_cast<std::size_t>(face_ids.shape(0)) != n ||
              static_cast<std::size_t>(uv.shape(0)) != n)
            throw sorpia::ParameterError("face_ids and uv must have one row per point (" + std::to_string(n) + ")");
          sorpia::Footpoints fp;
          fp.face_ids = to_vector(face_ids);
          fp.uv = to_vector(uv);
          const double* p = points.data();
          {
            LongCall call;
            sorpia::refine_footpoints(surface, topology, p, n, footpoint_options(0, max_steps), fp);
          }
          return footpoint_tuple(std::move(fp));
        },
        "surface"_a, "topology"_a, "points"_a.noconvert(), "face_ids"_a.noconvert(), "uv"_a.noconvert(),
        "max_steps"_a);

  m.def(
      "scale_exponent",
      [](const py::args& arrays) {
        double largest = 0.0;
        for (const auto& a : arrays) {
          const auto v = a.cast<py::array_t<double, py::array::c_style>>();
          largest = sorpia::detail::largest_magnitude(v.data(), static_cast<std::size_t>(v.size()), largest);
        }
        return sorpia::detail::scale_exponent(largest);
      },
      "The exponent e of the core's exact scaling (sorpia/detail/scaling.hpp) for data whose largest magnitude\n"
      "is that of the arrays given: 0 within 2^+-200.");

  m.def("rms_levelled", &sorpia::rms_levelled, "bests"_a, "tol"_a, "window"_a,
        "approximation's stop test on the lowest RMS after each iteration (sorpia::rms_levelled).");

  m.def(
      "approximate",
      [](sorpia::LimitSurface& surface, const Vertices& points, const py::object& weights, int iterations, double tol,
         double fairness, double tangential, const std::string& method, double solver_tol, long long solver_max_iter,
         int grid, int newton_steps, int report_level, const py::object& callback, double seconds_before,
         const std::string& robust, double robust_quantile, double robust_c) {
        check_shape(points, 3, "points");
        const auto k = static_cast<std::size_t>(points.shape(0));
        Vertices w;
        if (!weights.is_none()) {
          w = weights.cast<Vertices>();
          if (w.ndim() != 1 || static_cast<std::size_t>(w.shape(0)) != k)
            throw sorpia::ParameterError("weights must have one entry per point");
        }
        sorpia::ApproximationOptions o;
        o.iterations = iterations;
        o.tol = tol;
        o.fairness = fairness;
        o.tangential = tangential;
        if (method != "cg" && method != "lspia")
          throw sorpia::ParameterError("method = '" + method + "' must be one of cg, lspia");
        o.update = method == "cg" ? sorpia::ApproximationUpdate::CG : sorpia::ApproximationUpdate::LSPIA;
        o.solver_tol = solver_tol;
        o.solver_max_iter = solver_max_iter;
        o.footpoints = footpoint_options(grid, newton_steps);
        o.report_level = report_level;
        o.robust.loss = sorpia::robust_loss(robust);
        o.robust.quantile = robust_quantile;
        o.robust.c = robust_c;
        sorpia::ApproximationProgress progress;
        if (!callback.is_none())
          progress = [&callback, seconds_before](const sorpia::ApproximationRecord& r) {
            py::gil_scoped_acquire gil;
            callback(record_dict(r, seconds_before));
          };
        sorpia::ApproximationResult r;
        {
          LongCall call;
          r = sorpia::approximate(surface, points.data(), k, weights.is_none() ? nullptr : w.data(), o, progress);
        }
        py::list history;
        for (const auto& rec : r.history) history.append(record_dict(rec, seconds_before));
        py::dict out;
        out["control_vertices"] = to_numpy(std::move(r.control_vertices), 3);
        out["face_ids"] = to_numpy(std::move(r.footpoints.face_ids), 0);
        out["uv"] = to_numpy(std::move(r.footpoints.uv), 2);
        out["distances"] = to_numpy(std::move(r.footpoints.distances), 0);
        out["iterations"] = r.iterations;
        out["stop_reason"] = r.stop_reason;
        out["best_iteration"] = r.best_iteration;
        out["diagonal"] = r.diagonal;
        out["robust_scale"] = r.robust_scale;
        out["robust_outliers"] = r.robust_outliers;
        out["history"] = history;
        py::dict timings = timings_dict(r.seconds);
        timings["cpu"] = timings_dict(r.cpu_seconds);
        out["timings"] = timings;
        return out;
      },
      "surface"_a, "points"_a.noconvert(), "weights"_a, "iterations"_a, "tol"_a, "fairness"_a, "tangential"_a,
      "method"_a, "solver_tol"_a, "solver_max_iter"_a, "grid"_a, "newton_steps"_a, "report_level"_a, "callback"_a,
      "seconds_before"_a = 0.0, "robust"_a = sorpia::robust_loss_name(sorpia::RobustOptions{}.loss),
      "robust_quantile"_a = sorpia::RobustOptions{}.quantile, "robust_c"_a = sorpia::RobustOptions{}.c,
      "Approximation's pipeline (sorpia::approximate) from the surface's control vertices: a dict with\n"
      "control_vertices, face_ids, uv, distances, iterations, stop_reason, best_iteration, diagonal, robust_scale,\n"
      "robust_outliers, history\n"
      "(records as dicts, seconds counted from seconds_before) and timings; callback(record) after each record.");
}

}  // namespace sorpia_py
