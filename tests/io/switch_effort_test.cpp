// Actuator efforts across the drive switches of the GRM, case 1 (examples/grm/grm_rigid.yaml:
// rigid joints, soft coupler, rocker and arms), issue 14: "every actuated effort is smooth across
// the switches". The measure is the one the issue names: the second difference of each effort
// series, e_{n+1} - 2 e_n + e_{n-1}, against the series' range.
//
// What the second difference of a correct solution is (measured, docs/numerics.md "Efforts across
// drive switches"): a smooth effort has |d2| = h^2 |e''|, about 5e-5 of its range at h = 1e-3 here
// (1.1e-5 at h = 5e-4), so a threshold of 1e-6 of the range cannot be met by any smooth effort at
// h = 1e-3. A jump of a prescribed acceleration also excites the soft bodies' stiff modes (axial,
// shear and the rotation-against-shear modes, sqrt(GA / rho I) = 1414 rad/s and above: physical,
// they converge as h shrinks), and their share of the effort rings until generalized-alpha damps
// them: for 100 to 150 steps at the scene's rho_inf = 0.8, for about 10 steps at rho_inf = 0. So
// the claims checked here are, with the restart at the switches (docs/numerics.md, "Restarts at breakpoints") and
// rho_inf = 0:
//  - ten steps after a switch, J2, J3 and J5's second differences are back at the smooth level
//    (at most 1.5 times the largest before the switch) and shrink like h^2 (a step-to-step
//    oscillation would not shrink);
//  - J0, which carries the soft four-bar loop (coupler and rocker), keeps a resolved vibration
//    of that loop after the switch: its second differences stay below 3e-3 of its range.
//  - without the restart the first steps after the switch ring (index 3, the sign-alternating
//    error of docs/numerics.md, "Restarts at breakpoints"), with the restart they do not: the test can fail.
// Index 3 and the stabilised index 2 (analysis.constraints: ggl) give the same efforts here to
// two digits (measured); the test runs index 3, which is three times cheaper on this scene.
//
// Cost: four runs of 0.56 s of the rigid GRM at 4 elements per soft body, about 1 s in Release.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::switch_effort_test {
namespace {

using test::ReadCsv;
using test::ScopedDir;
using test::Table;

constexpr const char* kActuated[] = {"J0", "J2", "J3", "J5"};
constexpr double kSwitch = 0.5;  // the bang-bang drives' acceleration jumps at 0, 0.5 and 1 s
constexpr double kEnd = 0.56;

struct Efforts {
  std::vector<double> t;
  std::vector<std::vector<double>> effort;  // one series per entry of kActuated
};

// Runs the rigid GRM to kEnd with a row every step and returns the actuated joints' efforts.
Efforts RunGrm(double step, double rho_inf, bool restart, const std::string& tag) {
  const std::vector<std::string> overrides = {
      "defaults.elements=4",
      "analysis.end_time=" + std::to_string(kEnd),
      "analysis.step=" + std::to_string(step),
      "analysis.rho_inf=" + std::to_string(rho_inf),
      std::string("analysis.restart_at_breakpoints=") + (restart ? "true" : "false"),
      "outputs.interval=0",
      "outputs.vtk=false"};
  const Scene scene =
      LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/grm_rigid.yaml", overrides);
  const ScopedDir dir("switch_effort_" + tag);
  const RunResult result = RunScene(scene, dir.path());
  EXPECT_TRUE(result.ok) << result.message;
  const Table joints = ReadCsv(dir.path() + "/joints.csv");
  EXPECT_TRUE(joints.well_formed) << joints.problem;
  Efforts out;
  const int ct = joints.Column("t");
  EXPECT_GE(ct, 0);
  for (const auto& row : joints.rows) out.t.push_back(row[static_cast<std::size_t>(ct)]);
  for (const char* name : kActuated) {
    const int c = joints.Column(std::string(name) + ".effort");
    EXPECT_GE(c, 0) << name;
    std::vector<double> e;
    for (const auto& row : joints.rows)
      e.push_back(c >= 0 ? row[static_cast<std::size_t>(c)] : NAN);
    out.effort.push_back(std::move(e));
  }
  return out;
}

// Largest |e_{n+1} - 2 e_n + e_{n-1}| over the rows n with t_n in (from, to), divided by the
// range of the whole series.
double MaxSecondDifference(const Efforts& r, std::size_t joint, double from, double to) {
  const std::vector<double>& e = r.effort[joint];
  const auto [lo, hi] = std::minmax_element(e.begin(), e.end());
  const double range = *hi - *lo;
  double worst = 0.0;
  for (std::size_t n = 1; n + 1 < e.size(); ++n)
    if (r.t[n] > from && r.t[n] < to)
      worst = std::max(worst, std::abs(e[n + 1] - 2.0 * e[n] + e[n - 1]));
  return worst / range;
}

TEST(SwitchEfforts, SmoothTenStepsAfterASwitchWithRestartsAndFullNumericalDamping) {
  constexpr double h = 1e-3;
  const Efforts coarse = RunGrm(h, 0.0, true, "coarse");
  const Efforts fine = RunGrm(h / 2, 0.0, true, "fine");
  ASSERT_EQ(coarse.t.size(), 561u);
  ASSERT_EQ(fine.t.size(), 1121u);
  const double after = kSwitch + 10 * h;  // the soft bodies' stiff modes are damped by then
  for (std::size_t j = 0; j < std::size(kActuated); ++j) {
    SCOPED_TRACE(kActuated[j]);
    const double before_coarse = MaxSecondDifference(coarse, j, 0.1, kSwitch - 1.5 * h);
    const double after_coarse = MaxSecondDifference(coarse, j, after, kEnd);
    const double after_fine = MaxSecondDifference(fine, j, after, kEnd);
    std::printf(
        "%s: max |d2| / range before the switch %.2e, from 10 steps after it %.2e (h) "
        "and %.2e (h / 2)\n",
        kActuated[j], before_coarse, after_coarse, after_fine);
    // Before the switch every effort is smooth: |d2| = h^2 |e''| (measured 2e-5 to 7e-5).
    EXPECT_LT(before_coarse, 1e-4);
    if (std::string(kActuated[j]) == "J0") {
      // The soft four-bar loop's vibration (measured 1.9e-3 at h, 1.2e-3 at h / 2).
      EXPECT_LT(after_coarse, 3e-3);
      EXPECT_LT(after_fine, 3e-3);
      continue;
    }
    // Measured after / before: 1.15 (J2), 0.58 (J3), 0.95 (J5); h / (h/2): 4.0, 4.0, 4.0.
    EXPECT_LT(after_coarse, 1.5 * before_coarse);
    EXPECT_GT(after_coarse / after_fine, 3.0);
    EXPECT_LT(after_coarse / after_fine, 5.0);
  }
}

// Without the restart the integrator carries its auxiliary acceleration across the jump and
// the first steps after it ring (docs/numerics.md, "Restarts at breakpoints"); measured at rho_inf = 0.8 over the ten
// steps after the first: |d2| 0.26 (J0), 0.19, 0.12, 0.052 (J5) of the range without the
// restart, 0.042, 0.034, 0.032, 0.0047 with it (the soft bodies' stiff modes, which rho_inf =
// 0.8 damps slowly).
TEST(SwitchEfforts, RestartRemovesTheRingingOfTheAuxiliaryAcceleration) {
  constexpr double h = 1e-3;
  const Efforts with = RunGrm(h, 0.8, true, "restart");
  const Efforts without = RunGrm(h, 0.8, false, "no_restart");
  for (std::size_t j = 0; j < std::size(kActuated); ++j) {
    SCOPED_TRACE(kActuated[j]);
    const double a = MaxSecondDifference(with, j, kSwitch + 1.5 * h, kSwitch + 10 * h);
    const double b = MaxSecondDifference(without, j, kSwitch + 1.5 * h, kSwitch + 10 * h);
    EXPECT_GT(b, 2.5 * a);  // measured 6.1, 5.7, 3.7, 11
  }
}

}  // namespace
}  // namespace screwfem::switch_effort_test
