// Simulation: a Model, its Data and an Integrator for stepping from Python, with the output
// quantities of assemble/outputs.h and io/writers.h and the energies of solve/dynamics.h.
// Every method calls one public C++ function; this file adds only argument checks, name
// lookups and the conversion of numerical failures into screwfem.SolverError.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>

#include <Eigen/Geometry>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <csignal>
#include <cmath>
#include <memory>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "bind.h"
#include "simulation.h"
#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/elements/joint.h"
#include "screwfem/io/recording.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/statics.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {

using Vector = Eigen::VectorXd;

// sim.inputs: the run-time input values by name (a view of Data::inputs; MuJoCo's data.ctrl).
struct InputsView {
  Simulation* sim;
};

// Frames of the given nodes as an (n, 4, 4) array, or their positions (n, 3) or rotations
// (n, 3, 3) (copies).
enum class FramePart { kMatrix, kPosition, kRotation };
py::array_t<double> NodeFrames(const Data& data, const std::vector<int>& nodes, FramePart part) {
  const auto n = static_cast<py::ssize_t>(nodes.size());
  std::vector<py::ssize_t> shape{n, 4, 4};
  if (part == FramePart::kPosition) shape = {n, 3};
  if (part == FramePart::kRotation) shape = {n, 3, 3};
  py::array_t<double> out(shape);
  double* p = out.mutable_data();
  for (int node : nodes) {
    const SE3& H = data.H[static_cast<std::size_t>(node)];
    if (part == FramePart::kPosition) {
      for (int i = 0; i < 3; ++i) *p++ = H.x(i);
      continue;
    }
    const int rows = part == FramePart::kMatrix ? 4 : 3;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < rows; ++c)
        *p++ = part == FramePart::kMatrix ? H.Matrix()(r, c) : H.R(r, c);
  }
  return out;
}

// The row of CalcPointRow / CalcJointRow as a NumPy array (a copy).
Vector ToVector(const std::vector<double>& row) {
  return Eigen::Map<const Vector>(row.data(), static_cast<Eigen::Index>(row.size()));
}

// Simulation.record: a Recording of the simulation's steps, opened on entering the block and
// finished on leaving it (recording.h).
class RecordingHandle {
 public:
  RecordingHandle(Simulation& sim, std::string outdir, std::optional<double> interval, bool force)
      : sim_(sim), outdir_(std::move(outdir)), outputs_(sim.scene().outputs) {
    if (interval) {
      if (!(std::isfinite(*interval) && *interval >= 0.0))
        throw InputError("Simulation.record: interval must be a finite time >= 0 s");
      outputs_.interval = *interval;
    }
    options_.replace_results = force;
  }

  RecordingHandle& Enter() {
    if (recording_) throw std::logic_error("Simulation.record: this recording was entered before");
    if (sim_.recording() != nullptr)
      throw std::logic_error("Simulation.record: the simulation is being recorded already");
    recording_ = std::make_unique<Recording>(sim_.scene(), outputs_, sim_.model(), sim_.data(),
                                             sim_.integrator(), outdir_, options_);
    sim_.Attach(recording_.get());
    return *this;
  }

  // Finishes the recording: "completed" (the current state recorded unless it was), "failed"
  // or "interrupted" for an exception. Never suppresses it.
  bool Exit(const py::object& type, const py::object& value, const py::object&) {
    if (!recording_) return false;
    sim_.Attach(nullptr);
    if (type.is_none()) {
      if (recording_->RecordFinalState()) recording_->Finish("completed", {});
    } else if (PyErr_GivenExceptionMatches(type.ptr(), PyExc_KeyboardInterrupt)) {
      const bool statics = sim_.scene().analysis.kind == AnalysisKind::kStatic;
      recording_->Interrupted(
          SIGINT, statics
                      ? FormatNumbers("at load factor λ = %.9g", recording_->Result().load_factor)
                      : FormatNumbers("at t = %.9g s; the last recorded row is at t = %.9g s",
                                      sim_.data().time, recording_->last_row_time()));
    } else {
      const std::string name = py::str(type.attr("__name__"));
      recording_->Finish("failed", name + ": " + std::string(py::str(value)));
    }
    result_ = recording_->Result();
    recording_.reset();
    return false;
  }

  const std::string& outdir() const { return outdir_; }
  const std::optional<RunResult>& result() const { return result_; }

 private:
  Simulation& sim_;
  std::string outdir_;
  OutputSpec outputs_;
  RunOptions options_;
  std::unique_ptr<Recording> recording_;
  std::optional<RunResult> result_;
};

void BindResults(py::module_& m) {
  py::class_<StepResult>(m, "StepResult", "Outcome of one Simulation.step (dynamics.h).")
      .def_readonly("ok", &StepResult::ok, "The step (or advance) completed.")
      .def_readonly("iterations", &StepResult::iterations,
                    "Newton iterations of this step (all substeps).")
      .def_readonly("substeps", &StepResult::substeps, "1 unless the step was halved.")
      .def_readonly("message", &StepResult::message, "On failure: when and why.")
      .def("__repr__", [](const StepResult& r) {
        return std::string("<screwfem.StepResult ok=") + (r.ok ? "True" : "False") +
               " iterations=" + std::to_string(r.iterations) + ">";
      });

  py::class_<StaticStep>(m, "StaticStep", "One accepted load step of solve_static.")
      .def_readonly("load_factor", &StaticStep::load_factor, "Load factor of this converged step.")
      .def_readonly("iterations", &StaticStep::iterations, "Newton iterations of this step.")
      .def_readonly("residual_norms", &StaticStep::residual_norms,
                    "|R|_inf before each Newton solve, then at convergence [N, N m].");

  py::class_<StaticResult>(m, "StaticResult", "Outcome of Simulation.solve_static (statics.h).")
      .def_readonly("converged", &StaticResult::converged, "The solve reached end_load_factor.")
      .def_readonly("load_factor", &StaticResult::load_factor,
                    "Last converged load factor (end_load_factor when converged): the "
                    "start_load_factor to continue from.")
      .def_readonly("limit_point", &StaticResult::limit_point,
                    "Stopped at a limit point load stepping cannot pass (see message).")
      .def_readonly("limit_points", &StaticResult::limit_points,
                    "Load factors of the limit points an arc-length solve passed.")
      .def_readonly("load_steps", &StaticResult::load_steps, "Accepted load steps.")
      .def_readonly("total_iterations", &StaticResult::total_iterations,
                    "Newton iterations of all load steps.")
      .def_readonly("halvings", &StaticResult::halvings,
                    "Failed load steps retried with half the increment.")
      .def_readonly("steps", &StaticResult::steps, "List of StaticStep (copies).")
      .def_readonly("message", &StaticResult::message, "Why it failed (empty on success).");

  py::class_<Energy>(m, "Energy", "Energies of a state [J] (dynamics.h, CalcEnergy).")
      .def_readonly("kinetic", &Energy::kinetic,
                    "Rigid bodies and rods (consistent with the model's rod inertia).")
      .def_readonly("strain", &Energy::strain, "Rods.")
      .def_readonly("spring", &Energy::spring,
                    "Joint springs (towards their rest, incl. series-elastic drives).")
      .def_readonly("gravity", &Energy::gravity, "Potential of gravity, zero at the world origin.")
      .def("total", &Energy::total, "kinetic + strain + spring + gravity [J].");

  py::class_<SettlingState>(m, "SettlingState",
                            "How far a state is from rest (outputs.h, CalcSettlingState; the "
                            "row of settling.csv).")
      .def_readonly("kinetic", &SettlingState::kinetic, "Kinetic energy [J].")
      .def_readonly("speed", &SettlingState::speed,
                    "Largest translational speed of a free node [m/s].")
      .def_readonly("angular_speed", &SettlingState::angular_speed,
                    "Largest angular speed of a free node [rad/s].")
      .def_readonly("contacts", &SettlingState::contacts,
                    "Active contacts (obstacle pairs and pairs of moving shapes).")
      .def_readonly("slipping", &SettlingState::slipping,
                    "Of them, those slipping under the stick law (0 under the smooth law).")
      .def_readonly("overlap", &SettlingState::overlap, "Deepest overlap of a pair [m].")
      .def_readonly("overlap_ratio", &SettlingState::overlap_ratio,
                    "Deepest overlap relative to the pair's smaller round radius.");

  py::class_<PointMotion>(m, "PointMotion",
                          "World position [m], velocity [m/s] and acceleration [m/s^2] of a point "
                          "(outputs.h); read-only views into this object.")
      .def_readonly("position", &PointMotion::position, "World position [m].")
      .def_readonly("velocity", &PointMotion::velocity, "World velocity [m/s].")
      .def_readonly("acceleration", &PointMotion::acceleration, "World acceleration [m/s^2].");

  py::class_<RodPoint>(m, "RodPoint", "Section frame and motion of a point on a rod (outputs.h).")
      .def_property_readonly(
          "frame", [](const RodPoint& p) { return p.frame.Matrix(); },
          "Section frame H(xi) as a 4x4 matrix [R x; 0 1] in the world frame [m] (a copy).")
      .def_readonly("motion", &RodPoint::motion, "PointMotion of the centre-line point.")
      .def_readonly("element", &RodPoint::element, "Global element index.")
      .def_readonly("xi", &RodPoint::xi, "Position in the element, in [0, 1].");
}

void BindInputs(py::module_& m) {
  py::class_<SimulationState>(m, "SimulationState",
                              "A saved simulation state (Simulation.get_state; dynamics.h).")
      .def_readonly("time", &SimulationState::time, "Simulated time of the saved state [s].")
      .def("__copy__", [](const SimulationState& s) { return s; })
      .def("__deepcopy__", [](const SimulationState& s, py::dict) { return s; });
  py::class_<InputsView>(m, "Inputs", "Simulation.inputs: run-time input values by name.")
      .def("__getitem__",
           [](const InputsView& v, const std::string& name) {
             return v.sim->data().inputs(v.sim->Input(name));
           })
      .def("__setitem__",
           [](InputsView& v, const std::string& name, double value) {
             const int i = v.sim->Input(name);
             if (!std::isfinite(value))
               throw InputError("Simulation.inputs['" + name + "']: must be finite");
             v.sim->data().inputs(i) = value;
           })
      .def("__len__", [](const InputsView& v) { return v.sim->model().inputs.size(); })
      .def("__contains__",
           [](const InputsView& v, const std::string& name) {
             return v.sim->model().FindInput(name) >= 0;
           })
      .def(
          "keys",
          [](const InputsView& v) {
            std::vector<std::string> k;
            for (const ModelInput& in : v.sim->model().inputs) k.push_back(in.name);
            return k;
          },
          "The input names, in model order.")
      .def("__iter__",
           [](const InputsView& v) {
             std::vector<std::string> k;
             for (const ModelInput& in : v.sim->model().inputs) k.push_back(in.name);
             return py::iter(py::cast(k));
           })
      .def(
          "values",
          [](const InputsView& v) {
            const Vector& u = v.sim->data().inputs;
            return std::vector<double>(u.data(), u.data() + u.size());
          },
          "The current input values, in model order.")
      .def("__repr__", [](const InputsView& v) {
        std::string s = "{";
        for (std::size_t i = 0; i < v.sim->model().inputs.size(); ++i) {
          char buf[64];
          std::snprintf(buf, sizeof buf, "%.17g", v.sim->data().inputs(static_cast<long>(i)));
          s += (i ? ", '" : "'") + v.sim->model().inputs[i].name + "': " + buf;
        }
        return s + "}";
      });
}

void BindSimulationClass(py::module_& m) {
  using S = Simulation;
  py::class_<S>(m, "Simulation", R"doc(Simulation(scene)

A Model, its Data and a generalized-alpha Integrator (screwfem::Model, Data, Integrator) for
stepping a scene from Python. The scene is copied: later changes to `scene` do not affect the
simulation (edit `Simulation.scene` instead). The state starts in the reference configuration,
at rest, at analysis.start_time (static analyses: analysis.statics.time).

Typical use: sim.initialize(); then sim.step(h) repeatedly. run_scene does the same, plus the
optional static preload (here: call solve_static() before initialize()), breakpoint-aligned
step ends (StepSchedule) and the files.

Units are SI; point quantities are in the world frame. The arrays v, vdot, lambda_ and
q_joint are NumPy views of the simulation's Data (no copy): they keep the Simulation alive,
stay valid for its whole life and change as it steps; copy them (numpy.copy) to keep a value.
v, vdot and lambda_ are writable (to set a state; call initialize() afterwards to make the
accelerations consistent), q_joint is read-only (set configurations with set_node_frames or
the scene's initial_position). get_state and set_state save and restore the whole state.

Failures: numerical failures raise SolverError (step and solve_static attach their result as
SolverError.result); invalid arguments raise InputError (a ValueError), unknown names KeyError
and indices out of range IndexError.)doc")
      .def(py::init<const Scene&>(), py::arg("scene"))
      .def_property_readonly("scene", &S::scene,
                             "The simulation's copy of the scene (a reference; its analysis "
                             "settings are the defaults of initialize and solve_static).")
      .def_property_readonly("model", &S::model, "The Model (a read-only reference).")
      .def_property(
          "time", [](S& s) { return s.data().time; },
          [](S& s, double t) {
            if (!std::isfinite(t)) throw InputError("Simulation.time: must be finite");
            s.data().time = t;
          },
          "Simulated time [s]. step(h) advances it by h; assigning it changes only the clock at "
          "which profiles are evaluated, not the state (run_scene sets it to each step end of "
          "its StepSchedule this way, so that round-off in t does not accumulate).")
      .def_property(
          "v", [](S& s) -> Vector& { return s.data().v; },
          [](S& s, const Eigen::Ref<const Vector>& v) {
            if (v.size() != s.data().v.size())
              throw InputError("Simulation.v: expected " + std::to_string(s.data().v.size()) +
                               " values, got " + std::to_string(v.size()));
            if (!v.allFinite()) throw InputError("Simulation.v: must be finite");
            s.data().v = v;
          },
          "Velocities (nv; writable view): per free node the body velocity [v (m/s); w (rad/s)] "
          "in the node frame, then the joint-coordinate rates [m/s or rad/s] (Model docs). "
          "Assigning copies into the existing array.")
      .def_property(
          "vdot", [](S& s) -> Vector& { return s.data().vdot; },
          [](S& s, const Eigen::Ref<const Vector>& v) {
            if (v.size() != s.data().vdot.size())
              throw InputError("Simulation.vdot: expected " + std::to_string(s.data().vdot.size()) +
                               " values");
            if (!v.allFinite()) throw InputError("Simulation.vdot: must be finite");
            s.data().vdot = v;
          },
          "Accelerations (nv; writable view): time derivatives of v [m/s^2, rad/s^2], same "
          "layout and frames as v.")
      .def_property(
          "lambda_", [](S& s) -> Vector& { return s.data().lambda; },
          [](S& s, const Eigen::Ref<const Vector>& v) {
            if (v.size() != s.data().lambda.size())
              throw InputError("Simulation.lambda_: expected " +
                               std::to_string(s.data().lambda.size()) + " values");
            if (!v.allFinite()) throw InputError("Simulation.lambda_: must be finite");
            s.data().lambda = v;
          },
          "Lagrange multipliers (nc; writable view): generalised constraint forces [N, N m] "
          "conjugate to the constraint rows (6 relative-frame rows per joint from Joint.row, "
          "one row per prescribed drive from Joint.drive_row; elements/joint.h).")
      .def_property_readonly(
          "q_joint", [](S& s) -> const Vector& { return s.data().q_joint; },
          "Joint coordinates (nv - nv_nodes; read-only view) [m or rad], in velocity order "
          "offset by Model.nv_nodes; exact for abelian joints.")
      .def_property(
          "threads", [](S& s) { return s.data().parallel.threads(); },
          [](S& s, int n) {
            if (n < 1 || n > kMaxAssemblyThreads)
              throw InputError("Simulation.threads: expected an integer from 1 to " +
                               std::to_string(kMaxAssemblyThreads) + ", got " + std::to_string(n));
            SetAssemblyThreads(s.data(), n);
          },
          "Threads of the assembly (the scene's analysis.threads, 'auto' resolved at "
          "construction): the rod elements' kernels run on them, the results are the same "
          "doubles with any number (docs/architecture.md, 'Parallel assembly'). Assigning "
          "starts a new pool of threads (not during a step).")
      .def_property_readonly("initialized", &S::initialized,
                             "initialize() has succeeded since construction or the last "
                             "solve_static().")
      .def_property_readonly(
          "steps", [](const S& s) { return s.integrator().steps; }, "Accepted time steps.")
      .def_property_readonly(
          "iterations", [](const S& s) { return s.integrator().iterations; },
          "Newton iterations of all steps.")
      .def_property_readonly(
          "halvings", [](const S& s) { return s.integrator().halvings; }, "Halved time steps.")
      .def_property_readonly(
          "factorizations", [](const S& s) { return s.integrator().factorizations; },
          "Factorisations of the iteration matrix.")
      .def_property_readonly(
          "symbolic_analyses", [](S& s) { return s.data().sparse.analyses(); },
          "Symbolic analyses of the sparse LU (Model.sparse_solver; 0 for the banded LU): one "
          "per sparsity pattern.")
      .def_property_readonly(
          "sparse_pattern_changes", [](S& s) { return s.data().sparse.pattern_changes(); },
          "Changes of the sparse LU's pattern to another list of contact couplings (the node "
          "blocks of the pairs the broad phase found), analysed or taken from the kept ones.")
      .def_property_readonly(
          "sparse_pattern_hits", [](S& s) { return s.data().sparse.pattern_hits(); },
          "Changes of the sparse LU's pattern that took a kept pattern back (no symbolic "
          "analysis; the last 4 patterns are kept).")
      .def_property_readonly(
          "sparse_factorizations", [](S& s) { return s.data().sparse.factorizations(); },
          "Numerical factorisations by the sparse LU (refactorisations included).")
      .def_property_readonly(
          "sparse_fallbacks", [](S& s) { return s.data().sparse.fallbacks(); },
          "Refactorisations of the sparse LU whose pivots were poor, redone with new pivots.")
      .def_property_readonly(
          "retries", [](const S& s) { return s.integrator().retries; },
          "Steps redone with full Newton from the zero-acceleration start.")
      .def_property_readonly(
          "estimated_convergences",
          [](const S& s) { return s.integrator().estimated_convergences; },
          "Steps accepted by ConvergenceTest.ESTIMATED without a residual at their last iterate.")
      .def_property_readonly(
          "restarts", [](const S& s) { return s.integrator().restarts; },
          "Re-initialisations at profile breakpoints (DynamicOptions.restart_at_breakpoints).")
      .def_property_readonly(
          "perturbed_start_skips", [](const S& s) { return s.integrator().perturbed_start_skips; },
          "Starts and restarts left unperturbed by DynamicOptions.perturbed_start because the "
          "step does not resolve the change of the acceleration.")
      .def_property_readonly(
          "rejected_steps", [](const S& s) { return s.integrator().rejected; },
          "Attempts the error control rejected (advance_to).")
      .def_property_readonly(
          "step_history",
          [](const S& s) {
            const Integrator& i = s.integrator();
            py::dict d;
            d["accepted"] = i.accepted_substeps;
            d["rejected"] = i.rejected;
            d["min_step"] = i.accepted_substeps > 0 ? i.min_h : 0.0;
            d["max_step"] = i.max_h;
            d["mean_step"] = i.accepted_substeps > 0 ? i.sum_h / i.accepted_substeps : 0.0;
            return d;
          },
          "Accepted steps (or substeps), rejected attempts and the smallest, largest and mean "
          "accepted step [s], as summary.json's step_history.")
      .def_property_readonly(
          "error_norm", [](const S& s) { return s.integrator().error_norm; },
          "Weighted local error estimate of the last error-controlled step (accepted if <= 1).")
      .def_property_readonly(
          "max_iterations_in_step",
          [](const S& s) { return s.integrator().max_iterations_in_step; },
          "Most Newton iterations one step took.")

      .def("initialize", &S::Initialize, py::arg("options") = py::none(),
           R"doc(initialize(options=None)

InitializeDynamics: consistent initial accelerations and multipliers (docs/numerics.md, 'Restarts at breakpoints') at the
current time from the current configuration and velocities; allocates the integrator.
`options` (DynamicOptions) defaults to scene.analysis.dynamic. Raises SolverError if the
saddle-point system is singular, InputError for invalid options.)doc")
      .def("step", &S::Advance, py::arg("h") = py::none(),
           R"doc(step(h=None) -> StepResult

Advances the state by one step: of h [s] (Advance with fixed steps of h: generalized-alpha,
possibly in halved substeps, a substep ending on each profile breakpoint inside), or with h
None the next step of the scene's analysis as `screwfem run` takes it (steps of analysis.step on
its schedule: the profile breakpoints inserted with align_steps, the time set to each step end
so that round-off does not accumulate). Returns the StepResult on success. On failure the state
is left at the start of the step and SolverError is raised, with the StepResult (ok False,
message) as its `result`. Requires initialize(). A signal (Ctrl-C) between substeps ends the
call with the signal's exception (KeyboardInterrupt), the state at the end of the last completed
substep. Inside a `record` block the rows and frames due are written.)doc")
      .def("simulate", &S::Simulate, py::arg("until") = py::none(),
           R"doc(simulate(until=None) -> StepResult

Advances under the scene's step policy, exactly as `screwfem run` does, to `until` [s]
(default: analysis.end_time): fixed steps on the analysis schedule, or error-controlled steps
when analysis.step is auto (adaptive_steps). Inside a `record` block it writes what the CLI
writes: `with sim.record(out): sim.simulate()` after initialize() leaves the files of
`screwfem run` bit for bit. Raises like step().)doc")
      .def("advance_to", &S::AdvanceToTime, py::arg("t_end"),
           R"doc(advance_to(t_end) -> StepResult

Error-controlled steps (Advance with error-controlled steps, as AdvanceTo in C++;
docs/numerics.md "Adaptive time steps") until the time is exactly t_end: a local error
estimate per step, a PI controller within the options' min_step and max_step, steps ending on
profile breakpoints. The tolerances are the options'
absolute_tolerance and relative_tolerance (DynamicOptions). Returns the StepResult (substeps:
the accepted steps of this call). Call it with successive output times: the controller keeps
its step between calls. On failure SolverError, the state at the last accepted step.)doc")
      .def(
          "record",
          [](S& s, const std::string& outdir, std::optional<double> interval, bool force) {
            return std::make_unique<RecordingHandle>(s, outdir, interval, force);
          },
          py::arg("outdir"), py::arg("interval") = py::none(), py::arg("force") = false,
          py::keep_alive<0, 1>(),
          R"doc(record(outdir, interval=None, force=False) -> Recording

A context manager that writes, as the simulation steps, exactly what `screwfem run` writes for
the scene: every table its outputs enable (points.csv, joints.csv, reactions.csv, energy.csv,
tendons, forces, actuators and contacts when the model has them), joints.json, summary.json and
the ParaView frames with their collection (vtk/motion.pvd), through the same writers. Rows are
due every `interval` [s] (default: the scene's outputs.interval; 0: every step), and the state
when the block ends is recorded too. `plot` and `view` read the folder like a CLI run's.

    sim.initialize()
    with sim.record("out/arm"):
        while sim.time < 2.0:
            sim.inputs["u"] = controller(sim)
            sim.step()

A dynamic scene records from its first step (the state then, after initialize(), is the first
row); step, simulate and advance_to write the rows and frames due (advance_to and
error-controlled steps interpolate the state at output times inside a step). A static scene
records solve_static: a row per load step and the solution's frame. The folder is refused when
another run holds it or it holds an earlier run's results, unless `force` (then screwfem's
files only are removed). On leaving the block summary.json says "completed"; an exception
inside the block leaves complete files and a summary saying "failed" (SolverError, with its
message) or "interrupted" (KeyboardInterrupt), and propagates. One recording at a time.)doc")
      .def("solve_static", &S::Statics, py::arg("options") = py::none(),
           R"doc(solve_static(options=None) -> StaticResult

SolveStatic: brings the model from the current state to equilibrium under the full loads, with
load stepping (statics.h). `options` (StaticOptions) defaults to scene.analysis.statics with
time = the current time; the simulation's time is set to options.time. Velocities are left as
they were; call initialize() before stepping again. Raises SolverError (result: the
StaticResult) if it does not converge; the state then holds the last converged load step.
A signal (Ctrl-C) between Newton iterations ends the call with the signal's exception
(KeyboardInterrupt), the state at the last converged load step.)doc")

      .def(
          "node_frame", [](S& s, long i) { return s.data().H[s.Node(i)].Matrix(); },
          py::arg("node"))
      .def(
          "node_frame", [](S& s, const std::string& n) { return s.data().H[s.Node(n)].Matrix(); },
          py::arg("node"),
          "node_frame(node) -> 4x4 array\n\nCurrent frame H of a node (index or name) as a "
          "homogeneous matrix [R x; 0 1]: orientation and position [m] in the world frame "
          "(a copy).")
      .def(
          "joint_relative_frame",
          [](S& s, long j) {
            return JointRelativeFrame(s.model(), s.data(), s.JointIndex(j)).Matrix();
          },
          py::arg("joint"))
      .def(
          "joint_relative_frame",
          [](S& s, const std::string& j) {
            return JointRelativeFrame(s.model(), s.data(), s.JointIndex(j)).Matrix();
          },
          py::arg("joint"),
          "joint_relative_frame(joint) -> 4x4 array\n\nRelative frame H_J of a joint (index or "
          "name), from the joint frame on side A to the one on side B [m] (a copy).")

      .def(
          "calc_node_point_motion",
          [](S& s, long node, const Vec3& p) {
            return CalcNodePointMotion(s.model(), s.data(), s.Node(node), p);
          },
          py::arg("node"), py::arg("p") = Vec3::Zero().eval())
      .def(
          "calc_node_point_motion",
          [](S& s, const std::string& node, const Vec3& p) {
            return CalcNodePointMotion(s.model(), s.data(), s.Node(node), p);
          },
          py::arg("node"), py::arg("p") = Vec3::Zero().eval(),
          "calc_node_point_motion(node, p=[0, 0, 0]) -> PointMotion\n\nWorld position [m], "
          "velocity [m/s] and acceleration [m/s^2] of the point p given in the frame of "
          "`node` (index or name) [m] (outputs.h; a fixed node has zero velocity).")
      .def(
          "calc_rod_point_motion",
          [](S& s, long rod, double arc) {
            if (!std::isfinite(arc))
              throw InputError("Simulation.calc_rod_point_motion: s must be finite");
            return CalcRodPointMotion(s.model(), s.data(), s.Rod(rod), arc);
          },
          py::arg("rod"), py::arg("s"))
      .def(
          "calc_rod_point_motion",
          [](S& s, const std::string& rod, double arc) {
            if (!std::isfinite(arc))
              throw InputError("Simulation.calc_rod_point_motion: s must be finite");
            return CalcRodPointMotion(s.model(), s.data(), s.Rod(rod), arc);
          },
          py::arg("rod"), py::arg("s"),
          "calc_rod_point_motion(rod, s) -> RodPoint\n\nSection frame and world motion of the "
          "centre-line point of `rod` (index or name) at reference arc length s [m] from its "
          "first node, clamped to [0, length] (outputs.h).")
      .def(
          "point_motion",
          [](S& s, const std::string& name) {
            const OutputPoint& p = s.OutputPointNamed(name);
            return p.rod >= 0 ? CalcRodPointMotion(s.model(), s.data(), p.rod, p.arc_length).motion
                              : CalcNodePointMotion(s.model(), s.data(), p.node, p.offset);
          },
          py::arg("name"),
          "point_motion(name) -> PointMotion\n\nWorld motion of the scene's output point `name` "
          "(outputs.points), the values of its points.csv columns.")
      .def(
          "calc_point_row",
          [](S& s) {
            std::vector<double> row;
            CalcPointRow(s.model(), s.data(), s.scene().outputs.points, &row);
            return ToVector(row);
          },
          "calc_point_row() -> array\n\nOne points.csv row without t, for the scene's output "
          "points at the current state (columns: point_columns()); world frame, SI (a copy).")
      .def(
          "calc_joint_row",
          [](S& s) {
            std::vector<double> row;
            CalcJointRow(s.model(), s.data(), s.scene().outputs.joints, &row);
            return ToVector(row);
          },
          "calc_joint_row() -> array\n\nOne joints.csv row without t, for the scene's output "
          "joints (columns: joint_columns()); coordinates [m or rad], their first and second "
          "time derivatives and efforts [N or N m] (a copy).")
      .def(
          "point_columns", [](S& s) { return PointColumns(s.scene().outputs.points); },
          "Column names of calc_point_row (those of points.csv after 't').")
      .def(
          "joint_columns", [](S& s) { return JointColumns(s.model(), s.scene().outputs.joints); },
          "Column names of calc_joint_row (those of joints.csv after 't').")

      .def(
          "tendon_state",
          [](S& s, const std::string& name, double load_factor) {
            const LineForceState t =
                CalcTendonState(s.model(), s.data(), s.TendonIndex(name), load_factor);
            return py::make_tuple(t.length, t.rate, t.force);
          },
          py::arg("tendon"), py::arg("load_factor") = 1.0,
          "tendon_state(tendon, load_factor=1.0) -> (length [m], rate [m/s], tension [N]) of a "
          "tendon (name), as tendons.csv records it: the tension applied at `load_factor` (a "
          "static path's, whose rows record the scaled tension; 1 in dynamics).")
      .def(
          "actuator_value",
          [](S& s, const std::string& name) {
            const int a = s.ActuatorIndex(name);
            return ActuatorValue(s.model().actuators[static_cast<std::size_t>(a)], s.data().time,
                                 s.data());
          },
          py::arg("actuator"),
          "actuator_value(actuator) -> its profile's value now (pressure [Pa], activation, or "
          "factor), as actuators.csv records it.")
      .def(
          "rod_stresses",
          [](S& s, const std::string& r) {
            std::vector<Vec6> total, elastic;
            CalcRodStresses(s.model(), s.data(), s.Rod(r), &total, &elastic);
            const auto array = [](const std::vector<Vec6>& v) {
              py::array_t<double> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{6}});
              auto w = out.mutable_unchecked<2>();
              for (std::size_t i = 0; i < v.size(); ++i)
                for (int k = 0; k < 6; ++k) w(static_cast<py::ssize_t>(i), k) = v[i](k);
              return out;
            };
            return py::make_tuple(array(total), array(elastic));
          },
          py::arg("rod"),
          "rod_stresses(rod) -> (total, elastic), two (num_elements, 6) arrays of section "
          "stress resultants [N, N m] (N, V2, V3, T, M2, M3): what each element transmits, "
          "K (eps - eps0) - sigma_a, and its elastic part K (eps - eps0).")
      .def(
          "rod_fields",
          [](S& s, const std::string& r) {
            std::vector<double> rows;  // CalcRodFieldRows, as rod_fields.csv without its t
            CalcRodFieldRows(s.model(), s.data(), s.Rod(r), 1.0, &rows);
            const auto n = static_cast<py::ssize_t>(rows.size() / kRodFieldValues);
            py::array_t<double> out({n, py::ssize_t{kRodFieldValues + 1}});
            auto w = out.mutable_unchecked<2>();
            for (py::ssize_t i = 0; i < n; ++i) {
              w(i, 0) = s.data().time;
              for (py::ssize_t k = 0; k < kRodFieldValues; ++k)
                w(i, k + 1) = rows[static_cast<std::size_t>(i * kRodFieldValues + k)];
            }
            return out;
          },
          py::arg("rod"),
          "rod_fields(rod) -> (num_elements, 15) array, the rows of rod_fields.csv for one rod "
          "(name) now: t, rod (index), s (the element's mid arc length [m]), gamma1 gamma2 "
          "gamma3 (extension, shears), kappa1 kappa2 kappa3 (twist, curvatures [1/m]), n1 n2 n3 "
          "[N], m1 m2 m3 [N m]; section components, axis 1 along the rod (CalcRodFieldRows, "
          "assemble/outputs.h; actuation at full value, as in dynamics).")
      .def(
          "force_element_state",
          [](S& s, const std::string& name, double load_factor) {
            const LineForceState f =
                CalcForceElementState(s.model(), s.data(), s.ForceElementIndex(name), load_factor);
            return py::make_tuple(f.length, f.rate, f.force);
          },
          py::arg("element"), py::arg("load_factor") = 1.0,
          "force_element_state(element, load_factor=1.0) -> (length [m], rate [m/s], force [N], "
          "positive in tension) of a force element (name), as forces.csv records it: its actuator "
          "scaled by `load_factor` (a static path's; 1 in dynamics).")
      .def(
          "contact_states",
          [](S& s) {
            py::list out;
            for (int i = 0; i < static_cast<int>(s.model().contact_pairs.size()); ++i) {
              const ContactState c = CalcContactState(s.model(), s.data(), i);
              if (!c.active) continue;
              out.append(
                  py::dict(py::arg("pair") = i, py::arg("point") = c.point,
                           py::arg("normal") = c.normal, py::arg("normal_force") = c.normal_force,
                           py::arg("friction_force") = c.friction_force, py::arg("gap") = c.gap,
                           py::arg("slipping") = c.slipping, py::arg("deflection") = c.deflection,
                           py::arg("friction_share") = c.friction_share));
            }
            return out;
          },
          "The active contacts as contacts.csv records them: a list of dicts with pair, point "
          "[m], normal, normal_force [N], friction_force [N] (world), gap [m], slipping (stick "
          "law), deflection [m] (the anchor's elastic deflection) and friction_share (|f_t| / "
          "(mu_s f_n)).")
      .def(
          "pair_contact_states",
          [](S& s) {
            py::list out;
            UpdateShapePairs(s.model(), s.data());  // the pairs of the state as it is now
            for (int i = 0; i < s.data().num_shape_pairs; ++i) {
              const ShapePairState c = CalcShapePairState(s.model(), s.data(), i);
              if (!c.active) continue;
              const ShapePair& p = s.data().shape_pairs[static_cast<std::size_t>(i)];
              out.append(
                  py::dict(py::arg("pair") = static_cast<long>(ShapePairKey(s.model(), p)),
                           py::arg("rod_a") = p.side[0].rod, py::arg("owner_a") = p.side[0].owner,
                           py::arg("rod_b") = p.side[1].rod, py::arg("owner_b") = p.side[1].owner,
                           py::arg("point_a") = c.point[0], py::arg("point_b") = c.point[1],
                           py::arg("normal") = c.normal, py::arg("normal_force") = c.normal_force,
                           py::arg("friction_force") = c.friction_force, py::arg("gap") = c.gap,
                           py::arg("part") = p.part, py::arg("slipping") = c.slipping,
                           py::arg("deflection") = c.deflection,
                           py::arg("friction_share") = c.friction_share));
            }
            return out;
          },
          "The active contacts between moving shapes as pair_contacts.csv records them: dicts "
          "with pair (the key of its two contact segments), rod_a/owner_a, rod_b/owner_b, "
          "point_a and point_b [m], normal (from B to "
          "A), normal_force [N], friction_force [N] (on A, world), gap [m], part (0 or 1: "
          "the two ends of a segment clipped to a box face; -1: a pair's single point), and "
          "as contact_states slipping, deflection [m] and friction_share.")
      .def(
          "joint_coordinate",
          [](S& s, long j, int c) {
            return s.data().q_joint(s.JointDof(s.JointIndex(j), c) - s.model().nv_nodes);
          },
          py::arg("joint"), py::arg("c") = 0)
      .def(
          "joint_coordinate",
          [](S& s, const std::string& j, int c) {
            return s.data().q_joint(s.JointDof(s.JointIndex(j), c) - s.model().nv_nodes);
          },
          py::arg("joint"), py::arg("c") = 0,
          "joint_coordinate(joint, c=0) -> float\n\nCoordinate c of a joint (index or name) "
          "[m or rad].")
      .def(
          "joint_velocity",
          [](S& s, long j, int c) { return s.data().v(s.JointDof(s.JointIndex(j), c)); },
          py::arg("joint"), py::arg("c") = 0)
      .def(
          "joint_velocity",
          [](S& s, const std::string& j, int c) {
            return s.data().v(s.JointDof(s.JointIndex(j), c));
          },
          py::arg("joint"), py::arg("c") = 0,
          "joint_velocity(joint, c=0) -> float\n\nRate of coordinate c [m/s or rad/s].")
      .def(
          "joint_acceleration",
          [](S& s, long j, int c) { return s.data().vdot(s.JointDof(s.JointIndex(j), c)); },
          py::arg("joint"), py::arg("c") = 0)
      .def(
          "joint_acceleration",
          [](S& s, const std::string& j, int c) {
            return s.data().vdot(s.JointDof(s.JointIndex(j), c));
          },
          py::arg("joint"), py::arg("c") = 0,
          "joint_acceleration(joint, c=0) -> float\n\nSecond time derivative of coordinate c "
          "[m/s^2 or rad/s^2].")
      .def(
          "joint_effort",
          [](S& s, long j, int c) {
            const int jj = s.JointIndex(j);
            s.JointDof(jj, c);
            return JointCoordinateEffort(s.model(), s.data(), jj, c);
          },
          py::arg("joint"), py::arg("c") = 0)
      .def(
          "joint_effort",
          [](S& s, const std::string& j, int c) {
            const int jj = s.JointIndex(j);
            s.JointDof(jj, c);
            return JointCoordinateEffort(s.model(), s.data(), jj, c);
          },
          py::arg("joint"), py::arg("c") = 0,
          "joint_effort(joint, c=0) -> float\n\nGeneralised force on coordinate c [N or N m] "
          "(writers.h, JointCoordinateEffort): the drive's effort on the driven coordinate, "
          "otherwise -(K (alpha - rest) + D alpha_dot) of the joint's spring and damper, "
          "otherwise 0.")

      .def_property_readonly(
          "inputs", [](S& s) { return InputsView{&s}; }, py::keep_alive<0, 1>(),
          "The run-time input values by name (the scene's inputs section; MuJoCo's data.ctrl): "
          "sim.inputs['u'] = 0.3 between steps sets the value every profile of type input "
          "named u takes during the next steps. Supports [], len, iteration over the names, "
          "keys(), values() and 'name' in.")
      .def_property(
          "input_values", [](S& s) -> Vector& { return s.data().inputs; },
          [](S& s, const Eigen::Ref<const Vector>& u) {
            if (u.size() != s.data().inputs.size())
              throw InputError("Simulation.input_values: expected " +
                               std::to_string(s.data().inputs.size()) + " values, got " +
                               std::to_string(u.size()));
            if (!u.allFinite()) throw InputError("Simulation.input_values: must be finite");
            s.data().inputs = u;
          },
          "All input values in Model.inputs order (writable view of Data::inputs).")
      .def(
          "restart",
          [](S& s) {
            if (!s.initialized())
              throw std::logic_error("Simulation.restart: call initialize() first");
            std::string why;
            if (!RestartDynamics(s.model(), s.data(), s.integrator(), &why))
              RaiseSolverError(why, py::none());
          },
          "restart()\n\nRestartDynamics: consistent accelerations and multipliers at the current "
          "state, time and input values, as at a profile breakpoint. Stepping does not restart "
          "when an input changes (docs/numerics.md, \"Run-time inputs\"); call this after a "
          "large jump of an input if its ringing in the accelerations matters.")
      .def(
          "set_joint_stiffness",
          [](S& s, const std::string& j, const Eigen::Ref<const Vector>& k) {
            s.SetJointSprings(s.JointIndex(j), k, false);
          },
          py::arg("joint"), py::arg("stiffness"),
          "set_joint_stiffness(joint, stiffness)\n\nThe joint's spring stiffness per spring "
          "(JointSpringCount values, >= 0) [N/m or N m/rad], from the next step on (the "
          "simulation's own copy of the model; scene unchanged).")
      .def(
          "set_joint_damping",
          [](S& s, const std::string& j, const Eigen::Ref<const Vector>& d) {
            s.SetJointSprings(s.JointIndex(j), d, true);
          },
          py::arg("joint"), py::arg("damping"),
          "set_joint_damping(joint, damping)\n\nThe joint's damper values, as "
          "set_joint_stiffness.")
      .def(
          "get_state", [](S& s) { return s.GetState(); },
          "get_state() -> SimulationState\n\nA copy of everything stepping continues from "
          "(time, node and joint frames, joint coordinates, velocities, accelerations, "
          "multipliers, input values, the integrator's auxiliary acceleration; "
          "SaveSimulationState). set_state(s) and stepping repeats the same steps bit for bit.")
      .def(
          "set_state", [](S& s, const SimulationState& st) { s.SetState(st); }, py::arg("state"),
          "set_state(state)\n\nRestores a state from get_state() of a simulation of the same "
          "scene (InputError if the sizes differ). The integrator stays initialised.")
      .def(
          "node_frames",
          [](S& s) {
            std::vector<int> all(s.model().nodes.size());
            for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
            return NodeFrames(s.data(), all, FramePart::kMatrix);
          },
          "node_frames() -> (n, 4, 4) array\n\nEvery node's frame H (a copy).")
      .def(
          "set_node_frames",
          [](S& s, const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
            const auto n = static_cast<py::ssize_t>(s.data().H.size());
            if (a.ndim() != 3 || a.shape(0) != n || a.shape(1) != 4 || a.shape(2) != 4)
              throw InputError("Simulation.set_node_frames: expected an array of shape (" +
                               std::to_string(n) + ", 4, 4)");
            const double* p = a.data();
            for (py::ssize_t i = 0; i < n; ++i, p += 16) {
              SE3 H;
              for (int r = 0; r < 3; ++r) {
                for (int c = 0; c < 3; ++c) H.R(r, c) = p[4 * r + c];
                H.x(r) = p[4 * r + 3];
              }
              if (!H.R.allFinite() || !H.x.allFinite() ||
                  (H.R.transpose() * H.R - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-9 ||
                  H.R.determinant() < 0.0)
                throw InputError("Simulation.set_node_frames: frame " + std::to_string(i) +
                                 " is not a finite rigid transformation");
              s.data().H[static_cast<std::size_t>(i)] = H;
            }
          },
          py::arg("frames"),
          "set_node_frames(frames)\n\nSets every node's frame from an (n, 4, 4) array (the "
          "caller keeps fixed nodes and joints consistent; call initialize() before stepping).")
      .def(
          "rod_centerline",
          [](S& s, const std::string& r) {
            return NodeFrames(s.data(), s.model().rods[s.Rod(r)].nodes, FramePart::kPosition);
          },
          py::arg("rod"))
      .def(
          "rod_centerline",
          [](S& s, long r) {
            return NodeFrames(s.data(), s.model().rods[s.Rod(r)].nodes, FramePart::kPosition);
          },
          py::arg("rod"),
          "rod_centerline(rod) -> (n, 3) array\n\nWorld positions [m] of the rod's n nodes "
          "(num_elements + 1), from its first node (a copy).")
      .def(
          "rod_rotations",
          [](S& s, const std::string& r) {
            return NodeFrames(s.data(), s.model().rods[s.Rod(r)].nodes, FramePart::kRotation);
          },
          py::arg("rod"))
      .def(
          "rod_rotations",
          [](S& s, long r) {
            return NodeFrames(s.data(), s.model().rods[s.Rod(r)].nodes, FramePart::kRotation);
          },
          py::arg("rod"),
          "rod_rotations(rod) -> (n, 3, 3) array\n\nSection rotations R (columns: the section "
          "axes in world components) at the rod's n nodes (a copy).")

      .def(
          "joint_reaction",
          [](S& s, const std::string& j) {
            return CalcJointReaction(s.model(), s.data(), s.JointIndex(j));
          },
          py::arg("joint"))
      .def(
          "joint_reaction",
          [](S& s, long j) { return CalcJointReaction(s.model(), s.data(), s.JointIndex(j)); },
          py::arg("joint"),
          "joint_reaction(joint) -> array(6)\n\nForce [N] and moment [N m] the joint transmits "
          "to its side B, world components, moment about the joint point on side B "
          "(CalcJointReaction; the reactions.csv columns).")
      .def(
          "calc_momentum", [](S& s) { return CalcMomentum(s.model(), s.data()); },
          "calc_momentum() -> array(6)\n\nLinear [kg m/s] and angular momentum about the world "
          "origin [kg m^2/s], world components (CalcMomentum; energy.csv px..Lz).")
      .def(
          "body_orientation",
          [](S& s, const std::string& b) {
            const int i = s.model().FindBody(b);
            if (i < 0) throw py::key_error("no rigid body named '" + b + "'");
            const Eigen::Quaterniond q(
                s.data()
                    .H[static_cast<std::size_t>(s.model().bodies[static_cast<std::size_t>(i)].node)]
                    .R);
            Eigen::Vector4d out(q.w(), q.x(), q.y(), q.z());
            if (out(0) < 0.0) out = -out;
            return out;
          },
          py::arg("body"),
          "body_orientation(body) -> array(4)\n\nOrientation of a rigid body's frame as a unit "
          "quaternion [w, x, y, z] (w >= 0), world from body.")
      .def(
          "body_angular_velocity",
          [](S& s, const std::string& b) {
            const int i = s.model().FindBody(b);
            if (i < 0) throw py::key_error("no rigid body named '" + b + "'");
            const Node& n = s.model().nodes[static_cast<std::size_t>(
                s.model().bodies[static_cast<std::size_t>(i)].node)];
            if (n.dof < 0) return Vec3::Zero().eval();
            return Vec3(
                s.data()
                    .H[static_cast<std::size_t>(s.model().bodies[static_cast<std::size_t>(i)].node)]
                    .R *
                s.data().v.segment<3>(n.dof + 3));
          },
          py::arg("body"),
          "body_angular_velocity(body) -> array(3)\n\nAngular velocity of a rigid body [rad/s], "
          "world components.")
      .def(
          "calc_energy", [](S& s) { return CalcEnergy(s.model(), s.data()); },
          "calc_energy() -> Energy\n\nKinetic, strain, spring and gravity energies of the "
          "current state [J] (CalcEnergy).")
      .def(
          "calc_settling",
          [](S& s) {
            return CalcSettlingState(s.model(), s.data(),
                                     s.scene().analysis.kind != AnalysisKind::kStatic);
          },
          "calc_settling() -> SettlingState\n\nKinetic energy, largest node speeds, active and "
          "slipping contacts and the deepest overlap of the current state (settling.csv's row).")
      .def(
          "view",
          [](py::object self, int port, bool open_browser, const std::string& host,
             py::object max_rate, py::object pause_timeout) {
            return py::module_::import("screwfem._live")
                .attr("LiveView")(self, py::arg("port") = port,
                                  py::arg("open_browser") = open_browser, py::arg("host") = host,
                                  py::arg("max_rate") = max_rate,
                                  py::arg("pause_timeout") = pause_timeout);
          },
          py::arg("port") = 0, py::arg("open_browser") = false, py::arg("host") = "127.0.0.1",
          py::arg("max_rate") = 30.0, py::arg("pause_timeout") = py::none(),
          "view(port=0, open_browser=False, host='127.0.0.1', max_rate=30.0, "
          "pause_timeout=None) -> LiveView\n\nLive view: serves the browser viewer "
          "(tools/viewer) on http://host:port/ (port 0: a free one) from a background thread "
          "and pushes the simulation's frame to every connected page over a WebSocket after "
          "each step(), advance_to(), simulate() and static load step (the last step of every "
          "call; the steps inside one call at most max_rate frames per second of wall time, "
          "None or 0: all). Nothing is built while no page is connected. The page's Pause "
          "button pauses the simulation: a step taken while paused waits at its end until "
          "the page resumes, every page has gone, close() is called or pause_timeout seconds "
          "have passed. Returns a LiveView (screwfem/_live.py) with .url, .close() and "
          "context-manager support; docs/python.md, 'Live view'. Needs Debian's "
          "python3-websockets.")
      .def(
          "_set_step_hook", [](S& s, py::object hook) { s.SetStepHook(std::move(hook)); },
          py::arg("hook"),
          "_set_step_hook(hook)\n\nhook(t, last) after every accepted step (None: none); "
          "used by view().")
      .def(
          "_step_hook", [](S& s) { return s.step_hook(); },
          "_step_hook() -> callable or None\n\nThe hook _set_step_hook set.")
      .def(
          "_vtk_frame",
          [](S& s, double time, double load_factor) { return s.VtkFrame(time, load_factor); },
          py::arg("time"), py::arg("load_factor") = 1.0,
          "_vtk_frame(time, load_factor=1.0) -> bytes\n\nThe ParaView frame of the current "
          "state (io/vtk.h, binary), as view() sends it.")
      .def(
          "max_constraint_violation",
          [](S& s) { return MaxConstraintViolation(s.model(), s.data(), s.data().time, 1.0); },
          "max_constraint_violation() -> float\n\nLargest |phi| over all constraint rows at the "
          "current state and time [m or rad] (MaxConstraintViolation; overwrites only the "
          "residual workspace).");
}

}  // namespace

void BindRecording(py::module_& m) {
  py::class_<RecordingHandle>(m, "Recording",
                              "Simulation.record(outdir): a context manager writing the run's "
                              "files as the simulation steps (recording.h).")
      .def("__enter__", &RecordingHandle::Enter, py::return_value_policy::reference_internal)
      .def("__exit__", &RecordingHandle::Exit)
      .def_property_readonly("outdir", &RecordingHandle::outdir, "The output folder.")
      .def_property_readonly(
          "result", &RecordingHandle::result,
          "The RunResult once the block has ended (status in summary.json), else None.");
}

void BindSimulation(py::module_& m) {
  BindResults(m);
  BindInputs(m);
  BindSimulationClass(m);
  BindRecording(m);
}

}  // namespace screwfem::python
