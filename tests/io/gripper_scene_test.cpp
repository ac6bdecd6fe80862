// The gripper example (examples/gripper/gripper.yaml; issue 16, item 7 and "must show"): two
// pneumatic fingers on a driven wrist pick a ball up from the ground, lift it against gravity and
// hold it. Asserted: the ball leaves the ground and its height gain follows the wrist's travel;
// during the hold its height follows the wrist's and, under the stick law, it does not slip in
// the wrist's frame (the smooth law: it creeps at its closed-form speed); the finger-ball contact forces
// carry its weight; and with friction 0 the same fingers do not lift it (friction, not the
// geometry of the grasp, holds it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::gripper_scene_test {
namespace {

const std::string kGripper = std::string(SCREWFEM_SOURCE_DIR) + "/examples/gripper/gripper.yaml";

// The scene's values: ball mass, wrist travel, start and end of the lift, the ball's index
// among the rigid bodies (after the wrist).
constexpr double kMass = 0.03, kGravity = 9.81, kTravel = 0.05;
constexpr double kLiftStart = 0.6, kLiftEnd = 1.4;
constexpr int kBall = 1;
// The hold measured: 1 s from 0.4 s after the lift.
constexpr double kHoldStart = 1.8, kHoldEnd = 2.8;

// points.csv: the ball's centre and the wrist's point at each row.
struct Track {
  std::vector<double> t;
  std::vector<Vec3> ball, wrist;
  std::size_t RowAt(double time) const {
    std::size_t best = 0;
    for (std::size_t i = 0; i < t.size(); ++i)
      if (std::abs(t[i] - time) < std::abs(t[best] - time)) best = i;
    return best;
  }
  // The ball's centre in the wrist's frame (the wrist only translates).
  Vec3 Relative(std::size_t i) const { return ball[i] - wrist[i]; }
};

Track ReadTrack(const std::string& dir) {
  const test::Table p = test::ReadCsv(dir + "/points.csv");
  EXPECT_TRUE(p.well_formed) << p.problem;
  Track out;
  const int b = p.Column("ball.x"), w = p.Column("wrist.x");
  EXPECT_GE(std::min(b, w), 0);
  if (b < 0 || w < 0) return out;
  for (const std::vector<double>& r : p.rows) {
    out.t.push_back(r[0]);
    out.ball.emplace_back(r[b], r[b + 1], r[b + 2]);
    out.wrist.emplace_back(r[w], r[w + 1], r[w + 2]);
  }
  return out;
}

// The finger-ball contacts at one output time (pair_contacts.csv).
struct Grip {
  double t = 0.0;
  int contacts = 0;
  Vec3 force = Vec3::Zero();  // their sum on the ball, world [N]
  double min_fn = INFINITY;   // the smallest normal force [N]
  double max_nz = 0.0;        // the largest |n_z| of a normal (0: horizontal)
  double share = 0.0;         // the mean friction share x = |f_t| / (mu f_n)
};

std::vector<Grip> ReadGrip(const std::string& dir, double mu) {
  const test::Table c = test::ReadCsv(dir + "/pair_contacts.csv");
  EXPECT_TRUE(c.well_formed) << c.problem;
  std::vector<Grip> out;
  const int rod_a = c.Column("rod_a"), owner_a = c.Column("owner_a"), rod_b = c.Column("rod_b"),
            owner_b = c.Column("owner_b"), nx = c.Column("nx"), fn = c.Column("fn"),
            ftx = c.Column("ftx");
  EXPECT_GE(std::min({rod_a, owner_a, rod_b, owner_b, nx, fn, ftx}), 0);
  if (std::min({rod_a, owner_a, rod_b, owner_b, nx, fn, ftx}) < 0) return out;
  for (const std::vector<double>& r : c.rows) {
    // Side A or B is the ball: a rigid body (rod flag 0) with the ball's index.
    const bool ball_a = r[rod_a] == 0.0 && r[owner_a] == kBall;
    const bool ball_b = r[rod_b] == 0.0 && r[owner_b] == kBall;
    if (!ball_a && !ball_b) continue;
    if (out.empty() || out.back().t != r[0]) {
      out.emplace_back();
      out.back().t = r[0];
    }
    Grip& g = out.back();
    const Vec3 n(r[nx], r[nx + 1], r[nx + 2]), ft(r[ftx], r[ftx + 1], r[ftx + 2]);
    const Vec3 on_a = r[fn] * n + ft;  // the force on side A; B carries its opposite
    g.force += ball_a ? on_a : Vec3(-on_a);
    g.min_fn = std::min(g.min_fn, r[fn]);
    g.max_nz = std::max(g.max_nz, std::abs(n.z()));
    g.share =
        (g.share * g.contacts + (mu > 0.0 ? ft.norm() / (mu * r[fn]) : 0.0)) / (g.contacts + 1);
    g.contacts += 1;
  }
  return out;
}

// Whether contacts.csv has a row of the ball on the ground at time t.
bool BallOnGround(const std::string& dir, double t) {
  const test::Table c = test::ReadCsv(dir + "/contacts.csv");
  EXPECT_TRUE(c.well_formed) << c.problem;
  const int rod = c.Column("rod"), owner = c.Column("owner");
  for (const std::vector<double>& row : c.rows)
    if (std::abs(row[0] - t) < 1e-9 && row[rod] == 0.0 && row[owner] == kBall) return true;
  return false;
}

// The slip the regularised friction law predicts over [t0, t1]: the integral of its creep
// speed eps_v x / sqrt(1 - x^2) at the friction share x the contacts use (docs/numerics.md,
// "Contact"; trapezoid rule over the output rows).
double CreepOfTheLaw(const std::vector<Grip>& grip, double t0, double t1, double eps_v) {
  double slip = 0.0;
  const Grip* last = nullptr;
  auto speed = [eps_v](const Grip& g) {
    return eps_v * g.share / std::sqrt(1.0 - g.share * g.share);
  };
  for (const Grip& g : grip) {
    if (g.t < t0 - 1e-9 || g.t > t1 + 1e-9) continue;
    if (last) slip += 0.5 * (g.t - last->t) * (speed(g) + speed(*last));
    last = &g;
  }
  return slip;
}

// The scene as it stands (the stick law), run to the end of the measured hold.
TEST(GripperScene, FingersLiftTheBallWithTheWristAndHoldItByFriction) {
  test::ScopedDir dir("gripper_scene");
  const Scene scene = LoadScene(kGripper, {"analysis.end_time=" + std::to_string(kHoldEnd)});
  const RunResult r = RunScene(scene, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const Model& m = scene.model;
  ASSERT_EQ(m.bodies.size(), 2u);  // the wrist, the ball
  EXPECT_EQ(m.bodies[kBall].mass, kMass);
  const double mu = m.contact.friction;
  ASSERT_GT(mu, 0.0);

  const Track k = ReadTrack(dir.path());
  ASSERT_GE(k.t.size(), 280u);
  const std::size_t lift0 = k.RowAt(kLiftStart), lift1 = k.RowAt(kLiftEnd);
  const std::size_t hold0 = k.RowAt(kHoldStart), hold1 = k.RowAt(kHoldEnd);
  ASSERT_NEAR(k.t[hold1] - k.t[hold0], 1.0, 1e-9);
  // The ball rests on the ground at the start; the closing fingers lift it off before the wrist
  // moves (their tips turn as they curl and roll it up: 2.8 mm, contact ends at 0.23 s).
  EXPECT_TRUE(BallOnGround(dir.path(), 0.0));
  EXPECT_FALSE(BallOnGround(dir.path(), k.t[lift0]));
  // The lift: the ball's height gain is the wrist's travel (measured 49.915 mm of 50 mm), and
  // from the start of the lift to the end of the hold its height follows the wrist's to
  // 0.5 mm (measured 0.24 mm: 0.085 mm lost in the lift, 0.11 mm creep in the hold).
  EXPECT_NEAR(k.wrist[lift1].z() - k.wrist[lift0].z(), kTravel, 1e-9);
  EXPECT_NEAR(k.ball[lift1].z() - k.ball[lift0].z(), kTravel, 0.5e-3);
  double follow = 0.0;
  for (std::size_t i = lift0; i < k.t.size(); ++i)
    follow = std::max(follow, std::abs(k.Relative(i).z() - k.Relative(lift0).z()));
  EXPECT_LT(follow, 0.5e-3);
  // The slip over 1 s of hold, the ball's centre in the wrist's frame: below the 1 mm
  // (measured 0.112 mm).
  const Vec3 slip = k.Relative(hold1) - k.Relative(hold0);
  EXPECT_LT(slip.norm(), 1e-3) << "slip " << slip.transpose();

  // The contacts during the hold: two, horizontal normals (measured |n_z| <= 0.0037), and the
  // fingers' forces carry the ball's weight (the wrist rests, the ball creeps at a constant
  // speed; measured to 2.6e-7 m g, the horizontal components cancelling to 3e-13 N).
  const std::vector<Grip> grip = ReadGrip(dir.path(), mu);
  double fn = INFINITY;
  int rows = 0;
  for (const Grip& g : grip) {
    if (g.t < k.t[hold0] - 1e-9 || g.t > k.t[hold1] + 1e-9) continue;
    ++rows;
    EXPECT_EQ(g.contacts, 2) << "t = " << g.t;
    EXPECT_NEAR(g.force.z(), kMass * kGravity, 1e-5 * kMass * kGravity) << "t = " << g.t;
    EXPECT_LT(std::hypot(g.force.x(), g.force.y()), 1e-6 * kMass * kGravity) << "t = " << g.t;
    EXPECT_LT(g.max_nz, 0.01) << "t = " << g.t;
    fn = std::min(fn, g.min_fn);
  }
  EXPECT_EQ(rows, 101);
  // The stick law (the default; docs/numerics.md, "Stick friction"): with horizontal normals
  // the weight is friction's alone, each contact using the share m g / (2 mu f_n) of its
  // friction, and the contacts stick: the ball does not move in the wrist's frame over the hold
  // (measured 2e-16 m; the smooth law crept 0.11 mm, the test below).
  EXPECT_LT(kMass * kGravity / (2.0 * mu * fn), 0.5);
  EXPECT_LT(slip.norm(), 1e-9);
}

// The scene with the smooth law (contact.friction_law=smooth, eps_v = 3e-4 m/s): each contact
// uses the share x = m g / (2 mu f_n) of its friction (0.345), and the regularised law creeps at
// eps_v x / sqrt(1 - x^2) = 0.110 mm/s (measured slip 0.112 mm, 1.4 % above); the slip also
// matches the law integrated at the shares the contacts report (2.8 %).
TEST(GripperScene, TheSmoothLawCreepsAtItsClosedFormSpeed) {
  test::ScopedDir dir("gripper_scene_smooth");
  const Scene scene = LoadScene(
      kGripper, {"contact.friction_law=smooth", "analysis.end_time=" + std::to_string(kHoldEnd)});
  const RunResult r = RunScene(scene, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const double mu = scene.model.contact.friction, eps_v = scene.model.contact.slip_velocity;
  const Track k = ReadTrack(dir.path());
  const std::size_t hold0 = k.RowAt(kHoldStart), hold1 = k.RowAt(kHoldEnd);
  const Vec3 slip = k.Relative(hold1) - k.Relative(hold0);
  const std::vector<Grip> grip = ReadGrip(dir.path(), mu);
  double fn = INFINITY;
  for (const Grip& g : grip)
    if (g.t >= k.t[hold0] - 1e-9 && g.t <= k.t[hold1] + 1e-9) fn = std::min(fn, g.min_fn);
  const double x = kMass * kGravity / (2.0 * mu * fn);
  EXPECT_LT(x, 0.5);
  const double creep = eps_v * x / std::sqrt(1.0 - x * x);
  EXPECT_NEAR(slip.norm(), creep, 0.05 * creep) << "x = " << x;
  const double law = CreepOfTheLaw(grip, k.t[hold0], k.t[hold1], eps_v);
  EXPECT_NEAR(slip.norm(), law, 0.05 * law);
  EXPECT_LT(slip.z(), 0.0);  // down, not up
}

// With the default slip velocity eps_v = 1e-3 m/s the ball creeps faster, at the same law:
// 0.42 mm over 1 s of hold, still below 1 mm. The creep moves the contacts above the ball's
// equator (|n_z| up to 0.023), so the normals push it down, friction's share grows beyond
// m g / (2 mu f_n) and the creep speeds up (the closed form at horizontal normals, 0.37 mm,
// is 12 % short); the law at the shares the contacts report gives the slip to 2.3 %.
TEST(GripperScene, TheBallCreepsAtTheRegularisedFrictionLaw) {
  test::ScopedDir dir("gripper_scene_creep");
  const Scene scene =
      LoadScene(kGripper, {"contact.friction_law=smooth", "contact.slip_velocity=1e-3",
                           "analysis.end_time=" + std::to_string(kHoldEnd)});
  const RunResult r = RunScene(scene, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const Track k = ReadTrack(dir.path());
  ASSERT_GE(k.t.size(), 280u);
  const std::size_t hold0 = k.RowAt(kHoldStart), hold1 = k.RowAt(kHoldEnd);
  const double slip = (k.Relative(hold1) - k.Relative(hold0)).norm();
  EXPECT_LT(slip, 1e-3);
  const std::vector<Grip> grip = ReadGrip(dir.path(), scene.model.contact.friction);
  const double law = CreepOfTheLaw(grip, k.t[hold0], k.t[hold1], 1e-3);
  EXPECT_NEAR(slip, law, 0.05 * law);
  // Three times eps_v = 3e-4 m/s, more than three times the creep (0.112 mm there).
  EXPECT_GT(slip, 3.0 * 0.112e-3);
}

// With friction 0 the same fingers, pressure and lift leave the ball on the ground: the fingers
// slide up over it (the grasp's geometry alone does not hold it).
TEST(GripperScene, WithoutFrictionTheBallStaysOnTheGround) {
  test::ScopedDir dir("gripper_scene_mu0");
  const Scene scene =
      LoadScene(kGripper, {"contact.friction=0", "analysis.end_time=" + std::to_string(kLiftEnd)});
  const RunResult r = RunScene(scene, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const Track k = ReadTrack(dir.path());
  ASSERT_GE(k.t.size(), 100u);
  EXPECT_NEAR(k.wrist.back().z() - k.wrist.front().z(), kTravel, 1e-9);
  // The ball never rises (measured: at most 5.2e-7 m above its start; the fingers sliding over it
  // press it up to 0.26 mm into the penalty layer) and rests on the ground at the end.
  double rise = -INFINITY;
  for (std::size_t i = 0; i < k.t.size(); ++i) rise = std::max(rise, k.ball[i].z() - k.ball[0].z());
  EXPECT_LT(rise, 1e-5);
  EXPECT_NEAR(k.ball.back().z(), k.ball.front().z(), 1e-5);
  EXPECT_TRUE(BallOnGround(dir.path(), k.t.back()));
}

}  // namespace
}  // namespace screwfem::gripper_scene_test
