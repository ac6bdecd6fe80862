// Validation M2 (docs/validation.md): the heavy (Lagrange) top on a spherical joint.
//
// m = 15 kg, inertia about the CoM J = diag(0.234375, 0.46875, 0.234375) kg m^2 (symmetry axis
// = body y), CoM at (0, 1, 0) m from the fixed point, gravity (0, 0, -9.81), R(0) = I, body
// angular velocity W(0) = (0, 150, -4.61538) rad/s. Model: one node at the fixed point (frame
// = world at t = 0) carrying the body, a spherical joint from the ground at the origin. The
// node point does not move, so its translational body velocity is 0, and the joint rates of
// the spherical joint (rotation about the joint frame's axes, which coincide with the node
// frame) equal the body angular velocity: B v = 0.
//
// Integrator: rho_inf = 1 (no numerical dissipation), so the invariants' drift is the plain
// O(h^2) truncation error of generalized-alpha (with rho_inf = 0.9 the drifts were within 10 %
// of these, also O(h^2)).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

#include "screwfem/assemble/outputs.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::heavy_top_test {
namespace {

constexpr double kMass = 15.0;
const Vec3 kCom(0.0, 1.0, 0.0);
const Vec3 kOmega0(0.0, 150.0, -4.61538);
const Vec3 kGravity(0.0, 0.0, -9.81);

Mat3 InertiaAboutCom() { return Vec3(0.234375, 0.46875, 0.234375).asDiagonal(); }
// About the fixed point: J_O = J_c - m skew(c)^2 = diag(15.234375, 0.46875, 15.234375).
Mat3 InertiaAboutFixedPoint() { return InertiaAboutCom() - kMass * Skew(kCom) * Skew(kCom); }

struct Top {
  Model model;
  Data data;
  Integrator integ;
};

void MakeTop(Top* t, double rho_inf = 1.0) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "top");
  b.AddRigidBody("top", node, kMass, kCom, InertiaAboutCom());
  b.AddJointAt("fixed point", JointType::kSpherical, kGround, node, Vec3::Zero());
  b.SetGravity(kGravity);
  t->model = b.Build();
  t->data = MakeData(t->model);
  const int dof = t->model.nodes[0].dof, coord = t->model.joints[0].coord;
  t->data.v.segment<3>(dof).setZero();      // the node point is the fixed point
  t->data.v.segment<3>(dof + 3) = kOmega0;  // body angular velocity
  t->data.v.segment<3>(coord) = kOmega0;    // spherical joint rates (B v = 0)
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(t->model, t->data, t->integ, opt, &message)) << message;
}

Vec3 Omega(const Top& t) { return t.data.v.segment<3>(t.model.nodes[0].dof + 3); }
double Energy(const Top& t) { return CalcEnergy(t.model, t.data).total(); }
// Spatial angular momentum about the fixed point (the node origin stays at the world origin).
Vec3 AngularMomentum(const Top& t) { return t.data.H[0].R * (InertiaAboutFixedPoint() * Omega(t)); }

TEST(HeavyTopM2, InitialInvariantsMatchTheQuotedValues) {
  Top t;
  MakeTop(&t);
  EXPECT_NEAR(Energy(t), 5435.69679, 1e-5);
  EXPECT_NEAR(AngularMomentum(t).z(), -70.3124297, 1e-7);
  EXPECT_EQ(Omega(t).y(), 150.0);
  EXPECT_LT(MaxConstraintViolation(t.model, t.data, 0.0, 1.0), 1e-15);
}

// Kynema's "consistent initial acceleration" (0, -21.3017325444, -30.9608307692) is the world
// acceleration of the centre of mass (it equals w' x c + w x (w x c) with the angular
// acceleration below), not an angular acceleration: the angular acceleration is (661.346..., 0,
// 0) rad/s^2 from Euler's equations J_O w' = c x m R^T g - w x J_O w.
TEST(HeavyTopM2, ConsistentInitialAccelerationsMatchEulerAndKynema) {
  Top t;
  MakeTop(&t);
  const Mat3 Jo = InertiaAboutFixedPoint();
  const Vec3 torque = kCom.cross(kMass * kGravity);
  const Vec3 wdot = Jo.inverse() * (torque - kOmega0.cross(Jo * kOmega0));
  const Vec6 acc = t.data.vdot.segment<6>(t.model.nodes[0].dof);
  EXPECT_LT((acc.tail<3>() - wdot).norm(), 1e-9 * wdot.norm()) << acc.transpose();
  EXPECT_NEAR(wdot.x(), 661.34616923, 1e-7);
  EXPECT_LT(acc.head<3>().norm(), 1e-9);  // the node point is fixed
  // The joint rates accelerate with the body.
  EXPECT_LT((t.data.vdot.segment<3>(t.model.joints[0].coord) - wdot).norm(), 1e-9);
  const PointMotion com = CalcNodePointMotion(t.model, t.data, 0, kCom);
  EXPECT_NEAR(com.acceleration.x(), 0.0, 1e-9);
  EXPECT_NEAR(com.acceleration.y(), -21.3017325444, 1e-6);
  EXPECT_NEAR(com.acceleration.z(), -30.9608307692, 1e-6);
}

struct Drift {
  double energy = 0.0, lz = 0.0, spin = 0.0;  // largest relative deviations
};

Drift RunDrift(double h, double duration) {
  Top t;
  MakeTop(&t);
  const double E0 = Energy(t), L0 = AngularMomentum(t).z();
  Drift d;
  const int steps = static_cast<int>(std::lround(duration / h));
  for (int n = 0; n < steps; ++n) {
    const StepResult r = Step(t.model, t.data, t.integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) break;
    // One correction and one convergence check per step (exact tangent incl. the joint's).
    EXPECT_LE(r.iterations, 3);
    d.energy = std::max(d.energy, std::abs(Energy(t) - E0) / std::abs(E0));
    d.lz = std::max(d.lz, std::abs(AngularMomentum(t).z() - L0) / std::abs(L0));
    d.spin = std::max(d.spin, std::abs(Omega(t).y() - 150.0) / 150.0);
  }
  EXPECT_LT(MaxConstraintViolation(t.model, t.data, t.data.time, 1.0), 1e-12);
  return d;
}

TEST(HeavyTopM2, InvariantDriftConvergesAtSecondOrder) {
  const Drift d1 = RunDrift(1e-3, 1.0);
  const Drift d2 = RunDrift(5e-4, 1.0);
  // Energy and vertical angular momentum: O(h^2) drift (measured ratios 4.00 and 4.00).
  EXPECT_GT(d1.energy / d2.energy, 3.5);
  EXPECT_LT(d1.energy / d2.energy, 4.5);
  EXPECT_GT(d1.lz / d2.lz, 3.5);
  EXPECT_LT(d1.lz / d2.lz, 4.5);
  EXPECT_LT(d2.energy, 2e-5);  // measured 1.3e-5
  // The vertical momentum is the sensitive one: the 150 rad/s spin makes its error constant
  // large (measured 1.5e-2 relative at h = 5e-4, 3e-4 at h = 1e-4 — a bound of 1e-6 at
  // h = 1e-4 is out of reach for a second-order method on this problem).
  EXPECT_LT(d2.lz, 2e-2);
  // The spin is conserved to round-off: with J_x = J_z about the fixed point and the gravity
  // torque normal to the symmetry axis, its equation is w_y' = 0 and the scheme preserves it.
  EXPECT_LT(d1.spin, 1e-13);  // measured 0
  EXPECT_LT(d2.spin, 1e-13);
}

// An independent reference: classical RK4 on (R, w) with Euler's equations about the fixed
// point, R re-orthonormalised every step.
Mat3 ReferenceOrientation(double t_end, double h) {
  struct S {
    Mat3 R;
    Vec3 w;
  };
  const Mat3 Jo = InertiaAboutFixedPoint(), Jo_inv = Jo.inverse();
  auto f = [&](const S& s) {
    const Vec3 torque = kCom.cross(kMass * (s.R.transpose() * kGravity));
    return S{s.R * Skew(s.w), Jo_inv * (torque - s.w.cross(Jo * s.w))};
  };
  auto add = [](const S& a, const S& b, double c) { return S{a.R + c * b.R, a.w + c * b.w}; };
  S s{Mat3::Identity(), kOmega0};
  const int steps = static_cast<int>(std::lround(t_end / h));
  for (int n = 0; n < steps; ++n) {
    const S k1 = f(s), k2 = f(add(s, k1, h / 2)), k3 = f(add(s, k2, h / 2)), k4 = f(add(s, k3, h));
    s.R += h / 6 * (k1.R + 2 * k2.R + 2 * k3.R + k4.R);
    s.w += h / 6 * (k1.w + 2 * k2.w + 2 * k3.w + k4.w);
    const Eigen::JacobiSVD<Mat3> svd(s.R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    s.R = svd.matrixU() * svd.matrixV().transpose();
  }
  return s.R;
}

Mat3 FromEulerParameters(double e0, double e1, double e2, double e3) {
  return Eigen::Quaterniond(e0, e1, e2, e3).normalized().toRotationMatrix();
}

Mat3 SimulatedOrientation(double t_end, double h) {
  Top t;
  MakeTop(&t);
  const int steps = static_cast<int>(std::lround(t_end / h));
  for (int n = 0; n < steps; ++n) {
    const StepResult r = Step(t.model, t.data, t.integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) break;
  }
  return t.data.H[0].R;
}

TEST(HeavyTopM2, OrientationAtPoint2SecondsMatchesExudynRk4) {
  // Exudyn RK4 (h = 1e-4) at t = 0.2 s; q and -q are the same rotation.
  const Mat3 quoted = FromEulerParameters(-0.70828, 0.43878, 0.54573, 0.0894);
  // Our own RK4 reproduces the quoted values to their 5 printed digits.
  const Mat3 rk4 = ReferenceOrientation(0.2, 1e-4);
  EXPECT_LT((rk4 - quoted).norm(), 2e-5);  // measured 5.3e-6
  // Generalized-alpha (measured Frobenius error vs the RK4 reference: 1.28e-3 at h = 2e-4,
  // 3.2e-4 at h = 1e-4, ratio 4.00).
  const Mat3 R1 = SimulatedOrientation(0.2, 2e-4);
  const Mat3 R2 = SimulatedOrientation(0.2, 1e-4);
  EXPECT_LT((R2 - quoted).norm(), 1e-3);
  const double e1 = (R1 - rk4).norm(), e2 = (R2 - rk4).norm();
  EXPECT_LT(e2, 1e-3);
  EXPECT_GT(e1 / e2, 3.5);
  EXPECT_LT(e1 / e2, 4.5);
}

}  // namespace
}  // namespace screwfem::heavy_top_test
