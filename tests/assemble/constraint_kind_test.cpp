// The constraint kinds (elements/constraint.h, registry.h) and the constraint functions of
// assemble/assemble.h against their own definitions, on a
// mechanism that has every kind: a rod on a driven revolute joint to the ground (joint rows, a
// prescribed drive with a time-varying profile), a rigid body on its tip by a spherical joint
// (coordinates that retract by the exponential) and a length-driven tendon from the ground
// through two eyelets between rod nodes to the body (a rheonomic row over many nodes).
//
// - the gradient blocks are the derivative of the constraint rows (the residual's s_C phi with
//   s_C = 1) through the retraction, by central differences, for every unknown;
// - the factored gradient B x equals the blocks times x;
// - the columns a kind declares (ForEachColumn, the coupling pattern) hold every nonzero of its
//   rows of B;
// - the targets are the explicit time dependence: the velocity constraint at v = 0 is
//   d phi / dt and the accelerations subtracted are d2 phi / dt2, by differences in time;
// - the efforts read the multipliers as the drive's torque and the tendon's tension.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/registry.h"

namespace screwfem::constraint_kind_test {
namespace {

constexpr double kTime = 0.3;

Section ArmSection() {
  return Section::FromDiagonals((Vec6() << 1e4, 4e3, 4e3, 2.0, 1.0, 1.0).finished(),
                                (Vec6() << 0.1, 0.1, 0.1, 1e-4, 1e-4, 1e-4).finished());
}

Model Mechanism() {
  ModelBuilder b;
  b.SetConformMesh(false);  // the span kinds: features between nodes stay there
  const RodId rod = b.AddStraightRod("arm", Vec3::Zero(), Vec3::UnitX(), 4, ArmSection());
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  const NodeId root = nodes.front(), tip = nodes.back();
  JointSpec shoulder;
  shoulder.name = "shoulder";
  shoulder.type = JointType::kRevolute;
  shoulder.node_a = kGround;
  shoulder.node_b = root;
  shoulder.point = Vec3::Zero();
  shoulder.axis = Vec3::UnitZ();
  shoulder.drive = DriveKind::kPrescribed;
  shoulder.drive_profile = Profile::Sine(0.4, 1.3, 0.2);
  b.AddJoint(shoulder);
  const NodeId hand = b.AddNode(SE3::Translation(Vec3(1.2, 0.0, 0.0)), "hand");
  b.AddRigidBody("hand", hand, 0.5, Vec3::Zero(), 0.01 * Mat3::Identity());
  b.AddJointAt("wrist", JointType::kSpherical, tip, hand, Vec3::UnitX());
  std::vector<BodyPoint> eyelets = {{kGround, Vec3(0.0, 0.05, 0.2)}};
  for (const double s : {0.35, 0.8}) {
    BodyPoint p{kGround, Vec3(0.0, 0.02, 0.01)};
    p.rod = rod;
    p.arc_length = s;
    eyelets.push_back(p);
  }
  eyelets.push_back({hand, Vec3(0.1, 0.02, 0.0)});
  b.AddLengthDrivenTendon("cable", eyelets, Profile::Constant(1.35).Add(Profile::Sine(0.05, 0.7)));
  return b.Build();
}

// A state away from the reference: every unknown retracted by a fixed pseudo-random amount,
// with velocities and multipliers of the same kind.
Data PerturbedData(const Model& m) {
  Data d = MakeData(m);
  Eigen::VectorXd dx(m.nv), v(m.nv), lambda(m.nc);
  for (int i = 0; i < m.nv; ++i) {
    dx(i) = 0.05 * std::sin(1.7 * i + 0.3);
    v(i) = 0.8 * std::cos(0.9 * i + 0.1);
  }
  for (int r = 0; r < m.nc; ++r) lambda(r) = 3.0 * std::sin(2.3 * r + 0.5);
  Retract(m, d, dx);
  d.v = v;
  d.lambda = lambda;
  d.time = kTime;
  return d;
}

// The constraint rows phi(q, t) (nc) from an assembly with s_C = 1.
Eigen::VectorXd ConstraintRows(const Model& m, Data d, double time) {
  AssemblyOptions o;
  o.time = time;
  o.assemble_matrix = false;
  EXPECT_TRUE(Assemble(m, d, o));
  return d.residual.tail(m.nc);
}

TEST(ConstraintKinds, MechanismHasEveryKindAndNoHeldRow) {
  const Model m = Mechanism();
  int items[3] = {0, 0, 0};
  int i = 0;
  ForEachKind<ConstraintKinds>([&]<class Kind>() {
    Kind::ForEach(m, [&](const typename Kind::Item& item) {
      if (Kind::RowCount(m, item) > 0) ++items[i];
    });
    ++i;
  });
  EXPECT_EQ(items[0], 2);  // the revolute and the spherical joint
  EXPECT_EQ(items[1], 1);  // the drive
  EXPECT_EQ(items[2], 1);  // the tendon
  EXPECT_EQ(m.nc, 6 + 6 + 1 + 1);
  EXPECT_TRUE(m.redundant_rows.empty());
}

TEST(ConstraintKinds, GradientIsTheDerivativeOfTheRowsThroughTheRetraction) {
  const Model m = Mechanism();
  const Data d = PerturbedData(m);
  Eigen::MatrixXd B(m.nc, m.nv);
  CalcConstraintGradient(m, d, B);
  const double eps = 1e-6;
  Eigen::MatrixXd fd(m.nc, m.nv);
  for (int i = 0; i < m.nv; ++i) {
    Data p = d, q = d;
    Retract(m, p, eps * Eigen::VectorXd::Unit(m.nv, i));
    Retract(m, q, -eps * Eigen::VectorXd::Unit(m.nv, i));
    fd.col(i) = (ConstraintRows(m, p, kTime) - ConstraintRows(m, q, kTime)) / (2.0 * eps);
  }
  EXPECT_LT((B - fd).cwiseAbs().maxCoeff(), 1e-7 * B.cwiseAbs().maxCoeff()) << "B\n"
                                                                            << B << "\nfd\n"
                                                                            << fd;
  // Each kind's rows are nonzero (the test would pass on an empty gradient otherwise).
  for (int r = 0; r < m.nc; ++r) EXPECT_GT(B.row(r).norm(), 1e-3) << "row " << r;
}

TEST(ConstraintKinds, FactoredGradientEqualsTheBlocks) {
  const Model m = Mechanism();
  const Data d = PerturbedData(m);
  Eigen::MatrixXd B(m.nc, m.nv);
  CalcConstraintGradient(m, d, B);
  Eigen::VectorXd x(m.nv), bx(m.nc);
  for (int i = 0; i < m.nv; ++i) x(i) = std::cos(3.1 * i + 0.7);
  CalcConstraintGradientTimes(m, d, x, bx);
  EXPECT_LT((bx - B * x).cwiseAbs().maxCoeff(), 1e-12 * (B * x).cwiseAbs().maxCoeff());
}

TEST(ConstraintKinds, DeclaredColumnsHoldEveryNonzeroOfTheirRows) {
  const Model m = Mechanism();
  const Data d = PerturbedData(m);
  Eigen::MatrixXd B(m.nc, m.nv);
  CalcConstraintGradient(m, d, B);
  Eigen::MatrixXd covered = Eigen::MatrixXd::Zero(m.nc, m.nv);
  ForEachKind<ConstraintKinds>([&]<class Kind>() {
    Kind::ForEach(m, [&](const typename Kind::Item& item) {
      const int row = Kind::FirstRow(m, item), rows = Kind::RowCount(m, item);
      if (rows == 0) return;
      Kind::ForEachColumn(
          m, item, [&](int col, int size) { covered.block(row, col, rows, size).setOnes(); });
    });
  });
  int nonzeros = 0;
  for (int r = 0; r < m.nc; ++r)
    for (int c = 0; c < m.nv; ++c) {
      if (B(r, c) == 0.0) continue;
      ++nonzeros;
      EXPECT_EQ(covered(r, c), 1.0) << "B(" << r << ", " << c << ") outside the columns";
    }
  EXPECT_GT(nonzeros, 60);
  // The tendon's row covers the nodes of both elements of each eyelet between nodes (rod
  // nodes 1, 2 and 3, 4) and the hand's node.
  const int tendon_row = m.tendons[0].row;
  EXPECT_EQ(covered.row(tendon_row).sum(), 6.0 * 5);
}

TEST(ConstraintKinds, TargetsAreTheExplicitTimeDerivatives) {
  const Model m = Mechanism();
  Data d = PerturbedData(m);
  d.v.setZero();
  Eigen::VectorXd rate(m.nc);
  CalcVelocityConstraint(m, d, kTime, rate);  // B 0 + d phi / dt
  Eigen::VectorXd accel = Eigen::VectorXd::Zero(m.nc);
  SubtractConstraintAccelerations(m, d, kTime, accel);  // d2 phi / dt2
  // Central differences: steps that balance truncation (e^2 phi''') and round-off.
  const double e1 = 1e-5, e2 = 1e-4;
  const Eigen::VectorXd fd_rate =
      (ConstraintRows(m, d, kTime + e1) - ConstraintRows(m, d, kTime - e1)) / (2.0 * e1);
  const Eigen::VectorXd fd_accel =
      (ConstraintRows(m, d, kTime + e2) - 2.0 * ConstraintRows(m, d, kTime) +
       ConstraintRows(m, d, kTime - e2)) /
      (e2 * e2);
  EXPECT_LT((rate - fd_rate).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((accel - fd_accel).cwiseAbs().maxCoeff(), 1e-4);
  // Rheonomic rows only: the drive's and the tendon's.
  const int drive_row = m.joints[0].drive_row, tendon_row = m.tendons[0].row;
  EXPECT_GT(std::abs(rate(drive_row)), 0.1);
  EXPECT_GT(std::abs(rate(tendon_row)), 0.01);
  for (int r = 0; r < m.nc; ++r)
    if (r != drive_row && r != tendon_row) {
      EXPECT_EQ(rate(r), 0.0) << "row " << r;
    }
}

TEST(ConstraintKinds, EffortsReadTheMultipliers) {
  const Model m = Mechanism();
  const Data d = PerturbedData(m);
  Eigen::VectorXd effort(1);
  DriveConstraintKind::Effort(m, d, 0, effort);
  EXPECT_EQ(effort(0), JointDriveEffort(m, d, 0));
  TendonLengthKind::Effort(m, d, 0, effort);
  EXPECT_EQ(effort(0), TendonTension(m.tendons[0], d, d.time));
  Eigen::VectorXd reaction(6);
  JointConstraintKind::Effort(m, d, 1, reaction);
  EXPECT_EQ(reaction, d.lambda.segment<6>(m.joints[1].row));
}

}  // namespace
}  // namespace screwfem::constraint_kind_test
