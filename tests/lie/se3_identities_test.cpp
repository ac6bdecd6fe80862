// Algebraic identities of the se(3) operators and exp/log round trips (lie/se3.h),
// checked at the identity, in the small-angle series ranges, at generic angles, near pi, exactly
// at pi and past pi.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "lie/lie_test_util.h"
#include "screwfem/lie/se3.h"

namespace screwfem::se3_identities_test {
namespace {

using test::AngleCase;
using test::kPi;
using test::kTwoPi;
using test::MatrixNear;

// --- operators without an angle: exact or to round-off ---------------------------------------

TEST(Se3Algebra, VeeInvertsWedgeExactly) {
  std::mt19937 rng = test::MakeRng(1);
  for (int i = 0; i < 100; ++i) {
    const Vec6 xi = test::RandomVec6(rng, 5.0);
    EXPECT_TRUE(MatrixNear(Vee(Wedge(xi)), xi, 0.0));
    const Mat4 X = Wedge(xi);
    EXPECT_TRUE(MatrixNear(Wedge(Vee(X)), X, 0.0));
  }
}

TEST(Se3Algebra, WedgeHasSkewRotationBlockTranslationColumnAndZeroLastRow) {
  Vec6 xi;
  xi << 1.0, 2.0, 3.0, 4.0, 5.0, 6.0;
  Mat4 expected;
  expected << 0.0, -6.0, 5.0, 1.0,  //
      6.0, 0.0, -4.0, 2.0,          //
      -5.0, 4.0, 0.0, 3.0,          //
      0.0, 0.0, 0.0, 0.0;
  EXPECT_TRUE(MatrixNear(Wedge(xi), expected, 0.0));
}

TEST(Se3Algebra, UnskewInvertsSkewAndTakesSkewSymmetricPart) {
  std::mt19937 rng = test::MakeRng(2);
  for (int i = 0; i < 100; ++i) {
    const Vec3 a = test::RandomVec6(rng, 3.0).head<3>();
    EXPECT_TRUE(MatrixNear(Unskew(Skew(a)), a, 0.0));
    const Mat3 S = Mat3::Random() + Mat3::Random().transpose();  // symmetric part is ignored
    const Mat3 Ssym = 0.5 * (S + S.transpose());
    EXPECT_TRUE(MatrixNear(Unskew(Skew(a) + Ssym), a, 1e-15 * 8.0));
  }
}

TEST(Se3Algebra, SkewTimesVectorIsCrossProduct) {
  std::mt19937 rng = test::MakeRng(3);
  for (int i = 0; i < 100; ++i) {
    const Vec3 a = test::RandomVec6(rng, 3.0).head<3>();
    const Vec3 b = test::RandomVec6(rng, 3.0).head<3>();
    EXPECT_TRUE(MatrixNear(Skew(a) * b, a.cross(b), 1e-15 * 9.0));
    EXPECT_TRUE(MatrixNear(Skew(a).transpose(), -Skew(a), 0.0));
  }
}

TEST(Se3Algebra, StarIsDefinedByAdTransposeTimesDualVector) {
  // ad(xi)^T y = Star(y) xi for all xi, y.
  std::mt19937 rng = test::MakeRng(4);
  for (int i = 0; i < 100; ++i) {
    const Vec6 xi = test::RandomVec6(rng, 4.0);
    const Vec6 y = test::RandomVec6(rng, 4.0);
    EXPECT_TRUE(MatrixNear(ad(xi).transpose() * y, Star(y) * xi, 1e-15 * 64.0));
  }
}

TEST(Se3Algebra, AdTransposeTimesIsTheTransposedAdjointApplied) {
  std::mt19937 rng = test::MakeRng(6);
  for (int i = 0; i < 100; ++i) {
    const SE3 H = ExpSE3(test::RandomVec6(rng, 3.0));
    const Vec6 f = test::RandomVec6(rng, 4.0);
    EXPECT_TRUE(MatrixNear(AdTransposeTimes(H, f), Ad(H).transpose() * f, 1e-13));
  }
}

TEST(Se3Algebra, InverseOfSe3ComposesToIdentity) {
  std::mt19937 rng = test::MakeRng(5);
  for (int i = 0; i < 50; ++i) {
    const SE3 H = ExpSE3(test::RandomVec6(rng, 2.0));
    EXPECT_TRUE(MatrixNear((H * H.Inverse()).Matrix(), Mat4::Identity(), 1e-14));
    EXPECT_TRUE(MatrixNear((H.Inverse() * H).Matrix(), Mat4::Identity(), 1e-14));
    EXPECT_TRUE(MatrixNear(H.Inverse().Matrix(), H.Matrix().inverse(), 1e-14));
    const Vec3 p(0.3, -1.2, 2.0);
    EXPECT_TRUE(MatrixNear(H.Act(p), (H.Matrix() * p.homogeneous()).head<3>(), 1e-14));
  }
}

// --- identities at every angle case ------------------------------------------------------------

class Se3AtAngle : public ::testing::TestWithParam<AngleCase> {
 protected:
  // Samples of this angle case; the seed depends only on the angle so each test sees the same set.
  std::vector<Vec6> Samples() const { return test::SamplesAtAngle(GetParam(), 7u); }
  // A second, independent set of vectors (z, y, ...).
  static std::vector<Vec6> Others(std::uint32_t salt) {
    std::mt19937 rng = test::MakeRng(salt);
    std::vector<Vec6> out;
    for (int i = 0; i < test::kSamplesPerAngle; ++i) out.push_back(test::RandomVec6(rng, 2.0));
    return out;
  }
  static double Scale(const Vec6& xi) { return 1.0 + xi.norm(); }
};

TEST_P(Se3AtAngle, VeeInvertsWedgeAndSkewIsCrossProductAndStarIsDualOfAd) {
  const std::vector<Vec6> ys = Others(10);
  const std::vector<Vec6> xis = Samples();
  for (std::size_t i = 0; i < xis.size(); ++i) {
    const Vec6& xi = xis[i];
    const Vec6& y = ys[i];
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose() << ", y = " << y.transpose());
    EXPECT_TRUE(MatrixNear(Vee(Wedge(xi)), xi, 0.0));
    EXPECT_TRUE(MatrixNear(Skew(xi.tail<3>()) * y.head<3>(), xi.tail<3>().cross(y.head<3>()),
                           4e-16 * Scale(xi) * Scale(y)));
    EXPECT_TRUE(MatrixNear(ad(xi).transpose() * y, Star(y) * xi, 4e-16 * Scale(xi) * Scale(y)));
  }
}

TEST_P(Se3AtAngle, BracketAndCoBracketAreAdAndAdTransposeTimesTheVector) {
  const std::vector<Vec6> ys = Others(11);
  const std::vector<Vec6> xis = Samples();
  for (std::size_t i = 0; i < xis.size(); ++i) {
    const Vec6& xi = xis[i];
    const Vec6& y = ys[i];
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose() << ", y = " << y.transpose());
    EXPECT_TRUE(MatrixNear(Bracket(xi, y), Vec6(ad(xi) * y), 4e-16 * Scale(xi) * Scale(y)));
    EXPECT_TRUE(
        MatrixNear(CoBracket(xi, y), Vec6(ad(xi).transpose() * y), 4e-16 * Scale(xi) * Scale(y)));
  }
}

TEST_P(Se3AtAngle, AdOfTwistAnnihilatesTheTwist) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    EXPECT_TRUE(MatrixNear(ad(xi) * xi, Vec6::Zero(), 4e-16 * Scale(xi) * Scale(xi)));
  }
}

TEST_P(Se3AtAngle, AdIsAntisymmetricInItsTwoArguments) {
  const std::vector<Vec6> zs = Others(11);
  const std::vector<Vec6> xis = Samples();
  for (std::size_t i = 0; i < xis.size(); ++i) {
    const Vec6& x = xis[i];
    const Vec6& z = zs[i];
    SCOPED_TRACE(::testing::Message() << "x = " << x.transpose() << ", z = " << z.transpose());
    EXPECT_TRUE(MatrixNear(ad(x) * z, -(ad(z) * x), 4e-16 * Scale(x) * Scale(z)));
  }
}

TEST_P(Se3AtAngle, WedgeOfAdIsTheMatrixCommutator) {
  const std::vector<Vec6> zs = Others(12);
  const std::vector<Vec6> xis = Samples();
  for (std::size_t i = 0; i < xis.size(); ++i) {
    const Vec6& x = xis[i];
    const Vec6& z = zs[i];
    SCOPED_TRACE(::testing::Message() << "x = " << x.transpose() << ", z = " << z.transpose());
    const Mat4 commutator = Wedge(x) * Wedge(z) - Wedge(z) * Wedge(x);
    EXPECT_TRUE(MatrixNear(Wedge(ad(x) * z), commutator, 4e-16 * Scale(x) * Scale(z)));
  }
}

TEST_P(Se3AtAngle, ConjugationOfWedgeByHIsWedgeOfAdjoint) {
  const std::vector<Vec6> zs = Others(13);
  const std::vector<Vec6> xis = Samples();
  for (std::size_t i = 0; i < xis.size(); ++i) {
    const SE3 H = ExpSE3(xis[i]);
    const Vec6& z = zs[i];
    SCOPED_TRACE(::testing::Message() << "xi = " << xis[i].transpose());
    const Mat4 lhs = H.Matrix() * Wedge(z) * H.Inverse().Matrix();
    EXPECT_TRUE(MatrixNear(lhs, Wedge(Ad(H) * z), 2e-15 * Scale(xis[i]) * Scale(z)));
  }
}

TEST_P(Se3AtAngle, InverseOfAdjointIsAdjointOfInverse) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const SE3 H = ExpSE3(xi);
    EXPECT_TRUE(MatrixNear(Ad(H).inverse(), Ad(H.Inverse()), 2e-15 * Scale(xi) * Scale(xi)));
    EXPECT_TRUE(MatrixNear(Ad(H) * Ad(H.Inverse()), Mat6::Identity(), 2e-15 * Scale(xi)));
  }
}

TEST_P(Se3AtAngle, AdjointOfExpEqualsMatrixExponentialOfAd) {
  // Ad(exp xi) = exp(ad xi), reference: long-double Taylor series with scaling and squaring.
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const Mat6 reference = test::ExpSeries<6>(test::AdLd(xi)).cast<double>();
    EXPECT_TRUE(MatrixNear(Ad(ExpSE3(xi)), reference, 1e-14 * Scale(xi)));
  }
}

TEST_P(Se3AtAngle, ExpSO3IsOrthonormalWithDeterminantOne) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "w = " << xi.tail<3>().transpose());
    const Mat3 R = ExpSO3(xi.tail<3>());
    EXPECT_TRUE(MatrixNear(R.transpose() * R, Mat3::Identity(), 4e-15));
    EXPECT_NEAR(R.determinant(), 1.0, 4e-15);
    // The rotation axis is fixed: R w = w.
    EXPECT_TRUE(MatrixNear(R * xi.tail<3>(), xi.tail<3>(), 1e-15 * Scale(xi)));
  }
}

TEST_P(Se3AtAngle, ExpSO3HasTheRotationAngleAsTraceAngle) {
  // tr R = 1 + 2 cos(phi): ExpSO3 rotates by exactly |w|.
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "w = " << xi.tail<3>().transpose());
    const double phi = xi.tail<3>().norm();
    EXPECT_NEAR(ExpSO3(xi.tail<3>()).trace(), 1.0 + 2.0 * std::cos(phi), 2e-15);
  }
}

TEST_P(Se3AtAngle, ExpSE3EqualsMatrixExponentialOfWedge) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const Mat4 reference = test::ExpSeries<4>(test::WedgeLd(xi)).cast<double>();
    EXPECT_TRUE(MatrixNear(ExpSE3(xi).Matrix(), reference, 1e-13));
    EXPECT_TRUE(MatrixNear(ExpSE3(xi).R, ExpSO3(xi.tail<3>()), 2e-15));
  }
}

TEST_P(Se3AtAngle, LogSO3InvertsExpSO3OnThePrincipalBranch) {
  // |w| < pi: LogSO3(ExpSO3(w)) = w. |w| = pi: +-w (both are the principal log). |w| > pi: the
  // principal representative (|w| - 2 pi) w/|w|.
  const double phi = GetParam().phi;
  for (const Vec6& xi : Samples()) {
    const Vec3 w = xi.tail<3>();
    SCOPED_TRACE(::testing::Message() << "w = " << w.transpose());
    const Vec3 log_w = LogSO3(ExpSO3(w));
    if (phi < kPi) {
      EXPECT_TRUE(MatrixNear(log_w, w, 2e-15 * (1.0 + phi)));
    } else if (phi == kPi) {
      EXPECT_TRUE(test::IsPlusOrMinus(log_w, w, 1e-15 * kPi)) << "log = " << log_w.transpose();
    } else {
      const Vec3 principal = (1.0 - kTwoPi / w.norm()) * w;
      EXPECT_TRUE(MatrixNear(log_w, principal, 2e-15 * (1.0 + phi)));
    }
    EXPECT_LE(log_w.norm(), kPi + 1e-15);
    EXPECT_TRUE(MatrixNear(ExpSO3(log_w), ExpSO3(w), 2e-15));
  }
}

TEST_P(Se3AtAngle, LogSE3InvertsExpSE3OnThePrincipalBranch) {
  const double phi = GetParam().phi;
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const SE3 H = ExpSE3(xi);
    const Vec6 log_h = LogSE3(H);
    if (phi < kPi) {
      EXPECT_TRUE(MatrixNear(log_h, xi, 4e-15 * Scale(xi)));
    } else {
      EXPECT_LE(log_h.tail<3>().norm(), kPi + 1e-15);
    }
    // Always: the logarithm reproduces H (compares the motions past pi).
    EXPECT_TRUE(MatrixNear(ExpSE3(log_h).Matrix(), H.Matrix(), 4e-15 * Scale(xi)));
  }
}

TEST_P(Se3AtAngle, LogSE3NearWithTheTwistAsReferenceInvertsExpSE3OnEveryBranch) {
  // Past pi, the principal log cannot return xi; the branch-continued log with w_ref = w can.
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const Vec6 log_h = LogSE3Near(ExpSE3(xi), xi.tail<3>());
    // Near 2 pi, T_SO3^-1 (used for the translation) grows like 1/|2 pi - phi|.
    EXPECT_TRUE(MatrixNear(log_h, xi, 3e-14 * Scale(xi)));
  }
}

INSTANTIATE_TEST_SUITE_P(Angles, Se3AtAngle, ::testing::ValuesIn(test::kAngleCases),
                         test::AngleCaseName);

// --- logarithm accuracy over the whole principal range ---------------------------------------

TEST(Se3LogAccuracy, LogSO3RoundTripIsAccurateToRoundOffAtEveryAngleBelowPi) {
  // The log is well conditioned up to pi; every formula switch must keep it at round-off level.
  // (An axis taken from the antisymmetric part of R loses accuracy like eps/sin(phi) near pi.)
  std::vector<double> phis;
  for (int k = 0; k <= 200; ++k) phis.push_back(kPi - std::pow(10.0, -0.5 - 8.5 * k / 200.0));
  for (int k = 1; k < 200; ++k) phis.push_back(kPi * k / 200.0);
  for (int k = 0; k <= 60; ++k) phis.push_back(std::pow(10.0, -12.0 + 0.2 * k));  // 1e-12 .. 1
  for (double p : {5e-5, 9.9e-5, 1.01e-4, 0.5 * kPi - 1e-9, 0.5 * kPi + 1e-9}) phis.push_back(p);
  std::mt19937 rng = test::MakeRng(6);
  double worst = 0.0;
  for (double phi : phis) {
    for (int s = 0; s < 5; ++s) {
      const Vec3 w = phi * test::RandomUnitVector(rng);
      const double err = test::MaxAbs(LogSO3(ExpSO3(w)) - w) / phi;
      worst = std::max(worst, err);
      EXPECT_LE(err, 2e-15) << "phi = " << phi << ", w = " << w.transpose();
    }
  }
  RecordProperty("worst_relative_error", ::testing::PrintToString(worst));
}

// --- dedicated cases at exactly pi ------------------------------------------------------------

TEST(Se3LogAtPi, LogSO3OfHalfTurnAboutEachAxisHasAnglePiAndThatAxis) {
  for (int i = 0; i < 3; ++i) {
    const Vec3 w = kPi * Vec3::Unit(i);
    const Vec3 log_w = LogSO3(ExpSO3(w));
    EXPECT_NEAR(log_w.norm(), kPi, 1e-15);
    EXPECT_TRUE(test::IsPlusOrMinus(log_w, w, 1e-15)) << log_w.transpose();
  }
  // A half turn about a diagonal axis, built exactly: R = 2 n n^T - I.
  const Vec3 n = Vec3(1.0, -2.0, 2.0) / 3.0;
  const Mat3 R = 2.0 * n * n.transpose() - Mat3::Identity();
  const Vec3 log_w = LogSO3(R);
  EXPECT_NEAR(log_w.norm(), kPi, 1e-15);
  EXPECT_TRUE(test::IsPlusOrMinus(log_w, kPi * n, 2e-15)) << log_w.transpose();
}

TEST(Se3LogAtPi, LogSE3OfHalfTurnReproducesTheMotion) {
  SE3 H;
  const Vec3 n = Vec3(2.0, 3.0, 6.0) / 7.0;
  H.R = 2.0 * n * n.transpose() - Mat3::Identity();
  H.x = Vec3(0.5, -1.0, 2.0);
  const Vec6 log_h = LogSE3(H);
  EXPECT_NEAR(log_h.tail<3>().norm(), kPi, 1e-15);
  EXPECT_TRUE(MatrixNear(ExpSE3(log_h).Matrix(), H.Matrix(), 1e-14));
}

}  // namespace
}  // namespace screwfem::se3_identities_test
