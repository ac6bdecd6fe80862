#include "screwfem/elements/shape_pair.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "screwfem/elements/contact.h"
#include "screwfem/elements/solid_geometry.h"

namespace screwfem {

namespace {

void SideEnds(const ShapePairSide& side, const SE3* const (&H)[4], int first, Vec3* P0, Vec3* P1) {
  const SE3& Ha = *H[first + side.end_node[0]];
  const SE3& Hb = *H[first + side.end_node[1]];
  *P0 = Ha.x + Ha.R * side.offset[0];
  *P1 = Hb.x + Hb.R * side.offset[1];
}

// A box or cylinder side: its surface point is ShapePairGeometry::box_point.
bool IsSolid(const ShapePairSide& side) { return side.half.x() > 0.0 || side.cylinder > 0.0; }

// Weights and levers of the item nodes at parameters s and normal n.
void SetLevers(const ShapePair& pair, const SE3* const (&H)[4], ShapePairGeometry* out) {
  for (int k = 0; k < 4; ++k) {
    out->weight[k] = 0.0;
    out->lever[k].setZero();
  }
  for (int side = 0; side < 2; ++side) {
    const ShapePairSide& sd = pair.side[side];
    const double w[2] = {1.0 - out->s[side], out->s[side]};
    Vec3 b[2] = {Vec3::Zero(), Vec3::Zero()};
    for (int j = 0; j < 2; ++j) {
      out->weight[2 * side + sd.end_node[j]] += w[j];
      b[sd.end_node[j]] += w[j] * (IsSolid(sd) ? out->box_point : sd.offset[j]);
    }
    const double sign = side == 0 ? 1.0 : -1.0;
    for (int i = 0; i < 2; ++i) {
      const int k = 2 * side + i;
      if (out->weight[k] == 0.0) continue;
      out->lever[k] =
          b[i] / out->weight[k] - sign * sd.radius * (H[k]->R.transpose() * out->normal);
    }
  }
}

// A segment carried at two points by a box (ShapePair::part): the face is the one the
// segment's nearest point s_near is furthest out of (the largest coordinate of c - q, c the
// point and q its clamp into the box), or, inside, the face it leaves through; the segment is
// clipped to the prism over that face (|c_j(s)| <= h_j for the two other axes), and part 0
// takes the lower end of the clipped interval, part 1 the upper. Each end is then a sphere of
// the segment's radius against the box. A segment lying on a face is so carried at the ends of
// its part over the face, at points that move continuously as it tilts (the nearest point
// jumps from one end to the other as the tilt changes sign). When the segment misses the
// prism (it lies beside an edge), part 0 takes s_near and part 1 is inactive (false).
bool BoxFaceClipParameter(const Vec3& a, const Vec3& d, const Vec3& h, double s_near, int part,
                          double* s) {
  const Vec3 c = a + s_near * d;
  const Vec3 q = c.cwiseMax(-h).cwiseMin(h);
  int axis = 0;
  if (q != c)
    (c - q).cwiseAbs().maxCoeff(&axis);
  else
    (h - c.cwiseAbs()).minCoeff(&axis);
  double lo = 0.0, hi = 1.0;
  for (int j = 0; j < 3; ++j) {
    if (j == axis) continue;
    if (d(j) == 0.0) {
      if (std::abs(a(j)) > h(j)) lo = 2.0;  // outside the prism all along
      continue;
    }
    const double s1 = (-h(j) - a(j)) / d(j), s2 = (h(j) - a(j)) / d(j);
    lo = std::max(lo, std::min(s1, s2));
    hi = std::min(hi, std::max(s1, s2));
  }
  if (lo <= hi) {
    *s = part == 0 ? lo : hi;
    return true;
  }
  *s = s_near;
  return part == 0;
}

}  // namespace

bool CalcShapePairGeometry(const ShapePair& pair, const SE3* const (&H)[4], double reject,
                           ShapePairGeometry* out) {
  Vec3 A0, A1, B0, B1;
  SideEnds(pair.side[0], H, 0, &A0, &A1);
  SideEnds(pair.side[1], H, 2, &B0, &B1);
  // Bounding spheres of the two capsules (a box: of its corners).
  const Vec3& half = pair.side[1].half;
  const double bound = 0.5 * ((A1 - A0).norm() + (B1 - B0).norm()) + pair.side[0].radius +
                       pair.side[1].radius + half.norm() + pair.side[1].cylinder + reject;
  if ((0.5 * (A0 + A1 - B0 - B1)).squaredNorm() > bound * bound) return false;
  if (pair.side[1].cylinder > 0.0) {
    // A segment (a sphere: A0 = A1) against a cylinder with axis B0..B1 (docs/numerics.md,
    // "Cylinders"): the segment's point nearest to it or deepest in it, and the cylinder's
    // surface point nearest to that (side, flat face or rim), frozen in node 2's frame.
    const double R = pair.side[1].cylinder;
    const double s = CylinderSegmentParameter(B0, B1, R, A0, A1);
    const Vec3 c = A0 + s * (A1 - A0);
    const SolidPoint sp = CylinderClosestPoint(B0, B1, R, c);
    const SE3& Hb = *H[2];
    out->s[0] = s;
    out->s[1] = 0.0;
    out->box_point = Hb.R.transpose() * (sp.point - Hb.x);
    out->normal = sp.normal;
    out->gap = sp.distance - pair.side[0].radius;
    out->point[0] = c - pair.side[0].radius * out->normal;
    out->point[1] = sp.point;
    SetLevers(pair, H, out);
    return true;
  }
  if (half.x() > 0.0) {
    // A segment (a sphere: A0 = A1) against a box centred at B0: the point of the segment
    // nearest to the box, or deepest in it, clamped into the box; a point inside leaves through
    // the face nearest to it.
    const SE3& Hb = *H[2];
    const Mat3& Rs = pair.side[1].rotation;  // the box's axes in the node frame
    const Mat3 Rb = Hb.R * Rs;
    const Vec3 a = Rb.transpose() * (A0 - B0), d = Rb.transpose() * (A1 - A0);
    double s = BoxSegmentParameter(a, d, half);
    if (pair.part >= 0 && !BoxFaceClipParameter(a, d, half, s, pair.part, &s)) return false;
    const Vec3 c = a + s * d;
    Vec3 q = c.cwiseMax(-half).cwiseMin(half);
    Vec3 d_local;
    double distance;
    if (q != c) {
      d_local = c - q;
      distance = d_local.norm();
      d_local /= distance;
    } else {
      int axis = 0;
      (half - c.cwiseAbs()).minCoeff(&axis);
      const double sign = c(axis) >= 0.0 ? 1.0 : -1.0;
      q(axis) = sign * half(axis);
      d_local = sign * Vec3::Unit(axis);
      distance = sign * c(axis) - half(axis);  // <= 0
    }
    out->s[0] = s;
    out->s[1] = 0.0;
    out->box_point = pair.side[1].offset[0] + Rs * q;
    out->normal = Rb * d_local;
    out->gap = distance - pair.side[0].radius;
    out->point[0] = A0 + s * (A1 - A0) - pair.side[0].radius * out->normal;
    out->point[1] = Hb.x + Hb.R * out->box_point;
    SetLevers(pair, H, out);
    return true;
  }
  double s = 0.0, t = 0.0;
  ClosestSegmentParameters(A0, A1, B0, B1, &s, &t);
  const Vec3 p = A0 + s * (A1 - A0), q = B0 + t * (B1 - B0);
  const double distance = (p - q).norm();
  if (!(distance > 0.0)) return false;
  out->s[0] = s;
  out->s[1] = t;
  out->normal = (p - q) / distance;
  out->gap = distance - pair.side[0].radius - pair.side[1].radius;
  out->point[0] = p - pair.side[0].radius * out->normal;
  out->point[1] = q + pair.side[1].radius * out->normal;
  SetLevers(pair, H, out);
  return true;
}

void FreezeShapePairGeometry(const ShapePair& pair, const SE3* const (&H)[4],
                             const ShapePairGeometry& frozen, ShapePairGeometry* out) {
  Vec3 A0, A1, B0, B1;
  SideEnds(pair.side[0], H, 0, &A0, &A1);
  SideEnds(pair.side[1], H, 2, &B0, &B1);
  *out = frozen;
  const Vec3 p = A0 + frozen.s[0] * (A1 - A0);
  const Vec3 q = IsSolid(pair.side[1]) ? Vec3(H[2]->x + H[2]->R * frozen.box_point)
                                       : Vec3(B0 + frozen.s[1] * (B1 - B0));
  const Vec3& n = frozen.normal;
  out->gap = n.dot(p - q) - pair.side[0].radius - pair.side[1].radius;
  out->point[0] = p - pair.side[0].radius * n;
  out->point[1] = q + pair.side[1].radius * n;
  SetLevers(pair, H, out);
}

namespace {

// The relative velocity map of the surface points, J = [sign_k W_k R_k [I  -Skew(l_k)]]
// (3 x 24), and m_k = R_k^T n.
void CalcRelativeVelocityMap(const ShapePairGeometry& G, const NodeMotion<4>& x,
                             Eigen::Matrix<double, 3, 24>* J, Vec3 (&m)[4]) {
  const double sign[4] = {1.0, 1.0, -1.0, -1.0};
  J->setZero();
  for (int k = 0; k < 4; ++k) {
    m[k] = x.H[k]->R.transpose() * G.normal;
    if (G.weight[k] == 0.0) continue;
    const double w = sign[k] * G.weight[k];
    J->block<3, 3>(0, 6 * k) = w * x.H[k]->R;
    J->block<3, 3>(0, 6 * k + 3) = -w * x.H[k]->R * Skew(G.lever[k]);
  }
}

// The stick law's slip of a pair since its last acceptance: the change of the offset p_A - p_B
// of its material points then, and its derivative [sign_k W_k R_k  -sign_k W_k R_k Skew(l_k)].
Vec3 AnchorSlip(const ShapePairAnchor& a, const SE3* const (&H)[4],
                Eigen::Matrix<double, 3, 24>* dslip) {
  const double sign[4] = {1.0, 1.0, -1.0, -1.0};
  Vec3 p = Vec3::Zero();
  if (dslip) dslip->setZero();
  for (int k = 0; k < 4; ++k) {
    if (a.weight[k] == 0.0) continue;
    const double w = sign[k] * a.weight[k];
    p += w * (H[k]->x + H[k]->R * a.lever[k]);
    if (dslip) {
      dslip->block<3, 3>(0, 6 * k) = w * H[k]->R;
      dslip->block<3, 3>(0, 6 * k + 3) = -w * H[k]->R * Skew(a.lever[k]);
    }
  }
  return p - a.point;
}

// The trial of the stick law (nullptr: no stick history is kept).
const AnchorTrial* MakeAnchorTrial(const ShapePairAnchor* anchor, bool stick,
                                   const SE3* const (&H)[4], AnchorTrial* trial,
                                   Eigen::Matrix<double, 3, 24>* dslip) {
  if (!stick) return nullptr;
  *trial = AnchorTrial{};
  if (anchor) {
    trial->deflection = anchor->deflection;
    trial->slip = AnchorSlip(*anchor, H, dslip);
    trial->slipping = anchor->slipping;
  } else if (dslip) {
    dslip->setZero();
  }
  return trial;
}

}  // namespace

const ShapePairAnchor* FindShapePairAnchor(const Model& model, const Data& data,
                                           const ShapePair& pair) {
  if (data.num_shape_pair_anchors == 0) return nullptr;
  const double key = ShapePairAnchorKey(model, pair);
  const auto begin = data.shape_pair_anchors.begin();
  const auto end = begin + data.num_shape_pair_anchors;
  const auto it = std::lower_bound(begin, end, key,
                                   [](const ShapePairAnchor& a, double k) { return a.key < k; });
  return it != end && it->key == key ? &*it : nullptr;
}

bool CalcShapePairTerms(const Model& model, const ShapePair& pair, const ShapePairGeometry& G,
                        const NodeMotion<4>& x, const KernelOptions& o, ElementTerms<4>* t,
                        const ShapePairAnchor* anchor_history, bool stick) {
  if (G.gap >= ContactOnsetOf(model, pair.material)) {
    t->active = false;
    return true;
  }
  const Vec3& n = G.normal;
  const double sign[4] = {1.0, 1.0, -1.0, -1.0};
  const double radius[4] = {pair.side[0].radius, pair.side[0].radius, pair.side[1].radius,
                            pair.side[1].radius};
  Eigen::Matrix<double, 3, 24> J;
  Vec3 m[4];
  CalcRelativeVelocityMap(G, x, &J, m);
  const bool dyn = o.dynamics;
  const Vec3 v_c = dyn ? Vec3(J * x.eta) : Vec3::Zero();
  // The law (ContactForceLaw): friction and damping in dynamics only.
  const ContactLawParameters law =
      ContactLawFor(model.contact, ContactLawOf(model, pair.material), pair.damping, dyn);
  AnchorTrial trial;
  Eigen::Matrix<double, 3, 24> dslip;
  const AnchorTrial* anchor =
      MakeAnchorTrial(anchor_history, stick, x.H, &trial, o.tangent ? &dslip : nullptr);
  const ContactForce c = ContactForceLaw(G.gap, n, v_c, law, o.tangent, anchor);
  if (!c.active) {
    t->active = false;
    return true;
  }
  const Vec3& F = c.force;  // on A
  double arm = 1.0;
  Vec3 f[4];
  for (int k = 0; k < 4; ++k) {
    f[k] = sign[k] * (x.H[k]->R.transpose() * F);
    t->residual.segment<3>(6 * k) = -G.weight[k] * f[k];
    t->residual.segment<3>(6 * k + 3) = -G.weight[k] * G.lever[k].cross(f[k]);
    if (G.weight[k] != 0.0) arm = std::max(arm, G.lever[k].norm());
  }
  t->force_scale = F.norm() * arm;
  t->term_scale = t->force_scale;
  if (!o.tangent) return true;
  // dv_c/dh at fixed eta: rotation columns sign_k W_k R_k (-Skew(y_k) - sign_k r_k Skew(w_k)
  // Skew(m_k)), y_k = v_k + w_k x l_k.
  Eigen::Matrix<double, 3, 24> dV = Eigen::Matrix<double, 3, 24>::Zero();
  if (dyn) {
    for (int k = 0; k < 4; ++k) {
      if (G.weight[k] == 0.0) continue;
      const Vec3 v = x.eta.segment<3>(6 * k), om = x.eta.segment<3>(6 * k + 3);
      const Vec3 y = v + om.cross(G.lever[k]);
      dV.block<3, 3>(0, 6 * k + 3) = sign[k] * G.weight[k] * x.H[k]->R *
                                     (-Skew(y) - sign[k] * radius[k] * Skew(om) * Skew(m[k]));
    }
  }
  const Eigen::Matrix<double, 24, 1> j = J.transpose() * n;  // dg/dh
  const Eigen::Matrix<double, 1, 24> dfn_dh =
      c.normal.dforce_dgap * j.transpose() + c.normal.dforce_drate * (n.transpose() * dV);
  const bool friction = law.friction > 0.0;
  Eigen::Matrix<double, 3, 24> dF_dh = c.direction * dfn_dh;
  if (friction) dF_dh.noalias() -= c.slip_tangent * dV;
  if (friction && anchor) dF_dh.noalias() -= c.anchor_tangent * dslip;
  auto& K = t->stiffness;
  K.noalias() = -J.transpose() * dF_dh;
  // The rotation of the frames at fixed world F.
  for (int k = 0; k < 4; ++k) {
    if (G.weight[k] == 0.0) continue;
    const Mat3 Sf = Skew(f[k]);
    K.block<3, 3>(6 * k, 6 * k + 3) -= G.weight[k] * Sf;
    K.block<3, 3>(6 * k + 3, 6 * k + 3) -=
        G.weight[k] * (Skew(G.lever[k]) * Sf + sign[k] * radius[k] * Sf * Skew(m[k]));
  }
  t->has_stiffness = true;
  if (dyn) {
    const Eigen::Matrix<double, 1, 24> dfn_deta = c.normal.dforce_drate * j.transpose();
    Eigen::Matrix<double, 3, 24> dF_deta = c.direction * dfn_deta;
    if (friction) dF_deta.noalias() -= c.slip_tangent * J;
    t->damping.noalias() = -J.transpose() * dF_deta;
    t->has_damping = true;
  }
  return true;
}

namespace {

// The world ends of a side's segment, and its box (inflated by pad): a box side's corners.
void SegmentBox(const ContactSegment& g, const Data& d, double pad, Vec3* lo, Vec3* hi) {
  const ShapePairSide& sd = g.side;
  const SE3& Ha = NodeFrame(d, sd.node[sd.end_node[0]]);
  if (sd.half.x() > 0.0) {
    // |R h| per axis: the half extent of the rotated box.
    const Vec3 c = Ha.x + Ha.R * sd.offset[0];
    const Vec3 e = (Ha.R * sd.rotation).cwiseAbs() * sd.half;
    *lo = c - e - Vec3::Constant(pad);
    *hi = c + e + Vec3::Constant(pad);
    return;
  }
  const SE3& Hb = NodeFrame(d, sd.node[sd.end_node[1]]);
  const Vec3 p0 = Ha.x + Ha.R * sd.offset[0], p1 = Hb.x + Hb.R * sd.offset[1];
  const double r = sd.radius + sd.cylinder + pad;
  *lo = p0.cwiseMin(p1) - Vec3::Constant(r);
  *hi = p0.cwiseMax(p1) + Vec3::Constant(r);
}

// Whether boxes i and j of the arrays lo, hi (chunks' or segments') overlap.
bool BoxesOverlap(const std::vector<Vec3>& lo, const std::vector<Vec3>& hi, int i, int j) {
  const std::size_t a = static_cast<std::size_t>(i), b = static_cast<std::size_t>(j);
  return (lo[a].array() <= hi[b].array()).all() && (lo[b].array() <= hi[a].array()).all();
}

// Makes the items of segments i and j if they may touch, and gives each to sink(pair).
template <class Sink>
class PairWriter {
 public:
  PairWriter(const Model& m, Sink& sink) : m_(m), sink_(sink) {}
  void Consider(int i, int j) {
    const ContactSegment& a = m_.contact_segments[static_cast<std::size_t>(i)];
    const ContactSegment& b = m_.contact_segments[static_cast<std::size_t>(j)];
    if (a.entity == b.entity) {
      const double skip = m_.contact_entity_self_skip[static_cast<std::size_t>(a.entity)];
      if (skip < 0.0 || std::max(b.s0 - a.s1, a.s0 - b.s1) < skip) return;
    } else if (!m_.contact_entity_pairs.MayTouch(a.entity, b.entity)) {
      return;
    }
    if (std::isinf(a.mass) && std::isinf(b.mass)) return;
    const double reduced = std::isinf(a.mass)   ? b.mass
                           : std::isinf(b.mass) ? a.mass
                                                : a.mass * b.mass / (a.mass + b.mass);
    // The pair's material: O(1) from the two entities' groups (model.h, ContactLawIndex).
    material_ = ContactLawIndex(m_, a.material_group, b.material_group);
    const ContactMaterial law = ContactLawOf(m_, material_);
    damping_ = 2.0 * law.damping_ratio * std::sqrt(law.stiffness * std::max(reduced, 0.0));
    const bool box_a = IsBox(a.side), box_b = IsBox(b.side);
    if (box_a && box_b) {
      edge_ = 0;
      // Box-box: the 12 edges of each box (segments of radius 0) against the other box.
      for (int first = 0; first < 2; ++first) {
        const ContactSegment& edges = first == 0 ? a : b;
        const ContactSegment& box = first == 0 ? b : a;
        const Vec3& h = edges.side.half;
        for (int k = 0; k < 8; ++k)
          for (int bit : {1, 2, 4}) {
            if (k & bit) continue;
            ShapePairSide edge = edges.side;
            edge.half.setZero();
            edge.radius = 0.0;
            edge.rotation.setIdentity();
            const Vec3& c = edges.side.offset[0];
            const Mat3& R = edges.side.rotation;
            edge.offset[0] = c + R * BoxCorner(Vec3::Zero(), h, k);
            edge.offset[1] = c + R * BoxCorner(Vec3::Zero(), h, k | bit);
            Push(edge, box.side, first == 0 ? i : j, first == 0 ? j : i);
            ++edge_;
          }
      }
      edge_ = -1;
    } else if (a.side.cylinder > 0.0 || b.side.cylinder > 0.0) {
      // A cylinder against a segment side (the cylinder is side B); Build refuses a cylinder
      // against a box or a cylinder.
      if (box_a || box_b || (a.side.cylinder > 0.0 && b.side.cylinder > 0.0)) return;
      if (a.side.cylinder > 0.0)
        Store(b.side, a.side, j, i, -1);
      else
        Store(a.side, b.side, i, j, -1);
    } else if (box_a) {
      Push(b.side, a.side, j, i);  // the box is side B
    } else {
      Push(a.side, b.side, i, j);
    }
  }

 private:
  static bool IsBox(const ShapePairSide& s) { return s.half.x() > 0.0; }
  void Push(const ShapePairSide& side_a, const ShapePairSide& side_b, int seg_a, int seg_b) {
    // A segment of positive length against a box: two points (the ends of the segment clipped
    // to the face), so that a segment lying on a face balances any moment over it.
    const bool segment =
        side_a.end_node[0] != side_a.end_node[1] || side_a.offset[0] != side_a.offset[1];
    if (IsBox(side_b) && segment) {
      Store(side_a, side_b, seg_a, seg_b, 0);
      Store(side_a, side_b, seg_a, seg_b, 1);
    } else {
      Store(side_a, side_b, seg_a, seg_b, -1);
    }
  }
  void Store(const ShapePairSide& side_a, const ShapePairSide& side_b, int seg_a, int seg_b,
             int part) {
    ShapePair p;
    p.side[0] = side_a;
    p.side[1] = side_b;
    p.segment[0] = seg_a;
    p.segment[1] = seg_b;
    p.damping = damping_;
    p.material = material_;
    p.part = part;
    p.edge = edge_;
    sink_(p);
  }

  const Model& m_;
  Sink& sink_;
  double damping_ = 0.0;
  int material_ = 0;
  int edge_ = -1;
};

std::uint32_t CellHash(const Eigen::Vector3i& c) {
  return static_cast<std::uint32_t>(c.x()) * 73856093u ^
         static_cast<std::uint32_t>(c.y()) * 19349663u ^
         static_cast<std::uint32_t>(c.z()) * 83492791u;
}

// The broad phase once (UpdateShapePairs): bound the chunks of segments, sort them into the
// cells of a hashed grid, then pair the chunks that share a cell (and the large ones with
// all), segment by segment. Each phase is a method; the grid's arrays are Data's (sized by
// MakeData), so a search allocates nothing.
class BroadPhase {
 public:
  BroadPhase(const Model& model, Data& data)
      : m_(model),
        data_(data),
        g_(data.shape_pair_grid),
        chunks_(static_cast<int>(g_.chunk_first.size()) - 1) {}

  void Run() {
    data_.num_shape_pairs = 0;
    data_.shape_pair_overflow = false;
    if (m_.contact_segments.empty() || !MayHaveShapePairs(m_)) return;
    g_.box_tests = 0;
    if (!BoundChunks()) return;
    SortChunksIntoCells();
    auto sink = [this](const ShapePair& p) {
      if (data_.num_shape_pairs >= static_cast<int>(data_.shape_pairs.size())) {
        data_.shape_pair_overflow = true;
        return;
      }
      data_.shape_pairs[static_cast<std::size_t>(data_.num_shape_pairs++)] = p;
    };
    PairWriter<decltype(sink)> writer(m_, sink);
    PairChunks(writer);
  }

 private:
  int First(int c) const { return g_.chunk_first[static_cast<std::size_t>(c)]; }
  const ContactSegment& Segment(int i) const {
    return m_.contact_segments[static_cast<std::size_t>(i)];
  }
  Eigen::Vector3i CellOf(const Vec3& p) const {
    return Eigen::Vector3i(static_cast<int>(std::floor(p.x() * inv_cell_)),
                           static_cast<int>(std::floor(p.y() * inv_cell_)),
                           static_cast<int>(std::floor(p.z() * inv_cell_)));
  }
  std::size_t Bucket(const Eigen::Vector3i& v) const {
    return CellHash(v) & static_cast<std::uint32_t>(buckets_ - 1);
  }
  // f(cell) for every cell chunk c's box touches.
  template <class F>
  void ForCells(int c, F&& f) const {
    const std::size_t k = static_cast<std::size_t>(c);
    const Eigen::Vector3i a = CellOf(g_.lo[k]), b = CellOf(g_.hi[k]);
    for (int x = a.x(); x <= b.x(); ++x)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int z = a.z(); z <= b.z(); ++z) f(Eigen::Vector3i(x, y, z));
  }

  // Boxes inflated by the radii and half the onset: surfaces nearer than the onset have
  // overlapping boxes. A chunk's box holds its segments'. The cell: the largest box of a rod's
  // chunk (or of any chunk when there is no rod); a larger box is tested against all. False
  // when no pair is possible (no extent, or a state that is not finite: the step fails).
  bool BoundChunks() {
    const double pad = 0.5 * MaxContactOnset(m_);
    double cell = 0.0, cell_any = 0.0;
    for (int c = 0; c < chunks_; ++c) {
      const std::size_t k = static_cast<std::size_t>(c);
      g_.lo[k] = Vec3::Constant(INFINITY);
      g_.hi[k] = Vec3::Constant(-INFINITY);
      for (int i = First(c); i < First(c + 1); ++i) {
        const std::size_t q = static_cast<std::size_t>(i);
        SegmentBox(Segment(i), data_, pad, &g_.segment_lo[q], &g_.segment_hi[q]);
        g_.lo[k] = g_.lo[k].cwiseMin(g_.segment_lo[q]);
        g_.hi[k] = g_.hi[k].cwiseMax(g_.segment_hi[q]);
      }
      const double extent = (g_.hi[k] - g_.lo[k]).maxCoeff();
      if (!std::isfinite(extent)) return false;
      cell_any = std::max(cell_any, extent);
      if (Segment(First(c)).side.rod) cell = std::max(cell, extent);
    }
    if (cell == 0.0) cell = cell_any;
    if (!(cell > 0.0)) return false;
    cell_ = cell;
    inv_cell_ = 1.0 / cell;
    return true;
  }

  // Counting sort of the entries (chunk, cell) into the buckets: count, prefix, fill. Chunks
  // larger than a cell, or with cells beyond the int range, are listed apart (large_chunks).
  void SortChunksIntoCells() {
    const double limit = 1e9 * cell_;
    buckets_ = static_cast<int>(g_.bucket_start.size()) - 1;
    std::fill(g_.bucket_start.begin(), g_.bucket_start.end(), 0);
    num_large_ = 0;
    for (int c = 0; c < chunks_; ++c) {
      const std::size_t k = static_cast<std::size_t>(c);
      const bool large = (g_.hi[k] - g_.lo[k]).maxCoeff() > cell_ ||
                         g_.lo[k].cwiseAbs().maxCoeff() > limit ||
                         g_.hi[k].cwiseAbs().maxCoeff() > limit;
      g_.large[k] = large;
      if (large) {
        g_.large_chunks[static_cast<std::size_t>(num_large_++)] = c;
        continue;
      }
      ForCells(c, [&](const Eigen::Vector3i& v) { ++g_.bucket_start[Bucket(v) + 1]; });
    }
    for (int b = 0; b < buckets_; ++b)
      g_.bucket_start[static_cast<std::size_t>(b + 1)] +=
          g_.bucket_start[static_cast<std::size_t>(b)];
    // Fill: bucket_start[b] advances to the end of bucket b, then is restored from b - 1's end.
    for (int c = 0; c < chunks_; ++c) {
      if (g_.large[static_cast<std::size_t>(c)]) continue;
      ForCells(c, [&](const Eigen::Vector3i& v) {
        const std::size_t e = static_cast<std::size_t>(g_.bucket_start[Bucket(v)]++);
        g_.entry_chunk[e] = c;
        g_.entry_cell[e] = v;
      });
    }
    for (int b = buckets_; b > 0; --b)
      g_.bucket_start[static_cast<std::size_t>(b)] =
          g_.bucket_start[static_cast<std::size_t>(b - 1)];
    g_.bucket_start[0] = 0;
  }

  bool SegmentsOverlap(int i, int j) {
    ++g_.box_tests;
    return BoxesOverlap(g_.segment_lo, g_.segment_hi, i, j);
  }

  // Two chunks whose boxes overlap: their segments' pairs, unless no two of their segments may
  // touch (other entities that may not; the same rod with every two elements within the skip).
  template <class Writer>
  void ChunkPair(int a, int b, Writer& writer) {
    const int a0 = First(a), a1 = First(a + 1), b0 = First(b), b1 = First(b + 1);
    const int ea = Segment(a0).entity, eb = Segment(b0).entity;
    if (ea == eb) {
      const double skip = m_.contact_entity_self_skip[static_cast<std::size_t>(ea)];
      const double far =
          std::max(Segment(b1 - 1).s0 - Segment(a0).s1, Segment(a1 - 1).s0 - Segment(b0).s1);
      if (skip < 0.0 || far < skip) return;
    } else if (!m_.contact_entity_pairs.MayTouch(ea, eb)) {
      return;
    }
    for (int i = a0; i < a1; ++i)
      for (int j = b0; j < b1; ++j)
        if (SegmentsOverlap(i, j)) writer.Consider(std::min(i, j), std::max(i, j));
  }

  // The candidate pairs: chunks sharing a cell, the large chunks with every other, and the
  // segments inside a chunk of a rod touching itself.
  template <class Writer>
  void PairChunks(Writer& writer) {
    // Two chunks sharing a cell; each pair once, in the cell of the corner max(lo_a, lo_b).
    for (int b = 0; b < buckets_; ++b) {
      const int first = g_.bucket_start[static_cast<std::size_t>(b)];
      const int end = g_.bucket_start[static_cast<std::size_t>(b + 1)];
      for (int x = first; x < end; ++x)
        for (int y = x + 1; y < end; ++y) {
          const Eigen::Vector3i& v = g_.entry_cell[static_cast<std::size_t>(x)];
          if (v != g_.entry_cell[static_cast<std::size_t>(y)]) continue;  // a hash collision
          const int i = g_.entry_chunk[static_cast<std::size_t>(x)];
          const int j = g_.entry_chunk[static_cast<std::size_t>(y)];
          ++g_.box_tests;
          if (!BoxesOverlap(g_.lo, g_.hi, i, j)) continue;
          const std::size_t ki = static_cast<std::size_t>(i), kj = static_cast<std::size_t>(j);
          if (CellOf(g_.lo[ki].cwiseMax(g_.lo[kj])) != v) continue;
          ChunkPair(std::min(i, j), std::max(i, j), writer);
        }
    }
    // Large chunks against every other (two large ones once).
    for (int q = 0; q < num_large_; ++q) {
      const int i = g_.large_chunks[static_cast<std::size_t>(q)];
      for (int j = 0; j < chunks_; ++j) {
        if (j == i || (g_.large[static_cast<std::size_t>(j)] && j < i)) continue;
        ++g_.box_tests;
        if (BoxesOverlap(g_.lo, g_.hi, i, j)) ChunkPair(std::min(i, j), std::max(i, j), writer);
      }
    }
    // Inside a chunk of a rod touching itself: only when its span exceeds the skip (a skip set
    // below a diameter).
    for (int c = 0; c < chunks_; ++c) {
      const int c0 = First(c), c1 = First(c + 1);
      const double skip = m_.contact_entity_self_skip[static_cast<std::size_t>(Segment(c0).entity)];
      if (c1 - c0 < 3 || skip < 0.0 || Segment(c1 - 1).s0 - Segment(c0).s1 < skip) continue;
      for (int i = c0; i < c1; ++i)
        for (int j = i + 2; j < c1; ++j)
          if (SegmentsOverlap(i, j)) writer.Consider(i, j);
    }
  }

  const Model& m_;
  Data& data_;
  ShapePairGrid& g_;
  const int chunks_;
  double cell_ = 0.0, inv_cell_ = 0.0;
  int buckets_ = 0, num_large_ = 0;
};

void FindShapePairs(const Model& model, Data& data) { BroadPhase(model, data).Run(); }

}  // namespace

std::vector<ShapePair> AllShapePairs(const Model& model) {
  std::vector<ShapePair> out;
  auto sink = [&out](const ShapePair& p) { out.push_back(p); };
  PairWriter<decltype(sink)> writer(model, sink);
  const int n = static_cast<int>(model.contact_segments.size());
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) writer.Consider(i, j);
  return out;
}

void UpdateShapePairs(const Model& model, Data& data) {
  FindShapePairs(model, data);
  data.shape_pair_limit_reached = false;
  if (!data.shape_pair_overflow) return;
  const std::size_t limit = ShapePairPoolLimit(model);
  while (data.shape_pair_overflow) {
    if (data.shape_pairs.size() >= limit) {
      data.shape_pair_limit_reached = true;
      return;
    }
    GrowShapePairPool(data, limit);
    FindShapePairs(model, data);
  }
}

bool ShapePairKind::Calc(const Model& model, const Data& data, const Item& item,
                         const NodeMotion<4>& x, const KernelOptions& o, ElementTerms<4>* t) {
  const ShapePair& pair = data.shape_pairs[static_cast<std::size_t>(item)];
  ShapePairGeometry G;
  if (!CalcShapePairGeometry(pair, x.H, ContactOnsetOf(model, pair.material), &G)) {
    t->active = false;
    return true;
  }
  return CalcShapePairTerms(model, pair, G, x, o, t, FindShapePairAnchor(model, data, pair),
                            !data.shape_pair_anchors.empty());
}

void ShapePairKind::AddEnergy(const Model& model, const Data& data, const Item& item, Energy* E) {
  const ShapePair& pair = data.shape_pairs[static_cast<std::size_t>(item)];
  const SE3* H[4] = {&NodeFrame(data, pair.side[0].node[0]), &NodeFrame(data, pair.side[0].node[1]),
                     &NodeFrame(data, pair.side[1].node[0]),
                     &NodeFrame(data, pair.side[1].node[1])};
  ShapePairGeometry G;
  if (!CalcShapePairGeometry(pair, H, ContactOnsetOf(model, pair.material), &G)) return;
  const ContactLawParameters law =
      ContactLawFor(model.contact, ContactLawOf(model, pair.material), pair.damping, false);
  E->spring += ContactPotential(G.gap, law.onset, law.stiffness);
  // The stick law's anchor: its elastic energy 1/2 k_t |u|^2 after the return mapping.
  AnchorTrial trial;
  const AnchorTrial* anchor = MakeAnchorTrial(FindShapePairAnchor(model, data, pair),
                                              !data.shape_pair_anchors.empty(), H, &trial, nullptr);
  if (anchor == nullptr || G.gap >= ContactOnsetOf(model, pair.material)) return;
  const ContactForce c = ContactForceLaw(G.gap, G.normal, Vec3::Zero(), law, false, anchor);
  if (c.active) E->spring += 0.5 * law.tangential_stiffness * c.deflection.squaredNorm();
}

ShapePairState CalcShapePairState(const Model& model, const Data& data, int item, bool dynamics) {
  const ShapePair& pair = data.shape_pairs[static_cast<std::size_t>(item)];
  ShapePairState out;
  const int nodes[4] = {pair.side[0].node[0], pair.side[0].node[1], pair.side[1].node[0],
                        pair.side[1].node[1]};
  NodeMotion<4> x;
  const Mat6 identity = Mat6::Identity();
  for (int k = 0; k < 4; ++k) {
    x.H[k] = &NodeFrame(data, nodes[k]);
    x.T[k] = &identity;
  }
  GatherNodeMotion<4>(model, data, nodes, &x.eta, &x.eta_dot);
  ShapePairGeometry G;
  if (!CalcShapePairGeometry(pair, x.H, ContactOnsetOf(model, pair.material), &G)) return out;
  out.gap = G.gap;
  out.point[0] = G.point[0];
  out.point[1] = G.point[1];
  out.normal = G.normal;
  if (G.gap >= ContactOnsetOf(model, pair.material)) return out;
  // The kernel's velocity map and law, with damping and friction (dynamics).
  Eigen::Matrix<double, 3, 24> J;
  Vec3 m[4];
  CalcRelativeVelocityMap(G, x, &J, m);
  const Vec3 v_c = dynamics ? Vec3(J * x.eta) : Vec3::Zero();
  const ContactLawParameters law =
      ContactLawFor(model.contact, ContactLawOf(model, pair.material), pair.damping, dynamics);
  AnchorTrial trial;
  const AnchorTrial* anchor =
      MakeAnchorTrial(FindShapePairAnchor(model, data, pair), !data.shape_pair_anchors.empty(), x.H,
                      &trial, nullptr);
  const ContactForce c = ContactForceLaw(G.gap, G.normal, v_c, law, false, anchor);
  if (!c.active) return out;
  out.active = true;
  out.normal_force = c.normal.force;
  out.friction_force = c.friction;
  out.slipping = c.slipping;
  out.deflection = c.deflection.norm();
  out.friction_share = FrictionShare(c, law);
  return out;
}

void AcceptShapePairHistory(const Model& model, Data& data, bool dynamics) {
  if (data.shape_pair_anchors.empty()) return;
  UpdateShapePairs(model, data);  // the pairs near each other in the accepted state
  const double sign[4] = {1.0, 1.0, -1.0, -1.0};
  int count = 0;
  for (int i = 0; i < data.num_shape_pairs; ++i) {
    const ShapePair& pair = data.shape_pairs[static_cast<std::size_t>(i)];
    const int nodes[4] = {pair.side[0].node[0], pair.side[0].node[1], pair.side[1].node[0],
                          pair.side[1].node[1]};
    NodeMotion<4> x;
    const Mat6 identity = Mat6::Identity();
    for (int k = 0; k < 4; ++k) {
      x.H[k] = &NodeFrame(data, nodes[k]);
      x.T[k] = &identity;
    }
    ShapePairGeometry G;
    if (!CalcShapePairGeometry(pair, x.H, ContactOnsetOf(model, pair.material), &G)) continue;
    ContactForce c;
    if (G.gap < ContactOnsetOf(model, pair.material)) {
      GatherNodeMotion<4>(model, data, nodes, &x.eta, nullptr);
      Eigen::Matrix<double, 3, 24> J;
      Vec3 m[4];
      CalcRelativeVelocityMap(G, x, &J, m);
      const Vec3 v_c = dynamics ? Vec3(J * x.eta) : Vec3::Zero();
      AnchorTrial trial;
      const AnchorTrial* anchor =
          MakeAnchorTrial(FindShapePairAnchor(model, data, pair), true, x.H, &trial, nullptr);
      c = ContactForceLaw(
          G.gap, G.normal, v_c,
          ContactLawFor(model.contact, ContactLawOf(model, pair.material), pair.damping, dynamics),
          false, anchor);
    }
    ShapePairAnchor& a = data.shape_pair_anchors_next[static_cast<std::size_t>(count++)];
    a.key = ShapePairAnchorKey(model, pair);
    a.deflection = c.active ? c.deflection : Vec3::Zero();
    a.slipping = c.active && c.slipping;
    a.point.setZero();
    for (int k = 0; k < 4; ++k) {
      a.weight[k] = G.weight[k];
      a.lever[k] = G.lever[k];
      if (G.weight[k] != 0.0)
        a.point += sign[k] * G.weight[k] * (x.H[k]->x + x.H[k]->R * G.lever[k]);
    }
  }
  std::sort(data.shape_pair_anchors_next.begin(), data.shape_pair_anchors_next.begin() + count,
            [](const ShapePairAnchor& a, const ShapePairAnchor& b) { return a.key < b.key; });
  std::swap(data.shape_pair_anchors, data.shape_pair_anchors_next);
  data.num_shape_pair_anchors = count;
}

}  // namespace screwfem
