// SE(3) toolkit: lie/se3.h. Series thresholds are chosen so that the truncation error of
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

// Coefficients of T(xi) = I + t1 A + t2 A^2 + t3 A^3 + t4 A^4, A = ad(xi) (lie/se3.h B).
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
// hat_s_k = (1/phi) d s_k / d phi (lie/se3.h B).
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

TSeries CalcTSeries(double phi) {
  // The closed forms of TCoefficients, TInvCoefficients and TInvCoefficientDerivatives with
  // sin(phi) = 2 sh ch, 1 - cos(phi) = 2 sh^2 and tan(phi/2) = sh/ch, (sh, ch) of phi/2; the
  // series below the same switches.
  TSeries c{};
  if (phi < 0.25) {
    const TCoeffs t = TCoefficients(phi);
    const TInvCoeffs s = TInvCoefficients(phi);
    const TInvCoeffs ds = TInvCoefficientDerivatives(phi);
    return {t.t1, t.t2, t.t3, t.t4, s.s2, s.s4, ds.s2, ds.s4};
  }
  const double sh = std::sin(0.5 * phi), ch = std::cos(0.5 * phi);
  const double sn = 2.0 * sh * ch, omc = 2.0 * sh * sh, cs = 1.0 - omc;
  const double p2 = phi * phi, p3 = p2 * phi, p4 = p2 * p2, p5 = p4 * phi;
  c.t1 = (phi * sn - 4.0 * omc) / (2.0 * p2);
  c.t2 = (4.0 * phi + phi * cs - 5.0 * sn) / (2.0 * p3);
  c.t3 = (phi * sn - 2.0 * omc) / (2.0 * p4);
  c.t4 = (2.0 * phi + phi * cs - 3.0 * sn) / (2.0 * p5);
  const double kappa = 0.5 * phi * ch / sh;
  c.s4 = ((1.0 - 0.5 * kappa) / p2 - 1.0 / (4.0 * omc)) / p2;
  c.s2 = (1.0 - kappa) / p2 + c.s4 * p2;
  if (phi < 0.9) {
    const TInvCoeffs ds = TInvCoefficientDerivatives(phi);
    c.s2_hat = ds.s2;
    c.s4_hat = ds.s4;
    return c;
  }
  const double dkappa = (kappa - kappa * kappa - 0.25 * p2) / phi;
  const double ds4 =
      (-dkappa / (2.0 * p2) - (2.0 - kappa) / p3 + sn / (4.0 * omc * omc)) / p2 - 2.0 * c.s4 / phi;
  const double ds2 = -dkappa / p2 - 2.0 * (1.0 - kappa) / p3 + ds4 * p2 + 2.0 * c.s4 * phi;
  c.s2_hat = ds2 / phi;
  c.s4_hat = ds4 / phi;
  return c;
}

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
    static constexpr double c[] = {1.0 / 6, -1.0 / 120, 1.0 / 5040, -1.0 / 362880, 1.0 / 39916800};
    return Poly(c, phi * phi);
  }
  return (phi - std::sin(phi)) / (phi * phi * phi);
}
double C(double phi) {
  if (phi < 0.2) {
    static constexpr double c[] = {1.0 / 12, 1.0 / 720, 1.0 / 30240, 1.0 / 1209600, 1.0 / 47900160};
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

Mat3 ExpSO3(const Vec3& w) {
  const double phi = w.norm();
  const Mat3 W = Skew(w);
  return Mat3::Identity() + A0(phi) * W + A1(phi) * (W * W);
}

Vec3 LogSO3(const Mat3& R) {
  const Vec3 v = Unskew(R);  // = sin(phi) n
  const double sn = v.norm();
  const double cs = 0.5 * (R.trace() - 1.0);
  // Near the identity (the joint constraints, phi ~ their violation) without the atan2:
  // phi = asin(sn) = sn (1 + sn^2 / 6 + ...), so phi^2 / 6 and sn^2 / 6 differ by sn^4 / 18
  // < 6e-18, below the rounding of the factor.
  if (cs > 0.0 && sn < 9.9e-5) return (1.0 + sn * sn / 6.0) * v;
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
  // A0, A1, A2 from one sincos above the series switch of A0 .. A2 (0.2).
  double a0, a1, a2;
  if (phi < 0.2) {
    a0 = A0(phi);
    a1 = A1(phi);
    a2 = A2(phi);
  } else {
    const double sn = std::sin(phi), cs = std::cos(phi), p2 = phi * phi;
    a0 = sn / phi;
    a1 = (1.0 - cs) / p2;
    a2 = (phi - sn) / (p2 * phi);
  }
  // W^2 = w w^T - |w|^2 I, and W^k x by cross and dot products.
  const Vec3 u = xi.head<3>();
  const double p2 = w.squaredNorm();
  SE3 H;
  H.R.noalias() = a1 * (w * w.transpose());
  H.R.diagonal().array() += 1.0 - a1 * p2;
  H.R += a0 * Skew(w);
  // TSO3(w)^T = I + a1 W + a2 W^2
  H.x = u + a1 * w.cross(u) + a2 * (w.dot(u) * w - p2 * u);
  return H;
}

namespace {
// Translation part of the logarithm on the branch w: u = TSO3Inv(w)^T x = (I - W/2 + c W^2) x,
// c = C(|w|).
Vec3 LogTranslation(const Vec3& w, const Vec3& x, double c) {
  const Vec3 wx = w.cross(x);
  return x - 0.5 * wx + c * w.cross(wx);
}
Vec3 LogTranslation(const Vec3& w, const Vec3& x) { return LogTranslation(w, x, C(w.norm())); }
}  // namespace

Vec6 LogSE3(const SE3& H) {
  Vec6 xi;
  xi.tail<3>() = LogSO3(H.R);
  xi.head<3>() = LogTranslation(xi.tail<3>(), H.x);
  return xi;
}

Vec3 LogSO3Near(const Mat3& R, const Vec3& w_ref) {
  const Vec3 w0 = LogSO3(R);
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
  return w;
}

Vec6 LogSE3Near(const SE3& H, const Vec3& w_ref) {
  Vec6 xi;
  xi.tail<3>() = LogSO3Near(H.R, w_ref);
  xi.head<3>() = LogTranslation(xi.tail<3>(), H.x);
  return xi;
}

Vec6 LogSE3Near(const SE3& H, const Vec3& w_ref, TSeries* series) {
  // LogTranslation with C = s2 - theta^2 s4 (TSO3Inv is the diagonal block of TSE3Inv).
  Vec6 xi;
  xi.tail<3>() = LogSO3Near(H.R, w_ref);
  const Vec3 w = xi.tail<3>();
  *series = CalcTSeries(w.norm());
  xi.head<3>() = LogTranslation(w, H.x, series->s2 - w.squaredNorm() * series->s4);
  return xi;
}

namespace {
// Blocks of the powers of A = ad(xi) = [W U; 0 W] (W = Skew(w), U = Skew(u)), which are
// A^k = [W^k C_k; 0 W^k] with W^3 = -theta^2 W, W^4 = -theta^2 W^2 and, from
// Skew(a) Skew(b) = b a^T - (a.b) I,
//   C_1 = U,  C_2 = W U + U W = u w^T + w u^T - 2 c I,  C_3 = -2 c W - theta^2 U,
//   C_4 = -2 c W^2 - theta^2 C_2,  c = w.u.
// A series sum_k a_k A^k then costs a few 3x3 sums instead of 6x6 products.
struct AdPowers {
  Mat3 W, W2, U, C2;
  double theta2, c;
};
AdPowers CalcAdPowers(const Vec6& xi) {
  const Vec3 u = xi.head<3>(), w = xi.tail<3>();
  AdPowers p;
  p.theta2 = w.squaredNorm();
  p.c = w.dot(u);
  p.W = Skew(w);
  p.U = Skew(u);
  p.W2.noalias() = w * w.transpose();
  p.W2.diagonal().array() -= p.theta2;
  p.C2.noalias() = u * w.transpose();
  p.C2 += p.C2.transpose().eval();
  p.C2.diagonal().array() -= 2.0 * p.c;
  return p;
}
}  // namespace

Mat6 TSE3(const Vec6& xi) {
  const TCoeffs t = TCoefficients(xi.tail<3>().norm());
  TSeries c{};
  c.t1 = t.t1;
  c.t2 = t.t2;
  c.t3 = t.t3;
  c.t4 = t.t4;
  return TSE3(xi, c);
}

namespace {
// T(s xi) in blocks from the powers of ad(xi) (the powers of ad(s xi) are those of ad(xi)
// scaled: W, U by s; W^2, C_2, theta^2, c by s^2), t = CalcTSeries(s |w|):
//   I + t1 A + t2 A^2 + t3 A^3 + t4 A^4, A = ad(s xi), is
//   diagonal   I + a W + b W^2,                       a = t1 - theta^2 t3, b = t2 - theta^2 t4
//   upper right a U + b C_2 - 2 c (t3 W + t4 W^2)      (W .. c those of s xi).
void FillTSE3(const AdPowers& p, double s, const TSeries& t, Mat6* T) {
  const double s2 = s * s, theta2 = s2 * p.theta2;
  const double a = s * (t.t1 - theta2 * t.t3), b = s2 * (t.t2 - theta2 * t.t4);
  T->topLeftCorner<3, 3>() = a * p.W + b * p.W2;
  T->topLeftCorner<3, 3>().diagonal().array() += 1.0;
  T->bottomRightCorner<3, 3>() = T->topLeftCorner<3, 3>();
  T->bottomLeftCorner<3, 3>().setZero();
  T->topRightCorner<3, 3>() =
      a * p.U + b * p.C2 - (2.0 * s2 * p.c) * ((s * t.t3) * p.W + (s2 * t.t4) * p.W2);
}

// T^-1(xi) = I + A/2 + s2 A^2 + s4 A^4 in blocks, e = s2 - theta^2 s4:
//   diagonal I + W/2 + e W^2,  upper right U/2 + e C_2 - 2 c s4 W^2.
void FillTSE3Inv(const AdPowers& p, const TSeries& s, Mat6* Ti) {
  const double e = s.s2 - p.theta2 * s.s4;
  Ti->topLeftCorner<3, 3>() = 0.5 * p.W + e * p.W2;
  Ti->topLeftCorner<3, 3>().diagonal().array() += 1.0;
  Ti->bottomRightCorner<3, 3>() = Ti->topLeftCorner<3, 3>();
  Ti->bottomLeftCorner<3, 3>().setZero();
  Ti->topRightCorner<3, 3>() = 0.5 * p.U + e * p.C2 - (2.0 * p.c * s.s4) * p.W2;
}
}  // namespace

Mat6 TSE3(const Vec6& xi, const TSeries& t) {
  Mat6 T;
  FillTSE3(CalcAdPowers(xi), 1.0, t, &T);
  return T;
}

void TSE3InvAndScaledTSE3(const Vec6& xi, const TSeries& c, int n, const double* scales,
                          const TSeries* scaled, Mat6* Ti, Mat6* T) {
  const AdPowers p = CalcAdPowers(xi);
  FillTSE3Inv(p, c, Ti);
  for (int i = 0; i < n; ++i) FillTSE3(p, scales[i], scaled[i], &T[i]);
}

Mat6 TSE3Inv(const Vec6& xi) {
  const TInvCoeffs s = TInvCoefficients(xi.tail<3>().norm());
  TSeries c{};
  c.s2 = s.s2;
  c.s4 = s.s4;
  return TSE3Inv(xi, c);
}

Mat6 TSE3Inv(const Vec6& xi, const TSeries& s) {
  Mat6 Ti;
  FillTSE3Inv(CalcAdPowers(xi), s, &Ti);
  return Ti;
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

namespace {
// The T^-1 part of TSeries (s2, s4 and their derivatives) at |w| of xi, for the operators
// below that need no T.
TSeries TInvSeries(const Vec6& xi) {
  const double phi = xi.tail<3>().norm();
  const TInvCoeffs s = TInvCoefficients(phi);
  const TInvCoeffs ds = TInvCoefficientDerivatives(phi);
  TSeries c{};
  c.s2 = s.s2;
  c.s4 = s.s4;
  c.s2_hat = ds.s2;
  c.s4_hat = ds.s4;
  return c;
}
}  // namespace

Vec6 TSE3InvDirectionalTimes(const Vec6& xi, const Vec6& dxi, const Vec6& v) {
  return TSE3InvDirectionalTimes(xi, dxi, v, TInvSeries(xi));
}

Vec6 TSE3InvDirectionalTimes(const Vec6& xi, const Vec6& dxi, const Vec6& v, const TSeries& c) {
  // ad(xi) = [W U; 0 W] is the dual number W + eps U, so every series in it is
  // F(W + eps U) = F(W) + eps DF(W)[U]: T^-1(xi) = [Phi(w)  DPhi(w)[u]; 0  Phi(w)], with
  // Phi(w) = TSO3Inv(w) = I + W/2 + C W^2 (C = s2 - theta^2 s4, and hat C = C'/phi = -2 s4,
  // breve C = hat C'/phi = -2 hat s4 from the coefficients above). Then, for v = [x; y] and
  // the direction dxi = [a; b],
  //   d/de T^-1(xi + e dxi) v = [DPhi[b] x + DPhi[a] y + D2Phi[u, b] y;  DPhi[b] y],
  //   DPhi[p] z    = p x z / 2 + C (p x (w x z) + w x (p x z)) + hat C (w.p) w x (w x z),
  //   D2Phi[p, q] z = C (p x (q x z) + q x (p x z)) + hat C (w.q) (p x (w x z) + w x (p x z))
  //                 + hat C (w.p) (q x (w x z) + w x (q x z))
  //                 + (hat C (p.q) + breve C (w.p)(w.q)) w x (w x z),
  // 18 cross products instead of the 36 of twelve 6-vector brackets.
  const Vec3 u = xi.head<3>(), w = xi.tail<3>();
  const Vec3 a = dxi.head<3>(), b = dxi.tail<3>();
  const Vec3 x = v.head<3>(), y = v.tail<3>();
  const double theta2 = w.squaredNorm();
  const double C = c.s2 - theta2 * c.s4, C_hat = -2.0 * c.s4, C_breve = -2.0 * c.s4_hat;
  const double wa = w.dot(a), wb = w.dot(b), wu = w.dot(u), ub = u.dot(b);
  // DPhi[b] x
  const Vec3 wx = w.cross(x), bx = b.cross(x);
  const Vec3 out_x = 0.5 * bx + C * (b.cross(wx) + w.cross(bx)) + (C_hat * wb) * w.cross(wx);
  // The y terms share w x y, b x y, w x (w x y), b x (w x y), w x (b x y).
  const Vec3 wy = w.cross(y), by = b.cross(y), ay = a.cross(y), uy = u.cross(y);
  const Vec3 wwy = w.cross(wy);
  const Vec3 b_wy_w_by = b.cross(wy) + w.cross(by);
  const Vec3 a_wy_w_ay = a.cross(wy) + w.cross(ay);
  const Vec3 u_wy_w_uy = u.cross(wy) + w.cross(uy);
  const Vec3 Db_y = 0.5 * by + C * b_wy_w_by + (C_hat * wb) * wwy;
  const Vec3 Da_y = 0.5 * ay + C * a_wy_w_ay + (C_hat * wa) * wwy;
  const Vec3 D2_y = C * (u.cross(by) + b.cross(uy)) + (C_hat * wb) * u_wy_w_uy +
                    (C_hat * wu) * b_wy_w_by + (C_hat * ub + C_breve * wu * wb) * wwy;
  Vec6 out;
  out.head<3>() = out_x + Da_y + D2_y;
  out.tail<3>() = Db_y;
  return out;
}

Mat6 TSE3Directional(const Vec6& xi, const Vec6& dxi) {
  const Mat6 T = TSE3(xi);
  return -T * TSE3InvDirectional(xi, dxi) * T;
}

Mat6 DTSE3InvT(const Vec6& xi, const Vec6& sigma) { return DTSE3InvT(xi, sigma, TInvSeries(xi)); }

Mat6 DTSE3InvT(const Vec6& xi, const Vec6& sigma, const TSeries& series) {
  // lie/se3.h evaluated in the blocks of the form-B series (see TSE3Inv):
  //   T^-T = [Dg^T 0; Q^T Dg^T],  Dg^T x = x - (w x x)/2 + e W^2 x,
  //   Q^T x = -(u x x)/2 + e C_2 x - 2 c s4 W^2 x,
  // e = s2 - theta^2 s4, c = w.u, W^2 x = w (w.x) - theta^2 x, C_2 x = u (w.x) + w (u.x) - 2 c x,
  // so with sigma = [f; m], T^-T sigma = [Dg^T f; Q^T f + Dg^T m]. Its derivatives in u and w,
  // with d s_k / dw = hat_s_k w^T and hat_e = (1/phi) de/dphi = hat_s2 - 2 s4 - theta^2 hat_s4:
  //   d/dw [Dg^T x]   = Skew(x)/2 + (W^2 x) hat_e w^T + e (w x^T + (w.x) I - 2 x w^T)
  //   d/du [Q^T f]    = Skew(f)/2 + e ((w.f) I + w f^T - 2 f w^T) - 2 s4 (W^2 f) w^T
  //   d/dw [Q^T f]    = (C_2 f) hat_e w^T + e (u f^T + (u.f) I - 2 f u^T)
  //                     - 2 (W^2 f) (s4 u^T + c hat_s4 w^T) - 2 c s4 (w f^T + (w.f) I - 2 f w^T).
  const Vec3 u = xi.head<3>(), w = xi.tail<3>();
  const Vec3 f = sigma.head<3>(), m = sigma.tail<3>();
  const double theta2 = w.squaredNorm();
  const TInvCoeffs s{series.s2, series.s4}, ds{series.s2_hat, series.s4_hat};
  const double e = s.s2 - theta2 * s.s4;
  const double e_hat = ds.s2 - 2.0 * s.s4 - theta2 * ds.s4;
  const double c = w.dot(u), wf = w.dot(f), wm = w.dot(m), uf = u.dot(f);
  const Vec3 W2f = wf * w - theta2 * f;
  const Vec3 C2f = wf * u + uf * w - (2.0 * c) * f;
  // w x^T + (w.x) I - 2 x w^T, the derivative of W^2 x in w.
  const auto dW2 = [&w](const Vec3& x, double wx) {
    Mat3 J = w * x.transpose() - 2.0 * x * w.transpose();
    J.diagonal().array() += wx;
    return J;
  };
  const auto dDg = [&](const Vec3& x, double wx) {
    const Vec3 W2x = wx * w - theta2 * x;
    Mat3 J = 0.5 * Skew(x) + e * dW2(x, wx);
    J.noalias() += (e_hat * W2x) * w.transpose();
    return J;
  };
  Mat6 D;
  D.topLeftCorner<3, 3>().setZero();
  D.topRightCorner<3, 3>() = dDg(f, wf);
  D.bottomLeftCorner<3, 3>() = 0.5 * Skew(f) + e * dW2(f, wf);
  D.bottomLeftCorner<3, 3>().noalias() -= (2.0 * s.s4 * W2f) * w.transpose();
  Mat3 J = dDg(m, wm) + e * (u * f.transpose() - 2.0 * f * u.transpose()) -
           (2.0 * c * s.s4) * dW2(f, wf);
  J.diagonal().array() += e * uf;
  J.noalias() += C2f * (e_hat * w).transpose();
  J.noalias() -= (2.0 * W2f) * (s.s4 * u + (c * ds.s4) * w).transpose();
  D.bottomRightCorner<3, 3>() = J;
  return D;
}

Mat3 FrameAlong(const Vec3& axis, const Vec3& up) {
  const Vec3 ex = axis.normalized();
  Vec3 ez = up - up.dot(ex) * ex;
  if (ez.norm() < 1e-8 * std::max(1.0, up.norm())) {
    // `up` parallel to the axis: take the world axis least aligned with it.
    Eigen::Index i = 0;
    ex.cwiseAbs().minCoeff(&i);
    const Vec3 alt = Vec3::Unit(i);
    ez = alt - alt.dot(ex) * ex;
  }
  ez.normalize();
  Mat3 R;
  R.col(0) = ex;
  R.col(1) = ez.cross(ex);
  R.col(2) = ez;
  return R;
}

}  // namespace screwfem
