#include "screwfem/elements/loads.h"

#include "screwfem/elements/rod.h"

namespace screwfem {

void AddDeadForce(const Vec3& f, const Vec3& p, Vec6* g, Mat6* K) {
  g->head<3>() += f;
  g->tail<3>() += p.cross(f);
  const Mat3 Sf = Skew(f);
  K->topRightCorner<3, 3>() -= Sf;
  K->bottomRightCorner<3, 3>() -= Skew(p) * Sf;
}

bool PointLoadKind::Calc(const Model& model, const Data& data, const Item& load,
                         const NodeMotion<1>& motion, const KernelOptions& o, ElementTerms<1>* t) {
  const PointLoad& l = model.point_loads[static_cast<std::size_t>(load)];
  const double scale = model.nodes[static_cast<std::size_t>(l.node)].dof < 0
                           ? 0.0
                           : o.load_factor * EvalProfile(l.profile, o.time, data).value;
  if (scale == 0.0) {
    t->active = false;
    return true;
  }
  const SE3& H = *motion.H[0];
  Vec6 g = Vec6::Zero();
  Mat6& K = t->stiffness;
  K.setZero();
  if (l.frame == LoadFrame::kWorld) {
    AddDeadForce(scale * (H.R.transpose() * l.force), l.point, &g, &K);
    const Vec3 mb = scale * (H.R.transpose() * l.moment);
    g.tail<3>() += mb;
    K.bottomRightCorner<3, 3>() -= Skew(mb);
  } else {
    g.head<3>() += scale * l.force;
    g.tail<3>() += scale * (l.point.cross(l.force) + l.moment);
  }
  t->residual = -g;
  t->has_stiffness = true;
  return true;
}

bool RodLoadKind::Calc(const Model& model, const Data& data, const Item& item,
                       const NodeMotion<2>& motion, const KernelOptions& o, ElementTerms<2>* t) {
  const RodLoad& l = model.rod_loads[static_cast<std::size_t>(item.load)];
  const double scale = o.load_factor * EvalProfile(l.profile, o.time, data).value;
  if (scale == 0.0) {
    t->active = false;
    return true;
  }
  const RodElement& el = model.elements[static_cast<std::size_t>(item.element)];
  const SE3& HA = *motion.H[0];
  const Vec6 dd =
      CalcRodRelativeMotion(HA, *motion.H[1], data.w_ref[static_cast<std::size_t>(item.element)]);
  Vec12 g = Vec12::Zero();
  Mat12& K = t->stiffness;
  K.setZero();
  if (l.distributed) {
    for (int i = 0; i < kGauss3Points; ++i)
      AddRodSectionLoad(kGauss3Xi[i], el.length * kGauss3W[i], HA, dd, l.frame, scale * l.force,
                        scale * l.moment, &g, &K);
  } else {
    AddRodSectionLoad(l.xi, 1.0, HA, dd, l.frame, scale * l.force, scale * l.moment, &g, &K);
  }
  t->residual = -g;
  t->has_stiffness = true;
  return true;
}

}  // namespace screwfem
