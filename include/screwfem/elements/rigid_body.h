// The rigid body as an element kind (elements/rigid_body.h): a mass with inertia on one node, its
// weight, inertia and gyroscopic forces. Stateless and fixed-size; the contract is
// elements/element.h.
#pragma once

#include "screwfem/elements/element.h"

namespace screwfem {

// Mass matrix about the node origin, node-frame components (elements/rigid_body.h):
// [m I, -m S(c); m S(c), J_c - m S(c)^2], c the centre of mass.
Mat6 RigidBodyMass(const RigidBody& body);

struct RigidBodyKind {
  static constexpr int kNodes = 1;
  using Item = int;  // index into Model::bodies
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.bodies.size(); ++i) {
      const int nodes[1] = {model.bodies[i].node};
      f(static_cast<int>(i), nodes);
    }
  }
  // Weight (scaled by the load factor); in dynamics M eta_dot - ad(eta)^T M eta with the
  // blocks M and C = -(ad(eta)^T M + Star(M eta)). A body on a fixed node contributes nothing.
  static bool Calc(const Model& model, const Data& data, const Item& body,
                   const NodeMotion<1>& motion, const KernelOptions& options,
                   ElementTerms<1>* terms);
  static void AddEnergy(const Model& model, const Data& data, const Item& body, Energy* energy);
};

}  // namespace screwfem
