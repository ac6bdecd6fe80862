// Validation J2 (docs/validation.md): joints driven by a prescribed bang-bang motion; the drive's
// multiplier is the actuator effort.
//
// A single rigid link (the seed paper's: m = 0.15 kg, J = 1e-4 kg m^2 about the CoM, CoM at
// l_c = 0.25 m along the node's x axis) in the vertical x-y plane, gravity g = 9.81 m/s^2
// along -y, driven from the ground at the node by
//   (a) a revolute joint about +z with q(t) = BangBang(0, 1 s, pi/6) ([G] Table III, q0):
//       q is the angle of the link from the horizontal +x axis, counter-clockwise. The torque
//       about +z that the actuator applies to the link is
//         tau(t) = (J + m l_c^2) q''(t) + m g l_c cos q(t);
//   (b) a prismatic joint along e = (cos 1.1903, sin 1.1903, 0) (the direction of [G]'s joint
//       3) with q(t) = BangBang(0, 1 s, 0.75 m) (Table III, q3). The force along +e that the
//       actuator applies to the link is F(t) = m q''(t) - m g_vec . e = m (q'' + g e_y).
// JointDriveEffort returns exactly these (it is -lambda_act: the drive row's multiplier enters
// the coordinate equation as +lambda_act, and the coordinate equation balances the wrench that
// the joint transmits to the link).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "screwfem/elements/joint.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::actuated_joint_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMass = 0.15, kJc = 1e-4, kLc = 0.25, kG = 9.81;
const double kPrismaticAngle = 1.1903;

struct Drive {
  JointType type;
  double stroke;  // q_f [rad or m]
  Vec3 axis;
};

const Drive kRevolute{JointType::kRevolute, kPi / 6, Vec3::UnitZ()};
const Drive kPrismatic{JointType::kPrismatic, 0.75,
                       Vec3(std::cos(kPrismaticAngle), std::sin(kPrismaticAngle), 0.0)};

struct Link {
  Model model;
  Data data;
  Integrator integ;
  int joint = 0, coord = 0;
  Profile q;
};

void MakeLink(Link* l, const Drive& drive, double rho_inf, bool restart = true) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "link");
  b.AddRigidBody("link", node, kMass, Vec3(kLc, 0.0, 0.0), kJc * Mat3::Identity());
  l->joint = b.AddJointAt("q", drive.type, kGround, node, Vec3::Zero(), drive.axis);
  Joint& j = b.model().joints[static_cast<std::size_t>(l->joint)];
  l->q = Profile::BangBang(0.0, 1.0, drive.stroke);
  j.drive = DriveKind::kPrescribed;
  j.drive_coord = 0;
  j.drive_profile = l->q;
  b.SetGravity(Vec3(0.0, -kG, 0.0));
  l->model = b.Build();
  l->data = MakeData(l->model);
  l->coord = l->model.joints[0].coord;
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  opt.restart_at_breakpoints = restart;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(l->model, l->data, l->integ, opt, &message)) << message;
}

// The exact effort at time t (right limits of the profile at its switches).
double ExactEffort(const Drive& drive, const Profile& q, double t) {
  const ProfileValue p = q.Eval(t);
  if (drive.type == JointType::kRevolute)
    return (kJc + kMass * kLc * kLc) * p.accel + kMass * kG * kLc * std::cos(p.value);
  return kMass * (p.accel + kG * drive.axis.y());
}

TEST(ActuatedJointJ2, ConsistentStartHasTheRightLimitOfTheProfileAcceleration) {
  for (const Drive& drive : {kRevolute, kPrismatic}) {
    SCOPED_TRACE(JointTypeName(drive.type));
    Link l;
    MakeLink(&l, drive, 0.9);
    // q''(0+) = 4 q_f / T^2: 2 pi / 3 = 2.0944 rad/s^2 (docs/numerics.md), 3 m/s^2.
    EXPECT_NEAR(l.data.vdot(l.coord), 4.0 * drive.stroke, 1e-12);
    if (drive.type == JointType::kRevolute) {
      EXPECT_NEAR(l.data.vdot(l.coord), 2.0944, 1e-4);
    }
    EXPECT_NEAR(JointDriveEffort(l.model, l.data, l.joint), ExactEffort(drive, l.q, 0.0), 1e-12);
  }
}

// Effort error statistics over a run of 1.5 s: the largest |effort - exact| on steps that are
// at least `settle` after an acceleration jump (t = 0.5 s, 1 s; the start is consistent), the
// time integral of |effort - exact| over the 0.1 s after each jump, the settling time after
// the jump at 0.5 s (last step with |error| > 1e-6 of the effort scale), and |q - q(t)|.
struct Tracking {
  double effort_error = 0.0, impulse_error = 0.0, settle_time = 0.0, final_error = 0.0;
  double position_error = 0.0, effort_scale = 0.0;
};

Tracking Track(const Drive& drive, double rho_inf, double h, double settle = 0.1,
               bool restart = true) {
  Link l;
  MakeLink(&l, drive, rho_inf, restart);
  Tracking r;
  const double scale = std::abs(ExactEffort(drive, l.q, 0.0));
  r.effort_scale = scale;
  const int steps = static_cast<int>(std::lround(1.5 / h));
  for (int n = 1; n <= steps; ++n) {
    const StepResult s = Step(l.model, l.data, l.integ, h);
    EXPECT_TRUE(s.ok) << s.message;
    if (!s.ok) break;
    const double t = n * h;
    r.position_error = std::max(r.position_error, std::abs(l.data.q_joint(0) - l.q(t)));
    const double err =
        std::abs(JointDriveEffort(l.model, l.data, l.joint) - ExactEffort(drive, l.q, t));
    r.final_error = err;
    bool transient = false;
    for (double tj : {0.5, 1.0}) {
      // The step that ends at a jump belongs to the interval before it (left limit).
      if (t > tj + 0.5 * h && t < tj + settle) {
        transient = true;
        r.impulse_error += h * err;
      }
    }
    if (t > 0.5 + 0.5 * h && t < 1.0 && err > 1e-6 * scale) r.settle_time = t - 0.5;
    const bool at_jump = std::abs(t - 0.5) < 0.5 * h || std::abs(t - 1.0) < 0.5 * h;
    if (!transient && !at_jump) r.effort_error = std::max(r.effort_error, err);
  }
  // The link follows its coordinate (frame consistent with the joint).
  const SE3& H = l.data.H[0];
  if (drive.type == JointType::kRevolute)
    EXPECT_NEAR(std::atan2(H.R(1, 0), H.R(0, 0)), l.q(1.5), 1e-10);
  else
    EXPECT_LT((H.x - l.q(1.5) * drive.axis).norm(), 1e-10);
  return r;
}

// The prescribed coordinate is exact at every step (to the Newton tolerance) and, away from
// the jumps of q'', the effort equals the closed form to round-off: the bang-bang q(t) is
// piecewise quadratic, which generalized-alpha integrates exactly (measured error <= 5e-8 of
// the effort scale; at t = 0 there is no transient because the start uses the right limit).
TEST(ActuatedJointJ2, PositionFollowsTheProfileAndEffortMatchesTheClosedFormAwayFromJumps) {
  for (const Drive& drive : {kRevolute, kPrismatic}) {
    SCOPED_TRACE(JointTypeName(drive.type));
    for (double h : {1e-3, 5e-4}) {
      const Tracking r = Track(drive, 0.8, h);
      EXPECT_LT(r.position_error, 1e-10);
      EXPECT_LT(r.effort_error, 1e-6 * r.effort_scale) << "h = " << h;
    }
  }
}

// Without restarts at the breakpoints (DynamicOptions::restart_at_breakpoints = false, the
// behaviour before issue 14): right after each jump of q'' the multiplier (and q'' of the
// scheme) carries a transient of generalized-alpha (docs/architecture.md, "One time step"): its first values are of the size of the jump whatever h,
// but it decays by the spurious root (|.| <= rho_inf) per step, so its duration and its time
// integral (the impulse error) are O(h).
TEST(ActuatedJointJ2, EffortTransientAfterAccelerationJumpsLastsOh) {
  for (const Drive& drive : {kRevolute, kPrismatic}) {
    SCOPED_TRACE(JointTypeName(drive.type));
    const Tracking r1 = Track(drive, 0.8, 1e-3, 0.1, false);
    const Tracking r2 = Track(drive, 0.8, 5e-4, 0.1, false);
    EXPECT_GT(r1.impulse_error / r2.impulse_error, 1.8);
    EXPECT_LT(r1.impulse_error / r2.impulse_error, 2.2);
    EXPECT_GT(r1.settle_time / r2.settle_time, 1.7);
    EXPECT_LT(r1.settle_time / r2.settle_time, 2.3);
    EXPECT_LT(r1.settle_time, 0.1);
  }
}

// Without restarts and with rho_inf = 1 the transient is not damped at all: after the jump at 0.5 s the effort
// oscillates about the exact value with the amplitude of the jump until the end of the run.
// Restarts at the jumps remove the ringing (tests/validation/four_bar_test.cpp).
TEST(ActuatedJointJ2, EffortOscillationAfterAJumpIsUndampedWithRhoInfOne) {
  const Tracking r = Track(kRevolute, 1.0, 1e-3, 0.1, false);
  const double jump = 2.0 * (kJc + kMass * kLc * kLc) * 4.0 * kRevolute.stroke;  // J_O * 2a
  EXPECT_GT(r.final_error, 0.4 * jump);
  EXPECT_LT(r.position_error, 1e-10);  // the motion itself is still exact
}

// A series-elastic drive (spring K and damper D towards rest + q(t)) swinging the link: its
// effort is exactly minus the force the kernel puts on the coordinate's residual row
// (JointCoordinateSpringLaw, shared), it is K (q + rest - alpha) + D (q' - alpha'), and it is the
// torque that moves the link: (J + m l_c^2) alpha'' + m g l_c cos alpha.
TEST(ActuatedJointJ2, SeriesElasticEffortIsTheKernelsSpringForceAndMovesTheLink) {
  const double K = 2.0, D = 0.05, rest = 0.1;
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "link");
  b.AddRigidBody("link", node, kMass, Vec3(kLc, 0.0, 0.0), kJc * Mat3::Identity());
  const JointId joint =
      b.AddJointAt("q", JointType::kRevolute, kGround, node, Vec3::Zero(), Vec3::UnitZ());
  Joint& j = b.model().joints[joint];
  j.stiffness(0) = K;
  j.damping(0) = D;
  j.rest(0) = rest;
  j.drive = DriveKind::kSeriesElastic;
  j.drive_coord = 0;
  const Profile profile = Profile::BangBang(0.0, 1.0, kPi / 6);
  j.drive_profile = profile;
  b.SetGravity(Vec3(0.0, -kG, 0.0));
  const Model m = b.Build();
  Data d = MakeData(m);
  Integrator integ;
  DynamicOptions opt;
  opt.rho_inf = 0.8;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(m, d, integ, opt, &message)) << message;
  const int coord = m.joints[0].coord;
  double max_effort = 0.0;
  for (int i = 0; i < 600; ++i) {
    ASSERT_TRUE(Step(m, d, integ, 1e-3).ok);
    const double effort = JointDriveEffort(m, d, joint);
    JointCoordinateTerms terms;
    CalcJointCoordinateTerms(m, d, joint, d.time, 1.0, true, false, &terms);
    EXPECT_EQ(effort, 0.0 - terms.force(0)) << "t = " << d.time;
    EXPECT_EQ(JointCoordinateEffort(m, d, joint, 0), effort);
    const ProfileValue q = profile.Eval(d.time);
    const double alpha = d.q_joint(coord - m.nv_nodes), alpha_dot = d.v(coord);
    const double closed = K * (q.value + rest - alpha) + D * (q.rate - alpha_dot);
    EXPECT_NEAR(effort, closed, 1e-14 * (K + D));
    const double torque =
        (kJc + kMass * kLc * kLc) * d.vdot(coord) + kMass * kG * kLc * std::cos(alpha);
    EXPECT_NEAR(effort, torque, 1e-6 * kMass * kG * kLc) << "t = " << d.time;
    max_effort = std::max(max_effort, std::abs(effort));
  }
  EXPECT_GT(max_effort, 0.5 * kMass * kG * kLc);  // the spring carried the link
}

}  // namespace
}  // namespace screwfem::actuated_joint_test
