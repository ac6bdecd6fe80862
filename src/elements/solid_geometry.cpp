#include "screwfem/elements/solid_geometry.h"

#include <algorithm>
#include <cmath>

namespace screwfem {

Vec3 Perpendicular(const Vec3& e) {
  int axis = 0;
  e.cwiseAbs().minCoeff(&axis);
  return e.cross(Vec3::Unit(axis)).normalized();
}

namespace {

// The cylinder in its axis coordinates: z along the unit axis e from the middle m, the radial
// offset r (perpendicular to e) of c.
struct CylinderCoordinates {
  Vec3 m, e, r;
  double h = 0.0, z = 0.0, rho = 0.0;
};

CylinderCoordinates CylinderCoordinatesOf(const Vec3& A, const Vec3& B, const Vec3& c) {
  CylinderCoordinates k;
  k.m = 0.5 * (A + B);
  const Vec3 axis = B - A;
  k.h = 0.5 * axis.norm();
  k.e = axis / (2.0 * k.h);
  const Vec3 v = c - k.m;
  k.z = k.e.dot(v);
  k.r = v - k.z * k.e;
  k.rho = k.r.norm();
  return k;
}

}  // namespace

double CylinderSignedDistance(const Vec3& A, const Vec3& B, double R, const Vec3& c) {
  const CylinderCoordinates k = CylinderCoordinatesOf(A, B, c);
  const double qr = k.rho - R, qz = std::abs(k.z) - k.h;
  return std::hypot(std::max(qr, 0.0), std::max(qz, 0.0)) + std::min(std::max(qr, qz), 0.0);
}

SolidPoint CylinderClosestPoint(const Vec3& A, const Vec3& B, double R, const Vec3& c) {
  const CylinderCoordinates k = CylinderCoordinatesOf(A, B, c);
  const Vec3 u = k.rho > 0.0 ? Vec3(k.r / k.rho) : Perpendicular(k.e);
  const double qr = k.rho - R, qz = std::abs(k.z) - k.h;
  const double sz = k.z >= 0.0 ? 1.0 : -1.0;
  SolidPoint out;
  // The side (radial), the flat face (axial) or the rim (both out).
  const bool side = qr > 0.0 ? qz <= 0.0 : (qz <= 0.0 && qr > qz);
  if (qr > 0.0 && qz > 0.0) {
    out.point = k.m + sz * k.h * k.e + R * u;
    const Vec3 d = c - out.point;
    out.distance = d.norm();
    out.normal = d / out.distance;
  } else if (side) {
    out.point = k.m + k.z * k.e + R * u;
    out.normal = u;
    out.distance = qr;
  } else {
    out.point = k.m + sz * k.h * k.e + k.r;
    out.normal = sz * k.e;
    out.distance = qz;
  }
  return out;
}

namespace {

// The minimum of a convex function f on [0, 1]: golden-section search to round-off, then the
// middle of the set where f is within `tolerance` of the least value (a flat minimum).
template <class F>
double ConvexMinimum(F&& f, double tolerance) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = 0.0, b = 1.0;
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < 80 && b - a > 1e-15; ++i) {
    if (f1 <= f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = f(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = f(x2);
    }
  }
  // The ends may be lower than the interior (the minimum on a boundary).
  double s = f1 <= f2 ? x1 : x2, best = std::min(f1, f2);
  for (double end : {0.0, 1.0}) {
    const double v = f(end);
    if (v < best) best = v, s = end;
  }
  const double level = best + tolerance;
  // A flat minimum: bisect for the ends of {f <= level} around s.
  auto edge = [&](double inside, double outside) {
    if (f(outside) <= level) return outside;
    for (int i = 0; i < 60 && std::abs(outside - inside) > 1e-15; ++i) {
      const double mid = 0.5 * (inside + outside);
      (f(mid) <= level ? inside : outside) = mid;
    }
    return inside;
  };
  // Flat: f within the tolerance 1e-4 of the segment away on a side (a strict minimum rises
  // by at least f'' 1e-8 / 2 there, far above round-off).
  const double step = 1e-4;
  const bool flat =
      (s - step >= 0.0 && f(s - step) <= level) || (s + step <= 1.0 && f(s + step) <= level);
  if (!flat) return s;
  return 0.5 * (edge(s, 0.0) + edge(s, 1.0));
}

}  // namespace

double CylinderSegmentParameter(const Vec3& A, const Vec3& B, double R, const Vec3& P0,
                                const Vec3& P1) {
  const Vec3 d = P1 - P0;
  if (d.squaredNorm() == 0.0) return 0.0;
  const double tolerance = 1e-14 * (R + (B - A).norm() + d.norm());
  return ConvexMinimum([&](double s) { return CylinderSignedDistance(A, B, R, Vec3(P0 + s * d)); },
                       tolerance);
}

Vec3 CylinderRimPoint(const Vec3& C, const Vec3& e, double R, const Vec3& n, int k) {
  const Vec3 w = n - n.dot(e) * e;
  const double norm = w.norm();
  const Vec3 u0 = norm > 1e-12 ? Vec3(-w / norm) : Perpendicular(e);
  if (k == 0) return C + R * u0;
  const double angle = (k == 1 ? 2.0 : -2.0) * 3.14159265358979323846 / 3.0;
  return C + R * (std::cos(angle) * u0 + std::sin(angle) * e.cross(u0));
}

SolidPoint BoxClosestPoint(const Vec3& c, const Vec3& h) {
  SolidPoint out;
  Vec3 q = c.cwiseMax(-h).cwiseMin(h);
  if (q != c) {
    const Vec3 d = c - q;
    out.distance = d.norm();
    out.normal = d / out.distance;
  } else {
    int axis = 0;
    (h - c.cwiseAbs()).minCoeff(&axis);
    const double sign = c(axis) >= 0.0 ? 1.0 : -1.0;
    q(axis) = sign * h(axis);
    out.normal = sign * Vec3::Unit(axis);
    out.distance = sign * c(axis) - h(axis);  // <= 0
  }
  out.point = q;
  return out;
}

// Signed distance from a point c to the box |x_i| <= h_i (box frame): the distance outside,
// minus the depth below the nearest face inside. Convex in c.
double BoxSignedDistance(const Vec3& c, const Vec3& h) {
  const Vec3 q = c.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// The parameter s in [0, 1] of the point a + s d (box frame) nearest to the box |x_i| <= h_i
// or deepest in it: the minimum of the convex function BoxSignedDistance(a + s d) over the
// segment, exactly. Outside the box it is the root of a piecewise quadratic (sum over the
// axes out of the box of (|c_i| - h_i)^2, pieces between the breakpoints |c_i| = h_i); inside
// it is the maximum of the six lines +-c_i(s) - h_i, least at an end or where two lines cross.
// So the minimum is among: the ends, the breakpoints, each piece's clamped minimiser and the
// crossings of the lines; every candidate is evaluated. A flat minimum (a segment parallel to
// a face) takes the middle of the set where the distance is least (as parallel segments do).
double BoxSegmentParameter(const Vec3& a, const Vec3& d, const Vec3& h) {
  double candidate[40];
  int n = 0;
  candidate[n++] = 0.0;
  candidate[n++] = 1.0;
  auto inside = [](double s) { return s > 0.0 && s < 1.0; };
  // Breakpoints |a_i + s d_i| = h_i, sorted with the ends: the pieces.
  double breaks[8];
  int nb = 0;
  breaks[nb++] = 0.0;
  for (int i = 0; i < 3; ++i) {
    if (d(i) == 0.0) continue;
    for (double sign : {-1.0, 1.0}) {
      const double s = (sign * h(i) - a(i)) / d(i);
      if (inside(s)) breaks[nb++] = s;
    }
  }
  breaks[nb++] = 1.0;
  for (int k = 1; k < nb; ++k)  // insertion sort of at most 8 values
    for (int j = k; j > 0 && breaks[j - 1] > breaks[j]; --j) std::swap(breaks[j - 1], breaks[j]);
  for (int k = 1; k < nb - 1; ++k) candidate[n++] = breaks[k];
  for (int k = 0; k + 1 < nb; ++k) {
    const double lo = breaks[k], hi = breaks[k + 1];
    const Vec3 mid = a + 0.5 * (lo + hi) * d;
    double num = 0.0, den = 0.0;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(mid(i)) <= h(i)) continue;
      const double sign = mid(i) > 0.0 ? 1.0 : -1.0;
      num -= d(i) * (a(i) - sign * h(i));
      den += d(i) * d(i);
    }
    if (den > 0.0) candidate[n++] = std::clamp(num / den, lo, hi);
  }
  // Crossings of the lines sign_i c_i(s) - h_i (15 pairs, the centre planes c_i = 0 included).
  for (int l = 0; l < 6; ++l)
    for (int m = l + 1; m < 6; ++m) {
      const int i = l / 2, j = m / 2;
      const double si = (l % 2) ? 1.0 : -1.0, sj = (m % 2) ? 1.0 : -1.0;
      const double den = si * d(i) - sj * d(j);
      if (den == 0.0) continue;
      const double s = (sj * a(j) - h(j) - si * a(i) + h(i)) / den;
      if (inside(s)) candidate[n++] = s;
    }
  double value[40];
  double best = INFINITY;
  for (int k = 0; k < n; ++k) {
    value[k] = BoxSignedDistance(a + candidate[k] * d, h);
    best = std::min(best, value[k]);
  }
  const double tolerance = 1e-12 * (h.maxCoeff() + d.norm());
  double s_lo = 1.0, s_hi = 0.0;
  for (int k = 0; k < n; ++k)
    if (value[k] <= best + tolerance) {
      s_lo = std::min(s_lo, candidate[k]);
      s_hi = std::max(s_hi, candidate[k]);
    }
  return 0.5 * (s_lo + s_hi);
}

}  // namespace screwfem
