#include "screwfem/solve/banded_lu.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <queue>

namespace screwfem {

void BandedLU::Resize(int n, int kl, int ku) {
  n_ = n;
  kl_ = kl;
  ku_ = ku;
  kv_ = kl + ku;
  ldab_ = 2 * kl + ku + 1;
  ab_.assign(static_cast<std::size_t>(ldab_) * static_cast<std::size_t>(std::max(n, 1)), 0.0);
  ipiv_.assign(static_cast<std::size_t>(std::max(n, 1)), 0);
}

void BandedLU::SetZero() { std::fill(ab_.begin(), ab_.end(), 0.0); }

int BandedLU::Factorize() {
  max_pivot_ = 0.0;
  min_pivot_ = n_ > 0 ? INFINITY : 0.0;
  // Column j+kv of the fill-in region must start at zero: SetZero() before assembly does it.
  int ju = 0;  // last column touched by the row interchanges so far
  for (int j = 0; j < n_; ++j) {
    const int km = std::min(kl_, n_ - 1 - j);
    // Pivot search in column j, rows j .. j+km.
    int p = j;
    double best = std::abs(At(j, j));
    for (int i = j + 1; i <= j + km; ++i) {
      const double a = std::abs(At(i, j));
      if (a > best) {
        best = a;
        p = i;
      }
    }
    ipiv_[static_cast<std::size_t>(j)] = p;
    if (best == 0.0) return j;
    max_pivot_ = std::max(max_pivot_, best);
    min_pivot_ = std::min(min_pivot_, best);
    ju = std::max(ju, std::min(p + ku_, n_ - 1));
    if (p != j) {
      for (int c = j; c <= ju; ++c) std::swap(At(p, c), At(j, c));
    }
    if (km > 0) {
      const double inv = 1.0 / At(j, j);
      for (int i = j + 1; i <= j + km; ++i) At(i, j) *= inv;
      for (int c = j + 1; c <= ju; ++c) {
        const double ujc = At(j, c);
        if (ujc == 0.0) continue;
        for (int i = j + 1; i <= j + km; ++i) At(i, c) -= At(i, j) * ujc;
      }
    }
  }
  return -1;
}

void BandedLU::Solve(Eigen::Ref<Eigen::VectorXd> b) const {
  assert(b.size() == n_);
  // Forward: apply the interchanges and L.
  for (int j = 0; j < n_ - 1; ++j) {
    const int lm = std::min(kl_, n_ - 1 - j);
    const int p = ipiv_[static_cast<std::size_t>(j)];
    if (p != j) std::swap(b(p), b(j));
    const double bj = b(j);
    if (bj == 0.0) continue;
    for (int i = j + 1; i <= j + lm; ++i) b(i) -= At(i, j) * bj;
  }
  // Backward: U has kl + ku super-diagonals.
  for (int j = n_ - 1; j >= 0; --j) {
    if (b(j) == 0.0) continue;
    b(j) /= At(j, j);
    const double bj = b(j);
    for (int i = std::max(0, j - kv_); i < j; ++i) b(i) -= At(i, j) * bj;
  }
}

std::vector<int> ReverseCuthillMcKee(const std::vector<std::vector<int>>& adjacency) {
  const int n = static_cast<int>(adjacency.size());
  std::vector<int> degree(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) degree[static_cast<std::size_t>(i)] =
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
      if (start < 0 || degree[static_cast<std::size_t>(i)] < degree[static_cast<std::size_t>(start)])
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
