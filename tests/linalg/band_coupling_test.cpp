// Tests of BandCoupling: the Woodbury solve of a banded matrix plus off-band blocks, checked
// against Eigen's dense PartialPivLU of the whole matrix.
#include "screwfem/linalg/band_coupling.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <random>
#include <vector>

#include "linalg/band_matrix.h"

namespace screwfem::band_coupling_test {
namespace {

constexpr int kBlock = 6;

// A random banded matrix (entries uniform in [-1, 1]). saddle: the rows and columns of a few
// unknowns get a zero diagonal (multiplier-like rows: the LU must pivot).
Eigen::MatrixXd RandomBanded(std::mt19937& rng, int n, int kl, int ku, bool saddle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = std::max(0, j - ku); i <= std::min(n - 1, j + kl); ++i) A(i, j) = u(rng);
  if (saddle)
    for (int i : {3, 17, 18, 31, 44, 58}) A(i, i) = 0.0;
  return A;
}

Eigen::VectorXd RandomVector(std::mt19937& rng, int n) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b(i) = normal(rng);
  return b;
}

using band_matrix::Load;

// A random banded matrix of n = 60 unknowns with kl = ku = 7 (RandomBanded) and its banded
// factors.
constexpr int kN = 60, kBand = 7;
struct Band {
  Eigen::MatrixXd A;
  BandedLU lu;
};
void FactorizeRandomBand(std::mt19937& rng, bool saddle, Band* band) {
  band->A = RandomBanded(rng, kN, kBand, kBand, saddle);
  Load(band->A, kBand, kBand, &band->lu);
  ASSERT_EQ(band->lu.Factorize(), -1);
}
// The n x n identity in a band of 2, factorised.
void FactorizeIdentity(int n, BandedLU* lu) {
  Load(Eigen::MatrixXd::Identity(n, n), 2, 2, lu);
  ASSERT_EQ(lu->Factorize(), -1);
}

// One Add: block (p_i, p_j) += scale * B.
struct Entry {
  int p_i, p_j;
  Eigen::MatrixXd B;
  double scale;
};

// Adds the entries to the coupling and to the dense matrix *full.
void AddAll(const std::vector<Entry>& entries, BandCoupling* coupling, Eigen::MatrixXd* full) {
  for (const Entry& e : entries) {
    ASSERT_TRUE(coupling->Add(e.p_i, e.p_j, e.B, e.scale));
    full->block(e.p_i, e.p_j, kBlock, kBlock) += e.scale * e.B;
  }
}

std::vector<Entry> RandomEntries(std::mt19937& rng, const std::vector<std::pair<int, int>>& at) {
  std::vector<Entry> entries;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const auto& [p_i, p_j] : at) {
    Eigen::MatrixXd B(kBlock, kBlock);
    for (int c = 0; c < kBlock; ++c)
      for (int r = 0; r < kBlock; ++r) B(r, c) = u(rng);
    entries.push_back({p_i, p_j, B, 0.5 + u(rng)});
  }
  return entries;
}

// (A + P E P^T)^-1 b by BandedLU::Solve and BandCoupling::Correct.
Eigen::VectorXd CoupledSolve(const BandedLU& lu, BandCoupling& coupling, const Eigen::VectorXd& b) {
  Eigen::VectorXd x = b;
  lu.Solve(x);
  coupling.Correct(lu, x);
  return x;
}

double RelativeError(const Eigen::VectorXd& x, const Eigen::VectorXd& ref) {
  return (x - ref).norm() / ref.norm();
}

// Blocks far apart in the band order (starts 0, 20, 37, 53: not multiples of 6), coupled
// non-symmetrically, one block pair added twice, one pair on the diagonal.
const std::vector<std::pair<int, int>> kFarPairs = {{0, 53},  {53, 0}, {20, 37}, {37, 0},
                                                    {53, 20}, {0, 53}, {37, 37}, {20, 20}};

TEST(BandCoupling, WoodburySolveMatchesDenseLUOfTheWholeMatrix) {
  std::mt19937 rng(11);
  for (const bool saddle : {false, true}) {
    for (int trial = 0; trial < 3; ++trial) {
      Band band;
      ASSERT_NO_FATAL_FAILURE(FactorizeRandomBand(rng, saddle, &band));
      const BandedLU& lu = band.lu;
      const int n = kN;
      BandCoupling coupling;
      coupling.Resize(n, kBlock, 4);
      Eigen::MatrixXd full = band.A;
      AddAll(RandomEntries(rng, kFarPairs), &coupling, &full);
      EXPECT_EQ(coupling.blocks(), 4);
      EXPECT_FALSE(coupling.overflowed());
      ASSERT_TRUE(coupling.Factorize(lu));
      const Eigen::PartialPivLU<Eigen::MatrixXd> dense = full.partialPivLu();
      // Two right-hand sides after one Factorize.
      for (int rhs = 0; rhs < 2; ++rhs) {
        const Eigen::VectorXd b = RandomVector(rng, n);
        const Eigen::VectorXd x = CoupledSolve(lu, coupling, b);
        EXPECT_LT(RelativeError(x, dense.solve(b)), 1e-12) << "saddle " << saddle;
        EXPECT_LT((full * x - b).norm() / (full.norm() * x.norm()), 1e-14);
      }
      // The whole matrix has det(A) det(G).
      const double det = dense.determinant();
      ASSERT_NE(det, 0.0);
      EXPECT_EQ(det > 0.0 ? 1 : -1, lu.determinant_sign() * coupling.determinant_sign());
    }
  }
}

TEST(BandCoupling, DeterminantSignFollowsTheWholeMatrix) {
  // A = I (det +1); E = diag(-2) on one unknown of a block flips the sign of that diagonal
  // entry of A + P E P^T (one negative eigenvalue), -2 on two unknowns flips it back.
  const int n = 30;
  BandedLU lu;
  ASSERT_NO_FATAL_FAILURE(FactorizeIdentity(n, &lu));
  BandCoupling coupling;
  coupling.Resize(n, kBlock, 4);
  for (int flipped = 1; flipped <= 3; ++flipped) {
    coupling.Clear();
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(kBlock, kBlock);
    E.diagonal().head(flipped).setConstant(-2.0);
    ASSERT_TRUE(coupling.Add(11, 11, E, 1.0));
    ASSERT_TRUE(coupling.Factorize(lu));
    EXPECT_EQ(coupling.determinant_sign(), flipped % 2 == 1 ? -1 : 1) << flipped;
  }
}

TEST(BandCoupling, ForEachEntryGivesBackTheAddedMatrix) {
  const int n = kN;
  std::mt19937 rng(5);
  const Eigen::MatrixXd A = RandomBanded(rng, n, kBand, kBand, false);
  BandCoupling coupling;
  coupling.Resize(n, kBlock, 4);
  Eigen::MatrixXd full = A;
  AddAll(RandomEntries(rng, kFarPairs), &coupling, &full);
  Eigen::MatrixXd back = A;
  int calls = 0;
  coupling.ForEachEntry([&](int i, int j, double value) {
    back(i, j) += value;
    ++calls;
  });
  EXPECT_EQ(calls, 7 * kBlock * kBlock);  // seven distinct block pairs (one added twice)
  EXPECT_LT((back - full).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(BandCoupling, OverlappingBlocksAddUp) {
  // Starts 10 and 13 share unknowns 13..15: P has them twice, the identity still holds.
  const int n = kN;
  std::mt19937 rng(3);
  Band band;
  ASSERT_NO_FATAL_FAILURE(FactorizeRandomBand(rng, true, &band));
  const Eigen::MatrixXd& A = band.A;
  const BandedLU& lu = band.lu;
  BandCoupling coupling;
  coupling.Resize(n, kBlock, 4);
  Eigen::MatrixXd full = A;
  AddAll(RandomEntries(rng, {{10, 40}, {13, 40}, {40, 13}, {10, 13}}), &coupling, &full);
  ASSERT_TRUE(coupling.Factorize(lu));
  const Eigen::VectorXd b = RandomVector(rng, n);
  EXPECT_LT(RelativeError(CoupledSolve(lu, coupling, b), full.partialPivLu().solve(b)), 1e-12);
}

TEST(BandCoupling, EmptyCouplingLeavesTheBandedSolutionUnchanged) {
  const int n = kN;
  std::mt19937 rng(8);
  Band band;
  ASSERT_NO_FATAL_FAILURE(FactorizeRandomBand(rng, true, &band));
  const BandedLU& lu = band.lu;
  BandCoupling coupling;
  coupling.Resize(n, kBlock, 3);
  EXPECT_TRUE(coupling.empty());
  EXPECT_TRUE(coupling.Factorize(lu));
  EXPECT_EQ(coupling.determinant_sign(), 1);
  Eigen::VectorXd x = RandomVector(rng, n);
  lu.Solve(x);
  const Eigen::VectorXd y = x;
  coupling.Correct(lu, x);
  for (int i = 0; i < n; ++i) EXPECT_EQ(x(i), y(i));  // bitwise
}

TEST(BandCoupling, OverflowAddsNothingUntilClearThenSlotsAreReused) {
  const int n = kN;
  std::mt19937 rng(21);
  Band band;
  ASSERT_NO_FATAL_FAILURE(FactorizeRandomBand(rng, true, &band));
  const Eigen::MatrixXd& A = band.A;
  const BandedLU& lu = band.lu;
  BandCoupling coupling;
  coupling.Resize(n, kBlock, 2);
  EXPECT_EQ(coupling.max_blocks(), 2);
  Eigen::MatrixXd full = A;
  AddAll(RandomEntries(rng, {{2, 40}, {40, 2}, {40, 40}}), &coupling, &full);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Constant(kBlock, kBlock, 7.0);
  EXPECT_FALSE(coupling.Add(2, 25, B, 1.0));   // a third block
  EXPECT_FALSE(coupling.Add(25, 25, B, 1.0));  // also on its own
  EXPECT_TRUE(coupling.overflowed());
  EXPECT_EQ(coupling.blocks(), 2);
  ASSERT_TRUE(coupling.Add(2, 2, B, 0.5));  // existing blocks still take entries
  full.block(2, 2, kBlock, kBlock) += 0.5 * B;
  EXPECT_TRUE(coupling.overflowed());  // and the flag stays
  ASSERT_TRUE(coupling.Factorize(lu));
  Eigen::VectorXd b = RandomVector(rng, n);
  EXPECT_LT(RelativeError(CoupledSolve(lu, coupling, b), full.partialPivLu().solve(b)), 1e-12);

  coupling.Clear();
  EXPECT_FALSE(coupling.overflowed());
  EXPECT_TRUE(coupling.empty());
  EXPECT_EQ(coupling.blocks(), 0);
  // New blocks: the old slots' entries must be gone, the old starts unknown.
  full = A;
  AddAll(RandomEntries(rng, {{25, 49}, {49, 25}}), &coupling, &full);
  EXPECT_EQ(coupling.blocks(), 2);
  EXPECT_FALSE(coupling.overflowed());
  ASSERT_TRUE(coupling.Factorize(lu));
  b = RandomVector(rng, n);
  EXPECT_LT(RelativeError(CoupledSolve(lu, coupling, b), full.partialPivLu().solve(b)), 1e-12);
}

TEST(BandCoupling, SingularWholeMatrixGivesASingularG) {
  // A = I, E = -I on one block: A + P E P^T has a zero 6 x 6 diagonal block; G = I - I.
  const int n = 30;
  BandedLU lu;
  ASSERT_NO_FATAL_FAILURE(FactorizeIdentity(n, &lu));
  BandCoupling coupling;
  coupling.Resize(n, kBlock, 2);
  ASSERT_TRUE(coupling.Add(9, 9, Eigen::MatrixXd::Identity(kBlock, kBlock), -1.0));
  EXPECT_FALSE(coupling.Factorize(lu));
  // Rank one short: only the last unknown of the block cancelled, coupled to a far block.
  coupling.Clear();
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(kBlock, kBlock);
  E(5, 5) = -1.0;
  ASSERT_TRUE(coupling.Add(9, 9, E, 1.0));
  ASSERT_TRUE(coupling.Add(22, 9, Eigen::MatrixXd::Identity(kBlock, kBlock), 3.0));
  EXPECT_FALSE(coupling.Factorize(lu));  // row 14 of A + P E P^T is zero
  // A non-finite entry.
  coupling.Clear();
  E(5, 5) = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(coupling.Add(9, 22, E, 1.0));
  EXPECT_FALSE(coupling.Factorize(lu));
}

}  // namespace
}  // namespace screwfem::band_coupling_test
