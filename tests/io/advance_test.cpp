// Advance (solve/advance.h), the one stepping loop of RunScene, Python's Simulation and
// AdvanceTo: a run through Advance writes RunScene's rows, fixed steps end exactly on profile
// breakpoints, error-controlled steps report the output times inside them, and the stop
// request and the observer end it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/advance.h"
#include "screwfem/solve/initial_state.h"

namespace screwfem::advance_test {
namespace {

using test::ReadCsv;
using test::ScopedDir;
using test::Table;

// A rigid link (0.3 kg, centre of mass 0.25 m from the axis) driven about world z by a
// bang-bang profile from 0 to pi/3 over [0, 1] s: breakpoints at 0, 0.5 and 1 s, where the
// prescribed acceleration jumps.
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
  s.source = "advance_test.cpp";
  s.name = "driven link";
  s.model = b.Build();
  s.analysis.end_time = 1.2;
  s.analysis.step = step;
  s.outputs.joints = {OutputJoint{.name = "motor", .joint = j}};
  s.outputs.vtk = false;
  return s;
}

// A Data at the scene's start, initialised for stepping.
struct Stepper {
  explicit Stepper(const Scene& s) : model(s.model), data(MakeData(s.model)) {
    data.time = s.analysis.start_time;
    std::string why;
    EXPECT_TRUE(AssembleInitialState(model, data, &why)) << why;
    EXPECT_TRUE(InitializeDynamics(model, data, integ, s.analysis.dynamic, &why)) << why;
  }
  const Model& model;
  Data data;
  Integrator integ;
};

// Records the time and the joint angle after every step, and the output times reported inside
// steps (every `interval` from 0).
class Log : public AdvanceObserver {
 public:
  Log(const Stepper& s, double interval) : s_(s), interval_(interval) {}
  double NextOutputTime() const override {
    return interval_ > 0.0 ? next_ * interval_ : AdvanceObserver::NextOutputTime();
  }
  bool OutputInsideStep(double t) override {
    // Strictly inside the step just taken (InterpolateStep's record of it).
    EXPECT_GT(t, s_.integ.dense_t0);
    EXPECT_LT(t, s_.data.time);
    inside.push_back(t);
    ++next_;
    return true;
  }
  bool AfterStep(bool last) override {
    times.push_back(s_.data.time);
    angles.push_back(s_.data.q_joint(0));
    while (interval_ > 0.0 && next_ * interval_ <= s_.data.time) ++next_;  // due at the end
    lasts += last ? 1 : 0;
    return steps_left < 0 || --steps_left > 0;
  }
  std::vector<double> times, angles, inside;
  int lasts = 0;
  int steps_left = -1;  // > 0: end Advance after this many steps

 private:
  const Stepper& s_;
  double interval_;
  long next_ = 1;
};

bool Contains(const std::vector<double>& v, double t) {
  return std::find(v.begin(), v.end(), t) != v.end();
}

TEST(Advance, OnTheRunsScheduleGivesTheRowsOfRunScene) {
  const Scene s = DrivenLink(0.03);  // 0.03 does not divide 0.5: shortened steps at breakpoints
  const ScopedDir dir("advance_rows");
  ASSERT_TRUE(RunScene(s, dir.path()).ok);
  const Table rows = ReadCsv(dir.path() + "/joints.csv");
  ASSERT_TRUE(rows.well_formed) << rows.problem;

  Stepper st(s);
  const StepSchedule schedule(s.analysis.start_time, s.analysis.end_time, s.analysis.step,
                              ProfileBreakpoints(s.model));
  Log log(st, 0.0);
  const AdvanceResult r = Advance(st.model, st.data, st.integ, StepPolicy::OnSchedule(schedule),
                                  s.analysis.end_time, &log);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.steps, static_cast<long>(log.times.size()));
  EXPECT_EQ(log.lasts, 1);
  EXPECT_EQ(st.data.time, s.analysis.end_time);
  // One row per step (outputs.interval 0) after the initial one, at the same times and angles.
  ASSERT_EQ(rows.rows.size(), log.times.size() + 1);
  for (std::size_t i = 0; i < log.times.size(); ++i) {
    EXPECT_EQ(rows.rows[i + 1][0], log.times[i]) << i;
    EXPECT_EQ(rows.rows[i + 1][1], log.angles[i]) << i;
  }
}

TEST(Advance, FixedStepsEndExactlyOnTheBreakpoints) {
  const Scene s = DrivenLink(0.03);
  // On the run's schedule: the breakpoints are step ends.
  {
    Stepper st(s);
    const StepSchedule schedule(0.0, 1.2, 0.03, ProfileBreakpoints(s.model));
    Log log(st, 0.0);
    ASSERT_TRUE(
        Advance(st.model, st.data, st.integ, StepPolicy::OnSchedule(schedule), 1.2, &log).ok);
    EXPECT_TRUE(Contains(log.times, 0.5));
    EXPECT_TRUE(Contains(log.times, 1.0));
    EXPECT_EQ(st.integ.restarts, 2);  // at 0.5 and 1 s
  }
  // Steps of 0.03 s from the start: the step across a breakpoint ends a substep on it and
  // restarts there, and the steps keep their size.
  {
    Stepper st(s);
    Log log(st, 0.0);
    const AdvanceResult r =
        Advance(st.model, st.data, st.integ, StepPolicy::Fixed(0.03), 0.6, &log);
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_EQ(st.integ.restarts, 1);
    EXPECT_EQ(r.substeps, r.steps + 1);  // the step across 0.5 s in two
    EXPECT_FALSE(Contains(log.times, 0.5));
    EXPECT_NEAR(st.data.time, 0.6, 1e-12);
  }
}

TEST(Advance, ErrorControlledStepsReportTheOutputTimesInsideThem) {
  Scene s = DrivenLink(0.03);
  s.analysis.dynamic.absolute_tolerance = 1e-7;
  Stepper st(s);
  Log log(st, 0.05);
  const AdvanceResult r =
      Advance(st.model, st.data, st.integ, StepPolicy::ErrorControlled(), 1.2, &log);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(st.data.time, 1.2);  // lands exactly on t_until
  EXPECT_TRUE(Contains(log.times, 0.5));
  EXPECT_TRUE(Contains(log.times, 1.0));
  // Steps longer than the output interval hold output times inside: every output time is
  // either inside a step (reported) or at a step's end.
  EXPECT_GT(st.integ.max_h, 0.05);
  EXPECT_FALSE(log.inside.empty());
  for (long k = 1; k * 0.05 < 1.2; ++k)
    EXPECT_TRUE(Contains(log.inside, k * 0.05) || Contains(log.times, k * 0.05)) << k;
  // Advance with error control is AdvanceTo.
  Stepper other(s);
  const StepResult to = AdvanceTo(other.model, other.data, other.integ, 1.2);
  ASSERT_TRUE(to.ok);
  EXPECT_EQ(to.substeps, r.substeps);
  EXPECT_EQ(other.data.q_joint(0), st.data.q_joint(0));
}

TEST(Advance, EndsOnAStopRequestOrWhenTheObserverSaysSo) {
  const Scene s = DrivenLink(0.03);
  {
    Stepper st(s);
    std::atomic<int> flag{2};
    StopRequest stop;
    stop.flag = &flag;
    const AdvanceResult r =
        Advance(st.model, st.data, st.integ, StepPolicy::Fixed(0.03), 1.2, nullptr, stop);
    EXPECT_FALSE(r.ok);
    EXPECT_TRUE(r.interrupted);
    EXPECT_FALSE(r.interrupted_in_step);  // before the first step
    EXPECT_EQ(r.steps, 0);
    EXPECT_EQ(st.data.time, 0.0);
  }
  {
    Stepper st(s);
    Log log(st, 0.0);
    log.steps_left = 3;
    const AdvanceResult r =
        Advance(st.model, st.data, st.integ, StepPolicy::Fixed(0.03), 1.2, &log);
    EXPECT_FALSE(r.ok);
    EXPECT_TRUE(r.stopped);
    EXPECT_EQ(r.steps, 3);
  }
}

}  // namespace
}  // namespace screwfem::advance_test
