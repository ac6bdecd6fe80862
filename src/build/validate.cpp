// Build steps that validate the nodes, rods, bodies and joints (build/build_steps.h), and the
// helpers that name nodes and validate profiles for every step.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "build_steps.h"
#include "screwfem/elements/joint.h"
#include "screwfem/model/errors.h"

namespace screwfem::build_steps {

namespace {

bool IsFinite(const SE3& H) { return H.R.allFinite() && H.x.allFinite(); }

bool IsRotation(const Mat3& R) {
  return (R.transpose() * R - Mat3::Identity()).norm() < 1e-9 && R.determinant() > 0.0;
}

}  // namespace

std::string NodeLabel(const Model& m, int node) {
  if (node == kGround) return "ground";
  const Node& n = m.nodes[static_cast<std::size_t>(node)];
  return n.name.empty() ? "node " + std::to_string(node) : "node '" + n.name + "'";
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
      throw InputError(label + ": Rayleigh damping coefficients must be finite and non-negative",
                       entity);
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
        throw InputError(
            label + ": element " + std::to_string(e) + " has zero length (its nodes coincide)",
            entity);
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
                               JointTypeName(j.type) + ")",
                           entity);
        ValidateProfile(m, j.drive_profile, label, entity);
      }
      if ((j.has_initial_coordinate && !j.initial_coordinate.allFinite()) ||
          (j.has_initial_rate && !j.initial_rate.allFinite()))
        throw InputError(label + ": initial coordinates and rates must be finite", entity);
      if (j.has_initial_coordinate && !JointHasGlobalCoordinates(j.type))
        throw InputError(label +
                             ": initial coordinates need a joint with global coordinates "
                             "(not " +
                             JointTypeName(j.type) + ")",
                         entity);
      if (!j.name.empty() && !names.insert(j.name).second)
        throw InputError("duplicate joint name '" + j.name + "'", entity);
      if (j.node_a != kGround) used[static_cast<std::size_t>(j.node_a)] = 1;
      if (j.node_b != kGround) used[static_cast<std::size_t>(j.node_b)] = 1;
    }
  }
}

// Every node that is not fixed is used by a rod, a body or a joint.
void CheckConnected(const Model& m, const std::vector<char>& used) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  for (int n = 0; n < num_nodes; ++n)
    if (!m.nodes[static_cast<std::size_t>(n)].fixed && !used[static_cast<std::size_t>(n)])
      throw InputError(NodeLabel(m, n) + " is connected to nothing (no rod, body or joint)",
                       {EntityKind::kNode, n, {}});
}

void CheckJointFramesCoincide(const Model& m) {
  // The joint frames must coincide in the reference configuration (H_J = I, elements/joint.h).
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

}  // namespace screwfem::build_steps
