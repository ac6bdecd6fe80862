// Static equilibrium on the Lie group with load stepping (method.md §5.6).
#pragma once

#include <string>
#include <vector>

#include "screwfem/model/data.h"
#include "screwfem/solve/stop.h"

namespace screwfem {

// Solves data.matrix * x = -data.residual (the system left by Assemble) into data.increment
// (global order). Returns false when the matrix is singular.
bool SolveAssembledSystem(const Model& model, Data& data);
// The same with the factorisation data.matrix already holds (from an earlier
// SolveAssembledSystem): only data.residual is read.
bool SolveFactorizedSystem(const Model& model, Data& data);

struct StaticOptions {
  double time = 0.0;                  // profiles of loads and drives are evaluated at this time
  int load_steps = 10;                // initial number of equal load increments
  int max_halvings = 12;              // consecutive halvings of the load increment
  int max_iterations = 30;            // Newton iterations per load step
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
// max_halvings have the ranges of the dynamic solver (kMaxNewtonIterations, kMaxHalvings).
inline constexpr int kMaxLoadSteps = 1000000;

// Throws InputError "<owner>.<field>: what is expected" unless time is finite, load_steps in
// [1, kMaxLoadSteps], max_halvings in [0, 30], max_iterations in [1, 1000] and the tolerances
// finite and > 0.
void ValidateStaticOptions(const StaticOptions& options, const std::string& owner);

struct StaticStep {
  double load_factor = 0.0;
  int iterations = 0;
  std::vector<double> residual_norms;  // |R|_inf before each Newton solve, then at convergence
};

struct StaticResult {
  bool converged = false;
  bool interrupted = false;     // ended by a StopRequest (then not converged)
  double load_factor = 0.0;     // last converged load factor (1 when converged)
  int load_steps = 0;           // accepted load steps
  int total_iterations = 0;
  int halvings = 0;             // failed load steps retried with half the increment
  std::vector<StaticStep> steps;
  std::string message;          // why it failed (empty on success)
};

// Brings the model from data's current state to equilibrium under the full loads. On failure
// data holds the last converged state. `stop` is polled before every Newton iteration; when
// it is requested the solve ends with interrupted = true at the last converged load step.
StaticResult SolveStatic(const Model& model, Data& data, const StaticOptions& options = {},
                         const StopRequest& stop = {});

}  // namespace screwfem
