// ModelBuilder: the compiler of a Model (docs/architecture.md). C++ and Python users and the
// scene compiler (io/) build models through it; Build() validates everything once and computes
// the layout, the solver ordering and the redundant constraint rows.
#pragma once

#include <string>
#include <vector>

#include "screwfem/elements/joint.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/model.h"

namespace screwfem {

// A joint, added in one call by ModelBuilder::AddJoint(const JointSpec&). The joint frame is
// world-aligned at `point` in the reference configuration, so H_J = I and the coordinates are 0
// there (elements/joint.h).
struct JointSpec {
  std::string name;
  JointType type = JointType::kRevolute;
  NodeId node_a = kGround;  // the two sides: nodes or kGround (not both the same)
  NodeId node_b = kGround;
  Vec3 point = Vec3::Zero();  // [m], world
  // Unit axis of the joint type (plane normal of a planar joint); axis2 is the universal
  // joint's second axis (orthogonal to axis); pitch [m/rad] of a helical joint. Used as the
  // type's table row says (JointTypeInfo::uses_axis, uses_axis2, uses_pitch).
  Vec3 axis = Vec3::UnitZ();
  Vec3 axis2 = Vec3::Zero();
  double pitch = 0.0;
  // Springs and dampers on the coordinates (elements/joint.h), JointSpringCount entries used:
  // stiffness [N/m or N m/rad], damping [N s/m or N m s/rad], rest [m or rad] (global
  // coordinates only).
  Vec6 stiffness = Vec6::Zero();
  Vec6 damping = Vec6::Zero();
  Vec6 rest = Vec6::Zero();
  // A drive on one coordinate (elements/joint.h): prescribed q(t) [m or rad], force f(t) [N or
  // N m], or a series-elastic spring whose rest value follows the profile.
  DriveKind drive = DriveKind::kNone;
  int drive_coordinate = 0;
  Profile drive_profile;
  // Initial coordinates [m or rad] and rates [m/s or rad/s] (k values), assembled with the
  // constraints before the start (AssembleInitialState, solve/initial_state.h).
  bool has_initial_coordinate = false, has_initial_rate = false;
  Vec6 initial_coordinate = Vec6::Zero(), initial_rate = Vec6::Zero();
};

// The result of ModelBuilder::FindNodeAt: the nearest node and its distance; node is invalid
// (-1) when the nearest one is farther than the tolerance (or there is none).
struct NodeMatch {
  NodeId node;
  NodeId nearest;         // the nearest node, even when out of tolerance
  double distance = 0.0;  // [m] to the nearest node (infinity when there is none)
};

// A contact entity: a rod or a rigid body (ModelBuilder's contact groups and exclusions).
struct ContactEntity {
  ContactEntity(RodId r) : rod(true), index(r) {}    // NOLINT(google-explicit-constructor)
  ContactEntity(BodyId b) : rod(false), index(b) {}  // NOLINT(google-explicit-constructor)
  bool rod;
  int index;
};

// Builds a Model through a small C++ API; Build() validates everything and computes the layout.
// It hands out and takes typed ids (model/ids.h): a NodeId where a RodId or BodyId is expected
// does not compile.
class ModelBuilder {
 public:
  // A node with a frame. Names must be unique when given.
  NodeId AddNode(const SE3& frame, std::string name = {});
  void FixNode(NodeId node);
  // A straight rod from p0 to p1 with n elements. Node frames have x along the rod and z as
  // close as possible to `up` (any vector not parallel to the rod). Optional existing end
  // nodes are shared (their positions must coincide with p0/p1; the rod is then rigidly joined
  // there).
  RodId AddStraightRod(std::string name, const Vec3& p0, const Vec3& p1, int num_elements,
                       const Section& section, const Vec3& up = Vec3::UnitZ(),
                       NodeId start_node = {}, NodeId end_node = {});
  // A straight rod of given length along the x axis of `root` (root.R gives all node frames).
  RodId AddStraightRodFromFrame(std::string name, const SE3& root, double length, int num_elements,
                                const Section& section, NodeId start_node = {},
                                NodeId end_node = {});
  // A rod through existing nodes (curved references allowed: element references are
  // log(H_a^-1 H_b) of the nodes' reference frames).
  RodId AddRodThroughNodes(std::string name, const std::vector<NodeId>& nodes,
                           const Section& section);
  // A rod along the polyline `path` (at least two points [m], world) with
  // `elements_per_segment` elements on each segment. Node frames have x along the segment and z
  // as close as possible to `up`; at interior path points x is along the bisector of the two
  // segments (the sum of their unit directions), so that the rod turns there by curving. A path
  // of two points is AddStraightRod. Optional existing end nodes are shared (welds): their
  // reference frames must equal the path's frames there. Throws InputError (entity: the rod,
  // part "path[i]" for a segment of zero length or a point where the path turns back on itself,
  // "start_node"/"end_node" for a shared node that does not fit).
  RodId AddRodAlongPath(std::string name, const std::vector<Vec3>& path, int elements_per_segment,
                        const Section& section, const Vec3& up = Vec3::UnitZ(),
                        NodeId start_node = {}, NodeId end_node = {});
  // The node nearest to world point p in the reference configuration, among the nodes of rod
  // `rod` (all nodes when rod is invalid), within `tolerance` [m]. A negative tolerance means
  // 1e-8 max(1, |p|, the distance between the rod's end nodes).
  NodeMatch FindNodeAt(const Vec3& p, RodId rod = {}, double tolerance = -1.0) const;
  // Reference arc length [m] of a rod added so far (the sum of its elements' lengths, as Build
  // computes them).
  double RodLength(RodId rod) const;
  // The reference arc length at each node of a rod added so far, from its first node [m]
  // (RodLength is the last; FindRodNodeAtArcLength, the scene compiler and RouteAlongRod place
  // points on these same doubles).
  std::vector<double> RodArcLengths(RodId rod) const;
  // The nodes of a rod added so far, in order along it.
  std::vector<NodeId> RodNodes(RodId rod) const;
  BodyId AddRigidBody(std::string name, NodeId node, double mass, const Vec3& com,
                      const Mat3& inertia);
  JointId AddJoint(const Joint& joint);  // offsets, basis and names filled by the caller
  // A joint from its spec (AddJointAt plus springs, dampers and drive). Throws InputError
  // (entity: the joint, part "node_a"/"node_b" for an invalid side).
  JointId AddJoint(const JointSpec& spec);
  // A joint at world point `point` with world axis `axis` (plane normal for planar joints;
  // `axis2` is the second axis of a universal joint), between node_a and node_b (either may be
  // kGround). The joint frame is world-aligned in the reference configuration, so H_J = I and
  // the coordinates are 0 there (elements/joint.h). Returns the joint; AddJoint(JointSpec)
  // also sets stiffness, damping and a drive.
  JointId AddJointAt(std::string name, JointType type, NodeId node_a, NodeId node_b,
                     const Vec3& point, const Vec3& axis = Vec3::UnitZ(),
                     const Vec3& axis2 = Vec3::Zero(), double pitch = 0.0);
  // A tendon through `eyelets` (at least two body points, in routing order: node frames with
  // node-frame offsets, or world points on kGround) pulling with tension tau(t) [N]
  // (docs/numerics.md, "Tendons and force elements"). Eyelets sit on nodes: an eyelet on a rod is a section frame's node
  // plus an offset (FindRodNodeAtArcLength places one at an arc length); one given by rod and
  // arc length between nodes gets a node of its own (SetConformMesh) or sits on the element. Build checks: at least
  // two eyelets, valid nodes, finite offsets, consecutive eyelets apart in the reference
  // configuration, and a tension profile that cannot become negative (each term's lower bound
  // summed). Errors carry EntityKind::kTendon, part "eyelets[i]" for an eyelet.
  TendonId AddTendon(std::string name, std::vector<BodyPoint> eyelets, const Profile& tension);
  // A tendon drawn by length (model.h, TendonDrive::kLength): the constraint L(q) = L_p(t) [m]
  // with the tension as its multiplier, slack while the route is shorter than L_p.
  TendonId AddLengthDrivenTendon(std::string name, std::vector<BodyPoint> eyelets,
                                 const Profile& length);
  // A spring-damper-actuator between two body points (model.h, ForceElement); a negative
  // rest_length means the reference distance. An end may give a rod and an arc length: Build
  // places it as a tendon eyelet (on the node there or between nodes: ForceElementSpanKind,
  // elements/force_span.h). Build checks: valid ends, not both on one node (or the ground),
  // finite values, non-negative stiffness and damping, ends apart in the reference
  // configuration. Errors carry EntityKind::kForceElement, part "a" or "b" for an end.
  ForceElementId AddForceElement(const ForceElement& element);
  // The node of rod `rod` at reference arc length s [m] (from its first node), within
  // `tolerance` [m] (negative: 1e-8 max(1, rod length)); node -1 and the nearest node and its
  // arc-length distance otherwise.
  NodeMatch FindRodNodeAtArcLength(RodId rod, double s, double tolerance = -1.0) const;
  // Internal actuation of a rod (model.h, Actuator; docs/numerics.md, "Active stress and rest strain"). Build checks: a valid
  // rod, [from, to] inside it and at nodes (SetConformMesh puts nodes there; without it an
  // error names the nearest node's arc length), positive area for pressure and muscle,
  // non-negative max_stress, finite offset and vector, the profile's inputs, unique names, and
  // no value the type does not use (a chamber's or muscle's axial offset component, a vector
  // on a chamber, max_stress on a pressure chamber, area, offset or max_stress on a rest strain
  // or active stress). Errors carry EntityKind::kActuator and the field as part.
  ActuatorId AddActuator(const Actuator& actuator);
  PointLoadId AddPointLoad(const PointLoad& load);
  RodLoadId AddRodLoad(const RodLoad& load);
  void SetGravity(const Vec3& g);
  // The initial body velocity of a node [v; w] in its frame (AssembleInitialState).
  void SetInitialVelocity(NodeId node, const Vec6& velocity);
  // A run-time input (Model::inputs) that profiles take with Profile::Input(index); returns
  // the index. Names are unique.
  InputId AddInput(std::string name, double default_value = 0.0);
  // Contact (docs/numerics.md, "Contact", elements/contact.h). A rod in contact is a chain of capsules
  // of `radius` around its element chords (its nodes' spheres against planes); a rigid body
  // carries shapes in its frame (model.h, ContactShape); obstacles are fixed in the world.
  // Build pairs every rod and body that has shapes with every obstacle, except excluded pairs
  // and pairs whose group bitmasks do not match (model.h, ContactGroup), and resolves the
  // law's defaults (ContactSettings). Errors carry EntityKind::kContactRod, kContactShape or
  // kObstacle: non-positive sizes, unknown rods or bodies, mu < 0, a zero plane normal.
  ContactRodId AddContactRod(RodId rod, double radius);
  ContactShapeId AddContactShape(const ContactShape& shape);
  ObstacleId AddObstacle(const ContactObstacle& obstacle);
  void SetContactGroup(ContactEntity entity, unsigned contype, unsigned conaffinity);
  void ExcludeContact(ContactEntity entity, ObstacleId obstacle);
  void SetContactSettings(const ContactSettings& settings);
  // Pairs between moving shapes (elements/shape_pair.h): Build also pairs every two contact
  // entities (rods, bodies with shapes; a box only against spheres) whose bitmasks match,
  // unless excluded here or joined (a shared node or a joint between their nodes); a rod with
  // itself when ContactSettings::self.
  void ExcludeContactPair(ContactEntity a, ContactEntity b);
  // Contact materials (model.h, ContactMaterial; docs/scene-format.md, `contact.pairs`): a named
  // group of rods, bodies and obstacles (each in at most one group), returning its index, and
  // the law's parameters for a pair of groups (ContactMaterial::group; negative values: the
  // scene's). Build checks them (unknown groups or members, a pair of groups given twice,
  // mu_s < mu_k) and resolves them into Model::contact_laws.
  int AddContactMaterialGroup(const std::string& name, const std::vector<ContactEntity>& members,
                              const std::vector<ObstacleId>& obstacles = {});
  void AddContactMaterial(const ContactMaterial& material);
  Model& model() { return model_; }
  const Model& model() const { return model_; }
  // The memory the model may need [bytes] (0: the process default; model/memory.h). Build()
  // estimates, before allocating them, the pairs of moving shapes and obstacles, the table of
  // contact entities, the contact couplings of the ordering and the workspace of MakeData (the
  // banded LU above all), and throws InputError naming the part that exceeds it.
  void SetMemoryLimit(std::size_t bytes) { model_.memory_limit = bytes; }
  // The direct solver of the Newton systems (Model::linear_solver; kAuto by default).
  void SetLinearSolver(LinearSolver solver) { model_.linear_solver = solver; }

  // Whether Build conforms the rod meshes to the features placed on them (Model::conform_mesh,
  // default true; docs/numerics.md, "Conforming rod meshes"): a node where a tendon eyelet, a
  // force element's end, a concentrated rod load or an actuator's from/to falls inside an
  // element, the element split there (second-order convergence; element counts grow by the
  // nodes added, Model::conformed_nodes). The nodes added come after all others, so NodeIds and
  // RodNodes taken before Build stay valid; element indices of the built Model count the split
  // elements.
  void SetConformMesh(bool conform) { model_.conform_mesh = conform; }

  // Validates and computes sizes and the ordering. Throws InputError.
  Model Build() const;

 private:
  // The entity of the rod that the next Add*Rod* call adds (for its errors).
  EntityRef NextRod() const { return {EntityKind::kRod, static_cast<int>(model_.rods.size()), {}}; }
  Model model_;
};

// The most pairs of moving shapes and obstacles a model may have (Build: InputError naming
// the count; every pair is tested at every assembly): a 100,000-element rod against 100 curved
// obstacles.
inline constexpr double kMaxObstaclePairs = 1e7;
// The most node couplings the solver ordering puts in the band for pairs of contact entities
// that may touch (ContactSettings::band_pair_nodes each): beyond, none is (they enter the solve
// as the off-band coupling when they touch) and Build warns. 10,000 spheres that may touch
// each other made a band of 59,999 (86 GB of LU factors).
inline constexpr double kMaxBandContactLinks = 1e6;

// Redundant constraint rows at the reference configuration (called by ModelBuilder::Build on
// a model whose layout is set; build/redundancy.cpp): fills model.redundant_rows and adds a
// warning naming the joints involved. The joint graph (nodes with unknowns, and one vertex for
// the ground and every fixed node; an edge per joint with constraint rows) is split into a
// spanning forest and chords. The rows of tree joints are independent (each has an invertible
// block on its child node), so only chord rows and drive rows can be redundant: they are
// reduced onto the coordinates of the tree joints between the chord's ends and their lowest
// common ancestor (the common ancestor's rigid motion drops out exactly), and each group of
// reduced rows that share coordinates is rank-revealed with a column-pivoting QR (relative
// threshold 1e-10). The gradient is the joint kernel's (CalcJointGradient), as in the
// assembly. Cost: linear in the joints for trees; for loops, the tree paths walked plus one
// dense QR per group. Scenes whose loops exceed kMaxRedundancyWork skip the check with a
// warning.
void FindRedundantConstraints(Model& model);
// Work bound of FindRedundantConstraints: tree-path steps (a few microseconds each) plus the
// dense QRs' operation counts / 1000; about 2 s at the bound.
inline constexpr double kMaxRedundancyWork = 1e6;

}  // namespace screwfem
