// Inverse statics: bounded nonlinear least squares over actuator parameters with the exact
// Jacobian of the equilibrium (solve/sensitivity.h, docs/inverse.md "Inverse statics"), solved
// by Ceres' trust region (Levenberg-Marquardt, parameter bounds by projection).
#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/errors.h"
#include "reequilibrate.h"
#include "screwfem/solve/sensitivity.h"

namespace screwfem {

namespace {

// The equilibrium as a function of the parameters' values, with its Jacobian.
class InverseProblem {
 public:
  InverseProblem(const Model& model, Data& data, const std::vector<Parameter>& params,
                 const std::vector<InverseTarget>& targets, const InverseStaticsOptions& o)
      : original_(model),
        work_(model),
        data_(data),
        params_(params),
        targets_(targets),
        options_(o),
        workspace_(MakeSensitivityWorkspace(model)),
        inputs0_(data.inputs) {
    for (const InverseTarget& t : targets)
      for (int c = 0; c < 3; ++c) {
        SensitivityOutput out;
        out.kind = OutputKind::kPointPosition;
        out.index = t.node;
        out.component = c;
        out.offset = t.offset;
        outputs_.push_back(out);
      }
  }

  int residuals() const { return 3 * static_cast<int>(targets_.size()); }
  int solves() const { return solves_; }
  const std::string& failure() const { return failure_; }
  const Model& work_model() const { return work_; }

  // Brings data to the equilibrium at `values`; false (failure() says why) if none is found.
  bool Equilibrium(const double* values) {
    const int np = static_cast<int>(params_.size());
    bool same = have_state_ && static_cast<int>(current_.size()) == np;
    for (int i = 0; same && i < np; ++i) same = current_(i) == values[i];
    if (same) return true;
    data_.inputs = inputs0_;
    // Every item back to the model's own first, then the offsets (two parameters may touch
    // one item, e.g. two components of a point load).
    for (const Parameter& p : params_) ResetParameter(work_, original_, p);
    for (int i = 0; i < np; ++i) {
      const Parameter& p = params_[static_cast<std::size_t>(i)];
      if (p.kind == ParameterKind::kInput)
        data_.inputs(p.index) = values[i];  // an input's value itself
      else
        OffsetParameter(work_, data_, p, values[i]);
    }
    current_ = Eigen::Map<const Eigen::VectorXd>(values, np);
    have_state_ = false;
    if (!Reequilibrate(work_, data_, options_.statics, &solves_, &failure_)) return false;
    have_state_ = true;
    return true;
  }

  void Residual(double* r) const {
    for (std::size_t k = 0; k < targets_.size(); ++k) {
      const InverseTarget& t = targets_[k];
      const Vec3 x = NodeFrame(data_, t.node).Act(t.offset);
      Eigen::Map<Vec3>(r + 3 * k) = x - t.target;
    }
  }

  // The Jacobian (residuals x parameters, row-major) at the equilibrium data holds.
  bool Jacobian(double* jac) {
    const StaticSensitivity s = CalcStaticSensitivity(
        work_, data_, params_, outputs_, SensitivityMode::kForward, options_.statics, &workspace_);
    if (!s.ok) {
      failure_ = "no sensitivity: " + s.message;
      return false;
    }
    // A stiffness or mass factor is perturbed relative to its current value (1 + value).
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(
        jac, s.outputs.rows(), s.outputs.cols());
    J = s.outputs;
    for (Eigen::Index j = 0; j < J.cols(); ++j)
      J.col(j) *= ParameterChainFactor(params_[static_cast<std::size_t>(j)], current_(j));
    return true;
  }

 private:
  const Model& original_;
  Model work_;
  Data& data_;
  const std::vector<Parameter>& params_;
  const std::vector<InverseTarget>& targets_;
  const InverseStaticsOptions& options_;
  SensitivityWorkspace workspace_;
  std::vector<SensitivityOutput> outputs_;
  Eigen::VectorXd inputs0_, current_;
  bool have_state_ = false;
  int solves_ = 0;
  std::string failure_;
};

class InverseCost : public ceres::CostFunction {
 public:
  InverseCost(InverseProblem& problem, int parameters) : problem_(problem) {
    set_num_residuals(problem.residuals());
    mutable_parameter_block_sizes()->push_back(parameters);
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    if (!problem_.Equilibrium(x[0])) return false;
    problem_.Residual(residuals);
    return !(jacobians && jacobians[0]) || problem_.Jacobian(jacobians[0]);
  }

 private:
  InverseProblem& problem_;
};

// Stops Ceres once the effectors are within the tolerance of their targets.
class DistanceCallback : public ceres::IterationCallback {
 public:
  explicit DistanceCallback(double tolerance) : half_squared_(0.5 * tolerance * tolerance) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    return s.cost <= half_squared_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  double half_squared_;
};

void ValidateInverse(const Model& model, const std::vector<Parameter>& params,
                     const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                     const std::vector<InverseTarget>& targets, const Eigen::VectorXd& start,
                     const InverseStaticsOptions& o) {
  const std::string owner = "SolveInverseStatics";
  if (params.empty()) throw InputError(owner + ": no parameters");
  if (targets.empty()) throw InputError(owner + ": no targets");
  for (const Parameter& p : params) ValidateParameter(model, p, owner);
  const Eigen::Index np = static_cast<Eigen::Index>(params.size());
  if (lower.size() != np || upper.size() != np || start.size() != np)
    throw InputError(owner + ": lower, upper and start need one value per parameter");
  for (Eigen::Index i = 0; i < np; ++i)
    if (!(std::isfinite(start(i)) && !std::isnan(lower(i)) && !std::isnan(upper(i)) &&
          lower(i) <= upper(i)))
      throw InputError(owner + ": parameter " + std::to_string(i) +
                       ": start must be finite and lower <= upper");
  for (const InverseTarget& t : targets)
    if (t.node < 0 || t.node >= static_cast<int>(model.nodes.size()) || !t.offset.allFinite() ||
        !t.target.allFinite())
      throw InputError(owner + ": a target needs a node of the model and finite points");
  if (o.max_iterations < 1 || !(o.tolerance > 0.0) || !(o.parameter_tolerance > 0.0))
    throw InputError(owner + ": max_iterations >= 1 and tolerances > 0 required");
  ValidateStaticOptions(o.statics, owner + ".statics");
}

}  // namespace

InverseStaticsResult SolveInverseStatics(const Model& model, Data& data,
                                         const std::vector<Parameter>& parameters,
                                         const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                         const std::vector<InverseTarget>& targets,
                                         const Eigen::VectorXd& start,
                                         const InverseStaticsOptions& options) {
  ValidateInverse(model, parameters, lower, upper, targets, start, options);
  const int np = static_cast<int>(parameters.size());
  InverseProblem problem(model, data, parameters, targets, options);
  InverseStaticsResult result;
  result.values = start.cwiseMax(lower).cwiseMin(upper);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem ls(problem_options);
  ls.AddResidualBlock(new InverseCost(problem, np), nullptr, result.values.data());
  for (int i = 0; i < np; ++i) {
    if (std::isfinite(lower(i))) ls.SetParameterLowerBound(result.values.data(), i, lower(i));
    if (std::isfinite(upper(i))) ls.SetParameterUpperBound(result.values.data(), i, upper(i));
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = 1e-16;
  so.gradient_tolerance = 0.0;
  so.parameter_tolerance = options.parameter_tolerance;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  DistanceCallback stop_at_target(options.tolerance);
  so.callbacks.push_back(&stop_at_target);
  so.update_state_every_iteration = false;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &ls, &summary);
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  // data to the equilibrium at the values found (Ceres' last evaluation may be a rejected
  // trial point).
  result.residual.resize(3 * static_cast<Eigen::Index>(targets.size()));
  if (!problem.Equilibrium(result.values.data())) {
    result.message = problem.failure();
    result.equilibrium_solves = problem.solves();
    return result;
  }
  problem.Residual(result.residual.data());
  result.distance = result.residual.norm();
  result.equilibrium_solves = problem.solves();
  for (int i = 0; i < np; ++i)
    result.at_bound =
        result.at_bound || result.values(i) <= lower(i) || result.values(i) >= upper(i);
  result.converged = result.distance <= options.tolerance;
  if (!result.converged)
    result.message =
        FormatNumbers(
            "the targets are not reached: the nearest equilibrium within the bounds is %.6g m "
            "from them",
            result.distance) +
        (result.at_bound ? " (a parameter is on its bound)" : "") +
        "; optimiser: " + summary.message;
  return result;
}

}  // namespace screwfem
