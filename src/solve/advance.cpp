#include "screwfem/solve/advance.h"

#include <utility>

#include "step_stages.h"

namespace screwfem {

namespace {

// One fixed step: to the schedule's next end (the time then set to it exactly), or of `step`.
StepResult FixedStep(const Model& model, Data& data, Integrator& integ, const StepPolicy& policy,
                     AdvanceObserver& observer, const StopRequest& stop) {
  if (policy.schedule == nullptr) {
    observer.BeforeStep(data.time + policy.step);
    return Step(model, data, integ, policy.step, stop);
  }
  const double t_next = policy.schedule->Next(data.time);
  observer.BeforeStep(t_next);
  StepResult r = Step(model, data, integ, t_next - data.time, stop);
  if (r.ok) data.time = t_next;
  return r;
}

// Reports the caller's output times inside the error-controlled step just taken (up to 1e-9 of
// the step before its end); false if the observer ended Advance.
bool ReportOutputsInsideStep(const Integrator& integ, const Data& data, AdvanceObserver& observer) {
  const double inside = data.time - 1e-9 * integ.dense_h;
  for (double t = observer.NextOutputTime(); t < inside; t = observer.NextOutputTime())
    if (!observer.OutputInsideStep(t)) return false;
  return true;
}

}  // namespace

AdvanceResult Advance(const Model& model, Data& data, Integrator& integ, const StepPolicy& policy,
                      double t_until, AdvanceObserver* observer, const StopRequest& stop) {
  AdvanceObserver nothing;
  AdvanceObserver& obs = observer != nullptr ? *observer : nothing;
  AdvanceResult result;
  result.substeps = 0;
  const double tolerance = 1e-9 * policy.step;
  const auto reached = [&](double t) { return t >= t_until - tolerance; };
  // The workspace of error-controlled steps, before the first (a step allocates nothing).
  if (policy.kind == StepKind::kErrorControlled && !reached(data.time))
    PrepareAdaptiveSteps(model, data, integ);
  while (!reached(data.time)) {
    if (stop.Requested()) {
      result.interrupted = true;
      result.message = generalized_alpha::InterruptedMessage(data.time);
      return result;
    }
    StepResult r;
    if (policy.kind == StepKind::kErrorControlled) {
      obs.BeforeStep(data.time);
      r = AdaptiveStep(model, data, integ, t_until, stop);
    } else {
      r = FixedStep(model, data, integ, policy, obs, stop);
    }
    result.iterations += r.iterations;
    result.substeps += r.substeps;
    if (!r.ok) {
      result.interrupted = r.interrupted;
      result.interrupted_in_step = r.interrupted;
      result.message = std::move(r.message);
      return result;
    }
    ++result.steps;
    if (policy.kind == StepKind::kErrorControlled && !ReportOutputsInsideStep(integ, data, obs)) {
      result.stopped = true;
      return result;
    }
    if (!obs.AfterStep(reached(data.time))) {
      result.stopped = true;
      return result;
    }
  }
  result.ok = true;
  return result;
}

StepResult AdvanceTo(const Model& model, Data& data, Integrator& integ, double t_end,
                     const StopRequest& stop) {
  return Advance(model, data, integ, StepPolicy::ErrorControlled(), t_end, nullptr, stop);
}

}  // namespace screwfem
