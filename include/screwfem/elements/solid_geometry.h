// The closest points of the solid contact shapes with flat faces (boxes and cylinders; see
// docs/numerics.md, "Cylinders" and "Box-box"): the point of a segment nearest to a solid, or
// deepest in it, and the solid's surface point and outward normal there. Shared by the obstacle
// pairs (elements/contact.h) and the pairs of moving shapes (elements/shape_pair.h).
#pragma once

#include "screwfem/lie/se3.h"

namespace screwfem {

// A solid's surface point nearest to a point c, with the normal out of the solid there and the
// signed distance from the surface to c (> 0 outside; inside, minus the depth below the face
// nearest to c, through which c leaves).
struct SolidPoint {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  double distance = 0.0;
};

// A unit vector perpendicular to the unit vector e (a fixed choice: e x the axis along e's
// smallest component).
Vec3 Perpendicular(const Vec3& e);

// The cylinder with axis from A to B (A != B) and radius R > 0, flat ends: side, flat face or
// rim, whichever is nearest (docs/numerics.md, "Cylinders").
SolidPoint CylinderClosestPoint(const Vec3& A, const Vec3& B, double R, const Vec3& c);
double CylinderSignedDistance(const Vec3& A, const Vec3& B, double R, const Vec3& c);
// The parameter s in [0, 1] of the point P0 + s (P1 - P0) nearest to the cylinder or deepest in
// it: the minimum of its signed distance (convex along the segment) by golden-section search
// to round-off; a flat minimum (a segment parallel to the side or lying on a face) takes the
// middle of the set where the distance is least.
double CylinderSegmentParameter(const Vec3& A, const Vec3& B, double R, const Vec3& P0,
                                const Vec3& P1);

// The box |x_i| <= h_i in its own frame: signed distance, and the parameter s of the point
// a + s d (box frame) nearest to it or deepest in it (exact: the candidates of a piecewise
// quadratic; a flat minimum takes the middle).
double BoxSignedDistance(const Vec3& c, const Vec3& h);
double BoxSegmentParameter(const Vec3& a, const Vec3& d, const Vec3& h);
// The box's surface point nearest to c (box frame), normal and signed distance (box frame).
SolidPoint BoxClosestPoint(const Vec3& c, const Vec3& h);

// The rim point k (0, 1, 2) of a cylinder's flat end with centre C, unit axis e and radius R
// against a plane of normal n: k = 0 the deepest (the rim point furthest along -n), k = 1, 2
// at +-120 degrees from it about e (for an end face parallel to the plane, any rim direction).
Vec3 CylinderRimPoint(const Vec3& C, const Vec3& e, double R, const Vec3& n, int k);

}  // namespace screwfem
