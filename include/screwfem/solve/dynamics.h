// Lie group generalized-alpha time integration of the constrained DAE (docs/architecture.md, "One time step").
//
// Index-3 formulation with the Bottasso-Dopico-Trainelli scaling; configurations update
// through the retraction from the state at the start of the step; Newton on the scaled
// iteration matrix, including the tangent operator T(h dq) on node columns; consistent initial
// accelerations and multipliers; failed steps are retried with halved step sizes.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/LU>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/data.h"
#include "screwfem/model/enum_names.h"
#include "screwfem/solve/common.h"
#include "screwfem/solve/schedule.h"  // ProfileBreakpoints, the breakpoints steps end on
#include "screwfem/solve/stop.h"

namespace screwfem {

struct GeneralizedAlpha {
  double alpha_m, alpha_f, gamma, beta;
  // Chung-Hulbert parameters from the spectral radius at infinity rho in [0, 1].
  static GeneralizedAlpha FromSpectralRadius(double rho_inf);
};

// The options' values and their names (scene key analysis.newton, .predictor, .convergence;
// summary.json; Python NewtonMatrix.SIMPLIFIED, ...): DynamicOptions below says what they do.
enum class NewtonMatrix { kSimplified, kFull };
enum class Predictor { kAdaptive, kLast, kZero };
enum class ConvergenceTest { kEstimated, kMeasured };
enum class ConstraintFormulation { kIndex3, kGgl, kAuto };
template <>
struct EnumNames<NewtonMatrix> {
  static constexpr std::array<EnumName<NewtonMatrix>, 2> kValues = {{
      {NewtonMatrix::kSimplified, "simplified",
       "simplified Newton: the matrix of a step's first iteration, reused by its later ones"},
      {NewtonMatrix::kFull, "full", "full Newton: a new matrix at every iteration"},
  }};
};
template <>
struct EnumNames<Predictor> {
  static constexpr std::array<EnumName<Predictor>, 3> kValues = {{
      {Predictor::kAdaptive, "adaptive",
       "per step, whichever of the two others was closer at the previous step"},
      {Predictor::kLast, "last", "vdot = the last step's"},
      {Predictor::kZero, "zero", "vdot = 0 (Arnold and Bruls)"},
  }};
};
template <>
struct EnumNames<ConvergenceTest> {
  static constexpr std::array<EnumName<ConvergenceTest>, 2> kValues = {{
      {ConvergenceTest::kEstimated, "estimated",
       "also at the iterate after a small correction, estimated from the contraction"},
      {ConvergenceTest::kMeasured, "measured", "at assembled iterates only"},
  }};
};

template <>
struct EnumNames<ConstraintFormulation> {
  static constexpr std::array<EnumName<ConstraintFormulation>, 3> kValues = {{
      {ConstraintFormulation::kIndex3, "index3", "position constraints only (index 3)"},
      {ConstraintFormulation::kGgl, "ggl",
       "stabilised index 2: position and velocity constraints (Gear-Gupta-Leimkuhler)"},
      {ConstraintFormulation::kAuto, "auto",
       "ggl for models without rods (rigid mechanisms), index3 for models with rods"},
  }};
};

// DynamicOptions::perturbed_start: the largest change of the consistent acceleration over the
// next step, relative to the acceleration, for which the start is perturbed (docs/numerics.md,
// "Stabilised index 2": 0.003 on the four-bar and the spring chain, 60 to 1000 on a rod with
// penalty contacts whose axial modes the step does not resolve).
inline constexpr double kPerturbedStartMaxChange = 0.5;

// DynamicOptions::rho_inf chosen by the model (any negative value; docs/numerics.md, "Impacts
// and the contact line search"): kDefaultRhoInf, or kContactRhoInf in a model with contact.
inline constexpr double kAutoRhoInf = -1.0;
inline constexpr double kDefaultRhoInf = 0.9;
// A penalty contact that the step does not resolve (omega_c h >> 1) is a stiff mode that any
// rho_inf near 1 leaves ringing; in its one-sided spring the ringing turns into bounces that
// gain energy (two crossed rod layers, h = 1/240 s: 57 J grew to 194 J at 0.9, never above 57 J
// at 0). 0 annihilates it in a step and keeps the scheme second-order accurate.
inline constexpr double kContactRhoInf = 0.0;

struct DynamicOptions {
  // Spectral radius at infinity in [0, 1] (1: no numerical damping); kAutoRhoInf (negative):
  // kDefaultRhoInf, or kContactRhoInf in a model with contact (InitializeDynamics resolves it
  // into Integrator::options).
  double rho_inf = kAutoRhoInf;
  int max_iterations = 20;  // Newton iterations per step
  int max_halvings = 8;     // a failed step is retried as 2, 4, ... 2^max substeps
  // Converged when the last Newton correction of the positions is below increment_tolerance
  // (translations relative to the model's length scale, rotations and joint coordinates as
  // they are), every constraint |phi| is below constraint_tolerance, and the residual is
  // below residual_tolerance relative to its largest force term (or at its round-off floor).
  double increment_tolerance = 1e-10;
  double constraint_tolerance = 1e-11;
  double residual_tolerance = 1e-8;
  bool use_tangent_operator = true;  // T(h dq) on node columns of the iteration matrix
  // When the iteration matrix is assembled and factorised (docs/numerics.md, "Newton
  // iteration"):
  //   kFull: full Newton (quadratic convergence, one factorisation per iteration);
  //   kSimplified:    simplified Newton: at the first iteration of each step, reused by the
  //                    step's later iterations; when a reused matrix shrinks a correction by
  //                    less than refresh_ratio, the rest of the step is full Newton.
  // Both converge to the same solution (they solve the same residual to the same tolerances).
  NewtonMatrix newton_matrix = NewtonMatrix::kSimplified;
  double refresh_ratio = 0.1;
  // The acceleration vdot_{n+1} the Newton iteration starts from (docs/architecture.md, "One time step"):
  //   kZero:  vdot_{n+1} = 0 (Arnold & Bruls 2007);
  //   kLast:  vdot_{n+1} = vdot_n, an O(h) closer start for smooth motions;
  //   kAdaptive:          per step, whichever of the two was closer at the previous step
  //                       (vdot_n unless undamped high frequencies make vdot alternate).
  Predictor predictor = Predictor::kAdaptive;
  // Where the residual and constraint tests are applied (docs/numerics.md, "Convergence test"):
  //   kMeasured:  at an assembled iterate: the step ends at it, or at its correction when that
  //               correction is below increment_tolerance;
  //   kEstimated: also at the iterate a correction leads to when what that iterate would
  //               have to pass (residual, constraints, the size of its own correction) passes
  //               by estimate: the values at the corrected iterate times the contraction of
  //               the iteration (the larger of |dx_k| / |dx_k-1| and of the ratio of the last
  //               two residuals, at most kMaxEstimateContraction), below kEstimateSafety
  //               times the tolerances. Saves one residual assembly per step where the
  //               quasi-Newton matrix leaves the first corrected residual or correction just
  //               above its tolerance (the GRM: 2.0 instead of 2.1-2.6 iterations per step).
  ConvergenceTest convergence = ConvergenceTest::kEstimated;
  // Restart at the breakpoints of drive and load profiles (docs/numerics.md, "Restarts at
  // breakpoints"; docs/numerics.md, "Restarts at breakpoints"): Step never straddles a breakpoint (it ends a substep
  // exactly on it), the substep that ends on it sees the profiles' left limits, and there
  // vdot, lambda and the auxiliary acceleration are re-initialised from the right limits as at
  // the start (docs/numerics.md, "Restarts at breakpoints"). Without it the auxiliary acceleration carries the old branch
  // across a jump of a prescribed acceleration, and efforts and accelerations ring as
  // (-rho_inf)^k for many steps.
  bool restart_at_breakpoints = true;
  // The auxiliary acceleration after the start and after each restart (docs/numerics.md, "Restarts at breakpoints"
  // step 4, after Arnold, Brüls and Cardona 2015): false: a = vdot (first order in the
  // multipliers for a few steps when alpha_m != alpha_f); true: a = vdot + (alpha_m - alpha_f)
  // (vdot_s - vdot), vdot_s the consistent acceleration at the state predicted one step ahead
  // (q exp(h v + h^2 vdot / 2), v + h vdot, t + h; h = the next step). One more solve of
  // [M B^T; B 0] per start and restart; nothing changes at rho_inf = 1 (alpha_m = alpha_f).
  // Applied only where the step resolves the change of the acceleration: when
  // |vdot_s - vdot| > kPerturbedStartMaxChange |vdot| (scaled infinity norms, as for Newton's
  // increments) the perturbation is a finite difference across modes the step does not
  // resolve (stiff contacts, axial modes of a rod, a tendon going slack), and the step starts
  // from a = vdot instead (counted in Integrator::perturbed_start_skips). Under
  // constraints kAuto it applies to models without rods only (see kAuto).
  bool perturbed_start = true;
  // How the joints' constraints enter the step (docs/numerics.md, "Stabilised index 2"):
  //   kIndex3: phi(q) = 0 at the end of each step (docs/architecture.md, "One time step");
  //   kGgl:    also the velocity constraint B(q) v + d phi/dt = 0, with a second multiplier nu
  //            acting on the configuration update only (docs/numerics.md, "Stabilised index 2", Arnold & Hante
  //            2017): velocities satisfy the constraints to round-off and multipliers
  //            (actuator efforts) are second-order accurate.
  //   kAuto:   (the default) kGgl for a model without rods, kIndex3 for one with rods, decided
  //            by InitializeDynamics (Integrator::options holds the choice): on rigid
  //            mechanisms GGL makes the efforts exact and costs little; on the GRM, dominated
  //            by its soft bodies, it costs 1.5 times the CPU time and moves nothing beyond
  //            the time-discretisation error (docs/numerics.md, "Which formulation is the
  //            default").
  ConstraintFormulation constraints = ConstraintFormulation::kAuto;
  // Contact line search (docs/numerics.md, "Impacts and the contact line search"): in a model
  // with contact (obstacle pairs or contact segments) and under kIndex3, a Newton correction
  // after which the residual is larger (or the assembly fails) is halved, up to
  // kMaxLineSearchHalvings times, before the next correction: a penalty contact activated
  // inside a step otherwise makes the iterates cycle between "deep inside" (a linearisation
  // that overshoots to a gap beyond the onset, where the force and its tangent vanish) and
  // "apart" (a free flight back inside).
  bool line_search = true;
  // Error-controlled steps (AdaptiveStep, AdvanceTo; docs/numerics.md, "Adaptive time steps";
  // docs/numerics.md, "Adaptive time steps"). A step is accepted when the weighted RMS of its local position error
  // estimate C h^2 (a_{n+1} - a_n) is at most 1, each component weighted by
  //   absolute_tolerance (node translations and prismatic coordinates in units of the model's
  //   length scale, rotations and other coordinates in rad) + relative_tolerance |h dq_i|.
  // Steps stay within [min_step, max_step]; initial_step is the first step's size (0: 1e-3 of
  // the span from the start to the first AdaptiveStep's t_limit).
  double absolute_tolerance = 1e-6;
  double relative_tolerance = 1e-4;
  double min_step = 1e-10;
  double max_step = std::numeric_limits<double>::infinity();
  double initial_step = 0.0;
};

// Throws InputError "<owner>.<field>: what is expected" unless every setting is in range:
// rho_inf in [0, 1] or negative (auto), not NaN; absolute and relative tolerances finite and > 0 (relative may be 0);
// 0 < min_step <= max_step (max_step may be infinite); initial_step >= 0 and finite; max_iterations in [1, kMaxNewtonIterations]; max_halvings in
// [0, kMaxHalvings] (a step is never cut below 2^-30 of itself, so a failing step ends);
// tolerances finite and > 0; refresh_ratio in (0, 1); enums one of their values. The one
// check of these settings, for scenes, runs and the Python bindings.
void ValidateDynamicOptions(const DynamicOptions& options, const std::string& owner);

// The spectral radius a run with these options uses on this model (DynamicOptions::rho_inf,
// kAutoRhoInf resolved).
double ResolvedRhoInf(const Model& model, const DynamicOptions& options);

// Largest contraction of two consecutive corrections for which ConvergenceTest::kEstimated
// accepts a step without assembling the residual at its last iterate, and the fraction of
// the tolerances the estimated residual and constraints must stay below.
inline constexpr double kMaxEstimateContraction = 1e-2;
inline constexpr double kEstimateSafety = 0.1;

// Halvings of one Newton correction by the contact line search (DynamicOptions::line_search).
inline constexpr int kMaxLineSearchHalvings = 6;

// Per-simulation integrator workspace (allocated once by InitializeDynamics).
struct Integrator {
  DynamicOptions options;
  GeneralizedAlpha params{};
  Eigen::VectorXd a;  // auxiliary acceleration (nv)
  // Step workspace.
  State q_start;
  Eigen::VectorXd v_start, vdot_start, a_start, lambda_start, dq, a_base;
  // The contact line search (DynamicOptions::line_search): on for this model (contact, index 3),
  // and the last Newton correction (nv + nc; sized only when on).
  bool line_search = false;
  Eigen::VectorXd line_search_dx;
  // Restarts: the breakpoints after the start time (sorted, ProfileBreakpoints) and the
  // workspace of the consistent-acceleration solve (Bdot v by differences, docs/numerics.md, "Restarts at breakpoints").
  std::vector<double> breakpoints;
  Eigen::VectorXd phi_plus, phi_minus, phi_zero, bdot_v, v_work;
  // Length-driven tendons: Data::tendon_slack at the step's start (restored with it); a step
  // that changed it ends with a restart, and a taut tendon whose route stretches at another
  // rate than L_p (caught taut, or L_p's rate jumps at a breakpoint) is caught inelastically.
  std::vector<char> slack_start;
  Eigen::VectorXd tendon_rate_error;  // nc
  // ConstraintFormulation::kGgl: the constraint gradient B_n = B(q_n) of the step's start
  // (dense, nc x nv, redundant rows zero), the velocity constraint B v + dphi/dt of the
  // iterate, the constraint values,
  // the Newmark correction y and the multiplier nu of the step, and the largest |nu| of the run.
  // DynamicOptions::perturbed_start: a start or restart whose auxiliary acceleration is still
  // to be perturbed (it needs the next step's size), and the state saved meanwhile.
  bool perturb_pending = false;
  State perturb_q;
  Eigen::VectorXd perturb_v, perturb_vdot, perturb_lambda;
  // nu of the last two accepted steps: the next step starts from their linear extrapolation
  // (PrepareGglStep), so that its first correction of nu, whose effect on the elastic forces the
  // iteration matrix leaves out, is small.
  Eigen::MatrixXd ggl_b;
  Eigen::VectorXd ggl_bv, ggl_phi, ggl_y, ggl_nu, ggl_dnu, ggl_nu_last, ggl_nu_before;
  // The position-constraint rows of the iteration, B(q) T at the iterate where the matrix was
  // last factorised (dense, nc x nv), and the factorised B T B_n^T of the nu correction.
  Eigen::MatrixXd ggl_bt, ggl_cross;
  Eigen::PartialPivLU<Eigen::MatrixXd> ggl_cross_lu;
  Eigen::VectorXd ggl_rhs;
  std::string why;              // why the last attempt failed (reserved at set-up; Step, AdvanceTo)
  std::vector<char> ggl_slack;  // Data::tendon_slack while B_n is computed (PrepareGglStep)
  // Where B has entries (docs/numerics.md, "Stabilised index 2"): blocks of at most 6 rows of one
  // constraint item over one column group (a node's 6 dofs or a joint's k coordinates), with the
  // tangent operator of that group (an index into Data::node_tangent; -1: none). Every product
  // of the iteration with B_n or B T runs over these blocks only, and B T B_n^T over the pairs
  // of blocks that share a column group (indices into ggl_pattern).
  struct GglBlock {
    int row, rows, col, cols, tangent;
  };
  std::vector<GglBlock> ggl_pattern;
  std::vector<std::pair<int, int>> ggl_pairs;
  double max_nu = 0.0;
  bool use_last_acceleration = true;  // predictor of the next step (DynamicOptions::predictor)
  // Statistics.
  long steps = 0, iterations = 0, halvings = 0;
  long factorizations = 0;          // of the iteration matrix (including failed attempts)
  long retries = 0;                 // steps redone with full Newton from the zero start
  long estimated_convergences = 0;  // steps accepted by ConvergenceTest::kEstimated
  long restarts = 0;                // re-initialisations at profile breakpoints
  long perturbed_start_skips = 0;   // starts and restarts left unperturbed (perturbed_start)
  long tendon_switches = 0;         // steps in which a length-driven tendon went slack or taut
  long tendon_catches = 0;          // inelastic catches of length-driven tendons (CatchTendons)
  long line_search_halvings = 0;    // Newton corrections halved by the contact line search
  int max_iterations_in_step = 0;
  // Step history (every accepted step or substep, fixed or adaptive): the smallest, largest
  // and summed step sizes, and the steps AdaptiveStep rejected (error estimate above the
  // tolerance, or Newton failed).
  double min_h = std::numeric_limits<double>::infinity(), max_h = 0.0, sum_h = 0.0;
  long accepted_substeps = 0;
  long rejected = 0;

  // Error control (AdaptiveStep). The controller's next step size (0 before the first), the
  // error of the last accepted step (for the PI controller; 0: none), whether the next step
  // may grow (not after a rejection), the size of the last accepted step (the auxiliary
  // acceleration is rescaled when the next differs, docs/numerics.md, "Adaptive time steps"), the local error
  // estimate of the last attempted step (nv, velocity layout) and its weighted norm.
  double h_control = 0.0, err_last = 0.0, h_last = 0.0;
  bool allow_growth = true;
  Eigen::VectorXd error, a_accepted;
  double error_norm = 0.0;
  // Dense output of the last accepted AdaptiveStep (InterpolateStep): its start time and size,
  // the configuration at its start, the velocities, accelerations and multipliers at both ends
  // (the end's before a restart), and the step increment h dq.
  double dense_t0 = 0.0, dense_h = 0.0;
  State dense_q0;
  Eigen::VectorXd dense_v0, dense_vdot0, dense_lambda0, dense_v1, dense_vdot1, dense_lambda1,
      dense_d, dense_psi, dense_dpsi;
};

struct StepResult {
  bool ok = false;
  bool interrupted = false;  // ended by a StopRequest (then not ok)
  int iterations = 0;        // Newton iterations of this step (all substeps)
  int substeps = 1;          // 1 unless the step was halved
  std::string message;       // on failure: when and why (allocated only on failure)
};

// Computes consistent initial accelerations and multipliers (docs/numerics.md, "Restarts at breakpoints") at data.time
// from data's configuration and velocities, and allocates the workspace. Profiles use their
// right limit at the start time. Returns false with a message if the saddle-point system is
// singular.
bool InitializeDynamics(const Model& model, Data& data, Integrator& integrator,
                        const DynamicOptions& options, std::string* message = nullptr);

// Re-initialises vdot, lambda and the auxiliary acceleration at data's state and time as
// InitializeDynamics does (profiles at their right limits), keeping the workspace: the restart
// at a breakpoint. No allocation unless it fails (then false with a message naming the time).
bool RestartDynamics(const Model& model, Data& data, Integrator& integrator,
                     std::string* message = nullptr);

// Advances data by h (possibly in halved substeps; with restart_at_breakpoints, a substep
// ends on every profile breakpoint inside the step and the integrator restarts there). On failure data is left at the start of
// the step. `stop` is polled before every attempt at a (sub)step: when it is requested the
// step ends with interrupted = true, data at the end of the last completed substep (the start
// of the step unless the step was halved). No allocation unless it fails or is interrupted.
StepResult Step(const Model& model, Data& data, Integrator& integrator, double h,
                const StopRequest& stop = {});

// ---- error-controlled steps (docs/numerics.md, "Adaptive time steps"; docs/numerics.md, "Adaptive time steps") ----

// The constant C of the local error estimate eps = C h^2 (a_{n+1} - a_n) of generalized-alpha:
// beta - 1/6 + (alpha_m - alpha_f) / 2.
double LocalErrorConstant(const GeneralizedAlpha& p);

// Sizes the workspace of error-controlled steps and of their dense output (Integrator::error,
// a_accepted and the dense_* members: 11 vectors of nv or nc and a copy of the configuration;
// for a rod, 0.55 kB per element) after InitializeDynamics, which leaves it empty so that runs
// with fixed steps do not carry it (docs/limits.md, "Memory"). Allocates once; does nothing
// when it is sized already. Advance calls it for error-controlled steps; a caller of
// AdaptiveStep calls it before the first step, or that step allocates it.
void PrepareAdaptiveSteps(const Model& model, const Data& data, Integrator& integrator);
// Frees that workspace (InitializeDynamics does).
void ReleaseAdaptiveSteps(Integrator& integrator);

// One accepted error-controlled step from data.time, ending at or before t_limit (exactly on
// t_limit when it is within reach, and exactly on the next profile breakpoint, where the
// integrator restarts as Step does). Rejected attempts (estimated error above the tolerance,
// or Newton failure) are retried with a smaller step chosen by the PI controller; below
// options.min_step the step fails with a message naming the time and the worst component.
// After it, InterpolateStep gives the state anywhere inside the step. No allocation unless it
// fails or is interrupted, or its workspace is not sized yet (PrepareAdaptiveSteps).
StepResult AdaptiveStep(const Model& model, Data& data, Integrator& integrator, double t_limit,
                        const StopRequest& stop = {});

// Dense output: sets `out` (a Data of the same model, e.g. a copy of data) to the state at time
// t inside the last accepted AdaptiveStep [t_n, t_n + h] (docs/numerics.md, "Adaptive time steps"): node frames
// H_n exp(psi(theta)) with the cubic Hermite increment psi in the Lie algebra that matches
// H, v at both ends (joint coordinates the same way), velocities T(psi) psi' / h, and
// accelerations and multipliers linear between the step's ends. Pose error O(h^4), velocity
// O(h^3). Branch references are copied from `data` (the step's end). No allocation. Before
// any AdaptiveStep (no workspace, PrepareAdaptiveSteps), `out` gets data's state.
void InterpolateStep(const Model& model, const Data& data, Integrator& integrator, double t,
                     Data& out);

// Everything a dynamic simulation continues from: time, configuration (node frames, joint
// frames and coordinates, the rod elements' rotation branches), velocities, accelerations,
// multipliers, run-time input values and the integrator's auxiliary acceleration and predictor
// choice. Restoring a saved state and stepping repeats the same steps bit for bit (resets,
// reinforcement-learning rollouts).
struct SimulationState {
  double time = 0.0;
  State q;
  std::vector<Vec3> w_ref;
  Eigen::VectorXd v, vdot, lambda, inputs, a;
  Eigen::VectorXd nu_last, nu_before;  // ConstraintFormulation::kGgl: the nu predictor's history
  std::vector<char> tendon_slack;
  std::vector<ContactAnchor> contact_anchors;  // the stick law's history
  bool use_last_acceleration = true;
};
void SaveSimulationState(const Data& data, const Integrator& integrator, SimulationState* state);
// The state must come from Data of the same model (same sizes; InputError otherwise).
void RestoreSimulationState(const SimulationState& state, Data& data, Integrator& integrator);

}  // namespace screwfem
