// Tests of the sparse LU (KLU): solutions and determinant signs against Eigen's dense LU, the
// pattern of dense blocks, the reuse of the symbolic analysis and the refactorisation with its
// fallback to new pivots.
#include "screwfem/linalg/sparse_lu.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <iterator>
#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "screwfem/linalg/banded_lu.h"

namespace screwfem::sparse_lu_test {
namespace {

using Block = SparseLU::Block;

// A block-sparse saddle-point matrix like the Newton systems: a chain of `nodes` 6 x 6 node
// blocks (each coupled with the next), then `rows` constraint rows, each acting on the node
// blocks listed in `acts` (one list per row). Node blocks are diagonally dominant with random
// entries; the constraint rows' diagonal block is zero. Returns the matrix, fills *blocks.
Eigen::MatrixXd SaddleMatrix(std::mt19937& rng, int nodes,
                             const std::vector<std::vector<int>>& acts,
                             std::vector<Block>* blocks) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int nv = 6 * nodes, nc = static_cast<int>(acts.size()), n = nv + nc;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  blocks->clear();
  const auto fill = [&](int r, int rows, int c, int cols) {
    for (int j = c; j < c + cols; ++j)
      for (int i = r; i < r + rows; ++i) A(i, j) = u(rng);
    blocks->push_back({r, rows, c, cols});
  };
  for (int a = 0; a < nodes; ++a) {
    fill(6 * a, 6, 6 * a, 6);
    for (int i = 0; i < 6; ++i) A(6 * a + i, 6 * a + i) += 20.0;
    if (a + 1 < nodes) {
      fill(6 * a, 6, 6 * a + 6, 6);
      fill(6 * a + 6, 6, 6 * a, 6);
    }
  }
  for (int r = 0; r < nc; ++r)
    for (int a : acts[static_cast<std::size_t>(r)]) {
      fill(nv + r, 1, 6 * a, 6);
      fill(6 * a, 6, nv + r, 1);
    }
  return A;
}

// Loads A's entries (inside the pattern) into lu.
void Load(const Eigen::MatrixXd& A, SparseLU* lu) {
  lu->SetZero();
  lu->ForEachEntry([&](int i, int j, double) { lu->At(i, j) = A(i, j); });
}

int DenseSign(const Eigen::MatrixXd& A) {
  const double det = A.partialPivLu().determinant();
  return det > 0.0 ? 1 : (det < 0.0 ? -1 : 0);
}

TEST(SparseLU, PatternIsTheUnionOfTheBlocksAndTheDiagonal) {
  SparseLU lu;
  lu.SetPattern(5, {{0, 2, 3, 2}, {1, 2, 3, 1}, {4, 1, 0, 1}});
  // Column 3: rows 0, 1, 2 (blocks) and 3 (diagonal); column 4: rows 0, 1, 4; column 0: 0, 4.
  EXPECT_EQ(lu.nonzeros(), 2 + 1 + 1 + 4 + 3);
  EXPECT_GE(lu.Find(2, 3), 0);
  EXPECT_LT(lu.Find(2, 4), 0);
  EXPECT_EQ(lu.FindRun(0, 3, 4), lu.Find(0, 3));
  EXPECT_EQ(lu.FindRun(0, 4, 3), -1);  // rows 0, 1 and 4: not consecutive
  EXPECT_TRUE(lu.Contains(0, 3, 2, 2));
  EXPECT_FALSE(lu.Contains(1, 3, 2, 2));
  EXPECT_EQ(lu.Find(4, 0), lu.Find(0, 0) + 1);
  EXPECT_EQ(lu.analyses(), 1);
}

TEST(SparseLU, MatchesDenseLUOnSaddlePointSystems) {
  std::mt19937 rng(11);
  // Chains with rows on neighbouring nodes, and a row across every node (a tendon drawn by
  // length), which a bandwidth-reducing order cannot keep narrow.
  for (int nodes : {1, 3, 12, 40}) {
    std::vector<std::vector<int>> acts;
    for (int a = 0; a + 1 < nodes; a += 3) acts.push_back({a, a + 1});
    std::vector<int> all;
    for (int a = 0; a < nodes; ++a) all.push_back(a);
    acts.push_back(all);
    std::vector<Block> blocks;
    const Eigen::MatrixXd A = SaddleMatrix(rng, nodes, acts, &blocks);
    SparseLU lu;
    lu.SetPattern(static_cast<int>(A.rows()), blocks);
    Load(A, &lu);
    ASSERT_EQ(lu.Factorize(), -1) << nodes;
    Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
    const Eigen::VectorXd b = x;
    lu.Solve(x);
    const Eigen::VectorXd ref = A.partialPivLu().solve(b);
    EXPECT_LT((x - ref).norm(), 1e-11 * ref.norm()) << nodes;
    EXPECT_LT((A * x - b).norm(), 1e-13 * A.norm() * x.norm()) << nodes;
    EXPECT_EQ(lu.determinant_sign(), DenseSign(A)) << nodes;
    EXPECT_GT(lu.min_pivot(), 0.0);
    EXPECT_GE(lu.max_pivot(), lu.min_pivot());
  }
}

// SolveTransposed (klu_tsolve): A^T x = b against the dense LU of A^T.
TEST(SparseLU, TransposedSolveMatchesDenseLUOfTheTranspose) {
  std::mt19937 rng(23);
  for (int nodes : {1, 5, 20}) {
    std::vector<std::vector<int>> acts;
    for (int a = 0; a + 1 < nodes; a += 2) acts.push_back({a, a + 1});
    std::vector<Block> blocks;
    const Eigen::MatrixXd A = SaddleMatrix(rng, nodes, acts, &blocks);
    SparseLU lu;
    lu.SetPattern(static_cast<int>(A.rows()), blocks);
    Load(A, &lu);
    ASSERT_EQ(lu.Factorize(), -1) << nodes;
    Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(A.rows(), 2.0, -1.0);
    const Eigen::VectorXd b = x;
    lu.SolveTransposed(x);
    const Eigen::VectorXd ref = A.transpose().partialPivLu().solve(b);
    EXPECT_LT((x - ref).norm(), 1e-11 * ref.norm()) << nodes;
    EXPECT_LT((A.transpose() * x - b).norm(), 1e-13 * A.norm() * x.norm()) << nodes;
  }
}

TEST(SparseLU, DeterminantSignMatchesTheDenseAndTheBandedLU) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int negative = 0;
  for (int trial = 0; trial < 40; ++trial) {
    // Random block-sparse matrices without a dominant diagonal: pivoting, both signs.
    const int n = 24;
    std::vector<Block> blocks;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
    for (int b = 0; b < n / 3; ++b) {
      const int c = std::uniform_int_distribution<int>(0, n / 3 - 1)(rng);
      blocks.push_back({3 * b, 3, 3 * c, 3});
      blocks.push_back({3 * b, 3, 3 * b, 3});
    }
    for (const Block& b : blocks)
      for (int j = b.col; j < b.col + b.cols; ++j)
        for (int i = b.row; i < b.row + b.rows; ++i) A(i, j) = u(rng);
    SparseLU lu;
    lu.SetPattern(n, blocks);
    Load(A, &lu);
    ASSERT_EQ(lu.Factorize(), -1);
    BandedLU band;
    band.Resize(n, n - 1, n - 1);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) band.At(i, j) = A(i, j);
    ASSERT_EQ(band.Factorize(), -1);
    EXPECT_EQ(lu.determinant_sign(), DenseSign(A)) << trial;
    EXPECT_EQ(lu.determinant_sign(), band.determinant_sign()) << trial;
    negative += lu.determinant_sign() < 0 ? 1 : 0;
  }
  EXPECT_GT(negative, 5);
  EXPECT_LT(negative, 35);
}

TEST(SparseLU, RefactorisesWithOneAnalysisAndFallsBackOnPoorPivots) {
  std::mt19937 rng(3);
  std::vector<Block> blocks;
  const Eigen::MatrixXd A = SaddleMatrix(rng, 10, {{0, 1}, {4, 5}, {8, 9}}, &blocks);
  const int n = static_cast<int>(A.rows());
  SparseLU lu;
  lu.SetPattern(n, blocks);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
  for (int k = 0; k < 5; ++k) {
    // Values that change a little from one Newton iteration to the next.
    const Eigen::MatrixXd Ak = A * (1.0 + 0.01 * k);
    Load(Ak, &lu);
    ASSERT_EQ(lu.Factorize(), -1);
    Eigen::VectorXd x = b;
    lu.Solve(x);
    EXPECT_LT((Ak * x - b).norm(), 1e-13 * Ak.norm() * x.norm()) << k;
  }
  EXPECT_EQ(lu.analyses(), 1);
  EXPECT_EQ(lu.factorizations(), 5);
  EXPECT_EQ(lu.full_factorizations(), 1);
  EXPECT_EQ(lu.fallbacks(), 0);
  // A matrix whose first pivots (those of the dominant diagonal) are now zero: the
  // refactorisation finds a zero pivot, and a factorisation with new pivots takes over.
  Eigen::MatrixXd P = A;
  for (int i = 0; i < 6; ++i) P(i, i) = 0.0;
  P.block(0, 6, 6, 6) *= 1e3;
  P.block(6, 0, 6, 6) *= 1e3;
  Load(P, &lu);
  ASSERT_EQ(lu.Factorize(), -1);
  Eigen::VectorXd x = b;
  lu.Solve(x);
  EXPECT_LT((P * x - b).norm(), 1e-12 * P.norm() * x.norm());
  EXPECT_EQ(lu.fallbacks(), 1);
  EXPECT_EQ(lu.full_factorizations(), 2);
  EXPECT_EQ(lu.analyses(), 1);
  EXPECT_EQ(lu.determinant_sign(), DenseSign(P));
}

TEST(SparseLU, SingularMatrixReportsAZeroPivotColumn) {
  std::mt19937 rng(9);
  std::vector<Block> blocks;
  Eigen::MatrixXd A = SaddleMatrix(rng, 4, {{1}}, &blocks);
  // Row 24 (the constraint row) acts on nothing: a zero row.
  const int n = static_cast<int>(A.rows());
  SparseLU lu;
  lu.SetPattern(n, blocks);
  A.row(n - 1).setZero();
  Load(A, &lu);
  const int col = lu.Factorize();
  EXPECT_GE(col, 0);
  EXPECT_LT(col, n);
  EXPECT_EQ(lu.determinant_sign(), 0);
  // The next factorisation of a regular matrix is a full one, and succeeds.
  A(n - 1, 6) = 1.0;
  Load(A, &lu);
  EXPECT_EQ(lu.Factorize(), -1);
}

TEST(SparseLU, SetRowHoldsOneUnknown) {
  std::mt19937 rng(2);
  std::vector<Block> blocks;
  Eigen::MatrixXd A = SaddleMatrix(rng, 3, {{0, 2}}, &blocks);
  const int n = static_cast<int>(A.rows());
  SparseLU lu;
  lu.SetPattern(n, blocks);
  Load(A, &lu);
  lu.SetRow(n - 1, 1.0);
  A.row(n - 1).setZero();
  A(n - 1, n - 1) = 1.0;
  Eigen::MatrixXd back = Eigen::MatrixXd::Zero(n, n);
  lu.ForEachEntry([&](int i, int j, double v) { back(i, j) = v; });
  EXPECT_EQ((back - A).cwiseAbs().maxCoeff(), 0.0);
}

// Couplings (SetCouplings): a chain of 12 node blocks whose far blocks are coupled (contact
// pairs between nodes the base pattern does not link). Each list solves its matrix exactly
// (the dense LU's solution to round-off); a pattern holding the list is kept in use (a pair
// that comes and goes), a kept pattern holding it is taken back without an analysis, and a new
// pattern takes the couplings of the one in use along while they are few.
TEST(SparseLU, CouplingsEnterThePatternAndKeptPatternsAreTakenBack) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Block> blocks;
  const Eigen::MatrixXd A = SaddleMatrix(rng, 12, {{0, 1}, {5, 6}}, &blocks);
  const int n = static_cast<int>(A.rows());
  SparseLU lu;
  lu.SetPattern(n, blocks);
  EXPECT_TRUE(lu.InBase(0, 6));  // neighbours in the chain
  EXPECT_FALSE(lu.InBase(0, 30));
  const auto list = [&](std::vector<std::pair<int, int>> nodes) {
    std::vector<std::int64_t> key;
    for (const auto& [a, b] : nodes) key.push_back(lu.PackCoupling(6 * a, 6 * b));
    std::sort(key.begin(), key.end());
    return key;
  };
  const std::vector<std::int64_t> a = list({{0, 7}}), b = list({{3, 9}});
  std::vector<std::pair<int, int>> twenty;  // 20 far pairs, none of a, b or d
  for (int i = 0; i < 12 && twenty.size() < 20; ++i)
    for (int k = i + 2; k < 12 && twenty.size() < 20; ++k)
      if (!(i == 0 && k == 7) && !(i == 3 && k == 9) && !(i == 4 && k == 11))
        twenty.emplace_back(i, k);
  const std::vector<std::int64_t> c = list(twenty), d = list({{4, 11}});
  struct Expect {
    const std::vector<std::int64_t>* key;
    std::int64_t changes, hits;
  };
  const std::vector<std::int64_t> none;
  // a: analysed; none, a: held; b: analysed with a; c: analysed with a and b (22 couplings);
  // d: analysed alone (22 > 1 + 16); c: taken back (the kept pattern of a, b, c holds it).
  const Expect steps[] = {{&a, 1, 0}, {&none, 1, 0}, {&a, 1, 0}, {&b, 2, 0},
                          {&a, 2, 0}, {&c, 3, 0},    {&d, 4, 0}, {&c, 5, 1}};
  for (std::size_t k = 0; k < std::size(steps); ++k) {
    const std::vector<std::int64_t>& key = *steps[k].key;
    lu.SetCouplings(key.data(), key.size(), 6);
    EXPECT_TRUE(std::includes(lu.couplings().begin(), lu.couplings().end(), key.begin(), key.end()))
        << k;
    EXPECT_EQ(lu.pattern_changes(), steps[k].changes) << k;
    EXPECT_EQ(lu.pattern_hits(), steps[k].hits) << k;
    EXPECT_EQ(lu.analyses(), 1 + lu.pattern_changes() - lu.pattern_hits()) << k;
    EXPECT_LE(lu.cached_patterns(), SparseLU::kCachedPatterns - 1);
    // The matrix with these couplings: random blocks (p, q) and (q, p).
    Eigen::MatrixXd C = A;
    for (const std::int64_t x : key) {
      const int p = static_cast<int>(x / n), q = static_cast<int>(x % n);
      EXPECT_TRUE(lu.Contains(p, q, 6, 6) && lu.Contains(q, p, 6, 6));
      EXPECT_FALSE(lu.InBase(p, q));
      for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 6; ++i) {
          C(p + i, q + j) = u(rng);
          C(q + i, p + j) = u(rng);
        }
    }
    Load(C, &lu);
    ASSERT_EQ(lu.Factorize(), -1) << k;
    const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    Eigen::VectorXd x = rhs;
    lu.Solve(x);
    const Eigen::VectorXd y = C.partialPivLu().solve(rhs);
    EXPECT_LT((x - y).norm(), 1e-12 * y.norm()) << k;
    EXPECT_EQ(lu.determinant_sign(), DenseSign(C)) << k;
  }
  EXPECT_EQ(lu.couplings().size(), 22u);
  // A new base drops the kept patterns.
  lu.SetPattern(n, blocks);
  EXPECT_EQ(lu.cached_patterns(), 0);
  EXPECT_TRUE(lu.couplings().empty());
}

TEST(SparseLU, CopyKeepsThePatternAndTheCounters) {
  std::mt19937 rng(4);
  std::vector<Block> blocks;
  const Eigen::MatrixXd A = SaddleMatrix(rng, 5, {{0, 4}}, &blocks);
  const int n = static_cast<int>(A.rows());
  SparseLU lu;
  lu.SetPattern(n, blocks);
  Load(A, &lu);
  ASSERT_EQ(lu.Factorize(), -1);
  SparseLU copy = lu;
  EXPECT_EQ(copy.analyses(), 1);
  EXPECT_EQ(copy.factorizations(), 1);
  ASSERT_EQ(copy.Factorize(), -1);
  Eigen::VectorXd x = Eigen::VectorXd::Ones(n), y = x;
  lu.Solve(x);
  copy.Solve(y);
  EXPECT_LT((x - y).norm(), 1e-14 * x.norm());
  SparseLU moved = std::move(copy);
  EXPECT_EQ(moved.factorizations(), 2);
  EXPECT_EQ(moved.size(), n);
}

}  // namespace
}  // namespace screwfem::sparse_lu_test
