#include "screwfem/model/mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace screwfem {

namespace {

double MeshClamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

// Closest parameters of segments P0 + s d1 and Q0 + t d2 (Ericson, Real-Time Collision
// Detection, 2005, section 5.1.9), clamped to [0, 1]; parallel: the middle of the overlap.
void MeshSegmentSegment(const Vec3& P0, const Vec3& d1, const Vec3& Q0, const Vec3& d2, double* s,
                        double* t) {
  const Vec3 r = P0 - Q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  if (a <= 1e-300) {
    *s = 0.0;
    *t = MeshClamp01(f / e);
    return;
  }
  const double c = d1.dot(r), b = d1.dot(d2), denom = a * e - b * b;
  if (denom > 1e-10 * a * e) {
    *s = MeshClamp01((b * f - c * e) / denom);
  } else {
    const double s0 = -c / a, s1 = (b - c) / a;
    const double lo = std::max(0.0, std::min(s0, s1)), hi = std::min(1.0, std::max(s0, s1));
    *s = lo <= hi ? 0.5 * (lo + hi) : (std::max(s0, s1) < 0.0 ? 0.0 : 1.0);
  }
  *t = (b * *s + f) / e;
  if (*t < 0.0) {
    *t = 0.0;
    *s = MeshClamp01(-c / a);
  } else if (*t > 1.0) {
    *t = 1.0;
    *s = MeshClamp01((b - c) / a);
  }
}

// Distance between the boxes [lo, hi] and [a, b] (0 when they overlap).
double MeshBoxDistance(const Vec3& lo, const Vec3& hi, const Vec3& a, const Vec3& b) {
  double d2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double g = std::max(0.0, std::max(lo(i) - b(i), a(i) - hi(i)));
    d2 += g * g;
  }
  return std::sqrt(d2);
}

// Eberly's subexpressions of the polyhedral integrals.
void MeshSubexpressions(double w0, double w1, double w2, double* f1, double* f2, double* f3,
                        double* g0, double* g1, double* g2) {
  const double temp0 = w0 + w1;
  *f1 = temp0 + w2;
  const double temp1 = w0 * w0;
  const double temp2 = temp1 + w1 * temp0;
  *f2 = temp2 + w2 * *f1;
  *f3 = w0 * temp1 + w1 * temp2 + w2 * *f2;
  *g0 = *f2 + w0 * (*f1 + w0);
  *g1 = *f2 + w1 * (*f1 + w1);
  *g2 = *f2 + w2 * (*f1 + w2);
}

}  // namespace

std::string CheckTriangleMesh(const TriangleMesh& mesh, const std::string& what) {
  char buf[256];
  if (mesh.faces.empty()) return what + ": the mesh has no triangles";
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!mesh.vertices[i].allFinite()) {
      std::snprintf(buf, sizeof buf, ": vertex %zu is not finite", i);
      return what + buf;
    }
  const int n = static_cast<int>(mesh.vertices.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const std::array<int, 3>& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k)
      if (t[static_cast<std::size_t>(k)] < 0 || t[static_cast<std::size_t>(k)] >= n) {
        std::snprintf(buf, sizeof buf,
                      ": face %zu refers to vertex %d, expected an index in [0, %d) (0-based)", f,
                      t[static_cast<std::size_t>(k)], n);
        return what + buf;
      }
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Vec3& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Vec3& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), 1e-300});
    if (!((b - a).cross(c - a).norm() > 1e-12 * scale)) {
      std::snprintf(buf, sizeof buf, ": face %zu (vertices %d, %d, %d) is degenerate (no area)", f,
                    t[0], t[1], t[2]);
      return what + buf;
    }
  }
  return {};
}

TriangleMesh HeightFieldMesh(const std::vector<double>& h, int rows, int cols, double dx,
                             double dy) {
  TriangleMesh m;
  m.vertices.reserve(static_cast<std::size_t>(rows * cols));
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      m.vertices.emplace_back((j - 0.5 * (cols - 1)) * dx, (i - 0.5 * (rows - 1)) * dy,
                              h[static_cast<std::size_t>(i * cols + j)]);
  m.faces.reserve(static_cast<std::size_t>(2 * (rows - 1) * (cols - 1)));
  for (int i = 0; i + 1 < rows; ++i)
    for (int j = 0; j + 1 < cols; ++j) {
      const int a = i * cols + j, b = a + 1, c = a + cols, d = c + 1;
      m.faces.push_back({a, b, d});  // counter-clockwise seen from +z
      m.faces.push_back({a, d, c});
    }
  return m;
}

MeshMassProperties CalcMeshMassProperties(const TriangleMesh& mesh) {
  // Eberly (Polyhedral mass properties, 2002) after Mirtich (1996), about a reference point
  // inside the mesh's box (less round-off far from the origin).
  Vec3 ref = Vec3::Zero();
  for (const Vec3& v : mesh.vertices) ref += v;
  if (!mesh.vertices.empty()) ref /= static_cast<double>(mesh.vertices.size());
  double in[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (const std::array<int, 3>& t : mesh.faces) {
    const Vec3 p0 = mesh.vertices[static_cast<std::size_t>(t[0])] - ref;
    const Vec3 p1 = mesh.vertices[static_cast<std::size_t>(t[1])] - ref;
    const Vec3 p2 = mesh.vertices[static_cast<std::size_t>(t[2])] - ref;
    const Vec3 d = (p1 - p0).cross(p2 - p0);
    double f1[3], f2[3], f3[3], g0[3], g1[3], g2[3];
    for (int i = 0; i < 3; ++i)
      MeshSubexpressions(p0(i), p1(i), p2(i), &f1[i], &f2[i], &f3[i], &g0[i], &g1[i], &g2[i]);
    in[0] += d(0) * f1[0];
    in[1] += d(0) * f2[0];
    in[2] += d(1) * f2[1];
    in[3] += d(2) * f2[2];
    in[4] += d(0) * f3[0];
    in[5] += d(1) * f3[1];
    in[6] += d(2) * f3[2];
    in[7] += d(0) * (p0(1) * g0[0] + p1(1) * g1[0] + p2(1) * g2[0]);
    in[8] += d(1) * (p0(2) * g0[1] + p1(2) * g1[1] + p2(2) * g2[1]);
    in[9] += d(2) * (p0(0) * g0[2] + p1(0) * g1[2] + p2(0) * g2[2]);
  }
  const double mult[10] = {1.0 / 6,  1.0 / 24, 1.0 / 24,  1.0 / 24,  1.0 / 60,
                           1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (int i = 0; i < 10; ++i) in[i] *= mult[i];
  MeshMassProperties out;
  const double V = in[0];
  out.volume = V;
  if (V == 0.0) return out;
  const Vec3 c(in[1] / V, in[2] / V, in[3] / V);
  Mat3 J;
  J(0, 0) = in[5] + in[6] - V * (c(1) * c(1) + c(2) * c(2));
  J(1, 1) = in[4] + in[6] - V * (c(2) * c(2) + c(0) * c(0));
  J(2, 2) = in[4] + in[5] - V * (c(0) * c(0) + c(1) * c(1));
  J(0, 1) = J(1, 0) = -(in[7] - V * c(0) * c(1));
  J(1, 2) = J(2, 1) = -(in[8] - V * c(1) * c(2));
  J(0, 2) = J(2, 0) = -(in[9] - V * c(2) * c(0));
  out.centroid = c + ref;
  out.inertia = J;
  return out;
}

// ---- The tree ----------------------------------------------------------------------------------

void MeshTree::Build(const TriangleMesh& mesh, const Mat3& R, const Vec3& x, double scale) {
  vertices_.clear();
  vertices_.reserve(mesh.vertices.size());
  for (const Vec3& v : mesh.vertices) vertices_.push_back(x + scale * (R * v));
  faces_ = mesh.faces;
  normals_.clear();
  std::vector<Vec3> centroids;
  for (const std::array<int, 3>& t : faces_) {
    const Vec3& a = vertices_[static_cast<std::size_t>(t[0])];
    const Vec3& b = vertices_[static_cast<std::size_t>(t[1])];
    const Vec3& c = vertices_[static_cast<std::size_t>(t[2])];
    normals_.push_back((b - a).cross(c - a).normalized());
    centroids.push_back((a + b + c) / 3.0);
  }
  order_.resize(faces_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
  nodes_.clear();
  nodes_.reserve(2 * faces_.size() / kLeafSize + 2);
  nodes_.push_back({});
  BuildNode(0, 0, static_cast<int>(faces_.size()), 0, centroids);
  extent_ = nodes_.empty() ? 0.0 : (nodes_[0].hi - nodes_[0].lo).norm();
}

void MeshTree::BuildNode(int node, int first, int count, int depth, std::vector<Vec3>& centroids) {
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  Vec3 clo = lo, chi = hi;
  for (int i = first; i < first + count; ++i) {
    const int f = order_[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) {
      const Vec3& v = vertices_[static_cast<std::size_t>(
          faces_[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)])];
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    clo = clo.cwiseMin(centroids[static_cast<std::size_t>(f)]);
    chi = chi.cwiseMax(centroids[static_cast<std::size_t>(f)]);
  }
  nodes_[static_cast<std::size_t>(node)].lo = lo;
  nodes_[static_cast<std::size_t>(node)].hi = hi;
  if (count <= kLeafSize || depth + 1 >= kMaxDepth) {
    nodes_[static_cast<std::size_t>(node)].first = first;
    nodes_[static_cast<std::size_t>(node)].count = count;
    return;
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const int half = count / 2;
  auto begin = order_.begin() + first;
  std::nth_element(begin, begin + half, begin + count, [&](int a, int b) {
    return centroids[static_cast<std::size_t>(a)](axis) <
           centroids[static_cast<std::size_t>(b)](axis);
  });
  const int left = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  nodes_.push_back({});
  nodes_[static_cast<std::size_t>(node)].first = left;
  nodes_[static_cast<std::size_t>(node)].count = 0;
  BuildNode(left, first, half, depth + 1, centroids);
  BuildNode(left + 1, first + half, count - half, depth + 1, centroids);
}

std::size_t MeshTree::bytes() const {
  return vertices_.capacity() * sizeof(Vec3) + normals_.capacity() * sizeof(Vec3) +
         faces_.capacity() * sizeof(std::array<int, 3>) + order_.capacity() * sizeof(int) +
         nodes_.capacity() * sizeof(TreeNode);
}

namespace {

// Offers candidate c to the best in front (distance >= 0) or behind (< 0) the faces:
// nearest in front, shallowest behind; ties under parallel faces merge their flat parts.
void Offer(const MeshHit& c, double tol, MeshHit* best) {
  if (!best->found) {
    *best = c;
    return;
  }
  const double key = std::abs(c.distance), best_key = std::abs(best->distance);
  if (key < best_key - tol) {
    *best = c;
    return;
  }
  if (key > best_key + tol) return;
  // A tie: two faces' flat parts under one parallel segment (coplanar faces) merge.
  if (c.feature == 0 && best->feature == 0 && c.s_hi > c.s_lo && best->s_hi > best->s_lo &&
      c.normal.dot(best->normal) > 1.0 - 1e-12) {
    best->s_lo = std::min(best->s_lo, c.s_lo);
    best->s_hi = std::max(best->s_hi, c.s_hi);
  } else if (c.feature == 0 && best->feature != 0) {
    *best = c;  // the face over its edge (the same point, the exact normal)
  }
}

}  // namespace

void MeshTree::Search(const Vec3& A, const Vec3& B, double reach, double depth, MeshHit* front,
                      MeshHit* behind) const {
  if (nodes_.empty()) return;
  const Vec3 d = B - A;
  const Vec3 slo = A.cwiseMin(B), shi = A.cwiseMax(B);
  const double tol = 1e-12 * std::max(1.0, extent_);
  const double dd = d.squaredNorm();
  int stack[2 * kMaxDepth + 2];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const TreeNode& node = nodes_[static_cast<std::size_t>(stack[--top])];
    // Nothing in this box can beat what is found: a point in front nearer than the best in
    // front (or `reach`), or a point behind a face (within `depth` of it).
    const double bound_front = front->found ? std::abs(front->distance) : reach;
    const double bound =
        std::max(bound_front, behind->found ? std::abs(behind->distance) : depth) + tol;
    if (MeshBoxDistance(node.lo, node.hi, slo, shi) > bound) continue;
    if (node.count == 0) {
      stack[top++] = node.first;
      stack[top++] = node.first + 1;
      continue;
    }
    for (int i = node.first; i < node.first + node.count; ++i) {
      const int f = order_[static_cast<std::size_t>(i)];
      const std::array<int, 3>& t = faces_[static_cast<std::size_t>(f)];
      const Vec3& n = normals_[static_cast<std::size_t>(f)];
      const Vec3* v[3] = {&vertices_[static_cast<std::size_t>(t[0])],
                          &vertices_[static_cast<std::size_t>(t[1])],
                          &vertices_[static_cast<std::size_t>(t[2])]};
      // The segment clipped to the prism over the face.
      double lo = 0.0, hi = 1.0;
      for (int k = 0; k < 3 && lo <= hi; ++k) {
        const Vec3 m = n.cross(*v[(k + 1) % 3] - *v[k]);  // points into the triangle
        const double f0 = m.dot(A - *v[k]), df = m.dot(d);
        if (std::abs(df) <= 1e-14 * m.norm() * std::sqrt(dd)) {
          if (f0 < 0.0) hi = -1.0;
        } else if (df > 0.0) {
          lo = std::max(lo, -f0 / df);
        } else {
          hi = std::min(hi, -f0 / df);
        }
      }
      if (lo <= hi) {
        const double h0 = n.dot(A - *v[0]), dh = n.dot(d);
        MeshHit c;
        c.found = true;
        c.face = f;
        c.feature = 0;
        c.normal = n;
        if (std::abs(dh) <= 1e-12 * std::sqrt(dd)) {  // parallel: the middle
          c.s = 0.5 * (lo + hi);
          c.s_lo = lo;
          c.s_hi = hi;
        } else {
          c.s = c.s_lo = c.s_hi = (h0 + dh * hi < h0 + dh * lo) ? hi : lo;
        }
        c.distance = h0 + dh * c.s;
        c.point = A + c.s * d - c.distance * n;
        if (c.distance >= 0.0 && c.distance <= reach) Offer(c, tol, front);
        if (c.distance < 0.0 && -c.distance <= depth) Offer(c, tol, behind);
      }
      // The segment against the face's edges (points outside the prism).
      for (int k = 0; k < 3; ++k) {
        const Vec3& e0 = *v[k];
        const Vec3 de = *v[(k + 1) % 3] - e0;
        double s = 0.0, u = 0.0;
        MeshSegmentSegment(A, d, e0, de, &s, &u);
        const Vec3 p = A + s * d, q = e0 + u * de;
        const double dist = (p - q).norm();
        if (!(dist > 0.0) || dist > reach) continue;
        MeshHit c;
        c.found = true;
        c.face = f;
        c.feature = (u <= 0.0 || u >= 1.0) ? 2 : 1;
        c.s = c.s_lo = c.s_hi = s;
        c.point = q;
        c.normal = (p - q) / dist;
        c.distance = dist;
        Offer(c, tol, front);
      }
    }
  }
}

MeshHit MeshTree::ClosestToSegment(const Vec3& A, const Vec3& B, double reach, double depth) const {
  MeshHit front, behind;
  Search(A, B, reach, depth, &front, &behind);
  const Vec3 d = B - A;
  // A point behind a face counts only when that face is its nearest feature (else it is in
  // front of a nearer face: a thin wall's far side).
  if (behind.found) {
    const Vec3 p = A + behind.s * d;
    MeshHit pf, pb;
    Search(p, p, -behind.distance, -behind.distance, &pf, &pb);
    const double tol = 1e-12 * std::max(1.0, extent_);
    if (!(pf.found && pf.distance < -behind.distance - tol)) {
      if (behind.s_hi > behind.s_lo) {
        behind.s = 0.5 * (behind.s_lo + behind.s_hi);
        behind.point = A + behind.s * d - behind.distance * behind.normal;
      }
      return behind;
    }
  }
  if (front.found && front.s_hi > front.s_lo) {
    front.s = 0.5 * (front.s_lo + front.s_hi);
    front.point = A + front.s * d - front.distance * front.normal;
  }
  return front;
}

}  // namespace screwfem
