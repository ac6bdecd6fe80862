// Test helper shared by the banded-solver tests: a dense matrix's band copied into a BandedLU.
#pragma once

#include <Eigen/Core>
#include <algorithm>

#include "screwfem/linalg/banded_lu.h"

namespace screwfem::band_matrix {

// Copies the band (kl below, ku above the diagonal) of A into a freshly zeroed BandedLU.
inline void Load(const Eigen::MatrixXd& A, int kl, int ku, BandedLU* lu) {
  const int n = static_cast<int>(A.rows());
  lu->Resize(n, kl, ku);
  lu->SetZero();
  for (int j = 0; j < n; ++j)
    for (int i = std::max(0, j - ku); i <= std::min(n - 1, j + kl); ++i) lu->At(i, j) = A(i, j);
}

}  // namespace screwfem::band_matrix
