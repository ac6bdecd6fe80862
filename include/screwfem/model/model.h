// The compiled model (constant); its workspace is Data (model/data.h), its builder
// ModelBuilder (build/model_builder.h); see docs/architecture.md.
//
// Unknowns. Velocities v (size nv) stack 6 body-velocity components per free node (translation
// first) and then k joint-coordinate rates per joint. Multipliers lambda (size nc) stack the 6
// relative-frame constraints per joint (none for a free joint) and one row per prescribed
// drive. The Newton systems solve for x = [dx (nv); dmu (nc)] in a bandwidth-reducing order
// computed once at build time.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "screwfem/lie/se3.h"
#include "screwfem/linalg/sparse_lu.h"
#include "screwfem/model/enum_names.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/ids.h"
#include "screwfem/model/mesh.h"
#include "screwfem/model/profile.h"
#include "screwfem/model/section.h"

namespace screwfem {

using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Mat6X = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;

// kGround (model/ids.h): the node index -1 standing for the world frame.

struct Node {
  std::string name;
  SE3 reference;       // initial frame H_0
  bool fixed = false;  // clamped to the world: eliminated from the unknowns
  int dof = -1;        // first velocity index, or -1 when fixed
  // Initial body velocity [v (m/s); w (rad/s)] in the node frame, held by AssembleInitialState
  // (solve/initial_state.h) when given.
  bool has_initial_velocity = false;
  Vec6 initial_velocity = Vec6::Zero();
};

// One two-node helical element (elements/rod.h).
struct RodElement {
  int rod = -1;
  int node_a = -1, node_b = -1;
  double length = 0.0;     // reference arc length L = |u(d0)|
  Vec6 d0 = Vec6::Zero();  // reference relative motion log(H_A0^-1 H_B0)
  // Its actuators (docs/numerics.md, "Active stress and rest strain"): Model::element_actuators[first_actuator + i],
  // i < num_actuators (set by Build).
  int first_actuator = 0;
  int num_actuators = 0;
};

struct Rod {
  std::string name;
  Section section;
  std::vector<int> nodes;  // num_elements + 1 node indices, in order along the rod
  int first_element = 0;
  int num_elements = 0;
  double length = 0.0;  // sum of the element lengths
};

struct RigidBody {
  std::string name;
  int node = -1;                // the body's frame is this node's frame
  double mass = 0.0;            // [kg]
  Vec3 com = Vec3::Zero();      // centre of mass in the node frame [m]
  Mat3 inertia = Mat3::Zero();  // inertia about the centre of mass, node-frame axes [kg m^2]
};

enum class LoadFrame {
  kWorld,  // dead load: fixed direction in the world
  kBody,   // follower load: fixed in the node frame
};
template <>
struct EnumNames<LoadFrame> {
  static constexpr std::array<EnumName<LoadFrame>, 2> kValues = {{
      {LoadFrame::kWorld, "world", "dead load: fixed direction in the world"},
      {LoadFrame::kBody, "body", "follower load: fixed in the body's frame"},
  }};
};

// A force and a moment applied at a point of a node frame, scaled by a profile.
struct PointLoad {
  int node = -1;
  Vec3 point = Vec3::Zero();  // application point in the node frame [m]
  LoadFrame frame = LoadFrame::kWorld;
  Vec3 force = Vec3::Zero();   // [N]
  Vec3 moment = Vec3::Zero();  // [N m]
  Profile profile = Profile::Constant(1.0);
};

// A load on a rod: distributed over its whole length, or concentrated on the section at
// reference arc length `arc_length` (measured from the rod's first node), scaled by a profile.
struct RodLoad {
  int rod = -1;
  bool distributed = true;
  double arc_length = 0.0;  // concentrated loads [m]
  LoadFrame frame = LoadFrame::kWorld;
  Vec3 force = Vec3::Zero();   // [N/m] distributed, [N] concentrated
  Vec3 moment = Vec3::Zero();  // [N m/m] distributed, [N m] concentrated
  Profile profile = Profile::Constant(1.0);
  // Filled by Build for concentrated loads: the element carrying the section and xi in it.
  int element = -1;
  double xi = 0.0;
};

// A point fixed in a node frame (a rod node's section frame or a rigid body's frame), or in
// the world (node kGround): the eyelet of a tendon, the end of a force element. An eyelet or
// an end may also sit at an arc length of a rod (rod >= 0): Build places it on the node there
// or, between nodes, on the section of the element holding it, the helical interpolation
// H_A exp(xi d) of the element's frames (docs/numerics.md, "Eyelets between nodes"); the
// offset is then in that section's frame.
struct BodyPoint {
  int node = kGround;
  Vec3 offset = Vec3::Zero();  // node-frame components [m] (world point for kGround)
  int rod = -1;                // >= 0: the point is on this rod at arc_length
  double arc_length = 0.0;     // reference arc length along the rod [m]
  // Set by Build for a point between nodes: the element (node is its node A) and xi in (0, 1).
  int element = -1;
  double xi = 0.0;
};

// A tendon (cable) routed through an ordered list of eyelets, sliding through them without
// friction (docs/numerics.md, "Tendons and force elements"): its length is the sum of the straight segments between
// consecutive eyelets and it pulls with a prescribed tension tau(t) >= 0. Each segment is an
// item of TendonSegmentKind (elements/tendon.h).
//
// Or it is drawn by length (docs/numerics.md, "Tendons and force elements", a motor in position mode): the rheonomic
// constraint L(q) - L_p(t) = 0, one multiplier row whose multiplier is the tension; unilateral
// (the tendon goes slack when the solved tension would be negative and is taut again when its
// path length reaches L_p: Data::tendon_slack, docs/numerics.md "Length-driven tendons").
enum class TendonDrive {
  kTension,  // the tension profile
  kLength,   // the length profile; the tension is the multiplier
};

struct Tendon {
  std::string name;
  std::vector<BodyPoint> eyelets;            // at least two
  Profile tension = Profile::Constant(0.0);  // [N], scaled by the load factor in statics
  TendonDrive drive = TendonDrive::kTension;
  // kLength: the prescribed length L_p(t) [m]; in statics the load factor f moves it from the
  // reference length: L_ref + f (L_p - L_ref).
  Profile length = Profile::Constant(0.0);
  int first_segment = -1;         // set by Build: its segments are first_segment + 0 .. eyelets - 2
  int row = -1;                   // set by Build: kLength's multiplier row (else -1)
  double reference_length = 0.0;  // set by Build: L in the reference configuration [m]
};

// One straight segment of a tendon, between consecutive eyelets (made by Build).
struct TendonSegment {
  int tendon = -1;
  BodyPoint a, b;
};

// Segments of Model::tendon_segments between the same two nodes: indices
// tendon_group_segments[first, first + count).
struct TendonSegmentGroup {
  int node_a = -1, node_b = -1;
  int first = 0, count = 0;
};

// A spring-damper-actuator between two body points (either may be on the ground): along the
// line between them a force f = stiffness (l - rest_length) + damping dl/dt + actuator(t),
// positive pulling the points together (tension).
struct ForceElement {
  std::string name;
  BodyPoint a, b;
  double stiffness = 0.0;     // [N/m]
  double rest_length = -1.0;  // [m]; negative: the reference distance (set by Build)
  double damping = 0.0;       // [N s/m]
  Profile actuator = Profile::Constant(0.0);  // [N], scaled by the load factor in statics
};

// Internal actuation of a rod (docs/numerics.md, "Active stress and rest strain"): a rest-strain change eps0(t) and an active
// section stress sigma_a(t) (section frame; axial, shear 2, shear 3, torsion, bending 2,
// bending 3), constant over each element it covers, so that an element transmits
// sigma = K (eps - eps0) - sigma_a. Every type is linear in its profile's value v(t):
//  * kPressure: a chamber of area A at section offset r = (0, r2, r3), pressure v [Pa]:
//    sigma_a = v A [1, 0, 0, 0, r3, -r2] (the end caps pushed apart);
//  * kMuscle: fibres of area A at offset r, maximal stress s_max [Pa], activation v clamped to
//    [0, 1]: sigma_a = -v s_max A [1, 0, 0, 0, r3, -r2] (fibre tension compresses the section);
//  * kRestStrain: eps0 = v * vector;  * kActiveStress: sigma_a = v * vector.
enum class ActuatorType { kPressure, kMuscle, kRestStrain, kActiveStress };
template <>
struct EnumNames<ActuatorType> {
  static constexpr std::array<EnumName<ActuatorType>, 4> kValues = {{
      {ActuatorType::kPressure, "pressure", "a pressurised chamber: area, offset, pressure"},
      {ActuatorType::kMuscle, "muscle", "contractile fibres: area, offset, max_stress, activation"},
      {ActuatorType::kRestStrain, "rest_strain", "a rest-strain change: vector times a profile"},
      {ActuatorType::kActiveStress, "active_stress",
       "an active section stress: vector times a profile"},
  }};
};

struct Actuator {
  std::string name;
  ActuatorType type = ActuatorType::kActiveStress;
  int rod = -1;
  // The covered reference arc length [from, to] of the rod [m], both at nodes; to < 0: the
  // rod's end.
  double from = 0.0, to = -1.0;
  double area = 0.0;           // kPressure, kMuscle [m^2]
  Vec3 offset = Vec3::Zero();  // kPressure, kMuscle: centroid (0, r2, r3) in the section [m]
  double max_stress = 0.0;     // kMuscle [Pa]
  Vec6 vector = Vec6::Zero();  // kRestStrain [1, 1, 1, 1/m, 1/m, 1/m], kActiveStress [N, N m]
  // Pressure [Pa], activation [-] or the factor of `vector`; scaled by the load factor in
  // statics.
  Profile profile = Profile::Constant(1.0);
  // Set by Build: the covered elements (global indices first_element .. + num_elements - 1)
  // and eps0, sigma_a per unit profile value.
  int first_element = -1, num_elements = 0;
  Vec6 rest_strain_unit = Vec6::Zero(), active_stress_unit = Vec6::Zero();
};

enum class JointType {
  kRevolute,
  kPrismatic,
  kHelical,
  kCylindrical,
  kSpherical,
  kPlanar,
  kUniversal,
  kFixed,
  kFree,
};

enum class DriveKind {
  kNone,           // passive joint
  kPrescribed,     // rheonomic constraint alpha_i = q(t) on one coordinate (elements/joint.h)
  kSeriesElastic,  // spring/damper towards q(t) on one coordinate (elements/joint.h)
  kForce,          // generalised force f(t) on one coordinate
};
template <>
struct EnumNames<DriveKind> {
  static constexpr std::array<EnumName<DriveKind>, 4> kValues = {{
      {DriveKind::kNone, "none", "passive joint"},
      {DriveKind::kPrescribed, "prescribed", "the coordinate follows q(t) exactly"},
      {DriveKind::kSeriesElastic, "series_elastic", "a spring and damper towards q(t)"},
      {DriveKind::kForce, "force", "a generalised force f(t)"},
  }};
};

// A joint: relative frame H_J in a subgroup between frame A (node a, or the ground) and frame
// B (node b), placed by the constant offsets C_A, C_B (elements/joint.h): H_B C_B = H_A C_A H_J.
struct Joint {
  std::string name;
  JointType type = JointType::kRevolute;
  int node_a = kGround, node_b = kGround;
  SE3 offset_a, offset_b;  // C_A, C_B (C_A is the joint frame's world pose for the ground)
  Mat6X basis;             // A_J, 6 x k
  double pitch = 0.0;      // helical joints [m/rad]
  int coord = -1;          // first velocity index of the joint coordinates
  int row = -1;            // first multiplier row of the 6 relative-frame constraints (-1: none)
  // Soft joint: force K (alpha - alpha_rest) + D (alpha_dot - rest_rate) on each coordinate.
  Vec6 stiffness = Vec6::Zero();
  Vec6 damping = Vec6::Zero();
  Vec6 rest = Vec6::Zero();
  // Drive on one coordinate.
  DriveKind drive = DriveKind::kNone;
  int drive_coord = 0;    // which coordinate (0..k-1)
  int drive_row = -1;     // multiplier row of a prescribed drive
  Profile drive_profile;  // q(t) [m or rad], or the force/torque f(t)
  // Initial coordinates and rates (k values each), held by AssembleInitialState when given.
  bool has_initial_coordinate = false, has_initial_rate = false;
  Vec6 initial_coordinate = Vec6::Zero(), initial_rate = Vec6::Zero();
  // Coordinates (unknowns) of the joint: the columns of A_J. A free joint has none: its
  // relative motion is that of its two frames, with no constraint rows (JointSpringCount,
  // elements/joint.h, says how many springs a joint carries).
  int k() const { return static_cast<int>(basis.cols()); }
};

enum class RodInertia {
  kExact,  // option A: exact helical velocity field, M(d), 3-point Gauss (docs/numerics.md, "Rod inertia")
  kConstant,  // option B: linear velocity interpolation, constant mass matrix
};
template <>
struct EnumNames<RodInertia> {
  static constexpr std::array<EnumName<RodInertia>, 2> kValues = {{
      {RodInertia::kExact, "exact", "option A: the exact helical velocity field"},
      {RodInertia::kConstant, "constant", "option B: linear velocity field, constant mass"},
  }};
};

// The direct solver of the Newton systems (docs/numerics.md, "Sparse direct solve"): the
// banded LU on the bandwidth-reducing order, or the general sparse LU (KLU); kAuto picks the
// one whose predicted factorisation cost is lower (Model::sparse_solver).
enum class LinearSolver { kAuto, kBanded, kSparse };
template <>
struct EnumNames<LinearSolver> {
  static constexpr std::array<EnumName<LinearSolver>, 3> kValues = {{
      {LinearSolver::kAuto, "auto", "the lower predicted factorisation cost"},
      {LinearSolver::kBanded, "banded", "banded LU on the bandwidth-reducing order"},
      {LinearSolver::kSparse, "sparse", "general sparse LU (SuiteSparse KLU)"},
  }};
};
// The choice of LinearSolver::kAuto: the sparse LU when kSparseFlopCost x its predicted flops
// + kSparseFixedCost x the unknowns is below the banded LU's predicted flops, its off-band
// contact coupling's included (Model::coupling_flops; a flop of KLU's
// indexed columns costs more than one of the band's contiguous ones, and each column has a
// fixed cost; measured on bench/solver_bench.cpp, docs/numerics.md, "Sparse direct solve").
inline constexpr double kSparseFlopCost = 4.0;
inline constexpr double kSparseFixedCost = 200.0;
// The nodes of one entity a contact with another is predicted to couple (a rod crossing
// another: the two nodes of its nearest element and a neighbour's).
inline constexpr int kContactRegionNodes = 3;
// The weight of a flop of the banded LU's Woodbury coupling (Model::coupling_flops: banded
// solves on contiguous columns and a dense LU in cache) against one of the band's
// elimination: measured on one crossing of two rods (bench/pairs_bench.cpp rods/1x1, the
// sparse LU 1.15x the CPU time of banded + Woodbury) and nine (rods/3x3, 0.55x).
inline constexpr double kCouplingFlopCost = 0.25;

// A run-time input (MuJoCo's ctrl): a named value that any profile can take (ProfileTerm::kInput),
// set between steps (Data::inputs; Python sim.inputs["name"], the CLI's --inputs table).
struct ModelInput {
  std::string name;
  double default_value = 0.0;  // Data::inputs after MakeData
};

// Contact (docs/numerics.md, "Contact"; elements/contact.h): penalty normal law and regularised
// Coulomb friction between moving shapes and obstacles fixed in the world.
//
// A collision shape fixed in a rigid body's frame. Sizes in metres, node-frame components.
enum class ContactShapeType { kSphere, kCapsule, kBox, kCylinder };
template <>
struct EnumNames<ContactShapeType> {
  static constexpr std::array<EnumName<ContactShapeType>, 4> kValues = {{
      {ContactShapeType::kSphere, "sphere", "centre and radius"},
      {ContactShapeType::kCapsule, "capsule", "segment from..to and radius"},
      {ContactShapeType::kBox, "box", "centre, half sizes and orientation"},
      {ContactShapeType::kCylinder, "cylinder", "axis from..to and radius, flat ends"},
  }};
};
struct ContactShape {
  int body = -1;  // index into Model::bodies
  ContactShapeType type = ContactShapeType::kSphere;
  Vec3 from = Vec3::Zero();  // sphere and box: the centre; capsule, cylinder: one end of the axis
  Vec3 to = Vec3::Zero();    // capsule, cylinder: the other end; box: the half sizes (> 0)
  double radius = 0.0;       // sphere, capsule and cylinder (> 0); box: 0
  // Box: its edges' directions in the node frame (columns: the axes of the half sizes); a
  // rotation (Build checks it). The identity: edges along the node axes.
  Mat3 rotation = Mat3::Identity();
};
// A rod taking part in contact: a chain of capsules of `radius` around its element chords.
struct ContactRod {
  int rod = -1;
  double radius = 0.0;  // [m] > 0
};
// An obstacle fixed in the world (a plane may carry a moving surface: a conveyor, a turntable).
enum class ObstacleType { kPlane, kSphere, kCapsule, kCylinder, kBox, kMesh, kHeightfield };
template <>
struct EnumNames<ObstacleType> {
  static constexpr std::array<EnumName<ObstacleType>, 7> kValues = {{
      {ObstacleType::kPlane, "plane", "the half-space behind a point and a normal"},
      {ObstacleType::kSphere, "sphere", "a fixed sphere"},
      {ObstacleType::kCapsule, "capsule", "a fixed capsule (a cylinder with round ends)"},
      {ObstacleType::kCylinder, "cylinder", "a fixed cylinder with flat ends"},
      {ObstacleType::kBox, "box", "a fixed box: centre, half sizes and orientation"},
      {ObstacleType::kMesh, "mesh", "a fixed triangle mesh: centre, orientation and scale"},
      {ObstacleType::kHeightfield, "heightfield",
       "a fixed grid of heights, as triangles: centre, orientation and spacing"},
  }};
};
struct ContactObstacle {
  std::string name;
  ObstacleType type = ObstacleType::kPlane;
  // plane: a point of it; sphere, box: centre; capsule, cylinder: one end of the axis
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();       // plane: unit normal out of the obstacle (Build normalises)
  Vec3 to = Vec3::Zero();            // capsule, cylinder: the other end; box: the half sizes (> 0)
  double radius = 0.0;               // sphere, capsule and cylinder
  Mat3 rotation = Mat3::Identity();  // box, mesh, heightfield: its axes (columns), world
  // Mesh and heightfield (docs/numerics.md, "Triangle meshes"): the triangles in the obstacle's
  // frame (a height field's as HeightFieldMesh makes them), placed at point + rotation scale v;
  // Build makes `tree` (the world triangles and their AABB tree) from them.
  std::shared_ptr<const TriangleMesh> mesh = nullptr;
  double scale = 1.0;
  std::shared_ptr<const MeshTree> tree = nullptr;
  unsigned contype = 1, conaffinity = 1;
  // A plane's moving surface (docs/numerics.md, "Moving surfaces"): its material points move in
  // the plane at v_s(p, t) = motion(t) (velocity + spin n x (p - point)), a belt (velocity
  // [m/s], tangential) or a turntable (spin [rad/s] about the normal through `point`); the
  // shapes' slip in the friction law is relative to it. The plane itself does not move.
  Vec3 velocity = Vec3::Zero();
  double spin = 0.0;
  Profile motion = Profile::Constant(1.0);
  bool moving() const { return velocity != Vec3::Zero() || spin != 0.0; }
};
// Group bitmasks of a rod or body (MuJoCo's contype/conaffinity): a moving entity and an
// obstacle collide when (contype_1 & conaffinity_2) | (contype_2 & conaffinity_1) is non-zero.
struct ContactGroup {
  bool rod = false;  // a rod (index into Model::rods) or a rigid body (Model::bodies)
  int index = -1;
  unsigned contype = 1, conaffinity = 1;
};
// Which two contact entities (rods with contact, bodies with shapes; Model::contact_entity_pairs)
// may touch: those whose group bits match ((contype_a & conaffinity_b) | (contype_b &
// conaffinity_a) != 0) and that are not set apart (excluded, or joined by a shared node or a
// joint). Memory linear in the entities and the pairs set apart (a table of every ordered pair
// took a byte each: 100 MB for 10^4 spheres), one lookup of two entities' bits per query and
// a binary search when some pair is set apart. Filled by Build (Reset, SetGroups, SetApart,
// Finish).
class ContactEntityPairs {
 public:
  // n entities, none of which may touch another until SetGroups.
  void Reset(int n) {
    contype_.assign(static_cast<std::size_t>(n), 0u);
    conaffinity_.assign(static_cast<std::size_t>(n), 0u);
    apart_.clear();
    pairs_ = 0.0;
  }
  void SetGroups(int e, unsigned contype, unsigned conaffinity) {
    contype_[static_cast<std::size_t>(e)] = contype;
    conaffinity_[static_cast<std::size_t>(e)] = conaffinity;
  }
  // Entities a and b never touch (any order; repeats allowed).
  void SetApart(int a, int b) { apart_.push_back(Key(a < b ? a : b, a < b ? b : a)); }
  // Sorts the pairs set apart and counts the unordered pairs that may touch.
  void Finish();
  int size() const { return static_cast<int>(contype_.size()); }
  // Whether entities a != b may touch.
  bool MayTouch(int a, int b) const {
    const std::size_t ka = static_cast<std::size_t>(a), kb = static_cast<std::size_t>(b);
    if (((contype_[ka] & conaffinity_[kb]) | (contype_[kb] & conaffinity_[ka])) == 0u) return false;
    return apart_.empty() || !IsApart(a < b ? a : b, a < b ? b : a);
  }
  // The unordered pairs of two entities that may touch.
  double pairs() const { return pairs_; }
  bool any() const { return pairs_ > 0.0; }
  std::size_t bytes() const {
    return (contype_.capacity() + conaffinity_.capacity()) * sizeof(unsigned) +
           apart_.capacity() * sizeof(unsigned long long);
  }

 private:
  static unsigned long long Key(int a, int b) {
    return (static_cast<unsigned long long>(static_cast<unsigned>(a)) << 32) |
           static_cast<unsigned>(b);
  }
  bool IsApart(int a, int b) const;
  std::vector<unsigned> contype_, conaffinity_;
  std::vector<unsigned long long> apart_;  // sorted keys (a < b)
  double pairs_ = 0.0;
};
// An excluded (moving entity, obstacle) pair.
struct ContactExclusion {
  bool rod = false;
  int index = -1;
  int obstacle = -1;
};
// The contact law (docs/numerics.md, "Contact"). Negative values are defaults set by Build
// (docs/theory.md §N6.4): onset 0.01 r_min, stiffness 100 W_max / onset (W_max the largest
// weight one pair carries, with |g| = 9.81 m/s^2 when there is no gravity: the resting gap is
// 0.86 onset), slip velocity 1e-3 m/s.
// The friction law of contact (docs/numerics.md, "Stick friction"): an elastic tangential anchor
// that sticks inside the cone mu_s f_n and slips at mu_k f_n (a history variable of each pair,
// updated when a step or load step is accepted; friction in statics too), or Coulomb friction
// smoothed by a slip velocity eps_v (dynamics only; creeps at eps_v x / sqrt(1 - x^2) inside the
// cone, x the share of friction used).
enum class FrictionLaw { kStick, kSmooth };
template <>
struct EnumNames<FrictionLaw> {
  static constexpr std::array<EnumName<FrictionLaw>, 2> kValues = {{
      {FrictionLaw::kStick, "stick",
       "elastic anchor: sticks inside mu_s f_n, slips at mu_k f_n; statics and dynamics"},
      {FrictionLaw::kSmooth, "smooth", "Coulomb smoothed by the slip velocity; dynamics only"},
  }};
};
struct ContactSettings {
  double stiffness = -1.0;      // k_n [N/m]
  double onset = -1.0;          // delta [m]: the force starts at gap delta
  double damping_ratio = 1.0;   // zeta: c_n = 2 zeta sqrt(k_n m_eff)
  double friction = 0.0;        // mu (mu_k of the stick law) >= 0
  double slip_velocity = -1.0;  // eps_v [m/s] (smooth law)
  FrictionLaw friction_law = FrictionLaw::kStick;
  double static_friction = -1.0;       // mu_s >= mu_k (stick law; default: friction)
  double tangential_stiffness = -1.0;  // k_t [N/m] of the anchor (stick law; default: k_n)
  // Pairs between moving shapes (elements/shape_pair.h): rod self-contact on/off, and the arc
  // length between two elements' nearest ends below which they never collide (default 4 r).
  bool self = false;
  double self_skip = -1.0;  // [m]
  // Two entities whose node counts multiply to at most this are coupled inside the band of the
  // solver's matrix; the others by off-band blocks (docs/numerics.md, "Pairs and the band").
  int band_pair_nodes = 64;
};
// Contact materials (docs/scene-format.md, `contact.pairs`; MuJoCo's <pair>): named groups of
// contact entities (rods, bodies with shapes) and obstacles, and the law's parameters for a pair
// of groups. An entity or obstacle belongs to at most one group; pairs of entities in no group,
// or of groups without a material, take the scene's ContactSettings.
struct ContactMaterialGroup {
  std::string name;
  std::vector<int> rods, bodies, obstacles;  // members: Model::rods, bodies, obstacles indices
};
// The parameters of the law at a pair of groups (group[0] may equal group[1]). As given,
// negative values are the scene's (ContactSettings; static_friction: this pair's friction when
// it gives one, tangential_stiffness: this pair's stiffness unless the scene sets one); Build
// resolves them into Model::contact_laws, every value set.
struct ContactMaterial {
  int group[2] = {-1, -1};             // Model::contact_material_groups indices
  double friction = -1.0;              // mu_k >= 0
  double static_friction = -1.0;       // mu_s >= mu_k
  double stiffness = -1.0;             // k_n [N/m] > 0
  double damping_ratio = -1.0;         // zeta >= 0: c_n = 2 zeta sqrt(k_n m_pair)
  double tangential_stiffness = -1.0;  // k_t [N/m] > 0 of the stick law's anchor
  double onset = -1.0;                 // delta [m] > 0: the force starts at gap delta
};
// One (moving shape, obstacle) pair, made by Build: the shape is a segment p(s) = (1-s) p_0 +
// s p_1 with p_j = x_j + R_j c_j of item node j (both ends on node 0 for a rigid shape, whose
// node 1 is kGround; a sphere has p_0 = p_1), inflated by `radius`.
struct ContactPair {
  int node[2] = {kGround, kGround};
  int end_node[2] = {0, 0};  // which item node carries p_0 and p_1
  Vec3 offset[2] = {Vec3::Zero(), Vec3::Zero()};
  double radius = 0.0;
  int obstacle = -1;
  double damping = 0.0;  // c_n [N s/m] (Build: from the pair's mass)
  bool rod = false;      // the owner: a rod or a rigid body (index), for outputs
  int owner = -1;
  int material = 0;  // its law: Model::contact_laws index (Build)
  // A body's cylinder (docs/numerics.md, "Cylinders"): its radius, with the axis from
  // offset[0] to offset[1] (on node 0) and `radius` 0; else 0. Against a plane each flat end is
  // carried at three rim points (part 0..5: end part / 3, the deepest rim point and the two at
  // +-120 degrees from it); against a sphere or capsule obstacle one pair (part -1).
  double cylinder = 0.0;
  int part = -1;
};
// One side of a pair between two moving shapes (elements/shape_pair.h): a segment p(s) =
// (1-s) p_0 + s p_1 with p_j = x_j + R_j c_j of the side's item node end_node[j] (a rigid shape
// or a rod node sphere: both ends on node 0 and node 1 is kGround), inflated by `radius`.
struct ShapePairSide {
  int node[2] = {kGround, kGround};
  int end_node[2] = {0, 0};
  Vec3 offset[2] = {Vec3::Zero(), Vec3::Zero()};
  double radius = 0.0;
  bool rod = false;  // the owner: a rod or a rigid body (index), for outputs
  int owner = -1;
  int element = -1;  // a rod side: the element (index into Model::elements)
  // A box side (always side B, against a segment side: a sphere, a capsule, a rod element or
  // an edge of another box): half sizes > 0 along the columns of `rotation` (node frame),
  // centre offset[0]; zero for a segment side.
  Vec3 half = Vec3::Zero();
  Mat3 rotation = Mat3::Identity();
  // A cylinder side (always side B, against a sphere, a capsule or a rod element): its radius
  // > 0, the axis from offset[0] to offset[1] (both on node 0), `radius` 0; else 0.
  double cylinder = 0.0;
};
// A pair of moving shapes found by the broad phase (rigid-rigid, rod-rigid, rod-rod, rod
// self-contact; UpdateShapePairs, elements/shape_pair.h): the normal points from side 1 (B) to
// side 0 (A).
struct ShapePair {
  ShapePairSide side[2];
  int segment[2] = {-1, -1};  // the two Model::contact_segments (side A's shape first)
  double damping = 0.0;       // c_n [N s/m] (from the two segments' reduced mass)
  // A segment of positive length against a box is two pairs, part 0 and part 1: the lower and
  // the upper end of the segment clipped to the prism over the box face it is nearest to (the
  // two points that carry a segment lying on a face; docs/numerics.md, "Box-box"). -1: one
  // point, the segment's nearest point (every other pair).
  int part = -1;
  // Two boxes: which of the 24 edges (12 of each box against the other) this pair is; -1
  // otherwise (with the segments and part, the pair's name for the stick law's history).
  int edge = -1;
  int material = 0;  // its law: Model::contact_laws index (the broad phase, ContactLawIndex)
};
// A shape the broad phase sorts (Build): a rod element's capsule, or a body's sphere, capsule
// or box, as the side of a pair it would be.
struct ContactSegment {
  ShapePairSide side;
  double mass = 0.0;  // the element's or body's mass; INFINITY when all its nodes are fixed
  int entity = -1;    // the contact entity (a rod or a body): index of Model's entity tables
  double s0 = 0.0, s1 = 0.0;  // a rod element: its arc-length span along the rod [m]
  int material_group = -1;    // its entity's Model::contact_material_groups index, or -1
};
// An excluded pair of moving entities (scene `contact: exclude: [[a, b]]` with two bodies or rods).
struct ContactPairExclusion {
  bool rod[2] = {false, false};
  int index[2] = {-1, -1};
};

struct Model {
  std::vector<Node> nodes;
  std::vector<Rod> rods;
  std::vector<RodElement> elements;
  std::vector<RigidBody> bodies;
  std::vector<Joint> joints;
  std::vector<PointLoad> point_loads;
  std::vector<RodLoad> rod_loads;
  std::vector<Tendon> tendons;
  std::vector<TendonSegment> tendon_segments;  // of all tendons, tendon by tendon (Build)
  // The segments with both eyelets on nodes, grouped by their (ordered) node pair (Build): one
  // TendonSegmentKind item per group, so the segments of several tendons along one element are
  // one 2-node item (one scatter, one application of the node tangents).
  std::vector<TendonSegmentGroup> tendon_segment_groups;
  std::vector<int> tendon_group_segments;  // segment indices, group by group
  std::vector<ForceElement> force_elements;
  std::vector<ModelInput> inputs;
  std::vector<Actuator> actuators;
  std::vector<int> element_actuators;  // actuator indices, element by element (Build)
  // Contact (elements/contact.h): shapes and obstacles as given, the law with its defaults
  // resolved and the pairs enumerated by Build.
  std::vector<ContactShape> contact_shapes;
  std::vector<ContactRod> contact_rods;
  std::vector<ContactObstacle> obstacles;
  std::vector<ContactGroup> contact_groups;
  std::vector<ContactExclusion> contact_exclusions;
  ContactSettings contact;
  std::vector<ContactPair> contact_pairs;
  std::vector<ContactPairExclusion> contact_pair_exclusions;
  // Materials per pair of groups, as given (ModelBuilder::AddContactMaterialGroup,
  // AddContactMaterial), and as Build resolves them: contact_laws[0] the scene's settings,
  // contact_laws[1 + i] contact_materials[i] with its defaults, and the law of groups (a, b) at
  // contact_law_table[(a + 1) * (G + 1) + b + 1] (G groups; -1: no group), both orders: a
  // lookup in O(1) at assembly (ContactLawIndex).
  std::vector<ContactMaterialGroup> contact_material_groups;
  std::vector<ContactMaterial> contact_materials;
  std::vector<ContactMaterial> contact_laws;
  std::vector<int> contact_law_table;
  // Moving shapes (elements/shape_pair.h): the segments, and which two entities (rods, bodies
  // with shapes) may touch: contact_entity_pairs.MayTouch(a, b) for a != b (Build); a rod
  // touches itself when contact_entity_self_skip[a] >= 0 (the arc length between two elements'
  // nearest ends below which they do not). The pairs are found per assembly (Data).
  std::vector<ContactSegment> contact_segments;
  int num_contact_entities = 0;
  ContactEntityPairs contact_entity_pairs;
  std::vector<double> contact_entity_self_skip;
  Vec3 gravity = Vec3::Zero();  // [m/s^2], world frame
  RodInertia rod_inertia =
      RodInertia::kExact;  // option A by default (docs/numerics.md, "Rod inertia")

  // Sizes and the solver's ordering (computed by ModelBuilder::Build).
  int nv = 0;        // velocity unknowns
  int nv_nodes = 0;  // the first nv_nodes of them belong to nodes
  int nc = 0;        // multipliers
  int num_unknowns() const { return nv + nc; }
  // Global unknown index -> position in the banded system. The unknowns of one node, of one
  // joint's coordinates and of one joint's constraint rows stay consecutive (in order), so a
  // block of the iteration matrix maps to a contiguous block of the band.
  std::vector<int> permutation;
  int bandwidth = 0;  // half-bandwidth of the permuted system
  // Sparsity pattern of the permuted iteration matrix (symmetric): position i couples with
  // positions up to pattern_last[i] (the last unknown of any block adjacent to its own).
  std::vector<int> pattern_last;
  // The solver asked for (scene: analysis.linear_solver) and the one Build chose: the sparse
  // LU (Data::sparse) when sparse_solver, else the banded one (Data::matrix).
  LinearSolver linear_solver = LinearSolver::kAuto;
  bool sparse_solver = false;
  // The same pattern as dense blocks of the permuted matrix (row, rows, col, cols; every
  // block with itself and each pair of coupled blocks both ways): the sparse LU's pattern.
  std::vector<SparseLU::Block> sparse_pattern;
  // Predicted flops of one factorisation by each solver (the choice of kAuto): the banded
  // LU's from the band pattern, the sparse LU's from KLU's symbolic analysis (0 when not
  // analysed), and KLU's predicted nonzeros of L + U.
  double banded_flops = 0.0, sparse_flops = 0.0, sparse_factor_nonzeros = 0.0;
  // The banded LU's share for contact between moving shapes (kAuto's rule adds it to
  // banded_flops, weighed by kCouplingFlopCost): the nodes the pairs of moving shapes are predicted to couple off the band
  // at once (coupled_nodes: per pair of entities that may touch and are not linked in the
  // band, up to kContactRegionNodes nodes of each, at most the nodes of such entities) and the
  // flops of the Woodbury coupling per factorisation for them (k = 6 x coupled_nodes banded
  // solves and the dense LU of k x k; docs/numerics.md, "Sparse direct solve").
  int coupled_nodes = 0;
  double coupling_flops = 0.0;
  double length_scale = 1.0;  // characteristic length (bounding box diagonal) [m]

  // The rod meshes conform to the scene's features (docs/numerics.md, "Conforming rod
  // meshes"; scene: defaults.conform_mesh): Build puts a node wherever a tendon eyelet, a
  // force element's end, a concentrated rod load or an actuator's end falls between a rod's
  // nodes, splitting the element there. conformed_nodes: how many nodes Build added (after the
  // nodes the builder was given, so every NodeId handed out stays valid).
  bool conform_mesh = true;
  int conformed_nodes = 0;

  // Constraint rows found linearly dependent at build time (redundant constraints, e.g. a
  // planar loop closed with spatial revolute joints). Their multipliers are held at zero,
  // which leaves the motion unchanged; see ModelBuilder::Build.
  std::vector<int> redundant_rows;
  std::vector<std::string> warnings;  // non-fatal findings of Build, for the user

  // The memory Build() and MakeData may use [bytes] (model/memory.h; 0: the process default,
  // else half the physical memory). Build() refuses a model whose parts would exceed it.
  std::size_t memory_limit = 0;

  // Largest |rotation| one element may reach (elements/rod.h): 2 pi minus a safety margin.
  double max_element_rotation = 2.0 * 3.14159265358979323846 - 0.05;

  int FindNode(const std::string& name) const;  // -1 if absent
  int FindRod(const std::string& name) const;
  int FindBody(const std::string& name) const;
  int FindJoint(const std::string& name) const;
  int FindTendon(const std::string& name) const;
  int FindForceElement(const std::string& name) const;
  int FindInput(const std::string& name) const;
  int FindActuator(const std::string& name) const;
};

// True when two moving shapes of the model may touch (two entities allowed to, or a rod with
// itself): the broad phase has something to find and the run pairs to output.
inline bool MayHaveShapePairs(const Model& model) {
  if (model.contact_entity_pairs.any()) return true;
  for (double skip : model.contact_entity_self_skip)
    if (skip >= 0.0) return true;
  return false;
}

// The two costs LinearSolver::kAuto compares (flops of one factorisation weighed as in
// kSparseFlopCost, kCouplingFlopCost): the banded LU's with its off-band contact coupling,
// and the sparse LU's (infinite when it was not analysed: Model::sparse_flops is 0).
inline double PredictedBandedCost(const Model& model) {
  return model.banded_flops + kCouplingFlopCost * model.coupling_flops;
}
inline double PredictedSparseCost(const Model& model) {
  if (model.sparse_flops <= 0.0 && model.num_unknowns() > 0) return INFINITY;
  return kSparseFlopCost * model.sparse_flops + kSparseFixedCost * model.num_unknowns();
}

// The law (Model::contact_laws index) of a pair of contact material groups (-1: none).
inline int ContactLawIndex(const Model& model, int group_a, int group_b) {
  if (model.contact_law_table.empty()) return 0;
  const std::size_t n = model.contact_material_groups.size() + 1;
  return model.contact_law_table[static_cast<std::size_t>(group_a + 1) * n +
                                 static_cast<std::size_t>(group_b + 1)];
}

// The resolved law of a pair (Model::contact_laws[index]), or the scene's settings before Build.
inline ContactMaterial ContactLawOf(const Model& model, int index) {
  if (static_cast<std::size_t>(index) < model.contact_laws.size())
    return model.contact_laws[static_cast<std::size_t>(index)];
  const ContactSettings& c = model.contact;
  ContactMaterial out;
  out.friction = c.friction;
  out.static_friction = std::max(c.static_friction, c.friction);
  out.stiffness = c.stiffness;
  out.damping_ratio = c.damping_ratio;
  out.onset = c.onset;
  out.tangential_stiffness = c.tangential_stiffness > 0.0 ? c.tangential_stiffness : c.stiffness;
  return out;
}

// The onset delta [m] of a pair's law (Model::contact_laws[index]): the gap at which its force
// starts; the scene's contact.onset unless the pair's material gives its own.
inline double ContactOnsetOf(const Model& model, int index) {
  if (static_cast<std::size_t>(index) < model.contact_laws.size()) {
    const double onset = model.contact_laws[static_cast<std::size_t>(index)].onset;
    if (onset > 0.0) return onset;
  }
  return model.contact.onset;
}

// The largest onset of any law (the broad phase's padding).
inline double MaxContactOnset(const Model& model) {
  double onset = model.contact.onset;
  for (const ContactMaterial& law : model.contact_laws) onset = std::max(onset, law.onset);
  return onset;
}

// Whether the stick law keeps anchors (Data::contact_anchors, shape_pair_anchors): the stick
// law with friction on some pair.
inline bool KeepsContactAnchors(const Model& model) {
  if (model.contact.friction_law != FrictionLaw::kStick) return false;
  if (model.contact_laws.empty()) return model.contact.friction > 0.0;
  for (const ContactMaterial& law : model.contact_laws)
    if (law.friction > 0.0) return true;
  return false;
}

// The reference frame H_0 of a node, or the identity for kGround (the one ground-or-node
// lookup of reference frames; model/data.h has the current-frame one).
inline const SE3& NodeReferenceFrame(const Model& model, int node) {
  static const SE3 kWorld = SE3::Identity();
  return node == kGround ? kWorld : model.nodes[static_cast<std::size_t>(node)].reference;
}

}  // namespace screwfem
