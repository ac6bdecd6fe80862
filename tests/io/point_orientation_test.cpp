// The orientation columns of points.csv, P.qw P.qx P.qy P.qz (CalcPointRow, the row of the
// file): the unit quaternion of the node frame for node points (whatever their offset) and of
// the section frame between nodes for rod points, to 1e-12, with the documented sign (qw >= 0,
// at qw = 0 the first non-zero of qx, qy, qz positive).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/io/writers.h"
#include "screwfem/solve/statics.h"

namespace screwfem::point_orientation_test {
namespace {

// The rotation of a quaternion column group (w, x, y, z).
Mat3 Rotation(const std::vector<double>& row, std::size_t at) {
  return Eigen::Quaterniond(row[at], row[at + 1], row[at + 2], row[at + 3]).toRotationMatrix();
}

TEST(PointOrientation, FrameQuaternionHasTheDocumentedSign) {
  // w >= 0; at w = 0 (half turns) the first non-zero of x, y, z is positive.
  const Mat3 half_x = Vec3(1, -1, -1).asDiagonal();
  EXPECT_EQ(FrameQuaternion(half_x), Eigen::Vector4d(0, 1, 0, 0));
  // A half turn about n = (1, -2, 0) / sqrt(5), R = 2 n n^T - I: q = +-(0, n), x > 0 chosen.
  const Vec3 n = Vec3(1, -2, 0).normalized();
  const Mat3 half_n = 2.0 * n * n.transpose() - Mat3::Identity();
  const Eigen::Vector4d q = FrameQuaternion(half_n);
  EXPECT_EQ(q(0), 0.0);
  EXPECT_LT((q.tail<3>() - n).norm(), 1e-15) << q.transpose();
  for (const Vec3& w : {Vec3(0.3, -2.0, 0.4), Vec3(-3.0, 0.1, 0.2), Vec3(0, 0, -3.1)}) {
    const Mat3 R = ExpSO3(w);
    const Eigen::Vector4d p = FrameQuaternion(R);
    EXPECT_GE(p(0), 0.0);
    EXPECT_NEAR(p.norm(), 1.0, 1e-15);
    EXPECT_LT((Eigen::Quaterniond(p(0), p(1), p(2), p(3)).toRotationMatrix() - R).norm(), 1e-15);
  }
}

TEST(PointOrientation, ColumnsAreTheNodeAndSectionFrames) {
  // A bent and twisted cantilever along a path with a corner, a rigid body on its tip.
  ModelBuilder b;
  Vec6 K;
  K << 1e3, 1e3, 1e3, 0.5, 0.8, 1.0;
  const RodId rod = b.AddRodAlongPath("arm", {Vec3::Zero(), Vec3(0.6, 0, 0), Vec3(0.6, 0.5, 0.2)},
                                      3, Section::FromDiagonals(K));
  const std::vector<NodeId> nodes = b.RodNodes(RodId(0));
  b.FixNode(nodes.front());
  b.AddRigidBody("hand", nodes.back(), 0.1, Vec3(0.05, 0, 0), 1e-4 * Mat3::Identity());
  PointLoad tip;
  tip.node = nodes.back();
  tip.force = Vec3(0.3, -0.4, -0.8);
  tip.moment = Vec3(0.2, 0.3, -0.1);
  b.AddPointLoad(tip);
  const Model model = b.Build();
  Data data = MakeData(model);
  StaticOptions o;
  o.load_steps = 5;
  ASSERT_TRUE(SolveStatic(model, data, o).converged);

  std::vector<OutputPoint> points;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    points.push_back({.name = "N" + std::to_string(i),
                      .node = nodes[i],
                      .offset = Vec3(0.01 * static_cast<double>(i), 0.02, -0.03)});
  const double xi = 0.3;
  for (int e = 0; e < model.rods[0].num_elements; ++e) {
    double s = 0.0;
    for (int k = 0; k < e; ++k) s += model.elements[static_cast<std::size_t>(k)].length;
    s += xi * model.elements[static_cast<std::size_t>(e)].length;
    points.push_back({.name = "S" + std::to_string(e), .rod = rod, .arc_length = s});
  }
  const std::vector<std::string> columns = PointColumns(points);
  ASSERT_EQ(columns.size(), kPointColumns * points.size());
  EXPECT_EQ(columns[9], "N0.qw");
  EXPECT_EQ(columns[12], "N0.qz");
  EXPECT_EQ(columns[13], "N1.x");
  std::vector<double> row;
  CalcPointRow(model, data, points, &row);
  ASSERT_EQ(row.size(), columns.size());

  double node_error = 0.0, section_error = 0.0, rotation = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::size_t q = kPointColumns * i + 9;
    EXPECT_GE(row[q], 0.0);
    Mat3 expected;
    if (points[i].node >= 0) {
      expected = data.H[static_cast<std::size_t>(points[i].node)].R;
      node_error = std::max(node_error, (Rotation(row, q) - expected).cwiseAbs().maxCoeff());
    } else {
      // The section at xi of element e: H_A exp(xi log(H_A^-1 H_B)) (rotations below pi).
      const RodElement& el = model.elements[i - nodes.size()];
      const SE3& HA = data.H[static_cast<std::size_t>(el.node_a)];
      const SE3& HB = data.H[static_cast<std::size_t>(el.node_b)];
      expected = (HA * ExpSE3(xi * LogSE3(HA.Inverse() * HB))).R;
      section_error = std::max(section_error, (Rotation(row, q) - expected).cwiseAbs().maxCoeff());
    }
    rotation = std::max(rotation, LogSO3(expected).norm());
  }
  std::printf(
      "orientation columns: node frames %.2e, section frames %.2e (rotations up to %.2f "
      "rad)\n",
      node_error, section_error, rotation);
  EXPECT_LT(node_error, 1e-12);
  EXPECT_LT(section_error, 1e-12);
  EXPECT_GT(rotation, 1.0);  // the frames really turned (the corner alone turns 0.8 rad)
}

}  // namespace
}  // namespace screwfem::point_orientation_test
