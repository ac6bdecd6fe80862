// Scene files (docs/scene-format.md): YAML text -> document tree (scene_yaml.cpp) -> overrides
// -> validation and compilation into a Model through ModelBuilder, analysis settings and
// output specification. Every message names the file, line, column and field.
#include "screwfem/io/scene.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "scene_yaml.h"
#include "screwfem/io/schedule.h"
#include "screwfem/model/errors.h"
#include "screwfem/build/model_builder.h"

namespace screwfem {

namespace {

using scene_yaml::Location;
using scene_yaml::Node;
using scene_yaml::Reader;

// Maps of named entries: an override may not walk through an entry that does not exist.
const std::vector<std::string> kCollections = {"points", "materials", "sections",      "bodies",
                                               "joints", "loads",     "outputs.points"};

constexpr int kMaxElements = 100000;  // per rod (or per path segment)
constexpr long kMaxTotalElements = 1000000;  // all rods of a scene
constexpr double kMaxSteps = 1e9;     // time steps of one dynamic analysis

const char* const kGroundName = "ground";

const std::vector<std::string> kBodyKeys = {
    "type", "between", "at",   "mass",    "inertia",  "com", "fixed",      "free",
    "from", "to",      "path", "section", "elements", "up",  "weld_start", "weld_end"};

std::string Join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string FormatVec(const Vec3& v) {
  std::ostringstream s;
  s.precision(6);
  s << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return s.str();
}

struct BodyEntry {
  std::string name;
  std::string path;   // "bodies.NAME"
  Location location;  // of the name
  const Node* node = nullptr;
  bool rigid = true;
  int index = -1;              // rigid body index or rod index in the builder
  int frame_node = -1;         // rigid bodies: the body's node
  Vec3 origin = Vec3::Zero();  // rigid bodies: node position (the frame is world-aligned)
  bool fixed = false;
  bool free = false;
  bool connected = false;
};

struct EntityLocation {
  std::string path;
  Location location;
};

class SceneCompiler {
 public:
  explicit SceneCompiler(const std::string& source) : r_(source) {}

  Scene Compile(const Node& root, const std::string& default_name);

 private:
  // Sections of the file.
  void ReadUnits(const Node& root);
  void ReadDefaults(const Node* node);
  void ReadPoints(const Node* node);
  void ReadMaterials(const Node* node);
  void ReadSections(const Node* node);
  void ReadBodies(const Node* node);
  void ReadRigidBody(BodyEntry& body);
  void ReadSoftBody(BodyEntry& body);
  void ReadJoints(const Node* node);
  void ReadLoads(const Node* node);
  void CheckConnections() const;
  void ReadAnalysis(const Node* node, AnalysisSettings* analysis);
  void ReadOutputs(const Node* node, const Model& model, const AnalysisSettings& analysis,
                   OutputSpec* outputs);

  // Values.
  Vec3 Point(const Node& node, const std::string& path) const;
  Vec3 UnitAxis(const Node& node, const std::string& path) const;
  Material ReadMaterial(const Node& node, const std::string& path) const;
  Profile ReadProfile(const Node& node, const std::string& path) const;
  Profile ReadProfileTerm(const Node& node, const std::string& path) const;
  Vec6 PerCoordinate(const Node& node, const std::string& path, int k, bool non_negative) const;
  BodyEntry& Body(const Node& node, const std::string& path);
  // Node of a body at a world point: the rigid body's node, or the rod node there.
  int RodNodeAt(const BodyEntry& rod, const Vec3& p, const Location& at, const std::string& path,
                const std::string& what);
  double RodLength(const BodyEntry& rod);  // reference arc length, as Build computes it
  void NotUsedBy(const Node& map, const std::string& path, const std::vector<std::string>& keys,
                 const std::string& who) const;
  [[noreturn]] void RethrowBuildError(const InputError& e) const;

  Reader r_;
  ModelBuilder builder_;
  int default_elements_ = 8;
  long total_elements_ = 0;  // over all rods (kMaxTotalElements)
  Vec3 default_up_ = Vec3::UnitZ();
  std::vector<std::pair<std::string, Vec3>> points_;
  std::map<std::string, Material> materials_;
  std::map<std::string, Section> sections_;
  std::vector<std::string> material_names_, section_names_;
  std::vector<BodyEntry> bodies_;
  std::vector<EntityLocation> joint_locations_;
};

// --- values ------------------------------------------------------------------------------------

Vec3 SceneCompiler::Point(const Node& node, const std::string& path) const {
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

Vec3 SceneCompiler::UnitAxis(const Node& node, const std::string& path) const {
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

Material SceneCompiler::ReadMaterial(const Node& node, const std::string& path) const {
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

Profile SceneCompiler::ReadProfile(const Node& node, const std::string& path) const {
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

Profile SceneCompiler::ReadProfileTerm(const Node& node, const std::string& path) const {
  r_.CheckKeys(node, path,
               {"type", "value", "scale", "t0", "t1", "frequency", "phase", "times", "values"});
  const std::string type =
      r_.Choice(r_.Require(node, path, "type"), Join(path, "type"),
                {"constant", "ramp", "bang_bang", "s_curve", "smooth_step", "sine", "table"});
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

Vec6 SceneCompiler::PerCoordinate(const Node& node, const std::string& path, int k,
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

void SceneCompiler::NotUsedBy(const Node& map, const std::string& path,
                              const std::vector<std::string>& keys, const std::string& who) const {
  for (const auto& [entry, value] : map.entries)
    if (std::find(keys.begin(), keys.end(), entry.key) != keys.end())
      r_.Fail(entry.key_location, Join(path, entry.key),
              "'" + entry.key + "' is not used by " + who);
}

BodyEntry& SceneCompiler::Body(const Node& node, const std::string& path) {
  const std::string name = r_.Text(node, path);
  for (BodyEntry& b : bodies_)
    if (b.name == name) return b;
  std::vector<std::string> names;
  for (const BodyEntry& b : bodies_) names.push_back(b.name);
  r_.Fail(node.location, path,
          "undefined body '" + name + "'" + scene_yaml::DidYouMean(name, names));
}

int SceneCompiler::RodNodeAt(const BodyEntry& rod, const Vec3& p, const Location& at,
                             const std::string& path, const std::string& what) {
  const Model& m = builder_.model();
  const Rod& r = m.rods[static_cast<std::size_t>(rod.index)];
  double best = std::numeric_limits<double>::infinity();
  int best_node = -1;
  for (int n : r.nodes) {
    const double d = (m.nodes[static_cast<std::size_t>(n)].reference.x - p).norm();
    if (d < best) {
      best = d;
      best_node = n;
    }
  }
  const double tol =
      1e-8 * std::max({1.0, p.norm(),
                       (m.nodes[static_cast<std::size_t>(r.nodes.front())].reference.x -
                        m.nodes[static_cast<std::size_t>(r.nodes.back())].reference.x)
                           .norm()});
  if (best > tol) {
    std::ostringstream s;
    s.precision(6);
    s << what << ": soft body '" << rod.name << "' has no node at " << FormatVec(p)
      << " (nearest node " << best << " m away); attach at an end, a path point or a "
      << "subdivision point of the rod";
    r_.Fail(at, path, s.str());
  }
  return best_node;
}

double SceneCompiler::RodLength(const BodyEntry& rod) {
  const Model& m = builder_.model();
  const Rod& r = m.rods[static_cast<std::size_t>(rod.index)];
  double length = 0.0;
  for (std::size_t i = 0; i + 1 < r.nodes.size(); ++i)
    length += LogSE3(m.nodes[static_cast<std::size_t>(r.nodes[i])].reference.Inverse() *
                     m.nodes[static_cast<std::size_t>(r.nodes[i + 1])].reference)
                  .head<3>()
                  .norm();
  return length;
}

// --- sections of the file ----------------------------------------------------------------------

void SceneCompiler::ReadUnits(const Node& root) {
  const Node* units = root.Find("units");
  if (units == nullptr) return;
  if (!units->IsScalar() || units->scalar != "SI")
    r_.Fail(units->location, "units",
            "only SI units are supported (m, kg, s, N, rad), got " + scene_yaml::Describe(*units));
}

void SceneCompiler::ReadDefaults(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckKeys(*node, "defaults", {"elements", "up"});
  if (const Node* e = node->Find("elements"))
    default_elements_ = r_.Integer(*e, "defaults.elements", 1, kMaxElements);
  if (const Node* up = node->Find("up")) {
    default_up_ = r_.Vector3(*up, "defaults.up");
    if (!(default_up_.norm() > 0.0)) r_.Fail(up->location, "defaults.up", "the vector is zero");
  }
}

void SceneCompiler::ReadPoints(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "points", "point");
  for (const auto& [entry, value] : node->entries)
    points_.emplace_back(entry.key, r_.Vector3(value, Join("points", entry.key)));
}

void SceneCompiler::ReadMaterials(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "materials", "material");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("materials", entry.key);
    r_.ExpectMap(value, path);
    materials_[entry.key] = ReadMaterial(value, path);
    material_names_.push_back(entry.key);
  }
}

void SceneCompiler::ReadSections(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "sections", "section");
  for (const auto& [entry, value_binding] : node->entries) {
    const Node& value = value_binding;  // a variable the lambdas below can capture (Clang 14)
    const std::string path = Join("sections", entry.key);
    r_.CheckKeys(value, path,
                 {"stiffness", "inertia", "damping", "rayleigh_mass", "rayleigh_stiffness", "shape",
                  "material", "radius", "width", "height", "outer_radius", "inner_radius"});
    Section s;
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
        s = Section::Circle(positive("radius"), m);
      } else if (kind == "rectangle") {
        NotUsedBy(value, path, {"radius", "outer_radius", "inner_radius"}, "rectangles");
        s = Section::Rectangle(positive("width"), positive("height"), m);
      } else {
        NotUsedBy(value, path, {"radius", "width", "height"}, "tubes");
        const double ro = positive("outer_radius");
        const Node& in = r_.Require(value, path, "inner_radius");
        const double ri = r_.NonNegativeNumber(in, Join(path, "inner_radius"));
        if (!(ri < ro))
          r_.Fail(in.location, Join(path, "inner_radius"), "expected inner_radius < outer_radius");
        s = Section::Tube(ro, ri, m);
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

void SceneCompiler::ReadBodies(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "bodies", "body");
  for (const auto& [entry, value] : node->entries) {
    BodyEntry b;
    b.name = entry.key;
    b.path = Join("bodies", entry.key);
    b.location = entry.key_location;
    b.node = &value;
    if (b.name == kGroundName)
      r_.Fail(entry.key_location, b.path, "'ground' is reserved for the world frame");
    r_.ExpectMap(value, b.path);
    const std::string type = r_.Choice(r_.Require(value, b.path, "type"), Join(b.path, "type"),
                                       {"rigid", "soft", "rod"});
    b.rigid = type == "rigid";
    bodies_.push_back(b);
  }
  // Compile in file order (node and rod numbering follows the file).
  for (BodyEntry& b : bodies_) {
    if (b.rigid)
      ReadRigidBody(b);
    else
      ReadSoftBody(b);
  }
}

void SceneCompiler::ReadRigidBody(BodyEntry& b) {
  const Node& n = *b.node;
  const std::string& path = b.path;
  r_.CheckKeys(n, path, kBodyKeys);
  NotUsedBy(n, path, {"from", "to", "path", "section", "elements", "up", "weld_start", "weld_end"},
            "rigid bodies");
  const Node* between = n.Find("between");
  const Node* at = n.Find("at");
  if (between != nullptr && at != nullptr)
    r_.Fail(at->location, Join(path, "at"), "give either 'between' (two points) or 'at', not both");
  if (between == nullptr && at == nullptr)
    r_.Fail(n.location, path, "missing key 'between' (two points) or 'at' (one point)");
  Vec3 com_world;
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
  const double mass = r_.PositiveNumber(r_.Require(n, path, "mass"), Join(path, "mass"));
  const Node& in = r_.Require(n, path, "inertia");
  const std::string ip = Join(path, "inertia");
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
  if (const Node* f = n.Find("fixed")) b.fixed = r_.Bool(*f, Join(path, "fixed"));
  if (const Node* f = n.Find("free")) b.free = r_.Bool(*f, Join(path, "free"));
  if (b.fixed && b.free)
    r_.Fail(n.Find("free")->location, Join(path, "free"), "a body cannot be both fixed and free");
  b.frame_node = builder_.AddNode(SE3::Translation(b.origin), b.name);
  if (b.fixed) builder_.FixNode(b.frame_node);
  b.index = builder_.AddRigidBody(b.name, b.frame_node, mass, com_world - b.origin, J);
}

void SceneCompiler::ReadSoftBody(BodyEntry& b) {
  const Node& n = *b.node;
  const std::string& path = b.path;
  r_.CheckKeys(n, path, kBodyKeys);
  NotUsedBy(n, path, {"between", "at", "mass", "inertia", "com", "fixed"},
            "soft bodies (a soft body is clamped to the ground by a fixed joint)");
  const Node& sn = r_.Require(n, path, "section");
  const std::string section_name = r_.Text(sn, Join(path, "section"));
  const auto sec = sections_.find(section_name);
  if (sec == sections_.end())
    r_.Fail(sn.location, Join(path, "section"),
            "undefined section '" + section_name + "'" +
                scene_yaml::DidYouMean(section_name, section_names_));
  int elements = default_elements_;
  if (const Node* e = n.Find("elements"))
    elements = r_.Integer(*e, Join(path, "elements"), 1, kMaxElements);
  Vec3 up = default_up_;
  if (const Node* u = n.Find("up")) {
    up = r_.Vector3(*u, Join(path, "up"));
    if (!(up.norm() > 0.0)) r_.Fail(u->location, Join(path, "up"), "the vector is zero");
  }
  if (const Node* f = n.Find("free")) b.free = r_.Bool(*f, Join(path, "free"));

  // The polyline: from/to (one straight segment) or path (several).
  std::vector<Vec3> pts;
  std::vector<Location> pts_at;
  const Node* from = n.Find("from");
  const Node* to = n.Find("to");
  const Node* poly = n.Find("path");
  if (poly != nullptr && (from != nullptr || to != nullptr))
    r_.Fail(poly->location, Join(path, "path"), "give either 'from' and 'to', or 'path', not both");
  if (poly != nullptr) {
    const std::string p = Join(path, "path");
    if (!poly->IsSequence() || poly->items.size() < 2)
      r_.Fail(poly->location, p,
              "expected a list of at least two points, got " + scene_yaml::Describe(*poly));
    for (std::size_t i = 0; i < poly->items.size(); ++i) {
      pts.push_back(Point(poly->items[i], p + "[" + std::to_string(i) + "]"));
      pts_at.push_back(poly->items[i].location);
    }
  } else {
    if (from == nullptr) r_.Fail(n.location, path, "missing key 'from' (or 'path')");
    if (to == nullptr) r_.Fail(n.location, path, "missing key 'to'");
    pts.push_back(Point(*from, Join(path, "from")));
    pts.push_back(Point(*to, Join(path, "to")));
    pts_at.push_back(from->location);
    pts_at.push_back(to->location);
  }
  total_elements_ += static_cast<long>(elements) * static_cast<long>(pts.size() - 1);
  if (total_elements_ > kMaxTotalElements)
    r_.Fail(n.Find("elements") != nullptr ? n.Find("elements")->location : n.location, path,
            "the scene's rods have more than " + std::to_string(kMaxTotalElements) +
                " elements in all (the limit)");
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (!((pts[i] - pts[i - 1]).norm() > 1e-12 * std::max(1.0, pts[i].norm())))
      r_.Fail(
          pts_at[i],
          poly != nullptr ? Join(path, "path") + "[" + std::to_string(i) + "]" : Join(path, "to"),
          "zero-length segment (its end points coincide)");

  // Welds: share the end node of another soft body (a rigid clamp without extra unknowns).
  auto weld = [&](const char* key, const Vec3& p, const Mat3& R) -> int {
    const Node* w = n.Find(key);
    if (w == nullptr) return -1;
    const std::string wp = Join(path, key);
    BodyEntry& other = Body(*w, wp);
    if (&other == &b) r_.Fail(w->location, wp, "a soft body cannot be welded to itself");
    if (other.rigid || other.index < 0)
      r_.Fail(w->location, wp,
              "'" + other.name +
                  "' must be a soft body defined earlier in the file (to weld to a "
                  "rigid body, use a joint of type fixed)");
    const int node = RodNodeAt(other, p, w->location, wp, "weld");
    const Mat3& Ro = builder_.model().nodes[static_cast<std::size_t>(node)].reference.R;
    if ((Ro - R).norm() > 1e-9)
      r_.Fail(w->location, wp,
              "the section frames of '" + b.name + "' and '" + other.name +
                  "' differ at the shared node (a kink or a different 'up'); use a joint of "
                  "type fixed");
    other.connected = true;
    b.connected = true;
    return node;
  };

  const Section& section = sec->second;
  if (pts.size() == 2) {
    const Mat3 R = FrameAlong(pts[1] - pts[0], up);
    const int start = weld("weld_start", pts[0], R);
    const int end = weld("weld_end", pts[1], R);
    b.index = builder_.AddStraightRod(b.name, pts[0], pts[1], elements, section, up, start, end);
    return;
  }
  // Path: node frames along each segment, along the bisector at interior path points.
  const std::size_t segs = pts.size() - 1;
  std::vector<Vec3> dir(segs);
  for (std::size_t i = 0; i < segs; ++i) dir[i] = (pts[i + 1] - pts[i]).normalized();
  auto vertex_frame = [&](std::size_t i) {
    Vec3 t = i == 0 ? dir[0] : i == segs ? dir[segs - 1] : Vec3(dir[i - 1] + dir[i]);
    if (!(t.norm() > 1e-6))
      r_.Fail(pts_at[i], Join(path, "path") + "[" + std::to_string(i) + "]",
              "the path turns back on itself here");
    return FrameAlong(t, up);
  };
  std::vector<int> nodes;
  int count = 0;
  const int first = weld("weld_start", pts[0], vertex_frame(0));
  auto add = [&](const SE3& H) {
    return builder_.AddNode(H, b.name + "." + std::to_string(count));
  };
  {
    SE3 H;
    H.R = vertex_frame(0);
    H.x = pts[0];
    nodes.push_back(first >= 0 ? first : add(H));
    ++count;
  }
  for (std::size_t s = 0; s < segs; ++s) {
    for (int e = 1; e <= elements; ++e) {
      SE3 H;
      const bool vertex = e == elements;
      H.R = vertex ? vertex_frame(s + 1) : FrameAlong(dir[s], up);
      H.x = vertex ? pts[s + 1]
                   : Vec3(pts[s] + (pts[s + 1] - pts[s]) * (static_cast<double>(e) / elements));
      if (vertex && s + 1 == segs) {
        const int last = weld("weld_end", pts.back(), H.R);
        if (last >= 0) {
          nodes.push_back(last);
          ++count;
          continue;
        }
      }
      nodes.push_back(add(H));
      ++count;
    }
  }
  b.index = builder_.AddRodThroughNodes(b.name, nodes, section);
}

void SceneCompiler::ReadJoints(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "joints", "joint");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("joints", entry.key);
    joint_locations_.push_back({path, entry.key_location});
    r_.CheckKeys(value, path,
                 {"type", "at", "between", "axis", "axis2", "pitch", "stiffness", "damping", "rest",
                  "drive"});
    const std::string type_name =
        r_.Choice(r_.Require(value, path, "type"), Join(path, "type"), JointTypeNameList());
    const JointTypeInfo& info = *FindJointType(type_name);
    const JointType type = info.type;
    const std::string who = type_name + " joints";
    const Vec3 at = Point(r_.Require(value, path, "at"), Join(path, "at"));

    // Sides.
    const Node& bn = r_.Require(value, path, "between");
    const std::string bp = Join(path, "between");
    if (!bn.IsSequence() || bn.items.size() != 2)
      r_.Fail(bn.location, bp,
              "expected two sides [A, B] (ground or body names), got " + scene_yaml::Describe(bn));
    int side_nodes[2] = {kGround, kGround};
    BodyEntry* side_bodies[2] = {nullptr, nullptr};
    for (int s = 0; s < 2; ++s) {
      const Node& sn = bn.items[static_cast<std::size_t>(s)];
      const std::string sp = bp + "[" + std::to_string(s) + "]";
      const std::string name = r_.Text(sn, sp);
      if (name == kGroundName) continue;
      BodyEntry& body = Body(sn, sp);
      side_bodies[s] = &body;
      side_nodes[s] =
          body.rigid ? body.frame_node : RodNodeAt(body, at, sn.location, sp, "joint point");
    }
    if (side_bodies[0] == nullptr && side_bodies[1] == nullptr)
      r_.Fail(bn.location, bp, "both sides are the ground");
    if (side_bodies[0] == side_bodies[1])
      r_.Fail(bn.location, bp, "both sides are the same body '" + side_bodies[0]->name + "'");

    // Axes.
    Vec3 axis = Vec3::UnitZ(), axis2 = Vec3::Zero();
    double pitch = 0.0;
    if (info.uses_axis) {
      axis = UnitAxis(r_.Require(value, path, "axis"), Join(path, "axis"));
    } else {
      NotUsedBy(value, path, {"axis"}, who);
    }
    if (info.uses_axis2) {
      const Node& a2 = r_.Require(value, path, "axis2");
      axis2 = UnitAxis(a2, Join(path, "axis2"));
      if (std::abs(axis.dot(axis2)) > 1e-6)
        r_.Fail(a2.location, Join(path, "axis2"), "must be orthogonal to 'axis'");
      axis2 = (axis2 - axis.dot(axis2) * axis).normalized();
    } else {
      NotUsedBy(value, path, {"axis2"}, who);
    }
    if (info.uses_pitch) {
      pitch = r_.Number(r_.Require(value, path, "pitch"), Join(path, "pitch"));
    } else {
      NotUsedBy(value, path, {"pitch"}, who);
    }
    const int index =
        builder_.AddJointAt(entry.key, type, side_nodes[0], side_nodes[1], at, axis, axis2, pitch);
    Joint& j = builder_.model().joints[static_cast<std::size_t>(index)];
    for (BodyEntry* body : side_bodies)
      if (body != nullptr) body->connected = true;

    // Springs, dampers, drive (method.md §4.4, §4.5).
    const int k = j.k();
    const bool global = info.global_coordinates;
    if (JointSpringCount(j) == 0)
      NotUsedBy(value, path, {"stiffness", "damping", "rest", "drive"}, who);
    if (!global) NotUsedBy(value, path, {"rest", "drive"}, who + " (no global coordinates)");
    if (const Node* s = value.Find("stiffness"))
      j.stiffness = PerCoordinate(*s, Join(path, "stiffness"), JointSpringCount(j), true);
    if (const Node* d = value.Find("damping"))
      j.damping = PerCoordinate(*d, Join(path, "damping"), JointSpringCount(j), true);
    if (const Node* rest = value.Find("rest"))
      j.rest = PerCoordinate(*rest, Join(path, "rest"), k, false);
    if (const Node* drive = value.Find("drive")) {
      const std::string dp = Join(path, "drive");
      r_.CheckKeys(*drive, dp, {"type", "coordinate", "profile"});
      std::vector<std::string> kinds = EnumNameList<DriveKind>();
      kinds.erase(kinds.begin());  // "none": a passive joint has no `drive` key
      j.drive = *EnumFromName<DriveKind>(
          r_.Choice(r_.Require(*drive, dp, "type"), Join(dp, "type"), kinds));
      if (const Node* c = drive->Find("coordinate"))
        j.drive_coord = r_.Integer(*c, Join(dp, "coordinate"), 0, k - 1);
      j.drive_profile = ReadProfile(r_.Require(*drive, dp, "profile"), Join(dp, "profile"));
      if (j.drive == DriveKind::kSeriesElastic && !(j.stiffness(j.drive_coord) > 0.0))
        r_.Fail(drive->location, dp,
                "a series_elastic drive needs a positive stiffness on coordinate " +
                    std::to_string(j.drive_coord) + " (the spring it drives)");
    }
  }
}

void SceneCompiler::ReadLoads(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "loads", "load");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("loads", entry.key);
    r_.CheckKeys(value, path,
                 {"body", "at", "s", "distributed", "force", "moment", "frame", "profile"});
    const Node& bn = r_.Require(value, path, "body");
    BodyEntry& body = Body(bn, Join(path, "body"));
    const Node* f = value.Find("force");
    const Node* m = value.Find("moment");
    if (f == nullptr && m == nullptr)
      r_.Fail(value.location, path, "missing key 'force' (or 'moment')");
    Vec3 force = Vec3::Zero(), moment = Vec3::Zero();
    if (f != nullptr) force = r_.Vector3(*f, Join(path, "force"));
    if (m != nullptr) moment = r_.Vector3(*m, Join(path, "moment"));
    LoadFrame frame = LoadFrame::kWorld;
    if (const Node* fr = value.Find("frame"))
      frame = r_.Enum<LoadFrame>(*fr, Join(path, "frame"));
    Profile profile = Profile::Constant(1.0);
    if (const Node* p = value.Find("profile")) profile = ReadProfile(*p, Join(path, "profile"));

    // Where: a point of a rigid body, a rod node, a rod section at arc length s, or the
    // whole rod (per unit length).
    const Node* at = value.Find("at");
    const Node* s = value.Find("s");
    bool distributed = false;
    if (const Node* d = value.Find("distributed"))
      distributed = r_.Bool(*d, Join(path, "distributed"));
    const int given = (at != nullptr) + (s != nullptr) + (distributed ? 1 : 0);
    if (given > 1) r_.Fail(value.location, path, "give one of 'at', 's' or 'distributed: true'");
    if (body.rigid && (s != nullptr || distributed))
      r_.Fail(value.location, path, "'s' and 'distributed' apply to soft bodies only");
    if (given == 0)
      r_.Fail(
          value.location, path,
          body.rigid ? "missing key 'at'" : "missing key 'at' (or 's', or 'distributed: true')");
    if (at != nullptr) {
      PointLoad load;
      const Vec3 p = Point(*at, Join(path, "at"));
      if (body.rigid) {
        load.node = body.frame_node;
        load.point = p - body.origin;  // the body frame is world-aligned in the reference
      } else {
        load.node = RodNodeAt(body, p, at->location, Join(path, "at"), "load point");
      }
      load.frame = frame;
      load.force = force;
      load.moment = moment;
      load.profile = profile;
      builder_.AddPointLoad(load);
      continue;
    }
    RodLoad load;
    load.rod = body.index;
    load.distributed = distributed;
    if (s != nullptr) {
      load.arc_length = r_.NonNegativeNumber(*s, Join(path, "s"));
      const double length = RodLength(body);
      if (load.arc_length > length * (1.0 + 1e-12)) {
        std::ostringstream msg;
        msg.precision(9);
        msg << "arc length beyond the end of the rod (length " << length << " m)";
        r_.Fail(s->location, Join(path, "s"), msg.str());
      }
    }
    load.frame = frame;
    load.force = force;
    load.moment = moment;
    load.profile = profile;
    builder_.AddRodLoad(load);
  }
}

void SceneCompiler::CheckConnections() const {
  for (const BodyEntry& b : bodies_)
    if (!b.connected && !b.fixed && !b.free)
      r_.Fail(b.location, b.path,
              "body '" + b.name +
                  "' is connected to nothing: add a joint or a weld, or set "
                  "'fixed: true' (welded to the ground) or 'free: true' (floating)");
}

void SceneCompiler::ReadAnalysis(const Node* node, AnalysisSettings* a) {
  a->statics.time = a->start_time;
  if (node == nullptr || node->IsNull()) return;
  const std::string path = "analysis";
  r_.CheckKeys(*node, path,
               {"type", "start_time", "end_time", "step", "rho_inf", "tolerances", "max_iterations",
                "max_halvings", "align_steps", "static_preload", "load_steps", "rod_inertia",
                "newton", "predictor", "convergence", "restart_at_breakpoints"});
  auto find = [&](const char* key) { return node->Find(key); };
  if (const Node* t = find("type"))
    a->kind = r_.Enum<AnalysisKind>(*t, Join(path, "type"));
  if (const Node* t = find("start_time")) a->start_time = r_.Number(*t, Join(path, "start_time"));
  if (const Node* t = find("end_time")) {
    a->end_time = r_.Number(*t, Join(path, "end_time"));
    if (!(a->end_time > a->start_time))
      r_.Fail(t->location, Join(path, "end_time"), "expected end_time > start_time");
  } else if (!(a->end_time > a->start_time)) {
    r_.Fail(node->location, path, "start_time must be before end_time (default 1 s)");
  }
  if (const Node* t = find("step")) a->step = r_.PositiveNumber(*t, Join(path, "step"));
  if (a->kind == AnalysisKind::kDynamic && (a->end_time - a->start_time) / a->step > kMaxSteps)
    r_.Fail(find("step") != nullptr ? find("step")->location : node->location, Join(path, "step"),
            "more than 1e9 time steps from start_time to end_time");
  if (a->kind == AnalysisKind::kDynamic) {
    // Times so large that their doubles are coarser than the step (schedule.h).
    const std::string problem = TimeGridProblem(a->start_time, a->end_time, a->step);
    if (!problem.empty()) {
      const char* key = std::abs(a->start_time) > std::abs(a->end_time) ? "start_time" : "end_time";
      const Node* at = find(key) != nullptr ? find(key) : find("step") != nullptr ? find("step") : node;
      r_.Fail(at->location, Join(path, key), problem);
    }
  }
  if (const Node* t = find("rho_inf")) {
    a->dynamic.rho_inf = r_.Number(*t, Join(path, "rho_inf"));
    if (!(a->dynamic.rho_inf >= 0.0 && a->dynamic.rho_inf <= 1.0))
      r_.Fail(t->location, Join(path, "rho_inf"), "expected a spectral radius in [0, 1]");
  }
  if (const Node* t = find("tolerances")) {
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
  if (const Node* t = find("max_iterations"))
    a->dynamic.max_iterations = a->statics.max_iterations =
        r_.Integer(*t, Join(path, "max_iterations"), 1, kMaxNewtonIterations);
  if (const Node* t = find("max_halvings"))
    a->dynamic.max_halvings = a->statics.max_halvings =
        r_.Integer(*t, Join(path, "max_halvings"), 0, kMaxHalvings);
  if (const Node* t = find("newton"))
    a->dynamic.newton_matrix = r_.Enum<NewtonMatrix>(*t, Join(path, "newton"));
  if (const Node* t = find("predictor"))
    a->dynamic.predictor = r_.Enum<Predictor>(*t, Join(path, "predictor"));
  if (const Node* t = find("convergence"))
    a->dynamic.convergence = r_.Enum<ConvergenceTest>(*t, Join(path, "convergence"));
  if (const Node* t = find("load_steps"))
    a->statics.load_steps = r_.Integer(*t, Join(path, "load_steps"), 1, kMaxLoadSteps);
  if (const Node* t = find("align_steps")) a->align_steps = r_.Bool(*t, Join(path, "align_steps"));
  if (const Node* t = find("restart_at_breakpoints"))
    a->dynamic.restart_at_breakpoints = r_.Bool(*t, Join(path, "restart_at_breakpoints"));
  if (const Node* t = find("static_preload"))
    a->static_preload = r_.Bool(*t, Join(path, "static_preload"));
  // Statics evaluates the profiles at the end time (static analyses) or at the start time
  // (the preload of a dynamic analysis).
  a->statics.time = a->kind == AnalysisKind::kStatic ? a->end_time : a->start_time;
}

// A whole number of steps, about (end - start) / count long (one step at least).
double DefaultOutputInterval(const AnalysisSettings& a, int count) {
  if (a.kind == AnalysisKind::kStatic) return 0.0;
  const double steps = (a.end_time - a.start_time) / a.step;
  return a.step * std::max(1.0, std::round(steps / count));
}

void SceneCompiler::ReadOutputs(const Node* node, const Model& model,
                                const AnalysisSettings& analysis, OutputSpec* out) {
  out->interval = DefaultOutputInterval(analysis, kDefaultOutputRows);
  out->vtk_interval = DefaultOutputInterval(analysis, kDefaultVtkFrames);
  auto all_joints = [&] {
    out->joints.clear();
    for (std::size_t j = 0; j < model.joints.size(); ++j)
      if (model.joints[j].k() > 0)
        out->joints.push_back({model.joints[j].name, static_cast<int>(j)});
  };
  all_joints();
  if (node == nullptr || node->IsNull()) return;
  const std::string path = "outputs";
  r_.CheckKeys(*node, path, {"points", "joints", "interval", "vtk", "vtk_interval"});
  if (const Node* pts = node->Find("points")) {
    const std::string pp = Join(path, "points");
    r_.CheckNames(*pts, pp, "output point");
    for (const auto& [entry, value] : pts->entries) {
      const std::string p = Join(pp, entry.key);
      r_.CheckKeys(value, p, {"body", "at", "rod", "s"});
      OutputPoint op;
      op.name = entry.key;
      const Node* bn = value.Find("body");
      const Node* rn = value.Find("rod");
      if (bn != nullptr && rn != nullptr)
        r_.Fail(rn->location, Join(p, "rod"), "give either {body, at} or {rod, s}, not both");
      if (bn == nullptr && rn == nullptr)
        r_.Fail(value.location, p, "missing key 'body' (with 'at') or 'rod' (with 's')");
      if (bn != nullptr) {
        NotUsedBy(value, p, {"s"}, "body points (use 'rod' and 's' for a point along a rod)");
        BodyEntry& body = Body(*bn, Join(p, "body"));
        const Node& an = r_.Require(value, p, "at");
        const Vec3 at = Point(an, Join(p, "at"));
        if (body.rigid) {
          op.node = body.frame_node;
          op.offset = at - body.origin;
        } else {
          op.node = RodNodeAt(body, at, an.location, Join(p, "at"), "output point");
        }
      } else {
        NotUsedBy(value, p, {"at"}, "rod points (use 'body' and 'at' for a node point)");
        BodyEntry& body = Body(*rn, Join(p, "rod"));
        if (body.rigid)
          r_.Fail(rn->location, Join(p, "rod"),
                  "'" + body.name + "' is a rigid body; use {body: " + body.name + ", at: POINT}");
        const Node& sn = r_.Require(value, p, "s");
        op.rod = body.index;
        op.arc_length = r_.NonNegativeNumber(sn, Join(p, "s"));
        const double length = model.rods[static_cast<std::size_t>(op.rod)].length;
        if (op.arc_length > length * (1.0 + 1e-12)) {
          std::ostringstream s;
          s.precision(9);
          s << "arc length beyond the end of the rod (length " << length << " m)";
          r_.Fail(sn.location, Join(p, "s"), s.str());
        }
      }
      out->points.push_back(op);
    }
  }
  if (const Node* jn = node->Find("joints")) {
    const std::string jp = Join(path, "joints");
    if (jn->IsScalar() && (jn->scalar == "all" || jn->scalar == "none")) {
      if (jn->scalar == "none") out->joints.clear();
    } else if (jn->IsSequence()) {
      out->joints.clear();
      std::vector<std::string> names;
      for (const Joint& j : model.joints) names.push_back(j.name);
      for (std::size_t i = 0; i < jn->items.size(); ++i) {
        const Node& item = jn->items[i];
        const std::string ip = jp + "[" + std::to_string(i) + "]";
        const std::string name = r_.Text(item, ip);
        const int index = model.FindJoint(name);
        if (index < 0)
          r_.Fail(item.location, ip,
                  "undefined joint '" + name + "'" + scene_yaml::DidYouMean(name, names));
        if (model.joints[static_cast<std::size_t>(index)].k() == 0)
          r_.Fail(item.location, ip,
                  "joint '" + name + "' is fixed: it has no coordinates to record");
        for (const OutputJoint& o : out->joints)
          if (o.joint == index) r_.Fail(item.location, ip, "joint '" + name + "' is listed twice");
        out->joints.push_back({name, index});
      }
    } else {
      r_.Fail(jn->location, jp,
              "expected 'all', 'none' or a list of joint names, got " + scene_yaml::Describe(*jn));
    }
  }
  if (const Node* v = node->Find("interval"))
    out->interval = r_.NonNegativeNumber(*v, Join(path, "interval"));
  if (const Node* v = node->Find("vtk")) out->vtk = r_.Bool(*v, Join(path, "vtk"));
  if (const Node* v = node->Find("vtk_interval"))
    out->vtk_interval = r_.NonNegativeNumber(*v, Join(path, "vtk_interval"));
  else if (node->Find("interval") != nullptr)
    out->vtk_interval = 0.0;  // the same as the given interval
}

void SceneCompiler::RethrowBuildError(const InputError& e) const {
  const std::string msg = e.what();
  auto mentions = [&](const std::string& name) {
    return msg.find("'" + name + "'") != std::string::npos ||
           msg.find("'" + name + ".") != std::string::npos;
  };
  for (const EntityLocation& j : joint_locations_) {
    const std::string name = j.path.substr(j.path.find('.') + 1);
    if (mentions(name)) r_.Fail(j.location, j.path, msg);
  }
  for (const BodyEntry& b : bodies_)
    if (mentions(b.name)) r_.Fail(b.location, b.path, msg);
  throw InputError(r_.source() + ": " + msg);
}

Scene SceneCompiler::Compile(const Node& root, const std::string& default_name) {
  if (!root.IsMap())
    r_.Fail(root.location, "",
            "a scene is a map of sections (points:, sections:, bodies:, joints:, ...), got " +
                scene_yaml::Describe(root));
  r_.CheckKeys(root, "",
               {"name", "description", "units", "gravity", "defaults", "points", "materials",
                "sections", "bodies", "joints", "loads", "analysis", "outputs"});
  Scene scene;
  scene.source = r_.source();
  scene.name = default_name;
  if (const Node* n = root.Find("name")) scene.name = r_.Text(*n, "name");
  if (const Node* d = root.Find("description"))
    if (!d->IsScalar())
      r_.Fail(d->location, "description", "expected text, got " + scene_yaml::Describe(*d));
  ReadUnits(root);
  if (const Node* g = root.Find("gravity")) builder_.SetGravity(r_.Vector3(*g, "gravity"));
  ReadDefaults(root.Find("defaults"));
  ReadPoints(root.Find("points"));
  ReadMaterials(root.Find("materials"));
  ReadSections(root.Find("sections"));
  ReadBodies(root.Find("bodies"));
  if (bodies_.empty()) r_.Fail(root.location, "bodies", "the scene has no bodies");
  ReadJoints(root.Find("joints"));
  ReadLoads(root.Find("loads"));
  CheckConnections();
  ReadAnalysis(root.Find("analysis"), &scene.analysis);
  if (const Node* a = root.Find("analysis"); a != nullptr && a->Find("rod_inertia") != nullptr)
    builder_.model().rod_inertia = r_.Enum<RodInertia>(*a->Find("rod_inertia"), "analysis.rod_inertia");
  try {
    scene.model = builder_.Build();
  } catch (const InputError& e) {
    RethrowBuildError(e);
  }
  ReadOutputs(root.Find("outputs"), scene.model, scene.analysis, &scene.outputs);
  scene.named_points = points_;
  return scene;
}

std::string Stem(const std::string& source) {
  const std::string stem = std::filesystem::path(source).stem().string();
  return stem.empty() ? source : stem;
}

}  // namespace

Scene ParseScene(const std::string& yaml_text, const std::string& source_name,
                 const std::vector<std::string>& overrides) {
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
  SceneCompiler compiler(source_name);
  return compiler.Compile(root, Stem(source_name));
}

Scene LoadScene(const std::string& path, const std::vector<std::string>& overrides) {
  if (path.find('\0') != std::string::npos)
    throw InputError("scene path '" + std::string(path.c_str()) +
                     "...': contains a NUL character (not a file name)");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path + ": is a directory, not a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the scene file");
  // Bounded reads: a file without a size (/dev/zero, a pipe) stops at the limit.
  std::string text;
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxSceneBytes)
      throw InputError(path + ": the scene file is larger than " +
                       std::to_string(kMaxSceneBytes >> 20) + " MiB (the limit)");
  }
  if (in.bad()) throw InputError(path + ": cannot read the scene file");
  return ParseScene(text, path, overrides);
}

}  // namespace screwfem
