#include "screwfem/solve/modal.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

// Copies the assembled (unfactorised) band matrix back to the global order: the top-left
// nv x nv block into *top_left and the constraint rows' node/coordinate columns into *B.
void ReadAssembledMatrix(const Model& model, const Data& data, Eigen::MatrixXd* top_left,
                         Eigen::MatrixXd* B) {
  const int n = model.num_unknowns(), nv = model.nv;
  std::vector<int> global(static_cast<std::size_t>(n));
  for (int g = 0; g < n; ++g)
    global[static_cast<std::size_t>(model.permutation[static_cast<std::size_t>(g)])] = g;
  top_left->setZero(nv, nv);
  if (B) B->setZero(model.nc, nv);
  const auto store = [&](int pi, int pj, double value) {
    const int gi = global[static_cast<std::size_t>(pi)], gj = global[static_cast<std::size_t>(pj)];
    if (gj >= nv) return;
    if (gi < nv)
      (*top_left)(gi, gj) = value;
    else if (B)
      (*B)(gi - nv, gj) = value;
  };
  if (model.sparse_solver) data.sparse.ForEachEntry(store);
  const BandedLU& A = data.matrix;
  for (int pj = 0; pj < (model.sparse_solver ? 0 : n); ++pj) {
    const int gj = global[static_cast<std::size_t>(pj)];
    if (gj >= nv) continue;
    const int lo = std::max(0, pj - A.upper_bandwidth());
    const int hi = std::min(n - 1, pj + A.lower_bandwidth());
    for (int pi = lo; pi <= hi; ++pi) {
      const int gi = global[static_cast<std::size_t>(pi)];
      if (gi < nv)
        (*top_left)(gi, gj) = A.At(pi, pj);
      else if (B)
        (*B)(gi - nv, gj) = A.At(pi, pj);
    }
  }
  // The node blocks outside the band (pairs of moving shapes, Data::coupling).
  data.coupling.ForEachEntry([&](int pi, int pj, double value) {
    const int gi = global[static_cast<std::size_t>(pi)], gj = global[static_cast<std::size_t>(pj)];
    if (gi < nv && gj < nv) (*top_left)(gi, gj) += value;
  });
}

}  // namespace

bool CalcLinearizedSystem(const Model& model, Data& data, const ModalOptions& options,
                          LinearizedSystem* out) {
  const int nv = model.nv;
  const Eigen::VectorXd v_saved = data.v, vdot_saved = data.vdot;
  data.v.setZero();
  data.vdot.setZero();
  bool ok = true;

  // K, B and the equilibrium residual: the static assembly (docs/architecture.md, "One time step"), unscaled.
  AssemblyOptions o;
  o.time = options.time;
  o.load_factor = 1.0;
  ok = Assemble(model, data, o) && ok;
  ReadAssembledMatrix(model, data, &out->stiffness, &out->constraints);
  const double res = nv > 0 ? data.residual.head(nv).cwiseAbs().maxCoeff() : 0.0;
  out->relative_residual = res / std::max(data.force_scale, 1e-300);
  if (res == 0.0) out->relative_residual = 0.0;

  // M and C: the dynamic assembly at rest with one coefficient at a time.
  o.dynamics = true;
  o.c_stiffness = 0.0;
  o.c_mass = 1.0;
  o.c_damping = 0.0;
  ok = Assemble(model, data, o) && ok;
  ReadAssembledMatrix(model, data, &out->mass, nullptr);
  o.c_mass = 0.0;
  o.c_damping = 1.0;
  ok = Assemble(model, data, o) && ok;
  ReadAssembledMatrix(model, data, &out->damping, nullptr);
  data.v = v_saved;
  data.vdot = vdot_saved;

  // Orthonormal basis of ker B: the last columns of Q in B^T P = Q R.
  if (model.nc == 0) {
    out->null_space = Eigen::MatrixXd::Identity(nv, nv);
  } else {
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(out->constraints.transpose());
    qr.setThreshold(options.rank_tolerance);
    const int rank = static_cast<int>(qr.rank());
    const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(nv, nv);
    out->null_space = Q.rightCols(nv - rank);
  }
  return ok;
}

namespace {

// Reduced mass and stiffness on the admissible space Z (symmetrised; a warning when the
// stiffness is not symmetric).
void CalcReducedMatrices(const LinearizedSystem& sys, ModalResult* result, Eigen::MatrixXd* Mr,
                         Eigen::MatrixXd* Kr) {
  const Eigen::MatrixXd& Z = sys.null_space;
  *Mr = Z.transpose() * sys.mass * Z;
  *Kr = Z.transpose() * sys.stiffness * Z;
  *Mr = 0.5 * (*Mr + Mr->transpose()).eval();
  const double k_norm = Kr->norm();
  result->stiffness_asymmetry = k_norm > 0.0 ? (*Kr - Kr->transpose()).norm() / k_norm : 0.0;
  if (result->stiffness_asymmetry > 1e-6)
    result->warnings.push_back(FormatNumbers(
        "the stiffness is not symmetric (relative asymmetry %.3g; follower loads or a "
        "non-equilibrium state): its symmetric part is used",
        result->stiffness_asymmetry));
  *Kr = 0.5 * (*Kr + Kr->transpose()).eval();
}

// The reduced problem on the directions with mass, the massless ones condensed statically.
struct CondensedSystem {
  Eigen::MatrixXd V0, Vm;       // eigenvectors of Mr without and with mass
  Eigen::VectorXd inv_sqrt_mu;  // mu^-1/2 of the directions with mass
  Eigen::MatrixXd Kmm;          // K* = K_mm - K_m0 K_00^-1 K_0m
  Eigen::MatrixXd condense;     // n0 x nm: massless coordinates = condense * massive coordinates
};

// Splits the admissible space into directions with and without mass (eigenvectors of Mr) and
// condenses the massless ones. False (and result->message) when nothing carries mass or a
// massless direction has no stiffness.
bool CondenseMassless(const Eigen::MatrixXd& Mr, const Eigen::MatrixXd& Kr, ModalResult* result,
                      CondensedSystem* c) {
  const int m = static_cast<int>(Mr.cols());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> mass_eig(Mr);
  const Eigen::VectorXd mu = mass_eig.eigenvalues();
  const double mass_tol = 1e-12 * std::max(mu.cwiseAbs().maxCoeff(), 1e-300);
  int n0 = 0;
  while (n0 < m && mu(n0) <= mass_tol) ++n0;
  const int nm = m - n0;
  result->num_massless = n0;
  if (nm == 0) {
    result->message = "the admissible motions carry no mass";
    return false;
  }
  c->V0 = mass_eig.eigenvectors().leftCols(n0);
  c->Vm = mass_eig.eigenvectors().rightCols(nm);
  c->inv_sqrt_mu = mu.tail(nm).cwiseSqrt().cwiseInverse();
  c->Kmm = c->Vm.transpose() * Kr * c->Vm;
  if (n0 == 0) return true;
  const Eigen::MatrixXd K00 = c->V0.transpose() * Kr * c->V0;
  const Eigen::MatrixXd K0m = c->V0.transpose() * Kr * c->Vm;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(K00);
  if (!lu.isInvertible()) {
    result->message =
        "admissible motions without mass and without stiffness (an unrestrained massless "
        "part): no modes";
    return false;
  }
  c->condense = -lu.solve(K0m);
  c->Kmm.noalias() += K0m.transpose() * c->condense;
  return true;
}

// Frequencies, modal damping ratios phi^T C phi / (2 omega), and a warning for negative
// eigenvalues (an unstable equilibrium).
void CalcFrequenciesAndDamping(const LinearizedSystem& sys, double eigenvalue_scale, int count,
                               ModalResult* result) {
  result->omega = result->eigenvalues.cwiseMax(0.0).cwiseSqrt();
  result->frequency = result->omega / (2.0 * std::numbers::pi);
  result->damping_ratio = Eigen::VectorXd::Zero(count);
  int negative = 0;
  for (int i = 0; i < count; ++i) {
    const double lam = result->eigenvalues(i);
    if (lam < -1e-8 * eigenvalue_scale) ++negative;
    if (lam > 0.0) {
      const Eigen::VectorXd phi = result->modes.col(i);
      result->damping_ratio(i) = phi.dot(sys.damping * phi) / (2.0 * result->omega(i));
    }
  }
  if (negative > 0)
    result->warnings.push_back(
        FormatNumbers("%g negative eigenvalue(s): the equilibrium is unstable", negative));
}

}  // namespace

ModalResult CalcModes(const Model& model, Data& data, const ModalOptions& options) {
  ModalResult result;
  LinearizedSystem sys;
  if (!CalcLinearizedSystem(model, data, options, &sys)) {
    result.message = "an element's rotation is outside its admissible range";
    return result;
  }
  result.relative_residual = sys.relative_residual;
  if (sys.relative_residual > 1e-6)
    result.warnings.push_back(FormatNumbers(
        "the state is not an equilibrium (relative residual %.3g): the modes describe "
        "the linearisation about a non-equilibrium state",
        sys.relative_residual));
  const Eigen::MatrixXd& Z = sys.null_space;
  const int m = static_cast<int>(Z.cols());
  result.num_dofs = m;
  if (m == 0) {
    result.ok = true;
    return result;
  }
  Eigen::MatrixXd Mr, Kr;
  CalcReducedMatrices(sys, &result, &Mr, &Kr);
  CondensedSystem c;
  if (!CondenseMassless(Mr, Kr, &result, &c)) return result;
  const int nm = static_cast<int>(c.Vm.cols());
  // Mass-normalised standard problem: S = mu^-1/2 K* mu^-1/2.
  const Eigen::MatrixXd S = c.inv_sqrt_mu.asDiagonal() * c.Kmm * c.inv_sqrt_mu.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (S + S.transpose()));
  if (eig.info() != Eigen::Success) {
    result.message = "the eigenvalue solver did not converge";
    return result;
  }
  const int count = options.num_modes > 0 ? std::min(options.num_modes, nm) : nm;
  result.eigenvalues = eig.eigenvalues().head(count);
  const Eigen::MatrixXd y = c.inv_sqrt_mu.asDiagonal() * eig.eigenvectors().leftCols(count);
  Eigen::MatrixXd phi_r = c.Vm * y;
  if (c.V0.cols() > 0) phi_r.noalias() += c.V0 * (c.condense * y);
  result.modes = Z * phi_r;
  CalcFrequenciesAndDamping(sys, std::max(eig.eigenvalues().cwiseAbs().maxCoeff(), 1e-300), count,
                            &result);
  result.ok = true;
  return result;
}

}  // namespace screwfem
