#include "screwfem/model/profile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

// One switch over the term kinds (about 90 lines): each case is a few lines of closed-form value,
// rate and acceleration, which read best side by side (as in Validate() and Breakpoints()).
ProfileValue EvalTerm(const ProfileTerm& p, double t, const Eigen::VectorXd* inputs) {
  ProfileValue r;
  const double s = p.scale;
  switch (p.kind) {
    case ProfileTerm::Kind::kConstant:
      r.value = s;
      break;
    case ProfileTerm::Kind::kRamp: {
      const double T = p.t1 - p.t0;
      if (t < p.t0) break;
      if (t < p.t1) {
        r.value = s * (t - p.t0) / T;
        r.rate = s / T;
      } else {
        r.value = s;
      }
      break;
    }
    case ProfileTerm::Kind::kBangBang: {
      // The pieces are chosen by comparing t with the breakpoints themselves (the values
      // Breakpoints() returns), so that Eval(b) is the right limit at a breakpoint b and
      // EvalLeft(b) the left one, whatever the rounding of t - t0 (docs/numerics.md, "Restarts at breakpoints").
      const double T = p.t1 - p.t0, tau = t - p.t0;
      const double a = 4.0 * s / (T * T);
      if (t < p.t0) break;
      if (t < 0.5 * (p.t0 + p.t1)) {
        r.value = 0.5 * a * tau * tau;
        r.rate = a * tau;
        r.accel = a;
      } else if (t < p.t1) {
        const double rem = T - tau;
        r.value = s - 0.5 * a * rem * rem;
        r.rate = a * rem;
        r.accel = -a;
      } else {
        r.value = s;
      }
      break;
    }
    case ProfileTerm::Kind::kSmoothStep: {
      const double T = p.t1 - p.t0, u = (t - p.t0) / T;
      if (t < p.t0) break;
      if (t < p.t1) {
        const double u2 = u * u, u3 = u2 * u;
        r.value = s * u3 * (10.0 - 15.0 * u + 6.0 * u2);
        r.rate = s * 30.0 * u2 * (1.0 - u) * (1.0 - u) / T;
        r.accel = s * 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (T * T);
      } else {
        r.value = s;
      }
      break;
    }
    case ProfileTerm::Kind::kSine: {
      if (t < p.t0) break;
      const double w = 2.0 * std::numbers::pi * p.frequency;
      const double arg = w * (t - p.t0) + p.phase;
      r.value = s * std::sin(arg);
      r.rate = s * w * std::cos(arg);
      r.accel = -s * w * w * std::sin(arg);
      break;
    }
    case ProfileTerm::Kind::kTable: {
      const auto& ts = p.times;
      const auto& vs = p.values;
      // Before the first time: constant (rate 0); at it, the first segment's slope (right-
      // continuous, as every other kind at its start time).
      if (t < ts.front()) {
        r.value = s * vs.front();
        break;
      }
      if (t >= ts.back()) {
        r.value = s * vs.back();
        break;
      }
      // Right-continuous: the segment [ts[i], ts[i+1]) that contains t.
      const auto it = std::upper_bound(ts.begin(), ts.end(), t);
      const auto i = static_cast<std::size_t>(it - ts.begin()) - 1;
      const double slope = (vs[i + 1] - vs[i]) / (ts[i + 1] - ts[i]);
      r.value = s * (vs[i] + slope * (t - ts[i]));
      r.rate = s * slope;
      break;
    }
    case ProfileTerm::Kind::kInput:
      if (inputs == nullptr || p.input < 0 || p.input >= inputs->size())
        throw std::logic_error(
            "a profile that takes a run-time input was evaluated without the input values "
            "(use EvalProfile(profile, t, data))");
      r.value = s * (*inputs)(p.input);
      break;
  }
  return r;
}

}  // namespace

Profile Profile::Constant(double value) {
  ProfileTerm t;
  t.kind = ProfileTerm::Kind::kConstant;
  t.scale = value;
  return Profile().Add(t);
}

namespace {
Profile Windowed(ProfileTerm::Kind kind, double t0, double t1, double scale) {
  ProfileTerm t;
  t.kind = kind;
  t.t0 = t0;
  t.t1 = t1;
  t.scale = scale;
  return Profile().Add(t);
}
}  // namespace

Profile Profile::Ramp(double t0, double t1, double scale) {
  return Windowed(ProfileTerm::Kind::kRamp, t0, t1, scale);
}
Profile Profile::BangBang(double t0, double t1, double scale) {
  return Windowed(ProfileTerm::Kind::kBangBang, t0, t1, scale);
}
Profile Profile::SmoothStep(double t0, double t1, double scale) {
  return Windowed(ProfileTerm::Kind::kSmoothStep, t0, t1, scale);
}
Profile Profile::Sine(double amplitude, double frequency, double phase, double t0) {
  ProfileTerm t;
  t.kind = ProfileTerm::Kind::kSine;
  t.scale = amplitude;
  t.frequency = frequency;
  t.phase = phase;
  t.t0 = t0;
  return Profile().Add(t);
}
Profile Profile::Table(std::vector<double> times, std::vector<double> values, double scale) {
  ProfileTerm t;
  t.kind = ProfileTerm::Kind::kTable;
  t.scale = scale;
  t.times = std::move(times);
  t.values = std::move(values);
  return Profile().Add(t);
}

Profile Profile::Input(int input, double scale) {
  ProfileTerm t;
  t.kind = ProfileTerm::Kind::kInput;
  t.scale = scale;
  t.input = input;
  return Profile().Add(t);
}

Profile& Profile::Add(const ProfileTerm& term) {
  terms_.push_back(term);
  return *this;
}
Profile& Profile::Add(const Profile& other) {
  terms_.insert(terms_.end(), other.terms_.begin(), other.terms_.end());
  return *this;
}

void Profile::Validate(const char* where, int num_inputs) const {
  const std::string w(where);
  for (const ProfileTerm& p : terms_) {
    if (!std::isfinite(p.scale)) throw InputError(w + ": profile scale must be finite");
    switch (p.kind) {
      case ProfileTerm::Kind::kRamp:
      case ProfileTerm::Kind::kBangBang:
      case ProfileTerm::Kind::kSmoothStep:
        if (!std::isfinite(p.t0) || !std::isfinite(p.t1) || !(p.t1 > p.t0))
          throw InputError(w + ": profile needs finite start and end times with end > start");
        break;
      case ProfileTerm::Kind::kSine:
        if (!std::isfinite(p.frequency) || !std::isfinite(p.phase) || !std::isfinite(p.t0))
          throw InputError(w + ": sine profile needs finite frequency, phase and start");
        break;
      case ProfileTerm::Kind::kTable:
        if (p.times.size() < 2 || p.times.size() != p.values.size())
          throw InputError(w + ": table profile needs at least two (time, value) pairs");
        for (std::size_t i = 0; i < p.times.size(); ++i) {
          if (!std::isfinite(p.times[i]) || !std::isfinite(p.values[i]))
            throw InputError(w + ": table profile entries must be finite");
          if (i > 0 && !(p.times[i] > p.times[i - 1]))
            throw InputError(w + ": table profile times must be strictly increasing");
        }
        break;
      case ProfileTerm::Kind::kInput:
        if (p.input < 0 || p.input >= num_inputs)
          throw InputError(w + ": profile takes input #" + std::to_string(p.input) +
                           ", but the model has " + std::to_string(num_inputs) + " inputs");
        break;
      case ProfileTerm::Kind::kConstant:
        break;
    }
  }
}

namespace {
ProfileValue Sum(const std::vector<ProfileTerm>& terms, double t, const Eigen::VectorXd* inputs) {
  ProfileValue sum;
  for (const ProfileTerm& p : terms) {
    const ProfileValue v = EvalTerm(p, t, inputs);
    sum.value += v.value;
    sum.rate += v.rate;
    sum.accel += v.accel;
  }
  return sum;
}
}  // namespace

ProfileValue Profile::Eval(double t, const Eigen::VectorXd& inputs) const {
  return Sum(terms_, t, &inputs);
}
ProfileValue Profile::EvalLeft(double t, const Eigen::VectorXd& inputs) const {
  return Sum(terms_, std::nextafter(t, -std::numeric_limits<double>::infinity()), &inputs);
}
ProfileValue Profile::Eval(double t) const { return Sum(terms_, t, nullptr); }
ProfileValue Profile::EvalLeft(double t) const {
  return Sum(terms_, std::nextafter(t, -std::numeric_limits<double>::infinity()), nullptr);
}

bool Profile::HasInputs() const {
  for (const ProfileTerm& p : terms_)
    if (p.kind == ProfileTerm::Kind::kInput) return true;
  return false;
}

std::vector<double> Profile::Breakpoints() const {
  std::vector<double> b;
  for (const ProfileTerm& p : terms_) {
    switch (p.kind) {
      case ProfileTerm::Kind::kRamp:
      case ProfileTerm::Kind::kSmoothStep:
        b.push_back(p.t0);
        b.push_back(p.t1);
        break;
      case ProfileTerm::Kind::kBangBang:
        b.push_back(p.t0);
        b.push_back(0.5 * (p.t0 + p.t1));
        b.push_back(p.t1);
        break;
      case ProfileTerm::Kind::kSine:
        b.push_back(p.t0);
        break;
      case ProfileTerm::Kind::kTable:
        b.insert(b.end(), p.times.begin(), p.times.end());
        break;
      case ProfileTerm::Kind::kInput:  // changes between steps only (docs/numerics.md)
      case ProfileTerm::Kind::kConstant:
        break;
    }
  }
  std::sort(b.begin(), b.end());
  b.erase(std::unique(b.begin(), b.end()), b.end());
  return b;
}

}  // namespace screwfem
