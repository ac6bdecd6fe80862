// Cost of dynamic analyses (generalized-alpha time stepping, solve/dynamics.h).
//
// GRM: the generic robotic mechanism of examples/grm (grm_rigid, grm_soft_k, grm_soft_kd),
// loaded with LoadScene and the overrides defaults.elements=4 (4 elements per soft body) and
// analysis.step=1e-3, simulated over the scene's full span (0 to 2 s). One benchmark
// iteration is one whole simulation, so the reported time is the wall time of a run.
//   BM_GrmSolver  InitializeDynamics and Step over the scene's step schedule (profile
//                 breakpoints on step ends, as RunScene does), without outputs and without
//                 RunScene's per-step constraint check: the solver alone.
//   BM_GrmRun     RunScene into a fresh temporary directory, with the scene's outputs (CSV
//                 rows every 1 ms, VTK frames every 20 ms, summary.json): the full run.
// Counters: real_time_factor = simulated seconds / wall seconds (the target for the
// rigid-joint case is >= 10 on one core; reported, not asserted), steps, newton_iterations
// and halvings per run, elements and unknowns of the model.
//
// Rod: a straight cantilever (1 m along x, clamped at x = 0, released from rest in gravity
// 9.81 m/s^2 along -z) with the GRM arm section (EA = GA = 1e6 N, EI = GJ = 1 N m^2,
// rho A = 0.1 kg/m, rotational inertia 0.5 kg m per unit length), exact rod inertia,
// rho_inf = 0.8, h = 1e-3 s, 10 to 10000 elements.
//   BM_RodStep    one Step (every Newton iteration of it). Warm-up outside the timed loop:
//                 InitializeDynamics and kWarmupSteps steps; then kRodTimedSteps timed steps,
//                 the same simulated interval for every size.
// Counters: time_per_element (time per element-step), newton_per_step, unknowns, bandwidth.
// The times are wall-clock (real or manual time); the program runs single-threaded.
// Run with scripts/run-bench.sh, which writes bench/RESULTS.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/io/schedule.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

#ifndef SCREWFEM_SOURCE_DIR
#error "SCREWFEM_SOURCE_DIR must name the source tree (examples/grm)"
#endif

namespace screwfem {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// --- GRM -------------------------------------------------------------------------------------

constexpr const char* kGrmCases[] = {"grm_rigid", "grm_soft_k", "grm_soft_kd"};
constexpr int kGrmElements = 4;

Scene LoadGrm(int index) {
  const std::string path =
      std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/" + kGrmCases[index] + ".yaml";
  return LoadScene(path, {"defaults.elements=" + std::to_string(kGrmElements),
                          "analysis.step=1e-3"});
}

struct GrmTotals {
  double simulated = 0.0, wall = 0.0;
  long runs = 0, steps = 0, iterations = 0, halvings = 0;
};

void SetGrmCounters(benchmark::State& state, const Scene& scene, const GrmTotals& t) {
  const double runs = t.runs > 0 ? static_cast<double>(t.runs) : 1.0;
  state.counters["real_time_factor"] = t.wall > 0.0 ? t.simulated / t.wall : 0.0;
  state.counters["simulated_seconds"] = t.simulated / runs;
  state.counters["steps"] = static_cast<double>(t.steps) / runs;
  state.counters["newton_iterations"] = static_cast<double>(t.iterations) / runs;
  state.counters["halvings"] = static_cast<double>(t.halvings) / runs;
  state.counters["elements"] = static_cast<double>(scene.model.elements.size());
  state.counters["unknowns"] = scene.model.num_unknowns();
}

// Loads the scene, or reports why not (a scene the library rejects ends that benchmark only).
bool LoadGrm(benchmark::State& state, int index, Scene* scene) {
  try {
    *scene = LoadGrm(index);
    return true;
  } catch (const std::exception& e) {
    state.SkipWithError((std::string("LoadScene failed: ") + e.what()).c_str());
    return false;
  }
}

void BM_GrmSolver(benchmark::State& state, int index) {
  Scene scene;
  if (!LoadGrm(state, index, &scene)) return;
  const Model& model = scene.model;
  const AnalysisSettings& a = scene.analysis;
  const StepSchedule schedule(a.start_time, a.end_time, a.step,
                              a.align_steps ? ProfileBreakpoints(model) : std::vector<double>{});
  GrmTotals totals;
  for (auto _ : state) {
    Data data = MakeData(model);
    Integrator integ;
    data.time = a.start_time;
    const auto start = Clock::now();
    std::string message;
    bool ok = InitializeDynamics(model, data, integ, a.dynamic, &message);
    while (ok && !schedule.Done(data.time)) {
      const double t_next = schedule.Next(data.time);
      const StepResult step = Step(model, data, integ, t_next - data.time);
      ok = step.ok;
      if (ok) data.time = t_next;
      else message = step.message;
    }
    benchmark::DoNotOptimize(data.v.data());
    benchmark::ClobberMemory();
    const double wall = Seconds(start, Clock::now());
    if (!ok) {
      state.SkipWithError(("dynamic run failed: " + message).c_str());
      break;
    }
    state.SetIterationTime(wall);
    totals.simulated += data.time - a.start_time;
    totals.wall += wall;
    totals.runs += 1;
    totals.steps += integ.steps;
    totals.iterations += integ.iterations;
    totals.halvings += integ.halvings;
  }
  SetGrmCounters(state, scene, totals);
}

void BM_GrmRun(benchmark::State& state, int index) {
  Scene scene;
  if (!LoadGrm(state, index, &scene)) return;
  const std::filesystem::path outdir =
      std::filesystem::temp_directory_path() /
      ("screwfem_bench_" + std::to_string(::getpid()) + "_" + kGrmCases[index]);
  GrmTotals totals;
  for (auto _ : state) {
    std::filesystem::remove_all(outdir);
    const auto start = Clock::now();
    RunResult r;
    try {
      r = RunScene(scene, outdir.string());
    } catch (const std::exception& e) {
      r.ok = false;
      r.message = e.what();
    }
    const double wall = Seconds(start, Clock::now());
    if (!r.ok) {
      state.SkipWithError(("RunScene failed: " + r.message).c_str());
      break;
    }
    state.SetIterationTime(wall);
    totals.simulated += r.end_time - scene.analysis.start_time;
    totals.wall += wall;
    totals.runs += 1;
    totals.steps += r.steps;
    totals.iterations += r.newton_iterations;
    totals.halvings += r.halvings;
  }
  std::filesystem::remove_all(outdir);
  SetGrmCounters(state, scene, totals);
}

// Smallest value over the repetitions: the run least disturbed by other load on the machine
// (the median is reported beside it).
double Smallest(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}

// Registered as BM_GrmSolver/<case> and BM_GrmRun/<case>. One iteration is a whole 2 s
// simulation (a fraction of a second of wall time): a single iteration per repetition, nine
// repetitions of the solver (five of the full run), with the median and the smallest time.
const bool kGrmRegistered = [] {
  for (int i = 0; i < 3; ++i)
    benchmark::RegisterBenchmark((std::string("BM_GrmSolver/") + kGrmCases[i]).c_str(),
                                 BM_GrmSolver, i)
        ->Iterations(1)->Repetitions(9)->ComputeStatistics("min", Smallest)
        ->UseManualTime()->Unit(benchmark::kMillisecond);
  for (int i = 0; i < 3; ++i)
    benchmark::RegisterBenchmark((std::string("BM_GrmRun/") + kGrmCases[i]).c_str(), BM_GrmRun, i)
        ->Iterations(1)->Repetitions(5)->ComputeStatistics("min", Smallest)
        ->UseManualTime()->Unit(benchmark::kMillisecond);
  return true;
}();

// --- Cantilever rod --------------------------------------------------------------------------

constexpr double kRodLength = 1.0;  // [m]
constexpr double kRodStep = 1e-3;   // [s]
constexpr int kWarmupSteps = 5;

Model CantileverModel(int num_elements) {
  Vec6 stiffness, inertia;
  stiffness << 1e6, 1e6, 1e6, 1.0, 1.0, 1.0;  // EA, GA2, GA3, GJ, EI2, EI3
  inertia << 0.1, 0.1, 0.1, 0.5, 0.5, 0.5;    // rho A (x3) [kg/m], rotational [kg m]
  ModelBuilder builder;
  const int rod = builder.AddStraightRod("rod", Vec3::Zero(), Vec3(kRodLength, 0, 0),
                                         num_elements, Section::FromDiagonals(stiffness, inertia));
  builder.FixNode(builder.model().rods[static_cast<std::size_t>(rod)].nodes.front());
  builder.SetGravity(Vec3(0, 0, -9.81));
  builder.model().rod_inertia = RodInertia::kExact;
  return builder.Build();
}

// Timed steps: the same 50 steps (t = 5 ms to 55 ms, after the warm-up) for every size, so
// every size integrates the same part of the motion. Each benchmark iteration is one step.
constexpr int kRodTimedSteps = 50;

void BM_RodStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Model model = CantileverModel(n);
  Data data = MakeData(model);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 0.8;
  std::string message;
  if (!InitializeDynamics(model, data, integ, options, &message)) {
    state.SkipWithError(("InitializeDynamics failed: " + message).c_str());
    return;
  }
  for (int i = 0; i < kWarmupSteps; ++i) {
    const StepResult step = Step(model, data, integ, kRodStep);
    if (!step.ok) {
      state.SkipWithError(("warm-up step failed: " + step.message).c_str());
      return;
    }
    data.time += kRodStep;
  }
  const long iterations_before = integ.iterations, halvings_before = integ.halvings;
  int max_iterations = 0;
  for (auto _ : state) {
    const StepResult step = Step(model, data, integ, kRodStep);
    if (!step.ok) {
      state.SkipWithError(("step failed: " + step.message).c_str());
      break;
    }
    data.time += kRodStep;
    max_iterations = std::max(max_iterations, step.iterations);
    benchmark::DoNotOptimize(data.v.data());
    benchmark::ClobberMemory();
  }
  const double steps = static_cast<double>(state.iterations());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * n);
  state.counters["elements"] = n;
  state.counters["unknowns"] = model.num_unknowns();
  state.counters["bandwidth"] = model.bandwidth;
  state.counters["newton_per_step"] =
      steps > 0 ? static_cast<double>(integ.iterations - iterations_before) / steps : 0.0;
  state.counters["max_newton_per_step"] = max_iterations;
  state.counters["halvings"] = static_cast<double>(integ.halvings - halvings_before);
  state.counters["timed_steps"] = steps;
  state.counters["time_per_element"] = benchmark::Counter(
      static_cast<double>(n),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  // Tip deflection at the end of the timed steps (a sanity check of the motion) [m].
  state.counters["tip_z"] =
      data.H[static_cast<std::size_t>(model.rods.front().nodes.back())].x.z();
}

// Fewer repetitions for the slow sizes (10000 elements: about 0.5 s per step at the time of
// writing, about 25 s per repetition including set-up and warm-up).
void RodSizes(benchmark::internal::Benchmark* b) {
  b->Iterations(kRodTimedSteps)->UseRealTime()->Unit(benchmark::kMicrosecond);
}
BENCHMARK(BM_RodStep)->Apply(RodSizes)->Arg(10)->Repetitions(5);
BENCHMARK(BM_RodStep)->Apply(RodSizes)->Arg(100)->Repetitions(5);
BENCHMARK(BM_RodStep)->Apply(RodSizes)->Arg(1000)->Repetitions(3);
BENCHMARK(BM_RodStep)->Apply(RodSizes)->Arg(10000)->Repetitions(3);

}  // namespace
}  // namespace screwfem

BENCHMARK_MAIN();
