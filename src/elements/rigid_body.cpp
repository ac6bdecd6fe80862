#include "screwfem/elements/rigid_body.h"

#include <algorithm>

#include "screwfem/elements/loads.h"

namespace screwfem {

Mat6 RigidBodyMass(const RigidBody& b) {
  const Mat3 S = Skew(b.com);
  Mat6 M;
  M.topLeftCorner<3, 3>() = b.mass * Mat3::Identity();
  M.topRightCorner<3, 3>() = -b.mass * S;
  M.bottomLeftCorner<3, 3>() = b.mass * S;
  M.bottomRightCorner<3, 3>() = b.inertia - b.mass * S * S;
  return M;
}

bool RigidBodyKind::Calc(const Model& model, const Data&, const Item& body,
                         const NodeMotion<1>& motion, const KernelOptions& o, ElementTerms<1>* t) {
  const RigidBody& b = model.bodies[static_cast<std::size_t>(body)];
  if (model.nodes[static_cast<std::size_t>(b.node)].dof < 0) {
    t->active = false;
    return true;
  }
  const SE3& H = *motion.H[0];
  Vec6 g = Vec6::Zero();
  Mat6& K = t->stiffness;
  K.setZero();
  AddDeadForce(o.load_factor * b.mass * (H.R.transpose() * model.gravity), b.com, &g, &K);
  t->residual = -g;
  t->has_stiffness = true;
  if (!o.dynamics) return true;
  const Mat6 M = RigidBodyMass(b);
  const Vec6& eta = motion.eta;
  const Vec6 Meta = M * eta;
  const Vec6 M_vdot = M * motion.eta_dot;
  const Vec6 gyroscopic = ad(eta).transpose() * Meta;
  t->residual += M_vdot - gyroscopic;
  // The scale of the convergence test is the size of the terms, not of their sum: for a body
  // without joints or loads the sum is the residual itself and tends to zero.
  t->force_scale = std::max(
      {M_vdot.cwiseAbs().maxCoeff(), gyroscopic.cwiseAbs().maxCoeff(), g.cwiseAbs().maxCoeff()});
  if (o.tangent) {
    t->mass = M;
    t->damping = -(ad(eta).transpose() * M + Star(Meta));
    t->has_mass = t->has_damping = true;
  }
  return true;
}

void RigidBodyKind::AddEnergy(const Model& model, const Data& data, const Item& body, Energy* E) {
  const RigidBody& b = model.bodies[static_cast<std::size_t>(body)];
  const SE3& H = data.H[static_cast<std::size_t>(b.node)];
  const int dof = model.nodes[static_cast<std::size_t>(b.node)].dof;
  if (dof >= 0) {
    const Vec6 eta = data.v.segment<6>(dof);
    const Vec3 vc = eta.head<3>() + eta.tail<3>().cross(b.com);
    E->kinetic +=
        0.5 * b.mass * vc.squaredNorm() + 0.5 * eta.tail<3>().dot(b.inertia * eta.tail<3>());
    E->AddMomentum(H, RigidBodyMass(b) * eta);
  }
  E->gravity -= b.mass * model.gravity.dot(H.Act(b.com));
}

}  // namespace screwfem
