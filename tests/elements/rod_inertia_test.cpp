// Tests of the rod element's inertia (docs/numerics.md, "Rod inertia", options A and B) and damping kernels.
//
// Derivatives are checked by central finite differences (velocities and accelerations enter
// linearly or quadratically, so those differences are exact up to round-off; configurations
// through the retraction H <- H ExpSE3(eps e_i)). The option-A residual is checked against two
// computations that do not use its formulas: the power balance eta_AB^T g_ine = dT/dt and the
// momentum balance (world resultant of g_ine = rate of the linear and angular momentum of the
// exact velocity field), with the time derivatives taken by finite differences along a motion
// of the two nodes.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "screwfem/elements/rod.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::rod_inertia_test {
namespace {

constexpr double kGaussXi[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
constexpr double kGaussW[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

Vec6 MakeVec6(double a, double b, double c, double d, double e, double f) {
  Vec6 v;
  v << a, b, c, d, e, f;
  return v;
}

double RelativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

// A general (anisotropic) section and a curved, twisted element in a deformed state.
struct Case {
  Section section;
  RodElement element;
  SE3 H_A, H_B;
  Vec6 d;
  Vec12 eta, acc;
};

Case MakeCase(std::uint32_t seed, double rotation) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Case c;
  c.section = Section::FromDiagonals(MakeVec6(50, 20, 10, 1.5, 3.0, 0.8),
                                     MakeVec6(2.0, 1.5, 1.2, 0.3, 0.2, 0.25));
  const Vec6 d0 = MakeVec6(0.8, 0.05, -0.1, 0.2, -0.15, 0.3);
  c.element.rod = 0;
  c.element.node_a = 0;
  c.element.node_b = 1;
  c.element.d0 = d0;
  c.element.length = d0.head<3>().norm();
  c.H_A = ExpSE3(MakeVec6(n(rng), n(rng), n(rng), n(rng), n(rng), n(rng)));
  Vec3 axis(n(rng), n(rng), n(rng));
  c.d = MakeVec6(0.9 + 0.1 * n(rng), 0.2 * n(rng), 0.2 * n(rng), 0, 0, 0);
  c.d.tail<3>() = rotation * axis.normalized();
  c.H_B = c.H_A * ExpSE3(c.d);
  for (int i = 0; i < 12; ++i) {
    c.eta(i) = n(rng);
    c.acc(i) = n(rng);
  }
  return c;
}

RodInertiaTerms Inertia(RodInertia option, const Case& c, const Vec6& d, const Vec12& eta,
                        const Vec12& acc) {
  RodInertiaTerms t;
  CalcRodInertia(option, c.element, c.section, d, eta, acc, &t);
  return t;
}

// Central differences of g_ine in the accelerations and in the velocities (12 x 12).
Mat12 FdInAcceleration(RodInertia option, const Case& c) {
  Mat12 J;
  const double h = 1e-3;
  for (int j = 0; j < 12; ++j) {
    Vec12 p = c.acc, m = c.acc;
    p(j) += h;
    m(j) -= h;
    J.col(j) = (Inertia(option, c, c.d, c.eta, p).force - Inertia(option, c, c.d, c.eta, m).force) /
               (2.0 * h);
  }
  return J;
}
Mat12 FdInVelocity(RodInertia option, const Case& c) {
  Mat12 J;
  const double h = 1e-3;  // g is quadratic in eta: the central difference is exact
  for (int j = 0; j < 12; ++j) {
    Vec12 p = c.eta, m = c.eta;
    p(j) += h;
    m(j) -= h;
    J.col(j) = (Inertia(option, c, c.d, p, c.acc).force - Inertia(option, c, c.d, m, c.acc).force) /
               (2.0 * h);
  }
  return J;
}
// Derivative of g_ine in the right-trivialised node perturbations at fixed velocities.
Mat12 FdInConfiguration(RodInertia option, const Case& c) {
  Mat12 J;
  const double h = 1e-6;
  for (int j = 0; j < 12; ++j) {
    Vec12 g[2];
    for (int s = 0; s < 2; ++s) {
      const Vec6 dh = (s == 0 ? h : -h) * Vec6::Unit(j % 6);
      const SE3 A = j < 6 ? c.H_A * ExpSE3(dh) : c.H_A;
      const SE3 B = j < 6 ? c.H_B : c.H_B * ExpSE3(dh);
      const Vec6 d = CalcRodRelativeMotion(A, B, c.d.tail<3>());
      g[s] = Inertia(option, c, d, c.eta, c.acc).force;
    }
    J.col(j) = (g[0] - g[1]) / (2.0 * h);
  }
  return J;
}

TEST(RodInertia, OptionAResidualDoesNotDependOnWhetherTheTangentIsComputed) {
  // The Newton loop assembles the residual alone once the correction is small (TryStep): the
  // forces must be the same, bit for bit, with and without the tangent blocks.
  for (double rotation : {0.0, 0.4, 2.5}) {
    const Case c = MakeCase(31, rotation);
    RodGeometry with, without;
    CalcRodGeometry(c.d, true, true, &with);
    CalcRodGeometry(c.d, true, false, &without);
    RodInertiaTerms a, b;
    CalcRodInertiaExact(c.element, c.section, with, c.eta, c.acc, true, &a);
    CalcRodInertiaExact(c.element, c.section, without, c.eta, c.acc, false, &b);
    for (int i = 0; i < 12; ++i) EXPECT_EQ(a.force(i), b.force(i)) << "rotation " << rotation;
    EXPECT_EQ(a.kinetic_energy, b.kinetic_energy);
  }
}

TEST(RodInertia, OptionACombinedMatrixIsTheWeightedSumOfMassAndGyroscopicBlocks) {
  // CalcRodInertiaExactMatrix (the assembly's kernel) forms c_M M_e + c_C C_t in one pass: the
  // same force bit for bit, and the same matrix to round-off.
  for (double rotation : {0.0, 0.4, 2.5}) {
    const Case c = MakeCase(32, rotation);
    RodGeometry g;
    CalcRodGeometry(c.d, true, true, &g);
    RodInertiaTerms t;
    CalcRodInertiaExact(c.element, c.section, g, c.eta, c.acc, true, &t);
    const double c_mass = 3.7e6, c_gyro = 2.1e3;
    Vec12 force;
    Mat12 matrix;
    CalcRodInertiaExactMatrix(c.element, c.section, g, c.eta, c.acc, c_mass, c_gyro, &force,
                              &matrix);
    for (int i = 0; i < 12; ++i) EXPECT_EQ(force(i), t.force(i)) << "rotation " << rotation;
    const Mat12 ref = c_mass * t.mass + c_gyro * t.gyroscopic;
    EXPECT_LT((matrix - ref).norm(), 1e-14 * ref.norm()) << "rotation " << rotation;
    // The gyroscopic part (a small fraction of the sum) is resolved too.
    const Mat12 gyro = c_gyro * t.gyroscopic;
    EXPECT_GT(gyro.norm(), 1e-6 * ref.norm());
    EXPECT_LT((matrix - c_mass * t.mass - gyro).norm(), 1e-9 * gyro.norm());
  }
}

TEST(RodInertia, OptionAInterpolationHalvesSumToTheIdentity) {
  // RodGeometry's N = [I - N_B, N_B] (docs/numerics.md, "Rod inertia"): CalcRodN's left half is I - N_B.
  for (double rotation : {0.0, 1e-7, 0.4, 2.5, 4.0}) {
    const Case c = MakeCase(32, rotation);
    RodGeometry g;
    CalcRodGeometry(c.d, true, true, &g);
    for (int i = 0; i < kRodGaussPoints; ++i) {
      const Mat6x12 N = CalcRodN(kRodGaussXi[i], c.d);
      EXPECT_LT((N.rightCols<6>() - g.NB[i]).norm(), 1e-13 * N.norm()) << "rotation " << rotation;
      EXPECT_LT((N.leftCols<6>() + g.NB[i] - Mat6::Identity()).norm(), 1e-13 * N.norm())
          << "rotation " << rotation;
    }
  }
}

TEST(RodInertia, MassBlockIsTheExactDerivativeInTheAccelerationsForBothOptions) {
  for (const double rotation : {0.0, 1.0, 2.8, 4.2}) {
    const Case c = MakeCase(101, rotation);
    for (const RodInertia option : {RodInertia::kExact, RodInertia::kConstant}) {
      const RodInertiaTerms t = Inertia(option, c, c.d, c.eta, c.acc);
      EXPECT_LT(RelativeError(t.mass, FdInAcceleration(option, c)), 1e-10)
          << "rotation " << rotation << " option " << static_cast<int>(option);
      EXPECT_LT(RelativeError(t.mass, t.mass.transpose()), 1e-14);
      EXPECT_GT(t.mass.eigenvalues().real().minCoeff(), 0.0);  // positive definite
    }
  }
}

TEST(RodInertia, OptionBGyroscopicBlockIsTheExactVelocityDerivativeAndHasNoConfigurationTerm) {
  const Case c = MakeCase(102, 1.7);
  const RodInertiaTerms t = Inertia(RodInertia::kConstant, c, c.d, c.eta, c.acc);
  EXPECT_LT(RelativeError(t.gyroscopic, FdInVelocity(RodInertia::kConstant, c)), 1e-10);
  EXPECT_EQ(FdInConfiguration(RodInertia::kConstant, c).norm(), 0.0);
}

// Kinetic energy of the 3-point quadrature along a motion of the two nodes,
// H_n(t) = H_n exp(t eta_n + t^2/2 a_n): body velocity T(X) X', body acceleration a_n at t = 0.
struct ElementMotion {
  const Case& c;
  Vec6 X(int node, double t) const {
    const int o = 6 * node;
    return t * c.eta.segment<6>(o) + 0.5 * t * t * c.acc.segment<6>(o);
  }
  SE3 H(int node, double t) const { return (node == 0 ? c.H_A : c.H_B) * ExpSE3(X(node, t)); }
  Vec12 Eta(double t) const {
    Vec12 e;
    for (int n = 0; n < 2; ++n)
      e.segment<6>(6 * n) = TSE3(X(n, t)) * (c.eta.segment<6>(6 * n) + t * c.acc.segment<6>(6 * n));
    return e;
  }
  Vec6 D(double t) const { return CalcRodRelativeMotion(H(0, t), H(1, t), c.d.tail<3>()); }
};

TEST(RodInertia, OptionAPowerIsTheTimeDerivativeOfTheKineticEnergy) {
  for (const double rotation : {0.3, 2.0, 4.0}) {
    const Case c = MakeCase(103, rotation);
    const ElementMotion m{c};
    const RodInertiaTerms t = Inertia(RodInertia::kExact, c, c.d, c.eta, c.acc);
    const double h = 1e-4;
    auto T = [&](double s) {
      return CalcRodKineticEnergy(RodInertia::kExact, c.element, c.section, m.D(s), m.Eta(s));
    };
    const double dT = (T(-2 * h) - 8 * T(-h) + 8 * T(h) - T(2 * h)) / (12 * h);
    EXPECT_NEAR(c.eta.dot(t.force), dT, 1e-9 * std::abs(dT)) << "rotation " << rotation;
    EXPECT_NEAR(t.kinetic_energy, T(0.0), 1e-14 * T(0.0));
    EXPECT_NEAR(t.kinetic_energy, 0.5 * c.eta.dot(t.mass * c.eta), 1e-13 * T(0.0));
  }
}

TEST(RodInertia, OptionAForcesAreTheRateOfMomentumOfTheExactVelocityField) {
  // World momentum (linear; angular about the origin) of the exact field by the element's
  // quadrature: sum L w_i Ad(H(xi_i)^-1)^T M eta(xi_i), with H(xi) = H_A exp(xi d) and
  // eta(xi) the body velocity of that frame, here from finite differences of H(xi, t) itself
  // (no use of N). Its time derivative must equal the world resultant of the nodal inertia
  // forces, Ad(H_A^-1)^T g_A + Ad(H_B^-1)^T g_B, because rigid virtual motions are exact in N.
  for (const double rotation : {0.5, 2.5, 4.0}) {
    const Case c = MakeCase(104, rotation);
    const ElementMotion m{c};
    const auto M = c.section.inertia.asDiagonal();
    auto frame = [&](double xi, double t) { return m.H(0, t) * ExpSE3(xi * m.D(t)); };
    auto momentum = [&](double t) {
      Vec6 p = Vec6::Zero();
      for (int i = 0; i < 3; ++i) {
        const double e = 2e-4;
        const SE3 H = frame(kGaussXi[i], t);
        auto rel = [&](double s) { return LogSE3(H.Inverse() * frame(kGaussXi[i], t + s)); };
        const Vec6 eta = (rel(-2 * e) - 8 * rel(-e) + 8 * rel(e) - rel(2 * e)) / (12 * e);
        p += c.element.length * kGaussW[i] * (Ad(H.Inverse()).transpose() * (M * eta));
      }
      return p;
    };
    const double h = 1e-3;
    const Vec6 dp =
        (momentum(-2 * h) - 8 * momentum(-h) + 8 * momentum(h) - momentum(2 * h)) / (12 * h);
    const RodInertiaTerms t = Inertia(RodInertia::kExact, c, c.d, c.eta, c.acc);
    const Vec6 resultant = Ad(c.H_A.Inverse()).transpose() * t.force.head<6>() +
                           Ad(c.H_B.Inverse()).transpose() * t.force.tail<6>();
    EXPECT_LT((resultant - dp).norm(), 1e-8 * dp.norm()) << "rotation " << rotation;
  }
}

TEST(RodInertia, OptionBViolatesTheMomentumBalanceOfTheHelixAtOrderElementCurvature) {
  // The same balance for option B holds only for straight elements: its linear virtual field
  // is not rigid-exact once the element is curved. This is why option A is the default.
  const Case c = MakeCase(105, 1.0);
  const RodInertiaTerms a = Inertia(RodInertia::kExact, c, c.d, c.eta, c.acc);
  const RodInertiaTerms b = Inertia(RodInertia::kConstant, c, c.d, c.eta, c.acc);
  auto resultant = [&](const RodInertiaTerms& t) {
    return Vec6(Ad(c.H_A.Inverse()).transpose() * t.force.head<6>() +
                Ad(c.H_B.Inverse()).transpose() * t.force.tail<6>());
  };
  EXPECT_GT((resultant(b) - resultant(a)).norm(), 1e-2 * resultant(a).norm());
}

TEST(RodInertia, OptionAGyroscopicBlockOmitsExactlyTheVelocityDerivativeOfTheDnDtTerm) {
  // Documented split (elements/rod.h): d g_ine / d eta = C_t + d/d eta [L int N^T M (dN/dt)
  // eta dxi], the second part evaluated here independently with CalcRodNDirectional.
  const Case c = MakeCase(106, 2.2);
  const auto M = c.section.inertia.asDiagonal();
  const Mat6x12 P = CalcRodP(c.d);
  auto omitted_force = [&](const Vec12& eta) {
    Vec12 q = Vec12::Zero();
    for (int i = 0; i < 3; ++i) {
      const Mat6x12 N = CalcRodN(kGaussXi[i], c.d);
      const Vec6 ndot_eta = CalcRodNDirectional(kGaussXi[i], c.d, P * eta) * eta;
      q += c.element.length * kGaussW[i] * (N.transpose() * (M * ndot_eta));
    }
    return q;
  };
  Mat12 omitted;
  for (int j = 0; j < 12; ++j) {
    Vec12 p = c.eta, m = c.eta;
    p(j) += 1e-3;
    m(j) -= 1e-3;
    omitted.col(j) = (omitted_force(p) - omitted_force(m)) / 2e-3;
  }
  const RodInertiaTerms t = Inertia(RodInertia::kExact, c, c.d, c.eta, c.acc);
  const Mat12 exact = FdInVelocity(RodInertia::kExact, c);
  EXPECT_LT(RelativeError(t.gyroscopic + omitted, exact), 1e-9);
  // The omitted part is not small by itself (same order in |eta| as C_t): the approximation
  // rests on the time-step scaling checked next.
  EXPECT_GT(omitted.norm(), 0.05 * exact.norm());
}

TEST(RodInertia, OptionAIterationMatrixBlockIsConsistentToOrderH) {
  // Iteration-matrix block of the element, beta' M_e + gamma' C + K_ine (docs/architecture.md, "One time step"), with
  // the exact C and K_ine from finite differences versus the implemented beta' M_e + gamma' C_t
  // (no configuration term). The relative error must fall like h.
  const Case c = MakeCase(107, 1.9);
  const RodInertiaTerms t = Inertia(RodInertia::kExact, c, c.d, c.eta, c.acc);
  const Mat12 C_exact = FdInVelocity(RodInertia::kExact, c);
  const Mat12 K_exact = FdInConfiguration(RodInertia::kExact, c);
  const GeneralizedAlpha p = GeneralizedAlpha::FromSpectralRadius(0.8);
  auto error = [&](double h) {
    const double beta_p = (1.0 - p.alpha_m) / (h * h * p.beta * (1.0 - p.alpha_f));
    const double gamma_p = p.gamma / (h * p.beta);
    const Mat12 exact = beta_p * t.mass + gamma_p * C_exact + K_exact;
    const Mat12 approx = beta_p * t.mass + gamma_p * t.gyroscopic;
    return RelativeError(approx, exact);
  };
  const double e2 = error(1e-2), e3 = error(1e-3), e4 = error(1e-4);
  EXPECT_LT(e2, 0.1);
  EXPECT_NEAR(e2 / e3, 10.0, 1.5);
  EXPECT_NEAR(e3 / e4, 10.0, 1.0);
}

TEST(RodInertia, OptionAMassMatrixDependsOnTheDeformationAndOptionBIsConstant) {
  const Case c = MakeCase(108, 0.0);
  const Case bent = MakeCase(108, 2.0);
  const Mat12 Ma = Inertia(RodInertia::kExact, c, c.d, c.eta, c.acc).mass;
  const Mat12 Ma_bent = Inertia(RodInertia::kExact, bent, bent.d, c.eta, c.acc).mass;
  EXPECT_GT(RelativeError(Ma_bent, Ma), 1e-2);
  const Mat12 Mb = Inertia(RodInertia::kConstant, c, c.d, c.eta, c.acc).mass;
  const Mat12 Mb_bent = Inertia(RodInertia::kConstant, bent, bent.d, c.eta, c.acc).mass;
  EXPECT_EQ((Mb - Mb_bent).norm(), 0.0);
}

TEST(RodInertia, RigidMotionOfAStraightElementHasTheRigidRodKineticEnergy) {
  // Straight element of length L along x, rotating about z through node A with rate w and
  // translating along y with speed v: the y velocity at s is v + w s, so
  // T = 1/2 rhoA_y (v^2 L + v w L^2 + w^2 L^3 / 3) + 1/2 rhoI3 w^2 L. Both options are exact
  // here (option A's field is the rigid one, option B's is linear in s).
  const double L = 0.7, w = 1.3, v = -0.4;
  Case c = MakeCase(109, 0.0);
  c.element.d0 = MakeVec6(L, 0, 0, 0, 0, 0);
  c.element.length = L;
  c.d = c.element.d0;
  Vec6 eta_a = MakeVec6(0, v, 0, 0, 0, w);
  const Vec6 eta_b = Ad(ExpSE3(-c.d)) * eta_a;  // rigid: eta_B = Ad(H_AB^-1) eta_A
  Vec12 eta;
  eta << eta_a, eta_b;
  const double rhoA_y = c.section.inertia(1), rhoI3 = c.section.inertia(5);
  const double expected = 0.5 * rhoA_y * (v * v * L + v * w * L * L + w * w * L * L * L / 3.0) +
                          0.5 * rhoI3 * w * w * L;
  for (const RodInertia option : {RodInertia::kExact, RodInertia::kConstant}) {
    const double T = CalcRodKineticEnergy(option, c.element, c.section, c.d, eta);
    EXPECT_NEAR(T, expected, 1e-14) << static_cast<int>(option);
  }
  // A rigid motion has d_dot = 0: the strain-rate and stiffness-proportional damping vanish.
  Section damped = c.section;
  damped.damping.setConstant(0.3);
  damped.rayleigh_stiffness = 0.02;
  Vec12 f = Vec12::Zero();
  Mat12 C = Mat12::Zero();
  AddRodDamping(c.element, damped, c.d, eta, Mat12::Zero(), &f, &C);
  EXPECT_LT(f.norm(), 1e-14);
}

TEST(RodDamping, TangentIsTheVelocityDerivativeAndRayleighTermsAreProportional) {
  const Case c = MakeCase(110, 1.4);
  Section s = c.section;
  s.damping = MakeVec6(0.1, 0.2, 0.3, 0.01, 0.02, 0.03);
  s.rayleigh_mass = 0.7;
  s.rayleigh_stiffness = 0.05;
  const RodInertiaTerms t = Inertia(RodInertia::kExact, c, c.d, c.eta, c.acc);
  auto force = [&](const Section& sec, const Vec12& eta) {
    Vec12 f = Vec12::Zero();
    Mat12 C = Mat12::Zero();
    AddRodDamping(c.element, sec, c.d, eta, t.mass, &f, &C);
    return std::make_pair(f, C);
  };
  const auto [f, C] = force(s, c.eta);
  Mat12 fd;
  for (int j = 0; j < 12; ++j) {
    Vec12 p = c.eta, m = c.eta;
    p(j) += 1e-3;
    m(j) -= 1e-3;
    fd.col(j) = (force(s, p).first - force(s, m).first) / 2e-3;
  }
  EXPECT_LT(RelativeError(C, fd), 1e-11);
  // Mass-proportional part: a_M M_e eta.
  Section only_mass = c.section;
  only_mass.rayleigh_mass = 0.7;
  EXPECT_LT((force(only_mass, c.eta).first - 0.7 * t.mass * c.eta).norm(), 1e-13);
  // Stiffness-proportional part: a_K times the material stiffness (1/L) P^T K P applied to eta.
  Section only_k = c.section;
  only_k.rayleigh_stiffness = 0.05;
  const Mat6x12 P = CalcRodP(c.d);
  const Mat12 K_mat = P.transpose() * (c.section.stiffness / c.element.length).asDiagonal() * P;
  EXPECT_LT(RelativeError(force(only_k, c.eta).second, 0.05 * K_mat), 1e-14);
}

}  // namespace
}  // namespace screwfem::rod_inertia_test
