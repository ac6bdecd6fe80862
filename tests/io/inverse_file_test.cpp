// Inverse statics from a targets file (io/inverse_file.h, `screwfem inverse`): the
// three-tendon finger reaches targets that are tips of equilibria to 1e-8 m within its bounds,
// an unreachable target is reported with its nearest equilibrium (inverse.csv on disk), and
// the file's errors carry FILE:LINE:COL.
#include "screwfem/io/inverse_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/model/errors.h"

namespace screwfem::inverse_file_test {
namespace {

const std::string kFinger = std::string(SCREWFEM_SOURCE_DIR) + "/examples/tendon/finger3.yaml";

// The tip of the finger's equilibrium at tensions t1, t2, t3.
Vec3 TipAt(const Scene& scene, double t1, double t2, double t3) {
  Data d = MakeData(scene.model);
  d.inputs << t1, t2, t3;
  EXPECT_TRUE(SolveStatic(scene.model, d, scene.analysis.statics).converged);
  return d.H[static_cast<std::size_t>(scene.model.rods[0].nodes.back())].x;
}

std::string Point(const Vec3& x) {
  std::ostringstream s;
  s.precision(17);
  s << "[" << x(0) << ", " << x(1) << ", " << x(2) << "]";
  return s.str();
}

std::vector<std::vector<double>> ReadCsv(const std::string& path, std::string* header) {
  std::ifstream in(path);
  std::getline(in, *header);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<double> row;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST(InverseFile, FingerReachesEquilibriumTipsAndReportsAnUnreachableTarget) {
  const Scene scene = LoadScene(kFinger);
  const std::vector<Vec3> tips = {TipAt(scene, 20.0, 0.0, 10.0), TipAt(scene, 5.0, 30.0, 0.0)};
  const std::string text =
      "parameters:\n"
      "  - {input: t1, lower: 0, upper: 40}\n"
      "  - {input: t2, lower: 0, upper: 40}\n"
      "  - {input: t3, lower: 0, upper: 40}\n"
      "targets:\n"
      "  - {tip: " +
      Point(tips[0]) +
      "}\n"
      "  - {tip: " +
      Point(tips[1]) +
      "}\n"
      "  - {tip: [0, 0, -1.2]}\n";
  const InverseFile f = ParseInverseFile(text, "targets.yaml", scene);
  ASSERT_EQ(f.solves.size(), 3u);
  ASSERT_EQ(f.names, (std::vector<std::string>{"input t1", "input t2", "input t3"}));
  const test::ScopedDir dir("inverse_file");
  const InverseRunResult r = RunInverseFile(scene, f, dir.path());
  EXPECT_EQ(r.reached, 2);
  EXPECT_EQ(r.unreachable, 1);
  EXPECT_NE(r.message.find("target 2: the targets are not reached: the nearest equilibrium "
                           "within the bounds is"),
            std::string::npos)
      << r.message;
  std::string header;
  const auto rows = ReadCsv(dir.path() + "/inverse.csv", &header);
  EXPECT_EQ(header, "target,reached,distance,input_t1,input_t2,input_t3,tip_x,tip_y,tip_z");
  ASSERT_EQ(rows.size(), 3u);
  for (int k = 0; k < 2; ++k) {
    const std::vector<double>& row = rows[static_cast<std::size_t>(k)];
    EXPECT_EQ(row[1], 1.0);
    EXPECT_LT(row[2], 1e-8);
    for (int i = 3; i < 6; ++i) EXPECT_TRUE(row[i] >= 0.0 && row[i] <= 40.0);
    EXPECT_LT((Vec3(row[6], row[7], row[8]) - tips[static_cast<std::size_t>(k)]).norm(), 1e-8);
  }
  // The unreachable target: the nearest equilibrium, its tip and its distance.
  const std::vector<double>& far = rows[2];
  EXPECT_EQ(far[1], 0.0);
  EXPECT_GT(far[2], 0.1);
  EXPECT_NEAR((Vec3(far[6], far[7], far[8]) - Vec3(0, 0, -1.2)).norm(), far[2], 1e-9);
}

std::string ErrorOf(const std::string& text, const Scene& scene) {
  try {
    ParseInverseFile(text, "t.yaml", scene);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(InverseFile, ErrorsNameFileLineAndColumn) {
  const Scene scene = LoadScene(kFinger);
  EXPECT_EQ(ErrorOf("parameters:\n  - {tendon: q}\ntargets:\n  - {tip: [1, 0, 0]}\n", scene),
            "t.yaml:2:14: parameters[0].tendon: the scene has no tendon 'q' (known: a, b, c)");
  EXPECT_EQ(ErrorOf("parameters:\n  - {input: t1}\ntargets:\n  - {tipp: [1, 0, 0]}\n", scene),
            "t.yaml:4:6: targets[0].tipp: the scene has no point 'tipp' (its outputs.points) "
            "(did you mean 'tip'?)");
  EXPECT_EQ(ErrorOf("parameters:\n  - {input: t1, lower: 3, upper: 1}\ntargets:\n  - {tip: [1, "
                    "0, 0]}\n",
                    scene),
            "t.yaml:2:34: parameters[0].upper: must be >= lower");
  EXPECT_EQ(
      ErrorOf("parameters:\n  - {input: t1, tendon: a}\ntargets:\n  - {tip: [1, 0, 0]}\n", scene),
      "t.yaml:2:5: parameters[0]: give exactly one of input, tendon, actuator or joint");
}

}  // namespace
}  // namespace screwfem::inverse_file_test
