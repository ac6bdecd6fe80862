#include "screwfem/solve/dynamics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "screwfem/elements/rod.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/statics.h"

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
  require(o.newton_matrix == NewtonMatrix::kEveryIteration ||
              o.newton_matrix == NewtonMatrix::kOncePerStep,
          "newton_matrix", "must be EVERY_ITERATION or ONCE_PER_STEP");
  require(o.predictor == Predictor::kZeroAcceleration ||
              o.predictor == Predictor::kLastAcceleration || o.predictor == Predictor::kAdaptive,
          "predictor", "must be ZERO_ACCELERATION, LAST_ACCELERATION or ADAPTIVE");
  require(o.convergence == ConvergenceTest::kMeasured ||
              o.convergence == ConvergenceTest::kEstimated,
          "convergence", "must be MEASURED or ESTIMATED");
}

bool InitializeDynamics(const Model& model, Data& data, Integrator& integ,
                        const DynamicOptions& options, std::string* message) {
  integ.options = options;
  integ.params = GeneralizedAlpha::FromSpectralRadius(options.rho_inf);
  const int nv = model.nv, nc = model.nc;
  integ.a = Eigen::VectorXd::Zero(nv);
  integ.v_start = integ.vdot_start = integ.a_start = integ.dq = integ.a_base =
      Eigen::VectorXd::Zero(nv);
  integ.lambda_start = Eigen::VectorXd::Zero(nc);
  SaveState(data, &integ.q_start);
  // One tangent operator per node, then one per joint (used by spherical, planar and free
  // joints, whose coordinates retract by the exponential; see TryStep).
  data.node_tangent.assign(model.nodes.size() + model.joints.size(), Mat6::Identity());

  // Bdot v = d^2/de^2 phi(q exp(e v)) (exact for constant body velocities), by a central
  // second difference; only at start-up (method.md §5.4).
  Eigen::VectorXd bdot_v = Eigen::VectorXd::Zero(nc);
  const double vmax = ScaledIncrementSize(model, data.v);
  if (nc > 0 && vmax > 0.0) {
    const double e = 1e-4 / vmax;
    Eigen::VectorXd plus(nc), minus(nc), zero(nc), work(nv);
    ConstraintsAlong(model, data, integ.q_start, e, plus, work);
    ConstraintsAlong(model, data, integ.q_start, -e, minus, work);
    ConstraintsAlong(model, data, integ.q_start, 0.0, zero, work);
    bdot_v = (plus - 2.0 * zero + minus) / (e * e);
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
    if (message) *message = "initial state is invalid (an element is bent past its limit)";
    return false;
  }
  data.residual.tail(nc) = bdot_v;
  for (const Joint& j : model.joints)
    if (j.drive == DriveKind::kPrescribed)
      data.residual(nv + j.drive_row) -= j.drive_profile.Eval(data.time).accel;
  if (!SolveAssembledSystem(model, data)) {
    if (message)
      *message =
          "cannot compute consistent initial accelerations: the system [M B^T; B 0] is singular "
          "(a part without mass that is not fixed by constraints, or redundant constraints)";
    return false;
  }
  data.vdot = data.increment.head(nv);
  data.lambda = data.increment.tail(nc);
  integ.a = data.vdot;
  integ.use_last_acceleration = options.predictor != Predictor::kZeroAcceleration;
  return true;
}

namespace {

// One generalized-alpha step of size h from the current state (method.md §5.2). Returns the
// number of Newton corrections, or -1 on failure (state then undefined: caller restores).
// `conservative`: full Newton from the zero-acceleration start, whatever the options (the
// retry of a step the faster settings could not do).
int TryStep(const Model& model, Data& data, Integrator& integ, double h, bool conservative,
            std::string* why) {
  const GeneralizedAlpha& p = integ.params;
  const DynamicOptions& opt = integ.options;
  const int nv = model.nv;
  const double t_new = data.time + h;
  const double beta_p = (1.0 - p.alpha_m) / (h * h * p.beta * (1.0 - p.alpha_f));
  const double gamma_p = p.gamma / (h * p.beta);
  const double bh2 = p.beta * h * h;

  // Predictor. The auxiliary acceleration is a_{n+1} = a_base + c_a vdot_{n+1}; the Newton
  // corrections below keep v, dq and a consistent with it (gamma' dx = h gamma c_a beta' dx,
  // dx / h = h beta c_a beta' dx), so the iteration may start from any vdot_{n+1}.
  const double c_a = (1.0 - p.alpha_f) / (1.0 - p.alpha_m);
  integ.a_base = (p.alpha_f * integ.vdot_start - p.alpha_m * integ.a_start) / (1.0 - p.alpha_m);
  bool full_newton = conservative || opt.newton_matrix == NewtonMatrix::kEveryIteration;
  if (integ.use_last_acceleration && !conservative)
    data.vdot = integ.vdot_start;
  else
    data.vdot.setZero();
  integ.a = integ.a_base + c_a * data.vdot;
  data.v = integ.v_start + h * (1.0 - p.gamma) * integ.a_start + h * p.gamma * integ.a;
  integ.dq = integ.v_start + h * (0.5 - p.beta) * integ.a_start + h * p.beta * integ.a;
  data.lambda = integ.lambda_start;
  data.time = t_new;

  AssemblyOptions o;
  o.time = t_new;
  o.dynamics = true;
  o.c_mass = beta_p;
  o.c_damping = gamma_p;
  o.c_stiffness = 1.0;
  o.s_rows = bh2;
  o.s_constraints = 1.0;
  o.s_multipliers = 1.0 / bh2;
  o.use_node_tangent = opt.use_tangent_operator;

  // Assembles at the current iterate; the iteration matrix (and the tangent operators it
  // needs) only when `with_matrix`.
  const auto assemble = [&](bool with_matrix) {
    if (with_matrix && opt.use_tangent_operator) {
      for (const Node& n : model.nodes)
        if (n.dof >= 0)
          data.node_tangent[static_cast<std::size_t>(&n - model.nodes.data())] =
              TSE3(data.increment.segment<6>(n.dof));
      // Group joints: H_J = H_J,n exp(A_J x) with x = h dq_J; the correction of x moves H_J
      // by A_J T_k dx with T_k = A_J^T T(A_J x) A_J (A_J spans a subalgebra, orthonormal
      // columns).
      for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
        const Joint& j = model.joints[jj];
        const int k = j.k();
        if (k == 0 || JointHasGlobalCoordinates(j.type)) continue;
        const Vec6 xi = j.basis * data.increment.segment(j.coord, k);
        Mat6& TJ = data.node_tangent[model.nodes.size() + jj];
        TJ.setIdentity();
        TJ.topLeftCorner(k, k) = j.basis.transpose() * TSE3(xi) * j.basis;
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
  };
  // q_{n+1} = q_n o exp(h dq), always recomposed from q_n.
  const auto configure = [&] {
    RestoreState(integ.q_start, data);
    data.increment.head(nv) = h * integ.dq;
    Retract(model, data, data.increment.head(nv));
  };
  const auto accept = [&] {
    integ.a = integ.a_base + c_a * data.vdot;
    // The adaptive predictor starts the next step from whichever start would have been
    // closer for this one: vdot_n (smooth motion) or 0 (undamped high-frequency content,
    // which flips the sign of vdot from step to step).
    if (opt.predictor == Predictor::kAdaptive)
      integ.use_last_acceleration =
          (data.vdot - integ.vdot_start).squaredNorm() <= data.vdot.squaredNorm();
  };

  double last_increment = INFINITY, last_res = INFINITY, last_con = INFINITY;
  bool factorized = false;  // data.matrix holds a factorisation from this step
  for (int it = 0; it <= opt.max_iterations; ++it) {
    configure();
    const bool need_matrix = full_newton || !factorized;
    // Once the last correction passed the increment test the step usually converges here:
    // assemble the residual alone, and the matrix only if the residual test then fails (the
    // residual does not depend on it).
    const bool may_converge = last_increment <= opt.increment_tolerance;
    const bool with_matrix = need_matrix && !may_converge && it < opt.max_iterations;
    if (!assemble(with_matrix)) return -1;
    const double res = data.residual.head(nv).cwiseAbs().maxCoeff();
    const double con =
        model.nc > 0 ? data.residual.tail(model.nc).cwiseAbs().maxCoeff() : 0.0;
    const double scale = std::max(data.force_scale, 1e-300);
    const double floor = 32.0 * std::numeric_limits<double>::epsilon() *
                         std::max(data.term_scale, data.force_scale);
    const bool residual_ok = con <= opt.constraint_tolerance &&
                             (res <= opt.residual_tolerance * scale || res <= floor);
    if (it > 0 && residual_ok && may_converge) {
      accept();
      return it;
    }
    if (it == opt.max_iterations) break;
    if (need_matrix && !with_matrix && !assemble(true)) return -1;
    bool solved;
    if (need_matrix) {
      ++integ.factorizations;
      solved = SolveAssembledSystem(model, data);
      factorized = solved;
    } else {
      solved = SolveFactorizedSystem(model, data);
    }
    if (!solved) {
      if (why) *why = "the iteration matrix is singular";
      return -1;
    }
    const auto dx = data.increment.head(nv);
    integ.dq += dx / h;
    data.v += gamma_p * dx;
    data.vdot += beta_p * dx;
    data.lambda += data.increment.tail(model.nc) / bh2;
    const double increment = ScaledIncrementSize(model, dx);
    // Converged: the residual passed at this iterate and its correction is below the
    // increment tolerance (the corrected state is only closer to the solution).
    const bool increment_ok = increment <= opt.increment_tolerance;
    bool converged = increment_ok && residual_ok;
    // Estimated: the iterate after this correction has the residual, constraints and
    // correction of this one times the contraction of the iteration (simplified or
    // quasi-Newton, linear convergence): the larger of those of the last two corrections and
    // of the last two residuals (constraint maxima). What this iterate fails, the next one
    // must pass by estimate, with the margin kEstimateSafety.
    if (!converged && opt.convergence == ConvergenceTest::kEstimated && it > 0) {
      const auto ratio = [](double now, double before) { return now > 0.0 ? now / before : 0.0; };
      const double theta = ratio(increment, last_increment);
      const double c_res = std::max(theta, ratio(res, last_res));
      const double c_con = std::max(theta, ratio(con, last_con));
      const double r = kEstimateSafety * opt.residual_tolerance * scale;
      converged = std::max(c_res, c_con) <= kMaxEstimateContraction &&
                  (increment_ok || theta * increment <= kEstimateSafety * opt.increment_tolerance) &&
                  (residual_ok || (c_con * con <= kEstimateSafety * opt.constraint_tolerance &&
                                   (c_res * res <= r || c_res * res <= floor)));
      if (converged) ++integ.estimated_convergences;
    }
    if (converged) {
      configure();
      accept();
      return it + 1;
    }
    // A reused matrix that contracts too little: rebuild it, and from then on at every
    // iteration of this step (the step is too nonlinear for the simplified iteration).
    if (!need_matrix && increment > opt.refresh_ratio * last_increment) full_newton = true;
    last_increment = increment;
    last_res = res;
    last_con = con;
  }
  if (why) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "Newton did not converge in %d iterations",
                  opt.max_iterations);
    *why = buf;
  }
  return -1;
}

void SaveStepStart(const Data& data, Integrator& integ) {
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
  data.time = t;
  (void)model;
}

}  // namespace

StepResult Step(const Model& model, Data& data, Integrator& integ, double h,
                const StopRequest& stop) {
  StepResult result;
  result.substeps = 0;
  const double t_end = data.time + h;
  const double h_min = h * std::ldexp(1.0, -integ.options.max_halvings);
  double hs = h;
  std::string why;
  const DynamicOptions& opt = integ.options;
  const bool conservative = opt.newton_matrix == NewtonMatrix::kEveryIteration &&
                            opt.predictor == Predictor::kZeroAcceleration;
  while (data.time < t_end - 1e-12 * h) {
    hs = std::min(hs, t_end - data.time);
    const double t0 = data.time;
    if (stop.Requested()) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "step interrupted at t = %.9g s", t0);
      result.interrupted = true;
      result.message = buf;
      return result;
    }
    SaveStepStart(data, integ);
    int its = TryStep(model, data, integ, hs, false, &why);
    if (its < 0 && !conservative) {
      // The simplified iteration or the predictor failed: retry the same step with full
      // Newton from the zero-acceleration start before halving.
      RestoreStepStart(model, data, integ, t0);
      ++integ.retries;
      its = TryStep(model, data, integ, hs, true, &why);
    }
    if (its >= 0) {
      UpdateBranchReferences(model, data);
      result.iterations += its;
      ++result.substeps;
      integ.iterations += its;
      integ.max_iterations_in_step = std::max(integ.max_iterations_in_step, its);
      hs = std::min(h, 2.0 * hs);
      continue;
    }
    RestoreStepStart(model, data, integ, t0);
    if (hs * 0.5 < h_min * (1.0 - 1e-12)) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "step failed at t = %.9g s (step %.3g s, after %d halvings): ",
                    t0, hs, integ.options.max_halvings);
      result.message = std::string(buf) + why;
      return result;
    }
    hs *= 0.5;
    ++integ.halvings;
  }
  data.time = t_end;
  ++integ.steps;
  result.ok = true;
  return result;
}

Energy CalcEnergy(const Model& model, const Data& data) {
  Energy E;
  for (const RigidBody& b : model.bodies) {
    const SE3& H = data.H[static_cast<std::size_t>(b.node)];
    const int dof = model.nodes[static_cast<std::size_t>(b.node)].dof;
    if (dof >= 0) {
      const Vec6 eta = data.v.segment<6>(dof);
      const Vec3 vc = eta.head<3>() + eta.tail<3>().cross(b.com);
      E.kinetic += 0.5 * b.mass * vc.squaredNorm() + 0.5 * eta.tail<3>().dot(b.inertia * eta.tail<3>());
    }
    E.gravity -= b.mass * model.gravity.dot(H.Act(b.com));
  }
  constexpr double kXi[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
  constexpr double kW[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
  for (std::size_t e = 0; e < model.elements.size(); ++e) {
    const RodElement& el = model.elements[e];
    const Section& sec = model.rods[static_cast<std::size_t>(el.rod)].section;
    const SE3& HA = data.H[static_cast<std::size_t>(el.node_a)];
    const SE3& HB = data.H[static_cast<std::size_t>(el.node_b)];
    const Vec6 d = CalcRodRelativeMotion(HA, HB, data.w_ref[e]);
    const Vec6 strain = (d - el.d0) / el.length;
    E.strain += 0.5 * el.length * strain.dot(sec.stiffness.cwiseProduct(strain));
    const int da = model.nodes[static_cast<std::size_t>(el.node_a)].dof;
    const int db = model.nodes[static_cast<std::size_t>(el.node_b)].dof;
    Vec12 eta_ab = Vec12::Zero();
    if (da >= 0) eta_ab.head<6>() = data.v.segment<6>(da);
    if (db >= 0) eta_ab.tail<6>() = data.v.segment<6>(db);
    // 1/2 eta_AB^T M_e eta_AB of the model's inertia option (M_e(d) for option A).
    E.kinetic += CalcRodKineticEnergy(model.rod_inertia, el, sec, d, eta_ab);
    for (int i = 0; i < 3; ++i) {
      const Vec3 x = (HA * ExpSE3(kXi[i] * d)).x;
      E.gravity -= el.length * kW[i] * sec.inertia(0) * model.gravity.dot(x);
    }
  }
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.type == JointType::kFree) {  // spring on the relative motion's logarithm
      const Vec6 delta = CalcFreeJointDeflection(model, data, static_cast<int>(jj));
      E.spring += 0.5 * delta.dot(j.stiffness.cwiseProduct(delta));
      continue;
    }
    const int k = j.k();
    if (k == 0) continue;
    const auto alpha = data.q_joint.segment(j.coord - model.nv_nodes, k);
    if (!JointHasGlobalCoordinates(j.type)) {
      const Vec6 xi = LogSE3(data.HJ[jj]);
      for (int c = 0; c < k; ++c) {
        const double delta = j.basis.col(c).dot(xi);
        E.spring += 0.5 * j.stiffness(c) * delta * delta;
      }
      continue;
    }
    for (int c = 0; c < k; ++c) {
      double rest = j.rest(c);
      if (j.drive == DriveKind::kSeriesElastic && c == j.drive_coord)
        rest += j.drive_profile(data.time);
      const double delta = alpha(c) - rest;
      E.spring += 0.5 * j.stiffness(c) * delta * delta;
    }
  }
  return E;
}

}  // namespace screwfem
