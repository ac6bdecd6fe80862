// Running a scene and writing its results (issue: the main job).
//
// OUTDIR/points.csv   t, then per point P: P.x P.y P.z P.vx P.vy P.vz P.ax P.ay P.az (world, SI)
// OUTDIR/joints.csv   t, then per joint J (per coordinate i for multi-DOF joints: J.i.q ...):
//                     J.q J.qd J.qdd J.effort
// OUTDIR/summary.json resolved settings, counts, steps, Newton iterations, halvings, wall time,
//                     largest element rotation,
//                     largest constraint residual, status and message
// OUTDIR/vtk/frame_NNNNN.vtp and OUTDIR/vtk/motion.pvd (ParaView)
// Files are written as the run goes, in whole rows: the CSV rows are collected and flushed
// when 64 KiB have accumulated, at least every 2 s of wall time (with the summary), before
// every on_step callback and at the end of the run. An interrupted run (stop request) leaves
// valid files up to the last completed output step; the files of a killed process end with
// a complete row.
#pragma once

#include <atomic>
#include <functional>
#include <string>

#include "screwfem/io/scene.h"

namespace screwfem {

struct RunOptions {
  bool progress = false;                    // progress bar on stderr
  const std::atomic<bool>* stop = nullptr;  // set asynchronously (e.g. SIGINT) to stop cleanly
  // Called after every completed time step (and after the static solution) with the
  // simulated time [s], once the step's output rows are written to the files (flushed). For
  // tests and embedding.
  std::function<void(double t)> on_step;
};

struct RunResult {
  bool ok = false;
  bool interrupted = false;
  double end_time = 0.0;        // simulated time reached [s]
  long steps = 0;               // time steps (static analyses: accepted load steps)
  long newton_iterations = 0;   // dynamic steps and static solves (incl. a preload)
  int max_iterations_per_step = 0;
  long halvings = 0;            // halved time steps, or halved load increments in statics
  double wall_seconds = 0.0;
  double max_constraint_residual = 0.0;
  // Largest relative rotation of one rod element over the run [rad], on its continued branch;
  // one helical element is valid below 2 pi (method.md §2.7).
  double max_element_rotation = 0.0;
  std::string message;          // why it stopped early, with the time
};

// Runs the scene's analysis and writes the outputs into outdir (created if needed).
//
// Dynamic analyses: optional static preload at start_time, consistent initial accelerations,
// then steps of analysis.step; with align_steps, every breakpoint of a load or drive profile
// (Profile::Breakpoints) in (start_time, end_time) falls on a step end (a grid step end within
// a tenth of a step of a breakpoint moves onto it). Rows are recorded at start_time, at the
// first step end at or after each multiple of outputs.interval (every step when 0) and at the
// last step end. Static analyses: SolveStatic at statics.time, one row.
// Numerical failure, a stop request and write errors end the run with a result (and
// summary.json status "failed" or "interrupted"), never an exception.
// Throws InputError for invalid settings or outputs (naming the field) and when outdir or its
// files cannot be created.
RunResult RunScene(const Scene& scene, const std::string& outdir, const RunOptions& options = {});

}  // namespace screwfem
