// The timed loop of the per-step benchmarks (bench/tendons_bench.cpp, bench/contact_bench.cpp):
// every benchmark iteration restarts from the model's initial state, takes `warmup` untimed
// steps, then times `timed` steps of size h.
#pragma once

#include <benchmark/benchmark.h>

#include "screwfem/model/data.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"

namespace screwfem {

struct TimedStepCounts {
  long steps = 0;       // timed steps over all iterations
  long iterations = 0;  // Newton iterations of those steps
  double NewtonPerStep() const {
    return steps > 0 ? static_cast<double>(iterations) / static_cast<double>(steps) : 0.0;
  }
};

// `assemble_initial`: solve the initial state (AssembleInitialState) before InitializeDynamics,
// for models that start with joint coordinates or contacts to settle. Returns false after
// state.SkipWithError when a start or a timed step fails; `data` holds the last state.
inline bool RunTimedSteps(benchmark::State& state, const Model& model,
                          const DynamicOptions& options, bool assemble_initial, int warmup,
                          int timed, double h, Data& data, TimedStepCounts* counts) {
  Integrator integ;
  for (auto _ : state) {
    state.PauseTiming();
    data = MakeData(model);
    if ((assemble_initial && !AssembleInitialState(model, data)) ||
        !InitializeDynamics(model, data, integ, options)) {
      state.SkipWithError("InitializeDynamics failed");
      return false;
    }
    for (int i = 0; i < warmup; ++i) {
      Step(model, data, integ, h);
      data.time += h;
    }
    const long before = integ.iterations;
    state.ResumeTiming();
    for (int i = 0; i < timed; ++i) {
      if (!Step(model, data, integ, h).ok) {
        state.SkipWithError("step failed");
        return false;
      }
      data.time += h;
    }
    counts->steps += timed;
    counts->iterations += integ.iterations - before;
    benchmark::DoNotOptimize(data.v.data());
  }
  return true;
}

}  // namespace screwfem
