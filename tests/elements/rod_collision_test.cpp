// Issue 16, "momentum conserved in a free collision of two rods to the formulation's
// tolerance": two free rods (no gravity, no clamp) crossing at right angles collide through
// rod-rod shape pairs (elements/shape_pair.h) and separate. The total momentum is the one
// energy.csv writes (CalcMomentum: rods by Gauss quadrature of the helical velocity field,
// about the world origin). The forces of a pair are equal and opposite with a common line of
// action (the normal through the two surface points), so the contact adds neither momentum nor
// angular momentum; what remains is the integrator's: generalized-alpha on the Lie group with
// body-frame velocities conserves the momentum of rotating nodes only to its discretisation
// error, O(h^2) (docs/numerics.md, "Contact between moving shapes").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"

namespace screwfem::rod_collision_test {
namespace {

struct Collision {
  double momentum_drift = 0.0;  // max over the steps of |p(t) - p(0)| [kg m/s]
  double angular_drift = 0.0;   // max of |L(t) - L(0)| about the origin [kg m^2/s]
  double p0 = 0.0, L0 = 0.0;    // |p(0)|, |L(0)|: the scales
  double energy_before = 0.0, energy_after = 0.0;  // T + strain + penalty [J]
  double max_force = 0.0;                          // the largest contact force in the run [N]
  bool apart_at_end = false;                       // no active pair at the end
  double spin = 0.0;  // the largest node angular speed at the end [rad/s]
  // max over the steps of |L(t) - L(0) - C(t)|, C the impulse of the friction couples (below)
  double angular_residual = 0.0;
  std::vector<Vec3> positions;   // of the nodes at the end
  int bandwidth = 0;             // of the model's matrix
  int most_coupled = 0;          // most node blocks in the off-band coupling at a step's end
  std::vector<long> iterations;  // Newton iterations of each step
  long analyses = 0, pattern_changes = 0, pattern_hits = 0;  // the sparse LU's counters
};

// The moment about the origin of a pair's two forces, F at A's surface point and -F at B's:
// (p_A - p_B) x F = g n x f_t, the couple of the friction force across the gap (zero without
// friction or at g = 0).
Vec3 FrictionCouple(const Model& m, const Data& d) {
  Vec3 M = Vec3::Zero();
  for (std::size_t k = 0; k < static_cast<std::size_t>(d.num_shape_pairs); ++k) {
    const ShapePairState c = CalcShapePairState(m, d, static_cast<int>(k));
    if (c.active) M += (c.point[0] - c.point[1]).cross(c.friction_force);
  }
  return M;
}

// Rod A (0.2 m, 6 elements, r = 5 mm, E = 100 MPa, 1000 kg/m^3) along x at z = 0 moving up at
// 0.1 m/s; rod B the same along y, 3 mm above A's surface, crossing A at x = `cross_x` (A's
// centre at 0) and at `cross_y` of B's own centre, moving down at 0.1 m/s and sideways along x
// at `slide` m/s. k_n = 100 N/m, delta = 1 mm (omega_c h ~ 0.2 at h = 1e-3 for the elements'
// masses), no gravity. 60 ms: the rods meet after ~15 ms, touch for ~20 ms and separate.
Collision Collide(double h, double cross_x, double cross_y, double slide, double mu, double zeta,
                  double rho_inf, int band_pair_nodes = ContactSettings{}.band_pair_nodes,
                  LinearSolver solver = LinearSolver::kAuto) {
  const double r = 0.005, L = 0.2, clearance = 0.003, v = 0.1;
  Material mat;
  mat.youngs_modulus = 1e8;
  mat.poisson_ratio = 0.4;
  mat.density = 1000.0;
  const Section section = Section::Circle(r, mat);
  ModelBuilder b;
  const RodId a =
      b.AddStraightRod("a", Vec3(-0.5 * L, 0.0, 0.0), Vec3(0.5 * L, 0.0, 0.0), 6, section);
  const double z = 2.0 * r + 1e-3 + clearance;
  const RodId c = b.AddStraightRod("b", Vec3(cross_x, -0.5 * L - cross_y, z),
                                   Vec3(cross_x, 0.5 * L - cross_y, z), 6, section);
  b.AddContactRod(a, r);
  b.AddContactRod(c, r);
  ContactSettings law;
  law.stiffness = 100.0;
  law.onset = 1e-3;
  law.friction = mu;
  law.slip_velocity = 1e-3;
  law.friction_law = FrictionLaw::kSmooth;  // the convergence order of the smooth law
  law.damping_ratio = zeta;
  law.band_pair_nodes = band_pair_nodes;
  b.SetContactSettings(law);
  b.SetLinearSolver(solver);
  for (RodId rod : {a, c}) {
    const Vec3 world = rod == a ? Vec3(0.0, 0.0, v) : Vec3(slide, 0.0, -v);
    for (NodeId node : b.RodNodes(rod)) {
      const Mat3& R = b.model().nodes[static_cast<std::size_t>(node)].reference.R;
      Vec6 eta = Vec6::Zero();
      eta.head<3>() = R.transpose() * world;
      b.SetInitialVelocity(node, eta);
    }
  }
  const Model m = b.Build();
  EXPECT_EQ(AllShapePairs(m).size(), 36u);
  Data d = MakeData(m);
  Integrator integ;
  std::string message;
  EXPECT_TRUE(AssembleInitialState(m, d, &message)) << message;
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  EXPECT_TRUE(InitializeDynamics(m, d, integ, opt, &message)) << message;
  Collision out;
  out.bandwidth = m.bandwidth;
  const Vec6 h0 = CalcMomentum(m, d);
  out.p0 = h0.head<3>().norm();
  out.L0 = h0.tail<3>().norm();
  out.energy_before = CalcEnergy(m, d).total();
  const int n = static_cast<int>(std::lround(0.06 / h));
  Vec3 couple = FrictionCouple(m, d), impulse = Vec3::Zero();
  for (int i = 0; i < n; ++i) {
    const long before = integ.iterations;
    const StepResult s = Step(m, d, integ, h);
    EXPECT_TRUE(s.ok) << "step " << i << " at h = " << h;
    if (!s.ok) return out;
    out.iterations.push_back(integ.iterations - before);
    const Vec6 hm = CalcMomentum(m, d);
    out.momentum_drift = std::max(out.momentum_drift, (hm.head<3>() - h0.head<3>()).norm());
    out.angular_drift = std::max(out.angular_drift, (hm.tail<3>() - h0.tail<3>()).norm());
    const Vec3 next = FrictionCouple(m, d);
    impulse += 0.5 * h * (couple + next);
    couple = next;
    out.angular_residual =
        std::max(out.angular_residual, (hm.tail<3>() - h0.tail<3>() - impulse).norm());
    for (std::size_t k = 0; k < static_cast<std::size_t>(d.num_shape_pairs); ++k)
      out.max_force =
          std::max(out.max_force, CalcShapePairState(m, d, static_cast<int>(k)).normal_force);
    out.most_coupled = std::max(out.most_coupled, d.coupling.blocks());
  }
  for (const SE3& H : d.H) out.positions.push_back(H.x);
  out.apart_at_end = true;
  for (std::size_t k = 0; k < static_cast<std::size_t>(d.num_shape_pairs); ++k)
    out.apart_at_end = out.apart_at_end && !CalcShapePairState(m, d, static_cast<int>(k)).active;
  out.energy_after = CalcEnergy(m, d).total();
  out.analyses = d.sparse.analyses();
  out.pattern_changes = d.sparse.pattern_changes();
  out.pattern_hits = d.sparse.pattern_hits();
  for (std::size_t k = 0; k < m.nodes.size(); ++k)
    out.spin = std::max(out.spin, d.v.segment<3>(m.nodes[k].dof + 3).norm());
  return out;
}

// Frictionless, undamped, rho_inf = 1, B crossing A 40 mm from A's centre and 30 mm from its
// own: the rods spin and bend (node angular speeds up to 1.8 rad/s after the impact). The
// momentum (total 0, each rod 1.57e-3 kg m/s) and the angular momentum about the origin (7.85e-5
// kg m^2/s) drift at second order in h: measured 7.1e-8 / 1.8e-8 / 4.5e-9 kg m/s and 2.2e-9 /
// 5.5e-10 / 1.4e-10 kg m^2/s at h = 1e-3 / 5e-4 / 2.5e-4 s (ratios 4.0, 4.0). The energy after
// the impact (kinetic + strain, the rods vibrating) equals the energy before to 4.7e-5 / 1.7e-5
// / 7.0e-6 relative: the integrator's error (generalized-alpha at rho_inf = 1 conserves energy
// only to its discretisation error in a nonlinear problem), falling with h.
TEST(RodCollision, OffCentreImpactConservesMomentumAndEnergyToSecondOrderInH) {
  const double steps[3] = {1e-3, 5e-4, 2.5e-4};
  Collision r[3];
  for (int k = 0; k < 3; ++k) {
    r[k] = Collide(steps[k], 0.04, 0.03, 0.0, 0.0, 0.0, 1.0);
    EXPECT_GT(r[k].max_force, 0.1);  // the rods did collide (peak 0.12 N)
    EXPECT_TRUE(r[k].apart_at_end);  // and separated
    EXPECT_GT(r[k].spin, 1.0);       // off-centre: they spin
    EXPECT_LT(std::abs(r[k].energy_after - r[k].energy_before), 1e-4 * r[k].energy_before);
  }
  EXPECT_LT(r[0].momentum_drift, 1e-7);
  EXPECT_LT(r[0].angular_drift, 4e-9);
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(r[k].momentum_drift / r[k + 1].momentum_drift, 3.5) << k;  // second order
    EXPECT_GT(r[k].angular_drift / r[k + 1].angular_drift, 3.5) << k;
    EXPECT_GT(std::abs(r[k].energy_after - r[k].energy_before),
              1.5 * std::abs(r[k + 1].energy_after - r[k + 1].energy_before))
        << k;
  }
}

// Head-on: B crosses A at both centres, moving straight at it. The rods bend (node spins up to
// 0.35 rad/s) but symmetrically, and the momentum and angular momentum stay at round-off
// (measured 1e-18 kg m/s and 1e-19 kg m^2/s at every step).
TEST(RodCollision, HeadOnImpactConservesMomentumToRoundOff) {
  const Collision r = Collide(1e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0);
  EXPECT_GT(r.max_force, 0.05);
  EXPECT_TRUE(r.apart_at_end);
  EXPECT_LT(r.momentum_drift, 1e-15);
  EXPECT_LT(r.angular_drift, 1e-15);
  EXPECT_LT(std::abs(r.energy_after - r.energy_before), 5e-4 * r.energy_before);  // 3.3e-4
}

// Oblique with friction (mu = 0.4, B sliding along A at 0.05 m/s) and damping (zeta = 1,
// rho_inf = 0.8): the momentum still drifts at second order (1.7e-7 / 4.3e-8 / 1.1e-8 kg m/s),
// but the angular momentum changes by 8.8e-8 kg m^2/s (1e-3 of it) at every h: the penalty
// law's own error, the friction force acting at A's and B's surface points, which are the gap
// g apart along n, makes a couple g n x f_t. With that couple's impulse taken off, the
// remainder falls at second order (2.5e-9 / 7.6e-10 / 1.9e-10).
TEST(RodCollision, FrictionChangesAngularMomentumOnlyByTheCoupleAcrossTheGap) {
  const double steps[3] = {1e-3, 5e-4, 2.5e-4};
  Collision r[3];
  for (int k = 0; k < 3; ++k) {
    r[k] = Collide(steps[k], 0.04, 0.03, 0.05, 0.4, 1.0, 0.8);
    EXPECT_GT(r[k].max_force, 0.1);
    EXPECT_TRUE(r[k].apart_at_end);
    EXPECT_LT(r[k].energy_after, 0.5 * r[k].energy_before);  // damping and friction dissipate
    EXPECT_GT(r[k].angular_drift, 5e-8);                     // the couple: not an O(h^2) error
    EXPECT_LT(r[k].angular_drift, 1.2e-7);
  }
  EXPECT_LT(r[0].momentum_drift, 2.5e-7);
  EXPECT_LT(r[0].angular_residual, 4e-9);
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(r[k].momentum_drift / r[k + 1].momentum_drift, 3.5) << k;
    EXPECT_GT(r[k].angular_residual / r[k + 1].angular_residual, 3.0) << k;
  }
}

// The pairs' node blocks outside the band (ContactSettings::band_pair_nodes = 0: the two rods
// are not linked in the band) solved by the Woodbury identity (Data::coupling) give the motion
// of the band that holds them (band_pair_nodes large) to round-off (measured 8e-17 m): the same
// Newton iterates, with the band of the rods alone (11 against 77; up to 5 nodes coupled).
TEST(RodCollision, OffBandCouplingGivesTheMotionOfTheWideBand) {
  const Collision off = Collide(1e-3, 0.04, 0.03, 0.05, 0.4, 1.0, 0.8, 0);
  const Collision band = Collide(1e-3, 0.04, 0.03, 0.05, 0.4, 1.0, 0.8, 1000);
  EXPECT_GT(off.max_force, 0.1);
  EXPECT_LT(off.bandwidth, band.bandwidth / 4);
  EXPECT_GT(off.most_coupled, 1);   // nodes of both rods were coupled off the band
  EXPECT_EQ(band.most_coupled, 0);  // the band held every block
  ASSERT_EQ(off.positions.size(), band.positions.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < off.positions.size(); ++k)
    worst = std::max(worst, (off.positions[k] - band.positions[k]).norm());
  EXPECT_LT(worst, 1e-12);  // [m]; the rods travel 6 mm
  EXPECT_NEAR(off.momentum_drift, band.momentum_drift, 1e-12);
}

// The same collision on the sparse LU, whose pattern takes the pairs' node blocks (no off-band
// coupling; SelectSparsePattern): the same Newton iterates as the Woodbury solve of the band to
// round-off (measured 1.6e-16 m), the same iterations in every step; the pattern changes
// with the pairs the broad phase finds, one analysis per new pattern (measured: 1 change, 2
// analyses in all).
TEST(RodCollision, SparsePatternOfThePairsGivesTheIteratesOfTheWoodburySolve) {
  const Collision off = Collide(1e-3, 0.04, 0.03, 0.05, 0.4, 1.0, 0.8, 0, LinearSolver::kBanded);
  const Collision sparse = Collide(1e-3, 0.04, 0.03, 0.05, 0.4, 1.0, 0.8, 0, LinearSolver::kSparse);
  EXPECT_GT(off.most_coupled, 1);
  EXPECT_EQ(sparse.most_coupled, 0);  // nothing off the pattern
  EXPECT_EQ(sparse.iterations, off.iterations);
  ASSERT_EQ(off.positions.size(), sparse.positions.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < off.positions.size(); ++k)
    worst = std::max(worst, (off.positions[k] - sparse.positions[k]).norm());
  EXPECT_LT(worst, 1e-12);               // [m]
  EXPECT_GE(sparse.pattern_changes, 1);  // the pairs came
  EXPECT_EQ(sparse.analyses, 1 + sparse.pattern_changes - sparse.pattern_hits);
  std::printf("sparse against Woodbury: %.3g m; pattern changes %ld, hits %ld, analyses %ld\n",
              worst, sparse.pattern_changes, sparse.pattern_hits, sparse.analyses);
}

// Two parallel rods of 80 elements (162 nodes) pressed together along their whole length, with
// friction: the pairs couple more nodes than the banded solve's off-band coupling holds
// (kMaxCoupledNodes = 128), so its default iteration is quasi-Newton. The sparse LU's pattern
// holds every pair: the iterations of each step equal those of the banded LU with a coupling
// enlarged to hold them all (the exact Newton matrix), to the same iterates (measured
// 4.4e-16 m), and no more than the quasi-Newton iteration's (measured over 15 steps: 92 and 92
// against 97; 6 steps here, the enlarged Woodbury solve is slow: k = 972).
struct SideBySide {
  std::vector<long> iterations;
  std::vector<Vec3> positions;
  int most_coupled = 0;
  bool overflowed = false;
  long analyses = 0;
};
SideBySide PressTogether(LinearSolver solver, int room) {
  const double r = 0.005, L = 0.8;
  Material mat;
  mat.youngs_modulus = 1e8;
  mat.poisson_ratio = 0.4;
  mat.density = 1000.0;
  const Section section = Section::Circle(r, mat);
  ModelBuilder b;
  const RodId a = b.AddStraightRod("a", Vec3(0, 0, 0), Vec3(L, 0, 0), 80, section);
  const RodId c =
      b.AddStraightRod("b", Vec3(0, 0, 2 * r + 8e-4), Vec3(L, 0, 2 * r + 8e-4), 80, section);
  b.AddContactRod(a, r);
  b.AddContactRod(c, r);
  ContactSettings law;
  law.stiffness = 10.0;
  law.onset = 1e-3;
  law.damping_ratio = 0.0;
  law.friction = 0.3;
  law.slip_velocity = 1e-3;
  law.band_pair_nodes = 0;
  b.SetContactSettings(law);
  b.SetLinearSolver(solver);
  for (NodeId node : b.RodNodes(c)) {
    const Mat3& R = b.model().nodes[static_cast<std::size_t>(node)].reference.R;
    Vec6 eta = Vec6::Zero();
    eta.head<3>() = R.transpose() * Vec3(0.01, 0.0, -0.02);
    b.SetInitialVelocity(node, eta);
  }
  const Model m = b.Build();
  EXPECT_EQ(m.sparse_solver, solver == LinearSolver::kSparse);
  Data d = MakeData(m);
  if (room > 0) d.coupling.Resize(m.num_unknowns(), 6, room);
  Integrator integ;
  std::string message;
  EXPECT_TRUE(AssembleInitialState(m, d, &message)) << message;
  EXPECT_TRUE(InitializeDynamics(m, d, integ, DynamicOptions{}, &message)) << message;
  SideBySide out;
  for (int i = 0; i < 6; ++i) {
    const long before = integ.iterations;
    EXPECT_TRUE(Step(m, d, integ, 1e-3).ok) << i;
    out.iterations.push_back(integ.iterations - before);
    out.most_coupled = std::max(out.most_coupled, d.coupling.blocks());
    out.overflowed = out.overflowed || d.coupling.overflowed();
  }
  for (const SE3& H : d.H) out.positions.push_back(H.x);
  out.analyses = d.sparse.analyses();
  return out;
}

TEST(RodCollision, SparsePatternIsExactNewtonBeyondTheWoodburyRoom) {
  const SideBySide sparse = PressTogether(LinearSolver::kSparse, 0);
  const SideBySide exact = PressTogether(LinearSolver::kBanded, 200);
  const SideBySide quasi = PressTogether(LinearSolver::kBanded, 0);
  EXPECT_GT(exact.most_coupled, kMaxCoupledNodes);  // the pairs couple more nodes than 128
  EXPECT_FALSE(exact.overflowed);
  EXPECT_TRUE(quasi.overflowed);
  EXPECT_EQ(sparse.iterations, exact.iterations);
  double worst = 0.0;
  for (std::size_t k = 0; k < sparse.positions.size(); ++k)
    worst = std::max(worst, (sparse.positions[k] - exact.positions[k]).norm());
  EXPECT_LT(worst, 1e-12);  // [m]
  long total[3] = {0, 0, 0};
  for (std::size_t k = 0; k < sparse.iterations.size(); ++k) {
    total[0] += sparse.iterations[k];
    total[1] += exact.iterations[k];
    total[2] += quasi.iterations[k];
  }
  EXPECT_LE(total[0], total[2]);
  std::printf(
      "sparse against enlarged Woodbury: %.3g m; iterations sparse %ld, exact %ld, "
      "quasi-Newton %ld; most coupled %d; analyses %ld\n",
      worst, total[0], total[1], total[2], exact.most_coupled, sparse.analyses);
}

}  // namespace
}  // namespace screwfem::rod_collision_test
