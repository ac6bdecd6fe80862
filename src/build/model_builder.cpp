#include "screwfem/build/model_builder.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>

#include "screwfem/elements/shape_pair.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

std::string NodeLabel(const Model& m, int node) {
  if (node == kGround) return "ground";
  const Node& n = m.nodes[static_cast<std::size_t>(node)];
  return n.name.empty() ? "node " + std::to_string(node) : "node '" + n.name + "'";
}

bool IsFinite(const SE3& H) { return H.R.allFinite() && H.x.allFinite(); }

bool IsRotation(const Mat3& R) {
  return (R.transpose() * R - Mat3::Identity()).norm() < 1e-9 && R.determinant() > 0.0;
}

// The rod that a node belongs to ("'name'"), or the node's label when no rod has it.
std::string OwnerLabel(const Model& m, int node) {
  for (const Rod& r : m.rods)
    if (std::find(r.nodes.begin(), r.nodes.end(), node) != r.nodes.end()) return "'" + r.name + "'";
  return NodeLabel(m, node);
}

// Profile::Validate (input terms refer to one of the model's inputs), with the entity that owns
// the profile in the error.
void ValidateProfile(const Model& m, const Profile& profile, const std::string& label,
                     const EntityRef& entity) {
  try {
    profile.Validate(label.c_str(), static_cast<int>(m.inputs.size()));
  } catch (const InputError& e) {
    throw InputError(e.what(), entity);
  }
}

}  // namespace

int ModelBuilder::AddNode(const SE3& frame, std::string name) {
  Node n;
  n.name = std::move(name);
  n.reference = frame;
  model_.nodes.push_back(n);
  return static_cast<int>(model_.nodes.size()) - 1;
}

void ModelBuilder::FixNode(int node) {
  if (node < 0 || node >= static_cast<int>(model_.nodes.size()))
    throw InputError("FixNode: no node " + std::to_string(node));
  model_.nodes[static_cast<std::size_t>(node)].fixed = true;
}

int ModelBuilder::AddStraightRod(std::string name, const Vec3& p0, const Vec3& p1,
                                 int num_elements, const Section& section, const Vec3& up,
                                 int start_node, int end_node) {
  const double length = (p1 - p0).norm();
  if (!(length > 0.0) || !std::isfinite(length))
    throw InputError("rod '" + name + "': zero length (its end points coincide)", NextRod());
  SE3 root;
  root.R = FrameAlong(p1 - p0, up);
  root.x = p0;
  return AddStraightRodFromFrame(std::move(name), root, length, num_elements, section, start_node,
                                 end_node);
}

int ModelBuilder::AddStraightRodFromFrame(std::string name, const SE3& root, double length,
                                          int num_elements, const Section& section,
                                          int start_node, int end_node) {
  if (num_elements < 1)
    throw InputError("rod '" + name + "': needs at least one element, got " +
                         std::to_string(num_elements),
                     NextRod());
  if (!(length > 0.0) || !std::isfinite(length))
    throw InputError("rod '" + name + "': length must be positive", NextRod());
  std::vector<int> nodes;
  for (int i = 0; i <= num_elements; ++i) {
    SE3 H = root;
    H.x = root.x + root.R.col(0) * (length * i / num_elements);
    if (i == 0 && start_node >= 0) {
      nodes.push_back(start_node);
    } else if (i == num_elements && end_node >= 0) {
      nodes.push_back(end_node);
    } else {
      nodes.push_back(AddNode(H, name.empty() ? std::string{} : name + "." + std::to_string(i)));
    }
  }
  return AddRodThroughNodes(std::move(name), nodes, section);
}

int ModelBuilder::AddRodThroughNodes(std::string name, const std::vector<int>& nodes,
                                     const Section& section) {
  Rod rod;
  rod.name = std::move(name);
  rod.section = section;
  rod.nodes = nodes;
  rod.num_elements = static_cast<int>(nodes.size()) - 1;
  model_.rods.push_back(rod);
  return static_cast<int>(model_.rods.size()) - 1;
}

namespace {

// Frames of the nodes of a rod along a polyline with n elements per segment (AddRodAlongPath).
// Throws InputError for `rod` with the part "path[i]" of the offending point.
std::vector<SE3> PathNodeFrames(const std::string& name, const EntityRef& rod,
                                const std::vector<Vec3>& pts, int n, const Vec3& up) {
  auto fail = [&](std::size_t i, const std::string& detail) {
    const std::string part = "path[" + std::to_string(i) + "]";
    throw InputError("rod '" + name + "': " + part + ": " + detail,
                     {rod.kind, rod.index, part}, detail);
  };
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (!pts[i].allFinite()) fail(i, "the point is not finite");
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (!((pts[i] - pts[i - 1]).norm() > 1e-12 * std::max(1.0, pts[i].norm())))
      fail(i, "zero-length segment (its end points coincide)");
  const std::size_t segs = pts.size() - 1;
  std::vector<Vec3> dir(segs);
  for (std::size_t i = 0; i < segs; ++i) dir[i] = (pts[i + 1] - pts[i]).normalized();
  // At path point i: along the segment at the ends, along the bisector inside.
  auto vertex_frame = [&](std::size_t i) {
    const Vec3 t = i == 0 ? dir[0] : i == segs ? dir[segs - 1] : Vec3(dir[i - 1] + dir[i]);
    if (!(t.norm() > 1e-6)) fail(i, "the path turns back on itself here");
    return FrameAlong(t, up);
  };
  std::vector<SE3> frames;
  frames.reserve(segs * static_cast<std::size_t>(n) + 1);
  SE3 H;
  H.R = vertex_frame(0);
  H.x = pts[0];
  frames.push_back(H);
  for (std::size_t s = 0; s < segs; ++s) {
    for (int e = 1; e <= n; ++e) {
      const bool vertex = e == n;
      H.R = vertex ? vertex_frame(s + 1) : FrameAlong(dir[s], up);
      H.x = vertex ? pts[s + 1]
                   : Vec3(pts[s] + (pts[s + 1] - pts[s]) * (static_cast<double>(e) / n));
      frames.push_back(H);
    }
  }
  return frames;
}

}  // namespace

int ModelBuilder::AddRodAlongPath(std::string name, const std::vector<Vec3>& path,
                                  int elements_per_segment, const Section& section,
                                  const Vec3& up, int start_node, int end_node) {
  const EntityRef rod = NextRod();
  const std::string label = "rod '" + name + "'";
  if (path.size() < 2)
    throw InputError(label + ": a path needs at least two points", rod);
  if (elements_per_segment < 1)
    throw InputError(label + ": needs at least one element per segment, got " +
                         std::to_string(elements_per_segment),
                     rod);
  if (!up.allFinite() || !(up.norm() > 0.0))
    throw InputError(label + ": the up vector must be finite and non-zero", rod);
  const std::vector<SE3> frames = PathNodeFrames(name, rod, path, elements_per_segment, up);
  // A shared end node must sit at the path's end with the same section frame (else the rod
  // would start with a kink that no element carries).
  auto check_shared = [&](int node, const SE3& H, const char* part) {
    if (node < 0) return;
    std::string detail;
    if (node >= static_cast<int>(model_.nodes.size())) {
      detail = "no node " + std::to_string(node);
    } else {
      const SE3& Ho = model_.nodes[static_cast<std::size_t>(node)].reference;
      const double tol = 1e-8 * std::max({1.0, H.x.norm(), (path.back() - path.front()).norm()});
      if ((Ho.x - H.x).norm() > tol)
        detail = NodeLabel(model_, node) + " is not at the path's end";
      else if ((Ho.R - H.R).norm() > 1e-9)
        detail = "the section frames of '" + name + "' and " + OwnerLabel(model_, node) +
                 " differ at the shared node (a kink or a different up vector); join them by a "
                 "fixed joint instead";
    }
    if (!detail.empty())
      throw InputError(label + ": " + part + ": " + detail, {rod.kind, rod.index, part}, detail);
  };
  check_shared(start_node, frames.front(), "start_node");
  check_shared(end_node, frames.back(), "end_node");
  // Two points: the straight rod (its node positions are computed along the frame's x axis).
  if (path.size() == 2)
    return AddStraightRod(std::move(name), path[0], path[1], elements_per_segment, section, up,
                          start_node, end_node);
  std::vector<int> nodes;
  nodes.reserve(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (i == 0 && start_node >= 0) {
      nodes.push_back(start_node);
    } else if (i + 1 == frames.size() && end_node >= 0) {
      nodes.push_back(end_node);
    } else {
      nodes.push_back(
          AddNode(frames[i], name.empty() ? std::string{} : name + "." + std::to_string(i)));
    }
  }
  return AddRodThroughNodes(std::move(name), nodes, section);
}

NodeMatch ModelBuilder::FindNodeAt(const Vec3& p, int rod, double tolerance) const {
  const Model& m = model_;
  if (rod >= static_cast<int>(m.rods.size()))
    throw InputError("FindNodeAt: no rod " + std::to_string(rod));
  NodeMatch match;
  match.distance = std::numeric_limits<double>::infinity();
  auto valid = [&](int n) { return n >= 0 && n < static_cast<int>(m.nodes.size()); };
  auto consider = [&](int n) {
    if (!valid(n)) return;
    const double d = (m.nodes[static_cast<std::size_t>(n)].reference.x - p).norm();
    if (d < match.distance) {
      match.distance = d;
      match.nearest = n;
    }
  };
  double extent = 0.0;
  if (rod >= 0) {
    const Rod& r = m.rods[static_cast<std::size_t>(rod)];
    for (int n : r.nodes) consider(n);
    if (!r.nodes.empty() && valid(r.nodes.front()) && valid(r.nodes.back()))
      extent = (m.nodes[static_cast<std::size_t>(r.nodes.front())].reference.x -
                m.nodes[static_cast<std::size_t>(r.nodes.back())].reference.x)
                   .norm();
  } else {
    for (int n = 0; n < static_cast<int>(m.nodes.size()); ++n) consider(n);
  }
  if (tolerance < 0.0) tolerance = 1e-8 * std::max({1.0, p.norm(), extent});
  if (match.distance <= tolerance) match.node = match.nearest;
  return match;
}

double ModelBuilder::RodLength(int rod) const {
  const Model& m = model_;
  if (rod < 0 || rod >= static_cast<int>(m.rods.size()))
    throw InputError("RodLength: no rod " + std::to_string(rod));
  const Rod& r = m.rods[static_cast<std::size_t>(rod)];
  const int num_nodes = static_cast<int>(m.nodes.size());
  for (int n : r.nodes)
    if (n < 0 || n >= num_nodes) throw InputError("RodLength: rod " + std::to_string(rod) + " has an invalid node");
  double length = 0.0;
  for (std::size_t i = 0; i + 1 < r.nodes.size(); ++i)
    length += LogSE3(m.nodes[static_cast<std::size_t>(r.nodes[i])].reference.Inverse() *
                     m.nodes[static_cast<std::size_t>(r.nodes[i + 1])].reference)
                  .head<3>()
                  .norm();
  return length;
}

int ModelBuilder::AddRigidBody(std::string name, int node, double mass, const Vec3& com,
                               const Mat3& inertia) {
  RigidBody b;
  b.name = std::move(name);
  b.node = node;
  b.mass = mass;
  b.com = com;
  b.inertia = inertia;
  model_.bodies.push_back(b);
  return static_cast<int>(model_.bodies.size()) - 1;
}

int ModelBuilder::AddJoint(const Joint& joint) {
  model_.joints.push_back(joint);
  return static_cast<int>(model_.joints.size()) - 1;
}

int ModelBuilder::AddJointAt(std::string name, JointType type, int node_a, int node_b,
                             const Vec3& point, const Vec3& axis, const Vec3& axis2,
                             double pitch) {
  const int n = static_cast<int>(model_.nodes.size());
  const int index = static_cast<int>(model_.joints.size());
  const std::string label = "joint '" + name + "'";
  auto check = [&](int node, const char* part) {
    if (node != kGround && (node < 0 || node >= n)) {
      const std::string detail = "invalid node " + std::to_string(node);
      throw InputError(label + ": " + detail, {EntityKind::kJoint, index, part}, detail);
    }
  };
  check(node_a, "node_a");
  check(node_b, "node_b");
  const JointTypeInfo& info = GetJointTypeInfo(type);
  if (info.uses_axis && !(std::abs(axis.norm() - 1.0) < 1e-9))
    throw InputError(label + ": axis must be a unit vector", {EntityKind::kJoint, index, {}});
  if (info.uses_axis2 &&
      (!(std::abs(axis2.norm() - 1.0) < 1e-9) || std::abs(axis.dot(axis2)) > 1e-9))
    throw InputError(label + ": universal joint axes must be orthogonal unit vectors",
                     {EntityKind::kJoint, index, {}});
  Joint j;
  j.name = std::move(name);
  j.type = type;
  j.node_a = node_a;
  j.node_b = node_b;
  j.pitch = pitch;
  j.basis = JointBasis(type, axis, axis2, pitch);
  const SE3 frame = SE3::Translation(point);
  const auto ref = [&](int node) { return NodeReferenceFrame(model_, node); };
  j.offset_a = ref(node_a).Inverse() * frame;
  j.offset_b = ref(node_b).Inverse() * frame;
  return AddJoint(j);
}

int ModelBuilder::AddJoint(const JointSpec& spec) {
  const int index = AddJointAt(spec.name, spec.type, spec.node_a, spec.node_b, spec.point,
                               spec.axis, spec.axis2, spec.pitch);
  Joint& j = model_.joints[static_cast<std::size_t>(index)];
  j.stiffness = spec.stiffness;
  j.damping = spec.damping;
  j.rest = spec.rest;
  j.drive = spec.drive;
  j.drive_coord = spec.drive_coordinate;
  j.drive_profile = spec.drive_profile;
  j.has_initial_coordinate = spec.has_initial_coordinate;
  j.initial_coordinate = spec.initial_coordinate;
  j.has_initial_rate = spec.has_initial_rate;
  j.initial_rate = spec.initial_rate;
  return index;
}

int ModelBuilder::AddTendon(std::string name, std::vector<BodyPoint> eyelets,
                           const Profile& tension) {
  Tendon t;
  t.name = std::move(name);
  t.eyelets = std::move(eyelets);
  t.tension = tension;
  model_.tendons.push_back(std::move(t));
  return static_cast<int>(model_.tendons.size()) - 1;
}

int ModelBuilder::AddLengthDrivenTendon(std::string name, std::vector<BodyPoint> eyelets,
                                        const Profile& length) {
  const int index = AddTendon(std::move(name), std::move(eyelets), Profile::Constant(0.0));
  Tendon& t = model_.tendons[static_cast<std::size_t>(index)];
  t.drive = TendonDrive::kLength;
  t.length = length;
  return index;
}

int ModelBuilder::AddForceElement(const ForceElement& element) {
  model_.force_elements.push_back(element);
  return static_cast<int>(model_.force_elements.size()) - 1;
}

NodeMatch ModelBuilder::FindRodNodeAtArcLength(int rod, double s, double tolerance) const {
  const double length = RodLength(rod);  // validates the rod and its nodes
  const Rod& r = model_.rods[static_cast<std::size_t>(rod)];
  if (tolerance < 0.0) tolerance = 1e-8 * std::max(1.0, length);
  NodeMatch match;
  match.distance = std::numeric_limits<double>::infinity();
  double arc = 0.0;
  for (std::size_t i = 0; i < r.nodes.size(); ++i) {
    if (i > 0)
      arc += LogSE3(model_.nodes[static_cast<std::size_t>(r.nodes[i - 1])].reference.Inverse() *
                    model_.nodes[static_cast<std::size_t>(r.nodes[i])].reference)
                 .head<3>()
                 .norm();
    const double distance = std::abs(arc - s);
    if (distance < match.distance) {
      match.distance = distance;
      match.nearest = r.nodes[i];
    }
  }
  if (match.distance <= tolerance) match.node = match.nearest;
  return match;
}

int ModelBuilder::AddActuator(const Actuator& actuator) {
  model_.actuators.push_back(actuator);
  return static_cast<int>(model_.actuators.size()) - 1;
}

int ModelBuilder::AddPointLoad(const PointLoad& load) {
  model_.point_loads.push_back(load);
  return static_cast<int>(model_.point_loads.size()) - 1;
}

int ModelBuilder::AddRodLoad(const RodLoad& load) {
  model_.rod_loads.push_back(load);
  return static_cast<int>(model_.rod_loads.size()) - 1;
}

void ModelBuilder::SetGravity(const Vec3& g) { model_.gravity = g; }

void ModelBuilder::SetInitialVelocity(int node, const Vec6& velocity) {
  if (node < 0 || node >= static_cast<int>(model_.nodes.size()))
    throw InputError("initial velocity: invalid node " + std::to_string(node));
  model_.nodes[static_cast<std::size_t>(node)].has_initial_velocity = true;
  model_.nodes[static_cast<std::size_t>(node)].initial_velocity = velocity;
}

int ModelBuilder::AddInput(std::string name, double default_value) {
  model_.inputs.push_back(ModelInput{std::move(name), default_value});
  return static_cast<int>(model_.inputs.size()) - 1;
}

int ModelBuilder::AddContactRod(int rod, double radius) {
  model_.contact_rods.push_back({rod, radius});
  return static_cast<int>(model_.contact_rods.size()) - 1;
}

int ModelBuilder::AddContactShape(const ContactShape& shape) {
  model_.contact_shapes.push_back(shape);
  return static_cast<int>(model_.contact_shapes.size()) - 1;
}

int ModelBuilder::AddObstacle(const ContactObstacle& obstacle) {
  model_.obstacles.push_back(obstacle);
  return static_cast<int>(model_.obstacles.size()) - 1;
}

void ModelBuilder::SetContactGroup(bool rod, int index, unsigned contype, unsigned conaffinity) {
  model_.contact_groups.push_back({rod, index, contype, conaffinity});
}

void ModelBuilder::ExcludeContact(bool rod, int index, int obstacle) {
  model_.contact_exclusions.push_back({rod, index, obstacle});
}

void ModelBuilder::ExcludeContactPair(bool rod_a, int index_a, bool rod_b, int index_b) {
  model_.contact_pair_exclusions.push_back({{rod_a, rod_b}, {index_a, index_b}});
}

void ModelBuilder::SetContactSettings(const ContactSettings& settings) {
  model_.contact = settings;
}

namespace {

// Node frames are finite rigid transformations with unique names; gravity is finite.
void ValidateNodes(const Model& m) {
  {
    std::set<std::string> names;
    for (std::size_t i = 0; i < m.nodes.size(); ++i) {
      const Node& n = m.nodes[i];
      const EntityRef entity{EntityKind::kNode, static_cast<int>(i), {}};
      if (!IsFinite(n.reference) || !IsRotation(n.reference.R))
        throw InputError("node '" + n.name + "': frame is not a finite rigid transformation",
                         entity);
      if (!n.name.empty() && !names.insert(n.name).second)
        throw InputError("duplicate node name '" + n.name + "'", entity);
      if (n.has_initial_velocity && !n.initial_velocity.allFinite())
        throw InputError("node '" + n.name + "': initial velocity must be finite", entity);
      if (n.has_initial_velocity && n.fixed && !n.initial_velocity.isZero())
        throw InputError("node '" + n.name + "': a fixed node cannot have an initial velocity",
                         entity);
    }
  }
  if (!m.gravity.allFinite()) throw InputError("gravity must be finite");
  std::set<std::string> input_names;
  for (const ModelInput& in : m.inputs) {
    if (in.name.empty()) throw InputError("inputs: an input needs a name");
    if (!input_names.insert(in.name).second)
      throw InputError("inputs: duplicate input name '" + in.name + "'");
    if (!std::isfinite(in.default_value))
      throw InputError("inputs: the default of input '" + in.name + "' must be finite");
  }
}

// Rod sections and the elements of every rod (reference relative motion d0, length); marks
// the nodes rods use. Rod names are unique.
void BuildRodElements(Model& m, std::vector<char>& used) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  auto valid_node = [&](int n) { return n >= 0 && n < num_nodes; };
  m.elements.clear();
  for (std::size_t r = 0; r < m.rods.size(); ++r) {
    Rod& rod = m.rods[r];
    const std::string label = "rod '" + rod.name + "'";
    const EntityRef entity{EntityKind::kRod, static_cast<int>(r), {}};
    if (rod.num_elements < 1) throw InputError(label + ": needs at least two nodes", entity);
    for (int i = 0; i < 6; ++i) {
      if (!(rod.section.stiffness(i) > 0.0) || !std::isfinite(rod.section.stiffness(i)))
        throw InputError(label + ": section stiffness entries must be positive", entity);
      if (!(rod.section.inertia(i) >= 0.0) || !(rod.section.damping(i) >= 0.0))
        throw InputError(label + ": section inertia and damping must be non-negative", entity);
    }
    if (!(rod.section.rayleigh_mass >= 0.0) || !std::isfinite(rod.section.rayleigh_mass) ||
        !(rod.section.rayleigh_stiffness >= 0.0) || !std::isfinite(rod.section.rayleigh_stiffness))
      throw InputError(label + ": Rayleigh damping coefficients must be finite and non-negative", entity);
    rod.first_element = static_cast<int>(m.elements.size());
    rod.length = 0.0;
    for (int e = 0; e < rod.num_elements; ++e) {
      RodElement el;
      el.rod = static_cast<int>(r);
      el.node_a = rod.nodes[static_cast<std::size_t>(e)];
      el.node_b = rod.nodes[static_cast<std::size_t>(e) + 1];
      if (!valid_node(el.node_a) || !valid_node(el.node_b) || el.node_a == el.node_b)
        throw InputError(label + ": element " + std::to_string(e) + " has invalid nodes", entity);
      const SE3 rel = m.nodes[static_cast<std::size_t>(el.node_a)].reference.Inverse() *
                      m.nodes[static_cast<std::size_t>(el.node_b)].reference;
      el.d0 = LogSE3(rel);
      el.length = el.d0.head<3>().norm();
      if (!(el.length > 1e-12 * std::max(1.0, rel.x.norm())))
        throw InputError(label + ": element " + std::to_string(e) +
                         " has zero length (its nodes coincide)", entity);
      if (el.d0.tail<3>().norm() > 3.14159265358979323846 - 1e-3)
        throw InputError(label + ": element " + std::to_string(e) +
                         " is curved by more than pi in its reference state; use more elements",
                         entity);
      rod.length += el.length;
      used[static_cast<std::size_t>(el.node_a)] = used[static_cast<std::size_t>(el.node_b)] = 1;
      m.elements.push_back(el);
    }
  }
  {
    std::set<std::string> names;
    for (std::size_t r = 0; r < m.rods.size(); ++r)
      if (!m.rods[r].name.empty() && !names.insert(m.rods[r].name).second)
        throw InputError("duplicate rod name '" + m.rods[r].name + "'",
                         {EntityKind::kRod, static_cast<int>(r), {}});
  }
}

// Rigid bodies: node, positive mass, finite centre of mass, symmetric positive definite inertia,
// unique names; marks their nodes.
void ValidateBodies(const Model& m, std::vector<char>& used) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  auto valid_node = [&](int n) { return n >= 0 && n < num_nodes; };
  {
    std::set<std::string> names;
    for (std::size_t i = 0; i < m.bodies.size(); ++i) {
      const RigidBody& b = m.bodies[i];
      const std::string label = "body '" + b.name + "'";
      const EntityRef entity{EntityKind::kBody, static_cast<int>(i), {}};
      if (!valid_node(b.node)) throw InputError(label + ": invalid node", entity);
      if (!(b.mass > 0.0) || !std::isfinite(b.mass))
        throw InputError(label + ": mass must be positive", entity);
      if (!b.com.allFinite()) throw InputError(label + ": centre of mass must be finite", entity);
      const Mat3 J = 0.5 * (b.inertia + b.inertia.transpose());
      if (!b.inertia.allFinite() || (b.inertia - J).norm() > 1e-12 * std::max(1.0, J.norm()))
        throw InputError(label + ": inertia must be a finite symmetric matrix", entity);
      Eigen::LLT<Mat3> llt(J);
      if (llt.info() != Eigen::Success)
        throw InputError(label + ": inertia must be positive definite", entity);
      if (!b.name.empty() && !names.insert(b.name).second)
        throw InputError("duplicate body name '" + b.name + "'", entity);
      used[static_cast<std::size_t>(b.node)] = 1;
    }
  }
}

// Joints: sides, offsets, basis, springs, drives (on global coordinates only), unique names;
// marks their nodes.
void ValidateJoints(const Model& m, std::vector<char>& used) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  auto valid_node = [&](int n) { return n >= 0 && n < num_nodes; };
  {
    std::set<std::string> names;
    for (std::size_t i = 0; i < m.joints.size(); ++i) {
      const Joint& j = m.joints[i];
      const std::string label = "joint '" + j.name + "'";
      const EntityRef entity{EntityKind::kJoint, static_cast<int>(i), {}};
      if (j.node_a != kGround && !valid_node(j.node_a))
        throw InputError(label + ": invalid side a", {EntityKind::kJoint, entity.index, "node_a"},
                         "invalid side a");
      if (j.node_b != kGround && !valid_node(j.node_b))
        throw InputError(label + ": invalid side b", {EntityKind::kJoint, entity.index, "node_b"},
                         "invalid side b");
      if (j.node_a == j.node_b)
        throw InputError(label + ": both sides are " + NodeLabel(m, j.node_a), entity);
      if (!IsFinite(j.offset_a) || !IsFinite(j.offset_b) || !IsRotation(j.offset_a.R) ||
          !IsRotation(j.offset_b.R))
        throw InputError(label + ": joint frame offsets must be rigid transformations", entity);
      if (!j.basis.allFinite()) throw InputError(label + ": joint basis must be finite", entity);
      for (int c = 0; c < JointSpringCount(j); ++c) {
        if (!(j.stiffness(c) >= 0.0) || !(j.damping(c) >= 0.0) || !std::isfinite(j.stiffness(c)) ||
            !std::isfinite(j.damping(c)))
          throw InputError(label + ": stiffness and damping must be finite and non-negative",
                         entity);
      }
      if (j.drive != DriveKind::kNone) {
        if (j.drive_coord < 0 || j.drive_coord >= j.k())
          throw InputError(label + ": drive coordinate out of range", entity);
        if (!JointHasGlobalCoordinates(j.type))
          throw InputError(label + ": drives need a joint with global coordinates (not " +
                           JointTypeName(j.type) + ")", entity);
        ValidateProfile(m, j.drive_profile, label, entity);
      }
      if ((j.has_initial_coordinate && !j.initial_coordinate.allFinite()) ||
          (j.has_initial_rate && !j.initial_rate.allFinite()))
        throw InputError(label + ": initial coordinates and rates must be finite", entity);
      if (j.has_initial_coordinate && !JointHasGlobalCoordinates(j.type))
        throw InputError(label + ": initial coordinates need a joint with global coordinates "
                         "(not " + JointTypeName(j.type) + ")", entity);
      if (!j.name.empty() && !names.insert(j.name).second)
        throw InputError("duplicate joint name '" + j.name + "'", entity);
      if (j.node_a != kGround) used[static_cast<std::size_t>(j.node_a)] = 1;
      if (j.node_b != kGround) used[static_cast<std::size_t>(j.node_b)] = 1;
    }
  }
}

// Loads: finite values and valid profiles; a concentrated rod load finds its element and xi.
void PlaceLoads(Model& m) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  auto valid_node = [&](int n) { return n >= 0 && n < num_nodes; };
  for (std::size_t i = 0; i < m.point_loads.size(); ++i) {
    const PointLoad& l = m.point_loads[i];
    const EntityRef entity{EntityKind::kPointLoad, static_cast<int>(i), {}};
    if (!valid_node(l.node))
      throw InputError("point load: invalid node " + std::to_string(l.node), entity);
    const std::string label = "point load on " + NodeLabel(m, l.node);
    if (!l.force.allFinite() || !l.moment.allFinite() || !l.point.allFinite())
      throw InputError(label + ": values must be finite", entity);
    ValidateProfile(m, l.profile, label, entity);
  }
  for (std::size_t i = 0; i < m.rod_loads.size(); ++i) {
    RodLoad& l = m.rod_loads[i];
    const EntityRef entity{EntityKind::kRodLoad, static_cast<int>(i), {}};
    if (l.rod < 0 || l.rod >= static_cast<int>(m.rods.size()))
      throw InputError("rod load: invalid rod " + std::to_string(l.rod), entity);
    const Rod& rod = m.rods[static_cast<std::size_t>(l.rod)];
    const std::string label = "load on rod '" + rod.name + "'";
    if (!l.force.allFinite() || !l.moment.allFinite())
      throw InputError(label + ": values must be finite", entity);
    ValidateProfile(m, l.profile, label, entity);
    if (l.distributed) continue;
    if (!(l.arc_length >= 0.0 && l.arc_length <= rod.length * (1.0 + 1e-12)))
      throw InputError(
          label + ": arc length must be within [0, " + std::to_string(rod.length) + "]", entity);
    double s0 = 0.0;
    l.element = rod.first_element + rod.num_elements - 1;
    for (int k = 0; k < rod.num_elements; ++k) {
      const double L = m.elements[static_cast<std::size_t>(rod.first_element + k)].length;
      if (l.arc_length <= s0 + L || k == rod.num_elements - 1) {
        l.element = rod.first_element + k;
        l.xi = std::clamp((l.arc_length - s0) / L, 0.0, 1.0);
        break;
      }
      s0 += L;
    }
  }
}

// A lower bound of a profile over all times: the sum of each term's lower bound (a ramp or
// step lies between 0 and its scale, a sine between -|scale| and |scale|, a table between its
// extreme values times the scale).
double ProfileLowerBound(const Profile& profile) {
  double bound = 0.0;
  for (const ProfileTerm& t : profile.terms()) {
    switch (t.kind) {
      case ProfileTerm::Kind::kConstant: bound += t.scale; break;
      case ProfileTerm::Kind::kRamp:
      case ProfileTerm::Kind::kBangBang:
      case ProfileTerm::Kind::kSmoothStep: bound += std::min(0.0, t.scale); break;
      case ProfileTerm::Kind::kSine: bound -= std::abs(t.scale); break;
      case ProfileTerm::Kind::kTable: {
        double lo = 0.0;
        for (std::size_t i = 0; i < t.values.size(); ++i) {
          const double v = t.scale * t.values[i];
          lo = i == 0 ? v : std::min(lo, v);
        }
        bound += lo;
        break;
      }
      // A run-time input can take any value; the tension is clamped at 0 when it arrives
      // (TendonTension), so it adds nothing to the bound checked here.
      case ProfileTerm::Kind::kInput: break;
    }
  }
  return bound;
}

// A body point: a valid node (or the ground) and a finite offset; "" when it is, else why not.
std::string BodyPointProblem(const Model& m, const BodyPoint& p) {
  if (p.node != kGround && (p.node < 0 || p.node >= static_cast<int>(m.nodes.size())))
    return "invalid node " + std::to_string(p.node);
  if (!p.offset.allFinite()) return "the offset must be finite";
  return {};
}

Vec3 ReferencePosition(const Model& m, const BodyPoint& p) {
  SE3 H = NodeReferenceFrame(m, p.node);
  if (p.element >= 0)  // the section H_A0 exp(xi d0) of the element
    H = H * ExpSE3(p.xi * m.elements[static_cast<std::size_t>(p.element)].d0);
  return H.x + H.R * p.offset;
}

// An eyelet at an arc length of a rod (BodyPoint::rod >= 0): on the node there (within 1e-8
// of the element length) or between the nodes of the element holding it (element, xi, node A).
// "" when placed, else why not.
std::string PlaceOnRod(const Model& m, BodyPoint& p) {
  if (p.rod < 0) return {};
  if (p.rod >= static_cast<int>(m.rods.size())) return "invalid rod " + std::to_string(p.rod);
  const Rod& rod = m.rods[static_cast<std::size_t>(p.rod)];
  if (!(p.arc_length >= 0.0 && p.arc_length <= rod.length * (1.0 + 1e-12)))
    return "arc length " + std::to_string(p.arc_length) + " m is off the rod (length " +
           std::to_string(rod.length) + " m)";
  double s0 = 0.0;
  for (int k = 0; k < rod.num_elements; ++k) {
    const int e = rod.first_element + k;
    const RodElement& el = m.elements[static_cast<std::size_t>(e)];
    if (p.arc_length <= s0 + el.length || k == rod.num_elements - 1) {
      const double xi = std::clamp((p.arc_length - s0) / el.length, 0.0, 1.0);
      p.element = -1;
      p.xi = 0.0;
      if (xi <= 1e-8) {
        p.node = el.node_a;
      } else if (xi >= 1.0 - 1e-8) {
        p.node = el.node_b;
      } else {
        p.node = el.node_a;
        p.element = e;
        p.xi = xi;
      }
      return {};
    }
    s0 += el.length;
  }
  return "rod '" + rod.name + "' has no elements";
}

// Tendons (method-next.md §N4): eyelets, tension profile, unique names; their segments.
void BuildTendons(Model& m) {
  m.tendon_segments.clear();
  std::set<std::string> names;
  for (std::size_t i = 0; i < m.tendons.size(); ++i) {
    Tendon& t = m.tendons[i];
    const std::string label = "tendon '" + t.name + "'";
    const int index = static_cast<int>(i);
    const EntityRef entity{EntityKind::kTendon, index, {}};
    if (t.eyelets.size() < 2)
      throw InputError(label + ": needs at least two eyelets (it runs between them), got " +
                           std::to_string(t.eyelets.size()),
                       entity);
    for (std::size_t k = 0; k < t.eyelets.size(); ++k) {
      const std::string part = "eyelets[" + std::to_string(k) + "]";
      std::string problem = PlaceOnRod(m, t.eyelets[k]);
      if (problem.empty()) problem = BodyPointProblem(m, t.eyelets[k]);
      if (!problem.empty())
        throw InputError(label + ": eyelet " + std::to_string(k) + ": " + problem,
                         {EntityKind::kTendon, index, part}, problem);
      if (k == 0) continue;
      const double l = (ReferencePosition(m, t.eyelets[k]) - ReferencePosition(m, t.eyelets[k - 1])).norm();
      if (!(l > 1e-9 * std::max(1.0, m.length_scale))) {
        const std::string what = "coincides with eyelet " + std::to_string(k - 1) +
                                 " in the reference configuration (no direction between them)";
        throw InputError(label + ": eyelet " + std::to_string(k) + " " + what,
                         {EntityKind::kTendon, index, part}, what);
      }
    }
    t.reference_length = 0.0;
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k)
      t.reference_length +=
          (ReferencePosition(m, t.eyelets[k + 1]) - ReferencePosition(m, t.eyelets[k])).norm();
    if (t.drive == TendonDrive::kLength) {
      ValidateProfile(m, t.length, label + " length", entity);
      const double lower = ProfileLowerBound(t.length);
      if (!(lower > 0.0))
        throw InputError(label + ": the length profile can become zero or negative (its terms' "
                                 "lower bound is " + std::to_string(lower) + " m)",
                         entity);
    }
    ValidateProfile(m, t.tension, label + " tension", entity);
    const double lower = ProfileLowerBound(t.tension);
    if (lower < 0.0)
      throw InputError(label + ": the tension profile can become negative (its terms' lower "
                               "bound is " + std::to_string(lower) + " N); a tendon can only pull",
                       entity);
    if (!t.name.empty() && !names.insert(t.name).second)
      throw InputError("duplicate tendon name '" + t.name + "'", entity);
    t.first_segment = static_cast<int>(m.tendon_segments.size());
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k)
      m.tendon_segments.push_back({index, t.eyelets[k], t.eyelets[k + 1]});
  }
  // The segments on nodes, grouped by node pair in the order of their first segments.
  m.tendon_segment_groups.clear();
  m.tendon_group_segments.clear();
  std::map<std::pair<int, int>, std::vector<int>> by_pair;
  std::vector<std::pair<int, int>> order;
  for (std::size_t i = 0; i < m.tendon_segments.size(); ++i) {
    const TendonSegment& s = m.tendon_segments[i];
    if (s.a.element >= 0 || s.b.element >= 0) continue;  // TendonSpanSegmentKind's
    std::vector<int>& list = by_pair[{s.a.node, s.b.node}];
    if (list.empty()) order.emplace_back(s.a.node, s.b.node);
    list.push_back(static_cast<int>(i));
  }
  for (const auto& key : order) {
    const std::vector<int>& list = by_pair[key];
    m.tendon_segment_groups.push_back({key.first, key.second,
                                       static_cast<int>(m.tendon_group_segments.size()),
                                       static_cast<int>(list.size())});
    m.tendon_group_segments.insert(m.tendon_group_segments.end(), list.begin(), list.end());
  }
}

// Actuators (method-next.md §N5): rod, range at nodes, values; eps0 and sigma_a per unit
// profile value; the per-element lists of Model::element_actuators.
void BuildActuators(Model& m) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < m.actuators.size(); ++i) {
    Actuator& a = m.actuators[i];
    const std::string label = "actuator '" + a.name + "'";
    const int index = static_cast<int>(i);
    const EntityRef entity{EntityKind::kActuator, index, {}};
    const auto fail = [&](const std::string& part, const std::string& what) {
      throw InputError(label + ": " + what, {EntityKind::kActuator, index, part}, what);
    };
    if (a.rod < 0 || a.rod >= static_cast<int>(m.rods.size()))
      fail("rod", "invalid rod " + std::to_string(a.rod));
    if (!IsEnumValue(a.type)) fail("type", "invalid actuator type");
    const Rod& rod = m.rods[static_cast<std::size_t>(a.rod)];
    const double to = a.to < 0.0 ? rod.length : a.to;
    const double tol = 1e-8 * std::max(1.0, rod.length);
    if (!(a.from >= 0.0) || !std::isfinite(a.from))
      fail("from", "must be a finite arc length >= 0, got " + std::to_string(a.from));
    if (!(to <= rod.length + tol) || !std::isfinite(to))
      fail("to", "must not exceed the rod's length " + std::to_string(rod.length) + " m, got " +
                     std::to_string(to));
    if (!(to > a.from + tol))
      fail("to", "must be greater than from (" + std::to_string(a.from) + " m), got " +
                     std::to_string(to));
    // The range's ends at nodes: the first element starting at `from`, the last ending at `to`.
    int first = -1, last = -1;
    double s = 0.0, near_from = INFINITY, near_to = INFINITY;
    for (int k = 0; k < rod.num_elements; ++k) {
      const double L = m.elements[static_cast<std::size_t>(rod.first_element + k)].length;
      if (std::abs(s - a.from) <= tol) first = k;
      if (std::abs(s - a.from) < std::abs(near_from - a.from)) near_from = s;
      s += L;
      if (std::abs(s - to) <= tol) last = k;
      if (std::abs(s - to) < std::abs(near_to - to)) near_to = s;
    }
    if (first < 0)
      fail("from", "arc length " + std::to_string(a.from) + " m is not at a node of rod '" +
                       rod.name + "' (the nearest node is at " + std::to_string(near_from) + " m)");
    if (last < 0)
      fail("to", "arc length " + std::to_string(to) + " m is not at a node of rod '" + rod.name +
                     "' (the nearest node is at " + std::to_string(near_to) + " m)");
    a.first_element = rod.first_element + first;
    a.num_elements = last - first + 1;
    a.rest_strain_unit.setZero();
    a.active_stress_unit.setZero();
    const bool chamber = a.type == ActuatorType::kPressure || a.type == ActuatorType::kMuscle;
    if (chamber) {
      if (!(a.area > 0.0) || !std::isfinite(a.area))
        fail("area", "must be a positive area [m^2], got " + std::to_string(a.area));
      if (!a.offset.allFinite()) fail("offset", "must be finite");
      // sigma_a per unit pressure: A [e1; r x e1] (method-next.md §N5.2).
      Vec6 unit;
      unit << 1.0, 0.0, 0.0, 0.0, a.offset(2), -a.offset(1);
      unit *= a.area;
      if (a.type == ActuatorType::kMuscle) {
        if (!(a.max_stress >= 0.0) || !std::isfinite(a.max_stress))
          fail("max_stress", "must be finite and non-negative [Pa], got " +
                                 std::to_string(a.max_stress));
        unit *= -a.max_stress;
      }
      a.active_stress_unit = unit;
    } else {
      if (!a.vector.allFinite()) fail("vector", "must be finite");
      (a.type == ActuatorType::kRestStrain ? a.rest_strain_unit : a.active_stress_unit) = a.vector;
    }
    ValidateProfile(m, a.profile, label + " profile", entity);
    if (!a.name.empty() && !names.insert(a.name).second)
      throw InputError("duplicate actuator name '" + a.name + "'", entity);
  }
  // Per element, its actuators in order (several on one element add).
  m.element_actuators.clear();
  for (std::size_t e = 0; e < m.elements.size(); ++e) {
    RodElement& el = m.elements[e];
    el.first_actuator = static_cast<int>(m.element_actuators.size());
    for (std::size_t i = 0; i < m.actuators.size(); ++i) {
      const Actuator& a = m.actuators[i];
      const int k = static_cast<int>(e) - a.first_element;
      if (k >= 0 && k < a.num_elements) m.element_actuators.push_back(static_cast<int>(i));
    }
    el.num_actuators = static_cast<int>(m.element_actuators.size()) - el.first_actuator;
  }
}

// Force elements: ends, values, rest length (the reference distance when negative), names.
void BuildForceElements(Model& m) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < m.force_elements.size(); ++i) {
    ForceElement& f = m.force_elements[i];
    const std::string label = "force element '" + f.name + "'";
    const int index = static_cast<int>(i);
    const EntityRef entity{EntityKind::kForceElement, index, {}};
    for (const auto& [p, part] : {std::pair<const BodyPoint*, const char*>{&f.a, "a"}, {&f.b, "b"}}) {
      const std::string problem =
          p->rod >= 0 ? "ends sit on nodes (an arc length between nodes is for tendon eyelets)"
                      : BodyPointProblem(m, *p);
      if (!problem.empty())
        throw InputError(label + ": end " + part + ": " + problem,
                         {EntityKind::kForceElement, index, part}, problem);
    }
    if (f.a.node == f.b.node)
      throw InputError(label + ": both ends are on " + NodeLabel(m, f.a.node), entity);
    if (!(f.stiffness >= 0.0) || !std::isfinite(f.stiffness) || !(f.damping >= 0.0) ||
        !std::isfinite(f.damping))
      throw InputError(label + ": stiffness and damping must be finite and non-negative", entity);
    if (!std::isfinite(f.rest_length))
      throw InputError(label + ": the rest length must be finite", entity);
    const double l = (ReferencePosition(m, f.b) - ReferencePosition(m, f.a)).norm();
    if (!(l > 1e-9 * std::max(1.0, m.length_scale)))
      throw InputError(label + ": its ends coincide in the reference configuration (no direction "
                               "between them)",
                       {EntityKind::kForceElement, index, "b"},
                       "coincides with end a in the reference configuration");
    if (f.rest_length < 0.0) f.rest_length = l;
    ValidateProfile(m, f.actuator, label + " actuator", entity);
    if (!f.name.empty() && !names.insert(f.name).second)
      throw InputError("duplicate force element name '" + f.name + "'", entity);
  }
}

// The moving shapes (elements/shape_pair.h) as segments for the broad phase, and which two
// contact entities (a rod: its element capsules; a body: its spheres, capsules and boxes) may
// touch: their group bitmasks match, they are not excluded and not joined (a shared node or a
// joint between their nodes); a rod with itself when ContactSettings::self, skipping elements
// whose nearest ends are closer along the rod than self_skip. No pair of segments is listed
// here: the broad phase finds them per assembly (UpdateShapePairs), in time linear in the
// segments. r_min gets the smallest size and w_max the largest weight a pair can carry (the
// lighter side of the heaviest pair) for the law's defaults.
template <class Group>
void BuildContactSegments(Model& m, const Group& group, double* r_min, double* w_max) {
  m.contact_segments.clear();
  m.contact_entity_pairs.clear();
  m.contact_entity_self_skip.clear();
  m.num_contact_entities = 0;
  ContactSettings& law = m.contact;
  if (!std::isfinite(law.self_skip) || law.self_skip == 0.0)
    throw InputError("contact: self_skip must be positive (or left to its default)");
  // Entities: rods (contact_rods) and bodies with shapes (spheres, capsules, boxes).
  struct Entity {
    bool rod;
    int index;      // rod or body index
    int contact;    // contact_rods index (rods)
    std::vector<int> nodes;
  };
  std::vector<Entity> entities;
  for (std::size_t i = 0; i < m.contact_rods.size(); ++i) {
    const ContactRod& c = m.contact_rods[i];
    entities.push_back({true, c.rod, static_cast<int>(i), m.rods[static_cast<std::size_t>(c.rod)].nodes});
  }
  for (const ContactShape& c : m.contact_shapes) {
    bool seen = false;
    for (const Entity& e : entities) seen = seen || (!e.rod && e.index == c.body);
    if (!seen) entities.push_back({false, c.body, -1, {m.bodies[static_cast<std::size_t>(c.body)].node}});
  }
  for (const ContactPairExclusion& x : m.contact_pair_exclusions)
    for (int k = 0; k < 2; ++k) {
      const std::size_t size = x.rod[k] ? m.rods.size() : m.bodies.size();
      if (x.index[k] < 0 || x.index[k] >= static_cast<int>(size))
        throw InputError(std::string("contact exclusion: no ") + (x.rod[k] ? "rod " : "body ") +
                         std::to_string(x.index[k]));
    }
  auto excluded = [&](const Entity& a, const Entity& b) {
    for (const ContactPairExclusion& x : m.contact_pair_exclusions)
      for (int k = 0; k < 2; ++k)
        if (x.rod[k] == a.rod && x.index[k] == a.index && x.rod[1 - k] == b.rod &&
            x.index[1 - k] == b.index)
          return true;
    return false;
  };
  auto joined = [&](const Entity& a, const Entity& b) {
    auto has = [](const Entity& e, int node) {
      return std::find(e.nodes.begin(), e.nodes.end(), node) != e.nodes.end();
    };
    for (int n : a.nodes)
      if (has(b, n)) return true;
    for (const Joint& j : m.joints)
      if ((has(a, j.node_a) && has(b, j.node_b)) || (has(a, j.node_b) && has(b, j.node_a)))
        return true;
    return false;
  };
  // The segments of an entity: sides with their masses.
  struct Segment {
    ShapePairSide side;
    double mass;  // INFINITY when every node of the side is fixed
    int first, last;  // rod: the element's position along the rod and its arc-length span
    double s0, s1;
  };
  auto fixed = [&](int node) { return node == kGround || m.nodes[static_cast<std::size_t>(node)].fixed; };
  auto segments = [&](const Entity& e) {
    std::vector<Segment> out;
    if (e.rod) {
      const Rod& rod = m.rods[static_cast<std::size_t>(e.index)];
      const double radius = m.contact_rods[static_cast<std::size_t>(e.contact)].radius;
      double arc = 0.0;
      for (int k = 0; k < rod.num_elements; ++k) {
        const RodElement& el = m.elements[static_cast<std::size_t>(rod.first_element + k)];
        Segment g;
        g.side.node[0] = el.node_a;
        g.side.node[1] = el.node_b;
        g.side.end_node[1] = 1;
        g.side.radius = radius;
        g.side.rod = true;
        g.side.owner = e.index;
        g.side.element = rod.first_element + k;
        g.mass = fixed(el.node_a) && fixed(el.node_b) ? INFINITY : rod.section.inertia(0) * el.length;
        g.first = g.last = k;
        g.s0 = arc;
        arc += el.length;
        g.s1 = arc;
        out.push_back(g);
      }
      return out;
    }
    const RigidBody& body = m.bodies[static_cast<std::size_t>(e.index)];
    for (const ContactShape& c : m.contact_shapes) {
      if (c.body != e.index) continue;
      Segment g;
      g.side.node[0] = body.node;
      g.side.offset[0] = c.from;
      g.side.offset[1] = c.type == ContactShapeType::kCapsule ? c.to : c.from;
      g.side.radius = c.radius;
      if (c.type == ContactShapeType::kBox) {
        g.side.half = c.to;
        g.side.radius = 0.0;
      }
      g.side.owner = e.index;
      g.mass = fixed(body.node) ? INFINITY : body.mass;
      g.first = g.last = 0;
      g.s0 = g.s1 = 0.0;
      out.push_back(g);
    }
    return out;
  };
  const double gravity = m.gravity.norm() > 0.0 ? m.gravity.norm() : 9.81;
  const int ne = static_cast<int>(entities.size());
  m.num_contact_entities = ne;
  m.contact_entity_pairs.assign(static_cast<std::size_t>(ne * ne), 0);
  m.contact_entity_self_skip.assign(static_cast<std::size_t>(ne), -1.0);
  // Per entity: the largest finite segment mass (-1: none), whether a segment is fixed, the
  // smallest size (radius, or a box's smallest half size).
  std::vector<double> heaviest(static_cast<std::size_t>(ne), -1.0), smallest(static_cast<std::size_t>(ne), INFINITY);
  std::vector<char> has_fixed(static_cast<std::size_t>(ne), 0);
  for (int e = 0; e < ne; ++e) {
    for (const Segment& g : segments(entities[static_cast<std::size_t>(e)])) {
      ContactSegment cs;
      cs.side = g.side;
      cs.mass = g.mass;
      cs.entity = e;
      cs.s0 = g.s0;
      cs.s1 = g.s1;
      m.contact_segments.push_back(cs);
      const std::size_t k = static_cast<std::size_t>(e);
      if (std::isinf(g.mass))
        has_fixed[k] = 1;
      else
        heaviest[k] = std::max(heaviest[k], g.mass);
      smallest[k] = std::min(smallest[k], g.side.half.x() > 0.0 ? g.side.half.minCoeff()
                                                                 : g.side.radius);
    }
  }
  // The law's defaults over the pairs that can occur: max over pairs of min(m_x, m_y) is the
  // lighter entity's heaviest segment (or the heaviest of one side against a fixed segment).
  auto weigh = [&](int a, int b) {
    const std::size_t ka = static_cast<std::size_t>(a), kb = static_cast<std::size_t>(b);
    double w = std::min(heaviest[ka], heaviest[kb]);
    if (has_fixed[ka]) w = std::max(w, heaviest[kb]);
    if (has_fixed[kb]) w = std::max(w, heaviest[ka]);
    if (w > 0.0) *w_max = std::max(*w_max, w * gravity);
    *r_min = std::min(*r_min, std::min(smallest[ka], smallest[kb]));
  };
  for (int i = 0; i < ne; ++i) {
    const Entity& a = entities[static_cast<std::size_t>(i)];
    const ContactGroup ga = group(a.rod, a.index);
    for (int k = i + 1; k < ne; ++k) {
      const Entity& b = entities[static_cast<std::size_t>(k)];
      const ContactGroup gb = group(b.rod, b.index);
      if (((ga.contype & gb.conaffinity) | (gb.contype & ga.conaffinity)) == 0u) continue;
      if (excluded(a, b) || joined(a, b)) continue;
      m.contact_entity_pairs[static_cast<std::size_t>(i * ne + k)] = 1;
      m.contact_entity_pairs[static_cast<std::size_t>(k * ne + i)] = 1;
      weigh(i, k);
    }
    if (a.rod && law.self) {
      const double skip = law.self_skip > 0.0 ? law.self_skip
                                              : 4.0 * m.contact_rods[static_cast<std::size_t>(a.contact)].radius;
      m.contact_entity_self_skip[static_cast<std::size_t>(i)] = skip;
      const Rod& rod = m.rods[static_cast<std::size_t>(a.index)];
      double length = 0.0;
      for (int e = 0; e < rod.num_elements; ++e)
        length += m.elements[static_cast<std::size_t>(rod.first_element + e)].length;
      if (length > skip) weigh(i, i);  // two of its elements can be skip apart
    }
  }
}

// Contact (method-next.md §N6): validates shapes, obstacles and the law, enumerates the
// (moving shape, obstacle) pairs and resolves the defaults (model.h, ContactSettings).
void BuildContacts(Model& m) {
  m.contact_pairs.clear();
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  for (std::size_t i = 0; i < m.contact_rods.size(); ++i) {
    const ContactRod& c = m.contact_rods[i];
    const EntityRef entity{EntityKind::kContactRod, static_cast<int>(i), {}};
    if (c.rod < 0 || c.rod >= static_cast<int>(m.rods.size()))
      throw InputError("contact rod " + std::to_string(i) + ": no rod " + std::to_string(c.rod),
                       entity);
    if (!positive(c.radius))
      throw InputError("contact of rod '" + m.rods[static_cast<std::size_t>(c.rod)].name +
                           "': the contact radius must be positive, got " + std::to_string(c.radius),
                       entity);
  }
  for (std::size_t i = 0; i < m.contact_shapes.size(); ++i) {
    const ContactShape& c = m.contact_shapes[i];
    const EntityRef entity{EntityKind::kContactShape, static_cast<int>(i), {}};
    if (c.body < 0 || c.body >= static_cast<int>(m.bodies.size()))
      throw InputError("contact shape " + std::to_string(i) + ": no body " + std::to_string(c.body),
                       entity);
    const std::string label = "contact shape of body '" +
                              m.bodies[static_cast<std::size_t>(c.body)].name + "'";
    if (!c.from.allFinite() || !c.to.allFinite())
      throw InputError(label + ": points and sizes must be finite", entity);
    if (c.type == ContactShapeType::kBox ? !(c.to.minCoeff() > 0.0) : !positive(c.radius))
      throw InputError(label + (c.type == ContactShapeType::kBox
                                    ? ": the half sizes must be positive"
                                    : ": the radius must be positive"),
                       entity);
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < m.obstacles.size(); ++i) {
    ContactObstacle& o = m.obstacles[i];
    const EntityRef entity{EntityKind::kObstacle, static_cast<int>(i), {}};
    const std::string label = "obstacle '" + o.name + "'";
    if (!o.point.allFinite() || !o.normal.allFinite() || !o.to.allFinite())
      throw InputError(label + ": points and normal must be finite", entity);
    if (o.type == ObstacleType::kPlane) {
      if (!(o.normal.norm() > 0.0))
        throw InputError(label + ": the plane normal must not be zero", entity);
      o.normal.normalize();
    } else if (!positive(o.radius)) {
      throw InputError(label + ": the radius must be positive, got " + std::to_string(o.radius),
                       entity);
    }
    if (!o.name.empty() && !names.insert(o.name).second)
      throw InputError("duplicate obstacle name '" + o.name + "'", entity);
  }
  ContactSettings& law = m.contact;
  if (!(law.friction >= 0.0) || !std::isfinite(law.friction))
    throw InputError("contact: the friction coefficient must be finite and >= 0, got " +
                     std::to_string(law.friction));
  if (!(law.damping_ratio >= 0.0) || !std::isfinite(law.damping_ratio))
    throw InputError("contact: the damping ratio must be finite and >= 0");
  for (double v : {law.stiffness, law.onset, law.slip_velocity})
    if (!std::isfinite(v) || v == 0.0)
      throw InputError("contact: stiffness, onset and slip velocity must be positive (or left "
                       "to their defaults)");
  // Pairs: each moving shape against each obstacle it may touch.
  auto group = [&](bool rod, int index) {
    for (const ContactGroup& g : m.contact_groups)
      if (g.rod == rod && g.index == index) return g;
    return ContactGroup{rod, index, 1u, 1u};
  };
  auto excluded = [&](bool rod, int index, int obstacle) {
    for (const ContactExclusion& e : m.contact_exclusions)
      if (e.rod == rod && e.index == index && e.obstacle == obstacle) return true;
    return false;
  };
  const double gravity = m.gravity.norm() > 0.0 ? m.gravity.norm() : 9.81;
  double r_min = INFINITY, w_max = 0.0;
  std::vector<double> masses;  // per pair, for the damping
  for (int oi = 0; oi < static_cast<int>(m.obstacles.size()); ++oi) {
    const ContactObstacle& o = m.obstacles[static_cast<std::size_t>(oi)];
    const bool plane = o.type == ObstacleType::kPlane;
    auto collide = [&](bool rod, int index) {
      const ContactGroup g = group(rod, index);
      return ((g.contype & o.conaffinity) | (o.contype & g.conaffinity)) != 0u &&
             !excluded(rod, index, oi);
    };
    for (const ContactRod& c : m.contact_rods) {
      if (!collide(true, c.rod)) continue;
      const Rod& rod = m.rods[static_cast<std::size_t>(c.rod)];
      const double rho_a = rod.section.inertia(0);
      r_min = std::min(r_min, c.radius);
      if (plane) {
        // Node spheres (a chord's closest point to a plane is an end).
        for (std::size_t k = 0; k < rod.nodes.size(); ++k) {
          const int node = rod.nodes[k];
          if (m.nodes[static_cast<std::size_t>(node)].fixed) continue;
          double length = 0.0;
          if (k > 0) length += 0.5 * m.elements[static_cast<std::size_t>(rod.first_element + static_cast<int>(k) - 1)].length;
          if (k + 1 < rod.nodes.size()) length += 0.5 * m.elements[static_cast<std::size_t>(rod.first_element + static_cast<int>(k))].length;
          ContactPair p;
          p.node[0] = node;
          p.radius = c.radius;
          p.obstacle = oi;
          p.rod = true;
          p.owner = c.rod;
          m.contact_pairs.push_back(p);
          masses.push_back(rho_a * length);
        }
      } else {
        for (int e = rod.first_element; e < rod.first_element + rod.num_elements; ++e) {
          const RodElement& el = m.elements[static_cast<std::size_t>(e)];
          ContactPair p;
          p.node[0] = el.node_a;
          p.node[1] = el.node_b;
          p.end_node[1] = 1;
          p.radius = c.radius;
          p.obstacle = oi;
          p.rod = true;
          p.owner = c.rod;
          m.contact_pairs.push_back(p);
          masses.push_back(rho_a * el.length);
        }
      }
    }
    for (const ContactShape& c : m.contact_shapes) {
      if (!collide(false, c.body)) continue;
      const RigidBody& body = m.bodies[static_cast<std::size_t>(c.body)];
      if (m.nodes[static_cast<std::size_t>(body.node)].fixed) continue;
      auto add = [&](const Vec3& a, const Vec3& b, double radius) {
        ContactPair p;
        p.node[0] = body.node;
        p.offset[0] = a;
        p.offset[1] = b;
        p.radius = radius;
        p.obstacle = oi;
        p.owner = c.body;
        m.contact_pairs.push_back(p);
        masses.push_back(body.mass);
      };
      switch (c.type) {
        case ContactShapeType::kSphere:
          r_min = std::min(r_min, c.radius);
          add(c.from, c.from, c.radius);
          break;
        case ContactShapeType::kCapsule:
          r_min = std::min(r_min, c.radius);
          if (plane) {
            add(c.from, c.from, c.radius);
            add(c.to, c.to, c.radius);
          } else {
            add(c.from, c.to, c.radius);
          }
          break;
        case ContactShapeType::kBox: {
          // method-next.md §N6.2: 8 vertex spheres and (against curved obstacles) 12 edge
          // capsules, of radius 0.
          r_min = std::min(r_min, c.to.minCoeff());
          Vec3 v[8];
          for (int k = 0; k < 8; ++k) v[k] = BoxCorner(c.from, c.to, k);
          for (int k = 0; k < 8; ++k) add(v[k], v[k], 0.0);
          if (!plane)
            for (int k = 0; k < 8; ++k)
              for (int bit : {1, 2, 4})
                if (!(k & bit)) add(v[k], v[k | bit], 0.0);
          break;
        }
      }
    }
  }
  BuildContactSegments(m, group, &r_min, &w_max);
  // Defaults (method-next.md §N6.4) and the damping of each pair.
  for (double mass : masses) w_max = std::max(w_max, mass * gravity);
  if (law.onset < 0.0) law.onset = std::isfinite(r_min) ? 0.01 * r_min : 1e-4;
  if (law.stiffness < 0.0) law.stiffness = w_max > 0.0 ? 100.0 * w_max / law.onset : 1e6;
  if (law.slip_velocity < 0.0) law.slip_velocity = 1e-3;
  for (std::size_t i = 0; i < m.contact_pairs.size(); ++i)
    m.contact_pairs[i].damping =
        2.0 * law.damping_ratio * std::sqrt(law.stiffness * std::max(masses[i], 0.0));
}

// Every node that is not fixed is used by a rod, a body or a joint.
void CheckConnected(const Model& m, const std::vector<char>& used) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  for (int n = 0; n < num_nodes; ++n)
    if (!m.nodes[static_cast<std::size_t>(n)].fixed && !used[static_cast<std::size_t>(n)])
      throw InputError(NodeLabel(m, n) + " is connected to nothing (no rod, body or joint)",
                       {EntityKind::kNode, n, {}});
}

// Unknowns: 6 velocities per free node, then the joints' coordinates; multipliers: 6 rows per
// constrained joint and one per prescribed drive.
void LayOutUnknowns(Model& m) {
  m.nv = 0;
  for (Node& n : m.nodes) {
    n.dof = n.fixed ? -1 : m.nv;
    if (!n.fixed) m.nv += 6;
  }
  m.nv_nodes = m.nv;
  m.nc = 0;
  for (Joint& j : m.joints) {
    j.coord = m.nv;
    m.nv += j.k();
    j.row = -1;
    if (GetJointTypeInfo(j.type).constrained) {
      j.row = m.nc;
      m.nc += 6;
    }
    j.drive_row = -1;
    if (j.drive == DriveKind::kPrescribed) {
      j.drive_row = m.nc;
      m.nc += 1;
    }
  }
  // One row per length-driven tendon, after the joints' rows.
  for (Tendon& t : m.tendons) {
    t.row = -1;
    if (t.drive == TendonDrive::kLength) t.row = m.nc++;
  }
}

void CheckJointFramesCoincide(const Model& m) {
  // The joint frames must coincide in the reference configuration (H_J = I, method.md §4.2).
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    const Joint& j = m.joints[i];
    const SE3& HA = NodeReferenceFrame(m, j.node_a);
    const SE3& HB = NodeReferenceFrame(m, j.node_b);
    const Vec6 phi0 = LogSE3(j.offset_a.Inverse() * HA.Inverse() * HB * j.offset_b);
    if (j.row >= 0 && phi0.norm() > 1e-9 * std::max(1.0, HA.x.norm() + HB.x.norm()))
      throw InputError("joint '" + j.name +
                       "': its frames on the two sides do not coincide in the reference "
                       "configuration (check the joint point and the attached bodies)",
                       {EntityKind::kJoint, static_cast<int>(i), {}});
  }
}

// One function (about 80 lines): one algorithm, the block graph and the band pattern it implies
// share the block numbering, so the steps would pass the same four arrays to each other.
void OrderUnknowns(Model& m) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  // Block graph: a block is a contiguous range of unknowns that always couple together; an
  // edge is a block of the iteration matrix that the assembly writes (rod elements couple
  // their nodes, joints their constraint rows with both nodes and their coordinates, drives
  // their row with the coordinates). The term d(B^T lambda)/dq, which would couple the two
  // nodes of a joint, is not assembled (method.md §5.2). The permuted matrix has these blocks
  // only: model.pattern_last, checked by the assembly.
  struct Block {
    int start, size;
  };
  std::vector<Block> blocks;
  std::vector<int> node_block(static_cast<std::size_t>(num_nodes), -1);
  for (int n = 0; n < num_nodes; ++n) {
    const Node& node = m.nodes[static_cast<std::size_t>(n)];
    if (node.fixed) continue;
    node_block[static_cast<std::size_t>(n)] = static_cast<int>(blocks.size());
    blocks.push_back({node.dof, 6});
  }
  std::vector<std::vector<int>> adj;
  auto add_block = [&](int start, int size) {
    blocks.push_back({start, size});
    return static_cast<int>(blocks.size()) - 1;
  };
  std::vector<std::pair<int, int>> edges;
  auto link = [&](int a, int b) {
    if (a >= 0 && b >= 0 && a != b) edges.emplace_back(a, b);
  };
  auto nb = [&](int node) { return node == kGround ? -1 : node_block[static_cast<std::size_t>(node)]; };
  for (const RodElement& e : m.elements) link(nb(e.node_a), nb(e.node_b));
  // Tendon segments and force elements couple their two nodes (elements/tendon.h).
  // An eyelet between nodes brings both nodes of its element.
  for (const TendonSegment& s : m.tendon_segments) {
    auto node_b = [&](const BodyPoint& p) {
      return p.element >= 0 ? m.elements[static_cast<std::size_t>(p.element)].node_b : kGround;
    };
    const int nodes[4] = {s.a.node, node_b(s.a), s.b.node, node_b(s.b)};
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) link(nb(nodes[i]), nb(nodes[j]));
  }
  for (const ForceElement& f : m.force_elements) link(nb(f.a.node), nb(f.b.node));
  // A pair of moving shapes couples the nodes of its two sides (elements/shape_pair.h). Two
  // entities that may touch (or a rod that may touch itself) are linked here, every node of one
  // with every node of the other, when the product of their node counts is at most
  // ContactSettings::band_pair_nodes (bodies, short rods: the band has room for the coupling);
  // the couplings of the others that fall outside the band enter the solve as a low-rank
  // update (Data::coupling), so that long rods do not widen the band.
  {
    const int ne = m.num_contact_entities;
    std::vector<std::vector<int>> entity_nodes(static_cast<std::size_t>(ne));
    for (const ContactSegment& g : m.contact_segments)
      for (int k : g.side.node)
        if (nb(k) >= 0) entity_nodes[static_cast<std::size_t>(g.entity)].push_back(k);
    for (std::vector<int>& list : entity_nodes) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
    for (int a = 0; a < ne; ++a)
      for (int b = a; b < ne; ++b) {
        const bool touch = a == b ? m.contact_entity_self_skip[static_cast<std::size_t>(a)] >= 0.0
                                  : m.contact_entity_pairs[static_cast<std::size_t>(a * ne + b)] != 0;
        const std::vector<int>& na = entity_nodes[static_cast<std::size_t>(a)];
        const std::vector<int>& nbs = entity_nodes[static_cast<std::size_t>(b)];
        if (!touch || static_cast<double>(na.size()) * static_cast<double>(nbs.size()) >
                          static_cast<double>(m.contact.band_pair_nodes))
          continue;
        for (int x : na)
          for (int y : nbs) link(nb(x), nb(y));
      }
  }
  for (const Joint& j : m.joints) {
    const int coord_block = j.k() > 0 ? add_block(j.coord, j.k()) : -1;
    if (j.row >= 0) {
      const int cb = add_block(m.nv + j.row, 6);
      link(cb, nb(j.node_a));
      link(cb, nb(j.node_b));
      link(cb, coord_block);
    }
    // A joint whose springs act on the nodes' relative motion (a free joint) couples them.
    if (GetJointTypeInfo(j.type).spring_law == JointSpringLaw::kRelativeMotion)
      link(nb(j.node_a), nb(j.node_b));
    if (j.drive_row >= 0) link(add_block(m.nv + j.drive_row, 1), coord_block);
  }
  // A length-driven tendon's row couples with every eyelet's node (a band as wide as the
  // tendon's route in the ordering; docs/numerics.md).
  for (const Tendon& t : m.tendons) {
    if (t.row < 0) continue;
    const int tb = add_block(m.nv + t.row, 1);
    for (const BodyPoint& e : t.eyelets) {
      link(tb, nb(e.node));
      if (e.element >= 0)
        link(tb, nb(m.elements[static_cast<std::size_t>(e.element)].node_b));
    }
  }
  adj.assign(blocks.size(), {});
  for (const auto& [a, b] : edges) {
    adj[static_cast<std::size_t>(a)].push_back(b);
    adj[static_cast<std::size_t>(b)].push_back(a);
  }
  for (auto& list : adj) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  const std::vector<int> block_perm = ReverseCuthillMcKee(adj);
  std::vector<int> order(blocks.size());
  for (std::size_t b = 0; b < blocks.size(); ++b)
    order[static_cast<std::size_t>(block_perm[b])] = static_cast<int>(b);
  m.permutation.assign(static_cast<std::size_t>(m.num_unknowns()), -1);
  std::vector<int> block_pos(blocks.size());
  int pos = 0;
  for (int b : order) {
    block_pos[static_cast<std::size_t>(b)] = pos;
    const Block& blk = blocks[static_cast<std::size_t>(b)];
    for (int i = 0; i < blk.size; ++i) m.permutation[static_cast<std::size_t>(blk.start + i)] = pos++;
  }
  SCREWFEM_CHECK(pos == m.num_unknowns());
  m.bandwidth = 0;
  m.pattern_last.assign(static_cast<std::size_t>(m.num_unknowns()), 0);
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    m.bandwidth = std::max(m.bandwidth, blocks[b].size - 1);
    int last = block_pos[b] + blocks[b].size - 1;
    for (int c : adj[b]) {
      const int lo = std::min(block_pos[b], block_pos[static_cast<std::size_t>(c)]);
      const int hi = std::max(block_pos[b] + blocks[b].size,
                              block_pos[static_cast<std::size_t>(c)] +
                                  blocks[static_cast<std::size_t>(c)].size);
      m.bandwidth = std::max(m.bandwidth, hi - 1 - lo);
      last = std::max(last, block_pos[static_cast<std::size_t>(c)] +
                                blocks[static_cast<std::size_t>(c)].size - 1);
    }
    for (int i = 0; i < blocks[b].size; ++i)
      m.pattern_last[static_cast<std::size_t>(block_pos[b] + i)] = last;
  }
}

void SetLengthScale(Model& m) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  // Characteristic length: the diagonal of the bounding box of all node positions.
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Node& n : m.nodes) {
    lo = lo.cwiseMin(n.reference.x);
    hi = hi.cwiseMax(n.reference.x);
  }
  m.length_scale = num_nodes > 0 ? std::max((hi - lo).norm(), 1e-3) : 1.0;
  for (const Rod& r : m.rods) m.length_scale = std::max(m.length_scale, r.length);
}

}  // namespace

Model ModelBuilder::Build() const {
  Model m = model_;
  ValidateNodes(m);
  std::vector<char> used(m.nodes.size(), 0);  // nodes that something is attached to
  BuildRodElements(m, used);
  ValidateBodies(m, used);
  ValidateJoints(m, used);
  PlaceLoads(m);
  SetLengthScale(m);
  BuildTendons(m);
  BuildForceElements(m);
  BuildActuators(m);
  BuildContacts(m);
  CheckConnected(m, used);
  LayOutUnknowns(m);
  CheckJointFramesCoincide(m);
  FindRedundantConstraints(m);
  OrderUnknowns(m);
  return m;
}

}  // namespace screwfem
