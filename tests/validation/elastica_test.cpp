// Validation S3 (docs/validation.md): cantilever elastica under a dead transverse tip load,
// against the table of Mattiasson (1981), recomputed to 6 digits by quadrature of the exact
// first integral (docs/validation.md, S3).
//
// L = 1, EI = 1, P = alpha = P L^2 / EI, load fixed in space along +y, rod along x.
// Inextensibility and unshearability are approached with EA = GA = 1e7 EI / L^2 (the Cosserat
// answer then differs from the elastica by O(P / EA) <= 1e-6). The residual then has a
// round-off floor of about eps EA / L_e max|x| ~ 3e-7 N, far below the loads.
// The helical element converges at O(h^2) under a varying moment: 128 elements are needed for
// 4 significant digits on every row (measured relative errors with 128 elements: w/L <= 1.6e-5,
// u/L <= 2.6e-5, theta <= 7.5e-6; with 64 elements u/L is off by up to 1.0e-4).
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <string>

#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::elastica_test {
namespace {

struct MattiassonRow {
  double alpha;  // P L^2 / EI
  double w;      // transverse tip displacement / L
  double u;      // axial tip shortening / L
  double theta;  // tip rotation [rad]
};

constexpr MattiassonRow kTable[] = {
    {0.2, 0.0663645, 0.00264655, 0.0996362}, {0.4, 0.130975, 0.0103539, 0.197155},
    {0.6, 0.192350, 0.0224877, 0.290738},    {0.8, 0.249452, 0.0381656, 0.379063},
    {1.0, 0.301721, 0.0564332, 0.461352},    {1.5, 0.410978, 0.107942, 0.639540},
    {2.0, 0.493458, 0.160642, 0.781750},     {3.0, 0.603253, 0.254420, 0.986017},
    {4.0, 0.669964, 0.328941, 1.121239},     {5.0, 0.713792, 0.387628, 1.215368},
    {6.0, 0.744571, 0.434589, 1.283697},     {7.0, 0.767369, 0.472927, 1.334960},
    {8.0, 0.784982, 0.504828, 1.374432},     {9.0, 0.799056, 0.531821, 1.405465},
    {10.0, 0.810609, 0.554996, 1.430286},
};

void PrintTo(const MattiassonRow& row, std::ostream* os) { *os << "P L^2 / EI = " << row.alpha; }

constexpr int kElements = 128;
constexpr double kAxialStiffness = 1e7;  // EA = GA [N], with EI = 1 N m^2 and L = 1 m

class Elastica : public ::testing::TestWithParam<MattiassonRow> {};

TEST_P(Elastica, TipDisplacementAndRotationMatchMattiassonToFourDigits) {
  const MattiassonRow& row = GetParam();
  ModelBuilder b;
  Vec6 k;
  k << kAxialStiffness, kAxialStiffness, kAxialStiffness, 1.0, 1.0, 1.0;
  const RodId rod = b.AddStraightRod("cantilever", Vec3::Zero(), Vec3::UnitX(), kElements,
                                     Section::FromDiagonals(k));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  PointLoad load;
  load.node = nodes.back();
  load.frame = LoadFrame::kWorld;
  load.force = Vec3(0.0, row.alpha, 0.0);
  b.AddPointLoad(load);
  const Model model = b.Build();
  Data d = MakeData(model);
  const StaticResult r = SolveStatic(model, d);
  ASSERT_TRUE(r.converged) << r.message;

  const SE3& tip = d.H[static_cast<std::size_t>(nodes.back())];
  const double w = tip.x.y(), u = 1.0 - tip.x.x();
  const double theta = std::atan2(tip.R(1, 0), tip.R(0, 0));
  // 4 significant digits: relative 5e-5 on each tabulated value.
  EXPECT_NEAR(w, row.w, 5e-5 * row.w) << "w/L";
  EXPECT_NEAR(u, row.u, 5e-5 * row.u) << "u/L";
  EXPECT_NEAR(theta, row.theta, 5e-5 * row.theta) << "theta";
  // Planar problem: nothing leaves the x-y plane.
  EXPECT_LT(std::abs(tip.x.z()), 1e-12);
}

std::string RowName(const ::testing::TestParamInfo<MattiassonRow>& info) {
  std::string s = std::to_string(info.param.alpha);  // e.g. "0.200000"
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  for (char& ch : s)
    if (ch == '.') ch = 'p';
  return "alpha_" + s;
}

INSTANTIATE_TEST_SUITE_P(Mattiasson, Elastica, ::testing::ValuesIn(kTable), RowName);

}  // namespace
}  // namespace screwfem::elastica_test
