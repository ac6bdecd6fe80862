// Velocity-dependent forces of the helical rod element: inertia (docs/numerics.md, "Rod inertia", options A and
// B) and damping (strain-rate and Rayleigh). Stateless, fixed-size, allocation-free kernels.
#include <cmath>
#include <type_traits>

#include "screwfem/elements/rod.h"

namespace screwfem {

namespace {

// Sums over Gauss points of w N^T H N for N = [I - B, B] (RodGeometry), kept as the four
// 6 x 6 sums of w H, w H B, w B^T H and w B^T H B:
//   N^T H N = [H - HB - B^T H + B^T H B,  HB - B^T H B;  B^T H - B^T H B,  B^T H B].
struct NtHNSum {
  Mat6 H = Mat6::Zero(), HB = Mat6::Zero(), BtH = Mat6::Zero(), BtHB = Mat6::Zero();
  void Expand(Mat12* out) const {
    out->topLeftCorner<6, 6>() = H - HB - BtH + BtHB;
    out->topRightCorner<6, 6>() = HB - BtHB;
    out->bottomLeftCorner<6, 6>() = BtH - BtHB;
    out->bottomRightCorner<6, 6>() = BtHB;
  }
};

// Option A with the tangent: none (kNone), M_e and C_t (kSeparate: *mass_out, *gyro_out), or
// c_mass M_e + c_gyro C_t (kCombined: *mass_out, one set of products per Gauss point).
enum class InertiaTangent { kNone, kSeparate, kCombined };

// One function (about 85 lines) for the three tangent variants, so that they compute the force
// with the same operations (the residual is bit-identical with and without the tangent).
template <InertiaTangent kTangent>
void InertiaExact(const RodElement& element, const Section& section, const RodGeometry& geometry,
                  const Vec12& eta_ab, const Vec12& eta_dot_ab, double c_mass, double c_gyro,
                  Vec12* force, Mat12* mass_out, Mat12* gyro_out, double* kinetic_energy) {
  // Exact field (docs/numerics.md, "Rod inertia") with N = [I - N_B, N_B], N_B = xi T(X) T^-1(d), X = xi d:
  //   eta(xi)     = eta_A + xi T(X) y,                 y = T^-1(d) (eta_B - eta_A),
  //   eta_dot(xi) = eta_dot_A + xi T(X) T^-1(d) (eta_dot_B - eta_dot_A) + (dN_B/dt)(eta_B - eta_A),
  //   (dN_B/dt) v = xi T(X) [dT^-1(d; d_dot) v - xi dT^-1(X; d_dot) T(X) T^-1(d) v],
  // from d/dt T(X) = -T(X) dT^-1(X; xi d_dot) T(X) and the linearity of dT^-1 in its direction,
  // with d_dot = P eta_AB = y + ad(d) eta_A (elements/rod.h).
  // Force L int N^T f dxi, f = M eta_dot - ad(eta)^T M eta: with N_B^T f = T^-T(d) xi T^T f,
  //   g_B = T^-T(d) Phi,  g_A = L sum w_i f_i - g_B,  Phi = L sum w_i xi_i T_i^T f_i.
  const double L = element.length;
  const Vec6& Mdiag = section.inertia;
  const auto M = Mdiag.asDiagonal();
  const Vec6& d = geometry.d;
  const Vec6 eta_a = eta_ab.head<6>(), acc_a = eta_dot_ab.head<6>();
  const Vec6 y = geometry.Ti * (eta_ab.tail<6>() - eta_a);
  const Vec6 ya = geometry.Ti * (eta_dot_ab.tail<6>() - acc_a);
  const Vec6 d_dot = y + Bracket(d, eta_a);
  const Vec6 c0 = TSE3InvDirectionalTimes(d, d_dot, eta_ab.tail<6>() - eta_a, geometry.series);
  Vec6 f_sum = Vec6::Zero(), phi = Vec6::Zero();
  // The sums exist only for the tangents computed (no zeroing of unused 6 x 6 blocks).
  struct None {};
  std::conditional_t<kTangent == InertiaTangent::kSeparate, NtHNSum, None> mass;
  std::conditional_t<kTangent != InertiaTangent::kNone, NtHNSum, None> gyro;
  double energy = 0.0;
  for (int i = 0; i < kRodGaussPoints; ++i) {
    const double xi = kRodGaussXi[i], w = L * kRodGaussW[i];
    const Mat6& T = geometry.T[i];
    const Vec6 Ty = T * y;
    const Vec6 eta = eta_a + xi * Ty;
    Vec6 inner = c0 - xi * TSE3InvDirectionalTimes(xi * d, d_dot, Ty, geometry.series_gp[i]);
    inner += ya;
    const Vec6 eta_dot = acc_a + xi * (T * inner);
    const Vec6 M_eta = M * eta;
    // Inertia force density M eta_dot - ad(eta)^T M eta, weighted by the virtual field N.
    const Vec6 f = M * eta_dot - CoBracket(eta, M_eta);
    f_sum += w * f;
    phi.noalias() += (w * xi) * (T.transpose() * f);
    energy += 0.5 * w * eta.dot(M_eta);
    if constexpr (kTangent != InertiaTangent::kNone) {
      const Mat6& B = geometry.NB[i];
      // w B^T, stored column-major so that the products below run on columns (packets).
      const Mat6 wBt = w * B.transpose();
      if constexpr (kTangent == InertiaTangent::kSeparate) {
        // Mass: H = M (diagonal).
        const Mat6 MB = M * B;
        mass.HB += w * MB;
        mass.BtHB.noalias() += wBt * MB;
      }
      // Quasi-Newton gyroscopic block: the option-B form with the exact N and eta (see rod.h),
      // G = -(ad(eta)^T M + Star(M eta)) in 3x3 blocks, with ad(eta)^T = [-W 0; -U -W]:
      //   G = [W M_t  -Skew(y_t);  U M_t - Skew(y_t)  W M_r - Skew(y_r)],  y = M eta.
      Mat6 G;
      const Mat3 W = Skew(eta.tail<3>()), U = Skew(eta.head<3>()), Sy = Skew(M_eta.head<3>());
      G.topLeftCorner<3, 3>().noalias() = W * Mdiag.head<3>().asDiagonal();
      G.topRightCorner<3, 3>() = -Sy;
      G.bottomLeftCorner<3, 3>().noalias() = U * Mdiag.head<3>().asDiagonal();
      G.bottomLeftCorner<3, 3>() -= Sy;
      G.bottomRightCorner<3, 3>().noalias() = W * Mdiag.tail<3>().asDiagonal();
      G.bottomRightCorner<3, 3>() -= Skew(M_eta.tail<3>());
      if constexpr (kTangent == InertiaTangent::kCombined) {
        G *= c_gyro;
        G.diagonal() += c_mass * Mdiag;
      }
      const Mat6 GB = G * B;
      gyro.H += w * G;
      gyro.HB += w * GB;
      gyro.BtH.noalias() += wBt * G;
      gyro.BtHB.noalias() += wBt * GB;
    }
  }
  const Vec6 g_b = geometry.Ti.transpose() * phi;
  force->head<6>() = f_sum - g_b;
  force->tail<6>() = g_b;
  if (kinetic_energy) *kinetic_energy = energy;
  if constexpr (kTangent == InertiaTangent::kSeparate) {
    mass.H = L * Mat6(M);
    mass.BtH = mass.HB.transpose();
    mass.Expand(mass_out);
    gyro.Expand(gyro_out);
  } else if constexpr (kTangent == InertiaTangent::kCombined) {
    gyro.Expand(mass_out);
  }
}

}  // namespace

void CalcRodInertiaExact(const RodElement& element, const Section& section,
                         const RodGeometry& geometry, const Vec12& eta_ab, const Vec12& eta_dot_ab,
                         bool tangent, RodInertiaTerms* out) {
  if (tangent)
    InertiaExact<InertiaTangent::kSeparate>(element, section, geometry, eta_ab, eta_dot_ab, 0.0,
                                            0.0, &out->force, &out->mass, &out->gyroscopic,
                                            &out->kinetic_energy);
  else
    InertiaExact<InertiaTangent::kNone>(element, section, geometry, eta_ab, eta_dot_ab, 0.0, 0.0,
                                        &out->force, nullptr, nullptr, &out->kinetic_energy);
}

void CalcRodInertiaExactForce(const RodElement& element, const Section& section,
                              const RodGeometry& geometry, const Vec12& eta_ab,
                              const Vec12& eta_dot_ab, Vec12* force) {
  InertiaExact<InertiaTangent::kNone>(element, section, geometry, eta_ab, eta_dot_ab, 0.0, 0.0,
                                      force, nullptr, nullptr, nullptr);
}

void CalcRodInertiaExactMatrix(const RodElement& element, const Section& section,
                               const RodGeometry& geometry, const Vec12& eta_ab,
                               const Vec12& eta_dot_ab, double c_mass, double c_gyro, Vec12* force,
                               Mat12* matrix) {
  InertiaExact<InertiaTangent::kCombined>(element, section, geometry, eta_ab, eta_dot_ab, c_mass,
                                          c_gyro, force, matrix, nullptr, nullptr);
}

void CalcRodInertiaExact(const RodElement& element, const Section& section, const Vec6& d,
                         const Vec12& eta_ab, const Vec12& eta_dot_ab, RodInertiaTerms* out) {
  RodGeometry geometry;
  CalcRodGeometry(d, true, true, &geometry);
  CalcRodInertiaExact(element, section, geometry, eta_ab, eta_dot_ab, true, out);
}

void CalcRodInertiaConstant(const RodElement& element, const Section& section, const Vec12& eta_ab,
                            const Vec12& eta_dot_ab, RodInertiaTerms* out) {
  const double L = element.length;
  const auto M = section.inertia.asDiagonal();
  out->mass.setZero();
  for (int i = 0; i < 6; ++i) {
    out->mass(i, i) = out->mass(i + 6, i + 6) = L * section.inertia(i) / 3.0;
    out->mass(i, i + 6) = out->mass(i + 6, i) = L * section.inertia(i) / 6.0;
  }
  out->force.noalias() = out->mass * eta_dot_ab;
  out->gyroscopic.setZero();
  for (double xi : kGauss2Xi) {  // option B: integrands of degree <= 3 in xi
    const double n[2] = {1.0 - xi, xi};
    const Vec6 eta = n[0] * eta_ab.head<6>() + n[1] * eta_ab.tail<6>();
    const Vec6 M_eta = M * eta;
    const Vec6 f = -(ad(eta).transpose() * M_eta);
    const Mat6 G =
        -(ad(eta).transpose() * M + Star(M_eta));  // d f / d eta (docs/numerics.md, "Rod inertia")
    for (int a = 0; a < 2; ++a) {
      out->force.segment<6>(6 * a) += 0.5 * L * n[a] * f;
      for (int c = 0; c < 2; ++c)
        out->gyroscopic.block<6, 6>(6 * a, 6 * c) += 0.5 * L * n[a] * n[c] * G;
    }
  }
  out->kinetic_energy = 0.5 * eta_ab.dot(out->mass * eta_ab);
}

void CalcRodInertia(RodInertia option, const RodElement& element, const Section& section,
                    const RodGeometry& geometry, const Vec12& eta_ab, const Vec12& eta_dot_ab,
                    bool tangent, RodInertiaTerms* out) {
  if (option == RodInertia::kExact)
    CalcRodInertiaExact(element, section, geometry, eta_ab, eta_dot_ab, tangent, out);
  else
    CalcRodInertiaConstant(element, section, eta_ab, eta_dot_ab, out);
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
  Vec6 eta[kRodGaussPoints];
  CalcRodGaussVelocities(d, eta_ab, eta);
  return CalcRodKineticEnergyExact(element, section, eta);
}

double CalcRodKineticEnergyExact(const RodElement& element, const Section& section,
                                 const Vec6 (&eta)[kRodGaussPoints]) {
  double energy = 0.0;
  for (int i = 0; i < kRodGaussPoints; ++i)
    energy +=
        0.5 * element.length * kRodGaussW[i] * eta[i].dot(section.inertia.cwiseProduct(eta[i]));
  return energy;
}

void AddRodDamping(const RodElement& element, const Section& section, const Mat6x12& P,
                   const Vec12& eta_ab, const Mat12& mass, Vec12* force, Mat12* damping) {
  const Vec6 strain_damping = section.damping + section.rayleigh_stiffness * section.stiffness;
  if (strain_damping.squaredNorm() > 0.0) {
    // sigma_v = D_s d_dot / L, d_dot = P eta_AB; force P^T sigma_v (virtual work of sigma_v).
    const Vec6 scaled = strain_damping / element.length;
    const Vec6 sigma_v = scaled.cwiseProduct(P * eta_ab);
    force->noalias() += P.transpose() * sigma_v;
    if (damping) {
      const Mat6x12 DP = scaled.asDiagonal() * P;
      damping->noalias() += P.transpose().lazyProduct(DP);
    }
  }
  if (section.rayleigh_mass > 0.0) {
    force->noalias() += section.rayleigh_mass * (mass * eta_ab);
    if (damping) *damping += section.rayleigh_mass * mass;
  }
}

void AddRodDamping(const RodElement& element, const Section& section, const Vec6& d,
                   const Vec12& eta_ab, const Mat12& mass, Vec12* force, Mat12* damping) {
  AddRodDamping(element, section, CalcRodP(d), eta_ab, mass, force, damping);
}

}  // namespace screwfem
