// Tests of triangle-mesh and height-field obstacles (model/mesh.h, docs/numerics.md, "Triangle
// meshes"): the mass properties of a tessellated box and cylinder against their closed forms;
// the closest points of a mesh box against the analytic box; contact tangents on a mesh face
// against central differences; a sphere falling on a mesh box follows the analytic box's
// trajectory to 1e-9; a cantilever pressed on a tessellated cylinder converges to the analytic
// cylinder as the facets are refined; a ball rolls down a height-field slope at (5/7) g sin a.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/solid_geometry.h"
#include "screwfem/model/mesh.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/statics.h"
#include "kind_assembly.h"

namespace screwfem::mesh_contact_test {
namespace {

constexpr double kG = 9.81;

// The box |x_i| <= h_i as 12 outward triangles.
TriangleMesh BoxMesh(const Vec3& h) {
  TriangleMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(),
                            (k & 4) ? h.z() : -h.z());
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.faces.push_back({q[0], q[1], q[2]});
    m.faces.push_back({q[0], q[2], q[3]});
  }
  return m;
}

// A prism over the regular n-gon of circumradius R (axis z from -H/2 to H/2), capped by fans.
TriangleMesh PrismMesh(int n, double R, double H, double phase = 0.0) {
  TriangleMesh m;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < n; ++k) {
      const double a = phase + 2.0 * M_PI * k / n;
      m.vertices.emplace_back(R * std::cos(a), R * std::sin(a), (z - 0.5) * H);
    }
  m.vertices.emplace_back(0.0, 0.0, -0.5 * H);
  m.vertices.emplace_back(0.0, 0.0, 0.5 * H);
  const int bottom = 2 * n, top = 2 * n + 1;
  for (int k = 0; k < n; ++k) {
    const int a = k, b = (k + 1) % n;
    m.faces.push_back({a, b, b + n});
    m.faces.push_back({a, b + n, a + n});
    m.faces.push_back({bottom, b, a});
    m.faces.push_back({top, a + n, b + n});
  }
  return m;
}

TriangleMesh Placed(const TriangleMesh& in, const Mat3& R, const Vec3& x) {
  TriangleMesh m = in;
  for (Vec3& v : m.vertices) v = x + R * v;
  return m;
}

TEST(MeshMass, TessellatedBoxAndPrismMatchTheirClosedFormsToRoundOff) {
  const Mat3 R = ExpSO3(Vec3(0.3, -0.5, 0.7));
  const Vec3 x(1.5, -2.0, 0.75);
  {
    const Vec3 h(0.3, 0.2, 0.1);
    const MeshMassProperties p = CalcMeshMassProperties(Placed(BoxMesh(h), R, x));
    const double V = 8.0 * h.prod();
    EXPECT_NEAR(p.volume, V, 1e-15 * V);
    EXPECT_LT((p.centroid - x).norm(), 1e-14);
    const Vec3 s = 4.0 * h.cwiseProduct(h);  // full sizes squared
    const Mat3 J =
        R *
        Vec3(V * (s.y() + s.z()) / 12, V * (s.x() + s.z()) / 12, V * (s.x() + s.y()) / 12)
            .asDiagonal() *
        R.transpose();
    EXPECT_LT((p.inertia - J).norm(), 1e-14 * J.norm());
  }
  for (const int n : {3, 8, 64}) {
    const double r = 0.2, H = 0.5;
    const MeshMassProperties p = CalcMeshMassProperties(Placed(PrismMesh(n, r, H), R, x));
    const double A = 0.5 * n * r * r * std::sin(2.0 * M_PI / n), V = A * H;
    EXPECT_NEAR(p.volume, V, 1e-14 * V) << n;
    EXPECT_LT((p.centroid - x).norm(), 1e-14) << n;
    // A regular polygon's polar moment per area: R^2 (1 + 2 cos^2(pi/n)) / 6, half of it
    // about any axis in its plane.
    const double polar = r * r * (1.0 + 2.0 * std::pow(std::cos(M_PI / n), 2)) / 6.0;
    const Mat3 J = R *
                   Vec3(V * (0.5 * polar + H * H / 12), V * (0.5 * polar + H * H / 12), V * polar)
                       .asDiagonal() *
                   R.transpose();
    EXPECT_LT((p.inertia - J).norm(), 1e-13 * J.norm()) << n;
  }
}

// The mesh box's closest points to random points and segments around it are the analytic
// box's (BoxSegmentParameter, BoxClosestPoint): distance, normal and parameter.
TEST(MeshGeometry, MeshBoxClosestPointsAreTheAnalyticBoxs) {
  const Vec3 h(0.3, 0.2, 0.1), c(0.2, -0.1, 0.4);
  const Mat3 R = ExpSO3(Vec3(0.2, 0.4, -0.3));
  MeshTree tree;
  tree.Build(BoxMesh(h), R, c, 1.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int inside = 0, tested = 0;
  for (int i = 0; i < 4000; ++i) {
    // Points near the box, within 0.05 of its surface (some inside, within 0.02).
    Vec3 a(u(rng) * 0.4, u(rng) * 0.3, u(rng) * 0.2);
    Vec3 d = Vec3::Zero();
    if (i % 2 == 1) d = Vec3(u(rng), u(rng), u(rng)) * 0.1;
    const double s_box = BoxSegmentParameter(a, d, h);
    const SolidPoint sp = BoxClosestPoint(a + s_box * d, h);
    if (sp.distance > 0.05 || sp.distance < -0.02) continue;
    // A segment whose deepest point is inside: the mesh takes the deepest point under the face
    // it leaves through, the box the point deepest in the box; compare points only there.
    if (sp.distance < 0.0 && d != Vec3::Zero()) continue;
    const MeshHit hit = tree.ClosestToSegment(c + R * a, c + R * (a + d), 0.06, 0.03);
    ASSERT_TRUE(hit.found) << i;
    ++tested;
    inside += sp.distance < 0.0 ? 1 : 0;
    EXPECT_NEAR(hit.distance, sp.distance, 1e-12) << i;
    EXPECT_LT((hit.normal - R * sp.normal).norm(), 1e-9) << i << " s " << s_box;
    if (d != Vec3::Zero()) {
      EXPECT_NEAR(hit.s, s_box, 1e-9) << i;
    }
  }
  EXPECT_GT(tested, 1000);
  EXPECT_GT(inside, 50);
}

// A segment lying on two coplanar triangles is carried at the middle of its part over them
// (the union of the two faces' flat parts), as the analytic box takes the middle.
TEST(MeshGeometry, SegmentOnAFaceIsCarriedAtTheMiddleOfItsPartOverTheFace) {
  MeshTree tree;
  tree.Build(BoxMesh(Vec3(0.3, 0.2, 0.1)), Mat3::Identity(), Vec3::Zero(), 1.0);
  // From x = 0.1 to x = 0.5 at y = 0.05, 0.01 above the top: over the face from 0.1 to 0.3.
  const MeshHit hit =
      tree.ClosestToSegment(Vec3(0.1, 0.05, 0.11), Vec3(0.5, 0.05, 0.11), 0.1, 0.05);
  ASSERT_TRUE(hit.found);
  EXPECT_NEAR(hit.distance, 0.01, 1e-15);
  EXPECT_NEAR(hit.s, 0.25, 1e-14);  // the middle of [0, 0.5]
  EXPECT_LT((hit.normal - Vec3::UnitZ()).norm(), 1e-15);
}

// A rigid ball (its sphere off the node) and a rod on a tilted mesh slab, both pressed into a
// face: the contact stiffness and damping equal central differences of the residual (the
// friction law smooth and stick).
TEST(MeshContact, TangentsOnAFaceMatchFiniteDifferences) {
  for (const FrictionLaw law_kind : {FrictionLaw::kSmooth, FrictionLaw::kStick}) {
    ModelBuilder b;
    const Mat3 Rm = ExpSO3(Vec3(0.15, -0.1, 0.4));
    const Vec3 n = Rm * Vec3::UnitZ();
    ContactObstacle slab;
    slab.name = "slab";
    slab.type = ObstacleType::kMesh;
    slab.point = Vec3(0.0, 0.0, -0.05);
    slab.rotation = Rm;
    slab.mesh = std::make_shared<TriangleMesh>(BoxMesh(Vec3(1.0, 1.0, 0.05)));
    b.AddObstacle(slab);
    const double r = 0.03, delta = 1e-3;
    const Vec3 c1(0.01, 0.0, 0.02);
    const Mat3 R1 = ExpSO3(Vec3(0.3, 0.2, -0.1));
    const Vec3 centre = Vec3(0.2, 0.1, 0.0) + (r - 0.3 * delta) * n;
    const NodeId ball = b.AddNode(SE3{R1, centre - R1 * c1});
    b.AddRigidBody("ball", ball, 0.5, Vec3::Zero(), 0.001 * Mat3::Identity());
    b.AddContactShape({0, ContactShapeType::kSphere, c1, c1, r});
    // A rod of 3 elements above the slab, its nodes 0.4 onset deep and tilted a little.
    Material mat;
    mat.youngs_modulus = 1e7;
    mat.poisson_ratio = 0.3;
    mat.density = 1000.0;
    const double rr = 0.01;
    const Vec3 p0 = Rm * Vec3(-0.5, -0.3, 0.0) + (rr - 0.4 * delta) * n;
    const Vec3 p1 = Rm * Vec3(-0.2, -0.35, 0.0) + (rr - 0.2 * delta) * n;
    const RodId rod = b.AddStraightRod("rod", p0, p1, 3, Section::Circle(rr, mat));
    b.AddContactRod(rod, rr);
    ContactSettings law;
    law.stiffness = 1e5;
    law.onset = delta;
    law.friction = 0.4;
    law.slip_velocity = 0.05;
    law.friction_law = law_kind;
    b.SetContactSettings(law);
    const Model m = b.Build();
    Data d = MakeData(m);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < m.nv; ++i) d.v(i) = 0.3 * u(rng);
    d.time = 0.2;
    if (law_kind == FrictionLaw::kStick) {
      Data shifted = d;
      for (SE3& H : shifted.H) H.x += Vec3(1e-3, -5e-4, 0.0);
      AcceptContactHistory(m, shifted, true);
      d.contact_anchors = shifted.contact_anchors;
    }
    int active = 0;
    for (int i = 0; i < static_cast<int>(m.contact_pairs.size()); ++i)
      active += CalcContactState(m, d, i).active ? 1 : 0;
    EXPECT_EQ(active, 4);  // the ball and the rod's three elements
    KernelOptions o;
    o.dynamics = true;
    Eigen::VectorXd r0;
    Eigen::MatrixXd K, C;
    kind_assembly::AssembleKind<ContactKind>(m, d, o, &r0, &K, &C);
    const auto residual = [&](const Data& s) {
      Eigen::VectorXd res;
      kind_assembly::AssembleKind<ContactKind>(m, s, o, &res, nullptr, nullptr);
      return res;
    };
    const Eigen::MatrixXd K_fd = kind_assembly::FiniteDifference(m, d, residual, 1e-8);
    Eigen::MatrixXd C_fd(K.rows(), K.cols());
    for (int j = 0; j < K.cols(); ++j) {
      Data vp = d, vm = d;
      vp.v(j) += 1e-8;
      vm.v(j) -= 1e-8;
      C_fd.col(j) = (residual(vp) - residual(vm)) / 2e-8;
    }
    EXPECT_LT((K - K_fd).norm() / K_fd.norm(), 1e-6) << NameOf(law_kind);
    EXPECT_LT((C - C_fd).norm() / C_fd.norm(), 1e-6) << NameOf(law_kind);
  }
}

// A ball dropped onto a turned box, given as the analytic box and as its 12 triangles, with
// friction and an initial spin: the two trajectories agree to 1e-9.
TEST(MeshContact, BallFallingOnAMeshBoxFollowsTheAnalyticBox) {
  std::vector<Vec3> path[2];
  std::vector<double> force[2];
  for (int k = 0; k < 2; ++k) {
    ModelBuilder b;
    const Vec3 h(0.4, 0.3, 0.1);
    const Mat3 R = ExpSO3(Vec3(0.0, 0.0, 0.3));
    ContactObstacle box;
    box.name = "block";
    box.point = Vec3(0.0, 0.0, -0.1);
    box.rotation = R;
    if (k == 0) {
      box.type = ObstacleType::kBox;
      box.to = h;
    } else {
      box.type = ObstacleType::kMesh;
      box.mesh = std::make_shared<TriangleMesh>(BoxMesh(h));
    }
    b.AddObstacle(box);
    const NodeId node = b.AddNode(SE3{Mat3::Identity(), Vec3(0.1, 0.05, 0.05)});
    b.AddRigidBody("ball", node, 0.2, Vec3::Zero(), 2e-5 * Mat3::Identity());
    b.AddContactShape({0, ContactShapeType::kSphere, Vec3::Zero(), Vec3::Zero(), 0.02});
    ContactSettings law;
    law.stiffness = 2e4;
    law.onset = 2e-4;
    law.friction = 0.3;
    b.SetContactSettings(law);
    b.SetGravity(Vec3(0.0, 0.0, -kG));
    const Model m = b.Build();
    Data d = MakeData(m);
    d.v.segment<3>(0) = Vec3(0.3, -0.2, 0.0);
    d.v.segment<3>(3) = Vec3(5.0, 0.0, 2.0);
    Integrator integ;
    DynamicOptions opt;
    opt.rho_inf = 0.8;
    // Newton to its round-off floor: else the two runs differ by the tolerance.
    opt.residual_tolerance = 1e-14;
    opt.increment_tolerance = 1e-15;
    std::string message;
    ASSERT_TRUE(AssembleInitialState(m, d, &message)) << message;
    ASSERT_TRUE(InitializeDynamics(m, d, integ, opt, &message)) << message;
    for (int i = 0; i < 300; ++i) {
      const StepResult res = Step(m, d, integ, 1e-3);
      ASSERT_TRUE(res.ok) << res.message;
      path[k].push_back(d.H[0].x);
      force[k].push_back(CalcContactState(m, d, 0).normal_force);
    }
  }
  double peak = 0.0;
  for (std::size_t i = 0; i < path[0].size(); ++i) {
    EXPECT_LT((path[1][i] - path[0][i]).norm(), 1e-9) << i;
    EXPECT_NEAR(force[1][i], force[0][i], 1e-9 * std::max(1.0, force[0][i])) << i;
    peak = std::max(peak, force[0][i]);
  }
  EXPECT_GT(peak, 0.2 * kG);                                // it landed
  EXPECT_NEAR(force[0].back(), 0.2 * kG, 0.05 * 0.2 * kG);  // and rests
}

// A cantilever (16 elements) bent by a tip load onto a cylinder obstacle across it, and onto
// prisms of n facets inscribed in it (a facet on top): the tip deflection and the support
// reaction converge to the cylinder's as the facets are refined (error ~ n^-2, the sagitta
// R (1 - cos(pi / n))).
TEST(MeshContact, CantileverOnATessellatedCylinderConvergesToTheCylinder) {
  const double L = 1.0, radius = 0.01, P = 0.2, clearance = 0.002, R = 0.05;
  Material mat;
  mat.youngs_modulus = 2e9;
  mat.poisson_ratio = 0.3;
  mat.density = 1000.0;
  const Section section = Section::Circle(radius, mat);
  const int facets[] = {0, 16, 64, 256};
  double tip[4], reaction[4];
  for (int k = 0; k < 4; ++k) {
    ModelBuilder b;
    const RodId rod = b.AddStraightRod("beam", Vec3::Zero(), Vec3(L, 0.0, 0.0), 16, section);
    b.FixNode(b.RodNodes(RodId(0)).front());
    PointLoad load;
    load.node = b.RodNodes(RodId(0)).back();
    load.force = Vec3(0.0, 0.0, -P);
    b.AddPointLoad(load);
    b.AddContactRod(rod, radius);
    const double z = -radius - clearance - R;
    ContactObstacle post;
    post.name = "post";
    if (k == 0) {
      post.type = ObstacleType::kCylinder;
      post.point = Vec3(0.98 * L, -0.2, z);
      post.to = Vec3(0.98 * L, 0.2, z);
      post.radius = R;
    } else {
      // The prism's axis along y, a facet on top (R cos(pi / n) high).
      post.type = ObstacleType::kMesh;
      post.point = Vec3(0.98 * L, 0.0, z);
      post.rotation = ExpSO3(Vec3(M_PI / 2, 0.0, 0.0));  // z -> -y, y -> z
      post.mesh =
          std::make_shared<TriangleMesh>(PrismMesh(facets[k], R, 0.4, M_PI / 2 + M_PI / facets[k]));
    }
    b.AddObstacle(post);
    ContactSettings law;
    law.stiffness = 1e5;
    law.onset = 1e-4;
    b.SetContactSettings(law);
    const Model m = b.Build();
    Data d = MakeData(m);
    StaticOptions o;
    o.load_steps = 20;
    const StaticResult res = SolveStatic(m, d, o);
    ASSERT_TRUE(res.converged) << res.message;
    tip[k] = d.H[static_cast<std::size_t>(m.rods[0].nodes.back())].x.z();
    reaction[k] = 0.0;
    for (int i = 0; i < static_cast<int>(m.contact_pairs.size()); ++i) {
      const ContactState c = CalcContactState(m, d, i);
      if (c.active) reaction[k] += c.normal_force * c.normal.z();
    }
  }
  EXPECT_GT(reaction[0], 0.3 * P);
  double last = INFINITY;
  for (int k = 1; k < 4; ++k) {
    const double sagitta = R * (1.0 - std::cos(M_PI / facets[k]));
    const double err = std::abs(tip[k] - tip[0]);
    std::printf("facets %d: tip error %.3e m (sagitta %.3e m), reaction error %.3e N\n", facets[k],
                err, sagitta, std::abs(reaction[k] - reaction[0]));
    EXPECT_LT(err, 1.5 * sagitta) << facets[k];
    EXPECT_GT(err, 0.5 * sagitta) << facets[k];
    EXPECT_LT(err, last / 10.0) << facets[k];  // ~ 16 for 4 times the facets
    last = err;
  }
  EXPECT_LT(std::abs(reaction[3] - reaction[0]), 1e-3 * P);
}

// A ball on a height field that is a plane tilted by 10 degrees (a 20 x 7 grid of 0.05 m
// cells, the ball crossing their edges and diagonals), with the stick law: it rolls down without
// slip at a = (5/7) g sin(a), pressed by m g cos(a), against friction (2/7) m g sin(a).
TEST(MeshContact, BallRollsDownAHeightFieldSlopeAtFiveSeventhsGSinA) {
  const double a = 10.0 * M_PI / 180.0, mass = 0.1, r = 0.05;
  std::vector<double> heights;
  const int rows = 7, cols = 20;
  const double dx = 0.05, dy = 0.06;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) heights.push_back((j - 0.5 * (cols - 1)) * dx * std::tan(a));
  ModelBuilder b;
  ContactObstacle field;
  field.name = "terrain";
  field.type = ObstacleType::kHeightfield;
  field.mesh = std::make_shared<TriangleMesh>(HeightFieldMesh(heights, rows, cols, dx, dy));
  b.AddObstacle(field);
  const Vec3 n(-std::sin(a), 0.0, std::cos(a)), down(-std::cos(a), 0.0, -std::sin(a));
  // Start on the resting gap of m g cos(a) (docs/numerics.md, "Contact"), so that it does not
  // bounce.
  const double onset = 5e-4, stiffness = 1e5;
  const double gap = onset - std::sqrt(2.0 * onset * mass * kG * std::cos(a) / stiffness);
  const Vec3 start = Vec3(0.3, 0.013, 0.3 * std::tan(a)) + (r + gap) * n;
  const NodeId node = b.AddNode(SE3{Mat3::Identity(), start});
  b.AddRigidBody("ball", node, mass, Vec3::Zero(), 0.4 * mass * r * r * Mat3::Identity());
  b.AddContactShape({0, ContactShapeType::kSphere, Vec3::Zero(), Vec3::Zero(), r});
  ContactSettings law;
  law.stiffness = stiffness;
  law.onset = onset;
  law.friction = 0.3;
  law.friction_law = FrictionLaw::kStick;
  b.SetContactSettings(law);
  b.SetGravity(Vec3(0.0, 0.0, -kG));
  const Model m = b.Build();
  Data d = MakeData(m);
  Integrator integ;
  DynamicOptions opt;
  opt.rho_inf = 0.8;
  std::string message;
  ASSERT_TRUE(AssembleInitialState(m, d, &message)) << message;
  ASSERT_TRUE(InitializeDynamics(m, d, integ, opt, &message)) << message;
  const double h = 1e-3, T = 0.4;
  for (int i = 0; i < static_cast<int>(T / h + 0.5); ++i) {
    const StepResult res = Step(m, d, integ, h);
    ASSERT_TRUE(res.ok) << res.message;
  }
  const ContactState c = CalcContactState(m, d, 0);
  ASSERT_TRUE(c.active) << d.H[0].x.transpose() << " gap " << c.gap;
  const double acc = 5.0 / 7.0 * kG * std::sin(a);
  const Vec3 v = d.H[0].R * d.v.head<3>();  // the node's velocity, world
  EXPECT_NEAR(v.dot(down), acc * T, 1e-3 * acc * T);
  EXPECT_NEAR((d.H[0].x - start).dot(down), 0.5 * acc * T * T, 2e-3 * 0.5 * acc * T * T);
  EXPECT_LT((c.normal - n).norm(), 1e-12);
  EXPECT_NEAR(c.normal_force, mass * kG * std::cos(a), 1e-3 * mass * kG);
  EXPECT_NEAR(c.friction_force.norm(), 2.0 / 7.0 * mass * kG * std::sin(a), 1e-3 * mass * kG);
  EXPECT_LT(std::abs(v.y()), 1e-6);
}

}  // namespace
}  // namespace screwfem::mesh_contact_test
