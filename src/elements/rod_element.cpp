// The helical rod element as an element kind: the element-level combination of the rod
// kernels (rod.cpp, rod_inertia.cpp) that the assembly calls for each element.
#include <algorithm>

#include "screwfem/elements/rod.h"

namespace screwfem {

namespace {
const Mat12 kZero12 = Mat12::Zero();
}  // namespace

// One function (81 lines): the flags decided at the top choose between the combined exact-inertia
// matrix and the separate K, M, C blocks, and split steps would pass them all back and forth.
bool RodElementKind::Calc(const Model& m, const Data& d, const Item& e, const NodeMotion<2>& x,
                          const KernelOptions& o, ElementTerms<2>* t) {
  const RodElement& el = m.elements[static_cast<std::size_t>(e)];
  const Section& sec = m.rods[static_cast<std::size_t>(el.rod)].section;
  const SE3& HA = *x.H[0];
  const SE3& HB = *x.H[1];
  const bool tangent = o.tangent;
  const double rhoA = sec.inertia(0);
  const bool has_gravity = rhoA > 0.0 && m.gravity.squaredNorm() > 0.0;
  // Inertia (option A or B, docs/numerics.md, "Rod inertia") and damping: forces and the M, C blocks.
  const bool has_inertia = o.dynamics && sec.inertia.squaredNorm() > 0.0;
  const bool has_damping =
      o.dynamics && (sec.damping.squaredNorm() > 0.0 || sec.rayleigh_stiffness > 0.0 ||
                     (has_inertia && sec.rayleigh_mass > 0.0));
  // Mass-proportional damping needs M_e in the residual as well.
  const bool inertia_tangent = tangent || (has_damping && sec.rayleigh_mass > 0.0);
  const bool exact_inertia = has_inertia && m.rod_inertia == RodInertia::kExact;
  // The kernels share d, T^-1(d), P(d) and the Gauss-point operators (RodGeometry).
  RodGeometry geo;
  CalcRodGeometry(HA, HB, d.w_ref[static_cast<std::size_t>(e)], exact_inertia,
                  inertia_tangent && exact_inertia, &geo);
  // Internal forces and weight, with the stiffness already right-multiplied by the node
  // tangent operators when the iteration uses them.
  const bool node_tangent = tangent && o.node_tangent;
  Vec12& r = t->residual;
  Mat12& stiffness = t->stiffness;
  // Actuation (docs/numerics.md, "Active stress and rest strain"): sigma = K (eps - eps0) - sigma_a in the same kernel.
  RodActuation act;
  const bool actuated = CalcRodActuation(m, d, e, o.time, o.load_factor, &act);
  CalcRodConservative(el, sec, geo, HA,
                      has_gravity ? Vec3(o.load_factor * rhoA * m.gravity) : Vec3::Zero(),
                      node_tangent ? x.T[0] : nullptr, node_tangent ? x.T[1] : nullptr, &r,
                      tangent ? &stiffness : nullptr, actuated ? &act : nullptr);
  const double rotation = geo.d.tail<3>().norm();
  if (!(rotation < m.max_element_rotation) || !r.allFinite()) {
    t->failure = rotation;
    return false;
  }
  // Round-off in sigma = K (d - d0) / L: the translation of d comes from R_A^T (x_B - x_A),
  // whose absolute error is ~eps max(|x_A|, |x_B|) however short the element is.
  Vec6 magnitude = geo.d.cwiseAbs() + el.d0.cwiseAbs();
  magnitude.head<3>().array() += std::max(HA.x.norm(), HB.x.norm());
  t->term_scale = (sec.stiffness.cwiseProduct(magnitude) / el.length).maxCoeff();
  if (actuated) {
    // The actuation is a force term of its own (balanced by the element's elastic stress),
    // like a load: K eps0 + sigma_a sets the scale of the convergence test.
    const double a =
        (sec.stiffness.cwiseProduct(act.rest_strain) + act.active_stress).cwiseAbs().maxCoeff();
    t->force_scale = a;
    t->term_scale = std::max(t->term_scale, a);
  }
  // Option A without mass-proportional damping: the force alone for a residual, or with
  // c_M M_e + c_C C_t formed by the kernel (one set of Gauss-point products), the element
  // matrix scattered as one.
  if (exact_inertia && !(has_damping && sec.rayleigh_mass > 0.0)) {
    Vec12 force;
    if (tangent)
      CalcRodInertiaExactMatrix(el, sec, geo, x.eta, x.eta_dot, o.c_mass, o.c_damping, &force,
                                &t->matrix);
    else
      CalcRodInertiaExactForce(el, sec, geo, x.eta, x.eta_dot, &force);
    r += force;
    Mat12 damping;
    if (has_damping) {
      if (tangent) damping.setZero();
      AddRodDamping(el, sec, geo.P, x.eta, kZero12, &r, tangent ? &damping : nullptr);
    }
    if (tangent) {
      t->matrix.noalias() += o.c_stiffness * stiffness;
      if (has_damping) t->matrix.noalias() += o.c_damping * damping;
      t->combined = true;
    }
    return true;
  }
  t->has_stiffness = tangent;
  t->stiffness_has_node_tangent = true;
  if (!has_inertia && !has_damping) return true;
  RodInertiaTerms ine;
  if (has_inertia) {
    CalcRodInertia(m.rod_inertia, el, sec, geo, x.eta, x.eta_dot, inertia_tangent, &ine);
    r += ine.force;
  }
  if (has_damping)
    AddRodDamping(el, sec, geo.P, x.eta, ine.mass, &r, tangent ? &ine.gyroscopic : nullptr);
  if (tangent) {
    t->has_mass = has_inertia;
    if (has_inertia) t->mass = ine.mass;
    t->has_damping = true;
    t->damping = ine.gyroscopic;
  }
  return true;
}

double ActuatorValue(const Actuator& a, double time, const Data& data) {
  const double v = EvalProfile(a.profile, time, data).value;
  return a.type == ActuatorType::kMuscle ? std::clamp(v, 0.0, 1.0) : v;
}

bool CalcRodActuation(const Model& m, const Data& d, int element, double time, double load_factor,
                      RodActuation* out) {
  out->rest_strain.setZero();
  out->active_stress.setZero();
  const RodElement& el = m.elements[static_cast<std::size_t>(element)];
  if (el.num_actuators == 0) return false;
  for (int i = 0; i < el.num_actuators; ++i) {
    const Actuator& a = m.actuators[static_cast<std::size_t>(
        m.element_actuators[static_cast<std::size_t>(el.first_actuator + i)])];
    const double v = load_factor * ActuatorValue(a, time, d);
    out->rest_strain += v * a.rest_strain_unit;
    out->active_stress += v * a.active_stress_unit;
  }
  return true;
}

void RodElementKind::AddEnergy(const Model& m, const Data& d, const Item& e, Energy* E) {
  const RodElement& el = m.elements[static_cast<std::size_t>(e)];
  const Section& sec = m.rods[static_cast<std::size_t>(el.rod)].section;
  const SE3& HA = d.H[static_cast<std::size_t>(el.node_a)];
  const SE3& HB = d.H[static_cast<std::size_t>(el.node_b)];
  const Vec6 rel = CalcRodRelativeMotion(HA, HB, d.w_ref[static_cast<std::size_t>(e)]);
  // The law's energy (CalcRodLaw), the actuation at data.time.
  RodActuation act;
  CalcRodActuation(m, d, e, d.time, 1.0, &act);
  RodLaw law;
  CalcRodLaw(el, sec, rel, &act, true, &law);
  E->strain += law.energy;
  const int nodes[2] = {el.node_a, el.node_b};
  Vec12 eta_ab;
  GatherNodeMotion<2>(m, d, nodes, &eta_ab, nullptr);
  // Gravity and momentum at the Gauss points' sections H_A exp(xi d), with the exact velocity
  // field (whatever the inertia option: the momentum of the helical interpolation).
  Vec6 eta[kRodGaussPoints];
  SE3 G[kRodGaussPoints];
  CalcRodGaussVelocities(rel, eta_ab, eta, &G);
  // 1/2 eta_AB^T M_e eta_AB of the model's inertia option (M_e(d) for option A: from the Gauss
  // points' velocities above).
  E->kinetic += m.rod_inertia == RodInertia::kConstant
                    ? CalcRodKineticEnergy(m.rod_inertia, el, sec, rel, eta_ab)
                    : CalcRodKineticEnergyExact(el, sec, eta);
  for (int i = 0; i < kRodGaussPoints; ++i) {
    const SE3 Hg = HA * G[i];
    const double w = el.length * kRodGaussW[i];
    E->gravity -= w * sec.inertia(0) * m.gravity.dot(Hg.x);
    E->AddMomentum(Hg, w * sec.inertia.cwiseProduct(eta[i]));
  }
}

}  // namespace screwfem
