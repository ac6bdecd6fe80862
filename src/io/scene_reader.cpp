// The scene reader (docs/architecture.md, "Scenes"): YAML text -> document tree (scene_yaml.cpp)
// -> overrides -> a SceneSpec and the source of each entity (scene_spec.h). It checks what the
// text alone decides (keys, types, ranges, names); the compiler (scene_compiler.cpp) checks what
// needs the model's geometry. Every message names the file, line, column and field.
// This file holds the values, the file's core sections, bodies and joints, and the entry point;
// scene_reader_items.cpp and scene_reader_analysis.cpp the rest (scene_reader_impl.h).
#include <Eigen/Cholesky>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <unordered_map>

#include "scene_reader_impl.h"
#include "scene_yaml.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/schedule.h"

namespace screwfem {

namespace scene_reading {

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

// parameters: {NAME: NUMBER or EXPRESSION, ...}: named values every number of the scene may use;
// each may use the parameters above it. `--set parameters.NAME=VALUE` changes one; an override
// cannot add one (a misspelt name would otherwise change nothing).
void SceneReader::ReadParameters(const Node* node) {
  r_.SetParameters(&parameters_);
  if (node == nullptr || node->IsNull()) return;
  r_.CheckNames(*node, "parameters", "parameter");
  for (const auto& [entry, value] : node->entries) {
    const std::string path = Join("parameters", entry.key);
    if (!(std::isalpha(static_cast<unsigned char>(entry.key[0])) || entry.key[0] == '_') ||
        entry.key.find('-') != std::string::npos)
      r_.Fail(entry.key_location, path,
              "a parameter name starts with a letter or '_' and holds only letters, digits and "
              "'_' (it is used in expressions)");
    if (scene_yaml::IsReservedExpressionName(entry.key))
      r_.Fail(entry.key_location, path,
              "'" + entry.key + "' is a constant or function of expressions; choose another name");
    if (entry.key_location.override_text != nullptr) {
      std::vector<std::string> known;
      for (const auto& [e, v] : node->entries)
        if (e.key_location.override_text == nullptr) known.push_back(e.key);
      r_.Fail(entry.key_location, path,
              "the scene has no parameter '" + entry.key + "'" +
                  scene_yaml::UnknownNameHint(entry.key, known) +
                  " (an override can change a parameter, not add one)");
    }
    parameters_.emplace_back(entry.key, r_.Number(value, path));
  }
}

void SceneReader::ReadUnits(const Node& root) {
  const Node* units = root.Find("units");
  if (units == nullptr) return;
  if (!units->IsScalar() || units->scalar != "SI")
    r_.Fail(units->location, "units",
            "only SI units are supported (m, kg, s, N, rad), got " + scene_yaml::Describe(*units));
}

void SceneReader::ReadDefaults(const Node* node) {
  if (node == nullptr || node->IsNull()) return;
  r_.CheckKeys(*node, "defaults", {"elements", "up", "conform_mesh"});
  if (const Node* c = node->Find("conform_mesh"))
    spec_.conform_mesh = r_.Bool(*c, "defaults.conform_mesh");
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
  // (After the robots' links: robots: is read first.)
  const std::size_t first = spec_.bodies.size() - values.size();
  for (std::size_t i = 0; i < values.size(); ++i) {
    BodySpec& b = spec_.bodies[first + i];
    EntitySource& source = src_.bodies[first + i];
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

void SceneReader::Read(const Node& root, const std::string& default_name) {
  src_.root = Field(root.location, "");
  if (!root.IsMap())
    r_.Fail(root.location, "",
            "a scene is a map of sections (points:, sections:, bodies:, joints:, ...), got " +
                scene_yaml::Describe(root));
  r_.CheckKeys(root, "", {"name",     "description", "parameters", "units",    "gravity",
                          "defaults", "points",      "materials",  "sections", "bodies",
                          "joints",   "loads",       "tendons",    "forces",   "analysis",
                          "outputs",  "inputs",      "actuation",  "contact",  "robots"});
  ReadParameters(root.Find("parameters"));
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
  ReadRobots(root.Find("robots"));
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

}  // namespace scene_reading

namespace {

// Maps of named entries: an override may not walk through an entry that does not exist.
const std::vector<std::string> kCollections = {
    "points",  "materials", "sections",       "bodies", "joints",    "loads",
    "tendons", "forces",    "outputs.points", "inputs", "actuation", "robots"};

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
  scene_reading::SceneReader(source_name, &spec, sources).Read(root, Stem(source_name));
  return spec;
}

}  // namespace screwfem
