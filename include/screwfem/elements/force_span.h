// A force element with an end between rod nodes (docs/architecture.md, "Recipe: add an element
// kind"): the spring-damper-actuator of ForceElementKind (tendon.h) between two body points of
// which one or both lie on the section of a rod element at xi in (0, 1) (BodyPoint::element,
// placed by Build at an arc length), as a tendon eyelet between nodes does.
//
// The geometry is TendonSpanSegmentKind's (tendon.h, CalcSpanDistance): an end's section frame
// is H_E = H_A exp(xi d), d = log(H_A^-1 H_B) of its element, its increment dh_E = N(xi, d)
// [dh_A; dh_B] (rod.h, CalcRodN); an end on a node has N = [I 0] and the ground as its second
// node. With g = dl/d[dh of the four nodes] = N^T g_E and K_l = N^T H_l N + blockdiag(G_E P(d))
// the exact derivative of g (G_E the variation of the interpolation, rod.h
// CalcRodNTransposeDerivative), and the force f = k (l - l_0) + c dl/dt + F(t) of
// ForceElementLaw at the rate dl/dt = g^T eta:
//   residual  f g,
//   stiffness k g g^T + f K_l + c g (K_l^T eta)^T   (the last: dl/dt varies with q at fixed
//                                                    eta, exact, as ForceElementKind has it),
//   damping   c g g^T,
//   energy    1/2 k (l - l_0)^2 (Energy::spring).
#pragma once

#include "screwfem/elements/element.h"
#include "screwfem/elements/tendon.h"

namespace screwfem {

struct ForceElementSpanKind {
  static constexpr int kNodes = 4;
  using Item = int;  // index into Model::force_elements
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t i = 0; i < model.force_elements.size(); ++i) {
      const ForceElement& e = model.force_elements[i];
      if (e.a.element < 0 && e.b.element < 0) continue;  // ForceElementKind's
      int nodes[4];
      TendonSpanSegmentKind::SpanNodes(model, e.a, nodes);
      TendonSpanSegmentKind::SpanNodes(model, e.b, nodes + 2);
      f(static_cast<int>(i), nodes);
    }
  }
  static bool Calc(const Model& model, const Data& data, const Item& element,
                   const NodeMotion<4>& motion, const KernelOptions& options,
                   ElementTerms<4>* terms);
  static void AddEnergy(const Model& model, const Data& data, const Item& element, Energy* energy);
};

}  // namespace screwfem
