// Section strain and stress along a rod (CalcRodFieldRows, the values of rod_fields.csv)
// against closed forms of a cantilever L = 1 m along x, clamped at x = 0, 8 elements, loaded
// at its tip and solved by SolveStatic:
//  * pure bending by an end moment M about section axis 3 (2): a circular arc, kappa3 = M / EI3
//    (kappa2 = M / EI2) and m3 = M (m2 = M) at every station, exactly for any M;
//  * pure tension N: gamma1 = N / EA, n1 = N (section axis 1 is the rod axis);
//  * pure torsion T: kappa1 = T / GJ, m1 = T;
//  * a tip force F along y (small load, linear theory): shear n2 = F, gamma2 = F / GA2 and the
//    bending moment linear along the rod, m3(s) = F (L - s) at the element midpoints;
//  * actuation: a rest curvature's stress is scaled by the load factor given to the output.
// Each to 1e-9 relative. The section's stiffnesses are all of order 1 (and all different, so
// that a wrong index shows): the stress resultants of a statically determinate cantilever do
// not depend on them, and round-off in the strains (about 1e-15) then stays 1e-10 below a tip
// force of 1e-5 N, small enough for linear theory to hold to (F L^2 / 2 EI)^2 / 2 = 7e-12.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "screwfem/assemble/outputs.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/solve/statics.h"

namespace screwfem::rod_fields_test {
namespace {

constexpr double kEA = 2.0, kGA2 = 1.5, kGA3 = 1.2, kGJ = 0.8, kEI2 = 1.1, kEI3 = 1.3;
constexpr int kElements = 8;
constexpr double kLength = 1.0;

// Column of a station's values (CalcRodFieldRows): rod, s, gamma1..3, kappa1..3, n1..3, m1..3.
enum Column {
  kRod,
  kS,
  kGamma1,
  kGamma2,
  kGamma3,
  kKappa1,
  kKappa2,
  kKappa3,
  kN1,
  kN2,
  kN3,
  kM1,
  kM2,
  kM3
};

struct Solved {
  Model model;
  Data data;
  std::vector<double> rows;  // CalcRodFieldRows of rod 0 at load factor 1
  int stations = 0;
  double Value(int station, Column c) const {
    return rows[static_cast<std::size_t>(station * kRodFieldValues + c)];
  }
};

// The cantilever under a world force and moment at its tip, solved in `steps` load steps.
Solved SolveCantilever(const Vec3& force, const Vec3& moment, int steps = 4,
                       const std::vector<Actuator>& actuators = {}) {
  ModelBuilder b;
  Vec6 K;
  K << kEA, kGA2, kGA3, kGJ, kEI2, kEI3;
  b.AddStraightRod("rod", Vec3::Zero(), Vec3(kLength, 0, 0), kElements, Section::FromDiagonals(K));
  const std::vector<NodeId> nodes = b.RodNodes(RodId(0));
  b.FixNode(nodes.front());
  PointLoad tip;
  tip.node = nodes.back();
  tip.force = force;
  tip.moment = moment;
  b.AddPointLoad(tip);
  for (Actuator a : actuators) {
    a.rod = 0;
    b.AddActuator(a);
  }
  Solved s{b.Build(), {}, {}, 0};
  s.data = MakeData(s.model);
  StaticOptions o;
  o.load_steps = steps;
  const StaticResult r = SolveStatic(s.model, s.data, o);
  EXPECT_TRUE(r.converged) << r.message;
  CalcRodFieldRows(s.model, s.data, 0, 1.0, &s.rows);
  s.stations = static_cast<int>(s.rows.size()) / kRodFieldValues;
  return s;
}

// Largest |value - expected| / |expected| over the stations, and the largest |value| of the
// components expected to vanish, relative to `scale`.
struct Errors {
  double relative = 0.0;
  double others = 0.0;
};

Errors Compare(const Solved& s, const std::vector<std::pair<Column, double>>& expected,
               double scale) {
  Errors e;
  for (int i = 0; i < s.stations; ++i) {
    for (int c = kGamma1; c <= kM3; ++c) {
      const auto it = std::find_if(expected.begin(), expected.end(),
                                   [c](const auto& x) { return x.first == c; });
      const double v = s.Value(i, static_cast<Column>(c));
      if (it != expected.end())
        e.relative = std::max(e.relative, std::abs(v - it->second) / std::abs(it->second));
      else
        e.others = std::max(e.others, std::abs(v) / scale);
    }
  }
  return e;
}

TEST(RodFields, StationsAreTheElementMidpointsOfEveryRod) {
  ModelBuilder b;
  b.AddStraightRod("a", Vec3::Zero(), Vec3(1.0, 0, 0), 4, Section::FromDiagonals(Vec6::Ones()));
  b.AddRodAlongPath("b", {Vec3(0, 1, 0), Vec3(0.6, 1, 0), Vec3(0.6, 1.9, 0)}, 3,
                    Section::FromDiagonals(Vec6::Ones()));
  const Model model = b.Build();
  const Data data = MakeData(model);
  std::vector<double> rows;
  CalcRodFieldRows(model, data, -1, 1.0, &rows);
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kRodFieldValues * (4 + 6)));
  const double expected_s[10] = {0.125, 0.375, 0.625, 0.875, 0.1, 0.3, 0.5, 0.75, 1.05, 1.35};
  for (int i = 0; i < 10; ++i) {
    const double* row = &rows[static_cast<std::size_t>(i * kRodFieldValues)];
    EXPECT_EQ(row[kRod], i < 4 ? 0.0 : 1.0) << i;
    // The path's corner elements are arcs a little longer than their chords.
    EXPECT_NEAR(row[kS], expected_s[i], i < 4 ? 1e-15 : 0.03) << i;
    // At rest: no strain, no stress (the reference curvature of the corner is not strain).
    for (int c = kGamma1; c <= kM3; ++c) EXPECT_LT(std::abs(row[c]), 1e-14) << i << " " << c;
  }
  // The arc lengths add up: the last station is half an element before the rod's end.
  const double last_s = rows[static_cast<std::size_t>(9 * kRodFieldValues + kS)];
  const double last_length = model.elements.back().length;
  EXPECT_NEAR(last_s + 0.5 * last_length, model.rods[1].length, 1e-15);
  // One rod alone: its stations only.
  CalcRodFieldRows(model, data, 1, 1.0, &rows);
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kRodFieldValues * 6));
  EXPECT_EQ(rows[kRod], 1.0);
  EXPECT_NEAR(rows[kS], 0.1, 1e-15);
}

TEST(RodFields, PureBendingByAnEndMomentGivesConstantCurvatureAndMoment) {
  // kappa L = 0.5 rad about either bending axis: a circular arc, exact in the helical element.
  for (const int axis : {2, 3}) {
    SCOPED_TRACE(axis);
    const double EI = axis == 2 ? kEI2 : kEI3;
    const double M = 0.5 * EI / kLength;
    const Vec3 moment = axis == 2 ? Vec3(0, M, 0) : Vec3(0, 0, M);
    const Solved s = SolveCantilever(Vec3::Zero(), moment);
    ASSERT_EQ(s.stations, kElements);
    const Column kappa = axis == 2 ? kKappa2 : kKappa3, m = axis == 2 ? kM2 : kM3;
    const Errors e = Compare(s, {{kappa, M / EI}, {m, M}}, M);
    std::printf("pure bending about axis %d: max relative error %.2e, others %.2e\n", axis,
                e.relative, e.others);
    EXPECT_LT(e.relative, 1e-9);
    EXPECT_LT(e.others, 1e-9);
  }
}

TEST(RodFields, PureTensionGivesTheAxialStrainAndForce) {
  const double N = 0.02;  // gamma1 = 0.01
  const Solved s = SolveCantilever(Vec3(N, 0, 0), Vec3::Zero());
  const Errors e = Compare(s, {{kGamma1, N / kEA}, {kN1, N}}, N);
  std::printf("pure tension: max relative error %.2e, others %.2e\n", e.relative, e.others);
  EXPECT_LT(e.relative, 1e-9);
  EXPECT_LT(e.others, 1e-9);
}

TEST(RodFields, PureTorsionGivesTheTwistAndTorque) {
  const double T = 0.4;  // kappa1 = 0.5 rad/m
  const Solved s = SolveCantilever(Vec3::Zero(), Vec3(T, 0, 0));
  const Errors e = Compare(s, {{kKappa1, T / kGJ}, {kM1, T}}, T);
  std::printf("pure torsion: max relative error %.2e, others %.2e\n", e.relative, e.others);
  EXPECT_LT(e.relative, 1e-9);
  EXPECT_LT(e.others, 1e-9);
}

TEST(RodFields, TipForceGivesShearAndABendingMomentLinearAlongTheRod) {
  const double F = 1e-5;  // tip rotation F L^2 / (2 EI3) = 3.8e-6 rad: linear theory
  const Solved s = SolveCantilever(Vec3(0, F, 0), Vec3::Zero(), 1);
  ASSERT_EQ(s.stations, kElements);
  double shear = 0.0, moment = 0.0, strain = 0.0, others = 0.0;
  for (int i = 0; i < s.stations; ++i) {
    const double station = s.Value(i, kS);
    EXPECT_NEAR(station, (i + 0.5) * kLength / kElements, 1e-15);
    const double m = F * (kLength - station);
    shear = std::max(shear, std::abs(s.Value(i, kN2) - F) / F);
    shear = std::max(shear, std::abs(s.Value(i, kGamma2) - F / kGA2) / (F / kGA2));
    moment = std::max(moment, std::abs(s.Value(i, kM3) - m) / m);
    strain = std::max(strain, std::abs(s.Value(i, kKappa3) - m / kEI3) / (m / kEI3));
    for (const Column c : {kN3, kM1, kM2, kGamma3, kKappa1, kKappa2})
      others = std::max(others, std::abs(s.Value(i, c)) / F);
  }
  std::printf("tip force: max relative error n2, gamma2 %.2e; m3 %.2e; kappa3 %.2e; others %.2e\n",
              shear, moment, strain, others);
  EXPECT_LT(shear, 1e-9);
  EXPECT_LT(moment, 1e-9);
  EXPECT_LT(strain, 1e-9);
  EXPECT_LT(others, 1e-9);
  // n1 = F sin(theta) is second order: the rotated sections carry a little of F axially.
  for (int i = 0; i < s.stations; ++i) EXPECT_LT(std::abs(s.Value(i, kN1)), 1e-5 * F);
}

TEST(RodFields, ActuationEntersTheStressTimesTheLoadFactor) {
  // A rest curvature kappa0 about axis 3: the rod takes it without stress at load factor 1;
  // read at load factor 1/2 (half the rest curvature) the same state has m3 = EI3 kappa0 / 2.
  const double kappa0 = 0.7;
  Actuator a;
  a.type = ActuatorType::kRestStrain;
  a.vector << 0, 0, 0, 0, 0, kappa0;
  const Solved s = SolveCantilever(Vec3::Zero(), Vec3::Zero(), 4, {a});
  const Errors e = Compare(s, {{kKappa3, kappa0}}, kEI3 * kappa0);
  EXPECT_LT(e.relative, 1e-9);
  EXPECT_LT(e.others, 1e-9);  // no stress
  std::vector<double> half;
  CalcRodFieldRows(s.model, s.data, 0, 0.5, &half);
  for (int i = 0; i < s.stations; ++i) {
    const double m3 = half[static_cast<std::size_t>(i * kRodFieldValues + kM3)];
    EXPECT_NEAR(m3, 0.5 * kEI3 * kappa0, 1e-9 * kEI3 * kappa0);
  }
}

}  // namespace
}  // namespace screwfem::rod_fields_test
