// Validation J1 (docs/validation.md): soft revolute and prismatic joints (spring-damper on the
// joint coordinate) against the closed-form damped oscillator.
//
// One rigid body (the seed paper's link: m = 0.15 kg, J = 1e-4 kg m^2 about the CoM, CoM at
// l_c = 0.25 m along x from the node) on a joint to the ground at the node, no gravity:
//   revolute about z:  J_O a'' + D a' + K (a - a_rest) = 0, J_O = J + m l_c^2 = 0.009475
//   prismatic along x: m   a'' + D a' + K (a - a_rest) = 0.
// K = 10 (N m/rad or N/m). The initial deflection is set through the rest position: the body
// starts at rest at a = 0 with a_rest = -a0, so delta = a - a_rest starts at a0 with zero rate
// and the joint frames coincide in the reference configuration.
// Integrator: rho_inf = 1 unless stated (no numerical damping).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::soft_joint_test {
namespace {

constexpr double kMass = 0.15, kJc = 1e-4, kLc = 0.25, kK = 10.0;
constexpr double kA0 = 0.2;  // initial deflection [rad or m]

struct Oscillator {
  Model model;
  Data data;
  Integrator integ;
  int coord = 0;
};

void MakeOscillator(Oscillator* o, JointType type, double damping, double rho_inf = 1.0) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "link");
  b.AddRigidBody("link", node, kMass, Vec3(kLc, 0.0, 0.0), kJc * Mat3::Identity());
  const Vec3 axis = type == JointType::kRevolute ? Vec3::UnitZ() : Vec3::UnitX();
  const JointId j = b.AddJointAt("soft", type, kGround, node, Vec3::Zero(), axis);
  Joint& joint = b.model().joints[j];
  joint.stiffness(0) = kK;
  joint.damping(0) = damping;
  joint.rest(0) = -kA0;
  o->model = b.Build();
  o->data = MakeData(o->model);
  o->coord = o->model.joints[0].coord;
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  // The plain start a_0 = vdot_0 of the scalar recursion below (the default perturbed start
  // moves a_0 by (alpha_m - alpha_f) h vddot_0 when rho_inf < 1).
  opt.perturbed_start = false;
  ASSERT_TRUE(InitializeDynamics(o->model, o->data, o->integ, opt));
}

double Inertia(JointType type) {
  return type == JointType::kRevolute ? kJc + kMass * kLc * kLc : kMass;
}

// Free response delta(t) of J d'' + D d' + K d = 0 from delta(0) = a0, delta'(0) = 0.
double ExactDelta(JointType type, double D, double t) {
  const double J = Inertia(type);
  const double wn = std::sqrt(kK / J), zeta = D / (2.0 * std::sqrt(kK * J));
  if (zeta < 1.0) {
    const double wd = wn * std::sqrt(1.0 - zeta * zeta);
    return kA0 * std::exp(-zeta * wn * t) *
           (std::cos(wd * t) + zeta / std::sqrt(1.0 - zeta * zeta) * std::sin(wd * t));
  }
  const double s = wn * std::sqrt(zeta * zeta - 1.0);
  const double r1 = -zeta * wn + s, r2 = -zeta * wn - s;
  return kA0 * (-r2 * std::exp(r1 * t) + r1 * std::exp(r2 * t)) / (r1 - r2);
}

// Largest |alpha - alpha_exact| / a0 over [0, duration].
double MaxError(JointType type, double D, double h, double duration) {
  Oscillator o;
  MakeOscillator(&o, type, D);
  double err = 0.0;
  const int steps = static_cast<int>(std::lround(duration / h));
  for (int n = 1; n <= steps; ++n) {
    const StepResult r = Step(o.model, o.data, o.integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) return INFINITY;
    const double alpha = o.data.q_joint(0);
    err = std::max(err, std::abs(alpha - (-kA0 + ExactDelta(type, D, n * h))) / kA0);
  }
  // The body follows its joint coordinate (constraints satisfied).
  const SE3& H = o.data.H[0];
  if (type == JointType::kRevolute)
    EXPECT_NEAR(std::atan2(H.R(1, 0), H.R(0, 0)), o.data.q_joint(0), 1e-10);
  else
    EXPECT_NEAR(H.x.x(), o.data.q_joint(0), 1e-10);
  return err;
}

struct Case {
  const char* name;
  JointType type;
  double damping;
  double duration;
};

// zeta: revolute D = 0.1 -> 0.162, D = 5 -> 8.12 (stiff root -523 1/s); prismatic D = 0.1 ->
// 0.041, D = 5 -> 2.04 (the seed paper's values, overdamped).
const Case kCases[] = {
    {"revolute, underdamped D = 0.1", JointType::kRevolute, 0.1, 0.4},
    {"revolute, overdamped D = 5", JointType::kRevolute, 5.0, 0.4},
    {"prismatic, underdamped D = 0.1", JointType::kPrismatic, 0.1, 1.0},
    {"prismatic, overdamped D = 5 (paper)", JointType::kPrismatic, 5.0, 1.0},
};

TEST(SoftJointJ1, CoordinateFollowsTheClosedFormTo1e6WithSecondOrderConvergence) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.name);
    const double e1 = MaxError(c.type, c.damping, 1e-4, c.duration);
    const double e2 = MaxError(c.type, c.damping, 5e-5, c.duration);
    EXPECT_LT(e2, 1e-6);
    EXPECT_GT(e1 / e2, 3.5);
    EXPECT_LT(e1 / e2, 4.5);
  }
}

// Without damping and with rho_inf = 1 the scheme dissipates nothing: for this linear
// oscillator it is the trapezoidal rule, which conserves the quadratic energy exactly (the
// O((w h)^2) error is in the phase only). Over 20 periods: energy to round-off, and the peaks
// of the last period at a0.
TEST(SoftJointJ1, UndampedAmplitudeIsPreservedWithRhoInfOne) {
  for (JointType type : {JointType::kRevolute, JointType::kPrismatic}) {
    SCOPED_TRACE(JointTypeName(type));
    const double wn = std::sqrt(kK / Inertia(type));
    const double h = 1e-3, period = 2.0 * std::acos(-1.0) / wn;
    Oscillator o;
    MakeOscillator(&o, type, 0.0);
    const double E0 = CalcEnergy(o.model, o.data).total();
    EXPECT_NEAR(E0, 0.5 * kK * kA0 * kA0, 1e-15);
    const int steps = static_cast<int>(std::lround(20.0 * period / h));
    double max_energy = 0.0, last_peak = 0.0;
    for (int n = 1; n <= steps; ++n) {
      ASSERT_TRUE(Step(o.model, o.data, o.integ, h).ok);
      max_energy = std::max(max_energy, std::abs(CalcEnergy(o.model, o.data).total() - E0) / E0);
      if (n * h > 19.0 * period) last_peak = std::max(last_peak, std::abs(o.data.q_joint(0) + kA0));
    }
    EXPECT_LT(max_energy, 1e-12);  // measured 2.4e-14 (revolute), 2.8e-14 (prismatic)
    // The sampled peak can only miss the true one by the sampling: O((w h)^2).
    const double bound = (wn * h) * (wn * h);
    EXPECT_GT(last_peak, kA0 * (1.0 - bound));
    EXPECT_LT(last_peak, kA0 * (1.0 + 1e-10));
  }
}

// For this oscillator the Lie-group scheme reduces to the scalar generalized-alpha recursion
// (Chung-Hulbert parameters from rho_inf, Arnold-Bruls form with the equation of motion
// satisfied at t_{n+1}):
//   (1 - a_m) a_{n+1} + a_m a_n = (1 - a_f) d''_{n+1} + a_f d''_n
//   d_{n+1} = d_n + h d'_n + h^2 (1/2 - beta) a_n + h^2 beta a_{n+1}
//   d'_{n+1} = d'_n + h (1 - gamma) a_n + h gamma a_{n+1},  J d''_{n+1} + D d'_{n+1} + K d_{n+1} = 0
// The simulated coordinate reproduces it to round-off for rho_inf < 1, which pins down the
// numerical damping exactly (its principal roots: see the measured decay below).
struct ScalarGeneralizedAlpha {
  double am, af, gamma, beta;
  explicit ScalarGeneralizedAlpha(double rho)
      : am((2 * rho - 1) / (rho + 1)),
        af(rho / (rho + 1)),
        gamma(0.5 + af - am),
        beta(0.25 * (gamma + 0.5) * (gamma + 0.5)) {}
};

TEST(SoftJointJ1, NumericalDampingWithRhoInfBelowOneIsExactlyTheGeneralizedAlphaRecursion) {
  for (double rho : {0.8, 0.5}) {
    for (double D : {0.0, 0.1}) {
      SCOPED_TRACE("rho_inf = " + std::to_string(rho) + ", D = " + std::to_string(D));
      const ScalarGeneralizedAlpha p(rho);
      const double J = Inertia(JointType::kRevolute), h = 1e-3;
      Oscillator o;
      MakeOscillator(&o, JointType::kRevolute, D, rho);
      double d = kA0, v = 0.0, acc = -kK * kA0 / J, a = acc;
      double max_diff = 0.0;
      const int steps = 2000;
      for (int n = 1; n <= steps; ++n) {
        ASSERT_TRUE(Step(o.model, o.data, o.integ, h).ok);
        const double P = (p.af * acc - p.am * a) / (1 - p.am), Q = (1 - p.af) / (1 - p.am);
        const double S = d + h * v + h * h * (0.5 - p.beta) * a, V = v + h * (1 - p.gamma) * a;
        const double acc1 = -(D * (V + h * p.gamma * P) + kK * (S + h * h * p.beta * P)) /
                            (J + D * h * p.gamma * Q + kK * h * h * p.beta * Q);
        const double a1 = P + Q * acc1;
        d = S + h * h * p.beta * a1;
        v = V + h * p.gamma * a1;
        acc = acc1;
        a = a1;
        max_diff = std::max(max_diff, std::abs(o.data.q_joint(0) + kA0 - d) / kA0);
      }
      EXPECT_LT(max_diff, 1e-10);  // measured 3.5e-12
      // rho_inf < 1 removes energy even without a damper (measured over 2 s, w h = 0.032:
      // 1 - E/E0 = 5.4e-6 for rho_inf = 0.8, 1.04e-4 for 0.5).
      if (D == 0.0) {
        const double loss = 1.0 - CalcEnergy(o.model, o.data).total() / (0.5 * kK * kA0 * kA0);
        EXPECT_GT(loss, 1e-7);
        EXPECT_LT(loss, 1e-3);
      }
    }
  }
}

}  // namespace
}  // namespace screwfem::soft_joint_test
