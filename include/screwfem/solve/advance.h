// The stepping loop: Advance moves a simulation to a time under one step policy, and is what
// every driver of the integrator runs (the run loop of RunScene, Python's Simulation.step and
// advance_to, AdvanceTo). It owns the policy in one place: fixed or error-controlled steps,
// steps that end on the profile breakpoints (schedule.h), the caller's output times (reported
// inside error-controlled steps for dense output), and the stop request.
#pragma once

#include <limits>

#include "screwfem/model/data.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/stop.h"

namespace screwfem {

enum class StepKind {
  kFixed,            // Step: fixed steps, halved where Newton fails
  kErrorControlled,  // AdaptiveStep: the options' tolerances and step limits (DynamicOptions)
};

// How Advance chooses its steps.
struct StepPolicy {
  StepKind kind = StepKind::kFixed;
  // Fixed steps: their size. Either kind: Advance ends once data.time >= t_until - 1e-9 step
  // (step 0: at t_until exactly, where error-controlled steps land).
  double step = 0.0;
  // Fixed steps: end on the schedule's step ends (a grid of `step` with the profile breakpoints
  // inserted), the time set to each end so that round-off does not accumulate (RunScene).
  // nullptr: steps of exactly `step`, each from the end of the last (as Step(h)).
  const StepSchedule* schedule = nullptr;

  static StepPolicy Fixed(double h) { return {StepKind::kFixed, h, nullptr}; }
  static StepPolicy OnSchedule(const StepSchedule& s) { return {StepKind::kFixed, s.step(), &s}; }
  // `end_step`: a nominal step, for the end test only (RunScene's analysis.step with step: auto).
  static StepPolicy ErrorControlled(double end_step = 0.0) {
    return {StepKind::kErrorControlled, end_step, nullptr};
  }
};

// What the caller of Advance does between steps; every member's default does nothing. Advance
// calls it from the stepping thread, and it allocates only what the caller's code allocates.
class AdvanceObserver {
 public:
  virtual ~AdvanceObserver() = default;
  // Before every step: the time at which the step's run-time inputs are to be held
  // (Data::inputs, e.g. from a table): the step's end with fixed steps, its start with
  // error-controlled ones (whose end is not known before the step).
  virtual void BeforeStep(double /*t_inputs*/) {}
  // The caller's next output time (infinity: none). Error-controlled steps report each one
  // that falls inside the step just taken, before the last 1e-9 of the step (OutputInsideStep);
  // one at the step's end is the caller's to record in AfterStep.
  virtual double NextOutputTime() const { return std::numeric_limits<double>::infinity(); }
  // An output time t inside the step just taken (error-controlled steps): data is at the step's
  // end, and InterpolateStep(model, data, integrator, t, out) gives the state at t. The observer
  // moves NextOutputTime past t. False ends Advance (AdvanceResult::stopped).
  virtual bool OutputInsideStep(double /*t*/) { return true; }
  // After every accepted step, data at its end; `last`: the step reached t_until. False ends
  // Advance (AdvanceResult::stopped).
  virtual bool AfterStep(bool /*last*/) { return true; }
};

// The outcome of Advance. ok: data.time reached t_until; iterations: the Newton iterations of
// all its steps; substeps: the (sub)steps accepted (halved fixed steps count each substep);
// message: on failure, when and why.
struct AdvanceResult : StepResult {
  long steps = 0;                    // accepted steps (Step or AdaptiveStep calls)
  bool interrupted_in_step = false;  // interrupted inside a step (between its attempts or
                                     // substeps) rather than before one
  bool stopped = false;              // the observer ended it (then not ok)
};

// Steps data from data.time to t_until under `policy` (see StepPolicy). `stop` is polled before
// every step and by the step before each of its attempts (AdvanceResult::interrupted, data at
// the end of the last accepted (sub)step). On a failed step data is where the step left it
// (Step, AdaptiveStep) and the result holds the step's message. With t_until <= data.time it
// takes no step. Requires InitializeDynamics. No allocation unless a step fails or is
// interrupted (or the observer allocates).
AdvanceResult Advance(const Model& model, Data& data, Integrator& integrator,
                      const StepPolicy& policy, double t_until, AdvanceObserver* observer = nullptr,
                      const StopRequest& stop = {});

// Error-controlled steps until data.time == t_end exactly: Advance with
// StepPolicy::ErrorControlled(). The controller's state carries over between calls, so stepping
// to a series of output times costs at most one shortened step per call.
StepResult AdvanceTo(const Model& model, Data& data, Integrator& integrator, double t_end,
                     const StopRequest& stop = {});

}  // namespace screwfem
