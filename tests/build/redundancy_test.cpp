// Redundant constraints found at build time (FindRedundantConstraints): the count equals the
// rank deficiency of the dense constraint gradient built from the same CalcJointGradient, the
// warning names exactly the joints of the dependent loops, and the cost does not depend on
// the number of rod nodes that no joint touches.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <Eigen/QR>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/joint.h"
#include "screwfem/model/data.h"

namespace screwfem::redundancy_test {
namespace {

// Rank deficiency of the dense B (nc x nv) at the reference configuration: the oracle.
int DenseRankDeficiency(const Model& m) {
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(m.nc, m.nv);
  for (const Joint& j : m.joints) {
    if (j.drive_row >= 0) B(j.drive_row, j.coord + j.drive_coord) = 1.0;
    if (j.row < 0) continue;
    JointGradient g;
    CalcJointGradient(j, NodeReferenceFrame(m, j.node_a), NodeReferenceFrame(m, j.node_b),
                      SE3::Identity(), &g);
    const Mat6 BA = JointGradientA(g), BB = JointGradientB(g);
    const Mat6X BJ = JointGradientCoordinates(g, j.basis, JointMatrix::Identity(j.k(), j.k()));
    const int da = j.node_a == kGround ? -1 : m.nodes[static_cast<std::size_t>(j.node_a)].dof;
    const int db = j.node_b == kGround ? -1 : m.nodes[static_cast<std::size_t>(j.node_b)].dof;
    if (da >= 0) B.block<6, 6>(j.row, da) += BA;
    if (db >= 0) B.block<6, 6>(j.row, db) += BB;
    if (j.k() > 0) B.block(j.row, j.coord, 6, j.k()) += BJ;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(B.transpose());
  qr.setThreshold(1e-10);
  return m.nc - static_cast<int>(qr.rank());
}

// "prefix" + i (built by appending: GCC 12 warns falsely on literal + std::to_string).
std::string Name(const char* prefix, int i) {
  std::string s = prefix;
  s += std::to_string(i);
  return s;
}

std::string Warning(const Model& m) {
  for (const std::string& w : m.warnings)
    if (w.find("redundant") != std::string::npos) return w;
  return {};
}

NodeId AddBody(ModelBuilder& b, const SE3& frame, const std::string& name) {
  const NodeId node = b.AddNode(frame, name);
  b.AddRigidBody(name, node, 0.15, Vec3(0.1, 0.0, 0.0), 1e-4 * Mat3::Identity());
  return node;
}

// Planar four-bar of revolutes about z (3 redundant rows), optionally with a serial chain of
// three revolutes hanging from the coupler, which is in no loop.
Model PlanarFourBar(bool with_chain, bool drive) {
  ModelBuilder b;
  const Vec3 O(0, 0, 0), A(0.2, 0.6, 0), B(1, 1, 0), D(1.2, 0, 0), z = Vec3::UnitZ();
  const NodeId crank = AddBody(b, SE3::Translation(O), "crank");
  const NodeId coupler = AddBody(b, SE3::Translation(A), "coupler");
  const NodeId rocker = AddBody(b, SE3::Translation(D), "rocker");
  const JointId o = b.AddJointAt("O", JointType::kRevolute, kGround, crank, O, z);
  b.AddJointAt("A", JointType::kRevolute, crank, coupler, A, z);
  b.AddJointAt("B", JointType::kRevolute, coupler, rocker, B, z);
  b.AddJointAt("D", JointType::kRevolute, rocker, kGround, D, z);
  if (drive) {
    b.model().joints[o].drive = DriveKind::kPrescribed;
    b.model().joints[o].drive_profile = Profile::Constant(0.0);
  }
  if (with_chain) {
    NodeId prev = coupler;
    for (int i = 0; i < 3; ++i) {
      const Vec3 p(0.2 + 0.3 * (i + 1), 0.6, 0.5);
      const NodeId node = AddBody(b, SE3::Translation(p), Name("link", i));
      b.AddJointAt(Name("chain", i), JointType::kRevolute, prev, node, p, Vec3(0, 1, 0));
      prev = node;
    }
  }
  return b.Build();
}

TEST(Redundancy, PlanarLoopOfSpatialRevolutesHasThreeRedundantRowsNamingItsFourJoints) {
  const Model m = PlanarFourBar(false, false);
  EXPECT_EQ(m.redundant_rows.size(), 3u);
  EXPECT_EQ(DenseRankDeficiency(m), 3);
  EXPECT_NE(Warning(m).find("3 redundant constraint equation(s) among joints 'A', 'B', 'D', 'O';"),
            std::string::npos)
      << Warning(m);
}

TEST(Redundancy, JointsOutsideTheLoopAreNotNamedAndADriveAddsNoRedundancy) {
  const Model m = PlanarFourBar(true, true);
  EXPECT_EQ(m.redundant_rows.size(), 3u);
  EXPECT_EQ(DenseRankDeficiency(m), 3);
  EXPECT_NE(Warning(m).find("among joints 'A', 'B', 'D', 'O';"), std::string::npos) << Warning(m);
  EXPECT_EQ(Warning(m).find("chain"), std::string::npos) << Warning(m);
  // The drive row is independent (the loop has one degree of freedom).
  for (int r : m.redundant_rows) EXPECT_NE(r, m.joints[0].drive_row);
}

// Orthogonal Bricard linkage: six revolutes, link lengths 1, twists +-90 degrees, no offsets,
// in a closed configuration (Denavit-Hartenberg angles alternating t1, t2, found numerically).
// A generic 6R loop is rigid (36 rows on 36 unknowns, full rank); the Bricard loop moves with
// one degree of freedom, so exactly one of its rows is redundant.
TEST(Redundancy, BricardLinkageHasOneRedundantRowNamingAllSixJoints) {
  const double t[2] = {-1.128330748620619, 1.8752821687133436};
  const double alpha[2] = {std::numbers::pi / 2, -std::numbers::pi / 2};
  auto dh = [](double theta, double a, double twist) {
    SE3 rz, x;
    rz.R = Eigen::AngleAxisd(theta, Vec3::UnitZ()).toRotationMatrix();
    x.R = Eigen::AngleAxisd(twist, Vec3::UnitX()).toRotationMatrix();
    x.x = Vec3(a, 0, 0);
    return rz * x;
  };
  ModelBuilder b;
  std::vector<SE3> F(1, SE3::Identity());
  for (int i = 0; i < 6; ++i) F.push_back(F.back() * dh(t[i % 2], 1.0, alpha[i % 2]));
  ASSERT_LT((F[6].x).norm() + (F[6].R - Mat3::Identity()).norm(), 1e-12);
  std::vector<NodeId> node(7, kGround);
  for (int i = 1; i < 6; ++i)
    node[static_cast<std::size_t>(i)] = AddBody(b, F[static_cast<std::size_t>(i)], Name("link", i));
  for (int i = 1; i <= 6; ++i) {
    const SE3& Fi = F[static_cast<std::size_t>(i - 1)];
    b.AddJointAt(Name("R", i), JointType::kRevolute, node[static_cast<std::size_t>(i - 1)],
                 node[static_cast<std::size_t>(i)], Fi.x, Fi.R.col(2));
  }
  const Model m = b.Build();
  EXPECT_EQ(m.nc, 36);
  EXPECT_EQ(m.redundant_rows.size(), 1u);
  EXPECT_EQ(DenseRankDeficiency(m), 1);
  EXPECT_NE(Warning(m).find("1 redundant constraint equation(s) among joints 'R1', 'R2', 'R3', "
                            "'R4', 'R5', 'R6';"),
            std::string::npos)
      << Warning(m);
}

TEST(Redundancy, ParallelWeldsAndJointsBetweenFixedNodesAreRedundant) {
  ModelBuilder b;
  const NodeId a = AddBody(b, SE3::Translation(Vec3(0, 0, 0)), "a");
  const NodeId c = AddBody(b, SE3::Translation(Vec3(1, 0, 0)), "c");
  const NodeId f1 = b.AddNode(SE3::Translation(Vec3(0, 2, 0)), "f1");
  const NodeId f2 = b.AddNode(SE3::Translation(Vec3(1, 2, 0)), "f2");
  b.FixNode(f1);
  b.FixNode(f2);
  b.AddJointAt("ground", JointType::kRevolute, kGround, a, Vec3::Zero(), Vec3::UnitZ());
  b.AddJointAt("weld1", JointType::kFixed, a, c, Vec3(0.5, 0, 0));
  b.AddJointAt("weld2", JointType::kFixed, c, a, Vec3(0.7, 0.1, 0));
  b.AddJointAt("fixed_pair", JointType::kRevolute, f1, f2, Vec3(0.5, 2, 0), Vec3::UnitX());
  const Model m = b.Build();
  // 6 rows of the second weld, 5 of the revolute between two fixed nodes (its coordinate
  // takes one row).
  EXPECT_EQ(m.redundant_rows.size(), 11u);
  EXPECT_EQ(DenseRankDeficiency(m), 11);
  EXPECT_NE(Warning(m).find("among joints 'fixed_pair', 'weld1', 'weld2';"), std::string::npos)
      << Warning(m);
}

// A ladder of planar loops (revolutes about z between rigid bodies on two rails, rungs
// between them): every loop adds 3 redundant rows; the count agrees with the dense rank.
TEST(Redundancy, LadderOfLoopsMatchesTheDenseRank) {
  ModelBuilder b;
  const int n = 6;
  std::vector<NodeId> top, bottom;
  for (int i = 0; i < n; ++i) {
    top.push_back(AddBody(b, SE3::Translation(Vec3(i, 1, 0)), Name("t", i)));
    bottom.push_back(AddBody(b, SE3::Translation(Vec3(i, 0, 0)), Name("b", i)));
  }
  b.AddJointAt("g0", JointType::kRevolute, kGround, bottom[0], Vec3(0, 0, 0), Vec3::UnitZ());
  for (int i = 0; i < n; ++i) {
    b.AddJointAt(Name("rung", i), JointType::kRevolute, bottom[static_cast<std::size_t>(i)],
                 top[static_cast<std::size_t>(i)], Vec3(i, 0.5, 0), Vec3::UnitZ());
    if (i + 1 < n) {
      b.AddJointAt(Name("top", i), JointType::kRevolute, top[static_cast<std::size_t>(i)],
                   top[static_cast<std::size_t>(i) + 1], Vec3(i + 0.5, 1, 0), Vec3::UnitZ());
      b.AddJointAt(Name("bot", i), JointType::kSpherical, bottom[static_cast<std::size_t>(i)],
                   bottom[static_cast<std::size_t>(i) + 1], Vec3(i + 0.5, 0, 0));
    }
  }
  const Model m = b.Build();
  EXPECT_EQ(static_cast<int>(m.redundant_rows.size()), DenseRankDeficiency(m));
  EXPECT_GT(m.redundant_rows.size(), 0u);
}

// 500 welds on a 100000-element rod (nc = 3000): the dense check asked for 14.4 GB
// (nc x nv doubles); the sparse one touches only the welded nodes. Bounded here by the
// process's peak resident size growing less than 300 MB during Build (the model itself,
// 100001 nodes, takes most of that).
TEST(Redundancy, FiveHundredWeldsOnALongRodBuildQuicklyWithoutDenseGradient) {
  ModelBuilder b;
  Section s;
  s.stiffness = Vec6::Constant(1e3);
  s.inertia = Vec6::Constant(1e-3);
  const RodId rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3(100, 0, 0), 100000, s);
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  for (int i = 0; i < 499; ++i) {
    const Vec3 p(0.2 * i + 0.1, 0.5, 0.0);
    const NodeId body = AddBody(b, SE3::Translation(p), Name("b", i));
    const NodeId rod_node = nodes[static_cast<std::size_t>(200 * i + 100)];
    b.AddJointAt(Name("w", i), JointType::kFixed, body, rod_node,
                 b.model().nodes[static_cast<std::size_t>(rod_node)].reference.x);
  }
  b.AddJointAt("base", JointType::kFixed, kGround, nodes[0], Vec3::Zero());
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  const Model m = b.Build();
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_EQ(m.nc, 3000);
  EXPECT_TRUE(m.redundant_rows.empty());
  // Complexity guards, not timings: the dense gradient this replaced took 43 s and 2.9 GB; the
  // sparse check takes about 0.1 s of CPU in Release and a few seconds under the sanitizers.
  // CPU time (user + system), not wall time, so that the shared test machine's load cannot fail
  // the test.
  const auto cpu = [](const rusage& u) {
    return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  };
  EXPECT_LT(cpu(after) - cpu(before), 20.0);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 300L * 1024L);  // kB
}

}  // namespace
}  // namespace screwfem::redundancy_test
