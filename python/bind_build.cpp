// ModelBuilder (include/screwfem/build/model_builder.h): building a Model from Python, with the
// Section, Profile and JointSpec values it takes. Frames are 4x4 homogeneous matrices
// [R x; 0 1] (R must be a rotation; Build() checks).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "bind.h"
#include "screwfem/build/model_builder.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {

SE3 FrameFromMatrix(const Mat4& T) {
  SE3 H;
  H.R = T.topLeftCorner<3, 3>();
  H.x = T.topRightCorner<3, 1>();
  return H;
}

void BindValues(py::module_& m) {
  py::class_<Section>(m, "Section",
                      "Rod cross-section (section.h): diagonals of the sectional stiffness K "
                      "[N, N, N, N m^2, N m^2, N m^2] and mass M per length [kg/m x3, kg m x3].")
      .def(py::init(&Section::FromDiagonals), py::arg("stiffness"),
           py::arg("inertia") = Vec6::Zero())
      .def_readwrite("stiffness", &Section::stiffness)
      .def_readwrite("inertia", &Section::inertia)
      .def_readwrite("damping", &Section::damping, "Viscous damping on strain rates (per mode).")
      .def_readwrite("rayleigh_mass", &Section::rayleigh_mass, "a_M [1/s].")
      .def_readwrite("rayleigh_stiffness", &Section::rayleigh_stiffness, "a_K [s].")
      .def_readwrite("width", &Section::width,
                     "Outline for drawing only: extent along section axis 2 [m] (0: unknown).")
      .def_readwrite("height", &Section::height, "Extent along section axis 3 [m].")
      .def_readwrite("round", &Section::round, "Round (width = height = diameter) or a rectangle.");

  py::class_<Profile>(m, "Profile", "A time profile f(t) (profile.h).")
      .def_static("constant", &Profile::Constant, py::arg("value") = 1.0)
      .def_static("ramp", &Profile::Ramp, py::arg("t0"), py::arg("t1"), py::arg("scale") = 1.0,
                  "0 before t0, linear to `scale` at t1.")
      .def_static("smooth_step", &Profile::SmoothStep, py::arg("t0"), py::arg("t1"),
                  py::arg("scale") = 1.0)
      .def_static("sine", &Profile::Sine, py::arg("amplitude"), py::arg("frequency"),
                  py::arg("phase") = 0.0, py::arg("t0") = 0.0, "frequency in Hz")
      .def_static("input", &Profile::Input, py::arg("input"), py::arg("scale") = 1.0,
                  "scale times run-time input number `input` (Model.inputs; "
                  "ModelBuilder.add_input), read from Simulation.inputs at every evaluation.")
      .def("__call__", &Profile::operator(), py::arg("t"), "f(t).");

  py::class_<JointSpec>(m, "JointSpec",
                        "A joint for ModelBuilder.add_joint (model_builder.h): type, sides "
                        "(node indices or GROUND = -1), world point [m] and axes, springs, "
                        "dampers, rest values and a drive.")
      .def(py::init<>())
      .def_readwrite("name", &JointSpec::name)
      .def_readwrite("type", &JointSpec::type)
      .def_readwrite("node_a", &JointSpec::node_a)
      .def_readwrite("node_b", &JointSpec::node_b)
      .def_readwrite("point", &JointSpec::point)
      .def_readwrite("axis", &JointSpec::axis)
      .def_readwrite("axis2", &JointSpec::axis2)
      .def_readwrite("pitch", &JointSpec::pitch)
      .def_readwrite("stiffness", &JointSpec::stiffness)
      .def_readwrite("damping", &JointSpec::damping)
      .def_readwrite("rest", &JointSpec::rest)
      .def_readwrite("drive", &JointSpec::drive)
      .def_readwrite("drive_coordinate", &JointSpec::drive_coordinate)
      .def_readwrite("drive_profile", &JointSpec::drive_profile)
      .def_readwrite("has_initial_coordinate", &JointSpec::has_initial_coordinate)
      .def_readwrite("initial_coordinate", &JointSpec::initial_coordinate,
                     "Initial coordinates (first k entries), used when has_initial_coordinate.")
      .def_readwrite("has_initial_rate", &JointSpec::has_initial_rate)
      .def_readwrite("initial_rate", &JointSpec::initial_rate,
                     "Initial rates (first k entries), used when has_initial_rate.");

  py::class_<BodyPoint>(m, "BodyPoint",
                        "A point fixed in a node frame (node-frame offset [m]) or, on GROUND, a "
                        "world point: a tendon eyelet or a force element's end (model.h).")
      .def(py::init([](int node, const Vec3& offset) {
             return BodyPoint{node, offset};
           }),
           py::arg("node"), py::arg("offset") = Vec3::Zero())
      .def_readwrite("node", &BodyPoint::node)
      .def_readwrite("offset", &BodyPoint::offset)
      .def_static(
          "on_rod",
          [](int rod, double arc_length, const Vec3& offset) {
            BodyPoint p{kGround, offset};
            p.rod = rod;
            p.arc_length = arc_length;
            return p;
          },
          py::arg("rod"), py::arg("arc_length"), py::arg("offset") = Vec3::Zero(),
          "A tendon eyelet or force-element end at reference arc length [m] of a rod: build "
          "places it on the node "
          "there or, between nodes, on the section of the element holding it (offset in that "
          "section's frame).")
      .def_readwrite("rod", &BodyPoint::rod, "The rod of a point at an arc length (-1: none).")
      .def_readwrite("arc_length", &BodyPoint::arc_length, "Its reference arc length [m].")
      .def_readonly("element", &BodyPoint::element,
                    "Set by build for a point between nodes: its element (-1: on a node).")
      .def_readonly("xi", &BodyPoint::xi, "Set by build: its place in the element, in (0, 1).");

  py::class_<ForceElement>(m, "ForceElement",
                           "A spring-damper-actuator between two body points (model.h): force "
                           "k (l - rest_length) + c dl/dt + actuator(t) [N], positive pulling "
                           "the ends together; rest_length < 0 means the reference distance.")
      .def(py::init<>())
      .def_readwrite("name", &ForceElement::name)
      .def_readwrite("a", &ForceElement::a)
      .def_readwrite("b", &ForceElement::b)
      .def_readwrite("stiffness", &ForceElement::stiffness, "[N/m]")
      .def_readwrite("rest_length", &ForceElement::rest_length, "[m]")
      .def_readwrite("damping", &ForceElement::damping, "[N s/m]")
      .def_readwrite("actuator", &ForceElement::actuator, "Profile [N].");

  py::class_<Actuator>(m, "Actuator",
                       "Internal actuation of a rod over [from, to] of its arc length "
                       "(model.h; method-next.md §N5): an element transmits sigma = K (eps - "
                       "eps0) - sigma_a. PRESSURE: sigma_a = p A [1, 0, 0, 0, r3, -r2]; MUSCLE: "
                       "-u max_stress A [1, 0, 0, 0, r3, -r2], u clamped to [0, 1]; REST_STRAIN: "
                       "eps0 = v vector; ACTIVE_STRESS: sigma_a = v vector; the value from "
                       "`profile`.")
      .def(py::init<>())
      .def_readwrite("name", &Actuator::name)
      .def_readwrite("type", &Actuator::type)
      .def_readwrite("rod", &Actuator::rod, "Rod index.")
      .def_readwrite("from_", &Actuator::from, "Start of the range, arc length [m] (at a node).")
      .def_readwrite("to", &Actuator::to, "End of the range [m] (at a node); < 0: the rod's end.")
      .def_readwrite("area", &Actuator::area, "Chamber or muscle area [m^2].")
      .def_readwrite("offset", &Actuator::offset, "Centroid (0, r2, r3) in the section [m].")
      .def_readwrite("max_stress", &Actuator::max_stress, "Muscle [Pa].")
      .def_readwrite("vector", &Actuator::vector, "REST_STRAIN or ACTIVE_STRESS (6 entries).")
      .def_readwrite("profile", &Actuator::profile,
                     "Pressure [Pa], activation [-] or the factor of `vector` (a Profile; "
                     "Profile.input for a run-time input).");

  py::class_<ContactShape>(m, "ContactShape",
                           "A collision shape in a rigid body's frame (model.h): sphere (from = "
                           "centre, radius), capsule (from, to, radius), box (from = centre, to = "
                           "half sizes along the body axes). Node-frame components [m].")
      .def(py::init([](int body, ContactShapeType type, const Vec3& from, const Vec3& to,
                       double radius) {
             return ContactShape{body, type, from, to, radius};
           }),
           py::arg("body"), py::arg("type"), py::arg("from_"), py::arg("to") = Vec3::Zero(),
           py::arg("radius") = 0.0)
      .def_readwrite("body", &ContactShape::body)
      .def_readwrite("type", &ContactShape::type)
      .def_readwrite("from_", &ContactShape::from)
      .def_readwrite("to", &ContactShape::to)
      .def_readwrite("radius", &ContactShape::radius);

  py::class_<ContactObstacle>(m, "ContactObstacle",
                              "An obstacle fixed in the world (model.h): plane (point, normal), "
                              "sphere (point = centre, radius), capsule (point, to, radius).")
      .def(py::init<>())
      .def_readwrite("name", &ContactObstacle::name)
      .def_readwrite("type", &ContactObstacle::type)
      .def_readwrite("point", &ContactObstacle::point, "[m]")
      .def_readwrite("normal", &ContactObstacle::normal, "Plane: out of the obstacle.")
      .def_readwrite("to", &ContactObstacle::to, "[m]")
      .def_readwrite("radius", &ContactObstacle::radius, "[m]")
      .def_readwrite("contype", &ContactObstacle::contype)
      .def_readwrite("conaffinity", &ContactObstacle::conaffinity);

  py::class_<ContactSettings>(m, "ContactSettings",
                              "The contact law (method-next.md §N6.3); negative values are the "
                              "defaults set by build().")
      .def(py::init<>())
      .def_readwrite("stiffness", &ContactSettings::stiffness, "k_n [N/m]")
      .def_readwrite("onset", &ContactSettings::onset, "delta [m]")
      .def_readwrite("damping_ratio", &ContactSettings::damping_ratio)
      .def_readwrite("friction", &ContactSettings::friction, "mu")
      .def_readwrite("slip_velocity", &ContactSettings::slip_velocity, "eps_v [m/s]")
      .def_readwrite("self", &ContactSettings::self, "Rod self-contact.")
      .def_readwrite("self_skip", &ContactSettings::self_skip,
                     "Self-contact skips element pairs whose nearest ends are closer along the "
                     "rod [m] (default 4 r).");

  py::class_<NodeMatch>(m, "NodeMatch", "Result of ModelBuilder.find_node_at.")
      .def_readonly("node", &NodeMatch::node, "The node within the tolerance, or -1.")
      .def_readonly("nearest", &NodeMatch::nearest, "The nearest node (-1 when there is none).")
      .def_readonly("distance", &NodeMatch::distance, "Distance to the nearest node [m].");
}

}  // namespace

void BindBuild(py::module_& m) {
  m.attr("GROUND") = kGround;
  BindValues(m);
  using B = ModelBuilder;
  py::class_<B>(m, "ModelBuilder",
                "Builds a Model (model_builder.h); build() validates it and raises InputError.")
      .def(py::init<>())
      .def(
          "add_node",
          [](B& b, const Mat4& frame, std::string name) {
            return b.AddNode(FrameFromMatrix(frame), std::move(name));
          },
          py::arg("frame"), py::arg("name") = std::string{},
          "A node with the 4x4 reference frame [R x; 0 1]; returns its index.")
      .def("fix_node", &B::FixNode, py::arg("node"))
      .def("add_straight_rod", &B::AddStraightRod, py::arg("name"), py::arg("p0"), py::arg("p1"),
           py::arg("num_elements"), py::arg("section"), py::arg("up") = Vec3::UnitZ(),
           py::arg("start_node") = -1, py::arg("end_node") = -1)
      .def("add_rod_along_path", &B::AddRodAlongPath, py::arg("name"), py::arg("path"),
           py::arg("elements_per_segment"), py::arg("section"), py::arg("up") = Vec3::UnitZ(),
           py::arg("start_node") = -1, py::arg("end_node") = -1,
           "A rod along a polyline (points [m]); frames along the segments, along the bisector "
           "at interior points. start_node/end_node share existing nodes. Returns the rod index.")
      .def("find_node_at", &B::FindNodeAt, py::arg("point"), py::arg("rod") = -1,
           py::arg("tolerance") = -1.0,
           "The node at a world point (of one rod, or of all nodes when rod < 0) -> NodeMatch.")
      .def("rod_length", &B::RodLength, py::arg("rod"), "Reference arc length [m].")
      .def("add_rigid_body", &B::AddRigidBody, py::arg("name"), py::arg("node"), py::arg("mass"),
           py::arg("com"), py::arg("inertia"),
           "Mass [kg], centre of mass and inertia about it [kg m^2] in the node frame.")
      .def("add_joint", py::overload_cast<const JointSpec&>(&B::AddJoint), py::arg("spec"),
           "A joint from a JointSpec; returns its index.")
      .def("add_tendon", &B::AddTendon, py::arg("name"), py::arg("eyelets"), py::arg("tension"),
           "A tendon through eyelets (a list of BodyPoint, in routing order) pulling with the "
           "tension profile [N] (>= 0); returns its index.")
      .def("add_actuator", &B::AddActuator, py::arg("actuator"),
           "An Actuator (rest strain or active stress on a rod); returns its index.")
      .def("add_length_driven_tendon", &B::AddLengthDrivenTendon, py::arg("name"),
           py::arg("eyelets"), py::arg("length"),
           "A tendon drawn by length: its route length follows the length profile [m] while it "
           "is taut, its tension is the constraint's multiplier (tendon_state), and it goes "
           "slack instead of pushing; returns its index.")
      .def("add_force_element", &B::AddForceElement, py::arg("element"),
           "A ForceElement (spring-damper-actuator between two body points); returns its index.")
      .def("find_rod_node_at_arc_length", &B::FindRodNodeAtArcLength, py::arg("rod"), py::arg("s"),
           py::arg("tolerance") = -1.0,
           "The node of a rod at reference arc length s [m] -> NodeMatch (distance in arc length).")
      .def("set_gravity", &B::SetGravity, py::arg("g"), "[m/s^2], world frame.")
      .def("set_initial_velocity", &B::SetInitialVelocity, py::arg("node"), py::arg("velocity"),
           "Initial body velocity [v; w] of a node in its frame (AssembleInitialState).")
      .def("add_input", &B::AddInput, py::arg("name"), py::arg("default") = 0.0,
           "A run-time input (Model.inputs) for Profile.input; returns its index.")
      .def("add_contact_rod", &B::AddContactRod, py::arg("rod"), py::arg("radius"),
           "The rod takes part in contact as a chain of capsules of radius [m].")
      .def("add_contact_shape", &B::AddContactShape, py::arg("shape"),
           "A ContactShape on a rigid body; returns its index.")
      .def("add_obstacle", &B::AddObstacle, py::arg("obstacle"),
           "A ContactObstacle fixed in the world; returns its index.")
      .def("set_contact_group", &B::SetContactGroup, py::arg("rod"), py::arg("index"),
           py::arg("contype"), py::arg("conaffinity"),
           "Group bitmasks of a rod (rod=True) or rigid body (MuJoCo's contype/conaffinity).")
      .def("exclude_contact", &B::ExcludeContact, py::arg("rod"), py::arg("index"),
           py::arg("obstacle"), "No contact between a rod or rigid body and an obstacle.")
      .def("exclude_contact_pair", &B::ExcludeContactPair, py::arg("rod_a"), py::arg("index_a"),
           py::arg("rod_b"), py::arg("index_b"),
           "No contact between two moving entities (each a rod or a rigid body, by index).")
      .def("set_contact_settings", &B::SetContactSettings, py::arg("settings"))
      .def("build", &B::Build, "The validated Model.");
}

}  // namespace screwfem::python
