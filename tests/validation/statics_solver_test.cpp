// Behaviour of the static Newton solver with load stepping (docs/architecture.md, "One time step"): quadratic
// convergence, halving of failed load increments, round-off floors of stiff rods, and failure
// reports instead of crashes.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::statics_solver_test {
namespace {

struct Cantilever {
  Model model;
  std::vector<NodeId> nodes;
};

// Cantilever of length 1 along x from `origin`, EI = 1, EA = GA = axial, dead tip force
// (0, alpha, 0): the elastica of validation S3 with alpha = P L^2 / EI.
Cantilever MakeCantilever(int num_elements, double alpha, double axial,
                          const Vec3& origin = Vec3::Zero(), bool clamped = true) {
  ModelBuilder b;
  Vec6 k;
  k << axial, axial, axial, 1.0, 1.0, 1.0;
  const RodId rod = b.AddStraightRod("cantilever", origin, origin + Vec3::UnitX(), num_elements,
                                     Section::FromDiagonals(k));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  if (clamped) b.FixNode(nodes.front());
  PointLoad load;
  load.node = nodes.back();
  load.frame = LoadFrame::kWorld;
  load.force = Vec3(0.0, alpha, 0.0);
  b.AddPointLoad(load);
  return {b.Build(), nodes};
}

double TipRotation(const Data& d, const Cantilever& c) {
  const Mat3& R = d.H[static_cast<std::size_t>(c.nodes.back())].R;
  return std::atan2(R(1, 0), R(0, 0));
}

TEST(StaticSolver, NewtonConvergesQuadraticallyInTheFinalLoadStep) {
  // Elastica PL^2/EI = 1 in one load step, 16 elements, EA = GA = 100 EI/L^2 (a thick rod, so
  // that the infinity norm of the residual is not dominated by the stiff axial rows in the
  // pre-asymptotic iterations). Dimensionless contraction q_k = r_{k+1} r_0 / r_k^2 (r_0 = the
  // unbalanced load at the start of the step) over the iterations with r_k < 1e-2 r_0 whose
  // successor is still above the round-off floor (10x the converged residual).
  const Cantilever c = MakeCantilever(16, 1.0, 100.0);
  Data d = MakeData(c.model);
  StaticOptions opt;
  opt.load_steps = 1;
  const StaticResult r = SolveStatic(c.model, d, opt);
  ASSERT_TRUE(r.converged) << r.message;
  const std::vector<double>& res = r.steps.back().residual_norms;
  ASSERT_GE(res.size(), 4u);
  const double r0 = res.front(), floor = res.back();
  int pairs = 0;
  for (std::size_t k = 0; k + 1 < res.size(); ++k) {
    if (!(res[k] < 1e-2 * r0) || !(res[k + 1] > 10.0 * floor)) continue;
    EXPECT_LT(res[k + 1] * r0 / (res[k] * res[k]), 10.0) << "iteration " << k;
    ++pairs;
  }
  EXPECT_GE(pairs, 2);
  EXPECT_LE(r.steps.back().iterations, 6);
}

TEST(StaticSolver, HalvesTheLoadIncrementWhenAStepFailsAndStillConverges) {
  // PL^2/EI = 10 in one load step diverges; the solver retries with smaller increments.
  const Cantilever c = MakeCantilever(32, 10.0, 1e7);
  Data d = MakeData(c.model);
  StaticOptions opt;
  opt.load_steps = 1;
  const StaticResult r = SolveStatic(c.model, d, opt);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_GT(r.halvings, 0);
  EXPECT_GT(r.load_steps, 1);
  EXPECT_LT(r.steps.front().load_factor, 1.0);
  EXPECT_EQ(r.steps.back().load_factor, 1.0);
  EXPECT_EQ(r.load_factor, 1.0);
  // The right branch: Mattiasson's tip rotation 1.430286 (32 elements: within 2e-4).
  EXPECT_NEAR(TipRotation(d, c), 1.430286, 2e-4 * 1.430286);
}

TEST(StaticSolver, TakesExactlyTheRequestedNumberOfLoadSteps) {
  // Ten increments of 0.1 add up to 1 - 1e-16: no extra sliver of a load step.
  const Cantilever c = MakeCantilever(8, 0.5, 1e4);
  Data d = MakeData(c.model);
  const StaticResult r = SolveStatic(c.model, d);  // 10 load steps by default
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.halvings, 0);
  EXPECT_EQ(r.load_steps, 10);
  ASSERT_EQ(r.steps.size(), 10u);
  EXPECT_EQ(r.steps.back().load_factor, 1.0);
}

TEST(StaticSolver, ConvergesForStiffRodsFarFromTheOrigin) {
  // With EA = 1e7 and 64 elements the residual's round-off floor is ~eps EA / L_e max|x|: the
  // relative position of two nodes loses digits to their distance from the origin. Moving
  // the cantilever from x = 0 to x = 10 raises the floor tenfold; the solver must still
  // converge, to the same (translated) answer.
  Vec3 tips[2];
  double rotations[2];
  const Vec3 origins[2] = {Vec3::Zero(), Vec3(10.0, 0.0, 0.0)};
  for (int k = 0; k < 2; ++k) {
    const Cantilever c = MakeCantilever(64, 1.0, 1e7, origins[k]);
    Data d = MakeData(c.model);
    const StaticResult r = SolveStatic(c.model, d);
    ASSERT_TRUE(r.converged) << "origin " << origins[k].transpose() << ": " << r.message;
    tips[k] = d.H[static_cast<std::size_t>(c.nodes.back())].x - origins[k];
    rotations[k] = TipRotation(d, c);
  }
  EXPECT_LT((tips[0] - tips[1]).norm(), 1e-9);
  EXPECT_NEAR(rotations[0], rotations[1], 1e-9);
}

TEST(StaticSolver, AcceptsAStateAtTheRoundOffFloorOnlyAfterASmallCorrection) {
  // 128 stiff elements: the first Newton iterate of each load step already has a residual
  // close to the round-off floor but is still 2e-6 rad away from equilibrium. The converged
  // state must not depend on the load path (10 or 7 steps) beyond round-off.
  double theta[2];
  const int steps[2] = {10, 7};
  for (int k = 0; k < 2; ++k) {
    const Cantilever c = MakeCantilever(128, 0.2, 1e6);
    Data d = MakeData(c.model);
    StaticOptions opt;
    opt.load_steps = steps[k];
    const StaticResult r = SolveStatic(c.model, d, opt);
    ASSERT_TRUE(r.converged) << r.message;
    theta[k] = TipRotation(d, c);
  }
  EXPECT_NEAR(theta[0], theta[1], 1e-10);
}

TEST(StaticSolver, UnloadedModelStaysInItsReferenceConfiguration) {
  const Cantilever c = MakeCantilever(4, 0.0, 1e4);
  Data d = MakeData(c.model);
  const StaticResult r = SolveStatic(c.model, d);
  ASSERT_TRUE(r.converged) << r.message;
  for (std::size_t i = 0; i < d.H.size(); ++i) {
    EXPECT_LT((d.H[i].x - c.model.nodes[i].reference.x).norm(), 1e-14);
    EXPECT_LT((d.H[i].R - c.model.nodes[i].reference.R).norm(), 1e-14);
  }
}

TEST(StaticSolver, MechanismReportsAFailureInsteadOfNaN) {
  // A free-floating rod pushed by a force has no static equilibrium: the tangent is singular
  // (six rigid-body modes). The solver must say so and leave data finite and unchanged.
  const Cantilever c = MakeCantilever(4, 1.0, 1e4, Vec3::Zero(), /*clamped=*/false);
  Data d = MakeData(c.model);
  const StaticResult r = SolveStatic(c.model, d);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.load_steps, 0);
  EXPECT_NE(r.message.find("singular"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("mechanism"), std::string::npos) << r.message;
  for (std::size_t i = 0; i < d.H.size(); ++i) {
    ASSERT_TRUE(d.H[i].x.allFinite());
    ASSERT_TRUE(d.H[i].R.allFinite());
    EXPECT_EQ(d.H[i].x, c.model.nodes[i].reference.x);
  }
}

}  // namespace
}  // namespace screwfem::statics_solver_test
