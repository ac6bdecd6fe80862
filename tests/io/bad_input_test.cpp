// Bad scene input (docs/scene-format.md, "Errors"): every case throws InputError with a message
// "FILE:LINE:COL: FIELD: what was expected" that points at the offending line and column.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "scene_error_util.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::bad_input_test {
namespace {

// A valid scene; each case edits it. Line numbers below count from 1 at "points:".
const std::string kHead = R"(points: {A: [0, 0, 0], B: [1, 0, 0], C: [2, 0, 0]}
sections: {s: {stiffness: [1, 1, 1, 1, 1, 1]}}
)";

std::string Error(const std::string& text, const std::vector<std::string>& overrides = {}) {
  return test::SceneError(text, "bad.yaml", overrides);
}

// Asserts the location prefix exactly and that the message contains `what`.
void ExpectError(const std::string& text, const std::string& location, const std::string& what,
                 const std::vector<std::string>& overrides = {}) {
  test::ExpectErrorAt(Error(text, overrides), location, what);
}

TEST(BadInput, ValidBaseSceneParses) {
  EXPECT_EQ(Error(kHead + "bodies:\n  b: {type: rigid, between: [A, B], mass: 1, inertia: [1, 1, "
                          "1], fixed: true}\n"),
            "(no error)");
}

TEST(BadInput, UnknownTopLevelKeySuggestsTheClosest) {
  ExpectError(kHead + "bodys:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n",
              "bad.yaml:3:1", "bodys: unknown key 'bodys' (did you mean 'bodies'?)");
}

TEST(BadInput, UnknownBodyKeySuggestsTheClosest) {
  ExpectError(
      kHead + "bodies:\n  b: {type: rigid, at: A, mas: 1, inertia: [1, 1, 1], fixed: true}\n",
      "bad.yaml:4:27", "bodies.b.mas: unknown key 'mas' (did you mean 'mass'?)");
}

TEST(BadInput, MissingKey) {
  ExpectError(kHead + "bodies:\n  b: {type: rigid, at: A, inertia: [1, 1, 1], fixed: true}\n",
              "bad.yaml:4:6", "bodies.b: missing key 'mass'");
}

TEST(BadInput, WrongTypeListForNumber) {
  ExpectError(
      kHead + "bodies:\n  b: {type: rigid, at: A, mass: [1], inertia: [1, 1, 1], fixed: true}\n",
      "bad.yaml:4:33", "bodies.b.mass: expected a number, got a list");
}

TEST(BadInput, WrongTypeTextForNumber) {
  ExpectError(kHead + "bodies:\n  b:\n    type: rigid\n    at: A\n    mass: heavy\n",
              "bad.yaml:7:11", "bodies.b.mass: expected a number, got 'heavy'");
}

TEST(BadInput, WrongVectorSize) {
  ExpectError("points:\n  A: [0, 0]\n", "bad.yaml:2:6",
              "points.A: expected a list of 3 numbers, got a list of 2");
}

TEST(BadInput, WrongSixVectorSize) {
  ExpectError("sections:\n  s:\n    stiffness: [1, 1, 1, 1, 1]\n", "bad.yaml:3:16",
              "sections.s.stiffness: expected a list of 6 numbers, got a list of 5");
}

TEST(BadInput, UndefinedPoint) {
  ExpectError(kHead + "bodies:\n  b: {type: rigid, between: [A, Q], mass: 1, inertia: [1, 1, 1]}\n",
              "bad.yaml:4:33", "bodies.b.between[1]: undefined point 'Q'");
}

TEST(BadInput, UndefinedBodySuggestsTheClosest) {
  ExpectError(
      kHead +
          "bodies:\n  base: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
          "joints:\n  j: {type: revolute, at: A, between: [ground, bse], axis: [0, 0, 1]}\n",
      "bad.yaml:6:48", "joints.j.between[1]: undefined body 'bse' (did you mean 'base'?)");
}

TEST(BadInput, UndefinedSection) {
  ExpectError(kHead + "bodies:\n  r: {type: soft, from: A, to: B, section: t, free: true}\n",
              "bad.yaml:4:44", "bodies.r.section: undefined section 't'");
}

TEST(BadInput, DuplicateBodyName) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], fixed: true}\n"
                  "  b: {type: rigid, at: B, mass: 1, inertia: [1, 1, 1], fixed: true}\n",
              "bad.yaml:5:3", "duplicate body name 'b' (first defined at bad.yaml:4:3)");
}

TEST(BadInput, DuplicateKeyInsideAMap) {
  ExpectError(
      kHead +
          "bodies:\n  b: {type: rigid, at: A, mass: 1, mass: 2, inertia: [1, 1, 1], fixed: true}\n",
      "bad.yaml:4:36", "bodies.b.mass: duplicate key 'mass'");
}

TEST(BadInput, ZeroLengthRod) {
  ExpectError(
      kHead + "bodies:\n  r: {type: soft, from: A, to: [0, 0, 0], section: s, free: true}\n",
      "bad.yaml:4:32", "bodies.r.to: zero-length segment");
}

TEST(BadInput, ZeroAxis) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j: {type: revolute, at: A, between: [ground, b], axis: [0, 0, 0]}\n",
              "bad.yaml:6:58", "joints.j.axis: the axis is zero");
}

TEST(BadInput, NonUnitAxis) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j: {type: revolute, at: A, between: [ground, b], axis: [0, 0, 2]}\n",
              "bad.yaml:6:58", "joints.j.axis: expected a unit vector, got length 2");
}

TEST(BadInput, NonPositiveMass) {
  ExpectError(
      kHead + "bodies:\n  b: {type: rigid, at: A, mass: 0, inertia: [1, 1, 1], fixed: true}\n",
      "bad.yaml:4:33", "bodies.b.mass: expected a positive number, got '0'");
}

TEST(BadInput, NonPositiveSectionStiffness) {
  ExpectError("sections:\n  s: {stiffness: [1, 1, -1, 1, 1, 1]}\n", "bad.yaml:2:25",
              "sections.s.stiffness[2]: stiffness entries must be positive");
}

TEST(BadInput, NegativeJointDamping) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j: {type: revolute, at: A, between: [ground, b], axis: [0, 0, 1], "
                  "damping: -5}\n",
              "bad.yaml:6:78", "joints.j.damping: expected a non-negative number, got '-5'");
}

TEST(BadInput, BodyConnectedToNothing) {
  ExpectError(kHead + "bodies:\n  lonely: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n",
              "bad.yaml:4:3", "bodies.lonely: body 'lonely' is connected to nothing");
}

TEST(BadInput, ProfileEndNotAfterStart) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], fixed: true}\n"
                  "loads:\n  f:\n    body: b\n    at: A\n    force: [1, 0, 0]\n"
                  "    profile: {type: ramp, t0: 1, t1: 0.5}\n",
              "bad.yaml:10:38", "loads.f.profile.t1: expected t1 > t0");
}

TEST(BadInput, TableTimesNotIncreasing) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], fixed: true}\n"
                  "loads:\n  f:\n    body: b\n    at: A\n    force: [1, 0, 0]\n"
                  "    profile: {type: table, times: [0, 1, 1], values: [0, 1, 2]}\n",
              "bad.yaml:10:42", "loads.f.profile.times[2]: times must be strictly increasing");
}

TEST(BadInput, NonFiniteNumbers) {
  ExpectError("gravity: [0, 0, .inf]\n", "bad.yaml:1:17",
              "gravity[2]: expected a number, got '.inf'");
  ExpectError("gravity: [0, 0, 1e999]\n", "bad.yaml:1:17",
              "gravity[2]: expected a number, got '1e999' (number out of range)");
  ExpectError("gravity: [0, 0, 1/0]\n", "bad.yaml:1:17",
              "gravity[2]: expected a finite number, got '1/0'");
  ExpectError("gravity: [nan, 0, 0]\n", "bad.yaml:1:11",
              "gravity[0]: expected a number, got 'nan'");
}

TEST(BadInput, UnitsOtherThanSI) {
  ExpectError("units: imperial\n", "bad.yaml:1:8", "units: only SI units are supported");
}

TEST(BadInput, InvalidYaml) {
  ExpectError("points:\n  A: [0, 0, 0\n", "bad.yaml:3:1", "not valid YAML");
  ExpectError("points:\n  A: [0, 0, 0]\n   B: 1\n", "bad.yaml:3:4", "not valid YAML");
}

TEST(BadInput, SceneIsNotAMap) {
  ExpectError("- just\n- a list\n", "bad.yaml:1:1", "a scene is a map of sections");
  ExpectError("hello\n", "bad.yaml:1:1", "a scene is a map of sections");
}

TEST(BadInput, RodHasNoNodeAtTheJointPoint) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: C, section: s, elements: 3}\n"
                  "joints:\n  j: {type: revolute, at: B, between: [ground, r], axis: [0, 0, 1]}\n",
              "bad.yaml:6:48",
              "joints.j.between[1]: joint point: soft body 'r' has no node at [1, 0, 0]");
}

TEST(BadInput, MisspelledJointType) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j: {type: revolut, at: A, between: [ground, b], axis: [0, 0, 1]}\n",
              "bad.yaml:6:13", "joints.j.type: expected one of revolute, prismatic");
  EXPECT_NE(
      Error(kHead + "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                    "joints:\n  j: {type: revolut, at: A, between: [ground, b], axis: [0, 0, 1]}\n")
          .find("(did you mean 'revolute'?)"),
      std::string::npos);
}

TEST(BadInput, KeyNotUsedByThisJointType) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j: {type: spherical, at: A, between: [ground, b], axis: [0, 0, 1]}\n",
              "bad.yaml:6:53", "joints.j.axis: 'axis' is not used by spherical joints");
}

TEST(BadInput, SeriesElasticDriveWithoutSpring) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j:\n    type: revolute\n    at: A\n    between: [ground, b]\n"
                  "    axis: [0, 0, 1]\n    drive: {type: series_elastic, profile: 1}\n",
              "bad.yaml:11:12",
              "joints.j.drive: a series_elastic drive needs a positive stiffness");
}

TEST(BadInput, DriveCoordinateOutOfRange) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j:\n    type: revolute\n    at: A\n    between: [ground, b]\n"
                  "    axis: [0, 0, 1]\n    drive: {type: force, coordinate: 1, profile: 1}\n",
              "bad.yaml:11:38",
              "joints.j.drive.coordinate: expected an integer from 0 to 0, got '1'");
}

TEST(BadInput, UniversalAxesNotOrthogonal) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j: {type: universal, at: A, between: [ground, b], axis: [0, 0, 1], "
                  "axis2: [0, 0.6, 0.8]}\n",
              "bad.yaml:6:77", "joints.j.axis2: must be orthogonal to 'axis'");
}

TEST(BadInput, BothSidesTheSameBody) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1]}\n"
                  "joints:\n  j: {type: revolute, at: A, between: [b, b], axis: [0, 0, 1]}\n",
              "bad.yaml:6:39", "joints.j.between: both sides are the same body 'b'");
}

TEST(BadInput, GroundIsReserved) {
  ExpectError(
      kHead + "bodies:\n  ground: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], fixed: true}\n",
      "bad.yaml:4:3", "bodies.ground: 'ground' is reserved");
}

TEST(BadInput, WeldToARigidBody) {
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], fixed: true}\n"
                  "  r: {type: soft, from: A, to: B, section: s, weld_start: b}\n",
              "bad.yaml:5:59", "bodies.r.weld_start: 'b' must be a soft body");
}

TEST(BadInput, OutputArcLengthBeyondTheRod) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "outputs:\n  points:\n    mid: {rod: r, s: 1.5}\n",
              "bad.yaml:7:22", "outputs.points.mid.s: arc length beyond the end of the rod");
}

TEST(BadInput, UnknownJointInOutputs) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "outputs:\n  joints: [J9]\n",
              "bad.yaml:6:12", "outputs.joints[0]: undefined joint 'J9'");
}

TEST(BadInput, AnalysisEndBeforeStart) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis: {start_time: 2, end_time: 1}\n",
              "bad.yaml:5:37", "analysis.end_time: expected end_time > start_time");
}

// step: auto (error-controlled steps): its keys, their ranges, and the keys it needs.
TEST(BadInput, AdaptiveStepKeys) {
  const std::string body =
      kHead + "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\nanalysis:\n";
  ExpectError(body + "  step: auto\n", "bad.yaml:6:9",
              "analysis.step: 'step: auto' requires analysis.tolerance");
  ExpectError(body + "  step: fast\n", "bad.yaml:6:9", "analysis.step: expected a number");
  ExpectError(body + "  step: auto\n  tolerance: 0\n", "bad.yaml:7:14",
              "analysis.tolerance: expected a positive number");
  ExpectError(body + "  step: auto\n  tolerance: {absolute: 1e-6, relative: -1}\n", "bad.yaml:7:41",
              "analysis.tolerance.relative: expected a non-negative number");
  ExpectError(body + "  step: auto\n  tolerance: {absolut: 1e-6}\n", "bad.yaml:7:15",
              "analysis.tolerance.absolut: unknown key 'absolut' (did you mean 'absolute'?)");
  ExpectError(body + "  step: auto\n  tolerance: 1e-6\n  min_step: 1e-3\n  max_step: 1e-4\n",
              "bad.yaml:9:13", "analysis.max_step: expected max_step >= min_step");
  ExpectError(body + "  step: auto\n  tolerance: 1e-6\n  min_step: -1\n", "bad.yaml:8:13",
              "analysis.min_step: expected a positive number");
  ExpectError(body + "  step: auto\n  tolerance: 1e-6\n  max_step: 1e-2\n  initial_step: 1\n",
              "bad.yaml:9:17", "analysis.initial_step: expected a step in [min_step, max_step]");
  ExpectError(body + "  step: 1e-3\n  tolerance: 1e-6\n", "bad.yaml:7:14",
              "analysis.tolerance: applies only to 'step: auto'");
  ExpectError(body + "  max_step: 1e-3\n", "bad.yaml:6:13",
              "analysis.max_step: applies only to 'step: auto'");
  // Valid: a number for both tolerances, or both given, with limits.
  EXPECT_EQ(Error(body + "  step: auto\n  tolerance: 1e-6\n"), "(no error)");
  const Scene s = ParseScene(body +
                                 "  step: auto\n  tolerance: {absolute: 1e-5, relative: 1e-3}\n"
                                 "  min_step: 1e-6\n  max_step: 1e-2\n  initial_step: 2e-3\n",
                             "ok.yaml", {});
  EXPECT_TRUE(s.analysis.adaptive_steps);
  EXPECT_EQ(s.analysis.dynamic.absolute_tolerance, 1e-5);
  EXPECT_EQ(s.analysis.dynamic.relative_tolerance, 1e-3);
  EXPECT_EQ(s.analysis.dynamic.min_step, 1e-6);
  EXPECT_EQ(s.analysis.dynamic.max_step, 1e-2);
  EXPECT_EQ(s.analysis.dynamic.initial_step, 2e-3);
  EXPECT_EQ(s.analysis.step, 2e-3);
}

// Near t = 1e15 s doubles are 0.125 s apart: a 1 ms step would silently become 0.125 s.
TEST(BadInput, TimesTooLargeForTheStepAreRefusedNamingTheField) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  start_time: 1e15\n  end_time: 1.0000000000001e15\n",
              "bad.yaml:7:13",
              "analysis.end_time: doubles near t = 1e+15 s are 0.125 s apart, so steps of "
              "0.001 s cannot be taken");
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  start_time: -1e15\n  end_time: -0.9999999999999e15\n",
              "bad.yaml:6:15", "analysis.start_time: doubles near t = 1e+15 s");
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  start_time: 1e7\n  end_time: 1.00001e7\n",
              "bad.yaml:7:13",
              "analysis.end_time: doubles near t = 1.00001e+07 s are 1.86e-09 s "
              "apart, so steps of 0.001 s cannot be taken to a relative accuracy of 1e-06 (the "
              "step would silently change); use a step of at least 0.00186 s");
  // At the limit: a 1 ms step is representable to 1e-6 up to t = 4.5e6 s (spacing 9.3e-10 s).
  EXPECT_EQ(Error(kHead + "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                          "analysis:\n  start_time: 4e6\n  end_time: 4.000001e6\n"),
            "(no error)");
}

TEST(BadInput, SpectralRadiusOutsideTheUnitInterval) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  rho_inf: 1.5\n",
              "bad.yaml:6:12", "analysis.rho_inf: expected a spectral radius in [0, 1]");
}

TEST(BadInput, UnknownNewtonVariantOrPredictor) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  newton: modified\n",
              "bad.yaml:6:11",
              "analysis.newton: expected one of simplified or full, got 'modified'");
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  predictor: [last]\n",
              "bad.yaml:6:14",
              "analysis.predictor: expected one of adaptive, last or zero, got a list");
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  convergence: 1e-8\n",
              "bad.yaml:6:16",
              "analysis.convergence: expected one of estimated or measured, got '1e-8'");
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "analysis:\n  constraints: index2\n",
              "bad.yaml:6:16",
              "analysis.constraints: expected one of index3, ggl or auto, got 'index2'");
}

// analysis.statics (statics.h, StaticOptions): each bad value at its line and column.
TEST(BadInput, StaticPathSettings) {
  const std::string head = kHead + "bodies:\n  r: {type: soft, from: A, to: B, section: s}\n";
  ExpectError(head + "analysis:\n  statics: {method: riks}\n", "bad.yaml:6:21",
              "analysis.statics.method: expected one of load or arclength, got 'riks'");
  ExpectError(head + "analysis:\n  statics: {metod: load}\n", "bad.yaml:6:13",
              "analysis.statics.metod: unknown key 'metod' (did you mean 'method'?)");
  ExpectError(head + "analysis:\n  statics:\n    arc_length_min: 2\n    arc_length_max: 1\n",
              "bad.yaml:8:21",
              "analysis.statics.arc_length_max: expected arc_length_max >= arc_length_min");
  ExpectError(head + "analysis:\n  statics: {max_steps: 0}\n", "bad.yaml:6:24",
              "analysis.statics.max_steps: expected an integer from 1 to 10000000, got '0'");
  ExpectError(head + "analysis:\n  statics: {arc_length: -1}\n", "bad.yaml:6:25",
              "analysis.statics.arc_length: expected a positive number, got '-1'");
  ExpectError(head + "analysis:\n  max_iterations: 5\n  statics: {desired_iterations: 0}\n",
              "bad.yaml:7:33",
              "analysis.statics.desired_iterations: expected an integer from 1 to 1000, got '0'");
}

// analysis.threads: 'auto' or an integer from 1 to 256, each bad value at its line and column.
TEST(BadInput, Threads) {
  const std::string head =
      kHead + "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n";
  const std::string expected = "analysis.threads: expected 'auto' or an integer from 1 to 256";
  ExpectError(head + "analysis:\n  threads: 0\n", "bad.yaml:6:12", expected + ", got '0'");
  ExpectError(head + "analysis:\n  threads: 2.5\n", "bad.yaml:6:12", expected + ", got '2.5'");
  ExpectError(head + "analysis:\n  threads: 257\n", "bad.yaml:6:12", expected + ", got '257'");
  ExpectError(head + "analysis:\n  threads: many\n", "bad.yaml:6:12", expected + ", got 'many'");
  ExpectError(head + "analysis:\n  threads: 'auto'\n", "bad.yaml:6:12", expected + ", got 'auto'");
  ExpectError(head + "analysis:\n  threads: [2]\n", "bad.yaml:6:12", expected);
  EXPECT_EQ(ParseScene(head + "analysis:\n  threads: 3\n", "ok.yaml").analysis.threads, 3);
  EXPECT_EQ(ParseScene(head + "analysis:\n  threads: auto\n", "ok.yaml").analysis.threads,
            kAutoThreads);
  EXPECT_EQ(ParseScene(head, "ok.yaml").analysis.threads, kAutoThreads);
}

TEST(BadInput, NonScalarMapKey) {
  ExpectError("points:\n  [1, 2]: [0, 0, 0]\n", "bad.yaml:2:3", "map keys must be plain names");
}

TEST(BadInput, SecondYamlDocument) {
  ExpectError("units: SI\n---\nunits: SI\n", "bad.yaml:3:1", "one YAML document");
}

TEST(BadInput, AliasExpansionIsBounded) {
  std::string text = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i <= 8; ++i) {
    const std::string index = std::to_string(i);
    std::string prev = "*a";
    prev += std::to_string(i - 1);
    text += "a";
    text += index;
    text += ": &a";
    text += index;
    text += " [";
    text += prev;
    for (int k = 1; k < 10; ++k) text += ", " + prev;
    text += "]\n";
  }
  const std::string message = Error(text);
  EXPECT_NE(message.find("more than 1000000 nodes"), std::string::npos) << message;
}

TEST(BadInput, DeepNestingIsAnErrorNotACrash) {
  const std::string text = "a: " + std::string(100000, '[') + std::string(100000, ']') + "\n";
  const std::string message = Error(text);
  EXPECT_EQ(message.rfind("bad.yaml:", 0), 0u) << message;
}

TEST(BadInput, HugeElementCountIsRejected) {
  ExpectError(
      kHead + "bodies:\n  r: {type: soft, from: A, to: B, section: s, elements: 1e9, free: true}\n",
      "bad.yaml:4:57", "bodies.r.elements: expected an integer from 1 to 100000");
}

TEST(BadInput, OverrideOfAnUnknownPathNamesIt) {
  const std::string scene =
      kHead + "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n";
  ExpectError(scene, "bad.yaml: override 'analysis.stepp=1e-3'",
              "analysis.stepp: unknown key 'stepp' (did you mean 'step'?)",
              {"analysis.stepp=1e-3"});
  ExpectError(scene, "bad.yaml: override 'bodies.q.elements=3'", "bodies: no entry 'q'",
              {"bodies.q.elements=3"});
  ExpectError(scene, "bad.yaml: override 'points.A.x=1'",
              "'points.A' is a list of 3 items; 'x' is not an index", {"points.A.x=1"});
  ExpectError(scene, "bad.yaml: override 'analysis'", "expected KEY.PATH=VALUE", {"analysis"});
  ExpectError(scene, "bad.yaml: override 'bodies.r.elements=0'",
              "bodies.r.elements: expected an integer from 1", {"bodies.r.elements=0"});
}

TEST(BadInput, WeldAcrossAKink) {
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, free: true}\n"
                  "  q: {type: soft, from: B, to: [1, 1, 0], section: s, weld_start: r}\n",
              "bad.yaml:5:67", "bodies.q.weld_start: the section frames of 'q' and 'r' differ");
}

TEST(BadInput, SceneWithoutBodies) {
  ExpectError("units: SI\npoints: {A: [0, 0, 0]}\n", "bad.yaml:1:1",
              "bodies: the scene has no bodies");
}

TEST(BadInput, ModelBuilderErrorsAreRethrownWithTheLocation) {
  // Two welded rods share their node at B: a joint between them has the same node on both
  // sides, which ModelBuilder::Build rejects; the message gains the file and the joint's line.
  ExpectError(
      kHead +
          "bodies:\n  r: {type: soft, from: A, to: B, section: s, elements: 1, free: true}\n"
          "  q: {type: soft, from: B, to: C, section: s, elements: 1, weld_start: r}\n"
          "joints:\n  j: {type: revolute, at: B, between: [r, q], axis: [0, 0, 1]}\n",
      "bad.yaml:7:3", "joints.j: joint 'j': both sides are node 'r.1'");
}

// --- files --------------------------------------------------------------------------------------

class BadFile : public ::testing::Test {
 protected:
  std::string Write(const std::string& name, const std::string& bytes) {
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("screwfem_bad_input_" + std::to_string(::getpid()) + "_" + name))
                                 .string();
    std::ofstream(path, std::ios::binary) << bytes;
    paths_.push_back(path);
    return path;
  }
  static std::string LoadError(const std::string& path) {
    try {
      LoadScene(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }
  void TearDown() override {
    for (const std::string& p : paths_) std::remove(p.c_str());
  }
  std::vector<std::string> paths_;
};

TEST_F(BadFile, EmptyFile) {
  const std::string path = Write("empty.yaml", "");
  EXPECT_EQ(LoadError(path), path + ":1:1: empty scene (no YAML content)");
  const std::string comments = Write("comments.yaml", "# nothing but a comment\n\n");
  EXPECT_EQ(LoadError(comments), comments + ":1:1: empty scene (no YAML content)");
}

TEST_F(BadFile, BinaryFile) {
  std::string bytes = "units: SI\npoints:\n  A: [0, 0";
  bytes += std::string(
      "\x7f"
      "ELF\x02\x01\x01\x00\x00\xff\xfe",
      12);
  const std::string path = Write("binary.yaml", bytes);
  const std::string message = LoadError(path);
  EXPECT_EQ(message.rfind(path + ":3:11: ", 0), 0u) << message;
  EXPECT_NE(message.find("not a YAML text file"), std::string::npos) << message;
}

TEST_F(BadFile, InvalidUtf8) {
  const std::string path = Write("latin1.yaml", "name: caf\xe9\n");
  const std::string message = LoadError(path);
  EXPECT_EQ(message.rfind(path + ":1:10: ", 0), 0u) << message;
}

TEST_F(BadFile, MissingFileAndDirectory) {
  EXPECT_NE(LoadError("/nonexistent/scene.yaml").find("/nonexistent/scene.yaml: cannot open"),
            std::string::npos);
  const std::string dir = std::filesystem::temp_directory_path().string();
  EXPECT_NE(LoadError(dir).find("is a directory"), std::string::npos);
}

TEST_F(BadFile, ErrorsInAFileNameTheFile) {
  const std::string path = Write("typo.yaml", "units: SI\ngravty: [0, 0, -9.81]\n");
  EXPECT_EQ(LoadError(path), path + ":2:1: gravty: unknown key 'gravty' (did you mean 'gravity'?)");
}

// Tendons and force elements (docs/scene-format.md, "tendons", "forces"): line 3 is "bodies:",
// line 4 a free rod from A to C with nodes at s = 0, 1, 2, line 5 the section under test.
const std::string kRod =
    kHead + "bodies:\n  r: {type: soft, from: A, to: C, section: s, elements: 2, free: true}\n";

TEST(BadInput, EyeletOffTheRodOrAtAPointBetweenNodes) {
  // An arc length between nodes is an eyelet on the element's section; beyond the rod's end it
  // is an error.
  ExpectError(kRod +
                  "tendons:\n  t:\n    eyelets:\n      - {body: r, s: 0}\n"
                  "      - {body: r, s: 2.5, offset: [0, 0.01, 0]}\n    tension: 1\n",
              "bad.yaml:9:9",
              "tendons.t.eyelets[1]: eyelet: arc length 2.5 m is off soft body 'r' (length 2 m)");
  ExpectError(kRod +
                  "tendons:\n  t:\n    eyelets:\n      - {body: r, s: 0}\n"
                  "      - {body: r, at: [0.5, 0, 0]}\n    tension: 1\n",
              "bad.yaml:9:9", "eyelet: soft body 'r' has no node at [0.5, 0, 0]");
}

TEST(BadInput, TendonThroughOnePoint) {
  ExpectError(kRod + "tendons:\n  t: {eyelets: [{body: r, s: 0}], tension: 1}\n", "bad.yaml:6:16",
              "tendons.t.eyelets: expected a list of at least two eyelets");
}

TEST(BadInput, TendonTensionThatCanBecomeNegative) {
  ExpectError(kRod +
                  "tendons:\n  t:\n    eyelets: [{body: r, s: 0}, {body: r, s: 2}]\n"
                  "    tension: {type: sine, value: 2, frequency: 1}\n",
              "bad.yaml:6:3",
              "tendon 't': the tension profile can become negative (its terms' lower bound is "
              "-2.000000 N)");
  ExpectError(kRod + "tendons:\n  t: {eyelets: [{body: r, s: 0}, {body: r, s: 1}], tension: -5}\n",
              "bad.yaml:6:3", "a tendon can only pull");
}

TEST(BadInput, TendonDrawnByTensionAndByLength) {
  ExpectError(kRod +
                  "tendons:\n  t:\n    eyelets: [{body: r, s: 0}, {body: r, s: 2}]\n"
                  "    tension: 1\n    length: 1.9\n",
              "bad.yaml:9:13",
              "tendons.t.length: give either 'tension' or 'length' (the tendon is drawn by one of "
              "them), not both");
}

TEST(BadInput, TendonLengthThatCanReachZero) {
  ExpectError(kRod +
                  "tendons:\n  t:\n    eyelets: [{body: r, s: 0}, {body: r, s: 2}]\n"
                  "    length: {type: ramp, value: -3, t1: 1}\n",
              "bad.yaml:6:3",
              "tendon 't': the length profile can become zero or negative (its terms' lower bound "
              "is -3.000000 m)");
}

TEST(BadInput, CoincidingEyeletsPointAtTheSecond) {
  ExpectError(kRod +
                  "tendons:\n  t:\n    eyelets:\n      - {body: r, s: 1}\n"
                  "      - {body: r, at: B}\n    tension: 1\n",
              "bad.yaml:9:9",
              "tendons.t.eyelets[1]: coincides with eyelet 0 in the reference configuration");
}

TEST(BadInput, OffsetOnARigidBodyOrTheGround) {
  ExpectError(
      kRod + "forces:\n  f: {a: {at: A, offset: [0, 1, 0]}, b: {body: r, s: 2}, stiffness: 1}\n",
      "bad.yaml:6:18",
      "forces.f.a.offset: 'offset' is not used by the ground (give the point itself as "
      "'at')");
}

TEST(BadInput, ForceElementWithBothEndsOnTheGround) {
  ExpectError(kRod + "forces:\n  f: {a: {at: A}, b: {at: B}, stiffness: 1}\n", "bad.yaml:6:3",
              "force element 'f': both ends are on ground");
  ExpectError(kRod + "forces:\n  f: {a: {at: A}, b: {body: r, s: 2}}\n", "bad.yaml:6:6",
              "forces.f: missing key 'stiffness' (or 'damping', or 'force')");
  // A rest length without a spring would be ignored (issue 40 item 6).
  ExpectError(kRod + "forces:\n  f: {a: {at: A}, b: {body: r, s: 2}, damping: 1, rest_length: 1}\n",
              "bad.yaml:6:64",
              "forces.f.rest_length: 'rest_length' is the spring's rest length; this force "
              "element has no 'stiffness' (give one, or remove 'rest_length')");
}

TEST(BadInput, UnknownRunTimeInputName) {
  ExpectError(kHead +
                  "inputs: {u: 0}\nbodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], "
                  "free: true}\nloads:\n  f: {body: b, at: A, force: [1, 0, 0], profile: "
                  "{type: input, name: uu}}\n",
              "bad.yaml:7:70", "loads.f.profile.name: unknown input 'uu' (did you mean 'u'?)");
}

// Actuation (docs/scene-format.md, "actuation"): line 3 is "bodies:", line 4 the free rod r
// (nodes at s = 0, 1, 2), line 5 "actuation:", line 6 the actuator under test.
std::string Actuator(const std::string& entry) { return kRod + "actuation:\n  a: " + entry + "\n"; }

TEST(BadInput, ActuatorOnAnUnknownOrRigidBody) {
  ExpectError(Actuator("{type: pressure, rod: q, area: 1e-4, offset: [0, 0.01], pressure: 1}"),
              "bad.yaml:6:28", "actuation.a.rod: undefined body 'q'");
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], free: "
                  "true}\nactuation:\n  a: {type: rest_strain, rod: b, vector: [0, 0, 0, 0, "
                  "0, 1]}\n",
              "bad.yaml:6:31",
              "actuation.a.rod: 'b' is a rigid body; actuation acts on soft bodies (rods)");
}

TEST(BadInput, ActuatorTypeAreaAndOffsetAreChecked) {
  ExpectError(
      Actuator("{type: balloon, rod: r}"), "bad.yaml:6:13",
      "actuation.a.type: expected one of pressure, muscle, rest_strain or active_stress, got "
      "'balloon'");
  ExpectError(Actuator("{type: pressure, rod: r, area: -1e-4, offset: [0, 0.01], pressure: 1}"),
              "bad.yaml:6:37", "actuation.a.area: expected a positive number, got '-1e-4'");
  ExpectError(Actuator("{type: pressure, rod: r, area: 1e-4, offset: [0.01], pressure: 1}"),
              "bad.yaml:6:51",
              "actuation.a.offset: expected [r2, r3] (or [0, r2, r3]) in the section frame [m], "
              "got 1 numbers");
  ExpectError(Actuator("{type: pressure, rod: r, area: 1e-4, offset: [0, 0.01]}"), "bad.yaml:6:6",
              "actuation.a: missing key 'pressure'");
  ExpectError(Actuator("{type: muscle, rod: r, area: 1e-4, offset: [0, 0.01], activation: 1}"),
              "bad.yaml:6:6", "actuation.a: missing key 'max_stress'");
  ExpectError(Actuator("{type: pressure, rod: r, area: 1e-4, offset: [0, 0.01], pressure: 1, "
                       "vector: [1, 0, 0, 0, 0, 0]}"),
              "bad.yaml:6:75", "actuation.a.vector: 'vector' is not used by type 'pressure'");
  ExpectError(Actuator("{type: rest_strain, rod: r, vector: [0, 0, 1]}"), "bad.yaml:6:42",
              "actuation.a.vector");
}

TEST(BadInput, ActuatorRangeMustLieOnRodNodes) {
  ExpectError(Actuator("{type: rest_strain, rod: r, from: 0.5, vector: [0, 0, 0, 0, 0, 1]}"),
              "bad.yaml:6:40",
              "actuation.a.from: arc length 0.500000 m is not at a node of rod 'r' (the nearest "
              "node is at 0.000000 m); a conforming mesh (defaults.conform_mesh: true) puts one "
              "there",
              {"defaults.conform_mesh=false"});
  ExpectError(Actuator("{type: rest_strain, rod: r, to: 3, vector: [0, 0, 0, 0, 0, 1]}"),
              "bad.yaml:6:38", "actuation.a.to: must not exceed the rod's length 2.000000 m");
  ExpectError(Actuator("{type: rest_strain, rod: r, from: 1, to: 1, vector: [0, 0, 0, 0, 0, 1]}"),
              "bad.yaml:6:47", "actuation.a.to: expected an arc length greater than 'from'");
  ExpectError(Actuator("{type: active_stress, rod: r, vector: [0, 0, 0, 0, 0, 1], profile: "
                       "{type: input, name: u}}"),
              "bad.yaml:6:93", "actuation.a.profile.name: unknown input 'u'");
}

// visual_radius (docs/scene-format.md, sections and soft bodies): positive, soft bodies only;
// it sets the rod's drawn outline (Section::width, height, round), the body's over its
// section's.
TEST(BadInput, VisualRadius) {
  ExpectError("sections:\n  s: {stiffness: [1, 1, 1, 1, 1, 1], visual_radius: 0}\n",
              "bad.yaml:2:53", "sections.s.visual_radius: expected a positive number, got '0'");
  ExpectError(kHead +
                  "bodies:\n  r: {type: soft, from: A, to: B, section: s, visual_radius: -0.01, "
                  "free: true}\n",
              "bad.yaml:4:62", "bodies.r.visual_radius: expected a positive number, got '-0.01'");
  ExpectError(kHead +
                  "bodies:\n  b: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], fixed: true, "
                  "visual_radius: 0.1}\n",
              "bad.yaml:4:69",
              "bodies.b.visual_radius: 'visual_radius' is not used by rigid bodies");
}

TEST(BadInput, VisualRadiusSetsTheDrawnOutline) {
  const std::string text =
      "points: {A: [0, 0, 0], B: [1, 0, 0], C: [2, 0, 0]}\n"
      "sections:\n"
      "  s: {stiffness: [1, 1, 1, 1, 1, 1], visual_radius: 0.01}\n"
      "  r: {shape: rectangle, width: 0.02, height: 0.01, material: {E: 1e9, nu: 0.3, "
      "density: 1000}}\n"
      "bodies:\n"
      "  a: {type: soft, from: A, to: B, section: s, free: true}\n"
      "  b: {type: soft, from: B, to: C, section: s, visual_radius: 0.03, free: true}\n"
      "  c: {type: soft, from: A, to: C, section: r, free: true}\n"
      "  d: {type: soft, from: A, to: C, section: r, visual_radius: 0.005, free: true}\n";
  const Scene scene = ParseScene(text, "ok.yaml");
  const auto& rods = scene.model.rods;
  ASSERT_EQ(rods.size(), 4u);
  EXPECT_EQ(rods[0].section.width, 0.02);  // the section's visual_radius
  EXPECT_EQ(rods[0].section.height, 0.02);
  EXPECT_TRUE(rods[0].section.round);
  EXPECT_EQ(rods[1].section.width, 0.06);  // the body's, over the section's
  EXPECT_EQ(rods[2].section.width, 0.02);  // the rectangle's own outline
  EXPECT_EQ(rods[2].section.height, 0.01);
  EXPECT_FALSE(rods[2].section.round);
  EXPECT_EQ(rods[3].section.width, 0.01);  // drawn round, the mechanics unchanged
  EXPECT_TRUE(rods[3].section.round);
  EXPECT_EQ(rods[3].section.stiffness, rods[2].section.stiffness);
}

}  // namespace
}  // namespace screwfem::bad_input_test
