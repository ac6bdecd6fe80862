// Path-following statics (statics.h; docs/numerics.md, "Path-following statics", docs/numerics.md "Path-following
// statics"): a bounded solve that stops at a limit point with a message, arc-length
// continuation through the limit points of the von Mises two-bar truss (closed form),
// displacement control through a prescribed drive past its limit loads, continuation from a
// loaded state, and every converged step reported.
//
// Von Mises truss (docs/numerics.md, "Path-following statics"): supports at (-a, 0) and (a, 0), apex at (0, h),
// two bars of axial stiffness EA, each one helical rod element (exact for a straight bar:
// N = EA (l / L0 - 1)), pinned by revolute joints about z at the supports and at the apex; a
// downward apex load P = s P_ref. With the apex descent w:
//   P(w) = 2 EA (h - w) (1 / L(w) - 1 / L0),  L(w) = sqrt(a^2 + (h - w)^2),  L0 = L(0),
// limit points at L* = (a^2 L0)^(1/3): P* = +-2 EA y* (1 / L* - 1 / L0), y* = sqrt(L*^2 - a^2).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/joint.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"

namespace screwfem::statics_path_test {
namespace {

constexpr double kA = 1.0, kH = 0.5, kEA = 1.0;

double TrussLoad(double w) {
  const double L0 = std::hypot(kA, kH), L = std::hypot(kA, kH - w);
  return 2.0 * kEA * (kH - w) * (1.0 / L - 1.0 / L0);
}
double TrussLimitLoad() {
  const double L0 = std::hypot(kA, kH);
  const double Ls = std::cbrt(kA * kA * L0);
  const double ys = std::sqrt(Ls * Ls - kA * kA);
  return 2.0 * kEA * ys * (1.0 / Ls - 1.0 / L0);
}

struct Truss {
  Model model;
  NodeId apex;     // node of the apex (end node of the left bar)
  int drive = -1;  // joint index of the prismatic drive (displacement control)
};

// The truss under a dead apex load P_ref (s = 1), or, with `displacement_control`, with the
// apex moved down by a prescribed prismatic drive (alpha = s w_max) through a small slider body
// pinned to the apex (the prismatic joint also holds the apex on the symmetry axis).
Truss MakeTruss(double p_ref, bool displacement_control, double w_max = 1.1,
                LinearSolver solver = LinearSolver::kAuto) {
  ModelBuilder b;
  b.SetLinearSolver(solver);
  const Section bar = Section::FromDiagonals((Vec6() << kEA, kEA, kEA, 1.0, 1.0, 1.0).finished());
  const Vec3 left(-kA, 0.0, 0.0), right(kA, 0.0, 0.0), top(0.0, kH, 0.0);
  const RodId r0 = b.AddStraightRod("left", left, top, 1, bar);
  const RodId r1 = b.AddStraightRod("right", right, top, 1, bar);
  Truss t;
  const NodeMatch l0 = b.FindNodeAt(left, r0), l1 = b.FindNodeAt(top, r0);
  const NodeMatch m0 = b.FindNodeAt(right, r1), m1 = b.FindNodeAt(top, r1);
  b.AddJointAt("left support", JointType::kRevolute, kGround, l0.node, left, Vec3::UnitZ());
  b.AddJointAt("right support", JointType::kRevolute, kGround, m0.node, right, Vec3::UnitZ());
  b.AddJointAt("apex", JointType::kRevolute, l1.node, m1.node, top, Vec3::UnitZ());
  t.apex = l1.node;
  if (displacement_control) {
    const NodeId slider = b.AddNode(SE3::Translation(top), "slider");
    b.AddRigidBody("slider", slider, 1e-3, Vec3::Zero(), 1e-6 * Mat3::Identity());
    b.AddJointAt("pin", JointType::kRevolute, slider, t.apex, top, Vec3::UnitZ());
    t.drive = b.AddJointAt("push", JointType::kPrismatic, kGround, slider, top, -Vec3::UnitY());
    Joint& j = b.model().joints[static_cast<std::size_t>(t.drive)];
    j.drive = DriveKind::kPrescribed;
    j.drive_profile = Profile::Constant(w_max);
  } else {
    PointLoad load;
    load.node = t.apex;
    load.force = Vec3(0.0, -p_ref, 0.0);
    b.AddPointLoad(load);
  }
  t.model = b.Build();
  return t;
}

double ApexDescent(const Truss& t, const Data& d) {
  return kH - d.H[static_cast<std::size_t>(t.apex)].x.y();
}

// A wall-clock guard polled by the solver: the test fails (instead of hanging) when a solve
// runs longer than `seconds`.
struct TimeGuard {
  std::chrono::steady_clock::time_point end;
  explicit TimeGuard(double seconds)
      : end(std::chrono::steady_clock::now() +
            std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                std::chrono::duration<double>(seconds))) {}
  StopRequest Request() {
    StopRequest r;
    r.poll = [](void* self) {
      return std::chrono::steady_clock::now() > static_cast<TimeGuard*>(self)->end;
    };
    r.context = this;
    return r;
  }
};

// A slider-crank (crank O-A, coupler A-B, slider at B guided along x) whose slider is driven
// past its dead centre x = |OA| + |AB|: beyond it there is no equilibrium. The solve used to
// shrink its increment geometrically without bound (about 280000 accepted steps in a minute
// without ending); now it stops at the smallest increment, names the limit point, and returns
// within its step cap.
TEST(PathFollowingStatics, DisplacementControlPastATurningPointStopsWithALimitPointMessage) {
  ModelBuilder b;
  const Vec3 O(0, 0, 0), A(0.1, 0.1, 0), B(0.3, 0, 0);
  const Mat3 I = 1e-4 * Mat3::Identity();
  const NodeId crank = b.AddNode(SE3::Translation(O), "crank");
  const NodeId coupler = b.AddNode(SE3::Translation(A), "coupler");
  const NodeId slider = b.AddNode(SE3::Translation(B), "slider");
  b.AddRigidBody("crank", crank, 0.1, 0.5 * A, I);
  b.AddRigidBody("coupler", coupler, 0.1, 0.5 * (B - A), I);
  b.AddRigidBody("slider", slider, 0.1, Vec3::Zero(), I);
  b.AddJointAt("pivot", JointType::kRevolute, kGround, crank, O);
  b.AddJointAt("elbow", JointType::kRevolute, crank, coupler, A);
  b.AddJointAt("wrist", JointType::kRevolute, coupler, slider, B);
  const JointId guide =
      b.AddJointAt("guide", JointType::kPrismatic, kGround, slider, B, Vec3::UnitX());
  Joint& g = b.model().joints[guide];
  g.drive = DriveKind::kPrescribed;
  g.drive_profile = Profile::Constant(0.2);  // x_B = 0.3 + 0.2 s
  const Model m = b.Build();
  const double s_dead = (A.norm() + (B - A).norm() - B.x()) / 0.2;  // 0.325140...
  Data d = MakeData(m);
  StaticOptions opt;
  TimeGuard guard(20.0);
  const StaticResult r = SolveStatic(m, d, opt, guard.Request());
  ASSERT_FALSE(r.interrupted) << "the solve did not end within 20 s: " << r.message;
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.limit_point) << r.message;
  EXPECT_LE(r.load_steps, 2 * opt.load_steps + 1000);
  // Stopped within the smallest increment (0.1 / 2^12) below the dead centre.
  EXPECT_LT(r.load_factor, s_dead);
  EXPECT_GT(r.load_factor, s_dead - 0.1 * std::ldexp(1.0, -opt.max_halvings));
  EXPECT_NE(r.message.find("limit point at load factor 0.3251"), std::string::npos) << r.message;
  EXPECT_NEAR(d.H[slider].x.x(), 0.3 + 0.2 * r.load_factor, 1e-12);

  // The step cap: with 3 steps allowed the solve stops after 3 accepted steps, saying so.
  Data d3 = MakeData(m);
  opt.max_steps = 3;
  const StaticResult r3 = SolveStatic(m, d3, opt);
  EXPECT_FALSE(r3.converged);
  EXPECT_EQ(r3.load_steps, 3);
  EXPECT_NEAR(r3.load_factor, 0.3, 1e-15);
  EXPECT_NE(r3.message.find("max_steps"), std::string::npos) << r3.message;
}

// Load stepping on the truss reaches the limit load and stops there, reporting it as a limit
// point with the load factor (not as a Newton failure).
TEST(PathFollowingStatics, LoadSteppingStopsAtTheTrussLimitLoadAndReportsIt) {
  const double p_ref = 0.08, s_limit = TrussLimitLoad() / p_ref;
  const Truss t = MakeTruss(p_ref, false);
  Data d = MakeData(t.model);
  StaticOptions opt;
  TimeGuard guard(20.0);
  const StaticResult r = SolveStatic(t.model, d, opt, guard.Request());
  ASSERT_FALSE(r.interrupted);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.limit_point) << r.message;
  EXPECT_LT(r.load_factor, s_limit);
  EXPECT_GT(r.load_factor, s_limit - 0.1 * std::ldexp(1.0, -opt.max_halvings));
  EXPECT_NE(r.message.find("limit point at load factor 0.47"), std::string::npos) << r.message;
  // Every converged step is on the closed-form curve.
  EXPECT_NEAR(p_ref * r.load_factor, TrussLoad(ApexDescent(t, d)), 1e-9 * TrussLimitLoad());
}

// Arc length traces the snap-through: up to P*, down through zero and -P* and up again to
// P_ref, every converged point on P(w), the two limit points found.
TEST(PathFollowingStatics, ArcLengthTracesTheVonMisesTrussThroughBothLimitPoints) {
  const double p_ref = 0.08, p_star = TrussLimitLoad();
  EXPECT_NEAR(p_star, 0.038383740, 1e-9);  // docs/numerics.md, "Path-following statics"
  const Truss t = MakeTruss(p_ref, false);
  Data d = MakeData(t.model);
  StaticOptions opt;
  opt.method = StaticMethod::kArcLength;
  double max_error = 0.0, w_max = 0.0, s_min = 0.0;
  int steps = 0;
  const StaticResult r = SolveStatic(t.model, d, opt, {}, [&](const StaticStep& step) {
    const double w = ApexDescent(t, d);
    max_error = std::max(max_error, std::abs(p_ref * step.load_factor - TrussLoad(w)));
    w_max = std::max(w_max, w);
    s_min = std::min(s_min, step.load_factor);
    ++steps;
  });
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(steps, r.load_steps);
  EXPECT_EQ(r.load_factor, 1.0);
  EXPECT_LT(max_error, 1e-8 * p_star);
  // Snapped through: past the second limit point and below -P*.
  EXPECT_GT(w_max, 1.0);
  EXPECT_NEAR(p_ref * s_min, -p_star, 0.05 * p_star);
  EXPECT_NEAR(p_ref * 1.0, TrussLoad(ApexDescent(t, d)), 1e-10);
  ASSERT_EQ(r.limit_points.size(), 2u);
  EXPECT_NEAR(p_ref * r.limit_points[0], p_star, 1e-2 * p_star);
  EXPECT_NEAR(p_ref * r.limit_points[1], -p_star, 1e-2 * p_star);
  EXPECT_LT(r.load_steps, 40);
  // Shorter arcs locate the limit loads more closely, the vertex of the parabola through the
  // three points around each (measured relative errors: 5e-5 and 5e-3 with the default arc
  // length, 19 steps; 2e-5 and 5e-5 with arcs <= 0.015, 54 steps; 2.0e-6 and 1.4e-6 with arcs
  // <= 0.005, 160 steps).
  Data d2 = MakeData(t.model);
  opt.arc_length_max = 0.005;
  const StaticResult r2 = SolveStatic(t.model, d2, opt);
  ASSERT_TRUE(r2.converged) << r2.message;
  ASSERT_EQ(r2.limit_points.size(), 2u);
  EXPECT_NEAR(p_ref * r2.limit_points[0], p_star, 5e-6 * p_star);
  EXPECT_NEAR(p_ref * r2.limit_points[1], -p_star, 5e-6 * p_star);
}

// A snap-back: the truss loaded through a soft spring (stiffness k, a force element) from a
// slider on the symmetry axis 1.5 m above the apex (a small body on a prismatic joint; the
// spring shortens by P / k <= 0.8 m), the load on the slider. With
// the apex descent w and the slider's descent u: P = P(w) (the truss) and u = w + P / k (the
// spring), so du/dw = 1 + P'(w) / k turns negative where P'(w) < -k (P'(h) = -2 EA (1/a - 1/L0)
// = -0.211 here, k = 0.1): the path turns back in u as well as in P. The default arc-length
// settings trace it through the two load limit points and the two displacement turning points
// to the far branch at P_ref, every converged point on the closed form.
TEST(PathFollowingStatics, ArcLengthWithDefaultSettingsTracesASnapBack) {
  const double p_ref = 0.08, k = 0.1, c = 1.5, p_star = TrussLimitLoad();
  ModelBuilder b;
  const Section bar = Section::FromDiagonals((Vec6() << kEA, kEA, kEA, 1.0, 1.0, 1.0).finished());
  const Vec3 left(-kA, 0.0, 0.0), right(kA, 0.0, 0.0), top(0.0, kH, 0.0), slide(0.0, kH + c, 0.0);
  const RodId r0 = b.AddStraightRod("left", left, top, 1, bar);
  const RodId r1 = b.AddStraightRod("right", right, top, 1, bar);
  const NodeId apex = b.RodNodes(r0).back();
  b.AddJointAt("left support", JointType::kRevolute, kGround, b.RodNodes(r0).front(), left);
  b.AddJointAt("right support", JointType::kRevolute, kGround, b.RodNodes(r1).front(), right);
  b.AddJointAt("apex", JointType::kRevolute, apex, b.RodNodes(r1).back(), top);
  const NodeId slider = b.AddNode(SE3::Translation(slide), "slider");
  b.AddRigidBody("slider", slider, 1e-3, Vec3::Zero(), 1e-6 * Mat3::Identity());
  b.AddJointAt("guide", JointType::kPrismatic, kGround, slider, slide, -Vec3::UnitY());
  ForceElement spring;
  spring.name = "spring";
  spring.a = {slider, Vec3::Zero()};
  spring.b = {apex, Vec3::Zero()};
  spring.stiffness = k;
  b.AddForceElement(spring);
  PointLoad load;
  load.node = slider;
  load.force = Vec3(0.0, -p_ref, 0.0);
  b.AddPointLoad(load);
  const Model m = b.Build();
  Data d = MakeData(m);
  StaticOptions opt;
  opt.method = StaticMethod::kArcLength;  // every other setting at its default
  // The closed-form turning points of u: P'(w) = -k, by bisection on each side of w = h.
  auto slope = [](double w) { return (TrussLoad(w + 1e-6) - TrussLoad(w - 1e-6)) / 2e-6; };
  auto turn = [&](double lo, double hi) {  // slope + k changes sign in [lo, hi]
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      ((slope(lo) + k) * (slope(mid) + k) <= 0.0 ? hi : lo) = mid;
    }
    return 0.5 * (lo + hi);
  };
  const double w_a = turn(0.0, kH), w_b = turn(kH, 2.0 * kH);
  const double u_a = w_a + TrussLoad(w_a) / k, u_b = w_b + TrussLoad(w_b) / k;
  ASSERT_GT(u_a, u_b + 0.1);  // a real snap-back: u falls by more than 0.1 m
  double max_load_error = 0.0, max_spring_error = 0.0, u_max = -1.0, u_min_after = 1e9;
  double w_max = 0.0;
  const StaticResult r = SolveStatic(m, d, opt, {}, [&](const StaticStep& step) {
    const double w = kH - d.H[apex.index()].x.y(), u = kH + c - d.H[slider.index()].x.y();
    const double p = p_ref * step.load_factor;
    max_load_error = std::max(max_load_error, std::abs(p - TrussLoad(w)));
    max_spring_error = std::max(max_spring_error, std::abs(u - w - p / k));
    u_max = std::max(u_max, u);
    if (u_max > u_a - 0.02) u_min_after = std::min(u_min_after, u);  // after the first turn
    w_max = std::max(w_max, w);
  });
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.load_factor, 1.0);
  EXPECT_LT(max_load_error, 1e-8 * p_star);
  EXPECT_LT(max_spring_error, 1e-8);
  // Both displacement turning points passed: u rose to u_a, fell back to u_b, and rose again.
  EXPECT_GT(u_max, u_a - 0.02);
  EXPECT_LT(u_min_after, u_b + 0.02);
  EXPECT_GT(w_max, 1.0);
  // And both load limit points (located by the parabola through the steps around each: with
  // the default arcs within 1.1 % and 0.5 %, measured).
  ASSERT_EQ(r.limit_points.size(), 2u);
  EXPECT_NEAR(p_ref * r.limit_points[0], p_star, 2e-2 * p_star);
  EXPECT_NEAR(p_ref * r.limit_points[1], -p_star, 2e-2 * p_star);
  EXPECT_LT(r.load_steps, 40);
  std::printf(
      "snap-back: %d steps, %d Newton solves, u turns at %.4f and %.4f m (w %.4f, %.4f), limit "
      "loads %.4g %.4g (P* %.4g)\n",
      r.load_steps, r.total_iterations, u_a, u_b, w_a, w_b, p_ref * r.limit_points[0],
      p_ref * r.limit_points[1], p_star);
}

// The arc-length path with the sparse LU (docs/numerics.md, "Sparse direct solve"): the same
// load factors and limit points as with the banded LU, and at every converged step the same
// sign of the determinant of the last factorised matrix, which changes sign along the path.
TEST(PathFollowingStatics, SparseLUFollowsTheBandedPathWithTheSameDeterminantSigns) {
  const double p_ref = 0.08;
  struct Path {
    std::vector<double> load;
    std::vector<int> sign;
    StaticResult result;
  };
  Path paths[2];
  for (int k = 0; k < 2; ++k) {
    const Truss t =
        MakeTruss(p_ref, false, 1.1, k == 0 ? LinearSolver::kBanded : LinearSolver::kSparse);
    ASSERT_EQ(t.model.sparse_solver, k == 1);
    Data d = MakeData(t.model);
    StaticOptions opt;
    opt.method = StaticMethod::kArcLength;
    paths[k].result = SolveStatic(t.model, d, opt, {}, [&](const StaticStep& step) {
      paths[k].load.push_back(step.load_factor);
      paths[k].sign.push_back(k == 0 ? d.matrix.determinant_sign() : d.sparse.determinant_sign());
    });
    ASSERT_TRUE(paths[k].result.converged) << paths[k].result.message;
    // The exact tangent's pattern (a second analysis) and the model's back at the end.
    if (k == 1) {
      EXPECT_EQ(d.sparse.analyses(), 3);
    }
  }
  ASSERT_EQ(paths[1].load.size(), paths[0].load.size());
  for (std::size_t i = 0; i < paths[0].load.size(); ++i)
    EXPECT_NEAR(paths[1].load[i], paths[0].load[i], 1e-9) << i;
  EXPECT_EQ(paths[1].sign, paths[0].sign);
  int changes = 0;
  for (std::size_t i = 1; i < paths[0].sign.size(); ++i)
    changes += paths[0].sign[i] != paths[0].sign[i - 1] ? 1 : 0;
  EXPECT_GE(changes, 2);  // past both limit points
  ASSERT_EQ(paths[1].result.limit_points.size(), 2u);
  EXPECT_NEAR(paths[1].result.limit_points[0], paths[0].result.limit_points[0], 1e-9);
  EXPECT_NEAR(paths[1].result.limit_points[1], paths[0].result.limit_points[1], 1e-9);
}

// Displacement control (docs/numerics.md, "Path-following statics"): the apex pushed down by a prescribed
// drive; plain load stepping passes both limit loads, and the drive's effort equals P(w) at
// every load step.
TEST(PathFollowingStatics, DisplacementControlTracesTheTrussPastItsLimitLoads) {
  const double w_max = 1.1;
  const Truss t = MakeTruss(0.0, true, w_max);
  Data d = MakeData(t.model);
  StaticOptions opt;
  opt.load_steps = 22;
  double max_error = 0.0, p_max = 0.0, p_min = 0.0;
  const StaticResult r = SolveStatic(t.model, d, opt, {}, [&](const StaticStep& step) {
    const double w = ApexDescent(t, d);
    EXPECT_NEAR(w, w_max * step.load_factor, 1e-12);
    const double effort = JointDriveEffort(t.model, d, t.drive);
    max_error = std::max(max_error, std::abs(effort - TrussLoad(w)));
    p_max = std::max(p_max, effort);
    p_min = std::min(p_min, effort);
  });
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.load_steps, 22);
  EXPECT_LT(max_error, 1e-10);
  EXPECT_GT(p_max, 0.99 * TrussLimitLoad());
  EXPECT_LT(p_min, -0.99 * TrussLimitLoad());
  // The exact tangent (d(B^T lambda)/dq; the joints carry the bar forces) against the
  // dynamic solver's matrix without it: the same path in fewer Newton iterations.
  Data d_old = MakeData(t.model);
  opt.constraint_force_tangent = false;
  const StaticResult r_old = SolveStatic(t.model, d_old, opt);
  ASSERT_TRUE(r_old.converged) << r_old.message;
  EXPECT_NEAR(ApexDescent(t, d_old), ApexDescent(t, d), 1e-12);
  // Measured: 88 against 109 iterations; in a mid-path step the residual falls 5.3e-4, 7.5e-8,
  // 8.1e-14 with the exact tangent (quadratic) and 1.1e-2, 1.2e-5, 3.4e-6, 2.0e-9 without.
  EXPECT_LT(r.total_iterations, r_old.total_iterations);
  int slow_steps = 0;
  for (std::size_t i = 0; i < r.steps.size(); ++i) {
    EXPECT_LE(r.steps[i].iterations, 4) << "step " << i;
    slow_steps += r_old.steps[i].iterations > 4;
  }
  EXPECT_GT(slow_steps, 10);
}

// Continuation: a solve from 0 to 0.3 and one from there to 1 end in the state one solve from
// 0 to 1 reaches; start > end unloads back to the reference.
TEST(PathFollowingStatics, ContinuesFromTheCurrentStateAndUnloads) {
  const Truss t = MakeTruss(0.01, false);  // below the limit load: a unique branch
  Data whole = MakeData(t.model), parts = MakeData(t.model);
  ASSERT_TRUE(SolveStatic(t.model, whole).converged);
  StaticOptions first;
  first.end_load_factor = 0.3;
  ASSERT_TRUE(SolveStatic(t.model, parts, first).converged);
  EXPECT_NEAR(0.01 * 0.3, TrussLoad(ApexDescent(t, parts)), 1e-12);
  StaticOptions second;
  second.start_load_factor = 0.3;
  second.load_steps = 3;
  const StaticResult r = SolveStatic(t.model, parts, second);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.load_steps, 3);
  EXPECT_NEAR(r.steps.front().load_factor, 0.3 + 0.7 / 3, 1e-15);
  EXPECT_NEAR(ApexDescent(t, parts), ApexDescent(t, whole), 1e-12);
  StaticOptions unload;
  unload.start_load_factor = 1.0;
  unload.end_load_factor = 0.0;
  unload.method = StaticMethod::kArcLength;
  const StaticResult u = SolveStatic(t.model, parts, unload);
  ASSERT_TRUE(u.converged) << u.message;
  EXPECT_LT(std::abs(ApexDescent(t, parts)), 1e-12);
  // Fewer Newton iterations than the arc-length controller's default aim are valid settings.
  StaticOptions few;
  few.max_iterations = 3;
  EXPECT_NO_THROW(ValidateStaticOptions(few, "StaticOptions"));
  few.desired_iterations = 0;
  EXPECT_THROW(ValidateStaticOptions(few, "StaticOptions"), InputError);
}

}  // namespace
}  // namespace screwfem::statics_path_test
