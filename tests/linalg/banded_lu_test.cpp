// Tests of the banded LU factorisation (checked against Eigen's dense PartialPivLU) and of the
// reverse Cuthill-McKee ordering.
#include "screwfem/linalg/banded_lu.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include "linalg/band_matrix.h"

namespace screwfem::banded_lu_test {
namespace {

using band_matrix::Load;

Eigen::MatrixXd RandomBanded(std::mt19937& rng, int n, int kl, int ku) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = std::max(0, j - ku); i <= std::min(n - 1, j + kl); ++i) A(i, j) = u(rng);
  return A;
}

// Half-bandwidths (lower, upper) of a dense matrix.
std::pair<int, int> Bandwidths(const Eigen::MatrixXd& A) {
  int kl = 0, ku = 0;
  for (int j = 0; j < A.cols(); ++j)
    for (int i = 0; i < A.rows(); ++i)
      if (A(i, j) != 0.0) {
        kl = std::max(kl, i - j);
        ku = std::max(ku, j - i);
      }
  return {kl, ku};
}

// Solves with BandedLU and with dense PartialPivLU; returns the relative difference of the
// solutions divided by the 2-norm condition number of A (forward error bound of a backward
// stable solver: O(eps cond(A))) and, through *residual, the relative residual of the banded
// solution (backward error: O(eps)).
double CompareWithDense(const Eigen::MatrixXd& A, int kl, int ku, const Eigen::VectorXd& b,
                        double* residual) {
  BandedLU lu;
  Load(A, kl, ku, &lu);
  EXPECT_EQ(lu.Factorize(), -1);
  Eigen::VectorXd x = b;
  lu.Solve(x);
  const Eigen::VectorXd ref = A.partialPivLu().solve(b);
  *residual = (A * x - b).norm() / (A.norm() * x.norm());
  const Eigen::VectorXd sv = A.jacobiSvd().singularValues();
  const double cond = sv(0) / sv(sv.size() - 1);
  return (x - ref).norm() / ref.norm() / cond;
}

TEST(BandedLU, MatchesDenseLUOnRandomBandedMatrices) {
  std::mt19937 rng(7);
  const struct {
    int n, kl, ku;
  } shapes[] = {{1, 0, 0},  {5, 0, 0},    {8, 1, 1},  {20, 2, 5}, {20, 5, 2},
                {40, 7, 7}, {60, 11, 11}, {33, 0, 4}, {33, 4, 0}, {12, 11, 11}};
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const auto& s : shapes) {
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::MatrixXd A =
          RandomBanded(rng, s.n, s.kl, s.ku) +
          (s.kl == 0 && s.ku == 0 ? 1.0 : 0.0) * Eigen::MatrixXd::Identity(s.n, s.n);
      Eigen::VectorXd b(s.n);
      for (int i = 0; i < s.n; ++i) b(i) = normal(rng);
      double residual = 0.0;
      EXPECT_LT(CompareWithDense(A, s.kl, s.ku, b, &residual), 1e-13)
          << "n " << s.n << " kl " << s.kl << " ku " << s.ku;
      EXPECT_LT(residual, 1e-14) << "n " << s.n << " kl " << s.kl << " ku " << s.ku;
    }
  }
}

// determinant_sign(): the sign of det A (the product of U's diagonal and -1 per row
// interchange) against the dense determinant, over random banded matrices of both signs.
TEST(BandedLU, DeterminantSignMatchesTheDenseDeterminant) {
  std::mt19937 rng(11);
  int negative = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 3 + trial % 9, kl = 1 + trial % 3, ku = 2;
    const Eigen::MatrixXd A = RandomBanded(rng, n, kl, ku);
    BandedLU lu;
    Load(A, kl, ku, &lu);
    ASSERT_EQ(lu.Factorize(), -1);
    const double det = A.determinant();
    EXPECT_EQ(lu.determinant_sign(), det > 0.0 ? 1 : -1) << "trial " << trial;
    negative += det < 0.0;
  }
  EXPECT_GT(negative, 5);
  BandedLU singular;
  Load(Eigen::MatrixXd::Zero(3, 3), 1, 1, &singular);
  EXPECT_EQ(singular.Factorize(), 0);
  EXPECT_EQ(singular.determinant_sign(), 0);
}

TEST(BandedLU, PivotsOverZeroDiagonalEntries) {
  // Every diagonal entry zero: the factorisation works only through row interchanges, and the
  // upper band of U grows to kl + ku.
  std::mt19937 rng(8);
  for (const int kl : {1, 3, 6}) {
    const int n = 30, ku = kl;
    Eigen::MatrixXd A = RandomBanded(rng, n, kl, ku);
    A.diagonal().setZero();
    Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    double residual = 0.0;
    EXPECT_LT(CompareWithDense(A, kl, ku, b, &residual), 1e-13) << "kl " << kl;
    EXPECT_LT(residual, 1e-14) << "kl " << kl;
  }
}

TEST(BandedLU, SolvesBandedSaddlePointSystems) {
  // A chain of blocks [K_i  B_i^T; B_i 0] as the static solver assembles them: 6 unknowns per
  // node, 2 constraint rows between consecutive nodes, interleaved so the system is banded
  // with zero diagonal entries on the multiplier rows.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int nodes = 10, nx = 6, nl = 2, stride = nx + nl;
  const int n = nodes * nx + (nodes - 1) * nl;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < nodes; ++k) {
    const int p = k * stride;
    Eigen::MatrixXd M(nx, nx);
    for (int i = 0; i < nx; ++i)
      for (int j = 0; j < nx; ++j) M(i, j) = u(rng);
    A.block(p, p, nx, nx) = M * M.transpose() + 0.1 * Eigen::MatrixXd::Identity(nx, nx);
    if (k + 1 < nodes) {
      // Coupling stiffness between consecutive nodes and the constraint rows after node k.
      for (int i = 0; i < nx; ++i)
        for (int j = 0; j < nx; ++j)
          A(p + i, p + stride + j) = A(p + stride + j, p + i) = 0.3 * u(rng);
      for (int r = 0; r < nl; ++r)
        for (int j = 0; j < nx; ++j) {
          const double ba = u(rng), bb = u(rng);
          A(p + nx + r, p + j) = A(p + j, p + nx + r) = ba;
          A(p + nx + r, p + stride + j) = A(p + stride + j, p + nx + r) = bb;
        }
    }
  }
  const auto [kl, ku] = Bandwidths(A);
  EXPECT_LT(kl, n / 4);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1.0, -3.0);
  double residual = 0.0;
  EXPECT_LT(CompareWithDense(A, kl, ku, b, &residual), 1e-13);
  EXPECT_LT(residual, 1e-14);
}

// SolveTransposed: A^T x = b against the dense LU of A^T, on random banded matrices and on
// matrices whose diagonal is zero (every pivot an interchange), with a structural pattern.
TEST(BandedLU, TransposedSolveMatchesDenseLUOfTheTranspose) {
  std::mt19937 rng(21);
  const struct {
    int n, kl, ku;
    bool zero_diagonal;
  } shapes[] = {{1, 0, 0, false},  {8, 1, 1, false}, {20, 2, 5, false},
                {20, 5, 2, false}, {30, 3, 3, true}, {40, 7, 7, true}};
  for (const auto& s : shapes) {
    Eigen::MatrixXd A = RandomBanded(rng, s.n, s.kl, s.ku);
    if (s.zero_diagonal) A.diagonal().setZero();
    if (s.n == 1) A(0, 0) = 2.0;
    BandedLU lu;
    Load(A, s.kl, s.ku, &lu);
    ASSERT_EQ(lu.Factorize(), -1);
    Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(s.n, -1.0, 2.0);
    const Eigen::VectorXd b = x;
    lu.SolveTransposed(x);
    const Eigen::VectorXd ref = A.transpose().partialPivLu().solve(b);
    EXPECT_LT((A.transpose() * x - b).norm(), 1e-13 * A.norm() * x.norm()) << s.n;
    EXPECT_LT((x - ref).norm(), 1e-10 * ref.norm()) << s.n;
    // y^T (A x) = (A^T y)^T x: the adjoint identity the sensitivities rely on.
    Eigen::VectorXd z = b.reverse();
    lu.Solve(z);
    EXPECT_NEAR(x.dot(b.reverse()), b.dot(z), 1e-12 * std::abs(b.dot(z)) + 1e-14) << s.n;
  }
}

TEST(BandedLU, RefactorizesAfterSetZero) {
  // The workspace is reused by every Newton iteration: a second factorisation of another
  // matrix in the same storage must not see fill-in left over from the first one.
  std::mt19937 rng(10);
  const int n = 25, kl = 4, ku = 3;
  BandedLU lu;
  lu.Resize(n, kl, ku);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::MatrixXd A = RandomBanded(rng, n, kl, ku);
    A.diagonal().setZero();
    lu.SetZero();
    for (int j = 0; j < n; ++j)
      for (int i = std::max(0, j - ku); i <= std::min(n - 1, j + kl); ++i) lu.At(i, j) = A(i, j);
    ASSERT_EQ(lu.Factorize(), -1);
    Eigen::VectorXd x = Eigen::VectorXd::Ones(n);
    lu.Solve(x);
    EXPECT_LT((A * x - Eigen::VectorXd::Ones(n)).norm(), 1e-12 * A.norm() * x.norm());
  }
}

// A block-sparse saddle-point matrix like the assembled systems: a chain of 6-blocks (nodes)
// with 2-row constraint blocks (zero diagonal) between them, and its structural pattern
// (last position each row and column can reach).
Eigen::MatrixXd BlockChain(std::mt19937& rng, int nodes, std::vector<int>* last) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int nx = 6, nl = 2, stride = nx + nl;
  const int n = nodes * nx + (nodes - 1) * nl;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  last->assign(static_cast<std::size_t>(n), 0);
  for (int k = 0; k < nodes; ++k) {
    const int p = k * stride;
    for (int i = 0; i < nx; ++i)
      for (int j = 0; j < nx; ++j) A(p + i, p + j) = (i == j ? 2.0 : 0.0) + 0.3 * u(rng);
    // Constraint rows after node k couple node k and node k + 1 (a few zero entries inside).
    const int node_end = k + 1 < nodes ? p + stride + nx - 1 : p + nx - 1;
    for (int i = 0; i < nx; ++i)
      (*last)[static_cast<std::size_t>(p + i)] = std::min(n - 1, p + nx + nl - 1);
    if (k + 1 < nodes) {
      for (int r = 0; r < nl; ++r) {
        (*last)[static_cast<std::size_t>(p + nx + r)] = node_end;
        for (int j = 0; j < 2 * nx + nl; ++j) {
          if (j >= nx && j < nx + nl) continue;  // zero block on the multiplier rows
          const double b = (j + r) % 4 == 0 ? 0.0 : u(rng);
          A(p + nx + r, p + j) = A(p + j, p + nx + r) = b;
        }
      }
      for (int i = 0; i < nx; ++i)
        (*last)[static_cast<std::size_t>(p + stride + i)] =
            std::min(n - 1, p + stride + nx + nl - 1);
    }
  }
  return A;
}

TEST(BandedLU, StructuralPatternGivesTheSameSolutionsAsTheFullBand) {
  // SetPattern only skips operations on zeros: the results are identical, bit for bit, to the
  // full-band factorisation of the same matrix, factorisation after factorisation.
  std::mt19937 rng(15);
  std::vector<int> last;
  Eigen::MatrixXd A = BlockChain(rng, 12, &last);
  const int n = static_cast<int>(A.rows());
  const auto [kl, ku] = Bandwidths(A);
  BandedLU full, sparse;
  full.Resize(n, kl, ku);
  sparse.Resize(n, kl, ku);
  sparse.SetPattern(last, last);
  for (int trial = 0; trial < 3; ++trial) {
    if (trial > 0) A = BlockChain(rng, 12, &last);
    for (BandedLU* lu : {&full, &sparse}) {
      lu->SetZero();
      for (int j = 0; j < n; ++j)
        for (int i = std::max(0, j - ku); i <= std::min(n - 1, j + kl); ++i)
          if (A(i, j) != 0.0) lu->At(i, j) = A(i, j);
      ASSERT_EQ(lu->Factorize(), -1);
    }
    Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0), y = x;
    full.Solve(x);
    sparse.Solve(y);
    for (int i = 0; i < n; ++i) EXPECT_EQ(x(i), y(i)) << "trial " << trial << ", entry " << i;
    EXPECT_LT((A * y - Eigen::VectorXd::LinSpaced(n, -1.0, 2.0)).norm(),
              1e-12 * A.norm() * y.norm());
  }
}

// The band algorithm without any skipping (LAPACK's dgbtf2 and dgbtrs on a dense copy): the
// same pivot choice (first largest |a|), multipliers scaled by the reciprocal pivot, every
// update of the trailing matrix in the same order. Returns the solution of A x = b.
Eigen::VectorXd DenseBandReference(Eigen::MatrixXd A, int kl, Eigen::VectorXd x) {
  const int n = static_cast<int>(A.rows());
  std::vector<int> piv(static_cast<std::size_t>(n));
  Eigen::VectorXd inv(n);
  for (int j = 0; j < n; ++j) {
    int p = j;
    for (int i = j + 1; i <= std::min(n - 1, j + kl); ++i)
      if (std::abs(A(i, j)) > std::abs(A(p, j))) p = i;
    piv[static_cast<std::size_t>(j)] = p;
    A.row(j).tail(n - j).swap(A.row(p).tail(n - j));  // L's columns stay (as in dgbtf2)
    inv(j) = 1.0 / A(j, j);
    for (int i = j + 1; i < n; ++i) A(i, j) *= inv(j);
    for (int c = j + 1; c < n; ++c)
      for (int i = j + 1; i < n; ++i) A(i, c) -= A(i, j) * A(j, c);
  }
  for (int j = 0; j < n; ++j) {
    std::swap(x(j), x(piv[static_cast<std::size_t>(j)]));
    for (int i = j + 1; i < n; ++i) x(i) -= A(i, j) * x(j);
  }
  for (int j = n - 1; j >= 0; --j) {
    x(j) *= inv(j);
    for (int i = 0; i < j; ++i) x(i) -= A(i, j) * x(j);
  }
  return x;
}

TEST(BandedLU, SkipsOnlyExactZerosAgainstTheDenseBandAlgorithm) {
  // Every operation Factorize() and Solve() skip (zeros of the pattern, zero multipliers,
  // zero entries of the pivot row, rows and columns beyond the extents they track) would
  // subtract an exact zero: the solutions equal those of the dense algorithm bit for bit,
  // on block saddle-point matrices with pivoting over their zero diagonal blocks.
  std::mt19937 rng(17);
  for (int trial = 0; trial < 4; ++trial) {
    std::vector<int> last;
    const Eigen::MatrixXd A = BlockChain(rng, 6 + 3 * trial, &last);
    const int n = static_cast<int>(A.rows());
    const auto [kl, ku] = Bandwidths(A);
    BandedLU lu;
    Load(A, kl, ku, &lu);
    if (trial % 2 == 1) lu.SetPattern(last, last);
    ASSERT_EQ(lu.Factorize(), -1);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    Eigen::VectorXd x = b;
    lu.Solve(x);
    const Eigen::VectorXd ref = DenseBandReference(A, kl, b);
    for (int i = 0; i < n; ++i) EXPECT_EQ(x(i), ref(i)) << "trial " << trial << ", entry " << i;
  }
}

TEST(BandedLU, SetZeroAfterAFactorisationClearsEveryEntry) {
  // SetZero after a successful Factorize clears only the recorded extents of the factors:
  // every entry of the band, fill-in included, must be zero afterwards.
  std::mt19937 rng(16);
  std::vector<int> last;
  const Eigen::MatrixXd A = BlockChain(rng, 8, &last);
  const int n = static_cast<int>(A.rows());
  const auto [kl, ku] = Bandwidths(A);
  BandedLU lu;
  Load(A, kl, ku, &lu);
  lu.SetPattern(last, last);
  ASSERT_EQ(lu.Factorize(), -1);
  lu.SetZero();
  const BandedLU& zeroed = lu;
  for (int j = 0; j < n; ++j)
    for (int i = std::max(0, j - kl - ku); i <= std::min(n - 1, j + kl); ++i)
      EXPECT_EQ(zeroed.At(i, j), 0.0) << i << ", " << j;
}

TEST(BandedLU, SingularMatrixReportsTheZeroPivotColumn) {
  std::mt19937 rng(11);
  const int n = 20, kl = 3, ku = 2;
  for (const int zero_col : {0, 7, 19}) {
    Eigen::MatrixXd A = RandomBanded(rng, n, kl, ku);
    A.col(zero_col).setZero();
    BandedLU lu;
    Load(A, kl, ku, &lu);
    EXPECT_EQ(lu.Factorize(), zero_col);
  }
  BandedLU zero;
  zero.Resize(4, 1, 1);
  zero.SetZero();
  EXPECT_EQ(zero.Factorize(), 0);
}

TEST(BandedLU, ReportsPivotRange) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
  A.diagonal() << 2.0, -8.0, 0.5, 3.0;
  BandedLU lu;
  Load(A, 1, 1, &lu);
  ASSERT_EQ(lu.Factorize(), -1);
  EXPECT_EQ(lu.max_pivot(), 8.0);
  EXPECT_EQ(lu.min_pivot(), 0.5);
}

// ---- reverse Cuthill-McKee ----

bool IsPermutation(const std::vector<int>& perm) {
  std::vector<int> sorted = perm;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i)
    if (sorted[i] != static_cast<int>(i)) return false;
  return true;
}

int GraphBandwidth(const std::vector<std::vector<int>>& adj, const std::vector<int>& label) {
  int bw = 0;
  for (std::size_t v = 0; v < adj.size(); ++v)
    for (int w : adj[v]) bw = std::max(bw, std::abs(label[v] - label[static_cast<std::size_t>(w)]));
  return bw;
}

std::vector<std::vector<int>> ShuffledChains(std::mt19937& rng, const std::vector<int>& lengths,
                                             std::vector<int>* identity) {
  int n = 0;
  for (int len : lengths) n += len;
  std::vector<int> label(static_cast<std::size_t>(n));
  std::iota(label.begin(), label.end(), 0);
  std::shuffle(label.begin(), label.end(), rng);
  std::vector<std::vector<int>> adj(static_cast<std::size_t>(n));
  int start = 0;
  for (int len : lengths) {
    for (int i = start; i + 1 < start + len; ++i) {
      const int a = label[static_cast<std::size_t>(i)], b = label[static_cast<std::size_t>(i) + 1];
      adj[static_cast<std::size_t>(a)].push_back(b);
      adj[static_cast<std::size_t>(b)].push_back(a);
    }
    start += len;
  }
  identity->resize(static_cast<std::size_t>(n));
  std::iota(identity->begin(), identity->end(), 0);
  return adj;
}

TEST(ReverseCuthillMcKee, RestoresUnitBandwidthOfAShuffledChain) {
  std::mt19937 rng(12);
  std::vector<int> identity;
  const auto adj = ShuffledChains(rng, {60}, &identity);
  const std::vector<int> perm = ReverseCuthillMcKee(adj);
  ASSERT_EQ(perm.size(), adj.size());
  EXPECT_TRUE(IsPermutation(perm));
  EXPECT_GT(GraphBandwidth(adj, identity), 20);
  EXPECT_EQ(GraphBandwidth(adj, perm), 1);
}

TEST(ReverseCuthillMcKee, HandlesDisconnectedGraphsAndIsolatedVertices) {
  std::mt19937 rng(13);
  std::vector<int> identity;
  const auto adj = ShuffledChains(rng, {15, 1, 9, 1, 20}, &identity);
  const std::vector<int> perm = ReverseCuthillMcKee(adj);
  EXPECT_TRUE(IsPermutation(perm));
  EXPECT_EQ(GraphBandwidth(adj, perm), 1);
  EXPECT_TRUE(ReverseCuthillMcKee({}).empty());
}

TEST(ReverseCuthillMcKee, ReducesBandwidthOfAShuffledGrid) {
  // A 5 x 40 grid graph: the best ordering has bandwidth 5; RCM from a corner achieves about
  // that, a random labelling is far worse.
  std::mt19937 rng(14);
  const int w = 5, h = 40, n = w * h;
  std::vector<int> label(static_cast<std::size_t>(n));
  std::iota(label.begin(), label.end(), 0);
  std::shuffle(label.begin(), label.end(), rng);
  std::vector<std::vector<int>> adj(static_cast<std::size_t>(n));
  auto connect = [&](int a, int b) {
    const int la = label[static_cast<std::size_t>(a)], lb = label[static_cast<std::size_t>(b)];
    adj[static_cast<std::size_t>(la)].push_back(lb);
    adj[static_cast<std::size_t>(lb)].push_back(la);
  };
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      if (c + 1 < w) connect(r * w + c, r * w + c + 1);
      if (r + 1 < h) connect(r * w + c, (r + 1) * w + c);
    }
  std::vector<int> identity(static_cast<std::size_t>(n));
  std::iota(identity.begin(), identity.end(), 0);
  const std::vector<int> perm = ReverseCuthillMcKee(adj);
  EXPECT_TRUE(IsPermutation(perm));
  EXPECT_GT(GraphBandwidth(adj, identity), 100);
  EXPECT_LE(GraphBandwidth(adj, perm), 2 * w);
}

}  // namespace
}  // namespace screwfem::banded_lu_test
