// Tests of rod actuation in the element kernel (docs/numerics.md, "Active stress and rest strain"): with a rest-strain
// change eps0 and an active stress sigma_a, sigma = K (eps - eps0) - sigma_a, the force is the
// gradient of V = L/2 (eps - eps0)^T K (eps - eps0) - L eps^T sigma_a and the tangent (the same
// formula with the total sigma) is the derivative of the force; both are checked by central
// finite differences through the retraction H <- H ExpSE3(eps e_i), w_ref held fixed. The
// element kind's actuation (actuators of a built model, profiles, load factor) is checked too.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/rod.h"
#include "screwfem/model/section.h"

namespace screwfem::actuation_test {
namespace {

Vec6 V6(double a, double b, double c, double d, double e, double f) {
  Vec6 v;
  v << a, b, c, d, e, f;
  return v;
}

// Central differences over the 12 right-trivialised directions of the two node frames.
template <int Rows>
Eigen::Matrix<double, Rows, 12> FiniteDifference(
    const std::function<Eigen::Matrix<double, Rows, 1>(const SE3&, const SE3&)>& f, const SE3& A,
    const SE3& B, double eps) {
  Eigen::Matrix<double, Rows, 12> J;
  for (int i = 0; i < 12; ++i) {
    const Vec6 dh = eps * Vec6::Unit(i % 6);
    const SE3 Ap = i < 6 ? A * ExpSE3(dh) : A, Am = i < 6 ? A * ExpSE3(-dh) : A;
    const SE3 Bp = i < 6 ? B : B * ExpSE3(dh), Bm = i < 6 ? B : B * ExpSE3(-dh);
    J.col(i) = (f(Ap, Bp) - f(Am, Bm)) / (2.0 * eps);
  }
  return J;
}

struct Case {
  Section section = Section::FromDiagonals(V6(2e3, 8e2, 9e2, 3.0, 5.0, 7.0));
  RodElement element;
  SE3 H_A, H_B;
  RodActuation act;
};

// A curved reference element, deformed with a large rotation, with all six components of
// eps0 and sigma_a nonzero.
Case MakeCase(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Case c;
  c.element.rod = 0;
  c.element.node_a = 0;
  c.element.node_b = 1;
  c.element.d0 = V6(0.3, 0.02, -0.01, 0.1, -0.2, 0.4);
  c.element.length = c.element.d0.head<3>().norm();
  c.H_A = SE3{ExpSO3(Vec3(u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng))};
  const Vec6 d = c.element.d0 + V6(0.03 * u(rng), 0.02 * u(rng), 0.02 * u(rng), 1.5 * u(rng),
                                   1.5 * u(rng), 1.5 * u(rng));
  c.H_B = c.H_A * ExpSE3(d);
  for (int i = 0; i < 6; ++i) {
    c.act.rest_strain(i) = (i < 3 ? 0.01 : 2.0) * u(rng);
    c.act.active_stress(i) = (i < 3 ? 20.0 : 3.0) * u(rng);
  }
  return c;
}

TEST(RodActuationKernel, StressIsElasticMinusActiveWithRestStrainRemoved) {
  const Case c = MakeCase(1);
  RodInternal in;
  CalcRodInternal(c.element, c.section, c.H_A, c.H_B, Vec3::Zero(), &in, &c.act);
  const Vec6 elastic = c.section.stiffness.cwiseProduct(in.strain - c.act.rest_strain);
  EXPECT_LT((in.elastic_stress - elastic).norm(), 1e-12 * elastic.norm());
  EXPECT_LT((in.stress - (elastic - c.act.active_stress)).norm(), 1e-12 * elastic.norm());
  // With eps0 equal to the current strain the material is unstressed and the section
  // transmits -sigma_a alone.
  RodActuation at_rest = c.act;
  at_rest.rest_strain = in.strain;
  RodInternal r;
  CalcRodInternal(c.element, c.section, c.H_A, c.H_B, Vec3::Zero(), &r, &at_rest);
  EXPECT_LT(r.elastic_stress.norm(), 1e-9);
  EXPECT_LT((r.stress + c.act.active_stress).norm(), 1e-9);
}

TEST(RodActuationKernel, ForceIsEnergyGradientAndTangentIsForceDerivative) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(seed);
    const Case c = MakeCase(seed);
    RodInternal in;
    CalcRodInternal(c.element, c.section, c.H_A, c.H_B, Vec3::Zero(), &in, &c.act);
    const std::function<Eigen::Matrix<double, 1, 1>(const SE3&, const SE3&)> energy =
        [&](const SE3& A, const SE3& B) {
          RodInternal r;
          CalcRodInternal(c.element, c.section, A, B, Vec3::Zero(), &r, &c.act);
          return Eigen::Matrix<double, 1, 1>(r.energy);
        };
    const std::function<Vec12(const SE3&, const SE3&)> force = [&](const SE3& A, const SE3& B) {
      RodInternal r;
      CalcRodInternal(c.element, c.section, A, B, Vec3::Zero(), &r, &c.act);
      return r.force;
    };
    const Vec12 grad = FiniteDifference<1>(energy, c.H_A, c.H_B, 1e-5).transpose();
    const Mat12 K = FiniteDifference<12>(force, c.H_A, c.H_B, 1e-5);
    EXPECT_LT((grad - in.force).norm(), 1e-7 * in.force.norm());
    EXPECT_LT((K - in.stiffness).norm(), 1e-7 * in.stiffness.norm());
    // The actuation's share of the tangent (geometric term with sigma_a and K eps0) is not
    // negligible in this case: the unactuated tangent differs.
    RodInternal plain;
    CalcRodInternal(c.element, c.section, c.H_A, c.H_B, Vec3::Zero(), &plain);
    EXPECT_GT((plain.stiffness - in.stiffness).norm(), 1e-3 * in.stiffness.norm());
  }
}

TEST(RodActuationKernel, ConservativeKernelWithWeightAndNodeTangentsMatchesFiniteDifferences) {
  const Case c = MakeCase(7);
  RodGeometry geo;
  CalcRodGeometry(c.H_A, c.H_B, Vec3::Zero(), false, false, &geo);
  const Vec3 f_w(0.3, -2.0, 0.5);
  Vec12 force;
  Mat12 K;
  CalcRodConservative(c.element, c.section, geo, c.H_A, f_w, nullptr, nullptr, &force, &K, &c.act);
  // Force = internal (actuated) minus the distributed dead force.
  RodInternal in;
  CalcRodInternal(c.element, c.section, geo, false, &in, &c.act);
  Vec12 dead;
  Mat12 dead_tangent;
  CalcRodDistributedDeadForce(c.element, c.H_A, geo.d, f_w, &dead, &dead_tangent);
  EXPECT_LT((force - (in.force - dead)).norm(), 1e-12 * force.norm());
  const std::function<Vec12(const SE3&, const SE3&)> f = [&](const SE3& A, const SE3& B) {
    RodGeometry g;
    CalcRodGeometry(A, B, Vec3::Zero(), false, false, &g);
    Vec12 r;
    CalcRodConservative(c.element, c.section, g, A, f_w, nullptr, nullptr, &r, nullptr, &c.act);
    return r;
  };
  const Mat12 fd = FiniteDifference<12>(f, c.H_A, c.H_B, 1e-5);
  EXPECT_LT((fd - K).norm(), 1e-7 * K.norm());
  // With node tangent operators: K blockdiag(T_A, T_B).
  const Mat6 TA = TSE3(V6(0.01, 0.02, -0.01, 0.05, -0.02, 0.03));
  const Mat6 TB = TSE3(V6(-0.02, 0.01, 0.03, -0.04, 0.06, 0.01));
  Mat12 KT;
  CalcRodConservative(c.element, c.section, geo, c.H_A, f_w, &TA, &TB, &force, &KT, &c.act);
  Mat12 expected = K;
  expected.leftCols<6>() = K.leftCols<6>() * TA;
  expected.rightCols<6>() = K.rightCols<6>() * TB;
  EXPECT_LT((KT - expected).norm(), 1e-12 * K.norm());
}

TEST(RodActuationKernel, RestStrainAndEquivalentActiveStressGiveTheSameForceAndTangent) {
  // sigma_a = K eps0 (docs/numerics.md, "Active stress and rest strain"): the same equilibria, the same element terms.
  const Case c = MakeCase(3);
  RodActuation a, b;
  a.rest_strain = c.act.rest_strain;
  b.active_stress = c.section.stiffness.cwiseProduct(c.act.rest_strain);
  RodInternal ra, rb;
  CalcRodInternal(c.element, c.section, c.H_A, c.H_B, Vec3::Zero(), &ra, &a);
  CalcRodInternal(c.element, c.section, c.H_A, c.H_B, Vec3::Zero(), &rb, &b);
  EXPECT_LT((ra.force - rb.force).norm(), 1e-12 * ra.force.norm());
  EXPECT_LT((ra.stiffness - rb.stiffness).norm(), 1e-12 * ra.stiffness.norm());
  // ... but not the same elastic stress (what the section's material carries).
  EXPECT_GT((ra.elastic_stress - rb.elastic_stress).norm(), 0.1 * b.active_stress.norm());
}

// A two-rod model with actuators over parts of the first rod.
Model ActuatedModel() {
  ModelBuilder b;
  const Section s = Section::FromDiagonals(V6(1e5, 1e5, 1e5, 1.0, 1.0, 1.0));
  b.AddStraightRod("a", Vec3::Zero(), Vec3::UnitX(), 4, s);
  b.AddStraightRod("b", Vec3(0, 1, 0), Vec3(1, 1, 0), 2, s);
  b.FixNode(NodeId(0));
  b.FixNode(NodeId(5));
  const InputId input = b.AddInput("p", 2.0);
  Actuator chamber;
  chamber.name = "chamber";
  chamber.type = ActuatorType::kPressure;
  chamber.rod = 0;
  chamber.from = 0.25;
  chamber.to = 0.75;
  chamber.area = 1e-4;
  chamber.offset = Vec3(0.0, 0.01, 0.005);
  chamber.profile = Profile::Input(input, 1e5);  // 2e5 Pa by default
  b.AddActuator(chamber);
  Actuator muscle;
  muscle.name = "muscle";
  muscle.type = ActuatorType::kMuscle;
  muscle.rod = 0;
  muscle.area = 2e-5;
  muscle.offset = Vec3(0.0, -0.01, 0.0);
  muscle.max_stress = 3e5;
  muscle.profile = Profile::Constant(1.7);  // clamped to full activation
  b.AddActuator(muscle);
  Actuator curl;
  curl.name = "curl";
  curl.type = ActuatorType::kRestStrain;
  curl.rod = 0;
  curl.from = 0.5;
  curl.vector = V6(0, 0, 0, 0, 0, 3.0);
  curl.profile = Profile::Ramp(0.0, 1.0);  // 0 at t = 0, 1 from t = 1
  b.AddActuator(curl);
  return b.Build();
}

TEST(RodActuationKernel, ActuatorsOfAModelAddOnTheirElementsWithProfilesInputsAndLoadFactor) {
  const Model m = ActuatedModel();
  Data d = MakeData(m);
  ASSERT_EQ(m.elements.size(), 6u);
  // Element lists: the chamber covers elements 1-2, the muscle 0-3, the curl 2-3.
  const int expected_count[6] = {1, 2, 3, 2, 0, 0};
  for (int e = 0; e < 6; ++e)
    EXPECT_EQ(m.elements[static_cast<std::size_t>(e)].num_actuators, expected_count[e]);
  const Vec6 chamber = 2e5 * 1e-4 * V6(1, 0, 0, 0, 0.005, -0.01);
  const Vec6 muscle = -3e5 * 2e-5 * V6(1, 0, 0, 0, 0.0, 0.01);
  RodActuation a;
  ASSERT_TRUE(CalcRodActuation(m, d, 2, 0.5, 1.0, &a));
  EXPECT_LT((a.active_stress - (chamber + muscle)).norm(), 1e-12);
  EXPECT_LT((a.rest_strain - V6(0, 0, 0, 0, 0, 1.5)).norm(), 1e-12);
  // Statics scales actuation like loads; an input changes the pressure between steps.
  d.inputs(0) = 4.0;
  ASSERT_TRUE(CalcRodActuation(m, d, 1, 2.0, 0.25, &a));
  EXPECT_LT((a.active_stress - 0.25 * (2.0 * chamber + muscle)).norm(), 1e-12);
  EXPECT_EQ(a.rest_strain.norm(), 0.0);
  EXPECT_FALSE(CalcRodActuation(m, d, 4, 0.5, 1.0, &a));
  EXPECT_EQ(a.active_stress.norm() + a.rest_strain.norm(), 0.0);
  // A negative activation is no activation.
  EXPECT_EQ(ActuatorValue(m.actuators[1], 0.0, d), 1.0);
}

TEST(RodActuationKernel, ElementKindEnergyIsTheActuatedEnergy) {
  const Model m = ActuatedModel();
  Data d = MakeData(m);
  d.time = 0.4;
  d.H[3] = d.H[3] * ExpSE3(V6(0.001, 0.002, 0.0, 0.1, 0.05, -0.2));
  for (int e = 2; e <= 3; ++e) {  // the two elements at the moved node
    const RodElement& el = m.elements[static_cast<std::size_t>(e)];
    RodActuation a;
    CalcRodActuation(m, d, e, d.time, 1.0, &a);
    RodInternal in;
    CalcRodInternal(el, m.rods[0].section, d.H[static_cast<std::size_t>(el.node_a)],
                    d.H[static_cast<std::size_t>(el.node_b)], Vec3::Zero(), &in, &a);
    Energy E;
    RodElementKind::AddEnergy(m, d, e, &E);
    EXPECT_NEAR(E.strain, in.energy, 1e-12 * std::abs(in.energy) + 1e-15);
    EXPECT_NE(in.energy, 0.0);
  }
}

}  // namespace
}  // namespace screwfem::actuation_test
