// Validation S2 (docs/validation.md): a follower end moment turns a straight rod into a helix
// (Harsch & Eugster; cardillo's examples/Herrmann2025_mixed_Cosserat_rod/02_helix.py).
//
// Target helix: R0 = 10, height h = 50, n = 2 turns; c = h / (2 pi R0 n),
// L = sqrt(1 + c^2) 2 pi R0 n (= 135.25; 2 pi R0 n alone, the length without the rise, is
// 125.66). Circular section with E = 1, G = 0.5, so G Ip = E I exactly (needed for a pure
// moment to produce a helix). The clamp frame is the helix frame at alpha = 0; the body-fixed
// tip moment M_B = kappa_h (c G Ip, 0, E I), kappa_h = 1 / (R0 (1 + c^2)), gives the constant
// body curvature kappa_h (c, 0, 1). Exact: r(s) = R0 (sin a, -cos a, c a), a = 2 pi n s / L, with
// the frame at s equal to the root frame rotated by a about z; the tip is at (0, -10, 50) with
// the root's orientation (rotated by 4 pi). Constant strain: the helical element is exact, each
// element may rotate by up to 2 pi, so three elements (4 pi / 3 each, past pi) suffice.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::helix_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kR0 = 10.0, kHeight = 50.0, kTurns = 2.0;
const double kC = kHeight / (2.0 * kPi * kR0 * kTurns);
const double kLength = std::sqrt(1.0 + kC * kC) * 2.0 * kPi * kR0 * kTurns;

SE3 HelixFrame(double s) {
  const double cc = 1.0 / std::sqrt(1.0 + kC * kC);
  SE3 root;
  root.R.col(0) = cc * Vec3(1.0, 0.0, kC);
  root.R.col(1) = Vec3(0.0, 1.0, 0.0);
  root.R.col(2) = cc * Vec3(-kC, 0.0, 1.0);
  root.x = Vec3(0.0, -kR0, 0.0);
  const double a = 2.0 * kPi * kTurns * s / kLength;
  SE3 H;
  H.R = ExpSO3(Vec3(0.0, 0.0, a)) * root.R;
  H.x = kR0 * Vec3(std::sin(a), -std::cos(a), kC * a);
  return H;
}

struct HelixResult {
  StaticResult result;
  std::vector<SE3> frames;  // node frames along the rod
};

HelixResult SolveHelix(int num_elements, int load_steps) {
  // Slenderness L / r = 10 (any of 1e1 ... 1e4 would do: no force acts, so EA and GA do not
  // enter the answer). With L / r = 100 (EA L^2 / EI = 4e4) plain Newton needs about 64
  // load steps: with 8 ... 32 the first iterate of each step raises the residual 50-100x and
  // the solve runs out of its 12 load-step halvings near load factor 0.3.
  const Section section = Section::Circle(kLength / 10.0, Material{1.0, 0.5, -1.0, 0.0, 0.0});
  EXPECT_EQ(section.stiffness(3), section.stiffness(5));  // G Ip == E I exactly
  ModelBuilder b;
  const RodId rod =
      b.AddStraightRodFromFrame("helix", HelixFrame(0.0), kLength, num_elements, section);
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  const double kappa_h = 1.0 / (kR0 * (1.0 + kC * kC));
  PointLoad load;
  load.node = nodes.back();
  load.frame = LoadFrame::kBody;
  load.moment = kappa_h * Vec3(kC * section.stiffness(3), 0.0, section.stiffness(5));
  b.AddPointLoad(load);
  const Model model = b.Build();
  Data d = MakeData(model);
  StaticOptions opt;
  opt.load_steps = load_steps;
  HelixResult out;
  out.result = SolveStatic(model, d, opt);
  for (int n : nodes) out.frames.push_back(d.H[static_cast<std::size_t>(n)]);
  return out;
}

void ExpectOnHelix(const HelixResult& h, double tol, const char* what) {
  const int ne = static_cast<int>(h.frames.size()) - 1;
  for (int i = 0; i <= ne; ++i) {
    const SE3 exact = HelixFrame(kLength * i / ne);
    EXPECT_LT((h.frames[static_cast<std::size_t>(i)].x - exact.x).norm(), tol * kLength)
        << what << ", node " << i << " of " << ne;
    EXPECT_LT((h.frames[static_cast<std::size_t>(i)].R - exact.R).norm(), tol)
        << what << ", node " << i << " of " << ne;
  }
}

TEST(Helix, ThreeAndFiveElementsReproduceTheExactHelix) {
  for (const int ne : {3, 5}) {
    const HelixResult h = SolveHelix(ne, 8);
    ASSERT_TRUE(h.result.converged) << ne << " elements: " << h.result.message;
    // Tip back above the start, with the root's orientation (rotated by 4 pi about z).
    const SE3& tip = h.frames.back();
    EXPECT_LT((tip.x - Vec3(0.0, -10.0, 50.0)).norm(), 1e-8 * kLength) << ne << " elements";
    EXPECT_LT((tip.R - h.frames.front().R).norm(), 1e-8) << ne << " elements";
    // Every interior node on the exact helix, with the exact frame.
    ExpectOnHelix(h, 1e-8, ne == 3 ? "3 elements" : "5 elements");
  }
}

TEST(Helix, ResultDoesNotDependOnTheNumberOfLoadSteps) {
  const HelixResult a = SolveHelix(3, 8), b = SolveHelix(3, 16);
  ASSERT_TRUE(a.result.converged);
  ASSERT_TRUE(b.result.converged);
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_LT((a.frames[i].x - b.frames[i].x).norm(), 1e-10 * kLength) << "node " << i;
    EXPECT_LT((a.frames[i].R - b.frames[i].R).norm(), 1e-10) << "node " << i;
  }
}

}  // namespace
}  // namespace screwfem::helix_test
