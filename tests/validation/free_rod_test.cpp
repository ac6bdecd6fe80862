// A free-floating flexible rod, no loads, no constraints: conservation laws of the discrete
// dynamics with the exact inertia (option A).
//
// Rod: L = 1 along x, 8 elements, EA = GA = 1e4, GJ = EI = 10 N m^2, rhoA = 1, rotary inertia
// 1e-3 kg m. Initial velocity: a rigid twist (translation (0.3, -0.2, 0.1) m/s, spin
// (0.5, 0, 4) rad/s about the origin) plus a transverse velocity 0.2 sin(pi s / L) m/s along z
// that excites bending; t = 1 s, rho_inf = 1, h = 1e-2 ... 1.25e-3.
//
// World momentum of the exact velocity field (linear, and angular about the world origin),
//   h = sum_e sum_i L_e w_i Ad(H(xi_i)^-1)^T M eta(xi_i),
// with the same quadrature as the inertia forces. Asserted:
//  * at a converged step the world resultant of the residual vanishes to round-off: the
//    instantaneous rate dh/dt of the exact field (= world resultant of the inertia forces,
//    tests/elements/rod_inertia_test.cpp) balances the self-equilibrated internal forces;
//  * h itself and the energy (rho_inf = 1) are conserved to O(h^2), not to round-off: the Lie
//    group generalized-alpha step (q_{n+1} = q_n exp(h dq), velocities updated linearly in the
//    body frames) is not a momentum-conserving scheme. A single free rigid body shows the same
//    O(h^2) momentum drift, so this is a property of the integrator, not of the rod element.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

#include "screwfem/elements/rod.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/modal.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::free_rod_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kGaussXi[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
constexpr double kGaussW[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

Model MakeFreeRod(int num_elements, double axial_shear = 1e4, double rotary = 1e-3) {
  ModelBuilder b;
  Vec6 k, m;
  k << axial_shear, axial_shear, axial_shear, 10.0, 10.0, 10.0;
  m << 1.0, 1.0, 1.0, rotary, rotary, rotary;
  b.AddStraightRod("free", Vec3::Zero(), Vec3(1.0, 0.0, 0.0), num_elements,
                   Section::FromDiagonals(k, m));
  return b.Build();
}

// Initial velocities: rigid twist plus a bending velocity.
void SetInitialVelocity(const Model& model, Data& data) {
  const Vec3 v0(0.3, -0.2, 0.1), omega(0.5, 0.0, 4.0);
  for (std::size_t i = 0; i < model.nodes.size(); ++i) {
    const SE3& H = data.H[i];
    const int dof = model.nodes[i].dof;
    const double s = H.x.x();
    const Vec3 v_world = v0 + omega.cross(H.x) + Vec3(0.0, 0.0, 0.2 * std::sin(kPi * s));
    data.v.segment<3>(dof) = H.R.transpose() * v_world;
    data.v.segment<3>(dof + 3) = H.R.transpose() * omega;
  }
}

// World momentum [linear; angular about the origin] of the exact velocity field.
Vec6 WorldMomentum(const Model& model, const Data& data) {
  Vec6 h = Vec6::Zero();
  for (std::size_t e = 0; e < model.elements.size(); ++e) {
    const RodElement& el = model.elements[e];
    const auto M = model.rods[static_cast<std::size_t>(el.rod)].section.inertia.asDiagonal();
    const SE3& HA = data.H[static_cast<std::size_t>(el.node_a)];
    const SE3& HB = data.H[static_cast<std::size_t>(el.node_b)];
    const Vec6 d = CalcRodRelativeMotion(HA, HB, data.w_ref[e]);
    Vec12 eta_ab;
    eta_ab << data.v.segment<6>(model.nodes[static_cast<std::size_t>(el.node_a)].dof),
        data.v.segment<6>(model.nodes[static_cast<std::size_t>(el.node_b)].dof);
    for (int i = 0; i < 3; ++i) {
      const SE3 H = HA * ExpSE3(kGaussXi[i] * d);
      const Vec6 eta = CalcRodN(kGaussXi[i], d) * eta_ab;
      h += el.length * kGaussW[i] * (Ad(H.Inverse()).transpose() * (M * eta));
    }
  }
  return h;
}

struct RunResult {
  double momentum_drift = 0.0;  // max |h(t) - h(0)| / |h(0)|
  double energy_drift = 0.0;    // max |E(t) - E(0)| / E(0)
  double momentum_rate = 0.0;   // max |world resultant of the residual's inertia forces|
  long iterations = 0;
};

RunResult Simulate(int num_elements, double h, double t_end) {
  const Model model = MakeFreeRod(num_elements);
  Data data = MakeData(model);
  SetInitialVelocity(model, data);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 1.0;
  // Converge Newton to the round-off floor, so that the residual's momentum balance below
  // measures the discretisation, not the stopping rule.
  options.residual_tolerance = 1e-14;
  EXPECT_TRUE(InitializeDynamics(model, data, integ, options));
  const Vec6 h0 = WorldMomentum(model, data);
  const double e0 = CalcEnergy(model, data).total();
  RunResult r;
  const int steps = static_cast<int>(std::lround(t_end / h));
  for (int k = 0; k < steps; ++k) {
    const StepResult st = Step(model, data, integ, h);
    EXPECT_TRUE(st.ok) << st.message;
    if (!st.ok) break;
    r.momentum_drift =
        std::max(r.momentum_drift, (WorldMomentum(model, data) - h0).norm() / h0.norm());
    r.energy_drift = std::max(r.energy_drift, std::abs(CalcEnergy(model, data).total() - e0) / e0);
  }
  r.iterations = integ.iterations;
  // Instantaneous momentum balance at the final state: the world resultant of the nodal
  // inertia forces (the residual with c = 0 and no other forces) vanishes.
  AssemblyOptions o;
  o.time = data.time;
  o.dynamics = true;
  o.assemble_matrix = false;
  Assemble(model, data, o);
  Vec6 resultant = Vec6::Zero();
  for (std::size_t i = 0; i < model.nodes.size(); ++i)
    resultant += Ad(data.H[i].Inverse()).transpose() * data.residual.segment<6>(model.nodes[i].dof);
  // Relative to the round-off floor of the residual, eps times its largest cancelling term
  // (here eps EA |x| / L_e of the internal forces, data.term_scale).
  r.momentum_rate = resultant.norm() / (std::numeric_limits<double>::epsilon() *
                                        std::max(data.term_scale, data.force_scale));
  return r;
}

TEST(FreeRod, MomentumAndEnergyAreConservedToSecondOrderAndTheMomentumRateToRoundOff) {
  const double t_end = 1.0;
  const double steps[4] = {1e-2, 5e-3, 2.5e-3, 1.25e-3};
  RunResult r[4];
  for (int k = 0; k < 4; ++k) {
    r[k] = Simulate(8, steps[k], t_end);
    std::printf(
        "[ free rod ] h = %.4g: momentum drift %.3e, energy drift %.3e, momentum rate "
        "%.1f eps x term scale, %.2f Newton it/step\n",
        steps[k], r[k].momentum_drift, r[k].energy_drift, r[k].momentum_rate,
        static_cast<double>(r[k].iterations) * steps[k] / t_end);
  }
  // Newton stops at the round-off floor (32 eps x term_scale per entry, DynamicOptions).
  for (int k = 0; k < 4; ++k) EXPECT_LT(r[k].momentum_rate, 100.0);
  // Observed order over the four steps (and each halving within [3, 5.5]).
  const double energy_order = std::log2(r[0].energy_drift / r[3].energy_drift) / 3.0;
  const double momentum_order = std::log2(r[0].momentum_drift / r[3].momentum_drift) / 3.0;
  std::printf("[ free rod ] observed order: energy %.3f, momentum %.3f\n", energy_order,
              momentum_order);
  EXPECT_NEAR(energy_order, 2.0, 0.15);
  EXPECT_NEAR(momentum_order, 2.0, 0.15);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(r[k].energy_drift / r[k + 1].energy_drift, 4.25, 1.25) << "h " << steps[k];
    EXPECT_NEAR(r[k].momentum_drift / r[k + 1].momentum_drift, 4.0, 0.5) << "h " << steps[k];
  }
  EXPECT_LT(r[3].energy_drift, 1e-6);
  EXPECT_LT(r[3].momentum_drift, 2e-5);
}

TEST(FreeRod, FreeFreeBendingFrequenciesAndSixRigidModes) {
  // Free-free Euler-Bernoulli: beta L = 4.7300407449, 7.8532046241 (docs/validation.md, D1), here
  // with EI = 10, rhoA = 1, L = 1 and 24 elements, made slender (EA = GA = 1e7, rotary inertia
  // 1e-7: Timoshenko corrections below 1e-5).
  const Model model = MakeFreeRod(24, 1e7, 1e-7);
  Data data = MakeData(model);
  ModalOptions options;
  options.num_modes = 12;
  const ModalResult r = CalcModes(model, data, options);
  ASSERT_TRUE(r.ok) << r.message;
  // Rigid modes: zero up to round-off of the stiffest (rotary) modes, ~1e-16 * 1e11.
  for (int i = 0; i < 6; ++i)
    EXPECT_LT(std::sqrt(std::abs(r.eigenvalues(i))), 1e-3 * r.omega(6)) << "rigid mode " << i;
  const double scale = std::sqrt(10.0);
  const double beta[2] = {4.7300407449, 7.8532046241};
  // Each bending frequency appears twice (two section axes); torsion and axial are higher.
  for (int n = 0; n < 2; ++n)
    for (int j = 0; j < 2; ++j) {
      const double w = r.omega(6 + 2 * n + j), expected = beta[n] * beta[n] * scale;
      std::printf(
          "[ free rod ] free-free bending %d: omega %.6f rad/s, Euler-Bernoulli %.6f, "
          "error %+.2e\n",
          n + 1, w, expected, w / expected - 1.0);
      EXPECT_NEAR(w / expected, 1.0, 5e-3);
    }
}

}  // namespace
}  // namespace screwfem::free_rod_test
