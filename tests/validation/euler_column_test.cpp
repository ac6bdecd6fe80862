// Path following past buckling with default settings (docs/numerics.md, "Path-following
// statics"): a clamped column under a compressive dead tip load beyond its critical load
// P_cr = pi^2 EI / (4 L^2), with a lateral imperfection load of 1e-3 of the axial one, traced
// by arc-length continuation without any arc-length setting, to 2 P_cr. Its tip follows the
// elastica of the perfect column (Timoshenko and Gere 1961, art. 2.7): with k = sin(theta_0 / 2),
// theta_0 the tip rotation, L sqrt(P / EI) = K(k), the tip's lateral deflection is
// 2 k L / K(k) and its distance from the base along the load 2 L E(k) / K(k) - L (K, E the
// complete elliptic integrals of the first and second kind).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "screwfem/build/model_builder.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"

namespace screwfem::euler_column_test {
namespace {

constexpr double kL = 1.0, kEI = 1.0, kEA = 1e5;
constexpr int kElements = 32;
const double kCritical = std::numbers::pi * std::numbers::pi * kEI / (4.0 * kL * kL);

// The elastica's modulus k for the load P (bisection on K(k) = L sqrt(P / EI)).
double Modulus(double p) {
  const double target = kL * std::sqrt(p / kEI);
  double lo = 0.0, hi = 1.0 - 1e-15;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::comp_ellint_1(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct Column {
  Model model;
  int tip = -1;
};

Column MakeColumn(double p_ref, double imperfection) {
  ModelBuilder b;
  const Section s = Section::FromDiagonals((Vec6() << kEA, kEA, kEA, kEI, kEI, kEI).finished());
  const int rod = b.AddStraightRod("column", Vec3::Zero(), Vec3(kL, 0, 0), kElements, s);
  b.FixNode(NodeId(b.model().rods[static_cast<std::size_t>(rod)].nodes.front()));
  Column c;
  c.tip = b.model().rods[static_cast<std::size_t>(rod)].nodes.back();
  PointLoad load;
  load.node = c.tip;
  load.force = Vec3(-p_ref, imperfection * p_ref, 0.0);  // dead, world frame
  b.AddPointLoad(load);
  c.model = b.Build();
  return c;
}

TEST(EulerColumn, ArcLengthWithDefaultSettingsTracesThePostBucklingElastica) {
  const double p_ref = 2.0 * kCritical;
  const Column c = MakeColumn(p_ref, 1e-3);
  Data d = MakeData(c.model);
  StaticOptions opt;
  opt.method = StaticMethod::kArcLength;  // every other setting at its default
  double worst = 0.0;                     // largest tip distance from the elastica beyond 1.2 P_cr
  int checked = 0;
  const StaticResult r = SolveStatic(c.model, d, opt, {}, [&](const StaticStep& step) {
    const double p = p_ref * step.load_factor;
    if (p < 1.2 * kCritical) return;  // near P_cr the imperfection decides the deflection
    const double k = Modulus(p), K = std::comp_ellint_1(k), E = std::comp_ellint_2(k);
    const Vec3 tip = d.H[static_cast<std::size_t>(c.tip)].x;
    worst =
        std::max(worst, std::hypot(tip.x() - kL * (2.0 * E / K - 1.0), tip.y() - 2.0 * k * kL / K));
    ++checked;
  });
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.load_factor, 1.0);
  EXPECT_GE(checked, 5);
  // At 2 P_cr the elastica puts the tip 2 k L / K(k) aside (k from K(k) = L sqrt(2 P_cr / EI)).
  const double k = Modulus(p_ref), K = std::comp_ellint_1(k);
  const Vec3 tip = d.H[static_cast<std::size_t>(c.tip)].x;
  EXPECT_NEAR(tip.y(), 2.0 * k * kL / K, 0.01 * kL) << r.load_steps << " steps";
  EXPECT_LT(worst, 0.02 * kL) << r.load_steps << " steps";
  EXPECT_LT(r.load_steps, 200);
  std::printf("Euler column to 2 P_cr: %d steps, %d iterations, worst tip distance %.3g L\n",
              r.load_steps, r.total_iterations, worst / kL);
}

// A solve that runs out of steps names the controller setting that makes them longer.
TEST(EulerColumn, AStepCapMessageNamesTheArcLengthCap) {
  const Column c = MakeColumn(2.0 * kCritical, 1e-3);
  Data d = MakeData(c.model);
  StaticOptions opt;
  opt.method = StaticMethod::kArcLength;
  opt.max_steps = 20;
  opt.arc_length_max = 0.01;
  const StaticResult r = SolveStatic(c.model, d, opt);
  ASSERT_FALSE(r.converged);
  EXPECT_NE(r.message.find("static solve stopped after 20 steps (max_steps) at load factor "),
            std::string::npos)
      << r.message;
  EXPECT_NE(r.message.find("raise analysis.statics.max_steps or take longer steps "
                           "(analysis.statics.arc_length_max, now 0.01)"),
            std::string::npos)
      << r.message;
}

}  // namespace
}  // namespace screwfem::euler_column_test
