#include "screwfem/solve/statics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem {

bool SolveAssembledSystem(const Model& model, Data& data) {
  if (data.matrix.Factorize() >= 0) return false;
  return SolveFactorizedSystem(model, data);
}

bool SolveFactorizedSystem(const Model& model, Data& data) {
  const int n = model.num_unknowns();
  for (int i = 0; i < n; ++i)
    data.rhs(model.permutation[static_cast<std::size_t>(i)]) = -data.residual(i);
  data.matrix.Solve(data.rhs);
  for (int i = 0; i < n; ++i)
    data.increment(i) = data.rhs(model.permutation[static_cast<std::size_t>(i)]);
  return data.increment.allFinite();
}

namespace {

std::string Format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

std::string ElementLabel(const Model& m, int e) {
  const RodElement& el = m.elements[static_cast<std::size_t>(e)];
  const Rod& rod = m.rods[static_cast<std::size_t>(el.rod)];
  return "element " + std::to_string(e - rod.first_element) + " of rod '" + rod.name + "'";
}

}  // namespace

void ValidateStaticOptions(const StaticOptions& o, const std::string& owner) {
  const auto require = [&](bool ok, const char* field, const char* what) {
    if (!ok) throw InputError(owner + "." + field + ": " + what);
  };
  require(std::isfinite(o.time), "time", "must be finite");
  require(o.load_steps >= 1 && o.load_steps <= kMaxLoadSteps, "load_steps",
          "must lie in [1, 1000000]");
  require(o.max_halvings >= 0 && o.max_halvings <= kMaxHalvings, "max_halvings",
          "must lie in [0, 30]");
  require(o.max_iterations >= 1 && o.max_iterations <= kMaxNewtonIterations, "max_iterations",
          "must lie in [1, 1000]");
  for (const auto& [value, field] : {std::pair{o.residual_tolerance, "residual_tolerance"},
                                     std::pair{o.increment_tolerance, "increment_tolerance"},
                                     std::pair{o.constraint_tolerance, "constraint_tolerance"}})
    require(std::isfinite(value) && value > 0.0, field, "must be finite and > 0");
}

namespace {

// Scale of the constraint rows: the largest stiffness of the model (method.md §5.6).
double ConstraintScale(const Model& model) {
  double k_scale = 1.0;
  for (const Rod& r : model.rods)
    k_scale = std::max(k_scale, r.section.stiffness.maxCoeff() / std::max(r.length, 1e-12));
  for (const Joint& j : model.joints) k_scale = std::max(k_scale, j.stiffness.maxCoeff());
  return k_scale;
}

enum class LoadStepEnd { kConverged, kFailed, kStopped };

// Newton iterations at the load factor opt.load_factor from the current state: records the
// residual norms and the iterations in `step`, the cause of a failure in `cause`.
LoadStepEnd IterateLoadStep(const Model& model, Data& data, const StaticOptions& options,
                            const AssemblyOptions& opt, double k_scale, const StopRequest& stop,
                            StaticStep& step, std::string& cause) {
  double last_increment = INFINITY;
  for (int it = 0; it <= options.max_iterations; ++it) {
    if (stop.Requested()) return LoadStepEnd::kStopped;
    if (!Assemble(model, data, opt)) {
      if (data.failed_element >= 0) {
        cause = ElementLabel(model, data.failed_element) +
                Format(" rotates by %.4g rad, beyond what one helical element represents "
                       "(2 pi); use more elements",
                       data.failed_rotation);
      } else {
        cause = "the residual is not finite";
      }
      return LoadStepEnd::kFailed;
    }
    const double res = model.nv > 0 ? data.residual.head(model.nv).cwiseAbs().maxCoeff() : 0.0;
    const double con = model.nc > 0 ? data.residual.tail(model.nc).cwiseAbs().maxCoeff() / k_scale
                                    : 0.0;
    step.residual_norms.push_back(res);
    const double scale = std::max(data.force_scale, 1e-300);
    // Below this level the residual is round-off (e.g. eps EA |d|/L in a stiff rod).
    const double floor = 32.0 * std::numeric_limits<double>::epsilon() *
                         std::max(data.term_scale, data.force_scale);
    // There the residual no longer measures the error; the last Newton correction does, so
    // it must be small as well (as in the dynamic solver).
    const bool at_floor = res <= floor;
    if (con <= options.constraint_tolerance && last_increment <= options.increment_tolerance &&
        (at_floor || res <= options.residual_tolerance * scale)) {
      step.iterations = it;
      return LoadStepEnd::kConverged;
    }
    if (it == options.max_iterations) {
      cause = Format("Newton did not converge in %g iterations (residual %.3g, relative %.3g)",
                     options.max_iterations, res, res / scale);
      return LoadStepEnd::kFailed;
    }
    if (!SolveAssembledSystem(model, data)) {
      cause = "the tangent matrix is singular (a mechanism, or unsupported free motion)";
      return LoadStepEnd::kFailed;
    }
    Retract(model, data, data.increment.head(model.nv));
    data.lambda += k_scale * data.increment.tail(model.nc);
    last_increment = ScaledIncrementSize(model, data.increment.head(model.nv));
  }
  return LoadStepEnd::kFailed;
}

}  // namespace

StaticResult SolveStatic(const Model& model, Data& data, const StaticOptions& options,
                         const StopRequest& stop) {
  StaticResult result;
  State saved;
  SaveState(data, &saved);
  Eigen::VectorXd saved_lambda = data.lambda;
  auto restore = [&] {
    RestoreState(saved, data);
    data.lambda = saved_lambda;
    UpdateBranchReferences(model, data);
  };

  const double k_scale = ConstraintScale(model);
  AssemblyOptions opt;
  opt.time = options.time;
  opt.s_constraints = opt.s_multipliers = k_scale;

  const double ds0 = 1.0 / std::max(options.load_steps, 1);
  double s = 0.0, ds = ds0;
  int consecutive_halvings = 0;
  std::string last_cause;
  while (s < 1.0) {
    // Snap to 1 when only round-off separates s + ds from it (ten steps of 0.1 sum to
    // 1 - 1e-16, which would otherwise cost an extra load step).
    const double target = s + ds >= 1.0 - 1e-12 ? 1.0 : s + ds;
    opt.load_factor = target;
    StaticStep step;
    step.load_factor = target;
    const LoadStepEnd end =
        IterateLoadStep(model, data, options, opt, k_scale, stop, step, last_cause);
    if (end == LoadStepEnd::kStopped) {
      restore();
      result.interrupted = true;
      result.message = Format("static solve interrupted at load factor %.6g", s);
      return result;
    }
    result.total_iterations += step.iterations;
    if (end == LoadStepEnd::kConverged) {
      UpdateBranchReferences(model, data);
      SaveState(data, &saved);
      saved_lambda = data.lambda;
      s = target;
      result.load_factor = s;
      ++result.load_steps;
      result.steps.push_back(std::move(step));
      ds = std::min(ds0, 1.5 * ds);
      consecutive_halvings = 0;
      continue;
    }
    // Failed load step: back to the last converged state, retry with half the increment.
    restore();
    ++result.halvings;
    ds *= 0.5;
    // The limit is on consecutive halvings: progress is still made while steps succeed, each
    // advancing the load factor by at least ds0 / 2^max_halvings.
    if (++consecutive_halvings > options.max_halvings) {
      result.message = Format("static solve failed at load factor %.6g (last converged %.6g): ",
                              target, s) + last_cause;
      return result;
    }
  }
  result.converged = true;
  return result;
}

}  // namespace screwfem
