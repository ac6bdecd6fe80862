#include "screwfem/linalg/banded_lu.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <queue>

namespace screwfem {

namespace {
// y[0..n) -= x[0..n) * a, for two different columns of the band (they never overlap).
inline void SubtractScaled(double* __restrict y, const double* __restrict x, double a, int n) {
  for (int i = 0; i < n; ++i) y[i] -= x[i] * a;
}
// The same for two columns at once (x is read once for both).
inline void SubtractScaled2(double* __restrict y1, double* __restrict y2,
                            const double* __restrict x, double a1, double a2, int n) {
  for (int i = 0; i < n; ++i) {
    const double xi = x[i];
    y1[i] -= xi * a1;
    y2[i] -= xi * a2;
  }
}
}  // namespace

void BandedLU::Resize(int n, int kl, int ku) {
  n_ = n;
  kl_ = kl;
  ku_ = ku;
  kv_ = kl + ku;
  ldab_ = 2 * kl + ku + 1;
  const std::size_t size = static_cast<std::size_t>(std::max(n, 1));
  ab_.assign(static_cast<std::size_t>(ldab_) * size, 0.0);
  ipiv_.assign(size, 0);
  inv_pivot_.assign(size, 0.0);
  l_first_.assign(size, 0);
  l_last_.assign(size, -1);
  u_first_.assign(size, 0);
  pattern_row_last_.assign(size, 0);
  pattern_col_last_.assign(size, 0);
  row_last_.assign(size, 0);
  col_last_.assign(size, 0);
  update_cols_.assign(static_cast<std::size_t>(kv_ + 1), 0);
  for (int j = 0; j < n; ++j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    u_first_[sj] = j;
    pattern_row_last_[sj] = std::min(n - 1, j + ku);
    pattern_col_last_[sj] = std::min(n - 1, j + kl);
  }
  extents_valid_ = true;
}

void BandedLU::SetPattern(const std::vector<int>& row_last, const std::vector<int>& col_last) {
  assert(static_cast<int>(row_last.size()) == n_ && static_cast<int>(col_last.size()) == n_);
  for (int j = 0; j < n_; ++j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    pattern_row_last_[sj] = std::clamp(row_last[sj], j, std::min(n_ - 1, j + ku_));
    pattern_col_last_[sj] = std::clamp(col_last[sj], j, std::min(n_ - 1, j + kl_));
  }
}

void BandedLU::SetZero() {
  if (!extents_valid_) {
    std::fill(ab_.begin(), ab_.end(), 0.0);
  } else {
    // Only the recorded extents can hold nonzeros.
    for (int j = 0; j < n_; ++j) {
      const std::size_t sj = static_cast<std::size_t>(j);
      const int last = std::max(j, l_last_[sj]);
      double* col = &ab_[Index(u_first_[sj], j)];
      std::fill(col, col + (last - u_first_[sj] + 1), 0.0);
    }
  }
  for (int j = 0; j < n_; ++j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    l_first_[sj] = j + 1;
    l_last_[sj] = j;
    u_first_[sj] = j;
  }
  extents_valid_ = true;
}

// One function (about 100 lines): the column elimination is the hot loop of every step, and its
// extent bookkeeping, pivoting and updates share locals that splitting would pass around.
int BandedLU::Factorize() {
  extents_valid_ = false;
  max_pivot_ = 0.0;
  min_pivot_ = n_ > 0 ? INFINITY : 0.0;
  determinant_sign_ = 1;
  // Last column of row i (row_last_) and last row of column j (col_last_) that can be
  // nonzero: the pattern, widened below by the interchanges and the updates (structurally,
  // whatever the values).
  std::copy(pattern_row_last_.begin(), pattern_row_last_.end(), row_last_.begin());
  std::copy(pattern_col_last_.begin(), pattern_col_last_.end(), col_last_.begin());
  for (int j = 0; j < n_; ++j) u_first_[static_cast<std::size_t>(j)] = j;
  // Column j of the matrix starts at ab + j * ldab, entry (i, j) at offset kv + i - j: the
  // entries of a column are contiguous, those of a row are ldab - 1 apart.
  double* const ab = ab_.data();
  const std::ptrdiff_t row_stride = ldab_ - 1;
  // Column j+kv of the fill-in region must start at zero: SetZero() before assembly does it.
  int ju = 0;  // last column touched by the row interchanges so far (LAPACK's bound)
  for (int j = 0; j < n_; ++j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    // Rows j .. j+km of column j can be nonzero.
    const int km = std::min(kl_, col_last_[sj] - j);
    double* const diag = ab + Index(j, j);  // (j, j); (i, j) is diag[i - j]
    // Pivot search in column j (zero entries below row j + km never win).
    int p = j;
    double best = std::abs(diag[0]);
    for (int i = 1; i <= km; ++i) {
      const double a = std::abs(diag[i]);
      if (a > best) {
        best = a;
        p = j + i;
      }
    }
    ipiv_[sj] = p;
    if (best == 0.0) {
      determinant_sign_ = 0;
      return j;
    }
    // det = prod U_jj times -1 per row interchange; U_jj is the pivot found above.
    if ((p != j) != (diag[p - j] < 0.0)) determinant_sign_ = -determinant_sign_;
    max_pivot_ = std::max(max_pivot_, best);
    min_pivot_ = std::min(min_pivot_, best);
    ju = std::max(ju, std::min(p + ku_, n_ - 1));
    if (p != j) {
      // Rows j and p over the columns where either can be nonzero: (j, c) is
      // diag[(c - j) * row_stride]. Row j's entries move to row p.
      const std::size_t sp = static_cast<std::size_t>(p);
      const int last_j = std::min(row_last_[sj], ju);
      const int last = std::min(std::max(row_last_[sj], row_last_[sp]), ju);
      double* const row_p = diag + (p - j);
      for (std::ptrdiff_t c = 0; c <= last - j; ++c)
        std::swap(row_p[c * row_stride], diag[c * row_stride]);
      for (int c = j + 1; c <= last_j; ++c) {
        int& cl = col_last_[static_cast<std::size_t>(c)];
        cl = std::max(cl, p);
      }
      std::swap(row_last_[sj], row_last_[sp]);
    }
    // Multipliers, and the span [j+first, j+last] of the nonzero ones.
    int first = km + 1, last = 0;
    const double inv = 1.0 / diag[0];
    inv_pivot_[sj] = inv;
    if (km > 0) {
      for (int i = 1; i <= km; ++i) {
        if (diag[i] == 0.0) continue;
        diag[i] *= inv;
        first = std::min(first, i);
        last = i;
      }
    }
    l_first_[sj] = j + first;
    l_last_[sj] = j + last;
    // Rank-one update of the trailing columns c = j+1 .. (end of row j) with nonzero u_jc,
    // rows j+first .. j+last; their extents grow to cover it.
    const int row_end = std::min(row_last_[sj], ju);
    const int len = last - first + 1;
    int nu = 0;  // columns with nonzero u_jc, in update_cols_[0, nu)
    for (int c = j + 1; c <= row_end; ++c) {
      const std::size_t sc = static_cast<std::size_t>(c);
      if (diag[(c - j) * row_stride] == 0.0) continue;
      u_first_[sc] = std::min(u_first_[sc], j);
      col_last_[sc] = std::max(col_last_[sc], j + last);
      update_cols_[static_cast<std::size_t>(nu++)] = c - j;
    }
    if (len > 0) {
      const double* const l = diag + first;
      int k = 0;
      for (; k + 1 < nu; k += 2) {
        double* const c1 = diag + update_cols_[static_cast<std::size_t>(k)] * row_stride;
        double* const c2 = diag + update_cols_[static_cast<std::size_t>(k) + 1] * row_stride;
        SubtractScaled2(c1 + first, c2 + first, l, c1[0], c2[0], len);
      }
      if (k < nu) {
        double* const c1 = diag + update_cols_[static_cast<std::size_t>(k)] * row_stride;
        SubtractScaled(c1 + first, l, c1[0], len);
      }
    }
    // The update fills rows j+first .. j+last at the updated columns only: their extents
    // grow to the last of these (not to the end of row j, whose zeros fill nothing).
    const int fill_end = nu > 0 ? j + update_cols_[static_cast<std::size_t>(nu) - 1] : j;
    for (int i = j + first; i <= j + last; ++i) {
      int& rl = row_last_[static_cast<std::size_t>(i)];
      rl = std::max(rl, fill_end);
    }
  }
  extents_valid_ = true;
  return -1;
}

void BandedLU::Solve(Eigen::Ref<Eigen::VectorXd> b) const {
  assert(b.size() == n_);
  double* const x = b.data();
  // Forward: apply the interchanges and L (nonzero multipliers of column j only).
  for (int j = 0; j < n_ - 1; ++j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    const int p = ipiv_[sj];
    if (p != j) std::swap(x[p], x[j]);
    const double bj = x[j];
    if (bj == 0.0) continue;
    const int first = l_first_[sj];
    SubtractScaled(x + first, &ab_[Index(first, j)], bj, l_last_[sj] - first + 1);
  }
  // Backward: U has up to kl + ku super-diagonals; column j is nonzero from row u_first_[j].
  for (int j = n_ - 1; j >= 0; --j) {
    if (x[j] == 0.0) continue;
    x[j] *= inv_pivot_[static_cast<std::size_t>(j)];
    const int first = u_first_[static_cast<std::size_t>(j)];
    SubtractScaled(x + first, &ab_[Index(first, j)], x[j], j - first);
  }
}

void BandedLU::SolveTransposed(Eigen::Ref<Eigen::VectorXd> b) const {
  assert(b.size() == n_);
  double* const x = b.data();
  // A = P_0 L_0 ... P_{n-2} L_{n-2} U (Solve applies the inverse factors left to right), so
  // A^-T applies U^-T first, then (L_j^-1 P_j)^T = P_j (I - e_j l_j^T) for j = n-2 .. 0.
  for (int j = 0; j < n_; ++j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    const int first = u_first_[sj];
    const double* const u = &ab_[Index(first, j)];
    double s = x[j];
    for (int i = 0; i < j - first; ++i) s -= u[i] * x[first + i];
    x[j] = s * inv_pivot_[sj];
  }
  for (int j = n_ - 2; j >= 0; --j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    const int first = l_first_[sj];
    const int count = l_last_[sj] - first + 1;
    if (count > 0) {
      const double* const l = &ab_[Index(first, j)];
      double s = 0.0;
      for (int i = 0; i < count; ++i) s += l[i] * x[first + i];
      x[j] -= s;
    }
    const int p = ipiv_[sj];
    if (p != j) std::swap(x[p], x[j]);
  }
}

std::vector<int> ReverseCuthillMcKee(const std::vector<std::vector<int>>& adjacency) {
  const int n = static_cast<int>(adjacency.size());
  std::vector<int> degree(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    degree[static_cast<std::size_t>(i)] =
        static_cast<int>(adjacency[static_cast<std::size_t>(i)].size());
  std::vector<int> order;
  order.reserve(static_cast<std::size_t>(n));
  std::vector<char> visited(static_cast<std::size_t>(n), 0);
  std::vector<int> neighbours;
  while (static_cast<int>(order.size()) < n) {
    // Start each component at an unvisited vertex of minimum degree (a pseudo-peripheral
    // choice that is good enough for chains, trees and small loops).
    int start = -1;
    for (int i = 0; i < n; ++i) {
      if (visited[static_cast<std::size_t>(i)]) continue;
      if (start < 0 ||
          degree[static_cast<std::size_t>(i)] < degree[static_cast<std::size_t>(start)])
        start = i;
    }
    std::queue<int> queue;
    queue.push(start);
    visited[static_cast<std::size_t>(start)] = 1;
    while (!queue.empty()) {
      const int v = queue.front();
      queue.pop();
      order.push_back(v);
      neighbours.clear();
      for (int w : adjacency[static_cast<std::size_t>(v)])
        if (!visited[static_cast<std::size_t>(w)]) {
          visited[static_cast<std::size_t>(w)] = 1;
          neighbours.push_back(w);
        }
      std::sort(neighbours.begin(), neighbours.end(), [&](int a, int b) {
        return degree[static_cast<std::size_t>(a)] < degree[static_cast<std::size_t>(b)];
      });
      for (int w : neighbours) queue.push(w);
    }
  }
  std::vector<int> perm(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k)
    perm[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = n - 1 - k;
  return perm;
}

}  // namespace screwfem
