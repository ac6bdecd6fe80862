// Validation D1 (docs/validation.md): natural bending frequencies of a slender cantilever.
//
// L = 10, EI = 100, rhoA = 1 (EA = GA = 1e6, GJ = 100, rotary inertia 1e-6: shear and rotary
// inertia corrections below 1e-5). Euler-Bernoulli: omega_n = (beta_n L)^2 sqrt(EI/(rhoA L^4)),
// beta_n L = 1.8751040687, 4.6940911330, 7.8547574382 -> 0.351602, 2.203449, 6.169721 rad/s.
// Each frequency appears twice (bending about the two section axes, EI2 = EI3).
//
// (i) Linearisation (solve/modal.h) with 20 and 40 elements of the default inertia (option A):
// error O(L_e^2); 40 elements are within 0.5 % for the first three modes.
// (ii) Free vibration (40 elements, rho_inf = 1): a small tip load (tip deflection L/1000) is
// solved statically and released. Mode n's period is measured from the zero crossings of its
// modal coordinate q_n = phi_n^T M dx (dx = log(H_0^-1 H) per node; the projection removes the
// other modes, which the tip load excites as well), with a step h = T_n / 100. With rho_inf = 1
// the integrator is the trapezoidal rule (alpha_m = alpha_f = 1/2, a = vdot), whose period is
// exactly 2 pi h / (2 atan(omega h / 2)) for a linear oscillator: the measured periods must
// match that prediction from the linearised omega as well as Euler-Bernoulli.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/modal.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::cantilever_frequency_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kL = 10.0, kEI = 100.0, kRhoA = 1.0;
constexpr double kBetaL[3] = {1.8751040687, 4.6940911330, 7.8547574382};

double EulerBernoulli(int n) {
  return kBetaL[n] * kBetaL[n] * std::sqrt(kEI / (kRhoA * std::pow(kL, 4)));
}

Section SlenderSection() {
  Vec6 k, m;
  k << 1e6, 1e6, 1e6, 100.0, kEI, kEI;
  m << kRhoA, kRhoA, kRhoA, 2e-6, 1e-6, 1e-6;
  return Section::FromDiagonals(k, m);
}

struct Cantilever {
  Model model;
  int tip = -1;
};

// Rod along x, clamped at x = 0; with tip_force != 0 a dead tip load along z.
Cantilever MakeCantilever(int num_elements, double tip_force = 0.0) {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("cantilever", Vec3::Zero(), Vec3(kL, 0.0, 0.0), num_elements,
                                     SlenderSection());
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  if (tip_force != 0.0) {
    PointLoad load;
    load.node = nodes.back();
    load.force = Vec3(0.0, 0.0, tip_force);
    b.AddPointLoad(load);
  }
  return {b.Build(), nodes.back()};
}

// The six lowest frequencies are the three bending pairs; returns one of each pair.
std::vector<double> BendingFrequencies(const ModalResult& r) {
  std::vector<double> w;
  for (int n = 0; n < 3; ++n) {
    EXPECT_NEAR(r.omega(2 * n + 1), r.omega(2 * n), 1e-6 * r.omega(2 * n)) << "pair " << n;
    w.push_back(r.omega(2 * n));
  }
  return w;
}

TEST(CantileverFrequency,
     LinearisationIsWithinHalfAPercentWithFortyElementsAndConvergesAtSecondOrder) {
  std::vector<double> err[2];
  const int counts[2] = {20, 40};
  for (int k = 0; k < 2; ++k) {
    Cantilever c = MakeCantilever(counts[k]);
    Data data = MakeData(c.model);
    const ModalResult r = CalcModes(c.model, data);
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_TRUE(r.warnings.empty());
    EXPECT_EQ(r.num_dofs, c.model.nv);
    const std::vector<double> w = BendingFrequencies(r);
    for (int n = 0; n < 3; ++n) {
      err[k].push_back(w[static_cast<std::size_t>(n)] / EulerBernoulli(n) - 1.0);
      std::printf("[ D1 ] %d elements, mode %d: omega %.7f rad/s (%.7f Hz), EB %.7f, error %+.3e\n",
                  counts[k], n + 1, w[static_cast<std::size_t>(n)],
                  w[static_cast<std::size_t>(n)] / (2 * kPi), EulerBernoulli(n), err[k].back());
    }
  }
  for (int n = 0; n < 3; ++n) {
    const std::size_t i = static_cast<std::size_t>(n);
    EXPECT_LT(std::abs(err[1][i]), 5e-3) << "mode " << n + 1;
    EXPECT_GT(err[1][i], 0.0);  // consistent mass: the discrete model is stiffer
    EXPECT_NEAR(err[0][i] / err[1][i], 4.0, 0.2) << "mode " << n + 1;  // O(L_e^2)
    // Richardson extrapolation of the two meshes reaches Euler-Bernoulli to 1e-4 (D1).
    EXPECT_LT(std::abs((4.0 * err[1][i] - err[0][i]) / 3.0), 1e-4) << "mode " << n + 1;
  }
}

TEST(CantileverFrequency, ModesAreMassNormalisedAndRayleighDampingGivesTheTextbookRatio) {
  Cantilever c = MakeCantilever(10);
  const double a_m = 0.05, a_k = 0.01;
  c.model.rods[0].section.rayleigh_mass = a_m;
  c.model.rods[0].section.rayleigh_stiffness = a_k;
  Data data = MakeData(c.model);
  LinearizedSystem sys;
  ASSERT_TRUE(CalcLinearizedSystem(c.model, data, {}, &sys));
  ModalOptions options;
  options.num_modes = 8;
  const ModalResult r = CalcModes(c.model, data, options);
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(r.modes.cols(), 8);
  const Eigen::MatrixXd G = r.modes.transpose() * sys.mass * r.modes;
  EXPECT_LT((G - Eigen::MatrixXd::Identity(8, 8)).norm(), 1e-9);
  const Eigen::MatrixXd Kd = r.modes.transpose() * sys.stiffness * r.modes;
  EXPECT_LT((Kd - Eigen::MatrixXd(r.eigenvalues.asDiagonal())).norm(),
            1e-9 * r.eigenvalues.maxCoeff());
  for (int i = 0; i < 8; ++i) {
    const double w = r.omega(i);
    EXPECT_NEAR(r.damping_ratio(i), a_m / (2.0 * w) + a_k * w / 2.0, 1e-9) << "mode " << i;
  }
}

TEST(CantileverFrequency, ConstraintsRestrictTheModesToTheNullSpaceOfB) {
  // The same rod with its root held by a joint to the ground instead of FixNode: a fixed joint
  // reproduces the cantilever; a revolute joint about y makes bending in the xz plane
  // pinned-free (a rigid rotation, then beta L = 3.9266023120, 7.0685827500) while bending in
  // the xy plane stays clamped.
  constexpr int kElements = 40;
  Cantilever clamped = MakeCantilever(kElements);
  Data dc = MakeData(clamped.model);
  const ModalResult reference = CalcModes(clamped.model, dc);
  ASSERT_TRUE(reference.ok);
  for (const JointType type : {JointType::kFixed, JointType::kRevolute}) {
    ModelBuilder b;
    const RodId rod =
        b.AddStraightRod("rod", Vec3::Zero(), Vec3(kL, 0.0, 0.0), kElements, SlenderSection());
    b.AddJointAt("root", type, kGround, b.RodNodes(rod)[0], Vec3::Zero(), Vec3::UnitY());
    const Model model = b.Build();
    Data data = MakeData(model);
    const ModalResult r = CalcModes(model, data);
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_EQ(r.num_dofs, clamped.model.nv + (type == JointType::kRevolute ? 1 : 0));
    // The joint coordinate carries no mass of its own but is tied to the root by B.
    EXPECT_EQ(r.num_massless, 0);
    if (type == JointType::kFixed) {
      for (int i = 0; i < 12; ++i)
        EXPECT_NEAR(r.omega(i), reference.omega(i), 1e-8 * reference.omega(i)) << "mode " << i;
      continue;
    }
    EXPECT_LT(std::abs(r.omega(0)), 1e-4);  // rigid rotation about the pin
    // Remaining low modes: clamped (xy plane) and pinned-free (xz plane) frequencies, merged.
    const double scale = std::sqrt(kEI / (kRhoA * std::pow(kL, 4)));
    std::vector<double> expected = {EulerBernoulli(0), EulerBernoulli(1), EulerBernoulli(2),
                                    3.9266023120 * 3.9266023120 * scale,
                                    7.0685827500 * 7.0685827500 * scale};
    std::sort(expected.begin(), expected.end());
    for (std::size_t i = 0; i < expected.size(); ++i)
      EXPECT_NEAR(r.omega(static_cast<int>(i) + 1) / expected[i], 1.0, 3e-3) << "mode " << i + 2;
  }
}

// Discrete modal coordinate phi^T M dx of the current state.
double ModalCoordinate(const Model& model, const Data& data, const Eigen::VectorXd& M_phi) {
  double q = 0.0;
  for (std::size_t i = 0; i < model.nodes.size(); ++i) {
    const Node& n = model.nodes[i];
    if (n.dof < 0) continue;
    q += M_phi.segment<6>(n.dof).dot(LogSE3(n.reference.Inverse() * data.H[i]));
  }
  return q;
}

TEST(CantileverFrequency, FreeVibrationPeriodsAfterReleasingATipLoadMatchTheLinearisation) {
  constexpr int kElements = 40;
  const Cantilever free = MakeCantilever(kElements);
  // Tip load giving a tip deflection of L/1000: P L^3 / (3 EI) = L / 1000.
  const double P = 3.0 * kEI / (1000.0 * kL * kL);
  const Cantilever loaded = MakeCantilever(kElements, P);
  Data data0 = MakeData(loaded.model);
  const StaticResult s = SolveStatic(loaded.model, data0);
  ASSERT_TRUE(s.converged) << s.message;
  EXPECT_NEAR(data0.H[static_cast<std::size_t>(loaded.tip)].x.z(), kL / 1000.0, 1e-5 * kL);

  Data lin = MakeData(free.model);
  LinearizedSystem sys;
  ASSERT_TRUE(CalcLinearizedSystem(free.model, lin, {}, &sys));
  ModalOptions mo;
  mo.num_modes = 6;
  const ModalResult modes = CalcModes(free.model, lin, mo);
  ASSERT_TRUE(modes.ok);

  for (int n = 0; n < 3; ++n) {
    // Of the pair 2n, 2n+1 the mode bending in the xz plane (z motion of the tip).
    int col = 2 * n;
    const int tip_dof = free.model.nodes[static_cast<std::size_t>(free.tip)].dof;
    if (std::abs(modes.modes(tip_dof + 2, 2 * n + 1)) > std::abs(modes.modes(tip_dof + 2, col)))
      col = 2 * n + 1;
    const Eigen::VectorXd M_phi = sys.mass * modes.modes.col(col);
    const double omega = modes.omega(col);
    const double period_lin = 2.0 * kPi / omega;
    const double h = period_lin / 100.0;

    Data data = MakeData(free.model);
    data.H = data0.H;
    UpdateBranchReferences(free.model, data);
    Integrator integ;
    DynamicOptions options;
    options.rho_inf = 1.0;
    ASSERT_TRUE(InitializeDynamics(free.model, data, integ, options));
    std::vector<double> crossings;
    double q_prev = ModalCoordinate(free.model, data, M_phi), t_prev = 0.0;
    const int steps = n == 0 ? 220 : 320;  // ~2 and ~3 periods
    for (int k = 0; k < steps; ++k) {
      const StepResult st = Step(free.model, data, integ, h);
      ASSERT_TRUE(st.ok) << st.message;
      const double q = ModalCoordinate(free.model, data, M_phi);
      if ((q_prev < 0.0) != (q < 0.0))
        crossings.push_back(t_prev + h * q_prev / (q_prev - q));  // linear interpolation
      q_prev = q;
      t_prev = data.time;
    }
    ASSERT_GE(crossings.size(), 4u);
    const double period =
        2.0 * (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
    const double trapezoidal = 2.0 * kPi * h / (2.0 * std::atan(0.5 * omega * h));
    const double eb = 2.0 * kPi / EulerBernoulli(n);
    std::printf(
        "[ D1 ] time history, mode %d: h = T/100, period %.7f s, trapezoidal prediction "
        "%.7f (diff %+.2e), Euler-Bernoulli %.7f (error %+.3e), %.2f Newton it/step\n",
        n + 1, period, trapezoidal, period / trapezoidal - 1.0, eb, period / eb - 1.0,
        static_cast<double>(integ.iterations) / steps);
    EXPECT_LT(std::abs(period / eb - 1.0), 5e-3) << "mode " << n + 1;
    EXPECT_LT(std::abs(period / trapezoidal - 1.0), 2e-6) << "mode " << n + 1;
    EXPECT_EQ(integ.halvings, 0) << "mode " << n + 1;  // every step at h: the trapezoidal rule
  }
}

}  // namespace
}  // namespace screwfem::cantilever_frequency_test
