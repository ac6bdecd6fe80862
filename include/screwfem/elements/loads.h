// Applied loads as element kinds: forces and moments at a point of a node frame, and loads on
// rods (distributed over a rod or concentrated on one section), each scaled by its profile and
// the load factor. Stateless and fixed-size; the contract is elements/element.h.
#pragma once

#include "screwfem/elements/element.h"

namespace screwfem {

// A world (dead) force F with node-frame components f at the node-frame point p: adds the
// generalised force [f; p x f] to *g and the tangent of -g to *K (elements/rigid_body.h).
void AddDeadForce(const Vec3& f, const Vec3& p, Vec6* g, Mat6* K);

struct PointLoadKind {
  static constexpr int kNodes = 1;
  using Item = int;  // index into Model::point_loads
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const PointLoad& l : model.point_loads) f(l.profile);
  }
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.point_loads.size(); ++i) {
      const int nodes[1] = {model.point_loads[i].node};
      f(static_cast<int>(i), nodes);
    }
  }
  // Dead loads (LoadFrame::kWorld) have a configuration tangent, follower loads
  // (LoadFrame::kBody) none. Nothing at a fixed node or at a zero profile value.
  static bool Calc(const Model& model, const Data& data, const Item& load,
                   const NodeMotion<1>& motion, const KernelOptions& options,
                   ElementTerms<1>* terms);
  // Loads are not conservative in general: no energy.
  static void AddEnergy(const Model&, const Data&, const Item&, Energy*) {}
};

// One element of a rod load: the load's part on that element, consistent with the exact
// interpolation (AddRodSectionLoad, elements/rod.h): 3-point Gauss over the element for a
// distributed load, the section at xi for a concentrated one.
struct RodLoadKind {
  static constexpr int kNodes = 2;
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const RodLoad& l : model.rod_loads) f(l.profile);
  }
  struct Item {
    int load = -1;     // index into Model::rod_loads
    int element = -1;  // global element index
  };
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.rod_loads.size(); ++i) {
      const RodLoad& l = model.rod_loads[i];
      const Rod& rod = model.rods[static_cast<std::size_t>(l.rod)];
      const int first = l.distributed ? rod.first_element : l.element;
      const int last = l.distributed ? rod.first_element + rod.num_elements - 1 : l.element;
      for (int e = first; e <= last; ++e) {
        const RodElement& el = model.elements[static_cast<std::size_t>(e)];
        const int nodes[2] = {el.node_a, el.node_b};
        f(Item{static_cast<int>(i), e}, nodes);
      }
    }
  }
  static bool Calc(const Model& model, const Data& data, const Item& item,
                   const NodeMotion<2>& motion, const KernelOptions& options,
                   ElementTerms<2>* terms);
  static void AddEnergy(const Model&, const Data&, const Item&, Energy*) {}
};

}  // namespace screwfem
