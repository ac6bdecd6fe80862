// Recording: the files of a run (run.h lists them), written as a simulation advances. RunScene's
// run loop writes through it, and so does Python's Simulation.record, so a run driven from
// Python leaves the same files, written by the same code, as `screwfem run`.
//
// A Recording observes the stepping loop (solve/advance.h): passed to Advance, it holds the
// run-time inputs of a table over each step, writes the rows and frames due at each step end
// (and, for error-controlled steps, those due inside a step, from the interpolated state), and
// keeps the summary up to date every 2 s. Static analyses record a row and a ParaView frame per
// load step (the frame's time is the load factor).
#pragma once

#include <memory>
#include <string>

#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/data.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/rest.h"
#include "screwfem/solve/statics.h"
#include "screwfem/solve/stop.h"

namespace screwfem {

class Recording final : public AdvanceObserver {
 public:
  // Opens `outdir` (created if needed) for the outputs `outputs` of `scene` (scene.outputs,
  // or a copy with another interval): takes its lock, removes an earlier run's files when
  // options.replace_results (else refuses them), opens the tables and the ParaView writer and
  // writes the first summary (status "running") and joints.json. `model`, `data` and
  // `integrator` are the ones that will be stepped; they, `scene` and `options` must outlive
  // the Recording. Of the options it uses replace_results, progress, on_step and inputs.
  // Throws InputError as RunScene does (run.h).
  Recording(const Scene& scene, const OutputSpec& outputs, const Model& model, Data& data,
            Integrator& integrator, const std::string& outdir, const RunOptions& options);
  // Ends an unfinished recording as "failed" ("the recording was not finished"), so that the
  // files on disk are always complete and say how they ended.
  ~Recording() override;
  Recording(const Recording&) = delete;
  Recording& operator=(const Recording&) = delete;

  // Dynamic analyses. The state at data.time is consistent (InitializeDynamics): records its
  // row and frame and starts the output clocks there. False on a write error (then finished).
  bool Start();
  bool started() const;
  // Before Start, for a run that ends at rest (analysis.stop_at_rest, RunScene's loop): from
  // Start on, AfterStep watches the accepted steps (RestWatch, solve/rest.h, not before the
  // last profile breakpoint or input-table row); at rest it records the state's row and frame,
  // finishes "completed" with the time in the message and summary.json's rest_time, and
  // returns false, which ends Advance. Steps driven from Python stay the caller's to end.
  void StopAtRest(const RestCriterion& criterion);

  // AdvanceObserver: inputs from options.inputs, the rows and frames due, the largest
  // constraint residual and element rotation, options.on_step, the progress bar, the summary.
  void BeforeStep(double t_inputs) override;
  double NextOutputTime() const override;
  bool OutputInsideStep(double t) override;
  bool AfterStep(bool last) override;

  // Static analyses: the rows and the ParaView frame of the path at time t and `load_factor`
  // (SolveStatic's on_step). False on a write error (then finished).
  bool RecordStaticStep(double t, double load_factor);
  // The outcome of a static solution (of a static analysis or a dynamic one's preload), for
  // the summary.
  void SetStaticResult(const StaticResult& result);
  // A converged static analysis at time t: the largest residual and rotation of the solution,
  // its row and frame unless the path recorded them already (`row`: it did not, the solve
  // took no step); then options.on_step.
  bool RecordStaticSolution(double t, bool row);

  // `stop` extended to also ask to stop once this recording has finished (a write error, or
  // outputs.max_rows reached on the path), for the static solver that records through
  // RecordStaticStep: it then stops before its next Newton iteration rather than solving
  // the rest of the path. Valid while the Recording lives; one at a time.
  StopRequest StopWhenFinished(const StopRequest& stop);

  // The row and frame of the current state unless it is the last one recorded (the end of a
  // run driven step by step); false on a write error (then finished).
  bool RecordFinalState();

  // Ends the recording (once): the rows still collected go to disk, then the ParaView
  // collection and the summary with `status` ("completed", "failed", "interrupted" or
  // "terminated") and `message`. A write error turns the status into "failed".
  void Finish(const char* status, std::string message);
  // Finish after a stop request whose flag held `signal`: "interrupted", or "terminated" for
  // SIGTERM and SIGHUP, the message naming the signal, then `when`.
  void Interrupted(int signal, const std::string& when);
  bool finished() const;

  // The time of the last recorded row (NaN before the first).
  double last_row_time() const;
  RunResult Result() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace screwfem
