// Settling (docs/numerics.md, "Settling and rest"): settling.csv's columns against the other
// tables, analysis.stop_at_rest ending a run at rest (a box thrown onto a plane slides to rest
// at the closed-form distance), not before the inputs stop changing, and its bad values at
// file:line:col.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "scene_error_util.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::settling_test {
namespace {

// A box of 1 kg thrown along x at 2 m/s onto a plane, mu = 0.3 (stick law, mu_s = mu_k): it
// slides d = v0^2 / (2 mu g) = 0.67958 m in t = v0 / (mu g) = 0.67958 s.
std::string Box(const std::string& analysis, const std::string& extra = "") {
  return R"(gravity: [0, 0, -9.81]
bodies:
  box:
    type: rigid
    at: [0, 0, 0.10002996]
    mass: 1
    inertia: [0.00667, 0.00667, 0.00667]
    free: true
    initial_velocity: {linear: [2, 0, 0]}
    shapes: [{type: box, center: [0, 0, 0.10002996], half_sizes: [0.1, 0.1, 0.1]}]
)" + extra +
         R"(contact:
  stiffness: 1e5
  onset: 1e-4
  friction: 0.3
  obstacles:
    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
analysis: )" +
         analysis +
         R"(
outputs:
  points:
    c: {body: box, at: [0, 0, 0.10002996]}
  interval: 0.01
  vtk: false
)";
}

double Cell(const test::Table& t, std::size_t row, const char* column) {
  const int c = t.Column(column);
  EXPECT_GE(c, 0) << column;
  return c < 0 ? NAN : t.rows[row][static_cast<std::size_t>(c)];
}

TEST(Settling, BoxSlidesToRestAndTheRunEndsThere) {
  test::ScopedDir dir("settling_box");
  const Scene s = ParseScene(
      Box("{type: dynamic, end_time: 5, step: 1e-3, stop_at_rest: {speed: 1e-3, hold: 0.1}}"),
      "box.yaml");
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const double g = 9.81, mu = 0.3, v0 = 2.0;
  const double t_stop = v0 / (mu * g), d = v0 * v0 / (2.0 * mu * g);
  // Ended at rest: the hold after the stop (the stick law's anchor catches the box within a
  // few steps of v = 0), long before end_time.
  EXPECT_GT(r.end_time, t_stop + 0.1);
  EXPECT_LT(r.end_time, t_stop + 0.1 + 0.02);
  EXPECT_NE(r.message.find("at rest at t = "), std::string::npos) << r.message;
  const std::optional<test::Json> summary = test::ParseJsonFile(dir.path() + "/summary.json");
  ASSERT_TRUE(summary.has_value());
  EXPECT_EQ(summary->Find("status")->string, "completed");
  EXPECT_DOUBLE_EQ(summary->Find("rest_time")->number, r.end_time);
  EXPECT_EQ(summary->Find("settings.stop_at_rest.speed")->number, 1e-3);
  EXPECT_EQ(summary->Find("settings.stop_at_rest.hold")->number, 0.1);
  // The distance slid: the closed form to 0.5 % (the landing's jolt and the regularised onset).
  const test::Table p = test::ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(p.well_formed) << p.problem;
  const std::size_t last = p.rows.size() - 1;
  EXPECT_DOUBLE_EQ(Cell(p, last, "t"), r.end_time);  // the state at rest is the last row
  EXPECT_NEAR(Cell(p, last, "c.x"), d, 5e-3 * d);
  // settling.csv: the same rows; sliding, its four bottom corners slip; at rest they stick,
  // slower than the criterion, the kinetic energy that of the largest speed at most.
  const test::Table st = test::ReadCsv(dir.path() + "/settling.csv");
  ASSERT_TRUE(st.well_formed) << st.problem;
  ASSERT_EQ(st.rows.size(), p.rows.size());
  const std::vector<std::string> columns = {"t",        "kinetic",  "speed",   "angular_speed",
                                            "contacts", "slipping", "overlap", "overlap_ratio"};
  EXPECT_EQ(st.columns, columns);
  const test::Table e = test::ReadCsv(dir.path() + "/energy.csv");
  ASSERT_TRUE(e.well_formed) << e.problem;
  bool sliding_row = false;
  for (std::size_t i = 0; i < st.rows.size(); ++i) {
    EXPECT_EQ(Cell(st, i, "kinetic"), Cell(e, i, "kinetic"));  // the same CalcEnergy
    const double t = Cell(st, i, "t");
    if (t > 0.1 && t < t_stop - 0.1) {
      sliding_row = true;
      EXPECT_EQ(Cell(st, i, "contacts"), 4.0) << "t = " << t;
      EXPECT_EQ(Cell(st, i, "slipping"), 4.0) << "t = " << t;
      // Speed v0 - mu g t of the centre (the box does not turn much).
      EXPECT_NEAR(Cell(st, i, "speed"), v0 - mu * g * t, 0.02) << "t = " << t;
    }
  }
  EXPECT_TRUE(sliding_row);
  EXPECT_EQ(Cell(st, last, "contacts"), 4.0);
  EXPECT_EQ(Cell(st, last, "slipping"), 0.0);
  EXPECT_LT(Cell(st, last, "speed"), 1e-3);
  EXPECT_LT(Cell(st, last, "angular_speed"), 1e-2);
  EXPECT_LT(Cell(st, last, "kinetic"), 0.5 * 1e-3 * 1e-3 + 0.5 * 0.00667 * 1e-4 * 3.0);
  // The same run without stop_at_rest goes on to end_time, through the same states.
  test::ScopedDir full("settling_box_full");
  const RunResult rf = RunScene(
      ParseScene(Box("{type: dynamic, end_time: 1, step: 1e-3}"), "box.yaml"), full.path());
  ASSERT_TRUE(rf.ok) << rf.message;
  EXPECT_DOUBLE_EQ(rf.end_time, 1.0);
  const test::Table pf = test::ReadCsv(full.path() + "/points.csv");
  for (std::size_t i = 0; i < last; ++i) EXPECT_EQ(pf.rows[i], p.rows[i]) << "row " << i;
  const std::optional<test::Json> sf = test::ParseJsonFile(full.path() + "/summary.json");
  ASSERT_TRUE(sf.has_value());
  EXPECT_EQ(sf->Find("rest_time")->kind, test::Json::Kind::kNull);
  EXPECT_EQ(sf->Find("settings.stop_at_rest")->kind, test::Json::Kind::kBool);
}

// A box at rest from the start, pushed (below its friction) by a load that rises from t = 1 s
// to 1.2 s: at rest all along, but the run may not end before the load's last breakpoint.
TEST(Settling, NotAtRestBeforeTheInputsStopChanging) {
  test::ScopedDir dir("settling_wait");
  std::string text =
      Box("{type: dynamic, end_time: 3, step: 1e-3, stop_at_rest: true}",
          "loads:\n  push: {body: box, at: [0, 0, 0.10002996], force: [1, 0, 0], frame: world,\n"
          "         profile: {type: smooth_step, t0: 1, t1: 1.2, value: 1}}\n");
  text.replace(text.find("initial_velocity: {linear: [2, 0, 0]}"), 37,
               "initial_velocity: {linear: [0, 0, 0]}");
  const RunResult r = RunScene(ParseScene(text, "wait.yaml"), dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_GE(r.end_time, 1.2 - 1e-12);
  EXPECT_LT(r.end_time, 1.2 + 2e-3);
  // It was at rest from the first steps on (the default hold, 0.1 s, long over).
  const std::size_t since = r.message.find("since t = ");
  ASSERT_NE(since, std::string::npos) << r.message;
  EXPECT_LT(std::stod(r.message.substr(since + 10)), 0.05) << r.message;
}

// A sphere pressed into a soft plane: settling.csv's overlap is the pair's -gap of
// contacts.csv, its ratio that over the radius.
TEST(Settling, OverlapIsTheDeepestGapOfContacts) {
  test::ScopedDir dir("settling_overlap");
  const std::string text = R"(gravity: [0, 0, -9.81]
bodies:
  ball: {type: rigid, at: [0, 0, 0.05], mass: 2, inertia: [0.002, 0.002, 0.002], free: true,
         shapes: [{type: sphere, center: [0, 0, 0.05], radius: 0.05}]}
contact:
  stiffness: 1e4
  onset: 1e-4
  obstacles:
    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
analysis: {type: dynamic, end_time: 0.5, step: 1e-3}
outputs: {interval: 0.05, vtk: false}
)";
  const RunResult r = RunScene(ParseScene(text, "ball.yaml"), dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table st = test::ReadCsv(dir.path() + "/settling.csv");
  const test::Table c = test::ReadCsv(dir.path() + "/contacts.csv");
  ASSERT_TRUE(st.well_formed && c.well_formed) << st.problem << c.problem;
  const std::size_t last = st.rows.size() - 1;
  // The one contact of the last row (contacts.csv: one row per active pair and time).
  const std::size_t lc = c.rows.size() - 1;
  ASSERT_EQ(Cell(c, lc, "t"), Cell(st, last, "t"));
  EXPECT_EQ(Cell(st, last, "contacts"), 1.0);
  const double gap = Cell(c, lc, "gap");
  ASSERT_LT(gap, 0.0);  // 2 kg on 1e4 N/m: about 2 mm deep
  EXPECT_EQ(Cell(st, last, "overlap"), -gap);
  EXPECT_DOUBLE_EQ(Cell(st, last, "overlap_ratio"), -gap / 0.05);
}

TEST(Settling, BadValuesAreReportedAtTheirPlace) {
  const std::string bad_speed =
      test::SceneError(Box("{type: dynamic, end_time: 1, stop_at_rest: {speed: -1}}"), "box.yaml");
  EXPECT_NE(bad_speed.find("analysis.stop_at_rest.speed"), std::string::npos) << bad_speed;
  EXPECT_EQ(bad_speed.rfind("box.yaml:", 0), 0u) << bad_speed;
  const std::string unknown =
      test::SceneError(Box("{type: dynamic, end_time: 1, stop_at_rest: {sped: 1}}"), "box.yaml");
  EXPECT_NE(unknown.find("sped"), std::string::npos) << unknown;
  EXPECT_EQ(unknown.rfind("box.yaml:", 0), 0u) << unknown;
  const std::string word =
      test::SceneError(Box("{type: dynamic, end_time: 1, stop_at_rest: maybe}"), "box.yaml");
  EXPECT_NE(word.find("analysis.stop_at_rest"), std::string::npos) << word;
  EXPECT_EQ(word.rfind("box.yaml:", 0), 0u) << word;
  const std::string statics =
      test::SceneError(Box("{type: static, stop_at_rest: true}"), "box.yaml");
  EXPECT_NE(statics.find("applies to dynamic analyses only"), std::string::npos) << statics;
  EXPECT_EQ(statics.rfind("box.yaml:", 0), 0u) << statics;
  // Set in code, checked by the run (RunScene's settings check).
  Scene s = ParseScene(Box("{type: dynamic, end_time: 1}"), "box.yaml");
  s.analysis.stop_at_rest.enabled = true;
  s.analysis.stop_at_rest.hold = -1.0;
  test::ScopedDir dir("settling_bad");
  try {
    RunScene(s, dir.path());
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("analysis.stop_at_rest.hold"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace screwfem::settling_test
