// The scene reader's `robots:` section (docs/scene-format.md, "robots"; docs/urdf.md): URDF
// files whose links and joints become bodies and joints of the spec (io/urdf.h), before the
// scene's own bodies, so that joints, loads, tendons and outputs name them as
// "<robot>/<link>" and "<robot>/<joint>".
#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "scene_reader_impl.h"
#include "scene_yaml.h"
#include "screwfem/io/urdf.h"
#include "screwfem/model/errors.h"

namespace screwfem::scene_reading {

// A rotation: {quaternion: [w, x, y, z]} (unit within 1e-6, then normalised), {axis: [x, y, z],
// angle: rad} (the axis as a joint's), or {rpy: [roll, pitch, yaw]} (URDF's fixed-axis
// x-y-z angles: R = Rz(yaw) Ry(pitch) Rx(roll)).
Mat3 SceneReader::ReadOrientation(const Node& node, const std::string& path) const {
  r_.ExpectMap(node, path);
  r_.CheckKeys(node, path, {"quaternion", "axis", "angle", "rpy"});
  const Node* q = node.Find("quaternion");
  const Node* axis = node.Find("axis");
  const Node* angle = node.Find("angle");
  const Node* rpy = node.Find("rpy");
  const int forms = (q != nullptr) + (axis != nullptr || angle != nullptr) + (rpy != nullptr);
  if (forms != 1)
    r_.Fail(node.location, path,
            "give one of 'quaternion: [w, x, y, z]', 'axis' with 'angle', or 'rpy: [r, p, y]'");
  if (q != nullptr) {
    const std::string p = Join(path, "quaternion");
    const std::vector<double> v = r_.FixedNumbers(*q, p, 4);
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
    if (std::abs(n - 1.0) > 1e-6) {
      std::ostringstream s;
      s.precision(9);
      s << "expected a unit quaternion [w, x, y, z], got norm " << n;
      r_.Fail(q->location, p, s.str());
    }
    return RotationFromQuaternion(v[0], v[1], v[2], v[3]);
  }
  if (rpy != nullptr) return RotationFromRpy(r_.Vector3(*rpy, Join(path, "rpy")));
  if (axis == nullptr) r_.Fail(node.location, path, "missing key 'axis' (with 'angle')");
  if (angle == nullptr) r_.Fail(node.location, path, "missing key 'angle' (with 'axis')");
  const Vec3 u = UnitAxis(*axis, Join(path, "axis"));
  return RotationFromAxisAngle(u, r_.Number(*angle, Join(path, "angle")));
}

void SceneReader::ReadRobots(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "robots", "robot");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("robots", entry.key);
    r_.ExpectMap(value, path);
    r_.CheckKeys(value, path, {"urdf", "base", "fixed_base", "contype", "conaffinity", "joints"});
    UrdfImport import;
    import.name = entry.key;
    if (const Node* base = value.Find("base")) {
      const std::string bp = Join(path, "base");
      r_.ExpectMap(*base, bp);
      r_.CheckKeys(*base, bp, {"at", "orientation"});
      if (const Node* at = base->Find("at")) import.base_position = Point(*at, Join(bp, "at"));
      if (const Node* o = base->Find("orientation"))
        import.base_rotation = ReadOrientation(*o, Join(bp, "orientation"));
    }
    if (const Node* f = value.Find("fixed_base"))
      import.fixed_base = r_.Bool(*f, Join(path, "fixed_base"));
    ReadGroups(value, path, &import.contype, &import.conaffinity);
    // The file: relative to the scene file's directory (to the working directory for a
    // scene given as text).
    const Node& un = r_.Require(value, path, "urdf");
    const std::string up = Join(path, "urdf");
    std::filesystem::path file = r_.Text(un, up);
    if (file.empty()) r_.Fail(un.location, up, "expected a file name, got ''");
    std::error_code ec;
    const std::filesystem::path scene_file(r_.source());
    if (file.is_relative() && scene_file.has_parent_path() &&
        std::filesystem::is_regular_file(scene_file, ec))
      file = scene_file.parent_path() / file;
    UrdfAdded added;
    const std::size_t first_body = spec_.bodies.size();
    try {
      added = AppendUrdf(file.string(), import, &spec_);
    } catch (const InputError& e) {
      r_.Fail(un.location, up, e.what());
    }
    // Sources: every link and joint at the robot's name.
    for (int b = 0; b < added.bodies; ++b) {
      const std::string& name = spec_.bodies[first_body + static_cast<std::size_t>(b)].name;
      src_.bodies.push_back(
          {Field(entry.key_location, Join(path, "links." + name.substr(entry.key.size() + 1))),
           {}});
    }
    std::vector<std::string> joint_names;
    for (int j = 0; j < added.joints; ++j) {
      const std::string& name =
          spec_.joints[static_cast<std::size_t>(added.first_joint + j)].joint.name;
      joint_names.push_back(name.substr(entry.key.size() + 1));
      const FieldSource self =
          Field(entry.key_location, Join(path, "joints." + joint_names.back()));
      src_.joints.push_back({self, {{"node_a", self}, {"node_b", self}}});
    }
    // The drives, springs and initial state of the robot's joints, by URDF joint name.
    const Node* joints = value.Find("joints");
    if (joints == nullptr || joints->IsNull()) continue;
    const std::string jp = Join(path, "joints");
    r_.ExpectMap(*joints, jp);
    for (const auto& [je, jv] : joints->entries) {
      const std::string p = Join(jp, je.key);
      int index = -1;
      for (std::size_t k = 0; k < joint_names.size(); ++k)
        if (joint_names[k] == je.key) index = added.first_joint + static_cast<int>(k);
      if (index < 0)
        r_.Fail(je.key_location, p,
                "the URDF has no joint '" + je.key + "'" +
                    scene_yaml::UnknownNameHint(je.key, joint_names));
      r_.ExpectMap(jv, p);
      r_.CheckKeys(
          jv, p, {"stiffness", "damping", "rest", "drive", "initial_position", "initial_velocity"});
      JointSpec& j = spec_.joints[static_cast<std::size_t>(index)].joint;
      ReadJointSprings(jv, p, GetJointTypeInfo(j.type), j);
      EntitySource& source = src_.joints[static_cast<std::size_t>(index)];
      source.self = Field(je.key_location, p);
      source.parts = {{"node_a", source.self}, {"node_b", source.self}};
    }
  }
}

}  // namespace screwfem::scene_reading
