// General sparse LU of the Newton systems (SuiteSparse KLU), for the systems whose band is wide
// although few of its entries are nonzero: many fingers on one palm, a length-driven tendon
// whose row spans every node, many bodies (docs/numerics.md, "Sparse direct solve").
//
// The matrix is stored in compressed columns (CSC) on a fixed structural pattern: a union of
// dense blocks of consecutive rows and columns (SetPattern), in the same index space as the
// BandedLU it replaces (the permuted unknowns of Model::permutation). SetPattern allocates and
// runs KLU's symbolic analysis (its fill-reducing ordering, AMD on the block-triangular
// blocks) once per pattern; Factorize() factorises numerically the first time (klu_factor)
// and refactorises afterwards (klu_refactor, which allocates nothing) with one of up to 8
// kept pivot sequences, the most recently successful first: matrices of different kinds on
// one pattern (a step's iteration matrix, the mass matrix [M B^T; B 0] of restarts, held and
// acting tendon rows) each find a sequence that suits them. When none does (a zero pivot, or
// a reciprocal pivot growth below kMinPivotGrowth) it factorises with new pivots, kept as
// another sequence (this allocates; counted in fallbacks()). KLU's diagonal preference is 0.1
// (its default 0.001), so one sequence suits more matrices. Refactorisations, Solve() and the
// entry writes never allocate.
//
// Couplings (SetCouplings): pairs of blocks of unknowns whose two off-diagonal blocks are added
// to the pattern given to SetPattern (the base), for the node blocks of the contact pairs the
// broad phase finds at run time (docs/numerics.md, "Pairs and the sparse pattern"). Each
// pattern of couplings is analysed once: up to kCachedPatterns patterns are kept (the one in
// use and the most recently used others, each with its analysis, entries and pivot sequences),
// keyed by their sorted list of couplings; a list met before takes its pattern back without
// analysis or allocation (pattern_hits()); a new one is analysed (allocates) in place of the
// least recently used.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace screwfem {

class SparseLU {
 public:
  // A dense block of the pattern: rows [row, row + rows), columns [col, col + cols).
  struct Block {
    int row, rows, col, cols;
  };
  // Refactorised pivots whose reciprocal growth (klu_rgrowth) falls below this are replaced
  // by a factorisation with new pivots.
  static constexpr double kMinPivotGrowth = 1e-8;
  // Patterns of couplings kept (SetCouplings): the one in use and the most recent others.
  static constexpr int kCachedPatterns = 4;

  SparseLU();
  ~SparseLU();
  SparseLU(const SparseLU& other);
  SparseLU& operator=(const SparseLU& other);  // copies the pattern and analyses it again
  SparseLU(SparseLU&& other) noexcept;
  SparseLU& operator=(SparseLU&& other) noexcept;

  // n unknowns; the pattern is the union of `blocks` and the diagonal (blocks may overlap and
  // repeat). Allocates, runs the symbolic analysis (analyses() grows by one) and sets every
  // entry to zero. The next Factorize() is a full one. This is the base pattern: it has no
  // couplings, and the patterns of couplings kept so far are dropped.
  void SetPattern(int n, const std::vector<Block>& blocks);

  // Packs the coupling of the blocks starting at unknowns p != q (in either order) as SetCouplings
  // takes it: min(p, q) n + max(p, q).
  std::int64_t PackCoupling(int p, int q) const {
    return static_cast<std::int64_t>(p < q ? p : q) * n_ + (p < q ? q : p);
  }
  // Makes the pattern hold the base (SetPattern) plus, for every coupling in pairs[0, count)
  // (sorted ascending, without repeats, PackCoupling), the blocks (p, q) and (q, p) of
  // block_size x block_size unknowns. Nothing happens when the pattern in use holds them all; a
  // kept pattern of that list, else one holding it, is taken back (pattern_hits() grows; no
  // analysis, no allocation); else a new pattern is analysed (analyses() grows; allocates) in
  // place of the least recently used kept one: the list, with the couplings of the pattern in
  // use when those are at most count + 16 (so a pair that comes and goes keeps one pattern).
  // When the pattern changes, its entries are the values they had when it was last in use
  // (zero for a new one); set them before Factorize. block_size is the same at every call.
  void SetCouplings(const std::int64_t* pairs, std::size_t count, int block_size);
  // The couplings of the pattern in use (SetCouplings), sorted: the last list given, or more.
  const std::vector<std::int64_t>& couplings() const { return key_; }
  // True when entry (i, j) lies in the base pattern (SetPattern): in the pattern in use and not
  // in one of its coupling blocks. For entries (i, j) with i and j the first unknowns of blocks.
  bool InBase(int i, int j) const;

  int size() const { return n_; }
  int nonzeros() const { return static_cast<int>(row_.size()); }
  // The position of entry (i, j) in values(), or -1 when it is not in the pattern (binary
  // search in column j).
  int Find(int i, int j) const;
  // The position of entry (i, j) when rows [i, i + rows) of column j are all in the pattern
  // (they follow each other in values()), else -1.
  int FindRun(int i, int j, int rows) const {
    const int p = Find(i, j);
    return p >= 0 && p + rows <= col_start_[static_cast<std::size_t>(j) + 1] &&
                   row_[static_cast<std::size_t>(p + rows - 1)] == i + rows - 1
               ? p
               : -1;
  }
  double* values() { return value_.data(); }
  // True when the block (rows [i, i + rows), columns [j, j + cols)) lies in the pattern.
  bool Contains(int i, int j, int rows, int cols) const;
  // Entry (i, j); precondition: in the pattern. The rows i, i + 1, ... of one dense block of
  // the pattern follow each other in memory (&At(i, j) + r is entry (i + r, j)).
  double& At(int i, int j) { return value_[static_cast<std::size_t>(Find(i, j))]; }
  double At(int i, int j) const { return value_[static_cast<std::size_t>(Find(i, j))]; }
  // f(i, j, value) for every entry of the pattern, column by column.
  template <class F>
  void ForEachEntry(F&& f) const {
    for (int j = 0; j < n_; ++j)
      for (int p = col_start_[static_cast<std::size_t>(j)];
           p < col_start_[static_cast<std::size_t>(j) + 1]; ++p)
        f(row_[static_cast<std::size_t>(p)], j, value_[static_cast<std::size_t>(p)]);
  }
  // Sets row i to zero (every column of its pattern) and its diagonal entry to `diagonal`.
  void SetRow(int i, double diagonal);
  void SetZero();
  // Partial pivoting's preference for the diagonal (KLU's tol): a diagonal entry is the pivot
  // while it is at least `tolerance` times the largest of its column. kConstrainedPivotTolerance
  // (the default) suits matrices with multiplier rows (zero diagonals; fewer pivot sequences per
  // pattern); kDiagonalPivotTolerance, KLU's own default, keeps the diagonal of a matrix without
  // them (MakeData: a model with nc = 0), whose fill is then that of the symmetric ordering:
  // a pile of 40 rods of 40 elements (9840 unknowns, 4 layers) factors in 7.0e7 flops instead
  // of 1.4e8..2.4e8 with tol 0.1 (docs/numerics.md, "Sparse direct solve").
  static constexpr double kConstrainedPivotTolerance = 0.1;
  static constexpr double kDiagonalPivotTolerance = 0.001;
  void SetPivotTolerance(double tolerance);

  // Factorises. Returns -1 on success, or a column whose pivot is zero (the matrix is
  // singular).
  int Factorize();
  // Solves A x = b in place (b <- x) after a successful Factorize().
  void Solve(Eigen::Ref<Eigen::VectorXd> b) const;
  // Solves A^T x = b in place (klu_tsolve) after a successful Factorize(): for adjoint
  // sensitivities (solve/sensitivity.h). Never allocates.
  void SolveTransposed(Eigen::Ref<Eigen::VectorXd> b) const;
  // Largest and smallest |U_jj| of the last factorisation (of the row-scaled matrix KLU
  // factorises: each row divided by its largest entry).
  double max_pivot() const { return max_pivot_; }
  double min_pivot() const { return min_pivot_; }
  // Sign of the determinant of the last factorised matrix (+1 or -1; 0 when it was singular):
  // the sign of prod U_jj times the parities of the row and column permutations (the row
  // scaling is positive).
  int determinant_sign() const { return determinant_sign_; }

  // KLU's estimates from the symbolic analysis: nonzeros of L + U and the flops of one
  // factorisation (docs/numerics.md, "Sparse direct solve": the solver choice).
  double predicted_factor_nonzeros() const { return predicted_nonzeros_; }
  double predicted_flops() const { return predicted_flops_; }
  // Counters since construction: symbolic analyses (SetPattern), numerical factorisations
  // (Factorize calls that succeeded or failed), full factorisations with new pivots among
  // them, and refactorisations whose pivots were poor (replaced by a full one).
  std::int64_t analyses() const { return analyses_; }
  // SetCouplings calls that took a kept pattern back instead of a new analysis.
  std::int64_t pattern_hits() const { return pattern_hits_; }
  // SetCouplings calls that changed the pattern in use (analysed or taken back).
  std::int64_t pattern_changes() const { return pattern_changes_; }
  // Patterns kept besides the one in use.
  int cached_patterns() const;
  std::int64_t factorizations() const { return factorizations_; }
  std::int64_t full_factorizations() const { return full_factorizations_; }
  std::int64_t fallbacks() const { return fallbacks_; }

 private:
  // A pattern kept besides the one in use (SetCouplings): the members of the same names.
  struct Kept {
    std::vector<int> col_start, row;
    std::vector<double> value;
    bool symmetric = true;
    void* symbolic = nullptr;
    void* numeric = nullptr;
    int column_parity = 1;
    double predicted_nonzeros = 0.0, predicted_flops = 0.0;
    std::vector<std::int64_t> key;
    std::int64_t last_use = 0;
  };
  void Release();
  void ReleaseKept();
  void Analyze();
  // The structure of the base blocks plus the coupling blocks of key_ (col_start_, row_,
  // value_ set to zero, symmetric_).
  void BuildStructure();
  void SwapWith(Kept& k);
  bool FullFactorize();
  void ReadPivots();

  int n_ = 0;
  std::vector<int> col_start_;  // n + 1
  std::vector<int> row_;        // row indices, sorted within each column
  std::vector<double> value_;
  bool symmetric_ = true;  // the pattern is structurally symmetric
  // KLU's objects (klu_common, klu_symbolic, klu_numeric), opaque here.
  void* common_ = nullptr;
  void* symbolic_ = nullptr;
  void* numeric_ = nullptr;
  std::vector<char> mark_;  // n: the cycles of a permutation (determinant sign)
  int column_parity_ = 1;   // parity of KLU's column permutation (fixed by the analysis)
  double max_pivot_ = 0.0, min_pivot_ = 0.0;
  int determinant_sign_ = 0;
  double predicted_nonzeros_ = 0.0, predicted_flops_ = 0.0;
  std::int64_t analyses_ = 0, factorizations_ = 0, full_factorizations_ = 0, fallbacks_ = 0;
  // Couplings: the base blocks (SetPattern), the couplings of the pattern in use (sorted), their
  // block size, the kept patterns and the use counter that orders them.
  std::vector<Block> base_;
  std::vector<std::int64_t> key_;
  int block_size_ = 0;
  std::vector<Kept> kept_;  // kCachedPatterns - 1 (empty ones have no symbolic)
  std::int64_t uses_ = 0;
  std::int64_t pattern_hits_ = 0, pattern_changes_ = 0;
};

}  // namespace screwfem
