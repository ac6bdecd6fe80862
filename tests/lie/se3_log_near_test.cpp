// LogSE3Near: the logarithm on a continuous branch (elements/rod.h). Of the rotation vectors
// (theta + 2 pi k) n of a rotation, it returns the one closest to w_ref and recomputes the
// translation part on that branch.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "lie/lie_test_util.h"
#include "screwfem/lie/se3.h"

namespace screwfem::se3_log_near_test {
namespace {

using test::kPi;
using test::kTwoPi;
using test::MatrixNear;

TEST(Se3LogNear, ReturnsTheRotationPastPiWhenTheReferenceIsCloseToIt) {
  std::mt19937 rng = test::MakeRng(41);
  for (double theta : {kPi + 1e-9, kPi + 1e-6, 3.5, 4.5, 5.5, kTwoPi - 0.1}) {
    for (int s = 0; s < 8; ++s) {
      const Vec3 n = test::RandomUnitVector(rng);
      Vec6 xi;
      xi << test::RandomVec6(rng, 2.0).head<3>(), theta * n;
      const SE3 H = ExpSE3(xi);
      // A reference a bit off the answer (as after a load step), never closer to another branch.
      const Vec3 w_ref = theta * n + 0.3 * test::RandomUnitVector(rng);
      SCOPED_TRACE(::testing::Message() << "theta = " << theta << ", xi = " << xi.transpose());
      const Vec6 log_h = LogSE3Near(H, w_ref);
      EXPECT_TRUE(MatrixNear(log_h.tail<3>(), theta * n, 1e-14));
      EXPECT_NEAR(log_h.tail<3>().norm(), theta, 1e-14);
      // Not the principal log (theta - 2 pi) n.
      EXPECT_GT((log_h.tail<3>() - LogSE3(H).tail<3>()).norm(), 6.0);
      // T_SO3^-1 grows like 1/(2 pi - theta): up to ~60 at 2 pi - 0.1.
      EXPECT_TRUE(MatrixNear(log_h, xi, 5e-14));
      EXPECT_TRUE(MatrixNear(ExpSE3(log_h).Matrix(), H.Matrix(), 1e-14));
    }
  }
}

TEST(Se3LogNear, RotationAloneIsTheRotationPartBitForBit) {
  std::mt19937 rng = test::MakeRng(47);
  for (double theta : {0.0, 1e-9, 1e-5, 0.3, 2.0, kPi - 1e-7, kPi + 1e-6, 4.5, kTwoPi - 0.1}) {
    for (int s = 0; s < 8; ++s) {
      Vec6 xi;
      xi << test::RandomVec6(rng, 2.0).head<3>(), theta * test::RandomUnitVector(rng);
      const SE3 H = ExpSE3(xi);
      for (const Vec3& w_ref : {Vec3(Vec3::Zero()), Vec3(xi.tail<3>()),
                                Vec3(xi.tail<3>() + 0.3 * test::RandomUnitVector(rng))}) {
        const Vec3 w = LogSO3Near(H.R, w_ref), full = LogSE3Near(H, w_ref).tail<3>();
        for (int i = 0; i < 3; ++i) EXPECT_EQ(w(i), full(i)) << "theta " << theta;
      }
    }
  }
}

TEST(Se3LogNear, IsContinuousAsTheRotationAngleCrossesPi) {
  // Continuation: each call uses the previous result as reference, as a load-stepping loop would.
  const Vec3 n = Vec3(2.0, -3.0, 6.0) / 7.0;
  const Vec3 x(0.4, 1.0, -0.7);
  std::vector<double> thetas;
  for (int k = -20; k <= 20; ++k) thetas.push_back(kPi + 5e-5 * k);
  for (double d : {-1e-7, -1e-9, 0.0, 1e-9, 1e-7}) thetas.push_back(kPi + d);
  std::sort(thetas.begin(), thetas.end());

  Vec3 w_ref = thetas.front() * n;
  Vec6 previous = Vec6::Zero();
  for (std::size_t i = 0; i < thetas.size(); ++i) {
    const double theta = thetas[i];
    SE3 H;
    H.R = ExpSO3(theta * n);
    H.x = x;
    const Vec6 log_h = LogSE3Near(H, w_ref);
    SCOPED_TRACE(::testing::Message() << "theta - pi = " << theta - kPi);
    EXPECT_TRUE(MatrixNear(log_h.tail<3>(), theta * n, 1e-14));
    EXPECT_TRUE(MatrixNear(ExpSE3(log_h).Matrix(), H.Matrix(), 1e-14));
    if (i > 0) {
      // The change is of the order of the angle step (<= 5e-5), not a jump of 2 pi.
      const double dtheta = theta - thetas[i - 1];
      EXPECT_LE((log_h - previous).norm(), 10.0 * dtheta + 1e-14);
    }
    previous = log_h;
    w_ref = log_h.tail<3>();
  }
}

TEST(Se3LogNear, WithSeriesGivesTheSameLogAndTheCoefficientsOfItsAngle) {
  // The overload used by the rod kernels: the translation from C = s2 - theta^2 s4 of the
  // shared coefficients instead of lie_detail::C, on every branch up to 2 pi - 0.1.
  std::mt19937 rng = test::MakeRng(44);
  std::uniform_real_distribution<double> angle(0.0, kTwoPi - 0.1);
  for (int s = 0; s < 200; ++s) {
    const double phi = s < 4 ? std::vector<double>{0.0, 1e-9, 0.2, 0.3}[s] : angle(rng);
    const Vec6 xi = test::RandomTwist(rng, phi, 2.0);
    const SE3 H = ExpSE3(xi);
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    TSeries c;
    const Vec6 log_h = LogSE3Near(H, xi.tail<3>(), &c);
    const Vec6 reference = LogSE3Near(H, xi.tail<3>());
    // |T_SO3^-1| grows like 1/(2 pi - phi) towards 2 pi.
    EXPECT_TRUE(MatrixNear(log_h, reference, 1e-14 * (1.0 + xi.norm()) / (kTwoPi - phi)));
    const TSeries e = CalcTSeries(log_h.tail<3>().norm());
    EXPECT_EQ(c.s2, e.s2);
    EXPECT_EQ(c.t1, e.t1);
  }
}

TEST(Se3LogNear, WithZeroReferenceReturnsThePrincipalLogNearTheIdentity) {
  std::mt19937 rng = test::MakeRng(42);
  for (double phi : {0.0, 1e-12, 1e-8, 1e-4, 1e-3, 0.5, 2.0}) {
    for (int s = 0; s < 4; ++s) {
      const SE3 H = ExpSE3(test::RandomTwist(rng, phi, 1.0));
      SCOPED_TRACE(::testing::Message() << "phi = " << phi);
      EXPECT_TRUE(MatrixNear(LogSE3Near(H, Vec3::Zero()), LogSE3(H), 0.0));
    }
  }
  // Exactly the identity and a pure translation.
  EXPECT_TRUE(MatrixNear(LogSE3Near(SE3::Identity(), Vec3::Zero()), Vec6::Zero(), 0.0));
  Vec6 expected;
  expected << 1.0, -2.0, 0.5, 0.0, 0.0, 0.0;
  EXPECT_TRUE(
      MatrixNear(LogSE3Near(SE3::Translation(Vec3(1.0, -2.0, 0.5)), Vec3::Zero()), expected, 0.0));
}

TEST(Se3LogNear, ReproducesHWithTheTranslationOnTheChosenBranchUpToTwoPiMinus0p1) {
  std::mt19937 rng = test::MakeRng(43);
  std::uniform_real_distribution<double> angle(0.0, kTwoPi - 0.1);
  double worst = 0.0;
  for (int s = 0; s < 400; ++s) {
    const Vec6 xi = test::RandomTwist(rng, angle(rng), 3.0);
    const SE3 H = ExpSE3(xi);
    const Vec6 log_h = LogSE3Near(H, xi.tail<3>());
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const double err = test::MaxAbs(ExpSE3(log_h).Matrix() - H.Matrix());
    worst = std::max(worst, err);
    EXPECT_LE(err, 1e-12);
    EXPECT_NEAR(log_h.tail<3>().norm(), xi.tail<3>().norm(), 1e-13);
  }
  RecordProperty("worst_abs_error", ::testing::PrintToString(worst));
}

TEST(Se3LogNear, PicksTheNegativeBranchWhenTheReferenceIsThere) {
  std::mt19937 rng = test::MakeRng(44);
  for (double theta : {3.5, 4.5, 5.5}) {
    const Vec3 n = test::RandomUnitVector(rng);
    Vec6 xi;
    xi << 0.5, -1.0, 2.0, -theta * n;  // rotation by theta about -n
    const SE3 H = ExpSE3(xi);
    SCOPED_TRACE(::testing::Message() << "theta = " << theta);
    // Reference near -theta n: the branch continued from negative angles.
    const Vec6 negative = LogSE3Near(H, -theta * n + Vec3(0.1, -0.05, 0.08));
    EXPECT_TRUE(MatrixNear(negative, xi, 1e-13));
    // The same motion with a zero reference: the principal representative (2 pi - theta) n.
    const Vec6 principal = LogSE3Near(H, Vec3::Zero());
    EXPECT_TRUE(MatrixNear(principal.tail<3>(), (kTwoPi - theta) * n, 1e-14));
    EXPECT_TRUE(MatrixNear(principal, LogSE3(H), 1e-15));
    EXPECT_TRUE(MatrixNear(ExpSE3(principal).Matrix(), H.Matrix(), 1e-14));
  }
  // A rotation below pi continued to negative angles: (theta - 2 pi) n.
  const Vec3 n = Vec3(0.0, 0.6, 0.8);
  SE3 H;
  H.R = ExpSO3(2.5 * n);
  H.x = Vec3(1.0, 0.0, -1.0);
  const Vec6 log_h = LogSE3Near(H, (2.5 - kTwoPi) * n + Vec3(0.2, 0.0, 0.1));
  EXPECT_TRUE(MatrixNear(log_h.tail<3>(), (2.5 - kTwoPi) * n, 1e-14));
  EXPECT_TRUE(MatrixNear(ExpSE3(log_h).Matrix(), H.Matrix(), 1e-14));
}

TEST(Se3LogNear, AtZeroRotationWithAReferencePastPiReturnsTheFullTurnBranch) {
  // A pure translation seen from a reference with |w_ref| > pi: the continued branch is
  // 2 pi n_ref (the caller must reject it: T^-1 is singular there), never the principal 0.
  const Vec3 w_ref = 3.3 * Vec3(0.0, 0.0, 1.0);
  const Vec6 log_h = LogSE3Near(SE3::Translation(Vec3(1.0, 0.0, 0.0)), w_ref);
  EXPECT_TRUE(MatrixNear(log_h.tail<3>(), Vec3(0.0, 0.0, kTwoPi), 1e-15));
}

}  // namespace
}  // namespace screwfem::se3_log_near_test
