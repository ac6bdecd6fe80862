// RunScene (run.h): the run loop of static and dynamic analyses; what it records is
// Recording's (recording.h).
#include "screwfem/io/run.h"

#include <cmath>
#include <string>
#include <vector>

#include "screwfem/io/input_table.h"
#include "screwfem/io/recording.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/statics.h"

namespace screwfem {

namespace {

// The analysis settings (the outputs are the Recording's to check).
void ValidateSettings(const Scene& scene) {
  const AnalysisSettings& a = scene.analysis;
  const auto require = [](bool ok, const char* field, const std::string& what) {
    if (!ok) throw InputError(std::string(field) + ": " + what);
  };
  require(IsEnumValue(a.kind), "analysis.kind", "must be " + EnumNameAlternatives<AnalysisKind>());
  if (a.kind == AnalysisKind::kStatic || a.static_preload)
    ValidateStaticOptions(a.statics, "analysis.statics");
  require(!(a.kind == AnalysisKind::kStatic && a.stop_at_rest.enabled), "analysis.stop_at_rest",
          "applies to dynamic analyses only");
  if (a.kind == AnalysisKind::kStatic) return;
  ValidateTimeGrid(a.start_time, a.end_time, a.step, "analysis");
  ValidateDynamicOptions(a.dynamic, "analysis.dynamic");
  if (a.stop_at_rest.enabled) ValidateRestCriterion(a.stop_at_rest, "analysis.stop_at_rest");
}

// One call of RunScene: the state, the stepping and the files (Recording).
class Run {
 public:
  Run(const Scene& scene, Data& data, Integrator& integrator, const std::string& outdir,
      const RunOptions& options)
      : scene_(scene),
        model_(scene.model),
        options_(options),
        data_(data),
        integ_(integrator),
        recording_(scene, scene.outputs, scene.model, data, integrator, outdir, options) {}

  void Execute() {
    if (scene_.analysis.kind == AnalysisKind::kStatic)
      RunStatic();
    else
      RunDynamic();
  }

  void Failed(const std::string& message) { recording_.Finish("failed", message); }
  RunResult Result() const { return recording_.Result(); }

 private:
  // The scene's initial coordinates and velocities (solve/initial_state.h).
  bool AssembleInitial() {
    std::string why;
    if (AssembleInitialState(model_, data_, &why)) return true;
    Failed(FormatNumbers("initial state at t = %.9g s: ", data_.time) + why);
    return false;
  }

  // Static analyses record a row at every converged load step (the path), the ParaView frame
  // at the end only (every row has the same time).
  void RunStatic() {
    const StaticOptions& so = scene_.analysis.statics;
    data_.time = so.time;
    SetInputsAt(options_.inputs, so.time, data_);
    if (!AssembleInitial()) return;
    // A write error while recording the path ends the recording: the solver stops at its next
    // Newton iteration (StopWhenFinished) rather than solving the rest of the path.
    const StaticResult result = SolveStatic(
        model_, data_, so, recording_.StopWhenFinished(options_.stop),
        [&](const StaticStep& step) { recording_.RecordStaticStep(so.time, step.load_factor); });
    recording_.SetStaticResult(result);
    if (recording_.finished()) return;  // a write error (or outputs.max_rows) on the path
    if (result.interrupted) {
      Interrupted(
          FormatNumbers("static solution interrupted at load factor %.6g", result.load_factor));
      return;
    }
    if (!result.converged) {
      Failed(FormatNumbers(result.limit_point ? "static solution stopped at load factor %.9g: "
                                              : "static solution failed at load factor %.9g: ",
                           result.load_factor) +
             result.message);
      return;
    }
    // The last step's row is on the path already: the frame only (or the row as well when
    // the solve took no step, e.g. start_load_factor = end_load_factor).
    if (!recording_.RecordStaticSolution(so.time, result.load_steps == 0)) return;
    recording_.Finish("completed", {});
  }

  void RunDynamic() {
    const AnalysisSettings& a = scene_.analysis;
    data_.time = a.start_time;
    SetInputsAt(options_.inputs, a.start_time, data_);
    if (!AssembleInitial()) return;
    if (a.static_preload) {
      StaticOptions so = a.statics;
      so.time = a.start_time;
      const StaticResult preload = SolveStatic(model_, data_, so, options_.stop);
      recording_.SetStaticResult(preload);
      if (preload.interrupted) {
        Interrupted(FormatNumbers("static preload at t = %.9g s interrupted at load factor %.6g",
                                  a.start_time, preload.load_factor));
        return;
      }
      if (!preload.converged) {
        Failed(FormatNumbers("static preload at t = %.9g s failed at load factor %.6g: ",
                             a.start_time, preload.load_factor) +
               preload.message);
        return;
      }
      data_.time = a.start_time;
    }
    std::string why;
    if (!InitializeDynamics(model_, data_, integ_, a.dynamic, &why)) {
      Failed(FormatNumbers("cannot start the dynamic analysis at t = %.9g s: ", a.start_time) +
             why);
      return;
    }
    if (a.stop_at_rest.enabled) recording_.StopAtRest(a.stop_at_rest);
    if (!recording_.Start()) return;

    // Fixed steps end on the schedule's step ends (profile breakpoints inserted with
    // align_steps); step: auto: error-controlled steps, which land exactly on end_time (and on
    // profile breakpoints), the rows and frames due inside a step interpolated. Run-time inputs
    // from a table are held over each step (Recording::BeforeStep).
    const StepSchedule schedule(a.start_time, a.end_time, a.step,
                                a.align_steps ? ProfileBreakpoints(model_) : std::vector<double>{});
    const StepPolicy policy =
        a.adaptive_steps ? StepPolicy::ErrorControlled(a.step) : StepPolicy::OnSchedule(schedule);
    const AdvanceResult r =
        Advance(model_, data_, integ_, policy, a.end_time, &recording_, options_.stop);
    if (r.stopped) return;  // a write error ended the run, or it came to rest (stop_at_rest)
    if (r.interrupted) {
      Interrupted(r.interrupted_in_step
                      ? FormatNumbers("at t = %.9g s (within a halved step); the last recorded "
                                      "row is at t = %.9g s",
                                      data_.time, recording_.last_row_time())
                      : FormatNumbers("at t = %.9g s; the last recorded row is at t = %.9g s",
                                      data_.time, recording_.last_row_time()));
      return;
    }
    if (!r.ok) {
      Failed(r.message);
      return;
    }
    recording_.Finish("completed", {});
  }

  // Ends the run after a stop request (Recording::Interrupted).
  void Interrupted(const std::string& when) {
    recording_.Interrupted(options_.stop.Signal(), when);
  }

  const Scene& scene_;
  const Model& model_;
  const RunOptions& options_;
  Data& data_;
  Integrator& integ_;
  Recording recording_;
};

}  // namespace

RunResult RunScene(const Scene& scene, const std::string& outdir, const RunOptions& options) {
  Data data = MakeData(scene.model);
  Integrator integrator;
  return RunScene(scene, data, integrator, outdir, options);
}

RunResult RunScene(const Scene& scene, Data& data, Integrator& integrator,
                   const std::string& outdir, const RunOptions& options) {
  if (outdir.find('\0') != std::string::npos)
    throw InputError("output directory '" + std::string(outdir.c_str()) +
                     "...': contains a NUL character (not a directory name)");
  ValidateSettings(scene);
  // The assembly's threads (analysis.threads; assemble.h): started here, before any step.
  SetAssemblyThreads(data, ResolveAssemblyThreads(scene.model, scene.analysis.threads));
  Run run(scene, data, integrator, outdir, options);
  try {
    run.Execute();
  } catch (const std::exception& e) {
    run.Failed(std::string("internal error: ") + e.what());
    throw;
  }
  return run.Result();
}

}  // namespace screwfem
