// The parallel assembly (assemble.h, SetAssemblyThreads; docs/architecture.md, "Parallel
// assembly"): one thread against two, interleaved. Run with
// --benchmark_enable_random_interleaving=true (scripts/run-bench.sh does), so that the
// repetitions of threads = 1 and threads = 2 alternate and a change of the machine's load
// falls on both. Wall time (real_time) and the process's CPU time of all threads (cpu_time).
//
// Rod: the cantilever of bench/dynamics_bench.cpp (1 m, clamped, gravity, the GRM arm
// section, exact rod inertia, rho_inf = 0.8, h = 1e-3 s).
//   BM_ParallelRodStep/<elements>/<threads>      one Step (assembly and solve), after
//                                                InitializeDynamics and 3 warm-up steps.
//   BM_ParallelRodAssemble/<elements>/<threads>  one Assemble of residual and iteration
//                                                matrix (dynamics, node tangents) at the
//                                                state after the warm-up: the part that runs
//                                                on the threads.
// Counter main_thread_cpu: the CPU time of the calling thread per iteration [s], which runs
// the serial parts (the scatter, the solves) and its share of the kernels: on two idle cores
// the wall time of two threads approaches it, so CPU time at 1 thread / main_thread_cpu at 2
// threads estimates the speed-up when the machine is too loaded for the wall time to say.
// GRM: the scene's whole 2 s (examples/grm, 4 elements per soft body, h = 1e-3 s, the solver
// alone as BM_GrmSolver): 'auto' gives these models one thread; two threads show why.
//   BM_ParallelGrm/<case>/<threads>              threads 0 = auto.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/schedule.h"

#ifndef SCREWFEM_SOURCE_DIR
#error "SCREWFEM_SOURCE_DIR must name the source tree (examples/grm)"
#endif

namespace screwfem {
namespace {

constexpr double kStep = 1e-3;

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
constexpr int kWarmup = 3;

Model Cantilever(int n) {
  Vec6 stiffness, inertia;
  stiffness << 1e6, 1e6, 1e6, 1.0, 1.0, 1.0;
  inertia << 0.1, 0.1, 0.1, 0.5, 0.5, 0.5;
  ModelBuilder builder;
  const RodId rod = builder.AddStraightRod("rod", Vec3::Zero(), Vec3(1, 0, 0), n,
                                           Section::FromDiagonals(stiffness, inertia));
  builder.FixNode(builder.RodNodes(rod).front());
  builder.SetGravity(Vec3(0, 0, -9.81));
  builder.model().rod_inertia = RodInertia::kExact;
  return builder.Build();
}

// Data after InitializeDynamics and the warm-up steps, on `threads` threads.
bool StartRod(benchmark::State& state, const Model& model, int threads, Data* data,
              Integrator* integ) {
  *data = MakeData(model);
  SetAssemblyThreads(*data, threads);
  DynamicOptions options;
  options.rho_inf = 0.8;
  std::string message;
  if (!InitializeDynamics(model, *data, *integ, options, &message)) {
    state.SkipWithError(("InitializeDynamics failed: " + message).c_str());
    return false;
  }
  for (int i = 0; i < kWarmup; ++i) {
    if (!Step(model, *data, *integ, kStep).ok) {
      state.SkipWithError("warm-up step failed");
      return false;
    }
    data->time += kStep;
  }
  return true;
}

void BM_ParallelRodStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const Model model = Cantilever(n);
  Data data;
  Integrator integ;
  if (!StartRod(state, model, threads, &data, &integ)) return;
  const long before = integ.iterations;
  const double cpu0 = ThreadCpuSeconds();
  for (auto _ : state) {
    if (!Step(model, data, integ, kStep).ok) {
      state.SkipWithError("step failed");
      break;
    }
    data.time += kStep;
    benchmark::DoNotOptimize(data.v.data());
  }
  state.counters["main_thread_cpu"] =
      (ThreadCpuSeconds() - cpu0) / static_cast<double>(state.iterations());
  state.counters["threads"] = data.parallel.threads();
  state.counters["elements"] = n;
  state.counters["newton_per_step"] =
      static_cast<double>(integ.iterations - before) / static_cast<double>(state.iterations());
  state.counters["load_avg_1min"] = 0.0;
  double load[1];
  if (getloadavg(load, 1) == 1) state.counters["load_avg_1min"] = load[0];
}

void BM_ParallelRodAssemble(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const Model model = Cantilever(n);
  Data data;
  Integrator integ;
  if (!StartRod(state, model, threads, &data, &integ)) return;
  AssemblyOptions o;
  o.time = data.time;
  o.dynamics = true;
  o.use_node_tangent = true;
  o.c_mass = 1e6;
  o.c_damping = 1e3;
  o.s_rows = 1e-6;
  const double cpu0 = ThreadCpuSeconds();
  for (auto _ : state) {
    if (!Assemble(model, data, o)) {
      state.SkipWithError("assembly failed");
      break;
    }
    benchmark::DoNotOptimize(data.residual.data());
  }
  state.counters["main_thread_cpu"] =
      (ThreadCpuSeconds() - cpu0) / static_cast<double>(state.iterations());
  state.counters["threads"] = data.parallel.threads();
  state.counters["elements"] = n;
  double load[1];
  if (getloadavg(load, 1) == 1) state.counters["load_avg_1min"] = load[0];
}

constexpr const char* kGrmCases[] = {"grm_rigid", "grm_soft_kd"};

void BM_ParallelGrm(benchmark::State& state) {
  const std::string name = kGrmCases[state.range(0)];
  const int threads = static_cast<int>(state.range(1));
  const Scene scene = LoadScene(
      std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/" + name + ".yaml",
      {"defaults.elements=4", "analysis.step=1e-3",
       "analysis.threads=" + (threads == 0 ? std::string("auto") : std::to_string(threads))});
  const Model& model = scene.model;
  const AnalysisSettings& a = scene.analysis;
  int used = 0;
  for (auto _ : state) {
    Data data = MakeData(model);
    SetAssemblyThreads(data, ResolveAssemblyThreads(model, a.threads));
    used = data.parallel.threads();
    Integrator integ;
    data.time = a.start_time;
    std::string message;
    if (!AssembleInitialState(model, data, &message) ||
        !InitializeDynamics(model, data, integ, a.dynamic, &message)) {
      state.SkipWithError(("start failed: " + message).c_str());
      break;
    }
    const StepSchedule schedule(a.start_time, a.end_time, a.step, ProfileBreakpoints(model));
    while (!schedule.Done(data.time)) {
      const double t = schedule.Next(data.time);
      if (!Step(model, data, integ, t - data.time).ok) {
        state.SkipWithError("step failed");
        return;
      }
      data.time = t;
    }
    benchmark::DoNotOptimize(data.v.data());
  }
  state.counters["threads"] = used;
  state.counters["elements"] = static_cast<double>(model.elements.size());
  double load[1];
  if (getloadavg(load, 1) == 1) state.counters["load_avg_1min"] = load[0];
}

void Timed(benchmark::internal::Benchmark* b) {
  b->UseRealTime()->MeasureProcessCPUTime()->ComputeStatistics(
      "min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); });
}

BENCHMARK(BM_ParallelRodStep)
    ->Apply(Timed)
    ->Args({10000, 1})
    ->Args({10000, 2})
    ->Iterations(4)
    ->Repetitions(7)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParallelRodAssemble)
    ->Apply(Timed)
    ->Args({10000, 1})
    ->Args({10000, 2})
    ->Iterations(10)
    ->Repetitions(7)
    ->Unit(benchmark::kMillisecond);
// The sizes around 'auto's threshold (kParallelMinElements).
BENCHMARK(BM_ParallelRodStep)
    ->Apply(Timed)
    ->ArgsProduct({{100, 300, 1000, 3000}, {1, 2}})
    ->Iterations(20)
    ->Repetitions(5)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ParallelGrm)
    ->Apply(Timed)
    ->ArgsProduct({{0, 1}, {0, 2}})
    ->Iterations(1)
    ->Repetitions(7)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace screwfem

BENCHMARK_MAIN();
