#include "screwfem/assemble/outputs.h"

namespace screwfem {

PointMotion CalcPointMotion(const SE3& H, const Vec6& eta, const Vec6& eta_dot, const Vec3& p) {
  const Vec3 v = eta.head<3>(), w = eta.tail<3>();
  const Vec3 vp = v + w.cross(p);
  PointMotion m;
  m.position = H.Act(p);
  m.velocity = H.R * vp;
  m.acceleration = H.R * (eta_dot.head<3>() + eta_dot.tail<3>().cross(p) + w.cross(vp));
  return m;
}

PointMotion CalcNodePointMotion(const Model& model, const Data& data, int node, const Vec3& p) {
  const int dof = model.nodes[static_cast<std::size_t>(node)].dof;
  const SE3& H = data.H[static_cast<std::size_t>(node)];
  if (dof < 0) return CalcPointMotion(H, Vec6::Zero(), Vec6::Zero(), p);
  return CalcPointMotion(H, data.v.segment<6>(dof), data.vdot.segment<6>(dof), p);
}

}  // namespace screwfem
