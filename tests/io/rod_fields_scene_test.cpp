// Section strain and stress through the files of a run:
//  * rod_fields.csv (outputs.rod_fields) of a static cantilever bent by an end moment: every
//    load step, every element at its midpoint, kappa3 = s M / EI and m3 = s M at load factor s;
//    and at the rows of points.csv (true) or at an interval of its own (a number) in dynamics;
//  * a bad outputs.rod_fields value is reported at its file:line:col;
//  * the ParaView frames carry the fields at the rod nodes (point data strain and stress).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

namespace screwfem::rod_fields_scene_test {
namespace {

using test::ReadCsv;
using test::ScopedDir;
using test::Table;

// A static cantilever L = 1 m (EI3 = 2 N m^2, 5 elements) bent by an end moment M = 1 N m
// about z: kappa3 = s M / EI3 at load factor s.
const std::string kBentBeam = R"(name: bent beam
points: {root: [0, 0, 0], tip: [1, 0, 0]}
sections:
  s: {stiffness: [1e4, 1e4, 1e4, 1.5, 3, 2], inertia: [0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3]}
bodies:
  beam: {type: soft, from: root, to: tip, section: s, elements: 5}
joints:
  clamp: {type: fixed, at: root, between: [ground, beam]}
loads:
  end_moment: {body: beam, at: tip, moment: [0, 0, 1]}
analysis: {type: static, load_steps: 4}
outputs:
  points:
    tip: {body: beam, at: tip}
  rod_fields: true
  vtk: false
)";

TEST(RodFieldsScene, StaticRunRecordsEveryLoadStepAndElement) {
  const Scene scene = ParseScene(kBentBeam, "bent.yaml");
  EXPECT_TRUE(scene.outputs.rod_fields);
  EXPECT_LT(scene.outputs.rod_fields_interval, 0.0);
  const ScopedDir dir("rod_fields_static");
  const RunResult r = RunScene(scene, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const Table t = ReadCsv(dir.path() + "/rod_fields.csv");
  ASSERT_TRUE(t.well_formed) << t.problem;
  const std::vector<std::string> expected = {
      "t",      "load_factor", "rod", "s",  "gamma1", "gamma2", "gamma3", "kappa1",
      "kappa2", "kappa3",      "n1",  "n2", "n3",     "m1",     "m2",     "m3"};
  EXPECT_EQ(t.columns, expected);
  ASSERT_EQ(t.rows.size(), 4u * 5u);  // 4 load steps, 5 elements
  double error = 0.0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const std::vector<double>& row = t.rows[i];
    const double s = 0.25 * static_cast<double>(i / 5 + 1);
    EXPECT_EQ(row[0], 1.0);  // t: the static analysis' time (end_time)
    EXPECT_NEAR(row[1], s, 1e-15);
    EXPECT_EQ(row[2], 0.0);
    EXPECT_NEAR(row[3], 0.1 + 0.2 * static_cast<double>(i % 5), 1e-15);
    error = std::max(error, std::abs(row[9] - s * 0.5) / (s * 0.5));  // kappa3 = s M / EI3
    error = std::max(error, std::abs(row[15] - s) / s);               // m3 = s M
    for (const int c : {4, 5, 6, 7, 8, 10, 11, 12, 13, 14})
      EXPECT_LT(std::abs(row[static_cast<std::size_t>(c)]), 1e-9) << t.columns[c];
  }
  std::printf("rod_fields.csv, end moment: max relative error of kappa3 and m3 %.2e\n", error);
  EXPECT_LT(error, 1e-9);
  // The rows of the other tables: the same load steps.
  EXPECT_EQ(ReadCsv(dir.path() + "/points.csv").rows.size(), 4u);
}

TEST(RodFieldsScene, DynamicRunRecordsAtTheRowsOrAtItsOwnInterval) {
  const std::vector<std::string> dynamic = {"analysis.type=dynamic", "analysis.end_time=0.1",
                                            "analysis.step=1e-3", "outputs.interval=0.02",
                                            "outputs.vtk=false"};
  for (const char* setting : {"outputs.rod_fields=true", "outputs.rod_fields=0.05"}) {
    SCOPED_TRACE(setting);
    std::vector<std::string> overrides = dynamic;
    overrides.push_back(setting);
    const Scene scene = ParseScene(kBentBeam, "bent.yaml", overrides);
    const ScopedDir dir("rod_fields_dynamic");
    const RunResult r = RunScene(scene, dir.path());
    ASSERT_TRUE(r.ok) << r.message;
    const Table t = ReadCsv(dir.path() + "/rod_fields.csv");
    ASSERT_TRUE(t.well_formed) << t.problem;
    EXPECT_EQ(t.columns.size(), 15u);
    EXPECT_EQ(t.columns[1], "rod");
    const bool with_rows = std::string(setting).ends_with("true");
    const std::vector<double> times = with_rows
                                          ? std::vector<double>{0, 0.02, 0.04, 0.06, 0.08, 0.1}
                                          : std::vector<double>{0, 0.05, 0.1};
    ASSERT_EQ(t.rows.size(), 5 * times.size());
    for (std::size_t i = 0; i < t.rows.size(); ++i) {
      EXPECT_NEAR(t.rows[i][0], times[i / 5], 1e-12);
      EXPECT_NEAR(t.rows[i][2], 0.1 + 0.2 * static_cast<double>(i % 5), 1e-15);
    }
    // At rest at the start, bending afterwards (the moment is on from t = 0).
    EXPECT_EQ(t.rows[0][14], 0.0);
    EXPECT_GT(t.rows.back()[8], 0.0);
  }
}

// The 6 values per point of a point data array of an ascii frame.
std::vector<double> AsciiArray(const std::string& frame, const std::string& name) {
  const std::string tag = "Name=\"" + name + "\" NumberOfComponents=\"6\" format=\"ascii\">";
  const std::size_t at = frame.find(tag);
  if (at == std::string::npos) return {};
  std::vector<double> values;
  const char* p = frame.c_str() + at + tag.size();
  char* end = nullptr;
  for (double v = std::strtod(p, &end); end != p; v = std::strtod(p, &end)) {
    values.push_back(v);
    p = end;
  }
  return values;
}

TEST(RodFieldsScene, FramesCarryTheFieldsAtTheRodNodes) {
  // Points: the clamp's vertex, then the 6 rod nodes. At the last load step (s = 1) every
  // element has kappa3 = M / EI3 = 0.5 and m3 = M = 1, and so has every node.
  const Scene scene =
      ParseScene(kBentBeam, "bent.yaml", {"outputs.vtk=true", "outputs.vtk_format=ascii"});
  const ScopedDir dir("rod_fields_frames");
  ASSERT_TRUE(RunScene(scene, dir.path()).ok);
  const std::string frame = test::ReadFile(dir.path() + "/vtk/frame_00003.vtp");
  const std::vector<double> strain = AsciiArray(frame, "strain"),
                            stress = AsciiArray(frame, "stress");
  ASSERT_EQ(strain.size(), 6u * 7u);
  ASSERT_EQ(stress.size(), 6u * 7u);
  for (std::size_t c = 0; c < 6; ++c) EXPECT_EQ(stress[c], 0.0);  // the joint's point
  for (std::size_t point = 1; point < 7; ++point) {
    EXPECT_NEAR(strain[6 * point + 5], 0.5, 1e-12) << point;
    EXPECT_NEAR(stress[6 * point + 5], 1.0, 1e-12) << point;
    for (const std::size_t c : {0, 1, 2, 3, 4}) EXPECT_LT(std::abs(stress[6 * point + c]), 1e-9);
  }
  // Without rod_fields the frames have no such arrays.
  const Scene plain =
      ParseScene(kBentBeam, "bent.yaml",
                 {"outputs.vtk=true", "outputs.vtk_format=ascii", "outputs.rod_fields=false"});
  const ScopedDir plain_dir("rod_fields_plain_frames");
  ASSERT_TRUE(RunScene(plain, plain_dir.path()).ok);
  EXPECT_EQ(test::ReadFile(plain_dir.path() + "/vtk/frame_00003.vtp").find("strain"),
            std::string::npos);
}

TEST(RodFieldsScene, BadValueIsReportedAtItsLine) {
  for (const char* value : {"yes", "-0.1", "[0.1]"}) {
    std::string text = kBentBeam;
    const std::string key = "  rod_fields: true";
    text.replace(text.find(key), key.size(), std::string("  rod_fields: ") + value);
    std::string message = "(no error)";
    try {
      ParseScene(text, "bent.yaml");
    } catch (const InputError& e) {
      message = e.what();
    }
    EXPECT_EQ(message.rfind("bent.yaml:15:15: outputs.rod_fields: expected true, false or the "
                            "interval between rows in s (a number >= 0), got ",
                            0),
              0u)
        << message;
  }
  const Scene off = ParseScene(kBentBeam, "bent.yaml", {"outputs.rod_fields=false"});
  EXPECT_FALSE(off.outputs.rod_fields);
  const Scene every_step = ParseScene(kBentBeam, "bent.yaml", {"outputs.rod_fields=0"});
  EXPECT_TRUE(every_step.outputs.rod_fields);
  EXPECT_EQ(every_step.outputs.rod_fields_interval, 0.0);
}

}  // namespace
}  // namespace screwfem::rod_fields_scene_test
