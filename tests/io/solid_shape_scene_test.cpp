// Cylinders, turned boxes and moving surfaces from a scene file (docs/scene-format.md,
// "contact"): the example examples/contact/shapes.yaml compiles to the shapes, obstacles and
// pairs it describes, a short run carries the crate with the belt, the VTK frames draw the new
// shapes at their size and pose, and bad input is reported at file:line:col.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "run_test_util.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::solid_shape_scene_test {
namespace {

const std::string kShapes = std::string(SCREWFEM_SOURCE_DIR) + "/examples/contact/shapes.yaml";

TEST(SolidShapeScene, ExampleCompilesCylindersTurnedBoxesAndTheBelt) {
  const Scene s = LoadScene(kShapes);
  const Model& m = s.model;
  ASSERT_EQ(m.contact_shapes.size(), 2u);
  const ContactShape& crate = m.contact_shapes[0];
  EXPECT_EQ(crate.type, ContactShapeType::kBox);
  const Mat3 turn = Eigen::AngleAxisd(0.3, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_LT((crate.rotation - turn).norm(), 1e-15);
  const ContactShape& can = m.contact_shapes[1];
  EXPECT_EQ(can.type, ContactShapeType::kCylinder);
  EXPECT_EQ(can.radius, 0.04);
  EXPECT_LT((can.to - can.from - Vec3(0, 0.12, 0)).norm(), 1e-15);
  ASSERT_EQ(m.obstacles.size(), 3u);
  EXPECT_EQ(m.obstacles[0].velocity, Vec3(0.5, 0, 0));
  EXPECT_TRUE(m.obstacles[0].moving());
  EXPECT_EQ(m.obstacles[1].type, ObstacleType::kBox);
  EXPECT_LT(
      (m.obstacles[1].rotation - Eigen::AngleAxisd(0.2, Vec3::UnitZ()).toRotationMatrix()).norm(),
      1e-15);
  EXPECT_EQ(m.obstacles[2].type, ObstacleType::kCylinder);
  // The belt: 8 crate corners, 6 can rim points, 13 rod nodes; the wall: 8 + 12 crate corners
  // and edges, 12 rod elements; the post: 20 crate, 12 rod (the can excluded from both).
  int count[3] = {0, 0, 0};
  for (const ContactPair& p : m.contact_pairs) ++count[p.obstacle];
  EXPECT_EQ(count[0], 8 + 6 + 13);  // the root is clamped by a joint: its node moves
  EXPECT_EQ(count[1], 20 + 12);
  EXPECT_EQ(count[2], 20 + 12);
}

TEST(SolidShapeScene, TheBeltCarriesTheCrate) {
  test::ScopedDir dir("solid_shape_scene");
  Scene s =
      LoadScene(kShapes, {"analysis.end_time=0.5", "outputs.interval=0.1", "outputs.vtk=false"});
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  // The crate, from rest, catches the belt at 0.1 + 0.5 / (mu g) = 0.27 s and then moves with
  // it: at 0.5 s its four bottom corners stick and carry its weight with no net friction.
  const test::Table c = test::ReadCsv(dir.path() + "/contacts.csv");
  ASSERT_TRUE(c.well_formed) << c.problem;
  const double t_end = c.rows.back()[0];
  EXPECT_NEAR(t_end, 0.5, 1e-12);
  double fn = 0.0;
  Vec3 ft = Vec3::Zero();
  int corners = 0;
  for (const std::vector<double>& row : c.rows) {
    if (row[0] != t_end || row[2] != 0.0 || row[3] != 0.0 || row[4] != 0.0) continue;
    ++corners;
    fn += row[11];
    ft += Vec3(row[12], row[13], row[14]);
    EXPECT_EQ(row[16], 0.0);  // sticking
  }
  EXPECT_EQ(corners, 4);
  EXPECT_NEAR(fn, 9.81, 1e-6);
  EXPECT_LT(ft.norm(), 1e-6);
}

std::string Error(const std::string& text) {
  try {
    ParseScene(text, "bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

void ExpectError(const std::string& text, const std::string& location, const std::string& what) {
  const std::string message = Error(text);
  EXPECT_EQ(message.rfind(location + ": ", 0), 0u) << "message: " << message;
  EXPECT_NE(message.find(what), std::string::npos) << "message: " << message;
}

const std::string kHead = R"(gravity: [0, 0, -9.81]
bodies:
  ball: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
         shapes: [{type: sphere, center: [0, 0, 1], radius: 0.1}]}
)";

TEST(SolidShapeScene, BadInputIsReportedAtFileLineColumnNamingTheField) {
  ExpectError(R"(bodies:
  can: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
        shapes: [{type: cylinder, from: [0, 0, 1], to: [0, 0, 1], radius: 0.1}]}
)",
              "bad.yaml:3:56: bodies.can.shapes[0].to", "expected 'to' apart from 'from'");
  ExpectError(R"(bodies:
  can: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
        shapes: [{type: cylinder, from: [0, 0, 1], to: [0, 0, 2], radius: 0.1,
                  orientation: {axis: [0, 0, 1], angle: 1}}]}
)",
              "bad.yaml:4:19: bodies.can.shapes[0].orientation", "'orientation' is not used by");
  ExpectError(R"(bodies:
  crate: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
          shapes: [{type: box, center: [0, 0, 1], half_sizes: [1, 1, 1],
                    orientation: {quaternion: [1, 1, 0, 0]}}]}
)",
              "bad.yaml:4:47: bodies.crate.shapes[0].orientation.quaternion",
              "expected a unit quaternion");
  ExpectError(kHead +
                  "contact:\n  obstacles:\n    belt: {type: plane, point: [0, 0, 0], normal: [0, "
                  "0, 1], velocity: [0, 0, 1]}\n",
              "bad.yaml:7:72: contact.obstacles.belt.velocity",
              "expected a velocity along the plane");
  ExpectError(kHead +
                  "contact:\n  obstacles:\n    belt: {type: plane, point: [0, 0, 0], normal: [0, "
                  "0, 1], motion: 1}\n",
              "bad.yaml:7:70: contact.obstacles.belt.motion",
              "'motion' scales 'velocity' or 'spin'");
  ExpectError(kHead +
                  "contact:\n  obstacles:\n    post: {type: sphere, center: [0, 0, 0], radius: "
                  "1, spin: 2}\n",
              "bad.yaml:7:56: contact.obstacles.post.spin", "'spin' is not used by");
  ExpectError(kHead +
                  "contact:\n  obstacles:\n    wall: {type: box, center: [0, 0, 0], half_sizes: "
                  "[1, -1, 1]}\n",
              "bad.yaml:7:54: contact.obstacles.wall.half_sizes", "expected positive half sizes");
  ExpectError(
      kHead + "contact:\n  obstacles:\n    wall: {type: box, center: [0, 0, 0], radius: 1}\n",
      "bad.yaml:7:42: contact.obstacles.wall.radius", "'radius' is not used by boxes");
  ExpectError(kHead +
                  "contact:\n  obstacles:\n    post: {type: cylinder, from: [0, 0, 0], to: [0, "
                  "0, 1]}\n",
              "bad.yaml:7:11: contact.obstacles.post", "radius");
  // A cylinder against a box: the build's error names both (not a silent miss).
  const std::string crate_and_can = R"(bodies:
  crate: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
          shapes: [{type: box, center: [0, 0, 1], half_sizes: [0.1, 0.1, 0.1]}]}
  can: {type: rigid, at: [1, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
        shapes: [{type: cylinder, from: [1, 0, 1], to: [1, 0, 2], radius: 0.1}]}
contact: {friction: 0.3}
)";
  const std::string message = Error(crate_and_can);
  EXPECT_NE(message.find("contact between the cylinder of body 'can' and the box of body 'crate' "
                         "is not supported"),
            std::string::npos)
      << message;
  EXPECT_EQ(Error(crate_and_can.substr(0, crate_and_can.size() - 25) +
                  "contact: {friction: 0.3, exclude: [[can, crate]]}\n"),
            "(no error)");
}

}  // namespace
}  // namespace screwfem::solid_shape_scene_test
