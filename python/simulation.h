// Simulation: the class behind screwfem.Simulation, shared by the binding sources that step
// it (bind_simulation.cpp, bind_env.cpp). A Scene copy, its Data and an Integrator; every
// method calls the public C++ API and adds only argument checks and name lookups.
#pragma once

#include <pybind11/pybind11.h>

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "bind.h"
#include "screwfem/elements/joint.h"
#include "screwfem/io/recording.h"
#include "screwfem/io/scene.h"
#include "screwfem/io/vtk.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/statics.h"

namespace screwfem::python {

namespace py = pybind11;

// A copy of the scene, the Data allocated once from its model, and the integrator workspace.
// Data's arrays are never reallocated after construction (the C++ solvers assign them in
// place), so NumPy views of them stay valid for the life of the Simulation.
class Simulation {
 public:
  explicit Simulation(const Scene& scene) : scene_(scene), data_(MakeData(scene_.model)) {
    SetAssemblyThreads(data_, ResolveAssemblyThreads(scene_.model, scene_.analysis.threads));
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
    CheckInputsFinite("Simulation.initialize");
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

  // One step: of exactly h (Advance to t + h with fixed steps of h), or with h unset the
  // next step of the scene's analysis (its StepSchedule: steps of analysis.step ending on the
  // profile breakpoints, the time set to each step end, as `screwfem run` steps).
  StepResult Advance(std::optional<double> h) {
    CheckStepping("step");
    if (h && !(std::isfinite(*h) && *h > 0.0))
      throw InputError("Simulation.step: h must be a time > 0 s");
    if (h) return Run(StepPolicy::Fixed(*h), data_.time + *h);
    const StepSchedule& schedule = Schedule("step");
    if (!schedule.Accepts(data_.time))
      throw InputError(FormatNumbers(
          "Simulation.step: t = %.9g s is not within the scene's analysis (start_time to "
          "end_time %.9g s); pass a step h",
          data_.time, schedule.end()));
    return Run(StepPolicy::OnSchedule(schedule), schedule.Next(data_.time));
  }

  // Error-controlled steps to t_end exactly (Advance, as AdvanceTo); the controller's state
  // carries over.
  StepResult AdvanceToTime(double t_end) {
    CheckStepping("advance_to");
    if (!(std::isfinite(t_end) && t_end >= data_.time))
      throw InputError("Simulation.advance_to: t_end must be a finite time >= the current time");
    return Run(StepPolicy::ErrorControlled(), t_end);
  }

  // The scene's step policy (`screwfem run`'s) up to `until` (default: analysis.end_time).
  StepResult Simulate(std::optional<double> until) {
    CheckStepping("simulate");
    const AnalysisSettings& a = scene_.analysis;
    const double t_end = until ? *until : a.end_time;
    if (!(std::isfinite(t_end) && t_end >= data_.time))
      throw InputError("Simulation.simulate: until must be a finite time >= the current time");
    if (a.adaptive_steps) return Run(StepPolicy::ErrorControlled(a.step), t_end);
    const StepSchedule& schedule = Schedule("simulate");
    if (t_end > schedule.end())
      throw InputError(FormatNumbers(
          "Simulation.simulate: until = %.9g s is after the scene's analysis.end_time %.9g s "
          "(its steps end there); raise end_time or step on with step(h)",
          t_end, schedule.end()));
    return Run(StepPolicy::OnSchedule(schedule), t_end);
  }

  StaticResult Statics(const std::optional<StaticOptions>& options) {
    if (in_run_)
      throw std::logic_error(
          "Simulation.solve_static: not inside a run_scene callback (the run "
          "steps the simulation)");
    StaticOptions o = scene_.analysis.statics;
    o.time = data_.time;
    if (options) o = *options;
    ValidateStaticOptions(o, "StaticOptions");
    CheckInputsFinite("Simulation.solve_static");
    data_.time = o.time;
    initialized_ = false;
    PythonSignals signals;
    // A static analysis being recorded: a row per load step, the solution's frame.
    Recording* path = recording_ != nullptr && scene_.analysis.kind == AnalysisKind::kStatic
                          ? recording_
                          : nullptr;
    const double t = o.time;
    // A write error on the recorded path stops the solve at its next Newton iteration.
    const StopRequest stop =
        path != nullptr ? path->StopWhenFinished(signals.request()) : signals.request();
    std::optional<py::error_already_set> hook_error;
    StaticResult r = SolveStatic(model(), data_, o, stop, [&](const StaticStep& step) {
      if (path != nullptr) path->RecordStaticStep(t, step.load_factor);
      if (!step_hook_.is_none() && !hook_error) {
        try {
          step_hook_(step.load_factor, step.load_factor == o.end_load_factor);
        } catch (py::error_already_set& e) {
          hook_error.emplace(std::move(e));
        }
      }
    });
    if (hook_error) throw std::move(*hook_error);
    if (recording_ != nullptr) recording_->SetStaticResult(r);
    if (path != nullptr && r.converged && !path->finished())
      path->RecordStaticSolution(t, r.load_steps == 0);
    if (path != nullptr && path->finished()) ThrowRecordingFailed();
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

  // "" when every run-time input value is finite, else the message naming the first that is
  // not: Simulation.input_values is a writable NumPy view, whose element writes
  // (sim.input_values[0] = nan) no setter sees, so every call that steps or solves checks.
  std::string NonFiniteInput(const std::string& where) const {
    for (Eigen::Index i = 0; i < data_.inputs.size(); ++i)
      if (!std::isfinite(data_.inputs(i))) {
        char value[32];
        std::snprintf(value, sizeof value, "%g", data_.inputs(i));
        return where + ": input_values[" + std::to_string(i) + "] (input '" +
               model().inputs[static_cast<std::size_t>(i)].name + "') is " + value +
               "; run-time inputs must be finite";
      }
    return "";
  }
  void CheckInputsFinite(const std::string& where) const {
    const std::string bad = NonFiniteInput(where);
    if (!bad.empty()) throw InputError(bad);
  }

  // Simulation.record: the recording the steps write to (nullptr: none). A static scene's
  // recording takes solve_static's path; a dynamic one's starts at the first step.
  void Attach(Recording* recording) { recording_ = recording; }
  Recording* recording() const { return recording_; }
  // Simulation.view: a callable hook(t, last) run after every accepted step (t the time, or
  // the load factor of a static load step; last: the call's final step), None: none. It may
  // block (the live view's pause) and raise (the stepping call then raises it).
  void SetStepHook(py::object hook) { step_hook_ = std::move(hook); }
  const py::object& step_hook() const { return step_hook_; }
  // The ParaView frame of the current state (io/vtk.h, binary), composed in memory: the live
  // view's frames. `time` is the frame's TimeValue.
  py::bytes VtkFrame(double time, double load_factor) {
    if (!vtk_) {
      vtk_ = std::make_unique<VtkWriter>();
      vtk_->Open("", model(), VtkFormat::kBinary, 0, false);
    }
    const std::string& image = vtk_->ComposeFrame(model(), data_, time, load_factor);
    return py::bytes(image.data(), image.size());
  }
  // run_scene with a callback steps this simulation: its own stepping is refused meanwhile.
  void SetInRun(bool in_run) { in_run_ = in_run; }
  void SetInitialized() { initialized_ = true; }

 private:
  void CheckStepping(const char* method) const {
    if (in_run_)
      throw std::logic_error(std::string("Simulation.") + method +
                             ": not inside a run_scene callback (the run steps the simulation)");
    if (!initialized_)
      throw std::logic_error(std::string("Simulation.") + method +
                             ": call initialize() first (again after solve_static)");
    if (recording_ != nullptr && scene_.analysis.kind == AnalysisKind::kStatic)
      throw InputError(std::string("Simulation.") + method +
                       ": the recording is of a static analysis (scene.analysis.kind STATIC), "
                       "which records solve_static; set the kind to DYNAMIC before record()");
    CheckInputsFinite(std::string("Simulation.") + method);
  }

  // Advance under `policy` to t_until, with the recording (if any) observing; raises on
  // failure, a signal or a write error.
  StepResult Run(const StepPolicy& policy, double t_until) {
    PythonSignals signals;
    RecordingSteps observer(recording_, step_hook_, data_);
    if (recording_ != nullptr && !recording_->started() && !recording_->finished())
      recording_->Start();
    if (recording_ != nullptr && recording_->finished()) ThrowRecordingFailed();
    const bool observed = recording_ != nullptr || !step_hook_.is_none();
    AdvanceResult r = screwfem::Advance(model(), data_, integrator_, policy, t_until,
                                        observed ? &observer : nullptr, signals.request());
    if (observer.hook_error) throw std::move(*observer.hook_error);
    signals.ThrowIfRaised();
    if (r.stopped) ThrowRecordingFailed();
    if (!r.ok) RaiseSolverError(r.message, py::cast(static_cast<StepResult>(r)));
    return r;
  }

  // The recording's observer for steps driven from Python: the rows and frames due by its
  // clocks only (the end of the run is where the recording is closed, which records it); and
  // the step hook (Simulation.view), after every step. An exception of the hook ends the
  // stepping (hook_error, raised by Run).
  class RecordingSteps : public AdvanceObserver {
   public:
    RecordingSteps(Recording* r, const py::object& hook, const Data& data)
        : r_(r), hook_(hook), data_(data) {}
    void BeforeStep(double t) override {
      if (r_ != nullptr) r_->BeforeStep(t);
    }
    double NextOutputTime() const override {
      return r_ != nullptr ? r_->NextOutputTime() : std::numeric_limits<double>::infinity();
    }
    bool OutputInsideStep(double t) override {
      return r_ != nullptr ? r_->OutputInsideStep(t) : true;
    }
    bool AfterStep(bool last) override {
      if (r_ != nullptr && !r_->AfterStep(false)) return false;
      if (hook_.is_none()) return true;
      try {
        hook_(data_.time, last);
      } catch (py::error_already_set& e) {
        hook_error.emplace(std::move(e));
        return false;
      }
      return true;
    }
    std::optional<py::error_already_set> hook_error;

   private:
    Recording* r_;
    const py::object& hook_;
    const Data& data_;
  };

  [[noreturn]] void ThrowRecordingFailed() const {
    throw std::runtime_error("Simulation.record: writing the files failed: " +
                             recording_->Result().message);
  }

  // The scene's StepSchedule, rebuilt when its analysis times change.
  const StepSchedule& Schedule(const char* method) {
    const AnalysisSettings& a = scene_.analysis;
    const std::array<double, 4> key = {a.start_time, a.end_time, a.step, a.align_steps ? 1.0 : 0.0};
    if (!schedule_ || key != schedule_key_) {
      ValidateTimeGrid(a.start_time, a.end_time, a.step,
                       (std::string("Simulation.") + method + ": scene.analysis").c_str());
      schedule_.emplace(a.start_time, a.end_time, a.step,
                        a.align_steps ? ProfileBreakpoints(model()) : std::vector<double>{});
      schedule_key_ = key;
    }
    return *schedule_;
  }

  static int Named(int index, const char* what, const std::string& name) {
    if (index < 0) throw py::key_error(std::string("no ") + what + " named '" + name + "'");
    return index;
  }

  Scene scene_;
  Data data_;
  Integrator integrator_;
  bool initialized_ = false;
  Recording* recording_ = nullptr;
  bool in_run_ = false;
  std::optional<StepSchedule> schedule_;
  std::array<double, 4> schedule_key_{};
  py::object step_hook_ = py::none();
  std::unique_ptr<VtkWriter> vtk_;
};

}  // namespace screwfem::python
