// Velocity-dependent forces of the helical rod element: inertia (method.md §2.5, options A and
// B) and damping (strain-rate and Rayleigh). Stateless, fixed-size, allocation-free kernels.
#include <cmath>

#include "screwfem/elements/rod.h"

namespace screwfem {

namespace {

// 3-point Gauss-Legendre rule on [0, 1] (option A, method.md §2.5).
constexpr double kGauss3Xi[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
constexpr double kGauss3W[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
// 2-point rule (option B: every integrand is a polynomial of degree <= 3 in xi).
constexpr double kGauss2Xi[2] = {0.5 - 0.28867513459481287, 0.5 + 0.28867513459481287};

// Quantities shared by the Gauss points of one element in option A.
struct ExactFieldBasis {
  Mat6 Ti_m, Ti_p;    // T^-1(-d), T^-1(d)
  Mat6 dTi_m, dTi_p;  // their time derivatives along d_dot
  Vec6 d_dot;         // P(d) eta_AB
};

void CalcExactFieldBasis(const Vec6& d, const Vec12& eta_ab, ExactFieldBasis* b) {
  b->Ti_m = TSE3Inv(-d);
  b->Ti_p = TSE3Inv(d);
  // d_dot = P eta_AB = T^-1(d) eta_B - T^-1(-d) eta_A   (method.md §2.3)
  b->d_dot.noalias() = b->Ti_p * eta_ab.tail<6>();
  b->d_dot.noalias() -= b->Ti_m * eta_ab.head<6>();
  b->dTi_m = TSE3InvDirectional(-d, -b->d_dot);
  b->dTi_p = TSE3InvDirectional(d, b->d_dot);
}

// N(xi, d) and the velocity-dependent part of the acceleration field, (dN/dt) eta_AB.
//   N = [Ad(exp(-xi d)) - xi T(xi d) T^-1(-d),   xi T(xi d) T^-1(d)]     (method.md §2.5)
// With X = xi d and the identity Ad(exp(-X)) T(-X) = T(X) (method.md §1.3):
//   d/dt Ad(exp(-X)) = -xi ad(T(X) d_dot) Ad(exp(-X)),
//   d/dt [xi T(X)]   = xi dT(X; xi d_dot) = -xi^2 T(X) dT^-1(X; d_dot) T(X),
// and T^-1(d) eta_B - T^-1(-d) eta_A = d_dot, so
//   (dN/dt) eta_AB = -xi ad(T d_dot) Ad(exp(-X)) eta_A - xi^2 T dT^-1(X; d_dot) T d_dot
//                    + xi T (dT^-1(d; d_dot) eta_B - dT^-1(-d; -d_dot) eta_A).
// (CalcRodNDirectional gives the same matrix; this form needs only one directional derivative
// per Gauss point.)
void CalcExactField(double xi, const Vec6& d, const ExactFieldBasis& b, const Vec12& eta_ab,
                    Mat6x12* N, Vec6* N_dot_eta) {
  const Vec6 X = xi * d;
  const Mat6 T = TSE3(X);
  const Mat6 Ad_m = Ad(ExpSE3(-X));
  const Mat6 xT = xi * T;
  N->leftCols<6>() = Ad_m;
  N->leftCols<6>().noalias() -= xT * b.Ti_m;
  N->rightCols<6>().noalias() = xT * b.Ti_p;

  const Vec6 T_dd = T * b.d_dot;
  const Vec6 Ad_eta_a = Ad_m * eta_ab.head<6>();
  Vec6 inner = b.dTi_p * eta_ab.tail<6>();
  inner.noalias() -= b.dTi_m * eta_ab.head<6>();
  *N_dot_eta = -xi * (ad(T_dd) * Ad_eta_a);
  N_dot_eta->noalias() -= (xi * xi) * (T * (TSE3InvDirectional(X, b.d_dot) * T_dd));
  N_dot_eta->noalias() += xT * inner;
}

}  // namespace

void CalcRodInertiaExact(const RodElement& element, const Section& section, const Vec6& d,
                         const Vec12& eta_ab, const Vec12& eta_dot_ab, RodInertiaTerms* out) {
  const double L = element.length;
  const auto M = section.inertia.asDiagonal();
  ExactFieldBasis basis;
  CalcExactFieldBasis(d, eta_ab, &basis);
  out->force.setZero();
  out->mass.setZero();
  out->gyroscopic.setZero();
  out->kinetic_energy = 0.0;
  Mat6x12 N, MN, GN;
  Vec6 N_dot_eta;
  for (int i = 0; i < 3; ++i) {
    const double w = L * kGauss3W[i];
    CalcExactField(kGauss3Xi[i], d, basis, eta_ab, &N, &N_dot_eta);
    const Vec6 eta = N * eta_ab;
    Vec6 eta_dot = N_dot_eta;
    eta_dot.noalias() += N * eta_dot_ab;
    const Vec6 M_eta = M * eta;
    // Inertia force density M eta_dot - ad(eta)^T M eta, weighted by the virtual field N.
    Vec6 f = M * eta_dot;
    f.noalias() -= ad(eta).transpose() * M_eta;
    out->force.noalias() += w * (N.transpose() * f);
    MN.noalias() = M * N;
    out->mass.noalias() += w * (N.transpose() * MN);
    // Quasi-Newton gyroscopic block: the option-B form with the exact N and eta (see rod.h).
    const Mat6 G = -(ad(eta).transpose() * M + Star(M_eta));
    GN.noalias() = G * N;
    out->gyroscopic.noalias() += w * (N.transpose() * GN);
    out->kinetic_energy += 0.5 * w * eta.dot(M_eta);
  }
}

void CalcRodInertiaConstant(const RodElement& element, const Section& section,
                            const Vec12& eta_ab, const Vec12& eta_dot_ab, RodInertiaTerms* out) {
  const double L = element.length;
  const auto M = section.inertia.asDiagonal();
  out->mass.setZero();
  for (int i = 0; i < 6; ++i) {
    out->mass(i, i) = out->mass(i + 6, i + 6) = L * section.inertia(i) / 3.0;
    out->mass(i, i + 6) = out->mass(i + 6, i) = L * section.inertia(i) / 6.0;
  }
  out->force.noalias() = out->mass * eta_dot_ab;
  out->gyroscopic.setZero();
  for (double xi : kGauss2Xi) {
    const double n[2] = {1.0 - xi, xi};
    const Vec6 eta = n[0] * eta_ab.head<6>() + n[1] * eta_ab.tail<6>();
    const Vec6 M_eta = M * eta;
    const Vec6 f = -(ad(eta).transpose() * M_eta);
    const Mat6 G = -(ad(eta).transpose() * M + Star(M_eta));  // d f / d eta (method.md §2.5)
    for (int a = 0; a < 2; ++a) {
      out->force.segment<6>(6 * a) += 0.5 * L * n[a] * f;
      for (int c = 0; c < 2; ++c)
        out->gyroscopic.block<6, 6>(6 * a, 6 * c) += 0.5 * L * n[a] * n[c] * G;
    }
  }
  out->kinetic_energy = 0.5 * eta_ab.dot(out->mass * eta_ab);
}

void CalcRodInertia(RodInertia option, const RodElement& element, const Section& section,
                    const Vec6& d, const Vec12& eta_ab, const Vec12& eta_dot_ab,
                    RodInertiaTerms* out) {
  if (option == RodInertia::kExact)
    CalcRodInertiaExact(element, section, d, eta_ab, eta_dot_ab, out);
  else
    CalcRodInertiaConstant(element, section, eta_ab, eta_dot_ab, out);
}

double CalcRodKineticEnergy(RodInertia option, const RodElement& element, const Section& section,
                            const Vec6& d, const Vec12& eta_ab) {
  const double L = element.length;
  double energy = 0.0;
  if (option == RodInertia::kConstant) {
    // Quadratic integrand in xi: the 2-point rule is exact.
    for (double xi : kGauss2Xi) {
      const Vec6 eta = (1.0 - xi) * eta_ab.head<6>() + xi * eta_ab.tail<6>();
      energy += 0.25 * L * eta.dot(section.inertia.cwiseProduct(eta));
    }
    return energy;
  }
  for (int i = 0; i < 3; ++i) {
    const Vec6 eta = CalcRodN(kGauss3Xi[i], d) * eta_ab;
    energy += 0.5 * L * kGauss3W[i] * eta.dot(section.inertia.cwiseProduct(eta));
  }
  return energy;
}

void AddRodDamping(const RodElement& element, const Section& section, const Vec6& d,
                   const Vec12& eta_ab, const Mat12& mass, Vec12* force, Mat12* damping) {
  const Vec6 strain_damping = section.damping + section.rayleigh_stiffness * section.stiffness;
  if (strain_damping.squaredNorm() > 0.0) {
    // sigma_v = D_s d_dot / L, d_dot = P eta_AB; force P^T sigma_v (virtual work of sigma_v).
    const Mat6x12 P = CalcRodP(d);
    const Vec6 scaled = strain_damping / element.length;
    const Vec6 sigma_v = scaled.cwiseProduct(P * eta_ab);
    force->noalias() += P.transpose() * sigma_v;
    const Mat6x12 DP = scaled.asDiagonal() * P;
    damping->noalias() += P.transpose() * DP;
  }
  if (section.rayleigh_mass > 0.0) {
    force->noalias() += section.rayleigh_mass * (mass * eta_ab);
    *damping += section.rayleigh_mass * mass;
  }
}

}  // namespace screwfem
