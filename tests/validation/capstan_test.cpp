// The capstan (Euler-Eytelwein; docs/numerics.md, "Contact", issue 16): a soft cord (small EI)
// wrapped over a fixed cylinder (a capsule obstacle) through an angle theta, loaded by T1 at one
// end and T2 at the other. Coulomb friction holds it while T2/T1 < e^{mu theta}, and it slips
// above. With the regularised law (docs/numerics.md, "Contact") a held cord creeps: every contact
// slides at the same speed v, where the friction is mu_eff = mu v / sqrt(v^2 + eps_v^2), so the
// cord settles at the v for which e^{mu_eff theta} = T2/T1. The onset of slip follows from the
// measured creep speed as T2/T1 raised to mu / mu_eff; it must be e^{mu theta} to 2 %. The
// second test pulls end 2 at a constant speed by a prescribed drive and reads T2 from the
// drive's effort (T6.5 as the note states it).
//
// Measured (h = 1e-3 s, T2/T1 = 0.98 e^{mu theta}, mu = 0.3, eps_v = 1e-3 m/s): creep
// 3.450 / 5.192 mm/s (the continuous law: 3.304 / 4.752), onset ratio 1.59936 vs 1.60198
// (-0.16 %) at theta = pi/2 and 2.55800 vs 2.56633 (-0.32 %) at theta = pi; at 1.02 e^{mu theta}
// the cord slips, 0.147 -> 0.198 m/s and 0.140 -> 0.184 m/s over the last two quarters of 0.2 s.
// Two known offsets, both below: the chords (dtheta = pi/32; element contact at the chord's
// closest point, shared half and half by its nodes: -0.08 % and -0.17 % from the equilibrium of the
// chord polygon with tensions along the chords, solved by least squares), and the cord's thickness: friction acts at its surface, a radius r inside the
// axis, and its moment, carried by shear with EI ~ 0, lowers the exponent to
// mu theta (1 - r / rho) (-0.05 % and -0.09 % for r = 1e-4 m, rho = R + r; with r = 1e-3 m
// the onset fell to -0.6 % and -1.2 %).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/joint.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/statics.h"

namespace screwfem::capstan_test {
namespace {

// Cylinder radius R (axis along y through the origin), cord radius r, T1, friction.
constexpr double kR = 0.1, kCord = 1e-4, kT1 = 1.0, kMu = 0.3, kSlip = 1e-3;
constexpr double kStiffness = 2e4, kOnset = 5e-5;

// The unit radius and the direction of travel (clockwise in the x-z plane) at polar angle phi.
Vec3 Radial(double phi) { return Vec3(std::cos(phi), 0.0, std::sin(phi)); }
Vec3 Travel(double phi) { return Vec3(std::sin(phi), 0.0, -std::cos(phi)); }

struct Capstan {
  Model model;
  Data data;
  Integrator integ;
  int end2 = -1;     // the node pulled by T2
  Vec3 pull2;        // its direction
  int contacts = 0;  // wrapped elements
  int pull = -1;     // the joint pulling end 2, if any
};

// The cord runs over the top of the cylinder, polar angle from pi/2 + theta/2 down to
// pi/2 - theta/2, as a polygon of chords tangent to the cylinder (one element each, dtheta at
// most pi/32), with straight legs of 6 chords along the tangents at both ends. Its reference
// shape is the wrapped one (no bending moment at the start); EI = 1e-4 T1 R^2 (T6.5: bending
// adds O(EI / (R^2 T))); EA = GA = 1e4 N; 0.1 kg/m and 1e-5 kg m per length. No gravity: dead loads T1, T2
// along the legs.
void MakeCapstan(double theta, double ratio, Capstan* c, double pull_speed = 0.0,
                 FrictionLaw friction_law = FrictionLaw::kSmooth) {
  const int n = static_cast<int>(std::ceil(theta / (M_PI / 32.0) - 1e-9));
  const double dtheta = theta / n;
  // Start at the resting gap of the mean normal force per element.
  const double normal = 0.5 * (1.0 + ratio) * kT1 * 2.0 * std::sin(0.5 * dtheta);
  const double gap = kOnset - std::sqrt(2.0 * kOnset * normal / kStiffness);
  const double rho = (kR + kCord + gap) / std::cos(0.5 * dtheta);  // node circle
  const double chord = 2.0 * rho * std::sin(0.5 * dtheta);
  const double phi0 = 0.5 * M_PI + 0.5 * theta, phi1 = 0.5 * M_PI - 0.5 * theta;
  const int legs = 6;
  std::vector<Vec3> path;
  for (int j = legs; j >= 1; --j) path.push_back(rho * Radial(phi0) - j * chord * Travel(phi0));
  for (int k = 0; k <= n; ++k) path.push_back(rho * Radial(phi0 - k * dtheta));
  for (int j = 1; j <= legs; ++j) path.push_back(rho * Radial(phi1) + j * chord * Travel(phi1));

  const double EI = 1e-4 * kT1 * kR * kR;
  Vec6 stiffness, inertia;
  stiffness << 1e4, 1e4, 1e4, EI, EI, EI;
  inertia << 0.1, 0.1, 0.1, 1e-5, 1e-5, 1e-5;
  ModelBuilder b;
  const RodId rod =
      b.AddRodAlongPath("cord", path, 1, Section::FromDiagonals(stiffness, inertia), Vec3::UnitY());
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  PointLoad load1;
  load1.node = nodes.front();
  load1.force = -kT1 * Travel(phi0);
  b.AddPointLoad(load1);
  if (pull_speed > 0.0) {
    // End 2 on a prismatic joint along its leg, its drive pulling at pull_speed after a start
    // in five equal velocity steps over 0.05 s (ramps to the end of the run).
    JointSpec pull;
    pull.name = "pull";
    pull.type = JointType::kPrismatic;
    pull.node_a = kGround;
    pull.node_b = nodes.back();
    pull.point = path.back();
    pull.axis = Travel(phi1);
    pull.drive = DriveKind::kPrescribed;
    const double t_end = 10.0;
    for (int i = 0; i < 5; ++i) {
      const double t0 = 0.01 * i;
      pull.drive_profile.Add(Profile::Ramp(t0, t_end, 0.2 * pull_speed * (t_end - t0)));
    }
    c->pull = b.AddJoint(pull);
  } else {
    PointLoad load2;
    load2.node = nodes.back();
    load2.force = ratio * kT1 * Travel(phi1);
    b.AddPointLoad(load2);
  }
  b.AddContactRod(rod, kCord);
  b.AddObstacle({"drum", ObstacleType::kCapsule, Vec3(0.0, -0.1, 0.0), Vec3::UnitZ(),
                 Vec3(0.0, 0.1, 0.0), kR});
  ContactSettings law;
  law.stiffness = kStiffness;
  law.onset = kOnset;
  law.friction = kMu;
  law.slip_velocity = kSlip;
  law.friction_law = friction_law;
  b.SetContactSettings(law);
  c->model = b.Build();
  c->data = MakeData(c->model);
  c->end2 = nodes.back();
  c->pull2 = Travel(phi1);
  c->contacts = n;
  DynamicOptions opt;
  opt.rho_inf = 0.8;
  std::string message;
  ASSERT_TRUE(AssembleInitialState(c->model, c->data, &message)) << message;
  ASSERT_TRUE(InitializeDynamics(c->model, c->data, c->integ, opt, &message)) << message;
}

struct CapstanRun {
  double v_early = 0.0, v_late = 0.0;  // mean speed of end 2 along its pull [m/s]
  int active = 0;                      // active pairs at the end
  double iterations_per_step = 0.0;
  double effort_late = 0.0;  // mean drive effort over the last quarter [N]
};

// `steps` steps of h = 1e-3 s; mean speeds over the third and the last quarter of the run.
CapstanRun Simulate(Capstan* c, int steps) {
  CapstanRun out;
  const double h = 1e-3;
  double s_a = 0.0, s_b = 0.0;
  const Vec3 x0 = c->data.H[static_cast<std::size_t>(c->end2)].x;
  long iterations = 0;
  const int a = steps / 2, b = 3 * steps / 4;
  for (int i = 1; i <= steps; ++i) {
    const StepResult r = Step(c->model, c->data, c->integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) return out;
    iterations += r.iterations;
    const double s = c->pull2.dot(c->data.H[static_cast<std::size_t>(c->end2)].x - x0);
    if (i == a) s_a = s;
    if (i == b) {
      s_b = s;
      out.v_early = (s - s_a) / ((b - a) * h);
    }
    if (i == steps) out.v_late = (s - s_b) / ((steps - b) * h);
    if (i > b && c->pull >= 0)
      out.effort_late += JointDriveEffort(c->model, c->data, c->pull) / (steps - b);
  }
  for (int i = 0; i < static_cast<int>(c->model.contact_pairs.size()); ++i)
    if (CalcContactState(c->model, c->data, i).active) ++out.active;
  out.iterations_per_step = static_cast<double>(iterations) / steps;
  return out;
}

TEST(Capstan, HoldsBelowTheEulerEytelweinRatioAndSlipsAboveIt) {
  for (const double theta : {0.5 * M_PI, M_PI}) {
    const double limit = std::exp(kMu * theta);
    // Held: T2/T1 = 0.98 e^{mu theta}. The cord creeps at a steady speed v; the friction it
    // uses, mu_eff = mu v / sqrt(v^2 + eps^2), gives the onset ratio (T2/T1)^{mu / mu_eff}.
    Capstan held;
    MakeCapstan(theta, 0.98 * limit, &held);
    const CapstanRun h = Simulate(&held, 300);
    EXPECT_EQ(h.active, held.contacts) << "theta " << theta;
    const double x = h.v_late / std::hypot(h.v_late, kSlip);
    const double onset = std::pow(0.98 * limit, 1.0 / x);
    // Creep (not slip): the speed is steady and a few eps_v, as the continuous law predicts
    // (x_c = 1 + ln 0.98 / (mu theta), v = eps_v x_c / sqrt(1 - x_c^2)).
    const double x_c = 1.0 + std::log(0.98) / (kMu * theta);
    const double v_c = kSlip * x_c / std::sqrt(1.0 - x_c * x_c);
    EXPECT_GT(h.v_late, 0.0);
    EXPECT_NEAR(h.v_late, v_c, 0.15 * v_c) << "theta " << theta;
    EXPECT_NEAR(h.v_early, h.v_late, 0.02 * h.v_late) << "theta " << theta;
    // The issue asks 2 %; the model's offsets are smaller (see the file comment): 0.5 %.
    EXPECT_NEAR(onset, limit, 0.005 * limit) << "theta " << theta;
    // Slips: T2/T1 = 1.02 e^{mu theta}. The cord accelerates past the creep speeds.
    Capstan slips;
    MakeCapstan(theta, 1.02 * limit, &slips);
    const CapstanRun s = Simulate(&slips, 200);
    EXPECT_GT(s.v_late, 20.0 * v_c) << "theta " << theta;
    EXPECT_GT(s.v_late, 1.3 * s.v_early) << "theta " << theta;
  }
}

// T6.5 as the note states it: end 2 pulled at a constant speed V = 20 eps_v by a prescribed
// drive, end 1 loaded by T1; the drive's effort is T2 = T1 e^{mu_eff theta}, with
// mu_eff = mu V / sqrt(V^2 + eps_v^2) = 0.99875 mu. Measured: T2/T1 = 1.59834 (e^{mu theta} =
// 1.60198, e^{mu_eff theta} = 1.60104) at theta = pi/2 and 2.55446 (2.56633, 2.56332) at pi,
// the offsets of the file comment.
TEST(Capstan, PulledAtConstantSpeedTheDriveCarriesTheEulerEytelweinTension) {
  for (const double theta : {0.5 * M_PI, M_PI}) {
    const double V = 20.0 * kSlip;
    const double mu_eff = kMu * V / std::hypot(V, kSlip);
    Capstan c;
    MakeCapstan(theta, 0.0, &c, V);
    const CapstanRun r = Simulate(&c, 300);
    EXPECT_EQ(r.active, c.contacts) << "theta " << theta;
    EXPECT_NEAR(r.v_late, V, 1e-6 * V);  // the drive holds the speed
    const double ratio = std::abs(r.effort_late) / kT1;
    EXPECT_NEAR(ratio, std::exp(kMu * theta), 0.02 * std::exp(kMu * theta)) << "theta " << theta;
    EXPECT_NEAR(ratio, std::exp(mu_eff * theta), 0.005 * std::exp(mu_eff * theta))
        << "theta " << theta;
  }
}

// The stick law (docs/numerics.md, "Stick friction"): below e^{mu theta} the cord holds with no
// creep (end 2's mean speed below 1e-6 m/s, the smooth law's creep 3.45 mm/s) and a static solve
// finds the equilibrium; above it the cord slips and no static equilibrium exists.
TEST(Capstan, StickLawHoldsBelowTheRatioWithoutCreepInDynamicsAndStatics) {
  for (const double theta : {0.5 * M_PI, M_PI}) {
    const double limit = std::exp(kMu * theta);
    Capstan held;
    MakeCapstan(theta, 0.98 * limit, &held, 0.0, FrictionLaw::kStick);
    const CapstanRun h = Simulate(&held, 300);
    EXPECT_EQ(h.active, held.contacts) << "theta " << theta;
    // The mean speed of end 2 over the last quarter: what is left of the start's ringing on the
    // anchors (measured 4.4e-7 m/s, changing sign over longer runs), no creep (the smooth law's
    // is 3.45 mm/s here).
    EXPECT_LT(std::abs(h.v_late), 1e-6) << "theta " << theta;
    Capstan slips;
    MakeCapstan(theta, 1.02 * limit, &slips, 0.0, FrictionLaw::kStick);
    const CapstanRun s = Simulate(&slips, 200);
    EXPECT_GT(s.v_late, 0.05) << "theta " << theta;
    EXPECT_GT(s.v_late, 1.3 * s.v_early) << "theta " << theta;
    for (const double ratio : {0.98, 1.02}) {
      Capstan st;
      MakeCapstan(theta, ratio * limit, &st, 0.0, FrictionLaw::kStick);
      StaticOptions o;
      o.load_steps = 4;
      const StaticResult r = SolveStatic(st.model, st.data, o);
      EXPECT_EQ(r.converged, ratio < 1.0)
          << "theta " << theta << " ratio " << ratio << ": " << r.message;
    }
  }
}

}  // namespace
}  // namespace screwfem::capstan_test
