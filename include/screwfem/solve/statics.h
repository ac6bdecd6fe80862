// Static equilibrium on the Lie group with load stepping (docs/architecture.md, "One time step").
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "screwfem/model/data.h"
#include "screwfem/model/enum_names.h"
#include "screwfem/solve/common.h"  // SolveAssembledSystem, SolveFactorizedSystem
#include "screwfem/solve/stop.h"

namespace screwfem {

// How the load factor s moves (scene key analysis.statics.method; docs/numerics.md, "Path-following statics",
// docs/numerics.md "Path-following statics"):
//   kLoad:      load stepping, s prescribed per step (passes limit points of a *prescribed
//               drive's* path, i.e. displacement control, but stops at a limit load);
//   kArcLength: arc-length continuation (Crisfield), s an unknown bound by the step's arc
//               length: traces limit points and snap-backs.
enum class StaticMethod { kLoad, kArcLength };
template <>
struct EnumNames<StaticMethod> {
  static constexpr std::array<EnumName<StaticMethod>, 2> kValues = {{
      {StaticMethod::kLoad, "load", "load stepping: the load factor prescribed at each step"},
      {StaticMethod::kArcLength, "arclength",
       "arc-length continuation (Crisfield): through limit points and snap-backs"},
  }};
};

struct StaticOptions {
  double time = 0.0;  // profiles of loads and drives are evaluated at this time
  StaticMethod method = StaticMethod::kLoad;
  // Continuation: data holds an equilibrium at start_load_factor (0: the unloaded reference
  // state, or any state a previous solve ended in); the solve traces the path from there to
  // end_load_factor (which may be below start_load_factor: unloading).
  double start_load_factor = 0.0;
  double end_load_factor = 1.0;
  int load_steps = 10;  // initial number of equal load increments
  // Load stepping: a failed step is retried with half the increment, down to the initial
  // increment / 2^max_halvings (the smallest increment; below it the solve stops).
  int max_halvings = 12;
  int max_iterations = 30;  // Newton iterations per load step
  // Accepted steps at most (either method); 0: automatic, 2 load_steps + 1000. The solve
  // stops with a message when it is reached.
  int max_steps = 0;
  // Arc length (method kArcLength; docs/numerics.md, "Path-following statics"). Lengths are in the metric
  // |dx|^2 = sum (translations / length_scale)^2 + rotation_weight sum rotations^2 over the
  // node and joint unknowns (joint coordinates by the kind of their axis).
  double arc_length = 0.0;      // first arc length; 0: |dx/ds| (end - start) / load_steps
  double arc_length_min = 0.0;  // 0: the first / 2^max_halvings
  double arc_length_max = 0.0;  // 0: the larger of 10 x the first and the motion of every
                                // moving node by kArcLengthMaxResolution length scales
  int desired_iterations = 5;   // Newton solves per step the step-length controller aims
                                // at (at most max_iterations)
  double psi = 0.0;             // 0: cylindrical constraint, 1: spherical
  double rotation_weight = 0.0;
  // The exact tangent: the derivative of the joints' constraint forces d(B^T lambda)/dq in the
  // matrix (quadratic convergence with loaded joints, e.g. under displacement control);
  // false: the matrix of the dynamic solver (B^T lambda's derivative omitted).
  bool constraint_force_tangent = true;
  // Converged when the last Newton increment was below increment_tolerance (translations
  // relative to the model's length scale, rotations in rad) and either |R|_inf <=
  // residual_tolerance * (largest force term in R) or |R|_inf is at its round-off floor (32 eps
  // times the largest term that cancels in R, e.g. EA max(|d|, |x|) / L). Every load step
  // makes at least one Newton correction.
  double residual_tolerance = 1e-10;
  double increment_tolerance = 1e-10;
  double constraint_tolerance = 1e-10;  // |phi|_inf
};

// Range of StaticOptions::load_steps (scene files: analysis.load_steps); max_iterations and
// max_halvings have the ranges of the dynamic solver (kMaxNewtonIterations, kMaxHalvings;
// common.h).
// The default largest arc length lets every moving node move this many length scales per
// step (StaticOptions::arc_length_max = 0; docs/scene-format.md, `analysis.statics`).
inline constexpr double kArcLengthMaxResolution = 0.05;
inline constexpr int kMaxLoadSteps = 1000000;

inline constexpr int kMaxStaticSteps = 10000000;

// Throws InputError "<owner>.<field>: what is expected" unless time is finite, load_steps in
// [1, kMaxLoadSteps], max_halvings in [0, 30], max_iterations in [1, 1000], the tolerances
// finite and > 0, the load factors finite, max_steps in [0, kMaxStaticSteps], the arc lengths
// finite and >= 0 (min <= max when both are given), desired_iterations in [1, 1000] (the
// controller aims at the smaller of it and max_iterations),
// psi and rotation_weight finite and >= 0.
void ValidateStaticOptions(const StaticOptions& options, const std::string& owner);

struct StaticStep {
  double load_factor = 0.0;
  int iterations = 0;
  std::vector<double> residual_norms;  // |R|_inf before each Newton solve, then at convergence
};

struct StaticResult {
  bool converged = false;
  bool interrupted = false;  // ended by a StopRequest (then not converged)
  // Stopped at a limit point of the path (load stepping cannot pass it): see message.
  bool limit_point = false;
  double load_factor = 0.0;  // last converged load factor (end_load_factor when converged)
  int load_steps = 0;        // accepted load steps
  int total_iterations = 0;
  int halvings = 0;  // failed load steps retried with half the increment
  std::vector<StaticStep> steps;
  // Limit points passed (arc length: the load factor's increment changed sign), each the
  // extremum of a parabola through the three converged points around it.
  std::vector<double> limit_points;
  std::string message;  // why it failed (empty on success)
};

// Called after every converged step with data in that equilibrium.
using StaticStepCallback = std::function<void(const StaticStep& step)>;

// Brings the model from data's current state (an equilibrium at options.start_load_factor) to
// equilibrium at options.end_load_factor. On failure data holds the last converged state.
// `stop` is polled before every Newton iteration; when it is requested the solve ends with
// interrupted = true at the last converged step. The solve is bounded: it stops (converged =
// false, with a message) at the smallest increment, after max_steps accepted steps, and at a
// limit point that load stepping cannot pass (limit_point = true).
StaticResult SolveStatic(const Model& model, Data& data, const StaticOptions& options = {},
                         const StopRequest& stop = {}, const StaticStepCallback& on_step = {});

}  // namespace screwfem
