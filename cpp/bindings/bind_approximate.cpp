// Bindings of approximation (cpp/fit footpoints.hpp, normal_matrix.hpp): the
// k-d tree, the footpoints of data points on a limit surface, and the normal
// matrix of the fit. Conversion and error translation only.
#include "bindings.hpp"
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
        [](const py::array_t<std::int32_t, py::array::c_style>& indptr,
           const py::array_t<std::int32_t, py::array::c_style>& indices, const Vertices& data,
           std::size_t n_cols, const py::object& weights) {
          sorpia::CsrMatrix A;
          A.n_rows = static_cast<std::size_t>(indptr.shape(0)) - 1;
          A.n_cols = n_cols;
          A.indptr = to_vector(indptr);
          A.indices = to_vector(indices);
          A.data = to_vector(data);
          if (A.indices.size() != A.data.size() || static_cast<std::size_t>(A.indptr.back()) != A.data.size())
            throw sorpia::ParameterError("normal_matrix: indptr, indices and data disagree");
          for (const std::int32_t j : A.indices)
            if (j < 0 || static_cast<std::size_t>(j) >= n_cols)
              throw sorpia::ParameterError("normal_matrix: a column index is out of range");
          int count = 0;
          Vertices w;
          if (!weights.is_none()) {
            w = weights.cast<Vertices>();
            if (w.ndim() != 2 || static_cast<std::size_t>(w.shape(0)) != A.n_rows)
              throw sorpia::ParameterError("weights must have one row per row of A");
            count = static_cast<int>(w.shape(1));
          }
          const double* wp = count ? w.data() : nullptr;
          sorpia::NormalMatrix M;
          {
            LongCall call;
            M = sorpia::normal_matrix(A, wp, count);
          }
          const int nb = M.blocks;
          return py::make_tuple(to_numpy(std::move(M.indptr), 0), to_numpy(std::move(M.indices), 0),
                                to_numpy(std::move(M.values), nb));
        },
        "indptr"_a.noconvert(), "indices"_a.noconvert(), "data"_a.noconvert(), "n_cols"_a, "weights"_a);

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
}

}  // namespace sorpia_py
