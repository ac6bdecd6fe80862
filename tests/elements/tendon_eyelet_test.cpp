// Tendon eyelets between rod nodes (elements/tendon.h, TendonSpanSegmentKind; docs/numerics.md,
// "Eyelets between nodes"): an eyelet at an arc length inside an element sits on the section
// frame H_A exp(xi d) of the helical interpolation. Checks:
//  * the segments' node rows are tau dL/dq (L the tendon length, by central differences through
//    the retraction of every node) and their stiffness is the derivative of those rows;
//  * the length-gradient parts the length-driven rows use (CalcSegmentGradient) are dL/dq;
//  * a straight tendon at offset d with eyelets at element midpoints bends a cantilever into
//    the arc kappa = tau d / EI at second order in the element length, with no clamp reaction
//    (no gravity), and the strain energy changes by -tau dL (dU/dL = -tau at equilibrium).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "kind_assembly.h"
#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/solve/statics.h"

namespace screwfem::tendon_eyelet_test {
namespace {

constexpr double kEA = 1e5, kEI = 1.0, kOffset = 0.02;

Section RodSection() {
  return Section::FromDiagonals((Vec6() << kEA, kEA, kEA, kEI, kEI, kEI).finished());
}

double RelativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

using kind_assembly::AssembleKind;
using kind_assembly::FiniteDifference;

// A curved rod (a helix-like path through 5 nodes, 4 elements) with a tendon from the ground
// through eyelets at element interiors (two in one element, consecutive), on a node, and the
// tip, in a randomly perturbed configuration.
struct Scene {
  Model model;
  Data data;
};

Scene MakeScene(std::mt19937& rng, double tension) {
  ModelBuilder b;
  b.SetConformMesh(false);  // the span kinds: features between nodes stay there
  std::vector<Vec3> path;
  for (int i = 0; i <= 4; ++i) path.emplace_back(0.3 * i, 0.1 * std::sin(1.1 * i), 0.05 * i * i);
  const RodId rod = b.AddRodAlongPath("rod", path, 1, RodSection());
  const double length = b.RodLength(rod);
  std::vector<BodyPoint> eyelets;
  eyelets.push_back({kGround, Vec3(-0.3, 0.2, 0.1)});
  const double s[] = {0.13, 0.41, 0.52, 0.0, 1.0, 0.7};  // fractions of the rod length
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double f : s) {
    BodyPoint p{kGround, Vec3(0.02 * u(rng), 0.05 * u(rng), 0.05 * u(rng))};
    p.rod = rod;
    p.arc_length = f * length;
    eyelets.push_back(p);
  }
  b.AddTendon("t", eyelets, Profile::Constant(tension));
  Scene c{b.Build(), {}};
  c.data = MakeData(c.model);
  kind_assembly::PerturbFrames(rng, 0.05, 0.4, &c.data);
  return c;
}

TEST(TendonEyelets, PlacedOnNodesOrBetweenThemAtTheirArcLength) {
  std::mt19937 rng(5);
  const Scene c = MakeScene(rng, 1.0);
  const Tendon& t = c.model.tendons[0];
  ASSERT_EQ(t.eyelets.size(), 7u);
  // 0.13, 0.41, 0.52, 0.7 of the length lie inside elements; 0 and 1 on the end nodes.
  for (int k : {1, 2, 3, 6}) EXPECT_GE(t.eyelets[static_cast<std::size_t>(k)].element, 0) << k;
  EXPECT_EQ(t.eyelets[4].element, -1);
  EXPECT_EQ(t.eyelets[5].element, -1);
  EXPECT_EQ(t.eyelets[4].node, c.model.rods[0].nodes.front());
  EXPECT_EQ(t.eyelets[5].node, c.model.rods[0].nodes.back());
  // The reference position of an eyelet between nodes: the section of the helical element at
  // that arc length (on the rod's centreline, which passes through the path points).
  const Data ref = MakeData(c.model);
  for (int k : {1, 2, 3, 6}) {
    const BodyPoint& p = t.eyelets[static_cast<std::size_t>(k)];
    const RodElement& e = c.model.elements[static_cast<std::size_t>(p.element)];
    const SE3 H = ref.H[static_cast<std::size_t>(e.node_a)] * ExpSE3(p.xi * e.d0);
    EXPECT_LT((BodyPointPosition(c.model, ref, p) - (H.x + H.R * p.offset)).norm(), 1e-14);
    EXPECT_GT(p.xi, 0.0);
    EXPECT_LT(p.xi, 1.0);
  }
  // Off the rod: an error naming the eyelet.
  ModelBuilder b;
  b.SetConformMesh(false);  // the span kinds: features between nodes stay there
  const RodId rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3::UnitX(), 2, RodSection());
  BodyPoint off{kGround, Vec3::Zero()};
  off.rod = rod;
  off.arc_length = 1.5;
  b.AddTendon("t", {{kGround, Vec3(0, 1, 0)}, off}, Profile::Constant(1.0));
  try {
    b.Build();
    ADD_FAILURE() << "an eyelet off the rod was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("eyelet 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("off the rod"), std::string::npos) << e.what();
  }
}

TEST(TendonEyelets, RowsAreTensionTimesTheLengthGradientWithTheExactTangent) {
  std::mt19937 rng(9);
  const double tau = 8.5;
  const Scene c = MakeScene(rng, tau);
  int span = 0;
  TendonSpanSegmentKind::ForEach(c.model, [&](int, const int(&)[4]) { ++span; });
  ASSERT_EQ(span, 5);  // all segments but the one between the end nodes (TendonSegmentKind)
  KernelOptions o;
  Eigen::VectorXd r, r2;
  Eigen::MatrixXd K, K2;
  AssembleKind<TendonSegmentKind>(c.model, c.data, o, &r2, &K2);
  AssembleKind<TendonSpanSegmentKind>(c.model, c.data, o, &r, &K);
  r += r2;
  K += K2;
  // Force = gradient of the potential tau L(q): the tension does the work -tau dL.
  const Eigen::MatrixXd dV = FiniteDifference(
      c.model, c.data,
      [&](const Data& d) {
        return Eigen::VectorXd::Constant(1, tau * CalcTendonLength(c.model, d, 0));
      },
      1e-6);
  EXPECT_LT(RelativeError(r, dV.transpose()), 1e-8);
  const Eigen::MatrixXd dr = FiniteDifference(
      c.model, c.data,
      [&](const Data& d) {
        Eigen::VectorXd a, b;
        AssembleKind<TendonSegmentKind>(c.model, d, o, &a, nullptr);
        AssembleKind<TendonSpanSegmentKind>(c.model, d, o, &b, nullptr);
        return Eigen::VectorXd(a + b);
      },
      1e-6);
  EXPECT_LT(RelativeError(K, dr), 1e-7);
  // The gradient parts of the length-driven rows add up to the same dL/dq.
  Eigen::VectorXd B = Eigen::VectorXd::Zero(r.size());
  for (const TendonSegment& s : c.model.tendon_segments) {
    SegmentGradient g;
    ASSERT_TRUE(CalcSegmentGradient(c.model, c.data, s, &g));
    for (int i = 0; i < g.count; ++i) B.segment<6>(6 * g.nodes[i]) += g.parts[i];
  }
  EXPECT_LT(RelativeError(tau * B, dV.transpose()), 1e-8);
  EXPECT_NEAR(CalcTendonState(c.model, c.data, 0).length, CalcTendonLength(c.model, c.data, 0),
              1e-15);
}

// A straight cantilever along x, clamped at node 0, with a tendon at offset d along the
// section's y through eyelets at the clamp, at every element's midpoint and at the tip.
struct Cantilever {
  Model model;
  Data data;
  StaticResult result;
};

Cantilever SolveCantilever(int elements, double tension, bool by_length = false) {
  ModelBuilder b;
  b.SetConformMesh(false);  // the span kinds: features between nodes stay there
  const RodId rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3::UnitX(), elements, RodSection());
  b.FixNode(b.RodNodes(rod).front());
  std::vector<BodyPoint> eyelets;
  auto add = [&](double s) {
    BodyPoint p{kGround, Vec3(0.0, kOffset, 0.0)};
    p.rod = rod;
    p.arc_length = s;
    eyelets.push_back(p);
  };
  add(0.0);
  for (int e = 0; e < elements; ++e) add((e + 0.5) / elements);
  add(1.0);
  if (by_length)  // `tension` is then the prescribed length
    b.AddLengthDrivenTendon("tendon", eyelets, Profile::Constant(tension));
  else
    b.AddTendon("tendon", eyelets, Profile::Constant(tension));
  Cantilever c{b.Build(), {}, {}};
  c.data = MakeData(c.model);
  StaticOptions o;
  o.load_steps = 20;
  c.result = SolveStatic(c.model, c.data, o);
  return c;
}

// The force the clamp applies to node 0: minus node 0's rows of every item on it.
Vec6 ClampReaction(const Cantilever& c) {
  const int clamp = c.model.rods[0].nodes.front();
  KernelOptions o;
  o.tangent = false;
  Eigen::VectorXd r, rows = Eigen::VectorXd::Zero(6 * static_cast<int>(c.model.nodes.size()));
  AssembleKind<RodElementKind>(c.model, c.data, o, &r, nullptr);
  rows += r;
  AssembleKind<TendonSegmentKind>(c.model, c.data, o, &r, nullptr);
  rows += r;
  AssembleKind<TendonSpanSegmentKind>(c.model, c.data, o, &r, nullptr);
  rows += r;
  return -rows.segment<6>(6 * clamp);
}

TEST(TendonEyelets, MidpointEyeletsBendACantileverIntoTheArcAtSecondOrder) {
  const double tau = 50.0;
  const double k = tau * kOffset / kEI, eps = -tau / kEA;
  const Vec3 arc((1 + eps) / k * std::sin(k), (1 + eps) / k * (1 - std::cos(k)), 0.0);
  const int elements[3] = {4, 8, 16};
  double error[3];
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(elements[i]);
    const Cantilever c = SolveCantilever(elements[i], tau);
    ASSERT_TRUE(c.result.converged) << c.result.message;
    ASSERT_EQ(c.model.tendon_segments.size(), static_cast<std::size_t>(elements[i] + 1));
    const Vec3 x = c.data.H[static_cast<std::size_t>(c.model.rods[0].nodes.back())].x;
    EXPECT_NEAR(x.z(), 0.0, 1e-12);
    error[i] = (x - arc).norm();
    const Vec6 reaction = ClampReaction(c);
    EXPECT_LT(reaction.norm(), 1e-8 * tau) << reaction.transpose();
    EXPECT_EQ(CalcTendonState(c.model, c.data, 0).force, tau);
  }
  // Second order in the element length (measured: errors 1.25e-1, 2.95e-2, 7.42e-3 m, ratios
  // 4.23 and 3.97).
  EXPECT_GT(error[0] / error[1], 3.5);
  EXPECT_GT(error[1] / error[2], 3.5);
  EXPECT_LT(error[2], 0.01);
}

TEST(TendonEyelets, StrainEnergyChangesByMinusTensionTimesTendonLength) {
  // At equilibrium under U + tau L: dU = -tau dL (the tension's work goes into strain energy).
  const double tau = 30.0, dt = 0.3;
  const Cantilever lo = SolveCantilever(6, tau - dt), hi = SolveCantilever(6, tau + dt);
  ASSERT_TRUE(lo.result.converged && hi.result.converged);
  const double dU = CalcEnergy(hi.model, hi.data).strain - CalcEnergy(lo.model, lo.data).strain;
  const double dL =
      CalcTendonState(hi.model, hi.data, 0).length - CalcTendonState(lo.model, lo.data, 0).length;
  EXPECT_LT(dL, 0.0);
  EXPECT_NEAR(-dU / dL, tau, 1e-4 * tau);
}

TEST(TendonEyelets, DrawnByLengthTheMultiplierIsTheTensionThatGivesTheLength) {
  // Drawn by tension 50 N the tendon shortens to L*; drawn to L* by length (its row's gradient
  // from both nodes of every midpoint eyelet's element), the multiplier is 50 N, same shape.
  const Cantilever by_tension = SolveCantilever(4, 50.0);
  ASSERT_TRUE(by_tension.result.converged);
  const double length = CalcTendonState(by_tension.model, by_tension.data, 0).length;
  const Cantilever by_length = SolveCantilever(4, length, true);
  ASSERT_TRUE(by_length.result.converged) << by_length.result.message;
  EXPECT_LT((by_length.data.H.back().x - by_tension.data.H.back().x).norm(), 1e-9);
  EXPECT_NEAR(CalcTendonState(by_length.model, by_length.data, 0).force, 50.0, 1e-6);
}

}  // namespace
}  // namespace screwfem::tendon_eyelet_test
