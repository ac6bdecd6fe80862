// Contact couplings in the sparse pattern (docs/numerics.md, "Pairs and the sparse pattern"):
// memory and time per step of many spheres on a plane, and layers of crossing rods solved by
// the banded LU with the Woodbury coupling against the sparse LU whose pattern takes the pairs.
//
// Cases (h = 1e-3 s, rho_inf = 0.8, gravity, frictional contact; CPU time of the process per
// time step, after warm-up):
//   spheres/apart/N  N free spheres (rigid bodies, r = 5 cm, 0.1 kg) resting on a plane in a
//                    square grid 0.2 m apart (the case: every two may touch, none do);
//                    N = 100, 1000, 10000.
//   spheres/rows/N   the same spheres in rows along x, each touching its neighbours (centres
//                    2r - 0.2 mm apart; rows 0.2 m apart): a pair per neighbour, N - rows
//                    pairs, far beyond the banded solve's coupling room (128 nodes).
//   rods/KxK         K rods (20 elements, 0.2 m, r = 5 mm, clamped at both ends) along x under
//                    K free rods along y laid on them (0.5 mm gap, falling in gravity and
//                    pushed down at 0.05 m/s), mu = 0.3: K^2 crossings; K = 1 and 3 (the
//                    pairs' nodes fit the Woodbury room) and K = 6 (they exceed it:
//                    quasi-Newton).
// Spheres run with linear_solver auto (which takes the sparse LU: more nodes may be coupled
// than the room holds); rods with banded (Woodbury) and sparse. Memory: the heap the Data and
// the integrator hold after the timed steps (glibc mallinfo2, the in-use bytes beyond those
// before MakeData) and EstimateRunMemory's total and its Data and integrator parts (what the
// heap holds), each per sphere. The variants are interleaved
// (one timed run of each in turn, `rounds` times); the median run is reported.
// Output: JSON (format "screwfem pairs bench 1") on stdout or into the file given as the first
// argument; bench/make_results.py writes the section "Contact pairs in the sparse pattern" of
// bench/RESULTS.md from it.
#include <malloc.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/model/data.h"
#include "screwfem/model/memory.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"

namespace screwfem {
namespace {

double CpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double HeapInUse() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd);
}

std::string Name(const char* prefix, int i) {
  std::string s(prefix);
  s += std::to_string(i);
  return s;
}

ContactSettings Law(double stiffness) {
  ContactSettings law;
  law.stiffness = stiffness;
  law.onset = 1e-3;
  law.friction = 0.3;
  law.slip_velocity = 1e-3;
  return law;
}

// N spheres on the plane z = 0; `touching`: rows along x of 100 spheres (or fewer) whose
// neighbours overlap the onset, else a grid 0.2 m apart.
Model SpheresModel(int n, bool touching, LinearSolver solver) {
  const double r = 0.05;
  ModelBuilder b;
  b.SetLinearSolver(solver);
  for (int i = 0; i < n; ++i) {
    const double x = touching ? (2.0 * r - 2e-4) * (i % 100) : 0.2 * (i % 100);
    const double y = 0.2 * (i / 100);
    const NodeId node = b.AddNode(SE3::Translation(Vec3(x, y, r - 1e-4)), Name("s", i));
    const BodyId body =
        b.AddRigidBody(Name("s", i), node, 0.1, Vec3::Zero(), 1e-4 * Mat3::Identity());
    ContactShape shape;
    shape.body = static_cast<int>(body);
    shape.type = ContactShapeType::kSphere;
    shape.radius = r;
    b.AddContactShape(shape);
  }
  ContactObstacle plane;
  plane.name = "ground";
  b.AddObstacle(plane);
  b.SetContactSettings(Law(1e4));
  b.SetGravity(Vec3(0, 0, -9.81));
  return b.Build();
}

// K clamped rods along x under K free rods along y.
Model RodsModel(int k, LinearSolver solver) {
  const double r = 0.005, L = 0.2;
  Material mat;
  mat.youngs_modulus = 1e8;
  mat.poisson_ratio = 0.4;
  mat.density = 1000.0;
  const Section section = Section::Circle(r, mat);
  ModelBuilder b;
  b.SetLinearSolver(solver);
  std::vector<RodId> top;
  for (int i = 0; i < k; ++i) {
    const double y = L * (i + 0.5) / k;
    const RodId rod = b.AddStraightRod(Name("x", i), Vec3(0, y, 0), Vec3(L, y, 0), 20, section);
    b.FixNode(b.RodNodes(rod).front());
    b.FixNode(b.RodNodes(rod).back());
    b.AddContactRod(rod, r);
  }
  for (int i = 0; i < k; ++i) {
    const double x = L * (i + 0.5) / k;
    const RodId rod = b.AddStraightRod(Name("y", i), Vec3(x, 0, 2 * r + 5e-4),
                                       Vec3(x, L, 2 * r + 5e-4), 20, section);
    b.AddContactRod(rod, r);
    top.push_back(rod);
  }
  b.SetContactSettings(Law(100.0));
  for (RodId rod : top)
    for (NodeId node : b.RodNodes(rod)) {
      const Mat3& R = b.model().nodes[static_cast<std::size_t>(node)].reference.R;
      Vec6 eta = Vec6::Zero();
      eta.head<3>() = R.transpose() * Vec3(0, 0, -0.05);
      b.SetInitialVelocity(node, eta);
    }
  b.SetGravity(Vec3(0, 0, -9.81));
  return b.Build();
}

struct Variant {
  std::string name, solver;
  Model model;
  int count = 0;  // spheres (or rods)
  int warmup = 3, steps = 10;
  int max_runs = 1000;  // the quasi-Newton banded case beyond the room runs once (it is slow)
  std::vector<double> seconds;  // per timed run: CPU s per step
  long iterations = 0, timed_steps = 0;
  double heap = 0.0;  // bytes held by Data and the integrator after the timed steps
  double estimate = 0.0;
  double model_bytes = 0.0;    // EstimateModelMemory
  double data_estimate = 0.0;  // EstimateDataMemory + EstimateIntegratorMemory (what heap holds)
  long pairs = 0, most_coupled = 0, analyses = 0, pattern_changes = 0, pattern_hits = 0;
  bool failed = false;
};

void RunOnce(Variant& v) {
  if (static_cast<int>(v.seconds.size()) >= v.max_runs) return;
  const double heap0 = HeapInUse();
  Data data = MakeData(v.model);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 0.8;
  const double h = 1e-3;
  if (!AssembleInitialState(v.model, data) || !InitializeDynamics(v.model, data, integ, options)) {
    v.failed = true;
    return;
  }
  for (int i = 0; i < v.warmup; ++i) {
    if (!Step(v.model, data, integ, h).ok) v.failed = true;
    data.time += h;
  }
  const long before = integ.iterations;
  const double t0 = CpuSeconds();
  for (int i = 0; i < v.steps; ++i) {
    if (!Step(v.model, data, integ, h).ok) v.failed = true;
    data.time += h;
    v.most_coupled = std::max<long>(v.most_coupled, data.coupling.blocks());
  }
  const double t1 = CpuSeconds();
  v.seconds.push_back((t1 - t0) / v.steps);
  v.iterations += integ.iterations - before;
  v.timed_steps += v.steps;
  v.heap = HeapInUse() - heap0;
  v.pairs = data.num_shape_pairs;
  v.analyses = data.sparse.analyses();
  v.pattern_changes = data.sparse.pattern_changes();
  v.pattern_hits = data.sparse.pattern_hits();
  std::fprintf(stderr, "%s %s: %.3g s per step, %.3g Newton per step, %ld pairs, %s\n",
               v.name.c_str(), v.solver.c_str(), v.seconds.back(),
               static_cast<double>(integ.iterations - before) / v.steps, v.pairs,
               v.failed ? "failed" : "ok");
}

Variant MakeVariant(const std::string& name, const char* solver, Model model, int count) {
  Variant v;
  v.name = name;
  v.solver = solver;
  v.model = std::move(model);
  v.count = count;
  const std::vector<MemoryPart> parts = EstimateRunMemory(v.model, IntegratorMemoryOptions{});
  v.estimate = TotalBytes(parts);
  v.model_bytes = EstimateModelMemory(v.model).bytes;
  v.data_estimate = v.estimate - v.model_bytes;
  for (const MemoryPart& p : parts)
    std::fprintf(stderr, "%s: %s %.3g MB\n", name.c_str(), p.part.c_str(), 1e-6 * p.bytes);
  return v;
}

double Median(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  return x.empty() ? NAN : x[x.size() / 2];
}

}  // namespace
}  // namespace screwfem

int main(int argc, char** argv) {
  using namespace screwfem;
  const int rounds = argc > 2 ? std::atoi(argv[2]) : 5;
  std::vector<Variant> variants;
  for (int n : {100, 1000, 10000}) {
    variants.push_back(MakeVariant(Name("spheres/apart/", n), "auto",
                                   SpheresModel(n, false, LinearSolver::kAuto), n));
    variants.push_back(MakeVariant(Name("spheres/rows/", n), "auto",
                                   SpheresModel(n, true, LinearSolver::kAuto), n));
  }
  for (int k : {1, 3, 6})
    for (const auto& [solver, name] :
         {std::pair{LinearSolver::kBanded, "banded"}, std::pair{LinearSolver::kSparse, "sparse"},
          std::pair{LinearSolver::kAuto, "auto"}}) {
      std::string label = Name("rods/", k);
      label += 'x';
      label += std::to_string(k);
      variants.push_back(MakeVariant(label, name, RodsModel(k, solver), 2 * k));
      if (k == 6 && solver != LinearSolver::kSparse && !variants.back().model.sparse_solver) {
        variants.back().warmup = 1;
        variants.back().steps = 2;
        variants.back().max_runs = 1;
      }
    }
  // A third argument keeps the cases whose name contains it.
  if (argc > 3)
    variants.erase(
        std::remove_if(variants.begin(), variants.end(),
                       [&](const Variant& v) { return v.name.find(argv[3]) == std::string::npos; }),
        variants.end());
  for (int r = 0; r < rounds; ++r)
    for (Variant& v : variants) RunOnce(v);
  std::FILE* out = argc > 1 ? std::fopen(argv[1], "w") : stdout;
  if (!out) return 1;
  std::fprintf(out, "{\n  \"format\": \"screwfem pairs bench 1\",\n  \"rounds\": %d,\n", rounds);
  std::fprintf(out, "  \"cases\": [\n");
  for (std::size_t i = 0; i < variants.size(); ++i) {
    const Variant& v = variants[i];
    const double newton =
        v.timed_steps > 0 ? static_cast<double>(v.iterations) / v.timed_steps : 0.0;
    std::fprintf(out,
                 "    {\"case\": \"%s\", \"solver\": \"%s\", \"chosen\": \"%s\", \"failed\": %s, "
                 "\"count\": %d, \"unknowns\": %d, \"bandwidth\": %d, \"pairs\": %ld, "
                 "\"most_coupled_nodes\": %ld, \"cpu_per_step\": %.6g, \"newton_per_step\": %.4g, "
                 "\"heap_bytes\": %.6g, \"estimated_bytes\": %.6g, \"model_bytes\": %.6g, "
                 "\"data_estimated_bytes\": %.6g, \"banded_cost\": %.6g, \"sparse_cost\": %.6g, "
                 "\"coupled_nodes\": %d, \"analyses\": %ld, "
                 "\"pattern_changes\": %ld, \"pattern_hits\": %ld}%s\n",
                 v.name.c_str(), v.solver.c_str(), v.model.sparse_solver ? "sparse" : "banded",
                 v.failed ? "true" : "false", v.count, v.model.num_unknowns(), v.model.bandwidth,
                 v.pairs, v.most_coupled, Median(v.seconds), newton, v.heap, v.estimate,
                 v.model_bytes, v.data_estimate, PredictedBandedCost(v.model),
                 std::isfinite(PredictedSparseCost(v.model)) ? PredictedSparseCost(v.model) : -1.0,
                 v.model.coupled_nodes, v.analyses, v.pattern_changes, v.pattern_hits,
                 i + 1 < variants.size() ? "," : "");
  }
  std::fprintf(out, "  ]\n}\n");
  if (out != stdout) std::fclose(out);
  return 0;
}
