// The reader -> spec -> compiler split (scene_spec.h): ReadSceneSpec fills a plain spec and the
// side table of sources; CompileScene maps every error, including ModelBuilder's (through
// InputError::entity(), not the message text), to the file:line:col of the entity that made it.
#include <gtest/gtest.h>

#include <string>

#include "screwfem/io/scene_spec.h"
#include "screwfem/model/errors.h"

namespace screwfem::scene_spec_test {
namespace {

// Line numbers below count from 1 at "points:".
const std::string kScene = R"(points: {A: [0, 0, 0], B: [1, 0, 0], C: [2, 0, 0]}
sections: {s: {stiffness: [1, 1, 1, 1, 1, 1], inertia: [1, 1, 1, 1, 1, 1]}}
bodies:
  arm: {type: rigid, between: [A, B], mass: 1, inertia: [1, 1, 1]}
  rod: {type: soft, path: [B, C, [2, 1, 0]], section: s, elements: 2}
joints:
  pin: {type: revolute, at: A, between: [ground, arm], axis: [0, 0, 1]}
  weld: {type: fixed, at: B, between: [arm, rod]}
loads:
  push: {body: arm, at: B, force: [0, 1, 0]}
  tip: {body: rod, s: 2, force: [0, 0, 1]}
)";

std::string CompileError(const SceneSpec& spec, const SceneSources& sources) {
  try {
    CompileScene(spec, sources);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

class SceneSpecTest : public ::testing::Test {
 protected:
  void SetUp() override { spec_ = ReadSceneSpec(kScene, "spec.yaml", {}, &sources_); }
  SceneSpec spec_;
  SceneSources sources_;
};

TEST_F(SceneSpecTest, ReaderFillsThePlainSpecAndTheSourcesOfItsEntities) {
  ASSERT_EQ(spec_.bodies.size(), 2u);
  EXPECT_TRUE(spec_.bodies[0].rigid);
  EXPECT_EQ(spec_.bodies[0].com, Vec3(0.5, 0, 0));
  EXPECT_FALSE(spec_.bodies[1].rigid);
  EXPECT_EQ(spec_.bodies[1].path.size(), 3u);
  EXPECT_EQ(spec_.joints[1].body_a, 0);
  EXPECT_EQ(spec_.joints[1].body_b, 1);
  EXPECT_EQ(spec_.loads[1].where, LoadSpec::Where::kArcLength);
  EXPECT_EQ(sources_.bodies[1].self.location.line, 5);
  EXPECT_EQ(sources_.bodies[1].self.location.column, 3);
  EXPECT_EQ(sources_.bodies[1].self.field, "bodies.rod");
  const FieldSource* corner = sources_.bodies[1].Part("path[1]");
  ASSERT_NE(corner, nullptr);
  EXPECT_EQ(corner->field, "bodies.rod.path[1]");
  EXPECT_EQ(corner->location.line, 5);
  EXPECT_EQ(sources_.joints[1].Part("node_b")->field, "joints.weld.between[1]");
  EXPECT_EQ(sources_.loads[1].Part("s")->location.line, 11);
  const Scene scene = CompileScene(spec_, sources_);
  // 4 elements, and the load at s = 2 inside one of them: a node there (defaults.conform_mesh).
  EXPECT_EQ(scene.model.rods[0].nodes.size(), 6u);
  EXPECT_EQ(scene.model.conformed_nodes, 1);
  EXPECT_EQ(scene.model.joints.size(), 2u);
}

TEST_F(SceneSpecTest, BuildErrorOfABodyPointsAtTheBody) {
  spec_.bodies[0].mass = -1.0;  // the reader would not let this through; ModelBuilder::Build
  const std::string e = CompileError(spec_, sources_);
  EXPECT_EQ(e.rfind("spec.yaml:4:3: bodies.arm: body 'arm': mass must be positive", 0), 0u) << e;
}

TEST_F(SceneSpecTest, BuildErrorOfAJointPointsAtTheJoint) {
  spec_.joints[0].joint.damping(0) = -1.0;
  const std::string e = CompileError(spec_, sources_);
  EXPECT_EQ(e.rfind("spec.yaml:7:3: joints.pin: joint 'pin': stiffness and damping", 0), 0u) << e;
}

TEST_F(SceneSpecTest, BuildErrorOfADrivePointsAtItsJoint) {
  spec_.joints[0].joint.drive = DriveKind::kForce;
  spec_.joints[0].joint.drive_coordinate = 3;
  const std::string e = CompileError(spec_, sources_);
  EXPECT_EQ(e.rfind("spec.yaml:7:3: joints.pin: joint 'pin': drive coordinate out of range", 0), 0u)
      << e;
}

TEST_F(SceneSpecTest, BuildErrorOfALoadPointsAtTheLoad) {
  spec_.loads[1].force = Vec3(0, 0, std::nan(""));
  std::string e = CompileError(spec_, sources_);
  EXPECT_EQ(e.rfind("spec.yaml:11:3: loads.tip: load on rod 'rod': values must be finite", 0), 0u)
      << e;
  spec_.loads[1].force = Vec3::Zero();
  spec_.loads[0].moment = Vec3(std::nan(""), 0, 0);
  e = CompileError(spec_, sources_);
  EXPECT_EQ(e.rfind("spec.yaml:10:3: loads.push: point load on node 'arm'", 0), 0u) << e;
}

TEST_F(SceneSpecTest, ErrorOfAJointSpecPointsAtTheJoint) {
  spec_.joints[0].joint.axis = Vec3(0, 0, 2);  // not a unit vector (AddJoint)
  const std::string e = CompileError(spec_, sources_);
  EXPECT_EQ(e.rfind("spec.yaml:7:3: joints.pin: joint 'pin': axis must be a unit vector", 0), 0u)
      << e;
}

TEST_F(SceneSpecTest, PathErrorPointsAtThePathPoint) {
  spec_.bodies[1].path[2] = Vec3(1, 0, 0);  // back to the start of the corner segment
  const std::string e = CompileError(spec_, sources_);
  EXPECT_EQ(e.rfind("spec.yaml:5:", 0), 0u) << e;
  EXPECT_NE(e.find("bodies.rod.path[1]: the path turns back on itself here"), std::string::npos)
      << e;
}

TEST_F(SceneSpecTest, SpecMadeInCodeWithoutSourcesNamesTheFile) {
  SceneSources none;
  none.file = "code";
  spec_.bodies[0].mass = -1.0;
  EXPECT_EQ(CompileError(spec_, none).rfind("code: body 'arm': mass must be positive", 0), 0u)
      << CompileError(spec_, none);
  spec_.bodies[0].mass = 1.0;
  spec_.loads[0].body = 5;
  EXPECT_EQ(CompileError(spec_, none), "code: load: no body 5");
}

// The spec of kScene written in code, as a C++ program (or screwfem.SceneSpec) builds it.
SceneSpec CodeSpec() {
  SceneSpec spec;
  spec.name = "spec";  // ReadSceneSpec's default: the file name without its extension
  const Section s = Section::FromDiagonals(Vec6::Constant(1.0), Vec6::Constant(1.0));
  BodySpec arm;
  arm.name = "arm";
  arm.origin = Vec3(0, 0, 0);
  arm.com = Vec3(0.5, 0, 0);
  arm.mass = 1.0;
  arm.inertia = Mat3::Identity();
  BodySpec rod;
  rod.name = "rod";
  rod.rigid = false;
  rod.path = {Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0)};
  rod.elements = 2;
  rod.section = s;
  spec.bodies = {arm, rod};
  JointEntrySpec pin;
  pin.body_b = 0;
  pin.joint.name = "pin";
  pin.joint.type = JointType::kRevolute;
  JointEntrySpec weld;
  weld.body_a = 0;
  weld.body_b = 1;
  weld.joint.name = "weld";
  weld.joint.type = JointType::kFixed;
  weld.joint.point = Vec3(1, 0, 0);
  spec.joints = {pin, weld};
  LoadSpec push;
  push.name = "push";
  push.body = 0;
  push.at = Vec3(1, 0, 0);
  push.force = Vec3(0, 1, 0);
  LoadSpec tip;
  tip.name = "tip";
  tip.body = 1;
  tip.where = LoadSpec::Where::kArcLength;
  tip.arc_length = 2.0;
  tip.force = Vec3(0, 0, 1);
  spec.loads = {push, tip};
  spec.points = {{"A", Vec3(0, 0, 0)}, {"B", Vec3(1, 0, 0)}, {"C", Vec3(2, 0, 0)}};
  return spec;
}

TEST_F(SceneSpecTest, SpecBuiltInCodeCompilesAsTheFile) {
  const Scene file = CompileScene(spec_, sources_);
  const Scene code = CompileScene(CodeSpec(), "code");
  EXPECT_EQ(code.source, "code");
  EXPECT_EQ(code.name, file.name);
  ASSERT_EQ(code.model.nodes.size(), file.model.nodes.size());
  for (std::size_t n = 0; n < code.model.nodes.size(); ++n) {
    EXPECT_EQ(code.model.nodes[n].reference.R, file.model.nodes[n].reference.R) << n;
    EXPECT_EQ(code.model.nodes[n].reference.x, file.model.nodes[n].reference.x) << n;
  }
  ASSERT_EQ(code.model.joints.size(), 2u);
  EXPECT_EQ(code.model.joints[1].node_b, file.model.joints[1].node_b);
  EXPECT_EQ(code.model.rod_loads.size(), 1u);
  // The defaults a scene file leaves out are resolved by the compiler in both: every joint
  // with coordinates, about 1000 rows and 100 frames, statics at the start time.
  ASSERT_EQ(code.outputs.joints.size(), 1u);
  EXPECT_EQ(code.outputs.joints[0].name, "pin");
  EXPECT_EQ(code.outputs.interval, file.outputs.interval);
  EXPECT_EQ(code.outputs.interval, 1e-3);
  EXPECT_EQ(code.outputs.vtk_interval, 1e-2);
  EXPECT_EQ(code.named_points, file.named_points);
}

TEST_F(SceneSpecTest, EditedSpecResolvesItsDefaultsAsAnOverrideDoes) {
  spec_.analysis.end_time = 20.0;
  spec_.analysis.kind = AnalysisKind::kStatic;
  JointEntrySpec slide;
  slide.body_a = 1;
  slide.joint.name = "slide";
  slide.joint.type = JointType::kPrismatic;
  slide.joint.point = Vec3(2, 1, 0);
  slide.joint.axis = Vec3::UnitX();
  spec_.joints.push_back(slide);
  const Scene edited = CompileScene(spec_, "edited");
  const Scene overridden = ParseScene(
      kScene, "spec.yaml",
      {"analysis.end_time=20", "analysis.type=static",
       "joints.slide={type: prismatic, at: [2, 1, 0], between: [rod, ground], axis: [1, 0, 0]}"});
  EXPECT_EQ(edited.analysis.statics.time, 20.0);
  EXPECT_EQ(edited.analysis.statics.time, overridden.analysis.statics.time);
  EXPECT_EQ(edited.outputs.interval, overridden.outputs.interval);
  ASSERT_EQ(edited.outputs.joints.size(), 2u);  // the joint added after reading is recorded
  EXPECT_EQ(edited.outputs.joints[1].name, "slide");
  EXPECT_EQ(overridden.outputs.joints.size(), 2u);
}

TEST_F(SceneSpecTest, ErrorsOfASpecBuiltInCodeNameItsEntitiesAndFields) {
  SceneSpec spec = CodeSpec();
  spec.joints[1].joint.point = Vec3(1.5, 0.1, 0);  // no node of the rod there
  std::string e = CompileError(spec, NamedSources(spec, "code"));
  EXPECT_EQ(e.rfind("code: joints.weld.between[1]: joint point: soft body 'rod' has no node", 0),
            0u)
      << e;
  spec = CodeSpec();
  spec.bodies[0].mass = -1.0;
  e = CompileError(spec, NamedSources(spec, "code"));
  EXPECT_EQ(e, "code: bodies.arm: body 'arm': mass must be positive") << e;
  spec = CodeSpec();
  spec.loads[1].arc_length = 9.0;
  e = CompileError(spec, NamedSources(spec, "code"));
  EXPECT_EQ(e.rfind("code: loads.tip.s: arc length beyond the end of the rod", 0), 0u) << e;
  spec = CodeSpec();
  spec.bodies[1].path.resize(1);
  e = CompileError(spec, NamedSources(spec, "code"));
  EXPECT_EQ(e, "code: bodies.rod: soft body 'rod': a path needs at least two points") << e;
  spec = CodeSpec();
  spec.outputs.all_joints = false;
  spec.outputs.joints = {1};
  e = CompileError(spec, NamedSources(spec, "code"));
  EXPECT_EQ(e, "code: joints.weld: outputs: joint 'weld' is fixed: it has no coordinates to record")
      << e;
}

// A build error that a scene file can reach: elements shorter than the builder's length
// tolerance on a short segment.
TEST(SceneBuildErrors, ZeroLengthElementPointsAtTheSoftBody) {
  const std::string text = R"(points: {A: [0, 0, 0]}
sections: {s: {stiffness: [1, 1, 1, 1, 1, 1]}}
bodies:
  tiny: {type: soft, from: A, to: [1e-11, 0, 0], section: s, elements: 20, free: true}
)";
  std::string e;
  try {
    ParseScene(text, "bad.yaml");
  } catch (const InputError& x) {
    e = x.what();
  }
  EXPECT_EQ(e.rfind("bad.yaml:4:3: bodies.tiny: rod 'tiny': element 0 has zero length", 0), 0u)
      << e;
}

}  // namespace
}  // namespace screwfem::scene_spec_test
