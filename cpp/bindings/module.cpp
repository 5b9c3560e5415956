// The pybind11 module sorpia._core. Arrays are refused unless they already have
// the exact dtype and C layout (noconvert): the Python layer
// (sorpia/_validate.py) converts and validates them once, with messages that
// name the argument. Every output is a fresh array owned by Python.
#include "bindings.hpp"

namespace py = pybind11;

namespace sorpia_py {
namespace {
unsigned long main_thread_ident = 0;  // threading.main_thread().ident
}  // namespace

sorpia::InterruptChecker python_signal_checker() {
  if (PyThread_get_thread_ident() != main_thread_ident) return {};
  return [] {
    py::gil_scoped_acquire acquire;
    return PyErr_CheckSignals() != 0;
  };
}
}  // namespace sorpia_py

PYBIND11_MODULE(_core, m) {
  m.doc() = "sorpia's compiled core (OpenMesh topology, OpenSubdiv Loop and Catmull-Clark limits, PIA solvers)";
  m.attr("__version__") = SORPIA_VERSION;

  py::register_exception<sorpia::MeshError>(m, "MeshError", PyExc_ValueError);
  py::register_exception<sorpia::ParameterError>(m, "ParameterError", PyExc_ValueError);
  py::register_exception<sorpia::FileError>(m, "MeshFileError", PyExc_ValueError);
  sorpia_py::main_thread_ident = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const sorpia::Interrupted&) {
      // The exception a signal handler raised is still set (LongCall); a
      // checker that stopped without one stands for Ctrl-C.
      if (!PyErr_Occurred()) PyErr_SetNone(PyExc_KeyboardInterrupt);
    }
  });

  sorpia_py::bind_limit(m);
  sorpia_py::bind_solvers(m);
  sorpia_py::bind_surface(m);
  sorpia_py::bind_io(m);
  sorpia_py::bind_mesh_checks(m);
  sorpia_py::bind_repair(m);
  sorpia_py::bind_approximate(m);
  sorpia_py::bind_cage(m);
  sorpia_py::bind_fit(m);
  // One line per topic; each bind_<topic> lives in cpp/bindings/bind_<topic>.cpp.
}
