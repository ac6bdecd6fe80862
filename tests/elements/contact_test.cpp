// Tests of frictional contact (elements/contact.h, docs/numerics.md, "Contact"): the tangent blocks
// against central finite differences through the retraction and in the velocities, the
// normal force against the gradient of the penalty potential, the closest-point geometry
// against sampling, and closed-form motions: resting on a plane (T6.1), Coulomb sliding and
// stopping distance (T6.2), an incline below and above the friction angle, energy that never
// increases with damping (T6.4), and a cantilever pressed onto a plane against the closed form
// of a point support.
#include "screwfem/elements/contact.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/statics.h"

namespace screwfem::contact_test {
namespace {

constexpr double kG = 9.81;

double RelativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

// Assembles the contact pairs alone over all nodes (6 rows each).
void AssembleContacts(const Model& m, const Data& d, const KernelOptions& o, Eigen::VectorXd* r,
                      Eigen::MatrixXd* K, Eigen::MatrixXd* C) {
  const int n = static_cast<int>(m.nodes.size());
  r->setZero(6 * n);
  if (K) K->setZero(6 * n, 6 * n);
  if (C) C->setZero(6 * n, 6 * n);
  ContactKind::ForEach(m, [&](const int& item, const int(&nodes)[2]) {
    NodeMotion<2> x;
    const Mat6 I = Mat6::Identity();
    for (int i = 0; i < 2; ++i) {
      x.H[i] = &NodeFrame(d, nodes[i]);
      x.T[i] = &I;
    }
    GatherNodeMotion<2>(m, d, nodes, &x.eta, &x.eta_dot);
    ElementTerms<2> t;
    ASSERT_TRUE(ContactKind::Calc(m, d, item, x, o, &t));
    if (!t.active) return;
    for (int a = 0; a < 2; ++a) {
      if (nodes[a] == kGround) continue;
      r->segment<6>(6 * nodes[a]) += t.residual.segment<6>(6 * a);
      for (int b = 0; b < 2; ++b) {
        if (nodes[b] == kGround) continue;
        if (K && t.has_stiffness)
          K->block<6, 6>(6 * nodes[a], 6 * nodes[b]) += t.stiffness.block<6, 6>(6 * a, 6 * b);
        if (C && t.has_damping)
          C->block<6, 6>(6 * nodes[a], 6 * nodes[b]) += t.damping.block<6, 6>(6 * a, 6 * b);
      }
    }
  });
}

// Two rigid bodies with shapes off their node origins and a short rod, all slightly into a
// tilted plane, with random frames and velocities.
struct Scene {
  Model model;
  Data data;
};

Scene MakeTouchingScene(double friction, unsigned seed,
                        FrictionLaw friction_law = FrictionLaw::kSmooth) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ModelBuilder b;
  const Vec3 normal = Vec3(0.2, -0.1, 1.0).normalized();
  ContactObstacle plane;
  plane.name = "ground";
  plane.normal = normal;
  b.AddObstacle(plane);
  // Body 0: a sphere at an offset; body 1: a capsule. Each placed so one end sits 0.3 onset
  // below the surface (gap -0.3 delta .. +0.5 delta over the seeds).
  const double r = 0.05, delta = 1e-3;
  const Mat3 R0 = ExpSO3(Vec3(u(rng), u(rng), u(rng)));
  const Vec3 c0(0.03, -0.02, 0.01);
  const Vec3 x0 = Vec3(0.1, 0.2, 0.0) - R0 * c0 + (r + 0.5 * delta * u(rng)) * normal;
  const NodeId n0 = b.AddNode(SE3{R0, x0});
  b.AddRigidBody("ball", n0, 2.0, Vec3::Zero(), 0.01 * Mat3::Identity());
  b.AddContactShape({0, ContactShapeType::kSphere, c0, c0, r});
  const Mat3 R1 = ExpSO3(Vec3(u(rng), u(rng), u(rng)));
  const Vec3 c1a(0.05, 0.0, 0.02), c1b(-0.05, 0.01, 0.0);
  const Vec3 x1 = Vec3(-0.3, 0.1, 0.0) - R1 * c1a + (r + 0.5 * delta * u(rng)) * normal;
  const NodeId n1 = b.AddNode(SE3{R1, x1});
  b.AddRigidBody("pill", n1, 1.0, Vec3::Zero(), 0.01 * Mat3::Identity());
  b.AddContactShape({1, ContactShapeType::kCapsule, c1a, c1b, r});
  // A rod of two elements lying just into the plane (its node spheres).
  Material steel;
  steel.youngs_modulus = 1e7;
  steel.poisson_ratio = 0.3;
  steel.density = 1000.0;
  const Vec3 t = normal.cross(Vec3::UnitX()).normalized();
  const Vec3 p0 = Vec3(0.5, 0.0, 0.0) + 0.02 * t.cross(normal) + (0.01 - 0.4 * delta) * normal;
  const RodId rod = b.AddStraightRod("rod", p0, p0 + 0.2 * t, 2, Section::Circle(0.01, steel));
  b.AddContactRod(rod, 0.01);
  ContactSettings law;
  law.stiffness = 1e5;
  law.onset = delta;
  law.friction = friction;
  law.slip_velocity = 0.05;
  law.friction_law = friction_law;
  law.static_friction = 1.25 * friction;
  b.SetContactSettings(law);
  Scene s{b.Build(), {}};
  s.data = MakeData(s.model);
  for (int i = 0; i < s.model.nv; ++i) s.data.v(i) = 0.3 * u(rng);
  return s;
}

// Central differences of the assembled contact residual through the retraction (K) and in the
// velocities (C); nodes are numbered as their unknowns (no fixed nodes).
void DifferenceTangents(const Scene& s, const KernelOptions& o, double eps, Eigen::MatrixXd* K,
                        Eigen::MatrixXd* C) {
  const int n = static_cast<int>(s.model.nodes.size());
  K->resize(6 * n, 6 * n);
  C->resize(6 * n, 6 * n);
  for (int j = 0; j < 6 * n; ++j) {
    Data p = s.data, m = s.data;
    const Vec6 dh = eps * Vec6::Unit(j % 6);
    p.H[static_cast<std::size_t>(j / 6)] = p.H[static_cast<std::size_t>(j / 6)] * ExpSE3(dh);
    m.H[static_cast<std::size_t>(j / 6)] = m.H[static_cast<std::size_t>(j / 6)] * ExpSE3(-dh);
    Eigen::VectorXd rp, rm;
    AssembleContacts(s.model, p, o, &rp, nullptr, nullptr);
    AssembleContacts(s.model, m, o, &rm, nullptr, nullptr);
    K->col(j) = (rp - rm) / (2 * eps);
    Data vp = s.data, vm = s.data;
    vp.v(j) += eps;
    vm.v(j) -= eps;
    AssembleContacts(s.model, vp, o, &rp, nullptr, nullptr);
    AssembleContacts(s.model, vm, o, &rm, nullptr, nullptr);
    C->col(j) = (rp - rm) / (2 * eps);
  }
}

TEST(ContactKind, TangentsMatchFiniteDifferencesThroughTheRetractionAndInTheVelocities) {
  for (const double mu : {0.0, 0.4}) {
    for (unsigned seed : {1u, 2u, 3u}) {
      Scene s = MakeTouchingScene(mu, seed);
      ASSERT_EQ(s.model.contact_pairs.size(), 1u + 2u + 3u);
      KernelOptions o;
      o.dynamics = true;
      Eigen::VectorXd r;
      Eigen::MatrixXd K, C;
      AssembleContacts(s.model, s.data, o, &r, &K, &C);
      ASSERT_GT(r.norm(), 0.0);
      Eigen::MatrixXd K_fd, C_fd;
      DifferenceTangents(s, o, 1e-7, &K_fd, &C_fd);
      EXPECT_LT(RelativeError(K, K_fd), 1e-6) << "mu " << mu << " seed " << seed;
      EXPECT_LT(RelativeError(C, C_fd), 1e-6) << "mu " << mu << " seed " << seed;
    }
  }
}

// What contacts.csv reports (CalcContactState) is the force the kernel puts in the residual:
// the world force -sum_k R_k r_k of its translation rows is f_n n + f_t, its moment about the
// origin is that of the force at the reported surface point, f_n is the normal component and
// f_t is tangential, opposes the slip and stays within the friction cone.
TEST(ContactKind, ReportedForceIsTheForceInTheKernelsResidual) {
  int active = 0;
  for (const double mu : {0.0, 0.4}) {
    for (unsigned seed : {1u, 2u, 3u, 4u}) {
      Scene s = MakeTouchingScene(mu, seed);
      KernelOptions o;
      o.dynamics = true;
      o.tangent = false;
      for (int i = 0; i < static_cast<int>(s.model.contact_pairs.size()); ++i) {
        const ContactPair& pair = s.model.contact_pairs[static_cast<std::size_t>(i)];
        NodeMotion<2> x;
        const Mat6 I = Mat6::Identity();
        for (int k = 0; k < 2; ++k) {
          x.H[k] = &NodeFrame(s.data, pair.node[k]);
          x.T[k] = &I;
        }
        GatherNodeMotion<2>(s.model, s.data, pair.node, &x.eta, &x.eta_dot);
        ElementTerms<2> t;
        ASSERT_TRUE(ContactKind::Calc(s.model, s.data, i, x, o, &t));
        const ContactState c = CalcContactState(s.model, s.data, i);
        ASSERT_EQ(c.active, t.active) << "mu " << mu << " seed " << seed << " pair " << i;
        if (!t.active) continue;
        ++active;
        Vec3 F = Vec3::Zero(), M = Vec3::Zero();
        for (int k = 0; k < 2; ++k) {
          const Vec3 f = -(x.H[k]->R * t.residual.segment<3>(6 * k));
          F += f;
          M += x.H[k]->x.cross(f) - x.H[k]->R * t.residual.segment<3>(6 * k + 3);
        }
        const Vec3 reported = c.normal_force * c.normal + c.friction_force;
        const double scale = F.norm();
        EXPECT_LT((F - reported).norm(), 1e-13 * scale) << "mu " << mu << " seed " << seed;
        EXPECT_LT((M - c.point.cross(reported)).norm(), 1e-12 * scale);
        EXPECT_NEAR(c.normal.dot(F), c.normal_force, 1e-13 * scale);
        EXPECT_LT(std::abs(c.normal.dot(c.friction_force)), 1e-13 * scale);
        EXPECT_LE(c.friction_force.norm(), mu * c.normal_force * (1.0 + 1e-14));
        // The slip: the surface point's velocity minus its normal part.
        Vec3 v = Vec3::Zero();
        ContactGeometry G;
        ASSERT_TRUE(CalcContactGeometry(s.model, pair, *x.H[0], *x.H[1], &G));
        for (int k = 0; k < 2; ++k)
          v += G.weight[k] * (x.H[k]->R * (x.eta.segment<3>(6 * k) +
                                           x.eta.segment<3>(6 * k + 3).cross(G.lever[k])));
        const Vec3 slip = v - c.normal * c.normal.dot(v);
        if (mu > 0.0) {
          EXPECT_LT(c.friction_force.dot(slip), 0.0);
        }
        // f_n = f_e(g) - c_n w(g) dg/dt.
        const double onset = s.model.contact.onset;
        const double f_e = CalcNormalLaw(c.gap, onset, s.model.contact.stiffness).force;
        EXPECT_NEAR(c.normal_force,
                    f_e - pair.damping * std::min(1.0, (onset - c.gap) / onset) * c.normal.dot(v),
                    1e-12 * scale);
      }
    }
  }
  EXPECT_GE(active, 16);
}

TEST(ContactKind, StaticForceIsTheGradientOfThePenaltyPotential) {
  Scene s = MakeTouchingScene(0.4, 5);
  KernelOptions o;  // statics: no damping, no friction
  Eigen::VectorXd r;
  AssembleContacts(s.model, s.data, o, &r, nullptr, nullptr);
  const int n = static_cast<int>(s.model.nodes.size());
  Eigen::VectorXd dpsi(6 * n);
  const double eps = 1e-7;
  auto potential = [&](const Data& d) {
    Energy E;
    for (int i = 0; i < static_cast<int>(s.model.contact_pairs.size()); ++i)
      ContactKind::AddEnergy(s.model, d, i, &E);
    return E.spring;
  };
  for (int j = 0; j < 6 * n; ++j) {
    Data p = s.data, m = s.data;
    const Vec6 dh = eps * Vec6::Unit(j % 6);
    p.H[static_cast<std::size_t>(j / 6)] = p.H[static_cast<std::size_t>(j / 6)] * ExpSE3(dh);
    m.H[static_cast<std::size_t>(j / 6)] = m.H[static_cast<std::size_t>(j / 6)] * ExpSE3(-dh);
    dpsi(j) = (potential(p) - potential(m)) / (2 * eps);
  }
  EXPECT_LT(RelativeError(r, dpsi), 1e-6);
}

TEST(ContactGeometry, GapToSphereAndCapsuleObstaclesIsTheSampledMinimumDistance) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Model m;
  ContactObstacle sphere, capsule;
  sphere.type = ObstacleType::kSphere;
  sphere.point = Vec3(0.1, 0.2, -0.1);
  sphere.radius = 0.3;
  capsule.type = ObstacleType::kCapsule;
  capsule.point = Vec3(-0.2, 0.1, 0.0);
  capsule.to = Vec3(0.4, -0.3, 0.2);
  capsule.radius = 0.1;
  m.obstacles = {sphere, capsule};
  for (int c = 0; c < 100; ++c) {
    ContactPair p;
    p.node[0] = 0;
    p.node[1] = 1;
    p.end_node[1] = 1;
    p.offset[0] = Vec3(u(rng), u(rng), u(rng));
    p.offset[1] = Vec3(u(rng), u(rng), u(rng));
    p.radius = 0.05;
    p.obstacle = c % 2;
    const SE3 H0{ExpSO3(Vec3(u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng))};
    const SE3 H1{ExpSO3(Vec3(u(rng), u(rng), u(rng))), Vec3(u(rng), u(rng), u(rng))};
    ContactGeometry G;
    ASSERT_TRUE(CalcContactGeometry(m, p, H0, H1, &G));
    const Vec3 A = H0.x + H0.R * p.offset[0], B = H1.x + H1.R * p.offset[1];
    const ContactObstacle& o = m.obstacles[static_cast<std::size_t>(p.obstacle)];
    double best = INFINITY;
    const int ns = 400;
    for (int i = 0; i <= ns; ++i) {
      const Vec3 x = A + (B - A) * (double(i) / ns);
      if (o.type == ObstacleType::kSphere) {
        best = std::min(best, (x - o.point).norm());
      } else {
        for (int k = 0; k <= ns; ++k)
          best = std::min(best, (x - (o.point + (o.to - o.point) * (double(k) / ns))).norm());
      }
    }
    const double sampled = best - o.radius - p.radius;
    // The sampled minimum exceeds the true one by at most the sampling step squared / length.
    EXPECT_LE(G.gap, sampled + 1e-12) << c;
    EXPECT_GT(G.gap, sampled - 2e-4) << c;
    // The surface point is on the shape's surface, the gap along the normal.
    EXPECT_NEAR((G.point + p.radius * G.normal - A).cross(B - A).norm() / (B - A).norm(),
                ((A + G.s * (B - A)) - A).cross(B - A).norm() / (B - A).norm(), 1e-12);
  }
}

// A rigid sphere (or box) on the plane z = 0 under gravity.
struct Puck {
  Model model;
  Data data;
  Integrator integ;
};

void MakePuck(Puck* p, ContactShapeType type, double mu, double eps_v, const Vec3& normal,
              const Vec3& v0, double height, double rho_inf = 0.8, double zeta = 1.0,
              FrictionLaw friction_law = FrictionLaw::kSmooth, double mu_s = -1.0) {
  ModelBuilder b;
  const Mat3 R = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), normal).toRotationMatrix();
  const NodeId n = b.AddNode(SE3{R, height * normal});
  b.AddRigidBody("puck", n, 1.0, Vec3::Zero(), 0.004 * Mat3::Identity());
  if (type == ContactShapeType::kSphere)
    b.AddContactShape({0, type, Vec3::Zero(), Vec3::Zero(), 0.1});
  else
    b.AddContactShape({0, type, Vec3::Zero(), Vec3(0.1, 0.1, 0.1), 0.0});
  b.AddObstacle({"ground", ObstacleType::kPlane, Vec3::Zero(), normal, Vec3::Zero(), 0.0});
  ContactSettings law;
  law.stiffness = 1e6;
  law.onset = 1e-4;
  law.friction = mu;
  law.slip_velocity = eps_v;
  law.damping_ratio = zeta;
  law.friction_law = friction_law;
  law.static_friction = mu_s;
  b.SetContactSettings(law);
  b.SetGravity(Vec3(0.0, 0.0, -kG));
  b.SetInitialVelocity(n, (Vec6() << R.transpose() * v0, Vec3::Zero()).finished());
  p->model = b.Build();
  p->data = MakeData(p->model);
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  std::string message;
  ASSERT_TRUE(AssembleInitialState(p->model, p->data, &message)) << message;
  ASSERT_TRUE(InitializeDynamics(p->model, p->data, p->integ, opt, &message)) << message;
}

// docs/numerics.md, "Contact": equilibrium gap g* = delta - sqrt(2 delta W / k) on the onset branch.
double RestingGap(double weight) { return 1e-4 - std::sqrt(2.0 * 1e-4 * weight / 1e6); }

TEST(ContactValidation, SphereRestsOnThePlaneAtRadiusPlusTheEquilibriumGap) {
  const double gap = RestingGap(kG);
  EXPECT_NEAR(gap, 5.571e-5, 1e-8);  // the note's value
  Puck p;
  MakePuck(&p, ContactShapeType::kSphere, 0.3, 1e-3, Vec3::UnitZ(), Vec3::Zero(), 0.1 + gap);
  for (int i = 0; i < 300; ++i) ASSERT_TRUE(Step(p.model, p.data, p.integ, 1e-3).ok);
  EXPECT_NEAR(p.data.H[0].x.z(), 0.1 + gap, 1e-12);
  const ContactState c = CalcContactState(p.model, p.data, 0);
  EXPECT_TRUE(c.active);
  EXPECT_NEAR(c.normal_force, kG, 1e-8);
  EXPECT_NEAR(c.point.z(), gap, 1e-12);
}

// A box sliding at v0 = 2 m/s with mu = 0.3: deceleration mu g, stop after v0^2 / (2 mu g)
// (T6.2). A solid sphere launched the same way slides until friction at its surface point has
// spun it up to rolling, then rolls on at 5/7 v0 (I = 2/5 m r^2; T6.6's check that friction acts
// at the surface point).
TEST(ContactValidation, SlidingBoxStopsAfterTheCoulombDistanceAndASphereRollsOnAtFiveSevenths) {
  const double mu = 0.3, v0 = 2.0, eps_v = 1e-3, h = 1e-3;
  Puck box;
  MakePuck(&box, ContactShapeType::kBox, mu, eps_v, Vec3::UnitZ(), Vec3(v0, 0.0, 0.0),
           0.1 + RestingGap(kG / 4.0));
  double v_a = 0.0;
  for (int i = 0; i < 900; ++i) {
    ASSERT_TRUE(Step(box.model, box.data, box.integ, h).ok);
    const double v = (box.data.H[0].R * box.data.v.head<3>()).x();  // world
    if (i == 99) v_a = v;
    if (i == 399) {
      EXPECT_NEAR((v_a - v) / 0.3, mu * kG, 1e-6 * mu * kG);
    }
  }
  const double distance = box.data.H[0].x.x();
  const double exact = v0 * v0 / (2.0 * mu * kG);
  EXPECT_NEAR(distance, exact, 0.01 * exact);
  // The creep-phase bound (docs/validation.md, T6.2).
  EXPECT_NEAR(distance, exact, eps_v * v0 / (mu * kG));
  EXPECT_LT((box.data.H[0].R * box.data.v.head<3>()).norm(), 1e-6);

  Puck ball;
  MakePuck(&ball, ContactShapeType::kSphere, mu, eps_v, Vec3::UnitZ(), Vec3(v0, 0.0, 0.0),
           0.1 + RestingGap(kG));
  for (int i = 0; i < 400; ++i) ASSERT_TRUE(Step(ball.model, ball.data, ball.integ, h).ok);
  const Vec3 v = ball.data.H[0].R * ball.data.v.head<3>();
  const Vec3 w = ball.data.H[0].R * ball.data.v.segment<3>(3);
  EXPECT_NEAR(v.x(), 5.0 / 7.0 * v0, 1e-3 * v0);
  EXPECT_NEAR(w.y() * 0.1, v.x(), 2.0 * eps_v);  // rolling: slip below the regularisation
}

TEST(ContactValidation, BoxOnAnInclineStaysBelowTheFrictionAngleAndSlidesAboveIt) {
  const double mu = 0.5, eps_v = 1e-3;
  for (const double angle_deg : {20.0, 35.0}) {
    const double a = angle_deg * M_PI / 180.0;
    // The plane tilted about y; gravity stays -z. Downhill: +x of the tilted frame.
    const Vec3 normal(std::sin(a), 0.0, std::cos(a));
    Puck p;
    MakePuck(&p, ContactShapeType::kBox, mu, eps_v, normal, Vec3::Zero(),
             0.1 + RestingGap(kG * std::cos(a) / 4.0));
    const double h = 1e-3, T = 0.5;
    const Vec3 downhill(std::cos(a), 0.0, -std::sin(a));
    const Vec3 x0 = p.data.H[0].x;
    double v_mid = 0.0;
    for (int i = 0; i < 500; ++i) {
      ASSERT_TRUE(Step(p.model, p.data, p.integ, h).ok);
      if (i == 249) v_mid = downhill.dot(p.data.H[0].R * p.data.v.head<3>());
    }
    const double s = downhill.dot(p.data.H[0].x - x0);
    if (std::tan(a) < mu) {
      // Creep of the regularised law: v = eps_v x / sqrt(1 - x^2), x = tan(a) / mu
      // (docs/theory.md §N6.5).
      const double x = std::tan(a) / mu;
      const double creep = eps_v * x / std::sqrt(1.0 - x * x);
      EXPECT_GE(s, 0.0);
      EXPECT_LT(s, 1.01 * creep * T);
      EXPECT_GT(s, 0.9 * creep * (T - 0.25));
    } else {
      // dv/dt = g (sin a - mu cos a), measured over the second half (slip >> eps_v).
      const double acc = kG * (std::sin(a) - mu * std::cos(a));
      const double v_end = downhill.dot(p.data.H[0].R * p.data.v.head<3>());
      EXPECT_NEAR((v_end - v_mid) / 0.25, acc, 1e-5 * acc);
      EXPECT_NEAR(s, 0.5 * acc * T * T, 0.01 * 0.5 * acc * T * T);
    }
  }
}

// ---- The stick law (docs/numerics.md, "Stick friction") ------------------------------------

ContactLawParameters StickLaw(double mu_k, double mu_s, double k_t, double c_t) {
  ContactLawParameters law;
  law.stiffness = 1e5;
  law.onset = 1e-3;
  law.damping = 40.0;
  law.friction = mu_k;
  law.law = FrictionLaw::kStick;
  law.static_friction = mu_s;
  law.tangential_stiffness = k_t;
  law.tangential_damping = c_t;
  return law;
}

// Inside the cone the force is the anchor's spring, f_t = -k_t P (u_e + d) - c_t P v_c; outside
// it is mu_k f_n along the trial; the threshold is mu_s after a stick and mu_k after a slip.
TEST(StickLaw, SticksInsideTheStaticConeAndSlipsAtTheKineticOne) {
  const ContactLawParameters law = StickLaw(0.4, 0.6, 2e4, 0.0);
  const Vec3 n = Vec3(0.1, -0.2, 1.0).normalized();
  const double gap = -2e-4;
  const double f_n = CalcNormalLaw(gap, law.onset, law.stiffness).force;  // 60 N
  const Vec3 t = n.cross(Vec3::UnitX()).normalized();
  // |f*| = k_t |d|: 0.5 mu_s f_n, between mu_k and mu_s, and 1.5 mu_s f_n.
  for (const double share : {0.5, 0.8, 1.5}) {
    for (const bool slipping_before : {false, true}) {
      AnchorTrial a;
      a.slip = share * law.static_friction * f_n / law.tangential_stiffness * t + 1e-5 * n;
      a.slipping = slipping_before;
      const ContactForce c = ContactForceLaw(gap, n, Vec3::Zero(), law, false, &a);
      ASSERT_TRUE(c.active);
      EXPECT_NEAR(c.normal.force, f_n, 1e-12 * f_n);
      const double limit = (slipping_before ? law.friction : law.static_friction) * f_n;
      const double trial = share * law.static_friction * f_n;
      if (trial <= limit) {
        EXPECT_FALSE(c.slipping);
        EXPECT_LT((c.friction + trial * t).norm(), 1e-12 * f_n);
        EXPECT_LT((c.deflection - trial / law.tangential_stiffness * t).norm(), 1e-16);
      } else {
        EXPECT_TRUE(c.slipping);
        EXPECT_LT((c.friction + law.friction * f_n * t).norm(), 1e-12 * f_n);
        EXPECT_NEAR(c.deflection.norm(), law.friction * f_n / law.tangential_stiffness, 1e-16);
      }
      EXPECT_NEAR(FrictionShare(c, law), c.slipping ? law.friction / law.static_friction : share,
                  1e-12);
    }
  }
}

// dF = direction df_n - slip_tangent dv_c - anchor_tangent dd against central differences of
// the law in the slip d, the velocity v_c and the gap, sticking and slipping.
TEST(StickLaw, TangentsMatchFiniteDifferences) {
  const ContactLawParameters law = StickLaw(0.4, 0.5, 3e4, 25.0);
  const Vec3 n = Vec3(0.3, 0.1, 1.0).normalized();
  const double gap = -1e-4;
  for (const double scale : {0.3, 10.0}) {  // stick, slip
    AnchorTrial a;
    a.deflection = scale * Vec3(1e-4, -2e-4, 0.5e-4);
    a.slip = scale * Vec3(-0.3e-4, 0.7e-4, 0.2e-4);
    const Vec3 v(0.02, -0.01, 0.004);
    const ContactForce c = ContactForceLaw(gap, n, v, law, true, &a);
    ASSERT_TRUE(c.active);
    EXPECT_EQ(c.slipping, scale > 1.0);
    const double eps = 1e-9;
    Mat3 dd, dv;
    for (int j = 0; j < 3; ++j) {
      AnchorTrial p = a, m = a;
      p.slip(j) += eps;
      m.slip(j) -= eps;
      dd.col(j) = (ContactForceLaw(gap, n, v, law, false, &p).force -
                   ContactForceLaw(gap, n, v, law, false, &m).force) /
                  (2 * eps);
      const Vec3 e = eps * Vec3::Unit(j);
      // The velocity's normal part changes f_n: through direction dforce_drate n^T.
      dv.col(j) = (ContactForceLaw(gap, n, v + e, law, false, &a).force -
                   ContactForceLaw(gap, n, v - e, law, false, &a).force) /
                  (2 * eps);
    }
    EXPECT_LT(RelativeError(-c.anchor_tangent, dd), 1e-6) << "scale " << scale;
    const Mat3 dv_exact = c.direction * c.normal.dforce_drate * n.transpose() - c.slip_tangent;
    EXPECT_LT(RelativeError(dv_exact, dv), 1e-6) << "scale " << scale;
    const double eg = 1e-10;
    const Vec3 dg = (ContactForceLaw(gap + eg, n, v, law, false, &a).force -
                     ContactForceLaw(gap - eg, n, v, law, false, &a).force) /
                    (2 * eg);
    EXPECT_LT((c.direction * c.normal.dforce_dgap - dg).norm(), 1e-6 * dg.norm());
  }
}

// The kernel's stiffness (through the retraction, with the anchors' slip) and damping against
// central differences, for rigid shapes and rod nodes sticking and slipping on a tilted plane.
TEST(ContactKind, StickLawTangentsMatchFiniteDifferences) {
  int sticking = 0, slipping = 0;
  for (unsigned seed : {1u, 2u, 3u}) {
    Scene s = MakeTouchingScene(0.4, seed, FrictionLaw::kStick);
    ASSERT_EQ(s.data.contact_anchors.size(), s.model.contact_pairs.size());
    // The anchors of a state displaced along the plane by up to 2 mm (some pairs stick,
    // some slip from there).
    const Vec3 normal = s.model.obstacles[0].normal;
    Data shifted = s.data;
    std::mt19937 rng(seed + 10);
    std::uniform_real_distribution<double> u(-2e-3, 2e-3);
    for (SE3& H : shifted.H) {
      const Vec3 d(u(rng), u(rng), u(rng));
      H.x += d - normal * normal.dot(d);
    }
    AcceptContactHistory(s.model, shifted, true);
    s.data.contact_anchors = shifted.contact_anchors;
    for (int i = 0; i < static_cast<int>(s.model.contact_pairs.size()); ++i) {
      const ContactState c = CalcContactState(s.model, s.data, i);
      if (!c.active) continue;
      ++(c.slipping ? slipping : sticking);
    }
    KernelOptions o;
    o.dynamics = true;
    Eigen::VectorXd r;
    Eigen::MatrixXd K, C;
    AssembleContacts(s.model, s.data, o, &r, &K, &C);
    Eigen::MatrixXd K_fd, C_fd;
    DifferenceTangents(s, o, 1e-8, &K_fd, &C_fd);
    EXPECT_LT(RelativeError(K, K_fd), 1e-6) << "seed " << seed;
    EXPECT_LT(RelativeError(C, C_fd), 1e-6) << "seed " << seed;
  }
  EXPECT_GE(sticking, 1);
  EXPECT_GE(slipping, 1);
}

// A box on an incline below the static friction angle does not move beyond its anchors'
// elastic deflection: after the landing transient its position changes by less than 1e-9 m
// over 1 s. Between the kinetic and the static angle a box resting there (its equilibrium found
// by a static solve, which the kinetic coefficient could not hold) stays, while a box launched
// downhill keeps sliding and speeds up at g (sin a - mu_k cos a); above the static angle it
// slides from rest at that acceleration. (Put down at rest between the two angles, the box's
// start, with undeflected anchors, is a jolt that may exceed the static cone: the damped
// anchor's force overshoots a step load by up to 13.5 % at critical damping.)
TEST(ContactValidation, StickLawHoldsABoxBelowTheStaticAngleWithoutCreep) {
  const double mu_k = 0.45, mu_s = 0.6;  // angles 24.23 and 30.96 degrees
  struct Case {
    double angle_deg, v0;
    bool settle;  // start from the static equilibrium
  };
  for (const Case& k : {Case{20.0, 0.0, false}, Case{27.0, 0.0, true}, Case{27.0, 0.5, false},
                        Case{33.0, 0.0, false}}) {
    const double a = k.angle_deg * M_PI / 180.0;
    const Vec3 normal(std::sin(a), 0.0, std::cos(a));
    const Vec3 downhill(std::cos(a), 0.0, -std::sin(a));
    Puck p;
    MakePuck(&p, ContactShapeType::kBox, mu_k, 1e-3, normal, k.v0 * downhill,
             0.1 + RestingGap(kG * std::cos(a) / 4.0), 0.8, 1.0, FrictionLaw::kStick, mu_s);
    if (k.settle) {
      StaticOptions so;
      so.start_load_factor = so.end_load_factor = 1.0;
      const StaticResult r = SolveStatic(p.model, p.data, so);
      ASSERT_TRUE(r.converged) << r.message;
      std::string message;
      ASSERT_TRUE(InitializeDynamics(p.model, p.data, p.integ, DynamicOptions{}, &message))
          << message;
    }
    const double h = 1e-3;
    Vec3 x_half = Vec3::Zero();
    double v_half = 0.0;
    for (int i = 0; i < 1500; ++i) {
      ASSERT_TRUE(Step(p.model, p.data, p.integ, h).ok) << k.angle_deg;
      if (i == 499) {
        x_half = p.data.H[0].x;
        v_half = downhill.dot(p.data.H[0].R * p.data.v.head<3>());
      }
    }
    const double v_end = downhill.dot(p.data.H[0].R * p.data.v.head<3>());
    const bool sticks = std::tan(a) < mu_s && k.v0 == 0.0;
    if (sticks) {
      EXPECT_LT((p.data.H[0].x - x_half).norm(), 1e-9) << k.angle_deg;
      EXPECT_LT(std::abs(v_end), 1e-9) << k.angle_deg;
      // The friction forces hold the weight's downhill part, each within its cone.
      Vec3 friction = Vec3::Zero();
      for (int i = 0; i < static_cast<int>(p.model.contact_pairs.size()); ++i) {
        const ContactState c = CalcContactState(p.model, p.data, i);
        if (!c.active) continue;
        EXPECT_LE(c.friction_share, 1.0 + 1e-12);
        friction += c.friction_force;
      }
      EXPECT_NEAR(friction.dot(downhill), -kG * std::sin(a), 1e-6 * kG);
    } else {
      const double acc = kG * (std::sin(a) - mu_k * std::cos(a));
      EXPECT_NEAR((v_end - v_half) / 1.0, acc, 1e-5 * kG) << k.angle_deg;
    }
  }
}

// A box launched at v0 with mu = 0.3 stops after v0^2 / (2 mu g) and then stays: no creep.
TEST(ContactValidation, StickLawStopsASlidingBoxAtTheCoulombDistanceAndHoldsIt) {
  const double mu = 0.3, v0 = 2.0, h = 1e-3;
  Puck box;
  MakePuck(&box, ContactShapeType::kBox, mu, 1e-3, Vec3::UnitZ(), Vec3(v0, 0.0, 0.0),
           0.1 + RestingGap(kG / 4.0), 0.8, 1.0, FrictionLaw::kStick);
  Vec3 x_stop = Vec3::Zero();
  for (int i = 0; i < 1500; ++i) {
    ASSERT_TRUE(Step(box.model, box.data, box.integ, h).ok);
    if (i == 999) x_stop = box.data.H[0].x;
  }
  const double exact = v0 * v0 / (2.0 * mu * kG);
  EXPECT_NEAR(box.data.H[0].x.x(), exact, 2e-3 * exact);
  EXPECT_LT((box.data.H[0].x - x_stop).norm(), 1e-9);
}

// Statics with friction: the box on a 20-degree incline (mu_s = 0.5) rests in a static solve,
// its friction forces carrying W sin a and its normal forces W cos a, each corner within its
// cone with its anchor deflected by its force over k_t; at 30 degrees no equilibrium exists
// and the solve says so.
TEST(ContactValidation, StickLawHoldsABoxOnAnInclineInStatics) {
  for (const double angle_deg : {20.0, 30.0}) {
    const double a = angle_deg * M_PI / 180.0;
    const Vec3 normal(std::sin(a), 0.0, std::cos(a));
    const Vec3 downhill(std::cos(a), 0.0, -std::sin(a));
    Puck p;
    MakePuck(&p, ContactShapeType::kBox, 0.5, 1e-3, normal, Vec3::Zero(),
             0.1 + RestingGap(kG * std::cos(a) / 4.0), 0.8, 1.0, FrictionLaw::kStick);
    StaticOptions o;
    o.load_steps = 4;
    const StaticResult r = SolveStatic(p.model, p.data, o);
    if (std::tan(a) < 0.5) {
      ASSERT_TRUE(r.converged) << r.message;
      Vec3 force = Vec3::Zero();
      for (int i = 0; i < static_cast<int>(p.model.contact_pairs.size()); ++i) {
        const ContactState c = CalcContactState(p.model, p.data, i, false);
        if (!c.active) continue;
        // Within the cone; the uphill corners, unloaded by the friction's moment about the
        // centre (N = W (cos a -+ sin a) / 4 per corner), may reach it and slip in place
        // (whether they do depends on the Newton path: the two compilers differ).
        EXPECT_LE(c.friction_force.norm(), 0.5 * c.normal_force * (1.0 + 1e-12));
        EXPECT_NEAR(c.deflection, c.friction_force.norm() / p.model.contact.stiffness, 1e-15);
        force += c.normal_force * c.normal + c.friction_force;
      }
      EXPECT_NEAR(force.dot(downhill), -kG * std::sin(a), 1e-8 * kG);
      EXPECT_NEAR(force.dot(normal), kG * std::cos(a), 1e-8 * kG);
    } else {
      EXPECT_FALSE(r.converged);
      EXPECT_FALSE(r.message.empty());
    }
  }
}

// The stick-slip oscillator: a block (mass m_b, a sphere whose rotation is locked) on a plane,
// pulled by a spring k whose far end moves at V (a series-elastic drive on a prismatic joint
// to a carriage of mass m_c; a second prismatic joint lets the block move along the normal).
// It sticks until the spring force reaches mu_s N, slips (harmonic at omega^2 = k / (m_b +
// m_c) about the kinetic force mu_k N) until it comes to rest again at the force
// (2 mu_k - mu_s) N, and sticks while the force climbs back: T_stick = 2 Y / V and T_slip =
// (pi + 2 atan(V / (omega Y))) / omega, Y = (mu_s - mu_k) N / k.
TEST(ContactValidation, StickSlipOscillatorHasTheClosedFormPeriod) {
  const double m_b = 1.0, m_c = 0.05, k = 100.0, V = 0.1, mu_s = 0.6, mu_k = 0.4, r = 0.05;
  const double N = m_b * kG, Y = (mu_s - mu_k) * N / k, omega = std::sqrt(k / (m_b + m_c));
  const double t_stick = 2.0 * Y / V;
  const double t_slip = (M_PI + 2.0 * std::atan(V / (omega * Y))) / omega;
  ModelBuilder b;
  const double z0 = r + RestingGap(N);
  const NodeId carriage = b.AddNode(SE3{Mat3::Identity(), Vec3(0.0, 0.0, z0)});
  b.AddRigidBody("carriage", carriage, m_c, Vec3::Zero(), 1e-4 * Mat3::Identity());
  const NodeId block = b.AddNode(SE3{Mat3::Identity(), Vec3(0.0, 0.0, z0)});
  b.AddRigidBody("block", block, m_b, Vec3::Zero(), 1e-3 * Mat3::Identity());
  JointSpec drive;
  drive.name = "drive";
  drive.type = JointType::kPrismatic;
  drive.node_b = carriage;
  drive.point = Vec3(0.0, 0.0, z0);
  drive.axis = Vec3::UnitX();
  drive.drive = DriveKind::kSeriesElastic;
  drive.stiffness(0) = k;
  const double t_end = 4.0;
  drive.drive_profile = Profile::Ramp(0.0, t_end, V * t_end);
  b.AddJoint(drive);
  JointSpec lift;
  lift.name = "lift";
  lift.type = JointType::kPrismatic;
  lift.node_a = carriage;
  lift.node_b = block;
  lift.point = Vec3(0.0, 0.0, z0);
  lift.axis = Vec3::UnitZ();
  b.AddJoint(lift);
  b.AddContactShape({1, ContactShapeType::kSphere, Vec3::Zero(), Vec3::Zero(), r});
  b.AddObstacle({"ground", ObstacleType::kPlane, Vec3::Zero(), Vec3::UnitZ(), Vec3::Zero(), 0.0});
  ContactSettings law;
  law.stiffness = 1e6;
  law.onset = 1e-4;
  law.friction = mu_k;
  law.static_friction = mu_s;
  b.SetContactSettings(law);
  b.SetGravity(Vec3(0.0, 0.0, -kG));
  Model model = b.Build();
  Data data = MakeData(model);
  Integrator integ;
  DynamicOptions opt;
  opt.rho_inf = 0.8;
  std::string message;
  ASSERT_TRUE(AssembleInitialState(model, data, &message)) << message;
  ASSERT_TRUE(InitializeDynamics(model, data, integ, opt, &message)) << message;
  // The starts of slip and of stick (the contact's state after each step).
  const double h = 1e-3;
  std::vector<double> slip_starts, stick_starts;
  bool slipping = false;
  for (int i = 0; i < static_cast<int>(t_end / h); ++i) {
    ASSERT_TRUE(Step(model, data, integ, h).ok) << data.time;
    const bool now = CalcContactState(model, data, 0).slipping;
    if (now && !slipping) slip_starts.push_back(data.time);
    if (!now && slipping) stick_starts.push_back(data.time);
    slipping = now;
  }
  // The first slip when the spring reaches mu_s N from rest; then the cycle.
  ASSERT_GE(slip_starts.size(), 4u);
  EXPECT_NEAR(slip_starts[0], mu_s * N / (k * V), 3e-3);
  for (std::size_t i = 1; i + 1 < slip_starts.size(); ++i) {
    EXPECT_NEAR(slip_starts[i + 1] - slip_starts[i], t_stick + t_slip, 0.005 * (t_stick + t_slip))
        << i;
    ASSERT_GT(stick_starts.size(), i);
    EXPECT_NEAR(stick_starts[i] - slip_starts[i], t_slip, 0.01 * t_slip) << i;
  }
}

// T6.4: a sphere dropped from 0.1 m with 1 m/s sideways; with damping the discrete energy
// T + V + Psi never increases by more than 1e-5 E_0 in a step.
TEST(ContactValidation, EnergyNeverIncreasesThroughAnImpactWithDamping) {
  Puck p;
  MakePuck(&p, ContactShapeType::kSphere, 0.3, 1e-2, Vec3::UnitZ(), Vec3(1.0, 0.0, 0.0), 0.2, 1.0,
           1.0);
  const double E0 = CalcEnergy(p.model, p.data).total() - 0.1 * kG;  // relative to rest height
  double E_prev = CalcEnergy(p.model, p.data).total();
  double max_rise = -INFINITY;
  bool touched = false;
  for (int i = 0; i < 400; ++i) {
    ASSERT_TRUE(Step(p.model, p.data, p.integ, 1e-3).ok);
    const double E = CalcEnergy(p.model, p.data).total();
    max_rise = std::max(max_rise, E - E_prev);
    E_prev = E;
    touched = touched || CalcContactState(p.model, p.data, 0).active;
  }
  EXPECT_TRUE(touched);
  EXPECT_LT(max_rise, 1e-5 * E0);
  // It lost the normal impact's energy and friction's: it rests, rolling or sliding no faster.
  EXPECT_LT(E_prev, 0.1 * kG + 0.5 + 1e-6);
}

// A clamped cantilever pushed by a tip load P towards a plane (the rod's node spheres) or a
// fixed sphere (its element capsules) below its tip: the obstacle carries R = P - w / c, w the
// tip deflection and c the tip compliance of the same rod without the obstacle (the closed
// form of a point support at the measured tip position), and c matches Timoshenko's
// L^3 / (3 EI) + L / (kappa G A).
TEST(ContactValidation, CantileverPressedOntoAPlaneOrASphereCarriesThePointSupportReaction) {
  const double L = 1.0, radius = 0.01, P = 0.2, clearance = 0.002;
  Material mat;
  mat.youngs_modulus = 2e9;
  mat.poisson_ratio = 0.3;
  mat.density = 1000.0;
  const Section section = Section::Circle(radius, mat);
  const double sphere_radius = 0.05;
  for (ObstacleType obstacle : {ObstacleType::kPlane, ObstacleType::kSphere}) {
    auto solve = [&](bool contact, double* tip_z, double* reaction) {
      ModelBuilder b;
      const RodId rod = b.AddStraightRod("beam", Vec3::Zero(), Vec3(L, 0.0, 0.0), 16, section);
      b.FixNode(b.RodNodes(RodId(0)).front());
      PointLoad load;
      load.node = b.RodNodes(RodId(0)).back();
      load.force = Vec3(0.0, 0.0, -P);
      b.AddPointLoad(load);
      if (contact) {
        b.AddContactRod(rod, radius);
        if (obstacle == ObstacleType::kPlane)
          b.AddObstacle({"floor", obstacle, Vec3(0.0, 0.0, -radius - clearance), Vec3::UnitZ(),
                         Vec3::Zero(), 0.0});
        else
          b.AddObstacle({"post", obstacle, Vec3(L, 0.0, -radius - clearance - sphere_radius),
                         Vec3::UnitZ(), Vec3::Zero(), sphere_radius});
        ContactSettings law;
        law.stiffness = 1e5;
        law.onset = 1e-4;
        b.SetContactSettings(law);
      }
      const Model m = b.Build();
      Data d = MakeData(m);
      StaticOptions o;
      o.load_steps = 20;
      const StaticResult res = SolveStatic(m, d, o);
      ASSERT_TRUE(res.converged) << NameOf(obstacle) << ": " << res.message;
      *tip_z = d.H[static_cast<std::size_t>(m.rods[0].nodes.back())].x.z();
      *reaction = 0.0;
      for (int i = 0; i < static_cast<int>(m.contact_pairs.size()); ++i) {
        const ContactState c = CalcContactState(m, d, i);
        if (!c.active) continue;
        const ContactPair& p = m.contact_pairs[static_cast<std::size_t>(i)];
        EXPECT_TRUE(p.node[0] == m.rods[0].nodes.back() || p.node[1] == m.rods[0].nodes.back());
        *reaction += c.normal_force * c.normal.z();
      }
    };
    double w_free = 0.0, w = 0.0, R = 0.0, unused = 0.0;
    solve(false, &w_free, &unused);
    solve(true, &w, &R);
    const double c = -w_free / P;
    const double EI = section.stiffness(4), GA = section.stiffness(2);
    EXPECT_NEAR(c, L * L * L / (3 * EI) + L / GA, 1e-3 * c);
    ASSERT_GT(-w_free, clearance);  // it would pass the plane
    EXPECT_NEAR(R, P + w / c, 1e-3 * P);
    EXPECT_GT(R, 0.3 * P);
    // The tip rests at the plane + radius + the law's gap for R.
    EXPECT_NEAR(w, -clearance + (1e-4 - std::sqrt(2e-4 * R / 1e5)), 1e-3 * clearance);
  }
}

}  // namespace
}  // namespace screwfem::contact_test
