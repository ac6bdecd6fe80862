#include "screwfem/elements/crossing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "screwfem/elements/contact.h"
#include "screwfem/lie/se3.h"

namespace screwfem {

namespace {

// A segment's axis end points in the world at the state in data.
void SideEnds(const Data& data, const ShapePairSide& side, Vec3* p0, Vec3* p1) {
  const SE3& H0 = NodeFrame(data, side.node[side.end_node[0]]);
  const SE3& H1 = NodeFrame(data, side.node[side.end_node[1]]);
  *p0 = H0.x + H0.R * side.offset[0];
  *p1 = H1.x + H1.R * side.offset[1];
}

void PairEnds(const Data& data, const ContactPair& pair, Vec3* p0, Vec3* p1) {
  const SE3& H0 = NodeFrame(data, pair.node[pair.end_node[0]]);
  const SE3& H1 = NodeFrame(data, pair.node[pair.end_node[1]]);
  *p0 = H0.x + H0.R * pair.offset[0];
  *p1 = H1.x + H1.R * pair.offset[1];
}

bool IsBox(const ShapePairSide& side) { return side.half.x() > 0.0; }

// A box's reference: its centre and the rotation vector of its frame (node frame times the
// box's rotation), in place of a segment's two end points.
void BoxPose(const Data& data, const ShapePairSide& side, Vec3* centre, Mat3* R) {
  const SE3& H = NodeFrame(data, side.node[0]);
  *centre = H.x + H.R * side.offset[0];
  *R = H.R * side.rotation;
}

// Whether the segment from p to q meets the box [-e, e] (slab test).
bool SegmentMeetsBox(const Vec3& p, const Vec3& q, const Vec3& e) {
  double lo = 0.0, hi = 1.0;
  const Vec3 d = q - p;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d(k)) < 1e-300) {
      if (std::abs(p(k)) > e(k)) return false;
      continue;
    }
    double t0 = (-e(k) - p(k)) / d(k), t1 = (e(k) - p(k)) / d(k);
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
    if (lo > hi) return false;
  }
  return true;
}

// Box A against box B, both moved from the reference (centre a_r, rotation A_r; b_r, B_r) to the
// candidate, seen from B's frame with A's points moved linearly there: crossed when one of A's
// corners went into B's core, the box of half sizes h_B / 2 (past half its depth, where the
// penalty law of an edge, measured below B's nearest face, pushes it out of the far side), or
// A's centre into the box of half sizes (h_B + min h_A) / 2, each from outside it. A box resting
// or sliding on another keeps its corners within the contact's penetration of B's faces and its
// centre h_A + h_B from B's; a box carried through a thin one in a step passes through both.
bool BoxEnteredCore(const Vec3& a_r, const Mat3& A_r, const Vec3& b_r, const Mat3& B_r,
                    const Vec3& a_c, const Mat3& A_c, const Vec3& b_c, const Mat3& B_c,
                    const Vec3& half_a, const Vec3& half_b) {
  const auto entered = [](const Vec3& u_r, const Vec3& u_c, const Vec3& e) {
    if ((u_r.cwiseAbs().array() <= e.array()).all()) return false;  // inside already
    return SegmentMeetsBox(u_r, u_c, e);
  };
  const Vec3 e_centre = 0.5 * (half_b + Vec3::Constant(half_a.minCoeff()));
  if (entered(B_r.transpose() * (a_r - b_r), B_c.transpose() * (a_c - b_c), e_centre)) return true;
  const Vec3 e_corner = 0.5 * half_b;
  for (int k = 0; k < 8; ++k) {
    const Vec3 c((k & 1) ? half_a.x() : -half_a.x(), (k & 2) ? half_a.y() : -half_a.y(),
                 (k & 4) ? half_a.z() : -half_a.z());
    if (entered(B_r.transpose() * (a_r + A_r * c - b_r), B_c.transpose() * (a_c + A_c * c - b_c),
                e_corner))
      return true;
  }
  return false;
}

// The distance between segments P and Q.
double SegmentDistance(const Vec3& P0, const Vec3& P1, const Vec3& Q0, const Vec3& Q1) {
  double s = 0.0, t = 0.0;
  ClosestSegmentParameters(P0, P1, Q0, Q1, &s, &t);
  return ((P0 + s * (P1 - P0)) - (Q0 + t * (Q1 - Q0))).norm();
}

// The signed distance of the two axis lines times |d_A x d_B| (0 for a point or parallel axes).
double LineSide(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  return (a1 - a0).cross(b1 - b0).dot(a0 - b0);
}

// Segment pair (A, B) from the reference r (4 points a0 a1 b0 b1) to the candidate c, radii sum
// `reach`: the axes passed through each other, or went into each other.
bool SegmentsCrossed(const Vec3 (&r)[4], const Vec3 (&c)[4], double reach) {
  const double near = 0.5 * reach;
  const double d_c = SegmentDistance(c[0], c[1], c[2], c[3]);
  if (d_c < near) return SegmentDistance(r[0], r[1], r[2], r[3]) >= near;
  const double f0 = LineSide(r[0], r[1], r[2], r[3]);
  const double f1 = LineSide(c[0], c[1], c[2], c[3]);
  if (!(f0 * f1 < 0.0)) return false;
  // The parameter where the lines meet, by bisection on the linear motion of the end points.
  double lo = 0.0, hi = 1.0;
  Vec3 p[4];
  for (int it = 0; it < 40; ++it) {
    const double t = 0.5 * (lo + hi);
    for (int k = 0; k < 4; ++k) p[k] = r[k] + t * (c[k] - r[k]);
    const double f = LineSide(p[0], p[1], p[2], p[3]);
    if ((f < 0.0) == (f0 < 0.0))
      lo = t;
    else
      hi = t;
  }
  const double t = 0.5 * (lo + hi);
  for (int k = 0; k < 4; ++k) p[k] = r[k] + t * (c[k] - r[k]);
  return SegmentDistance(p[0], p[1], p[2], p[3]) < near;
}

// A shape against an obstacle: its axis went `depth` behind a plane, or into a capsule's or sphere's
// axis (nearer than half the sum of the radii), from the reference r to the candidate c.
bool ObstacleCrossed(const ContactObstacle& o, double radius, double depth, const Vec3 (&r)[2],
                     const Vec3 (&c)[2]) {
  // No swept check against meshes (nor boxes and cylinders): their pairs keep the penalty.
  if (o.type == ObstacleType::kMesh || o.type == ObstacleType::kHeightfield ||
      o.type == ObstacleType::kBox || o.type == ObstacleType::kCylinder)
    return false;
  if (o.type == ObstacleType::kPlane) {
    const double h_r = std::min(o.normal.dot(r[0] - o.point), o.normal.dot(r[1] - o.point));
    const double h_c = std::min(o.normal.dot(c[0] - o.point), o.normal.dot(c[1] - o.point));
    return h_r >= -depth && h_c < -depth;
  }
  const Vec3 q1 = o.type == ObstacleType::kSphere ? o.point : o.to;
  const Vec3 rr[4] = {r[0], r[1], o.point, q1};
  const Vec3 cc[4] = {c[0], c[1], o.point, q1};
  return SegmentsCrossed(rr, cc, radius + o.radius);
}

// Whether two contact segments may touch (as the broad phase's PairWriter decides).
bool SegmentsMayTouch(const Model& m, const ContactSegment& a, const ContactSegment& b) {
  if (a.entity == b.entity) {
    const double skip = m.contact_entity_self_skip[static_cast<std::size_t>(a.entity)];
    return skip >= 0.0 && std::max(b.s0 - a.s1, a.s0 - b.s1) >= skip;
  }
  return m.contact_entity_pairs.MayTouch(a.entity, b.entity);
}

}  // namespace

bool MayCross(const Model& model) {
  return !model.contact_segments.empty() || !model.contact_pairs.empty();
}

void SaveCrossingReference(const Model& model, Data& data) {
  if (data.crossing_points.empty()) return;
  std::size_t k = 0;
  for (const ContactSegment& s : model.contact_segments) {
    if (IsBox(s.side)) {
      Mat3 R;
      BoxPose(data, s.side, &data.crossing_points[k], &R);
      data.crossing_points[k + 1] = LogSO3(R);
    } else {
      SideEnds(data, s.side, &data.crossing_points[k], &data.crossing_points[k + 1]);
    }
    k += 2;
  }
  for (const ContactPair& p : model.contact_pairs) {
    PairEnds(data, p, &data.crossing_points[k], &data.crossing_points[k + 1]);
    k += 2;
  }
  data.crossing_valid = true;
}

bool FindCrossing(const Model& model, Data& data, Crossing* out) {
  if (!data.crossing_valid || data.crossing_points.empty()) return false;
  const std::vector<Vec3>& ref = data.crossing_points;
  // Obstacle pairs: each against its obstacle.
  const std::size_t ns = model.contact_segments.size();
  for (std::size_t i = 0; i < model.contact_pairs.size(); ++i) {
    const ContactPair& p = model.contact_pairs[i];
    // Behind a plane: deeper than 100 onsets of the pair's law (the default onset is 1 % of the
    // smallest radius), far beyond any resting penetration.
    const double depth = 100.0 * ContactOnsetOf(model, p.material);
    const Vec3 r[2] = {ref[2 * (ns + i)], ref[2 * (ns + i) + 1]};
    Vec3 c[2];
    PairEnds(data, p, &c[0], &c[1]);
    if (ObstacleCrossed(model.obstacles[static_cast<std::size_t>(p.obstacle)], p.radius, depth, r,
                        c)) {
      out->found = true;
      out->a = static_cast<int>(i);
      out->b = -1;
      return true;
    }
  }
  if (ns < 2 || !MayHaveShapePairs(model)) return false;
  // Swept boxes (reference and candidate ends, inflated by the radius), sorted by their low x;
  // then sweep-and-prune on x with the full boxes' overlap.
  for (std::size_t i = 0; i < ns; ++i) {
    const ContactSegment& s = model.contact_segments[i];
    Vec3 c0, c1;
    SideEnds(data, s.side, &c0, &c1);
    const double r = IsBox(s.side) ? s.side.half.norm() : s.side.radius;
    // A box's reference holds its centre and its rotation vector (SaveCrossingReference).
    const Vec3& r1 = IsBox(s.side) ? ref[2 * i] : ref[2 * i + 1];
    data.crossing_lo[i] = ref[2 * i].cwiseMin(r1).cwiseMin(c0.cwiseMin(c1)) - Vec3::Constant(r);
    data.crossing_hi[i] = ref[2 * i].cwiseMax(r1).cwiseMax(c0.cwiseMax(c1)) + Vec3::Constant(r);
    data.crossing_order[i] = static_cast<int>(i);
  }
  std::sort(data.crossing_order.begin(), data.crossing_order.end(), [&](int a, int b) {
    return data.crossing_lo[static_cast<std::size_t>(a)].x() <
           data.crossing_lo[static_cast<std::size_t>(b)].x();
  });
  for (std::size_t u = 0; u < ns; ++u) {
    const std::size_t i = static_cast<std::size_t>(data.crossing_order[u]);
    const ContactSegment& a = model.contact_segments[i];
    for (std::size_t w = u + 1; w < ns; ++w) {
      const std::size_t j = static_cast<std::size_t>(data.crossing_order[w]);
      if (data.crossing_lo[j].x() > data.crossing_hi[i].x()) break;
      if ((data.crossing_lo[j].array() > data.crossing_hi[i].array()).any() ||
          (data.crossing_lo[i].array() > data.crossing_hi[j].array()).any())
        continue;
      const ContactSegment& b = model.contact_segments[j];
      // A box against a segment is left out; two boxes: BoxEnteredCore both ways.
      if (IsBox(a.side) != IsBox(b.side) || !SegmentsMayTouch(model, a, b)) continue;
      if (std::isinf(a.mass) && std::isinf(b.mass)) continue;
      if (IsBox(a.side)) {
        Vec3 ca, cb;
        Mat3 Ra, Rb;
        BoxPose(data, a.side, &ca, &Ra);
        BoxPose(data, b.side, &cb, &Rb);
        const Mat3 Ra_r = ExpSO3(ref[2 * i + 1]), Rb_r = ExpSO3(ref[2 * j + 1]);
        if (BoxEnteredCore(ref[2 * i], Ra_r, ref[2 * j], Rb_r, ca, Ra, cb, Rb, a.side.half,
                           b.side.half) ||
            BoxEnteredCore(ref[2 * j], Rb_r, ref[2 * i], Ra_r, cb, Rb, ca, Ra, b.side.half,
                           a.side.half)) {
          out->found = true;
          out->a = static_cast<int>(i);
          out->b = static_cast<int>(j);
          return true;
        }
        continue;
      }
      Vec3 c[4];
      SideEnds(data, a.side, &c[0], &c[1]);
      SideEnds(data, b.side, &c[2], &c[3]);
      const Vec3 r[4] = {ref[2 * i], ref[2 * i + 1], ref[2 * j], ref[2 * j + 1]};
      if (SegmentsCrossed(r, c, a.side.radius + b.side.radius)) {
        out->found = true;
        out->a = static_cast<int>(i);
        out->b = static_cast<int>(j);
        return true;
      }
    }
  }
  return false;
}

namespace {

// "rod 'a' element 3" or "body 'b'" into buf (no allocation).
int FormatSide(const Model& model, const ShapePairSide& side, char* buf, std::size_t size) {
  if (side.rod) {
    const Rod& rod = model.rods[static_cast<std::size_t>(side.owner)];
    return std::snprintf(buf, size, "rod '%s' element %d", rod.name.c_str(),
                         side.element - rod.first_element);
  }
  return std::snprintf(buf, size, "body '%s'",
                       model.bodies[static_cast<std::size_t>(side.owner)].name.c_str());
}

}  // namespace

void FormatCrossing(const Model& model, const Crossing& c, char* buf, std::size_t size) {
  if (size == 0) return;
  buf[0] = 0;
  if (!c.found) return;
  if (c.b < 0) {
    const ContactPair& p = model.contact_pairs[static_cast<std::size_t>(c.a)];
    const char* owner = p.rod ? model.rods[static_cast<std::size_t>(p.owner)].name.c_str()
                              : model.bodies[static_cast<std::size_t>(p.owner)].name.c_str();
    std::snprintf(buf, size, "%s '%s' and obstacle '%s'", p.rod ? "rod" : "body", owner,
                  model.obstacles[static_cast<std::size_t>(p.obstacle)].name.c_str());
    return;
  }
  int n = FormatSide(model, model.contact_segments[static_cast<std::size_t>(c.a)].side, buf, size);
  if (n < 0 || static_cast<std::size_t>(n) + 5 >= size) return;
  std::snprintf(buf + n, size - static_cast<std::size_t>(n), " and ");
  n += 5;
  FormatSide(model, model.contact_segments[static_cast<std::size_t>(c.b)].side, buf + n,
             size - static_cast<std::size_t>(n));
}

std::string DescribeCrossing(const Model& model, const Crossing& c) {
  char buf[512];
  FormatCrossing(model, c, buf, sizeof buf);
  return buf;
}

int CheckStepCrossing(const Model& model, Data& data, int iterations, std::string* why) {
  if (iterations < 0) return iterations;
  Crossing c;
  if (!FindCrossing(model, data, &c)) return iterations;
  if (why) {
    char buf[256];
    FormatCrossing(model, c, buf, sizeof buf);
    why->assign("the step carried ");
    why->append(buf);
    why->append(" through each other (contact tunnelling)");
  }
  return -1;
}

}  // namespace screwfem
