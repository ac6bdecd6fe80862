#include "screwfem/solve/dynamics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include <Eigen/LU>

#include "screwfem/elements/contact.h"
#include "screwfem/elements/crossing.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/registry.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/model/errors.h"
#include "step_stages.h"

namespace screwfem {

GeneralizedAlpha GeneralizedAlpha::FromSpectralRadius(double rho) {
  GeneralizedAlpha p;
  p.alpha_m = (2.0 * rho - 1.0) / (rho + 1.0);
  p.alpha_f = rho / (rho + 1.0);
  p.gamma = 0.5 + p.alpha_f - p.alpha_m;
  p.beta = 0.25 * (p.gamma + 0.5) * (p.gamma + 0.5);
  return p;
}

namespace {

// phi(q exp(e v)) evaluated into out (constraint rows of the residual, unscaled).
void ConstraintsAlong(const Model& model, Data& data, const State& base, double e,
                      Eigen::VectorXd& out, Eigen::VectorXd& work) {
  RestoreState(base, data);
  work = e * data.v;
  Retract(model, data, work);
  AssemblyOptions o;
  o.time = data.time;
  o.assemble_matrix = false;
  Assemble(model, data, o);
  out = data.residual.tail(model.nc);
}

}  // namespace

double ResolvedRhoInf(const Model& model, const DynamicOptions& options) {
  if (options.rho_inf >= 0.0) return options.rho_inf;
  return HasContact(model) ? kContactRhoInf : kDefaultRhoInf;
}

void ValidateDynamicOptions(const DynamicOptions& o, const std::string& owner) {
  const auto require = [&](bool ok, const char* field, const char* what) {
    if (!ok) throw InputError(owner + "." + field + ": " + what);
  };
  require(o.rho_inf <= 1.0 && !std::isnan(o.rho_inf), "rho_inf",
          "must lie in [0, 1] (negative: auto)");
  require(o.max_iterations >= 1 && o.max_iterations <= kMaxNewtonIterations, "max_iterations",
          "must lie in [1, 1000]");
  require(o.max_halvings >= 0 && o.max_halvings <= kMaxHalvings, "max_halvings",
          "must lie in [0, 30]");
  for (const auto& [value, field] : {std::pair{o.increment_tolerance, "increment_tolerance"},
                                     std::pair{o.constraint_tolerance, "constraint_tolerance"},
                                     std::pair{o.residual_tolerance, "residual_tolerance"}})
    require(std::isfinite(value) && value > 0.0, field, "must be finite and > 0");
  require(o.refresh_ratio > 0.0 && o.refresh_ratio < 1.0, "refresh_ratio", "must lie in (0, 1)");
  require(std::isfinite(o.absolute_tolerance) && o.absolute_tolerance > 0.0, "tolerance.absolute",
          "must be finite and > 0");
  require(std::isfinite(o.relative_tolerance) && o.relative_tolerance >= 0.0, "tolerance.relative",
          "must be finite and >= 0");
  require(std::isfinite(o.min_step) && o.min_step > 0.0, "min_step", "must be a finite time > 0 s");
  require(!std::isnan(o.max_step) && o.max_step >= o.min_step, "max_step",
          "must be a time >= min_step");
  require(std::isfinite(o.initial_step) && o.initial_step >= 0.0, "initial_step",
          "must be a finite time >= 0 s (0: chosen by the integrator)");
  const auto require_enum = [&](auto value, const char* field) {
    using E = decltype(value);
    if (!IsEnumValue(value))
      throw InputError(owner + "." + field + ": must be " + EnumNameAlternatives<E>());
  };
  require_enum(o.newton_matrix, "newton_matrix");
  require_enum(o.predictor, "predictor");
  require_enum(o.convergence, "convergence");
  require_enum(o.constraints, "constraints");
}

namespace {

// Consistent accelerations and multipliers at data's state and time (docs/numerics.md, "Restarts at breakpoints"), and the
// auxiliary acceleration a = vdot. Uses the integrator's workspace (no allocation unless it
// fails); integ.q_start is overwritten with the current state.
bool ConsistentStart(const Model& model, Data& data, Integrator& integ, std::string* message) {
  const int nv = model.nv, nc = model.nc;
  SaveState(data, &integ.q_start);
  // Bdot v = d^2/de^2 phi(q exp(e v)) (exact for constant body velocities), by the central
  // fourth-order second difference (-f(2e) + 16 f(e) - 30 f(0) + 16 f(-e) - f(-2e)) / 12 e^2
  // with e |v| = 1e-3: truncation (e |v|)^4 and round-off eps / (e |v|)^2, about 1e-10
  // relative. (The three-point difference with e |v| = 1e-4 left 1e-8, a noise in the
  // restarts' accelerations that differences of whole runs amplify: docs/inverse.md,
  // "Multipliers".)
  integ.bdot_v.setZero();
  const double vmax = ScaledIncrementSize(model, data.v);
  if (nc > 0 && vmax > 0.0) {
    const double e = 1e-3 / vmax;
    constexpr double kPoints[4][2] = {{1.0, 16.0}, {-1.0, 16.0}, {2.0, -1.0}, {-2.0, -1.0}};
    ConstraintsAlong(model, data, integ.q_start, 0.0, integ.phi_zero, integ.v_work);
    integ.bdot_v = -30.0 * integ.phi_zero;
    for (const auto& [at, weight] : kPoints) {
      ConstraintsAlong(model, data, integ.q_start, at * e, integ.phi_plus, integ.v_work);
      integ.bdot_v += weight * integ.phi_plus;
    }
    integ.bdot_v /= 12.0 * e * e;
    RestoreState(integ.q_start, data);
  }

  // [M B^T; B 0] [vdot; lambda] = -[r(q, v, 0, t); Bdot v + phi_tt].
  data.vdot.setZero();
  data.lambda.setZero();
  if (!Assemble(model, data, generalized_alpha::MassMatrixOptions(data.time))) {
    if (message) *message = "the state is invalid (an element is bent past its limit)";
    return false;
  }
  data.residual.tail(nc) = integ.bdot_v;
  SubtractConstraintAccelerations(model, data, data.time, data.residual.tail(nc));
  if (!SolveAssembledSystem(model, data)) {
    if (message)
      *message =
          "cannot compute consistent accelerations: the system [M B^T; B 0] is singular "
          "(a part without mass that is not fixed by constraints, or redundant constraints)";
    return false;
  }
  data.vdot = data.increment.head(nv);
  data.lambda = data.increment.tail(nc);
  integ.a = data.vdot;
  integ.use_last_acceleration = integ.options.predictor != Predictor::kZero;
  integ.perturb_pending =
      integ.options.perturbed_start && integ.params.alpha_m != integ.params.alpha_f;
  return true;
}

// DynamicOptions::perturbed_start (docs/numerics.md, "Restarts at breakpoints" step 4): before the first step after
// a start or restart, of size h, a = vdot + (alpha_m - alpha_f) (vdot_s - vdot) with vdot_s
// the consistent acceleration at q exp(h v + h^2 vdot / 2), v + h vdot, t + h. One-sided
// (the left side of a breakpoint lies across the jump). The state is restored afterwards.
bool ApplyPerturbedStart(const Model& model, Data& data, Integrator& integ, double h,
                         std::string* why) {
  if (!integ.perturb_pending) return true;
  integ.perturb_pending = false;
  const double t = data.time;
  SaveState(data, &integ.perturb_q);
  integ.perturb_v = data.v;
  integ.perturb_vdot = data.vdot;
  integ.perturb_lambda = data.lambda;
  data.increment.head(model.nv) = h * data.v + (0.5 * h * h) * data.vdot;
  Retract(model, data, data.increment.head(model.nv));
  data.v += h * data.vdot;
  data.time = t + h;
  const bool ok = ConsistentStart(model, data, integ, why);
  // integ.a holds vdot_s now. The finite difference vdot_s - vdot estimates h times the
  // derivative of the acceleration only where the step resolves it; a larger change than
  // kPerturbedStartMaxChange |vdot| comes from modes it does not resolve, and the step then
  // starts from a = vdot.
  bool perturb = ok;
  if (ok) {
    integ.v_work = integ.a - integ.perturb_vdot;
    const double change = ScaledIncrementSize(model, integ.v_work);
    perturb = change <= kPerturbedStartMaxChange * ScaledIncrementSize(model, integ.perturb_vdot);
    if (!perturb) ++integ.perturbed_start_skips;
  }
  if (perturb)
    integ.a = integ.perturb_vdot +
              (integ.params.alpha_m - integ.params.alpha_f) * (integ.a - integ.perturb_vdot);
  else
    integ.a = integ.perturb_vdot;
  integ.perturb_pending = false;
  RestoreState(integ.perturb_q, data);
  data.v = integ.perturb_v;
  data.vdot = integ.perturb_vdot;
  data.lambda = integ.perturb_lambda;
  data.time = t;
  return ok;
}

// ConstraintFormulation::kGgl: the workspace of the stabilised index-2 iteration, and where the
// constraint gradient B has entries (Integrator::ggl_pattern, ggl_pairs).
void AllocateGglWorkspace(const Model& model, Integrator& integ) {
  const int nv = model.nv, nc = model.nc;
  const int num_nodes = static_cast<int>(model.nodes.size());
  integ.ggl_b = Eigen::MatrixXd::Zero(nc, nv);
  // Column groups: a node's 6 dofs, a joint's k coordinates (with their tangent operators).
  std::vector<Integrator::GglBlock> groups;
  std::vector<int> group_of(static_cast<std::size_t>(nv), -1);
  const auto add_group = [&](int col, int cols, int tangent) {
    for (int c = col; c < col + cols; ++c)
      group_of[static_cast<std::size_t>(c)] = static_cast<int>(groups.size());
    groups.push_back({0, 0, col, cols, tangent});
  };
  const bool tangent = integ.options.use_tangent_operator;
  for (int i = 0; i < num_nodes; ++i)
    if (model.nodes[static_cast<std::size_t>(i)].dof >= 0)
      add_group(model.nodes[static_cast<std::size_t>(i)].dof, 6, tangent ? i : -1);
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.k() > 0)
      add_group(
          j.coord, j.k(),
          tangent && !JointHasGlobalCoordinates(j.type) ? num_nodes + static_cast<int>(jj) : -1);
  }
  // The blocks: each item's rows (in chunks of at most 6) over each group its columns touch.
  integ.ggl_pattern.clear();
  ForEachKind<ConstraintKinds>([&]<class Kind>() {
    Kind::ForEach(model, [&](const typename Kind::Item& item) {
      const int rows = Kind::RowCount(model, item);
      if (rows <= 0) return;
      std::vector<int> touched;
      Kind::ForEachColumn(model, item, [&](int first, int size) {
        for (int c = first; c < first + size; ++c) {
          const int g = group_of[static_cast<std::size_t>(c)];
          if (g >= 0 && std::find(touched.begin(), touched.end(), g) == touched.end())
            touched.push_back(g);
        }
      });
      const int first_row = Kind::FirstRow(model, item);
      for (int r = 0; r < rows; r += 6)
        for (int g : touched) {
          const Integrator::GglBlock& col = groups[static_cast<std::size_t>(g)];
          integ.ggl_pattern.push_back(
              {first_row + r, std::min(6, rows - r), col.col, col.cols, col.tangent});
        }
    });
  });
  integ.ggl_pairs.clear();
  for (std::size_t a = 0; a < integ.ggl_pattern.size(); ++a)
    for (std::size_t b = 0; b < integ.ggl_pattern.size(); ++b)
      if (integ.ggl_pattern[a].col == integ.ggl_pattern[b].col)
        integ.ggl_pairs.emplace_back(static_cast<int>(a), static_cast<int>(b));
  integ.ggl_bv = integ.ggl_phi = integ.ggl_nu = integ.ggl_dnu = integ.ggl_nu_last =
      integ.ggl_nu_before = Eigen::VectorXd::Zero(nc);
  integ.ggl_y = Eigen::VectorXd::Zero(nv);
  integ.ggl_bt = Eigen::MatrixXd::Zero(nc, nv);
  integ.ggl_cross = Eigen::MatrixXd::Identity(nc, nc);
  integ.ggl_cross_lu = Eigen::PartialPivLU<Eigen::MatrixXd>(nc);
  integ.ggl_rhs = Eigen::VectorXd::Zero(nc);
  integ.ggl_slack.assign(model.tendons.size(), 0);
  integ.max_nu = 0.0;
}

// A length-driven tendon whose route is shorter than its prescribed length starts slack.
void SetInitialTendonSlack(const Model& model, Data& data) {
  for (std::size_t ti = 0; ti < model.tendons.size(); ++ti) {
    const Tendon& t = model.tendons[ti];
    if (t.row < 0) continue;
    const double target = TendonTargetLength(t, data, data.time).value;
    data.tendon_slack[ti] = CalcTendonLength(model, data, static_cast<int>(ti)) <
                            target - 1e-12 * std::max(1.0, target);
    if (data.tendon_slack[ti]) data.lambda(t.row) = 0.0;
  }
}

}  // namespace

bool InitializeDynamics(const Model& model, Data& data, Integrator& integ,
                        const DynamicOptions& options, std::string* message) {
  integ.options = options;
  if (options.constraints == ConstraintFormulation::kAuto) {
    // Rigid mechanisms: GGL with the perturbed start (exact efforts at every step); models
    // with rods: index 3 with the plain start (the perturbation is skipped at a rod model's
    // starts anyway, its axial modes unresolved, and its workspace would cost 0.2 kB per
    // element).
    integ.options.constraints =
        model.rods.empty() ? ConstraintFormulation::kGgl : ConstraintFormulation::kIndex3;
    integ.options.perturbed_start = options.perturbed_start && model.rods.empty();
  }
  integ.options.rho_inf = ResolvedRhoInf(model, options);
  integ.params = GeneralizedAlpha::FromSpectralRadius(integ.options.rho_inf);
  const int nv = model.nv, nc = model.nc;
  integ.a = Eigen::VectorXd::Zero(nv);
  integ.v_start = integ.vdot_start = integ.a_start = integ.dq = integ.a_base = integ.v_work =
      Eigen::VectorXd::Zero(nv);
  integ.lambda_start = integ.phi_plus = integ.phi_minus = integ.phi_zero = integ.bdot_v =
      Eigen::VectorXd::Zero(nc);
  if (integ.options.constraints == ConstraintFormulation::kGgl) AllocateGglWorkspace(model, integ);
  integ.line_search = integ.options.line_search &&
                      integ.options.constraints == ConstraintFormulation::kIndex3 &&
                      HasContact(model);
  integ.line_search_dx = integ.line_search ? Eigen::VectorXd::Zero(nv + nc) : Eigen::VectorXd();
  // The workspaces of error-controlled steps and of the perturbed start only for the runs
  // that use them (PrepareAdaptiveSteps; options.perturbed_start): 12 vectors of nv and two
  // copies of the configuration, 0.75 kB per rod element that fixed steps never touch.
  ReleaseAdaptiveSteps(integ);
  if (integ.options.perturbed_start && integ.params.alpha_m != integ.params.alpha_f) {
    integ.perturb_v = integ.perturb_vdot = Eigen::VectorXd::Zero(nv);
    integ.perturb_lambda = Eigen::VectorXd::Zero(nc);
    SaveState(data, &integ.perturb_q);
  } else {
    integ.perturb_v = integ.perturb_vdot = integ.perturb_lambda = Eigen::VectorXd();
    integ.perturb_q = State();
  }
  integ.perturb_pending = false;
  integ.dense_t0 = data.time;
  integ.dense_h = 0.0;
  integ.h_control = integ.err_last = integ.h_last = integ.error_norm = 0.0;
  integ.allow_growth = true;
  integ.why.reserve(256);
  // The breakpoints after the start, where steps end and the integrator restarts.
  integ.breakpoints.clear();
  if (options.restart_at_breakpoints)
    integ.breakpoints = SortedBreakpoints(ProfileBreakpoints(model), data.time,
                                          std::numeric_limits<double>::infinity(), 0.0);
  // One tangent operator per node, then one per joint (used by spherical, planar and free
  // joints, whose coordinates retract by the exponential; see TryStep).
  data.node_tangent.assign(model.nodes.size() + model.joints.size(), Mat6::Identity());
  integ.slack_start = data.tendon_slack;
  integ.tendon_switches = integ.tendon_catches = 0;
  integ.tendon_rate_error = Eigen::VectorXd::Zero(nc);
  SetInitialTendonSlack(model, data);
  AcceptContactHistory(model, data, true);  // the stick law's anchors at the start
  std::string why;
  if (!ConsistentStart(model, data, integ, &why)) {
    if (message) *message = "at the start time: " + why;
    return false;
  }
  return true;
}

namespace generalized_alpha {
bool AdaptiveStepsPrepared(const Model& model, const Data& data, const Integrator& integ) {
  return integ.dense_v0.size() == model.nv && integ.dense_lambda0.size() == model.nc &&
         integ.error.size() == model.nv && integ.dense_q0.H.size() == data.H.size() &&
         integ.dense_q0.HJ.size() == data.HJ.size();
}
}  // namespace generalized_alpha

void PrepareAdaptiveSteps(const Model& model, const Data& data, Integrator& integ) {
  const Eigen::Index nv = model.nv, nc = model.nc;
  if (generalized_alpha::AdaptiveStepsPrepared(model, data, integ)) return;
  integ.error = integ.a_accepted = integ.dense_v0 = integ.dense_vdot0 = integ.dense_v1 =
      integ.dense_vdot1 = integ.dense_d = integ.dense_psi = integ.dense_dpsi =
          Eigen::VectorXd::Zero(nv);
  integ.dense_lambda0 = integ.dense_lambda1 = Eigen::VectorXd::Zero(nc);
  SaveState(data, &integ.dense_q0);
  integ.dense_t0 = data.time;
  integ.dense_h = 0.0;
}

void ReleaseAdaptiveSteps(Integrator& integ) {
  for (Eigen::VectorXd* v : {&integ.error, &integ.a_accepted, &integ.dense_v0, &integ.dense_vdot0,
                             &integ.dense_v1, &integ.dense_vdot1, &integ.dense_d, &integ.dense_psi,
                             &integ.dense_dpsi, &integ.dense_lambda0, &integ.dense_lambda1})
    *v = Eigen::VectorXd();
  integ.dense_q0 = State();
  integ.dense_h = 0.0;
}

bool RestartDynamics(const Model& model, Data& data, Integrator& integ, std::string* message) {
  std::string why;  // empty: no allocation on success
  if (ConsistentStart(model, data, integ, &why)) {
    ++integ.restarts;
    return true;
  }
  if (message) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "restart at the profile breakpoint t = %.9g s: ", data.time);
    *message = buf + why;
  }
  return false;
}

namespace {

// The next substep of a step from t0 to t_end: hs, cut at the step's end and at the next
// breakpoint (a breakpoint within `snap` after its end is its end too).
struct Substep {
  double h, t_end;
  bool at_breakpoint;
};

Substep NextSubstep(const Integrator& integ, double t0, double hs, double t_end, double snap) {
  Substep s;
  s.h = std::min(hs, t_end - t0);
  s.t_end = t0 + s.h;
  if (s.h == t_end - t0) s.t_end = t_end;
  const double bp = NextBreakpoint(integ.breakpoints, t0, snap);
  s.at_breakpoint = EndsOnBreakpoint(s.t_end, bp, snap);
  if (s.at_breakpoint) {
    s.t_end = bp;
    s.h = bp - t0;
  }
  return s;
}

}  // namespace

StepResult Step(const Model& model, Data& data, Integrator& integ, double h,
                const StopRequest& stop) {
  using namespace generalized_alpha;
  StepResult result;
  result.substeps = 0;
  // A breakpoint within this distance of a substep's end is that end (the run loop's step ends
  // are breakpoints up to the rounding of start + h).
  const double snap = 1e-9 * h;
  const double t_end = SnapToBreakpoint(integ.breakpoints, data.time, data.time + h, snap);
  const double h_min = h * std::ldexp(1.0, -integ.options.max_halvings);
  double hs = h;
  std::string& why = integ.why;  // capacity reserved at set-up: a failed attempt allocates nothing
  why.clear();
  while (data.time < t_end - 1e-12 * h) {
    const double t0 = data.time;
    const Substep sub = NextSubstep(integ, t0, hs, t_end, snap);
    if (stop.Requested()) {
      result.interrupted = true;
      result.message = InterruptedMessage(t0);
      return result;
    }
    if (!ApplyPerturbedStart(model, data, integ, sub.h, &why)) {
      result.message = "perturbed start: " + why;
      return result;
    }
    const int its = CheckStepCrossing(
        model, data,
        TryStepWithRetry(model, data, integ, sub.h, sub.t_end, sub.at_breakpoint, &why), &why);
    if (its >= 0) {
      UpdateBranchReferences(model, data);
      result.iterations += its;
      ++result.substeps;
      CountAcceptedStep(integ, sub.h, its);
      AcceptContactHistory(model, data, true);
      hs = std::min(h, 2.0 * hs);
      bool restarted;
      if (!RestartAfterStep(model, data, integ, sub.at_breakpoint, &restarted, &result.message))
        return result;
      continue;
    }
    RestoreStepStart(data, integ, t0);
    if (sub.h * 0.5 < h_min * (1.0 - 1e-12)) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "step failed at t = %.9g s (step %.3g s, after %d halvings): ", t0, sub.h,
                    integ.options.max_halvings);
      result.message = std::string(buf) + why + ContactFailureHint(model, data, h);
      return result;
    }
    hs = 0.5 * sub.h;
    ++integ.halvings;
  }
  data.time = t_end;
  ++integ.steps;
  result.ok = true;
  return result;
}

void SaveSimulationState(const Data& data, const Integrator& integ, SimulationState* state) {
  state->time = data.time;
  SaveState(data, &state->q);
  state->w_ref = data.w_ref;
  state->v = data.v;
  state->vdot = data.vdot;
  state->lambda = data.lambda;
  state->inputs = data.inputs;
  state->tendon_slack = data.tendon_slack;
  state->contact_anchors = data.contact_anchors;
  state->a = integ.a;
  state->nu_last = integ.ggl_nu_last;
  state->nu_before = integ.ggl_nu_before;
  state->use_last_acceleration = integ.use_last_acceleration;
}

void RestoreSimulationState(const SimulationState& state, Data& data, Integrator& integ) {
  if (state.q.H.size() != data.H.size() || state.q.HJ.size() != data.HJ.size() ||
      state.q.q_joint.size() != data.q_joint.size() || state.w_ref.size() != data.w_ref.size() ||
      state.v.size() != data.v.size() || state.vdot.size() != data.vdot.size() ||
      state.lambda.size() != data.lambda.size() || state.inputs.size() != data.inputs.size())
    throw InputError("the saved state belongs to a different model (its sizes differ)");
  data.time = state.time;
  RestoreState(state.q, data);
  data.crossing_valid = false;  // the swept check resumes from the next accepted step
  data.w_ref = state.w_ref;
  data.v = state.v;
  data.vdot = state.vdot;
  data.lambda = state.lambda;
  data.inputs = state.inputs;
  if (state.tendon_slack.size() == data.tendon_slack.size()) data.tendon_slack = state.tendon_slack;
  if (state.contact_anchors.size() == data.contact_anchors.size())
    data.contact_anchors = state.contact_anchors;
  if (state.a.size() == integ.a.size()) integ.a = state.a;
  if (state.nu_last.size() == integ.ggl_nu_last.size()) {
    integ.ggl_nu_last = state.nu_last;
    integ.ggl_nu_before = state.nu_before;
  }
  integ.use_last_acceleration = state.use_last_acceleration;
}

}  // namespace screwfem
