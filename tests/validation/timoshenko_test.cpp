// Validation S4 (docs/validation.md): Timoshenko cantilever, PyElastica's case
// (Gazzola et al. 2018, §3.4.3; examples/TimoshenkoBeamCase).
//
// L = 3, solid circle r = 0.25, E = 1e6, G = 1e4, shear coefficient 4/3, dead transverse tip
// force F = 15. Linear Timoshenko theory: tip deflection F L / (kappa G A) + F L^3 / (3 E I)
// = 0.0171887 + 0.0440032 = 0.0611919.
//
// What the helical element does here (measured): the shear part is exact with any mesh (no
// shear locking: one element already carries the full F L / S), but the moment varies linearly,
// so the bending part is not: in the linear regime the tip deflection of N elements is
// F L / S + F L^3 / (3 E I) (1 - 1 / (4 N^2)), the result of the two-node element with exact
// constant-strain kinematics. The error falls as O(1/N^2) (1, 2, 4 elements: -18 %, -4.5 %,
// -1.1 %). With F = 15 the geometrically exact answer differs from linear theory by -3.0e-4
// relative (converged value 0.0611734); with F / 100 the difference is below 1e-7.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::timoshenko_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kL = 3.0, kRadius = 0.25, kE = 1e6, kG = 1e4, kShearCoefficient = 4.0 / 3.0;
constexpr double kForce = 15.0;

double ShearStiffness() { return kShearCoefficient * kG * kPi * kRadius * kRadius; }
double BendingStiffness() { return kE * kPi * std::pow(kRadius, 4) / 4.0; }
double LinearTipDeflection(double F) {
  return F * kL / ShearStiffness() + F * kL * kL * kL / (3.0 * BendingStiffness());
}

// Tip deflection (towards the force) of the cantilever with n elements.
double TipDeflection(double F, int num_elements) {
  ModelBuilder b;
  const Section section =
      Section::Circle(kRadius, Material{kE, kG, -1.0, 5000.0, kShearCoefficient});
  const RodId rod =
      b.AddStraightRod("timoshenko", Vec3::Zero(), Vec3(kL, 0.0, 0.0), num_elements, section);
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  PointLoad load;
  load.node = nodes.back();
  load.frame = LoadFrame::kWorld;
  load.force = Vec3(0.0, -F, 0.0);
  b.AddPointLoad(load);
  const Model model = b.Build();
  Data d = MakeData(model);
  const StaticResult r = SolveStatic(model, d);
  EXPECT_TRUE(r.converged) << r.message;
  return -d.H[static_cast<std::size_t>(nodes.back())].x.y();
}

TEST(Timoshenko, ReferenceValueIsReproducedFromTheParameters) {
  EXPECT_NEAR(ShearStiffness(), 2617.99, 0.01);
  EXPECT_NEAR(BendingStiffness(), 3067.96, 0.01);
  EXPECT_NEAR(LinearTipDeflection(kForce), 0.0611919, 1e-7);
}

TEST(Timoshenko, TipDeflectionWithinHalfAPercentOfLinearTheory) {
  const double w = TipDeflection(kForce, 64);
  EXPECT_NEAR(w / LinearTipDeflection(kForce), 1.0, 5e-3);
  // Shear matters: Euler-Bernoulli alone would give 0.0440.
  EXPECT_GT(w, 0.06);
}

TEST(Timoshenko, SmallForceMatchesLinearTheoryToOneInTenThousand) {
  // F / 100: geometric nonlinearity is negligible; with 64 elements the discretisation error is
  // 4.4e-5.
  const double w = 100.0 * TipDeflection(kForce / 100.0, 64);
  EXPECT_NEAR(w / LinearTipDeflection(kForce), 1.0, 1e-4);
}

TEST(Timoshenko, CoarseMeshesHaveNoShearLockingAndTheExpectedBendingError) {
  // In the linear regime: F L / S exactly, plus F L^3 / (3 EI) (1 - 1 / (4 N^2)).
  const double F = kForce / 100.0;
  double previous_error = INFINITY;
  for (const int n : {1, 2, 4}) {
    const double w = TipDeflection(F, n);
    const double discrete = F * kL / ShearStiffness() +
                            F * kL * kL * kL / (3.0 * BendingStiffness()) * (1.0 - 0.25 / (n * n));
    EXPECT_NEAR(w / discrete, 1.0, 1e-6) << n << " elements";
    const double error = std::abs(w - LinearTipDeflection(F));
    EXPECT_LT(error, 0.3 * previous_error) << n << " elements";  // O(1/N^2): factor 4 per halving
    previous_error = error;
  }
}

TEST(Timoshenko, MeshRefinementConvergesAtSecondOrderToLinearTheory) {
  // Richardson extrapolation of 64 and 128 elements removes the O(1/N^2) error.
  const double F = kForce / 100.0;
  const double w64 = TipDeflection(F, 64), w128 = TipDeflection(F, 128);
  const double extrapolated = (4.0 * w128 - w64) / 3.0;
  EXPECT_NEAR(extrapolated / LinearTipDeflection(F), 1.0, 1e-6);
}

}  // namespace
}  // namespace screwfem::timoshenko_test
