// Data: the state and every workspace of one simulation, allocated once from a Model (see
// docs/architecture.md, "Model and Data"). Algorithms read the Model and write Data.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "screwfem/linalg/band_coupling.h"
#include "screwfem/linalg/banded_lu.h"
#include "screwfem/linalg/sparse_lu.h"
#include "screwfem/model/model.h"
#include "screwfem/model/thread_pool.h"

namespace screwfem {

// The broad phase's workspace (UpdateShapePairs, elements/shape_pair.h): a uniform grid of
// cells hashed into buckets, filled by a counting sort; every array sized by MakeData.
// The grid sorts chunks: runs of consecutive elements of one rod about a diameter long (at most
// 16), or one body shape, so that a rod of elements shorter than its radius does not pair
// each element with the tens of neighbours its box overlaps, all within the self skip.
struct ShapePairGrid {
  std::vector<int> chunk_first;  // chunk c: segments [chunk_first[c], chunk_first[c + 1])
  std::vector<Vec3> segment_lo, segment_hi;  // per contact segment: its box, inflated [m]
  std::vector<Vec3> lo, hi;                  // per chunk: the union of its segments' boxes
  std::vector<char> large;                   // per chunk: larger than a cell (tested against all)
  std::vector<int> bucket_start;             // per bucket (a power of two, + 1): first entry
  std::vector<int> entry_chunk;              // entries (a chunk in a cell), bucket by bucket
  std::vector<Eigen::Vector3i> entry_cell;   // the entry's cell
  std::vector<int> large_chunks;             // the chunks larger than a cell
  long box_tests = 0;  // box-overlap tests of the last search (its cost, for tests)
};

// The most nodes the off-band coupling of the iteration matrix holds (Data::coupling: its
// factorisation costs 6 banded solves per node and a dense LU of 6 x that size; 128 nodes: 14 MB).
constexpr int kMaxCoupledNodes = 128;

// The most pairs of moving shapes a broad phase may find at once (ShapePairPoolLimit).
constexpr std::size_t kMaxShapePairs = 2000000;

// The history of one pair under the stick friction law (docs/numerics.md, "Stick friction"),
// as of the last accepted step or load step: the elastic tangential deflection u_e of its anchor
// and the material point of the shape that was in contact, by its weights W_k and node-frame
// levers l_k on the pair's item nodes and its world position then. A pair's slip since is the
// displacement of that material point, sum_k W_k (x_k + R_k l_k) - point.
struct ContactAnchor {
  Vec3 deflection = Vec3::Zero();  // u_e [m], world, tangential
  Vec3 point = Vec3::Zero();       // [m], world
  double weight[2] = {0.0, 0.0};
  Vec3 lever[2] = {Vec3::Zero(), Vec3::Zero()};
  bool valid = false;     // a material point is stored (false before the first acceptance)
  bool slipping = false;  // the pair slipped then: the threshold is mu_k, else mu_s
  double time = 0.0;      // Data::time then (a moving obstacle surface's material point)
};

// The same for a pair of moving shapes (Data::shape_pair_anchors), named by its key
// (ShapePairAnchorKey: its two contact segments and part): weights and levers on its four item
// nodes, and `point`, the world offset p_A - p_B of its two material points then; the slip is
// the change of that offset.
struct ShapePairAnchor {
  double key = 0.0;
  Vec3 deflection = Vec3::Zero();
  Vec3 point = Vec3::Zero();
  double weight[4] = {0.0, 0.0, 0.0, 0.0};
  Vec3 lever[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  bool slipping = false;
};

struct Data {
  double time = 0.0;
  std::vector<SE3> H;              // node frames
  std::vector<SE3> HJ;             // joint relative frames H_J
  Eigen::VectorXd q_joint;         // joint coordinates (nv - nv_nodes); exact for abelian joints
  Eigen::VectorXd v, vdot;         // velocities and accelerations (nv)
  Eigen::VectorXd lambda;          // multipliers (nc)
  std::vector<Vec3> w_ref;         // per rod element: rotation vector on the current branch
  Eigen::VectorXd inputs;          // values of the run-time inputs (Model::inputs), set between
                                   // steps; profiles read them through EvalProfile
  std::vector<char> tendon_slack;  // per tendon: 1 while a length-driven tendon is slack (its
                                   // row holds the multiplier at zero; docs/numerics.md)
  // Per Model::contact_pairs under the stick friction law with friction (else empty): updated by
  // AcceptContactHistory (elements/contact.h) when a step or load step is accepted.
  std::vector<ContactAnchor> contact_anchors;
  // The pairs of moving shapes' history under the stick law with friction: the first
  // num_shape_pair_anchors entries, sorted by key, and a buffer of the same size for the next
  // acceptance; both as large as the shape-pair pool.
  std::vector<ShapePairAnchor> shape_pair_anchors, shape_pair_anchors_next;
  int num_shape_pair_anchors = 0;

  // Pairs of moving shapes near each other at the last assembly (UpdateShapePairs,
  // elements/shape_pair.h): the first num_shape_pairs entries of a pool sized by MakeData and
  // grown between steps when a step finds it full (GrowShapePairPool).
  std::vector<ShapePair> shape_pairs;
  int num_shape_pairs = 0;
  bool shape_pair_overflow = false;  // the last broad phase found more pairs than the pool
  // The pool is at its limit (ShapePairPoolLimit) and the last broad phase found more pairs:
  // the assembly fails, and the step's message says so.
  bool shape_pair_limit_reached = false;
  ShapePairGrid shape_pair_grid;
  // The swept check against tunnelling (elements/crossing.h): the axis end points of each
  // contact segment, then of each obstacle pair, at the last accepted state (valid once set),
  // and the sweep's buffers (per segment: its swept box's corners, and the segments sorted by
  // the box's low x). Sized by MakeData.
  std::vector<Vec3> crossing_points;
  bool crossing_valid = false;
  std::vector<Vec3> crossing_lo, crossing_hi;
  std::vector<int> crossing_order;

  // Workspaces of the Newton solvers.
  Eigen::VectorXd residual;        // global order, size nv + nc
  Eigen::VectorXd rhs;             // permuted order
  Eigen::VectorXd increment;       // global order, size nv + nc
  std::vector<Mat6> node_tangent;  // T(h dq_i) per node for the dynamic iteration matrix
  BandedLU matrix;                 // permuted, banded iteration matrix
  // The same matrix in the sparse LU (Model::sparse_solver; the banded one is then empty):
  // pattern Model::sparse_pattern (analysed once by MakeData) plus the node blocks of the
  // contact pairs of each assembly (SelectSparsePattern: one analysis per list of couplings,
  // the last SparseLU::kCachedPatterns kept).
  SparseLU sparse;
  // SelectSparsePattern's list of couplings: 6 per pair of the pool (shape_pairs), sized with
  // it (MakeData, GrowShapePairPool); empty for the banded LU.
  std::vector<std::int64_t> sparse_couplings;
  // The banded matrix's node blocks outside the band pattern (pairs of moving shapes between
  // entities not linked in the band, ContactSettings::band_pair_nodes): a low-rank update
  // solved with the Woodbury identity (SolveAssembledSystem). Room for 32 nodes from MakeData,
  // doubled at the next assembly when an assembly overflowed it, up to kMaxCoupledNodes (blocks
  // that did not fit are left out of that matrix: a quasi-Newton step, the residual stays
  // exact). Unused by the sparse LU, whose pattern holds those blocks.
  BandCoupling coupling;

  // Diagnostics of the last assembly.
  double force_scale = 0.0;  // largest generalised-force term that entered the residual
  double term_scale = 0.0;   // largest term cancelling inside one (e.g. K d/L in sigma)
  int failed_element = -1;   // element whose rotation left the admissible range
  double failed_rotation = 0.0;

  // The threads of the assembly (SetAssemblyThreads, assemble/assemble.h): serial until set;
  // the pool is shut down with the Data.
  ParallelAssembly parallel;
};

// Allocates Data for a model and sets the reference state (at rest).
Data MakeData(const Model& model);

// Doubles the pool of shape pairs (Data::shape_pairs; at least 64, at most `limit`) and clears
// the overflow flag: called between steps when a broad phase found the pool full (allocates).
void GrowShapePairPool(Data& data, std::size_t limit = kMaxShapePairs);

// The most pairs of moving shapes the broad phase's pool may hold (docs/limits.md): at most
// kMaxShapePairs (each pair is assembled at every Newton iteration), and what the memory limit
// (Model::memory_limit, model/memory.h) leaves beside the rest of Data, counted twice (the
// pool is copied when it grows); never below the pool MakeData allocates (4 per contact
// segment and 64). Without a limit the pool grew with whatever a broad phase found (7.5 GB was
// reported for a resting rod in self-contact at 10,000 elements).
std::size_t ShapePairPoolLimit(const Model& model);
// The message of an assembly that stopped at that limit.
std::string ShapePairLimitMessage(const Model& model);

// The one evaluation of a profile by a kernel or solver: at time t, with this simulation's
// run-time input values (a profile with ProfileTerm::kInput terms reads data.inputs).
inline ProfileValue EvalProfile(const Profile& profile, double t, const Data& data) {
  return profile.Eval(t, data.inputs);
}

// The frame of the ground (the world frame).
inline const SE3 kGroundFrame = SE3::Identity();

// The current frame of a node, or the identity for kGround (the one ground-or-node lookup).
inline const SE3& NodeFrame(const Data& data, int node) {
  return node == kGround ? kGroundFrame : data.H[static_cast<std::size_t>(node)];
}

// Body velocities and accelerations of N nodes stacked (node 0 first), zero for a fixed node
// or the ground: the one gathering of node motion for kernels and outputs. dofs[i] is the
// first velocity unknown of node i (Node::dof; -1 for a fixed node or the ground).
template <int N>
void GatherNodeMotionAt(const Data& data, const int (&dofs)[N],
                        Eigen::Matrix<double, 6 * N, 1>* eta,
                        Eigen::Matrix<double, 6 * N, 1>* eta_dot) {
  for (int i = 0; i < N; ++i) {
    if (dofs[i] < 0) {
      if (eta) eta->template segment<6>(6 * i).setZero();
      if (eta_dot) eta_dot->template segment<6>(6 * i).setZero();
    } else {
      if (eta) eta->template segment<6>(6 * i) = data.v.segment<6>(dofs[i]);
      if (eta_dot) eta_dot->template segment<6>(6 * i) = data.vdot.segment<6>(dofs[i]);
    }
  }
}
template <int N>
void GatherNodeMotion(const Model& model, const Data& data, const int (&nodes)[N],
                      Eigen::Matrix<double, 6 * N, 1>* eta,
                      Eigen::Matrix<double, 6 * N, 1>* eta_dot) {
  int dofs[N];
  for (int i = 0; i < N; ++i)
    dofs[i] = nodes[i] == kGround ? -1 : model.nodes[static_cast<std::size_t>(nodes[i])].dof;
  GatherNodeMotionAt<N>(data, dofs, eta, eta_dot);
}

}  // namespace screwfem
