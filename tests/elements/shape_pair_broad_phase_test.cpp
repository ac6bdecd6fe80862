// The broad phase of the pairs of moving shapes (UpdateShapePairs, elements/shape_pair.h):
// every pair nearer than the onset is found, each once, and its cost grows linearly with the
// number of shapes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/lie/se3.h"

namespace screwfem::shape_pair_broad_phase_test {
namespace {

// What names a pair: its two segments, its part and (two boxes) the edge of side A.
using PairKey = std::tuple<int, int, int, double, double, double, double, double, double>;
PairKey KeyOf(const ShapePair& p) {
  const Vec3& a = p.side[0].offset[0];
  const Vec3& b = p.side[0].offset[1];
  return {p.segment[0], p.segment[1], p.part, a.x(), a.y(), a.z(), b.x(), b.y(), b.z()};
}

Section RodSection(double radius) {
  Material mat;
  mat.youngs_modulus = 1e7;
  mat.poisson_ratio = 0.45;
  mat.density = 1100.0;
  return Section::Circle(radius, mat);
}

// Three free rods of 12 elements and one of 40 elements 5 mm long (radius 10 mm: chunks of 4
// elements in the grid), self-contact on with the given skip (negative: the default 4 r),
// and three free bodies (a sphere, a capsule and a box): every kind of pair.
Model MakeScene(double self_skip) {
  const double r = 0.01;
  ModelBuilder b;
  for (int k = 0; k < 4; ++k) {
    const double y = 0.1 * k;
    const RodId rod =
        b.AddStraightRod("rod" + std::to_string(k), Vec3(0.0, y, 0.0),
                         Vec3(k < 3 ? 0.36 : 0.2, y, 0.0), k < 3 ? 12 : 40, RodSection(r));
    b.AddContactRod(rod, r);
  }
  const Mat3 J = 1e-4 * Mat3::Identity();
  const BodyId sphere = b.AddRigidBody("sphere", b.AddNode(SE3{Mat3::Identity(), Vec3(0, 0, 1)}),
                                       0.1, Vec3::Zero(), J);
  const BodyId capsule = b.AddRigidBody("capsule", b.AddNode(SE3{Mat3::Identity(), Vec3(0, 0, 2)}),
                                        0.1, Vec3::Zero(), J);
  const BodyId box =
      b.AddRigidBody("box", b.AddNode(SE3{Mat3::Identity(), Vec3(0, 0, 3)}), 0.1, Vec3::Zero(), J);
  b.AddContactShape({sphere, ContactShapeType::kSphere, Vec3::Zero(), Vec3::Zero(), 0.04});
  b.AddContactShape(
      {capsule, ContactShapeType::kCapsule, Vec3(-0.05, 0, 0), Vec3(0.05, 0, 0), 0.02});
  b.AddContactShape({box, ContactShapeType::kBox, Vec3::Zero(), Vec3(0.06, 0.04, 0.03), 0.0});
  ContactSettings law;
  law.stiffness = 1e3;
  law.onset = 0.01;
  law.self = true;
  law.self_skip = self_skip;
  b.SetContactSettings(law);
  return b.Build();
}

// Scatters the shapes in a 0.25 m cube: rods as random walks of 0.03 m steps, every frame
// randomly turned, so that many shapes touch.
void Scatter(const Model& m, std::mt19937& rng, Data* d) {
  std::uniform_real_distribution<double> u(0.0, 0.25), s(-1.0, 1.0);
  auto turn = [&] { return ExpSO3(Vec3(s(rng), s(rng), s(rng)) * 3.0); };
  for (const Rod& rod : m.rods) {
    Vec3 x(u(rng), u(rng), u(rng));
    for (int node : rod.nodes) {
      d->H[static_cast<std::size_t>(node)] = SE3{turn(), x};
      x += 0.03 * Vec3(s(rng), s(rng), s(rng)).normalized();
    }
  }
  for (const RigidBody& body : m.bodies)
    d->H[static_cast<std::size_t>(body.node)] = SE3{turn(), Vec3(u(rng), u(rng), u(rng))};
}

// In 40 random scatterings the broad phase finds every pair of AllShapePairs (the O(n^2)
// reference) whose surfaces are nearer than the onset, lists no pair twice and none that the
// reference does not have (they may touch: groups, exclusions, self skip); with the default
// skip (chunks of the fine rod never pair with their neighbours) and with a skip of 8 mm
// (elements 3 apart in one chunk of the fine rod may touch).
class ShapePairBroadPhase : public ::testing::TestWithParam<double> {};

TEST_P(ShapePairBroadPhase, FindsEveryPairNearerThanTheOnsetOnce) {
  const Model m = MakeScene(GetParam());
  Data fresh = MakeData(m);
  ASSERT_EQ(fresh.shape_pair_grid.chunk_first.size(), 3u * 12u + 10u + 3u + 1u);
  const std::vector<ShapePair> all = AllShapePairs(m);
  std::set<PairKey> possible;
  for (const ShapePair& p : all) possible.insert(KeyOf(p));
  ASSERT_EQ(possible.size(), all.size());
  Data d = MakeData(m);
  std::mt19937 rng(7);
  int near = 0, found = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Scatter(m, rng, &d);
    UpdateShapePairs(m, d);
    std::set<PairKey> pool;
    for (int i = 0; i < d.num_shape_pairs; ++i) {
      const PairKey key = KeyOf(d.shape_pairs[static_cast<std::size_t>(i)]);
      EXPECT_TRUE(pool.insert(key).second) << "a pair twice, trial " << trial;
      EXPECT_TRUE(possible.count(key)) << "a pair that may not touch, trial " << trial;
    }
    found += d.num_shape_pairs;
    for (const ShapePair& p : all) {
      const SE3* H[4] = {&NodeFrame(d, p.side[0].node[0]), &NodeFrame(d, p.side[0].node[1]),
                         &NodeFrame(d, p.side[1].node[0]), &NodeFrame(d, p.side[1].node[1])};
      ShapePairGeometry G;
      if (!CalcShapePairGeometry(p, H, INFINITY, &G) || !(G.gap < m.contact.onset)) continue;
      ++near;
      EXPECT_TRUE(pool.count(KeyOf(p))) << "missed a pair at gap " << G.gap << ", trial " << trial;
    }
  }
  EXPECT_GT(near, 400);         // the scatterings do bring many shapes together
  EXPECT_LT(found, 20 * near);  // and the boxes keep the candidates few
}
INSTANTIATE_TEST_SUITE_P(Skips, ShapePairBroadPhase, ::testing::Values(-1.0, 0.008));

// A rod of n elements (r = 5 mm, 1 cm long) laid on a flat spiral whose turns are 11 mm apart
// (1 mm between the surfaces, less than the onset): every element is near the elements of the
// next turn. The pairs found and the box tests of the search both grow as n (the reference
// lists n^2 / 2), and the pairs are those of the reference nearer than the onset.
TEST(ShapePairBroadPhaseCost, GrowsLinearlyWithTheElements) {
  const double r = 0.005, ds = 0.01, pitch = 2.0 * r + 0.001;
  std::vector<double> pairs, tests;
  const int sizes[3] = {250, 500, 1000};
  for (int n : sizes) {
    ModelBuilder b;
    const RodId rod = b.AddStraightRod("coil", Vec3::Zero(), Vec3(n * ds, 0, 0), n, RodSection(r));
    b.AddContactRod(rod, r);
    ContactSettings law;
    law.stiffness = 1e3;
    law.onset = 0.002;
    law.self = true;
    b.SetContactSettings(law);
    const Model m = b.Build();
    Data d = MakeData(m);
    // The spiral rho = a + pitch theta / (2 pi), nodes ds apart along it.
    double theta = 0.0;
    for (int node : m.rods[0].nodes) {
      const double rho = 0.05 + pitch * theta / (2.0 * M_PI);
      d.H[static_cast<std::size_t>(node)].x = Vec3(rho * std::cos(theta), rho * std::sin(theta), 0);
      theta += ds / rho;
    }
    UpdateShapePairs(m, d);
    pairs.push_back(d.num_shape_pairs);
    tests.push_back(static_cast<double>(d.shape_pair_grid.box_tests));
    if (n == sizes[0]) {
      int near = 0;
      for (const ShapePair& p : AllShapePairs(m)) {
        const SE3* H[4] = {&NodeFrame(d, p.side[0].node[0]), &NodeFrame(d, p.side[0].node[1]),
                           &NodeFrame(d, p.side[1].node[0]), &NodeFrame(d, p.side[1].node[1])};
        ShapePairGeometry G;
        if (CalcShapePairGeometry(p, H, INFINITY, &G) && G.gap < law.onset) ++near;
      }
      EXPECT_GE(d.num_shape_pairs, near);
      EXPECT_GT(near, n);  // each element touches about two of the next turn
      EXPECT_LT(d.num_shape_pairs, 3 * near);
    }
  }
  // Measured: 763 / 1689 / 3556 pairs and 9481 / 21551 / 45310 box tests, 12.4 / 12.8 / 12.7
  // tests per pair (the pairs per element rise from 3.1 to 3.6 as the outermost turn, which
  // has no neighbour outside, becomes a smaller part of the rod).
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(pairs[k + 1] / pairs[k], 1.8) << k;
    EXPECT_LT(tests[k + 1] / tests[k], 2.4) << k;  // linear: x 2 per doubling, not x 4
    EXPECT_NEAR(tests[k + 1] / pairs[k + 1], tests[0] / pairs[0], 0.1 * tests[0] / pairs[0]);
  }
  EXPECT_LT(pairs[2], 4.0 * sizes[2]);
  EXPECT_LT(tests[2], 50.0 * sizes[2]);
}

}  // namespace
}  // namespace screwfem::shape_pair_broad_phase_test
