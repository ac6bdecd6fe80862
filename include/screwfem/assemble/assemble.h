// Assembly of the global residual and iteration matrix (docs/architecture.md, "One time step").
//
// Residual (global order, data.residual):
//   rows [0, nv):       s_R * ( g_ine + g_int - g_ext + B^T lambda )
//   rows [nv, nv + nc): s_C * phi
// Iteration matrix (permuted, banded, data.matrix), for unknowns (dx, dmu) with
// dlambda = s_L dmu:
//   [ s_R (c_M M + c_C C + c_K K T)    s_R s_L B^T ]
//   [ s_C B T                          0           ]
// with M = dr/d(vdot), C = dr/dv, K = dr/d(dh) (right-trivialised), T = data.node_tangent
// (identity in statics). Statics: c_M = c_C = 0, c_K = 1, s_R = 1, s_C = s_L = k.
// Dynamics (Bottasso scaling): c_M = beta', c_C = gamma', c_K = 1, s_R = beta h^2, s_C = 1,
// s_L = 1 / (beta h^2).
#pragma once

#include "screwfem/elements/constraint.h"
#include "screwfem/elements/element.h"
#include "screwfem/elements/joint.h"
#include "screwfem/model/data.h"
#include "screwfem/model/model.h"

namespace screwfem {

// AssemblyOptions (what an assembly computes and how it scales): elements/constraint.h.

// model.pattern_last widened by the blocks of d(B^T lambda)/dq (each constrained joint couples
// its nodes and coordinates with each other), and the half-bandwidth it needs.
std::vector<int> ConstraintForceTangentPattern(const Model& model, int* bandwidth);
// The same blocks for the sparse LU (Model::sparse_solver): every pair of column blocks of each
// joint's rows, appended to `blocks` (permuted positions).
void AddConstraintForceTangentBlocks(const Model& model, std::vector<SparseLU::Block>* blocks);

// The sparse LU's pattern for the contact pairs of data.shape_pairs (Model::sparse_solver):
// every two nodes of a pair whose blocks the base pattern (Model::sparse_pattern) does not hold
// make a coupling (SparseLU::SetCouplings), so the iteration matrix is exact for any number of
// pairs. Allocates nothing while the list of couplings is one met before (the last
// kCachedPatterns); a new list is analysed (allocates). Called by Assemble with the matrix.
void SelectSparsePattern(const Model& model, Data& data);

// Evaluates residual (and matrix). Returns false if an element's relative rotation left the
// admissible range (data.failed_element, data.failed_rotation say which and how far).
bool Assemble(const Model& model, Data& data, const AssemblyOptions& options);

// The threads of the assembly (docs/architecture.md, "Parallel assembly"): the rod elements'
// kernels run on a pool of threads in chunks of kParallelChunk elements, scattered in element
// order, so that the results are the same doubles with any number of threads.
// kAutoThreads: every available core for a model of at least kParallelMinElements rod
// elements, one thread below (where the threads do not pay; bench/RESULTS.md).
inline constexpr int kAutoThreads = 0;
inline constexpr int kParallelMinElements = 1000;
inline constexpr int kParallelChunk = 256;
inline constexpr int kMaxAssemblyThreads = 256;
// The threads to use for a request (>= 1, or kAutoThreads); at most kMaxAssemblyThreads.
int ResolveAssemblyThreads(const Model& model, int requested);
// Starts data's pool of threads (1: the serial assembly, no pool). Allocates: call at set-up,
// not inside a step. A copy of the Data starts a pool of its own.
void SetAssemblyThreads(Data& data, int threads);

// Snapshot of the configuration (for restoring after a failed step).
struct State {
  std::vector<SE3> H, HJ;
  Eigen::VectorXd q_joint;
};
void SaveState(const Data& data, State* state);
void RestoreState(const State& state, Data& data);

// The retraction, the only place where configurations change: H_i <- H_i exp(dx_i) for every
// free node, alpha <- alpha + dx_J for joint coordinates (H_J <- H_J exp(A_J dx_J) for
// spherical, planar and free joints). dx has the velocity layout (size >= nv).
void Retract(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& dx);

// Size of a Newton correction dx (velocity layout): translations relative to the model's
// length scale, rotations and joint coordinates as they are (infinity norm).
double ScaledIncrementSize(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& dx);

// Moves every element's branch reference to its current relative rotation (call after an
// accepted step; elements/rod.h).
void UpdateBranchReferences(const Model& model, Data& data);

// Energies of the current state (for balances and tests): the sum of the element kinds'
// energies and the joints' springs.
Energy CalcEnergy(const Model& model, const Data& data);

// The constraint gradient B(q) (nc x nv, elements/joint.h; joint coordinates without tangent
// operator) at data's configuration times x (velocity layout): out = B x (nc). Rows held at
// zero (ForEachHeldRow) are zero. No allocation.
void CalcConstraintGradientTimes(const Model& model, const Data& data,
                                 const Eigen::Ref<const Eigen::VectorXd>& x,
                                 Eigen::Ref<Eigen::VectorXd> out);
// The velocity constraint B(q) v + d phi/dt at `time` (nc; drives: alpha_dot - q_dot(t);
// length-driven tendons: dL/dt - dL_p/dt).
void CalcVelocityConstraint(const Model& model, const Data& data, double time,
                            Eigen::Ref<Eigen::VectorXd> out);
// The dense constraint gradient B(q) (nc x nv, preallocated), rows held at zero zero.
void CalcConstraintGradient(const Model& model, const Data& data, Eigen::Ref<Eigen::MatrixXd> out);
// rows(r) -= the second time derivative of the target of every rheonomic row r that is not
// held (phi = g(q) - target(t): drives q_ddot(t), length-driven tendons L_p_ddot(t)); rows has
// the nc constraint rows. The acceleration-level constraint B vdot + dB/dt v = rows.
void SubtractConstraintAccelerations(const Model& model, const Data& data, double time,
                                     Eigen::Ref<Eigen::VectorXd> rows);

// Calls f(row) for every multiplier row held at zero: the redundant constraint rows and the
// rows of slack length-driven tendons (Data::tendon_slack). Their residual row is
// lambda_r / s_L with a unit diagonal, their gradient rows are zero.
template <class F>
void ForEachHeldRow(const Model& model, const Data& data, F&& f) {
  for (int r : model.redundant_rows) f(r);
  for (std::size_t i = 0; i < model.tendons.size(); ++i)
    if (model.tendons[i].row >= 0 && data.tendon_slack[i]) f(model.tendons[i].row);
}

// Largest |phi| over all constraint rows at the current state (global order residual rows).
double MaxConstraintViolation(const Model& model, Data& data, double time, double load_factor);

}  // namespace screwfem
