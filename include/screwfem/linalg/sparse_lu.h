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

  SparseLU();
  ~SparseLU();
  SparseLU(const SparseLU& other);
  SparseLU& operator=(const SparseLU& other);  // copies the pattern and analyses it again
  SparseLU(SparseLU&& other) noexcept;
  SparseLU& operator=(SparseLU&& other) noexcept;

  // n unknowns; the pattern is the union of `blocks` and the diagonal (blocks may overlap and
  // repeat). Allocates, runs the symbolic analysis (analyses() grows by one) and sets every
  // entry to zero. The next Factorize() is a full one.
  void SetPattern(int n, const std::vector<Block>& blocks);

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
  std::int64_t factorizations() const { return factorizations_; }
  std::int64_t full_factorizations() const { return full_factorizations_; }
  std::int64_t fallbacks() const { return fallbacks_; }

 private:
  void Release();
  void Analyze();
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
};

}  // namespace screwfem
