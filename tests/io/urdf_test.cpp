// URDF robots (issue 38, item 5; io/urdf.h, docs/urdf.md). Asserted: the example arm read from
// examples/urdf/arm.urdf equals the same arm written as scene bodies and joints bit for bit
// (every node frame over 60 dynamic steps with prescribed, series-elastic and force drives,
// with contact shapes); a rotated base and a rotated inertial give the closed-form world
// inertia, axes and centre of mass; bad URDF files are errors naming the element and the
// scene's file:line:col of the include; the example scene (a soft gripper on the arm's flange)
// runs and its flange follows the forward kinematics of the joint angles.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "scene_error_util.h"
#include "screwfem/io/scene.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/io/urdf.h"
#include "screwfem/model/data.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::urdf_test {
namespace {

const std::string kArmUrdf = std::string(SCREWFEM_SOURCE_DIR) + "/examples/urdf/arm.urdf";
const std::string kExample = std::string(SCREWFEM_SOURCE_DIR) + "/examples/urdf/arm_gripper.yaml";

// The drives of both versions of the arm: the waist and the shoulder prescribed, the elbow
// series-elastic towards a sine, the wrist by a force; with a contact section (the links' shapes
// take part; a floor far below touches nothing) under gravity.
const std::string kDrives = R"(
      waist: {drive: {type: prescribed, profile: {type: bang_bang, t1: 0.1, value: 0.5}}}
      shoulder: {drive: {type: prescribed, profile: {type: bang_bang, t1: 0.1, value: 0.3}}}
      elbow: {stiffness: 50, drive: {type: series_elastic, profile: {type: sine, value: 0.2, frequency: 5}}}
      wrist: {drive: {type: force, profile: {type: ramp, t1: 0.05, value: 0.01}}}
)";
const std::string kTail = R"(
contact:
  obstacles:
    floor: {type: plane, point: [0, 0, -1], normal: [0, 0, 1]}
analysis: {type: dynamic, end_time: 0.06, step: 1e-3}
)";

std::string UrdfScene(const std::string& urdf_path) {
  return "gravity: [0, 0, -9.81]\nrobots:\n  arm:\n    urdf: " + urdf_path +
         "\n    joints:" + kDrives + kTail;
}

// The same arm as the scene's own bodies and joints: the URDF's numbers, link frames at the
// joint points (the URDF's origins summed), in the URDF's order.
const std::string kSceneArm = R"(
gravity: [0, 0, -9.81]
bodies:
  base: {type: rigid, at: [0, 0, 0], com: [0, 0, 0.0625], mass: 4, inertia: [0.026, 0.026, 0.0417],
         fixed: true, shapes: [{type: box, center: [0, 0, 0.0625], half_sizes: [0.125, 0.125, 0.0625]}]}
  turret: {type: rigid, at: [0, 0, 0.125], com: [0, 0, 0.1875], mass: 1.5,
           inertia: [0.0039, 0.0039, 0.0039],
           shapes: [{type: box, center: [0, 0, 0.1875], half_sizes: [0.0625, 0.0625, 0.0625]}]}
  upper_arm: {type: rigid, at: [0, 0, 0.25], com: [0.25, 0, 0.25], mass: 1,
              inertia: [0.0026, 0.0221, 0.0221],
              shapes: [{type: box, center: [0.25, 0, 0.25], half_sizes: [0.25, 0.0625, 0.0625]}]}
  forearm: {type: rigid, at: [0.5, 0, 0.25], com: [0.6875, 0, 0.25], mass: 0.5,
            inertia: [0.00083, 0.00628, 0.00628],
            shapes: [{type: sphere, center: [0.5, 0, 0.25], radius: 0.0625},
                     {type: box, center: [0.71875, 0, 0.25], half_sizes: [0.15625, 0.05, 0.05]}]}
  flange: {type: rigid, at: [0.875, 0, 0.25], com: [0.90625, 0, 0.25], mass: 0.25,
           inertia: [0.00065, 0.00041, 0.00041],
           shapes: [{type: box, center: [0.90625, 0, 0.25], half_sizes: [0.03125, 0.0625, 0.0625]}]}
joints:
  waist: {type: revolute, at: [0, 0, 0.125], between: [base, turret], axis: [0, 0, 1], damping: 0.5,
          drive: {type: prescribed, profile: {type: bang_bang, t1: 0.1, value: 0.5}}}
  shoulder: {type: revolute, at: [0, 0, 0.25], between: [turret, upper_arm], axis: [0, 1, 0],
             damping: 0.5, drive: {type: prescribed, profile: {type: bang_bang, t1: 0.1, value: 0.3}}}
  elbow: {type: revolute, at: [0.5, 0, 0.25], between: [upper_arm, forearm], axis: [0, 1, 0],
          damping: 0.2, stiffness: 50,
          drive: {type: series_elastic, profile: {type: sine, value: 0.2, frequency: 5}}}
  wrist: {type: revolute, at: [0.875, 0, 0.25], between: [forearm, flange], axis: [1, 0, 0],
          damping: 0.05, drive: {type: force, profile: {type: ramp, t1: 0.05, value: 0.01}}}
)";

// Every node frame after each of n steps.
std::vector<SE3> Frames(const Scene& s, int n) {
  Data d = MakeData(s.model);
  Integrator integ;
  std::string message;
  EXPECT_TRUE(InitializeDynamics(s.model, d, integ, DynamicOptions{}, &message)) << message;
  std::vector<SE3> out;
  for (int i = 0; i < n; ++i) {
    const StepResult r = Step(s.model, d, integ, 1e-3);
    EXPECT_TRUE(r.ok) << r.message;
    out.insert(out.end(), d.H.begin(), d.H.end());
  }
  return out;
}

TEST(Urdf, TheArmEqualsTheSameArmWrittenAsASceneBitForBit) {
  const Scene urdf = ParseScene(UrdfScene(kArmUrdf), "urdf.yaml");
  const Scene scene = ParseScene(kSceneArm + kTail, "scene.yaml");
  ASSERT_EQ(urdf.model.bodies.size(), 5u);
  ASSERT_EQ(urdf.model.joints.size(), 4u);
  EXPECT_EQ(urdf.model.bodies[2].name, "arm/upper_arm");
  EXPECT_EQ(urdf.model.joints[1].name, "arm/shoulder");
  ASSERT_EQ(urdf.model.contact_shapes.size(), scene.model.contact_shapes.size());
  EXPECT_EQ(urdf.model.contact_shapes.size(), 6u);
  for (std::size_t i = 0; i < urdf.model.contact_shapes.size(); ++i) {
    const ContactShape &a = urdf.model.contact_shapes[i], &b = scene.model.contact_shapes[i];
    EXPECT_EQ(a.type, b.type) << i;
    EXPECT_EQ(a.from, b.from) << i;
    EXPECT_EQ(a.to, b.to) << i;
    EXPECT_EQ(a.radius, b.radius) << i;
  }
  for (std::size_t b = 0; b < urdf.model.bodies.size(); ++b) {
    EXPECT_EQ(urdf.model.bodies[b].mass, scene.model.bodies[b].mass) << b;
    EXPECT_EQ(urdf.model.bodies[b].com, scene.model.bodies[b].com) << b;
    EXPECT_EQ(urdf.model.bodies[b].inertia, scene.model.bodies[b].inertia) << b;
  }
  const std::vector<SE3> a = Frames(urdf, 60), b = Frames(scene, 60);
  ASSERT_EQ(a.size(), b.size());
  int differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differ += !(a[i].R == b[i].R && a[i].x == b[i].x);
  EXPECT_EQ(differ, 0);
  // The drives moved the arm: the flange turned with the waist and the wrist.
  const SE3& flange = a[a.size() - 1];
  EXPECT_GT((flange.R - Mat3::Identity()).norm(), 0.1);
}

// A URDF file in the test's temporary directory.
class UrdfFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("screwfem_urdf_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  // The scene error of a robot reading `path`; the `urdf:` value is at line 4, column 11.
  static std::string Error(const std::string& path, const std::string& extra = "") {
    return test::SceneError("bodies:\nrobots:\n  r:\n    urdf: " + path + "\n" + extra,
                            "scene.yaml");
  }
  std::filesystem::path dir_;
};

const std::string kLink = R"(<inertial><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>)";

std::string Robot(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\">" + kLink + "</link>\n" +
         body + "</robot>\n";
}

TEST_F(UrdfFiles, ErrorsNameTheElementAndTheInclude) {
  const std::string at = "scene.yaml:4:11: robots.r.urdf: ";
  // Missing inertial: the link's element, line 4 column 3 of the URDF.
  std::string p =
      Write("no_inertial.urdf", Robot("  <link name=\"b\"/>\n"
                                      "  <joint name=\"j\" type=\"fixed\">"
                                      "<parent link=\"a\"/><child link=\"b\"/></joint>\n"));
  test::ExpectErrorAt(Error(p), at + p + ":5:3",
                      "link 'b': no <inertial> (every link is a rigid body and needs its mass and "
                      "inertia)");
  // Unknown parent link: urdfdom's message names the joint and the link.
  p = Write("parent.urdf",
            Robot("  <link name=\"b\">" + kLink +
                  "</link>\n  <joint name=\"j\" type=\"revolute\"><parent link=\"c\"/>"
                  "<child link=\"b\"/><axis xyz=\"0 0 1\"/>"
                  "<limit effort=\"1\" velocity=\"1\"/></joint>\n"));
  const std::string parent = Error(p);
  test::ExpectErrorAt(parent, at + p, "not a valid URDF");
  EXPECT_NE(parent.find("parent link [c] of joint [j] not found"), std::string::npos) << parent;
  // Unsupported joint types.
  p = Write("planar.urdf",
            Robot("  <link name=\"b\">" + kLink +
                  "</link>\n  <joint name=\"slide\" type=\"planar\"><parent link=\"a\"/>"
                  "<child link=\"b\"/><axis xyz=\"0 0 1\"/></joint>\n"));
  test::ExpectErrorAt(Error(p), at + p + ":7:3",
                      "joint 'slide': type 'planar' is not supported (revolute, continuous, "
                      "prismatic, fixed)");
  p = Write("floating.urdf", Robot("  <link name=\"b\">" + kLink +
                                   "</link>\n  <joint name=\"float\" type=\"floating\"><parent "
                                   "link=\"a\"/><child link=\"b\"/></joint>\n"));
  test::ExpectErrorAt(Error(p), at + p + ":7:3", "joint 'float': type 'floating' is not supported");
  p = Write("mimic.urdf",
            Robot("  <link name=\"b\">" + kLink + "</link>\n  <link name=\"c\">" + kLink +
                  "</link>\n  <joint name=\"j1\" type=\"continuous\"><parent link=\"a\"/><child "
                  "link=\"b\"/></joint>\n  <joint name=\"j2\" type=\"continuous\"><parent "
                  "link=\"b\"/><child link=\"c\"/><mimic joint=\"j1\"/></joint>\n"));
  test::ExpectErrorAt(Error(p), at + p + ":10:3", "joint 'j2': <mimic> is not supported");
  // A cylinder collision shape of zero length: the <collision> element.
  p = Write("cylinder.urdf", "<robot name=\"r\">\n  <link name=\"a\">" + kLink +
                                 "\n    <collision name=\"can\"><geometry><cylinder radius=\"0.1\" "
                                 "length=\"0\"/></geometry></collision>\n  </link>\n</robot>\n");
  test::ExpectErrorAt(Error(p), at + p + ":4:5",
                      "link 'a': <collision> 'can': the cylinder's radius and length must be "
                      "positive");
  p = Write("mesh.urdf", "<robot name=\"r\">\n  <link name=\"a\">" + kLink +
                             "\n    <collision><geometry><mesh filename=\"a.stl\"/></geometry>"
                             "</collision>\n  </link>\n</robot>\n");
  test::ExpectErrorAt(Error(p), at + p + ":4:5", "link 'a': <collision> 0: mesh shapes");
  // Bad inertia and mass.
  p = Write("inertia.urdf",
            "<robot name=\"r\">\n  <link name=\"a\"><inertial><mass value=\"1\"/><inertia "
            "ixx=\"0.01\" ixy=\"0.02\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>"
            "</link>\n</robot>\n");
  test::ExpectErrorAt(Error(p), at + p + ":2:3",
                      "link 'a': <inertial> <inertia> must be positive definite, got ixx=0.01 "
                      "ixy=0.02");
  p = Write("mass.urdf",
            "<robot name=\"r\">\n  <link name=\"a\"><inertial><mass value=\"0\"/><inertia "
            "ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>"
            "</link>\n</robot>\n");
  test::ExpectErrorAt(Error(p), at + p + ":2:3",
                      "link 'a': <inertial> <mass value> must be positive, got 0");
  // Not XML, not a URDF, no file.
  p = Write("broken.urdf", "<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n");
  test::ExpectErrorAt(Error(p), at + p + ":3:1", "not valid XML: Error reading end tag.");
  p = Write("html.urdf", "<html/>\n");
  test::ExpectErrorAt(Error(p), at + p, "no <robot> element (not a URDF file)");
  const std::string missing = (dir_ / "missing.urdf").string();
  test::ExpectErrorAt(Error(missing), at + missing, "cannot open the URDF file");
  // A joint option for a joint the file does not have.
  p = Write("ok.urdf", Robot(""));
  test::ExpectErrorAt(Error(p, "    joints: {elbo: {damping: 1}}\n"),
                      "scene.yaml:5:14: robots.r.joints.elbo", "the URDF has no joint 'elbo'");
}

TEST_F(UrdfFiles, RotatedBaseAndInertialGiveTheClosedFormWorldValues) {
  // The link's inertial frame is turned by 90 degrees about z and the base by 90 degrees about
  // x: the principal moments (1, 2, 3) e-2 about the inertial axes end on world axes.
  const std::string p =
      Write("turned.urdf",
            "<robot name=\"r\">\n  <link name=\"a\"><inertial><origin xyz=\"0.1 0 0\" rpy=\"0 0 "
            "1.5707963267948966\"/><mass value=\"2\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" "
            "iyy=\"0.02\" iyz=\"0\" izz=\"0.03\"/></inertial><collision><origin xyz=\"0 0.2 0\" "
            "rpy=\"0 0 1.5707963267948966\"/><geometry><box size=\"0.1 0.2 0.3\"/></geometry>"
            "</collision></link>\n"
            "  <link name=\"b\">" +
                kLink +
                "</link>\n  <joint name=\"j\" type=\"prismatic\"><origin xyz=\"0 0 0.5\"/><parent "
                "link=\"a\"/><child link=\"b\"/><axis xyz=\"0 1 0\"/><limit effort=\"1\" "
                "velocity=\"1\"/></joint>\n</robot>\n");
  SceneSpec spec;
  UrdfImport import;
  import.name = "r";
  import.base_position = Vec3(1, 2, 3);
  import.base_rotation = RotationFromAxisAngle(Vec3::UnitX(), M_PI / 2);
  import.fixed_base = false;
  const UrdfAdded added = AppendUrdf(p, import, &spec);
  EXPECT_EQ(added.bodies, 2);
  EXPECT_EQ(added.joints, 1);
  const BodySpec& a = spec.bodies[0];
  EXPECT_TRUE(a.free);
  EXPECT_FALSE(a.fixed);
  EXPECT_EQ(a.origin, Vec3(1, 2, 3));
  // Inertial axes: x_i = world z? Rx(90) Rz(90): x_i -> Rx(y) = z, y_i -> Rx(-x) = -x,
  // z_i -> Rx(z) = -y. So Jxx(world) = J_yy(inertial), Jyy = J_zz, Jzz = J_xx.
  const Mat3 expected = Vec3(0.02, 0.03, 0.01).asDiagonal();
  EXPECT_LT((a.inertia - expected).norm(), 1e-17);
  // The centre of mass 0.1 along the link's x = world x.
  EXPECT_LT((a.com - Vec3(1.1, 2, 3)).norm(), 1e-15);
  // The box (0.1, 0.2, 0.3) turned as the inertial: its half sizes along its own edges, which
  // lie along the world axes with extents (0.1, 0.15, 0.05), at the link's y (world z) 0.2.
  ASSERT_EQ(a.shapes.size(), 1u);
  EXPECT_LT((a.shapes[0].to - Vec3(0.05, 0.1, 0.15)).norm(), 1e-15);
  EXPECT_LT((a.shapes[0].rotation.cwiseAbs() * a.shapes[0].to - Vec3(0.1, 0.15, 0.05)).norm(),
            1e-15);
  EXPECT_LT((a.shapes[0].from - Vec3(0, 0, 0.2)).norm(), 1e-15);  // relative to the origin
  // The joint at the link's z 0.5 (world -y), its axis the link's y (world z).
  const JointSpec& j = spec.joints[0].joint;
  EXPECT_EQ(j.name, "r/j");
  EXPECT_EQ(j.type, JointType::kPrismatic);
  EXPECT_LT((j.point - Vec3(1, 1.5, 3)).norm(), 1e-15);
  EXPECT_LT((j.axis - Vec3(0, 0, 1)).norm(), 1e-15);
  EXPECT_EQ(spec.joints[0].body_a, 0);
  EXPECT_EQ(spec.joints[0].body_b, 1);
  // The same robot a second time is an error naming the duplicate body; the spec is unchanged.
  try {
    AppendUrdf(p, import, &spec);
    ADD_FAILURE() << "a duplicate robot was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("link 'a': the scene already has a body 'r/a'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(spec.bodies.size(), 2u);
  EXPECT_EQ(spec.joints.size(), 1u);
}

TEST_F(UrdfFiles, BaseOrientationFormsAgreeAndBadOnesAreErrors) {
  const std::string p = Write("one.urdf", Robot(""));
  const auto base = [&](const std::string& orientation) {
    const Scene s =
        ParseScene("robots:\n  r:\n    urdf: " + p +
                       "\n    base: {at: [0, 0, 1], orientation: " + orientation + "}\n",
                   "scene.yaml");
    return s.model.bodies[0].inertia;
  };
  const Mat3 q = base("{quaternion: [0.7071067811865476, 0, 0, 0.7071067811865476]}");
  const Mat3 aa = base("{axis: [0, 0, 1], angle: pi/2}");
  const Mat3 rpy = base("{rpy: [0, 0, pi/2]}");
  EXPECT_LT((q - aa).norm(), 1e-16);
  EXPECT_LT((rpy - aa).norm(), 1e-16);
  EXPECT_EQ(test::SceneError("robots:\n  r:\n    urdf: " + p +
                                 "\n    base: {orientation: {quaternion: [1, 0, 0, 1]}}\n",
                             "scene.yaml"),
            "scene.yaml:4:38: robots.r.base.orientation.quaternion: expected a unit quaternion "
            "[w, x, y, z], got norm 1.41421356");
  EXPECT_EQ(test::SceneError("robots:\n  r:\n    urdf: " + p +
                                 "\n    base: {orientation: {rpy: [0, 0, 1], angle: 1}}\n",
                             "scene.yaml"),
            "scene.yaml:4:25: robots.r.base.orientation: give one of 'quaternion: [w, x, y, z]', "
            "'axis' with 'angle', or 'rpy: [r, p, y]'");
}

// Rz(a) and Ry(b).
Mat3 Rz(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }
Mat3 Ry(double b) { return Eigen::AngleAxisd(b, Vec3::UnitY()).toRotationMatrix(); }
Mat3 Rx(double c) { return Eigen::AngleAxisd(c, Vec3::UnitX()).toRotationMatrix(); }

TEST(Urdf, TheExampleRunsAndItsFlangeFollowsTheForwardKinematics) {
  const Scene s = LoadScene(kExample);
  ASSERT_EQ(s.model.bodies.size(), 5u);  // the arm's links (the fingers are rods)
  ASSERT_EQ(s.model.rods.size(), 2u);
  Data d = MakeData(s.model);
  Integrator integ;
  std::string message;
  ASSERT_TRUE(InitializeDynamics(s.model, d, integ, DynamicOptions{}, &message)) << message;
  const auto frame = [&](int body) {
    return d.H[static_cast<std::size_t>(s.model.bodies[static_cast<std::size_t>(body)].node)];
  };
  double worst_rotation = 0.0, worst_position = 0.0, t = 0.0;
  const double h = 2e-3;
  Vec3 tip0 = Vec3::Zero();
  for (int n = 0; n < 750; ++n) {
    const StepResult r = Step(s.model, d, integ, h);
    ASSERT_TRUE(r.ok) << r.message;
    t += h;
    // The waist and shoulder angles from their profiles; the elbow's (series-elastic, it sags)
    // and the wrist's (free) from the frames.
    const double a = s.model.joints[0].drive_profile.Eval(t).value;
    const double b = s.model.joints[1].drive_profile.Eval(t).value;
    const Mat3 upper = frame(2).R, fore = frame(3).R, flange = frame(4).R;
    const Mat3 elbow = upper.transpose() * fore, wrist = fore.transpose() * flange;
    const double c = std::atan2(elbow(0, 2), elbow(0, 0));
    const double w = std::atan2(wrist(2, 1), wrist(1, 1));
    const Mat3 R = Rz(a) * Ry(b) * Ry(c) * Rx(w);
    worst_rotation = std::max(worst_rotation, (flange - R).norm());
    worst_rotation = std::max(worst_rotation, (frame(1).R - Rz(a)).norm());
    // The flange's origin: waist at z 0.125, shoulder 0.125 above, 0.5 and 0.375 along x.
    const Vec3 p = Vec3(0, 0, 0.25) + Rz(a) * Ry(b) * (Vec3(0.5, 0, 0) + Ry(c) * Vec3(0.375, 0, 0));
    worst_position = std::max(worst_position, (frame(4).x - p).norm());
    if (n == 0) tip0 = d.H[static_cast<std::size_t>(s.model.rods[0].nodes.back())].x;
  }
  EXPECT_LT(worst_rotation, 1e-12);
  EXPECT_LT(worst_position, 1e-12);
  // After 1.5 s the waist has turned by pi/4 and the fingers have closed: the left finger's tip
  // moved towards the right one's.
  const Vec3 left = d.H[static_cast<std::size_t>(s.model.rods[0].nodes.back())].x;
  const Vec3 right = d.H[static_cast<std::size_t>(s.model.rods[1].nodes.back())].x;
  EXPECT_NEAR(std::atan2(frame(1).R(1, 0), frame(1).R(0, 0)), M_PI / 4, 1e-9);
  EXPECT_LT((left - right).norm(), 0.09375 - 0.01) << (left - tip0).transpose();
}

}  // namespace
}  // namespace screwfem::urdf_test
