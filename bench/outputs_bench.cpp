// Cost of a run's outputs (issue 17): the rigid GRM of examples/grm (grm_rigid.yaml with
// defaults.elements=4 and analysis.step=1e-3, 0 to 2 s) run as `screwfem run -q` runs it —
// RunScene into a fresh directory with the scene's own outputs (points.csv and joints.csv
// every step, ParaView frames every 20 ms, joints.json, summary.json, vtk/motion.pvd) —
// against the solver alone (InitializeDynamics and Step over the same step schedule, no
// outputs), as BM_GrmSolver in dynamics_bench.cpp.
//
// The machine's speed drifts by 10-25 % over minutes, so one benchmark runs both variants
// alternately (solver, run, run, solver, ...: the order flips every round) and reports the
// ratio run / solver per round; its median is the cost of the outputs.
// Bytes: written = the growth of `wchar` in /proc/self/io over RunScene (every byte the
// process handed to write(): tables, frames, temporary files of the atomic replacements, every
// rewrite of summary.json); final = the sizes of the files in the output directory after the
// run. Targets (issue 17): time ratio at most 1.15, bytes written at most 1.2 x final.
// Counters: time_ratio (wall time, median over rounds) with time_ratio_min and _max,
// cpu_time_ratio (the same with the thread's CPU time, user + system: the cost without the
// waits for a processor that other load causes), solver_seconds and run_seconds (medians),
// written_bytes, final_bytes, bytes_ratio, rounds, frames (vtk files).
// The case grm_rigid_lean: the same with outputs.reactions and outputs.energy false.
// Run with scripts/run-bench.sh (SCREWFEM_BENCH=outputs), which writes bench/RESULTS.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <time.h>
#include <unistd.h>

#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/dynamics.h"

#ifndef SCREWFEM_SOURCE_DIR
#error "SCREWFEM_SOURCE_DIR must name the source tree (examples/grm)"
#endif

namespace screwfem {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// CPU time of this thread, user and system [s]: what the work cost, without the waits for a
// processor that other load on the machine causes.
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Bytes this process has passed to write() and its relatives so far (/proc/self/io, "wchar");
// -1 when the kernel does not account them.
long long BytesWritten() {
  std::ifstream io("/proc/self/io");
  std::string key;
  long long value = 0;
  while (io >> key >> value)
    if (key == "wchar:") return value;
  return -1;
}

long long DirectoryBytes(const fs::path& dir, long long* vtk_files) {
  long long bytes = 0;
  *vtk_files = 0;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) {
      bytes += static_cast<long long>(e.file_size());
      if (e.path().extension() == ".vtp") ++*vtk_files;
    }
  return bytes;
}

// The solver alone: one whole simulation, its wall time [s]; false with a message on failure.
bool RunSolver(const Scene& scene, double* seconds, double* cpu_seconds, std::string* message) {
  const Model& model = scene.model;
  const AnalysisSettings& a = scene.analysis;
  const StepSchedule schedule(a.start_time, a.end_time, a.step,
                              a.align_steps ? ProfileBreakpoints(model) : std::vector<double>{});
  Data data = MakeData(model);
  Integrator integ;
  data.time = a.start_time;
  const double cpu_start = ThreadCpuSeconds();
  const auto start = Clock::now();
  bool ok = InitializeDynamics(model, data, integ, a.dynamic, message);
  while (ok && !schedule.Done(data.time)) {
    const double t_next = schedule.Next(data.time);
    const StepResult step = Step(model, data, integ, t_next - data.time);
    ok = step.ok;
    if (ok)
      data.time = t_next;
    else
      *message = step.message;
  }
  benchmark::DoNotOptimize(data.v.data());
  benchmark::ClobberMemory();
  *seconds = Seconds(start, Clock::now());
  *cpu_seconds = ThreadCpuSeconds() - cpu_start;
  return ok;
}

constexpr int kRounds = 12;

// `lean`: the same run without reactions.csv and energy.csv (outputs.reactions and
// outputs.energy false), the case grm_rigid_lean.
void BM_GrmOutputCost(benchmark::State& state, const char* name, bool lean) {
  Scene scene;
  try {
    std::vector<std::string> overrides = {"defaults.elements=4", "analysis.step=1e-3"};
    if (lean)
      overrides.insert(overrides.end(), {"outputs.reactions=false", "outputs.energy=false"});
    scene =
        LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/" + name + ".yaml", overrides);
  } catch (const std::exception& e) {
    state.SkipWithError((std::string("LoadScene failed: ") + e.what()).c_str());
    return;
  }
  const fs::path outdir =
      fs::temp_directory_path() / ("screwfem_bench_outputs_" + std::to_string(::getpid()));
  RunOptions options;  // as `screwfem run -q`: no progress bar
  std::vector<double> solver, run, ratio, cpu_ratio;
  long long written = 0, final_bytes = 0, frames = 0;
  for (auto _ : state) {
    for (int round = 0; round < kRounds; ++round) {
      double t_solver = 0.0, t_run = 0.0, cpu_solver = 0.0, cpu_run = 0.0;
      for (int k = 0; k < 2; ++k) {
        const bool solver_now = (k == 0) == (round % 2 == 0);
        std::string message;
        if (solver_now) {
          if (!RunSolver(scene, &t_solver, &cpu_solver, &message)) {
            state.SkipWithError(("solver failed: " + message).c_str());
            return;
          }
          continue;
        }
        fs::remove_all(outdir);
        const long long before = BytesWritten();
        const double cpu_start = ThreadCpuSeconds();
        const auto start = Clock::now();
        RunResult r;
        try {
          r = RunScene(scene, outdir.string(), options);
        } catch (const std::exception& e) {
          r.ok = false;
          r.message = e.what();
        }
        t_run = Seconds(start, Clock::now());
        cpu_run = ThreadCpuSeconds() - cpu_start;
        written = BytesWritten() - before;
        if (!r.ok) {
          state.SkipWithError(("RunScene failed: " + r.message).c_str());
          return;
        }
        final_bytes = DirectoryBytes(outdir, &frames);
      }
      solver.push_back(t_solver);
      run.push_back(t_run);
      ratio.push_back(t_run / t_solver);
      cpu_ratio.push_back(cpu_run / cpu_solver);
    }
    state.SetIterationTime(Median(run));
  }
  fs::remove_all(outdir);
  state.counters["rounds"] = kRounds;
  state.counters["solver_seconds"] = Median(solver);
  state.counters["run_seconds"] = Median(run);
  state.counters["time_ratio"] = Median(ratio);
  state.counters["time_ratio_min"] = *std::min_element(ratio.begin(), ratio.end());
  state.counters["time_ratio_max"] = *std::max_element(ratio.begin(), ratio.end());
  state.counters["cpu_time_ratio"] = Median(cpu_ratio);
  state.counters["written_bytes"] = static_cast<double>(written);
  state.counters["final_bytes"] = static_cast<double>(final_bytes);
  state.counters["bytes_ratio"] =
      final_bytes > 0 && written >= 0
          ? static_cast<double>(written) / static_cast<double>(final_bytes)
          : 0.0;
  state.counters["frames"] = static_cast<double>(frames);
}

const bool kRegistered = [] {
  benchmark::RegisterBenchmark("BM_GrmOutputCost/grm_rigid", BM_GrmOutputCost, "grm_rigid", false)
      ->Iterations(1)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("BM_GrmOutputCost/grm_rigid_lean", BM_GrmOutputCost, "grm_rigid",
                               true)
      ->Iterations(1)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace
}  // namespace screwfem

BENCHMARK_MAIN();
