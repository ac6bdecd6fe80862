#include "screwfem/linalg/band_coupling.h"

#include <cmath>
#include <utility>

namespace screwfem {

void BandCoupling::Resize(int n, int block_size, int max_blocks) {
  assert(n >= 0 && block_size > 0 && max_blocks >= 0);
  n_ = n;
  block_size_ = block_size;
  max_blocks_ = max_blocks;
  const int k_max = block_size * max_blocks;
  const std::size_t pair_capacity =
      static_cast<std::size_t>(max_blocks) * static_cast<std::size_t>(max_blocks);
  slot_of_start_.assign(static_cast<std::size_t>(n), -1);
  block_start_.assign(static_cast<std::size_t>(max_blocks), 0);
  pair_of_slots_.assign(pair_capacity, -1);
  pair_slots_.assign(2 * pair_capacity, 0);
  pivot_.assign(static_cast<std::size_t>(k_max), 0);
  e_.setZero(k_max, k_max);
  w_.setZero(k_max, k_max);
  lu_.setZero(k_max, k_max);
  work_n_.setZero(n);
  work_k_.setZero(k_max);
  t_k_.setZero(k_max);
  blocks_ = 0;
  pairs_ = 0;
  overflowed_ = false;
  factorized_ = true;
  determinant_sign_ = 1;
}

void BandCoupling::Clear() {
  for (int s = 0; s < blocks_; ++s)
    slot_of_start_[static_cast<std::size_t>(block_start_[static_cast<std::size_t>(s)])] = -1;
  const int bs = block_size_;
  for (int p = 0; p < pairs_; ++p) {
    const int si = pair_slots_[static_cast<std::size_t>(2 * p)];
    const int sj = pair_slots_[static_cast<std::size_t>(2 * p + 1)];
    pair_of_slots_[static_cast<std::size_t>(si * max_blocks_ + sj)] = -1;
    e_.block(si * bs, sj * bs, bs, bs).setZero();
  }
  blocks_ = 0;
  pairs_ = 0;
  overflowed_ = false;
  factorized_ = true;
  determinant_sign_ = 1;
}

int BandCoupling::ReservePair(int p_i, int p_j) {
  assert(0 <= p_i && p_i + block_size_ <= n_ && 0 <= p_j && p_j + block_size_ <= n_);
  int si = slot_of_start_[static_cast<std::size_t>(p_i)];
  int sj = slot_of_start_[static_cast<std::size_t>(p_j)];
  const int needed = (si < 0 ? 1 : 0) + (sj < 0 && p_j != p_i ? 1 : 0);
  if (blocks_ + needed > max_blocks_) {
    overflowed_ = true;
    return -1;
  }
  if (si < 0) {
    si = blocks_++;
    block_start_[static_cast<std::size_t>(si)] = p_i;
    slot_of_start_[static_cast<std::size_t>(p_i)] = si;
  }
  if (p_j == p_i) {
    sj = si;
  } else if (sj < 0) {
    sj = blocks_++;
    block_start_[static_cast<std::size_t>(sj)] = p_j;
    slot_of_start_[static_cast<std::size_t>(p_j)] = sj;
  }
  int& pair = pair_of_slots_[static_cast<std::size_t>(si * max_blocks_ + sj)];
  if (pair < 0) {
    pair = pairs_++;
    pair_slots_[static_cast<std::size_t>(2 * pair)] = si;
    pair_slots_[static_cast<std::size_t>(2 * pair + 1)] = sj;
  }
  factorized_ = false;
  return pair;
}

template <class LU>
bool BandCoupling::FactorizeWith(const LU& A) {
  assert(A.size() == n_);
  determinant_sign_ = 1;
  factorized_ = false;
  if (pairs_ == 0) {
    factorized_ = true;
    return true;
  }
  const int bs = block_size_;
  const int k = bs * blocks_;
  // W = P^T A^-1 P: column m is A^-1 at the m-th coupled unknown, read at every coupled one.
  for (int m = 0; m < k; ++m) {
    work_n_.setZero();
    work_n_(block_start_[static_cast<std::size_t>(m / bs)] + m % bs) = 1.0;
    A.Solve(work_n_);
    for (int s = 0; s < blocks_; ++s) {
      const int start = block_start_[static_cast<std::size_t>(s)];
      for (int r = 0; r < bs; ++r) w_(s * bs + r, m) = work_n_(start + r);
    }
  }
  // G = I + E W, E block by block (only the stored block pairs).
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) lu_(i, j) = i == j ? 1.0 : 0.0;
  for (int p = 0; p < pairs_; ++p) {
    const int row0 = bs * pair_slots_[static_cast<std::size_t>(2 * p)];
    const int col0 = bs * pair_slots_[static_cast<std::size_t>(2 * p + 1)];
    for (int j = 0; j < k; ++j)
      for (int c = 0; c < bs; ++c) {
        const double w = w_(col0 + c, j);
        if (w == 0.0) continue;
        for (int r = 0; r < bs; ++r) lu_(row0 + r, j) += e_(row0 + r, col0 + c) * w;
      }
  }
  // LU of G with partial pivoting (right-looking, Golub & Van Loan Alg. 3.4.1): L unit lower
  // and U overwrite G; pivot_[j] is the row swapped with row j at step j.
  int sign = 1;
  for (int j = 0; j < k; ++j) {
    int p = j;
    double best = std::abs(lu_(j, j));
    for (int i = j + 1; i < k; ++i)
      if (std::abs(lu_(i, j)) > best) {
        best = std::abs(lu_(i, j));
        p = i;
      }
    pivot_[static_cast<std::size_t>(j)] = p;
    if (!(best > 0.0) || !std::isfinite(best)) return false;  // zero, NaN or infinite pivot
    if (p != j) {
      for (int c = 0; c < k; ++c) std::swap(lu_(j, c), lu_(p, c));
      sign = -sign;
    }
    if (lu_(j, j) < 0.0) sign = -sign;
    const double inv = 1.0 / lu_(j, j);
    for (int i = j + 1; i < k; ++i) lu_(i, j) *= inv;
    for (int c = j + 1; c < k; ++c) {
      const double ujc = lu_(j, c);
      if (ujc == 0.0) continue;
      for (int i = j + 1; i < k; ++i) lu_(i, c) -= lu_(i, j) * ujc;
    }
  }
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i)
      if (!std::isfinite(lu_(i, j))) return false;
  determinant_sign_ = sign;
  factorized_ = true;
  return true;
}

template <class LU>
void BandCoupling::CorrectWith(const LU& A, Eigen::Ref<Eigen::VectorXd> x) {
  if (pairs_ == 0) return;
  assert(factorized_ && A.size() == n_ && x.size() == n_);
  const int bs = block_size_;
  const int k = bs * blocks_;
  // work_k_ = P^T y, t_k_ = E P^T y.
  for (int s = 0; s < blocks_; ++s) {
    const int start = block_start_[static_cast<std::size_t>(s)];
    for (int r = 0; r < bs; ++r) work_k_(s * bs + r) = x(start + r);
  }
  for (int i = 0; i < k; ++i) t_k_(i) = 0.0;
  for (int p = 0; p < pairs_; ++p) {
    const int row0 = bs * pair_slots_[static_cast<std::size_t>(2 * p)];
    const int col0 = bs * pair_slots_[static_cast<std::size_t>(2 * p + 1)];
    for (int c = 0; c < bs; ++c) {
      const double v = work_k_(col0 + c);
      for (int r = 0; r < bs; ++r) t_k_(row0 + r) += e_(row0 + r, col0 + c) * v;
    }
  }
  // c = G^-1 t_k_: the interchanges, L (unit lower), U.
  for (int j = 0; j < k; ++j) {
    const int p = pivot_[static_cast<std::size_t>(j)];
    if (p != j) std::swap(t_k_(j), t_k_(p));
  }
  for (int j = 0; j < k; ++j) {
    const double tj = t_k_(j);
    if (tj == 0.0) continue;
    for (int i = j + 1; i < k; ++i) t_k_(i) -= lu_(i, j) * tj;
  }
  for (int j = k - 1; j >= 0; --j) {
    t_k_(j) /= lu_(j, j);
    const double tj = t_k_(j);
    if (tj == 0.0) continue;
    for (int i = 0; i < j; ++i) t_k_(i) -= lu_(i, j) * tj;
  }
  // x = y - A^-1 P c.
  work_n_.setZero();
  for (int s = 0; s < blocks_; ++s) {
    const int start = block_start_[static_cast<std::size_t>(s)];
    for (int r = 0; r < bs; ++r) work_n_(start + r) += t_k_(s * bs + r);
  }
  A.Solve(work_n_);
  x -= work_n_;
}

bool BandCoupling::Factorize(const BandedLU& A) { return FactorizeWith(A); }
bool BandCoupling::Factorize(const SparseLU& A) { return FactorizeWith(A); }
void BandCoupling::Correct(const BandedLU& A, Eigen::Ref<Eigen::VectorXd> x) { CorrectWith(A, x); }
void BandCoupling::Correct(const SparseLU& A, Eigen::Ref<Eigen::VectorXd> x) { CorrectWith(A, x); }

}  // namespace screwfem
