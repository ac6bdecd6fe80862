// Validation S1 (docs/validation.md): a straight cantilever rolled up by an end moment.
//
// L = 10, EI = 100 (EA = GA = 1e4, GJ = 100), moment M = lambda 2 pi EI / L about z at the tip.
// Exact: curvature kappa = M / EI everywhere; the section at s is at
// (sin(kappa s), 1 - cos(kappa s)) / kappa, rotated by kappa s about z. The helical element
// represents this constant-strain state exactly, so one element is exact for every lambda < 1
// (element rotation 2 pi lambda < 2 pi; past pi only thanks to the branch continuation of
// elements/rod.h), and the full circle needs two elements.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "screwfem/elements/rod.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::rollup_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kL = 10.0, kEI = 100.0;

struct RollUpModel {
  Model model;
  std::vector<NodeId> nodes;  // along the rod, root first
};

RollUpModel MakeRollUp(int num_elements, double lambda) {
  ModelBuilder b;
  Vec6 k;
  k << 1e4, 1e4, 1e4, 100.0, kEI, kEI;
  const RodId rod = b.AddStraightRod("rollup", Vec3::Zero(), Vec3(kL, 0.0, 0.0), num_elements,
                                     Section::FromDiagonals(k));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  PointLoad load;
  load.node = nodes.back();
  load.frame = LoadFrame::kWorld;
  load.moment = Vec3(0.0, 0.0, lambda * 2.0 * kPi * kEI / kL);
  b.AddPointLoad(load);
  return {b.Build(), nodes};
}

Mat3 RotZ(double angle) { return ExpSO3(Vec3(0.0, 0.0, angle)); }

// Largest deviation of the nodes from the exact circle of curvature kappa: positions relative
// to L, rotation matrices in Frobenius norm.
void CircleErrors(const RollUpModel& m, const Data& d, double kappa, double* position,
                  double* rotation) {
  *position = *rotation = 0.0;
  const int ne = static_cast<int>(m.nodes.size()) - 1;
  for (int i = 0; i <= ne; ++i) {
    const double s = kL * i / ne;
    const Vec3 x =
        kappa == 0.0 ? Vec3(s, 0.0, 0.0)
                     : Vec3(std::sin(kappa * s) / kappa, (1.0 - std::cos(kappa * s)) / kappa, 0.0);
    const SE3& H = d.H[static_cast<std::size_t>(m.nodes[static_cast<std::size_t>(i)])];
    *position = std::max(*position, (H.x - x).norm() / kL);
    *rotation = std::max(*rotation, (H.R - RotZ(kappa * s)).norm());
  }
}

// Sum of the elements' rotations about z on their continued branches: the tip rotation
// including whole turns (the node frames alone only know it modulo 2 pi).
double TotalRotation(const Model& model, const Data& d) {
  double total = 0.0;
  for (const Vec3& w : d.w_ref) total += w.z();
  EXPECT_EQ(d.w_ref.size(), model.elements.size());
  return total;
}

TEST(RollUp, OneElementIsExactUpToNearlyAFullTurn) {
  for (const double lambda : {0.25, 0.5, 0.9}) {
    const RollUpModel m = MakeRollUp(1, lambda);
    Data d = MakeData(m.model);
    const StaticResult r = SolveStatic(m.model, d);
    ASSERT_TRUE(r.converged) << "lambda " << lambda << ": " << r.message;
    const double phi = lambda * 2.0 * kPi;  // = M L / EI
    const SE3& tip = d.H[static_cast<std::size_t>(m.nodes.back())];
    const Vec3 exact(kL * std::sin(phi) / phi, kL * (1.0 - std::cos(phi)) / phi, 0.0);
    EXPECT_LT((tip.x - exact).norm(), 1e-8 * kL) << "lambda " << lambda;
    EXPECT_LT((tip.R - RotZ(phi)).norm(), 1e-8) << "lambda " << lambda;
    EXPECT_NEAR(TotalRotation(m.model, d), phi, 1e-8 * phi) << "lambda " << lambda;
  }
}

TEST(RollUp, HalfTurnPutsTheTipAtTwoLOverPi) {
  const RollUpModel m = MakeRollUp(1, 0.5);
  Data d = MakeData(m.model);
  ASSERT_TRUE(SolveStatic(m.model, d).converged);
  const Vec3 tip = d.H[static_cast<std::size_t>(m.nodes.back())].x;
  EXPECT_LT((tip - Vec3(0.0, 2.0 * kL / kPi, 0.0)).norm(), 1e-8 * kL);
}

TEST(RollUp, FullCircleWithTwoAndTenElementsIsExactAtEveryNode) {
  for (const int ne : {2, 10}) {
    const RollUpModel m = MakeRollUp(ne, 1.0);
    Data d = MakeData(m.model);
    const StaticResult r = SolveStatic(m.model, d);
    ASSERT_TRUE(r.converged) << ne << " elements: " << r.message;
    double position = 0.0, rotation = 0.0;
    CircleErrors(m, d, 2.0 * kPi / kL, &position, &rotation);
    EXPECT_LT(position, 1e-8) << ne << " elements";
    EXPECT_LT(rotation, 1e-8) << ne << " elements";
    // The tip is back at the root with the root's orientation, after one full turn.
    const SE3& tip = d.H[static_cast<std::size_t>(m.nodes.back())];
    EXPECT_LT(tip.x.norm(), 1e-8 * kL) << ne << " elements";
    EXPECT_NEAR(TotalRotation(m.model, d), 2.0 * kPi, 1e-8) << ne << " elements";
  }
}

TEST(RollUp, IntermediateNodesLieOnTheExactCircle) {
  for (const double lambda : {0.25, 0.75}) {
    const RollUpModel m = MakeRollUp(5, lambda);
    Data d = MakeData(m.model);
    ASSERT_TRUE(SolveStatic(m.model, d).converged);
    double position = 0.0, rotation = 0.0;
    CircleErrors(m, d, lambda * 2.0 * kPi / kL, &position, &rotation);
    EXPECT_LT(position, 1e-8) << "lambda " << lambda;
    EXPECT_LT(rotation, 1e-8) << "lambda " << lambda;
  }
}

TEST(RollUp, ResultDoesNotDependOnTheNumberOfLoadSteps) {
  // Each step must move the element rotation by less than pi (1.8 pi in 2 or 4 steps).
  Vec3 tips[2];
  const int steps[2] = {2, 4};
  for (int k = 0; k < 2; ++k) {
    const RollUpModel m = MakeRollUp(1, 0.9);
    Data d = MakeData(m.model);
    StaticOptions opt;
    opt.load_steps = steps[k];
    ASSERT_TRUE(SolveStatic(m.model, d, opt).converged);
    tips[k] = d.H[static_cast<std::size_t>(m.nodes.back())].x;
  }
  EXPECT_LT((tips[0] - tips[1]).norm(), 1e-10 * kL);
}

TEST(RollUp, ElementDrivenPastTwoPiStopsWithAMessageAndKeepsTheLastConvergedState) {
  // lambda = 1.2 on one element would need an element rotation of 2.4 pi: one helical element
  // cannot represent it (T^-1 is singular at 2 pi), so the solve must stop and say why.
  const double lambda = 1.2;
  const RollUpModel m = MakeRollUp(1, lambda);
  Data d = MakeData(m.model);
  const StaticResult r = SolveStatic(m.model, d);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.message.find("element 0"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("rod 'rollup'"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("use more elements"), std::string::npos) << r.message;
  // It got as far as one element allows (rotation 2 pi - margin), not further: the element
  // rotation of the converged state, on its continued branch, lies below the limit the solver
  // applies to it, and is that of the load factor reached.
  const double reached = lambda * r.load_factor;  // fraction of a full turn
  EXPECT_GT(reached, 0.95);
  const RodElement& el = m.model.elements[0];
  const double rotation_reached =
      CalcRodRelativeMotion(d.H[static_cast<std::size_t>(el.node_a)],
                            d.H[static_cast<std::size_t>(el.node_b)], d.w_ref[0])
          .tail<3>()
          .norm();
  EXPECT_LT(rotation_reached, m.model.max_element_rotation);
  EXPECT_NEAR(rotation_reached, reached * 2.0 * kPi, 1e-8);
  // Data holds the last converged state: finite and exactly on its circle.
  for (const SE3& H : d.H) {
    ASSERT_TRUE(H.x.allFinite());
    ASSERT_TRUE(H.R.allFinite());
  }
  double position = 0.0, rotation = 0.0;
  CircleErrors(m, d, reached * 2.0 * kPi / kL, &position, &rotation);
  EXPECT_LT(position, 1e-8);
  EXPECT_LT(rotation, 1e-8);
}

}  // namespace
}  // namespace screwfem::rollup_test
