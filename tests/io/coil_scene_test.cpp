// The coiling example (examples/contact/coil.yaml; issue 16, item 7): a free rod dropped onto a
// ground plane with friction while a programmed rest curvature kappa_0 about the vertical rises
// curls into a coil of radius 1/kappa_0, to the bending that friction can hold,
// mu w L^2 / (8 EI); once it rests, the normal forces carry its weight and the friction forces
// cancel; after the actuation stops, the energy never increases (friction and the contact
// damping only dissipate).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::coil_scene_test {
namespace {

const std::string kCoil = std::string(SCREWFEM_SOURCE_DIR) + "/examples/contact/coil.yaml";

// The circle through points (x_i, y_i) in the least-squares sense of x^2 + y^2 + D x + E y + F
// (Kasa's fit): centre and radius.
void FitCircle(const std::vector<Vec3>& p, Vec3* centre, double* radius) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Vec3& q : p) {
    const Eigen::Vector3d v(q.x(), q.y(), 1.0);
    A += v * v.transpose();
    b -= v * (q.x() * q.x() + q.y() * q.y());
  }
  const Eigen::Vector3d s = A.ldlt().solve(b);
  *centre = Vec3(-0.5 * s(0), -0.5 * s(1), 0.0);
  *radius = std::sqrt(centre->x() * centre->x() + centre->y() * centre->y() - s(2));
}

TEST(CoilScene, RodCoilsToTheRestCurvatureRadiusAndRestsOnItsWeight) {
  test::ScopedDir dir("coil_scene");
  const Scene scene = LoadScene(kCoil, {"analysis.end_time=1.6", "outputs.interval=0.02"});
  const RunResult r = RunScene(scene, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const Model& m = scene.model;
  // The scene's values: kappa_0, rod length, weight per length, EI, friction.
  const double kappa = 5.5, L = 1.0, radius = 0.01;
  const double w = 1100.0 * M_PI * radius * radius * 9.81;
  const double EI = 1e8 * M_PI * std::pow(radius, 4) / 4.0;
  ASSERT_EQ(m.rods.size(), 1u);
  EXPECT_NEAR(m.rods[0].section.stiffness(4), EI, 1e-9 * EI);  // the section is as assumed
  EXPECT_EQ(m.contact.friction, 0.3);

  const test::Table c = test::ReadCsv(dir.path() + "/contacts.csv");
  ASSERT_TRUE(c.well_formed) << c.problem;
  const double t_end = c.rows.back()[0];
  EXPECT_NEAR(t_end, 1.6, 1e-12);
  std::vector<Vec3> points;
  double fn = 0.0;
  Vec3 ft = Vec3::Zero();
  for (const std::vector<double>& row : c.rows) {
    if (row[0] != t_end) continue;
    points.emplace_back(row[5], row[6], row[7]);
    fn += row[11];
    ft += Vec3(row[12], row[13], row[14]);
    EXPECT_GT(row[15], 0.0);  // no penetration: the gap is inside the onset, above zero
    EXPECT_LT(row[15], m.contact.onset);
  }
  // Every node sphere rests on the ground; the normal forces carry the weight w L, and the
  // friction forces, which hold what is left of the bending, cancel.
  ASSERT_EQ(points.size(), m.rods[0].nodes.size());
  EXPECT_NEAR(fn, w * L, 1e-5 * w * L);
  EXPECT_LT(ft.norm(), 1e-5 * w * L);
  // A circle of radius 1 / kappa_0 (the rod's stress-free shape), up to the curvature friction
  // can hold: |1/R - kappa_0| <= mu w L^2 / (8 EI).
  Vec3 centre;
  double R = 0.0;
  FitCircle(points, &centre, &R);
  const double held = m.contact.friction * w * L * L / (8.0 * EI);
  EXPECT_LT(std::abs(1.0 / R - kappa), held) << "R = " << R;
  EXPECT_LT(held, 0.03 * kappa);  // the bound (0.16 1/m) is tight enough to test the coil
  for (const Vec3& q : points) EXPECT_NEAR((q - centre).norm(), R, 2e-3 * R);
  // The coil's angle: the length wraps L R^-1 around the centre (the ends' angle, 2 pi - L / R
  // apart, measured the short way round; the stick law holds the coil where friction stopped it,
  // at 1/R within the bound above of kappa_0).
  const Vec3 a = points.front() - centre, b = points.back() - centre;
  EXPECT_NEAR(std::atan2(a.cross(b).norm(), a.dot(b)), 2.0 * M_PI - L / R, 0.005);
  EXPECT_NEAR(std::atan2(a.cross(b).norm(), a.dot(b)), 2.0 * M_PI - L * kappa, 0.03);

  // After the curvature stops rising (1.1 s), the energy (with the stick law's anchors) never
  // increases beyond round-off.
  const test::Table e = test::ReadCsv(dir.path() + "/energy.csv");
  ASSERT_TRUE(e.well_formed) << e.problem;
  const int total = e.Column("total");
  ASSERT_GE(total, 0);
  double previous = INFINITY, rise = -INFINITY;
  for (const std::vector<double>& row : e.rows) {
    if (row[0] < 1.1) continue;
    const double E = row[static_cast<std::size_t>(total)];
    rise = std::max(rise, E - previous);
    previous = E;
  }
  EXPECT_LT(rise, 1e-15);
}

}  // namespace
}  // namespace screwfem::coil_scene_test
