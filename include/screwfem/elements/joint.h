// Joints (elements/joint.h): the joint-type table and the joint kernel.
//
// A joint is a relative frame H_J in a Lie subgroup between frame A (node a, or the ground)
// and frame B (node b), placed by constant offsets: H_B C_B = H_A C_A H_J (model.h, Joint).
// Everything that depends on the joint's type is a row of the joint-type table (joint.cpp);
// everything else is one implementation for all types: the constraint and its gradient, the
// spring/damper law on the coordinates, drives, the retraction of the coordinates, energy and
// efforts. The assembly, the build-time redundancy check, the energy and the outputs call these
// functions (docs/architecture.md, "Add a joint type").
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "screwfem/elements/element.h"
#include "screwfem/model/data.h"

namespace screwfem {

// A k x k matrix over a joint's coordinates (k <= 6).
using JointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

// ---- the joint-type table ---------------------------------------------------------------------

// The law of a soft joint's springs (elements/joint.h):
//   kCoordinates:    force K (alpha - rest) on each global coordinate alpha;
//   kLogarithm:      energy 1/2 delta^T K delta with delta = A_J^T log(H_J), for subgroups
//                    without global coordinates (spherical, planar); no rest value;
//   kRelativeMotion: six springs on delta = log(C_A^-1 H_A^-1 H_B C_B), the relative motion of
//                    the two joint frames, acting on the nodes (the free joint: no coordinates,
//                    no constraint rows; JointSpringKind below; docs/numerics.md, "Free joints").
enum class JointSpringLaw { kCoordinates, kLogarithm, kRelativeMotion };

struct JointTypeInfo {
  JointType type;
  const char* name;  // in scene files, outputs and messages
  int dof;           // k, the number of coordinates
  // Global coordinates: H_J is a function of the coordinates alpha (the abelian subgroups, and
  // the universal joint as a product of two one-parameter subgroups); they retract additively
  // and may be driven. Otherwise H_J is stored and retracts by the exponential,
  // H_J <- H_J exp(A_J dx) (docs/architecture.md, "One time step").
  bool global_coordinates;
  bool constrained;  // 6 relative-frame constraint rows (a free joint has none)
  // Scene keys the type uses: `axis` (the plane normal of a planar joint), `axis2` (orthogonal
  // to `axis`), `pitch` [m/rad].
  bool uses_axis, uses_axis2, uses_pitch;
  JointSpringLaw spring_law;
  // A_J (6 x dof) for the unit axis e, the second axis e2 and the pitch (elements/joint.h).
  Mat6X (*basis)(const Vec3& e, const Vec3& e2, double pitch);
  // Global coordinates only: H_J(alpha) and the configuration-dependent basis A_J(alpha), the
  // columns of d H_J = H_J wedge(A_J(alpha) d alpha) (elements/joint.h; the constant A_J for
  // abelian subgroups).
  SE3 (*relative_frame)(const Mat6X& basis, const double* alpha);
  void (*current_basis)(const Mat6X& basis, const double* alpha, Mat6X* out);
};

// The row of a type; the type of a name (nullptr for an unknown name).
const JointTypeInfo& GetJointTypeInfo(JointType type);
const JointTypeInfo* FindJointType(std::string_view name);
// Every type's name, in table order.
std::vector<std::string> JointTypeNameList();
const char* JointTypeName(JointType type);
// Joint basis A_J of a type (elements/joint.h), for axis e (unit) and pitch p. For a planar
// joint e is the plane normal; for universal joints e is the first axis and e2 the second.
// Returns 6 x k.
Mat6X JointBasis(JointType type, const Vec3& e, const Vec3& e2 = Vec3::Zero(), double pitch = 0.0);
bool JointHasGlobalCoordinates(JointType type);
// Springs and dampers a joint carries: one per coordinate, six for kRelativeMotion.
int JointSpringCount(const Joint& joint);

// ---- the joint kernel -------------------------------------------------------------------------

// H_J of a joint in the current state.
SE3 JointRelativeFrame(const Model& model, const Data& data, int joint);
// Configuration-dependent basis: A_J for subgroups, the universal joint's moving basis.
Mat6X JointCurrentBasis(const Model& model, const Data& data, int joint);
// Constraint value phi_J = log(H_J^-1 C_A^-1 H_A^-1 H_B C_B) (6) of a joint.
Vec6 JointConstraint(const Model& model, const Data& data, int joint);

// The constraint gradient of one joint (elements/joint.h) in factored form, for frames H_A, H_B
// (identity for the ground) and H_J:
//   B_A = -T^-1(phi) Ad(G_A),  G_A = C_B^-1 H_B^-1 H_A,
//   B_B =  T^-1(phi) Ad(C_B^-1),
//   B_J = -T^-1(-phi) A_J T_J = -(T^-1(phi) - ad(phi)) A_J T_J,
// T_J the coordinates' tangent operator in dynamics (identity otherwise).
struct JointGradient {
  Vec6 phi = Vec6::Zero();
  Mat6 Tinv = Mat6::Identity();  // T^-1(phi)
  SE3 G_A;
  SE3 Cb_inv;
};
void CalcJointGradient(const Joint& joint, const SE3& H_A, const SE3& H_B, const SE3& H_J,
                       JointGradient* out);
// The same at the model's reference configuration (phi = 0, H_J = I): the build-time rank
// check of the constraints uses it.
void CalcJointReferenceGradient(const Model& model, const Joint& joint, JointGradient* out);
// The blocks B_A, B_B (6 x 6) and B_J (6 x k) of the gradient.
Mat6 JointGradientA(const JointGradient& g);
Mat6 JointGradientB(const JointGradient& g);
Mat6X JointGradientCoordinates(const JointGradient& g, const Mat6X& basis, const JointMatrix& T_J);
// B_A^T lambda and B_B^T lambda as transposed products applied to the vector (no 6 x 6 matrix
// is formed): -Ad(G_A)^T T^-T lambda and Ad(C_B^-1)^T T^-T lambda.
void JointGradientTransposeTimes(const JointGradient& g, const Vec6& lambda, Vec6* bt_a,
                                 Vec6* bt_b);
// B_A x_A + B_B x_B = T^-1(phi) (Ad(C_B^-1) x_B - Ad(G_A) x_A); a null x means that node is
// the ground (its block is absent).
Vec6 JointGradientTimes(const JointGradient& g, const Vec6* x_a, const Vec6* x_b);

// The derivative of the constraint forces B^T lambda of one joint with respect to its
// unknowns at fixed lambda (the geometric stiffness of the constraint, d(B^T lambda)/dq;
// docs/numerics.md, "Exact static tangent"): rows and columns ordered [x_A (6), x_B (6),
// x_J (k)], right-trivialised node increments and coordinate increments as in Retract. With
// mu = T^-T(phi) lambda, D = DTSE3InvT and dphi = B_A x_A + B_B x_B + B_J x_J:
//   d(B_A^T lambda) = -Ad(G_A)^T D(phi, lambda) dphi - Star(Ad(G_A)^T mu) (x_A - Ad(G_A^-1 C_B^-1) x_B)
//   d(B_B^T lambda) =  Ad(C_B^-1)^T D(phi, lambda) dphi
//   d(B_J^T lambda) =  A_J^T D(-phi, lambda) dphi
// plus, for the universal joint, the variation of its moving first axis A_1(alpha_2). `basis`
// is the current basis (JointCurrentBasis).
using JointForceTangent = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 18, 18>;
void CalcJointConstraintForceTangent(const Joint& joint, const JointGradient& g, const Vec6& lambda,
                                     const Mat6X& basis, JointForceTangent* out);

// The derivative Z = d(B v)/dq of one joint's velocity constraint rows at fixed velocities
// (docs/numerics.md, "Stabilised index 2", the (3,1) block of the stabilised index-2 iteration matrix): columns
// ordered [x_A (6), x_B (6), x_J (k)] as in CalcJointConstraintForceTangent. With
// u = Ad(C_B^-1) v_B - Ad(G_A) v_A - A_J v_J, B v = T^-1(phi) u + ad(phi) A_J v_J and
//   Z dx = [dT^-1(phi)/dphi . dphi] u + T^-1(phi) Ad(G_A) ad(v_A) (x_A - Ad(G_A^-1 C_B^-1) x_B)
//          - ad(A_J v_J) dphi,   dphi = B_A x_A + B_B x_B + B_J x_J,
// plus, for the universal joint, the variation of its moving first axis A_1(alpha_2). A null
// v_a (v_b) is a node at rest (the ground); v_j holds the k coordinate rates.
using JointVelocityTangent = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 18>;
void CalcJointVelocityConstraintTangent(const Joint& joint, const JointGradient& g, const Vec6* v_a,
                                        const Vec6* v_b,
                                        const Eigen::Ref<const Eigen::VectorXd>& v_j,
                                        const Mat6X& basis, JointVelocityTangent* out);

// The spring-damper law of global coordinate c of a joint (elements/joint.h, spring law
// kCoordinates): the generalised force on the coordinate's residual row
//   f = K_c (alpha - rest) + D_c (alpha_dot - rest_rate)   (D_c in dynamics only),
// with rest = rest_c and rest_rate = 0, except on the coordinate of a series-elastic drive,
// whose rest moves to rest_c + lambda q(t) at rate lambda dq/dt (`drive`: q(t) and dq/dt, the
// drive profile's value; lambda the load factor). The series-elastic drive's law: one
// definition behind the kernel (CalcJointCoordinateTerms) and its effort -f
// (JointDriveEffort, load factor 1, with damping).
struct JointCoordinateSpring {
  double force = 0.0;      // f
  double rest = 0.0;       // the rest it pulls towards
  double rest_rate = 0.0;  // and its rate
};
JointCoordinateSpring JointCoordinateSpringLaw(const Joint& joint, int c, double alpha,
                                               double alpha_dot, const ProfileValue& drive,
                                               double load_factor, bool dynamics);

// Springs, dampers and the drive on a joint's coordinates (elements/joint.h): the
// generalised force f (k) that enters the coordinate rows of the residual, and its derivatives
// K_q = df/dalpha and D_q = df/d(alpha_dot) (top-left k x k). `dynamics` adds the dampers;
// `load_factor` scales drives (statics). A prescribed drive adds its multiplier lambda to its
// coordinate (B_act^T lambda_act) and gives its constraint value alpha - q(t) in
// `drive_constraint`. term_scale: the largest spring term cancelling inside f (the round-off
// floor of the convergence test).
struct JointCoordinateTerms {
  Vec6 force = Vec6::Zero();
  Mat6 stiffness = Mat6::Zero();
  Mat6 damping = Mat6::Zero();
  double drive_constraint = 0.0;
  double term_scale = 0.0;
};
void CalcJointCoordinateTerms(const Model& model, const Data& data, int joint, double time,
                              double load_factor, bool dynamics, bool tangent,
                              JointCoordinateTerms* out);

// Tangent operator of the coordinates of a joint without global coordinates, whose H_J
// retracts by H_J exp(A_J x) with x = h dq_J (docs/architecture.md, "One time step"): T_k = A_J^T T(A_J x) A_J in the
// top-left k x k of *out (identity elsewhere). A_J spans a subalgebra with orthonormal columns.
void CalcJointCoordinateTangent(const Joint& joint, const Eigen::Ref<const Eigen::VectorXd>& x,
                                Mat6* out);
// The retraction of a joint's coordinates by dx (k): alpha += dx, and H_J <- H_J exp(A_J dx)
// for joints without global coordinates.
void RetractJoint(const Model& model, Data& data, int joint,
                  const Eigen::Ref<const Eigen::VectorXd>& dx);

// Largest |phi| over all constraint rows at `time`: the relative-frame constraints of the
// joints (JointConstraint) and the prescribed drives alpha - q(t) (docs/theory.md §4.4). The
// value MaxConstraintViolation (assemble.h) computes from a whole residual assembly, for one
// logarithm per joint.
double CalcMaxJointConstraint(const Model& model, const Data& data, double time);

// Deflection of a joint with JointSpringLaw::kRelativeMotion (the free joint):
// delta = log(C_A^-1 H_A^-1 H_B C_B), the principal logarithm its springs act on.
Vec6 CalcFreeJointDeflection(const Model& model, const Data& data, int joint);

// The springs and dampers of joints with JointSpringLaw::kRelativeMotion, as an element kind
// (elements/element.h) on the joint's two nodes: delta varies like a rod element's relative
// motion between the joint frames, d delta = P(delta) E [dh_A; dh_B] with
// E = diag(Ad(C_A^-1), Ad(C_B^-1)) and G = P E (elements/rod.h). Force G^T (K delta + D G
// eta_AB); stiffness G^T K G + E^T [D(-delta, s); D(delta, s)] P E with s = K delta
// (docs/theory.md §2.4); damping block G^T D G (its configuration derivative omitted, as for
// rods). Energy 1/2 delta^T K delta.
struct JointSpringKind {
  static constexpr int kNodes = 2;
  using Item = int;  // joint index
  template <class F>
  static void ForEach(const Model& model, F&& f) {
    for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
      const Joint& j = model.joints[jj];
      if (GetJointTypeInfo(j.type).spring_law != JointSpringLaw::kRelativeMotion) continue;
      const int nodes[2] = {j.node_a, j.node_b};
      f(static_cast<int>(jj), nodes);
    }
  }
  static bool Calc(const Model& model, const Data& data, const Item& joint,
                   const NodeMotion<2>& motion, const KernelOptions& options,
                   ElementTerms<2>* terms);
  static void AddEnergy(const Model& model, const Data& data, const Item& joint, Energy* energy);
};

// Effort of a joint's drive: the generalised force the drive applies along its coordinate
// (actuator torque or force; for a series-elastic drive the spring-damper force).
double JointDriveEffort(const Model& model, const Data& data, int joint);
// The generalised force on coordinate c of a joint in the current state: the drive's effort on
// a driven coordinate, otherwise minus the spring-damper force (the force the joint's soft
// elements apply along the coordinate).
double JointCoordinateEffort(const Model& model, const Data& data, int joint, int c);
// Energy stored in a joint's springs [J] (towards their rest, incl. series-elastic drives).
double JointSpringEnergy(const Model& model, const Data& data, int joint);

}  // namespace screwfem
