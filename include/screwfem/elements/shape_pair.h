// Frictional contact between two moving shapes, as an element kind (method-next.md §N6.2-N6.3;
// docs/numerics.md, "Contact between moving shapes").
//
// Each item is a ShapePair (model.h) enumerated by ModelBuilder::Build: rigid-rigid between
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

#include "screwfem/elements/element.h"
#include "screwfem/model/model.h"

namespace screwfem {

// The geometry of a pair at the frames H[0..3] of its item nodes.
struct ShapePairGeometry {
  double gap = 0.0;             // signed distance between the surfaces [m]
  double s[2] = {0.0, 0.0};     // closest parameters on the two segments
  Vec3 normal = Vec3::UnitZ();  // world, from B to A
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
bool CalcShapePairTerms(const Model& model, const ShapePair& pair, const ShapePairGeometry& G,
                        const NodeMotion<4>& x, const KernelOptions& options,
                        ElementTerms<4>* terms);

struct ShapePairKind {
  static constexpr int kNodes = 4;
  using Item = int;  // index into Model::shape_pairs
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.shape_pairs.size(); ++i) {
      const ShapePair& p = model.shape_pairs[i];
      const int nodes[4] = {p.side[0].node[0], p.side[0].node[1], p.side[1].node[0],
                            p.side[1].node[1]};
      f(static_cast<int>(i), nodes);
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

// A pair's state for the outputs (contacts.csv, VTK) in the current state of data; the
// forces act on side A (side B carries their opposite).
struct ShapePairState {
  bool active = false;
  double gap = 0.0;
  Vec3 point[2] = {Vec3::Zero(), Vec3::Zero()};
  Vec3 normal = Vec3::UnitZ();
  double normal_force = 0.0;
  Vec3 friction_force = Vec3::Zero();
};
ShapePairState CalcShapePairState(const Model& model, const Data& data, int pair);

}  // namespace screwfem
