#include "screwfem/solve/dynamics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include <Eigen/LU>

#include "screwfem/elements/joint.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/model/errors.h"

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

void ValidateDynamicOptions(const DynamicOptions& o, const std::string& owner) {
  const auto require = [&](bool ok, const char* field, const char* what) {
    if (!ok) throw InputError(owner + "." + field + ": " + what);
  };
  require(o.rho_inf >= 0.0 && o.rho_inf <= 1.0, "rho_inf", "must lie in [0, 1]");
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

std::vector<double> ProfileBreakpoints(const Model& model) {
  std::vector<double> b;
  const auto add = [&b](const Profile& profile) {
    const std::vector<double> p = profile.Breakpoints();
    b.insert(b.end(), p.begin(), p.end());
  };
  for (const PointLoad& l : model.point_loads) add(l.profile);
  for (const RodLoad& l : model.rod_loads) add(l.profile);
  for (const Joint& j : model.joints)
    if (j.drive != DriveKind::kNone) add(j.drive_profile);
  for (const Tendon& t : model.tendons) add(t.drive == TendonDrive::kLength ? t.length : t.tension);
  for (const ForceElement& f : model.force_elements) add(f.actuator);
  for (const Actuator& a : model.actuators) add(a.profile);
  return b;
}

namespace {

// Consistent accelerations and multipliers at data's state and time (method.md §5.4), and the
// auxiliary acceleration a = vdot. Uses the integrator's workspace (no allocation unless it
// fails); integ.q_start is overwritten with the current state.
bool ConsistentStart(const Model& model, Data& data, Integrator& integ, std::string* message) {
  const int nv = model.nv, nc = model.nc;
  SaveState(data, &integ.q_start);
  // Bdot v = d^2/de^2 phi(q exp(e v)) (exact for constant body velocities), by a central
  // second difference.
  integ.bdot_v.setZero();
  const double vmax = ScaledIncrementSize(model, data.v);
  if (nc > 0 && vmax > 0.0) {
    const double e = 1e-4 / vmax;
    ConstraintsAlong(model, data, integ.q_start, e, integ.phi_plus, integ.v_work);
    ConstraintsAlong(model, data, integ.q_start, -e, integ.phi_minus, integ.v_work);
    ConstraintsAlong(model, data, integ.q_start, 0.0, integ.phi_zero, integ.v_work);
    integ.bdot_v = (integ.phi_plus - 2.0 * integ.phi_zero + integ.phi_minus) / (e * e);
    RestoreState(integ.q_start, data);
  }

  // [M B^T; B 0] [vdot; lambda] = -[r(q, v, 0, t); Bdot v + phi_tt].
  data.vdot.setZero();
  data.lambda.setZero();
  AssemblyOptions o;
  o.time = data.time;
  o.dynamics = true;
  o.c_mass = 1.0;
  o.c_damping = 0.0;
  o.c_stiffness = 0.0;
  if (!Assemble(model, data, o)) {
    if (message) *message = "the state is invalid (an element is bent past its limit)";
    return false;
  }
  data.residual.tail(nc) = integ.bdot_v;
  for (const Joint& j : model.joints)
    if (j.drive == DriveKind::kPrescribed)
      data.residual(nv + j.drive_row) -= EvalProfile(j.drive_profile, data.time, data).accel;
  for (std::size_t ti = 0; ti < model.tendons.size(); ++ti) {
    const Tendon& t = model.tendons[ti];
    if (t.row >= 0 && !data.tendon_slack[ti])
      data.residual(nv + t.row) -= TendonTargetLength(t, data, data.time).accel;
  }
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
  integ.perturb_pending = integ.options.perturbed_start &&
                          integ.params.alpha_m != integ.params.alpha_f;
  return true;
}

// DynamicOptions::perturbed_start (method-next.md §N1.2 step 4): before the first step after
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

}  // namespace

bool InitializeDynamics(const Model& model, Data& data, Integrator& integ,
                        const DynamicOptions& options, std::string* message) {
  integ.options = options;
  integ.params = GeneralizedAlpha::FromSpectralRadius(options.rho_inf);
  const int nv = model.nv, nc = model.nc;
  integ.a = Eigen::VectorXd::Zero(nv);
  integ.v_start = integ.vdot_start = integ.a_start = integ.dq = integ.a_base =
      integ.v_work = Eigen::VectorXd::Zero(nv);
  integ.lambda_start = integ.phi_plus = integ.phi_minus = integ.phi_zero = integ.bdot_v =
      Eigen::VectorXd::Zero(nc);
  if (options.constraints == ConstraintFormulation::kGgl) {
    integ.ggl_b = Eigen::MatrixXd::Zero(nc, nv);
    std::vector<char> touched(static_cast<std::size_t>(nv), 0);
    const auto touch = [&](int first, int size) {
      for (int i = first; i < first + size; ++i) touched[static_cast<std::size_t>(i)] = 1;
    };
    for (const Joint& j : model.joints) {
      if (j.row < 0 && j.drive != DriveKind::kPrescribed) continue;
      for (const int node : {j.node_a, j.node_b})
        if (node != kGround && model.nodes[static_cast<std::size_t>(node)].dof >= 0)
          touch(model.nodes[static_cast<std::size_t>(node)].dof, 6);
      if (j.k() > 0) touch(j.coord, j.k());
    }
    for (const TendonSegment& seg : model.tendon_segments) {
      if (model.tendons[static_cast<std::size_t>(seg.tendon)].row < 0) continue;
      // An eyelet between rod nodes moves with both nodes of its element.
      const auto node_b = [&](const BodyPoint& p) {
        return p.element >= 0 ? model.elements[static_cast<std::size_t>(p.element)].node_b
                              : kGround;
      };
      for (const int node : {seg.a.node, seg.b.node, node_b(seg.a), node_b(seg.b)})
        if (node != kGround && model.nodes[static_cast<std::size_t>(node)].dof >= 0)
          touch(model.nodes[static_cast<std::size_t>(node)].dof, 6);
    }
    integ.ggl_blocks.clear();
    for (int i = 0; i < nv; ++i) {
      if (!touched[static_cast<std::size_t>(i)]) continue;
      if (!integ.ggl_blocks.empty() &&
          integ.ggl_blocks.back().first + integ.ggl_blocks.back().second == i)
        ++integ.ggl_blocks.back().second;
      else
        integ.ggl_blocks.emplace_back(i, 1);
    }
    integ.ggl_bv = integ.ggl_phi = integ.ggl_nu = integ.ggl_dnu = Eigen::VectorXd::Zero(nc);
    integ.ggl_y = Eigen::VectorXd::Zero(nv);
    integ.ggl_bt = Eigen::MatrixXd::Zero(nc, nv);
    integ.ggl_cross = Eigen::MatrixXd::Identity(nc, nc);
    integ.ggl_cross_lu = Eigen::PartialPivLU<Eigen::MatrixXd>(nc);
    integ.ggl_rhs = Eigen::VectorXd::Zero(nc);
    integ.ggl_slack.assign(model.tendons.size(), 0);
    integ.max_nu = 0.0;
  }
  integ.error = integ.a_accepted = integ.dense_v0 = integ.dense_vdot0 = integ.dense_v1 =
      integ.dense_vdot1 = integ.dense_d = integ.dense_psi = integ.dense_dpsi =
          Eigen::VectorXd::Zero(nv);
  integ.dense_lambda0 = integ.dense_lambda1 = Eigen::VectorXd::Zero(nc);
  integ.perturb_v = integ.perturb_vdot = Eigen::VectorXd::Zero(nv);
  integ.perturb_lambda = Eigen::VectorXd::Zero(nc);
  SaveState(data, &integ.perturb_q);
  integ.perturb_pending = false;
  SaveState(data, &integ.dense_q0);
  integ.dense_t0 = data.time;
  integ.dense_h = 0.0;
  integ.h_control = integ.err_last = integ.h_last = integ.error_norm = 0.0;
  integ.allow_growth = true;
  integ.why.reserve(256);
  integ.breakpoints.clear();
  if (options.restart_at_breakpoints) {
    std::vector<double> b = ProfileBreakpoints(model);
    std::sort(b.begin(), b.end());
    for (double t : b)
      if (t > data.time && (integ.breakpoints.empty() || t > integ.breakpoints.back()))
        integ.breakpoints.push_back(t);
  }
  // One tangent operator per node, then one per joint (used by spherical, planar and free
  // joints, whose coordinates retract by the exponential; see TryStep).
  data.node_tangent.assign(model.nodes.size() + model.joints.size(), Mat6::Identity());
  integ.slack_start = data.tendon_slack;
  integ.tendon_switches = integ.tendon_catches = 0;
  integ.tendon_rate_error = Eigen::VectorXd::Zero(nc);
  // A length-driven tendon whose route is shorter than its prescribed length starts slack.
  for (std::size_t ti = 0; ti < model.tendons.size(); ++ti) {
    const Tendon& t = model.tendons[ti];
    if (t.row < 0) continue;
    const double target = TendonTargetLength(t, data, data.time).value;
    data.tendon_slack[ti] =
        CalcTendonLength(model, data, static_cast<int>(ti)) < target - 1e-12 * std::max(1.0, target);
    if (data.tendon_slack[ti]) data.lambda(t.row) = 0.0;
  }
  std::string why;
  if (!ConsistentStart(model, data, integ, &why)) {
    if (message) *message = "at the start time: " + why;
    return false;
  }
  return true;
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

// ---- the stages of one generalized-alpha step (method.md §5.2) -------------------------------

// The step's constants: h, the iteration-matrix coefficients beta' and gamma', the residual
// scale beta h^2 and c_a, with the auxiliary acceleration a_{n+1} = a_base + c_a vdot_{n+1}.
struct StepConstants {
  double h, beta_p, gamma_p, bh2, c_a;
};

StepConstants MakeStepConstants(const GeneralizedAlpha& p, double h) {
  StepConstants c;
  c.h = h;
  c.beta_p = (1.0 - p.alpha_m) / (h * h * p.beta * (1.0 - p.alpha_f));
  c.gamma_p = p.gamma / (h * p.beta);
  c.bh2 = p.beta * h * h;
  c.c_a = (1.0 - p.alpha_f) / (1.0 - p.alpha_m);
  return c;
}

// Predict: the start of the Newton iteration at t + h. The Newton corrections keep v, dq and a
// consistent with the auxiliary acceleration (gamma' dx = h gamma c_a beta' dx,
// dx / h = h beta c_a beta' dx), so the iteration may start from any vdot_{n+1}: vdot_n or 0
// (DynamicOptions::predictor).
void Predict(Data& data, Integrator& integ, const StepConstants& c, bool from_last) {
  const GeneralizedAlpha& p = integ.params;
  const double h = c.h;
  integ.a_base = (p.alpha_f * integ.vdot_start - p.alpha_m * integ.a_start) / (1.0 - p.alpha_m);
  if (from_last)
    data.vdot = integ.vdot_start;
  else
    data.vdot.setZero();
  integ.a = integ.a_base + c.c_a * data.vdot;
  data.v = integ.v_start + h * (1.0 - p.gamma) * integ.a_start + h * p.gamma * integ.a;
  integ.dq = integ.v_start + h * (0.5 - p.beta) * integ.a_start + h * p.beta * integ.a;
  data.lambda = integ.lambda_start;
  data.time += h;
}

// ConstraintFormulation::kGgl (method-next.md §N1.3): the gradient B_n = B(q_n) of the step's
// start, which multiplies nu in the configuration update. Data holds q_n. The rows of slack
// length-driven tendons hold their gradient too (their route's dL/dq at q_n): a tendon caught
// taut during the step then corrects along it (its row of B T B_n^T is not zero).
void PrepareGglStep(const Model& model, Data& data, Integrator& integ) {
  if (integ.options.constraints != ConstraintFormulation::kGgl || model.nc == 0) return;
  std::copy(data.tendon_slack.begin(), data.tendon_slack.end(), integ.ggl_slack.begin());
  std::fill(data.tendon_slack.begin(), data.tendon_slack.end(), char{0});
  CalcConstraintGradient(model, data, integ.ggl_b);
  std::copy(integ.ggl_slack.begin(), integ.ggl_slack.end(), data.tendon_slack.begin());
  integ.ggl_nu.setZero();
}

// ConstraintFormulation::kGgl: the position-constraint rows of the iteration at the current
// iterate, B(q) T with the tangent operators the matrix was assembled with (method-next.md
// §N1.3; Delta x enters q as q_n o exp(h dq + Delta x)), and the factorised B T B_n^T that
// gives the nu correction (held rows and columns, ForEachHeldRow: the identity). False if it is singular
// (redundant constraints the build did not find).
bool FactorizeGglCross(const Model& model, const Data& data, Integrator& integ) {
  Eigen::MatrixXd& bt = integ.ggl_bt;
  CalcConstraintGradient(model, data, bt);
  if (integ.options.use_tangent_operator) {
    for (std::size_t i = 0; i < model.nodes.size(); ++i) {
      const int dof = model.nodes[i].dof;
      if (dof < 0) continue;
      const Mat6& T = data.node_tangent[i];
      for (int r = 0; r < model.nc; ++r) {
        const Vec6 row = bt.block<1, 6>(r, dof).transpose();
        bt.block<1, 6>(r, dof) = (T.transpose() * row).transpose();
      }
    }
    for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
      const Joint& j = model.joints[jj];
      const int k = j.k();
      if (k == 0 || JointHasGlobalCoordinates(j.type)) continue;
      const Mat6& T = data.node_tangent[model.nodes.size() + jj];
      for (int r = 0; r < model.nc; ++r) {
        Vec6 row = Vec6::Zero();
        row.head(k) = bt.block(r, j.coord, 1, k).transpose();
        const Vec6 out = T.transpose() * row;  // T_J is A_J^T T A_J, zero outside k x k
        bt.block(r, j.coord, 1, k) = out.head(k).transpose();
      }
    }
  }
  // B T B_n^T over the column blocks where B has entries.
  integ.ggl_cross.setZero();
  for (const auto& [first, size] : integ.ggl_blocks)
    integ.ggl_cross.noalias() +=
        bt.middleCols(first, size).lazyProduct(integ.ggl_b.middleCols(first, size).transpose());
  ForEachHeldRow(model, data, [&](int r) {
    integ.ggl_cross.row(r).setZero();
    integ.ggl_cross.col(r).setZero();
    integ.ggl_cross(r, r) = 1.0;
  });
  integ.ggl_cross_lu.compute(integ.ggl_cross);
  // Singular: a pivot below round-off of the largest (rcond() would allocate).
  const auto pivots = integ.ggl_cross_lu.matrixLU().diagonal().cwiseAbs();
  return pivots.allFinite() && pivots.minCoeff() > 1e-14 * pivots.maxCoeff();
}

// Update the configuration: q_{n+1} = q_n o exp(h dq), always recomposed from q_n.
void UpdateConfiguration(const Model& model, Data& data, const Integrator& integ, double h) {
  RestoreState(integ.q_start, data);
  data.increment.head(model.nv) = h * integ.dq;
  Retract(model, data, data.increment.head(model.nv));
}

// The assembly options of the dynamic iteration (Bottasso scaling, assemble.h).
AssemblyOptions DynamicAssemblyOptions(const DynamicOptions& opt, const StepConstants& c,
                                       double time) {
  AssemblyOptions o;
  o.time = time;
  o.dynamics = true;
  o.c_mass = c.beta_p;
  o.c_damping = c.gamma_p;
  o.c_stiffness = 1.0;
  o.s_rows = c.bh2;
  o.s_constraints = 1.0;
  o.s_multipliers = 1.0 / c.bh2;
  o.use_node_tangent = opt.use_tangent_operator;
  // Stabilised index 2: the constraint rows of the matrix are the velocity constraint's,
  // B + (h beta / gamma) Z T (method-next.md §N1.3, scaled by D_L).
  if (opt.constraints == ConstraintFormulation::kGgl)
    o.velocity_constraint_tangent = 1.0 / c.gamma_p;  // h beta / gamma
  return o;
}

// Assemble at the current iterate; the iteration matrix (and the tangent operators T(h dq) of
// the nodes and of joints whose H_J retracts by the exponential) only `with_matrix`.
bool AssembleIterate(const Model& model, Data& data, const DynamicOptions& opt,
                     AssemblyOptions& o, bool with_matrix, std::string* why) {
  if (with_matrix && opt.use_tangent_operator) {
    for (std::size_t i = 0; i < model.nodes.size(); ++i)
      if (model.nodes[i].dof >= 0)
        data.node_tangent[i] = TSE3(data.increment.segment<6>(model.nodes[i].dof));
    for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
      const Joint& j = model.joints[jj];
      if (j.k() == 0 || JointHasGlobalCoordinates(j.type)) continue;
      CalcJointCoordinateTangent(j, data.increment.segment(j.coord, j.k()),
                                 &data.node_tangent[model.nodes.size() + jj]);
    }
  }
  o.assemble_matrix = with_matrix;
  if (Assemble(model, data, o)) return true;
  if (why) {
    char buf[200];
    if (data.failed_element >= 0)
      std::snprintf(buf, sizeof buf,
                    "element %d rotates by %.4g rad, beyond what one helical element "
                    "represents (2 pi); use more elements",
                    data.failed_element, data.failed_rotation);
    else
      std::snprintf(buf, sizeof buf, "the residual is not finite");
    *why = buf;
  }
  return false;
}

// The convergence measures of an assembled iterate: largest residual and constraint entries,
// the residual's scale and round-off floor, and whether the residual test passes.
struct IterateMeasures {
  double res, con, scale, floor;
  bool residual_ok;
};

IterateMeasures MeasureIterate(const Model& model, const Data& data, const DynamicOptions& opt) {
  IterateMeasures m;
  m.res = data.residual.head(model.nv).cwiseAbs().maxCoeff();
  m.con = model.nc > 0 ? data.residual.tail(model.nc).cwiseAbs().maxCoeff() : 0.0;
  m.scale = std::max(data.force_scale, 1e-300);
  m.floor = 32.0 * std::numeric_limits<double>::epsilon() *
            std::max(data.term_scale, data.force_scale);
  m.residual_ok = m.con <= opt.constraint_tolerance &&
                  (m.res <= opt.residual_tolerance * m.scale || m.res <= m.floor);
  return m;
}

// ConvergenceTest::kEstimated: the iterate after this correction has the residual,
// constraints and correction of this one times the contraction of the iteration (simplified
// or quasi-Newton, linear convergence): the larger of those of the last two corrections and
// of the last two residuals (constraint maxima). What this iterate fails, the next one must
// pass by estimate, with the margin kEstimateSafety.
bool ConvergedByEstimate(const DynamicOptions& opt, const IterateMeasures& m, double increment,
                         bool increment_ok, double last_increment, double last_res,
                         double last_con) {
  const auto ratio = [](double now, double before) { return now > 0.0 ? now / before : 0.0; };
  const double theta = ratio(increment, last_increment);
  const double c_res = std::max(theta, ratio(m.res, last_res));
  const double c_con = std::max(theta, ratio(m.con, last_con));
  const double r = kEstimateSafety * opt.residual_tolerance * m.scale;
  return std::max(c_res, c_con) <= kMaxEstimateContraction &&
         (increment_ok || theta * increment <= kEstimateSafety * opt.increment_tolerance) &&
         (m.residual_ok || (c_con * m.con <= kEstimateSafety * opt.constraint_tolerance &&
                            (c_res * m.res <= r || c_res * m.res <= m.floor)));
}

// Correct: solve the iteration matrix for the Newton correction (factorising it when
// `factorize`) and apply it to dq, v, vdot and lambda. Returns false if the matrix is singular.
//
// ConstraintFormulation::kGgl (docs/numerics.md, "Stabilised index 2"): the unknowns are the
// Newmark correction y = dx + B_n^T dnu (which moves v and vdot), dlambda and dnu. With the
// (1,3) block and the coupling Z T B_n^T dnu of the velocity rows dropped (method-next.md
// §N1.3; both multiply dnu, which is of the size of the position-constraint defect), the
// system is block triangular:
//   [S_3 with rows B + (h beta / gamma) Z T] [y; dmu] = -[r; (h beta / gamma)(B v + dphi/dt)],
//   B T B_n^T dnu = B T y + phi,   dx = y - B_n^T dnu,
// B T at the iterate of the factorisation (FactorizeGglCross). The residual is exact, so the
// converged state is the stabilised index-2 one.
bool Correct(const Model& model, Data& data, Integrator& integ, const StepConstants& c,
             bool factorize) {
  const bool ggl = integ.options.constraints == ConstraintFormulation::kGgl && model.nc > 0;
  if (ggl) {
    const double s_v = c.h * integ.params.beta / integ.params.gamma;
    integ.ggl_phi = data.residual.tail(model.nc);
    data.residual.tail(model.nc) = s_v * integ.ggl_bv;
    ForEachHeldRow(model, data, [&](int r) { data.residual(model.nv + r) = integ.ggl_phi(r); });
  }
  bool solved;
  if (factorize) {
    ++integ.factorizations;
    solved = SolveAssembledSystem(model, data);
  } else {
    solved = SolveFactorizedSystem(model, data);
  }
  if (!solved) return false;
  if (ggl) {
    if (factorize && !FactorizeGglCross(model, data, integ)) return false;
    integ.ggl_y = data.increment.head(model.nv);
    integ.ggl_rhs.noalias() = integ.ggl_bt * integ.ggl_y;
    integ.ggl_rhs += integ.ggl_phi;
    ForEachHeldRow(model, data, [&](int r) { integ.ggl_rhs(r) = 0.0; });
    integ.ggl_dnu.noalias() = integ.ggl_cross_lu.solve(integ.ggl_rhs);
    integ.ggl_nu += integ.ggl_dnu;
    data.increment.head(model.nv).noalias() -= integ.ggl_b.transpose() * integ.ggl_dnu;
    const auto dx = data.increment.head(model.nv);
    integ.dq += dx / c.h;
    data.v += c.gamma_p * integ.ggl_y;
    data.vdot += c.beta_p * integ.ggl_y;
    data.lambda += data.increment.tail(model.nc) / c.bh2;
    return true;
  }
  const auto dx = data.increment.head(model.nv);
  integ.dq += dx / c.h;
  data.v += c.gamma_p * dx;
  data.vdot += c.beta_p * dx;
  data.lambda += data.increment.tail(model.nc) / c.bh2;
  return true;
}

// Accept: the auxiliary acceleration of the converged state, and the next step's predictor:
// whichever start would have been closer for this step, vdot_n (smooth motion) or 0
// (undamped high-frequency content, which flips the sign of vdot from step to step).
void Accept(Data& data, Integrator& integ, const StepConstants& c) {
  integ.a = integ.a_base + c.c_a * data.vdot;
  if (integ.options.constraints == ConstraintFormulation::kGgl && integ.ggl_nu.size() > 0)
    integ.max_nu = std::max(integ.max_nu, integ.ggl_nu.cwiseAbs().maxCoeff());
  if (integ.options.predictor == Predictor::kAdaptive)
    integ.use_last_acceleration =
        (data.vdot - integ.vdot_start).squaredNorm() <= data.vdot.squaredNorm();
}

// One generalized-alpha step of size h from the current state (method.md §5.2): predict, then
// Newton iterations of update configuration -> assemble -> check convergence -> correct, then
// accept. Returns the number of Newton corrections, or -1 on failure (state then undefined:
// the caller restores). `conservative`: full Newton from the zero-acceleration start, whatever
// the options (the retry of a step the faster settings could not do).
// The step ends at t_end (= its start + h up to rounding; exactly a breakpoint when it ends on
// one); `left_limit`: the profiles are evaluated just before t_end (a step ending on a
// breakpoint, method-next.md §N1.2 step 1).
int TryStep(const Model& model, Data& data, Integrator& integ, double h, double t_end,
            bool left_limit, bool conservative, std::string* why) {
  const DynamicOptions& opt = integ.options;
  const StepConstants c = MakeStepConstants(integ.params, h);
  bool full_newton = conservative || opt.newton_matrix == NewtonMatrix::kFull;
  Predict(data, integ, c, integ.use_last_acceleration && !conservative);
  data.time = t_end;
  AssemblyOptions o = DynamicAssemblyOptions(
      opt, c, left_limit ? std::nextafter(t_end, -std::numeric_limits<double>::infinity()) : t_end);

  const bool ggl = opt.constraints == ConstraintFormulation::kGgl && model.nc > 0;
  if (ggl) PrepareGglStep(model, data, integ);
  double last_increment = INFINITY, last_res = INFINITY, last_con = INFINITY;
  bool factorized = false;  // data.matrix holds a factorisation from this step
  // Length-driven tendons (docs/numerics.md, "Length-driven tendons"): at a converged iterate
  // a taut tendon with negative tension goes slack and a slack one that reached its length
  // goes taut; Newton then goes on from there with the new rows (at most two switches per
  // tendon per attempt: a set that keeps changing is accepted as it is).
  int switches_left = 2 * static_cast<int>(model.tendons.size());
  const auto active_set_changed = [&]() {
    if (switches_left <= 0 || UpdateTendonSlack(model, data, o.time) == 0) return false;
    --switches_left;
    factorized = false;
    last_increment = last_res = last_con = INFINITY;
    return true;
  };
  for (int it = 0; it <= opt.max_iterations; ++it) {
    UpdateConfiguration(model, data, integ, h);
    const bool need_matrix = full_newton || !factorized;
    // Once the last correction passed the increment test the step usually converges here:
    // assemble the residual alone, and the matrix only if the residual test then fails (the
    // residual does not depend on it).
    const bool may_converge = last_increment <= opt.increment_tolerance;
    const bool with_matrix = need_matrix && !may_converge && it < opt.max_iterations;
    if (!AssembleIterate(model, data, opt, o, with_matrix, why)) return -1;
    IterateMeasures m = MeasureIterate(model, data, opt);
    if (ggl) {
      // The velocity constraint, scaled like its row of the iteration matrix (h beta / gamma),
      // enters the constraint test.
      CalcVelocityConstraint(model, data, o.time, integ.ggl_bv);
      // A length-driven tendon caught taut in this step keeps its position row (nu) but not
      // its rate row: its route's rate jumps to L_p's by the inelastic catch after the step
      // (CatchTendons), as under index 3; asking it of the step would ask an impulse of the
      // smooth iteration.
      for (std::size_t ti = 0; ti < model.tendons.size(); ++ti)
        if (model.tendons[ti].row >= 0 && integ.slack_start[ti] && !data.tendon_slack[ti])
          integ.ggl_bv(model.tendons[ti].row) = 0.0;
      const double s_v = h * integ.params.beta / integ.params.gamma;
      m.con = std::max(m.con, s_v * integ.ggl_bv.cwiseAbs().maxCoeff());
      m.residual_ok = m.con <= opt.constraint_tolerance &&
                      (m.res <= opt.residual_tolerance * m.scale || m.res <= m.floor);
    }
    if (it > 0 && m.residual_ok && may_converge) {
      if (active_set_changed()) continue;
      Accept(data, integ, c);
      return it;
    }
    if (it == opt.max_iterations) break;
    if (need_matrix && !with_matrix && !AssembleIterate(model, data, opt, o, true, why)) return -1;
    if (!Correct(model, data, integ, c, need_matrix)) {
      if (why) *why = "the iteration matrix is singular";
      return -1;
    }
    if (need_matrix) factorized = true;
    double increment = ScaledIncrementSize(model, data.increment.head(model.nv));
    if (ggl) increment = std::max(increment, ScaledIncrementSize(model, integ.ggl_y));
    // Converged: the residual passed at this iterate and its correction is below the
    // increment tolerance (the corrected state is only closer to the solution).
    const bool increment_ok = increment <= opt.increment_tolerance;
    bool converged = increment_ok && m.residual_ok;
    if (!converged && opt.convergence == ConvergenceTest::kEstimated && it > 0) {
      converged = ConvergedByEstimate(opt, m, increment, increment_ok, last_increment, last_res,
                                      last_con);
      if (converged) ++integ.estimated_convergences;
    }
    if (converged) {
      UpdateConfiguration(model, data, integ, h);
      if (active_set_changed()) continue;
      Accept(data, integ, c);
      return it + 1;
    }
    // A reused matrix that contracts too little: rebuild it, and from then on at every
    // iteration of this step (the step is too nonlinear for the simplified iteration).
    if (!need_matrix && increment > opt.refresh_ratio * last_increment) full_newton = true;
    last_increment = increment;
    last_res = m.res;
    last_con = m.con;
  }
  if (why) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "Newton did not converge in %d iterations",
                  opt.max_iterations);
    *why = buf;
  }
  return -1;
}

// Length-driven tendons whose route stretches at another rate than L_p (a tendon caught taut
// in the step just taken, or L_p's rate jumping at a breakpoint) are caught inelastically: the
// velocities jump by the mass-weighted projection [M B^T; B 0] [dv; p] = [0; -e], e the taut
// tendons' rows of B v + dphi/dt (zero restitution) and zero in every other row (the joints
// keep their velocity constraints as they are). Nothing when every e is within round-off.
bool CatchTendons(const Model& model, Data& data, Integrator& integ) {
  if (model.tendons.empty() || model.nc == 0) return true;
  CalcVelocityConstraint(model, data, data.time, integ.tendon_rate_error);
  const double scale = 1e-10 * std::max(1.0, data.v.cwiseAbs().maxCoeff() * model.length_scale);
  bool any = false;
  for (std::size_t i = 0; i < model.tendons.size(); ++i) {
    const Tendon& t = model.tendons[i];
    if (t.row >= 0 && !data.tendon_slack[i])
      any = any || std::abs(integ.tendon_rate_error(t.row)) > scale;
  }
  if (!any) return true;
  AssemblyOptions o;
  o.time = data.time;
  o.dynamics = true;
  o.c_mass = 1.0;
  o.c_damping = 0.0;
  o.c_stiffness = 0.0;
  if (!Assemble(model, data, o)) return false;
  data.residual.setZero();
  for (std::size_t i = 0; i < model.tendons.size(); ++i) {
    const Tendon& t = model.tendons[i];
    if (t.row >= 0 && !data.tendon_slack[i])
      data.residual(model.nv + t.row) = integ.tendon_rate_error(t.row);
  }
  if (!SolveAssembledSystem(model, data)) return false;
  data.v += data.increment.head(model.nv);
  ++integ.tendon_catches;
  return true;
}

void SaveStepStart(const Data& data, Integrator& integ) {
  integ.slack_start = data.tendon_slack;  // same size: no allocation
  SaveState(data, &integ.q_start);
  integ.v_start = data.v;
  integ.vdot_start = data.vdot;
  integ.a_start = integ.a;
  integ.lambda_start = data.lambda;
}

void RestoreStepStart(const Model& model, Data& data, Integrator& integ, double t) {
  RestoreState(integ.q_start, data);
  data.v = integ.v_start;
  data.vdot = integ.vdot_start;
  integ.a = integ.a_start;
  data.lambda = integ.lambda_start;
  data.tendon_slack = integ.slack_start;
  data.time = t;
  (void)model;
}

// The step history (summary.json): every accepted step or substep.
void RecordStepSize(Integrator& integ, double h) {
  integ.min_h = std::min(integ.min_h, h);
  integ.max_h = std::max(integ.max_h, h);
  integ.sum_h += h;
  ++integ.accepted_substeps;
}

// The first breakpoint after t (beyond the snapping tolerance), or infinity.
double NextBreakpoint(const Integrator& integ, double t, double tolerance) {
  const auto it =
      std::upper_bound(integ.breakpoints.begin(), integ.breakpoints.end(), t + tolerance);
  return it != integ.breakpoints.end() ? *it : std::numeric_limits<double>::infinity();
}

}  // namespace

StepResult Step(const Model& model, Data& data, Integrator& integ, double h,
                const StopRequest& stop) {
  StepResult result;
  result.substeps = 0;
  double t_end = data.time + h;
  // A breakpoint within this distance of a substep's end is that end (the run loop's step ends
  // are breakpoints up to the rounding of start + h).
  const double snap = 1e-9 * h;
  const double h_min = h * std::ldexp(1.0, -integ.options.max_halvings);
  double hs = h;
  std::string& why = integ.why;  // capacity reserved at set-up: a failed attempt allocates nothing
  why.clear();
  const DynamicOptions& opt = integ.options;
  const bool conservative = opt.newton_matrix == NewtonMatrix::kFull &&
                            opt.predictor == Predictor::kZero;
  if (std::abs(NextBreakpoint(integ, data.time, snap) - t_end) <= snap)
    t_end = NextBreakpoint(integ, data.time, snap);
  while (data.time < t_end - 1e-12 * h) {
    const double t0 = data.time;
    // This substep: hs, cut at the step's end and at the next breakpoint.
    double h_sub = std::min(hs, t_end - t0), t_sub = t0 + h_sub;
    if (h_sub == t_end - t0) t_sub = t_end;
    const double bp = NextBreakpoint(integ, t0, snap);
    const bool at_breakpoint = bp <= t_sub + snap;
    if (at_breakpoint) {
      t_sub = bp;
      h_sub = bp - t0;
    }
    if (stop.Requested()) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "step interrupted at t = %.9g s", t0);
      result.interrupted = true;
      result.message = buf;
      return result;
    }
    if (!ApplyPerturbedStart(model, data, integ, h_sub, &why)) {
      result.message = "perturbed start: " + why;
      return result;
    }
    SaveStepStart(data, integ);
    int its = TryStep(model, data, integ, h_sub, t_sub, at_breakpoint, false, &why);
    if (its < 0 && !conservative) {
      // The simplified iteration or the predictor failed: retry the same step with full
      // Newton from the zero-acceleration start before halving.
      RestoreStepStart(model, data, integ, t0);
      ++integ.retries;
      its = TryStep(model, data, integ, h_sub, t_sub, at_breakpoint, true, &why);
    }
    if (its >= 0) {
      UpdateBranchReferences(model, data);
      result.iterations += its;
      ++result.substeps;
      RecordStepSize(integ, h_sub);
      integ.iterations += its;
      integ.max_iterations_in_step = std::max(integ.max_iterations_in_step, its);
      hs = std::min(h, 2.0 * hs);
      // A tendon went slack or taut in this step (docs/numerics.md, "Length-driven tendons"):
      // the forces jump, so restart as at a breakpoint; a tendon caught taut first stops its
      // route's stretching rate inelastically.
      const bool switched = data.tendon_slack != integ.slack_start;
      if (switched) ++integ.tendon_switches;
      if (switched || at_breakpoint) {
        if (!CatchTendons(model, data, integ)) {
          result.message = "the inelastic catch of a tendon failed (singular [M B^T; B 0])";
          return result;
        }
      }
      // method-next.md §N1.2: consistent vdot, lambda and a from the right limits.
      if ((at_breakpoint || switched) && !RestartDynamics(model, data, integ, &result.message))
        return result;
      continue;
    }
    RestoreStepStart(model, data, integ, t0);
    if (h_sub * 0.5 < h_min * (1.0 - 1e-12)) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "step failed at t = %.9g s (step %.3g s, after %d halvings): ",
                    t0, h_sub, integ.options.max_halvings);
      result.message = std::string(buf) + why;
      return result;
    }
    hs = 0.5 * h_sub;
    ++integ.halvings;
  }
  data.time = t_end;
  ++integ.steps;
  result.ok = true;
  return result;
}

// ---- error-controlled steps ------------------------------------------------------------------

double LocalErrorConstant(const GeneralizedAlpha& p) {
  return p.beta - 1.0 / 6.0 + 0.5 * (p.alpha_m - p.alpha_f);
}

namespace {

// PI controller (method-next.md §N2.4): the estimate is O(h^3).
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

// The weighted RMS norm of integ.error (method-next.md §N2.1): component i divided by
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

}  // namespace

StepResult AdaptiveStep(const Model& model, Data& data, Integrator& integ, double t_limit,
                        const StopRequest& stop) {
  StepResult result;
  result.substeps = 0;
  const DynamicOptions& opt = integ.options;
  const double t0 = data.time;
  if (!(t_limit > t0)) {
    result.ok = true;
    return result;
  }
  double h = integ.h_control;
  if (h <= 0.0)
    h = opt.initial_step > 0.0 ? opt.initial_step : 1e-3 * (t_limit - t0);
  const bool conservative = opt.newton_matrix == NewtonMatrix::kFull &&
                            opt.predictor == Predictor::kZero;
  const double c_err = LocalErrorConstant(integ.params);
  integ.a_accepted = integ.a;
  std::string& why = integ.why;  // capacity reserved at set-up: a failed attempt allocates nothing
  why.clear();
  for (;;) {
    h = std::clamp(h, opt.min_step, opt.max_step);
    // The step's end: t_limit or the next breakpoint when within 1.1 h; half the way there when
    // within 2 h (no sliver step before it); else t0 + h.
    const double snap = 1e-9 * h;
    const double bp = NextBreakpoint(integ, t0, snap);
    const double target = std::min(t_limit, bp);
    const bool target_is_breakpoint = bp <= t_limit;
    const double room = target - t0;
    double hs = h, t1 = t0 + h;
    bool lands = false;
    if (room <= 1.1 * h) {
      hs = room;
      t1 = target;
      lands = true;
    } else if (room < 2.0 * h) {
      hs = 0.5 * room;
      t1 = t0 + hs;
    }
    const bool truncated = hs < h;
    if (stop.Requested()) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "step interrupted at t = %.9g s", t0);
      result.interrupted = true;
      result.message = buf;
      integ.a = integ.a_accepted;
      return result;
    }
    // method-next.md §N2.2: a_n approximates vdot at t_n + (alpha_m - alpha_f) h; rescale it to
    // the new step size, or the scheme is first order on a variable grid.
    if (integ.h_last > 0.0 && hs != integ.h_last)
      integ.a = data.vdot + (hs / integ.h_last) * (integ.a_accepted - data.vdot);
    else
      integ.a = integ.a_accepted;
    SaveStepStart(data, integ);
    const bool left_limit = lands && target_is_breakpoint;
    int its = TryStep(model, data, integ, hs, t1, left_limit, false, &why);
    if (its < 0 && !conservative) {
      RestoreStepStart(model, data, integ, t0);
      ++integ.retries;
      its = TryStep(model, data, integ, hs, t1, left_limit, true, &why);
    }
    double err = INFINITY;
    int worst = 0;
    if (its >= 0) {
      integ.error = (c_err * hs * hs) * (integ.a - integ.a_start);
      err = WeightedErrorNorm(model, integ, hs, &worst);
      integ.error_norm = err;
    }
    if (its >= 0 && err <= 1.0) {
      // Accepted: the dense-output record of the step, then the controller.
      integ.dense_t0 = t0;
      integ.dense_h = hs;
      integ.dense_q0 = integ.q_start;
      integ.dense_v0 = integ.v_start;
      integ.dense_vdot0 = integ.vdot_start;
      integ.dense_lambda0 = integ.lambda_start;
      integ.dense_v1 = data.v;
      integ.dense_vdot1 = data.vdot;
      integ.dense_lambda1 = data.lambda;
      integ.dense_d = hs * integ.dq;
      UpdateBranchReferences(model, data);
      result.iterations += its;
      result.substeps = 1;
      integ.iterations += its;
      integ.max_iterations_in_step = std::max(integ.max_iterations_in_step, its);
      RecordStepSize(integ, hs);
      ++integ.steps;
      const double e = std::max(err, 1e-10);
      double factor = kSafety * std::pow(e, -kGainI);
      if (integ.err_last > 0.0) factor *= std::pow(integ.err_last / e, kGainP);
      else factor = kSafety * std::pow(e, -1.0 / kOrder);
      factor = std::clamp(factor, kMinShrink, integ.allow_growth ? kMaxGrowth : 1.0);
      // A step shortened to land on a target keeps the controller's size (§N2.4 step 5).
      integ.h_control = truncated ? std::max(h, hs * factor) : hs * factor;
      integ.h_control = std::clamp(integ.h_control, opt.min_step, opt.max_step);
      integ.err_last = e;
      integ.allow_growth = true;
      integ.h_last = hs;
      data.time = t1;
      // A length-driven tendon went slack or taut, or L_p's rate jumps here: as in Step.
      const bool switched = data.tendon_slack != integ.slack_start;
      if (switched) ++integ.tendon_switches;
      if ((switched || left_limit) && !CatchTendons(model, data, integ)) {
        result.message = "the inelastic catch of a tendon failed (singular [M B^T; B 0])";
        return result;
      }
      if (left_limit || switched) {
        // method-next.md §N1.2: consistent vdot, lambda and a from the right limits; the PI
        // memory restarts too.
        if (!RestartDynamics(model, data, integ, &result.message)) return result;
        integ.err_last = 0.0;
      }
      result.ok = true;
      return result;
    }
    // Rejected: Newton failure halves the step, an error above the tolerance shrinks it by
    // the I controller; the next accepted step may not grow.
    RestoreStepStart(model, data, integ, t0);
    ++integ.rejected;
    integ.err_last = 0.0;
    integ.allow_growth = false;
    if (hs <= opt.min_step * (1.0 + 1e-12)) {
      char buf[240];
      if (its < 0)
        std::snprintf(buf, sizeof buf, "step failed at t = %.9g s with the smallest step %.3g s: ",
                      t0, hs);
      else
        std::snprintf(buf, sizeof buf,
                      "step failed at t = %.9g s: with the smallest step %.3g s (min_step) the "
                      "estimated local error is %.4g times the tolerance, largest in ",
                      t0, hs, err);
      result.message = std::string(buf) + (its < 0 ? why : DescribeUnknown(model, worst));
      integ.a = integ.a_accepted;
      return result;
    }
    h = its < 0 ? 0.5 * hs
                : hs * std::clamp(kSafety * std::pow(err, -1.0 / kOrder), kMinShrink, 1.0);
  }
}

StepResult AdvanceTo(const Model& model, Data& data, Integrator& integ, double t_end,
                     const StopRequest& stop) {
  StepResult total;
  total.substeps = 0;
  while (data.time < t_end) {
    const StepResult r = AdaptiveStep(model, data, integ, t_end, stop);
    total.iterations += r.iterations;
    total.substeps += r.substeps;
    if (!r.ok) {
      total.interrupted = r.interrupted;
      total.message = r.message;
      return total;
    }
  }
  total.ok = true;
  return total;
}

void InterpolateStep(const Model& model, const Data& data, Integrator& integ, double t,
                     Data& out) {
  const double h = integ.dense_h;
  const double th = h > 0.0 ? std::clamp((t - integ.dense_t0) / h, 0.0, 1.0) : 1.0;
  const double th2 = th * th, th3 = th2 * th;
  // Cubic Hermite basis and its derivatives (method-next.md §N2.3).
  const double h10 = th3 - 2.0 * th2 + th, h01 = -2.0 * th3 + 3.0 * th2, h11 = th3 - th2;
  const double d10 = 3.0 * th2 - 4.0 * th + 1.0, d01 = 6.0 * th - 6.0 * th2,
               d11 = 3.0 * th2 - 2.0 * th;
  const Eigen::VectorXd& v0 = integ.dense_v0;
  const Eigen::VectorXd& v1 = integ.dense_v1;
  const Eigen::VectorXd& D = integ.dense_d;
  Eigen::VectorXd& psi = integ.dense_psi;
  Eigen::VectorXd& dpsi = integ.dense_dpsi;
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    const Vec6 d = D.segment<6>(n.dof);
    const Vec6 w = TSE3Inv(d) * v1.segment<6>(n.dof);  // T^-1(D) v_{n+1}
    const Vec6 a = v0.segment<6>(n.dof);
    psi.segment<6>(n.dof) = h10 * h * a + h01 * d + h11 * h * w;
    dpsi.segment<6>(n.dof) = d10 * h * a + d01 * d + d11 * h * w;
  }
  for (const Joint& j : model.joints) {
    const int k = j.k();
    if (k == 0) continue;
    Vec6 w = Vec6::Zero();
    w.head(k) = v1.segment(j.coord, k);
    if (!JointHasGlobalCoordinates(j.type)) {
      Mat6 T;
      CalcJointCoordinateTangent(j, D.segment(j.coord, k), &T);
      w = T.partialPivLu().solve(w);
    }
    psi.segment(j.coord, k) = h10 * h * v0.segment(j.coord, k) + h01 * D.segment(j.coord, k) +
                              h11 * h * w.head(k);
    dpsi.segment(j.coord, k) = d10 * h * v0.segment(j.coord, k) + d01 * D.segment(j.coord, k) +
                               d11 * h * w.head(k);
  }
  RestoreState(integ.dense_q0, out);
  Retract(model, out, psi);
  // Velocities: eta = T(psi) psi' / h.
  const double inv_h = h > 0.0 ? 1.0 / h : 0.0;
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    out.v.segment<6>(n.dof) = inv_h * (TSE3(psi.segment<6>(n.dof)) * dpsi.segment<6>(n.dof));
  }
  for (const Joint& j : model.joints) {
    const int k = j.k();
    if (k == 0) continue;
    if (JointHasGlobalCoordinates(j.type)) {
      out.v.segment(j.coord, k) = inv_h * dpsi.segment(j.coord, k);
    } else {
      Mat6 T;
      CalcJointCoordinateTangent(j, psi.segment(j.coord, k), &T);
      Vec6 x = Vec6::Zero();
      x.head(k) = dpsi.segment(j.coord, k);
      out.v.segment(j.coord, k) = inv_h * (T * x).head(k);
    }
  }
  if (h <= 0.0) out.v = data.v;
  out.vdot = (1.0 - th) * integ.dense_vdot0 + th * integ.dense_vdot1;
  out.lambda = (1.0 - th) * integ.dense_lambda0 + th * integ.dense_lambda1;
  out.w_ref = data.w_ref;
  UpdateShapePairs(model, out);  // the pairs of moving shapes near each other in this state
  out.time = t;
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
  state->a = integ.a;
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
  data.w_ref = state.w_ref;
  data.v = state.v;
  data.vdot = state.vdot;
  data.lambda = state.lambda;
  data.inputs = state.inputs;
  if (state.tendon_slack.size() == data.tendon_slack.size()) data.tendon_slack = state.tendon_slack;
  if (state.a.size() == integ.a.size()) integ.a = state.a;
  integ.use_last_acceleration = state.use_last_acceleration;
}

}  // namespace screwfem
