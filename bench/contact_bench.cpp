// The cost of contact (issue 16): one time step of a free 1000-element rod in gravity, without
// contact (it falls) and lying on a ground plane in contact along its whole length (1001 node
// spheres on the plane, elements/contact.h), at rest or sliding along its axis with friction.
// The target: in contact a step costs at most 2x the rod without contact.
// Run with --benchmark_enable_random_interleaving=true so that the repetitions of the variants
// alternate and see the same machine load (scripts/run-bench.sh does).
#include <benchmark/benchmark.h>

#include <cmath>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/contact.h"
#include "screwfem/solve/dynamics.h"

#include "timed_steps.h"

namespace screwfem {
namespace {

constexpr double kStep = 1e-3;  // [s]
constexpr int kElements = 1000;
constexpr int kWarmupSteps = 5;
constexpr int kTimedSteps = 20;
constexpr double kRadius = 0.01;  // contact radius [m]

// 0: no contact; 1: resting on the plane; 2: sliding along its axis at 0.5 m/s, mu = 0.3.
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
  const int rod = builder.AddStraightRod("rod", Vec3(0, 0, z), Vec3(1.0, 0, z), kElements,
                                         Section::FromDiagonals(stiffness, inertia));
  builder.SetGravity(Vec3(0, 0, -9.81));
  if (variant > 0) {
    builder.AddContactRod(rod, kRadius);
    builder.AddObstacle({"ground", ObstacleType::kPlane, Vec3::Zero(), Vec3::UnitZ(),
                         Vec3::Zero(), 0.0});
    ContactSettings law;
    law.friction = 0.3;
    law.slip_velocity = 1e-3;
    builder.SetContactSettings(law);
  }
  if (variant == 2)
    for (int n : builder.model().rods[static_cast<std::size_t>(rod)].nodes)
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
  if (!RunTimedSteps(state, model, options, true, kWarmupSteps, kTimedSteps, kStep, data,
                     &counts))
    return;
  int active = 0;
  for (int i = 0; i < static_cast<int>(model.contact_pairs.size()); ++i)
    if (CalcContactState(model, data, i).active) ++active;
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
BENCHMARK(BM_RodContactStep)->Arg(0)->Arg(1)->Arg(2)->Repetitions(7)->MinTime(0.2)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace screwfem

BENCHMARK_MAIN();
