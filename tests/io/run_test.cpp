// RunScene (io/run.h) on small scenes built in C++: the files it writes (CSV columns and rows,
// summary.json, ParaView frames), that recorded velocities and accelerations are the time
// derivatives of recorded positions and velocities, step alignment with profile breakpoints,
// static analyses and preloads, and clean ends on interruption, failure and bad input.
#include "screwfem/io/run.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::run_test {
namespace {

using test::Json;
using test::ParseJsonFile;
using test::ReadCsv;
using test::ReadFile;
using test::ScopedDir;
using test::Table;

// --- scenes ---------------------------------------------------------------------------------------

// A 0.4 m rigid link on a revolute joint about world y, released from the horizontal.
Scene Pendulum(double step = 1e-3, double end = 0.5) {
  ModelBuilder b;
  const NodeId link = b.AddNode(SE3::Identity(), "link");
  b.AddRigidBody("link", link, 0.2, Vec3(0.2, 0, 0), Vec3(1e-4, 2.7e-3, 2.7e-3).asDiagonal());
  b.AddJointAt("hinge", JointType::kRevolute, kGround, link, Vec3::Zero(), Vec3::UnitY());
  b.SetGravity(Vec3(0, 0, -9.81));
  Scene s;
  s.source = "run_test.cpp";
  s.name = "pendulum";
  s.model = b.Build();
  s.analysis.end_time = end;
  s.analysis.step = step;
  s.outputs.points = {OutputPoint{.name = "tip", .node = link, .offset = Vec3(0.4, 0, 0)}};
  s.outputs.joints = {OutputJoint{.name = "hinge", .joint = 0}};
  s.outputs.vtk_interval = 0.1;
  return s;
}

// A 1 m rod clamped at x = 0 (8 elements), loaded at the tip by a force that rises smoothly
// (C2) over [0, 0.2] s. Records the tip node and the rod point at s = 0.55 m. No gravity: its
// sudden onset at t = 0 would excite the axial and shear modes, which the step cannot resolve.
Scene Cantilever(double step = 1e-3, double end = 0.3) {
  ModelBuilder b;
  Vec6 K, M;
  K << 1e4, 1e4, 1e4, 2, 2, 2;
  M << 0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3;
  const RodId rod =
      b.AddStraightRod("rod", Vec3::Zero(), Vec3(1, 0, 0), 8, Section::FromDiagonals(K, M));
  const std::vector<NodeId> nodes = b.RodNodes(RodId(0));
  b.FixNode(nodes.front());
  PointLoad tip;
  tip.node = nodes.back();
  tip.force = Vec3(0, 0.3, -0.5);
  tip.profile = Profile::SmoothStep(0.0, 0.2);
  b.AddPointLoad(tip);
  Scene s;
  s.source = "run_test.cpp";
  s.name = "cantilever";
  s.model = b.Build();
  s.analysis.end_time = end;
  s.analysis.step = step;
  s.analysis.dynamic.rho_inf = 0.8;
  s.outputs.points = {OutputPoint{.name = "tip", .node = nodes.back()},
                      OutputPoint{.name = "mid", .rod = rod, .arc_length = 0.55}};
  s.outputs.vtk = false;
  return s;
}

// A rigid link (0.3 kg, centre of mass 0.25 m from the axis) driven about world z by a
// bang-bang profile from 0 to pi/3 over [0, 1] s: breakpoints at 0, 0.5 and 1 s.
Scene DrivenLink(double step) {
  ModelBuilder b;
  const NodeId link = b.AddNode(SE3::Identity(), "link");
  b.AddRigidBody("link", link, 0.3, Vec3(0.25, 0, 0), Vec3(1e-4, 2e-3, 2e-3).asDiagonal());
  const JointId j =
      b.AddJointAt("motor", JointType::kRevolute, kGround, link, Vec3::Zero(), Vec3::UnitZ());
  Joint& motor = b.model().joints[j];
  motor.drive = DriveKind::kPrescribed;
  motor.drive_profile = Profile::BangBang(0.0, 1.0, std::numbers::pi / 3);
  b.SetGravity(Vec3(0, 0, -9.81));
  Scene s;
  s.source = "run_test.cpp";
  s.name = "driven link";
  s.model = b.Build();
  s.analysis.end_time = 1.2;
  s.analysis.step = step;
  s.outputs.points = {OutputPoint{.name = "end", .node = link, .offset = Vec3(0.5, 0, 0)}};
  s.outputs.joints = {OutputJoint{.name = "motor", .joint = j}};
  s.outputs.vtk = false;
  return s;
}

// --- helpers --------------------------------------------------------------------------------------

// Largest difference between a recorded derivative column and the central difference of the
// recorded column it is the derivative of (rows evenly spaced), relative to the derivative's
// largest magnitude. Rows before `skip_until` (the start transient) are left out.
double DerivativeMismatch(const Table& t, const std::string& value, const std::string& rate,
                          double skip_until = 0.0) {
  const int cv = t.Column(value), cr = t.Column(rate);
  EXPECT_GE(cv, 0) << value;
  EXPECT_GE(cr, 0) << rate;
  if (cv < 0 || cr < 0) return INFINITY;
  double err = 0.0, scale = 0.0;
  for (std::size_t i = 1; i + 1 < t.rows.size(); ++i) {
    const auto& r = t.rows;
    const double dt = r[i + 1][0] - r[i - 1][0];
    scale = std::max(scale, std::abs(r[i][static_cast<std::size_t>(cr)]));
    if (r[i][0] < skip_until) continue;
    const double fd =
        (r[i + 1][static_cast<std::size_t>(cv)] - r[i - 1][static_cast<std::size_t>(cv)]) / dt;
    err = std::max(err, std::abs(fd - r[i][static_cast<std::size_t>(cr)]));
  }
  return err / scale;
}

// Largest mismatch over the x, y, z components of point P: velocity vs positions (order 1)
// or acceleration vs velocities (order 2).
double PointMismatch(const Table& t, const std::string& p, int order, double skip_until = 0.0) {
  double err = 0.0;
  for (const char* axis : {"x", "y", "z"}) {
    const std::string a(axis);
    err = std::max(err, order == 1 ? DerivativeMismatch(t, p + "." + a, p + ".v" + a, skip_until)
                                   : DerivativeMismatch(t, p + ".v" + a, p + ".a" + a, skip_until));
  }
  return err;
}

std::string LastLine(const std::string& path) {
  const std::string text = ReadFile(path);
  if (text.size() < 2) return {};
  const std::size_t start = text.rfind('\n', text.size() - 2);
  return text.substr(start == std::string::npos ? 0 : start + 1);
}

// --- columns and rows -----------------------------------------------------------------------------

TEST(RunScene, WritesTheDocumentedColumnsAndOneRowPerInterval) {
  Scene s = Pendulum();
  s.outputs.interval = 0.01;
  const ScopedDir scoped_dir("columns");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.steps, 500);
  EXPECT_DOUBLE_EQ(r.end_time, 0.5);

  const Table points = ReadCsv(dir + "/points.csv");
  ASSERT_TRUE(points.well_formed) << points.problem;
  const std::vector<std::string> expected = {"t",      "tip.x",  "tip.y",  "tip.z",  "tip.vx",
                                             "tip.vy", "tip.vz", "tip.ax", "tip.ay", "tip.az",
                                             "tip.qw", "tip.qx", "tip.qy", "tip.qz"};
  EXPECT_EQ(points.columns, expected);
  ASSERT_EQ(points.rows.size(), 51u);  // t = 0, 0.01, ..., 0.5
  for (std::size_t i = 0; i < points.rows.size(); ++i)
    EXPECT_NEAR(points.rows[i][0], 0.01 * static_cast<double>(i), 1e-12);
  // The first row is the initial configuration at rest: tip at (0.4, 0, 0), falling with g.
  EXPECT_NEAR(points.rows[0][1], 0.4, 1e-15);
  EXPECT_EQ(points.rows[0][4], 0.0);
  EXPECT_LT(points.rows[0][9], -9.81);  // a point 0.4 m out on a link with I_O = 0.0107 kg m^2

  const Table joints = ReadCsv(dir + "/joints.csv");
  ASSERT_TRUE(joints.well_formed) << joints.problem;
  EXPECT_EQ(joints.columns,
            (std::vector<std::string>{"t", "hinge.q", "hinge.qd", "hinge.qdd", "hinge.effort"}));
  ASSERT_EQ(joints.rows.size(), 51u);
  // Positive rotation about y lowers the tip (z = -0.4 sin q); a passive joint has no effort.
  for (const auto& row : joints.rows) EXPECT_EQ(row[4], 0.0);
  const auto& last_p = points.rows.back();
  const auto& last_j = joints.rows.back();
  EXPECT_NEAR(last_p[3], -0.4 * std::sin(last_j[1]), 1e-12);
  EXPECT_NEAR(last_p[1], 0.4 * std::cos(last_j[1]), 1e-12);
}

TEST(RunScene, MultiDofJointsGetOneGroupOfColumnsPerCoordinate) {
  ModelBuilder b;
  const NodeId n = b.AddNode(SE3::Translation(Vec3(0.1, 0, 0)), "ball");
  b.AddRigidBody("ball", n, 0.1, Vec3(0.1, 0, 0), 1e-4 * Mat3::Identity());
  b.AddJointAt("sph", JointType::kSpherical, kGround, n, Vec3(0.1, 0, 0));
  const NodeId m = b.AddNode(SE3::Translation(Vec3(0.3, 0, 0)), "stub");
  b.AddRigidBody("stub", m, 0.1, Vec3::Zero(), 1e-4 * Mat3::Identity());
  b.AddJointAt("weld", JointType::kFixed, n, m, Vec3(0.3, 0, 0));
  Model model = b.Build();
  std::vector<OutputJoint> joints = {{"sph", 0}, {"weld", 1}};
  const std::vector<std::string> columns = JointColumns(model, joints);
  ASSERT_EQ(columns.size(), 12u);  // 3 coordinates x (q, qd, qdd, effort); none for the weld
  EXPECT_EQ(columns[0], "sph.0.q");
  EXPECT_EQ(columns[5], "sph.1.qd");
  EXPECT_EQ(columns[11], "sph.2.effort");
}

// --- the recorded derivatives are consistent ---------------------------------------------------------

// Central differences of rows h apart differ from the derivative by h^2/6 x''' (plus the
// integrator's own O(h^2) error): halving the step divides the mismatch by about 4.
TEST(RunScene, RecordedVelocitiesAndAccelerationsAreTimeDerivativesOfThePendulum) {
  double previous[2] = {0.0, 0.0};
  for (const double h : {2e-3, 1e-3}) {
    const ScopedDir scoped_dir("pendulum_fd");
    const std::string& dir = scoped_dir.path();
    const RunResult r = RunScene(Pendulum(h, 0.5), dir);
    ASSERT_TRUE(r.ok) << r.message;
    const Table t = ReadCsv(dir + "/points.csv");
    ASSERT_TRUE(t.well_formed) << t.problem;
    const double ev = PointMismatch(t, "tip", 1), ea = PointMismatch(t, "tip", 2, 0.05);
    // Measured: 28 h^2 and 44 h^2 (h = 1e-3 and 2e-3).
    EXPECT_LT(ev, 50.0 * h * h) << "h = " << h;
    EXPECT_LT(ea, 100.0 * h * h) << "h = " << h;
    const Table j = ReadCsv(dir + "/joints.csv");
    EXPECT_LT(DerivativeMismatch(j, "hinge.q", "hinge.qd"), 50.0 * h * h);
    EXPECT_LT(DerivativeMismatch(j, "hinge.qd", "hinge.qdd", 0.05), 100.0 * h * h);
    if (previous[0] > 0.0) {
      EXPECT_GT(previous[0] / ev, 3.0) << "velocity mismatch should fall as h^2";
      EXPECT_GT(previous[1] / ea, 3.0) << "acceleration mismatch should fall as h^2";
    }
    previous[0] = ev;
    previous[1] = ea;
  }
}

TEST(RunScene, RecordedRodPointMotionIsConsistentOnACantilever) {
  double previous[2] = {0.0, 0.0};
  for (const double h : {2e-3, 1e-3}) {
    const ScopedDir scoped_dir("cantilever_fd");
    const std::string& dir = scoped_dir.path();
    const RunResult r = RunScene(Cantilever(h), dir);
    ASSERT_TRUE(r.ok) << r.message;
    const Table t = ReadCsv(dir + "/points.csv");
    ASSERT_TRUE(t.well_formed) << t.problem;
    ASSERT_EQ(t.rows.size(), static_cast<std::size_t>(std::lround(0.3 / h)) + 1);
    double ev = 0.0, ea = 0.0;
    for (const char* p : {"tip", "mid"}) {
      ev = std::max(ev, PointMismatch(t, p, 1));
      ea = std::max(ea, PointMismatch(t, p, 2, 0.02));
    }
    // Measured: 97 h^2 and 125-134 h^2.
    EXPECT_LT(ev, 200.0 * h * h) << "h = " << h;
    EXPECT_LT(ea, 300.0 * h * h) << "h = " << h;
    if (previous[0] > 0.0) {
      EXPECT_GT(previous[0] / ev, 3.0) << "velocity mismatch should fall as h^2";
      EXPECT_GT(previous[1] / ea, 3.0) << "acceleration mismatch should fall as h^2";
    }
    previous[0] = ev;
    previous[1] = ea;
    // The tip moves under the load, and the rod point lies between root and tip.
    const auto& last = t.rows.back();
    const auto at = [&](const char* c) { return last[static_cast<std::size_t>(t.Column(c))]; };
    EXPECT_LT(at("tip.z"), -0.01);
    EXPECT_GT(at("mid.x"), 0.3);
    EXPECT_LT(at("mid.x"), at("tip.x"));
  }
}

// --- step alignment and drives ---------------------------------------------------------------------

TEST(StepSchedule, InsertsBreakpointsIntoTheGridAndSnapsNearbyGridPoints) {
  const auto ends = [](const StepSchedule& s, double t) {
    std::vector<double> e;
    while (!s.Done(t)) e.push_back(t = s.Next(t));
    return e;
  };
  // 0.3 s steps with breakpoints at 0.5 (between grid points) and 0.91 (0.01 s after 0.9: the
  // grid point 0.9 moves onto it) and the end 1.0 (0.09 s after 0.91: reached in one step).
  const std::vector<double> e = ends(StepSchedule(0.0, 1.0, 0.3, {0.5, 0.91, -1.0, 2.0}), 0.0);
  const std::vector<double> expected = {0.3, 0.5, 0.6, 0.91, 1.0};
  ASSERT_EQ(e.size(), expected.size());
  for (std::size_t i = 0; i < e.size(); ++i) EXPECT_NEAR(e[i], expected[i], 1e-15) << i;
  // Grid points are start + n h, without accumulated round-off, and the end is exact.
  const std::vector<double> g = ends(StepSchedule(0.1, 0.4, 0.1, {}), 0.1);
  ASSERT_EQ(g.size(), 3u);
  EXPECT_EQ(g[0], 0.1 + 0.1);
  EXPECT_EQ(g[2], 0.4);
  // No breakpoints: the last step is shortened to end on end_time.
  EXPECT_NEAR(ends(StepSchedule(0.0, 0.25, 0.1, {}), 0.0).back(), 0.25, 0.0);
}

TEST(RunScene, PrescribedJointFollowsItsProfileWithStepsAlignedToTheAccelerationJumps) {
  const double h = 0.03;  // does not divide 0.5 s: the breakpoints need shortened steps
  Scene s = DrivenLink(h);
  const ScopedDir scoped_dir("driven");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir);
  ASSERT_TRUE(r.ok) << r.message;
  const Table t = ReadCsv(dir + "/joints.csv");
  ASSERT_TRUE(t.well_formed) << t.problem;
  const Profile& q = s.model.joints[0].drive_profile;
  bool saw_half = false, saw_one = false;
  const double inertia = 2e-3 + 0.3 * 0.25 * 0.25;  // about the axis [kg m^2]
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    saw_half = saw_half || row[0] == 0.5;
    saw_one = saw_one || row[0] == 1.0;
    if (i > 0) {
      EXPECT_LE(row[0] - t.rows[i - 1][0], (1.0 + StepSchedule::kSnap) * h + 1e-12);
    }
    EXPECT_NEAR(row[1], q(row[0]), 1e-10) << "t = " << row[0];  // exact, rheonomic
    // The actuator torque accelerates the link's inertia about the axis (gravity is along it).
    EXPECT_NEAR(row[4], inertia * row[3], 1e-8 * (1.0 + std::abs(row[4]))) << "t = " << row[0];
  }
  EXPECT_TRUE(saw_half) << "no step ends at the acceleration jump t = 0.5 s";
  EXPECT_TRUE(saw_one) << "no step ends at the acceleration jump t = 1 s";
  EXPECT_DOUBLE_EQ(t.rows.back()[0], 1.2);
  EXPECT_DOUBLE_EQ(t.rows.back()[1], std::numbers::pi / 3);

  // Without alignment the grid is kept: t = 0.5 is not a step end.
  s.analysis.align_steps = false;
  const ScopedDir scoped_dir2("driven_unaligned");
  const std::string& dir2 = scoped_dir2.path();
  ASSERT_TRUE(RunScene(s, dir2).ok);
  const Table u = ReadCsv(dir2 + "/joints.csv");
  EXPECT_TRUE(
      std::none_of(u.rows.begin(), u.rows.end(), [](const auto& row) { return row[0] == 0.5; }));
}

TEST(JointCoordinateEffort, SpringsAndDampersPushTowardsRest) {
  ModelBuilder b;
  const NodeId n = b.AddNode(SE3::Identity(), "ball");
  b.AddRigidBody("ball", n, 0.1, Vec3(0.1, 0, 0), 1e-4 * Mat3::Identity());
  b.AddJointAt("sph", JointType::kSpherical, kGround, n, Vec3::Zero());
  b.model().joints[0].stiffness.head<3>().setConstant(0.5);
  const NodeId m = b.AddNode(SE3::Translation(Vec3(1, 0, 0)), "slider");
  b.AddRigidBody("slider", m, 0.1, Vec3::Zero(), 1e-4 * Mat3::Identity());
  b.AddJointAt("slide", JointType::kPrismatic, kGround, m, Vec3(1, 0, 0), Vec3::UnitX());
  b.model().joints[1].stiffness(0) = 10.0;
  b.model().joints[1].damping(0) = 5.0;
  b.model().joints[1].rest(0) = 0.1;
  const Model model = b.Build();
  Data data = MakeData(model);
  // A rotation of 0.3 rad about one basis axis of the spherical joint: torque -K 0.3 on it.
  data.HJ[0] = ExpSE3((Vec6() << 0, 0, 0, 0.3, 0, 0).finished());
  EXPECT_NEAR(JointCoordinateEffort(model, data, 0, 0), -0.15, 1e-14);
  EXPECT_NEAR(JointCoordinateEffort(model, data, 0, 1), 0.0, 1e-14);
  // The prismatic spring-damper: -(K (q - rest) + D qd).
  const int slide = model.joints[1].coord;
  data.q_joint(slide - model.nv_nodes) = 0.3;
  data.v(slide) = -0.2;
  EXPECT_NEAR(JointCoordinateEffort(model, data, 1, 0), -(10.0 * 0.2 + 5.0 * -0.2), 1e-14);
}

// --- static analyses -------------------------------------------------------------------------------

// A static analysis records every converged load step (the path) with its load factor in a
// column after t, and a ParaView frame at each (the load factor as its time).
TEST(RunScene, StaticAnalysisRecordsEveryLoadStepWithItsLoadFactor) {
  Scene s = Cantilever();
  s.analysis.kind = AnalysisKind::kStatic;
  s.analysis.statics.time = 1.0;  // the tip load is fully on
  s.outputs.vtk = true;
  const ScopedDir scoped_dir("static");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.steps, 10);  // load steps
  for (const char* file : {"/points.csv", "/joints.csv"}) {
    const Table t = ReadCsv(dir + file);
    ASSERT_TRUE(t.well_formed) << t.problem;
    ASSERT_EQ(t.Column("load_factor"), 1) << file;
    ASSERT_EQ(t.rows.size(), 10u) << file;
    for (std::size_t i = 0; i < t.rows.size(); ++i) {
      EXPECT_EQ(t.rows[i][0], 1.0);
      EXPECT_NEAR(t.rows[i][1], 0.1 * static_cast<double>(i + 1), 1e-15);
    }
  }
  const Table t = ReadCsv(dir + "/points.csv");
  const auto tip_z = static_cast<std::size_t>(t.Column("tip.z"));
  EXPECT_LT(t.rows.back()[tip_z], -0.01);
  for (std::size_t i = 1; i < t.rows.size(); ++i) EXPECT_LT(t.rows[i][tip_z], t.rows[i - 1][tip_z]);
  for (const char* c : {"tip.vx", "tip.vz", "mid.ay", "tip.az"})
    EXPECT_EQ(t.rows.back()[static_cast<std::size_t>(t.Column(c))], 0.0) << c;
  const std::optional<Json> summary = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("settings.analysis")->string, "static");
  EXPECT_TRUE(summary->Find("static_solution.converged")->boolean);
  EXPECT_EQ(summary->Find("outputs.vtk_frames")->number, 10.0);
  // Each frame's time is its load step's load factor (all rows have the same t).
  const std::string pvd = ReadFile(dir + "/vtk/motion.pvd");
  std::size_t at = 0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    at = pvd.find("timestep=\"", at);
    ASSERT_NE(at, std::string::npos) << pvd;
    at += 10;
    EXPECT_EQ(std::strtod(pvd.c_str() + at, nullptr), t.rows[i][1]) << i;
    EXPECT_NE(pvd.find("file=\"frame_0000" + std::to_string(i) + ".vtp\"", at), std::string::npos);
  }
  EXPECT_EQ(pvd.find("timestep=\"", at), std::string::npos);  // no eleventh frame
}

TEST(RunScene, StaticPreloadStartsTheDynamicsAtEquilibrium) {
  Scene s = Cantilever(1e-3, 0.01);
  s.model.point_loads.clear();  // gravity only: the preload is the equilibrium for all t
  s.model.gravity = Vec3(0, 0, -9.81);
  s.analysis.static_preload = true;
  const ScopedDir scoped_dir("preload");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir);
  ASSERT_TRUE(r.ok) << r.message;
  const Table t = ReadCsv(dir + "/points.csv");
  ASSERT_TRUE(t.well_formed) << t.problem;
  const auto& first = t.rows.front();
  EXPECT_LT(first[static_cast<std::size_t>(t.Column("tip.z"))], -1e-3);  // sagged
  for (const char* c : {"tip.az", "mid.az", "tip.ax"})
    EXPECT_LT(std::abs(first[static_cast<std::size_t>(t.Column(c))]), 1e-6 * 9.81) << c;
  const std::optional<Json> summary = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_GT(summary->Find("static_solution.load_steps")->number, 0.0);
}

// --- summary.json ---------------------------------------------------------------------------------

TEST(RunScene, SummaryIsValidJsonWithSettingsCountsAndStatistics) {
  Scene s = Cantilever(2e-3, 0.1);
  const ScopedDir scoped_dir("summary");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir);
  ASSERT_TRUE(r.ok) << r.message;
  const std::optional<Json> j = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(j) << ReadFile(dir + "/summary.json");
  const auto number = [&](const char* path) {
    const Json* v = j->Find(path);
    EXPECT_TRUE(v && v->kind == Json::Kind::kNumber) << path;
    return v ? v->number : NAN;
  };
  EXPECT_EQ(j->Find("status")->string, "completed");
  EXPECT_EQ(j->Find("message")->string, "");
  EXPECT_EQ(j->Find("scene.name")->string, "cantilever");
  EXPECT_EQ(j->Find("settings.analysis")->string, "dynamic");
  EXPECT_EQ(number("settings.step"), 2e-3);
  EXPECT_EQ(number("settings.rho_inf"), 0.8);
  EXPECT_EQ(number("settings.increment_tolerance"), s.analysis.dynamic.increment_tolerance);
  EXPECT_EQ(number("counts.nodes"), 9.0);
  EXPECT_EQ(number("counts.free_nodes"), 8.0);
  EXPECT_EQ(number("counts.elements"), 8.0);
  EXPECT_EQ(number("counts.conformed_nodes"), 0.0);
  EXPECT_EQ(number("counts.rods"), 1.0);
  EXPECT_EQ(number("counts.rigid_bodies"), 0.0);
  EXPECT_EQ(number("counts.joints"), 0.0);
  EXPECT_EQ(number("counts.nv"), 48.0);
  EXPECT_EQ(number("counts.nc"), 0.0);
  EXPECT_EQ(number("counts.redundant_constraints"), 0.0);
  EXPECT_EQ(number("steps"), 50.0);
  EXPECT_EQ(number("steps"), static_cast<double>(r.steps));
  EXPECT_EQ(number("newton_iterations"), static_cast<double>(r.newton_iterations));
  EXPECT_GE(number("newton_iterations"), 50.0);
  EXPECT_EQ(number("max_iterations_per_step"), r.max_iterations_per_step);
  EXPECT_EQ(number("step_halvings"), 0.0);
  EXPECT_EQ(j->Find("settings.convergence")->string, "estimated");
  EXPECT_GE(number("estimated_convergences"), 0.0);
  EXPECT_LE(number("estimated_convergences"), number("steps"));
  EXPECT_EQ(number("outputs.rows"), 51.0);
  EXPECT_EQ(number("time"), 0.1);
  EXPECT_GT(number("wall_seconds"), 0.0);
  EXPECT_GT(number("real_time_factor"), 0.0);
  EXPECT_EQ(number("max_constraint_residual"), 0.0);  // no constraints
  EXPECT_EQ(j->Find("warnings")->kind, Json::Kind::kArray);
  EXPECT_EQ(j->Find("outputs.points")->array.size(), 2u);
}

TEST(RunScene, SummaryCountsConstraintsAndTheirLargestResidual) {
  const ScopedDir scoped_dir("summary_constraints");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(Pendulum(1e-3, 0.2), dir);
  ASSERT_TRUE(r.ok) << r.message;
  const std::optional<Json> j = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(j);
  EXPECT_EQ(j->Find("counts.nv")->number, 7.0);  // 6 for the node, 1 joint coordinate
  EXPECT_EQ(j->Find("counts.nc")->number, 6.0);
  EXPECT_EQ(j->Find("counts.joints")->number, 1.0);
  EXPECT_EQ(j->Find("counts.rigid_bodies")->number, 1.0);
  EXPECT_EQ(j->Find("max_constraint_residual")->number, r.max_constraint_residual);
  EXPECT_LT(r.max_constraint_residual, 1e-11);  // the constraint tolerance
}

TEST(RunScene, SummaryEscapesStringsFromTheScene) {
  Scene s = Pendulum(1e-3, 0.01);
  s.name = "a \"quoted\" name\\ with\nnewline, tab\t and \x01 control";
  s.source = "C:\\scenes\\odd \"file\".yaml";
  const ScopedDir scoped_dir("escape");
  const std::string& dir = scoped_dir.path();
  ASSERT_TRUE(RunScene(s, dir).ok);
  const std::optional<Json> j = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(j) << ReadFile(dir + "/summary.json");
  EXPECT_EQ(j->Find("scene.name")->string, s.name);
  EXPECT_EQ(j->Find("scene.source")->string, s.source);
}

// --- ParaView ---------------------------------------------------------------------------------------

TEST(RunScene, CollectionReferencesEveryFrameFileAndFramesHoldTheMechanism) {
  Scene s = Pendulum(1e-3, 0.3);
  s.outputs.interval = 0.01;
  s.outputs.vtk_interval = 0.05;
  const ScopedDir scoped_dir("vtk");
  const std::string& dir = scoped_dir.path();
  ASSERT_TRUE(RunScene(s, dir).ok);
  const std::string pvd = ReadFile(dir + "/vtk/motion.pvd");
  ASSERT_NE(pvd.find("<VTKFile type=\"Collection\""), std::string::npos);
  ASSERT_NE(pvd.find("</VTKFile>"), std::string::npos);
  int frames = 0;
  for (std::size_t at = pvd.find("file=\""); at != std::string::npos;
       at = pvd.find("file=\"", at + 1)) {
    const std::size_t start = at + 6, end = pvd.find('"', start);
    const std::string file = dir + "/vtk/" + pvd.substr(start, end - start);
    ASSERT_TRUE(std::filesystem::is_regular_file(file)) << file;
    const std::string vtp = ReadFile(file);
    EXPECT_NE(vtp.find("NumberOfPoints=\"4\" NumberOfVerts=\"2\" NumberOfLines=\"1\""),
              std::string::npos)
        << "one joint vertex and the body's inertia box, one body segment (node origin to "
           "centre of mass)";
    for (const char* name :
         {"frame_x", "frame_y", "frame_z", "velocity", "joint_id", "rod_id", "body_id"})
      EXPECT_NE(vtp.find(std::string("Name=\"") + name + "\""), std::string::npos) << name;
    EXPECT_EQ(vtp.substr(vtp.size() - 11), "</VTKFile>\n");
    ++frames;
  }
  EXPECT_EQ(frames, 7);  // t = 0, 0.05, ..., 0.3
  EXPECT_NE(pvd.find("timestep=\"0.29999999999999999\""), std::string::npos);
}

// Frame files named in motion.pvd, in order.
std::vector<std::string> CollectionFiles(const std::string& pvd) {
  std::vector<std::string> files;
  for (std::size_t at = pvd.find("file=\""); at != std::string::npos;
       at = pvd.find("file=\"", at + 1)) {
    const std::size_t start = at + 6, end = pvd.find('"', start);
    files.push_back(pvd.substr(start, end - start));
  }
  return files;
}

std::vector<std::string> FrameFilesOnDisk(const std::string& vtk_dir) {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(vtk_dir))
    if (e.path().extension() == ".vtp") files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  return files;
}

// The default outputs of a scene file without an outputs section: a 20 s pendulum (20000 steps)
// records about kDefaultOutputRows rows and kDefaultVtkFrames frames, and motion.pvd is written
// once at the end, not after every frame (which made the run quadratic: 90 s instead of 0.06).
TEST(RunScene, DefaultOutputsRecordAboutAThousandRowsAndAHundredFramesAndThePvdOnce) {
  std::string text = ReadFile(std::string(SCREWFEM_TEST_DATA_DIR) + "/pendulum.yaml");
  text = text.substr(0, text.find("outputs:"));
  const Scene s = ParseScene(text, "pendulum.yaml", {"analysis.end_time=20"});
  EXPECT_DOUBLE_EQ(s.outputs.interval, 0.02);
  EXPECT_DOUBLE_EQ(s.outputs.vtk_interval, 0.2);
  const ScopedDir scoped_dir("default_outputs");
  const std::string& dir = scoped_dir.path();
  std::atomic<int> stop{0};
  int pvd_seen_during_run = 0;
  RunOptions options;
  options.stop.flag = &stop;
  options.on_step = [&](double) {
    if (std::filesystem::exists(dir + "/vtk/motion.pvd") && ++pvd_seen_during_run > 0)
      stop = SIGINT;
  };
  const RunResult r = RunScene(s, dir, options);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(pvd_seen_during_run, 0) << "motion.pvd was written before the run ended";
  EXPECT_EQ(r.steps, 20000);
  const Table joints = ReadCsv(dir + "/joints.csv");
  ASSERT_TRUE(joints.well_formed) << joints.problem;
  EXPECT_EQ(joints.rows.size(), 1001u);  // every 20 steps
  const std::vector<std::string> listed = CollectionFiles(ReadFile(dir + "/vtk/motion.pvd"));
  EXPECT_EQ(listed.size(), 101u);  // every 200 steps
  EXPECT_EQ(listed, FrameFilesOnDisk(dir + "/vtk"));
  // Output work per step: at most one frame per 100 steps and one row per 10 steps.
  EXPECT_LE(100 * listed.size(), static_cast<std::size_t>(r.steps) + 100);
  EXPECT_LE(10 * joints.rows.size(), static_cast<std::size_t>(r.steps) + 10);
}

TEST(RunScene, CollectionOfAnInterruptedRunListsExactlyTheFramesOnDisk) {
  Scene s = Pendulum(1e-3, 0.5);
  s.outputs.vtk_interval = 0.01;
  std::atomic<int> stop{0};
  RunOptions options;
  options.stop.flag = &stop;
  options.on_step = [&](double t) {
    if (t > 0.0545) stop = SIGINT;
  };
  const ScopedDir scoped_dir("vtk_interrupted");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir, options);
  ASSERT_TRUE(r.interrupted);
  const std::vector<std::string> listed = CollectionFiles(ReadFile(dir + "/vtk/motion.pvd"));
  EXPECT_EQ(listed.size(), 6u);  // t = 0, 0.01, ..., 0.05
  EXPECT_EQ(listed, FrameFilesOnDisk(dir + "/vtk"));
  const std::optional<Json> j = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(j);
  EXPECT_EQ(j->Find("outputs.vtk_frames")->number, 6.0);
}

// --- clean ends ---------------------------------------------------------------------------------------

TEST(RunScene, StopRequestEndsTheRunWithCompleteFilesAndStatusInterrupted) {
  std::atomic<int> stop{0};
  int steps = 0;
  RunOptions options;
  options.stop.flag = &stop;
  options.on_step = [&](double) {
    if (++steps == 25) stop = SIGINT;
  };
  const ScopedDir scoped_dir("interrupted");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(Pendulum(1e-3, 0.5), dir, options);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.steps, 25);
  EXPECT_NEAR(r.end_time, 0.025, 1e-12);
  EXPECT_EQ(r.signal, SIGINT);
  EXPECT_NE(r.message.find("interrupted by SIGINT at t = 0.025"), std::string::npos) << r.message;
  for (const char* file : {"/points.csv", "/joints.csv"}) {
    const Table t = ReadCsv(dir + file);
    ASSERT_TRUE(t.well_formed) << file << ": " << t.problem;
    EXPECT_EQ(t.rows.size(), 26u) << file;  // t = 0 and 25 steps
    EXPECT_NEAR(t.rows.back()[0], 0.025, 1e-12);
  }
  const std::optional<Json> j = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(j);
  EXPECT_EQ(j->Find("status")->string, "interrupted");
  EXPECT_EQ(j->Find("message")->string, r.message);
  EXPECT_EQ(j->Find("steps")->number, 25.0);
}

// A stop request also ends static solutions and the static preload (between Newton
// iterations), as "interrupted", not "failed".
TEST(RunScene, StopRequestEndsStaticSolutionsAndPreloadsAsInterrupted) {
  for (const bool preload : {false, true}) {
    Scene s = Cantilever();
    if (preload)
      s.analysis.static_preload = true;
    else
      s.analysis.kind = AnalysisKind::kStatic;
    s.analysis.statics.time = 1.0;
    s.analysis.statics.load_steps = 1000000;  // about a minute
    s.outputs.max_rows = kMaxMaxRows;         // (a row per load step)
    int polls = 0;
    RunOptions options;
    options.stop.poll = [](void* count) { return ++*static_cast<int*>(count) > 50; };
    options.stop.context = &polls;
    const ScopedDir scoped_dir("static_interrupted");
    const RunResult r = RunScene(s, scoped_dir.path(), options);
    EXPECT_FALSE(r.ok);
    EXPECT_TRUE(r.interrupted) << r.message;
    EXPECT_EQ(polls, 51);
    EXPECT_NE(r.message.find("interrupted at load factor"), std::string::npos) << r.message;
    const std::optional<Json> j = ParseJsonFile(scoped_dir.path() + "/summary.json");
    ASSERT_TRUE(j);
    EXPECT_EQ(j->Find("status")->string, "interrupted");
    EXPECT_FALSE(j->Find("static_solution.converged")->boolean);
    EXPECT_GT(j->Find("static_solution.load_steps")->number, 0.0);
  }
}

// SIGTERM and SIGHUP (as the flag's value) end the run as "terminated", naming the signal.
TEST(RunScene, StopBySigtermEndsTheRunAsTerminatedAndNamesTheSignal) {
  std::atomic<int> stop{0};
  RunOptions options;
  options.stop.flag = &stop;
  options.on_step = [&](double t) {
    if (t > 0.0095) stop = SIGTERM;
  };
  const ScopedDir scoped_dir("terminated");
  const RunResult r = RunScene(Pendulum(1e-3, 0.5), scoped_dir.path(), options);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.signal, SIGTERM);
  EXPECT_EQ(r.message.rfind("terminated by SIGTERM at t = 0.01", 0), 0u) << r.message;
  const std::optional<Json> j = ParseJsonFile(scoped_dir.path() + "/summary.json");
  ASSERT_TRUE(j);
  EXPECT_EQ(j->Find("status")->string, "terminated");
  EXPECT_EQ(j->Find("signal")->string, "SIGTERM");
}

TEST(RunScene, SummaryReadsRunningWhileTheRunIsUnderWay) {
  std::string status;
  const ScopedDir scoped_dir("running");
  const std::string& dir = scoped_dir.path();
  RunOptions options;
  options.on_step = [&](double t) {
    if (t < 0.0015) {
      const std::optional<Json> j = ParseJsonFile(dir + "/summary.json");
      status = j ? j->Find("status")->string : "invalid";
    }
  };
  ASSERT_TRUE(RunScene(Pendulum(1e-3, 0.01), dir, options).ok);
  EXPECT_EQ(status, "running");
}

// A cantilever bent by a tip moment growing without bound: its elements pass the 2 pi a
// helical element can represent (elements/rod.h), and the step fails.
TEST(RunScene, FailedStepReportsTimeAndCauseAndKeepsEarlierRows) {
  Scene s = Cantilever(4e-3, 1.0);
  s.model.point_loads[0].force.setZero();
  s.model.point_loads[0].moment = Vec3(0, 0, 500.0);
  s.model.point_loads[0].profile = Profile::Ramp(0.0, 1.0);
  s.analysis.dynamic.max_halvings = 2;
  s.outputs.interval = 0.02;
  const ScopedDir scoped_dir("failed");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir);
  ASSERT_FALSE(r.ok);
  EXPECT_FALSE(r.interrupted);
  EXPECT_EQ(r.message.rfind("step failed at t = ", 0), 0u) << r.message;
  EXPECT_NE(r.message.find("element"), std::string::npos) << r.message;
  EXPECT_GT(r.end_time, 0.05);
  EXPECT_LT(r.end_time, 1.0);
  EXPECT_EQ(r.message.find("step failed at t = " + std::to_string(r.end_time).substr(0, 4)), 0u);
  const Table t = ReadCsv(dir + "/points.csv");
  ASSERT_TRUE(t.well_formed) << t.problem;
  EXPECT_GT(t.rows.size(), 5u) << r.message;
  EXPECT_LE(t.rows.back()[0], r.end_time + 1e-12);
  EXPECT_FALSE(LastLine(dir + "/points.csv").empty());
  const std::optional<Json> j = ParseJsonFile(dir + "/summary.json");
  ASSERT_TRUE(j);
  EXPECT_EQ(j->Find("status")->string, "failed");
  EXPECT_EQ(j->Find("message")->string, r.message);
}

TEST(RunScene, NewtonFailureAtTheFirstStepKeepsTheInitialRow) {
  Scene s = Pendulum();
  // One correction from the zero-acceleration start never converges (from the last
  // acceleration, the default start, it may).
  s.analysis.dynamic.max_iterations = 1;
  s.analysis.dynamic.predictor = Predictor::kZero;
  s.analysis.dynamic.max_halvings = 1;
  const ScopedDir scoped_dir("newton_failed");
  const std::string& dir = scoped_dir.path();
  const RunResult r = RunScene(s, dir);
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.message.rfind("step failed at t = 0 s", 0), 0u) << r.message;
  EXPECT_NE(r.message.find("Newton did not converge"), std::string::npos) << r.message;
  const Table t = ReadCsv(dir + "/points.csv");
  ASSERT_TRUE(t.well_formed) << t.problem;
  EXPECT_EQ(t.rows.size(), 1u);
}

// --- bad input -------------------------------------------------------------------------------------

TEST(RunScene, RejectsInvalidSettingsAndOutputsNamingTheField) {
  const auto message = [](const Scene& s) {
    try {
      const ScopedDir dir("bad_input");
      RunScene(s, dir.path());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no InputError");
  };
  Scene s = Pendulum();
  s.analysis.step = 0.0;
  EXPECT_NE(message(s).find("analysis.step"), std::string::npos);
  s = Pendulum();
  s.analysis.end_time = -1.0;
  EXPECT_NE(message(s).find("analysis.end_time"), std::string::npos);
  s = Pendulum();
  s.outputs.interval = -0.1;
  EXPECT_NE(message(s).find("outputs.interval"), std::string::npos);
  s = Pendulum();
  s.outputs.points[0].node = 7;
  EXPECT_NE(message(s).find("outputs.points 'tip'"), std::string::npos);
  s = Cantilever();
  s.outputs.points[1].arc_length = 1.5;
  EXPECT_NE(message(s).find("outputs.points 'mid'"), std::string::npos);
  s = Pendulum();
  s.outputs.joints[0].joint = 3;
  EXPECT_NE(message(s).find("outputs.joints 'hinge'"), std::string::npos);
  // An output directory that cannot be created.
  const ScopedDir dir("not_a_dir");
  const std::string file = dir.path() + "/plain_file";
  { std::ofstream(file) << "x"; }
  EXPECT_THROW(RunScene(Pendulum(), file + "/out"), InputError);
}

TEST(RunScene, ProgressBarGoesToStandardErrorAndEndsItsLine) {
  RunOptions options;
  options.progress = true;
  testing::internal::CaptureStderr();
  const ScopedDir dir("progress");
  const RunResult r = RunScene(Pendulum(1e-3, 0.05), dir.path(), options);
  const std::string err = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(r.ok);
  EXPECT_NE(err.find("steps/s"), std::string::npos) << err;
  EXPECT_NE(err.find("100%"), std::string::npos) << err;
  EXPECT_EQ(err.back(), '\n');
}

}  // namespace
}  // namespace screwfem::run_test
