// Output quantities (assemble/outputs.h).
#pragma once

#include <limits>
#include <vector>

#include "screwfem/model/data.h"

namespace screwfem {

// World position, velocity and acceleration of a point fixed in a moving frame.
struct PointMotion {
  Vec3 position = Vec3::Zero();      // [m]
  Vec3 velocity = Vec3::Zero();      // [m/s]
  Vec3 acceleration = Vec3::Zero();  // [m/s^2]
};

// For a frame H = (R, x) with body velocity eta = [v; w] and its time derivative eta_dot,
// and a point p given in the frame: x_P = x + R p, x_P' = R (v + w x p),
// x_P'' = R (v' + w' x p + w x (v + w x p))   (assemble/outputs.h).
PointMotion CalcPointMotion(const SE3& H, const Vec6& eta, const Vec6& eta_dot, const Vec3& p);

// The same for a point p in the frame of `node` (a fixed node has zero velocity).
PointMotion CalcNodePointMotion(const Model& model, const Data& data, int node, const Vec3& p);

// Section frame and motion of the point of rod `rod` at reference arc length s (clamped to
// [0, length]) on the section centre line: H(xi) = H_A exp(xi d), eta(xi) = N(xi, d) eta_AB,
// eta_dot(xi) = N eta_dot_AB + (dN/dd . d_dot) eta_AB (docs/numerics.md, "Rod inertia").
struct RodPoint {
  SE3 frame;
  PointMotion motion;
  int element = -1;  // global element index
  double xi = 0.0;   // in [0, 1]
};
RodPoint CalcRodPointMotion(const Model& model, const Data& data, int rod, double s);

// Section stress resultants of every element of a rod (section frame: N, V2, V3, T, M2, M3),
// written into out (size = number of elements): what the section transmits,
// sigma = K (d/L - f0 - eps0) - sigma_a with the actuation at data.time (docs/numerics.md, "Active stress and rest strain";
// K (d/L - f0) without actuators); with `elastic`, also the elastic part K (d/L - f0 - eps0).
void CalcRodStresses(const Model& model, const Data& data, int rod, std::vector<Vec6>* out,
                     std::vector<Vec6>* elastic = nullptr);

// Section strain and stress along rods (rod_fields.csv, io/writers.h RodFieldColumns), from
// the rod's constitutive law CalcRodLaw (elements/rod.h) with the actuation at data.time times
// `load_factor` (statics scales actuation like loads; 1 in dynamics). One station per
// element, at its mid arc length: a helical element's strain and stress are constant along it
// (for loads at its ends, its stress is the mean of the exact stress field over the element,
// which equals the field at the midpoint where that varies linearly). Per station
// kRodFieldValues values:
//   rod                  index in model.rods
//   s                    reference arc length of the station from the rod's first node [m]
//   eps = (gamma; kappa) strain (d - d0) / L relative to the reference configuration (zero at
//                        rest), section components: gamma1 extension, gamma2 gamma3 shear [-];
//                        kappa1 twist, kappa2 kappa3 bending curvatures about section axes 2
//                        and 3 [1/m] (section axis 1 is the rod axis, model/section.h)
//   sigma = (n; m)       stress resultants K eps - (K eps0 + sigma_a), what the section
//                        transmits: the force [N] and moment [N m] (about the section centre)
//                        that the part of the rod beyond the station (larger s) exerts on the
//                        part before it, section components: n1 axial force (> 0 tension),
//                        n2 n3 shear forces, m1 torque, m2 m3 bending moments
// i.e. the engine's translation-first 6-vectors eps and sigma in their order. `rod` < 0: every
// rod, in model order. *rows is resized to kRodFieldValues x stations (no allocation once it
// has that size).
inline constexpr int kRodFieldValues = 14;
void CalcRodFieldRows(const Model& model, const Data& data, int rod, double load_factor,
                      std::vector<double>* rows);

// The force and moment [N; N m] a joint transmits to its side B (node_b) from side A, world
// components, the moment about the origin of the joint frame on side B (H_B C_B): the
// constraint force -B_B^T lambda of its six relative-frame rows (which carries the joint's
// springs, dampers and drive too, as they act on the coordinates). Zero for joints without
// constraint rows (free joints) and for redundant rows (held at zero). The reaction on side A
// is the opposite force with the moment about the same point.
Vec6 CalcJointReaction(const Model& model, const Data& data, int joint);

// Linear momentum [kg m/s] and angular momentum about the world origin [kg m^2/s], world
// components: rigid bodies exactly, rods by 3-point Gauss quadrature of the exact helical
// velocity field eta(xi) = N(xi, d) eta_AB with the sectional mass matrix (docs/numerics.md, "Rod inertia").
Vec6 CalcMomentum(const Model& model, const Data& data);

// The largest translational [m/s] and angular [rad/s] speed of the free nodes (|v| and |w| of
// each node's body velocity, which equal the world ones), zero without free nodes: the measure
// of rest (solve/rest.h, RestWatch) and of settling.csv.
struct NodeSpeeds {
  double linear = 0.0;
  double angular = 0.0;
};
NodeSpeeds LargestNodeSpeeds(const Model& model, const Data& data);

// How far a scene is from rest (settling.csv; docs/numerics.md, "Settling and rest"): the
// kinetic energy [J] (CalcEnergy, unless the caller has it: `kinetic` not NaN), the largest
// node speeds (LargestNodeSpeeds), the active contacts of obstacle pairs and of pairs of
// moving shapes, how many of them slip (stick law; 0 under the smooth law, which has no stick
// state), the deepest overlap [m] (the largest -gap, 0 when no pair overlaps) and the largest
// overlap relative to the smaller radius of the pair's round shapes (rod capsules, spheres,
// capsules, cylinders; pairs without one, e.g. a box corner on a plane, do not count there).
// `dynamics`: the law with damping and the velocities (false: the static law). Allocates
// nothing.
struct SettlingState {
  double kinetic = 0.0;
  double speed = 0.0;
  double angular_speed = 0.0;
  int contacts = 0;
  int slipping = 0;
  double overlap = 0.0;
  double overlap_ratio = 0.0;
};
SettlingState CalcSettlingState(const Model& model, const Data& data, bool dynamics = true,
                                double kinetic = std::numeric_limits<double>::quiet_NaN());

}  // namespace screwfem
