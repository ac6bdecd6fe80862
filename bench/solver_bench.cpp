// Cost of the direct solvers of the Newton systems (docs/numerics.md, "Sparse direct solve"):
// the banded LU, the sparse LU (KLU) and the automatic choice, on the models whose band is
// wide although few of its entries are nonzero, against the models a band suits.
//
// Cases (CPU time of the process per time step, h = 1e-3 s, rho_inf = 0.8, after warm-up):
//   rod/320        a 320-element rod (GRM arm section, 1 m) clamped at one end, in gravity:
//                  the reference cost per element and Newton iteration.
//   hand/40x8      a palm (rigid body on a spherical joint to the ground) with 40 fingers of
//                  8 elements each (0.1 m, all rooted at the palm's node, fanned out over
//                  +-1 rad in two layers), in
//                  gravity: 320 elements, band 6 x 40 + 5.
//   finger/256     a 256-element finger (1 m) clamped at its base, in gravity, without and
//                  with a tendon drawn by length (shortened 2 mm over 0.1 s) through an eyelet
//                  on every node: one constraint row across every node.
//   chain/64       64 rigid links on spherical joints (a hanging chain released sideways).
//   grm_rigid      examples/grm/grm_rigid.yaml with defaults.elements=4.
// Every case runs with analysis.linear_solver banded, sparse and auto; the variants of all cases
// are interleaved (one timed run of each in turn, `rounds` times) and the median is reported.
// Per element and Newton iteration: CPU time / (steps x elements x mean iterations).
// Output: JSON (format "screwfem solver bench 1") on stdout or into the file given as the
// first argument; bench/make_results.py writes the section "Sparse direct solve" of
// bench/RESULTS.md from it.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/data.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"

#ifndef SCREWFEM_SOURCE_DIR
#error "SCREWFEM_SOURCE_DIR must name the source tree (examples/grm)"
#endif

namespace screwfem {
namespace {

double CpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// prefix + i (not "literal" + std::to_string: GCC 12 warns falsely, -Wrestrict).
std::string Name(const char* prefix, int i) {
  std::string s(prefix);
  s += std::to_string(i);
  return s;
}

Section ArmSection() {
  Vec6 K, M;
  K << 1e6, 1e6, 1e6, 1, 1, 1;
  M << 0.1, 0.1, 0.1, 0.05, 0.25, 0.25;
  return Section::FromDiagonals(K, M);
}

Model RodModel(int elements, LinearSolver solver) {
  ModelBuilder b;
  b.SetLinearSolver(solver);
  const RodId rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3(1, 0, 0), elements, ArmSection());
  b.FixNode(b.RodNodes(rod).front());
  b.SetGravity(Vec3(0, 0, -9.81));
  return b.Build();
}

Model HandModel(int fingers, int elements, LinearSolver solver) {
  ModelBuilder b;
  b.SetLinearSolver(solver);
  const NodeId palm = b.AddNode(SE3::Identity(), "palm");
  b.AddRigidBody("palm", palm, 0.2, Vec3::Zero(), 1e-4 * Mat3::Identity());
  b.AddJointAt("wrist", JointType::kSpherical, kGround, palm, Vec3(0, 0, 0.02));
  Vec6 K, M;
  K << 1e5, 1e5, 1e5, 0.05, 0.05, 0.05;
  M << 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4;
  const Section finger = Section::FromDiagonals(K, M);
  for (int f = 0; f < fingers; ++f) {
    // Fanned out within +-1 rad of the palm's x axis, in two layers (the palm node's frame
    // is the first node's of every finger: a finger must not turn from it by pi).
    const double a = -1.0 + 2.0 * f / std::max(fingers - 1, 1);
    const Vec3 dir(std::cos(a), std::sin(a), f % 2 == 0 ? 0.2 : -0.2);
    b.AddStraightRod(Name("f", f), Vec3::Zero(), 0.1 * dir.normalized(), elements, finger,
                     Vec3::UnitZ(), palm);
  }
  b.SetGravity(Vec3(0, 0, -9.81));
  return b.Build();
}

Model FingerModel(int elements, bool tendon, LinearSolver solver) {
  ModelBuilder b;
  b.SetLinearSolver(solver);
  const RodId rod = b.AddStraightRod("finger", Vec3::Zero(), Vec3(1, 0, 0), elements, ArmSection());
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  if (tendon) {
    std::vector<BodyPoint> eyelets;
    for (const NodeId n : nodes) eyelets.push_back({n, Vec3(0, 0.02, 0)});
    b.AddLengthDrivenTendon("flexor", eyelets,
                            Profile::Constant(1.0).Add(Profile::Ramp(0, 0.1, -0.002)));
  }
  b.SetGravity(Vec3(0, 0, -9.81));
  return b.Build();
}

Model ChainModel(int links, LinearSolver solver) {
  ModelBuilder b;
  b.SetLinearSolver(solver);
  NodeId prev = kGround;
  for (int i = 0; i < links; ++i) {
    const Vec3 at(0.05 * (i + 1), 0, 0);
    const NodeId node = b.AddNode(SE3::Translation(at), Name("l", i));
    b.AddRigidBody(Name("l", i), node, 0.01, Vec3(-0.025, 0, 0), 1e-6 * Mat3::Identity());
    b.AddJointAt(Name("j", i), JointType::kSpherical, prev, node, Vec3(0.05 * i, 0, 0));
    prev = node;
  }
  b.SetGravity(Vec3(0, 0, -9.81));
  return b.Build();
}

Model GrmModel(LinearSolver solver) {
  const char* names[] = {"auto", "banded", "sparse"};
  Scene s = LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/grm_rigid.yaml",
                      {"defaults.elements=4",
                       std::string("analysis.linear_solver=") + names[static_cast<int>(solver)]});
  return s.model;
}

struct Variant {
  std::string name, solver;
  Model model;
  int elements = 0;
  int warmup = 5, steps = 20;
  std::vector<double> seconds;  // per timed run: CPU s per step
  long iterations = 0, timed_steps = 0;
  bool failed = false;
};

void RunOnce(Variant& v) {
  Data data = MakeData(v.model);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 0.8;
  const double h = 1e-3;
  if (!AssembleInitialState(v.model, data) || !InitializeDynamics(v.model, data, integ, options)) {
    v.failed = true;
    return;
  }
  // Step advances data.time by h itself.
  for (int i = 0; i < v.warmup; ++i)
    if (!Step(v.model, data, integ, h).ok) v.failed = true;
  const long before = integ.iterations;
  const double t0 = CpuSeconds();
  for (int i = 0; i < v.steps; ++i)
    if (!Step(v.model, data, integ, h).ok) v.failed = true;
  const double t1 = CpuSeconds();
  v.seconds.push_back((t1 - t0) / v.steps);
  v.iterations += integ.iterations - before;
  v.timed_steps += v.steps;
}

// One matrix of the sparse variant `v` (assembled after InitializeDynamics and two steps),
// factorised `repeats` times by KLU (refactorisation), by Eigen's SparseLU (factorize() on
// the pattern analysed once) and, for comparison, Eigen's solution checked against KLU's.
// CPU seconds per factorisation.
struct FactorTimes {
  double klu_refactor = NAN, klu_full = NAN, eigen = NAN, difference = NAN;
};
FactorTimes TimeFactorisations(const Model& model, int repeats) {
  FactorTimes t;
  Data data = MakeData(model);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 0.8;
  if (!AssembleInitialState(model, data) || !InitializeDynamics(model, data, integ, options))
    return t;
  for (int i = 0; i < 2; ++i) Step(model, data, integ, 1e-3);
  const int n = model.num_unknowns();
  std::vector<Eigen::Triplet<double>> entries;
  data.sparse.ForEachEntry([&](int i, int j, double v) { entries.emplace_back(i, j, v); });
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());
  A.makeCompressed();
  double t0 = CpuSeconds();
  for (int r = 0; r < repeats; ++r) data.sparse.Factorize();
  t.klu_refactor = (CpuSeconds() - t0) / repeats;
  SparseLU fresh = data.sparse;  // a copy: analysed again, its first factorisation is full
  t0 = CpuSeconds();
  fresh.Factorize();
  t.klu_full = CpuSeconds() - t0;
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  lu.analyzePattern(A);
  t0 = CpuSeconds();
  for (int r = 0; r < repeats; ++r) lu.factorize(A);
  t.eigen = (CpuSeconds() - t0) / repeats;
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 1.0), x = b;
  data.sparse.Solve(x);
  const Eigen::VectorXd y = lu.solve(b);
  t.difference = (x - y).norm() / x.norm();
  return t;
}

Variant MakeVariant(const std::string& name, const char* solver, Model model, int elements) {
  Variant v;
  v.name = name;
  v.solver = solver;
  v.model = std::move(model);
  v.elements = elements;
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
  const int rounds = 9;
  std::vector<Variant> variants;
  const struct {
    LinearSolver solver;
    const char* name;
  } solvers[] = {{LinearSolver::kBanded, "banded"},
                 {LinearSolver::kSparse, "sparse"},
                 {LinearSolver::kAuto, "auto"}};
  for (const auto& s : solvers) {
    variants.push_back(MakeVariant("rod/320", s.name, RodModel(320, s.solver), 320));
    variants.push_back(MakeVariant("hand/40x8", s.name, HandModel(40, 8, s.solver), 320));
    variants.push_back(MakeVariant("finger/256", s.name, FingerModel(256, false, s.solver), 256));
    variants.push_back(
        MakeVariant("finger/256+tendon", s.name, FingerModel(256, true, s.solver), 256));
    variants.push_back(MakeVariant("chain/64", s.name, ChainModel(64, s.solver), 64));
    variants.push_back(MakeVariant("grm_rigid", s.name, GrmModel(s.solver), 0));
  }
  for (Variant& v : variants) v.elements = std::max(v.elements, 1);
  for (int r = 0; r < rounds; ++r)
    for (Variant& v : variants) RunOnce(v);
  std::FILE* out = argc > 1 ? std::fopen(argv[1], "w") : stdout;
  if (!out) return 1;
  std::fprintf(out, "{\n  \"format\": \"screwfem solver bench 1\",\n  \"rounds\": %d,\n", rounds);
  std::fprintf(out, "  \"cases\": [\n");
  for (std::size_t i = 0; i < variants.size(); ++i) {
    const Variant& v = variants[i];
    const double per_step = Median(v.seconds);
    const double newton =
        v.timed_steps > 0 ? static_cast<double>(v.iterations) / v.timed_steps : 0.0;
    std::fprintf(out,
                 "    {\"case\": \"%s\", \"solver\": \"%s\", \"chosen\": \"%s\", \"failed\": %s, "
                 "\"unknowns\": %d, \"bandwidth\": %d, \"elements\": %d, "
                 "\"banded_flops\": %.6g, \"sparse_flops\": %.6g, "
                 "\"cpu_per_step\": %.6g, \"newton_per_step\": %.4g, "
                 "\"cpu_per_element_iteration\": %.6g}%s\n",
                 v.name.c_str(), v.solver.c_str(), v.model.sparse_solver ? "sparse" : "banded",
                 v.failed ? "true" : "false", v.model.num_unknowns(), v.model.bandwidth, v.elements,
                 v.model.banded_flops, v.model.sparse_flops, per_step, newton,
                 per_step / (v.elements * std::max(newton, 1e-9)),
                 i + 1 < variants.size() ? "," : "");
  }
  std::fprintf(out, "  ],\n  \"factorisations\": [\n");
  const struct {
    const char* name;
    Model model;
  } matrices[] = {{"hand/40x8", HandModel(40, 8, LinearSolver::kSparse)},
                  {"finger/256+tendon", FingerModel(256, true, LinearSolver::kSparse)},
                  {"rod/320", RodModel(320, LinearSolver::kSparse)}};
  for (std::size_t i = 0; i < std::size(matrices); ++i) {
    const FactorTimes t = TimeFactorisations(matrices[i].model, 50);
    std::fprintf(out,
                 "    {\"case\": \"%s\", \"klu_refactor\": %.6g, \"klu_full\": %.6g, "
                 "\"eigen_sparselu\": %.6g, \"solution_difference\": %.3g}%s\n",
                 matrices[i].name, t.klu_refactor, t.klu_full, t.eigen, t.difference,
                 i + 1 < std::size(matrices) ? "," : "");
  }
  std::fprintf(out, "  ]\n}\n");
  if (out != stdout) std::fclose(out);
  return 0;
}
