// Contact from a scene file (docs/scene-format.md, "contact"): the example
// examples/contact/slide.yaml compiles to the shapes, obstacle and law it describes, a run
// writes contacts.csv with the states the kernel computes (the box stops after the Coulomb
// distance, the rod rests at its radius), and bad input is reported at file:line:col.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "run_test_util.h"
#include "screwfem/elements/contact.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"

namespace screwfem::contact_scene_test {
namespace {

const std::string kSlide = std::string(SCREWFEM_SOURCE_DIR) + "/examples/contact/slide.yaml";

TEST(ContactScene, SlideExampleCompilesShapesObstacleLawAndPairs) {
  const Scene s = LoadScene(kSlide);
  const Model& m = s.model;
  ASSERT_EQ(m.obstacles.size(), 1u);
  EXPECT_EQ(m.obstacles[0].name, "ground");
  ASSERT_EQ(m.contact_shapes.size(), 1u);
  EXPECT_EQ(m.contact_shapes[0].type, ContactShapeType::kBox);
  EXPECT_EQ(m.contact_shapes[0].from, Vec3::Zero());  // the centre, in the body frame
  ASSERT_EQ(m.contact_rods.size(), 1u);
  EXPECT_EQ(m.contact_rods[0].radius, 0.01);  // the circle section's radius
  // 8 box vertices + 11 rod node spheres against the plane.
  EXPECT_EQ(m.contact_pairs.size(), 8u + 11u);
  EXPECT_EQ(m.contact.friction, 0.3);
  EXPECT_EQ(m.contact.stiffness, 1e5);
}

TEST(ContactScene, RunWritesContactsTableTheBoxStopsAndTheRodRestsAtItsRadius) {
  test::ScopedDir dir("contact_scene");
  const Scene s = LoadScene(kSlide, {"analysis.end_time=0.8", "outputs.interval=0.1"});
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  const test::Table c = test::ReadCsv(dir.path() + "/contacts.csv");
  ASSERT_TRUE(c.well_formed) << c.problem;
  EXPECT_EQ(c.columns, (std::vector<std::string>{"t", "pair", "rod", "owner", "obstacle", "px",
                                                 "py", "pz", "nx", "ny", "nz", "fn", "ftx", "fty",
                                                 "ftz", "gap", "slip", "deflection", "share"}));
  // At the last time (0.8 s, after the stop at 0.68 s): the box's 4 bottom vertices carry its
  // weight with no friction, and every rod node touches the ground and the rod's normal forces
  // sum to its weight (rho A L g).
  const double t_end = c.rows.back()[0];
  EXPECT_NEAR(t_end, 0.8, 1e-12);
  double box_fn = 0.0, rod_fn = 0.0, box_x = 0.0;
  Vec3 box_ft = Vec3::Zero();
  int box_rows = 0, rod_rows = 0;
  for (const std::vector<double>& row : c.rows) {
    if (row[0] != t_end) continue;
    EXPECT_EQ(row[10], 1.0);    // the plane's normal
    EXPECT_GT(row[15], -1e-4);  // no penetration beyond the onset
    if (row[2] == 0.0) {
      box_fn += row[11];
      box_ft += Vec3(row[12], row[13], 0.0);
      box_x += 0.25 * row[5];
      ++box_rows;
    } else {
      rod_fn += row[11];
      ++rod_rows;
    }
  }
  EXPECT_EQ(box_rows, 4);
  EXPECT_EQ(rod_rows, 11);
  EXPECT_NEAR(box_fn, 9.81, 1e-3);
  EXPECT_LT(box_ft.norm(), 1e-3);  // at rest: the corners' friction forces balance
  const double rod_weight = 1100 * M_PI * 1e-4 * 1.0 * 9.81;
  EXPECT_NEAR(rod_fn, rod_weight, 0.02 * rod_weight);  // still ringing a little after the drop
  // The box stopped after v^2 / (2 mu g) = 0.6796 m (the contact points' mean x).
  EXPECT_NEAR(box_x, 2.0 * 2.0 / (2 * 0.3 * 9.81), 0.01 * 0.6796);
  // The frames draw the contact forces.
  const std::string frame = test::ReadFile(dir.path() + "/vtk/frame_00000.vtp");
  EXPECT_NE(frame.find("contact_force"), std::string::npos);
}

// A valid scene; each case edits it.
const std::string kHead = R"(gravity: [0, 0, -9.81]
bodies:
  ball: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
         shapes: [{type: sphere, center: [0, 0, 1], radius: 0.1}]}
)";

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

// A failed step names the contact settings: the smooth law at h = 1e-2 s on the slide example
// (a rod dropped onto the plane) without the contact line search fails, and the message counts
// the active contacts, names the keys to change and says that eps_v is below h mu g; the stick
// law completes the same run (and, with the line search, the default, so does the smooth law).
TEST(ContactScene, AFailedStepNamesTheContactSettings) {
  test::ScopedDir dir("contact_failure");
  const Scene smooth = LoadScene(kSlide, {"contact.friction_law=smooth", "analysis.step=1e-2",
                                          "analysis.line_search=false", "outputs.vtk=false"});
  const RunResult r = RunScene(smooth, dir.path());
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.message.find("contacts active at the step's start (contact.stiffness"),
            std::string::npos)
      << r.message;
  EXPECT_NE(r.message.find("contact.friction_law smooth"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("contact.slip_velocity 0.001 m/s is below h mu g = 0.02943 m/s"),
            std::string::npos)
      << r.message;
  test::ScopedDir dir2("contact_failure_stick");
  const Scene stick = LoadScene(kSlide, {"analysis.step=1e-2", "outputs.vtk=false"});
  const RunResult r2 = RunScene(stick, dir2.path());
  EXPECT_TRUE(r2.ok) << r2.message;
}

TEST(ContactScene, BadInputIsReportedAtFileLineColumnNamingTheField) {
  const std::string ground = "    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}\n";
  EXPECT_EQ(Error(kHead + "contact:\n  friction: 0.3\n  obstacles:\n" + ground), "(no error)");
  ExpectError(kHead + "contact:\n  friction: -0.3\n  obstacles:\n" + ground,
              "bad.yaml:6:13: contact.friction", "");
  ExpectError(R"(bodies:
  ball: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
         shapes: [{type: sphere, center: [0, 0, 1], radius: 0}]}
)",
              "bad.yaml:3:61: bodies.ball.shapes[0].radius", "");
  ExpectError(R"(bodies:
  ball: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
         shapes: [{type: box, center: [0, 0, 1], half_sizes: [1, 0, 1]}]}
)",
              "bad.yaml:3:62: bodies.ball.shapes[0].half_sizes", "positive");
  ExpectError(kHead +
                  "contact:\n  obstacles:\n    post: {type: capsule, from: [0, 0, 0], "
                  "to: [0, 0, 1], radius: -1}\n",
              "bad.yaml:7:67: contact.obstacles.post.radius", "");
  ExpectError(kHead + "contact:\n  obstacles:\n" + ground + "  exclude: [[bal, ground]]\n",
              "bad.yaml:8:14: contact.exclude[0][0]", "undefined body 'bal'");
  ExpectError(kHead + "contact:\n  obstacles:\n" + ground + "  exclude: [[ball, floor]]\n",
              "bad.yaml:8:20: contact.exclude[0][1]", "undefined obstacle 'floor'");
  ExpectError(kHead + "contact:\n  obstacles:\n    ground: {type: wall}\n",
              "bad.yaml:7:20: contact.obstacles.ground.type", "plane");
  // The stick law's keys.
  ExpectError(kHead + "contact:\n  friction_law: sticky\n  obstacles:\n" + ground,
              "bad.yaml:6:17: contact.friction_law", "stick");
  ExpectError(kHead + "contact:\n  friction: 0.5\n  static_friction: 0.4\n  obstacles:\n" + ground,
              "bad.yaml:7:20: contact.static_friction", "mu_s >= mu_k");
  ExpectError(kHead + "contact:\n  tangential_stiffness: 0\n  obstacles:\n" + ground,
              "bad.yaml:6:25: contact.tangential_stiffness", "");
}

}  // namespace
}  // namespace screwfem::contact_scene_test
