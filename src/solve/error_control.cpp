// Error-controlled time steps (docs/numerics.md, "Adaptive time steps"; docs/numerics.md, "Adaptive time steps"):
// the local error estimate of a generalized-alpha step, its weighted norm, the PI controller
// of the step size and AdaptiveStep.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "screwfem/elements/contact.h"
#include "screwfem/elements/crossing.h"
#include "screwfem/solve/dynamics.h"
#include "step_stages.h"

namespace screwfem {

double LocalErrorConstant(const GeneralizedAlpha& p) {
  return p.beta - 1.0 / 6.0 + 0.5 * (p.alpha_m - p.alpha_f);
}

namespace {

// PI controller (docs/numerics.md, "Adaptive time steps"): the estimate is O(h^3).
constexpr double kSafety = 0.9, kMaxGrowth = 2.0, kMinShrink = 0.2;
constexpr double kOrder = 3.0, kGainI = 0.3 / kOrder, kGainP = 0.4 / kOrder;

// The weight of velocity unknown i in the error norm: translations (node translations and
// prismatic joint coordinates) are measured in units of the model's length scale.
bool IsTranslation(const Model& model, int i) {
  if (i < model.nv_nodes) return false;  // caller handles node blocks
  for (const Joint& j : model.joints) {
    if (i < j.coord || i >= j.coord + j.k()) continue;
    return j.basis.col(i - j.coord).tail<3>().squaredNorm() == 0.0;
  }
  return false;
}

// The weighted RMS norm of integ.error (docs/numerics.md, "Adaptive time steps"): component i divided by
// atol_i + rtol |h dq_i|; *worst = the component with the largest ratio.
double WeightedErrorNorm(const Model& model, const Integrator& integ, double h, int* worst) {
  const DynamicOptions& o = integ.options;
  const double L = model.length_scale;
  double sum = 0.0, largest = -1.0;
  const auto add = [&](int i, double atol) {
    const double r = integ.error(i) / (atol + o.relative_tolerance * std::abs(h * integ.dq(i)));
    sum += r * r;
    if (std::abs(r) > largest) {
      largest = std::abs(r);
      *worst = i;
    }
  };
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    for (int c = 0; c < 3; ++c) add(n.dof + c, o.absolute_tolerance * L);
    for (int c = 3; c < 6; ++c) add(n.dof + c, o.absolute_tolerance);
  }
  for (int i = model.nv_nodes; i < model.nv; ++i)
    add(i, IsTranslation(model, i) ? o.absolute_tolerance * L : o.absolute_tolerance);
  return model.nv > 0 ? std::sqrt(sum / model.nv) : 0.0;
}

// "node 3 (translation)", "joint J2 coordinate 0", ... for the message of a failed step.
std::string DescribeUnknown(const Model& model, int i) {
  char buf[160];
  for (std::size_t n = 0; n < model.nodes.size(); ++n) {
    const int dof = model.nodes[n].dof;
    if (dof >= 0 && i >= dof && i < dof + 6) {
      std::snprintf(buf, sizeof buf, "node %zu %s", n, i - dof < 3 ? "translation" : "rotation");
      const std::string& name = model.nodes[n].name;
      return name.empty() ? std::string(buf) : std::string(buf) + " ('" + name + "')";
    }
  }
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (i >= j.coord && i < j.coord + j.k()) {
      std::snprintf(buf, sizeof buf, "joint %zu coordinate %d", jj, i - j.coord);
      return j.name.empty() ? std::string(buf) : std::string(buf) + " ('" + j.name + "')";
    }
  }
  std::snprintf(buf, sizeof buf, "velocity unknown %d", i);
  return buf;
}

// The end of an error-controlled step of size h from t0 (before t_limit): t_limit or the next
// breakpoint when within 1.1 h; half the way there when within 2 h (no sliver step before it);
// else t0 + h. `truncated`: shorter than h; `left_limit`: it lands on a breakpoint.
struct AdaptiveStepEnd {
  double h, t_end;
  bool truncated, left_limit;
};

AdaptiveStepEnd ChooseStepEnd(const Integrator& integ, double t0, double h, double t_limit) {
  const double snap = 1e-9 * h;
  const double bp = NextBreakpoint(integ.breakpoints, t0, snap);
  const bool target_is_breakpoint = EndsOnBreakpoint(t_limit, bp, 0.0);
  const double target = target_is_breakpoint ? bp : t_limit;
  const double room = target - t0;
  AdaptiveStepEnd e{h, t0 + h, false, false};
  if (room <= 1.1 * h) {
    e.h = room;
    e.t_end = target;
    e.left_limit = target_is_breakpoint;
  } else if (room < 2.0 * h) {
    e.h = 0.5 * room;
    e.t_end = t0 + e.h;
  }
  e.truncated = e.h < h;
  return e;
}

// docs/numerics.md, "Adaptive time steps": a_n approximates vdot at t_n + (alpha_m - alpha_f) h; rescale it to
// the new step size, or the scheme is first order on a variable grid.
void RescaleAuxiliaryAcceleration(const Data& data, Integrator& integ, double h) {
  if (integ.h_last > 0.0 && h != integ.h_last)
    integ.a = data.vdot + (h / integ.h_last) * (integ.a_accepted - data.vdot);
  else
    integ.a = integ.a_accepted;
}

// The dense-output record of the accepted step of size h from t0 (InterpolateStep): data is at
// its end, the integrator holds its start.
void RecordDenseOutput(const Data& data, Integrator& integ, double t0, double h) {
  integ.dense_t0 = t0;
  integ.dense_h = h;
  integ.dense_q0 = integ.q_start;
  integ.dense_v0 = integ.v_start;
  integ.dense_vdot0 = integ.vdot_start;
  integ.dense_lambda0 = integ.lambda_start;
  integ.dense_v1 = data.v;
  integ.dense_vdot1 = data.vdot;
  integ.dense_lambda1 = data.lambda;
  integ.dense_d = h * integ.dq;
}

// The PI controller after a step of size hs accepted with the error norm err; h is the
// controller's size the step was taken from (hs < h when it was truncated to land on a target).
void ControlAfterAcceptedStep(Integrator& integ, double h, double hs, double err, bool truncated) {
  const DynamicOptions& opt = integ.options;
  const double e = std::max(err, 1e-10);
  double factor = kSafety * std::pow(e, -kGainI);
  if (integ.err_last > 0.0)
    factor *= std::pow(integ.err_last / e, kGainP);
  else
    factor = kSafety * std::pow(e, -1.0 / kOrder);
  factor = std::clamp(factor, kMinShrink, integ.allow_growth ? kMaxGrowth : 1.0);
  // A step shortened to land on a target keeps the controller's size (docs/theory.md §N2.4).
  integ.h_control = truncated ? std::max(h, hs * factor) : hs * factor;
  integ.h_control = std::clamp(integ.h_control, opt.min_step, opt.max_step);
  integ.err_last = e;
  integ.allow_growth = true;
  integ.h_last = hs;
}

// The message of an attempt rejected at the smallest step hs (its < 0: Newton failed, why;
// else the error norm err, largest in unknown `worst`).
std::string SmallestStepFailure(const Model& model, double t0, double hs, int its, double err,
                                int worst, const std::string& why) {
  char buf[240];
  if (its < 0)
    std::snprintf(buf, sizeof buf, "step failed at t = %.9g s with the smallest step %.3g s: ", t0,
                  hs);
  else
    std::snprintf(buf, sizeof buf,
                  "step failed at t = %.9g s: with the smallest step %.3g s (min_step) the "
                  "estimated local error is %.4g times the tolerance, largest in ",
                  t0, hs, err);
  return std::string(buf) + (its < 0 ? why : DescribeUnknown(model, worst));
}

}  // namespace

StepResult AdaptiveStep(const Model& model, Data& data, Integrator& integ, double t_limit,
                        const StopRequest& stop) {
  using namespace generalized_alpha;
  StepResult result;
  result.substeps = 0;
  const DynamicOptions& opt = integ.options;
  const double t0 = data.time;
  if (!(t_limit > t0)) {
    result.ok = true;
    return result;
  }
  PrepareAdaptiveSteps(model, data, integ);  // (sized already after the first call)
  double h = integ.h_control;
  if (h <= 0.0) h = opt.initial_step > 0.0 ? opt.initial_step : 1e-3 * (t_limit - t0);
  const double c_err = LocalErrorConstant(integ.params);
  integ.a_accepted = integ.a;
  std::string& why = integ.why;  // capacity reserved at set-up: a failed attempt allocates nothing
  why.clear();
  for (;;) {
    h = std::clamp(h, opt.min_step, opt.max_step);
    const AdaptiveStepEnd end = ChooseStepEnd(integ, t0, h, t_limit);
    const double hs = end.h;
    if (stop.Requested()) {
      result.interrupted = true;
      result.message = InterruptedMessage(t0);
      integ.a = integ.a_accepted;
      return result;
    }
    RescaleAuxiliaryAcceleration(data, integ, hs);
    const int its = CheckStepCrossing(
        model, data, TryStepWithRetry(model, data, integ, hs, end.t_end, end.left_limit, &why),
        &why);
    double err = INFINITY;
    int worst = 0;
    if (its >= 0) {
      integ.error = (c_err * hs * hs) * (integ.a - integ.a_start);
      err = WeightedErrorNorm(model, integ, hs, &worst);
      integ.error_norm = err;
    }
    if (its >= 0 && err <= 1.0) {
      // Accepted: the dense-output record of the step, then the controller.
      RecordDenseOutput(data, integ, t0, hs);
      UpdateBranchReferences(model, data);
      result.iterations += its;
      result.substeps = 1;
      CountAcceptedStep(integ, hs, its);
      AcceptContactHistory(model, data, true);
      ++integ.steps;
      ControlAfterAcceptedStep(integ, h, hs, err, end.truncated);
      data.time = end.t_end;
      // A length-driven tendon went slack or taut, or L_p's rate jumps here: as in Step; the PI
      // memory restarts too.
      bool restarted;
      if (!RestartAfterStep(model, data, integ, end.left_limit, &restarted, &result.message))
        return result;
      if (restarted) integ.err_last = 0.0;
      result.ok = true;
      return result;
    }
    // Rejected: Newton failure halves the step, an error above the tolerance shrinks it by
    // the I controller; the next accepted step may not grow.
    RestoreStepStart(data, integ, t0);
    ++integ.rejected;
    integ.err_last = 0.0;
    integ.allow_growth = false;
    if (hs <= opt.min_step * (1.0 + 1e-12)) {
      result.message = SmallestStepFailure(model, t0, hs, its, err, worst, why);
      if (its < 0) result.message += ContactFailureHint(model, data, hs);
      integ.a = integ.a_accepted;
      return result;
    }
    h = its < 0 ? 0.5 * hs
                : hs * std::clamp(kSafety * std::pow(err, -1.0 / kOrder), kMinShrink, 1.0);
  }
}

}  // namespace screwfem
