// Exact sensitivities of a static equilibrium and inverse statics (docs/inverse.md).
//
// At a converged equilibrium R(x; p) = 0 (x: node twists, joint coordinates and multipliers,
// the unknowns of SolveStatic's Newton iteration), the implicit function theorem gives
//   dx/dp = -K^-1 dR/dp,   K = dR/dx the exact static tangent (factored once),
// with the node increments right-trivialised as the Newton updates are (H <- H exp(dx_i)).
// Forward mode solves once per parameter; adjoint mode solves K^T w = c once per output and
// gives dy/dp = -w^T dR/dp for every parameter.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "screwfem/model/data.h"
#include "screwfem/model/enum_names.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/statics.h"

namespace screwfem {

// What a parameter is (Parameter::kind). The residual is affine in every one but a tendon's
// offset at a fixed state, so dR/dp is the difference R(p + 1) - R(p) of one more residual
// assembly, exact up to round-off (docs/inverse.md, "The derivative of the residual"); a
// tendon's tension is clamped at zero, where this is the right derivative. A tendon's offset
// moves its route nonlinearly: dR/dp by a central difference (ParameterIsAffine).
enum class ParameterKind {
  kTendonTension,  // a tension-driven tendon's tension [N] (an offset added to its profile)
  kPointLoad,      // a point load's component: 0-2 force [N], 3-5 moment [N m] (load frame)
  kJointDrive,     // the value of a joint's drive profile [m, rad, N or N m] (an offset)
  kRodStiffness,   // a rod's section stiffness as a factor (1 + p) of one diagonal entry
                   // (component 0-5: EA, GA2, GA3, GJ, EI2, EI3) or of all six (-1)
  kRodRestStrain,  // a rod's uniform rest strain offset, component 0-5 (3: twist, 4, 5:
                   // curvatures [1/m]), added to every element's reference strain d0 / L
  kInput,          // the value of a run-time input (Model::inputs, Data::inputs)
  kActuator,       // the value of an actuator's profile (Model::actuators; a chamber's pressure
                   // [Pa], a muscle's activation, the factor of a rest strain or active stress)
  kRodMass,        // a rod's sectional inertia (mass and rotary inertia per length) as a
                   // factor (1 + p): its weight in statics
  kTendonLength,   // a length-driven tendon's prescribed length [m] (an offset added to its
                   // length profile)
  kTendonOffset,   // component 0-2 of the offsets of a tendon's eyelets on nodes [m] (node
                   // frames; added to each: the route's distance from the rods' centrelines)
};
template <>
struct EnumNames<ParameterKind> {
  static constexpr std::array<EnumName<ParameterKind>, 10> kValues = {{
      {ParameterKind::kTendonTension, "tendon_tension", "a tension-driven tendon's tension"},
      {ParameterKind::kPointLoad, "point_load", "a component of a point load"},
      {ParameterKind::kJointDrive, "joint_drive", "the value of a joint's drive"},
      {ParameterKind::kRodStiffness, "rod_stiffness", "a rod's section stiffness factor"},
      {ParameterKind::kRodRestStrain, "rod_rest_strain", "a rod's uniform rest strain"},
      {ParameterKind::kInput, "input", "the value of a run-time input"},
      {ParameterKind::kActuator, "actuator", "the value of an actuator's profile (a pressure)"},
      {ParameterKind::kRodMass, "rod_mass", "a rod's sectional inertia factor"},
      {ParameterKind::kTendonLength, "tendon_length", "a length-driven tendon's length"},
      {ParameterKind::kTendonOffset, "tendon_offset", "a component of a tendon's eyelet offsets"},
  }};
};

struct Parameter {
  Parameter() = default;
  Parameter(ParameterKind kind_, int index_, int component_ = -1, Profile shape_ = {})
      : kind(kind_), index(index_), component(component_), shape(std::move(shape_)) {}
  ParameterKind kind = ParameterKind::kTendonTension;
  int index = 0;       // the tendon, point load, joint, rod, input or actuator (Model's arrays)
  int component = -1;  // kPointLoad 0-5, kRodStiffness -1 or 0-5, kRodRestStrain 0-5,
                       // kTendonOffset 0-2
  // kTendonTension, kTendonLength, kJointDrive, kActuator: the parameter's value multiplies
  // this profile,
  // added to the item's own (no terms: the constant 1). A knot of a piecewise-linear input
  // profile is a hat-shaped Profile::Table (docs/inverse.md, "Dynamic sensitivities").
  Profile shape;
};

// What an output is (SensitivityOutput::kind).
enum class OutputKind {
  kPointPosition,    // world coordinate `component` (0-2) of a point fixed in a node's frame
  kNodeRotation,     // component (0-2) of a node's rotation increment (node frame, rad)
  kJointCoordinate,  // a joint's coordinate `component` (its own numbering, 0 .. k-1)
  kMultiplier,       // multiplier row `index` (0 .. nc-1)
};
template <>
struct EnumNames<OutputKind> {
  static constexpr std::array<EnumName<OutputKind>, 4> kValues = {{
      {OutputKind::kPointPosition, "point_position", "a world coordinate of a body point"},
      {OutputKind::kNodeRotation, "node_rotation", "a node's rotation increment (its frame)"},
      {OutputKind::kJointCoordinate, "joint_coordinate", "a joint coordinate"},
      {OutputKind::kMultiplier, "multiplier", "a constraint multiplier"},
  }};
};

struct SensitivityOutput {
  OutputKind kind = OutputKind::kPointPosition;
  int index = 0;               // node (kPointPosition, kNodeRotation), joint, or multiplier row
  int component = 0;           // 0-2 (points, rotations), the joint coordinate
  Vec3 offset = Vec3::Zero();  // kPointPosition: the point in the node's frame [m]
};

enum class SensitivityMode { kForward, kAdjoint };
template <>
struct EnumNames<SensitivityMode> {
  static constexpr std::array<EnumName<SensitivityMode>, 2> kValues = {{
      {SensitivityMode::kForward, "forward", "one solve with K per parameter"},
      {SensitivityMode::kAdjoint, "adjoint", "one solve with K^T per output"},
  }};
};

struct StaticSensitivity {
  bool ok = false;
  std::string message;  // why not (empty when ok)
  // d(outputs)/d(parameters): outputs x parameters.
  Eigen::MatrixXd outputs;
  // Forward mode only: the state's derivative, one column per parameter: dx (nv: node twists
  // in the node frames, translation first, and joint coordinates: Retract's layout) and
  // dlambda (nc).
  Eigen::MatrixXd dx, dlambda;
  // The scaled Newton correction -K^-1 R at the state (ScaledIncrementSize): how far data is
  // from the equilibrium the derivatives are for (round-off level at a converged solve).
  double equilibrium_error = 0.0;
};

// A copy of the model whose parameters the sensitivity perturbs one at a time (allocated once,
// reused by every call with the same model).
struct SensitivityWorkspace {
  Model model;
  Eigen::VectorXd r0, rhs;
  Eigen::MatrixXd dr;  // dR/dp, (nv + nc) x parameters
};
SensitivityWorkspace MakeSensitivityWorkspace(const Model& model);

// Throws InputError "<owner>: what is wrong" naming the parameter (kind, index, component)
// when it refers to nothing in the model or to a tendon that is length-driven.
void ValidateParameter(const Model& model, const Parameter& p, const std::string& owner);
void ValidateOutput(const Model& model, const SensitivityOutput& o, const std::string& owner);

// Adds `delta` to a parameter of `model` (as the sensitivity perturbs it; kInput: of
// data.inputs). ResetParameter copies the item back from `original` (for kInput nothing: the
// caller restores data.inputs).
void OffsetParameter(Model& model, Data& data, const Parameter& p, double delta);
void ResetParameter(Model& model, const Model& original, const Parameter& p);
// Whether the residual is affine in the parameter at a fixed state (all kinds but
// kTendonOffset): dR/dp = R(p + 1) - R(p). Otherwise the derivatives take central differences
// with the step ParameterDifferenceStep (1e-6 of the model's length scale).
bool ParameterIsAffine(const Parameter& p);
double ParameterDifferenceStep(const Model& model, const Parameter& p);

// The sensitivities at data's state, an equilibrium of SolveStatic(model, data, options) (at
// its end load factor and time; options.constraint_force_tangent must be true, the default:
// the exact tangent; else ok = false). Assembles and factorises the tangent once, assembles two residuals per
// parameter, and solves once per parameter (forward) or per output (adjoint). data's state is
// unchanged; its workspaces are overwritten. Adjoint mode needs a matrix without off-band
// coupling (no pairs of moving shapes outside the band; else ok = false with the reason).
// Validates parameters and outputs (InputError).
StaticSensitivity CalcStaticSensitivity(const Model& model, Data& data,
                                        const std::vector<Parameter>& parameters,
                                        const std::vector<SensitivityOutput>& outputs,
                                        SensitivityMode mode = SensitivityMode::kForward,
                                        const StaticOptions& options = {},
                                        SensitivityWorkspace* workspace = nullptr);

// ---- Inverse statics (docs/inverse.md, "Inverse statics") ----

// An effector: a point fixed in a node's frame, and its target in the world.
struct InverseTarget {
  int node = 0;
  Vec3 offset = Vec3::Zero();  // in the node's frame [m]
  Vec3 target = Vec3::Zero();  // world [m]
};

struct InverseStaticsOptions {
  StaticOptions statics;               // the equilibrium solves (and their time)
  int max_iterations = 100;            // of the optimiser (Ceres' trust region)
  double tolerance = 1e-10;            // stop when the distance to the targets is below [m]
  double parameter_tolerance = 1e-14;  // relative step of the parameters below which it stops
};

struct InverseStaticsResult {
  bool converged = false;    // every target met within options.tolerance
  std::string message;       // why not: an unreachable target, a failed equilibrium
  Eigen::VectorXd values;    // the parameters' values found (within their bounds)
  double distance = 0.0;     // |effector - target| over all targets (Euclidean) [m]
  Eigen::VectorXd residual;  // effector - target, 3 per target [m]
  int iterations = 0;        // of the optimiser
  int equilibrium_solves = 0;
  bool at_bound = false;  // a parameter ended on one of its bounds
};

// Finds the values of `parameters` within [lower, upper] (one per parameter) that bring the
// effector points to their targets: min 1/2 sum |x_k(p) - target_k|^2 by Ceres' bounded
// trust region (Levenberg-Marquardt) with the exact Jacobian (CalcStaticSensitivity,
// forward). `start` holds the parameters' values to start from (the last solution, for a
// moving target: the warm start); each evaluation brings data from its
// last equilibrium to the one of the new values by Newton (load stepping from the reference
// state when that fails). On return model is the original, data the equilibrium at the
// values found (the nearest reachable configuration when the target is not reachable: then
// converged is false and distance says how far). Parameter values are offsets from the
// model's own (OffsetParameter(model, data, p, values[i]) reproduces the equilibrium), except
// for kInput parameters, whose values are the inputs' values (data.inputs holds them on
// return, so a model whose tensions are inputs agrees with data afterwards).
InverseStaticsResult SolveInverseStatics(const Model& model, Data& data,
                                         const std::vector<Parameter>& parameters,
                                         const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                         const std::vector<InverseTarget>& targets,
                                         const Eigen::VectorXd& start,
                                         const InverseStaticsOptions& options = {});

// ---- Calibration (docs/inverse.md, "Calibration") ----

// One static load case of a calibration: the loads that make it (parameters of the model
// offset by `load_values`, as OffsetParameter applies them; kInput: the inputs' values) and the
// measured world positions of points fixed in node frames (InverseTarget: node, offset, the
// measured position as target).
struct CalibrationCase {
  std::vector<Parameter> loads;
  Eigen::VectorXd load_values;
  std::vector<InverseTarget> measurements;
};

struct CalibrationOptions {
  StaticOptions statics;               // the equilibrium solves
  int max_iterations = 100;            // of the optimiser (Ceres' Levenberg-Marquardt)
  double parameter_tolerance = 1e-12;  // relative parameter step below which it stops
  // The measurement noise's standard deviation per coordinate [m]; 0: estimated from the
  // residual at the fit, s^2 = |r|^2 / (m - n) (m coordinates measured, n parameters).
  double sigma = 0.0;
  double interval_sigmas = 3.0;  // the half-width of the confidence intervals, in standard errors
};

struct CalibrationResult {
  bool converged = false;          // the optimiser converged (a least-squares minimum)
  std::string message;             // why not
  Eigen::VectorXd values;          // the parameters' values fitted
  Eigen::MatrixXd covariance;      // sigma^2 (J^T J)^-1 at the fit (linearised)
  Eigen::VectorXd standard_error;  // sqrt(diag(covariance))
  Eigen::VectorXd lower, upper;    // values -+ interval_sigmas * standard_error
  double sigma = 0.0;              // the noise level used (given, or estimated)
  Eigen::VectorXd residual;        // model - measured, 3 per measurement, cases in order [m]
  Eigen::MatrixXd jacobian;        // d(residual)/d(values) at the fit
  double rms = 0.0;                // sqrt(|residual|^2 / m) [m]
  int iterations = 0;
  int equilibrium_solves = 0;
};

// Fits `parameters` (kRodStiffness, kRodRestStrain, kRodMass, loads, tensions, ...: values as
// offsets, OffsetParameter's meaning, from `start`) to measured positions of several static
// load cases: min 1/2 sum |x_k(p) - measured_k|^2 by Ceres' Levenberg-Marquardt with the exact
// Jacobian (CalcStaticSensitivity per case), each case's equilibrium warm-started from its last
// one. Returns the fit with the covariance sigma^2 (J^T J)^-1 and confidence intervals. Throws
// InputError for invalid parameters, cases or options, or fewer measured coordinates than
// parameters.
CalibrationResult Calibrate(const Model& model, const std::vector<Parameter>& parameters,
                            const Eigen::VectorXd& start, const std::vector<CalibrationCase>& cases,
                            const CalibrationOptions& options = {});

// d(value of the model's item)/d(sensitivity parameter) at an offset `value`: the sensitivity
// perturbs a stiffness or mass factor relative to the current one, (1 + value)(1 + p), so the
// derivative with respect to the offset is the sensitivity divided by (1 + value); 1 for the
// additive kinds.
double ParameterChainFactor(const Parameter& p, double value);

// ---- Sensitivities of dynamic trajectories (docs/inverse.md, "Dynamic sensitivities") ----

struct DynamicSensitivityOptions {
  DynamicOptions dynamics;  // the integrator (rho_inf, tolerances; steps are full Newton)
  double step = 1e-3;       // the fixed step h [s]; profile breakpoints must fall on step ends
  int steps = 100;          // steps from data.time
};

struct DynamicSensitivity {
  bool ok = false;
  std::string message;  // why not (empty when ok)
  // The outputs (point positions: kPointPosition) at every step end t_n = t_0 + n h,
  // n = 0 .. steps: values(n, k) = y_k(t_n).
  Eigen::MatrixXd values;
  // Forward mode: d y_k(t_n) / dp_j in row n * outputs + k, column j.
  Eigen::MatrixXd outputs;
  // The objective J = sum_n sum_k weights(n, k) y_k(t_n) and dJ/dp (both modes; empty
  // weights: J = the outputs at the final time summed).
  double objective = 0.0;
  Eigen::VectorXd gradient;
  int restarts = 0;  // re-initialisations at profile breakpoints along the run
};

// Runs `steps` generalized-alpha steps of size `step` from data's state (data ends at the
// final state; InitializeDynamics is called here, from data's configuration and velocities),
// and differentiates the discrete trajectory with respect to `parameters` (the initial state
// taken independent of them): forward (one sensitivity recursion per parameter, through the
// converged step's exact linearisation) or adjoint (one backward sweep for the objective).
// Restarts at profile breakpoints (DynamicOptions::restart_at_breakpoints) are differentiated
// as well. Supported: models without multipliers (nc = 0: rods, rigid bodies, fixed nodes,
// tension tendons, loads, actuators, contact without friction); dense matrices per step (a
// small model: the adjoint keeps them for the whole run). ok = false with the reason otherwise.
DynamicSensitivity CalcDynamicSensitivity(const Model& model, Data& data,
                                          const std::vector<Parameter>& parameters,
                                          const std::vector<SensitivityOutput>& outputs,
                                          const Eigen::MatrixXd& weights,
                                          SensitivityMode mode = SensitivityMode::kForward,
                                          const DynamicSensitivityOptions& options = {});

}  // namespace screwfem
