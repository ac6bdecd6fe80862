// The extension module screwfem._screwfem: exceptions, then the bindings of each layer.
#include <pybind11/pybind11.h>

#include <string>

#include "bind.h"
#include "screwfem/model/errors.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {
// screwfem.SolverError, owned by the module (kept alive by the module's attribute).
PyObject* g_solver_error = nullptr;
}  // namespace

void RaiseSolverError(const std::string& message, py::object result) {
  py::object error = py::reinterpret_borrow<py::object>(g_solver_error)(message);
  error.attr("result") = std::move(result);
  PyErr_SetObject(g_solver_error, error.ptr());
  throw py::error_already_set();
}

int CheckIndex(long index, std::size_t size, const char* what) {
  if (index < 0 || static_cast<std::size_t>(index) >= size)
    throw py::index_error(std::string(what) + " index " + std::to_string(index) +
                          " out of range [0, " + std::to_string(size) + ")");
  return static_cast<int>(index);
}

}  // namespace screwfem::python

PYBIND11_MODULE(_screwfem, m) {
  m.doc() =
      "screwfem: geometrically exact screw-based finite elements for articulated soft robots.\n\n"
      "Thin bindings of the C++ library (include/screwfem). Units are SI throughout (m, kg, s,\n"
      "N, rad); positions, velocities and accelerations of points are in the world frame;\n"
      "node velocities in Simulation.v are body velocities [v; w] in the node frame.";
  m.attr("__version__") = SCREWFEM_VERSION;

  py::register_exception<screwfem::InputError>(m, "InputError", PyExc_ValueError).doc() =
      "Invalid input: a scene, an override or an argument. For scene files the message reads\n"
      "'FILE:LINE:COLUMN: FIELD: what was expected' (docs/scene-format.md, 'Errors').";
  auto& solver_error =
      py::register_exception<screwfem::SolverError>(m, "SolverError", PyExc_RuntimeError);
  solver_error.doc() =
      "A numerical failure: a time step that failed after every halving, a static solution\n"
      "that did not converge, or singular initial conditions. The attribute `result` holds the\n"
      "StepResult or StaticResult of the failed call (None from Simulation.initialize).";
  screwfem::python::g_solver_error = solver_error.ptr();

  screwfem::python::BindModel(m);
  screwfem::python::BindBuild(m);
  screwfem::python::BindScene(m);
  screwfem::python::BindSimulation(m);
  screwfem::python::BindSpec(m);
  screwfem::python::BindEnv(m);
  screwfem::python::BindInverse(m);
}
