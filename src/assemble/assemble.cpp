#include "screwfem/assemble/assemble.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <cmath>
#include <tuple>
#include <type_traits>

#include "screwfem/elements/registry.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

const Mat6 kIdentity6 = Mat6::Identity();

// Writes element contributions into the global residual and the permuted band matrix.
class Scatter {
 public:
  Scatter(const Model& m, Data& d, const AssemblyOptions& o) : m_(m), d_(d), o_(o) {}

  int NodeDof(int node) const { return screwfem::NodeDof(m_, node); }
  // The global residual, for constraint kinds that add their rows and forces themselves.
  Eigen::VectorXd& Residual() { return d_.residual; }
  // Records the size of terms that cancel inside a residual entry (round-off floor estimate).
  void Term(double magnitude) { d_.term_scale = std::max(d_.term_scale, o_.s_rows * magnitude); }
  const Mat6& NodeT(int node) const { return d_.node_tangent[static_cast<std::size_t>(node)]; }

  // residual rows [dof, dof + n) += s_R * r
  template <typename V>
  void Rows(int dof, const Eigen::MatrixBase<V>& r) {
    if (dof < 0) return;
    d_.residual.segment(dof, r.size()) += o_.s_rows * r;
    Force(r.cwiseAbs().maxCoeff());
  }
  // Records the size of a generalised force term that entered the residual (the scale of the
  // relative convergence test).
  void Force(double magnitude) { d_.force_scale = std::max(d_.force_scale, o_.s_rows * magnitude); }
  // matrix(rows at global index gi, cols at global index gj) += scale * B. The rows (and the
  // columns) of a block are consecutive in the permuted order (model.h), so each column of
  // the block is a contiguous piece of a band column.
  template <typename B>
  void Block(int gi, int gj, const Eigen::MatrixBase<B>& block, double scale) {
    if (gi < 0 || gj < 0 || !o_.assemble_matrix) return;
    const int pi = m_.permutation[static_cast<std::size_t>(gi)];
    const int pj = m_.permutation[static_cast<std::size_t>(gj)];
    if (m_.sparse_solver) {
      // The sparse pattern holds whole blocks: a column search per column of the block.
      // The node blocks of the contact pairs are in it too (SelectSparsePattern).
      const int rows = static_cast<int>(block.rows());
      double* const values = d_.sparse.values();
      for (Eigen::Index j = 0; j < block.cols(); ++j) {
        const int p = d_.sparse.FindRun(pi, pj + static_cast<int>(j), rows);
        SCREWFEM_CHECK(p >= 0);
        double* const col = values + p;
        for (Eigen::Index i = 0; i < block.rows(); ++i) col[i] += scale * block(i, j);
      }
      return;
    }
    // The factorisation relies on the model's sparsity pattern (pattern_last is constant over
    // a block of unknowns, so the first row and column stand for all).
    const std::vector<int>& pattern = o_.pattern_last ? *o_.pattern_last : m_.pattern_last;
    const bool inside = pattern.empty()
                            ? d_.matrix.InBand(pi, pj + static_cast<int>(block.cols()) - 1) &&
                                  d_.matrix.InBand(pi + static_cast<int>(block.rows()) - 1, pj)
                            : pj + block.cols() - 1 <= pattern[static_cast<std::size_t>(pi)] &&
                                  pi + block.rows() - 1 <= pattern[static_cast<std::size_t>(pj)];
    if (!inside) {
      // Only the node blocks of pairs of moving shapes may lie outside (Data::coupling); a
      // block that does not fit the coupling's room is left out of this matrix.
      SCREWFEM_CHECK(off_band_ && block.rows() == 6 && block.cols() == 6);
      d_.coupling.Add(pi, pj, block, scale);
      return;
    }
    for (Eigen::Index j = 0; j < block.cols(); ++j) {
      double* const col = &d_.matrix.At(pi, pj + static_cast<int>(j));
      for (Eigen::Index i = 0; i < block.rows(); ++i) col[i] += scale * block(i, j);
    }
  }
  // Element matrix over nodes: rows/cols in 6-blocks. S = s_R (c_K K T + c_M M + c_C C);
  // with `kHasNodeTangent`, K already holds K T (or K when the iteration does not use T).
  // dofs[i] is node i's first unknown (-1: none), T[i] its tangent operator.
  template <int N, bool kHasNodeTangent = false>
  void NodeMatrix(const int (&dofs)[N], const Mat6* const (&T)[N],
                  const Eigen::Matrix<double, 6 * N, 6 * N>* K,
                  const Eigen::Matrix<double, 6 * N, 6 * N>* M,
                  const Eigen::Matrix<double, 6 * N, 6 * N>* C) {
    ForEachNodeBlock(dofs, [&](int a, int b, int gi, int gj) {
      Block(gi, gj, CombineNodeBlock<N, kHasNodeTangent>(o_, a, b, T, K, M, C), o_.s_rows);
    });
  }
  // The node block (a, b) of S / s_R = c_K K T + c_M M + c_C C (NodeMatrix; the threads of
  // the parallel assembly form it the same way).
  template <int N, bool kHasNodeTangent>
  static Mat6 CombineNodeBlock(const AssemblyOptions& o, int a, int b, const Mat6* const (&T)[N],
                               const Eigen::Matrix<double, 6 * N, 6 * N>* K,
                               const Eigen::Matrix<double, 6 * N, 6 * N>* M,
                               const Eigen::Matrix<double, 6 * N, 6 * N>* C) {
    Mat6 S = Mat6::Zero();
    if (K) {
      if (o.use_node_tangent && !kHasNodeTangent)
        S.noalias() += o.c_stiffness * K->template block<6, 6>(6 * a, 6 * b) * *T[b];
      else
        S += o.c_stiffness * K->template block<6, 6>(6 * a, 6 * b);
    }
    if (M) S += o.c_mass * M->template block<6, 6>(6 * a, 6 * b);
    if (C) S += o.c_damping * C->template block<6, 6>(6 * a, 6 * b);
    return S;
  }
  // An element matrix already combined (S = c_K K T + c_M M + c_C C): adds s_R S.
  template <int N>
  void ElementMatrix(const int (&dofs)[N], const Eigen::Matrix<double, 6 * N, 6 * N>& S) {
    ForEachNodeBlock(dofs, [&](int a, int b, int gi, int gj) {
      Block(gi, gj, S.template block<6, 6>(6 * a, 6 * b), o_.s_rows);
    });
  }
  // f(a, b, gi, gj) for the 6 x 6 blocks (a, b) of an element matrix over nodes with first
  // unknowns `dofs` (-1: none) whose nodes both have unknowns (gi, gj their first global
  // indices); nothing without the matrix.
  template <int N, typename F>
  void ForEachNodeBlock(const int (&dofs)[N], F&& f) {
    if (!o_.assemble_matrix) return;
    for (int b = 0; b < N; ++b) {
      const int gj = dofs[b];
      if (gj < 0) continue;
      for (int a = 0; a < N; ++a) {
        const int gi = dofs[a];
        if (gi >= 0) f(a, b, gi, gj);
      }
    }
  }
  // An item's terms (elements/element.h): its node rows, and its matrix blocks combined by the
  // kernel or here. dofs and x as gathered for the item (GatherItem).
  // While true, node blocks outside the band pattern go to the off-band coupling.
  void AllowOffBand(bool allow) { off_band_ = allow; }
  template <int N>
  void Add(const int (&dofs)[N], const NodeMotion<N>& x, const ElementTerms<N>& t) {
    if (!t.active) return;
    Force(t.force_scale);
    Term(t.term_scale);
    for (int i = 0; i < N; ++i) Rows(dofs[i], t.residual.template segment<6>(6 * i));
    if (!o_.assemble_matrix) return;
    using M = typename ElementTerms<N>::Matrix;
    const M* K = t.has_stiffness ? &t.stiffness : nullptr;
    const M* Ms = t.has_mass ? &t.mass : nullptr;
    const M* C = t.has_damping ? &t.damping : nullptr;
    if (t.combined)
      ElementMatrix<N>(dofs, t.matrix);
    else if (t.stiffness_has_node_tangent)
      NodeMatrix<N, true>(dofs, x.T, K, Ms, C);
    else
      NodeMatrix<N, false>(dofs, x.T, K, Ms, C);
  }
  // An item computed by a thread of the parallel assembly (ParallelItemTerms): the same
  // Force, Term, Rows and Block calls, with the same values, as Add.
  void AddComputed(const ParallelItemTerms& p) {
    if (!p.active) return;
    Force(p.force_scale);
    Term(p.term_scale);
    for (int i = 0; i < 2; ++i) Rows(p.dofs[i], p.residual.segment<6>(6 * i));
    ForEachNodeBlock(p.dofs, [&](int a, int b, int gi, int gj) {
      Block(gi, gj, p.matrix.block<6, 6>(6 * a, 6 * b), o_.s_rows);
    });
  }
  const AssemblyOptions& options() const { return o_; }
  // Constraint gradient block B (rows: constraint rows starting at `row`, cols: unknowns
  // starting at gj): adds s_C B T to the constraint rows and s_R s_L B^T to the equilibrium
  // rows, and B^T lambda to the residual.
  template <typename BT>
  void Gradient(int row, int gj, const Eigen::MatrixBase<BT>& B, const Mat6* T,
                const Eigen::Ref<const Eigen::VectorXd>& lambda) {
    if (gj < 0) return;
    d_.residual.segment(gj, B.cols()).noalias() += o_.s_rows * (B.transpose() * lambda);
    GradientMatrix(row, gj, B, T);
  }
  // The matrix blocks of Gradient alone (the caller adds B^T lambda to the residual).
  template <typename BT>
  void GradientMatrix(int row, int gj, const Eigen::MatrixBase<BT>& B, const Mat6* T) {
    if (gj < 0 || !o_.assemble_matrix) return;
    const int gr = m_.nv + row;
    Block(gj, gr, B.transpose(), o_.s_rows * o_.s_multipliers);
    if (T && o_.use_node_tangent)
      Block(gr, gj, typename BT::PlainObject(B * *T), o_.s_constraints);
    else
      Block(gr, gj, B, o_.s_constraints);
  }

 private:
  const Model& m_;
  Data& d_;
  const AssemblyOptions& o_;
  bool off_band_ = false;
};

// The node state of one item, as its kernel reads it (elements/element.h, NodeMotion), and
// the first unknown of each node (-1: fixed or the ground), looked up once per item.
template <int N>
void GatherItem(const Scatter& s, const Data& d, const AssemblyOptions& o, const int (&nodes)[N],
                int (&dofs)[N], NodeMotion<N>* x) {
  const bool node_tangent = o.use_node_tangent && o.assemble_matrix;
  for (int i = 0; i < N; ++i) {
    dofs[i] = s.NodeDof(nodes[i]);
    x->H[i] = &NodeFrame(d, nodes[i]);
    x->T[i] = node_tangent && dofs[i] >= 0 ? &s.NodeT(nodes[i]) : &kIdentity6;
  }
  if (o.dynamics) GatherNodeMotionAt<N>(d, dofs, &x->eta, &x->eta_dot);
}

KernelOptions MakeKernelOptions(const AssemblyOptions& o) {
  KernelOptions k;
  k.time = o.time;
  k.load_factor = o.load_factor;
  k.dynamics = o.dynamics;
  k.tangent = o.assemble_matrix;
  k.c_mass = o.c_mass;
  k.c_damping = o.c_damping;
  k.c_stiffness = o.c_stiffness;
  k.node_tangent = o.use_node_tangent && o.assemble_matrix;
  return k;
}

// Every item of one element kind: gather, compute, scatter. Stops at the first item whose
// kernel fails (a rod element past its rotation limit) and records it in data.
template <class Kind>
bool AddKind(const Model& m, Data& d, const AssemblyOptions& o, const KernelOptions& ko,
             Scatter& s) {
  constexpr int N = Kind::kNodes;
  bool ok = true;
  // A kind whose items couple nodes the band pattern may not hold (kOffBandBlocks).
  s.AllowOffBand(requires { Kind::kOffBandBlocks; });
  ForEachItem<Kind>(m, d, [&](const typename Kind::Item& item, const int(&nodes)[N]) {
    if (!ok) return;
    int dofs[N];
    NodeMotion<N> x;
    GatherItem<N>(s, d, o, nodes, dofs, &x);
    ElementTerms<N> t;
    if (!Kind::Calc(m, d, item, x, ko, &t)) {
      ok = false;
      if constexpr (std::is_same_v<typename Kind::Item, int>) d.failed_element = item;
      d.failed_rotation = t.failure;
      return;
    }
    s.Add(dofs, x, t);
  });
  s.AllowOffBand(false);
  return ok;
}

// The parallel assembly of a kind with kParallel (docs/architecture.md, "Parallel
// assembly"). Its items are taken in blocks of kParallelClaim in item order; the pool's threads
// claim blocks one after the other and compute their items into a ring buffer of blocks
// (ParallelItemTerms), while the calling thread scatters the blocks in item order as they
// become ready (computing blocks itself while it waits), so that every sum is formed in the
// order of AddKind, bit for bit. A block is claimed only when its place in the ring has been
// scattered, so the buffer stays Data::parallel's size whatever the model's.
struct ParallelRun {
  const Model* model;
  Data* data;  // the threads read it; the calling thread writes only after Calc (scatter)
  const AssemblyOptions* options;
  const KernelOptions* kernel;
  Scatter* scatter;
  ParallelItemTerms* items;       // ring_blocks * kParallelClaim items
  std::atomic<long>* ready;       // per place in the ring: 1 + the block it holds, when computed
  int count = 0;                  // items
  int blocks = 0;                 // blocks of items
  int ring_blocks = 0;            // places in the ring
  std::atomic<int> next{0};       // the first block not yet claimed
  std::atomic<int> scattered{0};  // blocks scattered: their places are free
  std::atomic<bool> stop{false};  // an item failed: claim nothing more
  bool failed = false;
};

// Items a thread claims at once.
constexpr int kParallelClaim = 8;

// Waiting for a block: a pause, then yielding the processor after a while.
void ParallelBackoff(int* spins) {
  if (++*spins < 2000) {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  } else {
    std::this_thread::yield();
  }
}

template <class Kind>
void ComputeParallelItem(const ParallelRun& r, ParallelItemTerms& p) {
  NodeMotion<2> x;
  GatherItem<2>(*r.scatter, *r.data, *r.options, p.nodes, p.dofs, &x);
  ElementTerms<2> t;
  p.ok = Kind::Calc(*r.model, *r.data, p.item, x, *r.kernel, &t);
  p.active = t.active;
  if (!p.ok) {
    p.failure = t.failure;
    return;
  }
  if (!t.active) return;
  p.force_scale = t.force_scale;
  p.term_scale = t.term_scale;
  p.residual = t.residual;
  const AssemblyOptions& o = *r.options;
  if (!o.assemble_matrix) return;
  using M = typename ElementTerms<2>::Matrix;
  const M* K = t.has_stiffness ? &t.stiffness : nullptr;
  const M* Ms = t.has_mass ? &t.mass : nullptr;
  const M* C = t.has_damping ? &t.damping : nullptr;
  for (int b = 0; b < 2; ++b) {
    if (p.dofs[b] < 0) continue;
    for (int a = 0; a < 2; ++a) {
      if (p.dofs[a] < 0) continue;
      auto S = p.matrix.block<6, 6>(6 * a, 6 * b);
      if (t.combined)
        S = t.matrix.block<6, 6>(6 * a, 6 * b);
      else if (t.stiffness_has_node_tangent)
        S = Scatter::CombineNodeBlock<2, true>(o, a, b, x.T, K, Ms, C);
      else
        S = Scatter::CombineNodeBlock<2, false>(o, a, b, x.T, K, Ms, C);
    }
  }
}

// The next block whose place in the ring is free: its index, -1 when the ring is full for now,
// -2 when every block is claimed (or an item failed).
int ClaimParallelBlock(ParallelRun& r) {
  int b = r.next.load(std::memory_order_relaxed);
  for (;;) {
    if (b >= r.blocks || r.stop.load(std::memory_order_relaxed)) return -2;
    if (b >= r.scattered.load(std::memory_order_acquire) + r.ring_blocks) return -1;
    if (r.next.compare_exchange_weak(b, b + 1, std::memory_order_acq_rel,
                                     std::memory_order_relaxed))
      return b;
  }
}

template <class Kind>
void ComputeParallelBlock(ParallelRun& r, int b) {
  ParallelItemTerms* place =
      r.items + static_cast<std::ptrdiff_t>(b % r.ring_blocks) * kParallelClaim;
  const int first = b * kParallelClaim;
  const int last = std::min(r.count, first + kParallelClaim);
  for (int i = first; i < last; ++i) {
    ParallelItemTerms& p = place[i - first];
    p.item = i;
    Kind::ItemNodes(*r.model, i, p.nodes);
    ComputeParallelItem<Kind>(r, p);
  }
  r.ready[b % r.ring_blocks].store(b + 1, std::memory_order_release);
}

// The calling thread (worker 0) scatters the blocks in order; the others compute.
template <class Kind>
void ScatterParallelBlocks(ParallelRun& r) {
  for (int b = 0; b < r.blocks; ++b) {
    int spins = 0;
    while (r.ready[b % r.ring_blocks].load(std::memory_order_acquire) != b + 1) {
      const int c = ClaimParallelBlock(r);
      if (c >= 0) {
        ComputeParallelBlock<Kind>(r, c);
        spins = 0;
      } else {
        ParallelBackoff(&spins);
      }
    }
    const ParallelItemTerms* place =
        r.items + static_cast<std::ptrdiff_t>(b % r.ring_blocks) * kParallelClaim;
    const int n = std::min(kParallelClaim, r.count - b * kParallelClaim);
    for (int i = 0; i < n; ++i) {
      const ParallelItemTerms& p = place[i];
      if (!p.ok) {
        r.data->failed_element = p.item;
        r.data->failed_rotation = p.failure;
        r.failed = true;
        r.stop.store(true, std::memory_order_relaxed);
        return;
      }
      r.scatter->AddComputed(p);
    }
    r.scattered.store(b + 1, std::memory_order_release);
  }
}

template <class Kind>
void RunParallelBlocks(void* context, int worker) {
  ParallelRun& r = *static_cast<ParallelRun*>(context);
  if (worker == 0) {
    try {
      ScatterParallelBlocks<Kind>(r);
    } catch (...) {
      r.stop.store(true, std::memory_order_relaxed);
      throw;
    }
    return;
  }
  int spins = 0;
  for (;;) {
    const int b = ClaimParallelBlock(r);
    if (b == -2) return;
    if (b == -1) {
      ParallelBackoff(&spins);
      continue;
    }
    spins = 0;
    ComputeParallelBlock<Kind>(r, b);
  }
}

template <class Kind>
bool AddKindParallel(const Model& m, Data& d, const AssemblyOptions& o, const KernelOptions& ko,
                     Scatter& s) {
  static_assert(Kind::kNodes == 2 && std::is_same_v<typename Kind::Item, int>,
                "the parallel assembly holds items of two nodes with an index");
  ParallelAssembly& par = d.parallel;
  ParallelRun r;
  r.model = &m;
  r.data = &d;
  r.options = &o;
  r.kernel = &ko;
  r.scatter = &s;
  r.items = par.items().data();
  r.ready = par.ready();
  r.count = Kind::ItemCount(m);
  r.blocks = (r.count + kParallelClaim - 1) / kParallelClaim;
  r.ring_blocks = static_cast<int>(par.items().size()) / kParallelClaim;
  if (r.blocks == 0) return true;
  for (int i = 0; i < r.ring_blocks; ++i) r.ready[i].store(0, std::memory_order_relaxed);
  s.AllowOffBand(false);
  par.pool()->Run(&RunParallelBlocks<Kind>, &r);
  return !r.failed;
}

template <class Kind>
bool AddKindAny(const Model& m, Data& d, const AssemblyOptions& o, const KernelOptions& ko,
                Scatter& s) {
  if constexpr (requires { Kind::kParallel; })
    if (d.parallel.threads() > 1 && d.parallel.pool() != nullptr)
      return AddKindParallel<Kind>(m, d, o, ko, s);
  return AddKind<Kind>(m, d, o, ko, s);
}

template <class... Kinds>
bool AddKinds(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s,
              std::tuple<Kinds...>*) {
  const KernelOptions ko = MakeKernelOptions(o);
  return (AddKindAny<Kinds>(m, d, o, ko, s) && ...);
}

template <class... Kinds>
void AddKindEnergies(const Model& m, const Data& d, Energy* E, std::tuple<Kinds...>*) {
  (ForEachItem<Kinds>(m, d,
                      [&](const typename Kinds::Item& item, const int(&)[Kinds::kNodes]) {
                        Kinds::AddEnergy(m, d, item, E);
                      }),
   ...);
}

// Every item of one constraint kind with rows that are not held: its rows, gradient and
// forces (elements/constraint.h).
template <class Kind>
void AddConstraintKind(const Model& m, Data& d, const AssemblyOptions& o, Scatter& s) {
  Kind::ForEach(m, [&](const typename Kind::Item& item) {
    if (Kind::Active(m, d, item)) Kind::Assemble(m, d, item, o, s);
  });
}

constexpr ElementKinds* kElementKinds = nullptr;
}  // namespace

std::vector<int> ConstraintForceTangentPattern(const Model& model, int* bandwidth) {
  std::vector<int> last = model.pattern_last;
  *bandwidth = model.bandwidth;
  if (static_cast<int>(last.size()) != model.num_unknowns()) return last;
  // d(B^T lambda)/dq of a joint couples every pair of its column blocks (node A, node B, the
  // coordinates): the permuted range [first, first + size) of each, from the kind's columns.
  struct Range {
    int first = -1, size = 0;
  };
  JointConstraintKind::ForEach(model, [&](int ji) {
    Range r[3];
    int n = 0;
    JointConstraintKind::ForEachColumn(model, ji, [&](int g, int size) {
      if (size > 0) r[n++] = Range{model.permutation[static_cast<std::size_t>(g)], size};
    });
    for (int ia = 0; ia < n; ++ia)
      for (int ib = 0; ib < n; ++ib) {
        const Range& a = r[ia];
        const Range& b = r[ib];
        for (int i = 0; i < a.size; ++i) {
          int& l = last[static_cast<std::size_t>(a.first + i)];
          l = std::max(l, b.first + b.size - 1);
          *bandwidth = std::max(*bandwidth, l - (a.first + i));
        }
      }
  });
  return last;
}

void AddConstraintForceTangentBlocks(const Model& model, std::vector<SparseLU::Block>* blocks) {
  JointConstraintKind::ForEach(model, [&](int ji) {
    int first[3], size[3], n = 0;
    JointConstraintKind::ForEachColumn(model, ji, [&](int g, int s) {
      if (s > 0) {
        first[n] = model.permutation[static_cast<std::size_t>(g)];
        size[n++] = s;
      }
    });
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) blocks->push_back({first[a], size[a], first[b], size[b]});
  });
}

Energy CalcEnergy(const Model& model, const Data& data) {
  Energy E;
  AddKindEnergies(model, data, &E, kElementKinds);
  // The constraint kinds that store energy (a joint's springs on its coordinates).
  ForEachKind<ConstraintKinds>([&]<class Kind>() {
    if constexpr (requires { &Kind::AddEnergy; })
      Kind::ForEach(
          model, [&](const typename Kind::Item& item) { Kind::AddEnergy(model, data, item, &E); });
  });
  return E;
}

void SaveState(const Data& data, State* state) {
  state->H = data.H;
  state->HJ = data.HJ;
  state->q_joint = data.q_joint;
}

void RestoreState(const State& state, Data& data) {
  data.H = state.H;
  data.HJ = state.HJ;
  data.q_joint = state.q_joint;
}

void Retract(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& dx) {
  for (std::size_t i = 0; i < model.nodes.size(); ++i) {
    const int dof = model.nodes[i].dof;
    if (dof >= 0) data.H[i] = data.H[i] * ExpSE3(dx.segment<6>(dof));
  }
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.k() > 0) RetractJoint(model, data, static_cast<int>(jj), dx.segment(j.coord, j.k()));
  }
}

double ScaledIncrementSize(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& dx) {
  double r = 0.0;
  for (const Node& n : model.nodes) {
    if (n.dof < 0) continue;
    r = std::max(r, dx.segment<3>(n.dof).cwiseAbs().maxCoeff() / model.length_scale);
    r = std::max(r, dx.segment<3>(n.dof + 3).cwiseAbs().maxCoeff());
  }
  for (int i = model.nv_nodes; i < model.nv; ++i) r = std::max(r, std::abs(dx(i)));
  return r;
}

void UpdateBranchReferences(const Model& model, Data& data) {
  // The rotation of CalcRodRelativeMotion alone: R_A^T R_B formed as (H_A^-1 H_B).R is.
  for (std::size_t e = 0; e < model.elements.size(); ++e) {
    const RodElement& el = model.elements[e];
    const Mat3 RAt = data.H[static_cast<std::size_t>(el.node_a)].R.transpose();
    data.w_ref[e] = LogSO3Near(RAt * data.H[static_cast<std::size_t>(el.node_b)].R, data.w_ref[e]);
  }
}

int ResolveAssemblyThreads(const Model& model, int requested) {
  if (requested >= 1) return std::min(requested, kMaxAssemblyThreads);
  if (static_cast<long>(model.elements.size()) < kParallelMinElements) return 1;
  return std::min(AvailableCores(), kMaxAssemblyThreads);
}

void SetAssemblyThreads(Data& data, int threads) {
  data.parallel.Set(std::clamp(threads, 1, kMaxAssemblyThreads), 2 * kParallelChunk);
}

void SelectSparsePattern(const Model& model, Data& data) {
  std::vector<std::int64_t>& list = data.sparse_couplings;
  const std::size_t most = 6 * static_cast<std::size_t>(data.num_shape_pairs);
  if (list.size() < most) list.resize(most);  // only when the pool grew without it (allocates)
  const SparseLU& lu = data.sparse;
  std::size_t count = 0;
  for (int k = 0; k < data.num_shape_pairs; ++k) {
    const ShapePair& pair = data.shape_pairs[static_cast<std::size_t>(k)];
    const int nodes[4] = {pair.side[0].node[0], pair.side[0].node[1], pair.side[1].node[0],
                          pair.side[1].node[1]};
    int first[4];
    for (int i = 0; i < 4; ++i) {
      const int dof = NodeDof(model, nodes[i]);
      first[i] = dof >= 0 ? model.permutation[static_cast<std::size_t>(dof)] : -1;
    }
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (first[a] >= 0 && first[b] >= 0 && first[a] != first[b] &&
            !lu.InBase(first[a], first[b]))
          list[count++] = lu.PackCoupling(first[a], first[b]);
  }
  std::sort(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(count));
  count = static_cast<std::size_t>(
      std::unique(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(count)) - list.begin());
  data.sparse.SetCouplings(list.data(), count, 6);
}

bool Assemble(const Model& model, Data& data, const AssemblyOptions& options) {
  data.residual.setZero();
  if (options.assemble_matrix) {
    if (!model.sparse_solver) data.matrix.SetZero();
    // The off-band coupling: doubled when the last assembly overflowed it, up to
    // kMaxCoupledNodes (beyond, the blocks that do not fit are left out of the matrix).
    if (data.coupling.overflowed() && data.coupling.max_blocks() < kMaxCoupledNodes)
      data.coupling.Resize(data.coupling.size(), 6,
                           std::min(2 * data.coupling.max_blocks(), kMaxCoupledNodes));
    data.coupling.Clear();
  }
  data.failed_element = -1;
  data.force_scale = 0.0;
  data.term_scale = 0.0;
  Scatter s(model, data, options);
  // The pairs of moving shapes near each other in this state (elements/shape_pair.h).
  UpdateShapePairs(model, data);
  if (data.shape_pair_limit_reached) return false;  // ShapePairLimitMessage says why
  if (options.assemble_matrix && model.sparse_solver) {
    // The pattern of this state's contact pairs (analysed once per list of couplings).
    SelectSparsePattern(model, data);
    data.sparse.SetZero();
  }
  if (!AddKinds(model, data, options, s, kElementKinds)) return false;
  ForEachKind<ConstraintKinds>(
      [&]<class Kind>() { AddConstraintKind<Kind>(model, data, options, s); });
  // Redundant constraint rows (found at build time) and slack tendons: the row becomes
  // dmu_r = -lambda_r / s_L, which holds their multipliers at zero.
  ForEachHeldRow(model, data, [&](int r) {
    const int g = model.nv + r;
    data.residual(g) = data.lambda(r) / options.s_multipliers;
    if (!options.assemble_matrix) return;
    const int p = model.permutation[static_cast<std::size_t>(g)];
    if (model.sparse_solver) {
      data.sparse.SetRow(p, 1.0);
      return;
    }
    const int lo = std::max(0, p - data.matrix.lower_bandwidth());
    const int hi = std::min(data.matrix.size() - 1, p + data.matrix.upper_bandwidth());
    for (int c = lo; c <= hi; ++c) data.matrix.At(p, c) = 0.0;
    data.matrix.At(p, p) = 1.0;
  });
  return data.residual.allFinite();
}

namespace {

// f.template operator()<Kind>(item) for every item of every constraint kind whose rows are not
// held by its state (a slack tendon's).
template <class F>
void ForEachActiveConstraint(const Model& model, const Data& data, F&& f) {
  ForEachKind<ConstraintKinds>([&]<class Kind>() {
    Kind::ForEach(model, [&](const typename Kind::Item& item) {
      if (Kind::RowCount(model, item) > 0 && Kind::Active(model, data, item))
        f.template operator()<Kind>(item);
    });
  });
}

// f(row, target) for every rheonomic row (phi = g(q) - target(t)) that is not held.
template <class F>
void ForEachConstraintTarget(const Model& model, const Data& data, double time, F&& f) {
  ForEachActiveConstraint(model, data, [&]<class Kind>(const typename Kind::Item& item) {
    Kind::ForEachTarget(model, data, item, time, f);
  });
}

}  // namespace

void CalcConstraintGradient(const Model& model, const Data& data, Eigen::Ref<Eigen::MatrixXd> out) {
  out.setZero();
  ForEachActiveConstraint(model, data, [&]<class Kind>(const typename Kind::Item& item) {
    Kind::ForEachGradientBlock(model, data, item, [&](int row, int col, const auto& B) {
      out.block(row, col, B.rows(), B.cols()) += B;
    });
  });
  ForEachHeldRow(model, data, [&](int r) { out.row(r).setZero(); });
}

void CalcConstraintGradientTimes(const Model& model, const Data& data,
                                 const Eigen::Ref<const Eigen::VectorXd>& x,
                                 Eigen::Ref<Eigen::VectorXd> out) {
  out.setZero();
  ForEachActiveConstraint(model, data, [&]<class Kind>(const typename Kind::Item& item) {
    Kind::GradientTimes(model, data, item, x, out);
  });
  ForEachHeldRow(model, data, [&](int r) { out(r) = 0.0; });
}

void CalcVelocityConstraint(const Model& model, const Data& data, double time,
                            Eigen::Ref<Eigen::VectorXd> out) {
  CalcConstraintGradientTimes(model, data, data.v, out);
  ForEachConstraintTarget(model, data, time,
                          [&](int row, const ProfileValue& target) { out(row) -= target.rate; });
}

void SubtractConstraintAccelerations(const Model& model, const Data& data, double time,
                                     Eigen::Ref<Eigen::VectorXd> rows) {
  ForEachConstraintTarget(model, data, time,
                          [&](int row, const ProfileValue& target) { rows(row) -= target.accel; });
}

double MaxConstraintViolation(const Model& model, Data& data, double time, double load_factor) {
  AssemblyOptions o;
  o.time = time;
  o.load_factor = load_factor;
  o.assemble_matrix = false;
  Assemble(model, data, o);
  return model.nc > 0 ? data.residual.tail(model.nc).cwiseAbs().maxCoeff() : 0.0;
}

}  // namespace screwfem
