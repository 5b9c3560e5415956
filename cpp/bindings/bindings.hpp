#pragma once
// Shared helpers of the pybind11 module sorpia._core. One binding file per
// topic (limit, solvers, surface, io, repair, cage), each with a bind_<topic>(module) that
// module.cpp calls: conversion and error translation only, no mathematics.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstring>
#include <string>
#include <vector>

#include "sorpia/errors.hpp"
#include "sorpia/interrupt.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/topology.hpp"

namespace sorpia_py {

namespace py = pybind11;

// Arrays the core accepts: exact dtype and C layout. Bind them with
// .noconvert(): the Python layer (sorpia/_validate.py) converts and validates.
using Vertices = py::array_t<double, py::array::c_style>;
using Faces = py::array_t<std::int32_t, py::array::c_style>;

inline void check_shape(const py::array& a, py::ssize_t cols, const char* name) {
  if (a.ndim() != 2 || a.shape(1) != cols)
    throw sorpia::ParameterError(std::string(name) + " must have shape (n, " + std::to_string(cols) + ")");
}

// a must have one row per vertex of `owner` ("the mesh", ...), n in all.
inline void check_rows(const py::array& a, std::size_t n, const char* name, const char* owner) {
  if (static_cast<std::size_t>(a.shape(0)) != n)
    throw sorpia::ParameterError(std::string(name) + " has " + std::to_string(a.shape(0)) + " rows but " + owner +
                                 " has " + std::to_string(n) + " vertices");
}

// A copy of a C-contiguous array's values.
template <class T>
std::vector<T> to_vector(const py::array_t<T, py::array::c_style>& a) {
  return std::vector<T>(a.data(), a.data() + a.size());
}

// Polygons as (face_vertex_counts, face_vertex_indices): one-dimensional,
// the counts summing to the indices' length (what the core reads).
inline void check_polygon_arrays(const py::array_t<std::int32_t, py::array::c_style>& counts,
                                 const py::array_t<std::int32_t, py::array::c_style>& indices) {
  if (counts.ndim() != 1 || indices.ndim() != 1)
    throw sorpia::ParameterError("face_vertex_counts and face_vertex_indices must be one-dimensional");
  std::int64_t total = 0;
  for (py::ssize_t f = 0; f < counts.shape(0); ++f) total += counts.data()[f];
  if (total != indices.shape(0))
    throw sorpia::MeshError("face_vertex_counts sum to " + std::to_string(total) + " but face_vertex_indices has " +
                            std::to_string(indices.shape(0)) + " entries");
}

// The interrupt checker of a long call (sorpia/interrupt.hpp): runs Python's
// signal handlers, with the GIL; true when one raised (KeyboardInterrupt),
// its exception left set for the module's translation of sorpia::Interrupted.
// Empty off the main thread, where Python runs no handlers.
sorpia::InterruptChecker python_signal_checker();

// A long call into the core: the GIL released and python_signal_checker
// installed while it lives (as a local, or a py::call_guard).
class LongCall {
  sorpia::InterruptScope scope_{python_signal_checker()};
  py::gil_scoped_release release_;
};

template <class T>
std::vector<py::ssize_t> numpy_shape(const std::vector<T>& v, py::ssize_t cols) {
  const auto len = static_cast<py::ssize_t>(v.size());
  return cols > 0 ? std::vector<py::ssize_t>{len / cols, cols} : std::vector<py::ssize_t>{len};
}

// A fresh numpy array (owned by Python) holding a copy of v; cols > 0 makes it
// (len/cols, cols), cols == 0 one-dimensional. For arrays that stay with a C++
// object (a topology's rings, an operator's arrays).
template <class T>
py::array_t<T> to_numpy(const std::vector<T>& v, py::ssize_t cols) {
  py::array_t<T> out(numpy_shape(v, cols));
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(T));
  return out;
}

// The same shape, without a copy: the numpy array takes v's storage over
// (a capsule frees it with the array). For results, which can be large: no
// copy into freshly faulted pages.
template <class T>
py::array_t<T> to_numpy(std::vector<T>&& v, py::ssize_t cols) {
  if (v.empty()) return py::array_t<T>(numpy_shape(v, cols));  // no storage to take over (data() may be null)
  auto* owner = new std::vector<T>(std::move(v));
  py::capsule free_with_array(owner, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(numpy_shape(*owner, cols), owner->data(), free_with_array);
}

// (data, indices, indptr) of a CSR matrix, for scipy.sparse.csr_matrix, taking its storage over.
inline py::tuple csr_tuple(sorpia::CsrMatrix&& b) {
  return py::make_tuple(to_numpy(std::move(b.data), 0), to_numpy(std::move(b.indices), 0),
                        to_numpy(std::move(b.indptr), 0));
}

// Taking the mesh's storage over: (vertices (n, 3), faces (m, 3)) for
// triangles without counts, else (vertices (n, 3), face_vertex_counts (m,),
// face_vertex_indices (sum of counts,)).
inline py::tuple mesh_tuple(sorpia::Mesh&& m) {
  if (m.all_triangles())
    return py::make_tuple(to_numpy(std::move(m.vertices), 3), to_numpy(std::move(m.face_vertex_indices), 3));
  return py::make_tuple(to_numpy(std::move(m.vertices), 3), to_numpy(m.counts(), 0),
                        to_numpy(std::move(m.face_vertex_indices), 0));
}

void bind_limit(py::module_& m);
void bind_solvers(py::module_& m);
void bind_surface(py::module_& m);
void bind_io(py::module_& m);
void bind_mesh_checks(py::module_& m);
void bind_repair(py::module_& m);
void bind_approximate(py::module_& m);
void bind_cage(py::module_& m);
void bind_fit(py::module_& m);

}  // namespace sorpia_py
