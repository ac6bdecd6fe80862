#include "screwfem/elements/rod.h"

#include <cmath>

namespace screwfem {

namespace {
// 3-point Gauss-Legendre rule on [0, 1].
constexpr double kGaussXi[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
constexpr double kGaussW[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
}  // namespace

Vec6 CalcRodRelativeMotion(const SE3& H_A, const SE3& H_B, const Vec3& w_ref) {
  return LogSE3Near(H_A.Inverse() * H_B, w_ref);
}

Mat6x12 CalcRodP(const Vec6& d) {
  Mat6x12 P;
  P.leftCols<6>() = -TSE3Inv(-d);
  P.rightCols<6>() = TSE3Inv(d);
  return P;
}

Mat6x12 CalcRodN(double xi, const Vec6& d) {
  const Mat6 T = xi * TSE3(xi * d);
  Mat6x12 N;
  N.leftCols<6>() = Ad(ExpSE3(-xi * d));
  N.leftCols<6>().noalias() -= T * TSE3Inv(-d);
  N.rightCols<6>().noalias() = T * TSE3Inv(d);
  return N;
}

void CalcRodInternal(const RodElement& element, const Section& section, const SE3& H_A,
                     const SE3& H_B, const Vec3& w_ref, RodInternal* out) {
  const double L = element.length;
  out->d = CalcRodRelativeMotion(H_A, H_B, w_ref);
  out->strain = (out->d - element.d0) / L;
  out->stress = section.stiffness.cwiseProduct(out->strain);
  out->energy = 0.5 * L * out->strain.dot(out->stress);
  const Mat6x12 P = CalcRodP(out->d);
  out->force.noalias() = P.transpose() * out->stress;
  // K_t = (1/L) P^T K P + [D(-d, sigma); D(d, sigma)] P   (method.md §2.4)
  const Mat6x12 KP = (section.stiffness / L).asDiagonal() * P;
  out->stiffness.noalias() = P.transpose() * KP;
  out->stiffness.topRows<6>().noalias() += DTSE3InvT(-out->d, out->stress) * P;
  out->stiffness.bottomRows<6>().noalias() += DTSE3InvT(out->d, out->stress) * P;
}

Mat6x12 CalcRodNDirectional(double xi, const Vec6& d, const Vec6& dd) {
  // N = [Ad(exp(-xi d)) - xi T(xi d) T^-1(-d),  xi T(xi d) T^-1(d)]   (method.md §2.5), and
  //   d Ad(exp(X)) = Ad(exp(X)) ad(T(X) dX) with X = -xi d,
  //   d [xi T(xi d)] = xi dT(xi d; xi dd),  d T^-1(+-d) = dT^-1(+-d; +-dd).
  const Mat6 T = xi * TSE3(xi * d);
  const Mat6 dT = xi * TSE3Directional(xi * d, xi * dd);
  Mat6x12 dN;
  dN.leftCols<6>() = Ad(ExpSE3(-xi * d)) * ad(TSE3(-xi * d) * (-xi * dd));
  dN.leftCols<6>().noalias() -= dT * TSE3Inv(-d);
  dN.leftCols<6>().noalias() -= T * TSE3InvDirectional(-d, -dd);
  dN.rightCols<6>().noalias() = dT * TSE3Inv(d);
  dN.rightCols<6>().noalias() += T * TSE3InvDirectional(d, dd);
  return dN;
}

void AddRodSectionLoad(double xi, double weight, const SE3& H_A, const Vec6& d, LoadFrame frame,
                       const Vec3& force, const Vec3& moment, Vec12* g, Mat12* tangent) {
  const Vec6 xd = xi * d;
  const Mat6 T_p = TSE3(xd);                 // T(xi d)
  const Mat6 Ad_m = Ad(ExpSE3(-xd));         // Ad(exp(-xi d))
  const Mat6 Ti_m = TSE3Inv(-d), Ti_p = TSE3Inv(d);
  Vec6 F;
  Mat6 S = Mat6::Zero();  // dF/d theta(xi)
  if (frame == LoadFrame::kWorld) {
    const Mat3 Rt = (H_A.R * ExpSO3(xd.tail<3>())).transpose();
    F << Rt * force, Rt * moment;
    S.topRightCorner<3, 3>() = Skew(F.head<3>());
    S.bottomRightCorner<3, 3>() = Skew(F.tail<3>());
  } else {
    F << force, moment;
  }
  // N^T F = [Ad_m^T F - T^-T(-d) z;  T^-T(d) z],  z = xi T(xi d)^T F.
  const Vec6 tF = T_p.transpose() * F;
  const Vec6 z = xi * tF;
  g->head<6>() += weight * (Ad_m.transpose() * F - Ti_m.transpose() * z);
  g->tail<6>() += weight * (Ti_p.transpose() * z);
  // Derivative of N^T F in d at fixed F (12 x 6), using D(x, y) = d/dx [T^-T(x) y] (§1.4) and
  // d/dx [T(x)^T F] = -T(x)^T D(x, T(x)^T F):
  //   dz/dd = -xi^2 T(xi d)^T D(xi d, T(xi d)^T F)
  //   d(Ad(exp(-xi d))^T F)/dd = -xi Star(Ad_m^T F) T(-xi d)
  const Mat6 dz = -(xi * xi) * (T_p.transpose() * DTSE3InvT(xd, tF));
  Eigen::Matrix<double, 12, 6> G;
  G.topRows<6>() = -xi * (Star(Ad_m.transpose() * F) * TSE3(-xd)) + DTSE3InvT(-d, z) -
                   Ti_m.transpose() * dz;
  G.bottomRows<6>() = DTSE3InvT(d, z) + Ti_p.transpose() * dz;
  Mat6x12 N;
  N.leftCols<6>() = Ad_m - xi * T_p * Ti_m;
  N.rightCols<6>() = xi * T_p * Ti_p;
  tangent->noalias() -= weight * (G * CalcRodP(d));
  if (frame == LoadFrame::kWorld) tangent->noalias() -= weight * (N.transpose() * S * N);
}

void CalcRodDistributedDeadForce(const RodElement& element, const SE3& H_A, const Vec6& d,
                                 const Vec3& f_w, Vec12* g, Mat12* tangent) {
  g->setZero();
  tangent->setZero();
  for (int i = 0; i < 3; ++i)
    AddRodSectionLoad(kGaussXi[i], element.length * kGaussW[i], H_A, d, LoadFrame::kWorld, f_w,
                      Vec3::Zero(), g, tangent);
}

}  // namespace screwfem
