// The cost of contact (issue 16): one time step of a free 1000-element rod in gravity, without
// contact (it falls) and lying on a ground plane in contact along its whole length (1001 node
// spheres on the plane, elements/contact.h), at rest or sliding along its axis with friction.
// The target: in contact a step costs at most 2x the rod without contact.
// The gripper (examples/gripper/gripper.yaml, issue 16: "the gripper example runs faster than
// real time on one core"): BM_GripperSolver is one whole run of the scene, the solver only
// (InitializeDynamics and Step over the scene's step schedule, no outputs), as BM_GrmSolver in
// dynamics_bench.cpp; real_time_factor = simulated seconds / wall seconds.
// Run with --benchmark_enable_random_interleaving=true so that the repetitions of the variants
// alternate and see the same machine load (scripts/run-bench.sh does).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/dynamics.h"

#include "timed_steps.h"

#ifndef SCREWFEM_SOURCE_DIR
#error "SCREWFEM_SOURCE_DIR must name the source tree (examples/gripper)"
#endif

namespace screwfem {
namespace {

constexpr double kStep = 1e-3;  // [s]
constexpr int kElements = 1000;
constexpr int kWarmupSteps = 5;
constexpr int kTimedSteps = 20;
constexpr double kRadius = 0.01;  // contact radius [m]

// 0: no contact; 1: resting on the plane; 2: sliding along its axis at 0.5 m/s, mu = 0.3;
// 3: as 1 with self-contact on (the broad phase over the 1000 elements at every assembly).
// The GRM arm section of the rod benchmarks (EA = GA = 1e6 N, EI = GJ = 1 N m^2,
// rhoA = 0.1 kg/m), 1 m along x; the contact law's defaults (onset 0.01 r, stiffness
// 100 W_max / onset), friction 0.3, slip velocity 1e-3 m/s; started at the resting gap of an
// interior node.
Model RodOnPlane(int variant) {
  ModelBuilder builder;
  Vec6 stiffness, inertia;
  stiffness << 1e6, 1e6, 1e6, 1.0, 1.0, 1.0;
  inertia << 0.1, 0.1, 0.1, 0.5, 0.5, 0.5;
  const double onset = 0.01 * kRadius;
  const double z = kRadius + onset * (1.0 - std::sqrt(0.02));
  const RodId rod = builder.AddStraightRod("rod", Vec3(0, 0, z), Vec3(1.0, 0, z), kElements,
                                           Section::FromDiagonals(stiffness, inertia));
  builder.SetGravity(Vec3(0, 0, -9.81));
  if (variant > 0) {
    builder.AddContactRod(rod, kRadius);
    builder.AddObstacle(
        {"ground", ObstacleType::kPlane, Vec3::Zero(), Vec3::UnitZ(), Vec3::Zero(), 0.0});
    ContactSettings law;
    law.friction = 0.3;
    law.slip_velocity = 1e-3;
    law.self = variant == 3;  // the rod with itself: the broad phase at every assembly
    builder.SetContactSettings(law);
  }
  if (variant == 2)
    for (NodeId n : builder.RodNodes(rod))
      builder.SetInitialVelocity(n, (Vec6() << 0.5, 0, 0, 0, 0, 0).finished());
  return builder.Build();
}

// One benchmark iteration: the same 20 steps (t = 5 ms to 25 ms) from the same start.
void BM_RodContactStep(benchmark::State& state) {
  const int variant = static_cast<int>(state.range(0));
  const Model model = RodOnPlane(variant);
  DynamicOptions options;
  options.rho_inf = 0.8;
  Data data;
  TimedStepCounts counts;
  if (!RunTimedSteps(state, model, options, true, kWarmupSteps, kTimedSteps, kStep, data, &counts))
    return;
  int active = 0, self_active = 0;
  for (int i = 0; i < static_cast<int>(model.contact_pairs.size()); ++i)
    if (CalcContactState(model, data, i).active) ++active;
  for (int i = 0; i < data.num_shape_pairs; ++i)
    if (CalcShapePairState(model, data, i).active) ++self_active;
  state.counters["self_active"] = self_active;
  state.counters["coupled_nodes"] = data.coupling.blocks();
  state.counters["bandwidth"] = model.bandwidth;
  state.counters["variant"] = variant;
  state.counters["elements"] = kElements;
  state.counters["unknowns"] = model.num_unknowns();
  state.counters["pairs"] = static_cast<double>(model.contact_pairs.size());
  state.counters["active"] = active;
  state.counters["newton_per_step"] = counts.NewtonPerStep();
  state.counters["timed_steps"] = kTimedSteps;
  const std::size_t mid = model.rods.front().nodes[kElements / 2];
  state.counters["mid_z"] = data.H[mid].x.z();
  state.counters["mid_vx"] = (data.H[mid].R * data.v.segment<3>(6 * mid)).x();
}
BENCHMARK(BM_RodContactStep)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Arg(3)
    ->Repetitions(7)
    ->MinTime(0.2)
    ->Unit(benchmark::kMillisecond);

// One benchmark iteration: the whole gripper run (0 to 3 s, h = 2e-3 s), solver only.
void BM_GripperSolver(benchmark::State& state) {
  Scene scene;
  try {
    scene = LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/gripper/gripper.yaml");
  } catch (const std::exception& e) {
    state.SkipWithError((std::string("LoadScene failed: ") + e.what()).c_str());
    return;
  }
  const Model& model = scene.model;
  const AnalysisSettings& a = scene.analysis;
  const StepSchedule schedule(a.start_time, a.end_time, a.step,
                              a.align_steps ? ProfileBreakpoints(model) : std::vector<double>{});
  double simulated = 0.0, wall_total = 0.0;
  long runs = 0, steps = 0, iterations = 0, halvings = 0;
  for (auto _ : state) {
    Data data = MakeData(model);
    Integrator integ;
    data.time = a.start_time;
    const auto start = std::chrono::steady_clock::now();
    std::string message;
    bool ok = AssembleInitialState(model, data, &message) &&
              InitializeDynamics(model, data, integ, a.dynamic, &message);
    while (ok && !schedule.Done(data.time)) {
      const double t_next = schedule.Next(data.time);
      const StepResult step = Step(model, data, integ, t_next - data.time);
      ok = step.ok;
      if (ok)
        data.time = t_next;
      else
        message = step.message;
    }
    benchmark::DoNotOptimize(data.v.data());
    benchmark::ClobberMemory();
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!ok) {
      state.SkipWithError(("gripper run failed: " + message).c_str());
      break;
    }
    state.SetIterationTime(wall);
    simulated += data.time - a.start_time;
    wall_total += wall;
    runs += 1;
    steps += integ.steps;
    iterations += integ.iterations;
    halvings += integ.halvings;
  }
  const double n = runs > 0 ? static_cast<double>(runs) : 1.0;
  state.counters["real_time_factor"] = wall_total > 0.0 ? simulated / wall_total : 0.0;
  state.counters["simulated_seconds"] = simulated / n;
  state.counters["steps"] = static_cast<double>(steps) / n;
  state.counters["newton_iterations"] = static_cast<double>(iterations) / n;
  state.counters["halvings"] = static_cast<double>(halvings) / n;
  state.counters["elements"] = static_cast<double>(model.elements.size());
  state.counters["unknowns"] = model.num_unknowns();
  state.counters["pairs"] =
      static_cast<double>(AllShapePairs(model).size() + model.contact_pairs.size());
  state.counters["bandwidth"] = model.bandwidth;
}
// The smallest time over the repetitions (the run least disturbed by other load).
double SmallestGripperTime(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}
// Registered as BM_GripperSolver/gripper (the family/argument naming of bench/make_results.py);
// one iteration is a whole run, seven repetitions with the median and the smallest time.
const bool kGripperRegistered = [] {
  benchmark::RegisterBenchmark("BM_GripperSolver/gripper", BM_GripperSolver)
      ->Iterations(1)
      ->Repetitions(7)
      ->ComputeStatistics("min", SmallestGripperTime)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace
}  // namespace screwfem

BENCHMARK_MAIN();
