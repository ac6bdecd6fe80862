// Error-controlled time steps (AdaptiveStep, AdvanceTo, InterpolateStep; docs/numerics.md, "Adaptive time steps",
// docs/numerics.md "Adaptive time steps") on the validation problems M1 (pendulum) and M2
// (heavy top) and on a free body in uniform motion:
//  - the local error estimate C h^2 (a_{n+1} - a_n) against the true local error (the step's
//    result minus the exact flow from the step's start, by a fine RK4);
//  - the validation tolerances of M1 and M2 kept with fewer steps than the fixed step;
//  - the global error falling with the tolerance at the rate of a controlled local error;
//  - dense output: exact for a constant twist, O(h^4) inside the steps of the pendulum;
//  - the min_step failure names the time and the component.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/dynamics.h"
#include "validation/elliptic.h"

namespace screwfem::adaptive_steps_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kG = 9.81;

// Validation M1: the bob of 1 kg at (-cos alpha, -sin alpha), released at alpha = 0; the
// joint angle obeys alpha'' = g cos alpha.
struct Pendulum {
  Model model;
  Data data;
  Integrator integ;
  int coord = 0;
  double Angle() const { return data.q_joint(coord - model.nv_nodes); }
  double Rate() const { return data.v(coord); }
};

void MakePendulum(Pendulum* p, const DynamicOptions& opt) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "pivot");
  b.AddRigidBody("bob", node, 1.0, Vec3(-1.0, 0.0, 0.0), 1e-10 * Mat3::Identity());
  b.AddJointAt("pin", JointType::kRevolute, kGround, node, Vec3::Zero(), Vec3::UnitZ());
  b.SetGravity(Vec3(0.0, -kG, 0.0));
  p->model = b.Build();
  p->data = MakeData(p->model);
  p->coord = p->model.joints[0].coord;
  ASSERT_TRUE(InitializeDynamics(p->model, p->data, p->integ, opt));
}

// The exact flow of alpha'' = g cos alpha over h from (alpha, rate), by RK4 with 400 substeps.
double ExactFlow(double alpha, double rate, double h) {
  const int n = 400;
  const double k = h / n;
  double q = alpha, v = rate;
  for (int i = 0; i < n; ++i) {
    const double q1 = v, v1 = kG * std::cos(q);
    const double q2 = v + 0.5 * k * v1, v2 = kG * std::cos(q + 0.5 * k * q1);
    const double q3 = v + 0.5 * k * v2, v3 = kG * std::cos(q + 0.5 * k * q2);
    const double q4 = v + k * v3, v4 = kG * std::cos(q + k * q3);
    q += k / 6 * (q1 + 2 * q2 + 2 * q3 + q4);
    v += k / 6 * (v1 + 2 * v2 + 2 * v3 + v4);
  }
  return q;
}

// The exact bob position at time t (docs/validation.md, M1).
Vec3 ExactPosition(double t) {
  const double k = std::sin(kPi / 4), K = test::EllipticK(k * k);
  const double theta = 2.0 * std::asin(k * test::JacobiElliptic(K - std::sqrt(kG) * t, k * k).sn);
  return Vec3(-std::sin(theta), -std::cos(theta), 0.0);
}
Vec3 BobPosition(const Data& d) { return d.H[0].Act(Vec3(-1.0, 0.0, 0.0)); }

DynamicOptions Adaptive(double tolerance, double rho_inf = 1.0) {
  DynamicOptions o;
  o.rho_inf = rho_inf;
  o.absolute_tolerance = o.relative_tolerance = tolerance;
  o.initial_step = 1e-3;
  return o;
}

TEST(AdaptiveSteps, LocalErrorConstantHasTheQuotedValues) {
  EXPECT_NEAR(LocalErrorConstant(GeneralizedAlpha::FromSpectralRadius(1.0)), 1.0 / 12, 1e-15);
  EXPECT_NEAR(LocalErrorConstant(GeneralizedAlpha::FromSpectralRadius(0.9)), 0.08403, 1e-5);
  EXPECT_NEAR(LocalErrorConstant(GeneralizedAlpha::FromSpectralRadius(0.8)), 0.08642, 1e-5);
  EXPECT_NEAR(LocalErrorConstant(GeneralizedAlpha::FromSpectralRadius(0.5)), 1.0 / 9, 1e-12);
  EXPECT_NEAR(LocalErrorConstant(GeneralizedAlpha::FromSpectralRadius(0.0)), 1.0 / 3, 1e-12);
}

// The estimate against the true local error of the joint angle, at a fixed step h (min_step =
// max_step, a tolerance every step passes), over the second half of the first period.
TEST(AdaptiveSteps, EstimateTracksTheTrueLocalErrorOnThePendulum) {
  for (double rho : {1.0, 0.9, 0.5, 0.0}) {
    for (double h : {0.04, 0.01}) {
      DynamicOptions o = Adaptive(1e6, rho);
      o.min_step = o.max_step = o.initial_step = h;
      Pendulum p;
      MakePendulum(&p, o);
      std::vector<double> est, truth;
      const int steps = static_cast<int>(std::lround(2.4 / h));
      for (int n = 0; n < steps; ++n) {
        const double alpha = p.Angle(), rate = p.Rate();
        const StepResult r = AdaptiveStep(p.model, p.data, p.integ, 1e9);
        ASSERT_TRUE(r.ok) << r.message;
        if (n < steps / 4) continue;  // past the start transient of the auxiliary acceleration
        est.push_back(p.integ.error(p.coord));
        truth.push_back(p.Angle() - ExactFlow(alpha, rate, h));
      }
      double largest = 0.0;
      for (double t : truth) largest = std::max(largest, std::abs(t));
      // Away from the zeros of the third derivative (where the true error changes sign).
      double lo = INFINITY, hi = 0.0;
      for (std::size_t i = 0; i < est.size(); ++i) {
        if (std::abs(truth[i]) < 0.3 * largest) continue;
        lo = std::min(lo, est[i] / truth[i]);
        hi = std::max(hi, est[i] / truth[i]);
      }
      // Measured [0.72, 1.42] (rho_inf 0, h 0.04) to [0.93, 1.08] (rho_inf 0.5, h 0.01); the
      // issue's requirement is [0.3, 3].
      EXPECT_GT(lo, h > 0.02 ? 0.6 : 0.85) << "rho_inf " << rho << ", h " << h;
      EXPECT_LT(hi, h > 0.02 ? 1.6 : 1.15) << "rho_inf " << rho << ", h " << h;
      std::printf("rho %.1f h %.3f ratio [%.3f, %.3f] largest %.3g\n", rho, h, lo, hi, largest);
    }
  }
}

// Validation M1 under error control: the bob positions at the table times (landed on exactly by
// AdvanceTo) keep the fixed step's tolerance 1e-4, in fewer steps than h = 1e-3 takes (10000).
TEST(AdaptiveSteps, PendulumKeepsTheValidationToleranceWithFewerSteps) {
  Pendulum p;
  MakePendulum(&p, Adaptive(1e-8));
  double worst = 0.0;
  for (double tc : {0.25, 0.5, 1.0, 2.0, 5.0, 10.0}) {
    const StepResult r = AdvanceTo(p.model, p.data, p.integ, tc);
    ASSERT_TRUE(r.ok) << r.message;
    ASSERT_EQ(p.data.time, tc);
    worst = std::max(worst, (BobPosition(p.data) - ExactPosition(tc)).norm());
  }
  EXPECT_LT(worst, 1e-4);
  EXPECT_LT(p.integ.steps, 10000 / 1.5);
  std::printf("pendulum auto: error %.3g, %ld steps, %ld rejected\n", worst, p.integ.steps,
              p.integ.rejected);
}

// The global error falls with the tolerance as tol^(2/3) (a controlled local error of a
// second-order method, docs/numerics.md, "Adaptive time steps"): the log-log slope over three decades.
TEST(AdaptiveSteps, GlobalErrorFallsWithTheToleranceAtTheControlledRate) {
  std::vector<double> tol = {1e-3, 1e-4, 1e-5, 1e-6}, err;
  for (double t : tol) {
    Pendulum p;
    MakePendulum(&p, Adaptive(t));
    const StepResult r = AdvanceTo(p.model, p.data, p.integ, 2.0);
    ASSERT_TRUE(r.ok) << r.message;
    err.push_back((BobPosition(p.data) - ExactPosition(2.0)).norm());
    std::printf("tol %.0e: error %.3g, %ld steps\n", t, err.back(), p.integ.steps);
  }
  const double slope = std::log(err.front() / err.back()) / std::log(tol.front() / tol.back());
  EXPECT_GT(slope, 0.5) << slope;
  EXPECT_LT(slope, 0.85) << slope;
}

// Dense output inside the steps of the pendulum: as accurate as the step ends (the
// interpolant's O(h^4) is below the integrator's error).
TEST(AdaptiveSteps, DenseOutputInsideStepsIsAsAccurateAsTheStepEnds) {
  Pendulum p;
  MakePendulum(&p, Adaptive(1e-5));
  Data dense = p.data;
  double at_ends = 0.0, inside = 0.0;
  int samples = 0;
  while (p.data.time < 2.0) {
    const double t0 = p.data.time;
    const StepResult r = AdaptiveStep(p.model, p.data, p.integ, 2.0);
    ASSERT_TRUE(r.ok) << r.message;
    at_ends = std::max(at_ends, (BobPosition(p.data) - ExactPosition(p.data.time)).norm());
    for (double th : {0.25, 0.5, 0.8}) {
      const double t = t0 + th * (p.data.time - t0);
      InterpolateStep(p.model, p.data, p.integ, t, dense);
      EXPECT_EQ(dense.time, t);
      inside = std::max(inside, (BobPosition(dense) - ExactPosition(t)).norm());
      ++samples;
    }
    // At theta = 1 the interpolant is the step's end.
    InterpolateStep(p.model, p.data, p.integ, p.data.time, dense);
    EXPECT_LT((BobPosition(dense) - BobPosition(p.data)).norm(), 1e-13);
    EXPECT_LT((dense.v - p.data.v).norm(), 1e-10 * (1.0 + p.data.v.norm()));
  }
  EXPECT_GT(samples, 30);
  EXPECT_LT(inside, 1.5 * at_ends + 1e-9) << inside << " " << at_ends;
}

// A free symmetric body spinning about its symmetry axis while translating (no gravity): the
// body twist is constant, H(t) = H_0 exp(t eta) exactly, and the interpolant reproduces it
// (psi = theta D when v_n = v_{n+1} = D / h), also the velocity.
TEST(AdaptiveSteps, DenseOutputIsExactForAConstantTwist) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "body");
  b.AddRigidBody("body", node, 2.0, Vec3::Zero(), Vec3(0.1, 0.1, 0.3).asDiagonal());
  b.SetGravity(Vec3::Zero());
  const Model model = b.Build();
  Data data = MakeData(model);
  Vec6 eta;
  eta << 0.0, 0.0, 0.5, 0.0, 0.0, 4.0;  // a screw motion along and about the body z axis
  data.v.segment<6>(model.nodes[0].dof) = eta;
  Integrator integ;
  ASSERT_TRUE(InitializeDynamics(model, data, integ, Adaptive(1e-6)));
  Data dense = data;
  for (int n = 0; n < 5; ++n) {
    const double t0 = data.time;
    ASSERT_TRUE(AdaptiveStep(model, data, integ, 1.0).ok);
    const double t = t0 + 0.37 * (data.time - t0);
    InterpolateStep(model, data, integ, t, dense);
    const SE3 exact = ExpSE3(t * eta);
    EXPECT_LT((dense.H[0].R - exact.R).norm(), 1e-12);
    EXPECT_LT((dense.H[0].x - exact.x).norm(), 1e-12);
    EXPECT_LT((dense.v.segment<6>(model.nodes[0].dof) - eta).norm(), 1e-12);
  }
}

// Validation M2 (the heavy top, tests/validation/heavy_top_test.cpp) under error control: the
// orientation at 0.2 s within 1e-3 of the quoted Exudyn RK4 value (Frobenius norm; the fixed
// step needs h = 1e-4, 2000 steps) and the relative energy drift over 1 s below 2e-5 (the fixed
// step: h = 5e-4, 2000 steps), with the spin conserved to round-off.
TEST(AdaptiveSteps, HeavyTopKeepsTheValidationTolerances) {
  constexpr double kMass = 15.0;
  const Vec3 com(0.0, 1.0, 0.0), omega0(0.0, 150.0, -4.61538);
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "top");
  b.AddRigidBody("top", node, kMass, com, Vec3(0.234375, 0.46875, 0.234375).asDiagonal());
  b.AddJointAt("fixed point", JointType::kSpherical, kGround, node, Vec3::Zero());
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  const Model model = b.Build();
  Data data = MakeData(model);
  const int dof = model.nodes[0].dof, coord = model.joints[0].coord;
  data.v.segment<3>(dof + 3) = omega0;
  data.v.segment<3>(coord) = omega0;
  Integrator integ;
  ASSERT_TRUE(InitializeDynamics(model, data, integ, Adaptive(2e-8)));
  const double e0 = CalcEnergy(model, data).total();
  double drift = 0.0, spin = 0.0;
  while (data.time < 1.0) {
    const StepResult r = AdaptiveStep(model, data, integ, data.time < 0.2 ? 0.2 : 1.0);
    ASSERT_TRUE(r.ok) << r.message;
    drift = std::max(drift, std::abs(CalcEnergy(model, data).total() - e0) / std::abs(e0));
    spin = std::max(spin, std::abs(data.v(dof + 4) - 150.0));
    if (data.time == 0.2) {
      const Mat3 quoted =
          Eigen::Quaterniond(-0.70828, 0.43878, 0.54573, 0.0894).normalized().toRotationMatrix();
      EXPECT_LT((data.H[0].R - quoted).norm(), 1e-3);
      std::printf("top at 0.2 s: %.3g, %ld steps\n", (data.H[0].R - quoted).norm(), integ.steps);
    }
  }
  EXPECT_LT(drift, 2e-5);
  EXPECT_LT(spin, 1e-10);
  std::printf("top: energy drift %.3g, %ld steps, %ld rejected\n", drift, integ.steps,
              integ.rejected);
}

// Below min_step the step fails, naming the time, the error and the component.
TEST(AdaptiveSteps, FailsBelowMinStepNamingTheComponent) {
  DynamicOptions o = Adaptive(1e-12);
  o.min_step = 1e-3;
  Pendulum p;
  MakePendulum(&p, o);
  const StepResult r = AdvanceTo(p.model, p.data, p.integ, 1.0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("min_step"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("t = "), std::string::npos) << r.message;
  // The pendulum's rotation is both the body's and the pin's coordinate, with the same error:
  // which of the two is reported largest is decided by round-off (the sanitizer build, with
  // the portable instruction set, names the body).
  EXPECT_TRUE(r.message.find("joint 0 coordinate 0 ('pin')") != std::string::npos ||
              r.message.find("node 0 rotation ('pivot')") != std::string::npos)
      << r.message;
  EXPECT_GT(p.integ.rejected, 0);
  // The state is that of the last accepted step.
  EXPECT_LT(p.data.time, 1.0);
}

// Invalid settings are refused by the one check of the options.
TEST(AdaptiveSteps, InvalidSettingsAreRefused) {
  const auto refused = [](auto change) {
    DynamicOptions o;
    change(o);
    try {
      ValidateDynamicOptions(o, "analysis");
    } catch (const InputError&) {
      return true;
    }
    return false;
  };
  EXPECT_TRUE(refused([](DynamicOptions& o) { o.absolute_tolerance = 0.0; }));
  EXPECT_TRUE(refused([](DynamicOptions& o) { o.relative_tolerance = -1.0; }));
  EXPECT_TRUE(refused([](DynamicOptions& o) { o.min_step = 0.0; }));
  EXPECT_TRUE(refused([](DynamicOptions& o) { o.max_step = 1e-12; }));
  EXPECT_TRUE(refused([](DynamicOptions& o) { o.initial_step = NAN; }));
  EXPECT_FALSE(refused([](DynamicOptions&) {}));
}

}  // namespace
}  // namespace screwfem::adaptive_steps_test
