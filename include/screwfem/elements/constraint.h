// The constraint-kind contract (docs/architecture.md, "Constraint kinds"), the twin of the
// element-kind contract (element.h).
//
// A constraint kind owns rows of the constraint phi(q, t) = 0, whose multipliers lambda are
// unknowns of the saddle-point system, and possibly unknowns of its own (a joint's
// coordinates). Its traits struct states what the assembly, the integrator, statics and the
// solver ordering need to know:
//
//   struct SomeConstraintKind {
//     using Item = ...;   // what identifies one item (an index)
//     // f(item) for every item of the model that has rows or unknowns of its own.
//     template <class F> static void ForEach(const Model& model, F&& f);
//     // The item's rows: the first (an index into the nc multipliers) and how many (0: none).
//     static int FirstRow(const Model&, const Item&);
//     static int RowCount(const Model&, const Item&);
//     // f(first_unknown, size) for each block of unknowns the item's rows (or forces) act on:
//     // node blocks (6), coordinates. The coupling pattern of the solver is made of these.
//     template <class F> static void ForEachColumn(const Model&, const Item&, F&& f);
//     // false: the item's rows are held (multiplier zero) in this state: a slack tendon.
//     static bool Active(const Model&, const Data&, const Item&);
//     // The residual (s_C phi on its rows, s_R B^T lambda and any force on its own unknowns)
//     // and the iteration-matrix blocks (s_R s_L B^T, s_C B T and tangent terms), written
//     // through the assembly's sink (assemble/assemble.cpp, Scatter).
//     template <class Sink>
//     static void Assemble(const Model&, const Data&, const Item&, const AssemblyOptions&,
//                          Sink&);
//     // The gradient as blocks: f(row, first_unknown, block), block rows x unknowns, joint
//     // coordinates without their tangent operator.
//     template <class F>
//     static void ForEachGradientBlock(const Model&, const Data&, const Item&, F&& f);
//     // The gradient in factored form: out(rows of the item) = B x.
//     static void GradientTimes(const Model&, const Data&, const Item&,
//                               const Eigen::Ref<const Eigen::VectorXd>& x,
//                               Eigen::Ref<Eigen::VectorXd> out);
//     // The explicit time dependence: phi = g(q) - target(t) row by row; f(row, target) for
//     // each rheonomic row (its value, rate and acceleration). Nothing for scleronomic rows.
//     template <class F>
//     static void ForEachTarget(const Model&, const Data&, const Item&, double time, F&& f);
//     // The readout: the generalised force its rows apply along their own direction (the
//     // multipliers as efforts: a drive's force or torque, a tendon's tension).
//     static void Effort(const Model&, const Data&, const Item&, Eigen::Ref<Eigen::VectorXd>);
//     // Optional: the energy it stores (CalcEnergy sums it with the element kinds').
//     static void AddEnergy(const Model&, const Data&, const Item&, Energy*);
//     // Optional: f(profile) for every profile its items evaluate (the run's breakpoints).
//     template <class F> static void ForEachProfile(const Model&, F&& f);
//   };
//
// The constraint kinds are listed in one place (elements/registry.h). The assembly loops over
// them as over the element kinds; the integrator and statics see rows only (the functions of
// assemble/assemble.h: CalcConstraintGradient, CalcConstraintGradientTimes,
// CalcVelocityConstraint, SubtractConstraintAccelerations); the solver ordering links the
// columns of each item (ForEachColumn) with each other and with its rows.
//
// A kind's B^T lambda may be carried by another kernel that already has its direction: a
// length-driven tendon's by its segments (TendonSegmentKind with tau = lambda, which also gives
// its tangent lambda d2L), a prescribed drive's by its joint's coordinate force.
#pragma once

#include <vector>

#include "screwfem/model/data.h"

namespace screwfem {

// What an assembly computes and how it scales (assemble/assemble.h): element kernels read the
// part of it they need (KernelOptions), constraint kinds all of it.
struct AssemblyOptions {
  double time = 0.0;         // profiles are evaluated at this time
  double load_factor = 1.0;  // multiplies every load and prescribed motion (statics)
  bool dynamics = false;     // include inertia and damping forces
  double c_mass = 0.0, c_damping = 0.0, c_stiffness = 1.0;
  double s_rows = 1.0, s_constraints = 1.0, s_multipliers = 1.0;
  bool use_node_tangent = false;
  bool assemble_matrix = true;
  // Statics: adds the derivative of the constraint forces, d(B^T lambda)/dq at fixed lambda
  // (CalcJointConstraintForceTangent), to the matrix: the exact tangent. Its blocks couple a
  // joint's two nodes and its coordinates, outside model.pattern_last: give the pattern that
  // holds them (ConstraintForceTangentPattern) and a matrix sized for it. Not with
  // use_node_tangent.
  bool constraint_force_tangent = false;
  const std::vector<int>* pattern_last = nullptr;  // null: model.pattern_last
  // Stabilised index 2 (docs/numerics.md, "Index 2"): adds s_C times this factor times Z T,
  // the derivative of the velocity constraint B(q) v at the current v
  // (CalcJointVelocityConstraintTangent), to the joints' constraint rows of the matrix, whose
  // right-hand side is then the scaled velocity constraint. 0: not added (index 3, statics).
  double velocity_constraint_tangent = 0.0;
};

// The first unknown of a node (-1: the ground or a fixed node).
inline int NodeDof(const Model& model, int node) {
  return node == kGround ? -1 : model.nodes[static_cast<std::size_t>(node)].dof;
}

}  // namespace screwfem
