// Time profiles of loads and drives (profile.h; elements/joint.h, [G] Tables III and IV).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "screwfem/model/errors.h"
#include "screwfem/model/profile.h"

namespace screwfem::profile_test {
namespace {

constexpr double kPi = std::numbers::pi;

// Central differences of value -> rate and rate -> accel at t (away from breakpoints).
void ExpectDerivativesMatchFiniteDifferences(const Profile& p, double t) {
  const double h = 1e-5;
  const ProfileValue v = p.Eval(t);
  const ProfileValue vp = p.Eval(t + h), vm = p.Eval(t - h);
  const double scale = 1.0 + std::abs(v.value) + std::abs(v.rate) + std::abs(v.accel);
  EXPECT_NEAR(v.rate, (vp.value - vm.value) / (2 * h), 1e-7 * scale) << "t = " << t;
  EXPECT_NEAR(v.accel, (vp.rate - vm.rate) / (2 * h), 1e-7 * scale) << "t = " << t;
}

TEST(Profile, EveryKindHasRateAndAccelerationConsistentWithItsValue) {
  ProfileTerm table;
  table.kind = ProfileTerm::Kind::kTable;
  table.times = {0.0, 0.3, 1.1, 2.0};
  table.values = {1.0, -2.0, 0.5, 0.5};
  table.scale = 1.5;
  const std::vector<Profile> profiles = {
      Profile::Constant(2.5),
      Profile::Ramp(0.2, 1.3, -4.0),
      Profile::BangBang(0.1, 1.1, kPi / 6),
      Profile::SmoothStep(0.2, 1.7, 3.0),
      Profile::Sine(0.7, 1.3, 0.4, 0.05),
      Profile().Add(table),
  };
  for (const Profile& p : profiles) {
    const std::vector<double> br = p.Breakpoints();
    for (double t = -0.4; t < 2.5; t += 0.0537) {
      bool near_break = false;
      for (double b : br) near_break = near_break || std::abs(t - b) < 1e-3;
      if (!near_break) ExpectDerivativesMatchFiniteDifferences(p, t);
    }
  }
}

TEST(Profile, ClosedFormsOfRampSmoothStepSineAndTable) {
  const Profile ramp = Profile::Ramp(1.0, 3.0, 4.0);
  EXPECT_EQ(ramp(0.5), 0.0);
  EXPECT_DOUBLE_EQ(ramp(2.5), 3.0);
  EXPECT_DOUBLE_EQ(ramp.Eval(2.5).rate, 2.0);
  EXPECT_DOUBLE_EQ(ramp(7.0), 4.0);
  EXPECT_EQ(ramp.Eval(7.0).rate, 0.0);

  const Profile smooth = Profile::SmoothStep(0.0, 2.0, 5.0);
  const double u = 0.3, t = 2.0 * u;
  EXPECT_NEAR(smooth(t), 5.0 * (10 * std::pow(u, 3) - 15 * std::pow(u, 4) + 6 * std::pow(u, 5)),
              1e-14);
  EXPECT_DOUBLE_EQ(smooth(1.0), 2.5);  // symmetric about the middle
  EXPECT_NEAR(smooth.Eval(1.0).accel, 0.0, 1e-14);
  EXPECT_DOUBLE_EQ(smooth.Eval(1.0).rate, 5.0 * 30.0 / 16.0 / 2.0);  // 30 u^2 (1-u)^2 / T
  // C2 at both ends: rate and accel vanish.
  for (double te : {0.0, 2.0}) {
    EXPECT_EQ(smooth.Eval(te).rate, 0.0);
    EXPECT_EQ(smooth.Eval(te).accel, 0.0);
  }

  const Profile sine = Profile::Sine(2.0, 0.5, 0.3, 1.0);
  EXPECT_EQ(sine(0.9), 0.0);
  const double w = 2.0 * kPi * 0.5;
  EXPECT_NEAR(sine(1.7), 2.0 * std::sin(w * 0.7 + 0.3), 1e-15);
  EXPECT_NEAR(sine.Eval(1.7).rate, 2.0 * w * std::cos(w * 0.7 + 0.3), 1e-14);
  EXPECT_NEAR(sine.Eval(1.7).accel, -2.0 * w * w * std::sin(w * 0.7 + 0.3), 1e-14);

  const Profile table = Profile::Table({0.0, 1.0, 3.0}, {0.0, 2.0, 1.0}, 3.0);
  EXPECT_DOUBLE_EQ(table(0.5), 3.0);
  EXPECT_DOUBLE_EQ(table(2.0), 4.5);
  EXPECT_DOUBLE_EQ(table.Eval(2.0).rate, -1.5);
  EXPECT_DOUBLE_EQ(table(-1.0), 0.0);
  EXPECT_DOUBLE_EQ(table(9.0), 3.0);
  // Right-continuous at an interior knot: the slope of the segment that starts there; at the
  // first knot as well (the first segment's), and the left limit there is the constant before.
  EXPECT_DOUBLE_EQ(table.Eval(1.0).rate, -1.5);
  EXPECT_DOUBLE_EQ(table.Eval(0.0).value, 0.0);
  EXPECT_DOUBLE_EQ(table.Eval(0.0).rate, 6.0);
  EXPECT_DOUBLE_EQ(table.EvalLeft(0.0).rate, 0.0);
}

// [G] Table III/IV: bang-bang acceleration over T = 1 s, a = 4 q_f / T^2.
TEST(Profile, BangBangReproducesThePaperTables) {
  struct Row {
    double q_f, a;
  };
  const Row rows[] = {
      {kPi / 6, 2 * kPi / 3},  // q0 and q2 (rad)
      {0.75, 3.0},             // q3, prismatic (m)
      {kPi / 3, 4 * kPi / 3},  // q5 (rad)
      {100.0, 400.0},          // S-shaped force profiles (N, N/s^2)
  };
  for (const Row& r : rows) {
    const Profile p = Profile::BangBang(0.0, 1.0, r.q_f);
    // Right limit at t = 0: the acceleration that holds just after the start.
    const ProfileValue p0 = p.Eval(0.0);
    EXPECT_EQ(p0.value, 0.0);
    EXPECT_EQ(p0.rate, 0.0);
    EXPECT_NEAR(p0.accel, r.a, 1e-14 * r.a);
    EXPECT_EQ(p.Eval(-1e-12).accel, 0.0);  // nothing before the start
    // First half: +a; middle: half the stroke at peak rate a T / 2; second half: -a.
    EXPECT_NEAR(p(0.25), 0.5 * r.a * 0.0625, 1e-14 * r.q_f);
    EXPECT_NEAR(p.Eval(0.25).rate, 0.25 * r.a, 1e-14 * r.a);
    const ProfileValue pm = p.Eval(0.5);
    EXPECT_NEAR(pm.value, 0.5 * r.q_f, 1e-14 * r.q_f);
    EXPECT_NEAR(pm.rate, 0.5 * r.a, 1e-14 * r.a);
    EXPECT_NEAR(pm.accel, -r.a, 1e-14 * r.a);  // right limit at the switch
    EXPECT_NEAR(p.Eval(0.5 - 1e-12).accel, r.a, 1e-14 * r.a);
    EXPECT_NEAR(p(0.75), r.q_f - 0.5 * r.a * 0.0625, 1e-14 * r.q_f);
    EXPECT_NEAR(p.Eval(0.75).accel, -r.a, 1e-14 * r.a);
    // At and after T: at rest at q_f.
    const ProfileValue p1 = p.Eval(1.0);
    EXPECT_NEAR(p1.value, r.q_f, 1e-14 * r.q_f);
    EXPECT_EQ(p1.rate, 0.0);
    EXPECT_EQ(p1.accel, 0.0);
    EXPECT_NEAR(p.Eval(1.0 - 1e-9).accel, -r.a, 1e-14 * r.a);
    EXPECT_NEAR(p(3.0), r.q_f, 1e-14 * r.q_f);
  }
  // A delayed, longer window: a = 4 q_f / T^2 with T = t1 - t0.
  const Profile late = Profile::BangBang(2.0, 4.0, 1.0);
  EXPECT_DOUBLE_EQ(late.Eval(2.0).accel, 1.0);
  EXPECT_DOUBLE_EQ(late(3.0), 0.5);
}

TEST(Profile, SumsOfTermsAddValuesRatesAndAccelerations) {
  Profile sum = Profile::BangBang(0.0, 1.0, 2.0);
  sum.Add(Profile::Sine(0.5, 2.0)).Add(Profile::Constant(-1.0));
  ProfileTerm ramp;
  ramp.kind = ProfileTerm::Kind::kRamp;
  ramp.t0 = 0.5;
  ramp.t1 = 2.5;
  ramp.scale = 3.0;
  sum.Add(ramp);
  ASSERT_EQ(sum.terms().size(), 4u);
  const Profile parts[] = {Profile::BangBang(0.0, 1.0, 2.0), Profile::Sine(0.5, 2.0),
                           Profile::Constant(-1.0), Profile::Ramp(0.5, 2.5, 3.0)};
  for (double t : {0.0, 0.3, 0.5, 0.77, 1.0, 1.9, 4.0}) {
    ProfileValue expect;
    for (const Profile& p : parts) {
      const ProfileValue v = p.Eval(t);
      expect.value += v.value;
      expect.rate += v.rate;
      expect.accel += v.accel;
    }
    const ProfileValue got = sum.Eval(t);
    EXPECT_NEAR(got.value, expect.value, 1e-14);
    EXPECT_NEAR(got.rate, expect.rate, 1e-13);
    EXPECT_NEAR(got.accel, expect.accel, 1e-12);
    EXPECT_DOUBLE_EQ(sum(t), got.value);
  }
  // Breakpoints are the sorted union without duplicates (0.5 appears twice).
  EXPECT_EQ(sum.Breakpoints(), (std::vector<double>{0.0, 0.5, 1.0, 2.5}));
}

TEST(Profile, BreakpointsOfEachKind) {
  EXPECT_TRUE(Profile::Constant(3.0).Breakpoints().empty());
  EXPECT_EQ(Profile::Ramp(1.0, 2.0).Breakpoints(), (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(Profile::BangBang(1.0, 2.0).Breakpoints(), (std::vector<double>{1.0, 1.5, 2.0}));
  EXPECT_EQ(Profile::SmoothStep(0.0, 3.0).Breakpoints(), (std::vector<double>{0.0, 3.0}));
  EXPECT_EQ(Profile::Sine(1.0, 1.0, 0.0, 0.25).Breakpoints(), (std::vector<double>{0.25}));
  EXPECT_EQ(Profile::Table({0.0, 0.4, 2.0}, {1.0, 2.0, 3.0}).Breakpoints(),
            (std::vector<double>{0.0, 0.4, 2.0}));
}

TEST(Profile, ValidateThrowsInputErrorOnBadParameters) {
  EXPECT_NO_THROW(Profile::BangBang(0.0, 1.0, 2.0).Validate("ok"));
  EXPECT_THROW(Profile::BangBang(1.0, 1.0).Validate("joint 'q0'"), InputError);
  EXPECT_THROW(Profile::Ramp(2.0, 1.0).Validate("x"), InputError);
  EXPECT_THROW(Profile::SmoothStep(0.0, NAN).Validate("x"), InputError);
  EXPECT_THROW(Profile::Constant(INFINITY).Validate("x"), InputError);
  EXPECT_THROW(Profile::Sine(1.0, NAN).Validate("x"), InputError);
  EXPECT_THROW(Profile::Table({0.0}, {1.0}).Validate("x"), InputError);
  EXPECT_THROW(Profile::Table({0.0, 1.0}, {1.0}).Validate("x"), InputError);
  EXPECT_THROW(Profile::Table({0.0, 0.0}, {1.0, 2.0}).Validate("x"), InputError);
  EXPECT_THROW(Profile::Table({0.0, 1.0}, {1.0, NAN}).Validate("x"), InputError);
  // The message names the place given by the caller.
  try {
    Profile::BangBang(1.0, 0.5).Validate("joint 'q0' drive");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'q0' drive"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace screwfem::profile_test
