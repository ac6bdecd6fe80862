#include "screwfem/elements/contact.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "screwfem/elements/crossing.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/solid_geometry.h"

namespace screwfem {

namespace {

double Clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

}  // namespace

NormalLaw CalcNormalLaw(double g, double delta, double k) {
  NormalLaw law;
  if (g >= delta) return law;
  if (g >= 0.0) {
    law.force = k * (delta - g) * (delta - g) / (2.0 * delta);
    law.slope = -k * (delta - g) / delta;
  } else {
    law.force = k * (0.5 * delta - g);
    law.slope = -k;
  }
  return law;
}

double ContactPotential(double g, double delta, double k) {
  if (g >= delta) return 0.0;
  if (g >= 0.0) return k * (delta - g) * (delta - g) * (delta - g) / (6.0 * delta);
  return k * delta * delta / 6.0 - 0.5 * k * delta * g + 0.5 * k * g * g;
}

ContactLawParameters ContactLawFor(const ContactSettings& settings, const ContactMaterial& material,
                                   double damping, bool dynamics) {
  ContactLawParameters p;
  p.stiffness = material.stiffness;
  p.onset = material.onset > 0.0 ? material.onset : settings.onset;
  p.damping = dynamics ? damping : 0.0;
  p.law = settings.friction_law;
  p.slip_velocity = settings.slip_velocity;
  if (p.law == FrictionLaw::kStick) {
    // Stick law: friction in statics too; the anchor damped in proportion to the normal.
    p.friction = material.friction;
    p.static_friction = std::max(material.static_friction, material.friction);
    p.tangential_stiffness =
        material.tangential_stiffness > 0.0 ? material.tangential_stiffness : material.stiffness;
    p.tangential_damping =
        dynamics ? damping * std::sqrt(p.tangential_stiffness / material.stiffness) : 0.0;
  } else {
    p.friction = dynamics ? material.friction : 0.0;
    p.static_friction = p.friction;
  }
  return p;
}

ContactLawParameters ContactLawFor(const ContactSettings& settings, double damping, bool dynamics) {
  ContactMaterial material;
  material.friction = settings.friction;
  material.static_friction = settings.static_friction;
  material.stiffness = settings.stiffness;
  material.damping_ratio = settings.damping_ratio;
  material.tangential_stiffness = settings.tangential_stiffness;
  material.onset = settings.onset;
  return ContactLawFor(settings, material, damping, dynamics);
}

ContactNormal ContactNormalLaw(double gap, double gap_rate, const ContactLawParameters& law) {
  const NormalLaw fe = CalcNormalLaw(gap, law.onset, law.stiffness);
  const double w = std::min(1.0, (law.onset - gap) / law.onset);
  const double dw = gap > 0.0 ? -1.0 / law.onset : 0.0;
  const double c_n = law.damping;
  ContactNormal out;
  out.force = fe.force - c_n * w * gap_rate;
  out.dforce_dgap = fe.slope - c_n * dw * gap_rate;
  out.dforce_drate = -c_n * w;
  return out;
}

namespace {

// The stick law's friction (docs/numerics.md, "Stick friction"): the return mapping of the
// elastic anchor, into out (whose normal force is set).
void StickFriction(const Vec3& n, const Vec3& v_c, const ContactLawParameters& law,
                   const AnchorTrial* anchor, bool tangent, ContactForce* out) {
  out->direction = n;
  const double f_n = out->normal.force;
  if (anchor == nullptr || !(law.friction > 0.0)) {
    out->force = f_n * n;
    return;
  }
  const Mat3 P = Mat3::Identity() - n * n.transpose();
  const Vec3 u = P * (anchor->deflection + anchor->slip);
  // The trial force of the damped anchor, returned onto the cone when it leaves it.
  const Vec3 f_trial = -law.tangential_stiffness * u - law.tangential_damping * (P * v_c);
  const double norm = f_trial.norm();
  const double mu = anchor->slipping ? law.friction : law.static_friction;
  if (norm <= mu * f_n) {
    out->friction = f_trial;
    out->deflection = u;
    if (tangent) {
      out->slip_tangent = law.tangential_damping * P;
      out->anchor_tangent = law.tangential_stiffness * P;
    }
  } else {
    const Vec3 t = f_trial / norm;
    const double f_t = law.friction * f_n;
    out->slipping = true;
    out->friction = f_t * t;
    out->deflection = (f_t / norm) * u;
    out->direction = n + law.friction * t;
    if (tangent) {
      const Mat3 DP = (f_t / norm) * (Mat3::Identity() - t * t.transpose()) * P;
      out->slip_tangent = law.tangential_damping * DP;
      out->anchor_tangent = law.tangential_stiffness * DP;
    }
  }
  out->force = f_n * n + out->friction;
}

}  // namespace

ContactForce ContactForceLaw(double gap, const Vec3& n, const Vec3& v_c,
                             const ContactLawParameters& law, bool tangent,
                             const AnchorTrial* anchor) {
  ContactForce out;
  if (gap >= law.onset) return out;
  // Normal force (docs/numerics.md, "Contact"): f_n = max(0, f_e - c_n w(g) dg/dt).
  out.normal = ContactNormalLaw(gap, n.dot(v_c), law);
  const double f_n = out.normal.force;
  if (!(f_n > 0.0)) return out;
  out.active = true;
  if (law.law == FrictionLaw::kStick) {
    StickFriction(n, v_c, law, anchor, tangent, &out);
    return out;
  }
  // Regularised Coulomb friction at the surface point.
  const double mu = law.friction;
  const Mat3 P = Mat3::Identity() - n * n.transpose();
  const Vec3 v_t = P * v_c;
  const double sv = std::sqrt(v_t.squaredNorm() + law.slip_velocity * law.slip_velocity);
  const Vec3 slip = v_t / sv;
  const Vec3 u = mu > 0.0 ? slip : Vec3::Zero();
  out.direction = n - mu * u;
  out.force = f_n * out.direction;
  out.friction = -mu * f_n * slip;
  if (tangent && mu > 0.0)
    out.slip_tangent =
        mu * f_n * (Mat3::Identity() / sv - v_t * v_t.transpose() / (sv * sv * sv)) * P;
  return out;
}

double FrictionShare(const ContactForce& c, const ContactLawParameters& law) {
  const double limit = law.static_friction * c.normal.force;
  return c.active && limit > 0.0 ? c.friction.norm() / limit : 0.0;
}

namespace {

// A body's cylinder against an obstacle (docs/numerics.md, "Cylinders"): the surface point on
// the cylinder (a rim point against a plane, ContactPair::part; the point nearest to a sphere's
// centre or a capsule's axis), frozen in the body frame as a lever of radius 0.
bool CylinderObstacleGeometry(const ContactObstacle& o, const ContactPair& pair, const SE3& H,
                              const Vec3& A, const Vec3& B, ContactGeometry* out) {
  Vec3 p, n;
  double gap = 0.0;
  if (o.type == ObstacleType::kPlane) {
    n = o.normal;
    const Vec3 e = (B - A).normalized();
    p = CylinderRimPoint(pair.part < 3 ? A : B, e, pair.cylinder, n, pair.part % 3);
    gap = n.dot(p - o.point);
  } else if (o.type == ObstacleType::kSphere || o.type == ObstacleType::kCapsule) {
    const Vec3 Q1 = o.type == ObstacleType::kSphere ? o.point : o.to;
    const double t = CylinderSegmentParameter(A, B, pair.cylinder, o.point, Q1);
    const Vec3 q = o.point + t * (Q1 - o.point);
    const SolidPoint sp = CylinderClosestPoint(A, B, pair.cylinder, q);
    p = sp.point;
    n = -sp.normal;  // from the obstacle to the cylinder
    gap = sp.distance - o.radius;
  } else {
    return false;  // Build refuses the other pairs
  }
  out->s = 0.0;
  out->normal = n;
  out->gap = gap;
  out->point = p;
  out->weight[0] = 1.0;
  out->weight[1] = 0.0;
  out->lever[0] = H.R.transpose() * (p - H.x);
  out->lever[1].setZero();
  out->lever_rate[0].setZero();
  out->lever_rate[1].setZero();
  if (o.type == ObstacleType::kPlane) {
    // The rim point slides along the rim as the body turns: in the body frame l = b_C +
    // R_c Q_k u_0(nu), u_0 = -w / |w|, w = P_e nu, nu = R^T n, d nu = Skew(nu) d theta, so
    // dl/d theta = -R_c Q_k (I - w^ w^T) P_e Skew(nu) / |w| (Q_k: the turn by 0, +-120 degrees
    // about the axis e_b; none when the end face is parallel to the plane).
    const Vec3 e_b = (pair.offset[1] - pair.offset[0]).normalized();
    const Vec3 nu = H.R.transpose() * n;
    const Mat3 P_e = Mat3::Identity() - e_b * e_b.transpose();
    const Vec3 w = P_e * nu;
    const double norm = w.norm();
    if (norm > 1e-12) {
      const Vec3 w_hat = w / norm;
      const int k = pair.part % 3;
      const double angle = k == 0 ? 0.0 : (k == 1 ? 2.0 : -2.0) * 3.14159265358979323846 / 3.0;
      const Mat3 Q = Eigen::AngleAxisd(angle, e_b).toRotationMatrix();
      out->lever_rate[0] = -(pair.cylinder / norm) * Q *
                           (Mat3::Identity() - w_hat * w_hat.transpose()) * P_e * Skew(nu);
    }
  }
  return true;
}

}  // namespace

bool CalcContactGeometry(const Model& model, const ContactPair& pair, const SE3& H_0,
                         const SE3& H_1, ContactGeometry* out) {
  const SE3* H[2] = {&H_0, &H_1};
  const SE3& Ha = *H[pair.end_node[0]];
  const SE3& Hb = *H[pair.end_node[1]];
  const Vec3 A = Ha.x + Ha.R * pair.offset[0];
  const Vec3 B = Hb.x + Hb.R * pair.offset[1];
  const ContactObstacle& o = model.obstacles[static_cast<std::size_t>(pair.obstacle)];
  if (pair.cylinder > 0.0) return CylinderObstacleGeometry(o, pair, H_0, A, B, out);
  double s = 0.0;
  Vec3 n;
  double distance = 0.0;  // from the obstacle's surface (plane) or axis to the shape's axis
  if (o.type == ObstacleType::kPlane) {
    n = o.normal;
    const double ha = n.dot(A - o.point), hb = n.dot(B - o.point);
    s = hb < ha ? 1.0 : 0.0;
    distance = std::min(ha, hb);
  } else if (o.type == ObstacleType::kCylinder) {
    // The segment's point nearest to the cylinder or deepest in it (docs/numerics.md,
    // "Cylinders"), and the cylinder's surface point nearest to that.
    s = CylinderSegmentParameter(o.point, o.to, o.radius, A, B);
    const SolidPoint sp = CylinderClosestPoint(o.point, o.to, o.radius, Vec3(A + s * (B - A)));
    n = sp.normal;
    distance = sp.distance;
  } else if (o.type == ObstacleType::kBox) {
    // The same for a box (its frame: centre `point`, edges along the columns of `rotation`).
    const Vec3 a = o.rotation.transpose() * (A - o.point), d = o.rotation.transpose() * (B - A);
    s = BoxSegmentParameter(a, d, o.to);
    const SolidPoint sp = BoxClosestPoint(a + s * d, o.to);
    n = o.rotation * sp.normal;
    distance = sp.distance;
  } else if (o.type == ObstacleType::kMesh || o.type == ObstacleType::kHeightfield) {
    // docs/numerics.md, "Triangle meshes": the segment's point nearest to the triangles (or
    // deepest behind a face, within the shape's radius), and the mesh's point there.
    // Nothing within the onset: the nearest feature anyway (the stick law's anchor keeps the
    // material point at the last accepted state, as for the other obstacles).
    MeshHit hit = o.tree->ClosestToSegment(A, B, pair.radius + model.contact.onset, pair.radius);
    if (!hit.found) hit = o.tree->ClosestToSegment(A, B, INFINITY, pair.radius);
    if (!hit.found) return false;
    s = hit.s;
    n = hit.normal;
    distance = hit.distance;
  } else {
    Vec3 q;
    if (o.type == ObstacleType::kSphere) {
      const Vec3 d = B - A;
      const double dd = d.squaredNorm();
      s = dd > 0.0 ? Clamp01((o.point - A).dot(d) / dd) : 0.0;
      q = o.point;
    } else {
      double t = 0.0;
      ClosestSegmentParameters(A, B, o.point, o.to, &s, &t);
      q = o.point + t * (o.to - o.point);
    }
    const Vec3 delta = A + s * (B - A) - q;
    distance = delta.norm();
    if (!(distance > 0.0)) return false;
    n = delta / distance;
    distance -= o.radius;
  }
  out->s = s;
  out->normal = n;
  out->gap = distance - pair.radius;
  out->point = A + s * (B - A) - pair.radius * n;
  const double w[2] = {1.0 - s, s};
  const SE3* Hk[2] = {&H_0, &H_1};
  for (int k = 0; k < 2; ++k) {
    out->weight[k] = 0.0;
    out->lever[k].setZero();
    out->lever_rate[k].setZero();
  }
  Vec3 b[2] = {Vec3::Zero(), Vec3::Zero()};
  for (int j = 0; j < 2; ++j) {
    out->weight[pair.end_node[j]] += w[j];
    b[pair.end_node[j]] += w[j] * pair.offset[j];
  }
  for (int k = 0; k < 2; ++k) {
    if (out->weight[k] == 0.0) continue;
    out->lever[k] = b[k] / out->weight[k] - pair.radius * (Hk[k]->R.transpose() * n);
    // l_k = b_k - r R_k^T n at fixed n: dl_k/d theta = -r Skew(R_k^T n).
    out->lever_rate[k] = -pair.radius * Skew(Vec3(Hk[k]->R.transpose() * n));
  }
  return true;
}

namespace {

// The surface point's velocity map J = [W_k R_k [I  -Skew(l_k)]] (3 x 12) and m_k = R_k^T n.
void CalcSurfaceVelocityMap(const ContactGeometry& G, const NodeMotion<2>& x,
                            Eigen::Matrix<double, 3, 12>* J, Vec3 (&m)[2]) {
  J->setZero();
  for (int k = 0; k < 2; ++k) {
    m[k] = x.H[k]->R.transpose() * G.normal;
    if (G.weight[k] == 0.0) continue;
    J->block<3, 3>(0, 6 * k) = G.weight[k] * x.H[k]->R;
    J->block<3, 3>(0, 6 * k + 3) = -G.weight[k] * x.H[k]->R * Skew(G.lever[k]);
  }
}

// A plane's moving surface (ContactObstacle::moving; docs/numerics.md, "Moving surfaces"): the
// motion's scale m(t), the velocity of its material point at p, v_s = m (v + spin n x (p - o)),
// and where the material point at p at time t_a is at time t (the trapezoidal rule on m: exact
// for a constant motion).
double SurfaceScale(const ContactObstacle& o, const Data& data, double t) {
  return EvalProfile(o.motion, t, data).value;
}
Vec3 SurfaceVelocity(const ContactObstacle& o, const Data& data, const Vec3& p) {
  return SurfaceScale(o, data, data.time) * (o.velocity + o.spin * o.normal.cross(p - o.point));
}
Vec3 SurfacePointMoved(const ContactObstacle& o, const Data& data, const Vec3& p, double t_a) {
  const double travel =
      0.5 * (SurfaceScale(o, data, t_a) + SurfaceScale(o, data, data.time)) * (data.time - t_a);
  const Mat3 turn = ExpSO3(Vec3(o.spin * travel * o.normal));
  return o.point + turn * (p - o.point) + travel * o.velocity;
}

// The stick law's trial at the current frames from the pair's history (none without it), and
// the slip's derivative in the item nodes' increments, dd/dh = [W_k R_k  -W_k R_k Skew(l_k)].
// On a moving surface (dynamics) the slip is relative to the surface's material point then.
const AnchorTrial* PairAnchorTrial(const Model& model, const Data& data, int item,
                                   const SE3* const (&H)[2], bool dynamics, AnchorTrial* trial,
                                   Eigen::Matrix<double, 3, 12>* dslip) {
  if (data.contact_anchors.empty()) return nullptr;
  const ContactAnchor& a = data.contact_anchors[static_cast<std::size_t>(item)];
  if (dslip) dslip->setZero();
  if (!a.valid) {
    *trial = AnchorTrial{};
    return trial;
  }
  Vec3 p = Vec3::Zero();
  for (int k = 0; k < 2; ++k) {
    if (a.weight[k] == 0.0) continue;
    p += a.weight[k] * (H[k]->x + H[k]->R * a.lever[k]);
    if (dslip) {
      dslip->block<3, 3>(0, 6 * k) = a.weight[k] * H[k]->R;
      dslip->block<3, 3>(0, 6 * k + 3) = -a.weight[k] * H[k]->R * Skew(a.lever[k]);
    }
  }
  trial->deflection = a.deflection;
  const ContactPair& pair = model.contact_pairs[static_cast<std::size_t>(item)];
  const ContactObstacle& o = model.obstacles[static_cast<std::size_t>(pair.obstacle)];
  trial->slip =
      p - (dynamics && o.moving() ? SurfacePointMoved(o, data, a.point, a.time) : a.point);
  trial->slipping = a.slipping;
  return trial;
}

}  // namespace

bool ContactKind::Calc(const Model& model, const Data& data, const Item& item,
                       const NodeMotion<2>& x, const KernelOptions& o, ElementTerms<2>* t) {
  const ContactPair& pair = model.contact_pairs[static_cast<std::size_t>(item)];
  ContactGeometry G;
  if (!CalcContactGeometry(model, pair, *x.H[0], *x.H[1], &G) ||
      G.gap >= ContactOnsetOf(model, pair.material)) {
    t->active = false;
    return true;
  }
  const Vec3& n = G.normal;
  Eigen::Matrix<double, 3, 12> J;
  Vec3 m[2];
  CalcSurfaceVelocityMap(G, x, &J, m);
  const bool dyn = o.dynamics;
  // The velocity relative to the obstacle's surface (a moving plane's, in dynamics).
  const ContactObstacle& obstacle = model.obstacles[static_cast<std::size_t>(pair.obstacle)];
  const bool moving = dyn && obstacle.moving();
  const Vec3 v_c =
      dyn ? Vec3(J * x.eta - (moving ? SurfaceVelocity(obstacle, data, G.point) : Vec3::Zero()))
          : Vec3::Zero();
  // The law (ContactForceLaw): friction and damping in dynamics only.
  const ContactLawParameters law =
      ContactLawFor(model.contact, ContactLawOf(model, pair.material), pair.damping, dyn);
  AnchorTrial trial;
  Eigen::Matrix<double, 3, 12> dslip;
  const AnchorTrial* anchor =
      PairAnchorTrial(model, data, item, x.H, dyn, &trial, o.tangent ? &dslip : nullptr);
  const ContactForce c = ContactForceLaw(G.gap, n, v_c, law, o.tangent, anchor);
  if (!c.active) {
    t->active = false;
    return true;
  }
  const Vec3& F = c.force;
  // Residual: minus the generalised force of F at the surface point.
  double arm = 1.0;
  Vec3 f[2];
  for (int k = 0; k < 2; ++k) {
    f[k] = x.H[k]->R.transpose() * F;
    t->residual.segment<3>(6 * k) = -G.weight[k] * f[k];
    t->residual.segment<3>(6 * k + 3) = -G.weight[k] * G.lever[k].cross(f[k]);
    if (G.weight[k] != 0.0) arm = std::max(arm, G.lever[k].norm());
  }
  t->force_scale = F.norm() * arm;
  t->term_scale = t->force_scale;
  if (!o.tangent) return true;
  // dv_c/dh at fixed eta (3 x 12): rotation columns W_k R_k (-Skew(y_k) - r Skew(w_k) Skew(m_k)),
  // y_k = v_k + w_k x l_k.
  Eigen::Matrix<double, 3, 12> dV = Eigen::Matrix<double, 3, 12>::Zero();
  if (dyn) {
    for (int k = 0; k < 2; ++k) {
      if (G.weight[k] == 0.0) continue;
      const Vec3 v = x.eta.segment<3>(6 * k), om = x.eta.segment<3>(6 * k + 3);
      const Vec3 y = v + om.cross(G.lever[k]);
      dV.block<3, 3>(0, 6 * k + 3) =
          G.weight[k] * x.H[k]->R * (-Skew(y) + Skew(om) * G.lever_rate[k]);
    }
    // A turntable's surface velocity at the moving surface point: -m spin n x dp/dh, with
    // dp/dh = J but for the lever's change (rotation columns W_k R_k dl_k/d theta).
    if (moving && obstacle.spin != 0.0) {
      Eigen::Matrix<double, 3, 12> dp = J;
      for (int k = 0; k < 2; ++k)
        if (G.weight[k] != 0.0)
          dp.block<3, 3>(0, 6 * k + 3) += G.weight[k] * x.H[k]->R * G.lever_rate[k];
      dV.noalias() -=
          SurfaceScale(obstacle, data, data.time) * obstacle.spin * Skew(obstacle.normal) * dp;
    }
  }
  const Eigen::Matrix<double, 12, 1> j = J.transpose() * n;  // dg/dh
  // df_n/dh and df_n/deta.
  const Eigen::Matrix<double, 1, 12> dfn_dh =
      c.normal.dforce_dgap * j.transpose() + c.normal.dforce_drate * (n.transpose() * dV);
  const Eigen::Matrix<double, 1, 12> dfn_deta = c.normal.dforce_drate * j.transpose();
  // dF = (n - mu u) df_n - mu f_n D P dv_c, D = I/s - v_t v_t^T / s^3.
  const bool friction = law.friction > 0.0;
  Eigen::Matrix<double, 3, 12> dF_dh = c.direction * dfn_dh;
  if (friction) dF_dh.noalias() -= c.slip_tangent * dV;
  if (friction && anchor) dF_dh.noalias() -= c.anchor_tangent * dslip;
  Mat12& K = t->stiffness;
  K.noalias() = -J.transpose() * dF_dh;
  // The rotation of the frames at fixed world F: -W_k [0 Skew(f_k); 0 Skew(l_k) Skew(f_k) +
  // r Skew(f_k) Skew(m_k)].
  for (int k = 0; k < 2; ++k) {
    if (G.weight[k] == 0.0) continue;
    const Mat3 Sf = Skew(f[k]);
    K.block<3, 3>(6 * k, 6 * k + 3) -= G.weight[k] * Sf;
    K.block<3, 3>(6 * k + 3, 6 * k + 3) -=
        G.weight[k] * (Skew(G.lever[k]) * Sf - Sf * G.lever_rate[k]);
  }
  t->has_stiffness = true;
  if (dyn) {
    Eigen::Matrix<double, 3, 12> dF_deta = c.direction * dfn_deta;
    if (friction) dF_deta.noalias() -= c.slip_tangent * J;
    t->damping.noalias() = -J.transpose() * dF_deta;
    t->has_damping = true;
  }
  return true;
}

void ContactKind::AddEnergy(const Model& model, const Data& data, const Item& item, Energy* E) {
  const ContactPair& pair = model.contact_pairs[static_cast<std::size_t>(item)];
  ContactGeometry G;
  if (!CalcContactGeometry(model, pair, NodeFrame(data, pair.node[0]),
                           NodeFrame(data, pair.node[1]), &G))
    return;
  const ContactLawParameters law =
      ContactLawFor(model.contact, ContactLawOf(model, pair.material), pair.damping, false);
  E->spring += ContactPotential(G.gap, law.onset, law.stiffness);
  // The stick law's anchor: its elastic energy 1/2 k_t |u|^2 after the return mapping.
  AnchorTrial trial;
  const SE3* H[2] = {&NodeFrame(data, pair.node[0]), &NodeFrame(data, pair.node[1])};
  const AnchorTrial* anchor = PairAnchorTrial(model, data, item, H, false, &trial, nullptr);
  if (anchor == nullptr || G.gap >= law.onset) return;
  const ContactForce c = ContactForceLaw(G.gap, G.normal, Vec3::Zero(), law, false, anchor);
  if (c.active) E->spring += 0.5 * law.tangential_stiffness * c.deflection.squaredNorm();
}

namespace {

// A pair's geometry and its law at the state in data (with damping and the velocities in
// dynamics), as the kernel evaluates it: false when the normal is undefined; *c stays inactive
// when the gap is at least the onset.
bool CalcPairLaw(const Model& model, const Data& data, int item, bool dynamics, ContactGeometry* G,
                 ContactLawParameters* law, ContactForce* c) {
  const ContactPair& pair = model.contact_pairs[static_cast<std::size_t>(item)];
  NodeMotion<2> x;
  const Mat6 identity = Mat6::Identity();
  for (int k = 0; k < 2; ++k) {
    x.H[k] = &NodeFrame(data, pair.node[k]);
    x.T[k] = &identity;
  }
  if (!CalcContactGeometry(model, pair, *x.H[0], *x.H[1], G)) return false;
  *law = ContactLawFor(model.contact, ContactLawOf(model, pair.material), pair.damping, dynamics);
  *c = ContactForce{};
  if (G->gap >= law->onset) return true;
  GatherNodeMotion<2>(model, data, pair.node, &x.eta, nullptr);
  Eigen::Matrix<double, 3, 12> J;
  Vec3 m[2];
  CalcSurfaceVelocityMap(*G, x, &J, m);
  const ContactObstacle& obstacle = model.obstacles[static_cast<std::size_t>(pair.obstacle)];
  const Vec3 v_c =
      dynamics ? Vec3(J * x.eta - (obstacle.moving() ? SurfaceVelocity(obstacle, data, G->point)
                                                     : Vec3::Zero()))
               : Vec3::Zero();
  AnchorTrial trial;
  const AnchorTrial* anchor = PairAnchorTrial(model, data, item, x.H, dynamics, &trial, nullptr);
  *c = ContactForceLaw(G->gap, G->normal, v_c, *law, false, anchor);
  return true;
}

}  // namespace

ContactState CalcContactState(const Model& model, const Data& data, int item, bool dynamics) {
  ContactState out;
  ContactGeometry G;
  ContactLawParameters law;
  ContactForce c;
  if (!CalcPairLaw(model, data, item, dynamics, &G, &law, &c)) return out;
  out.gap = G.gap;
  out.point = G.point;
  out.normal = G.normal;
  if (!c.active) return out;
  out.active = true;
  out.normal_force = c.normal.force;
  out.friction_force = c.friction;
  out.slipping = c.slipping;
  out.deflection = c.deflection.norm();
  out.friction_share = FrictionShare(c, law);
  return out;
}

std::string ContactFailureHint(const Model& model, const Data& data, double h) {
  if (model.contact_pairs.empty() && model.contact_segments.empty()) return {};
  int active = 0;
  for (int i = 0; i < static_cast<int>(model.contact_pairs.size()); ++i)
    if (CalcContactState(model, data, i).active) ++active;
  for (int i = 0; i < data.num_shape_pairs; ++i)
    if (CalcShapePairState(model, data, i).active) ++active;
  const ContactSettings& c = model.contact;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "; %d contacts active at the step's start (contact.stiffness %.4g N/m, "
                "contact.onset %.4g m, contact.friction %.4g, contact.friction_law %s): an "
                "impact or a contact stiffer than the step resolves fails Newton; lower "
                "analysis.step or use step: auto, or soften contact.stiffness",
                active, c.stiffness, c.onset, c.friction, NameOf(c.friction_law));
  std::string out = buf;
  const double g = model.gravity.norm();
  if (c.friction_law == FrictionLaw::kSmooth && c.friction > 0.0 &&
      c.slip_velocity < h * c.friction * g) {
    std::snprintf(buf, sizeof buf,
                  "; contact.slip_velocity %.4g m/s is below h mu g = %.4g m/s, where the smooth "
                  "law chatters: raise it or use contact.friction_law: stick",
                  c.slip_velocity, h * c.friction * g);
    out += buf;
  }
  return out;
}

void AcceptContactHistory(const Model& model, Data& data, bool dynamics) {
  SaveCrossingReference(model, data);  // the swept check's reference (elements/crossing.h)
  AcceptShapePairHistory(model, data, dynamics);
  if (data.contact_anchors.empty()) return;
  for (std::size_t i = 0; i < model.contact_pairs.size(); ++i) {
    ContactAnchor& a = data.contact_anchors[i];
    // The law at this state from the history so far: the anchor's deflection after the return
    // mapping is the new history (zero when the pair does not touch).
    ContactGeometry G;
    ContactLawParameters law;
    ContactForce c;
    if (!CalcPairLaw(model, data, static_cast<int>(i), dynamics, &G, &law, &c)) {
      a = ContactAnchor{};
      continue;
    }
    a.deflection = c.active ? c.deflection : Vec3::Zero();
    a.slipping = c.active && c.slipping;
    a.point = G.point;
    a.time = data.time;
    for (int k = 0; k < 2; ++k) {
      a.weight[k] = G.weight[k];
      a.lever[k] = G.lever[k];
    }
    a.valid = true;
  }
}

void ClosestSegmentParameters(const Vec3& P0, const Vec3& P1, const Vec3& Q0, const Vec3& Q1,
                              double* s, double* t) {
  const Vec3 d1 = P1 - P0, d2 = Q1 - Q0, r = P0 - Q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double tiny = 1e-30;
  if (a <= tiny && e <= tiny) {
    *s = *t = 0.0;
    return;
  }
  if (a <= tiny) {
    *s = 0.0;
    *t = Clamp01(f / e);
    return;
  }
  const double c = d1.dot(r);
  if (e <= tiny) {
    *t = 0.0;
    *s = Clamp01(-c / a);
    return;
  }
  const double b = d1.dot(d2), denom = a * e - b * b;
  if (denom > 1e-10 * a * e) {
    *s = Clamp01((b * f - c * e) / denom);
  } else {
    const double s0 = -c / a, s1 = (b - c) / a;  // Q0, Q1 projected onto P's line
    const double lo = std::max(0.0, std::min(s0, s1)), hi = std::min(1.0, std::max(s0, s1));
    *s = lo <= hi ? 0.5 * (lo + hi) : (std::max(s0, s1) < 0.0 ? 0.0 : 1.0);
  }
  *t = (b * *s + f) / e;
  if (*t < 0.0) {
    *t = 0.0;
    *s = Clamp01(-c / a);
  } else if (*t > 1.0) {
    *t = 1.0;
    *s = Clamp01((b - c) / a);
  }
}

}  // namespace screwfem
