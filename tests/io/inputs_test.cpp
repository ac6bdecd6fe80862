// Run-time inputs (Model::inputs, Data::inputs, ProfileTerm::kInput; docs/scene-format.md,
// "Run-time inputs"): the scene section and profile type, their errors, the CSV input table of
// the CLI, and the physics: a load that takes an input set between steps gives the same motion,
// bit for bit, as the same values given as a profile; a saved state restored and stepped again
// repeats its steps bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "run_test_util.h"
#include "screwfem/io/input_table.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::inputs_test {
namespace {

// A soft cantilever (0.3 m silicone rod, clamped) with a vertical tip force. `profile` is the
// YAML of the force's profile.
std::string Cantilever(const std::string& profile) {
  return R"(gravity: [0, 0, -9.81]
inputs: {u: 0.0, w: 1.5}
points: {A: [0, 0, 0], B: [0.3, 0, 0]}
materials: {m: {E: 1e7, nu: 0.45, density: 1100}}
sections: {s: {shape: circle, radius: 0.01, material: m}}
bodies:
  arm: {type: soft, from: A, to: B, section: s, elements: 6}
joints:
  clamp: {type: fixed, at: A, between: [ground, arm]}
loads:
  tip: {body: arm, at: B, force: [0, 0.2, 1], profile: )" +
         profile + R"(}
analysis: {type: dynamic, end_time: 0.1, step: 2e-3, rho_inf: 0.7}
outputs:
  points: {tip: {body: arm, at: B}}
  vtk: false
)";
}

std::string Error(const std::string& text) {
  try {
    ParseScene(text, "in.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Inputs, SceneDeclaresInputsWithDefaults) {
  const Scene scene = ParseScene(Cantilever("{type: input, name: w, scale: 2}"), "in.yaml");
  ASSERT_EQ(scene.model.inputs.size(), 2u);
  EXPECT_EQ(scene.model.inputs[1].name, "w");
  const Data data = MakeData(scene.model);
  ASSERT_EQ(data.inputs.size(), 2);
  EXPECT_EQ(data.inputs(0), 0.0);
  EXPECT_EQ(data.inputs(1), 1.5);
  // The load's profile is 2 w: 3 N at the defaults.
  EXPECT_EQ(EvalProfile(scene.model.point_loads[0].profile, 0.0, data).value, 3.0);
  EXPECT_EQ(EvalProfile(scene.model.point_loads[0].profile, 0.0, data).rate, 0.0);
  EXPECT_TRUE(scene.model.point_loads[0].profile.Breakpoints().empty());
}

TEST(Inputs, UnknownInputNameIsAFileLineError) {
  const std::string e = Error(Cantilever("{type: input, name: v}"));
  EXPECT_EQ(e.rfind("in.yaml:11:", 0), 0u) << e;
  EXPECT_NE(e.find("loads.tip.profile.name: unknown input 'v'"), std::string::npos) << e;
  EXPECT_NE(e.find("(known: u, w)"), std::string::npos) << e;
}

TEST(Inputs, InputProfileNeedsAName) {
  const std::string e = Error(Cantilever("{type: input}"));
  EXPECT_NE(e.find("in.yaml:11:"), std::string::npos) << e;
  EXPECT_NE(e.find("missing key 'name'"), std::string::npos) << e;
}

TEST(Inputs, NonNumericDefaultIsAFileLineError) {
  std::string text = Cantilever("{type: input, name: u}");
  text.replace(text.find("u: 0.0"), 6, "u: fast");
  const std::string e = Error(text);
  EXPECT_EQ(e.rfind("in.yaml:2:", 0), 0u) << e;
  EXPECT_NE(e.find("inputs.u"), std::string::npos) << e;
}

TEST(Inputs, ProfileWithoutInputValuesRefusesToEvaluate) {
  const Profile p = Profile::Input(0);
  EXPECT_THROW(p.Eval(0.0), std::logic_error);
  Eigen::VectorXd u(1);
  u << 0.25;
  EXPECT_EQ(p.Eval(1.0, u).value, 0.25);
  EXPECT_THROW(p.Validate("p", 0), InputError);  // no input 0 in a model without inputs
}

// The values a sine profile takes at the step ends, written into the input before each step,
// give the same motion bit for bit: the implicit step evaluates its loads at its end time only.
TEST(Inputs, RunTimeInputIsBitIdenticalToTheSameValuesAsAProfile) {
  const Scene by_profile =
      ParseScene(Cantilever("{type: sine, value: 0.8, frequency: 7}"), "p.yaml");
  const Scene by_input = ParseScene(Cantilever("{type: input, name: u}"), "i.yaml");
  Data dp = MakeData(by_profile.model), di = MakeData(by_input.model);
  Integrator ip, ii;
  const DynamicOptions& o = by_profile.analysis.dynamic;
  const Profile& sine = by_profile.model.point_loads[0].profile;
  di.inputs(0) = sine(0.0);
  ASSERT_TRUE(InitializeDynamics(by_profile.model, dp, ip, o));
  ASSERT_TRUE(InitializeDynamics(by_input.model, di, ii, o));
  const double h = 2e-3;
  double travel = 0.0;
  for (int n = 0; n < 40; ++n) {
    di.inputs(0) = sine(di.time + h);
    ASSERT_TRUE(Step(by_profile.model, dp, ip, h).ok);
    ASSERT_TRUE(Step(by_input.model, di, ii, h).ok);
    ASSERT_EQ(dp.time, di.time);
  }
  for (std::size_t i = 0; i < dp.H.size(); ++i) {
    for (int r = 0; r < 3; ++r) {
      EXPECT_EQ(dp.H[i].x(r), di.H[i].x(r)) << "node " << i;
      for (int c = 0; c < 3; ++c) EXPECT_EQ(dp.H[i].R(r, c), di.H[i].R(r, c)) << "node " << i;
    }
    travel = std::max(travel, (dp.H[i].x - by_profile.model.nodes[i].reference.x).norm());
  }
  EXPECT_EQ((dp.v - di.v).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((dp.lambda - di.lambda).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(travel, 1e-3);  // the load moved the arm: the comparison is not of rest states
}

// Saving, stepping, restoring and stepping again with the same inputs repeats the steps bit for
// bit (resets and rollouts); a different input after the restore gives a different motion.
TEST(Inputs, RestoredStateRepeatsItsStepsBitForBit) {
  const Scene scene = ParseScene(Cantilever("{type: input, name: u}"), "i.yaml");
  Data data = MakeData(scene.model);
  Integrator integ;
  ASSERT_TRUE(InitializeDynamics(scene.model, data, integ, scene.analysis.dynamic));
  const double h = 2e-3;
  for (int n = 0; n < 10; ++n) {
    data.inputs(0) = 0.5 * n;
    ASSERT_TRUE(Step(scene.model, data, integ, h).ok);
  }
  SimulationState saved;
  SaveSimulationState(data, integ, &saved);
  const auto rollout = [&](double u) {
    for (int n = 0; n < 10; ++n) {
      data.inputs(0) = u * n;
      EXPECT_TRUE(Step(scene.model, data, integ, h).ok);
    }
    return data.H.back().x;
  };
  const Vec3 first = rollout(-0.3);
  const double t_end = data.time;
  RestoreSimulationState(saved, data, integ);
  EXPECT_EQ(data.time, saved.time);
  const Vec3 again = rollout(-0.3);
  EXPECT_EQ(data.time, t_end);
  EXPECT_EQ(first(0), again(0));
  EXPECT_EQ(first(1), again(1));
  EXPECT_EQ(first(2), again(2));
  RestoreSimulationState(saved, data, integ);
  EXPECT_GT((rollout(0.3) - first).norm(), 1e-4);

  std::string coarser = Cantilever("{type: input, name: u}");
  coarser.replace(coarser.find("elements: 6"), 11, "elements: 3");
  Data other = MakeData(ParseScene(coarser, "x.yaml").model);
  EXPECT_THROW(RestoreSimulationState(saved, other, integ), InputError);
}

// ---- the CSV input table (screwfem run --inputs) ---------------------------------------------

TEST(InputTable, InterpolatesLinearlyAndHoldsOutside) {
  const Scene scene = ParseScene(Cantilever("{type: input, name: u}"), "i.yaml");
  const InputTable t = ParseInputTable("# comment\nt, w\n0.1, 2\n\n0.3, 6\n", "u.csv", scene.model);
  ASSERT_EQ(t.inputs.size(), 1u);
  EXPECT_EQ(t.inputs[0], 1);
  Data data = MakeData(scene.model);
  SetInputsAt(t, 0.0, data);
  EXPECT_EQ(data.inputs(1), 2.0);
  SetInputsAt(t, 0.2, data);
  EXPECT_NEAR(data.inputs(1), 4.0, 1e-14);
  SetInputsAt(t, 0.3, data);
  EXPECT_EQ(data.inputs(1), 6.0);
  SetInputsAt(t, 5.0, data);
  EXPECT_EQ(data.inputs(1), 6.0);
  EXPECT_EQ(data.inputs(0), 0.0);  // no column: keeps its value
}

std::string TableError(const std::string& csv) {
  const Scene scene = ParseScene(Cantilever("{type: input, name: u}"), "i.yaml");
  try {
    ParseInputTable(csv, "u.csv", scene.model);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(InputTable, ErrorsNameFileLineAndColumn) {
  EXPECT_EQ(TableError("t,u,x\n0,1,2\n"), "u.csv:1:5: unknown input 'x' (known: u, w)");
  EXPECT_EQ(TableError("t,uu\n0,1\n"), "u.csv:1:3: unknown input 'uu' (did you mean 'u'?)");
  EXPECT_EQ(TableError("t,u,u\n"), "u.csv:1:5: input 'u' has two columns");
  EXPECT_EQ(TableError("time,u\n0,1\n0.5,abc\n"), "u.csv:3:5: expected a finite number, got 'abc'");
  EXPECT_EQ(TableError("t,u\n0,1\n0,2\n"), "u.csv:3:1: times must be strictly increasing");
  EXPECT_EQ(TableError("t,u\n0,1\n1\n"),
            "u.csv:3:1: expected 2 values (t and one per input), got 1");
  EXPECT_EQ(TableError("u,t\n"),
            "u.csv:1:1: the first column is the time: expected the header 't,NAME,...', got 'u'");
  EXPECT_EQ(TableError("t,u\n"), "u.csv:1:1: expected at least one row of values");
  EXPECT_EQ(TableError(""), "u.csv:1:1: empty input table: expected the header 't,NAME,...'");
  EXPECT_EQ(TableError("t,u\n0,nan\n"), "u.csv:2:3: expected a finite number, got 'nan'");
}

// screwfem run --inputs: the table's values sampled at the step ends give the files a table
// profile gives, when the profile has no breakpoint inside the run (at a profile breakpoint the
// integrator restarts; an input's change is no breakpoint: docs/numerics.md).
TEST(InputTable, RunWithAnInputTableWritesTheSameRowsAsATableProfile) {
  test::ScopedDir by_profile("inputs_profile"), by_table("inputs_table");
  const Scene profile =
      ParseScene(Cantilever("{type: table, times: [0, 0.2], values: [0, 3]}"), "p.yaml");
  const Scene input = ParseScene(Cantilever("{type: input, name: u}"), "i.yaml");
  ASSERT_TRUE(RunScene(profile, by_profile.path()).ok);
  RunOptions options;
  options.inputs = ParseInputTable("t,u\n0,0\n0.2,3\n", "u.csv", input.model);
  ASSERT_TRUE(RunScene(input, by_table.path(), options).ok);
  const std::string a = test::ReadFile(by_profile.path() + "/points.csv");
  const std::string b = test::ReadFile(by_table.path() + "/points.csv");
  EXPECT_GT(a.size(), 100u);
  EXPECT_EQ(a, b);
  EXPECT_EQ(test::ReadFile(by_profile.path() + "/reactions.csv"),
            test::ReadFile(by_table.path() + "/reactions.csv"));
}

// 1e5 inputs (their names were checked pairwise, and each input profile searched and copied
// them: 12.6 s to check): the scene, a load on the last of them, and a table with a column for
// each, in reverse order, all resolved by name (bench/check_scaling.py times them).
TEST(Inputs, AHundredThousandInputsResolveByName) {
  constexpr int kCount = 100000;
  std::string inputs = "inputs: {";
  for (int i = 0; i < kCount; ++i) {
    inputs += i ? ", u" : "u";
    inputs += std::to_string(i);
    inputs += ": ";
    inputs += std::to_string(i % 7);
  }
  inputs += "}\n";
  std::string scene = Cantilever("{type: input, name: u99999, scale: 2}");
  scene.replace(scene.find("inputs: {u: 0.0, w: 1.5}\n"), 25, inputs);
  const Scene parsed = ParseScene(scene, "in.yaml");
  ASSERT_EQ(parsed.model.inputs.size(), static_cast<std::size_t>(kCount));
  EXPECT_EQ(parsed.model.inputs[kCount - 1].name, "u99999");
  EXPECT_EQ(parsed.model.inputs[kCount - 1].default_value, 99999 % 7);
  Data data = MakeData(parsed.model);
  data.inputs(kCount - 1) = 1.25;
  EXPECT_EQ(EvalProfile(parsed.model.point_loads[0].profile, 0.0, data).value, 2.5);
  // Duplicates are still found, at the second one.
  std::string twice = scene;
  twice.replace(twice.find(", u99999: "), 10, ", u12345: ");
  EXPECT_NE(Error(twice).find("duplicate input name 'u12345' (first defined at in.yaml:2:"),
            std::string::npos)
      << Error(twice).substr(0, 200);
  // A table with every input, last first.
  std::string table = "t";
  for (int i = kCount - 1; i >= 0; --i) table += ",u" + std::to_string(i);
  table += "\n0";
  for (int i = kCount - 1; i >= 0; --i) table += "," + std::to_string(i);
  table += "\n";
  const InputTable t = ParseInputTable(table, "u.csv", parsed.model);
  ASSERT_EQ(t.inputs.size(), static_cast<std::size_t>(kCount));
  SetInputsAt(t, 0.0, data);
  for (int i = 0; i < kCount; ++i) ASSERT_EQ(data.inputs(i), i) << i;
  table.replace(table.find(",u0\n"), 4, ",u7\n");
  try {
    ParseInputTable(table, "u.csv", parsed.model);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(": input 'u7' has two columns"), std::string::npos);
  }
}

}  // namespace
}  // namespace screwfem::inputs_test
