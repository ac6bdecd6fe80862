// SE(3) toolkit: method.md §1. Series thresholds are chosen so that the truncation error of
// the series and the cancellation error of the closed form are both below ~1e-14 relative at
// the switch (checked in tests/lie/se3_*_test.cpp against long-double series).
#include "screwfem/lie/se3.h"

#include <cmath>
#include <numbers>

namespace screwfem {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Horner evaluation of sum_k c[k] x^k.
template <std::size_t N>
double Poly(const double (&c)[N], double x) {
  double r = c[N - 1];
  for (std::size_t k = N - 1; k-- > 0;) r = r * x + c[k];
  return r;
}

// Coefficients of T(xi) = I + t1 A + t2 A^2 + t3 A^3 + t4 A^4, A = ad(xi) (method.md §1.3 B).
struct TCoeffs {
  double t1, t2, t3, t4;
};
TCoeffs TCoefficients(double phi) {
  if (phi < 0.25) {
    const double p2 = phi * phi;
    static constexpr double c1[] = {-0.5, 0.0, 1.0 / 720, -1.0 / 20160, 1.0 / 1209600};
    static constexpr double c2[] = {1.0 / 6, 0.0, -1.0 / 5040, 1.0 / 181440, -1.0 / 13305600};
    static constexpr double c3[] = {-1.0 / 24, 1.0 / 360, -1.0 / 13440, 1.0 / 907200,
                                    -1.0 / 95800320};
    static constexpr double c4[] = {1.0 / 120, -1.0 / 2520, 1.0 / 120960, -1.0 / 9979200,
                                    1.0 / 1245404160};
    return {Poly(c1, p2), Poly(c2, p2), Poly(c3, p2), Poly(c4, p2)};
  }
  const double s = std::sin(phi), c = std::cos(phi);
  const double p2 = phi * phi, p3 = p2 * phi, p4 = p2 * p2, p5 = p4 * phi;
  return {(phi * s - 4.0 * (1.0 - c)) / (2.0 * p2), (4.0 * phi + phi * c - 5.0 * s) / (2.0 * p3),
          (phi * s - 2.0 * (1.0 - c)) / (2.0 * p4), (2.0 * phi + phi * c - 3.0 * s) / (2.0 * p5)};
}

// Coefficients of T^-1(xi) = I + A/2 + s2 A^2 + s4 A^4 and their scaled derivatives
// hat_s_k = (1/phi) d s_k / d phi (method.md §1.3 B, §1.4).
struct TInvCoeffs {
  double s2, s4;
};
TInvCoeffs TInvCoefficients(double phi) {
  if (phi < 0.25) {
    const double p2 = phi * phi;
    static constexpr double c2[] = {1.0 / 12, 0.0, -1.0 / 30240, -1.0 / 604800, -1.0 / 15966720};
    static constexpr double c4[] = {-1.0 / 720, -1.0 / 15120, -1.0 / 403200, -1.0 / 11975040,
                                    -691.0 / 261534873600.0};
    return {Poly(c2, p2), Poly(c4, p2)};
  }
  const double p2 = phi * phi;
  const double kappa = 0.5 * phi / std::tan(0.5 * phi);
  const double s4 = ((1.0 - 0.5 * kappa) / p2 - 1.0 / (4.0 * (1.0 - std::cos(phi)))) / p2;
  const double s2 = (1.0 - kappa) / p2 + s4 * p2;
  return {s2, s4};
}

TInvCoeffs TInvCoefficientDerivatives(double phi) {
  if (phi < 0.9) {
    const double p2 = phi * phi;
    static constexpr double a[] = {0.0,
                                   -1.0 / 7560,
                                   -1.0 / 100800,
                                   -1.0 / 1995840,
                                   -691.0 / 32691859200.0,
                                   -1.0 / 1245404160.0,
                                   -3617.0 / 127031224320000.0,
                                   -43867.0 / 45616912653312000.0,
                                   -174611.0 / 5575400435404800000.0};
    static constexpr double b[] = {-1.0 / 7560,
                                   -1.0 / 100800,
                                   -1.0 / 1995840,
                                   -691.0 / 32691859200.0,
                                   -1.0 / 1245404160.0,
                                   -3617.0 / 127031224320000.0,
                                   -43867.0 / 45616912653312000.0,
                                   -174611.0 / 5575400435404800000.0,
                                   -77683.0 / 78339444663287808000.0};
    return {Poly(a, p2), Poly(b, p2)};
  }
  const double p2 = phi * phi, p3 = p2 * phi;
  const double s = std::sin(phi), omc = 1.0 - std::cos(phi);
  const double kappa = 0.5 * phi / std::tan(0.5 * phi);
  const double dkappa = (kappa - kappa * kappa - 0.25 * p2) / phi;
  const double s4 = ((1.0 - 0.5 * kappa) / p2 - 1.0 / (4.0 * omc)) / p2;
  const double ds4 =
      (-dkappa / (2.0 * p2) - (2.0 - kappa) / p3 + s / (4.0 * omc * omc)) / p2 - 2.0 * s4 / phi;
  const double ds2 = -dkappa / p2 - 2.0 * (1.0 - kappa) / p3 + ds4 * p2 + 2.0 * s4 * phi;
  return {ds2 / phi, ds4 / phi};
}

}  // namespace

namespace lie_detail {
double A0(double phi) {
  if (phi < 0.2) {
    static constexpr double c[] = {1.0, -1.0 / 6, 1.0 / 120, -1.0 / 5040, 1.0 / 362880};
    return Poly(c, phi * phi);
  }
  return std::sin(phi) / phi;
}
double A1(double phi) {
  if (phi < 0.2) {
    static constexpr double c[] = {0.5, -1.0 / 24, 1.0 / 720, -1.0 / 40320, 1.0 / 3628800};
    return Poly(c, phi * phi);
  }
  return (1.0 - std::cos(phi)) / (phi * phi);
}
double A2(double phi) {
  if (phi < 0.2) {
    static constexpr double c[] = {1.0 / 6, -1.0 / 120, 1.0 / 5040, -1.0 / 362880,
                                   1.0 / 39916800};
    return Poly(c, phi * phi);
  }
  return (phi - std::sin(phi)) / (phi * phi * phi);
}
double C(double phi) {
  if (phi < 0.2) {
    static constexpr double c[] = {1.0 / 12, 1.0 / 720, 1.0 / 30240, 1.0 / 1209600,
                                   1.0 / 47900160};
    return Poly(c, phi * phi);
  }
  return (1.0 - 0.5 * phi / std::tan(0.5 * phi)) / (phi * phi);
}
}  // namespace lie_detail

using namespace lie_detail;

Mat4 SE3::Matrix() const {
  Mat4 M = Mat4::Identity();
  M.topLeftCorner<3, 3>() = R;
  M.topRightCorner<3, 1>() = x;
  return M;
}

Mat3 Skew(const Vec3& a) {
  Mat3 S;
  S << 0.0, -a(2), a(1), a(2), 0.0, -a(0), -a(1), a(0), 0.0;
  return S;
}

Vec3 Unskew(const Mat3& A) {
  return 0.5 * Vec3(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
}

Mat4 Wedge(const Vec6& xi) {
  Mat4 X = Mat4::Zero();
  X.topLeftCorner<3, 3>() = Skew(xi.tail<3>());
  X.topRightCorner<3, 1>() = xi.head<3>();
  return X;
}

Vec6 Vee(const Mat4& X) {
  Vec6 xi;
  xi.head<3>() = X.topRightCorner<3, 1>();
  xi.tail<3>() = Unskew(X.topLeftCorner<3, 3>());
  return xi;
}

Mat6 Ad(const SE3& H) {
  Mat6 A;
  A.topLeftCorner<3, 3>() = H.R;
  A.topRightCorner<3, 3>().noalias() = Skew(H.x) * H.R;
  A.bottomLeftCorner<3, 3>().setZero();
  A.bottomRightCorner<3, 3>() = H.R;
  return A;
}

Mat6 ad(const Vec6& xi) {
  Mat6 A;
  const Mat3 W = Skew(xi.tail<3>());
  A.topLeftCorner<3, 3>() = W;
  A.topRightCorner<3, 3>() = Skew(xi.head<3>());
  A.bottomLeftCorner<3, 3>().setZero();
  A.bottomRightCorner<3, 3>() = W;
  return A;
}

Mat6 Star(const Vec6& y) {
  Mat6 S;
  const Mat3 F = Skew(y.head<3>());
  S.topLeftCorner<3, 3>().setZero();
  S.topRightCorner<3, 3>() = F;
  S.bottomLeftCorner<3, 3>() = F;
  S.bottomRightCorner<3, 3>() = Skew(y.tail<3>());
  return S;
}

Mat3 ExpSO3(const Vec3& w) {
  const double phi = w.norm();
  const Mat3 W = Skew(w);
  return Mat3::Identity() + A0(phi) * W + A1(phi) * (W * W);
}

Vec3 LogSO3(const Mat3& R) {
  const Vec3 v = Unskew(R);  // = sin(phi) n
  const double sn = v.norm();
  const double cs = 0.5 * (R.trace() - 1.0);
  const double phi = std::atan2(sn, cs);
  if (phi < 1e-4) return (1.0 + phi * phi / 6.0) * v;
  // The axis v/|v| has an absolute error ~eps/sin(phi) (v is a difference of O(1) entries of R),
  // so this formula is used only up to pi/2; beyond, B below gives the axis to ~eps. (A switch at
  // pi - 1e-3 lost ~500x accuracy just below it: 5e-13 round-trip error, tests/lie.)
  if (phi < 0.5 * kPi) return (phi / sn) * v;
  // Beyond pi/2: B = (R + R^T)/2 - cos(phi) I = (1 - cos(phi)) n n^T, with 1 - cos(phi) >= 1.
  const Mat3 B = 0.5 * (R + R.transpose()) - cs * Mat3::Identity();
  Eigen::Index i = 0;
  B.diagonal().maxCoeff(&i);
  Vec3 n = B.col(i).normalized();
  if (n.dot(v) < 0.0) n = -n;
  return phi * n;
}

Mat3 TSO3(const Vec3& w) {
  const double phi = w.norm();
  const Mat3 W = Skew(w);
  return Mat3::Identity() - A1(phi) * W + A2(phi) * (W * W);
}

Mat3 TSO3Inv(const Vec3& w) {
  const double phi = w.norm();
  const Mat3 W = Skew(w);
  return Mat3::Identity() + 0.5 * W + C(phi) * (W * W);
}

SE3 ExpSE3(const Vec6& xi) {
  const Vec3 w = xi.tail<3>();
  const double phi = w.norm();
  const Mat3 W = Skew(w);
  const Mat3 W2 = W * W;
  SE3 H;
  H.R = Mat3::Identity() + A0(phi) * W + A1(phi) * W2;
  // TSO3(w)^T = I + a1 W + a2 W^2
  H.x = xi.head<3>() + A1(phi) * (W * xi.head<3>()) + A2(phi) * (W2 * xi.head<3>());
  return H;
}

namespace {
// Translation part of the logarithm on the branch w: u = TSO3Inv(w)^T x = (I - W/2 + c W^2) x.
Vec3 LogTranslation(const Vec3& w, const Vec3& x) {
  const Mat3 W = Skew(w);
  return x - 0.5 * (W * x) + C(w.norm()) * (W * (W * x));
}
}  // namespace

Vec6 LogSE3(const SE3& H) {
  Vec6 xi;
  xi.tail<3>() = LogSO3(H.R);
  xi.head<3>() = LogTranslation(xi.tail<3>(), H.x);
  return xi;
}

Vec6 LogSE3Near(const SE3& H, const Vec3& w_ref) {
  const Vec3 w0 = LogSO3(H.R);
  const double theta = w0.norm();
  Vec3 w = w0;
  if (theta > 1e-12 || w_ref.norm() > kPi) {
    // Axis: that of the principal log; at (numerically) zero rotation that of the reference.
    const Vec3 n = theta > 1e-12 ? Vec3(w0 / theta) : Vec3(w_ref.normalized());
    double best = (w0 - w_ref).squaredNorm();
    for (int k = -3; k <= 3; ++k) {
      if (k == 0) continue;
      const Vec3 wk = (theta + kTwoPi * k) * n;
      const double dist = (wk - w_ref).squaredNorm();
      if (dist < best) {
        best = dist;
        w = wk;
      }
    }
  }
  Vec6 xi;
  xi.tail<3>() = w;
  xi.head<3>() = LogTranslation(w, H.x);
  return xi;
}

Mat6 TSE3(const Vec6& xi) {
  const TCoeffs t = TCoefficients(xi.tail<3>().norm());
  const Mat6 A = ad(xi);
  const Mat6 A2 = A * A;
  const Mat6 A3 = A2 * A;
  const Mat6 A4 = A2 * A2;
  return Mat6::Identity() + t.t1 * A + t.t2 * A2 + t.t3 * A3 + t.t4 * A4;
}

Mat6 TSE3Inv(const Vec6& xi) {
  const TInvCoeffs s = TInvCoefficients(xi.tail<3>().norm());
  const Mat6 A = ad(xi);
  const Mat6 A2 = A * A;
  return Mat6::Identity() + 0.5 * A + s.s2 * A2 + s.s4 * (A2 * A2);
}

Mat6 TSE3InvDirectional(const Vec6& xi, const Vec6& dxi) {
  const double phi = xi.tail<3>().norm();
  const TInvCoeffs s = TInvCoefficients(phi);
  const TInvCoeffs ds = TInvCoefficientDerivatives(phi);
  const double wdw = xi.tail<3>().dot(dxi.tail<3>());
  const Mat6 A = ad(xi), dA = ad(dxi);
  const Mat6 A2 = A * A;
  const Mat6 A3 = A2 * A;
  const Mat6 dA_A = dA * A, A_dA = A * dA;
  return 0.5 * dA + ds.s2 * wdw * A2 + s.s2 * (dA_A + A_dA) + ds.s4 * wdw * (A2 * A2) +
         s.s4 * (dA * A3 + A_dA * A2 + A2 * dA_A + A3 * dA);
}

Mat6 TSE3Directional(const Vec6& xi, const Vec6& dxi) {
  const Mat6 T = TSE3(xi);
  return -T * TSE3InvDirectional(xi, dxi) * T;
}

Mat6 DTSE3InvT(const Vec6& xi, const Vec6& sigma) {
  const double phi = xi.tail<3>().norm();
  const TInvCoeffs s = TInvCoefficients(phi);
  const TInvCoeffs ds = TInvCoefficientDerivatives(phi);
  const Mat6 At = ad(xi).transpose();
  const Vec6 y1 = At * sigma;
  const Vec6 y2 = At * y1;
  const Vec6 y3 = At * y2;
  const Vec6 y4 = At * y3;
  const Mat6 S0 = Star(sigma);
  const Mat6 At_S0 = At * S0;
  const Mat6 At2_S0 = At * At_S0;
  const Mat6 S1 = Star(y1);
  const Mat6 At_S1 = At * S1;
  Mat6 D = 0.5 * S0 + s.s2 * (S1 + At_S0) +
           s.s4 * (Star(y3) + At * Star(y2) + At * At_S1 + At * At2_S0);
  // Derivative of the coefficients through phi = |w|: (hat_s2 y2 + hat_s4 y4) [0 w^T].
  const Vec6 g = ds.s2 * y2 + ds.s4 * y4;
  D.rightCols<3>().noalias() += g * xi.tail<3>().transpose();
  return D;
}

}  // namespace screwfem
