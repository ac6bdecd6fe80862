#include "screwfem/elements/rod.h"

#include <cmath>

namespace screwfem {

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

namespace {
// s X Y for X, Y of the block form [A B; 0 A] of T and T^-1 (method.md §1.3):
// s [A_x A_y, A_x B_y + B_x A_y; 0, A_x A_y], three 3x3 products instead of a 6x6 one.
Mat6 ScaledTangentProduct(double s, const Mat6& X, const Mat6& Y) {
  const Mat3 Ax = s * X.topLeftCorner<3, 3>();
  const Mat3 Bx = s * X.topRightCorner<3, 3>();
  Mat6 Z;
  Z.topLeftCorner<3, 3>().noalias() = Ax * Y.topLeftCorner<3, 3>();
  Z.topRightCorner<3, 3>().noalias() = Ax * Y.topRightCorner<3, 3>();
  Z.topRightCorner<3, 3>().noalias() += Bx * Y.topLeftCorner<3, 3>();
  Z.bottomLeftCorner<3, 3>().setZero();
  Z.bottomRightCorner<3, 3>() = Z.topLeftCorner<3, 3>();
  return Z;
}
}  // namespace

void CalcRodGeometry(const Vec6& d, bool gauss_points, bool tangents, RodGeometry* out) {
  out->d = d;
  out->Ti = TSE3Inv(d);
  // P = [-T^-1(-d)  T^-1(d)] with T^-1(-d) = T^-1(d) - ad(d) (method.md §2.3).
  out->P.leftCols<6>() = ad(d) - out->Ti;
  out->P.rightCols<6>() = out->Ti;
  out->gauss_points = gauss_points || tangents;
  out->tangents = tangents;
  if (!out->gauss_points) return;
  for (int i = 0; i < kRodGaussPoints; ++i) {
    const double xi = kRodGaussXi[i];
    out->T[i] = TSE3(xi * d);
    if (tangents) out->NB[i] = ScaledTangentProduct(xi, out->T[i], out->Ti);
  }
}

void CalcRodInternal(const RodElement& element, const Section& section, const RodGeometry& geometry,
                     bool tangent, RodInternal* out) {
  const double L = element.length;
  const Mat6x12& P = geometry.P;
  out->d = geometry.d;
  out->strain = (out->d - element.d0) / L;
  out->stress = section.stiffness.cwiseProduct(out->strain);
  out->energy = 0.5 * L * out->strain.dot(out->stress);
  out->force.noalias() = P.transpose() * out->stress;
  if (!tangent) return;
  // K_t = (1/L) P^T K P + [D(-d, sigma); D(d, sigma)] P   (method.md §2.4), with
  // D(-d, sigma) = Star(sigma) - D(d, sigma) (derivative of T^-T(-d) sigma =
  // T^-T(d) sigma - Star(sigma) d), as one product Y P, Y = (1/L) P^T K + [D(-d); D(d)].
  const Mat6 D = DTSE3InvT(out->d, out->stress);
  Eigen::Matrix<double, 12, 6> Y = P.transpose() * (section.stiffness / L).asDiagonal();
  Y.topRows<6>() += Star(out->stress) - D;
  Y.bottomRows<6>() += D;
  out->stiffness.noalias() = Y.lazyProduct(P);
}

void CalcRodInternal(const RodElement& element, const Section& section, const SE3& H_A,
                     const SE3& H_B, const Vec3& w_ref, RodInternal* out) {
  RodGeometry geometry;
  CalcRodGeometry(CalcRodRelativeMotion(H_A, H_B, w_ref), false, false, &geometry);
  CalcRodInternal(element, section, geometry, true, out);
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

void AddRodDistributedDeadForce(const RodElement& element, const RodGeometry& geometry,
                                const SE3& H_A, const Vec3& f_w, Vec12* g, Mat12* tangent) {
  // g = L sum_i w_i N_i^T F_i, F_i = [R_i^T f_w; 0] with R_i the section rotation at xi_i
  // (method.md §2.6). With N = [I - N_B, N_B] and N_B^T F = T^-T(d) z, z = xi T(xi d)^T F:
  //   g_B = T^-T(d) Z,  g_A = sum w_i F_i - g_B,  Z = L sum_i w_i z_i.
  // Tangent of -g (as AddRodSectionLoad, summed over the points): the derivative of N^T F at
  // fixed F is [-G_B; G_B] (the halves of N sum to I for every d), with
  //   sum_i w_i G_B,i = D(d, Z) + T^-T(d) S,  S = L sum_i w_i dz_i/dd,
  //   dz_i/dd = -xi_i^2 T_i^T D(xi_i d, T_i^T F_i),
  // plus the rotation of F with the section, -L sum_i w_i N_i^T [0 Skew(f_i); 0 0] N_i.
  const double L = element.length;
  const Vec3 f_A = H_A.R.transpose() * f_w;  // node-A components of the force
  Vec3 F_sum = Vec3::Zero();
  Vec6 Z = Vec6::Zero();
  Mat6 S = Mat6::Zero();
  // Sums of the rotation term: w Skew(f_i) [N_B]_rot, w [N_B]_trans^T Skew(f_i) and their product.
  Eigen::Matrix<double, 3, 6> SkB = Eigen::Matrix<double, 3, 6>::Zero();
  Eigen::Matrix<double, 6, 3> BtSk = Eigen::Matrix<double, 6, 3>::Zero();
  Mat6 BtSkB = Mat6::Zero();
  Mat3 Sk_sum = Mat3::Zero();
  for (int i = 0; i < kRodGaussPoints; ++i) {
    const double xi = kRodGaussXi[i], w = L * kRodGaussW[i];
    const Mat6& T = geometry.T[i];
    const Vec3 f = ExpSO3(xi * geometry.d.tail<3>()).transpose() * f_A;  // section frame
    F_sum += w * f;
    Vec6 F;
    F << f, Vec3::Zero();
    const Vec6 tF = T.topRows<3>().transpose() * f;  // T^T F
    Z += (w * xi) * tF;
    if (!tangent) continue;
    S.noalias() -= (w * xi * xi) * (T.transpose() * DTSE3InvT(xi * geometry.d, tF));
    const Mat3 Sk = w * Skew(f);
    const Mat6& B = geometry.NB[i];
    const Eigen::Matrix<double, 3, 6> SkBi = Sk * B.bottomRows<3>();
    Sk_sum += Sk;
    SkB += SkBi;
    BtSk.noalias() += B.topRows<3>().transpose() * Sk;
    BtSkB.noalias() += B.topRows<3>().transpose() * SkBi;
  }
  const Vec6 g_B = geometry.Ti.transpose() * Z;
  g->head<3>() += F_sum - g_B.head<3>();
  g->segment<3>(3) -= g_B.tail<3>();
  g->tail<6>() += g_B;
  if (!tangent) return;
  Mat6 G_B = DTSE3InvT(geometry.d, Z);
  G_B.noalias() += geometry.Ti.transpose() * S;
  const Mat6x12 GP = G_B * geometry.P;
  tangent->topRows<6>() += GP;
  tangent->bottomRows<6>() -= GP;
  // sum w N^T H N, N = [I - B, B], H = [0 Sk; 0 0]:
  //   AA = H - HB - B^T H + B^T H B,  AB = HB - B^T H B,  BA = B^T H - B^T H B,  BB = B^T H B,
  // HB = [Sk B_rot; 0], B^T H = [0  B_trans^T Sk], B^T H B = B_trans^T Sk B_rot.
  Mat6 HB = Mat6::Zero(), BtH = Mat6::Zero(), H = Mat6::Zero();
  HB.topRows<3>() = SkB;
  BtH.rightCols<3>() = BtSk;
  H.topRightCorner<3, 3>() = Sk_sum;
  tangent->topLeftCorner<6, 6>() -= H - HB - BtH + BtSkB;
  tangent->topRightCorner<6, 6>() -= HB - BtSkB;
  tangent->bottomLeftCorner<6, 6>() -= BtH - BtSkB;
  tangent->bottomRightCorner<6, 6>() -= BtSkB;
}

void CalcRodDistributedDeadForce(const RodElement& element, const SE3& H_A, const Vec6& d,
                                 const Vec3& f_w, Vec12* g, Mat12* tangent) {
  RodGeometry geometry;
  CalcRodGeometry(d, true, true, &geometry);
  g->setZero();
  tangent->setZero();
  AddRodDistributedDeadForce(element, geometry, H_A, f_w, g, tangent);
}

}  // namespace screwfem
