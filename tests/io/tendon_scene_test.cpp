// Tendons and force elements from a scene file (docs/scene-format.md, "tendons", "forces"):
// the example examples/tendon/finger.yaml compiles to the model it describes, a static run
// curls the finger into the eyelet model's arc, and a run writes tendons.csv and forces.csv
// with the states the kernels compute, and draws both in the ParaView frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "run_test_util.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/statics.h"

namespace screwfem::tendon_scene_test {
namespace {

const std::string kFinger = std::string(SCREWFEM_SOURCE_DIR) + "/examples/tendon/finger.yaml";

TEST(TendonScene, FingerExampleCompilesEyeletsOnNodesWithTheirOffsets) {
  const Scene s = LoadScene(kFinger);
  ASSERT_EQ(s.model.tendons.size(), 1u);
  const Tendon& t = s.model.tendons[0];
  EXPECT_EQ(t.name, "flexor");
  ASSERT_EQ(t.eyelets.size(), 9u);
  EXPECT_EQ(s.model.tendon_segments.size(), 8u);
  const Rod& rod = s.model.rods[0];
  for (std::size_t k = 0; k < t.eyelets.size(); ++k) {
    EXPECT_EQ(t.eyelets[k].node, rod.nodes[k]);
    EXPECT_EQ(t.eyelets[k].offset, Vec3(0, 0.02, 0));
  }
  ASSERT_EQ(s.model.force_elements.size(), 1u);
  const ForceElement& f = s.model.force_elements[0];
  EXPECT_EQ(f.a.node, kGround);
  EXPECT_EQ(f.a.offset, Vec3(1, -0.5, 0));
  EXPECT_EQ(f.b.node, rod.nodes.back());
  EXPECT_DOUBLE_EQ(f.rest_length, 0.5);  // the reference distance
  EXPECT_EQ(f.stiffness, 0.5);
}

TEST(TendonScene, StaticFingerWithoutTheSpringCurlsIntoTheEyeletModelsArc) {
  const Scene s = LoadScene(
      kFinger, {"analysis.type=static", "analysis.load_steps=40", "forces.tip_spring.stiffness=0"});
  Data d = MakeData(s.model);
  StaticOptions o = s.analysis.statics;
  const StaticResult r = SolveStatic(s.model, d, o);
  ASSERT_TRUE(r.converged) << r.message;
  // 8 elements: the values of tests/validation/tendon_test.cpp (docs/numerics.md T4.3).
  const Vec3 tip = d.H[static_cast<std::size_t>(s.model.rods[0].nodes.back())].x;
  EXPECT_NEAR(tip.x(), 0.820295, 2e-6);
  EXPECT_NEAR(tip.y(), 0.484594, 2e-6);
  d.time = o.time;  // the static solution's time (the end time): the full tension
  EXPECT_EQ(CalcTendonState(s.model, d, 0).force, 50.0);
}

TEST(TendonScene, RunWritesTendonAndForceTablesAndDrawsThem) {
  test::ScopedDir dir("tendon_scene");
  const Scene s = LoadScene(kFinger, {"analysis.end_time=0.2", "outputs.interval=0.05"});
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table tendons = test::ReadCsv(dir.path() + "/tendons.csv");
  ASSERT_TRUE(tendons.well_formed) << tendons.problem;
  EXPECT_EQ(tendons.columns,
            (std::vector<std::string>{"t", "flexor.length", "flexor.rate", "flexor.tension"}));
  const test::Table forces = test::ReadCsv(dir.path() + "/forces.csv");
  ASSERT_TRUE(forces.well_formed) << forces.problem;
  EXPECT_EQ(forces.columns, (std::vector<std::string>{"t", "tip_spring.length", "tip_spring.rate",
                                                      "tip_spring.force"}));
  const test::Table points = test::ReadCsv(dir.path() + "/points.csv");
  ASSERT_EQ(tendons.rows.size(), points.rows.size());
  ASSERT_EQ(forces.rows.size(), points.rows.size());
  ASSERT_GE(tendons.rows.size(), 5u);
  // The tension follows the smooth step 50 (10u^3 - 15u^4 + 6u^5), u = t / 1 s; the tendon
  // shortens as the finger curls; the spring's force is k (l - l0) + c dl/dt.
  for (const std::vector<double>& row : tendons.rows) {
    const double u = row[0];
    EXPECT_NEAR(row[3], 50.0 * u * u * u * (10 - 15 * u + 6 * u * u), 1e-9);
  }
  EXPECT_NEAR(tendons.rows.front()[1], 1.0, 1e-12);
  EXPECT_LT(tendons.rows.back()[1], tendons.rows.front()[1]);
  EXPECT_LT(tendons.rows.back()[2], 0.0);
  for (const std::vector<double>& row : forces.rows)
    EXPECT_NEAR(row[3], 0.5 * (row[1] - 0.5) + 0.1 * row[2], 1e-12);
  // The frames hold one polyline per rod and tendon and one line per force element (the
  // joint's vertex, 9 rod nodes, 9 eyelets and the spring's 2 ends are the 21 points).
  const std::string frame = test::ReadFile(dir.path() + "/vtk/frame_00000.vtp");
  EXPECT_NE(frame.find("NumberOfLines=\"3\""), std::string::npos);
  EXPECT_NE(frame.find("NumberOfPoints=\"21\""), std::string::npos);
}

TEST(TendonScene, LengthDrivenTendonIsAConstraintRowWhoseTensionIsWritten) {
  // The finger drawn by length instead of tension: shortened by 0.01 m from 0.01 s to 0.11 s,
  // the tendon curls it; tendons.csv reports the route's length (the prescribed one while
  // taut, to the run's constraint tolerance), its rate and the tension (the multiplier, >= 0).
  const std::string yaml = R"(points: {base: [0, 0, 0], tip: [1, 0, 0]}
sections:
  finger: {stiffness: [1e5, 1e5, 1e5, 1, 1, 1], inertia: [0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3]}
bodies:
  finger: {type: soft, from: base, to: tip, section: finger, elements: 4}
joints:
  clamp: {type: fixed, at: base, between: [ground, finger]}
tendons:
  flexor:
    eyelets:
      - {body: finger, s: 0.0, offset: [0, 0.02, 0]}
      - {body: finger, s: 0.5, offset: [0, 0.02, 0]}
      - {body: finger, s: 1.0, offset: [0, 0.02, 0]}
    length: {sum: [{type: constant, value: 1}, {type: ramp, value: -0.01, t0: 0.01, t1: 0.11}]}
analysis: {type: dynamic, end_time: 0.15, step: 0.005}
outputs: {interval: 0.05}
)";
  const Scene s = ParseScene(yaml, "length.yaml");
  ASSERT_EQ(s.model.tendons.size(), 1u);
  EXPECT_EQ(s.model.tendons[0].drive, TendonDrive::kLength);
  EXPECT_EQ(s.model.tendons[0].row, s.model.nc - 1);
  test::ScopedDir dir("tendon_length_scene");
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table tendons = test::ReadCsv(dir.path() + "/tendons.csv");
  ASSERT_TRUE(tendons.well_formed) << tendons.problem;
  ASSERT_EQ(tendons.rows.size(), 4u);
  for (const std::vector<double>& row : tendons.rows) {
    const double t = row[0];
    EXPECT_NEAR(row[1], 1.0 - 0.01 * std::clamp((t - 0.01) / 0.1, 0.0, 1.0), 1e-5) << "t = " << t;
    EXPECT_GE(row[3], 0.0);
  }
  // The rate while the ramp runs: L_p's -0.1 m/s up to the velocity error of the index-3
  // iteration (the position row holds, the velocity oscillates about it by a few per cent).
  EXPECT_NEAR(tendons.rows[1][2], -0.1, 0.01);
  EXPECT_NEAR(tendons.rows[2][2], -0.1, 0.01);
  EXPECT_GT(tendons.rows.back()[3], 0.0);  // taut, holding the curl
}

TEST(TendonScene, EyeletsAtArcLengthsBetweenNodesSitOnTheElementSections) {
  // Eyelets at element midpoints (s: 0.125, 0.375, ...; nodes at 0, 0.25, ...): with
  // defaults.conform_mesh false the scene compiles them onto the elements' sections at xi = 1/2,
  // and a static run gives the tip of the same model built in code (ModelBuilder with
  // BodyPoint rod/arc_length). By default (conforming) they are nodes: 8 elements.
  test::ScopedDir dir("tendon_eyelet_scene");
  const std::string path = dir.path() + "/midpoints.yaml";
  std::ofstream(path)
      << "units: SI\ngravity: [0, 0, 0]\npoints: {base: [0, 0, 0], tip: [1, 0, 0]}\n"
         "sections:\n  s: {stiffness: [1e5, 1e5, 1e5, 1, 1, 1], "
         "inertia: [0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3]}\n"
         "bodies:\n  r: {type: soft, from: base, to: tip, section: s, elements: 4}\n"
         "joints:\n  clamp: {type: fixed, at: base, between: [ground, r]}\n"
         "tendons:\n  t:\n    eyelets:\n"
         "      - {body: r, s: 0, offset: [0, 0.02, 0]}\n"
         "      - {body: r, s: 0.125, offset: [0, 0.02, 0]}\n"
         "      - {body: r, s: 0.375, offset: [0, 0.02, 0]}\n"
         "      - {body: r, s: 0.625, offset: [0, 0.02, 0]}\n"
         "      - {body: r, s: 0.875, offset: [0, 0.02, 0]}\n"
         "      - {body: r, s: 1, offset: [0, 0.02, 0]}\n"
         "    tension: 50\n"
         "analysis: {type: static, load_steps: 20}\n";
  {
    const Scene conforming = LoadScene(path);
    EXPECT_EQ(conforming.model.conformed_nodes, 4);
    EXPECT_EQ(conforming.model.rods[0].num_elements, 8);
    for (const BodyPoint& p : conforming.model.tendons[0].eyelets) EXPECT_EQ(p.element, -1);
  }
  const Scene s = LoadScene(path, {"defaults.conform_mesh=false"});
  EXPECT_EQ(s.model.conformed_nodes, 0);
  const Tendon& t = s.model.tendons[0];
  ASSERT_EQ(t.eyelets.size(), 6u);
  EXPECT_EQ(t.eyelets[0].element, -1);
  EXPECT_EQ(t.eyelets[5].element, -1);
  for (std::size_t k = 1; k < 5; ++k) {
    EXPECT_GE(t.eyelets[k].element, 0);
    EXPECT_NEAR(t.eyelets[k].xi, 0.5, 1e-12);
  }
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
  std::vector<BodyPoint> eyelets;
  for (double a : {0.0, 0.125, 0.375, 0.625, 0.875, 1.0}) {
    BodyPoint p{kGround, Vec3(0, 0.02, 0)};
    p.rod = rod;
    p.arc_length = a;
    eyelets.push_back(p);
  }
  b.AddTendon("t", eyelets, Profile::Constant(50.0));
  const Model m = b.Build();
  Data dm = MakeData(m);
  StaticOptions om;
  om.load_steps = 20;
  ASSERT_TRUE(SolveStatic(m, dm, om).converged);
  const Vec3 tip = d.H[static_cast<std::size_t>(s.model.rods[0].nodes.back())].x;
  const Vec3 tip_code = dm.H[static_cast<std::size_t>(m.rods[0].nodes.back())].x;
  EXPECT_LT((tip - tip_code).norm(), 1e-9);
  EXPECT_GT(tip.y(), 0.3);  // curled towards the tendon
}

// A tendon of 10,000 eyelets at arc lengths along a 10,000-element rod (each eyelet walked the
// rod, with a logarithm per node: 19.6 s to check): every eyelet on the node or the element
// section at its arc length, found by binary searches (bench/check_scaling.py times them).
TEST(TendonScene, TenThousandEyeletsAlongARodAreEachAtTheirArcLength) {
  constexpr int kElements = 10000;
  std::string eyelets;
  for (int k = 1; k < kElements; ++k) {
    eyelets += k > 1 ? ", {body: arm, s: " : "{body: arm, s: ";
    eyelets += std::to_string(k) + "e-4, offset: [0, 0.005, 0]}";
  }
  eyelets += ", {body: arm, s: 0.99995, offset: [0, 0.005, 0]}";  // inside the last element
  const std::string scene =
      "points: {O: [0, 0, 0], E: [1, 0, 0]}\n"
      "materials: {m: {E: 1e6, nu: 0.45, density: 1000}}\n"
      "sections: {s: {shape: circle, radius: 0.01, material: m}}\n"
      "bodies:\n  arm: {type: soft, from: O, to: E, section: s, elements: 10000}\n"
      "joints:\n  clamp: {type: fixed, at: O, between: [ground, arm]}\n"
      "tendons:\n  t: {eyelets: [" +
      eyelets + "], tension: 1}\nanalysis: {type: static}\n";
  const Scene parsed = ParseScene(scene, "long.yaml");
  const Model& m = parsed.model;
  const Rod& rod = m.rods[0];
  const Tendon& t = m.tendons[0];
  ASSERT_EQ(t.eyelets.size(), static_cast<std::size_t>(kElements));
  for (int k = 1; k < kElements; ++k) {
    const BodyPoint& p = t.eyelets[static_cast<std::size_t>(k - 1)];
    ASSERT_EQ(p.node, rod.nodes[static_cast<std::size_t>(k)]) << k;
    ASSERT_EQ(p.element, -1) << k;
  }
  // The last one is inside the last element: the conforming mesh (the default) splits it.
  const BodyPoint& last = t.eyelets.back();
  EXPECT_EQ(m.conformed_nodes, 1);
  EXPECT_EQ(rod.num_elements, kElements + 1);
  EXPECT_EQ(last.element, -1);
  EXPECT_EQ(last.node, rod.nodes[kElements]);
  EXPECT_EQ(last.node, static_cast<int>(m.nodes.size()) - 1);  // appended
  EXPECT_EQ(m.tendon_segments.size(), static_cast<std::size_t>(kElements - 1));
}

}  // namespace
}  // namespace screwfem::tendon_scene_test
