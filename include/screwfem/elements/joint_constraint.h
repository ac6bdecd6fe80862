// Joints and prescribed drives as constraint kinds (elements/constraint.h).
//
// JointConstraintKind: a joint's six relative-frame rows phi = log(C_B^-1 H_B^-1 H_A C_A H_J)
// (joint.h, CalcJointGradient) with their gradient over node A, node B and the joint's
// coordinates, and the forces of the joint's springs, dampers and drives on its coordinates
// (CalcJointCoordinateTerms): the joint owns its coordinates. Free joints have neither rows
// nor coordinates (their springs are JointSpringKind, an element kind).
//
// DriveConstraintKind: a prescribed drive's row alpha_c - f q(t) on one coordinate (f the load
// factor), gradient 1 on that coordinate. Its force B^T lambda is carried by the joint's
// coordinate force (CalcJointCoordinateTerms adds lambda to the driven coordinate).
#pragma once

#include <cmath>

#include "screwfem/elements/constraint.h"
#include "screwfem/elements/joint.h"

namespace screwfem {

struct JointConstraintKind {
  using Item = int;  // joint index

  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
      const Joint& j = model.joints[jj];
      if (j.row >= 0 || j.k() > 0) f(static_cast<int>(jj));
    }
  }
  static int FirstRow(const Model& m, const Item& ji) { return Get(m, ji).row; }
  static int RowCount(const Model& m, const Item& ji) { return Get(m, ji).row >= 0 ? 6 : 0; }
  template <class F>
  static void ForEachColumn(const Model& m, const Item& ji, F&& f) {
    const Joint& j = Get(m, ji);
    if (j.row < 0) return;
    for (const int node : {j.node_a, j.node_b})
      if (NodeDof(m, node) >= 0) f(NodeDof(m, node), 6);
    if (j.k() > 0) f(j.coord, j.k());
  }
  static bool Active(const Model&, const Data&, const Item&) { return true; }
  // The profiles of its force and series-elastic drives (prescribed ones: DriveConstraintKind).
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const Joint& j : model.joints)
      if (j.drive == DriveKind::kForce || j.drive == DriveKind::kSeriesElastic) f(j.drive_profile);
  }

  // The constraint rows and their gradient (B^T lambda in the residual as transposed products
  // applied to the vector, the same with and without the matrix; the matrix the blocks
  // themselves), the tangent terms that options ask for, and the coordinates' forces.
  template <class Sink>
  static void Assemble(const Model& m, const Data& d, const Item& ji, const AssemblyOptions& o,
                       Sink& s) {
    const Joint& j = Get(m, ji);
    const int k = j.k();
    const JointMatrix TJ = CoordinateTangent(m, d, ji, o);
    if (j.row >= 0) AssembleRows(m, d, ji, o, TJ, s);
    if (k == 0) return;
    // Springs, dampers and drives act on the coordinates.
    JointCoordinateTerms c;
    CalcJointCoordinateTerms(m, d, ji, o.time, o.load_factor, o.dynamics, o.assemble_matrix, &c);
    s.Term(c.term_scale);
    s.Rows(j.coord, c.force.head(k));
    const JointMatrix S = o.c_stiffness * c.stiffness.topLeftCorner(k, k) * TJ +
                          o.c_damping * c.damping.topLeftCorner(k, k);
    s.Block(j.coord, j.coord, S, o.s_rows);
  }

  template <class F>
  static void ForEachGradientBlock(const Model& m, const Data& d, const Item& ji, F&& f) {
    const Joint& j = Get(m, ji);
    if (j.row < 0) return;
    JointGradient g;
    Gradient(m, d, ji, &g);
    const int da = NodeDof(m, j.node_a), db = NodeDof(m, j.node_b);
    if (da >= 0) f(j.row, da, JointGradientA(g));
    if (db >= 0) f(j.row, db, JointGradientB(g));
    if (j.k() > 0) {
      const JointMatrix I = Mat6::Identity().topLeftCorner(j.k(), j.k());
      f(j.row, j.coord, JointGradientCoordinates(g, JointCurrentBasis(m, d, ji), I));
    }
  }

  static void GradientTimes(const Model& m, const Data& d, const Item& ji,
                            const Eigen::Ref<const Eigen::VectorXd>& x,
                            Eigen::Ref<Eigen::VectorXd> out) {
    const Joint& j = Get(m, ji);
    if (j.row < 0) return;
    JointGradient g;
    Gradient(m, d, ji, &g);
    const int da = NodeDof(m, j.node_a), db = NodeDof(m, j.node_b);
    const Vec6 xa = da >= 0 ? Vec6(x.segment<6>(da)) : Vec6::Zero();
    const Vec6 xb = db >= 0 ? Vec6(x.segment<6>(db)) : Vec6::Zero();
    Vec6 bx = JointGradientTimes(g, da >= 0 ? &xa : nullptr, db >= 0 ? &xb : nullptr);
    if (j.k() > 0) {
      const JointMatrix I = Mat6::Identity().topLeftCorner(j.k(), j.k());
      bx += JointGradientCoordinates(g, JointCurrentBasis(m, d, ji), I) * x.segment(j.coord, j.k());
    }
    out.segment<6>(j.row) = bx;
  }

  // The energy of its springs on the coordinates (towards their rest, series-elastic drives
  // included); a free joint's springs are JointSpringKind's.
  static void AddEnergy(const Model& m, const Data& d, const Item& ji, Energy* energy) {
    energy->spring += JointSpringEnergy(m, d, ji);
  }

  // Scleronomic: phi depends on q alone.
  template <class F>
  static void ForEachTarget(const Model&, const Data&, const Item&, double, F&&) {}

  // The multipliers of the six rows (the reaction in the joint's constraint frame; the world
  // force and moment on side B is CalcJointReaction, assemble/outputs.h).
  static void Effort(const Model& m, const Data& d, const Item& ji,
                     Eigen::Ref<Eigen::VectorXd> out) {
    const Joint& j = Get(m, ji);
    if (j.row >= 0) out.head<6>() = d.lambda.segment<6>(j.row);
  }

 private:
  static const Joint& Get(const Model& m, int ji) { return m.joints[static_cast<std::size_t>(ji)]; }
  static void Gradient(const Model& m, const Data& d, int ji, JointGradient* g) {
    const Joint& j = Get(m, ji);
    CalcJointGradient(j, NodeFrame(d, j.node_a), NodeFrame(d, j.node_b),
                      JointRelativeFrame(m, d, ji), g);
  }
  // In dynamics the coordinates of joints without global coordinates (spherical, planar,
  // free) retract as H_J = H_J,n exp(A_J x), x = h dq_J, so their matrix columns carry the
  // subgroup's tangent operator A_J^T T(A_J x) A_J (docs/numerics.md), stored after the node
  // tangents by the integrator. Global coordinates retract additively: no tangent.
  static JointMatrix CoordinateTangent(const Model& m, const Data& d, int ji,
                                       const AssemblyOptions& o) {
    const Joint& j = Get(m, ji);
    const std::size_t jj = static_cast<std::size_t>(ji);
    if (o.use_node_tangent && !JointHasGlobalCoordinates(j.type) &&
        d.node_tangent.size() > m.nodes.size() + jj)
      return d.node_tangent[m.nodes.size() + jj].topLeftCorner(j.k(), j.k());
    return Mat6::Identity().topLeftCorner(j.k(), j.k());
  }

  template <class Sink>
  static void AssembleRows(const Model& m, const Data& d, int ji, const AssemblyOptions& o,
                           const JointMatrix& TJ, Sink& s) {
    const Joint& j = Get(m, ji);
    const int k = j.k();
    JointGradient g;
    Gradient(m, d, ji, &g);
    const Eigen::Ref<const Eigen::VectorXd> lam = d.lambda.segment(j.row, 6);
    s.Residual().template segment<6>(m.nv + j.row) += o.s_constraints * g.phi;
    // Stabilised index 2: the constraint rows of the matrix linearise B(q) v, whose
    // derivative with respect to the velocities is B itself (no tangent operator).
    const bool velocity_rows = o.velocity_constraint_tangent != 0.0;
    Vec6 bt_a, bt_b;
    JointGradientTransposeTimes(g, lam, &bt_a, &bt_b);
    const int da = NodeDof(m, j.node_a), db = NodeDof(m, j.node_b);  // -1: ground or fixed
    if (da >= 0) {
      s.Residual().template segment<6>(da).noalias() += o.s_rows * bt_a;
      if (o.assemble_matrix)
        s.GradientMatrix(j.row, da, JointGradientA(g),
                         velocity_rows ? nullptr : &s.NodeT(j.node_a));
    }
    if (db >= 0) {
      s.Residual().template segment<6>(db).noalias() += o.s_rows * bt_b;
      if (o.assemble_matrix)
        s.GradientMatrix(j.row, db, JointGradientB(g),
                         velocity_rows ? nullptr : &s.NodeT(j.node_b));
    }
    if (k > 0) {
      // The coordinates' force B_J^T lambda, in the residual and the multiplier columns,
      // has no tangent operator (it is the force on the velocity unknowns); the constraint
      // rows linearise phi along the retraction, B_J T_J.
      const Mat6X basis = JointCurrentBasis(m, d, ji);
      const JointMatrix I = Mat6::Identity().topLeftCorner(k, k);
      const auto BJ = JointGradientCoordinates(g, basis, I);
      s.Residual().segment(j.coord, k).noalias() += o.s_rows * (BJ.transpose() * lam);
      if (o.assemble_matrix) {
        s.Block(j.coord, m.nv + j.row, BJ.transpose(), o.s_rows * o.s_multipliers);
        s.Block(m.nv + j.row, j.coord, JointGradientCoordinates(g, basis, TJ), o.s_constraints);
      }
    }
    if (o.constraint_force_tangent && o.assemble_matrix && !o.use_node_tangent)
      AddForceTangent(m, d, ji, o, g, Vec6(lam), da, db, s);
    if (o.velocity_constraint_tangent != 0.0 && o.assemble_matrix)
      AddVelocityTangent(m, d, ji, o, g, TJ, da, db, s);
  }

  // d(B^T lambda)/dq (statics' exact tangent) into the blocks over node A, node B and the
  // coordinates (dofs -1: absent).
  template <class Sink>
  static void AddForceTangent(const Model& m, const Data& d, int ji, const AssemblyOptions& o,
                              const JointGradient& g, const Vec6& lambda, int da, int db, Sink& s) {
    const Joint& j = Get(m, ji);
    JointForceTangent K;
    CalcJointConstraintForceTangent(j, g, lambda, JointCurrentBasis(m, d, ji), &K);
    const int k = j.k();
    const int dofs[3] = {da, db, k > 0 ? j.coord : -1};
    const int sizes[3] = {6, 6, k}, offsets[3] = {0, 6, 12};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (dofs[a] >= 0 && dofs[b] >= 0)
          s.Block(dofs[a], dofs[b], K.block(offsets[a], offsets[b], sizes[a], sizes[b]),
                  o.s_rows * o.c_stiffness);
  }

  // Z = d(B v)/dq at the current v (stabilised index 2) into the constraint rows, with the
  // tangent operators of the columns, scaled by s_C o.velocity_constraint_tangent.
  template <class Sink>
  static void AddVelocityTangent(const Model& m, const Data& d, int ji, const AssemblyOptions& o,
                                 const JointGradient& g, const JointMatrix& TJ, int da, int db,
                                 Sink& s) {
    const Joint& j = Get(m, ji);
    const int k = j.k();
    const Vec6 v_a = da >= 0 ? Vec6(d.v.segment<6>(da)) : Vec6::Zero();
    const Vec6 v_b = db >= 0 ? Vec6(d.v.segment<6>(db)) : Vec6::Zero();
    JointVelocityTangent Z;
    CalcJointVelocityConstraintTangent(j, g, da >= 0 ? &v_a : nullptr, db >= 0 ? &v_b : nullptr,
                                       d.v.segment(k > 0 ? j.coord : 0, k),
                                       JointCurrentBasis(m, d, ji), &Z);
    const double scale = o.s_constraints * o.velocity_constraint_tangent;
    const int row = m.nv + j.row;
    const bool tangent = o.use_node_tangent;
    if (da >= 0)
      s.Block(row, da, tangent ? Mat6(Z.leftCols<6>() * s.NodeT(j.node_a)) : Mat6(Z.leftCols<6>()),
              scale);
    if (db >= 0)
      s.Block(row, db,
              tangent ? Mat6(Z.middleCols<6>(6) * s.NodeT(j.node_b)) : Mat6(Z.middleCols<6>(6)),
              scale);
    if (k > 0) {
      // The coordinates' constraint rows hold B_J T_J (AssembleRows); those of B v need B_J.
      const Mat6X basis = JointCurrentBasis(m, d, ji);
      const JointMatrix I = Mat6::Identity().topLeftCorner(k, k);
      s.Block(row, j.coord, Mat6X(Z.rightCols(k) * TJ), scale);
      s.Block(row, j.coord,
              Mat6X(JointGradientCoordinates(g, basis, I) - JointGradientCoordinates(g, basis, TJ)),
              o.s_constraints);
    }
  }
};

struct DriveConstraintKind {
  using Item = int;  // joint index

  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t jj = 0; jj < model.joints.size(); ++jj)
      if (model.joints[jj].drive == DriveKind::kPrescribed) f(static_cast<int>(jj));
  }
  static int FirstRow(const Model& m, const Item& ji) { return Get(m, ji).drive_row; }
  static int RowCount(const Model&, const Item&) { return 1; }
  template <class F>
  static void ForEachColumn(const Model& m, const Item& ji, F&& f) {
    f(Column(m, ji), 1);
  }
  static bool Active(const Model&, const Data&, const Item&) { return true; }
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const Joint& j : model.joints)
      if (j.drive == DriveKind::kPrescribed) f(j.drive_profile);
  }

  // The row alpha_c - f q(t) and its unit gradient (the multiplier's force on the coordinate
  // is in the joint's coordinate force, JointConstraintKind).
  template <class Sink>
  static void Assemble(const Model& m, const Data& d, const Item& ji, const AssemblyOptions& o,
                       Sink& s) {
    const Joint& j = Get(m, ji);
    const int c = Column(m, ji);
    s.Residual()(m.nv + j.drive_row) += o.s_constraints * Value(m, d, ji, o.time, o.load_factor);
    s.Block(c, m.nv + j.drive_row, Eigen::Matrix<double, 1, 1>::Ones(), o.s_rows * o.s_multipliers);
    s.Block(m.nv + j.drive_row, c, Eigen::Matrix<double, 1, 1>::Ones(), o.s_constraints);
  }
  template <class F>
  static void ForEachGradientBlock(const Model& m, const Data&, const Item& ji, F&& f) {
    f(Get(m, ji).drive_row, Column(m, ji), Eigen::Matrix<double, 1, 1>::Ones());
  }
  static void GradientTimes(const Model& m, const Data&, const Item& ji,
                            const Eigen::Ref<const Eigen::VectorXd>& x,
                            Eigen::Ref<Eigen::VectorXd> out) {
    out(Get(m, ji).drive_row) = x(Column(m, ji));
  }
  template <class F>
  static void ForEachTarget(const Model& m, const Data& d, const Item& ji, double time, F&& f) {
    const Joint& j = Get(m, ji);
    f(j.drive_row, EvalProfile(j.drive_profile, time, d));
  }
  // The drive's force or torque along its coordinate: -lambda.
  static void Effort(const Model& m, const Data& d, const Item& ji,
                     Eigen::Ref<Eigen::VectorXd> out) {
    out(0) = -d.lambda(Get(m, ji).drive_row);
  }
  // The row's value alpha_c - f q(t) (the drive's constraint violation at f = 1).
  static double Value(const Model& m, const Data& d, const Item& ji, double time,
                      double load_factor) {
    const Joint& j = Get(m, ji);
    return d.q_joint(Column(m, ji) - m.nv_nodes) -
           load_factor * EvalProfile(j.drive_profile, time, d).value;
  }

 private:
  static const Joint& Get(const Model& m, int ji) { return m.joints[static_cast<std::size_t>(ji)]; }
  static int Column(const Model& m, int ji) {
    const Joint& j = Get(m, ji);
    return j.coord + j.drive_coord;
  }
};

}  // namespace screwfem
