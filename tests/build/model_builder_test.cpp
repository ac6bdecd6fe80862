// ModelBuilder's geometry and joint API (AddRodAlongPath, FindNodeAt, AddJoint(JointSpec)) and
// the entity that its errors carry (InputError::entity()).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/model/data.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::model_builder_test {
namespace {

constexpr double kPi = std::numbers::pi;

Section UnitSection() {
  Section s;
  s.stiffness = Vec6::Ones();
  s.inertia = Vec6::Ones();
  return s;
}

// The error of `f`, which must throw InputError.
template <class F>
InputError ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError";
  return InputError("(none)");
}

// An L-shaped path in the xy plane, up = z: along +x to the corner, then along +y.
const std::vector<Vec3> kCorner = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0)};

TEST(AddRodAlongPath, NodesFollowTheSegmentsWithBisectorFramesAtThePathPoints) {
  ModelBuilder b;
  const RodId rod = b.AddRodAlongPath("L", kCorner, 2, UnitSection());
  const Model& m = b.model();
  const std::vector<int>& nodes = m.rods[rod].nodes;
  ASSERT_EQ(nodes.size(), 5u);
  const Vec3 positions[] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 0.5, 0}, {2, 1, 0}};
  // Section x axis: +x on the first segment, the bisector (x + y)/sqrt 2 at the corner, +y on
  // the second; z stays up, y = z cross x.
  const double c = std::sqrt(0.5);
  const Vec3 tangents[] = {{1, 0, 0}, {1, 0, 0}, {c, c, 0}, {0, 1, 0}, {0, 1, 0}};
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const SE3& H = m.nodes[static_cast<std::size_t>(nodes[i])].reference;
    EXPECT_LT((H.x - positions[i]).norm(), 1e-15) << "node " << i;
    EXPECT_LT((H.R.col(0) - tangents[i]).norm(), 1e-15) << "node " << i;
    EXPECT_LT((H.R.col(2) - Vec3::UnitZ()).norm(), 1e-15) << "node " << i;
    EXPECT_LT((H.R.col(1) - Vec3::UnitZ().cross(tangents[i])).norm(), 1e-15) << "node " << i;
    EXPECT_EQ(m.nodes[static_cast<std::size_t>(nodes[i])].name, "L." + std::to_string(i));
  }
  // The two elements at the corner each turn by half of its 90 degrees, about z.
  const Model built = b.Build();
  const Vec6 d1 = built.elements[1].d0, d2 = built.elements[2].d0;
  EXPECT_NEAR(d1(5), kPi / 4, 1e-14);
  EXPECT_NEAR(d2(5), kPi / 4, 1e-14);
  EXPECT_NEAR(d1.segment<2>(3).norm() + d2.segment<2>(3).norm(), 0.0, 1e-15);
}

TEST(AddRodAlongPath, TwoPointsMakeTheStraightRod) {
  ModelBuilder a, b;
  const Vec3 p0(0.1, 0.2, 0.3), p1(1.3, -0.4, 0.9);
  a.AddRodAlongPath("r", {p0, p1}, 5, UnitSection(), Vec3::UnitY());
  b.AddStraightRod("r", p0, p1, 5, UnitSection(), Vec3::UnitY());
  ASSERT_EQ(a.model().nodes.size(), b.model().nodes.size());
  for (std::size_t i = 0; i < a.model().nodes.size(); ++i) {
    EXPECT_EQ(a.model().nodes[i].reference.x, b.model().nodes[i].reference.x);
    EXPECT_EQ(a.model().nodes[i].reference.R, b.model().nodes[i].reference.R);
  }
}

TEST(AddRodAlongPath, ErrorsNameThePathPointOrTheSharedNode) {
  ModelBuilder b;
  const InputError back = ErrorOf([&] {
    b.AddRodAlongPath("zig", {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 0)}, 1, UnitSection());
  });
  EXPECT_EQ(back.entity().kind, EntityKind::kRod);
  EXPECT_EQ(back.entity().index, 0);
  EXPECT_EQ(back.entity().part, "path[1]");
  EXPECT_EQ(back.detail(), "the path turns back on itself here");
  const InputError zero = ErrorOf([&] {
    b.AddRodAlongPath("z", {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 0)}, 1, UnitSection());
  });
  EXPECT_EQ(zero.entity().part, "path[2]");
  EXPECT_EQ(zero.detail(), "zero-length segment (its end points coincide)");
  // A weld onto a node whose section frame differs (the second rod leaves at a right angle).
  const RodId first = b.AddRodAlongPath("a", {Vec3(0, 0, 0), Vec3(1, 0, 0)}, 2, UnitSection());
  const NodeId end = b.RodNodes(first).back();
  const InputError kink = ErrorOf([&] {
    b.AddRodAlongPath("b", {Vec3(1, 0, 0), Vec3(1, 1, 0)}, 2, UnitSection(), Vec3::UnitZ(), end);
  });
  EXPECT_EQ(kink.entity().kind, EntityKind::kRod);
  EXPECT_EQ(kink.entity().index, 1);
  EXPECT_EQ(kink.entity().part, "start_node");
}

TEST(FindNodeAt, FindsTheNodeThatTwoWeldedRodsShare) {
  ModelBuilder b;
  const RodId a = b.AddRodAlongPath("a", {Vec3(0, 0, 0), Vec3(1, 0, 0)}, 4, UnitSection());
  const NodeId shared = b.RodNodes(a).back();
  const RodId c = b.AddRodAlongPath("c", {Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0)}, 3,
                                    UnitSection(), Vec3::UnitZ(), shared);
  EXPECT_EQ(b.RodNodes(c).front(), shared);
  EXPECT_EQ(b.FindNodeAt(Vec3(1, 0, 0)).node, shared);
  EXPECT_EQ(b.FindNodeAt(Vec3(1, 0, 0), c).node, shared);
  EXPECT_EQ(b.FindNodeAt(Vec3(1, 0, 0) + Vec3::Constant(1e-9), a).node, shared);
  // Between nodes: none within the tolerance; the nearest and its distance are reported.
  const NodeMatch miss = b.FindNodeAt(Vec3(0.1, 0, 0), a);
  EXPECT_EQ(miss.node, -1);
  EXPECT_EQ(miss.nearest, b.RodNodes(a).front());
  EXPECT_NEAR(miss.distance, 0.1, 1e-15);
  EXPECT_EQ(b.FindNodeAt(Vec3(0.1, 0, 0), a, 0.2).node, miss.nearest);
  // The welded rods form one piece: the model builds and uses one node less.
  const Model m = b.Build();
  EXPECT_EQ(m.nodes.size(), 5u + 7u - 1u);
}

// A bob of mass m on a massless bar of length L, hanging from a revolute joint about z, released
// at rest at a small angle theta0 from the vertical (the reference configuration): its period is
// 2 pi sqrt(L/g) (1 + theta0^2/16 + ...).
TEST(JointSpec, PendulumHasTheSmallAnglePeriod) {
  constexpr double kG = 9.81, kL = 0.5, kTheta0 = 0.02;
  ModelBuilder b;
  const NodeId pivot = b.AddNode(SE3::Identity(), "pivot");
  const Vec3 com(kL * std::sin(kTheta0), -kL * std::cos(kTheta0), 0.0);
  b.AddRigidBody("bob", pivot, 2.0, com, 1e-10 * Mat3::Identity());
  JointSpec pin;
  pin.name = "pin";
  pin.type = JointType::kRevolute;
  pin.node_b = pivot;
  pin.axis = Vec3::UnitZ();
  const JointId joint = b.AddJoint(pin);
  b.SetGravity(Vec3(0.0, -kG, 0.0));
  const Model model = b.Build();
  ASSERT_EQ(model.joints[joint].k(), 1);
  Data data = MakeData(model);
  Integrator integ;
  DynamicOptions opt;
  opt.rho_inf = 1.0;
  ASSERT_TRUE(InitializeDynamics(model, data, integ, opt));
  const int coord = model.joints[joint].coord;
  // The angle swings to -2 theta0 and back; a period is two zero crossings of the velocity
  // after the start (linear interpolation within the step).
  const double h = 1e-3;
  const double period = 2.0 * kPi * std::sqrt(kL / kG) * (1.0 + kTheta0 * kTheta0 / 16.0);
  double t = 0.0, v_prev = 0.0, crossing = 0.0;
  int crossings = 0;
  while (crossings < 2 && t < 2.0 * period) {
    ASSERT_TRUE(Step(model, data, integ, h).ok);
    t += h;
    const double v = data.v(coord);
    if (t > h && v_prev != 0.0 && (v > 0.0) != (v_prev > 0.0)) {
      crossing = t - h * v / (v - v_prev);
      ++crossings;
    }
    v_prev = v;
  }
  ASSERT_EQ(crossings, 2);
  // Generalized-alpha's phase error is O((w h)^2) ~ 2e-5 here.
  EXPECT_NEAR(crossing / period, 1.0, 1e-4);
}

TEST(JointSpec, SetsSpringsDamperRestAndDriveInOneCall) {
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Translation(Vec3(1, 0, 0)), "n");
  b.AddRigidBody("body", node, 1.0, Vec3::Zero(), Mat3::Identity());
  JointSpec s;
  s.name = "slide";
  s.type = JointType::kPrismatic;
  s.node_a = kGround;
  s.node_b = node;
  s.point = Vec3(1, 0, 0);
  s.axis = Vec3::UnitX();
  s.stiffness(0) = 10.0;
  s.damping(0) = 0.5;
  s.rest(0) = 0.01;
  s.drive = DriveKind::kPrescribed;
  s.drive_profile = Profile::Ramp(0.0, 1.0, 0.2);
  const Model m = [&] {
    b.AddJoint(s);
    return b.Build();
  }();
  const Joint& j = m.joints[0];
  EXPECT_EQ(j.stiffness(0), 10.0);
  EXPECT_EQ(j.damping(0), 0.5);
  EXPECT_EQ(j.rest(0), 0.01);
  EXPECT_EQ(j.drive, DriveKind::kPrescribed);
  EXPECT_EQ(j.drive_coord, 0);
  EXPECT_GE(j.drive_row, 0);
  EXPECT_DOUBLE_EQ(j.drive_profile(0.5), 0.1);
  // The joint frame sits at the point on both sides.
  EXPECT_LT((j.offset_a.x - Vec3(1, 0, 0)).norm(), 1e-15);
  EXPECT_LT(j.offset_b.x.norm(), 1e-15);
}

TEST(BuildErrors, CarryTheEntityTheyAreAbout) {
  {  // a joint whose frames do not coincide in the reference configuration
    ModelBuilder b;
    const NodeId n0 = b.AddNode(SE3::Identity());
    const NodeId n1 = b.AddNode(SE3::Translation(Vec3(1, 0, 0)));
    b.AddRigidBody("b0", n0, 1.0, Vec3::Zero(), Mat3::Identity());
    b.AddRigidBody("b1", n1, 1.0, Vec3::Zero(), Mat3::Identity());
    b.AddJointAt("ok", JointType::kRevolute, kGround, n0, Vec3::Zero());
    Joint bad;
    bad.name = "apart";
    bad.type = JointType::kRevolute;
    bad.node_a = n0;
    bad.node_b = n1;
    bad.basis = JointBasis(JointType::kRevolute, Vec3::UnitZ(), Vec3::Zero(), 0.0);
    b.AddJoint(bad);  // identity offsets: the frames are 1 m apart
    const InputError e = ErrorOf([&] { b.Build(); });
    EXPECT_EQ(e.entity().kind, EntityKind::kJoint);
    EXPECT_EQ(e.entity().index, 1);
    EXPECT_NE(std::string(e.what()).find("do not coincide"), std::string::npos) << e.what();
  }
  {  // a node that nothing uses
    ModelBuilder b;
    b.AddNode(SE3::Identity(), "used");
    b.AddNode(SE3::Identity(), "lonely");
    b.AddRigidBody("body", NodeId(0), 1.0, Vec3::Zero(), Mat3::Identity());
    b.FixNode(NodeId(0));
    const InputError e = ErrorOf([&] { b.Build(); });
    EXPECT_EQ(e.entity().kind, EntityKind::kNode);
    EXPECT_EQ(e.entity().index, 1);
  }
  {  // a joint spec with a side that is no node
    ModelBuilder b;
    b.AddNode(SE3::Identity());
    JointSpec s;
    s.name = "j";
    s.node_b = NodeId(7);
    const InputError e = ErrorOf([&] { b.AddJoint(s); });
    EXPECT_EQ(e.entity().kind, EntityKind::kJoint);
    EXPECT_EQ(e.entity().index, 0);
    EXPECT_EQ(e.entity().part, "node_b");
    EXPECT_EQ(std::string(e.what()), "joint 'j': invalid node 7");
  }
  {  // a rigid body without mass
    ModelBuilder b;
    const NodeId n = b.AddNode(SE3::Identity());
    b.AddRigidBody("first", n, 1.0, Vec3::Zero(), Mat3::Identity());
    b.AddRigidBody("second", n, -1.0, Vec3::Zero(), Mat3::Identity());
    b.FixNode(n);
    const InputError e = ErrorOf([&] { b.Build(); });
    EXPECT_EQ(e.entity().kind, EntityKind::kBody);
    EXPECT_EQ(e.entity().index, 1);
  }
}

// Values an actuator's type does not use are errors, not ignored (issue 40 item 6): the axial
// component of a chamber's or muscle's offset, a vector on a chamber, max_stress on a pressure
// chamber, area, offset or max_stress on a rest strain or active stress. The error names the
// part.
TEST(ModelBuilder, ActuatorValuesItsTypeDoesNotUseAreErrors) {
  auto error = [](auto edit) {
    ModelBuilder b;
    const RodId rod = b.AddStraightRod("r", Vec3::Zero(), Vec3::UnitX(), 2, UnitSection());
    Actuator a;
    a.name = "a";
    a.type = ActuatorType::kPressure;
    a.rod = rod;
    a.area = 1e-4;
    a.offset = Vec3(0.0, 0.01, 0.0);
    edit(a);
    b.AddActuator(a);
    return ErrorOf([&] { b.Build(); });
  };
  InputError e = error([](Actuator& a) { a.offset.x() = 0.001; });
  EXPECT_EQ(e.entity().kind, EntityKind::kActuator);
  EXPECT_EQ(e.entity().part, "offset");
  EXPECT_NE(std::string(e.what()).find("the first (axial) component must be 0"), std::string::npos)
      << e.what();
  e = error([](Actuator& a) {
    a.type = ActuatorType::kMuscle;
    a.max_stress = 1e5;
    a.offset.x() = -0.002;
  });
  EXPECT_EQ(e.entity().part, "offset");
  e = error([](Actuator& a) { a.vector(0) = 1.0; });
  EXPECT_EQ(e.entity().part, "vector");
  e = error([](Actuator& a) { a.max_stress = 1e5; });
  EXPECT_EQ(e.entity().part, "max_stress");
  EXPECT_NE(std::string(e.what()).find("is not used by a pressure chamber"), std::string::npos)
      << e.what();
  e = error([](Actuator& a) {
    a.type = ActuatorType::kRestStrain;
    a.area = 0.0;
    a.vector(5) = 1.0;
  });
  EXPECT_EQ(e.entity().part, "offset");
  EXPECT_NE(std::string(e.what()).find("is not used by type 'rest_strain'"), std::string::npos)
      << e.what();
}

}  // namespace
}  // namespace screwfem::model_builder_test
