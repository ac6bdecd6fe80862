#include "screwfem/assemble/assemble.h"

#include <algorithm>
#include <cmath>

#include "screwfem/elements/rod.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

const Mat6 kIdentity6 = Mat6::Identity();
const Mat12 kZero12 = Mat12::Zero();

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
    SCREWFEM_CHECK(m_.pattern_last.empty() ||
                   (pj + block.cols() - 1 <= m_.pattern_last[static_cast<std::size_t>(pi)] &&
                    pi + block.rows() - 1 <= m_.pattern_last[static_cast<std::size_t>(pj)]));
    for (Eigen::Index j = 0; j < block.cols(); ++j) {
      double* const col = &d_.matrix.At(pi, pj + static_cast<int>(j));
      for (Eigen::Index i = 0; i < block.rows(); ++i) col[i] += scale * block(i, j);
    }
  }
  // Element matrix over nodes: rows/cols in 6-blocks. S = s_R (c_K K T + c_M M + c_C C);
  // with `kHasNodeTangent`, K already holds K T (or K when the iteration does not use T).
  template <int N, bool kHasNodeTangent = false>
  void NodeMatrix(const int (&nodes)[N], const Eigen::Matrix<double, 6 * N, 6 * N>* K,
                  const Eigen::Matrix<double, 6 * N, 6 * N>* M,
                  const Eigen::Matrix<double, 6 * N, 6 * N>* C) {
    ForEachNodeBlock(nodes, [&](int a, int b, int gi, int gj) {
      Mat6 S = Mat6::Zero();
      if (K) {
        if (o_.use_node_tangent && !kHasNodeTangent)
          S.noalias() += o_.c_stiffness * K->template block<6, 6>(6 * a, 6 * b) * NodeT(nodes[b]);
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
  void ElementMatrix(const int (&nodes)[N], const Eigen::Matrix<double, 6 * N, 6 * N>& S) {
    ForEachNodeBlock(nodes, [&](int a, int b, int gi, int gj) {
      Block(gi, gj, S.template block<6, 6>(6 * a, 6 * b), o_.s_rows);
    });
  }
  // f(a, b, gi, gj) for the 6 x 6 blocks (a, b) of an element matrix over `nodes` whose nodes
  // both have unknowns (gi, gj their first global indices); nothing without the matrix.
  template <int N, typename F>
  void ForEachNodeBlock(const int (&nodes)[N], F&& f) {
    if (!o_.assemble_matrix) return;
    for (int b = 0; b < N; ++b) {
      const int gj = NodeDof(nodes[b]);
      if (gj < 0) continue;
      for (int a = 0; a < N; ++a) {
        const int gi = NodeDof(nodes[a]);
        if (gi >= 0) f(a, b, gi, gj);
      }
    }
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
};

// Rigid-body mass matrix about the node origin (method.md §3).
Mat6 RigidMass(const RigidBody& b) {
  const Mat3 S = Skew(b.com);
  Mat6 M;
  M.topLeftCorner<3, 3>() = b.mass * Mat3::Identity();
  M.topRightCorner<3, 3>() = -b.mass * S;
  M.bottomLeftCorner<3, 3>() = b.mass * S;
  M.bottomRightCorner<3, 3>() = b.inertia - b.mass * S * S;
  return M;
}

// World force F (node-frame components f) at body point p: generalised force and the
// tangent of -g (method.md §3).
void AddDeadForce(const Vec3& f, const Vec3& p, Vec6* g, Mat6* K) {
  g->head<3>() += f;
  g->tail<3>() += p.cross(f);
  const Mat3 Sf = Skew(f);
  K->topRightCorner<3, 3>() -= Sf;
  K->bottomRightCorner<3, 3>() -= Skew(p) * Sf;
}

// Body velocities and accelerations of an element's nodes (zero for a fixed node).
void NodeVelocities(const Scatter& s, const Data& d, const RodElement& el, Vec12* eta_ab,
                    Vec12* acc_ab) {
  const int da = s.NodeDof(el.node_a), db = s.NodeDof(el.node_b);
  eta_ab->setZero();
  acc_ab->setZero();
  if (da >= 0) {
    eta_ab->head<6>() = d.v.segment<6>(da);
    acc_ab->head<6>() = d.vdot.segment<6>(da);
  }
  if (db >= 0) {
    eta_ab->tail<6>() = d.v.segment<6>(db);
    acc_ab->tail<6>() = d.vdot.segment<6>(db);
  }
}

bool AddRods(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  const bool tangent = o.assemble_matrix;
  for (std::size_t e = 0; e < m.elements.size(); ++e) {
    const RodElement& el = m.elements[e];
    const Section& sec = m.rods[static_cast<std::size_t>(el.rod)].section;
    const SE3& HA = d.H[static_cast<std::size_t>(el.node_a)];
    const SE3& HB = d.H[static_cast<std::size_t>(el.node_b)];
    const double rhoA = sec.inertia(0);
    const bool has_gravity = rhoA > 0.0 && m.gravity.squaredNorm() > 0.0;
    // Inertia (option A or B, method.md §2.5) and damping: forces and the M, C blocks.
    const bool has_inertia = o.dynamics && sec.inertia.squaredNorm() > 0.0;
    const bool has_damping =
        o.dynamics && (sec.damping.squaredNorm() > 0.0 || sec.rayleigh_stiffness > 0.0 ||
                       (has_inertia && sec.rayleigh_mass > 0.0));
    // Mass-proportional damping needs M_e in the residual as well.
    const bool inertia_tangent = tangent || (has_damping && sec.rayleigh_mass > 0.0);
    const bool exact_inertia = has_inertia && m.rod_inertia == RodInertia::kExact;
    // The kernels share d, T^-1(d), P(d) and the Gauss-point operators (RodGeometry).
    RodGeometry geo;
    CalcRodGeometry(HA, HB, d.w_ref[e], exact_inertia,
                    inertia_tangent && exact_inertia, &geo);
    // Internal forces and weight, with the stiffness already right-multiplied by the node
    // tangent operators when the iteration uses them.
    const int nodes[2] = {el.node_a, el.node_b};
    const bool node_tangent = tangent && o.use_node_tangent;
    const Mat6& TA = node_tangent && s.NodeDof(el.node_a) >= 0 ? s.NodeT(el.node_a) : kIdentity6;
    const Mat6& TB = node_tangent && s.NodeDof(el.node_b) >= 0 ? s.NodeT(el.node_b) : kIdentity6;
    Vec12 r;
    Mat12 stiffness;
    CalcRodConservative(el, sec, geo, HA,
                        has_gravity ? Vec3(o.load_factor * rhoA * m.gravity) : Vec3::Zero(),
                        node_tangent ? &TA : nullptr, node_tangent ? &TB : nullptr, &r,
                        tangent ? &stiffness : nullptr);
    const double rotation = geo.d.tail<3>().norm();
    if (!(rotation < m.max_element_rotation) || !r.allFinite()) {
      d.failed_element = static_cast<int>(e);
      d.failed_rotation = rotation;
      return false;
    }
    // Round-off in sigma = K (d - d0) / L: the translation of d comes from R_A^T (x_B - x_A),
    // whose absolute error is ~eps max(|x_A|, |x_B|) however short the element is.
    Vec6 magnitude = geo.d.cwiseAbs() + el.d0.cwiseAbs();
    magnitude.head<3>().array() += std::max(HA.x.norm(), HB.x.norm());
    s.Term((sec.stiffness.cwiseProduct(magnitude) / el.length).maxCoeff());
    // Option A without mass-proportional damping: the force alone for a residual, or with
    // c_M M_e + c_C C_t formed by the kernel (one set of Gauss-point products), the element
    // matrix scattered as one.
    const bool combined = exact_inertia && !(has_damping && sec.rayleigh_mass > 0.0);
    if (combined) {
      Vec12 eta_ab, acc_ab, force;
      NodeVelocities(s, d, el, &eta_ab, &acc_ab);
      Mat12 matrix, damping;
      if (tangent)
        CalcRodInertiaExactMatrix(el, sec, geo, eta_ab, acc_ab, o.c_mass, o.c_damping, &force,
                                  &matrix);
      else
        CalcRodInertiaExactForce(el, sec, geo, eta_ab, acc_ab, &force);
      r += force;
      if (has_damping) {
        if (tangent) damping.setZero();
        AddRodDamping(el, sec, geo.P, eta_ab, kZero12, &r, tangent ? &damping : nullptr);
      }
      if (tangent) {
        matrix.noalias() += o.c_stiffness * stiffness;
        if (has_damping) matrix.noalias() += o.c_damping * damping;
        s.ElementMatrix<2>(nodes, matrix);
      }
      s.Rows(s.NodeDof(el.node_a), r.head<6>());
      s.Rows(s.NodeDof(el.node_b), r.tail<6>());
      continue;
    }
    RodInertiaTerms ine;
    if (has_inertia || has_damping) {
      Vec12 eta_ab, acc_ab;
      NodeVelocities(s, d, el, &eta_ab, &acc_ab);
      if (has_inertia) {
        CalcRodInertia(m.rod_inertia, el, sec, geo, eta_ab, acc_ab, inertia_tangent, &ine);
        r += ine.force;
      }
      if (has_damping)
        AddRodDamping(el, sec, geo.P, eta_ab, ine.mass, &r, tangent ? &ine.gyroscopic : nullptr);
    }
    s.Rows(s.NodeDof(el.node_a), r.head<6>());
    s.Rows(s.NodeDof(el.node_b), r.tail<6>());
    if (tangent)
      s.NodeMatrix<2, true>(nodes, &stiffness, has_inertia ? &ine.mass : nullptr,
                            has_inertia || has_damping ? &ine.gyroscopic : nullptr);
  }
  return true;
}

void AddBodies(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  for (const RigidBody& b : m.bodies) {
    const int dof = s.NodeDof(b.node);
    if (dof < 0) continue;
    const SE3& H = d.H[static_cast<std::size_t>(b.node)];
    Vec6 g = Vec6::Zero();
    Mat6 K = Mat6::Zero();
    AddDeadForce(o.load_factor * b.mass * (H.R.transpose() * m.gravity), b.com, &g, &K);
    Vec6 r = -g;
    const int nodes[1] = {b.node};
    if (o.dynamics) {
      const Mat6 M = RigidMass(b);
      const Vec6 eta = d.v.segment<6>(dof);
      const Vec6 Meta = M * eta;
      const Vec6 M_vdot = M * d.vdot.segment<6>(dof);
      const Vec6 gyroscopic = ad(eta).transpose() * Meta;
      r += M_vdot - gyroscopic;
      // The scale of the convergence test is the size of the terms, not of their sum: for a
      // body without joints or loads the sum is the residual itself and tends to zero.
      s.Force(std::max({M_vdot.cwiseAbs().maxCoeff(), gyroscopic.cwiseAbs().maxCoeff(),
                        g.cwiseAbs().maxCoeff()}));
      if (o.assemble_matrix) {
        const Mat6 C = -(ad(eta).transpose() * M + Star(Meta));
        s.NodeMatrix<1>(nodes, &K, &M, &C);
      }
    } else {
      s.NodeMatrix<1>(nodes, &K, nullptr, nullptr);
    }
    s.Rows(dof, r);
  }
}

void AddPointLoads(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  for (const PointLoad& l : m.point_loads) {
    const int dof = s.NodeDof(l.node);
    if (dof < 0) continue;
    const double scale = o.load_factor * l.profile(o.time);
    if (scale == 0.0) continue;
    const SE3& H = d.H[static_cast<std::size_t>(l.node)];
    Vec6 g = Vec6::Zero();
    Mat6 K = Mat6::Zero();
    if (l.frame == LoadFrame::kWorld) {
      AddDeadForce(scale * (H.R.transpose() * l.force), l.point, &g, &K);
      const Vec3 mb = scale * (H.R.transpose() * l.moment);
      g.tail<3>() += mb;
      K.bottomRightCorner<3, 3>() -= Skew(mb);
    } else {
      g.head<3>() += scale * l.force;
      g.tail<3>() += scale * (l.point.cross(l.force) + l.moment);
    }
    s.Rows(dof, Vec6(-g));
    const int nodes[1] = {l.node};
    s.NodeMatrix<1>(nodes, &K, nullptr, nullptr);
  }
}

// Distributed and concentrated loads on rods (consistent with the exact interpolation).
void AddRodLoads(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  constexpr double kXi[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
  constexpr double kW[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
  for (const RodLoad& l : m.rod_loads) {
    const double scale = o.load_factor * l.profile(o.time);
    if (scale == 0.0) continue;
    const Rod& rod = m.rods[static_cast<std::size_t>(l.rod)];
    const int first = l.distributed ? rod.first_element : l.element;
    const int last = l.distributed ? rod.first_element + rod.num_elements - 1 : l.element;
    for (int e = first; e <= last; ++e) {
      const RodElement& el = m.elements[static_cast<std::size_t>(e)];
      const SE3& HA = d.H[static_cast<std::size_t>(el.node_a)];
      const Vec6 dd = CalcRodRelativeMotion(HA, d.H[static_cast<std::size_t>(el.node_b)],
                                            d.w_ref[static_cast<std::size_t>(e)]);
      Vec12 g = Vec12::Zero();
      Mat12 K = Mat12::Zero();
      if (l.distributed) {
        for (int i = 0; i < 3; ++i)
          AddRodSectionLoad(kXi[i], el.length * kW[i], HA, dd, l.frame, scale * l.force,
                            scale * l.moment, &g, &K);
      } else {
        AddRodSectionLoad(l.xi, 1.0, HA, dd, l.frame, scale * l.force, scale * l.moment, &g, &K);
      }
      s.Rows(s.NodeDof(el.node_a), Vec6(-g.head<6>()));
      s.Rows(s.NodeDof(el.node_b), Vec6(-g.tail<6>()));
      const int nodes[2] = {el.node_a, el.node_b};
      s.NodeMatrix<2>(nodes, &K, nullptr, nullptr);
    }
  }
}

// A free joint (no constraint rows, no coordinates) with springs and dampers on the logarithm
// of the relative motion of its frames F_A = H_A C_A, F_B = H_B C_B (docs/numerics.md, "Free
// joints"): delta = log(F_A^-1 F_B), energy 1/2 delta^T K delta, damping force D delta_dot.
// delta varies like a rod element's relative motion between the joint frames (method.md §2.3):
// d delta = P(delta) E [dh_A; dh_B], E = diag(Ad(C_A^-1), Ad(C_B^-1)), G = P E. Force
// G^T (K delta + D G eta_AB); stiffness G^T K G + E^T [D(-delta, s); D(delta, s)] P E with
// s = K delta (method.md §2.4); damping block G^T D G (its configuration derivative is
// omitted, as for rods).
void AddFreeJoint(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s, int joint) {
  const Joint& j = m.joints[static_cast<std::size_t>(joint)];
  const bool has_damping = o.dynamics && j.damping.squaredNorm() > 0.0;
  if (j.stiffness.squaredNorm() == 0.0 && !has_damping) return;
  const int nodes[2] = {j.node_a, j.node_b};
  const Vec6 delta = CalcFreeJointDeflection(m, d, joint);
  const Mat6x12 P = CalcRodP(delta);
  const Mat6 EA = Ad(j.offset_a.Inverse()), EB = Ad(j.offset_b.Inverse());
  Mat6x12 G;
  G.leftCols<6>().noalias() = P.leftCols<6>() * EA;
  G.rightCols<6>().noalias() = P.rightCols<6>() * EB;
  const Vec6 sigma = j.stiffness.cwiseProduct(delta);
  Vec6 f = sigma;
  if (has_damping) {
    Vec12 eta = Vec12::Zero();
    if (s.NodeDof(j.node_a) >= 0) eta.head<6>() = d.v.segment<6>(s.NodeDof(j.node_a));
    if (s.NodeDof(j.node_b) >= 0) eta.tail<6>() = d.v.segment<6>(s.NodeDof(j.node_b));
    f += j.damping.cwiseProduct(G * eta);
  }
  const Vec12 g = G.transpose() * f;
  s.Rows(s.NodeDof(j.node_a), g.head<6>());
  s.Rows(s.NodeDof(j.node_b), g.tail<6>());
  if (!o.assemble_matrix) return;
  Mat12 K = G.transpose() * j.stiffness.asDiagonal() * G;
  Mat6x12 geo_top = DTSE3InvT(-delta, sigma) * P, geo_bottom = DTSE3InvT(delta, sigma) * P;
  for (Mat6x12* rows : {&geo_top, &geo_bottom}) {
    rows->leftCols<6>() = rows->leftCols<6>() * EA;
    rows->rightCols<6>() = rows->rightCols<6>() * EB;
  }
  K.topRows<6>() += EA.transpose() * geo_top;
  K.bottomRows<6>() += EB.transpose() * geo_bottom;
  if (has_damping) {
    const Mat12 C = G.transpose() * j.damping.asDiagonal() * G;
    s.NodeMatrix<2>(nodes, &K, nullptr, &C);
  } else {
    s.NodeMatrix<2>(nodes, &K, nullptr, nullptr);
  }
}

void AddJoints(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  for (std::size_t jj = 0; jj < m.joints.size(); ++jj) {
    const Joint& j = m.joints[jj];
    const int ji = static_cast<int>(jj);
    const int k = j.k();
    const Mat6X A = JointCurrentBasis(m, d, ji);
    // In dynamics the coordinates of group joints (spherical, planar, free) retract as
    // H_J = H_J,n exp(A_J x), x = h dq_J, so their matrix columns carry the subgroup's tangent
    // operator A_J^T T(A_J x) A_J (method.md §5.2), stored after the node tangents by the
    // integrator. Abelian and universal joints retract additively: no tangent.
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6> TJ =
        Mat6::Identity().topLeftCorner(k, k);
    if (o.use_node_tangent && !JointHasGlobalCoordinates(j.type) &&
        d.node_tangent.size() > m.nodes.size() + jj)
      TJ = d.node_tangent[m.nodes.size() + jj].topLeftCorner(k, k);
    if (j.row >= 0) {
      const SE3 HA = j.node_a == kGround ? SE3::Identity() : d.H[static_cast<std::size_t>(j.node_a)];
      const SE3 HB = j.node_b == kGround ? SE3::Identity() : d.H[static_cast<std::size_t>(j.node_b)];
      const SE3 CBinv = j.offset_b.Inverse();
      const Vec6 phi = JointConstraint(m, d, ji);
      const Mat6 Tinv = TSE3Inv(phi);
      const Eigen::Ref<const Eigen::VectorXd> lam = d.lambda.segment(j.row, 6);
      d.residual.segment<6>(m.nv + j.row) += o.s_constraints * phi;
      // B_A = -T^-1 Ad(C_B^-1 H_B^-1 H_A), B_B = T^-1 Ad(C_B^-1): the residual gets B^T lambda
      // as transposed products applied to the vector (the same with and without the matrix),
      // the matrix the blocks themselves.
      const Vec6 tl = Tinv.transpose() * lam;
      const int da = s.NodeDof(j.node_a), db = s.NodeDof(j.node_b);  // -1: ground or fixed
      // The blocks B_A, B_B, B_J of CalcJointGradient (the matrix needs the node blocks).
      Mat6 BA, BB;
      Mat6X BJ;
      CalcJointGradient(j, HA, HB, phi, Tinv, A, o.assemble_matrix && da >= 0 ? &BA : nullptr,
                        o.assemble_matrix && db >= 0 ? &BB : nullptr, k > 0 ? &BJ : nullptr);
      if (da >= 0) {
        const SE3 GA = CBinv * HB.Inverse() * HA;
        d.residual.segment<6>(da).noalias() -= o.s_rows * AdTransposeTimes(GA, tl);
        if (o.assemble_matrix) s.GradientMatrix(j.row, da, BA, &s.NodeT(j.node_a));
      }
      if (db >= 0) {
        d.residual.segment<6>(db).noalias() += o.s_rows * AdTransposeTimes(CBinv, tl);
        if (o.assemble_matrix) s.GradientMatrix(j.row, db, BB, &s.NodeT(j.node_b));
      }
      if (k > 0) s.Gradient(j.row, j.coord, Mat6X(BJ * TJ), nullptr, lam);
    }
    if (j.type == JointType::kFree) AddFreeJoint(m, d, o, s, ji);
    if (k == 0) continue;
    // Joint springs, dampers and drives act on the coordinates.
    const int q0 = j.coord - m.nv_nodes;
    const auto alpha = d.q_joint.segment(q0, k);
    const auto alpha_dot = d.v.segment(j.coord, k);
    Vec6 rest = j.rest, rest_rate = Vec6::Zero();
    ProfileValue drive{};
    if (j.drive != DriveKind::kNone) drive = j.drive_profile.Eval(o.time);
    if (j.drive == DriveKind::kSeriesElastic) {
      rest(j.drive_coord) += o.load_factor * drive.value;
      rest_rate(j.drive_coord) = o.load_factor * drive.rate;
    }
    Eigen::Matrix<double, 6, 1> f = Vec6::Zero();
    Mat6 Kq = Mat6::Zero(), Dq = Mat6::Zero();
    if (JointHasGlobalCoordinates(j.type)) {
      for (int c = 0; c < k; ++c) {
        s.Term(j.stiffness(c) * (std::abs(alpha(c)) + std::abs(rest(c))));
        f(c) = j.stiffness(c) * (alpha(c) - rest(c));
        Kq(c, c) = j.stiffness(c);
        if (o.dynamics) {
          f(c) += j.damping(c) * (alpha_dot(c) - rest_rate(c));
          Dq(c, c) = j.damping(c);
        }
      }
    } else if (j.stiffness.head(k).squaredNorm() > 0.0 || j.damping.head(k).squaredNorm() > 0.0) {
      // Group joints: energy 1/2 delta^T K delta, delta = A^T log(H_J) (method.md §4.5).
      const Vec6 xi = LogSE3(d.HJ[jj]);
      const Mat6 Ti = TSE3Inv(xi);
      const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1> delta = A.transpose() * xi;
      const Vec6 Kd_alg = A * j.stiffness.head(k).cwiseProduct(delta);
      f.head(k) = A.transpose() * Ti.transpose() * Kd_alg;
      Kq.topLeftCorner(k, k) =
          A.transpose() * (Ti.transpose() * A * j.stiffness.head(k).asDiagonal() * A.transpose() * Ti +
                           DTSE3InvT(xi, Kd_alg) * Ti) * A;
      if (o.dynamics) {
        for (int c = 0; c < k; ++c) {
          f(c) += j.damping(c) * alpha_dot(c);
          Dq(c, c) = j.damping(c);
        }
      }
    }
    if (j.drive == DriveKind::kForce) f(j.drive_coord) -= o.load_factor * drive.value;
    if (j.drive == DriveKind::kPrescribed) {
      const double lam_act = d.lambda(j.drive_row);
      f(j.drive_coord) += lam_act;  // B_act^T lambda_act
      d.residual(m.nv + j.drive_row) +=
          o.s_constraints * (alpha(j.drive_coord) - o.load_factor * drive.value);
      s.Block(j.coord + j.drive_coord, m.nv + j.drive_row, Eigen::Matrix<double, 1, 1>::Ones(),
              o.s_rows * o.s_multipliers);
      s.Block(m.nv + j.drive_row, j.coord + j.drive_coord, Eigen::Matrix<double, 1, 1>::Ones(),
              o.s_constraints);
    }
    s.Rows(j.coord, f.head(k));
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6> S =
        o.c_stiffness * Kq.topLeftCorner(k, k) * TJ + o.c_damping * Dq.topLeftCorner(k, k);
    s.Block(j.coord, j.coord, S, o.s_rows);
  }
}

}  // namespace

bool JointHasGlobalCoordinates(JointType t) {
  return t != JointType::kSpherical && t != JointType::kPlanar && t != JointType::kFree;
}

SE3 JointRelativeFrame(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  if (!JointHasGlobalCoordinates(j.type)) return data.HJ[static_cast<std::size_t>(joint)];
  const auto alpha = data.q_joint.segment(j.coord - model.nv_nodes, j.k());
  if (j.type == JointType::kUniversal)
    return ExpSE3(j.basis.col(0) * alpha(0)) * ExpSE3(j.basis.col(1) * alpha(1));
  return ExpSE3(j.basis * alpha);
}

Mat6X JointCurrentBasis(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  if (j.type != JointType::kUniversal) return j.basis;
  const double a2 = data.q_joint(j.coord - model.nv_nodes + 1);
  Mat6X A = j.basis;
  A.col(0) = Ad(ExpSE3(-a2 * j.basis.col(1))) * j.basis.col(0);
  return A;
}

Vec6 JointConstraint(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const SE3 HA = j.node_a == kGround ? SE3::Identity() : data.H[static_cast<std::size_t>(j.node_a)];
  const SE3 HB = j.node_b == kGround ? SE3::Identity() : data.H[static_cast<std::size_t>(j.node_b)];
  const SE3 G = j.offset_a.Inverse() * HA.Inverse() * HB * j.offset_b;
  return LogSE3(JointRelativeFrame(model, data, joint).Inverse() * G);
}

Vec6 CalcFreeJointDeflection(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const SE3 HA = j.node_a == kGround ? SE3::Identity() : data.H[static_cast<std::size_t>(j.node_a)];
  const SE3 HB = j.node_b == kGround ? SE3::Identity() : data.H[static_cast<std::size_t>(j.node_b)];
  return LogSE3(j.offset_a.Inverse() * HA.Inverse() * HB * j.offset_b);
}

double JointDriveEffort(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  switch (j.drive) {
    case DriveKind::kNone:
      return 0.0;
    case DriveKind::kPrescribed:
      return -data.lambda(j.drive_row);
    case DriveKind::kForce:
      return j.drive_profile(data.time);
    case DriveKind::kSeriesElastic: {
      const int c = j.coord + j.drive_coord;
      const ProfileValue q = j.drive_profile.Eval(data.time);
      const double alpha = data.q_joint(c - model.nv_nodes);
      return j.stiffness(j.drive_coord) * (q.value + j.rest(j.drive_coord) - alpha) +
             j.damping(j.drive_coord) * (q.rate - data.v(c));
    }
  }
  return 0.0;
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
    const int k = j.k();
    if (k == 0) continue;
    if (JointHasGlobalCoordinates(j.type)) {
      data.q_joint.segment(j.coord - model.nv_nodes, k) += dx.segment(j.coord, k);
    } else {
      data.HJ[jj] = data.HJ[jj] * ExpSE3(j.basis * dx.segment(j.coord, k));
      data.q_joint.segment(j.coord - model.nv_nodes, k) += dx.segment(j.coord, k);
    }
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
  if (options.assemble_matrix) data.matrix.SetZero();
  data.failed_element = -1;
  data.force_scale = 0.0;
  data.term_scale = 0.0;
  Scatter s(model, data, options);
  if (!AddRods(model, data, options, s)) return false;
  AddBodies(model, data, options, s);
  AddPointLoads(model, data, options, s);
  AddRodLoads(model, data, options, s);
  AddJoints(model, data, options, s);
  // Redundant constraint rows (found at build time): the row becomes dmu_r = -lambda_r / s_L,
  // which holds their multipliers at zero.
  for (int r : model.redundant_rows) {
    const int g = model.nv + r;
    data.residual(g) = data.lambda(r) / options.s_multipliers;
    if (!options.assemble_matrix) continue;
    const int p = model.permutation[static_cast<std::size_t>(g)];
    const int lo = std::max(0, p - data.matrix.lower_bandwidth());
    const int hi = std::min(data.matrix.size() - 1, p + data.matrix.upper_bandwidth());
    for (int c = lo; c <= hi; ++c) data.matrix.At(p, c) = 0.0;
    data.matrix.At(p, p) = 1.0;
  }
  return data.residual.allFinite();
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
