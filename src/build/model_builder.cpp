// ModelBuilder's API (the Add* and Set* methods that record items) and Build(), which runs
// the steps of build/build_steps.h: validation (validate.cpp), items placed on rods
// (place_items.cpp), contact (contact_build.cpp), layout and ordering (ordering.cpp), and the
// redundant constraint rows (redundancy.cpp). The geometry of the API (rods along paths,
// nodes at points and arc lengths) is in geometry.cpp.
#include "screwfem/build/model_builder.h"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "build_steps.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/memory.h"

namespace screwfem {

namespace {

// The id of the item just appended to `items`.
template <typename IdType, typename T>
IdType LastId(const std::vector<T>& items) {
  return IdType(static_cast<int>(items.size()) - 1);
}

}  // namespace

NodeId ModelBuilder::AddNode(const SE3& frame, std::string name) {
  Node n;
  n.name = std::move(name);
  n.reference = frame;
  model_.nodes.push_back(n);
  return LastId<NodeId>(model_.nodes);
}

void ModelBuilder::FixNode(NodeId node) {
  if (!node.valid() || node.index() >= model_.nodes.size())
    throw InputError("FixNode: no node " + std::to_string(node));
  model_.nodes[node.index()].fixed = true;
}

BodyId ModelBuilder::AddRigidBody(std::string name, NodeId node, double mass, const Vec3& com,
                                  const Mat3& inertia) {
  RigidBody b;
  b.name = std::move(name);
  b.node = node;
  b.mass = mass;
  b.com = com;
  b.inertia = inertia;
  model_.bodies.push_back(b);
  return LastId<BodyId>(model_.bodies);
}

JointId ModelBuilder::AddJoint(const Joint& joint) {
  model_.joints.push_back(joint);
  return LastId<JointId>(model_.joints);
}

JointId ModelBuilder::AddJointAt(std::string name, JointType type, NodeId node_a, NodeId node_b,
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

JointId ModelBuilder::AddJoint(const JointSpec& spec) {
  const JointId index = AddJointAt(spec.name, spec.type, spec.node_a, spec.node_b, spec.point,
                                   spec.axis, spec.axis2, spec.pitch);
  Joint& j = model_.joints[index.index()];
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

TendonId ModelBuilder::AddTendon(std::string name, std::vector<BodyPoint> eyelets,
                                 const Profile& tension) {
  Tendon t;
  t.name = std::move(name);
  t.eyelets = std::move(eyelets);
  t.tension = tension;
  model_.tendons.push_back(std::move(t));
  return LastId<TendonId>(model_.tendons);
}

TendonId ModelBuilder::AddLengthDrivenTendon(std::string name, std::vector<BodyPoint> eyelets,
                                             const Profile& length) {
  const TendonId index = AddTendon(std::move(name), std::move(eyelets), Profile::Constant(0.0));
  Tendon& t = model_.tendons[index.index()];
  t.drive = TendonDrive::kLength;
  t.length = length;
  return index;
}

ForceElementId ModelBuilder::AddForceElement(const ForceElement& element) {
  model_.force_elements.push_back(element);
  return LastId<ForceElementId>(model_.force_elements);
}

ActuatorId ModelBuilder::AddActuator(const Actuator& actuator) {
  model_.actuators.push_back(actuator);
  return LastId<ActuatorId>(model_.actuators);
}

PointLoadId ModelBuilder::AddPointLoad(const PointLoad& load) {
  model_.point_loads.push_back(load);
  return LastId<PointLoadId>(model_.point_loads);
}

RodLoadId ModelBuilder::AddRodLoad(const RodLoad& load) {
  model_.rod_loads.push_back(load);
  return LastId<RodLoadId>(model_.rod_loads);
}

void ModelBuilder::SetGravity(const Vec3& g) { model_.gravity = g; }

void ModelBuilder::SetInitialVelocity(NodeId node, const Vec6& velocity) {
  if (!node.valid() || node.index() >= model_.nodes.size())
    throw InputError("initial velocity: invalid node " + std::to_string(node));
  model_.nodes[node.index()].has_initial_velocity = true;
  model_.nodes[node.index()].initial_velocity = velocity;
}

InputId ModelBuilder::AddInput(std::string name, double default_value) {
  model_.inputs.push_back(ModelInput{std::move(name), default_value});
  return LastId<InputId>(model_.inputs);
}

ContactRodId ModelBuilder::AddContactRod(RodId rod, double radius) {
  model_.contact_rods.push_back({rod, radius});
  return LastId<ContactRodId>(model_.contact_rods);
}

ContactShapeId ModelBuilder::AddContactShape(const ContactShape& shape) {
  model_.contact_shapes.push_back(shape);
  return LastId<ContactShapeId>(model_.contact_shapes);
}

ObstacleId ModelBuilder::AddObstacle(const ContactObstacle& obstacle) {
  model_.obstacles.push_back(obstacle);
  return LastId<ObstacleId>(model_.obstacles);
}

void ModelBuilder::SetContactGroup(ContactEntity entity, unsigned contype, unsigned conaffinity) {
  model_.contact_groups.push_back({entity.rod, entity.index, contype, conaffinity});
}

void ModelBuilder::ExcludeContact(ContactEntity entity, ObstacleId obstacle) {
  model_.contact_exclusions.push_back({entity.rod, entity.index, obstacle});
}

void ModelBuilder::ExcludeContactPair(ContactEntity a, ContactEntity b) {
  model_.contact_pair_exclusions.push_back({{a.rod, b.rod}, {a.index, b.index}});
}

int ModelBuilder::AddContactMaterialGroup(const std::string& name,
                                          const std::vector<ContactEntity>& members,
                                          const std::vector<ObstacleId>& obstacles) {
  ContactMaterialGroup g;
  g.name = name;
  for (const ContactEntity& e : members) (e.rod ? g.rods : g.bodies).push_back(e.index);
  for (ObstacleId o : obstacles) g.obstacles.push_back(o);
  model_.contact_material_groups.push_back(std::move(g));
  return static_cast<int>(model_.contact_material_groups.size()) - 1;
}

void ModelBuilder::AddContactMaterial(const ContactMaterial& material) {
  model_.contact_materials.push_back(material);
}

void ModelBuilder::SetContactSettings(const ContactSettings& settings) {
  model_.contact = settings;
}

Model ModelBuilder::Build() const {
  using namespace build_steps;
  Model m = model_;
  ValidateNodes(m);
  ConformRodMeshes(m);
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
  // The workspace MakeData allocates for this model, before anyone allocates it.
  CheckMemory(EstimateDataMemory(m), m.memory_limit, "the model's solver workspace",
              "The band is the widest span of coupled unknowns in the solver's ordering "
              "(closed loops, tendons, force elements and contact between distant bodies "
              "widen it); fewer elements make fewer unknowns");
  return m;
}

}  // namespace screwfem
