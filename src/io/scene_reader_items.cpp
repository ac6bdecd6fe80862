// The scene reader (scene_reader_impl.h): inputs, loads, tendons, force elements, actuation and
// contact.
#include <Eigen/Cholesky>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "scene_reader_impl.h"
#include "screwfem/io/mesh_file.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/schedule.h"

namespace screwfem::scene_reading {

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

// {route: {body: SOFT BODY, every: K, from: S0, to: S1, offset: [x, y, z],
//          helix: {radius: R, pitch: P, phase: A}}}: the eyelets of a route along a rod
// (build/routing.h; checked against the rod by the compiler).
BodyPointSpec SceneReader::ReadRoute(const Node& node, const std::string& path) const {
  r_.CheckKeys(node, path, {"route"});
  const Node& route = *node.Find("route");
  const std::string rp = Join(path, "route");
  r_.CheckKeys(route, rp, {"body", "every", "from", "to", "offset", "helix"});
  BodyPointSpec p;
  p.routed = true;
  const Node& body = r_.Require(route, rp, "body");
  p.body = Body(body, Join(rp, "body"));
  if (spec_.bodies[static_cast<std::size_t>(p.body)].rigid)
    r_.Fail(body.location, Join(rp, "body"),
            "a route runs along a soft body; '" + body.scalar + "' is rigid (list its eyelets)");
  RodRoute& r = p.route;
  if (const Node* e = route.Find("every"))
    r.every = r_.Integer(*e, Join(rp, "every"), 1, kMaxElements);
  if (const Node* f = route.Find("from")) r.from = r_.NonNegativeNumber(*f, Join(rp, "from"));
  if (const Node* t = route.Find("to")) r.to = r_.NonNegativeNumber(*t, Join(rp, "to"));
  if (route.Find("to") != nullptr && !(r.to > r.from))
    r_.Fail(route.Find("to")->location, Join(rp, "to"), "expected an arc length beyond 'from'");
  if (const Node* o = route.Find("offset")) r.offset = r_.Vector3(*o, Join(rp, "offset"));
  if (const Node* h = route.Find("helix")) {
    const std::string hp = Join(rp, "helix");
    r_.CheckKeys(*h, hp, {"radius", "pitch", "phase"});
    r.helix_radius = r_.PositiveNumber(r_.Require(*h, hp, "radius"), Join(hp, "radius"));
    const Node& pitch = r_.Require(*h, hp, "pitch");
    r.helix_pitch = r_.Number(pitch, Join(hp, "pitch"));
    if (r.helix_pitch == 0.0)
      r_.Fail(pitch.location, Join(hp, "pitch"),
              "expected a non-zero arc length per turn [m] (negative: the other hand)");
    if (const Node* a = h->Find("phase")) r.helix_phase = r_.Number(*a, Join(hp, "phase"));
  }
  return p;
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
    const bool routed =
        en.IsSequence() && std::any_of(en.items.begin(), en.items.end(), [](const Node& item) {
          return item.IsMap() && item.Find("route");
        });
    if (!en.IsSequence() || en.items.empty() || (en.items.size() < 2 && !routed))
      r_.Fail(en.location, ep,
              "expected a list of at least two eyelets (a tendon runs between them), got " +
                  scene_yaml::Describe(en));
    for (std::size_t i = 0; i < en.items.size(); ++i) {
      source.parts.emplace_back(Index("eyelets", i), Field(en.items[i].location, Index(ep, i)));
      const Node& item = en.items[i];
      t.eyelets.push_back(item.IsMap() && item.Find("route") != nullptr
                              ? ReadRoute(item, Index(ep, i))
                              : ReadBodyPoint(item, Index(ep, i)));
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
    if (const Node* l = value.Find("rest_length")) {
      f.rest_length = r_.NonNegativeNumber(*l, Join(path, "rest_length"));
      // The rest length is the spring's: without one it would be ignored.
      if (value.Find("stiffness") == nullptr)
        r_.Fail(l->location, Join(path, "rest_length"),
                "'rest_length' is the spring's rest length; this force element has no "
                "'stiffness' (give one, or remove 'rest_length')");
    }
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
      if (o.size() == 3 && o[0] != 0.0)
        r_.Fail(off.location, Join(path, "offset"),
                "the first (axial) component must be 0: a " +
                    std::string(a.type == ActuatorType::kMuscle ? "muscle" : "chamber") +
                    " runs along the rod, its offset lies in the section plane (got " + "'" +
                    off.items[0].scalar + "')");
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
    r_.CheckKeys(v, sp, {"type", "center", "from", "to", "radius", "half_sizes", "orientation"});
    ContactShape shape;
    shape.type = r_.Enum<ContactShapeType>(r_.Require(v, sp, "type"), Join(sp, "type"));
    auto point = [&](const char* key) -> Vec3 {
      const Vec3 world = Point(r_.Require(v, sp, key), Join(sp, key));
      return Vec3(world - b.origin);
    };
    if (shape.type == ContactShapeType::kCapsule || shape.type == ContactShapeType::kCylinder) {
      NotUsedBy(v, sp, {"center", "half_sizes"}, "capsules and cylinders");
      shape.from = point("from");
      shape.to = point("to");
      if (shape.from == shape.to)
        r_.Fail(r_.Require(v, sp, "to").location, Join(sp, "to"),
                "expected 'to' apart from 'from' (the axis of a capsule or cylinder)");
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
      if (const Node* on = v.Find("orientation"))
        shape.rotation = ReadOrientation(*on, Join(sp, "orientation"));
    } else {
      NotUsedBy(v, sp, {"half_sizes", "orientation"}, "spheres, capsules and cylinders");
      shape.radius = r_.PositiveNumber(r_.Require(v, sp, "radius"), Join(sp, "radius"));
    }
    b.shapes.push_back(shape);
  }
}

// One entry of contact.obstacles: a plane (with a moving surface), sphere, capsule, cylinder
// or box with its contact groups.
ContactObstacle SceneReader::ReadObstacle(const Node& v, const std::string& p,
                                          const std::string& name) const {
  r_.ExpectMap(v, p);
  r_.CheckKeys(
      v, p, {"type",       "point",       "normal",   "center", "from",    "to",      "radius",
             "half_sizes", "orientation", "velocity", "spin",   "motion",  "contype", "conaffinity",
             "scale",      "file",        "vertices", "faces",  "heights", "spacing"});
  ContactObstacle o;
  o.name = name;
  o.type = r_.Enum<ObstacleType>(r_.Require(v, p, "type"), Join(p, "type"));
  const bool mesh = o.type == ObstacleType::kMesh || o.type == ObstacleType::kHeightfield;
  if (o.type != ObstacleType::kPlane)
    NotUsedBy(v, p, {"point", "normal", "velocity", "spin", "motion"},
              "spheres, capsules, cylinders, boxes and meshes");
  if (o.type != ObstacleType::kBox) NotUsedBy(v, p, {"half_sizes"}, "obstacles other than boxes");
  if (o.type != ObstacleType::kBox && !mesh)
    NotUsedBy(v, p, {"orientation"}, "planes, spheres, capsules and cylinders");
  if (o.type != ObstacleType::kMesh)
    NotUsedBy(v, p, {"scale", "vertices", "faces"}, "obstacles other than meshes");
  if (o.type != ObstacleType::kHeightfield)
    NotUsedBy(v, p, {"heights", "spacing"}, "obstacles other than height fields");
  if (!mesh) NotUsedBy(v, p, {"file"}, "obstacles other than meshes and height fields");
  if (mesh) {
    ReadMeshObstacle(v, p, o);
  } else if (o.type == ObstacleType::kPlane) {
    NotUsedBy(v, p, {"center", "from", "to", "radius"}, "planes");
    o.point = Point(r_.Require(v, p, "point"), Join(p, "point"));
    o.normal = UnitAxis(r_.Require(v, p, "normal"), Join(p, "normal"));
    // A moving surface: a belt's velocity (its part along the normal is an error), a
    // turntable's spin about the normal through `point`, both scaled by `motion`.
    if (const Node* vn = v.Find("velocity")) {
      o.velocity = r_.Vector3(*vn, Join(p, "velocity"));
      if (std::abs(o.velocity.dot(o.normal)) > 1e-12 * o.velocity.norm())
        r_.Fail(vn->location, Join(p, "velocity"),
                "expected a velocity along the plane (perpendicular to its normal)");
    }
    if (const Node* sn = v.Find("spin")) o.spin = r_.Number(*sn, Join(p, "spin"));
    if (const Node* mn = v.Find("motion")) {
      if (v.Find("velocity") == nullptr && v.Find("spin") == nullptr)
        r_.Fail(mn->location, Join(p, "motion"), "'motion' scales 'velocity' or 'spin': give one");
      o.motion = ReadProfile(*mn, Join(p, "motion"));
    }
  } else if (o.type == ObstacleType::kBox) {
    NotUsedBy(v, p, {"from", "to", "radius"}, "boxes");
    o.point = Point(r_.Require(v, p, "center"), Join(p, "center"));
    const Node& hn = r_.Require(v, p, "half_sizes");
    o.to = r_.Vector3(hn, Join(p, "half_sizes"));
    if (!(o.to.minCoeff() > 0.0))
      r_.Fail(hn.location, Join(p, "half_sizes"), "expected positive half sizes");
    if (const Node* on = v.Find("orientation"))
      o.rotation = ReadOrientation(*on, Join(p, "orientation"));
  } else {
    o.radius = r_.PositiveNumber(r_.Require(v, p, "radius"), Join(p, "radius"));
    if (o.type == ObstacleType::kSphere) {
      NotUsedBy(v, p, {"from", "to"}, "spheres");
      o.point = Point(r_.Require(v, p, "center"), Join(p, "center"));
    } else {
      NotUsedBy(v, p, {"center"}, "capsules and cylinders");
      o.point = Point(r_.Require(v, p, "from"), Join(p, "from"));
      o.to = Point(r_.Require(v, p, "to"), Join(p, "to"));
      if (o.point == o.to)
        r_.Fail(r_.Require(v, p, "to").location, Join(p, "to"),
                "expected 'to' apart from 'from' (the axis of a capsule or cylinder)");
    }
  }
  ReadGroups(v, p, &o.contype, &o.conaffinity);
  return o;
}

// A mesh or height-field obstacle (docs/scene-format.md): its pose, and its triangles inline
// or from a file relative to the scene file's directory.
void SceneReader::ReadMeshObstacle(const Node& v, const std::string& p, ContactObstacle& o) const {
  NotUsedBy(v, p, {"from", "to", "radius"}, "meshes and height fields");
  if (const Node* cn = v.Find("center")) o.point = Point(*cn, Join(p, "center"));
  if (const Node* on = v.Find("orientation"))
    o.rotation = ReadOrientation(*on, Join(p, "orientation"));
  const Node* file = v.Find("file");
  const char* inline_key = o.type == ObstacleType::kMesh ? "vertices" : "heights";
  const Node* inline_node = v.Find(inline_key);
  if ((file == nullptr) == (inline_node == nullptr))
    r_.Fail(v.location, p,
            std::string("give either 'file' or '") + inline_key + "'" + (file ? ", not both" : ""));
  std::filesystem::path path;
  if (file) {
    path = r_.Text(*file, Join(p, "file"));
    if (path.empty()) r_.Fail(file->location, Join(p, "file"), "expected a file name, got ''");
    std::error_code ec;
    const std::filesystem::path scene_file(r_.source());
    if (path.is_relative() && scene_file.has_parent_path() &&
        std::filesystem::is_regular_file(scene_file, ec))
      path = scene_file.parent_path() / path;
  }
  auto mesh = std::make_shared<TriangleMesh>();
  if (o.type == ObstacleType::kMesh) {
    if (const Node* sn = v.Find("scale")) o.scale = r_.PositiveNumber(*sn, Join(p, "scale"));
    if (file) {
      try {
        *mesh = ReadMeshFile(path.string());
      } catch (const InputError& e) {
        r_.Fail(file->location, Join(p, "file"), e.what());
      }
    } else {
      const std::string vp = Join(p, "vertices"), fp = Join(p, "faces");
      if (!inline_node->IsSequence() || inline_node->items.empty())
        r_.Fail(inline_node->location, vp,
                "expected a list of vertices [x, y, z], got " + scene_yaml::Describe(*inline_node));
      for (std::size_t i = 0; i < inline_node->items.size(); ++i)
        mesh->vertices.push_back(r_.Vector3(inline_node->items[i], Index(vp, i)));
      const Node& fn = r_.Require(v, p, "faces");
      if (!fn.IsSequence() || fn.items.empty())
        r_.Fail(fn.location, fp,
                "expected a list of faces [i, j, k, ...], got " + scene_yaml::Describe(fn));
      const int n = static_cast<int>(mesh->vertices.size());
      for (std::size_t i = 0; i < fn.items.size(); ++i) {
        const Node& face = fn.items[i];
        const std::string ip = Index(fp, i);
        if (!face.IsSequence() || face.items.size() < 3)
          r_.Fail(face.location, ip,
                  "expected a face of at least 3 vertex indices (0-based), got " +
                      scene_yaml::Describe(face));
        std::vector<int> c;
        for (std::size_t k = 0; k < face.items.size(); ++k)
          c.push_back(r_.Integer(face.items[k], Index(ip, k), 0, n - 1));
        for (std::size_t k = 1; k + 1 < c.size(); ++k)
          mesh->faces.push_back({c[0], c[k], c[k + 1]});
      }
    }
  } else {
    const Node& sp = r_.Require(v, p, "spacing");
    double dx = 0.0, dy = 0.0;
    if (sp.IsSequence()) {
      const std::vector<double> d = r_.FixedNumbers(sp, Join(p, "spacing"), 2);
      dx = d[0];
      dy = d[1];
    } else {
      dx = dy = r_.Number(sp, Join(p, "spacing"));
    }
    if (!(dx > 0.0) || !(dy > 0.0))
      r_.Fail(sp.location, Join(p, "spacing"), "expected positive spacings [dx, dy]");
    std::vector<std::vector<double>> rows;
    if (file) {
      try {
        rows = ReadHeightFile(path.string());
      } catch (const InputError& e) {
        r_.Fail(file->location, Join(p, "file"), e.what());
      }
    } else {
      const std::string hp = Join(p, "heights");
      if (!inline_node->IsSequence() || inline_node->items.size() < 2)
        r_.Fail(inline_node->location, hp,
                "expected at least 2 rows of heights, got " + scene_yaml::Describe(*inline_node));
      for (std::size_t i = 0; i < inline_node->items.size(); ++i) {
        rows.push_back(r_.Numbers(inline_node->items[i], Index(hp, i)));
        if (rows.back().size() < 2 || rows.back().size() != rows.front().size())
          r_.Fail(inline_node->items[i].location, Index(hp, i),
                  "expected " + std::to_string(std::max<std::size_t>(rows.front().size(), 2)) +
                      " or more heights, as many in every row, got " +
                      std::to_string(rows.back().size()));
      }
    }
    std::vector<double> h;
    for (const std::vector<double>& row : rows) h.insert(h.end(), row.begin(), row.end());
    *mesh = HeightFieldMesh(h, static_cast<int>(rows.size()), static_cast<int>(rows.front().size()),
                            dx, dy);
  }
  const std::string why = CheckTriangleMesh(*mesh, "the mesh");
  if (!why.empty()) r_.Fail((file ? file : inline_node)->location, p, why);
  o.mesh = std::move(mesh);
}

void SceneReader::ReadContact(const Node* node) {
  // The bodies' shapes and groups are read with the bodies.
  if (node == nullptr) return;
  const std::string path = "contact";
  r_.ExpectMap(*node, path);
  r_.CheckKeys(*node, path,
               {"stiffness", "onset", "damping_ratio", "friction", "slip_velocity", "friction_law",
                "static_friction", "tangential_stiffness", "obstacles", "exclude", "self",
                "self_skip", "groups", "pairs"});
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
  if (const Node* v = node->Find("friction_law"))
    c.settings.friction_law = r_.Enum<FrictionLaw>(*v, Join(path, "friction_law"));
  if (const Node* v = node->Find("static_friction")) {
    c.settings.static_friction = r_.NonNegativeNumber(*v, Join(path, "static_friction"));
    if (c.settings.static_friction < c.settings.friction)
      r_.Fail(v->location, Join(path, "static_friction"),
              "expected a value >= contact.friction (mu_s >= mu_k)");
  }
  if (const Node* v = node->Find("tangential_stiffness"))
    c.settings.tangential_stiffness = r_.PositiveNumber(*v, Join(path, "tangential_stiffness"));
  if (const Node* v = node->Find("self")) c.settings.self = r_.Bool(*v, Join(path, "self"));
  if (const Node* v = node->Find("self_skip"))
    c.settings.self_skip = r_.PositiveNumber(*v, Join(path, "self_skip"));
  std::vector<std::string> names;
  if (const Node* on = node->Find("obstacles")) {
    const std::string op = Join(path, "obstacles");
    r_.CheckNames(*on, op, "obstacle");
    for (const auto& [entry, v] : on->entries) {
      c.obstacles.push_back(ReadObstacle(v, Join(op, entry.key), entry.key));
      names.push_back(entry.key);
    }
  }
  if (const Node* en = node->Find("exclude")) ReadContactExclusions(*en, names);
  if (const Node* gn = node->Find("groups")) ReadContactGroups(*gn, names);
  if (const Node* pn = node->Find("pairs")) ReadContactPairs(*pn, names);
}

namespace {

// A body's or obstacle's name as a member of a contact group: (false, body) or (true, obstacle),
// or (false, -1) when neither.
std::pair<bool, int> ContactMember(const SceneSpec& spec, const std::vector<std::string>& obstacles,
                                   const std::string& name) {
  for (std::size_t b = 0; b < spec.bodies.size(); ++b)
    if (spec.bodies[b].name == name) return {false, static_cast<int>(b)};
  for (std::size_t o = 0; o < obstacles.size(); ++o)
    if (obstacles[o] == name) return {true, static_cast<int>(o)};
  return {false, -1};
}

std::vector<std::string> ContactMemberNames(const SceneSpec& spec,
                                            const std::vector<std::string>& obstacles) {
  std::vector<std::string> known = obstacles;
  for (const BodySpec& b : spec.bodies) known.push_back(b.name);
  return known;
}

}  // namespace

// contact.groups: {NAME: [body or obstacle, ...]}, each member in one group at most.
void SceneReader::ReadContactGroups(const Node& gn, const std::vector<std::string>& names) {
  const std::string gp = "contact.groups";
  r_.CheckNames(gn, gp, "contact group");
  std::map<std::string, std::string> group_of;  // member name -> its group
  for (const auto& [entry, v] : gn.entries) {
    const std::string p = Join(gp, entry.key);
    if (ContactMember(spec_, names, entry.key).second >= 0)
      r_.Fail(entry.key_location, p,
              "a contact group cannot take the name of a body or obstacle ('" + entry.key + "')");
    if (!v.IsSequence() || v.items.empty())
      r_.Fail(v.location, p,
              "expected a non-empty list of bodies and obstacles, got " + scene_yaml::Describe(v));
    ContactGroupSpec g;
    g.name = entry.key;
    for (std::size_t i = 0; i < v.items.size(); ++i) {
      const std::string ip = Index(p, i);
      const std::string name = r_.Text(v.items[i], ip);
      const auto [obstacle, index] = ContactMember(spec_, names, name);
      if (index < 0)
        r_.Fail(v.items[i].location, ip,
                "undefined body or obstacle '" + name + "'" +
                    scene_yaml::DidYouMean(name, ContactMemberNames(spec_, names)));
      const auto [it, fresh] = group_of.emplace(name, entry.key);
      if (!fresh)
        r_.Fail(v.items[i].location, ip,
                "'" + name + "' is in contact group '" + it->second +
                    "' already (each body or obstacle is in one group at most)");
      (obstacle ? g.obstacles : g.bodies).push_back(index);
    }
    spec_.contact.groups.push_back(std::move(g));
  }
}

// contact.pairs: [{groups: [a, b], friction, static_friction, stiffness, damping_ratio,
// tangential_stiffness, onset}]; a name that is no group is a body or obstacle in no group (a group of
// its own).
void SceneReader::ReadContactPairs(const Node& pn, const std::vector<std::string>& names) {
  const std::string pp = "contact.pairs";
  if (!pn.IsSequence())
    r_.Fail(pn.location, pp,
            "expected a list of {groups: [a, b], friction, ...}, got " + scene_yaml::Describe(pn));
  ContactSpec& c = spec_.contact;
  const auto group_index = [&](const Node& node, const std::string& path) -> int {
    const std::string name = r_.Text(node, path);
    for (std::size_t g = 0; g < c.groups.size(); ++g)
      if (c.groups[g].name == name) return static_cast<int>(g);
    const auto [obstacle, index] = ContactMember(spec_, names, name);
    if (index < 0) {
      std::vector<std::string> known = ContactMemberNames(spec_, names);
      for (const ContactGroupSpec& g : c.groups) known.push_back(g.name);
      r_.Fail(node.location, path,
              "undefined contact group '" + name + "' (nor a body or obstacle)" +
                  scene_yaml::DidYouMean(name, known));
    }
    for (const ContactGroupSpec& g : c.groups) {
      const std::vector<int>& members = obstacle ? g.obstacles : g.bodies;
      if (std::find(members.begin(), members.end(), index) != members.end())
        r_.Fail(node.location, path,
                "'" + name + "' is in contact group '" + g.name + "': name the group");
    }
    // A group of its own, named after it.
    ContactGroupSpec g;
    g.name = name;
    (obstacle ? g.obstacles : g.bodies).push_back(index);
    c.groups.push_back(std::move(g));
    return static_cast<int>(c.groups.size()) - 1;
  };
  std::map<std::pair<int, int>, std::size_t> seen;
  for (std::size_t i = 0; i < pn.items.size(); ++i) {
    const Node& v = pn.items[i];
    const std::string p = Index(pp, i);
    r_.ExpectMap(v, p);
    r_.CheckKeys(v, p,
                 {"groups", "friction", "static_friction", "stiffness", "damping_ratio",
                  "tangential_stiffness", "onset"});
    const Node& gn = r_.Require(v, p, "groups");
    const std::string gp = Join(p, "groups");
    if (!gn.IsSequence() || gn.items.size() != 2)
      r_.Fail(gn.location, gp,
              "expected two contact groups [a, b], got " + scene_yaml::Describe(gn));
    ContactMaterial m;
    m.group[0] = group_index(gn.items[0], Index(gp, 0));
    m.group[1] = group_index(gn.items[1], Index(gp, 1));
    const auto key =
        std::make_pair(std::min(m.group[0], m.group[1]), std::max(m.group[0], m.group[1]));
    if (const auto [it, fresh] = seen.emplace(key, i); !fresh)
      r_.Fail(gn.location, gp,
              "the pair [" + c.groups[static_cast<std::size_t>(m.group[0])].name + ", " +
                  c.groups[static_cast<std::size_t>(m.group[1])].name + "] is given twice (" +
                  Index(pp, it->second) + ")");
    if (const Node* x = v.Find("friction"))
      m.friction = r_.NonNegativeNumber(*x, Join(p, "friction"));
    if (const Node* x = v.Find("stiffness"))
      m.stiffness = r_.PositiveNumber(*x, Join(p, "stiffness"));
    if (const Node* x = v.Find("damping_ratio"))
      m.damping_ratio = r_.NonNegativeNumber(*x, Join(p, "damping_ratio"));
    if (const Node* x = v.Find("tangential_stiffness"))
      m.tangential_stiffness = r_.PositiveNumber(*x, Join(p, "tangential_stiffness"));
    if (const Node* x = v.Find("onset")) m.onset = r_.PositiveNumber(*x, Join(p, "onset"));
    if (const Node* x = v.Find("static_friction")) {
      m.static_friction = r_.NonNegativeNumber(*x, Join(p, "static_friction"));
      const double kinetic = m.friction >= 0.0 ? m.friction : c.settings.friction;
      if (m.static_friction < kinetic) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "expected a value >= the pair's friction %g (mu_s >= mu_k)",
                      kinetic);
        r_.Fail(x->location, Join(p, "static_friction"), buf);
      }
    }
    c.pairs.push_back(m);
  }
}

// contact.exclude: [body, obstacle] or [body, body] pairs that never touch; `names` are the
// obstacles' names in order. Names are looked up in hash tables: linear in the pairs.
void SceneReader::ReadContactExclusions(const Node& en, const std::vector<std::string>& names) {
  const std::string ep = "contact.exclude";
  if (!en.IsSequence())
    r_.Fail(en.location, ep, "expected a list of [body, obstacle] or [body, body] pairs");
  std::unordered_map<std::string_view, int> obstacle_index, body_index;
  for (std::size_t i = 0; i < names.size(); ++i)
    obstacle_index.emplace(names[i], static_cast<int>(i));
  for (std::size_t b = 0; b < spec_.bodies.size(); ++b)
    body_index.emplace(spec_.bodies[b].name, static_cast<int>(b));
  for (std::size_t i = 0; i < en.items.size(); ++i) {
    const Node& pair = en.items[i];
    const std::string pp = Index(ep, i);
    if (!pair.IsSequence() || pair.items.size() != 2)
      r_.Fail(pair.location, pp,
              "expected [body, obstacle] or [body, body], got " + scene_yaml::Describe(pair));
    const int body = Body(pair.items[0], Index(pp, 0));
    const std::string other = r_.Text(pair.items[1], Index(pp, 1));
    if (const auto it = obstacle_index.find(other); it != obstacle_index.end()) {
      spec_.contact.exclude.emplace_back(body, it->second);
      continue;
    }
    // Not an obstacle: a second body (a pair of moving bodies that never touch).
    const auto second = body_index.find(other);
    if (second == body_index.end()) {
      std::vector<std::string> known = names;
      for (const BodySpec& b : spec_.bodies) known.push_back(b.name);
      r_.Fail(
          pair.items[1].location, Index(pp, 1),
          "undefined obstacle '" + other + "' (nor a body)" + scene_yaml::DidYouMean(other, known));
    }
    if (second->second == body)
      r_.Fail(pair.items[1].location, Index(pp, 1),
              "a body cannot be excluded from itself (rod self-contact: 'self: false')");
    spec_.contact.exclude_bodies.emplace_back(body, second->second);
  }
}

}  // namespace screwfem::scene_reading
