#include "screwfem/solve/initial_state.h"

#include <Eigen/QR>
#include <cmath>
#include <cstdio>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

constexpr int kMaxAssemblyIterations = 50;

// phi(q) into out (the constraint rows of the residual, unscaled).
bool ConstraintValues(const Model& model, Data& data, Eigen::VectorXd& out) {
  AssemblyOptions o;
  o.time = data.time;
  o.assemble_matrix = false;
  if (!Assemble(model, data, o)) return false;
  out = data.residual.tail(model.nc);
  return out.allFinite();
}

// Minimum-norm x with B_free x = rhs, B_free the gradient with the held columns zeroed.
Eigen::VectorXd MinimumNormSolve(Eigen::MatrixXd B, const std::vector<char>& held,
                                 const Eigen::VectorXd& rhs) {
  for (int c = 0; c < B.cols(); ++c)
    if (held[static_cast<std::size_t>(c)]) B.col(c).setZero();
  return B.completeOrthogonalDecomposition().solve(rhs);
}

// Step 1 of AssembleInitialState: sets the given joint coordinates and brings the others back
// onto the constraints by Gauss-Newton. B: workspace for the constraint gradient (nc x nv).
bool AssembleCoordinates(const Model& model, Data& data, Eigen::MatrixXd& B, std::string* message) {
  const int nv = model.nv, nc = model.nc;
  std::vector<char> held(static_cast<std::size_t>(nv), 0);
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(nv);
  bool any = false;
  for (const Joint& j : model.joints) {
    if (!j.has_initial_coordinate) continue;
    for (int c = 0; c < j.k(); ++c) {
      const int i = j.coord + c;
      dx(i) = j.initial_coordinate(c) - data.q_joint(i - model.nv_nodes);
      held[static_cast<std::size_t>(i)] = 1;
    }
    any = true;
  }
  if (!any) return true;
  Retract(model, data, dx);
  UpdateBranchReferences(model, data);
  Eigen::VectorXd phi(nc);
  const double tol = 1e-12 * std::max(1.0, model.length_scale);
  double violation = 0.0;
  for (int it = 0; nc > 0; ++it) {
    if (!ConstraintValues(model, data, phi)) {
      if (message) *message = "the initial joint coordinates bend an element past its limit";
      return false;
    }
    violation = phi.cwiseAbs().maxCoeff();
    if (violation <= tol) break;
    if (it == kMaxAssemblyIterations) {
      if (message)
        *message = FormatNumbers(
            "cannot assemble the initial joint coordinates: the constraints stay violated by "
            "%.3g after %.0f Gauss-Newton iterations (do the given coordinates contradict the "
            "joints or the drives?)",
            violation, kMaxAssemblyIterations);
      return false;
    }
    CalcConstraintGradient(model, data, B);
    dx = -MinimumNormSolve(B, held, phi);
    Retract(model, data, dx);
    UpdateBranchReferences(model, data);
  }
  return true;
}

// Step 2 of AssembleInitialState: sets the given body velocities and joint rates and corrects
// the others so that B v + dphi/dt = 0. B: as in AssembleCoordinates.
bool AssembleVelocities(const Model& model, Data& data, Eigen::MatrixXd& B, std::string* message) {
  const int nc = model.nc;
  std::vector<char> held(static_cast<std::size_t>(model.nv), 0);
  bool any = false;
  for (const Node& n : model.nodes) {
    if (!n.has_initial_velocity || n.dof < 0) continue;
    data.v.segment<6>(n.dof) = n.initial_velocity;
    for (int c = 0; c < 6; ++c) held[static_cast<std::size_t>(n.dof + c)] = 1;
    any = true;
  }
  for (const Joint& j : model.joints) {
    if (!j.has_initial_rate) continue;
    for (int c = 0; c < j.k(); ++c) {
      data.v(j.coord + c) = j.initial_rate(c);
      held[static_cast<std::size_t>(j.coord + c)] = 1;
    }
    any = true;
  }
  if (!any || nc == 0) return true;
  Eigen::VectorXd r(nc);
  CalcVelocityConstraint(model, data, data.time, r);
  CalcConstraintGradient(model, data, B);
  data.v -= MinimumNormSolve(B, held, r);
  CalcVelocityConstraint(model, data, data.time, r);
  const double scale = std::max(1.0, data.v.cwiseAbs().maxCoeff() * model.length_scale);
  if (!(r.cwiseAbs().maxCoeff() <= 1e-10 * scale)) {
    if (message)
      *message = FormatNumbers(
          "the initial velocities contradict the constraints: B v + dphi/dt stays at %.3g "
          "(given body velocities and joint rates over-determine the motion)",
          r.cwiseAbs().maxCoeff());
    return false;
  }
  return true;
}

}  // namespace

bool HasInitialState(const Model& model) {
  for (const Node& n : model.nodes)
    if (n.has_initial_velocity) return true;
  for (const Joint& j : model.joints)
    if (j.has_initial_coordinate || j.has_initial_rate) return true;
  return false;
}

bool AssembleInitialState(const Model& model, Data& data, std::string* message) {
  Eigen::MatrixXd B(model.nc, model.nv);  // the constraint gradient, for both steps
  // 1. Coordinates.
  if (!AssembleCoordinates(model, data, B, message)) return false;
  // 2. Velocities.
  return AssembleVelocities(model, data, B, message);
}

}  // namespace screwfem
