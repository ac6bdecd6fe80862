// A free joint with springs (a 6-DOF elastic connection, docs/numerics.md "Free joints"): two
// floating rigid bodies joined by it oscillate at the closed-form frequencies for small
// motion, and an undamped one conserves energy.
//
// Bodies 1 and 2 (m1 = 0.3 kg, m2 = 0.5 kg, inertia diag(2e-3, 3e-3, 4e-3) and
// diag(1e-3, 5e-3, 6e-3) kg m^2 about their centres of mass) have their frames at their
// centres of mass, at (-0.1, 0, 0) and (0.2, 0, 0); the joint sits at the origin, on the
// line through both. No gravity. Stretching along that line (x) and twisting about it are
// decoupled from the other four modes by symmetry:
//   axial:     mu u'' + k_x u = 0,        mu = m1 m2 / (m1 + m2),    w = sqrt(k_x / mu)
//   torsion:   Jr t'' + k_rx t = 0,       Jr = J1x J2x / (J1x + J2x), w = sqrt(k_rx / Jr)
// with u, t the relative slide and twist. Started with opposite velocities that conserve
// momentum, so the bodies' centre of mass stays at rest.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::free_joint_test {
namespace {

constexpr double kM1 = 0.3, kM2 = 0.5;
const Vec3 kJ1(2e-3, 3e-3, 4e-3), kJ2(1e-3, 5e-3, 6e-3);
const Vec6 kStiffness = (Vec6() << 40.0, 50.0, 60.0, 0.7, 0.8, 0.9).finished();

struct Pair {
  Model model;
  Data data;
  Integrator integ;
};

// Relative slide along x and twist about x (rad) of body 2 with respect to body 1.
Vec6 Relative(const Pair& p) {
  return LogSE3(p.data.H[0].Inverse() * p.data.H[1]) -
         LogSE3(p.model.nodes[0].reference.Inverse() * p.model.nodes[1].reference);
}

void MakePair(Pair* p, const Vec6& damping, double slide_rate, double twist_rate, double rho_inf) {
  ModelBuilder b;
  const NodeId n1 = b.AddNode(SE3::Translation(Vec3(-0.1, 0, 0)), "one");
  const NodeId n2 = b.AddNode(SE3::Translation(Vec3(0.2, 0, 0)), "two");
  b.AddRigidBody("one", n1, kM1, Vec3::Zero(), Mat3(kJ1.asDiagonal()));
  b.AddRigidBody("two", n2, kM2, Vec3::Zero(), Mat3(kJ2.asDiagonal()));
  const JointId j = b.AddJointAt("spring", JointType::kFree, n1, n2, Vec3::Zero());
  b.model().joints[j].stiffness = kStiffness;
  b.model().joints[j].damping = damping;
  p->model = b.Build();
  p->data = MakeData(p->model);
  // Opposite velocities with zero total momentum: u' = slide_rate, t' = twist_rate.
  const int d1 = p->model.nodes[0].dof, d2 = p->model.nodes[1].dof;
  p->data.v(d1 + 0) = -kM2 / (kM1 + kM2) * slide_rate;
  p->data.v(d2 + 0) = kM1 / (kM1 + kM2) * slide_rate;
  p->data.v(d1 + 3) = -kJ2.x() / (kJ1.x() + kJ2.x()) * twist_rate;
  p->data.v(d2 + 3) = kJ1.x() / (kJ1.x() + kJ2.x()) * twist_rate;
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(p->model, p->data, p->integ, opt, &message)) << message;
}

TEST(FreeJoint, TwoBodiesOscillateAtTheClosedFormAxialAndTorsionalFrequencies) {
  const double mu = kM1 * kM2 / (kM1 + kM2);
  const double Jr = kJ1.x() * kJ2.x() / (kJ1.x() + kJ2.x());
  const double w_axial = std::sqrt(kStiffness(0) / mu), w_twist = std::sqrt(kStiffness(3) / Jr);
  const double u0 = 1e-4, t0 = 1e-4;  // amplitudes [m, rad]: small motion
  Pair p;
  MakePair(&p, Vec6::Zero(), u0 * w_axial, t0 * w_twist, 1.0);
  const double h = 2e-4, duration = 1.0;
  double err_u = 0.0, err_t = 0.0, other = 0.0;
  for (int n = 1; n * h <= duration + 1e-12; ++n) {
    const StepResult r = Step(p.model, p.data, p.integ, h);
    ASSERT_TRUE(r.ok) << r.message;
    const Vec6 rel = Relative(p);
    err_u = std::max(err_u, std::abs(rel(0) - u0 * std::sin(w_axial * n * h)) / u0);
    err_t = std::max(err_t, std::abs(rel(3) - t0 * std::sin(w_twist * n * h)) / t0);
    other =
        std::max({other, std::abs(rel(1)), std::abs(rel(2)), std::abs(rel(4)), std::abs(rel(5))});
  }
  // Phase error of the trapezoidal rule (w h)^2 w t / 12 at most ~3e-3 here; the
  // geometric nonlinearity is O(amplitude) ~ 1e-4.
  EXPECT_LT(err_u, 5e-3);
  EXPECT_LT(err_t, 5e-3);
  EXPECT_LT(other, 1e-9);
  // The total momentum (zero) is conserved: body 1's centre of mass moves opposite to body 2's.
  const double x1 = p.data.H[0].x.x() + 0.1, x2 = p.data.H[1].x.x() - 0.2;
  EXPECT_NEAR(kM1 * x1 + kM2 * x2, 0.0, 1e-12);
}

TEST(FreeJoint, UndampedSpringConservesEnergyAndDampingDissipatesIt) {
  // Large motion in all six directions (the spring on the logarithm is nonlinear).
  for (bool damped : {false, true}) {
    SCOPED_TRACE(damped ? "damped" : "undamped");
    Pair p;
    MakePair(&p, damped ? Vec6::Constant(0.01) : Vec6::Zero(), 2.0, 20.0, 1.0);
    const int d2 = p.model.nodes[1].dof;
    p.data.v(d2 + 1) = 1.0;
    p.data.v(d2 + 2) = -0.5;
    p.data.v(d2 + 4) = 3.0;
    p.data.v(d2 + 5) = -2.0;
    DynamicOptions opt;
    opt.rho_inf = 1.0;
    ASSERT_TRUE(InitializeDynamics(p.model, p.data, p.integ, opt));
    const Energy e0 = CalcEnergy(p.model, p.data);
    double drift = 0.0, spring_max = 0.0;
    double previous = e0.kinetic + e0.spring;
    for (int n = 0; n < 2000; ++n) {
      const StepResult r = Step(p.model, p.data, p.integ, 5e-4);
      ASSERT_TRUE(r.ok) << r.message;
      const Energy e = CalcEnergy(p.model, p.data);
      const double total = e.kinetic + e.spring;
      drift = std::max(drift, std::abs(total - (e0.kinetic + e0.spring)));
      spring_max = std::max(spring_max, e.spring);
      if (damped) {
        EXPECT_LT(total, previous + 1e-9 * previous);
      }
      previous = total;
    }
    EXPECT_GT(spring_max, 0.2 * (e0.kinetic + e0.spring));  // the spring is exercised
    if (damped) {
      EXPECT_LT(previous, 0.98 * (e0.kinetic + e0.spring));
    } else {
      EXPECT_LT(drift, 2e-3 * (e0.kinetic + e0.spring));
    }
  }
}

}  // namespace
}  // namespace screwfem::free_joint_test
