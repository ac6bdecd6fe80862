#include "screwfem/elements/force_span.h"

#include <algorithm>
#include <cmath>

namespace screwfem {

bool ForceElementSpanKind::Calc(const Model& model, const Data& data, const Item& element,
                                const NodeMotion<4>& x, const KernelOptions& o,
                                ElementTerms<4>* t) {
  const ForceElement& fe = model.force_elements[static_cast<std::size_t>(element)];
  using Vector = ElementTerms<4>::Vector;
  using Matrix = ElementTerms<4>::Matrix;
  double length;
  Vector g;
  Matrix K_l;  // the length's hessian
  if (!CalcSpanDistance(data, fe.a, fe.b, x.H, 1.0, &length, &g, o.tangent ? &K_l : nullptr)) {
    t->active = false;  // coinciding ends: no direction, no force
    return true;
  }
  const bool damped = o.dynamics && fe.damping != 0.0;
  const double rate = damped ? g.dot(x.eta) : 0.0;
  const ForceElementForce law = ForceElementLaw(fe, data, length, rate, o.time, o.load_factor);
  const double f = law.force;
  t->residual.noalias() = f * g;
  const double arm = std::max({1.0, fe.a.offset.norm(), fe.b.offset.norm()});
  t->force_scale = std::abs(f) * arm;
  t->term_scale = (fe.stiffness * std::max(length, fe.rest_length) + std::abs(law.actuator)) * arm;
  if (!o.tangent) return true;
  Matrix& K = t->stiffness;
  K.noalias() = fe.stiffness * g * g.transpose();
  K.noalias() += f * K_l;
  t->has_stiffness = true;
  if (damped) {
    // d(dl/dt)/dq at fixed eta = (K_l^T eta)^T (a lazy product: Eigen's row-major GEMV here
    // draws a false -Waggressive-loop-optimizations from GCC, an error with -Werror).
    const Vector rate_q = K_l.transpose().lazyProduct(x.eta);
    K.noalias() += fe.damping * g * rate_q.transpose();
    t->damping.noalias() = fe.damping * g * g.transpose();
    t->has_damping = true;
  }
  return true;
}

void ForceElementSpanKind::AddEnergy(const Model& model, const Data& data, const Item& element,
                                     Energy* E) {
  const ForceElement& fe = model.force_elements[static_cast<std::size_t>(element)];
  const double l =
      (BodyPointPosition(model, data, fe.b) - BodyPointPosition(model, data, fe.a)).norm();
  E->spring += 0.5 * fe.stiffness * (l - fe.rest_length) * (l - fe.rest_length);
}

}  // namespace screwfem
