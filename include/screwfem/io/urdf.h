// URDF robots (docs/urdf.md): the links and joints of a URDF file become rigid bodies and joints
// of a SceneSpec, so that a scene (the `robots:` section, docs/scene-format.md) and Python
// (SceneSpec.add_urdf) build them through the same compiler as their own bodies and joints.
#pragma once

#include <string>

#include "screwfem/io/scene_spec.h"

namespace screwfem {

// Where a URDF robot goes and what it is called in the scene.
struct UrdfImport {
  // The robot's name in the scene: its links become the bodies "<name>/<link>" and its joints
  // the joints "<name>/<joint>".
  std::string name;
  // The pose of the root link's frame in the world (the reference configuration, all joint
  // coordinates 0): position [m] and rotation (world components of the root frame's axes).
  Vec3 base_position = Vec3::Zero();
  Mat3 base_rotation = Mat3::Identity();
  // true: the root link is welded to the ground (BodySpec::fixed); false: it floats
  // (BodySpec::free).
  bool fixed_base = true;
  // Contact group bitmasks of every link (BodySpec::contype, conaffinity).
  unsigned contype = 1, conaffinity = 1;
};

// The bodies and joints a URDF robot added to a spec: [first_body, first_body + bodies) and
// [first_joint, first_joint + joints), in the file's order of <link> and <joint> elements.
struct UrdfAdded {
  int first_body = 0, bodies = 0;
  int first_joint = 0, joints = 0;
};

// Reads the URDF file at `path` (at most kMaxUrdfBytes) and appends its links to spec->bodies
// and its joints to spec->joints (docs/urdf.md, "Mapping"):
// - a link is a rigid body whose frame sits at the link's origin with world-aligned axes; its
//   mass, centre of mass and inertia (about the centre of mass, rotated into world axes) come
//   from <inertial>; its <collision> spheres, boxes and cylinders become contact shapes
//   (BodySpec::shapes, points relative to the body's origin, as the scene reader gives them;
//   a box keeps its orientation, ContactShape::rotation);
// - revolute and continuous joints become revolute joints, prismatic and fixed joints theirs,
//   at the child link's origin with the axis in world components; <dynamics damping> is the
//   joint's damping. Limits, friction, <visual> and <transmission> are not used.
// Throws InputError "FILE:LINE:COLUMN: ELEMENT: what" (the URDF file's line and column where
// known, the element as "link 'forearm'", "joint 'elbow'", "link 'hand': <collision> 0") for a
// missing or unreadable file, XML or URDF parse errors, a link without <inertial>, a mass or
// inertia that is not positive (definite), mesh collision shapes, a cylinder without a
// positive radius and length, mimic joints, planar and floating joints, and a name that is
// already in the spec.
UrdfAdded AppendUrdf(const std::string& path, const UrdfImport& import, SceneSpec* spec);

// The same, from the URDF's text; `source_name` names it in messages.
UrdfAdded AppendUrdfText(const std::string& text, const std::string& source_name,
                         const UrdfImport& import, SceneSpec* spec);

// Rotations as the scene writes them (a robot's base.orientation; docs/scene-format.md,
// "Orientations"), shared by the scene reader and Python so that both give the same bits.
// The rotation of the quaternion (w, x, y, z), normalised first.
Mat3 RotationFromQuaternion(double w, double x, double y, double z);
// The rotation by `angle` [rad] about the unit vector `axis` (right hand).
Mat3 RotationFromAxisAngle(const Vec3& axis, double angle);
// URDF's roll-pitch-yaw (fixed x, y, z axes): R = Rz(yaw) Ry(pitch) Rx(roll).
Mat3 RotationFromRpy(const Vec3& rpy);

inline constexpr std::size_t kMaxUrdfBytes = std::size_t{64} << 20;

}  // namespace screwfem
