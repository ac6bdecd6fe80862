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

// The derivatives of the dynamic residual r = M vdot + f(q, v, t) (unscaled) at data's state:
// K = dr/dq (right-trivialised), C = dr/dv, M = dr/dvdot, and dr/dp for every parameter
// (r(p + 1) - r(p): the residual is affine in each, as in statics).
struct Linearisation {
  MatrixXd K, C, M, Rp;
};

bool Linearise(const Model& model, Data& data, const std::vector<Parameter>& params,
               SensitivityWorkspace& ws, double time, Linearisation* out, std::string* why) {
  const int nv = model.nv;
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
    *A = DenseMatrix(model, data).topLeftCorner(nv, nv);
    return true;
  };
  if (!matrix(0.0, 0.0, 1.0, &out->K) || !matrix(0.0, 1.0, 0.0, &out->C) ||
      !matrix(1.0, 0.0, 0.0, &out->M)) {
    if (why->empty()) *why = "the matrices could not be assembled";
    return false;
  }
  o.assemble_matrix = false;
  if (!Assemble(model, data, o)) {
    *why = "the residual could not be assembled";
    return false;
  }
  const VectorXd r0 = data.residual.head(nv);
  if (by_differences) {
    // K and C by central differences of the residual, one pair of assemblies per unknown each
    // (AssembledTangentIsExact says when the assembled ones are not the derivatives). The
    // residual is quadratic in v (C: exact up to round-off); in q the truncation error is
    // O(e^2), about 1e-12 relative.
    State saved;
    SaveState(data, &saved);
    const VectorXd v0 = data.v;
    VectorXd dx = VectorXd::Zero(nv), rq(nv), rv(nv);
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
        if (side == 0)
          rq = data.residual.head(nv);
        else
          out->K.col(j) = (rq - data.residual.head(nv)) / (2.0 * e);
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
  out->Rp.resize(nv, static_cast<Eigen::Index>(params.size()));
  for (std::size_t j = 0; j < params.size(); ++j) {
    const Parameter& p = params[j];
    const double saved = p.kind == ParameterKind::kInput ? data.inputs(p.index) : 0.0;
    OffsetParameter(ws.model, data, p, 1.0);
    const bool ok = Assemble(ws.model, data, o);
    ResetParameter(ws.model, model, p);
    if (p.kind == ParameterKind::kInput) data.inputs(p.index) = saved;
    if (!ok) {
      *why = "the residual could not be assembled with a parameter perturbed";
      return false;
    }
    out->Rp.col(static_cast<Eigen::Index>(j)) = data.residual.head(nv) - r0;
  }
  return true;
}

// One step n -> n+1 linearised at its converged solution, and the restart after it.
struct StepRecord {
  MatrixXd K, C, Rp;                // of the step's residual at the new state
  MatrixXd T, Ad;                   // block diagonal: T(h dq) and Ad(exp(-h dq)) of the nodes
  Eigen::PartialPivLU<MatrixXd> S;  // beta' M + gamma' C + K T (its transpose: adjoint)
  bool restart = false;
  MatrixXd K2, C2, Rp2;  // of the restart's consistent acceleration
  Eigen::PartialPivLU<MatrixXd> M2;
  MatrixXd G;  // the outputs' rows at t_{n+1} (over eta)
};

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
  const int np = static_cast<int>(parameters.size()), nv = model.nv;
  if (weights.size() > 0 && (weights.rows() != N + 1 || weights.cols() != no))
    throw InputError(owner + ": weights must be (steps + 1) x outputs");
  DynamicSensitivity out;
  if (model.nc > 0) {
    out.message = "models with multipliers (joints, length-driven tendons) are not supported yet";
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
  const Eigen::PartialPivLU<MatrixXd> M0(
      mode == SensitivityMode::kForward ? MatrixXd(lin.M) : MatrixXd(lin.M.transpose()));
  const MatrixXd Rp0 = lin.Rp;
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
    if (std::abs(hs - h) > 1e-12 * h) {
      out.message = "a step of another size than the others (the run's end or a breakpoint)";
      return out;
    }
    rec.K = lin.K;
    rec.C = lin.C;
    rec.Rp = lin.Rp;
    const MatrixXd S = beta_p * lin.M + gamma_p * lin.C + lin.K * rec.T;
    if (mode == SensitivityMode::kForward)
      rec.S.compute(S);
    else
      rec.S.compute(S.transpose());
    // The restart at a breakpoint: consistent vdot and a = vdot from the right limits.
    rec.restart = at_bp;
    if (at_bp) {
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
    Tangent z{MatrixXd::Zero(nv, np), MatrixXd::Zero(nv, np), -M0.solve(Rp0), MatrixXd()};
    z.a = z.vdot;
    out.outputs.topRows(no) = G0 * z.eta;
    for (int n = 0; n < N; ++n) {
      const StepRecord& rec = records[static_cast<std::size_t>(n)];
      const MatrixXd a_base = (p.alpha_f * z.vdot - p.alpha_m * z.a) / (1.0 - p.alpha_m);
      const MatrixXd dq0 = z.v + h * (0.5 - p.beta) * z.a + h * p.beta * a_base;
      const MatrixXd v0 = z.v + h * (1.0 - p.gamma) * z.a + h * p.gamma * a_base;
      const MatrixXd eta0 = rec.Ad * z.eta + h * rec.T * dq0;
      const MatrixXd dx = -rec.S.solve(rec.K * eta0 + rec.C * v0 + rec.Rp);
      z.eta = eta0 + rec.T * dx;
      z.v = v0 + gamma_p * dx;
      z.vdot = beta_p * dx;
      z.a = a_base + c_a * beta_p * dx;
      if (rec.restart) {
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
      if (rec.restart) {
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
      const VectorXd r = -rec.S.solve(dx);
      eta0 += rec.K.transpose() * r;
      v0 += rec.C.transpose() * r;
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
    const VectorXd r = -M0.solve(vdot + a);
    grad += Rp0.transpose() * r;
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
