#include "step_stages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/LU>

#include "screwfem/elements/joint.h"
#include "screwfem/elements/tendon.h"

namespace screwfem::generalized_alpha {

namespace {

// ---- the stages of one generalized-alpha step (docs/architecture.md, "One time step") -------------------------------

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

// ConstraintFormulation::kGgl (docs/numerics.md, "Stabilised index 2"): the gradient B_n = B(q_n)
// of the step's start, which multiplies nu in the configuration update. Data holds q_n. The rows
// of slack length-driven tendons hold their gradient too (their route's dL/dq at q_n): a tendon
// caught taut during the step then corrects along it (its row of B T B_n^T is not zero).
// nu starts from the linear extrapolation of the last two steps' (zero in held rows, and for a
// conservative retry), applied to the predicted configuration: the iteration matrix leaves out
// the effect of a nu correction on the elastic forces (K T B_n^T dnu), so its first correction
// must be small (docs/numerics.md, "Stabilised index 2", the nu predictor).
void PrepareGglStep(const Model& model, Data& data, Integrator& integ, double h,
                    bool conservative) {
  if (integ.options.constraints != ConstraintFormulation::kGgl || model.nc == 0) return;
  std::copy(data.tendon_slack.begin(), data.tendon_slack.end(), integ.ggl_slack.begin());
  std::fill(data.tendon_slack.begin(), data.tendon_slack.end(), char{0});
  CalcConstraintGradient(model, data, integ.ggl_b);
  std::copy(integ.ggl_slack.begin(), integ.ggl_slack.end(), data.tendon_slack.begin());
  if (conservative) {
    integ.ggl_nu.setZero();
    return;
  }
  integ.ggl_nu = 2.0 * integ.ggl_nu_last - integ.ggl_nu_before;
  ForEachHeldRow(model, data, [&](int r) { integ.ggl_nu(r) = 0.0; });
  for (const Integrator::GglBlock& b : integ.ggl_pattern)
    integ.dq.segment(b.col, b.cols).noalias() -=
        (1.0 / h) * integ.ggl_b.block(b.row, b.col, b.rows, b.cols)
                        .transpose()
                        .lazyProduct(integ.ggl_nu.segment(b.row, b.rows));
}

// ConstraintFormulation::kGgl: the position-constraint rows of the iteration at the current
// iterate, B(q) T with the tangent operators the matrix was assembled with (docs/numerics.md,
// "Stabilised index 2"; Delta x enters q as q_n o exp(h dq + Delta x)), and the factorised
// B T B_n^T that gives the nu correction (held rows and columns, ForEachHeldRow: the
// identity), over the blocks where B has entries (Integrator::ggl_pattern). False if it is
// singular (redundant constraints the build did not find).
bool FactorizeGglCross(const Model& model, const Data& data, Integrator& integ) {
  Eigen::MatrixXd& bt = integ.ggl_bt;
  CalcConstraintGradient(model, data, bt);
  using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;
  for (const Integrator::GglBlock& b : integ.ggl_pattern) {
    if (b.tangent < 0) continue;
    // T_J of a joint is A_J^T T A_J, zero outside k x k.
    const Mat6& T = data.node_tangent[static_cast<std::size_t>(b.tangent)];
    const Block out =
        bt.block(b.row, b.col, b.rows, b.cols).lazyProduct(T.topLeftCorner(b.cols, b.cols));
    bt.block(b.row, b.col, b.rows, b.cols) = out;
  }
  // B T B_n^T over the pairs of blocks that share a column group.
  integ.ggl_cross.setZero();
  for (const auto& [ia, ib] : integ.ggl_pairs) {
    const Integrator::GglBlock& a = integ.ggl_pattern[static_cast<std::size_t>(ia)];
    const Integrator::GglBlock& b = integ.ggl_pattern[static_cast<std::size_t>(ib)];
    integ.ggl_cross.block(a.row, b.row, a.rows, b.rows).noalias() +=
        bt.block(a.row, a.col, a.rows, a.cols)
            .lazyProduct(integ.ggl_b.block(b.row, b.col, b.rows, b.cols).transpose());
  }
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
  // B + (h beta / gamma) Z T (docs/numerics.md, "Stabilised index 2", scaled by D_L).
  if (opt.constraints == ConstraintFormulation::kGgl)
    o.velocity_constraint_tangent = 1.0 / c.gamma_p;  // h beta / gamma
  return o;
}

// Assemble at the current iterate; the iteration matrix (and the tangent operators T(h dq) of
// the nodes and of joints whose H_J retracts by the exponential) only `with_matrix`.
bool AssembleIterate(const Model& model, Data& data, const DynamicOptions& opt, AssemblyOptions& o,
                     bool with_matrix, std::string* why) {
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
    if (data.shape_pair_limit_reached)
      *why = ShapePairLimitMessage(model);
    else
      *why = buf;  // into the string's storage: no allocation inside a step
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
  m.floor =
      32.0 * std::numeric_limits<double>::epsilon() * std::max(data.term_scale, data.force_scale);
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
// (1,3) block and the coupling Z T B_n^T dnu of the velocity rows dropped (docs/numerics.md, "Stabilised index 2"; both multiply dnu, which is of the size of the position-constraint defect), the
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
    integ.ggl_rhs = integ.ggl_phi;
    for (const Integrator::GglBlock& b : integ.ggl_pattern)
      integ.ggl_rhs.segment(b.row, b.rows).noalias() +=
          integ.ggl_bt.block(b.row, b.col, b.rows, b.cols)
              .lazyProduct(integ.ggl_y.segment(b.col, b.cols));
    ForEachHeldRow(model, data, [&](int r) { integ.ggl_rhs(r) = 0.0; });
    integ.ggl_dnu.noalias() = integ.ggl_cross_lu.solve(integ.ggl_rhs);
    integ.ggl_nu += integ.ggl_dnu;
    for (const Integrator::GglBlock& b : integ.ggl_pattern)
      data.increment.segment(b.col, b.cols).noalias() -=
          integ.ggl_b.block(b.row, b.col, b.rows, b.cols)
              .transpose()
              .lazyProduct(integ.ggl_dnu.segment(b.row, b.rows));
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
  if (integ.line_search) integ.line_search_dx = data.increment.head(model.nv + model.nc);
  return true;
}

// The contact line search (DynamicOptions::line_search): takes back `share` of the last
// correction (Correct's, index 3), moving dq, v, vdot and lambda along it consistently.
void TakeBackCorrection(const Model& model, Data& data, Integrator& integ, const StepConstants& c,
                        double share) {
  const auto dx = integ.line_search_dx.head(model.nv);
  integ.dq -= (share / c.h) * dx;
  data.v -= (share * c.gamma_p) * dx;
  data.vdot -= (share * c.beta_p) * dx;
  data.lambda -= (share / c.bh2) * integ.line_search_dx.tail(model.nc);
}

// Accept: the auxiliary acceleration of the converged state, and the next step's predictor:
// whichever start would have been closer for this step, vdot_n (smooth motion) or 0
// (undamped high-frequency content, which flips the sign of vdot from step to step).
void Accept(Data& data, Integrator& integ, const StepConstants& c) {
  integ.a = integ.a_base + c.c_a * data.vdot;
  if (integ.options.constraints == ConstraintFormulation::kGgl && integ.ggl_nu.size() > 0) {
    integ.max_nu = std::max(integ.max_nu, integ.ggl_nu.cwiseAbs().maxCoeff());
    integ.ggl_nu_before = integ.ggl_nu_last;
    integ.ggl_nu_last = integ.ggl_nu;
  }
  if (integ.options.predictor == Predictor::kAdaptive)
    integ.use_last_acceleration =
        (data.vdot - integ.vdot_start).squaredNorm() <= data.vdot.squaredNorm();
}

// The state of a step's Newton iteration: whether it assembles a matrix at every iteration,
// whether data.matrix holds a factorisation from this step, the size of the last correction and
// the residual and constraint maxima of the last iterate (for the convergence tests), and the
// switches of length-driven tendons left.
struct NewtonIteration {
  bool full_newton = false;
  bool factorized = false;
  double last_increment = INFINITY, last_res = INFINITY, last_con = INFINITY;
  int switches_left = 0;
};

// Length-driven tendons (docs/numerics.md, "Length-driven tendons"): at a converged iterate
// a taut tendon with negative tension goes slack and a slack one that reached its length
// goes taut; Newton then goes on from there with the new rows (at most two switches per
// tendon per attempt: a set that keeps changing is accepted as it is).
bool ActiveSetChanged(const Model& model, Data& data, double time, NewtonIteration& n) {
  if (n.switches_left <= 0 || UpdateTendonSlack(model, data, time) == 0) return false;
  --n.switches_left;
  n.factorized = false;
  n.last_increment = n.last_res = n.last_con = INFINITY;
  return true;
}

// ConstraintFormulation::kGgl: the velocity constraint, scaled like its row of the iteration
// matrix (h beta / gamma), enters the constraint test.
void MeasureVelocityConstraint(const Model& model, Data& data, Integrator& integ, double h,
                               double time, IterateMeasures& m) {
  const DynamicOptions& opt = integ.options;
  CalcVelocityConstraint(model, data, time, integ.ggl_bv);
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

// After a correction (data.increment; the Newmark correction y too with kGgl) of the iterate
// measured by m: whether the step has converged. Otherwise the iteration's memory moves on to
// this iterate, and a reused matrix that contracts too little is rebuilt from now on.
bool ConvergedAfterCorrection(const Model& model, const Data& data, Integrator& integ,
                              const IterateMeasures& m, bool ggl, bool need_matrix, int it,
                              NewtonIteration& n) {
  const DynamicOptions& opt = integ.options;
  double increment = ScaledIncrementSize(model, data.increment.head(model.nv));
  if (ggl) increment = std::max(increment, ScaledIncrementSize(model, integ.ggl_y));
  // Converged: the residual passed at this iterate and its correction is below the
  // increment tolerance (the corrected state is only closer to the solution).
  const bool increment_ok = increment <= opt.increment_tolerance;
  bool converged = increment_ok && m.residual_ok;
  if (!converged && opt.convergence == ConvergenceTest::kEstimated && it > 0) {
    converged = ConvergedByEstimate(opt, m, increment, increment_ok, n.last_increment, n.last_res,
                                    n.last_con);
    if (converged) ++integ.estimated_convergences;
  }
  if (converged) return true;
  // A reused matrix that contracts too little: rebuild it, and from then on at every
  // iteration of this step (the step is too nonlinear for the simplified iteration).
  if (!need_matrix && increment > opt.refresh_ratio * n.last_increment) n.full_newton = true;
  n.last_increment = increment;
  n.last_res = m.res;
  n.last_con = m.con;
  return false;
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
  if (!Assemble(model, data, MassMatrixOptions(data.time))) return false;
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

}  // namespace

int TryStep(const Model& model, Data& data, Integrator& integ, double h, double t_end,
            bool left_limit, bool conservative, std::string* why) {
  const DynamicOptions& opt = integ.options;
  const StepConstants c = MakeStepConstants(integ.params, h);
  NewtonIteration n;
  n.full_newton = conservative || opt.newton_matrix == NewtonMatrix::kFull;
  n.switches_left = 2 * static_cast<int>(model.tendons.size());
  Predict(data, integ, c, integ.use_last_acceleration && !conservative);
  data.time = t_end;
  AssemblyOptions o = DynamicAssemblyOptions(
      opt, c, left_limit ? std::nextafter(t_end, -std::numeric_limits<double>::infinity()) : t_end);

  const bool ggl = opt.constraints == ConstraintFormulation::kGgl && model.nc > 0;
  if (ggl) PrepareGglStep(model, data, integ, h, conservative);
  for (int it = 0; it <= opt.max_iterations; ++it) {
    UpdateConfiguration(model, data, integ, h);
    bool need_matrix = n.full_newton || !n.factorized;
    // Once the last correction passed the increment test the step usually converges here:
    // assemble the residual alone, and the matrix only if the residual test then fails (the
    // residual does not depend on it).
    const bool may_converge = n.last_increment <= opt.increment_tolerance;
    const bool with_matrix = need_matrix && !may_converge && it < opt.max_iterations;
    bool assembled = AssembleIterate(model, data, opt, o, with_matrix, why);
    IterateMeasures m{};
    if (assembled) m = MeasureIterate(model, data, opt);
    // The contact line search: a correction after which the residual grew (or the state is
    // invalid) is halved, and the iteration goes on from there with full Newton.
    if (integ.line_search && it > 0) {
      double share = 0.5;
      for (int k = 0; k < kMaxLineSearchHalvings; ++k, share *= 0.5) {
        if (assembled && (m.residual_ok || !(m.res > n.last_res))) break;
        TakeBackCorrection(model, data, integ, c, share);
        ++integ.line_search_halvings;
        n.full_newton = need_matrix = true;
        UpdateConfiguration(model, data, integ, h);
        assembled = AssembleIterate(model, data, opt, o, with_matrix, why);
        if (assembled) m = MeasureIterate(model, data, opt);
      }
    }
    if (!assembled) return -1;
    if (ggl) MeasureVelocityConstraint(model, data, integ, h, o.time, m);
    if (it > 0 && m.residual_ok && may_converge) {
      if (ActiveSetChanged(model, data, o.time, n)) continue;
      Accept(data, integ, c);
      return it;
    }
    if (it == opt.max_iterations) break;
    if (need_matrix && !with_matrix && !AssembleIterate(model, data, opt, o, true, why)) return -1;
    if (!Correct(model, data, integ, c, need_matrix)) {
      if (why) *why = "the iteration matrix is singular";
      return -1;
    }
    if (need_matrix) n.factorized = true;
    if (ConvergedAfterCorrection(model, data, integ, m, ggl, need_matrix, it, n)) {
      UpdateConfiguration(model, data, integ, h);
      if (ActiveSetChanged(model, data, o.time, n)) continue;
      Accept(data, integ, c);
      return it + 1;
    }
  }
  if (why) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "Newton did not converge in %d iterations", opt.max_iterations);
    *why = buf;
  }
  return -1;
}

int TryStepWithRetry(const Model& model, Data& data, Integrator& integ, double h, double t_end,
                     bool left_limit, std::string* why) {
  const DynamicOptions& opt = integ.options;
  const bool conservative =
      opt.newton_matrix == NewtonMatrix::kFull && opt.predictor == Predictor::kZero;
  const double t0 = data.time;
  SaveStepStart(data, integ);
  int its = TryStep(model, data, integ, h, t_end, left_limit, false, why);
  if (its < 0 && !conservative) {
    // The simplified iteration or the predictor failed: retry the same step with full
    // Newton from the zero-acceleration start before halving.
    RestoreStepStart(data, integ, t0);
    ++integ.retries;
    its = TryStep(model, data, integ, h, t_end, left_limit, true, why);
  }
  return its;
}

void SaveStepStart(const Data& data, Integrator& integ) {
  integ.slack_start = data.tendon_slack;  // same size: no allocation
  SaveState(data, &integ.q_start);
  integ.v_start = data.v;
  integ.vdot_start = data.vdot;
  integ.a_start = integ.a;
  integ.lambda_start = data.lambda;
}

void RestoreStepStart(Data& data, Integrator& integ, double t) {
  RestoreState(integ.q_start, data);
  data.v = integ.v_start;
  data.vdot = integ.vdot_start;
  integ.a = integ.a_start;
  data.lambda = integ.lambda_start;
  data.tendon_slack = integ.slack_start;
  data.time = t;
}

void CountAcceptedStep(Integrator& integ, double h, int iterations) {
  integ.iterations += iterations;
  integ.max_iterations_in_step = std::max(integ.max_iterations_in_step, iterations);
  integ.min_h = std::min(integ.min_h, h);
  integ.max_h = std::max(integ.max_h, h);
  integ.sum_h += h;
  ++integ.accepted_substeps;
}

bool RestartAfterStep(const Model& model, Data& data, Integrator& integ, bool at_breakpoint,
                      bool* restarted, std::string* message) {
  const bool switched = data.tendon_slack != integ.slack_start;
  if (switched) ++integ.tendon_switches;
  *restarted = switched || at_breakpoint;
  if (!*restarted) return true;
  if (!CatchTendons(model, data, integ)) {
    *message = "the inelastic catch of a tendon failed (singular [M B^T; B 0])";
    return false;
  }
  return RestartDynamics(model, data, integ, message);
}

std::string InterruptedMessage(double t) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "step interrupted at t = %.9g s", t);
  return buf;
}

}  // namespace screwfem::generalized_alpha
