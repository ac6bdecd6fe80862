// The exact static tangent's pattern (internal to the solve layer): statics and its
// sensitivities (statics.cpp, sensitivity.cpp) assemble d(B^T lambda)/dq into the matrix, whose
// blocks may lie outside the model's band pattern. While an ExactTangentPattern lives, Data's
// matrix has the wider pattern (and band); its destructor gives the model's back.
#pragma once

#include <vector>

#include "screwfem/assemble/assemble.h"

namespace screwfem {

class ExactTangentPattern {
 public:
  // Widens data's matrix when `enable` (StaticOptions::constraint_force_tangent) and sets
  // options->constraint_force_tangent and options->pattern_last for the assembly.
  ExactTangentPattern(const Model& m, Data& d, bool enable, AssemblyOptions* options)
      : model_(m), data_(d) {
    const int n = m.num_unknowns();
    if (enable && m.sparse_solver) {
      // The sparse pattern gets the blocks of d(B^T lambda)/dq (a new symbolic analysis).
      std::vector<SparseLU::Block> blocks = m.sparse_pattern;
      AddConstraintForceTangentBlocks(m, &blocks);
      d.sparse.SetPattern(n, blocks);
      active_ = true;
    } else if (enable && static_cast<int>(m.pattern_last.size()) == n) {
      int bandwidth = 0;
      pattern_ = ConstraintForceTangentPattern(m, &bandwidth);
      if (bandwidth > d.matrix.lower_bandwidth() || bandwidth > d.matrix.upper_bandwidth()) {
        d.matrix.Resize(n, bandwidth, bandwidth);
        resized_ = true;
      }
      d.matrix.SetPattern(pattern_, pattern_);
      active_ = true;
      options->pattern_last = &pattern_;
    }
    options->constraint_force_tangent = active_;
  }
  ~ExactTangentPattern() {
    if (!active_) return;
    if (model_.sparse_solver) {
      data_.sparse.SetPattern(model_.num_unknowns(), model_.sparse_pattern);
      return;
    }
    if (resized_) data_.matrix.Resize(model_.num_unknowns(), model_.bandwidth, model_.bandwidth);
    data_.matrix.SetPattern(model_.pattern_last, model_.pattern_last);
  }
  ExactTangentPattern(const ExactTangentPattern&) = delete;
  ExactTangentPattern& operator=(const ExactTangentPattern&) = delete;

 private:
  const Model& model_;
  Data& data_;
  std::vector<int> pattern_;
  bool active_ = false, resized_ = false;
};

// The scale of the constraint rows in statics (s_C = s_L): the largest stiffness of the model.
double StaticConstraintScale(const Model& model);

}  // namespace screwfem
