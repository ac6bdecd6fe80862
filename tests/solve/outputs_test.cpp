// Point kinematics of method.md §6 against finite differences of a known frame motion.
#include <gtest/gtest.h>

#include "screwfem/assemble/outputs.h"

namespace screwfem {
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
}  // namespace screwfem
