// Parameters and expressions in scene files (docs/scene-format.md, "Parameters and
// expressions"): a `parameters:` block of named values that every number may use, powers in
// expressions, `--set` on parameters, `--set key=` restoring a default, and the errors of each,
// with the file, line, column and field.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "scene_error_util.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

namespace screwfem::parameters_test {
namespace {

std::string Error(const std::string& text, const std::vector<std::string>& overrides = {}) {
  return test::SceneError(text, "p.yaml", overrides);
}

// Asserts the location prefix exactly and that the message contains `what`.
void ExpectError(const std::string& text, const std::string& location, const std::string& what,
                 const std::vector<std::string>& overrides = {}) {
  test::ExpectErrorAt(Error(text, overrides), location, what);
}

// A cantilever written with parameters, and the same scene with the numbers written out.
const std::string kWithParameters = R"(parameters:
  length: 0.4
  n: 2 * 3
  radius: length / 40
  E: 2e6
  area: pi * radius^2
  inertia: pi * radius**4 / 4
  angle: 30 * deg
points: {A: [0, 0, 0]}
sections: {s: {stiffness: [E * area, E * area / 3, E * area / 3, E * inertia / 1.5, E * inertia, E * inertia]}}
bodies:
  rod: {type: soft, from: A, to: [length * cos(angle), length * sin(angle), 0], section: s,
        elements: n}
joints: {clamp: {type: fixed, at: A, between: [ground, rod]}}
analysis: {end_time: length / 4, step: 1e-3 * 2^-1}
)";

const std::string kWrittenOut = R"(points: {A: [0, 0, 0]}
sections: {s: {stiffness: [628.3185307179587, 209.43951023931956, 209.43951023931956, 0.010471975511965978, 0.015707963267948967, 0.015707963267948967]}}
bodies:
  rod: {type: soft, from: A, to: [0.3464101615137755, 0.19999999999999998, 0], section: s,
        elements: 6}
joints: {clamp: {type: fixed, at: A, between: [ground, rod]}}
analysis: {end_time: 0.1, step: 5e-4}
)";

TEST(SceneParameters, EveryNumberMayUseThemAndGivesTheWrittenOutScene) {
  const Scene p = ParseScene(kWithParameters, "p.yaml");
  const Scene w = ParseScene(kWrittenOut, "w.yaml");
  ASSERT_EQ(p.model.rods.size(), 1u);
  EXPECT_EQ(p.model.rods[0].num_elements, 6);
  EXPECT_EQ(p.analysis.end_time, 0.1);
  EXPECT_EQ(p.analysis.step, 5e-4);
  // The same model as the written-out scene: every element's stiffness and every node frame.
  const Vec6& ks = p.model.rods[0].section.stiffness;
  EXPECT_LT((ks - w.model.rods[0].section.stiffness).cwiseQuotient(ks).cwiseAbs().maxCoeff(),
            4e-16);
  ASSERT_EQ(p.model.nodes.size(), w.model.nodes.size());
  for (std::size_t i = 0; i < p.model.nodes.size(); ++i)
    EXPECT_LT((p.model.nodes[i].reference.x - w.model.nodes[i].reference.x).norm(), 1e-15) << i;
  // The tip at length * (cos 30°, sin 30°).
  EXPECT_NEAR(p.model.nodes.back().reference.x.x(), 0.4 * std::sqrt(3.0) / 2.0, 1e-15);
  EXPECT_NEAR(p.model.nodes.back().reference.x.y(), 0.2, 1e-15);
}

TEST(SceneParameters, PowersAreRightAssociativeAndBindTighterThanASign) {
  auto end_time = [](const std::string& expression) {
    return ParseScene(kWrittenOut, "e.yaml", {"analysis.end_time=" + expression}).analysis.end_time;
  };
  EXPECT_EQ(end_time("2^3^2 / 512"), 1.0);  // 2^(3^2)
  EXPECT_EQ(end_time("-2^2 + 5"), 1.0);     // -(2^2)
  EXPECT_EQ(end_time("2**-1"), 0.5);
  EXPECT_EQ(end_time("2 * 3 ** 2 / 36"), 0.5);
  EXPECT_EQ(end_time("(1 + 1)^-2"), 0.25);
  EXPECT_EQ(end_time("sqrt(2)^2 * 0.5"), std::pow(std::sqrt(2.0), 2.0) * 0.5);
}

TEST(SceneParameters, AnOverrideChangesAParameterEverywhereItIsUsed) {
  const Scene p = ParseScene(kWithParameters, "p.yaml", {"parameters.length=0.8"});
  EXPECT_EQ(p.analysis.end_time, 0.2);
  EXPECT_NEAR(p.model.nodes.back().reference.x.y(), 0.4, 1e-15);
  // radius = length / 40 follows: the axial stiffness E pi r^2 grows fourfold.
  const Scene base = ParseScene(kWithParameters, "p.yaml");
  EXPECT_NEAR(p.model.rods[0].section.stiffness(0) / base.model.rods[0].section.stiffness(0), 4.0,
              1e-12);
  // An expression in the override may use the other parameters.
  EXPECT_EQ(ParseScene(kWithParameters, "p.yaml", {"parameters.n=length * 10"})
                .model.rods[0]
                .num_elements,
            4);
}

TEST(SceneParameters, ErrorsNameTheFileLineColumnAndField) {
  // An unknown name, with the closest parameter.
  ExpectError("parameters: {length: 1}\npoints: {A: [0, 0, 0], B: [lenght, 0, 0]}\n", "p.yaml:2:28",
              "points.B[0]: expected a number, got 'lenght' (unknown name 'lenght' "
              "(did you mean 'length'?))");
  // A parameter may use only the parameters above it.
  ExpectError("parameters: {a: b * 2, b: 1}\n", "p.yaml:1:17",
              "parameters.a: expected a number, got 'b * 2' (unknown name 'b'");
  // Names: identifiers, not a constant or function of expressions.
  ExpectError("parameters: {pi: 3}\n", "p.yaml:1:14",
              "parameters.pi: 'pi' is a constant or function");
  ExpectError("parameters: {tip-mass: 3}\n", "p.yaml:1:14",
              "parameters.tip-mass: a parameter name");
  ExpectError("parameters: {2r: 3}\n", "p.yaml:1:14", "parameters.2r: a parameter name");
  ExpectError("parameters: {a: 1, a: 2}\n", "p.yaml:1:20", "duplicate parameter name 'a'");
  ExpectError("parameters: {a: [1, 2]}\n", "p.yaml:1:17", "parameters.a: expected a number");
  ExpectError("parameters: [1, 2]\n", "p.yaml:1:13", "parameters: expected a map");
  // A malformed power.
  ExpectError("parameters: {a: 2^}\n", "p.yaml:1:17", "parameters.a: expected a number, got '2^'");
  // An override cannot add a parameter (a misspelt one would change nothing).
  const std::string message = Error(kWithParameters, {"parameters.lenght=1"});
  EXPECT_NE(message.find("p.yaml: override 'parameters.lenght=1': parameters.lenght: the scene has "
                         "no parameter 'lenght' (did you mean 'length'?)"),
            std::string::npos)
      << message;
}

TEST(SceneOverrides, AnEmptyValueRestoresTheDefault) {
  const Scene base = ParseScene(kWrittenOut, "w.yaml");
  EXPECT_EQ(base.analysis.step, 5e-4);
  const Scene unset = ParseScene(kWrittenOut, "w.yaml", {"analysis.step="});
  const Scene absent = ParseScene(
      R"(points: {A: [0, 0, 0]}
sections: {s: {stiffness: [1, 1, 1, 1, 1, 1]}}
bodies: {rod: {type: soft, from: A, to: [1, 0, 0], section: s, elements: 6}}
joints: {clamp: {type: fixed, at: A, between: [ground, rod]}}
analysis: {end_time: 0.1}
)",
      "a.yaml");
  EXPECT_EQ(unset.analysis.step, absent.analysis.step);
  EXPECT_NE(unset.analysis.step, base.analysis.step);
  // The per-body element count falls back to defaults.elements (8 when not given).
  EXPECT_EQ(ParseScene(kWrittenOut, "w.yaml", {"bodies.rod.elements= "}).model.rods[0].num_elements,
            8);
  // A key that is not there: nothing to do.
  EXPECT_EQ(ParseScene(kWrittenOut, "w.yaml", {"outputs.interval="}).analysis.step, 5e-4);
  // An item of a list cannot be removed.
  const std::string message = Error(kWrittenOut, {"bodies.rod.to.1="});
  EXPECT_NE(message.find("an item of a list cannot be removed"), std::string::npos) << message;
}

TEST(SceneActuation, AnAxialChamberOffsetIsAnError) {
  const std::string finger = std::string(SCREWFEM_SOURCE_DIR) + "/examples/pneumatic/finger.yaml";
  try {
    LoadScene(finger, {"actuation.chamber.offset=[0.001, -0.005, 0]"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "actuation.chamber.offset: the first (axial) component must be 0: a chamber runs "
                  "along the rod, its offset lies in the section plane (got '0.001')"),
              std::string::npos)
        << e.what();
  }
  // Zero is accepted and means the two-number form.
  EXPECT_EQ(
      LoadScene(finger, {"actuation.chamber.offset=[0, -0.005, 0]"}).model.actuators[0].offset,
      LoadScene(finger).model.actuators[0].offset);
}

}  // namespace
}  // namespace screwfem::parameters_test
