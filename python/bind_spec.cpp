// The scene spec (include/screwfem/io/scene_spec.h) from Python: the conversions between the
// C++ SceneSpec and screwfem.SceneSpec (python/screwfem/_spec.py, plain Python dataclasses
// with the C++ field names), ReadSceneSpec and CompileScene. The Python objects are converted
// as a whole when a spec is compiled (and one entity at a time when an adder checks it), so
// a Python spec can hold references to its entities safely; every value is checked here, with
// messages "SOURCE: FIELD: what was expected" that name the entity and the field
// ("<python spec>: bodies.arm.path[1]: expected [x, y, z] (3 numbers), got 2").
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bind.h"
#include "screwfem/elements/joint.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/io/urdf.h"
#include "screwfem/model/errors.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {

constexpr int kMaxElements = 100000;         // per rod (or path segment), as in scene files
constexpr long kMaxTotalElements = 1000000;  // all rods of a scene
const char* const kGroundName = "ground";

// The Python classes of screwfem/_spec.py.
py::object SpecClass(const char* name) { return py::module_::import("screwfem._spec").attr(name); }

std::string Describe(py::handle v) {
  std::string s = py::repr(v).cast<std::string>();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::string Join(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) s += (i == 0 ? "" : ", ") + names[i];
  return s;
}

// ---- Python -> C++ ------------------------------------------------------------------------

// Reads a screwfem.SceneSpec (or one of its entities) into the C++ structs.
class SpecReader {
 public:
  SpecReader(py::handle spec, std::string source) : spec_(spec), source_(std::move(source)) {
    const py::list bodies = List(Attr(spec_, "bodies", ""), "bodies");
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      body_names_.push_back(OptionalName(bodies[b]));
      body_rigid_.push_back(
          Bool(Attr(bodies[b], "rigid", "bodies"), Index("bodies", b) + ".rigid"));
    }
  }

  SceneSpec Read();
  // Checks one entity of a collection ("bodies", "joints", ..., "outputs.points").
  void Check(const std::string& collection, int index);

 private:
  [[noreturn]] void Fail(const std::string& field, const std::string& what) const {
    throw InputError(source_ + ": " + (field.empty() ? "" : field + ": ") + what);
  }
  static std::string Index(const std::string& path, std::size_t i) {
    return path + "[" + std::to_string(i) + "]";
  }
  static std::string Key(const std::string& path, const char* key) {
    return path.empty() ? key : path + "." + key;
  }
  py::object Attr(py::handle obj, const char* key, const std::string& path) const {
    if (!py::hasattr(obj, key))
      Fail(path, "expected an object with the attribute '" + std::string(key) + "', got " +
                     Describe(obj));
    return obj.attr(key);
  }
  static std::string OptionalName(py::handle obj) {
    if (!py::hasattr(obj, "name")) return {};
    const py::object n = obj.attr("name");
    return py::isinstance<py::str>(n) ? n.cast<std::string>() : std::string{};
  }
  // "collection.NAME", or "collection[i]" without a name.
  std::string EntityPath(const std::string& collection, py::handle obj, std::size_t i) const {
    const std::string name = OptionalName(obj);
    return name.empty() ? Index(collection, i) : collection + "." + name;
  }

  // Values.
  double Number(py::handle v, const std::string& f) const;
  double NonNegative(py::handle v, const std::string& f) const {
    const double x = Number(v, f);
    if (!(x >= 0.0)) Fail(f, "expected a number >= 0, got " + Describe(v));
    return x;
  }
  double Positive(py::handle v, const std::string& f) const {
    const double x = Number(v, f);
    if (!(x > 0.0)) Fail(f, "expected a positive number, got " + Describe(v));
    return x;
  }
  int Integer(py::handle v, const std::string& f, long min, long max) const;
  bool Bool(py::handle v, const std::string& f) const {
    if (!py::isinstance<py::bool_>(v)) Fail(f, "expected True or False, got " + Describe(v));
    return v.cast<bool>();
  }
  std::string Text(py::handle v, const std::string& f) const {
    if (!py::isinstance<py::str>(v)) Fail(f, "expected a string, got " + Describe(v));
    return v.cast<std::string>();
  }
  py::list List(py::handle v, const std::string& f) const {
    if (py::isinstance<py::str>(v) || !py::isinstance<py::sequence>(v))
      Fail(f, "expected a list, got " + Describe(v));
    return py::list(py::reinterpret_borrow<py::sequence>(v));
  }
  std::vector<double> Numbers(py::handle v, const std::string& f) const {
    if (py::isinstance<py::str>(v) || !py::isinstance<py::sequence>(v))
      Fail(f, "expected a list of numbers, got " + Describe(v));
    const py::list items = List(v, f);
    std::vector<double> out;
    for (std::size_t i = 0; i < items.size(); ++i) out.push_back(Number(items[i], Index(f, i)));
    return out;
  }
  std::vector<double> FixedNumbers(py::handle v, const std::string& f, std::size_t n,
                                   const char* form) const {
    std::vector<double> x = Numbers(v, f);
    if (x.size() != n)
      Fail(f, std::string("expected ") + form + " (" + std::to_string(n) + " numbers), got " +
                  std::to_string(x.size()));
    return x;
  }
  Vec3 Vector3(py::handle v, const std::string& f) const {
    const std::vector<double> x = FixedNumbers(v, f, 3, "[x, y, z]");
    return Vec3(x[0], x[1], x[2]);
  }
  Vec6 Vector6(py::handle v, const std::string& f) const {
    const std::vector<double> x = FixedNumbers(v, f, 6, "6 values");
    Vec6 out;
    for (int i = 0; i < 6; ++i) out(i) = x[static_cast<std::size_t>(i)];
    return out;
  }
  Mat3 Inertia(py::handle v, const std::string& f) const;
  Profile ReadProfile(py::handle v, const std::string& f) const {
    if (py::isinstance<Profile>(v)) return v.cast<Profile>();
    if (py::isinstance<py::bool_>(v) || !PyNumber_Check(v.ptr()))
      Fail(f, "expected a Profile or a number (a constant), got " + Describe(v));
    return Profile::Constant(Number(v, f));
  }
  template <class T>
  T Object(py::handle v, const std::string& f, const char* what) const {
    if (!py::isinstance<T>(v)) Fail(f, std::string("expected a ") + what + ", got " + Describe(v));
    return v.cast<T>();
  }
  // A value of an enum with a vocabulary: the Python enum or its name ("world").
  template <class E>
  E Enum(py::handle v, const std::string& f) const {
    if (py::isinstance<E>(v)) return v.cast<E>();  // checked (bind.h)
    if (py::isinstance<py::str>(v))
      if (const auto e = EnumFromName<E>(v.cast<std::string>())) return *e;
    Fail(f, "expected one of " + Join(EnumNameList<E>()) + ", got " + Describe(v));
  }
  JointType ReadJointType(py::handle v, const std::string& f) const {
    if (py::isinstance<JointType>(v)) return v.cast<JointType>();
    if (py::isinstance<py::str>(v))
      if (const JointTypeInfo* info = FindJointType(v.cast<std::string>())) return info->type;
    Fail(f, "expected a JointType or one of " + Join(JointTypeNameList()) + ", got " + Describe(v));
  }
  // A body: its index or name; -1 (or "ground") for the ground where allowed.
  int Body(py::handle v, const std::string& f, bool ground) const;
  bool Soft(int b) const { return b >= 0 && !body_rigid_[static_cast<std::size_t>(b)]; }
  // A name that is a non-empty string, once in its collection (`others`, the entity at
  // `self` excluded).
  std::string UniqueName(py::handle obj, const std::string& path, const py::list& others,
                         std::size_t self, const char* what, bool required = true) const;

  // Entities. `path` is the entity's field ("bodies.arm").
  BodySpec ReadBody(py::handle obj, const std::string& path, std::size_t index) const;
  JointEntrySpec ReadJoint(py::handle obj, const std::string& path) const;
  LoadSpec ReadLoad(py::handle obj, const std::string& path) const;
  BodyPointSpec ReadBodyPoint(py::handle obj, const std::string& path) const;
  TendonSpec ReadTendon(py::handle obj, const std::string& path) const;
  ForceSpec ReadForce(py::handle obj, const std::string& path) const;
  ActuatorSpec ReadActuator(py::handle obj, const std::string& path) const;
  OutputPointSpec ReadOutputPoint(py::handle obj, const std::string& path) const;
  ContactSpec ReadContact(py::handle obj, const std::string& path) const;
  OutputsSpec ReadOutputs(py::handle obj, const std::string& path) const;
  // A named collection (a dict, or a list of (name, value) pairs), in order.
  std::vector<std::pair<std::string, py::object>> NamedValues(py::handle v,
                                                              const std::string& f) const;
  // The entities of a collection: `read(obj, path, i)` per item; names checked.
  template <typename T, typename F>
  std::vector<T> Collection(const py::list& items, const std::string& collection, const char* what,
                            bool names_required, F read) const {
    std::vector<T> out;
    for (std::size_t i = 0; i < items.size(); ++i) {
      const std::string path = EntityPath(collection, items[i], i);
      UniqueName(items[i], path, items, i, what, names_required);
      out.push_back(read(items[i], path, i));
    }
    return out;
  }

  py::handle spec_;
  std::string source_;
  std::vector<std::string> body_names_;
  std::vector<bool> body_rigid_;
};

double SpecReader::Number(py::handle v, const std::string& f) const {
  if (v.is_none() || py::isinstance<py::bool_>(v) || py::isinstance<py::str>(v) ||
      !PyNumber_Check(v.ptr()))
    Fail(f, "expected a number, got " + Describe(v));
  const double x = PyFloat_AsDouble(v.ptr());
  if (x == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    Fail(f, "expected a real number, got " + Describe(v));
  }
  if (!std::isfinite(x)) Fail(f, "expected a finite number, got " + Describe(v));
  return x;
}

int SpecReader::Integer(py::handle v, const std::string& f, long min, long max) const {
  if (py::isinstance<py::bool_>(v) || !PyIndex_Check(v.ptr()))
    Fail(f, "expected an integer, got " + Describe(v));
  const long x = PyLong_AsLong(v.ptr());
  if (x == -1 && PyErr_Occurred()) {
    PyErr_Clear();
    Fail(f, "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) +
                "], got " + Describe(v));
  }
  if (x < min || x > max)
    Fail(f, "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) +
                "], got " + std::to_string(x));
  return static_cast<int>(x);
}

// Three principal moments, nine numbers row by row, or a 3x3 matrix; symmetric positive
// definite (as the scene's `inertia`).
Mat3 SpecReader::Inertia(py::handle v, const std::string& f) const {
  const py::list rows = List(v, f);
  Mat3 J = Mat3::Zero();
  if (rows.size() == 3 && py::isinstance<py::sequence>(rows[0]) &&
      !py::isinstance<py::str>(rows[0])) {
    for (int i = 0; i < 3; ++i)
      J.row(i) = Vector3(rows[static_cast<std::size_t>(i)], Index(f, static_cast<std::size_t>(i)))
                     .transpose();
  } else if (rows.size() == 9) {
    const std::vector<double> x = Numbers(v, f);
    for (int i = 0; i < 9; ++i) J(i / 3, i % 3) = x[static_cast<std::size_t>(i)];
  } else if (rows.size() == 3) {
    const Vec3 d = Vector3(v, f);
    if (!(d.minCoeff() > 0.0)) Fail(f, "principal moments of inertia must be positive");
    J = d.asDiagonal();
  } else {
    Fail(f, "expected 3 principal moments [Jxx, Jyy, Jzz], 9 numbers or a 3x3 matrix, got " +
                Describe(v));
  }
  if ((J - J.transpose()).norm() > 1e-12 * std::max(1e-300, J.norm()))
    Fail(f, "the inertia matrix must be symmetric");
  if (Eigen::LLT<Mat3>(J).info() != Eigen::Success || !(J.determinant() > 0.0))
    Fail(f, "the inertia matrix must be positive definite");
  return J;
}

int SpecReader::Body(py::handle v, const std::string& f, bool ground) const {
  const int n = static_cast<int>(body_names_.size());
  if (py::isinstance<py::str>(v)) {
    const std::string name = v.cast<std::string>();
    if (ground && name == kGroundName) return -1;
    for (int b = 0; b < n; ++b)
      if (body_names_[static_cast<std::size_t>(b)] == name) return b;
    Fail(f, "undefined body '" + name + "'" +
                (body_names_.empty() ? std::string(" (the spec has no bodies)")
                                     : " (known: " + Join(body_names_) + ")"));
  }
  if (py::isinstance<py::bool_>(v) || !PyIndex_Check(v.ptr()))
    Fail(f, "expected a body index or name, got " + Describe(v));
  const long b = PyLong_AsLong(v.ptr());
  if (b == -1 && ground) return -1;
  if (b < 0 || b >= n)
    Fail(f, "no body " + std::to_string(b) + " (the spec has " + std::to_string(n) + ")" +
                (ground ? "; -1 is the ground" : ""));
  return static_cast<int>(b);
}

std::string SpecReader::UniqueName(py::handle obj, const std::string& path, const py::list& others,
                                   std::size_t self, const char* what, bool required) const {
  const std::string name = Text(Attr(obj, "name", path), Key(path, "name"));
  if (name.empty()) {
    if (required) Fail(path, std::string("a ") + what + " needs a name");
    return name;
  }
  for (std::size_t i = 0; i < others.size(); ++i)
    if (i != self && OptionalName(others[i]) == name)
      Fail(path, std::string("duplicate ") + what + " name '" + name + "'");
  return name;
}

BodySpec SpecReader::ReadBody(py::handle obj, const std::string& path, std::size_t index) const {
  const auto get = [&](const char* key) { return Attr(obj, key, path); };
  const auto f = [&](const char* key) { return Key(path, key); };
  BodySpec b;
  b.name = Text(get("name"), f("name"));
  if (b.name == kGroundName) Fail(f("name"), "'ground' is reserved for the world frame");
  b.rigid = Bool(get("rigid"), f("rigid"));
  b.free = Bool(get("free"), f("free"));
  b.fixed = Bool(get("fixed"), f("fixed"));
  if (b.fixed && b.free) Fail(f("free"), "a body cannot be both fixed and free");
  b.origin = Vector3(get("origin"), f("origin"));
  b.com = Vector3(get("com"), f("com"));
  b.has_initial_velocity = Bool(get("has_initial_velocity"), f("has_initial_velocity"));
  b.initial_linear = Vector3(get("initial_linear"), f("initial_linear"));
  b.initial_angular = Vector3(get("initial_angular"), f("initial_angular"));
  const py::list path_points = List(get("path"), f("path"));
  for (std::size_t i = 0; i < path_points.size(); ++i)
    b.path.push_back(Vector3(path_points[i], Index(f("path"), i)));
  b.elements = Integer(get("elements"), f("elements"), 1, kMaxElements);
  b.section = Object<Section>(get("section"), f("section"), "Section");
  b.up = Vector3(get("up"), f("up"));
  if (!(b.up.norm() > 0.0)) Fail(f("up"), "the vector is zero");
  for (const char* key : {"weld_start", "weld_end"}) {
    int& weld = key[5] == 's' ? b.weld_start : b.weld_end;
    const py::object w = get(key);
    weld = w.is_none() ? -1 : Body(w, f(key), true);
    if (weld >= 0 && (b.rigid || !Soft(weld) || weld >= static_cast<int>(index)))
      Fail(f(key), "'" + body_names_[static_cast<std::size_t>(weld)] +
                       "' must be a soft body added earlier (to weld to a rigid body, use a "
                       "joint of type fixed)");
  }
  b.contact_radius = NonNegative(get("contact_radius"), f("contact_radius"));
  b.visual_radius = NonNegative(get("visual_radius"), f("visual_radius"));
  if (b.rigid && b.visual_radius > 0.0)
    Fail(f("visual_radius"),
         "rigid bodies are drawn as their shapes (visual_radius is for soft bodies)");
  const py::list shapes = List(get("shapes"), f("shapes"));
  for (std::size_t i = 0; i < shapes.size(); ++i)
    b.shapes.push_back(Object<ContactShape>(shapes[i], Index(f("shapes"), i), "ContactShape"));
  b.contype = static_cast<unsigned>(Integer(get("contype"), f("contype"), 0, 1L << 30));
  b.conaffinity = static_cast<unsigned>(Integer(get("conaffinity"), f("conaffinity"), 0, 1L << 30));
  if (b.rigid) {
    b.mass = Positive(get("mass"), f("mass"));
    b.inertia = Inertia(get("inertia"), f("inertia"));
    if (b.fixed && b.has_initial_velocity)
      Fail(f("has_initial_velocity"), "a fixed body cannot have an initial velocity");
    if (!b.path.empty()) Fail(f("path"), "rigid bodies have no path (it is for soft bodies)");
  } else {
    b.mass = Number(get("mass"), f("mass"));
    b.inertia = Inertia(get("inertia"), f("inertia"));
    if (b.path.size() < 2)
      Fail(f("path"),
           "a soft body needs a path of at least two points, got " + std::to_string(b.path.size()));
    if (b.fixed) Fail(f("fixed"), "soft bodies are clamped to the ground by a joint of type fixed");
    if (b.has_initial_velocity)
      Fail(f("has_initial_velocity"), "soft bodies take no initial velocity of their own");
  }
  return b;
}

JointEntrySpec SpecReader::ReadJoint(py::handle obj, const std::string& path) const {
  JointEntrySpec j;
  j.body_a = Body(Attr(obj, "body_a", path), Key(path, "body_a"), true);
  j.body_b = Body(Attr(obj, "body_b", path), Key(path, "body_b"), true);
  if (j.body_a < 0 && j.body_b < 0) Fail(Key(path, "body_b"), "both sides are the ground");
  if (j.body_a == j.body_b)
    Fail(Key(path, "body_b"),
         "both sides are the same body '" + body_names_[static_cast<std::size_t>(j.body_a)] + "'");
  j.joint = Object<JointSpec>(Attr(obj, "joint", path), Key(path, "joint"), "JointSpec");
  return j;
}

LoadSpec SpecReader::ReadLoad(py::handle obj, const std::string& path) const {
  const auto get = [&](const char* key) { return Attr(obj, key, path); };
  const auto f = [&](const char* key) { return Key(path, key); };
  LoadSpec l;
  l.name = Text(get("name"), f("name"));
  l.body = Body(get("body"), f("body"), false);
  const py::object where = get("where");
  const std::string w = py::isinstance<py::str>(where) ? where.cast<std::string>() : "";
  if (w == "at")
    l.where = LoadSpec::Where::kAt;
  else if (w == "s")
    l.where = LoadSpec::Where::kArcLength;
  else if (w == "distributed")
    l.where = LoadSpec::Where::kDistributed;
  else
    Fail(f("where"), "expected 'at', 's' or 'distributed', got " + Describe(where));
  if (l.where != LoadSpec::Where::kAt && !Soft(l.body))
    Fail(f("where"), "'s' and 'distributed' apply to soft bodies only");
  l.at = Vector3(get("at"), f("at"));
  l.arc_length = NonNegative(get("arc_length"), f("arc_length"));
  l.frame = Enum<LoadFrame>(get("frame"), f("frame"));
  l.force = Vector3(get("force"), f("force"));
  l.moment = Vector3(get("moment"), f("moment"));
  l.profile = ReadProfile(get("profile"), f("profile"));
  return l;
}

BodyPointSpec SpecReader::ReadBodyPoint(py::handle obj, const std::string& path) const {
  const auto get = [&](const char* key) { return Attr(obj, key, path); };
  const auto f = [&](const char* key) { return Key(path, key); };
  BodyPointSpec p;
  p.body = Body(get("body"), f("body"), true);
  p.along_rod = Bool(get("along_rod"), f("along_rod"));
  p.at = Vector3(get("at"), f("at"));
  p.arc_length = NonNegative(get("arc_length"), f("arc_length"));
  p.offset = Vector3(get("offset"), f("offset"));
  p.routed = Bool(get("routed"), f("routed"));
  if (p.routed) {
    if (!Soft(p.body)) Fail(f("body"), "a route runs along a soft body");
    const py::handle route = get("route");
    if (!py::isinstance<RodRoute>(route))
      Fail(f("route"), "expected a RodRoute, got " + py::repr(route).cast<std::string>());
    p.route = route.cast<RodRoute>();
    return p;
  }
  if (!Soft(p.body)) {
    const std::string who = p.body < 0 ? "the ground" : "rigid bodies";
    if (p.along_rod) Fail(f("along_rod"), "'s' is not used by " + who + " (give the point 'at')");
    if (!p.offset.isZero(0.0)) Fail(f("offset"), "'offset' is not used by " + who);
  }
  return p;
}

TendonSpec SpecReader::ReadTendon(py::handle obj, const std::string& path) const {
  TendonSpec t;
  t.name = Text(Attr(obj, "name", path), Key(path, "name"));
  const py::list eyelets = List(Attr(obj, "eyelets", path), Key(path, "eyelets"));
  const bool routed = std::any_of(eyelets.begin(), eyelets.end(), [](py::handle e) {
    return py::hasattr(e, "routed") && py::bool_(e.attr("routed"));
  });
  if (eyelets.empty() || (eyelets.size() < 2 && !routed))
    Fail(Key(path, "eyelets"), "expected at least two eyelets (a tendon runs between them), got " +
                                   std::to_string(eyelets.size()));
  for (std::size_t i = 0; i < eyelets.size(); ++i)
    t.eyelets.push_back(ReadBodyPoint(eyelets[i], Index(Key(path, "eyelets"), i)));
  t.tension = ReadProfile(Attr(obj, "tension", path), Key(path, "tension"));
  t.by_length = Bool(Attr(obj, "by_length", path), Key(path, "by_length"));
  t.length = ReadProfile(Attr(obj, "length", path), Key(path, "length"));
  return t;
}

ForceSpec SpecReader::ReadForce(py::handle obj, const std::string& path) const {
  const auto get = [&](const char* key) { return Attr(obj, key, path); };
  const auto f = [&](const char* key) { return Key(path, key); };
  ForceSpec s;
  s.name = Text(get("name"), f("name"));
  s.a = ReadBodyPoint(get("a"), f("a"));
  s.b = ReadBodyPoint(get("b"), f("b"));
  s.stiffness = NonNegative(get("stiffness"), f("stiffness"));
  s.damping = NonNegative(get("damping"), f("damping"));
  s.rest_length = Number(get("rest_length"), f("rest_length"));
  s.actuator = ReadProfile(get("actuator"), f("actuator"));
  return s;
}

ActuatorSpec SpecReader::ReadActuator(py::handle obj, const std::string& path) const {
  const auto get = [&](const char* key) { return Attr(obj, key, path); };
  const auto f = [&](const char* key) { return Key(path, key); };
  ActuatorSpec a;
  a.name = Text(get("name"), f("name"));
  a.type = Enum<ActuatorType>(get("type"), f("type"));
  a.body = Body(get("body"), f("body"), false);
  if (!Soft(a.body))
    Fail(f("body"), "'" + body_names_[static_cast<std::size_t>(a.body)] +
                        "' is a rigid body; actuation acts on soft bodies (rods)");
  a.from = NonNegative(get("from_"), f("from_"));
  a.to = Number(get("to"), f("to"));
  if (a.to >= 0.0 && !(a.to > a.from))
    Fail(f("to"), "expected an arc length greater than 'from' (or < 0: the rod's end)");
  a.area = NonNegative(get("area"), f("area"));
  a.offset = Vector3(get("offset"), f("offset"));
  a.max_stress = NonNegative(get("max_stress"), f("max_stress"));
  a.vector = Vector6(get("vector"), f("vector"));
  a.profile = ReadProfile(get("profile"), f("profile"));
  return a;
}

OutputPointSpec SpecReader::ReadOutputPoint(py::handle obj, const std::string& path) const {
  OutputPointSpec p;
  p.name = Text(Attr(obj, "name", path), Key(path, "name"));
  p.body = Body(Attr(obj, "body", path), Key(path, "body"), false);
  p.along_rod = Bool(Attr(obj, "along_rod", path), Key(path, "along_rod"));
  if (p.along_rod && !Soft(p.body))
    Fail(Key(path, "along_rod"), "a point along a rod needs a soft body");
  p.at = Vector3(Attr(obj, "at", path), Key(path, "at"));
  p.arc_length = NonNegative(Attr(obj, "arc_length", path), Key(path, "arc_length"));
  return p;
}

ContactSpec SpecReader::ReadContact(py::handle obj, const std::string& path) const {
  ContactSpec c;
  c.present = Bool(Attr(obj, "present", path), Key(path, "present"));
  c.settings = Object<ContactSettings>(Attr(obj, "settings", path), Key(path, "settings"),
                                       "ContactSettings");
  const py::list obstacles = List(Attr(obj, "obstacles", path), Key(path, "obstacles"));
  std::vector<std::string> names;
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    c.obstacles.push_back(
        Object<ContactObstacle>(obstacles[i], Index(Key(path, "obstacles"), i), "ContactObstacle"));
    names.push_back(c.obstacles.back().name);
  }
  const auto pairs = [&](const char* key, bool bodies) {
    std::vector<std::pair<int, int>> out;
    const py::list items = List(Attr(obj, key, path), Key(path, key));
    for (std::size_t i = 0; i < items.size(); ++i) {
      const std::string f = Index(Key(path, key), i);
      const py::list pair = List(items[i], f);
      if (pair.size() != 2) Fail(f, "expected a pair, got " + Describe(items[i]));
      const int a = Body(pair[0], Index(f, 0), false);
      int b = -1;
      if (bodies) {
        b = Body(pair[1], Index(f, 1), false);
        if (a == b) Fail(f, "a body cannot be excluded from itself");
      } else if (py::isinstance<py::str>(pair[1])) {
        const auto it = std::find(names.begin(), names.end(), pair[1].cast<std::string>());
        if (it == names.end()) Fail(Index(f, 1), "undefined obstacle " + Describe(pair[1]));
        b = static_cast<int>(it - names.begin());
      } else {
        b = Integer(pair[1], Index(f, 1), 0, static_cast<long>(names.size()) - 1);
      }
      out.emplace_back(a, b);
    }
    return out;
  };
  c.exclude = pairs("exclude", false);
  c.exclude_bodies = pairs("exclude_bodies", true);
  // Material groups: (name, body indices, obstacle indices); pairs: ContactMaterial objects
  // (groups and values are checked by Build).
  const py::list groups = List(Attr(obj, "groups", path), Key(path, "groups"));
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const std::string f = Index(Key(path, "groups"), i);
    const py::list g = List(groups[i], f);
    if (g.size() != 3) Fail(f, "expected (name, bodies, obstacles), got " + Describe(groups[i]));
    ContactGroupSpec spec;
    spec.name = Text(g[0], Index(f, 0));
    const py::list bodies = List(g[1], Index(f, 1));
    for (std::size_t k = 0; k < bodies.size(); ++k)
      spec.bodies.push_back(Body(bodies[k], Index(Index(f, 1), k), false));
    const py::list obs = List(g[2], Index(f, 2));
    for (std::size_t k = 0; k < obs.size(); ++k)
      spec.obstacles.push_back(
          Integer(obs[k], Index(Index(f, 2), k), 0, static_cast<long>(names.size()) - 1));
    c.groups.push_back(std::move(spec));
  }
  const py::list materials = List(Attr(obj, "pairs", path), Key(path, "pairs"));
  for (std::size_t i = 0; i < materials.size(); ++i)
    c.pairs.push_back(
        Object<ContactMaterial>(materials[i], Index(Key(path, "pairs"), i), "ContactMaterial"));
  return c;
}

OutputsSpec SpecReader::ReadOutputs(py::handle obj, const std::string& path) const {
  const auto get = [&](const char* key) { return Attr(obj, key, path); };
  const auto f = [&](const char* key) { return Key(path, key); };
  OutputsSpec o;
  o.points = Collection<OutputPointSpec>(
      List(get("points"), f("points")), f("points"), "output point", true,
      [&](py::handle p, const std::string& pp, std::size_t) { return ReadOutputPoint(p, pp); });
  o.all_joints = Bool(get("all_joints"), f("all_joints"));
  const py::list joints = List(get("joints"), f("joints"));
  const py::list spec_joints = List(Attr(spec_, "joints", ""), "joints");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const std::string jf = Index(f("joints"), i);
    int j = -1;
    if (py::isinstance<py::str>(joints[i])) {
      const std::string name = joints[i].cast<std::string>();
      for (std::size_t k = 0; k < spec_joints.size() && j < 0; ++k)
        if (OptionalName(spec_joints[k]) == name) j = static_cast<int>(k);
      if (j < 0) Fail(jf, "undefined joint '" + name + "'");
    } else {
      j = Integer(joints[i], jf, 0, static_cast<long>(spec_joints.size()) - 1);
    }
    if (std::find(o.joints.begin(), o.joints.end(), j) != o.joints.end())
      Fail(jf, "joint " + Describe(joints[i]) + " is listed twice");
    o.joints.push_back(j);
  }
  o.interval = Number(get("interval"), f("interval"));
  o.vtk = Bool(get("vtk"), f("vtk"));
  o.vtk_format = Enum<VtkFormat>(get("vtk_format"), f("vtk_format"));
  o.vtk_interval = Number(get("vtk_interval"), f("vtk_interval"));
  o.rod_fields = Bool(get("rod_fields"), f("rod_fields"));
  o.rod_fields_interval = Number(get("rod_fields_interval"), f("rod_fields_interval"));
  o.max_rows = Integer(get("max_rows"), f("max_rows"), 1, kMaxMaxRows);
  o.reactions = Bool(get("reactions"), f("reactions"));
  o.energy = Bool(get("energy"), f("energy"));
  return o;
}

std::vector<std::pair<std::string, py::object>> SpecReader::NamedValues(
    py::handle v, const std::string& f) const {
  std::vector<std::pair<std::string, py::object>> out;
  if (py::isinstance<py::dict>(v)) {
    for (const auto& [key, value] : py::reinterpret_borrow<py::dict>(v))
      out.emplace_back(Text(key, f), py::reinterpret_borrow<py::object>(value));
  } else {
    const py::list items = List(v, f);
    for (std::size_t i = 0; i < items.size(); ++i) {
      const py::list pair = List(items[i], Index(f, i));
      if (pair.size() != 2) Fail(Index(f, i), "expected a (name, value) pair");
      out.emplace_back(Text(pair[0], Index(f, i)), pair[1]);
    }
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (out[i].first.empty()) Fail(f, "a name is empty");
    for (std::size_t k = 0; k < i; ++k)
      if (out[k].first == out[i].first) Fail(Key(f, out[i].first.c_str()), "defined twice");
  }
  return out;
}

SceneSpec SpecReader::Read() {
  SceneSpec s;
  s.name = Text(Attr(spec_, "name", ""), "name");
  s.gravity = Vector3(Attr(spec_, "gravity", ""), "gravity");
  s.rod_inertia = Enum<RodInertia>(Attr(spec_, "rod_inertia", ""), "rod_inertia");
  s.linear_solver = Enum<LinearSolver>(Attr(spec_, "linear_solver", ""), "linear_solver");
  s.conform_mesh = Bool(Attr(spec_, "conform_mesh", ""), "conform_mesh");
  for (const auto& [name, p] : NamedValues(Attr(spec_, "points", ""), "points"))
    s.points.emplace_back(name, Vector3(p, Key("points", name.c_str())));
  for (const auto& [name, v] : NamedValues(Attr(spec_, "inputs", ""), "inputs"))
    s.inputs.emplace_back(name, Number(v, Key("inputs", name.c_str())));
  const auto list = [&](const char* key) { return List(Attr(spec_, key, ""), key); };
  s.bodies = Collection<BodySpec>(
      list("bodies"), "bodies", "body", true,
      [&](py::handle o, const std::string& p, std::size_t i) { return ReadBody(o, p, i); });
  long total = 0;
  for (std::size_t b = 0; b < s.bodies.size(); ++b)
    if (!s.bodies[b].rigid) {
      total +=
          static_cast<long>(s.bodies[b].elements) * static_cast<long>(s.bodies[b].path.size() - 1);
      if (total > kMaxTotalElements)
        Fail(Index("bodies", b) + ".elements", "the spec's rods have more than " +
                                                   std::to_string(kMaxTotalElements) +
                                                   " elements in all (the limit)");
    }
  s.joints = Collection<JointEntrySpec>(
      list("joints"), "joints", "joint", true,
      [&](py::handle o, const std::string& p, std::size_t) { return ReadJoint(o, p); });
  s.loads = Collection<LoadSpec>(
      list("loads"), "loads", "load", false,
      [&](py::handle o, const std::string& p, std::size_t) { return ReadLoad(o, p); });
  s.tendons = Collection<TendonSpec>(
      list("tendons"), "tendons", "tendon", true,
      [&](py::handle o, const std::string& p, std::size_t) { return ReadTendon(o, p); });
  s.forces = Collection<ForceSpec>(
      list("forces"), "forces", "force element", true,
      [&](py::handle o, const std::string& p, std::size_t) { return ReadForce(o, p); });
  s.actuators = Collection<ActuatorSpec>(
      list("actuators"), "actuation", "actuator", true,
      [&](py::handle o, const std::string& p, std::size_t) { return ReadActuator(o, p); });
  s.contact = ReadContact(Attr(spec_, "contact", ""), "contact");
  s.analysis =
      Object<AnalysisSettings>(Attr(spec_, "analysis", ""), "analysis", "AnalysisSettings");
  s.outputs = ReadOutputs(Attr(spec_, "outputs", ""), "outputs");
  return s;
}

void SpecReader::Check(const std::string& collection, int index) {
  const auto one = [&](const char* key, const char* path, const char* what, bool required,
                       auto read) {
    const py::list items =
        collection == "outputs.points"
            ? List(Attr(Attr(spec_, "outputs", ""), "points", "outputs"), "outputs.points")
            : List(Attr(spec_, key, ""), key);
    const std::size_t i = static_cast<std::size_t>(CheckIndex(index, items.size(), key));
    const std::string p = EntityPath(path, items[i], i);
    UniqueName(items[i], p, items, i, what, required);
    read(items[i], p, i);
  };
  if (collection == "bodies")
    one("bodies", "bodies", "body", true,
        [&](py::handle o, const std::string& p, std::size_t i) { ReadBody(o, p, i); });
  else if (collection == "joints")
    one("joints", "joints", "joint", true,
        [&](py::handle o, const std::string& p, std::size_t) { ReadJoint(o, p); });
  else if (collection == "loads")
    one("loads", "loads", "load", false,
        [&](py::handle o, const std::string& p, std::size_t) { ReadLoad(o, p); });
  else if (collection == "tendons")
    one("tendons", "tendons", "tendon", true,
        [&](py::handle o, const std::string& p, std::size_t) { ReadTendon(o, p); });
  else if (collection == "forces")
    one("forces", "forces", "force element", true,
        [&](py::handle o, const std::string& p, std::size_t) { ReadForce(o, p); });
  else if (collection == "actuators")
    one("actuators", "actuation", "actuator", true,
        [&](py::handle o, const std::string& p, std::size_t) { ReadActuator(o, p); });
  else if (collection == "outputs.points")
    one("outputs", "outputs.points", "output point", true,
        [&](py::handle o, const std::string& p, std::size_t) { ReadOutputPoint(o, p); });
  else
    throw InputError("SceneSpec: no collection '" + collection + "'");
}

// ---- C++ -> Python ------------------------------------------------------------------------

py::tuple Tuple(const Vec3& v) { return py::make_tuple(v.x(), v.y(), v.z()); }
py::tuple Tuple(const Vec6& v) { return py::make_tuple(v(0), v(1), v(2), v(3), v(4), v(5)); }
py::tuple Tuple(const Mat3& m) {
  return py::make_tuple(Tuple(Vec3(m.row(0).transpose())), Tuple(Vec3(m.row(1).transpose())),
                        Tuple(Vec3(m.row(2).transpose())));
}

py::object ToPython(const BodySpec& b) {
  py::list path, shapes;
  for (const Vec3& p : b.path) path.append(Tuple(p));
  for (const ContactShape& s : b.shapes) shapes.append(py::cast(s));
  return SpecClass("BodySpec")(
      py::arg("name") = b.name, py::arg("rigid") = b.rigid, py::arg("free") = b.free,
      py::arg("fixed") = b.fixed, py::arg("origin") = Tuple(b.origin),
      py::arg("com") = Tuple(b.com), py::arg("mass") = b.mass,
      py::arg("inertia") = Tuple(b.inertia),
      py::arg("has_initial_velocity") = b.has_initial_velocity,
      py::arg("initial_linear") = Tuple(b.initial_linear),
      py::arg("initial_angular") = Tuple(b.initial_angular), py::arg("path") = path,
      py::arg("elements") = b.elements, py::arg("section") = b.section, py::arg("up") = Tuple(b.up),
      py::arg("weld_start") = b.weld_start, py::arg("weld_end") = b.weld_end,
      py::arg("contact_radius") = b.contact_radius, py::arg("visual_radius") = b.visual_radius,
      py::arg("shapes") = shapes, py::arg("contype") = b.contype,
      py::arg("conaffinity") = b.conaffinity);
}

py::object ToPython(const JointEntrySpec& j) {
  return SpecClass("JointEntrySpec")(py::arg("body_a") = j.body_a, py::arg("body_b") = j.body_b,
                                     py::arg("joint") = j.joint);
}

const char* WhereName(LoadSpec::Where w) {
  switch (w) {
    case LoadSpec::Where::kAt:
      return "at";
    case LoadSpec::Where::kArcLength:
      return "s";
    case LoadSpec::Where::kDistributed:
      return "distributed";
  }
  return "at";
}

py::object ToPython(const LoadSpec& l) {
  return SpecClass("LoadSpec")(py::arg("name") = l.name, py::arg("body") = l.body,
                               py::arg("where") = WhereName(l.where), py::arg("at") = Tuple(l.at),
                               py::arg("arc_length") = l.arc_length, py::arg("frame") = l.frame,
                               py::arg("force") = Tuple(l.force),
                               py::arg("moment") = Tuple(l.moment), py::arg("profile") = l.profile);
}

py::object ToPython(const BodyPointSpec& p) {
  return SpecClass("BodyPointSpec")(
      py::arg("body") = p.body, py::arg("along_rod") = p.along_rod, py::arg("at") = Tuple(p.at),
      py::arg("arc_length") = p.arc_length, py::arg("offset") = Tuple(p.offset),
      py::arg("routed") = p.routed,
      py::arg("route") = p.routed ? py::cast(p.route) : py::object(py::none()));
}

py::object ToPython(const TendonSpec& t) {
  py::list eyelets;
  for (const BodyPointSpec& p : t.eyelets) eyelets.append(ToPython(p));
  return SpecClass("TendonSpec")(py::arg("name") = t.name, py::arg("eyelets") = eyelets,
                                 py::arg("tension") = t.tension, py::arg("by_length") = t.by_length,
                                 py::arg("length") = t.length);
}

py::object ToPython(const ForceSpec& f) {
  return SpecClass("ForceSpec")(
      py::arg("name") = f.name, py::arg("a") = ToPython(f.a), py::arg("b") = ToPython(f.b),
      py::arg("stiffness") = f.stiffness, py::arg("damping") = f.damping,
      py::arg("rest_length") = f.rest_length, py::arg("actuator") = f.actuator);
}

py::object ToPython(const ActuatorSpec& a) {
  return SpecClass("ActuatorSpec")(
      py::arg("name") = a.name, py::arg("type") = a.type, py::arg("body") = a.body,
      py::arg("from_") = a.from, py::arg("to") = a.to, py::arg("area") = a.area,
      py::arg("offset") = Tuple(a.offset), py::arg("max_stress") = a.max_stress,
      py::arg("vector") = Tuple(a.vector), py::arg("profile") = a.profile);
}

py::object ToPython(const ContactMaterial& m) { return py::cast(m); }

py::object ToPython(const OutputPointSpec& p) {
  return SpecClass("OutputPointSpec")(
      py::arg("name") = p.name, py::arg("body") = p.body, py::arg("along_rod") = p.along_rod,
      py::arg("at") = Tuple(p.at), py::arg("arc_length") = p.arc_length);
}

template <typename T>
py::list ListOf(const std::vector<T>& items) {
  py::list out;
  for (const T& item : items) out.append(ToPython(item));
  return out;
}

py::list Pairs(const std::vector<std::pair<int, int>>& pairs) {
  py::list out;
  for (const auto& [a, b] : pairs) out.append(py::make_tuple(a, b));
  return out;
}

py::list ContactGroups(const std::vector<ContactGroupSpec>& groups) {
  py::list out;
  for (const ContactGroupSpec& g : groups)
    out.append(py::make_tuple(g.name, py::cast(g.bodies), py::cast(g.obstacles)));
  return out;
}

py::object ToPython(const SceneSpec& s) {
  py::dict points, inputs;
  for (const auto& [name, p] : s.points) points[py::str(name)] = Tuple(p);
  for (const auto& [name, v] : s.inputs) inputs[py::str(name)] = v;
  py::list obstacles;
  for (const ContactObstacle& o : s.contact.obstacles) obstacles.append(py::cast(o));
  const py::object contact = SpecClass("ContactSpec")(
      py::arg("present") = s.contact.present, py::arg("settings") = s.contact.settings,
      py::arg("obstacles") = obstacles, py::arg("exclude") = Pairs(s.contact.exclude),
      py::arg("exclude_bodies") = Pairs(s.contact.exclude_bodies),
      py::arg("groups") = ContactGroups(s.contact.groups),
      py::arg("pairs") = ListOf(s.contact.pairs));
  const OutputsSpec& o = s.outputs;
  const py::object outputs = SpecClass("OutputsSpec")(
      py::arg("points") = ListOf(o.points), py::arg("all_joints") = o.all_joints,
      py::arg("joints") = py::cast(o.joints), py::arg("interval") = o.interval,
      py::arg("vtk") = o.vtk, py::arg("vtk_format") = o.vtk_format,
      py::arg("vtk_interval") = o.vtk_interval, py::arg("rod_fields") = o.rod_fields,
      py::arg("rod_fields_interval") = o.rod_fields_interval, py::arg("max_rows") = o.max_rows,
      py::arg("reactions") = o.reactions, py::arg("energy") = o.energy);
  return SpecClass("SceneSpec")(
      py::arg("name") = s.name, py::arg("gravity") = Tuple(s.gravity),
      py::arg("rod_inertia") = s.rod_inertia, py::arg("linear_solver") = s.linear_solver,
      py::arg("conform_mesh") = s.conform_mesh, py::arg("points") = points,
      py::arg("inputs") = inputs, py::arg("bodies") = ListOf(s.bodies),
      py::arg("joints") = ListOf(s.joints), py::arg("loads") = ListOf(s.loads),
      py::arg("tendons") = ListOf(s.tendons), py::arg("forces") = ListOf(s.forces),
      py::arg("actuators") = ListOf(s.actuators), py::arg("contact") = contact,
      py::arg("analysis") = s.analysis, py::arg("outputs") = outputs);
}

// ---- helpers of the adders ----------------------------------------------------------------

// The scene's unit axis from [x, y, z]: within 1e-6 of unit length, divided by its norm.
Vec3 UnitAxis(const Vec3& a, const std::string& field) {
  const double n = a.norm();
  if (!(n > 0.0) || !std::isfinite(n)) throw InputError(field + ": the axis is zero or not finite");
  if (std::abs(n - 1.0) > 1e-6)
    throw InputError(field + ": expected a unit vector, got length " + std::to_string(n) +
                     " (normalise it, or give {'from': POINT, 'to': POINT})");
  return a / n;
}

// The scene's {from: A, to: B}: the unit vector from A to B.
Vec3 AxisBetween(const Vec3& from, const Vec3& to, const std::string& field) {
  const Vec3 a = to - from;
  if (!(a.norm() > 0.0) || !a.allFinite())
    throw InputError(field + ": 'from' and 'to' coincide: no direction");
  return a.normalized();
}

// A universal joint's second axis: orthogonal to the first (within 1e-6), re-orthonormalised.
Vec3 SecondAxis(const Vec3& axis, const Vec3& axis2, const std::string& field) {
  if (std::abs(axis.dot(axis2)) > 1e-6) throw InputError(field + ": must be orthogonal to 'axis'");
  return (axis2 - axis.dot(axis2) * axis).normalized();
}

// A robot base's orientation as the scene writes it (docs/scene-format.md, "robots"): {} (the
// identity), {'quaternion': [w, x, y, z]}, {'axis': [x, y, z], 'angle': rad} or
// {'rpy': [roll, pitch, yaw]}; the same functions as the scene reader (io/urdf.h).
Mat3 Orientation(const py::dict& o, const std::string& field) {
  for (const auto& item : o) {
    const std::string key = py::str(item.first);
    if (key != "quaternion" && key != "axis" && key != "angle" && key != "rpy")
      throw InputError(field + ": unknown key '" + key +
                       "' (expected 'quaternion', 'axis' with 'angle', or 'rpy')");
  }
  const bool q = o.contains("quaternion"), aa = o.contains("axis") || o.contains("angle"),
             rpy = o.contains("rpy");
  if (!q && !aa && !rpy) return Mat3::Identity();
  if (q + aa + rpy != 1)
    throw InputError(field +
                     ": give one of 'quaternion': [w, x, y, z], 'axis' with 'angle', or 'rpy'");
  if (q) {
    const auto v = o["quaternion"].cast<std::vector<double>>();
    if (v.size() != 4)
      throw InputError(field + ".quaternion: expected 4 numbers [w, x, y, z], got " +
                       std::to_string(v.size()));
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
    if (!(std::abs(n - 1.0) <= 1e-6))
      throw InputError(field + ".quaternion: expected a unit quaternion [w, x, y, z], got norm " +
                       std::to_string(n));
    return RotationFromQuaternion(v[0], v[1], v[2], v[3]);
  }
  if (rpy) return RotationFromRpy(o["rpy"].cast<Vec3>());
  if (!o.contains("axis")) throw InputError(field + ": missing 'axis' (with 'angle')");
  if (!o.contains("angle")) throw InputError(field + ": missing 'angle' (with 'axis')");
  return RotationFromAxisAngle(UnitAxis(o["axis"].cast<Vec3>(), field + ".axis"),
                               o["angle"].cast<double>());
}

}  // namespace

void BindSpec(py::module_& m) {
  m.def(
      "_read_urdf",
      [](const std::string& path, const std::string& name, const Vec3& base, const Mat3& rotation,
         bool fixed_base, unsigned contype, unsigned conaffinity) {
        UrdfImport import;
        import.name = name;
        import.base_position = base;
        import.base_rotation = rotation;
        import.fixed_base = fixed_base;
        import.contype = contype;
        import.conaffinity = conaffinity;
        SceneSpec s;
        AppendUrdf(path, import, &s);
        return ToPython(s);
      },
      py::arg("path"), py::arg("name"), py::arg("base"), py::arg("rotation"), py::arg("fixed_base"),
      py::arg("contype"), py::arg("conaffinity"),
      "AppendUrdf into an empty spec: a URDF robot's bodies and joints as a screwfem.SceneSpec "
      "(use SceneSpec.add_urdf).");
  m.def("_orientation", &Orientation, py::arg("orientation"), py::arg("field"),
        "A robot base's rotation matrix from its scene form (use SceneSpec.add_urdf).");
  m.def(
      "_read_scene_spec",
      [](const std::string& text, const std::string& source_name,
         const std::vector<std::string>& overrides) {
        SceneSources sources;
        return ToPython(ReadSceneSpec(text, source_name, overrides, &sources));
      },
      py::arg("text"), py::arg("source_name"), py::arg("overrides"),
      "ReadSceneSpec: scene text -> screwfem.SceneSpec (use screwfem.read_scene_spec).");
  m.def(
      "_load_scene_spec",
      [](const std::string& path, const std::vector<std::string>& overrides) {
        SceneSources sources;
        return ToPython(LoadSceneSpec(path, overrides, &sources));
      },
      py::arg("path"), py::arg("overrides"),
      "LoadSceneSpec: a scene file -> screwfem.SceneSpec (use screwfem.read_scene_spec).");
  m.def(
      "_compile_spec",
      [](py::handle spec, const std::string& source_name) {
        return CompileScene(SpecReader(spec, source_name).Read(), source_name);
      },
      py::arg("spec"), py::arg("source_name"),
      "CompileScene of a screwfem.SceneSpec (use SceneSpec.compile).");
  m.def(
      "_copy_spec",
      [](py::handle spec) { return ToPython(SpecReader(spec, "<python spec>").Read()); },
      py::arg("spec"), "A deep copy of a screwfem.SceneSpec through the C++ SceneSpec.");
  m.def(
      "_check_spec_entity",
      [](py::handle spec, const std::string& collection, int index,
         const std::string& source_name) {
        SpecReader(spec, source_name).Check(collection, index);
      },
      py::arg("spec"), py::arg("collection"), py::arg("index"), py::arg("source_name"),
      "Checks one entity of a screwfem.SceneSpec as compile would (InputError).");
  m.def(
      "_default_spec",
      [] {
        SceneSpec s;
        s.bodies.emplace_back();
        s.joints.emplace_back();
        s.loads.emplace_back();
        s.tendons.emplace_back();
        s.forces.emplace_back();
        s.actuators.emplace_back();
        s.outputs.points.emplace_back();
        return ToPython(s);
      },
      "A SceneSpec with one default-constructed C++ entity of each kind (for tests of the "
      "Python defaults).");
  m.def("_unit_axis", &UnitAxis, py::arg("axis"), py::arg("field"));
  m.def("_axis_between", &AxisBetween, py::arg("from_"), py::arg("to"), py::arg("field"));
  m.def("_second_axis", &SecondAxis, py::arg("axis"), py::arg("axis2"), py::arg("field"));
  m.def(
      "_joint_type_info",
      [](JointType type) {
        const JointTypeInfo& info = GetJointTypeInfo(type);
        py::dict d;
        d["name"] = info.name;
        d["dof"] = info.dof;
        d["springs"] = info.spring_law == JointSpringLaw::kRelativeMotion ? 6 : info.dof;
        d["global_coordinates"] = info.global_coordinates;
        d["uses_axis"] = info.uses_axis;
        d["uses_axis2"] = info.uses_axis2;
        d["uses_pitch"] = info.uses_pitch;
        return d;
      },
      py::arg("type"), "The row of the joint-type table (elements/joint.h) a spec needs.");
}

}  // namespace screwfem::python
