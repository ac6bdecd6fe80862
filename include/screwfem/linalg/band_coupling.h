// Entries of a matrix outside the band of a BandedLU, on a few blocks of unknowns, and the
// solve of the whole matrix by the Woodbury identity (docs/numerics.md, "Pairs and the band";
// option (ii) of docs/numerics.md, "Contact").
//
// The whole matrix is A + P E P^T: A the banded matrix (BandedLU), P (n x k) the selection of
// the k coupled unknowns (block_size consecutive unknowns per block in use), E (k x k) the
// entries among them that are stored here (block-sparse: only the block pairs given to Add).
// With y = A^-1 b,
//   (A + P E P^T)^-1 b = y - A^-1 P c,   c = G^-1 E P^T y,   G = I + E W,   W = P^T A^-1 P,
// which holds for any E (E need not be invertible) and any P (two blocks may overlap: an
// unknown then appears twice in P, and the entries at one position are the sum of both).
// det(A + P E P^T) = det(A) det(G) (Sylvester's determinant identity), so G is singular
// exactly when A + P E P^T is (for a nonsingular A); a G that is singular or not finite while
// the whole matrix is regular means that A's factorisation is unsuitable (nearly singular A).
//
// Cost: Factorize makes k banded solves (W, one unit vector each), the block-sparse product
// E W (4 x 36 x k multiply-adds per stored 6 x 6 block pair) and the dense LU of G with
// partial pivoting (k^3 / 3); Correct makes the products E P^T y, the triangular solves with
// G (k^2) and one banded solve. Storage: Resize allocates 3 k_max^2 + 2 k_max + n doubles
// (k_max = block_size x max_blocks) and 3 max_blocks^2 + k_max + max_blocks + n indices;
// nothing allocates afterwards.
#pragma once

#include <Eigen/Core>
#include <cassert>
#include <vector>

#include "screwfem/linalg/banded_lu.h"
#include "screwfem/linalg/sparse_lu.h"

namespace screwfem {

class BandCoupling {
 public:
  // n unknowns; room for max_blocks blocks of block_size consecutive unknowns. Allocates;
  // removes every entry.
  void Resize(int n, int block_size, int max_blocks);
  // Removes every entry (cost: the blocks used, not n). Keeps the storage.
  void Clear();
  // Entries (p_i + r, p_j + c) += scale * B(r, c), with p_i, p_j the first unknowns of two
  // blocks (band-order indices; any start with 0 <= start and start + block_size <= n; B is
  // block_size x block_size). Returns false, adding nothing, when a new block would exceed
  // max_blocks (overflowed() then stays true until Clear()). Invalidates Factorize().
  template <class M>
  bool Add(int p_i, int p_j, const Eigen::MatrixBase<M>& B, double scale) {
    assert(B.rows() == block_size_ && B.cols() == block_size_);
    const int pair = ReservePair(p_i, p_j);
    if (pair < 0) return false;
    const int row0 = block_size_ * pair_slots_[static_cast<std::size_t>(2 * pair)];
    const int col0 = block_size_ * pair_slots_[static_cast<std::size_t>(2 * pair + 1)];
    for (int c = 0; c < block_size_; ++c)
      for (int r = 0; r < block_size_; ++r) e_(row0 + r, col0 + c) += scale * B(r, c);
    return true;
  }

  int size() const { return n_; }
  int block_size() const { return block_size_; }
  int blocks() const { return blocks_; }      // blocks in use
  bool empty() const { return pairs_ == 0; }  // no entries
  bool overflowed() const { return overflowed_; }
  int max_blocks() const { return max_blocks_; }

  // After a successful A.Factorize() (A of size n): W and the LU of G (partial pivoting, in
  // the preallocated storage). false when G has an exact zero pivot (singular) or a value
  // that is not finite. Nothing to do (true) when empty.
  bool Factorize(const BandedLU& A);
  bool Factorize(const SparseLU& A);  // the same with the sparse LU as A
  // x holds A^-1 b (A.Solve already applied): overwrites it with (A + P E P^T)^-1 b.
  // Precondition: Factorize(A) returned true and no entry was added since. Nothing to do when
  // empty.
  void Correct(const BandedLU& A, Eigen::Ref<Eigen::VectorXd> x);
  void Correct(const SparseLU& A, Eigen::Ref<Eigen::VectorXd> x);
  // Sign of det(G) of the last successful Factorize (+1 or -1; +1 when empty), so that
  // det(A + P E P^T) has the sign A.determinant_sign() * determinant_sign().
  int determinant_sign() const { return determinant_sign_; }

  // f(i, j, value) for every stored entry (i, j band-order indices; every entry of each
  // stored block pair, zeros included). A position covered by two overlapping blocks can be
  // reported twice: the matrix entry is the sum.
  template <class F>
  void ForEachEntry(F&& f) const {
    for (int p = 0; p < pairs_; ++p) {
      const int si = pair_slots_[static_cast<std::size_t>(2 * p)];
      const int sj = pair_slots_[static_cast<std::size_t>(2 * p + 1)];
      const int i0 = block_start_[static_cast<std::size_t>(si)];
      const int j0 = block_start_[static_cast<std::size_t>(sj)];
      for (int c = 0; c < block_size_; ++c)
        for (int r = 0; r < block_size_; ++r)
          f(i0 + r, j0 + c, e_(si * block_size_ + r, sj * block_size_ + c));
    }
  }

 private:
  // The index of the block pair (p_i, p_j), new if needed; -1 (nothing added, overflowed_
  // set) when the blocks do not fit.
  int ReservePair(int p_i, int p_j);
  template <class LU>
  bool FactorizeWith(const LU& A);
  template <class LU>
  void CorrectWith(const LU& A, Eigen::Ref<Eigen::VectorXd> x);

  int n_ = 0, block_size_ = 0, max_blocks_ = 0;
  int blocks_ = 0;  // slots in use: slot s holds unknowns block_start_[s] + [0, block_size)
  int pairs_ = 0;   // block pairs in use
  bool overflowed_ = false;
  bool factorized_ = true;  // Factorize() is up to date with the entries
  int determinant_sign_ = 1;
  std::vector<int> slot_of_start_;  // size n: block start -> slot, -1 when unused
  std::vector<int> block_start_;    // size max_blocks: slot -> first unknown
  std::vector<int> pair_of_slots_;  // max_blocks^2: (slot_i, slot_j) -> pair index, or -1
  std::vector<int> pair_slots_;     // 2 max_blocks^2: pair -> (slot_i, slot_j)
  std::vector<int> pivot_;          // k_max: row interchanges of the LU of G
  Eigen::MatrixXd e_;               // k_max x k_max: E (slot-major rows and columns)
  Eigen::MatrixXd w_;               // k_max x k_max: W = P^T A^-1 P
  Eigen::MatrixXd lu_;            // k_max x k_max: G = I + E W, then its LU factors (L unit lower)
  Eigen::VectorXd work_n_;        // n: banded solves
  Eigen::VectorXd work_k_, t_k_;  // k_max: P^T y, then E P^T y and c
};

}  // namespace screwfem
