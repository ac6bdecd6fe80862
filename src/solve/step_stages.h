// Internal to screwfem::solve: the stages of one generalized-alpha step (docs/architecture.md, "One time step") and
// what the fixed steps (Step, dynamics.cpp) and the error-controlled ones (AdaptiveStep,
// error_control.cpp) share around them: trying a step, saving and restoring its start, counting
// an accepted step and the restart after it.
#pragma once

#include <string>

#include "screwfem/solve/dynamics.h"

namespace screwfem::generalized_alpha {

// Whether the workspace of error-controlled steps (PrepareAdaptiveSteps) is sized for `model`
// and `data`: the vectors and the saved configuration (also for a model without unknowns).
bool AdaptiveStepsPrepared(const Model& model, const Data& data, const Integrator& integ);

// The dynamic assembly at `time` whose matrix is the mass matrix alone (c_M = 1, c_C = c_K = 0):
// the saddle-point solves for accelerations and multipliers at a fixed state (the consistent
// start, ConsistentStart; a tendon caught taut, CatchTendons).
inline AssemblyOptions MassMatrixOptions(double time) {
  AssemblyOptions o;
  o.time = time;
  o.dynamics = true;
  o.c_mass = 1.0;
  o.c_damping = 0.0;
  o.c_stiffness = 0.0;
  return o;
}

// One generalized-alpha step of size h from the current state (docs/architecture.md, "One time step"): predict, then
// Newton iterations of update configuration -> assemble -> check convergence -> correct, then
// accept. Returns the number of Newton corrections, or -1 on failure (state then undefined:
// the caller restores). `conservative`: full Newton from the zero-acceleration start, whatever
// the options (the retry of a step the faster settings could not do).
// The step ends at t_end (= its start + h up to rounding; exactly a breakpoint when it ends on
// one); `left_limit`: the profiles are evaluated just before t_end (a step ending on a
// breakpoint, docs/numerics.md, "Restarts at breakpoints" step 1).
int TryStep(const Model& model, Data& data, Integrator& integ, double h, double t_end,
            bool left_limit, bool conservative, std::string* why);

// Saves the step's start (SaveStepStart) and tries the step (TryStep); when that fails with the
// options' faster settings (the simplified iteration or the predictor), retries the same step
// with full Newton from the zero-acceleration start before the caller halves or shrinks it
// (counted in Integrator::retries). Returns TryStep's result.
int TryStepWithRetry(const Model& model, Data& data, Integrator& integ, double h, double t_end,
                     bool left_limit, std::string* why);

// The state at the start of a step (configuration, velocities, accelerations, auxiliary
// acceleration, multipliers, slack tendons), saved into and restored from the integrator.
void SaveStepStart(const Data& data, Integrator& integ);
void RestoreStepStart(Data& data, Integrator& integ, double t);

// The statistics of an accepted step or substep of size h that took `iterations` Newton
// corrections, and the step history (summary.json).
void CountAcceptedStep(Integrator& integ, double h, int iterations);

// After an accepted (sub)step: when it ended on a breakpoint, or a length-driven tendon went
// slack or taut in it (docs/numerics.md, "Length-driven tendons"), the forces jump, so the
// integrator restarts as at the start (docs/numerics.md, "Restarts at breakpoints": consistent vdot, lambda and a from
// the right limits); a tendon caught taut first stops its route's stretching rate
// inelastically (CatchTendons). *restarted says whether it restarted. False, with the message,
// when the catch or the restart failed.
bool RestartAfterStep(const Model& model, Data& data, Integrator& integ, bool at_breakpoint,
                      bool* restarted, std::string* message);

// "step interrupted at t = ... s": the message of a step a StopRequest ended.
std::string InterruptedMessage(double t);

}  // namespace screwfem::generalized_alpha
