#include "screwfem/assemble/assemble.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <type_traits>

#include "screwfem/elements/contact.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/loads.h"
#include "screwfem/elements/rigid_body.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

const Mat6 kIdentity6 = Mat6::Identity();

// Writes element contributions into the global residual and the permuted band matrix.
class Scatter {
 public:
  Scatter(const Model& m, Data& d, const AssemblyOptions& o) : m_(m), d_(d), o_(o) {}

  int NodeDof(int node) const {
    return node == kGround ? -1 : m_.nodes[static_cast<std::size_t>(node)].dof;
  }
  // Records the size of terms that cancel inside a residual entry (round-off floor estimate).
  void Term(double magnitude) { d_.term_scale = std::max(d_.term_scale, o_.s_rows * magnitude); }
  const Mat6& NodeT(int node) const { return d_.node_tangent[static_cast<std::size_t>(node)]; }

  // residual rows [dof, dof + n) += s_R * r
  template <typename V>
  void Rows(int dof, const Eigen::MatrixBase<V>& r) {
    if (dof < 0) return;
    d_.residual.segment(dof, r.size()) += o_.s_rows * r;
    Force(r.cwiseAbs().maxCoeff());
  }
  // Records the size of a generalised force term that entered the residual (the scale of the
  // relative convergence test).
  void Force(double magnitude) {
    d_.force_scale = std::max(d_.force_scale, o_.s_rows * magnitude);
  }
  // matrix(rows at global index gi, cols at global index gj) += scale * B. The rows (and the
  // columns) of a block are consecutive in the permuted order (model.h), so each column of
  // the block is a contiguous piece of a band column.
  template <typename B>
  void Block(int gi, int gj, const Eigen::MatrixBase<B>& block, double scale) {
    if (gi < 0 || gj < 0 || !o_.assemble_matrix) return;
    const int pi = m_.permutation[static_cast<std::size_t>(gi)];
    const int pj = m_.permutation[static_cast<std::size_t>(gj)];
    // The factorisation relies on the model's sparsity pattern (pattern_last is constant over
    // a block of unknowns, so the first row and column stand for all).
    const std::vector<int>& pattern = o_.pattern_last ? *o_.pattern_last : m_.pattern_last;
    const bool inside =
        pattern.empty() ? d_.matrix.InBand(pi, pj + static_cast<int>(block.cols()) - 1) &&
                              d_.matrix.InBand(pi + static_cast<int>(block.rows()) - 1, pj)
                        : pj + block.cols() - 1 <= pattern[static_cast<std::size_t>(pi)] &&
                              pi + block.rows() - 1 <= pattern[static_cast<std::size_t>(pj)];
    if (!inside) {
      // Only the node blocks of pairs of moving shapes may lie outside (Data::coupling); a
      // block that does not fit the coupling's room is left out of this matrix.
      SCREWFEM_CHECK(off_band_ && block.rows() == 6 && block.cols() == 6);
      d_.coupling.Add(pi, pj, block, scale);
      return;
    }
    for (Eigen::Index j = 0; j < block.cols(); ++j) {
      double* const col = &d_.matrix.At(pi, pj + static_cast<int>(j));
      for (Eigen::Index i = 0; i < block.rows(); ++i) col[i] += scale * block(i, j);
    }
  }
  // Element matrix over nodes: rows/cols in 6-blocks. S = s_R (c_K K T + c_M M + c_C C);
  // with `kHasNodeTangent`, K already holds K T (or K when the iteration does not use T).
  // dofs[i] is node i's first unknown (-1: none), T[i] its tangent operator.
  template <int N, bool kHasNodeTangent = false>
  void NodeMatrix(const int (&dofs)[N], const Mat6* const (&T)[N],
                  const Eigen::Matrix<double, 6 * N, 6 * N>* K,
                  const Eigen::Matrix<double, 6 * N, 6 * N>* M,
                  const Eigen::Matrix<double, 6 * N, 6 * N>* C) {
    ForEachNodeBlock(dofs, [&](int a, int b, int gi, int gj) {
      Mat6 S = Mat6::Zero();
      if (K) {
        if (o_.use_node_tangent && !kHasNodeTangent)
          S.noalias() += o_.c_stiffness * K->template block<6, 6>(6 * a, 6 * b) * *T[b];
        else
          S += o_.c_stiffness * K->template block<6, 6>(6 * a, 6 * b);
      }
      if (M) S += o_.c_mass * M->template block<6, 6>(6 * a, 6 * b);
      if (C) S += o_.c_damping * C->template block<6, 6>(6 * a, 6 * b);
      Block(gi, gj, S, o_.s_rows);
    });
  }
  // An element matrix already combined (S = c_K K T + c_M M + c_C C): adds s_R S.
  template <int N>
  void ElementMatrix(const int (&dofs)[N], const Eigen::Matrix<double, 6 * N, 6 * N>& S) {
    ForEachNodeBlock(dofs, [&](int a, int b, int gi, int gj) {
      Block(gi, gj, S.template block<6, 6>(6 * a, 6 * b), o_.s_rows);
    });
  }
  // f(a, b, gi, gj) for the 6 x 6 blocks (a, b) of an element matrix over nodes with first
  // unknowns `dofs` (-1: none) whose nodes both have unknowns (gi, gj their first global
  // indices); nothing without the matrix.
  template <int N, typename F>
  void ForEachNodeBlock(const int (&dofs)[N], F&& f) {
    if (!o_.assemble_matrix) return;
    for (int b = 0; b < N; ++b) {
      const int gj = dofs[b];
      if (gj < 0) continue;
      for (int a = 0; a < N; ++a) {
        const int gi = dofs[a];
        if (gi >= 0) f(a, b, gi, gj);
      }
    }
  }
  // An item's terms (elements/element.h): its node rows, and its matrix blocks combined by the
  // kernel or here. dofs and x as gathered for the item (GatherItem).
  // While true, node blocks outside the band pattern go to the off-band coupling.
  void AllowOffBand(bool allow) { off_band_ = allow; }
  template <int N>
  void Add(const int (&dofs)[N], const NodeMotion<N>& x, const ElementTerms<N>& t) {
    if (!t.active) return;
    Force(t.force_scale);
    Term(t.term_scale);
    for (int i = 0; i < N; ++i) Rows(dofs[i], t.residual.template segment<6>(6 * i));
    if (!o_.assemble_matrix) return;
    using M = typename ElementTerms<N>::Matrix;
    const M* K = t.has_stiffness ? &t.stiffness : nullptr;
    const M* Ms = t.has_mass ? &t.mass : nullptr;
    const M* C = t.has_damping ? &t.damping : nullptr;
    if (t.combined)
      ElementMatrix<N>(dofs, t.matrix);
    else if (t.stiffness_has_node_tangent)
      NodeMatrix<N, true>(dofs, x.T, K, Ms, C);
    else
      NodeMatrix<N, false>(dofs, x.T, K, Ms, C);
  }
  // Constraint gradient block B (rows: constraint rows starting at `row`, cols: unknowns
  // starting at gj): adds s_C B T to the constraint rows and s_R s_L B^T to the equilibrium
  // rows, and B^T lambda to the residual.
  template <typename BT>
  void Gradient(int row, int gj, const Eigen::MatrixBase<BT>& B, const Mat6* T,
                const Eigen::Ref<const Eigen::VectorXd>& lambda) {
    if (gj < 0) return;
    d_.residual.segment(gj, B.cols()).noalias() += o_.s_rows * (B.transpose() * lambda);
    GradientMatrix(row, gj, B, T);
  }
  // The matrix blocks of Gradient alone (the caller adds B^T lambda to the residual).
  template <typename BT>
  void GradientMatrix(int row, int gj, const Eigen::MatrixBase<BT>& B, const Mat6* T) {
    if (gj < 0 || !o_.assemble_matrix) return;
    const int gr = m_.nv + row;
    Block(gj, gr, B.transpose(), o_.s_rows * o_.s_multipliers);
    if (T && o_.use_node_tangent)
      Block(gr, gj, typename BT::PlainObject(B * *T), o_.s_constraints);
    else
      Block(gr, gj, B, o_.s_constraints);
  }

 private:
  const Model& m_;
  Data& d_;
  const AssemblyOptions& o_;
  bool off_band_ = false;
};

// The node state of one item, as its kernel reads it (elements/element.h, NodeMotion), and
// the first unknown of each node (-1: fixed or the ground), looked up once per item.
template <int N>
void GatherItem(const Scatter& s, const Data& d, const AssemblyOptions& o,
                const int (&nodes)[N], int (&dofs)[N], NodeMotion<N>* x) {
  const bool node_tangent = o.use_node_tangent && o.assemble_matrix;
  for (int i = 0; i < N; ++i) {
    dofs[i] = s.NodeDof(nodes[i]);
    x->H[i] = &NodeFrame(d, nodes[i]);
    x->T[i] = node_tangent && dofs[i] >= 0 ? &s.NodeT(nodes[i]) : &kIdentity6;
  }
  if (o.dynamics) GatherNodeMotionAt<N>(d, dofs, &x->eta, &x->eta_dot);
}

KernelOptions MakeKernelOptions(const AssemblyOptions& o) {
  KernelOptions k;
  k.time = o.time;
  k.load_factor = o.load_factor;
  k.dynamics = o.dynamics;
  k.tangent = o.assemble_matrix;
  k.c_mass = o.c_mass;
  k.c_damping = o.c_damping;
  k.c_stiffness = o.c_stiffness;
  k.node_tangent = o.use_node_tangent && o.assemble_matrix;
  return k;
}

// The items of a kind: from the Model, or from the Data for a kind whose items are found
// during the run (kItemsInData: the pairs of the contact broad phase).
template <class Kind, class F>
void ForEachItem(const Model& m, const Data& d, F&& f) {
  if constexpr (requires { Kind::kItemsInData; })
    Kind::ForEach(m, d, f);
  else
    Kind::ForEach(m, f);
}

// Every item of one element kind: gather, compute, scatter. Stops at the first item whose
// kernel fails (a rod element past its rotation limit) and records it in data.
template <class Kind>
bool AddKind(const Model& m, Data& d, const AssemblyOptions& o, const KernelOptions& ko,
             Scatter& s) {
  constexpr int N = Kind::kNodes;
  bool ok = true;
  // A kind whose items couple nodes the band pattern may not hold (kOffBandBlocks).
  s.AllowOffBand(requires { Kind::kOffBandBlocks; });
  ForEachItem<Kind>(m, d, [&](const typename Kind::Item& item, const int (&nodes)[N]) {
    if (!ok) return;
    int dofs[N];
    NodeMotion<N> x;
    GatherItem<N>(s, d, o, nodes, dofs, &x);
    ElementTerms<N> t;
    if (!Kind::Calc(m, d, item, x, ko, &t)) {
      ok = false;
      if constexpr (std::is_same_v<typename Kind::Item, int>) d.failed_element = item;
      d.failed_rotation = t.failure;
      return;
    }
    s.Add(dofs, x, t);
  });
  s.AllowOffBand(false);
  return ok;
}

template <class... Kinds>
bool AddKinds(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s,
              std::tuple<Kinds...>*) {
  const KernelOptions ko = MakeKernelOptions(o);
  return (AddKind<Kinds>(m, d, o, ko, s) && ...);
}

template <class... Kinds>
void AddKindEnergies(const Model& m, const Data& d, Energy* E, std::tuple<Kinds...>*) {
  (ForEachItem<Kinds>(m, d, [&](const typename Kinds::Item& item, const int(&)[Kinds::kNodes]) {
     Kinds::AddEnergy(m, d, item, E);
   }),
   ...);
}

// d(B^T lambda)/dq of joint ji (statics' exact tangent) into the blocks over its node A, node
// B and coordinates (dofs -1: absent).
void AddConstraintForceTangent(const Model& m, const Data& d, const AssemblyOptions& o,
                               Scatter& s, int ji, const JointGradient& g, const Vec6& lambda,
                               int da, int db) {
  const Joint& j = m.joints[static_cast<std::size_t>(ji)];
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

// Z = d(B v)/dq of joint ji at the current v (stabilised index 2) into its constraint rows,
// with the tangent operators of the columns, scaled by s_C o.velocity_constraint_tangent.
void AddVelocityConstraintTangent(const Model& m, const Data& d, const AssemblyOptions& o,
                                  Scatter& s, int ji, const JointGradient& g,
                                  const JointMatrix& TJ, int da, int db) {
  const Joint& j = m.joints[static_cast<std::size_t>(ji)];
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
    // The coordinates' constraint rows hold B_J T_J (AddJoints); those of B v need B_J.
    const Mat6X basis = JointCurrentBasis(m, d, ji);
    const JointMatrix I = Mat6::Identity().topLeftCorner(k, k);
    s.Block(row, j.coord, Mat6X(Z.rightCols(k) * TJ), scale);
    s.Block(row, j.coord,
            Mat6X(JointGradientCoordinates(g, basis, I) - JointGradientCoordinates(g, basis, TJ)),
            o.s_constraints);
  }
}

// Joints (method.md §4): the constraint rows and their gradient, and the forces of springs,
// dampers and drives on the coordinates, from the joint kernel (elements/joint.h).
void AddJoints(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  for (std::size_t jj = 0; jj < m.joints.size(); ++jj) {
    const Joint& j = m.joints[jj];
    const int ji = static_cast<int>(jj);
    const int k = j.k();
    // In dynamics the coordinates of joints without global coordinates (spherical, planar,
    // free) retract as H_J = H_J,n exp(A_J x), x = h dq_J, so their matrix columns carry the
    // subgroup's tangent operator A_J^T T(A_J x) A_J (method.md §5.2), stored after the node
    // tangents by the integrator. Global coordinates retract additively: no tangent.
    JointMatrix TJ = Mat6::Identity().topLeftCorner(k, k);
    if (o.use_node_tangent && !JointHasGlobalCoordinates(j.type) &&
        d.node_tangent.size() > m.nodes.size() + jj)
      TJ = d.node_tangent[m.nodes.size() + jj].topLeftCorner(k, k);
    if (j.row >= 0) {
      JointGradient g;
      CalcJointGradient(j, NodeFrame(d, j.node_a), NodeFrame(d, j.node_b),
                        JointRelativeFrame(m, d, ji), &g);
      const Eigen::Ref<const Eigen::VectorXd> lam = d.lambda.segment(j.row, 6);
      d.residual.segment<6>(m.nv + j.row) += o.s_constraints * g.phi;
      // Stabilised index 2: the constraint rows of the matrix linearise B(q) v, whose
      // derivative with respect to the velocities is B itself (no tangent operator).
      const bool velocity_rows = o.velocity_constraint_tangent != 0.0;
      // The residual gets B^T lambda as transposed products applied to the vector (the same
      // with and without the matrix), the matrix the blocks themselves.
      Vec6 bt_a, bt_b;
      JointGradientTransposeTimes(g, lam, &bt_a, &bt_b);
      const int da = s.NodeDof(j.node_a), db = s.NodeDof(j.node_b);  // -1: ground or fixed
      if (da >= 0) {
        d.residual.segment<6>(da).noalias() += o.s_rows * bt_a;
        if (o.assemble_matrix)
          s.GradientMatrix(j.row, da, JointGradientA(g), velocity_rows ? nullptr : &s.NodeT(j.node_a));
      }
      if (db >= 0) {
        d.residual.segment<6>(db).noalias() += o.s_rows * bt_b;
        if (o.assemble_matrix)
          s.GradientMatrix(j.row, db, JointGradientB(g), velocity_rows ? nullptr : &s.NodeT(j.node_b));
      }
      if (k > 0) {
        // The coordinates' force B_J^T lambda, in the residual and the multiplier columns,
        // has no tangent operator (it is the force on the velocity unknowns); the constraint
        // rows linearise phi along the retraction, B_J T_J.
        const Mat6X basis = JointCurrentBasis(m, d, ji);
        const JointMatrix I = Mat6::Identity().topLeftCorner(k, k);
        const auto BJ = JointGradientCoordinates(g, basis, I);
        d.residual.segment(j.coord, k).noalias() += o.s_rows * (BJ.transpose() * lam);
        if (o.assemble_matrix) {
          s.Block(j.coord, m.nv + j.row, BJ.transpose(), o.s_rows * o.s_multipliers);
          s.Block(m.nv + j.row, j.coord, JointGradientCoordinates(g, basis, TJ), o.s_constraints);
        }
      }
      if (o.constraint_force_tangent && o.assemble_matrix && !o.use_node_tangent)
        AddConstraintForceTangent(m, d, o, s, ji, g, Vec6(lam), da, db);
      if (o.velocity_constraint_tangent != 0.0 && o.assemble_matrix)
        AddVelocityConstraintTangent(m, d, o, s, ji, g, TJ, da, db);
    }
    if (k == 0) continue;
    // Springs, dampers and drives act on the coordinates.
    JointCoordinateTerms c;
    CalcJointCoordinateTerms(m, d, ji, o.time, o.load_factor, o.dynamics, o.assemble_matrix, &c);
    s.Term(c.term_scale);
    if (j.drive == DriveKind::kPrescribed) {
      d.residual(m.nv + j.drive_row) += o.s_constraints * c.drive_constraint;
      s.Block(j.coord + j.drive_coord, m.nv + j.drive_row, Eigen::Matrix<double, 1, 1>::Ones(),
              o.s_rows * o.s_multipliers);
      s.Block(m.nv + j.drive_row, j.coord + j.drive_coord, Eigen::Matrix<double, 1, 1>::Ones(),
              o.s_constraints);
    }
    s.Rows(j.coord, c.force.head(k));
    const JointMatrix S = o.c_stiffness * c.stiffness.topLeftCorner(k, k) * TJ +
                          o.c_damping * c.damping.topLeftCorner(k, k);
    s.Block(j.coord, j.coord, S, o.s_rows);
  }
}

// Length-driven tendons (method-next.md §N4.3): the row L(q) - L_p(t) and its gradient B_T,
// the segments' length gradients added node by node into the row and (transposed) into the
// column. B_T^T lambda and its tangent lambda d2L come from the segments themselves
// (TendonSegmentKind with tau = lambda). A slack tendon's row is held (Assemble).
void AddTendonRows(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  for (std::size_t ti = 0; ti < m.tendons.size(); ++ti) {
    const Tendon& t = m.tendons[ti];
    if (t.row < 0 || d.tendon_slack[ti]) continue;
    // Stabilised index 2: the row of the matrix linearises dL/dt = B_T v, whose derivative
    // with respect to the velocities is B_T (no tangent operator; d(B_T v)/dq is left out of
    // the matrix: simplified Newton on this row).
    const bool velocity_rows = o.velocity_constraint_tangent != 0.0;
    double L = 0.0;
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k) {
      const TendonSegment& seg =
          m.tendon_segments[static_cast<std::size_t>(t.first_segment) + k];
      SegmentGradient g;  // eyelets between nodes: parts on both nodes of their element
      if (!CalcSegmentGradient(m, d, seg, &g)) continue;
      L += g.length;
      if (!o.assemble_matrix) continue;
      for (int i = 0; i < g.count; ++i) {
        const int dof = s.NodeDof(g.nodes[i]);
        if (dof < 0) continue;
        const Eigen::Matrix<double, 1, 6> B = g.parts[i].transpose();
        s.GradientMatrix(t.row, dof, B, velocity_rows ? nullptr : &s.NodeT(g.nodes[i]));
      }
    }
    d.residual(m.nv + t.row) +=
        o.s_constraints * (L - TendonTargetLength(t, d, o.time, o.load_factor).value);
  }
}

// The element kinds the assembly calls, in this order (docs/architecture.md, "Add an element
// kind"); joints follow them.
using ElementKinds = std::tuple<RodElementKind, RigidBodyKind, PointLoadKind, RodLoadKind,
                                JointSpringKind, TendonSegmentKind, TendonSpanSegmentKind,
                                ForceElementKind, ContactKind, ShapePairKind>;
constexpr ElementKinds* kElementKinds = nullptr;
}  // namespace

std::vector<int> ConstraintForceTangentPattern(const Model& model, int* bandwidth) {
  std::vector<int> last = model.pattern_last;
  *bandwidth = model.bandwidth;
  if (static_cast<int>(last.size()) != model.num_unknowns()) return last;
  // The permuted range [first, first + size) of a block of unknowns starting at global g.
  struct Range {
    int first = -1, size = 0;
  };
  const auto range = [&](int g, int size) {
    return g < 0 || size == 0 ? Range{} : Range{model.permutation[static_cast<std::size_t>(g)], size};
  };
  const auto node_dof = [&](int node) {
    return node == kGround ? -1 : model.nodes[static_cast<std::size_t>(node)].dof;
  };
  for (const Joint& j : model.joints) {
    if (j.row < 0) continue;
    const Range r[3] = {range(node_dof(j.node_a), 6), range(node_dof(j.node_b), 6),
                        range(j.coord, j.k())};
    for (const Range& a : r)
      for (const Range& b : r) {
        if (a.first < 0 || b.first < 0) continue;
        for (int i = 0; i < a.size; ++i) {
          int& l = last[static_cast<std::size_t>(a.first + i)];
          l = std::max(l, b.first + b.size - 1);
          *bandwidth = std::max(*bandwidth, l - (a.first + i));
        }
      }
  }
  return last;
}

Energy CalcEnergy(const Model& model, const Data& data) {
  Energy E;
  AddKindEnergies(model, data, &E, kElementKinds);
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj)
    E.spring += JointSpringEnergy(model, data, static_cast<int>(jj));
  return E;
}

void SaveState(const Data& data, State* state) {
  state->H = data.H;
  state->HJ = data.HJ;
  state->q_joint = data.q_joint;
}

void RestoreState(const State& state, Data& data) {
  data.H = state.H;
  data.HJ = state.HJ;
  data.q_joint = state.q_joint;
}

void Retract(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& dx) {
  for (std::size_t i = 0; i < model.nodes.size(); ++i) {
    const int dof = model.nodes[i].dof;
    if (dof >= 0) data.H[i] = data.H[i] * ExpSE3(dx.segment<6>(dof));
  }
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.k() > 0) RetractJoint(model, data, static_cast<int>(jj), dx.segment(j.coord, j.k()));
  }
}

double ScaledIncrementSize(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& dx) {
  double r = 0.0;
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    r = std::max(r, dx.segment<3>(n.dof).cwiseAbs().maxCoeff() / model.length_scale);
    r = std::max(r, dx.segment<3>(n.dof + 3).cwiseAbs().maxCoeff());
  }
  for (int i = model.nv_nodes; i < model.nv; ++i) r = std::max(r, std::abs(dx(i)));
  return r;
}

void UpdateBranchReferences(const Model& model, Data& data) {
  // The rotation of CalcRodRelativeMotion alone: R_A^T R_B formed as (H_A^-1 H_B).R is.
  for (std::size_t e = 0; e < model.elements.size(); ++e) {
    const RodElement& el = model.elements[e];
    const Mat3 RAt = data.H[static_cast<std::size_t>(el.node_a)].R.transpose();
    data.w_ref[e] = LogSO3Near(RAt * data.H[static_cast<std::size_t>(el.node_b)].R, data.w_ref[e]);
  }
}

bool Assemble(const Model& model, Data& data, const AssemblyOptions& options) {
  data.residual.setZero();
  if (options.assemble_matrix) {
    data.matrix.SetZero();
    // The off-band coupling: doubled when the last assembly overflowed it, up to
    // kMaxCoupledNodes (beyond, the blocks that do not fit are left out of the matrix).
    if (data.coupling.overflowed() && data.coupling.max_blocks() < kMaxCoupledNodes)
      data.coupling.Resize(data.coupling.size(), 6,
                           std::min(2 * data.coupling.max_blocks(), kMaxCoupledNodes));
    data.coupling.Clear();
  }
  data.failed_element = -1;
  data.force_scale = 0.0;
  data.term_scale = 0.0;
  Scatter s(model, data, options);
  // The pairs of moving shapes near each other in this state (elements/shape_pair.h).
  UpdateShapePairs(model, data);
  if (!AddKinds(model, data, options, s, kElementKinds)) return false;
  AddJoints(model, data, options, s);
  AddTendonRows(model, data, options, s);
  // Redundant constraint rows (found at build time) and slack tendons: the row becomes
  // dmu_r = -lambda_r / s_L, which holds their multipliers at zero.
  ForEachHeldRow(model, data, [&](int r) {
    const int g = model.nv + r;
    data.residual(g) = data.lambda(r) / options.s_multipliers;
    if (!options.assemble_matrix) return;
    const int p = model.permutation[static_cast<std::size_t>(g)];
    const int lo = std::max(0, p - data.matrix.lower_bandwidth());
    const int hi = std::min(data.matrix.size() - 1, p + data.matrix.upper_bandwidth());
    for (int c = lo; c <= hi; ++c) data.matrix.At(p, c) = 0.0;
    data.matrix.At(p, p) = 1.0;
  });
  return data.residual.allFinite();
}

namespace {

// Calls visit(joint, its index, gradient factors, dof of node A, dof of node B; -1 for the
// ground) for every joint with constraint rows, at the current configuration.
template <typename Visit>
void ForEachConstraintGradient(const Model& model, const Data& data, Visit&& visit) {
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.row < 0) continue;
    const int ji = static_cast<int>(jj);
    JointGradient g;
    CalcJointGradient(j, NodeFrame(data, j.node_a), NodeFrame(data, j.node_b),
                      JointRelativeFrame(model, data, ji), &g);
    const int da = j.node_a == kGround ? -1 : model.nodes[static_cast<std::size_t>(j.node_a)].dof;
    const int db = j.node_b == kGround ? -1 : model.nodes[static_cast<std::size_t>(j.node_b)].dof;
    visit(j, ji, g, da, db);
  }
}

// Calls visit(tendon, dof, gradient part) for every segment end of every taut length-driven
// tendon on a node with unknowns: the row's gradient B_T is the sum of these parts.
template <typename Visit>
void ForEachTendonGradientPart(const Model& model, const Data& data, Visit&& visit) {
  for (std::size_t ti = 0; ti < model.tendons.size(); ++ti) {
    const Tendon& t = model.tendons[ti];
    if (t.row < 0 || data.tendon_slack[ti]) continue;
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k) {
      const TendonSegment& seg =
          model.tendon_segments[static_cast<std::size_t>(t.first_segment) + k];
      SegmentGradient g;
      if (!CalcSegmentGradient(model, data, seg, &g)) continue;
      for (int i = 0; i < g.count; ++i) {
        const int dof = model.nodes[static_cast<std::size_t>(g.nodes[i])].dof;
        if (dof >= 0) visit(t, dof, g.parts[i]);
      }
    }
  }
}

}  // namespace

void CalcConstraintGradient(const Model& model, const Data& data, Eigen::Ref<Eigen::MatrixXd> out) {
  out.setZero();
  ForEachConstraintGradient(model, data, [&](const Joint& j, int ji, const JointGradient& g,
                                             int da, int db) {
    if (da >= 0) out.block<6, 6>(j.row, da) += JointGradientA(g);
    if (db >= 0) out.block<6, 6>(j.row, db) += JointGradientB(g);
    if (j.k() > 0) {
      const JointMatrix I = Mat6::Identity().topLeftCorner(j.k(), j.k());
      out.block(j.row, j.coord, 6, j.k()) +=
          JointGradientCoordinates(g, JointCurrentBasis(model, data, ji), I);
    }
  });
  for (const Joint& j : model.joints)
    if (j.drive == DriveKind::kPrescribed) out(j.drive_row, j.coord + j.drive_coord) = 1.0;
  ForEachTendonGradientPart(model, data, [&](const Tendon& t, int dof, const Vec6& b) {
    out.block<1, 6>(t.row, dof) += b.transpose();
  });
  ForEachHeldRow(model, data, [&](int r) { out.row(r).setZero(); });
}

void CalcConstraintGradientTimes(const Model& model, const Data& data,
                                 const Eigen::Ref<const Eigen::VectorXd>& x,
                                 Eigen::Ref<Eigen::VectorXd> out) {
  out.setZero();
  ForEachConstraintGradient(model, data, [&](const Joint& j, int ji, const JointGradient& g,
                                             int da, int db) {
    const Vec6 xa = da >= 0 ? Vec6(x.segment<6>(da)) : Vec6::Zero();
    const Vec6 xb = db >= 0 ? Vec6(x.segment<6>(db)) : Vec6::Zero();
    Vec6 bx = JointGradientTimes(g, da >= 0 ? &xa : nullptr, db >= 0 ? &xb : nullptr);
    if (j.k() > 0) {
      const JointMatrix I = Mat6::Identity().topLeftCorner(j.k(), j.k());
      bx += JointGradientCoordinates(g, JointCurrentBasis(model, data, ji), I) *
            x.segment(j.coord, j.k());
    }
    out.segment<6>(j.row) = bx;
  });
  for (const Joint& j : model.joints)
    if (j.drive == DriveKind::kPrescribed) out(j.drive_row) = x(j.coord + j.drive_coord);
  ForEachTendonGradientPart(model, data, [&](const Tendon& t, int dof, const Vec6& b) {
    out(t.row) += b.dot(x.segment<6>(dof));
  });
  ForEachHeldRow(model, data, [&](int r) { out(r) = 0.0; });
}

void CalcVelocityConstraint(const Model& model, const Data& data, double time,
                            Eigen::Ref<Eigen::VectorXd> out) {
  CalcConstraintGradientTimes(model, data, data.v, out);
  for (const Joint& j : model.joints)
    if (j.drive == DriveKind::kPrescribed) out(j.drive_row) -= EvalProfile(j.drive_profile, time, data).rate;
  for (std::size_t ti = 0; ti < model.tendons.size(); ++ti) {
    const Tendon& t = model.tendons[ti];
    if (t.row >= 0 && !data.tendon_slack[ti]) out(t.row) -= TendonTargetLength(t, data, time).rate;
  }
}

double MaxConstraintViolation(const Model& model, Data& data, double time, double load_factor) {
  AssemblyOptions o;
  o.time = time;
  o.load_factor = load_factor;
  o.assemble_matrix = false;
  Assemble(model, data, o);
  return model.nc > 0 ? data.residual.tail(model.nc).cwiseAbs().maxCoeff() : 0.0;
}

}  // namespace screwfem
