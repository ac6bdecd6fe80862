// The step ends of a dynamic run (run.h): a uniform grid with the profile breakpoints
// inserted, so that jumps of prescribed accelerations and load rates fall on step ends
// (method.md §5.5).
#pragma once

#include <vector>

#include "screwfem/model/data.h"

namespace screwfem {

// Every breakpoint (Profile::Breakpoints) of the model's load and drive profiles, unsorted.
std::vector<double> ProfileBreakpoints(const Model& model);

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
  // The step end following t (t is start or an earlier step end). Requires !Done(t).
  double Next(double t) const;

 private:
  double start_, end_, step_, tolerance_;
  std::vector<double> targets_;  // sorted breakpoints in (start, end), then end
};

}  // namespace screwfem
