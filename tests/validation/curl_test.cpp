// A soft cantilever curled by a large end moment applied suddenly: element rotations pass pi
// during the motion (branch continuation of the logarithm, elements/rod.h), and the energy
// balance of the undamped dynamics (rho_inf = 1) converges at second order in h.
//
// Rod: L = 1 along x, clamped at x = 0, 3 elements, EA = GA = 1e3 N, GJ = EI = 1 N m^2,
// rhoA = 1 kg/m, rotary inertia 1e-2 kg m. A dead moment M = 0.7 (2 pi EI / L) about world z
// (the static curl would be 0.7 of a full circle) acts from t = 0 (Profile::Constant); the rod
// rolls up in the xy plane, its tip rotating by up to ~6.6 rad and each element by up to ~3.4 rad
// within t = 0.6 s. The moment is conservative for this planar motion: its work is M theta_tip,
// theta_tip = the sum of the elements' rotations about z on their continued branches, and must
// equal kinetic + strain energy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::curl_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMoment = 0.7 * 2.0 * kPi;  // 0.7 * 2 pi EI / L
constexpr double kEnd = 0.6;

Model MakeCurl() {
  ModelBuilder b;
  Vec6 k, m;
  k << 1e3, 1e3, 1e3, 1.0, 1.0, 1.0;
  m << 1.0, 1.0, 1.0, 1e-2, 1e-2, 1e-2;
  const RodId rod =
      b.AddStraightRod("soft", Vec3::Zero(), Vec3(1.0, 0.0, 0.0), 3, Section::FromDiagonals(k, m));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  PointLoad load;
  load.node = nodes.back();
  load.frame = LoadFrame::kWorld;
  load.moment = Vec3(0.0, 0.0, kMoment);
  load.profile = Profile::Constant(1.0);
  b.AddPointLoad(load);
  return b.Build();
}

struct CurlRun {
  bool completed = false;
  double max_element_rotation = 0.0;  // max over elements and steps of |w|
  double max_tip_rotation = 0.0;      // max of theta_tip
  double max_branch_jump = 0.0;       // max change of an element's w between steps
  double max_energy_error = 0.0;      // max |M theta_tip - (K + U)|
  double work_at_end = 0.0;
  long iterations = 0;
};

CurlRun Simulate(double h) {
  const Model model = MakeCurl();
  Data data = MakeData(model);
  Integrator integ;
  DynamicOptions options;
  options.rho_inf = 1.0;
  CurlRun r;
  if (!InitializeDynamics(model, data, integ, options)) return r;
  const int steps = static_cast<int>(std::lround(kEnd / h));
  std::vector<Vec3> previous = data.w_ref;
  for (int k = 0; k < steps; ++k) {
    const StepResult st = Step(model, data, integ, h);
    if (!st.ok) {
      ADD_FAILURE() << st.message;
      return r;
    }
    double tip = 0.0;
    for (std::size_t e = 0; e < data.w_ref.size(); ++e) {
      tip += data.w_ref[e].z();
      r.max_element_rotation = std::max(r.max_element_rotation, data.w_ref[e].norm());
      r.max_branch_jump = std::max(r.max_branch_jump, (data.w_ref[e] - previous[e]).norm());
    }
    previous = data.w_ref;
    r.max_tip_rotation = std::max(r.max_tip_rotation, tip);
    const Energy E = CalcEnergy(model, data);
    r.work_at_end = kMoment * tip;
    r.max_energy_error =
        std::max(r.max_energy_error, std::abs(r.work_at_end - E.kinetic - E.strain));
  }
  r.completed = true;
  r.iterations = integ.iterations;
  return r;
}

TEST(Curl, ElementsRotatePastPiContinuouslyAndTheEnergyBalanceConvergesAtSecondOrder) {
  const double steps[3] = {2e-3, 1e-3, 5e-4};
  CurlRun r[3];
  for (int k = 0; k < 3; ++k) {
    r[k] = Simulate(steps[k]);
    ASSERT_TRUE(r[k].completed) << "h " << steps[k];
    std::printf(
        "[ curl ] h = %.4g: max element rotation %.4f rad, max tip rotation %.4f rad, "
        "largest step change of an element's w %.3f, work at end %.5f J, max |work - "
        "(K + U)| %.3e J, %.2f Newton it/step\n",
        steps[k], r[k].max_element_rotation, r[k].max_tip_rotation, r[k].max_branch_jump,
        r[k].work_at_end, r[k].max_energy_error,
        static_cast<double>(r[k].iterations) * steps[k] / kEnd);
    // Past pi (the principal logarithm would have jumped by 2 pi), below 2 pi, continuous.
    EXPECT_GT(r[k].max_element_rotation, kPi + 0.1);
    EXPECT_LT(r[k].max_element_rotation, 2.0 * kPi - 0.5);
    EXPECT_LT(r[k].max_branch_jump, 0.5);  // no 2 pi jumps
  }
  for (int k = 0; k < 2; ++k)
    EXPECT_NEAR(r[k].max_energy_error / r[k + 1].max_energy_error, 4.0, 0.7) << "h " << steps[k];
  EXPECT_LT(r[2].max_energy_error, 1e-4 * r[2].work_at_end);
}

}  // namespace
}  // namespace screwfem::curl_test
