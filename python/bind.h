// Declarations shared by the binding sources of the extension module screwfem._screwfem.
// The bindings are thin: they convert arguments, check indices and call the public C++ API
// (include/screwfem); no physics lives here.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

#include "screwfem/solve/stop.h"

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

// A stop request for long C++ calls made with the GIL held: polls Python's pending signals
// (PyErr_CheckSignals, which runs their handlers; SIGINT's raises KeyboardInterrupt). Once a
// handler has raised, the request stays set and ThrowIfRaised() re-raises that exception.
class PythonSignals {
 public:
  StopRequest request() { return StopRequest{nullptr, &PythonSignals::Poll, this}; }
  void ThrowIfRaised() const {
    if (raised_) throw pybind11::error_already_set();
  }

 private:
  static bool Poll(void* self) {
    auto* s = static_cast<PythonSignals*>(self);
    if (!s->raised_ && PyErr_CheckSignals() != 0) s->raised_ = true;
    return s->raised_;
  }
  bool raised_ = false;
};

// Index checks for ids passed from Python: raise IndexError (never undefined behaviour).
int CheckIndex(long index, std::size_t size, const char* what);

}  // namespace screwfem::python
