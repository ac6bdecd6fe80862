// Dense output of error-controlled steps (docs/numerics.md, "Adaptive time steps"): the state anywhere inside the
// last accepted AdaptiveStep, interpolated on the Lie group.
#include <algorithm>

#include <Eigen/LU>

#include "screwfem/elements/joint.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/solve/dynamics.h"
#include "step_stages.h"

namespace screwfem {

void InterpolateStep(const Model& model, const Data& data, Integrator& integ, double t, Data& out) {
  if (!generalized_alpha::AdaptiveStepsPrepared(model, data, integ)) {  // no AdaptiveStep yet
    out.H = data.H;
    out.HJ = data.HJ;
    out.q_joint = data.q_joint;
    out.v = data.v;
    out.vdot = data.vdot;
    out.lambda = data.lambda;
    out.w_ref = data.w_ref;
    UpdateShapePairs(model, out);
    out.time = t;
    return;
  }
  const double h = integ.dense_h;
  const double th = h > 0.0 ? std::clamp((t - integ.dense_t0) / h, 0.0, 1.0) : 1.0;
  const double th2 = th * th, th3 = th2 * th;
  // Cubic Hermite basis and its derivatives (docs/numerics.md, "Adaptive time steps").
  const double h10 = th3 - 2.0 * th2 + th, h01 = -2.0 * th3 + 3.0 * th2, h11 = th3 - th2;
  const double d10 = 3.0 * th2 - 4.0 * th + 1.0, d01 = 6.0 * th - 6.0 * th2,
               d11 = 3.0 * th2 - 2.0 * th;
  const Eigen::VectorXd& v0 = integ.dense_v0;
  const Eigen::VectorXd& v1 = integ.dense_v1;
  const Eigen::VectorXd& D = integ.dense_d;
  Eigen::VectorXd& psi = integ.dense_psi;
  Eigen::VectorXd& dpsi = integ.dense_dpsi;
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    const Vec6 d = D.segment<6>(n.dof);
    const Vec6 w = TSE3Inv(d) * v1.segment<6>(n.dof);  // T^-1(D) v_{n+1}
    const Vec6 a = v0.segment<6>(n.dof);
    psi.segment<6>(n.dof) = h10 * h * a + h01 * d + h11 * h * w;
    dpsi.segment<6>(n.dof) = d10 * h * a + d01 * d + d11 * h * w;
  }
  for (const Joint& j : model.joints) {
    const int k = j.k();
    if (k == 0) continue;
    Vec6 w = Vec6::Zero();
    w.head(k) = v1.segment(j.coord, k);
    if (!JointHasGlobalCoordinates(j.type)) {
      Mat6 T;
      CalcJointCoordinateTangent(j, D.segment(j.coord, k), &T);
      w = T.partialPivLu().solve(w);
    }
    psi.segment(j.coord, k) =
        h10 * h * v0.segment(j.coord, k) + h01 * D.segment(j.coord, k) + h11 * h * w.head(k);
    dpsi.segment(j.coord, k) =
        d10 * h * v0.segment(j.coord, k) + d01 * D.segment(j.coord, k) + d11 * h * w.head(k);
  }
  RestoreState(integ.dense_q0, out);
  Retract(model, out, psi);
  // Velocities: eta = T(psi) psi' / h.
  const double inv_h = h > 0.0 ? 1.0 / h : 0.0;
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    out.v.segment<6>(n.dof) = inv_h * (TSE3(psi.segment<6>(n.dof)) * dpsi.segment<6>(n.dof));
  }
  for (const Joint& j : model.joints) {
    const int k = j.k();
    if (k == 0) continue;
    if (JointHasGlobalCoordinates(j.type)) {
      out.v.segment(j.coord, k) = inv_h * dpsi.segment(j.coord, k);
    } else {
      Mat6 T;
      CalcJointCoordinateTangent(j, psi.segment(j.coord, k), &T);
      Vec6 x = Vec6::Zero();
      x.head(k) = dpsi.segment(j.coord, k);
      out.v.segment(j.coord, k) = inv_h * (T * x).head(k);
    }
  }
  if (h <= 0.0) out.v = data.v;
  out.vdot = (1.0 - th) * integ.dense_vdot0 + th * integ.dense_vdot1;
  out.lambda = (1.0 - th) * integ.dense_lambda0 + th * integ.dense_lambda1;
  out.w_ref = data.w_ref;
  UpdateShapePairs(model, out);  // the pairs of moving shapes near each other in this state
  out.time = t;
}

}  // namespace screwfem
