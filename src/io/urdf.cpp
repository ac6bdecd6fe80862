// URDF robots as bodies and joints of a SceneSpec (io/urdf.h, docs/urdf.md). urdfdom parses
// the file (its messages go through console_bridge, captured here); TinyXML, which urdfdom
// uses, gives the order of the <link> and <joint> elements and their lines for messages.
#include "screwfem/io/urdf.h"

#include <console_bridge/console.h>
#include <tinyxml.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>
#include <urdf_parser/urdf_parser.h>

#include "read_file.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

// console_bridge's handler is global: one import at a time captures urdfdom's messages.
std::mutex& ParseMutex() {
  static std::mutex m;
  return m;
}

class Capture : public console_bridge::OutputHandler {
 public:
  Capture() { console_bridge::useOutputHandler(this); }
  ~Capture() override { console_bridge::restorePreviousOutputHandler(); }
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors.push_back(text);
  }
  std::vector<std::string> errors;
};

// Where an element of the file is: "FILE:LINE:COLUMN" (the file alone when unknown).
struct Element {
  int row = 0, column = 0;
};

class Importer {
 public:
  Importer(const std::string& source, const UrdfImport& import, SceneSpec* spec)
      : source_(source), import_(import), spec_(*spec) {}

  UrdfAdded Run(const std::string& text);

 private:
  [[noreturn]] void Fail(const Element& at, const std::string& what) const {
    std::ostringstream where;
    where << source_;
    if (at.row > 0) where << ':' << at.row << ':' << at.column;
    where << ": " << what;
    throw InputError(where.str());
  }
  Element LinkAt(const std::string& name) const {
    const auto it = link_rows_.find(name);
    return it == link_rows_.end() ? Element{} : it->second;
  }
  Element JointAt(const std::string& name) const {
    const auto it = joint_rows_.find(name);
    return it == joint_rows_.end() ? Element{} : it->second;
  }
  void ReadOrder(const std::string& text);
  void AddLink(const urdf::Link& link, const Mat3& R, const Vec3& p);
  void AddShapes(const urdf::Link& link, const Mat3& R, const Vec3& p, BodySpec& b) const;
  void AddJoint(const urdf::Joint& joint);

  std::string source_;
  const UrdfImport& import_;
  SceneSpec& spec_;
  std::vector<std::string> link_order_, joint_order_;  // file order
  std::map<std::string, Element> link_rows_, joint_rows_;
  std::map<std::string, std::vector<Element>> collision_rows_;  // by link
  std::map<std::string, std::pair<Mat3, Vec3>> link_pose_;      // world, reference config
  std::map<std::string, int> body_of_link_;
  urdf::ModelInterfaceSharedPtr model_;
};

Mat3 Rotation(const urdf::Rotation& r) {
  return Eigen::Quaterniond(r.w, r.x, r.y, r.z).toRotationMatrix();
}
Vec3 Vector(const urdf::Vector3& v) { return Vec3(v.x, v.y, v.z); }

// The file order of <link> and <joint> and the lines of them and of each link's <collision>.
void Importer::ReadOrder(const std::string& text) {
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (doc.Error())
    Fail(Element{doc.ErrorRow(), doc.ErrorCol()}, std::string("not valid XML: ") + doc.ErrorDesc());
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) Fail(Element{}, "no <robot> element (not a URDF file)");
  for (const TiXmlElement* e = robot->FirstChildElement("link"); e != nullptr;
       e = e->NextSiblingElement("link")) {
    const char* name = e->Attribute("name");
    if (name == nullptr) Fail(Element{e->Row(), e->Column()}, "<link> without a name");
    link_order_.emplace_back(name);
    link_rows_[name] = Element{e->Row(), e->Column()};
    auto& rows = collision_rows_[name];
    for (const TiXmlElement* c = e->FirstChildElement("collision"); c != nullptr;
         c = c->NextSiblingElement("collision"))
      rows.push_back(Element{c->Row(), c->Column()});
  }
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e != nullptr;
       e = e->NextSiblingElement("joint")) {
    const char* name = e->Attribute("name");
    if (name == nullptr) Fail(Element{e->Row(), e->Column()}, "<joint> without a name");
    joint_order_.emplace_back(name);
    joint_rows_[name] = Element{e->Row(), e->Column()};
  }
}

void Importer::AddShapes(const urdf::Link& link, const Mat3& R, const Vec3& p, BodySpec& b) const {
  const std::vector<Element>& rows = collision_rows_.at(link.name);
  for (std::size_t i = 0; i < link.collision_array.size(); ++i) {
    const urdf::Collision& c = *link.collision_array[i];
    const Element at = i < rows.size() ? rows[i] : LinkAt(link.name);
    const std::string who = "link '" + link.name + "': <collision> " +
                            (c.name.empty() ? std::to_string(i) : "'" + c.name + "'");
    if (!c.geometry) Fail(at, who + ": no <geometry>");
    const Mat3 Rc = R * Rotation(c.origin.rotation);
    const Vec3 centre = p + R * Vector(c.origin.position);
    ContactShape s;
    switch (c.geometry->type) {
      case urdf::Geometry::SPHERE: {
        const auto& g = static_cast<const urdf::Sphere&>(*c.geometry);
        if (!(g.radius > 0.0)) Fail(at, who + ": the sphere's radius must be positive");
        s.type = ContactShapeType::kSphere;
        s.from = s.to = Vec3(centre - p);  // the body frame, as the scene reader's
        s.radius = g.radius;
        break;
      }
      case urdf::Geometry::BOX: {
        const auto& g = static_cast<const urdf::Box&>(*c.geometry);
        const Vec3 dim = Vector(g.dim);
        if (!(dim.minCoeff() > 0.0)) Fail(at, who + ": the box's sizes must be positive");
        // The box's edges along the collision frame's axes (ContactShape::rotation).
        const Vec3 half = 0.5 * dim;
        s.type = ContactShapeType::kBox;
        s.from = Vec3(centre - p);
        s.to = half;
        s.rotation = Rc;
        break;
      }
      case urdf::Geometry::CYLINDER: {
        // URDF's cylinder: its axis along the collision frame's z, `length` long.
        const auto& g = static_cast<const urdf::Cylinder&>(*c.geometry);
        if (!(g.radius > 0.0) || !(g.length > 0.0))
          Fail(at, who + ": the cylinder's radius and length must be positive");
        s.type = ContactShapeType::kCylinder;
        s.from = Vec3(centre - p - 0.5 * g.length * Rc.col(2));
        s.to = Vec3(centre - p + 0.5 * g.length * Rc.col(2));
        s.radius = g.radius;
        break;
      }
      case urdf::Geometry::MESH:
        Fail(at, who + ": mesh shapes are not supported (spheres, boxes and cylinders are)");
    }
    b.shapes.push_back(s);
  }
}

void Importer::AddLink(const urdf::Link& link, const Mat3& R, const Vec3& p) {
  const Element at = LinkAt(link.name);
  const std::string who = "link '" + link.name + "'";
  if (!link.inertial)
    Fail(at, who + ": no <inertial> (every link is a rigid body and needs its mass and inertia)");
  const urdf::Inertial& in = *link.inertial;
  if (!(in.mass > 0.0) || !std::isfinite(in.mass)) {
    std::ostringstream s;
    s << who << ": <inertial> <mass value> must be positive, got " << in.mass;
    Fail(at, s.str());
  }
  Mat3 J;
  J << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  if (!J.allFinite() || Eigen::LLT<Mat3>(J).info() != Eigen::Success || !(J.determinant() > 0.0)) {
    std::ostringstream s;
    s << who << ": <inertial> <inertia> must be positive definite, got ixx=" << in.ixx
      << " ixy=" << in.ixy << " ixz=" << in.ixz << " iyy=" << in.iyy << " iyz=" << in.iyz
      << " izz=" << in.izz;
    Fail(at, s.str());
  }
  const Mat3 Ri = R * Rotation(in.origin.rotation);
  BodySpec b;
  b.name = import_.name + "/" + link.name;
  b.rigid = true;
  b.origin = p;
  b.com = p + R * Vector(in.origin.position);
  b.mass = in.mass;
  b.inertia = Ri * J * Ri.transpose();
  b.inertia = 0.5 * (b.inertia + b.inertia.transpose()).eval();
  b.contype = import_.contype;
  b.conaffinity = import_.conaffinity;
  AddShapes(link, R, p, b);
  const bool root = link.name == model_->getRoot()->name;
  if (root) {
    b.fixed = import_.fixed_base;
    b.free = !import_.fixed_base;
  }
  for (const BodySpec& other : spec_.bodies)
    if (other.name == b.name) Fail(at, who + ": the scene already has a body '" + b.name + "'");
  body_of_link_[link.name] = static_cast<int>(spec_.bodies.size());
  spec_.bodies.push_back(std::move(b));
}

void Importer::AddJoint(const urdf::Joint& joint) {
  const Element at = JointAt(joint.name);
  const std::string who = "joint '" + joint.name + "'";
  if (joint.mimic)
    Fail(at, who + ": <mimic> is not supported (drive both joints, or use one joint)");
  JointEntrySpec e;
  JointSpec& j = e.joint;
  j.name = import_.name + "/" + joint.name;
  switch (joint.type) {
    case urdf::Joint::REVOLUTE:
    case urdf::Joint::CONTINUOUS:
      j.type = JointType::kRevolute;
      break;
    case urdf::Joint::PRISMATIC:
      j.type = JointType::kPrismatic;
      break;
    case urdf::Joint::FIXED:
      j.type = JointType::kFixed;
      break;
    case urdf::Joint::PLANAR:
      Fail(at, who + ": type 'planar' is not supported (revolute, continuous, prismatic, fixed)");
    case urdf::Joint::FLOATING:
      Fail(at, who + ": type 'floating' is not supported (revolute, continuous, prismatic, fixed)");
    default:
      Fail(at, who + ": unknown joint type (revolute, continuous, prismatic, fixed)");
  }
  const auto& [R, p] = link_pose_.at(joint.child_link_name);
  j.point = p;
  if (j.type != JointType::kFixed) {
    const Vec3 axis = Vector(joint.axis);
    if (!(axis.norm() > 0.0)) Fail(at, who + ": <axis> is zero");
    j.axis = R * axis.normalized();
    if (joint.dynamics) {
      if (!(joint.dynamics->damping >= 0.0) || !std::isfinite(joint.dynamics->damping))
        Fail(at, who + ": <dynamics damping> must be a non-negative number");
      j.damping(0) = joint.dynamics->damping;
    }
  }
  e.body_a = body_of_link_.at(joint.parent_link_name);
  e.body_b = body_of_link_.at(joint.child_link_name);
  for (const JointEntrySpec& other : spec_.joints)
    if (other.joint.name == j.name)
      Fail(at, who + ": the scene already has a joint '" + j.name + "'");
  spec_.joints.push_back(std::move(e));
}

UrdfAdded Importer::Run(const std::string& text) {
  if (import_.name.empty()) Fail(Element{}, "the robot needs a name");
  ReadOrder(text);
  {
    const std::lock_guard<std::mutex> lock(ParseMutex());
    Capture capture;
    try {
      model_ = urdf::parseURDF(text);
    } catch (const std::exception& e) {
      capture.errors.emplace_back(e.what());
      model_.reset();
    }
    if (!model_) {
      std::string what = "not a valid URDF";
      for (const std::string& m : capture.errors) what += ": " + m;
      Fail(Element{}, what);
    }
  }
  // World poses of the links in the reference configuration (every joint coordinate 0),
  // from the root through the joints' origins: the joint frame is the child link's frame.
  std::vector<urdf::LinkConstSharedPtr> stack = {model_->getRoot()};
  link_pose_[model_->getRoot()->name] = {import_.base_rotation, import_.base_position};
  while (!stack.empty()) {
    const urdf::LinkConstSharedPtr link = stack.back();
    stack.pop_back();
    const auto [R, p] = link_pose_.at(link->name);
    for (const urdf::JointSharedPtr& joint : link->child_joints) {
      const urdf::Pose& o = joint->parent_to_joint_origin_transform;
      link_pose_[joint->child_link_name] = {R * Rotation(o.rotation), p + R * Vector(o.position)};
    }
    for (const urdf::LinkSharedPtr& child : link->child_links) stack.push_back(child);
  }
  UrdfAdded added;
  added.first_body = static_cast<int>(spec_.bodies.size());
  added.first_joint = static_cast<int>(spec_.joints.size());
  for (const std::string& name : link_order_) {
    const urdf::LinkConstSharedPtr link = model_->getLink(name);
    const auto [R, p] = link_pose_.at(name);
    AddLink(*link, R, p);
  }
  for (const std::string& name : joint_order_) AddJoint(*model_->getJoint(name));
  added.bodies = static_cast<int>(spec_.bodies.size()) - added.first_body;
  added.joints = static_cast<int>(spec_.joints.size()) - added.first_joint;
  return added;
}

}  // namespace

Mat3 RotationFromQuaternion(double w, double x, double y, double z) {
  return Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
}

Mat3 RotationFromAxisAngle(const Vec3& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
}

Mat3 RotationFromRpy(const Vec3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

UrdfAdded AppendUrdfText(const std::string& text, const std::string& source_name,
                         const UrdfImport& import, SceneSpec* spec) {
  if (text.size() > kMaxUrdfBytes)
    throw InputError(source_name + ": the URDF file is larger than " +
                     std::to_string(kMaxUrdfBytes >> 20) + " MiB (the limit)");
  // On error the spec is left as it was.
  const std::size_t nb = spec->bodies.size(), nj = spec->joints.size();
  try {
    return Importer(source_name, import, spec).Run(text);
  } catch (...) {
    spec->bodies.resize(nb);
    spec->joints.resize(nj);
    throw;
  }
}

UrdfAdded AppendUrdf(const std::string& path, const UrdfImport& import, SceneSpec* spec) {
  const std::string text = io_detail::ReadFileWithLimit(path, kMaxUrdfBytes, "URDF file", {});
  return AppendUrdfText(text, path, import, spec);
}

}  // namespace screwfem
