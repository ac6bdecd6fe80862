// The scene compiler (docs/architecture.md, "Scenes"): a SceneSpec -> ModelBuilder calls -> a
// Scene. It finds the nodes that joints, welds, loads and output points attach to
// (ModelBuilder::FindNodeAt), checks that every body is connected, and maps every error,
// including the builder's (InputError::entity()), to the place in the file that defined the
// entity (SceneSources).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include "scene_yaml.h"
#include "screwfem/elements/joint.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

// A soft body's section with its outline for drawing: a circle of visual_radius when given
// (Section::width and height are read only by the ParaView frames and the viewer).
Section DrawnSection(const BodySpec& b) {
  Section s = b.section;
  if (b.visual_radius > 0.0) {
    s.width = s.height = 2.0 * b.visual_radius;
    s.round = true;
  }
  return s;
}

std::string FormatVec(const Vec3& v) {
  std::ostringstream s;
  s.precision(6);
  s << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return s.str();
}

// The source of entity i, or an empty one (a spec made in code may have no sources).
const EntitySource& SourceOf(const std::vector<EntitySource>& sources, std::size_t i) {
  static const EntitySource kNone;
  return i < sources.size() ? sources[i] : kNone;
}

// A part of an entity's source, or the entity's own.
const FieldSource& PartOf(const EntitySource& source, const std::string& part) {
  const FieldSource* field = source.Part(part);
  return field != nullptr ? *field : source.self;
}

// The default output interval: a whole number of steps, about (end - start) / count long (one
// step at least; 0, every step, in statics).
double DefaultOutputInterval(const AnalysisSettings& a, int count) {
  if (a.kind == AnalysisKind::kStatic) return 0.0;
  const double steps = (a.end_time - a.start_time) / a.step;
  return a.step * std::max(1.0, std::round(steps / count));
}

// The values a point load and a rod load share.
template <typename Load>
void CopyLoadValues(const LoadSpec& l, Load* load) {
  load->frame = l.frame;
  load->force = l.force;
  load->moment = l.moment;
  load->profile = l.profile;
}

class SceneCompiler {
 public:
  SceneCompiler(const SceneSpec& spec, const SceneSources& sources)
      : spec_(spec), src_(sources), r_(sources.file) {}

  Scene Compile();

 private:
  void AddBodies();
  void AddRigidBody(int b);
  void AddSoftBody(int b);
  void AddJoints();
  void AddLoads();
  void AddTendonsAndForces();
  void AddActuators();
  void AddContacts();
  // The builder's body point for a spec's (an error at `at` when it is off its body).
  BodyPoint ResolveBodyPoint(const BodyPointSpec& p, const FieldSource& at,
                             const std::string& what) const;
  void CheckConnections() const;
  void AddOutputs(const Model& model, OutputSpec* out) const;

  // The node of body b at world point p: the rigid body's node, or the rod node there (an
  // error at `at` otherwise; `what` names the attachment in the message).
  NodeId NodeAt(int b, const Vec3& p, const FieldSource& at, const std::string& what) const;
  const std::vector<double>& RodArcs(RodId rod) const;
  NodeMatch RodNodeAtArcLength(RodId rod, const std::vector<double>& arcs, double s) const;
  // The builder's entities of spec body b: its rod (a soft body), its rigid body and node (a
  // rigid body), as a contact entity.
  RodId RodOf(int b) const { return rod_of_[static_cast<std::size_t>(b)]; }
  NodeId NodeOf(int b) const { return body_node_[static_cast<std::size_t>(b)]; }
  ContactEntity EntityOf(int b) const {
    const std::size_t i = static_cast<std::size_t>(b);
    return spec_.bodies[i].rigid ? ContactEntity(rigid_of_[i]) : ContactEntity(rod_of_[i]);
  }
  // Fails at an entity's source, or at its part that `e` names.
  [[noreturn]] void Fail(const EntitySource& source, const InputError& e) const;
  [[noreturn]] void Fail(const FieldSource& field, const std::string& what) const {
    r_.Fail(field.location, field.field, what);
  }
  // Maps an error of ModelBuilder::Build to the spec entity that made the builder's entity.
  [[noreturn]] void RethrowBuildError(const InputError& e) const;
  void RethrowRoutedEyeletError(const EntitySource& source, const InputError& e) const;
  const EntitySource& BodySource(int b) const {
    return SourceOf(src_.bodies, static_cast<std::size_t>(b));
  }
  // Every reference to a body in the spec is a valid index (the reader guarantees it; a spec
  // made in code may not).
  void CheckReferences() const;

  const SceneSpec& spec_;
  const SceneSources& src_;
  scene_yaml::Reader r_;  // for messages
  ModelBuilder builder_;
  // Per spec body (spec bodies are indexed by int): the builder's rod or rigid body and a
  // rigid body's node.
  std::vector<RodId> rod_of_;
  std::vector<BodyId> rigid_of_;
  std::vector<NodeId> body_node_;
  mutable std::vector<std::vector<double>> rod_arcs_;  // RodArcs
  // Per tendon, per eyelet given to the builder: the index of its item in the spec's list.
  std::vector<std::vector<int>> tendon_eyelet_items_;
  std::vector<char> connected_;
  std::vector<int> node_body_, rod_body_, rigid_body_, point_load_, rod_load_;
  std::vector<int> contact_rod_body_, contact_shape_body_;  // spec body of each contact rod, shape
};

void SceneCompiler::Fail(const EntitySource& source, const InputError& e) const {
  if (!e.entity().part.empty())
    if (const FieldSource* part = source.Part(e.entity().part))
      Fail(*part, e.detail().empty() ? e.what() : e.detail());
  Fail(source.self, e.what());
}

void SceneCompiler::RethrowBuildError(const InputError& e) const {
  const EntityRef& entity = e.entity();
  auto owner = [&](const std::vector<int>& owners) {
    return entity.index >= 0 && entity.index < static_cast<int>(owners.size())
               ? owners[static_cast<std::size_t>(entity.index)]
               : -1;
  };
  const EntitySource* source = nullptr;
  auto pick = [&](const std::vector<EntitySource>& sources, int i) {
    if (i >= 0 && i < static_cast<int>(sources.size()))
      source = &sources[static_cast<std::size_t>(i)];
  };
  switch (entity.kind) {
    case EntityKind::kNode:
      pick(src_.bodies, owner(node_body_));
      break;
    case EntityKind::kRod:
      pick(src_.bodies, owner(rod_body_));
      break;
    case EntityKind::kBody:
      pick(src_.bodies, owner(rigid_body_));
      break;
    case EntityKind::kJoint:
      pick(src_.joints, entity.index);
      break;
    case EntityKind::kPointLoad:
      pick(src_.loads, owner(point_load_));
      break;
    case EntityKind::kRodLoad:
      pick(src_.loads, owner(rod_load_));
      break;
    case EntityKind::kTendon:
      pick(src_.tendons, entity.index);
      if (source != nullptr) RethrowRoutedEyeletError(*source, e);
      break;
    case EntityKind::kForceElement:
      pick(src_.forces, entity.index);
      break;
    case EntityKind::kActuator:
      pick(src_.actuators, entity.index);
      break;
    case EntityKind::kContactRod:
      pick(src_.bodies, owner(contact_rod_body_));
      break;
    case EntityKind::kContactShape:
      pick(src_.bodies, owner(contact_shape_body_));
      break;
    case EntityKind::kObstacle:
      break;
    case EntityKind::kNone:
      break;
  }
  if (source != nullptr) Fail(*source, e);
  throw InputError(src_.file + ": " + e.what());
}

// A builder error on a tendon's eyelet i: the spec item that made it (a route makes several).
void SceneCompiler::RethrowRoutedEyeletError(const EntitySource& source,
                                             const InputError& e) const {
  const EntityRef& entity = e.entity();
  const std::string prefix = "eyelets[";
  if (entity.index < 0 || entity.index >= static_cast<int>(tendon_eyelet_items_.size()) ||
      entity.part.rfind(prefix, 0) != 0)
    return;
  const std::vector<int>& items = tendon_eyelet_items_[static_cast<std::size_t>(entity.index)];
  std::size_t i = 0;
  const char* first = entity.part.data() + prefix.size();
  const auto r = std::from_chars(first, entity.part.data() + entity.part.size(), i);
  if (r.ec != std::errc() || i >= items.size()) return;
  const int item = items[i];
  const std::size_t first_of_item =
      static_cast<std::size_t>(std::find(items.begin(), items.end(), item) - items.begin());
  if (static_cast<std::size_t>(item) == i && std::count(items.begin(), items.end(), item) == 1)
    return;  // an eyelet of its own, at its own index: the part names it already
  const std::string what = e.detail().empty() ? e.what() : e.detail();
  Fail(PartOf(source, prefix + std::to_string(item) + "]"),
       what + " (eyelet " + std::to_string(i - first_of_item) + " of this item, eyelet " +
           std::to_string(i) + " of the tendon)");
}

NodeId SceneCompiler::NodeAt(int b, const Vec3& p, const FieldSource& at,
                             const std::string& what) const {
  const BodySpec& body = spec_.bodies[static_cast<std::size_t>(b)];
  if (body.rigid) return NodeOf(b);
  const NodeMatch match = builder_.FindNodeAt(p, RodOf(b));
  if (!match.node.valid()) {
    std::ostringstream s;
    s.precision(6);
    s << what << ": soft body '" << body.name << "' has no node at " << FormatVec(p)
      << " (nearest node " << match.distance << " m away); attach at an end, a path point or a "
      << "subdivision point of the rod";
    Fail(at, s.str());
  }
  return match.node;
}

// --- bodies ------------------------------------------------------------------------------------

void SceneCompiler::AddBodies() {
  const std::size_t n = spec_.bodies.size();
  rod_of_.assign(n, RodId());
  rigid_of_.assign(n, BodyId());
  body_node_.assign(n, NodeId());
  connected_.assign(n, 0);
  // In file order (node and rod numbering follows the file).
  for (std::size_t b = 0; b < n; ++b) {
    const std::size_t first_node = builder_.model().nodes.size();
    if (spec_.bodies[b].rigid)
      AddRigidBody(static_cast<int>(b));
    else
      AddSoftBody(static_cast<int>(b));
    node_body_.resize(builder_.model().nodes.size(), -1);
    for (std::size_t i = first_node; i < node_body_.size(); ++i)
      node_body_[i] = static_cast<int>(b);
  }
}

void SceneCompiler::AddRigidBody(int b) {
  const BodySpec& s = spec_.bodies[static_cast<std::size_t>(b)];
  const NodeId node = builder_.AddNode(SE3::Translation(s.origin), s.name);
  if (s.fixed) builder_.FixNode(node);
  body_node_[static_cast<std::size_t>(b)] = node;
  rigid_of_[static_cast<std::size_t>(b)] =
      builder_.AddRigidBody(s.name, node, s.mass, s.com - s.origin, s.inertia);
  if (s.has_initial_velocity) {
    // The body frame is world-aligned at the origin in the reference configuration: its body
    // velocity is the angular velocity and the velocity of the origin, v_com + w x (o - com).
    const Vec3 arm = s.origin - s.com;
    const Vec3 w = s.initial_angular;
    const Vec3 velocity = s.initial_linear + w.cross(arm);
    Vec6 v;
    v.head<3>() = velocity;
    v.tail<3>() = w;
    builder_.SetInitialVelocity(node, v);
  }
  rigid_body_.push_back(b);
}

void SceneCompiler::AddSoftBody(int b) {
  const BodySpec& s = spec_.bodies[static_cast<std::size_t>(b)];
  const EntitySource& source = BodySource(b);
  // Welds: the node of the earlier soft body at the path's end (its frame is checked by
  // AddRodAlongPath).
  auto weld = [&](int other, const Vec3& p, const char* part) {
    if (other < 0) return NodeId();
    const NodeId node = NodeAt(other, p, PartOf(source, part), "weld");
    connected_[static_cast<std::size_t>(other)] = connected_[static_cast<std::size_t>(b)] = 1;
    return node;
  };
  const NodeId start = weld(s.weld_start, s.path.front(), "start_node");
  const NodeId end = weld(s.weld_end, s.path.back(), "end_node");
  try {
    rod_of_[static_cast<std::size_t>(b)] =
        builder_.AddRodAlongPath(s.name, s.path, s.elements, DrawnSection(s), s.up, start, end);
  } catch (const InputError& e) {
    Fail(source, e);
  }
  rod_body_.push_back(b);
}

void SceneCompiler::CheckConnections() const {
  for (std::size_t b = 0; b < spec_.bodies.size(); ++b) {
    const BodySpec& s = spec_.bodies[b];
    if (!connected_[b] && !s.fixed && !s.free)
      Fail(SourceOf(src_.bodies, b).self,
           "body '" + s.name +
               "' is connected to nothing: add a joint or a weld, or set "
               "'fixed: true' (welded to the ground) or 'free: true' "
               "(floating)");
  }
}

// --- joints and loads ----------------------------------------------------------------------

void SceneCompiler::AddJoints() {
  for (std::size_t i = 0; i < spec_.joints.size(); ++i) {
    const JointEntrySpec& entry = spec_.joints[i];
    const EntitySource& source = SourceOf(src_.joints, i);
    JointSpec j = entry.joint;
    NodeId* nodes[2] = {&j.node_a, &j.node_b};
    const int bodies[2] = {entry.body_a, entry.body_b};
    for (int s = 0; s < 2; ++s) {
      if (bodies[s] < 0) continue;
      *nodes[s] =
          NodeAt(bodies[s], j.point, PartOf(source, s == 0 ? "node_a" : "node_b"), "joint point");
      connected_[static_cast<std::size_t>(bodies[s])] = 1;
    }
    try {
      builder_.AddJoint(j);
    } catch (const InputError& e) {
      Fail(source, e);
    }
  }
}

void SceneCompiler::AddLoads() {
  for (std::size_t i = 0; i < spec_.loads.size(); ++i) {
    const LoadSpec& l = spec_.loads[i];
    const EntitySource& source = SourceOf(src_.loads, i);
    const BodySpec& body = spec_.bodies[static_cast<std::size_t>(l.body)];
    if (l.where == LoadSpec::Where::kAt) {
      PointLoad load;
      if (body.rigid) {
        load.node = NodeOf(l.body);
        load.point = l.at - body.origin;  // the body frame is world-aligned in the reference
      } else {
        load.node = NodeAt(l.body, l.at, PartOf(source, "at"), "load point");
      }
      CopyLoadValues(l, &load);
      builder_.AddPointLoad(load);
      point_load_.push_back(static_cast<int>(i));
      continue;
    }
    const RodId rod = RodOf(l.body);
    RodLoad load;
    load.rod = rod;
    load.distributed = l.where == LoadSpec::Where::kDistributed;
    if (!load.distributed) {
      load.arc_length = l.arc_length;
      const double length = builder_.RodLength(rod);
      if (load.arc_length > length * (1.0 + 1e-12)) {
        std::ostringstream msg;
        msg.precision(9);
        msg << "arc length beyond the end of the rod (length " << length << " m)";
        Fail(PartOf(source, "s"), msg.str());
      }
    }
    CopyLoadValues(l, &load);
    builder_.AddRodLoad(load);
    rod_load_.push_back(static_cast<int>(i));
  }
}

// --- tendons and force elements ----------------------------------------------------------

BodyPoint SceneCompiler::ResolveBodyPoint(const BodyPointSpec& p, const FieldSource& at,
                                          const std::string& what) const {
  if (p.body < 0) return {kGround, p.at};
  const BodySpec& body = spec_.bodies[static_cast<std::size_t>(p.body)];
  if (body.rigid)  // the body frame is world-aligned in the reference configuration
    return {NodeOf(p.body), p.at - body.origin};
  if (!p.along_rod) return {NodeAt(p.body, p.at, at, what), p.offset};
  const RodId rod = RodOf(p.body);
  const std::vector<double>& arcs = RodArcs(rod);
  const NodeMatch match = RodNodeAtArcLength(rod, arcs, p.arc_length);
  const double length = arcs.back();
  if (!match.node.valid()) {
    // A point between nodes: on the section of the element there (Build places it).
    if (!(p.arc_length >= 0.0 && p.arc_length <= length * (1.0 + 1e-12))) {
      std::ostringstream s;
      s.precision(9);
      s << what << ": arc length " << p.arc_length << " m is off soft body '" << body.name
        << "' (length " << length << " m)";
      Fail(at, s.str());
    }
    BodyPoint point{kGround, p.offset};
    point.rod = rod;
    point.arc_length = p.arc_length;
    return point;
  }
  return {match.node, p.offset};
}

// The arc length at each node of a rod, as ModelBuilder::RodLength and FindRodNodeAtArcLength
// sum them (in order, the same doubles), once per rod: eyelets and force-element ends at an
// arc length are placed by a binary search (a walk along the rod per eyelet took 19.6 s for
// a tendon of 1e4 eyelets).
const std::vector<double>& SceneCompiler::RodArcs(RodId rod) const {
  if (rod_arcs_.size() <= rod.index()) rod_arcs_.resize(rod.index() + 1);
  std::vector<double>& arcs = rod_arcs_[rod.index()];
  if (arcs.empty()) arcs = builder_.RodArcLengths(rod);
  return arcs;
}

// ModelBuilder::FindRodNodeAtArcLength on RodArcs: the first node nearest to s.
NodeMatch SceneCompiler::RodNodeAtArcLength(RodId rod, const std::vector<double>& arcs,
                                            double s) const {
  const Rod& r = builder_.model().rods[rod.index()];
  NodeMatch match;
  match.distance = std::numeric_limits<double>::infinity();
  if (r.nodes.empty() || arcs.size() != r.nodes.size()) return match;
  const auto at = std::lower_bound(arcs.begin(), arcs.end(), s);
  std::size_t i = static_cast<std::size_t>(at - arcs.begin());
  if (i == arcs.size() || (i > 0 && std::abs(arcs[i - 1] - s) <= std::abs(arcs[i] - s))) --i;
  match.distance = std::abs(arcs[i] - s);
  match.nearest = NodeId(r.nodes[i]);
  if (match.distance <= 1e-8 * std::max(1.0, arcs.back())) match.node = match.nearest;
  return match;
}

void SceneCompiler::AddTendonsAndForces() {
  for (std::size_t i = 0; i < spec_.tendons.size(); ++i) {
    const TendonSpec& t = spec_.tendons[i];
    const EntitySource& source = SourceOf(src_.tendons, i);
    std::vector<BodyPoint> eyelets;
    std::vector<int> items;  // per eyelet: the spec item it comes from (routes give several)
    for (std::size_t k = 0; k < t.eyelets.size(); ++k) {
      const BodyPointSpec& p = t.eyelets[k];
      const FieldSource& at = PartOf(source, "eyelets[" + std::to_string(k) + "]");
      if (!p.routed) {
        eyelets.push_back(ResolveBodyPoint(p, at, "eyelet"));
        items.push_back(static_cast<int>(k));
        continue;
      }
      RodRoute route = p.route;
      route.rod = RodOf(p.body).value();
      try {
        for (const BodyPoint& e : RouteAlongRod(builder_, route)) {
          eyelets.push_back(e);
          items.push_back(static_cast<int>(k));
        }
      } catch (const InputError& e) {
        Fail(at, std::string("route along '") +
                     spec_.bodies[static_cast<std::size_t>(p.body)].name + "': " + e.what());
      }
    }
    tendon_eyelet_items_.push_back(std::move(items));
    if (t.by_length)
      builder_.AddLengthDrivenTendon(t.name, eyelets, t.length);
    else
      builder_.AddTendon(t.name, eyelets, t.tension);
  }
  for (std::size_t i = 0; i < spec_.forces.size(); ++i) {
    const ForceSpec& f = spec_.forces[i];
    const EntitySource& source = SourceOf(src_.forces, i);
    ForceElement fe;
    fe.name = f.name;
    fe.a = ResolveBodyPoint(f.a, PartOf(source, "a"), "end");
    fe.b = ResolveBodyPoint(f.b, PartOf(source, "b"), "end");
    fe.stiffness = f.stiffness;
    fe.damping = f.damping;
    fe.rest_length = f.rest_length;
    fe.actuator = f.actuator;
    builder_.AddForceElement(fe);
  }
}

// Actuators on the rods of soft bodies (one per actuation entry, same index).
void SceneCompiler::AddActuators() {
  for (const ActuatorSpec& s : spec_.actuators) {
    Actuator a;
    a.name = s.name;
    a.type = s.type;
    a.rod = RodOf(s.body);
    a.from = s.from;
    a.to = s.to;
    a.area = s.area;
    a.offset = s.offset;
    a.max_stress = s.max_stress;
    a.vector = s.vector;
    a.profile = s.profile;
    builder_.AddActuator(a);
  }
}

// --- outputs ---------------------------------------------------------------------------------

void SceneCompiler::AddOutputs(const Model& model, OutputSpec* out) const {
  const OutputsSpec& o = spec_.outputs;
  for (std::size_t i = 0; i < o.points.size(); ++i) {
    const OutputPointSpec& p = o.points[i];
    const EntitySource& source = SourceOf(src_.output_points, i);
    const BodySpec& body = spec_.bodies[static_cast<std::size_t>(p.body)];
    OutputPoint op;
    op.name = p.name;
    if (!p.along_rod) {
      op.node = NodeAt(p.body, p.at, PartOf(source, "at"), "output point");
      if (body.rigid) op.offset = p.at - body.origin;
    } else {
      op.rod = RodOf(p.body);
      op.arc_length = p.arc_length;
      const double length = model.rods[static_cast<std::size_t>(op.rod)].length;
      if (op.arc_length > length * (1.0 + 1e-12)) {
        std::ostringstream s;
        s.precision(9);
        s << "arc length beyond the end of the rod (length " << length << " m)";
        Fail(PartOf(source, "s"), s.str());
      }
    }
    out->points.push_back(op);
  }
  // By default every joint with coordinates, in joint order.
  std::vector<int> joints = o.joints;
  if (o.all_joints) {
    joints.clear();
    for (std::size_t j = 0; j < spec_.joints.size(); ++j)
      if (GetJointTypeInfo(spec_.joints[j].joint.type).dof > 0)
        joints.push_back(static_cast<int>(j));
  }
  for (int j : joints) out->joints.push_back({model.joints[static_cast<std::size_t>(j)].name, j});
  const AnalysisSettings& a = spec_.analysis;
  out->interval = o.interval >= 0.0 ? o.interval : DefaultOutputInterval(a, kDefaultOutputRows);
  out->vtk = o.vtk;
  out->vtk_format = o.vtk_format;
  out->vtk_interval = o.vtk_interval >= 0.0 ? o.vtk_interval
                      : o.interval >= 0.0   ? 0.0  // the same as the given interval
                                            : DefaultOutputInterval(a, kDefaultVtkFrames);
  out->rod_fields = o.rod_fields;
  out->rod_fields_interval = o.rod_fields_interval;
  out->max_rows = o.max_rows;
  out->reactions = o.reactions;
  out->energy = o.energy;
}

void SceneCompiler::CheckReferences() const {
  const int n = static_cast<int>(spec_.bodies.size());
  auto check = [&](int b, bool ground_allowed, const EntitySource& source, const char* what) {
    if ((b < 0 && !(ground_allowed && b == -1)) || b >= n)
      Fail(source.self, std::string(what) + ": no body " + std::to_string(b));
  };
  for (std::size_t i = 0; i < spec_.bodies.size(); ++i) {
    const BodySpec& b = spec_.bodies[i];
    if (!b.rigid && b.path.size() < 2)
      Fail(BodySource(static_cast<int>(i)).self,
           "soft body '" + b.name + "': a path needs at least two points");
    check(b.weld_start, true, BodySource(static_cast<int>(i)), "weld_start");
    check(b.weld_end, true, BodySource(static_cast<int>(i)), "weld_end");
    if (b.weld_start >= static_cast<int>(i) || b.weld_end >= static_cast<int>(i) ||
        (b.weld_start >= 0 && spec_.bodies[static_cast<std::size_t>(b.weld_start)].rigid) ||
        (b.weld_end >= 0 && spec_.bodies[static_cast<std::size_t>(b.weld_end)].rigid))
      Fail(BodySource(static_cast<int>(i)).self, "a weld needs a soft body defined earlier");
  }
  for (std::size_t i = 0; i < spec_.joints.size(); ++i) {
    check(spec_.joints[i].body_a, true, SourceOf(src_.joints, i), "joint side a");
    check(spec_.joints[i].body_b, true, SourceOf(src_.joints, i), "joint side b");
  }
  for (std::size_t i = 0; i < spec_.loads.size(); ++i) {
    const LoadSpec& l = spec_.loads[i];
    check(l.body, false, SourceOf(src_.loads, i), "load");
    if (l.where != LoadSpec::Where::kAt && spec_.bodies[static_cast<std::size_t>(l.body)].rigid)
      Fail(SourceOf(src_.loads, i).self, "'s' and 'distributed' apply to soft bodies only");
  }
  for (std::size_t i = 0; i < spec_.actuators.size(); ++i) {
    const int b = spec_.actuators[i].body;
    check(b, false, SourceOf(src_.actuators, i), "actuator");
    if (spec_.bodies[static_cast<std::size_t>(b)].rigid)
      Fail(SourceOf(src_.actuators, i).self, "actuation acts on soft bodies (rods)");
  }
  for (std::size_t i = 0; i < spec_.outputs.points.size(); ++i) {
    const OutputPointSpec& p = spec_.outputs.points[i];
    check(p.body, false, SourceOf(src_.output_points, i), "output point");
    if (p.along_rod && spec_.bodies[static_cast<std::size_t>(p.body)].rigid)
      Fail(SourceOf(src_.output_points, i).self, "a point along a rod needs a soft body");
  }
  for (std::size_t i = 0; i < spec_.tendons.size(); ++i)
    for (const BodyPointSpec& p : spec_.tendons[i].eyelets) {
      check(p.body, !p.routed, SourceOf(src_.tendons, i), "eyelet");
      if (p.routed && spec_.bodies[static_cast<std::size_t>(p.body)].rigid)
        Fail(SourceOf(src_.tendons, i).self, "a route runs along a soft body");
    }
  for (std::size_t i = 0; i < spec_.forces.size(); ++i) {
    check(spec_.forces[i].a.body, true, SourceOf(src_.forces, i), "end a");
    check(spec_.forces[i].b.body, true, SourceOf(src_.forces, i), "end b");
  }
  if (!spec_.outputs.all_joints)
    for (int j : spec_.outputs.joints) {
      if (j < 0 || j >= static_cast<int>(spec_.joints.size()))
        Fail(src_.root, "outputs: no joint " + std::to_string(j));
      const JointSpec& joint = spec_.joints[static_cast<std::size_t>(j)].joint;
      if (GetJointTypeInfo(joint.type).dof == 0)
        Fail(SourceOf(src_.joints, static_cast<std::size_t>(j)).self,
             "outputs: joint '" + joint.name + "' is fixed: it has no coordinates to record");
    }
}

// The contact: section, the rods' capsule chains and the rigid bodies' shapes (in body order).
void SceneCompiler::AddContacts() {
  const ContactSpec& c = spec_.contact;
  if (!c.present) return;
  builder_.SetContactSettings(c.settings);
  for (const ContactObstacle& o : c.obstacles) builder_.AddObstacle(o);
  for (std::size_t b = 0; b < spec_.bodies.size(); ++b) {
    const BodySpec& s = spec_.bodies[b];
    if (s.rigid) {
      for (ContactShape shape : s.shapes) {
        shape.body = rigid_of_[b];
        builder_.AddContactShape(shape);
        contact_shape_body_.push_back(static_cast<int>(b));
      }
    } else {
      if (!(s.contact_radius > 0.0))
        Fail(BodySource(static_cast<int>(b)).self,
             "a soft body in a scene with contact needs 'contact_radius' (its section has no "
             "radius)");
      builder_.AddContactRod(rod_of_[b], s.contact_radius);
      contact_rod_body_.push_back(static_cast<int>(b));
    }
    if (s.contype != 1u || s.conaffinity != 1u)
      builder_.SetContactGroup(EntityOf(static_cast<int>(b)), s.contype, s.conaffinity);
  }
  for (const auto& [b, obstacle] : c.exclude)
    // Obstacles are added in spec order (an index out of range is Build's error).
    builder_.ExcludeContact(EntityOf(b), ObstacleId(obstacle));
  for (const auto& [a, b] : c.exclude_bodies) builder_.ExcludeContactPair(EntityOf(a), EntityOf(b));
  for (const ContactGroupSpec& g : c.groups) {
    std::vector<ContactEntity> members;
    for (int b : g.bodies) members.push_back(EntityOf(b));
    std::vector<ObstacleId> obstacles;
    for (int o : g.obstacles) obstacles.push_back(ObstacleId(o));
    builder_.AddContactMaterialGroup(g.name, members, obstacles);
  }
  for (const ContactMaterial& m : c.pairs) builder_.AddContactMaterial(m);
}

Scene SceneCompiler::Compile() {
  CheckReferences();
  Scene scene;
  scene.source = src_.file;
  scene.name = spec_.name;
  builder_.SetGravity(spec_.gravity);
  for (const auto& [name, default_value] : spec_.inputs) builder_.AddInput(name, default_value);
  builder_.model().rod_inertia = spec_.rod_inertia;
  builder_.model().linear_solver = spec_.linear_solver;
  builder_.SetConformMesh(spec_.conform_mesh);
  AddBodies();
  AddJoints();
  AddLoads();
  AddTendonsAndForces();
  AddActuators();
  AddContacts();
  CheckConnections();
  scene.analysis = spec_.analysis;
  // Statics evaluates the profiles at the end time (static analyses) or at the start time
  // (the preload of a dynamic analysis).
  scene.analysis.statics.time = spec_.analysis.kind == AnalysisKind::kStatic
                                    ? spec_.analysis.end_time
                                    : spec_.analysis.start_time;
  try {
    scene.model = builder_.Build();
  } catch (const InputError& e) {
    RethrowBuildError(e);
  }
  AddOutputs(scene.model, &scene.outputs);
  scene.named_points = spec_.points;
  return scene;
}

}  // namespace

Scene CompileScene(const SceneSpec& spec, const SceneSources& sources) {
  return SceneCompiler(spec, sources).Compile();
}

namespace {

// "collection.name", or "collection[i]" for an entity without a name.
std::string EntityField(const char* collection, const std::string& name, std::size_t i) {
  return name.empty() ? std::string(collection) + "[" + std::to_string(i) + "]"
                      : std::string(collection) + "." + name;
}

// An entity's source and its parts (part name, the key under the entity's field).
template <typename T, typename Name>
std::vector<EntitySource> NamedEntities(
    const std::vector<T>& items, const char* collection, Name name,
    const std::vector<std::pair<std::string, std::string>>& parts) {
  std::vector<EntitySource> out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    EntitySource e;
    e.self.field = EntityField(collection, name(items[i]), i);
    for (const auto& [part, key] : parts)
      e.parts.emplace_back(part, FieldSource{{}, e.self.field + "." + key});
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

SceneSources NamedSources(const SceneSpec& spec, const std::string& source_name) {
  SceneSources s;
  s.file = source_name;
  const auto named = [](const auto& x) { return x.name; };
  s.bodies = NamedEntities(spec.bodies, "bodies", named,
                           {{"start_node", "weld_start"}, {"end_node", "weld_end"}});
  for (std::size_t b = 0; b < spec.bodies.size(); ++b)
    for (std::size_t k = 0; k < spec.bodies[b].path.size(); ++k) {
      const std::string part = "path[" + std::to_string(k) + "]";
      s.bodies[b].parts.emplace_back(part, FieldSource{{}, s.bodies[b].self.field + "." + part});
    }
  s.joints =
      NamedEntities(spec.joints, "joints", [](const JointEntrySpec& j) { return j.joint.name; },
                    {{"node_a", "between[0]"}, {"node_b", "between[1]"}});
  s.loads = NamedEntities(spec.loads, "loads", named, {{"at", "at"}, {"s", "s"}});
  s.output_points =
      NamedEntities(spec.outputs.points, "outputs.points", named, {{"at", "at"}, {"s", "s"}});
  s.tendons =
      NamedEntities(spec.tendons, "tendons", named, {{"tension", "tension"}, {"length", "length"}});
  for (std::size_t t = 0; t < spec.tendons.size(); ++t)
    for (std::size_t k = 0; k < spec.tendons[t].eyelets.size(); ++k) {
      const std::string part = "eyelets[" + std::to_string(k) + "]";
      s.tendons[t].parts.emplace_back(part, FieldSource{{}, s.tendons[t].self.field + "." + part});
    }
  s.forces = NamedEntities(spec.forces, "forces", named, {{"a", "a"}, {"b", "b"}});
  s.actuators = NamedEntities(
      spec.actuators, "actuation", named,
      {{"rod", "rod"}, {"from", "from"}, {"to", "to"}, {"area", "area"}, {"offset", "offset"}});
  return s;
}

Scene CompileScene(const SceneSpec& spec, const std::string& source_name) {
  return CompileScene(spec, NamedSources(spec, source_name));
}

}  // namespace screwfem
