// The scene reader's class, shared by its three source files (internal to src/io): the file's
// core sections, bodies and joints in scene_reader.cpp; URDF robots in
// scene_reader_robots.cpp; inputs, loads, tendons, forces,
// actuation and contact in scene_reader_items.cpp; analysis and outputs in
// scene_reader_analysis.cpp. docs/architecture.md, "Scenes".
#pragma once

#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "scene_yaml.h"
#include "screwfem/io/scene_spec.h"

namespace screwfem::scene_reading {

using scene_yaml::Location;
using scene_yaml::Node;
using scene_yaml::Reader;

inline constexpr int kMaxElements = 100000;         // per rod (or per path segment)
inline constexpr long kMaxTotalElements = 1000000;  // all rods of a scene
inline constexpr double kMaxSteps = 1e9;            // time steps of one dynamic analysis

inline constexpr const char* kGroundName = "ground";

inline const std::vector<std::string> kBodyKeys = {"type",
                                                   "between",
                                                   "at",
                                                   "mass",
                                                   "inertia",
                                                   "com",
                                                   "fixed",
                                                   "free",
                                                   "from",
                                                   "to",
                                                   "path",
                                                   "section",
                                                   "elements",
                                                   "up",
                                                   "weld_start",
                                                   "weld_end",
                                                   "initial_velocity",
                                                   "contact_radius",
                                                   "visual_radius",
                                                   "shapes",
                                                   "contype",
                                                   "conaffinity"};

inline std::string Join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

inline std::string Index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

inline FieldSource Field(const Location& location, std::string field) {
  return FieldSource{location, std::move(field)};
}

class SceneReader {
 public:
  SceneReader(const std::string& source, SceneSpec* spec, SceneSources* sources)
      : r_(source), spec_(*spec), src_(*sources) {}

  void Read(const Node& root, const std::string& default_name);

 private:
  // Sections of the file.
  void ReadParameters(const Node* node);
  void ReadUnits(const Node& root);
  void ReadDefaults(const Node* node);
  void ReadPoints(const Node* node);
  void ReadMaterials(const Node* node);
  void ReadSections(const Node* node);
  void ReadInputs(const Node* node);
  void ReadRobots(const Node* node);  // scene_reader_robots.cpp
  Mat3 ReadOrientation(const Node& node, const std::string& path) const;
  void ReadBodies(const Node* node);
  void ReadRigidBody(const Node& n, const std::string& path, BodySpec& b);
  void ReadSoftBody(const Node& n, const std::string& path, BodySpec& b, EntitySource& source);
  void ReadPath(const Node& n, const std::string& path, BodySpec& b, EntitySource& source);
  int ReadWeld(const Node& n, const std::string& path, const char* key, const char* part, int self,
               EntitySource& source);
  void ReadJoints(const Node* node);
  void ReadJointSides(const Node& value, const std::string& path, JointEntrySpec& j,
                      EntitySource& source);
  void ReadJointAxes(const Node& value, const std::string& path, const JointTypeInfo& info,
                     JointSpec& j);
  void ReadJointSprings(const Node& value, const std::string& path, const JointTypeInfo& info,
                        JointSpec& j);
  void ReadLoads(const Node* node);
  void ReadLoad(const Node& value, const std::string& path, LoadSpec& load, EntitySource& source);
  void ReadTendons(const Node* node);
  void ReadForces(const Node* node);
  void ReadActuation(const Node* node);
  void ReadContact(const Node* node);
  ContactObstacle ReadObstacle(const Node& v, const std::string& path,
                               const std::string& name) const;
  void ReadMeshObstacle(const Node& v, const std::string& path, ContactObstacle& o) const;
  void ReadContactExclusions(const Node& exclude, const std::vector<std::string>& names);
  void ReadContactGroups(const Node& groups, const std::vector<std::string>& names);
  void ReadContactPairs(const Node& pairs, const std::vector<std::string>& names);
  void ReadShapes(const Node& node, const std::string& path, BodySpec& b) const;
  void ReadGroups(const Node& node, const std::string& path, unsigned* contype,
                  unsigned* conaffinity) const;
  BodyPointSpec ReadBodyPoint(const Node& node, const std::string& path) const;
  BodyPointSpec ReadRoute(const Node& node, const std::string& path) const;
  void ReadAnalysis(const Node* node);
  void ReadTimes(const Node& node, const std::string& path);
  void ReadThreads(const Node& node, const std::string& path);
  void ReadStopAtRest(const Node& node, const std::string& path);
  void ReadStepControl(const Node& node, const std::string& path);
  void ReadSolverOptions(const Node& node, const std::string& path);
  void ReadStatics(const Node& node, const std::string& path);
  void ReadOutputs(const Node* node);
  void ReadOutputPoint(const Node& value, const std::string& path, OutputPointSpec& op,
                       EntitySource& source);
  void ReadOutputJoints(const Node& jn, const std::string& path);
  void ReadRodFields(const Node& v, const std::string& path);

  // Values.
  Vec3 Point(const Node& node, const std::string& path) const;
  Vec3 UnitAxis(const Node& node, const std::string& path) const;
  Material ReadMaterial(const Node& node, const std::string& path) const;
  Mat3 ReadInertia(const Node& node, const std::string& path) const;
  Profile ReadProfile(const Node& node, const std::string& path) const;
  Profile ReadProfileTerm(const Node& node, const std::string& path) const;
  Vec6 PerCoordinate(const Node& node, const std::string& path, int k, bool non_negative) const;
  int Body(const Node& node, const std::string& path) const;  // index of a named body
  void NotUsedBy(const Node& map, const std::string& path, const std::vector<std::string>& keys,
                 const std::string& who) const;

  Reader r_;
  scene_yaml::ParameterTable parameters_;  // the `parameters:` block, in file order
  SceneSpec& spec_;
  SceneSources& src_;
  int default_elements_ = 8;
  long total_elements_ = 0;  // over all rods (kMaxTotalElements)
  Vec3 default_up_ = Vec3::UnitZ();
  std::vector<std::pair<std::string, Vec3>>& points_ = spec_.points;
  std::unordered_map<std::string, int> input_index_;  // spec_.inputs by name
  std::map<std::string, Material> materials_;
  std::map<std::string, Section> sections_;
  std::vector<std::string> material_names_, section_names_;
  std::map<std::string, double> section_radius_;  // the contact radius a section implies
  std::map<std::string, double> section_visual_;  // a section's visual_radius
};

}  // namespace screwfem::scene_reading
