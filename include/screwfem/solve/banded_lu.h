// Banded LU factorisation with partial pivoting (the algorithm of LAPACK's dgbtf2/dgbtrs),
// for the global saddle-point systems of screwfem after a bandwidth-reducing ordering.
//
// Storage is allocated once by Resize(); Factorize() and Solve() never allocate. Partial
// pivoting keeps the indefinite constrained systems (zero blocks on the multiplier rows)
// stable; the upper bandwidth grows to kl + ku through row interchanges, as in LAPACK.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace screwfem {

class BandedLU {
 public:
  // n unknowns, kl sub-diagonals, ku super-diagonals of the matrix before pivoting.
  void Resize(int n, int kl, int ku);
  void SetZero();

  int size() const { return n_; }
  int lower_bandwidth() const { return kl_; }
  int upper_bandwidth() const { return ku_; }

  // True when (i, j) lies inside the band of the unfactorised matrix.
  bool InBand(int i, int j) const { return i - j <= kl_ && j - i <= ku_; }
  // Entry (i, j); precondition InBand(i, j) (checked in debug builds).
  double& At(int i, int j) { return ab_[Index(i, j)]; }
  double At(int i, int j) const { return ab_[Index(i, j)]; }

  // Factorises in place. Returns -1 on success, or the first column whose pivot is exactly
  // zero (the matrix is singular).
  int Factorize();
  // Solves A x = b in place (b <- x) after a successful Factorize().
  void Solve(Eigen::Ref<Eigen::VectorXd> b) const;
  // Largest and smallest |U_jj| of the last factorisation (a cheap conditioning indicator).
  double max_pivot() const { return max_pivot_; }
  double min_pivot() const { return min_pivot_; }

 private:
  std::size_t Index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(ldab_) +
           static_cast<std::size_t>(kv_ + i - j);
  }

  int n_ = 0, kl_ = 0, ku_ = 0, kv_ = 0, ldab_ = 0;
  std::vector<double> ab_;
  std::vector<int> ipiv_;
  double max_pivot_ = 0.0, min_pivot_ = 0.0;
};

// Reverse Cuthill-McKee ordering of an undirected graph given as adjacency lists.
// Returns perm with perm[old] = new. Handles disconnected graphs.
std::vector<int> ReverseCuthillMcKee(const std::vector<std::vector<int>>& adjacency);

}  // namespace screwfem
