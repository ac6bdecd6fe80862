#include "screwfem/assemble/outputs.h"

#include <algorithm>
#include <cmath>

#include "screwfem/assemble/assemble.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/quadrature.h"
#include "screwfem/elements/rigid_body.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/shape_pair.h"

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

RodPoint CalcRodPointMotion(const Model& model, const Data& data, int rod_index, double s) {
  const Rod& rod = model.rods[static_cast<std::size_t>(rod_index)];
  // Element containing s (reference arc length) and the local coordinate xi.
  int e = rod.first_element;
  double s0 = 0.0;
  s = std::clamp(s, 0.0, rod.length);
  for (int k = 0; k < rod.num_elements - 1; ++k) {
    const double L = model.elements[static_cast<std::size_t>(e)].length;
    if (s <= s0 + L) break;
    s0 += L;
    ++e;
  }
  const RodElement& el = model.elements[static_cast<std::size_t>(e)];
  const double xi = std::clamp((s - s0) / el.length, 0.0, 1.0);
  const SE3& HA = data.H[static_cast<std::size_t>(el.node_a)];
  const SE3& HB = data.H[static_cast<std::size_t>(el.node_b)];
  const Vec6 d = CalcRodRelativeMotion(HA, HB, data.w_ref[static_cast<std::size_t>(e)]);
  const int nodes[2] = {el.node_a, el.node_b};
  Vec12 eta_ab, acc_ab;
  GatherNodeMotion<2>(model, data, nodes, &eta_ab, &acc_ab);
  const Vec6 d_dot = CalcRodP(d) * eta_ab;
  const Mat6x12 N = CalcRodN(xi, d);
  const Mat6x12 N_dot = CalcRodNDirectional(xi, d, d_dot);  // d/dt N(xi, d(t))
  RodPoint p;
  p.element = e;
  p.xi = xi;
  p.frame = HA * ExpSE3(xi * d);
  p.motion = CalcPointMotion(p.frame, N * eta_ab, N * acc_ab + N_dot * eta_ab, Vec3::Zero());
  return p;
}

namespace {

// The law of element e (of `rod`) at data's state: the kernel's law (rod.h), with the
// actuation at data.time times load_factor.
RodLaw ElementLaw(const Model& model, const Data& data, const Rod& rod, int element,
                  double load_factor) {
  const std::size_t e = static_cast<std::size_t>(element);
  const RodElement& el = model.elements[e];
  const Vec6 d = CalcRodRelativeMotion(data.H[static_cast<std::size_t>(el.node_a)],
                                       data.H[static_cast<std::size_t>(el.node_b)], data.w_ref[e]);
  RodActuation act;
  const bool actuated = CalcRodActuation(model, data, element, data.time, load_factor, &act);
  RodLaw law;
  CalcRodLaw(el, rod.section, d, actuated ? &act : nullptr, false, &law);
  return law;
}

}  // namespace

void CalcRodStresses(const Model& model, const Data& data, int rod_index, std::vector<Vec6>* out,
                     std::vector<Vec6>* elastic) {
  const Rod& rod = model.rods[static_cast<std::size_t>(rod_index)];
  out->resize(static_cast<std::size_t>(rod.num_elements));
  if (elastic) elastic->resize(static_cast<std::size_t>(rod.num_elements));
  for (int k = 0; k < rod.num_elements; ++k) {
    const RodLaw law = ElementLaw(model, data, rod, rod.first_element + k, 1.0);
    (*out)[static_cast<std::size_t>(k)] = law.stress;
    if (elastic) (*elastic)[static_cast<std::size_t>(k)] = law.elastic_stress;
  }
}

void CalcRodFieldRows(const Model& model, const Data& data, int rod_index, double load_factor,
                      std::vector<double>* rows) {
  const std::size_t first = rod_index < 0 ? 0 : static_cast<std::size_t>(rod_index);
  const std::size_t last = rod_index < 0 ? model.rods.size() : first + 1;
  std::size_t stations = 0;
  for (std::size_t r = first; r < last; ++r)
    stations += static_cast<std::size_t>(model.rods[r].num_elements);
  rows->resize(kRodFieldValues * stations);
  double* out = rows->data();
  for (std::size_t r = first; r < last; ++r) {
    const Rod& rod = model.rods[r];
    double s0 = 0.0;  // reference arc length at the element's first node
    for (int k = 0; k < rod.num_elements; ++k) {
      const int e = rod.first_element + k;
      const double length = model.elements[static_cast<std::size_t>(e)].length;
      const RodLaw law = ElementLaw(model, data, rod, e, load_factor);
      *out++ = static_cast<double>(r);
      *out++ = s0 + 0.5 * length;
      for (int i = 0; i < 6; ++i) *out++ = law.strain(i);
      for (int i = 0; i < 6; ++i) *out++ = law.stress(i);
      s0 += length;
    }
  }
}

Vec6 CalcJointReaction(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  Vec6 out = Vec6::Zero();
  if (j.row < 0) return out;
  const SE3& HB = NodeFrame(data, j.node_b);
  JointGradient g;
  CalcJointGradient(j, NodeFrame(data, j.node_a), HB, JointRelativeFrame(model, data, joint), &g);
  // Constraint force on node B's velocity rows (body frame, about the node origin).
  const Vec6 w = -(JointGradientB(g).transpose() * data.lambda.segment<6>(j.row));
  const Vec3 f = HB.R * w.head<3>();
  const Vec3 point = (HB * j.offset_b).x;
  out.head<3>() = f;
  out.tail<3>() = HB.R * w.tail<3>() + (HB.x - point).cross(f);
  return out;
}

Vec6 CalcMomentum(const Model& model, const Data& data) {
  // Summed with the energies, item by item (Energy::momentum: RigidBodyKind and RodElementKind).
  return CalcEnergy(model, data).momentum;
}

namespace {

// The smaller positive of two radii (0 when neither is positive).
double SmallerRadius(double a, double b) {
  if (a > 0.0 && b > 0.0) return std::min(a, b);
  return std::max(a, b) > 0.0 ? std::max(a, b) : 0.0;
}

void CountContact(bool active, bool slipping, double gap, double radius, SettlingState* s) {
  if (!active) return;
  ++s->contacts;
  if (slipping) ++s->slipping;
  if (gap < 0.0) {
    s->overlap = std::max(s->overlap, -gap);
    if (radius > 0.0) s->overlap_ratio = std::max(s->overlap_ratio, -gap / radius);
  }
}

}  // namespace

NodeSpeeds LargestNodeSpeeds(const Model& model, const Data& data) {
  NodeSpeeds s;
  for (const Node& node : model.nodes) {
    if (node.dof < 0) continue;
    s.linear = std::max(s.linear, data.v.segment<3>(node.dof).norm());
    s.angular = std::max(s.angular, data.v.segment<3>(node.dof + 3).norm());
  }
  return s;
}

SettlingState CalcSettlingState(const Model& model, const Data& data, bool dynamics,
                                double kinetic) {
  SettlingState s;
  s.kinetic = std::isnan(kinetic) ? CalcEnergy(model, data).kinetic : kinetic;
  const NodeSpeeds speeds = LargestNodeSpeeds(model, data);
  s.speed = speeds.linear;
  s.angular_speed = speeds.angular;
  for (int i = 0; i < static_cast<int>(model.contact_pairs.size()); ++i) {
    const ContactPair& pair = model.contact_pairs[static_cast<std::size_t>(i)];
    const ContactState c = CalcContactState(model, data, i, dynamics);
    const ContactObstacle& o = model.obstacles[static_cast<std::size_t>(pair.obstacle)];
    const double obstacle_radius =
        o.type == ObstacleType::kPlane || o.type == ObstacleType::kBox ? 0.0 : o.radius;
    CountContact(c.active, c.slipping, c.gap,
                 SmallerRadius(SmallerRadius(pair.radius, pair.cylinder), obstacle_radius), &s);
  }
  for (int i = 0; i < data.num_shape_pairs; ++i) {
    const ShapePair& pair = data.shape_pairs[static_cast<std::size_t>(i)];
    const ShapePairState c = CalcShapePairState(model, data, i, dynamics);
    const double a = SmallerRadius(pair.side[0].radius, pair.side[0].cylinder);
    const double b = SmallerRadius(pair.side[1].radius, pair.side[1].cylinder);
    CountContact(c.active, c.slipping, c.gap, SmallerRadius(a, b), &s);
  }
  return s;
}

}  // namespace screwfem
