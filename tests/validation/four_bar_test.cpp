// A planar four-bar linkage built from spatial joints: a closed loop, with and without
// redundant constraints.
//
// Geometry (the loop of [G]'s example, method.md §7.2): ground pivots O = (0, 0, 0) and
// D = (1.2, 0, 0), crank O-A with A = (0.2, 0.6, 0) (0.6325 m), coupler A-B with B = (1, 1, 0)
// (0.8944 m), rocker D-B (1.0198 m): Grashof crank-rocker. Each link is a rigid body (m = 0.15
// kg, J = 1e-4 kg m^2 about its CoM at mid-link) whose node sits at its first joint point
// (crank at O, coupler at A, rocker at D) with world-aligned axes.
//
// Pure-revolute loop: four revolute joints about z. Spatially this has 3 redundant constraint
// equations (24 constraint rows + 1 drive on 22 unknowns, 1 DOF before the drive); the model
// detects them at build time and holds their multipliers at zero. Non-redundant variant:
// revolute at O and D, spherical at A, universal at B (axes z and z x AB), whose spatial
// mobility is exactly one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem {
namespace {

constexpr double kPi = std::numbers::pi;
const Vec3 kO(0.0, 0.0, 0.0), kA(0.2, 0.6, 0.0), kB(1.0, 1.0, 0.0), kD(1.2, 0.0, 0.0);
constexpr double kMass = 0.15, kJc = 1e-4;

enum class Variant { kRevolutes, kSphericalUniversal };

struct FourBar {
  Model model;
  Data data;
  Integrator integ;
  int crank = 0, coupler = 0, rocker = 0;  // nodes
  int drive_joint = 0;
};

void AddLink(ModelBuilder& b, int node, const Vec3& from, const Vec3& to, const std::string& name) {
  b.AddRigidBody(name, node, kMass, 0.5 * (to - from), kJc * Mat3::Identity());
}

// Builds the loop; `drive` (if non-empty) prescribes the crank angle relative to its start.
Model BuildFourBar(Variant variant, const Profile* drive, bool gravity, FourBar* fb) {
  ModelBuilder b;
  fb->crank = b.AddNode(SE3::Translation(kO), "crank");
  fb->coupler = b.AddNode(SE3::Translation(kA), "coupler");
  fb->rocker = b.AddNode(SE3::Translation(kD), "rocker");
  AddLink(b, fb->crank, kO, kA, "crank");
  AddLink(b, fb->coupler, kA, kB, "coupler");
  AddLink(b, fb->rocker, kD, kB, "rocker");
  const Vec3 z = Vec3::UnitZ();
  fb->drive_joint = b.AddJointAt("O", JointType::kRevolute, kGround, fb->crank, kO, z);
  if (variant == Variant::kRevolutes) {
    b.AddJointAt("A", JointType::kRevolute, fb->crank, fb->coupler, kA, z);
    b.AddJointAt("B", JointType::kRevolute, fb->coupler, fb->rocker, kB, z);
  } else {
    b.AddJointAt("A", JointType::kSpherical, fb->crank, fb->coupler, kA);
    b.AddJointAt("B", JointType::kUniversal, fb->coupler, fb->rocker, kB, z,
                 z.cross(kB - kA).normalized());
  }
  b.AddJointAt("D", JointType::kRevolute, fb->rocker, kGround, kD, z);
  if (drive) {
    Joint& j = b.model().joints[static_cast<std::size_t>(fb->drive_joint)];
    j.drive = DriveKind::kPrescribed;
    j.drive_profile = *drive;
  }
  if (gravity) b.SetGravity(Vec3(0.0, -9.81, 0.0));
  return b.Build();
}

bool Initialize(FourBar* fb, double rho_inf) {
  fb->data = MakeData(fb->model);
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  std::string message;
  const bool ok = InitializeDynamics(fb->model, fb->data, fb->integ, opt, &message);
  EXPECT_TRUE(ok) << message;
  return ok;
}

// Closed-form position analysis: for crank angle theta2 (from +x), the coupler and rocker
// angles (from +x) on the assembly branch of the reference configuration (B to the left of
// the diagonal A -> D).
struct LoopAngles {
  double coupler, rocker;
};
LoopAngles SolveLoop(double theta2) {
  const double l2 = (kA - kO).norm(), l3 = (kB - kA).norm(), l4 = (kB - kD).norm();
  const Vec3 A = kO + l2 * Vec3(std::cos(theta2), std::sin(theta2), 0.0);
  const Vec3 AD = kD - A;
  const double d = AD.norm();
  // B = A + a e + s h n, e = AD/d, n = z x e, a = (l3^2 - l4^2 + d^2) / (2d).
  const double a = (l3 * l3 - l4 * l4 + d * d) / (2.0 * d);
  const double hgt = std::sqrt(l3 * l3 - a * a);
  const Vec3 e = AD / d, n = Vec3::UnitZ().cross(e);
  const Vec3 B = A + a * e + hgt * n;  // the reference has (B - A) . n > 0
  return {std::atan2(B.y() - A.y(), B.x() - A.x()), std::atan2(B.y() - kD.y(), B.x() - kD.x())};
}

double Wrap(double a) { return std::remainder(a, 2.0 * kPi); }
double NodeAngle(const FourBar& fb, int node) {
  const Mat3& R = fb.data.H[static_cast<std::size_t>(node)].R;
  return std::atan2(R(1, 0), R(0, 0));
}

// Largest deviation of the joint constraints (all 6 components of every joint, including the
// redundant ones) and of the drive.
double ConstraintResidual(const FourBar& fb) {
  double r = 0.0;
  for (std::size_t j = 0; j < fb.model.joints.size(); ++j)
    r = std::max(r, JointConstraint(fb.model, fb.data, static_cast<int>(j)).cwiseAbs().maxCoeff());
  return r;
}

void RunPrescribedCrank(Variant variant) {
  const double theta2_0 = std::atan2(kA.y(), kA.x());
  const LoopAngles ref = SolveLoop(theta2_0);
  ASSERT_NEAR(ref.coupler, std::atan2(kB.y() - kA.y(), kB.x() - kA.x()), 1e-14);
  // One full crank revolution in 1 s, bang-bang, then at rest; gravity in the plane.
  const Profile crank = Profile::BangBang(0.0, 1.0, 2.0 * kPi);
  FourBar fb;
  fb.model = BuildFourBar(variant, &crank, true, &fb);
  if (variant == Variant::kRevolutes) {
    EXPECT_EQ(fb.model.redundant_rows.size(), 3u);
  } else {
    EXPECT_TRUE(fb.model.redundant_rows.empty());
  }
  ASSERT_TRUE(Initialize(&fb, 0.9));
  const double h = 1e-3;
  double max_angle = 0.0, max_phi = 0.0, max_viol = 0.0;
  for (int n = 1; n <= 1200; ++n) {
    const StepResult r = Step(fb.model, fb.data, fb.integ, h);
    ASSERT_TRUE(r.ok) << r.message;
    const double t = n * h;
    const double theta2 = theta2_0 + fb.data.q_joint(0);
    EXPECT_NEAR(fb.data.q_joint(0), crank(t), 1e-10);
    const LoopAngles exact = SolveLoop(theta2);
    max_angle = std::max(max_angle, std::abs(Wrap(ref.coupler + NodeAngle(fb, fb.coupler) - exact.coupler)));
    max_angle = std::max(max_angle, std::abs(Wrap(ref.rocker + NodeAngle(fb, fb.rocker) - exact.rocker)));
    max_angle = std::max(max_angle, std::abs(Wrap(theta2_0 + NodeAngle(fb, fb.crank) - theta2)));
    max_phi = std::max(max_phi, ConstraintResidual(fb));
    max_viol = std::max(max_viol, MaxConstraintViolation(fb.model, fb.data, t, 1.0));
  }
  EXPECT_LT(max_angle, 1e-8);
  EXPECT_LT(max_phi, 1e-10);
  EXPECT_LT(max_viol, 1e-10);
  // The crank went round once and stopped; the loop closed back on its start.
  EXPECT_NEAR(Wrap(NodeAngle(fb, fb.coupler)), 0.0, 1e-8);
  EXPECT_NEAR(Wrap(NodeAngle(fb, fb.rocker)), 0.0, 1e-8);
  // The redundant multipliers stay at zero.
  for (int row : fb.model.redundant_rows) EXPECT_EQ(fb.data.lambda(row), 0.0);
}

TEST(FourBar, PrescribedCrankMatchesClosedFormPositionAnalysisWithRedundantRevoluteLoop) {
  RunPrescribedCrank(Variant::kRevolutes);
}

TEST(FourBar, PrescribedCrankMatchesClosedFormPositionAnalysisWithoutRedundancy) {
  RunPrescribedCrank(Variant::kSphericalUniversal);
}

// Unactuated loop released at rest under gravity, rho_inf = 1: the energy error is bounded
// and converges at O(h^2).
double EnergyError(Variant variant, double h) {
  FourBar fb;
  fb.model = BuildFourBar(variant, nullptr, true, &fb);
  if (!Initialize(&fb, 1.0)) return INFINITY;
  const double E0 = CalcEnergy(fb.model, fb.data).total();
  double err = 0.0;
  const int steps = static_cast<int>(std::lround(1.0 / h));
  for (int n = 1; n <= steps; ++n) {
    const StepResult r = Step(fb.model, fb.data, fb.integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) return INFINITY;
    err = std::max(err, std::abs(CalcEnergy(fb.model, fb.data).total() - E0));
  }
  EXPECT_LT(ConstraintResidual(fb), 1e-10);
  // It really moved: the crank swung by more than 0.5 rad at some point is not tracked; the
  // kinetic energy at the end is a sizeable part of the potential drop.
  EXPECT_GT(CalcEnergy(fb.model, fb.data).kinetic, 1e-3);
  return err;
}

TEST(FourBar, UnactuatedRedundantLoopEnergyErrorIsSecondOrderWithRhoInfOne) {
  for (Variant v : {Variant::kRevolutes, Variant::kSphericalUniversal}) {
    SCOPED_TRACE(v == Variant::kRevolutes ? "revolutes (redundant)" : "spherical + universal");
    const double e1 = EnergyError(v, 2e-3), e2 = EnergyError(v, 1e-3);
    EXPECT_GT(e1 / e2, 3.5);
    EXPECT_LT(e1 / e2, 4.5);
    EXPECT_LT(e2, 1e-4);
  }
}

}  // namespace
}  // namespace screwfem
