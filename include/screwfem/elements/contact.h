// Frictional contact between moving shapes and obstacles fixed in the world, as an element kind
// (docs/numerics.md, "Contact": a penalty law).
//
// Each item is a (moving shape, obstacle) pair enumerated by ModelBuilder::Build
// (model.h, ContactPair): a rod element's chord capsule, a rod node's sphere, or a primitive of
// a rigid body, against a plane, sphere or capsule fixed in the world. The pair is a segment
// p(s) = (1-s) p_0 + s p_1 of body points inflated by a radius r; the closest parameter s* and
// the normal n (from the obstacle to the shape) are found at every evaluation and frozen in the
// tangent (envelope theorem for the gap gradient). The force acts at the surface point
// p_s = p(s*) - r n, which moves with the item's node(s) as sum_k W_k (x_k + R_k l_k): weights
// W_k and node-frame levers l_k = b_k - r R_k^T n (b_k the axis point's offset in node k).
//
// Law (docs/numerics.md, "Contact"): C1 penalty f_e(g) with onset delta and stiffness k_n, damping
// -c_n w(g) dg/dt, f_n = max(0, f_e + f_d); regularised Coulomb friction
// f_t = -mu f_n v_t / sqrt(|v_t|^2 + eps_v^2) at the surface point, applied implicitly.
// Friction and damping act in dynamics only (statics: frictionless contact).
#pragma once

#include <string>

#include "screwfem/elements/element.h"
#include "screwfem/model/model.h"

namespace screwfem {

// The elastic normal force f_e(g) [N] >= 0 and its derivative df_e/dg <= 0 (docs/numerics.md, "Contact"): 0 for g >= delta, k (delta - g)^2 / (2 delta) on [0, delta), k (delta/2 - g) below.
struct NormalLaw {
  double force = 0.0;
  double slope = 0.0;
};
NormalLaw CalcNormalLaw(double gap, double onset, double stiffness);
// Its potential Psi(g) = integral from g to delta of f_e [J].
double ContactPotential(double gap, double onset, double stiffness);

// The parameters of the contact law at one pair: the scene's ContactSettings and the pair's
// material (stiffness, friction coefficients, anchor stiffness) with its damping c_n [N s/m]; ContactLawFor gives no damping in statics, and no friction in statics
// under the smooth law.
struct ContactLawParameters {
  double stiffness = 0.0;      // k_n [N/m]
  double onset = 0.0;          // delta [m]
  double damping = 0.0;        // c_n [N s/m]
  double friction = 0.0;       // mu (mu_k of the stick law)
  double slip_velocity = 0.0;  // eps_v [m/s] (smooth law)
  FrictionLaw law = FrictionLaw::kSmooth;
  double static_friction = 0.0;       // mu_s (stick law)
  double tangential_stiffness = 0.0;  // k_t [N/m] (stick law)
  double tangential_damping = 0.0;    // c_t = c_n sqrt(k_t / k_n) [N s/m] (stick law)
};
// The law of a pair with its material (model.h, ContactMaterial, resolved: Model::contact_laws),
// or with the scene's settings alone (every pair of one material).
ContactLawParameters ContactLawFor(const ContactSettings& settings, const ContactMaterial& material,
                                   double damping, bool dynamics);
ContactLawParameters ContactLawFor(const ContactSettings& settings, double damping, bool dynamics);

// The stick law's input at one evaluation (docs/numerics.md, "Stick friction"): the anchor's
// elastic deflection u_e at the last accepted state, the slip since (the displacement of the
// material point then in contact, relative to the other side) and whether the pair slipped then.
struct AnchorTrial {
  Vec3 deflection = Vec3::Zero();  // u_e [m], world
  Vec3 slip = Vec3::Zero();        // d [m], world
  bool slipping = false;
};

// The normal force of the law (docs/numerics.md, "Contact") at gap g closing at rate dg/dt:
// f_n = f_e(g) - c_n w(g) dg/dt with w(g) = min(1, (delta - g) / delta) (the damping grows in
// over the onset), and its derivatives. The pair pushes only while g < delta and f_n > 0.
struct ContactNormal {
  double force = 0.0;         // f_n [N]
  double dforce_dgap = 0.0;   // df_n/dg at fixed dg/dt [N/m]
  double dforce_drate = 0.0;  // df_n/d(dg/dt) = -c_n w(g) [N s/m]
};
ContactNormal ContactNormalLaw(double gap, double gap_rate, const ContactLawParameters& law);

// The whole law at a surface point with normal n (from the obstacle, or side B, to the shape)
// moving at v_c relative to it: the normal force at dg/dt = n . v_c and regularised Coulomb
// friction on the tangential velocity v_t = (I - n n^T) v_c,
//   F = f_n (n - mu u),  u = v_t / sqrt(|v_t|^2 + eps_v^2),
// the force on the shape (on side A). The one definition behind the kernels (ContactKind,
// ShapePairKind) and what the outputs report (CalcContactState, CalcShapePairState).
//
// Under the stick law (law.law == kStick, with `anchor`; none: no friction) the friction is the
// return mapping of an elastic anchor instead: the trial force f* = -k_t P (u_e + d) - c_t P v_c
// (P = I - n n^T) sticks when |f*| <= mu f_n (mu = mu_k if the pair slipped at the last accepted
// state, else mu_s), f_t = f*, and slips otherwise, f_t = mu_k f_n f* / |f*|.
struct ContactForce {
  bool active = false;  // g < delta and f_n > 0
  ContactNormal normal;
  Vec3 force = Vec3::Zero();     // F [N], world
  Vec3 friction = Vec3::Zero();  // f_t [N], world
  // With the tangent: dF = direction df_n - slip_tangent dv_c - anchor_tangent dd. Smooth law:
  // direction = n - mu u, slip_tangent = mu f_n (I / s - v_t v_t^T / s^3) P,
  // s = sqrt(|v_t|^2 + eps_v^2) (zero without friction), anchor_tangent = 0. Stick law, sticking:
  // direction = n, slip_tangent = c_t P, anchor_tangent = k_t P; slipping, with t = f* / |f*|
  // and D = mu_k f_n (I - t t^T) / |f*|: direction = n + mu_k t, slip_tangent = c_t D P,
  // anchor_tangent = k_t D P.
  Vec3 direction = Vec3::Zero();
  Mat3 slip_tangent = Mat3::Zero();
  Mat3 anchor_tangent = Mat3::Zero();
  // Stick law: whether it slips, and the anchor's deflection after the return mapping (the
  // history AcceptContactHistory keeps): the trial deflection P (u_e + d), scaled back onto the
  // cone when slipping.
  bool slipping = false;
  Vec3 deflection = Vec3::Zero();
};
ContactForce ContactForceLaw(double gap, const Vec3& normal, const Vec3& velocity,
                             const ContactLawParameters& law, bool tangent,
                             const AnchorTrial* anchor = nullptr);

// The share of static friction a pair uses, |f_t| / (mu_s f_n) (0 without friction).
double FrictionShare(const ContactForce& force, const ContactLawParameters& law);

// The geometry of a pair at frames H[0], H[1] of its item nodes.
struct ContactGeometry {
  double gap = 0.0;                              // signed distance between the surfaces [m]
  double s = 0.0;                                // closest parameter on the shape's segment
  Vec3 normal = Vec3::UnitZ();                   // world, from the obstacle to the shape
  Vec3 point = Vec3::Zero();                     // the surface point p_s of the shape [m], world
  double weight[2] = {0.0, 0.0};                 // W_k
  Vec3 lever[2] = {Vec3::Zero(), Vec3::Zero()};  // l_k, node-frame components
  // dl_k/d theta_k, the lever's change as node k turns at fixed n and s*: -r Skew(R_k^T n) for
  // a segment (its surface point p - r n); a cylinder's rim point sliding along the rim
  // against a plane (docs/numerics.md, "Cylinders"); zero for a cylinder's point nearest to a
  // sphere or capsule obstacle (frozen, as their n).
  Mat3 lever_rate[2] = {Mat3::Zero(), Mat3::Zero()};
};
// Returns false when the normal is undefined (the shape's axis touches a sphere's centre or a
// capsule's axis).
bool CalcContactGeometry(const Model& model, const ContactPair& pair, const SE3& H_0,
                         const SE3& H_1, ContactGeometry* out);

struct ContactKind {
  static constexpr int kNodes = 2;
  using Item = int;  // index into Model::contact_pairs
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.contact_pairs.size(); ++i) {
      const ContactPair& p = model.contact_pairs[i];
      f(static_cast<int>(i), p.node);
    }
  }
  // Inactive when the gap is at least the onset or the damped force would pull. Residual
  // -W_k [R_k^T F; l_k x R_k^T F], F = f_n n + f_t; stiffness: the exact derivative at frozen
  // n and s* (exact for a plane), damping: the exact derivative in the velocities.
  static bool Calc(const Model& model, const Data& data, const Item& pair,
                   const NodeMotion<2>& motion, const KernelOptions& options,
                   ElementTerms<2>* terms);
  // The penalty potential Psi(g), counted as Energy::spring.
  static void AddEnergy(const Model& model, const Data& data, const Item& pair, Energy* energy);
};

// A pair's state for the outputs (contacts.csv, VTK) in the current state of data.
struct ContactState {
  bool active = false;                 // gap < onset and f_n > 0
  double gap = 0.0;                    // [m]
  Vec3 point = Vec3::Zero();           // surface point of the shape, world [m]
  Vec3 normal = Vec3::UnitZ();         // world, from the obstacle to the shape
  double normal_force = 0.0;           // f_n [N]
  Vec3 friction_force = Vec3::Zero();  // f_t on the shape, world [N]
  // Stick law: slipping or sticking, the anchor's elastic deflection |u_e| [m]; both laws: the
  // share of static friction used, |f_t| / (mu_s f_n).
  bool slipping = false;
  double deflection = 0.0;
  double friction_share = 0.0;
};
// `dynamics`: with damping and the velocities (false: the static law).
ContactState CalcContactState(const Model& model, const Data& data, int pair, bool dynamics = true);

// True when the model has contact: obstacle pairs or contact segments (rod capsules, body
// shapes) that the broad phase may pair.
inline bool HasContact(const Model& model) {
  return !model.contact_pairs.empty() || !model.contact_segments.empty();
}

// What a failed step's message adds when contact may be the cause (empty without contact or
// without an active or near pair at the state in data): the number of contacts active, the
// law's stiffness, onset and friction law with the keys that change them, and, under the smooth
// law with eps_v < h mu g, the slip velocity (docs/numerics.md, "Contact"). Allocates.
std::string ContactFailureHint(const Model& model, const Data& data, double h);

// The stick law's history (Data::contact_anchors): each pair's anchor deflection after the
// return mapping at the current state, and the material point in contact now. Call when a step
// or load step is accepted and at the start of a run (no-op without the stick law's anchors).
// Also saves the reference of the swept check against tunnelling (elements/crossing.h).
void AcceptContactHistory(const Model& model, Data& data, bool dynamics);

// Closest parameters (s, t) of segments P0 + s (P1 - P0) and Q0 + t (Q1 - Q0), clamped to
// [0, 1] (Ericson, Real-Time Collision Detection, 2005, section 5.1.9). Parallel segments take
// the middle of the overlap of their projections (docs/numerics.md, "Contact": the force then
// does not jump between an element's nodes), or the nearest ends when they do not overlap.
// Shared by the obstacle pairs (capsule obstacles) and the pairs of moving shapes.
void ClosestSegmentParameters(const Vec3& P0, const Vec3& P1, const Vec3& Q0, const Vec3& Q1,
                              double* s, double* t);

}  // namespace screwfem
