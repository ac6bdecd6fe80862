// Declarations shared by the binding sources of the extension module screwfem._screwfem.
// The bindings are thin: they convert arguments, check indices and call the public C++ API
// (include/screwfem); no physics lives here.
#pragma once

#include <pybind11/pybind11.h>

#include <cctype>
#include <string>

#include "screwfem/model/enum_names.h"
#include "screwfem/solve/stop.h"

namespace screwfem::python {

// bind_model.cpp: Model and its entities (read-only), SE3 conversions.
void BindModel(pybind11::module_& m);
// bind_build.cpp: ModelBuilder, Section, Profile, JointSpec.
void BindBuild(pybind11::module_& m);
// bind_scene.cpp: analysis settings, Scene, LoadScene/ParseScene, RunScene, StepSchedule.
void BindScene(pybind11::module_& m);
// bind_simulation.cpp: Simulation (Model + Data + Integrator) and its results.
void BindSimulation(pybind11::module_& m);
// bind_spec.cpp: the scene spec (scene_spec.h) <-> screwfem.SceneSpec, ReadSceneSpec, CompileScene.
void BindSpec(pybind11::module_& m);
// bind_env.cpp: _step_many, the threaded stepping behind screwfem.Env and VectorEnv.
void BindEnv(pybind11::module_& m);

// An enum with a vocabulary (model/enum_names.h) as a Python enum whose members are its
// names in capitals (NewtonMatrix.SIMPLIFIED for the scene's `newton: simplified`).
template <class E>
pybind11::enum_<E> BindEnum(pybind11::module_& m, const char* name, const char* doc) {
  pybind11::enum_<E> e(m, name, doc);
  for (const EnumName<E>& v : EnumNames<E>::kValues) {
    std::string upper = v.name;
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    e.value(upper.c_str(), v.value, v.doc);
  }
  return e;
}

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
