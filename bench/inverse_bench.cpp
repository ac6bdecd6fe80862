// Cost of static sensitivities and inverse statics (docs/inverse.md, "Cost").
//
// 1. A forward sensitivity per parameter against a static solve: a finger of n elements
//    (n = 10, 100, 1000; 1 m, EI 1 N m^2, EA 1e3 N) clamped at its base with three tendons
//    through eyelets on every node (tensions 10, 25, 5 N). Timed (CPU time of the process,
//    variants interleaved, median of `rounds`):
//      solve       SolveStatic from the reference state (10 load steps, the default);
//      resolve     SolveStatic by Newton from the equilibrium at tensions 0.1 N lower (what
//                  one evaluation of inverse statics costs);
//      sens0       CalcStaticSensitivity with no parameter (the tangent's assembly and
//                  factorisation: the fixed cost);
//      sens3       CalcStaticSensitivity, forward, the three tensions, three tip outputs;
//      adjoint3    the same in adjoint mode.
//    Per parameter: (sens3 - sens0) / 3.
// 2. The optimisers on inverse statics of the 10- and 100-element finger: 20 reachable targets visited
//    in turn, each warm-started, by Ceres (SolveInverseStatics) and by NLopt's SLSQP and
//    L-BFGS (on 1/2 |r|^2 with gradient J^T r from the same sensitivities, the same bounds, the
//    same warm starts): equilibrium solves, the largest final distance, CPU time.
// Output: a text table on stdout.
#include <nlopt.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/solve/sensitivity.h"

namespace screwfem {
namespace {

double CpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Finger {
  Model model;
  int tip = 0;
};

Finger MakeFinger(int elements, const Eigen::Vector3d& tensions) {
  ModelBuilder b;
  Vec6 k;
  k << 1e3, 1e3, 1e3, 1.0, 1.0, 1.0;
  const RodId rod =
      b.AddStraightRod("finger", Vec3::Zero(), Vec3::UnitX(), elements, Section::FromDiagonals(k));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  for (int t = 0; t < 3; ++t) {
    const double a = 0.5 * M_PI + 2.0 * M_PI * t / 3.0;
    std::vector<BodyPoint> eyelets;
    for (NodeId n : nodes)
      eyelets.push_back({n, Vec3(0.0, 0.02 * std::cos(a), 0.02 * std::sin(a))});
    std::string name = "t";  // not "t" + std::to_string(t): GCC 12 warns falsely (-Wrestrict)
    name += std::to_string(t);
    b.AddTendon(name, eyelets, Profile::Constant(tensions(t)));
  }
  return {b.Build(), nodes.back()};
}

const std::vector<Parameter> kTensions = {{ParameterKind::kTendonTension, 0, -1},
                                          {ParameterKind::kTendonTension, 1, -1},
                                          {ParameterKind::kTendonTension, 2, -1}};

std::vector<SensitivityOutput> TipOutputs(int tip) {
  std::vector<SensitivityOutput> out;
  for (int c = 0; c < 3; ++c) out.push_back({OutputKind::kPointPosition, tip, c, Vec3::Zero()});
  return out;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void SensitivityCost(int elements, int rounds) {
  const Finger f = MakeFinger(elements, Eigen::Vector3d(10.0, 25.0, 5.0));
  const Finger lower = MakeFinger(elements, Eigen::Vector3d(9.9, 24.9, 4.9));
  Data eq = MakeData(f.model);
  SolveStatic(f.model, eq);
  Data near = MakeData(lower.model);
  SolveStatic(lower.model, near);
  SensitivityWorkspace ws = MakeSensitivityWorkspace(f.model);
  StaticOptions warm;
  warm.start_load_factor = 1.0;
  warm.load_steps = 1;
  const std::vector<SensitivityOutput> outputs = TipOutputs(f.tip);
  const char* names[] = {"solve", "resolve", "sens0", "sens3", "adjoint3"};
  std::vector<std::function<void()>> variants = {
      [&] {
        Data d = MakeData(f.model);
        SolveStatic(f.model, d);
      },
      [&] {
        Data d = near;
        SolveStatic(f.model, d, warm);
      },
      [&] { CalcStaticSensitivity(f.model, eq, {}, outputs, SensitivityMode::kForward, {}, &ws); },
      [&] {
        CalcStaticSensitivity(f.model, eq, kTensions, outputs, SensitivityMode::kForward, {}, &ws);
      },
      [&] {
        CalcStaticSensitivity(f.model, eq, kTensions, outputs, SensitivityMode::kAdjoint, {}, &ws);
      },
  };
  // The copies of Data in solve and resolve are timed too: subtract a copy alone.
  std::vector<std::vector<double>> times(variants.size() + 1);
  for (int r = 0; r < rounds; ++r) {
    for (std::size_t v = 0; v < variants.size(); ++v) {
      const double t0 = CpuSeconds();
      variants[v]();
      times[v].push_back(CpuSeconds() - t0);
    }
    const double t0 = CpuSeconds();
    Data copy = near;
    times.back().push_back(CpuSeconds() - t0 + 0.0 * copy.time);
  }
  double med[6];
  for (std::size_t v = 0; v < times.size(); ++v) med[v] = Median(times[v]);
  const double solve = med[0] - med[5], resolve = med[1] - med[5];
  const double per_param = (med[3] - med[2]) / 3.0;
  std::printf("finger/%d (%d rounds, median CPU ms):", elements, rounds);
  for (int v = 0; v < 5; ++v)
    std::printf(" %s %.3f", names[v], 1e3 * (v < 2 ? med[v] - med[5] : med[v]));
  std::printf(
      "\n  per parameter %.4f ms = %.4f of a solve, %.4f of a Newton re-solve; "
      "fixed cost (tangent) %.3f of a solve\n",
      1e3 * per_param, per_param / solve, per_param / resolve, med[2] / solve);
}

// ---- The optimisers ----

struct Evaluator {
  const Finger& f;
  Data& data;
  Vec3 target;
  SensitivityWorkspace ws;
  int solves = 0;

  // r = tip - target and J at tensions p (Newton from data's last equilibrium).
  bool Eval(const double* p, Vec3* r, Eigen::Matrix3d* J) {
    Model m = f.model;
    for (int i = 0; i < 3; ++i)
      OffsetParameter(m, data, kTensions[static_cast<std::size_t>(i)], p[i]);
    StaticOptions warm;
    warm.start_load_factor = 1.0;
    warm.load_steps = 1;
    ++solves;
    if (!SolveStatic(m, data, warm).converged) return false;
    *r = data.H[static_cast<std::size_t>(f.tip)].x - target;
    if (J) {
      const StaticSensitivity s = CalcStaticSensitivity(m, data, kTensions, TipOutputs(f.tip),
                                                        SensitivityMode::kForward, {}, &ws);
      *J = s.outputs;
    }
    return true;
  }
};

double NloptObjective(unsigned n, const double* x, double* grad, void* self) {
  auto* e = static_cast<Evaluator*>(self);
  Vec3 r;
  Eigen::Matrix3d J;
  if (!e->Eval(x, &r, grad ? &J : nullptr)) return HUGE_VAL;
  if (grad) {
    const Vec3 g = J.transpose() * r;
    for (unsigned i = 0; i < n; ++i) grad[i] = g(static_cast<Eigen::Index>(i));
  }
  return 0.5 * r.squaredNorm();
}

void OptimiserComparison(int elements) {
  std::printf("inverse statics, finger/%d, 20 targets:\n", elements);
  const Finger f = MakeFinger(elements, Eigen::Vector3d::Zero());
  // Targets: tips at random tensions in [0, 40] N (one zero every other target).
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 40.0);
  std::vector<Vec3> targets;
  for (int k = 0; k < 20; ++k) {
    Eigen::Vector3d t(u(rng), u(rng), u(rng));
    if (k % 2 == 1) t(k % 3) = 0.0;
    Model m = f.model;
    Data d = MakeData(m);
    for (int i = 0; i < 3; ++i) OffsetParameter(m, d, kTensions[static_cast<std::size_t>(i)], t(i));
    SolveStatic(m, d);
    targets.push_back(d.H[static_cast<std::size_t>(f.tip)].x);
  }
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(3),
                        upper = Eigen::VectorXd::Constant(3, 40.0);
  {
    Data d = MakeData(f.model);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(3);
    int solves = 0;
    double worst = 0.0;
    const double t0 = CpuSeconds();
    for (const Vec3& t : targets) {
      const InverseStaticsResult r =
          SolveInverseStatics(f.model, d, kTensions, lower, upper, {{f.tip, Vec3::Zero(), t}}, x);
      solves += r.equilibrium_solves;
      worst = std::max(worst, r.distance);
      x = r.values;
    }
    std::printf("ceres LM      : %4d equilibrium solves, largest distance %.2e m, %.3f s CPU\n",
                solves, worst, CpuSeconds() - t0);
  }
  for (const auto& [algorithm, name] :
       {std::pair{NLOPT_LD_SLSQP, "nlopt SLSQP   "}, std::pair{NLOPT_LD_LBFGS, "nlopt L-BFGS  "},
        std::pair{NLOPT_LD_MMA, "nlopt MMA     "}}) {
    if (algorithm == NLOPT_LD_MMA && elements > 10) continue;  // 500 evaluations per target
    Data d = MakeData(f.model);
    Evaluator e{f, d, Vec3::Zero(), MakeSensitivityWorkspace(f.model)};
    double x[3] = {0.0, 0.0, 0.0};
    double worst = 0.0;
    const double t0 = CpuSeconds();
    for (const Vec3& t : targets) {
      e.target = t;
      nlopt_opt opt = nlopt_create(algorithm, 3);
      const double lb[3] = {0, 0, 0}, ub[3] = {40, 40, 40};
      nlopt_set_lower_bounds(opt, lb);
      nlopt_set_upper_bounds(opt, ub);
      nlopt_set_min_objective(opt, NloptObjective, &e);
      nlopt_set_stopval(opt, 0.5 * 1e-10 * 1e-10);
      nlopt_set_xtol_rel(opt, 1e-15);
      nlopt_set_maxeval(opt, 500);
      double f_min = 0.0;
      nlopt_optimize(opt, x, &f_min);
      nlopt_destroy(opt);
      worst = std::max(worst, std::sqrt(2.0 * std::max(f_min, 0.0)));
    }
    std::printf("%s: %4d equilibrium solves, largest distance %.2e m, %.3f s CPU\n", name, e.solves,
                worst, CpuSeconds() - t0);
  }
}

}  // namespace
}  // namespace screwfem

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 9;
  for (int n : {10, 100, 1000})
    screwfem::SensitivityCost(n, n >= 1000 ? std::max(3, rounds / 3) : rounds);
  for (int n : {10, 100}) screwfem::OptimiserComparison(n);
  return 0;
}
