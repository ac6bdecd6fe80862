// Sensitivities of dynamic trajectories (solve/sensitivity.h, docs/inverse.md "Dynamic
// sensitivities"): the Lie-group generalized-alpha step differentiated at its converged
// solution, forward and discrete adjoint, through restarts at profile breakpoints.
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/joint.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/sensitivity.h"
#include "step_stages.h"

namespace screwfem {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The matrix data holds after an assembly (before factorisation), dense in global order.
MatrixXd DenseMatrix(const Model& m, const Data& d) {
  const int n = m.num_unknowns();
  MatrixXd A = MatrixXd::Zero(n, n);
  if (m.sparse_solver) {
    std::vector<int> global(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
      global[static_cast<std::size_t>(m.permutation[static_cast<std::size_t>(i)])] = i;
    d.sparse.ForEachEntry([&](int i, int j, double v) {
      A(global[static_cast<std::size_t>(i)], global[static_cast<std::size_t>(j)]) = v;
    });
    return A;
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int pi = m.permutation[static_cast<std::size_t>(i)];
      const int pj = m.permutation[static_cast<std::size_t>(j)];
      if (d.matrix.InBand(pi, pj)) A(i, j) = d.matrix.At(pi, pj);
    }
  return A;
}

// Whether the assembled K = dr/dq and C = dr/dv of the dynamic residual are its exact
// derivatives. The iteration matrix leaves out parts of them where Newton does not need them:
// option A's rod inertia (docs/numerics.md, "Rod inertia": dg/dq and part of dg/dv), the
// dependence of rod damping (section damping, Rayleigh a_K) on the configuration; contact and
// rigid bodies are not checked. Option B's inertia (constant M_e) and everything static are
// exact (tests/solve/dynamic_sensitivity_test.cpp checks both paths against differences of
// whole runs).
bool AssembledTangentIsExact(const Model& model) {
  if (!model.bodies.empty() || !model.obstacles.empty() || !model.contact_pairs.empty() ||
      !model.contact_rods.empty() || !model.contact_shapes.empty())
    return false;
  for (const Rod& rod : model.rods) {
    const Section& s = rod.section;
    if (s.damping.squaredNorm() > 0.0 || s.rayleigh_stiffness > 0.0) return false;
    if (model.rod_inertia == RodInertia::kExact && s.inertia.squaredNorm() > 0.0) return false;
  }
  return true;
}

// The derivatives of the dynamic residual (unscaled) at data's state, its equilibrium rows
// r = M vdot + f(q, v, t) + B^T lambda and its constraint rows phi(q, t) (held rows, ForEachHeldRow:
// lambda_r): K = dr/dq (right-trivialised), C = dr/dv, M = dr/dvdot, B = dphi/dq (nc x nv),
// Bt = dr/dlambda (nv x nc: B^T), H = the constraint rows' dlambda (the identity in held rows,
// zero elsewhere), and dR/dp of both row sets for every parameter ((nv + nc) x parameters;
// R(p + 1) - R(p): the residual is affine in each, as in statics).
struct Linearisation {
  MatrixXd K, C, M, B, Bt, H, Rp;
};

bool Linearise(const Model& model, Data& data, const std::vector<Parameter>& params,
               SensitivityWorkspace& ws, double time, Linearisation* out, std::string* why) {
  const int nv = model.nv, nc = model.nc, n = nv + nc;
  const bool by_differences = !AssembledTangentIsExact(model);
  AssemblyOptions o;
  o.time = time;
  o.dynamics = true;
  const auto matrix = [&](double cm, double cc, double ck, MatrixXd* A) {
    o.c_mass = cm;
    o.c_damping = cc;
    o.c_stiffness = ck;
    o.assemble_matrix = true;
    if (!Assemble(model, data, o)) return false;
    if (!data.coupling.empty()) {
      *why = "off-band couplings (pairs of moving shapes) are not supported";
      return false;
    }
    *A = DenseMatrix(model, data);
    return true;
  };
  MatrixXd AK, AC, AM;
  if (!matrix(0.0, 0.0, 1.0, &AK) || !matrix(0.0, 1.0, 0.0, &AC) || !matrix(1.0, 0.0, 0.0, &AM)) {
    if (why->empty()) *why = "the matrices could not be assembled";
    return false;
  }
  // The constraint blocks do not depend on the coefficients (Scatter::GradientMatrix).
  out->K = AK.topLeftCorner(nv, nv);
  out->C = AC.topLeftCorner(nv, nv);
  out->M = AM.topLeftCorner(nv, nv);
  out->B = AK.bottomLeftCorner(nc, nv);
  out->Bt = AK.topRightCorner(nv, nc);
  out->H = AK.bottomRightCorner(nc, nc);
  o.assemble_matrix = false;
  if (!Assemble(model, data, o)) {
    *why = "the residual could not be assembled";
    return false;
  }
  const VectorXd r0 = data.residual.head(n);
  if (by_differences) {
    // K and C by central differences of the residual, one pair of assemblies per unknown each
    // (AssembledTangentIsExact says when the assembled ones are not the derivatives). The
    // residual is quadratic in v (C: exact up to round-off); in q the truncation error is
    // O(e^2), about 1e-12 relative.
    State saved;
    SaveState(data, &saved);
    const VectorXd v0 = data.v;
    VectorXd dx = VectorXd::Zero(nv), rq(n), rv(nv);
    const double ev = std::max(1.0, v0.cwiseAbs().maxCoeff()) * 1e-3;
    for (int j = 0; j < nv; ++j) {
      const bool translation = j < model.nv_nodes && j % 6 < 3;
      const double e = 1e-6 * (translation ? model.length_scale : 1.0);
      for (int side = 0; side < 2; ++side) {
        dx(j) = side == 0 ? e : -e;
        Retract(model, data, dx);
        if (!Assemble(model, data, o)) {
          RestoreState(saved, data);
          *why = "the residual could not be assembled near the state";
          return false;
        }
        RestoreState(saved, data);
        if (side == 0) {
          rq = data.residual.head(n);
        } else {
          out->K.col(j) = (rq.head(nv) - data.residual.head(nv)) / (2.0 * e);
          out->B.col(j) = (rq.tail(nc) - data.residual.segment(nv, nc)) / (2.0 * e);
        }
        data.v(j) = v0(j) + (side == 0 ? ev : -ev);
        Assemble(model, data, o);
        data.v(j) = v0(j);
        if (side == 0)
          rv = data.residual.head(nv);
        else
          out->C.col(j) = (rv - data.residual.head(nv)) / (2.0 * ev);
      }
      dx(j) = 0.0;
    }
  }
  out->Rp.resize(n, static_cast<Eigen::Index>(params.size()));
  for (std::size_t j = 0; j < params.size(); ++j) {
    const Parameter& p = params[j];
    const double saved = p.kind == ParameterKind::kInput ? data.inputs(p.index) : 0.0;
    // Affine: R(p + 1) - R(p); else (R(p + e) - R(p - e)) / 2e (ParameterIsAffine).
    const bool affine = ParameterIsAffine(p);
    const double e = ParameterDifferenceStep(model, p);
    const Eigen::Index c = static_cast<Eigen::Index>(j);
    for (int side = 0; side < (affine ? 1 : 2); ++side) {
      OffsetParameter(ws.model, data, p, side == 0 ? e : -e);
      const bool ok = Assemble(ws.model, data, o);
      ResetParameter(ws.model, model, p);
      if (p.kind == ParameterKind::kInput) data.inputs(p.index) = saved;
      if (!ok) {
        *why = "the residual could not be assembled with a parameter perturbed";
        return false;
      }
      if (side == 0) out->Rp.col(c) = data.residual.head(n);
    }
    if (affine)
      out->Rp.col(c) -= r0;
    else
      out->Rp.col(c) = (out->Rp.col(c) - data.residual.head(n)) / (2.0 * e);
  }
  return true;
}

// One step n -> n+1 linearised at its converged solution, and the restart after it.
struct StepRecord {
  MatrixXd KB, C, Rp;               // [K; B], C and dR/dp of the step's residual at the new state
  MatrixXd T, Ad;                   // block diagonal: T(h dq) and Ad(exp(-h dq)) of the nodes
                                    // (and of joints whose coordinates retract by exp)
  Eigen::PartialPivLU<MatrixXd> S;  // [beta' M + gamma' C + K T, B^T; B T, H] (its transpose:
                                    // adjoint)
  bool restart = false;
  // The restart without multipliers: the consistent acceleration's M vdot = -r.
  MatrixXd K2, C2, Rp2;
  Eigen::PartialPivLU<MatrixXd> M2;
  // The restart with multipliers (catch and consistent start, RestartAfterStep): its Jacobian
  // d(v+, vdot+)/d(eta, v, p), 2 nv x (2 nv + parameters).
  MatrixXd J;
  MatrixXd G;  // the outputs' rows at t_{n+1} (over eta)
};

// The Jacobian of a restart with multipliers, d(v+, vdot+)/d(eta, v, p) (2 nv x (2 nv + np)),
// by central differences of the whole map at data's state: the inelastic catch of length-driven
// tendons and the consistent accelerations [M B^T; B 0] [vdot; lambda] = -[r; Bdot v + phi_tt]
// (`with_catch`: RestartAfterStep, else the start's RestartDynamics). Their derivatives hold
// second derivatives of the constraints (Bdot v, the catch's B(q)), which the assembly does
// not provide (docs/inverse.md, "Multipliers"). The map is smooth in q and v; in each
// parameter it is affine or (a mass factor) smooth. Data and the integrator are restored.
bool RestartJacobian(const Model& model, Data& data, Integrator& integ,
                     const std::vector<Parameter>& params, SensitivityWorkspace& ws,
                     bool with_catch, bool state_columns, MatrixXd* J, std::string* why) {
  const int nv = model.nv, np = static_cast<int>(params.size());
  State saved;
  SaveState(data, &saved);
  const VectorXd v0 = data.v, vdot0 = data.vdot, lambda0 = data.lambda, a0 = integ.a;
  const std::vector<char> slack0 = data.tendon_slack;
  const double t = data.time;
  const auto restore = [&] {
    RestoreState(saved, data);
    data.v = v0;
    data.vdot = vdot0;
    data.lambda = lambda0;
    integ.a = a0;
    data.tendon_slack = slack0;
    data.time = t;
  };
  const auto eval = [&](const Model& m, Eigen::Ref<VectorXd> col, double sign) {
    bool restarted = false;
    const bool ok = with_catch
                        ? generalized_alpha::RestartAfterStep(m, data, integ, true, &restarted, why)
                        : RestartDynamics(m, data, integ, why);
    if (ok) {
      col.head(nv) += sign * data.v;
      col.tail(nv) += sign * data.vdot;
    }
    restore();
    return ok;
  };
  J->setZero(2 * nv, 2 * nv + np);
  if (state_columns) {
    VectorXd dx = VectorXd::Zero(nv);
    const double ev = 1e-4 * std::max(1.0, v0.cwiseAbs().maxCoeff());
    for (int j = 0; j < nv; ++j) {
      const bool translation = j < model.nv_nodes && j % 6 < 3;
      const double e = 1e-5 * (translation ? model.length_scale : 1.0);
      for (int side = 0; side < 2; ++side) {
        const double sign = side == 0 ? 1.0 : -1.0;
        dx(j) = sign * e;
        Retract(model, data, dx);
        if (!eval(model, J->col(j), sign / (2.0 * e))) return false;
        data.v(j) = v0(j) + sign * ev;
        if (!eval(model, J->col(nv + j), sign / (2.0 * ev))) return false;
      }
      dx(j) = 0.0;
    }
  }
  for (int j = 0; j < np; ++j) {
    const Parameter& p = params[static_cast<std::size_t>(j)];
    const double e = ParameterIsAffine(p) ? 1e-4 : ParameterDifferenceStep(model, p);
    for (int side = 0; side < 2; ++side) {
      const double sign = side == 0 ? 1.0 : -1.0;
      const double saved_input = p.kind == ParameterKind::kInput ? data.inputs(p.index) : 0.0;
      OffsetParameter(ws.model, data, p, sign * e);
      const bool ok = eval(ws.model, J->col(2 * nv + j), sign / (2.0 * e));
      ResetParameter(ws.model, model, p);
      if (p.kind == ParameterKind::kInput) data.inputs(p.index) = saved_input;
      if (!ok) return false;
    }
  }
  return true;
}

// The state's derivative: configuration eta (right-trivialised), v, vdot and the auxiliary
// acceleration a, one column per parameter (forward) or the adjoint vectors (one column).
struct Tangent {
  MatrixXd eta, v, vdot, a;
};

// The rows of the outputs in eta (node twists in the node frames) at data's state.
MatrixXd OutputRows(const Model& m, const Data& d, const std::vector<SensitivityOutput>& outputs) {
  MatrixXd G = MatrixXd::Zero(static_cast<Eigen::Index>(outputs.size()), m.nv);
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const SensitivityOutput& o = outputs[k];
    const int dof = m.nodes[static_cast<std::size_t>(o.index)].dof;
    if (dof < 0) continue;
    // p = x + R o: dp = R (du + deta x o), as in statics.
    const Eigen::Index r = static_cast<Eigen::Index>(k);
    const Mat3& R = d.H[static_cast<std::size_t>(o.index)].R;
    const Vec3 row = R.row(o.component).transpose();
    G.block<1, 3>(r, dof) = row.transpose();
    G.block<1, 3>(r, dof + 3) = o.offset.cross(row).transpose();
  }
  return G;
}

VectorXd OutputValues(const Data& d, const std::vector<SensitivityOutput>& outputs) {
  VectorXd y(static_cast<Eigen::Index>(outputs.size()));
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const SensitivityOutput& o = outputs[k];
    y(static_cast<Eigen::Index>(k)) =
        d.H[static_cast<std::size_t>(o.index)].Act(o.offset)(o.component);
  }
  return y;
}

}  // namespace

DynamicSensitivity CalcDynamicSensitivity(const Model& model, Data& data,
                                          const std::vector<Parameter>& parameters,
                                          const std::vector<SensitivityOutput>& outputs,
                                          const Eigen::MatrixXd& weights, SensitivityMode mode,
                                          const DynamicSensitivityOptions& options) {
  const std::string owner = "CalcDynamicSensitivity";
  for (const Parameter& p : parameters) ValidateParameter(model, p, owner);
  for (const SensitivityOutput& o : outputs) {
    ValidateOutput(model, o, owner);
    if (o.kind != OutputKind::kPointPosition)
      throw InputError(owner + ": outputs must be point positions");
  }
  ValidateDynamicOptions(options.dynamics, owner + ".dynamics");
  if (!(options.step > 0.0) || !std::isfinite(options.step) || options.steps < 1)
    throw InputError(owner + ": step must be > 0 and steps >= 1");
  const int N = options.steps, no = static_cast<int>(outputs.size());
  const int np = static_cast<int>(parameters.size()), nv = model.nv, nc = model.nc;
  if (weights.size() > 0 && (weights.rows() != N + 1 || weights.cols() != no))
    throw InputError(owner + ": weights must be (steps + 1) x outputs");
  DynamicSensitivity out;
  // Stabilised index 2 (GGL, the default of models without rods) is not differentiated: its
  // step holds the start's gradient B(q_n) and a second multiplier (docs/inverse.md,
  // "Multipliers").
  const bool ggl =
      options.dynamics.constraints == ConstraintFormulation::kGgl ||
      (options.dynamics.constraints == ConstraintFormulation::kAuto && model.rods.empty());
  if (nc > 0 && ggl) {
    out.message =
        "constraints: ggl (stabilised index 2, the default of models without rods) is not "
        "differentiated; run with constraints: index3";
    return out;
  }
  if (model.contact.friction > 0.0 &&
      !(model.obstacles.empty() && model.contact_pairs.empty() && model.contact_rods.empty() &&
        model.contact_shapes.empty())) {
    out.message = "contact with friction (a history of the run) is not supported yet";
    return out;
  }
  MatrixXd W = weights;
  if (W.size() == 0) {
    W = MatrixXd::Zero(N + 1, no);
    W.row(N).setOnes();
  }

  DynamicOptions dyn = options.dynamics;
  dyn.perturbed_start = false;
  dyn.constraints = ConstraintFormulation::kIndex3;
  Integrator integ;
  std::string why;
  if (!InitializeDynamics(model, data, integ, dyn, &why)) {
    out.message = why;
    return out;
  }
  // The parameters' shapes' breakpoints are the run's too (the derivative's profile has
  // its kinks there).
  if (dyn.restart_at_breakpoints) {
    std::vector<double> bps = ProfileBreakpoints(model);
    for (const Parameter& p : parameters)
      for (double b : p.shape.Breakpoints()) bps.push_back(b);
    integ.breakpoints =
        SortedBreakpoints(bps, data.time, std::numeric_limits<double>::infinity(), 0.0);
  }
  const GeneralizedAlpha& ga = integ.params;
  const double h = options.step;
  const double beta_p = (1.0 - ga.alpha_m) / (h * h * ga.beta * (1.0 - ga.alpha_f));
  const double gamma_p = ga.gamma / (h * ga.beta);
  const double c_a = (1.0 - ga.alpha_f) / (1.0 - ga.alpha_m);
  SensitivityWorkspace ws = MakeSensitivityWorkspace(model);

  // The consistent start: M vdot_0 = -r(q_0, v_0, 0, t_0), a_0 = vdot_0.
  Linearisation lin;
  if (!Linearise(model, data, parameters, ws, data.time, &lin, &why)) {
    out.message = "at the start: " + why;
    return out;
  }
  // Without multipliers M vdot_0 = -r (M0, Rp0); with them the start's consistent
  // accelerations by RestartJacobian (its parameter columns: q_0 and v_0 do not depend on p).
  const Eigen::PartialPivLU<MatrixXd> M0(
      mode == SensitivityMode::kForward ? MatrixXd(lin.M) : MatrixXd(lin.M.transpose()));
  const MatrixXd Rp0 = lin.Rp;
  MatrixXd J0;
  if (nc > 0) {
    if (!RestartJacobian(model, data, integ, parameters, ws, false, false, &J0, &why)) {
      out.message = "at the start: " + why;
      return out;
    }
    J0 = MatrixXd(J0.bottomRightCorner(nv, np));
  }
  out.values.resize(N + 1, no);
  out.values.row(0) = OutputValues(data, outputs).transpose();
  const MatrixXd G0 = OutputRows(model, data, outputs);

  std::vector<StepRecord> records(static_cast<std::size_t>(N));
  const double t0 = data.time;
  const double snap = 1e-9 * h;
  for (int n = 0; n < N; ++n) {
    StepRecord& rec = records[static_cast<std::size_t>(n)];
    const double ts = data.time;
    double t_end = t0 + (n + 1) * h;
    const double bp = NextBreakpoint(integ.breakpoints, ts, snap);
    if (bp < t_end - snap) {
      out.message = FormatNumbers(
          "the breakpoint at t = %.9g s lies inside a step: choose a step size whose step ends "
          "fall on the breakpoints",
          bp);
      return out;
    }
    const bool at_bp = EndsOnBreakpoint(t_end, bp, snap);
    if (at_bp) t_end = bp;
    const double hs = t_end - ts;
    generalized_alpha::SaveStepStart(data, integ);
    const int its = generalized_alpha::TryStep(model, data, integ, hs, t_end, at_bp, true, &why);
    if (its < 0) {
      out.message = FormatNumbers("step %g failed: ", n) + why;
      return out;
    }
    if (data.tendon_slack != integ.slack_start) {
      out.message = FormatNumbers(
          "a length-driven tendon went slack or taut in the step to t = %.9g s (the trajectory "
          "is not differentiable there)",
          t_end);
      return out;
    }
    UpdateBranchReferences(model, data);
    AcceptContactHistory(model, data, true);
    // The step's linearisation at its converged state (the profiles' left limits when it ends
    // on a breakpoint, as the step saw them).
    const double t_assembly =
        at_bp ? std::nextafter(t_end, -std::numeric_limits<double>::infinity()) : t_end;
    if (!Linearise(model, data, parameters, ws, t_assembly, &lin, &why)) {
      out.message = FormatNumbers("step %g: ", n) + why;
      return out;
    }
    rec.T = MatrixXd::Identity(nv, nv);
    rec.Ad = MatrixXd::Identity(nv, nv);
    for (const Node& node : model.nodes) {
      if (node.dof < 0) continue;
      const Vec6 x = hs * integ.dq.segment<6>(node.dof);
      rec.T.block<6, 6>(node.dof, node.dof) = TSE3(x);
      rec.Ad.block<6, 6>(node.dof, node.dof) = Ad(ExpSE3(-x));
    }
    // Joints whose frame H_J retracts by the exponential (spherical, planar, free): A_J^T T A_J
    // and A_J^T Ad A_J on their k coordinates (a subgroup: Ad maps its algebra into itself).
    for (const Joint& j : model.joints) {
      const int k = j.k();
      if (k == 0 || JointHasGlobalCoordinates(j.type)) continue;
      const Vec6 x = j.basis * (hs * integ.dq.segment(j.coord, k));
      rec.T.block(j.coord, j.coord, k, k) = j.basis.transpose() * TSE3(x) * j.basis;
      rec.Ad.block(j.coord, j.coord, k, k) = j.basis.transpose() * Ad(ExpSE3(-x)) * j.basis;
    }
    if (std::abs(hs - h) > 1e-12 * h) {
      out.message = "a step of another size than the others (the run's end or a breakpoint)";
      return out;
    }
    rec.KB.resize(nv + nc, nv);
    rec.KB << lin.K, lin.B;
    rec.C = lin.C;
    rec.Rp = lin.Rp;
    MatrixXd S(nv + nc, nv + nc);
    S << beta_p * lin.M + gamma_p * lin.C + lin.K * rec.T, lin.Bt, lin.B * rec.T, lin.H;
    if (mode == SensitivityMode::kForward)
      rec.S.compute(S);
    else
      rec.S.compute(S.transpose());
    // The restart at a breakpoint: consistent vdot and a = vdot from the right limits.
    rec.restart = at_bp;
    if (at_bp && nc > 0) {
      // The catch of length-driven tendons and the consistent start, as Step restarts
      // (RestartAfterStep), differentiated as one map.
      if (!RestartJacobian(model, data, integ, parameters, ws, true, true, &rec.J, &why)) {
        out.message = "at a restart: " + why;
        return out;
      }
      bool restarted = false;
      if (!generalized_alpha::RestartAfterStep(model, data, integ, true, &restarted, &why)) {
        out.message = why;
        return out;
      }
      ++out.restarts;
    } else if (at_bp) {
      if (!RestartDynamics(model, data, integ, &why)) {
        out.message = why;
        return out;
      }
      ++out.restarts;
      if (!Linearise(model, data, parameters, ws, data.time, &lin, &why)) {
        out.message = "at a restart: " + why;
        return out;
      }
      rec.K2 = lin.K;
      rec.C2 = lin.C;
      rec.Rp2 = lin.Rp;
      if (mode == SensitivityMode::kForward)
        rec.M2.compute(lin.M);
      else
        rec.M2.compute(lin.M.transpose());
    }
    out.values.row(n + 1) = OutputValues(data, outputs).transpose();
    rec.G = OutputRows(model, data, outputs);
  }
  out.objective = (W.array() * out.values.array()).sum();

  const GeneralizedAlpha p = ga;
  if (mode == SensitivityMode::kForward) {
    out.outputs.resize(static_cast<Eigen::Index>(N + 1) * no, np);
    Tangent z{MatrixXd::Zero(nv, np), MatrixXd::Zero(nv, np),
              nc > 0 ? J0 : MatrixXd(-M0.solve(Rp0)), MatrixXd()};
    z.a = z.vdot;
    out.outputs.topRows(no) = G0 * z.eta;
    for (int n = 0; n < N; ++n) {
      const StepRecord& rec = records[static_cast<std::size_t>(n)];
      const MatrixXd a_base = (p.alpha_f * z.vdot - p.alpha_m * z.a) / (1.0 - p.alpha_m);
      const MatrixXd dq0 = z.v + h * (0.5 - p.beta) * z.a + h * p.beta * a_base;
      const MatrixXd v0 = z.v + h * (1.0 - p.gamma) * z.a + h * p.gamma * a_base;
      const MatrixXd eta0 = rec.Ad * z.eta + h * rec.T * dq0;
      MatrixXd rhs = rec.KB * eta0 + rec.Rp;
      rhs.topRows(nv) += rec.C * v0;
      const MatrixXd dx = -rec.S.solve(rhs).topRows(nv);
      z.eta = eta0 + rec.T * dx;
      z.v = v0 + gamma_p * dx;
      z.vdot = beta_p * dx;
      z.a = a_base + c_a * beta_p * dx;
      if (rec.restart && nc > 0) {
        const MatrixXd x =
            rec.J.leftCols(nv) * z.eta + rec.J.middleCols(nv, nv) * z.v + rec.J.rightCols(np);
        z.v = x.topRows(nv);
        z.vdot = x.bottomRows(nv);
        z.a = z.vdot;
      } else if (rec.restart) {
        z.vdot = -rec.M2.solve(rec.K2 * z.eta + rec.C2 * z.v + rec.Rp2);
        z.a = z.vdot;
      }
      out.outputs.middleRows(static_cast<Eigen::Index>(n + 1) * no, no) = rec.G * z.eta;
    }
    out.gradient = VectorXd::Zero(np);
    for (int n = 0; n <= N; ++n)
      out.gradient += out.outputs.middleRows(static_cast<Eigen::Index>(n) * no, no).transpose() *
                      W.row(n).transpose();
  } else {
    // The discrete adjoint: the forward recursion's operations transposed in reverse order.
    VectorXd eta = records.back().G.transpose() * W.row(N).transpose();
    VectorXd v = VectorXd::Zero(nv), vdot = VectorXd::Zero(nv), a = VectorXd::Zero(nv);
    VectorXd grad = VectorXd::Zero(np);
    for (int n = N - 1; n >= 0; --n) {
      const StepRecord& rec = records[static_cast<std::size_t>(n)];
      if (rec.restart && nc > 0) {
        VectorXd w(2 * nv);
        w << v, vdot + a;
        eta += rec.J.leftCols(nv).transpose() * w;
        v = rec.J.middleCols(nv, nv).transpose() * w;
        grad += rec.J.rightCols(np).transpose() * w;
        vdot.setZero();
        a.setZero();
      } else if (rec.restart) {
        const VectorXd r = -rec.M2.solve(vdot + a);
        eta += rec.K2.transpose() * r;
        v += rec.C2.transpose() * r;
        grad += rec.Rp2.transpose() * r;
        vdot.setZero();
        a.setZero();
      }
      const VectorXd dx = rec.T.transpose() * eta + gamma_p * v + beta_p * vdot + c_a * beta_p * a;
      VectorXd eta0 = eta, v0 = v;
      VectorXd a_base = a;
      VectorXd dxl = VectorXd::Zero(nv + nc);
      dxl.head(nv) = dx;
      const VectorXd r = -rec.S.solve(dxl);
      eta0 += rec.KB.transpose() * r;
      v0 += rec.C.transpose() * r.head(nv);
      grad += rec.Rp.transpose() * r;
      eta = rec.Ad.transpose() * eta0;
      const VectorXd dq0 = h * rec.T.transpose() * eta0;
      v = v0 + dq0;
      a = h * (1.0 - p.gamma) * v0 + h * (0.5 - p.beta) * dq0;
      a_base += h * p.gamma * v0 + h * p.beta * dq0;
      vdot = (p.alpha_f / (1.0 - p.alpha_m)) * a_base;
      a -= (p.alpha_m / (1.0 - p.alpha_m)) * a_base;
      const MatrixXd& G = n > 0 ? records[static_cast<std::size_t>(n - 1)].G : G0;
      eta += G.transpose() * W.row(n).transpose();
    }
    // The start: vdot_0 = a_0 = -M^-1 r_p (q_0, v_0 independent of the parameters).
    if (nc > 0) {
      grad += J0.transpose() * (vdot + a);
    } else {
      const VectorXd r = -M0.solve(vdot + a);
      grad += Rp0.transpose() * r;
    }
    out.gradient = grad;
  }
  if (!out.gradient.allFinite() ||
      (mode == SensitivityMode::kForward && !out.outputs.allFinite())) {
    out.message = "the sensitivities are not finite (a singular step matrix)";
    return out;
  }
  out.ok = true;
  return out;
}

}  // namespace screwfem
