// Point kinematics of assemble/outputs.h against finite differences of a known frame motion.
#include <gtest/gtest.h>

#include "screwfem/assemble/outputs.h"

#include "screwfem/assemble/assemble.h"
#include "screwfem/elements/rod.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::outputs_test {
namespace {

// A frame moving with a body velocity that itself changes in time: H(t) = H0 exp(t xi1 +
// t^2/2 xi2) is not exactly that, so instead integrate eta(t) = eta0 + t eta_dot very
// accurately with many small exponential steps and compare.
TEST(PointMotion, VelocityAndAccelerationMatchFiniteDifferencesOfPosition) {
  SE3 H0;
  H0.R = ExpSO3(Vec3(0.3, -0.2, 0.5));
  H0.x = Vec3(1.0, -2.0, 0.5);
  Vec6 eta0, etadot;
  eta0 << 0.4, -0.1, 0.3, 1.2, -0.7, 0.9;
  etadot << -0.5, 0.8, 0.2, 0.6, 0.3, -1.1;
  const Vec3 p(0.2, 0.5, -0.3);
  // Exact flow with a high-order (midpoint-exponential, 4000 substeps) integration.
  auto frame_at = [&](double t) {
    SE3 H = H0;
    const int n = 4000;
    const double dt = t / n;
    for (int i = 0; i < n; ++i) H = H * ExpSE3(dt * (eta0 + (i + 0.5) * dt * etadot));
    return H;
  };
  const double t = 0.3, h = 1e-3;
  const Vec3 xm = frame_at(t - h).Act(p), x0 = frame_at(t).Act(p), xp = frame_at(t + h).Act(p);
  const PointMotion m = CalcPointMotion(frame_at(t), eta0 + t * etadot, etadot, p);
  EXPECT_LT((m.position - x0).norm(), 1e-14);
  EXPECT_LT((m.velocity - (xp - xm) / (2 * h)).norm(), 1e-5);
  EXPECT_LT((m.acceleration - (xp - 2 * x0 + xm) / (h * h)).norm(), 1e-4);
  // Without the w x (v + w x p) term the acceleration would be off by O(1).
  const Vec3 w = (eta0 + t * etadot).tail<3>();
  const Vec3 vp = (eta0 + t * etadot).head<3>() + w.cross(p);
  EXPECT_GT(w.cross(vp).norm(), 0.1);
}

}  // namespace
}  // namespace screwfem::outputs_test

namespace screwfem::outputs_test {
namespace {

// Node motions H(t) = H0 exp(X(t)), X(t) = t a1 + t^2 a2: body velocity T(X) X', and the body
// acceleration by a central difference (test oracle).
struct NodeMotion {
  SE3 H0;
  Vec6 a1, a2;
  Vec6 X(double t) const { return t * a1 + t * t * a2; }
  SE3 H(double t) const { return H0 * ExpSE3(X(t)); }
  Vec6 Eta(double t) const { return TSE3(X(t)) * (a1 + 2 * t * a2); }
  Vec6 EtaDot(double t) const { return (Eta(t + 1e-5) - Eta(t - 1e-5)) / 2e-5; }
};

TEST(RodPointMotion, FieldInsideAnElementMatchesFiniteDifferencesOfTheHelix) {
  ModelBuilder b;
  Vec6 K;
  K << 1e3, 1e3, 1e3, 1, 1, 1;
  b.AddStraightRod("rod", Vec3(0, 0, 0), Vec3(1.0, 0, 0), 1, Section::FromDiagonals(K));
  const Model model = b.Build();
  Data data = MakeData(model);
  NodeMotion A{SE3::Identity(), Vec6(), Vec6()}, B{model.nodes[1].reference, Vec6(), Vec6()};
  A.a1 << 0.3, -0.2, 0.1, 0.4, 0.9, -0.3;
  A.a2 << -0.1, 0.2, 0.3, -0.5, 0.2, 0.6;
  B.a1 << -0.2, 0.5, 0.2, 1.1, -0.4, 0.7;
  B.a2 << 0.3, -0.1, 0.2, 0.4, 0.8, -0.2;
  const double t = 0.6, xi = 0.37;
  auto set_state = [&](double time) {
    data.H[0] = A.H(time);
    data.H[1] = B.H(time);
    data.v << A.Eta(time), B.Eta(time);
    data.vdot << A.EtaDot(time), B.EtaDot(time);
    UpdateBranchReferences(model, data);
  };
  auto position = [&](double time) {
    set_state(time);
    return CalcRodPointMotion(model, data, 0, xi * model.rods[0].length).motion.position;
  };
  const double h = 1e-4;
  const Vec3 xm = position(t - h), x0 = position(t), xp = position(t + h);
  set_state(t);
  const RodPoint p = CalcRodPointMotion(model, data, 0, xi * model.rods[0].length);
  EXPECT_NEAR(p.xi, xi, 1e-14);
  EXPECT_LT((p.motion.position - x0).norm(), 1e-15);
  EXPECT_LT((p.motion.velocity - (xp - xm) / (2 * h)).norm(), 1e-7);
  EXPECT_LT((p.motion.acceleration - (xp - 2 * x0 + xm) / (h * h)).norm(), 2e-5);
  // The d(N)/dt term matters: dropping it changes the acceleration by O(1).
  Vec12 acc;
  acc << data.vdot.segment<6>(0), data.vdot.segment<6>(6);
  const Vec6 d = LogSE3(data.H[0].Inverse() * data.H[1]);
  const Vec3 without = p.frame.R * (CalcRodN(xi, d) * acc).head<3>();
  EXPECT_GT((without - p.motion.acceleration).norm(), 0.05);
}

TEST(TangentOperator, DirectionalDerivativesMatchFiniteDifferences) {
  Vec6 xi, dxi;
  xi << 0.3, -0.7, 0.2, 1.1, -2.0, 0.6;
  dxi << 0.5, 0.1, -0.4, 0.3, 0.8, -0.2;
  for (double scale : {1e-6, 0.1, 1.0, 1.5}) {
    const Vec6 x = scale * xi;
    const double e = 1e-6;
    const Mat6 fd_inv = (TSE3Inv(x + e * dxi) - TSE3Inv(x - e * dxi)) / (2 * e);
    const Mat6 fd = (TSE3(x + e * dxi) - TSE3(x - e * dxi)) / (2 * e);
    EXPECT_LT((TSE3InvDirectional(x, dxi) - fd_inv).norm(), 1e-8) << "scale " << scale;
    EXPECT_LT((TSE3Directional(x, dxi) - fd).norm(), 1e-8) << "scale " << scale;
  }
}

}  // namespace
}  // namespace screwfem::outputs_test
