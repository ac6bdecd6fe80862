// What the static and dynamic solvers share: the solve of the assembled Newton system and the
// ranges of their iteration limits. Both solvers include this header and neither includes the
// other's.
#pragma once

#include "screwfem/model/data.h"

namespace screwfem {

// Ranges of the iteration limits (scene files: analysis.max_iterations, max_halvings; the
// static solver's max_iterations and max_halvings have the same ranges).
inline constexpr int kMaxNewtonIterations = 1000;
inline constexpr int kMaxHalvings = 30;

// Solves data.matrix * x = -data.residual (the system left by Assemble) into data.increment
// (global order). Returns false when the matrix is singular.
bool SolveAssembledSystem(const Model& model, Data& data);
// The same with the factorisation data.matrix already holds (from an earlier
// SolveAssembledSystem): only data.residual is read.
bool SolveFactorizedSystem(const Model& model, Data& data);

}  // namespace screwfem
