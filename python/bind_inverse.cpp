// Sensitivities of static equilibria and inverse statics (solve/sensitivity.h, docs/inverse.md):
// screwfem.static_sensitivity and screwfem.inverse_statics on a Simulation.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "bind.h"
#include "screwfem/solve/sensitivity.h"
#include "simulation.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {

StaticOptions SimulationStatics(Simulation& s, const std::optional<StaticOptions>& options) {
  StaticOptions o = s.scene().analysis.statics;
  o.time = s.data().time;
  if (options) o = *options;
  ValidateStaticOptions(o, "StaticOptions");
  return o;
}

}  // namespace

void BindInverse(py::module_& m) {
  BindEnum<ParameterKind>(m, "ParameterKind",
                          "What a sensitivity or inverse-statics parameter is (sensitivity.h).");
  BindEnum<OutputKind>(m, "OutputKind", "What a sensitivity output is (sensitivity.h).");
  BindEnum<SensitivityMode>(m, "SensitivityMode",
                            "Forward (a solve per parameter) or adjoint (a solve per output).");

  py::class_<Parameter>(m, "Parameter",
                        "A parameter of a static equilibrium (docs/inverse.md): kind, index of "
                        "the tendon, point load, joint, rod, input or actuator, and component "
                        "(point loads 0-5; rod stiffness -1 for all six or 0-5; rod rest strain "
                        "0-5; tendon offset 0-2).")
      .def(py::init([](ParameterKind kind, int index, int component,
                       const std::optional<Profile>& shape) {
             Parameter p{kind, index, component, {}};
             if (shape) p.shape = *shape;
             return p;
           }),
           py::arg("kind"), py::arg("index"), py::arg("component") = -1,
           py::arg("shape") = py::none())
      .def_readwrite("kind", &Parameter::kind, "What the parameter is (ParameterKind).")
      .def_readwrite("index", &Parameter::index,
                     "The tendon, point load, joint, rod, input or actuator (the model's index).")
      .def_readwrite(
          "component", &Parameter::component,
          "Point loads 0-5 (force, moment); rod stiffness -1 (all) or 0-5; rest strain 0-5; "
          "tendon offset 0-2 (node-frame axis).")
      .def_readwrite("shape", &Parameter::shape,
                     "TENDON_TENSION, TENDON_LENGTH, JOINT_DRIVE, ACTUATOR: the profile the "
                     "value multiplies "
                     "(none: the constant 1); a hat-shaped Profile.table is a knot of a "
                     "piecewise-linear input.")
      .def("__repr__", [](const Parameter& p) {
        return "Parameter(" + std::string(NameOf(p.kind)) + ", " + std::to_string(p.index) + ", " +
               std::to_string(p.component) + ")";
      });

  py::class_<SensitivityOutput>(m, "SensitivityOutput",
                                "An output of a static sensitivity: a world coordinate of a point "
                                "in a node's frame (offset), a node's rotation component, a joint "
                                "coordinate or a multiplier row.")
      .def(py::init([](OutputKind kind, int index, int component, const Vec3& offset) {
             return SensitivityOutput{kind, index, component, offset};
           }),
           py::arg("kind"), py::arg("index"), py::arg("component") = 0,
           py::arg("offset") = Vec3::Zero())
      .def_readwrite("kind", &SensitivityOutput::kind, "What the output is (OutputKind).")
      .def_readwrite("index", &SensitivityOutput::index,
                     "The node (points, rotations), joint or multiplier row.")
      .def_readwrite("component", &SensitivityOutput::component,
                     "0-2 for points and rotations; the joint coordinate.")
      .def_readwrite("offset", &SensitivityOutput::offset,
                     "POINT_POSITION: the point in the node's frame [m].");

  py::class_<StaticSensitivity>(m, "StaticSensitivity",
                                "Result of static_sensitivity: outputs (outputs x parameters), "
                                "and in forward mode dx (nv x parameters: node twists in the "
                                "node frames, joint coordinates) and dlambda (nc x parameters).")
      .def_readonly("ok", &StaticSensitivity::ok, "True when the derivatives were computed.")
      .def_readonly("message", &StaticSensitivity::message, "Why not (empty when ok).")
      .def_readonly("outputs", &StaticSensitivity::outputs,
                    "d(outputs)/d(parameters), outputs x parameters.")
      .def_readonly("dx", &StaticSensitivity::dx,
                    "Forward mode: nv x parameters (node twists in the node frames, translation "
                    "first; joint coordinates).")
      .def_readonly("dlambda", &StaticSensitivity::dlambda,
                    "Forward mode: nc x parameters, the multipliers' derivatives.")
      .def_readonly(
          "equilibrium_error", &StaticSensitivity::equilibrium_error,
          "Scaled size of the Newton correction at the state: how far it is from the equilibrium.");

  py::class_<InverseTarget>(m, "InverseTarget",
                            "An effector point (node, offset in its frame [m]) and its world "
                            "target [m].")
      .def(py::init([](int node, const Vec3& offset, const Vec3& target) {
             return InverseTarget{node, offset, target};
           }),
           py::arg("node"), py::arg("offset"), py::arg("target"))
      .def_readwrite("node", &InverseTarget::node, "The node carrying the effector point.")
      .def_readwrite("offset", &InverseTarget::offset,
                     "The effector point in the node's frame [m].")
      .def_readwrite("target", &InverseTarget::target, "The target in the world [m].");

  py::class_<InverseStaticsOptions>(m, "InverseStaticsOptions",
                                    "Settings of inverse_statics (sensitivity.h).")
      .def(py::init<>())
      .def_readwrite("statics", &InverseStaticsOptions::statics,
                     "StaticOptions of the equilibrium solves (and their time).")
      .def_readwrite("max_iterations", &InverseStaticsOptions::max_iterations,
                     "Iterations of the optimiser at most (default 100).")
      .def_readwrite("tolerance", &InverseStaticsOptions::tolerance,
                     "Stop when the effectors are this close to their targets [m] (default 1e-10).")
      .def_readwrite("parameter_tolerance", &InverseStaticsOptions::parameter_tolerance,
                     "Relative parameter step below which the optimiser stops (default 1e-14).");

  py::class_<InverseStaticsResult>(m, "InverseStaticsResult", "Result of inverse_statics.")
      .def_readonly("converged", &InverseStaticsResult::converged,
                    "Every target met within the tolerance.")
      .def_readonly("message", &InverseStaticsResult::message,
                    "Why not: an unreachable target (the distance left), a failed equilibrium.")
      .def_readonly("values", &InverseStaticsResult::values,
                    "The parameters' values found, within their bounds.")
      .def_readonly("distance", &InverseStaticsResult::distance,
                    "|effector - target| over all targets [m].")
      .def_readonly("residual", &InverseStaticsResult::residual,
                    "effector - target, three per target [m].")
      .def_readonly("iterations", &InverseStaticsResult::iterations, "Iterations of the optimiser.")
      .def_readonly("equilibrium_solves", &InverseStaticsResult::equilibrium_solves,
                    "Static solves made (Newton re-solves and load-stepping fallbacks).")
      .def_readonly("at_bound", &InverseStaticsResult::at_bound,
                    "A parameter ended on one of its bounds.")
      .def("__repr__", [](const InverseStaticsResult& r) {
        return FormatNumbers("InverseStaticsResult(converged=%g, distance=%.3g m, ",
                             r.converged ? 1.0 : 0.0, r.distance) +
               FormatNumbers("iterations=%g)", r.iterations);
      });

  m.def(
      "inverse_target",
      [](Simulation& s, const std::string& point, const Vec3& target) {
        const OutputPoint& p = s.OutputPointNamed(point);
        if (p.rod < 0) return InverseTarget{p.node, p.offset, target};
        // A point on a rod: the node at its arc length.
        const Rod& rod = s.model().rods[static_cast<std::size_t>(p.rod)];
        double arc = 0.0;
        for (int e = 0; e <= rod.num_elements; ++e) {
          if (std::abs(arc - p.arc_length) <= 1e-9 * std::max(1.0, rod.length))
            return InverseTarget{rod.nodes[static_cast<std::size_t>(e)], Vec3::Zero(), target};
          if (e < rod.num_elements)
            arc += s.model().elements[static_cast<std::size_t>(rod.first_element + e)].length;
        }
        throw InputError("inverse_target: output point '" + point +
                         "' lies between the nodes of its rod (an effector must be on a node)");
      },
      py::arg("simulation"), py::arg("point"), py::arg("target"),
      "inverse_target(simulation, point, target) -> InverseTarget\n\nAn effector at the scene's "
      "output point `point` (outputs.points; on a node) with its world target [m].");

  m.def(
      "static_sensitivity",
      [](Simulation& s, const std::vector<Parameter>& parameters,
         const std::vector<SensitivityOutput>& outputs, SensitivityMode mode,
         const std::optional<StaticOptions>& options) {
        const StaticOptions o = SimulationStatics(s, options);
        StaticSensitivity r =
            CalcStaticSensitivity(s.model(), s.data(), parameters, outputs, mode, o);
        if (!r.ok) RaiseSolverError("static_sensitivity: " + r.message, py::none());
        return r;
      },
      py::arg("simulation"), py::arg("parameters"), py::arg("outputs"),
      py::arg("mode") = SensitivityMode::kForward, py::arg("options") = py::none(),
      R"doc(static_sensitivity(simulation, parameters, outputs, mode=SensitivityMode.FORWARD, options=None) -> StaticSensitivity

The exact derivatives d(outputs)/d(parameters) at the simulation's static equilibrium (call
solve_static first), by the implicit function theorem with the factored exact tangent
(docs/inverse.md). options: the StaticOptions of the solve (default: the scene's, at the current
time). Raises SolverError when the tangent is singular.)doc");

  m.def(
      "inverse_statics",
      [](Simulation& s, const std::vector<Parameter>& parameters, const Eigen::VectorXd& lower,
         const Eigen::VectorXd& upper, const std::vector<InverseTarget>& targets,
         const std::optional<Eigen::VectorXd>& start,
         const std::optional<InverseStaticsOptions>& options) {
        InverseStaticsOptions o = options ? *options : InverseStaticsOptions{};
        if (!options) o.statics = SimulationStatics(s, std::nullopt);
        // By default: zero offsets, and the inputs' current values.
        Eigen::VectorXd x0 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(parameters.size()));
        for (std::size_t i = 0; i < parameters.size(); ++i)
          if (parameters[i].kind == ParameterKind::kInput && parameters[i].index >= 0 &&
              parameters[i].index < s.data().inputs.size())
            x0(static_cast<Eigen::Index>(i)) = s.data().inputs(parameters[i].index);
        if (start) x0 = *start;
        return SolveInverseStatics(s.model(), s.data(), parameters, lower, upper, targets, x0, o);
      },
      py::arg("simulation"), py::arg("parameters"), py::arg("lower"), py::arg("upper"),
      py::arg("targets"), py::arg("start") = py::none(), py::arg("options") = py::none(),
      R"doc(inverse_statics(simulation, parameters, lower, upper, targets, start=None, options=None) -> InverseStaticsResult

The parameter values within [lower, upper] that bring the effector points to their targets
(bounded least squares by Ceres with the exact Jacobian; docs/inverse.md). Values are offsets
from the model's own (a tendon's tension added to its profile), except that an INPUT parameter's
value is the input's value (the simulation's inputs hold the values found). start: the values to
start from (the last solution for a moving target; default: zero offsets, the inputs' current
values). The simulation ends in the equilibrium at
the values found; when the targets are out of reach, converged is False and distance gives how
far the nearest equilibrium within the bounds is.)doc");

  py::class_<CalibrationCase>(m, "CalibrationCase",
                              "A static load case of a calibration: loads (Parameters) with "
                              "their values, and measured points (InverseTarget: node, offset, "
                              "the measured world position as target).")
      .def(py::init([](const std::vector<Parameter>& loads, const Eigen::VectorXd& values,
                       const std::vector<InverseTarget>& measurements) {
             return CalibrationCase{loads, values, measurements};
           }),
           py::arg("loads"), py::arg("load_values"), py::arg("measurements"))
      .def_readwrite("loads", &CalibrationCase::loads, "The parameters that make the case.")
      .def_readwrite("load_values", &CalibrationCase::load_values,
                     "Their values (offsets; an INPUT's value itself).")
      .def_readwrite("measurements", &CalibrationCase::measurements,
                     "Measured points: InverseTarget(node, offset, measured position) [m].");

  py::class_<CalibrationOptions>(m, "CalibrationOptions", "Settings of calibrate (sensitivity.h).")
      .def(py::init<>())
      .def_readwrite("statics", &CalibrationOptions::statics,
                     "StaticOptions of the equilibrium solves.")
      .def_readwrite("max_iterations", &CalibrationOptions::max_iterations,
                     "Iterations of the optimiser at most (default 100).")
      .def_readwrite("parameter_tolerance", &CalibrationOptions::parameter_tolerance,
                     "Relative parameter step below which the optimiser stops (default 1e-12).")
      .def_readwrite("sigma", &CalibrationOptions::sigma,
                     "Measurement noise per coordinate [m]; 0 (default): estimated from the "
                     "residual, |r|^2 / (m - n).")
      .def_readwrite("interval_sigmas", &CalibrationOptions::interval_sigmas,
                     "Half-width of the confidence intervals in standard errors (default 3).");

  py::class_<CalibrationResult>(m, "CalibrationResult", "Result of calibrate.")
      .def_readonly("converged", &CalibrationResult::converged,
                    "The optimiser converged to a least-squares minimum.")
      .def_readonly("message", &CalibrationResult::message, "Why not (empty when converged).")
      .def_readonly("values", &CalibrationResult::values, "The parameters' fitted values.")
      .def_readonly("covariance", &CalibrationResult::covariance,
                    "sigma^2 (J^T J)^-1 at the fit (parameters x parameters).")
      .def_readonly("standard_error", &CalibrationResult::standard_error,
                    "The square roots of the covariance's diagonal.")
      .def_readonly("lower", &CalibrationResult::lower,
                    "values - interval_sigmas * standard_error.")
      .def_readonly("upper", &CalibrationResult::upper,
                    "values + interval_sigmas * standard_error.")
      .def_readonly("sigma", &CalibrationResult::sigma,
                    "The noise level used, given or estimated [m].")
      .def_readonly("residual", &CalibrationResult::residual,
                    "model - measured, three per measurement, cases in order [m].")
      .def_readonly("jacobian", &CalibrationResult::jacobian,
                    "d(residual)/d(values) at the fit (exact).")
      .def_readonly("rms", &CalibrationResult::rms, "Root mean square of the residual [m].")
      .def_readonly("iterations", &CalibrationResult::iterations, "Iterations of the optimiser.")
      .def_readonly("equilibrium_solves", &CalibrationResult::equilibrium_solves,
                    "Static solves made, all cases.");

  m.def(
      "calibrate",
      [](Simulation& s, const std::vector<Parameter>& parameters, const Eigen::VectorXd& start,
         const std::vector<CalibrationCase>& cases,
         const std::optional<CalibrationOptions>& options) {
        CalibrationOptions o = options ? *options : CalibrationOptions{};
        if (!options) o.statics = SimulationStatics(s, std::nullopt);
        return Calibrate(s.model(), parameters, start, cases, o);
      },
      py::arg("simulation"), py::arg("parameters"), py::arg("start"), py::arg("cases"),
      py::arg("options") = py::none(),
      R"doc(calibrate(simulation, parameters, start, cases, options=None) -> CalibrationResult

Fits parameters (stiffness factors, rest strains, masses, tendon offsets, ...; values as
offsets from the
model's own) to measured point positions of several static load cases (CalibrationCase) by
least squares with the exact Jacobian of each equilibrium (Ceres' Levenberg-Marquardt;
docs/inverse.md, Calibration). Returns the fit, its covariance sigma^2 (J^T J)^-1 and
confidence intervals. The simulation's own state is not changed (each case has its own).)doc");

  py::class_<DynamicSensitivityOptions>(m, "DynamicSensitivityOptions",
                                        "Settings of dynamic_sensitivity (sensitivity.h).")
      .def(py::init<>())
      .def_readwrite("dynamics", &DynamicSensitivityOptions::dynamics,
                     "DynamicOptions of the integrator (rho_inf, tolerances).")
      .def_readwrite("step", &DynamicSensitivityOptions::step,
                     "The fixed step [s]; profile breakpoints must fall on step ends.")
      .def_readwrite("steps", &DynamicSensitivityOptions::steps, "Steps of the run.");

  py::class_<DynamicSensitivity>(m, "DynamicSensitivity", "Result of dynamic_sensitivity.")
      .def_readonly("ok", &DynamicSensitivity::ok, "True when the derivatives were computed.")
      .def_readonly("message", &DynamicSensitivity::message, "Why not (empty when ok).")
      .def_readonly("values", &DynamicSensitivity::values,
                    "(steps + 1) x outputs: the outputs at every step end.")
      .def_readonly("outputs", &DynamicSensitivity::outputs,
                    "Forward mode: d y_k(t_n)/dp_j in row n * outputs + k, column j.")
      .def_readonly("objective", &DynamicSensitivity::objective,
                    "J = sum of weights times the outputs over the run.")
      .def_readonly("gradient", &DynamicSensitivity::gradient, "dJ/dp, one per parameter.")
      .def_readonly("restarts", &DynamicSensitivity::restarts,
                    "Restarts at profile breakpoints along the run.");

  m.def(
      "dynamic_sensitivity",
      [](Simulation& s, const std::vector<Parameter>& parameters,
         const std::vector<SensitivityOutput>& outputs, double step, int steps,
         const std::optional<Eigen::MatrixXd>& weights, SensitivityMode mode,
         const std::optional<DynamicOptions>& dynamics) {
        DynamicSensitivityOptions o;
        o.dynamics = dynamics ? *dynamics : s.scene().analysis.dynamic;
        o.dynamics.newton_matrix = NewtonMatrix::kFull;
        o.step = step;
        o.steps = steps;
        Data d = s.data();  // the simulation's own state is left as it is
        DynamicSensitivity r = CalcDynamicSensitivity(
            s.model(), d, parameters, outputs, weights ? *weights : Eigen::MatrixXd(), mode, o);
        if (!r.ok) RaiseSolverError("dynamic_sensitivity: " + r.message, py::none());
        return r;
      },
      py::arg("simulation"), py::arg("parameters"), py::arg("outputs"), py::arg("step"),
      py::arg("steps"), py::arg("weights") = py::none(),
      py::arg("mode") = SensitivityMode::kForward, py::arg("dynamics") = py::none(),
      R"doc(dynamic_sensitivity(simulation, parameters, outputs, step, steps, weights=None, mode=SensitivityMode.FORWARD, dynamics=None) -> DynamicSensitivity

Runs `steps` generalized-alpha steps of size `step` from the simulation's current state (on a
copy: the simulation is not advanced) and differentiates the discrete trajectory of the
outputs (point positions) with respect to the parameters: forward (every output at every step)
or adjoint (the gradient of J = sum of weights[n, k] * y_k(t_n); weights (steps + 1) x outputs,
default: the final outputs summed). Restarts at profile breakpoints are differentiated too.
Models with multipliers (joints, drives, length-driven tendons) under constraints: index3;
ggl (the default of models without rods) and a tendon going slack or taut during the run are
refused. docs/inverse.md, Dynamic sensitivities. Raises SolverError when it cannot.)doc");
}

}  // namespace screwfem::python
