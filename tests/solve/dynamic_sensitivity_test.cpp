// Sensitivities of dynamic trajectories (solve/sensitivity.h, CalcDynamicSensitivity): the
// forward sensitivities of a swinging tendon-driven rod against central differences of whole
// re-run trajectories (1e-6 relative), through restarts at the breakpoints of the tendon's
// piecewise-linear tension profile, for a constant tension offset, a knot of the profile (a
// hat-shaped parameter), the stiffness, the mass and a tip load; the discrete adjoint against
// the forward mode (1e-10) for an objective over the whole run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/sensitivity.h"

namespace screwfem::dynamic_sensitivity_test {
namespace {

// A 1 m rod of 4 elements clamped at its base (EI 1 N m^2, EA 1e3 N, 10 g/m: its first bending
// mode has a period of 0.18 s), with a tendon 2 cm off its axis whose tension follows a
// piecewise-linear profile with knots every 10 ms (breakpoints: restarts; positive from the
// start, where a tendon's tension would otherwise sit on its clamp at zero), and a small tip
// load. Option B's inertia without damping (the assembled K and C are the exact derivatives),
// or option A with Rayleigh damping (K and C by differences of the residual).
struct Arm {
  Model model;
  NodeId tip;
};

Arm MakeArm(RodInertia inertia = RodInertia::kExact) {
  ModelBuilder b;
  Vec6 k, m;
  k << 1e3, 1e3, 1e3, 1.0, 1.0, 1.0;
  m << 1e-2, 1e-2, 1e-2, 1e-6, 1e-6, 2e-6;
  Section section = Section::FromDiagonals(k, m);
  section.rayleigh_stiffness = inertia == RodInertia::kConstant ? 0.0 : 1e-4;
  const RodId rod = b.AddStraightRod("arm", Vec3::Zero(), Vec3::UnitX(), 4, section);
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  std::vector<BodyPoint> eyelets;
  for (NodeId n : nodes) eyelets.push_back({n, Vec3(0.0, 0.02, 0.0)});
  b.AddTendon("pull", eyelets,
              Profile::Table({0.0, 0.01, 0.02, 0.03, 0.04}, {0.5, 3.0, 5.0, 5.0, 4.0}));
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(0.0, 0.0, 0.02);
  b.AddPointLoad(load);
  Arm arm{b.Build(), nodes.back()};
  arm.model.rod_inertia = inertia;
  return arm;
}

DynamicSensitivityOptions RunOptions() {
  DynamicSensitivityOptions o;
  o.step = 2e-3;
  o.steps = 20;  // 40 ms: through the breakpoints at 10, 20 and 30 ms
  o.dynamics.newton_matrix = NewtonMatrix::kFull;
  o.dynamics.increment_tolerance = 1e-14;
  o.dynamics.residual_tolerance = 1e-13;
  return o;
}

// The tip's trajectory by the ordinary integrator (InitializeDynamics, Step).
Eigen::MatrixXd Trajectory(const Model& m, const std::vector<SensitivityOutput>& outputs,
                           const DynamicSensitivityOptions& o) {
  Data d = MakeData(m);
  Integrator integ;
  std::string why;
  EXPECT_TRUE(InitializeDynamics(m, d, integ, o.dynamics, &why)) << why;
  Eigen::MatrixXd y(o.steps + 1, static_cast<Eigen::Index>(outputs.size()));
  const auto record = [&](int n) {
    for (std::size_t k = 0; k < outputs.size(); ++k)
      y(n, static_cast<Eigen::Index>(k)) = d.H[static_cast<std::size_t>(outputs[k].index)].Act(
          outputs[k].offset)(outputs[k].component);
  };
  record(0);
  for (int n = 0; n < o.steps; ++n) {
    const StepResult r = Step(m, d, integ, o.step);
    EXPECT_TRUE(r.ok) << r.message;
    record(n + 1);
  }
  return y;
}

std::vector<SensitivityOutput> TipOutputs(NodeId tip) {
  std::vector<SensitivityOutput> out;
  for (int c = 0; c < 3; ++c)
    out.push_back({OutputKind::kPointPosition, tip, c, Vec3(0.0, 0.01, 0.0)});
  return out;
}

std::vector<Parameter> ArmParameters() {
  Parameter knot{ParameterKind::kTendonTension, 0, -1};
  knot.shape = Profile::Table({0.0, 0.01, 0.02, 0.03}, {0.0, 0.0, 1.0, 0.0});  // the knot at 20 ms
  return {{ParameterKind::kTendonTension, 0, -1},
          knot,
          {ParameterKind::kRodStiffness, 0, -1},
          {ParameterKind::kRodMass, 0, -1},
          {ParameterKind::kPointLoad, 0, 2}};
}

void CheckForwardAgainstFiniteDifferences(RodInertia inertia) {
  const Arm arm = MakeArm(inertia);
  const std::vector<SensitivityOutput> outputs = TipOutputs(arm.tip);
  const std::vector<Parameter> params = ArmParameters();
  const DynamicSensitivityOptions o = RunOptions();
  Data d = MakeData(arm.model);
  const DynamicSensitivity s = CalcDynamicSensitivity(
      arm.model, d, params, outputs, Eigen::MatrixXd(), SensitivityMode::kForward, o);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(s.restarts, 4);  // at 10, 20, 30 and 40 ms (the end)
  // The run is the integrator's: the same trajectory as Step's.
  const Eigen::MatrixXd nominal = Trajectory(arm.model, outputs, o);
  EXPECT_LT((s.values - nominal).cwiseAbs().maxCoeff(), 1e-12);
  // The tip swings: it has moved by centimetres.
  EXPECT_GT(std::abs(nominal(o.steps, 1) - nominal(0, 1)), 0.005);
  const std::vector<double> steps = {1e-4, 1e-4, 1e-6, 1e-6, 1e-5};
  const int no = static_cast<int>(outputs.size());
  for (std::size_t j = 0; j < params.size(); ++j) {
    Eigen::MatrixXd y[2];
    for (int side = 0; side < 2; ++side) {
      Model m = arm.model;
      Data unused = MakeData(m);
      OffsetParameter(m, unused, params[j], side == 0 ? steps[j] : -steps[j]);
      y[side] = Trajectory(m, outputs, o);
    }
    const Eigen::MatrixXd fd = (y[0] - y[1]) / (2.0 * steps[j]);
    const Eigen::Index col = static_cast<Eigen::Index>(j);
    // Every step's tip, relative to the largest derivative along the run.
    const double scale = fd.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    for (int n = 0; n <= o.steps; ++n)
      for (int k = 0; k < no; ++k)
        EXPECT_NEAR(s.outputs(n * no + k, col), fd(n, k), 1e-6 * scale)
            << "parameter " << j << " step " << n << " output " << k;
  }
}

// Option B (constant mass matrix), undamped: the assembled matrices are the exact derivatives.
TEST(DynamicSensitivity, ForwardMatchesFiniteDifferencesOfTheWholeRunThroughRestarts) {
  CheckForwardAgainstFiniteDifferences(RodInertia::kConstant);
}

// Option A (the default) with Rayleigh damping: K and C by central differences of the
// residual (the iteration matrix leaves out parts of the inertia's and the damping's
// derivatives).
TEST(DynamicSensitivity, ExactInertiaForwardMatchesFiniteDifferencesOfTheWholeRun) {
  CheckForwardAgainstFiniteDifferences(RodInertia::kExact);
}

TEST(DynamicSensitivity, AdjointEqualsForwardForAnObjectiveOverTheRun) {
  const Arm arm = MakeArm();
  const std::vector<SensitivityOutput> outputs = TipOutputs(arm.tip);
  const std::vector<Parameter> params = ArmParameters();
  const DynamicSensitivityOptions o = RunOptions();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd weights(o.steps + 1, 3);
  for (Eigen::Index i = 0; i < weights.size(); ++i) weights(i) = u(rng);
  Data d1 = MakeData(arm.model), d2 = MakeData(arm.model);
  const DynamicSensitivity fwd =
      CalcDynamicSensitivity(arm.model, d1, params, outputs, weights, SensitivityMode::kForward, o);
  const DynamicSensitivity adj =
      CalcDynamicSensitivity(arm.model, d2, params, outputs, weights, SensitivityMode::kAdjoint, o);
  ASSERT_TRUE(fwd.ok && adj.ok) << fwd.message << adj.message;
  EXPECT_EQ(fwd.objective, adj.objective);
  const double scale = fwd.gradient.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.0);
  EXPECT_LT((adj.gradient - fwd.gradient).cwiseAbs().maxCoeff(), 1e-10 * scale)
      << fwd.gradient.transpose() << "\n"
      << adj.gradient.transpose();
  // The final-time objective (no weights) too.
  Data d3 = MakeData(arm.model), d4 = MakeData(arm.model);
  const DynamicSensitivity f2 =
      CalcDynamicSensitivity(arm.model, d3, params, outputs, {}, SensitivityMode::kForward, o);
  const DynamicSensitivity a2 =
      CalcDynamicSensitivity(arm.model, d4, params, outputs, {}, SensitivityMode::kAdjoint, o);
  ASSERT_TRUE(f2.ok && a2.ok);
  EXPECT_LT((a2.gradient - f2.gradient).cwiseAbs().maxCoeff(),
            1e-10 * f2.gradient.cwiseAbs().maxCoeff());
}

TEST(DynamicSensitivity, ABreakpointInsideAStepIsRefused) {
  const Arm arm = MakeArm();
  DynamicSensitivityOptions o = RunOptions();
  o.step = 3e-3;
  Data d = MakeData(arm.model);
  const DynamicSensitivity s = CalcDynamicSensitivity(
      arm.model, d, ArmParameters(), TipOutputs(arm.tip), {}, SensitivityMode::kForward, o);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message,
            "the breakpoint at t = 0.01 s lies inside a step: choose a step size whose step ends "
            "fall on the breakpoints");
}

// ---- models with multipliers (index 3) -------------------------------------------------------

// Forward sensitivities of every step's outputs against central differences of whole runs of
// the ordinary integrator (1e-6 of the largest derivative along the run), and the adjoint of
// an objective over the run against the forward mode (1e-10).
void CheckAgainstWholeRuns(const Model& model, const std::vector<SensitivityOutput>& outputs,
                           const std::vector<Parameter>& params, const std::vector<double>& steps,
                           const DynamicSensitivityOptions& o, int restarts) {
  Data d = MakeData(model);
  const DynamicSensitivity s = CalcDynamicSensitivity(model, d, params, outputs, Eigen::MatrixXd(),
                                                      SensitivityMode::kForward, o);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(s.restarts, restarts);
  const Eigen::MatrixXd nominal = Trajectory(model, outputs, o);
  EXPECT_LT((s.values - nominal).cwiseAbs().maxCoeff(), 1e-12);
  const int no = static_cast<int>(outputs.size());
  for (std::size_t j = 0; j < params.size(); ++j) {
    Eigen::MatrixXd y[2];
    for (int side = 0; side < 2; ++side) {
      Model m = model;
      Data unused = MakeData(m);
      OffsetParameter(m, unused, params[j], side == 0 ? steps[j] : -steps[j]);
      y[side] = Trajectory(m, outputs, o);
    }
    const Eigen::MatrixXd fd = (y[0] - y[1]) / (2.0 * steps[j]);
    const Eigen::Index col = static_cast<Eigen::Index>(j);
    const double scale = fd.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    double worst = 0.0;
    for (int n = 0; n <= o.steps; ++n)
      for (int k = 0; k < no; ++k) {
        worst = std::max(worst, std::abs(s.outputs(n * no + k, col) - fd(n, k)) / scale);
        EXPECT_NEAR(s.outputs(n * no + k, col), fd(n, k), 1e-6 * scale)
            << "parameter " << j << " step " << n << " output " << k;
      }
    std::printf("parameter %zu: largest error %.2e of the largest derivative %.3e\n", j, worst,
                scale);
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd weights(o.steps + 1, no);
  for (Eigen::Index i = 0; i < weights.size(); ++i) weights(i) = u(rng);
  Data d1 = MakeData(model), d2 = MakeData(model);
  const DynamicSensitivity fwd =
      CalcDynamicSensitivity(model, d1, params, outputs, weights, SensitivityMode::kForward, o);
  const DynamicSensitivity adj =
      CalcDynamicSensitivity(model, d2, params, outputs, weights, SensitivityMode::kAdjoint, o);
  ASSERT_TRUE(fwd.ok && adj.ok) << fwd.message << adj.message;
  EXPECT_EQ(fwd.objective, adj.objective);
  const double gscale = fwd.gradient.cwiseAbs().maxCoeff();
  ASSERT_GT(gscale, 0.0);
  EXPECT_LT((adj.gradient - fwd.gradient).cwiseAbs().maxCoeff(), 1e-10 * gscale)
      << fwd.gradient.transpose() << "\n"
      << adj.gradient.transpose();
}

// The arm of MakeArm without its tendon, with a 10 g rigid body on a revolute joint at its tip
// whose angle (about z) is prescribed by a piecewise-linear profile with knots every 10 ms (the
// drive's breakpoints: restarts), under gravity: seven multiplier rows (the joint's six and
// the drive's).
struct Jointed {
  Model model;
  NodeId body;
};

Jointed MakeJointedArm() {
  ModelBuilder b;
  Vec6 k, m;
  k << 1e3, 1e3, 1e3, 1.0, 1.0, 1.0;
  m << 1e-2, 1e-2, 1e-2, 1e-6, 1e-6, 2e-6;
  const RodId rod =
      b.AddStraightRod("arm", Vec3::Zero(), Vec3::UnitX(), 4, Section::FromDiagonals(k, m));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  const NodeId body = b.AddNode(SE3::Translation(Vec3::UnitX()), "body");
  b.AddRigidBody("body", body, 0.01, Vec3(0.05, 0.0, 0.0), 1e-5 * Mat3::Identity());
  JointSpec j;
  j.name = "wrist";
  j.type = JointType::kRevolute;
  j.node_a = nodes.back();
  j.node_b = body;
  j.point = Vec3::UnitX();
  j.axis = Vec3::UnitZ();
  j.drive = DriveKind::kPrescribed;
  j.drive_profile = Profile::Table({0.0, 0.01, 0.02, 0.03, 0.04}, {0.0, 0.3, 0.8, 0.8, 0.5});
  b.AddJoint(j);
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  PointLoad load;
  load.node = body;
  load.force = Vec3(0.0, 0.01, 0.0);
  b.AddPointLoad(load);
  Jointed out{b.Build(), body};
  out.model.rod_inertia = RodInertia::kConstant;
  return out;
}

TEST(DynamicSensitivity, JointedArmThroughDriveBreakpointsMatchesWholeRuns) {
  const Jointed arm = MakeJointedArm();
  ASSERT_EQ(arm.model.nc, 7);
  std::vector<SensitivityOutput> outputs;
  for (int c = 0; c < 3; ++c)
    outputs.push_back({OutputKind::kPointPosition, arm.body, c, Vec3(0.05, 0.0, 0.0)});
  Parameter ramp{ParameterKind::kJointDrive, 0, -1};
  ramp.shape = Profile::Table({0.0, 0.04}, {0.0, 1.0});  // zero at the start (consistent q_0)
  Parameter knot{ParameterKind::kJointDrive, 0, -1};
  knot.shape = Profile::Table({0.0, 0.01, 0.02, 0.03}, {0.0, 0.0, 1.0, 0.0});
  const std::vector<Parameter> params = {ramp,
                                         knot,
                                         {ParameterKind::kRodStiffness, 0, -1},
                                         {ParameterKind::kRodMass, 0, -1},
                                         {ParameterKind::kPointLoad, 0, 1}};
  // The body moves: the tip swings by centimetres.
  const DynamicSensitivityOptions o = RunOptions();
  const Eigen::MatrixXd y = Trajectory(arm.model, outputs, o);
  EXPECT_GT((y.row(o.steps) - y.row(0)).norm(), 0.005);
  // Steps well above the round-off of the runs' restarts (their Bdot v, docs/inverse.md).
  CheckAgainstWholeRuns(arm.model, outputs, params, {1e-4, 1e-4, 1e-4, 1e-4, 1e-3}, o, 4);
}

// The tendon-driven arm of MakeArm carrying a 10 g body on a spherical joint at its tip (a joint
// whose coordinates retract by the exponential: T and Ad on its three coordinates), under
// gravity: the tension's breakpoints restart the run. The joint's damper reads the coordinates'
// rates, so the joint's T matters (with the identity instead the derivatives are off by 1e-5).
TEST(DynamicSensitivity, SphericalJointThroughRestartsMatchesWholeRuns) {
  ModelBuilder b;
  Vec6 k, m;
  k << 1e3, 1e3, 1e3, 1.0, 1.0, 1.0;
  m << 1e-2, 1e-2, 1e-2, 1e-6, 1e-6, 2e-6;
  const RodId rod =
      b.AddStraightRod("arm", Vec3::Zero(), Vec3::UnitX(), 4, Section::FromDiagonals(k, m));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  std::vector<BodyPoint> eyelets;
  for (NodeId n : nodes) eyelets.push_back({n, Vec3(0.0, 0.02, 0.0)});
  b.AddTendon("pull", eyelets,
              Profile::Table({0.0, 0.01, 0.02, 0.03, 0.04}, {0.5, 3.0, 5.0, 5.0, 4.0}));
  const NodeId body = b.AddNode(SE3::Translation(Vec3::UnitX()), "body");
  b.AddRigidBody("body", body, 0.01, Vec3(0.05, 0.01, 0.0), 1e-5 * Mat3::Identity());
  JointSpec ball;
  ball.name = "ball";
  ball.type = JointType::kSpherical;
  ball.node_a = nodes.back();
  ball.node_b = body;
  ball.point = Vec3::UnitX();
  ball.stiffness << 0.01, 0.01, 0.01, 0.0, 0.0, 0.0;  // [N m/rad]
  ball.damping << 2e-4, 2e-4, 2e-4, 0.0, 0.0, 0.0;    // [N m s/rad]: the rates matter
  b.AddJoint(ball);
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  Model model = b.Build();
  model.rod_inertia = RodInertia::kConstant;
  ASSERT_EQ(model.nc, 6);
  std::vector<SensitivityOutput> outputs;
  for (int c = 0; c < 3; ++c)
    outputs.push_back({OutputKind::kPointPosition, body, c, Vec3(0.05, 0.01, 0.0)});
  const std::vector<Parameter> params = {{ParameterKind::kTendonTension, 0, -1},
                                         {ParameterKind::kRodStiffness, 0, -1},
                                         {ParameterKind::kRodMass, 0, -1}};
  CheckAgainstWholeRuns(model, outputs, params, {1e-3, 1e-4, 1e-4}, RunOptions(), 4);
}

// A finger drawn by a length-driven tendon 2 cm off its axis (the arm of MakeArm): the
// prescribed length shortens piecewise-linearly (knots every 10 ms: restarts, each with the
// tendon's inelastic catch), the tendon stays taut, its tension the multiplier. Parameters:
// the length (a ramp and a knot), the stiffness, the mass, the tip load and the tendon's
// offset from the centreline.
Arm MakeLengthFinger(RodInertia inertia) {
  ModelBuilder b;
  Vec6 k, m;
  k << 1e3, 1e3, 1e3, 1.0, 1.0, 1.0;
  m << 1e-2, 1e-2, 1e-2, 1e-6, 1e-6, 2e-6;
  Section section = Section::FromDiagonals(k, m);
  section.rayleigh_stiffness = inertia == RodInertia::kConstant ? 0.0 : 1e-5;
  const RodId rod = b.AddStraightRod("finger", Vec3::Zero(), Vec3::UnitX(), 4, section);
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  std::vector<BodyPoint> eyelets;
  for (NodeId n : nodes) eyelets.push_back({n, Vec3(0.0, 0.02, 0.0)});
  b.AddLengthDrivenTendon(
      "pull", eyelets,
      Profile::Table({0.0, 0.01, 0.02, 0.03, 0.04}, {1.0, 0.998, 0.995, 0.994, 0.994}));
  PointLoad load;
  load.node = nodes.back();
  load.force = Vec3(0.0, 0.0, 0.02);
  b.AddPointLoad(load);
  Arm arm{b.Build(), nodes.back()};
  arm.model.rod_inertia = inertia;
  return arm;
}

std::vector<Parameter> FingerParameters() {
  Parameter ramp{ParameterKind::kTendonLength, 0, -1};
  ramp.shape = Profile::Table({0.0, 0.04}, {0.0, -1.0});
  Parameter knot{ParameterKind::kTendonLength, 0, -1};
  knot.shape = Profile::Table({0.0, 0.01, 0.02, 0.03}, {0.0, 0.0, 1.0, 0.0});
  return {ramp,
          knot,
          {ParameterKind::kRodStiffness, 0, -1},
          {ParameterKind::kRodMass, 0, -1},
          {ParameterKind::kPointLoad, 0, 2},
          {ParameterKind::kTendonOffset, 0, 1}};
}

TEST(DynamicSensitivity, LengthDrivenFingerThroughBreakpointsMatchesWholeRuns) {
  const Arm finger = MakeLengthFinger(RodInertia::kConstant);
  ASSERT_EQ(finger.model.nc, 1);
  const DynamicSensitivityOptions o = RunOptions();
  const Eigen::MatrixXd y = Trajectory(finger.model, TipOutputs(finger.tip), o);
  EXPECT_GT(std::abs(y(o.steps, 1) - y(0, 1)), 0.005);  // it curls
  CheckAgainstWholeRuns(finger.model, TipOutputs(finger.tip), FingerParameters(),
                        {1e-6, 1e-6, 1e-6, 1e-6, 1e-5, 1e-6}, o, 4);
}

// Option A's inertia with Rayleigh damping (the residual's derivatives by differences).
TEST(DynamicSensitivity, DampedLengthDrivenFingerMatchesWholeRuns) {
  const Arm finger = MakeLengthFinger(RodInertia::kExact);
  CheckAgainstWholeRuns(finger.model, TipOutputs(finger.tip), FingerParameters(),
                        {1e-6, 1e-6, 1e-6, 1e-6, 1e-5, 1e-6}, RunOptions(), 4);
}

TEST(DynamicSensitivity, StabilisedIndexTwoIsRefused) {
  const Jointed arm = MakeJointedArm();
  DynamicSensitivityOptions o = RunOptions();
  o.dynamics.constraints = ConstraintFormulation::kGgl;
  Data d = MakeData(arm.model);
  const DynamicSensitivity s = CalcDynamicSensitivity(
      arm.model, d, {{ParameterKind::kRodStiffness, 0, -1}},
      {{OutputKind::kPointPosition, arm.body, 0, Vec3::Zero()}}, {}, SensitivityMode::kForward, o);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.message,
            "constraints: ggl (stabilised index 2, the default of models without rods) is not "
            "differentiated; run with constraints: index3");
}

}  // namespace
}  // namespace screwfem::dynamic_sensitivity_test
