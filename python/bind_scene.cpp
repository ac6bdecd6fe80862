// Scenes and runs (include/screwfem/io/scene.h, run.h; solve/schedule.h) and the solver
// settings they carry (solve/dynamics.h, solve/statics.h). Settings are plain read-write
// structures; nested settings are references into their owner (scene.analysis.dynamic.rho_inf
// = 1 edits the scene).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bind.h"
#include "screwfem/model/memory.h"
#include "simulation.h"
#include "screwfem/io/input_table.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/statics.h"

namespace py = pybind11;

namespace screwfem::python {

// A memory size from Python: None (0: the process default), a positive int of bytes, or a
// size text such as '8G' (ParseMemorySize).
std::size_t MemorySize(const py::object& v, const std::string& setting) {
  if (v.is_none()) return 0;
  if (py::isinstance<py::str>(v)) return ParseMemorySize(v.cast<std::string>(), setting);
  if (py::isinstance<py::bool_>(v) || !py::isinstance<py::int_>(v) ||
      v.cast<py::int_>() <= py::int_(0))
    throw InputError(setting + ": expected None, a number of bytes > 0 or a size such as '8G'");
  return v.cast<std::size_t>();
}

namespace {

bool OnMainThread() {
  const py::module_ threading = py::module_::import("threading");
  return threading.attr("current_thread")().is(threading.attr("main_thread")());
}

// The process default for the length of one call (max_memory of load_scene, parse_scene).
class ScopedMemoryLimit {
 public:
  ScopedMemoryLimit(const py::object& size, const std::string& setting)
      : old_(DefaultMemoryLimit()), set_(!size.is_none()) {
    if (set_) SetDefaultMemoryLimit(MemorySize(size, setting));
  }
  ~ScopedMemoryLimit() {
    if (set_) SetDefaultMemoryLimit(old_);
  }
  ScopedMemoryLimit(const ScopedMemoryLimit&) = delete;
  ScopedMemoryLimit& operator=(const ScopedMemoryLimit&) = delete;

 private:
  std::size_t old_;
  bool set_;
};

// run_scene with a callback: RunScene on the state of a Simulation that the callback receives.
// The run stops (as interrupted) once the callback has raised, and the exception is raised
// again after the files are complete.
RunResult RunWithCallback(const Scene& scene, const std::string& outdir, RunOptions options,
                          const py::object& callback, long every) {
  if (every < 1) throw InputError("run_scene: every must be a number of steps >= 1");
  if (!PyCallable_Check(callback.ptr())) throw InputError("run_scene: callback must be callable");
  py::object sim_object = py::module_::import("screwfem._screwfem").attr("Simulation")(scene);
  Simulation& sim = sim_object.cast<Simulation&>();
  struct State {
    PythonSignals signals;
    StopRequest signal_request;
    std::optional<py::error_already_set> error;
    static bool Poll(void* self) {
      auto* s = static_cast<State*>(self);
      return s->error.has_value() || s->signal_request.Requested();
    }
  } state;
  if (OnMainThread()) state.signal_request = state.signals.request();
  const auto call = [&] {
    try {
      callback(sim_object);
      // Inputs written through the input_values view: the run must not step on a NaN.
      const std::string bad = sim.NonFiniteInput("run_scene: after the callback");
      if (!bad.empty()) {
        PyErr_SetString(PyExc_ValueError, bad.c_str());
        throw py::error_already_set();
      }
    } catch (py::error_already_set& e) {
      state.error.emplace(std::move(e));
    }
  };
  sim.SetInRun(true);
  call();
  if (state.error) {
    sim.SetInRun(false);
    throw std::move(*state.error);
  }
  long steps = 0;
  options.on_step = [&](double) {
    if (++steps % every == 0 && !state.error) call();
  };
  options.stop = StopRequest{nullptr, &State::Poll, &state};
  RunResult r;
  try {
    r = RunScene(sim.scene(), sim.data(), sim.integrator(), outdir, options);
  } catch (...) {
    sim.SetInRun(false);
    throw;
  }
  sim.SetInRun(false);
  if (r.ok && scene.analysis.kind == AnalysisKind::kDynamic) sim.SetInitialized();
  if (state.error) throw std::move(*state.error);
  state.signals.ThrowIfRaised();
  return r;
}

void BindSettings(py::module_& m) {
  py::class_<GeneralizedAlpha>(m, "GeneralizedAlpha",
                               "Generalized-alpha parameters (Chung-Hulbert), dimensionless.")
      .def_readonly("alpha_m", &GeneralizedAlpha::alpha_m,
                    "alpha_m of the generalized-alpha scheme (Chung and Hulbert), from rho_inf.")
      .def_readonly("alpha_f", &GeneralizedAlpha::alpha_f,
                    "alpha_f of the generalized-alpha scheme, from rho_inf.")
      .def_readonly("gamma", &GeneralizedAlpha::gamma, "gamma = 1/2 + alpha_f - alpha_m.")
      .def_readonly("beta", &GeneralizedAlpha::beta, "beta = (gamma + 1/2)^2 / 4.")
      .def_static("from_spectral_radius", &GeneralizedAlpha::FromSpectralRadius, py::arg("rho_inf"),
                  "Chung-Hulbert parameters from the spectral radius at infinity rho in [0, 1].");

  BindEnum<NewtonMatrix>(m, "NewtonMatrix",
                         "When the dynamic iteration matrix is factorised (dynamics.h).");
  BindEnum<Predictor>(m, "Predictor", "Acceleration each step's iteration starts from.");
  BindEnum<ConvergenceTest>(m, "ConvergenceTest",
                            "Where the residual and constraint tests of a step are applied.");
  BindEnum<ConstraintFormulation>(m, "ConstraintFormulation",
                                  "How joint constraints enter a step: index 3, stabilised "
                                  "index 2 (GGL) or auto (GGL without rods).");

  m.attr("AUTO_RHO_INF") = kAutoRhoInf;
  py::class_<DynamicOptions>(m, "DynamicOptions",
                             "Settings of the generalized-alpha integrator (dynamics.h). Checked "
                             "when used (ValidateDynamicOptions): out-of-range values, tolerances "
                             "that are not finite and > 0, and unknown enum values raise "
                             "InputError.")
      .def(py::init<>())
      .def_readwrite("rho_inf", &DynamicOptions::rho_inf,
                     "Spectral radius at infinity in [0, 1] (1: no numerical damping); negative "
                     "(the default, AUTO_RHO_INF): 0.9, or 0 in a model with contact.")
      .def_readwrite("line_search", &DynamicOptions::line_search,
                     "Contact line search: in a model with contact (index 3), a Newton "
                     "correction after which the residual grew is halved (up to 6 times).")
      .def_readwrite("max_iterations", &DynamicOptions::max_iterations,
                     "Newton iterations per step, in [1, 1000].")
      .def_readwrite("max_halvings", &DynamicOptions::max_halvings,
                     "A failed step is retried as 2, 4, ... 2^max_halvings substeps; in [0, 30].")
      .def_readwrite("increment_tolerance", &DynamicOptions::increment_tolerance,
                     "Last Newton correction of the positions (translations relative to the "
                     "model's length scale, rotations [rad] and joint coordinates as they are).")
      .def_readwrite("constraint_tolerance", &DynamicOptions::constraint_tolerance,
                     "Every constraint |phi| [m or rad].")
      .def_readwrite("residual_tolerance", &DynamicOptions::residual_tolerance,
                     "Residual relative to its largest force term.")
      .def_readwrite("use_tangent_operator", &DynamicOptions::use_tangent_operator,
                     "T(h dq) on node columns of the iteration matrix.")
      .def_readwrite("newton_matrix", &DynamicOptions::newton_matrix,
                     "Full or simplified Newton (NewtonMatrix).")
      .def_readwrite("refresh_ratio", &DynamicOptions::refresh_ratio,
                     "Simplified Newton switches to full Newton for the rest of a step when a "
                     "correction shrinks by less than this factor.")
      .def_readwrite("predictor", &DynamicOptions::predictor, "Start of each step (Predictor).")
      .def_readwrite("convergence", &DynamicOptions::convergence,
                     "Where the residual tests apply (ConvergenceTest).")
      .def_readwrite("restart_at_breakpoints", &DynamicOptions::restart_at_breakpoints,
                     "End a substep on every breakpoint of a drive or load profile and "
                     "re-initialise accelerations and multipliers there (right limits), as at "
                     "the start.")
      .def_readwrite("perturbed_start", &DynamicOptions::perturbed_start,
                     "After the start and each restart, the auxiliary acceleration "
                     "a = vdot + (alpha_m - alpha_f) (vdot one step ahead - vdot) instead of "
                     "a = vdot (fixed steps; second-order efforts with rho_inf < 1 under GGL). "
                     "Default True.")
      .def_readwrite("constraints", &DynamicOptions::constraints,
                     "INDEX3 (position constraints), GGL (also the velocity constraints, "
                     "stabilised index 2: round-off velocity constraints, second-order "
                     "multipliers and efforts) or AUTO (the default: GGL for a model without "
                     "rods, INDEX3 for one with rods).")
      .def_readwrite("absolute_tolerance", &DynamicOptions::absolute_tolerance,
                     "Error-controlled steps (Simulation.advance_to): absolute local error per "
                     "step (translations relative to the model's length scale, rotations and "
                     "joint coordinates as they are); > 0.")
      .def_readwrite("relative_tolerance", &DynamicOptions::relative_tolerance,
                     "Error-controlled steps: local error relative to the step's own motion "
                     "|h dq|; >= 0.")
      .def_readwrite("min_step", &DynamicOptions::min_step,
                     "Error-controlled steps: smallest step [s] (below it the step fails); > 0.")
      .def_readwrite("max_step", &DynamicOptions::max_step,
                     "Error-controlled steps: largest step [s] (inf: none); >= min_step.")
      .def_readwrite("initial_step", &DynamicOptions::initial_step,
                     "Error-controlled steps: the first step [s] (0: 1e-3 of the first "
                     "advance_to's span).");

  BindEnum<StaticMethod>(m, "StaticMethod",
                         "How a static solution follows its path (statics.h): LOAD (load "
                         "stepping) or ARCLENGTH (arc-length continuation).");

  py::class_<StaticOptions>(m, "StaticOptions",
                            "Settings of the static solver: load stepping or arc-length "
                            "continuation (statics.h). Checked when used (ValidateStaticOptions), "
                            "raising InputError.")
      .def(py::init<>())
      .def_readwrite("time", &StaticOptions::time,
                     "Time at which the profiles of loads and drives are evaluated [s].")
      .def_readwrite("method", &StaticOptions::method, "StaticMethod.LOAD or .ARCLENGTH.")
      .def_readwrite("start_load_factor", &StaticOptions::start_load_factor,
                     "The load factor the current state is in equilibrium at (0 from rest; an "
                     "earlier solve_static's load_factor to continue from where it ended).")
      .def_readwrite("end_load_factor", &StaticOptions::end_load_factor,
                     "The load factor to reach (may be below start_load_factor: unloading).")
      .def_readwrite("max_steps", &StaticOptions::max_steps,
                     "Accepted steps at most (0: 2 load_steps + 1000); the solve stops there.")
      .def_readwrite("arc_length", &StaticOptions::arc_length,
                     "First arc length (0: |dx/ds| (end - start) / load_steps).")
      .def_readwrite("arc_length_min", &StaticOptions::arc_length_min,
                     "Smallest arc length (0: the first / 2^max_halvings).")
      .def_readwrite("arc_length_max", &StaticOptions::arc_length_max,
                     "Largest arc length (0: 10 x the first).")
      .def_readwrite("desired_iterations", &StaticOptions::desired_iterations,
                     "Newton solves per arc-length step the step-length controller aims at.")
      .def_readwrite("psi", &StaticOptions::psi,
                     "Load term of the arc-length constraint: 0 cylindrical, 1 spherical.")
      .def_readwrite("rotation_weight", &StaticOptions::rotation_weight,
                     "Weight of rotations in the arc-length metric (0: translations only).")
      .def_readwrite("constraint_force_tangent", &StaticOptions::constraint_force_tangent,
                     "Exact tangent with d(B^T lambda)/dq (scene key exact_tangent).")
      .def_readwrite("load_steps", &StaticOptions::load_steps,
                     "Initial number of equal load increments, in [1, 1000000].")
      .def_readwrite("max_halvings", &StaticOptions::max_halvings,
                     "Halvings of the first load increment (arc length) down to the smallest, "
                     "in [0, 30].")
      .def_readwrite("max_iterations", &StaticOptions::max_iterations,
                     "Newton iterations per load step, in [1, 1000].")
      .def_readwrite("residual_tolerance", &StaticOptions::residual_tolerance,
                     "|R|_inf relative to the largest force term in R.")
      .def_readwrite("increment_tolerance", &StaticOptions::increment_tolerance,
                     "Last Newton increment (translations relative to the model's length scale, "
                     "rotations [rad]).")
      .def_readwrite("constraint_tolerance", &StaticOptions::constraint_tolerance,
                     "|phi|_inf [m or rad].");

  BindEnum<AnalysisKind>(m, "AnalysisKind", "What a scene's analysis does (scene.h).");

  py::class_<RestCriterion>(m, "RestCriterion",
                            "When a dynamic run has come to rest (solve/rest.h; the scene's "
                            "analysis.stop_at_rest).")
      .def(py::init<>())
      .def_readwrite("enabled", &RestCriterion::enabled,
                     "End the run, completed, once the scene is at rest.")
      .def_readwrite("speed", &RestCriterion::speed,
                     "Every free node's translational speed below this [m/s].")
      .def_readwrite("angular_speed", &RestCriterion::angular_speed,
                     "Every free node's angular speed below this [rad/s].")
      .def_readwrite("hold", &RestCriterion::hold,
                     "For this long without interruption [s] (simulated time).");

  py::class_<AnalysisSettings>(m, "AnalysisSettings", "What a scene does (scene.h).")
      .def(py::init<>())
      .def_readwrite("kind", &AnalysisSettings::kind,
                     "AnalysisKind.STATIC or DYNAMIC (the scene's analysis.type).")
      .def_readwrite("start_time", &AnalysisSettings::start_time, "[s]")
      .def_readwrite("end_time", &AnalysisSettings::end_time, "[s]")
      .def_readwrite("step", &AnalysisSettings::step, "Time step of dynamic analyses [s].")
      .def_readwrite("adaptive_steps", &AnalysisSettings::adaptive_steps,
                     "step: auto: error-controlled steps (DynamicOptions.absolute_tolerance, "
                     "...); rows inside a step are interpolated.")
      .def_readwrite("align_steps", &AnalysisSettings::align_steps,
                     "Shorten steps so that profile breakpoints fall on step ends.")
      .def_readwrite("dynamic", &AnalysisSettings::dynamic, "DynamicOptions (a reference).")
      .def_readwrite("statics", &AnalysisSettings::statics, "StaticOptions (a reference).")
      .def_readwrite("static_preload", &AnalysisSettings::static_preload,
                     "Dynamic analyses start from a static equilibrium of the loads at "
                     "start_time.")
      .def_readwrite("stop_at_rest", &AnalysisSettings::stop_at_rest,
                     "RestCriterion (a reference): dynamic runs end once the scene is at rest "
                     "(summary.json rest_time).")
      .def_property(
          "threads",
          [](const AnalysisSettings& a) -> py::object {
            if (a.threads == kAutoThreads) return py::str("auto");
            return py::int_(a.threads);
          },
          [](AnalysisSettings& a, const py::object& value) {
            const std::string expected =
                "AnalysisSettings.threads: expected 'auto' or an "
                "integer from 1 to " +
                std::to_string(kMaxAssemblyThreads);
            if (py::isinstance<py::str>(value)) {
              if (value.cast<std::string>() != "auto") throw InputError(expected);
              a.threads = kAutoThreads;
              return;
            }
            if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value))
              throw InputError(expected);
            const long n = value.cast<long>();
            if (n < 1 || n > kMaxAssemblyThreads) throw InputError(expected);
            a.threads = static_cast<int>(n);
          },
          "Threads of the assembly: 'auto' (every core for a model of at least "
          "kParallelMinElements rod elements) or an integer >= 1 (analysis.threads).")
      .def_property(
          "rho_inf", [](const AnalysisSettings& a) { return a.dynamic.rho_inf; },
          [](AnalysisSettings& a, double rho) { a.dynamic.rho_inf = rho; },
          "Shorthand for dynamic.rho_inf: spectral radius at infinity in [0, 1]; negative: "
          "auto (0.9, or 0 with contact).");
}

void BindScenesAndRuns(py::module_& m) {
  py::class_<OutputPoint>(m, "OutputPoint",
                          "A recorded point (scene.h): fixed in a node frame (node >= 0, offset in "
                          "that frame [m]) or on a rod's centre line at arc length s (rod >= 0, "
                          "arc_length [m] from its first node).")
      .def_readonly("name", &OutputPoint::name, "Column prefix, e.g. 'P8'.")
      .def_readonly("node", &OutputPoint::node,
                    "Node the point is fixed to (a point of a rigid body or a rod node), or -1 for "
                    "a point along a rod.")
      .def_readonly("offset", &OutputPoint::offset, "Node-frame components of the point [m].")
      .def_readonly("rod", &OutputPoint::rod, "A point along a rod: its rod index (else -1).")
      .def_readonly("arc_length", &OutputPoint::arc_length,
                    "A point along a rod: its reference arc length from the rod's first node [m].");

  py::class_<OutputJoint>(m, "OutputJoint", "A recorded joint (scene.h).")
      .def_readonly("name", &OutputJoint::name,
                    "The joint's name (the column prefix in joints.csv).")
      .def_readonly("joint", &OutputJoint::joint, "Index into Model.joints.");

  BindEnum<VtkFormat>(m, "VtkFormat", "Encoding of the ParaView frames (vtk.h).");

  py::class_<OutputSpec>(m, "OutputSpec", "What a run records (scene.h, run.h).")
      .def_readonly("points", &OutputSpec::points, "List of OutputPoint (copies).")
      .def_readonly("joints", &OutputSpec::joints, "List of OutputJoint (copies).")
      .def_readwrite("interval", &OutputSpec::interval,
                     "Time between recorded rows [s]; 0: every step.")
      .def_readwrite("vtk", &OutputSpec::vtk, "Write ParaView files under vtk/.")
      .def_readwrite("vtk_interval", &OutputSpec::vtk_interval,
                     "Time between ParaView frames [s]; 0: same as interval.")
      .def_readwrite("vtk_format", &OutputSpec::vtk_format,
                     "Encoding of the ParaView frames (VtkFormat.BINARY or ASCII; vtk.h).")
      .def_readwrite("rod_fields", &OutputSpec::rod_fields,
                     "Write rod_fields.csv: section strain and stress of every rod element.")
      .def_readwrite("rod_fields_interval", &OutputSpec::rod_fields_interval,
                     "Time between rod_fields.csv rows [s]; 0: every step; < 0: at the rows "
                     "of points.csv.")
      .def_readwrite("max_rows", &OutputSpec::max_rows,
                     "Most output times a run records (rows of each table, rod_fields.csv "
                     "times, ParaView frames; default 1000000): run_scene and record refuse a "
                     "scene estimated above it (estimate_outputs), and a run reaching it fails.")
      .def_readwrite("reactions", &OutputSpec::reactions,
                     "Write reactions.csv (the joints' force and moment on side B; default "
                     "True); False: neither written nor computed.")
      .def_readwrite("energy", &OutputSpec::energy,
                     "Write energy.csv (energies and momenta; default True); False: neither "
                     "written nor computed.");

  py::class_<Scene>(m, "Scene",
                    "A compiled scene (scene.h): the model plus what to do with it (analysis) and "
                    "what to record (outputs). Made by load_scene or parse_scene.")
      .def(py::init([](const Model& model, std::string name) {
             Scene scene;
             scene.model = model;
             scene.name = std::move(name);
             return scene;
           }),
           py::arg("model"), py::arg("name") = std::string("model"),
           "A scene of a Model built in code (ModelBuilder), with the default analysis and "
           "no outputs.")
      .def_readonly("source", &Scene::source, "File name (for messages and the summary).")
      .def_readonly("name", &Scene::name, "Scene title.")
      .def_readonly("model", &Scene::model, "The compiled Model (a read-only reference).")
      .def_readwrite("analysis", &Scene::analysis, "AnalysisSettings (a reference; writable).")
      .def_readwrite("outputs", &Scene::outputs, "OutputSpec (a reference).")
      .def_readonly("named_points", &Scene::named_points,
                    "Named points of the scene: (name, world position in the reference "
                    "configuration [m]) pairs (copies).")
      .def("__repr__", [](const Scene& s) { return "<screwfem.Scene '" + s.name + "'>"; });

  m.def(
      "load_scene",
      [](const std::string& path, const std::vector<std::string>& overrides,
         const py::object& max_memory) {
        const ScopedMemoryLimit limit(max_memory, "load_scene: max_memory");
        PythonSignals signals;
        try {
          return LoadScene(path, overrides, signals.request());
        } catch (const InputError&) {
          signals.ThrowIfRaised();  // Ctrl-C while reading: KeyboardInterrupt
          throw;
        }
      },
      py::arg("path"), py::arg("overrides") = std::vector<std::string>{},
      py::arg("max_memory") = py::none(),
      "load_scene(path, overrides=[], max_memory=None) -> Scene\n\n"
      "Parses and compiles a scene file (docs/scene-format.md). `overrides` are 'key.path=value'\n"
      "strings applied to the YAML tree before compilation (e.g. 'analysis.step=5e-4',\n"
      "'bodies.arm56.elements=8'). `max_memory` (bytes, or a size such as '8G'; None: the\n"
      "process default, set_memory_limit) bounds the memory the model and its solver may need\n"
      "(docs/limits.md). Raises InputError with the message\n"
      "'FILE:LINE:COLUMN: FIELD: what was expected'.");
  m.def(
      "parse_scene",
      [](const std::string& text, const std::string& source,
         const std::vector<std::string>& overrides, const py::object& max_memory) {
        const ScopedMemoryLimit limit(max_memory, "parse_scene: max_memory");
        return ParseScene(text, source, overrides);
      },
      py::arg("yaml_text"), py::arg("source_name"),
      py::arg("overrides") = std::vector<std::string>{}, py::arg("max_memory") = py::none(),
      "parse_scene(yaml_text, source_name, overrides=[], max_memory=None) -> Scene\n\n"
      "As load_scene, from YAML text; messages name `source_name` as the file.");
  m.def(
      "set_memory_limit",
      [](const py::object& size) { SetDefaultMemoryLimit(MemorySize(size, "set_memory_limit")); },
      py::arg("size"),
      "set_memory_limit(size)\n\n"
      "The memory limit of this process (the CLI's --max-memory): bytes, or a size such as\n"
      "'8G' or '512M' (powers of 1024); None: the default, half the physical memory. Building a\n"
      "model (load_scene, parse_scene, ModelBuilder.build) estimates what it and its solver\n"
      "will allocate and raises InputError, naming the largest part, beyond it\n"
      "(docs/limits.md).");
  m.def(
      "parse_memory_size",
      [](const std::string& text) { return ParseMemorySize(text, "memory size"); }, py::arg("text"),
      "parse_memory_size(text) -> int\n\nBytes of a size such as '8G', '512MiB' or '1000000' "
      "(K, M, G, T: powers of 1024); InputError otherwise.");
  m.def(
      "memory_limit", []() { return ResolveMemoryLimit(0); },
      "memory_limit() -> int\n\nThe memory limit in force [bytes] (set_memory_limit).");
  m.def(
      "estimate_memory",
      [](const Model& model) {
        py::list out;
        for (const MemoryPart& p : EstimateDataMemory(model))
          out.append(py::make_tuple(p.part, p.bytes, p.why));
        return out;
      },
      py::arg("model"),
      "estimate_memory(model) -> list of (part, bytes, why)\n\n"
      "What a Simulation of `model` allocates (MakeData): the banded LU factors, the state,\n"
      "the off-band coupling and the broad phase of pairs of moving shapes.");
  m.def(
      "estimate_run_memory",
      [](const Model& model, bool statics, bool adaptive, bool perturbed_start, bool ggl) {
        IntegratorMemoryOptions o;
        o.statics = statics;
        o.adaptive = adaptive;
        o.perturbed_start = perturbed_start;
        o.ggl = ggl;
        py::list out;
        for (const MemoryPart& p : EstimateRunMemory(model, o))
          out.append(py::make_tuple(p.part, p.bytes, p.why));
        return out;
      },
      py::arg("model"), py::arg("statics") = false, py::arg("adaptive") = false,
      py::arg("perturbed_start") = false, py::arg("ggl") = false,
      "estimate_run_memory(model, statics=False, adaptive=False, perturbed_start=False, "
      "ggl=False) -> list of (part, bytes, why)\n\n"
      "The memory of a run, as `screwfem check` prints it (EstimateRunMemory): the model, the\n"
      "parts of estimate_memory and the time integrator's workspace (adaptive: step auto;\n"
      "statics: the static solver's instead).");

  py::class_<RunResult>(m, "RunResult", "Outcome of run_scene (run.h).")
      .def_readonly("ok", &RunResult::ok, "The analysis completed.")
      .def_readonly("interrupted", &RunResult::interrupted,
                    "Ended by a stop request (Ctrl-C, a signal, an exception in a callback).")
      .def_readonly("end_time", &RunResult::end_time, "Simulated time reached [s].")
      .def_readonly("steps", &RunResult::steps,
                    "Time steps (static analyses: accepted load steps).")
      .def_readonly("newton_iterations", &RunResult::newton_iterations,
                    "Dynamic steps and static solves (incl. a preload).")
      .def_readonly("max_iterations_per_step", &RunResult::max_iterations_per_step,
                    "Most Newton iterations one step (or load step) took.")
      .def_readonly("halvings", &RunResult::halvings,
                    "Halved time steps, or halved load increments in statics.")
      .def_readonly("wall_seconds", &RunResult::wall_seconds, "[s]")
      .def_readonly("max_constraint_residual", &RunResult::max_constraint_residual,
                    "Largest |phi| over the run [m or rad].")
      .def_readonly("max_element_rotation", &RunResult::max_element_rotation,
                    "Largest relative rotation of one rod element over the run [rad] (a helical "
                    "element is valid below 2 pi).")
      .def_readonly("message", &RunResult::message,
                    "Why it stopped early, with the time (static analyses: the load factor).")
      .def_readonly("io_error", &RunResult::io_error,
                    "It failed writing its files (message: which and why).")
      .def_readonly("load_factor", &RunResult::load_factor,
                    "Static analyses: the load factor reached; NaN for dynamic ones.")
      .def("__repr__", [](const RunResult& r) {
        return std::string("<screwfem.RunResult ok=") + (r.ok ? "True" : "False") +
               " steps=" + std::to_string(r.steps) + ">";
      });

  py::class_<OutputEstimate>(m, "OutputEstimate",
                             "The output times a run is estimated to record (run.h).")
      .def_readonly("rows", &OutputEstimate::rows,
                    "Rows of each table (NaN: not known ahead, step auto with interval 0).")
      .def_readonly("field_times", &OutputEstimate::field_times,
                    "rod_fields.csv times at its own interval (0 when it has none).")
      .def_readonly("frames", &OutputEstimate::frames, "ParaView frames (0 without vtk).")
      .def("__repr__", [](const OutputEstimate& e) {
        return FormatNumbers("<screwfem.OutputEstimate rows=%g field_times=%g frames=%g>", e.rows,
                             e.field_times, e.frames);
      });
  m.def(
      "estimate_outputs",
      [](const Scene& scene, const std::optional<OutputSpec>& outputs, bool check) {
        const OutputSpec& o = outputs ? *outputs : scene.outputs;
        if (check) CheckOutputRows(scene, o);
        return EstimateOutputs(scene, o);
      },
      py::arg("scene"), py::arg("outputs") = py::none(), py::arg("check") = false,
      R"doc(estimate_outputs(scene, outputs=None, check=False) -> OutputEstimate

The rows per table, rod_fields.csv times and ParaView frames a run of `scene` with `outputs`
(default: the scene's) is estimated to record, as `screwfem check` prints them. With `check`,
raises ValueError as run_scene and record do when one is above outputs.max_rows, naming the
setting that fixes it (outputs.interval, outputs.vtk_interval, outputs.rod_fields or
outputs.max_rows).)doc");

  m.def(
      "run_scene",
      [](const Scene& scene, const std::string& outdir, bool progress, bool force,
         const py::object& callback, long every, const std::optional<std::string>& inputs) {
        RunOptions options;
        options.progress = progress;
        options.replace_results = force;
        if (inputs) {
          PythonSignals signals;
          try {
            options.inputs = ReadInputTable(*inputs, scene.model, signals.request());
          } catch (const InputError&) {
            signals.ThrowIfRaised();  // Ctrl-C while reading: KeyboardInterrupt
            throw;
          }
        }
        if (!callback.is_none()) return RunWithCallback(scene, outdir, options, callback, every);
        // On Python's main thread the run polls for signals (Ctrl-C), which needs the GIL. On
        // another thread (a Dask worker's) no signal is ever delivered: the run releases the
        // GIL, so other Python threads (the worker's event loop and heartbeats) go on.
        if (OnMainThread()) {
          PythonSignals signals;
          options.stop = signals.request();
          RunResult r = RunScene(scene, outdir, options);
          signals.ThrowIfRaised();
          return r;
        }
        py::gil_scoped_release release;
        return RunScene(scene, outdir, options);
      },
      py::arg("scene"), py::arg("outdir"), py::arg("progress") = false, py::arg("force") = false,
      py::arg("callback") = py::none(), py::arg("every") = 1, py::arg("inputs") = py::none(),
      R"doc(run_scene(scene, outdir, progress=False, force=False, callback=None, every=1, inputs=None) -> RunResult

Runs the scene's analysis as `screwfem run` does and writes its outputs into `outdir` (created
if needed): points.csv (t, then per point P: P.x P.y P.z P.vx P.vy P.vz P.ax P.ay P.az and
P.qw P.qx P.qy P.qz; world frame, SI), joints.csv, summary.json, vtk/ and the other tables
the model has (run.h).
`progress` draws a progress bar on stderr. `inputs`: a CSV file of run-time input values over
time (the CLI's --inputs).

`callback(sim)` is called with a Simulation holding the run's state once at the start (before
the first step: the inputs it sets are held over that step) and then after every `every`
completed steps (after the static solution in a static analysis), once that step's rows are on
disk. It may read the state (sim.time, sim.point_motion(...), ...) and set run-time inputs
(sim.inputs[name] = value), which the following steps hold: a controller in closed loop. It must
not step the simulation itself. An exception in the callback ends the run (summary.json status
"interrupted", files complete) and is raised again. Inputs set from a callback and the same
values from an `inputs` table give the same tables bit for bit.

A numerical failure ends the run and is reported in the result (ok False, message), not raised;
raises InputError for invalid settings or outputs and when outdir or its files cannot be
created, when another run holds outdir, and when it holds an earlier run's results unless
`force` (then screwfem's files, and only those, are removed first). On the main thread a signal
(Ctrl-C) ends the run cleanly, with summary.json status 'interrupted' and complete files, then
raises KeyboardInterrupt; on other threads, without a callback, the run releases the GIL (do
not modify `scene` from another thread meanwhile).)doc");

  py::class_<StepSchedule>(
      m, "StepSchedule",
      "The step ends of a dynamic run (schedule.h): start + n step for n >= 1, "
      "every breakpoint in (start, end), and end.")
      .def(py::init([](double start, double end, double step, std::vector<double> breakpoints) {
             ValidateTimeGrid(start, end, step, "StepSchedule");
             for (double b : breakpoints)
               if (!std::isfinite(b)) throw InputError("StepSchedule: breakpoints must be finite");
             return StepSchedule(start, end, step, std::move(breakpoints));
           }),
           py::arg("start"), py::arg("end"), py::arg("step"),
           py::arg("breakpoints") = std::vector<double>{},
           "Times in [s]. Raises InputError (a ValueError) unless start and end are finite, "
           "end >= start, step > 0, at most 1e9 steps, and the step ends representable to a "
           "relative accuracy of 1e-6 (docs/scene-format.md, 'analysis').")
      .def("done", &StepSchedule::Done, py::arg("t"), "True once t [s] has reached the end.")
      .def(
          "next",
          [](const StepSchedule& s, double t) {
            if (!s.Accepts(t))
              throw InputError(
                  "StepSchedule.next: t must be finite, not before start and not "
                  "done(t)");
            return s.Next(t);
          },
          py::arg("t"),
          "The step end following t [s] (start or an earlier step end). Raises InputError (a "
          "ValueError) unless t is finite, not before start and not done(t).");

  m.def("profile_breakpoints", &ProfileBreakpoints, py::arg("model"),
        "profile_breakpoints(model) -> list of float\n\n"
        "Every breakpoint [s] of the model's load and drive profiles (unsorted): pass them to\n"
        "StepSchedule to put them on step ends, as run_scene does with align_steps.");
}

}  // namespace

void BindScene(py::module_& m) {
  BindSettings(m);
  BindScenesAndRuns(m);
}

}  // namespace screwfem::python
