// Validation M1 (docs/validation.md): the IFToMM simple pendulum (benchmark A01).
//
// A point mass of 1 kg on a massless bar of 1 m, pinned at the origin, gravity 9.81 m/s^2 along
// -y, released at rest from P = (-1, 0). Model: one node at the pivot carrying a rigid body
// with its centre of mass at (-1, 0, 0) and a negligible inertia (1e-10 kg m^2), held by a
// revolute joint about z to the ground. The joint coordinate alpha is the rotation of the bar
// about +z, so P = (-cos alpha, -sin alpha) and the angle from the downward vertical is
// theta = pi/2 - alpha.
//
// Exact: sin(theta/2) = k sn(K - w0 t | k^2), k = sin(pi/4), w0 = sqrt(g/L), period 4K/w0.
// Generalized-alpha with rho_inf = 1 (no numerical damping); its phase error is O((w0 h)^2).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"
#include "validation/elliptic.h"

namespace screwfem::pendulum_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kG = 9.81;
constexpr double kPeriod = 2.36784194758;  // docs/validation.md, M1

struct Pendulum {
  Model model;
  Data data;
  Integrator integ;
  int coord = 0;  // velocity index of the joint angle
};

void MakePendulum(Pendulum* p) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "pivot");
  b.AddRigidBody("bob", node, 1.0, Vec3(-1.0, 0.0, 0.0), 1e-10 * Mat3::Identity());
  b.AddJointAt("pin", JointType::kRevolute, kGround, node, Vec3::Zero(), Vec3::UnitZ());
  b.SetGravity(Vec3(0.0, -kG, 0.0));
  p->model = b.Build();
  p->data = MakeData(p->model);
  p->coord = p->model.joints[0].coord;
  DynamicOptions opt;
  opt.rho_inf = 1.0;
  ASSERT_TRUE(InitializeDynamics(p->model, p->data, p->integ, opt));
}

// Exact bob position at time t.
Vec3 ExactPosition(double t) {
  const double k = std::sin(kPi / 4), K = test::EllipticK(k * k);
  const double w0 = std::sqrt(kG);
  const double theta = 2.0 * std::asin(k * test::JacobiElliptic(K - w0 * t, k * k).sn);
  return Vec3(-std::sin(theta), -std::cos(theta), 0.0);
}

Vec3 BobPosition(const Pendulum& p) { return p.data.H[0].Act(Vec3(-1.0, 0.0, 0.0)); }

TEST(PendulumM1, ExactReferenceReproducesTheQuotedPeriodAndTable) {
  const double k2 = 0.5;
  EXPECT_NEAR(4.0 * test::EllipticK(k2) / std::sqrt(kG), kPeriod, 1e-11);
  const double table[][3] = {
      {0.25, -0.953664612, -0.300871746}, {0.5, -0.391048792, -0.920369949},
      {1.0, 0.986291751, -0.165010853},   {2.0, -0.793566195, -0.608483930},
      {5.0, -0.942305435, -0.334754338},  {10.0, -0.275087463, -0.961419205}};
  for (const auto& row : table) {
    const Vec3 x = ExactPosition(row[0]);
    EXPECT_NEAR(x.x(), row[1], 1e-9) << "t = " << row[0];
    EXPECT_NEAR(x.y(), row[2], 1e-9) << "t = " << row[0];
  }
}

// Times of the zero crossings of the angular velocity at T/2 and T, by linear interpolation
// over the step that brackets each: at a turning point of a pendulum d^2(alpha_dot)/dt^2 =
// -w0^2 cos(theta) theta_dot = 0, so the interpolation error is O(h^3), below the integrator's
// O(h^2). (The accelerations are not used: with rho_inf = 1 generalized-alpha does not damp
// the round-off left in vdot by the Newton stopping test, which is amplified by 1/(beta h^2)
// — measured |vdot error| 1e-4 at h = 1e-3 but 8e-4 at h = 2.5e-4, against 5e-6 with
// rho_inf = 0.9 — so a Hermite interpolant through (v, vdot) would spoil the measurement.)
struct Crossings {
  double half = 0.0, full = 0.0;
};

Crossings MeasureCrossings(double h) {
  Pendulum p;
  MakePendulum(&p);
  Crossings c;
  int found = 0;
  const int steps = static_cast<int>(std::ceil(1.1 * kPeriod / h));
  for (int n = 0; n < steps && found < 2; ++n) {
    const double t0 = n * h;
    const double v0 = p.data.v(p.coord);
    const StepResult r = Step(p.model, p.data, p.integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) break;
    const double v1 = p.data.v(p.coord);
    if (t0 > 0.25 * kPeriod && (v0 > 0.0) != (v1 > 0.0)) {
      const double t = t0 + h * v0 / (v0 - v1);
      (found++ == 0 ? c.half : c.full) = t;
    }
  }
  EXPECT_EQ(found, 2);
  return c;
}

TEST(PendulumM1, PeriodFromAngularVelocityZeroCrossingsConvergesAtSecondOrder) {
  const Crossings c1 = MeasureCrossings(5e-4);
  const Crossings c2 = MeasureCrossings(2.5e-4);
  const double e1 = c1.full - kPeriod, e2 = c2.full - kPeriod;
  // h = 2.5e-4: the period itself to 1e-6 relative.
  EXPECT_LT(std::abs(e2) / kPeriod, 1e-6) << "error " << e2;
  // Half period (from the first crossing) equally.
  EXPECT_LT(std::abs(2.0 * c2.half - kPeriod) / kPeriod, 1e-6);
  // Second-order convergence and a Richardson extrapolation far better than either run.
  EXPECT_GT(e1 / e2, 3.5);
  EXPECT_LT(e1 / e2, 4.5);
  const double richardson = (4.0 * c2.full - c1.full) / 3.0;
  EXPECT_LT(std::abs(richardson - kPeriod) / kPeriod, 1e-9) << "Richardson " << richardson;
}

// Bob positions at the validation table times (error measured against the exact solution,
// which reproduces the table to 1e-9) and the largest position error over 10 s.
double RunToTenSeconds(double h, double* max_energy_drift) {
  Pendulum p;
  MakePendulum(&p);
  const int steps = static_cast<int>(std::lround(10.0 / h));
  const std::vector<double> check = {0.25, 0.5, 1.0, 2.0, 5.0, 10.0};
  double max_err = 0.0;
  *max_energy_drift = 0.0;
  for (int n = 1; n <= steps; ++n) {
    const StepResult r = Step(p.model, p.data, p.integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) return INFINITY;
    const double t = n * h;
    *max_energy_drift = std::max(*max_energy_drift, std::abs(CalcEnergy(p.model, p.data).total()));
    for (double tc : check) {
      if (std::abs(t - tc) > 0.25 * h) continue;
      const double err = (BobPosition(p) - ExactPosition(tc)).norm();
      max_err = std::max(max_err, err);
      EXPECT_LT(err, 1e-4) << "h = " << h << ", t = " << tc;
    }
  }
  return max_err;
}

TEST(PendulumM1, PositionsAtTableTimesWithin1e4AndSecondOrderInStepSize) {
  double drift1 = 0.0, drift2 = 0.0;
  const double e1 = RunToTenSeconds(2e-3, &drift1);
  const double e2 = RunToTenSeconds(1e-3, &drift2);
  EXPECT_LT(e2, 1e-4);
  EXPECT_GT(e1 / e2, 3.5) << e1 << " " << e2;
  EXPECT_LT(e1 / e2, 4.5) << e1 << " " << e2;
  // Energy (zero at release) is not conserved exactly by generalized-alpha, but its error
  // stays bounded and O(h^2).
  EXPECT_LT(drift2, 1e-4);
  EXPECT_GT(drift1 / drift2, 3.0);
}

}  // namespace
}  // namespace screwfem::pendulum_test
