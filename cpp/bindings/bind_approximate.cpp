// Bindings of approximation (cpp/fit footpoints.hpp, normal_matrix.hpp): the
// k-d tree, the footpoints of data points on a limit surface, and the normal
// matrix of the fit and its normal equations (solved by the fitting layer's
// PCG), and approximation's pipeline (approximation.hpp). Conversion and error
// translation only.
#include <pybind11/stl.h>

#include <array>
#include <memory>
#include <optional>

#include "bindings.hpp"
#include "sorpia/approximation.hpp"
#include "sorpia/detail/scaling.hpp"
#include "sorpia/footpoints.hpp"
#include "sorpia/normal_matrix.hpp"
#include "sorpia/point_chunks.hpp"

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
  d["points"] = r.points;
  d["rms"] = r.rms;
  d["max"] = r.max;
  // The surface-to-data figures of a record where they were not measured (report_each off): None.
  const auto measured = [](double v) -> py::object { return std::isnan(v) ? py::object(py::none()) : py::float_(v); };
  d["surface_rms"] = measured(r.surface_rms);
  d["surface_max"] = measured(r.surface_max);
  d["rms_relative"] = r.rms_relative;
  d["max_relative"] = r.max_relative;
  d["surface_rms_relative"] = measured(r.surface_rms_relative);
  d["surface_max_relative"] = measured(r.surface_max_relative);
  d["robust_loss"] = r.robust_loss;
  d["robust_loss_relative"] = r.robust_loss_relative;
  d["inlier_rms"] = r.inlier_rms;
  d["inlier_rms_relative"] = r.inlier_rms_relative;
  d["robust_cut"] = r.robust_cut;
  d["robust_scale"] = r.robust_scale;
  d["move_max_relative"] = r.move_max_relative;
  d["move_rms_relative"] = r.move_rms_relative;
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

// The Python forms of the chunks' sums (the calls and their order: sorpia/point_chunks.hpp): DistanceSums as
// (squares, max, count, changed), NormalSums as (indptr, indices, values, rhs), PointExtent as (count, weighted, lo, hi, largest), PointMoments as (count,
// sum, sum2). A backend written in Python may return one of them or a list of them, one per chunk: the list is
// added in its order (sorpia::add), as the core's backends add their chunks'.
// k points' weights (None: null), converted into `holder`, which must outlive the pointer.
const double* point_weights(const py::object& weights, std::size_t k, Vertices& holder) {
  if (weights.is_none()) return nullptr;
  holder = weights.cast<Vertices>();
  if (holder.ndim() != 1 || static_cast<std::size_t>(holder.shape(0)) != k)
    throw sorpia::ParameterError("weights must have one entry per point");
  return holder.data();
}

py::tuple distance_tuple(const sorpia::DistanceSums& d) {
  return py::make_tuple(d.squares, d.max, d.count, d.changed);
}

template <class T, class One>
T fold(const py::handle& obj, One one) {
  if (py::isinstance<py::list>(obj)) {
    T total;
    for (const auto& item : obj.cast<py::list>()) add(total, one(item));
    return total;
  }
  return one(obj);
}

sorpia::DistanceSums to_distance_sums(const py::handle& obj) {
  return fold<sorpia::DistanceSums>(obj, [](const py::handle& h) {
    const auto t = h.cast<py::tuple>();
    if (t.size() < 3 || t.size() > 4)
      throw sorpia::ParameterError("distance sums must be (squares, max, count[, changed]), got " +
                                   std::to_string(t.size()) + " items");
    sorpia::DistanceSums d;
    d.squares = t[0].cast<double>();
    d.max = t[1].cast<double>();
    d.count = t[2].cast<std::size_t>();
    d.changed = t.size() > 3 ? t[3].cast<std::size_t>() : 0;
    return d;
  });
}

py::tuple normal_tuple(sorpia::NormalSums&& s) {
  const int nb = s.matrix.blocks;
  return py::make_tuple(to_numpy(std::move(s.matrix.indptr), 0), to_numpy(std::move(s.matrix.indices), 0),
                        to_numpy(std::move(s.matrix.values), nb), to_numpy(std::move(s.rhs), 3));
}

sorpia::NormalSums to_normal_sums(const py::handle& obj) {
  return fold<sorpia::NormalSums>(obj, [](const py::handle& h) {
    const auto t = h.cast<py::tuple>();
    if (t.size() != 4) throw sorpia::ParameterError("normal sums must be (indptr, indices, values, rhs)");
    sorpia::NormalSums s;
    const auto indptr = t[0].cast<py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>>();
    const auto indices = t[1].cast<py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>>();
    const auto values = t[2].cast<py::array_t<double, py::array::c_style | py::array::forcecast>>();
    const auto rhs = t[3].cast<py::array_t<double, py::array::c_style | py::array::forcecast>>();
    if (indptr.ndim() != 1 || indptr.shape(0) < 1 || indices.ndim() != 1)
      throw sorpia::ParameterError("normal sums: indptr and indices must be one-dimensional");
    const auto n = static_cast<std::size_t>(indptr.shape(0)) - 1;
    const auto nnz = static_cast<std::size_t>(indices.shape(0));
    const auto nb = values.ndim() == 2 ? static_cast<std::size_t>(values.shape(1)) : 1;
    if ((nb != 1 && nb != 6) || static_cast<std::size_t>(values.size()) != nnz * nb ||
        static_cast<std::size_t>(rhs.size()) != 3 * n || indptr.data()[0] != 0 ||
        static_cast<std::size_t>(indptr.data()[n]) != nnz)
      throw sorpia::ParameterError("normal sums: indptr, indices, values ((nnz, 1 or 6)) and rhs ((n, 3)) disagree");
    for (std::size_t r = 0; r < n; ++r) {
      if (indptr.data()[r + 1] < indptr.data()[r])
        throw sorpia::ParameterError("normal sums: indptr decreases");
      for (auto p = indptr.data()[r]; p < indptr.data()[r + 1]; ++p) {
        const auto q = static_cast<std::size_t>(p);
        if (indices.data()[q] < 0 || static_cast<std::size_t>(indices.data()[q]) >= n ||
            (p > indptr.data()[r] && indices.data()[q] <= indices.data()[q - 1]))
          throw sorpia::ParameterError("normal sums: row " + std::to_string(r) +
                                       " has a column out of range or out of order");
      }
    }
    s.matrix.n = n;
    s.matrix.blocks = static_cast<int>(nb);
    s.matrix.indptr.assign(indptr.data(), indptr.data() + n + 1);
    s.matrix.indices.assign(indices.data(), indices.data() + nnz);
    s.matrix.values.assign(values.data(), values.data() + nnz * nb);
    s.rhs.assign(rhs.data(), rhs.data() + 3 * n);
    return s;
  });
}

py::tuple extent_tuple(const sorpia::PointExtent& e) {
  return py::make_tuple(e.count, e.weighted, py::make_tuple(e.lo[0], e.lo[1], e.lo[2]),
                        py::make_tuple(e.hi[0], e.hi[1], e.hi[2]), e.largest);
}

sorpia::PointExtent to_extent(const py::handle& obj) {
  return fold<sorpia::PointExtent>(obj, [](const py::handle& h) {
    const auto t = h.cast<py::tuple>();
    if (t.size() != 5) throw sorpia::ParameterError("an extent must be (count, weighted, lo, hi, largest)");
    sorpia::PointExtent e;
    e.count = t[0].cast<std::size_t>();
    e.weighted = t[1].cast<std::size_t>();
    const auto lo = t[2].cast<std::vector<double>>(), hi = t[3].cast<std::vector<double>>();
    if (lo.size() != 3 || hi.size() != 3) throw sorpia::ParameterError("an extent's lo and hi must have 3 items");
    for (int c = 0; c < 3; ++c) {
      e.lo[c] = lo[static_cast<std::size_t>(c)];
      e.hi[c] = hi[static_cast<std::size_t>(c)];
    }
    e.largest = t[4].cast<double>();
    return e;
  });
}

py::tuple moments_tuple(const sorpia::PointMoments& m) {
  std::vector<double> s(m.sum, m.sum + 3), s2(m.sum2, m.sum2 + 9);
  return py::make_tuple(m.count, to_numpy(std::move(s), 0), to_numpy(std::move(s2), 3));
}

sorpia::PointMoments to_moments(const py::handle& obj) {
  return fold<sorpia::PointMoments>(obj, [](const py::handle& h) {
    const auto t = h.cast<py::tuple>();
    if (t.size() != 3) throw sorpia::ParameterError("moments must be (count, sum (3), sum2 (3, 3))");
    sorpia::PointMoments m;
    m.count = t[0].cast<std::size_t>();
    const auto s = t[1].cast<py::array_t<double, py::array::c_style | py::array::forcecast>>();
    const auto s2 = t[2].cast<py::array_t<double, py::array::c_style | py::array::forcecast>>();
    if (s.size() != 3 || s2.size() != 9) throw sorpia::ParameterError("moments: sum (3) and sum2 (3, 3)");
    std::copy_n(s.data(), 3, m.sum);
    std::copy_n(s2.data(), 9, m.sum2);
    return m;
  });
}

// A distance histogram crosses to Python as (unit, total, mass): plain values a process can send.
py::tuple histogram_tuple(const sorpia::DistanceHistogram& h) {
  return py::make_tuple(h.unit(), h.total(), to_numpy(std::vector<double>(h.mass()), 0));
}

// (unit, total, mass), or a list of them merged in its order.
sorpia::DistanceHistogram to_histogram(const py::handle& obj) {
  const auto one = [](const py::handle& h) {
    const auto t = h.cast<py::tuple>();
    if (t.size() != 3) throw sorpia::ParameterError("a distance histogram must be (unit, total, mass)");
    return sorpia::DistanceHistogram(t[0].cast<double>(), t[1].cast<double>(), t[2].cast<std::vector<double>>());
  };
  if (!py::isinstance<py::list>(obj)) return one(obj);
  const auto items = obj.cast<py::list>();
  if (items.empty()) throw sorpia::ParameterError("a list of distance histograms is empty");
  sorpia::DistanceHistogram total = one(items[0]);
  for (std::size_t i = 1; i < items.size(); ++i) total.merge(one(items[i]));
  return total;
}

// A robust fit's settings cross to Python as (loss name, quantile, c).
py::tuple robust_tuple(const sorpia::RobustOptions& o) {
  return py::make_tuple(sorpia::robust_loss_name(o.loss), o.quantile, o.c);
}

// A robust fit's sums cross as (loss, inlier_squares, inlier_weight, cut).
py::tuple robust_sums_tuple(const sorpia::RobustSums& s) {
  return py::make_tuple(s.loss, s.inlier_squares, s.inlier_weight, s.cut);
}

// robust_sums_tuple's inverse, or a list of them added in the list's order.
sorpia::RobustSums to_robust_sums(const py::object& obj) {
  const auto one = [](const py::handle& h) {
    const auto t = h.cast<py::tuple>();
    if (t.size() != 4) throw sorpia::ParameterError("robust sums must be (loss, inlier_squares, inlier_weight, cut)");
    sorpia::RobustSums s;
    s.loss = t[0].cast<double>();
    s.inlier_squares = t[1].cast<double>();
    s.inlier_weight = t[2].cast<double>();
    s.cut = t[3].cast<long long>();
    return s;
  };
  if (!py::isinstance<py::list>(obj)) return one(obj);
  sorpia::RobustSums total;
  for (const auto& v : obj.cast<py::list>()) total.add(one(v));
  return total;
}

// robust_tuple's inverse.
sorpia::RobustOptions to_robust(const py::tuple& robust) {
  if (robust.size() != 3) throw sorpia::ParameterError("robust must be (loss, quantile, c)");
  sorpia::RobustOptions o;
  o.loss = sorpia::robust_loss(robust[0].cast<std::string>(), "loss");
  o.quantile = robust[1].cast<double>();
  o.c = robust[2].cast<double>();
  return o;
}

std::array<double, 3> triple(const py::handle& h, const char* name) {
  const auto v = h.cast<std::vector<double>>();
  if (v.size() != 3) throw sorpia::ParameterError(std::string(name) + " must have 3 items");
  return {v[0], v[1], v[2]};
}

// A chunk's footpoint call without the GIL (LongCall), its sums as distance_tuple.
template <class F>
py::tuple long_sums(F&& call) {
  sorpia::DistanceSums d;
  {
    LongCall long_call;
    d = call();
  }
  return distance_tuple(d);
}

// The trampoline of PointChunks: a Python subclass is a backend the C++ driver calls (the driver runs without the
// GIL; each call takes it).
class PyPointChunks : public sorpia::PointChunks {
 public:
  std::size_t size() override { PYBIND11_OVERRIDE_PURE(std::size_t, sorpia::PointChunks, size, ); }
  void scale(int e) override { PYBIND11_OVERRIDE_PURE(void, sorpia::PointChunks, scale, e); }
  void keep_best() override { PYBIND11_OVERRIDE_PURE(void, sorpia::PointChunks, keep_best, ); }
  void keep_fresh(double closer) override { PYBIND11_OVERRIDE_PURE(void, sorpia::PointChunks, keep_fresh, closer); }
  sorpia::PointExtent extent() override { py::gil_scoped_acquire gil;
    return to_extent(call_locked("extent")); }
  sorpia::PointMoments moments(const double center[3], double diagonal) override {
    py::gil_scoped_acquire gil;
    return to_moments(call_locked("moments", py::make_tuple(center[0], center[1], center[2]), diagonal));
  }
  double line_offset(const double mean[3], const double axis[3], double diagonal) override {
    py::gil_scoped_acquire gil;
    const py::object r = call_locked("line_offset", py::make_tuple(mean[0], mean[1], mean[2]),
                              py::make_tuple(axis[0], axis[1], axis[2]), diagonal);
    if (py::isinstance<py::list>(r)) {
      double off = 0.0;
      for (const auto& v : r.cast<py::list>()) off = std::max(off, v.cast<double>());
      return off;
    }
    return r.cast<double>();
  }
  void set_control_vertices(const double* vertices, std::size_t n) override {
    py::gil_scoped_acquire gil;
    std::vector<double> v(vertices, vertices + 3 * n);
    call_locked("set_control_vertices", to_numpy(std::move(v), 3));
  }
  sorpia::DistanceSums search(const sorpia::FootpointOptions& o) override {
    py::gil_scoped_acquire gil;
    return to_distance_sums(call_locked("search", o.grid, o.max_steps));
  }
  sorpia::DistanceSums refine(const sorpia::FootpointOptions& o) override {
    py::gil_scoped_acquire gil;
    return to_distance_sums(call_locked("refine", o.grid, o.max_steps));
  }
  sorpia::DistanceSums search_fresh(const sorpia::FootpointOptions& o, double closer) override {
    py::gil_scoped_acquire gil;
    return to_distance_sums(call_locked("search_fresh", o.grid, o.max_steps, closer));
  }
  // Optional: without it the base's refine then search_fresh.
  sorpia::DistanceSums refine_fresh(const sorpia::FootpointOptions& o) override {
    py::gil_scoped_acquire gil;
    if (!override_of("refine_fresh")) return sorpia::PointChunks::refine_fresh(o);
    return to_distance_sums(call_locked("refine_fresh", o.grid, o.max_steps));
  }
  sorpia::DistanceSums keep_fresh_in_best() override { py::gil_scoped_acquire gil;
    return to_distance_sums(call_locked("keep_fresh_in_best")); }
  sorpia::NormalSums normal_sums(double tangential) override { py::gil_scoped_acquire gil;
    return to_normal_sums(call_locked("normal_sums", tangential)); }
  // The robust fit's calls are optional: a backend without them fits with robust = "none" only (the base's
  // ParameterError says so). The robust settings go as (loss, quantile, c).
  sorpia::DistanceHistogram distance_histogram(double unit) override {
    py::gil_scoped_acquire gil;
    if (!override_of("distance_histogram")) return sorpia::PointChunks::distance_histogram(unit);
    return to_histogram(call_locked("distance_histogram", unit));
  }
  sorpia::RobustSums robust_sums(const sorpia::RobustOptions& robust, double scale) override {
    py::gil_scoped_acquire gil;
    if (!override_of("robust_sums")) return sorpia::PointChunks::robust_sums(robust, scale);
    return to_robust_sums(call_locked("robust_sums", robust_tuple(robust), scale));
  }
  sorpia::NormalSums robust_normal_sums(double tangential, const sorpia::RobustOptions& robust,
                                        double scale) override {
    py::gil_scoped_acquire gil;
    if (!override_of("robust_normal_sums"))
      return sorpia::PointChunks::robust_normal_sums(tangential, robust, scale);
    return to_normal_sums(call_locked("robust_normal_sums", tangential, robust_tuple(robust), scale));
  }
  // Optional as the robust calls: without it the base's ParameterError says to pass coarse_iterations = 0.
  void set_sample(std::size_t sample_points) override {
    py::gil_scoped_acquire gil;
    if (!override_of("set_sample")) return sorpia::PointChunks::set_sample(sample_points);
    call_locked("set_sample", sample_points);
  }
  std::vector<double> sample() override {
    py::gil_scoped_acquire gil;
    const auto a = call_locked("sample").cast<Vertices>();
    check_shape(a, 3, "sample()");
    return to_vector(a);
  }
  sorpia::Footpoints best_footpoints() override {
    py::gil_scoped_acquire gil;
    const py::object r = call_locked("best_footpoints");
    sorpia::Footpoints f;
    if (r.is_none()) return f;
    const auto t = r.cast<py::tuple>();
    if (t.size() != 3) throw sorpia::ParameterError("best_footpoints() must return (face_ids, uv, distances) or None");
    f.face_ids = to_vector(t[0].cast<FaceIds>());
    f.uv = to_vector(t[1].cast<Vertices>());
    f.distances = to_vector(t[2].cast<Vertices>());
    return f;
  }

 private:
  // The Python override of `name`, or none (the GIL held by the caller).
  py::function override_of(const char* name) const {
    return py::get_override(static_cast<const sorpia::PointChunks*>(this), name);
  }
  // The Python override of `name` called with the GIL held (held by the caller).
  template <class... Args>
  py::object call_locked(const char* name, Args&&... args) {
    const py::function f = override_of(name);
    if (!f) throw sorpia::ParameterError(std::string("PointChunks.") + name + " is not implemented");
    return f(std::forward<Args>(args)...);
  }
};

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

  // Footpoints (face_ids, uv) given for points, checked.
  const auto given_footpoints = [](const Vertices& points, const FaceIds& face_ids, const Vertices& uv) {
    check_shape(points, 3, "points");
    check_shape(uv, 2, "uv");
    const auto n = static_cast<std::size_t>(points.shape(0));
    if (face_ids.ndim() != 1 || static_cast<std::size_t>(face_ids.shape(0)) != n ||
        static_cast<std::size_t>(uv.shape(0)) != n)
      throw sorpia::ParameterError("face_ids and uv must have one row per point (" + std::to_string(n) + ")");
    sorpia::Footpoints fp;
    fp.face_ids = to_vector(face_ids);
    fp.uv = to_vector(uv);
    return fp;
  };
  m.def("refine_footpoints",
        [given_footpoints](const sorpia::LimitSurface& surface, const sorpia::Topology& topology,
                           const Vertices& points, const FaceIds& face_ids, const Vertices& uv, int max_steps) {
          const auto n = static_cast<std::size_t>(points.shape(0));
          sorpia::Footpoints fp = given_footpoints(points, face_ids, uv);
          const double* p = points.data();
          {
            LongCall call;
            sorpia::refine_footpoints(surface, topology, p, n, footpoint_options(0, max_steps), fp);
          }
          return footpoint_tuple(std::move(fp));
        },
        "surface"_a, "topology"_a, "points"_a.noconvert(), "face_ids"_a.noconvert(), "uv"_a.noconvert(),
        "max_steps"_a);

  m.def("closer_footpoints",
        [given_footpoints](const sorpia::LimitSurface& surface, const sorpia::Topology& topology,
                           const Vertices& points, const FaceIds& face_ids, const Vertices& uv, int grid,
                           int max_steps, int starts, double near, bool certify) {
          const auto n = static_cast<std::size_t>(points.shape(0));
          sorpia::Footpoints fp = given_footpoints(points, face_ids, uv);
          const double* p = points.data();
          std::size_t moved = 0, certified = 0;
          {
            LongCall call;
            sorpia::FootpointOptions o = footpoint_options(grid, max_steps);
            o.starts = starts;
            o.near = near;
            o.certify = certify;
            const sorpia::FootpointSearch search(surface, topology, o);
            fp.positions.resize(3 * n);
            fp.normals.resize(3 * n);
            fp.distances.resize(n);
            surface.evaluate(fp.face_ids.data(), fp.uv.data(), n, fp.positions.data(), nullptr, nullptr,
                             fp.normals.data());
            for (std::size_t i = 0; i < n; ++i) {
              double d2 = 0.0;
              for (std::size_t c = 0; c < 3; ++c) d2 += (p[3 * i + c] - fp.positions[3 * i + c]) * (p[3 * i + c] - fp.positions[3 * i + c]);
              fp.distances[i] = std::sqrt(d2);
            }
            moved = search.closer(p, n, fp, false, &certified);
          }
          return py::make_tuple(footpoint_tuple(std::move(fp)), moved, certified);
        },
        "surface"_a, "topology"_a, "points"_a.noconvert(), "face_ids"_a.noconvert(), "uv"_a.noconvert(), "grid"_a,
        "max_steps"_a, "starts"_a, "near"_a = sorpia::FootpointOptions{}.near,
        "certify"_a = sorpia::FootpointOptions{}.certify,
        "((face_ids, uv, positions, distances, normals), moved, certified): the footpoints given, evaluated at their\n"
        "(face, uv), re-searched from the grid samples within their distance (sorpia::FootpointSearch::closer);\n"
        "certified: how many points its certificate let leave out their star's samples (certify=False: none).");

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

  py::class_<sorpia::FootpointSearch>(m, "FootpointSearch",
                                      "closest_points' search start on one state of a surface, built once and "
                                      "queried per chunk (sorpia::FootpointSearch); keep the surface unchanged "
                                      "while it is used.")
      .def(py::init([](const sorpia::LimitSurface& surface, int grid, int max_steps) {
             LongCall call;
             return std::make_unique<sorpia::FootpointSearch>(surface, surface.topology(),
                                                              footpoint_options(grid, max_steps));
           }),
           "surface"_a, "grid"_a, "max_steps"_a, py::keep_alive<1, 2>());

  py::class_<sorpia::ApproximationChunk>(m, "ApproximationChunk",
                                         "One chunk of approximation's points: its footpoints and its share of "
                                         "the normal equations (sorpia::ApproximationChunk, sorpia/point_chunks.hpp).")
      .def(py::init([](const Vertices& points, const py::object& weights, std::size_t first) {
             check_shape(points, 3, "points");
             const auto k = static_cast<std::size_t>(points.shape(0));
             Vertices w;
             const double* wd = point_weights(weights, k, w);
             return sorpia::ApproximationChunk(points.data(), k, wd, first);
           }),
           "points"_a, "weights"_a = py::none(), "first"_a = 0)
      .def_property_readonly("size", &sorpia::ApproximationChunk::size)
      .def_property_readonly("first", &sorpia::ApproximationChunk::first)
      .def_property_readonly("points",
                             [](const sorpia::ApproximationChunk& c) {
                               // as given (the chunk holds them in its own order)
                               std::vector<double> p(c.points().size());
                               for (std::size_t i = 0; i < c.size(); ++i)
                                 std::copy_n(&c.points()[3 * i], 3, &p[3 * c.given(i)]);
                               return to_numpy(p, 3);
                             })
      .def("extent", [](const sorpia::ApproximationChunk& c) { return extent_tuple(c.extent()); })
      .def("scale", &sorpia::ApproximationChunk::scale, "e"_a)
      .def("moments",
           [](const sorpia::ApproximationChunk& c, const py::object& center, double diagonal) {
             const auto x = triple(center, "center");
             return moments_tuple(c.moments(x.data(), diagonal));
           },
           "center"_a, "diagonal"_a)
      .def("line_offset",
           [](const sorpia::ApproximationChunk& c, const py::object& mean, const py::object& axis, double diagonal) {
             const auto x = triple(mean, "mean"), u = triple(axis, "axis");
             return c.line_offset(x.data(), u.data(), diagonal);
           },
           "mean"_a, "axis"_a, "diagonal"_a)
      .def("search",
           [](sorpia::ApproximationChunk& c, const sorpia::FootpointSearch& s) {
             return long_sums([&] { return c.search(s); });
           },
           "search"_a)
      .def("refine",
           [](sorpia::ApproximationChunk& c, const sorpia::LimitSurface& surface, int grid, int max_steps) {
             return long_sums([&] { return c.refine(surface, footpoint_options(grid, max_steps)); });
           },
           "surface"_a, "grid"_a, "max_steps"_a)
      .def("keep_best", &sorpia::ApproximationChunk::keep_best)
      .def("search_fresh",
           [](sorpia::ApproximationChunk& c, const sorpia::FootpointSearch& s, double closer) {
             return long_sums([&] { return c.search_fresh(s, closer); });
           },
           "search"_a, "closer"_a)
      .def("refine_fresh",
           [](sorpia::ApproximationChunk& c, const sorpia::FootpointSearch& s) {
             return long_sums([&] { return c.refine_fresh(s); });
           },
           "search"_a)
      .def("keep_fresh", &sorpia::ApproximationChunk::keep_fresh, "closer"_a)
      .def("keep_fresh_in_best",
           [](sorpia::ApproximationChunk& c) { return distance_tuple(c.keep_fresh_in_best()); })
      .def("normal_sums",
           [](const sorpia::ApproximationChunk& c, const sorpia::LimitSurface& surface, double tangential) {
             sorpia::NormalSums s;
             {
               LongCall call;
               s = c.normal_sums(surface, tangential);
             }
             return normal_tuple(std::move(s));
           },
           "surface"_a, "tangential"_a)
      .def("distance_histogram",
           [](const sorpia::ApproximationChunk& c, double unit) { return histogram_tuple(c.distance_histogram(unit)); },
           "unit"_a, "the current distances' weighted histogram (sorpia/robust.hpp) as (unit, total, mass)")
      .def("robust_sums",
           [](const sorpia::ApproximationChunk& c, const py::tuple& robust, double scale) {
             return robust_sums_tuple(c.robust_sums(to_robust(robust), scale));
           },
           "robust"_a, "scale"_a,
           "the current distances' robust sums (sorpia/robust.hpp) as (sum w rho(d), sum w d^2 and sum w within the "
           "cut c s, the points beyond it); robust = (loss, quantile, c)")
      .def("robust_normal_sums",
           [](const sorpia::ApproximationChunk& c, const sorpia::LimitSurface& surface, double tangential,
              const py::tuple& robust, double scale) {
             const sorpia::RobustOptions o = to_robust(robust);
             sorpia::NormalSums s;
             {
               LongCall call;
               s = c.normal_sums(surface, tangential, &o, scale);
             }
             return normal_tuple(std::move(s));
           },
           "surface"_a, "tangential"_a, "robust"_a, "scale"_a,
           "normal_sums with each weight times the robust factor of its distance at `scale`")
      .def("sampled", &sorpia::ApproximationChunk::sampled, "k"_a, "sample_points"_a,
           "a chunk of this one's points in the fixed sample of about sample_points of all k (the coarse "
           "iterations' chunk)")
      .def("best_footpoints", [](const sorpia::ApproximationChunk& c) {
        sorpia::Footpoints f = c.best_footpoints();
        return py::make_tuple(to_numpy(std::move(f.face_ids), 0), to_numpy(std::move(f.uv), 2),
                              to_numpy(std::move(f.distances), 0));
      });

  py::class_<sorpia::PointChunks, PyPointChunks>(
      m, "PointChunks",
      "approximation's points as chunks (sorpia::PointChunks), the backend its driver calls: subclass it in "
      "Python and implement every method (their calls and order: sorpia/point_chunks.hpp); sums may be returned "
      "per chunk, as a list, added in its order.")
      .def(py::init<>())
      .def("size", &sorpia::PointChunks::size, "the number of points");

  py::class_<sorpia::InMemoryChunks, sorpia::PointChunks>(m, "InMemoryChunks")
      .def(py::init([](sorpia::LimitSurface& surface, const Vertices& points, const py::object& weights,
                       std::size_t chunk_points) {
             check_shape(points, 3, "points");
             const auto k = static_cast<std::size_t>(points.shape(0));
             Vertices w;
             const double* wd = point_weights(weights, k, w);
             return std::make_unique<sorpia::InMemoryChunks>(surface, points.data(), k, wd, chunk_points);
           }),
           "surface"_a, "points"_a.noconvert(), "weights"_a, "chunk_points"_a, py::keep_alive<1, 2>());

  py::class_<sorpia::FileChunks, sorpia::PointChunks>(
      m, "FileChunks",
      "Points streamed from a binary little-endian PLY or .npy file a chunk at a time, footpoint states spilled to "
      "a temporary file in spill_directory (sorpia::FileChunks).")
      .def(py::init([](sorpia::LimitSurface& surface, const std::string& path, std::size_t chunk_points,
                       const std::string& spill_directory, std::size_t sample_points) {
             return std::make_unique<sorpia::FileChunks>(surface, path, chunk_points, spill_directory, sample_points);
           }),
           "surface"_a, "path"_a, "chunk_points"_a, "spill_directory"_a, "sample_points"_a, py::keep_alive<1, 2>());

  m.def("point_file_points", [](const std::string& path) { return sorpia::point_file_layout(path).k; }, "path"_a,
        "The number of points of a file FileChunks streams (a binary little-endian PLY's vertices, a .npy (k, 3)\n"
        "array), from its header; FileError (sorpia.MeshFileError) for any other file.");
  m.def(
      "read_point_file",
      [](const std::string& path, std::size_t first, std::size_t count) {
        std::vector<double> p;
        {
          LongCall call;
          p = sorpia::read_point_file(path, first, count);
        }
        return to_numpy(std::move(p), 3);
      },
      "path"_a, "first"_a, "count"_a,
      "Points first .. first + count of a file FileChunks streams, (count, 3) float64 (a chunk read where it is\n"
      "used: a Dask worker).");
  m.def(
      "point_sample_mask",
      [](std::size_t first, std::size_t count, std::size_t k, std::size_t sample_points) {
        const std::vector<char> in = sorpia::point_sample_mask(first, count, k, sample_points);
        py::array_t<bool> out(static_cast<py::ssize_t>(count));
        std::copy(in.begin(), in.end(), out.mutable_data());
        return out;
      },
      "first"_a, "count"_a, "k"_a, "sample_points"_a,
      "Which of points first .. first + count of k are in FileChunks' fixed sample of about sample_points.");

  m.def(
      "approximate",
      [](sorpia::LimitSurface& surface, sorpia::PointChunks& chunks, int iterations, double tol,
         double fairness, double tangential, const std::string& method, double solver_tol, long long solver_max_iter,
         int grid, int newton_steps, int report_level, const py::object& callback, double seconds_before,
         bool report_each, const std::string& robust, std::optional<double> robust_quantile,
         std::optional<double> robust_c,
         int coarse_iterations, double coarse_points, double coarse_tol) {
        sorpia::ApproximationOptions o;
        o.iterations = iterations;
        o.coarse_iterations = coarse_iterations;
        o.coarse_points = coarse_points;
        o.coarse_tol = coarse_tol;
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
        o.report_each = report_each;
        o.robust = sorpia::robust_options(sorpia::robust_loss(robust));
        if (robust_quantile) o.robust.quantile = *robust_quantile;
        if (robust_c) o.robust.c = *robust_c;
        sorpia::ApproximationProgress progress;
        if (!callback.is_none())
          progress = [&callback, seconds_before](const sorpia::ApproximationRecord& r) {
            py::gil_scoped_acquire gil;
            callback(record_dict(r, seconds_before));
          };
        sorpia::ApproximationResult r;
        {
          LongCall call;
          r = sorpia::approximate(surface, chunks, o, progress);
        }
        py::list history;
        for (const auto& rec : r.history) history.append(record_dict(rec, seconds_before));
        py::dict out;
        out["control_vertices"] = to_numpy(std::move(r.control_vertices), 3);
        out["face_ids"] = to_numpy(std::move(r.footpoints.face_ids), 0);
        out["uv"] = to_numpy(std::move(r.footpoints.uv), 2);
        out["distances"] = to_numpy(std::move(r.footpoints.distances), 0);
        out["iterations"] = r.iterations;
        out["coarse_iterations"] = r.coarse_iterations;
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
      "surface"_a, "chunks"_a, "iterations"_a, "tol"_a, "fairness"_a, "tangential"_a,
      "method"_a, "solver_tol"_a, "solver_max_iter"_a, "grid"_a, "newton_steps"_a, "report_level"_a, "callback"_a,
      "seconds_before"_a = 0.0, "report_each"_a = false,
      "robust"_a = sorpia::robust_loss_name(sorpia::ApproximationOptions{}.robust.loss),
      "robust_quantile"_a = py::none(), "robust_c"_a = py::none(),
      "coarse_iterations"_a = sorpia::ApproximationOptions{}.coarse_iterations,
      "coarse_points"_a = sorpia::ApproximationOptions{}.coarse_points,
      "coarse_tol"_a = sorpia::ApproximationOptions{}.coarse_tol,
      "Approximation's pipeline (sorpia::approximate) from the surface's control vertices, over the points of\n"
      "`chunks` (InMemoryChunks, FileChunks or a Python PointChunks): a dict with control_vertices, face_ids, uv,\n"
      "distances, iterations, stop_reason, best_iteration, diagonal, robust_scale, robust_outliers, history\n"
      "(records as dicts, seconds counted from seconds_before) and timings; callback(record) after each record.\n"
      "The surface-to-data figures in every record with report_each, else only in the returned iterate's (None\n"
      "in the others). robust: the loss of the robust fit (none, cauchy, tukey; the core's default unless\n"
      "given) at the robust_quantile of the distances times robust_c (sorpia/robust.hpp; None: the loss's\n"
      "defaults, robust_options): a Python backend fits robustly only where it defines distance_histogram,\n"
      "robust_sums and robust_normal_sums (sorpia/point_chunks.hpp); robust = 'none' runs without them. coarse_iterations: updates on a fixed sample of\n"
      "coarse_points per control vertex first, at most that many, fewer where one lowers the sample's criterion by\n"
      "at most coarse_tol of it (ApproximationOptions), where the backend defines set_sample.");

  // The robust fit's defaults cross from the core (sorpia::robust_options, ApproximationOptions::robust), so that
  // the Python API and the command line take them from the one place they are set.
  m.attr("DEFAULT_ROBUST") = sorpia::robust_loss_name(sorpia::ApproximationOptions{}.robust.loss);
  m.attr("DEFAULT_COARSE_ITERATIONS") = sorpia::ApproximationOptions{}.coarse_iterations;
  m.attr("DEFAULT_COARSE_POINTS") = sorpia::ApproximationOptions{}.coarse_points;
  m.attr("DEFAULT_COARSE_TOL") = sorpia::ApproximationOptions{}.coarse_tol;
  m.def(
      "robust_options", [](const std::string& loss) { return robust_tuple(sorpia::robust_options(sorpia::robust_loss(loss))); },
      "loss"_a, "The default settings of a robust loss (sorpia::robust_options) as (loss, quantile, c).");
}

}  // namespace sorpia_py
