// The element-kind contract (docs/architecture.md, "Element kinds").
//
// An element kind is a stateless kernel over items of the Model (a rod element, a rigid body, a
// load on a node, ...). Its traits struct states what the assembly needs to know and nothing
// else:
//
//   struct SomeKind {
//     static constexpr int kNodes = N;   // the nodes one item couples (fixed per kind)
//     using Item = ...;                  // what identifies one item (an index, or indices)
//     // f(item, nodes) for every item that contributes, nodes[i] a node index (or kGround).
//     template <class F> static void ForEach(const Model& model, F&& f);
//     // The item's part of the node rows of the residual and its iteration-matrix blocks, at
//     // the nodes' current frames and motion. Returns false when the item cannot be evaluated
//     // (terms->failure says why); the assembly then stops.
//     static bool Calc(const Model&, const Data&, const Item&, const NodeMotion<N>&,
//                      const KernelOptions&, ElementTerms<N>*);
//     // Adds the item's energies (and the momentum of its mass, Energy::momentum).
//     static void AddEnergy(const Model&, const Data&, const Item&, Energy*);
//   };
//
// Two optional traits: `static constexpr bool kItemsInData = true;` for a kind whose items are
// found during the run (the contact broad phase's pairs): the assembly then calls
// `ForEach(model, data, f)` instead; `static constexpr bool kOffBandBlocks = true;` for a kind
// whose node blocks may lie outside the model's band pattern: they go to Data::coupling (a
// low-rank update of the banded solve) instead of failing the pattern check. And an optional
// `template <class F> static void ForEachProfile(const Model&, F&& f)` calls f(profile) for
// every profile its items evaluate: the steps of a run end on their breakpoints.
//
// `static constexpr bool kParallel = true;` (two nodes, an int item 0 .. ItemCount(model) - 1
// in ForEach's order, `static int ItemCount(const Model&)` and `static void ItemNodes(const
// Model&, int item, int (&nodes)[2])`) lets the assembly run the kind's Calc on several
// threads at once (SetAssemblyThreads): Calc must then only read the Model and the Data (no
// static state). The rod element has it.
//
// The assembly (assemble/assemble.cpp) loops over the registered kinds, gathers the node
// motion, calls Calc and scatters ElementTerms into the global residual and the banded
// iteration matrix; CalcEnergy sums AddEnergy. A kind never touches global arrays.
#pragma once

#include "screwfem/model/data.h"

namespace screwfem {

// What the assembly asks of a kernel.
struct KernelOptions {
  double time = 0.0;         // profiles are evaluated at this time
  double load_factor = 1.0;  // multiplies every load (statics)
  bool dynamics = false;     // inertia and damping forces
  bool tangent = true;       // iteration-matrix terms
  // Coefficients of the iteration matrix S = c_K K T + c_M M + c_C C (assemble.h).
  double c_mass = 0.0, c_damping = 0.0, c_stiffness = 1.0;
  bool node_tangent = false;  // K is right-multiplied by the node tangent operators T
};

// The state of an item's nodes, gathered by the assembly: frames (the identity for the
// ground), node tangent operators (identity unless KernelOptions::node_tangent) and, in
// dynamics, body velocities and accelerations stacked node by node (zero for fixed nodes).
template <int N>
struct NodeMotion {
  const SE3* H[N];
  const Mat6* T[N];
  Eigen::Matrix<double, 6 * N, 1> eta, eta_dot;
};

// An item's contribution, in node-frame components, node by node (6 rows each).
template <int N>
struct ElementTerms {
  using Vector = Eigen::Matrix<double, 6 * N, 1>;
  using Matrix = Eigen::Matrix<double, 6 * N, 6 * N>;
  // false: the item contributes nothing at this state (a load whose profile is zero, a body
  // on a fixed node); nothing below is set.
  bool active = true;
  // The node rows of the residual: inertia + internal - applied forces.
  Vector residual;
  // The iteration-matrix blocks, in one of two forms:
  //  * combined: `matrix` = c_K K T + c_M M + c_C C, formed by the kernel;
  //  * separate: `stiffness` K (already times T when stiffness_has_node_tangent), `mass` M,
  //    `damping` C, each present when its flag is set; the assembly combines them.
  bool combined = false;
  Matrix matrix;
  bool has_stiffness = false, has_mass = false, has_damping = false;
  bool stiffness_has_node_tangent = false;
  Matrix stiffness, mass, damping;
  // The scale of the convergence test: the largest force term (beyond |residual|, which the
  // assembly measures itself) and the largest term cancelling inside a residual entry (its
  // round-off floor).
  double force_scale = 0.0;
  double term_scale = 0.0;
  // Calc returned false: the value that is out of range (a rod element's rotation [rad]).
  double failure = 0.0;
};

// Energies of a state [J].
struct Energy {
  double kinetic = 0.0;  // rigid bodies and rods (consistent with the model's rod inertia)
  double strain = 0.0;   // rods
  double spring = 0.0;   // joint springs (towards their rest, incl. series-elastic drives)
  double gravity = 0.0;  // potential of gravity, zero at the world origin
  double total() const { return kinetic + strain + spring + gravity; }
  // Not an energy, summed in the same pass over the items (the kinetic energy's velocities
  // serve both): linear momentum [kg m/s] and angular momentum about the world origin
  // [kg m^2/s], world components (outputs.h, CalcMomentum).
  Vec6 momentum = Vec6::Zero();
  // Adds the momentum h = [p; L] of a frame H (body components, about the frame's origin).
  void AddMomentum(const SE3& H, const Vec6& h) {
    const Vec3 p = H.R * h.head<3>();
    momentum.head<3>() += p;
    momentum.tail<3>() += H.R * h.tail<3>() + H.x.cross(p);
  }
};

}  // namespace screwfem
