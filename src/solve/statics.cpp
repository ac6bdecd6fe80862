#include "screwfem/solve/statics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "screwfem/assemble/assemble.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/crossing.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/common.h"
#include "exact_tangent.h"

namespace screwfem {

namespace {

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
  require(IsEnumValue(o.method), "method", "must be load or arclength");
  require(std::isfinite(o.start_load_factor), "start_load_factor", "must be finite");
  require(std::isfinite(o.end_load_factor), "end_load_factor", "must be finite");
  require(o.load_steps >= 1 && o.load_steps <= kMaxLoadSteps, "load_steps",
          "must lie in [1, 1000000]");
  require(o.max_halvings >= 0 && o.max_halvings <= kMaxHalvings, "max_halvings",
          "must lie in [0, 30]");
  require(o.max_iterations >= 1 && o.max_iterations <= kMaxNewtonIterations, "max_iterations",
          "must lie in [1, 1000]");
  require(o.max_steps >= 0 && o.max_steps <= kMaxStaticSteps, "max_steps",
          "must lie in [0, 10000000] (0: automatic)");
  for (const auto& [value, field] :
       {std::pair{o.arc_length, "arc_length"}, std::pair{o.arc_length_min, "arc_length_min"},
        std::pair{o.arc_length_max, "arc_length_max"}, std::pair{o.psi, "psi"},
        std::pair{o.rotation_weight, "rotation_weight"}})
    require(std::isfinite(value) && value >= 0.0, field, "must be finite and >= 0");
  require(
      o.arc_length_min == 0.0 || o.arc_length_max == 0.0 || o.arc_length_min <= o.arc_length_max,
      "arc_length_min", "must not exceed arc_length_max");
  require(o.desired_iterations >= 1 && o.desired_iterations <= kMaxNewtonIterations,
          "desired_iterations", "must lie in [1, 1000]");
  for (const auto& [value, field] : {std::pair{o.residual_tolerance, "residual_tolerance"},
                                     std::pair{o.increment_tolerance, "increment_tolerance"},
                                     std::pair{o.constraint_tolerance, "constraint_tolerance"}})
    require(std::isfinite(value) && value > 0.0, field, "must be finite and > 0");
}

// Scale of the constraint rows: the largest stiffness of the model (docs/architecture.md, "One time step").
double StaticConstraintScale(const Model& model) {
  double k_scale = 1.0;
  for (const Rod& r : model.rods)
    k_scale = std::max(k_scale, r.section.stiffness.maxCoeff() / std::max(r.length, 1e-12));
  for (const Joint& j : model.joints) k_scale = std::max(k_scale, j.stiffness.maxCoeff());
  return k_scale;
}

namespace {

// Weights of the arc-length metric (docs/numerics.md, "Path-following statics"), velocity layout: translations (node
// translations, joint coordinates whose axis has no rotation part) 1 / length_scale^2,
// rotations rotation_weight.
Eigen::VectorXd MetricWeights(const Model& model, double rotation_weight) {
  Eigen::VectorXd w = Eigen::VectorXd::Zero(model.nv);
  const double t = 1.0 / (model.length_scale * model.length_scale);
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    w.segment<3>(n.dof).setConstant(t);
    w.segment<3>(n.dof + 3).setConstant(rotation_weight);
  }
  for (const Joint& j : model.joints)
    for (int c = 0; c < j.k(); ++c)
      w(j.coord + c) = j.basis.col(c).tail<3>().norm() > 0.0 ? rotation_weight : t;
  return w;
}

enum class LoadStepEnd { kConverged, kFailed, kStopped };

// The equilibrium solver's shared state: options, scales and the workspaces of the bordered
// solves (allocated once per solve).
struct StaticSolver {
  const Model& model;
  Data& data;
  const StaticOptions& options;
  const StopRequest& stop;
  double k_scale = 1.0;
  AssemblyOptions opt;
  Eigen::VectorXd weights;              // arc-length metric (nv)
  Eigen::VectorXd r_s, load, x_r, x_f;  // nv + nc: residual at s, F = -dR/ds, the two solves
  Eigen::VectorXd step_dx;              // nv: the sum of a load step's Newton corrections

  ExactTangentPattern exact_tangent;  // the matrix's pattern with d(B^T lambda)/dq

  StaticSolver(const Model& m, Data& d, const StaticOptions& o, const StopRequest& st)
      : model(m),
        data(d),
        options(o),
        stop(st),
        k_scale(StaticConstraintScale(m)),
        weights(MetricWeights(m, o.rotation_weight)),
        exact_tangent(m, d, o.constraint_force_tangent, &opt) {
    opt.time = o.time;
    opt.s_constraints = opt.s_multipliers = k_scale;
    const int n = m.num_unknowns();
    r_s.resize(n);
    load.resize(n);
    x_r.resize(n);
    x_f.resize(n);
    step_dx.resize(m.nv);
  }
  StaticSolver(const StaticSolver&) = delete;
  StaticSolver& operator=(const StaticSolver&) = delete;

  double Dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
    return (a.head(model.nv).array() * weights.array() * b.head(model.nv).array()).sum();
  }

  // Assembles at opt.load_factor; false (with the cause) if the assembly failed.
  bool AssembleAt(bool matrix, std::string& cause) {
    opt.assemble_matrix = matrix;
    const bool ok = Assemble(model, data, opt);
    opt.assemble_matrix = true;
    if (ok) return true;
    if (data.shape_pair_limit_reached) {
      cause = ShapePairLimitMessage(model);
    } else if (data.failed_element >= 0) {
      cause = ElementLabel(model, data.failed_element) +
              FormatNumbers(
                  " rotates by %.4g rad, beyond what one helical element represents "
                  "(2 pi); use more elements",
                  data.failed_rotation);
    } else {
      cause = "the residual is not finite";
    }
    return false;
  }

  // Convergence test of the state just assembled (data.residual); records |R|_inf in step.
  bool Converged(double last_increment, StaticStep& step, double* res_out, double* con_out) const {
    const double res = model.nv > 0 ? data.residual.head(model.nv).cwiseAbs().maxCoeff() : 0.0;
    const double con =
        model.nc > 0 ? data.residual.tail(model.nc).cwiseAbs().maxCoeff() / k_scale : 0.0;
    step.residual_norms.push_back(res);
    *res_out = res;
    *con_out = con;
    const double scale = std::max(data.force_scale, 1e-300);
    // Below this level the residual is round-off (e.g. eps EA |d|/L in a stiff rod).
    const double floor =
        32.0 * std::numeric_limits<double>::epsilon() * std::max(data.term_scale, data.force_scale);
    // There the residual no longer measures the error; the last Newton correction does, so
    // it must be small as well (as in the dynamic solver).
    const bool at_floor = res <= floor;
    return con <= options.constraint_tolerance && last_increment <= options.increment_tolerance &&
           (at_floor || res <= options.residual_tolerance * scale);
  }

  // Why a load step ran out of Newton iterations: all three criteria of Converged, so that a
  // step held back by its constraints or its increment does not read as "residual 0".
  std::string NotConverged(double res, double con, double last_increment) const {
    return FormatNumbers(
               "Newton did not converge in %g iterations (force residual %.3g, relative %.3g; ",
               options.max_iterations, res, res / std::max(data.force_scale, 1e-300)) +
           FormatNumbers("constraint residual %.3g, tolerance %.3g; last scaled increment %.3g)",
                         con, options.constraint_tolerance, last_increment);
  }

  // With data.residual assembled (matrix included) at s = opt.load_factor: the load vector
  // F = -dR/ds = R(s) - R(s + 1) (R is affine in s: loads and drive values are scaled by it),
  // the factorisation, x_r = -A^-1 R and x_f = A^-1 F (docs/numerics.md, "Path-following statics"). False if the
  // matrix is singular or an assembly failed.
  bool BorderedSolves(std::string& cause) {
    r_s = data.residual;
    const double s = opt.load_factor;
    opt.load_factor = s + 1.0;
    const bool ok = AssembleAt(false, cause);
    opt.load_factor = s;
    if (!ok) return false;
    load = r_s - data.residual;
    data.residual = r_s;
    if (!SolveAssembledSystem(model, data)) {
      cause = "the tangent matrix is singular (a mechanism, or unsupported free motion)";
      return false;
    }
    x_r = data.increment;
    data.residual = -load;
    const bool finite = SolveFactorizedSystem(model, data);
    x_f = data.increment;
    data.residual = r_s;
    if (!finite || !x_r.allFinite()) {
      cause = "the tangent matrix is singular (a mechanism, or unsupported free motion)";
      return false;
    }
    return true;
  }

  // x_f = dx/ds at the current state (an equilibrium at opt.load_factor); false if singular.
  bool PathTangent(std::string& cause) { return AssembleAt(true, cause) && BorderedSolves(cause); }

  void Apply(const Eigen::VectorXd& dx) {
    Retract(model, data, dx.head(model.nv));
    data.lambda += k_scale * dx.tail(model.nc);
  }

  // Newton iterations at the load factor opt.load_factor from the current state: records the
  // residual norms and the iterations in `step`, the cause of a failure in `cause`.
  LoadStepEnd IterateLoadStep(StaticStep& step, std::string& cause) {
    double last_increment = INFINITY;
    step_dx.setZero();
    // Length-driven tendons: the active set of the slack rule (docs/numerics.md), updated at
    // each converged iterate and Newton continued with the new rows (as TryStep does).
    int switches_left = 2 * static_cast<int>(model.tendons.size());
    for (int it = 0; it <= options.max_iterations; ++it) {
      if (stop.Requested()) return LoadStepEnd::kStopped;
      if (!AssembleAt(true, cause)) return LoadStepEnd::kFailed;
      double res = 0.0, con = 0.0;
      bool converged = Converged(last_increment, step, &res, &con);
      if (converged && switches_left > 0 &&
          UpdateTendonSlack(model, data, opt.time, opt.load_factor) > 0) {
        --switches_left;
        last_increment = INFINITY;
        converged = false;
        if (!AssembleAt(true, cause)) return LoadStepEnd::kFailed;
      }
      if (converged) {
        step.iterations = it;
        return LoadStepEnd::kConverged;
      }
      if (it == options.max_iterations) {
        cause = NotConverged(res, con, last_increment);
        return LoadStepEnd::kFailed;
      }
      if (!SolveAssembledSystem(model, data)) {
        cause = "the tangent matrix is singular (a mechanism, or unsupported free motion)";
        return LoadStepEnd::kFailed;
      }
      Apply(data.increment);
      step_dx += data.increment.head(model.nv);
      last_increment = ScaledIncrementSize(model, data.increment.head(model.nv));
    }
    return LoadStepEnd::kFailed;
  }

  // After IterateLoadStep converged (data.residual and data.matrix assembled at the converged
  // state): x_f = dx/ds there. False if an assembly failed or the matrix is singular;
  // data.residual is kept.
  bool PathTangentAfterStep() {
    r_s = data.residual;
    const double s = opt.load_factor;
    opt.load_factor = s + 1.0;
    std::string ignored;
    bool ok = AssembleAt(false, ignored);
    opt.load_factor = s;
    if (ok) {
      load = r_s - data.residual;
      data.residual = -load;
      ok = SolveAssembledSystem(model, data);
      x_f = data.increment;
    }
    data.residual = r_s;
    return ok && x_f.allFinite();
  }
};

// The converged state a failed step returns to.
struct Checkpoint {
  State state;
  Eigen::VectorXd lambda;
  void Save(const Data& d) {
    SaveState(d, &state);
    lambda = d.lambda;
  }
  void Restore(const Model& m, Data& d) const {
    RestoreState(state, d);
    d.lambda = lambda;
    UpdateBranchReferences(m, d);
  }
};

int MaxSteps(const StaticOptions& o) {
  return o.max_steps > 0 ? o.max_steps : 2 * o.load_steps + 1000;
}

// The message of a solve that reached max_steps, naming the settings that make steps longer:
// the arc-length controller's cap (its value given), or the load steps.
std::string StepCapMessage(int steps, double s, double arc_length_max = 0.0) {
  const std::string longer =
      arc_length_max > 0.0
          ? FormatNumbers("take longer steps (analysis.statics.arc_length_max, now %.3g)",
                          arc_length_max)
          : "take longer steps (fewer analysis.load_steps)";
  return FormatNumbers(
             "static solve stopped after %g steps (max_steps) at load factor %.9g, before "
             "reaching the end load factor; raise analysis.statics.max_steps or ",
             steps, s) +
         longer;
}

// Load stepping (docs/architecture.md, "One time step") with a bounded increment and step count.
class LoadStepPath {
 public:
  LoadStepPath(StaticSolver& s, const StaticStepCallback& on_step)
      : S_(s),
        on_step_(on_step),
        s0_(s.options.start_load_factor),
        span_(s.options.end_load_factor - s0_),
        dp0_(span_ == 0.0 ? 1.0 : 1.0 / std::max(s.options.load_steps, 1)),
        dp_min_(dp0_ * std::ldexp(1.0, -s.options.max_halvings)),
        dp_(dp0_) {}

  StaticResult Run() {
    saved_.Save(S_.data);
    result_.load_factor = s0_;
    const int max_steps = MaxSteps(S_.options);
    MeasureStartSpeed();
    while (p_ < 1.0) {
      if (result_.load_steps >= max_steps) {
        result_.message = StepCapMessage(result_.load_steps, result_.load_factor);
        return result_;
      }
      // Snap to 1 when only round-off separates p + dp from it (ten steps of 0.1 sum to
      // 1 - 1e-16, which would otherwise cost an extra load step).
      const double target = p_ + dp_ >= 1.0 - 1e-12 ? 1.0 : p_ + dp_;
      const double s_target = target == 1.0 ? S_.options.end_load_factor : s0_ + target * span_;
      S_.opt.load_factor = s_target;
      StaticStep step;
      step.load_factor = s_target;
      const LoadStepEnd end = S_.IterateLoadStep(step, last_cause_);
      if (end == LoadStepEnd::kStopped) return Interrupted();
      result_.total_iterations += step.iterations;
      // A load step that carried a contact shape through another is retried smaller
      // (elements/crossing.h); one that still does at the smallest increment ends the solve.
      if (end == LoadStepEnd::kConverged && FindCrossing(S_.model, S_.data, &crossing_)) {
        last_cause_ = "the load step carried " + DescribeCrossing(S_.model, crossing_) +
                      " through each other (contact tunnelling)";
        if (RetryShorter()) continue;
        result_.message =
            FormatNumbers("static solve stopped at load factor %.9g: the load step to %.9g ",
                          result_.load_factor, s_target) +
            "carried " + DescribeCrossing(S_.model, crossing_) +
            " through each other even at the smallest increment (analysis.max_halvings); a "
            "stiffer or thicker contact (contact.stiffness, contact_radius), more load steps "
            "or a dynamic settle resolves it";
        return result_;
      }
      if (end == LoadStepEnd::kConverged) {
        std::string why;
        const JumpCheck check = CheckForJump(target, &why);
        if (check == JumpCheck::kLimitPoint) return LimitPointResult(why);
        if (check == JumpCheck::kAccept) {
          Accept(std::move(step), target, s_target);
          continue;
        }
      }
      if (RetryShorter()) continue;
      return FailureResult(s_target);
    }
    result_.converged = true;
    return result_;
  }

 private:
  // What CheckForJump makes of a converged step.
  enum class JumpCheck { kAccept, kRetry, kLimitPoint };

  // path_speed0_ (and path_speed_) from dx/ds at the start load factor; leaves data unchanged.
  void MeasureStartSpeed() {
    if (span_ != 0.0) {
      S_.opt.load_factor = s0_;
      std::string ignored;
      if (S_.PathTangent(ignored))
        path_speed0_ = ScaledIncrementSize(S_.model, S_.x_f.head(S_.model.nv));
      saved_.Restore(S_.model, S_.data);
    }
    path_speed_ = path_speed0_;
  }

  // A jump: the step's correction is more than ten times what dx/ds at the last converged
  // state predicts (on one branch it is at most twice that, up to a limit point where x
  // varies like sqrt(s* - s)): Newton left the path across a limit point and converged on
  // another branch (a snap-through). Halve; at the smallest increment, stop at a limit
  // point, and otherwise accept.
  JumpCheck CheckForJump(double target, std::string* why) {
    const Model& model = S_.model;
    Data& data = S_.data;
    const double predicted = path_speed_ * std::abs((target - p_) * span_);
    const bool jumped =
        std::isfinite(path_speed_) && ScaledIncrementSize(model, S_.step_dx) >
                                          10.0 * predicted + 100.0 * S_.options.increment_tolerance;
    if (!jumped) return JumpCheck::kAccept;
    if (dp_ > dp_min_ * (1.0 + 1e-12)) {
      last_cause_ = "the step jumped to another branch of the path";
      return JumpCheck::kRetry;
    }
    Checkpoint next;
    next.Save(data);
    saved_.Restore(model, data);
    if (AtLimitPoint(why)) return JumpCheck::kLimitPoint;
    next.Restore(model, data);
    return JumpCheck::kAccept;
  }

  // The converged step to progress `target` (load factor s_target) becomes the last converged
  // state; the increment grows again, up to dp0.
  void Accept(StaticStep&& step, double target, double s_target) {
    const Model& model = S_.model;
    path_speed_ =
        S_.PathTangentAfterStep() ? ScaledIncrementSize(model, S_.x_f.head(model.nv)) : NAN;
    UpdateBranchReferences(model, S_.data);
    AcceptContactHistory(model, S_.data, false);
    saved_.Save(S_.data);
    p_ = target;
    result_.load_factor = s_target;
    ++result_.load_steps;
    if (on_step_) on_step_(step);
    result_.steps.push_back(std::move(step));
    dp_ = std::min(dp0_, 1.5 * dp_);
  }

  // Failed load step: back to the last converged state, retry with half the increment,
  // down to the smallest increment dp0 / 2^max_halvings. False below it.
  bool RetryShorter() {
    saved_.Restore(S_.model, S_.data);
    ++result_.halvings;
    dp_ *= 0.5;
    return dp_ >= dp_min_ * (1.0 - 1e-12);
  }

  // At the last converged state (data): a limit point of the path when dx/ds has grown
  // tenfold since the start (it grows like (s* - s)^-1/2 towards a limit point) or the tangent
  // is singular there. Leaves data unchanged.
  bool AtLimitPoint(std::string* why) {
    if (result_.load_steps == 0 || span_ == 0.0 || !std::isfinite(path_speed0_)) return false;
    const Model& model = S_.model;
    Checkpoint here;
    here.Save(S_.data);
    double speed = INFINITY;
    S_.opt.load_factor = result_.load_factor;
    if (S_.PathTangent(*why)) speed = ScaledIncrementSize(model, S_.x_f.head(model.nv));
    here.Restore(model, S_.data);
    if (speed < 10.0 * path_speed0_) return false;
    if (std::isfinite(speed))
      *why = FormatNumbers("|dx/ds| grew %.3g-fold since the start", speed / path_speed0_);
    return true;
  }

  StaticResult LimitPointResult(const std::string& why) {
    result_.limit_point = true;
    result_.message =
        FormatNumbers(
            "limit point at load factor %.9g: load stepping finds no equilibrium on "
            "this path at a load factor %.3g further (",
            result_.load_factor, dp_min_ * std::abs(span_)) +
        why +
        "); arc-length continuation (analysis.statics.method: arclength) follows the path "
        "through limit points";
    return result_;
  }

  StaticResult Interrupted() {
    saved_.Restore(S_.model, S_.data);
    result_.interrupted = true;
    result_.message =
        FormatNumbers("static solve interrupted at load factor %.9g", result_.load_factor);
    return result_;
  }

  // No equilibrium at s_target even with the smallest increment.
  StaticResult FailureResult(double s_target) {
    std::string why;
    if (AtLimitPoint(&why)) return LimitPointResult(why);
    result_.message =
        FormatNumbers("static solve failed at load factor %.9g (last converged %.9g): ", s_target,
                      result_.load_factor) +
        last_cause_;
    return result_;
  }

  StaticSolver& S_;
  const StaticStepCallback& on_step_;
  StaticResult result_;
  Checkpoint saved_;  // the last converged state
  // Progress p in [0, 1] along the load path, s = s0 + p span.
  const double s0_, span_;
  const double dp0_, dp_min_;
  double p_ = 0.0, dp_;
  // |dx/ds| at the start, for the limit-point diagnosis (NaN: unknown, e.g. singular).
  double path_speed0_ = NAN;
  double path_speed_ = NAN;  // |dx/ds| at the last converged state
  std::string last_cause_;
  Crossing crossing_;  // the last crossing found (elements/crossing.h)
};

}  // namespace

namespace {

// Arc-length continuation (docs/numerics.md, "Path-following statics"): Crisfield's cylindrical (psi = 0) or
// spherical constraint on the summed Newton corrections, the multipliers carried by the two
// bordered solves, the predictor's sign from the previous step, the root of the smaller
// angle, a step-length controller, and the end load factor reached by a load-controlled
// Newton from the interpolated state.
class ArcLengthPath {
 public:
  ArcLengthPath(StaticSolver& s, const StaticStepCallback& on_step)
      : S_(s),
        on_step_(on_step),
        dx_(s.model.nv),
        prev_dx_(s.model.nv),
        delta_(s.model.num_unknowns()),
        lambda_new_(s.model.nc) {}

  StaticResult Run() {
    const Model& model = S_.model;
    Data& data = S_.data;
    const StaticOptions& o = S_.options;
    saved_.Save(data);
    s_ = o.start_load_factor;
    result_.load_factor = s_;
    const double span = o.end_load_factor - s_;
    direction_ = span < 0.0 ? -1.0 : 1.0;
    if (span == 0.0) return Finish();
    if (!Start(span)) return result_;
    double dl = std::clamp(dl0_, dl_min_, dl_max_);
    const int max_steps = MaxSteps(o);
    std::string last_cause;
    while (true) {
      if (result_.load_steps >= max_steps) {
        result_.message = StepCapMessage(result_.load_steps, s_, dl_max_);
        return result_;
      }
      StaticStep step;
      double ds = 0.0;
      const LoadStepEnd end = Step(dl, step, &ds, last_cause);
      if (end == LoadStepEnd::kStopped) return Interrupted();
      result_.total_iterations += step.iterations;
      bool accepted = end == LoadStepEnd::kConverged;
      // A step that turned back along the path (the root choice jumped to the reverse
      // branch) is retried shorter.
      if (accepted && have_prev_ && S_.Dot(dx_, prev_dx_) + c2_ * ds * prev_ds_ < 0.0) {
        accepted = false;
        last_cause = "the step turned back along the path";
      }
      Crossing crossing;
      if (accepted && FindCrossing(model, data, &crossing)) {
        accepted = false;
        last_cause = "the step carried " + DescribeCrossing(model, crossing) +
                     " through each other (contact tunnelling)";
      }
      if (accepted && (s_ + ds - o.end_load_factor) * direction_ >= 0.0) {
        const LoadStepEnd landed = LandOnEnd(ds, last_cause);
        if (landed == LoadStepEnd::kConverged) return Finish();
        if (landed == LoadStepEnd::kStopped) return Interrupted();
        // Retry with a shorter arc: the crossing moves closer to the converged state.
        accepted = false;
      }
      if (accepted) {
        UpdateBranchReferences(model, data);
        const int iterations = std::max(step.iterations, 1);
        Accept(std::move(step), ds);
        const int desired = std::min(o.desired_iterations, o.max_iterations);
        dl *= std::clamp(std::sqrt(static_cast<double>(desired) / iterations), 0.5, 2.0);
        dl = std::clamp(dl, dl_min_, dl_max_);
        continue;
      }
      saved_.Restore(model, data);
      ++result_.halvings;
      dl *= 0.5;
      if (dl < dl_min_ * (1.0 - 1e-12)) {
        result_.message = FormatNumbers(
                              "arc-length continuation failed at load factor %.9g: the arc "
                              "length fell below its minimum %.3g: ",
                              s_, dl_min_) +
                          last_cause;
        return result_;
      }
    }
  }

 private:
  // The first arc length, its limits and the spherical constraint's scale c2 from dx/ds at the
  // start; false (with the message) when the path has no tangent or the metric sees no motion.
  bool Start(double span) {
    const Model& model = S_.model;
    const StaticOptions& o = S_.options;
    std::string cause;
    S_.opt.load_factor = s_;
    if (!S_.PathTangent(cause)) {
      saved_.Restore(model, S_.data);
      result_.message = "arc-length continuation cannot start at load factor " +
                        FormatNumbers("%.9g: ", s_) + cause;
      return false;
    }
    saved_.Restore(model, S_.data);
    const double speed = std::sqrt(S_.Dot(S_.x_f, S_.x_f));
    if (!(speed > 0.0) || !std::isfinite(speed)) {
      result_.message =
          "arc-length continuation: the load moves nothing the arc-length metric measures "
          "(|dx/ds| = 0 in translations); set analysis.statics.rotation_weight, or use load "
          "stepping";
      return false;
    }
    c2_ = o.psi * o.psi * speed * speed;
    dl0_ = o.arc_length > 0.0 ? o.arc_length : speed * std::abs(span) / o.load_steps;
    dl_min_ = o.arc_length_min > 0.0 ? o.arc_length_min : dl0_ * std::ldexp(1.0, -o.max_halvings);
    dl_max_ = o.arc_length_max > 0.0 ? o.arc_length_max
                                     : std::max(10.0 * dl0_, ResolutionArcLength(model));
    return true;
  }

  // The default cap's floor: the arc of every moving node displaced by
  // kArcLengthMaxResolution length scales (the metric sums squares over the nodes, so a
  // motion of the whole model by d length scales has length d sqrt(nodes)). 10 x the first
  // arc alone was no cap for a path that starts slow: a column before buckling shortens by
  // P / EA, and its arcs stayed 1e-4 of the buckled path's (859 steps to 2 P_cr).
  static double ResolutionArcLength(const Model& model) {
    int moving = 0;
    for (const Node& n : model.nodes) moving += n.dof >= 0 ? 1 : 0;
    return kArcLengthMaxResolution * std::sqrt(static_cast<double>(std::max(moving, 1)));
  }

  // The step of ds crossed the end load factor: Newton at exactly that load factor from the
  // state interpolated between the two converged ones. Converged: accepted as the last step.
  // Otherwise the converged state is restored.
  LoadStepEnd LandOnEnd(double ds, std::string& cause) {
    const Model& model = S_.model;
    Data& data = S_.data;
    const StaticOptions& o = S_.options;
    lambda_new_ = data.lambda;
    saved_.Restore(model, data);
    const double t = (o.end_load_factor - s_) / ds;
    delta_.head(model.nv) = t * dx_;
    Retract(model, data, delta_.head(model.nv));
    data.lambda = (1.0 - t) * data.lambda + t * lambda_new_;
    StaticStep last;
    last.load_factor = o.end_load_factor;
    S_.opt.load_factor = o.end_load_factor;
    const LoadStepEnd end = S_.IterateLoadStep(last, cause);
    result_.total_iterations += last.iterations;
    if (end == LoadStepEnd::kConverged) {
      UpdateBranchReferences(model, data);
      dx_ *= t;
      Accept(std::move(last), o.end_load_factor - s_);
      return end;
    }
    saved_.Restore(model, data);
    return end;
  }

  // A stop request: the last converged state, the result marked interrupted.
  StaticResult Interrupted() {
    saved_.Restore(S_.model, S_.data);
    result_.interrupted = true;
    result_.message = FormatNumbers("static solve interrupted at load factor %.9g", s_);
    return result_;
  }

  // One arc-length step of length dl from the converged state: predictor and corrector
  // (docs/numerics.md, "Path-following statics"). On convergence dx_ and *ds hold the step's increments.
  LoadStepEnd Step(double dl, StaticStep& step, double* ds, std::string& cause) {
    const Model& model = S_.model;
    const StaticOptions& o = S_.options;
    dx_.setZero();
    *ds = 0.0;
    double last_increment = INFINITY;
    for (int it = 0; it <= o.max_iterations; ++it) {
      if (S_.stop.Requested()) return LoadStepEnd::kStopped;
      S_.opt.load_factor = s_ + *ds;
      if (!S_.AssembleAt(true, cause)) return LoadStepEnd::kFailed;
      double res = 0.0, con = 0.0;
      const bool converged = S_.Converged(last_increment, step, &res, &con);
      if (it > 0 && converged) {
        step.iterations = it;
        return LoadStepEnd::kConverged;
      }
      if (it == o.max_iterations) {
        cause = S_.NotConverged(res, con, last_increment);
        return LoadStepEnd::kFailed;
      }
      if (!S_.BorderedSolves(cause)) return LoadStepEnd::kFailed;
      const Eigen::VectorXd& xr = S_.x_r;
      const Eigen::VectorXd& xf = S_.x_f;
      // |dx + xr + d xf|^2 + c2 (ds + d)^2 = dl^2, a quadratic a1 d^2 + a2 d + a3 = 0.
      const double a1 = S_.Dot(xf, xf) + c2_;
      const double ux = S_.Dot(dx_, dx_) + 2.0 * S_.Dot(dx_, xr) + S_.Dot(xr, xr);
      const double a2 = 2.0 * (S_.Dot(dx_, xf) + S_.Dot(xr, xf)) + 2.0 * c2_ * *ds;
      const double a3 = ux + c2_ * *ds * *ds - dl * dl;
      const double disc = a2 * a2 - 4.0 * a1 * a3;
      if (!(a1 > 0.0) || !(disc >= 0.0)) {
        cause = "the arc-length equation has no real root";
        return LoadStepEnd::kFailed;
      }
      // Roots without cancellation.
      const double q = -0.5 * (a2 + std::copysign(std::sqrt(disc), a2));
      const double r1 = q / a1, r2 = q != 0.0 ? a3 / q : -r1;
      double d;
      if (it == 0) {
        // Predictor: the sign rule (Feng, Peric and Owen): along the previous step, or
        // towards the end load factor at the first step.
        const double sigma =
            have_prev_ ? (S_.Dot(prev_dx_, xf) + c2_ * prev_ds_ >= 0.0 ? 1.0 : -1.0) : direction_;
        d = (r1 * sigma >= r2 * sigma) ? r1 : r2;
      } else {
        // Corrector: the root whose increment makes the smaller angle with the current one.
        const auto angle = [&](double x) {
          return S_.Dot(dx_, dx_) + S_.Dot(dx_, xr) + x * S_.Dot(dx_, xf) + c2_ * *ds * (*ds + x);
        };
        d = angle(r1) >= angle(r2) ? r1 : r2;
      }
      delta_ = xr + d * xf;
      dx_ += delta_.head(model.nv);
      *ds += d;
      S_.Apply(delta_);
      last_increment = ScaledIncrementSize(model, delta_.head(model.nv));
    }
    return LoadStepEnd::kFailed;
  }

  void Accept(StaticStep step, double ds) {
    const double s_new = s_ + ds;
    const double dl = std::sqrt(S_.Dot(dx_, dx_) + c2_ * ds * ds);
    // A sign change of the load factor's increment: a limit point between the last steps,
    // located at the vertex of the parabola s(l) through the three converged points around it.
    if (have_prev_ && ds * prev_ds_ < 0.0) {
      const double l0 = -prev_dl_, l2 = dl;  // arc lengths relative to the middle point
      const double s0 = s_ - prev_ds_, s1 = s_, s2 = s_new;
      // s(l) = s1 + b l + c l^2 through (l0, s0), (0, s1), (l2, s2).
      const double c = ((s2 - s1) / l2 - (s0 - s1) / l0) / (l2 - l0);
      const double b = (s2 - s1) / l2 - c * l2;
      result_.limit_points.push_back(c != 0.0 ? s1 - b * b / (4.0 * c) : s1);
    }
    AcceptContactHistory(S_.model, S_.data, false);
    saved_.Save(S_.data);
    s_ = s_new;
    result_.load_factor = s_;
    ++result_.load_steps;
    step.load_factor = s_;
    if (on_step_) on_step_(step);
    result_.steps.push_back(std::move(step));
    prev_dx_ = dx_;
    prev_ds_ = ds;
    prev_dl_ = dl;
    have_prev_ = true;
  }

  StaticResult Finish() {
    result_.converged = true;
    result_.load_factor = S_.options.end_load_factor;
    return std::move(result_);
  }

  StaticSolver& S_;
  const StaticStepCallback& on_step_;
  StaticResult result_;
  Checkpoint saved_;
  double s_ = 0.0, direction_ = 1.0, c2_ = 0.0;
  double dl0_ = 0.0, dl_min_ = 0.0, dl_max_ = 0.0;  // the first arc length and its limits
  Eigen::VectorXd dx_, prev_dx_, delta_, lambda_new_;
  double prev_ds_ = 0.0, prev_dl_ = 0.0;
  bool have_prev_ = false;
};

}  // namespace

StaticResult SolveStatic(const Model& model, Data& data, const StaticOptions& options,
                         const StopRequest& stop, const StaticStepCallback& on_step) {
  AcceptContactHistory(model, data, false);  // the stick law's anchors at the start
  StaticSolver solver(model, data, options, stop);
  if (options.method == StaticMethod::kArcLength) return ArcLengthPath(solver, on_step).Run();
  return LoadStepPath(solver, on_step).Run();
}

}  // namespace screwfem
