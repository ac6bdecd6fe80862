// Force elements between rod points from a scene file (docs/scene-format.md, "Body points",
// "forces"): an end given by `s` between nodes compiles onto the element's section (as a tendon
// eyelet does) and a static run gives the model built in code; an `s` off the rod is an error
// at the end's file:line:col and field.
#include <gtest/gtest.h>

#include <string>

#include "run_test_util.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/statics.h"

namespace screwfem::force_span_scene_test {
namespace {

// Line 14 is the force element's end b. The mesh as given (conform_mesh: false): the ends stay
// between nodes (with a conforming mesh they would be nodes, docs/numerics.md).
std::string SceneText(const std::string& s_b) {
  return "units: SI\ndefaults: {conform_mesh: false}\ngravity: [0, 0, 0]\npoints: {base: [0, 0, "
         "0], tip: [1, 0, 0]}\n"
         "sections:\n  s: {stiffness: [1e5, 1e5, 1e5, 1, 1, 1], "
         "inertia: [0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3]}\n"
         "bodies:\n  r: {type: soft, from: base, to: tip, section: s, elements: 4}\n"
         "joints:\n  clamp: {type: fixed, at: base, between: [ground, r]}\n"
         "forces:\n  brace:\n    a: {body: r, s: 0.1, offset: [0, 0.05, 0]}\n"
         "    b: {body: r, s: " +
         s_b +
         ", offset: [0, 0.05, 0]}\n"
         "    stiffness: 200\n    force: 5\n"
         "analysis: {type: static, load_steps: 10}\n";
}

TEST(ForceSpanScene, EndsBetweenNodesSitOnTheElementSections) {
  const Scene s = ParseScene(SceneText("0.8"), "brace.yaml");
  ASSERT_EQ(s.model.force_elements.size(), 1u);
  const ForceElement& f = s.model.force_elements[0];
  // Nodes at 0, 0.25, ...: s = 0.1 is xi 0.4 of element 0, s = 0.8 xi 0.2 of element 3.
  EXPECT_EQ(f.a.element, s.model.rods[0].first_element);
  EXPECT_NEAR(f.a.xi, 0.4, 1e-12);
  EXPECT_EQ(f.b.element, s.model.rods[0].first_element + 3);
  EXPECT_NEAR(f.b.xi, 0.2, 1e-12);
  Data d = MakeData(s.model);
  StaticOptions o = s.analysis.statics;
  const StaticResult r = SolveStatic(s.model, d, o);
  ASSERT_TRUE(r.converged) << r.message;

  ModelBuilder b;
  b.SetConformMesh(false);
  const RodId rod =
      b.AddStraightRod("r", Vec3::Zero(), Vec3::UnitX(), 4,
                       Section::FromDiagonals((Vec6() << 1e5, 1e5, 1e5, 1, 1, 1).finished()));
  b.FixNode(b.RodNodes(RodId(0)).front());
  ForceElement fe;
  fe.name = "brace";
  fe.a = {kGround, Vec3(0, 0.05, 0)};
  fe.a.rod = rod;
  fe.a.arc_length = 0.1;
  fe.b = fe.a;
  fe.b.arc_length = 0.8;
  fe.stiffness = 200.0;
  fe.actuator = Profile::Constant(5.0);
  b.AddForceElement(fe);
  const Model m = b.Build();
  Data dm = MakeData(m);
  StaticOptions om;
  om.load_steps = 10;
  ASSERT_TRUE(SolveStatic(m, dm, om).converged);
  const Vec3 tip = d.H[static_cast<std::size_t>(s.model.rods[0].nodes.back())].x;
  const Vec3 tip_code = dm.H[static_cast<std::size_t>(m.rods[0].nodes.back())].x;
  EXPECT_LT((tip - tip_code).norm(), 1e-9);
  // The actuator's 5 N, ramped by the load steps, curls the rod towards the ends' side
  // (measured tip y 0.0809 m); the spring resists the shortening (length 0.6930 m, force
  // 3.6032 N).
  EXPECT_GT(tip.y(), 0.05) << tip.transpose();
  const LineForceState state = CalcForceElementState(s.model, d, 0);
  EXPECT_LT(state.length, 0.7);
  EXPECT_NEAR(state.force, 5.0 + 200.0 * (state.length - 0.7), 1e-12);
  EXPECT_GT(state.force, 0.0);
}

TEST(ForceSpanScene, ArcLengthOffTheRodIsAnErrorAtTheEnd) {
  try {
    ParseScene(SceneText("1.5"), "brace.yaml");
    ADD_FAILURE() << "an end off the rod was accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("brace.yaml:14:8: forces.brace.b: end: arc length 1.5 m is off soft "
                            "body 'r' (length 1 m)",
                            0),
              0u)
        << message;
  }
}

}  // namespace
}  // namespace screwfem::force_span_scene_test
