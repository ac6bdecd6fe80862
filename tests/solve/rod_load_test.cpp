// Distributed and concentrated loads on rods (RodLoad) in static equilibrium.
#include <gtest/gtest.h>

#include <cmath>

#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::rod_load_test {
namespace {

struct Cantilever {
  ModelBuilder builder;
  int tip = -1;
};

// A clamped rod along x of length L = 2 with EI = 3, EA = GA = 1e7 (nearly inextensible).
Cantilever MakeCantilever(int elements) {
  Cantilever c;
  Vec6 K;
  K << 1e7, 1e7, 1e7, 3.0, 3.0, 3.0;
  const RodId rod = c.builder.AddStraightRod("beam", Vec3::Zero(), Vec3(2.0, 0, 0), elements,
                                             Section::FromDiagonals(K));
  c.builder.FixNode(c.builder.RodNodes(rod).front());
  c.tip = c.builder.RodNodes(rod).back();
  return c;
}

Vec3 SolveTip(Cantilever& c) {
  const Model m = c.builder.Build();
  Data d = MakeData(m);
  const StaticResult r = SolveStatic(m, d);
  EXPECT_TRUE(r.converged) << r.message;
  return d.H[static_cast<std::size_t>(c.tip)].x;
}

TEST(RodLoad, UniformDeadLoadGivesTheBeamTheoryTipDeflection) {
  // Small load: w_tip = q L^4 / (8 EI) from Euler-Bernoulli (shear adds q L^2 / (2 GA) ~ 1e-7 of
  // it, the geometric nonlinearity ~ (w/L)^2 ~ 1e-8).
  const double q = -1e-4, L = 2.0, EI = 3.0;
  const double exact = q * std::pow(L, 4) / (8 * EI);
  double previous_error = INFINITY;
  for (int n : {4, 8, 16}) {
    Cantilever c = MakeCantilever(n);
    RodLoad load;
    load.rod = 0;
    load.force = Vec3(0, q, 0);
    c.builder.AddRodLoad(load);
    const double w = SolveTip(c).y();
    const double error = std::abs(w / exact - 1.0);
    EXPECT_LT(error, previous_error / 3.0) << n << " elements";  // second-order convergence
    previous_error = error;
  }
  EXPECT_LT(previous_error, 2e-3);
}

TEST(RodLoad, ConcentratedLoadAtTheEndEqualsANodalLoad) {
  for (LoadFrame frame : {LoadFrame::kWorld, LoadFrame::kBody}) {
    Cantilever a = MakeCantilever(6), b = MakeCantilever(6);
    RodLoad rl;
    rl.rod = 0;
    rl.distributed = false;
    rl.arc_length = 2.0;
    rl.frame = frame;
    rl.force = Vec3(0, -1.5, 0.4);
    rl.moment = Vec3(0, 0.2, 0.1);
    a.builder.AddRodLoad(rl);
    PointLoad pl;
    pl.node = b.tip;
    pl.frame = frame;
    pl.force = rl.force;
    pl.moment = rl.moment;
    b.builder.AddPointLoad(pl);
    const Vec3 xa = SolveTip(a), xb = SolveTip(b);
    EXPECT_LT((xa - xb).norm(), 1e-10);
    EXPECT_GT((xa - Vec3(2.0, 0, 0)).norm(), 0.3);  // large deflection
  }
}

TEST(RodLoad, ConcentratedLoadInsideAnElementConvergesToTheNodalLoadAtThatPoint) {
  // A load at s = 1 on a rod meshed with an element boundary at s = 1 (4 elements) and with s
  // = 1 inside an element (3 elements): both converge to the same configuration.
  Cantilever fine = MakeCantilever(24), coarse = MakeCantilever(3);
  coarse.builder.SetConformMesh(false);  // the load inside the element
  for (Cantilever* c : {&fine, &coarse}) {
    RodLoad rl;
    rl.rod = 0;
    rl.distributed = false;
    rl.arc_length = 1.0;
    rl.force = Vec3(0, -1.0, 0);
    c->builder.AddRodLoad(rl);
  }
  const Vec3 xf = SolveTip(fine), xc = SolveTip(coarse);
  EXPECT_LT((xf - xc).norm(), 0.05 * (xf - Vec3(2.0, 0, 0)).norm());
  const Model m = coarse.builder.Build();
  EXPECT_EQ(m.rod_loads[0].element, 1);
  EXPECT_NEAR(m.rod_loads[0].xi, 1.0 / 3.0 * 3.0 - 1.0 + 0.5, 1e-12);
}

TEST(RodLoad, ArcLengthOutsideTheRodIsAnInputError) {
  Cantilever c = MakeCantilever(2);
  RodLoad rl;
  rl.rod = 0;
  rl.distributed = false;
  rl.arc_length = 2.5;
  c.builder.AddRodLoad(rl);
  EXPECT_THROW(c.builder.Build(), InputError);
}

}  // namespace
}  // namespace screwfem::rod_load_test
