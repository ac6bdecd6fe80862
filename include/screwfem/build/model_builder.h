// ModelBuilder: the compiler of a Model (docs/architecture.md). C++ and Python users and the
// scene compiler (io/) build models through it; Build() validates everything once and computes
// the layout, the solver ordering and the redundant constraint rows.
#pragma once

#include <string>
#include <vector>

#include "screwfem/elements/joint.h"
#include "screwfem/model/model.h"

namespace screwfem {

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
