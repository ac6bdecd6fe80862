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
// band_pair_nodes): auto keeps the banded LU while their nodes fit the Woodbury coupling's room
// (102 <= kMaxCoupledNodes = 128), and takes the sparse LU, whose pattern takes every pair,
// when they may exceed it (202 nodes).
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

}  // namespace
}  // namespace screwfem::linear_solver_test
