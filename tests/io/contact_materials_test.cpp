// Contact materials per pair of groups (docs/scene-format.md, `contact.groups`, `contact.pairs`)
// and the swept check against tunnelling (elements/crossing.h; docs/numerics.md, "No
// tunnelling"): two boxes on one plane under tilted gravity, one pair sticking and one sliding
// (closed forms), the resolved values in summary.json, bad input at file:line:col, and a rod
// swinging onto a clamped rod in statics and dropped fast onto it in dynamics.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "scene_error_util.h"
#include "screwfem/assemble/assemble.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/crossing.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::contact_materials_test {
namespace {

// Gravity tilted by 20 degrees along x over a plane z = 0: tan 20 deg = 0.364. Box `grip`
// (pair with the ground mu_s 0.6, mu_k 0.5) sticks; box `slick` (mu 0.1) slides at
// a = g (sin 20 - 0.1 cos 20) = 2.43336 m/s^2.
const double kTheta = 20.0 * M_PI / 180.0;
const std::string kBoxes = "gravity: [" + std::to_string(9.81 * std::sin(kTheta)) + ", 0, " +
                           std::to_string(-9.81 * std::cos(kTheta)) + R"(]
bodies:
  grip: {type: rigid, at: [0, 0, 0.05], mass: 1, inertia: [0.00167, 0.00167, 0.00167],
         free: true, shapes: [{type: box, center: [0, 0, 0.05], half_sizes: [0.05, 0.05, 0.05]}]}
  slick: {type: rigid, at: [0, 0.5, 0.05], mass: 1, inertia: [0.00167, 0.00167, 0.00167],
          free: true, shapes: [{type: box, center: [0, 0.5, 0.05], half_sizes: [0.05, 0.05, 0.05]}]}
contact:
  stiffness: 1e5
  onset: 1e-4
  friction: 0.3
  obstacles:
    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
  groups:
    gripping: [grip]
  pairs:
    - {groups: [gripping, ground], friction: 0.5, static_friction: 0.6}
    - {groups: [slick, ground], friction: 0.1, damping_ratio: 0.5, stiffness: 2e5}
analysis: {type: dynamic, end_time: 0.5, step: 1e-3, rho_inf: 0.8}
outputs:
  points:
    grip: {body: grip, at: [0, 0, 0.05]}
    slick: {body: slick, at: [0, 0.5, 0.05]}
  interval: 0.05
  vtk: false
)";

TEST(ContactMaterials, ScenePairsResolveWithTheScenesDefaults) {
  const Scene s = ParseScene(kBoxes, "boxes.yaml");
  const Model& m = s.model;
  // gripping, then the groups of their own of the names in no group: ground, slick.
  ASSERT_EQ(m.contact_material_groups.size(), 3u);
  EXPECT_EQ(m.contact_material_groups[0].name, "gripping");
  EXPECT_EQ(m.contact_material_groups[1].name, "ground");
  EXPECT_EQ(m.contact_material_groups[1].obstacles, std::vector<int>{0});
  EXPECT_EQ(m.contact_material_groups[2].name, "slick");
  EXPECT_EQ(m.contact_material_groups[2].bodies, std::vector<int>{1});
  ASSERT_EQ(m.contact_laws.size(), 3u);
  const ContactMaterial& base = m.contact_laws[0];
  EXPECT_EQ(base.friction, 0.3);
  EXPECT_EQ(base.static_friction, 0.3);
  EXPECT_EQ(base.stiffness, 1e5);
  EXPECT_EQ(base.damping_ratio, 1.0);
  const ContactMaterial& grip = m.contact_laws[1];
  EXPECT_EQ(grip.friction, 0.5);
  EXPECT_EQ(grip.static_friction, 0.6);
  EXPECT_EQ(grip.stiffness, 1e5);  // the scene's
  EXPECT_EQ(grip.tangential_stiffness, 1e5);
  const ContactMaterial& slick = m.contact_laws[2];
  EXPECT_EQ(slick.friction, 0.1);
  EXPECT_EQ(slick.static_friction, 0.1);  // this pair's friction
  EXPECT_EQ(slick.stiffness, 2e5);
  EXPECT_EQ(slick.tangential_stiffness, 2e5);  // this pair's stiffness
  EXPECT_EQ(slick.damping_ratio, 0.5);
  // Every obstacle pair carries its law: 8 vertices of each box.
  ASSERT_EQ(m.contact_pairs.size(), 16u);
  for (const ContactPair& p : m.contact_pairs) {
    EXPECT_EQ(p.material, p.owner == 0 ? 1 : 2);
    // c_n = 2 zeta sqrt(k_n m).
    EXPECT_NEAR(p.damping, p.owner == 0 ? 2.0 * std::sqrt(1e5) : std::sqrt(2e5), 1e-9);
  }
  // The lookup by groups, both orders; no group: the scene's.
  EXPECT_EQ(ContactLawIndex(m, 0, 1), 1);
  EXPECT_EQ(ContactLawIndex(m, 1, 0), 1);
  EXPECT_EQ(ContactLawIndex(m, 1, 2), 2);
  EXPECT_EQ(ContactLawIndex(m, 0, -1), 0);
  EXPECT_EQ(ContactLawIndex(m, -1, -1), 0);
  EXPECT_EQ(ContactLawIndex(m, 0, 2), 0);
}

TEST(ContactMaterials, OneBoxSticksTheOtherSlidesAndSummaryHasThePairs) {
  test::ScopedDir dir("contact_materials");
  const Scene s = ParseScene(kBoxes, "boxes.yaml");
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table p = test::ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(p.well_formed) << p.problem;
  const int gx = p.Column("grip.x"), sx = p.Column("slick.x"), t = p.Column("t");
  ASSERT_GE(gx, 0);
  ASSERT_GE(sx, 0);
  const std::vector<double>& last = p.rows.back();
  ASSERT_NEAR(last[static_cast<std::size_t>(t)], 0.5, 1e-12);
  // Sliding: x = a t^2 / 2 with a = g (sin - mu_k cos) = 0.30417 m at 0.5 s.
  const double a = 9.81 * (std::sin(kTheta) - 0.1 * std::cos(kTheta));
  EXPECT_NEAR(last[static_cast<std::size_t>(sx)], 0.5 * a * 0.25, 0.01 * 0.5 * a * 0.25);
  // Sticking: the box settles within the first 0.25 s (the anchors' elastic deflection
  // m g sin / (4 k_t) = 8.4 um, the tilt of its normal springs, the start's jolt) to 23 um and
  // then does not creep: under 1e-9 m over the last 0.25 s.
  const double elastic = 9.81 * std::sin(kTheta) / (4.0 * 1e5);
  double x_quarter = NAN;
  for (const std::vector<double>& row : p.rows)
    if (std::abs(row[static_cast<std::size_t>(t)] - 0.25) < 1e-9)
      x_quarter = row[static_cast<std::size_t>(gx)];
  ASSERT_TRUE(std::isfinite(x_quarter));
  EXPECT_LT(std::abs(last[static_cast<std::size_t>(gx)]), 4.0 * elastic);
  EXPECT_LT(std::abs(last[static_cast<std::size_t>(gx)] - x_quarter), 1e-9);
  // summary.json: the laws as resolved, the scene's first (groups null).
  const std::optional<test::Json> summary = test::ParseJsonFile(dir.path() + "/summary.json");
  ASSERT_TRUE(summary.has_value());
  const test::Json* laws = summary->Find("settings.contact.materials");
  ASSERT_NE(laws, nullptr);
  ASSERT_EQ(laws->array.size(), 3u);
  EXPECT_EQ(summary->Find("settings.contact.friction_law")->string, "stick");
  EXPECT_EQ(laws->array[0].Find("groups")->kind, test::Json::Kind::kNull);
  const double expected[3][5] = {
      {0.3, 0.3, 1e5, 1.0, 1e5}, {0.5, 0.6, 1e5, 1.0, 1e5}, {0.1, 0.1, 2e5, 0.5, 2e5}};
  const char* keys[5] = {"friction", "static_friction", "stiffness", "damping_ratio",
                         "tangential_stiffness"};
  const char* groups[3][2] = {{"", ""}, {"gripping", "ground"}, {"slick", "ground"}};
  for (std::size_t i = 0; i < 3; ++i) {
    for (int k = 0; k < 5; ++k)
      EXPECT_EQ(laws->array[i].Find(keys[k])->number, expected[i][k]) << i << " " << keys[k];
    if (i == 0) continue;
    const test::Json* g = laws->array[i].Find("groups");
    ASSERT_EQ(g->array.size(), 2u);
    EXPECT_EQ(g->array[0].string, groups[i][0]);
    EXPECT_EQ(g->array[1].string, groups[i][1]);
  }
}

// A pair's own onset (contact.pairs[].onset): two boxes held at a gap g above the plane with the
// scene's onset 1e-4 m and box `grip`'s pair at 1e-3 m. The force starts at each pair's onset:
// grip's bottom corners push with f_n = k (delta - g)^2 / (2 delta) (gap within its onset), slick's
// (the scene's onset) not at all; the potential k (delta - g)^3 / (6 delta) likewise.
std::string OnsetBoxes(double gap) {
  const std::string z = std::to_string(0.05 + gap);
  return R"(gravity: [0, 0, -9.81]
bodies:
  grip: {type: rigid, at: [0, 0, )" +
         z + R"(], mass: 1, inertia: [0.00167, 0.00167, 0.00167], free: true,
         shapes: [{type: box, center: [0, 0, )" +
         z + R"(], half_sizes: [0.05, 0.05, 0.05]}]}
  slick: {type: rigid, at: [0, 0.5, )" +
         z + R"(], mass: 1, inertia: [0.00167, 0.00167, 0.00167], free: true,
          shapes: [{type: box, center: [0, 0.5, )" +
         z + R"(], half_sizes: [0.05, 0.05, 0.05]}]}
contact:
  stiffness: 1e5
  onset: 1e-4
  friction: 0.5
  obstacles:
    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
  pairs:
    - {groups: [grip, ground], onset: 1e-3}
analysis: {type: static}
outputs:
  vtk: false
  points:
    grip: {body: grip, at: [0, 0, )" +
         z + R"(]}
    slick: {body: slick, at: [0, 0.5, )" +
         z + R"(]}
)";
}

TEST(ContactMaterials, ThePairsOwnOnsetStartsItsForce) {
  const double k = 1e5, delta = 1e-3, scene_delta = 1e-4;
  for (double gap : {5e-4, 0.9e-4, 1.01e-3}) {
    const Scene s = ParseScene(OnsetBoxes(gap), "onset.yaml");
    const Model& m = s.model;
    ASSERT_EQ(m.contact_laws.size(), 2u);
    EXPECT_EQ(m.contact_laws[0].onset, scene_delta);
    EXPECT_EQ(m.contact_laws[1].onset, delta);
    EXPECT_EQ(ContactOnsetOf(m, 1), delta);
    EXPECT_EQ(ContactOnsetOf(m, 0), scene_delta);
    const Data data = MakeData(m);
    double grip_force = 0.0, slick_force = 0.0;
    int grip_active = 0, slick_active = 0;
    for (std::size_t i = 0; i < m.contact_pairs.size(); ++i) {
      const ContactState c = CalcContactState(m, data, static_cast<int>(i), false);
      if (!c.active) continue;
      // The box's bottom corners, at the gap to within the position's printed digits.
      EXPECT_NEAR(c.gap, gap, 1e-9);
      (m.contact_pairs[i].owner == 0 ? grip_force : slick_force) += c.normal_force;
      ++(m.contact_pairs[i].owner == 0 ? grip_active : slick_active);
    }
    const double g = gap;
    const double expected_grip =
        g < delta ? 4.0 * k * (delta - g) * (delta - g) / (2.0 * delta) : 0.0;
    const double expected_slick =
        g < scene_delta ? 4.0 * k * (scene_delta - g) * (scene_delta - g) / (2.0 * scene_delta)
                        : 0.0;
    EXPECT_EQ(grip_active, g < delta ? 4 : 0) << "gap " << g;
    EXPECT_EQ(slick_active, g < scene_delta ? 4 : 0) << "gap " << g;
    EXPECT_NEAR(grip_force, expected_grip, 1e-6 * (1.0 + expected_grip)) << "gap " << g;
    EXPECT_NEAR(slick_force, expected_slick, 1e-6 * (1.0 + expected_slick)) << "gap " << g;
    // The potential: the spring energy of both boxes' contacts (gravity apart).
    const double potential =
        (g < delta ? 4.0 * k * std::pow(delta - g, 3) / (6.0 * delta) : 0.0) +
        (g < scene_delta ? 4.0 * k * std::pow(scene_delta - g, 3) / (6.0 * scene_delta) : 0.0);
    EXPECT_NEAR(CalcEnergy(m, data).spring, potential, 1e-6 * (1e-9 + potential)) << "gap " << g;
  }
  // At rest in statics each box sinks to its own equilibrium within its onset, 4 k (delta -
  // g)^2 / (2 delta) = m g: g = delta - sqrt(m g delta / (2 k)), 0.78 mm for grip, 30 um for slick.
  test::ScopedDir dir("contact_onset");
  const RunResult r = RunScene(ParseScene(OnsetBoxes(5e-5), "onset.yaml"), dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table p = test::ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(p.well_formed) << p.problem;
  const std::vector<double>& last = p.rows.back();
  const double w = 9.81;  // m g [N]
  EXPECT_NEAR(last[static_cast<std::size_t>(p.Column("grip.z"))] - 0.05,
              delta - std::sqrt(w * delta / (2.0 * k)), 1e-8);
  EXPECT_NEAR(last[static_cast<std::size_t>(p.Column("slick.z"))] - 0.05,
              scene_delta - std::sqrt(w * scene_delta / (2.0 * k)), 1e-8);
  const std::optional<test::Json> summary = test::ParseJsonFile(dir.path() + "/summary.json");
  ASSERT_TRUE(summary.has_value());
  const test::Json* laws = summary->Find("settings.contact.materials");
  ASSERT_NE(laws, nullptr);
  ASSERT_EQ(laws->array.size(), 2u);
  EXPECT_EQ(laws->array[0].Find("onset")->number, scene_delta);
  EXPECT_EQ(laws->array[1].Find("onset")->number, delta);
}

// The same scene with its groups and pairs replaced (from line 13).
std::string WithPairs(const std::string& tail) {
  const std::size_t at = kBoxes.find("  groups:");
  const std::size_t end = kBoxes.find("analysis:");
  return kBoxes.substr(0, at) + tail + kBoxes.substr(end);
}

TEST(ContactMaterials, BadPairsAreReportedAtFileLineColumn) {
  using test::ExpectErrorAt;
  using test::SceneError;
  EXPECT_EQ(SceneError(WithPairs("  pairs: [{groups: [grip, ground], friction: 0.4}]\n"), "b.yaml"),
            "(no error)");
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grap, ground]}]\n"), "b.yaml"),
                "b.yaml:13:21: contact.pairs[0].groups[0]",
                "undefined contact group 'grap' (nor a body or obstacle) (did you mean 'grip'?)");
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grip, ground]}, {groups: [ground, "
                                     "grip]}]\n"),
                           "b.yaml"),
                "b.yaml:13:46: contact.pairs[1].groups",
                "the pair [ground, grip] is given twice (contact.pairs[0])");
  ExpectErrorAt(
      SceneError(WithPairs("  pairs: [{groups: [grip, ground], friction: -1}]\n"), "b.yaml"),
      "b.yaml:13:46: contact.pairs[0].friction", "");
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grip, ground], friction: 0.5, "
                                     "static_friction: 0.4}]\n"),
                           "b.yaml"),
                "b.yaml:13:68: contact.pairs[0].static_friction",
                "expected a value >= the pair's friction 0.5 (mu_s >= mu_k)");
  // Without its own friction, mu_k is the scene's (0.3).
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grip, ground], static_friction: "
                                     "0.2}]\n"),
                           "b.yaml"),
                "b.yaml:13:53: contact.pairs[0].static_friction",
                "expected a value >= the pair's friction 0.3 (mu_s >= mu_k)");
  ExpectErrorAt(
      SceneError(WithPairs("  pairs: [{groups: [grip, ground], stiffness: 0}]\n"), "b.yaml"),
      "b.yaml:13:47: contact.pairs[0].stiffness", "");
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grip, ground], onset: 0}]\n"), "b.yaml"),
                "b.yaml:13:43: contact.pairs[0].onset", "expected a positive number, got '0'");
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grip, ground], onset: x}]\n"), "b.yaml"),
                "b.yaml:13:43: contact.pairs[0].onset", "");
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grip], friction: 1}]\n"), "b.yaml"),
                "b.yaml:13:20: contact.pairs[0].groups", "expected two contact groups [a, b]");
  ExpectErrorAt(SceneError(WithPairs("  pairs: [{groups: [grip, ground], mu: 1}]\n"), "b.yaml"),
                "b.yaml:13:36: contact.pairs[0].mu", "unknown key 'mu'");
  ExpectErrorAt(SceneError(WithPairs("  groups: {boxes: [grip, slick, grip]}\n"), "b.yaml"),
                "b.yaml:13:33: contact.groups.boxes[2]",
                "'grip' is in contact group 'boxes' already");
  ExpectErrorAt(SceneError(WithPairs("  groups: {boxes: [grip, slik]}\n"), "b.yaml"),
                "b.yaml:13:26: contact.groups.boxes[1]", "undefined body or obstacle 'slik'");
  ExpectErrorAt(SceneError(WithPairs("  groups: {grip: [slick]}\n"), "b.yaml"),
                "b.yaml:13:12: contact.groups.grip",
                "a contact group cannot take the name of a body or obstacle ('grip')");
  ExpectErrorAt(SceneError(WithPairs("  groups: {boxes: [grip]}\n  pairs: [{groups: [grip, "
                                     "ground]}]\n"),
                           "b.yaml"),
                "b.yaml:14:21: contact.pairs[0].groups[0]",
                "'grip' is in contact group 'boxes': name the group");
}

// The issue's case (docs/numerics.md, "No tunnelling"): a rod hinged 1 mm above a rod clamped
// at both ends, loaded by its weight in one load step. The arm's line passes through the clamped
// rod's axis 6.3 deg below the horizontal.
std::string Hinged(const std::string& joint_extra, const std::string& analysis) {
  return R"(gravity: [0, 0, -9.81]
sections:
  rod: {shape: circle, radius: 0.005, material: {E: 2e9, nu: 0.3, density: 1000}}
bodies:
  base: {type: soft, from: [-0.1, 0, 0], to: [0.1, 0, 0], section: rod, elements: 4}
  arm: {type: soft, from: [0, -0.1, 0.011], to: [0, 0.1, 0.011], section: rod, elements: 8}
joints:
  clamp_a: {type: fixed, at: [-0.1, 0, 0], between: [ground, base]}
  clamp_b: {type: fixed, at: [0.1, 0, 0], between: [ground, base]}
  hinge: {type: revolute, at: [0, -0.1, 0.011], between: [ground, arm], axis: [1, 0, 0])" +
         joint_extra + R"(}
contact: {stiffness: 1e5}
)" + analysis +
         "outputs: {vtk: false, points: {tip: {body: arm, at: [0, 0.1, 0.011]}}}\n";
}

// The hinge's torsion spring: without contact the arm would rest at k phi = (M g L / 2) cos phi,
// 40 deg down (phi = 0.7 rad), through the clamped rod (which it touches at 0.58 deg).
double HingeStiffness() {
  const double weight = 1000 * M_PI * 0.005 * 0.005 * 0.2 * 9.81;  // 0.0154 N
  return weight * 0.1 * std::cos(0.7) / 0.7;
}

TEST(Tunnelling, StaticLoadStepThroughAClampedRodIsReportedNotCompleted) {
  // One load step and at most 2 halvings: even a quarter of the weight swings the arm 13 deg,
  // through the clamped rod, so every retry crosses and the solve ends naming the pair and the
  // load factor (before the check it reported `completed`).
  test::ScopedDir dir("tunnel_static");
  const Scene s = ParseScene(Hinged(", stiffness: " + std::to_string(HingeStiffness()),
                                    "analysis: {type: static, load_steps: 1, max_halvings: 2}\n"),
                             "h.yaml");
  const RunResult r = RunScene(s, dir.path());
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.message,
            "static solution failed at load factor 0: static solve stopped at load factor 0: the "
            "load step to 0.25 carried rod 'base' element 1 and rod 'arm' element 3 through each "
            "other even at the smallest increment (analysis.max_halvings); a stiffer or thicker "
            "contact (contact.stiffness, contact_radius), more load steps or a dynamic settle "
            "resolves it");
  const std::optional<test::Json> summary = test::ParseJsonFile(dir.path() + "/summary.json");
  ASSERT_TRUE(summary.has_value());
  EXPECT_NE(summary->Find("status")->string, "completed");
}

TEST(Tunnelling, StaticArmOnASpringComesToRestOnTheClampedRod) {
  // In one load step the arm would cross the clamped rod; retried smaller (up to 20 halvings),
  // it comes to rest on it and the load factor reaches 1.
  test::ScopedDir dir("tunnel_static_spring");
  const Scene s = ParseScene(Hinged(", stiffness: " + std::to_string(HingeStiffness()),
                                    "analysis: {type: static, load_steps: 1, max_halvings: 20}\n"),
                             "h.yaml");
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table p = test::ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(p.well_formed) << p.problem;
  const double tip_z = p.rows.back()[static_cast<std::size_t>(p.Column("tip.z"))];
  // Resting on the clamped rod: the arm touches it 0.58 deg below the horizontal (the tangent
  // from the hinge to the circle of radius 0.01 around the base's axis), so the tip (0.2 m from
  // the hinge) rests near z = 0.011 - 0.2 sin(0.58 deg) = 0.009 m; without the check it hung
  // at -0.189 m or swung through to 40 deg (-0.12 m).
  EXPECT_GT(tip_z, 0.005);
  EXPECT_LT(tip_z, 0.011);
}

TEST(Tunnelling, FastDynamicDropIsRejectedAndRetriedSmaller) {
  // The arm hinged above the clamped rod, launched down at 60 rad/s (12 m/s at the tip): one
  // step of 10 ms would carry it 34 deg, through the clamped rod; the check rejects such steps
  // and the halved steps let the contact stop it (the tip stays above the clamped rod).
  test::ScopedDir dir("tunnel_dynamic");
  const Scene s = ParseScene(
      Hinged(", initial_velocity: -60",
             "analysis: {type: dynamic, end_time: 0.03, step: 1e-2, max_halvings: 12}\n"),
      "h.yaml");
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table p = test::ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(p.well_formed) << p.problem;
  for (const std::vector<double>& row : p.rows)
    EXPECT_GT(row[static_cast<std::size_t>(p.Column("tip.z"))], -0.005) << "t = " << row[0];
}

// Two boxes (the swept check's box case): a block of half size 0.05 m thrown at 20 m/s at a
// fixed wall 4 cm thick, 5 cm away. One step of 10 ms carries its centre from x = -0.12 to
// +0.08, its faces from [-0.17, -0.07] to [0.03, 0.13], clear of the wall's [-0.02, 0.02]:
// without the check the penalty contact never sees the pair and the block passes through.
std::string BoxAndWall(double end_time) {
  return R"(gravity: [0, 0, 0]
bodies:
  wall: {type: rigid, at: [0, 0, 0], mass: 1, inertia: [0.001, 0.001, 0.001],
         shapes: [{type: box, center: [0, 0, 0], half_sizes: [0.02, 0.2, 0.2]}]}
  block: {type: rigid, at: [-0.12, 0, 0], mass: 1, inertia: [0.00167, 0.00167, 0.00167],
          free: true, initial_velocity: {linear: [20, 0, 0]},
          shapes: [{type: box, center: [-0.12, 0, 0], half_sizes: [0.05, 0.05, 0.05]}]}
joints:
  hold: {type: fixed, at: [0, 0, 0], between: [ground, wall]}
contact: {stiffness: 1e6, onset: 1e-4}
analysis: {type: dynamic, end_time: )" +
         std::to_string(end_time) + R"(, step: 1e-2, max_halvings: 12}
outputs: {vtk: false, interval: 1e-2, points: {c: {body: block, at: [-0.12, 0, 0]}}}
)";
}

TEST(Tunnelling, BoxCarriedThroughAThinBoxIsFound) {
  const Scene s = ParseScene(BoxAndWall(0.03), "walls.yaml");
  const Model& m = s.model;
  Data data = MakeData(m);
  const int block = m.bodies[1].node;
  ASSERT_EQ(m.bodies[1].name, "block");
  SaveCrossingReference(m, data);
  const auto crossed_at = [&](double x, double angle) {
    Data d = data;
    d.H[static_cast<std::size_t>(block)].x = Vec3(x, 0.0, 0.0);
    d.H[static_cast<std::size_t>(block)].R = ExpSO3(Vec3(0.0, 0.0, angle));
    Crossing c;
    const bool found = FindCrossing(m, d, &c);
    return found ? DescribeCrossing(m, c) : std::string();
  };
  // Through the wall, turned or not: found, naming both bodies.
  const std::string through = crossed_at(0.08, 0.0);
  EXPECT_NE(through.find("body 'wall'"), std::string::npos) << through;
  EXPECT_NE(through.find("body 'block'"), std::string::npos) << through;
  EXPECT_NE(crossed_at(0.08, 0.3), "");
  EXPECT_NE(crossed_at(-0.02, 0.0), "");  // the leading corners past the wall's mid-plane
  // Touching (resting at x = -0.07), pressed 5 mm in, moved away: not a crossing.
  EXPECT_EQ(crossed_at(-0.07, 0.0), "");
  EXPECT_EQ(crossed_at(-0.065, 0.0), "");
  EXPECT_EQ(crossed_at(-0.3, 0.5), "");
  // Past the wall's side (its half width 0.2 m): the block's path misses the wall's core.
  Data d = data;
  d.H[static_cast<std::size_t>(block)].x = Vec3(0.08, 0.6, 0.0);
  Crossing c;
  EXPECT_FALSE(FindCrossing(m, d, &c));
}

TEST(Tunnelling, BoxThrownAtAThinBoxIsStoppedNotCarriedThrough) {
  // The steps that carry the block through are rejected and retried smaller, until the contact
  // stops it (its 12 corner points at 1e6 N/m take its 200 J within 6 mm): its centre never
  // gets past x = -0.06, its face 1 cm into the wall.
  test::ScopedDir dir("tunnel_boxes");
  const RunResult r = RunScene(ParseScene(BoxAndWall(0.03), "walls.yaml"), dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table p = test::ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(p.well_formed) << p.problem;
  ASSERT_GE(p.rows.size(), 4u);
  for (const std::vector<double>& row : p.rows)
    EXPECT_LT(row[static_cast<std::size_t>(p.Column("c.x"))], -0.06) << "t = " << row[0];
}

}  // namespace
}  // namespace screwfem::contact_materials_test
