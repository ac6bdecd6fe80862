// Loads on the sections of a helical element (AddRodSectionLoad): the tangent is the exact
// derivative of the generalised force, and the generalised forces are statically equivalent to
// the applied force and moment for any deformation (exact virtual work of rigid motions).
#include <gtest/gtest.h>

#include <random>

#include "screwfem/elements/rod.h"

namespace screwfem::rod_load_test {
namespace {

struct Config {
  SE3 A, B;
  Vec3 w_ref;
};

Config RandomBentElement(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec6 xa, d;
  for (int i = 0; i < 6; ++i) xa(i) = u(rng);
  d << 1.0 + 0.2 * u(rng), 0.1 * u(rng), 0.1 * u(rng), 1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng);
  Config c;
  c.A = ExpSE3(xa);
  c.B = c.A * ExpSE3(d);
  c.w_ref = d.tail<3>();
  return c;
}

void Generalized(const Config& c, double xi, LoadFrame frame, const Vec3& f, const Vec3& m,
                 Vec12* g, Mat12* K) {
  g->setZero();
  K->setZero();
  const Vec6 d = CalcRodRelativeMotion(c.A, c.B, c.w_ref);
  AddRodSectionLoad(xi, 0.7, c.A, d, frame, f, m, g, K);
}

TEST(RodSectionLoad, TangentIsTheDerivativeOfTheGeneralisedForce) {
  std::mt19937 rng(7);
  for (LoadFrame frame : {LoadFrame::kWorld, LoadFrame::kBody}) {
    for (int trial = 0; trial < 4; ++trial) {
      const Config c = RandomBentElement(rng);
      const double xi = 0.15 + 0.2 * trial;
      const Vec3 f(0.3, -1.2, 0.8), m(0.5, 0.2, -0.7);
      Vec12 g;
      Mat12 K;
      Generalized(c, xi, frame, f, m, &g, &K);
      Mat12 fd;
      const double e = 1e-6;
      for (int j = 0; j < 12; ++j) {
        Config cp = c, cm = c;
        Vec6 dh = Vec6::Zero();
        dh(j % 6) = e;
        (j < 6 ? cp.A : cp.B) = (j < 6 ? c.A : c.B) * ExpSE3(dh);
        (j < 6 ? cm.A : cm.B) = (j < 6 ? c.A : c.B) * ExpSE3(-dh);
        Vec12 gp, gm;
        Mat12 unused;
        Generalized(cp, xi, frame, f, m, &gp, &unused);
        Generalized(cm, xi, frame, f, m, &gm, &unused);
        fd.col(j) = -(gp - gm) / (2 * e);  // the tangent belongs to the residual term -g
      }
      EXPECT_LT((K - fd).norm(), 1e-7 * std::max(1.0, fd.norm()))
          << (frame == LoadFrame::kWorld ? "dead" : "follower") << " load, trial " << trial;
    }
  }
}

TEST(RodSectionLoad, NodalForcesAreStaticallyEquivalentToTheAppliedLoad) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const Config c = RandomBentElement(rng);
    const double xi = 0.1 + 0.2 * trial;
    const Vec3 f(1.0, -2.0, 0.5), m(-0.4, 0.3, 0.9);
    Vec12 g;
    Mat12 K;
    Generalized(c, xi, LoadFrame::kWorld, f, m, &g, &K);
    const Vec6 d = CalcRodRelativeMotion(c.A, c.B, c.w_ref);
    const SE3 H = c.A * ExpSE3(xi * d);  // the loaded section
    // Resultant force and moment about the world origin, in world components.
    const Vec3 FA = c.A.R * g.segment<3>(0), FB = c.B.R * g.segment<3>(6);
    const Vec3 MA = c.A.R * g.segment<3>(3), MB = c.B.R * g.segment<3>(9);
    const Vec3 force = FA + FB;
    const Vec3 moment = c.A.x.cross(FA) + c.B.x.cross(FB) + MA + MB;
    EXPECT_LT((force - 0.7 * f).norm(), 1e-12);
    EXPECT_LT((moment - 0.7 * (H.x.cross(f) + m)).norm(), 1e-12);
  }
}

TEST(RodDistributedDeadForce, EqualsTheSectionLoadsAtTheGaussPointsWithTheirTangent) {
  // CalcRodDistributedDeadForce (through AddRodDistributedDeadForce and RodGeometry) against the
  // three section loads it stands for, L w_i N_i^T F_i, computed by AddRodSectionLoad.
  std::mt19937 rng(13);
  for (int trial = 0; trial < 5; ++trial) {
    const Config c = RandomBentElement(rng);
    const Vec6 d = CalcRodRelativeMotion(c.A, c.B, c.w_ref);
    RodElement el;
    el.length = 0.8 + 0.1 * trial;
    const Vec3 f(0.2, -0.5, -9.81);
    Vec12 g, g_ref = Vec12::Zero();
    Mat12 K, K_ref = Mat12::Zero();
    CalcRodDistributedDeadForce(el, c.A, d, f, &g, &K);
    for (int i = 0; i < kRodGaussPoints; ++i)
      AddRodSectionLoad(kRodGaussXi[i], el.length * kRodGaussW[i], c.A, d, LoadFrame::kWorld, f,
                        Vec3::Zero(), &g_ref, &K_ref);
    EXPECT_LT((g - g_ref).norm(), 1e-13 * g_ref.norm()) << "trial " << trial;
    EXPECT_LT((K - K_ref).norm(), 1e-12 * K_ref.norm()) << "trial " << trial;
    // Without the tangent, the same force.
    RodGeometry geometry;
    CalcRodGeometry(d, true, false, &geometry);
    Vec12 g_only = Vec12::Zero();
    AddRodDistributedDeadForce(el, geometry, c.A, f, &g_only, nullptr);
    for (int i = 0; i < 12; ++i) EXPECT_EQ(g_only(i), g(i)) << "trial " << trial;
  }
}

TEST(RodDistributedDeadForce, AgreesWithTheSectionLoadsOverTheWholeRotationRange) {
  // The kernel works from the potential of the load (closed forms of J(v) and its derivatives
  // above |v| = 1, Taylor series below): straight, nearly straight, either side of the switch
  // at the Gauss points (xi_i |w| = 1) and large rotations, against the section loads.
  const double angles[] = {0.0,
                           1e-7,
                           1e-3,
                           0.3,
                           1.0 / kRodGaussXi[0],
                           1.0 / kRodGaussXi[1],
                           0.999 / kRodGaussXi[2],
                           1.001 / kRodGaussXi[2],
                           3.0,
                           5.5,
                           6.2};
  const Vec3 axis = Vec3(0.3, -0.8, 0.5).normalized();
  for (double angle : angles) {
    SE3 A;
    A.R = ExpSO3(Vec3(0.4, 0.1, -0.7));
    A.x = Vec3(0.2, -0.1, 0.3);
    Vec6 d;
    d << 0.9, 0.05, -0.1, angle * axis;
    RodElement el;
    el.length = 0.9;
    const Vec3 f(0.2, -0.5, -9.81);
    Vec12 g, g_ref = Vec12::Zero();
    Mat12 K, K_ref = Mat12::Zero();
    CalcRodDistributedDeadForce(el, A, d, f, &g, &K);
    for (int i = 0; i < kRodGaussPoints; ++i)
      AddRodSectionLoad(kRodGaussXi[i], el.length * kRodGaussW[i], A, d, LoadFrame::kWorld, f,
                        Vec3::Zero(), &g_ref, &K_ref);
    EXPECT_LT((g - g_ref).norm(), 1e-13 * g_ref.norm()) << "angle " << angle;
    EXPECT_LT((K - K_ref).norm(), 1e-12 * K_ref.norm()) << "angle " << angle;
  }
}

TEST(RodConservative, EqualsInternalMinusDeadForceWithTheNodeTangentsApplied) {
  // CalcRodConservative (the assembly's kernel) against its two parts computed separately,
  // with and without weight, with and without the node tangent operators T_A, T_B.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    const Config c = RandomBentElement(rng);
    const Vec6 d = CalcRodRelativeMotion(c.A, c.B, c.w_ref);
    RodElement el;
    el.length = 0.7 + 0.1 * trial;
    el.d0 << el.length, 0.0, 0.0, 0.1, 0.0, -0.2;
    Section sec;
    sec.stiffness << 3e3, 1e3, 2e3, 4.0, 5.0, 6.0;
    const Vec3 f = trial % 3 == 0 ? Vec3::Zero() : Vec3(0.3, -0.2, -9.81);
    RodGeometry geo;
    CalcRodGeometry(d, false, false, &geo);
    RodInternal in;
    CalcRodInternal(el, sec, geo, true, &in);
    Vec12 g = Vec12::Zero();
    Mat12 Kg = Mat12::Zero();
    AddRodDistributedDeadForce(el, geo, c.A, f, &g, &Kg);
    const Vec12 force_ref = in.force - g;
    Mat12 K_ref = in.stiffness + Kg;
    Vec6 xa, xb;
    for (int i = 0; i < 6; ++i) {
      xa(i) = 0.3 * u(rng);
      xb(i) = 0.3 * u(rng);
    }
    const Mat6 TA = TSE3(xa), TB = TSE3(xb);
    Vec12 force;
    Mat12 K, KT;
    CalcRodConservative(el, sec, geo, c.A, f, nullptr, nullptr, &force, &K);
    EXPECT_LT((force - force_ref).norm(), 1e-13 * force_ref.norm()) << "trial " << trial;
    EXPECT_LT((K - K_ref).norm(), 1e-13 * K_ref.norm()) << "trial " << trial;
    CalcRodConservative(el, sec, geo, c.A, f, &TA, &TB, &force, &KT);
    K_ref.leftCols<6>() = K_ref.leftCols<6>() * TA;
    K_ref.rightCols<6>() = K_ref.rightCols<6>() * TB;
    EXPECT_LT((KT - K_ref).norm(), 1e-13 * K_ref.norm()) << "trial " << trial;
    Vec12 force_only;
    CalcRodConservative(el, sec, geo, c.A, f, nullptr, nullptr, &force_only, nullptr);
    for (int i = 0; i < 12; ++i) EXPECT_EQ(force_only(i), force(i)) << "trial " << trial;
  }
}

}  // namespace
}  // namespace screwfem::rod_load_test
