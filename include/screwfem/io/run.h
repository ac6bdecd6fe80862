// Running a scene and writing its results (issue: the main job).
//
// OUTDIR/points.csv   t, then per point P: P.x P.y P.z P.vx P.vy P.vz P.ax P.ay P.az (world, SI)
// OUTDIR/joints.csv   t, then per joint J (per coordinate i for multi-DOF joints: J.i.q ...):
//                     J.q J.qd J.qdd J.effort
// OUTDIR/summary.json resolved settings, counts, steps, Newton iterations, halvings, wall time,
//                     largest constraint residual, status and message
// OUTDIR/vtk/frame_NNNNN.vtp and OUTDIR/vtk/motion.pvd (ParaView)
// Files are written as the run goes and flushed at every output row, so an interrupted run
// leaves valid files up to the last completed output step.
#pragma once

#include <atomic>
#include <functional>
#include <string>

#include "screwfem/io/scene.h"

namespace screwfem {

struct RunOptions {
  bool progress = false;                    // progress bar on stderr
  const std::atomic<bool>* stop = nullptr;  // set asynchronously (e.g. SIGINT) to stop cleanly
};

struct RunResult {
  bool ok = false;
  bool interrupted = false;
  double end_time = 0.0;        // simulated time reached [s]
  long steps = 0;
  long newton_iterations = 0;
  int max_iterations_per_step = 0;
  long halvings = 0;
  double wall_seconds = 0.0;
  double max_constraint_residual = 0.0;
  std::string message;          // why it stopped early, with the time
};

// Runs the scene's analysis and writes the outputs into outdir (created if needed).
RunResult RunScene(const Scene& scene, const std::string& outdir, const RunOptions& options = {});

}  // namespace screwfem
