// screwfem against MuJoCo on a box dropped onto a plane and sliding to rest (issue 37,
// "Benchmarks"; bench/RESULTS.md, "Sliding box against MuJoCo").
//
// The model, the same in both codes: a 1 kg cube of half size 0.1 m (J = m (2a)^2 / 6 =
// 0.0066667 kg m^2 about its centre), its centre released at z = 0.15 m (5 cm drop) with
// v = (2, 0, 0) m/s over the plane z = 0, gravity 9.81 m/s^2 down, Coulomb friction mu = 0.4
// (static = kinetic). It lands at 0.10 s and slides v^2 / (2 mu g) = 0.51 m, to rest at about
// 0.6 s. Contact: a spring-damper at each of the four corners that touch, total normal stiffness
// 4e4 N/m (the box's normal mode at 200 rad/s), critically damped, the force starting at gap 0
// (screwfem: k_n = 1e4 N/m per corner, onset 1e-4 m, damping ratio 0.5 per corner, that is 1 for
// the four; the stick law with k_t = k_n. MuJoCo: solref = (-4e4, -400), the reference
// acceleration -b v - k r of a critically damped 1 kg on 4e4 N/m, and solimp (0.99, 0.99,
// 0.001) so that the constraint follows it; pyramidal cones, condim 3). Each code's contact
// regularisation differs in its details (MuJoCo's soft constraints, screwfem's penalty law
// with an elastic stick anchor), so each is measured against its own fine run.
//
// What it does (all in one process):
//  1. each code's reference: MuJoCo (Euler) and screwfem at h = 1e-5 s; their own convergence
//     (against h = 2e-5 s);
//  2. the error of a setting: the largest distance over the run between the box centre and
//     its reference's, sampled every 10 ms;
//  3. for each accuracy target (1 cm, 1 mm) and each variant (MuJoCo Euler and RK4, screwfem
//     at fixed steps and at `step: auto`), the cheapest setting on a grid (the largest step
//     dividing 10 ms, or the loosest tolerance) within the target;
//  4. the CPU and wall time of the stepping loop (reset excluded; the sampling of the centre
//     included, a copy of 3 numbers per 10 ms) of each selected setting, interleaved in rounds
//     (A B C ... A B C ...), medians, and the median over rounds of each setting's ratio to
//     the fastest MuJoCo setting of its target in that round.
// Usage: screwfem_bench_mujoco_box [--horizon T] [--rounds N] [--block-ms B] [--json FILE]
//                                  [--revision REV] [--profile mujoco|screwfem]
//                                  [--profile-step H]
#include <mujoco/mujoco.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "screwfem/io/scene.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "mujoco_common.h"

namespace screwfem::mujoco_box_bench {
namespace {

using mujoco_common::LoadMjcf;
using mujoco_common::MaxDistance;
using mujoco_common::Median;
using mujoco_common::MjDataDeleter;
using mujoco_common::MjModelDeleter;
using mujoco_common::Trajectory;

constexpr double kSample = 1e-2;      // sampling interval of the centre [s]
constexpr double kReferenceH = 1e-5;  // both codes' reference step [s]

// Trajectories: the centre at k * kSample, k = 1..n, 3 values per sample.

double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ---- MuJoCo ----

const char* kMjcf = R"(<mujoco model="sliding_box">
  <option timestep="0.001" integrator="Euler" gravity="0 0 -9.81" cone="pyramidal"/>
  <default>
    <geom solref="-40000 -400" solimp="0.99 0.99 0.001" friction="0.4 0 0" condim="3"/>
  </default>
  <worldbody>
    <geom name="ground" type="plane" size="10 10 0.1"/>
    <body name="box" pos="0 0 0.15">
      <freejoint/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.0066666667 0.0066666667 0.0066666667"/>
      <geom name="box" type="box" size="0.1 0.1 0.1" density="0"/>
    </body>
  </worldbody>
</mujoco>
)";

std::unique_ptr<mjModel, MjModelDeleter> LoadMujocoModel() { return LoadMjcf(kMjcf, "box.xml"); }

struct MujocoSetting {
  int integrator = mjINT_EULER;
  double h = 1e-3;
};

std::string Format(const MujocoSetting& s) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s, h = %.4g ms", s.integrator == mjINT_RK4 ? "RK4" : "Euler",
                s.h * 1e3);
  return buf;
}

struct MujocoRun {
  mjModel* m;
  mjData* d;
  long steps = 0;
  void Reset(const MujocoSetting& s) {
    m->opt.timestep = s.h;
    m->opt.integrator = s.integrator;
    mj_resetData(m, d);
    d->qvel[0] = 2.0;
  }
  // The stepping loop from the reset state to `horizon` (kSample / h an integer).
  void Run(const MujocoSetting& s, double horizon, Trajectory* out) {
    const int per_sample = static_cast<int>(std::lround(kSample / s.h));
    const int samples = static_cast<int>(std::lround(horizon / kSample));
    for (int k = 0; k < samples; ++k) {
      for (int j = 0; j < per_sample; ++j) mj_step(m, d);
      for (int c = 0; c < 3; ++c) (*out)[static_cast<std::size_t>(3 * k + c)] = d->qpos[c];
    }
    steps = static_cast<long>(samples) * per_sample;
  }
};

// ---- screwfem ----

std::string ScrewfemScene() {
  return R"(name: sliding box (bench/mujoco_box_bench.cpp)
gravity: [0, 0, -9.81]
bodies:
  box:
    type: rigid
    at: [0, 0, 0.15]
    mass: 1
    inertia: [0.0066666667, 0.0066666667, 0.0066666667]
    free: true
    initial_velocity: {linear: [2, 0, 0]}
    shapes: [{type: box, center: [0, 0, 0.15], half_sizes: [0.1, 0.1, 0.1]}]
contact:
  stiffness: 1e4
  onset: 1e-4
  damping_ratio: 0.5
  friction: 0.4
  obstacles:
    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
analysis: {type: dynamic, end_time: 1, step: 1e-3}
outputs: {vtk: false}
)";
}

struct ScrewfemSetting {
  bool adaptive = false;
  double h = 1e-3;          // fixed step [s]
  double tolerance = 1e-6;  // adaptive: absolute and relative tolerance
  double rho_inf = kAutoRhoInf;
};

std::string Format(const ScrewfemSetting& s) {
  char buf[128];
  const std::string rho = s.rho_inf < 0.0 ? std::string("rho_inf auto (0)")
                                          : "rho_inf " + std::to_string(s.rho_inf).substr(0, 4);
  if (s.adaptive)
    std::snprintf(buf, sizeof buf, "step: auto, tol %.3g, %s", s.tolerance, rho.c_str());
  else
    std::snprintf(buf, sizeof buf, "h = %.4g ms, %s", s.h * 1e3, rho.c_str());
  return buf;
}

struct ScrewfemRun {
  const Model& model;
  DynamicOptions base;
  Data data, out;
  Integrator integ;
  long steps = 0, iterations = 0, rejected = 0;
  long steps0 = 0, iterations0 = 0, rejected0 = 0;
  ScrewfemRun(const Model& m, const DynamicOptions& o)
      : model(m), base(o), data(MakeData(m)), out(MakeData(m)) {}

  void Reset(const ScrewfemSetting& s) {
    data = MakeData(model);
    std::string why;
    // The scene's initial velocity (as `screwfem run` sets it).
    if (!AssembleInitialState(model, data, &why))
      throw std::runtime_error("AssembleInitialState: " + why);
    DynamicOptions opt = base;
    opt.rho_inf = s.rho_inf;
    opt.absolute_tolerance = s.tolerance;
    opt.relative_tolerance = s.tolerance;
    std::string message;
    if (!InitializeDynamics(model, data, integ, opt, &message))
      throw std::runtime_error("InitializeDynamics: " + message);
    if (s.adaptive) PrepareAdaptiveSteps(model, data, integ);
    steps0 = integ.steps;
    iterations0 = integ.iterations;
    rejected0 = integ.rejected;
  }
  static void Record(const Data& d, int k, Trajectory* traj) {
    for (int c = 0; c < 3; ++c) (*traj)[static_cast<std::size_t>(3 * k + c)] = d.H[0].x(c);
  }
  // The stepping loop; false if a step failed.
  bool Run(const ScrewfemSetting& s, double horizon, Trajectory* traj) {
    const bool ok =
        mujoco_common::RunSampled(model, data, out, integ, s.adaptive, s.h, kSample, horizon,
                                  [&](const Data& d, int k) { Record(d, k, traj); });
    steps = integ.steps - steps0;
    iterations = integ.iterations - iterations0;
    rejected = integ.rejected - rejected0;
    return ok;
  }
};

std::string LoadAverage() {
  std::ifstream f("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  if (!(f >> a >> b >> c)) return "unknown";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f, %.2f, %.2f", a, b, c);
  return buf;
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

// A selected setting of one code for one target.
struct Chosen {
  std::string code, variant, setting;
  bool mujoco = false;
  MujocoSetting mj;
  ScrewfemSetting sf;
  double error = 0.0;
  long steps = 0, iterations = 0;
  std::vector<double> cpu, wall;  // per round, seconds per run
  std::vector<double> cpu_ratio, wall_ratio;
};

int Main(int argc, char** argv) {
  double horizon = 1.0;
  int rounds = 11;
  double block = 0.1;  // [s] of timed runs per setting per round
  std::string json_path, revision = "unknown", profile;
  double profile_step = 1e-3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--horizon")
      horizon = std::atof(argv[i + 1]);
    else if (a == "--rounds")
      rounds = std::atoi(argv[i + 1]);
    else if (a == "--block-ms")
      block = 1e-3 * std::atof(argv[i + 1]);
    else if (a == "--json")
      json_path = argv[i + 1];
    else if (a == "--revision")
      revision = argv[i + 1];
    else if (a == "--profile")
      profile = argv[i + 1];
    else if (a == "--profile-step")
      profile_step = std::atof(argv[i + 1]);
    else {
      std::fprintf(stderr,
                   "usage: %s [--horizon T] [--rounds N] [--block-ms B] [--json FILE]\n"
                   "       [--revision REV] [--profile mujoco|screwfem] [--profile-step H]\n",
                   argv[0]);
      return 2;
    }
  }
  const int samples = static_cast<int>(std::lround(horizon / kSample));
  std::printf("MuJoCo %s; horizon %g s, box centre sampled every %g ms\n", mj_versionString(),
              horizon, kSample * 1e3);

  auto mjm = LoadMujocoModel();
  std::unique_ptr<mjData, MjDataDeleter> mjd(mj_makeData(mjm.get()));
  MujocoRun mj{mjm.get(), mjd.get()};
  const Scene scene = ParseScene(ScrewfemScene(), "sliding_box.yaml");
  ScrewfemRun sf(scene.model, scene.analysis.dynamic);

  Trajectory traj(static_cast<std::size_t>(3 * samples));
  auto run_mj = [&](const MujocoSetting& s, Trajectory* t) {
    mj.Reset(s);
    mj.Run(s, horizon, t);
  };
  auto run_sf = [&](const ScrewfemSetting& s, Trajectory* t) {
    sf.Reset(s);
    return sf.Run(s, horizon, t);
  };
  if (!profile.empty()) {
    for (int k = 0; k < 20; ++k) {
      if (profile == "mujoco")
        run_mj({mjINT_EULER, profile_step}, &traj);
      else
        run_sf({false, profile_step, 0.0, kAutoRhoInf}, &traj);
    }
    std::printf("%s: 20 runs of %g s at h = %g s\n", profile.c_str(), horizon, profile_step);
    return 0;
  }

  // 1. References.
  Trajectory mj_ref(traj.size()), sf_ref(traj.size()), coarse(traj.size());
  run_mj({mjINT_EULER, kReferenceH}, &mj_ref);
  run_mj({mjINT_EULER, 2 * kReferenceH}, &coarse);
  const double mj_self = MaxDistance(coarse, mj_ref);
  if (!run_sf({false, kReferenceH, 0.0, kAutoRhoInf}, &sf_ref))
    throw std::runtime_error("screwfem reference run failed");
  run_sf({false, 2 * kReferenceH, 0.0, kAutoRhoInf}, &coarse);
  const double sf_self = MaxDistance(coarse, sf_ref);
  const double between = MaxDistance(mj_ref, sf_ref);
  const std::size_t last = traj.size() - 3;
  std::printf("\n## References (h = %g s)\n", kReferenceH);
  std::printf(
      "MuJoCo Euler: rest at x = %.5f m (closed form 0.5097 + the landing), own error "
      "(vs 2h) %.3g m\n",
      mj_ref[last], mj_self);
  std::printf("screwfem:     rest at x = %.5f m, own error (vs 2h) %.3g m\n", sf_ref[last],
              sf_self);
  std::printf("references apart by at most %.3g m over the run\n", between);

  // 2-3. The grids.
  const int divisors[] = {1,  2,  4,  5,   8,   10,  16,  20,  25,  32,  40,
                          50, 64, 80, 100, 125, 160, 200, 250, 400, 500, 1000};
  std::vector<double> tolerances;
  for (double t = 1e-1; t > 1e-9; t /= std::sqrt(10.0)) tolerances.push_back(t);
  const double targets[2] = {1e-2, 1e-3};
  std::vector<Chosen> chosen[2];
  std::printf("\n## Grids (error against the code's own reference)\n");
  for (int integrator : {mjINT_EULER, mjINT_RK4}) {
    bool found[2] = {false, false};
    for (int k : divisors) {
      const MujocoSetting s{integrator, kSample / k};
      run_mj(s, &traj);
      const double e = MaxDistance(traj, mj_ref);
      const bool finite = std::isfinite(e);
      std::printf("  MuJoCo %-22s error %9.3g m  steps %ld\n", Format(s).c_str(), e, mj.steps);
      for (int t = 0; t < 2; ++t)
        if (!found[t] && finite && e <= targets[t]) {
          found[t] = true;
          Chosen c;
          c.code = "MuJoCo";
          c.variant = integrator == mjINT_RK4 ? "RK4" : "Euler";
          c.setting = Format(s);
          c.mujoco = true;
          c.mj = s;
          c.error = e;
          c.steps = mj.steps;
          chosen[t].push_back(c);
        }
      if (found[0] && found[1]) break;
    }
  }
  struct Variant {
    const char* name;
    bool adaptive;
    double rho_inf;
  };
  const Variant variants[] = {{"fixed step, rho_inf auto", false, kAutoRhoInf},
                              {"fixed step, rho_inf 0.5", false, 0.5},
                              {"step: auto, rho_inf auto", true, kAutoRhoInf}};
  for (const Variant& v : variants) {
    bool found[2] = {false, false};
    const std::size_t n = v.adaptive ? tolerances.size() : std::size(divisors);
    for (std::size_t i = 0; i < n; ++i) {
      const ScrewfemSetting s{v.adaptive, v.adaptive ? 0.0 : kSample / divisors[i],
                              v.adaptive ? tolerances[i] : 0.0, v.rho_inf};
      const bool ok = run_sf(s, &traj);
      const double e = ok ? MaxDistance(traj, sf_ref) : INFINITY;
      std::printf("  screwfem %-38s error %9.3g m  steps %6ld  iterations %6ld  rejected %ld%s\n",
                  Format(s).c_str(), e, sf.steps, sf.iterations, sf.rejected,
                  ok ? "" : "  (failed)");
      for (int t = 0; t < 2; ++t)
        if (!found[t] && ok && e <= targets[t]) {
          found[t] = true;
          Chosen c;
          c.code = "screwfem";
          c.variant = v.name;
          c.setting = Format(s);
          c.sf = s;
          c.error = e;
          c.steps = sf.steps;
          c.iterations = sf.iterations;
          chosen[t].push_back(c);
        }
      if (found[0] && found[1]) break;
    }
  }

  // 4. Interleaved timing of the stepping loops (resets outside the timed part).
  std::vector<Chosen*> all;
  for (auto& list : chosen)
    for (Chosen& c : list) all.push_back(&c);
  std::vector<int> reps(all.size());
  auto timed = [&](Chosen& c, int n, double* cpu, double* wall) {
    *cpu = *wall = 0.0;
    for (int k = 0; k < n; ++k) {
      if (c.mujoco)
        mj.Reset(c.mj);
      else
        sf.Reset(c.sf);
      const double c0 = CpuSeconds(), w0 = WallSeconds();
      if (c.mujoco)
        mj.Run(c.mj, horizon, &traj);
      else
        sf.Run(c.sf, horizon, &traj);
      *cpu += CpuSeconds() - c0;
      *wall += WallSeconds() - w0;
    }
    *cpu /= n;
    *wall /= n;
  };
  for (std::size_t i = 0; i < all.size(); ++i) {
    double cpu, wall;
    timed(*all[i], 1, &cpu, &wall);
    reps[i] = std::max(1, static_cast<int>(block / std::max(cpu, 1e-9)));
  }
  for (int r = 0; r < rounds; ++r)
    for (std::size_t i = 0; i < all.size(); ++i) {
      double cpu, wall;
      timed(*all[i], reps[i], &cpu, &wall);
      all[i]->cpu.push_back(cpu);
      all[i]->wall.push_back(wall);
    }
  // Ratios per round to the fastest MuJoCo setting of the target in that round.
  for (auto& list : chosen)
    for (int r = 0; r < rounds; ++r) {
      double best_cpu = INFINITY, best_wall = INFINITY;
      for (const Chosen& c : list)
        if (c.mujoco) {
          best_cpu = std::min(best_cpu, c.cpu[static_cast<std::size_t>(r)]);
          best_wall = std::min(best_wall, c.wall[static_cast<std::size_t>(r)]);
        }
      for (Chosen& c : list) {
        c.cpu_ratio.push_back(c.cpu[static_cast<std::size_t>(r)] / best_cpu);
        c.wall_ratio.push_back(c.wall[static_cast<std::size_t>(r)] / best_wall);
      }
    }
  const std::string load = LoadAverage();
  std::printf("\n## Stepping loop of one %g s run, %d rounds (load average %s)\n", horizon, rounds,
              load.c_str());
  std::ostringstream js;
  js.precision(6);
  js << "{\n  \"format\": \"screwfem mujoco box bench 1\",\n  \"revision\": "
     << JsonString(revision) << ",\n  \"mujoco\": " << JsonString(mj_versionString())
     << ",\n  \"horizon\": " << horizon << ",\n  \"sample\": " << kSample
     << ",\n  \"rounds\": " << rounds << ",\n  \"load\": " << JsonString(load)
     << ",\n  \"reference_step\": " << kReferenceH << ",\n  \"mujoco_self_error\": " << mj_self
     << ",\n  \"screwfem_self_error\": " << sf_self << ",\n  \"references_apart\": " << between
     << ",\n  \"mujoco_rest_x\": " << mj_ref[last] << ",\n  \"screwfem_rest_x\": " << sf_ref[last]
     << ",\n  \"targets\": [";
  for (int t = 0; t < 2; ++t) {
    std::printf("target %g m:\n", targets[t]);
    std::printf(
        "| code | variant | setting | error [m] | steps | Newton it. | CPU per run | wall per "
        "run | CPU ratio | wall ratio |\n");
    js << (t ? ",\n" : "\n") << "    {\"target\": " << targets[t] << ", \"rows\": [";
    for (std::size_t i = 0; i < chosen[t].size(); ++i) {
      const Chosen& c = chosen[t][i];
      std::printf("| %s | %s | %s | %.3g | %ld | %ld | %.4g ms | %.4g ms | %.2f | %.2f |\n",
                  c.code.c_str(), c.variant.c_str(), c.setting.c_str(), c.error, c.steps,
                  c.iterations, Median(c.cpu) * 1e3, Median(c.wall) * 1e3, Median(c.cpu_ratio),
                  Median(c.wall_ratio));
      js << (i ? ",\n" : "\n") << "      {\"code\": " << JsonString(c.code)
         << ", \"variant\": " << JsonString(c.variant) << ", \"setting\": " << JsonString(c.setting)
         << ", \"error\": " << c.error << ", \"steps\": " << c.steps
         << ", \"iterations\": " << c.iterations << ", \"cpu\": " << Median(c.cpu)
         << ", \"wall\": " << Median(c.wall) << ", \"cpu_ratio\": " << Median(c.cpu_ratio)
         << ", \"wall_ratio\": " << Median(c.wall_ratio) << "}";
    }
    js << "\n    ]}";
  }
  js << "\n  ]\n}\n";
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    f << js.str();
    if (!f) throw std::runtime_error("cannot write " + json_path);
    std::printf("wrote %s\n", json_path.c_str());
  }
  return 0;
}

}  // namespace
}  // namespace screwfem::mujoco_box_bench

int main(int argc, char** argv) {
  try {
    return screwfem::mujoco_box_bench::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "screwfem_bench_mujoco_box: %s\n", e.what());
    return 1;
  }
}
