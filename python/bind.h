// Declarations shared by the binding sources of the extension module screwfem._screwfem.
// The bindings are thin: they convert arguments, check indices and call the public C++ API
// (include/screwfem); no physics lives here.
#pragma once

#include <pybind11/pybind11.h>

#include <cctype>
#include <type_traits>
#include <string>

#include "screwfem/elements/joint.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/enum_names.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/statics.h"
#include "screwfem/solve/stop.h"

// Typed ids (model/ids.h) are Python ints: scripts pass and receive plain indices.
namespace pybind11::detail {
template <typename Tag>
struct type_caster<screwfem::Id<Tag>> {
  PYBIND11_TYPE_CASTER(screwfem::Id<Tag>, const_name("int"));
  bool load(handle src, bool convert) {
    make_caster<int> index;
    if (!index.load(src, convert)) return false;
    value = screwfem::Id<Tag>(cast_op<int>(index));
    return true;
  }
  static handle cast(screwfem::Id<Tag> id, return_value_policy /*policy*/, handle /*parent*/) {
    return PyLong_FromLong(id.value());
  }
};
}  // namespace pybind11::detail

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
// bind_inverse.cpp: static sensitivities and inverse statics (solve/sensitivity.h).
void BindInverse(pybind11::module_& m);

// Whether an enum value from Python is one of the enum's values (pybind11's enums make a member
// from any integer: JointType(99)).
template <class E>
bool IsValidEnum(E value) {
  return IsEnumValue(value);
}
template <>
inline bool IsValidEnum(JointType value) {
  for (const std::string& name : JointTypeNameList())
    if (FindJointType(name)->type == value) return true;
  return false;
}
// "JointType: 99 is not a member (REVOLUTE, PRISMATIC, ...)".
template <class E>
std::string InvalidEnumMessage(const char* enum_name, E value) {
  std::string names;
  if constexpr (std::is_same_v<E, JointType>) {
    for (const std::string& n : JointTypeNameList()) names += (names.empty() ? "" : ", ") + n;
  } else {
    for (const std::string& n : EnumNameList<E>()) names += (names.empty() ? "" : ", ") + n;
  }
  for (char& c : names) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return std::string(enum_name) + ": " + std::to_string(static_cast<long long>(value)) +
         " is not a member (" + names + ")";
}

// E(i) from an integer raises ValueError unless i is one of the enum's values (pybind11's own
// constructor, which this one comes before, accepts any integer).
template <class E>
void CheckEnumConstructor(pybind11::enum_<E>& e, const char* name) {
  using Scalar = typename pybind11::enum_<E>::Scalar;
  e.def(pybind11::init([name](Scalar i) {
          const E value = static_cast<E>(i);
          if (!IsValidEnum(value)) throw pybind11::value_error(InvalidEnumMessage(name, value));
          return value;
        }),
        pybind11::arg("value"), pybind11::prepend());
}

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
  CheckEnumConstructor(e, name);
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

// A memory size from Python (max_memory, set_memory_limit; bind_scene.cpp): None (0: the
// process default), a positive int of bytes, or a text such as '8G' (ParseMemorySize).
std::size_t MemorySize(const pybind11::object& v, const std::string& setting);

// Index checks for ids passed from Python: raise IndexError (never undefined behaviour).
int CheckIndex(long index, std::size_t size, const char* what);

}  // namespace screwfem::python

// Every enum bound to Python is checked where it enters C++ as well (an argument, an attribute
// set, a list element): a value outside the enum that got past the constructor (unpickled by
// __setstate__) raises ValueError instead of reaching the library, where joint_type_name and
// ModelBuilder.add_joint aborted the interpreter on JointType(99).
namespace pybind11::detail {
template <class E>
struct screwfem_checked_enum : type_caster_base<E> {
  bool load(handle src, bool convert) {
    if (!type_caster_base<E>::load(src, convert)) return false;
    if (this->value != nullptr) {
      const E v = *static_cast<const E*>(this->value);
      if (!screwfem::python::IsValidEnum(v))
        throw value_error(screwfem::python::InvalidEnumMessage(
            src.get_type().attr("__name__").cast<std::string>().c_str(), v));
    }
    return true;
  }
};
#define SCREWFEM_CHECKED_ENUM(E) \
  template <>                    \
  struct type_caster<E> : screwfem_checked_enum<E> {}
SCREWFEM_CHECKED_ENUM(screwfem::JointType);
SCREWFEM_CHECKED_ENUM(screwfem::DriveKind);
SCREWFEM_CHECKED_ENUM(screwfem::LinearSolver);
SCREWFEM_CHECKED_ENUM(screwfem::RodInertia);
SCREWFEM_CHECKED_ENUM(screwfem::LoadFrame);
SCREWFEM_CHECKED_ENUM(screwfem::ActuatorType);
SCREWFEM_CHECKED_ENUM(screwfem::ContactShapeType);
SCREWFEM_CHECKED_ENUM(screwfem::ObstacleType);
SCREWFEM_CHECKED_ENUM(screwfem::NewtonMatrix);
SCREWFEM_CHECKED_ENUM(screwfem::Predictor);
SCREWFEM_CHECKED_ENUM(screwfem::ConvergenceTest);
SCREWFEM_CHECKED_ENUM(screwfem::ConstraintFormulation);
SCREWFEM_CHECKED_ENUM(screwfem::StaticMethod);
SCREWFEM_CHECKED_ENUM(screwfem::AnalysisKind);
SCREWFEM_CHECKED_ENUM(screwfem::VtkFormat);
#undef SCREWFEM_CHECKED_ENUM
}  // namespace pybind11::detail
