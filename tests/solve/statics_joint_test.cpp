// Static equilibrium with joints (statics.h, elements/joint.h): a rigid pendulum
// held by a soft revolute joint under gravity, and prescribed, force and series-elastic drives
// evaluated at StaticOptions::time.
//
// Pendulum: one node at the pivot (the origin), a rigid body of mass m with its CoM at
// (-l, 0, 0) in the node frame, a revolute joint about +z to the ground, gravity g along -y.
// The joint angle alpha turns the bar about +z, so the CoM is at (-l cos a, -l sin a) and the
// potential is V = 1/2 K a^2 - m g l sin a: equilibrium K a = m g l cos a.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::statics_joint_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMass = 1.3, kL = 0.8, kG = 9.81;

int AddPendulum(ModelBuilder& b, double com_sign) {
  const NodeId node = b.AddNode(SE3::Identity(), "pivot");
  b.AddRigidBody("bob", node, kMass, Vec3(com_sign * kL, 0.0, 0.0), 1e-3 * Mat3::Identity());
  b.SetGravity(Vec3(0.0, -kG, 0.0));
  return b.AddJointAt("pin", JointType::kRevolute, kGround, node, Vec3::Zero(), Vec3::UnitZ());
}

// Root of K a = m g l cos a by Newton (unique for K > 0 on (0, pi/2)).
double EquilibriumAngle(double K) {
  double a = 0.5;
  for (int i = 0; i < 50; ++i)
    a -= (K * a - kMass * kG * kL * std::cos(a)) / (K + kMass * kG * kL * std::sin(a));
  return a;
}

double NodeAngle(const Data& d) { return std::atan2(d.H[0].R(1, 0), d.H[0].R(0, 0)); }

TEST(StaticsWithJoints, SoftRevolutePendulumSettlesWhereTheSpringBalancesGravity) {
  for (double K : {50.0, 10.0, 3.0}) {  // equilibrium angles 0.200, 0.748, 1.208 rad
    SCOPED_TRACE("K = " + std::to_string(K));
    ModelBuilder b;
    const int j = AddPendulum(b, -1.0);
    b.model().joints[j].stiffness(0) = K;
    const Model m = b.Build();
    Data d = MakeData(m);
    const StaticResult r = SolveStatic(m, d);
    ASSERT_TRUE(r.converged) << r.message;
    const double a = EquilibriumAngle(K);
    EXPECT_NEAR(d.q_joint(0), a, 1e-9);
    EXPECT_NEAR(K * d.q_joint(0), kMass * kG * kL * std::cos(d.q_joint(0)), 1e-8);
    EXPECT_NEAR(NodeAngle(d), a, 1e-9);
    EXPECT_LT(d.H[0].x.norm(), 1e-12);
    EXPECT_LT(MaxConstraintViolation(m, d, 0.0, 1.0), 1e-10);
  }
}

// A load step that runs out of Newton iterations names all three criteria: the force residual,
// the constraint residual against its tolerance and the last scaled increment (a step held
// back by its constraints or its increment used to read "residual 0").
TEST(StaticsWithJoints, NonConvergenceMessageNamesEveryCriterion) {
  ModelBuilder b;
  const int j = AddPendulum(b, -1.0);
  b.model().joints[j].stiffness(0) = 3.0;  // swings to 1.208 rad
  const Model m = b.Build();
  Data d = MakeData(m);
  StaticOptions opt;
  opt.load_steps = 1;
  opt.max_halvings = 0;
  opt.max_iterations = 1;
  const StaticResult r = SolveStatic(m, d, opt);
  ASSERT_FALSE(r.converged);
  for (const char* part : {"Newton did not converge in 1 iterations (force residual ",
                           "; constraint residual ", ", tolerance ", "; last scaled increment "})
    EXPECT_NE(r.message.find(part), std::string::npos) << part << " in: " << r.message;
}

// A prescribed drive is a rheonomic constraint alpha = s q(t) (s = load factor); SolveStatic
// evaluates it at options.time. Its effort holds the weight: tau = m g l cos q for a bob at
// (+l, 0, 0) (torque about +z applied to the bar).
TEST(StaticsWithJoints, PrescribedDriveMovesTheJointToTheProfileValueAtTheGivenTime) {
  ModelBuilder b;
  const int j = AddPendulum(b, 1.0);
  Joint& joint = b.model().joints[j];
  joint.drive = DriveKind::kPrescribed;
  joint.drive_profile = Profile::BangBang(0.0, 1.0, kPi / 6);
  const Model m = b.Build();
  for (double t : {0.25, 0.5, 0.75, 2.0}) {
    SCOPED_TRACE("t = " + std::to_string(t));
    Data d = MakeData(m);
    StaticOptions opt;
    opt.time = t;
    const StaticResult r = SolveStatic(m, d, opt);
    ASSERT_TRUE(r.converged) << r.message;
    const double q = m.joints[0].drive_profile(t);
    EXPECT_NEAR(d.q_joint(0), q, 1e-12);
    EXPECT_NEAR(NodeAngle(d), q, 1e-12);
    EXPECT_NEAR(JointDriveEffort(m, d, 0), kMass * kG * kL * std::cos(q), 1e-9);
  }
}

// A force drive adds -f(t) to the coordinate equation: with a spring, K a = f (+ gravity).
TEST(StaticsWithJoints, ForceDriveIsBalancedByTheJointSpring) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "slider");
  b.AddRigidBody("slider", node, 2.0, Vec3(0.1, 0.2, 0.0), 1e-2 * Mat3::Identity());
  const Vec3 e = Vec3(1.0, 1.0, 0.0).normalized();
  const JointId j = b.AddJointAt("slide", JointType::kPrismatic, kGround, node, Vec3::Zero(), e);
  Joint& joint = b.model().joints[j];
  joint.stiffness(0) = 40.0;
  joint.drive = DriveKind::kForce;
  joint.drive_profile = Profile::Ramp(0.0, 1.0, 12.0);
  b.SetGravity(Vec3(0.0, -kG, 0.0));
  const Model m = b.Build();
  Data d = MakeData(m);
  StaticOptions opt;
  opt.time = 0.5;  // f = 6 N along e
  ASSERT_TRUE(SolveStatic(m, d, opt).converged);
  // K a = f + m g_vec . e
  const double expected = (6.0 + 2.0 * Vec3(0.0, -kG, 0.0).dot(e)) / 40.0;
  EXPECT_NEAR(d.q_joint(0), expected, 1e-10);
  EXPECT_LT((d.H[0].x - expected * e).norm(), 1e-10);
}

// A series-elastic drive is a spring towards s q(t) + rest; its effort is the spring force,
// which holds the weight.
TEST(StaticsWithJoints, SeriesElasticDriveSettlesWithSpringDeflectionCarryingTheWeight) {
  ModelBuilder b;
  const int j = AddPendulum(b, 1.0);
  Joint& joint = b.model().joints[j];
  joint.stiffness(0) = 20.0;
  joint.drive = DriveKind::kSeriesElastic;
  joint.drive_profile = Profile::BangBang(0.0, 1.0, kPi / 3);
  const Model m = b.Build();
  Data d = MakeData(m);
  StaticOptions opt;
  opt.time = 1.0;  // q = pi/3
  ASSERT_TRUE(SolveStatic(m, d, opt).converged);
  const double a = d.q_joint(0);
  // K (q - a) = m g l cos a: the spring lags the motor by the weight's torque.
  EXPECT_NEAR(20.0 * (kPi / 3 - a), kMass * kG * kL * std::cos(a), 1e-8);
  EXPECT_GT(kPi / 3 - a, 0.1);
  d.time = opt.time;
  EXPECT_NEAR(JointDriveEffort(m, d, 0), kMass * kG * kL * std::cos(a), 1e-8);
}

}  // namespace
}  // namespace screwfem::statics_joint_test
