// The initial state of a scene (solve/initial_state.h; docs/scene-format.md, "Initial state"):
// initial body velocities and joint rates, initial joint coordinates assembled with the
// constraints, checked against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "screwfem/assemble/assemble.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"

namespace screwfem::initial_state_test {
namespace {

// A free rigid body with principal moments 1, 2, 3 kg m^2 spinning about its major axis (z) at
// 5 rad/s: the torque-free Euler equations keep w constant (w x J w = 0) and the body in place.
// A second free body translates at 0.3 m/s: uniform motion. (A body that spins and translates
// at once has a body-frame velocity that rotates; the Lie-group integrator follows its straight
// path only to O(h^2), which is no test of the initial state.)
TEST(InitialState, FreeBodySpinningAboutItsMajorAxisKeepsItsAngularVelocity) {
  const Scene scene = ParseScene(R"(points: {C: [0, 0.1, 0], P: [0, 0.2, 0]}
bodies:
  top: {type: rigid, at: C, mass: 2, inertia: [1, 2, 3], free: true,
        initial_velocity: {angular: [0, 0, 5]}}
  puck: {type: rigid, at: P, mass: 1, inertia: [1, 1, 1], free: true,
         initial_velocity: {linear: [0.3, 0, 0]}}
analysis: {type: dynamic, end_time: 1, step: 1e-2, rho_inf: 1}
)",
                                 "spin.yaml");
  const Model& m = scene.model;
  Data data = MakeData(m);
  ASSERT_TRUE(AssembleInitialState(m, data));
  const int top = m.nodes[0].dof, puck = m.nodes[1].dof;
  EXPECT_EQ(data.v(top + 5), 5.0);
  EXPECT_EQ(data.v(puck), 0.3);
  Integrator integ;
  ASSERT_TRUE(InitializeDynamics(m, data, integ, scene.analysis.dynamic));
  const double h = 1e-2;
  for (int n = 0; n < 100; ++n) ASSERT_TRUE(Step(m, data, integ, h).ok);
  const Vec3 w = data.v.segment<3>(top + 3);
  EXPECT_NEAR(w(0), 0.0, 1e-13);
  EXPECT_NEAR(w(1), 0.0, 1e-13);
  EXPECT_NEAR(w(2), 5.0, 5e-14);
  EXPECT_NEAR((data.H[0].x - Vec3(0, 0.1, 0)).norm(), 0.0, 1e-13);
  // The angle turned: 5 rad about z.
  EXPECT_NEAR(std::atan2(data.H[0].R(1, 0), data.H[0].R(0, 0)), 5.0 - 2 * std::numbers::pi, 1e-11);
  EXPECT_NEAR((data.H[1].x - Vec3(0.3 * data.time, 0.2, 0)).norm(), 0.0, 1e-13);
}

// The pendulum of tests/data/pendulum.yaml started hanging (initial_position pi/2, assembled
// with the joint's constraints) with the rate qdot0: small-amplitude motion
// q = pi/2 + (qdot0 / w0) sin(w0 t), w0 = sqrt(m g d / I_O).
TEST(InitialState, PendulumStartedWithARateFollowsTheSmallAmplitudeSolution) {
  const double qdot0 = 0.01;
  const Scene scene = ParseScene(R"(gravity: [0, 0, -9.81]
points: {O: [0, 0, 0], E: [0.4, 0, 0]}
bodies:
  link: {type: rigid, between: [O, E], mass: 0.2, inertia: [1e-4, 2.7e-3, 2.7e-3]}
joints:
  hinge: {type: revolute, at: O, between: [ground, link], axis: [0, 1, 0],
          initial_position: pi/2, initial_velocity: 0.01}
analysis: {type: dynamic, end_time: 1, step: 1e-3, rho_inf: 1}
)",
                                 "pendulum.yaml");
  const Model& m = scene.model;
  Data data = MakeData(m);
  ASSERT_TRUE(AssembleInitialState(m, data));
  // Assembled: the link hangs (its far end at (0, 0, -0.4)), the constraints hold, and the
  // link's angular velocity is the joint rate about y.
  const Vec3 tip = data.H[0].x + data.H[0].R * Vec3(0.4, 0.0, 0.0);
  EXPECT_NEAR(tip(0), 0.0, 1e-12);
  EXPECT_NEAR(tip(2), -0.4, 1e-12);
  EXPECT_LT(MaxConstraintViolation(m, data, 0.0, 1.0), 1e-13);
  const int dof = m.nodes[0].dof;
  EXPECT_NEAR((data.H[0].R * data.v.segment<3>(dof + 3) - Vec3(0, qdot0, 0)).norm(), 0.0, 1e-15);

  const double mass = 0.2, d = 0.2, g = 9.81;
  const double w0 = std::sqrt(mass * g * d / (2.7e-3 + mass * d * d));
  Integrator integ;
  ASSERT_TRUE(InitializeDynamics(m, data, integ, scene.analysis.dynamic));
  const double h = 1e-3, amplitude = qdot0 / w0;
  double worst = 0.0;
  for (int n = 1; n <= 1000; ++n) {
    ASSERT_TRUE(Step(m, data, integ, h).ok);
    const double exact = std::numbers::pi / 2 + amplitude * std::sin(w0 * data.time);
    worst = std::max(worst, std::abs(data.q_joint(0) - exact));
  }
  // Errors: the nonlinearity (amplitude^2 / 16 relative) and the integrator's phase error
  // (w0 t (w0 h)^2 / 12 ~ 2e-5 rad after 1 s).
  EXPECT_LT(worst, 1e-4 * amplitude) << "amplitude " << amplitude;
}

TEST(InitialState, ContradictoryInitialVelocitiesAreRefused) {
  // A body welded to the ground by a fixed joint cannot move.
  const Scene scene = ParseScene(R"(points: {O: [0, 0, 0]}
bodies:
  b: {type: rigid, at: O, mass: 1, inertia: [1, 1, 1], initial_velocity: {angular: [0, 0, 1]}}
joints:
  weld: {type: fixed, at: O, between: [ground, b]}
)",
                                 "weld.yaml");
  Data data = MakeData(scene.model);
  std::string why;
  EXPECT_FALSE(AssembleInitialState(scene.model, data, &why));
  EXPECT_NE(why.find("contradict the constraints"), std::string::npos) << why;
}

TEST(InitialState, BadKeysAreFileLineErrors) {
  try {
    ParseScene(R"(points: {O: [0, 0, 0]}
bodies:
  b: {type: rigid, at: O, mass: 1, inertia: [1, 1, 1], fixed: true,
      initial_velocity: {angular: [0, 0, 1]}}
)",
               "bad.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bad.yaml:4:", 0), 0u) << what;
    EXPECT_NE(what.find("fixed body cannot have an initial velocity"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace screwfem::initial_state_test
