// The scene reader (docs/architecture.md, "Scenes"): YAML text -> document tree (scene_yaml.cpp)
// -> overrides -> a SceneSpec and the source of each entity (scene_spec.h). It checks what the
// text alone decides (keys, types, ranges, names); the compiler (scene_compiler.cpp) checks what
// needs the model's geometry. Every message names the file, line, column and field.
#include <Eigen/Cholesky>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <unordered_map>

#include "scene_yaml.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

using scene_yaml::Location;
using scene_yaml::Node;
using scene_yaml::Reader;

// Maps of named entries: an override may not walk through an entry that does not exist.
const std::vector<std::string> kCollections = {"points",         "materials", "sections", "bodies",
                                               "joints",         "loads",     "tendons",  "forces",
                                               "outputs.points", "inputs",    "actuation"};

constexpr int kMaxElements = 100000;         // per rod (or per path segment)
constexpr long kMaxTotalElements = 1000000;  // all rods of a scene
constexpr double kMaxSteps = 1e9;            // time steps of one dynamic analysis

const char* const kGroundName = "ground";

const std::vector<std::string> kBodyKeys = {"type",
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

std::string Join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string Index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

FieldSource Field(const Location& location, std::string field) {
  return FieldSource{location, std::move(field)};
}

class SceneReader {
 public:
  SceneReader(const std::string& source, SceneSpec* spec, SceneSources* sources)
      : r_(source), spec_(*spec), src_(*sources) {}

  void Read(const Node& root, const std::string& default_name);

 private:
  // Sections of the file.
  void ReadUnits(const Node& root);
  void ReadDefaults(const Node* node);
  void ReadPoints(const Node* node);
  void ReadMaterials(const Node* node);
  void ReadSections(const Node* node);
  void ReadInputs(const Node* node);
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
  void ReadShapes(const Node& node, const std::string& path, BodySpec& b) const;
  void ReadGroups(const Node& node, const std::string& path, unsigned* contype,
                  unsigned* conaffinity) const;
  BodyPointSpec ReadBodyPoint(const Node& node, const std::string& path) const;
  void ReadAnalysis(const Node* node);
  void ReadTimes(const Node& node, const std::string& path);
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

// --- values ------------------------------------------------------------------------------------

Vec3 SceneReader::Point(const Node& node, const std::string& path) const {
  if (node.IsScalar()) {
    for (const auto& [name, p] : points_)
      if (name == node.scalar) return p;
    std::vector<std::string> names;
    for (const auto& np : points_) names.push_back(np.first);
    r_.Fail(node.location, path,
            "undefined point '" + node.scalar + "'" + scene_yaml::DidYouMean(node.scalar, names));
  }
  if (node.IsSequence()) return r_.Vector3(node, path);
  r_.Fail(node.location, path,
          "expected a point name or [x, y, z], got " + scene_yaml::Describe(node));
}

Vec3 SceneReader::UnitAxis(const Node& node, const std::string& path) const {
  Vec3 a;
  if (node.IsMap()) {
    // {from: A, to: B}: the unit vector from point A to point B.
    r_.CheckKeys(node, path, {"from", "to"});
    a = Point(r_.Require(node, path, "to"), Join(path, "to")) -
        Point(r_.Require(node, path, "from"), Join(path, "from"));
    if (!(a.norm() > 0.0)) r_.Fail(node.location, path, "'from' and 'to' coincide: no direction");
    return a.normalized();
  }
  if (!node.IsSequence())
    r_.Fail(node.location, path,
            "expected a unit vector [x, y, z] or {from: POINT, to: POINT}, got " +
                scene_yaml::Describe(node));
  a = r_.Vector3(node, path);
  const double n = a.norm();
  if (!(n > 0.0)) r_.Fail(node.location, path, "the axis is zero");
  if (std::abs(n - 1.0) > 1e-6) {
    std::ostringstream s;
    s.precision(9);
    s << "expected a unit vector, got length " << n
      << " (write it normalised, or as {from: POINT, to: POINT})";
    r_.Fail(node.location, path, s.str());
  }
  return a / n;
}

Material SceneReader::ReadMaterial(const Node& node, const std::string& path) const {
  if (node.IsScalar()) {
    const auto it = materials_.find(node.scalar);
    if (it == materials_.end())
      r_.Fail(node.location, path,
              "undefined material '" + node.scalar + "'" +
                  scene_yaml::DidYouMean(node.scalar, material_names_));
    return it->second;
  }
  r_.CheckKeys(node, path, {"E", "G", "nu", "density", "shear_coefficient"});
  Material m;
  m.youngs_modulus = r_.PositiveNumber(r_.Require(node, path, "E"), Join(path, "E"));
  const Node* G = node.Find("G");
  const Node* nu = node.Find("nu");
  if (G != nullptr && nu != nullptr)
    r_.Fail(nu->location, Join(path, "nu"), "give either G or nu, not both");
  if (G == nullptr && nu == nullptr) r_.Fail(node.location, path, "missing key 'G' (or 'nu')");
  if (G != nullptr) {
    m.shear_modulus = r_.PositiveNumber(*G, Join(path, "G"));
  } else {
    m.poisson_ratio = r_.Number(*nu, Join(path, "nu"));
    if (!(m.poisson_ratio > -1.0 && m.poisson_ratio <= 0.5))
      r_.Fail(nu->location, Join(path, "nu"), "expected a Poisson ratio in (-1, 0.5]");
  }
  m.density = r_.NonNegativeNumber(r_.Require(node, path, "density"), Join(path, "density"));
  if (const Node* k = node.Find("shear_coefficient"))
    m.shear_coefficient = r_.PositiveNumber(*k, Join(path, "shear_coefficient"));
  return m;
}

Profile SceneReader::ReadProfile(const Node& node, const std::string& path) const {
  if (node.IsScalar()) return Profile::Constant(r_.Number(node, path));
  r_.ExpectMap(node, path);
  if (const Node* sum = node.Find("sum")) {
    r_.CheckKeys(node, path, {"sum"});
    const std::string p = Join(path, "sum");
    if (!sum->IsSequence() || sum->items.empty())
      r_.Fail(sum->location, p,
              "expected a non-empty list of profiles, got " + scene_yaml::Describe(*sum));
    Profile total;
    for (std::size_t i = 0; i < sum->items.size(); ++i)
      total.Add(ReadProfile(sum->items[i], p + "[" + std::to_string(i) + "]"));
    return total;
  }
  return ReadProfileTerm(node, path);
}

Profile SceneReader::ReadProfileTerm(const Node& node, const std::string& path) const {
  r_.CheckKeys(
      node, path,
      {"type", "value", "scale", "t0", "t1", "frequency", "phase", "times", "values", "name"});
  const std::string type = r_.Choice(
      r_.Require(node, path, "type"), Join(path, "type"),
      {"constant", "ramp", "bang_bang", "s_curve", "smooth_step", "sine", "table", "input"});
  const Node* value = node.Find("value");
  const Node* scale = node.Find("scale");
  if (value != nullptr && scale != nullptr)
    r_.Fail(scale->location, Join(path, "scale"), "give either value or scale, not both");
  double s = 1.0;
  if (value != nullptr) s = r_.Number(*value, Join(path, "value"));
  if (scale != nullptr) s = r_.Number(*scale, Join(path, "scale"));
  auto number = [&](const char* key, double fallback) {
    const Node* n = node.Find(key);
    return n == nullptr ? fallback : r_.Number(*n, Join(path, key));
  };
  const std::string who = type + " profiles";
  if (type != "input") NotUsedBy(node, path, {"name"}, who);
  if (type == "input") {
    // scale * (the run-time input `name`, declared in the scene's inputs section).
    NotUsedBy(node, path, {"t0", "t1", "frequency", "phase", "times", "values"}, who);
    const Node& nn = r_.Require(node, path, "name");
    const std::string name = r_.Text(nn, Join(path, "name"));
    // By name in constant time: a scene of 1e5 inputs and profiles took 12.6 s to check.
    const auto found = input_index_.find(name);
    if (found != input_index_.end()) return Profile::Input(found->second, s);
    std::vector<std::string> names;
    for (const auto& input : spec_.inputs) names.push_back(input.first);
    r_.Fail(nn.location, Join(path, "name"),
            "unknown input '" + name + "'" +
                (names.empty() ? std::string(" (the scene declares no inputs: add an inputs: "
                                             "section, e.g. inputs: {" +
                                             name + ": 0.0})")
                               : scene_yaml::UnknownNameHint(name, names)));
  }
  if (type == "constant") {
    NotUsedBy(node, path, {"t0", "t1", "frequency", "phase", "times", "values"}, who);
    return Profile::Constant(s);
  }
  if (type == "sine") {
    NotUsedBy(node, path, {"t1", "times", "values"}, who);
    const double f =
        r_.NonNegativeNumber(r_.Require(node, path, "frequency"), Join(path, "frequency"));
    return Profile::Sine(s, f, number("phase", 0.0), number("t0", 0.0));
  }
  if (type == "table") {
    NotUsedBy(node, path, {"t0", "t1", "frequency", "phase"}, who);
    const Node& tn = r_.Require(node, path, "times");
    const Node& vn = r_.Require(node, path, "values");
    const std::vector<double> times = r_.Numbers(tn, Join(path, "times"));
    const std::vector<double> values = r_.Numbers(vn, Join(path, "values"));
    if (times.size() < 2) r_.Fail(tn.location, Join(path, "times"), "expected at least two times");
    if (values.size() != times.size())
      r_.Fail(vn.location, Join(path, "values"),
              "expected " + std::to_string(times.size()) + " values (one per time), got " +
                  std::to_string(values.size()));
    for (std::size_t i = 1; i < times.size(); ++i)
      if (!(times[i] > times[i - 1]))
        r_.Fail(tn.items[i].location, Join(path, "times") + "[" + std::to_string(i) + "]",
                "times must be strictly increasing");
    return Profile::Table(times, values, s);
  }
  // Windowed laws: 0 before t0, the full value after t1.
  NotUsedBy(node, path, {"frequency", "phase", "times", "values"}, who);
  const double t0 = number("t0", 0.0);
  const Node& t1n = r_.Require(node, path, "t1");
  const double t1 = r_.Number(t1n, Join(path, "t1"));
  if (!(t1 > t0)) r_.Fail(t1n.location, Join(path, "t1"), "expected t1 > t0");
  if (type == "ramp") return Profile::Ramp(t0, t1, s);
  if (type == "smooth_step") return Profile::SmoothStep(t0, t1, s);
  return Profile::BangBang(t0, t1, s);  // bang_bang and its alias s_curve
}

Vec6 SceneReader::PerCoordinate(const Node& node, const std::string& path, int k,
                                bool non_negative) const {
  Vec6 v = Vec6::Zero();
  if (node.IsScalar()) {
    const double x = non_negative ? r_.NonNegativeNumber(node, path) : r_.Number(node, path);
    v.head(k).setConstant(x);
    return v;
  }
  const std::vector<double> list = r_.FixedNumbers(node, path, static_cast<std::size_t>(k));
  for (int i = 0; i < k; ++i) {
    v(i) = list[static_cast<std::size_t>(i)];
    if (non_negative && !(v(i) >= 0.0))
      r_.Fail(node.items[static_cast<std::size_t>(i)].location,
              path + "[" + std::to_string(i) + "]", "expected a non-negative number");
  }
  return v;
}

void SceneReader::NotUsedBy(const Node& map, const std::string& path,
                            const std::vector<std::string>& keys, const std::string& who) const {
  for (const auto& [entry, value] : map.entries)
    if (std::find(keys.begin(), keys.end(), entry.key) != keys.end())
      r_.Fail(entry.key_location, Join(path, entry.key),
              "'" + entry.key + "' is not used by " + who);
}

// --- sections of the file ----------------------------------------------------------------------

void SceneReader::ReadUnits(const Node& root) {
  const Node* units = root.Find("units");
  if (units == nullptr) return;
  if (!units->IsScalar() || units->scalar != "SI")
    r_.Fail(units->location, "units",
            "only SI units are supported (m, kg, s, N, rad), got " + scene_yaml::Describe(*units));
}

void SceneReader::ReadDefaults(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckKeys(*node, "defaults", {"elements", "up"});
  if (const Node* e = node->Find("elements"))
    default_elements_ = r_.Integer(*e, "defaults.elements", 1, kMaxElements);
  if (const Node* up = node->Find("up")) {
    default_up_ = r_.Vector3(*up, "defaults.up");
    if (!(default_up_.norm() > 0.0)) r_.Fail(up->location, "defaults.up", "the vector is zero");
  }
}

void SceneReader::ReadPoints(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "points", "point");
  for (const auto& [entry, value] : node->entries)
    points_.emplace_back(entry.key, r_.Vector3(value, Join("points", entry.key)));
}

void SceneReader::ReadMaterials(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "materials", "material");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("materials", entry.key);
    r_.ExpectMap(value, path);
    materials_[entry.key] = ReadMaterial(value, path);
    material_names_.push_back(entry.key);
  }
}

void SceneReader::ReadSections(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "sections", "section");
  for (const auto& [entry, value_binding] : node->entries) {
    const Node& value = value_binding;  // a variable the lambdas below can capture (Clang 14)
    const std::string path = Join("sections", entry.key);
    r_.CheckKeys(
        value, path,
        {"stiffness", "inertia", "damping", "rayleigh_mass", "rayleigh_stiffness", "shape",
         "material", "radius", "width", "height", "outer_radius", "inner_radius", "visual_radius"});
    Section s;
    if (const Node* v = value.Find("visual_radius"))
      section_visual_[entry.key] = r_.PositiveNumber(*v, Join(path, "visual_radius"));
    if (const Node* shape = value.Find("shape")) {
      NotUsedBy(value, path, {"stiffness", "inertia"}, "sections given by shape and material");
      const std::string kind =
          r_.Choice(*shape, Join(path, "shape"), {"circle", "rectangle", "tube"});
      const Material m = ReadMaterial(r_.Require(value, path, "material"), Join(path, "material"));
      auto positive = [&](const char* key) {
        return r_.PositiveNumber(r_.Require(value, path, key), Join(path, key));
      };
      if (kind == "circle") {
        NotUsedBy(value, path, {"width", "height", "outer_radius", "inner_radius"}, "circles");
        const double radius = positive("radius");
        s = Section::Circle(radius, m);
        section_radius_[entry.key] = radius;
      } else if (kind == "rectangle") {
        NotUsedBy(value, path, {"radius", "outer_radius", "inner_radius"}, "rectangles");
        const double width = positive("width"), height = positive("height");
        s = Section::Rectangle(width, height, m);
        section_radius_[entry.key] = 0.5 * std::min(width, height);
      } else {
        NotUsedBy(value, path, {"radius", "width", "height"}, "tubes");
        const double ro = positive("outer_radius");
        const Node& in = r_.Require(value, path, "inner_radius");
        const double ri = r_.NonNegativeNumber(in, Join(path, "inner_radius"));
        if (!(ri < ro))
          r_.Fail(in.location, Join(path, "inner_radius"), "expected inner_radius < outer_radius");
        s = Section::Tube(ro, ri, m);
        section_radius_[entry.key] = ro;
      }
    } else {
      NotUsedBy(value, path,
                {"material", "radius", "width", "height", "outer_radius", "inner_radius"},
                "sections given by stiffness (add 'shape')");
      const Node& kn = r_.Require(value, path, "stiffness");
      s.stiffness = r_.Vector6(kn, Join(path, "stiffness"));
      for (int i = 0; i < 6; ++i)
        if (!(s.stiffness(i) > 0.0))
          r_.Fail(kn.items[static_cast<std::size_t>(i)].location,
                  Join(path, "stiffness") + "[" + std::to_string(i) + "]",
                  "stiffness entries must be positive");
      if (const Node* in = value.Find("inertia")) {
        s.inertia = r_.Vector6(*in, Join(path, "inertia"));
        for (int i = 0; i < 6; ++i)
          if (!(s.inertia(i) >= 0.0))
            r_.Fail(in->items[static_cast<std::size_t>(i)].location,
                    Join(path, "inertia") + "[" + std::to_string(i) + "]",
                    "inertia entries must be non-negative");
      }
    }
    if (const Node* d = value.Find("damping")) {
      s.damping = r_.Vector6(*d, Join(path, "damping"));
      for (int i = 0; i < 6; ++i)
        if (!(s.damping(i) >= 0.0))
          r_.Fail(d->items[static_cast<std::size_t>(i)].location,
                  Join(path, "damping") + "[" + std::to_string(i) + "]",
                  "damping entries must be non-negative");
    }
    if (const Node* a = value.Find("rayleigh_mass"))
      s.rayleigh_mass = r_.NonNegativeNumber(*a, Join(path, "rayleigh_mass"));
    if (const Node* a = value.Find("rayleigh_stiffness"))
      s.rayleigh_stiffness = r_.NonNegativeNumber(*a, Join(path, "rayleigh_stiffness"));
    sections_[entry.key] = s;
    section_names_.push_back(entry.key);
  }
}

int SceneReader::Body(const Node& node, const std::string& path) const {
  const std::string name = r_.Text(node, path);
  for (std::size_t b = 0; b < spec_.bodies.size(); ++b)
    if (spec_.bodies[b].name == name) return static_cast<int>(b);
  std::vector<std::string> names;
  for (const BodySpec& b : spec_.bodies) names.push_back(b.name);
  r_.Fail(node.location, path,
          "undefined body '" + name + "'" + scene_yaml::DidYouMean(name, names));
}

void SceneReader::ReadBodies(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "bodies", "body");
  // Names and types first: welds, joints and loads refer to bodies by name.
  std::vector<const Node*> values;
  for (const auto& [entry, value] : node->entries) {
    BodySpec b;
    b.name = entry.key;
    const std::string path = Join("bodies", entry.key);
    if (b.name == kGroundName)
      r_.Fail(entry.key_location, path, "'ground' is reserved for the world frame");
    r_.ExpectMap(value, path);
    const std::string type =
        r_.Choice(r_.Require(value, path, "type"), Join(path, "type"), {"rigid", "soft", "rod"});
    b.rigid = type == "rigid";
    spec_.bodies.push_back(b);
    src_.bodies.push_back({Field(entry.key_location, path), {}});
    values.push_back(&value);
  }
  // Then each body in file order (node and rod numbering follows the file).
  for (std::size_t i = 0; i < values.size(); ++i) {
    BodySpec& b = spec_.bodies[i];
    EntitySource& source = src_.bodies[i];
    if (b.rigid)
      ReadRigidBody(*values[i], source.self.field, b);
    else
      ReadSoftBody(*values[i], source.self.field, b, source);
  }
}

void SceneReader::ReadRigidBody(const Node& n, const std::string& path, BodySpec& b) {
  r_.CheckKeys(n, path, kBodyKeys);
  NotUsedBy(n, path, {"from", "to", "path", "section", "elements", "up", "weld_start", "weld_end"},
            "rigid bodies");
  const Node* between = n.Find("between");
  const Node* at = n.Find("at");
  if (between != nullptr && at != nullptr)
    r_.Fail(at->location, Join(path, "at"), "give either 'between' (two points) or 'at', not both");
  if (between == nullptr && at == nullptr)
    r_.Fail(n.location, path, "missing key 'between' (two points) or 'at' (one point)");
  Vec3& com_world = b.com;
  if (between != nullptr) {
    const std::string p = Join(path, "between");
    if (!between->IsSequence() || between->items.size() != 2)
      r_.Fail(between->location, p,
              "expected two points [A, B], got " + scene_yaml::Describe(*between));
    const Vec3 a = Point(between->items[0], p + "[0]");
    const Vec3 c = Point(between->items[1], p + "[1]");
    if (!((c - a).norm() > 0.0))
      r_.Fail(between->location, p, "the two points coincide (zero-length body; use 'at')");
    b.origin = a;
    com_world = 0.5 * (a + c);
  } else {
    b.origin = Point(*at, Join(path, "at"));
    com_world = b.origin;
  }
  if (const Node* com = n.Find("com")) com_world = Point(*com, Join(path, "com"));
  NotUsedBy(n, path, {"contact_radius"}, "rigid bodies (they carry 'shapes')");
  NotUsedBy(n, path, {"visual_radius"}, "rigid bodies (they are drawn as their 'shapes')");
  if (const Node* sh = n.Find("shapes")) ReadShapes(*sh, Join(path, "shapes"), b);
  ReadGroups(n, path, &b.contype, &b.conaffinity);
  b.mass = r_.PositiveNumber(r_.Require(n, path, "mass"), Join(path, "mass"));
  b.inertia = ReadInertia(r_.Require(n, path, "inertia"), Join(path, "inertia"));
  if (const Node* f = n.Find("fixed")) b.fixed = r_.Bool(*f, Join(path, "fixed"));
  if (const Node* f = n.Find("free")) b.free = r_.Bool(*f, Join(path, "free"));
  if (b.fixed && b.free)
    r_.Fail(n.Find("free")->location, Join(path, "free"), "a body cannot be both fixed and free");
  if (const Node* iv = n.Find("initial_velocity")) {
    // {linear: [vx, vy, vz] (centre of mass, m/s), angular: [wx, wy, wz] (rad/s)}, world.
    const std::string p = Join(path, "initial_velocity");
    r_.CheckKeys(*iv, p, {"linear", "angular"});
    if (b.fixed) r_.Fail(iv->location, p, "a fixed body cannot have an initial velocity");
    b.has_initial_velocity = true;
    if (const Node* v = iv->Find("linear")) b.initial_linear = r_.Vector3(*v, Join(p, "linear"));
    if (const Node* w = iv->Find("angular")) b.initial_angular = r_.Vector3(*w, Join(p, "angular"));
  }
}

// A 3x3 matrix, nine numbers, or three principal moments; symmetric positive definite.
Mat3 SceneReader::ReadInertia(const Node& in, const std::string& ip) const {
  Mat3 J = Mat3::Zero();
  if (in.IsSequence() && in.items.size() == 3 && in.items[0].IsSequence()) {
    for (int i = 0; i < 3; ++i) {
      const Vec3 row =
          r_.Vector3(in.items[static_cast<std::size_t>(i)], ip + "[" + std::to_string(i) + "]");
      J.row(i) = row.transpose();
    }
  } else if (in.IsSequence() && in.items.size() == 9) {
    const std::vector<double> v = r_.Numbers(in, ip);
    for (int i = 0; i < 9; ++i) J(i / 3, i % 3) = v[static_cast<std::size_t>(i)];
  } else if (in.IsSequence() && in.items.size() == 3) {
    const Vec3 d = r_.Vector3(in, ip);
    for (int i = 0; i < 3; ++i)
      if (!(d(i) > 0.0))
        r_.Fail(in.items[static_cast<std::size_t>(i)].location, ip + "[" + std::to_string(i) + "]",
                "principal moments of inertia must be positive");
    J = d.asDiagonal();
  } else {
    r_.Fail(in.location, ip,
            "expected 3 principal moments [Jxx, Jyy, Jzz] or a 3x3 matrix, got " +
                (in.IsSequence() ? "a list of " + std::to_string(in.items.size())
                                 : scene_yaml::Describe(in)));
  }
  if ((J - J.transpose()).norm() > 1e-12 * std::max(1e-300, J.norm()))
    r_.Fail(in.location, ip, "the inertia matrix must be symmetric");
  if (Eigen::LLT<Mat3>(J).info() != Eigen::Success || !(J.determinant() > 0.0))
    r_.Fail(in.location, ip, "the inertia matrix must be positive definite");
  return J;
}

void SceneReader::ReadSoftBody(const Node& n, const std::string& path, BodySpec& b,
                               EntitySource& source) {
  r_.CheckKeys(n, path, kBodyKeys);
  NotUsedBy(n, path, {"between", "at", "mass", "inertia", "com", "fixed", "initial_velocity"},
            "soft bodies (a soft body is clamped to the ground by a fixed joint)");
  const Node& sn = r_.Require(n, path, "section");
  const std::string section_name = r_.Text(sn, Join(path, "section"));
  const auto sec = sections_.find(section_name);
  if (sec == sections_.end())
    r_.Fail(sn.location, Join(path, "section"),
            "undefined section '" + section_name + "'" +
                scene_yaml::DidYouMean(section_name, section_names_));
  b.section = sec->second;
  b.elements = default_elements_;
  if (const Node* e = n.Find("elements"))
    b.elements = r_.Integer(*e, Join(path, "elements"), 1, kMaxElements);
  b.up = default_up_;
  if (const Node* u = n.Find("up")) {
    b.up = r_.Vector3(*u, Join(path, "up"));
    if (!(b.up.norm() > 0.0)) r_.Fail(u->location, Join(path, "up"), "the vector is zero");
  }
  if (const Node* f = n.Find("free")) b.free = r_.Bool(*f, Join(path, "free"));
  ReadPath(n, path, b, source);
  total_elements_ += static_cast<long>(b.elements) * static_cast<long>(b.path.size() - 1);
  if (total_elements_ > kMaxTotalElements)
    r_.Fail(n.Find("elements") != nullptr ? n.Find("elements")->location : n.location, path,
            "the scene's rods have more than " + std::to_string(kMaxTotalElements) +
                " elements in all (the limit)");
  const int self = static_cast<int>(&b - spec_.bodies.data());
  b.weld_start = ReadWeld(n, path, "weld_start", "start_node", self, source);
  b.weld_end = ReadWeld(n, path, "weld_end", "end_node", self, source);
  NotUsedBy(n, path, {"shapes"}, "soft bodies (a rod's contact shape is its capsule chain)");
  if (const auto r = section_radius_.find(section_name); r != section_radius_.end())
    b.contact_radius = r->second;
  if (const Node* c = n.Find("contact_radius"))
    b.contact_radius = r_.PositiveNumber(*c, Join(path, "contact_radius"));
  if (const auto v = section_visual_.find(section_name); v != section_visual_.end())
    b.visual_radius = v->second;
  if (const Node* v = n.Find("visual_radius"))
    b.visual_radius = r_.PositiveNumber(*v, Join(path, "visual_radius"));
  ReadGroups(n, path, &b.contype, &b.conaffinity);
}

// The polyline: from/to (one straight segment) or path (several); the source of each point is
// the part "path[i]".
void SceneReader::ReadPath(const Node& n, const std::string& path, BodySpec& b,
                           EntitySource& source) {
  const Node* from = n.Find("from");
  const Node* to = n.Find("to");
  const Node* poly = n.Find("path");
  if (poly != nullptr && (from != nullptr || to != nullptr))
    r_.Fail(poly->location, Join(path, "path"), "give either 'from' and 'to', or 'path', not both");
  auto add = [&](const Node& point, const std::string& field) {
    source.parts.emplace_back(Index("path", b.path.size()), Field(point.location, field));
    b.path.push_back(Point(point, field));
  };
  if (poly != nullptr) {
    const std::string p = Join(path, "path");
    if (!poly->IsSequence() || poly->items.size() < 2)
      r_.Fail(poly->location, p,
              "expected a list of at least two points, got " + scene_yaml::Describe(*poly));
    for (std::size_t i = 0; i < poly->items.size(); ++i) add(poly->items[i], Index(p, i));
    return;
  }
  if (from == nullptr) r_.Fail(n.location, path, "missing key 'from' (or 'path')");
  if (to == nullptr) r_.Fail(n.location, path, "missing key 'to'");
  add(*from, Join(path, "from"));
  add(*to, Join(path, "to"));
}

// A weld: the end node is shared with an earlier soft body (a rigid clamp without extra
// unknowns). Returns the body index, -1 without the key.
int SceneReader::ReadWeld(const Node& n, const std::string& path, const char* key, const char* part,
                          int self, EntitySource& source) {
  const Node* w = n.Find(key);
  if (w == nullptr) return -1;
  const std::string wp = Join(path, key);
  const int other = Body(*w, wp);
  if (other == self) r_.Fail(w->location, wp, "a soft body cannot be welded to itself");
  const BodySpec& o = spec_.bodies[static_cast<std::size_t>(other)];
  if (o.rigid || other > self)
    r_.Fail(w->location, wp,
            "'" + o.name +
                "' must be a soft body defined earlier in the file (to weld to a "
                "rigid body, use a joint of type fixed)");
  source.parts.emplace_back(part, Field(w->location, wp));
  return other;
}

void SceneReader::ReadJoints(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "joints", "joint");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("joints", entry.key);
    src_.joints.push_back({Field(entry.key_location, path), {}});
    EntitySource& source = src_.joints.back();
    r_.CheckKeys(value, path,
                 {"type", "at", "between", "axis", "axis2", "pitch", "stiffness", "damping", "rest",
                  "drive", "initial_position", "initial_velocity"});
    const std::string type_name =
        r_.Choice(r_.Require(value, path, "type"), Join(path, "type"), JointTypeNameList());
    const JointTypeInfo& info = *FindJointType(type_name);
    JointEntrySpec entry_spec;
    JointSpec& j = entry_spec.joint;
    j.name = entry.key;
    j.type = info.type;
    j.point = Point(r_.Require(value, path, "at"), Join(path, "at"));
    ReadJointSides(value, path, entry_spec, source);
    ReadJointAxes(value, path, info, j);
    ReadJointSprings(value, path, info, j);
    spec_.joints.push_back(entry_spec);
  }
}

// between: [A, B], ground or body names; their sources are the parts node_a and node_b.
void SceneReader::ReadJointSides(const Node& value, const std::string& path, JointEntrySpec& j,
                                 EntitySource& source) {
  const Node& bn = r_.Require(value, path, "between");
  const std::string bp = Join(path, "between");
  if (!bn.IsSequence() || bn.items.size() != 2)
    r_.Fail(bn.location, bp,
            "expected two sides [A, B] (ground or body names), got " + scene_yaml::Describe(bn));
  int* sides[2] = {&j.body_a, &j.body_b};
  for (std::size_t s = 0; s < 2; ++s) {
    const Node& sn = bn.items[s];
    const std::string sp = Index(bp, s);
    source.parts.emplace_back(s == 0 ? "node_a" : "node_b", Field(sn.location, sp));
    if (r_.Text(sn, sp) != kGroundName) *sides[s] = Body(sn, sp);
  }
  if (j.body_a < 0 && j.body_b < 0) r_.Fail(bn.location, bp, "both sides are the ground");
  if (j.body_a == j.body_b)
    r_.Fail(bn.location, bp,
            "both sides are the same body '" +
                spec_.bodies[static_cast<std::size_t>(j.body_a)].name + "'");
}

void SceneReader::ReadJointAxes(const Node& value, const std::string& path,
                                const JointTypeInfo& info, JointSpec& j) {
  const std::string who = std::string(info.name) + " joints";
  if (info.uses_axis) {
    j.axis = UnitAxis(r_.Require(value, path, "axis"), Join(path, "axis"));
  } else {
    NotUsedBy(value, path, {"axis"}, who);
  }
  if (info.uses_axis2) {
    const Node& a2 = r_.Require(value, path, "axis2");
    j.axis2 = UnitAxis(a2, Join(path, "axis2"));
    if (std::abs(j.axis.dot(j.axis2)) > 1e-6)
      r_.Fail(a2.location, Join(path, "axis2"), "must be orthogonal to 'axis'");
    j.axis2 = (j.axis2 - j.axis.dot(j.axis2) * j.axis).normalized();
  } else {
    NotUsedBy(value, path, {"axis2"}, who);
  }
  if (info.uses_pitch) {
    j.pitch = r_.Number(r_.Require(value, path, "pitch"), Join(path, "pitch"));
  } else {
    NotUsedBy(value, path, {"pitch"}, who);
  }
}

// Springs, dampers, drive (elements/joint.h).
void SceneReader::ReadJointSprings(const Node& value, const std::string& path,
                                   const JointTypeInfo& info, JointSpec& j) {
  const std::string who = std::string(info.name) + " joints";
  const int k = info.dof;
  const int springs =
      info.spring_law == JointSpringLaw::kRelativeMotion ? 6 : k;  // JointSpringCount
  if (springs == 0) NotUsedBy(value, path, {"stiffness", "damping", "rest", "drive"}, who);
  if (!info.global_coordinates)
    NotUsedBy(value, path, {"rest", "drive"}, who + " (no global coordinates)");
  if (const Node* s = value.Find("stiffness"))
    j.stiffness = PerCoordinate(*s, Join(path, "stiffness"), springs, true);
  if (const Node* d = value.Find("damping"))
    j.damping = PerCoordinate(*d, Join(path, "damping"), springs, true);
  if (const Node* rest = value.Find("rest"))
    j.rest = PerCoordinate(*rest, Join(path, "rest"), k, false);
  if (k == 0) NotUsedBy(value, path, {"initial_position", "initial_velocity"}, who);
  if (!info.global_coordinates) NotUsedBy(value, path, {"initial_position"}, who);
  if (const Node* q0 = value.Find("initial_position")) {
    j.has_initial_coordinate = true;
    j.initial_coordinate = PerCoordinate(*q0, Join(path, "initial_position"), k, false);
  }
  if (const Node* qd0 = value.Find("initial_velocity")) {
    j.has_initial_rate = true;
    j.initial_rate = PerCoordinate(*qd0, Join(path, "initial_velocity"), k, false);
  }
  const Node* drive = value.Find("drive");
  if (drive == nullptr) return;
  const std::string dp = Join(path, "drive");
  r_.CheckKeys(*drive, dp, {"type", "coordinate", "profile"});
  std::vector<std::string> kinds = EnumNameList<DriveKind>();
  kinds.erase(kinds.begin());  // "none": a passive joint has no `drive` key
  j.drive =
      *EnumFromName<DriveKind>(r_.Choice(r_.Require(*drive, dp, "type"), Join(dp, "type"), kinds));
  if (const Node* c = drive->Find("coordinate"))
    j.drive_coordinate = r_.Integer(*c, Join(dp, "coordinate"), 0, k - 1);
  j.drive_profile = ReadProfile(r_.Require(*drive, dp, "profile"), Join(dp, "profile"));
  if (j.drive == DriveKind::kSeriesElastic && !(j.stiffness(j.drive_coordinate) > 0.0))
    r_.Fail(drive->location, dp,
            "a series_elastic drive needs a positive stiffness on coordinate " +
                std::to_string(j.drive_coordinate) + " (the spring it drives)");
}

// inputs: {NAME: DEFAULT, ...}: the run-time inputs that profiles take ({type: input, name}).
void SceneReader::ReadInputs(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "inputs", "input");
  for (const auto& [entry, value] : node->entries) {
    input_index_.emplace(entry.key, static_cast<int>(spec_.inputs.size()));
    spec_.inputs.emplace_back(entry.key, r_.Number(value, Join("inputs", entry.key)));
  }
}

void SceneReader::ReadLoads(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "loads", "load");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("loads", entry.key);
    src_.loads.push_back({Field(entry.key_location, path), {}});
    spec_.loads.emplace_back();
    spec_.loads.back().name = entry.key;
    ReadLoad(value, path, spec_.loads.back(), src_.loads.back());
  }
}

void SceneReader::ReadLoad(const Node& value, const std::string& path, LoadSpec& load,
                           EntitySource& source) {
  r_.CheckKeys(value, path,
               {"body", "at", "s", "distributed", "force", "moment", "frame", "profile"});
  load.body = Body(r_.Require(value, path, "body"), Join(path, "body"));
  const bool rigid = spec_.bodies[static_cast<std::size_t>(load.body)].rigid;
  const Node* f = value.Find("force");
  const Node* m = value.Find("moment");
  if (f == nullptr && m == nullptr)
    r_.Fail(value.location, path, "missing key 'force' (or 'moment')");
  if (f != nullptr) load.force = r_.Vector3(*f, Join(path, "force"));
  if (m != nullptr) load.moment = r_.Vector3(*m, Join(path, "moment"));
  if (const Node* fr = value.Find("frame"))
    load.frame = r_.Enum<LoadFrame>(*fr, Join(path, "frame"));
  if (const Node* p = value.Find("profile")) load.profile = ReadProfile(*p, Join(path, "profile"));

  // Where: a point of a rigid body, a rod node, a rod section at arc length s, or the
  // whole rod (per unit length).
  const Node* at = value.Find("at");
  const Node* s = value.Find("s");
  bool distributed = false;
  if (const Node* d = value.Find("distributed"))
    distributed = r_.Bool(*d, Join(path, "distributed"));
  const int given = (at != nullptr) + (s != nullptr) + (distributed ? 1 : 0);
  if (given > 1) r_.Fail(value.location, path, "give one of 'at', 's' or 'distributed: true'");
  if (rigid && (s != nullptr || distributed))
    r_.Fail(value.location, path, "'s' and 'distributed' apply to soft bodies only");
  if (given == 0)
    r_.Fail(value.location, path,
            rigid ? "missing key 'at'" : "missing key 'at' (or 's', or 'distributed: true')");
  if (at != nullptr) {
    load.where = LoadSpec::Where::kAt;
    load.at = Point(*at, Join(path, "at"));
    source.parts.emplace_back("at", Field(at->location, Join(path, "at")));
  } else if (s != nullptr) {
    load.where = LoadSpec::Where::kArcLength;
    load.arc_length = r_.NonNegativeNumber(*s, Join(path, "s"));
    source.parts.emplace_back("s", Field(s->location, Join(path, "s")));
  } else {
    load.where = LoadSpec::Where::kDistributed;
  }
}

// {body: NAME or ground, at: POINT} or, on a soft body, {body, s: ARC_LENGTH, offset: [x, y, z]}
// (the node at `at` or at arc length s, and the offset in its section frame).
BodyPointSpec SceneReader::ReadBodyPoint(const Node& node, const std::string& path) const {
  r_.ExpectMap(node, path);
  r_.CheckKeys(node, path, {"body", "at", "s", "offset"});
  BodyPointSpec p;
  const Node* body = node.Find("body");
  if (body != nullptr && r_.Text(*body, Join(path, "body")) != kGroundName)
    p.body = Body(*body, Join(path, "body"));
  const bool soft = p.body >= 0 && !spec_.bodies[static_cast<std::size_t>(p.body)].rigid;
  const Node* at = node.Find("at");
  const Node* s = node.Find("s");
  if (!soft) {
    const std::string who = p.body < 0 ? "the ground" : "rigid bodies";
    NotUsedBy(node, path, {"s", "offset"}, who + " (give the point itself as 'at')");
    p.at = Point(r_.Require(node, path, "at"), Join(path, "at"));
    return p;
  }
  if (at != nullptr && s != nullptr)
    r_.Fail(node.location, path, "give either 'at' or 's', not both");
  if (at == nullptr && s == nullptr)
    r_.Fail(node.location, path, "missing key 's' (or 'at'): the rod node the point is fixed to");
  if (at != nullptr) p.at = Point(*at, Join(path, "at"));
  if (s != nullptr) {
    p.along_rod = true;
    p.arc_length = r_.NonNegativeNumber(*s, Join(path, "s"));
  }
  if (const Node* o = node.Find("offset")) p.offset = r_.Vector3(*o, Join(path, "offset"));
  return p;
}

void SceneReader::ReadTendons(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "tendons", "tendon");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("tendons", entry.key);
    src_.tendons.push_back({Field(entry.key_location, path), {}});
    EntitySource& source = src_.tendons.back();
    r_.ExpectMap(value, path);
    r_.CheckKeys(value, path, {"eyelets", "tension", "length"});
    TendonSpec t;
    t.name = entry.key;
    const Node& en = r_.Require(value, path, "eyelets");
    const std::string ep = Join(path, "eyelets");
    if (!en.IsSequence() || en.items.size() < 2)
      r_.Fail(en.location, ep,
              "expected a list of at least two eyelets (a tendon runs between them), got " +
                  scene_yaml::Describe(en));
    for (std::size_t i = 0; i < en.items.size(); ++i) {
      source.parts.emplace_back(Index("eyelets", i), Field(en.items[i].location, Index(ep, i)));
      t.eyelets.push_back(ReadBodyPoint(en.items[i], Index(ep, i)));
    }
    // Drawn by tension or by length (a rheonomic constraint whose multiplier is the tension).
    const Node* ln = value.Find("length");
    if (ln != nullptr && value.Find("tension") != nullptr)
      r_.Fail(ln->location, Join(path, "length"),
              "give either 'tension' or 'length' (the tendon is drawn by one of them), not both");
    if (ln != nullptr) {
      t.by_length = true;
      t.length = ReadProfile(*ln, Join(path, "length"));
      source.parts.emplace_back("length", Field(ln->location, Join(path, "length")));
    } else {
      const Node& tn = r_.Require(value, path, "tension");
      t.tension = ReadProfile(tn, Join(path, "tension"));
      source.parts.emplace_back("tension", Field(tn.location, Join(path, "tension")));
    }
    spec_.tendons.push_back(std::move(t));
  }
}

void SceneReader::ReadForces(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "forces", "force element");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("forces", entry.key);
    src_.forces.push_back({Field(entry.key_location, path), {}});
    EntitySource& source = src_.forces.back();
    r_.ExpectMap(value, path);
    r_.CheckKeys(value, path, {"a", "b", "stiffness", "damping", "rest_length", "force"});
    ForceSpec f;
    f.name = entry.key;
    for (const char* end : {"a", "b"}) {
      const Node& en = r_.Require(value, path, end);
      source.parts.emplace_back(end, Field(en.location, Join(path, end)));
      (end[0] == 'a' ? f.a : f.b) = ReadBodyPoint(en, Join(path, end));
    }
    if (const Node* k = value.Find("stiffness"))
      f.stiffness = r_.NonNegativeNumber(*k, Join(path, "stiffness"));
    if (const Node* c = value.Find("damping"))
      f.damping = r_.NonNegativeNumber(*c, Join(path, "damping"));
    if (const Node* l = value.Find("rest_length"))
      f.rest_length = r_.NonNegativeNumber(*l, Join(path, "rest_length"));
    if (const Node* p = value.Find("force")) f.actuator = ReadProfile(*p, Join(path, "force"));
    if (value.Find("stiffness") == nullptr && value.Find("damping") == nullptr &&
        value.Find("force") == nullptr)
      r_.Fail(value.location, path, "missing key 'stiffness' (or 'damping', or 'force')");
    spec_.forces.push_back(std::move(f));
  }
}

// actuation: {NAME: {type, rod, from, to, ...}} (docs/numerics.md, "Active stress and rest strain"; docs/scene-format.md).
void SceneReader::ReadActuation(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "actuation", "actuator");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("actuation", entry.key);
    src_.actuators.push_back({Field(entry.key_location, path), {}});
    EntitySource& source = src_.actuators.back();
    r_.ExpectMap(value, path);
    r_.CheckKeys(value, path,
                 {"type", "rod", "from", "to", "area", "offset", "pressure", "max_stress",
                  "activation", "vector", "profile"});
    ActuatorSpec a;
    a.name = entry.key;
    a.type = r_.Enum<ActuatorType>(r_.Require(value, path, "type"), Join(path, "type"));
    const Node& rod = r_.Require(value, path, "rod");
    a.body = Body(rod, Join(path, "rod"));
    if (spec_.bodies[static_cast<std::size_t>(a.body)].rigid)
      r_.Fail(rod.location, Join(path, "rod"),
              "'" + spec_.bodies[static_cast<std::size_t>(a.body)].name +
                  "' is a rigid body; actuation acts on soft bodies (rods)");
    source.parts.emplace_back("rod", Field(rod.location, Join(path, "rod")));
    for (const char* key : {"from", "to"}) {
      if (const Node* v = value.Find(key)) {
        (key[0] == 'f' ? a.from : a.to) = r_.NonNegativeNumber(*v, Join(path, key));
        source.parts.emplace_back(key, Field(v->location, Join(path, key)));
      }
    }
    if (a.to >= 0.0 && !(a.to > a.from))
      r_.Fail(value.Find("to")->location, Join(path, "to"),
              "expected an arc length greater than 'from' (" + std::to_string(a.from) + " m)");
    const bool chamber = a.type == ActuatorType::kPressure || a.type == ActuatorType::kMuscle;
    const char* profile_key = a.type == ActuatorType::kPressure ? "pressure"
                              : a.type == ActuatorType::kMuscle ? "activation"
                                                                : "profile";
    const std::string who = std::string("type '") + NameOf(a.type) + "'";
    if (chamber) {
      NotUsedBy(value, path, {"vector", "profile"}, who);
      if (a.type == ActuatorType::kPressure)
        NotUsedBy(value, path, {"max_stress", "activation"}, who);
      else
        NotUsedBy(value, path, {"pressure"}, who);
      const Node& area = r_.Require(value, path, "area");
      a.area = r_.PositiveNumber(area, Join(path, "area"));
      source.parts.emplace_back("area", Field(area.location, Join(path, "area")));
      const Node& off = r_.Require(value, path, "offset");
      const std::vector<double> o = r_.Numbers(off, Join(path, "offset"));
      if (o.size() != 2 && o.size() != 3)
        r_.Fail(off.location, Join(path, "offset"),
                "expected [r2, r3] (or [0, r2, r3]) in the section frame [m], got " +
                    std::to_string(o.size()) + " numbers");
      a.offset = o.size() == 2 ? Vec3(0.0, o[0], o[1]) : Vec3(o[0], o[1], o[2]);
      source.parts.emplace_back("offset", Field(off.location, Join(path, "offset")));
      if (a.type == ActuatorType::kMuscle)
        a.max_stress =
            r_.NonNegativeNumber(r_.Require(value, path, "max_stress"), Join(path, "max_stress"));
      a.profile = ReadProfile(r_.Require(value, path, profile_key), Join(path, profile_key));
    } else {
      NotUsedBy(value, path, {"area", "offset", "pressure", "max_stress", "activation"}, who);
      a.vector = r_.Vector6(r_.Require(value, path, "vector"), Join(path, "vector"));
      if (const Node* p = value.Find("profile")) a.profile = ReadProfile(*p, Join(path, "profile"));
    }
    spec_.actuators.push_back(std::move(a));
  }
}

// --- contact -----------------------------------------------------------------------------------

void SceneReader::ReadGroups(const Node& n, const std::string& path, unsigned* contype,
                             unsigned* conaffinity) const {
  if (const Node* c = n.Find("contype"))
    *contype = static_cast<unsigned>(r_.Integer(*c, Join(path, "contype"), 0, 1 << 30));
  if (const Node* c = n.Find("conaffinity"))
    *conaffinity = static_cast<unsigned>(r_.Integer(*c, Join(path, "conaffinity"), 0, 1 << 30));
}

void SceneReader::ReadShapes(const Node& node, const std::string& path, BodySpec& b) const {
  if (!node.IsSequence())
    r_.Fail(node.location, path, "expected a list of shapes, got " + scene_yaml::Describe(node));
  for (std::size_t i = 0; i < node.items.size(); ++i) {
    const Node& v = node.items[i];
    const std::string sp = Index(path, i);
    r_.ExpectMap(v, sp);
    r_.CheckKeys(v, sp, {"type", "center", "from", "to", "radius", "half_sizes"});
    ContactShape shape;
    shape.type = r_.Enum<ContactShapeType>(r_.Require(v, sp, "type"), Join(sp, "type"));
    auto point = [&](const char* key) -> Vec3 {
      const Vec3 world = Point(r_.Require(v, sp, key), Join(sp, key));
      return Vec3(world - b.origin);
    };
    if (shape.type == ContactShapeType::kCapsule) {
      NotUsedBy(v, sp, {"center", "half_sizes"}, "capsules");
      shape.from = point("from");
      shape.to = point("to");
    } else {
      NotUsedBy(v, sp, {"from", "to"}, "spheres and boxes");
      shape.from = shape.to = point("center");
    }
    if (shape.type == ContactShapeType::kBox) {
      NotUsedBy(v, sp, {"radius"}, "boxes");
      const Node& hn = r_.Require(v, sp, "half_sizes");
      shape.to = r_.Vector3(hn, Join(sp, "half_sizes"));
      if (!(shape.to.minCoeff() > 0.0))
        r_.Fail(hn.location, Join(sp, "half_sizes"), "expected positive half sizes");
    } else {
      NotUsedBy(v, sp, {"half_sizes"}, "spheres and capsules");
      shape.radius = r_.PositiveNumber(r_.Require(v, sp, "radius"), Join(sp, "radius"));
    }
    b.shapes.push_back(shape);
  }
}

void SceneReader::ReadContact(const Node* node) {
  // The bodies' shapes and groups are read with the bodies.
  if (node == nullptr) return;
  const std::string path = "contact";
  r_.ExpectMap(*node, path);
  r_.CheckKeys(*node, path,
               {"stiffness", "onset", "damping_ratio", "friction", "slip_velocity", "obstacles",
                "exclude", "self", "self_skip"});
  ContactSpec& c = spec_.contact;
  c.present = true;
  if (const Node* v = node->Find("stiffness"))
    c.settings.stiffness = r_.PositiveNumber(*v, Join(path, "stiffness"));
  if (const Node* v = node->Find("onset"))
    c.settings.onset = r_.PositiveNumber(*v, Join(path, "onset"));
  if (const Node* v = node->Find("damping_ratio"))
    c.settings.damping_ratio = r_.NonNegativeNumber(*v, Join(path, "damping_ratio"));
  if (const Node* v = node->Find("friction"))
    c.settings.friction = r_.NonNegativeNumber(*v, Join(path, "friction"));
  if (const Node* v = node->Find("slip_velocity"))
    c.settings.slip_velocity = r_.PositiveNumber(*v, Join(path, "slip_velocity"));
  if (const Node* v = node->Find("self")) c.settings.self = r_.Bool(*v, Join(path, "self"));
  if (const Node* v = node->Find("self_skip"))
    c.settings.self_skip = r_.PositiveNumber(*v, Join(path, "self_skip"));
  std::vector<std::string> names;
  if (const Node* on = node->Find("obstacles")) {
    const std::string op = Join(path, "obstacles");
    r_.CheckNames(*on, op, "obstacle");
    for (const auto& [entry, v] : on->entries) {
      const std::string p = Join(op, entry.key);
      r_.ExpectMap(v, p);
      r_.CheckKeys(
          v, p,
          {"type", "point", "normal", "center", "from", "to", "radius", "contype", "conaffinity"});
      ContactObstacle o;
      o.name = entry.key;
      o.type = r_.Enum<ObstacleType>(r_.Require(v, p, "type"), Join(p, "type"));
      if (o.type == ObstacleType::kPlane) {
        NotUsedBy(v, p, {"center", "from", "to", "radius"}, "planes");
        o.point = Point(r_.Require(v, p, "point"), Join(p, "point"));
        o.normal = UnitAxis(r_.Require(v, p, "normal"), Join(p, "normal"));
      } else {
        o.radius = r_.PositiveNumber(r_.Require(v, p, "radius"), Join(p, "radius"));
        NotUsedBy(v, p, {"point", "normal"}, "spheres and capsules");
        if (o.type == ObstacleType::kSphere) {
          NotUsedBy(v, p, {"from", "to"}, "spheres");
          o.point = Point(r_.Require(v, p, "center"), Join(p, "center"));
        } else {
          NotUsedBy(v, p, {"center"}, "capsules");
          o.point = Point(r_.Require(v, p, "from"), Join(p, "from"));
          o.to = Point(r_.Require(v, p, "to"), Join(p, "to"));
        }
      }
      ReadGroups(v, p, &o.contype, &o.conaffinity);
      c.obstacles.push_back(o);
      names.push_back(entry.key);
    }
  }
  if (const Node* en = node->Find("exclude")) {
    const std::string ep = Join(path, "exclude");
    if (!en->IsSequence())
      r_.Fail(en->location, ep, "expected a list of [body, obstacle] or [body, body] pairs");
    for (std::size_t i = 0; i < en->items.size(); ++i) {
      const Node& pair = en->items[i];
      const std::string pp = Index(ep, i);
      if (!pair.IsSequence() || pair.items.size() != 2)
        r_.Fail(pair.location, pp,
                "expected [body, obstacle] or [body, body], got " + scene_yaml::Describe(pair));
      const int body = Body(pair.items[0], Index(pp, 0));
      const std::string other = r_.Text(pair.items[1], Index(pp, 1));
      const auto it = std::find(names.begin(), names.end(), other);
      if (it != names.end()) {
        c.exclude.emplace_back(body, static_cast<int>(it - names.begin()));
        continue;
      }
      // Not an obstacle: a second body (a pair of moving bodies that never touch).
      std::vector<std::string> known = names;
      int second = -1;
      for (std::size_t b = 0; b < spec_.bodies.size(); ++b) {
        known.push_back(spec_.bodies[b].name);
        if (spec_.bodies[b].name == other) second = static_cast<int>(b);
      }
      if (second < 0)
        r_.Fail(pair.items[1].location, Index(pp, 1),
                "undefined obstacle '" + other + "' (nor a body)" +
                    scene_yaml::DidYouMean(other, known));
      if (second == body)
        r_.Fail(pair.items[1].location, Index(pp, 1),
                "a body cannot be excluded from itself (rod self-contact: 'self: false')");
      c.exclude_bodies.emplace_back(body, second);
    }
  }
}

void SceneReader::ReadAnalysis(const Node* node) {
  AnalysisSettings* a = &spec_.analysis;
  if (node == nullptr || node->IsNull()) return;
  const std::string path = "analysis";
  r_.CheckKeys(*node, path,
               {"type",
                "start_time",
                "end_time",
                "step",
                "rho_inf",
                "tolerances",
                "max_iterations",
                "max_halvings",
                "align_steps",
                "static_preload",
                "load_steps",
                "rod_inertia",
                "newton",
                "predictor",
                "convergence",
                "restart_at_breakpoints",
                "perturbed_start",
                "constraints",
                "tolerance",
                "min_step",
                "max_step",
                "initial_step",
                "statics"});
  if (const Node* t = node->Find("type")) a->kind = r_.Enum<AnalysisKind>(*t, Join(path, "type"));
  ReadTimes(*node, path);
  ReadSolverOptions(*node, path);
  if (const Node* t = node->Find("statics")) ReadStatics(*t, Join(path, "statics"));
  if (const Node* t = node->Find("align_steps"))
    a->align_steps = r_.Bool(*t, Join(path, "align_steps"));
  if (const Node* t = node->Find("restart_at_breakpoints"))
    a->dynamic.restart_at_breakpoints = r_.Bool(*t, Join(path, "restart_at_breakpoints"));
  if (const Node* t = node->Find("perturbed_start"))
    a->dynamic.perturbed_start = r_.Bool(*t, Join(path, "perturbed_start"));
  if (const Node* t = node->Find("constraints"))
    a->dynamic.constraints = r_.Enum<ConstraintFormulation>(*t, Join(path, "constraints"));
  if (const Node* t = node->Find("static_preload"))
    a->static_preload = r_.Bool(*t, Join(path, "static_preload"));
  if (const Node* t = node->Find("rod_inertia"))
    spec_.rod_inertia = r_.Enum<RodInertia>(*t, Join(path, "rod_inertia"));
  // analysis.statics.time follows from the kind; the compiler sets it (SceneSpec::analysis).
}

// start_time, end_time, step: a time grid that a dynamic analysis can step through.
void SceneReader::ReadTimes(const Node& node, const std::string& path) {
  AnalysisSettings* a = &spec_.analysis;
  auto find = [&](const char* key) { return node.Find(key); };
  if (const Node* t = find("start_time")) a->start_time = r_.Number(*t, Join(path, "start_time"));
  if (const Node* t = find("end_time")) {
    a->end_time = r_.Number(*t, Join(path, "end_time"));
    if (!(a->end_time > a->start_time))
      r_.Fail(t->location, Join(path, "end_time"), "expected end_time > start_time");
  } else if (!(a->end_time > a->start_time)) {
    r_.Fail(node.location, path, "start_time must be before end_time (default 1 s)");
  }
  const Node* step = find("step");
  if (step != nullptr && step->IsScalar() && !step->quoted && step->scalar == "auto")
    ReadStepControl(node, path);
  else if (step != nullptr)
    a->step = r_.PositiveNumber(*step, Join(path, "step"));
  if (!a->adaptive_steps)
    for (const char* key : {"tolerance", "min_step", "max_step", "initial_step"})
      if (const Node* t = find(key))
        r_.Fail(t->location, Join(path, key),
                "applies only to 'step: auto' (error-controlled steps)");
  if (a->kind != AnalysisKind::kDynamic) return;
  if ((a->end_time - a->start_time) / a->step > kMaxSteps)
    r_.Fail(find("step") != nullptr ? find("step")->location : node.location, Join(path, "step"),
            "more than 1e9 time steps from start_time to end_time");
  // Times so large that their doubles are coarser than the step (schedule.h).
  const std::string problem = TimeGridProblem(a->start_time, a->end_time, a->step);
  if (!problem.empty()) {
    const char* key = std::abs(a->start_time) > std::abs(a->end_time) ? "start_time" : "end_time";
    const Node* at = find(key) != nullptr      ? find(key)
                     : find("step") != nullptr ? find("step")
                                               : &node;
    r_.Fail(at->location, Join(path, key), problem);
  }
}

// step: auto: tolerance (required; a number for both, or {absolute, relative}), min_step,
// max_step, initial_step (DynamicOptions). analysis.step becomes the first step.
void SceneReader::ReadStepControl(const Node& node, const std::string& path) {
  AnalysisSettings* a = &spec_.analysis;
  DynamicOptions& d = a->dynamic;
  a->adaptive_steps = true;
  const Node* tol = node.Find("tolerance");
  if (tol == nullptr)
    r_.Fail(
        node.Find("step")->location, Join(path, "step"),
        "'step: auto' requires analysis.tolerance (a number, or {absolute: .., relative: ..}: "
        "the local error per step, translations relative to the model's size, rotations in rad)");
  const std::string tp = Join(path, "tolerance");
  if (tol->IsMap()) {
    r_.CheckKeys(*tol, tp, {"absolute", "relative"});
    if (const Node* v = tol->Find("absolute"))
      d.absolute_tolerance = r_.PositiveNumber(*v, Join(tp, "absolute"));
    if (const Node* v = tol->Find("relative"))
      d.relative_tolerance = r_.NonNegativeNumber(*v, Join(tp, "relative"));
  } else {
    d.absolute_tolerance = d.relative_tolerance = r_.PositiveNumber(*tol, tp);
  }
  const double span = a->end_time - a->start_time;
  if (const Node* t = node.Find("min_step"))
    d.min_step = r_.PositiveNumber(*t, Join(path, "min_step"));
  if (const Node* t = node.Find("max_step")) {
    d.max_step = r_.PositiveNumber(*t, Join(path, "max_step"));
    if (!(d.max_step >= d.min_step))
      r_.Fail(t->location, Join(path, "max_step"), "expected max_step >= min_step");
  }
  a->step = std::clamp(1e-3 * span, d.min_step, d.max_step);
  if (const Node* t = node.Find("initial_step")) {
    a->step = r_.PositiveNumber(*t, Join(path, "initial_step"));
    if (a->step < d.min_step || a->step > d.max_step)
      r_.Fail(t->location, Join(path, "initial_step"), "expected a step in [min_step, max_step]");
  }
  d.initial_step = a->step;
}

// The Newton iteration's options, shared by dynamics and statics where both have them.
void SceneReader::ReadSolverOptions(const Node& node, const std::string& path) {
  AnalysisSettings* a = &spec_.analysis;
  if (const Node* t = node.Find("rho_inf")) {
    a->dynamic.rho_inf = r_.Number(*t, Join(path, "rho_inf"));
    if (!(a->dynamic.rho_inf >= 0.0 && a->dynamic.rho_inf <= 1.0))
      r_.Fail(t->location, Join(path, "rho_inf"), "expected a spectral radius in [0, 1]");
  }
  if (const Node* t = node.Find("tolerances")) {
    const std::string tp = Join(path, "tolerances");
    r_.CheckKeys(*t, tp, {"increment", "constraint", "residual"});
    if (const Node* v = t->Find("increment"))
      a->dynamic.increment_tolerance = a->statics.increment_tolerance =
          r_.PositiveNumber(*v, Join(tp, "increment"));
    if (const Node* v = t->Find("constraint"))
      a->dynamic.constraint_tolerance = a->statics.constraint_tolerance =
          r_.PositiveNumber(*v, Join(tp, "constraint"));
    if (const Node* v = t->Find("residual"))
      a->dynamic.residual_tolerance = a->statics.residual_tolerance =
          r_.PositiveNumber(*v, Join(tp, "residual"));
  }
  if (const Node* t = node.Find("max_iterations"))
    a->dynamic.max_iterations = a->statics.max_iterations =
        r_.Integer(*t, Join(path, "max_iterations"), 1, kMaxNewtonIterations);
  if (const Node* t = node.Find("max_halvings"))
    a->dynamic.max_halvings = a->statics.max_halvings =
        r_.Integer(*t, Join(path, "max_halvings"), 0, kMaxHalvings);
  if (const Node* t = node.Find("newton"))
    a->dynamic.newton_matrix = r_.Enum<NewtonMatrix>(*t, Join(path, "newton"));
  if (const Node* t = node.Find("predictor"))
    a->dynamic.predictor = r_.Enum<Predictor>(*t, Join(path, "predictor"));
  if (const Node* t = node.Find("convergence"))
    a->dynamic.convergence = r_.Enum<ConvergenceTest>(*t, Join(path, "convergence"));
  if (const Node* t = node.Find("load_steps"))
    a->statics.load_steps = r_.Integer(*t, Join(path, "load_steps"), 1, kMaxLoadSteps);
}

// analysis.statics: how a static solution follows its path (statics.h, StaticOptions).
void SceneReader::ReadStatics(const Node& node, const std::string& path) {
  StaticOptions* o = &spec_.analysis.statics;
  r_.CheckKeys(node, path,
               {"method", "end_load_factor", "max_steps", "arc_length", "arc_length_min",
                "arc_length_max", "desired_iterations", "psi", "rotation_weight", "exact_tangent"});
  const auto field = [&](const char* key) { return Join(path, key); };
  if (const Node* t = node.Find("method")) o->method = r_.Enum<StaticMethod>(*t, field("method"));
  if (const Node* t = node.Find("end_load_factor"))
    o->end_load_factor = r_.Number(*t, field("end_load_factor"));
  if (const Node* t = node.Find("max_steps"))
    o->max_steps = r_.Integer(*t, field("max_steps"), 1, kMaxStaticSteps);
  if (const Node* t = node.Find("arc_length"))
    o->arc_length = r_.PositiveNumber(*t, field("arc_length"));
  if (const Node* t = node.Find("arc_length_min"))
    o->arc_length_min = r_.PositiveNumber(*t, field("arc_length_min"));
  if (const Node* t = node.Find("arc_length_max")) {
    o->arc_length_max = r_.PositiveNumber(*t, field("arc_length_max"));
    if (o->arc_length_min > o->arc_length_max)
      r_.Fail(t->location, field("arc_length_max"), "expected arc_length_max >= arc_length_min");
  }
  if (const Node* t = node.Find("desired_iterations"))
    o->desired_iterations = r_.Integer(*t, field("desired_iterations"), 1, kMaxNewtonIterations);
  if (const Node* t = node.Find("psi")) o->psi = r_.NonNegativeNumber(*t, field("psi"));
  if (const Node* t = node.Find("rotation_weight"))
    o->rotation_weight = r_.NonNegativeNumber(*t, field("rotation_weight"));
  if (const Node* t = node.Find("exact_tangent"))
    o->constraint_force_tangent = r_.Bool(*t, field("exact_tangent"));
}

// The defaults (every joint with coordinates, the intervals of about kDefaultOutputRows rows
// and kDefaultVtkFrames frames) are OutputsSpec's, resolved by the compiler.
void SceneReader::ReadOutputs(const Node* node) {
  OutputsSpec* out = &spec_.outputs;
  if (node == nullptr || node->IsNull()) return;
  const std::string path = "outputs";
  r_.CheckKeys(*node, path,
               {"points", "joints", "interval", "vtk", "vtk_format", "vtk_interval", "rod_fields",
                "max_rows"});
  if (const Node* pts = node->Find("points")) {
    const std::string pp = Join(path, "points");
    r_.CheckNames(*pts, pp, "output point");
    for (const auto& [entry, value] : pts->entries) {
      const std::string p = Join(pp, entry.key);
      src_.output_points.push_back({Field(entry.key_location, p), {}});
      out->points.emplace_back();
      out->points.back().name = entry.key;
      ReadOutputPoint(value, p, out->points.back(), src_.output_points.back());
    }
  }
  if (const Node* jn = node->Find("joints")) ReadOutputJoints(*jn, Join(path, "joints"));
  if (const Node* v = node->Find("interval"))
    out->interval = r_.NonNegativeNumber(*v, Join(path, "interval"));
  if (const Node* v = node->Find("vtk")) out->vtk = r_.Bool(*v, Join(path, "vtk"));
  if (const Node* v = node->Find("vtk_format"))
    out->vtk_format = r_.Enum<VtkFormat>(*v, Join(path, "vtk_format"));
  if (const Node* v = node->Find("vtk_interval"))
    out->vtk_interval = r_.NonNegativeNumber(*v, Join(path, "vtk_interval"));
  if (const Node* v = node->Find("rod_fields")) ReadRodFields(*v, Join(path, "rod_fields"));
  if (const Node* v = node->Find("max_rows"))
    out->max_rows = r_.Integer(*v, Join(path, "max_rows"), 1, static_cast<int>(kMaxMaxRows));
}

// true (at the rows of points.csv), false, or the interval between rows [s] (>= 0).
void SceneReader::ReadRodFields(const Node& v, const std::string& path) {
  OutputsSpec* out = &spec_.outputs;
  std::string word = v.IsScalar() ? v.scalar : std::string();
  for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (word == "true" || word == "false") {
    out->rod_fields = r_.Bool(v, path);
    out->rod_fields_interval = -1.0;
    return;
  }
  double interval = 0.0;
  std::string error;
  if (!v.IsScalar() || !scene_yaml::EvaluateExpression(v.scalar, &interval, &error) ||
      !std::isfinite(interval) || interval < 0.0)
    r_.Fail(v.location, path,
            "expected true, false or the interval between rows in s (a number >= 0), got " +
                (v.IsScalar() ? "'" + v.scalar + "'" : scene_yaml::Describe(v)));
  out->rod_fields = true;
  out->rod_fields_interval = interval;
}

void SceneReader::ReadOutputPoint(const Node& value, const std::string& p, OutputPointSpec& op,
                                  EntitySource& source) {
  r_.CheckKeys(value, p, {"body", "at", "rod", "s"});
  const Node* bn = value.Find("body");
  const Node* rn = value.Find("rod");
  if (bn != nullptr && rn != nullptr)
    r_.Fail(rn->location, Join(p, "rod"), "give either {body, at} or {rod, s}, not both");
  if (bn == nullptr && rn == nullptr)
    r_.Fail(value.location, p, "missing key 'body' (with 'at') or 'rod' (with 's')");
  if (bn != nullptr) {
    NotUsedBy(value, p, {"s"}, "body points (use 'rod' and 's' for a point along a rod)");
    op.body = Body(*bn, Join(p, "body"));
    const Node& an = r_.Require(value, p, "at");
    op.at = Point(an, Join(p, "at"));
    source.parts.emplace_back("at", Field(an.location, Join(p, "at")));
    return;
  }
  NotUsedBy(value, p, {"at"}, "rod points (use 'body' and 'at' for a node point)");
  op.body = Body(*rn, Join(p, "rod"));
  const BodySpec& body = spec_.bodies[static_cast<std::size_t>(op.body)];
  if (body.rigid)
    r_.Fail(rn->location, Join(p, "rod"),
            "'" + body.name + "' is a rigid body; use {body: " + body.name + ", at: POINT}");
  const Node& sn = r_.Require(value, p, "s");
  op.along_rod = true;
  op.arc_length = r_.NonNegativeNumber(sn, Join(p, "s"));
  source.parts.emplace_back("s", Field(sn.location, Join(p, "s")));
}

// 'all', 'none' or a list of joint names (with coordinates, each once).
void SceneReader::ReadOutputJoints(const Node& jn, const std::string& jp) {
  std::vector<int>& out = spec_.outputs.joints;
  out.clear();
  if (jn.IsScalar() && (jn.scalar == "all" || jn.scalar == "none")) {
    spec_.outputs.all_joints = jn.scalar == "all";
    return;
  }
  if (!jn.IsSequence())
    r_.Fail(jn.location, jp,
            "expected 'all', 'none' or a list of joint names, got " + scene_yaml::Describe(jn));
  spec_.outputs.all_joints = false;
  std::vector<std::string> names;
  for (const JointEntrySpec& j : spec_.joints) names.push_back(j.joint.name);
  for (std::size_t i = 0; i < jn.items.size(); ++i) {
    const Node& item = jn.items[i];
    const std::string ip = Index(jp, i);
    const std::string name = r_.Text(item, ip);
    const auto found = std::find(names.begin(), names.end(), name);
    if (found == names.end())
      r_.Fail(item.location, ip,
              "undefined joint '" + name + "'" + scene_yaml::DidYouMean(name, names));
    const int index = static_cast<int>(found - names.begin());
    if (GetJointTypeInfo(spec_.joints[static_cast<std::size_t>(index)].joint.type).dof == 0)
      r_.Fail(item.location, ip, "joint '" + name + "' is fixed: it has no coordinates to record");
    if (std::find(out.begin(), out.end(), index) != out.end())
      r_.Fail(item.location, ip, "joint '" + name + "' is listed twice");
    out.push_back(index);
  }
}

void SceneReader::Read(const Node& root, const std::string& default_name) {
  src_.root = Field(root.location, "");
  if (!root.IsMap())
    r_.Fail(root.location, "",
            "a scene is a map of sections (points:, sections:, bodies:, joints:, ...), got " +
                scene_yaml::Describe(root));
  r_.CheckKeys(root, "",
               {"name", "description", "units", "gravity", "defaults", "points", "materials",
                "sections", "bodies", "joints", "loads", "tendons", "forces", "analysis", "outputs",
                "inputs", "actuation", "contact"});
  spec_.name = default_name;
  if (const Node* n = root.Find("name")) spec_.name = r_.Text(*n, "name");
  if (const Node* d = root.Find("description"))
    if (!d->IsScalar())
      r_.Fail(d->location, "description", "expected text, got " + scene_yaml::Describe(*d));
  ReadUnits(root);
  if (const Node* g = root.Find("gravity")) spec_.gravity = r_.Vector3(*g, "gravity");
  ReadDefaults(root.Find("defaults"));
  ReadPoints(root.Find("points"));
  ReadMaterials(root.Find("materials"));
  ReadSections(root.Find("sections"));
  ReadInputs(root.Find("inputs"));
  ReadBodies(root.Find("bodies"));
  if (spec_.bodies.empty()) r_.Fail(root.location, "bodies", "the scene has no bodies");
  ReadJoints(root.Find("joints"));
  ReadLoads(root.Find("loads"));
  ReadTendons(root.Find("tendons"));
  ReadForces(root.Find("forces"));
  ReadActuation(root.Find("actuation"));
  ReadContact(root.Find("contact"));
  ReadAnalysis(root.Find("analysis"));
  ReadOutputs(root.Find("outputs"));
}

std::string Stem(const std::string& source) {
  const std::string stem = std::filesystem::path(source).stem().string();
  return stem.empty() ? source : stem;
}

}  // namespace

const FieldSource* EntitySource::Part(const std::string& name) const {
  for (const auto& [key, field] : parts)
    if (key == name) return &field;
  return nullptr;
}

SceneSpec ReadSceneSpec(const std::string& yaml_text, const std::string& source_name,
                        const std::vector<std::string>& overrides, SceneSources* sources) {
  if (yaml_text.size() > kMaxSceneBytes)
    throw InputError(source_name + ": the scene is larger than " +
                     std::to_string(kMaxSceneBytes >> 20) + " MiB (the limit)");
  for (const std::string& o : overrides)
    if (o.size() > kMaxOverrideBytes)
      throw InputError(source_name + ": an override is longer than " +
                       std::to_string(kMaxOverrideBytes >> 20) + " MiB (the limit): '" +
                       o.substr(0, 40) + "...'");
  scene_yaml::Node root = scene_yaml::Parse(yaml_text, source_name);
  for (const std::string& o : overrides)
    scene_yaml::ApplyOverride(root, o, source_name, kCollections);
  SceneSpec spec;
  *sources = SceneSources{};
  sources->file = source_name;
  SceneReader(source_name, &spec, sources).Read(root, Stem(source_name));
  return spec;
}

}  // namespace screwfem
