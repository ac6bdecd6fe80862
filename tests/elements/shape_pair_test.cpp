// Tests of contact between two moving shapes (elements/shape_pair.h, method-next.md §N6): the
// residual against the gradient of the penalty potential, the stiffness against central
// differences through the retraction at the frozen closest parameters and normal (what the
// tangent linearises), the damping and friction blocks against differences in the velocities,
// for rod-rod, rod-capsule, sphere-capsule and parallel rod pairs; the closest points against
// sampling; and closed forms: a head-on impact of two free spheres (momentum conserved, the
// undamped rebound elastic to O(h^2)), and two crossing cantilevers pressed together (the
// contact force from the compliances).
#include "screwfem/elements/shape_pair.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/contact.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/statics.h"

namespace screwfem::shape_pair_test {
namespace {

double RelativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

// A pair and four node frames with velocities (item nodes 0, 1: side A; 2, 3: side B).
struct Case {
  Model model;
  ShapePair pair;
  SE3 H[4];
  Eigen::Matrix<double, 24, 1> eta;
};

enum class Kind { kRodRod, kRodCapsule, kSphereCapsule, kParallelRods, kSphereBox };

Case MakeCase(Kind kind, double mu, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random_vec = [&]() { return Vec3(u(rng), u(rng), u(rng)); };
  Case c;
  c.model.contact.stiffness = 1e5;
  c.model.contact.onset = 1e-3;
  c.model.contact.friction = mu;
  c.model.contact.slip_velocity = 0.05;
  c.pair.damping = 30.0;
  for (auto& H : c.H) H = SE3{ExpSO3(random_vec()), 0.1 * random_vec()};
  ShapePairSide& a = c.pair.side[0];
  ShapePairSide& b = c.pair.side[1];
  auto rod_side = [&](ShapePairSide& s, int first, const Vec3& p0, const Vec3& p1) {
    s.node[0] = first;
    s.node[1] = first + 1;
    s.end_node[1] = 1;
    s.radius = 0.01;
    c.H[first].x = p0;
    c.H[first + 1].x = p1;
  };
  auto rigid_side = [&](ShapePairSide& s, const Vec3& c0, const Vec3& c1, double radius) {
    s.node[0] = 0;
    s.offset[0] = c0;
    s.offset[1] = c1;
    s.radius = radius;
  };
  switch (kind) {
    case Kind::kRodRod:
      rod_side(a, 0, Vec3(-0.1, 0.0, 0.0), Vec3(0.1, 0.02, 0.0));
      rod_side(b, 2, Vec3(0.01, -0.1, -0.05), Vec3(-0.02, 0.1, -0.02));
      break;
    case Kind::kParallelRods:
      rod_side(a, 0, Vec3(-0.1, 0.0, 0.0), Vec3(0.1, 0.0, 0.0));
      rod_side(b, 2, Vec3(-0.05, 0.0, -0.03), Vec3(0.15, 0.0, -0.03));
      break;
    case Kind::kRodCapsule:
      rod_side(a, 0, Vec3(-0.1, 0.0, 0.0), Vec3(0.1, 0.02, 0.0));
      rigid_side(b, Vec3(0.03, -0.02, 0.01), Vec3(-0.05, 0.04, 0.0), 0.04);
      b.node[0] = 2;
      break;
    case Kind::kSphereCapsule:
      rigid_side(a, Vec3(0.03, -0.02, 0.01), Vec3(0.03, -0.02, 0.01), 0.05);
      rigid_side(b, Vec3(0.02, 0.01, -0.03), Vec3(-0.06, 0.02, 0.01), 0.03);
      b.node[0] = 2;
      break;
    case Kind::kSphereBox:
      rigid_side(a, Vec3(0.03, -0.02, 0.01), Vec3(0.03, -0.02, 0.01), 0.05);
      rigid_side(b, Vec3(0.02, 0.01, -0.03), Vec3(0.02, 0.01, -0.03), 0.0);
      b.half = Vec3(0.04, 0.06, 0.03);
      b.node[0] = 2;
      break;
  }
  if (a.node[1] == kGround) a.node[1] = 1;  // a rigid side's node 1 carries nothing
  if (b.node[1] == kGround) b.node[1] = 3;
  // Move side B along the normal so that the gap is -0.3 onset .. +0.5 onset.
  const SE3* H[4] = {&c.H[0], &c.H[1], &c.H[2], &c.H[3]};
  ShapePairGeometry G;
  EXPECT_TRUE(CalcShapePairGeometry(c.pair, H, 1.0, &G));
  const double target = c.model.contact.onset * (0.1 + 0.4 * u(rng));
  for (int k = 2; k < 4; ++k) c.H[k].x += (G.gap - target) * G.normal;
  for (int i = 0; i < 24; ++i) c.eta(i) = 0.3 * u(rng);
  return c;
}

// The pair's terms at frames H (frozen geometry when `frozen` is given).
ElementTerms<4> Terms(const Case& c, const SE3 (&frames)[4], const Eigen::Matrix<double, 24, 1>& eta,
                      const KernelOptions& o, const ShapePairGeometry* frozen) {
  const SE3* H[4] = {&frames[0], &frames[1], &frames[2], &frames[3]};
  ShapePairGeometry G;
  if (frozen)
    FreezeShapePairGeometry(c.pair, H, *frozen, &G);
  else
    EXPECT_TRUE(CalcShapePairGeometry(c.pair, H, 1.0, &G));
  NodeMotion<4> x;
  const Mat6 I = Mat6::Identity();
  for (int k = 0; k < 4; ++k) {
    x.H[k] = H[k];
    x.T[k] = &I;
  }
  x.eta = eta;
  x.eta_dot.setZero();
  ElementTerms<4> t;
  EXPECT_TRUE(CalcShapePairTerms(c.model, c.pair, G, x, o, &t));
  if (!t.active) {
    t.residual.setZero();
    t.stiffness.setZero();
    t.damping.setZero();
  }
  return t;
}

TEST(ShapePairKind, TangentsMatchFiniteDifferencesAtTheFrozenClosestPointsAndInTheVelocities) {
  for (Kind kind : {Kind::kRodRod, Kind::kRodCapsule, Kind::kSphereCapsule, Kind::kParallelRods,
                    Kind::kSphereBox}) {
    for (const double mu : {0.0, 0.4}) {
      for (unsigned seed : {1u, 2u, 3u}) {
        const Case c = MakeCase(kind, mu, seed);
        KernelOptions o;
        o.dynamics = true;
        const ElementTerms<4> t = Terms(c, c.H, c.eta, o, nullptr);
        ASSERT_TRUE(t.active) << int(kind);
        const SE3* H[4] = {&c.H[0], &c.H[1], &c.H[2], &c.H[3]};
        ShapePairGeometry G0;
        ASSERT_TRUE(CalcShapePairGeometry(c.pair, H, 1.0, &G0));
        // Equal and opposite forces: the world sum of the forces on the two sides is zero.
        Vec3 sum = Vec3::Zero();
        for (int k = 0; k < 4; ++k) sum += c.H[k].R * t.residual.segment<3>(6 * k);
        EXPECT_LT(sum.norm(), 1e-12 * t.residual.norm());
        Eigen::MatrixXd K_fd(24, 24), C_fd(24, 24);
        const double eps = 1e-7;
        for (int j = 0; j < 24; ++j) {
          SE3 p[4] = {c.H[0], c.H[1], c.H[2], c.H[3]}, m[4] = {c.H[0], c.H[1], c.H[2], c.H[3]};
          p[j / 6] = p[j / 6] * ExpSE3(eps * Vec6::Unit(j % 6));
          m[j / 6] = m[j / 6] * ExpSE3(-eps * Vec6::Unit(j % 6));
          K_fd.col(j) = (Terms(c, p, c.eta, o, &G0).residual - Terms(c, m, c.eta, o, &G0).residual) /
                        (2 * eps);
          Eigen::Matrix<double, 24, 1> vp = c.eta, vm = c.eta;
          vp(j) += eps;
          vm(j) -= eps;
          C_fd.col(j) =
              (Terms(c, c.H, vp, o, nullptr).residual - Terms(c, c.H, vm, o, nullptr).residual) /
              (2 * eps);
        }
        EXPECT_LT(RelativeError(t.stiffness, K_fd), 1e-6) << int(kind) << " mu " << mu;
        EXPECT_LT(RelativeError(t.damping, C_fd), 1e-6) << int(kind) << " mu " << mu;
      }
    }
  }
}

TEST(ShapePairKind, StaticForceIsTheGradientOfThePenaltyPotential) {
  for (Kind kind : {Kind::kRodRod, Kind::kRodCapsule, Kind::kSphereCapsule, Kind::kSphereBox}) {
    const Case c = MakeCase(kind, 0.4, 7);
    KernelOptions o;  // statics: no damping, no friction
    const Eigen::Matrix<double, 24, 1> r = Terms(c, c.H, c.eta, o, nullptr).residual;
    auto potential = [&](const SE3 (&frames)[4]) {
      const SE3* H[4] = {&frames[0], &frames[1], &frames[2], &frames[3]};
      ShapePairGeometry G;
      EXPECT_TRUE(CalcShapePairGeometry(c.pair, H, 1.0, &G));
      return ContactPotential(G.gap, c.model.contact.onset, c.model.contact.stiffness);
    };
    Eigen::Matrix<double, 24, 1> dpsi;
    const double eps = 1e-7;
    for (int j = 0; j < 24; ++j) {
      SE3 p[4] = {c.H[0], c.H[1], c.H[2], c.H[3]}, m[4] = {c.H[0], c.H[1], c.H[2], c.H[3]};
      p[j / 6] = p[j / 6] * ExpSE3(eps * Vec6::Unit(j % 6));
      m[j / 6] = m[j / 6] * ExpSE3(-eps * Vec6::Unit(j % 6));
      dpsi(j) = (potential(p) - potential(m)) / (2 * eps);
    }
    ASSERT_GT(r.norm(), 0.0);
    EXPECT_LT(RelativeError(r, dpsi), 1e-6) << int(kind);
  }
}

TEST(ShapePairGeometry, GapIsTheSampledMinimumDistanceAlsoForParallelSegments) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    ShapePair pair;
    pair.side[0].node[1] = 1;
    pair.side[0].end_node[1] = 1;
    pair.side[1].node[0] = 2;
    pair.side[1].node[1] = 3;
    pair.side[1].end_node[1] = 1;
    pair.side[0].radius = 0.01;
    pair.side[1].radius = 0.02;
    SE3 F[4];
    for (auto& H : F) H = SE3{Mat3::Identity(), Vec3(u(rng), u(rng), u(rng))};
    if (trial % 4 == 0) {  // parallel, with or without overlap
      const Vec3 d = F[1].x - F[0].x;
      F[3].x = F[2].x + (0.3 + u(rng)) * d;
    }
    const SE3* H[4] = {&F[0], &F[1], &F[2], &F[3]};
    ShapePairGeometry G;
    ASSERT_TRUE(CalcShapePairGeometry(pair, H, 10.0, &G));
    double best = INFINITY;
    const int ns = 300;
    for (int i = 0; i <= ns; ++i)
      for (int k = 0; k <= ns; ++k)
        best = std::min(best, (F[0].x + (F[1].x - F[0].x) * (double(i) / ns) -
                               F[2].x - (F[3].x - F[2].x) * (double(k) / ns))
                                  .norm());
    const double sampled = best - 0.03;
    EXPECT_LE(G.gap, sampled + 1e-12) << trial;
    EXPECT_GT(G.gap, sampled - 1e-4) << trial;
    // The surface points are the gap apart along the normal.
    EXPECT_NEAR(G.normal.dot(G.point[0] - G.point[1]), G.gap, 1e-12);
  }
}

// Two free spheres (no gravity) colliding head-on along x: m_1 = 1 kg at v = 1 m/s, m_2 = 2 kg
// at -0.5 m/s (total momentum 0), offset in y by `offset` for an oblique impact.
struct TwoSpheres {
  Model model;
  Data data;
  Integrator integ;
};

void MakeTwoSpheres(TwoSpheres* s, double mu, double zeta, double offset, double rho_inf) {
  ModelBuilder b;
  const double r = 0.05;
  const int n1 = b.AddNode(SE3{Mat3::Identity(), Vec3(-0.06, 0.0, 0.0)});
  const int n2 = b.AddNode(SE3{Mat3::Identity(), Vec3(0.06, offset, 0.0)});
  b.AddRigidBody("a", n1, 1.0, Vec3::Zero(), 0.001 * Mat3::Identity());
  b.AddRigidBody("b", n2, 2.0, Vec3::Zero(), 0.002 * Mat3::Identity());
  b.AddContactShape({0, ContactShapeType::kSphere, Vec3::Zero(), Vec3::Zero(), r});
  b.AddContactShape({1, ContactShapeType::kSphere, Vec3::Zero(), Vec3::Zero(), r});
  ContactSettings law;
  law.stiffness = 1e5;
  law.onset = 1e-4;
  law.friction = mu;
  law.slip_velocity = 1e-2;
  law.damping_ratio = zeta;
  b.SetContactSettings(law);
  b.SetInitialVelocity(n1, (Vec6() << 1.0, 0.0, 0.0, 0.0, 0.0, 0.0).finished());
  b.SetInitialVelocity(n2, (Vec6() << -0.5, 0.0, 0.0, 0.0, 0.0, 0.0).finished());
  s->model = b.Build();
  s->data = MakeData(s->model);
  DynamicOptions opt;
  opt.rho_inf = rho_inf;
  std::string message;
  ASSERT_TRUE(AssembleInitialState(s->model, s->data, &message)) << message;
  ASSERT_TRUE(InitializeDynamics(s->model, s->data, s->integ, opt, &message)) << message;
}

Vec3 Momentum(const TwoSpheres& s) {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < 2; ++i)
    p += s.model.bodies[static_cast<std::size_t>(i)].mass *
         (s.data.H[static_cast<std::size_t>(i)].R * s.data.v.segment<3>(6 * i));
  return p;
}

Vec3 AngularMomentum(const TwoSpheres& s) {
  Vec3 L = Vec3::Zero();
  for (int i = 0; i < 2; ++i) {
    const RigidBody& body = s.model.bodies[static_cast<std::size_t>(i)];
    const SE3& H = s.data.H[static_cast<std::size_t>(i)];
    L += body.mass * H.x.cross(H.R * s.data.v.segment<3>(6 * i)) +
         H.R * (body.inertia * s.data.v.segment<3>(6 * i + 3));
  }
  return L;
}

TEST(ShapePairValidation, HeadOnSpheresConserveMomentumAndReboundElasticallyWithoutDamping) {
  // Frictionless, undamped, rho_inf = 1: the relative speed 1.5 m/s reverses; the rebound error
  // falls with h (the law is C1 only: its kinks at g = delta and g = 0 are crossed inside a step).
  const double steps[3] = {1e-3, 5e-4, 2.5e-4};
  double errors[3];
  for (int k = 0; k < 3; ++k) {
    TwoSpheres s;
    MakeTwoSpheres(&s, 0.0, 0.0, 0.0, 1.0);
    ASSERT_EQ(s.model.shape_pairs.size(), 1u);
    const int n = static_cast<int>(std::lround(0.03 / steps[k]));
    double max_force = 0.0;
    for (int i = 0; i < n; ++i) {
      ASSERT_TRUE(Step(s.model, s.data, s.integ, steps[k]).ok);
      EXPECT_LT(Momentum(s).norm(), 1e-9);  // equal and opposite forces, no rotation
      max_force = std::max(max_force, CalcShapePairState(s.model, s.data, 0).normal_force);
    }
    EXPECT_GT(max_force, 10.0);  // the spheres did collide
    EXPECT_FALSE(CalcShapePairState(s.model, s.data, 0).active);
    const double v_rel = (s.data.v.segment<3>(0) - s.data.v.segment<3>(6)).x();
    errors[k] = std::abs(v_rel + 1.5) / 1.5;
  }
  // Measured 3.0e-3, 2.4e-3, 2.8e-4: not a clean order (the kinks), but elastic to < 0.5 %.
  for (double e : errors) EXPECT_LT(e, 5e-3);
  EXPECT_LT(errors[2], 0.2 * errors[0]);
  // Oblique, with friction and damping: the Lie-group scheme conserves momentum and angular
  // momentum about the origin only to its discretisation error (body-frame velocities of
  // rotating bodies): measured at two steps.
  double drift[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    TwoSpheres s;
    MakeTwoSpheres(&s, 0.4, 1.0, 0.05, 0.8);
    const Vec3 L0 = AngularMomentum(s);
    double spin = 0.0;
    const int n = static_cast<int>(std::lround(0.04 / steps[k]));
    for (int i = 0; i < n; ++i) {
      ASSERT_TRUE(Step(s.model, s.data, s.integ, steps[k]).ok);
      drift[k] = std::max(drift[k], Momentum(s).norm() + (AngularMomentum(s) - L0).norm());
      spin = std::max(spin, std::abs(s.data.v(5)));
    }
    EXPECT_GT(spin, 0.1);  // friction at the surface points spun the spheres
  }
  EXPECT_LT(drift[0], 1e-3);  // measured 4.6e-4 and 1.2e-4 (kg m/s + kg m^2/s)
  EXPECT_GT(drift[0] / drift[1], 3.0);  // second order
}

// A 1 kg sphere (r = 0.1) resting on the middle of a fixed box's top face, where no vertex or
// edge is near (k = 1e5, onset 1e-4: the penetration branch, gap onset/2 - m g / k); and a
// sphere whose centre is inside the box leaves through the nearest face.
TEST(ShapePairValidation, SphereRestsOnTheMiddleOfABoxFace) {
  const double gap = 0.5e-4 - 9.81 / 1e5;
  ModelBuilder b;
  const int box = b.AddNode(SE3{Mat3::Identity(), Vec3::Zero()});
  b.FixNode(box);
  b.AddRigidBody("table", box, 1.0, Vec3::Zero(), Mat3::Identity());
  b.AddContactShape({0, ContactShapeType::kBox, Vec3(0.0, 0.0, -0.05), Vec3(0.5, 0.4, 0.05), 0.0});
  const int ball = b.AddNode(SE3{Mat3::Identity(), Vec3(0.1, -0.05, 0.1 + gap)});
  b.AddRigidBody("ball", ball, 1.0, Vec3::Zero(), 0.004 * Mat3::Identity());
  b.AddContactShape({1, ContactShapeType::kSphere, Vec3::Zero(), Vec3::Zero(), 0.1});
  ContactSettings law;
  law.stiffness = 1e5;
  law.onset = 1e-4;
  b.SetContactSettings(law);
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  TwoSpheres s;
  s.model = b.Build();
  ASSERT_EQ(s.model.shape_pairs.size(), 1u);
  EXPECT_GT(s.model.shape_pairs[0].side[1].half.x(), 0.0);  // the box is side B
  s.data = MakeData(s.model);
  std::string message;
  ASSERT_TRUE(AssembleInitialState(s.model, s.data, &message)) << message;
  ASSERT_TRUE(InitializeDynamics(s.model, s.data, s.integ, DynamicOptions{}, &message)) << message;
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(Step(s.model, s.data, s.integ, 1e-3).ok);
  const ShapePairState c = CalcShapePairState(s.model, s.data, 0);
  ASSERT_TRUE(c.active);
  EXPECT_NEAR(c.normal_force, 9.81, 1e-6);
  EXPECT_NEAR(c.gap, gap, 1e-9);
  EXPECT_NEAR(c.normal.z(), 1.0, 1e-12);
  EXPECT_NEAR(s.data.H[1].x.z(), 0.1 + gap, 1e-9);
  // The centre inside the box, 0.01 below the top face: the exit is up, the gap -0.11.
  s.data.H[1].x = Vec3(0.1, -0.05, -0.01);
  const ShapePairState inside = CalcShapePairState(s.model, s.data, 0);
  EXPECT_NEAR(inside.gap, -0.11, 1e-12);
  EXPECT_NEAR(inside.normal.z(), 1.0, 1e-12);
}

// Two equal cantilevers crossing at right angles: the upper one's tip (loaded by P) over the
// middle of the lower one's last element, `clearance` between the surfaces. With the
// cantilever's flexibility C(x, y) = min^2 (3 max - min) / (6 EI) + min / GA, the upper tip
// drops by C(L, L) (P - R) and the lower chord's midpoint by R/4 (C11 + 2 C12 + C22) (R split
// equally to the element's nodes at L - h and L): R = (C(L,L) P - clearance + g) / (C(L,L) +
// c_low), g the law's gap at R.
TEST(ShapePairValidation, CrossingCantileversPressedTogetherShareTheLoadByTheirCompliances) {
  const double L = 0.5, radius = 0.005, P = 0.2, clearance = 0.002;
  const int ne = 8;
  const double h = L / ne;
  Material mat;
  mat.youngs_modulus = 2e9;
  mat.poisson_ratio = 0.3;
  mat.density = 1000.0;
  const Section section = Section::Circle(radius, mat);
  ModelBuilder b;
  const int upper = b.AddStraightRod("upper", Vec3(-L, 0.0, 0.0), Vec3::Zero(), ne, section);
  const double z = -2.0 * radius - clearance;
  const int lower =
      b.AddStraightRod("lower", Vec3(0.0, -L + 0.5 * h, z), Vec3(0.0, 0.5 * h, z), ne, section);
  b.FixNode(b.model().rods[0].nodes.front());
  b.FixNode(b.model().rods[1].nodes.front());
  PointLoad load;
  load.node = b.model().rods[0].nodes.back();
  load.force = Vec3(0.0, 0.0, -P);
  b.AddPointLoad(load);
  b.AddContactRod(upper, radius);
  b.AddContactRod(lower, radius);
  ContactSettings law;
  law.stiffness = 1e5;
  law.onset = 1e-4;
  b.SetContactSettings(law);
  const Model m = b.Build();
  ASSERT_EQ(m.shape_pairs.size(), static_cast<std::size_t>(ne * ne));
  Data d = MakeData(m);
  StaticOptions o;
  o.load_steps = 10;
  const StaticResult res = SolveStatic(m, d, o);
  ASSERT_TRUE(res.converged) << res.message;
  double R = 0.0, gap = 0.0;
  int active = 0;
  for (int i = 0; i < static_cast<int>(m.shape_pairs.size()); ++i) {
    const ShapePairState c = CalcShapePairState(m, d, i);
    if (!c.active) continue;
    ++active;
    R += c.normal_force * c.normal.z();
    gap = c.gap;
  }
  EXPECT_EQ(active, 1);
  const double EI = section.stiffness(4), GA = section.stiffness(2);
  auto C = [&](double x, double y) {
    const double lo = std::min(x, y), hi = std::max(x, y);
    return lo * lo * (3 * hi - lo) / (6 * EI) + lo / GA;
  };
  const double c_up = C(L, L);
  const double c_low = 0.25 * (C(L - h, L - h) + 2 * C(L - h, L) + C(L, L));
  ASSERT_GT(c_up * P, clearance);  // the upper tip alone would pass through the lower rod
  EXPECT_NEAR(R, (c_up * P - clearance + gap) / (c_up + c_low), 2e-3 * R);
  EXPECT_NEAR(gap, 1e-4 - std::sqrt(2e-4 * R / 1e5), 1e-9);
  const double w_upper = d.H[static_cast<std::size_t>(m.rods[0].nodes.back())].x.z();
  // The linear closed form for the tip (measured 2.3e-3 relative: rotations of 0.015 rad).
  EXPECT_NEAR(w_upper, -c_up * (P - R), 5e-3 * c_up * P);
}

}  // namespace
}  // namespace screwfem::shape_pair_test
