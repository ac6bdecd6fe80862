// Calibration: parameters fitted to measured positions of several static load cases by
// nonlinear least squares with the exact Jacobian of each equilibrium (solve/sensitivity.h,
// docs/inverse.md "Calibration"), solved by Ceres' Levenberg-Marquardt; the covariance of the
// fit from the Jacobian.
#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>

#include "reequilibrate.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/sensitivity.h"

namespace screwfem {

namespace {

// One load case: its model (the calibrated parameters and the case's loads applied) and its
// equilibrium, kept from one evaluation to the next (the warm start).
struct CaseState {
  Model work;
  Data data;
  SensitivityWorkspace workspace;
  std::vector<SensitivityOutput> outputs;
  Eigen::VectorXd inputs0;
};

class CalibrationProblem {
 public:
  CalibrationProblem(const Model& model, const std::vector<Parameter>& params,
                     const std::vector<CalibrationCase>& cases, const CalibrationOptions& o)
      : original_(model), params_(params), cases_(cases), options_(o) {
    states_.reserve(cases.size());
    for (const CalibrationCase& c : cases) {
      CaseState s{model, MakeData(model), MakeSensitivityWorkspace(model), {}, {}};
      s.inputs0 = s.data.inputs;
      for (const InverseTarget& t : c.measurements)
        for (int k = 0; k < 3; ++k) {
          SensitivityOutput out;
          out.kind = OutputKind::kPointPosition;
          out.index = t.node;
          out.component = k;
          out.offset = t.offset;
          s.outputs.push_back(out);
        }
      residuals_ += 3 * static_cast<int>(c.measurements.size());
      states_.push_back(std::move(s));
    }
  }

  int residuals() const { return residuals_; }
  int solves() const { return solves_; }
  const std::string& failure() const { return failure_; }

  // Brings every case to its equilibrium at `values`.
  bool Equilibria(const double* values) {
    const int np = static_cast<int>(params_.size());
    bool same = have_state_;
    for (int i = 0; same && i < np; ++i) same = current_(i) == values[i];
    if (same) return true;
    current_ = Eigen::Map<const Eigen::VectorXd>(values, np);
    have_state_ = false;
    for (std::size_t c = 0; c < cases_.size(); ++c) {
      CaseState& s = states_[c];
      const CalibrationCase& lc = cases_[c];
      s.data.inputs = s.inputs0;
      // Every item back to the model's own first, then the offsets (two parameters may touch
      // one item, e.g. two components of a load). The case's loads also go to the
      // sensitivity's copy of the model (which gets the calibrated parameters from s.work at
      // every call, CalcStaticSensitivity).
      for (const Parameter& p : lc.loads) {
        ResetParameter(s.work, original_, p);
        ResetParameter(s.workspace.model, original_, p);
      }
      for (const Parameter& p : params_) ResetParameter(s.work, original_, p);
      for (std::size_t i = 0; i < lc.loads.size(); ++i) {
        const Parameter& p = lc.loads[i];
        const double value = lc.load_values(static_cast<Eigen::Index>(i));
        if (p.kind == ParameterKind::kInput) {
          s.data.inputs(p.index) = value;
          continue;
        }
        OffsetParameter(s.work, s.data, p, value);
        OffsetParameter(s.workspace.model, s.data, p, value);
      }
      for (int i = 0; i < np; ++i) {
        const Parameter& p = params_[static_cast<std::size_t>(i)];
        if (p.kind == ParameterKind::kInput)
          s.data.inputs(p.index) = values[i];  // an input's value itself
        else
          OffsetParameter(s.work, s.data, p, values[i]);
      }
      if (!Reequilibrate(s.work, s.data, options_.statics, &solves_, &failure_)) {
        failure_ = "load case " + std::to_string(c) + ": " + failure_;
        return false;
      }
    }
    have_state_ = true;
    return true;
  }

  void Residual(double* r) const {
    int row = 0;
    for (std::size_t c = 0; c < cases_.size(); ++c)
      for (const InverseTarget& t : cases_[c].measurements) {
        Eigen::Map<Vec3>(r + row) = NodeFrame(states_[c].data, t.node).Act(t.offset) - t.target;
        row += 3;
      }
  }

  // The Jacobian (residuals x parameters) at the equilibria the cases hold.
  bool Jacobian(Eigen::Ref<Eigen::MatrixXd> jac) {
    Eigen::Index row = 0;
    for (std::size_t c = 0; c < cases_.size(); ++c) {
      CaseState& s = states_[c];
      const StaticSensitivity sens =
          CalcStaticSensitivity(s.work, s.data, params_, s.outputs, SensitivityMode::kForward,
                                options_.statics, &s.workspace);
      if (!sens.ok) {
        failure_ = "load case " + std::to_string(c) + ": no sensitivity: " + sens.message;
        return false;
      }
      jac.middleRows(row, sens.outputs.rows()) = sens.outputs;
      row += sens.outputs.rows();
    }
    for (Eigen::Index j = 0; j < jac.cols(); ++j)
      jac.col(j) *= ParameterChainFactor(params_[static_cast<std::size_t>(j)], current_(j));
    return true;
  }

 private:
  const Model& original_;
  const std::vector<Parameter>& params_;
  const std::vector<CalibrationCase>& cases_;
  const CalibrationOptions& options_;
  std::vector<CaseState> states_;
  Eigen::VectorXd current_;
  bool have_state_ = false;
  int residuals_ = 0, solves_ = 0;
  std::string failure_;
};

class CalibrationCost : public ceres::CostFunction {
 public:
  CalibrationCost(CalibrationProblem& problem, int parameters) : problem_(problem) {
    set_num_residuals(problem.residuals());
    mutable_parameter_block_sizes()->push_back(parameters);
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    if (!problem_.Equilibria(x[0])) return false;
    problem_.Residual(residuals);
    if (!(jacobians && jacobians[0])) return true;
    const int np = parameter_block_sizes()[0];
    Eigen::MatrixXd J(num_residuals(), np);
    if (!problem_.Jacobian(J)) return false;
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        jacobians[0], num_residuals(), np) = J;
    return true;
  }

 private:
  CalibrationProblem& problem_;
};

void ValidateCalibration(const Model& model, const std::vector<Parameter>& params,
                         const Eigen::VectorXd& start, const std::vector<CalibrationCase>& cases,
                         const CalibrationOptions& o) {
  const std::string owner = "Calibrate";
  if (params.empty()) throw InputError(owner + ": no parameters");
  if (cases.empty()) throw InputError(owner + ": no load cases");
  for (const Parameter& p : params) ValidateParameter(model, p, owner);
  if (start.size() != static_cast<Eigen::Index>(params.size()) || !start.allFinite())
    throw InputError(owner + ": start needs one finite value per parameter");
  std::size_t measured = 0;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::string where = owner + ": load case " + std::to_string(c);
    const CalibrationCase& lc = cases[c];
    for (const Parameter& p : lc.loads) ValidateParameter(model, p, where);
    if (lc.load_values.size() != static_cast<Eigen::Index>(lc.loads.size()) ||
        !lc.load_values.allFinite())
      throw InputError(where + ": load_values needs one finite value per load");
    if (lc.measurements.empty()) throw InputError(where + ": no measurements");
    for (const InverseTarget& t : lc.measurements)
      if (t.node < 0 || t.node >= static_cast<int>(model.nodes.size()) || !t.offset.allFinite() ||
          !t.target.allFinite())
        throw InputError(where + ": a measurement needs a node of the model and finite points");
    measured += 3 * lc.measurements.size();
  }
  if (measured < params.size())
    throw InputError(owner + ": fewer measured coordinates (" + std::to_string(measured) +
                     ") than parameters (" + std::to_string(params.size()) + ")");
  if (o.max_iterations < 1 || !(o.parameter_tolerance > 0.0) || !(o.sigma >= 0.0) ||
      !std::isfinite(o.sigma) || !(o.interval_sigmas > 0.0) || !std::isfinite(o.interval_sigmas))
    throw InputError(owner +
                     ": max_iterations >= 1, parameter_tolerance > 0, sigma >= 0 and finite, "
                     "interval_sigmas > 0 required");
  ValidateStaticOptions(o.statics, owner + ".statics");
}

}  // namespace

CalibrationResult Calibrate(const Model& model, const std::vector<Parameter>& parameters,
                            const Eigen::VectorXd& start, const std::vector<CalibrationCase>& cases,
                            const CalibrationOptions& options) {
  ValidateCalibration(model, parameters, start, cases, options);
  const int np = static_cast<int>(parameters.size());
  CalibrationProblem problem(model, parameters, cases, options);
  CalibrationResult result;
  result.values = start;
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem ls(problem_options);
  ls.AddResidualBlock(new CalibrationCost(problem, np), nullptr, result.values.data());
  // A stiffness or mass factor (1 + p) stays positive.
  for (int i = 0; i < np; ++i) {
    const ParameterKind k = parameters[static_cast<std::size_t>(i)].kind;
    if (k == ParameterKind::kRodStiffness || k == ParameterKind::kRodMass)
      ls.SetParameterLowerBound(result.values.data(), i, -0.99);
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = 1e-15;
  so.gradient_tolerance = 1e-16;
  so.parameter_tolerance = options.parameter_tolerance;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  so.update_state_every_iteration = false;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &ls, &summary);
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  // The equilibria, residual and Jacobian at the values found (Ceres' last evaluation may be a
  // rejected trial point).
  const int m = problem.residuals();
  result.residual.resize(m);
  result.jacobian.resize(m, np);
  if (!problem.Equilibria(result.values.data()) || !problem.Jacobian(result.jacobian)) {
    result.message = problem.failure();
    result.equilibrium_solves = problem.solves();
    return result;
  }
  problem.Residual(result.residual.data());
  result.equilibrium_solves = problem.solves();
  result.rms = std::sqrt(result.residual.squaredNorm() / m);
  if (options.sigma > 0.0)
    result.sigma = options.sigma;
  else if (m > np)
    result.sigma = std::sqrt(result.residual.squaredNorm() / (m - np));
  // (J^T J)^-1 by the QR of J (R^T R = J^T J): its inverse R^-1 R^-T, without forming J^T J.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(result.jacobian);
  if (qr.rank() < np) {
    result.message =
        "the parameters are not identifiable from these measurements: the "
        "Jacobian has rank " +
        std::to_string(qr.rank()) + " < " + std::to_string(np);
    return result;
  }
  const Eigen::MatrixXd Rinv =
      qr.matrixR().topLeftCorner(np, np).triangularView<Eigen::Upper>().solve(
          Eigen::MatrixXd::Identity(np, np));
  const Eigen::MatrixXd P = qr.colsPermutation();
  const Eigen::MatrixXd inv = P * (Rinv * Rinv.transpose()) * P.transpose();
  result.covariance = result.sigma * result.sigma * inv;
  result.standard_error = result.covariance.diagonal().cwiseSqrt();
  result.lower = result.values - options.interval_sigmas * result.standard_error;
  result.upper = result.values + options.interval_sigmas * result.standard_error;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  if (!result.converged) result.message = "the optimiser did not converge: " + summary.message;
  return result;
}

}  // namespace screwfem
