// Declarations shared by the binding sources of the extension module screwfem._screwfem.
// The bindings are thin: they convert arguments, check indices and call the public C++ API
// (include/screwfem); no physics lives here.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

namespace screwfem::python {

// bind_model.cpp: Model and its entities (read-only), SE3 conversions.
void BindModel(pybind11::module_& m);
// bind_scene.cpp: analysis settings, Scene, LoadScene/ParseScene, RunScene, StepSchedule.
void BindScene(pybind11::module_& m);
// bind_simulation.cpp: Simulation (Model + Data + Integrator) and its results.
void BindSimulation(pybind11::module_& m);

// Raises screwfem.SolverError(message) with the attribute `result` set to `result` (the
// StepResult or StaticResult of the failed call).
[[noreturn]] void RaiseSolverError(const std::string& message, pybind11::object result);

// Index checks for ids passed from Python: raise IndexError (never undefined behaviour).
int CheckIndex(long index, std::size_t size, const char* what);

}  // namespace screwfem::python
