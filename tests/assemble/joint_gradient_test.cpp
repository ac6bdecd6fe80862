// Finite-difference checks of the assembled iteration matrix (assemble.h, elements/rigid_body.h,
// docs/theory.md §4.5): constraint rows and their transposes for every joint type away from
// phi = 0, and the equilibrium rows (stiffness, mass and damping blocks) of rigid bodies, point
// loads and joint springs/dampers. Every derivative is taken through the retraction of assemble.h
// (right-trivialised node increments, additive coordinate increments), by central differences.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/build/model_builder.h"

namespace screwfem::joint_gradient_test {
namespace {

constexpr double kEps = 1e-6;  // central-difference step

// Scales that differ from 1 so that a misplaced scale factor shows up.
constexpr double kConstraintScale = 7.0;  // s_C = s_L (statics convention)
constexpr double kRowScale = 1.0;         // s_R in statics

std::mt19937 Rng(unsigned salt) { return std::mt19937(4711u + salt); }

Vec6 RandomVec6(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Vec6 v;
  for (int i = 0; i < 6; ++i) v(i) = u(rng);
  return v;
}

SE3 RandomFrame(std::mt19937& rng) {
  const Vec6 xi = RandomVec6(rng, 1.0);
  return ExpSE3(xi);
}

// Entry (i, j) of the assembled matrix in global order; zero outside the band.
double MatrixEntry(const Model& m, const Data& d, int i, int j) {
  const int pi = m.permutation[static_cast<std::size_t>(i)];
  const int pj = m.permutation[j];
  return d.matrix.InBand(pi, pj) ? d.matrix.At(pi, pj) : 0.0;
}

Eigen::MatrixXd GlobalMatrix(const Model& m, const Data& d) {
  const int n = m.num_unknowns();
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = MatrixEntry(m, d, i, j);
  return A;
}

struct Snapshot {
  std::vector<SE3> H, HJ;
  Eigen::VectorXd q_joint, v, vdot, lambda;
};
Snapshot Take(const Data& d) { return {d.H, d.HJ, d.q_joint, d.v, d.vdot, d.lambda}; }
void Put(const Snapshot& s, Data& d) {
  d.H = s.H;
  d.HJ = s.HJ;
  d.q_joint = s.q_joint;
  d.v = s.v;
  d.vdot = s.vdot;
  d.lambda = s.lambda;
}

// Central difference of the residual with respect to each velocity-layout unknown, perturbed
// by `perturb(data, i, e)`. Columns [0, nv).
template <typename Perturb>
Eigen::MatrixXd ResidualDerivative(const Model& m, Data& d, const AssemblyOptions& o,
                                   Perturb perturb) {
  const Snapshot base = Take(d);
  Eigen::MatrixXd J(m.num_unknowns(), m.nv);
  for (int i = 0; i < m.nv; ++i) {
    Put(base, d);
    perturb(d, i, kEps);
    Assemble(m, d, o);
    const Eigen::VectorXd rp = d.residual;
    Put(base, d);
    perturb(d, i, -kEps);
    Assemble(m, d, o);
    J.col(i) = (rp - d.residual) / (2.0 * kEps);
  }
  Put(base, d);
  return J;
}

Eigen::MatrixXd RetractionDerivative(const Model& m, Data& d, const AssemblyOptions& o) {
  return ResidualDerivative(m, d, o, [&m](Data& data, int i, double e) {
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(m.nv);
    dx(i) = e;
    Retract(m, data, dx);
  });
}

double RelativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

// --- models ----------------------------------------------------------------------------------

// Axis data shared by all joint models (unit, not aligned with any world axis).
const Vec3 kAxis = Vec3(1.0, 2.0, 2.0).normalized();
const Vec3 kAxis2 = Vec3(2.0, -1.0, 0.0).normalized();  // orthogonal to kAxis
constexpr double kPitch = 0.3;

void AddBody(ModelBuilder& b, NodeId node, const std::string& name) {
  Mat3 J;
  J << 0.3, 0.01, -0.02, 0.01, 0.2, 0.03, -0.02, 0.03, 0.25;
  b.AddRigidBody(name, node, 1.7, Vec3(0.2, -0.3, 0.1), J);
}

// Two rigid bodies at random frames; joint "g" of `type` from the ground to body A and
// joint "ab" of the same type from A to B, both at generic points. With `reverse_ground`
// the ground joint has the ground on side b instead.
Model MakeJointModel(JointType type, bool reverse_ground) {
  auto rng = Rng(static_cast<unsigned>(type));
  ModelBuilder b;
  const NodeId na = b.AddNode(RandomFrame(rng), "A");
  const NodeId nb = b.AddNode(RandomFrame(rng), "B");
  AddBody(b, na, "body A");
  AddBody(b, nb, "body B");
  if (reverse_ground)
    b.AddJointAt("g", type, na, kGround, Vec3(0.3, -0.4, 0.5), kAxis, kAxis2, kPitch);
  else
    b.AddJointAt("g", type, kGround, na, Vec3(0.3, -0.4, 0.5), kAxis, kAxis2, kPitch);
  b.AddJointAt("ab", type, na, nb, Vec3(-0.2, 0.6, 0.1), kAxis, kAxis2, kPitch);
  return b.Build();
}

// Moves every unknown by a random amount so that the constraints are violated (|phi| ~ 0.5)
// and the joint coordinates are nonzero.
void Disturb(const Model& m, Data& d, unsigned salt) {
  auto rng = Rng(100 + salt);
  std::uniform_real_distribution<double> u(-0.35, 0.35);
  Eigen::VectorXd dx(m.nv);
  for (int i = 0; i < m.nv; ++i) dx(i) = u(rng);
  Retract(m, d, dx);
}

double MaxPhi(const Model& m, const Data& d) {
  double r = 0.0;
  for (std::size_t j = 0; j < m.joints.size(); ++j)
    if (m.joints[j].row >= 0)
      r = std::max(r, JointConstraint(m, d, static_cast<int>(j)).cwiseAbs().maxCoeff());
  return r;
}

AssemblyOptions StaticsOptions() {
  AssemblyOptions o;
  o.s_rows = kRowScale;
  o.s_constraints = o.s_multipliers = kConstraintScale;
  return o;
}

const JointType kAllTypes[] = {JointType::kRevolute,    JointType::kPrismatic, JointType::kHelical,
                               JointType::kCylindrical, JointType::kSpherical, JointType::kPlanar,
                               JointType::kUniversal,   JointType::kFixed,     JointType::kFree};

// --- constraint gradient ---------------------------------------------------------------------

TEST(JointGradient, ConstraintRowsEqualFiniteDifferenceOfPhiForEveryJointTypeAwayFromPhiZero) {
  for (JointType type : kAllTypes) {
    for (bool reverse : {false, true}) {
      SCOPED_TRACE(std::string(JointTypeName(type)) + (reverse ? " (ground on side b)" : ""));
      const Model m = MakeJointModel(type, reverse);
      ASSERT_TRUE(m.redundant_rows.empty());
      Data d = MakeData(m);
      Disturb(m, d, static_cast<unsigned>(type));
      if (type != JointType::kFree) {
        EXPECT_GT(MaxPhi(m, d), 0.2);
        EXPECT_LT(MaxPhi(m, d), 1.5);
      }
      const AssemblyOptions o = StaticsOptions();
      ASSERT_TRUE(Assemble(m, d, o));
      const Eigen::MatrixXd A = GlobalMatrix(m, d);
      const Eigen::VectorXd residual = d.residual;
      const Eigen::MatrixXd fd = RetractionDerivative(m, d, o);
      if (m.nc == 0) continue;
      // Constraint rows: s_C B (B = d phi / d(dx)).
      const Eigen::MatrixXd B = A.bottomLeftCorner(m.nc, m.nv) / kConstraintScale;
      const Eigen::MatrixXd B_fd = fd.bottomRows(m.nc) / kConstraintScale;
      EXPECT_LT(RelativeError(B, B_fd), 1e-7) << "B =\n" << B << "\nFD =\n" << B_fd;
      // Multiplier columns of the equilibrium rows: s_R s_L B^T.
      const Eigen::MatrixXd Bt = A.topRightCorner(m.nv, m.nc) / (kRowScale * kConstraintScale);
      EXPECT_LT((Bt - B.transpose()).cwiseAbs().maxCoeff(), 1e-13);
      // The constraint residual rows hold s_C phi.
      for (std::size_t j = 0; j < m.joints.size(); ++j) {
        const Joint& jt = m.joints[j];
        if (jt.row < 0) continue;
        const Vec6 phi = JointConstraint(m, d, static_cast<int>(j));
        EXPECT_LT((residual.segment<6>(m.nv + jt.row) - kConstraintScale * phi).norm(), 1e-13);
      }
    }
  }
}

// In dynamics the node columns of the constraint rows are B T(xi) for the configuration
// H = H_n exp(xi): the derivative with respect to the correction of xi (docs/architecture.md, "One time step"). The
// coordinates of spherical, planar and free joints retract the same way, H_J = H_Jn exp(A_J x),
// and their columns carry A_J^T T(A_J x) A_J (stored after the node tangents, as the
// integrator does); abelian and universal coordinates retract additively.
TEST(JointGradient,
     ConstraintRowsWithTangentOperatorEqualFiniteDifferenceInExponentialCoordinates) {
  for (JointType type : kAllTypes) {
    if (type == JointType::kFree) continue;
    SCOPED_TRACE(JointTypeName(type));
    Model m = MakeJointModel(type, false);
    for (Joint& jt : m.joints) jt.stiffness << 3.0, 5.0, 7.0, 11.0, 13.0, 17.0;  // springs
    Data d = MakeData(m);
    Disturb(m, d, 7u + static_cast<unsigned>(type));
    const Snapshot start = Take(d);
    auto rng = Rng(200 + static_cast<unsigned>(type));
    Eigen::VectorXd xi(m.nv);
    for (int i = 0; i < m.nv; ++i) xi(i) = std::uniform_real_distribution<double>(-0.4, 0.4)(rng);
    auto configure = [&](const Eigen::VectorXd& x) {
      Put(start, d);
      Retract(m, d, x);
    };
    configure(xi);
    d.node_tangent.assign(m.nodes.size() + m.joints.size(), Mat6::Identity());
    for (const Node& n : m.nodes)
      d.node_tangent[static_cast<std::size_t>(&n - m.nodes.data())] = TSE3(xi.segment<6>(n.dof));
    for (std::size_t j = 0; j < m.joints.size(); ++j) {
      const Joint& jt = m.joints[j];
      if (JointHasGlobalCoordinates(jt.type) || jt.k() == 0) continue;
      const Vec6 xj = jt.basis * xi.segment(jt.coord, jt.k());
      d.node_tangent[m.nodes.size() + j].topLeftCorner(jt.k(), jt.k()) =
          jt.basis.transpose() * TSE3(xj) * jt.basis;
    }
    AssemblyOptions o = StaticsOptions();
    o.use_node_tangent = true;
    ASSERT_TRUE(Assemble(m, d, o));
    const Eigen::MatrixXd A = GlobalMatrix(m, d);
    Eigen::MatrixXd fd(m.num_unknowns(), m.nv);
    for (int i = 0; i < m.nv; ++i) {
      Eigen::VectorXd x = xi;
      x(i) += kEps;
      configure(x);
      Assemble(m, d, o);
      const Eigen::VectorXd rp = d.residual;
      x(i) -= 2.0 * kEps;
      configure(x);
      Assemble(m, d, o);
      fd.col(i) = (rp - d.residual) / (2.0 * kEps);
    }
    // Constraint rows, and the spring rows of the joint coordinates (lambda = 0).
    EXPECT_LT(RelativeError(A.bottomLeftCorner(m.nc, m.nv), fd.bottomRows(m.nc)), 1e-7);
    const int nq = m.nv - m.nv_nodes;
    if (nq > 0) {
      EXPECT_LT(RelativeError(A.block(m.nv_nodes, 0, nq, m.nv), fd.block(m.nv_nodes, 0, nq, m.nv)),
                1e-7);
    }
  }
}

// --- equilibrium rows --------------------------------------------------------------------------

// The stiffness block (rows and columns [0, nv)) against the finite difference of the
// equilibrium residual, with lambda = 0 (d(B^T lambda)/dq is deliberately not assembled).
void ExpectStiffnessMatchesFiniteDifference(const Model& m, Data& d, double tol = 1e-7) {
  d.lambda.setZero();
  const AssemblyOptions o = StaticsOptions();
  ASSERT_TRUE(Assemble(m, d, o));
  const Eigen::MatrixXd K = GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv);
  const Eigen::MatrixXd K_fd = RetractionDerivative(m, d, o).topRows(m.nv);
  EXPECT_GT(K_fd.cwiseAbs().maxCoeff(), 1e-3) << "the test model has no stiffness to check";
  EXPECT_LT(RelativeError(K, K_fd), tol) << "K =\n" << K << "\nFD =\n" << K_fd;
}

TEST(EquilibriumTangent, GravityOnRigidBodiesWithOffsetCentreOfMass) {
  ModelBuilder b;
  auto rng = Rng(1);
  const NodeId na = b.AddNode(RandomFrame(rng));
  const NodeId nb = b.AddNode(RandomFrame(rng));
  AddBody(b, na, "A");
  AddBody(b, nb, "B");
  b.AddJointAt("g", JointType::kSpherical, kGround, na, Vec3(0.1, 0.2, 0.3));
  b.AddJointAt("ab", JointType::kRevolute, na, nb, Vec3(0.4, -0.2, 0.3), kAxis);
  b.SetGravity(Vec3(1.0, -9.81, 2.5));
  const Model m = b.Build();
  Data d = MakeData(m);
  Disturb(m, d, 11);
  ExpectStiffnessMatchesFiniteDifference(m, d);
}

TEST(EquilibriumTangent, WorldAndFollowerPointLoadsAtBodyPoints) {
  for (LoadFrame frame : {LoadFrame::kWorld, LoadFrame::kBody}) {
    SCOPED_TRACE(frame == LoadFrame::kWorld ? "world (dead) load" : "follower load");
    ModelBuilder b;
    auto rng = Rng(2);
    const NodeId n = b.AddNode(RandomFrame(rng));
    AddBody(b, n, "A");
    b.AddJointAt("g", JointType::kCylindrical, kGround, n, Vec3(0.1, 0.2, 0.3), kAxis);
    PointLoad load;
    load.node = n;
    load.point = Vec3(0.7, -0.4, 0.25);
    load.frame = frame;
    load.force = Vec3(3.0, -2.0, 5.0);
    load.moment = Vec3(-1.0, 0.5, 2.0);
    load.profile = Profile::Constant(0.8);
    b.AddPointLoad(load);
    const Model m = b.Build();
    Data d = MakeData(m);
    Disturb(m, d, 12);
    d.lambda.setZero();
    const AssemblyOptions o = StaticsOptions();
    ASSERT_TRUE(Assemble(m, d, o));
    const Eigen::MatrixXd K = GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv);
    const Eigen::MatrixXd K_fd = RetractionDerivative(m, d, o).topRows(m.nv);
    EXPECT_LT(RelativeError(K, K_fd), 1e-7) << "K =\n" << K << "\nFD =\n" << K_fd;
    // A follower load has no stiffness; a dead load has.
    if (frame == LoadFrame::kBody) {
      EXPECT_LT(K_fd.cwiseAbs().maxCoeff(), 1e-8);
    } else {
      EXPECT_GT(K_fd.cwiseAbs().maxCoeff(), 1.0);
    }
    // The generalised force itself: world force F at body point p and world moment.
    const SE3& H = d.H[n];
    const Vec3 f = frame == LoadFrame::kWorld ? Vec3(H.R.transpose() * load.force) : load.force;
    const Vec3 mom = frame == LoadFrame::kWorld ? Vec3(H.R.transpose() * load.moment) : load.moment;
    Vec6 g;
    g.head<3>() = 0.8 * f;
    g.tail<3>() = 0.8 * (load.point.cross(f) + mom);
    // Residual = inertia + internal - external (+ B^T lambda = 0); the body has no gravity.
    EXPECT_LT((d.residual.segment<6>(m.nodes[0].dof) + g).norm(), 1e-13);
  }
}

TEST(EquilibriumTangent, SoftJointSpringsOnCoordinatesOfEveryJointType) {
  for (JointType type : kAllTypes) {
    if (type == JointType::kFixed || type == JointType::kFree) continue;  // no coordinates
    SCOPED_TRACE(JointTypeName(type));
    ModelBuilder b;
    auto rng = Rng(30 + static_cast<unsigned>(type));
    const NodeId na = b.AddNode(RandomFrame(rng));
    const NodeId nb = b.AddNode(RandomFrame(rng));
    AddBody(b, na, "A");
    AddBody(b, nb, "B");
    const JointId jg =
        b.AddJointAt("g", type, kGround, na, Vec3(0.3, -0.4, 0.5), kAxis, kAxis2, kPitch);
    const JointId jab =
        b.AddJointAt("ab", type, na, nb, Vec3(-0.2, 0.6, 0.1), kAxis, kAxis2, kPitch);
    for (JointId j : {jg, jab}) {
      Joint& jt = b.model().joints[j];
      jt.stiffness << 3.0, 5.0, 7.0, 11.0, 13.0, 17.0;
      jt.rest << 0.1, -0.2, 0.3, -0.1, 0.2, 0.05;
    }
    const Model m = b.Build();
    Data d = MakeData(m);
    Disturb(m, d, 13);
    // Large joint deflections make the group-joint spring (log of H_J) strongly nonlinear.
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(m.nv);
    for (int i = m.nv_nodes; i < m.nv; ++i) dx(i) = 0.6 * std::cos(3.0 * i);
    Retract(m, d, dx);
    d.lambda.setZero();
    const AssemblyOptions o = StaticsOptions();
    ASSERT_TRUE(Assemble(m, d, o));
    const Eigen::MatrixXd A = GlobalMatrix(m, d);
    const Eigen::MatrixXd fd = RetractionDerivative(m, d, o);
    const int nq = m.nv - m.nv_nodes;
    const Eigen::MatrixXd Kq = A.block(m.nv_nodes, m.nv_nodes, nq, nq);
    const Eigen::MatrixXd Kq_fd = fd.block(m.nv_nodes, m.nv_nodes, nq, nq);
    EXPECT_GT(Kq_fd.cwiseAbs().maxCoeff(), 1.0);
    EXPECT_LT(RelativeError(Kq, Kq_fd), 1e-7) << "K =\n" << Kq << "\nFD =\n" << Kq_fd;
    // The springs act on the coordinates only: no coupling to the node unknowns.
    EXPECT_LT(fd.block(m.nv_nodes, 0, nq, m.nv_nodes).cwiseAbs().maxCoeff(), 1e-8);
  }
}

// The spring force on the coordinates is the gradient of the spring energy of CalcEnergy
// (force = dV/d(alpha) through the retraction), for abelian and group joints alike.
double SpringEnergy(const Model& m, const Data& d) {
  double e = 0.0;
  for (std::size_t jj = 0; jj < m.joints.size(); ++jj) {
    const Joint& j = m.joints[jj];
    const int k = j.k();
    if (k == 0) continue;
    if (JointHasGlobalCoordinates(j.type)) {
      for (int c = 0; c < k; ++c) {
        const double delta = d.q_joint(j.coord - m.nv_nodes + c) - j.rest(c);
        e += 0.5 * j.stiffness(c) * delta * delta;
      }
    } else {
      const Vec6 xi = LogSE3(d.HJ[jj]);
      for (int c = 0; c < k; ++c) {
        const double delta = j.basis.col(c).dot(xi);
        e += 0.5 * j.stiffness(c) * delta * delta;
      }
    }
  }
  return e;
}

TEST(EquilibriumTangent, JointSpringForceIsTheGradientOfTheSpringEnergy) {
  for (JointType type : {JointType::kRevolute, JointType::kHelical, JointType::kCylindrical,
                         JointType::kUniversal, JointType::kSpherical, JointType::kPlanar}) {
    SCOPED_TRACE(JointTypeName(type));
    ModelBuilder b;
    auto rng = Rng(50 + static_cast<unsigned>(type));
    const NodeId n = b.AddNode(RandomFrame(rng));
    AddBody(b, n, "A");
    const JointId j =
        b.AddJointAt("g", type, kGround, n, Vec3(0.3, -0.4, 0.5), kAxis, kAxis2, kPitch);
    Joint& jt = b.model().joints[j];
    jt.stiffness << 3.0, 5.0, 7.0, 11.0, 13.0, 17.0;
    if (JointHasGlobalCoordinates(type)) jt.rest << 0.1, -0.2, 0.3, -0.1, 0.2, 0.05;
    const Model m = b.Build();
    Data d = MakeData(m);
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(m.nv);
    for (int i = m.nv_nodes; i < m.nv; ++i) dx(i) = 0.7 * std::sin(2.0 * i + 1.0);
    Retract(m, d, dx);
    EXPECT_NEAR(SpringEnergy(m, d), CalcEnergy(m, d).spring, 1e-14);
    ASSERT_TRUE(Assemble(m, d, StaticsOptions()));
    const Eigen::VectorXd f = d.residual.segment(m.nv_nodes, m.nv - m.nv_nodes);
    const Snapshot base = Take(d);
    for (int i = m.nv_nodes; i < m.nv; ++i) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(m.nv);
      e(i) = kEps;
      Put(base, d);
      Retract(m, d, e);
      const double vp = SpringEnergy(m, d);
      Put(base, d);
      Retract(m, d, -e);
      const double vm = SpringEnergy(m, d);
      EXPECT_NEAR(f(i - m.nv_nodes), (vp - vm) / (2.0 * kEps), 1e-7 * std::max(1.0, f.norm()));
    }
  }
}

// A free joint's springs act on delta = log(C_A^-1 H_A^-1 H_B C_B) between the nodes (no
// coordinates, no constraint rows): the node force is the gradient of the spring energy of
// CalcEnergy through the retraction, and the stiffness block its derivative, at large
// deflections (|delta| ~ 1), with the ground on either side and between two bodies.
TEST(EquilibriumTangent, FreeJointSpringForceIsTheEnergyGradientAndItsTangentMatches) {
  ModelBuilder b;
  auto rng = Rng(60);
  const NodeId na = b.AddNode(RandomFrame(rng));
  const NodeId nb = b.AddNode(RandomFrame(rng));
  AddBody(b, na, "A");
  AddBody(b, nb, "B");
  const JointId j1 = b.AddJointAt("g", JointType::kFree, kGround, na, Vec3(0.3, -0.4, 0.5));
  const JointId j2 = b.AddJointAt("ab", JointType::kFree, na, nb, Vec3(-0.2, 0.6, 0.1));
  const JointId j3 = b.AddJointAt("bg", JointType::kFree, nb, kGround, Vec3(0.1, 0.1, -0.3));
  for (JointId j : {j1, j2, j3}) b.model().joints[j].stiffness << 3.0, 5.0, 7.0, 11.0, 13.0, 17.0;
  const Model m = b.Build();
  EXPECT_EQ(m.nc, 0);
  EXPECT_EQ(m.nv, 12);
  Data d = MakeData(m);
  Disturb(m, d, 61);
  for (JointId j : {j1, j2, j3}) EXPECT_GT(CalcFreeJointDeflection(m, d, j).norm(), 0.3);
  ExpectStiffnessMatchesFiniteDifference(m, d);
  ASSERT_TRUE(Assemble(m, d, StaticsOptions()));
  const Eigen::VectorXd f = d.residual.head(m.nv);
  const Snapshot base = Take(d);
  for (int i = 0; i < m.nv; ++i) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(m.nv);
    e(i) = kEps;
    Put(base, d);
    Retract(m, d, e);
    const double vp = CalcEnergy(m, d).spring;
    Put(base, d);
    Retract(m, d, -e);
    const double vm = CalcEnergy(m, d).spring;
    EXPECT_NEAR(f(i), (vp - vm) / (2.0 * kEps), 1e-7 * std::max(1.0, f.norm()));
  }
}

// --- mass and damping blocks (dynamics) ----------------------------------------------------------

Model MakeMovingModel() {
  ModelBuilder b;
  auto rng = Rng(3);
  const NodeId na = b.AddNode(RandomFrame(rng));
  const NodeId nb = b.AddNode(RandomFrame(rng));
  AddBody(b, na, "A");
  AddBody(b, nb, "B");
  const JointId j1 =
      b.AddJointAt("g", JointType::kCylindrical, kGround, na, Vec3(0.1, 0.2, 0.3), kAxis);
  const JointId j2 = b.AddJointAt("ab", JointType::kSpherical, na, nb, Vec3(0.4, -0.2, 0.3));
  const JointId j3 =
      b.AddJointAt("bg", JointType::kPlanar, nb, kGround, Vec3(0.0, 0.5, -0.3), kAxis2);
  for (JointId j : {j1, j2, j3}) {
    Joint& jt = b.model().joints[j];
    jt.damping << 0.3, 0.5, 0.7, 0.0, 0.0, 0.0;
    jt.stiffness << 2.0, 3.0, 4.0, 0.0, 0.0, 0.0;
  }
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  return b.Build();
}

void SetRandomMotion(const Model& m, Data& d) {
  Disturb(m, d, 21);
  auto rng = Rng(22);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < m.nv; ++i) {
    d.v(i) = u(rng);
    d.vdot(i) = u(rng);
  }
  d.lambda.setZero();
}

TEST(DynamicTangent, MassBlockIsTheDerivativeOfTheResidualWithRespectToAcceleration) {
  const Model m = MakeMovingModel();
  Data d = MakeData(m);
  SetRandomMotion(m, d);
  AssemblyOptions o;
  o.dynamics = true;
  o.c_mass = 1.0;
  o.c_damping = 0.0;
  o.c_stiffness = 0.0;
  ASSERT_TRUE(Assemble(m, d, o));
  const Eigen::MatrixXd M = GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv);
  const Eigen::MatrixXd M_fd = ResidualDerivative(m, d, o, [](Data& data, int i, double e) {
                                 data.vdot(i) += e;
                               }).topRows(m.nv);
  EXPECT_LT(RelativeError(M, M_fd), 1e-8) << "M =\n" << M << "\nFD =\n" << M_fd;
  // Joint coordinates carry no mass.
  EXPECT_EQ(M.bottomRows(m.nv - m.nv_nodes).cwiseAbs().maxCoeff(), 0.0);
}

TEST(DynamicTangent, DampingBlockIsTheDerivativeOfTheResidualWithRespectToVelocity) {
  const Model m = MakeMovingModel();
  Data d = MakeData(m);
  SetRandomMotion(m, d);
  AssemblyOptions o;
  o.dynamics = true;
  o.c_mass = 0.0;
  o.c_damping = 1.0;
  o.c_stiffness = 0.0;
  ASSERT_TRUE(Assemble(m, d, o));
  const Eigen::MatrixXd C = GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv);
  const Eigen::MatrixXd C_fd = ResidualDerivative(m, d, o, [](Data& data, int i, double e) {
                                 data.v(i) += e;
                               }).topRows(m.nv);
  // Gyroscopic terms of the bodies and the joint dampers are both present.
  EXPECT_GT(C_fd.topLeftCorner(m.nv_nodes, m.nv_nodes).cwiseAbs().maxCoeff(), 0.1);
  EXPECT_GT(C_fd.bottomRightCorner(m.nv - m.nv_nodes, m.nv - m.nv_nodes).cwiseAbs().maxCoeff(),
            0.1);
  EXPECT_LT(RelativeError(C, C_fd), 1e-7) << "C =\n" << C << "\nFD =\n" << C_fd;
}

// A free joint's damper acts on the rate of its deflection, D G eta_AB: exact block G^T D G.
TEST(DynamicTangent, FreeJointDamperBlockIsTheDerivativeOfTheResidualWithRespectToVelocity) {
  ModelBuilder b;
  auto rng = Rng(4);
  const NodeId na = b.AddNode(RandomFrame(rng));
  const NodeId nb = b.AddNode(RandomFrame(rng));
  AddBody(b, na, "A");
  AddBody(b, nb, "B");
  const JointId j1 = b.AddJointAt("g", JointType::kFree, kGround, na, Vec3(0.1, 0.2, 0.3));
  const JointId j2 = b.AddJointAt("ab", JointType::kFree, na, nb, Vec3(0.4, -0.2, 0.3));
  for (JointId j : {j1, j2}) {
    b.model().joints[j].damping << 0.3, 0.5, 0.7, 1.1, 1.3, 1.7;
    b.model().joints[j].stiffness << 2.0, 3.0, 4.0, 5.0, 6.0, 7.0;
  }
  const Model m = b.Build();
  Data d = MakeData(m);
  SetRandomMotion(m, d);
  AssemblyOptions o;
  o.dynamics = true;
  o.c_mass = 0.0;
  o.c_damping = 1.0;
  o.c_stiffness = 0.0;
  ASSERT_TRUE(Assemble(m, d, o));
  const Eigen::MatrixXd C = GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv);
  const Eigen::MatrixXd C_fd = ResidualDerivative(m, d, o, [](Data& data, int i, double e) {
                                 data.v(i) += e;
                               }).topRows(m.nv);
  // The dampers couple the two bodies.
  EXPECT_GT(C_fd.topRightCorner(6, 6).cwiseAbs().maxCoeff(), 0.1);
  EXPECT_LT(RelativeError(C, C_fd), 1e-7) << "C =\n" << C << "\nFD =\n" << C_fd;
}

TEST(DynamicTangent, StiffnessBlockInDynamicsMatchesFiniteDifferenceWithMotion) {
  const Model m = MakeMovingModel();
  Data d = MakeData(m);
  SetRandomMotion(m, d);
  AssemblyOptions o;
  o.dynamics = true;
  o.c_mass = 0.0;
  o.c_damping = 0.0;
  o.c_stiffness = 1.0;
  ASSERT_TRUE(Assemble(m, d, o));
  const Eigen::MatrixXd K = GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv);
  const Eigen::MatrixXd K_fd = RetractionDerivative(m, d, o).topRows(m.nv);
  EXPECT_LT(RelativeError(K, K_fd), 1e-7) << "K =\n" << K << "\nFD =\n" << K_fd;
}

// Statics' exact tangent (AssemblyOptions::constraint_force_tangent): with multipliers away
// from zero the equilibrium rows' derivative includes d(B^T lambda)/dq, which couples a joint's
// two nodes and its coordinates (outside the model's band pattern: the matrix gets the wider
// one). Without it the equilibrium block misses exactly that term.
TEST(EquilibriumTangent, ConstraintForceDerivativeMatchesFiniteDifferenceForEveryJointType) {
  for (JointType type : kAllTypes) {
    if (type == JointType::kFree) continue;  // no constraint rows
    for (bool reverse : {false, true}) {
      SCOPED_TRACE(std::string(JointTypeName(type)) + (reverse ? " (ground on side b)" : ""));
      const Model m = MakeJointModel(type, reverse);
      Data d = MakeData(m);
      Disturb(m, d, static_cast<unsigned>(type));
      auto rng = Rng(200 + static_cast<unsigned>(type));
      for (int i = 0; i < m.nc; ++i) d.lambda(i) = RandomVec6(rng, 3.0)(0);
      int bandwidth = 0;
      const std::vector<int> pattern = ConstraintForceTangentPattern(m, &bandwidth);
      EXPECT_GE(bandwidth, m.bandwidth);
      d.matrix.Resize(m.num_unknowns(), bandwidth, bandwidth);
      d.matrix.SetPattern(pattern, pattern);
      AssemblyOptions o = StaticsOptions();
      o.constraint_force_tangent = true;
      o.pattern_last = &pattern;
      ASSERT_TRUE(Assemble(m, d, o));
      const Eigen::MatrixXd K = GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv);
      const Eigen::MatrixXd fd = RetractionDerivative(m, d, o).topRows(m.nv);
      EXPECT_LT(RelativeError(K, fd), 1e-7) << "K =\n" << K << "\nFD =\n" << fd;
      o.constraint_force_tangent = false;
      ASSERT_TRUE(Assemble(m, d, o));
      EXPECT_GT(RelativeError(GlobalMatrix(m, d).topLeftCorner(m.nv, m.nv), fd), 1e-2);
    }
  }
}

// Stabilised index 2 (docs/numerics.md, "Stabilised index 2"): with AssemblyOptions::velocity_constraint_tangent
// = c the constraint rows of the matrix are s_C (B + c Z), without the tangent operator on B
// (the rows linearise B(q) v, whose velocity derivative is B), and Z is the derivative of the
// velocity constraint B(q) v at fixed v through the retraction (CalcVelocityConstraint).
TEST(DynamicTangent, VelocityConstraintDerivativeMatchesFiniteDifferenceForEveryJointType) {
  constexpr double c = 0.37;
  for (JointType type : kAllTypes) {
    if (type == JointType::kFree) continue;  // no constraint rows
    for (bool reverse : {false, true}) {
      SCOPED_TRACE(std::string(JointTypeName(type)) + (reverse ? " (ground on side b)" : ""));
      const Model m = MakeJointModel(type, reverse);
      Data d = MakeData(m);
      Disturb(m, d, static_cast<unsigned>(type));
      auto rng = Rng(300 + static_cast<unsigned>(type));
      for (int i = 0; i < m.nv; ++i) d.v(i) = RandomVec6(rng, 3.0)(0);
      AssemblyOptions o = StaticsOptions();
      ASSERT_TRUE(Assemble(m, d, o));
      const Eigen::MatrixXd B = GlobalMatrix(m, d).block(m.nv, 0, m.nc, m.nv) / kConstraintScale;
      o.velocity_constraint_tangent = c;
      ASSERT_TRUE(Assemble(m, d, o));
      const Eigen::MatrixXd Z =
          (GlobalMatrix(m, d).block(m.nv, 0, m.nc, m.nv) / kConstraintScale - B) / c;
      // d(B(q) v)/dx at fixed v.
      const State base = [&] {
        State st;
        SaveState(d, &st);
        return st;
      }();
      Eigen::MatrixXd fd(m.nc, m.nv);
      Eigen::VectorXd plus(m.nc), minus(m.nc);
      for (int i = 0; i < m.nv; ++i) {
        Eigen::VectorXd dx = Eigen::VectorXd::Zero(m.nv);
        dx(i) = kEps;
        RestoreState(base, d);
        Retract(m, d, dx);
        CalcVelocityConstraint(m, d, 0.0, plus);
        dx(i) = -kEps;
        RestoreState(base, d);
        Retract(m, d, dx);
        CalcVelocityConstraint(m, d, 0.0, minus);
        fd.col(i) = (plus - minus) / (2.0 * kEps);
      }
      RestoreState(base, d);
      EXPECT_GT(fd.cwiseAbs().maxCoeff(), 0.1);
      EXPECT_LT(RelativeError(Z, fd), 1e-7) << "Z =\n" << Z << "\nFD =\n" << fd;
      // With the tangent operators of a dynamic iteration the B part of the rows stays B.
      for (std::size_t n = 0; n < m.nodes.size(); ++n)
        d.node_tangent[n] = TSE3(RandomVec6(rng, 0.3));
      for (std::size_t jj = 0; jj < m.joints.size(); ++jj)
        if (m.nodes.size() + jj < d.node_tangent.size())
          d.node_tangent[m.nodes.size() + jj].setIdentity();
      o.use_node_tangent = true;
      o.velocity_constraint_tangent = 0.0;
      ASSERT_TRUE(Assemble(m, d, o));
      const Eigen::MatrixXd BT = GlobalMatrix(m, d).block(m.nv, 0, m.nc, m.nv) / kConstraintScale;
      o.velocity_constraint_tangent = c;
      ASSERT_TRUE(Assemble(m, d, o));
      const Eigen::MatrixXd rows = GlobalMatrix(m, d).block(m.nv, 0, m.nc, m.nv) / kConstraintScale;
      EXPECT_GT(RelativeError(BT, B), 1e-3);  // the tangent operators do act on B T
      // rows = B + c Z T: compare column blocks of the nodes.
      for (std::size_t n = 0; n < m.nodes.size(); ++n) {
        const int dof = m.nodes[n].dof;
        if (dof < 0) continue;
        const Eigen::MatrixXd expected =
            B.middleCols(dof, 6) + c * Z.middleCols(dof, 6) * d.node_tangent[n];
        EXPECT_LT(RelativeError(rows.middleCols(dof, 6), expected), 1e-12);
      }
    }
  }
}

}  // namespace
}  // namespace screwfem::joint_gradient_test
