// The parallel assembly (assemble.h, SetAssemblyThreads; docs/architecture.md, "Parallel
// assembly"): the rod elements' kernels on 2 and 3 threads give the same doubles as on one,
// step after step, on a rod of several chunks, the GRM with soft bodies and a contact scene;
// an element that fails stops the assembly at the same element with the same partial sums;
// analysis.threads reaches the run and its summary.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <stdexcept>
#include <utility>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/solve/statics.h"

namespace screwfem::parallel_assembly_test {
namespace {

// A cantilever of n elements in gravity (bench/dynamics_bench.cpp's rod), with joint-free
// damping so that every kind of block (stiffness, mass, damping) is formed.
Model Cantilever(int n) {
  Vec6 K, M;
  K << 1e6, 1e6, 1e6, 1.0, 1.0, 1.0;
  M << 0.1, 0.1, 0.1, 0.5, 0.5, 0.5;
  Section section = Section::FromDiagonals(K, M);
  section.damping << 0, 0, 0, 0.01, 0.01, 0.01;
  ModelBuilder b;
  const int rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3(1, 0, 0), n, section);
  b.FixNode(NodeId(b.model().rods[static_cast<std::size_t>(rod)].nodes.front()));
  b.SetGravity(Vec3(0, 0, -9.81));
  return b.Build();
}

// The state of a Data as bytes: node and joint frames, coordinates, velocities,
// accelerations, multipliers and the last residual.
std::vector<unsigned char> StateBytes(const Data& d) {
  std::vector<unsigned char> bytes;
  const auto add = [&](const void* p, std::size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    bytes.insert(bytes.end(), c, c + n);
  };
  for (const SE3& H : d.H) add(&H, sizeof(SE3));
  for (const SE3& H : d.HJ) add(&H, sizeof(SE3));
  for (const Eigen::VectorXd* v : {&d.q_joint, &d.v, &d.vdot, &d.lambda, &d.residual})
    add(v->data(), sizeof(double) * static_cast<std::size_t>(v->size()));
  add(&d.time, sizeof(double));
  return bytes;
}

struct Outcome {
  std::vector<unsigned char> state;
  long iterations = 0;
  int threads = 0;
};

// `steps` fixed steps of h from the model's initial state with the given threads.
Outcome Simulate(const Model& model, int threads, int steps, double h, bool initial_state = false) {
  Data data = MakeData(model);
  SetAssemblyThreads(data, threads);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 0.8;
  std::string message;
  if (initial_state) {
    EXPECT_TRUE(AssembleInitialState(model, data, &message)) << message;
  }
  EXPECT_TRUE(InitializeDynamics(model, data, integ, options, &message)) << message;
  for (int i = 0; i < steps; ++i) {
    const StepResult r = Step(model, data, integ, h);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) break;
    data.time += h;
  }
  return {StateBytes(data), integ.iterations, data.parallel.threads()};
}

// The scene's own steps (its analysis.step over the step schedule) up to `steps`.
Outcome SimulateScene(const Scene& scene, int threads, int steps) {
  const Model& model = scene.model;
  const AnalysisSettings& a = scene.analysis;
  Data data = MakeData(model);
  SetAssemblyThreads(data, threads);
  Integrator integ;
  std::string message;
  data.time = a.start_time;
  EXPECT_TRUE(AssembleInitialState(model, data, &message)) << message;
  EXPECT_TRUE(InitializeDynamics(model, data, integ, a.dynamic, &message)) << message;
  const StepSchedule schedule(a.start_time, a.end_time, a.step,
                              a.align_steps ? ProfileBreakpoints(model) : std::vector<double>{});
  for (int i = 0; i < steps && !schedule.Done(data.time); ++i) {
    const double t = schedule.Next(data.time);
    const StepResult r = Step(model, data, integ, t - data.time);
    EXPECT_TRUE(r.ok) << r.message;
    if (!r.ok) break;
    data.time = t;
  }
  return {StateBytes(data), integ.iterations, data.parallel.threads()};
}

void ExpectSameRuns(const Outcome& serial, const Outcome& parallel) {
  EXPECT_EQ(parallel.iterations, serial.iterations);
  ASSERT_EQ(parallel.state.size(), serial.state.size());
  EXPECT_EQ(std::memcmp(parallel.state.data(), serial.state.data(), serial.state.size()), 0)
      << "the state differs from the serial assembly's";
}

// 605 elements: more than the ring of 2 kParallelChunk, its last block partial.
TEST(ParallelAssembly, RodStatesAreBitwiseTheSameOnOneTwoAndThreeThreads) {
  static_assert(2 * kParallelChunk < 605);
  const Model model = Cantilever(605);
  const Outcome serial = Simulate(model, 1, 20, 1e-3);
  EXPECT_EQ(serial.threads, 1);
  EXPECT_GT(serial.iterations, 20);
  for (int threads : {2, 3}) {
    SCOPED_TRACE(threads);
    const Outcome parallel = Simulate(model, threads, 20, 1e-3);
    EXPECT_EQ(parallel.threads, threads);
    ExpectSameRuns(serial, parallel);
    // Run after run.
    ExpectSameRuns(parallel, Simulate(model, threads, 20, 1e-3));
  }
}

// Statics (no inertia, load stepping) on the pool gives the serial equilibrium too.
TEST(ParallelAssembly, StaticSolutionIsBitwiseTheSame) {
  const Model model = Cantilever(300);
  std::vector<unsigned char> states[2];
  for (int threads : {1, 2}) {
    Data data = MakeData(model);
    SetAssemblyThreads(data, threads);
    const StaticResult r = SolveStatic(model, data);
    ASSERT_TRUE(r.converged) << r.message;
    states[threads - 1] = StateBytes(data);
  }
  EXPECT_EQ(states[0], states[1]);
}

TEST(ParallelAssembly, GrmWithSoftBodiesIsBitwiseTheSame) {
  const Scene scene = LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/grm_soft_kd.yaml",
                                {"defaults.elements=8", "analysis.step=1e-3"});
  ASSERT_GT(scene.model.elements.size(), 8u);
  const Outcome serial = SimulateScene(scene, 1, 150);
  for (int threads : {2, 3}) {
    SCOPED_TRACE(threads);
    ExpectSameRuns(serial, SimulateScene(scene, threads, 150));
  }
}

// The coiling rod on a plane with friction (examples/contact/coil.yaml): contacts and a
// programmed rest curvature (actuators) on the rod elements.
TEST(ParallelAssembly, ContactSceneIsBitwiseTheSame) {
  const Scene scene =
      LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/contact/coil.yaml", {});
  ASSERT_FALSE(scene.model.contact_segments.empty());
  const Outcome serial = SimulateScene(scene, 1, 300);
  for (int threads : {2, 3}) {
    SCOPED_TRACE(threads);
    ExpectSameRuns(serial, SimulateScene(scene, threads, 300));
  }
}

// An element past its rotation limit, on the second lap of the ring: the assembly stops at the same
// element, with the same rotation, and with the same partial residual as the serial loop.
TEST(ParallelAssembly, FailingElementStopsAtTheSameElement) {
  const Model model = Cantilever(600);
  const int bad_node = 560;  // elements 559 (node_b) and 560 (node_a), past the ring, twist
  struct Result {
    bool ok;
    int element;
    double rotation;
    std::vector<unsigned char> state;
  };
  std::vector<Result> results;
  for (int threads : {1, 2, 3}) {
    Data data = MakeData(model);
    SetAssemblyThreads(data, threads);
    data.H[bad_node].R = data.H[bad_node].R * ExpSO3(Vec3(7.0, 0, 0));
    data.w_ref[bad_node - 1] = Vec3(7.0, 0, 0);  // on the branch past 2 pi
    AssemblyOptions o;
    const bool ok = Assemble(model, data, o);
    results.push_back({ok, data.failed_element, data.failed_rotation, StateBytes(data)});
  }
  EXPECT_FALSE(results[0].ok);
  EXPECT_EQ(results[0].element, bad_node - 1);
  EXPECT_GT(results[0].rotation, model.max_element_rotation);
  for (std::size_t i = 1; i < results.size(); ++i) {
    EXPECT_EQ(results[i].ok, results[0].ok);
    EXPECT_EQ(results[i].element, results[0].element);
    EXPECT_EQ(results[i].rotation, results[0].rotation);
    EXPECT_EQ(results[i].state, results[0].state);
  }
}

// auto: one thread below kParallelMinElements rod elements, every available core from there;
// a number is taken as given (at most kMaxAssemblyThreads).
TEST(ParallelAssembly, AutoUsesTheCoresForLargeModelsOnly) {
  const Model small = Cantilever(kParallelMinElements - 1);
  const Model large = Cantilever(kParallelMinElements);
  EXPECT_EQ(ResolveAssemblyThreads(small, kAutoThreads), 1);
  EXPECT_EQ(ResolveAssemblyThreads(large, kAutoThreads), AvailableCores());
  EXPECT_EQ(ResolveAssemblyThreads(small, 3), 3);
  EXPECT_EQ(ResolveAssemblyThreads(small, 1000), kMaxAssemblyThreads);
  EXPECT_GE(AvailableCores(), 1);
}

// A copy of a Data is an independent simulation: a pool of its own with as many threads; a
// Data set back to one thread has no pool.
TEST(ParallelAssembly, CopiedDataHasItsOwnPool) {
  const Model model = Cantilever(10);
  Data a = MakeData(model);
  EXPECT_EQ(a.parallel.threads(), 1);
  EXPECT_EQ(a.parallel.pool(), nullptr);
  SetAssemblyThreads(a, 2);
  ASSERT_NE(a.parallel.pool(), nullptr);
  EXPECT_EQ(a.parallel.pool()->size(), 2);
  EXPECT_EQ(a.parallel.items().size(), static_cast<std::size_t>(2 * kParallelChunk));
  const Data b = a;
  EXPECT_EQ(b.parallel.threads(), 2);
  ASSERT_NE(b.parallel.pool(), nullptr);
  EXPECT_NE(b.parallel.pool(), a.parallel.pool());
  SetAssemblyThreads(a, 1);
  EXPECT_EQ(a.parallel.pool(), nullptr);
  EXPECT_TRUE(a.parallel.items().empty());
}

// The pool rethrows a job's exception on the calling thread, after every thread returned, and
// runs the next job as usual.
TEST(ParallelAssembly, PoolRethrowsAJobsException) {
  ThreadPool pool(3);
  std::atomic<int> calls{0};
  const auto count = [](void* c, int) { ++*static_cast<std::atomic<int>*>(c); };
  const auto fail = [](void* c, int worker) {
    ++*static_cast<std::atomic<int>*>(c);
    if (worker == 2) throw std::runtime_error("worker 2");
  };
  EXPECT_THROW(pool.Run(fail, &calls), std::runtime_error);
  EXPECT_EQ(calls.load(), 3);
  for (int i = 0; i < 100; ++i) pool.Run(count, &calls);
  EXPECT_EQ(calls.load(), 303);
}

// analysis.threads reaches the run: summary.json reports the threads used, 'auto' resolved.
TEST(ParallelAssembly, SummaryReportsTheThreads) {
  const std::string scene_path = std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/grm_soft_k.yaml";
  for (const auto& [value, expected] :
       std::vector<std::pair<std::string, int>>{{"2", 2}, {"auto", 1}}) {
    SCOPED_TRACE(value);
    test::ScopedDir dir("parallel_summary");
    const Scene scene =
        LoadScene(scene_path, {"analysis.end_time=0.01", "analysis.threads=" + value});
    const RunResult r = RunScene(scene, dir.path());
    ASSERT_TRUE(r.ok) << r.message;
    const std::string summary = test::ReadFile(dir.path() + "/summary.json");
    EXPECT_NE(summary.find("\"threads\": " + std::to_string(expected) + ","), std::string::npos)
        << summary;
  }
}

}  // namespace
}  // namespace screwfem::parallel_assembly_test
