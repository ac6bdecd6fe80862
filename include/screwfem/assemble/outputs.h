// Output quantities (method.md §6).
#pragma once

#include "screwfem/model/model.h"

namespace screwfem {

// World position, velocity and acceleration of a point fixed in a moving frame.
struct PointMotion {
  Vec3 position = Vec3::Zero();      // [m]
  Vec3 velocity = Vec3::Zero();      // [m/s]
  Vec3 acceleration = Vec3::Zero();  // [m/s^2]
};

// For a frame H = (R, x) with body velocity eta = [v; w] and its time derivative eta_dot,
// and a point p given in the frame: x_P = x + R p, x_P' = R (v + w x p),
// x_P'' = R (v' + w' x p + w x (v + w x p))   (method.md §6).
PointMotion CalcPointMotion(const SE3& H, const Vec6& eta, const Vec6& eta_dot, const Vec3& p);

// The same for a point p in the frame of `node` (a fixed node has zero velocity).
PointMotion CalcNodePointMotion(const Model& model, const Data& data, int node, const Vec3& p);

}  // namespace screwfem
