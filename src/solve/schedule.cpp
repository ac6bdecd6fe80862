#include "screwfem/solve/schedule.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "screwfem/elements/registry.h"
#include "screwfem/model/errors.h"

namespace screwfem {

std::vector<double> ProfileBreakpoints(const Model& model) {
  std::vector<double> b;
  const auto add = [&b](const Profile& profile) {
    const std::vector<double> p = profile.Breakpoints();
    b.insert(b.end(), p.begin(), p.end());
  };
  ForEachKindProfile(model, add);
  return b;
}

std::vector<double> SortedBreakpoints(std::vector<double> breakpoints, double after, double before,
                                      double tolerance) {
  std::sort(breakpoints.begin(), breakpoints.end());
  std::vector<double> sorted;
  for (double b : breakpoints)
    if (b > after + tolerance && b < before - tolerance &&
        (sorted.empty() || b > sorted.back() + tolerance))
      sorted.push_back(b);
  return sorted;
}

double NextBreakpoint(const std::vector<double>& breakpoints, double t, double tolerance) {
  const auto it = std::upper_bound(breakpoints.begin(), breakpoints.end(), t + tolerance);
  return it != breakpoints.end() ? *it : std::numeric_limits<double>::infinity();
}

double SnapToBreakpoint(const std::vector<double>& breakpoints, double t, double end,
                        double tolerance) {
  const double bp = NextBreakpoint(breakpoints, t, tolerance);
  return std::abs(bp - end) <= tolerance ? bp : end;
}

std::string TimeGridProblem(double start, double end, double step) {
  const double t_max = std::max(std::abs(start), std::abs(end));
  const double spacing = std::nextafter(t_max, INFINITY) - t_max;
  if (spacing <= kTimeGridAccuracy * step) return {};
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "doubles near t = %.6g s are %.3g s apart, so steps of %.6g s cannot be taken to "
                "a relative accuracy of %g (the step would silently change); use a step of at "
                "least %.3g s, or times nearer to 0 (e.g. start_time 0)",
                t_max, spacing, step, kTimeGridAccuracy, spacing / kTimeGridAccuracy);
  return buf;
}

void ValidateTimeGrid(double start, double end, double step, const std::string& owner) {
  const auto require = [&](bool ok, const char* field, const std::string& what) {
    if (!ok) throw InputError(owner + "." + field + ": " + what);
  };
  require(std::isfinite(start), "start_time", "must be finite");
  require(std::isfinite(end) && end >= start, "end_time",
          "must be finite and not before start_time");
  require(std::isfinite(step) && step > 0.0, "step", "must be a finite time > 0 s");
  require((end - start) / step <= 1e9, "step",
          "more than 1e9 time steps from start_time to end_time");
  const std::string problem = TimeGridProblem(start, end, step);
  require(problem.empty(), std::abs(start) > std::abs(end) ? "start_time" : "end_time", problem);
}

StepSchedule::StepSchedule(double start, double end, double step, std::vector<double> breakpoints)
    : start_(start),
      end_(end),
      step_(step),
      tolerance_(1e-9 * step),
      breakpoints_(SortedBreakpoints(std::move(breakpoints), start, end, 1e-9 * step)) {}

double StepSchedule::Next(double t) const {
  // The next breakpoint (or the end) after t.
  const double target = std::min(NextBreakpoint(breakpoints_, t, tolerance_), end_);
  // The next grid point, skipping any within kSnap steps of t (t was a breakpoint just before it).
  // (At most two more grid points: n is the grid index of t; bounded also for t outside the
  // precondition, where n + 1 may round to n.)
  double n = std::floor((t - start_) / step_ + 1e-9) + 1.0;
  double grid = start_ + n * step_;
  for (int k = 0; k < 2 && grid <= t + kSnap * step_; ++k) grid = start_ + (++n) * step_;
  // A breakpoint before the grid point, or just after it, replaces it.
  return EndsOnBreakpoint(grid, target, kSnap * step_) ? target : grid;
}

}  // namespace screwfem
