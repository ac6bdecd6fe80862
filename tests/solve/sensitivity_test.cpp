// Sensitivities of static equilibria (solve/sensitivity.h): forward derivatives against central
// finite differences of re-solved equilibria (1e-6 relative) for a cantilever (load,
// stiffness, rest curvature), a driven revolute joint (drive value; multipliers), a
// two-tendon finger (tensions), a pressurised chamber (pressure, mass) and a rod pressed on a
// plane (an active contact); the adjoint mode against the forward mode (1e-10); inverse
// statics of a three-tendon finger (20 reachable targets to 1e-8 m, an unreachable one);
// calibration of stiffness and rest curvature from noisy shapes (intervals, Monte Carlo).
#include "screwfem/solve/sensitivity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/model/errors.h"

namespace screwfem::sensitivity_test {
namespace {

Section RodSection(double EA, double EI) {
  Vec6 k;
  k << EA, EA, EA, EI, EI, EI;
  return Section::FromDiagonals(k);
}

// The outputs of a state, in the order of `outputs`: point coordinates, rotation components
// relative to `reference` (log(R_ref^T R), the node frame's right-trivialised rotation), joint
// coordinates and multipliers.
Eigen::VectorXd Evaluate(const Model& m, const Data& d, const Data& reference,
                         const std::vector<SensitivityOutput>& outputs) {
  Eigen::VectorXd y(static_cast<Eigen::Index>(outputs.size()));
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const SensitivityOutput& o = outputs[i];
    const Eigen::Index r = static_cast<Eigen::Index>(i);
    switch (o.kind) {
      case OutputKind::kPointPosition:
        y(r) = d.H[static_cast<std::size_t>(o.index)].Act(o.offset)(o.component);
        break;
      case OutputKind::kNodeRotation:
        y(r) = LogSO3(reference.H[static_cast<std::size_t>(o.index)].R.transpose() *
                      d.H[static_cast<std::size_t>(o.index)].R)(o.component);
        break;
      case OutputKind::kJointCoordinate:
        y(r) =
            d.q_joint(m.joints[static_cast<std::size_t>(o.index)].coord - m.nv_nodes + o.component);
        break;
      case OutputKind::kMultiplier:
        y(r) = d.lambda(o.index);
        break;
    }
  }
  return y;
}

// Central differences of the outputs over re-solved equilibria (Newton from the equilibrium
// with the parameter offset by +-h), one column per parameter.
Eigen::MatrixXd FiniteDifferences(const Model& model, const Data& equilibrium,
                                  const std::vector<Parameter>& params,
                                  const std::vector<SensitivityOutput>& outputs,
                                  const std::vector<double>& steps) {
  Eigen::MatrixXd fd(static_cast<Eigen::Index>(outputs.size()),
                     static_cast<Eigen::Index>(params.size()));
  StaticOptions warm;
  warm.start_load_factor = 1.0;
  warm.load_steps = 1;
  warm.residual_tolerance = warm.increment_tolerance = 1e-13;
  warm.constraint_tolerance = 1e-13;
  for (std::size_t j = 0; j < params.size(); ++j) {
    Eigen::VectorXd y[2];
    for (int side = 0; side < 2; ++side) {
      Model m = model;
      Data d = equilibrium;
      OffsetParameter(m, d, params[j], side == 0 ? steps[j] : -steps[j]);
      const StaticResult r = SolveStatic(m, d, warm);
      EXPECT_TRUE(r.converged) << r.message;
      y[side] = Evaluate(m, d, equilibrium, outputs);
    }
    fd.col(static_cast<Eigen::Index>(j)) = (y[0] - y[1]) / (2.0 * steps[j]);
  }
  return fd;
}

// Forward against finite differences (column by column, relative to the column's largest
// entry) and adjoint against forward (relative to the largest entry).
void CheckSensitivities(const Model& m, Data& d, const std::vector<Parameter>& params,
                        const std::vector<SensitivityOutput>& outputs,
                        const std::vector<double>& steps) {
  const StaticSensitivity fwd = CalcStaticSensitivity(m, d, params, outputs);
  ASSERT_TRUE(fwd.ok) << fwd.message;
  EXPECT_LT(fwd.equilibrium_error, 1e-9);
  const Eigen::MatrixXd fd = FiniteDifferences(m, d, params, outputs, steps);
  for (Eigen::Index j = 0; j < fd.cols(); ++j) {
    const double scale = fd.col(j).cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0) << "parameter " << j;
    for (Eigen::Index i = 0; i < fd.rows(); ++i)
      EXPECT_NEAR(fwd.outputs(i, j), fd(i, j), 1e-6 * scale)
          << "output " << i << " parameter " << j;
  }
  const StaticSensitivity adj =
      CalcStaticSensitivity(m, d, params, outputs, SensitivityMode::kAdjoint);
  ASSERT_TRUE(adj.ok) << adj.message;
  const double scale = fwd.outputs.cwiseAbs().maxCoeff();
  EXPECT_LT((adj.outputs - fwd.outputs).cwiseAbs().maxCoeff(), 1e-10 * scale);
}

std::vector<SensitivityOutput> TipOutputs(int node, const Vec3& offset, bool rotation) {
  std::vector<SensitivityOutput> out;
  for (int c = 0; c < 3; ++c) out.push_back({OutputKind::kPointPosition, node, c, offset});
  if (rotation)
    for (int c = 0; c < 3; ++c) out.push_back({OutputKind::kNodeRotation, node, c, Vec3::Zero()});
  return out;
}

// A 1 m cantilever (EA 1e4 N, EI 1 N m^2, 10 elements) with a tip load that turns its tip by
// about 0.2 rad: load components, stiffness factors and the rest curvature.
TEST(StaticSensitivity, CantileverLoadStiffnessAndRestCurvatureMatchFiniteDifferences) {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("beam", Vec3::Zero(), Vec3::UnitX(), 10, RodSection(1e4, 1.0));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(-0.1, 0.4, 0.2);
  load.moment = Vec3(0.05, 0.0, 0.0);
  b.AddPointLoad(load);
  const Model m = b.Build();
  Data d = MakeData(m);
  ASSERT_TRUE(SolveStatic(m, d).converged);
  const std::vector<Parameter> params = {
      {ParameterKind::kPointLoad, 0, 1},     {ParameterKind::kPointLoad, 0, 2},
      {ParameterKind::kPointLoad, 0, 3},     {ParameterKind::kRodStiffness, 0, -1},
      {ParameterKind::kRodStiffness, 0, 5},  {ParameterKind::kRodRestStrain, 0, 5},
      {ParameterKind::kRodRestStrain, 0, 3},
  };
  CheckSensitivities(m, d, params, TipOutputs(nodes.back(), Vec3(0.0, 0.05, 0.0), true),
                     {1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4});
}

// The internal forces are linear in the stiffness, so scaling every stiffness by (1 + p) is
// scaling the loads by 1 / (1 + p): d tip / dp = -(F . d tip / dF) at p = 0, exactly, however
// far the beam bends (an identity between two kinds of parameter).
TEST(StaticSensitivity, StiffnessFactorEqualsMinusTheLoadScaling) {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("beam", Vec3::Zero(), Vec3::UnitX(), 8, RodSection(1e3, 1.0));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(0.3, 1.5, -0.4);
  b.AddPointLoad(load);
  const Model m = b.Build();
  Data d = MakeData(m);
  ASSERT_TRUE(SolveStatic(m, d).converged);
  const StaticSensitivity s = CalcStaticSensitivity(m, d,
                                                    {{ParameterKind::kRodStiffness, 0, -1},
                                                     {ParameterKind::kPointLoad, 0, 0},
                                                     {ParameterKind::kPointLoad, 0, 1},
                                                     {ParameterKind::kPointLoad, 0, 2}},
                                                    TipOutputs(nodes.back(), Vec3::Zero(), true));
  ASSERT_TRUE(s.ok) << s.message;
  const Eigen::VectorXd by_load = -(s.outputs.rightCols(3) * load.force);
  EXPECT_LT((s.outputs.col(0) - by_load).cwiseAbs().maxCoeff(),
            1e-10 * by_load.cwiseAbs().maxCoeff());
  EXPECT_GT(by_load.cwiseAbs().maxCoeff(), 0.1);  // a large deflection
}

// A rod on a revolute joint to the ground with a prescribed angle, loaded at its tip: the
// drive value moves the tip and the multipliers (the joint's reactions and the drive torque).
TEST(StaticSensitivity, DrivenJointAngleAndMultipliersMatchFiniteDifferences) {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("arm", Vec3::Zero(), Vec3::UnitX(), 6, RodSection(1e4, 2.0));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  JointSpec j;
  j.name = "hinge";
  j.type = JointType::kRevolute;
  j.node_a = kGround;
  j.node_b = nodes.front();
  j.axis = Vec3::UnitZ();
  j.drive = DriveKind::kPrescribed;
  j.drive_profile = Profile::Constant(0.3);
  b.AddJoint(j);
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(0.2, -1.0, 0.3);
  b.AddPointLoad(load);
  const Model m = b.Build();
  Data d = MakeData(m);
  const StaticResult r = SolveStatic(m, d);
  ASSERT_TRUE(r.converged) << r.message;
  ASSERT_EQ(m.nc, 7);  // six rows of the joint's relative frame, one of the drive
  std::vector<SensitivityOutput> outputs = TipOutputs(nodes.back(), Vec3::Zero(), true);
  for (int row = 0; row < m.nc; ++row)
    outputs.push_back({OutputKind::kMultiplier, row, 0, Vec3::Zero()});
  outputs.push_back({OutputKind::kJointCoordinate, 0, 0, Vec3::Zero()});
  const std::vector<Parameter> params = {{ParameterKind::kJointDrive, 0, 0},
                                         {ParameterKind::kPointLoad, 0, 1}};
  CheckSensitivities(m, d, params, outputs, {1e-5, 1e-4});
  // The joint coordinate follows its drive exactly: d alpha / dq = 1.
  const StaticSensitivity s = CalcStaticSensitivity(m, d, params, outputs);
  EXPECT_NEAR(s.outputs(static_cast<Eigen::Index>(outputs.size()) - 1, 0), 1.0, 1e-12);
}

// A finger (1 m rod, EI 1 N m^2) clamped at its base, two tendons through eyelets on every
// node at 0.02 m from the axis (section y and z), tensions 30 N and 20 N.
struct Finger {
  Model model;
  NodeId tip;
};

Finger MakeFinger(const std::vector<double>& angles, const std::vector<double>& tensions,
                  double EA) {
  ModelBuilder b;
  const RodId rod =
      b.AddStraightRod("finger", Vec3::Zero(), Vec3::UnitX(), 10, RodSection(EA, 1.0));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  for (std::size_t t = 0; t < angles.size(); ++t) {
    std::vector<BodyPoint> eyelets;
    const Vec3 offset(0.0, 0.02 * std::cos(angles[t]), 0.02 * std::sin(angles[t]));
    for (NodeId n : nodes) eyelets.push_back({n, offset});
    b.AddTendon("tendon" + std::to_string(t), eyelets, Profile::Constant(tensions[t]));
  }
  return {b.Build(), nodes.back()};
}

TEST(StaticSensitivity, TendonTensionsMatchFiniteDifferences) {
  const Finger f = MakeFinger({0.0, 0.5 * std::numbers::pi}, {30.0, 20.0}, 1e4);
  Data d = MakeData(f.model);
  ASSERT_TRUE(SolveStatic(f.model, d).converged);
  CheckSensitivities(
      f.model, d, {{ParameterKind::kTendonTension, 0, -1}, {ParameterKind::kTendonTension, 1, -1}},
      TipOutputs(f.tip, Vec3(0.0, 0.0, 0.01), true), {1e-3, 1e-3});
}

// The tendons' offsets from the centreline (kTendonOffset, nonlinear in the route: dR/dp by
// central differences) of the two-tendon finger, components along and across the offset.
TEST(StaticSensitivity, TendonOffsetsMatchFiniteDifferences) {
  const Finger f = MakeFinger({0.0, 0.5 * std::numbers::pi}, {30.0, 20.0}, 1e4);
  Data d = MakeData(f.model);
  ASSERT_TRUE(SolveStatic(f.model, d).converged);
  CheckSensitivities(f.model, d,
                     {{ParameterKind::kTendonOffset, 0, 1},
                      {ParameterKind::kTendonOffset, 0, 2},
                      {ParameterKind::kTendonOffset, 1, 2}},
                     TipOutputs(f.tip, Vec3(0.0, 0.0, 0.01), true), {1e-6, 1e-6, 1e-6});
}

// A length-driven tendon (the tension a multiplier) shortened by 5 mm under a tip load: its
// prescribed length (kTendonLength) and its offset move the tip and the tension.
TEST(StaticSensitivity, LengthDrivenTendonLengthAndOffsetMatchFiniteDifferences) {
  ModelBuilder b;
  const RodId rod =
      b.AddStraightRod("finger", Vec3::Zero(), Vec3::UnitX(), 8, RodSection(1e4, 2.0));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  std::vector<BodyPoint> eyelets;
  for (NodeId n : nodes) eyelets.push_back({n, Vec3(0.0, 0.02, 0.0)});
  b.AddLengthDrivenTendon("pull", eyelets, Profile::Constant(0.995));
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(0.0, 0.0, -0.5);
  b.AddPointLoad(load);
  const Model m = b.Build();
  Data d = MakeData(m);
  const StaticResult r = SolveStatic(m, d);
  ASSERT_TRUE(r.converged) << r.message;
  ASSERT_GT(d.lambda(0), 0.0);  // taut
  std::vector<SensitivityOutput> outputs = TipOutputs(nodes.back(), Vec3::Zero(), true);
  outputs.push_back({OutputKind::kMultiplier, 0, 0, Vec3::Zero()});
  CheckSensitivities(m, d,
                     {{ParameterKind::kTendonLength, 0, -1},
                      {ParameterKind::kTendonOffset, 0, 1},
                      {ParameterKind::kRodStiffness, 0, 4}},
                     outputs, {1e-6, 1e-6, 1e-4});
}

// A cantilever with a pressurised chamber off its axis (2 cm along section y and 1 cm along
// z, 1 cm^2): the pressure bends it, a tip load and gravity act too. Parameters: the pressure
// (kActuator) and the rod's mass (kRodMass, its weight) besides a load and the stiffness.
TEST(StaticSensitivity, ChamberPressureAndMassMatchFiniteDifferences) {
  ModelBuilder b;
  Vec6 inertia;
  inertia << 0.5, 0.5, 0.5, 1e-4, 1e-4, 2e-4;
  const RodId rod =
      b.AddStraightRod("arm", Vec3::Zero(), Vec3::UnitX(), 10,
                       Section::FromDiagonals(RodSection(1e4, 1.0).stiffness, inertia));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  Actuator chamber;
  chamber.name = "chamber";
  chamber.type = ActuatorType::kPressure;
  chamber.rod = rod;
  chamber.area = 1e-4;
  chamber.offset = Vec3(0.0, 0.02, 0.01);
  chamber.profile = Profile::Constant(5e4);  // 50 kPa: 5 N over 2 cm, 0.1 N m of bending
  b.AddActuator(chamber);
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(0.0, 0.3, 0.0);
  b.AddPointLoad(load);
  const Model m = b.Build();
  Data d = MakeData(m);
  ASSERT_TRUE(SolveStatic(m, d).converged);
  EXPECT_GT(std::abs(d.H[nodes.back()].x.y()), 0.03);  // a large deflection
  CheckSensitivities(m, d,
                     {{ParameterKind::kActuator, 0, -1},
                      {ParameterKind::kRodMass, 0, -1},
                      {ParameterKind::kPointLoad, 0, 1},
                      {ParameterKind::kRodStiffness, 0, 4}},
                     TipOutputs(nodes.back(), Vec3(0.0, 0.02, 0.0), true), {1.0, 1e-4, 1e-4, 1e-4});
}

// A rod above a plane, clamped at one end and pushed down at the other so that its last
// nodes press into the plane (penalty contact of the node spheres and element capsules, whose
// tangent is in the Newton matrix): loads, stiffness and the rod's weight against central
// differences, and the contact force's share of the load checked to be substantial.
TEST(StaticSensitivity, ActiveContactOnAPlaneMatchesFiniteDifferences) {
  ModelBuilder b;
  Vec6 inertia;
  inertia << 0.2, 0.2, 0.2, 1e-5, 1e-5, 2e-5;
  const RodId rod =
      b.AddStraightRod("arm", Vec3(0.0, 0.0, 0.1), Vec3(1.0, 0.0, 0.1), 10,
                       Section::FromDiagonals(RodSection(1e4, 1.0).stiffness, inertia));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  b.AddContactRod(rod, 0.01);
  b.AddObstacle({"ground", ObstacleType::kPlane, Vec3::Zero(), Vec3::UnitZ(), Vec3::Zero(), 0.0});
  ContactSettings contact;
  contact.stiffness = 1e4;
  contact.onset = 1e-3;
  b.SetContactSettings(contact);
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(0.2, 0.1, -1.0);
  b.AddPointLoad(load);
  const Model m = b.Build();
  Data d = MakeData(m);
  const StaticResult r = SolveStatic(m, d);
  ASSERT_TRUE(r.converged) << r.message;
  // In contact: the tip sits near the plane (within the radius and the onset).
  EXPECT_LT(d.H[nodes.back()].x.z(), 0.0115);
  CheckSensitivities(m, d,
                     {{ParameterKind::kPointLoad, 0, 2},
                      {ParameterKind::kPointLoad, 0, 1},
                      {ParameterKind::kRodStiffness, 0, -1},
                      {ParameterKind::kRodMass, 0, -1}},
                     TipOutputs(nodes.back(), Vec3(0.0, 0.0, 0.01), true),
                     {1e-4, 1e-4, 1e-4, 1e-4});
  // Without the plane the same load takes the tip far below it: the contact carries load.
  ModelBuilder free_builder;
  const RodId free_rod =
      free_builder.AddStraightRod("arm", Vec3(0.0, 0.0, 0.1), Vec3(1.0, 0.0, 0.1), 10,
                                  Section::FromDiagonals(RodSection(1e4, 1.0).stiffness, inertia));
  free_builder.FixNode(free_builder.RodNodes(free_rod).front());
  free_builder.SetGravity(Vec3(0.0, 0.0, -9.81));
  free_builder.AddPointLoad(load);
  const Model fm = free_builder.Build();
  Data fd = MakeData(fm);
  ASSERT_TRUE(SolveStatic(fm, fd).converged);
  EXPECT_LT(fd.H[nodes.back()].x.z(), -0.1);
}

// The sparse LU (KLU, klu_tsolve for the adjoint) gives the banded LU's sensitivities: the
// driven joint's model solved with each.
TEST(StaticSensitivity, SparseAndBandedSolversAgree) {
  Eigen::MatrixXd results[2];
  for (int k = 0; k < 2; ++k) {
    ModelBuilder b;
    b.SetLinearSolver(k == 0 ? LinearSolver::kBanded : LinearSolver::kSparse);
    const RodId rod = b.AddStraightRod("arm", Vec3::Zero(), Vec3::UnitX(), 6, RodSection(1e4, 2.0));
    const std::vector<NodeId> nodes = b.RodNodes(rod);
    JointSpec j;
    j.type = JointType::kRevolute;
    j.node_b = nodes.front();
    j.drive = DriveKind::kPrescribed;
    j.drive_profile = Profile::Constant(0.3);
    b.AddJoint(j);
    PointLoad load;
    load.node = nodes.back();
    load.force = Vec3(0.2, -1.0, 0.3);
    b.AddPointLoad(load);
    const Model m = b.Build();
    ASSERT_EQ(m.sparse_solver, k == 1);
    Data d = MakeData(m);
    ASSERT_TRUE(SolveStatic(m, d).converged);
    std::vector<SensitivityOutput> outputs = TipOutputs(nodes.back(), Vec3::Zero(), true);
    for (int row = 0; row < m.nc; ++row)
      outputs.push_back({OutputKind::kMultiplier, row, 0, Vec3::Zero()});
    const std::vector<Parameter> params = {{ParameterKind::kJointDrive, 0, 0},
                                           {ParameterKind::kRodStiffness, 0, 4}};
    const StaticSensitivity fwd = CalcStaticSensitivity(m, d, params, outputs);
    const StaticSensitivity adj =
        CalcStaticSensitivity(m, d, params, outputs, SensitivityMode::kAdjoint);
    ASSERT_TRUE(fwd.ok && adj.ok) << fwd.message << adj.message;
    const double scale = fwd.outputs.cwiseAbs().maxCoeff();
    EXPECT_LT((adj.outputs - fwd.outputs).cwiseAbs().maxCoeff(), 1e-10 * scale);
    results[k] = fwd.outputs;
  }
  EXPECT_LT((results[1] - results[0]).cwiseAbs().maxCoeff(),
            1e-9 * results[0].cwiseAbs().maxCoeff());
}

TEST(StaticSensitivity, InvalidParametersAndOutputsAreNamed) {
  const Finger f = MakeFinger({0.0}, {1.0}, 1e4);
  Data d = MakeData(f.model);
  try {
    CalcStaticSensitivity(f.model, d, {{ParameterKind::kPointLoad, 0, 1}}, {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "CalcStaticSensitivity: parameter point_load 0 (component 1): no such point load");
  }
  StaticOptions inexact;
  inexact.constraint_force_tangent = false;
  const StaticSensitivity s =
      CalcStaticSensitivity(f.model, d, {}, {}, SensitivityMode::kForward, inexact);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message,
            "options.constraint_force_tangent is false: the derivatives need the exact tangent");
  try {
    CalcStaticSensitivity(f.model, d, {}, {{OutputKind::kMultiplier, 0, 0, Vec3::Zero()}});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "CalcStaticSensitivity: output multiplier 0: no such multiplier row");
  }
}

// Three tendons at 120 degrees: tensions in [0, 40] N reach 20 targets (tips of equilibria at
// random tensions, visited one after the other, each warm-started from the last solution) to
// 1e-8 m; a target out of reach gives the nearest equilibrium and its distance.
TEST(InverseStatics, ThreeTendonFingerReachesTwentyTargetsWithinBounds) {
  const double third = 2.0 * std::numbers::pi / 3.0;
  const Finger f = MakeFinger({0.5 * std::numbers::pi, 0.5 * std::numbers::pi + third,
                               0.5 * std::numbers::pi + 2.0 * third},
                              {0.0, 0.0, 0.0}, 1e3);
  const std::vector<Parameter> params = {{ParameterKind::kTendonTension, 0, -1},
                                         {ParameterKind::kTendonTension, 1, -1},
                                         {ParameterKind::kTendonTension, 2, -1}};
  const Eigen::Vector3d lower = Eigen::Vector3d::Zero(), upper = Eigen::Vector3d::Constant(40.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 40.0);
  Data d = MakeData(f.model);
  Eigen::VectorXd values = Eigen::VectorXd::Zero(3);
  int worst_solves = 0;
  for (int k = 0; k < 20; ++k) {
    // The target: the tip at random tensions (one of them zero half the time: on a bound).
    Eigen::Vector3d tensions(u(rng), u(rng), u(rng));
    if (k % 2 == 1) tensions(k % 3) = 0.0;
    Model m = f.model;
    Data probe = MakeData(m);
    for (int i = 0; i < 3; ++i)
      OffsetParameter(m, probe, params[static_cast<std::size_t>(i)], tensions(i));
    ASSERT_TRUE(SolveStatic(m, probe).converged);
    const InverseTarget target{f.tip, Vec3::Zero(), probe.H[f.tip].x};
    const InverseStaticsResult r =
        SolveInverseStatics(f.model, d, params, lower, upper, {target}, values);
    ASSERT_TRUE(r.converged) << "target " << k << ": " << r.message;
    EXPECT_LT(r.distance, 1e-8) << "target " << k;
    EXPECT_LT((d.H[f.tip].x - target.target).norm(), 1e-8) << "target " << k;
    EXPECT_TRUE((r.values.array() >= 0.0).all() && (r.values.array() <= 40.0).all());
    worst_solves = std::max(worst_solves, r.equilibrium_solves);
    values = r.values;
  }
  EXPECT_LT(worst_solves, 60);
  // Out of reach: 0.5 m beside the finger's base.
  const InverseTarget far{f.tip, Vec3::Zero(), Vec3(0.0, 0.0, -1.2)};
  const InverseStaticsResult r =
      SolveInverseStatics(f.model, d, params, lower, upper, {far}, values);
  EXPECT_FALSE(r.converged);
  EXPECT_GT(r.distance, 0.1);
  EXPECT_NEAR(r.distance, (d.H[f.tip].x - far.target).norm(), 1e-12);
  EXPECT_NE(r.message.find("the targets are not reached: the nearest equilibrium within the "
                           "bounds is"),
            std::string::npos)
      << r.message;
  EXPECT_TRUE((r.values.array() >= 0.0).all() && (r.values.array() <= 40.0).all());
}

// Calibration: a cantilever (1 m, 10 elements, EI 1 N m^2) whose true bending is 1.25 times the
// model's (stiffness factor 0.25) and whose rest curvature is 0.3 1/m, measured at five nodes
// in four load cases (tip forces along y and z) with Gaussian noise of 1 mm per coordinate
// (fixed seed). The fit recovers both within the reported 3-sigma intervals, and the reported
// covariance sigma^2 (J^T J)^-1 agrees with the scatter of 40 fits to independent noise draws.
struct CalibrationSetup {
  Model model;
  std::vector<NodeId> nodes;
  std::vector<Parameter> params;
  std::vector<CalibrationCase> cases;  // measurements: the noise-free truth
};

CalibrationSetup MakeCalibrationSetup() {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("beam", Vec3::Zero(), Vec3::UnitX(), 10, RodSection(1e4, 1.0));
  CalibrationSetup s;
  s.nodes = b.RodNodes(rod);
  b.FixNode(s.nodes.front());
  PointLoad load;
  load.node = s.nodes.back();
  b.AddPointLoad(load);
  s.model = b.Build();
  s.params = {{ParameterKind::kRodStiffness, 0, -1}, {ParameterKind::kRodRestStrain, 0, 5}};
  const Eigen::Vector2d truth(0.25, 0.3);
  const std::vector<Parameter> loads = {{ParameterKind::kPointLoad, 0, 1},
                                        {ParameterKind::kPointLoad, 0, 2}};
  for (const Eigen::Vector2d& f : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(0.5, 0.0),
                                   Eigen::Vector2d(1.0, 0.0), Eigen::Vector2d(0.0, 0.5)}) {
    Model m = s.model;
    Data d = MakeData(m);
    for (int i = 0; i < 2; ++i) {
      OffsetParameter(m, d, s.params[static_cast<std::size_t>(i)], truth(i));
      OffsetParameter(m, d, loads[static_cast<std::size_t>(i)], f(i));
    }
    EXPECT_TRUE(SolveStatic(m, d).converged);
    CalibrationCase c{loads, f, {}};
    for (int k = 2; k <= 10; k += 2)
      c.measurements.push_back({s.nodes[static_cast<std::size_t>(k)], Vec3::Zero(),
                                d.H[s.nodes[static_cast<std::size_t>(k)]].x});
    s.cases.push_back(c);
  }
  return s;
}

std::vector<CalibrationCase> WithNoise(std::vector<CalibrationCase> cases, double sigma,
                                       std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, sigma);
  for (CalibrationCase& c : cases)
    for (InverseTarget& t : c.measurements)
      for (int k = 0; k < 3; ++k) t.target(k) += noise(rng);
  return cases;
}

TEST(Calibration, RecoversStiffnessAndRestCurvatureWithinTheReportedIntervals) {
  const CalibrationSetup s = MakeCalibrationSetup();
  const Eigen::Vector2d truth(0.25, 0.3), start(0.0, 0.0);
  // Noise-free: the truth to round-off.
  const CalibrationResult exact = Calibrate(s.model, s.params, start, s.cases);
  ASSERT_TRUE(exact.converged) << exact.message;
  EXPECT_LT((exact.values - truth).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT(exact.rms, 1e-10);
  // With noise of 1 mm, sigma estimated from the residual.
  const double sigma = 1e-3;
  std::mt19937 rng(11);
  const CalibrationResult r = Calibrate(s.model, s.params, start, WithNoise(s.cases, sigma, rng));
  ASSERT_TRUE(r.converged) << r.message;
  for (int i = 0; i < 2; ++i) {
    EXPECT_LE(r.lower(i), truth(i)) << "parameter " << i;
    EXPECT_GE(r.upper(i), truth(i)) << "parameter " << i;
    EXPECT_NEAR(r.upper(i) - r.values(i), 3.0 * r.standard_error(i), 1e-15);
    EXPECT_GT(r.standard_error(i), 0.0);
  }
  // 60 coordinates, 2 parameters: the estimated sigma within 30 % (its spread is ~9 %).
  EXPECT_NEAR(r.sigma, sigma, 0.3 * sigma);
  CalibrationOptions given;
  given.sigma = sigma;
  // Monte Carlo: 40 fits to independent draws, sigma given; their scatter against the
  // covariance the first reports (sample variances of 40 draws spread by ~23 %).
  const int draws = 40;
  Eigen::MatrixXd fits(draws, 2);
  Eigen::Matrix2d reported = Eigen::Matrix2d::Zero();
  for (int k = 0; k < draws; ++k) {
    const CalibrationResult f =
        Calibrate(s.model, s.params, start, WithNoise(s.cases, sigma, rng), given);
    ASSERT_TRUE(f.converged) << f.message;
    fits.row(k) = f.values.transpose();
    if (k == 0) reported = f.covariance;
  }
  const Eigen::RowVector2d mean = fits.colwise().mean();
  const Eigen::MatrixXd centred = fits.rowwise() - mean;
  const Eigen::Matrix2d sample = centred.transpose() * centred / (draws - 1);
  for (int i = 0; i < 2; ++i) {
    const double ratio = sample(i, i) / reported(i, i);
    EXPECT_GT(ratio, 0.5) << "parameter " << i;
    EXPECT_LT(ratio, 1.6) << "parameter " << i;
    // Unbiased: the mean of the fits within 3 standard errors of the mean of the truth.
    EXPECT_NEAR(mean(i), truth(i), 3.0 * std::sqrt(reported(i, i) / draws)) << "parameter " << i;
  }
  const double rho_sample = sample(0, 1) / std::sqrt(sample(0, 0) * sample(1, 1));
  const double rho_reported = reported(0, 1) / std::sqrt(reported(0, 0) * reported(1, 1));
  EXPECT_NEAR(rho_sample, rho_reported, 0.3);
}

TEST(Calibration, InvalidInputsAreNamed) {
  const CalibrationSetup s = MakeCalibrationSetup();
  try {
    Calibrate(s.model, s.params, Eigen::VectorXd::Zero(1), s.cases);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "Calibrate: start needs one finite value per parameter");
  }
  std::vector<CalibrationCase> bad = s.cases;
  bad[1].measurements.clear();
  try {
    Calibrate(s.model, s.params, Eigen::VectorXd::Zero(2), bad);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "Calibrate: load case 1: no measurements");
  }
}

}  // namespace
}  // namespace screwfem::sensitivity_test
