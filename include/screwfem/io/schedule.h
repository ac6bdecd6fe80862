// The step ends of a dynamic run (run.h): a uniform grid with the profile breakpoints
// inserted, so that jumps of prescribed accelerations and load rates fall on step ends
// (method.md §5.5).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "screwfem/model/data.h"
#include "screwfem/solve/dynamics.h"  // ProfileBreakpoints

namespace screwfem {

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
  bool Accepts(double t) const {
    return std::isfinite(t) && t >= start_ - tolerance_ && !Done(t);
  }

 private:
  double start_, end_, step_, tolerance_;
  std::vector<double> targets_;  // sorted breakpoints in (start, end), then end
};

}  // namespace screwfem
