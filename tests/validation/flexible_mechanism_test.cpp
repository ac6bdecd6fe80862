// The flexible mechanism of docs/numerics.md tests 7-9 (reference numbers of the Python prototype).
//
// Reconstruction (the prototype is described only in words): every joint axis is world z and
// the chain starts along world x, so the mechanism moves in the horizontal plane and gravity
// (-z) bends the soft arm out of it.
//   ground --(actuated revolute at the origin, bang-bang 0 -> pi/6 on [0, 1] s)--> link 1
//   (node at the origin, 0.15 kg, CoM (0.25, 0, 0), J = 1e-4 I, length 0.5 m)
//   --(soft revolute at (0.5, 0, 0), K = 10 N m/rad, D = 5 N m s/rad)--> link 2
//   (node at (0.5, 0, 0), 0.15 kg, CoM (0.25, 0, 0) from it, J = 1e-4 I)
//   --(fixed joint = k = 0 weld at (0.7, 0, 0), 0.2 m from the link-2 node)--> soft arm
//   from (0.7, 0, 0) to (1.3, 0, 0) (0.6 m), M = diag(0.1 x3, 0.5 x3), K = diag(1e6 x3, 1 x3).
// Start at rest in this configuration, gravity -9.81 z from t = 0, rho_inf = 0.8, t = 0.6 s;
// output: tip z of the arm.
//
// Findings (measured numbers are printed):
//  * Option A reproduces the prototype's option-A values (3 elements, h = 1e-2/5e-3/2.5e-3) and
//    mesh sequence (3/6/12 elements) to ~1e-6 m, and converges at second order in h. The tip z
//    hardly depends on the reconstruction (link lengths 0.2 ... 1 m and weld offsets 0 ... 0.5 m
//    move it by < 1e-5 m): it is the arm's own sag under gravity.
//  * Our option B does NOT reproduce the prototype's option-B values: it gives a tip z within
//    ~3e-6 m of option A, where the prototype lists ~1e-3 m lower values. The prototype's B
//    numbers are reproduced to ~1e-6 m when, in addition to the inertia, the rod's GRAVITY is
//    distributed with the linear field N = [(1 - xi) I, xi I] (lumped nodal forces rhoA L_e g / 2,
//    no nodal moments), as checked below. docs/numerics.md, "Rod inertia" defines option B as the linear field
//    "in the inertia term only" and docs/theory.md §2.6 writes the gravity load with the exact N,
//    which is what screwfem does for both options. So the prototype's A-B gap (9.7e-4 -> 2.4e-4 ->
//    6.0e-5 m in tip z) and the "tip z differs by 1.0e-3 m (4 % of the sag) between A and B"
//    of docs/numerics.md, "Rod inertia" measure consistent versus lumped gravity loading, not the inertia
//    options; the listed option-B values are wrong for option B as docs/numerics.md defines it.
//  * The inertia options themselves differ by O(L_e^2) in the tip position (mostly in-plane,
//    1.3e-4 m with 3 elements), asserted below; in tip z alone the gap is below 3e-6 m and not
//    monotone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::flexible_mechanism_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEnd = 0.6;
const Vec3 kGravity(0.0, 0.0, -9.81);

// docs/numerics.md
constexpr double kStepSizes[4] = {1e-2, 5e-3, 2.5e-3, 1.25e-3};
constexpr double kPrototypeB[4] = {-0.0250677, -0.0250731, -0.0250745, -0.0250748};
constexpr double kPrototypeA[3] = {-0.0240993, -0.0241047, -0.0241060};
constexpr int kMeshes[3] = {3, 6, 12};
constexpr double kPrototypeMeshA[3] = {-0.024099, -0.024203, -0.024282};  // h = 1e-2
constexpr double kPrototypeMeshB[3] = {-0.025068, -0.024444, -0.024343};

enum class Gravity {
  kConsistent,  // screwfem: exact virtual displacement field N (elements/rod.h)
  kLumped,      // linear field for the rod's gravity: nodal forces rhoA L_e g / 2 per element end
};

struct Mechanism {
  Model model;
  int tip = -1;
  int drive = -1;
};

Mechanism MakeMechanism(RodInertia inertia, int num_elements, Gravity gravity) {
  ModelBuilder b;
  const Mat3 J = 1e-4 * Mat3::Identity();
  const NodeId link1 = b.AddNode(SE3::Identity(), "link1");
  b.AddRigidBody("link1", link1, 0.15, Vec3(0.25, 0.0, 0.0), J);
  const NodeId link2 = b.AddNode(SE3::Translation(Vec3(0.5, 0.0, 0.0)), "link2");
  b.AddRigidBody("link2", link2, 0.15, Vec3(0.25, 0.0, 0.0), J);
  Vec6 k, m;
  k << 1e6, 1e6, 1e6, 1.0, 1.0, 1.0;
  m << 0.1, 0.1, 0.1, 0.5, 0.5, 0.5;
  const RodId rod = b.AddStraightRod("arm", Vec3(0.7, 0.0, 0.0), Vec3(1.3, 0.0, 0.0), num_elements,
                                     Section::FromDiagonals(k, m));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  const JointId drive =
      b.AddJointAt("actuated", JointType::kRevolute, kGround, link1, Vec3::Zero(), Vec3::UnitZ());
  Joint& j0 = b.model().joints[drive];
  j0.drive = DriveKind::kPrescribed;
  j0.drive_profile = Profile::BangBang(0.0, 1.0, kPi / 6.0);
  const JointId soft =
      b.AddJointAt("soft", JointType::kRevolute, link1, link2, Vec3(0.5, 0.0, 0.0), Vec3::UnitZ());
  b.model().joints[soft].stiffness(0) = 10.0;
  b.model().joints[soft].damping(0) = 5.0;
  b.AddJointAt("weld", JointType::kFixed, link2, nodes.front(), Vec3(0.7, 0.0, 0.0));
  if (gravity == Gravity::kConsistent) {
    b.SetGravity(kGravity);
  } else {
    // Same gravity on the links (world force m g at the CoM), lumped gravity on the rod.
    for (const int node : {link1, link2}) {
      PointLoad load;
      load.node = node;
      load.point = Vec3(0.25, 0.0, 0.0);
      load.force = 0.15 * kGravity;
      b.AddPointLoad(load);
    }
    const double element_weight = m(0) * 0.6 / num_elements;
    for (int i = 0; i <= num_elements; ++i) {
      PointLoad load;
      load.node = nodes[static_cast<std::size_t>(i)];
      load.force = (i == 0 || i == num_elements ? 0.5 : 1.0) * element_weight * kGravity;
      b.AddPointLoad(load);
    }
  }
  b.model().rod_inertia = inertia;
  return {b.Build(), nodes.back(), drive};
}

struct MechanismRun {
  Vec3 tip = Vec3::Zero();
  double initial_drive_acceleration = 0.0;  // alpha_ddot of the actuated joint at t = 0
  double max_constraint = 0.0;              // max |phi| over the steps
  long iterations = 0;
};

MechanismRun Simulate(RodInertia inertia, int num_elements, double h,
                      Gravity gravity = Gravity::kConsistent) {
  const Mechanism mech = MakeMechanism(inertia, num_elements, gravity);
  Data data = MakeData(mech.model);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 0.8;
  MechanismRun r;
  std::string message;
  if (!InitializeDynamics(mech.model, data, integ, options, &message)) {
    ADD_FAILURE() << message;
    return r;
  }
  r.initial_drive_acceleration =
      data.vdot(mech.model.joints[static_cast<std::size_t>(mech.drive)].coord);
  const int steps = static_cast<int>(std::lround(kEnd / h));
  for (int k = 0; k < steps; ++k) {
    const StepResult st = Step(mech.model, data, integ, h);
    if (!st.ok) {
      ADD_FAILURE() << st.message;
      return r;
    }
    r.max_constraint =
        std::max(r.max_constraint, MaxConstraintViolation(mech.model, data, data.time, 1.0));
  }
  r.tip = data.H[static_cast<std::size_t>(mech.tip)].x;
  r.iterations = integ.iterations;
  return r;
}

TEST(FlexibleMechanism, OptionAMatchesThePrototypeAndConvergesAtSecondOrderInH) {
  MechanismRun r[4];
  for (int k = 0; k < 4; ++k) {
    r[k] = Simulate(RodInertia::kExact, 3, kStepSizes[k]);
    std::printf("[ test 7 ] option A, 3 elements, h = %.4g: tip z %.7f m", kStepSizes[k],
                r[k].tip.z());
    if (k < 3)
      std::printf(" (prototype %.7f, diff %+.1e)", kPrototypeA[k], r[k].tip.z() - kPrototypeA[k]);
    std::printf(", max |phi| %.1e, %.2f Newton it/step\n", r[k].max_constraint,
                static_cast<double>(r[k].iterations) * kStepSizes[k] / kEnd);
    if (k < 3) {
      EXPECT_NEAR(r[k].tip.z(), kPrototypeA[k], 1e-5) << "h " << kStepSizes[k];
    }
    EXPECT_LT(r[k].max_constraint, 1e-11);
  }
  // Test 9: consistent start, alpha_ddot(0) = q_ddot(0+) = 4 (pi/6) / T^2 = 2.0944.
  EXPECT_NEAR(r[0].initial_drive_acceleration, 4.0 * kPi / 6.0, 1e-9);
  // Second order: successive differences of the whole tip position shrink by 4.
  for (int k = 0; k < 2; ++k) {
    const double ratio = (r[k].tip - r[k + 1].tip).norm() / (r[k + 1].tip - r[k + 2].tip).norm();
    std::printf("[ test 7 ] option A, difference ratio h = %.4g: %.3f\n", kStepSizes[k], ratio);
    EXPECT_NEAR(ratio, 4.0, 0.6);
  }
}

TEST(FlexibleMechanism, PrototypeOptionBValuesComeFromLumpedGravityNotFromTheInertia) {
  for (int k = 0; k < 4; ++k) {
    const MechanismRun ours = Simulate(RodInertia::kConstant, 3, kStepSizes[k]);
    const MechanismRun lumped = Simulate(RodInertia::kConstant, 3, kStepSizes[k], Gravity::kLumped);
    std::printf(
        "[ test 7 ] option B, 3 elements, h = %.4g: tip z %.7f m (prototype %.7f, diff "
        "%+.2e); with lumped rod gravity %.7f (diff %+.1e)\n",
        kStepSizes[k], ours.tip.z(), kPrototypeB[k], ours.tip.z() - kPrototypeB[k], lumped.tip.z(),
        lumped.tip.z() - kPrototypeB[k]);
    EXPECT_NEAR(lumped.tip.z(), kPrototypeB[k], 1e-5) << "h " << kStepSizes[k];
    // Option B as defined (exact-field gravity) is ~1e-3 m above the prototype's B values.
    EXPECT_GT(ours.tip.z() - kPrototypeB[k], 9e-4) << "h " << kStepSizes[k];
  }
}

TEST(FlexibleMechanism, MeshRefinementAndTheGapBetweenInertiaOptionsFallsLikeElementLengthSquared) {
  double gap[3];
  for (int i = 0; i < 3; ++i) {
    const MechanismRun a = Simulate(RodInertia::kExact, kMeshes[i], 1e-2);
    const MechanismRun b = Simulate(RodInertia::kConstant, kMeshes[i], 1e-2);
    const MechanismRun lumped = Simulate(RodInertia::kConstant, kMeshes[i], 1e-2, Gravity::kLumped);
    gap[i] = (a.tip - b.tip).norm();
    std::printf(
        "[ test 7 ] %2d elements, h = 1e-2: tip z A %.6f (prototype %.6f), B %.6f, B with "
        "lumped gravity %.6f (prototype B %.6f); |tip A - tip B| %.3e m (z: %+.1e)\n",
        kMeshes[i], a.tip.z(), kPrototypeMeshA[i], b.tip.z(), lumped.tip.z(), kPrototypeMeshB[i],
        gap[i], b.tip.z() - a.tip.z());
    EXPECT_NEAR(a.tip.z(), kPrototypeMeshA[i], 1e-5) << kMeshes[i] << " elements";
    EXPECT_NEAR(lumped.tip.z(), kPrototypeMeshB[i], 1e-5) << kMeshes[i] << " elements";
    EXPECT_NEAR(b.tip.z(), a.tip.z(), 1e-5) << kMeshes[i] << " elements";
  }
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(gap[i] / gap[i + 1], 4.0, 0.4) << kMeshes[i];
}

}  // namespace
}  // namespace screwfem::flexible_mechanism_test
