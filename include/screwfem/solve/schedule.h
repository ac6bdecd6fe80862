// Where time steps end. The profile breakpoints (the times where a drive or load profile has a
// kink or a jump) and the one rule that puts a step's end on them, used by the step schedule of
// a run (StepSchedule: a uniform grid with the breakpoints inserted, docs/architecture.md, "One time step"), by Step's
// substeps and by AdaptiveStep; and the check that a run's step ends are representable.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "screwfem/model/data.h"

namespace screwfem {

// Every breakpoint (Profile::Breakpoints) of the model's load, drive, tendon tension and force
// element actuator profiles, unsorted.
std::vector<double> ProfileBreakpoints(const Model& model);

// The breakpoints sorted, those after `after + tolerance` and before `before - tolerance` only,
// and each more than `tolerance` after the one before it.
std::vector<double> SortedBreakpoints(std::vector<double> breakpoints, double after, double before,
                                      double tolerance);

// The first of the sorted `breakpoints` after t + tolerance, or infinity.
double NextBreakpoint(const std::vector<double>& breakpoints, double t, double tolerance);

// `end`, or the first breakpoint after t when that lies within `tolerance` of end (either
// side): a step end that is a breakpoint up to the rounding of start + h.
double SnapToBreakpoint(const std::vector<double>& breakpoints, double t, double end,
                        double tolerance);

// Whether a step that would end at `end` ends on the breakpoint `breakpoint` instead: when the
// breakpoint comes before the end, or at most `margin` after it (then the step is shortened
// or stretched to end exactly on it).
inline bool EndsOnBreakpoint(double end, double breakpoint, double margin) {
  return breakpoint <= end + margin;
}

// Relative accuracy to which the step ends of a dynamic run must be representable. A time t
// is a double, and consecutive doubles near t are u(t) = 2^(floor(log2 |t|) - 52) apart (about
// 2.2e-16 |t|); a step end start + n h is rounded to that grid, so every step taken differs
// from h by up to u(t_max), t_max = max(|start|, |end|). A grid is accepted when
// u(t_max) <= kTimeGridAccuracy h, i.e. roughly h >= 2.2e-10 t_max: a 1 ms step is fine up
// to t = 4.5e6 s, and start_time 1e15 s (u = 0.125 s) needs h >= 1.25e5 s.
inline constexpr double kTimeGridAccuracy = 1e-6;

// Empty when [start, end] with steps of `step` passes the check above, else the reason (the
// spacing of doubles, the least step and what to do). Requires finite start <= end, step > 0.
std::string TimeGridProblem(double start, double end, double step);

// Throws InputError "<owner>.<field>: ..." unless start and end are finite, end >= start,
// step is finite and > 0, there are at most 1e9 steps and TimeGridProblem is empty (field:
// start_time or end_time, whichever is larger in magnitude, for the last). The check shared
// by runs, scenes and the Python StepSchedule.
void ValidateTimeGrid(double start, double end, double step, const std::string& owner);

// The step ends of a dynamic run with fixed steps (Advance, StepPolicy): a uniform grid with
// the profile breakpoints inserted, so that jumps of prescribed accelerations and load rates
// fall on step ends (docs/architecture.md, "One time step"). Each end is computed from the start and the step's
// index, so round-off does not accumulate over the run.
class StepSchedule {
 public:
  // A grid end within this fraction of a step of a breakpoint is moved onto the breakpoint,
  // so no step is shorter than (1 - kSnap) h except to reach a breakpoint that lies closer to
  // its predecessor, and none is longer than (1 + kSnap) h.
  static constexpr double kSnap = 0.1;

  // Step ends: start + n step for n >= 1, every breakpoint in (start, end), and end.
  // Requires step > 0 and end >= start.
  StepSchedule(double start, double end, double step, std::vector<double> breakpoints);

  // True once t has reached the end (within round-off).
  bool Done(double t) const { return t >= end_ - tolerance_; }
  // The step end following t (t is start or an earlier step end). Requires start <= t and
  // !Done(t) (Accepts(t)).
  double Next(double t) const;
  // True when t is finite, not before start and not Done: a valid argument of Next.
  bool Accepts(double t) const { return std::isfinite(t) && t >= start_ - tolerance_ && !Done(t); }
  double step() const { return step_; }
  double end() const { return end_; }

 private:
  double start_, end_, step_, tolerance_;
  std::vector<double> breakpoints_;  // sorted breakpoints in (start, end)
};

}  // namespace screwfem
