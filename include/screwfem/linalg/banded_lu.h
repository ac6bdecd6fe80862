// Banded LU factorisation with partial pivoting (the algorithm of LAPACK's dgbtf2/dgbtrs),
// for the global saddle-point systems of screwfem after a bandwidth-reducing ordering.
//
// Storage is allocated once by Resize(); Factorize() and Solve() never allocate. Partial
// pivoting keeps the indefinite constrained systems (zero blocks on the multiplier rows)
// stable; the upper bandwidth grows to kl + ku through row interchanges, as in LAPACK.
//
// The systems of screwfem are sparse inside their band (a tenth of the band's multiply-adds
// of a GRM factorisation have nonzero operands). Factorize() therefore skips what is known to
// be zero: it keeps, per row and per column, the last position that can hold a nonzero
// (starting from the structural pattern given by SetPattern, the full band by default, and
// widened by the row interchanges and updates as they happen), restricts each column
// elimination to those rows and columns and skips zero entries of the pivot row. It records
// the nonzero extent of every column of L and U, which Solve() and SetZero() use. Every
// operation it skips would subtract an exact zero: the results are those of the dense-band
// algorithm (LAPACK's dgbtf2/dgbtrs).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace screwfem {

class BandedLU {
 public:
  // n unknowns, kl sub-diagonals, ku super-diagonals of the matrix before pivoting. Resets
  // the pattern to the full band.
  void Resize(int n, int kl, int ku);
  // Structural pattern of the matrices to be factorised: entry (i, j) is zero whenever
  // j > row_last[i] or i > col_last[j] (size n each, inside the band). A promise about every
  // matrix factorised from now on; the factorisation is wrong if it is broken.
  void SetPattern(const std::vector<int>& row_last, const std::vector<int>& col_last);
  // Sets every entry to zero (after a successful Factorize() only the recorded extents).
  void SetZero();

  int size() const { return n_; }
  int lower_bandwidth() const { return kl_; }
  int upper_bandwidth() const { return ku_; }

  // True when (i, j) lies inside the band of the unfactorised matrix.
  bool InBand(int i, int j) const { return i - j <= kl_ && j - i <= ku_; }
  // Entry (i, j); precondition InBand(i, j) (checked in debug builds).
  double& At(int i, int j) {
    extents_valid_ = false;
    return ab_[Index(i, j)];
  }
  double At(int i, int j) const { return ab_[Index(i, j)]; }

  // Factorises in place. Returns -1 on success, or the first column whose pivot is exactly
  // zero (the matrix is singular).
  int Factorize();
  // Solves A x = b in place (b <- x) after a successful Factorize().
  void Solve(Eigen::Ref<Eigen::VectorXd> b) const;
  // Solves A^T x = b in place (b <- x) after a successful Factorize(): U^T, then L^T and the
  // interchanges in reverse order (LAPACK dgbtrs with 'T'); for adjoint sensitivities
  // (solve/sensitivity.h). Never allocates.
  void SolveTransposed(Eigen::Ref<Eigen::VectorXd> b) const;
  // Largest and smallest |U_jj| of the last factorisation (a cheap conditioning indicator).
  double max_pivot() const { return max_pivot_; }
  double min_pivot() const { return min_pivot_; }
  // Sign of the determinant of the last factorised matrix (+1 or -1; 0 when it was singular):
  // a change between two matrices tells that an odd number of eigenvalues crossed zero.
  int determinant_sign() const { return determinant_sign_; }

 private:
  std::size_t Index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(ldab_) +
           static_cast<std::size_t>(kv_ + i - j);
  }

  int n_ = 0, kl_ = 0, ku_ = 0, kv_ = 0, ldab_ = 0;
  std::vector<double> ab_;
  std::vector<int> ipiv_;
  std::vector<double> inv_pivot_;  // 1 / U_jj: the backward solve multiplies (no divisions)
  // Nonzero extents of the factors, per column j: rows [l_first_[j], l_last_[j]] of L below
  // the diagonal (empty when l_last_[j] < l_first_[j]) and rows [u_first_[j], j] of U.
  std::vector<int> l_first_, l_last_, u_first_;
  // Structural pattern (SetPattern) and its working copies during Factorize().
  std::vector<int> pattern_row_last_, pattern_col_last_, row_last_, col_last_;
  std::vector<int> update_cols_;  // Factorize(): the columns one pivot row updates
  // True when every entry outside the extents above is zero (set by a successful
  // Factorize() and by SetZero(), cleared by any write access through At()).
  bool extents_valid_ = false;
  double max_pivot_ = 0.0, min_pivot_ = 0.0;
  int determinant_sign_ = 0;
};

// Reverse Cuthill-McKee ordering of an undirected graph given as adjacency lists.
// Returns perm with perm[old] = new. Handles disconnected graphs.
std::vector<int> ReverseCuthillMcKee(const std::vector<std::vector<int>>& adjacency);

}  // namespace screwfem
