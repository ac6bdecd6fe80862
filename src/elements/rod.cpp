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

void CalcRodGaussVelocities(const Vec6& d, const Vec12& eta_ab, Vec6 (&eta)[kRodGaussPoints],
                            SE3 (*G)[kRodGaussPoints]) {
  // The tangent operators applied to vectors through the powers of A = ad(d) (lie/se3.h,
  // TSeries), not formed as 6 x 6 matrices: a quarter of the instructions of the energy row.
  const double phi = d.tail<3>().norm();
  const TSeries c = CalcTSeries(phi);
  const Vec6 eta_a = eta_ab.head<6>();
  // d_dot = P eta_AB = T^-1(d) z + ad(d) eta_A, z = eta_B - eta_A (T^-1(-d) = T^-1(d) - ad(d)),
  // T^-1(d) = I + A / 2 + s2 A^2 + s4 A^4.
  const Vec6 z = eta_ab.tail<6>() - eta_a;
  const Vec6 z1 = Bracket(d, z);
  const Vec6 z2 = Bracket(d, z1);
  const Vec6 z4 = Bracket(d, Bracket(d, z2));
  Vec6 d_dot = Bracket(d, eta_a);
  d_dot += z + 0.5 * z1 + c.s2 * z2 + c.s4 * z4;
  // T(xi d) d_dot = d_dot + t1 xi A d_dot + t2 xi^2 A^2 d_dot + t3 xi^3 A^3 d_dot
  //                 + t4 xi^4 A^4 d_dot, the series at xi |w|.
  Vec6 y[5];
  y[0] = d_dot;
  for (int k = 1; k < 5; ++k) y[k] = Bracket(d, y[k - 1]);
  for (int i = 0; i < kRodGaussPoints; ++i) {
    const double xi = kRodGaussXi[i];
    const TSeries s = CalcTSeries(xi * phi);
    const SE3 g = ExpSE3(xi * d);
    // Ad(g^-1) eta_A = [R^T (u - x x w); R^T w] (translation first).
    eta[i].head<3>().noalias() = g.R.transpose() * (eta_a.head<3>() - g.x.cross(eta_a.tail<3>()));
    eta[i].tail<3>().noalias() = g.R.transpose() * eta_a.tail<3>();
    const double x2 = xi * xi;
    eta[i] += xi * (y[0] + (s.t1 * xi) * y[1] + (s.t2 * x2) * y[2] + (s.t3 * x2 * xi) * y[3] +
                    (s.t4 * x2 * x2) * y[4]);
    if (G) (*G)[i] = g;
  }
}

namespace {
// s X Y for X, Y of the block form [A B; 0 A] of T and T^-1 (lie/se3.h):
// s [A_x A_y, A_x B_y + B_x A_y; 0, A_x A_y], three 3x3 products instead of a 6x6 one.
void ScaledTangentProduct(double s, const Mat6& X, const Mat6& Y, Mat6* out) {
  const Mat3 Ax = s * X.topLeftCorner<3, 3>();
  const Mat3 Bx = s * X.topRightCorner<3, 3>();
  Mat6& Z = *out;
  Z.topLeftCorner<3, 3>().noalias() = Ax * Y.topLeftCorner<3, 3>();
  Z.topRightCorner<3, 3>().noalias() = Ax * Y.topRightCorner<3, 3>();
  Z.topRightCorner<3, 3>().noalias() += Bx * Y.topLeftCorner<3, 3>();
  Z.bottomLeftCorner<3, 3>().setZero();
  Z.bottomRightCorner<3, 3>() = Z.topLeftCorner<3, 3>();
}

// From out->d and out->series: T^-1(d), P and the Gauss-point operators.
void CompleteRodGeometry(bool gauss_points, bool tangents, RodGeometry* out) {
  const Vec6& d = out->d;
  const double phi = d.tail<3>().norm();
  out->gauss_points = gauss_points || tangents;
  out->tangents = tangents;
  int n = 0;
  if (out->gauss_points) {
    n = kRodGaussPoints;
    for (int i = 0; i < n; ++i) out->series_gp[i] = CalcTSeries(kRodGaussXi[i] * phi);
  }
  TSE3InvAndScaledTSE3(d, out->series, n, kRodGaussXi, out->series_gp, &out->Ti, out->T);
  // P = [-T^-1(-d)  T^-1(d)] with T^-1(-d) = T^-1(d) - ad(d) (elements/rod.h).
  out->P.leftCols<6>() = ad(d) - out->Ti;
  out->P.rightCols<6>() = out->Ti;
  if (tangents)
    for (int i = 0; i < n; ++i)
      ScaledTangentProduct(kRodGaussXi[i], out->T[i], out->Ti, &out->NB[i]);
}

}  // namespace

void CalcRodGeometry(const Vec6& d, bool gauss_points, bool tangents, RodGeometry* out) {
  out->series = CalcTSeries(d.tail<3>().norm());
  out->d = d;
  CompleteRodGeometry(gauss_points, tangents, out);
}

void CalcRodGeometry(const SE3& H_A, const SE3& H_B, const Vec3& w_ref, bool gauss_points,
                     bool tangents, RodGeometry* out) {
  out->d = LogSE3Near(H_A.Inverse() * H_B, w_ref, &out->series);
  CompleteRodGeometry(gauss_points, tangents, out);
}

void CalcRodLaw(const RodElement& element, const Section& section, const Vec6& d,
                const RodActuation* actuation, bool energy, RodLaw* out) {
  const double L = element.length;
  out->strain = (d - element.d0) / L;
  out->stress = section.stiffness.cwiseProduct(out->strain);
  if (actuation == nullptr) {
    out->elastic_stress = out->stress;
    if (energy) out->energy = 0.5 * L * out->strain.dot(out->stress);
    return;
  }
  const Vec6 elastic = out->strain - actuation->rest_strain;
  out->elastic_stress = section.stiffness.cwiseProduct(elastic);
  out->stress -= section.stiffness.cwiseProduct(actuation->rest_strain) + actuation->active_stress;
  if (energy)
    out->energy =
        0.5 * L * elastic.dot(out->elastic_stress) - L * out->strain.dot(actuation->active_stress);
}

void CalcRodInternal(const RodElement& element, const Section& section, const RodGeometry& geometry,
                     bool tangent, RodInternal* out, const RodActuation* actuation) {
  const double L = element.length;
  const Mat6x12& P = geometry.P;
  out->d = geometry.d;
  RodLaw law;
  CalcRodLaw(element, section, out->d, actuation, true, &law);
  out->strain = law.strain;
  out->elastic_stress = law.elastic_stress;
  out->stress = law.stress;
  out->energy = law.energy;
  out->force.noalias() = P.transpose() * out->stress;
  if (!tangent) return;
  // K_t = (1/L) P^T K P + [D(-d, sigma); D(d, sigma)] P   (elements/rod.h), with
  // D(-d, sigma) = Star(sigma) - D(d, sigma) (derivative of T^-T(-d) sigma =
  // T^-T(d) sigma - Star(sigma) d), as one product Y P, Y = (1/L) P^T K + [D(-d); D(d)].
  const Mat6 D = DTSE3InvT(out->d, out->stress, geometry.series);
  Eigen::Matrix<double, 12, 6> Y = P.transpose() * (section.stiffness / L).asDiagonal();
  Y.topRows<6>() += Star(out->stress) - D;
  Y.bottomRows<6>() += D;
  out->stiffness.noalias() = Y.lazyProduct(P);
}

void CalcRodInternal(const RodElement& element, const Section& section, const SE3& H_A,
                     const SE3& H_B, const Vec3& w_ref, RodInternal* out,
                     const RodActuation* actuation) {
  RodGeometry geometry;
  CalcRodGeometry(CalcRodRelativeMotion(H_A, H_B, w_ref), false, false, &geometry);
  CalcRodInternal(element, section, geometry, true, out, actuation);
}

Mat6x12 CalcRodNDirectional(double xi, const Vec6& d, const Vec6& dd) {
  // N = [Ad(exp(-xi d)) - xi T(xi d) T^-1(-d),  xi T(xi d) T^-1(d)]   (docs/numerics.md, "Rod inertia"), and
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
  const Mat6 T_p = TSE3(xd);          // T(xi d)
  const Mat6 Ad_m = Ad(ExpSE3(-xd));  // Ad(exp(-xi d))
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
  // Derivative of N^T F in d at fixed F (12 x 6), using D(x, y) = d/dx [T^-T(x) y]
  // (docs/theory.md §1.4) and
  // d/dx [T(x)^T F] = -T(x)^T D(x, T(x)^T F):
  //   dz/dd = -xi^2 T(xi d)^T D(xi d, T(xi d)^T F)
  //   d(Ad(exp(-xi d))^T F)/dd = -xi Star(Ad_m^T F) T(-xi d)
  const Mat6 dz = -(xi * xi) * (T_p.transpose() * DTSE3InvT(xd, tF));
  Eigen::Matrix<double, 12, 6> G;
  G.topRows<6>() =
      -xi * (Star(Ad_m.transpose() * F) * TSE3(-xd)) + DTSE3InvT(-d, z) - Ti_m.transpose() * dz;
  G.bottomRows<6>() = DTSE3InvT(d, z) + Ti_p.transpose() * dz;
  Mat6x12 N;
  N.leftCols<6>() = Ad_m - xi * T_p * Ti_m;
  N.rightCols<6>() = xi * T_p * Ti_p;
  tangent->noalias() -= weight * (G * CalcRodP(d));
  if (frame == LoadFrame::kWorld) tangent->noalias() -= weight * (N.transpose() * S * N);
}

Eigen::Matrix<double, 12, 6> CalcRodNTransposeDerivative(double xi, const Vec6& d, const Vec6& F) {
  // As in AddRodSectionLoad: N^T F = [Ad_m^T F - T^-T(-d) z;  T^-T(d) z],  z = xi T(xi d)^T F.
  const Vec6 xd = xi * d;
  const Mat6 T_p = TSE3(xd);
  const Mat6 Ad_m = Ad(ExpSE3(-xd));
  const Vec6 tF = T_p.transpose() * F;
  const Vec6 z = xi * tF;
  const Mat6 dz = -(xi * xi) * (T_p.transpose() * DTSE3InvT(xd, tF));
  Eigen::Matrix<double, 12, 6> G;
  G.topRows<6>() = -xi * (Star(Ad_m.transpose() * F) * TSE3(-xd)) + DTSE3InvT(-d, z) -
                   TSE3Inv(-d).transpose() * dz;
  G.bottomRows<6>() = DTSE3InvT(d, z) + TSE3Inv(d).transpose() * dz;
  return G;
}

namespace {
// J(v) = I + A1 V + A2 V^2 (V = Skew(v), phi = |v|): the translation of exp(X) is J(w_X) u_X.
// With hat = (1/phi) d/dphi and breve = (1/phi) d/dphi of hat (A0 = sin(phi)/phi):
//   hat A0 = (cos - A0)/phi^2, hat A1 = (A0 - 2 A1)/phi^2, hat A2 = (A1 - 3 A2)/phi^2,
//   breve A1 = (hat A0 - 4 hat A1)/phi^2, breve A2 = (hat A1 - 5 hat A2)/phi^2.
// Each step divides a difference by phi^2, so below phi = 1 the Taylor series are used.
struct JCoeffs {
  double a1, a2, a1h, a2h, a1b, a2b;
};

// sum_j c_j x^j with c_j = sign * num(j) / (2 j + first)!, for the series of JCoeffs.
struct JSeries {
  static constexpr int kTerms = 10;
  double a1[kTerms], a2[kTerms], a1h[kTerms], a2h[kTerms], a1b[kTerms], a2b[kTerms];
  constexpr JSeries() : a1(), a2(), a1h(), a2h(), a1b(), a2b() {
    // A1 = sum (-1)^k x^k / (2k+2)!, A2 = sum (-1)^k x^k / (2k+3)!, and their term-wise
    // derivatives: hat (sum c_k x^k) = sum 2 k c_k x^(k-1), breve = sum 2k (2k - 2) c_k x^(k-2).
    double f[2 * kTerms + 8] = {1.0};
    for (int i = 1; i < 2 * kTerms + 8; ++i) f[i] = f[i - 1] * i;
    for (int j = 0; j < kTerms; ++j) {
      const double sj = j % 2 == 0 ? 1.0 : -1.0;
      a1[j] = sj / f[2 * j + 2];
      a2[j] = sj / f[2 * j + 3];
      a1h[j] = -sj * 2.0 * (j + 1) / f[2 * j + 4];
      a2h[j] = -sj * 2.0 * (j + 1) / f[2 * j + 5];
      a1b[j] = sj * 4.0 * (j + 2) * (j + 1) / f[2 * j + 6];
      a2b[j] = sj * 4.0 * (j + 2) * (j + 1) / f[2 * j + 7];
    }
  }
};
constexpr JSeries kJSeries;

double Horner(const double (&c)[JSeries::kTerms], double x) {
  double r = c[JSeries::kTerms - 1];
  for (int k = JSeries::kTerms - 1; k-- > 0;) r = r * x + c[k];
  return r;
}

// The breve (second-derivative) coefficients only with `second` (zero otherwise).
JCoeffs JCoefficients(double phi, bool second) {
  const double x = phi * phi;
  if (phi < 1.0) {
    const JSeries& s = kJSeries;
    return {Horner(s.a1, x),
            Horner(s.a2, x),
            Horner(s.a1h, x),
            Horner(s.a2h, x),
            second ? Horner(s.a1b, x) : 0.0,
            second ? Horner(s.a2b, x) : 0.0};
  }
  const double sn = std::sin(phi), cs = std::cos(phi);
  const double a0 = sn / phi, a1 = (1.0 - cs) / x, a2 = (phi - sn) / (x * phi);
  const double a0h = (cs - a0) / x, a1h = (a0 - 2.0 * a1) / x, a2h = (a1 - 3.0 * a2) / x;
  return {a1, a2, a1h, a2h, (a0h - 4.0 * a1h) / x, (a1h - 5.0 * a2h) / x};
}

// The dead-force potential of one element and its derivatives (see AddRodDistributedDeadForce).
struct DeadForcePieces {
  Vec3 f, pbar;
  Vec6 s;                  // [Jbar^T f; Pw^T f]
  Mat3 Jbar, Pw, Qw, Hww;  // with `tangent` only
};

DeadForcePieces CalcDeadForcePieces(const Vec6& d, const SE3& H_A, const Vec3& f_w, bool tangent) {
  // At the Gauss points v = xi w, so every sum over them is a few scalar sums of
  // coefficient functions of xi_i |w| times fixed vectors and matrices of u, w, f. With
  // wx_i = w_i xi_i and S0 = sum wx_i (= 1/2):
  //   A = sum wx xi A1, D = sum wx xi^2 A2, B = sum wx xi^3 hat A1, Cc = sum wx xi^4 hat A2,
  //   G = sum wx xi^5 breve A1, Hh = sum wx xi^6 breve A2,
  // and, from J(v) x = x + A1 v x x + A2 v x (v x x), h(v) = f . J(v) u = f.u + A1 v.m + A2 b
  // (m = u x f, b = (v.f)(v.u) - |v|^2 f.u = xi^2 b0, grad b = xi gb0):
  //   pbar = S0 u + A w x u + D w x (w x u),    Jbar^T f = S0 f - A w x f + D w x (w x f),
  //   Pw^T f = A m + D gb0 + (B w.m + Cc b0) w,
  //   Jbar = (S0 - D |w|^2) I + A Skew(w) + D w w^T,
  //   Pw = -A Skew(u) + (B w x u + Cc w x (w x u)) w^T + D (w u^T + (w.u) I - 2 u w^T),
  //   Qw =  A Skew(f) + (-B w x f + Cc w x (w x f)) w^T + D (w f^T + (w.f) I - 2 f w^T),
  //   Hww = c w^T + w c^T + (G w.m + Hh b0) w w^T + D (f u^T + u f^T)
  //         + (B w.m + Cc b0 - 2 D f.u) I,   c = B m + Cc gb0.
  DeadForcePieces p;
  const Vec3 u = d.head<3>(), w = d.tail<3>();
  const Vec3 f = H_A.R.transpose() * f_w;
  p.f = f;
  const double w_norm = w.norm();
  double S0 = 0.0, A = 0.0, D = 0.0, B = 0.0, Cc = 0.0, G = 0.0, Hh = 0.0;
  for (int i = 0; i < kRodGaussPoints; ++i) {
    const double xi = kRodGaussXi[i], wx = kRodGaussW[i] * xi;
    const JCoeffs k = JCoefficients(xi * w_norm, tangent);
    const double x2 = xi * xi, x3 = x2 * xi, x4 = x2 * x2;
    S0 += wx;
    A += wx * xi * k.a1;
    D += wx * x2 * k.a2;
    B += wx * x3 * k.a1h;
    Cc += wx * x4 * k.a2h;
    G += wx * x4 * xi * k.a1b;
    Hh += wx * x4 * x2 * k.a2b;
  }
  const double theta2 = w.squaredNorm();
  const double wu = w.dot(u), wf = w.dot(f), fu = f.dot(u);
  const Vec3 m = u.cross(f);
  const double wm = w.dot(m);
  const Vec3 wxu = w.cross(u), wxf = w.cross(f);
  const Vec3 wwu = w.cross(wxu), wwf = w.cross(wxf);
  const double b0 = wf * wu - theta2 * fu;
  const Vec3 gb0 = wu * f + wf * u - (2.0 * fu) * w;
  p.pbar = S0 * u + A * wxu + D * wwu;
  p.s.head<3>() = S0 * f - A * wxf + D * wwf;
  p.s.tail<3>() = A * m + D * gb0 + (B * wm + Cc * b0) * w;
  if (!tangent) return p;
  p.Jbar = A * Skew(w);
  p.Jbar.noalias() += D * (w * w.transpose());
  p.Jbar.diagonal().array() += S0 - D * theta2;
  const auto dw2 = [&w](const Vec3& x, double w_x) {  // w x^T + (w.x) I - 2 x w^T
    Mat3 J = w * x.transpose() - 2.0 * x * w.transpose();
    J.diagonal().array() += w_x;
    return J;
  };
  p.Pw = -A * Skew(u) + D * dw2(u, wu);
  p.Pw.noalias() += (B * wxu + Cc * wwu) * w.transpose();
  p.Qw = A * Skew(f) + D * dw2(f, wf);
  p.Qw.noalias() += (Cc * wwf - B * wxf) * w.transpose();
  const Vec3 c = B * m + Cc * gb0;
  p.Hww = c * w.transpose();
  p.Hww += p.Hww.transpose().eval();
  p.Hww.noalias() += (G * wm + Hh * b0) * (w * w.transpose());
  p.Hww.noalias() += D * (f * u.transpose() + u * f.transpose());
  p.Hww.diagonal().array() += B * wm + Cc * b0 - 2.0 * D * fu;
  return p;
}

// The d-Hessian of f . pbar, [0 Qw; Qw^T Hww].
Mat6 DeadForceHessian(const DeadForcePieces& p) {
  Mat6 Hs;
  Hs.topLeftCorner<3, 3>().setZero();
  Hs.topRightCorner<3, 3>() = p.Qw;
  Hs.bottomLeftCorner<3, 3>() = p.Qw.transpose();
  Hs.bottomRightCorner<3, 3>() = p.Hww;
  return Hs;
}

// -L times the tangent columns of node A's rotation (12 x 3, see AddRodDistributedDeadForce):
// P^T S_f Skew(f) + E_A [Skew(f); Skew(pbar) Skew(f)].
Eigen::Matrix<double, 12, 3> DeadForceRotationColumns(const DeadForcePieces& p, const Mat6x12& P) {
  const Mat3 Sf = Skew(p.f);
  Eigen::Matrix<double, 6, 3> SfSk;
  SfSk.topRows<3>().noalias() = p.Jbar.transpose() * Sf;
  SfSk.bottomRows<3>().noalias() = p.Pw.transpose() * Sf;
  Eigen::Matrix<double, 12, 3> C = P.transpose() * SfSk;
  C.topRows<3>() += Sf;
  C.middleRows<3>(3).noalias() += Skew(p.pbar) * Sf;
  return C;
}

// Rows 3-5 (node A's moment) of the d-part of the tangent: -Skew(f) [Jbar Pw].
Eigen::Matrix<double, 3, 6> DeadForceMomentRows(const DeadForcePieces& p) {
  const Mat3 Sf = Skew(p.f);
  Eigen::Matrix<double, 3, 6> R;
  R.leftCols<3>().noalias() = -Sf * p.Jbar;
  R.rightCols<3>().noalias() = -Sf * p.Pw;
  return R;
}

void AddDeadForce(double L, const DeadForcePieces& p, const Mat6x12& P, Vec12* g) {
  g->head<3>() += L * p.f;
  g->segment<3>(3) += L * p.pbar.cross(p.f);
  g->noalias() += L * (P.transpose() * p.s);
}
}  // namespace

void AddRodDistributedDeadForce(const RodElement& element, const RodGeometry& geometry,
                                const SE3& H_A, const Vec3& f_w, Vec12* g, Mat12* tangent) {
  // A dead force density f_w on the centreline x(xi) = x_A + R_A p(xi d), p(X) = J(w_X) u_X the
  // translation of exp(X), has the potential V = -L sum_i w_i f_w . x(xi_i) (3-point Gauss).
  // With f = R_A^T f_w (node-A components) and d = [u; w]:
  //   V = -L f_w . x_A - L f . pbar(d),   pbar = sum_i w_i xi_i J(xi_i w) u,
  // so g = -dV/dh (the same as L sum_i w_i N_i^T [R_i^T f_w; 0] at the same points) is
  //   g = L [f; pbar x f; 0] + L P^T s,   s = d(f . pbar)/dd = [Jbar^T f; Pw^T f],
  // Jbar = d pbar / du = sum w_i xi_i J(xi_i w), Pw = d pbar / dw. f . pbar is linear in u, so
  // its Hessian in d is Hs = [0 Qw; Qw^T Hww], Qw = d(Jbar^T f)/dw, Hww = d^2(f . pbar)/dw^2.
  // The tangent of -g, with delta f = Skew(f) delta theta_A and delta d = P delta h:
  //   -L ([D(-d, s); D(d, s)] + P^T Hs + E_A [0; -Skew(f) [Jbar Pw]]) P
  //   -L (P^T S_f Skew(f) + E_A [Skew(f); Skew(pbar) Skew(f)]) Theta_A,
  // S_f = [Jbar^T; Pw^T] (s = S_f f), E_A the rows of node A, Theta_A its rotation columns,
  // and D(-d, s) = Star(s) - D(d, s) as in CalcRodInternal.
  const double L = element.length;
  const Vec6& d = geometry.d;
  const Mat6x12& P = geometry.P;
  const DeadForcePieces p = CalcDeadForcePieces(d, H_A, f_w, tangent != nullptr);
  AddDeadForce(L, p, P, g);
  if (!tangent) return;
  const Mat6 D = DTSE3InvT(d, p.s, geometry.series);
  Eigen::Matrix<double, 12, 6> Y = P.transpose() * DeadForceHessian(p);
  Y.topRows<6>() += Star(p.s) - D;
  Y.bottomRows<6>() += D;
  Y.middleRows<3>(3) += DeadForceMomentRows(p);
  tangent->noalias() -= L * Y.lazyProduct(P);
  tangent->middleCols<3>(3) -= L * DeadForceRotationColumns(p, P);
}

void CalcRodConservative(const RodElement& element, const Section& section,
                         const RodGeometry& geometry, const SE3& H_A, const Vec3& f_w,
                         const Mat6* T_A, const Mat6* T_B, Vec12* force, Mat12* stiffness,
                         const RodActuation* actuation) {
  // force = P^T sigma - g_dead = P^T (sigma - L s) - L [f; pbar x f; 0], and the tangent
  //   (P^T (K/L - L Hs) + [Star(st) - D(d, st); D(d, st)] + L E_A [0; Skew(f) [Jbar Pw]]) P
  //   - L (P^T S_f Skew(f) + E_A [Skew(f); Skew(pbar) Skew(f)]) Theta_A,   st = sigma - L s
  // (CalcRodInternal, AddRodDistributedDeadForce), right-multiplied by blockdiag(T_A, T_B):
  // P blockdiag(T_A, T_B) = [P_A T_A, P_B T_B] and Theta_A T = rows 3-5 of T_A.
  const double L = element.length;
  const Vec6& d = geometry.d;
  const Mat6x12& P = geometry.P;
  RodLaw law;
  CalcRodLaw(element, section, d, actuation, false, &law);
  Vec6& stress = law.stress;
  const bool weight = f_w.squaredNorm() > 0.0;
  DeadForcePieces p;
  if (weight) {
    p = CalcDeadForcePieces(d, H_A, f_w, stiffness != nullptr);
    stress -= L * p.s;
    force->head<3>() = -L * p.f;
    force->segment<3>(3) = -L * p.pbar.cross(p.f);
    force->tail<6>().setZero();
    force->noalias() += P.transpose() * stress;
  } else {
    force->noalias() = P.transpose() * stress;
  }
  if (!stiffness) return;
  const Mat6 D = DTSE3InvT(d, stress, geometry.series);
  Eigen::Matrix<double, 12, 6> Y;
  if (weight) {
    Mat6 H = -L * DeadForceHessian(p);
    H.diagonal() += section.stiffness / L;
    Y.noalias() = P.transpose() * H;
    Y.middleRows<3>(3) -= L * DeadForceMomentRows(p);
  } else {
    Y = P.transpose() * (section.stiffness / L).asDiagonal();
  }
  Y.topRows<6>() += Star(stress) - D;
  Y.bottomRows<6>() += D;
  if (T_A && T_B) {
    Mat6x12 PT;
    PT.leftCols<6>().noalias() = P.leftCols<6>() * *T_A;
    PT.rightCols<6>().noalias() = P.rightCols<6>() * *T_B;
    stiffness->noalias() = Y.lazyProduct(PT);
    if (weight)
      stiffness->leftCols<6>().noalias() -=
          L * (DeadForceRotationColumns(p, P) * T_A->middleRows<3>(3));
  } else {
    stiffness->noalias() = Y.lazyProduct(P);
    if (weight) stiffness->middleCols<3>(3) -= L * DeadForceRotationColumns(p, P);
  }
}

void CalcRodDistributedDeadForce(const RodElement& element, const SE3& H_A, const Vec6& d,
                                 const Vec3& f_w, Vec12* g, Mat12* tangent) {
  RodGeometry geometry;
  CalcRodGeometry(d, false, false, &geometry);
  g->setZero();
  tangent->setZero();
  AddRodDistributedDeadForce(element, geometry, H_A, f_w, g, tangent);
}

}  // namespace screwfem
