// Tendons and force elements against closed forms (docs/numerics.md, "Tendons and force elements"):
//  * a straight tendon at offset d along a straight cantilever, eyelets at every node, tension
//    tau: every element takes the same curvature (the discrete model's values of T4.3), which
//    tends to the continuous arc kappa = tau d / EI at second order in the element length; the
//    clamp reaction vanishes (the tendon's pull on the clamped eyelet and the rod's force on
//    the clamp cancel);
//  * dU/dL_T = -tau at equilibrium (the tendon's work goes into strain energy);
//  * a mass on a spring-damper from the ground is the damped oscillator;
//  * a spring between two free bodies conserves their linear and angular momentum (to
//    round-off along the line of centres; at the integrator's O(h^2) when they tumble).
#include <gtest/gtest.h>

#include <cmath>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/statics.h"

namespace screwfem::tendon_test {
namespace {

// T4.2/T4.3: L = 1, EA = GA = 1e5, EI = GJ = 1, offset d = 0.02 along section y.
constexpr double kEA = 1e5, kEI = 1.0, kOffset = 0.02;

struct Cantilever {
  Model model;
  Data data;
  StaticResult result;
};

Cantilever SolveCantilever(int elements, double tension) {
  ModelBuilder b;
  const RodId rod =
      b.AddStraightRod("rod", Vec3::Zero(), Vec3::UnitX(), elements,
                       Section::FromDiagonals((Vec6() << kEA, kEA, kEA, kEI, kEI, kEI).finished()));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  std::vector<BodyPoint> eyelets;
  for (int n : nodes) eyelets.push_back({n, Vec3(0.0, kOffset, 0.0)});
  b.AddTendon("tendon", eyelets, Profile::Constant(tension));
  Cantilever c{b.Build(), {}, {}};
  c.data = MakeData(c.model);
  StaticOptions o;
  o.load_steps = 40;  // a follower-like load (docs/numerics.md, "Tendons and force elements")
  c.result = SolveStatic(c.model, c.data, o);
  return c;
}

// The force that the clamp must apply to node 0: minus the node-0 rows of the rod's first
// element and of the tendon's first segment (the only items on it).
Vec6 ClampReaction(const Cantilever& c) {
  const Mat6 I = Mat6::Identity();
  Vec6 rows = Vec6::Zero();
  KernelOptions o;
  o.tangent = false;
  auto add = [&](auto kind, int item, int node_a, int node_b) {
    NodeMotion<2> x;
    x.H[0] = &NodeFrame(c.data, node_a);
    x.H[1] = &NodeFrame(c.data, node_b);
    x.T[0] = x.T[1] = &I;
    x.eta.setZero();
    x.eta_dot.setZero();
    ElementTerms<2> t;
    ASSERT_TRUE(decltype(kind)::Calc(c.model, c.data, item, x, o, &t));
    if (t.active) rows += t.residual.head<6>();
  };
  const RodElement& e = c.model.elements[0];
  add(RodElementKind{}, 0, e.node_a, e.node_b);
  const TendonSegmentGroup& s = c.model.tendon_segment_groups[0];  // the first segment alone
  add(TendonSegmentKind{}, 0, s.node_a, s.node_b);
  return -rows;
}

TEST(TendonValidation, StraightTendonWithEyeletsAtEveryNodeBendsTheRodIntoAnArc) {
  const double tau = 50.0;
  // The discrete model's curvature and tip (docs/numerics.md, "Tendons and force elements", T4.3) and the continuum arc.
  const int elements[3] = {4, 8, 16};
  const double kappa[3] = {1.331886, 1.067189, 1.016023};
  const Vec3 tip[3] = {{0.729126, 0.572854, 0}, {0.820295, 0.484594, 0}, {0.836197, 0.465553, 0}};
  const double k = tau * kOffset / kEI, eps = -tau / kEA;
  const Vec3 arc((1 + eps) / k * std::sin(k), (1 + eps) / k * (1 - std::cos(k)), 0.0);
  double error[3];
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(elements[i]);
    const Cantilever c = SolveCantilever(elements[i], tau);
    ASSERT_TRUE(c.result.converged) << c.result.message;
    // Every element has the same curvature: the rod is a circular arc.
    for (const RodElement& e : c.model.elements) {
      const Vec6 d = LogSE3(c.data.H[static_cast<std::size_t>(e.node_a)].Inverse() *
                            c.data.H[static_cast<std::size_t>(e.node_b)]);
      EXPECT_NEAR(d(5) / e.length, kappa[i], 1e-6);
      EXPECT_NEAR(d(3), 0.0, 1e-10);
      EXPECT_NEAR(d(4), 0.0, 1e-10);
    }
    const Vec3 x = c.data.H[static_cast<std::size_t>(c.model.rods[0].nodes.back())].x;
    EXPECT_LT((x - tip[i]).norm(), 2e-6);
    error[i] = (x - arc).norm();
    // No reaction at the clamp: the tendon's pull on the clamped eyelet and the eyelets' push
    // on the rod cancel (no gravity here).
    const Vec6 reaction = ClampReaction(c);
    EXPECT_LT(reaction.norm(), 1e-8 * tau) << reaction.transpose();
    // Outputs: the tendon length and its tension.
    const LineForceState s = CalcTendonState(c.model, c.data, 0);
    EXPECT_EQ(s.force, tau);
    EXPECT_LT(s.length, 1.0);
  }
  // Second order in the element length (measured ratios 4.9 and 4.2).
  EXPECT_GT(error[0] / error[1], 3.5);
  EXPECT_GT(error[1] / error[2], 3.5);
  EXPECT_LT(error[2], 0.01);
}

TEST(TendonValidation, StrainEnergyChangesByMinusTensionTimesTendonLength) {
  // At equilibrium under the potential U + tau L: dU/dtau = -tau dL/dtau, so dU/dL = -tau.
  const double tau = 30.0, dt = 0.3;
  const Cantilever lo = SolveCantilever(8, tau - dt), hi = SolveCantilever(8, tau + dt);
  ASSERT_TRUE(lo.result.converged && hi.result.converged);
  const double dU = CalcEnergy(hi.model, hi.data).strain - CalcEnergy(lo.model, lo.data).strain;
  const double dL =
      CalcTendonState(hi.model, hi.data, 0).length - CalcTendonState(lo.model, lo.data, 0).length;
  EXPECT_LT(dL, 0.0);
  EXPECT_NEAR(-dU / dL, tau, 1e-4 * tau);  // central difference: O(dt^2)
}

// A 2 kg mass at the origin hangs from the ground point (0, 0, 1) by a spring-damper of
// stiffness 50 N/m, damping 1 N s/m and rest length 1.1 m: it starts at rest 0.1 m above its
// equilibrium, m z'' + c z' + k z = -0.1 k.
double OscillatorError(double h, double duration) {
  const double m = 2.0, k = 50.0, c = 1.0;
  ModelBuilder b;
  const NodeId n = b.AddNode(SE3::Identity(), "mass");
  b.AddRigidBody("mass", n, m, Vec3::Zero(), Mat3::Identity());
  ForceElement fe;
  fe.name = "spring";
  fe.a = {kGround, Vec3(0, 0, 1)};
  fe.b = {n, Vec3::Zero()};
  fe.stiffness = k;
  fe.damping = c;
  fe.rest_length = 1.1;
  b.AddForceElement(fe);
  const Model model = b.Build();
  Data data = MakeData(model);
  Integrator integ;
  DynamicOptions o;
  o.rho_inf = 1.0;
  std::string message;
  EXPECT_TRUE(InitializeDynamics(model, data, integ, o, &message)) << message;
  const double w = std::sqrt(k / m), zeta = c / (2 * std::sqrt(k * m));
  const double wd = w * std::sqrt(1 - zeta * zeta);
  double err = 0.0;
  const int steps = static_cast<int>(std::lround(duration / h));
  for (int i = 1; i <= steps; ++i) {
    const StepResult r = Step(model, data, integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    const double t = i * h;
    const double z = -0.1 + 0.1 * std::exp(-zeta * w * t) *
                                (std::cos(wd * t) + zeta * w / wd * std::sin(wd * t));
    err = std::max(err, std::abs(data.H[0].x.z() - z));
    err = std::max(err, data.H[0].x.head<2>().norm());
  }
  return err;
}

TEST(ForceElementValidation, MassOnASpringDamperIsTheDampedOscillator) {
  const double e1 = OscillatorError(1e-3, 2.0), e2 = OscillatorError(5e-4, 2.0);
  EXPECT_LT(e2, 1e-6);
  EXPECT_GT(e1 / e2, 3.5);  // second order
  EXPECT_LT(e1 / e2, 4.5);
}

// World linear momentum and angular momentum about the origin of rigid bodies whose centres
// of mass are at their nodes.
Vec6 Momentum(const Model& model, const Data& data) {
  Vec6 p = Vec6::Zero();
  for (const RigidBody& body : model.bodies) {
    const SE3& H = data.H[static_cast<std::size_t>(body.node)];
    const Vec6 eta = data.v.segment<6>(model.nodes[static_cast<std::size_t>(body.node)].dof);
    const Vec3 linear = body.mass * (H.R * eta.head<3>());
    p.head<3>() += linear;
    p.tail<3>() += H.x.cross(linear) + H.R * (body.inertia * eta.tail<3>());
  }
  return p;
}

// Two free bodies tumbling on a stretched, damped spring with an oscillating actuator force,
// attached off their centres of mass; no gravity. Returns the largest drift of the linear and
// of the angular momentum over 1 s at step h, and the largest stretch of the spring.
struct MomentumDrift {
  double linear = 0.0, angular = 0.0, stretch = 0.0, initial = 0.0;
};
MomentumDrift TumblingPair(double h) {
  ModelBuilder b;
  const NodeId n1 = b.AddNode(SE3::Identity(), "one");
  const NodeId n2 = b.AddNode(SE3::Translation(Vec3(1, 0, 0)), "two");
  b.AddRigidBody("one", n1, 0.7, Vec3::Zero(), Vec3(0.02, 0.03, 0.04).asDiagonal().toDenseMatrix());
  b.AddRigidBody("two", n2, 1.3, Vec3::Zero(), Vec3(0.05, 0.02, 0.03).asDiagonal().toDenseMatrix());
  ForceElement fe;
  fe.a = {n1, Vec3(0.05, 0.1, 0.0)};
  fe.b = {n2, Vec3(-0.05, -0.1, 0.05)};
  fe.stiffness = 80.0;
  fe.damping = 0.5;
  fe.rest_length = 0.7;  // starts stretched: the bodies tumble towards each other
  fe.actuator = Profile::Sine(3.0, 2.0);
  b.AddForceElement(fe);
  const Model model = b.Build();
  Data data = MakeData(model);
  data.v.segment<6>(model.nodes[0].dof) << 0.1, -0.2, 0.3, 1.0, -2.0, 0.5;
  data.v.segment<6>(model.nodes[1].dof) << -0.3, 0.1, 0.2, -0.5, 1.5, 2.0;
  Integrator integ;
  DynamicOptions o;
  o.rho_inf = 1.0;
  o.residual_tolerance = 1e-12;
  EXPECT_TRUE(InitializeDynamics(model, data, integ, o));
  const Vec6 p0 = Momentum(model, data);
  MomentumDrift d;
  d.initial = p0.norm();
  const int steps = static_cast<int>(std::lround(1.0 / h));
  for (int i = 0; i < steps; ++i) {
    EXPECT_TRUE(Step(model, data, integ, h).ok);
    const Vec6 dp = Momentum(model, data) - p0;
    d.linear = std::max(d.linear, dp.head<3>().norm());
    d.angular = std::max(d.angular, dp.tail<3>().norm());
    d.stretch = std::max(d.stretch, std::abs(CalcForceElementState(model, data, 0).length - 0.7));
  }
  return d;
}

TEST(ForceElementValidation, SpringBetweenTwoFreeBodiesConservesMomentum) {
  const MomentumDrift d1 = TumblingPair(1e-3), d2 = TumblingPair(5e-4);
  EXPECT_GT(d1.stretch, 0.1);  // the spring is exercised
  // The element's forces have a zero world resultant to round-off (tests/elements/
  // tendon_test.cpp); what is left is the integrator's: the Lie-group generalized-alpha
  // updates body-frame velocities, so the world momentum of tumbling bodies drifts at O(h^2)
  // (measured 4.2e-5 and 1.0e-5 linear, 2.0e-5 and 5.0e-6 angular, |p0| = 0.67).
  EXPECT_LT(d1.linear, 1e-4 * d1.initial);
  EXPECT_LT(d1.angular, 1e-4 * d1.initial);
  EXPECT_NEAR(d1.linear / d2.linear, 4.0, 0.3);
  EXPECT_NEAR(d1.angular / d2.angular, 4.0, 0.3);
}

TEST(ForceElementValidation, SpringAlongTheLineOfCentresConservesMomentumToRoundOff) {
  // Without rotation the body-frame and world velocities coincide: the momentum of two bodies
  // sliding on a spring along the line through their centres is exact to round-off.
  ModelBuilder b;
  const NodeId n1 = b.AddNode(SE3::Identity(), "one");
  const NodeId n2 = b.AddNode(SE3::Translation(Vec3(1, 0, 0)), "two");
  b.AddRigidBody("one", n1, 0.7, Vec3::Zero(), Mat3::Identity());
  b.AddRigidBody("two", n2, 1.3, Vec3::Zero(), Mat3::Identity());
  ForceElement fe;
  fe.a = {n1, Vec3::Zero()};
  fe.b = {n2, Vec3::Zero()};
  fe.stiffness = 80.0;
  fe.damping = 0.5;
  fe.rest_length = 0.7;
  b.AddForceElement(fe);
  const Model model = b.Build();
  Data data = MakeData(model);
  data.v(model.nodes[0].dof) = 0.4;
  data.v(model.nodes[1].dof) = -0.1;
  Integrator integ;
  ASSERT_TRUE(InitializeDynamics(model, data, integ, DynamicOptions{}));
  const Vec6 p0 = Momentum(model, data);
  double drift = 0.0;
  for (int i = 0; i < 500; ++i) {
    ASSERT_TRUE(Step(model, data, integ, 2e-3).ok);
    drift = std::max(drift, (Momentum(model, data) - p0).norm());
  }
  EXPECT_LT(drift, 1e-13);
}

}  // namespace
}  // namespace screwfem::tendon_test
