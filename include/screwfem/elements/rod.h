// The two-node helical Cosserat rod element (elements/rod.h): a stateless kernel.
#pragma once

#include "screwfem/elements/element.h"
#include "screwfem/elements/quadrature.h"
#include "screwfem/lie/se3.h"
#include "screwfem/model/model.h"

namespace screwfem {

using Mat6x12 = Eigen::Matrix<double, 6, 12>;

// The rod's Gauss rule: 3 points (elements/quadrature.h) for inertia (option A) and
// distributed loads (elements/rod.h).
inline constexpr int kRodGaussPoints = kGauss3Points;
inline constexpr const double (&kRodGaussXi)[kRodGaussPoints] = kGauss3Xi;
inline constexpr const double (&kRodGaussW)[kRodGaussPoints] = kGauss3W;

// Relative motion d = log(H_A^-1 H_B) on the branch closest to w_ref (elements/rod.h).
Vec6 CalcRodRelativeMotion(const SE3& H_A, const SE3& H_B, const Vec3& w_ref);

// P(d) = [-T^-1(-d)  T^-1(d)]: delta d = P [dh_A; dh_B] and d_dot = P [eta_A; eta_B]
// (docs/theory.md §2.3).
Mat6x12 CalcRodP(const Vec6& d);

// Exact velocity / virtual-displacement interpolation of the helical element
// (docs/theory.md §2.5): eta(xi) = N(xi, d) [eta_A; eta_B], xi in [0, 1].
Mat6x12 CalcRodN(double xi, const Vec6& d);

// The same interpolation applied at the rod's Gauss points without forming N (for the energy
// and momentum outputs): with d_dot = P(d) eta_AB,
//   eta(xi) = Ad(exp(-xi d)) eta_A + xi T(xi d) d_dot,
// which is N(xi, d) eta_AB since T^-1(d) eta_B - T^-1(-d) eta_A = P eta_AB. eta[i] at xi_i;
// G (optional) receives the section frames relative to node A, exp(xi_i d).
void CalcRodGaussVelocities(const Vec6& d, const Vec12& eta_ab, Vec6 (&eta)[kRodGaussPoints],
                            SE3 (*G)[kRodGaussPoints] = nullptr);

// What the kernels of one element share, computed once per element and assembly (the
// kernels below that take it are the ones the assembly calls; the overloads taking H or d
// compute it themselves):
//  * d on the current branch, T^-1(d) and P(d) = [-T^-1(-d)  T^-1(d)], with
//    T^-1(-d) = T^-1(d) - ad(d) (the series of T^-1 is even but for its ad/2 term;
//    docs/theory.md §1.3);
//  * at the Gauss points xi_i (kRodGaussXi), T(xi_i d) and, for tangents,
//    N_B(xi_i) = xi_i T(xi_i d) T^-1(d). The interpolation of docs/theory.md §2.5 is
//    N = [I - N_B, N_B]:
//    its halves sum to Ad(exp(-X)) + xi T(X) ad(d) = Ad(exp(-X)) + T(X) ad(X) = I (X = xi d,
//    T(X) ad(X) = I - exp(-ad(X)) for the right tangent), so eta(xi) = eta_A + N_B (eta_B - eta_A).
struct RodGeometry {
  Vec6 d;
  TSeries series;  // series coefficients at |w| of d
  Mat6 Ti;         // T^-1(d)
  Mat6x12 P;
  bool gauss_points = false;           // T below is set
  bool tangents = false;               // NB below is set
  TSeries series_gp[kRodGaussPoints];  // at xi_i |w|
  Mat6 T[kRodGaussPoints];             // T(xi_i d)
  Mat6 NB[kRodGaussPoints];            // N_B(xi_i)
};
// From d; `gauss_points` adds T(xi_i d), `tangents` also N_B(xi_i).
void CalcRodGeometry(const Vec6& d, bool gauss_points, bool tangents, RodGeometry* out);
// The same with d = CalcRodRelativeMotion(H_A, H_B, w_ref) (one series evaluation for both).
void CalcRodGeometry(const SE3& H_A, const SE3& H_B, const Vec3& w_ref, bool gauss_points,
                     bool tangents, RodGeometry* out);

// The actuation of one element at one time (docs/numerics.md, "Active stress and rest strain"): a rest-strain change eps0
// and an active stress sigma_a, section frame, constant over the element.
struct RodActuation {
  Vec6 rest_strain = Vec6::Zero();    // eps0
  Vec6 active_stress = Vec6::Zero();  // sigma_a [N, N m]
};

// The actuation of element `element` at `time`: eps0 and sigma_a summed over its actuators
// (model.h, Actuator), each unit vector times ActuatorValue times load_factor (statics scales
// actuation like loads). False, with both zero, when the element has no actuators.
bool CalcRodActuation(const Model& model, const Data& data, int element, double time,
                      double load_factor, RodActuation* out);
// An actuator's profile value at `time` (run-time inputs through EvalProfile; a muscle's
// activation clamped to [0, 1]).
double ActuatorValue(const Actuator& actuator, double time, const Data& data);

// The rod's constitutive law, its one definition (docs/numerics.md, "Active stress and rest
// strain"): an element whose relative motion is d has the strain eps = (d - d0) / L, the stress
// sigma = K eps - (K eps0 + sigma_a) and the energy L/2 (eps - eps0)^T K (eps - eps0) -
// L eps^T sigma_a, with the rest-strain change eps0 and active stress sigma_a of `actuation`
// (zero without). The kernels, the energy and the stress outputs all evaluate it here.
struct RodLaw {
  Vec6 strain;          // eps
  Vec6 stress;          // sigma (section frame: N, V2, V3, T, M2, M3)
  Vec6 elastic_stress;  // K (eps - eps0): the part the elastic strain carries
  double energy = 0.0;  // with `energy` only
};
void CalcRodLaw(const RodElement& element, const Section& section, const Vec6& d,
                const RodActuation* actuation, bool energy, RodLaw* out);

struct RodInternal {
  Vec6 d;               // relative motion on the current branch
  Vec6 strain;          // d / L - f0
  Vec6 stress;          // sigma = K (strain - eps0) - sigma_a (section frame: N, V2, V3, T, M2, M3)
  Vec6 elastic_stress;  // K (strain - eps0)
  double energy;        // L/2 (strain - eps0)^T K (strain - eps0) - L strain^T sigma_a
  Vec12 force;          // g_int = P^T sigma  (node A then node B, node-frame components)
  Mat12 stiffness;      // d g_int / d[dh_A; dh_B] with the geometric term (docs/theory.md §2.4)
};

// Internal forces and consistent tangent of one element (docs/theory.md §2.4), with actuation
// when given
// (docs/numerics.md, "Active stress and rest strain": the same tangent formula with the total sigma; actuation frozen).
void CalcRodInternal(const RodElement& element, const Section& section, const SE3& H_A,
                     const SE3& H_B, const Vec3& w_ref, RodInternal* out,
                     const RodActuation* actuation = nullptr);
// The same from the element's geometry (out->d is copied from it); without `tangent` the
// stiffness is left unset.
void CalcRodInternal(const RodElement& element, const Section& section, const RodGeometry& geometry,
                     bool tangent, RodInternal* out, const RodActuation* actuation = nullptr);

// Directional derivative of N(xi, d) along dd: d/de N(xi, d + e dd) (for d/dt N, dd = d_dot).
Mat6x12 CalcRodNDirectional(double xi, const Vec6& d, const Vec6& dd);

// Velocity-dependent forces of one element (docs/numerics.md, "Rod inertia"): inertia and damping, with the
// blocks of the iteration matrix. Inputs are the relative motion d on the current branch, the
// node body velocities eta_AB = [eta_A; eta_B] and accelerations eta_dot_AB (zero for a fixed
// node). Every kernel is fixed-size and allocation-free.
struct RodInertiaTerms {
  Vec12 force = Vec12::Zero();       // g_ine (node A then node B, node-frame components) [N, N m]
  Mat12 mass = Mat12::Zero();        // M_e = d g_ine / d eta_dot_AB (exact for both options)
  Mat12 gyroscopic = Mat12::Zero();  // C_t, the eta_AB block of the iteration matrix (see below)
  double kinetic_energy = 0.0;       // 1/2 eta_AB^T M_e eta_AB [J]
};

// Option A (RodInertia::kExact): the exact velocity field of the helical interpolation,
//   eta(xi) = N(xi, d) eta_AB,  eta_dot(xi) = N eta_dot_AB + (dN/dt) eta_AB,
//   g_ine = L int_0^1 N^T (M eta_dot - ad(eta)^T M eta) dxi,   M_e(d) = L int N^T M N dxi,
// dN/dt = directional derivative of N in d along d_dot = P(d) eta_AB; 3-point Gauss-Legendre.
// The residual is exact: the power eta_AB^T g_ine is the time derivative of the kinetic energy
// of the same quadrature, and for a free element the world resultant of g_ine is the rate of
// the linear and angular momentum of the exact field.
// Tangent (a documented quasi-Newton choice, docs/numerics.md, "Rod inertia"): `mass` is exact, `gyroscopic`
// is the option-B form evaluated with the exact N and the exact Gauss-point velocities,
//   C_t = -L int N^T (ad(eta)^T M + Star(M eta)) N dxi,
// which omits d[(dN/dt) eta_AB]/d eta_AB (the same order in |eta| as C_t itself) and
// d g_ine / dq (no configuration term). In the iteration matrix beta' M_e + gamma' C_t the
// omitted parts are O(h |eta|) and O(h^2) relative to beta' M_e, so Newton converges linearly
// with a rate that vanishes as h -> 0 (tests/elements/rod_inertia_test.cpp measures both).
void CalcRodInertiaExact(const RodElement& element, const Section& section, const Vec6& d,
                         const Vec12& eta_ab, const Vec12& eta_dot_ab, RodInertiaTerms* out);
// The same from the element's geometry (with Gauss points; with N_B when `tangent`). Without
// `tangent`, mass and gyroscopic are left unset.
void CalcRodInertiaExact(const RodElement& element, const Section& section,
                         const RodGeometry& geometry, const Vec12& eta_ab, const Vec12& eta_dot_ab,
                         bool tangent, RodInertiaTerms* out);

// The force alone (what a residual-only assembly needs).
void CalcRodInertiaExactForce(const RodElement& element, const Section& section,
                              const RodGeometry& geometry, const Vec12& eta_ab,
                              const Vec12& eta_dot_ab, Vec12* force);
// The same force, with the iteration-matrix block c_mass M_e + c_gyro C_t in place of the two
// matrices (what the assembly scatters): one set of Gauss-point products instead of two.
void CalcRodInertiaExactMatrix(const RodElement& element, const Section& section,
                               const RodGeometry& geometry, const Vec12& eta_ab,
                               const Vec12& eta_dot_ab, double c_mass, double c_gyro, Vec12* force,
                               Mat12* matrix);

// Option B (RodInertia::kConstant): velocities and virtual displacements interpolated linearly
// in the inertia term only, N = [(1 - xi) I, xi I]: M_e = L [M/3 M/6; M/6 M/3] constant,
// g_ine = M_e eta_dot_AB - L int N^T ad(eta)^T M eta dxi (2-point Gauss, exact), and the
// tangents are exact: `gyroscopic` = d g_ine / d eta_AB, d g_ine / dq = 0.
void CalcRodInertiaConstant(const RodElement& element, const Section& section, const Vec12& eta_ab,
                            const Vec12& eta_dot_ab, RodInertiaTerms* out);

// The model's choice of the two.
void CalcRodInertia(RodInertia option, const RodElement& element, const Section& section,
                    const Vec6& d, const Vec12& eta_ab, const Vec12& eta_dot_ab,
                    RodInertiaTerms* out);
void CalcRodInertia(RodInertia option, const RodElement& element, const Section& section,
                    const RodGeometry& geometry, const Vec12& eta_ab, const Vec12& eta_dot_ab,
                    bool tangent, RodInertiaTerms* out);

// Kinetic energy 1/2 eta_AB^T M_e eta_AB of one element for either option [J] (the same
// quadrature as the inertia forces, so that the power of g_ine is its exact time derivative).
double CalcRodKineticEnergy(RodInertia option, const RodElement& element, const Section& section,
                            const Vec6& d, const Vec12& eta_ab);
// Option A's, from the section velocities at the Gauss points (CalcRodGaussVelocities).
double CalcRodKineticEnergyExact(const RodElement& element, const Section& section,
                                 const Vec6 (&eta)[kRodGaussPoints]);

// Damping forces of one element, added to *force and their eta_AB-derivative to *damping:
//  * strain-rate (material) damping, sigma_v = D_s d_dot / L with D_s = section.damping +
//    section.rayleigh_stiffness * section.stiffness: force P^T sigma_v, tangent
//    (1/L) P^T diag(D_s) P. The stiffness-proportional Rayleigh term is thus a_K times the
//    material part of K_t (objective: zero for rigid motions; equal to a_K K at an unstressed
//    state);
//  * mass-proportional Rayleigh damping a_M M_e eta_AB (tangent a_M M_e), with M_e = `mass`
//    of the element's inertia option. It acts on absolute velocities: it also damps rigid-body
//    motion (like a drag), so it does not conserve momentum.
// The configuration derivatives of both are omitted from the iteration matrix.
void AddRodDamping(const RodElement& element, const Section& section, const Vec6& d,
                   const Vec12& eta_ab, const Mat12& mass, Vec12* force, Mat12* damping);
// The same with P(d) given; damping may be null (no tangent).
void AddRodDamping(const RodElement& element, const Section& section, const Mat6x12& P,
                   const Vec12& eta_ab, const Mat12& mass, Vec12* force, Mat12* damping);

// A force and a moment acting on the section at xi, consistent with the exact virtual
// displacement field: g += weight * N(xi, d)^T F, with F = [R(xi)^T f; R(xi)^T m] for a world
// (dead) load or F = [f; m] for a body (follower) load, R(xi) the section rotation of
// H_A exp(xi d). tangent += -d(weight N^T F)/d[dh_A; dh_B] (exact: the residual holds -g).
// Rigid translations of the element do exactly the virtual work of the applied force, so
// linear momentum balance is exact and dead loads are conservative.
void AddRodSectionLoad(double xi, double weight, const SE3& H_A, const Vec6& d, LoadFrame frame,
                       const Vec3& force, const Vec3& moment, Vec12* g, Mat12* tangent);

// The derivative of N(xi, d)^T F in d at fixed F (12 x 6): d(N^T F)/d[dh_A; dh_B] at fixed F
// is this times P(d) (the first part of AddRodSectionLoad's tangent; tendon eyelets between
// nodes, elements/tendon.h).
Eigen::Matrix<double, 12, 6> CalcRodNTransposeDerivative(double xi, const Vec6& d, const Vec6& F);

// A dead force f_w per unit length (e.g. rho A g) over the element, 3-point Gauss:
// g and the tangent of -g (both overwritten). The same as the section loads
// L w_i N_i^T [R_i^T f_w; 0] at the Gauss points (AddRodSectionLoad), computed from the
// potential V = -L sum_i w_i f_w . x(xi_i) of the load: the centreline x(xi) = x_A + R_A J(xi w)
// xi u is linear in u, so g and its tangent need J(v) = TSO3(v)^T and its first and second
// derivatives at the Gauss points, in 3 x 3 blocks, instead of 6 x 6 products (rod.cpp).
void CalcRodDistributedDeadForce(const RodElement& element, const SE3& H_A, const Vec6& d,
                                 const Vec3& f_w, Vec12* g, Mat12* tangent);
// The same from the element's geometry (d, T^-1(d) and P; the Gauss-point operators are not
// used), added to *g and *tangent (tangent may be null).
void AddRodDistributedDeadForce(const RodElement& element, const RodGeometry& geometry,
                                const SE3& H_A, const Vec3& f_w, Vec12* g, Mat12* tangent);

// The conservative part of one element in one pass, as the assembly calls it: internal forces
// minus the distributed dead force f_w per unit length (f_w may be zero),
//   force = g_int - g_dead,
// and, with `stiffness`, its tangent (CalcRodInternal's plus AddRodDistributedDeadForce's),
// right-multiplied by blockdiag(T_A, T_B) when both are given (the node tangent operators of
// the dynamic iteration). The two share one geometric term D(d, sigma - L s), s the dead
// force's d-gradient, and one product with P (tests/elements/rod_load_test.cpp compares).
// With `actuation`, sigma = K (strain - eps0) - sigma_a throughout (docs/numerics.md, "Active stress and rest strain").
void CalcRodConservative(const RodElement& element, const Section& section,
                         const RodGeometry& geometry, const SE3& H_A, const Vec3& f_w,
                         const Mat6* T_A, const Mat6* T_B, Vec12* force, Mat12* stiffness,
                         const RodActuation* actuation = nullptr);

// ---- the rod element as an element kind (elements/element.h) --------------------------------

// One helical element: internal forces, the weight of the rod (gravity times rhoA), inertia
// (the model's option) and damping, with the element matrix. Calc fails when the
// element's relative rotation leaves the admissible range (model.max_element_rotation)
// or its forces are not finite (terms->failure: the rotation).
struct RodElementKind {
  static constexpr int kNodes = 2;
  using Item = int;  // global element index
  // Calc runs on the threads of the parallel assembly (element.h, kParallel), which takes the
  // items by index.
  static constexpr bool kParallel = true;
  static int ItemCount(const Model& model) { return static_cast<int>(model.elements.size()); }
  static void ItemNodes(const Model& model, int e, int (&nodes)[2]) {
    nodes[0] = model.elements[static_cast<std::size_t>(e)].node_a;
    nodes[1] = model.elements[static_cast<std::size_t>(e)].node_b;
  }
  // The actuators' profiles (pressure, activation, strain: CalcRodActuation).
  template <class F>
  static void ForEachProfile(const Model& model, F&& f) {
    for (const Actuator& a : model.actuators) f(a.profile);
  }
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t e = 0; e < model.elements.size(); ++e) {
      const int nodes[2] = {model.elements[e].node_a, model.elements[e].node_b};
      f(static_cast<int>(e), nodes);
    }
  }
  static bool Calc(const Model& model, const Data& data, const Item& element,
                   const NodeMotion<2>& motion, const KernelOptions& options,
                   ElementTerms<2>* terms);
  // Strain energy (with the actuation at data.time: L/2 (eps - eps0)^T K (eps - eps0) -
  // L eps^T sigma_a), kinetic energy of the model's inertia option and the gravity potential
  // of the element (3-point Gauss over the exact centreline).
  static void AddEnergy(const Model& model, const Data& data, const Item& element, Energy* energy);
};

}  // namespace screwfem
