// screwfem against MuJoCo on a spatial spring chain (issue 14, "Benchmarks"; bench/RESULTS.md,
// "Spring chain against MuJoCo").
//
// The model is that of tests/validation/spring_chain_test.cpp: three rigid links (m = 0.15 kg,
// J = diag(1e-4, 2e-4, 3e-4) kg m^2 about the CoM, CoM at mid-link, 0.5 m long along x) from
// the ground: a spherical joint at the origin (springs 2 N m/rad on the rotation vector), a
// universal joint at x = 0.5 (axes z then y, springs 3 N m/rad towards 0.4 and -0.3 rad) and a
// revolute joint about (0, 1, 1)/sqrt2 at x = 1 (spring 1 N m/rad towards 0.5 rad); gravity
// -z, released at rest, no damping. In MuJoCo (MJCF built below) the spherical joint is a ball
// joint (its spring -k log(q) is the gradient of the same energy k/2 |theta|^2), the universal
// joint two hinges in one body (MuJoCo composes a body's joints in order: R_z(a1) R_y(a2), as
// screwfem's H_J = exp(a1 A_1) exp(a2 A_2)).
//
// What it does (all in one process):
//  1. reference: MuJoCo RK4 at h = 8 ms / 256; agreement: screwfem at tiny steps against it
//     (the difference must fall at screwfem's order, 2, towards round-off level);
//  2. the error of MuJoCo RK4 at 8 ms: the largest distance over the run between the three
//     link ends and the reference's, sampled every 8 ms;
//  3. for each screwfem variant (fixed step or `step: auto`, index 3 or GGL, rho_inf), the
//     cheapest setting on a grid (largest fixed step dividing 8 ms, loosest tolerance) whose
//     error is at most MuJoCo's;
//  4. wall time of a whole run (reset + simulation + sampling) of MuJoCo at 8 ms and of each
//     selected screwfem setting, interleaved in rounds (A B C ... A B C ...), medians and
//     ratios to MuJoCo.
// Usage: screwfem_bench_mujoco [--horizon T] [--rounds N] [--block-ms B]
//                              [--base spherical|revolute|spherical-nospring]
//                              [--profile mujoco|screwfem]
//                              [--profile-step H]
#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "mujoco_common.h"

namespace screwfem::mujoco_bench {
namespace {

using mujoco_common::LoadMjcf;
using mujoco_common::MaxDistance;
using mujoco_common::Median;
using mujoco_common::MjDataDeleter;
using mujoco_common::MjModelDeleter;
using mujoco_common::Trajectory;

constexpr double kSample = 8e-3;  // sampling interval = MuJoCo's step [s]
constexpr double kLinkLength = 0.5;
// --base revolute: the spherical joint at the ground replaced by a revolute joint about y with
// the same spring (2 N m/rad); a control model without screwfem's spherical-joint spring
// (bench/RESULTS.md: with it screwfem converges at first order only).
bool g_revolute_base = false;
// --base spherical-nospring: the spherical joint without its spring (a second control model).
bool g_no_base_spring = false;

// Trajectories: the three link end points at the sample times k * kSample, 9 values per sample.

// ---- MuJoCo ----

const char* kMjcf = R"(<mujoco model="spring_chain">
  <compiler angle="radian"/>
  <option timestep="0.008" integrator="RK4" gravity="0 0 -9.81">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="link0" pos="0 0 0">
      <joint name="s" type="ball" stiffness="2"/>
      <inertial pos="0.25 0 0" mass="0.15" diaginertia="1e-4 2e-4 3e-4"/>
      <body name="link1" pos="0.5 0 0">
        <joint name="u1" type="hinge" axis="0 0 1" stiffness="3" springref="0.4"/>
        <joint name="u2" type="hinge" axis="0 1 0" stiffness="3" springref="-0.3"/>
        <inertial pos="0.25 0 0" mass="0.15" diaginertia="1e-4 2e-4 3e-4"/>
        <body name="link2" pos="0.5 0 0">
          <joint name="r" type="hinge" axis="0 1 1" stiffness="1" springref="0.5"/>
          <inertial pos="0.25 0 0" mass="0.15" diaginertia="1e-4 2e-4 3e-4"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
)";

std::unique_ptr<mjModel, MjModelDeleter> LoadMujocoModel() {
  std::string xml = kMjcf;
  if (g_no_base_spring) {
    const std::string spring = "type=\"ball\" stiffness=\"2\"";
    xml.replace(xml.find(spring), spring.size(), "type=\"ball\"");
  }
  if (g_revolute_base) {
    const std::string ball = "type=\"ball\"";
    xml.replace(xml.find(ball), ball.size(), "type=\"hinge\" axis=\"0 1 0\"");
  }
  return LoadMjcf(xml, "chain.xml");
}

struct MujocoRun {
  mjModel* m;
  mjData* d;
  // Runs to `horizon` with step h (kSample / h an integer), records the link ends every 8 ms.
  void Run(double h, double horizon, Trajectory* out) {
    m->opt.timestep = h;
    // The state only (mj_resetData also clears the whole arena, a memset of about 3.7 M
    // instructions, more than the 125 steps of a run cost together).
    d->time = 0.0;
    mju_copy(d->qpos, m->qpos0, m->nq);
    mju_zero(d->qvel, m->nv);
    mju_zero(d->qacc_warmstart, m->nv);
    const int per_sample = static_cast<int>(std::lround(kSample / h));
    const int samples = static_cast<int>(std::lround(horizon / kSample));
    out->resize(static_cast<std::size_t>(9 * samples));
    for (int s = 0; s < samples; ++s) {
      for (int k = 0; k < per_sample; ++k) mj_step(m, d);
      // mj_step leaves xpos and xmat at the step's start (its mj_forward runs before the
      // integration): the kinematics of the new qpos.
      mj_kinematics(m, d);
      for (int b = 0; b < 3; ++b) {
        const mjtNum* x = d->xpos + 3 * (b + 1);
        const mjtNum* R = d->xmat + 9 * (b + 1);  // row-major
        for (int c = 0; c < 3; ++c)
          (*out)[static_cast<std::size_t>(9 * s + 3 * b + c)] = x[c] + kLinkLength * R[3 * c];
      }
    }
  }
  double Energy() {  // at d's state (mj_forward computes it with the energy flag)
    m->opt.enableflags |= mjENBL_ENERGY;
    mj_forward(m, d);
    m->opt.enableflags &= ~mjENBL_ENERGY;
    return d->energy[0] + d->energy[1];
  }
};

// ---- screwfem ----

Model BuildChain() {
  ModelBuilder b;
  const Mat3 J = Vec3(1e-4, 2e-4, 3e-4).asDiagonal();
  NodeId nodes[3];
  const char* node_names[3] = {"n0", "n1", "n2"};
  const char* link_names[3] = {"link0", "link1", "link2"};
  for (int i = 0; i < 3; ++i) {
    nodes[i] = b.AddNode(SE3::Translation(Vec3(0.5 * i, 0.0, 0.0)), node_names[i]);
    b.AddRigidBody(link_names[i], nodes[i], 0.15, Vec3(0.25, 0.0, 0.0), J);
  }
  const int s =
      g_revolute_base
          ? b.AddJointAt("s", JointType::kRevolute, kGround, nodes[0], Vec3::Zero(), Vec3::UnitY())
          : b.AddJointAt("s", JointType::kSpherical, kGround, nodes[0], Vec3::Zero());
  const JointId u = b.AddJointAt("u", JointType::kUniversal, nodes[0], nodes[1], Vec3(0.5, 0, 0),
                                 Vec3::UnitZ(), Vec3::UnitY());
  const JointId r = b.AddJointAt("r", JointType::kRevolute, nodes[1], nodes[2], Vec3(1.0, 0, 0),
                                 Vec3(0.0, 1.0, 1.0).normalized());
  Joint& js = b.model().joints[static_cast<std::size_t>(s)];
  js.stiffness.head(js.k()).setConstant(g_no_base_spring ? 0.0 : 2.0);
  Joint& ju = b.model().joints[u];
  ju.stiffness.head<2>().setConstant(3.0);
  ju.rest.head<2>() << 0.4, -0.3;
  Joint& jr = b.model().joints[r];
  jr.stiffness(0) = 1.0;
  jr.rest(0) = 0.5;
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  return b.Build();
}

struct Setting {
  bool adaptive = false;
  double h = 1e-3;          // fixed step [s] (kSample / h an integer)
  double tolerance = 1e-6;  // adaptive: absolute and relative tolerance
  ConstraintFormulation constraints = ConstraintFormulation::kIndex3;
  double rho_inf = 0.9;
};

std::string Format(const Setting& s) {
  char buf[160];
  if (s.adaptive)
    std::snprintf(buf, sizeof(buf), "auto, tol %.3g, %s, rho_inf %.2g", s.tolerance,
                  s.constraints == ConstraintFormulation::kGgl ? "GGL" : "index 3", s.rho_inf);
  else
    std::snprintf(buf, sizeof(buf), "h = %.4g ms, %s, rho_inf %.2g", s.h * 1e3,
                  s.constraints == ConstraintFormulation::kGgl ? "GGL" : "index 3", s.rho_inf);
  return buf;
}

struct ScrewfemRun {
  const Model& model;
  Data data, out;
  Integrator integ;
  long steps = 0, iterations = 0, rejected = 0;
  explicit ScrewfemRun(const Model& m) : model(m), data(MakeData(m)), out(MakeData(m)) {}

  void Record(const Data& d, int s, Trajectory* traj) const {
    for (int b = 0; b < 3; ++b) {
      const Vec3 p = d.H[static_cast<std::size_t>(b)].Act(Vec3(kLinkLength, 0.0, 0.0));
      for (int c = 0; c < 3; ++c) (*traj)[static_cast<std::size_t>(9 * s + 3 * b + c)] = p(c);
    }
  }
  // false if a step failed.
  bool Run(const Setting& setting, double horizon, Trajectory* traj) {
    data = MakeData(model);
    const long steps0 = integ.steps, iterations0 = integ.iterations, rejected0 = integ.rejected;
    DynamicOptions opt;
    opt.rho_inf = setting.rho_inf;
    opt.constraints = setting.constraints;
    opt.absolute_tolerance = setting.tolerance;
    opt.relative_tolerance = setting.tolerance;
    std::string message;
    if (!InitializeDynamics(model, data, integ, opt, &message))
      throw std::runtime_error("InitializeDynamics: " + message);
    const int samples = static_cast<int>(std::lround(horizon / kSample));
    traj->resize(static_cast<std::size_t>(9 * samples));
    const bool ok =
        mujoco_common::RunSampled(model, data, out, integ, setting.adaptive, setting.h, kSample,
                                  horizon, [&](const Data& d, int s) { Record(d, s, traj); });
    steps = integ.steps - steps0;
    iterations = integ.iterations - iterations0;
    rejected = integ.rejected - rejected0;
    return ok;
  }
};

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

int Main(int argc, char** argv) {
  double horizon = 1.0;
  int rounds = 11;
  double block = 0.05;  // [s] of timed runs per variant per round
  // --profile mujoco|screwfem: only 20 runs of MuJoCo at 8 ms or of screwfem at its setting
  // matching MuJoCo's accuracy on the spherical chain (h = 1.6 ms, index 3, rho_inf 0.9;
  // --profile-step H for another fixed step), for perf or callgrind.
  std::string profile;
  double profile_step = 1.6e-3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--horizon")
      horizon = std::atof(argv[i + 1]);
    else if (a == "--rounds")
      rounds = std::atoi(argv[i + 1]);
    else if (a == "--block-ms")
      block = 1e-3 * std::atof(argv[i + 1]);
    else if (a == "--profile")
      profile = argv[i + 1];
    else if (a == "--profile-step")
      profile_step = std::atof(argv[i + 1]);
    else if (a == "--base" && std::string(argv[i + 1]) == "revolute")
      g_revolute_base = true;
    else if (a == "--base" && std::string(argv[i + 1]) == "spherical-nospring")
      g_no_base_spring = true;
    else if (a == "--base" && std::string(argv[i + 1]) == "spherical")
      g_revolute_base = false;
    else {
      std::fprintf(stderr,
                   "usage: %s [--horizon T] [--rounds N] [--block-ms B]\n"
                   "       [--base spherical|revolute|spherical-nospring]\n"
                   "       [--profile mujoco|screwfem] [--profile-step H]\n",
                   argv[0]);
      return 2;
    }
  }
  std::printf("MuJoCo %s (header %d); horizon %g s, link ends sampled every %g ms; base joint %s\n",
              mj_versionString(), mjVERSION_HEADER, horizon, kSample * 1e3,
              g_revolute_base    ? "revolute (about y)"
              : g_no_base_spring ? "spherical without spring"
                                 : "spherical");

  auto mjm = LoadMujocoModel();
  std::unique_ptr<mjData, MjDataDeleter> mjd(mj_makeData(mjm.get()));
  MujocoRun mj{mjm.get(), mjd.get()};
  const Model model = BuildChain();
  ScrewfemRun sf(model);

  Trajectory ref, ref2, traj;
  if (!profile.empty()) {
    const Setting s{false, profile_step, 0, ConstraintFormulation::kIndex3, 0.9};
    for (int k = 0; k < 20; ++k) {
      if (profile == "mujoco")
        mj.Run(kSample, horizon, &traj);
      else
        sf.Run(s, horizon, &traj);
    }
    std::printf("%s: 20 runs of %g s\n",
                profile == "mujoco" ? "MuJoCo RK4, h = 8 ms" : Format(s).c_str(), horizon);
    return 0;
  }
  // 1. Reference and agreement.
  mj.Run(kSample / 256, horizon, &ref);
  mj.Run(kSample / 128, horizon, &ref2);
  std::printf("\n## Reference: MuJoCo RK4 at h = 8 ms / 256 = %.4g ms\n", kSample / 256 * 1e3);
  std::printf("MuJoCo RK4 8 ms/128 vs 8 ms/256: %.3g m (its own error)\n", MaxDistance(ref2, ref));
  mj.Run(kSample, horizon, &traj);
  const double mj_error = MaxDistance(traj, ref);
  double mj_e0 = 0.0;
  {
    mj.Run(kSample / 256, 0.0, &traj);
    mj_e0 = mj.Energy();
    mj.Run(kSample / 256, horizon, &traj);
    std::printf("MuJoCo energy at 0 / %g s (h = 8 ms/256): %.9f / %.9f J\n", horizon, mj_e0,
                mj.Energy());
  }
  for (ConstraintFormulation c : {ConstraintFormulation::kGgl, ConstraintFormulation::kIndex3}) {
    for (double rho : {c == ConstraintFormulation::kGgl ? 1.0 : 0.9}) {
      Trajectory previous;
      for (int k : {64, 128, 256, 512}) {
        const Setting s{false, kSample / k, 0, c, rho};
        if (!sf.Run(s, horizon, &traj)) throw std::runtime_error("screwfem failed: " + Format(s));
        std::printf("agreement: screwfem %-32s vs reference: %9.3g m", Format(s).c_str(),
                    MaxDistance(traj, ref));
        if (!previous.empty())
          std::printf(", vs screwfem at 2h: %9.3g m", MaxDistance(traj, previous));
        std::printf("\n");
        previous = traj;
      }
    }
  }
  std::printf(
      "screwfem energy at 0: %.9f J (MuJoCo %.9f J)\n",
      [&] {
        Data d = MakeData(model);
        return CalcEnergy(model, d).total();
      }(),
      mj_e0);

  // 2. MuJoCo's error at 8 ms (and at other steps, for the order).
  std::printf("\n## MuJoCo RK4 error (max link-end distance to the reference)\n");
  for (int k : {1, 2, 4}) {
    mj.Run(kSample / k, horizon, &traj);
    std::printf("h = %g ms: %.3g m\n", kSample / k * 1e3, MaxDistance(traj, ref));
  }
  std::printf("target: %.3g m\n", mj_error);

  // 3. The cheapest setting of each screwfem variant at MuJoCo's error.
  struct Variant {
    const char* name;
    bool adaptive;
    ConstraintFormulation constraints;
    double rho_inf;
  };
  const Variant variants[] = {
      {"fixed, index 3, rho_inf 0.9", false, ConstraintFormulation::kIndex3, 0.9},
      {"fixed, GGL, rho_inf 1", false, ConstraintFormulation::kGgl, 1.0},
      {"fixed, GGL, rho_inf 0.9", false, ConstraintFormulation::kGgl, 0.9},
      {"auto, index 3, rho_inf 0.9", true, ConstraintFormulation::kIndex3, 0.9},
      {"auto, GGL, rho_inf 1", true, ConstraintFormulation::kGgl, 1.0},
  };
  const int divisors[] = {1,  2,  3,  4,  5,  6,   8,   10,  12,  16,  20,  24, 32,
                          40, 48, 64, 80, 96, 128, 160, 192, 256, 320, 384, 512};
  std::vector<double> tolerances;
  for (double t = 1e-2; t > 1e-12; t /= std::sqrt(10.0)) tolerances.push_back(t);
  std::vector<Setting> chosen;
  std::vector<std::string> chosen_names;
  std::printf("\n## screwfem settings (error, steps, Newton iterations)\n");
  for (const Variant& v : variants) {
    std::printf("%s:\n", v.name);
    const std::size_t n = v.adaptive ? tolerances.size() : std::size(divisors);
    for (std::size_t i = 0; i < n; ++i) {
      Setting s{v.adaptive, v.adaptive ? 0.0 : kSample / divisors[i],
                v.adaptive ? tolerances[i] : 0.0, v.constraints, v.rho_inf};
      const bool ok = sf.Run(s, horizon, &traj);
      const double e = ok ? MaxDistance(traj, ref) : INFINITY;
      std::printf("  %-40s error %9.3g m  steps %6ld  iterations %6ld  rejected %ld%s\n",
                  Format(s).c_str(), e, sf.steps, sf.iterations, sf.rejected,
                  ok ? "" : "  (failed)");
      if (ok && e <= mj_error) {
        chosen.push_back(s);
        chosen_names.push_back(v.name);
        break;
      }
    }
  }

  // 4. Interleaved wall time.
  std::printf("\n## Wall time of one run of %g s (reset, simulation, sampling), %d rounds\n",
              horizon, rounds);
  const std::size_t nv = chosen.size() + 1;  // 0: MuJoCo
  auto run_variant = [&](std::size_t i) {
    if (i == 0)
      mj.Run(kSample, horizon, &traj);
    else
      sf.Run(chosen[i - 1], horizon, &traj);
  };
  // Repetitions per block from one calibration run each.
  std::vector<int> reps(nv);
  for (std::size_t i = 0; i < nv; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    run_variant(i);
    const double t = Seconds(std::chrono::steady_clock::now() - t0);
    reps[i] = std::max(1, static_cast<int>(block / std::max(t, 1e-9)));
  }
  std::vector<std::vector<double>> times(nv), ratios(nv);
  for (int r = 0; r < rounds; ++r) {
    std::vector<double> per_run(nv);
    for (std::size_t i = 0; i < nv; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < reps[i]; ++k) run_variant(i);
      per_run[i] = Seconds(std::chrono::steady_clock::now() - t0) / reps[i];
      times[i].push_back(per_run[i]);
    }
    for (std::size_t i = 0; i < nv; ++i) ratios[i].push_back(per_run[i] / per_run[0]);
  }
  const double mj_median = Median(times[0]);
  std::printf(
      "| variant | setting | error [m] | steps | Newton it. | median wall per run | "
      "per step | ratio to MuJoCo (median of rounds) |\n");
  mj.Run(kSample, horizon, &traj);
  std::printf("| MuJoCo RK4 | h = 8 ms | %.3g | %d | – | %.4g ms | %.3g us | 1 |\n",
              MaxDistance(traj, ref), static_cast<int>(std::lround(horizon / kSample)),
              mj_median * 1e3, mj_median / (horizon / kSample) * 1e6);
  for (std::size_t i = 1; i < nv; ++i) {
    sf.Run(chosen[i - 1], horizon, &traj);
    const double med = Median(times[i]);
    std::printf("| screwfem %s | %s | %.3g | %ld | %ld | %.4g ms | %.3g us | %.1f |\n",
                chosen_names[i - 1].c_str(), Format(chosen[i - 1]).c_str(), MaxDistance(traj, ref),
                sf.steps, sf.iterations, med * 1e3, med / sf.steps * 1e6, Median(ratios[i]));
  }
  return 0;
}

}  // namespace
}  // namespace screwfem::mujoco_bench

int main(int argc, char** argv) {
  try {
    return screwfem::mujoco_bench::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "screwfem_bench_mujoco: %s\n", e.what());
    return 1;
  }
}
