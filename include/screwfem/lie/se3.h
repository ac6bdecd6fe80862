// SE(3) / se(3) toolkit (lie/se3.h).
//
// Conventions, fixed for the whole code base:
//  * A frame H = (R, x) maps frame coordinates to world coordinates: p_W = R p + x.
//  * 6-vectors are ordered translation first, rotation second: xi = [u; w].
//  * Velocities are body (left-invariant) velocities: dH/dt = H wedge(eta).
//  * Increments are right-trivialised: H <- H exp(wedge(dh)). Every tangent matrix in screwfem
//    is a derivative with respect to such a dh.
//  * T(xi) is the right tangent of exp: exp(xi + dxi) = exp(xi) exp(wedge(T(xi) dxi)) + O(dxi^2).
//
// Everything here is fixed-size, allocation-free and depends on Eigen only.
#pragma once

#include <Eigen/Dense>

namespace screwfem {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat4 = Eigen::Matrix4d;

// A rigid transformation (element of SE(3)).
struct SE3 {
  Mat3 R = Mat3::Identity();  // orientation of the frame in the world
  Vec3 x = Vec3::Zero();      // world position of the frame origin

  static SE3 Identity() { return SE3{}; }
  static SE3 Translation(const Vec3& p) { return SE3{Mat3::Identity(), p}; }

  SE3 operator*(const SE3& other) const { return SE3{R * other.R, R * other.x + x}; }
  SE3 Inverse() const {
    SE3 inv;
    inv.R = R.transpose();
    inv.x = -(inv.R * x);
    return inv;
  }
  // Maps a point given in this frame to the parent (world) frame.
  Vec3 Act(const Vec3& p) const { return R * p + x; }
  Mat4 Matrix() const;
};

// --- algebra operators (lie/se3.h) -------------------------------------------------------
// The small ones are inline: they sit in the inner loops of the element kernels.
inline Mat3 Skew(const Vec3& a) {  // Skew(a) b = a x b
  Mat3 S;
  S << 0.0, -a(2), a(1), a(2), 0.0, -a(0), -a(1), a(0), 0.0;
  return S;
}
Vec3 Unskew(const Mat3& A);  // inverse of Skew (uses the skew-symmetric part)
Mat4 Wedge(const Vec6& xi);  // 4x4 algebra matrix [Skew(w) u; 0 0]
Vec6 Vee(const Mat4& X);     // inverse of Wedge
Mat6 Ad(const SE3& H);       // H wedge(z) H^-1 = wedge(Ad(H) z)
// Ad(H)^T f = [R^T a; R^T (b - x x a)] for f = [a; b], without forming Ad(H).
inline Vec6 AdTransposeTimes(const SE3& H, const Vec6& f) {
  Vec6 r;
  r.head<3>().noalias() = H.R.transpose() * f.head<3>();
  r.tail<3>().noalias() = H.R.transpose() * (f.tail<3>() - H.x.cross(f.head<3>()));
  return r;
}
inline Mat6 ad(const Vec6& xi) {  // wedge(ad(xi) z) = [wedge(xi), wedge(z)]
  Mat6 A;
  const Mat3 W = Skew(xi.tail<3>());
  A.topLeftCorner<3, 3>() = W;
  A.topRightCorner<3, 3>() = Skew(xi.head<3>());
  A.bottomLeftCorner<3, 3>().setZero();
  A.bottomRightCorner<3, 3>() = W;
  return A;
}
inline Mat6 Star(const Vec6& y) {  // ad(xi)^T y = Star(y) xi,  y = [force; moment]
  Mat6 S;
  const Mat3 F = Skew(y.head<3>());
  S.topLeftCorner<3, 3>().setZero();
  S.topRightCorner<3, 3>() = F;
  S.bottomLeftCorner<3, 3>() = F;
  S.bottomRightCorner<3, 3>() = Skew(y.tail<3>());
  return S;
}
// ad(xi) y, the Lie bracket [xi, y] = [w x y_u + u x y_w; w x y_w], without forming ad(xi)
// (inline: it sits in the inner loops of the rod kernels).
inline Vec6 Bracket(const Vec6& xi, const Vec6& y) {
  const auto cross = [](double a0, double a1, double a2, double b0, double b1, double b2) {
    return Vec3(a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0);
  };
  Vec6 r;
  r.head<3>() =
      cross(xi(3), xi(4), xi(5), y(0), y(1), y(2)) + cross(xi(0), xi(1), xi(2), y(3), y(4), y(5));
  r.tail<3>() = cross(xi(3), xi(4), xi(5), y(3), y(4), y(5));
  return r;
}
// ad(xi)^T y = Star(y) xi = [y_u x w; y_u x u + y_w x w], without forming a matrix.
inline Vec6 CoBracket(const Vec6& xi, const Vec6& y) {
  const auto cross = [](double a0, double a1, double a2, double b0, double b1, double b2) {
    return Vec3(a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0);
  };
  Vec6 r;
  r.head<3>() = cross(y(0), y(1), y(2), xi(3), xi(4), xi(5));
  r.tail<3>() =
      cross(y(0), y(1), y(2), xi(0), xi(1), xi(2)) + cross(y(3), y(4), y(5), xi(3), xi(4), xi(5));
  return r;
}

// --- SO(3) -----------------------------------------------------------------------------------
Mat3 ExpSO3(const Vec3& w);
// Principal logarithm, |w| <= pi. Robust at 0 and near/at pi (uses atan2, never acos).
Vec3 LogSO3(const Mat3& R);
Mat3 TSO3(const Vec3& w);  // R(w)^T dR = Skew(TSO3(w) dw)
Mat3 TSO3Inv(const Vec3& w);

// --- SE(3) -----------------------------------------------------------------------------------
SE3 ExpSE3(const Vec6& xi);
Vec6 LogSE3(const SE3& H);     // principal branch (rotation angle <= pi)
Mat6 TSE3(const Vec6& xi);     // right tangent operator, lie/se3.h form B
Mat6 TSE3Inv(const Vec6& xi);  // singular at |w| = 2 pi k, k != 0
// D(xi, sigma) = d/dxi [ TSE3Inv(xi)^T sigma ]  (lie/se3.h).
Mat6 DTSE3InvT(const Vec6& xi, const Vec6& sigma);

// Directional derivative d/de TSE3Inv(xi + e dxi) at e = 0 (from form B: with A = ad(xi),
// A' = ad(dxi), d s_k = hat_s_k (w . dw)).
Mat6 TSE3InvDirectional(const Vec6& xi, const Vec6& dxi);
// The same derivative applied to a vector, [d/de TSE3Inv(xi + e dxi)] v, without forming the
// matrix (brackets only).
Vec6 TSE3InvDirectionalTimes(const Vec6& xi, const Vec6& dxi, const Vec6& v);
// Directional derivative of TSE3: -T (dT^-1) T.
Mat6 TSE3Directional(const Vec6& xi, const Vec6& dxi);

// The scalar coefficients of the series of T and T^-1 at one angle phi = |w| (lie/se3.h
// form B), for the kernels that evaluate several operators at the same xi: one call
// (one sincos of phi/2) instead of one set of trigonometric functions per operator.
struct TSeries {
  double t1, t2, t3, t4;  // T(xi) = I + t1 A + t2 A^2 + t3 A^3 + t4 A^4, A = ad(xi)
  double s2, s4;          // T^-1(xi) = I + A/2 + s2 A^2 + s4 A^4
  double s2_hat, s4_hat;  // (1/phi) d s_k / d phi
};
TSeries CalcTSeries(double phi);
// The operators above with the coefficients of |w| given (the same values to round-off).
Mat6 TSE3(const Vec6& xi, const TSeries& c);
Mat6 TSE3Inv(const Vec6& xi, const TSeries& c);
Mat6 DTSE3InvT(const Vec6& xi, const Vec6& sigma, const TSeries& c);
Vec6 TSE3InvDirectionalTimes(const Vec6& xi, const Vec6& dxi, const Vec6& v, const TSeries& c);
// *Ti = TSE3Inv(xi) and T[i] = TSE3(scales[i] xi), i < n, with c = CalcTSeries(|w|) and
// scaled[i] = CalcTSeries(scales[i] |w|): the powers of ad(xi) formed once (the Gauss points
// of a rod element), written in place.
void TSE3InvAndScaledTSE3(const Vec6& xi, const TSeries& c, int n, const double* scales,
                          const TSeries* scaled, Mat6* Ti, Mat6* T);

// Logarithm on a continuous branch (elements/rod.h): of all rotation vectors representing the
// rotation of H, w_k = (theta + 2 pi k) n, returns the one closest to w_ref, with the
// translation part recomputed on that branch. The caller must reject |w| near 2 pi.
Vec6 LogSE3Near(const SE3& H, const Vec3& w_ref);
// The same, with *series = CalcTSeries(|w|) of the result (used for its translation part).
Vec6 LogSE3Near(const SE3& H, const Vec3& w_ref, TSeries* series);
// The rotation part alone: LogSE3Near(H, w_ref).tail<3>() for H.R = R, bit for bit.
Vec3 LogSO3Near(const Mat3& R, const Vec3& w_ref);

// Scalar coefficient functions of phi = |w| (exposed for tests).
namespace lie_detail {
double A0(double phi);  // sin(phi)/phi
double A1(double phi);  // (1 - cos(phi))/phi^2
double A2(double phi);  // (phi - sin(phi))/phi^3
double C(double phi);   // (1 - (phi/2) cot(phi/2))/phi^2
}  // namespace lie_detail

// Rotation whose x axis is `axis` (normalised) and whose z axis is as close as possible to
// `up`; when `up` is parallel to `axis`, the world axis least aligned with `axis` stands in.
// The section-frame convention of rods (AddStraightRod, scene paths).
Mat3 FrameAlong(const Vec3& axis, const Vec3& up);

}  // namespace screwfem
