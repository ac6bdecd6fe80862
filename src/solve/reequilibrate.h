// Internal to screwfem::solve: the equilibrium of a model whose parameters changed, from the
// last one (inverse statics and calibration, docs/inverse.md).
#pragma once

#include <string>

#include "screwfem/model/data.h"
#include "screwfem/solve/statics.h"

namespace screwfem {

// Brings data from its last equilibrium to the one of `model` (its parameters changed): Newton
// at the end load factor (the warm start), failing fast (no halvings, at most 12 iterations:
// a step far from the last equilibrium costs 13 Newton iterations before the fallback, not
// 13 x 30; measured 1.27 s against 0.38 s of CPU for the 20 targets of bench/inverse_bench.cpp
// at 100 elements), else load stepping from the reference state with `statics`. Counts the
// solves in *solves. False, with data back at its start and *failure saying why, when
// neither converges.
bool Reequilibrate(const Model& model, Data& data, const StaticOptions& statics, int* solves,
                   std::string* failure);

}  // namespace screwfem
