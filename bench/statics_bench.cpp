// Cost per element of the two stages of a static Newton iteration, for a clamped straight rod
// (cantilever, 1 m, EA = GA = 1e6 N, EI = GJ = 1 N m^2) discretised with 10 to 10000 helical
// elements:
//   BM_Assemble  one Assemble() of residual and iteration matrix (default AssemblyOptions);
//   BM_Solve     one SolveAssembledSystem(): factorisation of the banded matrix and solve.
// Items processed = elements, so items_per_second and `time_per_element` show the cost per
// element. The rod is evaluated bent and twisted (constant curvature and twist), not in its
// straight reference, so the element kernels take their general (non-series) branches.
// Run with scripts/run-bench.sh, which writes bench/RESULTS.md.
#include <benchmark/benchmark.h>

#include <chrono>

#include "screwfem/assemble/assemble.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem {
namespace {

constexpr double kLength = 1.0;     // [m]
constexpr double kCurvature = 1.5;  // bending of the evaluated configuration [rad/m]
constexpr double kTwist = 0.5;      // twist of the evaluated configuration [rad/m]

Model CantileverModel(int num_elements) {
  Vec6 stiffness;
  stiffness << 1e6, 1e6, 1e6, 1.0, 1.0, 1.0;  // EA, GA2, GA3, GJ, EI2, EI3
  ModelBuilder builder;
  const RodId rod = builder.AddStraightRod("rod", Vec3::Zero(), Vec3(kLength, 0, 0), num_elements,
                                           Section::FromDiagonals(stiffness));
  builder.FixNode(builder.RodNodes(rod).front());
  return builder.Build();
}

// Moves every node of the rod onto the curve H(s) = H_0(0) exp(s [e1; twist e1 + curvature e3])
// through the retraction, then puts the element branches on the new configuration.
void BendAndTwist(const Model& model, Data& data) {
  const Rod& rod = model.rods.front();
  const SE3 H_root = model.nodes[static_cast<std::size_t>(rod.nodes.front())].reference;
  Vec6 xi;
  xi << 1.0, 0.0, 0.0, kTwist, 0.0, kCurvature;
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(model.nv);
  for (std::size_t i = 0; i < rod.nodes.size(); ++i) {
    const Node& node = model.nodes[static_cast<std::size_t>(rod.nodes[i])];
    if (node.dof < 0) continue;
    const double s = kLength * static_cast<double>(i) / rod.num_elements;
    const SE3 H_target = H_root * ExpSE3(s * xi);
    dx.segment<6>(node.dof) =
        LogSE3(data.H[static_cast<std::size_t>(rod.nodes[i])].Inverse() * H_target);
  }
  Retract(model, data, dx);
  UpdateBranchReferences(model, data);
}

void SetElementCounters(benchmark::State& state, const Model& model) {
  const auto elements = static_cast<int64_t>(model.elements.size());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * elements);
  state.counters["unknowns"] = model.num_unknowns();
  state.counters["bandwidth"] = model.bandwidth;
  state.counters["time_per_element"] = benchmark::Counter(
      static_cast<double>(elements),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_Assemble(benchmark::State& state) {
  const Model model = CantileverModel(static_cast<int>(state.range(0)));
  Data data = MakeData(model);
  BendAndTwist(model, data);
  const AssemblyOptions options;
  for (auto _ : state) {
    if (!Assemble(model, data, options)) {
      state.SkipWithError("Assemble failed");
      break;
    }
    benchmark::DoNotOptimize(data.residual.data());
    benchmark::ClobberMemory();
  }
  SetElementCounters(state, model);
}

// The factorisation works in place, so each iteration starts from a copy of the assembled
// matrix; only SolveAssembledSystem() is timed (manual time).
void BM_Solve(benchmark::State& state) {
  const Model model = CantileverModel(static_cast<int>(state.range(0)));
  Data data = MakeData(model);
  BendAndTwist(model, data);
  if (!Assemble(model, data, AssemblyOptions{})) {
    state.SkipWithError("Assemble failed");
    return;
  }
  const BandedLU assembled = data.matrix;
  for (auto _ : state) {
    data.matrix = assembled;
    benchmark::ClobberMemory();
    const auto start = std::chrono::steady_clock::now();
    const bool ok = SolveAssembledSystem(model, data);
    benchmark::DoNotOptimize(data.increment.data());
    benchmark::ClobberMemory();
    const auto stop = std::chrono::steady_clock::now();
    if (!ok) {
      state.SkipWithError("SolveAssembledSystem failed (singular matrix)");
      break;
    }
    state.SetIterationTime(std::chrono::duration<double>(stop - start).count());
  }
  SetElementCounters(state, model);
}

BENCHMARK(BM_Assemble)
    ->RangeMultiplier(10)
    ->Range(10, 10000)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
BENCHMARK(BM_Solve)
    ->RangeMultiplier(10)
    ->Range(10, 10000)
    ->Unit(benchmark::kMicrosecond)
    ->UseManualTime();

}  // namespace
}  // namespace screwfem

BENCHMARK_MAIN();
