// Tangent operators of exp/log on SO(3) and SE(3) (lie/se3.h): identities, accuracy
// against long-double series across the series/closed-form switches, and finite-difference checks
// through the right-trivialised retraction H exp(wedge(dh)).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <string>
#include <vector>

#include "lie/lie_test_util.h"
#include "screwfem/lie/se3.h"

namespace screwfem::se3_tangent_test {
namespace {

using test::AngleCase;
using test::kPi;
using test::kTwoPi;
using test::MatrixNear;

double RelativeError(const Mat6& a, const Mat6& reference) {
  return test::MaxAbs(a - reference) / test::MaxAbs(reference);
}

// --- identities at every angle case ------------------------------------------------------------

class Se3TangentAtAngle : public ::testing::TestWithParam<AngleCase> {
 protected:
  std::vector<Vec6> Samples() const { return test::SamplesAtAngle(GetParam(), 17u); }
  static double Scale(const Vec6& xi) { return 1.0 + xi.norm(); }
};

TEST_P(Se3TangentAtAngle, TSE3FixesItsOwnTwist) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    EXPECT_TRUE(MatrixNear(TSE3(xi) * xi, xi, 2e-15 * Scale(xi)));
  }
}

TEST_P(Se3TangentAtAngle, TSE3InvDirectionalTimesIsTheDirectionalDerivativeAppliedToTheVector) {
  std::mt19937 rng = test::MakeRng(static_cast<std::uint32_t>(1000.0 * GetParam().phi) + 29u);
  for (const Vec6& xi : Samples()) {
    const Vec6 dxi = test::RandomVec6(rng, 1.0), v = test::RandomVec6(rng, 1.0);
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const Vec6 expected = TSE3InvDirectional(xi, dxi) * v;
    EXPECT_TRUE(MatrixNear(TSE3InvDirectionalTimes(xi, dxi, v), expected,
                           1e-14 * (1.0 + expected.norm()) * Scale(xi) * Scale(xi)));
  }
}

TEST_P(Se3TangentAtAngle, SharedSeriesCoefficientsGiveTheSameOperators) {
  // CalcTSeries evaluates the coefficients of T, T^-1 and the derivatives of T^-1 together
  // (one sincos of phi/2); the overloads that take them agree with the standalone operators.
  std::mt19937 rng = test::MakeRng(static_cast<std::uint32_t>(1000.0 * GetParam().phi) + 31u);
  for (const Vec6& xi : Samples()) {
    const Vec6 dxi = test::RandomVec6(rng, 1.0), v = test::RandomVec6(rng, 1.0);
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const TSeries c = CalcTSeries(xi.tail<3>().norm());
    const double tol = 1e-14 * Scale(xi) * Scale(xi);
    EXPECT_LT(RelativeError(TSE3(xi, c), TSE3(xi)), tol);
    EXPECT_LT(RelativeError(TSE3Inv(xi, c), TSE3Inv(xi)), tol);
    EXPECT_LT(RelativeError(DTSE3InvT(xi, v, c), DTSE3InvT(xi, v)), tol);
    const Vec6 expected = TSE3InvDirectionalTimes(xi, dxi, v);
    EXPECT_TRUE(MatrixNear(TSE3InvDirectionalTimes(xi, dxi, v, c), expected,
                           tol * (1.0 + expected.norm())));
    // T at several points along the twist from the powers of ad(xi) once.
    const double scales[3] = {0.1127, 0.5, 0.8873};
    TSeries scaled[3];
    for (int i = 0; i < 3; ++i) scaled[i] = CalcTSeries(scales[i] * xi.tail<3>().norm());
    Mat6 Ti, T[3];
    TSE3InvAndScaledTSE3(xi, c, 3, scales, scaled, &Ti, T);
    EXPECT_LT(RelativeError(Ti, TSE3Inv(xi)), tol);
    for (int i = 0; i < 3; ++i) EXPECT_LT(RelativeError(T[i], TSE3(scales[i] * xi)), tol);
  }
}

TEST_P(Se3TangentAtAngle, TSE3InvFixesItsOwnTwist) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    // |T^-1| grows like 1/(2 pi - phi): scale the round-off by it.
    const double tinv_norm = test::MaxAbs(TSE3Inv(xi));
    EXPECT_TRUE(MatrixNear(TSE3Inv(xi) * xi, xi, 4e-15 * tinv_norm * Scale(xi)));
  }
}

TEST_P(Se3TangentAtAngle, TSE3InvIsTheInverseOfTSE3) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const double tinv_norm = test::MaxAbs(TSE3Inv(xi));
    EXPECT_TRUE(
        MatrixNear(TSE3(xi) * TSE3Inv(xi), Mat6::Identity(), 4e-15 * tinv_norm * Scale(xi)));
    EXPECT_TRUE(
        MatrixNear(TSE3Inv(xi) * TSE3(xi), Mat6::Identity(), 4e-15 * tinv_norm * Scale(xi)));
  }
}

TEST_P(Se3TangentAtAngle, TSE3OfNegatedTwistIsAdjointOfExpTimesTSE3) {
  // T(-xi) = Ad(exp xi) T(xi), hence T^-1(xi) Ad(exp(-xi)) = T^-1(-xi).
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    EXPECT_TRUE(MatrixNear(TSE3(-xi), Ad(ExpSE3(xi)) * TSE3(xi), 4e-15 * Scale(xi) * Scale(xi)));
    EXPECT_TRUE(
        MatrixNear(TSE3Inv(-xi), TSE3Inv(xi) * Ad(ExpSE3(-xi)), 1e-14 * Scale(xi) * Scale(xi)));
  }
}

TEST_P(Se3TangentAtAngle, TSE3HasTSO3DiagonalBlocksAndZeroLowerLeftBlock) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const Mat6 T = TSE3(xi);
    const Mat3 t_so3 = TSO3(xi.tail<3>());
    EXPECT_TRUE(MatrixNear(T.topLeftCorner<3, 3>(), t_so3, 1e-15 * Scale(xi)));
    EXPECT_TRUE(MatrixNear(T.bottomRightCorner<3, 3>(), t_so3, 1e-15 * Scale(xi)));
    EXPECT_TRUE(MatrixNear(T.bottomLeftCorner<3, 3>(), Mat3::Zero(), 0.0));
  }
}

TEST_P(Se3TangentAtAngle, TSE3InvHasTSO3InvDiagonalBlocksAndZeroLowerLeftBlock) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    const Mat6 T = TSE3Inv(xi);
    const Mat3 t_so3 = TSO3Inv(xi.tail<3>());
    const double tol = 1e-15 * test::MaxAbs(t_so3) * Scale(xi);
    EXPECT_TRUE(MatrixNear(T.topLeftCorner<3, 3>(), t_so3, tol));
    EXPECT_TRUE(MatrixNear(T.bottomRightCorner<3, 3>(), t_so3, tol));
    EXPECT_TRUE(MatrixNear(T.bottomLeftCorner<3, 3>(), Mat3::Zero(), 0.0));
  }
}

TEST_P(Se3TangentAtAngle, TSO3InvIsInverseOfTSO3AndTSO3TransposeIsTSO3OfNegated) {
  for (const Vec6& xi : Samples()) {
    const Vec3 w = xi.tail<3>();
    SCOPED_TRACE(::testing::Message() << "w = " << w.transpose());
    // |T_SO3^-1| grows like 1/(2 pi - phi): scale the round-off by it.
    const double tol = 2e-15 * (1.0 + test::MaxAbs(TSO3Inv(w)));
    EXPECT_TRUE(MatrixNear(TSO3(w) * TSO3Inv(w), Mat3::Identity(), tol));
    EXPECT_TRUE(MatrixNear(TSO3Inv(w) * TSO3(w), Mat3::Identity(), tol));
    EXPECT_TRUE(MatrixNear(TSO3(w).transpose(), TSO3(-w), 1e-15));
    EXPECT_TRUE(MatrixNear(TSO3(w) * w, w, 2e-15 * Scale(xi)));
  }
}

TEST_P(Se3TangentAtAngle, TSE3AndTSE3InvMatchLongDoubleAdSeries) {
  for (const Vec6& xi : Samples()) {
    SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose());
    EXPECT_LE(RelativeError(TSE3(xi), test::TSeries(xi).cast<double>()), 1e-14);
    EXPECT_LE(RelativeError(TSE3Inv(xi), test::TInvSeries(xi).cast<double>()), 2e-14);
  }
}

INSTANTIATE_TEST_SUITE_P(Angles, Se3TangentAtAngle, ::testing::ValuesIn(test::kAngleCases),
                         test::AngleCaseName);

// --- accuracy sweeps against long-double references ----------------------------------------

// phi from 1e-9 to 3: 10 points per decade plus the series switches (0.2 scalars, 0.25 T and
// T^-1, 0.9 D) approached to one ulp from both sides.
std::vector<double> PhiSweep() {
  std::vector<double> phis;
  for (int k = 0; k <= 95; ++k) phis.push_back(1e-9 * std::pow(10.0, 0.1 * k));
  for (double s : {0.2, 0.25, 0.9}) {
    phis.push_back(std::nextafter(s, 0.0));
    phis.push_back(s);
    phis.push_back(std::nextafter(s, 1.0));
    phis.push_back(s - 1e-9);
    phis.push_back(s + 1e-9);
  }
  for (double p : {1.2, 1.6, 2.0, 2.4, 2.8, 3.0}) phis.push_back(p);
  return phis;
}

TEST(Se3TangentAccuracy, TSE3MatchesLongDoubleAdSeriesToRelative1em13FromPhi1em9To3) {
  std::mt19937 rng = test::MakeRng(21);
  double worst = 0.0;
  for (double phi : PhiSweep()) {
    for (double u_norm : {0.0, 0.1, 1.0, 10.0}) {
      const Vec6 xi = test::RandomTwist(rng, phi, u_norm);
      const double err = RelativeError(TSE3(xi), test::TSeries(xi).cast<double>());
      worst = std::max(worst, err);
      EXPECT_LE(err, 1e-13) << "phi = " << phi << ", xi = " << xi.transpose();
    }
  }
  RecordProperty("worst_relative_error", ::testing::PrintToString(worst));
}

TEST(Se3TangentAccuracy, TSE3InvMatchesInverseOfLongDoubleSeriesToRelative1em13FromPhi1em9To3) {
  std::mt19937 rng = test::MakeRng(22);
  double worst = 0.0;
  for (double phi : PhiSweep()) {
    for (double u_norm : {0.0, 0.1, 1.0, 10.0}) {
      const Vec6 xi = test::RandomTwist(rng, phi, u_norm);
      const double err = RelativeError(TSE3Inv(xi), test::TInvSeries(xi).cast<double>());
      worst = std::max(worst, err);
      EXPECT_LE(err, 1e-13) << "phi = " << phi << ", xi = " << xi.transpose();
    }
  }
  RecordProperty("worst_relative_error", ::testing::PrintToString(worst));
}

TEST(Se3TangentAccuracy, TSE3AndTSE3InvAreContinuousAcrossTheirSeriesSwitchAtPhi0p25) {
  const Vec3 n = Vec3(1.0, 2.0, -2.0) / 3.0;
  const Vec3 u(0.7, -0.4, 1.1);
  Vec6 below, at;
  below.head<3>() = u;
  below.tail<3>() = std::nextafter(0.25, 0.0) * n;
  at.head<3>() = u;
  at.tail<3>() = 0.25 * n;
  // The true change over one ulp of phi is ~1e-17; the jump is the disagreement of the branches.
  EXPECT_LE(RelativeError(TSE3(below), TSE3(at)), 2e-14);
  EXPECT_LE(RelativeError(TSE3Inv(below), TSE3Inv(at)), 2e-14);
}

struct ScalarFunction {
  const char* name;
  double (*f)(double);
  test::LD (*reference)(test::LD);
};
const ScalarFunction kScalarFunctions[] = {
    {"A0", lie_detail::A0, test::A0Ref},
    {"A1", lie_detail::A1, test::A1Ref},
    {"A2", lie_detail::A2, test::A2Ref},
    {"C", lie_detail::C, test::CRef},
};

TEST(Se3ScalarFunctions, MatchLongDoubleSeriesToRelative1em13FromPhi1em9To3) {
  std::vector<double> phis = PhiSweep();
  phis.push_back(0.0);
  for (const ScalarFunction& fn : kScalarFunctions) {
    double worst = 0.0;
    for (double phi : phis) {
      const double reference = static_cast<double>(fn.reference(phi));
      const double err = std::abs(fn.f(phi) - reference) / std::abs(reference);
      worst = std::max(worst, err);
      EXPECT_LE(err, 1e-13) << fn.name << "(" << phi << ")";
    }
    RecordProperty(std::string(fn.name) + "_worst_relative_error", ::testing::PrintToString(worst));
  }
}

TEST(Se3ScalarFunctions, HaveTheDocumentedValuesAtZeroAndAtGenericAngles) {
  EXPECT_EQ(lie_detail::A0(0.0), 1.0);
  EXPECT_EQ(lie_detail::A1(0.0), 0.5);
  EXPECT_EQ(lie_detail::A2(0.0), 1.0 / 6.0);
  EXPECT_EQ(lie_detail::C(0.0), 1.0 / 12.0);
  // Closed forms evaluated independently (no cancellation at phi = 1.3).
  const double p = 1.3;
  EXPECT_NEAR(lie_detail::A0(p), std::sin(p) / p, 1e-15);
  EXPECT_NEAR(lie_detail::A1(p), (1.0 - std::cos(p)) / (p * p), 1e-15);
  EXPECT_NEAR(lie_detail::A2(p), (p - std::sin(p)) / (p * p * p), 1e-15);
  EXPECT_NEAR(lie_detail::C(p), (1.0 - 0.5 * p / std::tan(0.5 * p)) / (p * p), 1e-15);
  // C(pi) = 1/pi^2 since cot(pi/2) = 0.
  EXPECT_NEAR(lie_detail::C(kPi), 1.0 / (kPi * kPi), 1e-16);
}

TEST(Se3ScalarFunctions, AreContinuousAtTheSeriesSwitchPhi0p2) {
  const double below = std::nextafter(0.2, 0.0);
  for (const ScalarFunction& fn : kScalarFunctions) {
    // The true change over one ulp is ~1e-17 relative; any jump is the error of the two branches.
    const double jump = std::abs(fn.f(0.2) - fn.f(below)) / std::abs(fn.f(0.2));
    EXPECT_LE(jump, 1e-13) << fn.name;
  }
}

// --- finite differences through the retraction ---------------------------------------------

constexpr double kStep = 1e-6;

// Angles for the derivative checks: small-angle ranges, both sides of the 0.25 switch, generic,
// near pi and past pi (exp is smooth there).
const double kFdAngles[] = {0.0, 1e-8, 1e-4, 0.2, 0.3, 1.0, 2.0, 3.0, kPi - 1e-9, 4.0, 6.0};

TEST(Se3TangentFiniteDifference, RightDerivativeOfExpSE3IsWedgeOfTSE3TimesIncrement) {
  // exp(xi)^-1 exp(xi + e dxi) = exp(wedge(e T(xi) dxi)) + O(e^2).
  std::mt19937 rng = test::MakeRng(31);
  for (double phi : kFdAngles) {
    for (int s = 0; s < 4; ++s) {
      const Vec6 xi = test::RandomTwist(rng, phi, 1.5);
      const Vec6 dxi = test::RandomVec6(rng, 1.0);
      SCOPED_TRACE(::testing::Message()
                   << "xi = " << xi.transpose() << ", dxi = " << dxi.transpose());
      const SE3 H_inv = ExpSE3(xi).Inverse();
      const Vec6 plus = LogSE3(H_inv * ExpSE3(xi + kStep * dxi));
      const Vec6 minus = LogSE3(H_inv * ExpSE3(xi - kStep * dxi));
      const Vec6 fd = (plus - minus) / (2.0 * kStep);
      const Vec6 analytic = TSE3(xi) * dxi;
      EXPECT_TRUE(MatrixNear(fd, analytic, 1e-8 * std::max(1.0, test::MaxAbs(analytic))));
    }
  }
}

TEST(Se3TangentFiniteDifference, RightDerivativeOfExpSO3IsSkewOfTSO3TimesIncrement) {
  // R(w)^T R(w + e dw) = exp(skew(e T_SO3(w) dw)) + O(e^2).
  std::mt19937 rng = test::MakeRng(32);
  for (double phi : kFdAngles) {
    for (int s = 0; s < 4; ++s) {
      const Vec3 w = phi * test::RandomUnitVector(rng);
      const Vec3 dw = test::RandomVec6(rng, 1.0).head<3>();
      SCOPED_TRACE(::testing::Message() << "w = " << w.transpose() << ", dw = " << dw.transpose());
      const Mat3 Rt = ExpSO3(w).transpose();
      const Vec3 plus = LogSO3(Rt * ExpSO3(w + kStep * dw));
      const Vec3 minus = LogSO3(Rt * ExpSO3(w - kStep * dw));
      const Vec3 fd = (plus - minus) / (2.0 * kStep);
      const Vec3 analytic = TSO3(w) * dw;
      EXPECT_TRUE(MatrixNear(fd, analytic, 1e-8 * std::max(1.0, test::MaxAbs(analytic))));
    }
  }
}

TEST(Se3TangentFiniteDifference, RightDerivativeOfLogSE3IsTSE3InvOfTheLog) {
  // log(H exp(e z)) - log(H) = e T^-1(log H) z + O(e^2). Past pi, on the continued branch.
  std::mt19937 rng = test::MakeRng(33);
  for (double phi : {0.0, 1e-8, 1e-4, 0.2, 0.3, 1.0, 2.0, 3.0, 4.0, 5.5}) {
    for (int s = 0; s < 4; ++s) {
      const Vec6 xi = test::RandomTwist(rng, phi, 1.5);
      const Vec6 z = test::RandomVec6(rng, 1.0);
      SCOPED_TRACE(::testing::Message() << "xi = " << xi.transpose() << ", z = " << z.transpose());
      const SE3 H = ExpSE3(xi);
      const Vec3 w_ref = xi.tail<3>();
      const Vec6 plus = LogSE3Near(H * ExpSE3(kStep * z), w_ref);
      const Vec6 minus = LogSE3Near(H * ExpSE3(-kStep * z), w_ref);
      const Vec6 fd = (plus - minus) / (2.0 * kStep);
      const Vec6 analytic = TSE3Inv(xi) * z;
      EXPECT_TRUE(MatrixNear(fd, analytic, 1e-8 * std::max(1.0, test::MaxAbs(analytic))));
      if (phi < 3.1) {  // the principal log agrees below pi
        const Vec6 fd_principal =
            (LogSE3(H * ExpSE3(kStep * z)) - LogSE3(H * ExpSE3(-kStep * z))) / (2.0 * kStep);
        EXPECT_TRUE(
            MatrixNear(fd_principal, analytic, 1e-8 * std::max(1.0, test::MaxAbs(analytic))));
      }
    }
  }
}

TEST(Se3TangentFiniteDifference, RightDerivativeOfLogSO3IsTSO3InvOfTheLog) {
  std::mt19937 rng = test::MakeRng(34);
  for (double phi : {0.0, 1e-8, 1e-4, 0.2, 0.3, 1.0, 2.0, 3.0}) {
    for (int s = 0; s < 4; ++s) {
      const Vec3 w = phi * test::RandomUnitVector(rng);
      const Vec3 z = test::RandomVec6(rng, 1.0).head<3>();
      SCOPED_TRACE(::testing::Message() << "w = " << w.transpose() << ", z = " << z.transpose());
      const Mat3 R = ExpSO3(w);
      const Vec3 fd =
          (LogSO3(R * ExpSO3(kStep * z)) - LogSO3(R * ExpSO3(-kStep * z))) / (2.0 * kStep);
      const Vec3 analytic = TSO3Inv(w) * z;
      EXPECT_TRUE(MatrixNear(fd, analytic, 1e-8 * std::max(1.0, test::MaxAbs(analytic))));
    }
  }
}

// D switches to its series below 0.9, T^-1 below 0.25; 6 is close to the singularity at 2 pi.
const double kDAngles[] = {1e-8, 1e-3, 0.2, 0.3, 0.85, 0.95, 2.0, 3.0, 4.5, 6.0};

TEST(Se3TangentFiniteDifference, DTSE3InvTIsCentralDifferenceOfTSE3InvTransposeTimesSigma) {
  std::mt19937 rng = test::MakeRng(35);
  for (double phi : kDAngles) {
    for (int s = 0; s < 3; ++s) {
      const Vec6 xi = test::RandomTwist(rng, phi, 1.0 + s);
      const Vec6 sigma = test::RandomVec6(rng, 5.0);
      SCOPED_TRACE(::testing::Message()
                   << "xi = " << xi.transpose() << ", sigma = " << sigma.transpose());
      Mat6 fd;
      for (int j = 0; j < 6; ++j) {
        const Vec6 e = kStep * Vec6::Unit(j);
        fd.col(j) = (TSE3Inv(xi + e).transpose() * sigma - TSE3Inv(xi - e).transpose() * sigma) /
                    (2.0 * kStep);
      }
      const Mat6 D = DTSE3InvT(xi, sigma);
      // Just above the T^-1 switch (0.3) the closed form of s4 carries ~1e-14 absolute noise,
      // which the difference quotient amplifies to ~5e-9: hence 3e-8, not 1e-8.
      EXPECT_TRUE(MatrixNear(D, fd, 3e-8 * std::max(1.0, test::MaxAbs(D))));
    }
  }
}

TEST(Se3TangentAccuracy, DTSE3InvTMatchesComplexStepDerivativeOfLongDoubleSeries) {
  std::mt19937 rng = test::MakeRng(36);
  std::vector<double> phis(std::begin(kDAngles), std::end(kDAngles));
  for (double p : {0.0, 1e-9, 0.1, 0.25, 0.5, std::nextafter(0.9, 0.0), 0.9, 1.5, 5.0})
    phis.push_back(p);
  double worst = 0.0;
  for (double phi : phis) {
    for (int s = 0; s < 2; ++s) {
      const Vec6 xi = test::RandomTwist(rng, phi, 1.0 + s);
      const Vec6 sigma = test::RandomVec6(rng, 5.0);
      SCOPED_TRACE(::testing::Message()
                   << "xi = " << xi.transpose() << ", sigma = " << sigma.transpose());
      const Mat6 reference = test::DSeries(xi, sigma);
      const double err = test::MaxAbs(DTSE3InvT(xi, sigma) - reference) / test::MaxAbs(reference);
      worst = std::max(worst, err);
      EXPECT_LE(err, 1e-12);
    }
  }
  RecordProperty("worst_relative_error", ::testing::PrintToString(worst));
}

TEST(Se3TangentAccuracy, DTSE3InvTIsContinuousAcrossItsSeriesSwitchAtPhi0p9) {
  const Vec3 n = Vec3(2.0, -1.0, 2.0) / 3.0;
  const Vec3 u(0.3, 1.2, -0.8);
  Vec6 below, at, sigma;
  below.head<3>() = u;
  below.tail<3>() = std::nextafter(0.9, 0.0) * n;
  at.head<3>() = u;
  at.tail<3>() = 0.9 * n;
  sigma << 1.0, -2.0, 3.0, 0.5, 4.0, -1.5;
  EXPECT_LE(test::MaxAbs(DTSE3InvT(below, sigma) - DTSE3InvT(at, sigma)) /
                test::MaxAbs(DTSE3InvT(at, sigma)),
            1e-12);
}

}  // namespace
}  // namespace screwfem::se3_tangent_test
