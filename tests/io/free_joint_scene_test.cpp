// A scene with a free joint carrying springs and dampers (docs/user-guide.md, "Joint library": a 6-DOF
// elastic connection) compiles and runs: six springs per joint are read, the joint adds no
// unknowns and no constraint rows, and the dynamics starts and moves (before, the joint's six
// massless coordinates were decoupled from the bodies and the start was singular).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::free_joint_scene_test {
namespace {

const char* kScene = R"(
name: free joint
gravity: [0, 0, -9.81]
points: {O: [0, 0, 0], A: [0.3, 0, 0], B: [0.6, 0, 0]}
bodies:
  base: {type: rigid, between: [O, A], mass: 0.2, inertia: [1e-4, 1e-3, 1e-3], fixed: true}
  tip:  {type: rigid, between: [A, B], mass: 0.2, inertia: [1e-4, 1e-3, 1e-3]}
joints:
  elastic:
    type: free
    at: A
    between: [base, tip]
    stiffness: [1e3, 1e3, 1e3, 5, 5, 5]
    damping: 0.01
analysis: {type: dynamic, end_time: 0.2, step: 1e-3}
)";

TEST(FreeJointScene, CompilesWithSixSpringsAndNoConstraintRows) {
  const Scene s = ParseScene(kScene, "free.yaml");
  ASSERT_EQ(s.model.joints.size(), 1u);
  const Joint& j = s.model.joints[0];
  EXPECT_EQ(j.type, JointType::kFree);
  EXPECT_EQ(j.k(), 0);
  EXPECT_EQ(JointSpringCount(j), 6);
  EXPECT_EQ(j.stiffness(5), 5.0);
  EXPECT_EQ(j.damping(3), 0.01);
  EXPECT_EQ(s.model.nc, 0);
  EXPECT_EQ(s.model.nv, 6);  // the tip body only
}

TEST(FreeJointScene, RunsAndSagsUnderGravityTowardsTheSpringEquilibrium) {
  Scene s = ParseScene(kScene, "free.yaml");
  Data d = MakeData(s.model);
  Integrator integ;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(s.model, d, integ, DynamicOptions{}, &message)) << message;
  double lowest = 0.0;
  for (int n = 0; n < 200; ++n) {
    const StepResult r = Step(s.model, d, integ, 1e-3);
    ASSERT_TRUE(r.ok) << r.message;
    lowest = std::min(lowest, d.H[static_cast<std::size_t>(s.model.bodies[1].node)].x.z());
  }
  // The tip body hangs on the springs: it moves down, by about m g / k_z = 2e-3 m plus the
  // rotation of its lever (bounded well below 0.1 m).
  EXPECT_LT(lowest, -1e-3);
  EXPECT_GT(lowest, -0.1);
}

TEST(FreeJointScene, RestAndDrivesAreErrorsWithTheField) {
  std::string scene = kScene;
  scene.replace(scene.find("    damping: 0.01"), 17, "    rest: 0.1");
  try {
    ParseScene(scene, "free.yaml");
    FAIL() << "rest on a free joint was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("free.yaml:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("joints.elastic.rest"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace screwfem::free_joint_scene_test
