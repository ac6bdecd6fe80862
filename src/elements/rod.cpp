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

void CalcRodDistributedDeadForce(const RodElement& element, const SE3& H_A, const Vec6& d,
                                 const Vec3& f_w, Vec12* g, Mat12* tangent) {
  const double L = element.length;
  g->setZero();
  tangent->setZero();
  for (int i = 0; i < 3; ++i) {
    const double xi = kGaussXi[i], w = L * kGaussW[i];
    const SE3 H = H_A * ExpSE3(xi * d);
    const Vec3 f = H.R.transpose() * f_w;  // load in the section frame at xi
    g->segment<3>(0) += w * (1.0 - xi) * f;
    g->segment<3>(6) += w * xi * f;
    // d f / d theta(xi) = Skew(f); theta(xi) = rotational rows of N(xi, d) [dh_A; dh_B].
    const Eigen::Matrix<double, 3, 12> dF = Skew(f) * CalcRodN(xi, d).bottomRows<3>();
    tangent->middleRows<3>(0) -= w * (1.0 - xi) * dF;
    tangent->middleRows<3>(6) -= w * xi * dF;
  }
}

}  // namespace screwfem
