// Internal actuation of rods against closed forms (docs/numerics.md, "Active stress and rest strain"):
//  * T5.1 a rest curvature kappa0 on a cantilever: the exact solution is stress-free, a circular
//    arc, and one helical element reproduces it to Newton tolerance with no clamp reaction;
//    kappa0 L = 0.9 (2 pi) needs the branch continuation of elements/rod.h (one element);
//  * T5.2 a pressure chamber: the strains p A / EA, p A r3 / EI2, -p A r2 / EI3 exactly; two
//    equal chambers at +-r extend the rod without bending it;
//  * T5.4 a free rod whose rest curvature is ramped from 0 to 2 pi / L curls into a closed
//    circle; its element forces have a zero world resultant, and its momentum stays zero up to
//    the integrator's O(h^2) drift;
//  * T5.5 a damped dynamic cantilever whose rest curvature rises by a smooth step settles on
//    the static shape of T5.1.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/rod.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/statics.h"

namespace screwfem::rod_actuation_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEA = 1e5, kEI = 1.0;

Vec6 V6(double a, double b, double c, double d, double e, double f) {
  Vec6 v;
  v << a, b, c, d, e, f;
  return v;
}

struct Cantilever {
  Model model;
  Data data;
  StaticResult result;
};

// A cantilever L = 1 along x (EA = GA = 1e5, EI = GJ = 1), clamped at x = 0, with actuators.
Cantilever SolveCantilever(int elements, const std::vector<Actuator>& actuators, int steps = 4) {
  ModelBuilder b;
  b.AddStraightRod("rod", Vec3::Zero(), Vec3::UnitX(), elements,
                   Section::FromDiagonals(V6(kEA, kEA, kEA, kEI, kEI, kEI)));
  b.FixNode(NodeId(0));
  for (Actuator a : actuators) {
    a.rod = 0;
    b.AddActuator(a);
  }
  Cantilever c{b.Build(), {}, {}};
  c.data = MakeData(c.model);
  StaticOptions o;
  o.load_steps = steps;
  c.result = SolveStatic(c.model, c.data, o);
  return c;
}

// What the clamp must apply to node 0: minus the node-0 rows of the first element (the only
// item on it).
Vec6 ClampReaction(const Cantilever& c) {
  const Mat6 I = Mat6::Identity();
  NodeMotion<2> x;
  x.H[0] = &c.data.H[0];
  x.H[1] = &c.data.H[1];
  x.T[0] = x.T[1] = &I;
  x.eta.setZero();
  x.eta_dot.setZero();
  KernelOptions o;
  o.tangent = false;
  ElementTerms<2> t;
  EXPECT_TRUE(RodElementKind::Calc(c.model, c.data, 0, x, o, &t));
  return -t.residual.head<6>();
}

Actuator RestCurvature(double kappa) {
  Actuator a;
  a.type = ActuatorType::kRestStrain;
  a.vector = V6(0, 0, 0, 0, 0, kappa);
  return a;
}

Actuator Chamber(double pressure_times_area, const Vec3& offset) {
  Actuator a;
  a.type = ActuatorType::kPressure;
  a.area = 1e-4;
  a.offset = offset;
  a.profile = Profile::Constant(pressure_times_area / a.area);
  return a;
}

TEST(ActuationValidation, RestCurvatureBendsOneElementIntoTheExactArcWithoutClampReaction) {
  const double kappa = 3.0;
  const Cantilever c = SolveCantilever(1, {RestCurvature(kappa)});
  ASSERT_TRUE(c.result.converged) << c.result.message;
  const SE3& tip = c.data.H[1];
  // (sin kL, 1 - cos kL) / k = (0.0470400, 0.6633308), rotation 3 rad about z.
  EXPECT_NEAR(tip.x.x(), 0.0470400, 1e-7);
  EXPECT_NEAR(tip.x.y(), 0.6633308, 1e-7);
  EXPECT_NEAR(tip.x.x(), std::sin(kappa) / kappa, 1e-10);
  EXPECT_NEAR(tip.x.y(), (1.0 - std::cos(kappa)) / kappa, 1e-10);
  EXPECT_NEAR(LogSO3(tip.R).z(), kappa, 1e-10);
  const Vec6 reaction = ClampReaction(c);
  EXPECT_LT(reaction.norm(), 1e-8) << reaction.transpose();
  // Stress-free: the section transmits nothing, elastic and total.
  std::vector<Vec6> total, elastic;
  CalcRodStresses(c.model, c.data, 0, &total, &elastic);
  EXPECT_LT(total[0].norm(), 1e-8);
  EXPECT_LT(elastic[0].norm(), 1e-8);
  EXPECT_LT(std::abs(CalcEnergy(c.model, c.data).strain), 1e-12);
}

TEST(ActuationValidation, RestCurvaturePastPiFollowsTheRotationBranchInOneElement) {
  const double kappa = 0.9 * 2.0 * kPi;  // 5.65 rad in one element
  const Cantilever c = SolveCantilever(1, {RestCurvature(kappa)}, 8);
  ASSERT_TRUE(c.result.converged) << c.result.message;
  const SE3& tip = c.data.H[1];
  EXPECT_NEAR(tip.x.x(), std::sin(kappa) / kappa, 1e-9);
  EXPECT_NEAR(tip.x.y(), (1.0 - std::cos(kappa)) / kappa, 1e-9);
  // On the branch past pi: w_ref carries the 5.65 rad (the principal log would say -0.63).
  EXPECT_NEAR(c.data.w_ref[0].z(), kappa, 1e-9);
  EXPECT_LT(ClampReaction(c).norm(), 1e-8);
}

TEST(ActuationValidation, PressureChamberGivesTheClosedFormStrainsInOneElement) {
  // p A = 20 N at r = (0, 0.01, 0.005): eps1 = 2e-4, kappa2 = 0.1, kappa3 = -0.2 (T5.2).
  const Cantilever c = SolveCantilever(1, {Chamber(20.0, Vec3(0.0, 0.01, 0.005))});
  ASSERT_TRUE(c.result.converged) << c.result.message;
  const RodElement& el = c.model.elements[0];
  const Vec6 strain = (LogSE3(c.data.H[0].Inverse() * c.data.H[1]) - el.d0) / el.length;
  EXPECT_NEAR(strain(0), 2e-4, 1e-12);
  EXPECT_NEAR(strain(4), 0.1, 1e-10);
  EXPECT_NEAR(strain(5), -0.2, 1e-10);
  EXPECT_LT(std::abs(strain(1)) + std::abs(strain(2)) + std::abs(strain(3)), 1e-10);
  EXPECT_LT(ClampReaction(c).norm(), 1e-8);
  // The section transmits nothing; its material carries the chamber's axial force and moments.
  std::vector<Vec6> total, elastic;
  CalcRodStresses(c.model, c.data, 0, &total, &elastic);
  EXPECT_LT(total[0].norm(), 1e-8);
  EXPECT_LT((elastic[0] - V6(20.0, 0, 0, 0, 0.1, -0.2)).norm(), 1e-8);
}

TEST(ActuationValidation, TwoChambersAtOppositeOffsetsExtendTheRodWithoutBending) {
  const Vec3 r(0.0, 0.01, 0.005);
  const Cantilever c = SolveCantilever(2, {Chamber(20.0, r), Chamber(20.0, -r)});
  ASSERT_TRUE(c.result.converged) << c.result.message;
  const Vec3 tip = c.data.H[2].x;
  EXPECT_NEAR(tip.x(), 1.0 + 2.0 * 20.0 / kEA, 1e-12);
  EXPECT_LT(std::abs(tip.y()) + std::abs(tip.z()), 1e-12);
  EXPECT_LT(LogSO3(c.data.H[2].R).norm(), 1e-12);
}

TEST(ActuationValidation, ChamberOverPartOfTheRodBendsOnlyThatPart) {
  // Chamber over [0.25, 0.75] of four elements: the outer elements stay straight (the end caps'
  // forces appear by themselves through P^T sigma_a), the inner ones take kappa3 = -p A r2 / EI.
  Actuator a = Chamber(20.0, Vec3(0.0, 0.01, 0.0));
  a.from = 0.25;
  a.to = 0.75;
  const Cantilever c = SolveCantilever(4, {a});
  ASSERT_TRUE(c.result.converged) << c.result.message;
  const double expected[4] = {0.0, -0.2, -0.2, 0.0};
  for (int e = 0; e < 4; ++e) {
    const RodElement& el = c.model.elements[static_cast<std::size_t>(e)];
    const Vec6 d = LogSE3(c.data.H[static_cast<std::size_t>(e)].Inverse() *
                          c.data.H[static_cast<std::size_t>(e + 1)]);
    EXPECT_NEAR(d(5) / el.length, expected[e], 1e-10) << e;
  }
  EXPECT_LT(ClampReaction(c).norm(), 1e-8);
}

// A free rod (4 elements, no supports, no gravity) whose rest curvature rises from 0 to
// 2 pi / L with a smooth step over [0, ramp]; strain-rate damping settles it.
struct FreeCurl {
  double max_linear = 0.0, max_angular = 0.0, gap = 0.0, elastic_energy = 0.0, scale = 0.0;
  double resultant = 0.0;  // |world force and moment of the elements' static forces| at the end
};
FreeCurl CurlFreeRod(double ramp, double t_end, double h) {
  ModelBuilder b;
  Section s =
      Section::FromDiagonals(V6(1e4, 1e4, 1e4, 1.0, 1.0, 1.0), V6(1, 1, 1, 1e-3, 1e-3, 1e-3));
  s.damping = V6(10, 10, 10, 0.05, 0.05, 0.05);
  b.AddStraightRod("free", Vec3::Zero(), Vec3::UnitX(), 4, s);
  Actuator a = RestCurvature(2.0 * kPi);
  a.rod = 0;
  a.profile = Profile::SmoothStep(0.0, ramp);
  b.AddActuator(a);
  const Model m = b.Build();
  Data d = MakeData(m);
  Integrator integ;
  DynamicOptions o;
  o.rho_inf = 0.9;
  EXPECT_TRUE(InitializeDynamics(m, d, integ, o));
  FreeCurl r;
  const int steps = static_cast<int>(std::lround(t_end / h));
  for (int i = 0; i < steps; ++i) {
    EXPECT_TRUE(Step(m, d, integ, h).ok);
    const Vec6 p = CalcMomentum(m, d);
    r.max_linear = std::max(r.max_linear, p.head<3>().norm());
    r.max_angular = std::max(r.max_angular, p.tail<3>().norm());
    // The momentum scale: the largest node speed times the rod's mass (1 kg).
    for (std::size_t n = 0; n < m.nodes.size(); ++n)
      r.scale = std::max(r.scale, d.v.segment<3>(m.nodes[n].dof).norm());
  }
  // World resultant (force, moment about the origin) of the elements' forces without inertia
  // and damping: internal forces sum to zero.
  Vec6 sum = Vec6::Zero();
  const Mat6 I = Mat6::Identity();
  for (int e = 0; e < 4; ++e) {
    NodeMotion<2> x;
    x.H[0] = &d.H[static_cast<std::size_t>(e)];
    x.H[1] = &d.H[static_cast<std::size_t>(e + 1)];
    x.T[0] = x.T[1] = &I;
    x.eta.setZero();
    x.eta_dot.setZero();
    KernelOptions ko;
    ko.time = d.time;
    ko.tangent = false;
    ElementTerms<2> t;
    EXPECT_TRUE(RodElementKind::Calc(m, d, e, x, ko, &t));
    for (int k = 0; k < 2; ++k) {
      const SE3& H = *x.H[k];
      const Vec3 f = H.R * t.residual.segment<3>(6 * k);
      sum.head<3>() += f;
      sum.tail<3>() += H.x.cross(f) + H.R * t.residual.segment<3>(6 * k + 3);
    }
  }
  r.resultant = sum.norm();
  r.gap = (d.H.back().x - d.H.front().x).norm();
  // Elastic energy L/2 (eps - eps0)^T K (eps - eps0) at the end (sigma_a = 0 here).
  r.elastic_energy = CalcEnergy(m, d).strain;
  return r;
}

TEST(ActuationValidation, FreeRodCurlsIntoAClosedCircleConservingMomentum) {
  const FreeCurl r1 = CurlFreeRod(1.0, 2.0, 0.01), r2 = CurlFreeRod(1.0, 2.0, 0.005);
  EXPECT_GT(r1.scale, 0.5);  // the rod moves (largest node speed [m/s], the rod's mass is 1 kg)
  // Internal forces only: the actuated elements' forces have a zero world resultant.
  EXPECT_LT(r1.resultant, 1e-12 * 2.0 * kPi) << r1.resultant;
  // What is left is the integrator's: the Lie-group generalized-alpha step updates body-frame
  // velocities, so the world momentum drifts at O(h^2) as for a free rod with initial
  // velocities (free_rod_test.cpp). Measured 1.96e-4 / 4.89e-5 kg m/s linear and
  // 9.78e-5 / 2.44e-5 angular at h = 0.01 / 0.005, against node speeds of 1.28 m/s.
  EXPECT_LT(r1.max_linear, 3e-4 * r1.scale);
  EXPECT_LT(r1.max_angular, 2e-4 * r1.scale);
  EXPECT_NEAR(r1.max_linear / r2.max_linear, 4.0, 0.2);
  EXPECT_NEAR(r1.max_angular / r2.max_angular, 4.0, 0.2);
  // Four elements of kappa0 L_e = pi/2 close the circle exactly at rest (measured gap 4.0e-6 m
  // after 1 s of settling) and the elastic energy returns to ~0 (2.3e-10 J).
  EXPECT_LT(r1.gap, 1e-5);
  EXPECT_LT(r1.elastic_energy, 1e-8);
}

TEST(ActuationValidation, DampedDynamicCurlEndsAtTheStaticShape) {
  // T5.5: the rest curvature of T5.1 applied with a smooth step over 1 s to a damped
  // one-element cantilever with mass settles on the static (closed-form) shape.
  ModelBuilder b;
  Section s =
      Section::FromDiagonals(V6(kEA, kEA, kEA, kEI, kEI, kEI), V6(1, 1, 1, 1e-3, 1e-3, 1e-3));
  s.damping = V6(10, 10, 10, 0.5, 0.5, 0.5);
  b.AddStraightRod("rod", Vec3::Zero(), Vec3::UnitX(), 1, s);
  b.FixNode(NodeId(0));
  Actuator a = RestCurvature(3.0);
  a.rod = 0;
  a.profile = Profile::SmoothStep(0.0, 1.0);
  b.AddActuator(a);
  const Model m = b.Build();
  Data d = MakeData(m);
  Integrator integ;
  ASSERT_TRUE(InitializeDynamics(m, d, integ, DynamicOptions{}));
  // The heavy strain-rate damping leaves a slow creep towards equilibrium: the tip error falls
  // by 3.3x every 0.5 s (measured 3.2e-3 m at 3 s, 2.3e-6 m at 6 s, 1.5e-10 m at 10 s).
  const Vec3 arc(std::sin(3.0) / 3.0, (1.0 - std::cos(3.0)) / 3.0, 0.0);
  double error_at_6 = 0.0;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(Step(m, d, integ, 0.01).ok);
    if (i == 599) error_at_6 = (d.H[1].x - arc).norm();
  }
  const Vec3 tip = d.H[1].x;
  EXPECT_LT(error_at_6, 1e-5);
  EXPECT_LT((tip - arc).norm(), 1e-9);
  EXPECT_LT((tip - arc).norm(), 1e-3 * error_at_6);  // still converging, not stuck elsewhere
  EXPECT_NEAR(LogSO3(d.H[1].R).z(), 3.0, 1e-8);
}

}  // namespace
}  // namespace screwfem::rod_actuation_test
