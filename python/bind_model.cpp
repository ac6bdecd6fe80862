// Model (include/screwfem/model/model.h), read-only from Python: sizes, the entities and
// lookups by name. Eigen members are NumPy read-only views into the Model (which stays
// alive as long as a view exists); frames (SE3) are returned as 4x4 homogeneous matrices
// [R x; 0 1] (copies).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "bind.h"
#include "screwfem/elements/joint.h"
#include "screwfem/model/model.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {

// The elements of a vector as Python objects referring into the Model (kept alive by them).
template <class T>
py::list ReferenceList(const std::vector<T>& items, py::handle parent) {
  py::list out;
  for (const T& item : items)
    out.append(py::cast(&item, py::return_value_policy::reference_internal, parent));
  return out;
}

}  // namespace

void BindModel(py::module_& m) {
  // Joint types: the names of the joint-type table (elements/joint.h), in capitals.
  py::enum_<JointType> joint_type(m, "JointType",
                                  "Joint types (model.h); the relative frame H_J lies in the "
                                  "joint's Lie subgroup.");
  for (const std::string& type_name : JointTypeNameList()) {
    std::string upper = type_name;
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    joint_type.value(upper.c_str(), FindJointType(type_name)->type);
  }
  CheckEnumConstructor(joint_type, "JointType");
  BindEnum<DriveKind>(m, "DriveKind", "Drive on one joint coordinate (model.h).");
  BindEnum<RodInertia>(m, "RodInertia", "Rod inertia model (docs/numerics.md, 'Rod inertia').");
  BindEnum<LinearSolver>(m, "LinearSolver",
                         "Direct solver of the Newton systems (docs/numerics.md, 'Sparse direct "
                         "solve').");
  BindEnum<FrictionLaw>(m, "FrictionLaw",
                        "Friction law of contact (docs/numerics.md, 'Stick friction').");
  BindEnum<LoadFrame>(m, "LoadFrame", "Frame of an applied load's components (model.h).");
  BindEnum<ActuatorType>(m, "ActuatorType", "Kind of a rod actuator (model.h, Actuator).");
  BindEnum<ContactShapeType>(m, "ContactShapeType", "A rigid body's collision shape (model.h).");
  BindEnum<ObstacleType>(m, "ObstacleType", "An obstacle fixed in the world (model.h).");

  m.def("joint_type_name", &JointTypeName, py::arg("type"),
        "Name of a joint type as written in scene files, e.g. 'revolute'.");

  py::class_<Node>(m, "Node", "A node: a frame on SE(3) (model.h). Read-only.")
      .def_readonly("name", &Node::name,
                    "The node's name (made by the builder from its rod or body).")
      .def_property_readonly(
          "reference", [](const Node& n) { return n.reference.Matrix(); },
          "Initial frame H_0 as a 4x4 homogeneous matrix [R x; 0 1]: orientation and position "
          "[m] of the node in the world frame (a copy).")
      .def_readonly("fixed", &Node::fixed, "Clamped to the world (eliminated from the unknowns).")
      .def_readonly("dof", &Node::dof,
                    "First velocity index of the node's 6 body-velocity components [v; w] "
                    "(node frame), or -1 when fixed.")
      .def("__repr__", [](const Node& n) { return "<screwfem.Node '" + n.name + "'>"; });

  py::class_<RodElement>(m, "RodElement", "A two-node helical element (elements/rod.h). Read-only.")
      .def_readonly("rod", &RodElement::rod, "Index of the rod the element belongs to.")
      .def_readonly("node_a", &RodElement::node_a, "First node of the element.")
      .def_readonly("node_b", &RodElement::node_b, "Second node of the element.")
      .def_readonly("length", &RodElement::length, "Reference arc length L = |u(d0)| [m].")
      .def_readonly("d0", &RodElement::d0,
                    "Reference relative motion log(H_A0^-1 H_B0): [u (m); w (rad)] (view).");

  py::class_<Rod>(m, "Rod", "A Cosserat rod: a chain of helical elements (model.h). Read-only.")
      .def_readonly("name", &Rod::name, "Unique name (the scene's bodies: key of the soft body).")
      .def_readonly("nodes", &Rod::nodes,
                    "Node indices in order along the rod (num_elements + 1; a copy).")
      .def_readonly("first_element", &Rod::first_element,
                    "Index of its first element in Model.elements.")
      .def_readonly("num_elements", &Rod::num_elements, "Number of its elements.")
      .def_readonly("length", &Rod::length, "Reference length: sum of the element lengths [m].")
      .def("__repr__", [](const Rod& r) { return "<screwfem.Rod '" + r.name + "'>"; });

  py::class_<Tendon>(m, "Tendon", "A tendon through eyelets (model.h). Read-only.")
      .def_readonly("name", &Tendon::name, "Unique name (the scene's tendons: key).")
      .def_readonly("eyelets", &Tendon::eyelets,
                    "Its eyelets in routing order, as Build placed them (BodyPoint list; a copy).")
      .def_readonly("reference_length", &Tendon::reference_length,
                    "Length in the reference configuration [m].")
      .def("__repr__", [](const Tendon& t) { return "<screwfem.Tendon '" + t.name + "'>"; });

  py::class_<RigidBody>(m, "RigidBody",
                        "A rigid body carried by one node's frame (model.h). "
                        "Read-only.")
      .def_readonly("name", &RigidBody::name, "Unique name (the scene's bodies: key).")
      .def_readonly("node", &RigidBody::node, "The body's frame is this node's frame.")
      .def_readonly("mass", &RigidBody::mass, "[kg]")
      .def_readonly("com", &RigidBody::com, "Centre of mass in the node frame [m] (view).")
      .def_readonly("inertia", &RigidBody::inertia,
                    "Inertia about the centre of mass, node-frame axes [kg m^2] (3x3 view).")
      .def("__repr__", [](const RigidBody& b) { return "<screwfem.RigidBody '" + b.name + "'>"; });

  py::class_<Joint>(m, "Joint",
                    "A joint: relative frame H_J in a subgroup between frame A (node_a, or the "
                    "ground, -1) and frame B (node_b), placed by the offsets C_A, C_B: "
                    "H_B C_B = H_A C_A H_J (elements/joint.h). Read-only.")
      .def_readonly("name", &Joint::name, "Unique name (the scene's joints: key).")
      .def_readonly("type", &Joint::type,
                    "JointType: the Lie subgroup of the relative frame (REVOLUTE, PRISMATIC, ...).")
      .def_readonly("node_a", &Joint::node_a, "Node of side A, or -1 (kGround) for the world.")
      .def_readonly("node_b", &Joint::node_b, "Node of side B, or -1 (kGround) for the world.")
      .def_property_readonly(
          "offset_a", [](const Joint& j) { return j.offset_a.Matrix(); },
          "C_A as a 4x4 matrix in frame A [m] (for the ground: the joint frame's world pose).")
      .def_property_readonly(
          "offset_b", [](const Joint& j) { return j.offset_b.Matrix(); },
          "C_B as a 4x4 matrix in frame B [m].")
      .def_readonly("basis", &Joint::basis,
                    "Joint basis A_J (6 x k, rows [translation; rotation]; view).")
      .def_readonly("pitch", &Joint::pitch, "Helical joints [m/rad].")
      .def_readonly("coord", &Joint::coord,
                    "First velocity index of the joint coordinates (index into Simulation.v; "
                    "into Simulation.q_joint subtract Model.nv_nodes).")
      .def_readonly("row", &Joint::row,
                    "First multiplier row of the 6 relative-frame constraints (-1: none).")
      .def_readonly("stiffness", &Joint::stiffness,
                    "Soft joint stiffness K per coordinate [N/m or N m/rad] (view).")
      .def_readonly("damping", &Joint::damping,
                    "Soft joint damping D per coordinate [N s/m or N m s/rad] (view).")
      .def_readonly("rest", &Joint::rest, "Spring rest coordinates [m or rad] (view).")
      .def_readonly("drive", &Joint::drive,
                    "DriveKind of the joint's drive (NONE, PRESCRIBED, SERIES_ELASTIC, ...).")
      .def_readonly("drive_coord", &Joint::drive_coord, "Driven coordinate (0..k-1).")
      .def_readonly("drive_row", &Joint::drive_row, "Multiplier row of a prescribed drive, or -1.")
      .def("k", &Joint::k, "Number of joint coordinates.")
      .def("__repr__", [](const Joint& j) {
        return "<screwfem.Joint '" + j.name + "' (" + JointTypeName(j.type) + ")>";
      });

  py::class_<Model>(
      m, "Model",
      "The compiled model (model.h), constant. Velocities v (size nv) stack 6 body-velocity "
      "components [v; w] per free node (node frame, translation first) and then k joint-"
      "coordinate rates per joint; multipliers (size nc) stack the 6 relative-frame "
      "constraints per joint (none for a free joint) and one row per prescribed drive. "
      "Read-only from Python; entity lists refer into the model.")
      .def_readonly("nv", &Model::nv, "Number of velocity unknowns.")
      .def_readonly("nv_nodes", &Model::nv_nodes,
                    "The first nv_nodes velocities belong to nodes, the rest to joints.")
      .def_readonly("nc", &Model::nc, "Number of multipliers (constraint rows).")
      .def("num_unknowns", &Model::num_unknowns, "nv + nc.")
      .def_readonly("bandwidth", &Model::bandwidth, "Half-bandwidth of the permuted system.")
      .def_readonly("length_scale", &Model::length_scale,
                    "Characteristic length (bounding box diagonal) [m].")
      .def_readonly("gravity", &Model::gravity, "Gravity [m/s^2], world frame (view).")
      .def_property_readonly(
          "input_names",
          [](const Model& model) {
            std::vector<std::string> names;
            for (const ModelInput& in : model.inputs) names.push_back(in.name);
            return names;
          },
          "Names of the run-time inputs, in Simulation.input_values order.")
      .def_readonly("contact_laws", &Model::contact_laws,
                    "The contact law of each pair of material groups as Build resolved it "
                    "(ContactMaterial objects): the scene's settings first, then each "
                    "contact.pairs entry with its defaults (docs/scene-format.md, 'contact').")
      .def_property_readonly(
          "contact_group_names",
          [](const Model& model) {
            std::vector<std::string> names;
            for (const ContactMaterialGroup& g : model.contact_material_groups)
              names.push_back(g.name);
            return names;
          },
          "Names of the contact material groups, in ContactMaterial.groups order.")
      .def_readonly("rod_inertia", &Model::rod_inertia,
                    "RodInertia of the rods: EXACT (the exact helical velocity field) or CONSTANT "
                    "(linear velocity field, constant mass matrix).")
      .def_readonly("conform_mesh", &Model::conform_mesh,
                    "Whether build() conformed the rod meshes to their features (scene: "
                    "defaults.conform_mesh).")
      .def_readonly("conformed_nodes", &Model::conformed_nodes,
                    "Nodes build() added where features fell inside rod elements.")
      .def_readonly("linear_solver", &Model::linear_solver,
                    "LinearSolver asked for (AUTO, BANDED or SPARSE; scene: "
                    "analysis.linear_solver).")
      .def_readonly("sparse_solver", &Model::sparse_solver,
                    "True when Build chose the sparse LU (KLU) for the Newton systems, False "
                    "for the banded LU.")
      .def_readonly("banded_flops", &Model::banded_flops,
                    "Predicted flops of one banded factorisation (the choice of AUTO).")
      .def_readonly("sparse_flops", &Model::sparse_flops,
                    "Predicted flops of one sparse factorisation, from KLU's symbolic analysis "
                    "(0 when BANDED was asked for).")
      .def_readonly("coupled_nodes", &Model::coupled_nodes,
                    "Nodes the pairs of moving shapes are predicted to couple off the band at "
                    "once (the banded LU's contact coupling in the choice of AUTO).")
      .def_readonly("coupling_flops", &Model::coupling_flops,
                    "Predicted flops of the banded LU's off-band contact coupling per "
                    "factorisation (counted with banded_flops in the choice of AUTO).")
      .def_property_readonly(
          "banded_cost", [](const Model& mo) { return PredictedBandedCost(mo); },
          "The banded LU's predicted cost that AUTO compares: banded_flops + 0.25 "
          "coupling_flops.")
      .def_property_readonly(
          "sparse_cost", [](const Model& mo) { return PredictedSparseCost(mo); },
          "The sparse LU's predicted cost that AUTO compares: 4 sparse_flops + 200 per "
          "unknown (inf when it was not analysed).")
      .def_readonly("redundant_rows", &Model::redundant_rows,
                    "Constraint rows found linearly dependent at build time (their multipliers "
                    "are held at zero).")
      .def_readonly("warnings", &Model::warnings, "Non-fatal findings of the build.")
      .def_property_readonly(
          "num_nodes", [](const Model& mo) { return mo.nodes.size(); },
          "Number of nodes (frames on SE(3)).")
      .def_property_readonly(
          "num_elements", [](const Model& mo) { return mo.elements.size(); },
          "Number of rod elements of all rods.")
      .def_property_readonly(
          "num_rods", [](const Model& mo) { return mo.rods.size(); },
          "Number of rods (soft bodies).")
      .def_property_readonly(
          "num_bodies", [](const Model& mo) { return mo.bodies.size(); }, "Number of rigid bodies.")
      .def_property_readonly(
          "num_joints", [](const Model& mo) { return mo.joints.size(); }, "Number of joints.")
      .def_property_readonly(
          "num_tendons", [](const Model& mo) { return mo.tendons.size(); }, "Number of tendons.")
      .def_property_readonly(
          "num_actuators", [](const Model& mo) { return mo.actuators.size(); },
          "Number of rod actuators (chambers, muscles, rest strains, active stresses).")
      .def_property_readonly(
          "num_force_elements", [](const Model& mo) { return mo.force_elements.size(); },
          "Number of force elements.")
      .def_property_readonly(
          "nodes",
          [](py::object self) { return ReferenceList(self.cast<const Model&>().nodes, self); },
          "List of Node (copies).")
      .def_property_readonly(
          "elements",
          [](py::object self) { return ReferenceList(self.cast<const Model&>().elements, self); },
          "List of RodElement (copies).")
      .def_property_readonly(
          "rods",
          [](py::object self) { return ReferenceList(self.cast<const Model&>().rods, self); },
          "List of Rod (copies).")
      .def_property_readonly(
          "tendons",
          [](py::object self) { return ReferenceList(self.cast<const Model&>().tendons, self); },
          "List of Tendon (copies).")
      .def_property_readonly(
          "bodies",
          [](py::object self) { return ReferenceList(self.cast<const Model&>().bodies, self); },
          "List of RigidBody (copies).")
      .def_property_readonly(
          "joints",
          [](py::object self) { return ReferenceList(self.cast<const Model&>().joints, self); },
          "List of Joint (copies).")
      .def("find_node", &Model::FindNode, py::arg("name"), "Index of the named node, -1 if absent.")
      .def("find_rod", &Model::FindRod, py::arg("name"), "Index of the named rod, -1 if absent.")
      .def("find_body", &Model::FindBody, py::arg("name"),
           "Index of the named rigid body, -1 if absent.")
      .def("find_joint", &Model::FindJoint, py::arg("name"),
           "Index of the named joint, -1 if absent.")
      .def("find_tendon", &Model::FindTendon, py::arg("name"),
           "Index of the named tendon, -1 if absent.")
      .def("find_input", &Model::FindInput, py::arg("name"),
           "Index of the named run-time input, -1 if absent.");

  m.attr("kGround") = static_cast<int>(kGround);
}

}  // namespace screwfem::python
