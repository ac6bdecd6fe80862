// Joint reactions (CalcJointReaction, reactions.csv) and energy.csv (CalcEnergy, CalcMomentum):
// a pinned beam's support reactions balance the applied load; a free body's energy and momentum
// rows are constant and equal to their closed forms.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "run_test_util.h"
#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/statics.h"

namespace screwfem::reactions_energy_test {
namespace {

using test::ReadCsv;
using test::ScopedDir;
using test::Table;

// A 1 m beam pinned at A (revolute about y) and B (spherical), loaded at s = 0.3 m by a force
// and a moment in general directions. In equilibrium the reactions on the beam, the force and
// the moment sum to zero, forces and moments about A, in world components.
TEST(JointReaction, PinnedBeamReactionsBalanceTheLoad) {
  const Scene scene = ParseScene(R"(points: {A: [0, 0, 0], B: [1, 0, 0]}
sections: {s: {stiffness: [1e4, 1e4, 1e4, 20, 10, 10]}}
bodies:
  beam: {type: soft, from: A, to: B, section: s, elements: 8}
joints:
  pin: {type: revolute, at: A, between: [ground, beam], axis: [0, 1, 0]}
  ball: {type: spherical, at: B, between: [ground, beam]}
loads:
  push: {body: beam, s: 0.3, force: [0.3, 0.5, -2], moment: [0.1, -0.05, 0.2]}
analysis: {type: static}
)",
                                 "beam.yaml");
  const Model& m = scene.model;
  Data data = MakeData(m);
  const StaticResult r = SolveStatic(m, data, scene.analysis.statics);
  ASSERT_TRUE(r.converged) << r.message;
  const Vec3 F(0.3, 0.5, -2), M(0.1, -0.05, 0.2);
  const RodPoint p = CalcRodPointMotion(m, data, 0, 0.3);
  const Vec6 ra = CalcJointReaction(m, data, m.FindJoint("pin"));
  const Vec6 rb = CalcJointReaction(m, data, m.FindJoint("ball"));
  // Moments about the world origin (= A): the reaction moment is about the joint point.
  const Vec3 pa = (NodeFrame(data, m.joints[0].node_b) * m.joints[0].offset_b).x;
  const Vec3 pb = (NodeFrame(data, m.joints[1].node_b) * m.joints[1].offset_b).x;
  const Vec3 force = ra.head<3>() + rb.head<3>() + F;
  const Vec3 moment = ra.tail<3>() + pa.cross(ra.head<3>()) + rb.tail<3>() +
                      pb.cross(rb.head<3>()) + M + p.frame.x.cross(F);
  EXPECT_LT(force.norm(), 1e-9 * F.norm()) << force.transpose();
  EXPECT_LT(moment.norm(), 1e-9 * F.norm()) << moment.transpose();
  // The pin carries a moment about x and z (its axis is y), the ball none.
  EXPECT_GT(ra.tail<3>().norm(), 1e-3);
  EXPECT_LT(rb.tail<3>().norm(), 1e-9);
  EXPECT_NEAR(ra.tail<3>()(1), 0.0, 1e-9);  // no moment about the pin's axis
}

// energy.csv of two free rigid bodies, one spinning about a principal axis, one translating:
// every row has kinetic energy 1/2 J w^2 + 1/2 m v^2, zero other energies, the momentum m v and
// the angular momentum J w + x x (m v) about the origin.
TEST(EnergyCsv, FreeBodyEnergyAndMomentumAreConstantAndExact) {
  ScopedDir dir("energy_csv");
  const Scene scene = ParseScene(R"(points: {C: [0, 0.1, 0], P: [0, 0.2, 0]}
bodies:
  top: {type: rigid, at: C, mass: 2, inertia: [1, 2, 3], free: true,
        initial_velocity: {angular: [0, 0, 5]}}
  puck: {type: rigid, at: P, mass: 1, inertia: [1, 1, 1], free: true,
         initial_velocity: {linear: [0.3, 0, 0]}}
analysis: {type: dynamic, end_time: 0.5, step: 1e-2, rho_inf: 0.8}
outputs: {interval: 0.1, vtk: false}
)",
                                 "spin.yaml");
  const RunResult r = RunScene(scene, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const Table t = ReadCsv(dir.path() + "/energy.csv");
  ASSERT_TRUE(t.well_formed) << t.problem;
  ASSERT_EQ(t.rows.size(), 6u);
  const double kinetic = 0.5 * 3 * 25 + 0.5 * 1 * 0.3 * 0.3;
  for (const std::vector<double>& row : t.rows) {
    EXPECT_NEAR(row[t.Column("kinetic")], kinetic, 1e-13 * kinetic);
    EXPECT_EQ(row[t.Column("strain")], 0.0);
    EXPECT_EQ(row[t.Column("spring")], 0.0);
    EXPECT_EQ(row[t.Column("gravity")], 0.0);
    EXPECT_EQ(row[t.Column("total")], row[t.Column("kinetic")]);
    EXPECT_NEAR(row[t.Column("px")], 0.3, 1e-14);
    EXPECT_NEAR(row[t.Column("py")], 0.0, 1e-14);
    EXPECT_NEAR(row[t.Column("Lx")], 0.0, 1e-13);
    EXPECT_NEAR(row[t.Column("Ly")], 0.0, 1e-13);
    EXPECT_NEAR(row[t.Column("Lz")], 15.0 - 0.2 * 0.3, 1e-12) << "t = " << row[0];
  }
}

TEST(ReactionsCsv, HasSixColumnsPerConstrainedJoint) {
  ScopedDir dir("reactions_csv");
  const Scene scene = LoadScene(std::string(SCREWFEM_TEST_DATA_DIR) + "/pendulum.yaml",
                                {"analysis.end_time=0.01", "outputs.vtk=false"});
  ASSERT_TRUE(RunScene(scene, dir.path()).ok);
  const Table t = ReadCsv(dir.path() + "/reactions.csv");
  ASSERT_TRUE(t.well_formed) << t.problem;
  ASSERT_EQ(t.columns.size(), 7u);
  EXPECT_EQ(t.columns[1], "hinge.Fx");
  EXPECT_EQ(t.columns[6], "hinge.Mz");
  // At the release from rest the hinge carries the weight minus the tangential inertia force:
  // m g (1 - m d^2 / I_O) upwards for the horizontal link.
  const double m = 0.2, d = 0.2, g = 9.81, io = 2.7e-3 + m * d * d;
  EXPECT_NEAR(t.rows[0][t.Column("hinge.Fz")], m * g * (1.0 - m * d * d / io), 1e-9);
  EXPECT_NEAR(t.rows[0][t.Column("hinge.Fx")], 0.0, 1e-12);
}

// outputs.reactions and outputs.energy false: neither table is written, the other tables are
// the same bytes as with them, and the summary's settings say which are off.
TEST(ReactionsCsv, TablesTurnedOffAreNotWritten) {
  ScopedDir dir("reactions_off");
  const std::string pendulum = std::string(SCREWFEM_TEST_DATA_DIR) + "/pendulum.yaml";
  const Scene both = LoadScene(pendulum, {"analysis.end_time=0.01", "outputs.vtk=false"});
  EXPECT_TRUE(both.outputs.reactions);
  EXPECT_TRUE(both.outputs.energy);
  ASSERT_TRUE(RunScene(both, dir.path() + "/both").ok);
  for (const char* off : {"outputs.reactions=false", "outputs.energy=false"}) {
    SCOPED_TRACE(off);
    const Scene scene = LoadScene(pendulum, {"analysis.end_time=0.01", "outputs.vtk=false", off});
    const bool reactions = std::string(off).find("reactions") == std::string::npos;
    EXPECT_EQ(scene.outputs.reactions, reactions);
    EXPECT_EQ(scene.outputs.energy, !reactions);
    const std::string out = dir.path() + (reactions ? "/no_energy" : "/no_reactions");
    ASSERT_TRUE(RunScene(scene, out).ok);
    EXPECT_EQ(std::filesystem::exists(out + "/reactions.csv"), reactions);
    EXPECT_EQ(std::filesystem::exists(out + "/energy.csv"), !reactions);
    const char* kept = reactions ? "/reactions.csv" : "/energy.csv";
    EXPECT_EQ(test::ReadFile(out + kept), test::ReadFile(dir.path() + "/both" + kept));
    EXPECT_EQ(test::ReadFile(out + "/points.csv"), test::ReadFile(dir.path() + "/both/points.csv"));
    EXPECT_EQ(test::ReadFile(out + "/joints.csv"), test::ReadFile(dir.path() + "/both/joints.csv"));
    const std::string summary = test::ReadFile(out + "/summary.json");
    EXPECT_NE(summary.find(reactions ? "\"energy\": false" : "\"reactions\": false"),
              std::string::npos)
        << summary;
  }
  const std::string summary = test::ReadFile(dir.path() + "/both/summary.json");
  EXPECT_EQ(summary.find("\"reactions\""), std::string::npos) << summary;
  EXPECT_EQ(summary.find("\"energy\""), std::string::npos) << summary;
}

TEST(ReactionsCsv, SwitchMustBeABool) {
  const std::string text =
      "bodies: {b: {type: rigid, at: [0, 0, 0], mass: 1, inertia: [1, 1, 1]}}\n"
      "outputs: {reactions: 2}\n";
  try {
    ParseScene(text, "bad.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "bad.yaml:2:22: outputs.reactions: expected true or false, got '2'");
  }
  try {
    ParseScene(
        "bodies: {b: {type: rigid, at: [0, 0, 0], mass: 1, inertia: [1, 1, 1]}}\noutputs: {energy: "
        "yes}\n",
        "bad.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "bad.yaml:2:19: outputs.energy: expected true or false, got 'yes'");
  }
}

}  // namespace
}  // namespace screwfem::reactions_energy_test
