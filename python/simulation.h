// Simulation: the class behind screwfem.Simulation, shared by the binding sources that step
// it (bind_simulation.cpp, bind_env.cpp). A Scene copy, its Data and an Integrator; every
// method calls the public C++ API and adds only argument checks and name lookups.
#pragma once

#include <pybind11/pybind11.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "bind.h"
#include "screwfem/elements/joint.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/statics.h"

namespace screwfem::python {

namespace py = pybind11;

// A copy of the scene, the Data allocated once from its model, and the integrator workspace.
// Data's arrays are never reallocated after construction (the C++ solvers assign them in
// place), so NumPy views of them stay valid for the life of the Simulation.
class Simulation {
 public:
  explicit Simulation(const Scene& scene) : scene_(scene), data_(MakeData(scene_.model)) {
    data_.time = scene_.analysis.kind == AnalysisKind::kStatic ? scene_.analysis.statics.time
                                                               : scene_.analysis.start_time;
    std::string why;
    if (!AssembleInitialState(scene_.model, data_, &why))
      RaiseSolverError("initial state: " + why, py::none());
  }

  Scene& scene() { return scene_; }
  const Model& model() const { return scene_.model; }
  Data& data() { return data_; }
  const Integrator& integrator() const { return integrator_; }
  Integrator& integrator() { return integrator_; }
  bool initialized() const { return initialized_; }

  void Initialize(const std::optional<DynamicOptions>& options) {
    const DynamicOptions o = options ? *options : scene_.analysis.dynamic;
    ValidateDynamicOptions(o, "DynamicOptions");
    initialized_ = false;
    std::string why;
    if (!InitializeDynamics(model(), data_, integrator_, o, &why)) {
      char when[96];
      std::snprintf(when, sizeof when,
                    "cannot start the dynamic analysis at t = %.9g s: ", data_.time);
      RaiseSolverError(when + why, py::none());
    }
    initialized_ = true;
  }

  StepResult Advance(double h) {
    if (!initialized_)
      throw std::logic_error("Simulation.step: call initialize() first (again after solve_static)");
    if (!(std::isfinite(h) && h > 0.0)) throw InputError("Simulation.step: h must be a time > 0 s");
    PythonSignals signals;
    // One step of exactly h (Advance to t + h with fixed steps of h).
    StepResult r = screwfem::Advance(model(), data_, integrator_, StepPolicy::Fixed(h),
                                     data_.time + h, nullptr, signals.request());
    signals.ThrowIfRaised();
    if (!r.ok) RaiseSolverError(r.message, py::cast(r));
    return r;
  }

  // Error-controlled steps to t_end exactly (Advance, as AdvanceTo); the controller's state
  // carries over.
  StepResult AdvanceToTime(double t_end) {
    if (!initialized_)
      throw std::logic_error(
          "Simulation.advance_to: call initialize() first (again after solve_static)");
    if (!(std::isfinite(t_end) && t_end >= data_.time))
      throw InputError("Simulation.advance_to: t_end must be a finite time >= the current time");
    PythonSignals signals;
    StepResult r = screwfem::Advance(model(), data_, integrator_, StepPolicy::ErrorControlled(),
                                     t_end, nullptr, signals.request());
    signals.ThrowIfRaised();
    if (!r.ok) RaiseSolverError(r.message, py::cast(r));
    return r;
  }

  StaticResult Statics(const std::optional<StaticOptions>& options) {
    StaticOptions o = scene_.analysis.statics;
    o.time = data_.time;
    if (options) o = *options;
    ValidateStaticOptions(o, "StaticOptions");
    data_.time = o.time;
    initialized_ = false;
    PythonSignals signals;
    StaticResult r = SolveStatic(model(), data_, o, signals.request());
    signals.ThrowIfRaised();
    if (!r.converged) {
      char head[96];
      std::snprintf(head, sizeof head, "static solution %s at load factor %.9g: ",
                    r.limit_point ? "stopped" : "failed", r.load_factor);
      RaiseSolverError(head + r.message, py::cast(r));
    }
    return r;
  }

  // Index lookups for arguments given as an index or a name.
  int Node(long i) const { return CheckIndex(i, model().nodes.size(), "node"); }
  int Node(const std::string& name) const { return Named(model().FindNode(name), "node", name); }
  int Rod(long i) const { return CheckIndex(i, model().rods.size(), "rod"); }
  int Rod(const std::string& name) const { return Named(model().FindRod(name), "rod", name); }
  int TendonIndex(const std::string& name) const {
    return Named(model().FindTendon(name), "tendon", name);
  }
  int ActuatorIndex(const std::string& name) const {
    return Named(model().FindActuator(name), "actuator", name);
  }
  int ForceElementIndex(const std::string& name) const {
    return Named(model().FindForceElement(name), "force element", name);
  }
  int JointIndex(long i) const { return CheckIndex(i, model().joints.size(), "joint"); }
  int JointIndex(const std::string& name) const {
    return Named(model().FindJoint(name), "joint", name);
  }
  // Velocity index of coordinate c of a joint.
  int JointDof(int joint, int c) const {
    const Joint& j = model().joints[static_cast<std::size_t>(joint)];
    CheckIndex(c, static_cast<std::size_t>(j.k()),
               ("coordinate of joint '" + j.name + "'").c_str());
    return j.coord + c;
  }

  int Input(const std::string& name) const {
    const int i = model().FindInput(name);
    if (i < 0) {
      std::string known;
      for (const ModelInput& in : model().inputs)
        known += (known.empty() ? "'" : ", '") + in.name + "'";
      throw py::key_error("no input named '" + name + "' (the scene's inputs: " +
                          (known.empty() ? std::string("none") : known) + ")");
    }
    return i;
  }

  // Soft-joint spring or damper values (JointSpringCount of them, finite, >= 0): parameters that
  // may change between steps (they enter the residual and tangent, not the matrix pattern).
  void SetJointSprings(int joint, const Eigen::Ref<const Eigen::VectorXd>& values, bool damping) {
    Joint& j = scene_.model.joints[static_cast<std::size_t>(joint)];
    const int n = JointSpringCount(j);
    const char* what = damping ? "set_joint_damping" : "set_joint_stiffness";
    if (values.size() != n)
      throw InputError(std::string("Simulation.") + what + ": joint '" + j.name + "' has " +
                       std::to_string(n) + " springs, got " + std::to_string(values.size()) +
                       " values");
    for (int c = 0; c < n; ++c)
      if (!std::isfinite(values(c)) || values(c) < 0.0)
        throw InputError(std::string("Simulation.") + what + ": values must be finite and >= 0");
    (damping ? j.damping : j.stiffness).head(n) = values;
  }

  SimulationState GetState() const {
    SimulationState s;
    SaveSimulationState(data_, integrator_, &s);
    return s;
  }
  void SetState(const SimulationState& s) { RestoreSimulationState(s, data_, integrator_); }

  const OutputPoint& OutputPointNamed(const std::string& name) const {
    for (const OutputPoint& p : scene_.outputs.points)
      if (p.name == name) return p;
    throw py::key_error("no output point named '" + name + "' in the scene's outputs.points");
  }

 private:
  static int Named(int index, const char* what, const std::string& name) {
    if (index < 0) throw py::key_error(std::string("no ") + what + " named '" + name + "'");
    return index;
  }

  Scene scene_;
  Data data_;
  Integrator integrator_;
  bool initialized_ = false;
};

}  // namespace screwfem::python
