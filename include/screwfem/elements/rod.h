// The two-node helical Cosserat rod element (method.md §2.2-2.6): a stateless kernel.
#pragma once

#include "screwfem/lie/se3.h"
#include "screwfem/model/model.h"

namespace screwfem {

using Mat6x12 = Eigen::Matrix<double, 6, 12>;

// Relative motion d = log(H_A^-1 H_B) on the branch closest to w_ref (method.md §2.7).
Vec6 CalcRodRelativeMotion(const SE3& H_A, const SE3& H_B, const Vec3& w_ref);

// P(d) = [-T^-1(-d)  T^-1(d)]: delta d = P [dh_A; dh_B] and d_dot = P [eta_A; eta_B] (§2.3).
Mat6x12 CalcRodP(const Vec6& d);

// Exact velocity / virtual-displacement interpolation of the helical element (§2.5):
// eta(xi) = N(xi, d) [eta_A; eta_B], xi in [0, 1].
Mat6x12 CalcRodN(double xi, const Vec6& d);

struct RodInternal {
  Vec6 d;            // relative motion on the current branch
  Vec6 strain;       // d / L - f0
  Vec6 stress;       // sigma = K strain (section frame: N, V2, V3, T, M2, M3)
  double energy;     // L/2 strain^T K strain
  Vec12 force;       // g_int = P^T sigma  (node A then node B, node-frame components)
  Mat12 stiffness;   // d g_int / d[dh_A; dh_B], with the geometric term (§2.4)
};

// Internal forces and consistent tangent of one element (§2.4).
void CalcRodInternal(const RodElement& element, const Section& section, const SE3& H_A,
                     const SE3& H_B, const Vec3& w_ref, RodInternal* out);

// A dead (world-fixed) force per unit length f_w distributed along the element: generalised
// external force g (to be subtracted from the residual) and the tangent of the residual
// contribution, -dg/d[dh_A; dh_B] (exact for this load vector). The load is distributed with
// linear weights and follows the exact helical kinematics (3-point Gauss).
void CalcRodDistributedDeadForce(const RodElement& element, const SE3& H_A, const Vec6& d,
                                 const Vec3& f_w, Vec12* g, Mat12* tangent);

}  // namespace screwfem
