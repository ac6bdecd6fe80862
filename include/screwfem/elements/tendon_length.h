// Length-driven tendons as a constraint kind (elements/constraint.h; docs/numerics.md,
// "Length-driven tendons"): one row L(q) - L_p(t) per tendon, its gradient B_T the sum of its
// segments' length gradients node by node (CalcSegmentGradient). B_T^T lambda and its tangent
// lambda d2L come from the segments themselves (TendonSegmentKind with tau = lambda). A slack
// tendon's row is held at zero multiplier (Active is false; ForEachHeldRow).
#pragma once

#include "screwfem/elements/constraint.h"
#include "screwfem/elements/tendon.h"

namespace screwfem {

struct TendonLengthKind {
  using Item = int;  // tendon index

  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t ti = 0; ti < model.tendons.size(); ++ti)
      if (model.tendons[ti].row >= 0) f(static_cast<int>(ti));
  }
  static int FirstRow(const Model& m, const Item& ti) { return Get(m, ti).row; }
  static int RowCount(const Model&, const Item&) { return 1; }
  // The nodes of every eyelet (both nodes of the element of an eyelet between rod nodes); a
  // node may come more than once.
  template <class F>
  static void ForEachColumn(const Model& m, const Item& ti, F&& f) {
    const Tendon& t = Get(m, ti);
    const auto node_b = [&](const BodyPoint& p) {
      return p.element >= 0 ? m.elements[static_cast<std::size_t>(p.element)].node_b : kGround;
    };
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k) {
      const TendonSegment& seg = Segment(m, t, k);
      for (const int node : {seg.a.node, seg.b.node, node_b(seg.a), node_b(seg.b)})
        if (NodeDof(m, node) >= 0) f(NodeDof(m, node), 6);
    }
  }
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const Tendon& t : model.tendons)
      if (t.drive == TendonDrive::kLength) f(t.length);
  }
  static bool Active(const Model&, const Data& d, const Item& ti) {
    return !d.tendon_slack[static_cast<std::size_t>(ti)];
  }

  // The row L - L_p(t) and the gradient blocks B_T (stabilised index 2: the row of the matrix
  // linearises dL/dt = B_T v, whose derivative with respect to the velocities is B_T, no
  // tangent operator; d(B_T v)/dq is left out of the matrix: simplified Newton on this row).
  template <class Sink>
  static void Assemble(const Model& m, const Data& d, const Item& ti, const AssemblyOptions& o,
                       Sink& s) {
    const Tendon& t = Get(m, ti);
    const bool velocity_rows = o.velocity_constraint_tangent != 0.0;
    double L = 0.0;
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k) {
      SegmentGradient g;  // eyelets between nodes: parts on both nodes of their element
      if (!CalcSegmentGradient(m, d, Segment(m, t, k), &g)) continue;
      L += g.length;
      if (!o.assemble_matrix) continue;
      for (int i = 0; i < g.count; ++i) {
        const int dof = NodeDof(m, g.nodes[i]);
        if (dof < 0) continue;
        const Eigen::Matrix<double, 1, 6> B = g.parts[i].transpose();
        s.GradientMatrix(t.row, dof, B, velocity_rows ? nullptr : &s.NodeT(g.nodes[i]));
      }
    }
    s.Residual()(m.nv + t.row) +=
        o.s_constraints * (L - TendonTargetLength(t, d, o.time, o.load_factor).value);
  }
  template <class F>
  static void ForEachGradientBlock(const Model& m, const Data& d, const Item& ti, F&& f) {
    ForEachPart(m, d, ti, [&](int dof, const Vec6& b) { f(Get(m, ti).row, dof, b.transpose()); });
  }
  static void GradientTimes(const Model& m, const Data& d, const Item& ti,
                            const Eigen::Ref<const Eigen::VectorXd>& x,
                            Eigen::Ref<Eigen::VectorXd> out) {
    const int row = Get(m, ti).row;
    ForEachPart(m, d, ti, [&](int dof, const Vec6& b) { out(row) += b.dot(x.segment<6>(dof)); });
  }
  template <class F>
  static void ForEachTarget(const Model& m, const Data& d, const Item& ti, double time, F&& f) {
    f(Get(m, ti).row, TendonTargetLength(Get(m, ti), d, time));
  }
  // The tension (the multiplier; zero while slack).
  static void Effort(const Model& m, const Data& d, const Item& ti,
                     Eigen::Ref<Eigen::VectorXd> out) {
    out(0) = d.lambda(Get(m, ti).row);
  }

 private:
  static const Tendon& Get(const Model& m, int ti) {
    return m.tendons[static_cast<std::size_t>(ti)];
  }
  static const TendonSegment& Segment(const Model& m, const Tendon& t, std::size_t k) {
    return m.tendon_segments[static_cast<std::size_t>(t.first_segment) + k];
  }
  // f(dof, part) for every segment end on a node with unknowns: B_T is the sum of the parts.
  template <class F>
  static void ForEachPart(const Model& m, const Data& d, int ti, F&& f) {
    const Tendon& t = Get(m, ti);
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k) {
      SegmentGradient g;
      if (!CalcSegmentGradient(m, d, Segment(m, t, k), &g)) continue;
      for (int i = 0; i < g.count; ++i) {
        const int dof = NodeDof(m, g.nodes[i]);
        if (dof >= 0) f(dof, g.parts[i]);
      }
    }
  }
};

}  // namespace screwfem
