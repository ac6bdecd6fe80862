// The compiled model (constant) and its workspace (Data); see style.md "Model and Data".
//
// Unknowns. Velocities v (size nv) stack 6 body-velocity components per free node (translation
// first) and then k joint-coordinate rates per joint. Multipliers lambda (size nc) stack the 6
// relative-frame constraints per joint (none for a free joint) and one row per prescribed
// drive. The Newton systems solve for x = [dx (nv); dmu (nc)] in a bandwidth-reducing order
// computed once at build time.
#pragma once

#include <string>
#include <vector>

#include "screwfem/lie/se3.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/profile.h"
#include "screwfem/model/section.h"
#include "screwfem/solve/banded_lu.h"

namespace screwfem {

using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Mat6X = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;

constexpr int kGround = -1;  // node index standing for the world frame

struct Node {
  std::string name;
  SE3 reference;       // initial frame H_0
  bool fixed = false;  // clamped to the world: eliminated from the unknowns
  int dof = -1;        // first velocity index, or -1 when fixed
};

// One two-node helical element (method.md §2.2).
struct RodElement {
  int rod = -1;
  int node_a = -1, node_b = -1;
  double length = 0.0;   // reference arc length L = |u(d0)|
  Vec6 d0 = Vec6::Zero();// reference relative motion log(H_A0^-1 H_B0)
};

struct Rod {
  std::string name;
  Section section;
  std::vector<int> nodes;  // num_elements + 1 node indices, in order along the rod
  int first_element = 0;
  int num_elements = 0;
  double length = 0.0;     // sum of the element lengths
};

struct RigidBody {
  std::string name;
  int node = -1;                   // the body's frame is this node's frame
  double mass = 0.0;               // [kg]
  Vec3 com = Vec3::Zero();         // centre of mass in the node frame [m]
  Mat3 inertia = Mat3::Zero();     // inertia about the centre of mass, node-frame axes [kg m^2]
};

enum class LoadFrame {
  kWorld,  // dead load: fixed direction in the world
  kBody,   // follower load: fixed in the node frame
};

// A force and a moment applied at a point of a node frame, scaled by a profile.
struct PointLoad {
  int node = -1;
  Vec3 point = Vec3::Zero();   // application point in the node frame [m]
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
  double arc_length = 0.0;     // concentrated loads [m]
  LoadFrame frame = LoadFrame::kWorld;
  Vec3 force = Vec3::Zero();   // [N/m] distributed, [N] concentrated
  Vec3 moment = Vec3::Zero();  // [N m/m] distributed, [N m] concentrated
  Profile profile = Profile::Constant(1.0);
  // Filled by Build for concentrated loads: the element carrying the section and xi in it.
  int element = -1;
  double xi = 0.0;
};

enum class JointType {
  kRevolute, kPrismatic, kHelical, kCylindrical, kSpherical, kPlanar, kUniversal, kFixed,
  kFree,
};

enum class DriveKind {
  kNone,           // passive joint
  kPrescribed,     // rheonomic constraint alpha_i = q(t) on one coordinate (method.md §4.4)
  kSeriesElastic,  // spring/damper towards q(t) on one coordinate (method.md §4.5)
  kForce,          // generalised force f(t) on one coordinate
};

// A joint: relative frame H_J in a subgroup between frame A (node a, or the ground) and frame
// B (node b), placed by the constant offsets C_A, C_B (method.md §4.1): H_B C_B = H_A C_A H_J.
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
  int drive_coord = 0;     // which coordinate (0..k-1)
  int drive_row = -1;      // multiplier row of a prescribed drive
  Profile drive_profile;   // q(t) [m or rad], or the force/torque f(t)
  // Coordinates (unknowns) of the joint: the columns of A_J. A free joint has none: its
  // relative motion is that of its two frames, with no constraint rows (see num_springs).
  int k() const { return static_cast<int>(basis.cols()); }
  // Springs and dampers the joint can carry: one per coordinate, and six on a free joint,
  // acting on delta = log(C_A^-1 H_A^-1 H_B C_B) (docs/numerics.md, "Free joints").
  int num_springs() const { return type == JointType::kFree ? 6 : k(); }
};

enum class RodInertia {
  kExact,     // option A: exact helical velocity field, M(d), 3-point Gauss (method.md §2.5)
  kConstant,  // option B: linear velocity interpolation, constant mass matrix
};

struct Model {
  std::vector<Node> nodes;
  std::vector<Rod> rods;
  std::vector<RodElement> elements;
  std::vector<RigidBody> bodies;
  std::vector<Joint> joints;
  std::vector<PointLoad> point_loads;
  std::vector<RodLoad> rod_loads;
  Vec3 gravity = Vec3::Zero();  // [m/s^2], world frame
  RodInertia rod_inertia = RodInertia::kExact;  // option A by default (method.md §2.5)

  // Sizes and the solver's ordering (computed by ModelBuilder::Build).
  int nv = 0;            // velocity unknowns
  int nv_nodes = 0;      // the first nv_nodes of them belong to nodes
  int nc = 0;            // multipliers
  int num_unknowns() const { return nv + nc; }
  // Global unknown index -> position in the banded system. The unknowns of one node, of one
  // joint's coordinates and of one joint's constraint rows stay consecutive (in order), so a
  // block of the iteration matrix maps to a contiguous block of the band.
  std::vector<int> permutation;
  int bandwidth = 0;             // half-bandwidth of the permuted system
  // Sparsity pattern of the permuted iteration matrix (symmetric): position i couples with
  // positions up to pattern_last[i] (the last unknown of any block adjacent to its own).
  std::vector<int> pattern_last;
  double length_scale = 1.0;     // characteristic length (bounding box diagonal) [m]

  // Constraint rows found linearly dependent at build time (redundant constraints, e.g. a
  // planar loop closed with spatial revolute joints). Their multipliers are held at zero,
  // which leaves the motion unchanged; see ModelBuilder::Build.
  std::vector<int> redundant_rows;
  std::vector<std::string> warnings;  // non-fatal findings of Build, for the user

  // Largest |rotation| one element may reach (method.md §2.7): 2 pi minus a safety margin.
  double max_element_rotation = 2.0 * 3.14159265358979323846 - 0.05;

  int FindNode(const std::string& name) const;  // -1 if absent
  int FindRod(const std::string& name) const;
  int FindBody(const std::string& name) const;
  int FindJoint(const std::string& name) const;
};

// Builds a Model through a small C++ API; Build() validates everything and computes the layout.
class ModelBuilder {
 public:
  // A node with a frame. Names must be unique when given.
  int AddNode(const SE3& frame, std::string name = {});
  void FixNode(int node);
  // A straight rod from p0 to p1 with n elements. Node frames have x along the rod and z as
  // close as possible to `up` (any vector not parallel to the rod). Optional existing end
  // nodes are shared (their positions must coincide with p0/p1; the rod is then rigidly joined
  // there).
  int AddStraightRod(std::string name, const Vec3& p0, const Vec3& p1, int num_elements,
                     const Section& section, const Vec3& up = Vec3::UnitZ(), int start_node = -1,
                     int end_node = -1);
  // A straight rod of given length along the x axis of `root` (root.R gives all node frames).
  int AddStraightRodFromFrame(std::string name, const SE3& root, double length, int num_elements,
                              const Section& section, int start_node = -1, int end_node = -1);
  // A rod through existing nodes (curved references allowed: element references are
  // log(H_a^-1 H_b) of the nodes' reference frames).
  int AddRodThroughNodes(std::string name, const std::vector<int>& nodes, const Section& section);
  int AddRigidBody(std::string name, int node, double mass, const Vec3& com, const Mat3& inertia);
  int AddJoint(const Joint& joint);  // offsets, basis and names filled by the caller
  // A joint at world point `point` with world axis `axis` (plane normal for planar joints;
  // `axis2` is the second axis of a universal joint), between node_a and node_b (either may be
  // kGround). The joint frame is world-aligned in the reference configuration, so H_J = I and
  // the coordinates are 0 there (method.md §4.2). Returns the joint index; edit
  // model().joints[i] to add stiffness, damping or a drive.
  int AddJointAt(std::string name, JointType type, int node_a, int node_b, const Vec3& point,
                 const Vec3& axis = Vec3::UnitZ(), const Vec3& axis2 = Vec3::Zero(),
                 double pitch = 0.0);
  int AddPointLoad(const PointLoad& load);
  int AddRodLoad(const RodLoad& load);
  void SetGravity(const Vec3& g);
  Model& model() { return model_; }

  // Validates and computes sizes and the ordering. Throws InputError.
  Model Build() const;

 private:
  Model model_;
};

// Joint basis A_J of each joint type (method.md §4.2), for axis e (unit) and pitch p. For a
// planar joint e is the plane normal; for universal joints e is the first axis and e2 the
// second. Returns 6 x k (6 x 0 for fixed and free joints: neither has coordinates).
Mat6X JointBasis(JointType type, const Vec3& e, const Vec3& e2 = Vec3::Zero(), double pitch = 0.0);
const char* JointTypeName(JointType type);

// Gradient of a joint's six relative-frame constraints phi_J (method.md §4.3) with respect to
// the right-trivialised variations of node A, node B and the joint coordinates:
//   B_A = -T^-1(phi) Ad(C_B^-1 H_B^-1 H_A),   B_B = T^-1(phi) Ad(C_B^-1),
//   B_J = -T^-1(-phi) A = -(T^-1(phi) - ad(phi)) A.
// H_A, H_B are the node frames (identity for the ground), phi the constraint value,
// Tinv = T^-1(phi) and A the joint's current basis (6 x k). Outputs may be null. The assembly
// and the redundancy check of Build use this one function.
void CalcJointGradient(const Joint& joint, const SE3& H_A, const SE3& H_B, const Vec6& phi,
                       const Mat6& Tinv, const Mat6X& A, Mat6* B_A, Mat6* B_B, Mat6X* B_J);
// Rotation whose x axis is `axis` (normalised) and whose z axis is as close as possible to
// `up`; when `up` is parallel to `axis`, the world axis least aligned with `axis` stands in.
// The section-frame convention of rods (AddStraightRod, scene paths).
Mat3 FrameAlong(const Vec3& axis, const Vec3& up);

// Redundant constraint rows at the reference configuration (called by ModelBuilder::Build on
// a model whose layout is set): fills model.redundant_rows and adds a warning naming the
// joints involved. The joint graph (nodes with unknowns, and one vertex for the ground and
// every fixed node; an edge per joint with constraint rows) is split into a spanning forest
// and chords. The rows of tree joints are independent (each has an invertible block on its
// child node), so only chord rows and drive rows can be redundant: they are reduced onto the
// coordinates of the tree joints between the chord's ends and their lowest common ancestor
// (the common ancestor's rigid motion drops out exactly), and each group of reduced rows that
// share coordinates is rank-revealed with a column-pivoting QR (relative threshold 1e-10).
// Cost: linear in the joints for trees; for loops, the tree paths walked plus one dense QR
// per group. Scenes whose loops exceed kMaxRedundancyWork skip the check with a warning.
void FindRedundantConstraints(Model& model);
// Work bound of FindRedundantConstraints: tree-path steps (a few microseconds each) plus the
// dense QRs' operation counts / 1000; about 2 s at the bound.
inline constexpr double kMaxRedundancyWork = 1e6;

// ------------------------------------------------------------------------------------------
// Data: the state and every workspace of one simulation, allocated once from a Model.
struct Data {
  double time = 0.0;
  std::vector<SE3> H;              // node frames
  std::vector<SE3> HJ;             // joint relative frames H_J
  Eigen::VectorXd q_joint;         // joint coordinates (nv - nv_nodes); exact for abelian joints
  Eigen::VectorXd v, vdot;         // velocities and accelerations (nv)
  Eigen::VectorXd lambda;          // multipliers (nc)
  std::vector<Vec3> w_ref;         // per rod element: rotation vector on the current branch

  // Workspaces of the Newton solvers.
  Eigen::VectorXd residual;        // global order, size nv + nc
  Eigen::VectorXd rhs;             // permuted order
  Eigen::VectorXd increment;       // global order, size nv + nc
  std::vector<Mat6> node_tangent;  // T(h dq_i) per node for the dynamic iteration matrix
  BandedLU matrix;                 // permuted, banded iteration matrix

  // Diagnostics of the last assembly.
  double force_scale = 0.0;        // largest generalised-force term that entered the residual
  double term_scale = 0.0;         // largest term cancelling inside one (e.g. K d/L in sigma)
  int failed_element = -1;         // element whose rotation left the admissible range
  double failed_rotation = 0.0;
};

// Allocates Data for a model and sets the reference state (at rest).
Data MakeData(const Model& model);

}  // namespace screwfem
