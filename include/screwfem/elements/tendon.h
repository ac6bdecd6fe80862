// Tendons and point-to-point force elements (docs/numerics.md, "Tendons and force elements"): forces along the straight
// line between two body points (model.h, BodyPoint), as element kinds (elements/element.h).
//
// Both rest on one piece of geometry, the distance between two body-fixed points and its
// first two derivatives under the right-trivialised increments of the two frames
// (CalcPointDistance). A frictionless tendon with prescribed tension tau is the sum of its
// straight segments: its generalised force tau dL/dq is the sum of tau times each segment's
// length gradient, so each segment couples only its two eyelets' nodes (TendonSegmentKind, one
// 2-node item per node pair) and the tendon needs no coupling beyond consecutive eyelets. A
// force element (ForceElementKind) is one segment with a spring-damper-actuator law.
#pragma once

#include "screwfem/elements/element.h"
#include "screwfem/model/model.h"

namespace screwfem {

// The distance between p_A = x_A + R_A r_A and p_B = x_B + R_B r_B, and its derivatives under
// H_A <- H_A exp(dh_A), H_B <- H_B exp(dh_B) (docs/numerics.md, "Tendons and force elements"), with S(r) = [I  -Skew(r)]:
//   l = |p_B - p_A|,  e = (p_B - p_A) / l (world),  J = [-R_A S(r_A)   R_B S(r_B)] (3 x 12),
//   gradient  dl/d[dh_A; dh_B] = J^T e = [-e_A; -r_A x e_A; e_B; r_B x e_B],  e_X = R_X^T e;
//   hessian   J^T (I - e e^T) J / l + blockdiag(-S(r_A)^T Skew(e_A) [0 I], S(r_B)^T Skew(e_B) [0 I])
// (the first part symmetric, the second from the rotation of e into each node frame). The
// hessian is the derivative of the gradient: d(gradient)/d[dh_A; dh_B], column j for dh_j.
struct PointDistance {
  double length = 0.0;  // l [m]
  Vec3 direction;       // e, world, from A to B
  Vec12 gradient;       // node-frame components, node A then node B
  Mat12 hessian;        // set when asked for
};
// Returns false when the points coincide (l = 0: no direction).
bool CalcPointDistance(const SE3& H_A, const Vec3& r_A, const SE3& H_B, const Vec3& r_B,
                       bool hessian, PointDistance* out);

// The tension of a tendon at `time` [N]: drawn by tension, max(0, load_factor tau(t)) (a
// tendon cannot push); drawn by length, its multiplier data.lambda(row) (the current Newton
// iterate, not clipped; zero while slack, where its row holds it at zero).
double TendonTension(const Tendon& tendon, const Data& data, double time, double load_factor = 1.0);

// A length-driven tendon's prescribed length and its first two time derivatives at `time`
// (docs/numerics.md, "Tendons and force elements"): L_p(t), in statics moved from the reference length by the load
// factor f: L_ref + f (L_p(t) - L_ref).
ProfileValue TendonTargetLength(const Tendon& tendon, const Data& data, double time,
                                double load_factor = 1.0);

// The length L(q) of a tendon in the current state of data [m].
double CalcTendonLength(const Model& model, const Data& data, int tendon);

// The length of one tendon segment and its gradient node by node: parts[i] is
// dl/d[dh of nodes[i]] (node-frame components), i < count; an eyelet on a node gives one part,
// an eyelet between nodes two (its element's nodes A and B: parts N_A^T g, N_B^T g with g the
// gradient on the eyelet's section frame and N the element's interpolation, rod.h CalcRodN).
// Parts on the ground are left out. False when the eyelets coincide (no direction).
struct SegmentGradient {
  double length = 0.0;
  int count = 0;
  int nodes[4];
  Vec6 parts[4];
};
bool CalcSegmentGradient(const Model& model, const Data& data, const TendonSegment& segment,
                         SegmentGradient* out);

// Sets data.tendon_slack for the length-driven tendons from the current state at `time` (the
// active set of the unilateral constraint L(q) <= L_p(t), docs/numerics.md): a taut tendon
// whose multiplier is negative goes slack (its multiplier is set to zero); a slack one becomes
// taut when its length reaches L_p - tolerance. Returns how many tendons changed.
int UpdateTendonSlack(const Model& model, Data& data, double time, double load_factor = 1.0);

// The straight segments of tendons between two nodes (eyelets on nodes): the residual rows
// tau dl/d[dh_A; dh_B] and the stiffness tau d2l of each (docs/numerics.md, "Tendons and force elements"
// prescribed tension); the segments of a tendon add up to tau dL/dq and its exact tangent. One
// item is one Model::tendon_segment_groups entry, the segments of all tendons along the same
// node pair (Build), summed before the node tangents are applied. No energy (the tension may
// vary in time; at constant tension the potential is tau L, and the tests check the forces
// against it).
struct TendonSegmentKind {
  static constexpr int kNodes = 2;
  using Item = int;  // index into Model::tendon_segment_groups
  // The tensions of the tendons drawn by tension (those drawn by length: TendonLengthKind).
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const Tendon& t : model.tendons)
      if (t.drive != TendonDrive::kLength) f(t.tension);
  }
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.tendon_segment_groups.size(); ++i) {
      const TendonSegmentGroup& g = model.tendon_segment_groups[i];
      const int nodes[2] = {g.node_a, g.node_b};
      f(static_cast<int>(i), nodes);
    }
  }
  static bool Calc(const Model& model, const Data& data, const Item& group,
                   const NodeMotion<2>& motion, const KernelOptions& options,
                   ElementTerms<2>* terms);
  static void AddEnergy(const Model&, const Data&, const Item&, Energy*) {}
};

// The distance between two body points either of which may lie between nodes, on the four
// nodes of a TendonSpanSegmentKind item (H: their frames, in its node order: each end's element
// nodes A and B, or its node and the ground): the length l, `scale` times its gradient N^T g_E
// and (hessian != nullptr) `scale` times the derivative of that gradient, the exact hessian
// N^T H_l N + blockdiag(G_E P(d)) of TendonSpanSegmentKind below. One geometry for every item
// on such a line (TendonSpanSegmentKind: scale tau; ForceElementSpanKind, force_span.h: 1).
// False when the points coincide (no direction).
bool CalcSpanDistance(const Data& data, const BodyPoint& a, const BodyPoint& b,
                      const SE3* const (&H)[4], double scale, double* length,
                      Eigen::Matrix<double, 24, 1>* gradient,
                      Eigen::Matrix<double, 24, 24>* hessian);

// A tendon segment with an eyelet between nodes at one end or both (docs/numerics.md, "Eyelets
// between nodes"): the eyelet's section frame is H_E = H_A exp(xi d), d = log(H_A^-1 H_B) of
// its element, and its increment dh_E = N(xi, d) [dh_A; dh_B] (rod.h, CalcRodN). The items
// couple four nodes: each end's element nodes A and B (an end on a node: that node and the
// ground). With g_E = dl/d[dh_E] and H_l the hessian of CalcPointDistance on the two eyelet
// frames, the residual rows are tau N^T g_E and the exact stiffness
//   tau (N^T H_l N + blockdiag(G_E P(d)))   (N = blockdiag(N_1, N_2)),
// G_E = d(N^T F)/dd at F = g_E (rod.h, CalcRodNTransposeDerivative), the variation of the
// interpolation itself.
struct TendonSpanSegmentKind {
  static constexpr int kNodes = 4;
  using Item = int;  // index into Model::tendon_segments
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.tendon_segments.size(); ++i) {
      const TendonSegment& s = model.tendon_segments[i];
      if (s.a.element < 0 && s.b.element < 0) continue;  // TendonSegmentKind's
      int nodes[4];
      SpanNodes(model, s.a, nodes);
      SpanNodes(model, s.b, nodes + 2);
      f(static_cast<int>(i), nodes);
    }
  }
  // The two nodes of an end: its element's nodes, or its node and the ground.
  static void SpanNodes(const Model& model, const BodyPoint& p, int* nodes) {
    nodes[0] = p.node;
    nodes[1] =
        p.element >= 0 ? model.elements[static_cast<std::size_t>(p.element)].node_b : kGround;
  }
  static bool Calc(const Model& model, const Data& data, const Item& segment,
                   const NodeMotion<4>& motion, const KernelOptions& options,
                   ElementTerms<4>* terms);
  static void AddEnergy(const Model&, const Data&, const Item&, Energy*) {}
};

// The force element's law: the tension f = k (l - l_0) + c dl/dt + lambda F(t) [N] at length l
// and rate dl/dt (positive: pulling the points together), with the actuator's value
// lambda F(t) at load factor lambda. The one definition behind the kernel (ForceElementKind)
// and what the outputs report (CalcForceElementState, at the recorded load factor).
struct ForceElementForce {
  double force = 0.0;     // f [N]
  double actuator = 0.0;  // lambda F(t) [N]
};
ForceElementForce ForceElementLaw(const ForceElement& element, const Data& data, double length,
                                  double rate, double time, double load_factor);

// A spring-damper-actuator between two body points: force (ForceElementLaw)
//   f = k (l - l_0) + c dl/dt + F(t)   (positive: tension, pulling the points together),
// residual rows f dl/d[dh_A; dh_B], with dl/dt = gradient^T [eta_A; eta_B]; exact tangents:
//   stiffness k g g^T + f d2l + c g (d2l^T eta)^T   (the last: dl/dt varies with q at fixed eta),
//   damping   c g g^T,
// g the gradient. The spring's energy 1/2 k (l - l_0)^2 counts as Energy::spring.
struct ForceElementKind {
  static constexpr int kNodes = 2;
  using Item = int;  // index into Model::force_elements
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const ForceElement& e : model.force_elements) f(e.actuator);
  }
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.force_elements.size(); ++i) {
      const ForceElement& e = model.force_elements[i];
      if (e.a.element >= 0 || e.b.element >= 0) continue;  // ForceElementSpanKind's
      const int nodes[2] = {e.a.node, e.b.node};
      f(static_cast<int>(i), nodes);
    }
  }
  static bool Calc(const Model& model, const Data& data, const Item& element,
                   const NodeMotion<2>& motion, const KernelOptions& options,
                   ElementTerms<2>* terms);
  static void AddEnergy(const Model& model, const Data& data, const Item& element, Energy* energy);
};

// What the outputs report (io/writers.cpp, tendons.csv and forces.csv), in the current state of
// data at data.time: length [m], its rate [m/s] and the tension or force [N] applied at
// `load_factor` (static analyses: the load step's; dynamics: 1): a tension-driven tendon's
// lambda T(t), a force element's actuator part lambda F(t) (its spring and damper are not
// scaled), as the kernels apply them; a length-driven tendon's multiplier.
struct LineForceState {
  double length = 0.0;
  double rate = 0.0;
  double force = 0.0;
};
LineForceState CalcTendonState(const Model& model, const Data& data, int tendon,
                               double load_factor = 1.0);
LineForceState CalcForceElementState(const Model& model, const Data& data, int element,
                                     double load_factor = 1.0);
// The world position of a body point on a node (or the ground) in the current state.
Vec3 BodyPointPosition(const Data& data, const BodyPoint& point);
// The frame a body point is fixed in, in the current state: its node's, or for a point between
// nodes the section frame H_A exp(xi d) of its element; and the point's world position.
SE3 BodyPointFrame(const Model& model, const Data& data, const BodyPoint& point);
Vec3 BodyPointPosition(const Model& model, const Data& data, const BodyPoint& point);

}  // namespace screwfem
