// Shared helpers for the Lie toolkit tests: sampling with fixed seeds, matrix comparison with a
// readable failure message, and long-double references (power series, no closed forms) that do
// not share any formula with src/lie/se3.cpp.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "screwfem/lie/se3.h"

namespace screwfem::test {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

using LD = long double;
template <int N>
using MatL = Eigen::Matrix<long double, N, N>;
using Mat4L = MatL<4>;
using Mat6L = MatL<6>;

// --- sampling ------------------------------------------------------------------------------------

inline std::mt19937 MakeRng(std::uint32_t salt = 0) { return std::mt19937(20240611u + salt); }

inline Vec3 RandomUnitVector(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Vec3 v;
  do {
    v = Vec3(g(rng), g(rng), g(rng));
  } while (v.norm() < 1e-2);
  return v.normalized();
}

inline Vec6 RandomVec6(std::mt19937& rng, double scale = 1.0) {
  std::uniform_real_distribution<double> uni(-scale, scale);
  Vec6 v;
  for (int i = 0; i < 6; ++i) v(i) = uni(rng);
  return v;
}

// xi = [u; w] with |w| = phi (to round-off) about a random axis and |u| = u_norm.
inline Vec6 RandomTwist(std::mt19937& rng, double phi, double u_norm = 1.0) {
  Vec6 xi;
  xi.head<3>() = u_norm * RandomUnitVector(rng);
  xi.tail<3>() = phi * RandomUnitVector(rng);
  return xi;
}

// Rotation angles at which every identity is checked: the identity, the small-angle series
// ranges, generic angles, near pi (the log switches formula at pi - 1e-3), exactly pi, and past pi
// (up to 2 pi - 0.3, where T^-1 is still far from its singularity at 2 pi).
struct AngleCase {
  const char* name;
  double phi;
};
inline constexpr AngleCase kAngleCases[] = {
    {"Identity", 0.0},
    {"Phi1em8", 1e-8},
    {"Phi1em4", 1e-4},
    {"Phi0p2", 0.2},
    {"Generic0p7", 0.7},
    {"Generic2p0", 2.0},
    {"PiMinus1em3", kPi - 1e-3},
    {"PiMinus1em7", kPi - 1e-7},
    {"PiMinus1em9", kPi - 1e-9},
    {"ExactlyPi", kPi},
    {"PiPlus1em9", kPi + 1e-9},
    {"PastPi4p0", 4.0},
    {"TwoPiMinus0p3", kTwoPi - 0.3},
};

inline std::string AngleCaseName(const ::testing::TestParamInfo<AngleCase>& info) {
  return info.param.name;
}

// Sample i of an angle case: the first three use the coordinate axes (so that |w| == phi exactly,
// e.g. exactly pi), the others random axes; |u| cycles through 0, 0.3, 1.5, 4.
inline Vec6 SampleTwist(const AngleCase& c, int i, std::mt19937& rng) {
  static constexpr double kUNorms[] = {0.0, 0.3, 1.5, 4.0};
  Vec6 xi = RandomTwist(rng, c.phi, kUNorms[i % 4]);
  if (i < 3) {
    xi.tail<3>() = Vec3::Unit(i) * c.phi;
  }
  return xi;
}
inline constexpr int kSamplesPerAngle = 16;

// kSamplesPerAngle twists of angle case c; the seed depends only on the angle and `salt`, so
// every test of a suite sees the same set.
inline std::vector<Vec6> SamplesAtAngle(const AngleCase& c, std::uint32_t salt) {
  std::mt19937 rng = MakeRng(static_cast<std::uint32_t>(1000.0 * c.phi) + salt);
  std::vector<Vec6> out;
  for (int i = 0; i < kSamplesPerAngle; ++i) out.push_back(SampleTwist(c, i, rng));
  return out;
}

// --- comparison ----------------------------------------------------------------------------------

// Passes if every entry of a and b is finite and max |a - b| <= tol. The expressions are
// evaluated into dynamic matrices first, so the comparison and its failure message (Eigen's
// printing) are instantiated once per scalar type, not once per expression type (the Lie-group
// tests compare ~50 expression types; this took se3_identities_test.cpp from 30 to 25 s).
template <typename S>
::testing::AssertionResult MatrixNearEvaluated(
    const Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>& a,
    const Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>& b, double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "size mismatch";
  }
  if (!a.allFinite() || !b.allFinite()) {
    return ::testing::AssertionFailure() << "non-finite entry\na =\n" << a << "\nb =\n" << b;
  }
  const double err = static_cast<double>((a - b).cwiseAbs().maxCoeff());
  if (err <= tol) return ::testing::AssertionSuccess();
  Eigen::IOFormat fmt(Eigen::FullPrecision);
  return ::testing::AssertionFailure() << "max |a - b| = " << err << " > tol = " << tol << "\na =\n"
                                       << a.format(fmt) << "\nb =\n"
                                       << b.format(fmt);
}

template <typename DerivedA, typename DerivedB>
::testing::AssertionResult MatrixNear(const Eigen::MatrixBase<DerivedA>& a,
                                      const Eigen::MatrixBase<DerivedB>& b, double tol) {
  using S = typename DerivedA::Scalar;
  using Dyn = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  return MatrixNearEvaluated<S>(Dyn(a), Dyn(b), tol);
}

template <typename Derived>
double MaxAbs(const Eigen::MatrixBase<Derived>& a) {
  return a.cwiseAbs().maxCoeff();
}

// Same rotation vector up to sign flip allowed only at exactly pi (both represent the rotation).
inline bool IsPlusOrMinus(const Vec3& a, const Vec3& b, double tol) {
  return (a - b).cwiseAbs().maxCoeff() <= tol || (a + b).cwiseAbs().maxCoeff() <= tol;
}

// --- long-double references ----------------------------------------------------------------------

template <int N>
MatL<N> ToLd(const Eigen::Matrix<double, N, N>& m) {
  return m.template cast<long double>();
}
inline Eigen::Matrix<long double, 6, 1> ToLd(const Vec6& v) { return v.cast<long double>(); }

// Matrix exponential: 40-term Taylor series after scaling to infinity norm <= 1/2, then squaring.
template <int N>
MatL<N> ExpSeries(const MatL<N>& X) {
  const LD norm = X.cwiseAbs().rowwise().sum().maxCoeff();
  int squarings = 0;
  LD scale = 1.0L;
  while (norm * scale > 0.5L) {
    scale *= 0.5L;
    ++squarings;
  }
  const MatL<N> Y = scale * X;
  MatL<N> term = MatL<N>::Identity();
  MatL<N> sum = MatL<N>::Identity();
  for (int k = 1; k <= 40; ++k) {
    term = (term * Y) / static_cast<LD>(k);
    sum += term;
  }
  for (int i = 0; i < squarings; ++i) sum = (sum * sum).eval();
  return sum;
}

// 4x4 algebra matrix and 6x6 ad operator in long double, built entry by entry from the definitions
// of lie/se3.h (not from the library).
inline Mat4L WedgeLd(const Vec6& xi) {
  const auto u = xi.head<3>().cast<LD>();
  const auto w = xi.tail<3>().cast<LD>();
  Mat4L X = Mat4L::Zero();
  X(0, 1) = -w(2);
  X(0, 2) = w(1);
  X(1, 0) = w(2);
  X(1, 2) = -w(0);
  X(2, 0) = -w(1);
  X(2, 1) = w(0);
  X(0, 3) = u(0);
  X(1, 3) = u(1);
  X(2, 3) = u(2);
  return X;
}

// ad(xi) for any scalar type (long double, complex long double for complex-step derivatives).
template <typename S>
Eigen::Matrix<S, 6, 6> AdOf(const Eigen::Matrix<S, 6, 1>& xi) {
  auto skew = [](const S& a0, const S& a1, const S& a2) {
    Eigen::Matrix<S, 3, 3> K;
    K << S(0), -a2, a1, a2, S(0), -a0, -a1, a0, S(0);
    return K;
  };
  Eigen::Matrix<S, 6, 6> A = Eigen::Matrix<S, 6, 6>::Zero();
  A.template topLeftCorner<3, 3>() = skew(xi(3), xi(4), xi(5));
  A.template topRightCorner<3, 3>() = skew(xi(0), xi(1), xi(2));
  A.template bottomRightCorner<3, 3>() = skew(xi(3), xi(4), xi(5));
  return A;
}

inline Mat6L AdLd(const Vec6& xi) { return AdOf<LD>(xi.cast<LD>()); }

// T(xi) = sum_k (-1)^k/(k+1)! ad(xi)^k (lie/se3.h), 120 terms.
template <typename S>
Eigen::Matrix<S, 6, 6> TSeriesOf(const Eigen::Matrix<S, 6, 1>& xi) {
  using M = Eigen::Matrix<S, 6, 6>;
  const M minus_a = -AdOf<S>(xi);
  M term = M::Identity();  // (-A)^k/(k+1)!
  M sum = M::Identity();
  for (int k = 1; k <= 120; ++k) {
    term = (term * minus_a) / S(static_cast<LD>(k + 1));
    sum += term;
  }
  return sum;
}

inline Mat6L TSeries(const Vec6& xi) { return TSeriesOf<LD>(xi.cast<LD>()); }

// T^-1(xi) as the full-pivot LU inverse of the long-double series.
inline Mat6L TInvSeries(const Vec6& xi) { return TSeries(xi).fullPivLu().inverse(); }

// D(xi, sigma) = d/dxi [T^-1(xi)^T sigma] by complex-step differentiation of the long-double
// series (no subtraction, so the step can be 1e-30 and the result is exact to round-off).
inline Mat6 DSeries(const Vec6& xi, const Vec6& sigma) {
  using CL = std::complex<LD>;
  constexpr LD kStep = 1e-30L;
  const Eigen::Matrix<CL, 6, 1> sigma_c = sigma.cast<LD>().cast<CL>();
  Mat6 D;
  for (int j = 0; j < 6; ++j) {
    Eigen::Matrix<CL, 6, 1> xi_c = xi.cast<LD>().cast<CL>();
    xi_c(j) += CL(0.0L, kStep);
    const Eigen::Matrix<CL, 6, 6> tinv = TSeriesOf<CL>(xi_c).fullPivLu().inverse();
    const Eigen::Matrix<CL, 6, 1> g = tinv.transpose() * sigma_c;
    for (int i = 0; i < 6; ++i) D(i, j) = static_cast<double>(g(i).imag() / kStep);
  }
  return D;
}

// Scalar coefficient functions as alternating power series in long double, summed until the terms
// drop below 1e-24 relative (no cancellation for the phi <= 6 used here).
namespace detail {
// sum_{n>=0} (-1)^n p^(2n) / (2n + offset)!
inline LD AlternatingFactorialSeries(LD p, int offset) {
  LD fact = 1.0L;
  for (int i = 2; i <= offset; ++i) fact *= static_cast<LD>(i);
  LD term = 1.0L / fact;
  LD sum = term;
  for (int n = 1; n < 200; ++n) {
    term *= -p * p / (static_cast<LD>(2 * n + offset - 1) * static_cast<LD>(2 * n + offset));
    sum += term;
    if (std::fabs(term) < 1e-24L * std::fabs(sum)) break;
  }
  return sum;
}
}  // namespace detail

inline LD A0Ref(LD p) { return detail::AlternatingFactorialSeries(p, 1); }  // sin(p)/p
inline LD A1Ref(LD p) { return detail::AlternatingFactorialSeries(p, 2); }  // (1-cos p)/p^2
inline LD A2Ref(LD p) { return detail::AlternatingFactorialSeries(p, 3); }  // (p-sin p)/p^3

// C(p) = (1 - x cot x)/p^2 with x = p/2. Since sin x - x cos x = sum_{n>=1} (-1)^(n+1) 2n
// x^(2n+1)/(2n+1)! =: x^3 Q(x), C = Q(x) / (4 sin(x)/x).
inline LD CRef(LD p) {
  const LD x = 0.5L * p;
  LD sum = 0.0L;
  LD xpow = 1.0L;  // x^(2n-2)
  LD fact = 6.0L;  // (2n+1)!
  for (int n = 1; n < 200; ++n) {
    const LD term = ((n % 2 == 1) ? 1.0L : -1.0L) * static_cast<LD>(2 * n) * xpow / fact;
    sum += term;
    if (std::fabs(term) < 1e-24L * std::fabs(sum)) break;
    xpow *= x * x;
    fact *= static_cast<LD>(2 * n + 2) * static_cast<LD>(2 * n + 3);
  }
  return sum / (4.0L * A0Ref(x));
}

}  // namespace screwfem::test
