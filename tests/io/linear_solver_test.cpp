// The choice of the direct solver (analysis.linear_solver, docs/numerics.md, "Sparse direct
// solve"): the banded and the sparse LU give the same Newton iterates on every example scene,
// the sparse LU analyses its pattern once, summary.json reports the choice and its counters,
// and a bad value is an error at its place in the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

namespace screwfem::linear_solver_test {
namespace {

using test::Json;
using test::ParseJsonFile;
using test::ScopedDir;

struct SolverRun {
  Model model;
  Data data;
  RunResult result;
  std::optional<Json> summary;
};

// Runs `steps` fixed steps of an example scene with the given solver (no ParaView frames).
SolverRun RunExample(const std::string& file, const std::string& solver, int steps) {
  const std::string path = std::string(SCREWFEM_SOURCE_DIR) + "/examples/" + file;
  const Scene probe = LoadScene(path);
  const double end = probe.analysis.start_time + steps * probe.analysis.step;
  char end_text[64];
  std::snprintf(end_text, sizeof end_text, "analysis.end_time=%.17g", end);
  std::string choice = "analysis.linear_solver=";
  choice += solver;
  const Scene s = LoadScene(path, {choice, "outputs.vtk=false", std::string(end_text)});
  SolverRun run{s.model, MakeData(s.model), {}, {}};
  Integrator integ;
  std::string tag = "linear_solver_";
  tag += solver;
  const ScopedDir dir(tag);
  run.result = RunScene(s, run.data, integ, dir.path());
  run.summary = ParseJsonFile(dir.path() + "/summary.json");
  return run;
}

std::string SummaryText(const SolverRun& run, const std::string& key) {
  const Json* v = run.summary ? run.summary->Find(key) : nullptr;
  return v && v->kind == Json::Kind::kString ? v->string : "(none)";
}
double SummaryNumber(const SolverRun& run, const std::string& key) {
  const Json* v = run.summary ? run.summary->Find(key) : nullptr;
  return v && v->kind == Json::Kind::kNumber ? v->number : NAN;
}

TEST(LinearSolver, BandedAndSparseGiveTheSameIteratesOnEveryExampleScene) {
  for (const char* file :
       {"contact/coil.yaml", "contact/slide.yaml", "gripper/gripper.yaml", "grm/grm_rigid.yaml",
        "grm/grm_soft_k.yaml", "grm/grm_soft_kd.yaml", "grm/grm_soft_k_parallel.yaml",
        "grm/grm_soft_kd_parallel.yaml", "pneumatic/finger.yaml", "tendon/finger.yaml",
        "python/soft_arm_control.yaml", "python/two_tendon_arm.yaml"}) {
    SCOPED_TRACE(file);
    const int steps = 4;
    const SolverRun banded = RunExample(file, "banded", steps);
    const SolverRun sparse = RunExample(file, "sparse", steps);
    ASSERT_TRUE(banded.result.ok) << banded.result.message;
    ASSERT_TRUE(sparse.result.ok) << sparse.result.message;
    EXPECT_FALSE(banded.model.sparse_solver);
    EXPECT_TRUE(sparse.model.sparse_solver);
    EXPECT_EQ(banded.result.steps, steps);
    EXPECT_EQ(sparse.result.newton_iterations, banded.result.newton_iterations);
    // Node frames (positions scaled by the model's length), velocities, multipliers.
    const double L = banded.model.length_scale;
    double dx = 0.0, dR = 0.0;
    for (std::size_t i = 0; i < banded.data.H.size(); ++i) {
      dx = std::max(dx, (banded.data.H[i].x - sparse.data.H[i].x).norm() / L);
      dR = std::max(dR, (banded.data.H[i].R - sparse.data.H[i].R).norm());
    }
    EXPECT_LT(dx, 1e-10);
    EXPECT_LT(dR, 1e-10);
    // (velocities relative to the largest, at least L per second: some scenes start at rest)
    const double v = std::max(banded.data.v.cwiseAbs().maxCoeff(), L / 1.0);
    EXPECT_LT((banded.data.v - sparse.data.v).cwiseAbs().maxCoeff(), 1e-10 * v);
    if (banded.data.lambda.size() > 0) {
      const double lam = std::max(banded.data.lambda.cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT((banded.data.lambda - sparse.data.lambda).cwiseAbs().maxCoeff(), 1e-9 * lam);
    }
    // The sparse LU analysed its pattern once, and once per list of contact couplings not met
    // before (the scenes with pairs of moving shapes), and refactorised at every later
    // factorisation.
    const SparseLU& lu = sparse.data.sparse;
    EXPECT_EQ(lu.analyses(), 1 + lu.pattern_changes() - lu.pattern_hits());
    if (sparse.data.num_shape_pairs == 0 && lu.pattern_changes() == 0) {
      EXPECT_EQ(lu.analyses(), 1);
    }
    EXPECT_GT(sparse.data.sparse.factorizations(), 0);
    EXPECT_EQ(banded.data.sparse.analyses(), 0);
    // summary.json: the choice and the counters.
    EXPECT_EQ(SummaryText(banded, "linear_solver.requested"), "banded");
    EXPECT_EQ(SummaryText(banded, "linear_solver.chosen"), "banded");
    EXPECT_EQ(SummaryText(sparse, "linear_solver.requested"), "sparse");
    EXPECT_EQ(SummaryText(sparse, "linear_solver.chosen"), "sparse");
    EXPECT_EQ(SummaryNumber(sparse, "linear_solver.symbolic_analyses"),
              static_cast<double>(lu.analyses()));
    EXPECT_EQ(SummaryNumber(sparse, "linear_solver.pattern_changes"),
              static_cast<double>(lu.pattern_changes()));
    EXPECT_EQ(SummaryNumber(sparse, "linear_solver.pattern_cache_hits"),
              static_cast<double>(lu.pattern_hits()));
    EXPECT_EQ(SummaryNumber(sparse, "linear_solver.factorizations"),
              static_cast<double>(sparse.data.sparse.factorizations()));
    EXPECT_EQ(SummaryNumber(banded, "linear_solver.symbolic_analyses"), 0.0);
    EXPECT_GT(SummaryNumber(sparse, "linear_solver.sparse_flops"), 0.0);
    EXPECT_GT(SummaryNumber(banded, "linear_solver.banded_flops"), 0.0);
    // The costs auto compares: the banded one with its contact coupling; the sparse one is
    // null when the pattern was not analysed (banded asked for).
    EXPECT_EQ(SummaryNumber(banded, "linear_solver.banded_cost"),
              banded.model.banded_flops + kCouplingFlopCost * banded.model.coupling_flops);
    EXPECT_EQ(SummaryNumber(sparse, "linear_solver.sparse_cost"),
              kSparseFlopCost * sparse.model.sparse_flops +
                  kSparseFixedCost * sparse.model.num_unknowns());
    const Json* null_cost =
        banded.summary ? banded.summary->Find("linear_solver.sparse_cost") : nullptr;
    ASSERT_NE(null_cost, nullptr);
    EXPECT_EQ(null_cost->kind, Json::Kind::kNull);
    EXPECT_EQ(SummaryNumber(sparse, "linear_solver.coupled_nodes"),
              static_cast<double>(sparse.model.coupled_nodes));
  }
}

// A rod of `elements` elements clamped at its base, and `fingers` such rods clamped to one
// free rigid palm (the text of a scene).
std::string Section() {
  return "sections:\n"
         "  s: {stiffness: [1e5, 1e5, 1e5, 1, 1, 1], inertia: [0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3]}\n";
}
std::string RodScene(int elements) {
  char text[256];
  std::snprintf(text, sizeof text,
                "bodies:\n  arm: {type: soft, from: [0, 0, 0], to: [1, 0, 0], section: s, "
                "elements: %d}\njoints:\n  clamp: {type: fixed, at: [0, 0, 0], between: "
                "[ground, arm]}\n",
                elements);
  return Section() + text;
}
std::string HandScene(int fingers, int elements) {
  std::string text = Section();
  text += "bodies:\n  palm: {type: rigid, at: [0, 0, 0], mass: 0.5, ";
  text += "inertia: [1e-3, 1e-3, 1e-3], free: true}\n";
  char line[256];
  for (int f = 0; f < fingers; ++f) {
    std::snprintf(line, sizeof line,
                  "  f%d: {type: soft, from: [0, %g, 0], to: [0.1, %g, 0], section: s, "
                  "elements: %d}\n",
                  f, 0.01 * f, 0.01 * f, elements);
    text += line;
  }
  text += "joints:\n";
  for (int f = 0; f < fingers; ++f) {
    std::snprintf(line, sizeof line, "  j%d: {type: fixed, at: [0, %g, 0], between: [palm, f%d]}\n",
                  f, 0.01 * f, f);
    text += line;
  }
  return text;
}

TEST(LinearSolver, BadValueIsAnErrorAtItsPlace) {
  std::string text = RodScene(2);
  text += "analysis:\n  type: dynamic\n  linear_solver: dense\n";
  try {
    ParseScene(text, "bad.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bad.yaml:9:18: analysis.linear_solver:", 0), 0u) << what;
    EXPECT_NE(what.find("auto"), std::string::npos) << what;
    EXPECT_NE(what.find("banded"), std::string::npos) << what;
    EXPECT_NE(what.find("sparse"), std::string::npos) << what;
  }
}

TEST(LinearSolver, AutoPicksTheBandedLUForARodAndTheSparseLUForAHand) {
  // A rod: a band so narrow that it is not even analysed for the sparse LU.
  const Scene r = ParseScene(RodScene(64), "rod.yaml");
  EXPECT_FALSE(r.model.sparse_solver);
  EXPECT_EQ(r.model.linear_solver, LinearSolver::kAuto);
  EXPECT_EQ(r.model.sparse_flops, 0.0);
  EXPECT_LT(r.model.banded_flops, (kSparseFixedCost + 24.0 * kSparseFlopCost) * 6 * 64);
  const Scene rs = ParseScene(RodScene(64), "rod.yaml", {"analysis.linear_solver=sparse"});
  EXPECT_TRUE(rs.model.sparse_solver);
  EXPECT_GT(rs.model.sparse_flops, 0.0);
  // A palm with 16 fingers of 8 elements fixed to it: the band spans every finger's base.
  const Scene h = ParseScene(HandScene(16, 8), "hand.yaml");
  EXPECT_TRUE(h.model.sparse_solver) << h.model.banded_flops << " " << h.model.sparse_flops;
  EXPECT_GT(h.model.banded_flops, kSparseFlopCost * h.model.sparse_flops);
  const Scene forced = ParseScene(HandScene(16, 8), "hand.yaml", {"analysis.linear_solver=banded"});
  EXPECT_FALSE(forced.model.sparse_solver);
  EXPECT_EQ(forced.model.sparse_flops, 0.0);
}

// Two crossing rods that may touch (not linked in the band: 51 x 51 or 101 x 101 nodes >
// band_pair_nodes): auto keeps the banded LU while their nodes fit the Woodbury coupling's
// room (102 <= kMaxCoupledNodes = 128) and its cost with the coupling of the nodes one crossing
// is predicted to couple (2 x kContactRegionNodes) is below the sparse LU's (one crossing of
// two 20-element rods, bench/pairs_bench.cpp rods/1x1: sparse 1.15x the CPU time of banded),
// and takes the sparse LU, whose pattern takes every pair, when they may exceed it (202
// nodes).
std::string CrossingRods(int elements) {
  char text[512];
  std::snprintf(text, sizeof text,
                "bodies:\n  a: {type: soft, from: [-0.5, 0, 0], to: [0.5, 0, 0], section: s, "
                "elements: %d, contact_radius: 0.01}\n  b: {type: soft, from: [0, -0.5, 0.1], "
                "to: [0, 0.5, 0.1], section: s, elements: %d, contact_radius: 0.01}\n"
                "joints:\n  ca: {type: fixed, at: [-0.5, 0, 0], between: [ground, a]}\n  cb: "
                "{type: fixed, at: [0, -0.5, 0.1], between: [ground, b]}\ncontact: {}\n",
                elements, elements);
  return Section() + text;
}

TEST(LinearSolver, AutoPicksTheSparseLUWhenContactPairsMayExceedTheCouplingRoom) {
  const Scene fits = ParseScene(CrossingRods(50), "rods.yaml");
  EXPECT_FALSE(fits.model.sparse_solver);
  EXPECT_EQ(fits.model.coupled_nodes, 2 * kContactRegionNodes);
  EXPECT_GT(fits.model.coupling_flops, 0.0);
  EXPECT_LT(PredictedBandedCost(fits.model), PredictedSparseCost(fits.model));
  const Scene exceeds = ParseScene(CrossingRods(100), "rods.yaml");
  EXPECT_TRUE(exceeds.model.sparse_solver);
  EXPECT_GT(exceeds.model.sparse_flops, 0.0);
  // Its base pattern holds no contact blocks (the pairs enter at run time): the rods' own
  // blocks and their clamps' only, so a new Data has no couplings and no coupling room.
  const Data d = MakeData(exceeds.model);
  EXPECT_TRUE(d.sparse.couplings().empty());
  EXPECT_EQ(d.coupling.max_blocks(), 0);
  const Scene forced =
      ParseScene(CrossingRods(100), "rods.yaml", {"analysis.linear_solver=banded"});
  EXPECT_FALSE(forced.model.sparse_solver);
}

// The cases of bench/solver_bench.cpp and bench/pairs_bench.cpp (the same models): auto picks
// the solver that was the cheaper there (bench/RESULTS.md, "Sparse direct solve" and "Contact
// pairs in the sparse pattern": CPU per step, banded against sparse).
screwfem::Section ArmSection() {
  Vec6 K, M;
  K << 1e6, 1e6, 1e6, 1, 1, 1;
  M << 0.1, 0.1, 0.1, 0.05, 0.25, 0.25;
  return screwfem::Section::FromDiagonals(K, M);
}
std::string Label(const char* prefix, int i) {
  std::string s(prefix);
  s += std::to_string(i);
  return s;
}
Model BenchRod() {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3(1, 0, 0), 320, ArmSection());
  b.FixNode(b.RodNodes(rod).front());
  return b.Build();
}
Model BenchHand() {
  ModelBuilder b;
  const NodeId palm = b.AddNode(SE3::Identity(), "palm");
  b.AddRigidBody("palm", palm, 0.2, Vec3::Zero(), 1e-4 * Mat3::Identity());
  b.AddJointAt("wrist", JointType::kSpherical, kGround, palm, Vec3(0, 0, 0.02));
  Vec6 K, M;
  K << 1e5, 1e5, 1e5, 0.05, 0.05, 0.05;
  M << 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4;
  for (int f = 0; f < 40; ++f) {
    const double a = -1.0 + 2.0 * f / 39.0;
    const Vec3 dir(std::cos(a), std::sin(a), f % 2 == 0 ? 0.2 : -0.2);
    b.AddStraightRod(Label("f", f), Vec3::Zero(), 0.1 * dir.normalized(), 8,
                     screwfem::Section::FromDiagonals(K, M), Vec3::UnitZ(), palm);
  }
  return b.Build();
}
Model BenchFinger(bool tendon) {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("finger", Vec3::Zero(), Vec3(1, 0, 0), 256, ArmSection());
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  if (tendon) {
    std::vector<BodyPoint> eyelets;
    for (const NodeId n : nodes) eyelets.push_back({n, Vec3(0, 0.02, 0)});
    b.AddLengthDrivenTendon("flexor", eyelets,
                            Profile::Constant(1.0).Add(Profile::Ramp(0, 0.1, -0.002)));
  }
  return b.Build();
}
Model BenchChain() {
  ModelBuilder b;
  NodeId prev = kGround;
  for (int i = 0; i < 64; ++i) {
    const NodeId node = b.AddNode(SE3::Translation(Vec3(0.05 * (i + 1), 0, 0)), Label("l", i));
    b.AddRigidBody(Label("l", i), node, 0.01, Vec3(-0.025, 0, 0), 1e-6 * Mat3::Identity());
    b.AddJointAt(Label("j", i), JointType::kSpherical, prev, node, Vec3(0.05 * i, 0, 0));
    prev = node;
  }
  return b.Build();
}
// K clamped rods along x under K free rods along y (bench/pairs_bench.cpp, rods/KxK).
Model BenchRods(int k) {
  const double r = 0.005, L = 0.2;
  Material mat;
  mat.youngs_modulus = 1e8;
  mat.poisson_ratio = 0.4;
  mat.density = 1000.0;
  const screwfem::Section section = screwfem::Section::Circle(r, mat);
  ModelBuilder b;
  for (int i = 0; i < k; ++i) {
    const double y = L * (i + 0.5) / k;
    const RodId rod = b.AddStraightRod(Label("x", i), Vec3(0, y, 0), Vec3(L, y, 0), 20, section);
    b.FixNode(b.RodNodes(rod).front());
    b.FixNode(b.RodNodes(rod).back());
    b.AddContactRod(rod, r);
  }
  for (int i = 0; i < k; ++i) {
    const double x = L * (i + 0.5) / k;
    const RodId rod = b.AddStraightRod(Label("y", i), Vec3(x, 0, 2 * r + 5e-4),
                                       Vec3(x, L, 2 * r + 5e-4), 20, section);
    b.AddContactRod(rod, r);
  }
  ContactSettings law;
  law.stiffness = 100.0;
  law.onset = 1e-3;
  law.friction = 0.3;
  b.SetContactSettings(law);
  return b.Build();
}

TEST(LinearSolver, AutoPicksTheCheaperSolverOnTheBenchmarkCases) {
  struct Case {
    const char* name;
    Model model;
    bool sparse_cheaper;  // measured
  };
  const Scene grm = LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/grm_rigid.yaml",
                              {"defaults.elements=4"});
  const Case cases[] = {
      {"rod/320", BenchRod(), false},
      {"hand/40x8", BenchHand(), true},
      {"finger/256", BenchFinger(false), false},
      {"finger/256+tendon", BenchFinger(true), true},
      {"chain/64", BenchChain(), false},
      {"grm_rigid", grm.model, false},
      {"rods/1x1", BenchRods(1), false},
      {"rods/3x3", BenchRods(3), true},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    EXPECT_EQ(c.model.sparse_solver, c.sparse_cheaper)
        << PredictedBandedCost(c.model) << " " << PredictedSparseCost(c.model);
    EXPECT_EQ(c.model.sparse_solver, PredictedSparseCost(c.model) < PredictedBandedCost(c.model));
  }
  // Crossing rods: the Woodbury coupling of the nodes their contacts are predicted to couple
  // enters the banded cost; a model without pairs of moving shapes has none.
  const Model rods = BenchRods(3);
  EXPECT_GT(rods.coupled_nodes, 0);
  EXPECT_GT(rods.coupling_flops, rods.banded_flops);
  EXPECT_EQ(BenchRod().coupled_nodes, 0);
  EXPECT_EQ(BenchRod().coupling_flops, 0.0);
}

}  // namespace
}  // namespace screwfem::linear_solver_test
