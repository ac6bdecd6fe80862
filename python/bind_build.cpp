// ModelBuilder (include/screwfem/build/model_builder.h): building a Model from Python, with the
// Section, Profile and JointSpec values it takes. Frames are 4x4 homogeneous matrices
// [R x; 0 1] (R must be a rotation; Build() checks).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "bind.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/build/routing.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/mesh.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {

SE3 FrameFromMatrix(const Mat4& T) {
  SE3 H;
  H.R = T.topLeftCorner<3, 3>();
  H.x = T.topRightCorner<3, 1>();
  return H;
}

// A section from a shape (Section::Circle, Rectangle, Tube) with the damping keys of the scene's
// `sections:`, as a Python object whose attribute `radius` is the contact radius the shape
// implies (docs/scene-format.md, "contact").
py::object ShapedSection(Section s, double radius, const std::optional<Vec6>& damping,
                         double rayleigh_mass, double rayleigh_stiffness) {
  if (damping) s.damping = *damping;
  s.rayleigh_mass = rayleigh_mass;
  s.rayleigh_stiffness = rayleigh_stiffness;
  py::object out = py::cast(std::move(s));
  out.attr("radius") = radius;
  return out;
}

// A contact entity from Python's (rod, index) pair.
ContactEntity Entity(bool rod, int index) {
  return rod ? ContactEntity(RodId(index)) : ContactEntity(BodyId(index));
}

double PositiveSize(double x, const char* what) {
  if (!(x > 0.0) || !std::isfinite(x))
    throw InputError(std::string("Section: ") + what + " must be a positive number, got " +
                     std::to_string(x));
  return x;
}

void BindValues(py::module_& m) {
  py::class_<Material>(m, "Material",
                       "A material for Section.circle, .rectangle and .tube (section.h; the "
                       "scene's `materials:`). Give E and one of nu and G.")
      .def(py::init([](double E, std::optional<double> nu, double density, std::optional<double> G,
                       std::optional<double> shear_coefficient) {
             Material mat;
             if (!(E > 0.0) || !std::isfinite(E))
               throw InputError("Material: E must be a positive number");
             if (nu.has_value() == G.has_value())
               throw InputError("Material: give either nu or G (one of them)");
             if (G && (!(*G > 0.0) || !std::isfinite(*G)))
               throw InputError("Material: G must be a positive number");
             if (nu && !(*nu > -1.0 && *nu <= 0.5))
               throw InputError("Material: nu must be a Poisson ratio in (-1, 0.5]");
             if (!(density >= 0.0) || !std::isfinite(density))
               throw InputError("Material: density must be a number >= 0");
             if (shear_coefficient &&
                 (!(*shear_coefficient > 0.0) || !std::isfinite(*shear_coefficient)))
               throw InputError("Material: shear_coefficient must be a positive number");
             mat.youngs_modulus = E;
             if (nu) mat.poisson_ratio = *nu;
             if (G) mat.shear_modulus = *G;
             mat.density = density;
             if (shear_coefficient) mat.shear_coefficient = *shear_coefficient;
             return mat;
           }),
           py::arg("E"), py::arg("nu") = py::none(), py::arg("density") = 0.0,
           py::arg("G") = py::none(), py::arg("shear_coefficient") = py::none(),
           "Material(E, nu=None, density=0, G=None, shear_coefficient=None): Young's modulus E "
           "[Pa] > 0; Poisson's ratio nu in (-1, 0.5] or shear modulus G [Pa] > 0; density "
           "[kg/m^3] >= 0; shear correction kappa > 0 (default: Cowper's value for the shape).")
      .def_readwrite("youngs_modulus", &Material::youngs_modulus, "E [Pa] (scene key E).")
      .def_readwrite("shear_modulus", &Material::shear_modulus,
                     "G [Pa] (scene key G); 0: from poisson_ratio.")
      .def_readwrite("poisson_ratio", &Material::poisson_ratio, "nu (scene key nu).")
      .def_readwrite("density", &Material::density, "rho [kg/m^3].")
      .def_readwrite("shear_coefficient", &Material::shear_coefficient,
                     "kappa; 0: Cowper's value for the shape.");

  py::class_<Section>(m, "Section", py::dynamic_attr(),
                      "Rod cross-section (section.h): diagonals of the sectional stiffness K "
                      "[N, N, N, N m^2, N m^2, N m^2] and mass M per length [kg/m x3, kg m x3]. "
                      "Section(stiffness, inertia) is the scene's section by `stiffness` and "
                      "`inertia`; Section.circle, .rectangle and .tube its sections by `shape` "
                      "and `material`.")
      .def(py::init(&Section::FromDiagonals), py::arg("stiffness"),
           py::arg("inertia") = Vec6::Zero())
      .def(py::init<>(), "Section(): zeros, to be filled (a rigid body's unused section).")
      .def_static(
          "circle",
          [](double radius, const Material& material, const std::optional<Vec6>& damping,
             double rayleigh_mass, double rayleigh_stiffness) {
            return ShapedSection(Section::Circle(PositiveSize(radius, "radius"), material), radius,
                                 damping, rayleigh_mass, rayleigh_stiffness);
          },
          py::arg("radius"), py::arg("material"), py::arg("damping") = py::none(),
          py::arg("rayleigh_mass") = 0.0, py::arg("rayleigh_stiffness") = 0.0,
          "A solid circle of radius [m] (scene: shape: circle). damping: 6 values per mode "
          "[stiffness units x s]; rayleigh_mass a_M [1/s], rayleigh_stiffness a_K [s]. "
          "`radius` of the result: the contact radius (the circle's).")
      .def_static(
          "rectangle",
          [](double width, double height, const Material& material,
             const std::optional<Vec6>& damping, double rayleigh_mass, double rayleigh_stiffness) {
            return ShapedSection(Section::Rectangle(PositiveSize(width, "width"),
                                                    PositiveSize(height, "height"), material),
                                 0.5 * std::min(width, height), damping, rayleigh_mass,
                                 rayleigh_stiffness);
          },
          py::arg("width"), py::arg("height"), py::arg("material"), py::arg("damping") = py::none(),
          py::arg("rayleigh_mass") = 0.0, py::arg("rayleigh_stiffness") = 0.0,
          "A solid rectangle, width [m] along section axis 2 (y), height [m] along axis 3 (z) "
          "(scene: shape: rectangle); `radius`: half the smaller side.")
      .def_static(
          "tube",
          [](double outer_radius, double inner_radius, const Material& material,
             const std::optional<Vec6>& damping, double rayleigh_mass, double rayleigh_stiffness) {
            if (!(inner_radius >= 0.0 && inner_radius < outer_radius))
              throw InputError("Section: expected 0 <= inner_radius < outer_radius");
            return ShapedSection(
                Section::Tube(PositiveSize(outer_radius, "outer_radius"), inner_radius, material),
                outer_radius, damping, rayleigh_mass, rayleigh_stiffness);
          },
          py::arg("outer_radius"), py::arg("inner_radius"), py::arg("material"),
          py::arg("damping") = py::none(), py::arg("rayleigh_mass") = 0.0,
          py::arg("rayleigh_stiffness") = 0.0,
          "A circular tube [m] (scene: shape: tube); `radius`: the outer radius.")
      .def_readwrite("stiffness", &Section::stiffness,
                     "Diagonal stiffness (EA, GA2, GA3, GJ, EI2, EI3) [N, N, N, N m^2, N m^2, N "
                     "m^2] (a copy; assign a whole vector).")
      .def_readwrite("inertia", &Section::inertia,
                     "Diagonal inertia per length (rhoA, rhoA, rhoA, rhoJ, rhoI2, rhoI3) [kg/m, kg "
                     "m] (a copy; assign a whole vector).")
      .def_readwrite("damping", &Section::damping, "Viscous damping on strain rates (per mode).")
      .def_readwrite("rayleigh_mass", &Section::rayleigh_mass, "a_M [1/s].")
      .def_readwrite("rayleigh_stiffness", &Section::rayleigh_stiffness, "a_K [s].")
      .def_readwrite("width", &Section::width,
                     "Outline for drawing only: extent along section axis 2 [m] (0: unknown).")
      .def_readwrite("height", &Section::height, "Extent along section axis 3 [m].")
      .def_readwrite("round", &Section::round, "Round (width = height = diameter) or a rectangle.");

  py::class_<Profile>(m, "Profile", "A time profile f(t) (profile.h).")
      .def_static("constant", &Profile::Constant, py::arg("value") = 1.0, "f(t) = value.")
      .def_static("ramp", &Profile::Ramp, py::arg("t0"), py::arg("t1"), py::arg("scale") = 1.0,
                  "0 before t0, linear to `scale` at t1.")
      .def_static(
          "smooth_step", &Profile::SmoothStep, py::arg("t0"), py::arg("t1"), py::arg("scale") = 1.0,
          "0 before t0, `scale` after t1, the quintic C2 step 10u^3 - 15u^4 + 6u^5 between.")
      .def_static("bang_bang", &Profile::BangBang, py::arg("t0"), py::arg("t1"),
                  py::arg("scale") = 1.0,
                  "0 before t0, from 0 to `scale` on [t0, t1] with a bang-bang acceleration "
                  "(the scene's bang_bang and s_curve), held after.")
      .def_static("s_curve", &Profile::BangBang, py::arg("t0"), py::arg("t1"),
                  py::arg("scale") = 1.0, "The same law as bang_bang (the scene's s_curve).")
      .def_static("table", &Profile::Table, py::arg("times"), py::arg("values"),
                  py::arg("scale") = 1.0,
                  "Piecewise linear through (times[i], values[i]) times `scale`, held outside "
                  "(times [s] strictly increasing).")
      .def(
          "__add__",
          [](const Profile& a, const Profile& b) {
            Profile sum = a;
            sum.Add(b);
            return sum;
          },
          py::is_operator(), "The sum of the terms (the scene's {sum: [...]}).")
      .def(
          "__add__",
          [](const Profile& a, double b) {
            Profile sum = a;
            sum.Add(Profile::Constant(b));
            return sum;
          },
          py::is_operator())
      .def(
          "__radd__",
          [](const Profile& a, double b) {
            Profile sum = Profile::Constant(b);
            sum.Add(a);
            return sum;
          },
          py::is_operator())
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
      .def_readwrite("name", &JointSpec::name, "Unique name.")
      .def_readwrite("type", &JointSpec::type, "JointType: the Lie subgroup of the relative frame.")
      .def_readwrite("node_a", &JointSpec::node_a, "Node of side A, or -1 for the ground.")
      .def_readwrite("node_b", &JointSpec::node_b, "Node of side B, or -1 for the ground.")
      .def_readwrite("point", &JointSpec::point,
                     "The joint's point [m], world, in the reference configuration.")
      .def_readwrite("axis", &JointSpec::axis,
                     "The joint's axis (revolute, prismatic, helical, cylindrical; universal: the "
                     "first) [-], world, normalised by the builder.")
      .def_readwrite("axis2", &JointSpec::axis2, "Universal joints: the second axis [-], world.")
      .def_readwrite("pitch", &JointSpec::pitch, "Helical joints: translation per radian [m/rad].")
      .def_readwrite(
          "stiffness", &JointSpec::stiffness,
          "Spring stiffness per coordinate (JointSpringCount entries used) [N/m or N m/rad].")
      .def_readwrite("damping", &JointSpec::damping, "Damping per coordinate [N s/m or N m s/rad].")
      .def_readwrite("rest", &JointSpec::rest, "Spring rest value per coordinate [m or rad].")
      .def_readwrite("drive", &JointSpec::drive,
                     "DriveKind: NONE, PRESCRIBED (a constraint row), SERIES_ELASTIC, ...")
      .def_readwrite("drive_coordinate", &JointSpec::drive_coordinate,
                     "The driven coordinate (0 .. dof - 1).")
      .def_readwrite("drive_profile", &JointSpec::drive_profile,
                     "Profile of the drive: the coordinate q(t) [m or rad] (prescribed, "
                     "series-elastic) or the force or torque f(t) [N or N m].")
      .def_readwrite("has_initial_coordinate", &JointSpec::has_initial_coordinate,
                     "True: the joint starts at its initial coordinates (not the reference).")
      .def_readwrite("initial_coordinate", &JointSpec::initial_coordinate,
                     "Initial coordinates (first k entries), used when has_initial_coordinate.")
      .def_readwrite("has_initial_rate", &JointSpec::has_initial_rate,
                     "True: the joint starts with its initial rates.")
      .def_readwrite("initial_rate", &JointSpec::initial_rate,
                     "Initial rates (first k entries), used when has_initial_rate.");

  py::class_<BodyPoint>(m, "BodyPoint",
                        "A point fixed in a node frame (node-frame offset [m]) or, on GROUND, a "
                        "world point: a tendon eyelet or a force element's end (model.h).")
      .def(py::init([](int node, const Vec3& offset) {
             return BodyPoint{node, offset};
           }),
           py::arg("node"), py::arg("offset") = Vec3::Zero())
      .def_readwrite(
          "node", &BodyPoint::node,
          "The node the point is fixed to, or -1 (the ground: offset is then a world point).")
      .def_readwrite("offset", &BodyPoint::offset,
                     "Node-frame components of the point [m] (world coordinates for the ground).")
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

  py::class_<RodRoute>(m, "RodRoute",
                       "A tendon's eyelets on the nodes of a rod by rule (build/routing.h; the "
                       "scene's 'route' eyelet item): from arc length 'from' to 'to', every "
                       "'every'-th node and the last one, at 'offset' in the section frame, plus "
                       "a helical offset helix_radius (0, cos a, sin a), a = helix_phase + 2 pi "
                       "(s - from) / helix_pitch.")
      .def(py::init([](int rod, int every, double from, double to, const Vec3& offset,
                       double helix_radius, double helix_pitch, double helix_phase) {
             return RodRoute{rod, every, from, to, offset, helix_radius, helix_pitch, helix_phase};
           }),
           py::arg("rod") = -1, py::arg("every") = 1, py::arg("from_") = 0.0, py::arg("to") = -1.0,
           py::arg("offset") = Vec3::Zero(), py::arg("helix_radius") = 0.0,
           py::arg("helix_pitch") = 0.0, py::arg("helix_phase") = 0.0)
      .def_readwrite("rod", &RodRoute::rod, "The rod (builder index; -1 in a spec: its body).")
      .def_readwrite("every", &RodRoute::every, "Every k-th node (k >= 1).")
      .def_readwrite("from_", &RodRoute::from, "Arc length where the route starts [m].")
      .def_readwrite("to", &RodRoute::to, "Arc length where it ends [m]; negative: the end.")
      .def_readwrite("offset", &RodRoute::offset, "Section-frame offset [m].")
      .def_readwrite("helix_radius", &RodRoute::helix_radius, "Helix radius [m]; 0: none.")
      .def_readwrite("helix_pitch", &RodRoute::helix_pitch,
                     "Arc length per turn [m] (negative: the other hand).")
      .def_readwrite("helix_phase", &RodRoute::helix_phase,
                     "Angle of the helical offset at 'from' [rad], from section axis 2.");
  m.def("route_along_rod", &RouteAlongRod, py::arg("builder"), py::arg("route"),
        "The eyelets (BodyPoint list, in order along the rod) of a RodRoute on a builder's rod, "
        "for add_tendon; the scene's 'route' items expand through the same function.");
  m.def(
      "rod_node_arc_lengths", [](const ModelBuilder& b, RodId rod) { return b.RodArcLengths(rod); },
      py::arg("builder"), py::arg("rod"),
      "Reference arc length of each node of a builder's rod [m].");

  py::class_<ForceElement>(m, "ForceElement",
                           "A spring-damper-actuator between two body points (model.h): force "
                           "k (l - rest_length) + c dl/dt + actuator(t) [N], positive pulling "
                           "the ends together; rest_length < 0 means the reference distance.")
      .def(py::init<>())
      .def_readwrite("name", &ForceElement::name, "Unique name (the scene's forces: key).")
      .def_readwrite("a", &ForceElement::a, "BodyPoint of end A.")
      .def_readwrite("b", &ForceElement::b, "BodyPoint of end B.")
      .def_readwrite("stiffness", &ForceElement::stiffness, "[N/m]")
      .def_readwrite("rest_length", &ForceElement::rest_length, "[m]")
      .def_readwrite("damping", &ForceElement::damping, "[N s/m]")
      .def_readwrite("actuator", &ForceElement::actuator, "Profile [N].");

  py::class_<Actuator>(m, "Actuator",
                       "Internal actuation of a rod over [from, to] of its arc length "
                       "(model.h; docs/numerics.md, 'Active stress and rest strain'): an element "
                       "transmits sigma = K (eps - "
                       "eps0) - sigma_a. PRESSURE: sigma_a = p A [1, 0, 0, 0, r3, -r2]; MUSCLE: "
                       "-u max_stress A [1, 0, 0, 0, r3, -r2], u clamped to [0, 1]; REST_STRAIN: "
                       "eps0 = v vector; ACTIVE_STRESS: sigma_a = v vector; the value from "
                       "`profile`.")
      .def(py::init<>())
      .def_readwrite("name", &Actuator::name, "Unique name (the scene's actuation: key).")
      .def_readwrite("type", &Actuator::type,
                     "ActuatorType: PRESSURE, MUSCLE, REST_STRAIN or ACTIVE_STRESS.")
      .def_readwrite("rod", &Actuator::rod, "Rod index.")
      .def_readwrite("from_", &Actuator::from,
                     "Start of the range, arc length [m] (build puts a node there with "
                     "set_conform_mesh, the default; else it must be at one).")
      .def_readwrite("to", &Actuator::to, "End of the range [m] (as from_); < 0: the rod's end.")
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
                           "half sizes along the columns of rotation), cylinder (from, to: the "
                           "axis, radius; flat ends). Node-frame components [m].")
      .def(py::init([](int body, ContactShapeType type, const Vec3& from, const Vec3& to,
                       double radius, const Mat3& rotation) {
             return ContactShape{body, type, from, to, radius, rotation};
           }),
           py::arg("body"), py::arg("type"), py::arg("from_"), py::arg("to") = Vec3::Zero(),
           py::arg("radius") = 0.0, py::arg("rotation") = Mat3::Identity())
      .def_readwrite("body", &ContactShape::body,
                     "The rigid body the shape moves with (index into Model.bodies).")
      .def_readwrite("type", &ContactShape::type,
                     "ContactShapeType: SPHERE, CAPSULE, BOX or CYLINDER.")
      .def_readwrite("from_", &ContactShape::from,
                     "Sphere and box: the centre; capsule: one end of the axis [m] (world, "
                     "reference configuration).")
      .def_readwrite(
          "to", &ContactShape::to,
          "Capsule and cylinder: the other end of the axis [m]; box: the half sizes along its "
          "edges (> 0).")
      .def_readwrite("radius", &ContactShape::radius,
                     "Sphere, capsule and cylinder: the radius [m] (> 0); box: 0.")
      .def_readwrite("rotation", &ContactShape::rotation,
                     "Box: the directions of its edges in the body frame (3 x 3 rotation, "
                     "columns; scene: orientation); identity by default.");

  py::class_<ContactObstacle>(
      m, "ContactObstacle",
      "An obstacle fixed in the world (model.h): plane (point, normal; a "
      "moving surface: velocity, spin, motion), sphere (point = centre, "
      "radius), capsule and cylinder (point, to, radius), box (point = "
      "centre, to = half sizes, rotation), mesh (point, rotation, scale, set_mesh) and "
      "heightfield (point, rotation, set_heights).")
      .def(py::init<>())
      .def_readwrite("name", &ContactObstacle::name,
                     "Unique name (the scene's contact.obstacles key).")
      .def_readwrite(
          "type", &ContactObstacle::type,
          "ObstacleType: PLANE, SPHERE, CAPSULE, CYLINDER, BOX, MESH or HEIGHTFIELD, fixed in "
          "the world.")
      .def_readwrite("point", &ContactObstacle::point, "[m]")
      .def_readwrite("normal", &ContactObstacle::normal, "Plane: out of the obstacle.")
      .def_readwrite("to", &ContactObstacle::to, "[m]")
      .def_readwrite("radius", &ContactObstacle::radius, "[m]")
      .def_readwrite("rotation", &ContactObstacle::rotation,
                     "Box: the directions of its edges in the world (3 x 3 rotation, columns).")
      .def_readwrite("velocity", &ContactObstacle::velocity,
                     "Plane: the velocity of its surface along it [m/s] (a conveyor belt), "
                     "scaled by motion.")
      .def_readwrite("spin", &ContactObstacle::spin,
                     "Plane: the spin of its surface about the normal through point [rad/s] (a "
                     "turntable), scaled by motion.")
      .def_readwrite("motion", &ContactObstacle::motion,
                     "Plane: the Profile m(t) scaling velocity and spin (default 1).")
      .def_readwrite("contype", &ContactObstacle::contype,
                     "Contact group bitmask: a pair touches when contype & conaffinity of the "
                     "other is non-zero (either way).")
      .def_readwrite("conaffinity", &ContactObstacle::conaffinity,
                     "Contact affinity bitmask (see contype).")
      .def_readwrite("scale", &ContactObstacle::scale,
                     "Mesh: the factor on its vertices (default 1).")
      .def(
          "set_mesh",
          [](ContactObstacle& o, const Eigen::Matrix<double, Eigen::Dynamic, 3>& vertices,
             const Eigen::Matrix<int, Eigen::Dynamic, 3>& faces) {
            auto mesh = std::make_shared<TriangleMesh>();
            for (Eigen::Index i = 0; i < vertices.rows(); ++i)
              mesh->vertices.push_back(vertices.row(i).transpose());
            for (Eigen::Index i = 0; i < faces.rows(); ++i)
              mesh->faces.push_back({faces(i, 0), faces(i, 1), faces(i, 2)});
            const std::string why = CheckTriangleMesh(*mesh, "obstacle '" + o.name + "'");
            if (!why.empty()) throw InputError(why);
            o.mesh = std::move(mesh);
          },
          py::arg("vertices"), py::arg("faces"),
          "Mesh: its triangles in the obstacle frame (placed at point + rotation scale v): "
          "vertices (n x 3) [m], faces (m x 3, 0-based, counter-clockwise seen from outside).")
      .def(
          "set_heights",
          [](ContactObstacle& o, const Eigen::MatrixXd& heights, double dx, double dy) {
            if (heights.rows() < 2 || heights.cols() < 2)
              throw InputError("obstacle '" + o.name + "': expected at least 2 x 2 heights");
            if (!(dx > 0.0) || !(dy > 0.0))
              throw InputError("obstacle '" + o.name + "': expected positive spacings");
            std::vector<double> h;
            for (Eigen::Index i = 0; i < heights.rows(); ++i)
              for (Eigen::Index j = 0; j < heights.cols(); ++j) h.push_back(heights(i, j));
            o.mesh = std::make_shared<TriangleMesh>(HeightFieldMesh(
                h, static_cast<int>(heights.rows()), static_cast<int>(heights.cols()), dx, dy));
          },
          py::arg("heights"), py::arg("dx"), py::arg("dy"),
          "Height field: heights[i, j] (rows along y, columns along x) [m] on a grid of spacing "
          "dx, dy [m] centred on point.")
      .def(
          "mesh_vertices",
          [](const ContactObstacle& o) {
            Eigen::Matrix<double, Eigen::Dynamic, 3> v(o.mesh ? o.mesh->vertices.size() : 0, 3);
            for (Eigen::Index i = 0; i < v.rows(); ++i)
              v.row(i) = o.mesh->vertices[static_cast<std::size_t>(i)].transpose();
            return v;
          },
          "Mesh and height field: the vertices in the obstacle frame (n x 3) [m].")
      .def(
          "mesh_faces",
          [](const ContactObstacle& o) {
            Eigen::Matrix<int, Eigen::Dynamic, 3> f(o.mesh ? o.mesh->faces.size() : 0, 3);
            for (Eigen::Index i = 0; i < f.rows(); ++i)
              for (int k = 0; k < 3; ++k)
                f(i, k) = o.mesh->faces[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)];
            return f;
          },
          "Mesh and height field: the triangles (m x 3, 0-based).");

  m.def(
      "mesh_mass_properties",
      [](const Eigen::Matrix<double, Eigen::Dynamic, 3>& vertices,
         const Eigen::Matrix<int, Eigen::Dynamic, 3>& faces, double density) {
        TriangleMesh mesh;
        for (Eigen::Index i = 0; i < vertices.rows(); ++i)
          mesh.vertices.push_back(vertices.row(i).transpose());
        for (Eigen::Index i = 0; i < faces.rows(); ++i)
          mesh.faces.push_back({faces(i, 0), faces(i, 1), faces(i, 2)});
        const std::string why = CheckTriangleMesh(mesh, "mesh_mass_properties");
        if (!why.empty()) throw InputError(why);
        const MeshMassProperties p = CalcMeshMassProperties(mesh);
        return py::make_tuple(density * p.volume, p.centroid, Mat3(density * p.inertia));
      },
      py::arg("vertices"), py::arg("faces"), py::arg("density"),
      "Mass [kg], centre of mass [m] and inertia about it [kg m^2] of the solid a closed, "
      "outward-oriented triangle mesh bounds (Mirtich 1996), at a density [kg/m^3].");

  py::class_<ContactSettings>(
      m, "ContactSettings",
      "The contact law (docs/numerics.md, 'Contact'); negative values are the "
      "defaults set by build().")
      .def(py::init<>())
      .def_readwrite("stiffness", &ContactSettings::stiffness, "k_n [N/m]")
      .def_readwrite("onset", &ContactSettings::onset, "delta [m]")
      .def_readwrite("damping_ratio", &ContactSettings::damping_ratio,
                     "zeta [-]: the normal damping c_n = 2 zeta sqrt(k_n m_eff).")
      .def_readwrite("friction", &ContactSettings::friction, "mu (mu_k of the stick law)")
      .def_readwrite("slip_velocity", &ContactSettings::slip_velocity, "eps_v [m/s] (smooth law)")
      .def_readwrite("friction_law", &ContactSettings::friction_law,
                     "FrictionLaw: STICK (elastic anchor, statics and dynamics) or SMOOTH.")
      .def_readwrite("static_friction", &ContactSettings::static_friction,
                     "mu_s >= mu_k (stick law; default: friction)")
      .def_readwrite("tangential_stiffness", &ContactSettings::tangential_stiffness,
                     "k_t [N/m] of the stick law's anchor (default: the normal stiffness)")
      .def_readwrite("self", &ContactSettings::self, "Rod self-contact.")
      .def_readwrite("self_skip", &ContactSettings::self_skip,
                     "Self-contact skips element pairs whose nearest ends are closer along the "
                     "rod [m] (default 4 r).");

  py::class_<ContactMaterial>(
      m, "ContactMaterial",
      "The contact law's parameters for a pair of contact material groups (model.h; the "
      "scene's contact.pairs, MuJoCo's pair); negative values are the scene's settings "
      "(static_friction: this pair's friction when it gives one; tangential_stiffness: this "
      "pair's stiffness unless the scene sets one). Model.contact_laws holds them resolved.")
      .def(py::init<>())
      .def_property(
          "groups", [](const ContactMaterial& c) { return py::make_tuple(c.group[0], c.group[1]); },
          [](ContactMaterial& c, const std::pair<int, int>& g) {
            c.group[0] = g.first;
            c.group[1] = g.second;
          },
          "The two groups (indices of ModelBuilder.add_contact_material_group; may be equal).")
      .def_readwrite("friction", &ContactMaterial::friction, "mu_k >= 0")
      .def_readwrite("static_friction", &ContactMaterial::static_friction, "mu_s >= mu_k")
      .def_readwrite("stiffness", &ContactMaterial::stiffness, "k_n [N/m] > 0")
      .def_readwrite("damping_ratio", &ContactMaterial::damping_ratio,
                     "zeta >= 0: c_n = 2 zeta sqrt(k_n m_pair)")
      .def_readwrite("tangential_stiffness", &ContactMaterial::tangential_stiffness,
                     "k_t [N/m] > 0 of the stick law's anchor")
      .def_readwrite("onset", &ContactMaterial::onset,
                     "delta [m] > 0: the force starts at gap delta (default: contact.onset)");

  py::class_<NodeMatch>(m, "NodeMatch", "Result of ModelBuilder.find_node_at.")
      .def_readonly("node", &NodeMatch::node, "The node within the tolerance, or -1.")
      .def_readonly("nearest", &NodeMatch::nearest, "The nearest node (-1 when there is none).")
      .def_readonly("distance", &NodeMatch::distance, "Distance to the nearest node [m].");
}

}  // namespace

void BindBuild(py::module_& m) {
  m.attr("GROUND") = static_cast<int>(kGround);
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
      .def("fix_node", &B::FixNode, py::arg("node"),
           "Clamps a node to the world (the node is eliminated from the unknowns).")
      .def("add_straight_rod", &B::AddStraightRod, py::arg("name"), py::arg("p0"), py::arg("p1"),
           py::arg("num_elements"), py::arg("section"), py::arg("up") = Vec3::UnitZ(),
           py::arg("start_node") = -1, py::arg("end_node") = -1,
           "A rod of num_elements helical elements from p0 to p1 [m], its section frame x along "
           "the rod and z towards `up`; start_node / end_node >= 0 share an existing node at that "
           "end. Returns the rod index.")
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
      .def(
          "set_contact_group",
          [](B& b, bool rod, int index, unsigned contype, unsigned conaffinity) {
            b.SetContactGroup(Entity(rod, index), contype, conaffinity);
          },
          py::arg("rod"), py::arg("index"), py::arg("contype"), py::arg("conaffinity"),
          "Group bitmasks of a rod (rod=True) or rigid body (MuJoCo's contype/conaffinity).")
      .def(
          "exclude_contact",
          [](B& b, bool rod, int index, ObstacleId obstacle) {
            b.ExcludeContact(Entity(rod, index), obstacle);
          },
          py::arg("rod"), py::arg("index"), py::arg("obstacle"),
          "No contact between a rod or rigid body and an obstacle.")
      .def(
          "exclude_contact_pair",
          [](B& b, bool rod_a, int index_a, bool rod_b, int index_b) {
            b.ExcludeContactPair(Entity(rod_a, index_a), Entity(rod_b, index_b));
          },
          py::arg("rod_a"), py::arg("index_a"), py::arg("rod_b"), py::arg("index_b"),
          "No contact between two moving entities (each a rod or a rigid body, by index).")
      .def(
          "add_contact_material_group",
          [](B& b, const std::string& name, const std::vector<std::pair<bool, int>>& members,
             const std::vector<int>& obstacles) {
            std::vector<ContactEntity> entities;
            for (const auto& [rod, index] : members) entities.push_back(Entity(rod, index));
            std::vector<ObstacleId> ids;
            for (int o : obstacles) ids.push_back(ObstacleId(o));
            return b.AddContactMaterialGroup(name, entities, ids);
          },
          py::arg("name"), py::arg("members"), py::arg("obstacles") = std::vector<int>{},
          "A named group of contact entities ((rod, index) pairs: a rod with rod=True, else a "
          "rigid body) and obstacles (indices), each in one group at most; returns its index "
          "for ContactMaterial.groups.")
      .def("add_contact_material", &B::AddContactMaterial, py::arg("material"),
           "The law's parameters (ContactMaterial) for a pair of groups; each pair once.")
      .def("set_contact_settings", &B::SetContactSettings, py::arg("settings"),
           "The contact law's settings (ContactSettings) for every pair.")
      .def(
          "set_memory_limit",
          [](B& b, const py::object& size) {
            b.SetMemoryLimit(MemorySize(size, "ModelBuilder.set_memory_limit"));
          },
          py::arg("size"),
          "The memory the model and its solver may need: bytes or a size such as '8G' (None: "
          "the process default, screwfem.set_memory_limit). build() raises InputError naming "
          "the part beyond it (docs/limits.md).")
      .def("set_conform_mesh", &B::SetConformMesh, py::arg("conform"),
           "Whether build() puts a node wherever a tendon eyelet, a force element's end, a "
           "concentrated rod load or an actuator's end falls inside a rod element, splitting "
           "the element there (default True; scene: defaults.conform_mesh). Second-order "
           "convergence with such features; the nodes added come after all others "
           "(Model.conformed_nodes counts them), so node indices taken before build() stay "
           "valid.")
      .def("set_linear_solver", &B::SetLinearSolver, py::arg("solver"),
           "The direct solver of the Newton systems (LinearSolver; scene: "
           "analysis.linear_solver): AUTO picks the lower predicted factorisation cost.")
      .def("build", &B::Build, "The validated Model.");
}

}  // namespace screwfem::python
