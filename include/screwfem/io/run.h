// Running a scene and writing its results (issue: the main job).
//
// OUTDIR/points.csv   t, then per point P: P.x P.y P.z P.vx P.vy P.vz P.ax P.ay P.az (world, SI)
//                     and P.qw P.qx P.qy P.qz: the unit quaternion, world from the point's
//                     frame (the section frame along a rod, else the node frame), qw >= 0
//                     (FrameQuaternion, writers.h)
// OUTDIR/joints.csv   t, then per joint J (per coordinate i for multi-DOF joints: J.i.q ...):
//                     J.q J.qd J.qdd J.effort
// OUTDIR/reactions.csv t, then per joint with constraint rows: J.Fx J.Fy J.Fz J.Mx J.My J.Mz
//                     (CalcJointReaction: on side B, world, about the joint point); not with
//                     outputs.reactions false
// OUTDIR/energy.csv   t, kinetic strain spring gravity total, px py pz, Lx Ly Lz (world); not
//                     with outputs.energy false
// OUTDIR/rod_fields.csv (outputs.rod_fields) t, then per rod element, one row each: rod s
//                     gamma1 gamma2 gamma3 kappa1 kappa2 kappa3 n1 n2 n3 m1 m2 m3 (section
//                     strain and stress at the element's midpoint, CalcRodFieldRows)
// OUTDIR/settling.csv (scenes with contact) t, kinetic speed angular_speed contacts slipping
//                     overlap overlap_ratio (CalcSettlingState, assemble/outputs.h)
// OUTDIR/summary.json resolved settings, counts, steps, Newton iterations, halvings, wall time,
//                     largest element rotation,
//                     largest constraint residual, status and message
// OUTDIR/vtk/frame_NNNNN.vtp and OUTDIR/vtk/motion.pvd (ParaView; the collection is written
//                     once, when the run ends, also when it is interrupted or fails; static
//                     analyses: a frame per load step, its time the load factor)
// OUTDIR/.screwfem.lock  held (flock) by the running run, with its process id
// The names are one list (writers.h, kOutputFiles, kVtkFiles, IsFrameFileName). OUTDIR is
// opened once, by a directory descriptor, and every file is created relative to it with
// O_NOFOLLOW: a symbolic link (or another file's hard link) at one of these names, or a vtk/
// that is a link, is refused (InputError naming the path), never written through.
// Files are written as the run goes, in whole rows: the CSV rows are collected and written
// when 64 KiB have accumulated, at least every 2 s of wall time (with the summary), before
// every on_step callback and at the end of the run; points.csv, joints.csv, reactions.csv,
// energy.csv (those written; and rod_fields.csv when it has their rows: it then ends at the same time) always
// hold the same rows. An interrupted run (stop request) leaves valid files up to the last
// completed output step; the files of a killed process end with a complete row; a write
// error (a full disk, a file size limit) cuts a torn row off, every table (contacts.csv,
// pair_contacts.csv and rod_fields.csv included) at the same last output time, ends the run at
// once (a static path at its next Newton iteration), and the summary says which file failed,
// why, and how many rows the tables hold. Static analyses name the load factor (λ) in their
// messages, where dynamic ones name the time.
#pragma once

#include <atomic>
#include <functional>
#include <limits>
#include <string>

#include "screwfem/io/input_table.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/data.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/stop.h"

namespace screwfem {

// The lock file of an output directory (see above).
inline constexpr const char* kOutputLockFile = ".screwfem.lock";

struct RunOptions {
  bool progress = false;  // progress bar on stderr
  // Polled before every time step, (sub)step attempt and static Newton iteration: a request
  // ends the run cleanly (status "interrupted", or "terminated" when the flag holds SIGTERM
  // or SIGHUP; RunResult::signal is the flag's value).
  StopRequest stop;
  // Called after every completed time step (and after the static solution) with the
  // simulated time [s], once the step's output rows are written to the files (flushed). For
  // tests and embedding.
  std::function<void(double t)> on_step;
  // An outdir that holds the files of an earlier run (any of writers.h's kOutputFiles, or
  // kVtkFiles and frames in vtk/) is refused unless this is set; then exactly those files are
  // removed first, by name (a link is refused, never followed), and vtk/ if that leaves it
  // empty. The CLI's --force.
  bool replace_results = false;
  // Run-time input values over time (the CLI's --inputs). Each step's inputs are the table's
  // values at the step's end, where the implicit step evaluates its loads (docs/numerics.md,
  // "Run-time inputs"); the start and a static analysis use those at their time.
  InputTable inputs;
};

struct RunResult {
  bool ok = false;
  bool interrupted = false;    // ended by RunOptions::stop
  int signal = 0;              // then the value of its flag (the signal number), else 0
  double end_time = 0.0;       // simulated time reached [s]
  long steps = 0;              // time steps (static analyses: accepted load steps)
  long newton_iterations = 0;  // dynamic steps and static solves (incl. a preload)
  int max_iterations_per_step = 0;
  long halvings = 0;  // halved time steps, or halved load increments in statics
  double wall_seconds = 0.0;
  double max_constraint_residual = 0.0;
  // Largest relative rotation of one rod element over the run [rad], on its continued branch;
  // one helical element is valid below 2 pi (elements/rod.h).
  double max_element_rotation = 0.0;
  std::string message;    // why it stopped early, with the time (statics: the load factor)
  bool io_error = false;  // it failed writing its files (message: which and why)
  // Static analyses: the load factor reached (the last converged state's); NaN otherwise.
  double load_factor = std::numeric_limits<double>::quiet_NaN();
};

// The output times a run of `scene` with `outputs` is estimated to record, each bounded by
// outputs.max_rows (docs/scene-format.md, "outputs"): rows of the tables, rod_fields.csv
// times at its own interval (0 when it has none) and ParaView frames (0 without vtk).
// Static analyses: one per load step and the start (load_steps + 1). Dynamic analyses with
// fixed steps: the start, the end, and one per interval or, below a step, per step (and per
// profile breakpoint with align_steps); with step: auto, from the interval and the duration
// alone: ceil((end_time - start_time) / interval) + 1; with interval 0 the number of steps is
// not known ahead (NaN: not estimated; the bound is then kept at run time only).
struct OutputEstimate {
  double rows = 0.0;
  double field_times = 0.0;
  double frames = 0.0;
};
OutputEstimate EstimateOutputs(const Scene& scene, const OutputSpec& outputs);
// Throws InputError when an estimate is above outputs.max_rows, naming the output, the
// setting that sets it (outputs.interval, outputs.vtk_interval, outputs.rod_fields) and
// outputs.max_rows. `check` and RunScene (and Simulation.record) call it.
void CheckOutputRows(const Scene& scene, const OutputSpec& outputs);

// Runs the scene's analysis and writes the outputs into outdir (created if needed).
//
// Dynamic analyses: optional static preload at start_time, consistent initial accelerations,
// then steps of analysis.step; with align_steps, every breakpoint of a load or drive profile
// (Profile::Breakpoints) in (start_time, end_time) falls on a step end (a grid step end within
// a tenth of a step of a breakpoint moves onto it). Rows are recorded at start_time, at the
// first step end at or after each multiple of outputs.interval (every step when 0) and at the
// last step end. Static analyses: SolveStatic at statics.time; every converged load step is a
// row of every table (t = statics.time, then its load factor) and a ParaView frame (the load
// factor as its time).
// Numerical failure, a stop request and write errors end the run with a result (and
// summary.json status "failed" or "interrupted"), never an exception.
// Throws InputError for invalid settings or outputs (naming the field), when outdir or its
// files cannot be created, when another run holds outdir (naming its process id) and when
// outdir holds an earlier run's results without replace_results.
RunResult RunScene(const Scene& scene, const std::string& outdir, const RunOptions& options = {});

// The same with the caller's state: `data` (MakeData(scene.model)) and `integrator` are the
// ones stepped, and hold the run's end state afterwards. An on_step callback may read data and
// set its run-time inputs (Data::inputs), which the next step holds (Python's run_scene
// callback); options.inputs, when not empty, sets them before every step instead.
RunResult RunScene(const Scene& scene, Data& data, Integrator& integrator,
                   const std::string& outdir, const RunOptions& options = {});

}  // namespace screwfem
