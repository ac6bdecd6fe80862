// Sensitivities of static equilibria by the implicit function theorem (solve/sensitivity.h,
// docs/inverse.md).
#include "screwfem/solve/sensitivity.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "exact_tangent.h"
#include "reequilibrate.h"
#include "screwfem/assemble/assemble.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/common.h"

namespace screwfem {

namespace {

std::string ParameterLabel(const Parameter& p) {
  return std::string(NameOf(p.kind)) + " " + std::to_string(p.index) + " (component " +
         std::to_string(p.component) + ")";
}

template <class V>
bool InRange(int i, const V& v) {
  return i >= 0 && i < static_cast<int>(v.size());
}

ProfileTerm ConstantTerm(double value) {
  ProfileTerm t;
  t.kind = ProfileTerm::Kind::kConstant;
  t.scale = value;
  return t;
}

// Adds value * shape (the constant 1 when it has no terms) to a profile.
void AddShaped(Profile& profile, const Profile& shape, double value) {
  if (shape.terms().empty()) {
    profile.Add(ConstantTerm(value));
    return;
  }
  for (ProfileTerm t : shape.terms()) {
    t.scale *= value;
    profile.Add(t);
  }
}

}  // namespace

SensitivityWorkspace MakeSensitivityWorkspace(const Model& model) {
  SensitivityWorkspace ws{model, {}, {}, {}};
  const int n = model.num_unknowns();
  ws.r0.resize(n);
  ws.rhs.resize(n);
  return ws;
}

void ValidateParameter(const Model& m, const Parameter& p, const std::string& owner) {
  const auto fail = [&](const std::string& what) {
    throw InputError(owner + ": parameter " + ParameterLabel(p) + ": " + what);
  };
  const bool profiled = p.kind == ParameterKind::kTendonTension ||
                        p.kind == ParameterKind::kTendonLength ||
                        p.kind == ParameterKind::kJointDrive || p.kind == ParameterKind::kActuator;
  if (!p.shape.terms().empty()) {
    if (!profiled)
      fail("only tendon tensions and lengths, joint drives and actuators take a shape");
    try {
      p.shape.Validate("shape", static_cast<int>(m.inputs.size()));
    } catch (const InputError& e) {
      fail(e.what());
    }
  }
  switch (p.kind) {
    case ParameterKind::kTendonTension:
      if (!InRange(p.index, m.tendons)) fail("no such tendon");
      if (m.tendons[static_cast<std::size_t>(p.index)].drive != TendonDrive::kTension)
        fail("the tendon is length-driven (its tension is a multiplier, an output)");
      return;
    case ParameterKind::kPointLoad:
      if (!InRange(p.index, m.point_loads)) fail("no such point load");
      if (p.component < 0 || p.component > 5) fail("component must lie in [0, 5]");
      return;
    case ParameterKind::kJointDrive:
      if (!InRange(p.index, m.joints)) fail("no such joint");
      if (m.joints[static_cast<std::size_t>(p.index)].drive == DriveKind::kNone)
        fail("the joint has no drive");
      return;
    case ParameterKind::kRodStiffness:
      if (!InRange(p.index, m.rods)) fail("no such rod");
      if (p.component < -1 || p.component > 5) fail("component must be -1 (all) or in [0, 5]");
      return;
    case ParameterKind::kRodRestStrain:
      if (!InRange(p.index, m.rods)) fail("no such rod");
      if (p.component < 0 || p.component > 5) fail("component must lie in [0, 5]");
      return;
    case ParameterKind::kInput:
      if (!InRange(p.index, m.inputs)) fail("no such input");
      return;
    case ParameterKind::kActuator:
      if (!InRange(p.index, m.actuators)) fail("no such actuator");
      return;
    case ParameterKind::kRodMass:
      if (!InRange(p.index, m.rods)) fail("no such rod");
      return;
    case ParameterKind::kTendonLength:
      if (!InRange(p.index, m.tendons)) fail("no such tendon");
      if (m.tendons[static_cast<std::size_t>(p.index)].drive != TendonDrive::kLength)
        fail("the tendon is tension-driven (it has no length profile)");
      return;
    case ParameterKind::kTendonOffset:
      if (!InRange(p.index, m.tendons)) fail("no such tendon");
      if (p.component < 0 || p.component > 2) fail("component must lie in [0, 2]");
      return;
  }
  fail("unknown kind");
}

void ValidateOutput(const Model& m, const SensitivityOutput& o, const std::string& owner) {
  const auto fail = [&](const std::string& what) {
    throw InputError(owner + ": output " + std::string(NameOf(o.kind)) + " " +
                     std::to_string(o.index) + ": " + what);
  };
  switch (o.kind) {
    case OutputKind::kPointPosition:
    case OutputKind::kNodeRotation:
      if (!InRange(o.index, m.nodes)) fail("no such node");
      if (o.component < 0 || o.component > 2) fail("component must lie in [0, 2]");
      if (!o.offset.allFinite()) fail("offset must be finite");
      return;
    case OutputKind::kJointCoordinate:
      if (!InRange(o.index, m.joints)) fail("no such joint");
      if (o.component < 0 || o.component >= m.joints[static_cast<std::size_t>(o.index)].k())
        fail("the joint has no such coordinate");
      return;
    case OutputKind::kMultiplier:
      if (o.index < 0 || o.index >= m.nc) fail("no such multiplier row");
      return;
  }
  fail("unknown kind");
}

void OffsetParameter(Model& m, Data& data, const Parameter& p, double delta) {
  const std::size_t i = static_cast<std::size_t>(p.index);
  switch (p.kind) {
    case ParameterKind::kTendonTension:
      AddShaped(m.tendons[i].tension, p.shape, delta);
      return;
    case ParameterKind::kPointLoad:
      if (p.component < 3)
        m.point_loads[i].force(p.component) += delta;
      else
        m.point_loads[i].moment(p.component - 3) += delta;
      return;
    case ParameterKind::kJointDrive:
      AddShaped(m.joints[i].drive_profile, p.shape, delta);
      return;
    case ParameterKind::kRodStiffness:
      if (p.component < 0)
        m.rods[i].section.stiffness *= 1.0 + delta;
      else
        m.rods[i].section.stiffness(p.component) *= 1.0 + delta;
      return;
    case ParameterKind::kRodRestStrain: {
      const Rod& rod = m.rods[i];
      for (int e = rod.first_element; e < rod.first_element + rod.num_elements; ++e) {
        RodElement& el = m.elements[static_cast<std::size_t>(e)];
        el.d0(p.component) += delta * el.length;
      }
      return;
    }
    case ParameterKind::kInput:
      data.inputs(p.index) += delta;
      return;
    case ParameterKind::kActuator:
      AddShaped(m.actuators[i].profile, p.shape, delta);
      return;
    case ParameterKind::kRodMass:
      m.rods[i].section.inertia *= 1.0 + delta;
      return;
    case ParameterKind::kTendonLength:
      AddShaped(m.tendons[i].length, p.shape, delta);
      return;
    case ParameterKind::kTendonOffset:
      // The eyelets on nodes (not world points on the ground) and the segments' copies of them.
      for (BodyPoint& e : m.tendons[i].eyelets)
        if (e.node != kGround) e.offset(p.component) += delta;
      for (TendonSegment& s : m.tendon_segments) {
        if (s.tendon != p.index) continue;
        if (s.a.node != kGround) s.a.offset(p.component) += delta;
        if (s.b.node != kGround) s.b.offset(p.component) += delta;
      }
      return;
  }
}

void ResetParameter(Model& m, const Model& original, const Parameter& p) {
  const std::size_t i = static_cast<std::size_t>(p.index);
  switch (p.kind) {
    case ParameterKind::kTendonTension:
      m.tendons[i].tension = original.tendons[i].tension;
      return;
    case ParameterKind::kPointLoad:
      m.point_loads[i] = original.point_loads[i];
      return;
    case ParameterKind::kJointDrive:
      m.joints[i].drive_profile = original.joints[i].drive_profile;
      return;
    case ParameterKind::kRodStiffness:
      m.rods[i].section = original.rods[i].section;
      return;
    case ParameterKind::kRodRestStrain: {
      const Rod& rod = original.rods[i];
      for (int e = rod.first_element; e < rod.first_element + rod.num_elements; ++e)
        m.elements[static_cast<std::size_t>(e)].d0 =
            original.elements[static_cast<std::size_t>(e)].d0;
      return;
    }
    case ParameterKind::kInput:
      return;
    case ParameterKind::kActuator:
      m.actuators[i].profile = original.actuators[i].profile;
      return;
    case ParameterKind::kRodMass:
      m.rods[i].section = original.rods[i].section;
      return;
    case ParameterKind::kTendonLength:
      m.tendons[i].length = original.tendons[i].length;
      return;
    case ParameterKind::kTendonOffset:
      m.tendons[i].eyelets = original.tendons[i].eyelets;
      for (std::size_t k = 0; k < m.tendon_segments.size(); ++k)
        if (m.tendon_segments[k].tendon == p.index)
          m.tendon_segments[k] = original.tendon_segments[k];
      return;
  }
}

bool ParameterIsAffine(const Parameter& p) { return p.kind != ParameterKind::kTendonOffset; }

double ParameterDifferenceStep(const Model& model, const Parameter& p) {
  return ParameterIsAffine(p) ? 1.0 : 1e-6 * model.length_scale;
}

namespace {

// The row c of an output in the unknowns' space (nv node twists and joint coordinates, then
// nc scaled multipliers mu, lambda = k mu): d(output) = c^T dx.
void OutputRow(const Model& m, const Data& d, const SensitivityOutput& o, double k_scale,
               Eigen::Ref<Eigen::VectorXd> c) {
  c.setZero();
  switch (o.kind) {
    case OutputKind::kPointPosition: {
      const int dof = m.nodes[static_cast<std::size_t>(o.index)].dof;
      if (dof < 0) return;
      // p = x + R o: dp = R (du + dw x o) = R du - R [o]x dw.
      const Mat3& R = d.H[static_cast<std::size_t>(o.index)].R;
      const Eigen::RowVector3d r = R.row(o.component);
      c.segment<3>(dof) = r.transpose();
      c.segment<3>(dof + 3) = o.offset.cross(r.transpose());  // -(r [o]x)^T = o x r
      return;
    }
    case OutputKind::kNodeRotation: {
      const int dof = m.nodes[static_cast<std::size_t>(o.index)].dof;
      if (dof >= 0) c(dof + 3 + o.component) = 1.0;
      return;
    }
    case OutputKind::kJointCoordinate:
      c(m.joints[static_cast<std::size_t>(o.index)].coord + o.component) = 1.0;
      return;
    case OutputKind::kMultiplier:
      c(m.nv + o.index) = k_scale;
      return;
  }
}

// Solves K^T w = c (global order in and out, through the permutation) with the factorisation
// data holds.
void SolveTransposedSystem(const Model& m, Data& d, const Eigen::VectorXd& c, Eigen::VectorXd* w) {
  const int n = m.num_unknowns();
  for (int i = 0; i < n; ++i) d.rhs(m.permutation[static_cast<std::size_t>(i)]) = c(i);
  if (m.sparse_solver)
    d.sparse.SolveTransposed(d.rhs);
  else
    d.matrix.SolveTransposed(d.rhs);
  for (int i = 0; i < n; ++i) (*w)(i) = d.rhs(m.permutation[static_cast<std::size_t>(i)]);
}

// dR/dp for every parameter into ws.dr (columns): R(p + 1) - R(p) with R(p) = ws.r0, exact
// for the affine dependence (docs/inverse.md, "The derivative of the residual"); one residual
// assembly per parameter. A tendon's tension is clamped at 0 (a tendon cannot push): the
// difference is then the right derivative at T = 0. False (with the cause) if an assembly
// failed.
bool ResidualDerivatives(const Model& model, Data& data, const std::vector<Parameter>& params,
                         AssemblyOptions opt, SensitivityWorkspace& ws, std::string* why) {
  opt.assemble_matrix = false;
  const int n = model.num_unknowns();
  ws.dr.resize(n, static_cast<Eigen::Index>(params.size()));
  for (std::size_t j = 0; j < params.size(); ++j) {
    const Parameter& p = params[j];
    const double saved_input = p.kind == ParameterKind::kInput ? data.inputs(p.index) : 0.0;
    // Affine: R(p + 1) - R(p); else (R(p + e) - R(p - e)) / 2e.
    const bool affine = ParameterIsAffine(p);
    const double e = ParameterDifferenceStep(model, p);
    bool ok = true;
    for (int side = 0; side < (affine ? 1 : 2) && ok; ++side) {
      OffsetParameter(ws.model, data, p, side == 0 ? e : -e);
      ok = Assemble(ws.model, data, opt);
      ResetParameter(ws.model, model, p);
      if (p.kind == ParameterKind::kInput) data.inputs(p.index) = saved_input;
      if (side == 0) ws.dr.col(static_cast<Eigen::Index>(j)) = data.residual;
    }
    if (!ok) {
      *why = "the residual could not be assembled with parameter " + ParameterLabel(p) +
             " perturbed (an element past its rotation limit)";
      return false;
    }
    const Eigen::Index c = static_cast<Eigen::Index>(j);
    if (affine)
      ws.dr.col(c) -= ws.r0;
    else
      ws.dr.col(c) = (ws.dr.col(c) - data.residual) / (2.0 * e);
  }
  return true;
}

}  // namespace

StaticSensitivity CalcStaticSensitivity(const Model& model, Data& data,
                                        const std::vector<Parameter>& parameters,
                                        const std::vector<SensitivityOutput>& outputs,
                                        SensitivityMode mode, const StaticOptions& options,
                                        SensitivityWorkspace* workspace) {
  for (const Parameter& p : parameters) ValidateParameter(model, p, "CalcStaticSensitivity");
  for (const SensitivityOutput& o : outputs) ValidateOutput(model, o, "CalcStaticSensitivity");
  SensitivityWorkspace local;
  if (!workspace) local = MakeSensitivityWorkspace(model);
  SensitivityWorkspace& ws = workspace ? *workspace : local;
  // The workspace's copy carries the model's current parameter values.
  for (const Parameter& p : parameters) ResetParameter(ws.model, model, p);
  StaticSensitivity out;
  if (!options.constraint_force_tangent) {
    out.message =
        "options.constraint_force_tangent is false: the derivatives need the exact tangent";
    return out;
  }
  const int n = model.num_unknowns(), np = static_cast<int>(parameters.size());
  const int no = static_cast<int>(outputs.size());
  const double k_scale = StaticConstraintScale(model);
  AssemblyOptions opt;
  opt.time = options.time;
  opt.load_factor = options.end_load_factor;
  opt.s_constraints = opt.s_multipliers = k_scale;
  ExactTangentPattern exact(model, data, options.constraint_force_tangent, &opt);
  if (!Assemble(model, data, opt)) {
    out.message = "the tangent could not be assembled at this state";
    return out;
  }
  ws.r0 = data.residual;
  if (!SolveAssembledSystem(model, data)) {
    out.message = "the tangent matrix is singular (a mechanism, or unsupported free motion)";
    return out;
  }
  out.equilibrium_error = ScaledIncrementSize(model, data.increment.head(model.nv));
  if (!ResidualDerivatives(model, data, parameters, opt, ws, &out.message)) return out;
  data.residual = ws.r0;
  Eigen::MatrixXd C(no, n);
  for (int o = 0; o < no; ++o) {
    OutputRow(model, data, outputs[static_cast<std::size_t>(o)], k_scale, ws.rhs);
    C.row(o) = ws.rhs.transpose();
  }
  out.outputs.resize(no, np);
  if (mode == SensitivityMode::kForward) {
    out.dx.resize(model.nv, np);
    out.dlambda.resize(model.nc, np);
    for (int j = 0; j < np; ++j) {
      data.residual = ws.dr.col(j);  // the solve gives -K^-1 dR/dp
      SolveFactorizedSystem(model, data);
      out.dx.col(j) = data.increment.head(model.nv);
      out.dlambda.col(j) = k_scale * data.increment.tail(model.nc);
      out.outputs.col(j) = C * data.increment;
    }
    data.residual = ws.r0;
  } else {
    if (!data.coupling.empty()) {
      out.message =
          "adjoint sensitivities need a matrix without off-band coupling (pairs of moving "
          "shapes outside the band); use the forward mode";
      return out;
    }
    for (int o = 0; o < no; ++o) {
      const Eigen::VectorXd c = C.row(o).transpose();
      SolveTransposedSystem(model, data, c, &ws.rhs);
      out.outputs.row(o) = -(ws.rhs.transpose() * ws.dr);
    }
  }
  if (!out.outputs.allFinite()) {
    out.message = "the sensitivities are not finite (a nearly singular tangent)";
    return out;
  }
  out.ok = true;
  return out;
}

bool Reequilibrate(const Model& model, Data& data, const StaticOptions& statics, int* solves,
                   std::string* failure) {
  StaticOptions warm = statics;
  warm.start_load_factor = warm.end_load_factor;
  warm.load_steps = 1;
  warm.max_halvings = 0;
  warm.max_iterations = std::min(warm.max_iterations, 12);
  State saved;
  SaveState(data, &saved);
  const Eigen::VectorXd lambda = data.lambda;
  ++*solves;
  StaticResult r = SolveStatic(model, data, warm);
  if (!r.converged) {
    // ... else load stepping from the reference state.
    const Data fresh = MakeData(model);
    RestoreState(State{fresh.H, fresh.HJ, fresh.q_joint}, data);
    data.lambda = fresh.lambda;
    data.w_ref = fresh.w_ref;
    data.tendon_slack = fresh.tendon_slack;
    StaticOptions cold = statics;
    cold.start_load_factor = 0.0;
    ++*solves;
    r = SolveStatic(model, data, cold);
  }
  if (!r.converged) {
    RestoreState(saved, data);
    data.lambda = lambda;
    UpdateBranchReferences(model, data);
    *failure = "no equilibrium at the parameters tried: " + r.message;
    return false;
  }
  return true;
}

double ParameterChainFactor(const Parameter& p, double value) {
  const bool factor = p.kind == ParameterKind::kRodStiffness || p.kind == ParameterKind::kRodMass;
  return factor ? 1.0 / (1.0 + value) : 1.0;
}

}  // namespace screwfem
