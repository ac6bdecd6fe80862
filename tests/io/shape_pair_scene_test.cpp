// Contact between moving bodies from a scene file (docs/scene-format.md, "contact"): two rigid
// spheres and a soft body pair with each other unless excluded (`exclude: [[a, b]]`), a soft
// body pairs with itself with `self: true` (skipping elements closer along it than
// `self_skip`), and bad input is reported at file:line:col.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "run_test_util.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::shape_pair_scene_test {
namespace {

const std::string kScene = R"(gravity: [0, 0, -9.81]
sections:
  rubber: {shape: circle, radius: 0.01, material: {E: 1e7, nu: 0.45, density: 1100}}
bodies:
  a: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
      shapes: [{type: sphere, center: [0, 0, 1], radius: 0.1}]}
  b: {type: rigid, at: [0.3, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
      shapes: [{type: sphere, center: [0.3, 0, 1], radius: 0.1},
               {type: capsule, from: [0.3, 0, 1], to: [0.4, 0, 1], radius: 0.05}]}
  rod: {type: soft, from: [0, 1, 0], to: [1, 1, 0], section: rubber, elements: 10, free: true}
)";

// Runs a scene with `pairs` pairs of shapes (one pair of bodies: a segment on a box is two)
// into a scratch directory and reads its pair_contacts.csv.
test::Table RunOnePairScene(const std::string& text, const char* dir_name, std::size_t pairs = 1) {
  test::ScopedDir dir(dir_name);
  const Scene s = ParseScene(text, "rest.yaml");
  EXPECT_EQ(AllShapePairs(s.model).size(), pairs);
  const RunResult r = RunScene(s, dir.path());
  EXPECT_TRUE(r.ok) << r.message;
  return test::ReadCsv(dir.path() + "/pair_contacts.csv");
}

std::string Error(const std::string& text) {
  try {
    ParseScene(text, "bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ShapePairScene, BodiesPairUnlessExcludedAndARodWithItselfWhenAsked) {
  // a: 1 sphere, b: 2 shapes, the rod: 10 capsules.
  const Model m = ParseScene(kScene + "contact: {}\n", "s.yaml").model;
  EXPECT_EQ(AllShapePairs(m).size(), 1u * 2u + 1u * 10u + 2u * 10u);
  const Model x = ParseScene(kScene + "contact: {exclude: [[a, b], [rod, b]]}\n", "s.yaml").model;
  EXPECT_EQ(AllShapePairs(x).size(), 10u);
  for (const ShapePair& p : AllShapePairs(x)) {
    EXPECT_TRUE(p.side[0].rod != p.side[1].rod);  // the rod with a
    EXPECT_EQ(p.side[p.side[0].rod ? 1 : 0].owner, 0);
  }
  // Self-contact: element pairs whose nearest ends are at least self_skip apart along the rod
  // (elements 0.1 m long, nearest ends 0, 0.1, 0.2 m apart for index differences 1, 2, 3: 0.25 m
  // keeps the differences from 4).
  const Model s = ParseScene(kScene +
                                 "contact: {self: true, self_skip: 0.25, exclude: [[a, b], "
                                 "[rod, b], [rod, a]]}\n",
                             "s.yaml")
                      .model;
  int count = 0;
  for (int i = 0; i < 10; ++i)
    for (int k = i + 4; k < 10; ++k) ++count;
  EXPECT_EQ(AllShapePairs(s).size(), static_cast<std::size_t>(count));
  for (const ShapePair& p : AllShapePairs(s)) {
    EXPECT_TRUE(p.side[0].rod && p.side[1].rod);
    EXPECT_GE(p.side[1].element - p.side[0].element, 4);
  }
}

// A 1 kg sphere resting on a fixed one (k = 1e5 N/m, onset 1e-4 m: the penetration branch,
// gap onset/2 - m g / k): pair_contacts.csv carries its weight along +z at that gap.
TEST(ShapePairScene, RunWritesPairContactsWithTheRestingSpheresWeight) {
  const double gap = 0.5e-4 - 9.81 / 1e5;
  const std::string text = R"(gravity: [0, 0, -9.81]
bodies:
  low: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], fixed: true,
        shapes: [{type: sphere, center: [0, 0, 1], radius: 0.1}]}
  top: {type: rigid, at: [0, 0, )" +
                           std::to_string(1.2 + gap) + R"(], mass: 1,
        inertia: [0.004, 0.004, 0.004], free: true,
        shapes: [{type: sphere, center: [0, 0, )" +
                           std::to_string(1.2 + gap) + R"(], radius: 0.1}]}
contact: {stiffness: 1e5, onset: 1e-4}
analysis: {type: dynamic, end_time: 0.05, step: 1e-3}
outputs: {interval: 0.01}
)";
  const test::Table c = RunOnePairScene(text, "shape_pair_scene");
  ASSERT_TRUE(c.well_formed) << c.problem;
  ASSERT_EQ(c.columns.size(), 26u);
  EXPECT_EQ(c.columns[14], "nx");
  EXPECT_EQ(c.columns[22], "part");
  EXPECT_EQ(c.columns[23], "slip");
  EXPECT_EQ(c.columns[24], "deflection");
  EXPECT_EQ(c.columns[25], "share");
  ASSERT_GE(c.rows.size(), 5u);
  const std::vector<double>& last = c.rows.back();
  EXPECT_NEAR(last[0], 0.05, 1e-12);
  // Side A is the first body (low): the normal points from the resting sphere down to it.
  EXPECT_EQ(last[2], 0.0);
  EXPECT_EQ(last[3], 0.0);
  EXPECT_EQ(last[6], 1.0);
  EXPECT_NEAR(last[16], -1.0, 1e-12);  // nz
  EXPECT_NEAR(last[17], 9.81, 1e-6);   // fn
  EXPECT_NEAR(last[21], gap, 1e-9);
  EXPECT_NEAR(last[10], 1.1, 1e-9);        // paz: the surface point of A
  EXPECT_NEAR(last[13], 1.1 + gap, 1e-9);  // pbz
  EXPECT_EQ(last[22], -1.0);               // part: two spheres, one point
}

// Boxes from a scene: a fixed box pairs with a capsule (2 pairs: the ends of the segment
// clipped to the face), a rod (2 per element) and another box (48: the 12 edges of each against
// the other, 2 points each); the capsule, lying flat on the box off its centre, carries half its
// weight at each end at the quadratic-branch gap (pair_contacts.csv).
TEST(ShapePairScene, BoxesPairWithCapsulesRodsAndBoxesAndCarryARestingCapsule) {
  const double gap = 1e-4 - std::sqrt(2e-4 * 0.5 * 9.81 / 1e5);
  const std::string z = std::to_string(0.02 + gap);
  const std::string bodies = R"(gravity: [0, 0, -9.81]
sections:
  rubber: {shape: circle, radius: 0.01, material: {E: 1e7, nu: 0.45, density: 1100}}
bodies:
  table: {type: rigid, at: [0, 0, 0], mass: 1, inertia: [1, 1, 1], fixed: true,
          shapes: [{type: box, center: [0, 0, -0.05], half_sizes: [0.5, 0.4, 0.05]}]}
  bar: {type: rigid, at: [0.1, -0.05, )" +
                             z + R"(], mass: 1, inertia: [1e-4, 4e-3, 4e-3], free: true,
        shapes: [{type: capsule, from: [0, -0.05, )" +
                             z + R"(], to: [0.2, -0.05, )" + z +
                             R"(], radius: 0.02}]}
)";
  const std::string more =
      R"(  block: {type: rigid, at: [0, 0.3, 1], mass: 1, inertia: [1, 1, 1], free: true,
          shapes: [{type: box, center: [0, 0.3, 1], half_sizes: [0.05, 0.04, 0.03]}]}
  rod: {type: soft, from: [0, 0, 2], to: [1, 0, 2], section: rubber, elements: 5, free: true}
contact: {exclude: [[bar, block], [bar, rod], [block, rod]]}
)";
  const Model m = ParseScene(bodies + more, "boxes.yaml").model;
  EXPECT_EQ(AllShapePairs(m).size(), 2u + 48u + 10u);
  for (const ShapePair& p : AllShapePairs(m)) {
    EXPECT_GT(p.side[1].half.x(), 0.0);  // the box is side B
    EXPECT_EQ(p.side[0].half.x(), 0.0);
  }
  const std::string text = bodies + R"(contact: {stiffness: 1e5, onset: 1e-4, friction: 0.5}
analysis: {type: dynamic, end_time: 0.05, step: 1e-3}
outputs: {interval: 0.01}
)";
  const test::Table c = RunOnePairScene(text, "shape_pair_box_scene", 2);
  ASSERT_TRUE(c.well_formed) << c.problem;
  ASSERT_GE(c.rows.size(), 5u);
  for (int k = 0; k < 2; ++k) {  // the last output's two rows: parts 0 and 1
    const std::vector<double>& last = c.rows[c.rows.size() - 2 + static_cast<std::size_t>(k)];
    EXPECT_NEAR(last[16], 1.0, 1e-12);        // nz: from the box (B) up to the capsule (A)
    EXPECT_NEAR(last[17], 0.5 * 9.81, 1e-6);  // fn
    EXPECT_NEAR(last[21], gap, 1e-9);
    EXPECT_NEAR(last[8], 0.2 * k, 1e-9);  // pax: the segment's ends
    EXPECT_EQ(last[22], k);               // part
    EXPECT_NEAR(last[13], 0.0, 1e-12);    // pbz: the box's top face
  }
}

TEST(ShapePairScene, BadInputIsReportedAtFileLineColumnNamingTheField) {
  auto expect = [](const std::string& text, const std::string& location, const std::string& what) {
    const std::string message = Error(text);
    EXPECT_EQ(message.rfind(location + ": ", 0), 0u) << "message: " << message;
    EXPECT_NE(message.find(what), std::string::npos) << "message: " << message;
  };
  expect(kScene + "contact:\n  exclude: [[a, c]]\n", "bad.yaml:12:17: contact.exclude[0][1]",
         "undefined obstacle 'c' (nor a body)");
  expect(kScene + "contact:\n  exclude: [[a, a]]\n", "bad.yaml:12:17: contact.exclude[0][1]",
         "itself");
  expect(kScene + "contact:\n  self: maybe\n", "bad.yaml:12:9: contact.self", "");
  expect(kScene + "contact:\n  self_skip: -1\n", "bad.yaml:12:14: contact.self_skip", "");
}

}  // namespace
}  // namespace screwfem::shape_pair_scene_test
