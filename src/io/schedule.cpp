#include "screwfem/io/schedule.h"

#include <algorithm>
#include <cmath>

namespace screwfem {

std::vector<double> ProfileBreakpoints(const Model& model) {
  std::vector<double> b;
  for (const PointLoad& l : model.point_loads) {
    const std::vector<double> p = l.profile.Breakpoints();
    b.insert(b.end(), p.begin(), p.end());
  }
  for (const RodLoad& l : model.rod_loads) {
    const std::vector<double> p = l.profile.Breakpoints();
    b.insert(b.end(), p.begin(), p.end());
  }
  for (const Joint& j : model.joints)
    if (j.drive != DriveKind::kNone) {
      const std::vector<double> p = j.drive_profile.Breakpoints();
      b.insert(b.end(), p.begin(), p.end());
    }
  return b;
}

StepSchedule::StepSchedule(double start, double end, double step, std::vector<double> breakpoints)
    : start_(start), end_(end), step_(step), tolerance_(1e-9 * step) {
  std::sort(breakpoints.begin(), breakpoints.end());
  for (double b : breakpoints)
    if (b > start_ + tolerance_ && b < end_ - tolerance_ &&
        (targets_.empty() || b > targets_.back() + tolerance_))
      targets_.push_back(b);
  targets_.push_back(end_);
}

double StepSchedule::Next(double t) const {
  // The next breakpoint (or the end) after t.
  const auto it = std::upper_bound(targets_.begin(), targets_.end(), t + tolerance_);
  const double target = it != targets_.end() ? *it : end_;
  // The next grid point, skipping any within kSnap steps of t (t was a breakpoint just before it).
  double n = std::floor((t - start_) / step_ + 1e-9) + 1.0;
  double grid = start_ + n * step_;
  while (grid <= t + kSnap * step_) grid = start_ + (++n) * step_;
  // A breakpoint before the grid point, or just after it, replaces it.
  return target <= grid + kSnap * step_ ? target : grid;
}

}  // namespace screwfem
