// Tests of the two-node helical Cosserat rod element (elements/rod.h) and of the section
// helpers. Every analytic derivative is checked by central finite differences through the
// retraction H <- H ExpSE3(eps e_i) (style.md "Tests"); the branch reference w_ref is held fixed
// while perturbing, as in a Newton iteration.
#include "screwfem/elements/rod.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "screwfem/model/errors.h"
#include "screwfem/model/section.h"

namespace screwfem::rod_test {
namespace {

constexpr double kPi = std::numbers::pi;

Vec6 MakeVec6(double a, double b, double c, double d, double e, double f) {
  Vec6 v;
  v << a, b, c, d, e, f;
  return v;
}

// Random unit vector and random 6-vector with rotation part of the given magnitude.
Vec3 RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 v(n(rng), n(rng), n(rng));
  return v.normalized();
}

SE3 RandomFrame(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> angle(0.0, 3.0);
  return ExpSE3((Vec6() << 2.0 * u(rng), 2.0 * u(rng), 2.0 * u(rng), Vec3::Zero()).finished()) *
         ExpSE3((Vec6() << Vec3::Zero(), angle(rng) * RandomUnit(rng)).finished());
}

// A relative motion of rotation |w| = rotation and a translation of order `length`.
Vec6 RandomRelativeMotion(std::mt19937& rng, double rotation, double length) {
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  Vec6 d;
  d.head<3>() = Vec3(length * (1.0 + u(rng)), length * u(rng), length * u(rng));
  d.tail<3>() = rotation * RandomUnit(rng);
  return d;
}

RodElement MakeElement(const Vec6& d0) {
  RodElement el;
  el.rod = 0;
  el.node_a = 0;
  el.node_b = 1;
  el.d0 = d0;
  el.length = d0.head<3>().norm();
  return el;
}

double RelativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

// Perturbation of node A (i < 6) or node B (i >= 6) along e_{i mod 6} by eps.
void Perturb(const SE3& H_A, const SE3& H_B, int i, double eps, SE3* A, SE3* B) {
  const Vec6 dh = eps * Vec6::Unit(i % 6);
  *A = i < 6 ? H_A * ExpSE3(dh) : H_A;
  *B = i < 6 ? H_B : H_B * ExpSE3(dh);
}

// Central-difference Jacobian (columns = the 12 right-trivialised perturbation directions) of a
// function of the two node frames.
template <int Rows>
Eigen::Matrix<double, Rows, 12> FiniteDifference(
    const std::function<Eigen::Matrix<double, Rows, 1>(const SE3&, const SE3&)>& f, const SE3& H_A,
    const SE3& H_B, double eps) {
  Eigen::Matrix<double, Rows, 12> J;
  for (int i = 0; i < 12; ++i) {
    SE3 Ap, Bp, Am, Bm;
    Perturb(H_A, H_B, i, eps, &Ap, &Bp);
    Perturb(H_A, H_B, i, -eps, &Am, &Bm);
    J.col(i) = (f(Ap, Bp) - f(Am, Bm)) / (2.0 * eps);
  }
  return J;
}

struct InternalCase {
  Section section;
  RodElement element;
  SE3 H_A, H_B;
  Vec3 w_ref;
};

// Checks g_int = grad V and K_t = d g_int / dq by finite differences; returns the errors.
void CheckInternalDerivatives(const InternalCase& c, double* force_error, double* stiffness_error) {
  RodInternal in;
  CalcRodInternal(c.element, c.section, c.H_A, c.H_B, c.w_ref, &in);
  const std::function<Eigen::Matrix<double, 1, 1>(const SE3&, const SE3&)> energy =
      [&](const SE3& A, const SE3& B) {
        RodInternal r;
        CalcRodInternal(c.element, c.section, A, B, c.w_ref, &r);
        return Eigen::Matrix<double, 1, 1>(r.energy);
      };
  const std::function<Vec12(const SE3&, const SE3&)> force = [&](const SE3& A, const SE3& B) {
    RodInternal r;
    CalcRodInternal(c.element, c.section, A, B, c.w_ref, &r);
    return r.force;
  };
  const Vec12 grad = FiniteDifference<1>(energy, c.H_A, c.H_B, 1e-5).transpose();
  const Mat12 K = FiniteDifference<12>(force, c.H_A, c.H_B, 1e-5);
  *force_error = RelativeError(in.force, grad);
  *stiffness_error = RelativeError(in.stiffness, K);
}

Section IsotropicSection() {
  return Section::FromDiagonals(MakeVec6(40.0, 15.0, 15.0, 2.0, 3.0, 3.0));
}
Section GeneralSection() {
  return Section::FromDiagonals(MakeVec6(55.0, 21.0, 9.0, 1.3, 4.1, 0.7));
}

// ---- relative motion and branch ----

TEST(RodRelativeMotion, ReproducesTheRelativeMotionOnThePrincipalBranch) {
  std::mt19937 rng(11);
  for (int k = 0; k < 20; ++k) {
    const SE3 H_A = RandomFrame(rng);
    const Vec6 d = RandomRelativeMotion(rng, 0.1 + 2.9 * k / 20.0, 1.5);
    const Vec6 got = CalcRodRelativeMotion(H_A, H_A * ExpSE3(d), Vec3::Zero());
    EXPECT_LT((got - d).norm(), 1e-12 * d.norm()) << "case " << k;
  }
}

TEST(RodRelativeMotion, FollowsTheBranchOfTheReferenceRotationPastPi) {
  std::mt19937 rng(12);
  const SE3 H_A = RandomFrame(rng);
  const Vec6 d = RandomRelativeMotion(rng, 4.0, 1.0);  // beyond pi: not the principal log
  const SE3 H_B = H_A * ExpSE3(d);
  // Reference on the far branch: d itself is recovered (rotation and recomputed translation).
  const Vec6 far = CalcRodRelativeMotion(H_A, H_B, d.tail<3>() * 0.9);
  EXPECT_LT((far - d).norm(), 1e-12 * d.norm());
  // Reference at zero: the principal branch, rotation 2 pi - 4 about the opposite axis.
  const Vec6 principal = CalcRodRelativeMotion(H_A, H_B, Vec3::Zero());
  EXPECT_NEAR(principal.tail<3>().norm(), 2.0 * kPi - 4.0, 1e-12);
  EXPECT_NEAR(principal.tail<3>().dot(d.tail<3>()), -(2.0 * kPi - 4.0) * 4.0, 1e-11);
  // Both describe the same relative frame.
  const SE3 back = H_A * ExpSE3(principal);
  EXPECT_LT((back.R - H_B.R).norm(), 1e-12);
  EXPECT_LT((back.x - H_B.x).norm(), 1e-12);
}

// ---- internal force and tangent ----

TEST(RodInternal, ForceAndStressVanishInTheReferenceConfiguration) {
  std::mt19937 rng(13);
  const Vec6 d0 = MakeVec6(1.2, 0.1, -0.2, 0.4, -0.3, 0.5);
  const RodElement el = MakeElement(d0);
  const SE3 H_A = RandomFrame(rng);
  RodInternal in;
  CalcRodInternal(el, GeneralSection(), H_A, H_A * ExpSE3(d0), d0.tail<3>(), &in);
  EXPECT_LT(in.stress.norm(), 1e-13);
  EXPECT_LT(in.force.norm(), 1e-13);
  EXPECT_LT(std::abs(in.energy), 1e-26);
}

TEST(RodInternal, EnergyStrainAndStressFollowTheConstitutiveLaw) {
  std::mt19937 rng(14);
  const Vec6 d0 = MakeVec6(1.3, 0.0, 0.0, 0.0, 0.0, 0.0);
  const RodElement el = MakeElement(d0);
  const Section sec = GeneralSection();
  const SE3 H_A = RandomFrame(rng);
  const Vec6 d = RandomRelativeMotion(rng, 2.0, 1.3);
  RodInternal in;
  CalcRodInternal(el, sec, H_A, H_A * ExpSE3(d), d.tail<3>(), &in);
  const Vec6 strain = (d - d0) / 1.3;
  EXPECT_LT((in.d - d).norm(), 1e-12);
  EXPECT_LT((in.strain - strain).norm(), 1e-12);
  EXPECT_LT((in.stress - sec.stiffness.cwiseProduct(strain)).norm(), 1e-11);
  EXPECT_NEAR(in.energy, 0.5 * 1.3 * strain.dot(sec.stiffness.cwiseProduct(strain)), 1e-12);
}

TEST(RodInternal, ForceIsEnergyGradientAndTangentIsForceDerivativeForLargeRotations) {
  // Straight reference, isotropic section, |relative rotation| from 0.05 to 2.5 rad.
  std::mt19937 rng(2024);
  const RodElement el = MakeElement(MakeVec6(1.3, 0.0, 0.0, 0.0, 0.0, 0.0));
  for (int k = 0; k < 12; ++k) {
    InternalCase c{IsotropicSection(), el, RandomFrame(rng), SE3(), Vec3::Zero()};
    const Vec6 d = RandomRelativeMotion(rng, 0.05 + 2.45 * k / 11.0, 1.3);
    c.H_B = c.H_A * ExpSE3(d);
    c.w_ref = d.tail<3>();
    double ef = 0.0, ek = 0.0;
    CheckInternalDerivatives(c, &ef, &ek);
    EXPECT_LT(ef, 1e-7) << "case " << k << " |w| = " << d.tail<3>().norm();
    EXPECT_LT(ek, 1e-6) << "case " << k << " |w| = " << d.tail<3>().norm();
  }
}

TEST(RodInternal, ForceAndTangentAreConsistentOnTheFarBranchPastPi) {
  // Relative rotation 4 rad with w_ref on that branch (elements/rod.h): the principal log would
  // give 2 pi - 4 about the opposite axis; the element must use the continued branch.
  std::mt19937 rng(2025);
  for (const double rotation : {3.5, 4.0, 5.5}) {
    InternalCase c{GeneralSection(), MakeElement(MakeVec6(1.1, 0.0, 0.0, 0.0, 0.0, 0.0)),
                   RandomFrame(rng), SE3(), Vec3::Zero()};
    const Vec6 d = RandomRelativeMotion(rng, rotation, 1.1);
    c.H_B = c.H_A * ExpSE3(d);
    c.w_ref = d.tail<3>();
    RodInternal in;
    CalcRodInternal(c.element, c.section, c.H_A, c.H_B, c.w_ref, &in);
    ASSERT_NEAR(in.d.tail<3>().norm(), rotation, 1e-12);
    double ef = 0.0, ek = 0.0;
    CheckInternalDerivatives(c, &ef, &ek);
    EXPECT_LT(ef, 1e-7) << "rotation " << rotation;
    EXPECT_LT(ek, 1e-6) << "rotation " << rotation;
  }
}

TEST(RodInternal, ForceAndTangentAreConsistentForCurvedReferenceAndGeneralSection) {
  std::mt19937 rng(2026);
  const RodElement el = MakeElement(MakeVec6(1.0, 0.2, -0.1, 0.3, -0.5, 0.8));
  for (int k = 0; k < 8; ++k) {
    InternalCase c{GeneralSection(), el, RandomFrame(rng), SE3(), Vec3::Zero()};
    const Vec6 d = RandomRelativeMotion(rng, 0.3 + 2.2 * k / 7.0, 1.0);
    c.H_B = c.H_A * ExpSE3(d);
    c.w_ref = d.tail<3>();
    double ef = 0.0, ek = 0.0;
    CheckInternalDerivatives(c, &ef, &ek);
    EXPECT_LT(ef, 1e-7) << "case " << k;
    EXPECT_LT(ek, 1e-6) << "case " << k;
  }
}

TEST(RodInternal, GeometricStiffnessTermIsSignificant) {
  // The tangent without the geometric term, (1/L) P^T K P, is far from the FD tangent: the
  // FD check above therefore really tests the D(d, sigma) terms of elements/rod.h.
  std::mt19937 rng(2027);
  const RodElement el = MakeElement(MakeVec6(1.3, 0.0, 0.0, 0.0, 0.0, 0.0));
  const SE3 H_A = RandomFrame(rng);
  const Vec6 d = RandomRelativeMotion(rng, 1.5, 1.3);
  RodInternal in;
  CalcRodInternal(el, IsotropicSection(), H_A, H_A * ExpSE3(d), d.tail<3>(), &in);
  const Mat6x12 P = CalcRodP(in.d);
  const Mat12 material = P.transpose() * (IsotropicSection().stiffness / 1.3).asDiagonal() * P;
  EXPECT_GT(RelativeError(material, in.stiffness), 0.05);
}

TEST(RodInternal, ForcesAreObjective) {
  // A superposed rigid motion G of both nodes leaves the node-frame forces unchanged.
  std::mt19937 rng(2028);
  const RodElement el = MakeElement(MakeVec6(1.0, 0.2, -0.1, 0.3, -0.5, 0.8));
  const SE3 H_A = RandomFrame(rng);
  const Vec6 d = RandomRelativeMotion(rng, 2.2, 1.0);
  const SE3 H_B = H_A * ExpSE3(d);
  const SE3 G = RandomFrame(rng);
  RodInternal a, b;
  CalcRodInternal(el, GeneralSection(), H_A, H_B, d.tail<3>(), &a);
  CalcRodInternal(el, GeneralSection(), G * H_A, G * H_B, d.tail<3>(), &b);
  EXPECT_LT((a.force - b.force).norm(), 1e-11 * a.force.norm());
  EXPECT_LT((a.stiffness - b.stiffness).norm(), 1e-11 * a.stiffness.norm());
}

// ---- P and N ----

TEST(RodP, GivesTheTimeDerivativeOfTheRelativeMotion) {
  std::mt19937 rng(31);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const double rotation : {0.0, 1e-3, 0.7, 2.0, 3.0, 4.0}) {
    const SE3 H_A = RandomFrame(rng);
    const Vec6 d = RandomRelativeMotion(rng, rotation, 1.2);
    const SE3 H_B = H_A * ExpSE3(d);
    Vec12 eta;
    for (int i = 0; i < 12; ++i) eta(i) = n(rng);
    const double h = 1e-5;
    auto d_at = [&](double t) {
      return CalcRodRelativeMotion(H_A * ExpSE3(t * eta.head<6>()), H_B * ExpSE3(t * eta.tail<6>()),
                                   d.tail<3>());
    };
    const Vec6 fd = (d_at(h) - d_at(-h)) / (2.0 * h);
    const Vec6 analytic = CalcRodP(d) * eta;
    EXPECT_LT((analytic - fd).norm(), 1e-8 * fd.norm()) << "rotation " << rotation;
  }
}

TEST(RodN, InterpolatesTheNodeVelocitiesAtTheEnds) {
  std::mt19937 rng(32);
  const Vec6 d = RandomRelativeMotion(rng, 2.3, 1.0);
  Mat6x12 left, right;
  left << Mat6::Identity(), Mat6::Zero();
  right << Mat6::Zero(), Mat6::Identity();
  EXPECT_LT((CalcRodN(0.0, d) - left).norm(), 1e-14);
  EXPECT_LT((CalcRodN(1.0, d) - right).norm(), 1e-12);
}

TEST(RodN, IsTheExactVelocityFieldOfTheHelicalInterpolation) {
  // eta(xi) = N(xi, d) [eta_A; eta_B] is the body velocity of H_A(t) exp(xi d(t)).
  std::mt19937 rng(33);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const double rotation : {0.0, 0.8, 2.5, 4.0}) {
    const SE3 H_A = RandomFrame(rng);
    const Vec6 d = RandomRelativeMotion(rng, rotation, 1.2);
    const SE3 H_B = H_A * ExpSE3(d);
    Vec12 eta;
    for (int i = 0; i < 12; ++i) eta(i) = n(rng);
    for (const double xi : {0.0, 0.21, 0.5, 0.77, 1.0}) {
      auto H_at = [&](double t) {
        const SE3 A = H_A * ExpSE3(t * eta.head<6>());
        const SE3 B = H_B * ExpSE3(t * eta.tail<6>());
        return A * ExpSE3(xi * CalcRodRelativeMotion(A, B, d.tail<3>()));
      };
      const double h = 1e-5;
      const SE3 H0 = H_at(0.0);
      const Vec6 fd =
          (LogSE3(H0.Inverse() * H_at(h)) - LogSE3(H0.Inverse() * H_at(-h))) / (2.0 * h);
      const Vec6 analytic = CalcRodN(xi, d) * eta;
      EXPECT_LT((analytic - fd).norm(), 1e-8 * fd.norm())
          << "rotation " << rotation << " xi " << xi;
    }
  }
}

TEST(RodN, GaussVelocitiesWithoutNAreNTimesTheNodeVelocities) {
  // CalcRodGaussVelocities (the energy and momentum outputs): Ad(exp(-xi d)) eta_A +
  // xi T(xi d) P eta_AB at the Gauss points equals N(xi, d) eta_AB, and its frames exp(xi d);
  // small and large rotations (the series branch of T near 0).
  std::mt19937 rng(34);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const double rotation : {0.0, 1e-7, 0.8, 2.5, 4.0}) {
    const Vec6 d = RandomRelativeMotion(rng, rotation, 1.2);
    Vec12 eta_ab;
    for (int i = 0; i < 12; ++i) eta_ab(i) = n(rng);
    Vec6 eta[kRodGaussPoints];
    SE3 G[kRodGaussPoints];
    CalcRodGaussVelocities(d, eta_ab, eta, &G);
    for (int i = 0; i < kRodGaussPoints; ++i) {
      const Vec6 expected = CalcRodN(kRodGaussXi[i], d) * eta_ab;
      EXPECT_LT((eta[i] - expected).norm(), 1e-13 * eta_ab.norm()) << "rotation " << rotation;
      const SE3 g = ExpSE3(kRodGaussXi[i] * d);
      EXPECT_LT((G[i].R - g.R).norm() + (G[i].x - g.x).norm(), 1e-15);
    }
  }
}

// ---- distributed dead load ----

TEST(RodDistributedDeadForce, TangentIsTheDerivativeOfTheLoadVector) {
  std::mt19937 rng(41);
  const RodElement el = MakeElement(MakeVec6(1.0, 0.2, -0.1, 0.3, -0.5, 0.8));
  const Vec3 f_w(0.3, -2.0, 0.7);
  for (const double rotation : {0.5, 2.0, 4.0}) {
    const SE3 H_A = RandomFrame(rng);
    const Vec6 d = RandomRelativeMotion(rng, rotation, 1.0);
    const SE3 H_B = H_A * ExpSE3(d);
    const Vec3 w_ref = d.tail<3>();
    Vec12 g;
    Mat12 tangent;
    CalcRodDistributedDeadForce(el, H_A, d, f_w, &g, &tangent);
    const std::function<Vec12(const SE3&, const SE3&)> load = [&](const SE3& A, const SE3& B) {
      Vec12 gp;
      Mat12 tp;
      CalcRodDistributedDeadForce(el, A, CalcRodRelativeMotion(A, B, w_ref), f_w, &gp, &tp);
      return gp;
    };
    const Mat12 fd = FiniteDifference<12>(load, H_A, H_B, 1e-5);
    // tangent = -dg/dq (the residual contains -g).
    EXPECT_LT(RelativeError(-tangent, fd), 1e-7) << "rotation " << rotation;
  }
}

TEST(RodDistributedDeadForce, ResultantsOnAStraightElementAreExact) {
  // Total force f_w L and moment about node A (L^2 / 2) e_axis x f_w: the load vector does the
  // exact virtual work in every rigid motion of the element.
  std::mt19937 rng(42);
  const double L = 2.5;
  const RodElement el = MakeElement(MakeVec6(L, 0.0, 0.0, 0.0, 0.0, 0.0));
  const SE3 H_A = RandomFrame(rng);
  const Vec3 f_w(0.3, -2.0, 0.7);
  Vec12 g;
  Mat12 tangent;
  CalcRodDistributedDeadForce(el, H_A, el.d0, f_w, &g, &tangent);
  const Vec3 force_b = H_A.R * g.segment<3>(6);
  const Vec3 total = H_A.R * g.segment<3>(0) + force_b;
  EXPECT_LT((total - L * f_w).norm(), 1e-14 * L * f_w.norm());
  const Vec3 axis = H_A.R.col(0);
  const Vec3 moment_a = H_A.R * (g.segment<3>(3) + g.segment<3>(9)) + (L * axis).cross(force_b);
  EXPECT_LT((moment_a - 0.5 * L * L * axis.cross(f_w)).norm(), 1e-14 * L * L * f_w.norm());
}

TEST(RodDistributedDeadForce, TotalForceIsExactOnADeformedElement) {
  // Per unit reference length: the world resultant stays f_w L however the element deforms.
  std::mt19937 rng(43);
  const RodElement el = MakeElement(MakeVec6(1.0, 0.2, -0.1, 0.3, -0.5, 0.8));
  const Vec3 f_w(-1.0, 0.4, 2.0);
  for (const double rotation : {0.7, 2.5, 4.0}) {
    const SE3 H_A = RandomFrame(rng);
    const Vec6 d = RandomRelativeMotion(rng, rotation, 1.0);
    const SE3 H_B = H_A * ExpSE3(d);
    Vec12 g;
    Mat12 tangent;
    CalcRodDistributedDeadForce(el, H_A, d, f_w, &g, &tangent);
    const Vec3 total = H_A.R * g.segment<3>(0) + H_B.R * g.segment<3>(6);
    EXPECT_LT((total - el.length * f_w).norm(), 1e-13 * el.length * f_w.norm())
        << "rotation " << rotation;
  }
}

// ---- sections ----

TEST(Section, CircleHasTextbookPropertiesAndCowperShearCoefficient) {
  const double r = 0.05, E = 2.1e11, nu = 0.3, rho = 7800.0;
  const Section s = Section::Circle(r, Material{E, 0.0, nu, rho, 0.0});
  const double A = kPi * r * r, I = kPi * std::pow(r, 4) / 4.0, J = kPi * std::pow(r, 4) / 2.0;
  const double G = E / (2.0 * (1.0 + nu));
  const double kappa = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu);  // Cowper 1966
  EXPECT_NEAR(kappa, 0.886363636363636, 1e-14);
  const Vec6 expected = MakeVec6(E * A, kappa * G * A, kappa * G * A, G * J, E * I, E * I);
  EXPECT_LT((s.stiffness - expected).cwiseQuotient(expected).cwiseAbs().maxCoeff(), 1e-14);
  const Vec6 inertia = MakeVec6(rho * A, rho * A, rho * A, rho * J, rho * I, rho * I);
  EXPECT_LT((s.inertia - inertia).cwiseQuotient(inertia).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(Section, ExplicitShearModulusAndShearCoefficientAreUsed) {
  // PyElastica's Timoshenko case (validation S4): G = 1e4, kappa = 4/3, r = 0.25.
  const Section s = Section::Circle(0.25, Material{1e6, 1e4, -1.0, 5000.0, 4.0 / 3.0});
  EXPECT_NEAR(s.stiffness(1), 2617.99387799, 1e-8);
  EXPECT_NEAR(s.stiffness(2), 2617.99387799, 1e-8);
  EXPECT_NEAR(s.stiffness(4), 3067.96157577, 1e-8);
  EXPECT_NEAR(s.stiffness(0), 196349.540849, 1e-6);
  EXPECT_NEAR(s.stiffness(3), 1e4 * kPi * std::pow(0.25, 4) / 2.0, 1e-10);
}

TEST(Section, RectangleHasTextbookPropertiesAndTorsionConstant) {
  const double b = 0.04, h = 0.02, E = 7e10, nu = 0.33, rho = 2700.0;
  const Section s = Section::Rectangle(b, h, Material{E, 0.0, nu, rho, 0.0});
  const double A = b * h, G = E / (2.0 * (1.0 + nu));
  const double kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);  // Cowper 1966
  EXPECT_NEAR(s.stiffness(0) / (E * A), 1.0, 1e-14);
  EXPECT_NEAR(s.stiffness(1) / (kappa * G * A), 1.0, 1e-14);
  EXPECT_NEAR(s.stiffness(4) / (E * b * h * h * h / 12.0), 1.0, 1e-14);  // about axis 2
  EXPECT_NEAR(s.stiffness(5) / (E * h * b * b * b / 12.0), 1.0, 1e-14);  // about axis 3
  // Saint-Venant torsion constant J = k1 a b^3 (a >= b sides), Timoshenko & Goodier's table:
  // k1 = 0.1406 (a/b = 1), 0.229 (2), 0.312 (10), 1/3 (infinity). Roark's formula: < 0.5 %.
  const struct {
    double ratio, k1;
  } table[] = {{1.0, 0.1406}, {2.0, 0.229}, {10.0, 0.312}, {1000.0, 1.0 / 3.0}};
  for (const auto& row : table) {
    const double t = 0.01, w = row.ratio * t;
    const Section r = Section::Rectangle(w, t, Material{E, 0.0, nu, rho, 0.0});
    const double J = r.stiffness(3) / G;
    EXPECT_NEAR(J / (row.k1 * w * t * t * t), 1.0, 5e-3) << "a/b = " << row.ratio;
    // Symmetric in width and height.
    const Section rt = Section::Rectangle(t, w, Material{E, 0.0, nu, rho, 0.0});
    EXPECT_NEAR(rt.stiffness(3), r.stiffness(3), 1e-12 * r.stiffness(3));
  }
}

TEST(Section, TubeHasTextbookPropertiesAndCowperLimits) {
  const double ro = 0.05, ri = 0.04, E = 2e11, nu = 0.3;
  const Section s = Section::Tube(ro, ri, Material{E, 0.0, nu, 0.0, 0.0});
  const double A = kPi * (ro * ro - ri * ri);
  const double I = kPi * (std::pow(ro, 4) - std::pow(ri, 4)) / 4.0;
  const double G = E / (2.0 * (1.0 + nu));
  EXPECT_NEAR(s.stiffness(0) / (E * A), 1.0, 1e-14);
  EXPECT_NEAR(s.stiffness(3) / (G * 2.0 * I), 1.0, 1e-14);
  EXPECT_NEAR(s.stiffness(4) / (E * I), 1.0, 1e-14);
  const double m2 = (ri / ro) * (ri / ro);
  const double kappa = 6.0 * (1.0 + nu) * (1.0 + m2) * (1.0 + m2) /
                       ((7.0 + 6.0 * nu) * (1.0 + m2) * (1.0 + m2) + (20.0 + 12.0 * nu) * m2);
  EXPECT_NEAR(s.stiffness(1) / (kappa * G * A), 1.0, 1e-14);
  // Limits: a tube without a hole is the solid circle; a thin-walled tube has Cowper's
  // kappa = 2 (1 + nu) / (4 + 3 nu).
  const Section solid = Section::Tube(ro, 0.0, Material{E, 0.0, nu, 0.0, 0.0});
  const Section circle = Section::Circle(ro, Material{E, 0.0, nu, 0.0, 0.0});
  EXPECT_LT(
      (solid.stiffness - circle.stiffness).cwiseQuotient(circle.stiffness).cwiseAbs().maxCoeff(),
      1e-14);
  const Section thin = Section::Tube(ro, ro * (1.0 - 1e-6), Material{E, 0.0, nu, 0.0, 0.0});
  EXPECT_NEAR(thin.stiffness(1) / (G * thin.stiffness(0) / E), 2.0 * (1.0 + nu) / (4.0 + 3.0 * nu),
              1e-5);
}

TEST(Section, InvalidInputThrowsInputError) {
  const Material steel{2e11, 0.0, 0.3, 7800.0, 0.0};
  EXPECT_THROW(Section::Circle(0.0, steel), InputError);
  EXPECT_THROW(Section::Circle(-1.0, steel), InputError);
  EXPECT_THROW(Section::Rectangle(0.0, 1.0, steel), InputError);
  EXPECT_THROW(Section::Rectangle(1.0, -1.0, steel), InputError);
  EXPECT_THROW(Section::Tube(0.05, 0.05, steel), InputError);
  EXPECT_THROW(Section::Tube(0.05, 0.06, steel), InputError);
  EXPECT_THROW(Section::Tube(0.05, -0.01, steel), InputError);
  EXPECT_THROW(Section::Circle(0.1, Material{0.0, 0.0, 0.3, 1.0, 0.0}), InputError);
  EXPECT_THROW(Section::Circle(0.1, Material{-1.0, 0.0, 0.3, 1.0, 0.0}), InputError);
  EXPECT_THROW(Section::Circle(0.1, Material{1.0, 0.0, 0.3, -1.0, 0.0}), InputError);
  EXPECT_THROW(Section::Circle(0.1, Material{1.0, 0.0, 0.6, 1.0, 0.0}), InputError);
  EXPECT_THROW(Section::Circle(0.1, Material{1.0, 0.0, -1.0, 1.0, 0.0}), InputError);
  EXPECT_THROW(Section::Circle(0.1, Material{NAN, 0.0, 0.3, 1.0, 0.0}), InputError);
  EXPECT_THROW(Section::FromDiagonals(MakeVec6(1.0, 1.0, 0.0, 1.0, 1.0, 1.0)), InputError);
  EXPECT_THROW(Section::FromDiagonals(Vec6::Ones(), -Vec6::Ones()), InputError);
}

}  // namespace
}  // namespace screwfem::rod_test
