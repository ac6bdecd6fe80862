#include "screwfem/linalg/sparse_lu.h"

#include <klu.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

namespace screwfem {

namespace {

klu_common* Common(void* p) { return static_cast<klu_common*>(p); }
klu_symbolic* Symbolic(void* p) { return static_cast<klu_symbolic*>(p); }

// The numerical factorisations kept (SparseLU::numeric_ points to one PivotSequences): a few
// pivot sequences, each a klu_numeric of its own, so that matrices of different kinds that
// share one pattern (the iteration matrix of a step, the mass matrix [M B^T; B 0] of the
// consistent accelerations and restarts, whose zero blocks differ) are each refactorised with
// a pivot sequence that suits them, instead of a new factorisation (which allocates) at every
// change of kind. order[0..count) are the slots in use, the most recently successful first.
constexpr int kPivotSequences = 8;
struct PivotSequences {
  PivotSequences() {
    for (int i = 0; i < kPivotSequences; ++i) order[i] = i;
  }
  klu_numeric* numeric[kPivotSequences] = {};
  int order[kPivotSequences];
  int count = 0;
  bool current = false;  // numeric[order[0]] holds the last successful factorisation
  klu_numeric* Current() const { return numeric[order[0]]; }
  // Moves position k of order to the front.
  void Promote(int k) {
    const int slot = order[k];
    for (int i = k; i > 0; --i) order[i] = order[i - 1];
    order[0] = slot;
  }
  void Free(int k, klu_common* c) {
    klu_free_numeric(&numeric[order[k]], c);
    numeric[order[k]] = nullptr;
  }
  void Clear(klu_common* c) {
    for (klu_numeric*& n : numeric) klu_free_numeric(&n, c);
    count = 0;
    current = false;
  }
};
PivotSequences* Sequences(void* p) { return static_cast<PivotSequences*>(p); }

// Parity of a permutation of 0..n-1 (+1 even, -1 odd), by following its cycles; `mark` has
// room for n entries (no allocation).
int Parity(const int* perm, int n, std::vector<char>& mark) {
  std::fill(mark.begin(), mark.begin() + n, 0);
  int sign = 1;
  for (int i = 0; i < n; ++i) {
    if (mark[static_cast<std::size_t>(i)]) continue;
    int length = 0;
    for (int j = i; !mark[static_cast<std::size_t>(j)]; j = perm[j]) {
      mark[static_cast<std::size_t>(j)] = 1;
      ++length;
    }
    if (length % 2 == 0) sign = -sign;
  }
  return sign;
}

}  // namespace

SparseLU::SparseLU() {
  klu_common* c = new klu_common;
  klu_defaults(c);
  // Diagonal preference only down to a tenth of the column's largest entry (KLU's default
  // 0.001): a pivot sequence then suits more of the matrices of one pattern (the mixed model
  // of tests/alloc/no_alloc_test.cpp with GGL: 4 sequences instead of more than 8).
  c->tol = kConstrainedPivotTolerance;
  common_ = c;
  numeric_ = new PivotSequences;
  kept_.resize(kCachedPatterns - 1);
  for (Kept& k : kept_) k.numeric = new PivotSequences;
}

SparseLU::~SparseLU() {
  Release();
  ReleaseKept();
  for (Kept& k : kept_) delete Sequences(k.numeric);
  delete Sequences(numeric_);
  delete Common(common_);
}

SparseLU::SparseLU(const SparseLU& other) : SparseLU() { *this = other; }

SparseLU& SparseLU::operator=(const SparseLU& other) {
  if (this == &other) return *this;
  Release();
  ReleaseKept();
  Common(common_)->tol = Common(other.common_)->tol;
  n_ = other.n_;
  col_start_ = other.col_start_;
  row_ = other.row_;
  value_ = other.value_;
  symmetric_ = other.symmetric_;
  base_ = other.base_;
  key_ = other.key_;
  block_size_ = other.block_size_;
  if (n_ > 0) {
    const std::int64_t analyses = other.analyses_;
    Analyze();
    analyses_ = analyses;
  }
  factorizations_ = other.factorizations_;
  full_factorizations_ = other.full_factorizations_;
  fallbacks_ = other.fallbacks_;
  pattern_hits_ = other.pattern_hits_;
  pattern_changes_ = other.pattern_changes_;
  return *this;
}

SparseLU::SparseLU(SparseLU&& other) noexcept : SparseLU() { *this = std::move(other); }

SparseLU& SparseLU::operator=(SparseLU&& other) noexcept {
  if (this == &other) return *this;
  std::swap(n_, other.n_);
  col_start_.swap(other.col_start_);
  row_.swap(other.row_);
  value_.swap(other.value_);
  std::swap(symmetric_, other.symmetric_);
  std::swap(common_, other.common_);
  std::swap(symbolic_, other.symbolic_);
  std::swap(numeric_, other.numeric_);
  mark_.swap(other.mark_);
  std::swap(column_parity_, other.column_parity_);
  std::swap(max_pivot_, other.max_pivot_);
  std::swap(min_pivot_, other.min_pivot_);
  std::swap(determinant_sign_, other.determinant_sign_);
  std::swap(predicted_nonzeros_, other.predicted_nonzeros_);
  std::swap(predicted_flops_, other.predicted_flops_);
  std::swap(analyses_, other.analyses_);
  std::swap(factorizations_, other.factorizations_);
  std::swap(full_factorizations_, other.full_factorizations_);
  std::swap(fallbacks_, other.fallbacks_);
  base_.swap(other.base_);
  key_.swap(other.key_);
  std::swap(block_size_, other.block_size_);
  kept_.swap(other.kept_);
  std::swap(uses_, other.uses_);
  std::swap(pattern_hits_, other.pattern_hits_);
  std::swap(pattern_changes_, other.pattern_changes_);
  return *this;
}

void SparseLU::Release() {
  klu_common* c = Common(common_);
  Sequences(numeric_)->Clear(c);
  if (symbolic_) {
    klu_symbolic* sym = Symbolic(symbolic_);
    klu_free_symbolic(&sym, c);
    symbolic_ = nullptr;
  }
}

void SparseLU::ReleaseKept() {
  klu_common* c = Common(common_);
  for (Kept& k : kept_) {
    Sequences(k.numeric)->Clear(c);
    if (k.symbolic) {
      klu_symbolic* sym = Symbolic(k.symbolic);
      klu_free_symbolic(&sym, c);
      k.symbolic = nullptr;
    }
    std::vector<int>().swap(k.col_start);
    std::vector<int>().swap(k.row);
    std::vector<double>().swap(k.value);
    std::vector<std::int64_t>().swap(k.key);
  }
}

int SparseLU::cached_patterns() const {
  int count = 0;
  for (const Kept& k : kept_) count += k.symbolic != nullptr ? 1 : 0;
  return count;
}

void SparseLU::SetPattern(int n, const std::vector<Block>& blocks) {
  Release();
  ReleaseKept();
  n_ = n;
  base_ = blocks;
  key_.clear();
  BuildStructure();
  Analyze();
}

void SparseLU::BuildStructure() {
  const int n = n_;
  // f(block) for the base blocks and the two blocks of each coupling.
  const auto for_each_block = [&](auto&& f) {
    for (const Block& b : base_) f(b);
    for (const std::int64_t c : key_) {
      const int p = static_cast<int>(c / n), q = static_cast<int>(c % n);
      f(Block{p, block_size_, q, block_size_});
      f(Block{q, block_size_, p, block_size_});
    }
  };
  // Per column, the row ranges of the blocks that cover it and the diagonal (a counting sort
  // by column into one array), then merged.
  std::vector<int> start(static_cast<std::size_t>(n) + 1, 1);
  start[static_cast<std::size_t>(n)] = 0;
  for_each_block([&](const Block& b) {
    assert(b.row >= 0 && b.col >= 0 && b.row + b.rows <= n && b.col + b.cols <= n);
    for (int j = b.col; j < b.col + b.cols; ++j) ++start[static_cast<std::size_t>(j)];
  });
  int total = 0;
  for (int j = 0; j <= n; ++j) {
    const int count = start[static_cast<std::size_t>(j)];
    start[static_cast<std::size_t>(j)] = total;
    total += count;
  }
  std::vector<std::pair<int, int>> ranges(static_cast<std::size_t>(total));
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int j = 0; j < n; ++j)
    ranges[static_cast<std::size_t>(fill[static_cast<std::size_t>(j)]++)] = {j, j + 1};
  for_each_block([&](const Block& b) {
    for (int j = b.col; j < b.col + b.cols; ++j)
      ranges[static_cast<std::size_t>(fill[static_cast<std::size_t>(j)]++)] = {b.row,
                                                                               b.row + b.rows};
  });
  col_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  row_.clear();
  for (int j = 0; j < n; ++j) {
    const auto first = ranges.begin() + start[static_cast<std::size_t>(j)];
    const auto last = ranges.begin() + start[static_cast<std::size_t>(j) + 1];
    std::sort(first, last);
    int next = 0;  // the first row after those already in the column
    for (auto r = first; r != last; ++r) {
      for (int i = std::max(r->first, next); i < r->second; ++i) row_.push_back(i);
      next = std::max(next, r->second);
    }
    col_start_[static_cast<std::size_t>(j) + 1] = static_cast<int>(row_.size());
  }
  value_.assign(row_.size(), 0.0);
  symmetric_ = true;
  for (int j = 0; j < n && symmetric_; ++j)
    for (int q = col_start_[static_cast<std::size_t>(j)];
         q < col_start_[static_cast<std::size_t>(j) + 1] && symmetric_; ++q)
      symmetric_ = Find(j, row_[static_cast<std::size_t>(q)]) >= 0;
}

void SparseLU::SwapWith(Kept& k) {
  col_start_.swap(k.col_start);
  row_.swap(k.row);
  value_.swap(k.value);
  std::swap(symmetric_, k.symmetric);
  std::swap(symbolic_, k.symbolic);
  std::swap(numeric_, k.numeric);
  std::swap(column_parity_, k.column_parity);
  std::swap(predicted_nonzeros_, k.predicted_nonzeros);
  std::swap(predicted_flops_, k.predicted_flops);
  key_.swap(k.key);
  // Neither holds a factorisation of the entries it will have next.
  Sequences(numeric_)->current = false;
  Sequences(k.numeric)->current = false;
  determinant_sign_ = 0;
}

void SparseLU::SetCouplings(const std::int64_t* pairs, std::size_t count, int block_size) {
  assert(block_size > 0 && (block_size_ == 0 || block_size_ == block_size || key_.empty()));
  block_size_ = block_size;
  const auto same = [&](const std::vector<std::int64_t>& key) {
    return key.size() == count && std::equal(key.begin(), key.end(), pairs);
  };
  // A pattern whose couplings include the list holds its matrix (the other blocks are zero).
  const auto holds = [&](const std::vector<std::int64_t>& key) {
    return key.size() >= count && std::includes(key.begin(), key.end(), pairs, pairs + count);
  };
  if (same(key_) || holds(key_) || n_ == 0) return;
  ++uses_;
  ++pattern_changes_;
  // A kept pattern of this list (or holding it): it becomes the one in use, the one in use is
  // kept.
  for (int exact = 1; exact >= 0; --exact)
    for (Kept& k : kept_) {
      if (k.symbolic == nullptr || !(exact ? same(k.key) : holds(k.key))) continue;
      SwapWith(k);
      k.last_use = uses_;
      ++pattern_hits_;
      return;
    }
  // A new pattern, in place of an empty slot or the least recently used: the one in use is kept
  // there, and the slot's storage is reused for the new pattern.
  Kept* slot = &kept_.front();
  for (Kept& k : kept_) {
    if (k.symbolic == nullptr) {
      slot = &k;
      break;
    }
    if (k.last_use < slot->last_use) slot = &k;
  }
  klu_common* c = Common(common_);
  Sequences(slot->numeric)->Clear(c);
  if (slot->symbolic) {
    klu_symbolic* sym = Symbolic(slot->symbolic);
    klu_free_symbolic(&sym, c);
    slot->symbolic = nullptr;
  }
  SwapWith(*slot);
  slot->last_use = uses_;
  // The new pattern holds the list and, when that stays small, the couplings of the one in use
  // too: a pair that comes and goes between assemblies (a contact moving along a rod, a
  // projection at another configuration) then finds its pattern in use.
  const std::vector<std::int64_t>& previous = slot->key;
  key_.clear();
  if (previous.size() <= count + 16) {
    key_.resize(count + previous.size());
    key_.erase(std::set_union(pairs, pairs + count, previous.begin(), previous.end(), key_.begin()),
               key_.end());
  } else {
    key_.assign(pairs, pairs + count);
  }
  BuildStructure();
  Analyze();
}

bool SparseLU::InBase(int i, int j) const {
  if (Find(i, j) < 0) return false;
  return i == j || !std::binary_search(key_.begin(), key_.end(), PackCoupling(i, j));
}

void SparseLU::Analyze() {
  klu_common* c = Common(common_);
  mark_.assign(static_cast<std::size_t>(n_), 0);
  klu_symbolic* sym = klu_analyze(n_, col_start_.data(), row_.data(), c);
  symbolic_ = sym;
  ++analyses_;
  predicted_nonzeros_ = sym ? sym->lnz + sym->unz - n_ : 0.0;
  predicted_flops_ = sym ? sym->est_flops : 0.0;
  column_parity_ = sym ? Parity(sym->Q, n_, mark_) : 1;
}

int SparseLU::Find(int i, int j) const {
  if (i < 0 || j < 0 || i >= n_ || j >= n_) return -1;
  const int* first = row_.data() + col_start_[static_cast<std::size_t>(j)];
  const int* last = row_.data() + col_start_[static_cast<std::size_t>(j) + 1];
  const int* p = std::lower_bound(first, last, i);
  return p != last && *p == i ? static_cast<int>(p - row_.data()) : -1;
}

bool SparseLU::Contains(int i, int j, int rows, int cols) const {
  for (int c = j; c < j + cols; ++c)
    if (FindRun(i, c, rows) < 0) return false;
  return true;
}

void SparseLU::SetRow(int i, double diagonal) {
  if (symmetric_) {
    // Row i's columns are column i's rows.
    for (int q = col_start_[static_cast<std::size_t>(i)];
         q < col_start_[static_cast<std::size_t>(i) + 1]; ++q) {
      const int j = row_[static_cast<std::size_t>(q)];
      value_[static_cast<std::size_t>(Find(i, j))] = i == j ? diagonal : 0.0;
    }
    return;
  }
  for (int j = 0; j < n_; ++j) {
    const int p = Find(i, j);
    if (p >= 0) value_[static_cast<std::size_t>(p)] = i == j ? diagonal : 0.0;
  }
}

void SparseLU::SetZero() { std::fill(value_.begin(), value_.end(), 0.0); }

bool SparseLU::FullFactorize() {
  // Into a free slot, else in place of the least recently successful sequence; the slot
  // becomes the first.
  klu_common* c = Common(common_);
  PivotSequences& p = *Sequences(numeric_);
  if (p.count == kPivotSequences) {
    p.Free(kPivotSequences - 1, c);
    --p.count;
  }
  const int k = p.count;
  ++full_factorizations_;
  klu_numeric* num =
      klu_factor(col_start_.data(), row_.data(), value_.data(), Symbolic(symbolic_), c);
  if (num == nullptr || c->status != KLU_OK) {
    // A factorisation that stopped at a zero pivot is not kept.
    klu_free_numeric(&num, c);
    return false;
  }
  p.numeric[p.order[k]] = num;
  ++p.count;
  p.Promote(k);
  return true;
}

void SparseLU::SetPivotTolerance(double tolerance) { Common(common_)->tol = tolerance; }

int SparseLU::Factorize() {
  klu_common* c = Common(common_);
  PivotSequences& p = *Sequences(numeric_);
  ++factorizations_;
  determinant_sign_ = 0;
  p.current = false;
  if (!symbolic_ || n_ == 0) {
    p.current = n_ == 0;
    return n_ == 0 ? -1 : 0;
  }
  // Refactorise with the kept pivot sequences, the most recently successful first.
  bool ok = false;
  for (int k = 0; k < p.count && !ok; ++k) {
    klu_numeric* num = p.numeric[p.order[k]];
    ok = klu_refactor(col_start_.data(), row_.data(), value_.data(), Symbolic(symbolic_), num, c) &&
         c->status == KLU_OK;
    if (ok) {
      klu_rgrowth(col_start_.data(), row_.data(), value_.data(), Symbolic(symbolic_), num, c);
      ok = c->status == KLU_OK && c->rgrowth >= kMinPivotGrowth;
    }
    if (ok) p.Promote(k);
  }
  if (!ok && p.count > 0) ++fallbacks_;
  if (!ok) ok = FullFactorize();
  if (!ok) {
    const int col = c->singular_col;
    return col >= 0 && col < n_ ? col : 0;
  }
  p.current = true;
  ReadPivots();
  return -1;
}

void SparseLU::ReadPivots() {
  const klu_numeric* num = Sequences(numeric_)->Current();
  const double* u = static_cast<const double*>(num->Udiag);
  int sign = Parity(num->Pnum, n_, mark_) * column_parity_;
  max_pivot_ = 0.0;
  min_pivot_ = INFINITY;
  for (int j = 0; j < n_; ++j) {
    const double a = std::abs(u[j]);
    max_pivot_ = std::max(max_pivot_, a);
    min_pivot_ = std::min(min_pivot_, a);
    if (u[j] < 0.0) sign = -sign;
  }
  if (n_ == 0) min_pivot_ = 0.0;
  determinant_sign_ = min_pivot_ > 0.0 ? sign : 0;
}

void SparseLU::Solve(Eigen::Ref<Eigen::VectorXd> b) const {
  assert(Sequences(numeric_)->current && b.size() == n_);
  if (n_ == 0) return;
  klu_solve(Symbolic(symbolic_), Sequences(numeric_)->Current(), n_, 1, b.data(), Common(common_));
}

void SparseLU::SolveTransposed(Eigen::Ref<Eigen::VectorXd> b) const {
  assert(Sequences(numeric_)->current && b.size() == n_);
  if (n_ == 0) return;
  klu_tsolve(Symbolic(symbolic_), Sequences(numeric_)->Current(), n_, 1, b.data(), Common(common_));
}

}  // namespace screwfem
