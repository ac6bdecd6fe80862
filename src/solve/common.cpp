#include "screwfem/solve/common.h"

namespace screwfem {

bool SolveAssembledSystem(const Model& model, Data& data) {
  if (model.sparse_solver) {
    // The pattern holds every block, the contact pairs' included (SelectSparsePattern).
    if (data.sparse.Factorize() >= 0) return false;
    return SolveFactorizedSystem(model, data);
  }
  if (data.matrix.Factorize() >= 0) return false;
  if (!data.coupling.Factorize(data.matrix)) return false;  // the off-band blocks (Woodbury)
  return SolveFactorizedSystem(model, data);
}

bool SolveFactorizedSystem(const Model& model, Data& data) {
  const int n = model.num_unknowns();
  for (int i = 0; i < n; ++i)
    data.rhs(model.permutation[static_cast<std::size_t>(i)]) = -data.residual(i);
  if (model.sparse_solver) {
    data.sparse.Solve(data.rhs);
  } else {
    data.matrix.Solve(data.rhs);
    data.coupling.Correct(data.matrix, data.rhs);
  }
  for (int i = 0; i < n; ++i)
    data.increment(i) = data.rhs(model.permutation[static_cast<std::size_t>(i)]);
  return data.increment.allFinite();
}

}  // namespace screwfem
