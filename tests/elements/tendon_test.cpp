// Tests of the point-distance geometry shared by tendons and force elements, and of their
// element kinds (elements/tendon.h, docs/numerics.md, "Tendons and force elements"). Every analytic derivative is checked
// by central finite differences through the retraction H <- H ExpSE3(eps e_i); forces against
// the gradient of their potential (tau L for a tendon at constant tension, 1/2 k (l - l0)^2
// for a spring); the world resultant of a force element's forces vanishes (momentum).
#include "screwfem/elements/tendon.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "kind_assembly.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::tendon_test {
namespace {

SE3 RandomFrame(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec6 xi;
  for (int i = 0; i < 6; ++i) xi(i) = 1.5 * u(rng);
  return ExpSE3(xi);
}

Vec3 RandomVec3(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return scale * Vec3(u(rng), u(rng), u(rng));
}

double RelativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

TEST(PointDistance, GradientAndHessianMatchFiniteDifferencesThroughTheRetraction) {
  std::mt19937 rng(7);
  for (int c = 0; c < 20; ++c) {
    const SE3 HA = RandomFrame(rng), HB = RandomFrame(rng);
    const Vec3 rA = RandomVec3(rng, 0.3), rB = RandomVec3(rng, 0.3);
    PointDistance g;
    ASSERT_TRUE(CalcPointDistance(HA, rA, HB, rB, true, &g));
    EXPECT_NEAR(g.length, ((HB.x + HB.R * rB) - (HA.x + HA.R * rA)).norm(), 1e-14);
    Vec12 fd_gradient;
    Mat12 fd_hessian;
    const double eps = 1e-6;
    for (int i = 0; i < 12; ++i) {
      PointDistance p, m;
      const Vec6 dh = eps * Vec6::Unit(i % 6);
      const SE3 Ap = i < 6 ? HA * ExpSE3(dh) : HA, Am = i < 6 ? HA * ExpSE3(-dh) : HA;
      const SE3 Bp = i < 6 ? HB : HB * ExpSE3(dh), Bm = i < 6 ? HB : HB * ExpSE3(-dh);
      ASSERT_TRUE(CalcPointDistance(Ap, rA, Bp, rB, false, &p));
      ASSERT_TRUE(CalcPointDistance(Am, rA, Bm, rB, false, &m));
      fd_gradient(i) = (p.length - m.length) / (2 * eps);
      fd_hessian.col(i) = (p.gradient - m.gradient) / (2 * eps);
    }
    EXPECT_LT(RelativeError(g.gradient, fd_gradient), 1e-8) << "case " << c;
    EXPECT_LT(RelativeError(g.hessian, fd_hessian), 1e-7) << "case " << c;
  }
  // Coinciding points: no direction.
  PointDistance g;
  EXPECT_FALSE(
      CalcPointDistance(SE3::Identity(), Vec3::Zero(), SE3::Identity(), Vec3::Zero(), true, &g));
}

// A chain of four free nodes (rigid bodies) and the ground, with a tendon through eyelets on
// all of them and a force element between two of them; with `second_tension` > 0 a second
// tendon through nodes 1 to 3 (its segments share their node pairs with the first tendon's:
// TendonSegmentKind items of two segments).
struct Chain {
  Model model;
  Data data;
};

Chain MakeChain(std::mt19937& rng, double tension, double second_tension = 0.0) {
  ModelBuilder b;
  std::vector<BodyPoint> eyelets;
  eyelets.push_back({kGround, Vec3(-0.5, 0.1, 0.0)});
  for (int i = 0; i < 4; ++i) {
    const NodeId n = b.AddNode(SE3::Translation(Vec3(0.4 * i, 0.0, 0.0)));
    b.AddRigidBody("b" + std::to_string(i), n, 1.0, Vec3::Zero(), Mat3::Identity());
    eyelets.push_back({n, RandomVec3(rng, 0.1)});
  }
  b.AddTendon("t", eyelets, Profile::Constant(tension));
  if (second_tension > 0.0)
    b.AddTendon("t2",
                {{1, RandomVec3(rng, 0.1)}, {2, RandomVec3(rng, 0.1)}, {3, RandomVec3(rng, 0.1)}},
                Profile::Constant(second_tension));
  ForceElement fe;
  fe.name = "spring";
  fe.a = {1, RandomVec3(rng, 0.1)};
  fe.b = {3, RandomVec3(rng, 0.1)};
  fe.stiffness = 30.0;
  fe.rest_length = 0.5;
  fe.damping = 2.0;
  fe.actuator = Profile::Constant(1.5);
  b.AddForceElement(fe);
  Chain c{b.Build(), {}};
  c.data = MakeData(c.model);
  for (std::size_t i = 0; i < c.data.H.size(); ++i)
    c.data.H[i] =
        c.data.H[i] * ExpSE3((Vec6() << RandomVec3(rng, 0.1), RandomVec3(rng, 0.5)).finished());
  for (int i = 0; i < c.model.nv; ++i)
    c.data.v(i) = std::uniform_real_distribution<double>(-1, 1)(rng);
  return c;
}

// The node rows (all nodes, 6 each) of every segment of the tendon, and its tangent.
template <class Kind>
void AssembleKind(const Model& m, const Data& d, const KernelOptions& o, Eigen::VectorXd* r,
                  Eigen::MatrixXd* K, Eigen::MatrixXd* C) {
  const int n = static_cast<int>(m.nodes.size());
  r->setZero(6 * n);
  if (K) K->setZero(6 * n, 6 * n);
  if (C) C->setZero(6 * n, 6 * n);
  Kind::ForEach(m, [&](const typename Kind::Item& item, const int(&nodes)[2]) {
    NodeMotion<2> x;
    const Mat6 I = Mat6::Identity();
    for (int i = 0; i < 2; ++i) {
      x.H[i] = &NodeFrame(d, nodes[i]);
      x.T[i] = &I;
    }
    GatherNodeMotion<2>(m, d, nodes, &x.eta, &x.eta_dot);
    ElementTerms<2> t;
    ASSERT_TRUE(Kind::Calc(m, d, item, x, o, &t));
    if (!t.active) return;
    for (int a = 0; a < 2; ++a) {
      if (nodes[a] == kGround) continue;
      r->segment<6>(6 * nodes[a]) += t.residual.template segment<6>(6 * a);
      for (int b = 0; b < 2; ++b) {
        if (nodes[b] == kGround) continue;
        // The tendon's kernel forms its matrix (c_K K T; K with the options used here).
        if (K && (t.has_stiffness || t.combined))
          K->block<6, 6>(6 * nodes[a], 6 * nodes[b]) +=
              (t.combined ? t.matrix : t.stiffness).template block<6, 6>(6 * a, 6 * b);
        if (C && t.has_damping)
          C->block<6, 6>(6 * nodes[a], 6 * nodes[b]) +=
              t.damping.template block<6, 6>(6 * a, 6 * b);
      }
    }
  });
}

// Central differences of f(data) over the right-trivialised increments of every node.
template <class F>
Eigen::MatrixXd FiniteDifference(const Chain& c, F&& f, double eps) {
  return kind_assembly::FiniteDifference(c.model, c.data, f, eps);
}

TEST(TendonSegmentKind, SegmentsSumToTensionTimesTheLengthGradientWithTheExactTangent) {
  std::mt19937 rng(3);
  const double tau = 12.5, tau2 = 4.75;
  const Chain c = MakeChain(rng, tau, tau2);
  ASSERT_EQ(c.model.tendon_segments.size(), 6u);  // ground + 4 eyelets, and 3 eyelets
  // One item per node pair: (ground, 0), (0, 1), and (1, 2), (2, 3) with both tendons.
  ASSERT_EQ(c.model.tendon_segment_groups.size(), 4u);
  EXPECT_EQ(c.model.tendon_segment_groups[2].count, 2);
  EXPECT_EQ(c.model.tendon_segment_groups[3].count, 2);
  KernelOptions o;
  Eigen::VectorXd r;
  Eigen::MatrixXd K;
  AssembleKind<TendonSegmentKind>(c.model, c.data, o, &r, &K, nullptr);
  // Force = gradient of the potential tau L + tau2 L2 (constant tensions).
  const Eigen::MatrixXd dV = FiniteDifference(
      c,
      [&](const Data& d) {
        return Eigen::VectorXd::Constant(1, tau * CalcTendonState(c.model, d, 0).length +
                                                tau2 * CalcTendonState(c.model, d, 1).length);
      },
      1e-6);
  EXPECT_LT(RelativeError(r, dV.transpose()), 1e-8);
  const Eigen::MatrixXd dr = FiniteDifference(
      c,
      [&](const Data& d) {
        Eigen::VectorXd rr;
        AssembleKind<TendonSegmentKind>(c.model, d, o, &rr, nullptr, nullptr);
        return rr;
      },
      1e-6);
  EXPECT_LT(RelativeError(K, dr), 1e-7);
  // The tangent is not symmetric (the rotation terms, docs/numerics.md, "Tendons and force elements").
  EXPECT_GT((K - K.transpose()).norm(), 1e-3 * K.norm());
  // The rate is the gradient times the velocities (the first tendon alone).
  const Chain one = MakeChain(rng, tau);
  AssembleKind<TendonSegmentKind>(one.model, one.data, o, &r, nullptr, nullptr);
  const LineForceState s = CalcTendonState(one.model, one.data, 0);
  EXPECT_NEAR(s.rate, r.dot(one.data.v.head(r.size())) / tau, 1e-12);
  EXPECT_EQ(s.force, tau);
}

TEST(TendonSegmentKind, TangentTimesNodeTangentsIsTensionTimesTheHessianTimesThem) {
  // The kernel forms c_K sum(tau d2l) T over the segments of an item (elements/tendon.cpp,
  // factored, without the 12 x 12 hessians, and with the block structure [A B; 0 A] of the
  // SE(3) node tangents); the reference is the sum of tau times CalcPointDistance's hessian
  // (checked against finite differences above) times blockdiag(T_A, T_B), with T = TSE3 of
  // random increments (the node tangents of a dynamic step).
  std::mt19937 rng(11);
  const double tau = 7.25, tau2 = 2.5;
  const Chain c = MakeChain(rng, tau, tau2);
  KernelOptions o;
  o.c_stiffness = 0.37;
  o.node_tangent = true;
  int pairs = 0;
  for (std::size_t k = 0; k < c.model.tendon_segment_groups.size(); ++k) {
    const TendonSegmentGroup& group = c.model.tendon_segment_groups[k];
    const int nodes[2] = {group.node_a, group.node_b};
    Mat6 T[2];
    NodeMotion<2> x;
    for (int i = 0; i < 2; ++i) {
      T[i] = TSE3((Vec6() << RandomVec3(rng, 0.3), RandomVec3(rng, 0.6)).finished());
      x.H[i] = &NodeFrame(c.data, nodes[i]);
      x.T[i] = &T[i];
    }
    ElementTerms<2> t;
    ASSERT_TRUE(TendonSegmentKind::Calc(c.model, c.data, static_cast<int>(k), x, o, &t));
    ASSERT_TRUE(t.active && t.combined);
    Mat12 Tblock = Mat12::Zero();
    Tblock.topLeftCorner<6, 6>() = T[0];
    Tblock.bottomRightCorner<6, 6>() = T[1];
    Mat12 expected = Mat12::Zero();
    Vec12 residual = Vec12::Zero();
    for (int i = 0; i < group.count; ++i) {
      const TendonSegment& s = c.model.tendon_segments[static_cast<std::size_t>(
          c.model.tendon_group_segments[static_cast<std::size_t>(group.first + i)])];
      ASSERT_EQ(s.a.node, nodes[0]);
      ASSERT_EQ(s.b.node, nodes[1]);
      const double tension = s.tendon == 0 ? tau : tau2;
      PointDistance g;
      ASSERT_TRUE(CalcPointDistance(*x.H[0], s.a.offset, *x.H[1], s.b.offset, true, &g));
      expected += o.c_stiffness * tension * g.hessian * Tblock;
      residual += tension * g.gradient;
    }
    pairs += group.count == 2;
    EXPECT_LT((t.matrix - expected).norm(), 1e-13 * expected.norm()) << "item " << k;
    EXPECT_LT((t.residual - residual).norm(), 1e-14 * tau) << "item " << k;
  }
  EXPECT_EQ(pairs, 2);
}

TEST(TendonSegmentKind, StatesTensionNeverNegativeAndLoadFactorScalesIt) {
  Tendon t;
  Data data;
  data.inputs = Eigen::VectorXd::Zero(1);
  t.tension = Profile::Ramp(0.0, 1.0, 10.0);
  EXPECT_DOUBLE_EQ(TendonTension(t, data, 0.5), 5.0);
  EXPECT_DOUBLE_EQ(TendonTension(t, data, 0.5, 0.5), 2.5);
  t.tension = Profile::Constant(-3.0);  // a run-time value that would push: slack
  EXPECT_EQ(TendonTension(t, data, 0.0), 0.0);
  // A tension taken from a run-time input (EvalProfile): its value, scaled; slack below 0.
  t.tension = Profile::Input(0, 2.0);
  data.inputs(0) = 1.5;
  EXPECT_DOUBLE_EQ(TendonTension(t, data, 0.0), 3.0);
  data.inputs(0) = -1.0;
  EXPECT_EQ(TendonTension(t, data, 0.0), 0.0);
}

TEST(TendonSegmentKind, TensionAndActuatorProfilesAreBreakpointsOfTheModel) {
  // Steps end and the integrator restarts at their breakpoints, as at drives' and loads'.
  ModelBuilder b;
  const NodeId n = b.AddNode(SE3::Identity());
  b.AddRigidBody("b", n, 1.0, Vec3::Zero(), Mat3::Identity());
  b.AddTendon("t", {{kGround, Vec3(1, 0, 0)}, {n, Vec3::Zero()}}, Profile::Ramp(0.25, 0.5, 2.0));
  ForceElement fe;
  fe.a = {kGround, Vec3(0, 1, 0)};
  fe.b = {n, Vec3::Zero()};
  fe.actuator = Profile::BangBang(0.75, 1.5);
  b.AddForceElement(fe);
  std::vector<double> breakpoints = ProfileBreakpoints(b.Build());
  std::sort(breakpoints.begin(), breakpoints.end());
  EXPECT_EQ(breakpoints, (std::vector<double>{0.25, 0.5, 0.75, 1.125, 1.5}));
}

TEST(ForceElementKind, ForceIsTheSpringDamperActuatorLawWithExactTangents) {
  std::mt19937 rng(5);
  const Chain c = MakeChain(rng, 0.0);
  const ForceElement& fe = c.model.force_elements[0];
  KernelOptions o;
  o.dynamics = true;
  Eigen::VectorXd r;
  Eigen::MatrixXd K, C;
  AssembleKind<ForceElementKind>(c.model, c.data, o, &r, &K, &C);
  // The closed form: f = k (l - l0) + c dl/dt + F along the gradient of l.
  const LineForceState s = CalcForceElementState(c.model, c.data, 0);
  const Eigen::MatrixXd dl = FiniteDifference(
      c,
      [&](const Data& d) {
        return Eigen::VectorXd::Constant(1, CalcForceElementState(c.model, d, 0).length);
      },
      1e-6);
  const double f = fe.stiffness * (s.length - fe.rest_length) + fe.damping * s.rate + 1.5;
  EXPECT_NEAR(s.force, f, 1e-12);
  EXPECT_NEAR(s.rate, dl.row(0).dot(c.data.v.head(dl.cols())), 1e-8);
  EXPECT_LT(RelativeError(r, f * dl.row(0).transpose()), 1e-8);
  // Stiffness: d r / dq at fixed velocities (incl. the damper's dl/dt = g(q)^T eta).
  const Eigen::MatrixXd dr = FiniteDifference(
      c,
      [&](const Data& d) {
        Eigen::VectorXd rr;
        AssembleKind<ForceElementKind>(c.model, d, o, &rr, nullptr, nullptr);
        return rr;
      },
      1e-6);
  EXPECT_LT(RelativeError(K, dr), 1e-7);
  // Damping: d r / d eta.
  Eigen::MatrixXd dv(r.size(), r.size());
  for (int j = 0; j < r.size(); ++j) {
    Data p = c.data, m = c.data;
    p.v(j) += 1e-6;
    m.v(j) -= 1e-6;
    Eigen::VectorXd rp, rm;
    AssembleKind<ForceElementKind>(c.model, p, o, &rp, nullptr, nullptr);
    AssembleKind<ForceElementKind>(c.model, m, o, &rm, nullptr, nullptr);
    dv.col(j) = (rp - rm) / 2e-6;
  }
  EXPECT_LT(RelativeError(C, dv), 1e-8);
  // Without dynamics the damper is off and the spring force is the energy's gradient.
  o.dynamics = false;
  AssembleKind<ForceElementKind>(c.model, c.data, o, &r, nullptr, nullptr);
  const Eigen::MatrixXd dE = FiniteDifference(
      c,
      [&](const Data& d) {
        Energy e;
        ForceElementKind::AddEnergy(c.model, d, 0, &e);
        return Eigen::VectorXd::Constant(1, e.spring);
      },
      1e-6);
  const Eigen::VectorXd actuator = 1.5 * dl.row(0).transpose();
  EXPECT_LT(RelativeError(r - actuator, dE.transpose()), 1e-8);
}

// What forces.csv reports (CalcForceElementState) is the tension the kernel puts in the
// residual: node B's rows carry f e and node A's -f e (world, e the unit vector from a to b);
// in statics the damper is off and the actuator scales with the load factor.
TEST(ForceElementKind, ReportedForceIsTheTensionInTheKernelsResidual) {
  for (unsigned seed : {5u, 6u, 7u}) {
    std::mt19937 rng(seed);
    const Chain c = MakeChain(rng, 0.0);
    const ForceElement& fe = c.model.force_elements[0];
    const Vec3 pa = BodyPointPosition(c.data, fe.a), pb = BodyPointPosition(c.data, fe.b);
    const Vec3 e = (pb - pa).normalized();
    auto tension = [&](const KernelOptions& o, double* opposite) {
      Eigen::VectorXd r;
      AssembleKind<ForceElementKind>(c.model, c.data, o, &r, nullptr, nullptr);
      const SE3& Ha = c.data.H[static_cast<std::size_t>(fe.a.node)];
      const SE3& Hb = c.data.H[static_cast<std::size_t>(fe.b.node)];
      *opposite = -e.dot(Ha.R * r.segment<3>(6 * fe.a.node));
      return e.dot(Hb.R * r.segment<3>(6 * fe.b.node));
    };
    const LineForceState s = CalcForceElementState(c.model, c.data, 0);
    ASSERT_GT(std::abs(s.rate), 0.1);
    KernelOptions o;
    o.dynamics = true;
    double opposite = 0.0;
    const double f = tension(o, &opposite);
    EXPECT_NEAR(f, s.force, 1e-13 * std::abs(s.force)) << seed;
    EXPECT_NEAR(opposite, s.force, 1e-13 * std::abs(s.force)) << seed;
    EXPECT_NEAR(s.force, fe.stiffness * (s.length - fe.rest_length) + fe.damping * s.rate + 1.5,
                1e-13 * std::abs(s.force));
    o.dynamics = false;
    o.load_factor = 0.5;
    EXPECT_NEAR(tension(o, &opposite), fe.stiffness * (s.length - fe.rest_length) + 0.75,
                1e-13 * std::abs(s.force))
        << seed;
  }
}

TEST(ForceElementKind, ForcesHaveZeroWorldResultantSoMomentumIsConserved) {
  std::mt19937 rng(9);
  for (int c = 0; c < 10; ++c) {
    const SE3 HA = RandomFrame(rng), HB = RandomFrame(rng);
    const Vec3 rA = RandomVec3(rng, 0.3), rB = RandomVec3(rng, 0.3);
    PointDistance g;
    ASSERT_TRUE(CalcPointDistance(HA, rA, HB, rB, false, &g));
    // Node-frame wrench [f; m] at node X -> world force R f and moment about the origin
    // x x R f + R m.
    Vec6 total = Vec6::Zero();
    for (const auto& [H, w] :
         {std::pair<SE3, Vec6>{HA, g.gradient.head<6>()}, {HB, g.gradient.tail<6>()}}) {
      const Vec3 f = H.R * w.head<3>();
      total.head<3>() += f;
      total.tail<3>() += H.x.cross(f) + H.R * w.tail<3>();
    }
    EXPECT_LT(total.norm(), 1e-14 * (1.0 + HA.x.norm() + HB.x.norm())) << "case " << c;
  }
}

}  // namespace
}  // namespace screwfem::tendon_test
