// A scene as plain data, between reading and compiling (docs/architecture.md, "Scenes"): the
// reader (ReadSceneSpec) turns YAML into a SceneSpec, the compiler (CompileScene) turns a
// SceneSpec into ModelBuilder calls, the analysis settings and the output specification. A
// SceneSpec holds no YAML types: points, materials and sections are resolved to values, and
// entities refer to each other by index. Where each entity came from is kept apart, in the side
// table SceneSources, so that the physics structs carry no source locations.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/build/routing.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/stop.h"

namespace screwfem {

// A body: a rigid body at a node, or a soft body (a rod along a polyline).
struct BodySpec {
  std::string name;
  bool rigid = true;
  bool free = false;  // floating: connected to nothing on purpose
  // Rigid bodies. The body frame is world-aligned at `origin` in the reference configuration.
  bool fixed = false;               // welded to the ground
  Vec3 origin = Vec3::Zero();       // [m], world
  Vec3 com = Vec3::Zero();          // centre of mass [m], world
  double mass = 0.0;                // [kg]
  Mat3 inertia = Mat3::Identity();  // about the centre of mass, body frame [kg m^2]
  // Initial velocity of the centre of mass [m/s] and angular velocity [rad/s], world.
  bool has_initial_velocity = false;
  Vec3 initial_linear = Vec3::Zero(), initial_angular = Vec3::Zero();
  // Soft bodies: ModelBuilder::AddRodAlongPath(name, path, elements, section, up, ...).
  std::vector<Vec3> path;  // at least two points [m], world
  int elements = 8;        // per path segment
  Section section;
  Vec3 up = Vec3::UnitZ();
  // Welds: the first (last) node is shared with the node of an earlier soft body at that point.
  int weld_start = -1;  // body index, -1: none
  int weld_end = -1;
  // Contact (used when the scene has a contact: section). Soft bodies: the capsule radius [m]
  // (contact_radius, or the section's radius: circle radius, tube outer radius, half the
  // smaller side of a rectangle). Rigid bodies: shapes, points relative to `origin` (world axes;
  // ContactShape::body is set by the compiler). Group bitmasks of both.
  double contact_radius = 0.0;
  // Soft bodies: the radius the rod is drawn with [m] (the VTK frames' radius, the viewer's
  // tube), for drawing only; 0: the section's own outline (Section::width, height), else the
  // contact radius, else thin (io/vtk.h). The scene's visual_radius of the body or its section.
  double visual_radius = 0.0;
  std::vector<ContactShape> shapes;
  unsigned contype = 1, conaffinity = 1;
};

// A joint between two bodies (or a body and the ground) at joint.point. The compiler finds
// the sides' nodes (the rigid body's node, or the rod node at the point) and fills
// joint.node_a and joint.node_b.
struct JointEntrySpec {
  int body_a = -1;  // body index, -1: the ground
  int body_b = -1;
  JointSpec joint;
};

// An applied load: at a point of a body (`at`), at arc length s of a soft body, or distributed
// along a soft body (per unit length).
struct LoadSpec {
  enum class Where { kAt, kArcLength, kDistributed };
  std::string name;  // the scene's key (messages only: the model's loads have no names)
  int body = -1;
  Where where = Where::kAt;
  Vec3 at = Vec3::Zero();   // [m], world (kAt)
  double arc_length = 0.0;  // [m] (kArcLength)
  LoadFrame frame = LoadFrame::kWorld;
  Vec3 force = Vec3::Zero();   // [N] (or N/m)
  Vec3 moment = Vec3::Zero();  // [N m] (or N m/m)
  Profile profile = Profile::Constant(1.0);
};

// A point of a body (or of the ground) that a tendon eyelet or a force element's end is fixed
// to: the ground at `at`; a rigid body at `at` (world, reference configuration); a soft body at
// the rod node at `at` or at arc length s, offset from it in its section frame.
struct BodyPointSpec {
  int body = -1;               // body index, -1: the ground
  bool along_rod = false;      // soft bodies: the node at arc length s (else the node at `at`)
  Vec3 at = Vec3::Zero();      // [m], world
  double arc_length = 0.0;     // [m]
  Vec3 offset = Vec3::Zero();  // soft bodies: section-frame components [m]
  // Tendon eyelets only: this item stands for the eyelets of a route along the soft body
  // `body` (build/routing.h; route.rod is set by the compiler, `at`, `arc_length` and `offset`
  // are not used).
  bool routed = false;
  RodRoute route;
};

// A tendon (ModelBuilder::AddTendon): eyelets in routing order and the tension profile [N];
// or drawn by length (ModelBuilder::AddLengthDrivenTendon): the length profile [m].
struct TendonSpec {
  std::string name;
  std::vector<BodyPointSpec> eyelets;
  Profile tension = Profile::Constant(0.0);
  bool by_length = false;
  Profile length = Profile::Constant(0.0);
};

// A spring-damper-actuator between two body points (ModelBuilder::AddForceElement).
struct ForceSpec {
  std::string name;
  BodyPointSpec a, b;
  double stiffness = 0.0;     // [N/m]
  double damping = 0.0;       // [N s/m]
  double rest_length = -1.0;  // [m]; negative: the reference distance
  // The actuator [N], positive pulls the ends together (ForceElement::actuator; the scene key
  // is `force`).
  Profile actuator = Profile::Constant(0.0);
};

// Internal actuation of a soft body's rod over [from, to] of its arc length
// (ModelBuilder::AddActuator; model.h, Actuator): `profile` is the pressure [Pa], the
// activation [-] or the factor of `vector`, by type.
struct ActuatorSpec {
  std::string name;
  ActuatorType type = ActuatorType::kActiveStress;
  int body = -1;               // a soft body
  double from = 0.0;           // [m]
  double to = -1.0;            // [m]; negative: the rod's end
  double area = 0.0;           // [m^2]
  Vec3 offset = Vec3::Zero();  // section frame (0, r2, r3) [m]
  double max_stress = 0.0;     // [Pa]
  Vec6 vector = Vec6::Zero();
  Profile profile = Profile::Constant(1.0);
};

// A recorded point: a point of a body at `at`, or a point along a soft body at arc length s.
struct OutputPointSpec {
  std::string name;
  int body = -1;
  bool along_rod = false;
  Vec3 at = Vec3::Zero();   // [m], world
  double arc_length = 0.0;  // [m]
};

// A contact material group (contact.groups; ModelBuilder::AddContactMaterialGroup): bodies
// (rigid or soft; spec indices) and obstacles (ContactSpec::obstacles indices).
struct ContactGroupSpec {
  std::string name;
  std::vector<int> bodies;
  std::vector<int> obstacles;
};

// The contact: section (ModelBuilder::SetContactSettings, AddObstacle, ExcludeContact).
struct ContactSpec {
  bool present = false;
  ContactSettings settings;
  std::vector<ContactObstacle> obstacles;
  std::vector<std::pair<int, int>> exclude;         // (body index, obstacle index)
  std::vector<std::pair<int, int>> exclude_bodies;  // (body index, body index): moving pairs
  // Materials per pair of groups (contact.groups, contact.pairs; model.h, ContactMaterial with
  // group indices into `groups`).
  std::vector<ContactGroupSpec> groups;
  std::vector<ContactMaterial> pairs;
};

// What to record. The defaults depend on the rest of the spec and are resolved by the
// compiler, so that a spec edited after reading (a longer end_time, another joint) records as
// the same scene file would: negative intervals are the scene's defaults (OutputSpec,
// kDefaultOutputRows), and all_joints records every joint with coordinates.
struct OutputsSpec {
  std::vector<OutputPointSpec> points;
  bool all_joints = true;   // the scene's `joints: all` (the default); else `joints`
  std::vector<int> joints;  // joint indices, in the order recorded (when !all_joints)
  // [s]; 0: every step; negative: about kDefaultOutputRows rows over the run.
  double interval = -1.0;
  bool vtk = true;
  VtkFormat vtk_format = VtkFormat::kBinary;
  // [s]; 0: the same as interval; negative: `interval` when that is given (>= 0), else about
  // kDefaultVtkFrames frames over the run.
  double vtk_interval = -1.0;
  bool rod_fields = false;            // see OutputSpec
  double rod_fields_interval = -1.0;  // [s]; < 0: at the rows of points.csv
  long max_rows = kDefaultMaxRows;    // see OutputSpec
  bool reactions = true;              // see OutputSpec
  bool energy = true;                 // see OutputSpec
};

struct SceneSpec {
  std::string name;
  Vec3 gravity = Vec3::Zero();  // [m/s^2]
  RodInertia rod_inertia = RodInertia::kExact;
  LinearSolver linear_solver = LinearSolver::kAuto;  // analysis.linear_solver
  bool conform_mesh = true;  // defaults.conform_mesh (ModelBuilder::SetConformMesh)
  std::vector<std::pair<std::string, Vec3>> points;    // named points [m], world
  std::vector<std::pair<std::string, double>> inputs;  // run-time inputs and their defaults
  std::vector<BodySpec> bodies;
  std::vector<JointEntrySpec> joints;
  std::vector<LoadSpec> loads;
  std::vector<TendonSpec> tendons;
  std::vector<ForceSpec> forces;
  std::vector<ActuatorSpec> actuators;  // the `actuation:` section
  ContactSpec contact;
  // The compiler sets analysis.statics.time from the kind: end_time for static analyses,
  // start_time (the preload) for dynamic ones (docs/scene-format.md, "analysis").
  AnalysisSettings analysis;
  OutputsSpec outputs;
};

// ---- the side table of source locations --------------------------------------------------

// A line and column of the scene file (1-based; 0: unknown), or the override that wrote it.
struct SourceLocation {
  int line = 0;
  int column = 0;
  // Non-null: written by this override (shared by all nodes it wrote).
  std::shared_ptr<const std::string> override_text;
};

// A field of the file: where it is and its dotted name in messages ("bodies.arm.weld_start").
struct FieldSource {
  SourceLocation location;
  std::string field;
};

// Where an entity was defined (its name), and where some of its parts were: for bodies
// "path[i]" (each path point; "from" and "to" map to path[0] and path[1]), "start_node" and
// "end_node" (the welds); for joints "node_a" and "node_b" (the sides); for loads and output
// points "at" and "s"; for tendons "eyelets[i]"; for force elements "a" and "b". The part names
// are those of InputError::entity().part.
struct EntitySource {
  FieldSource self;
  std::vector<std::pair<std::string, FieldSource>> parts;
  const FieldSource* Part(const std::string& name) const;
};

struct SceneSources {
  std::string file;  // the source name used in messages
  FieldSource root;  // the document
  std::vector<EntitySource> bodies, joints, loads, output_points, tendons, forces;
  std::vector<EntitySource> actuators;  // parts "rod", "from", "to", "area", "offset", ...
};

// Reads scene text (docs/scene-format.md) with overrides applied into a spec and the sources
// of its entities. Checks everything that does not need the model's geometry. Throws
// InputError "FILE:LINE:COLUMN: FIELD: what was expected".
SceneSpec ReadSceneSpec(const std::string& yaml_text, const std::string& source_name,
                        const std::vector<std::string>& overrides, SceneSources* sources);

// ReadSceneSpec of a scene file (read as LoadScene reads it, with its size limit, polling
// `stop` while reading); messages name `path`.
SceneSpec LoadSceneSpec(const std::string& path, const std::vector<std::string>& overrides,
                        SceneSources* sources, const StopRequest& stop = {});

// Compiles a spec into a Scene through ModelBuilder: finds the nodes of joints, welds, loads
// and output points, checks that every body is connected, builds the Model. Errors, including
// the builder's (InputError::entity()), name the entity's place in `sources`.
Scene CompileScene(const SceneSpec& spec, const SceneSources& sources);

// Sources for a spec made in code (or edited after reading): no locations, and as fields the
// places a scene file would give, from the entities' names ("bodies.arm", parts
// "bodies.arm.path[1]", "joints.J1.between[0]", "tendons.t.eyelets[2]", ...; "loads[3]" for an
// entity without a name). Messages then read "SOURCE_NAME: FIELD: what".
SceneSources NamedSources(const SceneSpec& spec, const std::string& source_name);

// CompileScene(spec, NamedSources(spec, source_name)): the construction API for specs built
// in code, in C++ as in Python (screwfem.SceneSpec.compile).
Scene CompileScene(const SceneSpec& spec, const std::string& source_name);

}  // namespace screwfem
