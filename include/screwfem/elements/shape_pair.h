// Frictional contact between two moving shapes, as an element kind (docs/numerics.md, "Contact";
// docs/numerics.md, "Contact between moving shapes").
//
// Each item is a ShapePair (model.h) found by the broad phase (UpdateShapePairs, below, at every
// assembly, into Data::shape_pairs) among the Model's contact segments: rigid-rigid between
// primitives of different bodies (sphere, capsule, box; box-box as the 12 edges of each box
// against the other), rod-rigid (a rod element's chord capsule against a body's sphere,
// capsule or box), rod-rod and rod self-contact. Each side is a segment of body points
// inflated by a radius; side A uses item nodes 0 and 1, side B nodes 2 and 3. The closest
// parameters (s, t) of the two segments (clamped; the middle of the overlap for parallel
// segments; for a segment or sphere against a box side B the point of the segment nearest to
// the box or deepest in it, by an exact 1-D minimisation of the box's signed distance, with
// the closest point of the box, or the exit through the nearest face when that point is
// inside; a segment of positive length against a box is two items, ShapePair::part 0 and 1,
// the two ends of the segment clipped to the prism over the box face, so that a segment lying
// on a face is carried at two points) and the normal n from B to A are found at every
// evaluation and frozen in the tangent (envelope theorem for the gap gradient), as in
// ContactKind. The force F = f_n n + f_t acts on
// A at its surface point p_A - r_A n and -F on B at p_B + r_B n; friction and damping use the
// RELATIVE velocity of the two surface points. Same law as ContactKind (C1 penalty, damping
// -c_n w(g) dg/dt, regularised Coulomb friction applied implicitly; statics frictionless).
#pragma once

#include <vector>

#include "screwfem/elements/element.h"
#include "screwfem/model/model.h"

namespace screwfem {

// The geometry of a pair at the frames H[0..3] of its item nodes.
struct ShapePairGeometry {
  double gap = 0.0;                              // signed distance between the surfaces [m]
  double s[2] = {0.0, 0.0};                      // closest parameters on the two segments
  Vec3 normal = Vec3::UnitZ();                   // world, from B to A
  Vec3 point[2] = {Vec3::Zero(), Vec3::Zero()};  // surface points of A and B [m], world
  double weight[4] = {0.0, 0.0, 0.0, 0.0};       // W_k of item node k (on its side)
  Vec3 lever[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};  // node frame
  Vec3 box_point = Vec3::Zero();  // a box side B: the closest point of the box, node frame
  // (s[0] is then the parameter of side A's nearest or deepest point, or, for a pair with
  // ShapePair::part >= 0, of that end of side A clipped to the face; s[1] = 0)
};
// Returns false when the pair is certainly apart (bounding spheres of the two capsules further
// than `reject` apart: the cheap test before the closest points), the normal is undefined
// (the two axes meet), or it is part 1 of a segment that misses the prism over the box face.
bool CalcShapePairGeometry(const ShapePair& pair, const SE3* const (&H)[4], double reject,
                           ShapePairGeometry* out);
// The geometry the tangent linearises: s and n frozen at `frozen`, the gap n . (p_A - p_B) -
// r_A - r_B and the levers re-evaluated at H (tests compare the tangent with its differences).
void FreezeShapePairGeometry(const ShapePair& pair, const SE3* const (&H)[4],
                             const ShapePairGeometry& frozen, ShapePairGeometry* out);

// The terms of a pair at a given geometry (the kernel after the narrow phase).
// `anchor`: the pair's stick-law history (FindShapePairAnchor), if any; `stick`: the stick law
// is kept for this model (Data::shape_pair_anchors non-empty): then a pair without history has
// an anchor at its current material points.
bool CalcShapePairTerms(const Model& model, const ShapePair& pair, const ShapePairGeometry& G,
                        const NodeMotion<4>& x, const KernelOptions& options,
                        ElementTerms<4>* terms, const ShapePairAnchor* anchor = nullptr,
                        bool stick = false);

// Corner k (0..7) of a box with centre c and half sizes h: bit 0, 1, 2 of k select +h_x, +h_y,
// +h_z (else -h); corners k and k | bit (bit not in k) end an edge.
inline Vec3 BoxCorner(const Vec3& c, const Vec3& h, int k) {
  return c + Vec3((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(), (k & 4) ? h.z() : -h.z());
}

// The broad phase: finds the pairs of Model::contact_segments whose boxes, inflated by their
// radii and half the onset, overlap, and that may touch (Model::contact_entity_pairs, self
// skip), and writes their ShapePair items into data.shape_pairs (a box is side B; a segment of
// positive length against a box is two items, parts 0 and 1; two boxes are the 12 edges of
// each against the other). Every pair whose surfaces are nearer than the onset is found. A
// uniform grid of chunks (runs of rod elements about a diameter long, or one body shape;
// ShapePairGrid), cells of the largest rod chunk's box, hashed into buckets by a counting sort:
// time linear in the segments for shapes of bounded density; a chunk larger than a cell (a
// body's shape) is tested against every chunk. Allocates nothing unless the pool (sized by
// MakeData) is full: then it is doubled (GrowShapePairPool) and the search repeated, a
// geometric growth that ends once the pool holds what the run needs. Called by Assemble and
// InterpolateStep; call it before reading data.shape_pairs of a state set otherwise.
void UpdateShapePairs(const Model& model, Data& data);
// Every pair of shapes that may touch, wherever they are: O(n^2) in the segments (the broad
// phase's reference in tests; allocates).
std::vector<ShapePair> AllShapePairs(const Model& model);

// A pair's name that stays the same while the broad phase reorders the pairs: its two contact
// segments a (side A) and b as a x num_segments + b (two boxes' edges: the boxes).
inline double ShapePairKey(const Model& model, const ShapePair& pair) {
  return static_cast<double>(pair.segment[0]) * static_cast<double>(model.contact_segments.size()) +
         static_cast<double>(pair.segment[1]);
}

// The name of a pair in the stick law's history (Data::shape_pair_anchors): its key, box edge
// and part, unique among the pairs of one broad phase.
inline double ShapePairAnchorKey(const Model& model, const ShapePair& pair) {
  return (ShapePairKey(model, pair) * 25.0 + static_cast<double>(pair.edge + 1)) * 3.0 +
         static_cast<double>(pair.part + 1);
}
// The pair's history, or nullptr (none kept, or the pair was not near at the last acceptance).
const ShapePairAnchor* FindShapePairAnchor(const Model& model, const Data& data,
                                           const ShapePair& pair);

struct ShapePairKind {
  static constexpr int kNodes = 4;
  using Item = int;  // index into data.shape_pairs
  // The items are the pairs the broad phase found (Data), not fixed in the Model: the assembly
  // calls this form of ForEach (elements/element.h).
  static constexpr bool kItemsInData = true;
  // Its node blocks between two entities that the band does not link go to Data::coupling.
  static constexpr bool kOffBandBlocks = true;
  template <class F>
  static void ForEach(const Model&, const Data& data, F&& f) {
    for (int i = 0; i < data.num_shape_pairs; ++i) {
      const ShapePair& p = data.shape_pairs[static_cast<std::size_t>(i)];
      const int nodes[4] = {p.side[0].node[0], p.side[0].node[1], p.side[1].node[0],
                            p.side[1].node[1]};
      f(i, nodes);
    }
  }
  // Inactive when apart (gap >= onset) or the damped force would pull. Residual -J^T F with
  // J = [W_k sign_k R_k [I  -Skew(l_k)]] the map from the nodes' velocities to the relative
  // velocity of the surface points; stiffness: exact at frozen n and s (FreezeShapePairGeometry);
  // damping: exact in the velocities.
  static bool Calc(const Model& model, const Data& data, const Item& pair,
                   const NodeMotion<4>& motion, const KernelOptions& options,
                   ElementTerms<4>* terms);
  // The penalty potential Psi(g), counted as Energy::spring.
  static void AddEnergy(const Model& model, const Data& data, const Item& pair, Energy* energy);
};

// A pair's state for the outputs (pair_contacts.csv, VTK) in the current state of data (pair:
// index into data.shape_pairs); the forces act on side A (side B carries their opposite).
struct ShapePairState {
  bool active = false;
  double gap = 0.0;
  Vec3 point[2] = {Vec3::Zero(), Vec3::Zero()};
  Vec3 normal = Vec3::UnitZ();
  double normal_force = 0.0;
  Vec3 friction_force = Vec3::Zero();
  bool slipping = false;        // stick law
  double deflection = 0.0;      // the anchor's elastic deflection [m] (stick law)
  double friction_share = 0.0;  // |f_t| / (mu_s f_n)
};
ShapePairState CalcShapePairState(const Model& model, const Data& data, int pair,
                                  bool dynamics = true);
// The stick law's history of the pairs of moving shapes (Data::shape_pair_anchors), as
// AcceptContactHistory (elements/contact.h) for the obstacle pairs: runs the broad phase at the
// current state and keeps each near pair's anchor; allocates nothing unless the pool grows.
void AcceptShapePairHistory(const Model& model, Data& data, bool dynamics);

}  // namespace screwfem
