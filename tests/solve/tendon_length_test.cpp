// Length-driven tendons (model.h TendonDrive::kLength, docs/numerics.md, "Tendons and force elements"): the rheonomic
// constraint L(q) = L_p(t) whose multiplier is the tension, and the slack rule (the tension is
// never negative: the row is released when it would be, and re-activated when the route's
// length reaches L_p; docs/numerics.md "Length-driven tendons").
//
// Closed forms: a mass on a vertical slider hanging on a tendon routed over two ground eyelets
// (tension m (g + z''), position z = 2 - L_p); the straight cantilever tendon (the multiplier of
// the length that a prescribed tension produces is that tension, and the tip is the discrete
// model's value of docs/numerics.md T4.3); free fall while slack.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/statics.h"

namespace screwfem::tendon_length_test {
namespace {

constexpr double kG = 9.81;
constexpr double kMass = 2.0;
constexpr double kPi = 3.14159265358979323846;

// A body of mass kMass at the origin on a vertical slider, gravity -z, hanging on a tendon
// from the ground eyelets (-1, 0, 1) and (0, 0, 1) to the body's origin: L = 1 + (1 - z), so
// z = 2 - L_p while taut (reference length 2).
Model HangingMass(const Profile& length) {
  ModelBuilder b;
  const NodeId n = b.AddNode(SE3::Identity(), "mass");
  b.AddRigidBody("mass", n, kMass, Vec3::Zero(), 0.01 * Mat3::Identity());
  b.AddJointAt("slide", JointType::kPrismatic, kGround, n, Vec3::Zero(), Vec3::UnitZ());
  b.SetGravity(Vec3(0.0, 0.0, -kG));
  b.AddLengthDrivenTendon(
      "cable", {{kGround, Vec3(-1.0, 0.0, 1.0)}, {kGround, Vec3(0.0, 0.0, 1.0)}, {n, Vec3::Zero()}},
      length);
  return b.Build();
}

double Height(const Data& d) { return d.H[0].x.z(); }

TEST(LengthDrivenTendon, StaticTensionCarriesTheHangingWeight) {
  const Model m = HangingMass(Profile::Constant(2.3));
  ASSERT_EQ(m.tendons[0].row, m.nc - 1);  // after the slider's rows
  EXPECT_DOUBLE_EQ(m.tendons[0].reference_length, 2.0);
  Data d = MakeData(m);
  StaticOptions opt;
  const StaticResult r = SolveStatic(m, d, opt);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_NEAR(Height(d), 2.0 - 2.3, 1e-10);
  const LineForceState s = CalcTendonState(m, d, 0);
  EXPECT_NEAR(s.length, 2.3, 1e-10);
  EXPECT_NEAR(s.force, kMass * kG, 1e-8 * kMass * kG);
}

TEST(LengthDrivenTendon, StaticSlackRuleOnASpringSupportedMass) {
  // The hanging mass also rests on a spring k in its slider; the cable is let out to 2.3 m.
  // Stiff spring (m g / k = 0.098 m < 0.3 m): the mass stops above the cable's reach and the
  // tendon is slack (tension 0). Soft spring (m g / k = 0.981 m): the cable holds the mass at
  // z = -0.3 with tension m g - 0.3 k.
  for (const double k : {200.0, 20.0}) {
    SCOPED_TRACE("k = " + std::to_string(k));
    ModelBuilder b;
    const NodeId n = b.AddNode(SE3::Identity(), "mass");
    b.AddRigidBody("mass", n, kMass, Vec3::Zero(), 0.01 * Mat3::Identity());
    const JointId j =
        b.AddJointAt("slide", JointType::kPrismatic, kGround, n, Vec3::Zero(), Vec3::UnitZ());
    b.model().joints[j].stiffness(0) = k;
    b.SetGravity(Vec3(0.0, 0.0, -kG));
    b.AddLengthDrivenTendon(
        "cable",
        {{kGround, Vec3(-1.0, 0.0, 1.0)}, {kGround, Vec3(0.0, 0.0, 1.0)}, {n, Vec3::Zero()}},
        Profile::Constant(2.3));
    const Model m = b.Build();
    Data d = MakeData(m);
    const StaticResult r = SolveStatic(m, d, StaticOptions{});
    ASSERT_TRUE(r.converged) << r.message;
    const bool slack = kMass * kG / k < 0.3;
    EXPECT_EQ(d.tendon_slack[0], slack ? 1 : 0);
    EXPECT_NEAR(Height(d), slack ? -kMass * kG / k : -0.3, 1e-9);
    EXPECT_NEAR(CalcTendonState(m, d, 0).force, slack ? 0.0 : kMass * kG - 0.3 * k, 1e-8);
  }
}

TEST(LengthDrivenTendon, GradientRowIsTheLengthGradient) {
  // Three free bodies, eyelets offset from their frames and one on the ground: the tendon's
  // row of B(q) against central differences of L(q) through the retraction.
  ModelBuilder b;
  std::vector<BodyPoint> eyelets = {{kGround, Vec3(-0.4, 0.2, 0.1)}};
  const Vec3 offsets[3] = {Vec3(0.03, -0.05, 0.02), Vec3(-0.04, 0.06, 0.01),
                           Vec3(0.02, 0.0, -0.07)};
  for (int i = 0; i < 3; ++i) {
    const NodeId n = b.AddNode(SE3::Translation(Vec3(0.5 * i, 0.1 * i, 0.0)));
    b.AddRigidBody("b" + std::to_string(i), n, 1.0, Vec3::Zero(), Mat3::Identity());
    eyelets.push_back({n, offsets[i]});
  }
  b.AddLengthDrivenTendon("t", eyelets, Profile::Constant(1.0));
  const Model m = b.Build();
  Data d = MakeData(m);
  for (std::size_t i = 0; i < d.H.size(); ++i)
    d.H[i] = d.H[i] * ExpSE3((Vec6() << 0.05 * i, -0.03, 0.02, 0.3, -0.2 * i, 0.4).finished());
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(m.nc, m.nv);
  CalcConstraintGradient(m, d, B);
  const double eps = 1e-6;
  Eigen::RowVectorXd fd(m.nv);
  for (int j = 0; j < m.nv; ++j) {
    Data p = d, q = d;
    const Vec6 dh = eps * Vec6::Unit(j % 6);
    p.H[static_cast<std::size_t>(j / 6)] = p.H[static_cast<std::size_t>(j / 6)] * ExpSE3(dh);
    q.H[static_cast<std::size_t>(j / 6)] = q.H[static_cast<std::size_t>(j / 6)] * ExpSE3(-dh);
    fd(j) = (CalcTendonLength(m, p, 0) - CalcTendonLength(m, q, 0)) / (2.0 * eps);
  }
  EXPECT_LT((B.row(0) - fd).norm(), 1e-8 * fd.norm());
  // The velocity constraint is the length's rate (L_p constant).
  d.v.setLinSpaced(m.nv, -1.0, 1.0);
  Eigen::VectorXd bv(m.nc);
  CalcVelocityConstraint(m, d, 0.0, bv);
  EXPECT_NEAR(bv(0), CalcTendonState(m, d, 0).rate, 1e-12);
}

TEST(LengthDrivenTendon, StraightCantileverEffortIsTheTensionThatGivesTheLength) {
  // docs/numerics.md T4.3: L = 1, EA = GA = 1e5, EI = GJ = 1, 4 elements, eyelets at every node
  // 0.02 m from the axis (section y), tau = 50: tip (0.729126, 0.572854). Drawn by tension,
  // the tendon's length is L*; drawn to L* by length, the multiplier is 50 and the shape the same.
  const auto solve = [](bool by_length, double value, Data* out) {
    ModelBuilder b;
    Vec6 stiffness, inertia;
    stiffness << 1e5, 1e5, 1e5, 1.0, 1.0, 1.0;
    inertia << 1.0, 1.0, 1.0, 1.0, 1.0, 1.0;
    const RodId rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3::UnitX(), 4,
                                       Section::FromDiagonals(stiffness, inertia));
    const std::vector<NodeId> nodes = b.RodNodes(rod);
    b.FixNode(nodes.front());
    std::vector<BodyPoint> eyelets;
    for (int n : nodes) eyelets.push_back({n, Vec3(0.0, 0.02, 0.0)});
    if (by_length)
      b.AddLengthDrivenTendon("t", eyelets, Profile::Constant(value));
    else
      b.AddTendon("t", eyelets, Profile::Constant(value));
    const Model m = b.Build();
    *out = MakeData(m);
    StaticOptions opt;
    opt.load_steps = 40;  // a follower-like load (docs/numerics.md, "Tendons and force elements")
    const StaticResult r = SolveStatic(m, *out, opt);
    EXPECT_TRUE(r.converged) << r.message;
    return m;
  };
  Data by_tension, by_length;
  const Model mt = solve(false, 50.0, &by_tension);
  const double length = CalcTendonState(mt, by_tension, 0).length;
  const Model ml = solve(true, length, &by_length);
  const Vec3 tip_t = by_tension.H.back().x, tip_l = by_length.H.back().x;
  EXPECT_NEAR(tip_t.x(), 0.729126, 1e-6);
  EXPECT_NEAR(tip_t.y(), 0.572854, 1e-6);
  EXPECT_LT((tip_l - tip_t).norm(), 1e-9);
  EXPECT_NEAR(CalcTendonState(ml, by_length, 0).force, 50.0, 1e-6);
}

TEST(LengthDrivenTendon, DynamicTensionIsMassTimesGravityPlusAcceleration) {
  // L_p = 2 + A (1 - cos w t): z = -A (1 - cos w t), tension m (g - A w^2 cos w t) > 0.
  const double A = 0.05, f = 1.0, w = 2.0 * kPi * f;
  Profile length = Profile::Constant(2.0 + A);
  length.Add(Profile::Sine(-A, f, 0.5 * kPi));
  const Model m = HangingMass(length);
  Data d = MakeData(m);
  Integrator integ;
  DynamicOptions opt;
  opt.rho_inf = 0.8;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(m, d, integ, opt, &message)) << message;
  EXPECT_NEAR(CalcTendonState(m, d, 0).force, kMass * (kG - A * w * w), 1e-9);
  const double h = 2e-3;
  double max_z_error = 0.0, max_tension_error = 0.0;
  for (int i = 0; i < 500; ++i) {
    ASSERT_TRUE(Step(m, d, integ, h).ok);
    const double t = d.time;
    max_z_error = std::max(max_z_error, std::abs(Height(d) + A * (1.0 - std::cos(w * t))));
    max_tension_error = std::max(
        max_tension_error,
        std::abs(CalcTendonState(m, d, 0).force - kMass * (kG - A * w * w * std::cos(w * t))));
  }
  EXPECT_LT(max_z_error, 1e-9);  // the constraint holds at every step
  // The multiplier of generalized-alpha is second-order accurate: |error| ~ h^2 A w^4 m.
  EXPECT_LT(max_tension_error, 1e-3 * kMass * kG);
}

TEST(LengthDrivenTendon, SlackTendonLetsTheMassFallAndCatchesItAgain) {
  // The cable pays out at 0.5 m/s for 0.2 s (L_p = 2 + Ramp to 0.1): faster than the mass can
  // follow from rest, so the tendon goes slack at once and the mass falls freely (z'' = -g)
  // until its route reaches L_p (g t^2 / 2 = 0.5 t near t = 0.102 s); then the tendon catches it
  // inelastically (the mass moves on with the cable, 0.5 m/s down) and holds it at z = 2 - L_p;
  // when the cable stops at 0.2 s it stops the mass inelastically too: at rest at z = -0.1
  // with tension m g.
  Profile length = Profile::Constant(2.0);
  length.Add(Profile::Ramp(0.0, 0.2, 0.1));
  const Model m = HangingMass(length);
  Data d = MakeData(m);
  Integrator integ;
  DynamicOptions opt;
  opt.rho_inf = 0.5;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(m, d, integ, opt, &message)) << message;
  const double h = 1e-3;
  double fall_start_t = -1.0, fall_start_v = 0.0, caught_at = -1.0;
  for (int i = 0; i < 600; ++i) {
    const char was_slack = d.tendon_slack[0];
    ASSERT_TRUE(Step(m, d, integ, h).ok) << "t = " << d.time;
    const double t = d.time;
    const LineForceState s = CalcTendonState(m, d, 0);
    const double target = 2.0 + 0.1 * std::min(1.0, t / 0.2);
    EXPECT_GE(s.force, 0.0) << "t = " << t;             // never pushes
    EXPECT_LE(s.length, target + 1e-9) << "t = " << t;  // never longer than the cable
    if (d.tendon_slack[0]) {
      // Free fall: after the restart at the switch, z'' = -g exactly and v falls by g t.
      EXPECT_EQ(s.force, 0.0);
      EXPECT_NEAR(d.vdot(2), -kG, 1e-9) << "t = " << t;
      if (fall_start_t < 0.0) {
        fall_start_t = t;
        fall_start_v = d.v(2);
      }
      EXPECT_NEAR(d.v(2), fall_start_v - kG * (t - fall_start_t), 1e-9) << "t = " << t;
    } else if (was_slack) {
      caught_at = t;
      // The catch: the mass moves on with the cable (zero restitution), the route at L_p.
      EXPECT_NEAR(d.v(2), -0.5, 1e-9);
      EXPECT_NEAR(s.length, target, 1e-9);
    }
    if (caught_at > 0.0) {
      EXPECT_EQ(d.tendon_slack[0], 0) << "t = " << t;  // taut from then on
      EXPECT_NEAR(s.length, target, 1e-9) << "t = " << t;
    }
  }
  EXPECT_NEAR(fall_start_t, h, 1e-12);  // slack in the first step
  EXPECT_GT(caught_at, 0.1);
  EXPECT_LT(caught_at, 0.106);
  EXPECT_EQ(integ.tendon_switches, 2);  // slack, taut
  EXPECT_EQ(integ.tendon_catches, 2);   // caught at ~0.102 s; stopped with the cable at 0.2 s
  EXPECT_NEAR(d.v(2), 0.0, 1e-9);
  EXPECT_NEAR(Height(d), -0.1, 1e-9);
  EXPECT_NEAR(CalcTendonState(m, d, 0).force, kMass * kG, 1e-6 * kMass * kG);
}

TEST(LengthDrivenTendon, ErrorControlledStepsCatchTheMassToo) {
  // The run above with error-controlled steps (AdvanceTo): the same slack phase, catch and
  // stop, ending at rest on the cable.
  Profile length = Profile::Constant(2.0);
  length.Add(Profile::Ramp(0.0, 0.2, 0.1));
  const Model m = HangingMass(length);
  Data d = MakeData(m);
  Integrator integ;
  DynamicOptions opt;
  opt.rho_inf = 0.5;
  opt.absolute_tolerance = opt.relative_tolerance = 1e-6;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(m, d, integ, opt, &message)) << message;
  ASSERT_TRUE(AdvanceTo(m, d, integ, 0.1).ok);
  EXPECT_EQ(d.tendon_slack[0], 1);
  ASSERT_TRUE(AdvanceTo(m, d, integ, 0.3).ok);
  EXPECT_EQ(integ.tendon_switches, 2);
  EXPECT_EQ(integ.tendon_catches, 2);
  EXPECT_EQ(d.tendon_slack[0], 0);
  EXPECT_NEAR(Height(d), -0.1, 1e-9);
  EXPECT_NEAR(d.v(2), 0.0, 1e-9);
  EXPECT_NEAR(CalcTendonState(m, d, 0).force, kMass * kG, 1e-6 * kMass * kG);
}

}  // namespace
}  // namespace screwfem::tendon_length_test
