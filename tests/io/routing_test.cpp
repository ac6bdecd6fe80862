// Routing helpers (docs/scene-format.md, "Routing helpers"; build/routing.h): a tendon's eyelets
// along a rod by rule expand to the same eyelets as the long form, bit for bit, in a scene and
// through the C++ builder; every k-th node keeps the last one; a helix turns its offset by
// 2 pi per pitch of arc length; bad routes are errors at the route's line.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/build/routing.h"
#include "scene_error_util.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

namespace screwfem::routing_test {
namespace {

// A 1 m finger of 8 elements clamped at its base; `tendon` is its tendons: section.
std::string Finger(const std::string& tendon) {
  return R"(points: {base: [0, 0, 0], tip: [1, 0, 0]}
sections: {s: {stiffness: [1e5, 1e5, 1e5, 1, 1, 1], inertia: [0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3]}}
bodies:
  finger: {type: soft, from: base, to: tip, section: s, elements: 8}
joints:
  clamp: {type: fixed, at: base, between: [ground, finger]}
tendons:
)" + tendon;
}

void ExpectSameEyelets(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.model.tendons.size(), 1u);
  ASSERT_EQ(b.model.tendons.size(), 1u);
  const std::vector<BodyPoint>& ea = a.model.tendons[0].eyelets;
  const std::vector<BodyPoint>& eb = b.model.tendons[0].eyelets;
  ASSERT_EQ(ea.size(), eb.size());
  for (std::size_t i = 0; i < ea.size(); ++i) {
    EXPECT_EQ(ea[i].node, eb[i].node) << i;
    EXPECT_EQ(ea[i].offset, eb[i].offset) << i;  // bit for bit
    EXPECT_EQ(ea[i].rod, eb[i].rod) << i;
  }
  EXPECT_EQ(a.model.tendons[0].reference_length, b.model.tendons[0].reference_length);
}

TEST(Routing, EveryNodeEqualsTheLongFormBitForBit) {
  std::string long_form = "  flexor:\n    tension: 50\n    eyelets:\n";
  for (int i = 0; i <= 8; ++i)
    long_form +=
        "      - {body: finger, s: " + std::to_string(0.125 * i) + ", offset: [0, 0.02, 0]}\n";
  const Scene a = ParseScene(Finger(long_form), "long.yaml");
  const Scene b = ParseScene(Finger("  flexor:\n    tension: 50\n    eyelets:\n"
                                    "      - route: {body: finger, offset: [0, 0.02, 0]}\n"),
                             "route.yaml");
  ExpectSameEyelets(a, b);
  ASSERT_EQ(b.model.tendons[0].eyelets.size(), 9u);
  // The clamped base node carries the first eyelet, the tip the last.
  EXPECT_EQ(b.model.tendons[0].eyelets.front().node, b.model.rods[0].nodes.front());
  EXPECT_EQ(b.model.tendons[0].eyelets.back().node, b.model.rods[0].nodes.back());
}

TEST(Routing, EveryKthNodeFromToKeepsTheLastNodeAndMixesWithEyelets) {
  // From 0.25 to 1 every 3rd node: nodes at 0.25, 0.625 and the last, 1.0 (0.25 + 6 x 0.125 is
  // beyond the range; the node at `to` is always an eyelet). Behind an anchor on the ground.
  const Scene a = ParseScene(Finger(R"(  flexor:
    tension: 50
    eyelets:
      - {body: ground, at: [-0.1, 0.02, 0]}
      - {body: finger, s: 0.25, offset: [0, 0.02, 0.01]}
      - {body: finger, s: 0.625, offset: [0, 0.02, 0.01]}
      - {body: finger, s: 1, offset: [0, 0.02, 0.01]}
)"),
                             "long.yaml");
  const Scene b = ParseScene(Finger(R"(  flexor:
    tension: 50
    eyelets:
      - {body: ground, at: [-0.1, 0.02, 0]}
      - route: {body: finger, every: 3, from: 0.25, to: 1, offset: [0, 0.02, 0.01]}
)"),
                             "route.yaml");
  ExpectSameEyelets(a, b);
  // A range ending between nodes: its last node is the one before `to`.
  const Scene c = ParseScene(Finger(R"(  flexor:
    tension: 50
    eyelets:
      - route: {body: finger, every: 2, from: 0.1, to: 0.8}
)"),
                             "c.yaml");
  const Rod& rod = c.model.rods[0];
  const std::vector<BodyPoint>& e = c.model.tendons[0].eyelets;
  ASSERT_EQ(e.size(), 4u);  // nodes 1, 3, 5 (every 2nd from 0.125) and 6 (0.75, the last)
  EXPECT_EQ(e[0].node, rod.nodes[1]);
  EXPECT_EQ(e[1].node, rod.nodes[3]);
  EXPECT_EQ(e[2].node, rod.nodes[5]);
  EXPECT_EQ(e[3].node, rod.nodes[6]);
}

TEST(Routing, HelixTurnsTheOffsetOncePerPitch) {
  const Scene s = ParseScene(Finger(R"(  spiral:
    length: 1
    eyelets:
      - route: {body: finger, offset: [0, 0, 0], helix: {radius: 0.02, pitch: 0.5, phase: pi/2}}
)"),
                             "helix.yaml");
  const std::vector<BodyPoint>& e = s.model.tendons[0].eyelets;
  ASSERT_EQ(e.size(), 9u);
  for (std::size_t i = 0; i < e.size(); ++i) {
    const double a = std::numbers::pi / 2 + 2 * std::numbers::pi * (0.125 * i) / 0.5;
    EXPECT_NEAR(e[i].offset.x(), 0.0, 1e-18);
    EXPECT_NEAR(e[i].offset.y(), 0.02 * std::cos(a), 1e-15) << i;
    EXPECT_NEAR(e[i].offset.z(), 0.02 * std::sin(a), 1e-15) << i;
  }
  // Two full turns over the metre: the first and the last offsets coincide, and the quarter
  // turn at s = 0.125 puts the tendon on section axis -2.
  EXPECT_NEAR((e.front().offset - e.back().offset).norm(), 0.0, 1e-15);
  EXPECT_NEAR(e[1].offset.y(), -0.02, 1e-15);
  // The tendon's reference length: 8 chords of the helix r = 0.02 around the axis.
  const double chord =
      std::sqrt(0.125 * 0.125 + 2 * 0.02 * 0.02 * (1 - std::cos(std::numbers::pi / 2)));
  EXPECT_NEAR(s.model.tendons[0].reference_length, 8 * chord, 1e-12);
}

TEST(Routing, TheBuilderFunctionGivesTheSceneEyelets) {
  ModelBuilder b;
  const int rod = b.AddStraightRod("finger", Vec3::Zero(), Vec3(1, 0, 0), 8,
                                   Section::FromDiagonals(Vec6::Ones()));
  RodRoute r;
  r.rod = rod;
  r.every = 3;
  r.from = 0.25;
  r.to = 1.0;
  r.offset = Vec3(0, 0.02, 0.01);
  const std::vector<BodyPoint> e = RouteAlongRod(b, r);
  ASSERT_EQ(e.size(), 3u);
  const Rod& m = b.model().rods[static_cast<std::size_t>(rod)];
  EXPECT_EQ(e[0].node, m.nodes[2]);
  EXPECT_EQ(e[1].node, m.nodes[5]);
  EXPECT_EQ(e[2].node, m.nodes[8]);
  for (const BodyPoint& p : e) EXPECT_EQ(p.offset, r.offset);
  // Errors: plain messages the scene compiler places at the route.
  auto message = [&](RodRoute bad) {
    try {
      RouteAlongRod(b, bad);
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("(no error)");
  };
  RodRoute bad = r;
  bad.every = 0;
  EXPECT_NE(message(bad).find("every: expected an integer of at least 1"), std::string::npos);
  bad = r;
  bad.to = 1.5;
  EXPECT_NE(message(bad).find("from 0.25 m to 1.5 m is not a range on the rod (length 1 m)"),
            std::string::npos)
      << message(bad);
  bad = r;
  bad.from = 0.3;
  bad.to = 0.35;
  EXPECT_NE(message(bad).find("no node lies from 0.3 m to 0.35 m"), std::string::npos);
  bad = r;
  bad.helix_radius = 0.01;
  EXPECT_NE(message(bad).find("a helical route needs a non-zero pitch"), std::string::npos);
  bad = r;
  bad.rod = 7;
  EXPECT_NE(message(bad).find("no rod 7"), std::string::npos) << message(bad);
}

std::string Error(const std::string& text) { return test::SceneError(text, "r.yaml"); }

TEST(Routing, BadRoutesAreErrorsAtTheirLine) {
  // Line 11 is the route's eyelet item (the scene's tendons: section starts at line 7).
  auto route = [](const std::string& r) {
    return Finger("  flexor:\n    tension: 50\n    eyelets:\n      - route: " + r + "\n");
  };
  EXPECT_EQ(Error(route("{body: finger, from: 0.3, to: 0.35}")),
            "r.yaml:11:9: tendons.flexor.eyelets[0]: route along 'finger': no node lies from 0.3 m "
            "to 0.35 m");
  EXPECT_EQ(Error(route("{body: finger, to: 2}")),
            "r.yaml:11:9: tendons.flexor.eyelets[0]: route along 'finger': from 0 m to 2 m is not "
            "a range on the rod (length 1 m)");
  EXPECT_EQ(Error(route("{body: finger, every: 0}")),
            "r.yaml:11:38: tendons.flexor.eyelets[0].route.every: expected an integer from 1 to "
            "100000, got '0'");
  EXPECT_EQ(Error(route("{body: finger, helix: {radius: 0.01, pitch: 0}}")),
            "r.yaml:11:60: tendons.flexor.eyelets[0].route.helix.pitch: expected a non-zero arc "
            "length per turn [m] (negative: the other hand)");
  EXPECT_EQ(Error(route("{body: finger, from: 0.5, to: 0.5}")),
            "r.yaml:11:46: tendons.flexor.eyelets[0].route.to: expected an arc length beyond "
            "'from'");
  EXPECT_EQ(Error(route("{body: fnger}")),
            "r.yaml:11:23: tendons.flexor.eyelets[0].route.body: undefined body 'fnger' (did you "
            "mean 'finger'?)");
  EXPECT_EQ(Error(route("{body: finger, evry: 2}")).substr(0, 62),
            "r.yaml:11:31: tendons.flexor.eyelets[0].route.evry: unknown ke");
  // A builder error on an eyelet of a route names the route's item (and which of its eyelets).
  EXPECT_EQ(Error(Finger("  flexor:\n    tension: 50\n    eyelets:\n"
                         "      - route: {body: finger, offset: [0, 0.02, 0]}\n"
                         "      - {body: finger, s: 1, offset: [0, 0.02, 0]}\n")),
            "r.yaml:12:9: tendons.flexor.eyelets[1]: coincides with eyelet 8 in the reference "
            "configuration (no direction between them) (eyelet 0 of this item, eyelet 9 of the "
            "tendon)");
  // A route that expands to a single eyelet is not a tendon.
  EXPECT_EQ(Error(route("{body: finger, from: 1}")),
            "r.yaml:8:3: tendons.flexor: tendon 'flexor': needs at least two eyelets (it runs "
            "between them), got 1");
}

}  // namespace
}  // namespace screwfem::routing_test
