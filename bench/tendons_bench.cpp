// The cost of tendons (issue 15): one time step of a 10-element cantilever rod alone and with
// two tendons of 10 eyelets each (elements/tendon.h: 9 segments per tendon, each a 2-node
// item on consecutive rod nodes). The target: at most 25 % more per step than the rod alone.
// Run with --benchmark_enable_random_interleaving=true so that the repetitions of the two
// variants alternate and see the same machine load (scripts/run-bench.sh does).
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/solve/dynamics.h"

#include "timed_steps.h"

namespace screwfem {
namespace {

constexpr double kStep = 1e-3;  // [s]
constexpr int kWarmupSteps = 5;
constexpr int kTimedSteps = 50;

// The cantilever of the rod benchmarks (dynamics_bench.cpp, GRM arm section, gravity), 1 m,
// 10 elements, clamped at node 0; `tendons` = 0 or 2 tendons with eyelets on nodes 0..9 at
// 0.02 m from the axis (section +y, and -z), tensions ramping to 5 N and 3 N over 0.1 s.
Model CantileverWithTendons(int tendons) {
  ModelBuilder builder;
  Vec6 stiffness, inertia;
  stiffness << 1e6, 1e6, 1e6, 1.0, 1.0, 1.0;
  inertia << 0.1, 0.1, 0.1, 0.5, 0.5, 0.5;
  const RodId rod = builder.AddStraightRod("rod", Vec3::Zero(), Vec3(1.0, 0, 0), 10,
                                           Section::FromDiagonals(stiffness, inertia));
  const std::vector<NodeId> nodes = builder.RodNodes(rod);
  builder.FixNode(nodes.front());
  builder.SetGravity(Vec3(0, 0, -9.81));
  const Vec3 offsets[2] = {Vec3(0, 0.02, 0), Vec3(0, 0, -0.02)};
  const double tensions[2] = {5.0, 3.0};
  for (int t = 0; t < tendons; ++t) {
    std::vector<BodyPoint> eyelets;
    for (int k = 0; k < 10; ++k)
      eyelets.push_back({nodes[static_cast<std::size_t>(k)], offsets[t]});
    builder.AddTendon("tendon" + std::to_string(t), eyelets, Profile::Ramp(0.0, 0.1, tensions[t]));
  }
  return builder.Build();
}

// One benchmark iteration: the same 50 steps (t = 5 ms to 55 ms) from the same start.
void BM_RodTendonStep(benchmark::State& state) {
  const Model model = CantileverWithTendons(static_cast<int>(state.range(0)));
  DynamicOptions options;
  options.rho_inf = 0.8;
  Data data;
  TimedStepCounts counts;
  if (!RunTimedSteps(state, model, options, false, kWarmupSteps, kTimedSteps, kStep, data, &counts))
    return;
  state.counters["tendons"] = static_cast<double>(state.range(0));
  state.counters["unknowns"] = model.num_unknowns();
  state.counters["bandwidth"] = model.bandwidth;
  state.counters["newton_per_step"] = counts.NewtonPerStep();
  state.counters["timed_steps"] = kTimedSteps;
  state.counters["tip_y"] = data.H[static_cast<std::size_t>(model.rods.front().nodes.back())].x.y();
}
BENCHMARK(BM_RodTendonStep)
    ->Arg(0)
    ->Arg(2)
    ->Repetitions(9)
    ->MinTime(0.3)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace screwfem

BENCHMARK_MAIN();
