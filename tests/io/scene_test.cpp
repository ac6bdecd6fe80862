// Scene files (io/scene.h, docs/scene-format.md): a parsed scene compiles to the same Model as
// the C++ API and simulates the same trajectory; every documented default; overrides,
// expressions, profiles, sections and the three GRM example scenes.
#include "screwfem/io/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::scene_test {
namespace {

// --- the same model twice: as a scene and through ModelBuilder -----------------------------------

const char* kEquivalenceScene = R"(
name: equivalence
gravity: [0, 0, -9.81]
defaults: {elements: 4}
points:
  A: [0, 0, 0]
  B: [0.3, 0, 0]
  C: [0.3, 0.4, 0]
  D: [0.3, 0.4, 0.5]
  E: [0.6, 0.4, 0.5]
  F: [0.3, 0.4, 0.8]
sections:
  soft:
    stiffness: [1e5, 1e5, 1e5, 2, 2, 3]
    inertia: [0.1, 0.1, 0.1, 1e-3, 1e-3, 2e-3]
    damping: [0, 0, 0, 1e-3, 1e-3, 1e-3]
bodies:
  base: {type: rigid, between: [A, B], mass: 0.2, inertia: [1e-3, 2e-3, 3e-3]}
  link:
    type: rigid
    between: [B, C]
    mass: 0.1
    inertia: [[1e-3, 1e-4, 0], [1e-4, 2e-3, 0], [0, 0, 3e-3]]
    com: [0.3, 0.25, 0]
  arm: {type: soft, from: C, to: D, section: soft, up: [1, 0, 0]}
  arm2: {type: soft, from: D, to: F, section: soft, up: [1, 0, 0], elements: 2, weld_start: arm}
  tip: {type: soft, from: D, to: E, section: soft, elements: 3}
  knob: {type: rigid, at: E, mass: 0.05, inertia: [1e-5, 1e-5, 1e-5], com: [0.62, 0.4, 0.5]}
joints:
  J0:
    type: revolute
    at: A
    between: [ground, base]
    axis: [0, 0, 1]
    drive: {type: prescribed, profile: {type: bang_bang, t0: 0, t1: 0.2, value: 0.3}}
  J1:
    type: prismatic
    at: B
    between: [base, link]
    axis: [0, 1, 0]
    stiffness: 10
    damping: 1
    rest: 0.01
    drive: {type: series_elastic, profile: {type: smooth_step, t1: 0.2, value: 0.05}}
  J2:
    type: universal
    at: C
    between: [link, arm]
    axis: [1, 0, 0]
    axis2: [0, 1, 0]
    stiffness: [0.5, 0.7]
    drive: {type: force, coordinate: 1, profile: {type: sine, value: 0.01, frequency: 2}}
  clamp: {type: fixed, at: D, between: [arm, tip]}
  J3: {type: helical, at: E, between: [tip, knob], axis: {from: D, to: E}, pitch: 0.01, stiffness: 0.1}
loads:
  push: {body: link, at: C, force: [0, 0, 1], profile: {type: ramp, t0: 0, t1: 0.1}}
  twist: {body: tip, at: E, moment: [0.01, 0, 0], frame: body}
  side: {body: arm, s: 0.2, force: [0.5, 0, 0], profile: {sum: [0.5, {type: table, times: [0, 0.1], values: [0, 1]}]}}
  wind: {body: tip, distributed: true, force: [0, 0.2, 0], moment: [0, 0, 0.001], frame: world}
analysis: {end_time: 0.03, step: 1e-3, rho_inf: 0.8}
)";

Model EquivalenceModelByApi() {
  ModelBuilder b;
  const Vec3 A(0, 0, 0), B(0.3, 0, 0), C(0.3, 0.4, 0), D(0.3, 0.4, 0.5), E(0.6, 0.4, 0.5),
      F(0.3, 0.4, 0.8);
  b.SetGravity(Vec3(0, 0, -9.81));
  Vec6 K, M;
  K << 1e5, 1e5, 1e5, 2, 2, 3;
  M << 0.1, 0.1, 0.1, 1e-3, 1e-3, 2e-3;
  Section soft = Section::FromDiagonals(K, M);
  soft.damping << 0, 0, 0, 1e-3, 1e-3, 1e-3;
  const NodeId base = b.AddNode(SE3::Translation(A), "base");
  b.AddRigidBody("base", base, 0.2, 0.5 * (B - A), Vec3(1e-3, 2e-3, 3e-3).asDiagonal());
  const NodeId link = b.AddNode(SE3::Translation(B), "link");
  Mat3 J;
  J << 1e-3, 1e-4, 0, 1e-4, 2e-3, 0, 0, 0, 3e-3;
  b.AddRigidBody("link", link, 0.1, Vec3(0.3, 0.25, 0) - B, J);
  const RodId arm = b.AddStraightRod("arm", C, D, 4, soft, Vec3::UnitX());
  const NodeId arm_end = b.RodNodes(arm).back();
  b.AddStraightRod("arm2", D, F, 2, soft, Vec3::UnitX(), arm_end);
  const RodId tip = b.AddStraightRod("tip", D, E, 3, soft);
  const NodeId tip_start = b.RodNodes(tip).front();
  const NodeId tip_end = b.RodNodes(tip).back();
  const NodeId knob = b.AddNode(SE3::Translation(E), "knob");
  b.AddRigidBody("knob", knob, 0.05, Vec3(0.02, 0, 0), 1e-5 * Mat3::Identity());

  Joint* j = nullptr;
  auto joint = [&](int i) { return &b.model().joints[static_cast<std::size_t>(i)]; };
  j = joint(b.AddJointAt("J0", JointType::kRevolute, kGround, base, A, Vec3::UnitZ()));
  j->drive = DriveKind::kPrescribed;
  j->drive_profile = Profile::BangBang(0, 0.2, 0.3);
  j = joint(b.AddJointAt("J1", JointType::kPrismatic, base, link, B, Vec3::UnitY()));
  j->stiffness(0) = 10;
  j->damping(0) = 1;
  j->rest(0) = 0.01;
  j->drive = DriveKind::kSeriesElastic;
  j->drive_profile = Profile::SmoothStep(0, 0.2, 0.05);
  const NodeId arm_start = b.RodNodes(arm).front();
  j = joint(
      b.AddJointAt("J2", JointType::kUniversal, link, arm_start, C, Vec3::UnitX(), Vec3::UnitY()));
  j->stiffness.head<2>() << 0.5, 0.7;
  j->drive = DriveKind::kForce;
  j->drive_coord = 1;
  j->drive_profile = Profile::Sine(0.01, 2.0);
  b.AddJointAt("clamp", JointType::kFixed, arm_end, tip_start, D);
  j = joint(b.AddJointAt("J3", JointType::kHelical, tip_end, knob, E, (E - D).normalized(),
                         Vec3::Zero(), 0.01));
  j->stiffness(0) = 0.1;

  PointLoad push;
  push.node = link;
  push.point = C - B;
  push.force = Vec3(0, 0, 1);
  push.profile = Profile::Ramp(0, 0.1);
  b.AddPointLoad(push);
  PointLoad twist;
  twist.node = tip_end;
  twist.frame = LoadFrame::kBody;
  twist.moment = Vec3(0.01, 0, 0);
  b.AddPointLoad(twist);
  RodLoad side;
  side.rod = arm;
  side.distributed = false;
  side.arc_length = 0.2;
  side.force = Vec3(0.5, 0, 0);
  side.profile = Profile::Constant(0.5).Add(Profile::Table({0, 0.1}, {0, 1}));
  b.AddRodLoad(side);
  RodLoad wind;
  wind.rod = tip;
  wind.force = Vec3(0, 0.2, 0);
  wind.moment = Vec3(0, 0, 0.001);
  b.AddRodLoad(wind);
  return b.Build();
}

void ExpectSameFrame(const SE3& a, const SE3& b, const std::string& what) {
  EXPECT_LT((a.R - b.R).norm(), 1e-14) << what;
  EXPECT_LT((a.x - b.x).norm(), 1e-14) << what;
}

void ExpectSameProfile(const Profile& a, const Profile& b, const std::string& what) {
  ASSERT_EQ(a.terms().size(), b.terms().size()) << what;
  for (double t : {-0.1, 0.0, 0.03, 0.05, 0.1, 0.15, 0.2, 0.3, 1.0}) {
    EXPECT_DOUBLE_EQ(a.Eval(t).value, b.Eval(t).value) << what << " at t = " << t;
    EXPECT_DOUBLE_EQ(a.Eval(t).rate, b.Eval(t).rate) << what << " at t = " << t;
    EXPECT_DOUBLE_EQ(a.Eval(t).accel, b.Eval(t).accel) << what << " at t = " << t;
  }
  EXPECT_EQ(a.Breakpoints(), b.Breakpoints()) << what;
}

TEST(SceneCompile, SceneGivesTheSameModelAsTheCppApi) {
  const Scene scene = ParseScene(kEquivalenceScene, "equivalence.yaml");
  const Model& s = scene.model;
  const Model api = EquivalenceModelByApi();

  ASSERT_EQ(s.nodes.size(), api.nodes.size());
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    EXPECT_EQ(s.nodes[i].name, api.nodes[i].name);
    EXPECT_EQ(s.nodes[i].fixed, api.nodes[i].fixed);
    ExpectSameFrame(s.nodes[i].reference, api.nodes[i].reference, "node " + api.nodes[i].name);
  }
  ASSERT_EQ(s.rods.size(), api.rods.size());
  for (std::size_t r = 0; r < s.rods.size(); ++r) {
    EXPECT_EQ(s.rods[r].name, api.rods[r].name);
    EXPECT_EQ(s.rods[r].nodes, api.rods[r].nodes);
    EXPECT_EQ(s.rods[r].section.stiffness, api.rods[r].section.stiffness);
    EXPECT_EQ(s.rods[r].section.inertia, api.rods[r].section.inertia);
    EXPECT_EQ(s.rods[r].section.damping, api.rods[r].section.damping);
  }
  ASSERT_EQ(s.elements.size(), api.elements.size());
  for (std::size_t e = 0; e < s.elements.size(); ++e) {
    EXPECT_EQ(s.elements[e].node_a, api.elements[e].node_a);
    EXPECT_EQ(s.elements[e].node_b, api.elements[e].node_b);
    EXPECT_NEAR(s.elements[e].length, api.elements[e].length, 1e-15);
    EXPECT_LT((s.elements[e].d0 - api.elements[e].d0).norm(), 1e-14);
  }
  ASSERT_EQ(s.bodies.size(), api.bodies.size());
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    EXPECT_EQ(s.bodies[b].name, api.bodies[b].name);
    EXPECT_EQ(s.bodies[b].node, api.bodies[b].node);
    EXPECT_EQ(s.bodies[b].mass, api.bodies[b].mass);
    EXPECT_LT((s.bodies[b].com - api.bodies[b].com).norm(), 1e-15);
    EXPECT_EQ(s.bodies[b].inertia, api.bodies[b].inertia);
  }
  ASSERT_EQ(s.joints.size(), api.joints.size());
  for (std::size_t i = 0; i < s.joints.size(); ++i) {
    const Joint& a = s.joints[i];
    const Joint& b = api.joints[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.node_a, b.node_a) << a.name;
    EXPECT_EQ(a.node_b, b.node_b) << a.name;
    ExpectSameFrame(a.offset_a, b.offset_a, a.name + " offset_a");
    ExpectSameFrame(a.offset_b, b.offset_b, a.name + " offset_b");
    ASSERT_EQ(a.k(), b.k());
    EXPECT_LT((a.basis - b.basis).norm(), 1e-15) << a.name;
    EXPECT_EQ(a.pitch, b.pitch);
    EXPECT_EQ(a.stiffness, b.stiffness) << a.name;
    EXPECT_EQ(a.damping, b.damping) << a.name;
    EXPECT_EQ(a.rest, b.rest) << a.name;
    EXPECT_EQ(a.drive, b.drive) << a.name;
    EXPECT_EQ(a.drive_coord, b.drive_coord) << a.name;
    EXPECT_EQ(a.coord, b.coord);
    EXPECT_EQ(a.row, b.row);
    EXPECT_EQ(a.drive_row, b.drive_row);
    if (b.drive != DriveKind::kNone) ExpectSameProfile(a.drive_profile, b.drive_profile, a.name);
  }
  ASSERT_EQ(s.point_loads.size(), api.point_loads.size());
  for (std::size_t i = 0; i < s.point_loads.size(); ++i) {
    EXPECT_EQ(s.point_loads[i].node, api.point_loads[i].node);
    EXPECT_LT((s.point_loads[i].point - api.point_loads[i].point).norm(), 1e-15);
    EXPECT_EQ(s.point_loads[i].frame, api.point_loads[i].frame);
    EXPECT_EQ(s.point_loads[i].force, api.point_loads[i].force);
    EXPECT_EQ(s.point_loads[i].moment, api.point_loads[i].moment);
    ExpectSameProfile(s.point_loads[i].profile, api.point_loads[i].profile, "point load");
  }
  ASSERT_EQ(s.rod_loads.size(), api.rod_loads.size());
  for (std::size_t i = 0; i < s.rod_loads.size(); ++i) {
    EXPECT_EQ(s.rod_loads[i].rod, api.rod_loads[i].rod);
    EXPECT_EQ(s.rod_loads[i].distributed, api.rod_loads[i].distributed);
    EXPECT_EQ(s.rod_loads[i].arc_length, api.rod_loads[i].arc_length);
    EXPECT_EQ(s.rod_loads[i].element, api.rod_loads[i].element);
    EXPECT_EQ(s.rod_loads[i].xi, api.rod_loads[i].xi);
    EXPECT_EQ(s.rod_loads[i].frame, api.rod_loads[i].frame);
    EXPECT_EQ(s.rod_loads[i].force, api.rod_loads[i].force);
    EXPECT_EQ(s.rod_loads[i].moment, api.rod_loads[i].moment);
    ExpectSameProfile(s.rod_loads[i].profile, api.rod_loads[i].profile, "rod load");
  }
  EXPECT_EQ(s.gravity, api.gravity);
  EXPECT_EQ(s.nv, api.nv);
  EXPECT_EQ(s.nc, api.nc);
  EXPECT_EQ(s.permutation, api.permutation);
  EXPECT_EQ(s.bandwidth, api.bandwidth);
}

TEST(SceneCompile, SceneAndCppApiSimulateTheSameTrajectory) {
  const Scene scene = ParseScene(kEquivalenceScene, "equivalence.yaml");
  const Model api = EquivalenceModelByApi();
  Data ds = MakeData(scene.model), da = MakeData(api);
  Integrator is, ia;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(scene.model, ds, is, scene.analysis.dynamic, &message)) << message;
  DynamicOptions options;
  options.rho_inf = 0.8;
  ASSERT_TRUE(InitializeDynamics(api, da, ia, options, &message)) << message;
  for (int step = 0; step < 30; ++step) {
    ASSERT_TRUE(Step(scene.model, ds, is, scene.analysis.step).ok) << "scene, step " << step;
    ASSERT_TRUE(Step(api, da, ia, 1e-3).ok) << "api, step " << step;
  }
  double moved = 0.0;
  for (std::size_t n = 0; n < api.nodes.size(); ++n) {
    EXPECT_LT((ds.H[n].x - da.H[n].x).norm(), 1e-12) << "node " << n;
    EXPECT_LT((ds.H[n].R - da.H[n].R).norm(), 1e-12) << "node " << n;
    moved = std::max(moved, (da.H[n].x - api.nodes[n].reference.x).norm());
  }
  EXPECT_GT(moved, 1e-4);  // the run did something
  EXPECT_LT((ds.q_joint - da.q_joint).norm(), 1e-12);
  EXPECT_LT((ds.v - da.v).norm(), 1e-9);
}

// --- documented defaults
// ---------------------------------------------------------------------------

const char* kMinimalScene = R"(
points: {A: [0, 0, 0], B: [1, 0, 0]}
sections: {s: {stiffness: [1, 2, 3, 4, 5, 6]}}
bodies:
  b: {type: rigid, between: [A, B], mass: 1, inertia: [1, 1, 1]}
  c: {type: rigid, at: A, mass: 1, inertia: [1, 1, 1], free: true}
  r: {type: soft, from: B, to: [2, 0, 0], section: s}
joints:
  j: {type: revolute, at: A, between: [ground, b], axis: [0, 0, 1]}
  k: {type: fixed, at: B, between: [b, r]}
  d: {type: cylindrical, at: B, between: [b, r], axis: [1, 0, 0], drive: {type: force, profile: 2}}
loads:
  l: {body: r, at: [2, 0, 0], force: [0, 1, 0]}
  m: {body: b, at: B, moment: [0, 0, 1], profile: {type: ramp, t1: 2}}
)";

TEST(SceneDefaults, EveryDocumentedDefault) {
  const Scene scene = ParseScene(kMinimalScene, "dir/minimal.yaml");
  const Model& m = scene.model;
  EXPECT_EQ(scene.source, "dir/minimal.yaml");
  EXPECT_EQ(scene.name, "minimal");    // name: the file name without directory and extension
  EXPECT_EQ(m.gravity, Vec3::Zero());  // gravity: [0, 0, 0]
  // Soft bodies: defaults.elements = 8, up = [0, 0, 1]; section inertia and damping zero.
  ASSERT_EQ(m.rods.size(), 1u);
  EXPECT_EQ(m.rods[0].num_elements, 8);
  EXPECT_LT(
      (m.nodes[static_cast<std::size_t>(m.rods[0].nodes[3])].reference.R.col(2) - Vec3::UnitZ())
          .norm(),
      1e-15);
  EXPECT_EQ(m.rods[0].section.inertia, Vec6::Zero());
  EXPECT_EQ(m.rods[0].section.damping, Vec6::Zero());
  EXPECT_EQ(m.rods[0].section.rayleigh_mass, 0.0);
  EXPECT_EQ(m.rods[0].section.rayleigh_stiffness, 0.0);
  EXPECT_EQ(m.rod_inertia, Model{}.rod_inertia);  // analysis.rod_inertia: the engine default
  // Rigid bodies: com at the midpoint of `between`, at the point of `at`; not fixed.
  const RigidBody& b = m.bodies[static_cast<std::size_t>(m.FindBody("b"))];
  EXPECT_EQ(b.com, Vec3(0.5, 0, 0));
  EXPECT_FALSE(m.nodes[static_cast<std::size_t>(b.node)].fixed);
  EXPECT_EQ(m.nodes[static_cast<std::size_t>(b.node)].reference.R, Mat3::Identity());
  EXPECT_EQ(m.bodies[static_cast<std::size_t>(m.FindBody("c"))].com, Vec3::Zero());
  // Joints: no spring, damper, rest offset or drive; drive coordinate 0.
  const Joint& j = m.joints[static_cast<std::size_t>(m.FindJoint("j"))];
  EXPECT_EQ(j.stiffness, Vec6::Zero());
  EXPECT_EQ(j.damping, Vec6::Zero());
  EXPECT_EQ(j.rest, Vec6::Zero());
  EXPECT_EQ(j.drive, DriveKind::kNone);
  const Joint& d = m.joints[static_cast<std::size_t>(m.FindJoint("d"))];
  EXPECT_EQ(d.drive, DriveKind::kForce);
  EXPECT_EQ(d.drive_coord, 0);
  EXPECT_EQ(d.drive_profile(0.7), 2.0);  // a bare number is a constant profile
  // Loads: world frame, constant profile 1; a ramp starts at t0 = 0 and has value 1.
  ASSERT_EQ(m.point_loads.size(), 2u);
  EXPECT_EQ(m.point_loads[0].frame, LoadFrame::kWorld);
  EXPECT_EQ(m.point_loads[0].profile(0.0), 1.0);
  EXPECT_EQ(m.point_loads[0].profile(5.0), 1.0);
  EXPECT_EQ(m.point_loads[0].point, Vec3::Zero());
  EXPECT_EQ(m.point_loads[1].point, Vec3(1, 0, 0));
  EXPECT_DOUBLE_EQ(m.point_loads[1].profile(1.0), 0.5);
  EXPECT_DOUBLE_EQ(m.point_loads[1].profile(0.0), 0.0);
  EXPECT_DOUBLE_EQ(m.point_loads[1].profile(3.0), 1.0);
  // Analysis.
  const AnalysisSettings& a = scene.analysis;
  const DynamicOptions dyn;
  const StaticOptions sta;
  EXPECT_EQ(a.kind, AnalysisKind::kDynamic);
  EXPECT_EQ(a.start_time, 0.0);
  EXPECT_EQ(a.end_time, 1.0);
  EXPECT_EQ(a.step, 1e-3);
  EXPECT_TRUE(a.align_steps);
  EXPECT_FALSE(a.static_preload);
  EXPECT_EQ(a.dynamic.rho_inf, dyn.rho_inf);
  EXPECT_EQ(a.dynamic.max_iterations, dyn.max_iterations);
  EXPECT_EQ(a.dynamic.max_halvings, dyn.max_halvings);
  EXPECT_EQ(a.dynamic.increment_tolerance, dyn.increment_tolerance);
  EXPECT_EQ(a.dynamic.constraint_tolerance, dyn.constraint_tolerance);
  EXPECT_EQ(a.dynamic.residual_tolerance, dyn.residual_tolerance);
  EXPECT_EQ(a.statics.load_steps, sta.load_steps);
  EXPECT_EQ(a.statics.max_iterations, sta.max_iterations);
  EXPECT_EQ(a.statics.max_halvings, sta.max_halvings);
  EXPECT_EQ(a.statics.residual_tolerance, sta.residual_tolerance);
  EXPECT_EQ(a.statics.time, 0.0);  // the preload is solved at start_time
  // Outputs: no points, every joint with coordinates (not the fixed k), about 1000 rows and
  // 100 VTK frames per run in whole steps (1000 steps of 1 ms: every step and every 10 steps).
  EXPECT_TRUE(scene.outputs.points.empty());
  ASSERT_EQ(scene.outputs.joints.size(), 2u);
  EXPECT_EQ(scene.outputs.joints[0].name, "j");
  EXPECT_EQ(scene.outputs.joints[1].name, "d");
  EXPECT_EQ(scene.outputs.joints[1].joint, m.FindJoint("d"));
  EXPECT_EQ(scene.outputs.interval, 1e-3);
  EXPECT_TRUE(scene.outputs.vtk);
  EXPECT_EQ(scene.outputs.vtk_interval, 1e-2);
  ASSERT_EQ(scene.named_points.size(), 2u);
  EXPECT_EQ(scene.named_points[1].first, "B");
  EXPECT_EQ(scene.named_points[1].second, Vec3(1, 0, 0));
}

TEST(SceneDefaults, StaticAnalysisEvaluatesProfilesAtTheEndTime) {
  const Scene scene = ParseScene(
      std::string(kMinimalScene) + "analysis: {type: static, end_time: 2, load_steps: 4}\n",
      "static.yaml");
  EXPECT_EQ(scene.analysis.kind, AnalysisKind::kStatic);
  EXPECT_EQ(scene.analysis.statics.time, 2.0);
  EXPECT_EQ(scene.analysis.statics.load_steps, 4);
}

TEST(SceneAnalysis, EveryStaticPathSettingIsRead) {
  const Scene scene = ParseScene(std::string(kMinimalScene) + R"(
analysis:
  type: static
  max_iterations: 12
  statics:
    method: arclength
    end_load_factor: 0.75
    max_steps: 77
    arc_length: 0.02
    arc_length_min: 1e-5
    arc_length_max: 0.1
    desired_iterations: 6
    psi: 1
    rotation_weight: 0.5
    exact_tangent: false
)",
                                 "statics.yaml");
  const StaticOptions& o = scene.analysis.statics;
  EXPECT_EQ(o.method, StaticMethod::kArcLength);
  EXPECT_EQ(o.start_load_factor, 0.0);
  EXPECT_EQ(o.end_load_factor, 0.75);
  EXPECT_EQ(o.max_steps, 77);
  EXPECT_EQ(o.arc_length, 0.02);
  EXPECT_EQ(o.arc_length_min, 1e-5);
  EXPECT_EQ(o.arc_length_max, 0.1);
  EXPECT_EQ(o.desired_iterations, 6);
  EXPECT_EQ(o.psi, 1.0);
  EXPECT_EQ(o.rotation_weight, 0.5);
  EXPECT_FALSE(o.constraint_force_tangent);
  const StaticOptions defaults;
  EXPECT_EQ(defaults.method, StaticMethod::kLoad);
  EXPECT_TRUE(defaults.constraint_force_tangent);
}

TEST(SceneAnalysis, EverySettingIsRead) {
  const Scene scene = ParseScene(std::string(kMinimalScene) + R"(
analysis:
  type: dynamic
  start_time: 0.5
  end_time: 2.5
  step: 2e-3
  rho_inf: 0.6
  tolerances: {increment: 1e-9, constraint: 1e-10, residual: 1e-7}
  max_iterations: 12
  max_halvings: 3
  align_steps: false
  static_preload: true
  rod_inertia: exact
  newton: full
  predictor: zero
  convergence: measured
outputs:
  points:
    tip: {body: r, at: [2, 0, 0]}
    mid: {rod: r, s: 0.25}
    corner: {body: b, at: [1, 1, 0]}
  joints: [d]
  interval: 0.01
  vtk: false
  vtk_interval: 0.05
)",
                                 "all.yaml");
  const AnalysisSettings& a = scene.analysis;
  EXPECT_EQ(a.start_time, 0.5);
  EXPECT_EQ(a.end_time, 2.5);
  EXPECT_EQ(a.step, 2e-3);
  EXPECT_EQ(a.dynamic.rho_inf, 0.6);
  EXPECT_EQ(a.dynamic.increment_tolerance, 1e-9);
  EXPECT_EQ(a.statics.increment_tolerance, 1e-9);
  EXPECT_EQ(a.dynamic.constraint_tolerance, 1e-10);
  EXPECT_EQ(a.dynamic.residual_tolerance, 1e-7);
  EXPECT_EQ(a.dynamic.max_iterations, 12);
  EXPECT_EQ(a.dynamic.max_halvings, 3);
  EXPECT_FALSE(a.align_steps);
  EXPECT_TRUE(a.static_preload);
  EXPECT_EQ(a.statics.time, 0.5);
  EXPECT_EQ(scene.model.rod_inertia, RodInertia::kExact);
  EXPECT_EQ(a.dynamic.newton_matrix, NewtonMatrix::kFull);
  EXPECT_EQ(a.dynamic.predictor, Predictor::kZero);
  EXPECT_EQ(a.dynamic.convergence, ConvergenceTest::kMeasured);
  const OutputSpec& o = scene.outputs;
  ASSERT_EQ(o.points.size(), 3u);
  EXPECT_EQ(o.points[0].name, "tip");
  EXPECT_EQ(o.points[0].node, scene.model.rods[0].nodes.back());
  EXPECT_EQ(o.points[0].rod, -1);
  EXPECT_EQ(o.points[1].rod, 0);
  EXPECT_EQ(o.points[1].arc_length, 0.25);
  EXPECT_EQ(o.points[2].node, scene.model.bodies[0].node);
  EXPECT_EQ(o.points[2].offset, Vec3(1, 1, 0));
  ASSERT_EQ(o.joints.size(), 1u);
  EXPECT_EQ(o.joints[0].name, "d");
  EXPECT_EQ(o.interval, 0.01);
  EXPECT_FALSE(o.vtk);
  EXPECT_EQ(o.vtk_interval, 0.05);
}

// --- overrides, expressions, profiles, sections, paths -------------------------------------------

TEST(SceneOverrides, ChangeValuesBeforeCompilation) {
  const Scene scene =
      ParseScene(kMinimalScene, "o.yaml",
                 {"defaults.elements=3", "analysis.step=5e-4", "gravity=[0, 0, -1]",
                  "bodies.b.mass=2", "points.B.1=0.5", "outputs.joints=[j]", "name=renamed"});
  EXPECT_EQ(scene.model.rods[0].num_elements, 3);
  EXPECT_EQ(scene.analysis.step, 5e-4);
  EXPECT_EQ(scene.model.gravity, Vec3(0, 0, -1));
  EXPECT_EQ(scene.model.bodies[0].mass, 2.0);
  EXPECT_EQ(scene.named_points[1].second, Vec3(1, 0.5, 0));
  ASSERT_EQ(scene.outputs.joints.size(), 1u);
  EXPECT_EQ(scene.name, "renamed");
  // A per-body value wins over the scene-wide default.
  const Scene per_body =
      ParseScene(kMinimalScene, "o.yaml", {"defaults.elements=3", "bodies.r.elements=5"});
  EXPECT_EQ(per_body.model.rods[0].num_elements, 5);
}

TEST(SceneValues, NumbersMayBeSmallExpressions) {
  const Scene scene =
      ParseScene(std::string(kMinimalScene) +
                     "analysis: {end_time: 2*pi, step: 1/1000, rho_inf: sqrt(0.25)}\n",
                 "e.yaml",
                 {"gravity=[0, -(1+1)*3, -9.81e0]", "bodies.b.mass=30*deg",
                  "joints.j.axis=[cos(pi/3), sin(pi/3), 0]"});
  EXPECT_DOUBLE_EQ(scene.analysis.end_time, 2 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(scene.analysis.step, 1e-3);
  EXPECT_DOUBLE_EQ(scene.analysis.dynamic.rho_inf, 0.5);
  EXPECT_EQ(scene.model.gravity, Vec3(0, -6, -9.81));
  EXPECT_DOUBLE_EQ(scene.model.bodies[0].mass, std::numbers::pi / 6);
  EXPECT_NEAR(scene.model.joints[0].basis(3, 0), 0.5, 1e-15);
}

TEST(SceneValues, EveryProfileTypeMatchesTheProfileApi) {
  const std::string scene_text = std::string(kMinimalScene) + R"(
  p1: {body: b, at: A, force: [1, 0, 0], profile: {type: constant, value: 3}}
  p2: {body: b, at: A, force: [1, 0, 0], profile: {type: ramp, t0: 0.1, t1: 0.3, scale: 2}}
  p3: {body: b, at: A, force: [1, 0, 0], profile: {type: bang_bang, t0: 0.1, t1: 0.5, value: 2}}
  p4: {body: b, at: A, force: [1, 0, 0], profile: {type: s_curve, t0: 0.1, t1: 0.5, value: 2}}
  p5: {body: b, at: A, force: [1, 0, 0], profile: {type: smooth_step, t0: 0.1, t1: 0.5, value: 2}}
  p6: {body: b, at: A, force: [1, 0, 0], profile: {type: sine, value: 2, frequency: 3, phase: 0.2, t0: 0.1}}
  p7: {body: b, at: A, force: [1, 0, 0], profile: {type: table, times: [0, 0.2, 0.4], values: [0, 1, -1], scale: 2}}
  p8: {body: b, at: A, force: [1, 0, 0], profile: {sum: [1, {type: ramp, t1: 1}]}}
)";
  const Model m = ParseScene(scene_text, "p.yaml").model;
  ASSERT_EQ(m.point_loads.size(), 10u);
  const Profile expected[] = {
      Profile::Constant(3),
      Profile::Ramp(0.1, 0.3, 2),
      Profile::BangBang(0.1, 0.5, 2),
      Profile::BangBang(0.1, 0.5, 2),
      Profile::SmoothStep(0.1, 0.5, 2),
      Profile::Sine(2, 3, 0.2, 0.1),
      Profile::Table({0, 0.2, 0.4}, {0, 1, -1}, 2),
      Profile::Constant(1).Add(Profile::Ramp(0, 1)),
  };
  for (std::size_t i = 0; i < 8; ++i)
    ExpectSameProfile(m.point_loads[i + 2].profile, expected[i], std::to_string(i + 1));
}

TEST(SceneValues, MaterialSectionsMatchTheSectionApi) {
  const std::string text = R"(
points: {A: [0, 0, 0], B: [1, 0, 0]}
materials:
  steel: {E: 210e9, nu: 0.3, density: 7850}
sections:
  round: {shape: circle, radius: 0.01, material: steel, damping: [0, 0, 0, 1, 1, 1]}
  flat: {shape: rectangle, width: 0.02, height: 0.005, material: {E: 2e9, G: 0.8e9, density: 1000, shear_coefficient: 0.8}}
  pipe: {shape: tube, outer_radius: 0.02, inner_radius: 0.015, material: steel, rayleigh_mass: 0.1, rayleigh_stiffness: 1e-4}
bodies:
  r1: {type: soft, from: A, to: B, section: round, elements: 1, free: true}
  r2: {type: soft, from: A, to: B, section: flat, elements: 1, free: true}
  r3: {type: soft, from: A, to: B, section: pipe, elements: 1, free: true}
)";
  const Model m = ParseScene(text, "sections.yaml").model;
  Material steel;
  steel.youngs_modulus = 210e9;
  steel.poisson_ratio = 0.3;
  steel.density = 7850;
  Material plastic;
  plastic.youngs_modulus = 2e9;
  plastic.shear_modulus = 0.8e9;
  plastic.density = 1000;
  plastic.shear_coefficient = 0.8;
  const Section round = Section::Circle(0.01, steel);
  const Section flat = Section::Rectangle(0.02, 0.005, plastic);
  const Section pipe = Section::Tube(0.02, 0.015, steel);
  EXPECT_EQ(m.rods[0].section.stiffness, round.stiffness);
  EXPECT_EQ(m.rods[0].section.inertia, round.inertia);
  EXPECT_EQ(m.rods[0].section.damping, (Vec6() << 0, 0, 0, 1, 1, 1).finished());
  EXPECT_EQ(m.rods[1].section.stiffness, flat.stiffness);
  EXPECT_EQ(m.rods[1].section.inertia, flat.inertia);
  EXPECT_EQ(m.rods[2].section.stiffness, pipe.stiffness);
  EXPECT_EQ(m.rods[2].section.rayleigh_mass, 0.1);
  EXPECT_EQ(m.rods[2].section.rayleigh_stiffness, 1e-4);
}

TEST(SceneValues, PathRodsPassThroughTheirPointsWithBisectorFrames) {
  const std::string text = R"(
points: {A: [0, 0, 0], B: [1, 0, 0], C: [1, 1, 0]}
sections: {s: {stiffness: [1, 1, 1, 1, 1, 1]}}
bodies:
  r: {type: soft, path: [A, B, C], section: s, elements: 2, free: true}
)";
  const Model m = ParseScene(text, "path.yaml").model;
  const Rod& rod = m.rods[0];
  ASSERT_EQ(rod.num_elements, 4);
  auto node = [&](int i) {
    return m.nodes[static_cast<std::size_t>(rod.nodes[static_cast<std::size_t>(i)])].reference;
  };
  EXPECT_LT((node(0).x - Vec3(0, 0, 0)).norm(), 1e-15);
  EXPECT_LT((node(1).x - Vec3(0.5, 0, 0)).norm(), 1e-15);
  EXPECT_LT((node(2).x - Vec3(1, 0, 0)).norm(), 1e-15);
  EXPECT_LT((node(4).x - Vec3(1, 1, 0)).norm(), 1e-15);
  EXPECT_LT((node(0).R.col(0) - Vec3::UnitX()).norm(), 1e-15);
  EXPECT_LT((node(2).R.col(0) - Vec3(1, 1, 0).normalized()).norm(), 1e-15);  // bisector
  EXPECT_LT((node(3).R.col(0) - Vec3::UnitY()).norm(), 1e-15);
  EXPECT_LT((node(2).R.col(2) - Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_EQ(m.elements[0].d0.tail<3>().norm(), 0.0);                            // straight part
  EXPECT_NEAR(m.elements[1].d0.tail<3>().norm(), std::numbers::pi / 4, 1e-14);  // rounded corner
}

TEST(SceneDocs, TheExampleOfTheFormatReferenceRuns) {
  // The first ```yaml block of docs/scene-format.md.
  std::ifstream in(std::string(SCREWFEM_SOURCE_DIR) + "/docs/scene-format.md");
  ASSERT_TRUE(in.good());
  std::stringstream doc;
  doc << in.rdbuf();
  const std::string text = doc.str();
  const std::size_t start = text.find("```yaml\n");
  ASSERT_NE(start, std::string::npos);
  const std::size_t end = text.find("```", start + 8);
  const Scene scene = ParseScene(text.substr(start + 8, end - start - 8), "scene-format.md");
  EXPECT_EQ(scene.name, "crank and soft arm");
  EXPECT_EQ(scene.outputs.points.size(), 2u);
  Data data = MakeData(scene.model);
  Integrator integ;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(scene.model, data, integ, scene.analysis.dynamic, &message))
      << message;
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(Step(scene.model, data, integ, scene.analysis.step).ok);
}

// --- the GRM example scenes
// ------------------------------------------------------------------------

std::string GrmFile(const std::string& name) {
  return std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/" + name + ".yaml";
}

void ExpectGrmStructure(const Scene& scene, DriveKind drive, double stiffness, double damping) {
  const Model& m = scene.model;
  EXPECT_EQ(m.bodies.size(), 6u);
  EXPECT_EQ(m.rods.size(), 5u);
  ASSERT_EQ(m.joints.size(), 9u);  // J0, J1, J2p, J3p, J2, J3, J4, J5 and the weld W1
  EXPECT_EQ(m.point_loads.size(), 3u);
  EXPECT_EQ(m.gravity, Vec3(0, 0, -9.81));
  for (const RigidBody& b : m.bodies) {
    EXPECT_EQ(b.mass, 0.15) << b.name;
    EXPECT_EQ(b.inertia, 1e-4 * Mat3::Identity()) << b.name;
  }
  EXPECT_TRUE(
      m.nodes[static_cast<std::size_t>(m.bodies[static_cast<std::size_t>(m.FindBody("base"))].node)]
          .fixed);
  const RigidBody& link34 = m.bodies[static_cast<std::size_t>(m.FindBody("link34"))];
  EXPECT_LT((link34.com - 0.5 * Vec3(0.3, -0.2, 0.2)).norm(), 1e-15);  // midpoint of P3-P4
  for (const Rod& r : m.rods) {
    EXPECT_EQ(r.section.stiffness, (Vec6() << 1e6, 1e6, 1e6, 1, 1, 1).finished()) << r.name;
    EXPECT_EQ(r.section.inertia, (Vec6() << 0.1, 0.1, 0.1, 0.5, 0.5, 0.5).finished()) << r.name;
  }
  // The arms share their nodes at 6 and 7.
  const Rod& arm56 = m.rods[static_cast<std::size_t>(m.FindRod("arm56"))];
  const Rod& arm67 = m.rods[static_cast<std::size_t>(m.FindRod("arm67"))];
  const Rod& arm78 = m.rods[static_cast<std::size_t>(m.FindRod("arm78"))];
  EXPECT_EQ(arm56.nodes.back(), arm67.nodes.front());
  EXPECT_EQ(arm67.nodes.back(), arm78.nodes.front());
  const Joint& j3 = m.joints[static_cast<std::size_t>(m.FindJoint("J3"))];
  EXPECT_EQ(j3.type, JointType::kPrismatic);
  EXPECT_NEAR(j3.basis(0, 0), std::cos(1.1903), 1e-5);
  EXPECT_NEAR(j3.basis(1, 0), std::sin(1.1903), 1e-5);
  const Joint& j5 = m.joints[static_cast<std::size_t>(m.FindJoint("J5"))];
  EXPECT_EQ(j5.basis.col(0), (Vec6() << 0, 0, 0, 1, 0, 0).finished());
  EXPECT_EQ(m.joints[static_cast<std::size_t>(m.FindJoint("W1"))].type, JointType::kFixed);
  const std::pair<const char*, double> actuated[] = {{"J0", std::numbers::pi / 6},
                                                     {"J2", std::numbers::pi / 6},
                                                     {"J3", 0.75},
                                                     {"J5", std::numbers::pi / 3}};
  for (const auto& [name, qf] : actuated) {
    const Joint& j = m.joints[static_cast<std::size_t>(m.FindJoint(name))];
    EXPECT_EQ(j.drive, drive) << name;
    EXPECT_DOUBLE_EQ(j.drive_profile(1.0), qf) << name;
    EXPECT_DOUBLE_EQ(j.drive_profile.Eval(0.1).accel, 4 * qf) << name;  // a = 4 q_f / T^2
    EXPECT_DOUBLE_EQ(j.drive_profile(2.0), qf) << name;
  }
  for (const char* name : {"J0", "J1", "J2p", "J3p", "J2", "J3", "J4", "J5"}) {
    const Joint& j = m.joints[static_cast<std::size_t>(m.FindJoint(name))];
    EXPECT_EQ(j.stiffness(0), stiffness) << name;
    EXPECT_EQ(j.damping(0), damping) << name;
  }
  const Vec3 f_final[] = {Vec3(100, -100, 0), Vec3(-100, 100, 0), Vec3(100, -100, 0)};
  const Vec3 at[] = {Vec3(1, 1.8, 0.3), Vec3(1.2, 2, 0.4), Vec3(1.4, 2.2, 0.5)};
  for (std::size_t i = 0; i < 3; ++i) {
    const PointLoad& l = m.point_loads[i];
    EXPECT_EQ(l.frame, LoadFrame::kWorld);
    EXPECT_LT((m.nodes[static_cast<std::size_t>(l.node)].reference.x - at[i]).norm(), 1e-14);
    EXPECT_EQ(l.force * l.profile(1.0), f_final[i]);
    EXPECT_DOUBLE_EQ(l.profile.Eval(0.7).accel * 100, -400.0);  // +-400 N/s^2
  }
  EXPECT_EQ(scene.analysis.kind, AnalysisKind::kDynamic);
  EXPECT_EQ(scene.analysis.end_time, 2.0);
  EXPECT_EQ(scene.analysis.step, 1e-3);
  EXPECT_EQ(scene.analysis.dynamic.rho_inf, 0.8);
  ASSERT_EQ(scene.outputs.points.size(), 2u);
  EXPECT_EQ(scene.outputs.points[0].name, "P8");
  EXPECT_EQ(scene.outputs.points[0].node, arm78.nodes.back());
  EXPECT_EQ(scene.outputs.points[1].name, "P4");
  EXPECT_EQ(scene.outputs.points[1].node, link34.node);
  EXPECT_LT((scene.outputs.points[1].offset - Vec3(0.3, -0.2, 0.2)).norm(), 1e-15);
  EXPECT_EQ(scene.outputs.joints.size(), 8u);
  ASSERT_EQ(scene.named_points.size(), 11u);
  EXPECT_EQ(scene.named_points[2].first, "P2p");
}

TEST(SceneGrm, RigidCaseLoads) {
  ExpectGrmStructure(LoadScene(GrmFile("grm_rigid")), DriveKind::kPrescribed, 0.0, 0.0);
}
TEST(SceneGrm, SoftCaseLoads) {
  ExpectGrmStructure(LoadScene(GrmFile("grm_soft_k")), DriveKind::kSeriesElastic, 10.0, 0.0);
}
TEST(SceneGrm, SoftDampedCaseLoads) {
  ExpectGrmStructure(LoadScene(GrmFile("grm_soft_kd")), DriveKind::kSeriesElastic, 10.0, 5.0);
}

TEST(SceneGrm, ShortRunOfEachCaseSucceeds) {
  for (const char* name : {"grm_rigid", "grm_soft_k", "grm_soft_kd"}) {
    const Scene scene = LoadScene(GrmFile(name), {"defaults.elements=4"});
    Data data = MakeData(scene.model);
    Integrator integ;
    std::string message;
    ASSERT_TRUE(InitializeDynamics(scene.model, data, integ, scene.analysis.dynamic, &message))
        << name << ": " << message;
    for (int i = 0; i < 20; ++i)
      ASSERT_TRUE(Step(scene.model, data, integ, scene.analysis.step).ok) << name;
    EXPECT_NEAR(data.time, 0.02, 1e-12);
  }
}

}  // namespace
}  // namespace screwfem::scene_test
