// Time profiles for loads and drives: a sum of terms, each a scale times a unit shape.
// In statics the "time" is the load factor s in [0, 1].
#pragma once

#include <vector>

#include <Eigen/Core>

namespace screwfem {

struct ProfileValue {
  double value = 0.0;  // f(t)
  double rate = 0.0;   // df/dt
  double accel = 0.0;  // d2f/dt2 (right limit at jumps)
};

struct ProfileTerm {
  enum class Kind {
    kConstant,    // scale
    kRamp,        // 0 before t0, linear to scale at t1, scale after
    kBangBang,    // triangular velocity / bang-bang acceleration from 0 to scale on [t0, t1]
                  // (the paper's point-to-point law and its "S-shaped" force law;
                  // docs/theory.md §4.4)
    kSmoothStep,  // quintic C2 step 10u^3 - 15u^4 + 6u^5 from 0 to scale on [t0, t1]
    kSine,        // scale * sin(2 pi frequency (t - t0) + phase) for t >= t0, 0 before
    kTable,       // piecewise-linear through (times[i], values[i]) * scale, held constant outside
    kInput,       // scale * u, u the value of run-time input `input` (Data::inputs; constant
                  // between steps: zero rate and acceleration, no breakpoints)
  };
  Kind kind = Kind::kConstant;
  double scale = 1.0;
  double t0 = 0.0, t1 = 1.0;
  double frequency = 0.0, phase = 0.0;
  std::vector<double> times, values;  // kTable only
  int input = -1;                     // kInput only: index into Model::inputs
};

// Sum of terms. Right-continuous: at a switch time Eval returns the derivatives that hold just
// after it (the right limit needed for consistent initial accelerations, docs/numerics.md, "Restarts at breakpoints").
class Profile {
 public:
  Profile() = default;
  static Profile Constant(double value = 1.0);
  static Profile Ramp(double t0, double t1, double scale = 1.0);
  static Profile BangBang(double t0, double t1, double scale = 1.0);
  static Profile SmoothStep(double t0, double t1, double scale = 1.0);
  static Profile Sine(double amplitude, double frequency, double phase = 0.0, double t0 = 0.0);
  static Profile Table(std::vector<double> times, std::vector<double> values, double scale = 1.0);
  // scale * (value of run-time input number `input`, Model::inputs).
  static Profile Input(int input, double scale = 1.0);

  Profile& Add(const ProfileTerm& term);
  Profile& Add(const Profile& other);
  // Validates the parameters; throws InputError naming the problem, prefixed by `where`.
  // Input terms must refer to one of `num_inputs` inputs.
  void Validate(const char* where, int num_inputs = 0) const;

  // The value at time t, with `inputs` the values of the model's run-time inputs (Data::inputs;
  // kernels and solvers call EvalProfile(profile, t, data), model/data.h, which passes them).
  ProfileValue Eval(double t, const Eigen::VectorXd& inputs) const;
  // The left limit at t: the pieces that end at t (at a breakpoint b, EvalLeft(b) is the state
  // just before the switch, Eval(b) the state just after it). Evaluated at the double below t,
  // so value and rate are those at t to within one unit in the last place of t.
  ProfileValue EvalLeft(double t, const Eigen::VectorXd& inputs) const;
  // Without input values: for profiles that take no input (HasInputs() false). A profile that
  // takes one throws std::logic_error (a caller that should have used EvalProfile).
  ProfileValue Eval(double t) const;
  ProfileValue EvalLeft(double t) const;
  double operator()(double t) const { return Eval(t).value; }
  bool HasInputs() const;
  const std::vector<ProfileTerm>& terms() const { return terms_; }
  // Times where the second derivative (or the value or rate) may jump, sorted, without
  // duplicates: the time steps land on them (align_steps) and the integrator restarts there
  // (DynamicOptions::restart_at_breakpoints).
  std::vector<double> Breakpoints() const;

 private:
  std::vector<ProfileTerm> terms_;
};

}  // namespace screwfem
